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
//! which keeps every intermediate far from overflow and underflow, then balanced by a diagonal
//! similarity of powers of 2 (`dgebal`, scaling only; the impact engine's matrices are balanced
//! by construction and pass unchanged), so that e.g. the unbalanced first-order form
//! `[[0, I], [−M⁻¹K, −M⁻¹C]]` also gets eigenvalues accurate relative to `|λ|`.

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
        for x in a.col_as_slice(j) {
            amax = amax.max(x.abs());
        }
    }
    if !amax.is_finite() {
        return None;
    }
    let mut vmat = Mat::<c64>::zeros(n, n);
    if amax == 0.0 {
        for j in 0..n {
            vmat[(j, j)] = c64::new(1.0, 0.0);
        }
        return Some((vec![c64::new(0.0, 0.0); n], vmat));
    }
    let inv = 1.0 / amax;
    // One workspace: H, Z (n² each), wr, wi, and two n-vectors for the Hessenberg reduction.
    let mut work = vec![0.0f64; 2 * n * n + 5 * n];
    let (h, rest) = work.split_at_mut(n * n);
    let (z, rest) = rest.split_at_mut(n * n);
    let (wr, rest) = rest.split_at_mut(n);
    let (wi, rest) = rest.split_at_mut(n);
    let (d, tmp) = rest.split_at_mut(n);
    for j in 0..n {
        for (hij, aij) in h[j * n..j * n + n].iter_mut().zip(a.col_as_slice(j)) {
            *hij = aij * inv;
        }
        z[j * n + j] = 1.0;
    }
    balance(h, n, d);
    hessenberg(h, z, n, tmp);
    if !francis(h, z, n, wr, wi) {
        return None;
    }
    if !eigenvectors(h, z, d, n, wr, wi, &mut vmat) {
        return None;
    }
    let lam = (0..n)
        .map(|k| c64::new(wr[k] * amax, wi[k] * amax))
        .collect();
    Some((lam, vmat))
}

/// Diagonal balancing `H ← D⁻¹ H D` by powers of 2 (exact), LAPACK `dgebal` job 'S'
/// (Parlett & Reinsch, Numer. Math. 13 (1969) 293–304, with the 2-norms of LAPACK 3.5):
/// row and column `i` are rescaled by `f = 2^k` while that reduces `‖col_i‖ + ‖row_i‖`
/// (off-diagonal parts) below 0.95 of its value. Eigenvectors of the input are `D v`.
/// Matrices that are already balanced (as the impact engine's) cost one pass of norms.
fn balance(h: &mut [f64], n: usize, d: &mut [f64]) {
    d.iter_mut().for_each(|x| *x = 1.0);
    // Cumulative scale factors kept within 2^±200 (the matrix is normalised to max|h| = 1).
    let (lo, hi) = (2f64.powi(-200), 2f64.powi(200));
    for _pass in 0..100 {
        let mut changed = false;
        for i in 0..n {
            let mut c = 0.0;
            let mut r = 0.0;
            for j in 0..n {
                if j != i {
                    c += h[ix(j, i, n)] * h[ix(j, i, n)];
                    r += h[ix(i, j, n)] * h[ix(i, j, n)];
                }
            }
            let (mut c, mut r) = (c.sqrt(), r.sqrt());
            if c == 0.0 || r == 0.0 {
                continue;
            }
            let s = c + r;
            let mut f = 1.0;
            let mut g = r / 2.0;
            while c < g && d[i] * f < hi {
                f *= 2.0;
                c *= 2.0;
                r /= 2.0;
                g /= 2.0;
            }
            g = c / 2.0;
            while g >= r && d[i] * f > lo {
                f /= 2.0;
                c /= 2.0;
                g /= 2.0;
                r *= 2.0;
            }
            if c + r >= 0.95 * s {
                continue;
            }
            d[i] *= f;
            changed = true;
            let g = 1.0 / f;
            for j in 0..n {
                h[ix(i, j, n)] *= g;
            }
            for x in &mut h[i * n..i * n + n] {
                *x *= f;
            }
        }
        if !changed {
            break;
        }
    }
}

/// Householder reduction to upper Hessenberg form, `H ← Pᵀ H P`, `Z ← Z P`.
fn hessenberg(h: &mut [f64], z: &mut [f64], n: usize, tmp: &mut [f64]) {
    let (v, f) = tmp.split_at_mut(n);
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
                for (mij, fi) in m[j * n..j * n + n].iter_mut().zip(f.iter()) {
                    *mij -= fi * c;
                }
            }
        }
    }
}

