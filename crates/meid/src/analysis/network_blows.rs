//! A general machine ([`crate::model::network`]) struck at a production stroke rate: the train
//! of blows, and its periodic steady state found directly.
//!
//! # The re-launch rule
//! Blow `k` (`k = 0..N-1`) is struck at `t_k = k T`, `T = 60 / rate` s. The first blow starts
//! from the machine's initial state ([`crate::integrate::network::initial_state`]); every later
//! one from the state the previous blow left at `T`, with every impactor **re-launched**: its
//! velocity set to its configured `velocity`, and its position `z_b` placed so that each of its
//! contacts has its configured gap `g_c` relative to where the other end is *now*: with
//! `δ_c = a_cᵀx − g_c` and `s_c = ±1` the impactor's sign in `a_c` (+1 when it is the contact's
//! first end, the one that strikes),
//!
//! ```text
//! z_b = min_c (−r_c / s_c)  (every s_c = +1),   max_c (−r_c / s_c)  (every s_c = −1),
//! r_c = a_cᵀx − s_c z_b      (the contact's other terms: where the other end is now)
//! ```
//!
//! i.e. the contact that would be most closed gets exactly its configured gap, and no contact
//! of the impactor starts closer than configured (with mixed signs, an impactor between two
//! ends, the first contact's rule is used). Impactors are placed in the model's order (a
//! contact between two impactors sees the earlier one already placed). The structure and the
//! dampers keep their state; the previous blow's impactor is removed with its energy (it has
//! left the die). A blow is the exact engine run over `[0, T]` from that state
//! ([`crate::integrate::network::solve_from`]): with the re-launch at `x = 0` the first blow is
//! exactly `meid simulate` with `duration = T`.
//!
//! # Per blow
//! The **energy ratio** of blow `k` is the general machine's ([`crate::integrate::network`])
//! taken from the strike,
//!
//! ```text
//! η_k = (E_b,k− + W+ − E_b(t_c)) / (KE_imp,k− + W+)
//! ```
//!
//! with `E_b` the bodies' energy (impactors' and dampers' kinetic energies, the dampers'
//! spring energies), `KE_imp,k−` the re-launched impactors' kinetic energy and `W+` the
//! constant forces' work up to the end of the collision `t_c`: the share of the blow's energy
//! that the structure kept or dissipated, with the dampers' energy at the strike removed — the
//! paper machine's per-blow `η_k` ([`super::blows`]) when the machine is the paper's. The end
//! of the collision is the first instant after the strike at which every contact that is not
//! preloaded is open again; a blow whose collision has not ended at the next strike is refused
//! (`--rate-bpm`: the interval is shorter than the collision).
//!
//! Each blow also reports the peak force of every contact, the peak |acceleration| of every
//! named point (the struck point's as `peak_bed_acceleration_m_per_s2`: the point the first
//! impactor's first contact strikes), the peak floor force, and per damper its **gap at the
//! strike** `max(−δ, 0)` to its contact point (its first contact) and whether that contact
//! **touched** (was closed) during the blow.
//!
//! # Steady state
//! The blow map `P: y ↦ y'` acts on the state just before a strike without the impactors,
//! `y = [q; z_d; q̇; ż_d]` (dimension `2·(modes + dampers)`), and its fixed point (of `P^k` for
//! a period-k regime) is found by [`super::steady`]'s search: Newton on `P − I` from rest,
//! globalised by a backtracking step and march steps, then a march seeking a period, then
//! irregular; its multipliers `|eig ∂P^k/∂y|`, stability and blows to settle; the same energy
//! norm (`ω̄_i² q_i² + q̇_i²` per mode, `max(k, m ω_T²) z² + m ż²` per damper, over `Σ m v²` of
//! the impactors). The
//! Jacobian is taken by **forward differences**, `h_j = 1e-7/√w_j` (1e-7 of the blow's energy
//! norm): the general engine has held contacts, rigid impulses and non-linear laws, for which
//! no product of transition matrices holds. Cost: `1 + dim` blows per Newton step
//! (`dim = 2·(modes + dampers)`; 11 on the lumped paper machine, 89 on the 40-mode press with
//! four dampers), against the march's one blow per blow; a linearly converging march needs
//! `ln(tol)/ln|μ|max` blows, so the direct search pays where the slowest multiplier is near 1
//! (a damper creeping back on its one-way dashpot) and the model is small.

