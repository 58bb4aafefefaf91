//! Round trips, rate control, random access, cache and report.

use codec::report::{ReportOptions, report};
use codec::synth::{SynthSpec, scene};
use codec::{
    CodecError, Container, DecodeCache, EncodeInput, EncodeOptions, Lifetimes, ParamGrid,
    PsnrAccum, Target, TextureId, encode, encode::Weighting, encode_to_file,
};
use half::f16;

fn small_scene(samples: u32) -> EncodeInput {
    scene(&SynthSpec::cube(2, 2, ParamGrid::one_d(samples), 32))
}

/// PSNR of every texture over every sample, decoded as f32.
fn measure(c: &Container, input: &EncodeInput) -> (f64, Vec<f64>) {
    let mut total = PsnrAccum::default();
    let mut per = Vec::new();
    let mut cache = DecodeCache::default();
    for t in &input.textures {
        let mut acc = PsnrAccum::default();
        let mut out = vec![0.0f32; t.layout.texels() * 4];
        for s1 in 0..t.grid.n1 {
            for s0 in 0..t.grid.n0 {
                cache
                    .decode_leaf_all(c, t.id.object, t.id.layer, [s0, s1], &mut out)
                    .unwrap();
                assert!(out.iter().all(|v| v.is_finite()));
                acc.add(
                    t.sample(t.grid.index([s0, s1]).unwrap()),
                    t.layout.channels as usize,
                    &out,
                    4,
                );
            }
            cache.end_frame();
        }
        total.merge(&acc);
        per.push(acc.mse());
    }
    (total.psnr_db(), per)
}

#[test]
fn round_trip_1d_at_384_to_1() {
    let input = small_scene(12);
    let (bytes, rep) = encode(&input, Target::Ratio(384.0), &EncodeOptions::default()).unwrap();
    assert!(
        bytes.len() as u64 <= input.raw_bytes() / 384,
        "{} bytes",
        bytes.len()
    );
    assert_eq!(rep.bytes, bytes.len() as u64);
    let c = Container::from_bytes(bytes).unwrap();
    let (psnr, _) = measure(&c, &input);
    // Synthetic smooth content: stated bound with margin over the measured value.
    assert!(psnr >= 45.0, "psnr {psnr}");
}

#[test]
fn round_trip_2d_rgb_single_face() {
    let mut spec = SynthSpec::cube(1, 1, ParamGrid::two_d(10, 9), 16);
    spec.faces = 1;
    spec.channels = 3;
    let input = scene(&spec);
    let (bytes, rep) = encode(&input, Target::Ratio(48.0), &EncodeOptions::default()).unwrap();
    assert!(
        rep.textures[0]
            .plans
            .iter()
            .all(|p| p.first() == Some(&[0, 0]) && p.last() == Some(&[3, 3]))
    );
    let c = Container::from_bytes(bytes).unwrap();
    let (psnr, _) = measure(&c, &input);
    assert!(psnr >= 40.0, "psnr {psnr}");
}

#[test]
fn higher_budget_gives_higher_psnr_and_f16_matches_f32() {
    let input = small_scene(8);
    let mut last = 0.0;
    for r in [768.0, 192.0, 48.0] {
        let (bytes, _) = encode(&input, Target::Ratio(r), &EncodeOptions::default()).unwrap();
        let c = Container::from_bytes(bytes).unwrap();
        let (psnr, _) = measure(&c, &input);
        assert!(psnr > last, "ratio {r}: {psnr} <= {last}");
        last = psnr;
        let n = input.textures[0].layout.texels() * 4;
        let (mut a, mut b) = (vec![0.0f32; n], vec![f16::ZERO; n]);
        codec::decode_leaf_all(&c, 0, 0, [5, 0], &mut a).unwrap();
        codec::decode_leaf_all(&c, 0, 0, [5, 0], &mut b).unwrap();
        for (x, y) in a.iter().zip(&b) {
            assert!(
                (x - y.to_f32()).abs() <= 1e-3 * x.abs().max(1e-2),
                "{x} vs {y}"
            );
        }
    }
}

