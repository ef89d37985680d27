//! Plausibility of the numbers a user types: values far outside what impact machines have,
//! with the unit slip that would explain them.
//!
//! meid's model files are SI (kg, m, s, N). A value typed in another unit (a slider velocity in
//! mm/s, a spring in N/mm, a mesh in mm) is a valid number and runs, giving results wrong by
//! powers of 1000. Values no machine has are flagged here as **warnings**, not errors: an
//! unusual machine may be real, and a warning names the field, the value, what machines have,
//! and the likely slip. (FE materials are checked more strictly, as errors, by
//! `material::check_material_units`: a density and a Young's modulus together say their unit system.)
//!
//! A spring or a contact is flagged only when the unit slip named would make its value plausible
//! (a spring softer still is no slip; the propagator's conditioning check names springs too soft
//! to resolve). The bounds, each wide of every machine the field covers:
//! - **slider velocity** above [`MAX_BLOW_VELOCITY_M_PER_S`]: drop and counterblow hammers strike
//!   at 3–10 m/s, high-energy-rate hammers up to about 20–25 m/s, presses slower (the usual
//!   figures of forging handbooks); 1200 typed for 1200 mm/s is 1.2 m/s;
//! - **a mass** above [`MAX_MASS_KG`] (ten times the heaviest forging presses, about 1e7 kg), and a
//!   damper or added mass heavier than the whole lumped structure it is fixed to (a value in g);
//! - **a spring** on which the mass it holds would sag by more than [`MAX_STATIC_SAG_M`] under
//!   its own weight, `δ = m g / k` (a value in N/mm is 1000 times too soft: the paper's base
//!   sags 5 mm on its supports, its damper 19 mm on its spring);
//! - **a contact** that the blow would compress by more than [`MAX_CONTACT_COMPRESSION_M`]: the
//!   slider's whole kinetic energy in the contact spring, `δ = v_s √(m/K)` (an upper bound of the
//!   compression for the linear law: the struck side is held still), against the paper's 0.2 mm;
//! - **an FE structure** whose mesh spans more than [`MAX_STRUCTURE_EXTENT_M`] (coordinates in
//!   mm: a 2 m press read as 2 km).

use super::spec::{LawSpec, ModelSpec};
use super::Source;

/// Fastest blow a forging machine strikes with, m/s (high-energy-rate hammers reach ~25 m/s).
pub const MAX_BLOW_VELOCITY_M_PER_S: f64 = 50.0;
/// Heaviest body or lumped mass meid expects, kg (the largest forging presses weigh ~1e7 kg).
pub const MAX_MASS_KG: f64 = 1.0e8;
/// Largest static sag of a mounted mass under its own weight, m.
pub const MAX_STATIC_SAG_M: f64 = 1.0;
/// Largest compression of a contact by the blow, m.
pub const MAX_CONTACT_COMPRESSION_M: f64 = 0.05;
/// Largest extent (bounding-box diagonal) of an FE structure, m.
pub const MAX_STRUCTURE_EXTENT_M: f64 = 200.0;
/// Standard gravity, m/s² (only for the sag of the plausibility bound).
const G_M_PER_S2: f64 = 9.806_65;

/// The unit-slip warnings of `spec`, each `"<location>: <field> = <value> <unit> ..."` (the FE
/// structure's extent is checked where its mesh is built: [`extent_slip`]).
pub(super) fn unit_slips(spec: &ModelSpec, src: &Source) -> Vec<String> {
    // (field, text) of each finding.
    let mut found: Vec<(String, String)> = Vec::new();
    let mut warn = |field: &str, text: String| found.push((field.to_string(), text));
    let s = &spec.slider;
    if s.velocity.abs() > MAX_BLOW_VELOCITY_M_PER_S {
        warn(
            "slider.velocity",
            format!(
                "{} m/s is faster than any forging blow (hammers strike at 3-25 m/s, presses slower); velocities are in m/s: is it in mm/s ({} m/s)?",
                crate::num(s.velocity),
                crate::num(s.velocity / 1e3)
            ),
        );
    }
    let mut masses: Vec<(String, f64)> = vec![("slider.mass".into(), s.mass)];
    if let Some(d) = &spec.damper {
        masses.push(("damper.mass".into(), d.mass));
    }
    if let Some(m) = spec.added_mass.as_ref().and_then(|a| a.mass) {
        masses.push(("added_mass.mass".into(), m));
    }
    let lumped = spec.structure.lumped.as_ref();
    if let Some(l) = lumped {
        for (i, m) in l.masses.iter().enumerate() {
            masses.push((format!("structure.lumped.masses[{i}].mass"), m.mass));
        }
    }
    for (field, m) in &masses {
        if *m > MAX_MASS_KG {
            warn(
                field,
                format!(
                    "{} kg is heavier than any forging machine (the largest presses weigh about 1e7 kg); masses are in kg: is it in g ({} kg)?",
                    crate::num(*m),
                    crate::num(m / 1e3)
                ),
            );
        }
    }
    // A damper or added mass heavier than the whole lumped structure.
    let structure_kg: Option<f64> = lumped.map(|l| l.masses.iter().map(|m| m.mass).sum());
    if let Some(total) = structure_kg.filter(|t| *t > 0.0) {
        for (field, m) in masses.iter().filter(|(f, _)| f != "slider.mass") {
            if field.starts_with("structure.") || *m <= total {
                continue;
            }
            warn(
                field,
                format!(
                    "{} kg is heavier than the whole structure it is fixed to ({} kg, the sum of structure.lumped.masses); a damper is a fraction of the machine's mass: is it in g ({} kg)?",
                    crate::num(*m),
                    crate::num(total),
                    crate::num(m / 1e3)
                ),
            );
        }
    }
    sags(spec, &mut found);
    // A slip in the velocity is named above; the compressions it implies would repeat it.
    if s.velocity.abs() <= MAX_BLOW_VELOCITY_M_PER_S {
        contacts(spec, &mut found);
    }
    found
        .into_iter()
        .map(|(f, t)| format!("{}: {f} = {t}", src.locate(&f)))
        .collect()
}

