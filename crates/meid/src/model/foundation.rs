//! `[foundation]` and `[[receiver]]`: a rigid block on soil, its impedances, and the named
//! receivers around it (docs/explanations/foundation.md).
//!
//! # The block on the soil
//! `[foundation]` names the lumped mass that rests on the soil (`mass`, e.g. the floating base
//! or the block itself) and gives the block's plan `length` L × `width` B (m), its `height` h
//! and `embedment` depth D (m). A `block_mass` (kg), or a `block_density` (kg/m³) times
//! `L B h`, is **added** to that mass: the base and the block are one rigid body on the soil.
//! The soil is one of
//!
//! * an **elastic half-space**: `shear_modulus` G (Pa) or `shear_wave_velocity` V_s (m/s,
//!   G = ρ V_s²), `poisson` ν ∈ [0, 0.5), `density` ρ (kg/m³), `material_damping` D_m (ratio);
//! * IS 2974's **coefficient of elastic uniform compression** `uniform_compression` C_u (N/m³):
//!   `k_z = C_u L B` (and C_τ = 0.5 C_u, C_φ = 2 C_u, C_ψ = 0.75 C_u for the other directions);
//! * a spring and dashpot given directly: `stiffness_z` (N/m), `damping_z` (N·s/m).
//!
//! The vertical spring k_z and dashpot c_z join the mass to the ground as the lumped structure's
//! spring and **physical dashpot** named `soil` (`D = diag(2ζω) + ΦᵀCΦ`: the radiation damping is
//! not folded into the modal ζ). On a half-space they are the **Lysmer analog** (Lysmer &
//! Richart 1966) of a rigid disc of the block's area, `r0 = √(L B / π)`:
//!
//! `k_z = 4 G r0 / (1 − ν)`, `c_z = 3.4 r0² √(ρ G) / (1 − ν)`,
//!
//! plus `2 D_m √(k_z m)` for the soil's material damping (m: the mass on the soil), the
//! equivalent viscous dashpot of a hysteretic D_m at the block's own frequency √(k_z/m).
//! `radiation_damping = false` leaves c_z out. The other directions' impedances (Hall 1967;
//! Richart, Hall & Woods 1970; Gazetas 1991) are computed and reported by [`impedances`]; the
//! engine is one-axis, so only the vertical enters the dynamics.
//!
//! # Receivers
//! `[[receiver]]`: `name`, `distance` r (m) from the block's centre (beyond its equivalent
//! radius), `building` (DIN 4150-3's line: `"industrial"` = line 1, `"residential"` = line 2,
//! `"sensitive"` = line 3), optional `kind` (a label for people in the building) and
//! `people_limit` (m/s², the limit of the W_m-weighted acceleration the user sets).

use serde::Serialize;

pub use super::spec::{
    AllowableSpec, Excitation, FoundationSpec, GroundSpec, PadSpec, ReceiverSpec, SoilSpec,
};
use super::spec::{DashpotSpec, LumpedSpec, ModelSpec, SpringSpec};
use super::Source;
use crate::Result;

/// The name of the soil's spring and dashpot in the lumped structure.
pub const SOIL: &str = "soil";

/// DIN 4150-3's building classes, in line order.
pub const BUILDINGS: [&str; 3] = ["industrial", "residential", "sensitive"];

/// Standard gravity (m/s²), for the static soil pressure.
pub const G_N: f64 = 9.80665;

/// How the soil was given.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "form", rename_all = "kebab-case")]
pub enum Soil {
    HalfSpace {
        shear_modulus_pa: f64,
        poisson: f64,
        density_kg_per_m3: f64,
        material_damping: f64,
        radiation_damping: bool,
    },
    UniformCompression {
        c_u_n_per_m3: f64,
        damping_z_n_s_per_m: f64,
    },
    Direct {
        stiffness_z_n_per_m: f64,
        damping_z_n_s_per_m: f64,
    },
}

