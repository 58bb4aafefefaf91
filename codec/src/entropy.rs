//! Context-adaptive binary arithmetic coding on top of `constriction`.
//!
//! Why `constriction`: it is a maintained (2024–25 releases), MIT/Apache
//! entropy-coding library with a range coder whose decoder rejects invalid
//! data with an error instead of panicking, and it lets us plug in our own
//! probability model. Quantised DCT coefficients at 300–800:1 are almost all
//! zero; what wins there is *context modelling* (CABAC-style adaptive binary
//! decisions), which a static-table coder or zstd cannot do. So the only thing
//! written here is the model: an adaptive bit probability (12-bit, shift-5
//! update, as in LZMA/CABAC) implementing constriction's model traits.
//!
//! [`CostMeter`] runs the same binarisation without producing bits, summing
//! the ideal code length; the rate allocation uses it to draw rate/distortion
//! curves cheaply and without range-coder word granularity.

use std::borrow::Borrow;
use std::convert::Infallible;
use std::num::NonZeroU16;
use std::sync::OnceLock;

use constriction::Queue;
use constriction::backends::ReadWords;
use constriction::stream::model::{DecoderModel, EncoderModel, EntropyModel};
use constriction::stream::queue::{DefaultRangeEncoder, RangeDecoder};
use constriction::stream::{Decode, Encode};

const PREC: usize = 12;
const ONE: u16 = 1 << PREC;
const HALF: u16 = ONE / 2;
const SHIFT: u16 = 5;

/// An adaptive probability that the next bit is 0, in units of 2^-12.
/// The update keeps it within 31..=4065, so neither symbol reaches
/// probability zero.
#[derive(Clone, Copy, Debug)]
pub struct Ctx(u16);

impl Default for Ctx {
    fn default() -> Self {
        Ctx(HALF)
    }
}

impl Ctx {
    #[inline]
    fn update(&mut self, bit: bool) {
        if bit {
            self.0 -= self.0 >> SHIFT;
        } else {
            self.0 += (ONE - self.0) >> SHIFT;
        }
    }
}

/// A two-symbol model with P(false) = p0 / 4096, for constriction's coders.
#[derive(Clone, Copy)]
struct Bin(u16);

impl EntropyModel<PREC> for Bin {
    type Symbol = bool;
    type Probability = u16;
}

#[inline]
fn nz(p: u16) -> NonZeroU16 {
    // Ctx keeps p0 within 31..=4065, so both p0 and 4096 - p0 are nonzero.
    NonZeroU16::new(p).unwrap_or(NonZeroU16::MIN)
}

impl EncoderModel<PREC> for Bin {
    #[inline]
    fn left_cumulative_and_probability(
        &self,
        symbol: impl Borrow<bool>,
    ) -> Option<(u16, NonZeroU16)> {
        Some(if *symbol.borrow() {
            (self.0, nz(ONE - self.0))
        } else {
            (0, nz(self.0))
        })
    }
}

impl DecoderModel<PREC> for Bin {
    #[inline]
    fn quantile_function(&self, quantile: u16) -> (bool, u16, NonZeroU16) {
        if quantile < self.0 {
            (false, 0, nz(self.0))
        } else {
            (true, self.0, nz(ONE - self.0))
        }
    }
}

/// Where a binarised symbol stream goes: a real encoder or a cost meter.
pub trait BitSink {
    fn bit(&mut self, ctx: &mut Ctx, bit: bool);
    /// An equiprobable bit (signs, Exp-Golomb suffixes).
    fn bypass(&mut self, bit: bool);
}

/// Sums the ideal code length (bits) of what is fed to it.
#[derive(Default)]
pub struct CostMeter {
    pub bits: f64,
}

fn cost_table() -> &'static [f32] {
    static T: OnceLock<Vec<f32>> = OnceLock::new();
    T.get_or_init(|| {
        (0..=ONE as usize)
            .map(|p| -((p.max(1) as f32) / ONE as f32).log2())
            .collect()
    })
}

impl BitSink for CostMeter {
    #[inline]
    fn bit(&mut self, ctx: &mut Ctx, bit: bool) {
        let p = if bit { ONE - ctx.0 } else { ctx.0 };
        self.bits += cost_table()[p as usize] as f64;
        ctx.update(bit);
    }
    #[inline]
    fn bypass(&mut self, _bit: bool) {
        self.bits += 1.0;
    }
}

