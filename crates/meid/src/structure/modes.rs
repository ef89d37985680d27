//! From an assembled model and its modes to the reduced [`ModalModel`] (paper Eq. 9) and a table
//! of modal data (effective masses, participation at named points).
//!
//! For mass-normalised modes `φ_i` (`Φᵀ M Φ = I`):
//! * value at a named point: `Ψ_i(P) = d · u_P(φ_i)` with `d` the impact direction (set average
//!   for node sets);
//! * floor force per mode: `g_K · φ_i` and `g_C · φ_i` with the floor functionals of
//!   [`FeModel::floor_force_functional`];
//! * modal damping `D = diag(2 ζ_i ω_i) + Φᵀ C Φ` (dashpots add the second term);
//! * participation factor for a rigid-body direction `r` (unit translation, or unit rotation about
//!   a global axis through the origin): `Γ_i = φ_iᵀ M r`, effective modal mass `Γ_i²`
//!   (Chopra, *Dynamics of Structures*, §13.2); `Σ_i Γ_i² = rᵀ M r` over all modes of an
//!   unconstrained direction.

use std::collections::BTreeMap;

use crate::modal::dense::DenseModes;
use crate::modal::{FloorForce, ModalModel};
use crate::{Error, Result};

use super::assembly::FeModel;

/// Modal data for tables (`meid modes`).
#[derive(Debug, Clone, PartialEq)]
pub struct ModeTable {
    /// Natural frequencies (Hz).
    pub frequency_hz: Vec<f64>,
    /// Effective modal mass per mode for `[x, y, z, rx, ry, rz]` (kg for translations, kg·m² for
    /// rotations about global axes through the origin).
    pub effective_mass: Vec<[f64; 6]>,
    /// `rᵀ M r` per direction: the sum of the effective masses over all modes when nothing is fixed.
    pub total_mass: [f64; 6],
    /// Mode-shape translations `[x, y, z]` (global) at each named point, per mode.
    pub points: BTreeMap<String, Vec<[f64; 3]>>,
}

impl FeModel {
    /// Functionals (over reduced DOFs) giving the global x, y, z displacement of a named point
    /// (average over its nodes).
    pub fn point_translation_functionals(&self, name: &str) -> Result<[Vec<f64>; 3]> {
        let nodes = self.mesh.point(name)?;
        let n = self.n_dofs();
        let mut f = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        let w = 1.0 / nodes.len() as f64;
        for &node in nodes {
            for (d, fd) in f.iter_mut().enumerate() {
                for &(j, c) in self.dofs.row(6 * node + d) {
                    fd[j] += w * c;
                }
            }
        }
        Ok(f)
    }

    /// Functional giving the displacement of a named point along the impact direction.
    pub fn point_functional(&self, name: &str) -> Result<Vec<f64>> {
        let f = self.point_translation_functionals(name)?;
        let d = self.impact_direction;
        Ok((0..self.n_dofs())
            .map(|j| d[0] * f[0][j] + d[1] * f[1][j] + d[2] * f[2][j])
            .collect())
    }

    /// Force on the floor along the impact direction as `(g_K, g_C)`:
    /// `F = g_K · u + g_C · u̇` over reduced DOFs. It sums the forces of springs and dashpots to
    /// the ground (`+k u`) and the support reactions at fixed translations (`-(K u)_f`, the rows of
    /// the unreduced K for the fixed DOFs); the inertial part `M_fr ü` of the support reaction
    /// (consistent mass of the elements at the support) is not included. Reactions at a fixed
    /// master of a rigid link are not included either. `None` if nothing touches the ground.
    pub fn floor_force_functional(&self) -> Option<(&[f64], &[f64])> {
        if self.grounded {
            Some((&self.floor_stiffness, &self.floor_damping))
        } else {
            None
        }
    }

    fn check_modes(&self, modes: &DenseModes) -> Result<()> {
        if modes.shapes.nrows() != self.n_dofs() {
            return Err(Error::invalid(
                "modes",
                format!(
                    "mode shapes have {} rows but the model has {} DOFs",
                    modes.shapes.nrows(),
                    self.n_dofs()
                ),
            ));
        }
        if modes.shapes.ncols() != modes.omega_rad_per_s.len() {
            return Err(Error::invalid(
                "modes",
                format!(
                    "{} mode shapes but {} frequencies",
                    modes.shapes.ncols(),
                    modes.omega_rad_per_s.len()
                ),
            ));
        }
        Ok(())
    }

    fn dot_mode(&self, modes: &DenseModes, i: usize, f: &[f64]) -> f64 {
        (0..f.len()).map(|j| f[j] * modes.shapes[(j, i)]).sum()
    }

