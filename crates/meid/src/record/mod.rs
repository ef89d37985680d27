//! Measured records: one channel of a time history in SI units, where it was measured and how
//! it was sampled; the units a test lab's files use and their conversion to SI ([`units`]).
//!
//! This is the base the readers ([`crate::io::uff`], [`crate::io::csv_records`],
//! [`crate::io::parquet`]) fill and the processing ([`crate::measure`]) takes: it imports
//! nothing of either.

pub mod units;

use serde::Serialize;

pub use units::Quantity;

use crate::{Error, Result};

/// Where a channel was measured, as the file says (UFF record 6: response entity name, node
/// and direction; direction 1/2/3 = +X/+Y/+Z, negative for −, 0 scalar).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct PointRef {
    pub entity: String,
    pub node: i64,
    pub direction: i64,
}

impl PointRef {
    /// e.g. "bed:1 +Z".
    pub fn label(&self) -> String {
        let d = match self.direction {
            0 => "",
            1 => " +X",
            2 => " +Y",
            3 => " +Z",
            -1 => " -X",
            -2 => " -Y",
            -3 => " -Z",
            4 => " +RX",
            5 => " +RY",
            6 => " +RZ",
            -4 => " -RX",
            -5 => " -RY",
            -6 => " -RZ",
            _ => " ?",
        };
        format!("{}:{}{d}", self.entity, self.node)
    }
}

/// The sampling of a record.
#[derive(Debug, Clone, PartialEq)]
pub enum Abscissa {
    /// `t_n = start_s + n·step_s`.
    Even { start_s: f64, step_s: f64 },
    /// Explicit sample times (s), strictly increasing.
    Uneven(Vec<f64>),
}

/// One measured (or simulated) channel, values in the SI unit of its quantity.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// Channel name (UFF record 1, or the CSV column without its unit).
    pub name: String,
    pub quantity: Quantity,
    /// The unit the file gave (before conversion), e.g. "g".
    pub source_unit: String,
    /// Point and direction, when the file names them.
    pub point: Option<PointRef>,
    pub abscissa: Abscissa,
    /// Samples in [`Quantity::si_unit`].
    pub values: Vec<f64>,
    /// Where it came from: "FILE, dataset 3 (line 120)" or "FILE, column 2".
    pub origin: String,
}

impl Record {
    /// An evenly sampled record in SI units (`source_unit` = the quantity's SI unit, no point):
    /// `t_n = start_s + n·step_s`, what simulated channels and synthetic test signals are.
    pub fn sampled(
        name: impl Into<String>,
        quantity: Quantity,
        start_s: f64,
        step_s: f64,
        values: Vec<f64>,
        origin: impl Into<String>,
    ) -> Self {
        Self {
            name: name.into(),
            quantity,
            source_unit: quantity.si_unit().to_string(),
            point: None,
            abscissa: Abscissa::Even { start_s, step_s },
            values,
            origin: origin.into(),
        }
    }
}

/// Largest relative deviation of an uneven abscissa's steps from their mean for the record
/// to count as evenly sampled (ASCII files print times to 6 significant digits).
pub const EVEN_TOLERANCE: f64 = 1e-3;

