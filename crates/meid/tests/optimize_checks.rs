//! Checks of `analysis::optimize` on problems with known minima.
//!
//! References: x² - 2x (x* = 1, f* = -1); x⁴ - 3x³ + 2 (f' = x²(4x - 9), x* = 9/4);
//! Rosenbrock (Comput. J. 3 (1960) 175), chained form Σ 100 (x_{i+1} - x_i²)² + (1 - x_i)²
//! with global minimum x* = (1, ..., 1), f* = 0; a separable quadratic whose box-constrained
//! minimum is the projection of the free minimum onto the box.
//! Brent's method locates the minimum to within 3 tol, tol = √ε |x| + x_tolerance
//! (Brent 1973, ch. 5); tests use that bound.

use meid::analysis::optimize::{
    brent_minimize, minimize_box, minimize_box_global, BrentOptions, GlobalOptions, MinimumNd,
    NelderMeadOptions,
};

fn brent_bound(x: f64, o: &BrentOptions) -> f64 {
    3.0 * (o.relative_tolerance * x.abs() + o.x_tolerance)
}

#[test]
fn brent_finds_minimum_of_quadratic() {
    let o = BrentOptions::default();
    let m = brent_minimize(|x: f64| x * x - 2.0 * x, -3.0, 5.0, &o).unwrap();
    assert!(m.converged);
    assert!((m.x - 1.0).abs() <= brent_bound(1.0, &o), "x = {}", m.x);
    assert!((m.f + 1.0).abs() < 1e-15);
    assert_eq!(m.history.len(), m.evaluations);
    assert_eq!(m.failures, 0);
    // Parabolic interpolation is exact for a parabola: far fewer evaluations than golden
    // section alone (which needs ~ log(8/1e-8)/log(1.618) ≈ 43).
    assert!(m.evaluations < 20, "{} evaluations", m.evaluations);
}

#[test]
fn brent_finds_minimum_of_quartic() {
    let o = BrentOptions::default();
    let f = |x: f64| x.powi(4) - 3.0 * x.powi(3) + 2.0;
    let m = brent_minimize(f, 1.0, 4.0, &o).unwrap();
    let x_star = 2.25;
    assert!(
        (m.x - x_star).abs() <= brent_bound(x_star, &o),
        "x = {}",
        m.x
    );
    assert!((m.f - f(x_star)).abs() < 1e-13);
    // The quartic also has a stationary (inflection) point at 0: outside the interval.
}

#[test]
fn brent_tolerance_controls_accuracy() {
    let o = BrentOptions {
        x_tolerance: 1e-3,
        relative_tolerance: 0.0,
        ..BrentOptions::default()
    };
    let loose =
        brent_minimize(|x: f64| (x - 0.3).powi(2) * (2.0 + x.sin()), -2.0, 2.0, &o).unwrap();
    assert!((loose.x - 0.3).abs() <= 3e-3);
    let tight = brent_minimize(
        |x: f64| (x - 0.3).powi(2) * (2.0 + x.sin()),
        -2.0,
        2.0,
        &BrentOptions::default(),
    )
    .unwrap();
    assert!((tight.x - 0.3).abs() <= brent_bound(0.3, &BrentOptions::default()));
    assert!(tight.evaluations > loose.evaluations);
}

#[test]
fn brent_minimum_on_the_bound() {
    // f = x on [0, 1]: the minimum is the end point 0, reached to within 3 tol.
    let o = BrentOptions::default();
    let m = brent_minimize(|x: f64| x, 0.0, 1.0, &o).unwrap();
    assert!(m.x >= 0.0 && m.x <= brent_bound(0.0, &o), "x = {}", m.x);
}