use faer::Mat;
use serde::Serialize;

use super::blows::{blow_interval_s, BlowOptions};
use super::steady::{
    check_options, fixed_notes, search, settle, BlowMap, Evaluation, Found, Regime, SteadyOptions,
};
use crate::impact::network::{End, Network};
use crate::integrate::network::{self as engine, ChannelKind, NetSolution};
use crate::integrate::Options;
use crate::model::network::NetworkModel;
use crate::{Error, Result};

/// The most blows a march may ask for (its reports are kept: about 1 kB each).
pub const MAX_BLOWS: usize = 100_000;

/// A contact's peak force in one blow.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ContactPeak {
    pub name: String,
    /// Largest compressive force (N).
    pub peak_force_n: f64,
}

/// A named point's peak |acceleration| in one blow.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PointPeak {
    pub name: String,
    pub peak_acceleration_m_per_s2: f64,
}

/// A damper in one blow.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DamperBlow {
    pub name: String,
    /// `max(−δ, 0)` of its contact at the strike (m): 0 when it is back on its point.
    pub gap_at_strike_m: f64,
    /// Time its contact was closed during the blow (s).
    pub contact_time_s: f64,
    /// Its contact closed during the blow.
    pub touched: bool,
}

/// What one blow of a general machine did (module docs).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NetBlowReport {
    /// 1-based blow number.
    pub blow: usize,
    /// Strike time (s).
    pub start_s: f64,
    /// η_k (module docs); `None` if the collision did not end within the blow.
    pub energy_ratio: Option<f64>,
    /// End of the collision after the strike (s).
    pub collision_end_s: Option<f64>,
    /// The structure's energy `½Σ(q̇² + ω²q²)` at the strike (J): what earlier blows left.
    pub machine_energy_at_strike_j: f64,
    /// Peak |acceleration| of the struck point (m/s²).
    pub peak_bed_acceleration_m_per_s2: f64,
    /// Peak force to the floor (N); `None` when nothing carries force to it.
    pub peak_floor_force_n: Option<f64>,
    pub contacts: Vec<ContactPeak>,
    pub points: Vec<PointPeak>,
    pub dampers: Vec<DamperBlow>,
}

impl NetBlowReport {
    /// Every damper touched its point in this blow (true without dampers).
    pub fn dampers_touch(&self) -> bool {
        self.dampers.iter().all(|d| d.touched)
    }
}

/// A marched train.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NetBlowsRun {
    pub rate_bpm: f64,
    pub interval_s: f64,
    pub bed_point: String,
    pub blows: Vec<NetBlowReport>,
    /// The first blow (1-based) from which every later blow's energy ratio, floor force and
    /// struck-point acceleration stay within `steady_tolerance` (relative) of its
    /// predecessor's; `None` if the train has not settled.
    pub settled_from_blow: Option<usize>,
}

/// A damper in the steady regime.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DamperTouch {
    pub name: String,
    /// Touches its point in every blow of the period.
    pub touches: bool,
    /// Largest gap at a strike over the period (m).
    pub gap_at_strike_m: f64,
}

