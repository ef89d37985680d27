//! Benchmark: a 100 x 100 energy map of the lumped paper example.
//!
//! Method: `examples/paper-lumped.toml` is loaded once; the sweep varies
//! `ws/w_ref=10..300:100:log` and `wd/w_ref=10..300:100:log` (10 000 points), each point a
//! blow simulated with the `exact` method to the end of its collision
//! (`stop_at_collision_end`), every summary metric recorded. The whole map is run in a rayon
//! pool of 1 thread and of 2 threads (`ThreadPoolBuilder`), each `REPEATS` times after one
//! warm-up run; the best wall time (std::time::Instant) of each is printed with the per-point
//! cost and the speed-up. The CSV of both runs is compared byte for byte.
//!
//! Then the SciPy peer (`bench/peer/impact_rk45.py`, RK45 rtol 1e-8) runs on five of the map's
//! points (corners and centre, 3 runs each, median) and the per-point ratio of wall times is
//! printed (`--no-peer` skips it): taken at different moments of a shared machine, it is
//! indicative only; the CPU-time comparison with the peers is `bench/peer/README.md`.
//!
//! Run: `cargo run --release -p meid --example sweep_bench [MODEL.toml] [N]`.
//! The machine has 2 cores shared with other builds: note the load average beside the figures.

use std::time::Instant;

#[path = "common/peer.rs"]
mod peer;

use meid::analysis::sweep::{Sweep, Vary};
use meid::model::Model;

const REPEATS: usize = 1;

fn main() -> meid::Result<()> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "examples/paper-lumped.toml".into());
    let n: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(100);
    let model = Model::from_file(path.as_ref(), &[])?;
    let sweep = Sweep::new(
        model,
        vec![
            Vary::parse(&format!("ws/w_ref=10..300:{n}:log"))?,
            Vary::parse(&format!("wd/w_ref=10..300:{n}:log"))?,
        ],
    )?;
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!(
        "sweep_bench: {} points, method exact, to the end of each collision; load average {}",
        sweep.len(),
        load.split_whitespace()
            .take(3)
            .collect::<Vec<_>>()
            .join(" ")
    );
    let mut csv = Vec::new();
    let mut best = Vec::new();
    let mut last = None;
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| meid::Error::numerical("rayon", e.to_string()))?;
        let mut t_best = f64::INFINITY;
        let mut text = String::new();
        for rep in 0..REPEATS {
            let t0 = Instant::now();
            let r = pool.install(|| sweep.run(&|_, _| {}));
            let dt = t0.elapsed().as_secs_f64();
            t_best = t_best.min(dt);
            text = r.csv();
            last = Some(r.clone());
            if rep == 0 {
                println!(
                    "  {threads} thread(s): {} failed points, min energy ratio {:.4}",
                    r.failures(),
                    r.argmin("energy_ratio")
                        .map_or(f64::NAN, |i| r.points[i].metric("energy_ratio"))
                );
            }
        }
        println!(
            "  {threads} thread(s): best of {REPEATS}: {t_best:.3} s ({:.1} us/point)",
            1e6 * t_best / sweep.len() as f64
        );
        csv.push(text);
        best.push(t_best);
    }
    println!(
        "  speed-up 2 vs 1 thread: {:.2}x; CSV identical: {}",
        best[0] / best[1],
        csv[0] == csv[1]
    );
    // The SciPy peer on a sample of the map's points (corners and centre), to put a per-point
    // ratio on the whole map.
    if !std::env::args().any(|a| a == "--no-peer") {
        let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
        let side = (sweep.len() as f64).sqrt().round() as usize;
        let picks = [
            0,
            side - 1,
            sweep.len() / 2 + side / 2,
            sweep.len() - side,
            sweep.len() - 1,
        ];
        let mut total = 0.0;
        let mut total_min = 0.0;
        let mut count = 0usize;
        let mut max_diff = 0.0_f64;
        let mut version = String::new();
        for &i in &picks {
            let pm = sweep.point_model(i)?;
            let sys = pm.model.impact_system(meid::model::Case::AsSpecified)?;
            match peer::scipy_collision(&sys, &root, 3) {
                Ok(p) => {
                    let (med, min) = p.median_min();
                    total += med;
                    total_min += min;
                    count += 1;
                    version = p.scipy;
                    if let Some(r) = &last {
                        let ours: f64 = r.points[i].metric("energy_ratio");
                        max_diff = max_diff.max((ours - p.energy_ratio).abs());
                    }
                }
                Err(e) => println!("  SciPy peer not run at point {i}: {e}"),
            }
        }
        if count > 0 {
            let scipy_point = total / count as f64;
            let scipy_min = total_min / count as f64;
            let meid_point = best[0] / sweep.len() as f64;
            println!(
                "  SciPy {version} RK45 (rtol 1e-8), mean of {count} sampled points: {:.2} ms/point (of minima {:.2} ms) -> the map would take {:.1} min; meid 1 thread {:.1} us/point: wall-time ratio {:.0}x per point ({:.0}x on SciPy's minima; CPU time: bench/peer/README.md); max |energy ratio difference| {max_diff:.1e}",
                scipy_point * 1e3,
                scipy_min * 1e3,
                scipy_point * sweep.len() as f64 / 60.0,
                meid_point * 1e6,
                scipy_point / meid_point,
                scipy_min / meid_point
            );
        }
    }
    Ok(())
}
