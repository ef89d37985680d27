//! Matrix exponential by scaling and squaring with the [13/13] Padé approximant
//! (Higham, "The scaling and squaring method for the matrix exponential revisited",
//! SIAM J. Matrix Anal. Appl. 26 (2005) 1179-1193, Algorithm 2.3 with m = 13).
//!
//! Hand-written on faer because faer 0.24 has no `expm`; nalgebra's would pull in a second
//! linear-algebra crate for one function. Used by the exact propagator when a mode's
//! eigenvectors are too ill-conditioned for the spectral form.

use faer::linalg::solvers::Solve;
use faer::Mat;

const B13: [f64; 14] = [
    64764752532480000.0,
    32382376266240000.0,
    7771770303897600.0,
    1187353796428800.0,
    129060195264000.0,
    10559470521600.0,
    670442572800.0,
    33522128640.0,
    1323241920.0,
    40840800.0,
    960960.0,
    16380.0,
    182.0,
    1.0,
];
const THETA13: f64 = 5.371920351148152;

/// 1-norm (maximum absolute column sum).
pub fn norm1(a: &Mat<f64>) -> f64 {
    (0..a.ncols())
        .map(|j| (0..a.nrows()).map(|i| a[(i, j)].abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// Diagonal balancing (Parlett & Reinsch 1969, as LAPACK's `gebal` without permutation):
/// powers of two `d` such that `D⁻¹AD` has rows and columns of similar norm. For the
/// first-order form of a stiff oscillator ([[0, 1], [−ω², 0]]) it recovers [[0, ω], [−ω, 0]],
/// which scaling and squaring handles to round-off instead of losing `log₂ ω²` digits.
pub fn balance(a: &Mat<f64>) -> Vec<f64> {
    let n = a.nrows();
    let mut d = vec![1.0; n];
    let mut b = a.clone();
    for _ in 0..100 {
        let mut converged = true;
        for i in 0..n {
            let c: f64 = (0..n).filter(|&k| k != i).map(|k| b[(k, i)].abs()).sum();
            let r: f64 = (0..n).filter(|&k| k != i).map(|k| b[(i, k)].abs()).sum();
            if c == 0.0 || r == 0.0 {
                continue;
            }
            let mut f = 1.0;
            let (mut cc, g) = (c, r / 2.0);
            // f = 2^k with c·f² ≈ r.
            while cc < g {
                f *= 2.0;
                cc *= 4.0;
            }
            let g = r * 2.0;
            while cc >= g {
                f /= 2.0;
                cc /= 4.0;
            }
            // Apply only if it reduces the combined norm noticeably (LAPACK's 0.95 rule).
            if f != 1.0 && c * f + r / f < 0.95 * (c + r) {
                converged = false;
                d[i] *= f;
                for k in 0..n {
                    b[(i, k)] /= f;
                    b[(k, i)] *= f;
                }
            }
        }
        if converged {
            break;
        }
    }
    d
}

/// `exp(A t)`, with balancing.
pub fn expm(a: &Mat<f64>, t: f64) -> Mat<f64> {
    let n = a.nrows();
    let d = balance(a);
    // B = D⁻¹ A D; exp(A t) = D exp(B t) D⁻¹.
    let b = Mat::<f64>::from_fn(n, n, |i, j| a[(i, j)] * d[j] / d[i]);
    let e = expm_unbalanced(&b, t);
    Mat::<f64>::from_fn(n, n, |i, j| e[(i, j)] * d[i] / d[j])
}

fn expm_unbalanced(a: &Mat<f64>, t: f64) -> Mat<f64> {
    let n = a.nrows();
    let mut at = a * faer::Scale(t);
    let nrm = norm1(&at);
    let s = if nrm > THETA13 {
        (nrm / THETA13).log2().ceil() as i32
    } else {
        0
    };
    if s > 0 {
        at = &at * faer::Scale(0.5_f64.powi(s));
    }
    let ident = Mat::<f64>::identity(n, n);
    let a2 = &at * &at;
    let a4 = &a2 * &a2;
    let a6 = &a4 * &a2;
    let b = &B13;
    let inner_u =
        &a6 * (&a6 * faer::Scale(b[13]) + &a4 * faer::Scale(b[11]) + &a2 * faer::Scale(b[9]));
    let u_poly = inner_u
        + &a6 * faer::Scale(b[7])
        + &a4 * faer::Scale(b[5])
        + &a2 * faer::Scale(b[3])
        + &ident * faer::Scale(b[1]);
    let u = &at * u_poly;
    let inner_v =
        &a6 * (&a6 * faer::Scale(b[12]) + &a4 * faer::Scale(b[10]) + &a2 * faer::Scale(b[8]));
    let v = inner_v
        + &a6 * faer::Scale(b[6])
        + &a4 * faer::Scale(b[4])
        + &a2 * faer::Scale(b[2])
        + &ident * faer::Scale(b[0]);
    let p = &v + &u;
    let q = &v - &u;
    let mut r = q.partial_piv_lu().solve(&p);
    for _ in 0..s {
        r = &r * &r;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Undamped oscillator: exp([[0,1],[-w²,0]] t) = [[cos, sin/w],[-w sin, cos]].
    /// Scaling and squaring is accurate normwise: ‖E − exp(At)‖₁ ≤ c·u·‖exp(At)‖₁.
    #[test]
    fn oscillator_closed_form() {
        let w = 2000.0;
        let mut a = Mat::<f64>::zeros(2, 2);
        a[(0, 1)] = 1.0;
        a[(1, 0)] = -w * w;
        for &t in &[1e-5, 3.3e-3, 0.77] {
            let e = expm(&a, t);
            let (c, s) = ((w * t).cos(), (w * t).sin());
            let mut exact = Mat::<f64>::zeros(2, 2);
            exact[(0, 0)] = c;
            exact[(0, 1)] = s / w;
            exact[(1, 0)] = -w * s;
            exact[(1, 1)] = c;
            let diff = &e - &exact;
            let rel = norm1(&diff) / norm1(&exact);
            // Round-off grows with the number of squarings, about log2(‖A t‖).
            let tol = 1e-15 * (w * w * t).max(1.0).log2().max(1.0) * 10.0;
            assert!(rel < tol, "t={t}: relative error {rel:e} > {tol:e}");
        }
    }

    /// Defective (Jordan) block: exp([[0,1],[0,0]] t) = [[1,t],[0,1]].
    #[test]
    fn jordan_block() {
        let mut a = Mat::<f64>::zeros(2, 2);
        a[(0, 1)] = 1.0;
        let e = expm(&a, 2.5);
        assert!(
            (e[(0, 0)] - 1.0).abs() < 1e-15
                && (e[(0, 1)] - 2.5).abs() < 1e-14
                && e[(1, 0)].abs() < 1e-15
        );
    }
}
