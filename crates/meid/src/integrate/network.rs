//! Exact event-driven propagation of a general impact machine ([`crate::impact::network`]).
//!
//! Between switches a mode `σ` is `M ẍ + C_σ ẋ + K_σ x = f_σ` (the forcing `f_σ` carries the
//! impactors' constant forces and the closed contacts' gaps), propagated in closed form by
//! [`Propagator::shared_forced`] (built once per mode met, kept for the run). Each stretch:
//!
//! 1. the first sign change of any indicator (overlaps `a_cᵀx − g_c`, forces `K_c δ + C_c δ̇`
//!    of force-release contacts, relative velocities of one-way dashpots), all searched together
//!    over common growing windows ([`super::roots`]) to 1e-13 of the fastest period;
//! 2. exact extremes of every channel (contact forces, suspension spring and dashpot forces,
//!    displacement / velocity / acceleration of every named point, body motions, the floor
//!    force) on the closed form ([`super::peaks`]), the dissipated energy `∫ẋᵀC_σẋ dt`
//!    (closed form), and per closed contact its impulse `∫f dt` and dissipation `∫C δ̇² dt`;
//! 3. the new mode at the switch: the side of each indicator just after it is the sign of its
//!    first non-vanishing derivative `ℓᵀX⁽ᵏ⁾` under the candidate mode's dynamics, and candidate
//!    modes are iterated to a fixed point. All indicators are decided together, so switches
//!    that fall on the same instant (two contacts closing at once) are resolved in one step.
//!
//! A force-release contact that opens with `δ > 0` takes its elastic energy `K δ²/2` with it
//! (booked as dissipated, in the run's total and in the impact's row); one that closes again
//! at `δ > 0` (its force `K δ + C δ̇` rising through zero before the overlap has returned to
//! zero, as a body settling under a constant force does) gets `K δ²/2` back (booked as
//! negative dissipation), as the paper's engines do.
//!
//! # Resting contact
//! A contact rests when it stays closed with its force positive: a body at rest on a support
//! under a constant force, a damper pressed on by a preload. Every contact is held that way by
//! the rules above, with nothing added: its closed mode's closed form is exact over any span,
//! and the search of step 1 finds no sign change of its indicators (overlap and force stay
//! positive), so the run goes to its end in one stretch, without events or steps. Bounces that
//! accumulate (a body falling onto a damped contact under a constant force) end after finitely
//! many: a landing speed `v` is multiplied by about `e` per bounce, and below a landing speed of
//! the order of `F/(m ω)` (`ω = √(K/m)`) the contact's force no longer returns to zero (force
//! release), or its overlap no longer does (overlap release, `ζ > 0`): the body stays on,
//! after about `ln(v₀ ω m/F)/ln(1/e)` bounces, at the accumulation time of the rigid limit,
//! `√(2h/g)(1 + e)/(1 − e)` for a drop from rest at height `h` (`g = F/m`), within `O(1/ω)`
//! per bounce. An undamped contact (`e = 1`) never comes to rest, as a rigid elastic one
//! would not.
//!
//! # Initial state
//! Velocities are the impactors' (dampers start at rest). Without a preloaded contact every
//! displacement starts at 0 (the impactors touch, or stand off by their gaps). With preloaded
//! contacts (`g < 0`) the displacements are the static equilibrium
//! `K_p x = f_p` of the mode `p` in which exactly the preloaded contacts are closed (forcing:
//! the preloads `K_c g_c a_c` and the constant forces); a direction `K_p` does not hold (a free
//! impactor) is left at 0 and its constant force accelerates it. A preload is refused when, at
//! that equilibrium, its contact would pull or carry no force (nothing holds its ends against
//! it), and so is an open contact that the equilibrium makes overlap ([`initial_state`]).
//!
//! # Energy
//! `E = ½ẋᵀMẋ + ½Σω_i²q_i² + Σ_s ½k_sδ_s² + Σ_{closed} ½K_cδ_c²`; with `W` the work of the
//! constant forces and `D` the energy dissipated, a run must keep
//! `|E(0) + W − E(t) − D| ≤ 1e-9 (E(0) + |W|)` (the bound of the paper's exact runs), at the
//! end of the collision and of the run; otherwise it is an error.
//!
//! The **energy ratio** is the paper's `E_p+/E_s−` (Eqs. 10-11) generalised: at the end of
//! the collision (the first instant, after a contact that was not preloaded has closed, at
//! which every such contact is open again),
//!
//! ```text
//! ratio = (E_b(0) + W+ − E_b(t+)) / (KE_b(0) + W+)
//! ```
//!
//! with `E_b` the bodies' energy (kinetic energies and suspension spring energies: the paper's
//! `E_s + E_d`), `KE_b(0)` their initial kinetic energy and `W+` the constant forces' work up
//! to then: the share of the energy put in that the structure kept or dissipated.

use std::collections::HashMap;
use std::rc::Rc;

use faer::Mat;

use super::exact::{dissipated, exp_integral, first_switch, Lifted, GL_W, GL_X};
use super::peaks::{self, Extremes};
use super::propagator::{Functional, Propagator, Segment};
use super::roots::{Scalar, Search, SearchOptions};
use super::Options;
use crate::impact::network::{dot, End, NetIndicator, NetMode, Network};
use crate::{Error, Result};

