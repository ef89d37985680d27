//! Checks of the hand-written small dense eigen-solvers (`meid::integrate::small`).
//!
//! References are mathematical identities (residual `‖AV − VΛ‖/‖A‖`, `‖V V⁻¹ − I‖`,
//! orthonormality `‖UᵀU − I‖`) and closed forms (2×2 eigenvalues, path-graph Laplacian
//! `2 − 2cos(kπ/(n+1))`, free chain `2 − 2cos(kπ/n)`, 2-DOF chain frequencies, damped
//! oscillator roots `(−c ± √(c² − 4mk))/(2m)`), never the output of another eigen-solver.

use faer::{c64, Mat};
use meid::integrate::small::{inverse, norm_c, real_eigen, sym_eigen, sym_eigen_jacobi};
use proptest::prelude::*;

use meid::rng::SplitMix64 as Rng;

fn random(n: usize, seed: u64) -> Mat<f64> {
    let mut r = Rng::new(seed);
    Mat::<f64>::from_fn(n, n, |_, _| r.next_sym())
}

fn fro(a: &Mat<f64>) -> f64 {
    let mut s = 0.0;
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            s += a[(i, j)] * a[(i, j)];
        }
    }
    s.sqrt()
}

/// ‖AV − VΛ‖_F / ‖A‖_F (absolute when A = 0).
fn residual(a: &Mat<f64>, lam: &[c64], v: &Mat<c64>) -> f64 {
    let n = a.nrows();
    let mut s = 0.0;
    for j in 0..n {
        for i in 0..n {
            let mut av = c64::new(0.0, 0.0);
            for k in 0..n {
                av += v[(k, j)] * a[(i, k)];
            }
            s += (av - v[(i, j)] * lam[j]).norm_sqr();
        }
    }
    let na = fro(a);
    if na > 0.0 {
        s.sqrt() / na
    } else {
        s.sqrt()
    }
}

/// ‖V W − I‖_F.
fn inv_err(v: &Mat<c64>, w: &Mat<c64>) -> f64 {
    let n = v.nrows();
    let mut s = 0.0;
    for j in 0..n {
        for i in 0..n {
            let mut p = c64::new(0.0, 0.0);
            for k in 0..n {
                p += v[(i, k)] * w[(k, j)];
            }
            if i == j {
                p -= c64::new(1.0, 0.0);
            }
            s += p.norm_sqr();
        }
    }
    s.sqrt()
}

/// Conjugate pairs adjacent, positive imaginary part first, exact conjugates; unit columns.
fn check_structure(lam: &[c64], v: &Mat<c64>) {
    let n = lam.len();
    let mut j = 0;
    while j < n {
        let nrm: f64 = (0..n).map(|i| v[(i, j)].norm_sqr()).sum::<f64>().sqrt();
        assert!((nrm - 1.0).abs() <= 1e-14, "column {j} norm {nrm}");
        if lam[j].im != 0.0 {
            assert!(
                lam[j].im > 0.0,
                "pair at {j} starts with negative imaginary part"
            );
            assert!(j + 1 < n, "unpaired complex eigenvalue");
            assert_eq!(lam[j + 1], lam[j].conj());
            for i in 0..n {
                assert_eq!(v[(i, j + 1)], v[(i, j)].conj());
            }
            for i in 0..n {
                for k in [j, j + 1] {
                    assert!(v[(i, k)].re.is_finite() && v[(i, k)].im.is_finite());
                }
            }
            j += 2;
        } else {
            for i in 0..n {
                assert_eq!(v[(i, j)].im, 0.0, "real eigenvalue with complex vector");
            }
            j += 1;
        }
    }
}

/// Full check of a diagonalisable matrix: residual, structure, inverse. Returns ‖V‖‖V⁻¹‖.
fn check_eig(a: &Mat<f64>, tol_res: f64) -> (Vec<c64>, Mat<c64>, f64) {
    let (lam, v) = real_eigen(a).unwrap();
    let res = residual(a, &lam, &v);
    assert!(res <= tol_res, "residual {res:.3e} > {tol_res:.1e}");
    check_structure(&lam, &v);
    let w = inverse(&v).expect("eigenvectors independent");
    let cond = norm_c(&v) * norm_c(&w);
    // Backward-stable inversion: ‖VW − I‖ ≲ n ε cond(V).
    let e = inv_err(&v, &w);
    let n = a.nrows().max(1) as f64;
    assert!(
        e <= 10.0 * n * f64::EPSILON * cond,
        "‖VV⁻¹−I‖ = {e:.3e}, cond {cond:.3e}"
    );
    (lam, v, cond)
}

