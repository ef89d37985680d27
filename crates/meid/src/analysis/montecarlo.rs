//! Monte Carlo over uncertain model inputs: e.g. the slider-bed contact stiffness K_s varies
//! with the workpiece, `contact.slider_bed.stiffness=lognormal(4.3e7,0.2)`.
//!
//! # Formulation
//!
//! Each input is a model field (the `--set` path) with a distribution:
//!
//! * `normal(μ, σ)`: `x = μ + σ z`, `z ~ N(0, 1)` by Box-Muller.
//! * `lognormal(m, c)`: **arithmetic mean `m` and coefficient of variation `c`**:
//!   `σ_ln² = ln(1 + c²)`, `μ_ln = ln m − σ_ln²/2`, `x = exp(μ_ln + σ_ln z)`, so `E[x] = m`
//!   and `std[x] = c m` exactly (Johnson, Kotz & Balakrishnan, *Continuous Univariate
//!   Distributions* vol. 1, ch. 14).
//! * `uniform(a, b)`: `x = a + (b − a) u`, `u ~ U[0, 1)`.
//!
//! Sample `i` is the model with the drawn values set as `--set` overrides would
//! ([`Model::with_fields`]), written through the inputs' typed setters compiled once per study
//! ([`crate::model::setter`]: no TOML per sample; an input they do not cover takes the TOML
//! route), and simulated ([`super::simulate`], case as specified, the model's
//! `[simulation]`). The structure is solved once: a sample reuses the base model's modes
//! unless its inputs change the structural part of the model
//! ([`crate::model::StructureKey`]), so a Monte Carlo over contact stiffness on an FE model
//! costs what it costs on a lumped model of as many modes. Metrics are the
//! summary's energy ratio E_p+/E_s−, peak bed acceleration at B, peak floor force and peak
//! contact forces. Statistics over the successful samples: mean, sample standard deviation
//! (`n − 1`), and the 5th, 50th and 95th percentiles by linear interpolation between order
//! statistics (Hyndman & Fan 1996, definition 7). Failed samples are kept with their error;
//! when every sample fails, the run is that error (the first sample's, with how many failed).
//!
//! Inputs must be real-valued model fields: a whole-number field (a count such as
//! `elements_per_side`) or a non-numeric one is refused before any sample runs. A drawn
//! `simulation.*` field (duration, sample_rate, rtol, atol) takes effect per sample, like
//! every other field (the sample's model is re-read with it).
//!
//! **Reproducibility.** The generator is SplitMix64 (Steele, Lea & Flood, OOPSLA 2014),
//! hand-written (a dozen lines; no new dependency). Sample `i` draws from its own stream
//! seeded with `mix(seed ⊕ mix(i + 1))`: a counter-based key, so its inputs depend only on
//! `(seed, i)`, never on which samples were drawn before; samples run in parallel (rayon) and
//! are collected in sample order: the result is identical for any thread count and any split
//! of the study into shards ([`MonteCarlo::run_range`], `meid montecarlo --shard K/N`).

use rayon::prelude::*;
use serde::Serialize;

use super::energy::{simulate, Summary};
use super::sweep::{field_kind, FieldKind};
use crate::model::{Case, CompiledFields, FieldValue, Model, StructureCache};
use crate::{Error, Result};

pub use crate::rng::{mix64, SplitMix64};

/// A distribution of an uncertain input.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Distribution {
    Normal {
        mean: f64,
        std: f64,
    },
    /// Arithmetic mean and coefficient of variation (see the module docs).
    LogNormal {
        mean: f64,
        cov: f64,
    },
    Uniform {
        low: f64,
        high: f64,
    },
}

impl Distribution {
    /// Parses `normal(μ,σ)`, `lognormal(mean,cov)` or `uniform(a,b)`.
    pub fn parse(text: &str) -> Result<Self> {
        let t = text.trim();
        let bad = || {
            Error::invalid(
                "distribution",
                format!(
                    "'{t}': expected normal(mean,std), lognormal(mean,cov) or uniform(low,high)"
                ),
            )
        };
        let open = t.find('(').ok_or_else(bad)?;
        if !t.ends_with(')') {
            return Err(bad());
        }
        let name = t[..open].trim().to_ascii_lowercase();
        let args: Vec<f64> = t[open + 1..t.len() - 1]
            .split(',')
            .map(|a| a.trim().parse::<f64>().map_err(|_| bad()))
            .collect::<Result<_>>()?;
        if args.len() != 2 {
            return Err(bad());
        }
        let (a, b) = (args[0], args[1]);
        let (d, names) = match name.as_str() {
            "normal" => (Distribution::Normal { mean: a, std: b }, ["mean", "std"]),
            "lognormal" => (Distribution::LogNormal { mean: a, cov: b }, ["mean", "cov"]),
            "uniform" => (Distribution::Uniform { low: a, high: b }, ["low", "high"]),
            _ => return Err(bad()),
        };
        if let Some(i) = args.iter().position(|v| !v.is_finite()) {
            return Err(Error::invalid(
                "distribution",
                format!(
                    "'{t}': {} must be a finite number (got {})",
                    names[i], args[i]
                ),
            ));
        }
        d.validate()?;
        Ok(d)
    }

