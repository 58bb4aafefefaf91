//! Compressed sparse row matrix: f32 values, u32 columns, usize row pointers.
//!
//! Products accumulate in f64 and each output element is summed serially in a
//! fixed order, so results are bit-identical for any rayon thread count.

use rayon::prelude::*;

use super::SolveError;

/// Rows per rayon task; large enough that task overhead is noise.
const ROW_CHUNK: usize = 2048;
/// Below this many nonzeros a product is cheaper on one thread.
const PAR_MIN_NNZ: usize = 1 << 15;

/// Vector element types the products accept (f32 storage, f64 solver state).
pub trait Scalar: Copy + Send + Sync + Default + 'static {
    fn to_f64(self) -> f64;
    fn from_f64(v: f64) -> Self;
}

impl Scalar for f32 {
    fn to_f64(self) -> f64 {
        self as f64
    }
    fn from_f64(v: f64) -> Self {
        v as f32
    }
}

impl Scalar for f64 {
    fn to_f64(self) -> f64 {
        self
    }
    fn from_f64(v: f64) -> Self {
        v
    }
}

/// Row `r`'s entries are `col_idx[row_ptr[r]..row_ptr[r+1]]` / `values[..]`.
/// Fields are public for zero-copy construction; call
/// [`validate`](Self::validate) before trusting hand-built matrices.
#[derive(Clone, Debug, PartialEq)]
pub struct CsrMatrix {
    pub rows: usize,
    pub cols: usize,
    pub row_ptr: Vec<usize>,
    pub col_idx: Vec<u32>,
    pub values: Vec<f32>,
}

impl CsrMatrix {
    /// `rows × cols` with no nonzeros.
    pub fn zeros(rows: usize, cols: usize) -> Self {
        Self {
            rows,
            cols,
            row_ptr: vec![0; rows + 1],
            col_idx: Vec::new(),
            values: Vec::new(),
        }
    }

    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    /// Structure and finiteness check; `what` names the matrix in errors.
    pub fn validate(&self, what: &'static str) -> Result<(), SolveError> {
        let bad = |reason: String| Err(SolveError::MalformedMatrix { reason });
        if self.row_ptr.len() != self.rows + 1 {
            return bad(format!(
                "{what}: row_ptr has {} entries, expected rows + 1 = {}",
                self.row_ptr.len(),
                self.rows + 1
            ));
        }
        if self.col_idx.len() != self.values.len() {
            return bad(format!(
                "{what}: {} column indices but {} values",
                self.col_idx.len(),
                self.values.len()
            ));
        }
        if self.row_ptr[0] != 0 || self.row_ptr[self.rows] != self.values.len() {
            return bad(format!(
                "{what}: row_ptr must run from 0 to nnz = {}, runs {}..{}",
                self.values.len(),
                self.row_ptr[0],
                self.row_ptr[self.rows]
            ));
        }
        if self.cols > u32::MAX as usize + 1 {
            return bad(format!("{what}: {} columns exceed u32 indices", self.cols));
        }
        for r in 0..self.rows {
            let (s, e) = (self.row_ptr[r], self.row_ptr[r + 1]);
            if s > e {
                return bad(format!("{what}: row_ptr decreases at row {r}"));
            }
            for &c in &self.col_idx[s..e] {
                if c as usize >= self.cols {
                    return Err(SolveError::ColumnOutOfRange {
                        row: r,
                        col: c as u64,
                        cols: self.cols,
                    });
                }
            }
        }
        if let Some(index) = self.values.iter().position(|v| !v.is_finite()) {
            return Err(SolveError::NonFinite { what, index });
        }
        Ok(())
    }

    fn row_dot<T: Scalar>(&self, r: usize, x: &[T]) -> f64 {
        let (s, e) = (self.row_ptr[r], self.row_ptr[r + 1]);
        let mut acc = 0.0f64;
        for (&c, &v) in self.col_idx[s..e].iter().zip(&self.values[s..e]) {
            acc += v as f64 * x[c as usize].to_f64();
        }
        acc
    }

