//! How much of the structure a modal reduction keeps: the static flexibility of the full model at
//! a point against the part of it the retained modes carry.
//!
//! # Static flexibility (attached-mode convention)
//! For a point functional `f_P` (the displacement of P along the impact axis is `f_Pᵀ u`), the
//! static flexibility of the full structure is
//!
//! ```text
//! G_PP = f_Pᵀ K⁻¹ f_P = Σ_{all modes} ψ_i(P)² / ω_i²        (m/N),   ψ_i(P) = f_Pᵀ φ_i,
//! ```
//!
//! the displacement of P under a unit static force at P. When the structure has rigid-body modes
//! (`ω = 0`, K singular) the sum runs over the **elastic** modes only (the attached-mode /
//! inertia-relief convention): the load is made self-equilibrated, `f_e = f_P − M Φ_r Φ_rᵀ f_P`,
//! the elastic deflection `u` solves `K u = f_e` with `Φ_rᵀ M u = 0`, and `G_PP = f_Pᵀ u =
//! Σ_{ω_i > 0} ψ_i(P)²/ω_i²`. It is computed from the factorisation of K (not from the modes):
//!
//! * no rigid-body modes: sparse Cholesky `K = L Lᵀ`, `u = K⁻¹ f_P`;
//! * rigid-body modes: Cholesky of `K + σM` (σ = 1e-2 of the lowest elastic eigenvalue) and the
//!   fixed-point iteration `u ← P (K + σM)⁻¹ (f_e + σ M u)` with the projector
//!   `P = I − Φ_r Φ_rᵀ M`. Each elastic component of the error shrinks by `σ/(λ_i + σ) ≤ 1/101`
//!   per step, so ten steps reach double precision.
//!
//! # Captured share
//! The modal estimate over the retained modes is `Ĝ_PP = Σ_{retained, ω_i > 0} ψ_i(P)²/ω_i²` and
//! the captured share is `Ĝ_PP / G_PP ≤ 1`. It measures what a truncation loses at low
//! frequency: a retained set that misses a mode carrying P's flexibility (say a soft bounce
//! mode) shows a small share, whatever the mode's frequency. Below [`SHARE_WARNING`] meid warns.
//! A model with all its modes retained (lumped) has a share of exactly 1 up to round-off.
//!
//! # Effective mass at a point
//! A short blow of impulse `J` at P sets every retained mode moving at `q̇_i = ψ_i(P) J`, so P
//! moves at `v_P = Σ_i ψ_i(P)² J`: the structure meets the blow as a mass
//!
//! ```text
//! m_eff(P) = 1 / Σ_{retained} ψ_i(P)²        (kg),     per mode  m_i(P) = 1 / ψ_i(P)²,
//! ```
//!
//! (the driving-point apparent mass at the instant of impact, over the structure's retained
//! modes: static-correction pseudo-modes are left out; with all modes of a lumped model
//! retained, `Σ ψ_i(P)² = (M⁻¹)_PP` and `m_eff` is the mass lumped at P). This, not the bed's
//! mass, is what a damper's mass should be compared with: the momentum exchange is between the
//! damper and `m_eff`, and it is largest when `m_d / m_eff` is near 1.

use faer::sparse::SparseColMatRef;
use faer::{Mat, Par};
use serde::Serialize;

use super::lanczos::ShiftedPencil;
use super::ModalModel;
use crate::{Error, Result};

/// Captured shares below this (95 %) are reported as warnings.
pub const SHARE_WARNING: f64 = 0.95;

