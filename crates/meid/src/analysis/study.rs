//! Damper optimisation studies (issue 4, `meid optimize`): choose damper or contact
//! parameters that minimise a metric of one blow, and compare with the paper's rule w_d = w_s.
//!
//! Variables are the quantities of [`super::sweep`] (derived ratios `wd/ws`, `wd/w_ref`,
//! `ws/w_ref`, `md/mb`, or model field paths), resolved per point by
//! [`super::sweep::point_model`]. A variable whose bounds are both positive is searched in
//! `ln x` (stiffnesses, masses and ratios span decades; a bounded search in `ln x` spends
//! its effort evenly per decade); otherwise linearly.
//!
//! * One variable: a scan of [`SCAN_POINTS`] points evenly spaced (in the search coordinate)
//!   over the bounds, both included (in parallel; the result does not depend on the thread
//!   count), then Brent's method ([`super::optimize::brent_minimize`], Brent 1973 ch. 5) on
//!   the two scan intervals around each of the best [`GLOBAL_STARTS`] scan points lower than
//!   both their neighbours, the lowest result kept. The scan guards Brent, a local method,
//!   against the other local minima of impact metrics: the energy ratio over `md/mb` in
//!   0.1-4 on the soft-base example has its minimum 0.0059388 at 1.942, inside a basin the
//!   former 9-point scan (points 1.585 apart in ratio) missed, ending at 0.0064016 on the bound.
//! * Several (n): a global search in the box, [`super::optimize::minimize_box_global`]: a
//!   grid of `N` points per variable evenly spaced in the search coordinate, both bounds
//!   included (`Nⁿ` simulations, [`default_grid_points`]: 33 per variable for two, 16 for
//!   three; run in parallel, the result independent of the thread count), then the bounded
//!   Nelder-Mead with restarts and coordinate polish of [`super::optimize::minimize_box`]
//!   from each of the best [`GLOBAL_STARTS`] grid points lower than all their grid
//!   neighbours, the lowest result kept. A local search alone ends in the basin it starts
//!   in: the floor force over `wd/ws, md/mb` on the lumped example has about 24 basins on a
//!   161² grid, and the search from the model's point ended at 26.03 N on md/mb = 2 while
//!   24.56 N lies inside the box at ω_d/ω_s = 0.377, m_d/m_b = 1.20.
//!
//! Objectives: `energy` = E_p+/E_s− at the end of the collision (Eq. 10 over Eq. 11; the
//! run stops there); `bed-accel` = peak |a_B| (m/s²) and `floor-force` = peak floor force (N)
//! over the model's whole `simulation.duration`.
//!
//! The paper's rule (section 4.1: the best damper has w_d = w_s) is evaluated at the
//! optimum's other variables with `wd/ws = 1`.
//!
//! **At a stroke rate** ([`OptimizeStudy::with_stroke_rate`], `meid optimize --rate-bpm R`)
//! the objective is the **steady blow's** ([`super::steady`]: the periodic steady state of the
//! blow train at `R` blows/min, the mean energy ratio or the largest peak over its period), not
//! the first blow's, and a design whose damper does not touch the bed in every steady blow (or
//! whose train does not settle) is **infeasible**: it counts as `+∞` (an extreme barrier) and is
//! tallied apart from failed simulations. The first blow is still simulated for the other
//! metrics of the point.
//!
//! The free variables are searched in the order of their names (the result does not depend
//! on the order they were given in); a variable with `LO = HI` is held fixed. After the
//! search, each free variable is moved by ±[`NEIGHBOUR_STEP`] of its range in the search
//! coordinate ([`LocalCheck`]): the report says whether the optimum is a local minimum, a
//! minimum on a bound, not a minimum (a lower neighbour, then reported), or that the
//! objective is flat; and it lists the `--set` overrides that make `meid simulate` give the
//! same objective.

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;
use serde::Serialize;

use super::optimize::{
    brent_minimize, minimize_box_global, BrentOptions, GlobalOptions, NelderMeadOptions,
};
use super::sweep::{
    check_bed_mass, check_quantities, evaluate, evaluate_cached, failure_error, field_kind,
    FieldKind, PointResult, Quantity, METRICS,
};
use crate::integrate::Options;
use crate::model::{Model, StructureCache};
use crate::{Error, Result};

/// Points of the scan before Brent in one variable (the default grid for one variable).
pub const SCAN_POINTS: usize = 33;

/// Local searches after the grid, for two or more variables: from the best this many grid
/// points lower than their grid neighbours ([`super::optimize::GlobalOptions::starts`]).
pub const GLOBAL_STARTS: usize = 4;

/// The largest grid the optimiser accepts (`--grid N` with `Nⁿ` above it is refused before
/// anything runs).
pub const MAX_GRID_SIMULATIONS: usize = 1_000_000;

/// Simulations for the local searches and checks on top of the grid when no budget is given
/// ([`OptimizeStudy::budget`]).
pub const LOCAL_BUDGET: usize = 800;

/// Grid points per variable when none are given: [`SCAN_POINTS`] for one variable; for n ≥ 2
/// the largest `N ≤ 33` with `Nⁿ ≤ 4096` (33 for two variables, 1089 simulations; 16 for
/// three, 4096), at least 3.
pub fn default_grid_points(n: usize) -> usize {
    if n <= 1 {
        return SCAN_POINTS;
    }
    (3..=33)
        .rev()
        .find(|&p| super::optimize::grid_size(p, n).is_some_and(|t| t <= 4096))
        .unwrap_or(3)
}

/// The neighbour check's step ([`LocalCheck`]): a fraction of each variable's box width in
/// the search coordinate (`ln x` for a log variable), 1000 times the Brent tolerance.
pub const NEIGHBOUR_STEP: f64 = 1e-3;

/// What to minimise.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Objective {
    /// Energy left in the machine, E_p+/E_s− (1).
    Energy,
    /// Peak bed acceleration at B (m/s²).
    BedAccel,
    /// Peak force to the floor (N).
    FloorForce,
}

impl Objective {
    /// `energy`, `bed-accel` or `floor-force`.
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "energy" => Ok(Objective::Energy),
            "bed-accel" => Ok(Objective::BedAccel),
            "floor-force" => Ok(Objective::FloorForce),
            _ => Err(Error::invalid(
                "objective",
                format!("unknown objective `{s}`; valid: energy, bed-accel, floor-force"),
            )),
        }
    }

    /// The metric column it reads ([`super::sweep::METRICS`]).
    pub fn metric(self) -> &'static str {
        match self {
            Objective::Energy => "energy_ratio",
            Objective::BedAccel => "peak_bed_acceleration_m_per_s2",
            Objective::FloorForce => "peak_floor_force_n",
        }
    }
}

