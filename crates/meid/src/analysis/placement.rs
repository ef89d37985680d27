//! Where to put a general machine's dampers, how many, and how heavy:
//! `meid optimize GENERAL.toml --place D1,D2,D3,D4 --dampers 1..4 --total-mass 3.5`.
//!
//! **Placements.** A placement of `n` dampers is a choice of `n` of the candidate structure
//! points (`--repeat`: a point may carry several dampers). Each damper is a copy of a template
//! `[[damper]]` of the file scaled to its mass so that its spring, dashpot and contact keep the
//! template's frequencies and damping ratios; the file's other dampers are removed
//! ([`crate::model::network_fields::placed_spec`]). Masses: `--total-mass M` gives each of
//! the `n` dampers `M/n` (a placement is one simulation); `--mass-bounds LO..HI` makes every
//! damper's mass a variable in `[LO, HI]` kg, chosen for each placement by the bounded
//! Nelder-Mead search of [`super::optimize::minimize_box`] from the box's centre, within
//! `--mass-evaluations` simulations per placement.
//!
//! **Search.** The placements of `n` dampers among `c` candidates number `C(c, n)`
//! (`C(c + n − 1, n)` with repetition); their sum over the counts asked for is bounded up front
//! by `--max-combinations`. Within the bound every placement is evaluated (exhaustive). Over
//! it (or with `--search heuristic`) a greedy search with swaps: starting from no damper, add
//! the candidate that lowers the objective most, one damper at a time up to the largest count;
//! at each count asked for, move one damper at a time to another candidate, taking the best
//! move while one lowers the objective (steepest descent over single moves). It evaluates about
//! `c · n` placements per count instead of `C(c, n)`, and finds the optimum whenever the
//! objective has no local minimum over single moves other than the global one; a heuristic
//! result is labelled as such.
//!
//! **Objectives** (minimised): `energy` (the energy ratio, the share of the blows' energy kept
//! by the structure), `floor-force` (peak force to the floor), `accel:POINT` (peak |acceleration|
//! of a named point), `contact-force:NAME` (peak force of a contact that is not a damper's).
//!
//! **Operating condition.** With a stroke rate (`--rate-bpm R`, or the file's `[production]
//! rate_bpm`) each design is judged on its **steady blow** at that rate
//! ([`super::network_blows::steady_state`]: the fixed point of the blow-to-blow map), not on
//! the first blow: the objective is the steady level (for a period-k regime the mean energy
//! ratio and the largest peaks over the period), and each design reports `dampers_return`,
//! whether the train settled and every damper touches its point before each strike. **Only
//! designs whose dampers all return are feasible**: a damper that no longer touches its point
//! at the strike cannot take the blow's momentum, and in the steady regime it is a tuned mass at
//! best (the paper's damper at 60 /min makes the floor force worse than no damper). An infeasible
//! design has no objective value; its error names the dampers that do not return, their largest
//! gap at a strike and the value it would have had; the report counts them (`infeasible`). A
//! design whose train did not settle has no objective value either (its error says so). With no
//! feasible design the study ends with an error saying so.

use rayon::prelude::*;
use serde::Serialize;

use super::network::summary;
use super::network_blows::{settled_steady_state, DamperTouch, NetSteadyState};
use super::network_study::metrics;
use super::optimize::{minimize_box, NelderMeadOptions};
use crate::model::network::NetworkModel;
use crate::model::network_fields::{placed_spec, NetCache, Placement};
use crate::model::network_paths::did_you_mean;
use crate::{Error, Result};

/// What a placement study minimises (module docs).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum NetObjective {
    Energy,
    FloorForce,
    Accel(String),
    ContactForce(String),
}

impl NetObjective {
    /// Parses `energy`, `floor-force`, `accel:POINT` or `contact-force:NAME`.
    pub fn parse(s: &str) -> Result<Self> {
        let s = s.trim();
        Ok(match s.split_once(':') {
            None if s == "energy" => Self::Energy,
            None if s == "floor-force" => Self::FloorForce,
            Some(("accel", p)) if !p.is_empty() => Self::Accel(p.to_string()),
            Some(("contact-force", c)) if !c.is_empty() => Self::ContactForce(c.to_string()),
            _ => {
                return Err(Error::invalid(
                    "--objective",
                    format!("unknown objective `{s}` for a general machine; valid: energy, floor-force, accel:POINT, contact-force:CONTACT"),
                ))
            }
        })
    }

