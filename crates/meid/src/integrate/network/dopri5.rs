//! Dormand-Prince 5(4) for a general impact machine ([`crate::impact::network`]): any number
//! of contacts with linear, Hertz or Hunt-Crossley laws, and one-way dashpots.
//!
//! Within a step the mode `σ` (closed contacts, acting one-way dashpots) is frozen and the
//! right-hand side is
//!
//! ```text
//! M ẍ = −K_σ x − C_σ ẋ + f_σ − Σ_{c closed, non-linear} a_c f_c(δ_c, δ̇_c)
//! ```
//!
//! (`K_σ`, `C_σ`, `f_σ` of the linear elements, [`Network::matrices`]; `f_c` the Hertz law
//! `K δ^{3/2}` or Hunt-Crossley's `K δⁿ (1 + 3/2 α δ̇)`, [`crate::impact::ContactLaw::force`]),
//! integrated by the tableau, PI step control and 4th-order dense output of the paper
//! machine's engine ([`crate::integrate::dopri5`]: [`stages`], [`Dense`], [`initial_step`]). The state
//! carries, beside `[x; ẋ]`, the dissipated energy `D` (`Ḋ = ẋᵀC_σẋ + Σ (f_c − f_c,el) δ̇_c`,
//! `f_c,el = f_c(δ, 0)`), and per contact its impulse `∫f dt` and dissipation; they are not
//! under error control.
//!
//! **Switches.** Every indicator of [`Network::indicators`] is affine in the state: overlaps
//! `a_cᵀx − g_c`, the force-release functions `K δ + C δ̇` (linear) and `1 + 3/2 α δ̇`
//! (Hunt-Crossley; a Hertz contact never pulls, so it opens with its overlap), the relative
//! velocities of one-way dashpots. After each accepted step they are searched on the dense
//! output with the crossing search of the paper's engine ([`crate::integrate::roots`]; values and slopes
//! at the step ends with a Hermite dip test first, the search lifted by the indicator's zero
//! band `max(rtol/10, 1e-9)` of its terms); the step is cut at the first crossing. The new mode
//! is that of the signs of the indicators' first non-vanishing derivatives
//! ([`super`]'s rule, with the Jacobian of the right-hand side at the switch: exact for
//! linear laws, and for the first two derivatives with any law), candidate modes iterated to a
//! consistent one; an indicator the derivatives leave on the side it was searched from while
//! the state is past its zero takes the state's side. An indicator still zero to all orders (a
//! Hertz contact at zero overlap moves with fractional powers of time, so a structure struck
//! through it starts moving with all derivatives zero at t = 0) is settled by the motion: when
//! the next accepted step leaves it beyond its band on a side that implies another mode, it
//! left zero at once, and the step is redone from its start in that mode (as the paper
//! machine's engine does).
//!
//! **Outputs** are those of the exact engine ([`NetSolution`]): the same channels, with their
//! extremes located on the dense output (values and slopes at the step ends, the slope's root
//! where it changes sign or where the Hermite cubic of the ends has critical points,
//! [`extremes_on_step`]); a closed non-linear contact's force enters a channel as
//! `f_c(δ, δ̇)`, its slope as `∂f/∂δ δ̇ + ∂f/∂δ̇ δ̈`. Impact rows, the end of the collision and
//! the energy ratio are booked as by the exact engine ([`super::book_contacts`],
//! [`super::close_rows_and_ratio`]).
//!
//! **Energy balance**: `|E(0) + W − E − D| ≤ max(1e-6, 100·rtol) (E(0) + |W|)` at the end of
//! the collision and of the run (the paper engine's dopri5 bound,
//! `analysis::energy::residual_bound`); otherwise the run is an error.
//!
//! **Not done here**: rigid contacts (impulses and held constraints are the exact engine's:
//! refused with dopri5), and a held (resting) contact: a contact resting under a constant force
//! is integrated as it is, at the step its stiffness allows, and a one-way dashpot at rest
//! switches at the tolerance's noise. Such a run ends with an error from its guards (more than
//! `simulation.max_events` switches, 1000 rejected steps or switches without progress in a row,
//! a step below 16 ulps of `t`, or [`MAX_STEPS`] steps), never hangs.

