//! Finite-element structures in model files (`[structure.fem]`): the general model
//! ([`super::general`]), the parametric machine of the paper's Fig. 1 (a generator of the
//! general model, [`crate::structure::machine`]) or a Gmsh quad mesh, solved for its modes and
//! reduced to the selected ones (paper Eq. 9).
//!
//! ```toml
//! [structure.fem]
//! select = "auto"            # or "participation", [6, 10] (1-based mode numbers), { band_hz = [1, 400] }
//! damping_ratios = 0.01      # one value, or one per selected mode; or rayleigh = [alpha, beta]
//! static_correction = true   # pseudo-modes restoring the static flexibility (default true)
//! solver = "dense"           # or "lanczos" (default: dense below 1000 DOF)
//! count = 30                 # modes computed (table length; Lanczos k)
//!
//! [structure.fem.machine]    # or [structure.fem.mesh] with a Gmsh file
//! elements_per_side = 8
//! bed = { length_x = 0.32, length_y = 0.20, thickness = 0.020 }
//! column = { diameter = 0.025 }
//! support = "floating-base"
//! base = { length_x = 0.50, length_y = 0.35, thickness = 0.030 }
//! spring_stiffness = [1.5e4, 1.5e4, 1.5e4]
//! ```
//!
//! Units: m, kg, N/m, N·s/m, Pa, kg/m³ (no suffixes in the file, see [`super`]).
//!
//! **Sign convention.** The FE model has z up and the slider moving in −z; it is assembled with
//! the impact direction `d = (0, 0, −1)`, so the point values `Ψ_i(P) = d · u_P(φ_i)` and the floor
//! force (`g · φ_i`, along d) that [`FeModel::modal_model`] returns are already along the impact
//! engine's +z (the slider's direction): no further flip is needed.
//!
//! **Automatic mode selection** (`select = "auto"`, the default). The named points are those
//! with a role, O_b, O_f and B (`contact_points` adds or replaces them). "auto" keeps
//!
//! 1. every mode up to the cutoff `f_c = 3 ω_c / 2π` (`auto_max_hz` to override) that moves a
//!    named point (`ψ_i(P)² > 1e-12 max_j ψ_j(P)²` at some P; a mode that moves none is never
//!    excited by the contact forces nor seen at B). `ω_c` is the highest contact frequency,
//!    `sqrt(K_s/m_s)` and `sqrt(K_d/m_d)` for linear contacts ([`contact_omega`] for Hertz and
//!    Hunt-Crossley). A contact of duration `T = π/ω_c` is a half-sine force pulse whose
//!    spectrum has its main lobe up to `3/(2T)` Hz = `3 ω_c/2π` (first zero of
//!    `|F(f)| ∝ |cos(π f T)/(1 − (2 f T)²)|` beyond the peak): modes below respond dynamically
//!    to the blow, modes above it mostly statically;
//! 2. then, above the cutoff, the modes with the largest share `ψ_i(P)²/(ω_i² G_PP)` of some
//!    point's static flexibility (see [`crate::modal::truncation`]), one at a time, until every
//!    named point's captured share reaches 95 % (at most `auto_count` of them; default no limit).
//!
//! So a low mode is never dropped in favour of a higher one, and a soft mode carrying a point's
//! flexibility (a plate's bounce on its springs) is always kept. `select = "participation"` is
//! the rule "auto" had before: the `auto_count` (default 2) modes with the largest
//! participation score `s_i = Σ_A ψ_i(A)²` (A = `contact_points`, default the named points)
//! among those up to `auto_max_hz` — it can drop a low mode; the truncation table then shows
//! what it lost. [`FemAnalysis`] carries the scores so `meid modes` can show why. The modes of
//! a repeated eigenvalue get a basis that does not depend on the solver
//! ([`crate::modal::eigenspace`]; one mode more than `count` is solved for it) and are kept
//! together by "auto" and "participation".
//!
//! **Static correction** (`static_correction = true`, the default): after the selection, the
//! selected modes are augmented by pseudo-modes, Ritz vectors built from the full model's static
//! responses `K⁻¹ f_P` at the named points minus what the selected modes carry of them
//! ([`crate::modal::static_correction`]): the reduced model then has the full model's static
//! flexibility `G_PQ` at those points (up to the pseudo-modes left out beyond the resolved
//! spread, with a note). Pseudo-modes are appended after the selected modes, labelled "static
//! correction j", mode number 0, flagged in [`ModalModel::pseudo_modes`]; their damping is
//! `α + β ω̃²` with Rayleigh damping (the exact projection) and, with modal ratios, the ratio of
//! the highest selected mode.
//!
//! **Rayleigh damping** `C = αM + βK` gives the modal damping `D_ii = α + β ω_i²`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Serialize;

pub use super::general::{parse_dofs, ConstraintSpec};
use super::material::{check_material, check_material_units};
pub use super::material::{
    MaterialSpec, MIN_SOLID_DENSITY_KG_PER_M3, SOLID_WAVE_SPEED_RANGE_M_PER_S,
};
pub use super::spec::{
    AddedMassFileSpec, FemSpec, GroupSpringSpec, MachineFileSpec, MeshFileSpec, PerDirection,
    PlateFileSpec, SectionFileSpec, SelectSpec, SolverSpec, SupportSpec,
};
use super::spec::{ContactSpec, LawSpec, ModelSpec, Ratios};
use super::{Model, Source};
use crate::modal::dense::{DenseModes, DEFAULT_RELATIVE_SHIFT};
use crate::modal::lanczos::{self, LanczosOptions};
use crate::modal::{static_correction, truncation, ModalModel};
use crate::structure::machine::{AddedMass, Plate, PlateSpec};
use crate::structure::{FeModel, MachineSpec, Material, Mesh, ModeTable, Section, Support};
use crate::{Error, Result};

/// What reducing a structure to modes needs from the rest of the model: the contact frequencies
/// (for the "auto" selection's cutoff and the rigid-limit test of lumped springs) and the points
/// with a role (for the selection and the truncation table).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ReductionContext {
    /// The highest contact frequency ω_c (rad/s) of the slider-bed and bed-damper contacts
    /// ([`contact_omega`]); 0 when none is known.
    pub contact_omega_rad_per_s: f64,
    /// The named points with a role: (name, roles) for O_b (`bed_contact`), O_f
    /// (`damper_anchor`, unless "ground") and B (`measurement`), in that order, merged by name.
    pub role_points: Vec<(String, Vec<String>)>,
}

impl ReductionContext {
    /// The context of a model spec. Invalid masses or stiffnesses give no contact frequency
    /// (validation reports them later).
    pub fn of(spec: &ModelSpec) -> Self {
        let mut role_points: Vec<(String, Vec<String>)> = Vec::new();
        let mut add = |name: &str, role: &str| match role_points.iter_mut().find(|(n, _)| n == name)
        {
            Some((_, r)) => r.push(role.to_string()),
            None => role_points.push((name.to_string(), vec![role.to_string()])),
        };
        add(&spec.points.bed_contact, "bed_contact");
        if let Some(a) = spec.points.damper_anchor.as_deref() {
            if a != "ground" {
                add(a, "damper_anchor");
            }
        }
        add(&spec.points.measurement, "measurement");
        let v = spec.slider.velocity.abs();
        let mut w = contact_omega(&spec.contact.slider_bed, spec.slider.mass, v).unwrap_or(0.0);
        if let (Some(d), Some(c)) = (&spec.damper, &spec.contact.bed_damper) {
            // The bed hits the damper at most at about 2 v_s (an elastic blow on a bed at rest).
            w = w.max(contact_omega(c, d.mass, 2.0 * v).unwrap_or(0.0));
        }
        Self {
            contact_omega_rad_per_s: w,
            role_points,
        }
    }
}

/// `∫₀¹ dx / sqrt(1 − x^p)` (p > 0): with `x = 1 − u²` the integrand `2u / sqrt(1 − (1 − u²)^p)`
/// is bounded (→ 2/√p at u = 0); composite Simpson with 4000 panels. `p = 2` gives π/2; in
/// general `√π Γ(1 + 1/p) / Γ(1/2 + 1/p)`.
fn half_period_integral(p: f64) -> f64 {
    let f = |u: f64| {
        if u == 0.0 {
            2.0 / p.sqrt()
        } else {
            2.0 * u / (1.0 - (1.0 - u * u).powf(p)).sqrt()
        }
    };
    let n = 4000;
    let h = 1.0 / n as f64;
    let mut s = f(0.0) + f(1.0);
    for i in 1..n {
        s += if i % 2 == 1 { 4.0 } else { 2.0 } * f(i as f64 * h);
    }
    s * h / 3.0
}

/// The contact frequency `ω_c = π / T_c` (rad/s) of a body of mass `m` (kg) striking a rigid
/// wall at speed `v` (m/s) through the contact law `F = K δ^n`: `T_c` is the contact duration,
///
/// ```text
/// T_c = 2 (δ_max / v) ∫₀¹ dx / sqrt(1 − x^(n+1)),   δ_max = ((n + 1) m v² / (2K))^(1/(n+1)),
/// ```
///
/// which for the linear law (n = 1) is `π sqrt(m/K)`, so `ω_c = sqrt(K/m)` whatever v; for Hertz
/// (n = 1.5) it is `2.9432 δ_max / v`. Damping (C, α) is ignored. `None` for invalid inputs or a
/// nonlinear law at v = 0.
pub fn contact_omega(c: &ContactSpec, m: f64, v: f64) -> Option<f64> {
    let k = c.stiffness;
    if !(k.is_finite() && k > 0.0 && m.is_finite() && m > 0.0) {
        return None;
    }
    let n = match c.law {
        LawSpec::Linear => return Some((k / m).sqrt()),
        LawSpec::Hertz => 1.5,
        LawSpec::HuntCrossley => c.exponent.unwrap_or(1.5),
        // No contact frequency: the impacts are instantaneous.
        LawSpec::Rigid => return None,
    };
    if !(n.is_finite() && n > 0.0 && v.is_finite() && v > 0.0) {
        return None;
    }
    let p = n + 1.0;
    let d_max = (p * m * v * v / (2.0 * k)).powf(1.0 / p);
    let t = 2.0 * d_max / v * half_period_integral(p);
    Some(std::f64::consts::PI / t)
}

/// Below this many DOFs the default solver is the dense one (measured: the dense solver takes
/// ~3 s at 1,500 DOFs, the Lanczos solver 0.3-0.7 s for 30 modes up to 5,000 DOFs).
pub const DENSE_LIMIT_DOFS: usize = 1000;

/// How modes were selected, for reports.
#[derive(Debug, Clone, PartialEq)]
pub enum Selection {
    Indices,
    Band([f64; 2]),
    /// Every participating mode up to `cutoff_hz`, plus `extra` modes above it.
    Auto {
        cutoff_hz: f64,
        extra: usize,
        points: Vec<String>,
    },
    /// The `count` modes with the largest participation score.
    Participation {
        count: usize,
        points: Vec<String>,
    },
}