    /// The metric column it reads ([`super::network_study::metrics`]).
    pub fn column(&self) -> String {
        match self {
            Self::Energy => "energy_ratio".into(),
            Self::FloorForce => "floor_force_n".into(),
            Self::Accel(p) => format!("peak_acceleration_m_per_s2:{p}"),
            Self::ContactForce(c) => format!("peak_force_n:{c}"),
        }
    }

    /// Checks that every placement of `model` has the objective: a floor, a named point, a
    /// contact kept by every placement (not a damper's).
    fn check(&self, model: &NetworkModel) -> Result<()> {
        let fail = |m: String| Err(Error::invalid("--objective", m));
        match self {
            Self::Energy => Ok(()),
            Self::FloorForce if model.network.has_floor_force() => Ok(()),
            Self::FloorForce => fail("floor-force: nothing in this machine carries force to the floor (no spring or damper to the ground)".into()),
            Self::Accel(p) if model.structure.points.contains_key(p) => Ok(()),
            Self::Accel(p) => {
                let known: Vec<&str> = model.structure.points.keys().map(|s| s.as_str()).collect();
                fail(format!("accel:{p}: unknown point{} (valid: {})", did_you_mean(p, &known), known.join(", ")))
            }
            Self::ContactForce(c) => {
                let kept: Vec<&str> = model
                    .spec
                    .contact
                    .iter()
                    .filter(|k| !k.between.iter().any(|e| model.spec.damper.iter().any(|d| d.name == *e)))
                    .map(|k| k.name.as_str())
                    .collect();
                if kept.contains(&c.as_str()) {
                    Ok(())
                } else {
                    fail(format!("contact-force:{c}: not a contact every placement keeps{} (valid: {}; a damper's contacts are replaced by the placement's)", did_you_mean(c, &kept), kept.join(", ")))
                }
            }
        }
    }
}

/// How the dampers' masses are set (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum MassRule {
    /// `--total-mass M`: `M/n` each.
    Total(f64),
    /// `--mass-bounds LO..HI`: each a variable in `[LO, HI]` kg.
    Free { lower: f64, upper: f64 },
}

/// The discrete search (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Search {
    /// Exhaustive within the bound, else heuristic.
    Auto,
    Exhaustive,
    Heuristic,
}

impl Search {
    pub fn parse(s: &str) -> Result<Self> {
        match s.trim() {
            "auto" => Ok(Self::Auto),
            "exhaustive" => Ok(Self::Exhaustive),
            "heuristic" => Ok(Self::Heuristic),
            o => Err(Error::invalid(
                "--search",
                format!("unknown search `{o}`; valid: auto, exhaustive, heuristic"),
            )),
        }
    }
}

/// A placement study (module docs).
#[derive(Debug)]
pub struct PlacementStudy {
    pub model: NetworkModel,
    /// The `[[damper]]` copied to every place.
    pub template: String,
    pub candidates: Vec<String>,
    /// Counts of dampers, `lower..=upper`.
    pub counts: (usize, usize),
    /// A point may carry several dampers.
    pub repeat: bool,
    pub masses: MassRule,
    pub objective: NetObjective,
    pub search: Search,
    pub max_combinations: usize,
    /// Simulations per placement for free masses.
    pub mass_evaluations: usize,
    /// The stroke rate (blows/min) at which each design is judged on its steady blow; `None`:
    /// on the first blow (module docs).
    pub rate_bpm: Option<f64>,
}

/// One simulation of the study.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Evaluation {
    pub points: Vec<String>,
    pub masses_kg: Vec<f64>,
    /// `None`: the run failed or has no value (see `error`).
    pub objective: Option<f64>,
    pub error: Option<String>,
    /// With a stroke rate: the train settled and every damper touches before each strike.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dampers_return: Option<bool>,
}

/// Whether every damper of a design returns at the stroke rate; when not, why (the error of
/// an infeasible design: module docs, "Operating condition").
#[derive(Debug, Clone, PartialEq)]
enum Returning {
    Yes,
    No(String),
}