/// Francis double-shift QR to real Schur form, accumulating into `z`; eigenvalues in
/// `wr + i wi`. Returns false when an eigenvalue needs more than `30 max(n, 10)` iterations.
///
/// Each iteration on the active block `l..=i` (`l` from [`negligible_subdiagonal`]): the
/// shifts ([`shifts`]), the bulge's start ([`bulge_start`]) and the sweep ([`qr_sweep`]),
/// until a 1×1 or 2×2 block deflates at the bottom.
fn francis(h: &mut [f64], z: &mut [f64], n: usize, wr: &mut [f64], wi: &mut [f64]) -> bool {
    let smlnum = f64::MIN_POSITIVE * (n as f64 / ULP);
    let itmax = 30 * n.max(10);
    let mut hi = n; // rows < hi are not yet deflated
    while hi > 0 {
        let i = hi - 1;
        let mut its = 0usize;
        let l = loop {
            let k = negligible_subdiagonal(h, n, i, smlnum);
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
            let (x, y, w) = shifts(h, n, l, i, its);
            let (m, v) = bulge_start(h, n, l, i, (x, y, w));
            qr_sweep(h, z, n, (l, m, i), v);
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

/// The row `k ≤ i` of the lowest negligible subdiagonal entry `h[k, k−1]` of the active
/// block ending at row `i` (0 when there is none), by the Ahues–Tisseur criterion of LAPACK's
/// `dlahqr`.
fn negligible_subdiagonal(h: &[f64], n: usize, i: usize, smlnum: f64) -> usize {
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
    k
}

/// The shifts of iteration `its` on the block `l..=i`: the eigenvalues of `[[y, ·], [·, x]]`
/// with off-diagonal product `w`, the trailing 2×2 block's (a real pair replaced by the one
/// closer to `h[i, i]`, twice), or an exceptional shift every 10th iteration.
fn shifts(h: &[f64], n: usize, l: usize, i: usize, its: usize) -> (f64, f64, f64) {
    let (mut x, mut y, mut w);
    if its.is_multiple_of(20) {
        let s = h[ix(i, i - 1, n)].abs() + h[ix(i - 1, i - 2, n)].abs();
        x = 0.75 * s + h[ix(i, i, n)];
        y = x;
        w = -0.4375 * s * s;
    } else if its.is_multiple_of(10) {
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
    (x, y, w)
}

/// The bulge's start row `m ≥ l` (two consecutive small subdiagonal entries) and the first
/// column `v` of the double-shift polynomial there, scaled to unit 1-norm.
fn bulge_start(
    h: &[f64],
    n: usize,
    l: usize,
    i: usize,
    shift: (f64, f64, f64),
) -> (usize, [f64; 3]) {
    let (x, y, w) = shift;
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
    (m, v)
}

/// The double-shift QR sweep (bulge chase) over rows `m..=i` of the block `l..=i`
/// (`rows = (l, m, i)`) from the first column `v`: 3×3 (last: 2×2) reflectors applied to `h`
/// and accumulated into `z`.
fn qr_sweep(h: &mut [f64], z: &mut [f64], n: usize, rows: (usize, usize, usize), mut v: [f64; 3]) {
    let (l, m, i) = rows;
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
            (v[1] * v[1] + v[2] * v[2]).sqrt()
        } else {
            v[1].abs()
        };
        if xnorm == 0.0 {
            continue;
        }
        // |v| ≤ 1 after the scaling above: no overflow in the squares.
        let beta = -(alpha * alpha + xnorm * xnorm)
            .sqrt()
            .copysign(if alpha >= 0.0 { 1.0 } else { -1.0 });
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
                let c = &mut h[j * n + k..j * n + k + 3];
                let s = c[0] + v1 * c[1] + v2 * c[2];
                c[0] -= s * tau;
                c[1] -= s * t1;
                c[2] -= s * t2;
            }
            let rmax = (k + 3).min(i);
            apply_right3(h, n, k, rmax + 1, tau, t1, t2, v1, v2);
            apply_right3(z, n, k, n, tau, t1, t2, v1, v2);
        } else {
            for j in k..n {
                let c = &mut h[j * n + k..j * n + k + 2];
                let s = c[0] + v1 * c[1];
                c[0] -= s * tau;
                c[1] -= s * t1;
            }
            apply_right2(h, n, k, i + 1, tau, t1, v1);
            apply_right2(z, n, k, n, tau, t1, v1);
        }
    }
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
    let a = &mut a[..rows];
    let b = &mut b[..rows];
    let c = &mut c[..rows];
    for r in 0..rows {
        let s = a[r] + v1 * b[r] + v2 * c[r];
        a[r] -= s * tau;
        b[r] -= s * t1;
        c[r] -= s * t2;
    }
}

/// `M[0..rows, k..k+2] ← M (I − τ u uᵀ)`, `u = (1, v1)`.
#[inline(always)]
fn apply_right2(m: &mut [f64], n: usize, k: usize, rows: usize, tau: f64, t1: f64, v1: f64) {
    let (a, rest) = m[k * n..].split_at_mut(n);
    let a = &mut a[..rows];
    let b = &mut rest[..rows];
    for r in 0..rows {
        let s = a[r] + v1 * b[r];
        a[r] -= s * tau;
        b[r] -= s * t1;
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
            let r = (sn * sn + cs * cs).sqrt();
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
/// Written into the zero-initialised `out`, unit 2-norm columns; false if a column is not
/// finite.
fn eigenvectors(
    t: &[f64],
    z: &[f64],
    dscale: &[f64],
    n: usize,
    wr: &[f64],
    wi: &[f64],
    out: &mut Mat<c64>,
) -> bool {
    let zero = c64::new(0.0, 0.0);
    let mut xr = vec![zero; 2 * n];
    let (x, rhs) = xr.split_at_mut(n);
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
                    [
                        c64::new(t[ix(r - 1, r - 1, n)], 0.0) - lam,
                        c64::new(t[ix(r - 1, r, n)], 0.0),
                    ],
                    [
                        c64::new(t[ix(r, r - 1, n)], 0.0),
                        c64::new(t[ix(r, r, n)], 0.0) - lam,
                    ],
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
                return false;
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
        let col = out.col_as_slice_mut(k);
        for j in 0..=top {
            let xj = x[j];
            for (o, zr) in col.iter_mut().zip(&z[j * n..j * n + n]) {
                *o += xj * zr;
            }
        }
        for (o, di) in col.iter_mut().zip(dscale) {
            *o *= di;
        }
        let nrm = col.iter().map(|e| e.norm_sqr()).sum::<f64>().sqrt();
        if !(nrm > 0.0 && nrm.is_finite()) {
            return false;
        }
        let s = 1.0 / nrm;
        col.iter_mut().for_each(|e| *e *= s);
        if pair {
            for i in 0..n {
                out[(i, k + 1)] = out[(i, k)].conj();
            }
            k += 2;
        } else {
            k += 1;
        }
    }
    true
}
