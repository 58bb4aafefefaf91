//! Like `container`, but checksums are recomputed after mutation so the
//! fuzzer reaches the structural checks and the entropy decoder.
#![no_main]

use codec::{Container, DecodeCache};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut bytes = data.to_vec();
    codec::container::reseal_checksums(&mut bytes);
    let Ok(c) = Container::from_bytes(bytes) else {
        return;
    };
    let mut cache = DecodeCache::default();
    for t in c.textures().to_vec() {
        let mut out = vec![half::f16::ZERO; t.layout.texels() * 4];
        for s0 in [0, 1, 2, t.grid.n0 / 2, t.grid.n0 - 1] {
            let _ = cache.decode_leaf_all(&c, t.id.object, t.id.layer, [s0, t.grid.n1 - 1], &mut out);
            // 0, 1, 2 is a steady walk: decoding ahead runs from there.
            let _ = cache.warm_ahead(&c, t.id.object, t.id.layer);
        }
        cache.end_frame();
    }
});