impl Returning {
    /// From a settled steady state whose objective `column` is `value`.
    fn of(s: &NetSteadyState, column: &str, value: f64) -> Self {
        if s.dampers_return() {
            return Self::Yes;
        }
        let away: Vec<&DamperTouch> = s.dampers_touch.iter().filter(|d| !d.touches).collect();
        let gap = away
            .iter()
            .map(|d| d.gap_at_strike_m)
            .fold(0.0_f64, f64::max);
        let names: Vec<&str> = away.iter().map(|d| d.name.as_str()).collect();
        Self::No(format!(
            "infeasible: at {} blows/min {} {} not return between blows (largest gap at a strike {:.4} mm in the {} steady state); its {column} would be {}",
            crate::num(s.rate_bpm),
            names.join(", "),
            if names.len() == 1 { "does" } else { "do" },
            gap * 1e3,
            s.regime.name(),
            crate::num(value),
        ))
    }
}

/// A placement's best result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlacedResult {
    pub dampers: usize,
    pub points: Vec<String>,
    pub masses_kg: Vec<f64>,
    pub total_mass_kg: f64,
    pub objective: Option<f64>,
    pub simulations: usize,
    /// With a stroke rate: every damper returns in the steady regime of the chosen masses.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dampers_return: Option<bool>,
}

/// The study's report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlacementReport {
    pub machine: &'static str,
    pub objective: String,
    /// "exhaustive" or "heuristic (greedy + swap)".
    pub search: String,
    pub combinations: usize,
    pub max_combinations: usize,
    pub candidates: Vec<String>,
    pub template: String,
    pub masses: MassRule,
    /// The stroke rate the designs were judged at (their steady blow); `None`: the first blow.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rate_bpm: Option<f64>,
    /// With a stroke rate: the simulations refused because a damper does not return (module
    /// docs, "Operating condition").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub infeasible: Option<usize>,
    pub best: PlacedResult,
    /// The best placement of each count of dampers.
    pub best_per_count: Vec<PlacedResult>,
    /// The next best placements (up to 5).
    pub runner_ups: Vec<PlacedResult>,
    /// Every placement evaluated, best first.
    pub placements: Vec<PlacedResult>,
    /// Every simulation run, in the order of the search.
    pub evaluations: Vec<Evaluation>,
    pub simulations: usize,
    pub structures_built: usize,
    pub notes: Vec<String>,
}

/// `C(n, k)`, saturating.
fn choose(n: usize, k: usize) -> usize {
    if k > n {
        return 0;
    }
    let k = k.min(n - k);
    let mut r: u128 = 1;
    for i in 0..k {
        r = r * (n - i) as u128 / (i + 1) as u128;
        if r > usize::MAX as u128 {
            return usize::MAX;
        }
    }
    r as usize
}

/// Every multiset (with `repeat`) or set of `n` indices below `c`, as sorted vectors in
/// lexicographic order.
fn placements_of(c: usize, n: usize, repeat: bool) -> Vec<Vec<usize>> {
    let mut out = Vec::new();
    let mut cur = Vec::with_capacity(n);
    fn rec(
        c: usize,
        n: usize,
        repeat: bool,
        start: usize,
        cur: &mut Vec<usize>,
        out: &mut Vec<Vec<usize>>,
    ) {
        if cur.len() == n {
            out.push(cur.clone());
            return;
        }
        for i in start..c {
            cur.push(i);
            rec(c, n, repeat, if repeat { i } else { i + 1 }, cur, out);
            cur.pop();
        }
    }
    rec(c, n, repeat, 0, &mut cur, &mut out);
    out
}