/// Parses a range of two numbers, `LO..HI` (the canonical form, as in `--vary NAME=A..B:N`)
/// or `LO:HI` (also accepted), as written: the caller checks the order and the domain. The one
/// parser of every range option (`optimize --bounds`, `calibrate --bounds` and `--spectrum`).
/// The error says what is wrong with the text.
pub fn parse_range(text: &str) -> std::result::Result<(f64, f64), String> {
    let (lo, hi) = match text.split_once("..") {
        Some(parts) => parts,
        None => text.split_once(':').ok_or_else(|| {
            format!("`{text}` is not a range; give LO..HI (or LO:HI), e.g. 1e7..1e8")
        })?,
    };
    let number = |t: &str| -> std::result::Result<f64, String> {
        t.trim()
            .parse()
            .map_err(|_| format!("`{}` in `{text}` is not a number", t.trim()))
    };
    Ok((number(lo)?, number(hi)?))
}

/// Parses one bound of an optimisation variable, `PATH=LO..HI` or `PATH=LO:HI`
/// (`meid optimize --bounds`, [`parse_range`]): the quantity ([`Quantity::parse`]) and
/// `(LO, HI)` as written (the study checks them).
pub fn parse_bounds(spec: &str) -> Result<(Quantity, (f64, f64))> {
    let bad = |what: String| Error::invalid("--bounds", format!("`{spec}`: {what}"));
    let (name, range) = spec
        .split_once('=')
        .ok_or_else(|| bad("expected PATH=LO..HI (or PATH=LO:HI)".into()))?;
    let (lo, hi) = parse_range(range).map_err(bad)?;
    Ok((Quantity::parse(name)?, (lo, hi)))
}

/// One variable of an optimisation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Variable {
    pub quantity: Quantity,
    pub lower: f64,
    pub upper: f64,
    /// Searched in `ln x`.
    pub log: bool,
    /// `LO = HI`: held at that value, not searched.
    pub fixed: bool,
}

/// A point next to the optimum, evaluated after the search to establish what the optimum is
/// ([`LocalCheck`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Neighbour {
    /// The variable moved (its name); the others stay at the optimum.
    pub variable: String,
    /// Its value at the neighbour.
    pub value: f64,
    /// The objective there (NaN when the run failed).
    pub objective: f64,
}

/// What the reported optimum is, as established by the neighbour check.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// Every neighbour gives a larger or equal objective and no variable sits on a bound.
    LocalMinimum,
    /// No neighbour inside the bounds is lower, but a variable sits on a bound: the objective
    /// falls towards it, and a lower value may lie beyond it.
    OnBound,
    /// A neighbour was lower: the reported optimum is that neighbour, not a verified local
    /// minimum (the search stopped short, or the objective is rough at the step's scale).
    NotAMinimum,
    /// The objective took the same value at every point evaluated: it does not depend on the
    /// variables within the bounds, and any value is as good as the one reported.
    Flat,
    /// Every variable is fixed (`LO = HI`): one point was evaluated, nothing searched.
    Fixed,
    /// The budget left no simulations for the neighbour check.
    NotChecked,
}

/// The check of the optimum by its neighbours: each free variable moved by
/// `±step_fraction` of its box width in the search coordinate (`ln x` for a log variable,
/// so the value is multiplied by `(HI/LO)^(±step_fraction)`), the others kept; a neighbour
/// outside the bounds is not evaluated (the variable is then on that bound).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LocalCheck {
    pub verdict: Verdict,
    /// The step as a fraction of each box width in the search coordinate.
    pub step_fraction: f64,
    pub neighbours: Vec<Neighbour>,
    /// Variables on a bound, `NAME (lower)` / `NAME (upper)`.
    pub at_bound: Vec<String>,
    /// The verdict in words, with the numbers that establish it.
    pub statement: String,
}

/// An optimisation study; build with [`OptimizeStudy::new`], run with [`OptimizeStudy::run`].
#[derive(Debug, Clone)]
pub struct OptimizeStudy {
    pub model: Model,
    pub variables: Vec<Variable>,
    pub objective: Objective,
    pub options: Options,
    /// m_b (kg) for `md/mb`, when given; `None`: each point's [`Model::bed_mass`].
    pub bed_mass_kg: Option<f64>,
    /// Simulation budget (grid included); `None`: [`OptimizeStudy::budget`]'s default.
    pub max_simulations: Option<usize>,
    /// Grid points per variable; `None`: [`default_grid_points`].
    pub grid_points: Option<usize>,
    /// The stroke rate (blows/min) of [`OptimizeStudy::with_stroke_rate`]; `None`: one blow.
    pub rate_bpm: Option<f64>,
}

/// The objective metrics a stroke rate replaces by the steady blow's.
const STEADY_METRICS: [&str; 3] = [
    "energy_ratio",
    "peak_bed_acceleration_m_per_s2",
    "peak_floor_force_n",
];

/// The result of [`OptimizeStudy::run`].
#[derive(Debug, Clone, Serialize)]
pub struct OptimizeReport {
    pub objective: Objective,
    pub metric: &'static str,
    pub variables: Vec<Variable>,
    /// Best values, in variable order.
    pub optimum: Vec<f64>,
    /// The objective there.
    pub objective_value: f64,
    /// Simulations run (including failed ones): the grid's, the local search's, the
    /// optimum's own run and the w_d = w_s comparison; never more than `max_simulations`.
    pub simulations: usize,
    /// The budget the search ran with ([`OptimizeStudy::budget`]).
    pub max_simulations: usize,
    /// What was searched: grid points per variable (the one-variable scan's points).
    pub grid_points_per_variable: usize,
    /// Simulations of the grid (`grid_points_per_variable`ⁿ over the n free variables).
    pub grid_simulations: usize,
    /// Local searches run from the best grid points (Brent: 1; none when all are fixed).
    pub local_searches: usize,
    /// The search in words (grid, local method, starts).
    pub method: String,
    pub failures: usize,
    pub converged: bool,
    /// w_d/w_s at the optimum.
    pub wd_over_ws_at_optimum: f64,
    /// The objective with w_d = w_s (other variables at the optimum); NaN if it failed.
    pub objective_at_wd_equal_ws: f64,
    /// The whole point at the optimum (every metric; with a stroke rate the objective metrics
    /// are the steady blow's).
    pub point: PointResult,
    /// The stroke rate the objective was taken at (blows/min); absent for one blow.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rate_bpm: Option<f64>,
    /// Designs refused because their damper does not return at the stroke rate (or their
    /// train did not settle); not in `failures`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub infeasible: Option<usize>,
    /// The optimum's steady state at the stroke rate.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steady_state: Option<super::steady::SteadyState>,
    /// What the optimum is, from a check of its neighbours ([`LocalCheck`]).
    pub local_check: LocalCheck,
    /// The model fields the optimum sets, `PATH=VALUE` (shortest round-trip numbers): `meid
    /// simulate MODEL --set …` with these (and the study's own `--set`) runs the optimum,
    /// the same objective to the last bit (a ratio is set as the stiffness or mass it
    /// derives: `wd/ws` as `contact.bed_damper.stiffness`, `md/mb` as `damper.mass`).
    pub overrides: Vec<String>,
}

