//! Dense real nonsymmetric eigenproblem `A V = V diag(λ)` for small matrices.
//!
//! The classical three-stage algorithm (Golub & Van Loan, *Matrix Computations*, 4th ed.,
//! §7.4–7.6; the EISPACK `orthes`/`hqr2` and LAPACK `dgehd2`/`dlahqr`/`dtrevc` routines):
//!
//! 1. **Hessenberg reduction** `H = Q₀ᵀ A Q₀` by Householder reflectors `P = I − v vᵀ / h`,
//!    `h = vᵀv / 2` (GVL Alg. 7.4.2), accumulating `Q₀`.
//! 2. **Francis implicit double-shift QR** on the active unreduced block `H[l..=i, l..=i]`
//!    (GVL Alg. 7.5.1, 7.5.2): the first column of `(H − σ₁)(H − σ₂)`, `σ₁,₂` the eigenvalues of the
//!    trailing 2×2 block, is `v = h₂₁ [ (x−z)(y−z) − w + h₁₂ h₂₁ ; h₂₁(h₂₂ − z − (x−z) − (y−z)) ;
//!    h₂₁ h₃₂ ]` with `x = h_ii`, `y = h_{i−1,i−1}`, `w = h_{i,i−1} h_{i−1,i}`, `z = h_mm`; the
//!    bulge is chased with 3×3 reflectors, started at the lowest `m` where two consecutive small
//!    subdiagonal entries allow it (Wilkinson). Deflation uses the Ahues–Tisseur criterion of
//!    `dlahqr` (LAPACK Working Note 122). Exceptional shifts `x = y = h + 0.75 s`,
//!    `w = −0.4375 s²` after 10 and 20 iterations without deflation (`dlahqr`); when both shifts are
//!    real, the one closer to `h_ii` is used twice (`dlahqr`). A 2×2 block with real eigenvalues is
//!    split by a plane rotation whose first column is its eigenvector `(z, h_{i,i−1})`,
//!    `z = p ± √(p² + w)`, `p = (h_{i−1,i−1} − h_ii)/2` (`hqr2`); a complex pair stays a 2×2 block
//!    with eigenvalues `h_ii + p ± i√(−p² − w)`. All transformations are accumulated: `A = Z T Zᵀ`.
//! 3. **Eigenvectors of the quasi-triangular `T`** by back-substitution (`dtrevc`): for an
//!    eigenvalue at the trailing position `k` of its block, solve `(T₁₁ − λ I) x₁ = −T₁₂ x₂` upward
//!    with 1×1 and 2×2 (complete pivoting) diagonal solves; a pivot smaller than
//!    `smin = max(ε |λ|, 10⁻¹⁵⁰)` is replaced by `smin`, so that repeated eigenvalues with
//!    independent eigenvectors still give independent vectors, and a defective eigenvalue gives
//!    a numerically dependent pair (huge condition of `V`, detected by the caller). Components
//!    are rescaled to stay below 10²⁰ (overflow guard). Then `v = Z x`, normalised to unit
//!    2-norm.
//!
//! The input is scaled by `1 / max|a_ij|` first (eigenvectors unchanged, eigenvalues scaled back),
//! which keeps every intermediate far from overflow and underflow. No balancing (`dgebal`): the
//! impact engine's matrices are balanced by construction.

use faer::{c64, Mat};

const ULP: f64 = f64::EPSILON;
/// Smallest pivot in the eigenvector back-substitution (matrix normalised to `max|a_ij| = 1`).
const SMIN_FLOOR: f64 = 1e-150;
/// Eigenvector components are rescaled when one exceeds this.
const BIG: f64 = 1e20;

/// Column-major index.
#[inline(always)]
fn ix(i: usize, j: usize, n: usize) -> usize {
    i + j * n
}

#[inline(always)]
fn abs1(z: c64) -> f64 {
    z.re.abs() + z.im.abs()
}