/// A validated `[foundation]`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Foundation {
    /// The lumped mass on the soil.
    pub mass_name: String,
    pub length_m: f64,
    pub width_m: f64,
    pub height_m: Option<f64>,
    pub embedment_m: f64,
    /// The block's own mass added to the lumped mass (kg, 0 when none is given).
    pub block_mass_kg: f64,
    /// Everything on the soil: the lumped mass plus the block (kg).
    pub mass_on_soil_kg: f64,
    pub soil: Soil,
    /// The vertical spring and dashpot to ground (N/m, N·s/m).
    pub k_z_n_per_m: f64,
    pub c_z_n_s_per_m: f64,
    /// Translational equivalent radius √(L B / π) (m): r1 of the attenuation law.
    pub equivalent_radius_m: f64,
    pub geometric_exponent: f64,
    pub attenuation_per_m: f64,
    pub excitation: Excitation,
    /// Why `excitation` is what it is when `foundation.excitation` is not given (the default
    /// and its reason); absent when the user gave it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub excitation_basis: Option<String>,
}

/// DIN 4150-3's class of excitation: the one given, else long-term with its reason. A
/// `[production] rate_bpm` repeats the blow, and repeated vibration is long-term; without a
/// stroke rate the model describes one blow of a machine that in production repeats it, and
/// the long-term guideline values are the lower ones at every frequency (Table 3 against
/// Table 1), so long-term is the conservative default.
pub fn excitation_of(
    given: Option<Excitation>,
    rate_bpm: Option<f64>,
) -> (Excitation, Option<String>) {
    match (given, rate_bpm) {
        (Some(e), _) => (e, None),
        (None, Some(r)) => (
            Excitation::LongTerm,
            Some(format!(
                "long-term by default: [production] rate_bpm = {} repeats the blow, and repeated vibration is long-term (DIN 4150-3); set foundation.excitation = \"short-term\" to say otherwise",
                crate::num(r)
            )),
        ),
        (None, None) => (
            Excitation::LongTerm,
            Some("long-term by default: the model gives no [production] rate_bpm, and a machine in production repeats its blow; the long-term limits are also the lower ones at every frequency, so the check is the conservative one. Set foundation.excitation = \"short-term\" for an occasional blow".into()),
        ),
    }
}