/// A given bound must lie in its quantity's valid domain: a ratio (`wd/ws`, `md/mb` ...) must
/// be positive (a negative w_d/w_s would give the same stiffness m_d w_d² as its opposite); a
/// model field's bounds must each give a valid model (the model's own checks at LO and at HI,
/// e.g. a positive `damper.mass`).
fn check_bound_domain(
    model: &Model,
    q: &Quantity,
    lower: f64,
    upper: f64,
    bed_mass_kg: Option<f64>,
) -> Result<()> {
    let location = format!("--bounds {}={lower}..{upper}", q.name());
    if !matches!(q, Quantity::Field(_)) {
        if lower <= 0.0 {
            return Err(Error::Input {
                location,
                message: format!(
                    "the lower bound {lower} lies outside the domain of the ratio {}: it must be > 0",
                    q.name()
                ),
            });
        }
        return Ok(());
    }
    for (which, x) in [("lower", lower), ("upper", upper)] {
        let built = super::sweep::point_model(model, &[q], &[x], bed_mass_kg).and_then(|pm| {
            pm.model
                .impact_system(crate::model::Case::AsSpecified)
                .map(|_| ())
        });
        if let Err(e) = built {
            let why = match e {
                Error::Input { message, .. } => message,
                other => other.to_string(),
            };
            return Err(Error::Input {
                location,
                message: format!(
                    "the {which} bound {x} lies outside the valid domain of {}: {why}",
                    q.name()
                ),
            });
        }
    }
    Ok(())
}

/// The value of a numeric field path (`a.b.c`) of the model spec, if any.
fn field_value(model: &Model, path: &str) -> Option<f64> {
    let table = toml::Table::try_from(&model.spec).ok()?;
    let mut cur = toml::Value::Table(table);
    for seg in path.split('.') {
        cur = cur.as_table()?.get(seg)?.clone();
    }
    cur.as_float().or(cur.as_integer().map(|i| i as f64))
}

/// The current value of a quantity on the model (for default bounds and starts).
pub fn current_value(model: &Model, q: &Quantity, bed_mass_kg: Option<f64>) -> Option<f64> {
    let s = &model.spec;
    let w_s = (s.contact.slider_bed.stiffness / s.slider.mass).sqrt();
    let w_d = match (&s.damper, &s.contact.bed_damper) {
        (Some(d), Some(c)) => Some((c.stiffness / d.mass).sqrt()),
        _ => None,
    };
    match q {
        Quantity::WsOverWref => model.reference_omega().map(|w| w_s / w),
        Quantity::WdOverWref => Some(w_d? / model.reference_omega()?),
        Quantity::WdOverWs => w_d.map(|w| w / w_s),
        Quantity::MdOverMb => Some(s.damper.as_ref()?.mass / bed_mass_kg?),
        Quantity::Field(p) => field_value(model, p),
    }
}

impl OptimizeStudy {
    /// A study over `over` with optional bounds per variable. Default bounds: `wd/ws`
    /// 0.2..5, `md/mb` 0.05..2, other quantities a factor 5 (ratios) or 10 (fields) either
    /// side of the model's value. m_b for `md/mb` is [`Model::bed_mass`].
    pub fn new(
        model: Model,
        over: Vec<(Quantity, Option<(f64, f64)>)>,
        objective: Objective,
    ) -> Result<Self> {
        Self::with_bed_mass(model, over, objective, None)
    }

    /// [`OptimizeStudy::new`] with the bed mass m_b (kg) for `md/mb` given (`None`:
    /// [`Model::bed_mass`]). Model fields must be real numbers: a whole-number field (a count
    /// such as `elements_per_side`) cannot be searched continuously; sweep its values instead.
    pub fn with_bed_mass(
        model: Model,
        over: Vec<(Quantity, Option<(f64, f64)>)>,
        objective: Objective,
        bed_mass_kg: Option<f64>,
    ) -> Result<Self> {
        if over.is_empty() {
            return Err(Error::invalid("over", "give at least one variable"));
        }
        let bed_mass_kg = check_bed_mass(bed_mass_kg)?;
        let m_b = bed_mass_kg.or_else(|| model.bed_mass());
        let qs: Vec<&Quantity> = over.iter().map(|(q, _)| q).collect();
        check_quantities(&model, &qs, m_b)?;
        for q in &qs {
            if let Quantity::Field(p) = q {
                let kind = field_kind(&model, p).map_err(|e| match e {
                    Error::Input { message, .. } => Error::Input {
                        location: format!("--over {p}"),
                        message,
                    },
                    other => other,
                })?;
                if kind == FieldKind::Whole {
                    return Err(Error::Input {
                        location: format!("--over {p}"),
                        message: format!(
                            "{p} takes a whole number (a count or an index) and cannot be optimised continuously; sweep its values instead (meid sweep --vary {p}=LIST)"
                        ),
                    });
                }
            }
        }
        let mut variables = Vec::new();
        for (i, (q, b)) in over.iter().enumerate() {
            if over[..i].iter().any(|(p, _)| p == q) {
                return Err(Error::invalid(
                    "over",
                    format!("{} is given twice", q.name()),
                ));
            }
            let (lower, upper) = match (b, q) {
                (Some(b), _) => *b,
                (None, Quantity::WdOverWs) => (0.2, 5.0),
                (None, Quantity::MdOverMb) => (0.05, 2.0),
                (None, _) => {
                    let f = if matches!(q, Quantity::Field(_)) {
                        10.0
                    } else {
                        5.0
                    };
                    match current_value(&model, q, m_b) {
                        Some(v) if v > 0.0 && v.is_finite() => (v / f, v * f),
                        _ => {
                            return Err(Error::invalid(
                                "bounds",
                                format!(
                                    "no default bounds for {}: give --bounds {}=LO..HI",
                                    q.name(),
                                    q.name()
                                ),
                            ))
                        }
                    }
                }
            };
            if !(lower.is_finite() && upper.is_finite() && lower <= upper) {
                return Err(Error::invalid(
                    "bounds",
                    format!(
                        "{}: needs finite LO < HI (or LO = HI to hold it fixed), got {lower}..{upper}",
                        q.name()
                    ),
                ));
            }
            if b.is_some() {
                check_bound_domain(&model, q, lower, upper, bed_mass_kg)?;
            }
            variables.push(Variable {
                quantity: q.clone(),
                lower,
                upper,
                log: lower > 0.0,
                fixed: lower == upper,
            });
        }
        let mut options = model.options();
        options.stop_at_collision_end = objective == Objective::Energy;
        Ok(OptimizeStudy {
            model,
            variables,
            objective,
            options,
            bed_mass_kg,
            max_simulations: None,
            grid_points: None,
            rate_bpm: None,
        })
    }