/// The even grid `T_0 + k·D` that sample times printed in decimal are, when one lies within the
/// precision they were printed with: `|t_k − (T_0 + k·D)| ≤ h_k` for every `k`, `h_k` half a
/// unit of the last digit `t_k` was printed with (an ASCII UFF 58 prints 6 significant digits,
/// E13.5: 51.2 kHz steps of 19.53125 µs read 19.5312 µs or 19.5313 µs, 1 µs apart near 1 s,
/// and are still one even grid). `Some((T_0, D))` when one exists, `None` otherwise (also for
/// fewer than 2 times, or `half` not one per time).
///
/// For a step `D`, the starts allowed by every sample form the interval
/// `[max_k (t_k − h_k − kD), min_k (t_k + h_k − kD)]`; its excess
/// `g(D) = max_k (t_k − h_k − kD) − min_k (t_k + h_k − kD)` is convex in `D` (a maximum of
/// linear functions less a minimum of linear functions), so the grid exists exactly when the
/// minimum of `g` over `D` is ≤ 0, found by ternary search over the steps the first and last
/// samples allow. Each `h_k` is widened by 4 ulps of `t_k` for the decimal-to-binary conversion.
pub fn even_as_printed(t: &[f64], half: &[f64]) -> Option<(f64, f64)> {
    let n = t.len();
    if n < 2 || half.len() != n || t.iter().chain(half).any(|v| !v.is_finite()) {
        return None;
    }
    let h: Vec<f64> = t
        .iter()
        .zip(half)
        .map(|(t, h)| h.abs() + 4.0 * f64::EPSILON * t.abs())
        .collect();
    let last = (n - 1) as f64;
    let d_lo = ((t[n - 1] - h[n - 1]) - (t[0] + h[0])) / last;
    let d_hi = ((t[n - 1] + h[n - 1]) - (t[0] - h[0])) / last;
    if d_hi <= 0.0 {
        return None;
    }
    // The starts every sample allows for step d: (lowest, highest).
    let starts = |d: f64| {
        t.iter().zip(&h).enumerate().fold(
            (f64::NEG_INFINITY, f64::INFINITY),
            |(lo, hi), (k, (t, h))| {
                let c = t - k as f64 * d;
                (lo.max(c - h), hi.min(c + h))
            },
        )
    };
    let excess = |d: f64| {
        let (lo, hi) = starts(d);
        lo - hi
    };
    let (mut a, mut b) = (d_lo.max(0.0), d_hi);
    for _ in 0..200 {
        if excess(a) <= 0.0 || b - a <= 1e-15 * b {
            break;
        }
        let m1 = a + (b - a) / 3.0;
        let m2 = b - (b - a) / 3.0;
        if excess(m1) <= excess(m2) {
            b = m2;
        } else {
            a = m1;
        }
    }
    let d = [a, 0.5 * (a + b), b]
        .into_iter()
        .min_by(|x, y| excess(*x).total_cmp(&excess(*y)))?;
    let (lo, hi) = starts(d);
    (d > 0.0 && lo <= hi).then_some((0.5 * (lo + hi), d))
}

impl Record {
    /// The SI unit of the values.
    pub fn unit(&self) -> &'static str {
        self.quantity.si_unit()
    }

    /// Sample `n`'s time (s).
    pub fn time_at(&self, n: usize) -> f64 {
        match &self.abscissa {
            Abscissa::Even { start_s, step_s } => start_s + n as f64 * step_s,
            Abscissa::Uneven(t) => t.get(n).copied().unwrap_or(f64::NAN),
        }
    }

    /// `(start_s, step_s)` of an evenly sampled record. An uneven abscissa whose steps differ
    /// from their mean by at most [`EVEN_TOLERANCE`] (relative) counts as even with the mean
    /// step `(t_last − t_0)/(N − 1)`; otherwise the error says to resample.
    pub fn even(&self) -> Result<(f64, f64)> {
        match &self.abscissa {
            Abscissa::Even { start_s, step_s } => {
                if step_s.is_finite() && *step_s > 0.0 && start_s.is_finite() {
                    Ok((*start_s, *step_s))
                } else {
                    Err(Error::Input {
                        location: self.origin.clone(),
                        message: format!(
                            "channel '{}': the abscissa increment must be a positive finite time step, got {step_s} s",
                            self.name
                        ),
                    })
                }
            }
            Abscissa::Uneven(t) => {
                let n = t.len();
                if n < 2 {
                    return Err(Error::Input {
                        location: self.origin.clone(),
                        message: format!("channel '{}': needs at least 2 samples", self.name),
                    });
                }
                let mean = (t[n - 1] - t[0]) / (n - 1) as f64;
                let worst = t
                    .windows(2)
                    .map(|w| ((w[1] - w[0]) - mean).abs())
                    .fold(0.0, f64::max);
                if mean > 0.0 && mean.is_finite() && worst <= EVEN_TOLERANCE * mean {
                    Ok((t[0], mean))
                } else {
                    Err(Error::Input {
                        location: self.origin.clone(),
                        message: format!(
                            "channel '{}': the sample times are uneven (steps differ from their mean {mean:e} s by up to {worst:e} s); spectra need even sampling: resample the record",
                            self.name
                        ),
                    })
                }
            }
        }
    }

    /// Sample rate `1/step` (Hz) of an evenly sampled record ([`Self::even`]).
    pub fn sample_rate_hz(&self) -> Result<f64> {
        Ok(1.0 / self.even()?.1)
    }
}