use std::collections::HashMap;

use super::{
    book_contacts, channel_kinds, channel_vector, check_within, close_rows_and_ratio, lex_signs_of,
    merge, ChannelKind, ModeData, NetChannel, NetCollisionEnd, NetSolution, Start, VALUE_TOL,
};
use crate::impact::network::{dot, End, NetIndicator, NetMode, Network};
use crate::impact::SparseVec;
use crate::integrate::dopri5::{extremes_on_step, initial_step, scale, stages, Dense};
use crate::integrate::peaks::Extremes;
use crate::integrate::roots::{first_crossing, hermite_dip, Scalar, SearchOptions};
use crate::integrate::Options;
use crate::{Error, Result};

/// Consecutive rejected steps, or switches that do not advance time, before a run gives up.
const MAX_STALLED: usize = 1000;
/// Steps (accepted and rejected) a run may take.
pub const MAX_STEPS: usize = 50_000_000;

/// The energy-balance residual a dopri5 run must stay within (relative to the energy put in):
/// `max(1e-6, 100·rtol)`, as for the paper's machine.
pub fn residual_bound(opts: &Options) -> f64 {
    (100.0 * opts.rtol).max(1e-6)
}

/// A channel in a mode: its affine part `[ℓ; ℓ₀]` (of the linear elements) and the weights
/// `(c, w)` of the closed non-linear contacts' forces in it.
struct ChanVec {
    l: Option<SparseVec>,
    l0: f64,
    nl: Vec<(usize, f64)>,
}

/// One mode: the linear part's first-order data, the closed non-linear contacts, the channels.
struct DMode {
    md: ModeData,
    /// `C_σ` row-major (`nd × nd`), for `ẋᵀC_σẋ`.
    c: Vec<f64>,
    nl: Vec<usize>,
    chans: Vec<ChanVec>,
}

/// The machine's right-hand side and modes.
struct Rhs<'n> {
    net: &'n Network,
    nd: usize,
    nc: usize,
    minv: Vec<f64>,
    kinds: Vec<ChannelKind>,
    modes: HashMap<u64, DMode>,
}

impl<'n> Rhs<'n> {
    fn new(net: &'n Network) -> Self {
        Self {
            net,
            nd: net.dofs(),
            nc: net.contacts.len(),
            minv: net.mass_diag().iter().map(|m| 1.0 / m).collect(),
            kinds: channel_kinds(net),
            modes: HashMap::new(),
        }
    }

    /// Builds `mode`'s data on first use.
    fn prepare(&mut self, mode: NetMode) -> Result<()> {
        if self.modes.contains_key(&mode.0) {
            return Ok(());
        }
        let net = self.net;
        let nd = self.nd;
        let md = ModeData::new(net, mode)?;
        let c = (0..nd * nd).map(|k| md.c[(k / nd, k % nd)]).collect();
        let nl: Vec<usize> = (0..self.nc)
            .filter(|&c| net.closed(mode, c) && !net.contacts[c].contact.law.is_linear())
            .collect();
        let chans = self
            .kinds
            .iter()
            .map(|k| {
                let l = channel_vector(net, &md, mode, k);
                let n = 2 * nd;
                let lv = l[..n]
                    .iter()
                    .any(|v| *v != 0.0)
                    .then(|| SparseVec::new(&l[..n]));
                ChanVec {
                    l: lv,
                    l0: l[n],
                    nl: nonlinear_weights(net, &nl, k),
                }
            })
            .collect();
        self.modes.insert(mode.0, DMode { md, c, nl, chans });
        Ok(())
    }

    fn mode(&self, mode: NetMode) -> &DMode {
        &self.modes[&mode.0]
    }

