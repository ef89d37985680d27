//! The properties the parsers of meid must have on any input, shared by the proptest suite
//! (`tests/fuzz_parsers.rs`, stable, in `cargo test`) and the cargo-fuzz targets (`fuzz/`,
//! nightly), which include this file: a model file and its `--set` overrides, a Gmsh mesh,
//! and the command-line specifications (`--vary` of sweep and montecarlo, the distributions,
//! `--bounds`, `--over`, `--objective`, `--case`).
//!
//! The property is the same everywhere: the parser returns `Ok` or an `Err` whose message says
//! something; it never panics (a panic is the fuzzer's crash). What an `Ok` promises is checked
//! too: indices in range, values finite, a parsed name that reads back as itself.
//!
//! Cost is not this suite's subject (the limits on memory and time are tested with the limits):
//! a model whose finite-element mesh or mode count would take seconds to build is skipped
//! ([`affordable`]), so that the fuzzers spend their time on parsing.
#![allow(dead_code)]

use std::str::FromStr;
use std::sync::OnceLock;

use meid::analysis::montecarlo::{Distribution, SplitMix64, Uncertain};
use meid::analysis::study::{parse_bounds, Objective, OptimizeStudy};
use meid::analysis::sweep::{Quantity, Spacing, Sweep, Vary};
use meid::model::{Case, Model};
use meid::structure::gmsh::parse_msh_bytes;
use meid::structure::{Material, Mesh};

/// The lumped paper example: the model the specifications are checked against.
pub const LUMPED: &str = include_str!("../../../../examples/paper-lumped.toml");
/// An FE example (the paper machine on its soft base).
pub const FE_SOFT_BASE: &str = include_str!("../../../../examples/paper-soft-base.toml");
/// A Gmsh 4.1 mesh (8 × 6 quads, physical groups).
pub const PLATE_MSH: &str = include_str!("../../../meid-cli/tests/data/clamped_plate.msh");
/// The 16 × 16 plate Gmsh 4.15.2 wrote as MSH 4.1 binary (tests/data/gmsh/plate.py).
pub const PLATE_MSH_B41: &[u8] = include_bytes!("../data/gmsh/gmsh_plate_b41.msh");
/// The same plate as MSH 2.2 ASCII (each quadrangle twice: two physical groups).
pub const PLATE_MSH_22: &str = include_str!("../data/gmsh/gmsh_plate_a22.msh");

/// Largest `elements_per_side` and mode `count`/`auto_count` built by the fuzzers.
pub const MAX_ELEMENTS_PER_SIDE: i64 = 24;
pub const MAX_MODE_COUNT: i64 = 60;

fn too_big(key: &str, v: &toml::Value) -> bool {
    let limit = match key {
        "elements_per_side" => MAX_ELEMENTS_PER_SIDE,
        "count" | "auto_count" => MAX_MODE_COUNT,
        _ => return false,
    };
    v.as_integer().is_some_and(|n| n > limit) || v.as_float().is_some_and(|x| x > limit as f64)
}

fn table_too_big(t: &toml::Table) -> bool {
    t.iter().any(|(k, v)| too_big(k, v) || value_too_big(v))
}

fn value_too_big(v: &toml::Value) -> bool {
    match v {
        toml::Value::Table(t) => table_too_big(t),
        toml::Value::Array(a) => a.iter().any(value_too_big),
        _ => false,
    }
}

/// False when the model text or an override asks for a mesh finer than
/// [`MAX_ELEMENTS_PER_SIDE`] or more than [`MAX_MODE_COUNT`] modes (expensive, not wrong).
pub fn affordable(text: &str, overrides: &[String]) -> bool {
    if let Ok(t) = toml::from_str::<toml::Table>(text) {
        if table_too_big(&t) {
            return false;
        }
    }
    for o in overrides {
        if let Some((path, value)) = o.split_once('=') {
            let key = path
                .trim()
                .rsplit('.')
                .next()
                .unwrap_or("")
                .trim_matches(|c| c == '"' || c == '\'');
            if let Ok(t) = toml::from_str::<toml::Table>(&format!("v = {value}")) {
                if t.get("v")
                    .is_some_and(|v| too_big(key, v) || value_too_big(v))
                {
                    return false;
                }
            }
            // `--set structure.fem.machine={ elements_per_side = 400 }` and the like.
            if !value.contains("elements_per_side") && !value.contains("count") {
                continue;
            }
            return false;
        }
    }
    true
}

/// An error must say what was wrong.
fn check_error(what: &str, e: &meid::Error) {
    let m = e.to_string();
    assert!(!m.trim().is_empty(), "{what}: an error without a message");
}

/// A model file with `--set` overrides: loads or fails with a message; a loaded model builds
/// its impact system in every case it has.
pub fn check_model(name: &str, text: &str, overrides: &[String]) {
    if !affordable(text, overrides) {
        return;
    }
    match Model::from_text(name, text.to_string(), overrides) {
        Err(e) => check_error("model", &e),
        Ok(m) => {
            // Loading validated the case as specified; the other cases answer too.
            for case in [Case::NoDamper, Case::Damper, Case::AddedMass] {
                if let Err(e) = m.impact_system(case) {
                    check_error("impact system", &e);
                }
            }
            let _ = m.options();
            let _ = m.diagnostics();
        }
    }
}

