//! Dense kernels for the small matrices of the impact engine (a few to ~100 rows), run
//! sequentially.
//!
//! The three eigen-kernels the exact propagator calls for every contact state it meets
//! ([`sym_eigen`], [`real_eigen`], [`inverse`]) are **hand-written** rather than faer calls:
//! faer 0.24 has no small-matrix fast path, and its general EVD spends ~190k instructions on
//! an 8×8 matrix (dispatch, workspace queries, blocking) for ~10k flops of arithmetic, while a
//! collision builds ~5 such decompositions within a 50 µs budget. The kernels here are the
//! textbook unblocked algorithms on flat column-major buffers:
//!
//! * [`sym_eigen`]: cyclic Jacobi with threshold (Rutishauser), see the `jacobi` submodule,
//!   for n ≤ [`JACOBI_MAX_N`] (faer's tridiagonal QR is faster above, measured);
//! * [`real_eigen`]: Householder Hessenberg + Francis double-shift QR + triangular
//!   back-substitution (EISPACK `hqr2` / LAPACK `dlahqr` + `dtrevc`), see the `hqr` submodule;
//! * [`inverse`]: Gauss-Jordan with partial pivoting, in place.
//!
//! When Jacobi or QR fails to converge within its iteration limit, the faer routines
//! ([`sym_eigen_faer`], [`real_eigen_faer`]) are used instead. They are also called with
//! `Par::Seq`: faer's convenience methods use the global (rayon) parallelism, whose task
//! overhead dominates at this size and would also nest inside parallel sweeps.

mod hqr;
mod jacobi;

use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self, ComputeEigenvectors};
use faer::{c64, Mat, Par};

use crate::{Error, Result};

fn check_square_finite(a: &Mat<f64>, what: &str) -> Result<()> {
    if a.nrows() != a.ncols() {
        return Err(Error::invalid(
            what,
            format!("matrix is {}x{}, not square", a.nrows(), a.ncols()),
        ));
    }
    for j in 0..a.ncols() {
        if let Some(i) = a.col_as_slice(j).iter().position(|x| !x.is_finite()) {
            return Err(Error::numerical(
                what,
                format!("non-finite entry at ({i}, {j})"),
            ));
        }
    }
    Ok(())
}

/// Largest order for which [`sym_eigen`] uses Jacobi. Measured (callgrind, instructions per
/// call, Jacobi vs faer): 4×4 11.5k vs 18.1k, 8×8 74k vs 50k, 12×12 220k vs 99k, 22×22 1.12M vs
/// 0.35M — Jacobi's ~6n³ flops per sweep lose to tridiagonal QR beyond n ≈ 6.
pub const JACOBI_MAX_N: usize = 6;

/// Symmetric eigen-decomposition `A = U diag(s) Uᵀ` of `(A + Aᵀ)/2`, eigenvalues ascending,
/// `U` orthonormal. Cyclic Jacobi (`jacobi` submodule) for `n ≤ JACOBI_MAX_N`, with faer's
/// tridiagonal QR as fallback if Jacobi does not converge in 60 sweeps; faer above that order.
pub fn sym_eigen(a: &Mat<f64>) -> Result<(Vec<f64>, Mat<f64>)> {
    check_square_finite(a, "symmetric eigen-decomposition")?;
    if a.nrows() > JACOBI_MAX_N {
        return sym_eigen_faer(a);
    }
    match jacobi::jacobi_eigen(a) {
        Some(r) => Ok(r),
        None => sym_eigen_faer(a),
    }
}

/// Symmetric eigen-decomposition by cyclic Jacobi at any order (no size dispatch); `None` if
/// it does not converge in 60 sweeps. For tests and benchmarks; [`sym_eigen`] is the API.
pub fn sym_eigen_jacobi(a: &Mat<f64>) -> Result<Option<(Vec<f64>, Mat<f64>)>> {
    check_square_finite(a, "symmetric eigen-decomposition")?;
    Ok(jacobi::jacobi_eigen(a))
}