impl PlacementStudy {
    /// Checks the study's inputs (each error names its option).
    pub fn check(&self) -> Result<()> {
        let m = &self.model;
        let names: Vec<&str> = m.spec.damper.iter().map(|d| d.name.as_str()).collect();
        if !names.contains(&self.template.as_str()) {
            return Err(Error::invalid(
                "--template",
                format!(
                    "no [[damper]] is named '{}'{} (valid: {}; the placed dampers are copies of it)",
                    self.template,
                    did_you_mean(&self.template, &names),
                    if names.is_empty() { "none: the file needs a [[damper]] to copy".into() } else { names.join(", ") }
                ),
            ));
        }
        if self.candidates.is_empty() {
            return Err(Error::invalid("--place", "no candidate point"));
        }
        let known: Vec<&str> = m.structure.points.keys().map(|s| s.as_str()).collect();
        for (i, p) in self.candidates.iter().enumerate() {
            if !m.structure.points.contains_key(p) {
                return Err(Error::invalid(
                    "--place",
                    format!(
                        "'{p}' is not a structure point{} (valid: {})",
                        did_you_mean(p, &known),
                        known.join(", ")
                    ),
                ));
            }
            if self.candidates[..i].contains(p) {
                return Err(Error::invalid(
                    "--place",
                    format!(
                        "'{p}' is listed twice (use --repeat for several dampers at one point)"
                    ),
                ));
            }
        }
        let (lo, hi) = self.counts;
        if lo == 0 || hi < lo {
            return Err(Error::invalid(
                "--dampers",
                format!("give N or LO..HI with 1 ≤ LO ≤ HI (got {lo}..{hi})"),
            ));
        }
        if !self.repeat && hi > self.candidates.len() {
            return Err(Error::invalid(
                "--dampers",
                format!("{hi} dampers but only {} candidate points in --place (one damper per point; --repeat allows several)", self.candidates.len()),
            ));
        }
        match self.masses {
            MassRule::Total(t) if !(t.is_finite() && t > 0.0) => {
                return Err(Error::invalid(
                    "--total-mass",
                    format!("must be a finite number > 0 kg (got {})", crate::num(t)),
                ))
            }
            MassRule::Free { lower, upper }
                if !(lower.is_finite() && upper.is_finite() && lower > 0.0 && upper >= lower) =>
            {
                return Err(Error::invalid(
                    "--mass-bounds",
                    format!(
                        "give LO..HI with 0 < LO ≤ HI kg (got {}..{})",
                        crate::num(lower),
                        crate::num(upper)
                    ),
                ))
            }
            MassRule::Free { .. } if self.mass_evaluations < 2 => {
                return Err(Error::invalid(
                    "--mass-evaluations",
                    "at least 2 simulations per placement",
                ))
            }
            _ => {}
        }
        self.objective.check(m)?;
        if let Some(r) = self.rate_bpm {
            super::network_blows::check_rate(r)?;
        }
        if self.search == Search::Exhaustive && self.combinations() > self.max_combinations {
            return Err(Error::invalid(
                "--max-combinations",
                format!(
                    "{} placements of {lo}..{hi} dampers among {} candidates exceed the bound {} of an exhaustive search: raise --max-combinations, narrow --place or --dampers, or use --search heuristic",
                    self.combinations(), self.candidates.len(), self.max_combinations
                ),
            ));
        }
        Ok(())
    }

    /// The number of placements over the counts asked for (saturating).
    pub fn combinations(&self) -> usize {
        let c = self.candidates.len();
        (self.counts.0..=self.counts.1)
            .map(|n| {
                if self.repeat {
                    choose(c + n - 1, n)
                } else {
                    choose(c, n)
                }
            })
            .fold(0usize, usize::saturating_add)
    }

    /// The objective of one simulation of the dampers at `points` with `masses` (with a stroke
    /// rate: of its steady blow, and whether every damper returns, with the reason when not:
    /// [`Returning`]).
    fn simulate(
        &self,
        points: &[String],
        masses: &[f64],
        cache: &NetCache,
    ) -> Result<(f64, Option<Returning>)> {
        let placement = Placement {
            points: points.to_vec(),
            masses_kg: masses.to_vec(),
        };
        let spec = placed_spec(&self.model.spec, &self.template, &placement)?;
        let m = self
            .model
            .with_spec(spec, self.model.source.clone(), Some(cache))?;
        let col = self.objective.column();
        if let Some(rate_bpm) = self.rate_bpm {
            let s = settled_steady_state(&m, rate_bpm)?;
            let v = s.metric(&col).ok_or_else(|| {
                Error::numerical("placement", format!("{col}: no value in the steady blow"))
            })?;
            return Ok((v, Some(Returning::of(&s, &col, v))));
        }
        let sol = m.solve(&m.options()?)?;
        metrics(&summary(&m, &sol))
            .into_iter()
            .find(|(c, _)| *c == col)
            .and_then(|(_, v)| v)
            .map(|v| (v, None))
            .ok_or_else(|| {
                Error::numerical(
                    "placement",
                    format!("{col}: no value (the collision did not end within the run?)"),
                )
            })
    }

