//! Synthetic parameterized environment maps for tests and benchmarks:
//! view-dependent cube maps, smooth plus fine detail, with an HDR highlight (range about
//! 1e-3..1e3) and a coverage alpha that move along the parameter, and MIP
//! levels that are not exact filtered versions of each other (like
//! inferred ones).

use crate::input::{EncodeInput, LeafLayout, ParamGrid, ParamTexture, TextureId};
use crate::planes::box_down;

#[derive(Clone, Copy, Debug)]
pub struct SynthSpec {
    pub objects: u32,
    pub layers: u32,
    pub grid: ParamGrid,
    pub size: u32,
    pub mips: u32,
    pub faces: u32,
    pub channels: u32,
}

impl SynthSpec {
    /// A small scene: `objects × layers` cube maps of `size²` with full MIPs.
    pub fn cube(objects: u32, layers: u32, grid: ParamGrid, size: u32) -> Self {
        Self {
            objects,
            layers,
            grid,
            size,
            mips: LeafLayout::max_mips(size, size),
            faces: 6,
            channels: 4,
        }
    }
}

/// Direction of texel `(u, v)` in [-1, 1]² on cube face `face` (+X,−X,+Y,−Y,+Z,−Z).
fn cube_dir(face: u32, u: f32, v: f32) -> [f32; 3] {
    let d = match face {
        0 => [1.0, -v, -u],
        1 => [-1.0, -v, u],
        2 => [u, 1.0, v],
        3 => [u, -1.0, -v],
        4 => [u, -v, 1.0],
        _ => [-u, -v, -1.0],
    };
    let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    [d[0] / n, d[1] / n, d[2] / n]
}

/// Linear RGBA radiance of direction `d` at parameter `(p0, p1)` in [0, 1]².
fn radiance(d: [f32; 3], p: [f32; 2], seed: f32) -> [f32; 4] {
    let a = 2.0 * std::f32::consts::PI * (p[0] * 0.25 + seed * 0.1);
    let el = 0.4 + 0.5 * p[1];
    let s = [a.cos() * el.cos(), el.sin(), a.sin() * el.cos()];
    let cs = d[0] * s[0] + d[1] * s[1] + d[2] * s[2];
    let sun = 1.0e3 * ((cs - 1.0) * 400.0).exp() + 4.0 * ((cs - 1.0) * 6.0).exp();
    let sky = 0.05 + 0.6 * (0.5 + 0.5 * d[1]).powi(2);
    let pattern = 0.5 + 0.5 * (5.0 * d[0] + 3.0 * seed).sin() * (4.0 * d[2] + 6.0 * p[0]).cos();
    let ground = if d[1] < 0.0 {
        1e-3 + 0.02 * pattern * (1.0 + d[1])
    } else {
        0.0
    };
    // Fine detail (about 20 cycles per face) that slides with the parameter,
    // like reflected scene texture.
    let detail = 1.0
        + 0.25
            * (60.0 * d[0] + 37.0 * d[1] + 3.0 * p[0]).sin()
            * (53.0 * d[2] - 29.0 * d[1] + 2.0 * p[1]).sin();
    let base = detail
        * if d[1] >= 0.0 {
            sky * (0.6 + 0.4 * pattern)
        } else {
            ground
        };
    let cov = 1.0 / (1.0 + (-(8.0 * (d[2] - 0.6 * (a * 0.5).sin()))).exp());
    [
        base * 0.8 + sun,
        base * 0.9 + sun * 0.95,
        base * 1.2 + sun * 0.8,
        cov,
    ]
}

/// One synthetic texture.
pub fn texture(id: TextureId, spec: &SynthSpec) -> ParamTexture {
    let layout = LeafLayout {
        width: spec.size,
        height: spec.size,
        faces: spec.faces,
        mips: spec.mips,
        channels: spec.channels,
    };
    let area = 1000.0 * (1.0 + id.object as f32) / (1.0 + id.layer as f32);
    let mut t = ParamTexture::zeroed(id, spec.grid, layout, area);
    let seed = id.object as f32 * 1.7 + id.layer as f32 * 0.9;
    let ch = spec.channels as usize;
    let g = spec.grid;
    for s1 in 0..g.n1 {
        for s0 in 0..g.n0 {
            let p = [
                s0 as f32 / g.n0.max(2) as f32,
                s1 as f32 / g.n1.max(2) as f32,
            ];
            let si = g.index([s0, s1]).unwrap_or(0);
            let sample = t.sample_mut(si);
            for face in 0..layout.faces {
                let (w, h) = layout.mip_size(0);
                let o = layout.texel_offset(face, 0) * ch;
                for y in 0..h {
                    for x in 0..w {
                        let u = 2.0 * (x as f32 + 0.5) / w as f32 - 1.0;
                        let v = 2.0 * (y as f32 + 0.5) / h as f32 - 1.0;
                        let px = radiance(cube_dir(face, u, v), p, seed);
                        sample[o + (y * w + x) * ch..][..ch].copy_from_slice(&px[..ch]);
                    }
                }
                // MIPs: box-filtered (planar scratch), then perturbed a little.
                let mut prev: Vec<f32> = to_planar(&sample[o..o + w * h * ch], ch);
                for mip in 1..layout.mips {
                    let (pw, ph) = layout.mip_size(mip - 1);
                    let (mw, mh) = layout.mip_size(mip);
                    let mut next = vec![0.0; mw * mh * ch];
                    box_down(&prev, pw, ph, ch, &mut next);
                    let mo = layout.texel_offset(face, mip) * ch;
                    for t in 0..mw * mh {
                        for c in 0..ch {
                            let wobble =
                                1.0 + 0.03 * ((t as f32 * 0.37 + mip as f32 + c as f32).sin());
                            let v = next[c * mw * mh + t] * if c < 3 { wobble } else { 1.0 };
                            sample[mo + t * ch + c] = v;
                        }
                    }
                    prev = next;
                }
            }
        }
    }
    t
}

fn to_planar(interleaved: &[f32], ch: usize) -> Vec<f32> {
    let n = interleaved.len() / ch;
    let mut out = vec![0.0; interleaved.len()];
    for (t, px) in interleaved.chunks_exact(ch).enumerate() {
        for c in 0..ch {
            out[c * n + t] = px[c];
        }
    }
    out
}

/// A whole synthetic scene: every (object, layer) pair.
pub fn scene(spec: &SynthSpec) -> EncodeInput {
    let mut textures = Vec::new();
    for object in 0..spec.objects {
        for layer in 0..spec.layers {
            textures.push(texture(TextureId { object, layer }, spec));
        }
    }
    EncodeInput { textures }
}