/// A Gmsh mesh: parses or fails with a located message; a parsed mesh's indices are in range
/// and it becomes shell elements without a panic.
pub fn check_gmsh(text: &str) {
    check_gmsh_bytes(text.as_bytes());
}

/// As [`check_gmsh`], for any bytes (MSH 4.1 binary files included).
pub fn check_gmsh_bytes(data: &[u8]) {
    match parse_msh_bytes(data, "fuzz.msh") {
        Err(e) => check_error("gmsh", &e),
        Ok(g) => {
            let n = g.nodes.len();
            assert_eq!(g.node_tags.len(), n);
            assert_eq!(g.quad_tags.len(), g.quads.len());
            assert_eq!(g.line_tags.len(), g.lines.len());
            assert!(g.lines.iter().flatten().all(|&i| i < n), "line node index");
            assert!(
                g.line_sets.values().flatten().all(|&e| e < g.lines.len()),
                "line set index"
            );
            assert!(g.quads.iter().flatten().all(|&i| i < n), "quad node index");
            assert!(
                g.nodes.iter().flatten().all(|x| x.is_finite()),
                "coordinates"
            );
            assert!(
                g.node_sets.values().flatten().all(|&i| i < n),
                "node set index"
            );
            assert!(
                g.element_sets
                    .values()
                    .flatten()
                    .all(|&e| e < g.quads.len()),
                "element set index"
            );
            let mut mesh = Mesh::new();
            match g.add_to_mesh(&mut mesh, Material::STEEL, 0.01) {
                Err(e) => check_error("gmsh to mesh", &e),
                Ok(map) => assert_eq!(map.len(), n),
            }
        }
    }
}

fn lumped_model() -> &'static Model {
    static M: OnceLock<Model> = OnceLock::new();
    M.get_or_init(|| {
        Model::from_text("paper-lumped.toml", LUMPED.to_string(), &[])
            .expect("the lumped example loads")
    })
}

/// Largest range count a spec may ask for here: a larger one is refused by the memory limit
/// (the sweep's cost check), not by the parser.
const MAX_RANGE_COUNT: usize = 100_000;

fn range_count(spec: &str) -> Option<usize> {
    let rest = spec.split_once("..")?.1;
    rest.split(':').nth(1)?.trim().parse().ok()
}

/// A command-line specification: every parser that reads it answers without a panic, and what
/// they accept is consistent.
pub fn check_spec(s: &str) {
    // `--vary` of sweep: NAME=LIST | NAME=A..B:N[:log].
    if range_count(s).is_none_or(|n| n <= MAX_RANGE_COUNT) {
        match Vary::parse(s) {
            Err(e) => check_error("vary", &e),
            Ok(v) => {
                assert!(!v.values.is_empty(), "`{s}`: no values");
                assert!(
                    v.values.iter().all(|x| x.is_finite()),
                    "`{s}`: {:?}",
                    v.values
                );
                if v.spacing != Spacing::List {
                    assert!(v.values.len() >= 2);
                    assert!(
                        v.values.windows(2).all(|w| w[0] < w[1]),
                        "`{s}`: a range increases: {:?}",
                        v.values
                    );
                }
                assert_eq!(
                    Quantity::parse(&v.quantity.name()).ok().as_ref(),
                    Some(&v.quantity)
                );
                if v.values.len() <= 1000 {
                    if let Err(e) = Sweep::new(lumped_model().clone(), vec![v]) {
                        check_error("sweep", &e);
                    }
                }
            }
        }
    }
    // `--vary` of montecarlo: PATH=DIST(a,b), and the distribution alone.
    match Uncertain::parse(s) {
        Err(e) => check_error("uncertain", &e),
        Ok(u) => check_distribution(s, &u.distribution),
    }
    match Distribution::parse(s) {
        Err(e) => check_error("distribution", &e),
        Ok(d) => check_distribution(s, &d),
    }
    // `--over` / a `--vary` name: a quantity reads back as itself.
    match Quantity::parse(s) {
        Err(e) => check_error("quantity", &e),
        Ok(q) => assert_eq!(Quantity::parse(&q.name()).ok(), Some(q)),
    }
    // `--bounds PATH=LO..HI`, then the study that uses them.
    match parse_bounds(s) {
        Err(e) => check_error("bounds", &e),
        Ok((q, b)) => {
            match OptimizeStudy::new(
                lumped_model().clone(),
                vec![(q, Some(b))],
                Objective::Energy,
            ) {
                Err(e) => check_error("optimize", &e),
                Ok(study) => {
                    for v in &study.variables {
                        assert!(v.lower.is_finite() && v.upper.is_finite(), "`{s}`");
                    }
                }
            }
        }
    }
    if let Err(e) = Objective::parse(s) {
        check_error("objective", &e);
    }
    if let Err(e) = Case::from_str(s) {
        check_error("case", &e);
    }
}

/// An accepted distribution has a finite mean and standard deviation and draws finite values.
fn check_distribution(s: &str, d: &Distribution) {
    assert!(d.mean().is_finite(), "`{s}`: mean of {d:?}");
    assert!(d.std().is_finite() && d.std() >= 0.0, "`{s}`: std of {d:?}");
    let mut rng = SplitMix64::new(s.len() as u64);
    for _ in 0..32 {
        let x = d.sample(&mut rng);
        assert!(x.is_finite(), "`{s}`: {d:?} drew {x}");
    }
}
