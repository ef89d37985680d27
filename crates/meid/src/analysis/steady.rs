//! The periodic steady state of a blow train, found directly: the fixed point of the
//! blow-to-blow map, its Floquet multipliers and the regime (period-1, period-k, irregular).
//!
//! # The blow map
//! A train strikes every `T = 60 / rate` s ([`super::blows`]). Let `y` be the state of the
//! structure and the damper just before a strike (the slider, which is replaced at every
//! strike, is not part of it):
//!
//! ```text
//! y = [q; z_d; q̇; ż_d]           (2·(dofs − 1) values)
//! R(y) = x0:  x = y with z_s = ψ(O_b)ᵀq, ż_s = v_s     (a fresh slider, just touching)
//! P(y) = S Φ_T(R(y))              (Φ_T the exact flow over one interval, S drops the slider)
//! ```
//!
//! A **period-k steady state** is a fixed point of `P^k`. It is found by Newton's method on
//! `F(y) = P^k(y) − y`:
//!
//! ```text
//! (J − I) Δ = −F(y),   J = ∂P^k/∂y = Π_blows S · M_T · ∂R/∂y
//! ```
//!
//! where `M_T` is the flow's state-transition (monodromy) matrix along the run's path,
//! computed from the path itself ([`crate::integrate::PathPoint`]): between two switches the
//! motion is `Ẋ = A_σ X + b` ([`ImpactSystem::first_order`]), so the stretch contributes
//! `e^{A_σ Δt}` (the engine's closed form of the mode, its transition matrix
//! [`crate::integrate::propagator::Propagator::transition`], from the cache the run filled);
//! at a switch at `t_e` on the surface
//! `nᵀX = 0` the vector field may jump, and the variational equation takes the saltation matrix
//! (Aizerman & Gantmacher; di Bernardo et al., *Piecewise-smooth Dynamical Systems*, 2008,
//! §2.5)
//!
//! ```text
//! S_e = I + (f⁺ − f⁻) nᵀ / (nᵀ f⁻),   f^± = A_σ± X(t_e) + b
//! ```
//!
//! With undamped contacts (the paper's C_s = C_d = 0) and the one-way dashpot (its force
//! `c_d δ̇` is zero where it switches) the field is continuous and `S_e = I`. A damped contact
//! closes at `δ = 0` with a force jump `C δ̇`: `n = [a; 0]` (its relative vector). Where the path
//! has a held (resting) contact or a non-linear contact law, the flow is not a product of
//! exponentials and `J` is taken by forward differences instead (`2·(dofs − 1)` extra blow
//! evaluations per Newton step; the result says so in `jacobian`).
//!
//! The **multipliers** `μ_i = eig(J)` at the fixed point decide stability: the regime attracts
//! when `max |μ_i| < 1`, and a disturbance decays by `|μ|max` per period, so the blows to settle
//! to a relative level `ε` are `ln ε / ln |μ|max` (reported for ε = 1e-3).
//!
//! Convergence is measured in the energy norm relative to the blow's energy,
//!
//! ```text
//! ‖F‖ = √(Σ_i (ω̄_i² F_qi² + F_q̇i²) + k_d F_zd² + m_d F_żd²) / √(m_s v_s²)
//! ```
//!
//! (`ω̄_i = max(ω_i, 2π/T)`, so a rigid-body mode still counts), i.e. the square root of the
//! share of the blow's energy that one more period would change; the default tolerance 1e-10
//! is far below anything a reported level resolves.
//!
//! # Regimes and the fallback
//! 1. Newton on `P` from the machine at rest, globalised: a step that does not lower the
//!    residual is followed by one backtracking step along it (the quadratic model's minimiser,
//!    Dennis & Schnabel 1983, A6.3.1), and if that fails too by a march step `y ← P(y)`.
//!    Converged to a stable fixed point: **period-1**.
//! 2. Otherwise (no convergence within its budget: the map is non-smooth where a contact just
//!    grazes, or the fixed point is unstable) the train is **marched** blow by blow from where
//!    Newton was best, and after each blow the smallest `k ≤ max_period` with
//!    `‖y_j − y_{j−k}‖ < 1e-6` is sought; found, Newton on `P^k` refines it from `y_j`:
//!    **period-k** (every k-th blow alike; k = 2 is a damper touching every other blow).
//!    Where none appears to 1e-6 within the budget, the period with the smallest change over
//!    the last blows (below 1e-2) is refined by Newton on `P^k` once, and taken when it
//!    converges to a stable fixed point: the march was settling slowly onto it.
//! 3. No period within the budget: **irregular**, with the last marched blows' levels as an
//!    estimate, their spread beside them, and `converged = false`.
//!
//! A grazing contact makes `P` non-smooth: Newton's quadratic convergence fails, and the
//! result says so (`smooth = false`) when the switching sequence of the last two Newton
//! evaluations differs at convergence.

use std::rc::Rc;

use faer::linalg::solvers::Solve;
use faer::Mat;
use serde::Serialize;

use super::blows::{blow_interval_s, next_strike, one_blow, BlowReport};
use super::energy::{History, Recorder};
use crate::impact::{ImpactSystem, Mode, Switch};
use crate::integrate::{self, propagator::Propagator, Method, Options, Solution};
use crate::{Error, Result};

/// Blow evaluations the search from rest leaves for marching (step 2 of the module docs'
/// "Regimes and the fallback"): a disturbance decaying by `|μ|max = 0.75` per blow falls below
/// the period detection's `1e-6` within 48 blows.
const MARCH_RESERVE: usize = 48;

/// Settings of the direct steady state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SteadyOptions {
    /// Stroke rate (blows per minute), > 0.
    pub rate_bpm: f64,
    /// Residual `‖P^k(y) − y‖` (energy norm, relative: module docs) that counts as converged.
    pub tolerance: f64,
    /// Most blow-map evaluations (blows simulated) in all.
    pub max_evaluations: usize,
    /// Longest period (blows) sought.
    pub max_period: usize,
}

impl Default for SteadyOptions {
    fn default() -> Self {
        Self {
            rate_bpm: 60.0,
            tolerance: 1e-10,
            max_evaluations: 200,
            max_period: 8,
        }
    }
}

/// How the Jacobian of the blow map was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Jacobian {
    /// From the path: products of `e^{A_σ Δt}` and saltation matrices (module docs).
    Path,
    /// Forward differences (held contacts or non-linear contact laws on the path).
    FiniteDifferences,
}

/// The steady regime of a train.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Regime {
    /// Every k-th blow alike (k = 1: every blow alike).
    Period(usize),
    /// No period up to `max_period` within the budget.
    Irregular,
}

impl Regime {
    /// "period-1", "period-2", …, "irregular".
    pub fn name(self) -> String {
        match self {
            Regime::Period(k) => format!("period-{k}"),
            Regime::Irregular => "irregular".into(),
        }
    }
}

impl Serialize for Regime {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(&self.name())
    }
}

/// The periodic steady state of a train (module docs).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SteadyState {
    /// Stroke rate (blows per minute) and interval T = 60/rate (s).
    pub rate_bpm: f64,
    pub interval_s: f64,
    /// True when a fixed point of `P^k` was found to the tolerance.
    pub converged: bool,
    /// `‖P^k(y) − y‖` at the result (energy norm relative to the blow's energy, module docs).
    pub residual: f64,
    /// Blows simulated in all (Newton evaluations, marched blows, finite differences and the
    /// final evaluation of the steady blows).
    pub map_evaluations: usize,
    pub regime: Regime,
    /// k of a period-k regime; `None` when irregular.
    pub period_blows: Option<usize>,
    /// "newton" (found directly from rest), "newton after marching" (a period found by
    /// marching, refined by Newton) or "marching" (irregular: an estimate).
    pub method: &'static str,
    pub jacobian: Jacobian,
    /// The energy ratio η of the steady blow (mean over the blows of a period).
    pub energy_ratio: f64,
    /// Largest peak over the blows of the period.
    pub peak_floor_force_n: f64,
    pub peak_bed_acceleration_m_per_s2: f64,
    pub peak_contact_force_slider_bed_n: f64,
    /// Largest damper gap at a strike over the period (m); `None` without a damper.
    pub damper_gap_at_strike_m: Option<f64>,
    /// True when the damper touches the bed in every blow of the period; `None` without a
    /// damper.
    pub damper_touches_bed: Option<bool>,
    /// `|μ_i|` of the Floquet multipliers of `P^k` at the result, descending (empty when
    /// irregular).
    pub multipliers_abs: Vec<f64>,
    /// `max |μ| < 1`; `None` when irregular.
    pub stable: Option<bool>,
    /// Periods for a disturbance to decay to 1e-3 of itself, `ln 1e-3 / ln |μ|max`; `None`
    /// when not stable.
    pub periods_to_settle: Option<f64>,
    /// False when the switching sequence of the last two evaluations differed (a contact that
    /// grazes: the map is not smooth there).
    pub smooth: bool,
    /// The steady blows (one per blow of the period; for an irregular train the last
    /// `max_period` marched blows), struck at `k·T` from the first of them.
    pub blows: Vec<BlowReport>,
    /// What the reader should know about how the result was obtained.
    pub notes: Vec<String>,
    /// The search's residuals in order, each marked: `s` the start of a Newton search, `N` an
    /// accepted Newton step, `b` an accepted backtracking step after a rejected Newton step, `x`
    /// a rejected step (Newton or backtracking), `m` a march step of the Newton search.
    pub residual_history: Vec<(char, f64)>,
    /// The state `y` just before the first of [`Self::blows`] (the fixed point of `P^k`, or
    /// for an irregular train the marched state before its last blows): [`replay`] runs the
    /// steady blows again from it.
    #[serde(skip)]
    pub strike_state: Vec<f64>,
}

