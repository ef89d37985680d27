//! Benchmark of the hand-written small dense eigen-solvers (`meid::integrate::small`) against
//! faer 0.24 (sequential), on the matrices the exact propagator builds.
//!
//! ```text
//! cargo run --release -p meid --example small_eig_bench
//! ```
//!
//! Matrices: the balanced first-order matrix `A_r = [[0, S], [−diag(κ/S), −C_r]]` of a damped
//! grounded mass-spring chain with n DOF (8×8 for n = 4, 24×24 for n = 12; κ, C_r from the
//! mass-normalised K and a PSD damping), and the mass-normalised stiffness `M^{-½} K M^{-½}` of
//! a 4- and a 22-DOF chain for `sym_eigen`.
//!
//! Method: each case is run in batches of `reps` calls (reps chosen so a batch lasts ~2 ms);
//! the time per call of each batch is recorded over 41 batches after 5 warm-up batches, and the
//! median is printed (min and max too). Inputs and outputs pass through `black_box`.

use std::hint::black_box;
use std::time::Instant;

use faer::Mat;
use meid::integrate::small::{inverse, real_eigen, real_eigen_faer, sym_eigen, sym_eigen_faer};

use meid::rng::SplitMix64 as Rng;

/// Mass-normalised stiffness and damping of a grounded chain with n DOF.
fn chain(n: usize, seed: u64) -> (Mat<f64>, Mat<f64>) {
    let mut r = Rng::new(seed);
    let m: Vec<f64> = (0..n).map(|_| 1.0 + 20.0 * r.next_f64()).collect();
    let ks: Vec<f64> = (0..n).map(|_| 1e6 * (1.0 + 50.0 * r.next_f64())).collect();
    let cs: Vec<f64> = (0..n).map(|_| 50.0 * r.next_f64()).collect();
    let mut k = Mat::<f64>::zeros(n, n);
    let mut c = Mat::<f64>::zeros(n, n);
    for i in 0..n {
        k[(i, i)] += ks[i];
        c[(i, i)] += cs[i];
        if i > 0 {
            k[(i - 1, i - 1)] += ks[i];
            k[(i - 1, i)] -= ks[i];
            k[(i, i - 1)] -= ks[i];
            c[(i - 1, i - 1)] += cs[i];
            c[(i - 1, i)] -= cs[i];
            c[(i, i - 1)] -= cs[i];
        }
    }
    let kt = Mat::<f64>::from_fn(n, n, |i, j| k[(i, j)] / (m[i] * m[j]).sqrt());
    let ct = Mat::<f64>::from_fn(n, n, |i, j| c[(i, j)] / (m[i] * m[j]).sqrt());
    (kt, ct)
}

fn balanced(n: usize, seed: u64) -> Result<Mat<f64>, meid::Error> {
    let (kt, ct) = chain(n, seed);
    let (kappa, q) = sym_eigen(&kt)?;
    let cr = Mat::<f64>::from_fn(n, n, |i, j| {
        (0..n)
            .map(|a| {
                (0..n)
                    .map(|b| q[(a, i)] * ct[(a, b)] * q[(b, j)])
                    .sum::<f64>()
            })
            .sum()
    });
    Ok(Mat::<f64>::from_fn(2 * n, 2 * n, |i, j| {
        if i < n {
            if j == n + i {
                kappa[i].sqrt()
            } else {
                0.0
            }
        } else if j < n {
            if j == i - n {
                -kappa[j].sqrt()
            } else {
                0.0
            }
        } else {
            -0.5 * (cr[(i - n, j - n)] + cr[(j - n, i - n)])
        }
    }))
}

