//! The cached, sparse, SIMD decoder against a plain reference decoder
//! written from the format's definition: dense level images summed root
//! first (`0 + level 0 + level 1 + …`), MIP m > 0 plus the box-decimated
//! MIP 0 sum, then γ⁻¹ of YCoCg. Bit for bit, through cache hits and
//! misses, RGB and RGBA, 1D and 2D grids.

use codec::coefs::{Contexts, decode_image_add, step_of};
use codec::container::BlockView;
use codec::dct::Dct8;
use codec::domain::{Gamma, from_domain};
use codec::entropy::Reader;
use codec::planes::box_down;
use codec::synth::{SynthSpec, scene};
use codec::{Container, DecodeCache, EncodeOptions, Lifetimes, ParamGrid, Target, encode};

fn reference_leaf(c: &Container, ti: usize, sample: [u32; 2]) -> Vec<f32> {
    let t = &c.textures()[ti];
    let l = t.layout;
    let ch = l.channels as usize;
    let (block, local) = t.locate(sample).unwrap();
    let bytes = c.block_bytes(block).unwrap();
    let view = BlockView::parse(&bytes, t, block).unwrap();
    let dct = Dct8::default();
    let mut out = vec![0.0f32; l.texels() * 4];
    for face in 0..l.faces {
        // Dense sum of the levels, MIP by MIP.
        let len: usize = (0..l.mips).map(|m| l.face_texels(m) * ch).sum();
        let mut sum = vec![0.0f32; len];
        for level in 0..view.plan.levels.len() {
            let node = view.plan.node_of(level, local, t.log2b());
            let si = BlockView::stream_index(&view.plan, l.faces, level, node, face);
            let (steps, stream) = view.streams[si];
            if steps.iter().all(|&s| s == 0) {
                continue;
            }
            let mut r = Reader::new(stream).unwrap();
            let mut ctx = Contexts::default();
            let mut off = 0;
            for mip in 0..l.mips {
                let (w, h) = l.mip_size(mip);
                let n = w * h * ch;
                let idx = steps[mip as usize];
                if idx != 0 {
                    let mut level_img = vec![0.0f32; n];
                    decode_image_add(
                        &mut r,
                        &mut ctx,
                        &dct,
                        w,
                        h,
                        ch,
                        step_of(idx),
                        &mut level_img,
                    )
                    .unwrap();
                    for (s, v) in sum[off..off + n].iter_mut().zip(&level_img) {
                        *s += v;
                    }
                }
                off += n;
            }
        }
        // MIP prediction chain from the MIP 0 sum, then the colour transform.
        let (w0, h0) = l.mip_size(0);
        let mut pred: Vec<f32> = Vec::new();
        let mut off = 0;
        for mip in 0..l.mips {
            let (w, h) = l.mip_size(mip);
            let n = w * h;
            if mip > 0 {
                let (src, pw, ph) = if mip == 1 {
                    (sum[..w0 * h0 * ch].to_vec(), w0, h0)
                } else {
                    let (pw, ph) = l.mip_size(mip - 1);
                    (pred.clone(), pw, ph)
                };
                pred = vec![0.0; n * ch];
                box_down(&src, pw, ph, ch, &mut pred);
            }
            let o = l.texel_offset(face, mip) * 4;
            for i in 0..n {
                let v = |c: usize| {
                    let s = sum[off + c * n + i];
                    if mip > 0 { s + pred[c * n + i] } else { s }
                };
                let a = if ch > 3 { v(3) } else { 1.0 };
                let px = from_domain(Gamma(c.gamma), v(0), v(1), v(2), a);
                out[o + i * 4..o + i * 4 + 4].copy_from_slice(&px);
            }
            off += n * ch;
        }
    }
    out
}

fn check(input: &codec::EncodeInput, ratio: f64) {
    let (bytes, _) = encode(input, Target::Ratio(ratio), &EncodeOptions::default()).unwrap();
    let c = Container::from_bytes(bytes).unwrap();
    // Short lifetimes: hits, misses and evictions all happen.
    let mut cache = DecodeCache::new(Lifetimes { a: 1, b: 2 });
    for (ti, t) in c.textures().iter().enumerate() {
        let mut out = vec![0.0f32; t.layout.texels() * 4];
        for s1 in 0..t.grid.n1 {
            for s0 in (0..t.grid.n0).chain([1, 0]) {
                let s = [s0, s1];
                cache
                    .decode_leaf_all(&c, t.id.object, t.id.layer, s, &mut out)
                    .unwrap();
                cache.end_frame();
                let want = reference_leaf(&c, ti, s);
                let same = out
                    .iter()
                    .zip(&want)
                    .all(|(a, b)| a.to_bits() == b.to_bits());
                assert!(
                    same,
                    "texture {ti}, sample {s:?} differs from the reference"
                );
            }
        }
    }
    assert!(cache.stats().hits > 0 && cache.stats().evictions > 0);
}

#[test]
fn cached_decoder_matches_the_reference_bit_for_bit() {
    // RGB and RGBA cube maps along a 1D path (with stagger: two objects).
    let mut spec = SynthSpec::cube(2, 1, ParamGrid::one_d(11), 16);
    spec.channels = 3;
    let mut input = scene(&spec);
    spec.channels = 4;
    input
        .textures
        .extend(scene(&spec).textures.into_iter().map(|mut t| {
            t.id.layer = 1;
            t
        }));
    check(&input, 60.0);
    // A 2D grid of single-face maps with odd sizes.
    let mut spec = SynthSpec::cube(1, 1, ParamGrid::two_d(9, 3), 13);
    spec.faces = 1;
    check(&scene(&spec), 30.0);
}
