//! Benchmark of reading and processing measured data (issue 12's speed figure: a 60 s,
//! 8-channel, 51.2 kHz binary UFF 58b record — blow detection, averaging, spectra — in ≤ 2 s
//! and ≤ 2× the file size in memory).
//!
//! ```text
//! cargo run --release -p meid --example measure_bench
//! ```
//!
//! The example runs itself twice: `write FILE` makes the record (60 blows at 60 per minute:
//! a 2 ms half-sine blow force, a floor force and six accelerations ringing at 6.35 Hz and
//! 283 Hz with 1 % damping, seeded noise), `read FILE` times `read_uff` + `process_all`
//! (trigger on the blow force, 60 one-second records averaged, blow-averaged ESD and
//! one-third-octave bands of every channel) with `std::time::Instant` and reports the peak
//! resident memory of that process (`VmHWM` of /proc/self/status, Linux) against the file size.

use std::path::Path;
use std::time::Instant;

use meid::io::uff;
use meid::measure::process::{process_all, Processing};
use meid::measure::{Quantity, Record};
use meid::rng::SplitMix64;

const FS: f64 = 51_200.0;
const SECONDS: usize = 60;

fn vm_hwm_kib() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let l = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    l.split_whitespace().nth(1)?.parse().ok()
}

fn write(path: &Path) {
    let n = SECONDS * FS as usize;
    let mut rng = SplitMix64::new(7);
    let two_pi = 2.0 * std::f64::consts::PI;
    let ring = |t: f64, f: f64| (-0.01 * two_pi * f * t).exp() * (two_pi * f * t).sin();
    let mut records = Vec::new();
    for ch in 0..8 {
        let (name, q) = match ch {
            0 => ("blow_force".to_string(), Quantity::Force),
            1 => ("force_floor".to_string(), Quantity::Force),
            k => (format!("accel_{k}"), Quantity::Acceleration),
        };
        let mut v = vec![0.0; n];
        for (i, x) in v.iter_mut().enumerate() {
            let t = i as f64 / FS;
            let tb = t.fract(); // time since the last blow (one a second, at whole seconds + 0.1 s)
            let tb = tb - 0.1;
            *x = 1e-3 * rng.next_normal();
            if tb >= 0.0 {
                *x += match ch {
                    0 if tb < 2e-3 => 8e3 * (std::f64::consts::PI * tb / 2e-3).sin(),
                    0 => 0.0,
                    1 => 70.0 * ring(tb, 6.35),
                    k => 600.0 / k as f64 * ring(tb, 283.0) + 5.0 * ring(tb, 6.35),
                };
            }
        }
        records.push(Record::sampled(name, q, 0.0, 1.0 / FS, v, "bench"));
    }
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    uff::write_records(&mut f, &records, true, path).unwrap();
}

fn read(path: &Path) {
    let size = std::fs::metadata(path).unwrap().len();
    let before = vm_hwm_kib();
    let t = Instant::now();
    let file = uff::read_uff(path).unwrap();
    let t_read = t.elapsed().as_secs_f64();
    let p = Processing::default();
    let channels = process_all(&file.records, &p, None, "B").unwrap();
    let total = t.elapsed().as_secs_f64();
    let after = vm_hwm_kib();
    let c = &channels[0].summary;
    println!(
        "file {:.1} MB, {} channels × {} samples; blows detected {}, averaged {}; dominant line of '{}' {:.2} Hz",
        size as f64 / 1e6,
        channels.len(),
        c.samples,
        c.blows,
        channels[0].spectrum.averages,
        channels[2].summary.name,
        channels[2].summary.dominant_frequency_hz.unwrap_or(f64::NAN)
    );
    println!("read {t_read:.3} s, read + process {total:.3} s (target ≤ 2 s)");
    if let (Some(b), Some(a)) = (before, after) {
        let peak = a as f64 * 1024.0;
        println!(
            "peak resident memory {:.1} MB ({:.2}× the file; {:.1} MB before reading) (target ≤ 2×)",
            peak / 1e6,
            peak / size as f64,
            b as f64 * 1024.0 / 1e6
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    match args.get(1).map(String::as_str) {
        Some("write") => write(Path::new(&args[2])),
        Some("read") => read(Path::new(&args[2])),
        _ => {
            let path =
                std::env::temp_dir().join(format!("meid-measure-bench-{}.uff", std::process::id()));
            let exe = std::env::current_exe().unwrap();
            let ok = std::process::Command::new(&exe)
                .arg("write")
                .arg(&path)
                .status()
                .unwrap();
            assert!(ok.success());
            let ok = std::process::Command::new(&exe)
                .arg("read")
                .arg(&path)
                .status()
                .unwrap();
            let _ = std::fs::remove_file(&path);
            assert!(ok.success());
        }
    }
}