/// One row of the truncation table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TruncationRow {
    /// Named point.
    pub point: String,
    /// The model roles the point plays (`bed_contact`, `damper_anchor`, `measurement`).
    pub roles: Vec<String>,
    /// `G_PP` of the full structure over its elastic modes (m/N).
    pub static_flexibility_m_per_n: f64,
    /// `Σ ψ_i(P)²/ω_i²` over the retained elastic modes (m/N).
    pub modal_flexibility_m_per_n: f64,
    /// `modal / static` (1 when the point does not move under a static load, `G_PP = 0`).
    pub captured_share: f64,
    /// `m_eff(P) = 1/Σ ψ_i(P)²` over the retained modes of the structure (kg; module docs;
    /// static-correction pseudo-modes left out: Ritz vectors whose ψ depend on the points
    /// corrected, not a property of the structure); `None` when no retained mode moves P.
    pub effective_mass_kg: Option<f64>,
    /// The retained mode that moves P most (largest `ψ_i(P)²`; the structure's mode number)
    /// and its effective mass at P, `1/ψ_i(P)²` (kg).
    pub dominant_mode: Option<usize>,
    pub dominant_mode_effective_mass_kg: Option<f64>,
    /// Of P's static response to a force at the struck point (the `bed_contact` point, O_b),
    /// the share the retained modes carry: `Σ ψ_i(P) ψ_i(O_b)/ω_i² / G_{P,O_b}`. It says how
    /// much of the quasi-static part of what is printed at P (its displacement under the blow,
    /// the low-frequency part of its acceleration) the truncation loses, where
    /// `captured_share` speaks of any load at P. `None` at O_b itself, where the full `G_{P,O_b}`
    /// is unknown, or where P hardly moves under that force (`|G_{P,O_b}| < 1e-3 √(G_PP G_OO)`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blow_response_share: Option<f64>,
    /// Whether the retained set includes static-correction pseudo-modes
    /// ([`super::static_correction`]): then `modal_flexibility_m_per_n` and `captured_share`
    /// are those of the corrected basis (1 up to round-off at a corrected point) and
    /// `modes_share` is what the structural modes alone carry.
    pub static_correction: bool,
    /// With the static correction, the share `Σ_{structural} ψ²/ω² / G_PP` the retained
    /// structural modes carry alone (what the table showed without correction).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub modes_share: Option<f64>,
}

/// `(m_eff, dominant mode index, its 1/ψ²)` at a point with mode-shape values `psi` (module
/// docs); `None`s where no mode moves the point.
pub fn effective_mass(psi: &[f64]) -> (Option<f64>, Option<usize>, Option<f64>) {
    let sum: f64 = psi.iter().map(|p| p * p).fold(0.0, |a, x| a + x);
    let dominant = psi
        .iter()
        .enumerate()
        .filter(|(_, p)| **p != 0.0)
        .max_by(|a, b| (a.1 * a.1).total_cmp(&(b.1 * b.1)));
    (
        (sum > 0.0).then(|| 1.0 / sum),
        dominant.map(|(i, _)| i),
        dominant.map(|(_, p)| 1.0 / (p * p)),
    )
}

/// `Σ_{ω_i > 0} ψ_i²/ω_i²` (m/N) for mode-shape values `psi` (1/√kg) and frequencies `omega`;
/// `+0` when no retained mode is elastic (summed from `+0.0`: `Iterator::sum` of no `f64` is
/// `−0.0`, which the table printed as "-0.000000e0" and a share of "-0.000 %").
pub fn modal_flexibility(omega_rad_per_s: &[f64], psi: &[f64]) -> f64 {
    omega_rad_per_s
        .iter()
        .zip(psi)
        .filter(|(w, _)| **w > 0.0)
        .map(|(w, p)| p * p / (w * w))
        .fold(0.0, |acc, x| acc + x)
}

impl ModalModel {
    /// The truncation table for `points` = (name, roles): static flexibility of the full
    /// structure (from [`ModalModel::static_flexibility`]), the retained modes' estimate and
    /// their ratio. Points without a known static flexibility (tabulated modes) are left out.
    pub fn truncation(&self, points: &[(String, Vec<String>)]) -> Vec<TruncationRow> {
        let struck = points
            .iter()
            .find(|(_, roles)| roles.iter().any(|r| r == "bed_contact"))
            .map(|(name, _)| name.as_str());
        let mut rows = Vec::new();
        let corrected = (0..self.len()).any(|i| self.is_pseudo(i));
        // The structural modes alone: pseudo-modes count for nothing in the dominant mode and
        // the modes-only share.
        let structural = |v: &[f64]| -> Vec<f64> {
            v.iter()
                .enumerate()
                .map(|(i, x)| if self.is_pseudo(i) { 0.0 } else { *x })
                .collect()
        };
        for (name, roles) in points {
            let (Some(&g), Ok(psi)) = (self.static_flexibility.get(name), self.point(name)) else {
                continue;
            };
            let modal = modal_flexibility(&self.omega_rad_per_s, psi);
            let share = if g > 0.0 { modal / g } else { 1.0 };
            let psi_modes = structural(psi);
            let (m_eff, dominant, m_dominant) = effective_mass(&psi_modes);
            let modes_share = corrected.then(|| {
                let m = modal_flexibility(&self.omega_rad_per_s, &psi_modes);
                if g > 0.0 {
                    m / g
                } else {
                    1.0
                }
            });
            rows.push(TruncationRow {
                point: name.clone(),
                roles: roles.clone(),
                static_flexibility_m_per_n: g,
                modal_flexibility_m_per_n: modal,
                captured_share: share,
                effective_mass_kg: m_eff,
                dominant_mode: dominant.map(|i| self.mode_numbers.get(i).copied().unwrap_or(i + 1)),
                dominant_mode_effective_mass_kg: m_dominant,
                blow_response_share: struck.and_then(|o| self.blow_response_share(name, o, g)),
                static_correction: corrected,
                modes_share,
            });
        }
        rows
    }
}