#[test]
fn byte_budgets_are_met() {
    let input = small_scene(9);
    for budget in [9_000u64, 15_000, 40_000, 100_000] {
        let (bytes, rep) =
            encode(&input, Target::Bytes(budget), &EncodeOptions::default()).unwrap();
        assert!(bytes.len() as u64 <= budget, "{} > {budget}", bytes.len());
        // Not wastefully below it either.
        assert!(
            bytes.len() as u64 >= budget * 8 / 10,
            "{} << {budget}",
            bytes.len()
        );
        assert_eq!(rep.budget_bytes, budget);
    }
    let e = encode(&input, Target::Bytes(100), &EncodeOptions::default()).unwrap_err();
    assert!(matches!(e, CodecError::BudgetTooSmall { .. }), "{e}");
    for bad in [
        Target::Ratio(0.0),
        Target::Ratio(f64::NAN),
        Target::Bytes(0),
    ] {
        assert!(matches!(
            encode(&input, bad, &EncodeOptions::default()),
            Err(CodecError::BadRequest(_))
        ));
    }
}

#[test]
fn alpha_cap_bounds_each_texture_mse() {
    // Four textures; object 1's screen area is tiny so an uncapped
    // allocation starves it.
    let mut input = small_scene(8);
    for t in &mut input.textures {
        t.screen_area = if t.id.object == 1 { 1.0 } else { 10_000.0 };
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let free = EncodeOptions {
        alpha_cap: f64::INFINITY,
        ..Default::default()
    };
    let (_, rep) = encode(&input, Target::Ratio(384.0), &free).unwrap();
    let mse: Vec<f64> = rep.textures.iter().map(|t| t.predicted_mse).collect();
    let worst = mse.iter().cloned().fold(0.0, f64::max);
    assert!(
        worst > 1.25 * mean(&mse),
        "uncapped allocation already within the cap: {mse:?}"
    );

    let (bytes, rep) = encode(&input, Target::Ratio(384.0), &EncodeOptions::default()).unwrap();
    assert!(bytes.len() as u64 <= input.raw_bytes() / 384);
    let mse: Vec<f64> = rep.textures.iter().map(|t| t.predicted_mse).collect();
    let worst = mse.iter().cloned().fold(0.0, f64::max);
    assert!(worst <= 1.25 * mean(&mse) * 1.02, "{mse:?}");
    // The measured errors follow the predicted ones.
    let (_, measured) = measure(&Container::from_bytes(bytes).unwrap(), &input);
    let worst = measured.iter().cloned().fold(0.0, f64::max);
    assert!(worst <= 1.6 * mean(&measured), "{measured:?}");
}

#[test]
fn a_sample_reads_only_its_block() {
    let input = small_scene(20);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.ptxc");
    encode_to_file(
        &input,
        Target::Ratio(200.0),
        &EncodeOptions::default(),
        &path,
    )
    .unwrap();
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "temporary file left behind"
    );

    let c = Container::open(&path).unwrap();
    let header = c.bytes_read();
    let t = &c.textures()[0];
    assert!(t.block_count() >= 3);
    let (block, _) = t.locate([10, 0]).unwrap();
    let mut out = vec![0.0f32; t.layout.texels() * 4];
    DecodeCache::default()
        .decode_leaf_all(&c, 0, 0, [10, 0], &mut out)
        .unwrap();
    assert_eq!(c.bytes_read() - header, c.block_entries()[block].len as u64);

    // Corrupt every other block: this sample still decodes identically.
    let mut bytes = std::fs::read(&path).unwrap();
    for (i, e) in c.block_entries().iter().enumerate() {
        if i != block {
            bytes[e.offset as usize + e.len as usize / 2] ^= 0x55;
        }
    }
    let bad = Container::from_bytes(bytes).unwrap();
    let mut out2 = vec![0.0f32; out.len()];
    DecodeCache::default()
        .decode_leaf_all(&bad, 0, 0, [10, 0], &mut out2)
        .unwrap();
    assert_eq!(out, out2);
    let other = t.locate([0, 0]).unwrap().0;
    assert_ne!(other, block);
    let e = DecodeCache::default()
        .decode_leaf_all(&bad, 0, 0, [0, 0], &mut out2)
        .unwrap_err();
    assert!(
        matches!(e, CodecError::BlockChecksum { block: b, .. } if b == other),
        "{e}"
    );
}

#[test]
fn objects_get_staggered_block_origins() {
    let input = small_scene(20);
    let (bytes, _) = encode(&input, Target::Ratio(100.0), &EncodeOptions::default()).unwrap();
    let c = Container::from_bytes(bytes).unwrap();
    let s = |o: u32| {
        c.textures()
            .iter()
            .find(|t| t.id.object == o)
            .unwrap()
            .stagger
    };
    assert_ne!(s(0), s(1));
    // Layers of one object share the origin.
    let layers: Vec<_> = c
        .textures()
        .iter()
        .filter(|t| t.id.object == 1)
        .map(|t| t.stagger)
        .collect();
    assert!(layers.windows(2).all(|w| w[0] == w[1]));
}