fn sort_c(mut l: Vec<c64>) -> Vec<c64> {
    l.sort_by(|a, b| a.re.total_cmp(&b.re).then(a.im.total_cmp(&b.im)));
    l
}

#[test]
fn random_matrices_8_24_50() {
    // Reference: the identities A V = V Λ (residual ≤ 1e-13 ‖A‖) and V V⁻¹ = I.
    for (n, seed) in [(8, 1), (8, 2), (24, 3), (24, 4), (50, 5), (50, 6)] {
        let a = random(n, seed);
        let (lam, _, cond) = check_eig(&a, 1e-13);
        assert!(cond < 1e6, "n={n}: cond {cond:.2e}");
        // Trace identity: Σλ = tr A.
        let tr: f64 = (0..n).map(|i| a[(i, i)]).sum();
        let sl: c64 = lam.iter().sum();
        assert!((sl.re - tr).abs() <= 1e-12 * fro(&a) && sl.im.abs() <= 1e-12 * fro(&a));
    }
}

/// First-order matrix [[0, I], [−M⁻¹K, −M⁻¹C]] of a chain (diagonal M).
fn first_order(k: &Mat<f64>, c: &Mat<f64>, m: &[f64]) -> Mat<f64> {
    let n = m.len();
    Mat::<f64>::from_fn(2 * n, 2 * n, |i, j| {
        if i < n {
            if j == n + i {
                1.0
            } else {
                0.0
            }
        } else if j < n {
            -k[(i - n, j)] / m[i - n]
        } else {
            -c[(i - n, j - n)] / m[i - n]
        }
    })
}

/// Balanced first-order matrix A_r = [[0, S], [−diag(κ/S), −C_r]], S = diag(√κ), of the impact
/// engine (crates/meid/src/integrate/propagator.rs) for K > 0.
fn balanced(k: &Mat<f64>, c: &Mat<f64>, m: &[f64]) -> Mat<f64> {
    let n = m.len();
    let sq: Vec<f64> = m.iter().map(|x| x.sqrt()).collect();
    let kt = Mat::<f64>::from_fn(n, n, |i, j| k[(i, j)] / (sq[i] * sq[j]));
    let ct = Mat::<f64>::from_fn(n, n, |i, j| c[(i, j)] / (sq[i] * sq[j]));
    let (kappa, q) = sym_eigen(&kt).unwrap();
    let cr = Mat::<f64>::from_fn(n, n, |i, j| {
        let mut s = 0.0;
        for a in 0..n {
            for b in 0..n {
                s += q[(a, i)] * ct[(a, b)] * q[(b, j)];
            }
        }
        s
    });
    Mat::<f64>::from_fn(2 * n, 2 * n, |i, j| {
        if i < n {
            if j == n + i {
                kappa[i].sqrt()
            } else {
                0.0
            }
        } else if j < n {
            if j == i - n {
                -kappa[j].sqrt()
            } else {
                0.0
            }
        } else {
            -0.5 * (cr[(i - n, j - n)] + cr[(j - n, i - n)])
        }
    })
}

/// Grounded chain: spring k[0] to ground, k[i] between masses i−1 and i.
fn chain_k(k: &[f64]) -> Mat<f64> {
    let n = k.len();
    let mut m = Mat::<f64>::zeros(n, n);
    for i in 0..n {
        m[(i, i)] += k[i];
        if i > 0 {
            m[(i - 1, i - 1)] += k[i];
            m[(i - 1, i)] -= k[i];
            m[(i, i - 1)] -= k[i];
        }
    }
    m
}