/// Highest derivative order consulted when deciding an indicator's side.
const K_MAX: usize = 8;
/// The energy-balance residual an exact run must stay within (relative).
pub const RESIDUAL_BOUND: f64 = 1e-9;

/// What a response channel measures.
#[derive(Debug, Clone, PartialEq)]
pub enum ChannelKind {
    /// Force of contact `c` (N, compressive positive).
    ContactForce(usize),
    /// Spring force `k_s δ_s` of suspension `j` (N).
    SpringForce(usize),
    /// Dashpot force `c_s δ̇_s` of suspension `j` while it acts (N).
    DashpotForce(usize),
    /// Displacement (m), velocity (m/s), acceleration (m/s²) of a named structure point.
    PointDisplacement(String),
    PointVelocity(String),
    PointAcceleration(String),
    /// Displacement (m) and velocity (m/s) of body `b`.
    BodyDisplacement(usize),
    BodyVelocity(usize),
    /// The force to the floor (N): the structure's ground reactions, suspensions anchored to
    /// the ground and contacts with the ground.
    FloorForce,
}

/// A response channel and its exact extremes over the run.
#[derive(Debug, Clone, PartialEq)]
pub struct NetChannel {
    pub kind: ChannelKind,
    pub extremes: Extremes,
}

/// One closing of one contact (the per-impact table).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ImpactRow {
    /// The contact's name.
    pub contact: String,
    pub start_s: f64,
    /// Closing speed `δ̇` when the contact closed (m/s).
    pub approach_velocity_m_per_s: f64,
    pub peak_force_n: f64,
    pub peak_time_s: f64,
    /// Time closed (s); up to the end of the run for a contact still closed then.
    pub duration_s: f64,
    /// `∫ f dt` while closed (N·s).
    pub impulse_n_s: f64,
    /// Energy the contact dissipated (J): `∫ C δ̇² dt`, plus `K δ²/2` when it lets go at
    /// `δ > 0` (force release).
    pub dissipated_j: f64,
    /// Separating speed `−δ̇` when it opened (m/s); `None` while still closed.
    pub exit_velocity_m_per_s: Option<f64>,
    /// `exit / approach`; `None` without both.
    pub restitution: Option<f64>,
}

/// The energies at the end of the collision.
#[derive(Debug, Clone, PartialEq)]
pub struct NetCollisionEnd {
    pub t: f64,
    pub x: Vec<f64>,
    /// Work of the constant forces up to then (J).
    pub force_work_j: f64,
    pub dissipated_j: f64,
}

/// A finished run.
#[derive(Debug, Clone)]
pub struct NetSolution {
    pub x0: Vec<f64>,
    pub mode0: NetMode,
    pub t_final: f64,
    pub x_final: Vec<f64>,
    pub mode_final: NetMode,
    /// Switching events `(t, from, to)`.
    pub events: Vec<(f64, NetMode, NetMode)>,
    pub collision_end: Option<NetCollisionEnd>,
    pub channels: Vec<NetChannel>,
    /// Time each contact was closed (s).
    pub closed_time_s: Vec<f64>,
    pub impacts: Vec<ImpactRow>,
    pub dissipated_j: f64,
    pub force_work_j: f64,
    /// Energy-balance residuals at the end of the collision (if it ended) and of the run.
    pub residual_collision_end: Option<f64>,
    pub residual_run_end: f64,
    /// The energy ratio (module documentation); `None` if the collision did not end.
    pub energy_ratio: Option<f64>,
}

/// A channel's affine functional `[ℓ; ℓ₀]` and that of its slope.
type ChannelVectors = (Vec<f64>, Vec<f64>);

/// The first-order data of one mode, and its closed form once built.
struct ModeData {
    /// `A_σ` column-major (`n × n`, `n = 2·dofs`).
    a: Vec<f64>,
    /// `b_σ = [0; M⁻¹f_σ]`.
    b: Vec<f64>,
    k: Mat<f64>,
    c: Mat<f64>,
    f: Vec<f64>,
    prop: Option<Rc<Propagator>>,
    /// Per channel `(ℓ, ℓ_slope)` (both of length `n + 1`), `None` when identically zero.
    chans: Option<Vec<Option<ChannelVectors>>>,
}

impl ModeData {
    fn new(net: &Network, mode: NetMode) -> Result<Self> {
        let (k, c, f) = net.matrices(mode)?;
        let nd = net.dofs();
        let n = 2 * nd;
        let m = net.mass_diag();
        let mut a = vec![0.0; n * n];
        for i in 0..nd {
            a[(nd + i) * n + i] = 1.0;
            for j in 0..nd {
                a[j * n + nd + i] = -k[(i, j)] / m[i];
                a[(nd + j) * n + nd + i] = -c[(i, j)] / m[i];
            }
        }
        let mut b = vec![0.0; n];
        for i in 0..nd {
            b[nd + i] = f[i] / m[i];
        }
        Ok(Self {
            a,
            b,
            k,
            c,
            f,
            prop: None,
            chans: None,
        })
    }