    /// Checks the parameters: σ ≥ 0, lognormal mean > 0 and cov ≥ 0, low ≤ high, and every
    /// value [`Distribution::sample`] can draw finite. The standard normal deviate z of
    /// [`SplitMix64::next_normal`] (Box-Muller on 53-bit uniforms) has |z| ≤ √(106 ln 2) < 9, so
    /// a normal draws within μ ± 9σ; a lognormal draws exp(μ_ln + s z) with s² = ln(1 + cov²)
    /// and μ_ln = ln(mean) − s²/2, at most exp(μ_ln + 9 s); a uniform spans high − low.
    fn validate(&self) -> Result<()> {
        const Z_MAX: f64 = 9.0;
        let (ok, finite) = match *self {
            Distribution::Normal { mean, std } => {
                (std >= 0.0, (mean.abs() + Z_MAX * std).is_finite())
            }
            Distribution::LogNormal { mean, cov } => {
                let s2 = (1.0 + cov * cov).ln();
                let largest = mean.ln() - 0.5 * s2 + Z_MAX * s2.sqrt();
                (
                    mean > 0.0 && cov >= 0.0,
                    (mean * cov).is_finite() && largest.exp().is_finite(),
                )
            }
            Distribution::Uniform { low, high } => (low <= high, (high - low).is_finite()),
        };
        if !ok {
            return Err(Error::invalid(
                "distribution",
                format!(
                    "{self:?}: needs std ≥ 0, lognormal mean > 0 and cov ≥ 0, uniform low ≤ high"
                ),
            ));
        }
        if !finite {
            return Err(Error::invalid(
                "distribution",
                format!(
                    "{self:?}: draws values beyond the range of numbers (±1.8e308): needs |mean| + 9 std, lognormal mean·cov and exp(ln(mean) − s²/2 + 9 s) with s² = ln(1 + cov²), uniform high − low finite"
                ),
            ));
        }
        Ok(())
    }

    /// Draws one value.
    pub fn sample(&self, rng: &mut SplitMix64) -> f64 {
        match *self {
            Distribution::Normal { mean, std } => mean + std * rng.next_normal(),
            Distribution::LogNormal { mean, cov } => {
                let s2 = (1.0 + cov * cov).ln();
                let mu = mean.ln() - 0.5 * s2;
                (mu + s2.sqrt() * rng.next_normal()).exp()
            }
            Distribution::Uniform { low, high } => low + (high - low) * rng.next_f64(),
        }
    }

    /// Analytic mean.
    pub fn mean(&self) -> f64 {
        match *self {
            Distribution::Normal { mean, .. } | Distribution::LogNormal { mean, .. } => mean,
            // Halves first: (low + high)/2 overflows near ±1.8e308.
            Distribution::Uniform { low, high } => 0.5 * low + 0.5 * high,
        }
    }

    /// Analytic standard deviation.
    pub fn std(&self) -> f64 {
        match *self {
            Distribution::Normal { std, .. } => std,
            Distribution::LogNormal { mean, cov } => mean * cov,
            Distribution::Uniform { low, high } => (high - low) / 12f64.sqrt(),
        }
    }
}

/// An uncertain input: a model field path and its distribution.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Uncertain {
    pub path: String,
    pub distribution: Distribution,
}

impl Uncertain {
    /// Parses `PATH=DIST(a,b)`, e.g. `contact.slider_bed.stiffness=lognormal(4.3e7,0.2)`.
    pub fn parse(text: &str) -> Result<Self> {
        let (p, d) = text.split_once('=').ok_or_else(|| {
            Error::invalid(
                "uncertain input",
                format!("'{text}': expected PATH=DIST(a,b), e.g. contact.slider_bed.stiffness=lognormal(4.3e7,0.2)"),
            )
        })?;
        Ok(Self {
            path: p.trim().to_string(),
            distribution: Distribution::parse(d)?,
        })
    }
}

/// The metrics recorded per sample, in table order.
pub const METRICS: [&str; 5] = [
    "energy_ratio",
    "peak_bed_acceleration_m_per_s2",
    "peak_floor_force_n",
    "peak_contact_force_slider_bed_n",
    "peak_contact_force_bed_damper_n",
];

fn metrics_of(s: &Summary) -> [f64; 5] {
    [
        s.energy_ratio.unwrap_or(f64::NAN),
        s.peak_bed_acceleration_m_per_s2,
        s.peak_floor_force_n,
        s.peak_contact_force_slider_bed_n,
        s.peak_contact_force_bed_damper_n,
    ]
}

