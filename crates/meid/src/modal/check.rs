//! The check every computed set of modes passes before anything uses it: rigid-body modes told
//! from elastic ones by the problem itself, residuals and M-orthonormality against stated bounds.
//!
//! # Rigid-body modes
//! A mode is a rigid-body (zero-frequency) mode when its eigenvalue cannot be told from zero in
//! double precision. Computing `φᵀ K φ` in floating point makes an error of at most about
//! `ε |φ|ᵀ |K| |φ|` (ε machine precision, `|·|` entrywise absolute values: Higham, *Accuracy and
//! Stability of Numerical Algorithms*, 2nd ed., §3.5), so the Rayleigh quotient
//!
//! ```text
//! λ_R = φᵀ K φ / φᵀ M φ     has the round-off floor     λ_ε = ε |φ|ᵀ |K| |φ| / φᵀ M φ
//! ```
//!
//! and the computed vector carries an error that moves λ_R by up to about its residual
//! `u = (Σ_j r_j² / M_jj)^½`, `r = K φ − λ_R M φ` (for a symmetric pencil an exact eigenvalue lies
//! within `‖r‖_{M⁻¹}` of λ_R for an M-normalised φ; the mass diagonal stands in for M). The mode
//! is rigid when `|λ_R| ≤ RIGID_FLOOR_FACTOR · λ_ε + u`: zero is within its uncertainty. The
//! floor is the mode's own:
//! a very stiff spring enters it only through the motion of the mode at the spring (`k φ_s²`),
//! which is what the spring physically contributes. No threshold on `max K_ii / M_ii` (a single
//! stiff entry inflates that and made a 49 Hz plate mode a "rigid-body mode"). A Rayleigh
//! quotient below `−RIGID_FLOOR_FACTOR · λ_ε` means K is not positive semi-definite: an error.
//!
//! # Bounds (a failed bound is an error, never a field of a result)
//! * Elastic mode i: `‖D (K φ_i − λ_i M φ_i)‖ / ‖D K φ_i‖ ≤ RESIDUAL_BOUND` with the diagonal
//!   equilibration `D = diag(K_jj + λ_i M_jj)^(-1/2)`: the relative residual of the equivalent
//!   pencil `(D K D, D M D)` (same eigenvalues, vector `D⁻¹ φ`), the one the solvers factor. Without
//!   D a spring of 1e16 N/m makes the residual at least `k ε max|φ|` at its DOF (the absolute
//!   rounding of the tiny displacement there, which changes λ by only `k (ε max|φ|)²`): a
//!   49.2424 Hz plate mode correct to all printed digits had `‖r‖/‖Kφ‖` = 8e-5, and 1e-9
//!   equilibrated. A wrong mode (modes 5/6 of the same plate at 252.27 instead of 251.50 Hz) has
//!   a residual in every DOF and fails either way.
//!   The residual cannot be computed more accurately than its own rounding: `Kφ` and `λMφ` are
//!   sums whose terms are up to `|K||φ|` and `|λ||M||φ|` (entrywise), so the computed residual
//!   carries an error of order `ε ‖D (|K||φ| + |λ||M||φ|)‖ / ‖D K φ‖` (Higham, §3.5), the
//!   mode's *residual floor*. A low mode of a fine, stiff mesh on soft supports reaches it: the
//!   paper's soft-base machine at 200,000 DOF has its 2.74 Hz mode at a residual of 4.1e-6 with a
//!   floor of 2.1e-6 (the eigenvalue agrees with its Rayleigh quotient to 2.4e-8). Such a mode
//!   is correct to working precision and passes when its residual is within
//!   `RESIDUAL_FLOOR_FACTOR` floors and its eigenvalue agrees with its Rayleigh quotient
//!   `λ_R` within `RESIDUAL_BOUND · λ + RIGID_FLOOR_FACTOR · λ_ε` (so a wrong eigenvalue
//!   beside a right vector still fails). A contaminated vector has a residual of the size of
//!   its contamination times the spectral gap, far above the floor.
//! * Rigid-body mode i: `‖K φ_i‖ / ‖ |K| |φ_i| ‖ ≤ RESIDUAL_BOUND` (K φ = 0 up to the
//!   cancellation of its terms; `‖K φ‖` alone has no scale).
//! * `max |Φᵀ M Φ − I| ≤ ORTHONORMALITY_BOUND` over the modes checked.
//!
//! For a symmetric pencil the residual bounds the eigenvalue error: some exact eigenvalue lies
//! within `‖r‖_{M⁻¹}` of λ for an M-normalised φ (Parlett, *The Symmetric Eigenvalue Problem*,
//! §15.2); for an isolated mode the Rayleigh quotient's error is of the order of the squared
//! residual, so the bound [`RESIDUAL_BOUND`] keeps the frequencies' error far below what meid
//! prints.

