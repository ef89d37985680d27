//! Cyclic Jacobi method with threshold for the dense symmetric eigenproblem `A = U diag(λ) Uᵀ`.
//!
//! Formulation: H. Rutishauser, "The Jacobi method for real symmetric matrices",
//! Numer. Math. 9 (1966) 1–10 (Handbook for Automatic Computation II/1): row-cyclic sweeps over
//! the strict upper triangle; a plane rotation `J(p, q, θ)` with
//! `cot 2θ = (a_qq − a_pp) / (2 a_pq)`, `t = tan θ = sign(cot 2θ) / (|cot 2θ| + √(1 + cot² 2θ))`
//! (the smaller angle), updates `a_pp −= t a_pq`, `a_qq += t a_pq`, `a_pq = 0` and rotates the
//! other entries of rows/columns p, q and the columns p, q of `U` in the stable form
//! `x' = x − s (y + τ x)`, `y' = y + s (x − τ y)`, `τ = s / (1 + c)`. During the first three sweeps
//! only entries above the threshold `0.2 Σ|a_ij| / n²` are annihilated; the diagonal updates
//! are accumulated separately per sweep (Rutishauser's `z` vector) to limit rounding growth.
//!
//! Stopping rule (J. Demmel, K. Veselić, "Jacobi's method is more accurate than QR",
//! SIAM J. Matrix Anal. Appl. 13 (1992) 1204–1245): `a_pq` is set to zero when
//! `|a_pq| ≤ ε √|a_pp a_qq|`, which gives eigenvalues to high *relative* accuracy for
//! scaled-diagonally-dominant (graded) positive definite matrices, and otherwise only when it is
//! below the underflow level relative to `max|a_ij|`, so that eigenvalues that are exactly zero
//! (rigid-body modes) come out at the round-off level of `‖A‖`. Jacobi converges quadratically
//! (also for repeated eigenvalues), so the latter costs at most a few extra cheap sweeps.

use faer::Mat;

/// Maximum number of sweeps before giving up (the caller then falls back to faer).
const MAX_SWEEPS: usize = 60;

/// Eigenvalues ascending and orthonormal eigenvectors (columns) of the symmetric part
/// `(A + Aᵀ)/2` of `a`; `None` if the sweeps do not converge.
pub(super) fn jacobi_eigen(a: &Mat<f64>) -> Option<(Vec<f64>, Mat<f64>)> {
    let n = a.nrows();
    // One workspace: strict upper triangle of A, column-major (entry (i, j), i < j, at i + j n),
    // the eigenvector accumulator U, and Rutishauser's d, b, z vectors.
    let mut work = vec![0.0f64; 2 * n * n + 3 * n];
    let (w, rest) = work.split_at_mut(n * n);
    let (u, rest) = rest.split_at_mut(n * n);
    let (d, rest) = rest.split_at_mut(n);
    let (b, z) = rest.split_at_mut(n);
    let mut amax = 0.0f64;
    for j in 0..n {
        let col = a.col_as_slice(j);
        for i in 0..j {
            let x = 0.5 * (col[i] + a.col_as_slice(i)[j]);
            w[i + j * n] = x;
            amax = amax.max(x.abs());
        }
        d[j] = col[j];
        amax = amax.max(d[j].abs());
        u[j + j * n] = 1.0;
    }
    let floor = amax * (f64::MIN_POSITIVE / f64::EPSILON);
    b.copy_from_slice(d);
    let mut converged = n <= 1;
    for sweep in 0..MAX_SWEEPS {
        if converged {
            break;
        }
        let mut off = 0.0;
        for j in 1..n {
            for i in 0..j {
                off += w[i + j * n].abs();
            }
        }
        if off == 0.0 {
            converged = true;
            break;
        }
        let thresh = if sweep < 3 {
            0.2 * off / (n * n) as f64
        } else {
            0.0
        };
        let mut rotated = false;
        for p in 0..n - 1 {
            for q in p + 1..n {
                let apq = w[p + q * n];
                if apq == 0.0 {
                    continue;
                }
                if apq.abs() <= f64::EPSILON * (d[p].abs() * d[q].abs()).sqrt()
                    || apq.abs() <= floor
                {
                    w[p + q * n] = 0.0;
                    continue;
                }
                if apq.abs() <= thresh {
                    rotated = true; // not converged yet: a later sweep must look again
                    continue;
                }
                rotated = true;
                let h = d[q] - d[p];
                let t = if h.abs() + 100.0 * apq.abs() == h.abs() {
                    apq / h
                } else {
                    let theta = 0.5 * h / apq;
                    let t = 1.0 / (theta.abs() + (1.0 + theta * theta).sqrt());
                    if theta < 0.0 {
                        -t
                    } else {
                        t
                    }
                };
                let c = 1.0 / (1.0 + t * t).sqrt();
                let s = t * c;
                let tau = s / (1.0 + c);
                let hh = t * apq;
                z[p] -= hh;
                z[q] += hh;
                d[p] -= hh;
                d[q] += hh;
                w[p + q * n] = 0.0;
                let rot = |x: f64, y: f64| (x - s * (y + x * tau), y + s * (x - y * tau));
                for j in 0..p {
                    let (x, y) = rot(w[j + p * n], w[j + q * n]);
                    w[j + p * n] = x;
                    w[j + q * n] = y;
                }
                for j in p + 1..q {
                    let (x, y) = rot(w[p + j * n], w[j + q * n]);
                    w[p + j * n] = x;
                    w[j + q * n] = y;
                }
                for j in q + 1..n {
                    let (x, y) = rot(w[p + j * n], w[q + j * n]);
                    w[p + j * n] = x;
                    w[q + j * n] = y;
                }
                // p < q: columns p and q of U are disjoint slices.
                let (lo, hi) = u.split_at_mut(q * n);
                let up = &mut lo[p * n..p * n + n];
                let uq = &mut hi[..n];
                for (x, y) in up.iter_mut().zip(uq.iter_mut()) {
                    let (nx, ny) = rot(*x, *y);
                    *x = nx;
                    *y = ny;
                }
            }
        }
        for i in 0..n {
            b[i] += z[i];
            d[i] = b[i];
            z[i] = 0.0;
        }
        if !rotated {
            converged = true;
        }
    }
    if !converged || d.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&x, &y| d[x].total_cmp(&d[y]));
    let vals = order.iter().map(|&k| d[k]).collect();
    let mut vecs = Mat::<f64>::zeros(n, n);
    for (j, &k) in order.iter().enumerate() {
        vecs.col_as_slice_mut(j)
            .copy_from_slice(&u[k * n..k * n + n]);
    }
    Some((vals, vecs))
}
