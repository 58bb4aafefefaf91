//! The adaptive Laplacian pyramid over one parameter block (thesis §4.3).
//!
//! A block holds `B0 × B1` leaves (8, or 8×8). Level 0 is one node, the
//! mean of all leaves; each finer level splits every node along parameter
//! dimension 0, 1 or both, and stores *detail* = node mean − parent mean.
//! A leaf is the sum of exactly one node per level (its ancestors), so
//! decoding needs `levels` image additions. Prediction is piecewise constant
//! (box) rather than Gaussian-interpolated so that one node per level
//! suffices, as the thesis's decoder does.
//!
//! Adaptive order: in 2D each level multiplies the node count by 4 as in a
//! standard pyramid, but the split may be 2×2, 4×1 or 1×4; the split whose
//! new detail level carries the most energy is taken first (the less
//! coherent dimension is subdivided first), greedily, level by level.
//! In 1D each level halves the cells.

/// Exponents `(e0, e1)` per level: level `l` has `2^e0 × 2^e1` nodes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Plan {
    pub levels: Vec<[u8; 2]>,
}

impl Plan {
    pub fn node_grid(&self, level: usize) -> [usize; 2] {
        let e = self.levels[level];
        [1 << e[0], 1 << e[1]]
    }
    pub fn node_count(&self, level: usize) -> usize {
        let g = self.node_grid(level);
        g[0] * g[1]
    }
    pub fn total_nodes(&self) -> usize {
        (0..self.levels.len()).map(|l| self.node_count(l)).sum()
    }
    /// Node index at `level` containing leaf `local` of a block of
    /// `2^log2b[0] × 2^log2b[1]` leaves.
    pub fn node_of(&self, level: usize, local: [usize; 2], log2b: [u8; 2]) -> usize {
        let e = self.levels[level];
        let j0 = local[0] >> (log2b[0] - e[0]);
        let j1 = local[1] >> (log2b[1] - e[1]);
        j0 + (1 << e[0]) * j1
    }
    /// Whether this is a valid plan for the block size: starts at one node,
    /// never coarsens, ends at the leaves. Used on untrusted files.
    pub fn is_valid(&self, log2b: [u8; 2]) -> bool {
        let Some(first) = self.levels.first() else {
            return false;
        };
        let Some(last) = self.levels.last() else {
            return false;
        };
        *first == [0, 0]
            && *last == log2b
            && self
                .levels
                .windows(2)
                .all(|w| w[1][0] >= w[0][0] && w[1][1] >= w[0][1] && w[1] != w[0])
            && self
                .levels
                .iter()
                .all(|e| e[0] <= log2b[0] && e[1] <= log2b[1])
    }
}

/// Candidate splits for the next level, given the exponents still missing.
fn candidates(remaining: [u8; 2], two_d: bool) -> Vec<[u8; 2]> {
    let total = remaining[0] + remaining[1];
    let want = if two_d { total.min(2) } else { total.min(1) };
    (0..=want)
        .map(|a| [a, want - a])
        .filter(|s| s[0] <= remaining[0] && s[1] <= remaining[1])
        .collect()
}

fn cell_means(proxies: &[Vec<f32>], e: [u8; 2], log2b: [u8; 2]) -> Vec<Vec<f32>> {
    let b0 = 1usize << log2b[0];
    let b1 = 1usize << log2b[1];
    let n = [1usize << e[0], 1usize << e[1]];
    let len = proxies.first().map_or(0, |p| p.len());
    let mut out = vec![vec![0.0f32; len]; n[0] * n[1]];
    let inv = 1.0 / ((b0 * b1) / (n[0] * n[1])) as f32;
    for i1 in 0..b1 {
        for i0 in 0..b0 {
            let j = (i0 >> (log2b[0] - e[0])) + n[0] * (i1 >> (log2b[1] - e[1]));
            for (o, v) in out[j].iter_mut().zip(&proxies[i0 + b0 * i1]) {
                *o += v * inv;
            }
        }
    }
    out
}

