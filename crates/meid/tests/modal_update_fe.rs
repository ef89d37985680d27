//! Issue 32 item 6d: model updating (`meid calibrate --modal`) recovers a perturbed bed-plate
//! thickness, and separately a support spring's vertical stiffness, of the FE machine to 1 %
//! from its own modes.
//!
//! The machine is `examples/paper-soft-base.toml` at 6 elements per side (as the FE tests keep
//! their meshes small; about 0.1 s per model). The "measured" modes are the true (perturbed)
//! model's own retained modes at its three named points (B, O_b, O_f), real-normalised as
//! `meid identify` writes them; the fit starts from the example's value. Noise-free data: the
//! true value is the least-squares minimum (every residual 0 there), so the fit must land on it
//! far closer than the 1 %; the 95 % interval must hold it and the paired frequencies
//! must agree after the fit.

use std::collections::BTreeMap;
use std::path::Path;

use meid::measure::calibrate::{parameters, Settings as FitSettings};
use meid::measure::correlate::{
    parse_point_label, IdentifiedMode, IdentifiedModes, Mapping, Settings,
};
use meid::measure::modal_update::{calibrate_modal, ModalProblem};
use meid::model::Model;

const COARSE: &str = "structure.fem.machine.elements_per_side=6";
const THICKNESS: &str = "structure.fem.machine.bed.thickness";
const SPRING: &str = "structure.fem.machine.spring_stiffness[2]";

fn machine(extra: &[String]) -> Model {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper-soft-base.toml");
    let mut set = vec![COARSE.to_string()];
    set.extend_from_slice(extra);
    Model::from_file(&path, &set).unwrap()
}

/// The model's retained structural modes at its named points, each shape scaled to its largest
/// entry 1.
fn own_modes(m: &Model) -> IdentifiedModes {
    let s = &m.structure;
    let names: Vec<&String> = s.points.keys().collect();
    // The structure's modes (static-correction pseudo-modes are no modes a test finds).
    let modes = (0..s.len())
        .filter(|&i| !s.is_pseudo(i))
        .map(|i| {
            let v: Vec<f64> = names.iter().map(|p| s.points[*p][i]).collect();
            let top = v
                .iter()
                .copied()
                .fold(0.0_f64, |a, x| if x.abs() > a.abs() { x } else { a });
            IdentifiedMode {
                frequency_hz: s.omega_rad_per_s[i] / (2.0 * std::f64::consts::PI),
                damping_ratio: 0.01,
                shape: v.iter().map(|x| x / top).collect(),
            }
        })
        .collect();
    IdentifiedModes {
        file: "own modes".into(),
        points: names
            .iter()
            .enumerate()
            .map(|(k, n)| parse_point_label(&format!("{n}:{} +Z", k + 1)))
            .collect(),
        modes,
    }
}

/// Fits `paths` of the example (from its values) to the modes `id`, checking that the fit
/// converged and paired every mode.
fn fit(paths: &[&str], id: &IdentifiedModes) -> meid::measure::modal_update::ModalCalibration {
    let base = machine(&[]);
    let paths: Vec<String> = paths.iter().map(|p| p.to_string()).collect();
    let params = parameters(&base, &paths, &BTreeMap::new()).unwrap();
    let problem = ModalProblem::new(
        &base,
        params,
        id,
        None,
        Mapping::default(),
        Settings::default(),
        1.0,
        FitSettings::default(),
    )
    .unwrap();
    let c = calibrate_modal(&problem).unwrap();
    assert!(c.converged, "{:?}", c.convergence);
    assert_eq!(c.pairs.len(), id.modes.len());
    c
}

/// Fits `paths` of the example to the modes of the example with `truth` set; returns the
/// fitted values after checking the fit converged, every pair agrees after it and the
/// intervals hold the true values.
fn recover(paths: &[&str], truth: &[f64]) -> Vec<f64> {
    let set: Vec<String> = paths
        .iter()
        .zip(truth)
        .map(|(p, v)| format!("{p}={v:e}"))
        .collect();
    let truth_model = machine(&set);
    let id = own_modes(&truth_model);
    assert!(id.modes.len() >= 2, "{} modes", id.modes.len());
    let c = fit(paths, &id);
    assert!(c.pairs.iter().any(|p| p.error_before_percent.abs() > 0.5));
    for p in &c.pairs {
        assert!(
            p.error_after_percent.abs() < 1e-3 && p.mac_after > 0.99999,
            "{p:?}"
        );
    }
    for (e, t) in c.parameters.iter().zip(truth) {
        assert!(
            e.ci95_low <= t * (1.0 + 1e-6) && t * (1.0 - 1e-6) <= e.ci95_high,
            "{e:?} vs {t}"
        );
    }
    c.values()
}