impl SteadyState {
    /// The train settled (`converged`) and, with a damper, the damper touches the bed in every
    /// blow of the period: it returns between blows. Without a damper: the train settled.
    pub fn damper_returns(&self) -> bool {
        self.converged && self.damper_touches_bed != Some(false)
    }
}

/// One evaluation of a blow map `P` (one blow) with its Jacobian.
pub(crate) struct Evaluation<R, S> {
    /// `P(y)`.
    pub p: Vec<f64>,
    /// `∂P/∂y` when asked for.
    pub jac: Option<Mat<f64>>,
    /// The blow's levels.
    pub report: R,
    /// Its switching sequence (compared between iterates: a change means the map is not
    /// smooth there).
    pub switches: S,
}

/// A blow-to-blow map `P: y ↦ y'` (the state just before a strike to the state just before
/// the next) as the direct steady state's search sees it: the engine-independent part of the
/// method (Newton on `P^k`, the march and its period detection, the multipliers) is written
/// over it, for the paper's machine here ([`Map`]) and for a general machine
/// ([`super::network_blows`]).
pub(crate) trait BlowMap {
    /// The levels of one blow.
    type Report: Clone;
    /// A blow's switching sequence.
    type Switches: PartialEq;
    /// The dimension of `y`.
    fn dim(&self) -> usize;
    /// The energy-norm weights of the components of `y`, relative to the blow's energy
    /// (`‖d‖² = Σ w_i d_i²`).
    fn weight(&self) -> &[f64];
    /// One blow from `y` (blow number `k` of a period, for its report), with `∂P/∂y` when
    /// `with_jac`, and the blow's exact peaks only when `peaks`. Counts one evaluation (and
    /// those of a Jacobian by differences).
    fn eval(
        &mut self,
        y: &[f64],
        k: usize,
        with_jac: bool,
        peaks: bool,
    ) -> Result<Evaluation<Self::Report, Self::Switches>>;
    /// Blow evaluations spent, and the most allowed.
    fn evaluations(&self) -> usize;
    fn budget(&self) -> usize;
    /// The search's residual history ([`SteadyState::residual_history`]).
    fn history(&mut self) -> &mut Vec<(char, f64)>;
    /// The peak floor force of a blow (N), for the irregular regime's note.
    fn floor_force(report: &Self::Report) -> f64;
    /// Blow evaluations one blow with its Jacobian costs (1 where the Jacobian comes from the
    /// path; `1 + dim` by forward differences).
    fn step_cost(&self) -> usize {
        1
    }

    /// The relative energy norm of a difference of two states `y` (module docs).
    fn norm(&self, d: &[f64]) -> f64 {
        d.iter()
            .zip(self.weight())
            .map(|(v, w)| w * v * v)
            .sum::<f64>()
            .sqrt()
    }
    /// Records a residual of the search ([`SteadyState::residual_history`]).
    fn record(&mut self, what: char, residual: f64) {
        self.history().push((what, residual));
    }
    /// Blow evaluations left in the budget.
    fn left(&self) -> usize {
        self.budget().saturating_sub(self.evaluations())
    }
}

/// What stays fixed while the map is iterated.
struct Map<'a> {
    sys: &'a ImpactSystem,
    opts: Options,
    user: Options,
    rate_bpm: f64,
    /// Indices of `y` in the full state `X = [x; ẋ]`.
    keep: Vec<usize>,
    /// Energy-norm weights of the components of `y` (module docs), divided by m_s v_s².
    weight: Vec<f64>,
    path_jacobian: bool,
    evaluations: usize,
    budget: usize,
    history: Vec<(char, f64)>,
}

impl<'a> Map<'a> {
    fn new(sys: &'a ImpactSystem, user: &Options, so: &SteadyOptions) -> Result<Self> {
        let interval = blow_interval_s(so.rate_bpm)?;
        let nd = sys.dofs();
        let s = sys.slider_index();
        let keep: Vec<usize> = (0..2 * nd).filter(|&i| i % nd != s).collect();
        let n = sys.n_modes();
        let w_min = 2.0 * std::f64::consts::PI / interval;
        let e2 = sys.slider.mass * sys.slider.velocity * sys.slider.velocity;
        if !(e2 > 0.0 && e2.is_finite()) {
            return Err(Error::invalid(
                "slider.velocity",
                "a steady state of a blow train needs a slider with kinetic energy (v_s ≠ 0)",
            ));
        }
        let weight = keep
            .iter()
            .map(|&i| {
                let (j, vel) = (i % nd, i >= nd);
                let w = if j < n {
                    if vel {
                        1.0
                    } else {
                        sys.structure.omega_rad_per_s[j].max(w_min).powi(2)
                    }
                } else {
                    // the damper
                    let d = sys.damper.as_ref();
                    if vel {
                        d.map_or(1.0, |d| d.mass)
                    } else {
                        d.map_or(1.0, |d| d.stiffness.max(d.mass * w_min * w_min))
                    }
                };
                w / e2
            })
            .collect();
        let linear = [Switch::SliderBed, Switch::BedDamper]
            .iter()
            .filter(|&&c| c != Switch::BedDamper || sys.damper.is_some())
            .all(|&c| sys.contact(c).law.is_linear());
        let mut opts = *user;
        opts.duration = interval;
        opts.sample_rate = None;
        opts.stop_at_collision_end = false;
        Ok(Map {
            sys,
            opts,
            user: *user,
            rate_bpm: so.rate_bpm,
            keep,
            weight,
            path_jacobian: linear,
            evaluations: 0,
            budget: so.max_evaluations.max(2),
            history: Vec::new(),
        })
    }

    fn embed(&self, y: &[f64]) -> Vec<f64> {
        let mut x = vec![0.0; 2 * self.sys.dofs()];
        for (&i, &v) in self.keep.iter().zip(y) {
            x[i] = v;
        }
        next_strike(self.sys, &x)
    }

    fn select(&self, x: &[f64]) -> Vec<f64> {
        self.keep.iter().map(|&i| x[i]).collect()
    }

    /// Counts one blow evaluation. The loops check [`Self::left`] before they evaluate, so a
    /// spent budget ends a search (not converged) instead of failing it.
    fn spend(&mut self) -> Result<()> {
        self.evaluations += 1;
        Ok(())
    }

    /// One blow from `y` (blow number `k` for the report), with the Jacobian when `with_jac`,
    /// and the report's exact peaks and checked energy balance only when `peaks` (an iterate of
    /// the search needs the state at the next strike, not its levels: [`Options::levels`]).
    fn eval_blow(
        &mut self,
        y: &[f64],
        k: usize,
        with_jac: bool,
        peaks: bool,
    ) -> Result<Evaluation<BlowReport, Vec<Mode>>> {
        self.spend()?;
        let x0 = self.embed(y);
        let t0 = k as f64 * self.opts.duration;
        let o_blow = Options {
            levels: peaks,
            ..self.opts
        };
        let done = one_blow(
            self.sys,
            &o_blow,
            &self.user,
            &x0,
            k,
            t0,
            self.rate_bpm,
            &mut integrate::NoOutput,
        )?;
        let sol = &done.solution;
        let switches = sol.path.iter().map(|p| p.mode).collect();
        let p = self.select(&sol.x_final);
        let jac = if !with_jac {
            None
        } else {
            match self.path_monodromy(sol) {
                Some(m) => Some(self.reduce(&m)),
                None => Some(self.differences(y, &p)?),
            }
        };
        Ok(Evaluation {
            p,
            jac,
            report: done.report,
            switches,
        })
    }

    /// `S · M · ∂R/∂y` from the full-state monodromy `M`.
    fn reduce(&self, m: &Mat<f64>) -> Mat<f64> {
        let nd = self.sys.dofs();
        let s = self.sys.slider_index();
        let phi = &self.sys.points.bed_contact;
        let d = self.dim();
        // ∂R/∂y: the embedding, plus z_s = ψᵀq (row s, q columns).
        Mat::from_fn(d, d, |r, c| {
            let (i, j) = (self.keep[r], self.keep[c]);
            let mut v = m[(i, j)];
            if j < phi.len() {
                v += m[(i, s)] * phi[j];
            }
            let _ = nd;
            v
        })
    }