#[test]
fn undamped_two_dof_chain_closed_form() {
    // m1 m2 ω⁴ − (m1 k2 + m2 (k1 + k2)) ω² + k1 k2 = 0; eigenvalues ±iω.
    let (m1, m2, k1, k2) = (2.0f64, 0.5f64, 3.0e6f64, 1.2e6f64);
    let b = m1 * k2 + m2 * (k1 + k2);
    let disc = (b * b - 4.0 * m1 * m2 * k1 * k2).sqrt();
    let w2 = [(b - disc) / (2.0 * m1 * m2), (b + disc) / (2.0 * m1 * m2)];
    let k = chain_k(&[k1, k2]);
    let c = Mat::<f64>::zeros(2, 2);
    for (bal, a) in [
        (false, first_order(&k, &c, &[m1, m2])),
        (true, balanced(&k, &c, &[m1, m2])),
    ] {
        let (lam, _, cond) = check_eig(&a, 1e-13);
        // Balanced undamped A_r is skew-symmetric (normal): V unitary, ‖V‖_F ‖V⁻¹‖_F = n = 4.
        if bal {
            assert!((cond - 4.0).abs() <= 1e-12, "cond {cond}");
        }
        let mut l = lam;
        l.sort_by(|a, b| a.im.total_cmp(&b.im));
        // Sorted by imaginary part: −iω₂, −iω₁, +iω₁, +iω₂ (all real parts ~0).
        let expect = [-w2[1].sqrt(), -w2[0].sqrt(), w2[0].sqrt(), w2[1].sqrt()];
        let scale = w2[1].sqrt();
        for (li, e) in l.iter().zip(expect) {
            assert!((li.im - e).abs() <= 1e-13 * scale, "{li} vs {e}");
            assert!(li.re.abs() <= 1e-13 * scale, "{li}");
        }
    }
}

#[test]
fn overdamped_oscillator_and_chain() {
    // Single DOF, m = 3.5 kg, k = 1800 N/m, c = 700 N s/m: λ = (−c ± √(c² − 4mk))/(2m), real.
    let (m, k, c) = (3.5f64, 1800.0f64, 700.0f64);
    let d = (c * c - 4.0 * m * k).sqrt();
    let exact = [(-c - d) / (2.0 * m), (-c + d) / (2.0 * m)];
    let km = Mat::<f64>::from_fn(1, 1, |_, _| k);
    let cm = Mat::<f64>::from_fn(1, 1, |_, _| c);
    for a in [first_order(&km, &cm, &[m]), balanced(&km, &cm, &[m])] {
        let (lam, _, _) = check_eig(&a, 1e-13);
        let l = sort_c(lam);
        for (li, e) in l.iter().zip(exact) {
            assert_eq!(li.im, 0.0);
            assert!((li.re - e).abs() <= 1e-13 * e.abs(), "{li} vs {e}");
        }
    }
    // 2-DOF chain, equal m, k, proportional damping C = (c/k) K: each mode ω² solves
    // λ² + (c/k) ω² λ + ω² = 0, ω² = (k/m)(3 ∓ √5)/2; both modes overdamped.
    let kk = chain_k(&[k, k]);
    let cc = Mat::<f64>::from_fn(2, 2, |i, j| kk[(i, j)] * c / k);
    let mut exact = Vec::new();
    for w2 in [
        k / m * (3.0 - 5f64.sqrt()) / 2.0,
        k / m * (3.0 + 5f64.sqrt()) / 2.0,
    ] {
        let b = c / k * w2;
        let d = (b * b - 4.0 * w2).sqrt();
        exact.push(c64::new((-b - d) / 2.0, 0.0));
        exact.push(c64::new(-2.0 * w2 / (b + d), 0.0)); // (−b + d)/2 without cancellation
    }
    let exact = sort_c(exact);
    for a in [first_order(&kk, &cc, &[m, m]), balanced(&kk, &cc, &[m, m])] {
        let (lam, _, cond) = check_eig(&a, 1e-13);
        assert!(cond < 1e4, "cond {cond}");
        let l = sort_c(lam);
        for (li, e) in l.iter().zip(&exact) {
            assert_eq!(li.im, 0.0);
            assert!((li.re - e.re).abs() <= 1e-12 * e.re.abs(), "{li} vs {e}");
        }
    }
}