    /// `dy = f(y)`, `y = [x; ẋ; D; impulses; contact dissipations]` (module documentation).
    fn eval(&self, mode: NetMode, y: &[f64], dy: &mut [f64]) {
        let (nd, nc) = (self.nd, self.nc);
        let n = 2 * nd;
        let dm = self.mode(mode);
        dy[..n].copy_from_slice(&dm.md.b);
        for (j, &yj) in y[..n].iter().enumerate() {
            if yj != 0.0 {
                for (o, a) in dy[..n].iter_mut().zip(&dm.md.a[j * n..(j + 1) * n]) {
                    *o += a * yj;
                }
            }
        }
        let v = &y[nd..n];
        let mut power = 0.0;
        for (i, vi) in v.iter().enumerate() {
            if *vi != 0.0 {
                power += vi * dot(&dm.c[i * nd..(i + 1) * nd], v);
            }
        }
        dy[n + 1..].iter_mut().for_each(|o| *o = 0.0);
        for c in 0..nc {
            if !self.net.closed(mode, c) {
                continue;
            }
            let law = &self.net.contacts[c].contact.law;
            let (d, r) = self.net.overlap(c, &y[..n]);
            let f = law.force(d, r);
            let loss = (f - elastic(law, d)) * r;
            dy[n + 1 + c] = f;
            dy[n + 1 + nc + c] = loss;
            if !law.is_linear() {
                let a = self.net.contact_vector(c);
                for i in 0..nd {
                    dy[nd + i] -= a[i] * f * self.minv[i];
                }
                power += loss;
            }
        }
        dy[n] = power;
    }

    /// The Jacobian `J` (column-major `n × n`) of the right-hand side at `x = [x; ẋ]` and
    /// `b = F(x) − J x`, for the derivatives of the mode selection.
    fn linearised(&self, mode: NetMode, x: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let nd = self.nd;
        let n = 2 * nd;
        let dm = self.mode(mode);
        let mut a = dm.md.a.clone();
        for &c in &dm.nl {
            let (d, r) = self.net.overlap(c, x);
            let (fd, fr) = self.net.contacts[c].contact.law.partials(d, r);
            let ac = self.net.contact_vector(c);
            for i in 0..nd {
                let w = ac[i] * self.minv[i];
                if w == 0.0 {
                    continue;
                }
                for j in 0..nd {
                    a[j * n + nd + i] -= w * fd * ac[j];
                    a[(nd + j) * n + nd + i] -= w * fr * ac[j];
                }
            }
        }
        let mut y = x.to_vec();
        y.resize(n + 1 + 2 * self.nc, 0.0);
        let mut f = vec![0.0; y.len()];
        self.eval(mode, &y, &mut f);
        let b = (0..n)
            .map(|i| f[i] - (0..n).map(|j| a[j * n + i] * x[j]).sum::<f64>())
            .collect();
        (a, b)
    }

    /// Channel `k`'s value and slope at the state `y`, `ẏ` in `mode`.
    fn channel(&self, mode: NetMode, k: usize, y: &[f64], yd: &[f64]) -> (f64, f64) {
        let nd = self.nd;
        let ch = &self.mode(mode).chans[k];
        let (mut v, mut d) = match &ch.l {
            Some(l) => (l.dot(y) + ch.l0, l.dot(yd)),
            None => (ch.l0, 0.0),
        };
        for &(c, w) in &ch.nl {
            let law = &self.net.contacts[c].contact.law;
            let (dl, r) = self.net.overlap(c, &y[..2 * nd]);
            let acc = dot(self.net.contact_vector(c), &yd[nd..2 * nd]);
            let (fd, fr) = law.partials(dl, r);
            v += w * law.force(dl, r);
            d += w * (fd * r + fr * acc);
        }
        (v, d)
    }
}

/// The elastic part `f(δ, 0)` of a law's force.
fn elastic(law: &crate::impact::ContactLaw, d: f64) -> f64 {
    law.force(d, 0.0)
}

/// The weights of the closed non-linear contacts `nl` in channel `kind`: 1 in its own contact
/// force, `∓1` in the floor force for a contact with the ground (end B, end A), and
/// `−ψ_Pᵀa_c` (mass-normalised modes) in the acceleration of point `P`.
fn nonlinear_weights(net: &Network, nl: &[usize], kind: &ChannelKind) -> Vec<(usize, f64)> {
    let nm = net.n_modes();
    nl.iter()
        .filter_map(|&c| {
            let w = match kind {
                ChannelKind::ContactForce(k) if *k == c => 1.0,
                ChannelKind::FloorForce if net.contacts[c].ends[1] == End::Ground => 1.0,
                ChannelKind::FloorForce if net.contacts[c].ends[0] == End::Ground => -1.0,
                ChannelKind::PointAcceleration(p) => {
                    let psi = net.structure.point(p).ok()?;
                    -dot(psi, &net.contact_vector(c)[..nm])
                }
                _ => 0.0,
            };
            (w != 0.0).then_some((c, w))
        })
        .collect()
}