#[test]
fn modal_update_recovers_the_bed_plate_thickness() {
    // The example's 10.95 mm plate, truly 6 % thicker.
    let t0 = 0.01095;
    let t_true = 1.06 * t0;
    let t = recover(&[THICKNESS], &[t_true])[0];
    let err = (t - t_true) / t_true;
    assert!(err.abs() < 1e-2, "{t} vs {t_true}");
    assert!(err.abs() < 1e-5, "noise-free: {t} vs {t_true} ({err:e})");
}

#[test]
fn modal_update_recovers_the_support_spring_stiffness() {
    // The vertical stiffness of each coil spring, 2.111e4 N/m in the example, truly 10 % softer.
    let k_true = 0.9 * 2.111e4;
    let k = recover(&[SPRING], &[k_true])[0];
    let err = (k - k_true) / k_true;
    assert!(err.abs() < 1e-2, "{k} vs {k_true}");
    assert!(err.abs() < 1e-5, "noise-free: {k} vs {k_true} ({err:e})");
}

#[test]
fn modal_update_recovers_thickness_and_spring_together() {
    let truth = [0.97 * 0.01095, 1.08 * 2.111e4];
    let got = recover(&[THICKNESS, SPRING], &truth);
    for (g, t) in got.iter().zip(truth) {
        let err = (g - t) / t;
        assert!(err.abs() < 1e-2, "{g} vs {t}");
        assert!(err.abs() < 1e-5, "noise-free: {g} vs {t} ({err:e})");
    }
}

/// Issue 32 item 6d from modes *identified* from blows, as a test lab has them: the machine
/// with its plate truly 3 % thinner and its springs truly 8 % stiffer struck three times,
/// velocities at O_b, O_f and B with 0.2 % noise, modes identified on 2..400 Hz
/// (`identify_checks::modes_from_blows`, the same chain as item 6b); the example is fitted to
/// them. Both values come back within the 1 %. (The identified modes carry the
/// identification's own errors, about 3e-4 in the 6.35 Hz bounce mode's frequency on 2 s
/// records, so the fit is not exact as with the model's own modes above.) The machine is the
/// example as meid builds it, with the static correction (its pseudo-modes are in the blows,
/// not among the modes identified or fitted).
#[test]
fn modal_update_from_identified_modes_recovers_thickness_and_spring() {
    const POINTS: [&str; 3] = ["O_b", "O_f", "B"];
    let truth = [0.97 * 0.01095, 1.08 * 2.111e4];
    let set: Vec<String> = [THICKNESS, SPRING]
        .iter()
        .zip(truth)
        .map(|(p, v)| format!("{p}={v:e}"))
        .collect();
    let truth_model = machine(&set);
    let s = &truth_model.structure;
    let n_band = (0..s.len())
        .filter(|&i| !s.is_pseudo(i) && s.omega_rad_per_s[i] / (2.0 * std::f64::consts::PI) < 400.0)
        .count();
    let ident =
        crate::identify_checks::modes_from_blows(&truth_model, &POINTS, (2.0, 400.0), n_band);
    assert_eq!(ident.modes.len(), n_band, "{:#?}", ident.modes);
    let id = IdentifiedModes {
        file: "identified from blows".into(),
        points: POINTS
            .iter()
            .enumerate()
            .map(|(k, n)| parse_point_label(&format!("{n}:{} +Z", k + 1)))
            .collect(),
        modes: ident.modes.iter().map(IdentifiedMode::from).collect(),
    };
    let c = fit(&[THICKNESS, SPRING], &id);
    for (g, t) in c.values().iter().zip(truth) {
        let err = (g - t) / t;
        eprintln!("from identified modes: {g:e} vs {t:e} ({err:.2e})");
        assert!(err.abs() < 1e-2, "{g} vs {t} ({err:e})");
    }
    for p in &c.pairs {
        assert!(p.error_after_percent.abs() < 0.1, "{p:?}");
    }
}