/// The periodic steady state of a general machine's train (module docs); the fields of the
/// paper machine's [`super::steady::SteadyState`] with `dampers_touch` per damper.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NetSteadyState {
    pub rate_bpm: f64,
    pub interval_s: f64,
    pub converged: bool,
    pub residual: f64,
    pub map_evaluations: usize,
    pub regime: Regime,
    pub period_blows: Option<usize>,
    pub method: &'static str,
    /// Always "finite-differences" (module docs).
    pub jacobian: &'static str,
    /// Mean η over the blows of the period.
    pub energy_ratio: f64,
    /// Largest peaks over the period.
    pub peak_floor_force_n: Option<f64>,
    pub peak_bed_acceleration_m_per_s2: f64,
    /// The struck point whose acceleration is `peak_bed_acceleration_m_per_s2`.
    pub bed_point: String,
    pub contacts: Vec<ContactPeak>,
    pub points: Vec<PointPeak>,
    /// Largest gap of any damper at a strike (m); `None` without dampers.
    pub damper_gap_at_strike_m: Option<f64>,
    /// Every damper touches its point in every blow of the period; `None` without dampers.
    pub damper_touches_bed: Option<bool>,
    pub dampers_touch: Vec<DamperTouch>,
    pub multipliers_abs: Vec<f64>,
    pub stable: Option<bool>,
    pub periods_to_settle: Option<f64>,
    pub smooth: bool,
    pub blows: Vec<NetBlowReport>,
    pub notes: Vec<String>,
    pub residual_history: Vec<(char, f64)>,
    /// The state `y = [q; z_d; q̇; ż_d]` just before the first of [`Self::blows`] (the fixed
    /// point of `P^k`, or for an irregular train the state before its last marched blows).
    #[serde(skip)]
    pub strike_state: Vec<f64>,
}

impl NetSteadyState {
    /// The train settled and every damper touches in every blow of the period.
    pub fn dampers_return(&self) -> bool {
        self.converged && self.damper_touches_bed != Some(false)
    }

    /// A study's metric ([`super::network_study::metrics`]'s column names) of the steady blow:
    /// `energy_ratio`, `floor_force_n`, `peak_acceleration_m_per_s2:POINT`,
    /// `peak_force_n:CONTACT`.
    pub fn metric(&self, column: &str) -> Option<f64> {
        if column == "energy_ratio" {
            return self.energy_ratio.is_finite().then_some(self.energy_ratio);
        }
        if column == "floor_force_n" {
            return self.peak_floor_force_n;
        }
        if let Some(p) = column.strip_prefix("peak_acceleration_m_per_s2:") {
            return self
                .points
                .iter()
                .find(|q| q.name == p)
                .map(|q| q.peak_acceleration_m_per_s2);
        }
        if let Some(c) = column.strip_prefix("peak_force_n:") {
            return self
                .contacts
                .iter()
                .find(|q| q.name == c)
                .map(|q| q.peak_force_n);
        }
        None
    }
}

/// The blow map of a general machine (module docs).
struct NetMap<'a> {
    net: &'a Network,
    opts: Options,
    rate_bpm: f64,
    /// Indices of `y` in the full state `X = [x; ẋ]`.
    keep: Vec<usize>,
    weight: Vec<f64>,
    /// The impactors' body indices.
    impactors: Vec<usize>,
    /// Per suspension, its damper's first contact.
    damper_contact: Vec<Option<usize>>,
    bed_point: String,
    evaluations: usize,
    budget: usize,
    history: Vec<(char, f64)>,
}

impl<'a> NetMap<'a> {
    /// The steady search's budget of blow evaluations: `so.max_evaluations`, and at least
    /// eight Newton steps (each `1 + d` blows here, forward differences) besides the march's
    /// reserve of 84, so a machine with many modes (the 40-mode press with four dampers:
    /// d = 90) is not cut off after three steps.
    fn with_steady_budget(mut self, so: &SteadyOptions) -> Self {
        self.budget = so.max_evaluations.max(8 * self.step_cost() + 84).max(2);
        self
    }