/// An indicator on the dense output of a step, lifted by its zero band.
struct OnStep<'a> {
    dense: &'a Dense,
    l: &'a SparseVec,
    l0: f64,
    noise: f64,
}

impl Scalar for OnStep<'_> {
    fn value_slope(&self, s: f64) -> (f64, f64) {
        let (v, d) = self.dense.functional(self.l, s);
        (v + self.l0, d)
    }
    fn curvature_bound(&self, _a: f64, _b: f64) -> f64 {
        f64::INFINITY
    }
    fn fastest_period(&self) -> f64 {
        8.0 * self.dense.h()
    }
    fn noise(&self) -> f64 {
        self.noise
    }
}

/// Runs dopri5 on `net` from `x0` (module documentation); called by
/// [`super::solve_from`] for `Method::Dopri5`, which has checked `x0`.
pub fn solve_from(net: &Network, x0: Vec<f64>, opts: &Options) -> Result<NetSolution> {
    if !(opts.rtol > 0.0 && opts.rtol < 1.0 && opts.atol > 0.0) {
        return Err(Error::invalid(
            "simulation.rtol",
            format!(
                "dopri5 needs 0 < rtol < 1 and atol > 0 (got rtol {}, atol {})",
                opts.rtol, opts.atol
            ),
        ));
    }
    if let Some(c) = (0..net.contacts.len()).find(|&c| net.rigid(c).is_some()) {
        return Err(Error::invalid(
            format!("{}.law", net.contacts[c].name),
            "a rigid contact (law = \"rigid\") runs with simulation.method = \"exact\" only (its impulses and resting constraint are the exact engine's); give it law = \"linear\" with a stiffness and restitution to run dopri5",
        ));
    }
    let mut run = Run::new(net, x0, opts)?;
    run.integrate()?;
    let sol = run.finish();
    check_within(net, &sol, residual_bound(opts), "dopri5")?;
    Ok(sol)
}

/// The state of a run between steps.
struct Run<'n, 'o> {
    net: &'n Network,
    opts: &'o Options,
    rhs: Rhs<'n>,
    inds: Vec<NetIndicator>,
    /// The indicators' `ℓ` (sparse) and `ℓ₀`.
    ind_l: Vec<(SparseVec, f64)>,
    signs: Vec<f64>,
    /// Indicators zero to all orders at the last selection (module documentation).
    provisional: Vec<bool>,
    value_tol: f64,
    nd: usize,
    y: Vec<f64>,
    t: f64,
    mode: NetMode,
    start: Start,
    x0: Vec<f64>,
    mode0: NetMode,
    channels: Vec<NetChannel>,
    events: Vec<(f64, NetMode, NetMode)>,
    closed_time: Vec<f64>,
    collision_end: Option<NetCollisionEnd>,
    k: [Vec<f64>; 7],
    ytmp: Vec<f64>,
    ynew: Vec<f64>,
    dense: Dense,
    h: f64,
    facold: f64,
    last_reject: bool,
    need_k1: bool,
    steps: usize,
    stalled_rejects: usize,
    stalled_switches: usize,
}