    fn propagator(&mut self, masses: &[f64]) -> Result<Rc<Propagator>> {
        if let Some(p) = &self.prop {
            return Ok(p.clone());
        }
        let n = self.b.len();
        let a = Mat::from_fn(n, n, |i, j| self.a[j * n + i]);
        let forced = self.f.iter().any(|v| *v != 0.0);
        let p =
            Propagator::shared_forced(&self.k, &self.c, masses, a, forced.then_some(&self.f[..]))?;
        self.prop = Some(p.clone());
        Ok(p)
    }

    /// `ℓᵀ(A X + b)` as `[ℓᵀA; ℓᵀb]` for an affine functional `l = [ℓ; ℓ₀]`.
    fn slope(&self, l: &[f64]) -> Vec<f64> {
        let n = self.b.len();
        let mut out: Vec<f64> = (0..n)
            .map(|j| dot(&self.a[j * n..(j + 1) * n], &l[..n]))
            .collect();
        out.push(dot(&l[..n], &self.b));
        out
    }
}

/// The channels reported for a network, in order: contact forces, suspension spring and
/// dashpot forces, every named point's displacement, velocity and acceleration, every body's
/// displacement and velocity, the floor force (when something carries force to the floor).
pub fn channel_kinds(net: &Network) -> Vec<ChannelKind> {
    let mut out: Vec<ChannelKind> = (0..net.contacts.len())
        .map(ChannelKind::ContactForce)
        .collect();
    for j in 0..net.suspensions.len() {
        out.push(ChannelKind::SpringForce(j));
        out.push(ChannelKind::DashpotForce(j));
    }
    for p in net.structure.points.keys() {
        out.push(ChannelKind::PointDisplacement(p.clone()));
        out.push(ChannelKind::PointVelocity(p.clone()));
        out.push(ChannelKind::PointAcceleration(p.clone()));
    }
    for b in 0..net.bodies.len() {
        out.push(ChannelKind::BodyDisplacement(b));
        out.push(ChannelKind::BodyVelocity(b));
    }
    if net.has_floor_force() {
        out.push(ChannelKind::FloorForce);
    }
    out
}

/// The affine functional `[ℓ; ℓ₀]` (length `2·dofs + 1`) of channel `kind` in a mode.
fn channel_vector(net: &Network, md: &ModeData, mode: NetMode, kind: &ChannelKind) -> Vec<f64> {
    let nd = net.dofs();
    let n = 2 * nd;
    let nm = net.n_modes();
    let mut l = vec![0.0; n + 1];
    let contact = |l: &mut Vec<f64>, c: usize, sign: f64| {
        if let (true, Ok((k, cc))) = (net.closed(mode, c), net.linear_law(c)) {
            let a = net.contact_vector(c);
            for i in 0..nd {
                l[i] += sign * k * a[i];
                l[nd + i] += sign * cc * a[i];
            }
            l[n] -= sign * k * net.contacts[c].gap;
        }
    };
    let psi = |p: &str| {
        net.structure
            .point(p)
            .map(|v| v.to_vec())
            .unwrap_or_default()
    };
    match kind {
        ChannelKind::ContactForce(c) => contact(&mut l, *c, 1.0),
        ChannelKind::SpringForce(j) => {
            let k = net.suspensions[*j].stiffness;
            for (li, ai) in l.iter_mut().zip(net.suspension_vector(*j)) {
                *li = k * ai;
            }
        }
        ChannelKind::DashpotForce(j) => {
            if net.dashpot_on(mode, *j) {
                let c = net.suspensions[*j].damping;
                for (li, ai) in l[nd..].iter_mut().zip(net.suspension_vector(*j)) {
                    *li = c * ai;
                }
            }
        }
        ChannelKind::PointDisplacement(p) => l[..nm].copy_from_slice(&psi(p)),
        ChannelKind::PointVelocity(p) => l[nd..nd + nm].copy_from_slice(&psi(p)),
        ChannelKind::PointAcceleration(p) => {
            let mut v = vec![0.0; n + 1];
            v[nd..nd + nm].copy_from_slice(&psi(p));
            // The acceleration is the slope of the velocity.
            l = md.slope(&v);
        }
        ChannelKind::BodyDisplacement(b) => l[nm + b] = 1.0,
        ChannelKind::BodyVelocity(b) => l[nd + nm + b] = 1.0,
        ChannelKind::FloorForce => {
            if let Some(ff) = &net.structure.floor_force {
                l[..nm].copy_from_slice(&ff.stiffness);
                l[nd..nd + nm].copy_from_slice(&ff.damping);
            }
            for (j, s) in net.suspensions.iter().enumerate() {
                if s.anchor == End::Ground {
                    let a = net.suspension_vector(j);
                    let c = if net.dashpot_on(mode, j) {
                        s.damping
                    } else {
                        0.0
                    };
                    for i in 0..nd {
                        l[i] += s.stiffness * a[i];
                        l[nd + i] += c * a[i];
                    }
                }
            }
            for (c, link) in net.contacts.iter().enumerate() {
                // The ground as end B takes +f, as end A −f.
                if link.ends[1] == End::Ground {
                    contact(&mut l, c, 1.0);
                } else if link.ends[0] == End::Ground {
                    contact(&mut l, c, -1.0);
                }
            }
        }
    }
    l
}