    /// The map of `net`'s train at `rate_bpm`, with no limit on blow evaluations (a steady
    /// search sets its own: [`NetMap::with_steady_budget`]).
    fn new(net: &'a Network, user: &Options, rate_bpm: f64) -> Result<Self> {
        let interval = blow_interval_s(rate_bpm).map_err(rate_error)?;
        let nd = net.dofs();
        let n = net.n_modes();
        let impactors: Vec<usize> = (0..net.bodies.len())
            .filter(|b| !net.suspensions.iter().any(|s| s.body == *b))
            .collect();
        let keep: Vec<usize> = (0..2 * nd)
            .filter(|&i| {
                let j = i % nd;
                j < n || !impactors.contains(&(j - n))
            })
            .collect();
        let e2: f64 = impactors
            .iter()
            .map(|&b| net.bodies[b].mass * net.bodies[b].velocity.powi(2))
            .sum();
        if !(e2 > 0.0 && e2.is_finite()) {
            return Err(Error::invalid(
                "impactor.velocity",
                "a blow train needs an impactor with kinetic energy (a velocity ≠ 0)",
            ));
        }
        let w_min = 2.0 * std::f64::consts::PI / interval;
        let weight = keep
            .iter()
            .map(|&i| {
                let (j, vel) = (i % nd, i >= nd);
                let w = if j < n {
                    if vel {
                        1.0
                    } else {
                        net.structure.omega_rad_per_s[j].max(w_min).powi(2)
                    }
                } else {
                    let b = j - n;
                    let m = net.bodies[b].mass;
                    let k = net
                        .suspensions
                        .iter()
                        .filter(|s| s.body == b)
                        .map(|s| s.stiffness)
                        .sum::<f64>();
                    if vel {
                        m
                    } else {
                        k.max(m * w_min * w_min)
                    }
                };
                w / e2
            })
            .collect();
        let damper_contact = net
            .suspensions
            .iter()
            .map(|s| {
                net.contacts
                    .iter()
                    .position(|c| c.ends.contains(&End::Body(s.body)))
            })
            .collect();
        let bed_point = impactors
            .iter()
            .find_map(|&b| {
                net.contacts
                    .iter()
                    .find_map(|c| match (&c.ends[0], &c.ends[1]) {
                        (End::Body(x), End::Point(p)) | (End::Point(p), End::Body(x))
                            if *x == b =>
                        {
                            Some(p.clone())
                        }
                        _ => None,
                    })
            })
            .or_else(|| net.structure.points.keys().next().cloned())
            .unwrap_or_default();
        let opts = Options {
            duration: interval,
            sample_rate: None,
            stop_at_collision_end: false,
            ..*user
        };
        Ok(Self {
            net,
            opts,
            rate_bpm,
            keep,
            weight,
            impactors,
            damper_contact,
            bed_point,
            evaluations: 0,
            budget: usize::MAX,
            history: Vec::new(),
        })
    }

    /// The full state at the strike from `y`: the impactors re-launched (module docs).
    fn embed(&self, y: &[f64]) -> Vec<f64> {
        let mut x = vec![0.0; 2 * self.net.dofs()];
        for (&i, &v) in self.keep.iter().zip(y) {
            x[i] = v;
        }
        relaunch(self.net, &self.impactors, &mut x);
        x
    }

    fn select(&self, x: &[f64]) -> Vec<f64> {
        self.keep.iter().map(|&i| x[i]).collect()
    }

    /// One blow from the full state `x0` (blow `k`, struck at `k T`).
    fn blow(&self, x0: Vec<f64>, k: usize) -> Result<(NetSolution, NetBlowReport)> {
        let sol = engine::solve_from(self.net, x0, &self.opts)?;
        if sol.collision_end.is_none() {
            return Err(self.too_short(&sol.x0, k));
        }
        let report = blow_report(self, &sol, k);
        Ok((sol, report))
    }

    /// The error of a blow whose collision outlasts the interval, with its duration when
    /// it ends within 100 intervals.
    fn too_short(&self, x0: &[f64], k: usize) -> Error {
        let long = Options {
            duration: 100.0 * self.opts.duration,
            stop_at_collision_end: true,
            ..self.opts
        };
        let t_c = engine::solve_from(self.net, x0.to_vec(), &long)
            .ok()
            .and_then(|s| s.collision_end.map(|c| c.t));
        let valid = t_c.map_or(String::new(), |t| {
            format!(
                " (it lasts {t:.6} s: the rate must be ≤ {:.4} blows/min)",
                60.0 / t
            )
        });
        rate_error(Error::invalid(
            "rate_bpm",
            format!(
                "the interval 60/{} = {:.6} s is shorter than the collision of blow {}: a contact that closed is still closed at the next strike{valid}",
                crate::num(self.rate_bpm),
                self.opts.duration,
                k + 1
            ),
        ))
    }
}

