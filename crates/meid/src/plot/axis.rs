//! Tick positions and labels: a logarithmic axis labelled at 1-2-5 values, "nice" linear
//! ticks (steps of 1, 2 or 5 × 10ᵏ) and the tick-label format shared by every chart.

use std::ops::Range;

use plotters::coord::ranged1d::{
    KeyPointHint, KeyPointWeight, NoDefaultFormatting, Ranged, ValueFormatter,
};

/// Tick label: plain decimals for moderate magnitudes (at most 4 decimals, trailing zeros
/// removed), scientific notation otherwise (`1.5e3`).
pub fn fmt_tick(v: &f64) -> String {
    let v = *v;
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s == "-0" {
            "0".into()
        } else {
            s.into()
        }
    } else {
        let s = format!("{v:.2e}");
        // 1.50e3 -> 1.5e3
        match s.split_once('e') {
            Some((m, e)) => {
                let m = m.trim_end_matches('0').trim_end_matches('.');
                format!("{m}e{e}")
            }
            None => s,
        }
    }
}

/// Values `m · 10ᵏ` (for each mantissa `m` in `mantissas`) inside `[lo, hi]`, increasing.
fn decade_multiples(lo: f64, hi: f64, mantissas: &[f64]) -> Vec<f64> {
    let mut out = Vec::new();
    if !(lo > 0.0 && hi >= lo && hi.is_finite()) {
        return out;
    }
    let (d0, d1) = (lo.log10().floor() as i32 - 1, hi.log10().ceil() as i32 + 1);
    let tol = 1e-9;
    for d in d0..=d1 {
        let p = 10f64.powi(d);
        for m in mantissas {
            // Round to 12 significant digits so that 3e-3 prints as 0.003.
            let v = round_sig(m * p);
            if v >= lo * (1.0 - tol) && v <= hi * (1.0 + tol) {
                out.push(v);
            }
        }
    }
    out
}

fn round_sig(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let e = v.abs().log10().floor() as i32;
    let s = 10f64.powi(11 - e);
    (v * s).round() / s
}

/// Labelled ticks of a logarithmic axis over `[lo, hi]` (`0 < lo < hi`), at most `max`
/// of them: the 1-2-5 values (1, 2, 5, 10, 20, 50, …) when there are between 3 and `max`;
/// on a range shorter than about a decade every integer multiple 1…9 × 10ᵏ; on a long
/// range the decades only, thinned to every n-th decade when they are still too many;
/// on a range holding fewer than two such values, [`nice_ticks`].
pub fn log_ticks(lo: f64, hi: f64, max: usize) -> Vec<f64> {
    let max = max.max(2);
    let one_two_five = decade_multiples(lo, hi, &[1.0, 2.0, 5.0]);
    if (3..=max).contains(&one_two_five.len()) {
        return one_two_five;
    }
    if one_two_five.len() < 3 {
        let all = decade_multiples(lo, hi, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
        if all.len() >= 2 && all.len() <= max {
            return all;
        }
        if one_two_five.len() >= 2 {
            return one_two_five;
        }
        return nice_ticks(lo, hi, max.min(6));
    }
    let decades = decade_multiples(lo, hi, &[1.0]);
    if decades.len() <= max {
        return decades;
    }
    let step = decades.len().div_ceil(max);
    decades.into_iter().step_by(step).collect()
}

/// Unlabelled grid values of a logarithmic axis: 1…9 × 10ᵏ when at most `max`, else the
/// decades.
fn log_grid(lo: f64, hi: f64, max: usize) -> Vec<f64> {
    let all = decade_multiples(lo, hi, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
    if all.len() <= max {
        all
    } else {
        decade_multiples(lo, hi, &[1.0])
    }
}

/// "Nice" linear ticks in `[lo, hi]`: multiples of a step `s = {1, 2, 5} × 10ᵏ` chosen as
/// the smallest such step giving at most `max` ticks (at least 2 when the range allows).
pub fn nice_ticks(lo: f64, hi: f64, max: usize) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
        return if lo.is_finite() { vec![lo] } else { Vec::new() };
    }
    let max = max.max(2);
    let raw = (hi - lo) / max as f64;
    let mut k = raw.log10().floor() as i32;
    loop {
        for m in [1.0, 2.0, 5.0] {
            let s = m * 10f64.powi(k);
            let first = (lo / s - 1e-9).ceil();
            let last = (hi / s + 1e-9).floor();
            let n = (last - first + 1.0).max(0.0) as usize;
            if n <= max {
                return (0..n)
                    .map(|i| round_sig((first + i as f64) * s))
                    .map(|v| if v.abs() < s * 1e-9 { 0.0 } else { v })
                    .collect();
            }
        }
        k += 1;
    }
}