/// One sample: its inputs and metrics (in [`METRICS`] order), or its error.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Sample {
    pub index: usize,
    pub inputs: Vec<f64>,
    pub metrics: Option<[f64; 5]>,
    pub error: Option<String>,
}

/// Statistics of one quantity over the successful samples. Every value is an estimate from
/// the `count` samples; the `*_ci95` intervals say how precise (95 % confidence; `null` in
/// JSON where the samples are too few to bound it).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Stats {
    pub name: String,
    pub count: usize,
    pub mean: f64,
    pub std: f64,
    pub p5: f64,
    pub p50: f64,
    pub p95: f64,
    pub min: f64,
    pub max: f64,
    /// Standard error of the mean, `std/√count`.
    pub std_error: f64,
    /// 95 % confidence interval of the mean, `mean ± t(0.975, count − 1) std/√count`
    /// (Student's t; exact for normal data, asymptotically for any finite variance).
    pub mean_ci95: (f64, f64),
    /// 95 % confidence intervals of P5, P50 and P95: order statistics `[x_(l), x_(u)]` with
    /// binomial coverage `P(l ≤ B < u) ≥ 0.95`, `B ~ Bin(count, p)`, equal tails ≤ 2.5 %
    /// ([`quantile_ci_ranks`]); distribution-free.
    pub p5_ci95: (Option<f64>, Option<f64>),
    pub p50_ci95: (Option<f64>, Option<f64>),
    pub p95_ci95: (Option<f64>, Option<f64>),
}

/// Percentile `p` in [0, 1] of sorted data, Hyndman & Fan definition 7.
pub fn percentile_sorted(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let h = (sorted.len() - 1) as f64 * p.clamp(0.0, 1.0);
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(sorted.len() - 1);
    sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
}

/// `P(|T| ≤ t)` for Student's t with `nu ≥ 1` degrees of freedom, by the exact finite sums of
/// Abramowitz & Stegun 26.7.3-4 (θ = atan(t/√ν), c = cos θ): ν odd
/// `(2/π)(θ + sin θ cos θ Σ_{j=0}^{(ν−3)/2} a_j c^{2j})`, `a_j = a_{j−1}·2j/(2j+1)`; ν even
/// `sin θ Σ_{j=0}^{(ν−2)/2} b_j c^{2j}`, `b_j = b_{j−1}(2j−1)/(2j)`.
pub fn student_t_central(t: f64, nu: usize) -> f64 {
    let theta = (t.abs() / (nu as f64).sqrt()).atan();
    let (s, c) = theta.sin_cos();
    let c2 = c * c;
    if nu % 2 == 1 {
        let mut sum = 0.0;
        if nu > 1 {
            let (mut term, mut j) = (1.0, 0usize);
            loop {
                sum += term;
                j += 1;
                if 2 * j + 3 > nu {
                    break;
                }
                term *= c2 * (2 * j) as f64 / (2 * j + 1) as f64;
            }
        }
        std::f64::consts::FRAC_2_PI * (theta + s * c * sum)
    } else {
        let (mut sum, mut term, mut j) = (0.0, 1.0, 0usize);
        loop {
            sum += term;
            j += 1;
            if 2 * j + 2 > nu {
                break;
            }
            term *= c2 * (2 * j - 1) as f64 / (2 * j) as f64;
        }
        s * sum
    }
}

