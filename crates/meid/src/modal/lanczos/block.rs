//! Dense block kernels for the Lanczos driver: symmetric sparse × dense products, a
//! deterministic random generator, and M-orthonormalisation of a new block against the basis.

use crate::rng::SplitMix64;
use faer::linalg::matmul::matmul;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::SparseColMatRef;
use faer::{Accum, Col, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;

/// `y = A x` for a symmetric `A` stored with both triangles in compressed columns.
///
/// Because `A = Aᵀ`, row `j` of the product is column `j` of `A` dotted with `x`: a gather
/// that parallelises over rows without write conflicts. `x` is packed row-major so that the
/// inner loop runs over the block's columns contiguously.
pub(crate) fn sym_matmul(
    a: SparseColMatRef<'_, usize, f64>,
    x: MatRef<'_, f64>,
    y: MatMut<'_, f64>,
) {
    sym_matmul_with(a, x, y, &mut Vec::new());
}

/// Rows of `y` per task of [`sym_matmul_with`] (fixed: each row's sum is the same whatever the
/// thread count).
const GATHER_ROWS: usize = 256;

/// [`sym_matmul`] with a caller-owned buffer for the row-major copy of `x`, so that the
/// Lanczos iteration, which multiplies by M at every block step, does not map and fault in
/// fresh pages each time (at 10⁶ DOF a block is 48 MB, above glibc's largest mmap
/// threshold: every allocation of that size is a new mapping). Each row `j` of `y` is
/// `Σ_p a_pj x_{i_p}` summed from 0 in storage order, by one task.
pub(crate) fn sym_matmul_with(
    a: SparseColMatRef<'_, usize, f64>,
    x: MatRef<'_, f64>,
    y: MatMut<'_, f64>,
    xr: &mut Vec<f64>,
) {
    let n = x.nrows();
    let b = x.ncols();
    if b == 0 || n == 0 {
        return;
    }
    xr.clear();
    xr.resize(n * b, 0.0);
    for c in 0..b {
        let col = x.col(c);
        for (i, &v) in col.iter().enumerate() {
            xr[i * b + c] = v;
        }
    }
    let xr = &xr[..];
    let mut chunks = Vec::with_capacity(n.div_ceil(GATHER_ROWS));
    let mut rest = y;
    let mut start = 0;
    while rest.nrows() > 0 {
        let rows = GATHER_ROWS.min(rest.nrows());
        let (top, bottom) = rest.split_at_row_mut(rows);
        chunks.push((start, top));
        start += rows;
        rest = bottom;
    }
    chunks.into_par_iter().for_each(|(start, mut yq)| {
        let mut acc = vec![0.0; b];
        for r in 0..yq.nrows() {
            let j = start + r;
            acc.fill(0.0);
            for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
                let xrow = &xr[i * b..i * b + b];
                for (yc, &xc) in acc.iter_mut().zip(xrow) {
                    *yc += v * xc;
                }
            }
            for (c, &v) in acc.iter().enumerate() {
                yq[(r, c)] = v;
            }
        }
    });
}

/// Orthogonalises column `w` (with `mw = M w`) against `v[:, ..cols]` in the M-inner product
/// (classical Gram-Schmidt, one pass, using the stored `mv = M v`), accumulating the
/// coefficients into `coef[..cols]`.
pub(crate) fn project_column(
    v: MatRef<'_, f64>,
    mv: MatRef<'_, f64>,
    cols: usize,
    mut w: MatMut<'_, f64>,
    mut mw: MatMut<'_, f64>,
    coef: &mut [f64],
) {
    if cols == 0 {
        return;
    }
    let vb = v.get(.., ..cols);
    let mvb = mv.get(.., ..cols);
    let mut d = Mat::<f64>::zeros(cols, 1);
    matmul(
        d.as_mut(),
        Accum::Replace,
        mvb.transpose(),
        w.rb(),
        1.0,
        Par::Seq,
    );
    matmul(w.rb_mut(), Accum::Add, vb, d.as_ref(), -1.0, Par::Seq);
    matmul(mw.rb_mut(), Accum::Add, mvb, d.as_ref(), -1.0, Par::Seq);
    for (c, di) in coef.iter_mut().zip(d.col(0).iter()) {
        *c += *di;
    }
}

/// M-norm `sqrt(wᵀ M w)` of a column given `mw = M w` (0 if round-off made it negative).
pub(crate) fn m_norm(w: MatRef<'_, f64>, mw: MatRef<'_, f64>) -> f64 {
    let mut s = 0.0;
    for i in 0..w.nrows() {
        s += w[(i, 0)] * mw[(i, 0)];
    }
    s.max(0.0).sqrt()
}

/// Euclidean norm of a column.
pub(crate) fn norm2(x: faer::ColRef<'_, f64>) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// Fills a column with uniform random numbers.
pub(crate) fn fill_random(rng: &mut SplitMix64, n: usize) -> Col<f64> {
    Col::from_fn(n, |_| rng.next_sym())
}