#[test]
fn cache_lifetimes_follow_a_b_pow_level() {
    let input = small_scene(8);
    let (bytes, rep) = encode(&input, Target::Ratio(100.0), &EncodeOptions::default()).unwrap();
    let levels = rep.textures[0].plans[0].len();
    assert_eq!(levels, 4);
    let c = Container::from_bytes(bytes).unwrap();
    let mut cache = DecodeCache::new(Lifetimes { a: 2, b: 3 });
    let mut out = vec![0.0f32; input.textures[0].layout.texels() * 4];
    cache.decode_leaf_all(&c, 0, 0, [2, 0], &mut out).unwrap();
    let faces = 6;
    assert_eq!(cache.stats().resident_images, levels * faces);
    assert_eq!(cache.stats().misses, (levels * faces) as u64);
    cache.decode_leaf_all(&c, 0, 0, [2, 0], &mut out).unwrap();
    assert_eq!(
        cache.stats().misses,
        (levels * faces) as u64,
        "second decode must hit"
    );
    // Leaves live a = 2 frames, the next level a·b = 6, then 18, 54.
    let mut resident = Vec::new();
    for _ in 0..60 {
        cache.end_frame();
        resident.push(cache.stats().resident_images / faces);
    }
    assert_eq!(resident[1], 4);
    assert_eq!(resident[2], 3, "leaf level expires after 2 frames");
    assert_eq!(resident[5], 3);
    assert_eq!(resident[6], 2);
    assert_eq!(resident[18], 1);
    assert_eq!(resident[54], 0);
    // A neighbour in the same pair reuses everything but the leaf.
    let mut cache = DecodeCache::default();
    cache.decode_leaf_all(&c, 0, 0, [2, 0], &mut out).unwrap();
    let m = cache.stats().misses;
    cache.decode_leaf_all(&c, 0, 0, [3, 0], &mut out).unwrap();
    assert_eq!(cache.stats().misses - m, faces as u64);
}

#[test]
fn single_face_mip_decode_matches_full_leaf() {
    let input = small_scene(8);
    let (bytes, _) = encode(&input, Target::Ratio(100.0), &EncodeOptions::default()).unwrap();
    let c = Container::from_bytes(bytes).unwrap();
    let l = input.textures[1].layout;
    let mut all = vec![0.0f32; l.texels() * 4];
    codec::decode_leaf_all(&c, 0, 1, [4, 0], &mut all).unwrap();
    let mut cache = DecodeCache::default();
    for (face, mip) in [(0, 0), (3, 2), (5, l.mips - 1)] {
        let mut one = vec![0.0f32; l.face_texels(mip) * 4];
        cache
            .decode_leaf(&c, 0, 1, [4, 0], face, mip, &mut one)
            .unwrap();
        let o = l.texel_offset(face, mip) * 4;
        assert_eq!(&all[o..o + one.len()], &one[..]);
    }
    let mut one = vec![0.0f32; 4];
    assert!(matches!(
        cache.decode_leaf(&c, 0, 1, [4, 0], 6, 0, &mut one),
        Err(CodecError::IndexOutOfRange { what: "face", .. })
    ));
    let mut mip0 = vec![0.0f32; l.face_texels(0) * 4];
    assert!(matches!(
        cache.decode_leaf(&c, 0, 1, [8, 0], 0, 0, &mut mip0),
        Err(CodecError::IndexOutOfRange {
            what: "sample[0]",
            ..
        })
    ));
    assert!(matches!(
        cache.decode_leaf(&c, 0, 1, [0, 0], 0, l.mips - 1, &mut one[..3]),
        Err(CodecError::OutputSize { .. })
    ));
    assert!(matches!(
        cache.decode_leaf(&c, 7, 0, [0, 0], 0, 0, &mut one),
        Err(CodecError::NoSuchTexture {
            object: 7,
            layer: 0
        })
    ));
}

