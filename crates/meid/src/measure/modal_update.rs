//! Model updating from identified modes (`meid calibrate --modal`): model values fitted to
//! the identified frequencies and shapes by bounded least squares.
//!
//! # Residuals
//!
//! The identified modes are correlated with the model's at the start ([`super::correlate`]:
//! the same point mapping, signs and pairing rule); the pairs `(i, j)` found there are kept
//! through the fit (model mode `j` by its number in ascending frequency: a fit that makes two
//! model modes cross over would need a new correlation). For each pair,
//!
//! ```text
//! r_f = f_j(p)/f_i − 1,        r_MAC = √w (1 − MAC(φ_i, ψ_j(p)))
//! ```
//!
//! (`f_i` identified, `f_j(p)` the model's frequency with the values `p`, `φ_i` the identified
//! shape, `ψ_j(p)` the model's at the mapped points with their signs), stacked into `r(p)`; the
//! cost is `S = Σ r²`. The frequency residual is relative (a 1 % error weighs the same at 6 Hz
//! and at 300 Hz); the MAC weight `w` (`--mac-weight`, default 1) sets how much shape
//! disagreement counts beside it: `1 − MAC` of 0.01 costs as much as a 1 % frequency error at
//! `w = 1`, and `w = 0` fits the frequencies alone.
//!
//! # Sensitivities, solver, intervals
//!
//! As [`super::calibrate`]: each evaluation builds the model with the values set through its
//! typed setters ([`crate::model::Model::with_values`], the structure solved anew when a
//! structural value changes); the Jacobian is by central differences in the internal
//! coordinates (`θ = ln p` for a positive lower bound, step `10⁻⁴ (1 + |θ|)`, one-sided at a
//! bound), the same projected Levenberg-Marquardt solver
//! ([`super::calibrate::levenberg_marquardt`]), and the linearised 95 % intervals
//! `p̂ ± (t_{0.975, m−n} √Cov_ii + |δ_i|)`, `Cov = s² (J_pᵀJ_p)⁻¹`, `s² = S/(m − n)`, `δ` the
//! Gauss-Newton step left. With as many residuals as values (`m = n`) there is no interval.

use serde::Serialize;

use super::calibrate::{
    estimate, spd_inverse, student_t_975, BoundedFit, Convergence, Estimate, FitParameter, Settings,
};
use super::correlate::{
    correlate, IdentifiedModes, Mapping, ModelModes, Settings as CorrelateSettings,
};
use crate::identify::mac_real;
use crate::model::{CompiledFields, FieldValue, Model, StructureCache};
use crate::{Error, Result};

/// A paired model mode's frequency (Hz) and MAC with its identified mode.
type FrequencyMac = (f64, f64);

/// A model-updating problem (module docs).
pub struct ModalProblem<'a> {
    model: &'a Model,
    params: Vec<FitParameter>,
    fields: CompiledFields,
    cache: StructureCache,
    ident: &'a IdentifiedModes,
    /// Model point coordinates for the mapping (`None`: the display line).
    coordinates: Option<std::collections::BTreeMap<String, [f64; 3]>>,
    mapping: Mapping,
    correlate_settings: CorrelateSettings,
    /// `(identified, model)` 0-based pairs, fixed at the start.
    pairs: Vec<(usize, usize)>,
    mac_weight: f64,
    settings: Settings,
    before: super::correlate::Correlation,
}

/// One paired mode before and after the fit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PairUpdate {
    pub identified_mode: usize,
    pub model_mode: usize,
    pub identified_frequency_hz: f64,
    pub model_frequency_before_hz: f64,
    pub model_frequency_after_hz: f64,
    pub error_before_percent: f64,
    pub error_after_percent: f64,
    pub mac_before: f64,
    pub mac_after: f64,
}

/// The result of [`calibrate_modal`].
#[derive(Debug, Clone, Serialize)]
pub struct ModalCalibration {
    pub parameters: Vec<Estimate>,
    pub mac_weight: f64,
    pub residuals: usize,
    pub rms_residual_before: f64,
    pub rms_residual_after: f64,
    pub sigma: f64,
    pub iterations: usize,
    pub evaluations: usize,
    pub convergence: Convergence,
    pub converged: bool,
    pub pairs: Vec<PairUpdate>,
    /// The correlation with the model's values, and with the fitted ones.
    pub before: super::correlate::Correlation,
    pub after: super::correlate::Correlation,
    pub warnings: Vec<String>,
}

