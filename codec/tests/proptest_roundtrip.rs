//! Round trips of small random textures: any shape the input model allows,
//! any finite values (HDR and negative), generous budget → close result.

use codec::{
    Container, EncodeInput, EncodeOptions, LeafLayout, ParamGrid, ParamTexture, Target, TextureId,
    encode,
};
use proptest::prelude::*;

fn texture() -> impl Strategy<Value = ParamTexture> {
    (
        1u32..13,
        1u32..13,
        prop_oneof![Just(1u32), Just(6)],
        3u32..5,
        1u32..11,
        1u32..4,
        any::<u64>(),
    )
        .prop_flat_map(|(w, h, faces, ch, n0, n1, seed)| {
            let max_mips = LeafLayout::max_mips(w, h);
            (1..=max_mips).prop_map(move |mips| {
                let layout = LeafLayout {
                    width: w,
                    height: h,
                    faces,
                    mips,
                    channels: ch,
                };
                let grid = ParamGrid::two_d(n0, n1);
                let mut t = ParamTexture::zeroed(
                    TextureId {
                        object: 0,
                        layer: 0,
                    },
                    grid,
                    layout,
                    1.0,
                );
                // Smooth-ish content with an HDR spike and some negatives.
                let mut s = seed | 1;
                for (i, v) in t.data.iter_mut().enumerate() {
                    s ^= s << 13;
                    s ^= s >> 7;
                    s ^= s << 17;
                    let noise = (s % 1000) as f32 / 1000.0;
                    *v = (i as f32 * 0.01).sin() * 2.0
                        + noise * 0.1
                        + if s % 97 == 0 { 500.0 } else { 0.0 }
                        - if s % 89 == 0 { 0.05 } else { 0.0 };
                }
                t
            })
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, .. ProptestConfig::default() })]

    #[test]
    fn generous_budget_round_trips(t in texture()) {
        let input = EncodeInput { textures: vec![t] };
        // The raw size plus room for the container's tables: near-lossless.
        let budget = input.raw_bytes() + 40_000;
        let (bytes, _) = encode(&input, Target::Bytes(budget), &EncodeOptions::default()).unwrap();
        prop_assert!(bytes.len() as u64 <= budget);
        let c = Container::from_bytes(bytes).unwrap();
        let t = &input.textures[0];
        let mut acc = codec::PsnrAccum::default();
        let mut out = vec![0.0f32; t.layout.texels() * 4];
        let mut cache = codec::DecodeCache::default();
        for s1 in 0..t.grid.n1 {
            for s0 in 0..t.grid.n0 {
                cache.decode_leaf_all(&c, 0, 0, [s0, s1], &mut out).unwrap();
                acc.add(t.sample(t.grid.index([s0, s1]).unwrap()), t.layout.channels as usize, &out, 4);
            }
        }
        prop_assert!(acc.psnr_db() >= 45.0, "psnr {}", acc.psnr_db());
    }
}
