//! Which texels are probed together. Two probed texels must never reach the
//! same pixel: they are `spacing` apart in x and y (a bilinear footprint is
//! 2 texels wide, trilinear magnification/minification stays within that),
//! every third MIP level is probed at once (trilinear reads two adjacent
//! levels), and cube faces go in pairs of opposite faces, which share no
//! edge where seamless filtering could mix them. 6 × 6 × 3 = 108 sets for
//! a 2D texture (8 apart on a wrapping dimension 6 does not divide, so the
//! texels either side of the wrap stay apart), × 3 face pairs for a cube.

use crate::solve::layout::{TextureLayout, TextureShape};

pub const SPACING: u32 = 6;
pub const WRAP_SPACING: u32 = 8;
pub const LEVEL_STEP: u32 = 3;
const FACE_GROUPS: [[u32; 2]; 3] = [[0, 1], [2, 3], [4, 5]];

/// The texels of one probe render, in the order their local IDs count.
#[derive(Clone, Debug)]
pub struct ProbeSet {
    pub texels: Vec<usize>,
}

#[derive(Clone, Debug)]
pub struct ProbeSchedule {
    pub sets: Vec<ProbeSet>,
}

impl ProbeSchedule {
    pub fn new(layout: &TextureLayout, shape: TextureShape) -> Self {
        // 2D textures wrap (repeat sampler); cube faces clamp at their edge
        // and meet other faces, handled by the face pairs.
        let spacing = |size: u32| match shape {
            TextureShape::Tex2D { .. } if size % SPACING != 0 => WRAP_SPACING,
            _ => SPACING,
        };
        let (w0, h0) = layout.level_size(0);
        let (sx, sy) = (spacing(w0), spacing(h0));
        let groups: Vec<Vec<u32>> = if layout.faces() == 6 {
            FACE_GROUPS.iter().map(|g| g.to_vec()).collect()
        } else {
            vec![vec![0]]
        };
        let mut sets = Vec::new();
        for phase in 0..LEVEL_STEP.min(layout.levels()) {
            for faces in &groups {
                for dy in 0..sy {
                    for dx in 0..sx {
                        let mut texels = Vec::new();
                        for level in (phase..layout.levels()).step_by(LEVEL_STEP as usize) {
                            let (w, h) = layout.level_size(level);
                            for &face in faces {
                                for y in (dy..h).step_by(sy as usize) {
                                    for x in (dx..w).step_by(sx as usize) {
                                        texels.push(layout.index(face, level, x, y));
                                    }
                                }
                            }
                        }
                        if !texels.is_empty() {
                            sets.push(ProbeSet { texels });
                        }
                    }
                }
            }
        }
        Self { sets }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_texel_is_probed_exactly_once() {
        for shape in [
            TextureShape::Tex2D {
                width: 20,
                height: 12,
            },
            TextureShape::Cube { size: 16 },
        ] {
            let layout = TextureLayout::full_chain(shape);
            let schedule = ProbeSchedule::new(&layout, shape);
            let mut seen = vec![0u32; layout.len()];
            for set in &schedule.sets {
                for &t in &set.texels {
                    seen[t] += 1;
                }
            }
            assert!(seen.iter().all(|&n| n == 1), "{shape:?}");
        }
    }

    #[test]
    fn set_counts_match_the_thesis_schedule() {
        let tex = TextureShape::Tex2D {
            width: 96,
            height: 96,
        };
        let sets = ProbeSchedule::new(&TextureLayout::full_chain(tex), tex)
            .sets
            .len();
        assert_eq!(sets, 108, "6 x 6 x 3 for a 2D texture 6 divides");
        let cube = TextureShape::Cube { size: 96 };
        let sets = ProbeSchedule::new(&TextureLayout::full_chain(cube), cube)
            .sets
            .len();
        assert_eq!(sets, 324, "x 3 opposite-face pairs for a cube");
    }

    #[test]
    fn probed_texels_of_a_set_are_far_apart() {
        let shape = TextureShape::Cube { size: 32 };
        let layout = TextureLayout::full_chain(shape);
        for set in ProbeSchedule::new(&layout, shape).sets {
            for (i, &a) in set.texels.iter().enumerate() {
                for &b in &set.texels[i + 1..] {
                    let (fa, la, xa, ya) = layout.coords(a);
                    let (fb, lb, xb, yb) = layout.coords(b);
                    if fa == fb && la == lb {
                        assert!(xa.abs_diff(xb) >= SPACING || ya.abs_diff(yb) >= SPACING);
                    } else if fa == fb {
                        assert!(la.abs_diff(lb) >= LEVEL_STEP);
                    } else {
                        assert_eq!(fa / 2, fb / 2, "only opposite faces share a set");
                    }
                }
            }
        }
    }
}