    /// The monodromy matrix of a run from its path (module docs); `None` when the path has a
    /// held contact or a non-linear law, or a simultaneous switch with a jump in the field.
    fn path_monodromy(&self, sol: &Solution) -> Option<Mat<f64>> {
        if !self.path_jacobian || sol.path.iter().any(|p| p.mode.any_held()) {
            return None;
        }
        let sys = self.sys;
        let nd = sys.dofs();
        let nx = 2 * nd;
        let b = sys.forcing();
        let masses = sys.mass_diag();
        // The engine's closed forms (its per-thread cache: the same key, `K_σ`, `C_σ`, the
        // masses and the second-order force, finds the propagators the run just used).
        let force_2nd: Option<Vec<f64>> = b
            .as_ref()
            .map(|b| b[nd..].iter().zip(&masses).map(|(f, m)| f * m).collect());
        let field = |a: &Mat<f64>, x: &[f64]| -> Vec<f64> {
            (0..nx)
                .map(|i| {
                    (0..nx).map(|j| a[(i, j)] * x[j]).sum::<f64>()
                        + b.as_ref().map_or(0.0, |b| b[i])
                })
                .collect()
        };
        let mut m = Mat::<f64>::identity(nx, nx);
        let mut cache: Vec<(Mode, Rc<Propagator>)> = Vec::new();
        let mut prop_of = |mode: Mode| -> Option<Rc<Propagator>> {
            if let Some((_, p)) = cache.iter().find(|(md, _)| *md == mode) {
                return Some(p.clone());
            }
            let (k, c) = sys.matrices(mode);
            let p = Propagator::shared_forced(
                &k,
                &c,
                &masses,
                sys.first_order(mode),
                force_2nd.as_deref(),
            )
            .ok()?;
            cache.push((mode, p.clone()));
            Some(p)
        };
        for (i, pt) in sol.path.iter().enumerate() {
            let prop = prop_of(pt.mode)?;
            let a = &prop.a;
            if i > 0 {
                let prev = &sol.path[i - 1];
                let a_prev = &prop_of(prev.mode)?.a;
                let f_minus = field(a_prev, &pt.x);
                let f_plus = field(a, &pt.x);
                let jump: Vec<f64> = f_plus.iter().zip(&f_minus).map(|(p, q)| p - q).collect();
                let scale = f_minus
                    .iter()
                    .chain(&f_plus)
                    .fold(0.0_f64, |s, v| s.max(v.abs()));
                // A field continuous by construction (a dashpot or an undamped contact switches
                // where its force is zero) jumps only by the switch's location error; the
                // saltation matrix is then I up to that error and is applied all the same.
                if jump.iter().any(|v| v.abs() > 1e-15 * scale) {
                    let n = self.surface(prev.mode, pt.mode)?;
                    let nf: f64 = n.iter().zip(&f_minus).map(|(a, b)| a * b).sum();
                    if nf == 0.0 || !nf.is_finite() {
                        return None;
                    }
                    // M ← (I + jump nᵀ / nᵀf⁻) M
                    let nm: Vec<f64> = (0..nx)
                        .map(|c| (0..nx).map(|r| n[r] * m[(r, c)]).sum())
                        .collect();
                    for r in 0..nx {
                        for c in 0..nx {
                            m[(r, c)] += jump[r] * nm[c] / nf;
                        }
                    }
                }
            }
            let t_end = sol.path.get(i + 1).map_or(sol.t_final, |q| q.t);
            let dt = t_end - pt.t;
            if dt > 0.0 {
                // e^{A_σ Δt}: the closed form's transition matrix (of the homogeneous part,
                // which is the variation of an affine flow).
                m = prop.transition(dt) * &m;
            }
        }
        let finite = (0..nx).all(|c| (0..nx).all(|r| m[(r, c)].is_finite()));
        finite.then_some(m)
    }

    /// The switching surface normal `n` (`nᵀX = 0`, the switch's indicator vector
    /// [`ImpactSystem::indicator_vector`]) of a single switch from `from` to `to`: a contact
    /// closes at zero overlap; it opens at zero force under the force rule with a damped law,
    /// else at zero overlap; the one-way dashpot switches at zero relative velocity. `None` for
    /// a simultaneous switch of several.
    fn surface(&self, from: Mode, to: Mode) -> Option<Vec<f64>> {
        use crate::impact::{Indicator, Release};
        let sys = self.sys;
        let changed: Vec<Switch> = sys
            .switches()
            .into_iter()
            .filter(|&s| from.on(s) != to.on(s))
            .collect();
        let [s] = changed[..] else { return None };
        let ind = match s {
            Switch::Dashpot => Indicator::DashpotVelocity,
            c => {
                let contact = sys.contact(c);
                if from.on(c) && contact.release == Release::Force && contact.law.is_damped() {
                    Indicator::Force(c)
                } else {
                    Indicator::Overlap(c)
                }
            }
        };
        Some(sys.indicator_vector(ind))
    }

    /// `∂P/∂y` by forward differences, `h_j = 1e-7 / √w_j` (1e-7 of the blow's energy norm).
    fn differences(&mut self, y: &[f64], p: &[f64]) -> Result<Mat<f64>> {
        let d = self.dim();
        let mut jac = Mat::<f64>::zeros(d, d);
        for j in 0..d {
            let h = 1e-7 / self.weight[j].sqrt();
            let mut yj = y.to_vec();
            yj[j] += h;
            self.spend()?;
            let x0 = self.embed(&yj);
            let sol = integrate::solve_from(self.sys, &x0, &self.opts, &mut integrate::NoOutput)?;
            let pj = self.select(&sol.x_final);
            for i in 0..d {
                jac[(i, j)] = (pj[i] - p[i]) / h;
            }
        }
        Ok(jac)
    }
}

impl BlowMap for Map<'_> {
    type Report = BlowReport;
    type Switches = Vec<Mode>;
    fn dim(&self) -> usize {
        self.keep.len()
    }
    fn weight(&self) -> &[f64] {
        &self.weight
    }
    fn eval(
        &mut self,
        y: &[f64],
        k: usize,
        with_jac: bool,
        peaks: bool,
    ) -> Result<Evaluation<BlowReport, Vec<Mode>>> {
        self.eval_blow(y, k, with_jac, peaks)
    }
    fn evaluations(&self) -> usize {
        self.evaluations
    }
    fn budget(&self) -> usize {
        self.budget
    }
    fn history(&mut self) -> &mut Vec<(char, f64)> {
        &mut self.history
    }
    fn floor_force(report: &BlowReport) -> f64 {
        report.peak_floor_force_n
    }
}

/// The backtracked point after a Newton step `s = yt − y` was rejected (residual `rt ≥ r`):
/// `y + α s` with `α` the minimiser of the quadratic model of `φ(α) = ‖F(y + α s)‖²` through
/// `φ(0) = r²`, `φ'(0) = −2r²` (the Newton direction's own slope) and `φ(1) = rt²`,
/// safeguarded to `[0.1, 0.5]`:
///
/// ```text
/// α = clamp( r² / (rt² + r²), 0.1, 0.5 )
/// ```
///
/// (Dennis & Schnabel, *Numerical Methods for Unconstrained Optimization and Nonlinear
/// Equations*, 1983, §6.3.2, Algorithm A6.3.1). `None` when the budget has no room for it.
fn backtrack<M: BlowMap>(
    map: &M,
    y: &[f64],
    yt: &[f64],
    r: f64,
    rt: f64,
    k: usize,
) -> Option<Vec<f64>> {
    if map.left() < 2 * k || !(r > 0.0 && rt.is_finite()) {
        return None;
    }
    let a = (r * r / (rt * rt + r * r)).clamp(0.1, 0.5);
    Some(y.iter().zip(yt).map(|(p, q)| p + a * (q - p)).collect())
}

/// Solves `(J − I) Δ = −r`.
fn newton_step(jac: &Mat<f64>, r: &[f64]) -> Option<Vec<f64>> {
    let d = r.len();
    let a = Mat::from_fn(d, d, |i, j| jac[(i, j)] - if i == j { 1.0 } else { 0.0 });
    let rhs = Mat::from_fn(d, 1, |i, _| -r[i]);
    let x = a.partial_piv_lu().solve(&rhs);
    let out: Vec<f64> = (0..d).map(|i| x[(i, 0)]).collect();
    out.iter().all(|v| v.is_finite()).then_some(out)
}

/// `|eig(J)|`, descending.
pub(crate) fn multipliers(jac: &Mat<f64>) -> Vec<f64> {
    let mut m: Vec<f64> = jac
        .eigenvalues()
        .map(|v| v.iter().map(|z| z.norm()).collect())
        .unwrap_or_default();
    m.sort_by(|a, b| b.total_cmp(a));
    m
}