/// Re-launches the impactors in `x` (module docs).
fn relaunch(net: &Network, impactors: &[usize], x: &mut [f64]) {
    let nd = net.dofs();
    let n = net.n_modes();
    for &b in impactors {
        let i = n + b;
        x[nd + i] = net.bodies[b].velocity;
        let mut cands: Vec<(f64, f64)> = Vec::new();
        for (c, link) in net.contacts.iter().enumerate() {
            if !link.ends.contains(&End::Body(b)) {
                continue;
            }
            let a = net.contact_vector(c);
            let s = a[i];
            if s == 0.0 {
                continue;
            }
            let rest: f64 = (0..nd)
                .filter(|&j| j != i)
                .map(|j| a[j] * x[j])
                .sum::<f64>();
            cands.push((s, -rest / s));
        }
        let Some(&(s0, z0)) = cands.first() else {
            continue;
        };
        x[i] = if cands.iter().all(|(s, _)| *s > 0.0) {
            cands.iter().map(|(_, z)| *z).fold(z0, f64::min)
        } else if cands.iter().all(|(s, _)| *s < 0.0) {
            cands.iter().map(|(_, z)| *z).fold(z0, f64::max)
        } else {
            let _ = s0;
            z0
        };
    }
}

/// Maps an error naming `rate_bpm` to the option `--rate-bpm`.
fn rate_error(e: Error) -> Error {
    match e {
        Error::InvalidValue { field, message } if field == "rate_bpm" => Error::InvalidValue {
            field: "--rate-bpm".into(),
            message,
        },
        e => e,
    }
}

/// The levels of blow `k` from its run.
fn blow_report(map: &NetMap, sol: &NetSolution, k: usize) -> NetBlowReport {
    let net = map.net;
    let nd = net.dofs();
    let n = net.n_modes();
    let peak = |kind: &ChannelKind| -> f64 {
        sol.channels
            .iter()
            .find(|c| &c.kind == kind)
            .map_or(0.0, |c| c.extremes.peak().0.abs())
    };
    let contacts = net
        .contacts
        .iter()
        .enumerate()
        .map(|(c, link)| ContactPeak {
            name: link.name.clone(),
            peak_force_n: sol
                .channels
                .iter()
                .find(|ch| ch.kind == ChannelKind::ContactForce(c))
                .map_or(0.0, |ch| ch.extremes.max.max(0.0)),
        })
        .collect();
    let points: Vec<PointPeak> = net
        .structure
        .points
        .keys()
        .map(|p| PointPeak {
            name: p.clone(),
            peak_acceleration_m_per_s2: peak(&ChannelKind::PointAcceleration(p.clone())),
        })
        .collect();
    let dampers = net
        .suspensions
        .iter()
        .zip(&map.damper_contact)
        .map(|(s, c)| {
            let (gap, time) = c.map_or((0.0, 0.0), |c| {
                ((-net.overlap(c, &sol.x0).0).max(0.0), sol.closed_time_s[c])
            });
            DamperBlow {
                name: s.name.clone(),
                gap_at_strike_m: gap,
                contact_time_s: time,
                touched: time > 0.0,
            }
        })
        .collect();
    let machine_energy = 0.5
        * (0..n)
            .map(|i| {
                sol.x0[nd + i].powi(2) + (net.structure.omega_rad_per_s[i] * sol.x0[i]).powi(2)
            })
            .sum::<f64>();
    NetBlowReport {
        blow: k + 1,
        start_s: k as f64 * map.opts.duration,
        energy_ratio: sol.energy_ratio,
        collision_end_s: sol.collision_end.as_ref().map(|c| c.t),
        machine_energy_at_strike_j: machine_energy,
        peak_bed_acceleration_m_per_s2: peak(&ChannelKind::PointAcceleration(
            map.bed_point.clone(),
        )),
        peak_floor_force_n: net
            .has_floor_force()
            .then(|| peak(&ChannelKind::FloorForce)),
        contacts,
        points,
        dampers,
    }
}

