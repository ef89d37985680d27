//! Benchmark of the sparse shift-invert block Lanczos solver (`meid::modal::lanczos`).
//!
//! ```text
//! cargo run --release -p meid --example eig_bench -- [plate|lattice|truss] NX NY NZ [COUNT] [BLOCK] [--threads T] [--basis N] [--export DIR] [--peer]
//! ```
//! Builds a free-floating test model (see `tests/lanczos_support`), solves for COUNT modes
//! (default 20), prints a JSON line with times, frequencies and checks. `--export DIR` writes
//! `DIR/K.mtx` and `DIR/M.mtx`; `--peer` (implies export, default DIR = target/eig_bench) also
//! runs `bench/peer/eigsh_peer.py` (SciPy `eigsh` with the same shift) and prints the time
//! ratio and the largest relative frequency difference. Measure peak memory with
//! `/usr/bin/time -v`.

#[path = "../tests/lanczos_support/mod.rs"]
mod lanczos_support;

use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

use meid::io::matrix_market;
use meid::modal::lanczos::{lowest_modes, LanczosOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut pos: Vec<&str> = Vec::new();
    let mut export: Option<PathBuf> = None;
    let mut peer = false;
    let mut basis: Option<usize> = None;
    let mut i = 0;
    while i < args.len() {
        match args[i].as_str() {
            "--export" => {
                export = Some(PathBuf::from(
                    args.get(i + 1).ok_or("--export needs a directory")?,
                ));
                i += 1;
            }
            "--peer" => peer = true,
            "--basis" => {
                basis = Some(args.get(i + 1).ok_or("--basis needs a number")?.parse()?);
                i += 1;
            }
            "--threads" => {
                let t: usize = args.get(i + 1).ok_or("--threads needs a number")?.parse()?;
                rayon::ThreadPoolBuilder::new()
                    .num_threads(t)
                    .build_global()?;
                faer::set_global_parallelism(if t <= 1 {
                    faer::Par::Seq
                } else {
                    faer::Par::rayon(t)
                });
                i += 1;
            }
            a => pos.push(a),
        }
        i += 1;
    }
    let model = pos.first().copied().unwrap_or("plate");
    let num = |k: usize, d: usize| -> Result<usize, Box<dyn std::error::Error>> {
        Ok(pos.get(k).map(|s| s.parse()).transpose()?.unwrap_or(d))
    };
    let dims = [num(1, 130)?, num(2, 130)?, num(3, 2)?];
    let count = num(4, 20)?;
    let block = num(5, 6)?;

    let t0 = Instant::now();
    let (k, m) = match model {
        "plate" | "truss" => lanczos_support::truss_lattice(dims, 1.0e7, 4.0e6, 2.0),
        "lattice" => lanczos_support::scalar_lattice(dims, 1.0e7, 2.0),
        other => return Err(format!("unknown model `{other}` (plate, truss, lattice)").into()),
    };
    let t_build = t0.elapsed().as_secs_f64();

    let opts = LanczosOptions {
        count,
        block_size: block,
        basis_size: basis,
        ..Default::default()
    };
    let t1 = Instant::now();
    let r = lowest_modes(k.as_ref(), m.as_ref(), &opts)?;
    let t_solve = t1.elapsed().as_secs_f64();

    let freqs: Vec<String> = r.frequency_hz.iter().map(|f| format!("{f:.10e}")).collect();
    println!(
        "{{\"solver\":\"meid\",\"model\":\"{model}\",\"dims\":{:?},\"dof\":{},\"nnz\":{},\"count\":{count},\"block\":{block},\"build_s\":{t_build:.3},\"time_s\":{t_solve:.3},\"shift\":{:e},\"sturm_shift\":{:e},\"sturm_count\":{},\"computed_below\":{},\"rigid\":{},\"max_residual\":{:e},\"orthonormality_error\":{:e},\"stats\":\"{:?}\",\"frequencies_hz\":[{}]}}",
        dims,
        k.nrows(),
        k.compute_nnz(),
        r.shift,
        r.sturm_shift,
        r.sturm_count,
        r.computed_below_sturm_shift,
        r.rigid_body_modes,
        r.max_residual,
        r.orthonormality_error,
        r.stats,
        freqs.join(",")
    );

    if peer && export.is_none() {
        export = Some(PathBuf::from("target/eig_bench"));
    }
    if let Some(dir) = &export {
        std::fs::create_dir_all(dir)?;
        matrix_market::write_symmetric(&dir.join("K.mtx"), k.as_ref())?;
        matrix_market::write_symmetric(&dir.join("M.mtx"), m.as_ref())?;
    }
    if peer {
        let dir = export.clone().unwrap_or_default();
        let script =
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../bench/peer/eigsh_peer.py");
        let out = Command::new("python3")
            .arg(script)
            .arg(dir.join("K.mtx"))
            .arg(dir.join("M.mtx"))
            .arg(count.to_string())
            .arg(format!("{:e}", r.shift))
            .output()?;
        if !out.status.success() {
            return Err(format!("peer failed: {}", String::from_utf8_lossy(&out.stderr)).into());
        }
        let text = String::from_utf8(out.stdout)?;
        println!("{}", text.trim());
        let v: serde_json::Value = serde_json::from_str(text.trim())?;
        let peer_time = v["time_s"].as_f64().ok_or("peer output has no time_s")?;
        let peer_f: Vec<f64> = v["frequencies_hz"]
            .as_array()
            .ok_or("peer output has no frequencies_hz")?
            .iter()
            .filter_map(|x| x.as_f64())
            .collect();
        let fmax = r.frequency_hz.iter().fold(0.0_f64, |a, &b| a.max(b));
        let max_diff = r
            .frequency_hz
            .iter()
            .zip(&peer_f)
            .map(|(a, b)| (a - b).abs() / fmax.max(f64::MIN_POSITIVE))
            .fold(0.0_f64, f64::max);
        println!(
            "{{\"meid_time_s\":{t_solve:.3},\"scipy_time_s\":{peer_time:.3},\"ratio_meid_over_scipy\":{:.3},\"max_freq_diff_rel_to_fmax\":{max_diff:e}}}",
            t_solve / peer_time
        );
    }
    Ok(())
}