    /// The best result of placement `idx` (candidate indices) and its simulations.
    fn evaluate(&self, idx: &[usize], cache: &NetCache) -> (PlacedResult, Vec<Evaluation>) {
        let points: Vec<String> = idx.iter().map(|&i| self.candidates[i].clone()).collect();
        let n = points.len();
        let mut log = Vec::new();
        let mut run = |masses: &[f64]| -> Option<f64> {
            // An infeasible design (a damper that does not return) has no objective value.
            let (objective, error, dampers_return) = match self.simulate(&points, masses, cache) {
                Ok((v, None)) => (Some(v), None, None),
                Ok((v, Some(Returning::Yes))) => (Some(v), None, Some(true)),
                Ok((_, Some(Returning::No(why)))) => (None, Some(why), Some(false)),
                Err(e) => (None, Some(e.to_string()), None),
            };
            log.push(Evaluation {
                points: points.clone(),
                masses_kg: masses.to_vec(),
                objective,
                error,
                dampers_return,
            });
            objective
        };
        let (masses, objective) = match self.masses {
            MassRule::Total(t) => {
                let m = vec![t / n as f64; n];
                let f = run(&m);
                (m, f)
            }
            MassRule::Free { lower, upper } => {
                let opts = NelderMeadOptions {
                    max_evaluations: self.mass_evaluations,
                    ..Default::default()
                };
                let x0 = vec![0.5 * (lower + upper); n];
                match minimize_box(
                    |x: &[f64]| run(x),
                    &x0,
                    &vec![lower; n],
                    &vec![upper; n],
                    &opts,
                ) {
                    Ok(r) if r.f.is_finite() => (r.x, Some(r.f)),
                    _ => (x0, None),
                }
            }
        };
        // Whether the dampers return at the masses chosen (their evaluation's).
        let dampers_return = log
            .iter()
            .rev()
            .find(|e| e.masses_kg == masses)
            .and_then(|e| e.dampers_return);
        let result = PlacedResult {
            dampers: n,
            dampers_return,
            total_mass_kg: masses.iter().sum(),
            points,
            masses_kg: masses,
            objective,
            simulations: log.len(),
        };
        (result, log)
    }

    /// Evaluates the placements of `list` not yet in `memo` (in parallel, kept in order).
    fn evaluate_new(
        &self,
        list: &[Vec<usize>],
        memo: &mut Vec<(Vec<usize>, PlacedResult, Vec<Evaluation>)>,
        cache: &NetCache,
    ) {
        let mut new: Vec<Vec<usize>> = Vec::new();
        for p in list {
            if !memo.iter().any(|(q, _, _)| q == p) && !new.contains(p) {
                new.push(p.clone());
            }
        }
        let done: Vec<_> = new
            .par_iter()
            .map(|p| {
                let (r, log) = self.evaluate(p, cache);
                (p.clone(), r, log)
            })
            .collect();
        memo.extend(done);
    }

    /// The best of `list` in `memo` (lowest objective; ties: the first).
    fn best_of(
        list: &[Vec<usize>],
        memo: &[(Vec<usize>, PlacedResult, Vec<Evaluation>)],
    ) -> Option<(Vec<usize>, f64)> {
        let mut best: Option<(Vec<usize>, f64)> = None;
        for p in list {
            let f = memo
                .iter()
                .find(|(q, _, _)| q == p)
                .and_then(|(_, r, _)| r.objective);
            if let Some(f) = f {
                if best.as_ref().is_none_or(|(_, b)| f < *b) {
                    best = Some((p.clone(), f));
                }
            }
        }
        best
    }

    /// The greedy search with swaps (module docs).
    fn heuristic(
        &self,
        memo: &mut Vec<(Vec<usize>, PlacedResult, Vec<Evaluation>)>,
        cache: &NetCache,
    ) {
        let c = self.candidates.len();
        let allowed = |cur: &[usize], i: usize| self.repeat || !cur.contains(&i);
        let mut current: Vec<usize> = Vec::new();
        for k in 1..=self.counts.1 {
            let adds: Vec<Vec<usize>> = (0..c)
                .filter(|&i| allowed(&current, i))
                .map(|i| {
                    let mut p = current.clone();
                    p.push(i);
                    p.sort_unstable();
                    p
                })
                .collect();
            self.evaluate_new(&adds, memo, cache);
            let Some((best, mut f_best)) = Self::best_of(&adds, memo) else {
                return;
            };
            current = best;
            if k < self.counts.0 {
                continue;
            }
            loop {
                let mut moves: Vec<Vec<usize>> = Vec::new();
                for pos in 0..current.len() {
                    let rest: Vec<usize> = current
                        .iter()
                        .enumerate()
                        .filter(|(j, _)| *j != pos)
                        .map(|(_, &v)| v)
                        .collect();
                    for i in (0..c).filter(|&i| i != current[pos] && allowed(&rest, i)) {
                        let mut p = rest.clone();
                        p.push(i);
                        p.sort_unstable();
                        moves.push(p);
                    }
                }
                self.evaluate_new(&moves, memo, cache);
                match Self::best_of(&moves, memo) {
                    Some((p, f)) if f < f_best => {
                        current = p;
                        f_best = f;
                    }
                    _ => break,
                }
            }
        }
    }