/// Signs of the indicators just after the state `x` under the dynamics `Ẋ = A X + b` (the
/// first-order data of `md`): the sign of the first derivative `ℓᵀX⁽ᵏ⁾ (+ ℓ₀ for k = 0)`
/// above its round-off band, `1e-9` (value) or `1e-11` (derivatives) of the sizes of its terms
/// (`T₀ = |X|`, `T₁ = |A|T₀ + |b|`, `T_{k+1} = |A|T_k`); 0 when none is, up to order 8.
fn lex_signs(inds: &[NetIndicator], md: &ModeData, x: &[f64], out: &mut [f64]) {
    let n = x.len();
    out.fill(0.0);
    let mut y = x.to_vec();
    let mut terms: Vec<f64> = x.iter().map(|v| v.abs()).collect();
    let mut open = inds.len();
    for k in 0..=K_MAX {
        let tol = if k == 0 { 1e-9 } else { 1e-11 };
        for (ind, o) in inds.iter().zip(out.iter_mut()) {
            if *o != 0.0 {
                continue;
            }
            let (l, l0) = (&ind.l[..n], if k == 0 { ind.l[n] } else { 0.0 });
            let val = dot(l, &y) + l0;
            let scale: f64 = l.iter().zip(&terms).map(|(a, t)| a.abs() * t).sum::<f64>() + l0.abs();
            if val.abs() > tol * scale {
                *o = val.signum();
                open -= 1;
            }
        }
        if open == 0 {
            break;
        }
        let mut next = vec![0.0; n];
        let mut next_terms = vec![0.0; n];
        for j in 0..n {
            let col = &md.a[j * n..(j + 1) * n];
            for i in 0..n {
                next[i] += col[i] * y[j];
                next_terms[i] += col[i].abs() * terms[j];
            }
        }
        if k == 0 {
            for i in 0..n {
                next[i] += md.b[i];
                next_terms[i] += md.b[i].abs();
            }
        }
        y = next;
        terms = next_terms;
    }
}

/// The run's modes met, built on first use.
struct Modes<'n> {
    net: &'n Network,
    inds: Vec<NetIndicator>,
    kinds: Vec<ChannelKind>,
    masses: Vec<f64>,
    data: HashMap<u64, ModeData>,
}

impl Modes<'_> {
    fn get(&mut self, mode: NetMode) -> Result<&mut ModeData> {
        if !self.data.contains_key(&mode.0) {
            let md = ModeData::new(self.net, mode)?;
            self.data.insert(mode.0, md);
        }
        self.data
            .get_mut(&mode.0)
            .ok_or_else(|| Error::numerical("network", "mode cache"))
    }

    /// The indicators' signs just after `x` under `mode`'s dynamics ([`lex_signs`]).
    fn signs(&mut self, mode: NetMode, x: &[f64], out: &mut [f64]) -> Result<()> {
        self.get(mode)?;
        let md = self
            .data
            .get(&mode.0)
            .ok_or_else(|| Error::numerical("network", "mode cache"))?;
        lex_signs(&self.inds, md, x, out);
        Ok(())
    }

    /// A consistent mode at `x`, iterated from `start` (module documentation), and the
    /// indicators' signs under it. Without a fixed point, the last candidate.
    fn select(&mut self, x: &[f64], start: NetMode, signs: &mut [f64]) -> Result<NetMode> {
        let mut cand = start;
        let mut seen = vec![start];
        for _ in 0..(2 * self.inds.len() + 8) {
            self.signs(cand, x, signs)?;
            let next = self.net.implied(&self.inds, signs);
            if next == cand {
                return Ok(cand);
            }
            if seen.contains(&next) {
                break;
            }
            seen.push(next);
            cand = next;
        }
        self.signs(cand, x, signs)?;
        Ok(cand)
    }

    /// The channel vectors of `mode`, built on first use.
    fn channels(&mut self, mode: NetMode) -> Result<&ModeData> {
        let net = self.net;
        let kinds = self.kinds.clone();
        let md = self.get(mode)?;
        if md.chans.is_none() {
            let chans = kinds
                .iter()
                .map(|k| {
                    let l = channel_vector(net, md, mode, k);
                    if l.iter().all(|v| *v == 0.0) {
                        None
                    } else {
                        let la = md.slope(&l);
                        Some((l, la))
                    }
                })
                .collect();
            md.chans = Some(chans);
        }
        Ok(md)
    }
}

/// `∫₀^len ℓᵀX(s) ds` of a functional of a segment: in closed form for a sum of exponentials,
/// by 8-point Gauss-Legendre on quarter periods for the matrix-exponential fallback.
pub(crate) fn integral(f: &Functional<'_>, len: f64) -> f64 {
    match f {
        Functional::Exp(e) => {
            let mut v = e.p0 * len + e.p1 * len * len / 2.0 + e.p2 * len.powi(3) / 3.0;
            for (a, l) in e.amp.iter().zip(&e.lam) {
                v += (a * exp_integral(*l, len)).re;
            }
            v
        }
        other => {
            let p = other.fastest_period();
            let pieces = if p.is_finite() && p > 0.0 {
                ((len / (p / 4.0)).ceil() as usize).clamp(1, 1_000_000)
            } else {
                1
            };
            let h = len / pieces as f64;
            let mut total = 0.0;
            for k in 0..pieces {
                let mid = (k as f64 + 0.5) * h;
                for (xi, wi) in GL_X.iter().zip(GL_W) {
                    for sg in [-1.0, 1.0] {
                        total += wi * h / 2.0 * other.value_slope(mid + sg * xi * h / 2.0).0;
                    }
                }
            }
            total
        }
    }
}