#[test]
fn damped_chains_random_psd_damping() {
    // Balanced matrices of 4-, 12- and 25-DOF chains with random masses, stiffnesses and a
    // random PSD damping C = B Bᵀ (rank n/2): identities only.
    for (n, seed) in [(4usize, 11u64), (12, 12), (25, 13)] {
        let mut r = Rng::new(seed);
        let m: Vec<f64> = (0..n).map(|_| 1.0 + 10.0 * r.next_sym().abs()).collect();
        let ks: Vec<f64> = (0..n)
            .map(|_| 1e5 * (1.0 + 100.0 * r.next_sym().abs()))
            .collect();
        let k = chain_k(&ks);
        let bcols = n / 2;
        let b = Mat::<f64>::from_fn(n, bcols, |_, _| 30.0 * r.next_sym());
        let c = Mat::<f64>::from_fn(n, n, |i, j| (0..bcols).map(|l| b[(i, l)] * b[(j, l)]).sum());
        let a = balanced(&k, &c, &m);
        let (lam, _, cond) = check_eig(&a, 1e-13);
        assert!(cond < 1e6, "n={n}: cond {cond:.2e}");
        // Dissipative: Re λ ≤ 0 (up to round-off).
        let scale = lam.iter().map(|l| l.norm()).fold(0.0, f64::max);
        assert!(lam.iter().all(|l| l.re <= 1e-13 * scale));
    }
}

#[test]
fn repeated_pair_independent_vectors() {
    // Two identical uncoupled damped oscillators: λ = −c/2 ± i√(ω² − c²/4), each twice, with
    // two independent eigenvectors each.
    let (w, c) = (40.0, 3.0);
    let blk = |i: usize, j: usize| match (i % 2, j % 2) {
        (0, 1) => w,
        (1, 0) => -w,
        (1, 1) => -c,
        _ => 0.0,
    };
    let a = Mat::<f64>::from_fn(4, 4, |i, j| if i / 2 == j / 2 { blk(i, j) } else { 0.0 });
    // Same system, coordinates (x1, x2, v1, v2).
    let perm = [0, 2, 1, 3];
    let b = Mat::<f64>::from_fn(4, 4, |i, j| a[(perm[i], perm[j])]);
    // Undamped: skew-symmetric, ±iω twice.
    let s = Mat::<f64>::from_fn(4, 4, |i, j| match (i / 2 == j / 2, i % 2, j % 2) {
        (true, 0, 1) => w,
        (true, 1, 0) => -w,
        _ => 0.0,
    });
    let exact = c64::new(-c / 2.0, (w * w - c * c / 4.0).sqrt());
    for (mat, e) in [(&a, exact), (&b, exact), (&s, c64::new(0.0, w))] {
        let (lam, _, cond) = check_eig(mat, 1e-13);
        assert!(cond.is_finite() && cond < 1e3, "cond {cond}");
        for l in &lam {
            let d = (l - e).norm().min((l - e.conj()).norm());
            assert!(d <= 1e-13 * e.norm(), "{l} vs {e}");
        }
    }
}

/// Defective input: either an error, no inverse, or a V whose condition exceeds the caller's
/// limit (1e8) by a wide margin — never a well-conditioned wrong answer.
fn check_defective(a: &Mat<f64>, min_cond: f64) {
    match real_eigen(a) {
        Err(_) => {}
        Ok((lam, v)) => {
            let res = residual(a, &lam, &v);
            assert!(res <= 1e-13, "residual {res}");
            match inverse(&v) {
                None => {}
                Some(w) => {
                    let cond = norm_c(&v) * norm_c(&w);
                    assert!(!cond.is_finite() || cond >= min_cond, "cond {cond:.3e}");
                }
            }
        }
    }
}

