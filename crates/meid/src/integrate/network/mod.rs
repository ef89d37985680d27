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
//! # Rigid contacts
//! A contact with the rigid law ([`crate::impact::ContactLaw::Rigid`], restitution `e`) has no
//! force law: it is open, or held as a constraint.
//!
//! - **Impact.** When its overlap `aᵀx − g` reaches 0 (found by the search of step 1 and moved
//!   onto the exact zero by two Newton steps on its closed form, so that no lateness
//!   accumulates over a train of bounces) while closing at `v_in = aᵀẋ > 0`, the velocities jump
//!   by the impulse `J` along `a` that gives `aᵀẋ⁺ = −e v_in`:
//!   `ẋ⁺ = ẋ − (1 + e) v_in M⁻¹a/(aᵀM⁻¹a)`, removing `½(1 − e²) v_in²/(aᵀM⁻¹a)` (Newton's law of
//!   restitution), booked as the contact's dissipated energy (run total and impact row). The row
//!   has `impulse_n_s = J`, `duration_s = 0` and `peak_force_n = None`: an impulse has no finite
//!   peak. Springs and dashpots transmit no impulse; every other rigid contact at zero overlap
//!   or held at that instant does: the impulses `P ≥ 0` of all of them solve the complementarity
//!   problem `w = G P − b ≥ 0`, `Pᵀw = 0` (`G = AᵀM⁻¹A`, `b_c = (1 + e_c) v_c` for a closing
//!   contact, `v_c` otherwise; [`crate::impact::network::impulses_lcp`]), and each books
//!   `P_c (v_c⁻ + v_c⁺)/2`, the kinetic energy its impulse removes (these sum exactly to the
//!   loss).
//! - **Rest.** Under a constant force the bounces of `e < 1` accumulate (infinitely many in a
//!   finite time). After an impact with rebound `u = e v_in` and a normal acceleration
//!   `aₙ = d(aᵀẋ)/dt > 0` pushing the contact closed, the next flight rises `u²/(2aₙ)`: when
//!   that is inside the band within which [`lex_signs`] calls an overlap zero (`1e-9` of the
//!   overlap's terms), or when the rest of the bounces, `2u/(aₙ(1 − e))`, is shorter than the
//!   clock's resolution `ε t`, the next impacts come within round-off. The impact is then
//!   plastic (`e = 0`: the remaining bounces' energy `½ e² v_in²/(aᵀM⁻¹a)` is dissipated with
//!   it) and the contact is **held**: the constraint `aᵀx = g` of the constrained mode
//!   ([`Network::constrained`], exact, the α-terms vanishing on the manifold), with the
//!   constraint force `λ = G⁻¹AᵀM⁻¹(f − Cẋ − Kx)` (affine in the state) as the contact's force
//!   channel. Its resting row starts at the instant the collapsed bounces end, the impact plus
//!   their geometric sum `2u/(aₙ(1 − e))` (exact for a constant `aₙ`; the accumulation time
//!   `√(2h/g)(1 + e)/(1 − e)` of a ball dropped from `h` to round-off: about 1e-16 relative
//!   measured, 1e-9 asked by the tests). The
//!   number of impacts stays finite: about `ln(v₀²/(2aₙ·1e-9·s))/(2 ln(1/e))` for a first landing
//!   at `v₀` and an overlap scale `s`.
//! - **Release.** A held contact lets go when `λ` crosses zero (searched as an indicator);
//!   with several held, the most negative goes first and the others' forces are those of the
//!   smaller set.
//!
//! The dopri5 method ([`dopri5`]) runs general machines with linear, Hertz and
//! Hunt-Crossley laws but not rigid ones (an impulse is exact-only), so a rigid contact with a
//! Hertz or Hunt-Crossley contact in one machine is not possible yet; the paper's
//! form (`[contact.slider_bed]`) refuses the rigid law with a message that says how to write
//! the machine as a general one: its engine has no impulses, and the general machine's exact
//! engine already runs the same machine (`examples/hammer-rigid.toml`).
//!
//! # Initial state
//! Velocities are the impactors' (dampers start at rest). Without a preloaded contact every
//! displacement starts at 0 (the impactors touch, or stand off by their gaps). A rigid contact
//! closing at t = 0 strikes then; one touching with its bodies pushed together rests. With preloaded
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

pub mod dopri5;

use std::collections::HashMap;
use std::rc::Rc;

use faer::Mat;