    /// The modal model of the selected modes (0-based indices into `modes`, ascending frequency)
    /// with modal damping ratios `zeta` (one per selected mode): `ω`, `D = diag(2ζω) + ΦᵀCΦ`,
    /// values along the impact direction at every named point, floor-force coefficients.
    pub fn modal_model(
        &self,
        modes: &DenseModes,
        select: &[usize],
        zeta: &[f64],
    ) -> Result<ModalModel> {
        self.check_modes(modes)?;
        let nm = modes.omega_rad_per_s.len();
        if select.is_empty() {
            return Err(Error::invalid("mode selection", "select at least one mode"));
        }
        for &s in select {
            if s >= nm {
                return Err(Error::invalid(
                    "mode selection",
                    format!(
                        "mode index {s} out of range: the solution has modes 0..{}",
                        nm - 1
                    ),
                ));
            }
        }
        for (i, z) in zeta.iter().enumerate() {
            if !(z.is_finite() && *z >= 0.0) {
                return Err(Error::invalid(
                    format!("damping ratio {}", i + 1),
                    format!("must be finite and >= 0 (got {z})"),
                ));
            }
        }
        let omega: Vec<f64> = select.iter().map(|&s| modes.omega_rad_per_s[s]).collect();
        let mut mm = ModalModel::with_damping_ratios(omega, zeta)?;
        let n = select.len();
        // Φᵀ C Φ from the dashpots.
        let nd = self.n_dofs();
        let mut cphi = vec![vec![0.0; nd]; n];
        let mut any_c = false;
        for t in self.damping.triplet_iter() {
            any_c = true;
            for (a, &s) in select.iter().enumerate() {
                cphi[a][t.row] += t.val * modes.shapes[(t.col, s)];
            }
        }
        if any_c {
            for a in 0..n {
                for (b, &sb) in select.iter().enumerate() {
                    mm.damping[a * n + b] += (0..nd)
                        .map(|j| modes.shapes[(j, sb)] * cphi[a][j])
                        .sum::<f64>();
                }
            }
        }
        for name in self.mesh.points.keys() {
            let f = self.point_functional(name)?;
            let v = select
                .iter()
                .map(|&s| self.dot_mode(modes, s, &f))
                .collect();
            mm.points.insert(name.clone(), v);
        }
        if let Some((gk, gc)) = self.floor_force_functional() {
            mm.floor_force = Some(FloorForce {
                stiffness: select
                    .iter()
                    .map(|&s| self.dot_mode(modes, s, gk))
                    .collect(),
                damping: select
                    .iter()
                    .map(|&s| self.dot_mode(modes, s, gc))
                    .collect(),
            });
        }
        mm.labels = select
            .iter()
            .map(|&s| {
                format!(
                    "mode {} ({:.4} Hz)",
                    s + 1,
                    modes.omega_rad_per_s[s] / (2.0 * std::f64::consts::PI)
                )
            })
            .collect();
        mm.mode_numbers = select.iter().map(|&s| s + 1).collect();
        // Γ_i = φ_iᵀ M r along the impact direction d: r = d_x r_x + d_y r_y + d_z r_z.
        let rb = self.rigid_body_vectors();
        let d = self.impact_direction;
        let r: Vec<f64> = (0..nd)
            .map(|j| d[0] * rb[0][j] + d[1] * rb[1][j] + d[2] * rb[2][j])
            .collect();
        let mut mr = vec![0.0; nd];
        for t in self.mass.triplet_iter() {
            mr[t.row] += t.val * r[t.col];
        }
        mm.effective_mass_kg = Some(
            select
                .iter()
                .map(|&s| self.dot_mode(modes, s, &mr).powi(2))
                .collect(),
        );
        mm.validate()?;
        Ok(mm)
    }

    /// Rigid-body influence vectors over the reduced DOFs: unit translations x, y, z and unit
    /// rotations about the global axes through the origin.
    pub fn rigid_body_vectors(&self) -> [Vec<f64>; 6] {
        let n = self.n_dofs();
        let mut r: [Vec<f64>; 6] = std::array::from_fn(|_| vec![0.0; n]);
        for j in 0..n {
            let full = self.dofs.full_of(j);
            let (node, d) = (full / 6, full % 6);
            let x = self.mesh.nodes[node];
            if d < 3 {
                r[d][j] = 1.0;
                // rotation a × x: component d for a = e_rx, e_ry, e_rz
                for a in 0..3 {
                    let mut e = [0.0; 3];
                    e[a] = 1.0;
                    let c = super::geom::cross(e, x);
                    r[3 + a][j] = c[d];
                }
            } else {
                r[d][j] = 1.0;
            }
        }
        r
    }

    /// Frequencies, effective modal masses and point participation of all `modes`.
    pub fn mode_table(&self, modes: &DenseModes) -> Result<ModeTable> {
        self.check_modes(modes)?;
        let r = self.rigid_body_vectors();
        let n = self.n_dofs();
        let mut mr: [Vec<f64>; 6] = std::array::from_fn(|_| vec![0.0; n]);
        for t in self.mass.triplet_iter() {
            for d in 0..6 {
                mr[d][t.row] += t.val * r[d][t.col];
            }
        }
        let total_mass = std::array::from_fn(|d| (0..n).map(|j| r[d][j] * mr[d][j]).sum());
        let nm = modes.omega_rad_per_s.len();
        let effective_mass = (0..nm)
            .map(|i| std::array::from_fn(|d| self.dot_mode(modes, i, &mr[d]).powi(2)))
            .collect();
        let mut points = BTreeMap::new();
        for name in self.mesh.points.keys() {
            let f = self.point_translation_functionals(name)?;
            let v = (0..nm)
                .map(|i| std::array::from_fn(|d| self.dot_mode(modes, i, &f[d])))
                .collect();
            points.insert(name.clone(), v);
        }
        Ok(ModeTable {
            frequency_hz: modes
                .omega_rad_per_s
                .iter()
                .map(|w| w / (2.0 * std::f64::consts::PI))
                .collect(),
            effective_mass,
            total_mass,
            points,
        })
    }
}
