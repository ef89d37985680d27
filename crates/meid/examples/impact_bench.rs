//! Benchmark of the impact engine (issue 2's speed figures).
//!
//! ```text
//! cargo run --release -p meid --example impact_bench [-- --quick] [--no-peer]
//! ```
//!
//! (`--events` prints the collision's stretches and switches and each mode's Taylor step
//! instead; `--callgrind*` run one case for `valgrind --tool=callgrind`; `--spec PATH` writes
//! case 1's system with meid's exact energy ratio and collision end for the peers in
//! `bench/peer/`, and `--collisions N` runs N cold collisions of case 1 and nothing else (and
//! prints their CPU time per collision), the meid side of the CPU-time comparison in
//! `bench/peer/README.md`.)
//!
//! Method: every case is run once to warm up, then in `B` batches of `K` repetitions; the time
//! per run of each batch is `elapsed / K` (std::time::Instant), and the median and minimum over
//! batches are printed. Work measured:
//! 1. one collision of `examples/paper-lumped.toml` (first contact to the end of the collision,
//!    no output samples), `integrate::solve` on a prepared `ImpactSystem`. *Cold*: the
//!    per-thread propagator cache is cleared before each run, so the closed forms of the modes
//!    met are built inside each run (a sweep point whose modes are all new); *warm*: the cache
//!    holds them (repeated blows of one machine, or sweep points sharing modes);
//! 2. the same with `dopri5` (rtol 1e-8, atol 1e-14);
//! 3. a 2 s run of a 20-mode structure (synthetic modal model: 6.35 Hz rigid-body mode, 283 Hz bed
//!    mode and 18 modes from 400 Hz to 8 kHz, 1 % damping) with 20 kHz output, recording every
//!    history channel (what `meid simulate -o` does, without writing the file);
//! 4. the SciPy peer (`bench/peer/impact_rk45.py`, `solve_ivp` RK45, rtol 1e-8) on case 1's system,
//!    interleaved with case 1 so that both see the same load of a shared machine: 5 rounds of
//!    3 meid batches and 4 SciPy runs (each SciPy process does one untimed run first; SciPy times
//!    single runs, 15-30 ms each; a meid batch of 400 runs takes a few ms); prints the time
//!    ratios on medians and on minima (load only ever adds time; meid's minimum is over batch
//!    means, SciPy's over single runs, which favours SciPy) and the energy-ratio difference. The
//!    dopri5 ratio uses case 2's time, measured before, not interleaved. These are **wall-time**
//!    ratios against a peer without switch events (error 4.3e-7 at rtol 1e-8); the CPU-time
//!    comparison with SciPy RK45, SciPy `ode('dopri5')` and Exudyn at matched accuracy is
//!    `bench/peer/README.md` (`--spec`, `--collisions`).

#[path = "common/peer.rs"]
mod peer;
#[path = "common/twenty_modes.rs"]
mod twenty;
use twenty::twenty_modes;

use std::path::PathBuf;
use std::time::Instant;

use meid::analysis::simulate;
use meid::impact::ImpactSystem;
use meid::integrate::{self, Method, NoOutput, Options};
use meid::model::{Case, Model};

fn time_it(batches: usize, reps: usize, f: impl FnMut()) -> (f64, f64) {
    peer::median_min(batch_times(batches, reps, f))
}

