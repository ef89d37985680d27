//! Benchmark: what a study point costs besides its collision (issue 33, item 1).
//!
//! Method: `examples/paper-lumped.toml` is loaded once and one study of N points runs on a rayon
//! pool of one thread, the same collision at every point, so that two modes differ only in how
//! a point's model is made:
//!
//! * `ratio`: a sweep over `md/mb = 0.35 .. 0.35 + 3e-7` (the file's m_d/m_b = 3.5/10 kg:
//!   the ratio sets m_d and K_d = m_d ω_d² on a clone of the model, ω_d and so the contact
//!   frequency and the structure unchanged: the cheapest point there is);
//! * `field`: a sweep over `slider.velocity = 1.2 .. 1.2 + 1.2e-6` m/s (the file's 1.2 m/s: a
//!   model field, set through its typed setter);
//! * `mc`: a Monte Carlo of N samples over `slider.velocity = uniform(1.2, 1.2 + 1.2e-6)`.
//!
//! Each mode prints the points that succeeded and the per-point wall time (one run, for
//! orientation only). The figures to quote come from outside the process, on one thread:
//! the CPU time (user + sys) of `field` against `ratio`, the two runs alternated in one session
//! (A B A B …, ratio pair by pair, medians; the load average noted); and, load-independent, the
//! instructions under `valgrind --tool=callgrind`, where the inclusive cost of
//! `Model::with_values` against that of `MonteCarlo::sample_with` is the share of a Monte Carlo
//! sample spent in its model update.
//!
//! Run: `cargo run --release -p meid --example study_point_bench -- MODE [N]` (N default
//! 2000), from the repository's root.

use std::time::Instant;

use meid::analysis::montecarlo::{MonteCarlo, Uncertain};
use meid::analysis::sweep::{Sweep, Vary};
use meid::model::Model;

fn main() -> meid::Result<()> {
    let mode = std::env::args().nth(1).unwrap_or_else(|| "field".into());
    let n: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(2000);
    let model = Model::from_file("examples/paper-lumped.toml".as_ref(), &[])?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| meid::Error::numerical("rayon", e.to_string()))?;
    let t0 = Instant::now();
    let ok = match mode.as_str() {
        "ratio" | "field" => {
            let spec = if mode == "ratio" {
                format!("md/mb=0.35..0.3500003:{n}")
            } else {
                format!("slider.velocity=1.2..1.2000012:{n}")
            };
            let sweep = Sweep::new(model, vec![Vary::parse(&spec)?])?;
            let r = pool.install(|| sweep.run(&|_, _| {}));
            r.points.len() - r.failures()
        }
        "mc" => {
            let mc = MonteCarlo {
                model,
                inputs: vec![Uncertain::parse("slider.velocity=uniform(1.2,1.2000012)")?],
                samples: n,
                seed: 1,
            };
            let r = pool.install(|| mc.run())?;
            n - r.failed
        }
        other => {
            return Err(meid::Error::invalid(
                "mode",
                format!("unknown mode `{other}`; valid: ratio, field, mc"),
            ))
        }
    };
    let dt = t0.elapsed().as_secs_f64();
    println!(
        "study_point_bench {mode}: {ok} of {n} points ok, {:.1} us/point (wall, one run)",
        dt / n as f64 * 1e6
    );
    Ok(())
}