use faer::sparse::SparseColMatRef;
use faer::MatRef;

use crate::{Error, Result};

/// Bound on the relative residual of every checked mode (see the module docs).
pub const RESIDUAL_BOUND: f64 = 1e-6;
/// An elastic mode whose residual exceeds [`RESIDUAL_BOUND`] still passes when the residual is
/// within this many times its own round-off floor (module docs).
pub const RESIDUAL_FLOOR_FACTOR: f64 = 100.0;
/// Bound on `max |Φᵀ M Φ − I|` over the checked modes.
pub const ORTHONORMALITY_BOUND: f64 = 1e-6;
/// A mode is rigid when `|λ_R| ≤ RIGID_FLOOR_FACTOR · ε |φ|ᵀ|K||φ| / φᵀMφ`.
pub const RIGID_FLOOR_FACTOR: f64 = 100.0;

/// What the check found, per checked mode.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeCheck {
    /// ω (rad/s): exactly 0 for rigid-body modes, `sqrt(λ)` otherwise.
    pub omega_rad_per_s: Vec<f64>,
    /// Rayleigh quotient `φᵀKφ / φᵀMφ` (rad²/s²).
    pub rayleigh: Vec<f64>,
    /// Round-off floor `ε |φ|ᵀ|K||φ| / φᵀMφ` (rad²/s²).
    pub floor: Vec<f64>,
    /// Whether each mode is a rigid-body mode.
    pub rigid: Vec<bool>,
    /// Relative residual (module docs; the rigid-body definition for rigid modes).
    pub residuals: Vec<f64>,
    /// Round-off floor of each elastic mode's residual (module docs; 0 for rigid modes).
    pub residual_floors: Vec<f64>,
    /// `max |Φᵀ M Φ − I|`.
    pub orthonormality_error: f64,
    /// Number of rigid-body modes.
    pub rigid_body_modes: usize,
}

/// `y = A x` and `z = |A| |x|` for a sparse matrix stored with both triangles (sequential, in
/// storage order: the result does not depend on the thread count).
fn products(a: SparseColMatRef<'_, usize, f64>, x: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = a.nrows();
    let mut y = vec![0.0; n];
    let mut z = vec![0.0; n];
    for (j, &xj) in x.iter().enumerate().take(a.ncols()) {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            y[i] += v * xj;
            z[i] += v.abs() * xj.abs();
        }
    }
    (y, z)
}

fn diagonal(a: SparseColMatRef<'_, usize, f64>) -> Vec<f64> {
    let mut d = vec![0.0; a.ncols()];
    for (j, dj) in d.iter_mut().enumerate() {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            if i == j {
                *dj += v;
            }
        }
    }
    d
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Whether a mode with Rayleigh quotient `lam_r`, round-off floor `floor` and uncertainty `u`
/// (module docs) is rigid.
pub fn is_rigid(lam_r: f64, floor: f64, u: f64) -> bool {
    lam_r.abs() <= RIGID_FLOOR_FACTOR * floor + u
}

/// `(λ_R, λ_ε, u)` of a mode from `φ`, `Kφ`, `|K||φ|`, `Mφ` and the mass diagonal (module docs).
pub fn rigid_measures(
    phi: &[f64],
    kphi: &[f64],
    akphi: &[f64],
    mphi: &[f64],
    mdiag: &[f64],
) -> (f64, f64, f64) {
    let (mut e, mut f, mut q) = (0.0, 0.0, 0.0);
    for i in 0..phi.len() {
        e += phi[i] * kphi[i];
        f += phi[i].abs() * akphi[i];
        q += phi[i] * mphi[i];
    }
    let lam_r = e / q;
    let mut u2 = 0.0;
    for i in 0..phi.len() {
        if mdiag[i] > 0.0 {
            let r = kphi[i] - lam_r * mphi[i];
            u2 += r * r / mdiag[i];
        }
    }
    // φ is normalised here: u scales like 1/‖φ‖_M as λ_R does not.
    (lam_r, f64::EPSILON * f / q, u2.sqrt() / q.sqrt())
}

