//! Dense generalised symmetric eigen-solver for `K φ = λ M φ` (small and medium models).
//!
//! Hand-written because faer 0.24 has no generalised *symmetric* eigen-solver (its
//! `generalized_eigen` is a general QZ, complex and ~10x slower); the symmetric eigen-decomposition
//! itself is faer's, called sequentially so that the result does not depend on the thread count
//! (the products `K Φ`, `M Φ`, `Φᵀ M Φ` are parallel over fixed row chunks, `modal::kernels`). Two reductions to a standard symmetric problem:
//!
//! * **Diagonal M** (lumped masses): `C = M^(-1/2) K M^(-1/2)`, a diagonal similarity that loses
//!   nothing; `φ = M^(-1/2) y`.
//! * **Any other M** (consistent mass of shells and frames): the shift-invert (spectral)
//!   transformation (Ericsson & Ruhe, *Math. Comp.* 35 (1980) 1251-1268; Bathe, *Finite Element
//!   Procedures*, §11.2), applied to the equilibrated pencil `(D K D, D M D)`,
//!   `D = diag(K + σM)^(-1/2)`:
//!
//! ```text
//! K̂ + σ M̂ = L Lᵀ,   C = L⁻¹ M̂ L⁻ᵀ,   C y = μ y,   λ = 1/μ - σ,   φ = D L⁻ᵀ y / sqrt(μ)
//! ```
//!
//! so that `Φᵀ M Φ = I`.
//!
//! Why not the Cholesky factor of M for consistent masses: Mindlin shells have a tiny rotary
//! inertia (`ρ t³/12`) next to a large transverse-shear stiffness, so `‖L_M⁻¹ K L_M⁻ᵀ‖` reaches
//! 1e13-1e16 and a symmetric eigen-solver's absolute error `ε ‖C‖` swamps the low modes
//! (a 16×16 simply supported plate, a/h = 100, gave an eigenvalue of -5e7 and residuals of 0.1).
//! With shift-invert the *low* modes carry the largest μ and are computed to relative accuracy.
//!
//! Accuracy of the shift-invert route: rounding perturbs μ by about `ε κ/σ` (κ the condition
//! number of the equilibrated `K + σM`), i.e. mode i by a relative `ε κ (λ_i + σ)²/(σ λ_i)`:
//! the modes near σ are the most accurate; the top of the spectrum (discretisation noise of a
//! fine shell mesh, up to 1e15 rad²/s²) may have M-orthonormality and residual errors of 1e-3 and
//! more. σ therefore favours the low, physical modes: `σ = 1e-4 s̃` by default, s̃ the mass-weighted
//! median of `K_ii / M_ii` ([`default_shift`]; positive, so `K + σM` is positive definite for free
//! structures). `orthonormality_error` and
//! `max_residual` report the *worst* mode; [`mode_residuals`] gives the residual of each mode, so
//! a caller can report the accuracy of the modes it actually keeps.
//!
//! Relative residual of mode i: `‖K φ - λ M φ‖ / (‖K φ‖ + (|λ| + σ) ‖M φ‖)` (σ = 0 for the
//! diagonal route; the σ term keeps it meaningful for λ = 0). Rigid-body modes are those whose
//! Rayleigh quotient cannot be told from zero in double precision (`crate::modal::check`, no
//! threshold on the largest eigenvalue or on `max K_ii/M_ii`); they are reported as ω = 0 exactly.
//! Eigenvalues of the shift-inverted problem below its round-off (`n ε μ_max`) belong to modes so
//! far above σ that they are not resolved: they are left out of the result (at most the lowest
//! modes asked for must be resolved, else an error says how many are).

use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{Mat, MatRef, Par};

use super::kernels;
use crate::{Error, Result};

/// Mass-normalised modes of a dense symmetric pencil (K, M).
#[derive(Debug, Clone)]
pub struct DenseModes {
    /// Eigenvalues λ = ω² (rad²/s²), ascending, as computed (rigid-body ones may be tiny negatives).
    pub eigenvalues: Vec<f64>,
    /// Natural circular frequencies ω (rad/s), ascending; rigid-body modes exactly 0.
    pub omega_rad_per_s: Vec<f64>,
    /// Mass-normalised mode shapes, one column per mode (Φᵀ M Φ = I).
    pub shapes: Mat<f64>,
    /// max |Φᵀ M Φ - I| (worst pair of modes).
    pub orthonormality_error: f64,
    /// Largest relative residual over all modes (see the module docs for the definition).
    pub max_residual: f64,
    /// Number of modes reported with ω = 0.
    pub rigid_body_modes: usize,
}