/// `a / b` by Smith's algorithm (no overflow or underflow of `|b|²`).
#[inline]
pub(super) fn cdiv(a: c64, b: c64) -> c64 {
    if b.re.abs() >= b.im.abs() {
        let r = b.im / b.re;
        let den = b.re + b.im * r;
        c64::new((a.re + a.im * r) / den, (a.im - a.re * r) / den)
    } else {
        let r = b.re / b.im;
        let den = b.re * r + b.im;
        c64::new((a.re * r + a.im) / den, (a.im * r - a.re) / den)
    }
}

/// Eigenvalues and unit-norm eigenvectors; conjugate pairs adjacent, positive imaginary part
/// first, exact conjugates. `None` if the QR iteration does not converge.
pub(super) fn hqr_eigen(a: &Mat<f64>) -> Option<(Vec<c64>, Mat<c64>)> {
    let n = a.nrows();
    let mut amax = 0.0f64;
    for j in 0..n {
        for i in 0..n {
            amax = amax.max(a[(i, j)].abs());
        }
    }
    if !amax.is_finite() {
        return None;
    }
    if amax == 0.0 {
        return Some((
            vec![c64::new(0.0, 0.0); n],
            Mat::<c64>::from_fn(n, n, |i, j| c64::new(if i == j { 1.0 } else { 0.0 }, 0.0)),
        ));
    }
    let inv = 1.0 / amax;
    let mut h: Vec<f64> = (0..n * n).map(|k| a[(k % n, k / n)] * inv).collect();
    let mut z = vec![0.0f64; n * n];
    for i in 0..n {
        z[ix(i, i, n)] = 1.0;
    }
    hessenberg(&mut h, &mut z, n);
    let mut wr = vec![0.0f64; n];
    let mut wi = vec![0.0f64; n];
    if !francis(&mut h, &mut z, n, &mut wr, &mut wi) {
        return None;
    }
    let v = eigenvectors(&h, &z, n, &wr, &wi)?;
    let lam = (0..n)
        .map(|k| c64::new(wr[k] * amax, wi[k] * amax))
        .collect();
    Some((lam, Mat::<c64>::from_fn(n, n, |i, j| v[ix(i, j, n)])))
}

/// Householder reduction to upper Hessenberg form, `H ← Pᵀ H P`, `Z ← Z P`.
fn hessenberg(h: &mut [f64], z: &mut [f64], n: usize) {
    let mut v = vec![0.0f64; n];
    let mut f = vec![0.0f64; n];
    for k in 0..n.saturating_sub(2) {
        let scale: f64 = (k + 1..n).map(|i| h[ix(i, k, n)].abs()).sum();
        if scale == 0.0 {
            continue;
        }
        let mut sigma2 = 0.0;
        for i in k + 1..n {
            v[i] = h[ix(i, k, n)] / scale;
            sigma2 += v[i] * v[i];
        }
        let x1 = v[k + 1];
        let sigma = sigma2.sqrt();
        let g = if x1 >= 0.0 { -sigma } else { sigma };
        let hh = sigma2 - x1 * g;
        v[k + 1] = x1 - g;
        // Left: columns k+1.. (column k becomes g·scale e_{k+1}).
        for j in k + 1..n {
            let col = &mut h[j * n..j * n + n];
            let s: f64 = (k + 1..n).map(|i| v[i] * col[i]).sum();
            let fj = s / hh;
            for i in k + 1..n {
                col[i] -= fj * v[i];
            }
        }
        h[ix(k + 1, k, n)] = g * scale;
        for i in k + 2..n {
            h[ix(i, k, n)] = 0.0;
        }
        // Right: H ← H P and Z ← Z P on columns k+1.., all rows.
        for m in [&mut *h, &mut *z] {
            f.iter_mut().for_each(|x| *x = 0.0);
            for j in k + 1..n {
                let vj = v[j];
                for (fi, mij) in f.iter_mut().zip(&m[j * n..j * n + n]) {
                    *fi += mij * vj;
                }
            }
            for j in k + 1..n {
                let c = v[j] / hh;
                for (mij, fi) in m[j * n..j * n + n].iter_mut().zip(&f) {
                    *mij -= fi * c;
                }
            }
        }
    }
}