impl BlowMap for NetMap<'_> {
    type Report = NetBlowReport;
    type Switches = Vec<(
        crate::impact::network::NetMode,
        crate::impact::network::NetMode,
    )>;
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
        _peaks: bool,
    ) -> Result<Evaluation<NetBlowReport, Self::Switches>> {
        self.evaluations += 1;
        let (sol, report) = self.blow(self.embed(y), k)?;
        let p = self.select(&sol.x_final);
        let jac = if with_jac {
            let d = self.dim();
            let mut jac = Mat::<f64>::zeros(d, d);
            for j in 0..d {
                let h = 1e-7 / self.weight[j].sqrt();
                let mut yj = y.to_vec();
                yj[j] += h;
                self.evaluations += 1;
                let sj = engine::solve_from(self.net, self.embed(&yj), &self.opts)?;
                let pj = self.select(&sj.x_final);
                for i in 0..d {
                    jac[(i, j)] = (pj[i] - p[i]) / h;
                }
            }
            Some(jac)
        } else {
            None
        };
        let switches = sol.events.iter().map(|(_, a, b)| (*a, *b)).collect();
        Ok(Evaluation {
            p,
            jac,
            report,
            switches,
        })
    }
    fn evaluations(&self) -> usize {
        self.evaluations
    }
    fn step_cost(&self) -> usize {
        1 + self.dim()
    }
    fn budget(&self) -> usize {
        self.budget
    }
    fn history(&mut self) -> &mut Vec<(char, f64)> {
        &mut self.history
    }
    fn floor_force(report: &NetBlowReport) -> f64 {
        report.peak_floor_force_n.unwrap_or(0.0)
    }
}

/// Marches `b.blows` blows of `model` at `b.rate_bpm` (module docs).
pub fn run_blows(model: &NetworkModel, b: &BlowOptions) -> Result<NetBlowsRun> {
    if b.blows == 0 || b.blows > MAX_BLOWS {
        return Err(Error::invalid(
            "--blows",
            format!("must lie in 1..={MAX_BLOWS} (got {})", b.blows),
        ));
    }
    let net = &model.network;
    let map = NetMap::new(net, &model.options()?, b.rate_bpm)?;
    let mut x = engine::initial_state(net)?;
    let mut blows = Vec::with_capacity(b.blows);
    for k in 0..b.blows {
        if k > 0 {
            relaunch(net, &map.impactors, &mut x);
        }
        let (sol, report) = map.blow(x, k)?;
        blows.push(report);
        x = sol.x_final;
    }
    let settled_from_blow = settled(&blows, b.steady_tolerance);
    Ok(NetBlowsRun {
        rate_bpm: b.rate_bpm,
        interval_s: map.opts.duration,
        bed_point: map.bed_point.clone(),
        blows,
        settled_from_blow,
    })
}

/// The first blow from which every later one stays within `tol` of its predecessor.
fn settled(blows: &[NetBlowReport], tol: f64) -> Option<usize> {
    let change = |a: f64, b: f64| {
        let s = a.abs().max(b.abs());
        if s == 0.0 {
            0.0
        } else {
            (a - b).abs() / s
        }
    };
    let alike = |p: &NetBlowReport, q: &NetBlowReport| {
        change(
            p.energy_ratio.unwrap_or(f64::NAN),
            q.energy_ratio.unwrap_or(f64::NAN),
        ) <= tol
            && change(
                p.peak_floor_force_n.unwrap_or(0.0),
                q.peak_floor_force_n.unwrap_or(0.0),
            ) <= tol
            && change(
                p.peak_bed_acceleration_m_per_s2,
                q.peak_bed_acceleration_m_per_s2,
            ) <= tol
    };
    if blows.len() < 2 {
        return None;
    }
    let mut from = None;
    for k in (1..blows.len()).rev() {
        if alike(&blows[k - 1], &blows[k]) {
            from = Some(k);
        } else {
            break;
        }
    }
    from
}