impl ModalModel {
    /// [`TruncationRow::blow_response_share`] of point `p` (static flexibility `g_pp`) under a
    /// force at the struck point `o`.
    fn blow_response_share(&self, p: &str, o: &str, g_pp: f64) -> Option<f64> {
        if p == o {
            return None;
        }
        let g_po = *self.static_cross_flexibility.get(p)?.get(o)?;
        let g_oo = *self.static_flexibility.get(o)?;
        if !(g_po.abs() >= 1e-3 * (g_pp * g_oo).abs().sqrt() && g_po.abs() > 0.0) {
            return None;
        }
        let modal = modal_cross_flexibility(
            &self.omega_rad_per_s,
            self.point(p).ok()?,
            self.point(o).ok()?,
        );
        Some(modal / g_po)
    }
}

/// The truncation table as fixed-width text, one line per point, with a heading.
pub fn to_text(rows: &[TruncationRow]) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    if rows.is_empty() {
        return s;
    }
    s.push_str("static flexibility captured by the retained modes (sum psi^2/omega^2 over G_PP = e^T K^-1 e, elastic part):\n");
    let w = rows.iter().map(|r| r.point.len()).max().unwrap_or(5).max(5);
    let _ = writeln!(
        s,
        "  {:<w$} {:>14} {:>14} {:>10} {:>12} {:>20}  roles",
        "point", "G_PP m/N", "modal m/N", "share", "m_eff kg", "mode: 1/psi^2 kg"
    );
    let kg = |v: Option<f64>| v.map_or("—".to_string(), |m| format!("{m:.4}"));
    let corrected = rows.iter().any(|r| r.static_correction);
    for r in rows {
        let dominant = match (r.dominant_mode, r.dominant_mode_effective_mass_kg) {
            (Some(n), Some(m)) => format!("{n}: {m:.4}"),
            _ => "—".to_string(),
        };
        let alone = match r.modes_share {
            Some(m) => format!("  (modes alone {:.3} %)", 100.0 * m),
            None => String::new(),
        };
        let _ = writeln!(
            s,
            "  {:<w$} {:>14.6e} {:>14.6e} {:>9.3} % {:>12} {:>20}  {}{alone}",
            r.point,
            r.static_flexibility_m_per_n,
            r.modal_flexibility_m_per_n,
            100.0 * r.captured_share,
            kg(r.effective_mass_kg),
            dominant,
            r.roles.join(", ")
        );
    }
    s.push_str("  (m_eff = 1/sum psi^2 over the retained modes: the mass the structure opposes to a blow at the point)\n");
    if corrected {
        s.push_str("  (with static correction: modal and share include the pseudo-modes, which restore the full static flexibility at the named points; m_eff and the dominant mode are over the structural modes)\n");
    }
    s
}

/// CSV: `point,roles,static_flexibility_m_per_n,modal_flexibility_m_per_n,captured_share,
/// effective_mass_kg,dominant_mode,dominant_mode_effective_mass_kg,static_correction,
/// modes_share` (roles separated by `;`; an empty field where no retained mode moves the point
/// or, for `modes_share`, without static correction).
pub fn to_csv(rows: &[TruncationRow]) -> String {
    let mut s = String::from(
        "point,roles,static_flexibility_m_per_n,modal_flexibility_m_per_n,captured_share,effective_mass_kg,dominant_mode,dominant_mode_effective_mass_kg,static_correction,modes_share\n",
    );
    let opt = |v: Option<f64>| v.map_or(String::new(), |m| format!("{m:e}"));
    for r in rows {
        s.push_str(&format!(
            "{},{},{:e},{:e},{:e},{},{},{},{},{}\n",
            r.point,
            r.roles.join(";"),
            r.static_flexibility_m_per_n,
            r.modal_flexibility_m_per_n,
            r.captured_share,
            opt(r.effective_mass_kg),
            r.dominant_mode.map_or(String::new(), |n| n.to_string()),
            opt(r.dominant_mode_effective_mass_kg),
            r.static_correction,
            opt(r.modes_share)
        ));
    }
    s
}