#[test]
fn non_finite_input_is_rejected_with_its_location() {
    let mut input = small_scene(4);
    let n = input.textures[1].sample_len();
    input.textures[1].data[2 * n + 17] = f32::NAN;
    let e = encode(&input, Target::Ratio(10.0), &EncodeOptions::default()).unwrap_err();
    assert!(
        matches!(
            e,
            CodecError::NonFinite {
                object: 0,
                layer: 1,
                sample: 2,
                element: 17,
                ..
            }
        ),
        "{e}"
    );
    input.textures[1].data[2 * n + 17] = f32::INFINITY;
    assert!(matches!(
        encode(&input, Target::Ratio(10.0), &EncodeOptions::default()),
        Err(CodecError::NonFinite { .. })
    ));
    let mut dup = small_scene(4);
    dup.textures[1].id = TextureId {
        object: 0,
        layer: 0,
    };
    assert!(matches!(
        encode(&dup, Target::Ratio(10.0), &EncodeOptions::default()),
        Err(CodecError::BadRequest(_))
    ));
    let mut short = small_scene(4);
    short.textures[0].data.pop();
    assert!(matches!(
        encode(&short, Target::Ratio(10.0), &EncodeOptions::default()),
        Err(CodecError::BadInput { .. })
    ));
}

#[test]
fn report_has_the_json_fields() {
    let mut spec = SynthSpec::cube(1, 1, ParamGrid::one_d(4), 16);
    spec.faces = 1;
    let input = scene(&spec);
    let (bytes, _) = encode(&input, Target::Ratio(20.0), &EncodeOptions::default()).unwrap();
    let c = Container::from_bytes(bytes).unwrap();
    let rep = report(
        &c,
        &input,
        &ReportOptions {
            jpeg_baseline: true,
            ffmpeg_baseline: false,
            videos: Vec::new(),
        },
    )
    .unwrap();
    let v = serde_json::to_value(&rep).unwrap();
    assert!(v["ratio"].as_f64().unwrap() > 19.0);
    assert!(v["psnr_db"].as_f64().unwrap() > 30.0);
    assert_eq!(v["bytes"].as_u64().unwrap(), c.file_len());
    assert!(v["decode_ms_median"].as_f64().unwrap() >= 0.0);
    let b = &v["baselines"][0];
    assert_eq!(b["name"], "jpeg-per-texture");
    assert!(b["ratio"].as_f64().unwrap() > 0.0 && b["psnr_db"].as_f64().unwrap() > 0.0);
}

#[test]
fn several_targets_at_once_match_separate_encodes() {
    let input = small_scene(9);
    let targets = [
        Target::Ratio(300.0),
        Target::Bytes(40_000),
        Target::Ratio(60.0),
    ];
    let all = codec::encode_targets(&input, &targets, &EncodeOptions::default()).unwrap();
    assert_eq!(all.len(), targets.len());
    for (t, (bytes, rep)) in targets.iter().zip(&all) {
        let (alone, alone_rep) = encode(&input, *t, &EncodeOptions::default()).unwrap();
        assert!(*bytes == alone, "{t:?}: containers differ");
        assert_eq!(rep.bytes, alone_rep.bytes);
    }
    assert!(codec::encode_targets(&input, &[], &EncodeOptions::default()).is_err());
    let tiny = [Target::Ratio(100.0), Target::Bytes(100)];
    assert!(matches!(
        codec::encode_targets(&input, &tiny, &EncodeOptions::default()),
        Err(CodecError::BudgetTooSmall { budget: 100, .. })
    ));
}

#[test]
fn texel_weighting_maximises_the_pooled_texture_psnr() {
    // A cube map and a single-face texture of equal screen area: the
    // thesis's weighting gives the small one six times the weight per
    // element, texel weighting weighs every element alike.
    let cube = scene(&SynthSpec::cube(1, 1, ParamGrid::one_d(8), 32));
    let mut flat = SynthSpec::cube(2, 1, ParamGrid::one_d(8), 32);
    flat.faces = 1;
    let mut input = cube;
    input.textures.push(scene(&flat).textures.remove(1));
    for t in &mut input.textures {
        t.screen_area = 1.0;
    }
    let texels = EncodeOptions {
        weighting: Weighting::Texels,
        alpha_cap: f64::INFINITY,
        ..Default::default()
    };
    let mut psnr = Vec::new();
    for opts in [EncodeOptions::default(), texels] {
        let (bytes, _) = encode(&input, Target::Ratio(384.0), &opts).unwrap();
        assert!(bytes.len() as u64 <= input.raw_bytes() / 384);
        psnr.push(measure(&Container::from_bytes(bytes).unwrap(), &input).0);
    }
    eprintln!("MEASURE {psnr:?}");
    assert!(
        psnr[1] > psnr[0] + 0.1,
        "screen {} dB, texels {} dB",
        psnr[0],
        psnr[1]
    );
}
