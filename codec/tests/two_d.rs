//! 2D parameter blocks (8×8 samples, adaptive subdivision order) go through
//! the same pyramid, coder and decoder as 1D blocks (8 samples).

use codec::synth::{SynthSpec, scene};
use codec::{
    Container, DecodeCache, EncodeInput, EncodeOptions, ParamGrid, ParamTexture, PsnrAccum, Target,
    encode,
};

fn psnr_all(c: &Container, input: &EncodeInput) -> f64 {
    let mut acc = PsnrAccum::default();
    let mut cache = DecodeCache::default();
    for t in &input.textures {
        let mut out = vec![0.0f32; t.layout.texels() * 4];
        for s1 in 0..t.grid.n1 {
            for s0 in 0..t.grid.n0 {
                cache
                    .decode_leaf_all(c, t.id.object, t.id.layer, [s0, s1], &mut out)
                    .unwrap();
                let s = t.grid.index([s0, s1]).unwrap();
                acc.add(t.sample(s), t.layout.channels as usize, &out, 4);
                cache.end_frame();
            }
        }
    }
    acc.psnr_db()
}

#[test]
fn one_d_and_two_d_blocks_round_trip_through_the_same_coder() {
    for (grid, last) in [
        (ParamGrid::one_d(64), [3u8, 0u8]),
        (ParamGrid::two_d(8, 8), [3, 3]),
    ] {
        let input = scene(&SynthSpec::cube(1, 1, grid, 16));
        let (bytes, rep) = encode(&input, Target::Ratio(96.0), &EncodeOptions::default()).unwrap();
        assert!(bytes.len() as u64 <= input.raw_bytes() / 96);
        for plan in &rep.textures[0].plans {
            assert_eq!(plan.first(), Some(&[0, 0]), "{grid:?}: {plan:?}");
            assert_eq!(plan.last(), Some(&last), "{grid:?}: {plan:?}");
        }
        let c = Container::from_bytes(bytes).unwrap();
        // Measured 58.7 dB (1D) and 54.1 dB (2D) on this content.
        let psnr = psnr_all(&c, &input);
        let bound = if grid.dims() == 1 { 55.0 } else { 51.0 };
        assert!(psnr >= bound, "{grid:?}: {psnr} dB");
    }
}

/// A 2D texture whose samples vary along dimension `strong` only (the
/// other dimension nearly constant), from a 1D synthetic sequence.
fn anisotropic(strong: usize) -> EncodeInput {
    let line = scene(&SynthSpec::cube(1, 1, ParamGrid::one_d(8), 8));
    let src = &line.textures[0];
    let mut t = ParamTexture::zeroed(src.id, ParamGrid::two_d(8, 8), src.layout, 1.0);
    for i1 in 0..8u32 {
        for i0 in 0..8u32 {
            let (k, weak) = if strong == 0 { (i0, i1) } else { (i1, i0) };
            let s = t.grid.index([i0, i1]).unwrap();
            let scale = 1.0 + 1e-3 * weak as f32;
            t.sample_mut(s)
                .iter_mut()
                .zip(src.sample(k as usize))
                .for_each(|(d, v)| *d = v * scale);
        }
    }
    EncodeInput { textures: vec![t] }
}

#[test]
fn two_d_order_splits_the_less_coherent_dimension_first_and_decodes() {
    for (strong, first_split) in [(0, [2u8, 0u8]), (1, [0, 2])] {
        let input = anisotropic(strong);
        let (bytes, rep) = encode(&input, Target::Ratio(24.0), &EncodeOptions::default()).unwrap();
        let plans = &rep.textures[0].plans;
        assert_eq!(plans.len(), 1);
        assert_eq!(
            plans[0][1], first_split,
            "strong dim {strong}: {:?}",
            plans[0]
        );
        let c = Container::from_bytes(bytes).unwrap();
        // Measured 72.0 dB either way.
        let psnr = psnr_all(&c, &input);
        assert!(psnr >= 65.0, "strong dim {strong}: {psnr} dB");
    }
}

#[test]
fn sample_at_inverts_index_in_one_and_two_d() {
    for grid in [ParamGrid::one_d(13), ParamGrid::two_d(4, 3)] {
        for linear in 0..grid.len() as u32 {
            let at = grid.sample_at(linear);
            assert_eq!(grid.index(at).unwrap(), linear as usize, "{grid:?}");
        }
        assert!(
            grid.index(grid.sample_at(grid.len() as u32)).is_err(),
            "past the grid"
        );
    }
    assert_eq!(ParamGrid::two_d(4, 3).sample_at(6), [2, 1]);
}

/// A container that lays a 2D space out as a 1D sequence (as the engine
/// did before 2D blocks) is still measured against the 2D input: samples
/// match by linear index.
#[test]
fn report_matches_a_1d_container_to_a_2d_input_by_linear_index() {
    use codec::report::report;
    let two_d = scene(&SynthSpec::cube(1, 1, ParamGrid::two_d(4, 3), 16));
    let mut one_d = two_d.clone();
    for t in &mut one_d.textures {
        t.grid = ParamGrid::one_d(12);
    }
    let (bytes, _) = encode(&one_d, Target::Ratio(40.0), &EncodeOptions::default()).unwrap();
    let c = Container::from_bytes(bytes).unwrap();
    let opts = no_baselines();
    let against_2d = report(&c, &two_d, &opts).unwrap();
    let against_1d = report(&c, &one_d, &opts).unwrap();
    assert_eq!(against_2d.psnr_db, against_1d.psnr_db);
    assert!((psnr_all(&c, &one_d) - against_1d.psnr_db).abs() < 0.5);
}

/// Reference maps that are not the container's (fewer samples, another
/// size) are refused with both shapes named, not measured as garbage.
#[test]
fn report_refuses_maps_the_container_was_not_encoded_from() {
    use codec::report::report;
    let input = scene(&SynthSpec::cube(1, 1, ParamGrid::one_d(12), 16));
    let (bytes, _) = encode(&input, Target::Ratio(40.0), &EncodeOptions::default()).unwrap();
    let c = Container::from_bytes(bytes).unwrap();
    let opts = no_baselines();
    let fewer = scene(&SynthSpec::cube(1, 1, ParamGrid::one_d(6), 16));
    let smaller = scene(&SynthSpec::cube(1, 1, ParamGrid::one_d(12), 8));
    for (other, expect) in [
        (fewer, "6 samples of 16×16"),
        (smaller, "12 samples of 8×8"),
    ] {
        let e = report(&c, &other, &opts)
            .expect_err("mismatched maps")
            .to_string();
        assert!(
            e.contains("12 samples of 16×16") && e.contains(expect),
            "{e}"
        );
    }
    assert!(report(&c, &input, &opts).is_ok());
}

/// A report of the container alone: no JPEG, no video baselines.
fn no_baselines() -> codec::report::ReportOptions {
    codec::report::ReportOptions {
        jpeg_baseline: false,
        ffmpeg_baseline: false,
        videos: Vec::new(),
    }
}