/// Default relative shift `σ / s̃` of the shift-invert route (s̃ the mass-weighted median of
/// `K_ii / M_ii`, see [`default_shift`]).
pub const DEFAULT_RELATIVE_SHIFT: f64 = 1e-4;

/// The default shift `σ = 1e-4 min(s̃, tr K / tr M)`, `s̃` the **mass-weighted median** of `K_ii / M_ii` over the
/// DOFs (the ratio below which DOFs holding half of `tr M` lie). It is the scale of the element
/// stiffness per unit mass of the bulk of the structure. A mean (`tr K / tr M`, used before) is
/// dominated by a few very stiff springs: springs of 1e14 N/m on a plate's edges put σ at
/// 1e9 rad²/s², four decades above the plate's first mode, whose eigenvalues then drowned in
/// round-off. The mean stays a candidate: the smaller scale is the closer to the low modes.
/// 1 when neither is positive.
pub fn default_shift(k: MatRef<'_, f64>, m: MatRef<'_, f64>, tr_k: f64, tr_m: f64) -> f64 {
    let n = k.nrows();
    let mut r: Vec<(f64, f64)> = (0..n)
        .filter(|&i| m[(i, i)] > 0.0)
        .map(|i| (k[(i, i)] / m[(i, i)], m[(i, i)]))
        .collect();
    r.sort_by(|a, b| a.0.total_cmp(&b.0));
    let half = 0.5 * r.iter().map(|x| x.1).sum::<f64>();
    let mut acc = 0.0;
    let mut med = 0.0;
    for (ratio, w) in &r {
        acc += w;
        if acc >= half {
            med = *ratio;
            break;
        }
    }
    // The smaller of the median and the mean scale: the mean is the smaller one when the bulk's
    // K_ii/M_ii is spread by light rotational DOFs, and it is the shift this solver had before.
    [
        DEFAULT_RELATIVE_SHIFT * med,
        DEFAULT_RELATIVE_SHIFT * tr_k / tr_m,
    ]
    .into_iter()
    .filter(|s| s.is_finite() && *s > 0.0)
    .reduce(f64::min)
    .unwrap_or(1.0)
}

/// ω per mode (exactly 0 for rigid-body modes) and the number of rigid-body modes, decided by
/// [`crate::modal::check`]'s rule (zero within the Rayleigh quotient's round-off and the
/// vector's residual). Modes are ascending,
/// so the rigid ones come first; the test stops at the first elastic mode.
fn classify(
    k: MatRef<'_, f64>,
    m: MatRef<'_, f64>,
    eigenvalues: &[f64],
    shapes: MatRef<'_, f64>,
) -> Result<(Vec<f64>, usize)> {
    let n = k.nrows();
    let mut omega = Vec::with_capacity(eigenvalues.len());
    let mut rigid = 0;
    let mut elastic = false;
    for (j, &lam) in eigenvalues.iter().enumerate() {
        if !elastic {
            let phi: Vec<f64> = (0..n).map(|r| shapes[(r, j)]).collect();
            let (mut kp, mut akp, mut mp) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            for c in 0..n {
                let pc = phi[c];
                if pc == 0.0 {
                    continue;
                }
                for r in 0..n {
                    kp[r] += k[(r, c)] * pc;
                    akp[r] += k[(r, c)].abs() * pc.abs();
                    mp[r] += m[(r, c)] * pc;
                }
            }
            let mdiag: Vec<f64> = (0..n).map(|i| m[(i, i)]).collect();
            let (lam_r, floor, u) = super::check::rigid_measures(&phi, &kp, &akp, &mp, &mdiag);
            if super::check::is_rigid(lam_r, floor, u) {
                rigid += 1;
                omega.push(0.0);
                continue;
            }
            if lam_r < 0.0 || lam < 0.0 {
                return Err(negative_error(j, lam_r.min(lam)));
            }
            elastic = true;
        }
        if lam < 0.0 {
            return Err(negative_error(j, lam));
        }
        omega.push(lam.sqrt());
    }
    Ok((omega, rigid))
}