/// Everything `meid modes` shows: the model, all computed modes, the table and the selection.
#[derive(Debug, Clone)]
pub struct FemAnalysis {
    pub model: FeModel,
    pub modes: DenseModes,
    pub table: ModeTable,
    /// "dense" or "lanczos".
    pub solver: &'static str,
    /// Selected modes (0-based, ascending).
    pub selected: Vec<usize>,
    pub selection: Selection,
    /// Participation score `Σ_A ψ_i(A)²` (1/kg) per computed mode at `score_points`.
    pub scores: Vec<f64>,
    pub score_points: Vec<String>,
    /// Relative residual of each selected mode.
    pub selected_residuals: Vec<f64>,
    /// The reduced model.
    pub modal: ModalModel,
}

fn material(m: &Option<MaterialSpec>, default: Material) -> Material {
    m.map(Material::from).unwrap_or(default)
}

fn plate(p: &PlateFileSpec, default_material: Material) -> PlateSpec {
    PlateSpec {
        length_x_m: p.length_x,
        length_y_m: p.length_y,
        thickness_m: p.thickness,
        material: material(&p.material, default_material),
    }
}

fn section(s: &SectionFileSpec) -> Result<Section> {
    match (s.diameter, s.wall, s.width, s.depth, s.area) {
        (Some(d), None, None, None, None) => Section::solid_circle(d),
        (Some(d), Some(w), None, None, None) => Section::tube(d, w),
        (None, None, Some(b), Some(h), None) => Section::solid_rectangle(b, h),
        (None, Some(w), Some(b), Some(h), None) => Section::rectangular_tube(b, h, w),
        (None, None, None, None, Some(a)) => match (s.iy, s.iz, s.j) {
            (Some(iy), Some(iz), Some(j)) => Section::new(a, iy, iz, j),
            _ => Err(Error::invalid("column", "with `area` give `iy`, `iz` and `j` (m⁴)")),
        },
        _ => Err(Error::invalid(
            "column",
            "give `diameter` (solid circle), `diameter` + `wall` (tube), `width` + `depth` (solid rectangle), `width` + `depth` + `wall` (rectangular tube), or `area`, `iy`, `iz`, `j`",
        )),
    }
}

/// A plate whose sizes are valid one by one can still leave double precision: its mass
/// `ρ L_x L_y t` or its bending rigidity `D = E t³ / (12 (1 − ν²))` overflowing or underflowing
/// (a thickness of 1e-308 m gives D = 0, a length of 1e308 m an infinite mass). Refused naming
/// the plate's length or thickness (`key` is `bed` or `base`); sizes that are not finite and
/// > 0 are left to the structure library's own message.
fn check_plate_scale(p: &PlateSpec, key: &str) -> Result<()> {
    let sizes = [p.length_x_m, p.length_y_m, p.thickness_m];
    let mat = &p.material;
    if sizes.iter().any(|v| !(v.is_finite() && *v > 0.0))
        || !(mat.density_kg_per_m3.is_finite() && mat.density_kg_per_m3 > 0.0)
        || !(mat.youngs_modulus_pa.is_finite() && mat.youngs_modulus_pa > 0.0)
        || !(mat.poisson_ratio > -1.0 && mat.poisson_ratio < 0.5)
    {
        return Ok(());
    }
    let mass = mat.density_kg_per_m3 * p.length_x_m * p.length_y_m * p.thickness_m;
    let t = p.thickness_m;
    if let Some(msg) = super::general::thickness_fault(t, p.length_x_m.hypot(p.length_y_m)) {
        return Err(Error::invalid(format!("{key}.thickness"), msg));
    }
    let d =
        mat.youngs_modulus_pa * t * t * t / (12.0 * (1.0 - mat.poisson_ratio * mat.poisson_ratio));
    if !d.is_normal() {
        return Err(Error::invalid(
            format!("{key}.thickness"),
            format!(
                "t = {t} m gives the plate a bending rigidity E t³/(12(1−ν²)) = {d:e} N·m that double precision cannot carry (it must be a normal number, between {:e} and {:e}); give a plate thickness in metres",
                f64::MIN_POSITIVE,
                f64::MAX
            ),
        ));
    }
    if !mass.is_normal() {
        let (field, v) = if p.length_x_m >= p.length_y_m {
            ("length_x", p.length_x_m)
        } else {
            ("length_y", p.length_y_m)
        };
        return Err(Error::invalid(
            format!("{key}.{field}"),
            format!(
                "{v} m gives the plate a mass ρ L_x L_y t = {mass:e} kg that double precision cannot carry; give the plate's sides in metres"
            ),
        ));
    }
    Ok(())
}

/// The [`MachineSpec`] a `[structure.fem.machine]` table describes.
pub fn machine_spec(m: &MachineFileSpec) -> Result<MachineSpec> {
    let mut spec = MachineSpec::default();
    let mat = material(&m.material, Material::STEEL);
    spec.bed.material = mat;
    spec.column_material = material(&m.column_material, mat);
    if let Some(b) = &m.bed {
        spec.bed = plate(b, mat);
    }
    if let Some(c) = &m.column {
        spec.column_section = section(c)?;
    }
    if let Some(v) = m.column_length {
        spec.column_length_m = v;
    }
    if let Some(v) = m.column_inset {
        spec.column_inset_m = v;
    }
    if let Some(v) = m.column_elements {
        spec.column_elements = v;
    }
    if let Some(v) = m.elements_per_side {
        spec.elements_per_side = v;
    }
    if let Some(v) = m.b_offset {
        spec.b_offset_m = v;
    }
    spec.bed_points_m = m.bed_points.iter().map(|(k, v)| (k.clone(), *v)).collect();
    if let Some(v) = m.spiders {
        spec.spiders = v;
    }
    if let Some(v) = m.spider_half_size {
        spec.spider_half_size_m = v;
    }
    match m.support.unwrap_or(SupportSpec::FloatingBase) {
        SupportSpec::FixedColumns => {
            if m.base.is_some() || m.spring_stiffness.is_some() || m.spring_damping.is_some() {
                return Err(Error::invalid(
                    "support",
                    "\"fixed-columns\" has no floating base: remove `base`, `spring_stiffness` and `spring_damping`",
                ));
            }
            spec.support = Support::FixedColumns;
        }
        SupportSpec::FloatingBase => {
            if let Support::FloatingBase {
                base,
                spring_stiffness_n_per_m,
                spring_damping_n_s_per_m,
                spring_inset_m,
            } = &mut spec.support
            {
                base.material = mat;
                if let Some(b) = &m.base {
                    *base = plate(b, mat);
                }
                if let Some(k) = &m.spring_stiffness {
                    *spring_stiffness_n_per_m = k.xyz();
                }
                if let Some(c) = &m.spring_damping {
                    *spring_damping_n_s_per_m = c.xyz();
                }
                if let Some(v) = m.spring_inset {
                    *spring_inset_m = v;
                }
            }
        }
    }
    check_plate_scale(&spec.bed, "bed")?;
    if let Support::FloatingBase { base, .. } = &spec.support {
        check_plate_scale(base, "base")?;
    }
    for (i, a) in m.added_masses.iter().enumerate() {
        let plate = match a.plate.as_str() {
            "bed" => Plate::Bed,
            "base" => Plate::Base,
            other => {
                return Err(Error::invalid(
                    format!("added_masses[{i}].plate"),
                    format!("unknown plate '{other}'; valid: bed, base"),
                ))
            }
        };
        if !(a.mass.is_finite() && a.mass > 0.0) {
            return Err(Error::invalid(
                format!("added_masses[{i}].mass"),
                format!("must be > 0 kg (got {})", crate::num(a.mass)),
            ));
        }
        if !a.offset.iter().all(|v| v.is_finite()) {
            return Err(Error::invalid(
                format!("added_masses[{i}].offset"),
                format!(
                    "must be two finite numbers [x, y] m from the plate centre (got {:?})",
                    a.offset
                ),
            ));
        }
        if let Some(inertia) = a.inertia {
            if !inertia.iter().all(|v| v.is_finite() && *v >= 0.0) {
                return Err(Error::invalid(
                    format!("added_masses[{i}].inertia"),
                    format!(
                        "must be three finite numbers >= 0 kg·m² [Ixx, Iyy, Izz] (got {inertia:?})"
                    ),
                ));
            }
        }
        spec.added_masses.push(AddedMass {
            plate,
            offset_m: a.offset,
            mass_kg: a.mass,
            inertia_kg_m2: a.inertia.unwrap_or([0.0; 3]),
        });
    }
    Ok(spec)
}

/// The unit check of [`super::material::check_material_units`] on the materials of a `[structure.fem.machine]`
/// (`material`, `column_material`, `bed.material`, `base.material`). A material whose values are
/// not positive is left to the machine's own validation, which names it.
fn check_machine_units(m: &MachineFileSpec, src: &Source) -> Result<()> {
    let base = "structure.fem.machine";
    let mats = [
        (m.material.as_ref(), format!("{base}.material")),
        (
            m.column_material.as_ref(),
            format!("{base}.column_material"),
        ),
        (
            m.bed.as_ref().and_then(|b| b.material.as_ref()),
            format!("{base}.bed.material"),
        ),
        (
            m.base.as_ref().and_then(|b| b.material.as_ref()),
            format!("{base}.base.material"),
        ),
    ];
    for (mat, field) in mats {
        if let Some(mat) = mat {
            let positive = |v: f64| v.is_finite() && v > 0.0;
            if positive(mat.density) && positive(mat.youngs_modulus) {
                check_material_units(mat, &field, src)?;
            }
        }
    }
    Ok(())
}

