//! Linear elastic isotropic material.

use crate::{Error, Result};

/// Linear elastic isotropic material (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Young's modulus E (Pa).
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio ν (-), in (-1, 0.5).
    pub poisson_ratio: f64,
    /// Mass density ρ (kg/m³).
    pub density_kg_per_m3: f64,
}

impl Material {
    /// Structural steel as used throughout meid: E = 2.06e11 Pa, ν = 0.3, ρ = 7850 kg/m³.
    pub const STEEL: Material = Material {
        youngs_modulus_pa: 2.06e11,
        poisson_ratio: 0.3,
        density_kg_per_m3: 7850.0,
    };

    /// Shear modulus G = E / (2 (1 + ν)) (Pa).
    pub fn shear_modulus_pa(&self) -> f64 {
        self.youngs_modulus_pa / (2.0 * (1.0 + self.poisson_ratio))
    }

    /// Checks E > 0, ρ > 0, -1 < ν < 0.5; `what` names the owner in the error.
    pub fn validate(&self, what: &str) -> Result<()> {
        if !(self.youngs_modulus_pa.is_finite() && self.youngs_modulus_pa > 0.0) {
            return Err(Error::invalid(
                format!("{what}: Young's modulus"),
                format!("must be > 0 Pa (got {})", self.youngs_modulus_pa),
            ));
        }
        if !(self.density_kg_per_m3.is_finite() && self.density_kg_per_m3 > 0.0) {
            return Err(Error::invalid(
                format!("{what}: density"),
                format!("must be > 0 kg/m^3 (got {})", self.density_kg_per_m3),
            ));
        }
        if !(self.poisson_ratio > -1.0 && self.poisson_ratio < 0.5) {
            return Err(Error::invalid(
                format!("{what}: Poisson's ratio"),
                format!("must lie in (-1, 0.5) (got {})", self.poisson_ratio),
            ));
        }
        Ok(())
    }
}

impl Default for Material {
    fn default() -> Self {
        Material::STEEL
    }
}
