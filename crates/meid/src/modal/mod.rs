//! Modal analysis and the reduced modal model (paper Eq. 9).
//!
//! The impact engine never sees a finite-element mesh: it sees a [`ModalModel`],
//! the structure reduced to `n` mass-normalised modes,
//!
//! ```text
//! q̈_i + Σ_j D_ij q̇_j + ω_i² q_i = Ψ_i · f      (paper Eq. 9; D = diag(2 ζ_i ω_i) for modal damping)
//! ```
//!
//! together with the mode-shape values `Ψ_i(P)` at the named points the impact system
//! needs (bed contact O_b, floating-base point O_f, measurement point B) and the force
//! to the floor as a linear function of the modal coordinates. A lumped model, a
//! finite-element model and a user's table of measured or imported modes all end here.
//!
//! Submodules: [`check`] (every computed set of modes checked against stated bounds; rigid-body
//! modes from the problem itself), [`dense`] (dense generalised symmetric eigen-solver), [`eigenspace`] (repeated eigenvalues: a
//! basis of their eigenspace that does not depend on the solver), [`lanczos`]
//! (sparse shift-invert block Lanczos for large models), [`static_correction`] (pseudo-modes that
//! restore the static flexibility a truncation loses at the named points), [`truncation`] (the static flexibility
//! a set of retained modes captures at the named points), [`conditioning`] (spreads double
//! precision cannot carry).
//!
//! Every result of this module is bit-identical for any number of rayon threads: faer is
//! called with `Par::Seq` only, and the parallel parts cut their work into chunks of a fixed
//! size and combine them in index order (`kernels`).

pub mod check;
pub mod conditioning;
pub mod dense;
pub mod eigenspace;
pub(crate) mod kernels;
pub mod lanczos;
pub mod static_correction;
pub mod truncation;

use std::collections::BTreeMap;

use crate::{Error, Result};

/// Why a blow at a point cannot be simulated when no retained mode moves it along the impact
/// direction: its mode-shape values `psi` (one per mode) are all 0, so its effective mass
/// `1 / Σ_i ψ_i²` is infinite and the slider meets an immovable point (e.g. a point whose
/// impact-direction DOF is constrained). `what` names the point in the message. `None` when a
/// mode moves it.
pub fn immovable_point(what: &str, psi: &[f64]) -> Option<String> {
    if psi.is_empty() || psi.iter().any(|v| *v != 0.0) {
        return None;
    }
    let modes = match psi.len() {
        1 => "the one retained mode".to_string(),
        n => format!("all {n} retained modes"),
    };
    Some(format!(
        "{what}: no retained mode moves it along the impact direction (ψ = 0 in {modes}), \
         so its effective mass 1/Σψ² is infinite and a blow there meets an immovable point: the \
         machine takes none of the blow's energy. Strike a point the structure's modes move (is \
         the point's impact-direction DOF constrained, or are the modes that move it left out of \
         the selection?)"
    ))
}

/// The force to the floor as a linear function of the modal state:
/// `F_floor = Σ_i stiffness[i] q_i + Σ_i damping[i] q̇_i` (N), positive when it pushes
/// the floor in +z (the direction the slider moves).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FloorForce {
    /// Per mode, N per unit modal coordinate (N / (m·kg^½)).
    pub stiffness: Vec<f64>,
    /// Per mode, N per unit modal velocity.
    pub damping: Vec<f64>,
}