/// The warning for a row below [`SHARE_WARNING`], if any.
pub fn share_warning(row: &TruncationRow) -> Option<String> {
    if row.captured_share >= SHARE_WARNING {
        return None;
    }
    let roles = if row.roles.is_empty() {
        String::new()
    } else {
        format!(" ({})", row.roles.join(", "))
    };
    // What this means for the results printed at the point: its response to the blow.
    let effect = match row.blow_response_share {
        Some(b) => format!(
            "; of its static response to the blow (a force at the struck point) they carry \
             {:.2} %, so what is printed at '{}' (its displacement, the low-frequency part of \
             its acceleration) is off by about {:.2} % in its quasi-static part (the missing \
             modes' dynamic part is not estimated); results at the struck point are not \
             affected by this",
            100.0 * b,
            row.point,
            100.0 * (1.0 - b).abs()
        ),
        None => String::new(),
    };
    let carriers = if row.static_correction {
        "retained modes with their static correction (a pseudo-mode was left out: see the notes)"
    } else {
        "retained modes"
    };
    Some(format!(
        "the {carriers} carry {:.2} % of the static flexibility at point '{}'{roles} \
         ({:.4e} of {:.4e} m/N): a mode that moves this point is missing{effect}; keep more \
         modes (select = \"auto\", a larger `count`, or add the missing mode numbers to \
         `select`)",
        100.0 * row.captured_share,
        row.point,
        row.modal_flexibility_m_per_n,
        row.static_flexibility_m_per_n
    ))
}

/// Static flexibilities `G_PP = f_Pᵀ u_P` of the structure `(K, M)` at the points given by
/// `functionals` (one vector of length n per point), over the elastic modes (see the module
/// docs). `rigid` are the M-orthonormal rigid-body modes (columns, may be empty);
/// `lowest_elastic` the lowest nonzero eigenvalue λ (rad²/s²) when rigid-body modes exist.
pub fn static_flexibility(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    functionals: &[Vec<f64>],
    rigid: &[Vec<f64>],
    lowest_elastic: Option<f64>,
) -> Result<Vec<f64>> {
    let g = static_flexibility_matrix(k, m, functionals, rigid, lowest_elastic)?;
    Ok(g.iter().enumerate().map(|(i, row)| row[i]).collect())
}

/// The static (cross) flexibilities `G_PQ = f_Pᵀ u_Q` (m/N, elastic part) between the points
/// of `functionals`: the displacement of P under a unit static force at Q, a symmetric `p × p`
/// matrix (rows of the result) whose diagonal is [`static_flexibility`]. The modal estimate of
/// an entry is `Σ_{retained, ω_i > 0} ψ_i(P) ψ_i(Q)/ω_i²` ([`modal_cross_flexibility`]).
pub fn static_flexibility_matrix(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    functionals: &[Vec<f64>],
    rigid: &[Vec<f64>],
    lowest_elastic: Option<f64>,
) -> Result<Vec<Vec<f64>>> {
    let u = static_deflections(k, m, functionals, rigid, lowest_elastic)?;
    Ok(flexibility_of_deflections(functionals, u.as_ref()))
}

/// `G_PQ = f_Pᵀ u_Q` (rows P, columns Q) from the static deflections `u` of
/// [`static_deflections`] (one column per point of `functionals`).
pub fn flexibility_of_deflections(
    functionals: &[Vec<f64>],
    u: faer::MatRef<'_, f64>,
) -> Vec<Vec<f64>> {
    let n = u.nrows();
    functionals
        .iter()
        .map(|f| {
            (0..u.ncols())
                .map(|c| (0..n).map(|i| f[i] * u[(i, c)]).sum())
                .collect()
        })
        .collect()
}