/// Francis double-shift QR to real Schur form, accumulating into `z`; eigenvalues in
/// `wr + i wi`. Returns false when an eigenvalue needs more than `30 max(n, 10)` iterations.
fn francis(h: &mut [f64], z: &mut [f64], n: usize, wr: &mut [f64], wi: &mut [f64]) -> bool {
    let smlnum = f64::MIN_POSITIVE * (n as f64 / ULP);
    let itmax = 30 * n.max(10);
    let mut hi = n; // rows < hi are not yet deflated
    while hi > 0 {
        let i = hi - 1;
        let mut its = 0usize;
        let l = loop {
            // Look for a negligible subdiagonal entry (Ahues–Tisseur, dlahqr).
            let mut k = i;
            while k > 0 {
                let hkk1 = h[ix(k, k - 1, n)].abs();
                if hkk1 <= smlnum {
                    break;
                }
                let mut tst = h[ix(k - 1, k - 1, n)].abs() + h[ix(k, k, n)].abs();
                if tst == 0.0 {
                    if k >= 2 {
                        tst += h[ix(k - 1, k - 2, n)].abs();
                    }
                    if k < i {
                        tst += h[ix(k + 1, k, n)].abs();
                    }
                }
                if hkk1 <= ULP * tst {
                    let hk1k = h[ix(k - 1, k, n)].abs();
                    let ab = hkk1.max(hk1k);
                    let ba = hkk1.min(hk1k);
                    let hkk = h[ix(k, k, n)].abs();
                    let dif = (h[ix(k - 1, k - 1, n)] - h[ix(k, k, n)]).abs();
                    let aa = hkk.max(dif);
                    let bb = hkk.min(dif);
                    let s = aa + ab;
                    if ba * (ab / s) <= smlnum.max(ULP * (bb * (aa / s))) {
                        break;
                    }
                }
                k -= 1;
            }
            if k > 0 {
                h[ix(k, k - 1, n)] = 0.0;
            }
            if k + 1 >= i {
                break k;
            }
            its += 1;
            if its > itmax {
                return false;
            }
            let l = k;
            // Shifts: the eigenvalues of [[y, ·], [·, x]] with off-diagonal product w.
            let (mut x, mut y, mut w);
            if its % 20 == 0 {
                let s = h[ix(i, i - 1, n)].abs() + h[ix(i - 1, i - 2, n)].abs();
                x = 0.75 * s + h[ix(i, i, n)];
                y = x;
                w = -0.4375 * s * s;
            } else if its % 10 == 0 {
                let s = h[ix(l + 1, l, n)].abs() + h[ix(l + 2, l + 1, n)].abs();
                x = 0.75 * s + h[ix(l, l, n)];
                y = x;
                w = -0.4375 * s * s;
            } else {
                x = h[ix(i, i, n)];
                y = h[ix(i - 1, i - 1, n)];
                w = h[ix(i, i - 1, n)] * h[ix(i - 1, i, n)];
                let p = 0.5 * (y - x);
                let q = p * p + w;
                if q >= 0.0 {
                    // Real shifts: use the one closer to h_ii twice.
                    let sq = q.sqrt();
                    let r1 = x + p + sq;
                    let r2 = x + p - sq;
                    let r = if (r1 - x).abs() <= (r2 - x).abs() {
                        r1
                    } else {
                        r2
                    };
                    x = r;
                    y = r;
                    w = 0.0;
                }
            }
            // Start of the bulge: two consecutive small subdiagonal entries.
            let mut m = i - 2;
            let mut v = [0.0f64; 3];
            loop {
                let zz = h[ix(m, m, n)];
                let r = x - zz;
                let s = y - zz;
                let h21 = h[ix(m + 1, m, n)];
                v[0] = r * s - w + h[ix(m, m + 1, n)] * h21;
                v[1] = h21 * (h[ix(m + 1, m + 1, n)] - zz - r - s);
                v[2] = h21 * h[ix(m + 2, m + 1, n)];
                let sc = v[0].abs() + v[1].abs() + v[2].abs();
                if sc > 0.0 {
                    v.iter_mut().for_each(|t| *t /= sc);
                }
                if m == l {
                    break;
                }
                let lhs = h[ix(m, m - 1, n)].abs() * (v[1].abs() + v[2].abs());
                let rhs = ULP
                    * v[0].abs()
                    * (h[ix(m - 1, m - 1, n)].abs() + zz.abs() + h[ix(m + 1, m + 1, n)].abs());
                if lhs <= rhs {
                    break;
                }
                m -= 1;
            }
            // Double-shift QR sweep (bulge chase).
            for k in m..i {
                let nr = 3.min(i - k + 1);
                if k > m {
                    for (t, vt) in v.iter_mut().enumerate().take(nr) {
                        *vt = h[ix(k + t, k - 1, n)];
                    }
                }
                // Reflector I − τ u uᵀ, u = (1, v1, v2), mapping v to (β, 0, 0) (dlarfg).
                let alpha = v[0];
                let xnorm = if nr == 3 {
                    v[1].hypot(v[2])
                } else {
                    v[1].abs()
                };
                if xnorm == 0.0 {
                    continue;
                }
                let beta = -alpha.hypot(xnorm).copysign(if alpha >= 0.0 { 1.0 } else { -1.0 });
                let tau = (beta - alpha) / beta;
                let sc = 1.0 / (alpha - beta);
                let v1 = v[1] * sc;
                let v2 = if nr == 3 { v[2] * sc } else { 0.0 };
                if k > m {
                    h[ix(k, k - 1, n)] = beta;
                    h[ix(k + 1, k - 1, n)] = 0.0;
                    if nr == 3 {
                        h[ix(k + 2, k - 1, n)] = 0.0;
                    }
                } else if m > l {
                    h[ix(k, k - 1, n)] *= 1.0 - tau;
                }
                let t1 = tau * v1;
                let t2 = tau * v2;
                if nr == 3 {
                    for j in k..n {
                        let c = j * n;
                        let s = h[c + k] + v1 * h[c + k + 1] + v2 * h[c + k + 2];
                        h[c + k] -= s * tau;
                        h[c + k + 1] -= s * t1;
                        h[c + k + 2] -= s * t2;
                    }
                    let rmax = (k + 3).min(i);
                    apply_right3(h, n, k, rmax + 1, tau, t1, t2, v1, v2);
                    apply_right3(z, n, k, n, tau, t1, t2, v1, v2);
                } else {
                    for j in k..n {
                        let c = j * n;
                        let s = h[c + k] + v1 * h[c + k + 1];
                        h[c + k] -= s * tau;
                        h[c + k + 1] -= s * t1;
                    }
                    apply_right2(h, n, k, i + 1, tau, t1, v1);
                    apply_right2(z, n, k, n, tau, t1, v1);
                }
            }
        };
        if l == i {
            wr[i] = h[ix(i, i, n)];
            wi[i] = 0.0;
            hi -= 1;
        } else {
            deflate2(h, z, n, i, wr, wi);
            hi -= 2;
        }
    }
    true
}

