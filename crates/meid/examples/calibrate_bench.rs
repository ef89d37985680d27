//! Benchmark of `meid calibrate` (issue 12's speed figure: calibrating 3 parameters on the
//! lumped example against 10 blows in ≤ 10 s).
//!
//! ```text
//! cargo run --release -p meid --example calibrate_bench
//! ```
//!
//! The "measurement": the lumped example (examples/paper-lumped.toml, as specified: with its
//! damper) simulated at 20 kHz, ten 0.3 s blows one after the other (each 99 samples at rest,
//! then the blow), white noise of 5 % of each channel's RMS (seeded), channels `accel_B`,
//! `force_floor`, `hammer` (60 000 samples each). The fit: K_s, K_d and the bed mode's damping
//! ratio from a start 30 % stiff, 25 % soft and 1.6× the damping, time-history residuals
//! (18 000), default solver settings. Timed with `std::time::Instant` from the measured records
//! in memory to the finished [`Calibration`] (blow detection and averaging included); the
//! load average (/proc/loadavg) is printed beside it.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use meid::analysis::energy::simulate;
use meid::measure::calibrate::{calibrate, parameters, Problem, Settings};
use meid::measure::process::Processing;
use meid::measure::validate::MeasuredCase;
use meid::measure::{Quantity, Record};
use meid::model::{Case, Model};
use meid::rng::SplitMix64;

const FS: f64 = 20_000.0;
const LEAD: usize = 99;
const SEGMENT: usize = 6_000;
const BLOWS: usize = 10;

fn main() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper-lumped.toml");
    let truth = Model::from_file(&path, &[]).expect("the example reads");
    let sys = truth.impact_system(Case::AsSpecified).expect("system");
    let mut o = truth.options();
    o.sample_rate = Some(FS);
    o.duration = (SEGMENT - LEAD + 10) as f64 / FS;
    let h = simulate(&sys, &o, true)
        .expect("run")
        .history
        .expect("history");
    let mut rng = SplitMix64::new(12);
    let mut channel = |name: &str, q: Quantity, v: &[f64]| {
        let rms = (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
        let mut out = Vec::with_capacity(BLOWS * SEGMENT);
        for _ in 0..BLOWS {
            out.extend(std::iter::repeat_n(0.0, LEAD));
            out.extend(v.iter().take(SEGMENT - LEAD));
        }
        out.iter_mut()
            .for_each(|x| *x += 0.05 * rms * rng.next_normal());
        Record::sampled(name, q, 0.0, 1.0 / FS, out, "synthetic")
    };
    let records = vec![
        channel(
            "accel_B",
            Quantity::Acceleration,
            &h.bed_acceleration_m_per_s2,
        ),
        channel("force_floor", Quantity::Force, &h.floor_force_n),
        channel("hammer", Quantity::Force, &h.contact_force_slider_bed_n),
    ];
    let meas = MeasuredCase {
        case: Case::AsSpecified,
        files: vec!["synthetic".into()],
        records,
    };
    let paths = [
        "contact.slider_bed.stiffness",
        "contact.bed_damper.stiffness",
        "structure.lumped.damping_ratios[1]",
    ]
    .map(String::from);
    let known = parameters(&truth, &paths, &BTreeMap::new()).expect("paths");
    let start = Model::from_file(
        &path,
        &[
            format!("{}={:e}", paths[0], known[0].start * 1.3),
            format!("{}={:e}", paths[1], known[1].start * 0.75),
            format!("{}={:e}", paths[2], known[2].start * 1.6),
        ],
    )
    .expect("start model");
    let p = Processing {
        pretrigger_s: (LEAD + 1) as f64 / FS,
        ..Processing::default()
    };
    let t0 = Instant::now();
    let params = parameters(&start, &paths, &BTreeMap::new()).expect("parameters");
    let problem = Problem::new(
        &start,
        params,
        &[meas],
        &p,
        &BTreeMap::new(),
        Settings::default(),
    )
    .expect("problem");
    let c = calibrate(&problem).expect("calibration");
    let wall = t0.elapsed().as_secs_f64();
    print!("{}", c.to_text());
    for (e, k) in c.parameters.iter().zip(&known) {
        println!(
            "  {}: known {:e}, estimate {:e} ({:+.4} %)",
            e.path,
            k.start,
            e.value,
            100.0 * (e.value / k.start - 1.0)
        );
    }
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!(
        "calibrate 3 parameters, 10 blows: {wall:.3} s wall ({} evaluations, {:.2} ms each); load average {}",
        c.evaluations,
        1e3 * wall / c.evaluations as f64,
        load.split_whitespace().take(3).collect::<Vec<_>>().join(" ")
    );
}