/// Springs on which their mass would sag by more than [`MAX_STATIC_SAG_M`] (a spring-mass
/// frequency below `√(g/1 m)/2π` = 0.5 Hz): the damper's spring under the damper, and each lumped
/// spring under the lighter of the masses it joins (ground counts as infinitely heavy). A spring
/// is not judged by a mass already found suspect (in `found`).
fn sags(spec: &ModelSpec, found: &mut Vec<(String, String)>) {
    let suspect: Vec<String> = found.iter().map(|(f, _)| f.clone()).collect();
    let mut check = |field: &str, k: f64, m: f64, mass_field: &str, what: &str| {
        if !(k > 0.0 && m > 0.0) || suspect.iter().any(|f| f == mass_field) {
            return;
        }
        let sag = m * G_M_PER_S2 / k;
        // Only when N/mm explains it (a spring softer still is no unit slip: the propagator's
        // conditioning check names a spring too soft to resolve).
        if sag > MAX_STATIC_SAG_M && sag / 1e3 <= MAX_STATIC_SAG_M {
            found.push((
                field.to_string(),
                format!(
                    "{} N/m would let {what} ({} kg) sag {sag:.3} m under its own weight (m g / k); stiffnesses are in N/m: is it in N/mm ({} N/m)?",
                    crate::num(k),
                    crate::num(m),
                    crate::num(k * 1e3)
                ),
            ));
        }
    };
    if let Some(d) = &spec.damper {
        check(
            "damper.stiffness",
            d.stiffness,
            d.mass,
            "damper.mass",
            "the damper",
        );
    }
    if let Some(l) = spec.structure.lumped.as_ref() {
        // (mass kg, its index) of a node; ground (or an unknown name) is infinitely heavy.
        let mass_of = |node: &str| {
            l.masses
                .iter()
                .position(|m| m.name == node)
                .map_or((f64::INFINITY, usize::MAX), |i| (l.masses[i].mass, i))
        };
        for (i, s) in l.springs.iter().enumerate() {
            let (a, b) = (mass_of(&s.nodes[0]), mass_of(&s.nodes[1]));
            let ((m, j), node) = if a.0 <= b.0 {
                (a, &s.nodes[0])
            } else {
                (b, &s.nodes[1])
            };
            if m.is_finite() {
                check(
                    &format!("structure.lumped.springs[{i}].stiffness"),
                    s.stiffness,
                    m,
                    &format!("structure.lumped.masses[{j}].mass"),
                    &format!("the mass '{node}' it holds"),
                );
            }
        }
    }
}

/// Linear contacts the blow would compress by more than [`MAX_CONTACT_COMPRESSION_M`]:
/// `δ = v_s √(m/K)`, the body's kinetic energy `m v_s²/2` stored in `K δ²/2`.
fn contacts(spec: &ModelSpec, found: &mut Vec<(String, String)>) {
    let v = spec.slider.velocity.abs();
    let mut list = vec![(
        "contact.slider_bed.stiffness",
        &spec.contact.slider_bed,
        spec.slider.mass,
        "slider.mass",
        "the slider",
    )];
    if let (Some(c), Some(d)) = (&spec.contact.bed_damper, &spec.damper) {
        list.push((
            "contact.bed_damper.stiffness",
            c,
            d.mass,
            "damper.mass",
            "the damper",
        ));
    }
    for (field, c, m, mass_field, body) in list {
        if c.law != LawSpec::Linear || !(c.stiffness > 0.0 && m > 0.0) {
            continue;
        }
        let delta = v * (m / c.stiffness).sqrt();
        // Only when N/mm explains it (K × 1000 compresses √1000 times less).
        let explained = delta / 1e3_f64.sqrt() <= MAX_CONTACT_COMPRESSION_M;
        if delta > MAX_CONTACT_COMPRESSION_M
            && explained
            && !found.iter().any(|(f, _)| *f == mass_field)
        {
            found.push((
                field.to_string(),
                format!(
                    "{} N/m lets {body} ({} kg at {} m/s) compress the contact by up to {delta:.3} m (v √(m/K)), no contact of a die or a stop; stiffnesses are in N/m: is it in N/mm ({} N/m)?",
                    crate::num(c.stiffness),
                    crate::num(m),
                    crate::num(v),
                    crate::num(c.stiffness * 1e3)
                ),
            ));
        }
    }
}