/// Range encoder producing little-endian 32-bit words.
pub struct Writer {
    enc: DefaultRangeEncoder,
    failed: bool,
}

impl Default for Writer {
    fn default() -> Self {
        Self {
            enc: DefaultRangeEncoder::new(),
            failed: false,
        }
    }
}

impl Writer {
    /// The coded bytes, or `None` if the coder reported an internal error
    /// (impossible with the models above, but not silently ignored).
    pub fn finish(self) -> Option<Vec<u8>> {
        if self.failed {
            return None;
        }
        let words = self.enc.into_compressed().ok()?;
        Some(words.iter().flat_map(|w| w.to_le_bytes()).collect())
    }
}

impl BitSink for Writer {
    #[inline]
    fn bit(&mut self, ctx: &mut Ctx, bit: bool) {
        if self.enc.encode_symbol(bit, Bin(ctx.0)).is_err() {
            self.failed = true;
        }
        ctx.update(bit);
    }
    #[inline]
    fn bypass(&mut self, bit: bool) {
        if self.enc.encode_symbol(bit, Bin(HALF)).is_err() {
            self.failed = true;
        }
    }
}

/// Reads little-endian words straight from the container's bytes (no copy).
/// Past the end it reports exhaustion, which the range decoder treats as
/// zero padding; corrupt data then shows up as an error or a checksum miss.
pub struct LeWords<'a> {
    bytes: &'a [u8],
}

impl ReadWords<u32, Queue> for LeWords<'_> {
    type ReadError = Infallible;
    #[inline]
    fn read(&mut self) -> Result<Option<u32>, Infallible> {
        match self.bytes.split_first_chunk::<4>() {
            Some((w, rest)) => {
                self.bytes = rest;
                Ok(Some(u32::from_le_bytes(*w)))
            }
            None => Ok(None),
        }
    }
}

/// Range decoder over one stream; errors latch into [`Reader::failed`].
pub struct Reader<'a> {
    dec: RangeDecoder<u32, u64, LeWords<'a>>,
    failed: bool,
}

impl<'a> Reader<'a> {
    /// `bytes` must be a whole number of words (the writer emits words).
    pub fn new(bytes: &'a [u8]) -> Option<Self> {
        if bytes.len() % 4 != 0 {
            return None;
        }
        let dec = RangeDecoder::with_backend(LeWords { bytes }).ok()?;
        Some(Self { dec, failed: false })
    }
    #[inline]
    pub fn bit(&mut self, ctx: &mut Ctx) -> bool {
        match self.dec.decode_symbol(Bin(ctx.0)) {
            Ok(b) => {
                ctx.update(b);
                b
            }
            Err(_) => {
                self.failed = true;
                false
            }
        }
    }
    #[inline]
    pub fn bypass(&mut self) -> bool {
        match self.dec.decode_symbol(Bin(HALF)) {
            Ok(b) => b,
            Err(_) => {
                self.failed = true;
                false
            }
        }
    }
    pub fn failed(&self) -> bool {
        self.failed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_round_trip_and_cost_tracks_size() {
        let bits: Vec<bool> = (0..5000).map(|i| i % 13 == 0 || i % 7 == 0).collect();
        let mut w = Writer::default();
        let mut meter = CostMeter::default();
        let (mut c1, mut c2) = (Ctx::default(), Ctx::default());
        for &b in &bits {
            w.bit(&mut c1, b);
            meter.bit(&mut c2, b);
            w.bypass(b);
            meter.bypass(b);
        }
        let bytes = w.finish().unwrap();
        let actual = bytes.len() as f64 * 8.0;
        assert!(
            (actual - meter.bits).abs() < 0.02 * meter.bits + 96.0,
            "{actual} vs {}",
            meter.bits
        );
        let mut r = Reader::new(&bytes).unwrap();
        let mut c = Ctx::default();
        for &b in &bits {
            assert_eq!(r.bit(&mut c), b);
            assert_eq!(r.bypass(), b);
        }
        assert!(!r.failed());
    }

    #[test]
    fn garbage_does_not_panic() {
        let junk: Vec<u8> = (0..64u32).map(|i| (i * 97 + 13) as u8).collect();
        let mut r = Reader::new(&junk).unwrap();
        let mut c = Ctx::default();
        for _ in 0..10_000 {
            r.bit(&mut c);
        }
        assert!(Reader::new(&junk[..3]).is_none());
    }
}
