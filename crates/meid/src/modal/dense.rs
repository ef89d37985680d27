//! Dense generalised symmetric eigen-solver for `K φ = λ M φ` (small and medium models).
//!
//! faer 0.24 has no generalised *symmetric* eigen-solver (its `generalized_eigen` is a general QZ,
//! complex and ~10x slower), so the problem is reduced to a standard one by the Cholesky factor of
//! the mass matrix, `M = L Lᵀ`:
//!
//! ```text
//! C = L⁻¹ K L⁻ᵀ,   C y = λ y,   φ = L⁻ᵀ y,   so that Φᵀ M Φ = Yᵀ Y = I.
//! ```
//!
//! `C` is symmetrised before the symmetric eigen-decomposition. Eigenvalues `λ = ω²` of rigid-body
//! modes come out as tiny numbers of either sign; those with `|λ| ≤ 1e-10 · λ_max` are reported as
//! `ω = 0` exactly (`rigid_body_modes` counts them).

use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{Mat, MatRef, Par, Side};

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
    /// max |Φᵀ M Φ - I|.
    pub orthonormality_error: f64,
    /// max_i ‖K φ_i - λ_i M φ_i‖ / (‖K φ_i‖ + |λ_i| ‖M φ_i‖) (relative residual).
    pub max_residual: f64,
    /// Number of modes reported with ω = 0.
    pub rigid_body_modes: usize,
}

/// Relative size below which an eigenvalue is a rigid-body mode (ω = 0).
pub const RIGID_BODY_TOL: f64 = 1e-10;

/// Solves `K φ = λ M φ` for all modes. `K` symmetric positive semi-definite, `M` symmetric
/// positive definite (only the lower triangles are read by the factorisations).
pub fn solve(k: MatRef<'_, f64>, m: MatRef<'_, f64>) -> Result<DenseModes> {
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
    if k.col_iter()
        .flat_map(|c| c.iter().copied())
        .any(|x| !x.is_finite())
        || m.col_iter()
            .flat_map(|c| c.iter().copied())
            .any(|x| !x.is_finite())
    {
        return Err(Error::invalid(
            "stiffness/mass matrices",
            "contain a non-finite entry",
        ));
    }
    let llt = m.llt(Side::Lower).map_err(|_| {
        Error::numerical(
            "dense eigen-solver",
            "the mass matrix is not positive definite (a degree of freedom without mass?)",
        )
    })?;
    let l = llt.L();
    // C = L⁻¹ K L⁻ᵀ: solve L X = K, then L Cᵀ = Xᵀ.
    let mut x = k.to_owned();
    solve_lower_triangular_in_place(l, x.as_mut(), Par::Seq);
    let mut c = x.transpose().to_owned();
    solve_lower_triangular_in_place(l, c.as_mut(), Par::Seq);
    for j in 0..n {
        for i in 0..j {
            let s = 0.5 * (c[(i, j)] + c[(j, i)]);
            c[(i, j)] = s;
            c[(j, i)] = s;
        }
    }
    let evd = c.self_adjoint_eigen(Side::Lower).map_err(|e| {
        Error::numerical(
            "dense eigen-solver",
            format!("symmetric eigen-decomposition failed: {e:?}"),
        )
    })?;
    let eigenvalues: Vec<f64> = (0..n).map(|i| evd.S()[i]).collect();
    let mut shapes = evd.U().to_owned();
    solve_upper_triangular_in_place(l.transpose(), shapes.as_mut(), Par::Seq);

    let lam_max = eigenvalues.iter().fold(0.0_f64, |a, &b| a.max(b.abs()));
    let mut rigid = 0;
    let omega_rad_per_s = eigenvalues
        .iter()
        .map(|&lam| {
            if lam.abs() <= RIGID_BODY_TOL * lam_max {
                rigid += 1;
                0.0
            } else if lam < 0.0 {
                // A clearly negative eigenvalue means K is not positive semi-definite.
                f64::NAN
            } else {
                lam.sqrt()
            }
        })
        .collect::<Vec<_>>();
    if let Some(i) = omega_rad_per_s.iter().position(|w| w.is_nan()) {
        return Err(Error::numerical(
            "dense eigen-solver",
            format!(
                "eigenvalue {} = {:.3e} is negative beyond round-off: the stiffness matrix is not positive semi-definite",
                i + 1,
                eigenvalues[i]
            ),
        ));
    }

    let km = k * &shapes;
    let mm = m * &shapes;
    let gram = shapes.transpose() * &mm;
    let mut orth = 0.0_f64;
    for j in 0..n {
        for i in 0..n {
            let target = if i == j { 1.0 } else { 0.0 };
            orth = orth.max((gram[(i, j)] - target).abs());
        }
    }
    let mut max_residual = 0.0_f64;
    for j in 0..n {
        let lam = eigenvalues[j];
        let mut r2 = 0.0;
        let mut kn = 0.0;
        let mut mn = 0.0;
        for i in 0..n {
            let r = km[(i, j)] - lam * mm[(i, j)];
            r2 += r * r;
            kn += km[(i, j)] * km[(i, j)];
            mn += mm[(i, j)] * mm[(i, j)];
        }
        let denom = kn.sqrt() + lam.abs() * mn.sqrt();
        if denom > 0.0 {
            max_residual = max_residual.max(r2.sqrt() / denom);
        }
    }
    Ok(DenseModes {
        eigenvalues,
        omega_rad_per_s,
        shapes,
        orthonormality_error: orth,
        max_residual,
        rigid_body_modes: rigid,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