/// The warning for an FE structure whose mesh spans `extent_m` (its bounding-box diagonal, m)
/// more than [`MAX_STRUCTURE_EXTENT_M`], located at `field`.
pub(super) fn extent_slip(extent_m: f64, field: &str, src: &Source) -> Option<String> {
    (extent_m > MAX_STRUCTURE_EXTENT_M).then(|| {
        format!(
            "{}: {field}: a structure {} m across (the diagonal of its mesh's bounding box) is larger than any machine; coordinates and lengths are in m: is the mesh in mm ({} m)?",
            src.locate(field),
            crate::num(extent_m),
            crate::num(extent_m / 1e3)
        )
    })
}

#[cfg(test)]
mod tests {
    use crate::model::Model;

    const LUMPED: &str = include_str!("../../../../examples/paper-lumped.toml");

    /// The unit-slip warnings of the paper's lumped example with `overrides`.
    fn slips(overrides: &[&str]) -> Vec<String> {
        let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        let m = Model::from_text("paper-lumped.toml", LUMPED.to_string(), &o).expect("model");
        super::unit_slips(&m.spec, &m.source)
    }

    #[test]
    fn the_paper_machine_is_plausible() {
        assert_eq!(slips(&[]), Vec::<String>::new());
    }

    #[test]
    fn each_slip_is_named_with_its_likely_unit() {
        let cases: [(&str, &str, &str); 7] = [
            (
                "slider.velocity=1200",
                "slider.velocity = 1200 m/s",
                "mm/s (1.2 m/s)",
            ),
            (
                "damper.mass=3500",
                "damper.mass = 3500 kg",
                "heavier than the whole structure",
            ),
            (
                "slider.mass=2e9",
                "slider.mass = 2e9 kg",
                "in g (2000000 kg)",
            ),
            (
                "damper.stiffness=1.8",
                "damper.stiffness = 1.8 N/m",
                "N/mm (1800 N/m)",
            ),
            (
                "structure.lumped.springs[1].stiffness=81.2",
                "the mass 'base'",
                "N/mm (81200 N/m)",
            ),
            (
                "contact.slider_bed.stiffness=4.3e2",
                "compress the contact",
                "N/mm (430000 N/m)",
            ),
            (
                "contact.bed_damper.stiffness=1.25e3",
                "the damper (3.5 kg",
                "N/mm",
            ),
        ];
        for (set, field, hint) in cases {
            let w = slips(&[set]);
            assert_eq!(w.len(), 1, "{set}: {w:?}");
            assert!(
                w[0].starts_with("--set ") && w[0].contains(field) && w[0].contains(hint),
                "{set}: {}",
                w[0]
            );
        }
    }

    #[test]
    fn values_inside_the_bounds_are_quiet() {
        // Just inside each bound: 50 m/s, a 1 m sag, a 50 mm compression.
        let k_sag = 3.5 * super::G_M_PER_S2 / 0.999;
        let k_contact = 1.2 * (1.2_f64 / 0.0499).powi(2);
        let w = slips(&[
            "slider.velocity=1.2",
            &format!("damper.stiffness={k_sag}"),
            &format!("contact.slider_bed.stiffness={k_contact}"),
        ]);
        assert_eq!(w, Vec::<String>::new());
        // A damper as heavy as the whole lumped structure (10 + 41 kg).
        assert_eq!(slips(&["damper.mass=51"]), Vec::<String>::new());
        assert_eq!(slips(&["damper.mass=51.01"]).len(), 1);
        assert_eq!(slips(&["slider.velocity=50"]), Vec::<String>::new());
        // Softer than any unit slip explains: left to the propagator's conditioning check.
        assert_eq!(slips(&["damper.stiffness=1e-6"]), Vec::<String>::new());
        assert_eq!(
            slips(&["contact.slider_bed.stiffness=1e-2"]),
            Vec::<String>::new()
        );
        assert_eq!(slips(&["slider.velocity=50.001"]).len(), 1);
    }
}