    /// `y = A x`. Panics if the lengths do not match the shape.
    pub fn mul<T: Scalar>(&self, x: &[T], y: &mut [T]) {
        assert_eq!(x.len(), self.cols, "mul: x length vs columns");
        assert_eq!(y.len(), self.rows, "mul: y length vs rows");
        if self.nnz() >= PAR_MIN_NNZ {
            y.par_chunks_mut(ROW_CHUNK).enumerate().for_each(|(c, ys)| {
                for (o, yi) in ys.iter_mut().enumerate() {
                    *yi = T::from_f64(self.row_dot(c * ROW_CHUNK + o, x));
                }
            });
        } else {
            for (r, yi) in y.iter_mut().enumerate() {
                *yi = T::from_f64(self.row_dot(r, x));
            }
        }
    }

    /// `x = Aᵀ y`, serial scatter (deterministic). For repeated products,
    /// [`transpose`](Self::transpose) once and `mul` in parallel: same bits.
    pub fn mul_transpose<T: Scalar>(&self, y: &[T], x: &mut [T]) {
        assert_eq!(y.len(), self.rows, "mul_transpose: y length vs rows");
        assert_eq!(x.len(), self.cols, "mul_transpose: x length vs columns");
        let mut acc = vec![0.0f64; self.cols];
        for (r, yr) in y.iter().enumerate() {
            let yr = yr.to_f64();
            for k in self.row_ptr[r]..self.row_ptr[r + 1] {
                acc[self.col_idx[k] as usize] += self.values[k] as f64 * yr;
            }
        }
        for (xi, a) in x.iter_mut().zip(acc) {
            *xi = T::from_f64(a);
        }
    }

    /// `x += s · Aᵀ y`, serial scatter: for short matrices (seam rows) where
    /// a transposed copy would be mostly empty rows.
    pub(crate) fn mul_transpose_acc(&self, y: &[f64], s: f64, x: &mut [f64]) {
        assert_eq!((y.len(), x.len()), (self.rows, self.cols), "Aᵀ y shape");
        for (r, &yr) in y.iter().enumerate() {
            for k in self.row_ptr[r]..self.row_ptr[r + 1] {
                x[self.col_idx[k] as usize] += s * self.values[k] as f64 * yr;
            }
        }
    }

    /// `Aᵀ` with each row's columns ascending (counting sort, O(nnz)).
    pub fn transpose(&self) -> CsrMatrix {
        let mut row_ptr = vec![0usize; self.cols + 1];
        for &c in &self.col_idx {
            row_ptr[c as usize + 1] += 1;
        }
        for i in 0..self.cols {
            row_ptr[i + 1] += row_ptr[i];
        }
        let mut next = row_ptr.clone();
        let mut col_idx = vec![0u32; self.nnz()];
        let mut values = vec![0.0f32; self.nnz()];
        for r in 0..self.rows {
            for k in self.row_ptr[r]..self.row_ptr[r + 1] {
                let c = self.col_idx[k] as usize;
                col_idx[next[c]] = r as u32;
                values[next[c]] = self.values[k];
                next[c] += 1;
            }
        }
        CsrMatrix {
            rows: self.cols,
            cols: self.rows,
            row_ptr,
            col_idx,
            values,
        }
    }

    /// `AᵀA` (cols × cols), sparse, columns ascending per row.
    pub fn normal_matrix(&self) -> CsrMatrix {
        self.gram_with_transpose(&self.transpose())
    }