/// The initial state `[x; ẋ]` (module documentation): velocities of the bodies, and the static
/// equilibrium under the preloads. Errors name `<contact>.gap` for a preload that cannot be in
/// equilibrium or an open contact the equilibrium makes overlap.
pub fn initial_state(net: &Network) -> Result<Vec<f64>> {
    let nd = net.dofs();
    let nm = net.n_modes();
    let mut x = vec![0.0; 2 * nd];
    for (b, body) in net.bodies.iter().enumerate() {
        x[nd + nm + b] = body.velocity;
    }
    let preloaded: Vec<usize> = (0..net.contacts.len())
        .filter(|&c| net.contacts[c].gap < 0.0)
        .collect();
    if preloaded.is_empty() {
        return Ok(x);
    }
    let mode = preloaded.iter().fold(NetMode(0), |m, &c| m.with(c, true));
    let (k, _, f) = net.matrices(mode)?;
    let (lam, v) = super::small::sym_eigen(&k)?;
    let lam_max = lam.iter().fold(0.0_f64, |a, b| a.max(b.abs()));
    for (i, &l) in lam.iter().enumerate() {
        if l.abs() <= 1e-12 * lam_max {
            continue;
        }
        let proj: f64 = (0..nd).map(|r| v[(r, i)] * f[r]).sum::<f64>() / l;
        for r in 0..nd {
            x[r] += v[(r, i)] * proj;
        }
    }
    for c in 0..net.contacts.len() {
        let link = &net.contacts[c];
        let (delta, _) = net.overlap(c, &x);
        let (kk, _) = net.linear_law(c)?;
        let force = kk * delta;
        if link.gap < 0.0 && (force.is_nan() || force <= 1e-9 * kk * link.gap.abs()) {
            return Err(Error::invalid(
                format!("{}.gap", link.name),
                format!(
                    "a preload of {} m (gap = {}) cannot be in equilibrium: at the static state under the preloads and constant forces the contact {} (overlap {delta:.3e} m); nothing holds its two ends against each other, so give a gap ≥ 0, or anchor the body it pushes (a damper's spring, another preloaded contact)",
                    crate::num(-link.gap),
                    crate::num(link.gap),
                    if force < 0.0 { "would pull" } else { "carries no force" }
                ),
            ));
        }
        if link.gap >= 0.0 && delta > 1e-9 * link.gap.abs().max(1e-12) {
            return Err(Error::invalid(
                format!("{}.gap", link.name),
                format!(
                    "at the static state under the preloads the contact overlaps by {delta:.3e} m although its gap is {} m (open): give it a preload (gap < 0) or a larger gap",
                    crate::num(link.gap)
                ),
            ));
        }
    }
    Ok(x)
}

/// Per-contact bookkeeping of the impact now open on it.
struct OpenImpact {
    row: usize,
    ext: Extremes,
}

/// Simulates the network for `opts.duration` (`opts.max_events` caps the switches; sample
/// output is not produced). See the module documentation.
pub fn solve(net: &Network, opts: &Options) -> Result<NetSolution> {
    if !(opts.duration.is_finite() && opts.duration > 0.0) {
        return Err(Error::invalid(
            "simulation.duration",
            format!("must be > 0 s (got {})", opts.duration),
        ));
    }
    let mut run = Run::new(net, opts)?;
    loop {
        let switched = run.stretch()?;
        if !switched {
            break;
        }
        let new_mode = run.next_mode()?;
        if new_mode != run.mode {
            run.switch_to(new_mode)?;
        }
        if run.collision_ended() && opts.stop_at_collision_end {
            break;
        }
        if run.t >= opts.duration {
            break;
        }
    }
    let sol = run.finish();
    check(net, &sol)?;
    Ok(sol)
}

/// The state of a run between stretches ([`solve`]).
struct Run<'n, 'o> {
    net: &'n Network,
    opts: &'o Options,
    modes: Modes<'n>,
    channels: Vec<NetChannel>,
    /// `C a aᵀ` of each damped contact (for `∫ C δ̇² dt`).
    contact_c: Vec<Option<Mat<f64>>>,
    /// The indicators' signs just after the last switch (0: not searched).
    signs: Vec<f64>,
    mode0: NetMode,
    mode: NetMode,
    x0: Vec<f64>,
    x: Vec<f64>,
    t: f64,
    /// Initial total energy, the bodies' initial kinetic and total energies (J).
    e0: f64,
    body_ke0: f64,
    body_e0: f64,
    preloaded: Vec<bool>,
    /// Has a contact that was not preloaded closed yet?
    touched: bool,
    events: Vec<(f64, NetMode, NetMode)>,
    impacts: Vec<ImpactRow>,
    open: Vec<Option<OpenImpact>>,
    closed_time: Vec<f64>,
    dissipated_j: f64,
    collision_end: Option<NetCollisionEnd>,
    /// Consecutive stretches of no length.
    zero_length: usize,
    /// Scratch state.
    buf: Vec<f64>,
}