    /// The study at a stroke rate (module docs): the objective on the steady blow at
    /// `rate_bpm` blows/min, with the constraint that the damper returns.
    pub fn with_stroke_rate(mut self, rate_bpm: f64) -> Result<Self> {
        super::blows::blow_interval_s(rate_bpm).map_err(|e| match e {
            Error::InvalidValue { message, .. } => Error::Input {
                location: format!("--rate-bpm {rate_bpm}"),
                message,
            },
            other => other,
        })?;
        // The steady state needs the whole blow, not just the collision.
        self.options = self.model.options();
        self.rate_bpm = Some(rate_bpm);
        Ok(self)
    }

    /// The steady state at the stroke rate of the design `x` (`qs = x`).
    fn steady_of(
        &self,
        rate_bpm: f64,
        qs: &[&Quantity],
        x: &[f64],
        cache: Option<&StructureCache>,
    ) -> Result<super::steady::SteadyState> {
        let pm = super::sweep::point_model_cached(&self.model, qs, x, self.bed_mass_kg, cache)?;
        let sys = pm.model.impact_system(crate::model::Case::AsSpecified)?;
        let so = super::steady::SteadyOptions {
            rate_bpm,
            ..Default::default()
        };
        super::steady::steady_state(&sys, &pm.model.options(), &so)
    }

    /// With a stroke rate: `r` (the point's first-blow result) with its objective metrics
    /// replaced by the steady blow's, or NaN and the reason in `r.error` when the design is
    /// infeasible (then `true`: module docs). Without one, `r` as it is.
    fn at_stroke_rate(
        &self,
        qs: &[&Quantity],
        x: &[f64],
        mut r: PointResult,
        cache: Option<&StructureCache>,
    ) -> (PointResult, bool) {
        let Some(rate) = self.rate_bpm else {
            return (r, false);
        };
        if r.error.is_some() {
            return (r, false);
        }
        let set = |r: &mut PointResult, values: [f64; 3]| {
            for (name, v) in STEADY_METRICS.iter().zip(values) {
                if let Some(i) = METRICS.iter().position(|m| m == name) {
                    if let Some(cell) = r.metrics.get_mut(i) {
                        *cell = Some(v);
                    }
                }
            }
        };
        match self.steady_of(rate, qs, x, cache) {
            Err(e) => {
                set(&mut r, [f64::NAN; 3]);
                r.error = Some(format!("the steady state at {rate} blows/min: {e}"));
                (r, false)
            }
            Ok(st) if !st.damper_returns() => {
                set(&mut r, [f64::NAN; 3]);
                r.error = Some(if st.converged {
                    format!(
                        "infeasible: at {rate} blows/min the damper does not return (gap {:.3e} m at a strike of the {} steady state)",
                        st.damper_gap_at_strike_m.unwrap_or(f64::NAN),
                        st.regime.name()
                    )
                } else {
                    format!(
                        "infeasible: at {rate} blows/min the blow train does not settle ({}, residual {:.2e})",
                        st.regime.name(),
                        st.residual
                    )
                });
                (r, true)
            }
            Ok(st) => {
                set(
                    &mut r,
                    [
                        st.energy_ratio,
                        st.peak_bed_acceleration_m_per_s2,
                        st.peak_floor_force_n,
                    ],
                );
                (r, false)
            }
        }
    }

    /// The free variables (not fixed by `LO = HI`) in the order the search takes them: by
    /// name, so that the search, and so the optimum, does not depend on the order in which
    /// the variables were given (`--over a,b` or `--over b,a`).
    fn search_order(&self) -> Vec<usize> {
        let mut free: Vec<usize> = (0..self.variables.len())
            .filter(|&k| !self.variables[k].fixed)
            .collect();
        free.sort_by_key(|&k| self.variables[k].quantity.name());
        free
    }

    /// The fewest simulations [`OptimizeStudy::run`] can work with: for one free variable the
    /// scan ([`SCAN_POINTS`] points by default) and one Brent step, for n free variables one simplex (n + 1
    /// points), none when every variable is fixed; plus, always, the optimum's own run and
    /// the w_d = w_s comparison. The neighbour check ([`LocalCheck`], 2n more) runs when the
    /// budget allows it on top of this minimum.
    pub fn min_simulations(&self) -> usize {
        let n = self.search_order().len();
        let search = match n {
            0 => 0,
            1 => self.grid() + 1,
            _ => self.grid_total().saturating_add(n + 1),
        };
        search.saturating_add(2)
    }

    /// Grid points per variable: the given ones or [`default_grid_points`].
    pub fn grid(&self) -> usize {
        self.grid_points
            .unwrap_or_else(|| default_grid_points(self.search_order().len()))
    }

    /// Simulations of the grid: `grid()ⁿ` for n ≥ 2 free variables (saturating), `grid()`
    /// for one, 0 for none.
    pub fn grid_total(&self) -> usize {
        match self.search_order().len() {
            0 => 0,
            1 => self.grid(),
            n => super::optimize::grid_size(self.grid(), n).unwrap_or(usize::MAX),
        }
    }

    /// The simulation budget: `max_simulations`, or by default the grid (the scan for one
    /// variable) plus [`LOCAL_BUDGET`].
    pub fn budget(&self) -> usize {
        self.max_simulations
            .unwrap_or_else(|| self.grid_total().saturating_add(LOCAL_BUDGET))
    }

    fn value_to_search(&self, k: usize, x: f64) -> f64 {
        if self.variables[k].log {
            x.ln()
        } else {
            x
        }
    }