fn check_input(k: MatRef<'_, f64>, m: MatRef<'_, f64>) -> Result<()> {
    let n = k.nrows();
    if k.ncols() != n || m.nrows() != n || m.ncols() != n {
        return Err(Error::invalid(
            "stiffness/mass matrices",
            format!(
                "need square matrices of one size (K {}x{}, M {}x{})",
                k.nrows(),
                k.ncols(),
                m.nrows(),
                m.ncols()
            ),
        ));
    }
    if n == 0 {
        return Err(Error::invalid(
            "stiffness/mass matrices",
            "the model has no degrees of freedom",
        ));
    }
    let bad = |a: MatRef<'_, f64>| {
        a.col_iter()
            .flat_map(|c| c.iter().copied())
            .any(|x| !x.is_finite())
    };
    if bad(k) || bad(m) {
        return Err(Error::invalid(
            "stiffness/mass matrices",
            "contain a non-finite entry",
        ));
    }
    for i in 0..n {
        if m[(i, i)] <= 0.0 {
            return Err(Error::numerical(
                "dense eigen-solver",
                format!("the mass matrix is not positive definite: diagonal entry {i} is {:.3e} (a degree of freedom without mass?)", m[(i, i)]),
            ));
        }
        if k[(i, i)] < 0.0 {
            return Err(Error::numerical(
                "dense eigen-solver",
                format!("the stiffness matrix is not positive semi-definite: diagonal entry {i} is {:.3e}", k[(i, i)]),
            ));
        }
    }
    Ok(())
}

fn is_diagonal(m: MatRef<'_, f64>) -> bool {
    let n = m.nrows();
    (0..n).all(|j| (0..n).all(|i| i == j || m[(i, j)] == 0.0))
}

/// Solves `K φ = λ M φ` for all modes. `K` symmetric positive semi-definite, `M` symmetric
/// positive definite. Diagonal M: exact diagonal scaling; otherwise the shift-invert route with
/// the default shift (see the module docs).
pub fn solve(k: MatRef<'_, f64>, m: MatRef<'_, f64>) -> Result<DenseModes> {
    check_input(k, m)?;
    if is_diagonal(m) {
        solve_diagonal_mass(k, m)
    } else {
        solve_shift_invert(k, m, None)
    }
}

fn symmetrise(c: &mut Mat<f64>) {
    let n = c.nrows();
    for j in 0..n {
        for i in 0..j {
            let s = 0.5 * (c[(i, j)] + c[(j, i)]);
            c[(i, j)] = s;
            c[(j, i)] = s;
        }
    }
}

fn negative_error(i: usize, lam: f64) -> Error {
    Error::numerical(
        "dense eigen-solver",
        format!("eigenvalue {} = {lam:.3e} is negative beyond round-off: the stiffness matrix is not positive semi-definite", i + 1),
    )
}

/// `C = M^(-1/2) K M^(-1/2)` for a diagonal M.
fn solve_diagonal_mass(k: MatRef<'_, f64>, m: MatRef<'_, f64>) -> Result<DenseModes> {
    let n = k.nrows();
    let s: Vec<f64> = (0..n).map(|i| 1.0 / m[(i, i)].sqrt()).collect();
    let mut c = Mat::<f64>::from_fn(n, n, |i, j| s[i] * k[(i, j)] * s[j]);
    symmetrise(&mut c);
    let (eigenvalues, u) = kernels::self_adjoint_eigen(c.as_ref(), "dense eigen-solver")?;
    let shapes = Mat::<f64>::from_fn(n, n, |i, j| s[i] * u[(i, j)]);
    let (omega, rigid) = classify(k, m, &eigenvalues, shapes.as_ref())?;
    Ok(finish(k, m, eigenvalues, omega, shapes, rigid, 0.0))
}

/// Solves `K φ = λ M φ` for all modes by the shift-invert reduction; `shift` = σ (rad²/s², > 0)
/// or `None` for the default [`default_shift`]. Returns mass-normalised modes in ascending order.
pub fn solve_shift_invert(
    k: MatRef<'_, f64>,
    m: MatRef<'_, f64>,
    shift: Option<f64>,
) -> Result<DenseModes> {
    solve_shift_invert_lowest(k, m, shift, None)
}

