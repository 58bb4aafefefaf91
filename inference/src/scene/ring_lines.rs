//! How a viewpoint grid numbers its samples when the rings above the first
//! keep only some azimuth lines (`[orbit] ring_line_every`): the first
//! ring's lines, then each ring's own, ring after ring. With every line on
//! every ring this is the tensor grid's `k = line + lines · ring`.

/// `lines` azimuth lines on the first ring; the rings above it keep every
/// `every`-th (0 or 1: all) and the last.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RingLines {
    pub lines: u32,
    pub every: u32,
}

impl RingLines {
    /// The lines (indices, increasing) of the rings above the first.
    pub fn upper(&self) -> Vec<u32> {
        let mut v: Vec<u32> = (0..self.lines)
            .step_by(self.every.max(1) as usize)
            .collect();
        if self.lines > 0 && v.last() != Some(&(self.lines - 1)) {
            v.push(self.lines - 1);
        }
        v
    }

    /// The lines ring `ring` holds, increasing.
    pub fn on_ring(&self, ring: u32) -> Vec<u32> {
        match ring {
            0 => (0..self.lines).collect(),
            _ => self.upper(),
        }
    }

    /// Samples on `rings` rings.
    pub fn count(&self, rings: u32) -> u32 {
        self.lines + rings.max(1).saturating_sub(1) * self.upper().len() as u32
    }

    /// (line, ring) of sample `k`.
    pub fn coords(&self, k: u32) -> (u32, u32) {
        let (at, _, ring) = self.place(k);
        match ring {
            0 => (k, 0),
            _ => (self.upper().get(at as usize).copied().unwrap_or(0), ring),
        }
    }

    /// Sample `k`'s place among its ring's samples, and their count (a
    /// ring's samples are numbered consecutively).
    pub fn position(&self, k: u32) -> (u32, u32) {
        let (at, len, _) = self.place(k);
        (at, len)
    }

    /// The sample at line `line` of ring `ring` (on a ring that skips
    /// lines, its nearest line at or before `line`).
    pub fn index(&self, line: u32, ring: u32) -> u32 {
        if ring == 0 {
            return line;
        }
        let upper = self.upper();
        let at = upper.partition_point(|&l| l <= line).saturating_sub(1) as u32;
        self.lines + (ring - 1) * upper.len() as u32 + at
    }

    /// (place on its ring, the ring's sample count, ring) of sample `k`.
    fn place(&self, k: u32) -> (u32, u32, u32) {
        let n = self.lines.max(1);
        if k < n {
            return (k, n, 0);
        }
        let m = self.upper().len().max(1) as u32;
        ((k - n) % m, m, 1 + (k - n) / m)
    }
}

#[cfg(test)]
mod tests {
    use super::RingLines;

    #[test]
    fn every_line_is_the_tensor_grid_and_sparse_rings_number_their_own() {
        let tensor = RingLines { lines: 5, every: 1 };
        for k in 0..tensor.count(3) {
            let (line, ring) = tensor.coords(k);
            assert_eq!((line, ring), (k % 5, k / 5));
            assert_eq!(tensor.index(line, ring), k);
        }
        // 9 lines, every 4th and the last above the first ring: 0, 4, 8.
        let sparse = RingLines { lines: 9, every: 4 };
        assert_eq!(sparse.upper(), [0, 4, 8]);
        assert_eq!(sparse.count(3), 15);
        assert_eq!((sparse.coords(10), sparse.coords(14)), ((4, 1), (8, 2)));
        assert_eq!((sparse.position(3), sparse.position(13)), ((3, 9), (1, 3)));
        assert_eq!(sparse.index(7, 2), 13, "line 7 falls back to line 4");
        assert_eq!(RingLines { lines: 4, every: 4 }.upper(), [0, 3]);
    }
}
