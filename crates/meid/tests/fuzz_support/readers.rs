//! The properties of the measured-data and mode-file readers on any input, shared by the
//! proptest suite (`tests/fuzz_measure_readers.rs`, stable, in `cargo test`) and the cargo-fuzz
//! target `readers` (`fuzz/`, nightly), which include this file: UFF (58/58b/2411/55), CSV,
//! CalculiX `.frd`, and the modes import (`[structure.modes]`) of what a reader accepted.
//!
//! A reader returns `Ok` or an error; it never panics. What an `Ok` promises is checked: finite
//! values, no more samples or nodes than the file has bytes, an abscissa as long as the values,
//! and an imported modal model that validates (finite, ascending, one value per mode per point).
#![allow(dead_code)]

use meid::io::csv_records::parse_csv;
use meid::io::frd;
use meid::io::uff;
use meid::measure::Abscissa;
use meid::model::imported;
use meid::model::{ModesFileSpec, Source};

/// The modes import on what a reader accepted: never panics; an accepted model is valid.
pub fn check_import(modes: &[imported::FileMode], points: &[(&str, i64)]) {
    let src = Source {
        name: "fuzz.toml".into(),
        text: String::new(),
        overrides: Vec::new(),
    };
    for assumed in [None, Some(true)] {
        if let Ok(m) = imported::build(modes, &import_spec(points, assumed), "fuzz", &src) {
            m.validate().unwrap();
            assert!(m.omega_rad_per_s.windows(2).all(|w| w[1] >= w[0]));
            for v in m.points.values() {
                assert_eq!(v.len(), m.len());
                assert!(v.iter().all(|x| x.is_finite()));
            }
        }
    }
}

pub fn check_frd(bytes: &[u8]) {
    if let Ok(f) = frd::parse_frd(bytes, "fuzz.frd") {
        for (_, x) in &f.nodes {
            assert!(x.iter().all(|v| v.is_finite()));
        }
        for m in &f.modes {
            assert!(m.frequency_hz.is_finite());
            assert!(m.displacements.len() <= bytes.len());
            assert!(m
                .displacements
                .iter()
                .all(|(_, u)| u.iter().all(|v| v.is_finite())));
        }
        check_import(&imported::modes_from_frd(&f), &[("O_b", 3), ("B", 2)]);
    }
}

pub fn check_uff(bytes: &[u8]) {
    if let Ok(f) = uff::parse_uff(bytes, "fuzz.uff", Some(bytes.len() as u64)) {
        for r in &f.records {
            assert!(r.values.iter().all(|v| v.is_finite()));
            assert!(r.values.len() as u64 <= bytes.len() as u64);
            match &r.abscissa {
                Abscissa::Uneven(t) => {
                    assert_eq!(t.len(), r.values.len());
                    assert!(t.windows(2).all(|w| w[1] > w[0]));
                    assert!(t.iter().all(|v| v.is_finite()));
                }
                // Every sample's time, the record's end and the rate are finite numbers.
                Abscissa::Even { start_s, step_s } => {
                    let last = start_s + r.values.len() as f64 * step_s;
                    assert!(
                        start_s.is_finite() && last.is_finite(),
                        "{start_s} {step_s}"
                    );
                    assert!(*step_s > 0.0 && (1.0 / step_s).is_finite(), "{step_s}");
                }
            }
        }
    }
}

pub fn check_uff_import(bytes: &[u8]) {
    if let Ok(f) = uff::parse_uff(bytes, "fuzz.uff", Some(bytes.len() as u64)) {
        check_import(&imported::modes_from_uff(&f), &[("O_b", 1)]);
    }
}

pub fn check_csv(bytes: &[u8]) {
    if let Ok(rs) = parse_csv(bytes, "fuzz.csv") {
        for r in &rs {
            assert!(r.values.iter().all(|v| v.is_finite()));
            if let Abscissa::Uneven(t) = &r.abscissa {
                assert_eq!(t.len(), r.values.len());
            }
        }
    }
}

pub fn import_spec(points: &[(&str, i64)], mass_normalised: Option<bool>) -> ModesFileSpec {
    ModesFileSpec {
        file: "fuzz".into(),
        format: None,
        points: points.iter().map(|(p, n)| (p.to_string(), *n)).collect(),
        impact_direction: None,
        mass_normalised,
        select: None,
        max_hz: None,
        damping_ratios: None,
        units: None,
    }
}