fn mesh_model(ms: &MeshFileSpec, src: &Source) -> Result<FeModel> {
    let base = "structure.fem.mesh";
    let dir = Path::new(&src.name)
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    let path: PathBuf = dir.join(&ms.file);
    if !(ms.thickness.is_finite() && ms.thickness > 0.0) {
        return Err(src.error(
            &format!("{base}.thickness"),
            format!(
                "{base}.thickness must be > 0 m (got {})",
                crate::num(ms.thickness)
            ),
        ));
    }
    if let Some(m) = &ms.material {
        check_material(m, &format!("{base}.material"), src)?;
    }
    let g = crate::structure::gmsh::read_msh(&path)?;
    if g.quads.is_empty() && g.triangles.is_empty() {
        return Err(src.error(
            &format!("{base}.file"),
            format!("{base}.file: {} has no 4-node quadrangles or 3-node triangles; [structure.fem.mesh] reads shell meshes (frames from 2-node lines: use [structure.fem.model])", path.display()),
        ));
    }
    let mut mesh = Mesh::new();
    let map = g
        .add_to_mesh(
            &mut mesh,
            material(&ms.material, Material::STEEL),
            ms.thickness,
        )
        .map_err(|e| src.error(&format!("{base}.file"), format!("{}: {e}", path.display())))?;
    let extent = super::general::bounding_diagonal(mesh.nodes.iter().copied());
    if let Some(msg) = super::general::thickness_fault(ms.thickness, extent) {
        return Err(src.error(
            &format!("{base}.thickness"),
            format!("{base}.thickness: {msg} (the mesh {})", ms.file),
        ));
    }
    let pairs = super::general::coincident_node_pairs(&mesh);
    if let Some(&(i, j)) = pairs.first() {
        let name = |m: usize| match map.iter().position(|&x| x == Some(m)) {
            Some(k) => format!("node {} of {}", g.node_tags[k], ms.file),
            None => format!("node {m}"),
        };
        let f = format!("{base}.file");
        return Err(src.error(
            &f,
            format!(
                "{f}: {}",
                super::general::coincident_message(&name(i), &name(j), mesh.nodes[i], pairs.len())
            ),
        ));
    }
    let group = |name: &str, field: &str, mesh: &Mesh| -> Result<Vec<usize>> {
        mesh.point(name)
            .map(|v| v.to_vec())
            .map_err(|e| src.error(field, format!("{field}: {e}")))
    };
    for (model_name, gname) in &ms.points {
        let nodes = group(gname, &format!("{base}.points.{model_name}"), &mesh)?;
        mesh.name_point(model_name.clone(), nodes);
    }
    for (i, gname) in ms.fixed.iter().enumerate() {
        for n in group(gname, &format!("{base}.fixed[{i}]"), &mesh)? {
            mesh.fix_all(n);
        }
    }
    for (i, c) in ms.constraints.iter().enumerate() {
        let field = format!("{base}.constraints[{i}]");
        let dofs = parse_dofs(&c.dofs, &format!("{field}.dofs"))
            .map_err(|e| src.error(&format!("{field}.dofs"), e.to_string()))?;
        for n in group(&c.set, &format!("{field}.set"), &mesh)? {
            mesh.fix(n, &dofs);
        }
    }
    for (i, s) in ms.springs.iter().enumerate() {
        let field = format!("{base}.springs[{i}]");
        let k = s.stiffness.xyz();
        let c = s.damping.as_ref().map(|c| c.xyz()).unwrap_or([0.0; 3]);
        for n in group(&s.group, &format!("{field}.group"), &mesh)? {
            if k.iter().any(|&v| v != 0.0) {
                mesh.add_spring(crate::structure::Spring {
                    node: n,
                    other: None,
                    stiffness: [k[0], k[1], k[2], 0.0, 0.0, 0.0],
                });
            }
            if c.iter().any(|&v| v != 0.0) {
                mesh.add_dashpot(crate::structure::Dashpot {
                    node: n,
                    other: None,
                    damping: [c[0], c[1], c[2], 0.0, 0.0, 0.0],
                });
            }
        }
    }
    let d = ms.impact_direction.unwrap_or([0.0, 0.0, -1.0]);
    let norm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return Err(src.error(
            &format!("{base}.impact_direction"),
            "impact_direction must be a nonzero vector",
        ));
    }
    FeModel::assemble_with_direction(mesh, [d[0] / norm, d[1] / norm, d[2] / norm])
        .map_err(|e| src.error(base, format!("{base}: {e}")))
}

/// The general model (`[structure.fem.model]`) a `[structure.fem.machine]` table generates
/// ([`MachineSpec::generate`]); errors name the machine's fields.
pub fn machine_general(m: &MachineFileSpec, src: &Source) -> Result<super::general::GeneralSpec> {
    let field = "structure.fem.machine";
    check_machine_units(m, src)?;
    machine_spec(m)
        .and_then(|ms| ms.generate())
        .map(|g| g.spec)
        .map_err(|e| locate(e, field, src, Some(m)))
}

/// Builds the finite-element model the spec describes (no modes yet).
pub fn build_model(spec: &FemSpec, src: &Source) -> Result<FeModel> {
    match (&spec.machine, &spec.mesh, &spec.model) {
        (None, None, Some(g)) => super::general::build(g, src),
        (Some(m), None, None) => {
            let field = "structure.fem.machine";
            check_machine_units(m, src)?;
            let ms = machine_spec(m).map_err(|e| locate(e, field, src, Some(m)))?;
            ms.build()
                .map(|mach| mach.model)
                .map_err(|e| locate(e, field, src, Some(m)))
        }
        (None, Some(ms), None) => mesh_model(ms, src),
        _ => Err(src.error(
            "structure.fem",
            "structure.fem: give exactly one of [structure.fem.machine] (parametric machine), [structure.fem.mesh] (Gmsh quad mesh) or [structure.fem.model] (general model)",
        )),
    }
}

/// The `[structure.fem.machine]` key (relative path) of a field named by the structure library
/// ([`crate::structure::machine`], [`Material`], [`Section`]): "bed thickness" is
/// `bed.thickness`, "column: density" is `column_material.density` (or `material.density`
/// when the file gives no column material), ... `None` when the library's name has no key.
fn machine_key(field: &str, m: Option<&MachineFileSpec>) -> Option<String> {
    let plate_key = |what: &str| match what {
        "bed" => Some("bed"),
        "floating base" => Some("base"),
        _ => None,
    };
    // Plate sizes: "bed length x", "floating base thickness".
    for what in ["bed", "floating base"] {
        if let Some(rest) = field.strip_prefix(what).and_then(|r| r.strip_prefix(' ')) {
            let key = match rest {
                "length x" => "length_x",
                "length y" => "length_y",
                "thickness" => "thickness",
                _ => continue,
            };
            return Some(format!("{}.{key}", plate_key(what)?));
        }
    }
    // Materials: "bed: Young's modulus", "floating base: density", "column: Poisson's ratio".
    if let Some((what, prop)) = field.split_once(": ") {
        let key = match prop {
            "Young's modulus" => Some("youngs_modulus"),
            "density" => Some("density"),
            "Poisson's ratio" => Some("poisson_ratio"),
            _ => None,
        };
        if let Some(key) = key {
            let own = match what {
                "bed" => m
                    .and_then(|m| m.bed.as_ref())
                    .and_then(|b| b.material.as_ref())
                    .map(|_| "bed.material"),
                "floating base" => m
                    .and_then(|m| m.base.as_ref())
                    .and_then(|b| b.material.as_ref())
                    .map(|_| "base.material"),
                "column" => m
                    .and_then(|m| m.column_material.as_ref())
                    .map(|_| "column_material"),
                _ => return None,
            };
            return Some(format!("{}.{key}", own.unwrap_or("material")));
        }
        // Sections derived from sizes: the sizes the file gives.
        if what == "section" {
            let c = m.and_then(|m| m.column.as_ref());
            let given = c.map(|c| {
                [
                    ("diameter", c.diameter),
                    ("wall", c.wall),
                    ("width", c.width),
                    ("depth", c.depth),
                    ("area", c.area),
                ]
                .iter()
                .filter(|(_, v)| v.is_some())
                .map(|(k, _)| format!("column.{k}"))
                .collect::<Vec<_>>()
            });
            return Some(match given {
                Some(g) if !g.is_empty() => g.join(" / structure.fem.machine."),
                _ => "column".to_string(),
            });
        }
        // Sections: "column section: area A (m^2)".
        if what == "column section" {
            let key = match prop.split(' ').next() {
                Some("area") => "area",
                Some("Iy") => "iy",
                Some("Iz") => "iz",
                Some("torsion") => "j",
                _ => return None,
            };
            return Some(format!("column.{key}"));
        }
    }
    let key = match field {
        "column length" => "column_length",
        "column inset" => "column_inset",
        "spring inset" => "spring_inset",
        "spider half-size" => "spider_half_size",
        "spring stiffness" => "spring_stiffness",
        "spring damping" => "spring_damping",
        "tube wall" | "rectangular tube wall" => "column.wall",
        "tube outer diameter" | "circle diameter" => "column.diameter",
        "rectangle width" | "rectangular tube width" => "column.width",
        "rectangle depth" | "rectangular tube depth" => "column.depth",
        "column" => "column",
        f if f.starts_with("frame element") => "column_length",
        "support" => "support",
        "point B" => "b_offset",
        "added mass on the bed" | "added mass on the base" | "added mass" => "added_masses",
        "mesh density" => {
            let eps = m.and_then(|m| m.elements_per_side).unwrap_or(8);
            if (2..=400).contains(&eps) {
                "column_elements"
            } else {
                "elements_per_side"
            }
        }
        f if f.starts_with("added_masses[")
            || f.starts_with("bed.")
            || f.starts_with("base.")
            || f.starts_with("bed_points.") =>
        {
            return Some(f.to_string())
        }
        _ => return None,
    };
    Some(key.to_string())
}

/// An `InvalidValue` from the structure library, placed at its `[structure.fem.machine]` key
/// ([`machine_key`]) when it has one, else at `base.field`.
fn locate(e: Error, base: &str, src: &Source, m: Option<&MachineFileSpec>) -> Error {
    match e {
        Error::InvalidValue { field, message } => match machine_key(&field, m) {
            Some(key) => {
                let path = format!("{base}.{key}");
                Error::Input {
                    location: src.locate(&path),
                    message: format!("{path}: {message}"),
                }
            }
            None => {
                let key = field.replace(' ', "_");
                let path = format!("{base}.{key}");
                Error::Input {
                    location: src.locate(&path),
                    message: format!("{base}: {field}: {message}"),
                }
            }
        },
        other => other,
    }
}

fn to_dense(s: lanczos::SparseModes) -> DenseModes {
    DenseModes {
        eigenvalues: s.eigenvalues,
        omega_rad_per_s: s.omega_rad_per_s,
        shapes: s.shapes,
        orthonormality_error: s.orthonormality_error,
        max_residual: s.max_residual,
        rigid_body_modes: s.rigid_body_modes,
    }
}

/// Solves the modes of `model`: dense (all modes, the lowest `count` kept for tables) or Lanczos
/// (the lowest `count`). Returns the modes and the solver's name.
pub fn solve_modes(
    model: &FeModel,
    solver: Option<SolverSpec>,
    count: usize,
) -> Result<(DenseModes, &'static str)> {
    solve_modes_sharing(model, solver, count, &mut None)
}

/// [`solve_modes`], keeping the sparse solver's symbolic analysis of `K − σM` in `pencil` for
/// the static deflections ([`full_static_flexibility`]).
fn solve_modes_sharing(
    model: &FeModel,
    solver: Option<SolverSpec>,
    count: usize,
    pencil: &mut Option<lanczos::ShiftedPencil>,
) -> Result<(DenseModes, &'static str)> {
    let n = model.n_dofs();
    if solver.is_none() && n < DENSE_LIMIT_DOFS {
        // The automatic choice: dense, and when its solution fails the check (the dense
        // shift-invert loses accuracy on modes far below its shift, e.g. a soft bounce on stiff
        // plates), the sparse solver, whose result is checked the same way.
        let block = LanczosOptions::default().block_size;
        return match solve_modes(model, Some(SolverSpec::Dense), count) {
            Err(e) if lanczos_max_modes(n, block) >= count.min(n) => {
                solve_modes_sharing(model, Some(SolverSpec::Lanczos), count, pencil).map_err(|e2| {
                    Error::numerical("eigen-solvers", format!("dense: {e}; lanczos: {e2}"))
                })
            }
            other => other,
        };
    }
    let solver = solver.unwrap_or(if n < DENSE_LIMIT_DOFS {
        SolverSpec::Dense
    } else {
        SolverSpec::Lanczos
    });
    match solver {
        SolverSpec::Dense => {
            // K, M, the shift-inverted product, its eigenvectors and the shapes: five dense
            // n × n matrices of f64.
            crate::limits::check_memory(
                &format!("the dense eigen-solver ({n} DOFs: 5 × {n}² × 8 B)"),
                5.0 * 8.0 * (n as f64).powi(2),
                "structure.fem.solver",
                "the mesh, or use solver = \"lanczos\" (the lowest modes only)",
            )?;
            let keep = count.min(n);
            let mut modes = model
                .solve_dense_lowest(keep)
                .map_err(|e| solver_hint(e, model, "dense"))?;
            modes.eigenvalues.truncate(keep);
            modes.omega_rad_per_s.truncate(keep);
            modes.shapes = modes.shapes.subcols(0, keep).to_owned();
            Ok((checked(model, modes, "dense")?, "dense"))
        }
        SolverSpec::Lanczos => {
            let opts = LanczosOptions {
                count: count.min(n),
                ..LanczosOptions::default()
            };
            let (k, m) = (model.stiffness.as_ref(), model.mass.as_ref());
            let s = lanczos::lowest_modes_sharing(k, m, &opts, pencil)
                .map_err(|e| solver_hint(e, model, "lanczos"))?;
            Ok((checked(model, to_dense(s), "lanczos")?, "lanczos"))
        }
    }
}