/// Checks the modes `shapes` (one column per mode, eigenvalues `eigenvalues` in rad²/s²) of the
/// pencil `(K, M)` (sparse, both triangles stored) against the bounds of the module docs.
/// `what` names the solver in errors; a failed bound is an error naming the mode, the
/// measured value and the bound.
pub fn check_modes(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    eigenvalues: &[f64],
    shapes: MatRef<'_, f64>,
    what: &str,
) -> Result<ModeCheck> {
    let n = k.nrows();
    let p = eigenvalues.len();
    if shapes.nrows() != n || shapes.ncols() != p || m.nrows() != n {
        return Err(Error::invalid(
            "modes",
            format!(
                "{} mode shapes of {} rows for {p} eigenvalues and {n}x{n} matrices",
                shapes.ncols(),
                shapes.nrows()
            ),
        ));
    }
    let phis: Vec<Vec<f64>> = (0..p)
        .map(|j| shapes.col(j).iter().copied().collect())
        .collect();
    let mut mphis = Vec::with_capacity(p);
    let mut out = ModeCheck {
        omega_rad_per_s: Vec::with_capacity(p),
        rayleigh: Vec::with_capacity(p),
        floor: Vec::with_capacity(p),
        rigid: Vec::with_capacity(p),
        residuals: Vec::with_capacity(p),
        residual_floors: Vec::with_capacity(p),
        orthonormality_error: 0.0,
        rigid_body_modes: 0,
    };
    let kdiag = diagonal(k);
    let mdiag = diagonal(m);
    for (j, phi) in phis.iter().enumerate() {
        let (kphi, akphi) = products(k, phi);
        // `products` returns `M φ` and `|M||φ|`: the second is the mass term of the residual's
        // round-off floor below (the same sums in the same order as a product with `|φ|`).
        let (mphi, amphi) = products(m, phi);
        let q = dot(phi, &mphi);
        if !(q.is_finite() && q > 0.0) {
            return Err(Error::numerical(
                what,
                format!(
                    "mode {} has φᵀMφ = {q:e}: the mass matrix is not positive definite",
                    j + 1
                ),
            ));
        }
        let (lam_r, floor, u) = rigid_measures(phi, &kphi, &akphi, &mphi, &mdiag);
        let rigid = is_rigid(lam_r, floor, u);
        if !rigid && lam_r < 0.0 {
            return Err(Error::numerical(
                what,
                format!(
                    "mode {} has the Rayleigh quotient φᵀKφ/φᵀMφ = {lam_r:.3e} rad²/s², negative beyond its round-off {floor:.1e}: the stiffness matrix is not positive semi-definite",
                    j + 1
                ),
            ));
        }
        let lam = eigenvalues[j];
        let (residual, residual_floor) = if rigid {
            let d = norm(&akphi);
            (if d > 0.0 { norm(&kphi) / d } else { 0.0 }, 0.0)
        } else {
            let (mut r2, mut k2, mut f2) = (0.0, 0.0, 0.0);
            for i in 0..n {
                let w = kdiag[i] + lam.abs() * mdiag[i];
                let w = if w > 0.0 { 1.0 / w } else { 1.0 };
                let r = kphi[i] - lam * mphi[i];
                let f = akphi[i] + lam.abs() * amphi[i];
                r2 += w * r * r;
                k2 += w * kphi[i] * kphi[i];
                f2 += w * f * f;
            }
            ((r2 / k2).sqrt(), f64::EPSILON * (f2 / k2).sqrt())
        };
        // At the round-off floor the eigenvalue must still be the vector's Rayleigh quotient.
        let at_floor = !rigid
            && residual <= RESIDUAL_FLOOR_FACTOR * residual_floor
            && (lam - lam_r).abs() <= RESIDUAL_BOUND * lam.abs() + RIGID_FLOOR_FACTOR * floor;
        if residual.is_nan() || (residual > RESIDUAL_BOUND && !at_floor) {
            let f = if rigid || lam <= 0.0 {
                "0 Hz, rigid-body".to_string()
            } else {
                format!("{:.4} Hz", lam.sqrt() / (2.0 * std::f64::consts::PI))
            };
            return Err(Error::numerical(
                what,
                format!(
                    "mode {} ({f}) has the relative residual {} = {residual:.1e}, above the bound {RESIDUAL_BOUND:.0e}{}: the eigen-solution is wrong",
                    j + 1,
                    if rigid { "‖Kφ‖/‖|K||φ|‖" } else { "‖D(Kφ − λMφ)‖/‖DKφ‖" },
                    if rigid {
                        String::new()
                    } else {
                        format!(
                            " and {RESIDUAL_FLOOR_FACTOR:.0} times its round-off floor {residual_floor:.1e} (or its eigenvalue differs from its Rayleigh quotient by {:.1e} relative)",
                            (lam - lam_r).abs() / lam.abs().max(f64::MIN_POSITIVE)
                        )
                    }
                ),
            ));
        }
        out.omega_rad_per_s
            .push(if rigid { 0.0 } else { lam.max(0.0).sqrt() });
        out.rayleigh.push(lam_r);
        out.floor.push(floor);
        out.rigid.push(rigid);
        out.residuals.push(residual);
        out.residual_floors.push(residual_floor);
        out.rigid_body_modes += usize::from(rigid);
        mphis.push(mphi);
    }
    let mut orth = 0.0_f64;
    for a in 0..p {
        for b in a..p {
            let target = if a == b { 1.0 } else { 0.0 };
            orth = orth.max((dot(&phis[a], &mphis[b]) - target).abs());
        }
    }
    if orth.is_nan() || orth > ORTHONORMALITY_BOUND {
        return Err(Error::numerical(
            what,
            format!(
                "the modes are not M-orthonormal: max |ΦᵀMΦ − I| = {orth:.1e} over the lowest {p} modes, above the bound {ORTHONORMALITY_BOUND:.0e}: the eigen-solution is wrong"
            ),
        ));
    }
    out.orthonormality_error = orth;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::{SparseColMat, Triplet};
    use faer::Mat;

    fn sparse(n: usize, t: &[(usize, usize, f64)]) -> SparseColMat<usize, f64> {
        let t: Vec<_> = t.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
        SparseColMat::try_new_from_triplets(n, n, &t).unwrap()
    }

    /// Two unit masses joined by a spring k and one of them held by a spring k_g to the
    /// ground: λ = k (1 + r ± sqrt(1 + r²)) ... with k_g = 0 the pair is free: λ = 0 and 2k.
    /// The zero is rigid whatever k (1 to 1e16 N/m), the 2k mode never is.
    #[test]
    fn free_pair_has_one_rigid_mode_at_any_spring_scale() {
        for k in [1.0, 1e8, 1e16] {
            let kk = sparse(2, &[(0, 0, k), (1, 1, k), (0, 1, -k), (1, 0, -k)]);
            let mm = sparse(2, &[(0, 0, 1.0), (1, 1, 1.0)]);
            let s = std::f64::consts::FRAC_1_SQRT_2;
            let shapes = Mat::from_fn(2, 2, |i, j| match (i, j) {
                (_, 0) => s,
                (0, 1) => s,
                _ => -s,
            });
            let c = check_modes(
                kk.as_ref(),
                mm.as_ref(),
                &[0.0, 2.0 * k],
                shapes.as_ref(),
                "test",
            )
            .unwrap();
            assert_eq!(c.rigid, vec![true, false], "k = {k}");
            assert_eq!(c.omega_rad_per_s[0], 0.0);
            assert!((c.omega_rad_per_s[1] - (2.0 * k).sqrt()).abs() <= 1e-15 * (2.0 * k).sqrt());
        }
    }

    /// A wrong eigenvalue (2k (1 + 1e-4) for 2k) fails the residual bound: an error, not a result.
    #[test]
    fn wrong_eigenvalue_is_an_error() {
        let k = 3.0e5;
        let kk = sparse(2, &[(0, 0, k), (1, 1, k), (0, 1, -k), (1, 0, -k)]);
        let mm = sparse(2, &[(0, 0, 1.0), (1, 1, 1.0)]);
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let shapes = Mat::from_fn(2, 1, |i, _| if i == 0 { s } else { -s });
        let e = check_modes(
            kk.as_ref(),
            mm.as_ref(),
            &[2.0 * k * (1.0 + 1e-4)],
            shapes.as_ref(),
            "test",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("residual") && e.contains("above the bound"),
            "{e}"
        );
        // Not M-orthonormal (scaled by 1.001): an error too.
        let shapes = Mat::from_fn(2, 1, |i, _| 1.001 * if i == 0 { s } else { -s });
        let e = check_modes(
            kk.as_ref(),
            mm.as_ref(),
            &[2.0 * k],
            shapes.as_ref(),
            "test",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("M-orthonormal"), "{e}");
    }

    /// Two unit masses joined by k = 1e12 N/m, one held by k_g = 1 N/m: the suspension mode
    /// λ₁ = k k_g / λ₂ (λ₂ = ((a + c) + sqrt((a − c)² + 4k²))/2, a = k + k_g, c = k) has a
    /// residual floor of about ε k / λ₁ ≈ 4e-4 that no computed vector can beat. The exact
    /// pair passes through the floor rule although its residual is above 1e-6; a wrong
    /// eigenvalue and a contaminated vector still fail.
    #[test]
    fn a_mode_at_its_round_off_floor_passes_and_wrong_ones_fail() {
        let (k, kg) = (1e12, 1.0);
        let (a, c) = (k + kg, k);
        let kk = sparse(2, &[(0, 0, a), (1, 1, c), (0, 1, -k), (1, 0, -k)]);
        let mm = sparse(2, &[(0, 0, 1.0), (1, 1, 1.0)]);
        let l2 = 0.5 * ((a + c) + ((a - c) * (a - c) + 4.0 * k * k).sqrt());
        let l1 = k * kg / l2;
        let unit = |v: [f64; 2]| {
            let n = (v[0] * v[0] + v[1] * v[1]).sqrt();
            [v[0] / n, v[1] / n]
        };
        let v1 = unit([-k, l1 - a]);
        let v2 = unit([-k, l2 - a]);
        let run = |lam: f64, v: [f64; 2]| {
            let shapes = Mat::from_fn(2, 1, |i, _| v[i]);
            check_modes(kk.as_ref(), mm.as_ref(), &[lam], shapes.as_ref(), "test")
        };
        let c1 = run(l1, v1).unwrap();
        assert!(!c1.rigid[0]);
        assert!(c1.residuals[0] > RESIDUAL_BOUND, "{:?}", c1.residuals);
        assert!(
            c1.residual_floors[0] > RESIDUAL_BOUND,
            "{:?}",
            c1.residual_floors
        );
        assert!(c1.residuals[0] <= RESIDUAL_FLOOR_FACTOR * c1.residual_floors[0]);
        assert!((c1.omega_rad_per_s[0] - l1.sqrt()).abs() <= 1e-12 * l1.sqrt());
        // A wrong eigenvalue (+10 %) beside the right vector.
        let e = run(1.1 * l1, v1).unwrap_err().to_string();
        assert!(e.contains("round-off floor"), "{e}");
        // The right eigenvalue beside a vector contaminated by 1e-3 of the other mode.
        let w = unit([v1[0] + 1e-3 * v2[0], v1[1] + 1e-3 * v2[1]]);
        let e = run(l1, w).unwrap_err().to_string();
        assert!(e.contains("above the bound"), "{e}");
    }

    /// A negative Rayleigh quotient well above round-off: K is indefinite, an error.
    #[test]
    fn indefinite_stiffness_is_an_error() {
        let kk = sparse(1, &[(0, 0, -5.0)]);
        let mm = sparse(1, &[(0, 0, 1.0)]);
        let shapes = Mat::from_fn(1, 1, |_, _| 1.0);
        let e = check_modes(kk.as_ref(), mm.as_ref(), &[-5.0], shapes.as_ref(), "test")
            .unwrap_err()
            .to_string();
        assert!(e.contains("not positive semi-definite"), "{e}");
    }
}