impl<'n, 'o> Run<'n, 'o> {
    /// The initial state, its mode and energies, and the impacts of the contacts closed at t = 0.
    fn new(net: &'n Network, opts: &'o Options) -> Result<Self> {
        let x0 = initial_state(net)?;
        let nd = net.dofs();
        let nc = net.contacts.len();
        let mut modes = Modes {
            net,
            inds: net.indicators()?,
            kinds: channel_kinds(net),
            masses: net.mass_diag(),
            data: HashMap::new(),
        };
        let channels: Vec<NetChannel> = modes
            .kinds
            .iter()
            .map(|k| NetChannel {
                kind: k.clone(),
                extremes: Extremes::default(),
            })
            .collect();
        // ∫ C δ̇² of each damped contact: C a aᵀ.
        let contact_c: Vec<Option<Mat<f64>>> = (0..nc)
            .map(|c| {
                let (_, cc) = net.linear_law(c).ok()?;
                let a = net.contact_vector(c);
                (cc != 0.0).then(|| Mat::from_fn(nd, nd, |i, j| cc * a[i] * a[j]))
            })
            .collect();
        let mut signs = vec![0.0; modes.inds.len()];
        let mode = modes.select(&x0, NetMode(0), &mut signs)?;
        let (ke0, pe0) = net.energies(mode, &x0);
        let body_ke0: f64 = net
            .bodies
            .iter()
            .map(|b| 0.5 * b.mass * b.velocity * b.velocity)
            .sum();
        let body_e0 = net.body_energy(&x0);
        let preloaded: Vec<bool> = net.contacts.iter().map(|c| c.gap < 0.0).collect();
        let touched = (0..nc).any(|c| !preloaded[c] && net.closed(mode, c));
        let mut impacts: Vec<ImpactRow> = Vec::new();
        let mut open: Vec<Option<OpenImpact>> = (0..nc).map(|_| None).collect();
        for (c, o) in open.iter_mut().enumerate() {
            if net.closed(mode, c) {
                *o = Some(start_impact(net, c, &x0, 0.0, &mut impacts));
            }
        }
        Ok(Self {
            net,
            opts,
            modes,
            channels,
            contact_c,
            signs,
            mode0: mode,
            mode,
            x: x0.clone(),
            x0,
            t: 0.0,
            e0: ke0 + pe0,
            body_ke0,
            body_e0,
            preloaded,
            touched,
            events: Vec::new(),
            impacts,
            open,
            closed_time: vec![0.0; nc],
            dissipated_j: 0.0,
            collision_end: None,
            zero_length: 0,
            buf: vec![0.0; 2 * nd],
        })
    }

    /// One stretch in the current mode, from `t` to the first switch or the end of the run:
    /// its extremes, closed times, dissipation and impact bookkeeping, and the state at its
    /// end. Returns whether it ended on a switch.
    fn stretch(&mut self) -> Result<bool> {
        let net = self.net;
        let n = 2 * net.dofs();
        let horizon = self.opts.duration - self.t;
        let masses = self.modes.masses.clone();
        let prop = self.modes.get(self.mode)?.propagator(&masses)?;
        let seg = prop.segment(&self.x);
        let period = prop.period();
        let s_end = {
            let funcs: Vec<Functional<'_>> = self
                .modes
                .inds
                .iter()
                .map(|i| seg.functional(&i.l))
                .collect();
            let mut searches: Vec<Search<Lifted<&Functional<'_>>>> = funcs
                .iter()
                .zip(&self.signs)
                .zip(&self.modes.inds)
                .filter(|((_, s), _)| **s != 0.0)
                .map(|((f, s), ind)| {
                    let v = dot(&ind.l[..n], &self.x) + ind.l[n];
                    Search::new(Lifted::new(f, v, *s), *s, SearchOptions::default())
                })
                .collect();
            first_switch(&mut searches, period, horizon)
        };
        let (s_end, switched) = match s_end {
            Some(s) if s < horizon => (s.max(0.0), true),
            _ => (horizon, false),
        };
        self.book_stretch(&seg, s_end)?;
        seg.state(s_end, &mut self.buf);
        self.x.copy_from_slice(&self.buf);
        let t_before = self.t;
        self.t += s_end;
        if switched {
            self.count_zero_length(s_end, period, t_before)?;
        }
        Ok(switched)
    }