/// A spring at least this many times stiffer than the elements at its DOF acts as a constraint
/// ([`FeModel::constraint_like_springs`]): noted, and named when a solution fails.
pub const CONSTRAINT_LIKE_RATIO: f64 = 1e3;

/// What to change when the eigen-solution of `model` failed: the springs acting as
/// constraints, if any; else the other solver or fewer modes.
fn change_hint(model: &FeModel, solver: &str) -> String {
    match model.constraint_like_note(CONSTRAINT_LIKE_RATIO) {
        Some(note) => format!("what to change: {note}"),
        None => format!(
            "what to change: set structure.fem.solver = \"{}\", or lower structure.fem.count",
            if solver == "dense" {
                "lanczos"
            } else {
                "dense"
            }
        ),
    }
}

fn solver_hint(e: Error, model: &FeModel, solver: &str) -> Error {
    match e {
        Error::Numerical { context, message } => Error::Numerical {
            context,
            message: format!("{message}. {}", change_hint(model, solver)),
        },
        other => other,
    }
}

/// Checks the modes ([`crate::modal::check::check_modes`]: residual and M-orthonormality
/// against stated bounds, rigid-body modes from the Rayleigh quotient's round-off) and returns
/// them with ω, the rigid-body count, the orthonormality error and the largest residual the
/// check measured. A failed check is an error saying what to change.
fn checked(model: &FeModel, mut modes: DenseModes, solver: &str) -> Result<DenseModes> {
    let what = if solver == "dense" {
        "dense eigen-solver (check of the solution)"
    } else {
        "sparse eigen-solver (check of the solution)"
    };
    let c = crate::modal::check::check_modes(
        model.stiffness.as_ref(),
        model.mass.as_ref(),
        &modes.eigenvalues,
        modes.shapes.as_ref(),
        what,
    )
    .map_err(|e| solver_hint(e, model, solver))?;
    crate::modal::dense::orient_modes(&mut modes.shapes);
    modes.omega_rad_per_s = c.omega_rad_per_s;
    modes.rigid_body_modes = c.rigid_body_modes;
    modes.orthonormality_error = c.orthonormality_error;
    modes.max_residual = c.residuals.iter().fold(0.0_f64, |a, &b| a.max(b));
    Ok(modes)
}

/// The most modes the block Lanczos solver computes on `n` degrees of freedom with blocks of
/// `block` vectors: its basis, a multiple of `block` leaving one block spare
/// (`⌊(n − b)/b⌋ b`), must hold the wanted modes plus one block.
pub fn lanczos_max_modes(n: usize, block: usize) -> usize {
    if block == 0 {
        return 0;
    }
    (n.saturating_sub(block) / block * block).saturating_sub(block)
}

/// A failed eigen-solution of a finite-element structure, in the model's terms: the matrices
/// the solver refused come from the plates' and columns' sizes, materials and masses.
fn unsolvable(e: Error, src: &Source) -> Error {
    match e {
        // A cost refused up front (the dense solver's memory): the solver field, as it is; the
        // model's values are not at fault.
        Error::InvalidValue { field, message } if field == "structure.fem.solver" => {
            src.error(&field, format!("{field}: {message}"))
        }
        e @ Error::Numerical { .. } if e.to_string().contains("what to change:") => src.error(
            "structure.fem",
            format!("structure.fem: the finite-element model cannot be solved ({e})"),
        ),
        e @ (Error::InvalidValue { .. } | Error::Numerical { .. }) => src.error(
            "structure.fem",
            format!(
                "structure.fem: the finite-element model cannot be solved ({e}). Check the thicknesses, lengths, densities, Young's moduli and masses of [structure.fem]: a value so small that the element masses or stiffnesses underflow (e.g. 1e-308) or so large that they overflow does this"
            ),
        ),
        other => other,
    }
}

/// The "auto" selection keeps every participating mode up to this multiple of the highest
/// contact frequency (see the module docs: the main lobe of a half-sine contact pulse).
pub const AUTO_CUTOFF_FACTOR: f64 = 3.0;
/// Modes whose participation score is below this fraction of the largest are not moved by any
/// named point's force and are left out by "auto" (they are never excited).
pub const NEGLIGIBLE_SCORE: f64 = 1e-12;
/// Selected modes with a relative residual above this are warned about.
pub const RESIDUAL_WARNING: f64 = 1e-6;

/// The mass of `mesh`'s elements labelled [`super::BED_PART`] when every node of the bed
/// contact point (`ctx`'s role `bed_contact`) is on them: the bed mass m_b of `md/mb`.
fn bed_part_mass(mesh: &crate::structure::Mesh, ctx: &ReductionContext) -> Option<f64> {
    let bed = mesh.parts.get(super::BED_PART)?;
    let contact = ctx
        .role_points
        .iter()
        .find(|(_, roles)| roles.iter().any(|r| r == "bed_contact"))?;
    let at = mesh.points.get(&contact.0)?;
    let on_bed = mesh.nodes_of_part(bed);
    if at.is_empty() || at.iter().any(|n| on_bed.binary_search(n).is_err()) {
        return None;
    }
    let m_b = mesh.mass_of(bed);
    (m_b.is_finite() && m_b > 0.0).then_some(m_b)
}

/// Builds, solves, selects and reduces: the full analysis behind `[structure.fem]`. `ctx`
/// gives the contact frequency (for the "auto" cutoff) and the model's named points.
pub fn analyse(spec: &FemSpec, src: &Source, ctx: &ReductionContext) -> Result<FemAnalysis> {
    let base = "structure.fem";
    check_auto_max_hz(spec, src)?;
    let model = build_model(spec, src)?;
    let (wanted, solved) = mode_counts(spec, src, model.n_dofs())?;
    let mut pencil = None;
    let (mut modes, solver) =
        solve_modes_sharing(&model, spec.solver, solved.max(wanted), &mut pencil)
            .map_err(|e| unsolvable(e, src))?;
    let mut warnings = Vec::new();
    let extent = super::general::bounding_diagonal(model.mesh.nodes.iter().copied());
    warnings.extend(super::plausible::extent_slip(extent, base, src));
    let score_points = score_points(spec, src, ctx, &model)?;
    let functionals = point_functionals(&model, &score_points, ctx)?;
    let cut_cluster = settle_modes(&mut modes, &functionals, wanted, solver)?;
    let nm = modes.omega_rad_per_s.len();
    let table = model.mode_table(&modes)?;
    let psi = point_psi(&functionals, &modes);
    let mut scores = vec![0.0; nm];
    for p in &score_points {
        for (s, v) in scores.iter_mut().zip(&psi[p]) {
            *s += v * v;
        }
    }
    let statics = full_static_flexibility(&model, &modes, &functionals, &mut pencil, &mut warnings);
    drop(pencil);
    let (static_flexibility, static_cross) = (statics.diagonal.clone(), statics.cross.clone());
    let freq = &table.frequency_hz;
    let input = AutoInput {
        scores: &scores,
        freq,
        omega: &modes.omega_rad_per_s,
        points: &score_points,
        psi: &psi,
        static_flexibility: &static_flexibility,
        n_dofs: model.n_dofs(),
    };
    let (selected, selection) = select_modes(spec, src, ctx, &input, &mut warnings)?;
    let cluster = eigenspace_clusters(&modes.omega_rad_per_s, cut_cluster);
    warn_split_eigenspaces(&selected, &cluster, freq, &mut warnings);
    let zeta = damping_ratios(spec, src, selected.len())?;
    warn_split_damping(&selected, &zeta, &cluster, freq, &mut warnings);
    let corrected = correct_statically(spec, &model, &modes, &selected, &functionals, &statics)?;
    let mut modal = match &corrected {
        Some(c) => corrected_model(spec, src, &model, &modes, &selected, &zeta, c)?,
        None => reduced_model(spec, src, &model, &modes, &selected, &zeta)?,
    };
    if let Some(c) = &corrected {
        modal
            .notes
            .extend(c.notes.iter().map(|n| format!("{base}: {n}")));
    }
    let selected_residuals = sparse_residuals(&model, &modes, &selected);
    warn_residuals(&selected, &selected_residuals, freq, &mut warnings);
    modal.static_flexibility = static_flexibility;
    modal.static_cross_flexibility = static_cross;
    modal.warnings = warnings;
    modal.bed_mass_kg = bed_part_mass(&model.mesh, ctx);
    if let Some(note) = model.constraint_like_note(CONSTRAINT_LIKE_RATIO) {
        modal.notes.push(format!("{base}: {note}"));
    }
    Ok(FemAnalysis {
        model,
        modes,
        table,
        solver,
        selected,
        selection,
        scores,
        score_points,
        selected_residuals,
        modal,
    })
}

/// `structure.fem.auto_max_hz`, when given, is a finite frequency > 0 Hz.
fn check_auto_max_hz(spec: &FemSpec, src: &Source) -> Result<()> {
    let base = "structure.fem";
    match spec.auto_max_hz {
        Some(f) if !(f.is_finite() && f > 0.0) => Err(src.error(
            &format!("{base}.auto_max_hz"),
            format!(
                "{base}.auto_max_hz must be a finite number > 0 Hz (got {})",
                crate::num(f)
            ),
        )),
        _ => Ok(()),
    }
}

/// The modes wanted (`structure.fem.count`, default 30, at most the model's `n_dofs`) and the
/// modes to solve for: one more when the solver can compute it, so that a repeated eigenvalue
/// cut by `count` (its partner the next mode) gets the canonical basis of its whole eigenspace
/// too and the mode kept does not depend on the solver ([`settle_modes`] drops the extra one).
fn mode_counts(spec: &FemSpec, src: &Source, n_dofs: usize) -> Result<(usize, usize)> {
    let base = "structure.fem";
    let count = spec.count.unwrap_or(30);
    if count == 0 {
        return Err(src.error(
            &format!("{base}.count"),
            format!("{base}.count must be >= 1"),
        ));
    }
    let lanczos = spec.solver.unwrap_or(if n_dofs < DENSE_LIMIT_DOFS {
        SolverSpec::Dense
    } else {
        SolverSpec::Lanczos
    }) == SolverSpec::Lanczos;
    let max = lanczos_max_modes(n_dofs, LanczosOptions::default().block_size);
    if lanczos && count.min(n_dofs) > max {
        return Err(src.error(
            &format!("{base}.count"),
            format!(
                "{base}.count = {count}: the model has {n_dofs} degrees of freedom, of which the Lanczos solver computes at most {max} modes; lower {base}.count to {max} or less, or set {base}.solver = \"dense\" (all {n_dofs} modes; slow above ~{DENSE_LIMIT_DOFS} degrees of freedom)"
            ),
        ));
    }
    let wanted = count.min(n_dofs);
    let mut solved = (count + 1).min(n_dofs);
    if lanczos {
        solved = solved.min(max);
    }
    Ok((wanted, solved))
}