/// The result of Newton's method on `P^k`.
pub(crate) struct Fixed<R> {
    pub y: Vec<f64>,
    pub residual: f64,
    pub jac: Mat<f64>,
    pub smooth: bool,
    pub converged: bool,
    /// The k blows evaluated from `y`.
    pub reports: Vec<R>,
    /// Evaluations of `P^k` spent, and of them Newton steps rejected for a march step.
    pub rejected: usize,
    /// The states before each of the k blows from `y` (`y` first).
    pub orbit: Vec<Vec<f64>>,
}

/// `P^k(y)`, its Jacobian, the k blows' reports, their switching sequences and the states
/// before each of them (`y` first).
type PeriodEval<M> = (
    Vec<f64>,
    Mat<f64>,
    Vec<<M as BlowMap>::Report>,
    Vec<<M as BlowMap>::Switches>,
    Vec<Vec<f64>>,
);

/// `P^k(y)`, its Jacobian (the identity when not `with_jac`: a start that is marched from is
/// not differentiated), the blows' reports (with their exact peaks when `peaks`) and switching
/// sequences.
fn eval_k<M: BlowMap>(
    map: &mut M,
    y: &[f64],
    k: usize,
    peaks: bool,
    with_jac: bool,
) -> Result<PeriodEval<M>> {
    let d = map.dim();
    let mut z = y.to_vec();
    let mut jac = Mat::<f64>::identity(d, d);
    let mut reports = Vec::with_capacity(k);
    let mut switches = Vec::with_capacity(k);
    let mut orbit = Vec::with_capacity(k);
    for b in 0..k {
        orbit.push(z.clone());
        let e = map.eval(&z, b, with_jac, peaks)?;
        if with_jac {
            let jb = e
                .jac
                .ok_or_else(|| Error::numerical("steady state", "no Jacobian of the blow map"))?;
            jac = jb * &jac;
        }
        z = e.p;
        reports.push(e.report);
        switches.push(e.switches);
    }
    Ok((z, jac, reports, switches, orbit))
}

/// Newton on `P^k(y) − y = 0` from `y0`, globalised by backtracking and marching: a Newton
/// step whose residual is not smaller than the current one is rejected and followed by one
/// backtracking step along it ([`backtrack`]); if that is not smaller either, by the march step
/// `y ← P^k(y)` (already evaluated), which contracts wherever the regime attracts. At most
/// `iterations` steps (each one to three evaluations of `P^k`, within the map's budget).
///
/// With `march_first` the first step is a march step: from rest a damper touches the bed with
/// zero overlap and zero relative velocity (a grazing start), where the map is not
/// differentiable and a Newton step from there is wasted. No step is begun with fewer than
/// `reserve` evaluations of the budget left (kept for the march that follows a failed search).
///
/// The iterates are evaluated without the blows' exact peaks (they need only the state at the
/// next strike and the Jacobian), except the one Newton is expected to end on: after an accepted
/// Newton step from residual `r₀` to `r₁`, quadratic convergence predicts `r₂ ≈ r₁³/r₀²`, and
/// when that is within the tolerance the next evaluation tracks the peaks. The result's blows
/// always carry them: a search that ends on an evaluation without them evaluates its last
/// iterate once more (the same trajectory, bit for bit), with them.
fn newton<M: BlowMap>(
    map: &mut M,
    y0: Vec<f64>,
    k: usize,
    tol: f64,
    iterations: usize,
    march_first: bool,
    reserve: usize,
) -> Result<Fixed<M::Report>> {
    let mut y = y0;
    // From rest with a damper the first step is a march: the start is not differentiated.
    let (mut z, mut jac, mut reports, mut switches, mut orbit) =
        eval_k(map, &y, k, false, !march_first)?;
    let mut with_peaks = false;
    let diff = |a: &[f64], b: &[f64]| -> Vec<f64> { a.iter().zip(b).map(|(p, q)| p - q).collect() };
    let mut residual = map.norm(&diff(&z, &y));
    map.record('s', residual);
    let mut smooth = true;
    let mut rejected = 0;
    // The residual before the last accepted Newton step (`None` after a march step).
    let mut before: Option<f64> = None;
    for _ in 1..iterations {
        if residual <= tol || map.left() < 2 * k * map.step_cost() + reserve {
            break;
        }
        let r = diff(&z, &y);
        let trial: Option<Vec<f64>> = if march_first && map.history().len() == 1 {
            None
        } else {
            newton_step(&jac, &r).map(|s| y.iter().zip(&s).map(|(a, b)| a + b).collect())
        };
        let tried = trial.is_some();
        let accepted = match trial {
            Some(yt) => {
                let last = before.is_some_and(|r0| r0 > 0.0 && residual.powi(3) / (r0 * r0) <= tol);
                let (zt, jt, rt, st, ot) = eval_k(map, &yt, k, last, true)?;
                let res_t = map.norm(&diff(&zt, &yt));
                map.record(if res_t < residual { 'N' } else { 'x' }, res_t);
                if res_t < residual {
                    smooth = st == switches;
                    before = Some(residual);
                    (y, z, jac, reports, switches, residual) = (yt, zt, jt, rt, st, res_t);
                    orbit = ot;
                    with_peaks = last;
                    true
                } else if let Some(yw) = backtrack(map, &y, &yt, residual, res_t, k) {
                    // One backtracking step along the rejected Newton step.
                    let (zw, jw, rw, sw, ow) = eval_k(map, &yw, k, false, true)?;
                    let res_w = map.norm(&diff(&zw, &yw));
                    map.record(if res_w < residual { 'b' } else { 'x' }, res_w);
                    if res_w < residual {
                        smooth = sw == switches;
                        before = None;
                        (y, z, jac, reports, switches, residual) = (yw, zw, jw, rw, sw, res_w);
                        orbit = ow;
                        with_peaks = false;
                        true
                    } else {
                        false
                    }
                } else {
                    false
                }
            }
            None => false,
        };
        if !accepted {
            // March: y ← P^k(y).
            rejected += usize::from(tried);
            if residual <= tol || map.left() < k {
                break;
            }
            y = z.clone();
            let (zt, jt, rt, st, ot) = eval_k(map, &y, k, false, true)?;
            smooth = st == switches;
            residual = map.norm(&diff(&zt, &y));
            map.record('m', residual);
            (z, jac, reports, switches, orbit) = (zt, jt, rt, st, ot);
            (with_peaks, before) = (false, None);
        }
    }
    if !with_peaks {
        // The levels of the last iterate: the same blows again, with their exact peaks (and
        // the Jacobian, which a start that converged at once was not given).
        let (_, jt, rt, _, _) = eval_k(map, &y, k, true, true)?;
        (jac, reports) = (jt, rt);
    }
    Ok(Fixed {
        converged: residual <= tol,
        y,
        residual,
        jac,
        smooth,
        reports,
        rejected,
        orbit,
    })
}

/// The direct periodic steady state of the blow train of `sys` at `so.rate_bpm` (module
/// docs). `opts` are the model's run options (method, tolerances; duration and sample rate
/// are replaced by the interval and no output).
pub fn steady_state(sys: &ImpactSystem, opts: &Options, so: &SteadyOptions) -> Result<SteadyState> {
    check_options(so)?;
    let mut map = Map::new(sys, opts, so)?;
    let mut notes = Vec::new();
    if opts.method == Method::Dopri5 && map.path_jacobian {
        notes.push(
            "dopri5: the Jacobian is taken from the path's linear stretches (exact for linear \
             contact laws)"
                .to_string(),
        );
    }
    let found = search(&mut map, so, sys.damper.is_some(), &mut notes)?;
    match found {
        Found::Periodic {
            fixed,
            k,
            mu,
            method,
        } => finish(&mut map, so, fixed, k, mu, method, notes),
        Found::Irregular {
            tail,
            strike_state,
            residual,
        } => Ok(levels(SteadyState {
            rate_bpm: so.rate_bpm,
            interval_s: map.opts.duration,
            converged: false,
            residual,
            map_evaluations: map.evaluations,
            regime: Regime::Irregular,
            period_blows: None,
            method: "marching",
            jacobian: jacobian_kind(&map),
            energy_ratio: 0.0,
            peak_floor_force_n: 0.0,
            peak_bed_acceleration_m_per_s2: 0.0,
            peak_contact_force_slider_bed_n: 0.0,
            damper_gap_at_strike_m: None,
            damper_touches_bed: None,
            multipliers_abs: Vec::new(),
            stable: None,
            periods_to_settle: None,
            smooth: false,
            blows: tail,
            notes,
            residual_history: std::mem::take(&mut map.history),
            strike_state,
        })),
    }
}

