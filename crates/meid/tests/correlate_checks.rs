//! `meid correlate` and `meid calibrate --modal` in the library: the MAC against closed forms,
//! the pairing rule, blind-point warnings, mapping by name and by coordinates with the sign of
//! the direction, the test geometry read back, bad identified files, and model updating that
//! recovers a perturbed stiffness.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use meid::measure::correlate::{
    collinear, correlate, geometry_uff, mac_matrix, map_points, pair_modes, parse_point_label,
    read_identified, IdentifiedMode, IdentifiedModes, Mapping, ModelModes, Settings,
};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn lumped() -> meid::model::Model {
    meid::model::Model::from_file(&root().join("examples/paper-lumped.toml"), &[]).unwrap()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("meid-correlate-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A model of three points a, b, c (display line x = 0, 1, 2) with the given shapes (per point,
/// per mode) and frequencies.
fn model(freqs: &[f64], shapes: &[(&str, Vec<f64>)]) -> ModelModes {
    let points: BTreeMap<String, Vec<f64>> = shapes
        .iter()
        .map(|(n, v)| (n.to_string(), v.clone()))
        .collect();
    let coordinates = shapes
        .iter()
        .enumerate()
        .map(|(k, (n, _))| (n.to_string(), [k as f64, 0.0, 0.0]))
        .collect();
    ModelModes {
        frequencies_hz: freqs.to_vec(),
        labels: (1..=freqs.len()).map(|k| format!("mode {k}")).collect(),
        points,
        coordinates,
        geometric: false,
    }
}

fn identified(labels: &[&str], modes: &[(f64, Vec<f64>)]) -> IdentifiedModes {
    IdentifiedModes {
        file: "test.json".into(),
        points: labels.iter().map(|l| parse_point_label(l)).collect(),
        modes: modes
            .iter()
            .map(|(f, s)| IdentifiedMode {
                frequency_hz: *f,
                damping_ratio: 0.01,
                shape: s.clone(),
            })
            .collect(),
    }
}

/// MAC of a vector with a multiple of itself is 1, with an orthogonal vector 0, and of
/// (1, 0) with (1, 1) it is (1·1)²/(1·2) = 1/2.
#[test]
fn mac_closed_forms() {
    let m = mac_matrix(
        &[vec![1.0, 2.0, 3.0], vec![1.0, 0.0, 0.0]],
        &[
            vec![-2.0, -4.0, -6.0],
            vec![3.0, 0.0, -1.0],
            vec![1.0, 1.0, 0.0],
        ],
    );
    assert!((m[0][0] - 1.0).abs() < 1e-15, "{m:?}");
    assert_eq!(m[0][1], 0.0);
    assert!((m[1][2] - 0.5).abs() < 1e-15);
    assert!((m[1][1] - 0.9).abs() < 1e-15, "9/10: {m:?}");
}

/// The pairing takes the largest MAC first and uses each model mode once: on a permuted set it
/// recovers the permutation, and where a row-wise maximum would give one model mode twice
/// (both rows peak in column 0) the second row gets column 1.
#[test]
fn pairing_on_a_permuted_set() {
    let perm = [2usize, 0, 1];
    let mac: Vec<Vec<f64>> = (0..3)
        .map(|i| {
            (0..3)
                .map(|j| if j == perm[i] { 0.97 } else { 0.1 })
                .collect()
        })
        .collect();
    let pairs = pair_modes(&mac, 0.5, |_, _| 0.0);
    assert_eq!(pairs, vec![(0, 2), (1, 0), (2, 1)]);
    let greedy = pair_modes(&[vec![0.9, 0.8], vec![0.95, 0.1]], 0.5, |_, _| 0.0);
    assert_eq!(greedy, vec![(0, 1), (1, 0)]);
    // Below min_mac nothing pairs.
    assert!(pair_modes(&[vec![0.4]], 0.5, |_, _| 0.0).is_empty());
}

/// Two model modes alike at the measured points (auto-MAC > 0.9) and fewer points than modes
/// are both warned about; points spread well are not.
#[test]
fn blind_points_are_warned_about() {
    let m = model(
        &[10.0, 20.0],
        &[
            ("a", vec![1.0, 1.0]),
            ("b", vec![1.0, 1.1]),
            ("c", vec![1.0, -1.0]),
        ],
    );
    let id = identified(&["a:1 +Z", "b:2 +Z"], &[(10.0, vec![1.0, 1.0])]);
    let c = correlate(&id, &m, &Mapping::default(), &Settings::default()).unwrap();
    assert!(c.auto_mac[0][1] > 0.9);
    assert!(
        c.warnings
            .iter()
            .any(|w| w.contains("auto-MAC of model modes 1 and 2")),
        "{:?}",
        c.warnings
    );
    let id1 = identified(&["a:1 +Z"], &[(10.0, vec![1.0])]);
    let c1 = correlate(&id1, &m, &Mapping::default(), &Settings::default()).unwrap();
    assert!(
        c1.warnings
            .iter()
            .any(|w| w.contains("fewer points than modes")),
        "{:?}",
        c1.warnings
    );
    let good = identified(
        &["a:1 +Z", "c:3 +Z"],
        &[(10.0, vec![1.0, 1.0]), (21.0, vec![1.0, -1.0])],
    );
    let cg = correlate(&good, &m, &Mapping::default(), &Settings::default()).unwrap();
    assert!(cg.warnings.is_empty(), "{:?}", cg.warnings);
    assert_eq!(cg.pairs.len(), 2);
    assert!((cg.pairs[1].error_percent - 5.0).abs() < 1e-12);
    // Collinear points.
    assert!(collinear(
        &[[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [2.0, 2.0, 0.0]],
        1e-9
    ));
    assert!(!collinear(
        &[[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [2.0, 2.1, 0.0]],
        1e-9
    ));
}

/// By name with a −Z point: its values are compared negated (sign −1), so an identified shape
/// measured with the accelerometer upside down at b correlates at MAC 1; read as +Z it would
/// not (closed form: (1 − 1)² / … = 0 for (1, −1) against (1, 1)).
#[test]
fn mapping_by_name_flips_the_sign_of_minus_z() {
    let m = model(&[10.0], &[("a", vec![1.0]), ("b", vec![1.0])]);
    let flipped = identified(&["a:1 +Z", "b:2 -Z"], &[(10.0, vec![1.0, -1.0])]);
    let c = correlate(&flipped, &m, &Mapping::default(), &Settings::default()).unwrap();
    assert_eq!(c.points[1].sign, -1.0);
    assert_eq!(c.points[1].rule, "name");
    assert!((c.mac[0][0] - 1.0).abs() < 1e-15);
    let plain = identified(&["a:1 +Z", "b:2 +Z"], &[(10.0, vec![1.0, -1.0])]);
    let c = correlate(&plain, &m, &Mapping::default(), &Settings::default()).unwrap();
    assert!(c.mac[0][0].abs() < 1e-15);
    // An X direction is refused, naming the file, the point and the valid directions.
    let x = identified(&["a:1 +X"], &[(10.0, vec![1.0])]);
    let e = correlate(&x, &m, &Mapping::default(), &Settings::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("test.json") && e.contains("a:1 +X") && e.contains("+Z and -Z"),
        "{e}"
    );
}

/// By coordinates: nodes within the tolerance of the model's points map to them (the nearest);
/// a node beyond it is unmapped, and the error names the file, the point and the model's
/// points.
#[test]
fn mapping_by_coordinates_with_tolerance() {
    let m = model(
        &[10.0, 30.0],
        &[("a", vec![1.0, 1.0]), ("b", vec![2.0, -1.0])],
    );
    let id = identified(&["7 +Z", "9 -Z"], &[(10.0, vec![1.0, -2.0])]);
    let nodes = BTreeMap::from([(7, [1.0005, 0.0, 0.0]), (9, [0.0, 0.0, 0.0002])]);
    let mapping = Mapping {
        geometry: Some(("geo.uff".into(), nodes.clone(), 1e-3)),
        ..Default::default()
    };
    let (mapped, _) = map_points(&id, &m, &mapping).unwrap();
    assert_eq!(mapped[0].model_point, "b");
    assert_eq!(mapped[1].model_point, "a");
    assert_eq!(mapped[1].sign, -1.0);
    assert!((mapped[0].distance_m.unwrap() - 5e-4).abs() < 1e-12);
    // Identified (1, −2) at (b, −a): the model's mode 1 there is (2, −1)·… → (2, −1) vs (1, −2)
    // after the sign: model vector (ψ_b, −ψ_a) = (2, −1); MAC = (2 + 2)²/(5·5) = 16/25.
    let c = correlate(&id, &m, &mapping, &Settings::default()).unwrap();
    assert!((c.mac[0][0] - 16.0 / 25.0).abs() < 1e-15, "{:?}", c.mac);
    let far = Mapping {
        geometry: Some(("geo.uff".into(), nodes, 1e-4)),
        ..Default::default()
    };
    let e = map_points(&id, &m, &far).unwrap_err().to_string();
    assert!(
        e.contains("test.json") && e.contains("unmapped point(s) 7 +Z") && e.contains("a, b"),
        "{e}"
    );
}

/// The geometry meid writes for the lumped example reads back with meid's own reader: nodes
/// (dataset 15), the trace line (82), the rod (2412) and the modes (55) as written.
#[test]
fn geometry_reads_back() {
    let m = lumped();
    let s = &m.structure;
    let mm = ModelModes::new(&m, None);
    let bytes = geometry_uff(&m, &mm).unwrap();
    let u = meid::io::uff::parse_uff(bytes.as_slice(), "geometry.uff", None).unwrap();
    assert_eq!(u.nodes.len(), 2);
    assert_eq!(u.nodes[1].label, 2);
    assert_eq!(u.nodes[1].xyz, [1.0, 0.0, 0.0]);
    assert_eq!(u.traces.len(), 1);
    assert_eq!(u.traces[0].nodes, vec![1, 2]);
    assert_eq!(u.elements.len(), 1);
    assert_eq!(
        (u.elements[0].fe_descriptor, u.elements[0].nodes.clone()),
        (11, vec![1, 2])
    );
    assert_eq!(u.modes.len(), 2);
    assert!(u.skipped.is_empty(), "{:?}", u.skipped);
    for (i, md) in u.modes.iter().enumerate() {
        let w = s.omega_rad_per_s[i] / (2.0 * std::f64::consts::PI);
        assert!((md.frequency_hz - w).abs() <= 1e-5 * w);
        for (node, name) in [(1, "base"), (2, "bed")] {
            let z = md.shapes.iter().find(|x| x.0 == node).unwrap().1[2];
            let psi = s.points[name][i];
            assert!((z - psi).abs() <= 1e-5 * psi.abs(), "{z} vs {psi}");
        }
    }
    // The same modes correlate with themselves read as identified modes (UFF 55): MAC 1 on the
    // diagonal, frequency errors within the 6 printed digits.
    let dir = tmp("geo");
    let f = dir.join("modes.uff");
    std::fs::write(&f, &bytes).unwrap();
    let id = read_identified(&f).unwrap();
    // Its points are node numbers: by name they map to nothing (error), by the file's own
    // coordinates to the points they were written for.
    let e = correlate(&id, &mm, &Mapping::default(), &Settings::default()).unwrap_err();
    assert!(
        e.to_string().contains("unmapped point(s) 1 +Z, 2 +Z"),
        "{e}"
    );
    let nodes = u.nodes.iter().map(|n| (n.label, n.xyz)).collect();
    let by_xyz = Mapping {
        geometry: Some(("geometry.uff".into(), nodes, 1e-9)),
        ..Default::default()
    };
    let c = correlate(&id, &mm, &by_xyz, &Settings::default()).unwrap();
    assert_eq!(c.pairs.len(), 2);
    for p in &c.pairs {
        assert_eq!(p.identified_mode, p.model_mode);
        assert!(p.mac > 0.99999 && p.error_percent.abs() < 1e-3, "{p:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Identified files without shapes, or naming points the model lacks, or asking more modes than
/// points, are refused naming the file and the field.
#[test]
fn bad_identified_files() {
    let dir = tmp("bad");
    let f = dir.join("noshape.json");
    std::fs::write(
        &f,
        r#"{"points": ["bed:1 +Z"], "modes": [{"frequency_hz": 280.0, "damping_ratio": 0.01}]}"#,
    )
    .unwrap();
    let e = read_identified(&f).unwrap_err().to_string();
    assert!(
        e.contains("noshape.json") && e.contains("modes[0].shape"),
        "{e}"
    );
    let f = dir.join("nopoints.json");
    std::fs::write(
        &f,
        r#"{"modes": [{"frequency_hz": 280.0, "shape": [1.0]}]}"#,
    )
    .unwrap();
    let e = read_identified(&f).unwrap_err().to_string();
    assert!(e.contains("nopoints.json") && e.contains("points"), "{e}");
    let f = dir.join("short.json");
    std::fs::write(&f, r#"{"points": ["bed:1 +Z", "base:2 +Z"], "modes": [{"frequency_hz": 280.0, "shape": [1.0]}]}"#).unwrap();
    let e = read_identified(&f).unwrap_err().to_string();
    assert!(e.contains("1 values for 2 points"), "{e}");
    let mm = ModelModes::new(&lumped(), None);
    let id = identified(&["anvil:1 +Z"], &[(280.0, vec![1.0])]);
    let e = correlate(&id, &mm, &Mapping::default(), &Settings::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("unmapped point(s) anvil:1 +Z") && e.contains("base, bed"),
        "{e}"
    );
    let id = identified(&["bed:1 +Z"], &[(280.0, vec![1.0])]);
    let s = Settings {
        model_modes: Some(2),
        ..Settings::default()
    };
    let e = correlate(&id, &mm, &Mapping::default(), &s)
        .unwrap_err()
        .to_string();
    assert!(e.contains("fewer than the 2 modes asked"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The identified modes of the lumped example with its column stiffness 8 % stiffer (its exact
/// modes, real-normalised as meid identify writes them) bring `calibrate --modal` from the
/// example's stiffness back to the perturbed one within 1 % (noise-free data: far closer), and
/// the frequencies agree after the fit.
#[test]
fn modal_update_recovers_a_perturbed_stiffness() {
    use meid::measure::calibrate::{parameters, Settings as FitSettings};
    use meid::measure::modal_update::{calibrate_modal, ModalProblem};
    let path = "structure.lumped.springs[0].stiffness";
    let base = lumped();
    let k0 = 2.5415164e7;
    let k_true = 1.08 * k0;
    let perturbed = base
        .with_fields(&[format!("{path}={k_true:e}")], None)
        .unwrap();
    let s = &perturbed.structure;
    let names = ["bed", "base"];
    let modes = (0..s.len())
        .map(|i| {
            let v: Vec<f64> = names.iter().map(|p| s.points[*p][i]).collect();
            let top = v
                .iter()
                .copied()
                .fold(0.0_f64, |a, x| if x.abs() > a.abs() { x } else { a });
            (
                s.omega_rad_per_s[i] / (2.0 * std::f64::consts::PI),
                v.iter().map(|x| x / top).collect(),
            )
        })
        .collect::<Vec<_>>();
    let id = identified(&["bed:1 +Z", "base:2 +Z"], &modes);
    let params = parameters(&base, &[path.to_string()], &BTreeMap::new()).unwrap();
    assert_eq!(params[0].start, k0);
    let problem = ModalProblem::new(
        &base,
        params,
        &id,
        None,
        Mapping::default(),
        Settings::default(),
        1.0,
        FitSettings::default(),
    )
    .unwrap();
    let c = calibrate_modal(&problem).unwrap();
    assert!(c.converged, "{:?}", c.convergence);
    let k = c.parameters[0].value;
    assert!(((k - k_true) / k_true).abs() < 1e-2, "{k} vs {k_true}");
    assert!(
        ((k - k_true) / k_true).abs() < 1e-6,
        "noise-free: {k} vs {k_true}"
    );
    assert!(
        c.parameters[0].ci95_low <= k_true * (1.0 + 1e-6)
            && k_true * (1.0 - 1e-6) <= c.parameters[0].ci95_high
    );
    assert!(c
        .pairs
        .iter()
        .all(|p| p.error_after_percent.abs() < 1e-4 && p.mac_after > 0.999999));
    assert!(c.pairs.iter().any(|p| p.error_before_percent.abs() > 0.5));
}