/// The points that rank modes: `structure.fem.contact_points` (each a named point of the mesh),
/// else the model's named points with a role that are in the mesh.
fn score_points(
    spec: &FemSpec,
    src: &Source,
    ctx: &ReductionContext,
    model: &FeModel,
) -> Result<Vec<String>> {
    let base = "structure.fem";
    let Some(v) = &spec.contact_points else {
        return Ok(ctx
            .role_points
            .iter()
            .map(|(p, _)| p.clone())
            .filter(|p| model.mesh.points.contains_key(p))
            .collect());
    };
    for (i, p) in v.iter().enumerate() {
        if !model.mesh.points.contains_key(p) {
            let known: Vec<&str> = model.mesh.points.keys().map(|s| s.as_str()).collect();
            return Err(src.error(
                &format!("{base}.contact_points[{i}]"),
                format!(
                    "{base}.contact_points: unknown point '{p}'; valid: {}",
                    known.join(", ")
                ),
            ));
        }
    }
    Ok(v.clone())
}

/// The functionals (`ψ_i(P) = f_Pᵀ φ_i`) of the score points, then of the role points, each
/// once and in that order: the probes of the canonical basis, then the points' ψ.
fn point_functionals(
    model: &FeModel,
    score_points: &[String],
    ctx: &ReductionContext,
) -> Result<Vec<(String, Vec<f64>)>> {
    let mut functionals: Vec<(String, Vec<f64>)> = Vec::new();
    for p in score_points
        .iter()
        .chain(ctx.role_points.iter().map(|(p, _)| p))
    {
        if model.mesh.points.contains_key(p) && !functionals.iter().any(|(q, _)| q == p) {
            functionals.push((p.clone(), model.point_functional(p)?));
        }
    }
    Ok(functionals)
}

/// Puts the solved modes in their reported form: a repeated eigenvalue's modes in the basis of
/// its eigenspace that does not depend on the solver (dense and Lanczos return different
/// rotations of it), led by the direction that moves the first probe point most
/// (`modal::eigenspace`); every shape checked finite (ψ, effective masses and exported shapes
/// are functions of the shapes: a non-finite entry is an error here, not a NaN in modes.csv);
/// the modes cut to `wanted`. Returns the last wanted mode's eigenspace when it continues past
/// `wanted`.
fn settle_modes(
    modes: &mut DenseModes,
    functionals: &[(String, Vec<f64>)],
    wanted: usize,
    solver: &str,
) -> Result<Option<std::ops::Range<usize>>> {
    let probes: Vec<&[f64]> = functionals.iter().map(|(_, f)| f.as_slice()).collect();
    crate::modal::eigenspace::canonical_basis(&mut modes.shapes, &modes.omega_rad_per_s, &probes);
    if let Some(j) =
        (0..modes.shapes.ncols()).find(|&j| modes.shapes.col(j).iter().any(|v| !v.is_finite()))
    {
        return Err(Error::numerical(
            "structure.fem",
            format!(
                "mode {} ({:.6} Hz) has a non-finite mode-shape entry after the {solver} \
                 eigen-solution: its shape, ψ and effective masses cannot be reported",
                j + 1,
                modes.omega_rad_per_s[j] / (2.0 * std::f64::consts::PI)
            ),
        ));
    }
    let cut_cluster = (modes.omega_rad_per_s.len() > wanted && wanted > 0)
        .then(|| crate::modal::eigenspace::degenerate_clusters(&modes.omega_rad_per_s))
        .map(|c| c[wanted - 1].clone())
        .filter(|c| c.end > wanted);
    if modes.omega_rad_per_s.len() > wanted {
        modes.eigenvalues.truncate(wanted);
        modes.omega_rad_per_s.truncate(wanted);
        modes.shapes = modes.shapes.subcols(0, wanted).to_owned();
        modes.rigid_body_modes = modes.omega_rad_per_s.iter().filter(|w| **w == 0.0).count();
    }
    Ok(cut_cluster)
}

/// Each point's modal participation `ψ_i(P) = f_Pᵀ φ_i` over the modes.
fn point_psi(functionals: &[(String, Vec<f64>)], modes: &DenseModes) -> BTreeMap<String, Vec<f64>> {
    let nm = modes.omega_rad_per_s.len();
    functionals
        .iter()
        .map(|(p, f)| {
            let v: Vec<f64> = (0..nm)
                .map(|i| (0..f.len()).map(|j| f[j] * modes.shapes[(j, i)]).sum())
                .collect();
            (p.clone(), v)
        })
        .collect()
}

/// The rigid-body mode shapes (ω = 0) and the lowest elastic eigenvalue ω₁² (rad²/s²) of
/// `modes`: what the inertia-relief static solution needs (`truncation::static_flexibility`).
fn rigid_and_lowest(modes: &DenseModes) -> (Vec<Vec<f64>>, Option<f64>) {
    let rigid = (0..modes.omega_rad_per_s.len())
        .filter(|&i| modes.omega_rad_per_s[i] == 0.0)
        .map(|i| modes.shapes.col(i).iter().copied().collect())
        .collect();
    let lowest_elastic = modes
        .omega_rad_per_s
        .iter()
        .find(|w| **w > 0.0)
        .map(|w| w * w);
    (rigid, lowest_elastic)
}

/// The full model's static solution at the named points ([`full_static_flexibility`]).
#[derive(Default)]
struct Statics {
    /// `G_PP` by point name (m/N, elastic part).
    diagonal: BTreeMap<String, f64>,
    /// `G_PQ` (P ≠ Q) by point names.
    cross: CrossFlexibility,
    /// The deflections `u_P` (columns, in the order of the functionals) and `G_PP` in that
    /// order; `None` when the static solution failed.
    deflections: Option<(faer::Mat<f64>, Vec<f64>)>,
}

/// The full model's static flexibility `G_PP` (m/N, elastic part, module docs) at each point
/// of `functionals`, the cross flexibilities `G_PQ` (P ≠ Q) and the deflections (one
/// factorisation for the truncation table and the static correction); empty, with a warning,
/// when the static solution fails.
fn full_static_flexibility(
    model: &FeModel,
    modes: &DenseModes,
    functionals: &[(String, Vec<f64>)],
    pencil: &mut Option<lanczos::ShiftedPencil>,
    warnings: &mut Vec<String>,
) -> Statics {
    let (rigid, lowest_elastic) = rigid_and_lowest(modes);
    let fvecs: Vec<Vec<f64>> = functionals.iter().map(|(_, f)| f.clone()).collect();
    match truncation::static_deflections_sharing(
        model.stiffness.as_ref(),
        model.mass.as_ref(),
        &fvecs,
        &rigid,
        lowest_elastic,
        pencil,
    ) {
        Ok(u) => {
            let g = truncation::flexibility_of_deflections(&fvecs, u.as_ref());
            let names: Vec<&String> = functionals.iter().map(|(p, _)| p).collect();
            let diag = names.iter().zip(&g).enumerate();
            let diag = diag.map(|(i, (p, row))| ((*p).clone(), row[i])).collect();
            let gpp = (0..g.len()).map(|i| g[i][i]).collect();
            Statics {
                diagonal: diag,
                cross: truncation::cross_map(&names, &g),
                deflections: Some((u, gpp)),
            }
        }
        Err(e) => {
            warnings.push(format!(
                "structure.fem: the static flexibility could not be computed, so modes are \
                 selected without it and there is no truncation table nor static correction: {e}"
            ));
            Statics::default()
        }
    }
}

/// The static correction of the selected modes at the named points
/// ([`crate::modal::static_correction`]), unless `structure.fem.static_correction = false` or
/// the static solution failed.
fn correct_statically(
    spec: &FemSpec,
    model: &FeModel,
    modes: &DenseModes,
    selected: &[usize],
    functionals: &[(String, Vec<f64>)],
    statics: &Statics,
) -> Result<Option<static_correction::StaticCorrection>> {
    let Some((u, g)) = &statics.deflections else {
        return Ok(None);
    };
    if !spec.static_correction.unwrap_or(true) {
        return Ok(None);
    }
    let n = model.n_dofs();
    let retained =
        faer::Mat::<f64>::from_fn(n, selected.len(), |i, c| modes.shapes[(i, selected[c])]);
    let omega: Vec<f64> = selected.iter().map(|&s| modes.omega_rad_per_s[s]).collect();
    let loads = static_correction::PointLoads {
        functionals,
        deflections: u.as_ref(),
        flexibility: g,
    };
    static_correction::static_correction(
        model.stiffness.as_ref(),
        model.mass.as_ref(),
        retained.as_ref(),
        &omega,
        &loads,
    )
    .map(Some)
}

/// The modal model of the selected modes augmented by the pseudo-modes of `c` (appended after
/// them, labelled "static correction j", mode number 0, [`ModalModel::pseudo_modes`]).
/// Damping: Rayleigh `α + β ω̃²` (the exact projection: the augmented basis diagonalises K and
/// M); modal ratios: each pseudo-mode takes the ratio of the highest selected mode (with one
/// ratio for all, that ratio), documented in docs/explanations/fem.md.
fn corrected_model(
    spec: &FemSpec,
    src: &Source,
    model: &FeModel,
    modes: &DenseModes,
    selected: &[usize],
    zeta: &[f64],
    c: &static_correction::StaticCorrection,
) -> Result<ModalModel> {
    let (n, nm, q) = (
        model.n_dofs(),
        modes.omega_rad_per_s.len(),
        c.eigenvalues.len(),
    );
    // The solved modes with the pseudo-modes after them (the shapes copied once, not cloned
    // and then rebuilt: at 1M DOF each copy is n × modes doubles).
    let aug = DenseModes {
        shapes: faer::Mat::<f64>::from_fn(n, nm + q, |i, j| {
            if j < nm {
                modes.shapes[(i, j)]
            } else {
                c.shapes[(i, j - nm)]
            }
        }),
        eigenvalues: modes
            .eigenvalues
            .iter()
            .chain(&c.eigenvalues)
            .copied()
            .collect(),
        omega_rad_per_s: (modes.omega_rad_per_s.iter().copied())
            .chain(c.eigenvalues.iter().map(|l| l.sqrt()))
            .collect(),
        orthonormality_error: modes.orthonormality_error,
        max_residual: modes.max_residual,
        rigid_body_modes: modes.rigid_body_modes,
    };
    let sel: Vec<usize> = selected.iter().copied().chain(nm..nm + q).collect();
    let last = zeta.last().copied().unwrap_or(0.0);
    let z: Vec<f64> = zeta
        .iter()
        .copied()
        .chain(std::iter::repeat_n(last, q))
        .collect();
    let mut modal = reduced_model(spec, src, model, &aug, &sel, &z)?;
    let ns = selected.len();
    modal.pseudo_modes = (0..ns + q)
        .map(|i| i.checked_sub(ns).map(|j| c.points[j].clone()))
        .collect();
    for j in 0..q {
        modal.mode_numbers[ns + j] = 0;
        modal.labels[ns + j] = format!(
            "static correction {} ({:.4} Hz, point '{}')",
            j + 1,
            c.eigenvalues[j].sqrt() / (2.0 * std::f64::consts::PI),
            c.points[j]
        );
    }
    Ok(modal)
}

