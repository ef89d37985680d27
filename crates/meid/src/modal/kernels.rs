//! Dense kernels whose results do not depend on the number of threads.
//!
//! faer's parallel kernels (`Par::Rayon(n)`, and the global default `Par::rayon(0)` = as many
//! tasks as the current rayon pool has threads) choose their blocking and split their reductions
//! by the thread count, so the last bits of a product, a Cholesky factor or an eigen-decomposition
//! change between 1 and 2 threads; through the Lanczos iteration those bits grow to 1e-9 in the
//! frequencies of the paper machine's suspended modes. Every faer call in `modal` and
//! `structure` therefore passes `Par::Seq`, and the parallelism that is kept is of one kind only:
//! the rows of a product are cut into chunks of a fixed [`ROW_CHUNK`] rows (a number that does
//! not depend on the thread count), each chunk is computed sequentially by one task, and
//! reductions over rows sum the chunks' partial results in chunk order:
//!
//! ```text
//! A B:    (A B)[chunk q] = A[chunk q] B                 (row q of the result from chunk q alone)
//! Aᵀ W:   Aᵀ W = ((P₀ + P₁) + P₂) + …,   P_q = A[chunk q]ᵀ W[chunk q]
//! ```
//!
//! so the floating-point operations and their order are fixed by the shapes alone.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::matmul::matmul;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Accum, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;

use crate::{Error, Result};

/// Rows per task of the row-chunked products (fixed: the results must not depend on the
/// number of threads).
pub(crate) const ROW_CHUNK: usize = 512;

/// `a b`, sequential.
pub(crate) fn mul(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut c = Mat::<f64>::zeros(a.nrows(), b.ncols());
    matmul(c.as_mut(), Accum::Replace, a, b, 1.0, Par::Seq);
    c
}

/// Splits `m` into consecutive row blocks of [`ROW_CHUNK`] rows (the last one shorter).
fn row_chunks_mut(mut m: MatMut<'_, f64>) -> Vec<(usize, MatMut<'_, f64>)> {
    let mut out = Vec::with_capacity(m.nrows().div_ceil(ROW_CHUNK));
    let mut start = 0;
    while m.nrows() > ROW_CHUNK {
        let (top, rest) = m.split_at_row_mut(ROW_CHUNK);
        out.push((start, top));
        start += ROW_CHUNK;
        m = rest;
    }
    if m.nrows() > 0 {
        out.push((start, m));
    }
    out
}

/// `c = beta·c + alpha · a b` computed by row chunks in parallel (`Accum::Replace` ignores the
/// old `c`). Each row of `c` comes from one sequential product of its chunk, so the result is
/// the same for any number of threads.
pub(crate) fn mul_rows_into(
    c: MatMut<'_, f64>,
    accum: Accum,
    a: MatRef<'_, f64>,
    b: MatRef<'_, f64>,
    alpha: f64,
) {
    assert!(c.nrows() == a.nrows() && c.ncols() == b.ncols() && a.ncols() == b.nrows());
    row_chunks_mut(c)
        .into_par_iter()
        .for_each(|(start, mut cq)| {
            let rows = cq.nrows();
            let aq = a.get(start..start + rows, ..);
            matmul(cq.rb_mut(), accum, aq, b, alpha, Par::Seq);
        });
}

/// `a[:, ..l] = a[:, ..k] b` in place (`b` is k × l, l ≤ k), by row chunks in parallel: each
/// chunk's product goes through a chunk-sized buffer, so no n × l matrix is allocated. The
/// same sequential product per chunk as [`mul_rows`], hence the same bits.
pub(crate) fn mul_rows_leading_in_place(a: MatMut<'_, f64>, k: usize, b: MatRef<'_, f64>) {
    let l = b.ncols();
    assert!(b.nrows() == k && l <= k && k <= a.ncols());
    row_chunks_mut(a).into_par_iter().for_each(|(_, aq)| {
        let mut t = Mat::<f64>::zeros(aq.nrows(), l);
        matmul(
            t.as_mut(),
            Accum::Replace,
            aq.rb().get(.., ..k),
            b,
            1.0,
            Par::Seq,
        );
        aq.get_mut(.., ..l).copy_from(&t);
    });
}

/// `a b` by row chunks (see [`mul_rows_into`]).
pub(crate) fn mul_rows(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut c = Mat::<f64>::zeros(a.nrows(), b.ncols());
    mul_rows_into(c.as_mut(), Accum::Replace, a, b, 1.0);
    c
}

/// `aᵀ w` (a reduction over the rows of `a` and `w`): the partial products of the row chunks,
/// computed in parallel, summed in chunk order.
pub(crate) fn mul_tn(a: MatRef<'_, f64>, w: MatRef<'_, f64>) -> Mat<f64> {
    assert!(a.nrows() == w.nrows());
    let n = a.nrows();
    let (p, q) = (a.ncols(), w.ncols());
    let chunks = n.div_ceil(ROW_CHUNK);
    if chunks <= 1 {
        return mul(a.transpose(), w);
    }
    let partial: Vec<Mat<f64>> = (0..chunks)
        .into_par_iter()
        .map(|k| {
            let rows = k * ROW_CHUNK..((k + 1) * ROW_CHUNK).min(n);
            mul(a.get(rows.clone(), ..).transpose(), w.get(rows, ..))
        })
        .collect();
    let mut c = Mat::<f64>::zeros(p, q);
    for part in &partial {
        c += part;
    }
    c
}