#[test]
fn defective_matrices_are_flagged() {
    // Jordan blocks J₂(1), J₂(0), J₃(−2) and a similarity transform of J₂(3) ⊕ [5].
    let j2 = Mat::<f64>::from_fn(2, 2, |i, j| if j == i || j == i + 1 { 1.0 } else { 0.0 });
    check_defective(&j2, 1e12);
    let n2 = Mat::<f64>::from_fn(2, 2, |i, j| if j == i + 1 { 1.0 } else { 0.0 });
    check_defective(&n2, 1e12);
    let j3 = Mat::<f64>::from_fn(3, 3, |i, j| {
        if i == j {
            -2.0
        } else if j == i + 1 {
            1.0
        } else {
            0.0
        }
    });
    check_defective(&j3, 1e8);
    let jb = Mat::<f64>::from_fn(3, 3, |i, j| match (i, j) {
        (0, 0) | (1, 1) => 3.0,
        (0, 1) => 1.0,
        (2, 2) => 5.0,
        _ => 0.0,
    });
    let t = random(3, 99);
    let t = Mat::<f64>::from_fn(3, 3, |i, j| t[(i, j)] + if i == j { 2.0 } else { 0.0 });
    let ti = {
        let tc = Mat::<c64>::from_fn(3, 3, |i, j| c64::new(t[(i, j)], 0.0));
        inverse(&tc).unwrap()
    };
    let a = Mat::<f64>::from_fn(3, 3, |i, j| {
        let mut s = 0.0;
        for k in 0..3 {
            for l in 0..3 {
                s += t[(i, k)] * jb[(k, l)] * ti[(l, j)].re;
            }
        }
        s
    });
    // Rounding splits the double eigenvalue by ~√ε: condition ~1/√ε.
    check_defective(&a, 1e6);
}

#[test]
fn zero_and_tiny_sizes() {
    // Zero matrix: λ = 0, V = I.
    for n in [1usize, 3, 8] {
        let z = Mat::<f64>::zeros(n, n);
        let (lam, v) = real_eigen(&z).unwrap();
        assert!(lam.iter().all(|l| *l == c64::new(0.0, 0.0)));
        assert_eq!(inv_err(&v, &inverse(&v).unwrap()), 0.0);
        let (s, u) = sym_eigen(&z).unwrap();
        assert!(s.iter().all(|x| *x == 0.0));
        assert!(ortho_err(&u) == 0.0);
    }
    // n = 0.
    let e = Mat::<f64>::zeros(0, 0);
    assert!(real_eigen(&e).unwrap().0.is_empty());
    assert!(sym_eigen(&e).unwrap().0.is_empty());
    // n = 1.
    let a = Mat::<f64>::from_fn(1, 1, |_, _| -7.5);
    let (lam, v) = real_eigen(&a).unwrap();
    assert_eq!(lam[0], c64::new(-7.5, 0.0));
    assert_eq!(v[(0, 0)].norm(), 1.0);
    // n = 2, complex: [[1, −4], [2, 3]]: λ = 2 ± i√7.
    let a = Mat::<f64>::from_fn(2, 2, |i, j| [[1.0, -4.0], [2.0, 3.0]][i][j]);
    let (lam, _, _) = check_eig(&a, 1e-15);
    assert!((lam[0] - c64::new(2.0, 7f64.sqrt())).norm() <= 4e-16 * 5.0);
    // n = 2, real: [[4, 1], [2, 3]]: λ = 2, 5.
    let a = Mat::<f64>::from_fn(2, 2, |i, j| [[4.0, 1.0], [2.0, 3.0]][i][j]);
    let (lam, _, _) = check_eig(&a, 1e-15);
    let l = sort_c(lam);
    assert!((l[0].re - 2.0).abs() <= 1e-15 * 5.0 && (l[1].re - 5.0).abs() <= 1e-15 * 5.0);
}

#[test]
fn non_finite_input_is_an_error() {
    let mut a = random(4, 7);
    a[(1, 2)] = f64::NAN;
    assert!(real_eigen(&a).is_err());
    assert!(sym_eigen(&a).is_err());
    a[(1, 2)] = f64::INFINITY;
    assert!(real_eigen(&a).is_err());
    let sing = Mat::<c64>::from_fn(3, 3, |i, _| c64::new(i as f64, 1.0));
    assert!(inverse(&sing).is_none());
}

// ---------------------------------------------------------------- sym_eigen

fn ortho_err(u: &Mat<f64>) -> f64 {
    let n = u.ncols();
    let mut s = 0.0f64;
    for j in 0..n {
        for i in 0..n {
            let p: f64 = (0..u.nrows()).map(|k| u[(k, i)] * u[(k, j)]).sum();
            s = s.max((p - if i == j { 1.0 } else { 0.0 }).abs());
        }
    }
    s
}

