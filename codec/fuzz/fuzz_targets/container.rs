//! Container parser and decoder on arbitrary bytes: must never panic,
//! read out of bounds or allocate more than the file justifies.
#![no_main]

use codec::{Container, DecodeCache};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(c) = Container::from_bytes(data.to_vec()) else {
        return;
    };
    let mut cache = DecodeCache::default();
    let textures = c.textures().to_vec();
    for t in textures {
        // Decode a few samples per texture (first, last, middle), both formats.
        let n = t.layout.texels() * 4;
        let mut out = vec![0.0f32; n];
        let mut out16 = vec![half::f16::ZERO; n];
        for s0 in [0, 1, 2, t.grid.n0 / 2, t.grid.n0 - 1] {
            let s = [s0, t.grid.n1 - 1];
            let _ = cache.decode_leaf_all(&c, t.id.object, t.id.layer, s, &mut out);
            let _ = cache.decode_leaf_all(&c, t.id.object, t.id.layer, s, &mut out16);
            let _ = cache.decode_leaf(&c, t.id.object, t.id.layer, s, 0, t.layout.mips - 1, &mut out[..4]);
            // 0, 1, 2 is a steady walk: decoding ahead runs from there.
            let _ = cache.warm_ahead(&c, t.id.object, t.id.layer);
        }
        cache.end_frame();
    }
});
