//! Per-sample shell maps in playback: every sample's map in one cube-map
//! array, and each frame the two samples whose azimuths bracket the eye's,
//! mixed linearly (as the PEM's 1D blend): `glass_blend.frag` reads both.

/// The per-sample shell maps of the orbit lines at `azimuths` (increasing),
/// each the f16 RGBA bytes of a full MIP chain (level-major, face, rows).
#[derive(Clone, Debug, PartialEq)]
pub struct SampleShells {
    pub azimuths: Vec<f32>,
    pub maps: Vec<Vec<u8>>,
}

/// Every shell layer's per-sample maps: `layers[k][s]`, f16 RGBA bytes of
/// a full MIP chain, nearest layer first, samples at `azimuths`.
#[derive(Clone, Debug, PartialEq)]
pub struct LayerSamples {
    pub azimuths: Vec<f32>,
    pub layers: Vec<Vec<Vec<u8>>>,
}

/// Layers `a`, `b` of the array and the weight of `b` for an eye at
/// azimuth `az` (degrees, any turn): linear between the bracketing
/// samples, the nearest end outside them. None without samples.
pub fn blend_of(azimuths: &[f32], az: f32) -> Option<(u32, u32, f32)> {
    let (&first, &last) = (azimuths.first()?, azimuths.last()?);
    // The turn of `az` nearest the samples' middle (atan2 gives ±180°).
    let mid = 0.5 * (first + last);
    let az = az - 360.0 * ((az - mid) / 360.0).round();
    if !az.is_finite() || az <= first {
        return Some((0, 0, 0.0));
    }
    let n = azimuths.len() as u32;
    if az >= last {
        return Some((n - 1, n - 1, 0.0));
    }
    let b = azimuths
        .partition_point(|&s| s <= az)
        .min(azimuths.len() - 1);
    let a = b - 1;
    let w = (az - azimuths[a]) / (azimuths[b] - azimuths[a]);
    Some((a as u32, b as u32, w.clamp(0.0, 1.0)))
}

/// The maps' bytes in a cube-map array's upload order: level-major, then
/// element, then face and rows. `level_bytes[l]` is one map's level `l`.
pub fn array_bytes<M: AsRef<[u8]>>(maps: &[M], level_bytes: &[usize]) -> Option<Vec<u8>> {
    let per_map: usize = level_bytes.iter().sum();
    if maps.iter().any(|m| m.as_ref().len() != per_map) {
        return None;
    }
    let mut out = Vec::with_capacity(per_map * maps.len());
    let mut offset = 0;
    for &n in level_bytes {
        for m in maps {
            out.extend_from_slice(&m.as_ref()[offset..offset + n]);
        }
        offset += n;
    }
    Some(out)
}

/// Maps of f16 RGBA texels (equal sizes) as one whose every texel is the
/// one with the largest alpha among them: what any of them covers.
pub fn max_alpha(maps: &[Vec<u8>]) -> Vec<u8> {
    let Some(first) = maps.first() else {
        return Vec::new();
    };
    let alpha = |m: &[u8], t: usize| {
        m.get(8 * t + 6..8 * t + 8).map_or(f32::NEG_INFINITY, |b| {
            half::f16::from_le_bytes([b[0], b[1]]).to_f32()
        })
    };
    let mut out = first.clone();
    for m in &maps[1..] {
        for t in 0..out.len() / 8 {
            if alpha(m, t) > alpha(&out, t) {
                out[8 * t..8 * t + 8].copy_from_slice(&m[8 * t..8 * t + 8]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blend_brackets_the_eye_and_clamps_outside() {
        let az = [0.0, 10.0, 20.0, 25.0];
        assert_eq!(blend_of(&az, 0.0), Some((0, 0, 0.0)));
        assert_eq!(blend_of(&az, 10.0), Some((1, 2, 0.0)));
        assert_eq!(blend_of(&az, 12.5), Some((1, 2, 0.25)));
        assert_eq!(blend_of(&az, 22.5), Some((2, 3, 0.5)));
        assert_eq!(blend_of(&az, 30.0), Some((3, 3, 0.0)));
        assert_eq!(blend_of(&az, -5.0), Some((0, 0, 0.0)));
        // Another turn of the same azimuth.
        assert_eq!(blend_of(&az, 372.5), Some((1, 2, 0.25)));
        assert_eq!(blend_of(&az, f32::NAN), Some((0, 0, 0.0)));
        assert_eq!(blend_of(&[5.0], 7.0), Some((0, 0, 0.0)));
        assert_eq!(blend_of(&[], 7.0), None);
    }

    #[test]
    fn array_bytes_interleave_levels_and_refuse_odd_maps() {
        // Two maps of levels 3 + 1 bytes.
        let maps = vec![vec![1, 2, 3, 4], vec![5, 6, 7, 8]];
        assert_eq!(
            array_bytes(&maps, &[3, 1]),
            Some(vec![1, 2, 3, 5, 6, 7, 4, 8])
        );
        assert_eq!(array_bytes(&[vec![1, 2]], &[3, 1]), None);
    }

    #[test]
    fn max_alpha_keeps_each_texels_most_covered_sample() {
        let texel = |rgba: [f32; 4]| -> Vec<u8> {
            rgba.iter()
                .flat_map(|&x| half::f16::from_f32(x).to_le_bytes())
                .collect()
        };
        let a = [texel([1.0, 0.0, 0.0, 0.0]), texel([2.0, 0.0, 0.0, 0.75])].concat();
        let b = [texel([3.0, 0.0, 0.0, 0.5]), texel([4.0, 0.0, 0.0, 0.25])].concat();
        let max = max_alpha(&[a, b]);
        assert_eq!(
            max,
            [texel([3.0, 0.0, 0.0, 0.5]), texel([2.0, 0.0, 0.0, 0.75])].concat()
        );
        assert!(max_alpha(&[]).is_empty());
    }
}