impl Foundation {
    /// Reads and checks `[foundation]` against the lumped structure `l`; errors name the field
    /// and the valid range.
    /// `rate_bpm` is the model's `[production] rate_bpm` (for the default excitation,
    /// [`excitation_of`]).
    pub fn from_spec(
        f: &FoundationSpec,
        l: &LumpedSpec,
        rate_bpm: Option<f64>,
        src: &Source,
    ) -> Result<Self> {
        let err = |field: &str, msg: String| src.error(field, format!("{field}: {msg}"));
        let positive = |field: &str, v: f64, unit: &str| -> Result<f64> {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(err(
                    field,
                    format!("must be a finite number > 0 {unit} (got {})", crate::num(v)),
                ))
            }
        };
        let Some(lumped_mass) = l.masses.iter().find(|m| m.name == f.mass) else {
            let known: Vec<&str> = l.masses.iter().map(|m| m.name.as_str()).collect();
            return Err(err(
                "foundation.mass",
                format!(
                    "unknown mass '{}'; valid: {} (the structure.lumped mass that rests on the soil)",
                    f.mass,
                    known.join(", ")
                ),
            ));
        };
        let length = positive("foundation.length", f.length, "m")?;
        let width = positive("foundation.width", f.width, "m")?;
        let height = f
            .height
            .map(|h| positive("foundation.height", h, "m"))
            .transpose()?;
        let embedment = f.embedment.unwrap_or(0.0);
        if !(embedment.is_finite() && embedment >= 0.0) {
            return Err(err(
                "foundation.embedment",
                format!(
                    "must be a finite depth >= 0 m (got {})",
                    crate::num(embedment)
                ),
            ));
        }
        match height {
            None if embedment > 0.0 => {
                return Err(err(
                    "foundation.embedment",
                    format!(
                        "an embedment of {} m needs the block's height: give foundation.height (the embedment must be within 0..=height)",
                        crate::num(embedment)
                    ),
                ))
            }
            Some(h) if embedment > h => {
                return Err(err(
                    "foundation.embedment",
                    format!(
                        "{} m is deeper than the block (foundation.height = {} m): valid 0..={} m",
                        crate::num(embedment),
                        crate::num(h),
                        crate::num(h)
                    ),
                ))
            }
            _ => {}
        }
        let block_mass = match (f.block_mass, f.block_density) {
            (Some(_), Some(_)) => {
                return Err(err(
                    "foundation.block_density",
                    "give foundation.block_mass or foundation.block_density, not both".into(),
                ))
            }
            (Some(m), None) => positive("foundation.block_mass", m, "kg")?,
            (None, Some(rho)) => {
                let rho = positive("foundation.block_density", rho, "kg/m³")?;
                let h = height.ok_or_else(|| {
                    err(
                        "foundation.block_density",
                        "needs foundation.height for the block's volume L·B·h".into(),
                    )
                })?;
                rho * length * width * h
            }
            (None, None) => 0.0,
        };
        let mass_on_soil = lumped_mass.mass + block_mass;
        let r0 = (length * width / std::f64::consts::PI).sqrt();
        let soil = soil_of(&f.soil, src)?;
        let (k_z, c_z) = match soil {
            Soil::HalfSpace {
                shear_modulus_pa: g,
                poisson: nu,
                density_kg_per_m3: rho,
                material_damping: dm,
                radiation_damping,
            } => {
                let (k, c) = lysmer(g, nu, rho, r0);
                let c_rad = if radiation_damping { c } else { 0.0 };
                (k, c_rad + 2.0 * dm * (k * mass_on_soil).sqrt())
            }
            Soil::UniformCompression {
                c_u_n_per_m3,
                damping_z_n_s_per_m,
            } => (c_u_n_per_m3 * length * width, damping_z_n_s_per_m),
            Soil::Direct {
                stiffness_z_n_per_m,
                damping_z_n_s_per_m,
            } => (stiffness_z_n_per_m, damping_z_n_s_per_m),
        };
        let n = f.ground.geometric_exponent.unwrap_or(0.5);
        if !(n.is_finite() && (0.0..=2.0).contains(&n)) {
            return Err(err(
                "foundation.ground.geometric_exponent",
                format!(
                    "must be in [0, 2] (0.5 surface waves, 1 body waves, 2 body waves along the surface; got {})",
                    crate::num(n)
                ),
            ));
        }
        let alpha = f.ground.attenuation.unwrap_or(0.0);
        if !(alpha.is_finite() && alpha >= 0.0) {
            return Err(err(
                "foundation.ground.attenuation",
                format!(
                    "must be a finite number >= 0 1/m (typically 0.0003 to 0.03 1/m at 5 Hz; got {})",
                    crate::num(alpha)
                ),
            ));
        }
        let (excitation, excitation_basis) = excitation_of(f.excitation, rate_bpm);
        Ok(Foundation {
            mass_name: f.mass.clone(),
            length_m: length,
            width_m: width,
            height_m: height,
            embedment_m: embedment,
            block_mass_kg: block_mass,
            mass_on_soil_kg: mass_on_soil,
            soil,
            k_z_n_per_m: k_z,
            c_z_n_s_per_m: c_z,
            equivalent_radius_m: r0,
            geometric_exponent: n,
            attenuation_per_m: alpha,
            excitation,
            excitation_basis,
        })
    }

    /// The lumped structure with the block's mass added to the mass on the soil and the soil's
    /// spring and dashpot (both named [`SOIL`]) to ground.
    pub fn augment(&self, l: &LumpedSpec) -> LumpedSpec {
        let mut out = l.clone();
        for m in &mut out.masses {
            if m.name == self.mass_name {
                m.mass += self.block_mass_kg;
            }
        }
        out.springs.push(SpringSpec {
            name: Some(SOIL.into()),
            nodes: [self.mass_name.clone(), "ground".into()],
            stiffness: self.k_z_n_per_m,
        });
        if self.c_z_n_s_per_m > 0.0 {
            out.dashpots.push(DashpotSpec {
                name: Some(SOIL.into()),
                nodes: [self.mass_name.clone(), "ground".into()],
                damping: self.c_z_n_s_per_m,
            });
        }
        out
    }

    /// The block's base area L·B (m²).
    pub fn area_m2(&self) -> f64 {
        self.length_m * self.width_m
    }
}

