//! Solver tests on small synthetic problems with known answers, by topic;
//! the shared problem builders are here.

mod accuracy;
mod bounds;
mod degenerate_input;
mod matrices;
mod range_term;
mod unseen;

use super::*;

/// splitmix64: reproducible matrices from a proptest-shrinkable seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn below(&mut self, n: usize) -> u32 {
        (self.next() % n as u64) as u32
    }
}

fn shape_from(pick: u8, size: u32) -> TextureShape {
    match pick % 3 {
        0 => TextureShape::Cube { size },
        1 => TextureShape::Tex2D {
            width: size,
            height: size * 2,
        },
        _ => TextureShape::Tex2D {
            width: size * 2 + 1,
            height: size,
        },
    }
}

/// Full-column-rank A: one dominant diagonal row per texel plus `extra`
/// random filter-like rows (8 taps), so AᵀA is well conditioned.
fn well_conditioned(n_t: usize, extra: usize, rng: &mut Rng) -> CsrMatrix {
    let mut b = CsrBuilder::new(n_t);
    for i in 0..n_t {
        let mut row = vec![(i as u32, 1.0 + rng.unit())];
        for _ in 0..3 {
            row.push((rng.below(n_t), 0.2 * (rng.unit() - 0.5)));
        }
        b.push_row(&row).unwrap();
    }
    for _ in 0..extra {
        let row: Vec<_> = (0..8).map(|_| (rng.below(n_t), rng.unit() / 4.0)).collect();
        b.push_row(&row).unwrap();
    }
    b.finish()
}

fn mul_f32(a: &CsrMatrix, x: &[f32]) -> Vec<f32> {
    let mut y = vec![0.0; a.rows];
    a.mul(x, &mut y);
    y
}

fn max_abs_diff(a: &[f32], b: &[f32]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (p - q).abs())
        .fold(0.0, f32::max)
}

fn opts(eps_f: f32, form: Option<Form>, tolerance: f32) -> SolveOptions {
    SolveOptions {
        eps_f,
        force_form: form,
        tolerance,
        ..SolveOptions::default()
    }
}

fn tex(w: u32, h: u32) -> TextureLayout {
    TextureLayout::full_chain(TextureShape::Tex2D {
        width: w,
        height: h,
    })
}