impl<'n, 'o> Run<'n, 'o> {
    fn new(net: &'n Network, x0: Vec<f64>, opts: &'o Options) -> Result<Self> {
        let nd = net.dofs();
        let nc = net.contacts.len();
        let ny = 2 * nd + 1 + 2 * nc;
        let inds = net.indicators()?;
        let ind_l = inds
            .iter()
            .map(|i| (SparseVec::new(&i.l[..2 * nd]), i.l[2 * nd]))
            .collect();
        let mut run = Self {
            net,
            opts,
            rhs: Rhs::new(net),
            signs: vec![0.0; inds.len()],
            provisional: vec![false; inds.len()],
            inds,
            ind_l,
            value_tol: (opts.rtol / 10.0).max(VALUE_TOL),
            nd,
            y: Vec::new(),
            t: 0.0,
            mode: NetMode(0),
            start: Start::new(net, NetMode(0), &x0),
            x0: x0.clone(),
            mode0: NetMode(0),
            channels: channel_kinds(net)
                .into_iter()
                .map(|kind| NetChannel {
                    kind,
                    extremes: Extremes::default(),
                })
                .collect(),
            events: Vec::new(),
            closed_time: vec![0.0; nc],
            collision_end: None,
            k: std::array::from_fn(|_| vec![0.0; ny]),
            ytmp: vec![0.0; ny],
            ynew: vec![0.0; ny],
            dense: Dense::new(ny),
            h: 0.0,
            facold: 1e-4,
            last_reject: false,
            need_k1: true,
            steps: 0,
            stalled_rejects: 0,
            stalled_switches: 0,
        };
        let mode = run.select(&x0, NetMode(0))?;
        run.mode = mode;
        run.mode0 = mode;
        run.start = Start::new(net, mode, &x0);
        let mut y = x0;
        y.resize(ny, 0.0);
        run.y = y;
        Ok(run)
    }

    /// The indicators' signs just after `x` under `mode`'s dynamics (the exact engine's
    /// rule, with the Jacobian at `x`).
    fn signs_under(&mut self, mode: NetMode, x: &[f64]) -> Result<()> {
        self.rhs.prepare(mode)?;
        let (a, b) = self.rhs.linearised(mode, x);
        lex_signs_of(&self.inds, (&a, &b), x, self.value_tol, &mut self.signs);
        Ok(())
    }

    /// A consistent mode at `x` iterated from `start`, the indicators' signs under it; without
    /// a fixed point, the last candidate.
    fn select(&mut self, x: &[f64], start: NetMode) -> Result<NetMode> {
        let mut cand = start;
        let mut seen = vec![start];
        for _ in 0..(2 * self.inds.len() + 8) {
            self.signs_under(cand, x)?;
            let next = self.net.implied(&self.inds, &self.signs);
            if next == cand {
                break;
            }
            if seen.contains(&next) {
                self.signs_under(cand, x)?;
                break;
            }
            seen.push(next);
            cand = next;
        }
        for (p, s) in self.provisional.iter_mut().zip(&self.signs) {
            *p = *s == 0.0;
        }
        Ok(cand)
    }

    /// Indicators zero to all orders at the last selection (a Hertz contact at zero overlap
    /// moves with fractional powers of time), settled by where the accepted step took them:
    /// beyond their band, they take the side of the state; one whose side implies another
    /// mode left zero at once, and the step is redone from its start in that mode (returns
    /// true).
    fn settle_provisional(&mut self) -> Result<bool> {
        let n = 2 * self.nd;
        let mut forced = false;
        for (i, (l, l0)) in self.ind_l.iter().enumerate() {
            if !self.provisional[i] {
                continue;
            }
            let g = l.dot(&self.ynew[..n]) + l0;
            if g.abs() <= self.value_tol * terms(l, *l0, &self.ynew[..n]) {
                continue;
            }
            self.provisional[i] = false;
            self.signs[i] = g.signum();
            forced |= self.net.implied(&self.inds, &self.signs) != self.mode;
        }
        if !forced {
            return Ok(false);
        }
        let new_mode = self.net.implied(&self.inds, &self.signs);
        self.stalled_switches += 1;
        if self.stalled_switches > MAX_STALLED {
            return Err(self.stalled(&format!(
                "{MAX_STALLED} switches in a row without time advancing"
            )));
        }
        self.change_mode(new_mode)?;
        self.need_k1 = true;
        Ok(true)
    }

    /// The switch from the current mode to `new_mode` at `(t, y)`: the contacts' rows, the
    /// energy jumps of force-release contacts (into `D`), the event (more than
    /// `simulation.max_events` is an error).
    fn change_mode(&mut self, new_mode: NetMode) -> Result<()> {
        let n = 2 * self.nd;
        let (jump, touched) = book_contacts(
            self.net,
            (self.mode, new_mode),
            (self.t, &self.y[..n]),
            &self.start.preloaded,
            &mut self.start.impacts,
            &mut self.start.open,
        );
        self.y[n] += jump;
        self.start.touched |= touched;
        self.events.push((self.t, self.mode, new_mode));
        if self.events.len() > self.opts.max_events {
            return Err(Error::numerical(
                "dopri5",
                format!(
                    "more than {} switching events by t = {:.6e} s (simulation.max_events)",
                    self.opts.max_events, self.t
                ),
            ));
        }
        self.mode = new_mode;
        Ok(())
    }