#[test]
fn brent_counts_failures_and_survives_them() {
    // The objective fails (Err) for x > 1.3. The first point is 0 + 0.382·3 = 1.146 and the
    // first golden step goes into the larger part to 1.854, which fails.
    let o = BrentOptions::default();
    let m = brent_minimize(
        |x: f64| {
            if x > 1.3 {
                Err("diverged")
            } else {
                Ok(x * x - 2.0 * x)
            }
        },
        0.0,
        3.0,
        &o,
    )
    .unwrap();
    assert!(m.failures >= 1);
    assert_eq!(
        m.failures,
        m.history.iter().filter(|(_, f)| f.is_infinite()).count()
    );
    assert!((m.x - 1.0).abs() <= brent_bound(1.0, &o), "x = {}", m.x);
    // Everything failing is an error, not a silent answer.
    assert!(brent_minimize(|_x: f64| None, 0.0, 1.0, &o).is_err());
    assert!(brent_minimize(|x: f64| x, 1.0, 0.0, &o).is_err());
}

fn rosenbrock(x: &[f64]) -> f64 {
    x.windows(2)
        .map(|w| 100.0 * (w[1] - w[0] * w[0]).powi(2) + (1.0 - w[0]).powi(2))
        .sum()
}

fn tight() -> NelderMeadOptions {
    NelderMeadOptions {
        x_tolerance: 1e-11,
        f_tolerance: 1e-18,
        max_evaluations: 20_000,
        ..NelderMeadOptions::default()
    }
}

fn assert_history_consistent(m: &MinimumNd) {
    println!(
        "x = {:?}, f = {:e}, {} evaluations, {} failures, {} restarts",
        m.x, m.f, m.evaluations, m.failures, m.restarts
    );
    assert_eq!(m.history.len(), m.evaluations);
    let best = m
        .history
        .iter()
        .map(|(_, f)| *f)
        .fold(f64::INFINITY, f64::min);
    assert_eq!(best, m.f);
    assert_eq!(
        m.failures,
        m.history.iter().filter(|(_, f)| f.is_infinite()).count()
    );
}

#[test]
fn nelder_mead_rosenbrock_2d() {
    let m = minimize_box(
        rosenbrock,
        &[-1.2, 1.0],
        &[-2.0, -2.0],
        &[2.0, 2.0],
        &tight(),
    )
    .unwrap();
    for xi in &m.x {
        assert!((xi - 1.0).abs() < 1e-6, "x = {:?}", m.x);
    }
    assert!(m.converged);
    assert_history_consistent(&m);
}

#[test]
fn nelder_mead_rosenbrock_4d() {
    let m = minimize_box(
        rosenbrock,
        &[-1.2, 1.0, -1.2, 1.0],
        &[-2.0; 4],
        &[2.0; 4],
        &tight(),
    )
    .unwrap();
    for xi in &m.x {
        assert!((xi - 1.0).abs() < 1e-6, "x = {:?}, f = {}", m.x, m.f);
    }
    assert_history_consistent(&m);
}

#[test]
fn nelder_mead_minimum_on_the_bounds() {
    // Free minimum (3, -1, 0.5); box [0, 2]³; constrained minimum (2, 0, 0.5), f = 2.
    let f = |x: &[f64]| (x[0] - 3.0).powi(2) + (x[1] + 1.0).powi(2) + (x[2] - 0.5).powi(2);
    let m = minimize_box(f, &[1.0, 1.0, 1.0], &[0.0; 3], &[2.0; 3], &tight()).unwrap();
    // Projection onto the box lands exactly on the active bounds.
    assert_eq!((m.x[0], m.x[1]), (2.0, 0.0), "x = {:?}", m.x);
    // The free coordinate is limited by rounding of f* = 2: (z - 0.5)² is invisible below
    // ε f*, so |z - 0.5| can only be resolved to √(ε f*) ≈ 2.1e-8; allow twice that.
    let floor = (f64::EPSILON * 2.0).sqrt();
    assert!((m.x[2] - 0.5).abs() < 2.0 * floor, "x = {:?}", m.x);
    assert!((m.f - 2.0).abs() < 1e-14);
    for (xi, (lo, hi)) in m.x.iter().zip([(0.0, 2.0); 3]) {
        assert!(*xi >= lo && *xi <= hi);
    }
}

