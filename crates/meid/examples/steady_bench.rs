//! Benchmark: what the direct steady state of a blow train costs against marching it
//! (issue 28's speed figures).
//!
//! Method: the model is loaded and its impact system built once; then, on one thread,
//! `MODE` runs `N` times:
//!
//! * `steady`: [`meid::analysis::steady::steady_state`] of the train at `RATE` blows/min,
//!   printing its blow-map evaluations (the unit a march pays per blow);
//! * `march`: a 60-blow march of the same train ([`meid::analysis::blows::run_blows`], no
//!   history kept), the reference the targets are stated against.
//!
//! The figures to quote come from outside the process: the CPU time (user + sys) of `steady`
//! against `march` in one session, alternated (`farm-bench --vs 'B' -- A`, ratio pair by pair),
//! with the load noted; the steady state's cost in marched blows is then
//! `60 × CPU(steady) / CPU(march)`.
//!
//! Run: `cargo run --release -p meid --example steady_bench -- MODE MODEL CASE RATE [N]`
//! (MODE `steady` or `march`; CASE `none`, `damper` or `added-mass`; N default 20), from the
//! repository's root.

use meid::analysis::blows::{run_blows, BlowOptions};
use meid::analysis::steady::{steady_state, SteadyOptions};
use meid::model::{Case, Model};

fn main() -> meid::Result<()> {
    let arg = |i: usize, d: &str| std::env::args().nth(i).unwrap_or_else(|| d.into());
    let mode = arg(1, "steady");
    let path = arg(2, "examples/paper-lumped.toml");
    let case = match arg(3, "damper").as_str() {
        "none" => Case::NoDamper,
        "added-mass" => Case::AddedMass,
        _ => Case::Damper,
    };
    let rate: f64 = arg(4, "60").parse().unwrap_or(60.0);
    let n: usize = arg(5, "20").parse().unwrap_or(20);
    let model = Model::from_file(path.as_ref(), &[])?;
    let sys = model.impact_system(case)?;
    let mut opts = model.options();
    opts.sample_rate = None;
    for _ in 0..n {
        if mode == "march" {
            let b = BlowOptions {
                blows: 60,
                rate_bpm: rate,
                steady_tolerance: 1e-9,
            };
            let r = run_blows(&sys, &opts, &b, false)?;
            std::hint::black_box(r.blows.len());
        } else {
            let so = SteadyOptions {
                rate_bpm: rate,
                ..SteadyOptions::default()
            };
            let s = steady_state(&sys, &opts, &so)?;
            std::hint::black_box(s.map_evaluations);
        }
    }
    if mode != "march" {
        let so = SteadyOptions {
            rate_bpm: rate,
            ..SteadyOptions::default()
        };
        let s = steady_state(&sys, &opts, &so)?;
        println!(
            "{path} {case:?} {rate}/min: {} evaluations, residual {:.2e}, {}",
            s.map_evaluations,
            s.residual,
            s.regime.name()
        );
    }
    Ok(())
}