/// Time per run of each of `batches` batches of `reps` runs (after one warm-up run).
fn batch_times(batches: usize, reps: usize, mut f: impl FnMut()) -> Vec<f64> {
    f();
    (0..batches)
        .map(|_| {
            let t = Instant::now();
            for _ in 0..reps {
                f();
            }
            t.elapsed().as_secs_f64() / reps as f64
        })
        .collect()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.iter().any(|a| a == "--seq") {
        faer::set_global_parallelism(faer::Par::Seq);
    }
    let quick = args.iter().any(|a| a == "--quick");
    let peer = !args.iter().any(|a| a == "--no-peer");
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let model = Model::from_file(&root.join("examples/paper-lumped.toml"), &[]).unwrap();
    let sys = model.impact_system(Case::AsSpecified).unwrap();
    let (b, k) = if quick { (5, 50) } else { (15, 400) };
    let one = |method| Options {
        method,
        duration: 0.05,
        sample_rate: None,
        stop_at_collision_end: true,
        rtol: 1e-8,
        atol: 1e-14,
        ..Options::default()
    };

    let oe = one(Method::Exact);
    if args.iter().any(|a| a == "--events") {
        let closed = Options {
            taylor_steps_per_mode: 0,
            ..oe
        };
        let sc = integrate::solve(&sys, &closed, &mut NoOutput).unwrap();
        for e in &sc.events {
            println!(
                "closed forms only: t = {:.12e} s: mode {:?} -> {:?}",
                e.t, e.from, e.to
            );
        }
        let sd = integrate::solve(&sys, &one(Method::Dopri5), &mut NoOutput).unwrap();
        println!(
            "dopri5: {} accepted steps, {} rejected, {} events",
            sd.steps,
            sd.rejected,
            sd.events.len()
        );
        let sol = integrate::solve(&sys, &oe, &mut NoOutput).unwrap();
        println!(
            "{} stretches; collision end {:?} s",
            sol.steps,
            sol.collision_end.as_ref().map(|c| c.t)
        );
        for e in &sol.events {
            println!("t = {:.12e} s: mode {:?} -> {:?}", e.t, e.from, e.to);
        }
        for bits in [7u8, 3, 2, 0] {
            let a = sys.first_order(meid::impact::Mode(bits));
            let tm = meid::integrate::taylor::TaylorMatrix::new(&a).unwrap();
            println!(
                "mode {bits}: Taylor step {:.3e} s, period scale {:.3e} s",
                tm.validity(),
                tm.period()
            );
        }
        return;
    }
    // `--spec PATH`: the system and meid's exact values for the peers in `bench/peer/`.
    if let Some(path) = flag_value(&args, "--spec") {
        let sol = simulate(&sys, &oe, false).unwrap();
        let mut spec = peer::spec_json(&sys).unwrap();
        spec["meid_energy_ratio"] = sol.summary.energy_ratio.unwrap().into();
        spec["meid_collision_end_s"] = sol.summary.collision_end_s.unwrap().into();
        std::fs::write(&path, spec.to_string()).unwrap();
        return;
    }
    // `--collisions N`: N cold collisions (as case 1) and nothing else, for whole-process CPU
    // time against the peers (`bench/peer/README.md`); N = 0 measures the process's start.
    if let Some(n) = flag_value(&args, "--collisions") {
        let n: usize = n.parse().expect("--collisions N");
        let (t, cpu0) = (Instant::now(), thread_cpu_ns());
        let mut end = None;
        for _ in 0..n {
            meid::integrate::propagator::clear_cache();
            end = integrate::solve(&sys, &oe, &mut NoOutput)
                .unwrap()
                .collision_end
                .map(|c| c.t);
        }
        let wall = t.elapsed().as_secs_f64();
        let cpu = thread_cpu_ns()
            .zip(cpu0)
            .map_or("null".to_string(), |(b, a)| {
                format!("{:e}", (b - a) as f64 * 1e-9 / n.max(1) as f64)
            });
        let ratio = simulate(&sys, &oe, false)
            .unwrap()
            .summary
            .energy_ratio
            .unwrap();
        println!(
            "{{\"peer\": \"meid exact\", \"collisions\": {n}, \"energy_ratio\": {ratio:e}, \"collision_end_s\": {}, \"wall_per_collision_s\": {:e}, \"cpu_per_collision_s\": {cpu}}}",
            end.map_or("null".to_string(), |e| format!("{e:e}")),
            wall / n.max(1) as f64
        );
        return;
    }
    if args.iter().any(|a| a == "--callgrind20") {
        let s20 = twenty_modes();
        let o20 = twenty_mode_run();
        simulate(&s20, &o20, true).unwrap();
        return;
    }
    if args.iter().any(|a| a == "--callgrind-dopri5") {
        let od = one(Method::Dopri5);
        for _ in 0..20 {
            integrate::solve(&sys, &od, &mut NoOutput).unwrap();
        }
        return;
    }
    if args.iter().any(|a| a == "--callgrind") {
        for _ in 0..20 {
            meid::integrate::propagator::clear_cache();
            integrate::solve(&sys, &oe, &mut NoOutput).unwrap();
        }
        return;
    }
    let (med_e, min_e) = time_it(b, k, || {
        meid::integrate::propagator::clear_cache();
        integrate::solve(&sys, &oe, &mut NoOutput).unwrap();
    });
    let (med_w, min_w) = time_it(b, k, || {
        integrate::solve(&sys, &oe, &mut NoOutput).unwrap();
    });
    let od = one(Method::Dopri5);
    let (med_d, min_d) = time_it(b, k, || {
        integrate::solve(&sys, &od, &mut NoOutput).unwrap();
    });
    let ratio_e = simulate(&sys, &oe, false)
        .unwrap()
        .summary
        .energy_ratio
        .unwrap();
    let ratio_d = simulate(&sys, &od, false)
        .unwrap()
        .summary
        .energy_ratio
        .unwrap();
    println!(
        "machine: {} cores; method: median (min) of {b} batches x {k} runs",
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    println!(
        "1 collision, exact : {:8.2} us  (min {:.2} us)  energy ratio {ratio_e:.10}  [cold: closed forms built in the run]",
        med_e * 1e6,
        min_e * 1e6
    );
    println!(
        "1 collision, exact : {:8.2} us  (min {:.2} us)  [warm: closed forms from the cache]",
        med_w * 1e6,
        min_w * 1e6
    );
    println!(
        "1 collision, dopri5: {:8.2} us  (min {:.2} us)  energy ratio {ratio_d:.10}",
        med_d * 1e6,
        min_d * 1e6
    );

    if args.iter().any(|a| a == "--profile") {
        profile_parts(&sys);
        return;
    }
    let s20 = twenty_modes();
    let o20 = twenty_mode_run();
    let (b2, k2) = if quick { (3, 2) } else { (7, 5) };
    let mut samples = 0;
    let (med_20, min_20) = time_it(b2, k2, || {
        let r = simulate(&s20, &o20, true).unwrap();
        samples = r.history.map_or(0, |h| h.time_s.len());
    });
    println!(
        "2 s, 20 modes, 20 kHz output ({samples} samples, all channels): {:8.2} ms  (min {:.2} ms)",
        med_20 * 1e3,
        min_20 * 1e3
    );

    if peer {
        // Interleaved: rounds of meid batches (exact, cold) and SciPy runs, so that both see the
        // same moments of a shared machine's load.
        let rounds = if quick { 2 } else { 5 };
        let (mut ours, mut theirs) = (Vec::new(), Vec::new());
        let mut last = None;
        for _ in 0..rounds {
            ours.extend(batch_times(3, k, || {
                meid::integrate::propagator::clear_cache();
                integrate::solve(&sys, &oe, &mut NoOutput).unwrap();
            }));
            match peer::scipy_collision(&sys, &root, 4) {
                Ok(p) => {
                    theirs.extend(p.times_s.iter().copied());
                    last = Some(p);
                }
                Err(e) => {
                    println!("SciPy peer not run: {e}");
                    break;
                }
            }
        }
        if let (Some(p), false) = (last, theirs.is_empty()) {
            let r = p.energy_ratio;
            let (n_ours, n_theirs) = (ours.len(), theirs.len());
            let (t_med, t_min) = peer::median_min(theirs);
            let (o_med, o_min) = peer::median_min(ours);
            println!(
                "SciPy {} solve_ivp RK45 (rtol 1e-8), interleaved with meid ({n_theirs} SciPy runs, {n_ours} meid batches x {k}): {:.2} ms per collision (min {:.2} ms), energy ratio {r:.10}; meid exact {:.2} us (min {:.2} us)",
                p.scipy,
                t_med * 1e3,
                t_min * 1e3,
                o_med * 1e6,
                o_min * 1e6
            );
            println!(
                "wall-time ratio SciPy / meid exact: {:.0}x on medians, {:.0}x on minima; SciPy / meid dopri5 (timed above, not interleaved): {:.0}x on medians; |energy ratio difference| {:.2e} (CPU-time ratios: bench/peer/README.md)",
                t_med / o_med,
                t_min / o_min,
                t_med / med_d,
                (r - ratio_e).abs()
            );
        }
    }
}

/// This thread's CPU time so far (ns, user + system: the scheduler's run time,
/// `/proc/thread-self/schedstat`), where Linux gives it.
fn thread_cpu_ns() -> Option<u64> {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// The argument after `flag`, if `flag` is given.
fn flag_value(args: &[String], flag: &str) -> Option<String> {
    let i = args.iter().position(|a| a == flag)?;
    Some(args.get(i + 1).expect("the flag needs a value").clone())
}

/// Case 3's options: 2 s, `exact`, 20 kHz output.
fn twenty_mode_run() -> Options {
    Options {
        method: Method::Exact,
        duration: 2.0,
        sample_rate: Some(20_000.0),
        ..Options::default()
    }
}

#[allow(dead_code)]
pub fn profile_parts(sys: &ImpactSystem) {
    use meid::impact::Mode;
    use meid::integrate::propagator::Propagator;
    let m = sys.mass_diag();
    for bits in [3u8, 2, 6, 0, 4] {
        let mode = Mode(bits);
        let (kk, cc) = sys.matrices(mode);
        let a = sys.first_order(mode);
        let (med, _) = time_it(5, 200, || {
            let _ = Propagator::new(&kk, &cc, &m, a.clone()).unwrap();
        });
        let (med2, _) = time_it(5, 200, || {
            let _ = sys.first_order(mode);
        });
        println!(
            "mode {bits}: propagator build {:.2} us, first_order {:.2} us",
            med * 1e6,
            med2 * 1e6
        );
    }
}