#[test]
fn nelder_mead_is_deterministic_for_a_seed() {
    let o = NelderMeadOptions {
        random_starts: 3,
        seed: 42,
        ..tight()
    };
    let run = |o: &NelderMeadOptions| {
        minimize_box(rosenbrock, &[0.0, 0.0, 0.0], &[-2.0; 3], &[2.0; 3], o).unwrap()
    };
    let (a, b) = (run(&o), run(&o));
    assert_eq!(a, b);
    let c = run(&NelderMeadOptions { seed: 7, ..o });
    assert_ne!(a.history, c.history);
    for xi in &a.x {
        assert!((xi - 1.0).abs() < 1e-6, "x = {:?}", a.x);
    }
}

#[test]
fn nelder_mead_treats_failures_as_infinite() {
    // The simulation "diverges" (Err) whenever x0 + x1 > 2.5; the minimum (1, 1) is feasible.
    let f = |x: &[f64]| -> Result<f64, String> {
        if x[0] + x[1] > 2.5 {
            Err("diverged".into())
        } else {
            Ok(rosenbrock(x))
        }
    };
    let m = minimize_box(f, &[1.5, 0.9], &[-2.0, -2.0], &[2.0, 2.0], &tight()).unwrap();
    assert!(m.failures > 0, "this start must probe the failing region");
    for xi in &m.x {
        assert!((xi - 1.0).abs() < 1e-6, "x = {:?}", m.x);
    }
    assert_history_consistent(&m);
    // All failures: an error naming the cause.
    let none = minimize_box(|_x: &[f64]| f64::NAN, &[0.0], &[-1.0], &[1.0], &tight());
    assert!(none.is_err());
}

#[test]
fn nelder_mead_rejects_bad_input() {
    let o = NelderMeadOptions::default();
    assert!(minimize_box(rosenbrock, &[3.0, 0.0], &[-2.0; 2], &[2.0; 2], &o).is_err());
    assert!(minimize_box(rosenbrock, &[0.0, 0.0], &[1.0, -2.0], &[1.0, 2.0], &o).is_err());
    assert!(minimize_box(rosenbrock, &[0.0, 0.0], &[-2.0], &[2.0, 2.0], &o).is_err());
    assert!(minimize_box(rosenbrock, &[], &[], &[], &o).is_err());
}

#[test]
fn nelder_mead_respects_the_budget() {
    let o = NelderMeadOptions {
        max_evaluations: 60,
        ..tight()
    };
    let m = minimize_box(rosenbrock, &[-1.2, 1.0], &[-2.0; 2], &[2.0; 2], &o).unwrap();
    assert!(m.evaluations <= 60);
    assert!(!m.converged);
}

#[test]
fn random_starts_find_the_global_minimum() {
    // f = (x² - 1)² + 0.3 x + y² has two wells; the global one is at the root of
    // f'(x) = 4x(x² - 1) + 0.3 near x = -1 (found here by Newton's method, independent of
    // the optimiser), the local one near x = +1. Started in the right-hand well, a single
    // local search stays there; seeded random starts reach the global well.
    let f = |v: &[f64]| (v[0] * v[0] - 1.0).powi(2) + 0.3 * v[0] + v[1] * v[1];
    let mut x_star: f64 = -1.0;
    for _ in 0..50 {
        let g = 4.0 * x_star * (x_star * x_star - 1.0) + 0.3;
        let h = 12.0 * x_star * x_star - 4.0;
        x_star -= g / h;
    }
    let (lo, hi) = ([-2.0, -2.0], [2.0, 2.0]);
    let single = minimize_box(f, &[0.9, 0.5], &lo, &hi, &tight()).unwrap();
    assert!(
        single.x[0] > 0.0,
        "single start left its well: {:?}",
        single.x
    );
    let multi = minimize_box(
        f,
        &[0.9, 0.5],
        &lo,
        &hi,
        &NelderMeadOptions {
            random_starts: 10,
            seed: 3,
            ..tight()
        },
    )
    .unwrap();
    assert!((multi.x[0] - x_star).abs() < 1e-6, "x = {:?}", multi.x);
    assert!(multi.x[1].abs() < 1e-6);
    assert!(multi.f < single.f);
}