/// A structure reduced to its modes. All vectors have one entry per retained mode.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ModalModel {
    /// Natural circular frequencies ω_i (rad/s), ascending. Rigid-body modes are exactly 0.
    pub omega_rad_per_s: Vec<f64>,
    /// Modal damping matrix D (1/s), row-major `n × n`. For modal damping ratios it is
    /// `diag(2 ζ_i ω_i)`; discrete dashpots of a lumped model add `Φᵀ C Φ`.
    pub damping: Vec<f64>,
    /// Mass-normalised mode-shape values in z at named points (m per unit modal coordinate).
    pub points: BTreeMap<String, Vec<f64>>,
    /// Force to the floor, if the structure rests on the floor through something.
    pub floor_force: Option<FloorForce>,
    /// A label per mode for tables and plots, e.g. "mode 6".
    pub labels: Vec<String>,
    /// The structure's number of each retained mode (1-based, ascending frequency among all
    /// computed modes, as `meid modes` lists them): `structure.reference_mode` names a mode by
    /// it.
    pub mode_numbers: Vec<usize>,
    /// Effective modal mass along the impact direction of each retained mode (kg),
    /// `Γ_i² = (φ_iᵀ M r)²` with `r` the unit rigid translation along the impact direction
    /// (Chopra, *Dynamics of Structures*, §13.2): the mass that moves with the mode in the
    /// direction of the blow. `None` when the mass matrix is not known (tabulated or imported
    /// modes).
    pub effective_mass_kg: Option<Vec<f64>>,
    /// Static flexibility of the full (unreduced) structure along z at named points (m/N), over
    /// its elastic modes: `G_PP = Σ_{all elastic modes} ψ_i(P)²/ω_i²`, computed from the
    /// stiffness matrix (see [`truncation`]). Empty when unknown (tabulated modes).
    pub static_flexibility: BTreeMap<String, f64>,
    /// The full structure's static cross flexibilities `G_PQ` (m/N, elastic part) between the
    /// named points, P ≠ Q: `static_cross_flexibility[P][Q]` is the displacement of P under a
    /// unit static force at Q ([`truncation::static_flexibility_matrix`]). Empty when unknown.
    pub static_cross_flexibility: BTreeMap<String, BTreeMap<String, f64>>,
    /// What building the structure did that a user should know (e.g. a spring treated as rigid).
    pub notes: Vec<String>,
    /// What building the structure found doubtful (ill-conditioning, modes missing below the
    /// selection cutoff). Each names the model field concerned.
    pub warnings: Vec<String>,
    /// The bed mass m_b (kg) an FE model tells by its elements labelled `part = "bed"` when
    /// every node of the bed contact point is on them (`Mesh::mass_of`, computed from the
    /// mesh the modes came from); `None` otherwise.
    pub bed_mass_kg: Option<f64>,
    /// Per retained mode, for a static-correction pseudo-mode ([`static_correction`]: a Ritz
    /// vector that restores the static flexibility of the modes left out, not a mode of the
    /// structure; its `mode_numbers` entry is 0 and its label "static correction j") the named
    /// point whose flexibility it carries most; `None` for a mode of the structure. Empty when
    /// the model has none (lumped, tabulated and imported structures, `static_correction =
    /// false`).
    pub pseudo_modes: Vec<Option<String>>,
    /// The file of imported modes (`[structure.modes]`) when neither it (UFF dataset 164) nor
    /// the model (`structure.modes.units`) states their units: read as SI, and checked
    /// against the slider by [`crate::model::Model::diagnostics`]. `None` for every other
    /// structure (SI by construction) and for stated units.
    pub unstated_units: Option<String>,
}

impl ModalModel {
    /// Builds a model with modal damping ratios ζ_i: `D = diag(2 ζ_i ω_i)`.
    pub fn with_damping_ratios(omega_rad_per_s: Vec<f64>, zeta: &[f64]) -> Result<Self> {
        let n = omega_rad_per_s.len();
        if zeta.len() != n {
            return Err(Error::invalid(
                "damping ratios",
                format!("{} ratios given for {} modes", zeta.len(), n),
            ));
        }
        let mut damping = vec![0.0; n * n];
        for i in 0..n {
            damping[i * n + i] = 2.0 * zeta[i] * omega_rad_per_s[i];
        }
        let labels = (1..=n).map(|i| format!("mode {i}")).collect();
        Ok(Self {
            omega_rad_per_s,
            damping,
            points: BTreeMap::new(),
            floor_force: None,
            labels,
            mode_numbers: (1..=n).collect(),
            effective_mass_kg: None,
            static_flexibility: BTreeMap::new(),
            static_cross_flexibility: BTreeMap::new(),
            notes: Vec::new(),
            warnings: Vec::new(),
            bed_mass_kg: None,
            pseudo_modes: Vec::new(),
            unstated_units: None,
        })
    }

    /// Number of retained modes.
    pub fn len(&self) -> usize {
        self.omega_rad_per_s.len()
    }

    /// True when no mode is retained.
    pub fn is_empty(&self) -> bool {
        self.omega_rad_per_s.is_empty()
    }

    /// Whether retained mode `i` (0-based) is a static-correction pseudo-mode
    /// ([`ModalModel::pseudo_modes`]).
    pub fn is_pseudo(&self, i: usize) -> bool {
        self.pseudo_modes.get(i).is_some_and(Option::is_some)
    }

    /// Mode-shape values at a named point.
    pub fn point(&self, name: &str) -> Result<&[f64]> {
        self.points.get(name).map(|v| v.as_slice()).ok_or_else(|| {
            let known: Vec<&str> = self.points.keys().map(|s| s.as_str()).collect();
            Error::invalid(
                "point",
                format!(
                    "no point named '{name}'; known points: {}",
                    known.join(", ")
                ),
            )
        })
    }

    /// Why a blow at `point` (the model field `field` names it) cannot be simulated when no
    /// retained mode moves it along the impact direction ([`immovable_point`]). `None` when a
    /// mode moves it, or when the model has no such point.
    pub fn immovable_point(&self, field: &str, point: &str) -> Option<String> {
        immovable_point(&format!("{field} = '{point}'"), self.points.get(point)?)
    }