    /// The variable's value at search coordinate `u`; a bound's own coordinate gives the bound
    /// exactly (`exp(ln 4)` is 3.9999999999999996, which an optimum on the bound 4 printed).
    fn search_to_value(&self, k: usize, u: f64) -> f64 {
        let v = &self.variables[k];
        if u == self.value_to_search(k, v.upper) {
            return v.upper;
        }
        if u == self.value_to_search(k, v.lower) {
            return v.lower;
        }
        let x = if v.log { u.exp() } else { u };
        x.clamp(v.lower, v.upper)
    }

    /// Simulates a point given in the variables' own units.
    pub fn evaluate(&self, x: &[f64]) -> PointResult {
        let qs: Vec<&Quantity> = self.variables.iter().map(|v| &v.quantity).collect();
        let r = evaluate(&self.model, &qs, x, self.bed_mass_kg, &self.options, 0);
        self.at_stroke_rate(&qs, x, r, None).0
    }

    /// The error of the failed point `x` (with its kind, see [`failure_error`]).
    fn failure(&self, x: &[f64], note: &str, which: &str) -> Error {
        let qs: Vec<&Quantity> = self.variables.iter().map(|v| &v.quantity).collect();
        let p = self.evaluate(x);
        failure_error(
            &self.model,
            &qs,
            x,
            self.bed_mass_kg,
            p.error.as_deref().unwrap_or("objective undefined"),
            note,
            which,
        )
    }

    /// The model fields the point `x` (with its result `point`) sets, `PATH=VALUE`, in
    /// variable order, each path once ([`OptimizeReport::overrides`]).
    fn overrides(&self, x: &[f64], point: &PointResult) -> Vec<String> {
        let mut out: Vec<(String, f64)> = Vec::new();
        let mut put = |path: &str, v: f64| {
            if let Some(e) = out.iter_mut().find(|(p, _)| p == path) {
                e.1 = v;
            } else {
                out.push((path.to_string(), v));
            }
        };
        let derived = |i: usize| point.derived.get(i).copied().unwrap_or(f64::NAN);
        for (v, &xk) in self.variables.iter().zip(x) {
            match &v.quantity {
                Quantity::Field(p) => put(p, xk),
                Quantity::WsOverWref => put("contact.slider_bed.stiffness", derived(0)),
                Quantity::WdOverWs | Quantity::WdOverWref => {
                    put("contact.bed_damper.stiffness", derived(1))
                }
                Quantity::MdOverMb => {
                    put("damper.mass", derived(2));
                    put("contact.bed_damper.stiffness", derived(1));
                }
            }
        }
        // A ratio derives its field from the point's other fields: the field's final value
        // is the point's own (e.g. `damper.mass` with `wd/ws` gives K_d = m_d ω_d²).
        for (p, v) in out.iter_mut() {
            match p.as_str() {
                "contact.slider_bed.stiffness" => *v = derived(0),
                "contact.bed_damper.stiffness" => *v = derived(1),
                "damper.mass" => *v = derived(2),
                "slider.mass" => *v = derived(3),
                _ => {}
            }
        }
        out.into_iter().map(|(p, v)| format!("{p}={v:e}")).collect()
    }

    /// Runs the search (see the module docs).
    pub fn run(&self) -> Result<OptimizeReport> {
        self.run_with_progress(&|_, _| {})
    }