/// At most `n` contour levels at nice values strictly inside `(lo, hi)`: the multiples of
/// a 1-2-5 step ([`nice_ticks`] with `n + 2` ticks at most, the ends excluded; so between
/// about `n/2` and `n` levels).
pub fn nice_levels(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
        return Vec::new();
    }
    let mut l: Vec<f64> = nice_ticks(lo, hi, n + 2)
        .into_iter()
        .filter(|v| *v > lo && *v < hi)
        .collect();
    l.truncate(n);
    l
}

/// A logarithmic axis over `[lo, hi]` (`0 < lo < hi`) whose labelled points are
/// [`log_ticks`] and whose light grid lines are 1…9 × 10ᵏ. Position is linear in log10:
/// `p = p₀ + (log v − log lo)/(log hi − log lo) · (p₁ − p₀)`.
#[derive(Debug, Clone)]
pub(crate) struct LogAxis {
    lo: f64,
    hi: f64,
}

impl LogAxis {
    pub(crate) fn new(r: Range<f64>) -> Self {
        Self {
            lo: r.start,
            hi: r.end,
        }
    }
}

impl Ranged for LogAxis {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let (a, b) = (self.lo.log10(), self.hi.log10());
        let t = if *value > 0.0 {
            (value.log10() - a) / (b - a)
        } else {
            -10.0
        };
        let p = limit.0 as f64 + t * (limit.1 - limit.0) as f64;
        p.round().clamp(-1e7, 1e7) as i32
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        match hint.weight() {
            KeyPointWeight::Bold => log_ticks(self.lo, self.hi, hint.max_num_points()),
            KeyPointWeight::Any => log_grid(self.lo, self.hi, hint.max_num_points()),
        }
    }

    fn range(&self) -> Range<f64> {
        self.lo..self.hi
    }
}

impl ValueFormatter<f64> for LogAxis {
    fn format(value: &f64) -> String {
        fmt_tick(value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks_are_one_two_five() {
        assert_eq!(
            log_ticks(8.0, 350.0, 10),
            vec![10.0, 20.0, 50.0, 100.0, 200.0]
        );
        assert_eq!(
            log_ticks(0.9, 1100.0, 10),
            vec![1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0]
        );
        // Too many 1-2-5 values: decades.
        assert_eq!(
            log_ticks(1.0, 1e5, 10),
            vec![1.0, 10.0, 100.0, 1000.0, 1e4, 1e5]
        );
        // Narrow: 1…9 multiples.
        assert_eq!(
            log_ticks(18.0, 85.0, 10),
            vec![20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0]
        );
        // No multiple at all: linear nice ticks.
        let t = log_ticks(3.1, 3.9, 10);
        assert!(
            t.len() >= 2 && t.iter().all(|v| (3.1..=3.9).contains(v)),
            "{t:?}"
        );
        // Decades thinned.
        assert_eq!(log_ticks(1.0, 1e12, 5), vec![1.0, 1e3, 1e6, 1e9, 1e12]);
        // Small values print cleanly.
        assert_eq!(
            log_ticks(1e-3, 1e-2, 10)
                .iter()
                .map(fmt_tick)
                .collect::<Vec<_>>(),
            vec!["0.001", "0.002", "0.005", "0.01"]
        );
    }

    #[test]
    fn nice_ticks_use_one_two_five_steps() {
        assert_eq!(
            nice_ticks(0.073, 0.375, 7),
            vec![0.1, 0.15, 0.2, 0.25, 0.3, 0.35]
        );
        assert_eq!(nice_ticks(-3.0, 7.0, 6), vec![-2.0, 0.0, 2.0, 4.0, 6.0]);
        assert_eq!(nice_levels(0.0, 1.0, 4), vec![0.2, 0.4, 0.6, 0.8]);
        assert!(nice_ticks(1.0, 1.0, 5) == vec![1.0]);
    }
}