/// `M[0..rows, k..k+3] ← M (I − τ u uᵀ)`, `u = (1, v1, v2)`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn apply_right3(
    m: &mut [f64],
    n: usize,
    k: usize,
    rows: usize,
    tau: f64,
    t1: f64,
    t2: f64,
    v1: f64,
    v2: f64,
) {
    let (a, rest) = m[k * n..].split_at_mut(n);
    let (b, c) = rest.split_at_mut(n);
    for ((x, y), w) in a[..rows]
        .iter_mut()
        .zip(b[..rows].iter_mut())
        .zip(c[..rows].iter_mut())
    {
        let s = *x + v1 * *y + v2 * *w;
        *x -= s * tau;
        *y -= s * t1;
        *w -= s * t2;
    }
}

/// `M[0..rows, k..k+2] ← M (I − τ u uᵀ)`, `u = (1, v1)`.
#[inline(always)]
fn apply_right2(m: &mut [f64], n: usize, k: usize, rows: usize, tau: f64, t1: f64, v1: f64) {
    let (a, rest) = m[k * n..].split_at_mut(n);
    let b = &mut rest[..n];
    for (x, y) in a[..rows].iter_mut().zip(b[..rows].iter_mut()) {
        let s = *x + v1 * *y;
        *x -= s * tau;
        *y -= s * t1;
    }
}