    /// [`OptimizeStudy::run`] calling `progress(simulations, max_simulations)` after each
    /// simulation (the budget is the most the search can take; it may stop earlier).
    pub fn run_with_progress(
        &self,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<OptimizeReport> {
        let budget = self.budget();
        let grid = self.grid();
        self.check_search_size(budget, grid)?;
        let ev = Evaluator {
            study: self,
            cache: StructureCache::new(),
            count: AtomicUsize::new(0),
            infeasible: AtomicUsize::new(0),
            progress,
            budget,
        };
        let qs_all: Vec<&Quantity> = self.variables.iter().map(|v| &v.quantity).collect();
        let eval = |qs: &[&Quantity], x: &[f64]| ev.eval(qs, x);
        let metric = self.objective.metric();
        let order = self.search_order();
        let n = order.len();
        let min = self.min_simulations();
        // The neighbour check (2 per free variable) runs when the budget holds it on top of
        // the minimum; the optimum's run and the comparison come after the search.
        let check_runs = 2 * n;
        let checked = n > 0 && budget >= min + check_runs;
        let search_budget = budget - 2 - if checked { check_runs } else { 0 };
        // Every objective value the search saw (for the flatness test).
        let seen = std::sync::Mutex::new(Vec::<f64>::new());
        // A point in the variables' order from the free variables' search coordinates (in
        // `order`); a fixed variable is its bound.
        let to_x = |u: &[f64]| -> Vec<f64> {
            let mut x: Vec<f64> = self.variables.iter().map(|v| v.lower).collect();
            for (j, &k) in order.iter().enumerate() {
                x[k] = self.search_to_value(k, u[j]);
            }
            x
        };
        let f = |u: &[f64]| -> f64 {
            let v = eval(&qs_all, &to_x(u)).metric(metric);
            if let Ok(mut s) = seen.lock() {
                s.push(v);
            }
            v
        };
        let (lo, hi) = self.search_bounds();
        let box_ = SearchBox {
            lo: &lo,
            hi: &hi,
            grid,
            search_budget,
        };
        let (u_best, simulations, failures, converged, local_searches) = if n == 0 {
            (Vec::new(), 0, 0, true, 0)
        } else if n == 1 {
            self.scan_and_brent(&f, &to_x, &box_)?
        } else {
            self.box_search(&f, &box_)?
        };
        let search_infeasible = ev.infeasible.load(Ordering::Relaxed);
        let mut optimum = to_x(&u_best);
        let mut point = eval(&qs_all, &optimum);
        let mut objective_value = point.metric(metric);
        if !objective_value.is_finite() {
            return Err(self.no_valid_design(&point, &optimum, simulations + 1));
        }
        let mut simulations = simulations + 1;

        // The neighbour check: what the optimum is.
        let mut check = if checked {
            self.neighbours(&eval, &box_, &u_best, &optimum, objective_value)
        } else {
            // Without the check, a bound is still a bound.
            NeighbourCheck {
                at_bound: self.on_bounds(&box_, &u_best),
                ..NeighbourCheck::default()
            }
        };
        simulations += check.runs;
        let mut values: Vec<f64> = seen.into_inner().unwrap_or_default();
        values.push(objective_value);
        values.extend(check.neighbours.iter().map(|nb| nb.objective));
        let finite: Vec<f64> = values.into_iter().filter(|v| v.is_finite()).collect();
        let method = self.method_text(grid, local_searches);
        let search = SearchEnd {
            objective_value,
            converged,
            checked,
            budget,
            min_runs: min + check_runs,
            check_runs,
        };
        let (verdict, statement) = self.verdict(&check, &finite, &method, &search);
        if verdict == Verdict::NotAMinimum {
            if let Some((x, p, fv, _)) = check.lower.take() {
                optimum = x;
                point = p;
                objective_value = fv;
            }
        }
        let local_check = LocalCheck {
            verdict,
            step_fraction: NEIGHBOUR_STEP,
            neighbours: check.neighbours,
            at_bound: check.at_bound,
            statement,
        };
        let (rule, rule_runs) = self.rule_objective(&eval, &optimum);
        let overrides = self.overrides(&optimum, &point);
        let infeasible = ev.infeasible.into_inner();
        let steady_state = match self.rate_bpm {
            Some(rate) => Some(self.steady_of(rate, &qs_all, &optimum, Some(&ev.cache))?),
            None => None,
        };
        Ok(OptimizeReport {
            objective: self.objective,
            metric,
            variables: self.variables.clone(),
            optimum,
            objective_value,
            simulations: simulations + rule_runs,
            max_simulations: budget,
            grid_points_per_variable: if n == 0 { 0 } else { grid },
            grid_simulations: self.grid_total(),
            local_searches,
            method,
            failures: failures.saturating_sub(search_infeasible),
            converged,
            wd_over_ws_at_optimum: point.metric("wd_over_ws"),
            objective_at_wd_equal_ws: rule,
            point,
            rate_bpm: self.rate_bpm,
            infeasible: self.rate_bpm.map(|_| infeasible),
            steady_state,
            local_check,
            overrides,
        })
    }

    /// Refuses a search the settings cannot run: fewer than 2 grid points per variable, a grid
    /// of more than [`MAX_GRID_SIMULATIONS`] points, or a budget below
    /// [`OptimizeStudy::min_simulations`].
    fn check_search_size(&self, budget: usize, grid: usize) -> Result<()> {
        if grid < 2 {
            return Err(Error::Input {
                location: format!("--grid {grid}"),
                message: "the grid needs at least 2 points per variable (both bounds)".into(),
            });
        }
        let n_free = self.search_order().len();
        if n_free >= 1 && self.grid_total() > MAX_GRID_SIMULATIONS {
            return Err(Error::Input {
                location: format!("--grid {grid}"),
                message: format!(
                    "a grid of {grid}^{n_free} points is more than {MAX_GRID_SIMULATIONS} simulations; give at most {} points per variable",
                    (2..=grid)
                        .rev()
                        .find(|&p| super::optimize::grid_size(p, n_free)
                            .is_some_and(|t| t <= MAX_GRID_SIMULATIONS))
                        .unwrap_or(2)
                ),
            });
        }
        let n = n_free;
        let min = self.min_simulations();
        if budget < min {
            return Err(Error::Input {
                location: format!("--max-simulations {budget}"),
                message: format!(
                    "{budget} simulations are too few: with {n} variable{} the search needs at least {min} ({}, the optimum's own run and the w_d = w_s comparison){}",
                    if n == 1 { "" } else { "s" },
                    if n == 1 {
                        format!("a {grid}-point scan and one Brent step")
                    } else {
                        format!("a grid of {grid}^{n} = {} points and one simplex of {} points", self.grid_total(), n + 1)
                    },
                    if n >= 2 { "; give a larger --max-simulations or a smaller --grid" } else { "" }
                ),
            });
        }
        Ok(())
    }

    /// The free variables' bounds in search coordinates (ln x for a log variable), in
    /// search order.
    fn search_bounds(&self) -> (Vec<f64>, Vec<f64>) {
        let order = self.search_order();
        let lo: Vec<f64> = order
            .iter()
            .map(|&k| self.value_to_search(k, self.variables[k].lower))
            .collect();
        let hi: Vec<f64> = order
            .iter()
            .map(|&k| self.value_to_search(k, self.variables[k].upper))
            .collect();
        (lo, hi)
    }

    /// The search over two or more free variables: a grid over the box, then a bounded
    /// Nelder-Mead search with restarts and a coordinate polish from each of the best
    /// [`GLOBAL_STARTS`] grid points lower than their neighbours ([`minimize_box_global`]).
    fn box_search(
        &self,
        f: &(dyn Fn(&[f64]) -> f64 + Sync),
        box_: &SearchBox,
    ) -> Result<SearchOutcome> {
        let opts = GlobalOptions {
            grid_points: box_.grid,
            starts: GLOBAL_STARTS,
            max_evaluations: box_.search_budget,
            local: NelderMeadOptions {
                initial_step: 0.2,
                x_tolerance: 1e-5,
                f_tolerance: 1e-9,
                max_evaluations: box_.search_budget,
                max_restarts: 5,
                random_starts: 0,
                seed: 4,
                polish: true,
            },
        };
        let r = minimize_box_global(f, box_.lo, box_.hi, &opts)?;
        let searches = r.searches.len();
        Ok((r.x, r.evaluations, r.failures, r.converged, searches))
    }

    /// The error when the objective is undefined at the search's best point `optimum` (its
    /// run `point`, after `simulations` simulations).
    fn no_valid_design(&self, point: &PointResult, optimum: &[f64], simulations: usize) -> Error {
        if point.error.is_some() {
            return self.failure(
                optimum,
                &format!("no valid design found in {simulations} simulations"),
                "the last point",
            );
        }
        let metric = self.objective.metric();
        Error::numerical(
            "optimize",
            format!("no valid design found: {metric} is undefined at the best point"),
        )
    }

    /// The search over one free variable: a scan of `grid` points (in parallel, collected in
    /// grid order: the result does not depend on the thread count), then Brent's method around
    /// each of the best [`GLOBAL_STARTS`] scan points lower than both their neighbours
    /// (distinct basins), the lowest kept. Returns the best search coordinate, the
    /// simulations, the failures, whether the best search converged and the searches run.
    fn scan_and_brent(
        &self,
        f: &(dyn Fn(&[f64]) -> f64 + Sync),
        to_x: &dyn Fn(&[f64]) -> Vec<f64>,
        box_: &SearchBox,
    ) -> Result<SearchOutcome> {
        let (lo, hi) = (box_.lo, box_.hi);
        let m = box_.grid;
        let grid: Vec<f64> = (0..m)
            .map(|i| {
                // The last point is the upper bound itself (lo + (hi − lo) need not be hi).
                if i + 1 == m {
                    hi[0]
                } else {
                    lo[0] + (hi[0] - lo[0]) * i as f64 / (m - 1) as f64
                }
            })
            .collect();
        let vals: Vec<f64> = grid.par_iter().map(|&u| f(&[u])).collect();
        let scan_fail = vals.iter().filter(|v| !v.is_finite()).count();
        // `i` is below its neighbour `j` (a failed neighbour is above; ties go to the
        // first in grid order).
        let below = |i: usize, j: usize| {
            !vals[j].is_finite() || vals[i] < vals[j] || (vals[i] == vals[j] && i < j)
        };
        let mut minima: Vec<usize> = (0..m)
            .filter(|&i| {
                vals[i].is_finite()
                    && (i == 0 || below(i, i - 1))
                    && (i + 1 == m || below(i, i + 1))
            })
            .collect();
        minima.sort_by(|&a, &b| vals[a].total_cmp(&vals[b]).then(a.cmp(&b)));
        if minima.is_empty() {
            return Err(self.failure(
                &to_x(&[grid[0]]),
                &format!("all {m} points of the initial scan failed"),
                "the first scan point",
            ));
        }
        // Each search gets an equal share of the budget left (at least 10 simulations:
        // fewer starts when the budget is short), so each, and the result, is the same
        // whatever the others do.
        let left = box_.search_budget - m;
        minima.truncate(GLOBAL_STARTS.min((left / 10).max(1)));
        let share = left / minima.len();
        let (mut u_best, mut f_best) = (grid[minima[0]], vals[minima[0]]);
        let (mut evaluations, mut failures, mut converged) = (m, scan_fail, true);
        for &ib in &minima {
            let a = grid[ib.saturating_sub(1)];
            let b = grid[(ib + 1).min(m - 1)];
            let opts = BrentOptions {
                x_tolerance: 1e-6 * (hi[0] - lo[0]),
                relative_tolerance: 1e-8,
                max_evaluations: share,
            };
            let r = brent_minimize(|u| f(&[u]), a, b, &opts)?;
            evaluations += r.evaluations;
            failures += r.failures;
            if r.f < f_best {
                (u_best, f_best) = (r.x, r.f);
                converged = r.converged;
            } else if ib == minima[0] {
                converged = r.converged;
            }
        }
        // A search that ends within half the neighbour step of a bound, no lower than the
        // bound's own scan value beyond round-off, ends on the bound (Brent converges to
        // within its tolerance of a bound, not onto it).
        for end in [0, m - 1] {
            if (u_best - grid[end]).abs() < 0.5 * NEIGHBOUR_STEP * (hi[0] - lo[0])
                && vals[end] <= f_best + 1e-12 * f_best.abs()
            {
                u_best = grid[end];
            }
        }
        Ok((vec![u_best], evaluations, failures, converged, minima.len()))
    }

    /// The neighbour check: each free variable moved by ±[`NEIGHBOUR_STEP`] of its search
    /// range from the optimum (`u_best` in search coordinates, `optimum` in values, objective
    /// `objective_value` there), the others held; a neighbour the bound holds to less than
    /// half the step is the bound. Keeps the lowest neighbour below the optimum.
    fn neighbours(
        &self,
        eval: &(dyn Fn(&[&Quantity], &[f64]) -> PointResult + Sync),
        box_: &SearchBox,
        u_best: &[f64],
        optimum: &[f64],
        objective_value: f64,
    ) -> NeighbourCheck {
        let (lo, hi) = (box_.lo, box_.hi);
        let metric = self.objective.metric();
        let qs_all: Vec<&Quantity> = self.variables.iter().map(|v| &v.quantity).collect();
        let mut out = NeighbourCheck::default();
        for (j, &k) in self.search_order().iter().enumerate() {
            let h = NEIGHBOUR_STEP * (hi[j] - lo[j]);
            for (side, sign) in [("lower", -1.0), ("upper", 1.0)] {
                let t = (u_best[j] + sign * h).clamp(lo[j], hi[j]);
                let mut x = optimum.to_vec();
                x[k] = self.search_to_value(k, t);
                // A neighbour the bound holds to less than half the step (a search ending
                // within round-off of the bound) is the bound, not a neighbour.
                if x[k] == optimum[k] || (t - u_best[j]).abs() < 0.5 * h {
                    out.at_bound
                        .push(format!("{} ({side})", self.variables[k].quantity.name()));
                    continue;
                }
                let p = eval(&qs_all, &x);
                out.runs += 1;
                let fv = p.metric(metric);
                out.neighbours.push(Neighbour {
                    variable: self.variables[k].quantity.name(),
                    value: x[k],
                    objective: fv,
                });
                let lower = fv < objective_value - 1e-12 * objective_value.abs();
                if lower && out.lower.as_ref().is_none_or(|b| fv < b.2) {
                    out.lower = Some((x, p, fv, out.neighbours.len() - 1));
                }
            }
        }
        out
    }

    /// The free variables whose search coordinate `u_best` is exactly on a bound (named with
    /// the side), when no neighbour check ran.
    fn on_bounds(&self, box_: &SearchBox, u_best: &[f64]) -> Vec<String> {
        let mut at_bound = Vec::new();
        for (j, &k) in self.search_order().iter().enumerate() {
            for (side, b) in [("lower", box_.lo[j]), ("upper", box_.hi[j])] {
                if u_best[j] == b {
                    at_bound.push(format!("{} ({side})", self.variables[k].quantity.name()));
                }
            }
        }
        at_bound
    }

    /// How the search ran, in words (the report's `method`).
    fn method_text(&self, grid: usize, local_searches: usize) -> String {
        let n = self.search_order().len();
        match n {
            0 => "nothing searched (every variable fixed)".to_string(),
            1 => format!("a {grid}-point scan over the bounds, then Brent's method around each of the best {local_searches} scan points lower than their neighbours"),
            _ => format!(
                "a {} grid over the box ({} simulations), then a bounded Nelder-Mead search with restarts and a coordinate polish from each of the best {local_searches} grid points lower than their neighbours",
                vec![grid.to_string(); n].join("×"),
                self.grid_total()
            ),
        }
    }

    /// What the optimum is, from the neighbour check, with the statement for the report: every
    /// variable fixed, a flat objective (all `finite` values seen equal within 10⁻¹²), not a
    /// minimum (a neighbour is lower; the caller reports that neighbour), not checked, a
    /// minimum on a bound, or a local minimum.
    fn verdict(
        &self,
        check: &NeighbourCheck,
        finite: &[f64],
        method: &str,
        s: &SearchEnd,
    ) -> (Verdict, String) {
        let metric = self.objective.metric();
        let order = self.search_order();
        let objective_value = s.objective_value;
        let (f_min, f_max) = finite
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let names: Vec<String> = order
            .iter()
            .map(|&k| self.variables[k].quantity.name())
            .collect();
        let step_text = format!(
            "±{} % of each variable's range{}",
            100.0 * NEIGHBOUR_STEP,
            if order.iter().any(|&k| self.variables[k].log) {
                " (in ln x for a log variable)"
            } else {
                ""
            }
        );
        let (neighbours, at_bound) = (&check.neighbours, &check.at_bound);
        if order.is_empty() {
            (
                Verdict::Fixed,
                "every variable is fixed (LO = HI): this is the objective at that point; nothing was searched".to_string(),
            )
        } else if finite.len() > 1 && f_max - f_min <= 1e-12 * f_max.abs().max(f_min.abs()) {
            (
                Verdict::Flat,
                format!(
                    "the objective is flat: {metric} = {objective_value:e} at all {} points evaluated (spread {:e}): it does not depend on {} within the bounds, and any value there is as good as the one reported",
                    finite.len(),
                    f_max - f_min,
                    names.join(", ")
                ),
            )
        } else if let Some((_, _, fv, i)) = &check.lower {
            let nb = &neighbours[*i];
            let text = format!(
                "not a verified local minimum: the search ({}) ended at {metric} = {objective_value:e}, and its neighbour {} = {:e} gives {fv:e}, lower; reported is that neighbour. Raise --max-simulations, or narrow --bounds around it",
                if s.converged { "converged" } else { "budget reached" },
                nb.variable,
                nb.value
            );
            (Verdict::NotAMinimum, text)
        } else if !s.checked {
            (
                Verdict::NotChecked,
                format!(
                    "not checked: the budget (--max-simulations {}) left no simulations for the {} neighbours (give at least {}); found by {method}",
                    s.budget, s.check_runs, s.min_runs
                ),
            )
        } else if !at_bound.is_empty() {
            (
                Verdict::OnBound,
                format!(
                    "a minimum on the bound{}: {}; every neighbour inside the bounds ({step_text}) gives a higher {metric}, so the objective falls towards the bound and lower values may lie beyond it (widen --bounds if the model allows)",
                    if at_bound.len() == 1 { "" } else { "s" },
                    at_bound.join(", ")
                ),
            )
        } else {
            let rise = neighbours
                .iter()
                .map(|nb| nb.objective / objective_value - 1.0)
                .fold(f64::INFINITY, f64::min);
            (
                Verdict::LocalMinimum,
                format!(
                    "a local minimum: each of the {} neighbours ({step_text}) gives a higher {metric} (smallest rise {:.3e} relative); found by {method}; the lowest found, global to the grid's resolution (a basin narrower than about two grid cells can be missed)",
                    neighbours.len(),
                    rise
                ),
            )
        }
    }

    /// The objective with the paper's rule ω_d = ω_s at the optimum's other variables (any
    /// variable setting K_d dropped), and the runs it took (none without a damper: NaN).
    fn rule_objective(
        &self,
        eval: &(dyn Fn(&[&Quantity], &[f64]) -> PointResult + Sync),
        optimum: &[f64],
    ) -> (f64, usize) {
        let mut qs: Vec<&Quantity> = Vec::new();
        let mut vals: Vec<f64> = Vec::new();
        for (k, v) in self.variables.iter().enumerate() {
            let is_wd = matches!(v.quantity, Quantity::WdOverWs | Quantity::WdOverWref)
                || v.quantity == Quantity::Field("contact.bed_damper.stiffness".into());
            if !is_wd {
                qs.push(&v.quantity);
                vals.push(optimum[k]);
            }
        }
        let wd = Quantity::WdOverWs;
        qs.push(&wd);
        vals.push(1.0);
        if self.model.spec.damper.is_some() {
            let r = eval(&qs, &vals).metric(self.objective.metric());
            (r, 1)
        } else {
            (f64::NAN, 0)
        }
    }
}

/// A search's end: the best point in search coordinates, the simulations, the failures,
/// whether the best search converged and the local searches run.
type SearchOutcome = (Vec<f64>, usize, usize, bool, usize);

/// The optimiser's simulations: each point run through the shared structure cache (refused
/// when its damper does not return at the stroke rate), counted, and the count reported to
/// `progress` against the budget.
struct Evaluator<'a> {
    study: &'a OptimizeStudy,
    cache: StructureCache,
    count: AtomicUsize,
    /// Points refused at the stroke rate.
    infeasible: AtomicUsize,
    progress: &'a (dyn Fn(usize, usize) + Sync),
    budget: usize,
}

