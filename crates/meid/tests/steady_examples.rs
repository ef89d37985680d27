//! Issue 28's check on the paper machine's four examples with both methods: at 20, 60 and
//! 120 /min the direct periodic steady state (`analysis::steady`) equals a 60-blow march from
//! rest (`analysis::blows`) where the march has settled, within 1e-6 relative in every
//! reported level; where the search finds no period, the march has not settled either.

use meid::analysis::blows::{run_blows, BlowOptions, BlowReport};
use meid::analysis::steady::{steady_state, Regime, SteadyOptions, SteadyState};
use meid::integrate::Method;
use meid::model::{Case, Model};

fn example(name: &str) -> Model {
    let path = format!("{}/../../examples/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    Model::from_file(path.as_ref(), &[]).unwrap()
}

/// The levels of `k` blows as the steady state reports a period's: η the mean, the peaks and
/// the damper's gap the largest.
fn levels(b: &[BlowReport]) -> [f64; 4] {
    let max = |f: &dyn Fn(&BlowReport) -> f64| b.iter().map(f).fold(f64::MIN, f64::max);
    [
        b.iter().map(|r| r.energy_ratio.unwrap()).sum::<f64>() / b.len() as f64,
        max(&|r| r.peak_floor_force_n),
        max(&|r| r.peak_bed_acceleration_m_per_s2),
        max(&|r| r.damper_gap_at_strike_m.unwrap_or(0.0)),
    ]
}

fn steady_levels(s: &SteadyState) -> [f64; 4] {
    [
        s.energy_ratio,
        s.peak_floor_force_n,
        s.peak_bed_acceleration_m_per_s2,
        s.damper_gap_at_strike_m.unwrap_or(0.0),
    ]
}

/// One example, method and rate: the steady state against the march (module docs).
fn check(name: &str, model: &Model, method: Method, rate: f64) -> String {
    let sys = model.impact_system(Case::Damper).unwrap();
    let mut o = model.options();
    o.method = method;
    let so = SteadyOptions {
        rate_bpm: rate,
        ..SteadyOptions::default()
    };
    let s = steady_state(&sys, &o, &so).unwrap();
    o.sample_rate = None;
    let b = BlowOptions {
        blows: 60,
        rate_bpm: rate,
        steady_tolerance: 1e-9,
    };
    let march = run_blows(&sys, &o, &b, false).unwrap();
    let n = march.blows.len();
    let what = format!(
        "{name} {method:?} {rate} /min: {} converged {} ({} evaluations), |μ| {:?}",
        s.regime.name(),
        s.converged,
        s.map_evaluations,
        s.multipliers_abs.first()
    );
    let Regime::Period(k) = s.regime else {
        // No period within the budget: the march has not settled over its last blows either.
        let spread = |i: usize| {
            let v: Vec<f64> = march.blows[n - 8..]
                .iter()
                .map(|r| steady_levels_of(r)[i])
                .collect();
            let (lo, hi) = v
                .iter()
                .fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(*x), b.max(*x)));
            (hi - lo) / hi.abs()
        };
        assert!(!s.converged, "{what}");
        assert!(
            (0..3).any(|i| spread(i) > 1e-6),
            "{what}: the march settled"
        );
        return format!("{what}: irregular, the march unsettled too");
    };
    assert!(s.converged, "{what}");
    // The march's last period and the one before it; the march is still a geometric tail
    // away from its limit: the next blows add at most |Δ| μ/(1 − μ) (μ = |μ|max of P^k).
    let last = levels(&march.blows[n - k..]);
    let prev = levels(&march.blows[n - 2 * k..n - k]);
    let st = steady_levels(&s);
    let mu = s.multipliers_abs.first().copied().unwrap_or(0.0);
    let mut worst = 0.0_f64;
    for i in 0..4 {
        let tail = (last[i] - prev[i]).abs() * mu / (1.0 - mu);
        let scale = if i == 3 {
            last[i].abs().max(1e-6)
        } else {
            last[i].abs()
        };
        let d = (st[i] - last[i]).abs();
        assert!(
            d <= (1e-6 * scale).max(2.0 * tail),
            "{what}: level {i} steady {} march {} (previous period {}), tail {tail:.2e}",
            st[i],
            last[i],
            prev[i]
        );
        worst = worst.max(d / scale);
    }
    format!("{what}: largest difference {worst:.1e}")
}

fn steady_levels_of(r: &BlowReport) -> [f64; 4] {
    levels(std::slice::from_ref(r))
}

/// The four examples, exact and dopri5, at 20, 60 and 120 /min (24 steady states and 24
/// 60-blow marches; about a minute in release on one core).
#[test]
fn the_direct_steady_state_equals_a_long_march_on_the_four_examples_with_both_methods() {
    for name in [
        "paper-lumped",
        "paper-soft-base",
        "paper-stiff-base",
        "paper-no-base",
    ] {
        let model = example(name);
        for method in [Method::Exact, Method::Dopri5] {
            for rate in [20.0, 60.0, 120.0] {
                eprintln!("{}", check(name, &model, method, rate));
            }
        }
    }
}