/// Median, min, max time per call (µs).
fn time<F: FnMut()>(mut f: F) -> (f64, f64, f64) {
    let t0 = Instant::now();
    let mut calls = 0usize;
    while t0.elapsed().as_secs_f64() < 0.02 {
        f();
        calls += 1;
    }
    let per = t0.elapsed().as_secs_f64() / calls as f64;
    let reps = ((2e-3 / per).ceil() as usize).max(1);
    let mut v = Vec::new();
    for b in 0..46 {
        let t = Instant::now();
        for _ in 0..reps {
            f();
        }
        if b >= 5 {
            v.push(t.elapsed().as_secs_f64() / reps as f64 * 1e6);
        }
    }
    v.sort_by(f64::total_cmp);
    (v[v.len() / 2], v[0], v[v.len() - 1])
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // `-- calls CASE N`: run one case N times without timing (for callgrind instruction counts:
    // (Ir(N) − Ir(0)) / N). CASE: real8, real24, real8faer, inv8, sym{4,8,12,22}[faer].
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("calls") {
        let case = args.get(1).ok_or("calls CASE N")?.as_str();
        let reps: usize = args.get(2).ok_or("calls CASE N")?.parse()?;
        let a8 = balanced(4, 11)?;
        let a24 = balanced(12, 19)?;
        let v8 = real_eigen(&a8)?.1;
        let (k4, _) = chain(4, 7);
        let (k22, _) = chain(22, 25);
        let (k8, _) = chain(8, 9);
        let (k12, _) = chain(12, 13);
        for _ in 0..reps {
            match case {
                "real8" => drop(black_box(real_eigen(black_box(&a8)))),
                "real8faer" => drop(black_box(real_eigen_faer(black_box(&a8)))),
                "real24" => drop(black_box(real_eigen(black_box(&a24)))),
                "inv8" => drop(black_box(inverse(black_box(&v8)))),
                "sym4" => drop(black_box(sym_eigen(black_box(&k4)))),
                "sym4faer" => drop(black_box(sym_eigen_faer(black_box(&k4)))),
                "sym22" => drop(black_box(sym_eigen(black_box(&k22)))),
                "sym22faer" => drop(black_box(sym_eigen_faer(black_box(&k22)))),
                "sym8" => drop(black_box(sym_eigen(black_box(&k8)))),
                "sym8faer" => drop(black_box(sym_eigen_faer(black_box(&k8)))),
                "sym12" => drop(black_box(sym_eigen(black_box(&k12)))),
                "sym12faer" => drop(black_box(sym_eigen_faer(black_box(&k12)))),
                _ => return Err(format!("unknown case {case}").into()),
            }
        }
        return Ok(());
    }
    println!("case                          median_us   min_us   max_us");
    let show = |name: &str, t: (f64, f64, f64)| {
        println!("{name:<30}{:>9.3}{:>9.3}{:>9.3}", t.0, t.1, t.2);
    };
    for dof in [4usize, 12] {
        let a = balanced(dof, 7 + dof as u64)?;
        let n = 2 * dof;
        show(
            &format!("real_eigen+inverse {n}x{n} meid"),
            time(|| {
                if let Ok((l, v)) = real_eigen(black_box(&a)) {
                    black_box((l, inverse(&v)));
                }
            }),
        );
        show(
            &format!("real_eigen+inverse {n}x{n} faer"),
            time(|| {
                if let Ok((l, v)) = real_eigen_faer(black_box(&a)) {
                    black_box((l, inverse(&v)));
                }
            }),
        );
        show(
            &format!("real_eigen {n}x{n} meid"),
            time(|| {
                black_box(real_eigen(black_box(&a)).ok());
            }),
        );
        show(
            &format!("real_eigen {n}x{n} faer"),
            time(|| {
                black_box(real_eigen_faer(black_box(&a)).ok());
            }),
        );
        let v = real_eigen(&a)?.1;
        show(
            &format!("inverse {n}x{n} meid"),
            time(|| {
                black_box(inverse(black_box(&v)));
            }),
        );
    }
    for n in [4usize, 22] {
        let (kt, _) = chain(n, 3 + n as u64);
        show(
            &format!("sym_eigen {n}x{n} meid"),
            time(|| {
                black_box(sym_eigen(black_box(&kt)).ok());
            }),
        );
        show(
            &format!("sym_eigen {n}x{n} faer"),
            time(|| {
                black_box(sym_eigen_faer(black_box(&kt)).ok());
            }),
        );
    }
    Ok(())
}
