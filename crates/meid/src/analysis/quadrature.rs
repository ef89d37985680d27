//! Adaptive Gauss-Kronrod quadrature (G7/K15, as QUADPACK's `qk15`/`qag`) for integrals of the
//! exact energy spectral density ([`super::esd`]): band energies and Parseval checks.
//!
//! `∫_a^b f ≈ K₁₅ = Σ_j w_j f(x_j)` on each interval, with the embedded 7-point Gauss rule `G₇`;
//! the interval's error estimate is `|K₁₅ − G₇|` (for smooth integrands the true error of `K₁₅`
//! is orders of magnitude below it, so the stated error is an upper estimate). The interval with
//! the largest estimate is bisected until the sum of the estimates is below
//! `max(atol, rtol·|I|)` or the evaluation budget is spent. Breakpoints (e.g. the frequencies of
//! lightly damped poles, where the density has a narrow peak) start the subdivision.
//! R. Piessens et al., *QUADPACK*, Springer 1983.

/// Kronrod nodes (the positive half; 0 last) of the 15-point rule on [−1, 1].
const XGK: [f64; 8] = [
    0.991_455_371_120_812_6,
    0.949_107_912_342_758_5,
    0.864_864_423_359_769_1,
    0.741_531_185_599_394_4,
    0.586_087_235_467_691_1,
    0.405_845_151_377_397_2,
    0.207_784_955_007_898_5,
    0.0,
];
/// Kronrod weights for [`XGK`].
const WGK: [f64; 8] = [
    0.022_935_322_010_529_22,
    0.063_092_092_629_978_55,
    0.104_790_010_322_250_2,
    0.140_653_259_715_525_9,
    0.169_004_726_639_267_9,
    0.190_350_578_064_785_4,
    0.204_432_940_075_298_9,
    0.209_482_141_084_727_8,
];
/// Gauss weights of the 7-point rule, whose nodes are `XGK[1], XGK[3], XGK[5], XGK[7]`.
const WG: [f64; 4] = [
    0.129_484_966_168_869_7,
    0.279_705_391_489_276_7,
    0.381_830_050_505_118_9,
    0.417_959_183_673_469_4,
];

/// The result of an adaptive quadrature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quadrature {
    /// The integral (Kronrod sums).
    pub value: f64,
    /// Sum of the intervals' `|K₁₅ − G₇|`: an upper estimate of the error.
    pub error: f64,
    /// Integrand evaluations.
    pub evaluations: usize,
    /// True when the tolerance was met within the budget.
    pub converged: bool,
}

/// Settings of [`integrate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerance {
    pub rtol: f64,
    pub atol: f64,
    /// Evaluation budget (each interval costs 15).
    pub max_evaluations: usize,
}

impl Default for Tolerance {
    fn default() -> Self {
        Self {
            rtol: 1e-8,
            atol: 0.0,
            max_evaluations: 60_000,
        }
    }
}

/// `K₁₅` and `|K₁₅ − G₇|` on `[a, b]` of each of the `n` components of `f`.
fn rule(f: &mut dyn FnMut(f64, &mut [f64]), n: usize, a: f64, b: f64) -> (Vec<f64>, Vec<f64>) {
    let c = 0.5 * (a + b);
    let h = 0.5 * (b - a);
    let mut y = vec![0.0; n];
    let mut y2 = vec![0.0; n];
    f(c, &mut y);
    let mut k: Vec<f64> = y.iter().map(|v| WGK[7] * v).collect();
    let mut g: Vec<f64> = y.iter().map(|v| WG[3] * v).collect();
    for j in 0..7 {
        let x = h * XGK[j];
        f(c - x, &mut y);
        f(c + x, &mut y2);
        for i in 0..n {
            let s = y[i] + y2[i];
            k[i] += WGK[j] * s;
            if j % 2 == 1 {
                g[i] += WG[j / 2] * s;
            }
        }
    }
    let err = k.iter().zip(&g).map(|(a, b)| ((a - b) * h).abs()).collect();
    (k.iter().map(|v| v * h).collect(), err)
}

/// `∫_a^b f(x) dx` by adaptive G7/K15 (see the module docs). `breaks` inside `(a, b)` start the
/// subdivision. The integrand is never evaluated at `a` or `b`.
pub fn integrate(
    mut f: impl FnMut(f64) -> f64,
    a: f64,
    b: f64,
    breaks: &[f64],
    tol: Tolerance,
) -> Quadrature {
    integrate_many(|x, out| out[0] = f(x), 1, a, b, breaks, tol)[0]
}