use super::exact::{dissipated, exp_integral, first_switch, Lifted, GL_W, GL_X};
use super::peaks::{self, Extremes};
use super::propagator::{Functional, Propagator, Segment};
use super::roots::{Scalar, Search, SearchOptions};
use super::Options;
use crate::impact::network::{
    dot, impulses_lcp, End, IndicatorKind, NetIndicator, NetMode, Network,
};
use crate::{Error, Result};

/// The band, relative to the size of its terms, within which [`lex_signs`] calls a value zero.
pub(super) const VALUE_TOL: f64 = 1e-9;
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
    /// Largest force while closed (N); `None` for a rigid contact's impact, an impulse with no
    /// finite peak (its row carries the impulse, duration 0).
    pub peak_force_n: Option<f64>,
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

impl ImpactRow {
    /// The row of a contact that closed at `t` with closing speed `approach` (m/s): no force,
    /// impulse or dissipation yet, still closed.
    pub fn opening(contact: String, t: f64, approach: f64) -> Self {
        Self {
            contact,
            start_s: t,
            approach_velocity_m_per_s: approach,
            peak_force_n: Some(0.0),
            peak_time_s: t,
            duration_s: 0.0,
            impulse_n_s: 0.0,
            dissipated_j: 0.0,
            exit_velocity_m_per_s: None,
            restitution: None,
        }
    }
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
pub(super) struct ModeData {
    /// `A_σ` column-major (`n × n`, `n = 2·dofs`).
    pub(super) a: Vec<f64>,
    /// `b_σ = [0; M⁻¹f_σ]`.
    pub(super) b: Vec<f64>,
    k: Mat<f64>,
    pub(super) c: Mat<f64>,
    f: Vec<f64>,
    prop: Option<Rc<Propagator>>,
    /// The held rigid contacts' constraint forces `(contact, [ℓ; ℓ₀])`
    /// ([`Network::constraint_forces`]).
    lambda: Vec<(usize, Vec<f64>)>,
    /// Per channel `(ℓ, ℓ_slope)` (both of length `n + 1`), `None` when identically zero.
    chans: Option<Vec<Option<ChannelVectors>>>,
}

impl ModeData {
    pub(super) fn new(net: &Network, mode: NetMode) -> Result<Self> {
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
            lambda: net.constraint_forces(mode)?,
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
pub(super) fn channel_vector(
    net: &Network,
    md: &ModeData,
    mode: NetMode,
    kind: &ChannelKind,
) -> Vec<f64> {
    let nd = net.dofs();
    let n = 2 * nd;
    let nm = net.n_modes();
    let mut l = vec![0.0; n + 1];
    let contact = |l: &mut Vec<f64>, c: usize, sign: f64| {
        if let Some((_, lam)) = md.lambda.iter().find(|(ci, _)| *ci == c) {
            // A held rigid contact: its constraint force.
            for (li, v) in l.iter_mut().zip(lam) {
                *li += sign * v;
            }
        } else if let (true, Ok((k, cc))) = (net.closed(mode, c), net.linear_law(c)) {
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
    lex_signs_of(inds, (&md.a, &md.b), x, VALUE_TOL, out);
}

/// [`lex_signs`] under `Ẋ = A X + b` given as `(A column-major, b)`, with a value band of
/// `value_tol` of its terms (dopri5 on a network passes its Jacobian at `x`, `b = F(x) − A x`,
/// and a band of its tolerance: exact for linear laws and for the first two derivatives with
/// any law, [`dopri5`]).
pub(super) fn lex_signs_of(
    inds: &[NetIndicator],
    (a, b): (&[f64], &[f64]),
    x: &[f64],
    value_tol: f64,
    out: &mut [f64],
) {
    let n = x.len();
    out.fill(0.0);
    let mut y = x.to_vec();
    let mut terms: Vec<f64> = x.iter().map(|v| v.abs()).collect();
    let mut open = inds.len();
    for k in 0..=K_MAX {
        let tol = if k == 0 { value_tol } else { 1e-11 };
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
            let col = &a[j * n..(j + 1) * n];
            for i in 0..n {
                next[i] += col[i] * y[j];
                next_terms[i] += col[i].abs() * terms[j];
            }
        }
        if k == 0 {
            for i in 0..n {
                next[i] += b[i];
                next_terms[i] += b[i].abs();
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
        // Held rigid contacts stay held: their impacts and constraint forces decide.
        let held = self.net.held_bits(start).0;
        let mut cand = start;
        let mut seen = vec![start];
        for _ in 0..(2 * self.inds.len() + 8) {
            self.signs(cand, x, signs)?;
            let next = NetMode(self.net.implied(&self.inds, signs).0 | held);
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
        if net.rigid(c).is_some() {
            // Never preloaded (refused); an overlap here is the open-contact error below.
            if delta > 1e-9 * link.gap.abs().max(1e-12) {
                return Err(Error::invalid(
                    format!("{}.gap", link.name),
                    format!(
                        "at the static state under the preloads the rigid contact overlaps by {delta:.3e} m although its gap is {} m: give a larger gap",
                        crate::num(link.gap)
                    ),
                ));
            }
            continue;
        }
        let kk = match net.linear_law(c) {
            Ok((kk, _)) => kk,
            // A non-linear (Hertz, Hunt-Crossley) contact: open at the start, or refused
            // preloaded (its static state is not linear).
            Err(_) if link.gap < 0.0 => {
                return Err(Error::invalid(
                    format!("{}.gap", link.name),
                    "a preload (gap < 0) needs a linear contact law (the static state under the preloads is found as a linear equilibrium): give law = \"linear\" or a gap ≥ 0",
                ))
            }
            Err(_) => 0.0,
        };
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

/// A run's bookkeeping at its start `x0` in `mode` (either engine).
pub(super) struct Start {
    /// Initial total energy, the bodies' initial kinetic and total energies (J).
    pub e0: f64,
    pub body_ke0: f64,
    pub body_e0: f64,
    pub preloaded: Vec<bool>,
    /// Has a contact that was not preloaded closed at the start?
    pub touched: bool,
    /// The rows of the contacts closed at the start, open.
    pub impacts: Vec<ImpactRow>,
    pub open: Vec<Option<OpenImpact>>,
}

impl Start {
    pub(super) fn new(net: &Network, mode: NetMode, x0: &[f64]) -> Self {
        let nd = net.dofs();
        let nc = net.contacts.len();
        let (ke0, pe0) = net.energies(mode, x0);
        // The impactors' kinetic energy at x0 (at the initial state the dampers are at rest
        // and the impactors move with their configured velocities).
        let nm = net.n_modes();
        let body_ke0: f64 = net
            .bodies
            .iter()
            .enumerate()
            .filter(|(b, _)| !net.suspensions.iter().any(|s| s.body == *b))
            .map(|(b, body)| 0.5 * body.mass * x0[nd + nm + b] * x0[nd + nm + b])
            .sum();
        let preloaded: Vec<bool> = net.contacts.iter().map(|c| c.gap < 0.0).collect();
        let touched = (0..nc).any(|c| !preloaded[c] && net.closed(mode, c));
        let mut impacts: Vec<ImpactRow> = Vec::new();
        let mut open: Vec<Option<OpenImpact>> = (0..nc).map(|_| None).collect();
        for (c, o) in open.iter_mut().enumerate() {
            if net.closed(mode, c) {
                *o = Some(start_impact(net, c, x0, 0.0, &mut impacts));
            }
        }
        Self {
            e0: ke0 + pe0,
            body_ke0,
            body_e0: net.body_energy(x0),
            preloaded,
            touched,
            impacts,
            open,
        }
    }
}

/// The contacts' rows at a switch from `from` to `to` at `(t, x)`: those that open finish
/// their rows (a force-release contact letting go at `δ > 0` dissipates its elastic energy),
/// those that close start one (one closing again at `δ > 0` gets its elastic energy back:
/// negative dissipation). Returns the energy dissipated by the jumps and whether a contact
/// that was not preloaded closed.
pub(super) fn book_contacts(
    net: &Network,
    (from, to): (NetMode, NetMode),
    (t, x): (f64, &[f64]),
    preloaded: &[bool],
    impacts: &mut Vec<ImpactRow>,
    open: &mut [Option<OpenImpact>],
) -> (f64, bool) {
    let mut dissipated = 0.0;
    let mut touched = false;
    for c in 0..net.contacts.len() {
        let (was, now) = (net.closed(from, c), net.closed(to, c));
        if was && !now {
            let (delta, rate) = net.overlap(c, x);
            let jump = net.contacts[c].contact.law.potential_energy(delta);
            dissipated += jump;
            if let Some(o) = open[c].take() {
                finish_impact(&mut impacts[o.row], &o.ext, t, rate, jump);
            }
        } else if now && !was {
            // A force-release contact may close again at δ > 0 (its force rising through
            // zero before the overlap has): its elastic energy comes back with it.
            let (delta, _) = net.overlap(c, x);
            let back = net.contacts[c].contact.law.potential_energy(delta);
            dissipated -= back;
            let o = start_impact(net, c, x, t, impacts);
            impacts[o.row].dissipated_j -= back;
            open[c] = Some(o);
            touched |= !preloaded[c];
        }
    }
    (dissipated, touched)
}

/// The energy-balance residual `|E(0) + W − E − D| / (E(0) + |W|)` at `x` in mode `m`.
pub(super) fn residual(net: &Network, e0: f64, x: &[f64], w: f64, d: f64, m: NetMode) -> f64 {
    let (ke, pe) = net.energies(m, x);
    let denom = e0 + w.abs();
    let disc = e0 + w - ke - pe - d;
    if disc == 0.0 {
        0.0
    } else {
        disc.abs() / denom.max(f64::MIN_POSITIVE)
    }
}

/// The rows still open closed at the end of the run `t`, then the residuals and the energy
/// ratio (module documentation): `(residual_collision_end, energy_ratio)`.
/// `energies0 = (E(0), KE_b(0), E_b(0))` of [`Start`].
pub(super) fn close_rows_and_ratio(
    net: &Network,
    (energies0, preloaded): ((f64, f64, f64), &[bool]),
    (t, open): (f64, &[Option<OpenImpact>]),
    impacts: &mut [ImpactRow],
    collision_end: Option<&NetCollisionEnd>,
) -> (Option<f64>, Option<f64>) {
    let (e0, body_ke0, body_e0) = energies0;
    for o in open.iter().flatten() {
        let row = &mut impacts[o.row];
        row.duration_s = t - row.start_s;
        let (v, tv) = o.ext.peak();
        row.peak_force_n = Some(v);
        row.peak_time_s = tv;
    }
    match collision_end {
        Some(ce) => {
            // The mode at the collision's end: every non-preloaded contact open, the
            // preloaded ones as the state says.
            let m = (0..net.contacts.len()).fold(NetMode(0), |m, c| {
                m.with(c, preloaded[c] && net.overlap(c, &ce.x).0 > 0.0)
            });
            let r = residual(net, e0, &ce.x, ce.force_work_j, ce.dissipated_j, m);
            let e_in = body_ke0 + ce.force_work_j;
            let kept = body_e0 + ce.force_work_j - net.body_energy(&ce.x);
            (Some(r), (e_in > 0.0).then(|| kept / e_in))
        }
        None => (None, None),
    }
}

/// Per-contact bookkeeping of the impact now open on it.
pub(super) struct OpenImpact {
    pub row: usize,
    pub ext: Extremes,
}

/// Simulates the network for `opts.duration` (`opts.max_events` caps the switches; sample
/// output is not produced) from its initial state ([`initial_state`]): [`solve_from`] at it.
/// See the module documentation.
pub fn solve(net: &Network, opts: &Options) -> Result<NetSolution> {
    solve_from(net, initial_state(net)?, opts)
}

/// Simulates the network for `opts.duration` from the state `x0 = [x; ẋ]` (`2·dofs` values,
/// time restarting at 0): the mode at `x0` is decided by the same sign rules as at a switch
/// (each indicator's side is the sign of its first non-vanishing derivative), contacts closed
/// at `x0` open an impact row at t = 0 and a rigid contact closing there strikes, as at the
/// start of [`solve`]. The energy ratio's input `KE_b(0)` is the impactors' kinetic energy at
/// `x0` (the dampers' energy at `x0` is in `E_b(0)`): a blow of a train struck on a moving
/// machine ([`crate::analysis::network_blows`]).
pub fn solve_from(net: &Network, x0: Vec<f64>, opts: &Options) -> Result<NetSolution> {
    if !(opts.duration.is_finite() && opts.duration > 0.0) {
        return Err(Error::invalid(
            "simulation.duration",
            format!("must be > 0 s (got {})", opts.duration),
        ));
    }
    if x0.len() != 2 * net.dofs() || x0.iter().any(|v| !v.is_finite()) {
        return Err(Error::invalid(
            "initial state",
            format!(
                "needs {} finite values [x; ẋ] (got {}{})",
                2 * net.dofs(),
                x0.len(),
                if x0.iter().any(|v| !v.is_finite()) {
                    ", not all finite"
                } else {
                    ""
                }
            ),
        ));
    }
    if opts.method == super::Method::Dopri5 {
        return dopri5::solve_from(net, x0, opts);
    }
    if let Some(c) = net.first_nonlinear() {
        return Err(Error::invalid(
            format!("{}.law", net.contacts[c].name),
            "hertz and hunt-crossley contacts run with simulation.method = \"dopri5\" (the exact method takes linear and rigid laws)",
        ));
    }
    let mut run = Run::new(net, opts, x0)?;
    run.rigid_events()?;
    let ended_at_start = run.collision_ended() && opts.stop_at_collision_end;
    if !ended_at_start {
        run_stretches(&mut run, opts)?;
    }
    let sol = run.finish();
    check(net, &sol)?;
    Ok(sol)
}

/// The run's stretches and switches to its end (or the collision's, when asked).
fn run_stretches(run: &mut Run<'_, '_>, opts: &Options) -> Result<()> {
    loop {
        let switched = run.stretch()?;
        if !switched {
            break;
        }
        run.rigid_events()?;
        let new_mode = run.next_mode()?;
        if new_mode != run.mode {
            run.switch_to(new_mode)?;
            run.rigid_events()?;
        }
        if run.impacts.len() > opts.max_events {
            return Err(Error::numerical(
                "network propagator",
                format!(
                    "more than {} impacts by t = {:.6e} s (simulation.max_events)",
                    opts.max_events, run.t
                ),
            ));
        }
        if run.collision_ended() && opts.stop_at_collision_end {
            break;
        }
        if run.t >= opts.duration {
            break;
        }
    }
    Ok(())
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
    /// The state `x0`, its mode and energies, and the impacts of the contacts closed at t = 0.
    fn new(net: &'n Network, opts: &'o Options, x0: Vec<f64>) -> Result<Self> {
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
        let Start {
            e0,
            body_ke0,
            body_e0,
            preloaded,
            touched,
            impacts,
            open,
        } = Start::new(net, mode, &x0);
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
            e0,
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
        let md = self.modes.get(self.mode)?;
        let lam: Vec<Vec<f64>> = md.lambda.iter().map(|(_, l)| l.clone()).collect();
        let prop = md.propagator(&masses)?;
        let seg = prop.segment(&self.x);
        let period = prop.period();
        let held = net.held_bits(self.mode);
        let s_end = {
            let funcs: Vec<Functional<'_>> = self
                .modes
                .inds
                .iter()
                .map(|i| seg.functional(&i.l))
                .collect();
            let lam_funcs: Vec<Functional<'_>> = lam.iter().map(|l| seg.functional(l)).collect();
            let mut searches: Vec<Search<Lifted<&Functional<'_>>>> = funcs
                .iter()
                .zip(&self.signs)
                .zip(&self.modes.inds)
                .filter(|((_, s), ind)| **s != 0.0 && !held_overlap(held, ind))
                .map(|((f, s), ind)| {
                    let v = dot(&ind.l[..n], &self.x) + ind.l[n];
                    Search::new(Lifted::new(f, v, *s), *s, SearchOptions::default())
                })
                .collect();
            // A held rigid contact lets go when its constraint force λ (> 0 now) reaches 0.
            for (f, l) in lam_funcs.iter().zip(&lam) {
                let v = dot(&l[..n], &self.x) + l[n];
                searches.push(Search::new(
                    Lifted::new(f, v, 1.0),
                    1.0,
                    SearchOptions::default(),
                ));
            }
            let found = first_switch(&mut searches, period, horizon);
            found.map(|s| self.rigid_root(s, &funcs))
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

    /// The switch at `s` moved back onto the exact zero of a rigid contact's overlap when
    /// that is what ended the stretch: the search stops where the overlap is past zero by its
    /// round-off band, and an impact there would strike a little late and fast; over a train
    /// of bounces of shrinking speed `u` (a late time of band/u each) that bias accumulates.
    /// Two Newton steps on the overlap's closed form `δ(s)` give the zero to round-off.
    fn rigid_root(&self, s: f64, funcs: &[Functional<'_>]) -> f64 {
        let mut best = s;
        for ((f, ind), sign) in funcs.iter().zip(&self.modes.inds).zip(&self.signs) {
            if *sign >= 0.0 || !rigid_overlap(self.net, ind) {
                continue;
            }
            let (v, d) = f.value_slope(s);
            if !(v >= 0.0 && d > 0.0) {
                continue;
            }
            let mut r = s - v / d;
            for _ in 0..2 {
                let (v, d) = f.value_slope(r);
                if d > 0.0 {
                    r -= v / d;
                }
            }
            if r.is_finite() && r >= 0.0 && r < best {
                best = r;
            }
        }
        best
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
            if rigid_overlap(self.net, ind) {
                continue;
            }
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
        let t = self.t;
        let (jump, touched) = book_contacts(
            self.net,
            (self.mode, new_mode),
            (t, &self.x),
            &self.preloaded,
            &mut self.impacts,
            &mut self.open,
        );
        self.dissipated_j += jump;
        self.touched |= touched;
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

    /// The rigid contacts at an instant (t = 0 or a switch): held ones whose constraint force
    /// turns negative let go ([`Run::release_held`]), then the impacts of those closing
    /// ([`Run::rigid_impacts`]); the indicators' signs are then those of the new state.
    fn rigid_events(&mut self) -> Result<()> {
        if !(0..self.net.contacts.len()).any(|c| self.net.rigid(c).is_some()) {
            return Ok(());
        }
        let changed = self.release_held()? | self.rigid_impacts()?;
        if changed {
            self.mode = self.modes.select(&self.x, self.mode, &mut self.signs)?;
        }
        Ok(())
    }

    /// Lets go, one at a time, the held rigid contact whose constraint force `λ` is the most
    /// negative of those turning negative just after now (the sign of its first non-vanishing
    /// derivative, [`lex_signs`]); the others' forces are then those of the smaller set.
    fn release_held(&mut self) -> Result<bool> {
        let mut changed = false;
        loop {
            let md = self.modes.get(self.mode)?;
            if md.lambda.is_empty() {
                return Ok(changed);
            }
            let inds: Vec<NetIndicator> = md
                .lambda
                .iter()
                .map(|(c, l)| NetIndicator {
                    kind: IndicatorKind::Force(*c),
                    l: l.clone(),
                })
                .collect();
            let mut signs = vec![0.0; inds.len()];
            lex_signs(&inds, md, &self.x, &mut signs);
            let n = self.x.len();
            let worst = inds
                .iter()
                .zip(&signs)
                .filter(|(_, s)| **s < 0.0)
                .map(|(ind, _)| (ind, dot(&ind.l[..n], &self.x) + ind.l[n]))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            let Some((ind, _)) = worst else {
                return Ok(changed);
            };
            let IndicatorKind::Force(c) = ind.kind else {
                return Ok(changed);
            };
            self.switch_to(self.mode.with(c, false))?;
            changed = true;
        }
    }

    /// The rigid contacts at zero overlap (within the band [`lex_signs`] calls zero) and the
    /// ones held; `(contact, closing speed v = aᵀẋ, does it close?)`, where an open one closes
    /// when its overlap turns positive just after now.
    fn rigid_at_contact(&mut self) -> Result<Vec<(usize, f64, bool)>> {
        let net = self.net;
        let nd = net.dofs();
        let mut signs = vec![0.0; self.modes.inds.len()];
        self.modes.signs(self.mode, &self.x, &mut signs)?;
        let mut out = Vec::new();
        for (ind, sg) in self.modes.inds.iter().zip(&signs) {
            let IndicatorKind::Overlap(c) = ind.kind else {
                continue;
            };
            if net.rigid(c).is_none() {
                continue;
            }
            let (d, v) = net.overlap(c, &self.x);
            let a = net.contact_vector(c);
            let scale: f64 = a
                .iter()
                .zip(&self.x[..nd])
                .map(|(ai, xi)| (ai * xi).abs())
                .sum::<f64>()
                + net.contacts[c].gap.abs();
            if net.closed(self.mode, c) {
                out.push((c, v, false));
            } else if d.abs() <= VALUE_TOL * scale || (d > 0.0 && *sg > 0.0) {
                out.push((c, v, *sg > 0.0));
            }
        }
        Ok(out)
    }

    /// Newton impacts of the rigid contacts closing now (module documentation, "Rigid
    /// contacts"): the impulses of every rigid contact at zero overlap or held, from the
    /// complementarity problem of [`impulses_lcp`]; a contact whose rebound would end within
    /// round-off (the next apex `u²/(2aₙ)` inside the band [`lex_signs`] calls zero, or the
    /// rest of the bounces, `2u/(aₙ(1 − e))`, shorter than the clock's resolution `ε t`) is
    /// struck plastically instead and held from now on. Returns whether anything changed.
    fn rigid_impacts(&mut self) -> Result<bool> {
        let net = self.net;
        let nd = net.dofs();
        let set = self.rigid_at_contact()?;
        if !set.iter().any(|(_, _, closes)| *closes) {
            return Ok(false);
        }
        // The search stops just past the overlap's zero (within its round-off): put the
        // contacts that close exactly on it, along M⁻¹a (a shift within round-off, so no
        // overshoot accumulates over a train of bounces).
        let m = net.mass_diag();
        for (c, _, closes) in &set {
            if *closes {
                let (d, _) = net.overlap(*c, &self.x);
                let a = net.contact_vector(*c);
                let g: f64 = (0..nd).map(|k| a[k] * a[k] / m[k]).sum();
                for k in 0..nd {
                    self.x[k] -= a[k] / m[k] * d / g;
                }
            }
        }
        let r = set.len();
        let mut g = vec![0.0; r * r];
        for (i, (ci, _, _)) in set.iter().enumerate() {
            for (j, (cj, _, _)) in set.iter().enumerate() {
                let (ai, aj) = (net.contact_vector(*ci), net.contact_vector(*cj));
                g[i * r + j] = (0..nd).map(|k| ai[k] * aj[k] / m[k]).sum();
            }
        }
        let mode0 = self.mode;
        let t0 = self.t;
        let e_of = |c: usize, v: f64, plastic: bool| -> f64 {
            match net.rigid(c) {
                Some(e) if v > 0.0 && !plastic && !net.closed(mode0, c) => e,
                _ => 0.0,
            }
        };
        let solve = |plastic: &[bool]| -> Result<Vec<f64>> {
            let b: Vec<f64> = set
                .iter()
                .zip(plastic)
                .map(|((c, v, _), p)| (1.0 + e_of(*c, *v, *p)) * v)
                .collect();
            impulses_lcp(&g, &b).ok_or_else(|| {
                Error::numerical(
                    "network propagator",
                    format!(
                        "the impulses of {r} rigid contacts meeting at t = {t0:.9e} s have no solution (more than 16 at once, or dependent contacts)"
                    ),
                )
            })
        };
        let mut plastic = vec![false; r];
        let p = solve(&plastic)?;
        let rest = self.rests(&set, &g, &p)?;
        for (k, rt) in rest.iter().enumerate() {
            plastic[k] = rt.is_some();
        }
        let p = if plastic.iter().any(|x| *x) {
            solve(&plastic)?
        } else {
            p
        };
        self.apply_impulses(&set, &p);
        let mut mode = self.mode;
        for (k, rt) in rest.iter().enumerate() {
            if rt.is_some() {
                mode = mode.with(set[k].0, true);
            }
        }
        if mode != self.mode {
            self.switch_to(mode)?;
            for (k, rt) in rest.iter().enumerate() {
                if let (Some(tau), Some(o)) = (rt, &self.open[set[k].0]) {
                    // The collapsed bounces end (the contact comes to rest) τ later.
                    self.impacts[o.row].start_s = self.t + tau;
                }
            }
        }
        Ok(true)
    }

    /// For each contact of `set` that closes, struck by the impulses `p`: `Some(τ)` when its
    /// rebound ends within round-off (see [`Run::rigid_impacts`]), `τ = 2u/(aₙ(1 − e))` the
    /// time the remaining bounces take (0 for `e = 1`: a rebound within round-off).
    fn rests(
        &mut self,
        set: &[(usize, f64, bool)],
        g: &[f64],
        p: &[f64],
    ) -> Result<Vec<Option<f64>>> {
        let net = self.net;
        let nd = net.dofs();
        let n = 2 * nd;
        let r = set.len();
        let md = self.modes.get(self.mode)?;
        let mut out = vec![None; r];
        for (k, (c, v, closes)) in set.iter().enumerate() {
            let Some(e) = net.rigid(*c) else { continue };
            if !closes || net.closed(self.mode, *c) {
                continue;
            }
            let dv: f64 = (0..r).map(|j| g[k * r + j] * p[j]).sum();
            let u = (dv - v).max(0.0);
            // aₙ = d(aᵀẋ)/dt just after, under the mode with the contact open.
            let mut lv = vec![0.0; n + 1];
            lv[nd..n].copy_from_slice(net.contact_vector(*c));
            let slope = md.slope(&lv);
            let mut x = self.x.clone();
            let a = net.contact_vector(*c);
            let m = net.mass_diag();
            for i in 0..nd {
                x[nd + i] -= (0..r)
                    .map(|j| net.contact_vector(set[j].0)[i] * p[j])
                    .sum::<f64>()
                    / m[i];
            }
            let an = dot(&slope[..n], &x) + slope[n];
            if an.is_nan() || an <= 0.0 {
                continue;
            }
            let scale: f64 = a
                .iter()
                .zip(&x[..nd])
                .map(|(ai, xi)| (ai * xi).abs())
                .sum::<f64>()
                + net.contacts[*c].gap.abs();
            let tau = if e < 1.0 {
                2.0 * u / (an * (1.0 - e))
            } else {
                0.0
            };
            let apex = u * u / (2.0 * an);
            if apex <= VALUE_TOL * scale || (e < 1.0 && tau <= f64::EPSILON * self.t) {
                out[k] = Some(tau);
            }
        }
        Ok(out)
    }

    /// Applies the impulses `p` of the contacts `set` (`ẋ⁺ = ẋ − M⁻¹Σ a_c P_c`), books each
    /// one's dissipation `P_c (v_c⁻ + v_c⁺)/2` (the exact kinetic energy it removes) and its
    /// row: a new impact row (duration 0, no peak force) for an open contact, added to the
    /// resting row of a held one.
    fn apply_impulses(&mut self, set: &[(usize, f64, bool)], p: &[f64]) {
        let net = self.net;
        let nd = net.dofs();
        let m = net.mass_diag();
        for ((c, _, _), pc) in set.iter().zip(p) {
            let a = net.contact_vector(*c);
            for i in 0..nd {
                self.x[nd + i] -= a[i] * pc / m[i];
            }
        }
        for ((c, v, _), pc) in set.iter().zip(p) {
            if *pc <= 0.0 {
                continue;
            }
            let (_, after) = net.overlap(*c, &self.x);
            let lost = pc * (v + after) / 2.0;
            self.dissipated_j += lost;
            self.touched = true;
            if let Some(o) = &self.open[*c] {
                let row = &mut self.impacts[o.row];
                row.impulse_n_s += pc;
                row.dissipated_j += lost;
                continue;
            }
            self.impacts.push(ImpactRow {
                contact: net.contacts[*c].name.clone(),
                start_s: self.t,
                approach_velocity_m_per_s: *v,
                peak_force_n: None,
                peak_time_s: self.t,
                duration_s: 0.0,
                impulse_n_s: *pc,
                dissipated_j: lost,
                exit_velocity_m_per_s: Some(-after),
                restitution: (*v > 0.0).then(|| -after / v).filter(|e| e.is_finite()),
            });
        }
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
        residual(self.net, self.e0, x, w, d, m)
    }

    /// The finished run: the impacts still open closed at the end of the run, the residuals
    /// and the energy ratio (module documentation).
    fn finish(mut self) -> NetSolution {
        let net = self.net;
        let t = self.t;
        let force_work_j = net.force_work(&self.x0, &self.x);
        let residual_run_end = self.residual(&self.x, force_work_j, self.dissipated_j, self.mode);
        let (residual_collision_end, energy_ratio) = close_rows_and_ratio(
            net,
            ((self.e0, self.body_ke0, self.body_e0), &self.preloaded),
            (t, &self.open),
            &mut self.impacts,
            self.collision_end.as_ref(),
        );
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
    check_within(net, sol, RESIDUAL_BOUND, "exact")
}

/// [`check`] with the residual bound `bound` of the method `method` (named in the error).
pub(super) fn check_within(
    net: &Network,
    sol: &NetSolution,
    bound: f64,
    method: &str,
) -> Result<()> {
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
            if r.is_nan() || r > bound {
                return Err(Error::numerical(
                    "simulation",
                    format!(
                        "energy balance violated at the {what}: residual {r:.3e} of the energy put in > {bound:e} allowed ({method}); {} contacts, {} bodies{}",
                        net.contacts.len(),
                        net.bodies.len(),
                        if method == "dopri5" {
                            "; dopri5's residual follows its tolerance: a smaller simulation.rtol (e.g. 1e-10) tightens it"
                        } else {
                            ""
                        }
                    ),
                ));
            }
        }
    }
    Ok(())
}

pub(super) fn merge(into: &mut Extremes, e: &Extremes) {
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
    impacts.push(ImpactRow::opening(net.contacts[c].name.clone(), t, rate));
    OpenImpact {
        row: impacts.len() - 1,
        ext: Extremes::default(),
    }
}

fn finish_impact(row: &mut ImpactRow, ext: &Extremes, t: f64, rate: f64, jump: f64) {
    row.duration_s = t - row.start_s;
    let (v, tv) = ext.peak();
    row.peak_force_n = Some(v);
    row.peak_time_s = tv;
    row.dissipated_j += jump;
    row.exit_velocity_m_per_s = Some(-rate);
    row.restitution =
        (row.approach_velocity_m_per_s > 0.0).then(|| -rate / row.approach_velocity_m_per_s);
}

/// Is `ind` the overlap of a rigid contact held in `held`?
fn held_overlap(held: NetMode, ind: &NetIndicator) -> bool {
    matches!(ind.kind, IndicatorKind::Overlap(c) if held.on(c))
}

/// Is `ind` the overlap of a rigid contact?
fn rigid_overlap(net: &Network, ind: &NetIndicator) -> bool {
    matches!(ind.kind, IndicatorKind::Overlap(c) if net.rigid(c).is_some())
}