/// The direct periodic steady state of `model`'s train at `so.rate_bpm` (module docs).
pub fn steady_state(model: &NetworkModel, so: &SteadyOptions) -> Result<NetSteadyState> {
    check_options(so).map_err(rate_error)?;
    let net = &model.network;
    let mut map = NetMap::new(net, &model.options()?, so.rate_bpm)?.with_steady_budget(so);
    let mut notes = Vec::new();
    let found = search(&mut map, so, !net.suspensions.is_empty(), &mut notes)?;
    let (blows, converged, residual, regime, method, mu, smooth, strike_state) = match found {
        Found::Periodic {
            fixed,
            k,
            mu,
            method,
        } => {
            fixed_notes(&fixed, so, &mut notes);
            (
                fixed.reports,
                fixed.converged,
                fixed.residual,
                Regime::Period(k),
                method,
                mu,
                fixed.smooth,
                fixed.y,
            )
        }
        Found::Irregular {
            tail,
            residual,
            strike_state,
        } => (
            tail,
            false,
            residual,
            Regime::Irregular,
            "marching",
            Vec::new(),
            false,
            strike_state,
        ),
    };
    let mu_max = mu.first().copied();
    let period = match regime {
        Regime::Period(k) => Some(k),
        Regime::Irregular => None,
    };
    let mut s = NetSteadyState {
        rate_bpm: so.rate_bpm,
        interval_s: map.opts.duration,
        converged,
        residual,
        map_evaluations: map.evaluations,
        regime,
        period_blows: period,
        method,
        jacobian: "finite-differences",
        energy_ratio: 0.0,
        peak_floor_force_n: None,
        peak_bed_acceleration_m_per_s2: 0.0,
        bed_point: map.bed_point.clone(),
        contacts: Vec::new(),
        points: Vec::new(),
        damper_gap_at_strike_m: None,
        damper_touches_bed: None,
        dampers_touch: Vec::new(),
        stable: period.map(|_| mu_max.is_none_or(|m| m < 1.0)),
        periods_to_settle: mu_max.and_then(settle),
        multipliers_abs: mu,
        smooth,
        blows,
        notes,
        residual_history: std::mem::take(&mut map.history),
        strike_state,
    };
    levels(&mut s);
    Ok(s)
}

/// The steady state of `model` at `rate_bpm` (default settings) for a study's point or design:
/// an error, naming the regime and residual, when the train did not settle (the point has no
/// value then).
pub fn settled_steady_state(model: &NetworkModel, rate_bpm: f64) -> Result<NetSteadyState> {
    let so = SteadyOptions {
        rate_bpm,
        ..SteadyOptions::default()
    };
    let s = steady_state(model, &so)?;
    if !s.converged {
        return Err(Error::numerical(
            "steady state",
            format!(
                "the train at {rate_bpm} /min did not settle ({}, residual {:.2e})",
                s.regime.name(),
                s.residual
            ),
        ));
    }
    Ok(s)
}

