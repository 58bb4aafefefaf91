//! Decoding ahead along the path (`DecodeCache::warm_ahead`): the leaves
//! stay bit for bit what a cold cache decodes, and once the motion is
//! steady no leaf decodes a coarse level itself — block boundaries included
//! (without warming every new block's first leaf decodes its root).

use codec::synth::{SynthSpec, scene};
use codec::{Container, DecodeCache, EncodeOptions, ParamGrid, Target, encode};

fn container(grid: ParamGrid) -> Container {
    let input = scene(&SynthSpec::cube(1, 1, grid, 16));
    let (bytes, _) = encode(&input, Target::Ratio(40.0), &EncodeOptions::default()).unwrap();
    Container::from_bytes(bytes).unwrap()
}

/// A leaf's output buffer for the container's texture.
fn leaf_out(c: &Container) -> Vec<f32> {
    vec![0.0f32; c.textures()[0].layout.texels() * 4]
}

/// Decodes `path` in order (warming after each leaf when `warm`); returns
/// every leaf's texels and the misses each leaf's own decode took.
fn walk(c: &Container, path: &[[u32; 2]], warm: bool) -> (Vec<Vec<f32>>, Vec<u64>) {
    let mut cache = DecodeCache::default();
    let (mut leaves, mut misses) = (Vec::new(), Vec::new());
    for &s in path {
        let mut out = leaf_out(c);
        let before = cache.stats().misses;
        cache.decode_leaf_all(c, 0, 0, s, &mut out).unwrap();
        misses.push(cache.stats().misses - before);
        if warm {
            cache.warm_ahead(c, 0, 0).unwrap();
        }
        cache.end_frame();
        leaves.push(out);
    }
    (leaves, misses)
}

#[test]
fn warmed_leaves_match_cold_ones_and_never_wait_for_a_coarse_level() {
    let c = container(ParamGrid::one_d(48));
    let faces = c.textures()[0].layout.faces as u64;
    let path: Vec<[u32; 2]> = (0..48).map(|i| [i, 0]).collect();
    let (warm, warm_misses) = walk(&c, &path, true);
    let (cold, cold_misses) = walk(&c, &path, false);
    for (i, (w, k)) in warm.iter().zip(&cold).enumerate() {
        let same = w.iter().zip(k).all(|(a, b)| a.to_bits() == b.to_bits());
        assert!(
            same,
            "sample {i}: the warmed leaf differs from the cold one"
        );
    }
    // Unwarmed, some leaves decode coarse levels (block boundaries)...
    assert!(
        cold_misses.iter().any(|&m| m > faces),
        "no leaf missed a coarse level without warming: {cold_misses:?}"
    );
    // ...warmed, after one look-ahead of steady motion none does.
    let settled = 2 + codec::LOOKAHEAD as usize;
    for (i, &m) in warm_misses.iter().enumerate().skip(settled) {
        assert_eq!(
            m, faces,
            "sample {i} decoded coarse levels itself: {warm_misses:?}"
        );
    }
    // The same total work, moved earlier: warming decodes no more images
    // than the walk needs (the last look-ahead runs off the grid).
    let total_cold: u64 = cold_misses.iter().sum();
    let total_warm: u64 = warm_misses.iter().sum();
    assert!(total_warm < total_cold);
}

#[test]
fn a_blend_alternating_its_samples_warms_nothing() {
    let c = container(ParamGrid::two_d(8, 8));
    let mut cache = DecodeCache::default();
    let mut out = leaf_out(&c);
    for s in [[3, 2], [3, 3], [3, 2], [3, 3], [3, 2]] {
        cache.decode_leaf_all(&c, 0, 0, s, &mut out).unwrap();
        assert_eq!(cache.warm_ahead(&c, 0, 0).unwrap(), 0);
    }
    assert_eq!(cache.stats().warmed, 0);
}

#[test]
fn steady_motion_along_the_second_axis_warms_ahead() {
    let c = container(ParamGrid::two_d(4, 16));
    let mut cache = DecodeCache::default();
    let mut out = leaf_out(&c);
    let mut warmed = 0;
    for s1 in 0..16 {
        cache.decode_leaf_all(&c, 0, 0, [1, s1], &mut out).unwrap();
        warmed += cache.warm_ahead(&c, 0, 0).unwrap();
        cache.end_frame();
    }
    assert!(warmed > 0, "steady motion along s1 warmed nothing");
    assert_eq!(cache.stats().warmed, warmed as u64);
    // The walk ran off the grid's end: the last call had nothing to warm.
    assert_eq!(cache.warm_ahead(&c, 0, 0).unwrap(), 0);
}