/// The soil of `s` (exactly one form), checked.
fn soil_of(s: &SoilSpec, src: &Source) -> Result<Soil> {
    let base = "foundation.soil";
    let err = |field: &str, msg: String| {
        let path = format!("{base}.{field}");
        src.error(&path, format!("{path}: {msg}"))
    };
    let half = s.shear_modulus.is_some() || s.shear_wave_velocity.is_some();
    let forms = usize::from(half)
        + usize::from(s.uniform_compression.is_some())
        + usize::from(s.stiffness_z.is_some());
    if forms != 1 {
        return Err(src.error(
            base,
            format!("{base}: give exactly one of: a half-space (shear_modulus or shear_wave_velocity, with poisson and density), uniform_compression (C_u, N/m³) or stiffness_z (N/m)"),
        ));
    }
    let nonneg = |field: &str, v: Option<f64>, unit: &str| -> Result<f64> {
        let v = v.unwrap_or(0.0);
        if v.is_finite() && v >= 0.0 {
            Ok(v)
        } else {
            Err(err(
                field,
                format!(
                    "must be a finite number >= 0 {unit} (got {})",
                    crate::num(v)
                ),
            ))
        }
    };
    let positive = |field: &str, v: f64, unit: &str| -> Result<f64> {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(err(
                field,
                format!("must be a finite number > 0 {unit} (got {})", crate::num(v)),
            ))
        }
    };
    if let Some(cu) = s.uniform_compression {
        return Ok(Soil::UniformCompression {
            c_u_n_per_m3: positive("uniform_compression", cu, "N/m³")?,
            damping_z_n_s_per_m: nonneg("damping_z", s.damping_z, "N·s/m")?,
        });
    }
    if let Some(k) = s.stiffness_z {
        return Ok(Soil::Direct {
            stiffness_z_n_per_m: positive("stiffness_z", k, "N/m")?,
            damping_z_n_s_per_m: nonneg("damping_z", s.damping_z, "N·s/m")?,
        });
    }
    if s.damping_z.is_some() {
        return Err(err(
            "damping_z",
            "is for a spring given directly (stiffness_z or uniform_compression); a half-space's dashpot follows from G, ν and ρ (switch it off with radiation_damping = false)".into(),
        ));
    }
    let rho = positive(
        "density",
        s.density.ok_or_else(|| {
            err(
                "density",
                "the half-space needs its density ρ (kg/m³)".into(),
            )
        })?,
        "kg/m³",
    )?;
    let nu = s.poisson.ok_or_else(|| {
        err(
            "poisson",
            "the half-space needs Poisson's ratio ν in [0, 0.5)".into(),
        )
    })?;
    if !(nu.is_finite() && (0.0..0.5).contains(&nu)) {
        return Err(err(
            "poisson",
            format!(
                "Poisson's ratio must be in [0, 0.5) (got {})",
                crate::num(nu)
            ),
        ));
    }
    let g = match (s.shear_modulus, s.shear_wave_velocity) {
        (Some(_), Some(_)) => {
            return Err(err(
                "shear_wave_velocity",
                "give shear_modulus or shear_wave_velocity, not both (G = ρ V_s²)".into(),
            ))
        }
        (Some(g), None) => positive("shear_modulus", g, "Pa")?,
        (None, Some(vs)) => rho * positive("shear_wave_velocity", vs, "m/s")?.powi(2),
        (None, None) => unreachable!("a half-space has one of them (forms == 1)"),
    };
    let dm = nonneg(
        "material_damping",
        s.material_damping,
        "(fraction of critical)",
    )?;
    if dm >= 1.0 {
        return Err(err(
            "material_damping",
            format!(
                "must be in [0, 1) (fraction of critical; soils 0.02 to 0.05; got {})",
                crate::num(dm)
            ),
        ));
    }
    Ok(Soil::HalfSpace {
        shear_modulus_pa: g,
        poisson: nu,
        density_kg_per_m3: rho,
        material_damping: dm,
        radiation_damping: s.radiation_damping.unwrap_or(true),
    })
}