    /// The extremes of every channel over a stretch of length `s_end` from `t`, the open
    /// impacts' peaks, impulses and dissipation, the closed times and the dissipated energy.
    fn book_stretch(&mut self, seg: &Segment<'_>, s_end: f64) -> Result<()> {
        let net = self.net;
        let nd = net.dofs();
        let t = self.t;
        let md = self.modes.channels(self.mode)?;
        let chans = md.chans.as_ref().map_or(&[][..], |v| &v[..]);
        for (ch, lv) in self.channels.iter_mut().zip(chans) {
            let mut e = Extremes::default();
            match lv {
                Some((l, la)) => peaks::on_segment(seg, l, la, t, s_end, &mut e),
                None => e.offer(0.0, t),
            }
            merge(&mut ch.extremes, &e);
            if let (ChannelKind::ContactForce(c), Some((l, _))) = (&ch.kind, lv) {
                if let Some(o) = self.open[*c].as_mut() {
                    merge(&mut o.ext, &e);
                    self.impacts[o.row].impulse_n_s += integral(&seg.functional(l), s_end);
                    if let Some(cm) = &self.contact_c[*c] {
                        self.impacts[o.row].dissipated_j += dissipated(seg, cm, nd, s_end);
                    }
                }
            }
        }
        for c in 0..net.contacts.len() {
            if net.closed(self.mode, c) {
                self.closed_time[c] += s_end;
            }
        }
        self.dissipated_j += dissipated(seg, &md.c, nd, s_end);
        Ok(())
    }

    /// Counts consecutive stretches of no length ending on a switch: more than 50 is chatter,
    /// an error.
    fn count_zero_length(&mut self, s_end: f64, period: f64, t_before: f64) -> Result<()> {
        if s_end <= 1e-14 * period.min(self.opts.duration) || self.t == t_before {
            self.zero_length += 1;
            if self.zero_length > 50 {
                return Err(Error::numerical(
                    "network propagator",
                    format!(
                        "switches chatter at t = {:.9e} s without time advancing (mode {:#b})",
                        self.t, self.mode.0
                    ),
                ));
            }
        } else {
            self.zero_length = 0;
        }
        Ok(())
    }

    /// The mode after the switch that ended the stretch ([`Modes::select`]), with the
    /// trajectory deciding what the derivatives cannot: an indicator now on the other side of
    /// where it was searched from takes that side (and the mode follows); one at zero within
    /// round-off after a stretch of no length is not searched until the mode changes.
    fn next_mode(&mut self) -> Result<NetMode> {
        let n = 2 * self.net.dofs();
        let searched = self.signs.clone();
        let mut new_mode = self.modes.select(&self.x, self.mode, &mut self.signs)?;
        if new_mode != self.mode {
            return Ok(new_mode);
        }
        let signs = &mut self.signs;
        let mut moved = vec![false; signs.len()];
        for (i, ind) in self.modes.inds.iter().enumerate() {
            let v = dot(&ind.l[..n], &self.x) + ind.l[n];
            if searched[i] != 0.0 && searched[i] * v < 0.0 && signs[i] == searched[i] {
                signs[i] = -searched[i];
                moved[i] = true;
            } else if signs[i] * v <= 0.0 && self.zero_length > 0 {
                signs[i] = 0.0;
            }
        }
        if moved.iter().any(|m| *m) {
            new_mode = self.net.implied(&self.modes.inds, signs);
            let kept = signs.clone();
            self.modes.signs(new_mode, &self.x, &mut self.signs)?;
            for (i, m) in moved.iter().enumerate() {
                if *m {
                    self.signs[i] = kept[i];
                }
            }
        }
        Ok(new_mode)
    }

    /// The switch to `new_mode` at `t`: the contacts that open finish their impact rows (a
    /// force-release contact letting go at `δ > 0` dissipates `K δ²/2`), those that close
    /// start one (one closing again at `δ > 0` gets `K δ²/2` back: negative dissipation); the
    /// event is recorded, and more than `opts.max_events` is an error.
    fn switch_to(&mut self, new_mode: NetMode) -> Result<()> {
        let net = self.net;
        let t = self.t;
        for c in 0..net.contacts.len() {
            let (was, now) = (net.closed(self.mode, c), net.closed(new_mode, c));
            if was && !now {
                let (delta, rate) = net.overlap(c, &self.x);
                let jump = net.contacts[c].contact.law.potential_energy(delta);
                self.dissipated_j += jump;
                if let Some(o) = self.open[c].take() {
                    finish_impact(&mut self.impacts[o.row], &o.ext, t, rate, jump);
                }
            } else if now && !was {
                // A force-release contact may close again at δ > 0 (its force rising through
                // zero before the overlap has): its elastic energy comes back with it.
                let (delta, _) = net.overlap(c, &self.x);
                let back = net.contacts[c].contact.law.potential_energy(delta);
                self.dissipated_j -= back;
                let o = start_impact(net, c, &self.x, t, &mut self.impacts);
                self.impacts[o.row].dissipated_j -= back;
                self.open[c] = Some(o);
                self.touched |= !self.preloaded[c];
            }
        }
        self.events.push((t, self.mode, new_mode));
        if self.events.len() > self.opts.max_events {
            return Err(Error::numerical(
                "network propagator",
                format!(
                    "more than {} switching events by t = {t:.6e} s (simulation.max_events)",
                    self.opts.max_events
                ),
            ));
        }
        self.mode = new_mode;
        Ok(())
    }

    /// Records the end of the collision the first time every contact that was not preloaded
    /// is open again after one of them closed; true once it has ended.
    fn collision_ended(&mut self) -> bool {
        if self.collision_end.is_some() {
            return true;
        }
        let net = self.net;
        let all_open =
            (0..net.contacts.len()).all(|c| self.preloaded[c] || !net.closed(self.mode, c));
        if self.touched && all_open {
            self.collision_end = Some(NetCollisionEnd {
                t: self.t,
                x: self.x.clone(),
                force_work_j: net.force_work(&self.x0, &self.x),
                dissipated_j: self.dissipated_j,
            });
        }
        self.collision_end.is_some()
    }

