//! Discrete elements: springs, dashpots, point masses and rigid links.
//!
//! * [`Spring`] / [`Dashpot`]: uncoupled per-direction springs (N/m, N·m/rad) or dashpots
//!   (N·s/m, N·m·s/rad) in global axes, between two nodes (`k [1 -1; -1 1]` per direction) or from
//!   a node to the ground (`k` on the diagonal). Those to the ground transmit their force to the
//!   floor (see [`super::FeModel::floor_force_functional`]).
//! * [`PointMass`]: lumped mass on the three translations and rotary inertia about the global axes
//!   through the node.
//! * [`RigidLink`]: a rigid body (RBE2-type) joining slave nodes to a master node. Eliminated
//!   by the master-slave transformation (Cook et al., *Concepts and Applications of FEA*, 4th ed.,
//!   §9.2): `u_s = u_m + θ_m × (x_s - x_m)`, `θ_s = θ_m`, so `K_r = Tᵀ K T` with the slave DOFs
//!   removed. Used as "spiders" that tie a column end to a patch of plate nodes.

use crate::{Error, Result};

/// A spring between a node and another node, or the ground when `other` is `None`.
#[derive(Debug, Clone, PartialEq)]
pub struct Spring {
    pub node: usize,
    pub other: Option<usize>,
    /// Stiffness per global direction `[x, y, z, rx, ry, rz]` (N/m for translations, N·m/rad for rotations).
    pub stiffness: [f64; 6],
}

/// A viscous dashpot between a node and another node, or the ground when `other` is `None`.
#[derive(Debug, Clone, PartialEq)]
pub struct Dashpot {
    pub node: usize,
    pub other: Option<usize>,
    /// Damping coefficient per global direction `[x, y, z, rx, ry, rz]` (N·s/m, N·m·s/rad).
    pub damping: [f64; 6],
}

/// A lumped mass with rotary inertia about the global axes through its node.
#[derive(Debug, Clone, PartialEq)]
pub struct PointMass {
    pub node: usize,
    pub mass_kg: f64,
    /// `[Ixx, Iyy, Izz]` (kg·m²).
    pub inertia_kg_m2: [f64; 3],
}

/// A rigid body joining `slaves` to `master` (all six DOFs of each slave are eliminated).
#[derive(Debug, Clone, PartialEq)]
pub struct RigidLink {
    pub master: usize,
    pub slaves: Vec<usize>,
}

pub(crate) fn check_coefficients(what: &str, unit: &str, v: &[f64]) -> Result<()> {
    for (i, x) in v.iter().enumerate() {
        if !(x.is_finite() && *x >= 0.0) {
            return Err(Error::invalid(
                what.to_string(),
                format!(
                    "component {} ({}) must be finite and >= 0 {unit} (got {x})",
                    i + 1,
                    ["x", "y", "z", "rx", "ry", "rz"]
                        .get(i)
                        .copied()
                        .unwrap_or("?")
                ),
            ));
        }
    }
    Ok(())
}
