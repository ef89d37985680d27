//! The isotropic material of a finite-element model file (`material`, `column_material`,
//! `bed.material`, …, shared by `[structure.fem.machine]` and `[structure.fem.model]`) and its
//! checks: the valid range of each value, and the unit check that refuses a material of another
//! unit system (mm-t-s, MPa beside kg/m³).

use serde::{Deserialize, Serialize};

use super::Source;
use crate::structure::Material;
use crate::Result;

/// Isotropic material (SI). Default steel.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Pa.
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    /// kg/m³.
    pub density: f64,
}

impl From<MaterialSpec> for Material {
    fn from(m: MaterialSpec) -> Self {
        Material {
            youngs_modulus_pa: m.youngs_modulus,
            poisson_ratio: m.poisson_ratio,
            density_kg_per_m3: m.density,
        }
    }
}

/// A material of a model file, refused at its field with the valid range.
pub fn check_material(m: &MaterialSpec, field: &str, src: &Source) -> Result<()> {
    let checks: [(&str, f64, bool, &str); 3] = [
        (
            "youngs_modulus",
            m.youngs_modulus,
            m.youngs_modulus.is_finite() && m.youngs_modulus > 0.0,
            "a finite number > 0 Pa",
        ),
        (
            "density",
            m.density,
            m.density.is_finite() && m.density > 0.0,
            "a finite number > 0 kg/m³",
        ),
        (
            "poisson_ratio",
            m.poisson_ratio,
            m.poisson_ratio > -1.0 && m.poisson_ratio < 0.5,
            "in (-1, 0.5)",
        ),
    ];
    for (key, v, ok, range) in checks {
        if !ok {
            let f = format!("{field}.{key}");
            return Err(src.error(&f, format!("{f} must be {range} (got {})", crate::num(v))));
        }
    }
    check_material_units(m, field, src)
}

/// Lightest solid meid accepts as a structural density, kg/m³ (silica aerogel, the lightest
/// solid made, is ~1 kg/m³; steel 7850).
pub const MIN_SOLID_DENSITY_KG_PER_M3: f64 = 1.0;
/// Range of the bar wave speed `c = sqrt(E/ρ)` of solids, m/s: soft rubber ~30 m/s (E = 1 MPa,
/// ρ = 1100 kg/m³), diamond ~17,300 m/s (E = 1050 GPa, ρ = 3510 kg/m³), steel 5,100 m/s.
pub const SOLID_WAVE_SPEED_RANGE_M_PER_S: [f64; 2] = [10.0, 2.0e4];

/// Refuses a material (given as valid positive numbers) whose values are those of another unit
/// system: meid's FE models are SI (m, kg, Pa, kg/m³), and a model in mm-t-s (steel:
/// E = 2.1e5 N/mm², ρ = 7.85e-9 t/mm³), or with E in MPa or GPa next to ρ in kg/m³, gives the
/// same frequencies as in SI when every input follows the same system, but masses, effective
/// masses, flexibilities and the coupling to the slider's and damper's kg and m/s wrong by powers
/// of 1000. Checked: `ρ ≥ MIN_SOLID_DENSITY_KG_PER_M3` and the bar wave speed
/// `c = sqrt(E/ρ)` within [`SOLID_WAVE_SPEED_RANGE_M_PER_S`] (mm-t-s steel: c = 5.2e6 "m/s";
/// E in MPa with ρ in kg/m³: c = 5.2 m/s).
pub fn check_material_units(m: &MaterialSpec, field: &str, src: &Source) -> Result<()> {
    let si = "meid's FE models are in SI units: m, kg, s, N, Pa, kg/m³ (steel: youngs_modulus = 2.1e11, density = 7850); a model in mm-t-s (E = 2.1e5, density = 7.85e-9) must be converted";
    if m.density < MIN_SOLID_DENSITY_KG_PER_M3 {
        let f = format!("{field}.density");
        return Err(src.error(
            &f,
            format!(
                "{f} = {} kg/m³ is lighter than any solid (>= {} kg/m³); {si}",
                crate::num(m.density),
                crate::num(MIN_SOLID_DENSITY_KG_PER_M3)
            ),
        ));
    }
    let c = (m.youngs_modulus / m.density).sqrt();
    let [lo, hi] = SOLID_WAVE_SPEED_RANGE_M_PER_S;
    if !(lo..=hi).contains(&c) {
        let f = format!("{field}.youngs_modulus");
        return Err(src.error(
            &f,
            format!(
                "{f} = {} Pa with density = {} kg/m³ gives a wave speed sqrt(E/ρ) = {c:.4e} m/s, outside that of solids ({lo:e} to {hi:e} m/s); {si}",
                crate::num(m.youngs_modulus),
                crate::num(m.density)
            ),
        ));
    }
    Ok(())
}