    /// Runs the study: the report of every placement evaluated, best first.
    pub fn run(&self) -> Result<PlacementReport> {
        self.check()?;
        let cache = NetCache::new();
        let mut memo = Vec::new();
        let combinations = self.combinations();
        let mut notes = Vec::new();
        let exhaustive = match self.search {
            Search::Exhaustive => true,
            Search::Heuristic => false,
            Search::Auto => combinations <= self.max_combinations,
        };
        if exhaustive {
            let all: Vec<Vec<usize>> = (self.counts.0..=self.counts.1)
                .flat_map(|n| placements_of(self.candidates.len(), n, self.repeat))
                .collect();
            self.evaluate_new(&all, &mut memo, &cache);
        } else {
            if self.search == Search::Auto {
                notes.push(format!("{combinations} placements exceed --max-combinations {}: searched by the heuristic (greedy + swap), which may miss the optimum", self.max_combinations));
            }
            self.heuristic(&mut memo, &cache);
        }
        report(self, memo, exhaustive, combinations, cache.builds(), notes)
    }
}

/// The report of the placements in `memo`.
fn report(
    s: &PlacementStudy,
    memo: Vec<(Vec<usize>, PlacedResult, Vec<Evaluation>)>,
    exhaustive: bool,
    combinations: usize,
    structures_built: usize,
    notes: Vec<String>,
) -> Result<PlacementReport> {
    let evaluations: Vec<Evaluation> = memo
        .iter()
        .flat_map(|(_, _, l)| l.iter().cloned())
        .collect();
    let mut placements: Vec<PlacedResult> = memo.into_iter().map(|(_, r, _)| r).collect();
    // Best first; failed placements last; ties keep the search's order.
    placements.sort_by(|a, b| match (a.objective, b.objective) {
        (Some(x), Some(y)) => x.total_cmp(&y),
        (Some(_), None) => std::cmp::Ordering::Less,
        (None, Some(_)) => std::cmp::Ordering::Greater,
        (None, None) => std::cmp::Ordering::Equal,
    });
    let infeasible = evaluations
        .iter()
        .filter(|e| e.dampers_return == Some(false))
        .count();
    let best = placements
        .first()
        .filter(|p| p.objective.is_some())
        .cloned()
        .ok_or_else(|| {
            // The first infeasible design's error, else the first failure's.
            let why = evaluations
                .iter()
                .filter(|e| infeasible == 0 || e.dampers_return == Some(false))
                .find_map(|e| e.error.clone())
                .unwrap_or_default();
            let rate = s.rate_bpm.map(crate::num).unwrap_or_default();
            Error::numerical(
                "placement",
                if infeasible > 0 {
                    format!(
                        "no placement is feasible at {rate} blows/min: in {infeasible} of {} simulations a damper does not return between blows (first: {why}); a damper creeps back with a time constant of about c/k (docs/explanations/blows.md, \"The damper that does not return\"): try a template with a stiffer spring or a weaker dashpot, or a lower stroke rate",
                        evaluations.len()
                    )
                } else {
                    format!(
                        "no placement has a value of {}: {why}",
                        s.objective.column()
                    )
                },
            )
        })?;
    let best_per_count = (s.counts.0..=s.counts.1)
        .filter_map(|n| {
            placements
                .iter()
                .find(|p| p.dampers == n && p.objective.is_some())
                .cloned()
        })
        .collect();
    Ok(PlacementReport {
        machine: "general",
        objective: s.objective.column(),
        search: if exhaustive {
            "exhaustive".into()
        } else {
            "heuristic (greedy + swap)".into()
        },
        combinations,
        max_combinations: s.max_combinations,
        candidates: s.candidates.clone(),
        template: s.template.clone(),
        masses: s.masses,
        rate_bpm: s.rate_bpm,
        infeasible: s.rate_bpm.map(|_| infeasible),
        best,
        best_per_count,
        runner_ups: placements.iter().skip(1).take(5).cloned().collect(),
        simulations: evaluations.len(),
        placements,
        evaluations,
        structures_built,
        notes,
    })
}