/// [`solve_shift_invert`] for the lowest `lowest` modes (`None`: all). Modes above them whose
/// eigenvalues double precision does not resolve (next to a very stiff spring) are left out of
/// the result instead of failing; the result holds every resolved mode, at least `lowest`.
pub fn solve_shift_invert_lowest(
    k: MatRef<'_, f64>,
    m: MatRef<'_, f64>,
    shift: Option<f64>,
    lowest: Option<usize>,
) -> Result<DenseModes> {
    check_input(k, m)?;
    let n = k.nrows();
    let (mut tr_k, mut tr_m) = (0.0, 0.0);
    for i in 0..n {
        tr_k += k[(i, i)];
        tr_m += m[(i, i)];
    }
    let sigma = match shift {
        Some(s) if s.is_finite() && s > 0.0 => s,
        Some(s) => {
            return Err(Error::invalid(
                "eigen-solver shift",
                format!("must be finite and > 0 rad^2/s^2 (got {s})"),
            ))
        }
        None => default_shift(k, m, tr_k, tr_m),
    };
    // Equilibrate: D = diag(K + σM)^(-1/2), Â = D (K + σM) D has a unit diagonal; M̂ = D M D.
    let d: Vec<f64> = (0..n)
        .map(|i| 1.0 / (k[(i, i)] + sigma * m[(i, i)]).sqrt())
        .collect();
    let a = Mat::<f64>::from_fn(n, n, |i, j| d[i] * (k[(i, j)] + sigma * m[(i, j)]) * d[j]);
    let l = kernels::llt_lower(a.as_ref()).ok_or_else(|| {
        Error::numerical(
            "dense eigen-solver",
            "K + σM is not positive definite: the mass matrix is not positive definite or the stiffness is not positive semi-definite",
        )
    })?;
    let l = l.as_ref();
    let mut x = Mat::<f64>::from_fn(n, n, |i, j| d[i] * m[(i, j)] * d[j]);
    solve_lower_triangular_in_place(l, x.as_mut(), Par::Seq);
    let mut c = x.transpose().to_owned();
    solve_lower_triangular_in_place(l, c.as_mut(), Par::Seq);
    symmetrise(&mut c);
    let (mu_all, u) = kernels::self_adjoint_eigen(c.as_ref(), "dense eigen-solver")?;
    let mu_max = mu_all[n - 1];
    // μ below the round-off of the eigen-decomposition of C (≈ n ε μ_max) cannot be told from
    // zero: the top of the spectrum there (λ = 1/μ − σ beyond what double precision resolves
    // next to the stiffest entry) is not computed. A μ negative beyond that round-off means M
    // is not positive definite.
    if mu_all.iter().any(|mu| mu.is_nan()) {
        return Err(Error::numerical(
            "dense eigen-solver",
            "the shift-inverted problem has a NaN eigenvalue",
        ));
    }
    let mut mu_floor = n as f64 * f64::EPSILON * mu_max.abs();
    let mu_min = mu_all[0];
    if mu_min < -mu_floor {
        // Negative μ: M is indefinite, or forming C lost more than n ε μ_max (a very stiff
        // spring next to light masses). A Cholesky factorisation of the equilibrated M decides.
        let mh = Mat::<f64>::from_fn(n, n, |i, j| m[(i, j)] / (m[(i, i)] * m[(j, j)]).sqrt());
        if kernels::llt_lower(mh.as_ref()).is_none() {
            return Err(Error::numerical(
                "dense eigen-solver",
                format!("the mass matrix is not positive definite (its Cholesky factorisation fails; the shift-inverted problem has the eigenvalue {mu_min:e})"),
            ));
        }
        // M is positive definite, so every exact μ is > 0: |μ_min| measures the round-off.
        mu_floor = mu_floor.max(10.0 * mu_min.abs());
    }
    let resolved = (0..n).rev().take_while(|&i| mu_all[i] > mu_floor).count();
    let wanted = lowest.unwrap_or(n).min(n);
    if resolved < wanted {
        return Err(Error::numerical(
            "dense eigen-solver",
            format!(
                "only the lowest {resolved} of the {wanted} modes asked for are resolved in double precision (the others lie so far above the shift σ = {sigma:.3e} rad²/s², near the stiffest spring or element, that their eigenvalues are round-off): ask for at most {resolved} modes"
            ),
        ));
    }
    // Ascending λ = descending μ; only the resolved ones.
    let n_out = resolved;
    let mut eigenvalues = Vec::with_capacity(n_out);
    let mut y = Mat::<f64>::zeros(n, n_out);
    for col in 0..n_out {
        let i = n - 1 - col;
        let mu = mu_all[i];
        eigenvalues.push(1.0 / mu - sigma);
        let s = 1.0 / mu.sqrt();
        for r in 0..n {
            y[(r, col)] = u[(r, i)] * s;
        }
    }
    solve_upper_triangular_in_place(l.transpose(), y.as_mut(), Par::Seq);
    for j in 0..n_out {
        for i in 0..n {
            y[(i, j)] *= d[i];
        }
    }
    let (omega, rigid) = classify(k, m, &eigenvalues, y.as_ref())?;
    Ok(finish(k, m, eigenvalues, omega, y, rigid, sigma))
}