/// What the search of a blow map found ([`search`]).
pub(crate) enum Found<R> {
    /// A fixed point of `P^k` (converged or Newton's best), its multipliers `|μ|` descending,
    /// and how it was found.
    Periodic {
        fixed: Fixed<R>,
        k: usize,
        mu: Vec<f64>,
        method: &'static str,
    },
    /// No period within the budget: the last marched blows (at most `max_period`), the state
    /// before the first of them, and the last blow-to-blow change (energy norm).
    Irregular {
        tail: Vec<R>,
        strike_state: Vec<f64>,
        residual: f64,
    },
}

/// The steady state's search on any blow map (module docs, "Regimes and the fallback"):
/// Newton on `P` from rest (a first march step when `march_first`: a damper resting on its
/// contact at rest is a grazing start); else a march from Newton's best iterate (off an
/// unstable fixed point), seeking the smallest period `k ≤ max_period`, refined by Newton on
/// `P^k`; else irregular. Adds its notes to `notes`.
pub(crate) fn search<M: BlowMap>(
    map: &mut M,
    so: &SteadyOptions,
    march_first: bool,
    notes: &mut Vec<String>,
) -> Result<Found<M::Report>> {
    let d = map.dim();
    let k_max = so.max_period.max(1);
    // What the march of step 2 needs: the refinement of a period-k (`4·(k_max + 1)`, as below)
    // and enough blows to see a period settle (`MARCH_RESERVE`). A Newton search that has not
    // converged by then (a costly finite-difference Jacobian near a grazing contact can spend
    // the whole budget) hands over to the march.
    let reserve = (4 * (k_max + 1) + MARCH_RESERVE).min(map.budget() / 2);
    // 1. Newton on P from rest.
    let fixed = newton(map, vec![0.0; d], 1, so.tolerance, 40, march_first, reserve)?;
    let mu = multipliers(&fixed.jac);
    let stable = mu.first().is_none_or(|m| *m < 1.0);
    if fixed.converged && stable {
        return Ok(Found::Periodic {
            fixed,
            k: 1,
            mu,
            method: "newton",
        });
    }
    if fixed.converged {
        notes.push(format!(
            "the period-1 fixed point is unstable (|μ|max = {:.4}): the train was marched to \
             the regime it settles in",
            mu[0]
        ));
    } else {
        notes.push(format!(
            "Newton on the blow map (with march steps where it did not descend) did not \
             converge from rest in {} evaluations (residual {:.2e}): the train was marched on, \
             seeking a period",
            map.evaluations(),
            fixed.residual
        ));
    }
    // 2. March from the best iterate (perturbed off an unstable fixed point), seeking a period.
    let mut y = fixed.y.clone();
    if fixed.converged {
        // Off the unstable fixed point along everything (1e-6 of the blow's energy norm).
        for (v, w) in y.iter_mut().zip(map.weight()) {
            *v += 1e-6 / w.sqrt() / (d as f64).sqrt();
        }
    }
    let mut states = vec![y.clone()];
    let mut reports: Vec<M::Report> = Vec::new();
    let detect = 1e-6_f64.max(so.tolerance);
    let march_budget = map
        .budget()
        .saturating_sub(map.evaluations() + 4 * (k_max + 1));
    for j in 1..=march_budget {
        if map.left() == 0 {
            break;
        }
        let e = map.eval(&y, j - 1, false, true)?;
        y = e.p;
        reports.push(e.report);
        states.push(y.clone());
        let found = (1..=k_max.min(j)).find(|&k| {
            let diff: Vec<f64> = y.iter().zip(&states[j - k]).map(|(a, b)| a - b).collect();
            map.norm(&diff) < detect
        });
        if let Some(k) = found {
            let fixed = newton(map, y.clone(), k, so.tolerance, 8, false, 0)?;
            let mu = multipliers(&fixed.jac);
            notes.push(format!(
                "a period of {k} blow{} appeared after {j} marched blows and was refined by \
                 Newton on P^{k}",
                if k == 1 { "" } else { "s" }
            ));
            return Ok(Found::Periodic {
                fixed,
                k,
                mu,
                method: "newton after marching",
            });
        }
    }
    // 2b. No period to 1e-6 within the march: a regime that settles slowly (|μ| near 1 on
    // P^k) still has its fixed point of P^k near the last state, which Newton finds where the
    // march crawls. The closest period is refined once, and taken only converged and stable.
    if let Some(found) = closest_period(map, so, &states, k_max, notes)? {
        return Ok(found);
    }
    // 3. Irregular: the last blows' levels as an estimate.
    if reports.is_empty() {
        return Err(Error::numerical(
            "steady state",
            format!(
                "the budget of {} blow evaluations was spent before any blow could be marched (Newton's residual {:.2e}): raise it or lower the model's cost",
                map.budget(),
                fixed.residual
            ),
        ));
    }
    let tail: Vec<M::Report> = reports.iter().rev().take(k_max).rev().cloned().collect();
    // `states[j]` is the state before marched blow j + 1.
    let strike_state = states[reports.len() - tail.len()].clone();
    let (flo, fhi) = tail
        .iter()
        .map(M::floor_force)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    notes.push(format!(
        "no period of at most {k_max} blows within {} blows: irregular; the levels are the \
         largest of the last {} marched blows, an estimate (floor force {flo:.4}..{fhi:.4} N \
         over them)",
        map.evaluations(),
        tail.len()
    ));
    let n = states.len();
    let residual = if n >= 2 {
        let diff: Vec<f64> = states[n - 1]
            .iter()
            .zip(&states[n - 2])
            .map(|(a, b)| a - b)
            .collect();
        map.norm(&diff)
    } else {
        f64::NAN
    };
    Ok(Found::Irregular {
        tail,
        strike_state,
        residual,
    })
}

