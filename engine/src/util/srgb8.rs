//! Linear values to 8-bit sRGB, as every PNG the engine writes and every
//! display-referred score encodes them, without a `powf` per channel.
//!
//! The reference is `(linear_to_srgb(x) * 255 + 0.5) as u8`
//! ([`crate::capture::linear_to_srgb`]): a non-decreasing step function of
//! `x` with 255 steps. Its thresholds (the smallest `f32` at which each
//! byte begins) are found once by bisection over the bit patterns, which
//! order positive floats as their values. Buckets of the top 16 bits of
//! `x` (7 mantissa bits: 0.8% wide, narrower than any step, 0.89% near 1)
//! hold at most one threshold each, so a bucket's byte plus one comparison
//! gives the reference's byte exactly. A frame of 640×480 took ~7 ms of
//! `powf` on the capture writer.

use std::sync::LazyLock;

/// Bucket of a value in (0, 1): the top 16 bits of its bit pattern.
const BUCKETS: usize = (1.0f32.to_bits() >> 16) as usize + 1;

struct Table {
    /// The reference's byte at each bucket's first value.
    base: Vec<u8>,
    /// `start[k]`: the smallest value encoded as byte `k` (k = 1..=255);
    /// `start[0] = 0`, `start[256] = ∞`.
    start: [f32; 257],
}

static TABLE: LazyLock<Table> = LazyLock::new(Table::new);

/// The reference encoding, kept beside the table it builds.
fn reference(x: f32) -> u8 {
    (crate::capture::linear_to_srgb(x) * 255.0 + 0.5) as u8
}

impl Table {
    fn new() -> Self {
        let mut start = [f32::INFINITY; 257];
        start[0] = 0.0;
        for (k, s) in start.iter_mut().enumerate().take(256).skip(1) {
            // Smallest bit pattern in [0, 1] whose byte is ≥ k.
            let (mut lo, mut hi) = (0u32, 1.0f32.to_bits());
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                match reference(f32::from_bits(mid)) as usize >= k {
                    true => hi = mid,
                    false => lo = mid + 1,
                }
            }
            *s = f32::from_bits(lo);
        }
        let base = (0..BUCKETS)
            .map(|b| reference(f32::from_bits((b as u32) << 16)))
            .collect();
        Self { base, start }
    }
}

/// `x` (linear) as an 8-bit sRGB byte: clamped to [0, 1], NaN and ±∞ to 0,
/// exactly the reference's byte.
pub fn srgb8(x: f32) -> u8 {
    if !x.is_finite() || x <= 0.0 {
        return 0;
    }
    if x >= 1.0 {
        return 255;
    }
    let t = &*TABLE;
    let byte = t.base[(x.to_bits() >> 16) as usize];
    byte + u8::from(x >= t.start[byte as usize + 1])
}

/// Every half float's byte: what the device's RGBA16F frames hold, one
/// table read a channel.
static HALF_TABLE: LazyLock<Vec<u8>> = LazyLock::new(|| {
    (0..=u16::MAX)
        .map(|bits| srgb8(half::f16::from_bits(bits).to_f32()))
        .collect()
});

/// RGB bytes of RGBA16F pixels (4 halves a pixel, alpha dropped): the
/// same bytes as [`srgb8_rgb`] of the pixels as floats.
pub fn srgb8_rgb_halves(halves: &[half::f16]) -> Vec<u8> {
    let table = &*HALF_TABLE;
    let mut out = Vec::with_capacity(halves.len() / 4 * 3);
    for p in halves.chunks_exact(4) {
        out.extend_from_slice(&[
            table[p[0].to_bits() as usize],
            table[p[1].to_bits() as usize],
            table[p[2].to_bits() as usize],
        ]);
    }
    out
}

/// RGB bytes of linear RGBA pixels (alpha dropped).
pub fn srgb8_rgb(pixels: &[[f32; 4]]) -> Vec<u8> {
    let mut out = Vec::with_capacity(pixels.len() * 3);
    for p in pixels {
        out.extend_from_slice(&[srgb8(p[0]), srgb8(p[1]), srgb8(p[2])]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every bucket holds at most one step, so one comparison suffices.
    #[test]
    fn each_bucket_spans_at_most_one_step() {
        for b in 0..BUCKETS - 1 {
            let first = reference(f32::from_bits((b as u32) << 16));
            let last = reference(f32::from_bits(((b as u32 + 1) << 16) - 1));
            assert!(
                u16::from(last) <= u16::from(first) + 1,
                "bucket {b:#x}: {first} to {last}"
            );
        }
    }

    /// Equal to the reference at every half-float (what the frames read
    /// back hold), around every step (±64 ulps) and at special values.
    #[test]
    fn equals_the_reference_exactly() {
        let mut checked = 0;
        for bits in 0..=u16::MAX {
            let x = half::f16::from_bits(bits).to_f32();
            assert_eq!(srgb8(x), reference(x), "{x:e} (f16 {bits:#06x})");
            checked += 1;
        }
        for &s in &TABLE.start[1..256] {
            let b = s.to_bits();
            for x in (b - 64..=b + 64).map(f32::from_bits) {
                assert_eq!(srgb8(x), reference(x), "{x:e} near the step at {s:e}");
                checked += 1;
            }
        }
        for x in [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            -0.0,
            -1.0,
            f32::MIN_POSITIVE,
            1e-45,
            0.003_130_8,
            0.999_999_94,
            1.0,
            1.5,
            f32::MAX,
        ] {
            assert_eq!(srgb8(x), reference(x), "{x:e}");
        }
        assert!(checked > 90_000);
    }

    /// A stride through every float in (0, 1).
    #[test]
    fn equals_the_reference_across_the_unit_interval() {
        let one = 1.0f32.to_bits();
        for bits in (1..one).step_by(997) {
            let x = f32::from_bits(bits);
            assert_eq!(srgb8(x), reference(x), "{x:e}");
        }
    }

    /// Half-float frames encode as their float pixels do.
    #[test]
    fn halves_encode_as_their_floats() {
        let halves: Vec<half::f16> = (0..=u16::MAX).map(half::f16::from_bits).collect();
        let floats: Vec<[f32; 4]> = halves
            .chunks_exact(4)
            .map(|p| [p[0].to_f32(), p[1].to_f32(), p[2].to_f32(), p[3].to_f32()])
            .collect();
        assert_eq!(srgb8_rgb_halves(&halves), srgb8_rgb(&floats));
    }

    #[test]
    fn rgb_drops_alpha() {
        let px = [[0.0, 0.5, 1.0, 0.25], [2.0, f32::NAN, 0.001, 1.0]];
        assert_eq!(
            srgb8_rgb(&px),
            vec![0, reference(0.5), 255, 255, 0, reference(0.001)]
        );
    }
}