/// Eigen-decomposition of a real matrix, `A V = V diag(λ)`, columns of `V` of unit 2-norm.
/// A complex conjugate pair occupies adjacent positions, the eigenvalue with positive imaginary
/// part first, and the pair's eigenvalues and vectors are exact conjugates. Hessenberg + Francis
/// QR + back-substitution (`hqr` submodule); faer's EVD if QR does not converge. A defective matrix
/// gives a `V` of huge condition (check `‖V‖‖V⁻¹‖`).
pub fn real_eigen(a: &Mat<f64>) -> Result<(Vec<c64>, Mat<c64>)> {
    check_square_finite(a, "eigen-decomposition")?;
    match hqr::hqr_eigen(a) {
        Some(r) => Ok(r),
        None => real_eigen_faer(a),
    }
}

/// Symmetric eigen-decomposition by faer (`self_adjoint_evd`, sequential): the fallback of
/// [`sym_eigen`], and the reference of the benchmark.
pub fn sym_eigen_faer(a: &Mat<f64>) -> Result<(Vec<f64>, Mat<f64>)> {
    let n = a.nrows();
    let mut u = Mat::<f64>::zeros(n, n);
    let mut s = Diag::<f64>::zeros(n);
    let req = evd::self_adjoint_evd_scratch::<f64>(
        n,
        ComputeEigenvectors::Yes,
        Par::Seq,
        Default::default(),
    );
    let mut buf = MemBuffer::new(req);
    evd::self_adjoint_evd(
        a.as_ref(),
        s.as_mut(),
        Some(u.as_mut()),
        Par::Seq,
        MemStack::new(&mut buf),
        Default::default(),
    )
    .map_err(|e| Error::numerical("symmetric eigen-decomposition", format!("{e:?}")))?;
    Ok(((0..n).map(|i| s[i]).collect(), u))
}

/// Eigen-decomposition of a real matrix by faer (`evd_real`, sequential), same conventions as
/// [`real_eigen`] (LAPACK order of the pairs): the fallback of [`real_eigen`], and the
/// reference of the benchmark.
pub fn real_eigen_faer(a: &Mat<f64>) -> Result<(Vec<c64>, Mat<c64>)> {
    let n = a.nrows();
    let mut ur = Mat::<f64>::zeros(n, n);
    let mut sre = Diag::<f64>::zeros(n);
    let mut sim = Diag::<f64>::zeros(n);
    let req = evd::evd_scratch::<f64>(
        n,
        ComputeEigenvectors::No,
        ComputeEigenvectors::Yes,
        Par::Seq,
        Default::default(),
    );
    let mut buf = MemBuffer::new(req);
    evd::evd_real(
        a.as_ref(),
        sre.as_mut(),
        sim.as_mut(),
        None,
        Some(ur.as_mut()),
        Par::Seq,
        MemStack::new(&mut buf),
        Default::default(),
    )
    .map_err(|e| Error::numerical("eigen-decomposition", format!("{e:?}")))?;
    // Real form (LAPACK convention): a pair λ = a ± ib at (j, j+1) has vectors U[:,j] ± i U[:,j+1].
    let mut lam = Vec::with_capacity(n);
    let mut v = Mat::<c64>::zeros(n, n);
    let mut j = 0;
    while j < n {
        if sim[j] != 0.0 && j + 1 < n {
            lam.push(c64::new(sre[j], sim[j]));
            lam.push(c64::new(sre[j + 1], sim[j + 1]));
            for i in 0..n {
                v[(i, j)] = c64::new(ur[(i, j)], ur[(i, j + 1)]);
                v[(i, j + 1)] = c64::new(ur[(i, j)], -ur[(i, j + 1)]);
            }
            j += 2;
        } else {
            lam.push(c64::new(sre[j], 0.0));
            for i in 0..n {
                v[(i, j)] = c64::new(ur[(i, j)], 0.0);
            }
            j += 1;
        }
    }
    Ok((lam, v))
}