/// Lower Cholesky factor `L` of a symmetric positive definite `a` (lower triangle read),
/// sequential; `None` if `a` is not numerically positive definite.
pub(crate) fn llt_lower(a: MatRef<'_, f64>) -> Option<Mat<f64>> {
    use faer::linalg::cholesky::llt::factor;
    let n = a.nrows();
    let mut l = Mat::<f64>::zeros(n, n);
    l.copy_from_triangular_lower(a);
    let mut mem = MemBuffer::new(factor::cholesky_in_place_scratch::<f64>(
        n,
        Par::Seq,
        Default::default(),
    ));
    factor::cholesky_in_place(
        l.as_mut(),
        Default::default(),
        Par::Seq,
        MemStack::new(&mut mem),
        Default::default(),
    )
    .ok()?;
    for j in 0..n {
        for i in 0..j {
            l[(i, j)] = 0.0;
        }
    }
    Some(l)
}

/// Eigen-decomposition `a = U diag(s) Uᵀ` of a symmetric `a` (lower triangle read), eigenvalues
/// ascending, sequential. `what` names the computation in the error.
pub(crate) fn self_adjoint_eigen(a: MatRef<'_, f64>, what: &str) -> Result<(Vec<f64>, Mat<f64>)> {
    use faer::linalg::evd;
    let n = a.nrows();
    let mut u = Mat::<f64>::zeros(n, n);
    let mut s = faer::diag::Diag::<f64>::zeros(n);
    let mut mem = MemBuffer::new(evd::self_adjoint_evd_scratch::<f64>(
        n,
        evd::ComputeEigenvectors::Yes,
        Par::Seq,
        Default::default(),
    ));
    evd::self_adjoint_evd(
        a,
        s.as_mut(),
        Some(u.as_mut()),
        Par::Seq,
        MemStack::new(&mut mem),
        Default::default(),
    )
    .map_err(|e| Error::numerical(what, format!("symmetric eigen-decomposition failed: {e:?}")))?;
    Ok(((0..n).map(|i| s[i]).collect(), u))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pseudo(n: usize, m: usize, seed: u64) -> Mat<f64> {
        let mut rng = crate::rng::SplitMix64::new(seed);
        Mat::from_fn(n, m, |_, _| rng.next_sym())
    }

    /// The chunked products agree with the plain product to round-off and are bit-identical in
    /// rayon pools of 1, 2, 3 and 7 threads.
    #[test]
    fn chunked_products_are_thread_count_independent() {
        let n = 5 * ROW_CHUNK + 37;
        let a = pseudo(n, 23, 1);
        let b = pseudo(23, 9, 2);
        let w = pseudo(n, 9, 3);
        let run = || {
            (
                mul_rows(a.as_ref(), b.as_ref()),
                mul_tn(a.as_ref(), w.as_ref()),
            )
        };
        let (ab0, atw0) = run();
        let ab_ref = mul(a.as_ref(), b.as_ref());
        let atw_ref = mul(a.transpose(), w.as_ref());
        assert!((&ab0 - &ab_ref).norm_max() <= 1e-13 * ab_ref.norm_max());
        assert!((&atw0 - &atw_ref).norm_max() <= 1e-12 * atw_ref.norm_max());
        for t in [1, 2, 3, 7] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap();
            let (ab, atw) = pool.install(run);
            let bits = |m: &Mat<f64>| -> Vec<u64> {
                m.col_iter()
                    .flat_map(|c| c.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
                    .collect()
            };
            assert_eq!(bits(&ab), bits(&ab0), "A B, {t} threads");
            assert_eq!(bits(&atw), bits(&atw0), "Aᵀ W, {t} threads");
        }
    }

    /// The in-place leading product is the chunked product's bits, written over the leading
    /// columns, and leaves the other columns alone.
    #[test]
    fn leading_product_in_place_equals_the_chunked_product() {
        let n = 3 * ROW_CHUNK + 11;
        let a = pseudo(n, 14, 4);
        let b = pseudo(10, 7, 5);
        let expected = mul_rows(a.get(.., ..10), b.as_ref());
        let mut c = a.clone();
        mul_rows_leading_in_place(c.as_mut(), 10, b.as_ref());
        for j in 0..14 {
            for i in 0..n {
                let want = if j < 7 { expected[(i, j)] } else { a[(i, j)] };
                assert_eq!(c[(i, j)].to_bits(), want.to_bits(), "({i}, {j})");
            }
        }
    }

    /// The chain matrix `tridiag(-1, 2, -1)` of order n has eigenvalues
    /// `2 - 2 cos(kπ/(n+1))`, k = 1..n; its Cholesky factor reproduces it; `-I` has none.
    #[test]
    fn llt_and_eigen_match_closed_forms() {
        let n = 40;
        let a = Mat::<f64>::from_fn(n, n, |i, j| match i.abs_diff(j) {
            0 => 2.0,
            1 => -1.0,
            _ => 0.0,
        });
        let l = llt_lower(a.as_ref()).unwrap();
        let llt = mul(l.as_ref(), l.transpose());
        assert!((&llt - &a).norm_max() <= 1e-14);
        let (s, u) = self_adjoint_eigen(a.as_ref(), "test").unwrap();
        for (i, si) in s.iter().enumerate() {
            let k = (i + 1) as f64;
            let exact = 2.0 - 2.0 * (k * std::f64::consts::PI / (n as f64 + 1.0)).cos();
            assert!((si - exact).abs() < 1e-13, "{i}: {si} vs {exact}");
        }
        let utu = mul(u.transpose(), u.as_ref());
        assert!((utu - Mat::<f64>::identity(n, n)).norm_max() < 1e-13);
        assert!(llt_lower((-Mat::<f64>::identity(n, n)).as_ref()).is_none());
    }
}