/// `G_PQ` by point names (P ≠ Q): [`crate::modal::ModalModel::static_cross_flexibility`].
type CrossFlexibility = BTreeMap<String, BTreeMap<String, f64>>;

/// The selected modes (0-based, ascending, at least one) by `structure.fem.select`: "auto"
/// (the default), "participation", a list of 1-based mode numbers or a band in Hz.
fn select_modes(
    spec: &FemSpec,
    src: &Source,
    ctx: &ReductionContext,
    a: &AutoInput<'_>,
    warnings: &mut Vec<String>,
) -> Result<(Vec<usize>, Selection)> {
    let base = "structure.fem";
    let (nm, freq) = (a.scores.len(), a.freq);
    let (mut selected, selection) = match spec.select.clone() {
        None => auto_select(spec, src, ctx, a, warnings)?,
        Some(SelectSpec::Keyword(k)) if k == "auto" => auto_select(spec, src, ctx, a, warnings)?,
        Some(SelectSpec::Keyword(k)) if k == "participation" => {
            participation_select(spec, src, a.scores, freq, a.omega, a.points)?
        }
        Some(SelectSpec::Keyword(k)) => {
            return Err(src.error(
                &format!("{base}.select"),
                format!("{base}.select: unknown keyword '{k}'; give \"auto\", \"participation\", a list of 1-based mode numbers, or {{ band_hz = [lo, hi] }}"),
            ))
        }
        Some(SelectSpec::Indices(v)) => {
            let mut out = Vec::new();
            for &i in &v {
                if i == 0 || i > nm {
                    return Err(src.error(
                        &format!("{base}.select"),
                        format!("{base}.select: mode {i} does not exist; {nm} modes were computed (1..={nm}; raise `count`)"),
                    ));
                }
                out.push(i - 1);
            }
            (out, Selection::Indices)
        }
        Some(SelectSpec::Band { band_hz }) => {
            if !(band_hz[0].is_finite() && band_hz[1].is_finite() && band_hz[0] <= band_hz[1]) {
                return Err(src.error(
                    &format!("{base}.select"),
                    format!("{base}.select.band_hz must be [lo, hi] with lo <= hi (got {band_hz:?})"),
                ));
            }
            let v: Vec<usize> = (0..nm)
                .filter(|&i| freq[i] >= band_hz[0] && freq[i] <= band_hz[1])
                .collect();
            if v.is_empty() {
                return Err(src.error(
                    &format!("{base}.select"),
                    format!("{base}.select: no computed mode lies in {band_hz:?} Hz (computed: {:.3} to {:.3} Hz)", freq[0], freq[nm - 1]),
                ));
            }
            (v, Selection::Band(band_hz))
        }
    };
    selected.sort_unstable();
    selected.dedup();
    if selected.is_empty() {
        return Err(src.error(
            &format!("{base}.select"),
            format!("{base}.select keeps no mode: select at least one of the {nm} modes computed (a list of mode numbers 1..={nm}, \"auto\", \"participation\" or {{ band_hz = [lo, hi] }})"),
        ));
    }
    Ok((selected, selection))
}

/// Per computed mode, the modes sharing its eigenvalue (`modal::eigenspace`), with the last
/// wanted mode's eigenspace `cut` extended past the computed modes when `count` cut it.
fn eigenspace_clusters(
    omega: &[f64],
    cut: Option<std::ops::Range<usize>>,
) -> Vec<std::ops::Range<usize>> {
    let mut cluster = crate::modal::eigenspace::degenerate_clusters(omega);
    if let Some(c) = &cut {
        // Its members beyond `count` were computed, and dropped: the pair is cut.
        for r in cluster.iter_mut().skip(c.start) {
            *r = c.clone();
        }
    }
    cluster
}