/// [`integrate`] for `n` integrands evaluated together (`f(x, out)` fills `out[0..n]`): every
/// component must meet the tolerance; the interval bisected next is the one whose error is the
/// largest share of its component's target.
pub fn integrate_many(
    mut f: impl FnMut(f64, &mut [f64]),
    n: usize,
    a: f64,
    b: f64,
    breaks: &[f64],
    tol: Tolerance,
) -> Vec<Quadrature> {
    let empty = |converged| Quadrature {
        value: 0.0,
        error: 0.0,
        evaluations: 0,
        converged,
    };
    if !(a.is_finite() && b.is_finite()) || b <= a || n == 0 {
        return vec![empty(a == b); n];
    }
    let mut pts: Vec<f64> = breaks
        .iter()
        .copied()
        .filter(|x| x.is_finite() && *x > a && *x < b)
        .collect();
    pts.push(a);
    pts.push(b);
    pts.sort_by(f64::total_cmp);
    pts.dedup();
    // (a, b, values, errors)
    let mut parts: Vec<(f64, f64, Vec<f64>, Vec<f64>)> = Vec::new();
    let mut evals = 0;
    for w in pts.windows(2) {
        let (v, e) = rule(&mut f, n, w[0], w[1]);
        evals += 15;
        parts.push((w[0], w[1], v, e));
    }
    loop {
        let mut value = vec![0.0; n];
        let mut error = vec![0.0; n];
        for p in &parts {
            for i in 0..n {
                value[i] += p.2[i];
                error[i] += p.3[i];
            }
        }
        let target: Vec<f64> = value
            .iter()
            .map(|v| tol.atol.max(tol.rtol * v.abs()))
            .collect();
        let ok = (0..n).all(|i| error[i] <= target[i]);
        let finite = error.iter().all(|e| e.is_finite());
        if ok || !finite || evals + 30 > tol.max_evaluations {
            return (0..n)
                .map(|i| Quadrature {
                    value: value[i],
                    error: error[i],
                    evaluations: evals,
                    converged: error[i] <= target[i],
                })
                .collect();
        }
        let share = |p: &(f64, f64, Vec<f64>, Vec<f64>)| -> f64 {
            (0..n)
                .map(|i| p.3[i] / target[i].max(f64::MIN_POSITIVE))
                .fold(0.0, f64::max)
        };
        let (i, _) = parts.iter().enumerate().fold((0, -1.0), |best, (i, p)| {
            let s = share(p);
            if s > best.1 {
                (i, s)
            } else {
                best
            }
        });
        let (lo, hi, _, _) = parts.swap_remove(i);
        let mid = 0.5 * (lo + hi);
        if !(mid > lo && mid < hi) {
            // The interval cannot be split further in floating point: accept it.
            let (v, _) = rule(&mut f, n, lo, hi);
            evals += 15;
            parts.push((lo, hi, v, vec![0.0; n]));
            continue;
        }
        let (v1, e1) = rule(&mut f, n, lo, mid);
        let (v2, e2) = rule(&mut f, n, mid, hi);
        evals += 30;
        parts.push((lo, mid, v1, e1));
        parts.push((mid, hi, v2, e2));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polynomials_and_a_lorentzian() {
        // K15 is exact for degree ≤ 22.
        let q = integrate(
            |x| x.powi(9) - 3.0 * x * x,
            -1.0,
            2.0,
            &[],
            Tolerance::default(),
        );
        let exact = (2f64.powi(10) - 1.0) / 10.0 - (8.0 + 1.0);
        assert!((q.value - exact).abs() < 1e-12 * exact.abs(), "{q:?}");
        // ∫ ε/((x−1)² + ε²) over [0, 3] = atan(2/ε) + atan(1/ε), ε = 1e-4: a narrow peak.
        let e = 1e-4;
        let q = integrate(
            |x| e / ((x - 1.0) * (x - 1.0) + e * e),
            0.0,
            3.0,
            &[1.0],
            Tolerance::default(),
        );
        let exact = (2.0 / e).atan() + (1.0 / e).atan();
        assert!(
            q.converged && (q.value - exact).abs() < 1e-8 * exact,
            "{q:?}"
        );
        assert!((q.value - exact).abs() <= q.error.max(1e-15));
    }
}