/// A narrow deep Gaussian well inside the box and a broad shallower well of compact support
/// centred on the bound x = 1, covering most of the box: f = −exp(−|x − c₁|²/(2σ²))
/// − 0.7 max(0, 1 − |x − c₂|²/R²)², c₁ = (0.1, 0.9), σ = 0.035, c₂ = (1, 0.1), R = 1.
/// |c₁ − c₂| = 1.204 > R, so at c₁ the broad well is 0 with zero gradient: the global minimum
/// is exactly x* = c₁, f* = −1 (the broad well's depth is 0.7 and the Gaussian is below e⁻¹⁶
/// inside its support).
fn two_wells(v: &[f64]) -> f64 {
    let r1 = (v[0] - 0.1).powi(2) + (v[1] - 0.9).powi(2);
    let r2 = (v[0] - 1.0).powi(2) + (v[1] - 0.1).powi(2);
    -(-r1 / (2.0 * 0.035 * 0.035)).exp() - 0.7 * (1.0 - r2).max(0.0).powi(2)
}

/// The options `meid optimize` used for two variables before the grid (session 12): one
/// start at the box centre and 2 seeded random starts.
fn old_study_options() -> NelderMeadOptions {
    NelderMeadOptions {
        initial_step: 0.2,
        x_tolerance: 1e-5,
        f_tolerance: 1e-9,
        max_evaluations: 400,
        max_restarts: 5,
        random_starts: 2,
        seed: 4,
        polish: true,
    }
}

fn global_options() -> GlobalOptions {
    GlobalOptions {
        grid_points: 33,
        starts: 4,
        max_evaluations: 33 * 33 + 800,
        local: NelderMeadOptions {
            random_starts: 0,
            ..old_study_options()
        },
    }
}

#[test]
fn grid_search_finds_the_narrow_global_well_the_local_search_misses() {
    let (lo, hi) = ([0.0, 0.0], [1.0, 1.0]);
    // The local multi-start search of the old optimiser ends in the broad well on the bound.
    let old = minimize_box(two_wells, &[0.5, 0.5], &lo, &hi, &old_study_options()).unwrap();
    assert!(old.f > -0.9, "old search found {:?} f = {}", old.x, old.f);
    let m = minimize_box_global(two_wells, &lo, &hi, &global_options()).unwrap();
    assert!((m.x[0] - 0.1).abs() < 1e-4, "x = {:?}", m.x);
    assert!((m.x[1] - 0.9).abs() < 1e-4, "x = {:?}", m.x);
    assert!((m.f + 1.0).abs() < 1e-8, "f = {}", m.f);
    assert_eq!(m.grid_evaluations, 33 * 33);
    assert!(m.evaluations <= 33 * 33 + 800);
    assert!(m.searches.len() >= 2, "the broad well is a second start");
    // Same answer, and the same evaluation count, on one thread and on two.
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| minimize_box_global(two_wells, &lo, &hi, &global_options()).unwrap())
    };
    assert_eq!(on(1), m);
    assert_eq!(on(2), m);
}

#[test]
fn grid_search_refuses_a_budget_that_cannot_hold_its_grid() {
    let (lo, hi) = ([0.0, 0.0], [1.0, 1.0]);
    let o = GlobalOptions {
        max_evaluations: 33 * 33 + 2,
        ..global_options()
    };
    let e = minimize_box_global(two_wells, &lo, &hi, &o).unwrap_err();
    assert!(e.to_string().contains("33^2"), "{e}");
    let o = GlobalOptions {
        grid_points: 1,
        ..global_options()
    };
    assert!(minimize_box_global(two_wells, &lo, &hi, &o).is_err());
    let o = GlobalOptions {
        grid_points: usize::MAX,
        ..global_options()
    };
    assert!(minimize_box_global(two_wells, &lo, &hi, &o).is_err());
    assert!(minimize_box_global(|_x: &[f64]| f64::NAN, &lo, &hi, &global_options()).is_err());
}