/// max |(A U − U diag(s))_ij| / ‖A‖_F.
fn sym_residual(a: &Mat<f64>, s: &[f64], u: &Mat<f64>) -> f64 {
    let n = a.nrows();
    let mut e = 0.0f64;
    for j in 0..n {
        for i in 0..n {
            let au: f64 = (0..n).map(|k| a[(i, k)] * u[(k, j)]).sum();
            e = e.max((au - u[(i, j)] * s[j]).abs());
        }
    }
    e / fro(a).max(f64::MIN_POSITIVE)
}

/// Checks `sym_eigen` (the API, size-dispatched) and the Jacobi kernel at the same order; returns
/// the Jacobi result (so closed-form checks below test the hand-written kernel at every n).
fn check_sym(a: &Mat<f64>) -> (Vec<f64>, Mat<f64>) {
    let api = sym_eigen(a).unwrap();
    let jac = sym_eigen_jacobi(a).unwrap().expect("Jacobi converges");
    for (s, u) in [&api, &jac] {
        assert!(s.windows(2).all(|w| w[0] <= w[1]), "not ascending");
        let o = ortho_err(u);
        assert!(o <= 1e-14, "orthonormality {o:.3e}");
        let r = sym_residual(a, s, u);
        assert!(r <= 1e-14, "residual {r:.3e}");
    }
    // Both solve the same problem: eigenvalues agree to round-off of ‖A‖.
    for (x, y) in api.0.iter().zip(&jac.0) {
        assert!((x - y).abs() <= 1e-14 * fro(a).max(f64::MIN_POSITIVE));
    }
    jac
}

#[test]
fn sym_two_by_two_closed_form() {
    // [[a, b], [b, d]]: λ = (a+d)/2 ∓ √(((a−d)/2)² + b²).
    for (a, b, d) in [
        (2.0, 1.0, -3.0),
        (1.0, 1e-9, 1.0),
        (5.0, 0.0, 5.0),
        (0.0, 4.0, 0.0),
    ] {
        let m = Mat::<f64>::from_fn(2, 2, |i, j| match (i, j) {
            (0, 0) => a,
            (1, 1) => d,
            _ => b,
        });
        let (s, _) = check_sym(&m);
        let r = (((a - d) / 2.0f64).powi(2) + b * b).sqrt();
        let e = [(a + d) / 2.0 - r, (a + d) / 2.0 + r];
        for (x, y) in s.iter().zip(e) {
            assert!((x - y).abs() <= 2.0 * f64::EPSILON * (a.abs() + b.abs() + d.abs()));
        }
    }
    // Graded: [[1, 1e-10], [1e-10, 1e-15]]: λ_small = (ad − b²)/λ_big to full relative accuracy.
    let (a, b, d) = (1.0f64, 1e-10f64, 1e-15f64);
    let m = Mat::<f64>::from_fn(2, 2, |i, j| match (i, j) {
        (0, 0) => a,
        (1, 1) => d,
        _ => b,
    });
    let (s, _) = sym_eigen(&m).unwrap();
    let big = (a + d) / 2.0 + (((a - d) / 2.0).powi(2) + b * b).sqrt();
    let small = (a * d - b * b) / big;
    assert!(
        (s[0] - small).abs() <= 4.0 * f64::EPSILON * small,
        "{} vs {small}",
        s[0]
    );
    assert!((s[1] - big).abs() <= 2.0 * f64::EPSILON * big);
}

#[test]
fn sym_path_laplacians_closed_form() {
    for n in [1usize, 2, 4, 7, 22, 40] {
        // Dirichlet path: tridiag(−1, 2, −1), λ_k = 2 − 2cos(kπ/(n+1)), k = 1..n.
        let a = Mat::<f64>::from_fn(n, n, |i, j| {
            if i == j {
                2.0
            } else if i.abs_diff(j) == 1 {
                -1.0
            } else {
                0.0
            }
        });
        let (s, _) = check_sym(&a);
        for (k, x) in s.iter().enumerate() {
            let e = 2.0 - 2.0 * ((k + 1) as f64 * std::f64::consts::PI / (n + 1) as f64).cos();
            assert!(
                (x - e).abs() <= 4.0 * f64::EPSILON * 4.0,
                "n={n} k={k}: {x} vs {e}"
            );
        }
        // Free chain (graph Laplacian of the path): λ_k = 2 − 2cos(kπ/n), k = 0..n−1; λ_0 = 0
        // is a rigid-body mode and must come out at round-off level.
        if n >= 2 {
            let l = Mat::<f64>::from_fn(n, n, |i, j| {
                if i == j {
                    if i == 0 || i == n - 1 {
                        1.0
                    } else {
                        2.0
                    }
                } else if i.abs_diff(j) == 1 {
                    -1.0
                } else {
                    0.0
                }
            });
            let (s, _) = check_sym(&l);
            assert!(
                s[0].abs() <= 1e-15 * fro(&l),
                "n={n}: zero mode {:.3e}",
                s[0]
            );
            for (k, x) in s.iter().enumerate() {
                let e = 2.0 - 2.0 * (k as f64 * std::f64::consts::PI / n as f64).cos();
                assert!(
                    (x - e).abs() <= 16.0 * f64::EPSILON,
                    "n={n} k={k}: {x} vs {e}"
                );
            }
        }
    }
}

