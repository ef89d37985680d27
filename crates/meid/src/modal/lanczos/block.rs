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
    mut y: MatMut<'_, f64>,
) {
    let n = x.nrows();
    let b = x.ncols();
    if b == 0 || n == 0 {
        return;
    }
    let mut xr = vec![0.0; n * b];
    for c in 0..b {
        let col = x.col(c);
        for i in 0..n {
            xr[i * b + c] = col[i];
        }
    }
    let mut yr = vec![0.0; n * b];
    yr.par_chunks_mut(b)
        .with_min_len(256)
        .enumerate()
        .for_each(|(j, yrow)| {
            for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
                let xrow = &xr[i * b..i * b + b];
                for (yc, &xc) in yrow.iter_mut().zip(xrow) {
                    *yc += v * xc;
                }
            }
        });
    for c in 0..b {
        let mut col = y.rb_mut().col_mut(c);
        for i in 0..n {
            col[i] = yr[i * b + c];
        }
    }
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