/// Deflated 2×2 block at rows/columns (i−1, i): split it by a rotation if its eigenvalues are
/// real, otherwise record the complex pair (positive imaginary part first).
fn deflate2(h: &mut [f64], z: &mut [f64], n: usize, i: usize, wr: &mut [f64], wi: &mut [f64]) {
    let a = h[ix(i - 1, i - 1, n)];
    let b = h[ix(i - 1, i, n)];
    let c = h[ix(i, i - 1, n)];
    let d = h[ix(i, i, n)];
    let p = 0.5 * (a - d);
    let q = p * p + b * c;
    if q >= 0.0 {
        let sq = q.sqrt();
        let zz = if p >= 0.0 { p + sq } else { p - sq };
        let s = zz.abs() + c.abs();
        if s > 0.0 {
            let (mut sn, mut cs) = (c / s, zz / s);
            let r = sn.hypot(cs);
            sn /= r;
            cs /= r;
            for j in i - 1..n {
                let t = h[ix(i - 1, j, n)];
                let u = h[ix(i, j, n)];
                h[ix(i - 1, j, n)] = cs * t + sn * u;
                h[ix(i, j, n)] = cs * u - sn * t;
            }
            for (m, rows) in [(&mut *h, i + 1), (&mut *z, n)] {
                let (x, y) = m[(i - 1) * n..].split_at_mut(n);
                for (t, u) in x[..rows].iter_mut().zip(y[..rows].iter_mut()) {
                    let (t0, u0) = (*t, *u);
                    *t = cs * t0 + sn * u0;
                    *u = cs * u0 - sn * t0;
                }
            }
        }
        h[ix(i, i - 1, n)] = 0.0;
        wr[i - 1] = h[ix(i - 1, i - 1, n)];
        wr[i] = h[ix(i, i, n)];
        wi[i - 1] = 0.0;
        wi[i] = 0.0;
    } else {
        let im = (-q).sqrt();
        wr[i - 1] = d + p;
        wr[i] = d + p;
        wi[i - 1] = im;
        wi[i] = -im;
    }
}

/// Complete-pivoting solve of the 2×2 system `A x = b`, pivots below `smin` replaced by `smin`
/// (LAPACK `dlaln2`).
fn solve2(a: [[c64; 2]; 2], b: [c64; 2], smin: f64) -> [c64; 2] {
    let mut best = (0usize, 0usize);
    let mut cmax = -1.0;
    for (r, row) in a.iter().enumerate() {
        for (c, &e) in row.iter().enumerate() {
            if abs1(e) > cmax {
                cmax = abs1(e);
                best = (r, c);
            }
        }
    }
    let s = c64::new(smin, 0.0);
    if cmax < smin {
        return [cdiv(b[0], s), cdiv(b[1], s)];
    }
    let (r0, r1) = if best.0 == 0 { (0, 1) } else { (1, 0) };
    let (c0, c1) = if best.1 == 0 { (0, 1) } else { (1, 0) };
    let p = a[r0][c0];
    let a12 = a[r0][c1];
    let l = cdiv(a[r1][c0], p);
    let mut u22 = a[r1][c1] - l * a12;
    if abs1(u22) < smin {
        u22 = s;
    }
    let y1 = b[r0];
    let y2 = b[r1] - l * y1;
    let x2 = cdiv(y2, u22);
    let x1 = cdiv(y1 - a12 * x2, p);
    let mut x = [c64::new(0.0, 0.0); 2];
    x[c0] = x1;
    x[c1] = x2;
    x
}

