//! Dense kernels for the small matrices of the impact engine (a few to ~100 rows), run
//! sequentially: faer's convenience methods use the global (rayon) parallelism, whose task
//! overhead dominates at this size and would also nest inside parallel sweeps.

use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self, ComputeEigenvectors};
use faer::{c64, Mat, Par};

use crate::{Error, Result};

/// Symmetric eigen-decomposition `A = U diag(s) Uᵀ`, eigenvalues ascending.
pub fn sym_eigen(a: &Mat<f64>) -> Result<(Vec<f64>, Mat<f64>)> {
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

/// Eigen-decomposition of a real matrix, `A V = V diag(λ)`, complex eigenvectors.
pub fn real_eigen(a: &Mat<f64>) -> Result<(Vec<c64>, Mat<c64>)> {
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

/// Inverse by Gauss-Jordan elimination with partial pivoting; `None` if singular.
pub fn inverse(a: &Mat<c64>) -> Option<Mat<c64>> {
    let n = a.nrows();
    let mut m = a.clone();
    let mut inv = Mat::<c64>::identity(n, n);
    for col in 0..n {
        let p = (col..n).max_by(|&x, &y| m[(x, col)].norm().total_cmp(&m[(y, col)].norm()))?;
        if m[(p, col)].norm() == 0.0 {
            return None;
        }
        if p != col {
            for j in 0..n {
                let t = m[(p, j)];
                m[(p, j)] = m[(col, j)];
                m[(col, j)] = t;
                let t = inv[(p, j)];
                inv[(p, j)] = inv[(col, j)];
                inv[(col, j)] = t;
            }
        }
        let d = c64::new(1.0, 0.0) / m[(col, col)];
        for j in 0..n {
            m[(col, j)] *= d;
            inv[(col, j)] *= d;
        }
        for r in 0..n {
            if r != col {
                let f = m[(r, col)];
                if f.norm() != 0.0 {
                    for j in 0..n {
                        let mv = m[(col, j)];
                        let iv = inv[(col, j)];
                        m[(r, j)] -= f * mv;
                        inv[(r, j)] -= f * iv;
                    }
                }
            }
        }
    }
    Some(inv)
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
