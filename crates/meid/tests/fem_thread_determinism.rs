//! Every number of the FE route is independent of the thread count: assembly, the dense and
//! sparse eigen-solvers, the reduced modal model and a whole blow, run inside rayon pools of
//! 1, 2 and 3 threads, are compared bit for bit.
//!
//! Reference: bit identity (`f64::to_bits`), not a tolerance. Before the fix the paper
//! soft-base machine's lowest frequency differed in the 9th digit between 1 and 2 threads
//! (2.7416123541434754 vs 2.741612356085001 Hz): faer's parallel kernels split their reductions
//! by the thread count, and the Lanczos iteration amplified the last-bit differences.

use std::path::PathBuf;

use faer::Mat;
use meid::modal::lanczos::{lowest_modes, LanczosOptions};
use meid::model::{fem, Case, Model};
use meid::structure::FeModel;

const THREADS: [usize; 3] = [1, 2, 3];

fn example(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

/// Runs `f` in a rayon pool of `threads` threads.
fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

/// Asserts that `a` and `b` hold the same doubles bit for bit, naming the first difference.
fn assert_same(a: &[f64], b: &[f64], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    if let Some(i) = (0..a.len()).find(|&i| a[i].to_bits() != b[i].to_bits()) {
        panic!("{what}: entry {i} differs: {:e} vs {:e}", a[i], b[i]);
    }
}

fn entries(m: &Mat<f64>) -> Vec<f64> {
    m.col_iter()
        .flat_map(|c| c.iter().copied().collect::<Vec<_>>())
        .collect()
}

/// The FE model of an example with `elements_per_side` elements per bed side.
fn machine(name: &str, elements_per_side: usize) -> FeModel {
    let m = Model::from_file(&example(name), &[]).unwrap();
    let file = m
        .spec
        .structure
        .fem
        .as_ref()
        .unwrap()
        .machine
        .as_ref()
        .unwrap();
    let mut spec = fem::machine_spec(file).unwrap();
    spec.elements_per_side = elements_per_side;
    spec.build().unwrap().model
}

/// max |Φᵀ M Φ - I| from the shapes and the sparse mass matrix (M Φ by its triplets).
fn orthonormality(model: &FeModel, shapes: &Mat<f64>) -> f64 {
    let p = shapes.ncols();
    let mut mphi = Mat::<f64>::zeros(shapes.nrows(), p);
    for t in model.mass.triplet_iter() {
        for c in 0..p {
            mphi[(t.row, c)] += t.val * shapes[(t.col, c)];
        }
    }
    let mut worst = 0.0_f64;
    for a in 0..p {
        for b in 0..p {
            let g: f64 = (0..shapes.nrows())
                .map(|i| shapes[(i, a)] * mphi[(i, b)])
                .sum();
            worst = worst.max((g - if a == b { 1.0 } else { 0.0 }).abs());
        }
    }
    worst
}

/// The paper soft-base machine as the example builds it (20 elements per side, 3,552 DOFs,
/// sparse Lanczos, the example's 30 modes): assembly, eigenvalues, shapes, residuals and the Sturm count are
/// bit-identical in pools of 1, 2 and 3 threads, and the modes are sound (M-orthonormal,
/// residuals small), so the comparison is between correct results.
#[test]
fn lanczos_modes_of_the_paper_machine_are_thread_count_independent() {
    let opts = LanczosOptions {
        count: 30,
        ..LanczosOptions::default()
    };
    let runs: Vec<_> = THREADS
        .iter()
        .map(|&t| {
            in_pool(t, || {
                let model = machine("paper-soft-base.toml", 20);
                let r = lowest_modes(model.stiffness.as_ref(), model.mass.as_ref(), &opts).unwrap();
                (model, r)
            })
        })
        .collect();
    let (model0, r0) = &runs[0];
    assert!(model0.n_dofs() > 1000, "{} DOFs", model0.n_dofs());
    assert_eq!(r0.eigenvalues.len(), 30);
    assert!(r0.max_residual < 1e-6, "residual {}", r0.max_residual);
    let orth = orthonormality(model0, &r0.shapes);
    assert!(orth < 1e-10, "orthonormality {orth}");
    // The paper's vertical rigid-body mode (6.35 Hz) is among them (docs/explanations/paper-machine.md).
    assert!(
        r0.frequency_hz.iter().any(|f| (f - 6.35).abs() < 0.2),
        "{:?}",
        r0.frequency_hz
    );
    for (t, (model, r)) in THREADS.iter().zip(&runs).skip(1) {
        assert_same(
            model.stiffness.val(),
            model0.stiffness.val(),
            &format!("K, {t} threads"),
        );
        assert_same(
            model.mass.val(),
            model0.mass.val(),
            &format!("M, {t} threads"),
        );
        assert_same(
            &model.floor_stiffness,
            &model0.floor_stiffness,
            &format!("floor functional, {t} threads"),
        );
        assert_same(
            &r.eigenvalues,
            &r0.eigenvalues,
            &format!("eigenvalues, {t} threads"),
        );
        assert_same(&r.frequency_hz, &r0.frequency_hz, "frequencies");
        assert_same(
            &entries(&r.shapes),
            &entries(&r0.shapes),
            &format!("shapes, {t} threads"),
        );
        assert_same(&r.residuals, &r0.residuals, "residuals");
        assert_eq!(r.sturm_count, r0.sturm_count);
        assert_eq!(r.sturm_shift.to_bits(), r0.sturm_shift.to_bits());
        assert_eq!(r.stats.block_steps, r0.stats.block_steps);
    }
}

/// The dense solver (all modes, shift-invert reduction) on the soft-base machine at 6 elements
/// per side: bit-identical eigenvalues and shapes in pools of 1, 2 and 3 threads; the low modes are
/// M-orthonormal.
#[test]
fn dense_modes_of_the_paper_machine_are_thread_count_independent() {
    let model = machine("paper-soft-base.toml", 6);
    assert!(model.n_dofs() >= 300, "{} DOFs", model.n_dofs());
    let runs: Vec<_> = THREADS
        .iter()
        .map(|&t| in_pool(t, || model.solve_dense().unwrap()))
        .collect();
    let d0 = &runs[0];
    // The lowest 20 modes are sound (the top of a shell mesh's spectrum is round-off noise,
    // see `modal::dense`, so the solver's worst-mode figure is not the check here).
    let low = d0.shapes.subcols(0, 20).to_owned();
    let orth = orthonormality(&model, &low);
    assert!(orth < 1e-9, "orthonormality of the lowest 20 modes {orth}");
    for (t, d) in THREADS.iter().zip(&runs).skip(1) {
        assert_same(
            &d.eigenvalues,
            &d0.eigenvalues,
            &format!("eigenvalues, {t} threads"),
        );
        assert_same(
            &entries(&d.shapes),
            &entries(&d0.shapes),
            &format!("shapes, {t} threads"),
        );
        assert_eq!(d.max_residual.to_bits(), d0.max_residual.to_bits());
        assert_eq!(
            d.orthonormality_error.to_bits(),
            d0.orthonormality_error.to_bits()
        );
    }
}

/// `meid simulate examples/paper-soft-base.toml` through the library, every step (model file,
/// FE build, Lanczos, mode selection, reduction, the blow with recorded histories) inside pools
/// of 1, 2 and 3 threads: the reduced modal model, the summary and every history sample are
/// bit-identical (compared through `{:?}`, whose shortest round-trip digits differ for any two
/// different finite doubles).
#[test]
fn simulate_of_the_paper_machine_is_thread_count_independent() {
    let runs: Vec<_> = THREADS
        .iter()
        .map(|&t| {
            in_pool(t, || {
                let model = Model::from_file(&example("paper-soft-base.toml"), &[]).unwrap();
                let sys = model.impact_system(Case::AsSpecified).unwrap();
                let run = meid::analysis::simulate(&sys, &model.options(), true).unwrap();
                let history = run.history.unwrap();
                let samples = history.time_s.len();
                let ratio = run.summary.energy_ratio.unwrap();
                (
                    format!("{:?}", model.structure),
                    format!("{:?}", run.summary),
                    format!("{history:?}"),
                    samples,
                    ratio,
                )
            })
        })
        .collect();
    let (modal0, summary0, history0, samples, ratio) = &runs[0];
    assert!(*ratio > 0.0 && *ratio < 1.0, "energy ratio {ratio}");
    assert!(*samples > 1000, "{samples} samples");
    for (t, (modal, summary, history, _, _)) in THREADS.iter().zip(&runs).skip(1) {
        assert_eq!(modal, modal0, "modal model, {t} threads");
        assert_eq!(summary, summary0, "summary, {t} threads");
        assert!(history == history0, "histories differ, {t} threads");
    }
}