/// Eigenvectors `Z x` of `Z T Zᵀ` by back-substitution on the quasi-triangular `T` (dtrevc).
/// Column-major `n × n`, unit 2-norm columns; `None` if a column is not finite.
fn eigenvectors(t: &[f64], z: &[f64], n: usize, wr: &[f64], wi: &[f64]) -> Option<Vec<c64>> {
    let zero = c64::new(0.0, 0.0);
    let mut out = vec![zero; n * n];
    let mut x = vec![zero; n];
    let mut rhs = vec![zero; n];
    let mut k = 0;
    while k < n {
        let pair = wi[k] > 0.0 && k + 1 < n;
        let lam = c64::new(wr[k], if pair { wi[k] } else { 0.0 });
        x.iter_mut().for_each(|e| *e = zero);
        let top = if pair {
            // Eigenvector of the 2×2 block [[a, b], [c, d]]: (b, λ−a) or (λ−d, c).
            let a = t[ix(k, k, n)];
            let b = t[ix(k, k + 1, n)];
            let c = t[ix(k + 1, k, n)];
            let d = t[ix(k + 1, k + 1, n)];
            let e1 = [c64::new(b, 0.0), lam - a];
            let e2 = [lam - d, c64::new(c, 0.0)];
            let e = if abs1(e1[0]) + abs1(e1[1]) >= abs1(e2[0]) + abs1(e2[1]) {
                e1
            } else {
                e2
            };
            let s = abs1(e[0]).max(abs1(e[1]));
            x[k] = e[0] / s;
            x[k + 1] = e[1] / s;
            k + 1
        } else {
            x[k] = c64::new(1.0, 0.0);
            k
        };
        // rhs = −T[0..k, k..=top] x[k..=top]
        rhs[..k].iter_mut().for_each(|e| *e = zero);
        for j in k..=top {
            let xj = x[j];
            for (r, tr) in rhs[..k].iter_mut().zip(&t[j * n..j * n + k]) {
                *r -= xj * tr;
            }
        }
        let smin = (ULP * abs1(lam)).max(SMIN_FLOOR);
        let mut rows = k; // rows 0..rows remain
        while rows > 0 {
            let r = rows - 1;
            let lo = if r >= 1 && wi[r - 1] > 0.0 {
                let aa = [
                    [c64::new(t[ix(r - 1, r - 1, n)], 0.0) - lam, c64::new(t[ix(r - 1, r, n)], 0.0)],
                    [c64::new(t[ix(r, r - 1, n)], 0.0), c64::new(t[ix(r, r, n)], 0.0) - lam],
                ];
                let sol = solve2(aa, [rhs[r - 1], rhs[r]], smin);
                x[r - 1] = sol[0];
                x[r] = sol[1];
                r - 1
            } else {
                let mut den = c64::new(t[ix(r, r, n)], 0.0) - lam;
                if abs1(den) < smin {
                    den = c64::new(smin, 0.0);
                }
                x[r] = cdiv(rhs[r], den);
                r
            };
            // Overflow guard.
            let xm = x[lo..=top].iter().fold(0.0f64, |m, e| m.max(abs1(*e)));
            if !xm.is_finite() {
                return None;
            }
            if xm > BIG {
                let s = 1.0 / xm;
                x[lo..=top].iter_mut().for_each(|e| *e *= s);
                rhs[..lo].iter_mut().for_each(|e| *e *= s);
            }
            for j in lo..rows {
                let xj = x[j];
                for (rr, tr) in rhs[..lo].iter_mut().zip(&t[j * n..j * n + lo]) {
                    *rr -= xj * tr;
                }
            }
            rows = lo;
        }
        // v = Z x, unit 2-norm.
        let col = &mut out[k * n..k * n + n];
        for j in 0..=top {
            let xj = x[j];
            for (o, zr) in col.iter_mut().zip(&z[j * n..j * n + n]) {
                *o += xj * zr;
            }
        }
        let nrm = col.iter().map(|e| e.norm_sqr()).sum::<f64>().sqrt();
        if !(nrm > 0.0 && nrm.is_finite()) {
            return None;
        }
        let s = 1.0 / nrm;
        col.iter_mut().for_each(|e| *e *= s);
        if pair {
            for i in 0..n {
                out[ix(i, k + 1, n)] = out[ix(i, k, n)].conj();
            }
            k += 2;
        } else {
            k += 1;
        }
    }
    Some(out)
}