    /// Steps to the end of the run (or of the collision, when asked).
    fn integrate(&mut self) -> Result<()> {
        let t_end = self.opts.duration;
        if self.collision_ended() && self.opts.stop_at_collision_end {
            return Ok(());
        }
        loop {
            if self.need_k1 {
                self.restart()?;
            }
            if self.t >= t_end * (1.0 - 1e-15) {
                return Ok(());
            }
            self.guard()?;
            let (rhs, mode) = (&self.rhs, self.mode);
            stages(
                |y, dy| rhs.eval(mode, y, dy),
                self.h,
                &self.y,
                &mut self.k,
                &mut self.ytmp,
                &mut self.ynew,
            );
            let err = self.err_norm();
            let fac11 = err.powf(0.2 - 0.04 * 0.75);
            if err > 1.0 || !err.is_finite() {
                self.reject(err, fac11)?;
                continue;
            }
            self.stalled_rejects = 0;
            self.steps += 1;
            if self.settle_provisional()? {
                continue;
            }
            self.dense.fill(self.h, &self.y, &self.ynew, &self.k);
            let (s_end, switched) = self.crossing();
            self.book_step(s_end);
            if switched {
                if self.switch_at(s_end)? && self.opts.stop_at_collision_end {
                    return Ok(());
                }
                continue;
            }
            self.y.copy_from_slice(&self.ynew);
            self.k.swap(0, 6);
            self.t += self.h;
            self.stalled_switches = 0;
            self.control(err, fac11);
        }
    }

    /// `k[0] = f(y)` in the current mode, and the first step size when there is none.
    fn restart(&mut self) -> Result<()> {
        self.rhs.prepare(self.mode)?;
        let (rhs, mode) = (&self.rhs, self.mode);
        rhs.eval(mode, &self.y, &mut self.k[0]);
        if self.h == 0.0 {
            let opts = self.opts;
            let sc = |a: f64, b: f64| scale(opts, a, b);
            let (k0, k1) = self.k.split_at_mut(1);
            self.h = initial_step(
                |y, dy| rhs.eval(mode, y, dy),
                2 * self.nd,
                &self.y,
                &k0[0],
                opts.duration - self.t,
                &mut self.ytmp,
                &mut k1[0],
                &sc,
            );
        }
        self.need_k1 = false;
        Ok(())
    }

    /// The step cut to the end of the run; a step below 16 ulps of `t` or more than
    /// [`MAX_STEPS`] steps is an error.
    fn guard(&mut self) -> Result<()> {
        self.h = self.h.min(self.opts.duration - self.t);
        if self.h.is_nan() || self.h <= 16.0 * f64::EPSILON * self.t.abs() {
            return Err(self.stalled("step size underflow"));
        }
        if self.steps > MAX_STEPS {
            return Err(self.stalled(&format!("{MAX_STEPS} steps taken")));
        }
        Ok(())
    }

    fn stalled(&self, what: &str) -> Error {
        let closed: Vec<&str> = (0..self.net.contacts.len())
            .filter(|&c| self.net.closed(self.mode, c))
            .map(|c| self.net.contacts[c].name.as_str())
            .collect();
        Error::numerical(
            "dopri5",
            format!(
                "no progress at t = {:.9e} s ({what}; closed contacts: {}). Likely cause: a contact stiffness too high for the tolerance (rtol {:e}, atol {:e}), contacts that chatter, or a body resting on a contact (dopri5 does not hold resting contacts on a general machine: simulation.method = \"exact\" does, with linear laws)",
                self.t,
                if closed.is_empty() { "none".into() } else { closed.join(", ") },
                self.opts.rtol,
                self.opts.atol
            ),
        )
    }

    /// The RMS error of `[x; ẋ]` in units of [`scale`].
    fn err_norm(&self) -> f64 {
        let n = 2 * self.nd;
        let s: f64 = (0..n)
            .map(|i| (self.ytmp[i] / scale(self.opts, self.y[i], self.ynew[i])).powi(2))
            .sum();
        (s / n as f64).sqrt()
    }

