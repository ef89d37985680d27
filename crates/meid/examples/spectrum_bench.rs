//! Benchmark of the exact spectrum (issue 10's speed figure: the exact spectrum of a 2 s,
//! 20-mode run in ≤ 50 ms).
//!
//! ```text
//! cargo run --release -p meid --example spectrum_bench [-- --quick]
//! ```
//!
//! System: the 20-mode structure of `impact_bench` (6.35 Hz rigid-body mode, 283 Hz bed mode
//! and 18 modes from 400 Hz to 8 kHz, 1 % damping; slider, impact damper with a one-way
//! dashpot; 22 coordinates, 44 states). Its 2 s run (exact method, no output samples) is
//! simulated once, untimed. Work measured, for the three channels `meid compare` uses (bed
//! acceleration, floor force, slider-bed force):
//! 1. **the exact spectrum** = decomposing every mode the run met (eigen-decomposition of the
//!    44 × 44 first-order matrix with rigid-body deflation) and the boundary terms of every
//!    switch, then the ESD on the 1500-point logarithmic grid `meid compare` writes and plots
//!    (the bands' range, 2.8 Hz to 1.41 kHz), with the free decay after 2 s;
//! 2. the same plus the ESD peaks at two modes (Brent refinement) and the energies of the 27
//!    one-third-octave bands 3.15 Hz-1.25 kHz (0.5× the lowest to 4× the highest mode read, as
//!    `meid compare`; adaptive Gauss-Kronrod to `BAND_RTOL` = 1e-6), i.e. every spectral number
//!    of a comparison case;
//! 3. continuing the run until the free decay carries < 1e-12 of each channel's energy (the
//!    continuation rule), which `meid compare` does before 1-2, reported with its length, and
//!    1-2 again on the continued run (what `meid compare` computes for this system).
//!
//! Method: one warm-up, then `B` batches of `K` repetitions; time per repetition = batch time
//! / K (std::time::Instant); median and minimum over the batches.

use std::time::Instant;

#[path = "common/twenty_modes.rs"]
mod twenty;
use twenty::twenty_modes;

use meid::analysis::compare::BAND_RTOL;
use meid::analysis::esd::{DecayRule, SpectrumBuilder, Trajectory};
use meid::analysis::octave::bands_covering;
use meid::impact::Channel;
use meid::integrate::{self, NoOutput, Options};

fn batches(b: usize, k: usize, mut f: impl FnMut()) -> (f64, f64) {
    f();
    let mut v: Vec<f64> = (0..b)
        .map(|_| {
            let t = Instant::now();
            for _ in 0..k {
                f();
            }
            t.elapsed().as_secs_f64() / k as f64
        })
        .collect();
    v.sort_by(f64::total_cmp);
    let med = if v.len() % 2 == 1 {
        v[v.len() / 2]
    } else {
        0.5 * (v[v.len() / 2 - 1] + v[v.len() / 2])
    };
    (med, v[0])
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let (b, k) = if quick { (3, 2) } else { (9, 5) };
    let sys = twenty_modes();
    let ch = [
        Channel::BedAcceleration,
        Channel::FloorForce,
        Channel::ContactSliderBed,
    ];
    let opts = Options {
        duration: 2.0,
        sample_rate: None,
        ..Options::default()
    };
    let sol = integrate::solve(&sys, &opts, &mut NoOutput).unwrap();
    let traj = Trajectory::from_solution(&sol);
    let modes: std::collections::BTreeSet<u8> = traj.stretches.iter().map(|s| s.mode.0).collect();
    println!(
        "2 s run, 20 modes: {} stretches, {} switches, {} modes met {:?}",
        traj.stretches.len(),
        sol.events.len(),
        modes.len(),
        modes
    );
    let bands = bands_covering(0.5 * 6.35, 4.0 * 283.0);
    let (f_lo, f_hi) = (bands[0].lower_hz, bands[bands.len() - 1].upper_hz);
    let grid: Vec<f64> = (0..1500)
        .map(|i| f_lo * (f_hi / f_lo).powf(i as f64 / 1499.0))
        .collect();
    let curve = |traj: &Trajectory| {
        let mut bld = SpectrumBuilder::new(&sys, &ch);
        let spec = bld.build(traj, true).unwrap();
        let mut s = 0.0;
        for &f in &grid {
            s += spec.esd(f)[0];
        }
        (spec, s)
    };
    let (med, min) = batches(b, k, || {
        std::hint::black_box(curve(&traj));
    });
    println!(
        "exact spectrum (decomposition + 1500-point ESD curve, 3 channels): {:8.2} ms (min {:.2} ms)",
        med * 1e3,
        min * 1e3
    );
    let (med_b, min_b) = batches(b, k, || {
        let mut bld = SpectrumBuilder::new(&sys, &ch);
        std::hint::black_box(bld.build(&traj, true).unwrap());
    });
    println!(
        "  of which the decomposition and boundary terms: {:8.2} ms (min {:.2} ms)",
        med_b * 1e3,
        min_b * 1e3
    );
    let all = |traj: &Trajectory| -> usize {
        let (spec, _) = curve(traj);
        for ci in 0..2 {
            for (lo, hi) in [(6.35 * 0.9, 6.35 * 1.1), (283.0 * 0.9, 283.0 * 1.1)] {
                std::hint::black_box(spec.peak(ci, lo, hi).unwrap());
            }
        }
        let mut evals = 0;
        for bd in &bands {
            let q = spec.band_energies(bd.lower_hz, bd.upper_hz, BAND_RTOL);
            evals += q[0].evaluations;
        }
        evals
    };
    let evals = all(&traj);
    let (med2, min2) = batches(b, k, || {
        std::hint::black_box(all(&traj));
    });
    println!(
        "with peaks at 2 modes x 2 channels and {} band energies: {:8.2} ms (min {:.2} ms), {} ESD evaluations for the bands",
        bands.len(),
        med2 * 1e3,
        min2 * 1e3,
        evals
    );
    let t = Instant::now();
    let mut long = traj.clone();
    let mut bld = SpectrumBuilder::new(&sys, &ch);
    let cont = bld
        .continue_until_decayed(&opts, &mut long, &DecayRule::default())
        .unwrap();
    let dt = t.elapsed().as_secs_f64();
    println!(
        "continuation: to {:.2} s ({} switches, {} stretches) in {:.1} ms; tail fractions {:?}",
        cont.end_s,
        cont.switches,
        long.stretches.len(),
        dt * 1e3,
        cont.tail_energy_fraction
    );
    let (med3, min3) = batches(b.min(5), 1, || {
        std::hint::black_box(curve(&long));
    });
    println!(
        "exact spectrum of the continued run (decomposition + 1500-point curve): {:8.2} ms (min {:.2} ms)",
        med3 * 1e3,
        min3 * 1e3
    );
    let evals = all(&long);
    let (med4, min4) = batches(b.min(5), 1, || {
        std::hint::black_box(all(&long));
    });
    println!(
        "  with peaks and band energies: {:8.2} ms (min {:.2} ms), {} ESD evaluations for the bands",
        med4 * 1e3,
        min4 * 1e3,
        evals
    );
}