/// The two-sided 97.5 % point of Student's t, `t(0.975, ν)`: bisection on
/// [`student_t_central`] = 0.95 for ν ≤ 1000, the Cornish-Fisher expansion of A&S 26.7.5
/// (terms to ν⁻⁴, error below 1e-12 there) above.
pub fn student_t_975(nu: usize) -> f64 {
    const Z: f64 = 1.959_963_984_540_054;
    if nu == 0 {
        return f64::NAN;
    }
    if nu > 1000 {
        let v = nu as f64;
        let z = Z;
        let g1 = (z.powi(3) + z) / 4.0;
        let g2 = (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / 96.0;
        let g3 = (3.0 * z.powi(7) + 19.0 * z.powi(5) + 17.0 * z.powi(3) - 15.0 * z) / 384.0;
        let g4 = (79.0 * z.powi(9) + 776.0 * z.powi(7) + 1482.0 * z.powi(5)
            - 1920.0 * z.powi(3)
            - 945.0 * z)
            / 92160.0;
        return z + g1 / v + g2 / (v * v) + g3 / v.powi(3) + g4 / v.powi(4);
    }
    let (mut lo, mut hi) = (0.0_f64, 2.0_f64);
    while student_t_central(hi, nu) < 0.95 {
        lo = hi;
        hi *= 2.0;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if student_t_central(mid, nu) < 0.95 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The 1-based ranks `(l, u)` of the order statistics bounding the `p`-quantile of `n`
/// samples with 95 % confidence: with `B ~ Bin(n, p)` the number of samples below the
/// quantile, `l` is the largest rank with `P(B ≤ l − 1) ≤ 0.025` and `u` the smallest with
/// `P(B ≤ u − 1) ≥ 0.975`, so `P(x_(l) ≤ ξ_p ≤ x_(u)) ≥ 0.95` for any continuous
/// distribution (David & Nagaraja, *Order Statistics*, 3rd ed., §7.1). `None` for a side
/// that `n` samples cannot bound (e.g. the lower side of P5 below 72 samples). The binomial
/// CDF is summed exactly (log-space recurrence) for n ≤ 100 000; above, the normal
/// approximation `n p ∓ 1.96 √(n p (1 − p))` (continuity-corrected) is used.
pub fn quantile_ci_ranks(n: usize, p: f64) -> (Option<usize>, Option<usize>) {
    if n == 0 || !(p > 0.0 && p < 1.0) {
        return (None, None);
    }
    if n > 100_000 {
        let (nf, z) = (n as f64, 1.959_963_984_540_054);
        let sd = (nf * p * (1.0 - p)).sqrt();
        let l = (nf * p - z * sd + 0.5).floor();
        let u = (nf * p + z * sd + 0.5).ceil() + 1.0;
        let l = (l >= 1.0).then_some(l as usize);
        let u = (u <= nf).then_some(u as usize);
        return (l, u);
    }
    // ln P(B = k), k = 0..n, by ln P(B = k + 1) = ln P(B = k) + ln((n − k)/(k + 1)) + ln(p/(1 − p)).
    let odds = (p / (1.0 - p)).ln();
    let mut lp = n as f64 * (1.0 - p).ln();
    let (mut cdf, mut l, mut u) = (0.0_f64, None, None);
    for k in 0..=n {
        // cdf = P(B ≤ k − 1) here: rank k + 1 bounds from below when it is ≤ 0.025.
        if k >= 1 && cdf <= 0.025 {
            l = Some(k);
        }
        cdf += lp.exp();
        // Now cdf = P(B ≤ k): rank u = k + 1 bounds from above once it reaches 0.975.
        if cdf >= 0.975 {
            u = (k < n).then_some(k + 1);
            break;
        }
        if k < n {
            lp += ((n - k) as f64 / (k + 1) as f64).ln() + odds;
        }
    }
    (l, u)
}

/// The 95 % interval of the `p`-quantile of sorted data ([`quantile_ci_ranks`]); `None` on a
/// side the samples cannot bound.
fn quantile_ci(sorted: &[f64], p: f64) -> (Option<f64>, Option<f64>) {
    let (l, u) = quantile_ci_ranks(sorted.len(), p);
    (l.map(|r| sorted[r - 1]), u.map(|r| sorted[r - 1]))
}

/// Mean, std (n − 1), P5, P50, P95, min, max of the finite values, with the standard error
/// and 95 % confidence intervals of the mean and the percentiles (see [`Stats`]).
pub fn stats(name: &str, values: &[f64]) -> Stats {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let mean = if n > 0 {
        v.iter().sum::<f64>() / n as f64
    } else {
        f64::NAN
    };
    let std = if n > 1 {
        (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
    } else {
        f64::NAN
    };
    let std_error = std / (n as f64).sqrt();
    let half = if n > 1 {
        student_t_975(n - 1) * std_error
    } else {
        f64::NAN
    };
    Stats {
        name: name.to_string(),
        count: n,
        mean,
        std,
        p5: percentile_sorted(&v, 0.05),
        p50: percentile_sorted(&v, 0.50),
        p95: percentile_sorted(&v, 0.95),
        min: v.first().copied().unwrap_or(f64::NAN),
        max: v.last().copied().unwrap_or(f64::NAN),
        std_error,
        mean_ci95: (mean - half, mean + half),
        p5_ci95: quantile_ci(&v, 0.05),
        p50_ci95: quantile_ci(&v, 0.50),
        p95_ci95: quantile_ci(&v, 0.95),
    }
}

/// A Monte Carlo study you build and run.
#[derive(Debug, Clone)]
pub struct MonteCarlo {
    pub model: Model,
    pub inputs: Vec<Uncertain>,
    pub samples: usize,
    pub seed: u64,
}

/// The finished study.
#[derive(Debug, Clone, Serialize)]
pub struct MonteCarloResult {
    pub seed: u64,
    pub inputs: Vec<Uncertain>,
    pub samples: Vec<Sample>,
    /// Statistics of each input (as drawn) then of each metric.
    pub input_stats: Vec<Stats>,
    pub metric_stats: Vec<Stats>,
    pub failed: usize,
}

impl MonteCarlo {
    /// The values of sample `i` (depends only on the seed, `i` and the inputs).
    pub fn draw(&self, i: usize) -> Vec<f64> {
        let mut rng = SplitMix64::for_sample(self.seed, i as u64);
        self.inputs
            .iter()
            .map(|u| u.distribution.sample(&mut rng))
            .collect()
    }

    /// The inputs' paths compiled on the base model ([`crate::model::setter`]).
    pub fn compile_inputs(&self) -> CompiledFields {
        let paths: Vec<&str> = self.inputs.iter().map(|u| u.path.as_str()).collect();
        self.model.compile_fields(&paths)
    }

    /// Simulates sample values `values`: the base model with the inputs set through the typed
    /// setters `fields` ([`Model::with_values`]: the model `--set PATH=VALUE` with each value
    /// written `{:e}` gives, [`Model::with_fields`]; the structure is the base's, or
    /// `cache`'s, unless an input changes the structural part of the model).
    fn run_sample(
        &self,
        values: &[f64],
        fields: &CompiledFields,
        cache: &StructureCache,
    ) -> Result<[f64; 5]> {
        let typed: Vec<FieldValue> = values.iter().map(|v| FieldValue::Real(*v)).collect();
        let m = self.model.with_values(fields, &typed, Some(cache))?;
        let sys = m.impact_system(Case::AsSpecified)?;
        let run = simulate(&sys, &m.options(), false)?;
        Ok(metrics_of(&run.summary))
    }

    /// Sample `i`: its drawn inputs and its metrics or error.
    pub fn sample(&self, i: usize, cache: &StructureCache) -> Sample {
        self.sample_with(i, &self.compile_inputs(), cache)
    }

    /// [`MonteCarlo::sample`] with the inputs compiled ([`MonteCarlo::compile_inputs`]).
    pub fn sample_with(&self, i: usize, fields: &CompiledFields, cache: &StructureCache) -> Sample {
        let inputs = self.draw(i);
        match self.run_sample(&inputs, fields, cache) {
            Ok(m) => Sample {
                index: i,
                inputs,
                metrics: Some(m),
                error: None,
            },
            Err(e) => Sample {
                index: i,
                inputs,
                metrics: None,
                error: Some(e.to_string()),
            },
        }
    }

    /// Memory one sample takes in the study and its outputs (bytes): the result record with
    /// its drawn inputs, a copy of each value for the statistics (sorted), and its row of
    /// `samples.csv` (≤ 24 characters per value).
    pub fn bytes_per_sample(&self) -> f64 {
        let values = (self.inputs.len() + METRICS.len()) as f64;
        std::mem::size_of::<(Sample, Option<Error>)>() as f64
            + 8.0 * self.inputs.len() as f64
            + 16.0
            + 24.0 * values
    }

    /// A fingerprint of everything that determines the samples (model, the content of the
    /// files it refers to, inputs, seed, count):
    /// FNV-1a 64 over their text; shards of one study have the same.
    pub fn fingerprint(&self) -> String {
        let text = format!(
            "{}|{:?}|{}|{}|{}{}",
            serde_json::to_string(&self.model.spec).unwrap_or_default(),
            self.inputs,
            self.seed,
            self.samples,
            self.model.source.text,
            self.model.files_fingerprint()
        );
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in text.bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        format!("{h:016x}")
    }

    /// Checks the study's inputs and that `count` samples fit in memory.
    pub fn check(&self, count: usize) -> Result<()> {
        if self.samples == 0 {
            return Err(Error::invalid("samples", "needs at least one sample"));
        }
        if self.inputs.is_empty() {
            return Err(Error::invalid(
                "inputs",
                "give at least one uncertain input PATH=DIST(a,b)",
            ));
        }
        for (i, u) in self.inputs.iter().enumerate() {
            if self.inputs[..i].iter().any(|w| w.path == u.path) {
                return Err(Error::Input {
                    location: format!("--vary {}", u.path),
                    message: format!("{} is given twice; give each uncertain input once", u.path),
                });
            }
            let kind = field_kind(&self.model, &u.path).map_err(|e| match e {
                Error::Input { message, .. } => Error::Input {
                    location: format!("--vary {}", u.path),
                    message,
                },
                other => other,
            })?;
            if kind == FieldKind::Whole {
                return Err(Error::Input {
                    location: format!("--vary {}", u.path),
                    message: format!(
                        "{} takes a whole number (a count or an index); a distribution draws real values",
                        u.path
                    ),
                });
            }
        }
        crate::limits::check_memory(
            &format!(
                "{} Monte Carlo samples ({} B each)",
                count,
                self.bytes_per_sample()
            ),
            count as f64 * self.bytes_per_sample(),
            "samples",
            "the number of samples (--samples)",
        )
    }

    /// Runs every sample in parallel on the current rayon pool; results in sample order.
    pub fn run(&self) -> Result<MonteCarloResult> {
        self.run_with_progress(&|_, _| {})
    }

    /// [`MonteCarlo::run`] calling `progress(done, total)` after each sample (from the worker
    /// threads).
    pub fn run_with_progress(
        &self,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<MonteCarloResult> {
        self.check(self.samples)?;
        let samples = self.run_range(0..self.samples, progress);
        self.finish(samples)
    }

    /// The samples `range` (a shard of the study: sample `i` depends only on the seed and
    /// `i`, so any split gives the same samples), in parallel, in sample order;
    /// `progress(done, range length)` after each.
    pub fn run_range(
        &self,
        range: std::ops::Range<usize>,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Vec<Sample> {
        let cache = StructureCache::new();
        let fields = self.compile_inputs();
        let total = range.len();
        let done = std::sync::atomic::AtomicUsize::new(0);
        range
            .into_par_iter()
            .map(|i| {
                let s = self.sample_with(i, &fields, &cache);
                let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                progress(d, total);
                s
            })
            .collect()
    }

    /// The result of all the study's samples (in sample order, e.g. the shards' samples put
    /// together): statistics, failures; when every sample failed, that failure as the error
    /// (sample 0's, computed again for its kind, noting how many failed).
    pub fn finish(&self, samples: Vec<Sample>) -> Result<MonteCarloResult> {
        if samples.len() != self.samples || samples.iter().enumerate().any(|(i, s)| s.index != i) {
            return Err(Error::numerical(
                "montecarlo",
                format!(
                    "the samples are not the study's {} samples in order (got {})",
                    self.samples,
                    samples.len()
                ),
            ));
        }
        let n = samples.len();
        if samples.iter().all(|s| s.error.is_some()) {
            let first = self
                .run_sample(
                    &self.draw(0),
                    &self.compile_inputs(),
                    &StructureCache::new(),
                )
                .err();
            let tag = format!("all {n} samples failed; this is sample 0's error");
            return Err(match first {
                Some(Error::Input { location, message }) => Error::Input {
                    location,
                    message: format!("{message} ({tag})"),
                },
                Some(Error::InvalidValue { field, message }) => Error::InvalidValue {
                    field,
                    message: format!("{message} ({tag})"),
                },
                Some(Error::Numerical { context, message }) => Error::Numerical {
                    context,
                    message: format!("{message} ({tag})"),
                },
                Some(e) => e,
                None => Error::numerical(
                    "montecarlo",
                    format!("{tag}: {}", samples[0].error.as_deref().unwrap_or("failed")),
                ),
            });
        }
        let input_stats = self
            .inputs
            .iter()
            .enumerate()
            .map(|(k, u)| {
                let v: Vec<f64> = samples.iter().map(|s| s.inputs[k]).collect();
                stats(&u.path, &v)
            })
            .collect();
        let metric_stats = METRICS
            .iter()
            .enumerate()
            .map(|(k, name)| {
                let v: Vec<f64> = samples
                    .iter()
                    .filter_map(|s| s.metrics.map(|m| m[k]))
                    .collect();
                stats(name, &v)
            })
            .collect();
        let failed = samples.iter().filter(|s| s.error.is_some()).count();
        Ok(MonteCarloResult {
            seed: self.seed,
            inputs: self.inputs.clone(),
            samples,
            input_stats,
            metric_stats,
            failed,
        })
    }
}

/// Samples as exact rows (a shard of a study, `meid montecarlo --shard`): CSV with `sample`,
/// the inputs, the metrics (Rust's shortest round-trip form `{:e}`, which reads back to the
/// same bits, `NaN` included; empty when the sample failed) and the error.
pub fn samples_exact_csv(samples: &[Sample], inputs: usize) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let err = |e: csv::Error| Error::numerical("csv", e.to_string());
    let mut head = vec!["sample".to_string()];
    head.extend((0..inputs).map(|k| format!("input{k}")));
    head.extend(METRICS.iter().map(|m| m.to_string()));
    head.push("error".into());
    w.write_record(&head).map_err(err)?;
    for s in samples {
        let mut row = vec![s.index.to_string()];
        row.extend(s.inputs.iter().map(|v| format!("{v:e}")));
        match &s.metrics {
            Some(m) => row.extend(m.iter().map(|v| format!("{v:e}"))),
            None => row.extend(METRICS.iter().map(|_| String::new())),
        }
        row.push(s.error.clone().unwrap_or_default());
        w.write_record(&row).map_err(err)?;
    }
    w.into_inner()
        .map_err(|e| Error::numerical("csv", e.to_string()))
}

/// Reads [`samples_exact_csv`] back (`inputs` inputs per sample); `what` names the file in
/// errors. A non-finite input or an infinite metric is refused (a run writes neither).
pub fn read_samples_exact_csv(bytes: &[u8], inputs: usize, what: &str) -> Result<Vec<Sample>> {
    let bad = |line: u64, m: String| Error::Input {
        location: format!("{what}:{line}"),
        message: m,
    };
    let mut r = csv::ReaderBuilder::new().from_reader(bytes);
    let width = 1 + inputs + METRICS.len() + 1;
    let mut out = Vec::new();
    for rec in r.records() {
        let rec = rec.map_err(|e| bad(e.position().map_or(0, |p| p.line()), e.to_string()))?;
        let line = rec.position().map_or(0, |p| p.line());
        if rec.len() != width {
            return Err(bad(line, format!("{} fields, expected {width}", rec.len())));
        }
        let num = |k: usize| -> Result<f64> {
            rec[k]
                .parse::<f64>()
                .map_err(|_| bad(line, format!("`{}` is not a number", &rec[k])))
        };
        let index: usize = rec[0]
            .parse()
            .map_err(|_| bad(line, format!("`{}` is not a sample index", &rec[0])))?;
        let values = (1..=inputs).map(num).collect::<Result<Vec<f64>>>()?;
        let metrics = if rec[1 + inputs].is_empty() {
            None
        } else {
            let mut m = [0.0; 5];
            for (k, x) in m.iter_mut().enumerate() {
                *x = num(1 + inputs + k)?;
            }
            Some(m)
        };
        // A run draws finite inputs and writes no infinite metric (NaN where undefined).
        if let Some(v) = values.iter().find(|v| !v.is_finite()) {
            return Err(bad(
                line,
                format!(
                    "sample {index}: an input is {}, which a run never draws",
                    crate::num(*v)
                ),
            ));
        }
        if let Some(v) = metrics.iter().flatten().find(|v| v.is_infinite()) {
            return Err(bad(
                line,
                format!(
                    "sample {index}: a metric is {}, which a run never writes",
                    crate::num(*v)
                ),
            ));
        }
        let e = &rec[width - 1];
        out.push(Sample {
            index,
            inputs: values,
            metrics,
            error: (!e.is_empty()).then(|| e.to_string()),
        });
    }
    Ok(out)
}

impl MonteCarloResult {
    /// The values of metric `name` over the successful samples, in sample order.
    pub fn metric(&self, name: &str) -> Result<Vec<f64>> {
        let k = METRICS.iter().position(|m| *m == name).ok_or_else(|| {
            Error::invalid(
                "metric",
                format!("unknown metric '{name}'; valid: {}", METRICS.join(", ")),
            )
        })?;
        Ok(self
            .samples
            .iter()
            .filter_map(|s| s.metrics.map(|m| m[k]))
            .filter(|v| v.is_finite())
            .collect())
    }

    /// Samples as CSV: index, inputs, metrics, error.
    pub fn samples_csv(&self) -> Result<Vec<u8>> {
        let mut w = csv::Writer::from_writer(Vec::new());
        let err = |e: csv::Error| Error::numerical("csv", e.to_string());
        let mut head = vec!["sample".to_string()];
        head.extend(self.inputs.iter().map(|u| u.path.clone()));
        head.extend(METRICS.iter().map(|m| m.to_string()));
        head.push("error".into());
        w.write_record(&head).map_err(err)?;
        for s in &self.samples {
            let mut row = vec![s.index.to_string()];
            row.extend(s.inputs.iter().map(|v| format!("{v:.12e}")));
            match &s.metrics {
                Some(m) => row.extend(m.iter().map(|v| format!("{v:.12e}"))),
                None => row.extend(METRICS.iter().map(|_| String::new())),
            }
            row.push(s.error.clone().unwrap_or_default());
            w.write_record(&row).map_err(err)?;
        }
        w.into_inner()
            .map_err(|e| Error::numerical("csv", e.to_string()))
    }
}

/// A histogram of `values` with `bins` equal bins between min and max, as a closed step
/// outline `(x, y)` (counts) ready for an area plot.
pub fn histogram_outline(values: &[f64], bins: usize) -> (Vec<f64>, Vec<f64>) {
    let v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() || bins == 0 {
        return (Vec::new(), Vec::new());
    }
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let mut hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if hi <= lo {
        hi = lo + lo.abs().max(1.0) * 1e-6;
    }
    let width = (hi - lo) / bins as f64;
    let mut counts = vec![0usize; bins];
    for x in &v {
        let k = (((x - lo) / width) as usize).min(bins - 1);
        counts[k] += 1;
    }
    let mut xs = vec![lo];
    let mut ys = vec![0.0];
    for (k, c) in counts.iter().enumerate() {
        let a = lo + k as f64 * width;
        xs.push(a);
        ys.push(*c as f64);
        xs.push(a + width);
        ys.push(*c as f64);
    }
    xs.push(hi);
    ys.push(0.0);
    (xs, ys)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A non-finite parameter is named (before: the generic "expected normal(mean,std), …").
    #[test]
    fn a_non_finite_parameter_is_named() {
        for (text, want) in [
            ("normal(nan,5)", "mean must be a finite number (got NaN)"),
            ("normal(3,inf)", "std must be a finite number (got inf)"),
            (
                "lognormal(-inf,0.1)",
                "mean must be a finite number (got -inf)",
            ),
            ("uniform(3,nan)", "high must be a finite number (got NaN)"),
        ] {
            let e = Distribution::parse(text).expect_err(text).to_string();
            assert!(e.contains(want), "{text}: {e}");
        }
        assert!(Distribution::parse("weibull(nan,1)")
            .expect_err("unknown")
            .to_string()
            .contains("expected normal(mean,std)"));
        assert!(Distribution::parse("normal(1,2)").is_ok());
    }

    /// t(0.975, ν) from statistical tables (Fisher & Yates; R `qt(0.975, nu)`): 12.706205,
    /// 4.302653, 3.182446, 2.262157, 2.042272, 1.983972, 1.962339, 1.960201; the exact sums
    /// (ν ≤ 1000) and the Cornish-Fisher branch (above) to 1e-6.
    #[test]
    fn student_t_points_match_the_tables() {
        for (nu, t) in [
            (1, 12.706_205),
            (2, 4.302_653),
            (3, 3.182_446),
            (9, 2.262_157),
            (30, 2.042_272),
            (100, 1.983_972),
            (1000, 1.962_339),
            (10_000, 1.960_201),
        ] {
            let got = student_t_975(nu);
            assert!((got - t).abs() < 1e-6, "nu {nu}: {got} vs {t}");
        }
        // The two branches meet: ν = 1000 by the sums and by the expansion agree to 1e-12.
        let v = 1000.0_f64;
        let z = 1.959_963_984_540_054_f64;
        let cf = z
            + (z.powi(3) + z) / (4.0 * v)
            + (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / (96.0 * v * v)
            + (3.0 * z.powi(7) + 19.0 * z.powi(5) + 17.0 * z.powi(3) - 15.0 * z)
                / (384.0 * v.powi(3));
        assert!((student_t_975(1000) - cf).abs() < 1e-10);
        // ν = 1: the Cauchy distribution, P(|T| ≤ t) = (2/π) atan t.
        assert!((student_t_975(1) - (0.475 * std::f64::consts::PI).tan()).abs() < 1e-10);
    }

    /// The order-statistic ranks against a direct binomial sum: n = 100, p = 0.5 gives the
    /// textbook (40, 61) (coverage 0.9648); P5 of 59 samples cannot be bounded below
    /// (0.95^59 = 0.0485 > 0.025), of 72 it can (0.95^72 = 0.0249).
    #[test]
    fn quantile_ranks_cover_95_percent() {
        assert_eq!(quantile_ci_ranks(100, 0.5), (Some(40), Some(61)));
        assert_eq!(quantile_ci_ranks(59, 0.05).0, None);
        assert_eq!(quantile_ci_ranks(72, 0.05).0, Some(1));
        // Coverage by an independent sum of binomial terms (lgamma-free: products).
        for (n, p) in [
            (20usize, 0.5),
            (200, 0.05),
            (200, 0.95),
            (1000, 0.5),
            (5000, 0.95),
        ] {
            let (l, u) = quantile_ci_ranks(n, p);
            let (l, u) = (l.unwrap_or(0), u.unwrap_or(n + 1));
            let mut pmf = vec![0.0_f64; n + 1];
            // P(B = k) built from the mode outward in linear space, then normalised.
            let mode = ((n as f64 + 1.0) * p).floor() as usize;
            pmf[mode.min(n)] = 1.0;
            for k in (mode.min(n) + 1)..=n {
                pmf[k] = pmf[k - 1] * ((n - k + 1) as f64 / k as f64) * (p / (1.0 - p));
            }
            for k in (0..mode.min(n)).rev() {
                pmf[k] = pmf[k + 1] * ((k + 1) as f64 / (n - k) as f64) * ((1.0 - p) / p);
            }
            let total: f64 = pmf.iter().sum();
            // x_(l) ≤ ξ_p ≤ x_(u) ⇔ l ≤ B ≤ u − 1 (rank 0: no lower bound, n + 1: no upper).
            let cover: f64 = (l..u.min(n + 1)).map(|k| pmf[k]).sum::<f64>() / total;
            assert!(cover >= 0.95, "n {n} p {p}: ranks {l}..{u} cover {cover}");
            // Equal tails: P(B ≤ l − 1) ≤ 2.5 % < P(B ≤ l); P(B ≤ u − 2) < 97.5 % ≤ P(B ≤ u − 1).
            if l >= 1 {
                let below: f64 = pmf[..l].iter().sum::<f64>() / total;
                assert!(
                    below <= 0.025 + 1e-12 && below + pmf[l] / total > 0.025,
                    "n {n} p {p}"
                );
            }
            if u <= n {
                let upto: f64 = pmf[..u].iter().sum::<f64>() / total;
                assert!(
                    upto >= 0.975 - 1e-12 && upto - pmf[u - 1] / total < 0.975,
                    "n {n} p {p}"
                );
            }
        }
    }
}