    fn reject(&mut self, err: f64, fac11: f64) -> Result<()> {
        self.stalled_rejects += 1;
        if self.stalled_rejects > MAX_STALLED {
            return Err(self.stalled(&format!(
                "{MAX_STALLED} consecutive rejected steps, last h = {:.3e} s",
                self.h
            )));
        }
        let f = if err.is_finite() {
            (fac11 / 0.9).min(5.0)
        } else {
            10.0
        };
        self.h /= f.max(1.0);
        self.last_reject = true;
        Ok(())
    }

    /// PI step-size control (β = 0.04), as the paper machine's engine.
    fn control(&mut self, err: f64, fac11: f64) {
        let h = self.h;
        let fac = (fac11 / self.facold.powf(0.04) / 0.9).clamp(0.1, 5.0);
        let mut hnew = h / fac;
        if self.last_reject {
            hnew = hnew.min(h);
        }
        self.last_reject = false;
        self.facold = err.max(1e-4);
        self.h = hnew;
    }

    /// The first crossing of a searched indicator on the step: `(s_end, switched)`.
    fn crossing(&self) -> (f64, bool) {
        let n = 2 * self.nd;
        let h = self.h;
        let (y, ynew) = (&self.y[..n], &self.ynew[..n]);
        let (k0, k6) = (&self.k[0][..n], &self.k[6][..n]);
        let mut s_end = h;
        let mut switched = false;
        for ((l, l0), &sg) in self.ind_l.iter().zip(&self.signs) {
            if sg == 0.0 {
                continue;
            }
            let noise = self.value_tol * terms(l, *l0, y);
            let ga = (sg * (l.dot(y) + l0) + noise).max(0.0);
            let da = sg * l.dot(k0);
            let gb = sg * (l.dot(ynew) + l0) + noise;
            let db = sg * l.dot(k6);
            if gb >= 0.0 && hermite_dip(ga, da, gb, db, h).is_none() {
                continue;
            }
            let f = OnStep {
                dense: &self.dense,
                l,
                l0: *l0,
                noise,
            };
            if let Some(s) = first_crossing(&f, s_end, sg, SearchOptions::default()) {
                if s < s_end || !switched {
                    s_end = s;
                    switched = true;
                }
            }
        }
        (s_end, switched)
    }

    /// The step's share of the channels' extremes, the open rows' peaks, impulses and
    /// dissipation, and the closed times, over `[t, t + s_end]`.
    fn book_step(&mut self, s_end: f64) {
        let ny = self.y.len();
        let (mode, t, nd, nc) = (self.mode, self.t, self.nd, self.net.contacts.len());
        let (mut y, mut yd) = (vec![0.0; ny], vec![0.0; ny]);
        let mut at = |s: f64, k: usize| -> (f64, f64) {
            self.dense.eval_with_slope(s, &mut y, &mut yd);
            self.rhs.channel(mode, k, &y, &yd)
        };
        for k in 0..self.channels.len() {
            let (v0, d0) = at(0.0, k);
            let (v1, d1) = at(s_end, k);
            let mut e = Extremes::default();
            e.offer(v0, t);
            extremes_on_step(|s| at(s, k), (v0, d0, v1, d1), t, s_end, &mut e);
            merge(&mut self.channels[k].extremes, &e);
            if let ChannelKind::ContactForce(c) = self.channels[k].kind {
                if let Some(o) = self.start.open[c].as_mut() {
                    merge(&mut o.ext, &e);
                }
            }
        }
        let mut end = vec![0.0; ny];
        self.dense.eval(s_end, &mut end);
        let n = 2 * nd;
        for c in 0..nc {
            if self.net.closed(mode, c) {
                self.closed_time[c] += s_end;
            }
            if let Some(o) = &self.start.open[c] {
                let row = &mut self.start.impacts[o.row];
                row.impulse_n_s += end[n + 1 + c] - self.y[n + 1 + c];
                row.dissipated_j += end[n + 1 + nc + c] - self.y[n + 1 + nc + c];
            }
        }
    }