    /// `AᵀA` given `t = Aᵀ`: Gustavson row-by-row product with a dense
    /// accumulator per task; each entry sums over A's rows in order.
    pub(crate) fn gram_with_transpose(&self, t: &CsrMatrix) -> CsrMatrix {
        let n = self.cols;
        let starts: Vec<usize> = (0..n).step_by(ROW_CHUNK).collect();
        let blocks: Vec<(Vec<usize>, Vec<u32>, Vec<f32>)> = starts
            .par_iter()
            // Few big tasks: each allocates two n-long accumulators.
            .with_min_len((starts.len() / (4 * rayon::current_num_threads())).max(1))
            .map_init(
                || (vec![0.0f64; n], vec![usize::MAX; n], Vec::<u32>::new()),
                |(acc, mark, touched), &start| {
                    let end = (start + ROW_CHUNK).min(n);
                    let mut lens = Vec::with_capacity(end - start);
                    let (mut cols, mut vals) = (Vec::new(), Vec::new());
                    for i in start..end {
                        touched.clear();
                        for k in t.row_ptr[i]..t.row_ptr[i + 1] {
                            let r = t.col_idx[k] as usize;
                            let a_ri = t.values[k] as f64;
                            for m in self.row_ptr[r]..self.row_ptr[r + 1] {
                                let j = self.col_idx[m] as usize;
                                if mark[j] != i {
                                    mark[j] = i;
                                    acc[j] = 0.0;
                                    touched.push(j as u32);
                                }
                                acc[j] += a_ri * self.values[m] as f64;
                            }
                        }
                        touched.sort_unstable();
                        for &j in touched.iter() {
                            cols.push(j);
                            vals.push(acc[j as usize] as f32);
                        }
                        lens.push(touched.len());
                    }
                    (lens, cols, vals)
                },
            )
            .collect();
        let mut out = CsrMatrix::zeros(0, n);
        out.rows = n;
        for (lens, cols, vals) in blocks {
            for l in lens {
                let last = out.row_ptr[out.row_ptr.len() - 1];
                out.row_ptr.push(last + l);
            }
            out.col_idx.extend(cols);
            out.values.extend(vals);
        }
        out
    }

    /// Squared column norms, i.e. the diagonal of `AᵀA` without forming it.
    pub(crate) fn column_sq_norms(&self) -> Vec<f64> {
        let mut d = vec![0.0f64; self.cols];
        for (&c, &v) in self.col_idx.iter().zip(&self.values) {
            d[c as usize] += v as f64 * v as f64;
        }
        d
    }

    /// Stacks matrices with the same column count (multi-view systems).
    pub fn vstack(parts: &[&CsrMatrix]) -> Result<CsrMatrix, SolveError> {
        let cols = parts.first().map_or(0, |p| p.cols);
        let mut out = CsrMatrix::zeros(0, cols);
        for p in parts {
            if p.cols != cols {
                return Err(SolveError::DimensionMismatch {
                    what: "vstack part columns",
                    expected: cols,
                    found: p.cols,
                });
            }
            p.validate("vstack part")?;
            let base = out.values.len();
            out.row_ptr.extend(p.row_ptr[1..].iter().map(|&o| base + o));
            out.col_idx.extend_from_slice(&p.col_idx);
            out.values.extend_from_slice(&p.values);
            out.rows += p.rows;
        }
        Ok(out)
    }
}

/// Row-at-a-time construction; rows are sorted and duplicate columns summed.
#[derive(Clone, Debug)]
pub struct CsrBuilder {
    m: CsrMatrix,
    scratch: Vec<(u32, f32)>,
}

impl CsrBuilder {
    pub fn new(cols: usize) -> Self {
        Self {
            m: CsrMatrix::zeros(0, cols),
            scratch: Vec::new(),
        }
    }

    /// Appends one row; fails (leaving the builder unchanged) on a column
    /// outside `0..cols`.
    pub fn push_row(&mut self, entries: &[(u32, f32)]) -> Result<(), SolveError> {
        if let Some(&(c, _)) = entries.iter().find(|(c, _)| *c as usize >= self.m.cols) {
            return Err(SolveError::ColumnOutOfRange {
                row: self.m.rows,
                col: c as u64,
                cols: self.m.cols,
            });
        }
        self.scratch.clear();
        self.scratch.extend_from_slice(entries);
        self.scratch.sort_by_key(|&(c, _)| c);
        let start = self.m.values.len();
        for &(c, v) in &self.scratch {
            if self.m.values.len() > start && self.m.col_idx.last() == Some(&c) {
                if let Some(last) = self.m.values.last_mut() {
                    *last += v;
                }
            } else {
                self.m.col_idx.push(c);
                self.m.values.push(v);
            }
        }
        self.m.rows += 1;
        self.m.row_ptr.push(self.m.values.len());
        Ok(())
    }

    pub fn rows(&self) -> usize {
        self.m.rows
    }

    pub fn finish(self) -> CsrMatrix {
        self.m
    }
}