/// Warns of a repeated eigenvalue of which the selection keeps some modes, not all: which
/// direction within its eigenspace is kept is the canonical basis's choice.
fn warn_split_eigenspaces(
    selected: &[usize],
    cluster: &[std::ops::Range<usize>],
    freq: &[f64],
    warnings: &mut Vec<String>,
) {
    let base = "structure.fem";
    let nm = freq.len();
    for (i, c) in cluster.iter().enumerate() {
        if c.start != i || c.len() < 2 {
            continue;
        }
        let kept: Vec<usize> = c
            .clone()
            .filter(|j| selected.binary_search(j).is_ok())
            .collect();
        if !kept.is_empty() && kept.len() < c.len() {
            let one = |v: &[usize]| {
                v.iter()
                    .map(|j| (j + 1).to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let all: Vec<usize> = c.clone().collect();
            warnings.push(format!(
                "{base}.select keeps mode(s) {} of the modes {} that share one eigenvalue ({:.6} Hz): \
                 which direction within their eigenspace is kept is meid's canonical basis \
                 (docs/explanations/fem.md, \"Repeated eigenvalues\"), not a property of the structure; select \
                 all of them{}",
                one(&kept),
                one(&all),
                freq[c.start],
                if c.end > nm {
                    format!(" (raise {base}.count to {} to compute them)", c.end)
                } else {
                    String::new()
                }
            ));
        }
    }
}

/// The modal damping ratios of the `ns` selected modes: `damping_ratios` (one for all or one
/// per mode, each in [0, 1)), or 0 (none, or Rayleigh damping, added by [`reduced_model`]).
fn damping_ratios(spec: &FemSpec, src: &Source, ns: usize) -> Result<Vec<f64>> {
    let base = "structure.fem";
    let zeta = match (&spec.damping_ratios, &spec.rayleigh) {
        (Some(_), Some(_)) => {
            return Err(src.error(
                &format!("{base}.rayleigh"),
                format!("{base}: give damping_ratios or rayleigh, not both"),
            ))
        }
        (Some(Ratios::All(z)), None) => vec![*z; ns],
        (Some(Ratios::PerMode(v)), None) => {
            if v.len() != ns {
                return Err(src.error(
                    &format!("{base}.damping_ratios"),
                    format!("{base}.damping_ratios: {} ratios given for {ns} selected modes (give one per mode or a single number)", v.len()),
                ));
            }
            v.clone()
        }
        _ => vec![0.0; ns],
    };
    if let Some(z) = zeta
        .iter()
        .find(|z| !(z.is_finite() && **z >= 0.0 && **z < 1.0))
    {
        return Err(src.error(
            &format!("{base}.damping_ratios"),
            format!(
                "{base}.damping_ratios must be in [0, 1) (got {})",
                crate::num(*z)
            ),
        ));
    }
    Ok(zeta)
}

/// Warns of per-mode ratios that differ within a repeated eigenvalue: they damp one direction
/// of its eigenspace more than another, and which one is the basis's choice, not the
/// structure's.
fn warn_split_damping(
    selected: &[usize],
    zeta: &[f64],
    cluster: &[std::ops::Range<usize>],
    freq: &[f64],
    warnings: &mut Vec<String>,
) {
    for (i, c) in cluster.iter().enumerate() {
        let z: Vec<(usize, f64)> = selected
            .iter()
            .zip(zeta)
            .filter(|(j, _)| c.start == i && c.contains(j))
            .map(|(j, z)| (*j, *z))
            .collect();
        if z.len() > 1 && z.iter().any(|(_, v)| *v != z[0].1) {
            warnings.push(format!(
                "structure.fem.damping_ratios: the modes {} share one eigenvalue ({:.6} Hz) but \
                 get different ratios ({}): the damping then depends on meid's canonical basis \
                 of their eigenspace (docs/explanations/fem.md, \"Repeated eigenvalues\"); give them one ratio",
                z.iter()
                    .map(|(j, _)| (j + 1).to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
                freq[i],
                z.iter()
                    .map(|(_, v)| v.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
    }
}

/// The modal model of the selected modes ([`FeModel::modal_model`]) with Rayleigh damping
/// `C = αM + βK` projected onto them: `D_ii += α + β ω_i²`.
fn reduced_model(
    spec: &FemSpec,
    src: &Source,
    model: &FeModel,
    modes: &DenseModes,
    selected: &[usize],
    zeta: &[f64],
) -> Result<ModalModel> {
    let base = "structure.fem";
    let mut modal = model
        .modal_model(modes, selected, zeta)
        .map_err(|e| match e {
            Error::InvalidValue { field, message } => src.error(
                base,
                format!("{base}: the selected modes: {field}: {message}"),
            ),
            e => e,
        })?;
    if let Some([a, b]) = spec.rayleigh {
        if !(a.is_finite() && b.is_finite() && a >= 0.0 && b >= 0.0) {
            return Err(src.error(
                &format!("{base}.rayleigh"),
                format!("{base}.rayleigh = [alpha, beta] must be finite and >= 0 (got [{a}, {b}])"),
            ));
        }
        let n = modal.omega_rad_per_s.len();
        for (i, w) in modal.omega_rad_per_s.iter().enumerate() {
            modal.damping[i * n + i] += a + b * w * w;
        }
    }
    Ok(modal)
}

/// Warns of each selected mode whose relative residual exceeds [`RESIDUAL_WARNING`].
fn warn_residuals(selected: &[usize], residuals: &[f64], freq: &[f64], warnings: &mut Vec<String>) {
    for (&i, r) in selected.iter().zip(residuals) {
        if *r > RESIDUAL_WARNING {
            warnings.push(format!(
                "structure.fem: mode {} ({:.4} Hz) has a relative residual {r:.1e} > {RESIDUAL_WARNING:.0e}: \
                 the eigen-solution is inaccurate, as when stiffnesses or masses span more than \
                 double precision carries (a very stiff spring: give a rigid link instead, or \
                 lower it to ~1e3 times the structure's stiffness)",
                i + 1,
                freq[i]
            ));
        }
    }
}

/// Relative residuals `‖K φ − λ M φ‖ / (‖K φ‖ + (|λ| + σ) ‖M φ‖)` of the modes `which`, with
/// the sparse K and M (σ = 1e-4 tr K / tr M, as in [`crate::modal::dense::mode_residuals`]).
fn sparse_residuals(model: &FeModel, modes: &DenseModes, which: &[usize]) -> Vec<f64> {
    let n = model.n_dofs();
    let (mut tr_k, mut tr_m) = (0.0, 0.0);
    for t in model.stiffness.triplet_iter() {
        if t.row == t.col {
            tr_k += *t.val;
        }
    }
    for t in model.mass.triplet_iter() {
        if t.row == t.col {
            tr_m += *t.val;
        }
    }
    let sigma = DEFAULT_RELATIVE_SHIFT * tr_k / tr_m.max(f64::MIN_POSITIVE);
    which
        .iter()
        .map(|&j| {
            let mut kp = vec![0.0; n];
            let mut mp = vec![0.0; n];
            for t in model.stiffness.triplet_iter() {
                kp[t.row] += t.val * modes.shapes[(t.col, j)];
            }
            for t in model.mass.triplet_iter() {
                mp[t.row] += t.val * modes.shapes[(t.col, j)];
            }
            let lam = modes.eigenvalues[j];
            let (mut r2, mut kn, mut mn) = (0.0, 0.0, 0.0);
            for i in 0..n {
                let r = kp[i] - lam * mp[i];
                r2 += r * r;
                kn += kp[i] * kp[i];
                mn += mp[i] * mp[i];
            }
            let d = kn.sqrt() + (lam.abs() + sigma) * mn.sqrt();
            if d > 0.0 {
                r2.sqrt() / d
            } else {
                0.0
            }
        })
        .collect()
}

/// What [`auto_select`] ranks modes by.
struct AutoInput<'a> {
    scores: &'a [f64],
    freq: &'a [f64],
    omega: &'a [f64],
    points: &'a [String],
    psi: &'a BTreeMap<String, Vec<f64>>,
    static_flexibility: &'a BTreeMap<String, f64>,
    /// DOFs of the reduced model: as many modes as the structure has.
    n_dofs: usize,
}

/// `select = "auto"` (module docs): every participating mode up to the cutoff, then, above it,
/// the modes carrying the largest share of a point's static flexibility until every point
/// holds [`truncation::SHARE_WARNING`] (at most `auto_count` of them).
fn auto_select(
    spec: &FemSpec,
    src: &Source,
    ctx: &ReductionContext,
    a: &AutoInput<'_>,
    warnings: &mut Vec<String>,
) -> Result<(Vec<usize>, Selection)> {
    let base = "structure.fem";
    if a.points.is_empty() {
        return Err(src.error(
            &format!("{base}.select"),
            format!("{base}.select = \"auto\" needs the model's named points (O_b, O_f, B) in the mesh, or `contact_points`"),
        ));
    }
    let cutoff_hz = match spec.auto_max_hz {
        Some(f) if f.is_finite() && f > 0.0 => f,
        Some(f) => {
            return Err(src.error(
                &format!("{base}.auto_max_hz"),
                format!("{base}.auto_max_hz must be a finite number > 0 Hz (got {})", crate::num(f)),
            ))
        }
        None if ctx.contact_omega_rad_per_s > 0.0 => {
            AUTO_CUTOFF_FACTOR * ctx.contact_omega_rad_per_s / (2.0 * std::f64::consts::PI)
        }
        None => {
            return Err(src.error(
                &format!("{base}.auto_max_hz"),
                format!("{base}: select = \"auto\" needs a contact frequency (a linear contact, or a nonlinear one with slider.velocity != 0) or `auto_max_hz`"),
            ))
        }
    };
    let nm = a.scores.len();
    // A mode that moves none of the points (score points and role points) is never excited
    // by the impact forces and never seen at B.
    let peak: BTreeMap<&String, f64> = a
        .psi
        .iter()
        .map(|(p, v)| (p, v.iter().fold(0.0_f64, |x, y| x.max(y * y))))
        .collect();
    let moves_alone = |i: usize| {
        a.psi
            .iter()
            .any(|(p, v)| v[i] * v[i] > NEGLIGIBLE_SCORE * peak[p])
    };
    // A repeated eigenvalue's modes are one eigenspace, in which each solver returns its own
    // basis (the square cantilever's bending pair: one mode moving the tip's z and one not, or
    // both moving it): the space is kept or left out whole, so that what is kept does not
    // depend on the basis (dense selected 9 modes, Lanczos 12, of the same 20).
    let cluster = crate::modal::eigenspace::degenerate_clusters(a.omega);
    let moves = |i: usize| cluster[i].clone().any(moves_alone);
    // Shares are checked at every point of the truncation table (the role points) and at the
    // score points.
    let share_points: Vec<&String> = a.psi.keys().collect();
    let mut selected: Vec<usize> = (0..nm)
        .filter(|&i| a.freq[i] <= cutoff_hz && moves(i))
        .collect();
    // Every mode of the structure computed (nm = DOFs): none can be missing.
    if nm > 0 && nm < a.n_dofs && a.freq[nm - 1] < cutoff_hz {
        warnings.push(format!(
            "{base}.count: the {nm} computed modes stop at {:.4} Hz, below the \"auto\" cutoff \
             {cutoff_hz:.4} Hz ({AUTO_CUTOFF_FACTOR} times the highest contact frequency): \
             modes in between may be missing; raise {base}.count",
            a.freq[nm - 1]
        ));
    }
    // Above the cutoff: largest share of some point's static flexibility first.
    let share = |sel: &[usize], p: &str| -> Option<f64> {
        let g = *a.static_flexibility.get(p)?;
        if g <= 0.0 {
            return None;
        }
        let v = a.psi.get(p)?;
        let m: f64 = sel
            .iter()
            .filter(|&&i| a.omega[i] > 0.0)
            .map(|&i| v[i] * v[i] / (a.omega[i] * a.omega[i]))
            .sum();
        Some(m / g)
    };
    let contribution = |i: usize| -> f64 {
        share_points
            .iter()
            .filter_map(|p| {
                let g = *a.static_flexibility.get(p.as_str())?;
                let v = a.psi.get(p.as_str())?;
                (g > 0.0 && a.omega[i] > 0.0).then(|| v[i] * v[i] / (a.omega[i] * a.omega[i] * g))
            })
            .fold(0.0, f64::max)
    };
    let mut extra: Vec<usize> = (0..nm)
        .filter(|&i| a.freq[i] > cutoff_hz && moves(i))
        .collect();
    extra.sort_by(|&x, &y| contribution(y).total_cmp(&contribution(x)));
    let limit = spec.auto_count.unwrap_or(usize::MAX);
    let mut added = 0;
    for i in extra {
        if selected.contains(&i) {
            continue;
        }
        let short = share_points
            .iter()
            .any(|p| share(&selected, p).is_some_and(|s| s < truncation::SHARE_WARNING));
        if !short || added >= limit {
            break;
        }
        // The whole eigenspace of a repeated eigenvalue.
        for j in cluster[i].clone() {
            if !selected.contains(&j) {
                selected.push(j);
                added += 1;
            }
        }
    }
    if selected.is_empty() {
        return Err(src.error(
            &format!("{base}.select"),
            format!("{base}: no computed mode moves the points {} (up to {cutoff_hz:.4} Hz and above): check the points and `count`", a.points.join(", ")),
        ));
    }
    Ok((
        selected,
        Selection::Auto {
            cutoff_hz,
            extra: added,
            points: share_points.iter().map(|p| p.to_string()).collect(),
        },
    ))
}

/// `select = "participation"`: the `auto_count` modes (default 2) with the largest participation
/// score up to `auto_max_hz` (the rule "auto" had before; it can drop a low mode that carries
/// a point's flexibility, which the truncation table then shows). The modes of a repeated
/// eigenvalue are ranked by their summed score and kept whole, so the count can be exceeded by
/// the rest of a pair.
fn participation_select(
    spec: &FemSpec,
    src: &Source,
    scores: &[f64],
    freq: &[f64],
    omega: &[f64],
    points: &[String],
) -> Result<(Vec<usize>, Selection)> {
    let base = "structure.fem";
    if points.is_empty() {
        return Err(src.error(
            &format!("{base}.select"),
            format!("{base}.select = \"participation\" needs the model's named points in the mesh, or `contact_points`"),
        ));
    }
    let count = spec.auto_count.unwrap_or(2);
    if count == 0 {
        return Err(src.error(
            &format!("{base}.auto_count"),
            format!("{base}.auto_count must be >= 1 with select = \"participation\""),
        ));
    }
    let max_hz = spec.auto_max_hz.unwrap_or(f64::INFINITY);
    // A repeated eigenvalue's modes are ranked and kept together, by the score of the whole
    // eigenspace (the sum over its modes, the same in any basis of it): which member of a pair
    // would rank first depends on the basis, not on the structure.
    let cluster = crate::modal::eigenspace::degenerate_clusters(omega);
    let cluster_score = |i: usize| cluster[i].clone().map(|j| scores[j]).sum::<f64>();
    let mut firsts: Vec<usize> = (0..scores.len())
        .filter(|&i| freq[i] <= max_hz && cluster[i].start == i)
        .collect();
    firsts.sort_by(|&a, &b| cluster_score(b).total_cmp(&cluster_score(a)));
    let mut cand: Vec<usize> = Vec::new();
    for i in firsts {
        if cand.len() >= count {
            break;
        }
        cand.extend(cluster[i].clone().filter(|&j| freq[j] <= max_hz));
    }
    if cand.is_empty() {
        return Err(src.error(
            &format!("{base}.auto_max_hz"),
            format!("{base}: no computed mode lies below auto_max_hz = {max_hz} Hz"),
        ));
    }
    Ok((
        cand,
        Selection::Participation {
            count,
            points: points.to_vec(),
        },
    ))
}

/// Builds, solves and reduces the finite-element structure.
pub fn modal_model(spec: &FemSpec, src: &Source, ctx: &ReductionContext) -> Result<ModalModel> {
    Ok(analyse(spec, src, ctx)?.modal)
}

/// Reads a model file like [`Model::from_file`] and, when its structure is `[structure.fem]`,
/// also returns the [`FemAnalysis`] the model's modes came from: the FE model is built and solved
/// **once** (what `meid modes` shows is what the impact engine gets). `count` overrides
/// `structure.fem.count` (the number of modes computed) before the solve; the returned model's
/// spec says so too. For lumped or tabulated structures the analysis is `None`.
pub fn from_file_with_analysis(
    path: &Path,
    overrides: &[String],
    count: Option<usize>,
) -> Result<(Model, Option<FemAnalysis>)> {
    let text = crate::input::read_text(path)?;
    from_text_with_analysis(&path.display().to_string(), text, overrides, count)
}

/// [`from_file_with_analysis`] on a model's text (`name` is used in messages).
pub fn from_text_with_analysis(
    name: &str,
    text: String,
    overrides: &[String],
    count: Option<usize>,
) -> Result<(Model, Option<FemAnalysis>)> {
    let mut analysis = None;
    let mut model = Model::from_text_with(name, text, overrides, |spec, src| {
        match &spec.structure.fem {
            Some(f)
                if spec.structure.lumped.is_none()
                    && spec.structure.modal.is_none()
                    && spec.structure.modes.is_none() =>
            {
                let mut f = f.clone();
                if count.is_some() {
                    f.count = count;
                }
                let an = analyse(&f, src, &ReductionContext::of(spec))?;
                let modal = an.modal.clone();
                analysis = Some(an);
                Ok(modal)
            }
            _ => super::build_structure(spec, src),
        }
    })?;
    if let (Some(f), Some(c)) = (model.spec.structure.fem.as_mut(), count) {
        f.count = Some(c);
    }
    Ok((model, analysis))
}

/// Effective modal masses of one mode (kg for translations, kg·m² for rotations about global
/// axes through the origin).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct EffectiveMass {
    /// Translations (kg).
    #[serde(rename = "x_kg")]
    pub x: f64,
    #[serde(rename = "y_kg")]
    pub y: f64,
    #[serde(rename = "z_kg")]
    pub z: f64,
    /// Rotations about the axes through the origin (kg·m²).
    #[serde(rename = "rx_kg_m2")]
    pub rx: f64,
    #[serde(rename = "ry_kg_m2")]
    pub ry: f64,
    #[serde(rename = "rz_kg_m2")]
    pub rz: f64,
}

/// One row of the mode table.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ModeRow {
    /// 1-based mode number (ascending frequency).
    pub index: usize,
    pub frequency_hz: f64,
    /// `None` for lumped/tabulated models (no mass matrix in global directions). JSON
    /// `effective_mass`, its members named with their units.
    #[serde(rename = "effective_mass")]
    pub effective_mass_kg: Option<EffectiveMass>,
    /// Signed mass-normalised mode-shape value ψ_i(P) along the impact direction at each named
    /// point (1/√kg): `ψ_i(P) = d · u_P(φ_i)` with `φ_iᵀ M φ_i = 1`. Within a mode the signs give
    /// the relative phase of the points (e.g. bed and base in opposition); the sign of a whole
    /// mode is a convention (FE modes: see [`solve_modes`]).
    pub psi_per_sqrt_kg: BTreeMap<String, f64>,
    /// Participation score `Σ_A ψ_i(A)²` at the contact points (1/kg), FE models only.
    pub score: Option<f64>,
    pub selected: bool,
}

/// One static-correction pseudo-mode in `meid modes`: a Ritz vector of the reduced model, not a
/// mode of the structure.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct PseudoModeRow {
    /// 1-based among the pseudo-modes.
    pub index: usize,
    /// Its Ritz frequency `ω̃/2π` (Hz).
    pub frequency_hz: f64,
    /// The point whose static flexibility it carries most.
    pub point: String,
    /// Effective modal mass along the impact direction `(φ̃ᵀ M r)²` (kg).
    pub effective_mass_z_kg: Option<f64>,
    /// ψ̃(P) along the impact direction at each named point (1/√kg).
    pub psi_per_sqrt_kg: BTreeMap<String, f64>,
}

/// The pseudo-mode rows of a reduced model ([`ModalModel::pseudo_modes`]).
pub fn pseudo_mode_rows(m: &ModalModel) -> Vec<PseudoModeRow> {
    (0..m.len())
        .filter(|&i| m.is_pseudo(i))
        .enumerate()
        .map(|(j, i)| PseudoModeRow {
            index: j + 1,
            frequency_hz: m.omega_rad_per_s[i] / (2.0 * std::f64::consts::PI),
            point: m.pseudo_modes[i].clone().unwrap_or_default(),
            effective_mass_z_kg: m.effective_mass_kg.as_ref().and_then(|e| e.get(i).copied()),
            psi_per_sqrt_kg: m.points.iter().map(|(k, v)| (k.clone(), v[i])).collect(),
        })
        .collect()
}

/// What `meid modes` reports.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ModeReport {
    pub modes: Vec<ModeRow>,
    /// Selected modes (1-based).
    pub selected: Vec<usize>,
    /// Why these modes were selected.
    pub selection: String,
    /// "dense", "lanczos", or "lumped/modal".
    pub solver: String,
    /// Reduced DOFs of the FE model (0 for lumped/modal).
    pub dofs: usize,
    /// Total `rᵀ M r` per direction (x, y, z in kg; rx, ry, rz in kg·m²; JSON members named
    /// with their units).
    pub total_mass: Option<EffectiveMass>,
    /// Relative residual of each selected mode.
    pub selected_residuals: Vec<f64>,
    /// The static-correction pseudo-modes of the reduced model (Ritz vectors, not modes of the
    /// structure; [`crate::modal::static_correction`]); empty without correction.
    pub static_correction: Vec<PseudoModeRow>,
    /// max |Φᵀ M Φ − I| over the computed modes.
    pub orthonormality_error: Option<f64>,
    /// Captured share of the static flexibility at the named points with a role.
    pub truncation: Vec<truncation::TruncationRow>,
    /// What building the structure did (e.g. springs treated as rigid).
    pub notes: Vec<String>,
    /// Doubtful findings, each naming the model field concerned.
    pub warnings: Vec<String>,
}

fn eff(a: [f64; 6]) -> EffectiveMass {
    EffectiveMass {
        x: a[0],
        y: a[1],
        z: a[2],
        rx: a[3],
        ry: a[4],
        rz: a[5],
    }
}

impl FemAnalysis {
    /// The mode table of an FE analysis: all computed modes, the signed shape value ψ along the
    /// impact direction at the named points, and the selection with its reason.
    pub fn report(&self) -> Result<ModeReport> {
        let nm = self.table.frequency_hz.len();
        let mut part: BTreeMap<String, Vec<f64>> = BTreeMap::new();
        for name in self.model.mesh.points.keys() {
            let f = self.model.point_functional(name)?;
            part.insert(
                name.clone(),
                (0..nm)
                    .map(|i| {
                        (0..f.len())
                            .map(|j| f[j] * self.modes.shapes[(j, i)])
                            .sum::<f64>()
                    })
                    .collect(),
            );
        }
        let modes = (0..nm)
            .map(|i| ModeRow {
                index: i + 1,
                frequency_hz: self.table.frequency_hz[i],
                effective_mass_kg: Some(eff(self.table.effective_mass[i])),
                psi_per_sqrt_kg: part.iter().map(|(k, v)| (k.clone(), v[i])).collect(),
                score: Some(self.scores[i]),
                selected: self.selected.contains(&i),
            })
            .collect();
        let selection = match &self.selection {
            Selection::Indices => "by index (select = [...])".to_string(),
            Selection::Band(b) => format!("by frequency band {} to {} Hz", b[0], b[1]),
            Selection::Auto {
                cutoff_hz,
                extra,
                points,
            } => format!(
                "auto: every mode moving {} up to {cutoff_hz:.1} Hz ({AUTO_CUTOFF_FACTOR} x the highest contact frequency, or auto_max_hz), plus {extra} above it by share of static flexibility",
                points.join(", ")
            ),
            Selection::Participation { count, points } => format!(
                "participation: the {count} modes with the largest participation score sum of psi(P)^2 at {}",
                points.join(", ")
            ),
        };
        Ok(ModeReport {
            modes,
            selected: self.selected.iter().map(|i| i + 1).collect(),
            selection,
            solver: self.solver.to_string(),
            dofs: self.model.n_dofs(),
            total_mass: Some(eff(self.table.total_mass)),
            selected_residuals: self.selected_residuals.clone(),
            static_correction: pseudo_mode_rows(&self.modal),
            orthonormality_error: Some(self.modes.orthonormality_error),
            truncation: Vec::new(),
            notes: Vec::new(),
            warnings: Vec::new(),
        })
    }
}

/// The mode table of a lumped or tabulated structure (all its modes are retained).
pub fn report_from_modal(m: &ModalModel) -> ModeReport {
    let n = m.len();
    let modes = (0..n)
        .map(|i| ModeRow {
            index: i + 1,
            frequency_hz: m.omega_rad_per_s[i] / (2.0 * std::f64::consts::PI),
            effective_mass_kg: None,
            psi_per_sqrt_kg: m.points.iter().map(|(k, v)| (k.clone(), v[i])).collect(),
            score: None,
            selected: true,
        })
        .collect();
    ModeReport {
        modes,
        selected: (1..=n).collect(),
        selection: "all modes of the lumped/tabulated structure".into(),
        solver: "lumped/modal".into(),
        dofs: 0,
        total_mass: None,
        selected_residuals: Vec::new(),
        static_correction: Vec::new(),
        orthonormality_error: None,
        truncation: Vec::new(),
        notes: Vec::new(),
        warnings: Vec::new(),
    }
}

impl ModeReport {
    /// The report with a model's truncation table, notes and warnings ([`Model::diagnostics`]).
    pub fn with_diagnostics(mut self, d: super::Diagnostics) -> Self {
        self.truncation = d.truncation;
        self.notes = d.notes;
        self.warnings = d.warnings;
        self
    }

    /// A fixed-width text table (one line per mode) followed by the selection, the truncation
    /// table and the notes (warnings are left to the caller, for stderr).
    pub fn to_text(&self) -> String {
        use std::fmt::Write;
        let points: Vec<String> = self
            .modes
            .first()
            .map(|r| r.psi_per_sqrt_kg.keys().cloned().collect())
            .unwrap_or_default();
        let mut s = String::new();
        let _ = write!(
            s,
            "{:>4} {:>12} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
            "mode", "Hz", "m_x kg", "m_y kg", "m_z kg", "I_rx", "I_ry", "I_rz"
        );
        for p in &points {
            let _ = write!(s, " {:>10}", format!("psi({p})"));
        }
        s.push_str("  sel\n");
        for r in &self.modes {
            let _ = write!(s, "{:>4} {:>12.4}", r.index, r.frequency_hz);
            match &r.effective_mass_kg {
                Some(e) => {
                    for v in [e.x, e.y, e.z, e.rx, e.ry, e.rz] {
                        let _ = write!(s, " {v:>9.3}");
                    }
                }
                None => {
                    for _ in 0..6 {
                        let _ = write!(s, " {:>9}", "-");
                    }
                }
            }
            for p in &points {
                let _ = write!(
                    s,
                    " {:>10.4e}",
                    r.psi_per_sqrt_kg.get(p).copied().unwrap_or(0.0)
                );
            }
            s.push_str(if r.selected { "  *\n" } else { "\n" });
        }
        let _ = writeln!(
            s,
            "selected modes {:?} ({}); solver {}, {} DOFs",
            self.selected, self.selection, self.solver, self.dofs
        );
        if !self.selected_residuals.is_empty() {
            let _ = writeln!(
                s,
                "relative residuals of the selected modes: {:?}",
                self.selected_residuals
                    .iter()
                    .map(|r| format!("{r:.1e}"))
                    .collect::<Vec<_>>()
            );
        }
        if !self.static_correction.is_empty() {
            let _ = writeln!(
                s,
                "static correction (Ritz vectors restoring the static flexibility of the modes left out; not modes of the structure):"
            );
            for r in &self.static_correction {
                let _ = write!(
                    s,
                    "  static correction {} {:>12.4} Hz  point '{}'",
                    r.index, r.frequency_hz, r.point
                );
                for p in &points {
                    let v = r.psi_per_sqrt_kg.get(p).copied().unwrap_or(0.0);
                    let _ = write!(s, "  psi({p}) {v:.4e}");
                }
                s.push('\n');
            }
        }
        s.push_str(&truncation::to_text(&self.truncation));
        for n in &self.notes {
            let _ = writeln!(s, "note: {n}");
        }
        s
    }

    /// CSV: `mode,frequency_hz,m_x_kg,...,I_rz_kg_m2,psi_<P>_per_sqrt_kg...,selected`, one
    /// `psi_<P>_per_sqrt_kg` column per named point in name order (byte order): the signed
    /// ψ_i(P) of [`ModeRow::psi_per_sqrt_kg`], written to round-trip (shortest exact decimal).
    pub fn to_csv(&self) -> String {
        let points: Vec<String> = self
            .modes
            .first()
            .map(|r| r.psi_per_sqrt_kg.keys().cloned().collect())
            .unwrap_or_default();
        let mut s =
            String::from("mode,frequency_hz,m_x_kg,m_y_kg,m_z_kg,i_rx_kg_m2,i_ry_kg_m2,i_rz_kg_m2");
        for p in &points {
            s.push_str(&format!(",psi_{p}_per_sqrt_kg"));
        }
        s.push_str(",selected\n");
        for r in &self.modes {
            s.push_str(&format!("{},{:e}", r.index, r.frequency_hz));
            match &r.effective_mass_kg {
                Some(e) => {
                    for v in [e.x, e.y, e.z, e.rx, e.ry, e.rz] {
                        s.push_str(&format!(",{v:e}"));
                    }
                }
                None => s.push_str(",,,,,,"),
            }
            for p in &points {
                s.push_str(&format!(
                    ",{:e}",
                    r.psi_per_sqrt_kg.get(p).copied().unwrap_or(0.0)
                ));
            }
            s.push_str(if r.selected { ",1\n" } else { ",0\n" });
        }
        s
    }
}