/// The off-diagonal entries of a [`static_flexibility_matrix`] by point names: `map[P][Q] =
/// G_PQ` for P ≠ Q (the layout of [`ModalModel::static_cross_flexibility`]).
pub fn cross_map<S: AsRef<str>>(
    names: &[S],
    g: &[Vec<f64>],
) -> std::collections::BTreeMap<String, std::collections::BTreeMap<String, f64>> {
    let mut map = std::collections::BTreeMap::new();
    for (i, p) in names.iter().enumerate() {
        let row: std::collections::BTreeMap<String, f64> = names
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != i)
            .map(|(j, q)| (q.as_ref().to_string(), g[i][j]))
            .collect();
        map.insert(p.as_ref().to_string(), row);
    }
    map
}

/// `Σ_{ω_i > 0} ψ_i(P) ψ_i(Q)/ω_i²` (m/N) over the retained modes: the modal estimate of
/// `G_PQ` ([`static_flexibility_matrix`]).
pub fn modal_cross_flexibility(omega_rad_per_s: &[f64], psi_p: &[f64], psi_q: &[f64]) -> f64 {
    omega_rad_per_s
        .iter()
        .zip(psi_p.iter().zip(psi_q))
        .filter(|(w, _)| **w > 0.0)
        .map(|(w, (a, b))| a * b / (w * w))
        .fold(0.0, |acc, x| acc + x)
}

/// The elastic static deflections `u_Q` (columns) under unit loads at the points of
/// `functionals` (module docs: Cholesky of K, or the inertia-relief iteration with rigid-body
/// modes, converged on the diagonal `f_Qᵀ u_Q`). One factorisation serves every point: the
/// truncation table and the static correction ([`super::static_correction`]) share them.
pub fn static_deflections(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    functionals: &[Vec<f64>],
    rigid: &[Vec<f64>],
    lowest_elastic: Option<f64>,
) -> Result<Mat<f64>> {
    static_deflections_sharing(k, m, functionals, rigid, lowest_elastic, &mut None)
}