fn finish(
    k: MatRef<'_, f64>,
    m: MatRef<'_, f64>,
    eigenvalues: Vec<f64>,
    omega_rad_per_s: Vec<f64>,
    shapes: Mat<f64>,
    rigid_body_modes: usize,
    sigma: f64,
) -> DenseModes {
    let n = shapes.ncols();
    let mm = kernels::mul_rows(m, shapes.as_ref());
    let gram = kernels::mul_tn(shapes.as_ref(), mm.as_ref());
    let mut orth = 0.0_f64;
    for j in 0..n {
        for i in 0..n {
            let target = if i == j { 1.0 } else { 0.0 };
            orth = orth.max((gram[(i, j)] - target).abs());
        }
    }
    let km = kernels::mul_rows(k, shapes.as_ref());
    let max_residual = (0..n)
        .map(|j| residual(km.col(j).iter(), mm.col(j).iter(), eigenvalues[j], sigma))
        .fold(0.0_f64, f64::max);
    DenseModes {
        eigenvalues,
        omega_rad_per_s,
        shapes,
        orthonormality_error: orth,
        max_residual,
        rigid_body_modes,
    }
}

fn residual<'a>(
    kphi: impl Iterator<Item = &'a f64>,
    mphi: impl Iterator<Item = &'a f64>,
    lam: f64,
    sigma: f64,
) -> f64 {
    let (mut r2, mut kn, mut mn) = (0.0, 0.0, 0.0);
    for (&a, &b) in kphi.zip(mphi) {
        let r = a - lam * b;
        r2 += r * r;
        kn += a * a;
        mn += b * b;
    }
    let denom = kn.sqrt() + (lam.abs() + sigma) * mn.sqrt();
    if denom > 0.0 {
        r2.sqrt() / denom
    } else {
        0.0
    }
}

/// Relative residuals `‖K φ - λ M φ‖ / (‖K φ‖ + (|λ| + σ) ‖M φ‖)` of the modes `which`
/// (0-based), with σ = `1e-4 tr K / tr M` (a fixed scale so that rigid-body modes get a
/// meaningful value). Use it to report the accuracy of the modes a model keeps.
pub fn mode_residuals(
    k: MatRef<'_, f64>,
    m: MatRef<'_, f64>,
    modes: &DenseModes,
    which: &[usize],
) -> Result<Vec<f64>> {
    let n = k.nrows();
    if modes.shapes.nrows() != n || m.nrows() != n {
        return Err(Error::invalid(
            "modes",
            format!(
                "mode shapes have {} rows but the matrices are {n}x{n}",
                modes.shapes.nrows()
            ),
        ));
    }
    let (mut tr_k, mut tr_m) = (0.0, 0.0);
    for i in 0..n {
        tr_k += k[(i, i)];
        tr_m += m[(i, i)];
    }
    let sigma = DEFAULT_RELATIVE_SHIFT * tr_k / tr_m.max(f64::MIN_POSITIVE);
    let mut out = Vec::with_capacity(which.len());
    for &j in which {
        if j >= modes.shapes.ncols() {
            return Err(Error::invalid(
                "modes",
                format!("mode index {j} out of range (0..{})", modes.shapes.ncols()),
            ));
        }
        let phi = modes.shapes.get(.., j..j + 1);
        let kphi = kernels::mul(k, phi);
        let mphi = kernels::mul(m, phi);
        out.push(residual(
            kphi.col(0).iter(),
            mphi.col(0).iter(),
            modes.eigenvalues[j],
            sigma,
        ));
    }
    Ok(out)
}

/// Relative tolerance of [`orient_modes`]: entries within it of the largest count as tied.
const ORIENT_TIE: f64 = 1e-6;