impl Evaluator<'_> {
    /// The point with the quantities `qs` at the values `x`.
    fn eval(&self, qs: &[&Quantity], x: &[f64]) -> PointResult {
        let s = self.study;
        let r = evaluate_cached(
            &s.model,
            qs,
            x,
            s.bed_mass_kg,
            &s.options,
            0,
            Some(&self.cache),
        );
        let (r, refused) = s.at_stroke_rate(qs, x, r, Some(&self.cache));
        if refused {
            self.infeasible.fetch_add(1, Ordering::Relaxed);
        }
        let d = self.count.fetch_add(1, Ordering::Relaxed) + 1;
        (self.progress)(d.min(self.budget), self.budget);
        r
    }
}

/// The search box in search coordinates (ln x for a log variable), the grid points per
/// variable and the simulations the search may take.
struct SearchBox<'a> {
    lo: &'a [f64],
    hi: &'a [f64],
    grid: usize,
    search_budget: usize,
}

/// What the neighbour check found around the search's end.
#[derive(Default)]
struct NeighbourCheck {
    neighbours: Vec<Neighbour>,
    /// The variables whose neighbour on a side is the bound itself (`name (side)`).
    at_bound: Vec<String>,
    /// The lowest neighbour below the optimum: its point, result, objective and index in
    /// `neighbours`.
    lower: Option<(Vec<f64>, PointResult, f64, usize)>,
    /// The simulations the check ran.
    runs: usize,
}

/// How the search ended, for the verdict's statement.
struct SearchEnd {
    /// The objective at the search's optimum.
    objective_value: f64,
    converged: bool,
    /// Whether the neighbour check ran.
    checked: bool,
    /// The budget (`--max-simulations`), the least that holds the check, and the check's runs.
    budget: usize,
    min_runs: usize,
    check_runs: usize,
}
