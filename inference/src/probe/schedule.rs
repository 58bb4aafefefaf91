//! Which texels are probed together. Two probed texels must never reach the
//! same pixel. A trilinear lookup reads a 2 × 2 footprint on each of two
//! adjacent MIP levels (lavapipe's footprint is 2 texels for every ratio,
//! anisotropy being off), so the engine's schedule ([`ProbeSchedule::new`])
//! probes texels 2 apart in x and y on every second level: 2 × 2 × 2 = 8
//! sets for a 2D texture, × 3 pairs of opposite cube faces (which share no
//! edge where seamless filtering could mix them) = 24 for a cube, each set
//! split into parts of at most [`MAX_SET`] texels so that the float IDs
//! stay exact enough (48 sets for a 256² cube with all its MIP levels, 12
//! for a 256² 2D texture).
//!
//! The thesis spaced probed texels 6 apart on every third level (6 × 6 × 3
//! = 108 sets, [`ProbeSchedule::thesis`]) because its 8-bit IDs had to be
//! constant over each probed texel's filter neighbourhood; the float IDs of
//! [`super::build_matrix`] only need probed texels never to share a
//! footprint, and any pixel that two of them reach is reported as a
//! collision, never silently merged. Both schedules give the same matrix
//! (`engine/tests/probe.rs`), the compact one in 6.6× fewer renders at
//! 256²×6.
//!
//! A 2D texture wraps (repeat sampler), so each dimension's texels either
//! side of the wrap must stay apart too: 2 apart holds on every MIP level
//! of a power-of-two size; any other size falls back to the thesis's rule
//! (6 apart where 6 divides it, else 8).

use crate::solve::layout::{TextureLayout, TextureShape};