impl<'a> ModalProblem<'a> {
    /// The problem: correlates once to fix the pairs; no pair is an error.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        model: &'a Model,
        params: Vec<FitParameter>,
        ident: &'a IdentifiedModes,
        coordinates: Option<std::collections::BTreeMap<String, [f64; 3]>>,
        mapping: Mapping,
        correlate_settings: CorrelateSettings,
        mac_weight: f64,
        settings: Settings,
    ) -> Result<Self> {
        if params.is_empty() {
            return Err(Error::invalid("--fit", "no path to fit"));
        }
        if !(mac_weight.is_finite() && mac_weight >= 0.0) {
            return Err(Error::invalid(
                "--mac-weight",
                format!("{mac_weight}: give a finite weight ≥ 0 (0: frequencies alone)"),
            ));
        }
        let mm = ModelModes::new(model, coordinates.clone());
        let before = correlate(ident, &mm, &mapping, &correlate_settings)?;
        if before.pairs.is_empty() {
            return Err(Error::Input {
                location: ident.file.clone(),
                message: format!(
                    "no identified mode pairs with a model mode at MAC ≥ {}: nothing to fit (run meid correlate to see the MAC matrix)",
                    correlate_settings.min_mac
                ),
            });
        }
        let pairs = before
            .pairs
            .iter()
            .map(|p| (p.identified_mode - 1, p.model_mode - 1))
            .collect();
        let paths: Vec<&str> = params.iter().map(|q| q.path.as_str()).collect();
        let fields = model.compile_fields(&paths);
        Ok(ModalProblem {
            model,
            params,
            fields,
            cache: StructureCache::new(),
            ident,
            coordinates,
            mapping,
            correlate_settings,
            pairs,
            mac_weight,
            settings,
            before,
        })
    }

    /// The fitted parameters.
    pub fn parameters(&self) -> &[FitParameter] {
        &self.params
    }

    /// The model with `values` set.
    pub fn model_with(&self, values: &[f64]) -> Result<Model> {
        let typed: Vec<FieldValue> = values.iter().map(|v| FieldValue::Real(*v)).collect();
        self.model
            .with_values(&self.fields, &typed, Some(&self.cache))
    }

    /// Frequencies and MACs of the pairs, and the residuals, at `values`.
    fn evaluate(&self, values: &[f64]) -> Result<(Vec<FrequencyMac>, Vec<f64>)> {
        let m = self.model_with(values)?;
        let mm = ModelModes::new(&m, self.coordinates.clone());
        let points = &self.before.points;
        let mut per = Vec::new();
        let mut r = Vec::new();
        for &(i, j) in &self.pairs {
            let f = mm.frequencies_hz.get(j).copied().ok_or_else(|| {
                Error::numerical(
                    "calibrate --modal",
                    format!("the model with {values:?} retains no mode {}", j + 1),
                )
            })?;
            let im = &self.ident.modes[i];
            let a: Vec<f64> = points
                .iter()
                .map(|p| {
                    let k = self.ident.points.iter().position(|q| q.label == p.measured);
                    k.and_then(|k| im.shape.get(k)).copied().unwrap_or(0.0)
                })
                .collect();
            let b: Vec<f64> = points
                .iter()
                .map(|p| {
                    p.sign
                        * mm.points
                            .get(&p.model_point)
                            .and_then(|v| v.get(j))
                            .copied()
                            .unwrap_or(0.0)
                })
                .collect();
            let mac = mac_real(&a, &b);
            r.push(f / im.frequency_hz - 1.0);
            if self.mac_weight > 0.0 {
                r.push(self.mac_weight.sqrt() * (1.0 - mac));
            }
            per.push((f, mac));
        }
        if let Some(bad) = r.iter().position(|x| !x.is_finite()) {
            return Err(Error::numerical(
                "calibrate --modal",
                format!("residual {bad} is not finite at {values:?}"),
            ));
        }
        Ok((per, r))
    }

    /// The residual vector `r(p)` (module docs).
    pub fn residuals(&self, values: &[f64]) -> Result<Vec<f64>> {
        Ok(self.evaluate(values)?.1)
    }
}

