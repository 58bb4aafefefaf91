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
//! Decoding uses [`Reader`], a binary-only re-implementation of
//! constriction's range decoder that reads the same bytes (no format change)
//! several times faster.
//!
//! [`CostMeter`] runs the same binarisation without producing bits, summing
//! the ideal code length; the rate allocation uses it to draw rate/distortion
//! curves cheaply and without range-coder word granularity.

use std::borrow::Borrow;
use std::num::NonZeroU16;
use std::sync::OnceLock;

use constriction::stream::Encode;
use constriction::stream::model::{EncoderModel, EntropyModel};
use constriction::stream::queue::DefaultRangeEncoder;

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

/// Range decoder over one stream, bit-compatible with constriction's
/// `RangeDecoder<u32, u64>` (which [`Writer`] feeds) for the binary models
/// above; errors latch into [`Reader::failed`].
///
/// constriction's decoder is generic over arbitrary models and divides once
/// per symbol to find the quantile; for two symbols the same decision is a
/// comparison (`⌊d / scale⌋ < p0 ⟺ d < scale·p0`), and only `d = point − lower`
/// matters, never `lower` itself. The arithmetic is otherwise the same, step
/// for step — initial state, renormalisation, zero padding past the end, and
/// the "invalid data" condition — which `tests::matches_constriction` checks
/// on real and garbage streams. This loop is the decoder's hottest.
#[derive(Clone)]
pub struct Reader<'a> {
    /// Words not yet read (little-endian u32 each).
    words: &'a [u8],
    /// `point − lower` (wrapping), always `< range` on valid data.
    d: u64,
    range: u64,
    failed: bool,
}

impl<'a> Reader<'a> {
    /// `bytes` must be a whole number of words (the writer emits words).
    pub fn new(bytes: &'a [u8]) -> Option<Self> {
        if bytes.len() % 4 != 0 {
            return None;
        }
        let mut r = Self {
            words: bytes,
            d: 0,
            range: u64::MAX,
            failed: false,
        };
        // The initial point is the first two words, high word first; a
        // one-word stream is padded with a zero word.
        let mut point = 0u64;
        let mut read = 0;
        while read < 2 {
            match r.next_word() {
                Some(w) => {
                    point = (point << 32) | w;
                    read += 1;
                }
                None => break,
            }
        }
        if read == 1 {
            point <<= 32;
        }
        r.d = point;
        Some(r)
    }

    #[inline(always)]
    fn next_word(&mut self) -> Option<u64> {
        let (w, rest) = self.words.split_first_chunk::<4>()?;
        self.words = rest;
        Some(u32::from_le_bytes(*w) as u64)
    }

    /// One binary decision with P(false) = `p0` / 4096 (`p0` in 1..4096);
    /// `None` where constriction reports invalid data (state unchanged).
    #[inline(always)]
    fn decide(&mut self, p0: u16) -> Option<bool> {
        let scale = self.range >> PREC;
        if self.d >= scale << PREC {
            return None;
        }
        let bound = scale * p0 as u64;
        let bit = self.d >= bound;
        if bit {
            self.d -= bound;
            self.range = scale * (ONE - p0) as u64;
        } else {
            self.range = bound;
        }
        if self.range < 1 << 32 {
            self.range <<= 32;
            // Past the end the stream reads as zero words.
            self.d = (self.d << 32).wrapping_add(self.next_word().unwrap_or(0));
        }
        Some(bit)
    }

    #[inline(always)]
    pub fn bit(&mut self, ctx: &mut Ctx) -> bool {
        match self.decide(ctx.0) {
            Some(b) => {
                ctx.update(b);
                b
            }
            None => {
                self.failed = true;
                false
            }
        }
    }
    #[inline(always)]
    pub fn bypass(&mut self) -> bool {
        self.decide(HALF).unwrap_or_else(|| {
            self.failed = true;
            false
        })
    }
    pub fn failed(&self) -> bool {
        self.failed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use constriction::Queue;
    use constriction::backends::ReadWords;
    use constriction::stream::Decode;
    use constriction::stream::model::DecoderModel;
    use constriction::stream::queue::RangeDecoder;
    use std::convert::Infallible;

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

    /// The decoder this module replaced: constriction's own, over the same
    /// little-endian words. The reference for bit-compatibility.
    struct LeWords<'a>(&'a [u8]);
    impl ReadWords<u32, Queue> for LeWords<'_> {
        type ReadError = Infallible;
        fn read(&mut self) -> Result<Option<u32>, Infallible> {
            Ok(self.0.split_first_chunk::<4>().map(|(w, rest)| {
                self.0 = rest;
                u32::from_le_bytes(*w)
            }))
        }
    }
    struct Reference<'a> {
        dec: RangeDecoder<u32, u64, LeWords<'a>>,
        failed: bool,
    }
    impl<'a> Reference<'a> {
        fn new(bytes: &'a [u8]) -> Self {
            Self {
                dec: RangeDecoder::with_backend(LeWords(bytes)).unwrap(),
                failed: false,
            }
        }
        fn bit(&mut self, ctx: &mut Ctx) -> bool {
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
        fn bypass(&mut self) -> bool {
            self.dec.decode_symbol(Bin(HALF)).unwrap_or_else(|_| {
                self.failed = true;
                false
            })
        }
    }

    /// A small deterministic generator (no dependency needed).
    fn lcg(s: &mut u64) -> u64 {
        *s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        *s >> 33
    }

    #[test]
    fn matches_constriction() {
        // Real streams of skewed and mixed bits over several contexts, and
        // garbage (where both must fail at the same decision and agree on
        // every bit before and after), of several lengths including 0..=2
        // words.
        let mut seed = 7u64;
        let mut failures = 0;
        for case in 0..61 {
            let n = [0usize, 1, 3, 40, 700, 5000][case % 6];
            let bytes = if case == 60 {
                // The initial point lies beyond the last whole quantile.
                vec![0xff; 12]
            } else if case % 3 == 2 {
                let words = [0usize, 1, 2, 3, 17, 64][case % 6];
                (0..words * 4).map(|_| lcg(&mut seed) as u8).collect()
            } else {
                let mut w = Writer::default();
                let mut ctx = [Ctx::default(); 8];
                for i in 0..n {
                    let k = i % 8;
                    let b = lcg(&mut seed) % 100 < [1, 5, 20, 50, 80, 95, 99, 50][k];
                    if i % 5 == 4 {
                        w.bypass(b);
                    } else {
                        w.bit(&mut ctx[k], b);
                    }
                }
                w.finish().unwrap()
            };
            let mut ours = Reader::new(&bytes).unwrap();
            let mut theirs = Reference::new(&bytes);
            let (mut c1, mut c2) = ([Ctx::default(); 8], [Ctx::default(); 8]);
            for i in 0..n.max(300) + 64 {
                let k = i % 8;
                let (a, b) = if i % 5 == 4 {
                    (ours.bypass(), theirs.bypass())
                } else {
                    (ours.bit(&mut c1[k]), theirs.bit(&mut c2[k]))
                };
                assert_eq!(a, b, "case {case}, decision {i}");
                assert_eq!(ours.failed(), theirs.failed, "case {case}, decision {i}");
                assert_eq!(c1[k].0, c2[k].0);
            }
            failures += ours.failed() as usize;
        }
        assert!(failures > 0, "no stream exercised the invalid-data path");
    }

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