/// Step 2b of [`search`]: after a march of `states` (the states before each marched blow and
/// after the last) in which no period appeared to the detection's 1e-6, the period `k ≤ k_max`
/// with the smallest change `‖y_j − y_{j−k}‖` over the last `k` blows, when that change is below
/// 1e-2 of the blow's energy norm, is refined by Newton on `P^k` from the last state; a converged
/// fixed point whose multipliers are all inside the unit circle is the regime the march was
/// approaching (it attracts, and the march was within its reach), so it is returned, with its
/// least period (a divisor `d` of `k` with `‖P^d(y) − y‖ < 1e-6` is refined on `P^d`). Anything
/// else: `None`, and the train is irregular.
fn closest_period<M: BlowMap>(
    map: &mut M,
    so: &SteadyOptions,
    states: &[Vec<f64>],
    k_max: usize,
    notes: &mut Vec<String>,
) -> Result<Option<Found<M::Report>>> {
    let j = states.len().saturating_sub(1);
    let Some(y) = states.last() else {
        return Ok(None);
    };
    let Some((k, change)) = (1..=k_max.min(j))
        .map(|k| {
            let diff: Vec<f64> = y.iter().zip(&states[j - k]).map(|(a, b)| a - b).collect();
            (k, map.norm(&diff))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
    else {
        return Ok(None);
    };
    if change.is_nan() || change >= 1e-2 || map.left() < 2 * k * map.step_cost() {
        return Ok(None);
    }
    let k0 = k;
    let mut fixed = newton(map, y.clone(), k, so.tolerance, 8, false, 0)?;
    if !fixed.converged {
        return Ok(None);
    }
    // The least period of the orbit found: a slowly decaying disturbance of a period-d orbit
    // (multiplier μ of P^d near −1) changes least over 2d blows, so the closest period can be
    // a multiple of the orbit's own.
    let mut k = k;
    for d in (1..k).filter(|d| k % d == 0) {
        let diff: Vec<f64> = fixed.orbit[d]
            .iter()
            .zip(&fixed.y)
            .map(|(a, b)| a - b)
            .collect();
        if map.norm(&diff) < 1e-6 {
            let f = newton(map, fixed.y.clone(), d, so.tolerance, 8, false, 0)?;
            if f.converged {
                (fixed, k) = (f, d);
                break;
            }
        }
    }
    let mu = multipliers(&fixed.jac);
    if mu.first().is_some_and(|m| *m >= 1.0) {
        return Ok(None);
    }
    notes.push(format!(
        "no period appeared to 1e-6 within {j} marched blows; the closest (a change of \
         {change:.1e} over the last {k0} blows) was refined by Newton to a stable orbit of \
         {k} blow{} (|μ|max = {:.4} on P^{k}): the march was settling slowly onto it",
        if k == 1 { "" } else { "s" },
        mu.first().copied().unwrap_or(0.0)
    ));
    Ok(Some(Found::Periodic {
        fixed,
        k,
        mu,
        method: "newton after marching",
    }))
}

/// One steady blow run again by [`replay`]: its solution (exact peaks in `totals.peaks`, blow
/// time from its strike at 0) and its samples on the run options' output grid.
pub struct Replayed {
    pub solution: Solution,
    pub history: History,
}

/// The steady blows of `s` (one per blow of its period; for an irregular train its last
/// marched blows) run again on `sys` from [`SteadyState::strike_state`], each recorded on
/// `opts.sample_rate` from its strike to the next (`s.interval_s`). `sys` must have the
/// dynamics the steady state was found on; its output channels may differ (a probe point, a
/// different floor-force functional), which is how the foundation's checks measure the steady
/// blow at the block ([`crate::foundation`]).
pub fn replay(sys: &ImpactSystem, opts: &Options, s: &SteadyState) -> Result<Vec<Replayed>> {
    let so = SteadyOptions {
        rate_bpm: s.rate_bpm,
        ..SteadyOptions::default()
    };
    let map = Map::new(sys, opts, &so)?;
    if s.strike_state.len() != map.dim() {
        return Err(Error::numerical(
            "steady state",
            format!(
                "the steady strike state has {} values, the system's blow map {}",
                s.strike_state.len(),
                map.dim()
            ),
        ));
    }
    let o_blow = Options {
        sample_rate: opts.sample_rate,
        levels: true,
        ..map.opts
    };
    let mut y = s.strike_state.clone();
    let mut out = Vec::with_capacity(s.blows.len());
    for b in 0..s.blows.len() {
        let x0 = map.embed(&y);
        let mut rec = Recorder::new(sys).starting_at(&x0);
        let t0 = b as f64 * map.opts.duration;
        let done = one_blow(sys, &o_blow, opts, &x0, b, t0, s.rate_bpm, &mut rec)?;
        y = map.select(&done.solution.x_final);
        out.push(Replayed {
            solution: done.solution,
            history: rec.history,
        });
    }
    Ok(out)
}

fn jacobian_kind(map: &Map) -> Jacobian {
    if map.path_jacobian {
        Jacobian::Path
    } else {
        Jacobian::FiniteDifferences
    }
}

pub(crate) fn check_options(so: &SteadyOptions) -> Result<()> {
    blow_interval_s(so.rate_bpm)?;
    if !(so.tolerance.is_finite() && so.tolerance > 0.0 && so.tolerance < 1.0) {
        return Err(Error::invalid(
            "steady tolerance",
            format!("must lie in (0, 1) (got {})", so.tolerance),
        ));
    }
    if so.max_period == 0 || so.max_period > 64 {
        return Err(Error::invalid(
            "max_period",
            format!("must lie in 1..=64 blows (got {})", so.max_period),
        ));
    }
    Ok(())
}

/// Evaluates the k steady blows from the fixed point and fills the levels.
fn finish(
    map: &mut Map,
    so: &SteadyOptions,
    fixed: Fixed<BlowReport>,
    k: usize,
    mu: Vec<f64>,
    method: &'static str,
    notes: Vec<String>,
) -> Result<SteadyState> {
    let blows = fixed.reports.clone();
    debug_assert_eq!(blows.len(), k);
    let mu_max = mu.first().copied().unwrap_or(0.0);
    let stable = mu_max < 1.0;
    let mut notes = notes;
    fixed_notes(&fixed, so, &mut notes);
    Ok(levels(SteadyState {
        rate_bpm: so.rate_bpm,
        interval_s: map.opts.duration,
        converged: fixed.converged,
        residual: fixed.residual,
        map_evaluations: map.evaluations,
        regime: Regime::Period(k),
        period_blows: Some(k),
        method,
        jacobian: jacobian_kind(map),
        energy_ratio: 0.0,
        peak_floor_force_n: 0.0,
        peak_bed_acceleration_m_per_s2: 0.0,
        peak_contact_force_slider_bed_n: 0.0,
        damper_gap_at_strike_m: None,
        damper_touches_bed: None,
        multipliers_abs: mu,
        stable: Some(stable),
        periods_to_settle: settle(mu_max),
        smooth: fixed.smooth,
        blows,
        notes,
        residual_history: std::mem::take(&mut map.history),
        strike_state: fixed.y,
    }))
}

/// Periods for a disturbance to decay to 1e-3 of itself, `ln 1e-3 / ln |μ|max`, for a stable
/// regime (`0 < |μ|max < 1`).
pub(crate) fn settle(mu_max: f64) -> Option<f64> {
    (mu_max < 1.0 && mu_max > 0.0).then(|| 1e-3_f64.ln() / mu_max.ln())
}

/// The notes on how Newton's result was reached: a grazing contact, no convergence, rejected
/// steps.
pub(crate) fn fixed_notes<R>(fixed: &Fixed<R>, so: &SteadyOptions, notes: &mut Vec<String>) {
    if !fixed.smooth && fixed.converged {
        notes.push(
            "the switching sequence changed between the last two Newton evaluations: a \
             contact grazes and the blow map is not smooth there"
                .to_string(),
        );
    }
    if !fixed.converged {
        notes.push(format!(
            "Newton stopped at residual {:.2e} (tolerance {:.0e})",
            fixed.residual, so.tolerance
        ));
    }
    if fixed.rejected > 0 {
        notes.push(format!(
            "{} Newton step{} did not lower the residual, nor did a backtracking step along it, \
             and {} replaced by march steps (the map is not smooth there: a contact's closing \
             changed between iterates)",
            fixed.rejected,
            if fixed.rejected == 1 { "" } else { "s" },
            if fixed.rejected == 1 { "was" } else { "were" }
        ));
    }
}

/// Fills the levels of `s` from its blows: η the mean, peaks and gaps the largest,
/// `damper_touches_bed` true when every blow touched.
fn levels(mut s: SteadyState) -> SteadyState {
    let b = &s.blows;
    let max = |f: &dyn Fn(&BlowReport) -> f64| b.iter().map(f).fold(0.0_f64, f64::max);
    let ratios: Vec<f64> = b.iter().filter_map(|r| r.energy_ratio).collect();
    s.energy_ratio = ratios.iter().sum::<f64>() / ratios.len().max(1) as f64;
    s.peak_floor_force_n = max(&|r| r.peak_floor_force_n);
    s.peak_bed_acceleration_m_per_s2 = max(&|r| r.peak_bed_acceleration_m_per_s2);
    s.peak_contact_force_slider_bed_n = max(&|r| r.peak_contact_force_slider_bed_n);
    if b.iter().all(|r| r.damper_gap_at_strike_m.is_some()) && !b.is_empty() {
        s.damper_gap_at_strike_m = Some(max(&|r| r.damper_gap_at_strike_m.unwrap_or(0.0)));
        s.damper_touches_bed = Some(
            b.iter()
                .all(|r| r.damper_contact_time_s.is_some_and(|t| t > 0.0)),
        );
    }
    s
}

#[cfg(test)]
mod tests {
    //! The direct steady state against an independent semi-analytic solution of the periodically
    //! struck spring-mounted mass, and against long marches of the examples.

    use super::*;
    use crate::analysis::blows::{run_blows, BlowOptions};
    use crate::model::{Case, Model};

    /// `e^{A t}` by scaling and squaring of a 30-term Taylor series: independent of the
    /// engine's propagators and of [`crate::integrate::expm::expm`].
    fn expm_taylor(a: &[[f64; 4]; 4], t: f64) -> [[f64; 4]; 4] {
        let norm = a
            .iter()
            .map(|r| r.iter().map(|v| (v * t).abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let s = (norm.max(1.0).log2().ceil() as i32 + 2).max(0);
        let h = t / 2f64.powi(s);
        let mul = |x: &[[f64; 4]; 4], y: &[[f64; 4]; 4]| {
            let mut z = [[0.0; 4]; 4];
            for i in 0..4 {
                for j in 0..4 {
                    z[i][j] = (0..4).map(|k| x[i][k] * y[k][j]).sum();
                }
            }
            z
        };
        let mut e = [[0.0; 4]; 4];
        let mut term = [[0.0; 4]; 4];
        for i in 0..4 {
            e[i][i] = 1.0;
            term[i][i] = 1.0;
        }
        let ah: [[f64; 4]; 4] = std::array::from_fn(|i| std::array::from_fn(|j| a[i][j] * h));
        for k in 1..30 {
            term = mul(&term, &ah);
            for i in 0..4 {
                for j in 0..4 {
                    term[i][j] /= k as f64;
                    e[i][j] += term[i][j];
                }
            }
        }
        for _ in 0..s {
            e = mul(&e, &e);
        }
        e
    }

    /// The periodically struck mounted mass solved independently. Bed `u` (mass M on k, dashpot
    /// c = 2ζ√(kM)), slider `z` (m_s) through a linear undamped contact K: while closed
    /// (`δ = z − u > 0`) `w = (u, z, u̇, ż)` moves by `e^{A_c t}`; the contact opens at the first
    /// `t_c > 0` with `δ(t_c) = 0`; then the bed decays freely, `u(τ) = e^{−ζωτ}(u_a cos ω_d τ +
    /// (v_a + ζω u_a)/ω_d sin ω_d τ)`, until the next strike at T. The steady state is the
    /// fixed point of `y = (u, u̇) ↦ F(y)`; its Jacobian is `E_f(T − t_c) Sel E_c(t_c) R`
    /// (the derivative through t_c vanishes: the contact force `K δ(t_c)` is zero there).
    struct Mounted {
        m: f64,
        k: f64,
        zeta: f64,
        ms: f64,
        vs: f64,
        kc: f64,
        t: f64,
    }

    impl Mounted {
        fn a_contact(&self) -> [[f64; 4]; 4] {
            let c = 2.0 * self.zeta * (self.k * self.m).sqrt();
            [
                [0.0, 0.0, 1.0, 0.0],
                [0.0, 0.0, 0.0, 1.0],
                [
                    (-self.k - self.kc) / self.m,
                    self.kc / self.m,
                    -c / self.m,
                    0.0,
                ],
                [self.kc / self.ms, -self.kc / self.ms, 0.0, 0.0],
            ]
        }
        fn apply(e: &[[f64; 4]; 4], w: &[f64; 4]) -> [f64; 4] {
            std::array::from_fn(|i| (0..4).map(|j| e[i][j] * w[j]).sum())
        }
        /// Contact end t_c and the state there, from w0.
        fn contact(&self, w0: &[f64; 4]) -> (f64, [f64; 4]) {
            let a = self.a_contact();
            let delta = |t: f64| {
                let w = Self::apply(&expm_taylor(&a, t), w0);
                w[1] - w[0]
            };
            let wc = ((self.kc / self.ms) + (self.kc / self.m)).sqrt();
            let step = std::f64::consts::PI / wc / 200.0;
            let mut lo = step;
            while delta(lo + step) > 0.0 {
                lo += step;
            }
            let mut hi = lo + step;
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                if delta(mid) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let t = 0.5 * (lo + hi);
            (t, Self::apply(&expm_taylor(&a, t), w0))
        }
        fn free(&self, tau: f64) -> [[f64; 2]; 2] {
            let w = (self.k / self.m).sqrt();
            let wd = w * (1.0 - self.zeta * self.zeta).sqrt();
            let g = (-self.zeta * w * tau).exp();
            let (c, s) = ((wd * tau).cos(), (wd * tau).sin());
            let zw = self.zeta * w;
            [
                [g * (c + zw / wd * s), g * s / wd],
                [g * (-w * w / wd * s), g * (c - zw / wd * s)],
            ]
        }
        /// F(y), its Jacobian, and the slider's exit velocity.
        fn map(&self, y: [f64; 2]) -> ([f64; 2], [[f64; 2]; 2], f64) {
            let w0 = [y[0], y[0], y[1], self.vs];
            let (tc, wc) = self.contact(&w0);
            let ef = self.free(self.t - tc);
            let f = [
                ef[0][0] * wc[0] + ef[0][1] * wc[2],
                ef[1][0] * wc[0] + ef[1][1] * wc[2],
            ];
            let ec = expm_taylor(&self.a_contact(), tc);
            // Sel E_c R: columns for u (u and z both move with u) and u̇.
            let se = [
                [ec[0][0] + ec[0][1], ec[0][2]],
                [ec[2][0] + ec[2][1], ec[2][2]],
            ];
            let jac: [[f64; 2]; 2] = std::array::from_fn(|i| {
                std::array::from_fn(|j| ef[i][0] * se[0][j] + ef[i][1] * se[1][j])
            });
            (f, jac, wc[3])
        }
        fn fixed_point(&self) -> ([f64; 2], [[f64; 2]; 2], f64) {
            let mut y = [0.0, 0.0];
            for _ in 0..30 {
                let (f, j, _) = self.map(y);
                let r = [f[0] - y[0], f[1] - y[1]];
                let a = [[j[0][0] - 1.0, j[0][1]], [j[1][0], j[1][1] - 1.0]];
                let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
                let d = [
                    -(a[1][1] * r[0] - a[0][1] * r[1]) / det,
                    -(-a[1][0] * r[0] + a[0][0] * r[1]) / det,
                ];
                y = [y[0] + d[0], y[1] + d[1]];
            }
            let (_, j, vexit) = self.map(y);
            (y, j, vexit)
        }
    }

    fn mounted_model(p: &Mounted) -> Model {
        let text = format!(
            r#"
name = "spring-mounted mass"
[structure]
reference_mode = 1
[structure.lumped]
damping_ratios = [{}]
masses = [{{ name = "bed", mass = {} }}]
springs = [{{ name = "mount", nodes = ["bed", "ground"], stiffness = {} }}]
floor = ["mount"]
[points]
bed_contact = "bed"
measurement = "bed"
[slider]
mass = {}
velocity = {}
[contact.slider_bed]
law = "linear"
stiffness = {}
damping = 0.0
release = "force"
[simulation]
method = "exact"
duration = 1.0
sample_rate = 20000.0
"#,
            p.zeta, p.m, p.k, p.ms, p.vs, p.kc
        );
        Model::from_text("mounted.toml", text, &[]).unwrap()
    }

    /// The direct steady state of the struck mounted mass equals the independent solution:
    /// the state at the strike and the energy ratio to 1e-9, the multipliers (the eigenvalues
    /// of the one-period Jacobian `E_f(T − t_c) Sel E_c(t_c) R`) to 1e-9. (With a slider of
    /// finite mass the period map is not `e^{A_f T}`: the contact couples the bed to the
    /// slider for t_c, and the impulse depends on the bed's velocity; `e^{A_f T}` is its
    /// m_s → 0 limit.)
    #[test]
    fn steady_state_of_the_struck_mounted_mass_matches_the_closed_form() {
        let (m, k) = (100.0_f64, 1.0e5_f64);
        let period = 2.0 * std::f64::consts::PI / (k / m).sqrt();
        for (zeta, ms, cycles) in [(0.02, 0.01, 5.3), (0.05, 2.0, 3.7), (0.01, 0.5, 2.0)] {
            let p = Mounted {
                m,
                k,
                zeta,
                ms,
                vs: 1.0,
                kc: 1.0e6,
                t: cycles * period,
            };
            let (y, jac, vexit) = p.fixed_point();
            let model = mounted_model(&p);
            let sys = model.impact_system(Case::NoDamper).unwrap();
            let so = SteadyOptions {
                rate_bpm: 60.0 / p.t,
                ..SteadyOptions::default()
            };
            let s = steady_state(&sys, &model.options(), &so).unwrap();
            assert!(s.converged && s.regime == Regime::Period(1), "{s:?}");
            // The fixed point (modal coordinates q = √M u): re-derive it from the report's
            // machine energy at the strike, E = ½ k u² + ½ M u̇².
            let e_closed = 0.5 * k * y[0] * y[0] + 0.5 * m * y[1] * y[1];
            let e = s.blows[0].machine_energy_at_strike_j;
            // The fixed point amplifies a blow's round-off by κ = ‖(I − J)⁻¹‖ ≈ 1/(1 − |μ|)
            // (8.2 at ζ = 1 %, two periods per blow: the multipliers are 0.88, in phase).
            let mu_max = s.multipliers_abs[0];
            let kappa = 1.0 / (1.0 - mu_max);
            assert!(
                ((e - e_closed) / e_closed).abs() < 1e-9 * kappa.max(1.0),
                "ζ {zeta}, m_s {ms}: machine energy at the strike {e} J, closed form {e_closed} J"
            );
            let eta_closed = 1.0 - (vexit / p.vs).powi(2);
            assert!(
                (s.energy_ratio - eta_closed).abs() < 1e-9,
                "ζ {zeta}, m_s {ms}: η {} vs {eta_closed}",
                s.energy_ratio
            );
            let tr = jac[0][0] + jac[1][1];
            let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
            let disc = tr * tr - 4.0 * det;
            let mut mu = if disc < 0.0 {
                vec![det.sqrt(), det.sqrt()]
            } else {
                vec![
                    (0.5 * (tr + disc.sqrt())).abs(),
                    (0.5 * (tr - disc.sqrt())).abs(),
                ]
            };
            mu.sort_by(|a, b| b.total_cmp(a));
            assert_eq!(s.multipliers_abs.len(), 2);
            for (a, b) in s.multipliers_abs.iter().zip(&mu) {
                assert!(
                    (a - b).abs() < 1e-9,
                    "multipliers {:?} vs {mu:?}",
                    s.multipliers_abs
                );
            }
            assert_eq!(s.stable, Some(true));
        }
    }

    /// The path Jacobian of the blow map equals central differences (to 1e-6 of its norm, in
    /// the energy norm's units) on the lumped example: without the damper from rest, and with
    /// the damper at the state after 20 blows (the damper off the bed, the one-way dashpot
    /// switching many times). (From rest with the damper the map is not differentiable: the
    /// damper touches the bed at the strike with zero overlap and zero relative velocity, a
    /// grazing start.)
    /// An iterate evaluated without the levels (the Newton search's) follows the same
    /// trajectory bit for bit as the evaluation with them, and its peaks and dissipated energy
    /// stay empty; the steady blows the result reports carry them.
    #[test]
    fn iterates_without_peaks_follow_the_same_trajectory() {
        let model = example("paper-lumped");
        let sys = model.impact_system(Case::Damper).unwrap();
        let mut o = model.options();
        o.sample_rate = None;
        o.duration = 1.0;
        let x0 = next_strike(&sys, &vec![0.0; 2 * sys.dofs()]);
        let full = integrate::solve_from(&sys, &x0, &o, &mut integrate::NoOutput).unwrap();
        let lean = integrate::solve_from(
            &sys,
            &x0,
            &Options { levels: false, ..o },
            &mut integrate::NoOutput,
        )
        .unwrap();
        assert_eq!(full.x_final, lean.x_final);
        assert!(full.totals.dissipated > 0.0);
        assert_eq!(lean.totals.dissipated, 0.0, "no dashpot work tracked");
        assert_eq!(full.path.len(), lean.path.len());
        let bed = crate::impact::Channel::BedAcceleration;
        assert!(full.totals.peaks.get(bed).abs_peak() > 100.0);
        assert_eq!(lean.totals.peaks.get(bed).abs_peak(), 0.0);
        let s = steady_state(&sys, &model.options(), &SteadyOptions::default()).unwrap();
        let b = &s.blows[0];
        assert!(b.peak_bed_acceleration_m_per_s2 > 100.0, "{b:?}");
        assert!(b.peak_floor_force_n > 0.0, "{b:?}");
    }

    #[test]
    fn path_jacobian_matches_finite_differences() {
        let model = example("paper-lumped");
        let mut failures = Vec::new();
        for (case, start) in [(Case::NoDamper, 0), (Case::NoDamper, 5), (Case::Damper, 20)] {
            let sys = model.impact_system(case).unwrap();
            let so = SteadyOptions::default();
            let mut map = Map::new(&sys, &model.options(), &so).unwrap();
            map.budget = usize::MAX;
            let d = map.dim();
            let mut y = vec![0.0; d];
            for _ in 0..start {
                y = map.eval(&y, 0, false, false).unwrap().p;
            }
            let e = map.eval(&y, 0, true, false).unwrap();
            let jac = e.jac.unwrap();
            let mut worst = 0.0_f64;
            let mut norm = 0.0_f64;
            let mut at = (0, 0);
            for j in 0..d {
                let h = 1e-6 / map.weight[j].sqrt();
                let mut yp = y.clone();
                yp[j] += h;
                let mut ym = y.clone();
                ym[j] -= h;
                let pp = map.eval(&yp, 0, false, false).unwrap().p;
                let pm = map.eval(&ym, 0, false, false).unwrap().p;
                for i in 0..d {
                    // in the energy norm's units: rows by √w_i, columns by 1/√w_j
                    let s = (map.weight[i] / map.weight[j]).sqrt();
                    let fd = (pp[i] - pm[i]) / (2.0 * h) * s;
                    let an = jac[(i, j)] * s;
                    if (fd - an).abs() > worst {
                        worst = (fd - an).abs();
                        at = (i, j);
                    }
                    norm = norm.max(an.abs());
                }
            }
            eprintln!("{case:?} after {start} blows: worst {worst:.3e} at {at:?}, norm {norm:.3e}, {} path points", e.switches.len());
            if worst > 1e-6 * norm.max(1.0) {
                failures.push(format!(
                    "{case:?} after {start} blows: |J − FD| {worst:.3e} at {at:?}, |J| {norm:.3e}"
                ));
            }
        }
        assert!(failures.is_empty(), "{failures:?}");
    }

    /// A period-2 regime: the lumped example at 18.5 blows/min. Its period-1 fixed point is
    /// unstable and a march from rest settles into blows that alternate (the damper touches
    /// the bed in both, for different times, and the floor force alternates). The steady state
    /// is named period-2 with its two blows, and a 400-blow march from rest ends alternating
    /// between the same two levels.
    #[test]
    fn a_period_two_regime_is_found_and_named() {
        let model = example("paper-lumped");
        let sys = model.impact_system(Case::Damper).unwrap();
        let rate = 18.5;
        let s = steady_state(
            &sys,
            &model.options(),
            &SteadyOptions {
                rate_bpm: rate,
                ..SteadyOptions::default()
            },
        )
        .unwrap();
        assert_eq!(s.regime, Regime::Period(2), "{s:?}");
        assert_eq!(s.period_blows, Some(2));
        assert!(s.converged && s.stable == Some(true), "{s:?}");
        assert_eq!(s.blows.len(), 2);
        let (f0, f1) = (s.blows[0].peak_floor_force_n, s.blows[1].peak_floor_force_n);
        assert!(
            (f0 - f1).abs() > 1e-3 * f0.max(f1),
            "blows alike: {f0} {f1}"
        );
        assert_eq!(s.peak_floor_force_n, f0.max(f1));
        let mut o = model.options();
        o.sample_rate = None;
        let march = run_blows(
            &sys,
            &o,
            &BlowOptions {
                blows: 400,
                rate_bpm: rate,
                steady_tolerance: 1e-9,
            },
            false,
        )
        .unwrap();
        let n = march.blows.len();
        let (m0, m1) = (
            march.blows[n - 2].peak_floor_force_n,
            march.blows[n - 1].peak_floor_force_n,
        );
        let pair_ok = |a: f64, b: f64| {
            (a - f0).abs() < 1e-6 * f0 && (b - f1).abs() < 1e-6 * f1
                || (a - f1).abs() < 1e-6 * f1 && (b - f0).abs() < 1e-6 * f0
        };
        assert!(pair_ok(m0, m1), "march ends {m0} {m1}, steady {f0} {f1}");
    }

    fn example(name: &str) -> Model {
        let path = format!("{}/../../examples/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        Model::from_file(path.as_ref(), &[]).unwrap()
    }

    /// On the lumped example at 20, 60 and 120 /min, with and without the damper, the direct
    /// steady state equals the last blow of a 60-blow march to 1e-6 relative in every level,
    /// and costs at most a handful of blow evaluations.
    #[test]
    fn direct_steady_state_equals_a_long_march_on_the_lumped_example() {
        let model = example("paper-lumped");
        for case in [Case::Damper, Case::NoDamper, Case::AddedMass] {
            let sys = model.impact_system(case).unwrap();
            for rate in [20.0, 60.0, 120.0] {
                let s = steady_state(
                    &sys,
                    &model.options(),
                    &SteadyOptions {
                        rate_bpm: rate,
                        ..SteadyOptions::default()
                    },
                )
                .unwrap();
                let b = BlowOptions {
                    blows: 60,
                    rate_bpm: rate,
                    steady_tolerance: 1e-9,
                };
                let mut o = model.options();
                o.sample_rate = None;
                let march = run_blows(&sys, &o, &b, false).unwrap();
                let last = march.blows.last().unwrap();
                let prev = &march.blows[march.blows.len() - 2];
                let what = format!("{case:?} at {rate} /min: {s:?}");
                assert!(s.converged, "{what}");
                // The march is still a geometric tail away from its limit: the next blows add
                // at most |Δ_last| μ/(1 − μ) (μ = |μ|max); the levels must agree to 1e-6 or
                // within twice that tail where the march has not settled that far.
                let mu = s.multipliers_abs[0];
                let close = |a: f64, b: f64, b_prev: f64| {
                    let tail = (b - b_prev).abs() * mu / (1.0 - mu);
                    (a - b).abs() <= (1e-6 * b.abs()).max(2.0 * tail)
                };
                assert!(
                    close(
                        s.peak_floor_force_n,
                        last.peak_floor_force_n,
                        prev.peak_floor_force_n
                    ),
                    "{what}"
                );
                assert!(
                    close(
                        s.peak_bed_acceleration_m_per_s2,
                        last.peak_bed_acceleration_m_per_s2,
                        prev.peak_bed_acceleration_m_per_s2
                    ),
                    "{what}"
                );
                assert!(
                    close(
                        s.energy_ratio,
                        last.energy_ratio.unwrap(),
                        prev.energy_ratio.unwrap()
                    ),
                    "{what}"
                );
                if let Some(g) = s.damper_gap_at_strike_m {
                    let gm = last.damper_gap_at_strike_m.unwrap();
                    assert!((g - gm).abs() <= 1e-6 * gm.abs().max(1e-6), "{what}");
                }
                eprintln!(
                    "{case:?} {rate}/min: {} evaluations, {} , |μ|max {:?}, {:?}",
                    s.map_evaluations,
                    s.regime.name(),
                    s.multipliers_abs.first(),
                    s.residual_history
                );
            }
        }
    }
}