    /// The energy-balance residual `|E(0) + W − E − D| / (E(0) + |W|)` at `x` in mode `m`.
    fn residual(&self, x: &[f64], w: f64, d: f64, m: NetMode) -> f64 {
        let (ke, pe) = self.net.energies(m, x);
        let denom = self.e0 + w.abs();
        let disc = self.e0 + w - ke - pe - d;
        if disc == 0.0 {
            0.0
        } else {
            disc.abs() / denom.max(f64::MIN_POSITIVE)
        }
    }

    /// The finished run: the impacts still open closed at the end of the run, the residuals
    /// and the energy ratio (module documentation).
    fn finish(mut self) -> NetSolution {
        let net = self.net;
        let t = self.t;
        for o in self.open.iter_mut() {
            if let Some(o) = o.take() {
                let row = &mut self.impacts[o.row];
                row.duration_s = t - row.start_s;
                let (v, tv) = o.ext.peak();
                row.peak_force_n = v;
                row.peak_time_s = tv;
            }
        }
        let force_work_j = net.force_work(&self.x0, &self.x);
        let residual_run_end = self.residual(&self.x, force_work_j, self.dissipated_j, self.mode);
        let (residual_collision_end, energy_ratio) = match &self.collision_end {
            Some(ce) => {
                // The mode at the collision's end: every non-preloaded contact open, the
                // preloaded ones as the state says.
                let m = (0..net.contacts.len()).fold(NetMode(0), |m, c| {
                    m.with(c, self.preloaded[c] && net.overlap(c, &ce.x).0 > 0.0)
                });
                let r = self.residual(&ce.x, ce.force_work_j, ce.dissipated_j, m);
                let e_in = self.body_ke0 + ce.force_work_j;
                let kept = self.body_e0 + ce.force_work_j - net.body_energy(&ce.x);
                (Some(r), (e_in > 0.0).then(|| kept / e_in))
            }
            None => (None, None),
        };
        NetSolution {
            x0: self.x0,
            mode0: self.mode0,
            t_final: t,
            x_final: self.x,
            mode_final: self.mode,
            events: self.events,
            collision_end: self.collision_end,
            channels: self.channels,
            closed_time_s: self.closed_time,
            impacts: self.impacts,
            dissipated_j: self.dissipated_j,
            force_work_j,
            residual_collision_end,
            residual_run_end,
            energy_ratio,
        }
    }
}

/// A finished run's checks: finite state and extremes, and the energy balance within
/// [`RESIDUAL_BOUND`] at the end of the collision and of the run.
fn check(net: &Network, sol: &NetSolution) -> Result<()> {
    if sol.x_final.iter().any(|v| !v.is_finite())
        || sol.channels.iter().any(|c| !c.extremes.is_finite())
    {
        return Err(Error::numerical(
            "simulation",
            format!(
                "the state became non-finite by t = {:.6e} s (contact stiffnesses against the structure's frequencies?)",
                sol.t_final
            ),
        ));
    }
    for (what, r) in [
        ("end of the collision", sol.residual_collision_end),
        ("end of the run", Some(sol.residual_run_end)),
    ] {
        if let Some(r) = r {
            if r.is_nan() || r > RESIDUAL_BOUND {
                return Err(Error::numerical(
                    "simulation",
                    format!(
                        "energy balance violated at the {what}: residual {r:.3e} of the energy put in > {RESIDUAL_BOUND:e} allowed (exact); {} contacts, {} bodies",
                        net.contacts.len(),
                        net.bodies.len()
                    ),
                ));
            }
        }
    }
    Ok(())
}

fn merge(into: &mut Extremes, e: &Extremes) {
    if e.is_set() {
        into.offer(e.max, e.t_max);
        into.offer(e.min, e.t_min);
    }
}

fn start_impact(
    net: &Network,
    c: usize,
    x: &[f64],
    t: f64,
    impacts: &mut Vec<ImpactRow>,
) -> OpenImpact {
    let (_, rate) = net.overlap(c, x);
    impacts.push(ImpactRow {
        contact: net.contacts[c].name.clone(),
        start_s: t,
        approach_velocity_m_per_s: rate,
        peak_force_n: 0.0,
        peak_time_s: t,
        duration_s: 0.0,
        impulse_n_s: 0.0,
        dissipated_j: 0.0,
        exit_velocity_m_per_s: None,
        restitution: None,
    });
    OpenImpact {
        row: impacts.len() - 1,
        ext: Extremes::default(),
    }
}

fn finish_impact(row: &mut ImpactRow, ext: &Extremes, t: f64, rate: f64, jump: f64) {
    row.duration_s = t - row.start_s;
    let (v, tv) = ext.peak();
    row.peak_force_n = v;
    row.peak_time_s = tv;
    row.dissipated_j += jump;
    row.exit_velocity_m_per_s = Some(-rate);
    row.restitution =
        (row.approach_velocity_m_per_s > 0.0).then(|| -rate / row.approach_velocity_m_per_s);
}