/// The steady levels from the blows of the period: η the mean, peaks and gaps the largest,
/// a damper touches when it touched in every blow.
fn levels(s: &mut NetSteadyState) {
    let b = &s.blows;
    let max = |f: &dyn Fn(&NetBlowReport) -> f64| b.iter().map(f).fold(0.0_f64, f64::max);
    let ratios: Vec<f64> = b.iter().filter_map(|r| r.energy_ratio).collect();
    s.energy_ratio = ratios.iter().sum::<f64>() / ratios.len().max(1) as f64;
    s.peak_floor_force_n = b
        .first()
        .and_then(|f| f.peak_floor_force_n)
        .map(|_| max(&|r| r.peak_floor_force_n.unwrap_or(0.0)));
    s.peak_bed_acceleration_m_per_s2 = max(&|r| r.peak_bed_acceleration_m_per_s2);
    if let Some(first) = b.first() {
        s.contacts = (0..first.contacts.len())
            .map(|c| ContactPeak {
                name: first.contacts[c].name.clone(),
                peak_force_n: max(&|r| r.contacts[c].peak_force_n),
            })
            .collect();
        s.points = (0..first.points.len())
            .map(|p| PointPeak {
                name: first.points[p].name.clone(),
                peak_acceleration_m_per_s2: max(&|r| r.points[p].peak_acceleration_m_per_s2),
            })
            .collect();
        s.dampers_touch = (0..first.dampers.len())
            .map(|d| DamperTouch {
                name: first.dampers[d].name.clone(),
                touches: b.iter().all(|r| r.dampers[d].touched),
                gap_at_strike_m: max(&|r| r.dampers[d].gap_at_strike_m),
            })
            .collect();
        if !s.dampers_touch.is_empty() {
            s.damper_gap_at_strike_m = Some(
                s.dampers_touch
                    .iter()
                    .map(|d| d.gap_at_strike_m)
                    .fold(0.0, f64::max),
            );
            s.damper_touches_bed = Some(s.dampers_touch.iter().all(|d| d.touches));
        }
    }
}

/// The stroke rate: `--rate-bpm`, else the file's `[production] rate_bpm`, else 60; checked
/// (an error names `--rate-bpm`).
pub fn stroke_rate(model: &NetworkModel, given: Option<f64>) -> Result<f64> {
    let r = given
        .or_else(|| model.spec.production.as_ref().map(|p| p.rate_bpm))
        .unwrap_or(60.0);
    check_rate(r)?;
    Ok(r)
}

/// A stroke rate must be a finite number > 0 blows/min (an error names `--rate-bpm`).
pub fn check_rate(r: f64) -> Result<()> {
    if !(r.is_finite() && r > 0.0) {
        return Err(Error::invalid(
            "--rate-bpm",
            format!(
                "the stroke rate must be a finite number > 0 blows per minute (got {})",
                crate::num(r)
            ),
        ));
    }
    Ok(())
}

/// The sentence on top: whether every damper returns between blows in the steady regime.
pub fn verdict(s: &NetSteadyState) -> String {
    let rate = s.rate_bpm;
    let levels = format!(
        "{}, energy ratio {:.4}, peak acceleration at {} {:.4} m/s²{}",
        s.regime.name(),
        s.energy_ratio,
        s.bed_point,
        s.peak_bed_acceleration_m_per_s2,
        s.peak_floor_force_n
            .map_or(String::new(), |f| format!(", floor force {f:.4} N"))
    );
    if !s.converged {
        return format!(
            "At {rate} blows/min the train did not settle within {} blow evaluations ({levels}, an estimate).",
            s.map_evaluations
        );
    }
    let away: Vec<&str> = s
        .dampers_touch
        .iter()
        .filter(|d| !d.touches)
        .map(|d| d.name.as_str())
        .collect();
    if s.dampers_touch.is_empty() {
        format!(
            "At {rate} blows/min the machine (no damper) settles into the steady blow: {levels}."
        )
    } else if away.is_empty() {
        format!("At {rate} blows/min every damper returns between blows: each touches its point in every steady blow ({levels}).")
    } else {
        format!(
            "At {rate} blows/min {} of {} dampers do not return between blows ({}): in the steady blow they no longer touch their points (largest gap at the strike {:.4} mm; {levels}).",
            away.len(),
            s.dampers_touch.len(),
            away.join(", "),
            s.damper_gap_at_strike_m.unwrap_or(0.0) * 1e3
        )
    }
}

/// `meid blows GENERAL.toml --steady --json`'s object (also Python's `meid.blows` of a
/// machine): the machine kind, the rate and interval, the [`verdict`] and the steady state.
pub fn steady_object(s: &NetSteadyState) -> serde_json::Value {
    serde_json::json!({
        "machine": "general",
        "rate_bpm": s.rate_bpm,
        "interval_s": s.interval_s,
        "verdict": verdict(s),
        "steady_state": s,
    })
}