/// Random orthogonal matrix: product of Householder reflectors.
fn random_orthogonal(n: usize, seed: u64) -> Mat<f64> {
    let mut r = Rng::new(seed);
    let mut q = Mat::<f64>::identity(n, n);
    for _ in 0..n {
        let v: Vec<f64> = (0..n).map(|_| r.next_sym()).collect();
        let vv: f64 = v.iter().map(|x| x * x).sum();
        let qv: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|k| q[(i, k)] * v[k]).sum())
            .collect();
        for i in 0..n {
            for j in 0..n {
                q[(i, j)] -= 2.0 * qv[i] * v[j] / vv;
            }
        }
    }
    q
}

#[test]
fn sym_repeated_and_zero_eigenvalues() {
    // A = Q diag(d) Qᵀ with exactly repeated and zero entries in d.
    for (n, seed) in [(6usize, 21u64), (22, 22)] {
        let d: Vec<f64> = (0..n)
            .map(|i| [0.0, 0.0, 0.0, 1.0, 1.0, 2.5][i % 6] * 1e6)
            .collect();
        let q = random_orthogonal(n, seed);
        let a = Mat::<f64>::from_fn(n, n, |i, j| {
            (0..n).map(|k| q[(i, k)] * d[k] * q[(j, k)]).sum()
        });
        let a = Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
        let (s, _) = check_sym(&a);
        let mut e = d.clone();
        e.sort_by(f64::total_cmp);
        let na = fro(&a);
        for (x, y) in s.iter().zip(&e) {
            assert!(
                (x - y).abs() <= 1e-15 * na * (n as f64).sqrt(),
                "{x} vs {y}"
            );
        }
    }
    // Stiffness of a free 4-DOF chain with a free mass (two rigid-body modes, λ = 0 twice).
    let k = Mat::<f64>::from_fn(4, 4, |i, j| match (i, j) {
        (0, 0) | (1, 1) => 2e7,
        (0, 1) | (1, 0) => -2e7,
        _ => 0.0,
    });
    let (s, _) = check_sym(&k);
    assert!(s[0].abs() <= 1e-15 * fro(&k) && s[1].abs() <= 1e-15 * fro(&k));
    assert!(s[2].abs() <= 1e-15 * fro(&k));
    assert!((s[3] - 4e7).abs() <= 4.0 * f64::EPSILON * 4e7);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn prop_real_eigen_residual(n in 1usize..12, seed in any::<u64>(), scale_exp in -6i32..7) {
        let a = random(n, seed);
        let a = Mat::<f64>::from_fn(n, n, |i, j| a[(i, j)] * 10f64.powi(scale_exp));
        let (lam, v) = real_eigen(&a).unwrap();
        let res = residual(&a, &lam, &v);
        prop_assert!(res <= 1e-13, "residual {res:.3e}");
        check_structure(&lam, &v);
    }

    #[test]
    fn prop_sym_eigen(n in 1usize..12, seed in any::<u64>()) {
        let a = random(n, seed);
        let a = Mat::<f64>::from_fn(n, n, |i, j| a[(i, j)] + a[(j, i)]);
        let (s, u) = sym_eigen(&a).unwrap();
        prop_assert!(ortho_err(&u) <= 1e-14);
        prop_assert!(sym_residual(&a, &s, &u) <= 1e-14);
        prop_assert!(s.windows(2).all(|w| w[0] <= w[1]));
    }
}