/// The engine's spacing and level step (see the module comment).
pub const SPACING: u32 = 2;
pub const LEVEL_STEP: u32 = 2;
/// The thesis's spacing, level step and spacing on a wrapping dimension 6
/// does not divide.
pub const THESIS_SPACING: u32 = 6;
pub const THESIS_LEVEL_STEP: u32 = 3;
pub const WRAP_SPACING: u32 = 8;
const FACE_GROUPS: [[u32; 2]; 3] = [[0, 1], [2, 3], [4, 5]];
/// Most texels in one set. A pixel reads its texel's ID k as the ratio of
/// two filtered channels, exact to about 3e-7·k (2.5e-7 measured on
/// lavapipe at 256²×6), and [`super::build_matrix`] accepts it within
/// 0.01 of an integer; 16,384 keeps that error under 0.005.
pub const MAX_SET: usize = 16_384;

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
    /// The engine's schedule: texels 2 apart, every second level (a 2D
    /// texture whose sizes are not powers of two: the thesis's).
    pub fn new(layout: &TextureLayout, shape: TextureShape) -> Self {
        let (w0, h0) = layout.level_size(0);
        match shape {
            TextureShape::Tex2D { .. } if !(w0.is_power_of_two() && h0.is_power_of_two()) => {
                Self::thesis(layout, shape)
            }
            _ => Self::spaced(layout, (SPACING, SPACING), LEVEL_STEP),
        }
    }

    /// The thesis's schedule: texels 6 apart (8 on a wrapping dimension 6
    /// does not divide), every third level.
    pub fn thesis(layout: &TextureLayout, shape: TextureShape) -> Self {
        let spacing = |size: u32| match shape {
            TextureShape::Tex2D { .. } if size % THESIS_SPACING != 0 => WRAP_SPACING,
            _ => THESIS_SPACING,
        };
        let (w0, h0) = layout.level_size(0);
        Self::spaced(layout, (spacing(w0), spacing(h0)), THESIS_LEVEL_STEP)
    }

    /// Probed texels `sx` × `sy` apart on every `level_step`-th level, cube
    /// faces in opposite pairs.
    fn spaced(layout: &TextureLayout, (sx, sy): (u32, u32), level_step: u32) -> Self {
        let groups: Vec<Vec<u32>> = if layout.faces() == 6 {
            FACE_GROUPS.iter().map(|g| g.to_vec()).collect()
        } else {
            vec![vec![0]]
        };
        let mut sets = Vec::new();
        for phase in 0..level_step.min(layout.levels()) {
            for faces in &groups {
                for dy in 0..sy {
                    for dx in 0..sx {
                        let mut texels = Vec::new();
                        for level in (phase..layout.levels()).step_by(level_step as usize) {
                            let (w, h) = layout.level_size(level);
                            for &face in faces {
                                for y in (dy..h).step_by(sy as usize) {
                                    for x in (dx..w).step_by(sx as usize) {
                                        texels.push(layout.index(face, level, x, y));
                                    }
                                }
                            }
                        }
                        // Any part of a set is a set: split so IDs stay small.
                        for part in texels.chunks(MAX_SET) {
                            sets.push(ProbeSet {
                                texels: part.to_vec(),
                            });
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

    const SHAPES: [TextureShape; 4] = [
        TextureShape::Tex2D {
            width: 20,
            height: 12,
        },
        TextureShape::Tex2D {
            width: 64,
            height: 32,
        },
        TextureShape::Cube { size: 16 },
        TextureShape::Cube { size: 24 },
    ];

    fn both(layout: &TextureLayout, shape: TextureShape) -> [ProbeSchedule; 2] {
        [
            ProbeSchedule::new(layout, shape),
            ProbeSchedule::thesis(layout, shape),
        ]
    }

    #[test]
    fn every_texel_is_probed_exactly_once() {
        for shape in SHAPES {
            let layout = TextureLayout::full_chain(shape);
            for schedule in both(&layout, shape) {
                let mut seen = vec![0u32; layout.len()];
                for set in &schedule.sets {
                    for &t in &set.texels {
                        seen[t] += 1;
                    }
                }
                assert!(seen.iter().all(|&n| n == 1), "{shape:?}");
            }
        }
    }

    #[test]
    fn no_set_is_larger_than_the_ids_allow() {
        for shape in [
            TextureShape::Cube { size: 512 },
            TextureShape::Tex2D {
                width: 1024,
                height: 1024,
            },
        ] {
            let layout = TextureLayout::full_chain(shape);
            let [compact, thesis] = both(&layout, shape);
            let largest = |s: &ProbeSchedule| s.sets.iter().map(|s| s.texels.len()).max();
            assert_eq!(largest(&compact), Some(MAX_SET), "{shape:?} splits");
            assert!(largest(&thesis) <= Some(MAX_SET), "{shape:?}");
        }
    }

    #[test]
    fn set_counts() {
        let count = |shape: TextureShape, thesis: bool| {
            let layout = TextureLayout::full_chain(shape);
            let schedule = if thesis {
                ProbeSchedule::thesis(&layout, shape)
            } else {
                ProbeSchedule::new(&layout, shape)
            };
            schedule.sets.len()
        };
        let pow2 = TextureShape::Tex2D {
            width: 256,
            height: 256,
        };
        let cube = TextureShape::Cube { size: 256 };
        // Level 0's sets (128² texels + levels 2, 4, …) split in two.
        assert_eq!(count(pow2, false), 4 * 2 + 4, "2 x 2 x 2 sets, 4 split");
        let small = TextureShape::Tex2D {
            width: 64,
            height: 64,
        };
        assert_eq!(count(small, false), 8, "2 x 2 x 2 for a 64² texture");
        // Level 0 of a face pair (2 x 128² texels + levels 2, 4, …) splits
        // into 3 parts, level 1's (2 x 64² + …) stays whole.
        assert_eq!(count(cube, false), 3 * 12 + 12, "x 3 opposite-face pairs");
        let cube64 = TextureShape::Cube { size: 64 };
        assert_eq!(count(cube64, false), 24, "no set of a 64² cube splits");
        let six = TextureShape::Tex2D {
            width: 96,
            height: 96,
        };
        assert_eq!(count(six, true), 108, "the thesis: 6 x 6 x 3");
        assert_eq!(
            count(six, false),
            108,
            "a size not a power of two wraps badly at 2"
        );
        assert_eq!(count(TextureShape::Cube { size: 96 }, true), 324);
    }

    /// Texels `a` and `b` of one set: on one face and level they are at
    /// least `SPACING` apart in x or y (across the wrap for a 2D texture),
    /// so no 2 × 2 footprint holds both; on one face, `LEVEL_STEP` levels
    /// apart; otherwise on opposite faces.
    fn assert_apart(layout: &TextureLayout, wraps: bool, a: usize, b: usize) {
        let (fa, la, xa, ya) = layout.coords(a);
        let (fb, lb, xb, yb) = layout.coords(b);
        let (w, h) = layout.level_size(la);
        let apart = |d: u32, n: u32| if wraps { d.min(n - d) } else { d };
        if fa == fb && la == lb {
            let (dx, dy) = (apart(xa.abs_diff(xb), w), apart(ya.abs_diff(yb), h));
            assert!(dx >= SPACING || dy >= SPACING, "{a} and {b}");
        } else if fa == fb {
            assert!(la.abs_diff(lb) >= LEVEL_STEP);
        } else {
            assert_eq!(fa / 2, fb / 2, "only opposite faces share a set");
        }
    }

    #[test]
    fn probed_texels_of_a_set_never_share_a_footprint() {
        for shape in SHAPES {
            let layout = TextureLayout::full_chain(shape);
            let wraps = matches!(shape, TextureShape::Tex2D { .. });
            for schedule in both(&layout, shape) {
                for set in schedule.sets {
                    for (i, &a) in set.texels.iter().enumerate() {
                        for &b in &set.texels[i + 1..] {
                            assert_apart(&layout, wraps, a, b);
                        }
                    }
                }
            }
        }
    }
}