/// Greedy choice of the subdivision order from per-leaf proxy signals
/// (small images standing in for each leaf). Leaves are ordered `i0 + B0·i1`.
pub fn choose_plan(proxies: &[Vec<f32>], log2b: [u8; 2]) -> Plan {
    let two_d = log2b[0] > 0 && log2b[1] > 0;
    let mut levels = vec![[0u8, 0u8]];
    let mut cur = [0u8, 0u8];
    let mut cur_means = cell_means(proxies, cur, log2b);
    while cur != log2b {
        let remaining = [log2b[0] - cur[0], log2b[1] - cur[1]];
        let mut best: Option<(f64, [u8; 2], Vec<Vec<f32>>)> = None;
        for s in candidates(remaining, two_d) {
            let e = [cur[0] + s[0], cur[1] + s[1]];
            let means = cell_means(proxies, e, log2b);
            let n0 = 1usize << e[0];
            let p0 = 1usize << cur[0];
            let mut energy = 0.0f64;
            for (j, m) in means.iter().enumerate() {
                let parent = ((j % n0) >> s[0]) + p0 * ((j / n0) >> s[1]);
                energy += m
                    .iter()
                    .zip(&cur_means[parent])
                    .map(|(a, b)| ((a - b) as f64).powi(2))
                    .sum::<f64>();
            }
            if best.as_ref().is_none_or(|b| energy > b.0) {
                best = Some((energy, e, means));
            }
        }
        let Some((_, e, means)) = best else { break };
        levels.push(e);
        cur = e;
        cur_means = means;
    }
    Plan { levels }
}

/// Builds the pyramid: `[level][node]` signals, level 0 the block mean and
/// every other level the detail against its parent.
pub fn build(leaves: &[Vec<f32>], plan: &Plan, log2b: [u8; 2]) -> Vec<Vec<Vec<f32>>> {
    let means: Vec<Vec<Vec<f32>>> = plan
        .levels
        .iter()
        .map(|&e| cell_means(leaves, e, log2b))
        .collect();
    let mut out = Vec::with_capacity(means.len());
    for (l, level) in means.iter().enumerate() {
        if l == 0 {
            out.push(level.clone());
            continue;
        }
        let e = plan.levels[l];
        let pe = plan.levels[l - 1];
        let n0 = 1usize << e[0];
        let p0 = 1usize << pe[0];
        let details = level
            .iter()
            .enumerate()
            .map(|(j, m)| {
                let parent = ((j % n0) >> (e[0] - pe[0])) + p0 * ((j / n0) >> (e[1] - pe[1]));
                m.iter()
                    .zip(&means[l - 1][parent])
                    .map(|(a, b)| a - b)
                    .collect()
            })
            .collect();
        out.push(details);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn leaves_are_sums_of_their_ancestors() {
        let log2b = [3u8, 2u8];
        let leaves: Vec<Vec<f32>> = (0..32)
            .map(|i| {
                vec![
                    (i % 8) as f32 * 3.0 + (i / 8) as f32 * 0.1,
                    (i * i % 7) as f32,
                ]
            })
            .collect();
        let plan = choose_plan(&leaves, log2b);
        assert!(plan.is_valid(log2b), "{plan:?}");
        let pyr = build(&leaves, &plan, log2b);
        for i1 in 0..4 {
            for i0 in 0..8 {
                for k in 0..2 {
                    let s: f32 = (0..plan.levels.len())
                        .map(|l| pyr[l][plan.node_of(l, [i0, i1], log2b)][k])
                        .sum();
                    assert!((s - leaves[i0 + 8 * i1][k]).abs() < 1e-4);
                }
            }
        }
    }

    #[test]
    fn greedy_splits_the_less_coherent_dimension_first() {
        // Strong variation along dim 1, almost none along dim 0.
        let log2b = [3u8, 3u8];
        let leaves: Vec<Vec<f32>> = (0..64)
            .map(|i| vec![(i / 8) as f32 * 10.0 + (i % 8) as f32 * 0.01])
            .collect();
        let plan = choose_plan(&leaves, log2b);
        assert_eq!(plan.levels[1], [0, 2], "{plan:?}");
        assert_eq!(plan.levels.len(), 4);
        let one_d = choose_plan(&leaves[..8], [3, 0]);
        assert_eq!(one_d.levels, vec![[0, 0], [1, 0], [2, 0], [3, 0]]);
    }

    #[test]
    fn invalid_plans_are_rejected() {
        let p = |v: Vec<[u8; 2]>| Plan { levels: v };
        assert!(!p(vec![]).is_valid([3, 0]));
        assert!(!p(vec![[0, 0], [2, 0], [1, 0], [3, 0]]).is_valid([3, 0]));
        assert!(!p(vec![[0, 0], [4, 0]]).is_valid([3, 0]));
        assert!(!p(vec![[0, 0], [3, 0], [3, 0]]).is_valid([3, 0]));
        assert!(p(vec![[0, 0], [3, 0]]).is_valid([3, 0]));
    }
}