/// [`static_deflections`] with the symbolic analysis of `K − σM` taken from `pencil` (the
/// eigen-solver's, [`super::lanczos::lowest_modes_sharing`]) or built there when it is `None`.
/// `pencil` must hold the analysis of this `k` and `m`.
pub fn static_deflections_sharing(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    functionals: &[Vec<f64>],
    rigid: &[Vec<f64>],
    lowest_elastic: Option<f64>,
    pencil: &mut Option<ShiftedPencil>,
) -> Result<Mat<f64>> {
    let n = k.nrows();
    let p = functionals.len();
    if p == 0 {
        return Ok(Mat::zeros(n, 0));
    }
    if functionals.iter().chain(rigid).any(|f| f.len() != n) {
        return Err(Error::invalid(
            "static flexibility",
            format!("point functionals and rigid-body modes need {n} entries"),
        ));
    }
    let pencil = ShiftedPencil::in_slot(pencil, k, m)?;
    let mut rhs = Mat::<f64>::from_fn(n, p, |i, j| functionals[j][i]);
    if rigid.is_empty() {
        let mut llt = pencil.factor_llt(0.0, Par::Seq).map_err(|_| {
            Error::numerical(
                "static flexibility",
                "the stiffness matrix is singular but no rigid-body mode was found: the \
                 structure has a mechanism or its stiffnesses span more than double precision",
            )
        })?;
        llt.solve_in_place(rhs.as_mut())?;
        return Ok(rhs);
    }
    let lam1 = match lowest_elastic {
        Some(l) if l.is_finite() && l > 0.0 => l,
        _ => {
            return Err(Error::invalid(
                "static flexibility",
                "a structure with rigid-body modes needs its lowest elastic eigenvalue",
            ))
        }
    };
    let sigma = 1e-2 * lam1;
    let mut llt = pencil.factor_llt(-sigma, Par::Seq)?;
    let mul_m = |x: &Mat<f64>| -> Mat<f64> {
        let mut y = Mat::<f64>::zeros(n, x.ncols());
        for j in 0..n {
            for (&i, &v) in m.row_idx_of_col_raw(j).iter().zip(m.val_of_col(j)) {
                for c in 0..x.ncols() {
                    y[(i, c)] += v * x[(j, c)];
                }
            }
        }
        y
    };
    // f_e = f − M Φ_r Φ_rᵀ f.
    let mut fe = rhs.clone();
    let mr: Vec<Mat<f64>> = rigid
        .iter()
        .map(|r| mul_m(&Mat::<f64>::from_fn(n, 1, |i, _| r[i])))
        .collect();
    for (r, mrr) in rigid.iter().zip(&mr) {
        for c in 0..p {
            let a: f64 = (0..n).map(|i| r[i] * functionals[c][i]).sum();
            for i in 0..n {
                fe[(i, c)] -= a * mrr[(i, 0)];
            }
        }
    }
    let project = |u: &mut Mat<f64>| {
        for (r, mrr) in rigid.iter().zip(&mr) {
            for c in 0..p {
                let a: f64 = (0..n).map(|i| mrr[(i, 0)] * u[(i, c)]).sum();
                for i in 0..n {
                    u[(i, c)] -= a * r[i];
                }
            }
        }
    };
    let mut u = Mat::<f64>::zeros(n, p);
    let mut g_old = vec![f64::INFINITY; p];
    for _ in 0..60 {
        let mu = mul_m(&u);
        let mut next = Mat::<f64>::from_fn(n, p, |i, c| fe[(i, c)] + sigma * mu[(i, c)]);
        llt.solve_in_place(next.as_mut())?;
        project(&mut next);
        u = next;
        let g: Vec<f64> = (0..p)
            .map(|c| (0..n).map(|i| functionals[c][i] * u[(i, c)]).sum())
            .collect();
        let done = g
            .iter()
            .zip(&g_old)
            .all(|(a, b)| (a - b).abs() <= 1e-15 * a.abs());
        g_old = g;
        if done {
            return Ok(u);
        }
    }
    Err(Error::numerical(
        "static flexibility",
        "the inertia-relief iteration did not converge in 60 steps",
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::{SparseColMat, Triplet};

    fn sparse(n: usize, e: &[(usize, usize, f64)]) -> SparseColMat<usize, f64> {
        let t: Vec<_> = e.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
        SparseColMat::try_new_from_triplets(n, n, &t).unwrap()
    }

    /// Only rigid-body modes retained (a free piece of a mesh cut by duplicate nodes kept its
    /// six 0 Hz modes): the modal flexibility is +0 and the table prints "0.000000e0" and
    /// "0.000 %", not the "-0.000000e0" / "-0.000 %" an empty `f64` sum (−0.0) gave.
    #[test]
    fn no_elastic_mode_retained_is_a_positive_zero() {
        let m = modal_flexibility(&[0.0, 0.0], &[0.9, 0.7]);
        assert!(m == 0.0 && m.is_sign_positive(), "{m:?}");
        let g = 3.983281e-8;
        let row = TruncationRow {
            point: "O_b".into(),
            roles: vec!["bed_contact".into()],
            static_flexibility_m_per_n: g,
            modal_flexibility_m_per_n: m,
            captured_share: m / g,
            effective_mass_kg: Some(1.0),
            dominant_mode: Some(1),
            dominant_mode_effective_mass_kg: Some(1.0),
            blow_response_share: None,
            static_correction: false,
            modes_share: None,
        };
        let text = to_text(&[row]);
        assert!(!text.contains("-0"), "{text}");
        assert!(text.contains(" 0.000 %"), "{text}");
    }

    /// k, K, M and the unit loads of [`grounded_chain`].
    type Chain = (
        f64,
        SparseColMat<usize, f64>,
        SparseColMat<usize, f64>,
        Vec<Vec<f64>>,
    );

    /// A fixed-free chain of three springs k = 2e5 N/m over masses 1, 2, 3 kg: k, K, M and the
    /// unit loads at the tip and the middle.
    fn grounded_chain() -> Chain {
        let k = 2.0e5;
        let kk = sparse(
            3,
            &[
                (0, 0, 2.0 * k),
                (0, 1, -k),
                (1, 0, -k),
                (1, 1, 2.0 * k),
                (1, 2, -k),
                (2, 1, -k),
                (2, 2, k),
            ],
        );
        let mm = sparse(3, &[(0, 0, 1.0), (1, 1, 2.0), (2, 2, 3.0)]);
        let f = vec![vec![0.0, 0.0, 1.0], vec![0.0, 1.0, 0.0]];
        (k, kk, mm, f)
    }

    /// Fixed-free chain of three springs k: the tip flexibility is 3/k, the middle 2/k.
    #[test]
    fn grounded_chain_matches_series_springs() {
        let (k, kk, mm, f) = grounded_chain();
        let g = static_flexibility(kk.as_ref(), mm.as_ref(), &f, &[], None).unwrap();
        assert!((g[0] - 3.0 / k).abs() <= 1e-14 * 3.0 / k, "{g:?}");
        assert!((g[1] - 2.0 / k).abs() <= 1e-14 * 2.0 / k, "{g:?}");
    }

    /// Cross flexibilities against closed forms: on the grounded chain of three springs k a
    /// force at the middle moves the tip as much as the middle (2/k); on the free pair joined
    /// by k (inertia relief) `G_12 = φ(1)φ(2)/ω² = −m1 m2/((m1 + m2)² k)`, which the modal
    /// estimate with the one elastic mode gives too (share 1).
    #[test]
    fn cross_flexibilities_match_the_closed_forms() {
        let (k, kk, mm, f) = grounded_chain();
        let g = static_flexibility_matrix(kk.as_ref(), mm.as_ref(), &f, &[], None).unwrap();
        for (got, want) in [(g[0][1], 2.0 / k), (g[1][0], 2.0 / k), (g[0][0], 3.0 / k)] {
            assert!((got - want).abs() <= 1e-14 * want, "{g:?}");
        }
        let map = cross_map(&["tip", "middle"], &g);
        assert_eq!(map["tip"]["middle"], g[0][1]);
        assert!(!map["tip"].contains_key("tip"));

        let (m1, m2, k) = (2.0, 6.0, 3.0e4);
        let kk = sparse(2, &[(0, 0, k), (0, 1, -k), (1, 0, -k), (1, 1, k)]);
        let mm = sparse(2, &[(0, 0, m1), (1, 1, m2)]);
        let s = 1.0 / (m1 + m2).sqrt();
        let lam = k * (1.0 / m1 + 1.0 / m2);
        let f = vec![vec![1.0, 0.0], vec![0.0, 1.0]];
        let g = static_flexibility_matrix(kk.as_ref(), mm.as_ref(), &f, &[vec![s, s]], Some(lam))
            .unwrap();
        let want = -m1 * m2 / ((m1 + m2).powi(2) * k);
        assert!(
            (g[0][1] - want).abs() <= 1e-13 * want.abs(),
            "{g:?} vs {want}"
        );
        let (a, b) = (
            (m2 / (m1 * (m1 + m2))).sqrt(),
            -(m1 / (m2 * (m1 + m2))).sqrt(),
        );
        let modal = modal_cross_flexibility(&[0.0, lam.sqrt()], &[s, a], &[s, b]);
        assert!(
            (modal / g[0][1] - 1.0).abs() <= 1e-12,
            "{modal} vs {}",
            g[0][1]
        );
    }

    /// Two free masses m1, m2 joined by k: one elastic mode, ω² = k (1/m1 + 1/m2), shape
    /// φ = (m2, −m1)/sqrt(m1 m2 (m1 + m2)); the elastic flexibility at mass 1 is
    /// φ_1²/ω² = m2² / ((m1 + m2)² k).
    #[test]
    fn free_pair_uses_the_elastic_mode_only() {
        let (m1, m2, k) = (2.0, 6.0, 3.0e4);
        let kk = sparse(2, &[(0, 0, k), (0, 1, -k), (1, 0, -k), (1, 1, k)]);
        let mm = sparse(2, &[(0, 0, m1), (1, 1, m2)]);
        let s = 1.0 / (m1 + m2).sqrt();
        let rigid = vec![vec![s, s]];
        let lam = k * (1.0 / m1 + 1.0 / m2);
        let f = vec![vec![1.0, 0.0], vec![0.0, 1.0]];
        let g = static_flexibility(kk.as_ref(), mm.as_ref(), &f, &rigid, Some(lam)).unwrap();
        let e1 = m2 * m2 / ((m1 + m2).powi(2) * k);
        let e2 = m1 * m1 / ((m1 + m2).powi(2) * k);
        assert!((g[0] - e1).abs() <= 1e-13 * e1, "{} vs {e1}", g[0]);
        assert!((g[1] - e2).abs() <= 1e-13 * e2, "{} vs {e2}", g[1]);
    }

    #[test]
    fn singular_stiffness_without_rigid_modes_is_an_error() {
        let kk = sparse(2, &[(0, 0, 1.0), (0, 1, -1.0), (1, 0, -1.0), (1, 1, 1.0)]);
        let mm = sparse(2, &[(0, 0, 1.0), (1, 1, 1.0)]);
        let e = static_flexibility(kk.as_ref(), mm.as_ref(), &[vec![1.0, 0.0]], &[], None);
        assert!(e.is_err());
    }
}