/// Runs the model updating (module docs).
pub fn calibrate_modal(problem: &ModalProblem<'_>) -> Result<ModalCalibration> {
    let params = &problem.params;
    let n = params.len();
    let fit = BoundedFit::run(
        params,
        &problem.settings,
        |v| problem.evaluate(v),
        |v| problem.residuals(v),
    )?;
    let BoundedFit {
        ref values,
        ref out,
        ref before,
        ref after,
        ref r1,
        identifiability: ref ident,
        ref free,
        jtj: ref a,
        dof,
        s2,
        ..
    } = fit;
    let m = r1.len();
    let c = spd_inverse(a);
    let t = student_t_975(dof);
    let steps = fit.solver_steps(c.as_deref());
    let (rms_before, rms_after) = fit.rms_residuals();
    let mut estimates = Vec::new();
    for (i, p) in params.iter().enumerate() {
        let at_bound = fit.at_bound(i);
        let k = free.iter().position(|&f| f == i);
        let (se, step) = match (&c, k) {
            (Some(c), Some(k)) if !at_bound => ((s2 * c[k][k]).sqrt(), steps[i]),
            _ => (f64::NAN, f64::NAN),
        };
        estimates.push(estimate(p, values[i], se, step, t, at_bound, ident[i]));
    }
    let fitted = problem.model_with(values)?;
    let after_corr = correlate(
        problem.ident,
        &ModelModes::new(&fitted, problem.coordinates.clone()),
        &problem.mapping,
        &problem.correlate_settings,
    )?;
    let mut warnings = Vec::new();
    if !out.reason.converged() {
        warnings.push(format!("the fit {}", out.reason.describe()));
    }
    if dof == 0 {
        warnings.push(format!(
            "{m} residual(s) for {n} value(s): no degree of freedom left, so no interval"
        ));
    }
    let pairs = problem
        .pairs
        .iter()
        .zip(before.iter().zip(after))
        .map(|(&(i, j), (b, a))| {
            let fi = problem.ident.modes[i].frequency_hz;
            PairUpdate {
                identified_mode: i + 1,
                model_mode: j + 1,
                identified_frequency_hz: fi,
                model_frequency_before_hz: b.0,
                model_frequency_after_hz: a.0,
                error_before_percent: 100.0 * (fi - b.0) / b.0,
                error_after_percent: 100.0 * (fi - a.0) / a.0,
                mac_before: b.1,
                mac_after: a.1,
            }
        })
        .collect();
    Ok(ModalCalibration {
        parameters: estimates,
        mac_weight: problem.mac_weight,
        residuals: m,
        rms_residual_before: rms_before,
        rms_residual_after: rms_after,
        sigma: s2.sqrt(),
        iterations: out.iterations,
        evaluations: out.evaluations + 2,
        convergence: out.reason,
        converged: out.reason.converged(),
        pairs,
        before: problem.before.clone(),
        after: after_corr,
        warnings,
    })
}

impl ModalCalibration {
    /// The fitted values in the parameters' order.
    pub fn values(&self) -> Vec<f64> {
        self.parameters.iter().map(|e| e.value).collect()
    }

    /// The report as text: the values with their intervals, the before/after correlation table
    /// (the warnings are for the caller to show).
    pub fn to_text(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{} residual(s) (relative frequency errors{}), rms {:.4e} -> {:.4e}; {} ({} iterations)",
            self.residuals,
            if self.mac_weight > 0.0 {
                format!(", √{} (1 − MAC)", self.mac_weight)
            } else {
                String::new()
            },
            self.rms_residual_before,
            self.rms_residual_after,
            self.convergence.describe(),
            self.iterations
        );
        for e in &self.parameters {
            let _ = writeln!(
                s,
                "  {} = {:.6e} (start {:.6e}; 95 % interval {:.6e} .. {:.6e}; {})",
                e.path,
                e.value,
                e.start,
                e.ci95_low,
                e.ci95_high,
                if e.at_bound {
                    "at a bound"
                } else {
                    e.identifiability.describe()
                }
            );
        }
        let _ = writeln!(
            s,
            "\n{:>4} {:>5} {:>12} {:>12} {:>9} {:>7} {:>12} {:>9} {:>7}",
            "test",
            "model",
            "f_test (Hz)",
            "before (Hz)",
            "err (%)",
            "MAC",
            "after (Hz)",
            "err (%)",
            "MAC"
        );
        for p in &self.pairs {
            let _ = writeln!(
                s,
                "{:>4} {:>5} {:>12.4} {:>12.4} {:>9.3} {:>7.4} {:>12.4} {:>9.3} {:>7.4}",
                p.identified_mode,
                p.model_mode,
                p.identified_frequency_hz,
                p.model_frequency_before_hz,
                p.error_before_percent,
                p.mac_before,
                p.model_frequency_after_hz,
                p.error_after_percent,
                p.mac_after
            );
        }
        s
    }
}