    /// The same structure with a rigid point mass `mass_kg` fixed at point `point`, by
    /// Rayleigh-Ritz on the retained modes (exact when all modes of the structure are retained,
    /// e.g. a lumped model):
    ///
    /// ```text
    /// (I + m ψ ψᵀ) q̈ + D q̇ + Ω² q = 0,   ψ = Ψ(point);   solve Ω² y = λ (I + m ψ ψᵀ) y,
    /// q = Y q',  Ω'² = Yᵀ Ω² Y,  D' = Yᵀ D Y,  Ψ'(P) = Yᵀ Ψ(P).
    /// ```
    pub fn with_point_mass(&self, point: &str, mass_kg: f64) -> Result<ModalModel> {
        use faer::Mat;
        let n = self.len();
        let psi = self.point(point)?.to_vec();
        let mut k = Mat::<f64>::zeros(n, n);
        let mut m = Mat::<f64>::zeros(n, n);
        for i in 0..n {
            k[(i, i)] = self.omega_rad_per_s[i].powi(2);
            for j in 0..n {
                m[(i, j)] = mass_kg * psi[i] * psi[j] + if i == j { 1.0 } else { 0.0 };
            }
        }
        let modes = dense::solve(k.as_ref(), m.as_ref())?;
        let y = &modes.shapes;
        let project = |v: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|j| (0..n).map(|i| y[(i, j)] * v[i]).sum())
                .collect()
        };
        let mut damping = vec![0.0; n * n];
        for a in 0..n {
            for b in 0..n {
                let mut s = 0.0;
                for i in 0..n {
                    for j in 0..n {
                        s += y[(i, a)] * self.damping[i * n + j] * y[(j, b)];
                    }
                }
                damping[a * n + b] = s;
            }
        }
        let points = self
            .points
            .iter()
            .map(|(k, v)| (k.clone(), project(v)))
            .collect();
        let floor_force = self.floor_force.as_ref().map(|f| FloorForce {
            stiffness: project(&f.stiffness),
            damping: project(&f.damping),
        });
        Ok(ModalModel {
            omega_rad_per_s: modes.omega_rad_per_s,
            damping,
            points,
            floor_force,
            labels: (1..=n).map(|i| format!("mode {i}")).collect(),
            mode_numbers: (1..=n).collect(),
            effective_mass_kg: None,
            // A rigid mass changes no stiffness: without rigid-body modes G_PP is that of the
            // bare structure, and the Ritz basis keeps ψᵀΩ⁻²ψ (Y Ω'⁻² Yᵀ = Ω⁻² for
            // YᵀΩ²Y = Ω'²), so shares carry over. With rigid-body modes the elastic
            // (inertia-relief) flexibility depends on the mass distribution: unknown here.
            static_flexibility: if self.omega_rad_per_s.iter().all(|w| *w > 0.0) {
                self.static_flexibility.clone()
            } else {
                BTreeMap::new()
            },
            static_cross_flexibility: if self.omega_rad_per_s.iter().all(|w| *w > 0.0) {
                self.static_cross_flexibility.clone()
            } else {
                BTreeMap::new()
            },
            notes: self.notes.clone(),
            warnings: self.warnings.clone(),
            // The bare structure's bed, as the mass ratio md/mb means it.
            bed_mass_kg: self.bed_mass_kg,
            // The Ritz re-diagonalisation mixes pseudo-modes with structural ones.
            pseudo_modes: Vec::new(),
            unstated_units: self.unstated_units.clone(),
        })
    }

    /// Checks dimensions and finiteness.
    pub fn validate(&self) -> Result<()> {
        let n = self.len();
        if n == 0 {
            return Err(Error::invalid("modes", "the modal model has no modes"));
        }
        if self.damping.len() != n * n {
            return Err(Error::invalid(
                "damping",
                format!("expected {}x{} matrix", n, n),
            ));
        }
        for (i, w) in self.omega_rad_per_s.iter().enumerate() {
            if !w.is_finite() || *w < 0.0 {
                return Err(Error::invalid(
                    format!("mode {} frequency", i + 1),
                    format!("must be finite and >= 0 rad/s (got {w})"),
                ));
            }
        }
        if !(self.pseudo_modes.is_empty() || self.pseudo_modes.len() == n) {
            return Err(Error::invalid(
                "modes",
                format!(
                    "{} static-correction flags for {n} modes: give one per mode or none",
                    self.pseudo_modes.len()
                ),
            ));
        }
        if self.damping.iter().any(|d| !d.is_finite()) {
            return Err(Error::invalid(
                "damping",
                "modal damping matrix has a non-finite entry",
            ));
        }
        for (name, v) in &self.points {
            if v.len() != n {
                return Err(Error::invalid(
                    format!("point {name}"),
                    format!(
                        "{} mode-shape values for the {n} modes: give one value (1/√kg) per mode",
                        v.len()
                    ),
                ));
            }
            if let Some(k) = v.iter().position(|x| !x.is_finite()) {
                return Err(Error::invalid(
                    format!("point {name}"),
                    format!(
                        "the mode-shape value of mode {} ({} Hz) is {}: every value must be a finite number (1/√kg)",
                        k + 1,
                        crate::num(self.omega_rad_per_s[k] / (2.0 * std::f64::consts::PI)),
                        crate::num(v[k])
                    ),
                ));
            }
        }
        if let Some(f) = &self.floor_force {
            if f.stiffness.len() != n || f.damping.len() != n {
                return Err(Error::invalid(
                    "floor force",
                    format!("needs {n} coefficients per kind"),
                ));
            }
        }
        Ok(())
    }
}