/// Sign convention of computed modes (a mode `φ` and `−φ` are the same mode; the solvers return
/// either): each column of `shapes` is negated when needed so that its entry of largest
/// magnitude over the reduced DOFs is positive, taking the first in DOF order among the entries
/// with `|φ_j| ≥ (1 − 10⁻⁶) max_k |φ_k|`, so that round-off between the dense and Lanczos
/// solutions (or thread counts) cannot pick another entry of a symmetric pair. Signed outputs
/// (ψ in `modes.csv`, shapes in `modes.vtu`/`modes.uff`) then do not depend on the solver. Within
/// a degenerate (repeated) eigenvalue the basis itself is arbitrary; no sign rule fixes that.
/// Applied to the FE solutions (`model::fem::solve_modes`) and the lumped models' modes.
pub fn orient_modes(shapes: &mut Mat<f64>) {
    for i in 0..shapes.ncols() {
        let max = (0..shapes.nrows()).fold(0.0_f64, |a, j| a.max(shapes[(j, i)].abs()));
        let pick = (0..shapes.nrows()).find(|&j| shapes[(j, i)].abs() >= (1.0 - ORIENT_TIE) * max);
        if let Some(j) = pick {
            if shapes[(j, i)] < 0.0 {
                for r in 0..shapes.nrows() {
                    shapes[(r, i)] = -shapes[(r, i)];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sign rule: largest entry positive; a pair tied within 1e-6 goes by the first entry;
    /// a zero column is left alone; applying it twice changes nothing.
    #[test]
    fn orient_modes_makes_the_largest_entry_positive() {
        let mut s = Mat::from_fn(3, 3, |r, c| match (r, c) {
            (0, 0) => 0.1,
            (1, 0) => -0.5,
            (2, 0) => 0.2,
            (0, 1) => -0.7,
            (1, 1) => 0.7 * (1.0 + 1e-9),
            (2, 1) => 0.1,
            _ => 0.0,
        });
        orient_modes(&mut s);
        assert_eq!([s[(0, 0)], s[(1, 0)], s[(2, 0)]], [-0.1, 0.5, -0.2]);
        assert_eq!(
            [s[(0, 1)], s[(1, 1)], s[(2, 1)]],
            [0.7, -0.7 * (1.0 + 1e-9), -0.1]
        );
        assert_eq!([s[(0, 2)], s[(1, 2)], s[(2, 2)]], [0.0; 3]);
        let before = s.clone();
        orient_modes(&mut s);
        assert_eq!(s, before);
    }

    /// Fixed-free chain of n equal masses m and springs k:
    /// ω_j = 2 sqrt(k/m) sin((2j-1)π / (2(2n+1))).
    #[test]
    fn fixed_free_chain_matches_closed_form() {
        let n = 12;
        let (kk, mm) = (3.0e5, 2.5);
        let mut k = Mat::<f64>::zeros(n, n);
        let mut m = Mat::<f64>::zeros(n, n);
        for i in 0..n {
            m[(i, i)] = mm;
            k[(i, i)] += kk; // spring below node i (node 0 to ground)
            if i + 1 < n {
                k[(i, i)] += kk;
                k[(i + 1, i)] -= kk;
                k[(i, i + 1)] -= kk;
            }
        }
        let modes = solve(k.as_ref(), m.as_ref()).unwrap();
        for j in 1..=n {
            let exact = 2.0
                * (kk / mm).sqrt()
                * (((2 * j - 1) as f64) * std::f64::consts::PI / (2.0 * (2 * n + 1) as f64)).sin();
            let got = modes.omega_rad_per_s[j - 1];
            assert!(
                (got - exact).abs() <= 1e-10 * exact,
                "mode {j}: {got} vs {exact}"
            );
        }
        assert!(
            modes.orthonormality_error < 1e-12,
            "{}",
            modes.orthonormality_error
        );
        assert!(modes.max_residual < 1e-12, "{}", modes.max_residual);
        assert_eq!(modes.rigid_body_modes, 0);
    }

    /// A free chain has one rigid-body mode; the others are ω_j = 2 sqrt(k/m) sin(jπ/(2n)).
    #[test]
    fn free_chain_has_one_rigid_mode() {
        let n = 6;
        let (kk, mm) = (1.0e4, 1.0);
        let mut k = Mat::<f64>::zeros(n, n);
        let mut m = Mat::<f64>::zeros(n, n);
        for i in 0..n {
            m[(i, i)] = mm;
            if i + 1 < n {
                k[(i, i)] += kk;
                k[(i + 1, i + 1)] += kk;
                k[(i + 1, i)] -= kk;
                k[(i, i + 1)] -= kk;
            }
        }
        let modes = solve(k.as_ref(), m.as_ref()).unwrap();
        assert_eq!(modes.rigid_body_modes, 1);
        assert_eq!(modes.omega_rad_per_s[0], 0.0);
        for j in 1..n {
            let exact = 2.0
                * (kk / mm).sqrt()
                * ((j as f64) * std::f64::consts::PI / (2.0 * n as f64)).sin();
            assert!((modes.omega_rad_per_s[j] - exact).abs() < 1e-10 * exact);
        }
    }

    #[test]
    fn massless_dof_is_an_error() {
        let k = Mat::<f64>::identity(2, 2);
        let mut m = Mat::<f64>::identity(2, 2);
        m[(1, 1)] = 0.0;
        let err = solve(k.as_ref(), m.as_ref()).unwrap_err().to_string();
        assert!(err.contains("not positive definite"), "{err}");
    }

    /// A non-diagonal mass matrix with a positive diagonal but a negative eigenvalue
    /// (M = [1 2; 2 1], eigenvalues 3 and -1) is rejected by the shift-invert route: K + σM is
    /// still positive definite for this K, but the shift-inverted problem has a negative μ.
    #[test]
    fn indefinite_consistent_mass_is_an_error() {
        let k = Mat::<f64>::from_fn(2, 2, |i, j| if i == j { 1e3 } else { 0.0 });
        let m = Mat::<f64>::from_fn(2, 2, |i, j| if i == j { 1.0 } else { 2.0 });
        let err = solve(k.as_ref(), m.as_ref()).unwrap_err().to_string();
        assert!(
            err.contains("mass matrix is not positive definite"),
            "{err}"
        );
        // So is one that makes K + σM indefinite (σ = 1e-4 tr K/tr M is large for a light M).
        let m = Mat::<f64>::from_fn(2, 2, |i, j| if i == j { 1e-3 } else { -1.0 });
        let err = solve(k.as_ref(), m.as_ref()).unwrap_err().to_string();
        assert!(err.contains("not positive definite"), "{err}");
    }

    /// A badly conditioned diagonal M (masses 1 kg and 1e-12 kg on one spring to the ground
    /// each, k = 1): the diagonal route is a similarity and resolves both modes, ω² = 1 and 1e12,
    /// to round-off (the spread 1e12 costs the *coupled* case accuracy: see
    /// `modal::conditioning`).
    #[test]
    fn badly_scaled_diagonal_mass_is_resolved_exactly_when_uncoupled() {
        let k = Mat::<f64>::identity(2, 2);
        let m = Mat::<f64>::from_fn(2, 2, |i, j| match (i, j) {
            (0, 0) => 1.0,
            (1, 1) => 1e-12,
            _ => 0.0,
        });
        let modes = solve(k.as_ref(), m.as_ref()).unwrap();
        assert!((modes.eigenvalues[0] - 1.0).abs() <= 1e-15);
        assert!((modes.eigenvalues[1] - 1e12).abs() <= 1e-15 * 1e12);
        assert!(modes.orthonormality_error < 1e-15);
    }

    /// One consistent-mass bar element, free-free: K = k[1 -1; -1 1], M = m/6 [2 1; 1 2]
    /// (non-diagonal, so the shift-invert route): λ = 0 and λ = 12 k/m exactly.
    #[test]
    fn consistent_mass_bar_uses_shift_invert() {
        let (kk, mm) = (2.0e6, 3.0);
        let k = Mat::<f64>::from_fn(2, 2, |i, j| if i == j { kk } else { -kk });
        let m = Mat::<f64>::from_fn(2, 2, |i, j| if i == j { mm / 3.0 } else { mm / 6.0 });
        let modes = solve(k.as_ref(), m.as_ref()).unwrap();
        assert_eq!(modes.rigid_body_modes, 1);
        let exact = (12.0 * kk / mm).sqrt();
        assert!((modes.omega_rad_per_s[1] - exact).abs() <= 1e-12 * exact);
        let r = mode_residuals(k.as_ref(), m.as_ref(), &modes, &[0, 1]).unwrap();
        // Shift-invert bound ε κ (λ + σ)²/(σ λ) with σ = 3e-4 k/m, κ ≈ 4e4: ~4e-7; observed ~1e-12.
        assert!(r.iter().all(|&x| x < 1e-10), "{r:?}");
        assert!(modes.orthonormality_error < 1e-10);
    }
}