/// Inverse by in-place Gauss-Jordan elimination with partial (row) pivoting (Golub & Van Loan
/// §3.4; pivot rows are swapped whole and the column permutation is undone at the end);
/// `None` if a pivot is exactly zero or the result is not finite. ~n³ complex multiply-adds.
pub fn inverse(a: &Mat<c64>) -> Option<Mat<c64>> {
    let n = a.nrows();
    if a.ncols() != n {
        return None;
    }
    let nn = n * n;
    // Real and imaginary parts in separate column-major arrays (vectorisable updates).
    let mut work = vec![0.0f64; 2 * nn + 2 * n];
    let (re, rest) = work.split_at_mut(nn);
    let (im, rest) = rest.split_at_mut(nn);
    let (cre, cim) = rest.split_at_mut(n);
    let mut piv = vec![0usize; n];
    for j in 0..n {
        for (i, e) in a.col_as_slice(j).iter().enumerate() {
            re[j * n + i] = e.re;
            im[j * n + i] = e.im;
        }
    }
    for k in 0..n {
        let ck = k * n;
        let mut p = k;
        let mut best = -1.0;
        for i in k..n {
            let v = re[ck + i].abs() + im[ck + i].abs();
            if v > best {
                best = v;
                p = i;
            }
        }
        if !(best > 0.0 && best.is_finite()) {
            return None;
        }
        piv[k] = p;
        if p != k {
            for j in 0..n {
                re.swap(p + j * n, k + j * n);
                im.swap(p + j * n, k + j * n);
            }
        }
        let d = hqr::cdiv(c64::new(1.0, 0.0), c64::new(re[ck + k], im[ck + k]));
        cre.copy_from_slice(&re[ck..ck + n]);
        cim.copy_from_slice(&im[ck..ck + n]);
        cre[k] = 0.0;
        cim[k] = 0.0;
        re[ck..ck + n].iter_mut().for_each(|e| *e = 0.0);
        im[ck..ck + n].iter_mut().for_each(|e| *e = 0.0);
        re[ck + k] = 1.0;
        for j in 0..n {
            let (r, i) = (re[k + j * n], im[k + j * n]);
            re[k + j * n] = r * d.re - i * d.im;
            im[k + j * n] = r * d.im + i * d.re;
        }
        for j in 0..n {
            let (mr, mi) = (re[k + j * n], im[k + j * n]);
            if mr == 0.0 && mi == 0.0 {
                continue;
            }
            let rj = &mut re[j * n..j * n + n];
            let ij = &mut im[j * n..j * n + n];
            let (cr, ci) = (&cre[..n], &cim[..n]);
            for i in 0..n {
                rj[i] -= cr[i] * mr - ci[i] * mi;
                ij[i] -= cr[i] * mi + ci[i] * mr;
            }
        }
    }
    for k in (0..n).rev() {
        let p = piv[k];
        if p != k {
            for i in 0..n {
                re.swap(i + k * n, i + p * n);
                im.swap(i + k * n, i + p * n);
            }
        }
    }
    if re.iter().chain(im.iter()).any(|e| !e.is_finite()) {
        return None;
    }
    let mut out = Mat::<c64>::zeros(n, n);
    for j in 0..n {
        for (i, o) in out.col_as_slice_mut(j).iter_mut().enumerate() {
            *o = c64::new(re[j * n + i], im[j * n + i]);
        }
    }
    Some(out)
}

/// `aᵀ b c` for real matrices (plain loops).
pub fn at_b_c(a: &Mat<f64>, b: &Mat<f64>, c: &Mat<f64>) -> Mat<f64> {
    let bc = mul(b, c);
    Mat::<f64>::from_fn(a.ncols(), bc.ncols(), |i, j| {
        (0..a.nrows()).map(|k| a[(k, i)] * bc[(k, j)]).sum()
    })
}

/// `a b` for real matrices (plain loops).
pub fn mul(a: &Mat<f64>, b: &Mat<f64>) -> Mat<f64> {
    Mat::<f64>::from_fn(a.nrows(), b.ncols(), |i, j| {
        (0..a.ncols()).map(|k| a[(i, k)] * b[(k, j)]).sum()
    })
}

/// Frobenius norm of a complex matrix.
pub fn norm_c(a: &Mat<c64>) -> f64 {
    let mut s = 0.0;
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            s += a[(i, j)].norm_sqr();
        }
    }
    s.sqrt()
}