    /// The switch at `s_end` in the step: the state there, the new mode, the rows booked.
    /// Returns whether the collision has ended.
    fn switch_at(&mut self, s_end: f64) -> Result<bool> {
        let n = 2 * self.nd;
        let mut y = vec![0.0; self.y.len()];
        self.dense.eval(s_end, &mut y);
        let t_before = self.t;
        self.t += s_end;
        let searched = self.signs.clone();
        let mut new_mode = self.select(&y[..n], self.mode)?;
        if new_mode == self.mode {
            // The trajectory decides what the derivatives cannot: an indicator past its zero
            // takes the state's side; one the derivatives call zero is not searched further.
            let mut moved = vec![false; self.signs.len()];
            for (i, (l, l0)) in self.ind_l.iter().enumerate() {
                let v = l.dot(&y[..n]) + l0;
                if searched[i] != 0.0 && searched[i] * v < 0.0 && self.signs[i] == searched[i] {
                    self.signs[i] = -searched[i];
                    moved[i] = true;
                } else if self.signs[i] * v <= 0.0 {
                    self.signs[i] = 0.0;
                }
            }
            if moved.iter().any(|m| *m) {
                new_mode = self.net.implied(&self.inds, &self.signs);
                let kept = self.signs.clone();
                self.signs_under(new_mode, &y[..n])?;
                for (i, m) in moved.iter().enumerate() {
                    if *m {
                        self.signs[i] = kept[i];
                    }
                }
            }
        }
        if s_end <= 0.0 || self.t == t_before {
            self.stalled_switches += 1;
            if self.stalled_switches > MAX_STALLED {
                return Err(self.stalled(&format!(
                    "{MAX_STALLED} switches in a row without time advancing"
                )));
            }
        } else {
            self.stalled_switches = 0;
        }
        self.y = y;
        if new_mode != self.mode {
            self.change_mode(new_mode)?;
        }
        self.need_k1 = true;
        Ok(self.collision_ended())
    }

    /// Records the end of the collision the first time every contact that was not preloaded
    /// is open again after one of them closed (as the exact engine does).
    fn collision_ended(&mut self) -> bool {
        if self.collision_end.is_some() {
            return true;
        }
        let net = self.net;
        let n = 2 * self.nd;
        let all_open =
            (0..net.contacts.len()).all(|c| self.start.preloaded[c] || !net.closed(self.mode, c));
        if self.start.touched && all_open {
            let x = self.y[..n].to_vec();
            self.collision_end = Some(NetCollisionEnd {
                t: self.t,
                force_work_j: net.force_work(&self.x0, &x),
                dissipated_j: self.y[n],
                x,
            });
        }
        self.collision_end.is_some()
    }

    fn finish(self) -> NetSolution {
        let net = self.net;
        let n = 2 * self.nd;
        let x = self.y[..n].to_vec();
        let dissipated_j = self.y[n];
        let force_work_j = net.force_work(&self.x0, &x);
        let Start {
            e0,
            body_ke0,
            body_e0,
            preloaded,
            mut impacts,
            open,
            ..
        } = self.start;
        let residual_run_end = super::residual(net, e0, &x, force_work_j, dissipated_j, self.mode);
        let (residual_collision_end, energy_ratio) = close_rows_and_ratio(
            net,
            ((e0, body_ke0, body_e0), &preloaded),
            (self.t, &open),
            &mut impacts,
            self.collision_end.as_ref(),
        );
        NetSolution {
            x0: self.x0,
            mode0: self.mode0,
            t_final: self.t,
            x_final: x,
            mode_final: self.mode,
            events: self.events,
            collision_end: self.collision_end,
            channels: self.channels,
            closed_time_s: self.closed_time,
            impacts,
            dissipated_j,
            force_work_j,
            residual_collision_end,
            residual_run_end,
            energy_ratio,
        }
    }
}

/// `Σ|ℓ_i x_i| + |ℓ₀|`: the size of an indicator's terms, to which its zero band is relative.
fn terms(l: &SparseVec, l0: f64, x: &[f64]) -> f64 {
    let (idx, val) = l.parts();
    idx.iter()
        .zip(val)
        .map(|(&i, v)| (v * x[i]).abs())
        .sum::<f64>()
        + l0.abs()
}