/// The Lysmer analog of a rigid disc of radius `r0` on a half-space (Lysmer & Richart 1966):
/// `(k_z, c_z) = (4 G r0/(1 − ν), 3.4 r0² √(ρG)/(1 − ν))`.
pub fn lysmer(g: f64, nu: f64, rho: f64, r0: f64) -> (f64, f64) {
    (
        4.0 * g * r0 / (1.0 - nu),
        3.4 * r0 * r0 * (rho * g).sqrt() / (1.0 - nu),
    )
}

/// The receivers, checked against the foundation: a name given once, `distance` beyond the
/// block's equivalent radius, a known building class, a positive people limit.
pub fn check_receivers(spec: &ModelSpec, f: Option<&Foundation>, src: &Source) -> Result<()> {
    if spec.receiver.is_empty() {
        return Ok(());
    }
    let Some(f) = f else {
        return Err(src.error(
            "receiver",
            "receiver: receivers need a [foundation] (the block whose motion reaches them)",
        ));
    };
    for (i, r) in spec.receiver.iter().enumerate() {
        let base = format!("receiver[{i}]");
        if spec.receiver[..i].iter().any(|o| o.name == r.name) {
            let p = format!("{base}.name");
            return Err(src.error(&p, format!("{p}: '{}' is used twice", r.name)));
        }
        let p = format!("{base}.distance");
        if !(r.distance.is_finite() && r.distance > f.equivalent_radius_m) {
            return Err(src.error(
                &p,
                format!(
                    "{p}: {} m is not beyond the block's equivalent radius r1 = √(L B/π) = {:.4} m, where the attenuation law starts; valid: r > {:.4} m",
                    crate::num(r.distance),
                    f.equivalent_radius_m,
                    f.equivalent_radius_m
                ),
            ));
        }
        if !BUILDINGS.contains(&r.building.as_str()) {
            let p = format!("{base}.building");
            return Err(src.error(
                &p,
                format!(
                    "{p}: unknown building class '{}'; valid: \"industrial\" (DIN 4150-3 line 1), \"residential\" (line 2), \"sensitive\" (line 3)",
                    r.building
                ),
            ));
        }
        if let Some(l) = r.people_limit {
            if !(l.is_finite() && l > 0.0) {
                let p = format!("{base}.people_limit");
                return Err(src.error(
                    &p,
                    format!(
                        "{p}: must be a finite number > 0 m/s² (got {})",
                        crate::num(l)
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// One direction's impedance.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Impedance {
    /// "vertical", "horizontal", "rocking", "torsion".
    pub direction: &'static str,
    /// N/m or N·m/rad.
    pub stiffness: f64,
    /// N·s/m or N·m·s/rad; `None` where the source gives none (Gazetas' static stiffnesses) or
    /// an input is missing (the block's height for rocking).
    pub damping: Option<f64>,
    pub unit: &'static str,
    /// The equivalent radius used (m); `None` for the rectangle's own formulas.
    pub equivalent_radius_m: Option<f64>,
    pub source: &'static str,
}

/// Every impedance meid computes for the foundation (docs/explanations/foundation.md): the half-space's
/// analogs (Lysmer; Hall; Richart, Hall & Woods) and Gazetas' rectangle, or IS 2974's
/// coefficients of elastic compression; a spring given directly has only its vertical.
pub fn impedances(f: &Foundation) -> Vec<Impedance> {
    let (l, b) = (f.length_m, f.width_m);
    let m = f.mass_on_soil_kg;
    let pi = std::f64::consts::PI;
    let r0 = f.equivalent_radius_m;
    let vertical = |source: &'static str, r: Option<f64>| Impedance {
        direction: "vertical",
        stiffness: f.k_z_n_per_m,
        damping: Some(f.c_z_n_s_per_m),
        unit: "N/m",
        equivalent_radius_m: r,
        source,
    };
    // Mass moments of inertia of the block about its base's axes (a uniform block of the mass
    // on the soil): rocking in the L direction about the base's axis along B, torsion about z.
    let i_rock = f.height_m.map(|h| m * (l * l / 12.0 + h * h / 3.0));
    let i_tors = m * (l * l + b * b) / 12.0;
    match f.soil {
        Soil::Direct { .. } => vec![vertical(
            "given directly (foundation.soil.stiffness_z)",
            None,
        )],
        Soil::UniformCompression {
            c_u_n_per_m3: cu, ..
        } => {
            let i_area = b * l.powi(3) / 12.0;
            let j_area = l * b * (l * l + b * b) / 12.0;
            vec![
                vertical("IS 2974-1: k_z = C_u A", None),
                Impedance {
                    direction: "horizontal",
                    stiffness: 0.5 * cu * l * b,
                    damping: None,
                    unit: "N/m",
                    equivalent_radius_m: None,
                    source: "IS 2974-1: k_x = C_τ A, C_τ = 0.5 C_u",
                },
                Impedance {
                    direction: "rocking",
                    stiffness: 2.0 * cu * i_area,
                    damping: None,
                    unit: "N·m/rad",
                    equivalent_radius_m: None,
                    source: "IS 2974-1: k_φ = C_φ I, C_φ = 2 C_u, I = B L³/12",
                },
                Impedance {
                    direction: "torsion",
                    stiffness: 0.75 * cu * j_area,
                    damping: None,
                    unit: "N·m/rad",
                    equivalent_radius_m: None,
                    source: "IS 2974-1: k_ψ = C_ψ J, C_ψ = 0.75 C_u, J = L B (L² + B²)/12",
                },
            ]
        }
        Soil::HalfSpace {
            shear_modulus_pa: g,
            poisson: nu,
            density_kg_per_m3: rho,
            ..
        } => {
            let sq = (rho * g).sqrt();
            let r_rock = (b * l.powi(3) / (3.0 * pi)).powf(0.25);
            let r_tors = (l * b * (l * l + b * b) / (6.0 * pi)).powf(0.25);
            let k_rock = 8.0 * g * r_rock.powi(3) / (3.0 * (1.0 - nu));
            let c_rock = i_rock.map(|i| {
                let bp = 3.0 * (1.0 - nu) * i / (8.0 * rho * r_rock.powi(5));
                0.8 * r_rock.powi(4) * sq / ((1.0 - nu) * (1.0 + bp))
            });
            let k_tors = 16.0 * g * r_tors.powi(3) / 3.0;
            let bt = i_tors / (rho * r_tors.powi(5));
            let c_tors = 2.0 * 0.5 / (1.0 + 2.0 * bt) * (k_tors * i_tors).sqrt();
            let mut out = vec![
                vertical(
                    "Lysmer & Richart 1966: k_z = 4 G r0/(1 − ν), c_z = 3.4 r0² √(ρG)/(1 − ν) (+ 2 D_m √(k_z m))",
                    Some(r0),
                ),
                Impedance {
                    direction: "horizontal",
                    stiffness: 32.0 * (1.0 - nu) * g * r0 / (7.0 - 8.0 * nu),
                    damping: Some(18.4 * (1.0 - nu) * r0 * r0 * sq / (7.0 - 8.0 * nu)),
                    unit: "N/m",
                    equivalent_radius_m: Some(r0),
                    source: "Hall 1967: k_x = 32 (1 − ν) G r0/(7 − 8ν), c_x = 18.4 (1 − ν) r0² √(ρG)/(7 − 8ν)",
                },
                Impedance {
                    direction: "rocking",
                    stiffness: k_rock,
                    damping: c_rock,
                    unit: "N·m/rad",
                    equivalent_radius_m: Some(r_rock),
                    source: "Hall 1967: k_ψ = 8 G r0³/(3 (1 − ν)), c_ψ = 0.8 r0⁴ √(ρG)/((1 − ν)(1 + B_ψ)), B_ψ = 3 (1 − ν) I_ψ/(8 ρ r0⁵)",
                },
                Impedance {
                    direction: "torsion",
                    stiffness: k_tors,
                    damping: Some(c_tors),
                    unit: "N·m/rad",
                    equivalent_radius_m: Some(r_tors),
                    source: "Richart, Hall & Woods 1970: k_θ = 16 G r0³/3, c_θ = 2 D_θ √(k_θ I_θ), D_θ = 0.5/(1 + 2 B_θ), B_θ = I_θ/(ρ r0⁵)",
                },
            ];
            out.extend(gazetas(g, nu, l, b, f.embedment_m));
            out
        }
    }
}

/// Gazetas (1991) static stiffnesses of a rigid rectangle 2L' × 2B' (L' ≥ B') on a half-space,
/// and the vertical's embedment factor (sidewalls in full contact over the depth D).
fn gazetas(g: f64, nu: f64, length: f64, width: f64, d: f64) -> Vec<Impedance> {
    let lh = length.max(width) / 2.0;
    let bh = length.min(width) / 2.0;
    let chi = bh / lh;
    let i_bx = 4.0 * lh * bh.powi(3) / 3.0; // about the long axis
    let i_by = 4.0 * bh * lh.powi(3) / 3.0; // about the short axis
    let j = i_bx + i_by;
    let kz = 2.0 * g * lh / (1.0 - nu) * (0.73 + 1.54 * chi.powf(0.75));
    let ky = 2.0 * g * lh / (2.0 - nu) * (2.0 + 2.5 * chi.powf(0.85));
    let kx = ky - 0.2 / (0.75 - nu) * g * lh * (1.0 - chi);
    let krx = g / (1.0 - nu) * i_bx.powf(0.75) * (lh / bh).powf(0.25) * (2.4 + 0.5 * chi);
    let kry = 3.0 * g / (1.0 - nu) * i_by.powf(0.75) * (lh / bh).powf(0.15);
    let kt = 3.5 * g * j.powf(0.75) * chi.powf(0.4) * (j / bh.powi(4)).powf(0.2);
    let s = |direction, stiffness, unit, source| Impedance {
        direction,
        stiffness,
        damping: None,
        unit,
        equivalent_radius_m: None,
        source,
    };
    let mut out = vec![
        s("vertical", kz, "N/m", "Gazetas 1991, surface: K_z = 2GL/(1 − ν) (0.73 + 1.54 χ^0.75), χ = B/L"),
        s("horizontal", ky, "N/m", "Gazetas 1991, surface, across the long side: K_y = 2GL/(2 − ν) (2 + 2.5 χ^0.85)"),
        s("horizontal", kx, "N/m", "Gazetas 1991, surface, along the long side: K_x = K_y − 0.2/(0.75 − ν) G L (1 − B/L)"),
        s("rocking", krx, "N·m/rad", "Gazetas 1991, surface, about the long axis: K_rx = G/(1 − ν) I_bx^0.75 (L/B)^0.25 (2.4 + 0.5 B/L)"),
        s("rocking", kry, "N·m/rad", "Gazetas 1991, surface, about the short axis: K_ry = 3G/(1 − ν) I_by^0.75 (L/B)^0.15"),
        s("torsion", kt, "N·m/rad", "Gazetas 1991, surface: K_t = 3.5 G J^0.75 (B/L)^0.4 (J/B⁴)^0.2"),
    ];
    if d > 0.0 {
        let a_w = 4.0 * (lh + bh) * d;
        let a_b = 4.0 * lh * bh;
        let factor =
            (1.0 + d / (21.0 * bh) * (1.0 + 1.3 * chi)) * (1.0 + 0.2 * (a_w / a_b).powf(2.0 / 3.0));
        out.push(s(
            "vertical",
            kz * factor,
            "N/m",
            "Gazetas 1991, embedded (sidewalls in full contact): K_z [1 + D/(21B) (1 + 1.3χ)] [1 + 0.2 (A_w/A_b)^(2/3)]",
        ));
    }
    out
}
