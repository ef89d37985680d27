//! A general impact machine: a modal structure with any number of rigid impactors, impact
//! dampers and unilateral contacts between them (the paper's system, [`super::ImpactSystem`],
//! is one slider, one damper and two contacts of it).
//!
//! # Coordinates and sign convention
//! One axis `z`, positive in the direction the blows strike (downwards on a press), as for the
//! paper's system. Generalised coordinates, in this order:
//!
//! ```text
//! x = [q_1 … q_n,  z_1 … z_m]      (modal coordinates, then the bodies in the model's order:
//!                                   impactors first, then dampers)
//! ```
//!
//! `u_P = Σ_i ψ_i(P) q_i` is the displacement of structure point `P`, `z_b` that of body `b`,
//! and the ground does not move. `M = diag(1, …, 1, m_1 … m_m)` (mass-normalised modes).
//!
//! # Elements
//! | element | relative displacement | force while acting | acts |
//! |---|---|---|---|
//! | contact `between = [A, B]`, gap `g` | overlap `δ = u_A − u_B − g = aᵀx − g` | `f = K δ + C δ̇` (closed only) | `−f` on A, `+f` on B |
//! | damper suspension (k, c) | `δ_s = z_d − u_anchor` (`u_anchor = 0` for the ground) | `f_s = k δ_s + c δ̇_s` | `−f_s` on the damper, `+f_s` on the anchor |
//!
//! A contact's first end A is the one on the side the blow comes from: it closes by moving in
//! `+z` towards B (the paper's slider-bed contact is `between = [slider, bed]`, its bed-damper
//! contact `between = [bed, damper]`). A gap `g > 0` is a clearance at `x = 0`; `g < 0` a
//! preload (the contact overlaps by `−g` at `x = 0`).
//!
//! With `σ` the mode (which contacts are closed, which one-way dashpots act), the equations are
//! `M ẍ + C_σ ẋ + K_σ x = f_σ` with
//!
//! ```text
//! K_σ = diag(ω²) ⊕ 0 + Σ_s k_s a_s a_sᵀ + Σ_{c closed} K_c a_c a_cᵀ
//! C_σ = D ⊕ 0 + Σ_{s acting} c_s a_s a_sᵀ + Σ_{c closed} C_c a_c a_cᵀ
//! f_σ = Σ_b F_b e_b + Σ_{c closed} K_c g_c a_c
//! ```
//!
//! (`D` the structure's modal damping, `F_b` an impactor's constant force): affine, exact
//! between switches ([`crate::integrate::network`]). A closed contact with a non-linear law
//! (Hertz `f = Kδ^{3/2}`, Hunt-Crossley `f = Kδⁿ(1 + 3/2 αδ̇)`) is left out of `K_σ`, `C_σ`,
//! `f_σ`: dopri5 adds its force `−a_c f_c(δ, δ̇)` ([`crate::integrate::network::dopri5`]).
//!
//! # Switching rules
//! As in the paper's system: a contact is closed while `δ > 0` and, with the force-release rule
//! and a damped law, while `f > 0`; a one-way dashpot acts while `δ̇_s < 0` (the damper moving
//! back towards its anchor side); a two-way dashpot always acts. A mode is a bit set of up to
//! [`MAX_SWITCHES`] switches: the contacts in the model's order, then the one-way dashpots.

use faer::Mat;

use super::{Contact, ContactLaw, DashpotKind, Release};
use crate::modal::ModalModel;
use crate::{Error, Result};

/// The most switches (contacts plus one-way dashpots) a network may have: a mode is a 64-bit set.
pub const MAX_SWITCHES: usize = 64;

/// What a contact end or a suspension anchor is.
#[derive(Debug, Clone, PartialEq)]
pub enum End {
    /// A named point of the structure.
    Point(String),
    /// A body, by its index in [`Network::bodies`].
    Body(usize),
    /// The ground (does not move).
    Ground,
}

/// A rigid body: an impactor (initial velocity, constant force) or a damper mass.
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    pub name: String,
    /// m (kg).
    pub mass: f64,
    /// Velocity at t = 0 (m/s, positive along +z).
    pub velocity: f64,
    /// A constant force from t = 0 (N, positive along +z), e.g. its weight.
    pub force: f64,
}

/// A damper's spring and dashpot between its mass and an anchor.
#[derive(Debug, Clone, PartialEq)]
pub struct Suspension {
    /// Name of the damper (for reports).
    pub name: String,
    /// Index of the damper's mass in [`Network::bodies`].
    pub body: usize,
    /// k (N/m).
    pub stiffness: f64,
    /// c (N·s/m).
    pub damping: f64,
    pub dashpot: DashpotKind,
    /// A structure point or the ground.
    pub anchor: End,
}

/// A unilateral contact between two ends.
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    pub name: String,
    /// `[A, B]`: A strikes B moving along +z.
    pub ends: [End; 2],
    /// g (m): > 0 open at x = 0, < 0 preloaded.
    pub gap: f64,
    pub contact: Contact,
}

/// A switch of the network's piecewise system.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NetSwitch {
    /// Contact `i` ([`Network::contacts`]) closed.
    Contact(usize),
    /// One-way dashpot of suspension `j` acting.
    Dashpot(usize),
}

/// The discrete state: bit `k` set when switch `k` ([`Network::switches`]) is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, PartialOrd, Ord)]
pub struct NetMode(pub u64);

impl NetMode {
    /// Is switch `k` on?
    #[inline]
    pub fn on(self, k: usize) -> bool {
        (self.0 >> k) & 1 == 1
    }
    /// This mode with switch `k` set to `on`.
    #[inline]
    pub fn with(self, k: usize, on: bool) -> Self {
        if on {
            NetMode(self.0 | 1 << k)
        } else {
            NetMode(self.0 & !(1 << k))
        }
    }
}

/// A scalar whose sign decides a switch: `g = ℓᵀX + ℓ₀` of the state `X = [x; ẋ]`.
#[derive(Debug, Clone, PartialEq)]
pub struct NetIndicator {
    pub kind: IndicatorKind,
    /// `[ℓ; ℓ₀]`, length `2·dofs + 1`.
    pub l: Vec<f64>,
}

/// What an indicator measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IndicatorKind {
    /// The overlap `δ` of contact `i`.
    Overlap(usize),
    /// The sign of the force of contact `i` (force-release rule, damped law): `K δ + C δ̇`
    /// (linear), `1 + 3/2 α δ̇` (Hunt-Crossley).
    Force(usize),
    /// The relative velocity `δ̇_s` of suspension `j` (one-way dashpot).
    DashpotVelocity(usize),
}

/// The general impact system. See the module documentation.
#[derive(Debug, Clone)]
pub struct Network {
    pub structure: ModalModel,
    pub bodies: Vec<Body>,
    pub suspensions: Vec<Suspension>,
    pub contacts: Vec<Link>,
    /// `a_c` of each contact (`δ = a_cᵀx − g_c`).
    rel: Vec<Vec<f64>>,
    /// `a_s` of each suspension (`δ_s = a_sᵀx`).
    spring_rel: Vec<Vec<f64>>,
    switches: Vec<NetSwitch>,
}

impl Network {
    /// Assembles and checks the network. Field names in errors: `impactor[i]`/`damper[i]`
    /// (bodies named by the caller's `body_fields`), `contact[i]`.
    pub fn new(
        structure: &ModalModel,
        bodies: Vec<Body>,
        suspensions: Vec<Suspension>,
        contacts: Vec<Link>,
    ) -> Result<Self> {
        structure.validate()?;
        for b in &bodies {
            let f = |what: &str| format!("{}.{what}", b.name);
            if !(b.mass.is_finite() && b.mass > 0.0) {
                return Err(Error::invalid(
                    f("mass"),
                    format!(
                        "must be a finite number > 0 kg (got {})",
                        crate::num(b.mass)
                    ),
                ));
            }
            if !b.velocity.is_finite() {
                return Err(Error::invalid(
                    f("velocity"),
                    "must be a finite number (m/s)",
                ));
            }
            if !b.force.is_finite() {
                return Err(Error::invalid(f("force"), "must be a finite number (N)"));
            }
        }
        let point = |e: &End, field: &str| -> Result<()> {
            match e {
                End::Point(p) => structure.point(p).map(|_| ()).map_err(|e| match e {
                    Error::InvalidValue { message, .. } => Error::invalid(field, message),
                    other => other,
                }),
                End::Body(i) if *i >= bodies.len() => {
                    Err(Error::invalid(field, format!("no body {i}")))
                }
                _ => Ok(()),
            }
        };
        for s in &suspensions {
            for (v, what) in [(s.stiffness, "stiffness"), (s.damping, "damping")] {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(Error::invalid(
                        format!("{}.{what}", s.name),
                        format!("must be a finite number ≥ 0 (got {})", crate::num(v)),
                    ));
                }
            }
            point(&s.anchor, &format!("{}.anchor", s.name))?;
            if s.anchor == End::Body(s.body) {
                return Err(Error::invalid(
                    format!("{}.anchor", s.name),
                    "a damper cannot be anchored to itself",
                ));
            }
        }
        for c in &contacts {
            for e in &c.ends {
                point(e, &format!("{}.between", c.name))?;
            }
            if c.ends[0] == c.ends[1] {
                return Err(Error::invalid(
                    format!("{}.between", c.name),
                    "a contact needs two different ends (it joins a body or point to itself)",
                ));
            }
            if !c.gap.is_finite() {
                return Err(Error::invalid(
                    format!("{}.gap", c.name),
                    format!(
                        "must be a finite number of metres (> 0 open, < 0 preloaded; got {})",
                        crate::num(c.gap)
                    ),
                ));
            }
            super::check_contact(&c.name, &c.contact)?;
            if matches!(c.contact.law, ContactLaw::Rigid { .. }) && c.gap < 0.0 {
                return Err(Error::invalid(
                    format!("{}.gap", c.name),
                    format!(
                        "a rigid contact cannot be preloaded (gap = {} m would overlap it): give a gap ≥ 0",
                        crate::num(c.gap)
                    ),
                ));
            }
        }
        let one_way = suspensions
            .iter()
            .filter(|s| s.dashpot == DashpotKind::OneWay && s.damping > 0.0)
            .count();
        if contacts.len() + one_way > MAX_SWITCHES {
            return Err(Error::invalid(
                "contact",
                format!(
                    "{} contacts and {one_way} one-way dashpots make {} switches; meid handles at most {MAX_SWITCHES}",
                    contacts.len(),
                    contacts.len() + one_way
                ),
            ));
        }
        let mut net = Self {
            structure: structure.clone(),
            bodies,
            suspensions,
            contacts,
            rel: Vec::new(),
            spring_rel: Vec::new(),
            switches: Vec::new(),
        };
        net.rel = net
            .contacts
            .iter()
            .map(|c| net.difference(&c.ends[0], &c.ends[1]))
            .collect();
        net.spring_rel = net
            .suspensions
            .iter()
            .map(|s| net.difference(&End::Body(s.body), &s.anchor))
            .collect();
        net.switches = (0..net.contacts.len()).map(NetSwitch::Contact).collect();
        for (j, s) in net.suspensions.iter().enumerate() {
            if s.dashpot == DashpotKind::OneWay && s.damping > 0.0 {
                net.switches.push(NetSwitch::Dashpot(j));
            }
        }
        Ok(net)
    }

    /// `a` with `aᵀx = u_A − u_B`.
    fn difference(&self, a: &End, b: &End) -> Vec<f64> {
        let mut v = vec![0.0; self.dofs()];
        for (e, sign) in [(a, 1.0), (b, -1.0)] {
            match e {
                End::Point(p) => {
                    if let Ok(psi) = self.structure.point(p) {
                        for (vi, pi) in v.iter_mut().zip(psi) {
                            *vi += sign * pi;
                        }
                    }
                }
                End::Body(i) => v[self.n_modes() + i] += sign,
                End::Ground => {}
            }
        }
        v
    }

    /// Number of structural modes n.
    #[inline]
    pub fn n_modes(&self) -> usize {
        self.structure.len()
    }
    /// Number of second-order coordinates (modes and bodies).
    #[inline]
    pub fn dofs(&self) -> usize {
        self.n_modes() + self.bodies.len()
    }
    /// The switches, in bit order.
    pub fn switches(&self) -> &[NetSwitch] {
        &self.switches
    }
    /// `a_c` of contact `c` (`δ = a_cᵀx − g_c`).
    pub fn contact_vector(&self, c: usize) -> &[f64] {
        &self.rel[c]
    }
    /// `a_s` of suspension `j` (`δ_s = a_sᵀx`).
    pub fn suspension_vector(&self, j: usize) -> &[f64] {
        &self.spring_rel[j]
    }
    /// Masses of the coordinates: `[1, …, 1, m_1 … m_m]`.
    pub fn mass_diag(&self) -> Vec<f64> {
        let mut m = vec![1.0; self.n_modes()];
        m.extend(self.bodies.iter().map(|b| b.mass));
        m
    }

    /// Is contact `c` closed in `mode`?
    #[inline]
    pub fn closed(&self, mode: NetMode, c: usize) -> bool {
        mode.on(c)
    }

    /// Does the dashpot of suspension `j` act in `mode`?
    pub fn dashpot_on(&self, mode: NetMode, j: usize) -> bool {
        let s = &self.suspensions[j];
        match s.dashpot {
            DashpotKind::TwoWay => true,
            DashpotKind::OneWay => self
                .switches
                .iter()
                .position(|w| *w == NetSwitch::Dashpot(j))
                .is_some_and(|k| mode.on(k)),
        }
    }

    /// The restitution of contact `c` when its law is rigid ([`ContactLaw::Rigid`]).
    pub fn rigid(&self, c: usize) -> Option<f64> {
        match self.contacts[c].contact.law {
            ContactLaw::Rigid { restitution } => Some(restitution),
            _ => None,
        }
    }

    /// The first contact with a non-linear law (Hertz or Hunt-Crossley), which only dopri5
    /// runs.
    pub fn first_nonlinear(&self) -> Option<usize> {
        self.contacts.iter().position(|c| {
            !c.contact.law.is_linear() && !matches!(c.contact.law, ContactLaw::Rigid { .. })
        })
    }

    /// The rigid contacts held (closed, as constraints `a_cᵀx = g_c`) in `mode`.
    pub fn held(&self, mode: NetMode) -> Vec<usize> {
        (0..self.contacts.len())
            .filter(|&c| self.closed(mode, c) && self.rigid(c).is_some())
            .collect()
    }

    /// The bits of `mode`'s held rigid contacts.
    pub fn held_bits(&self, mode: NetMode) -> NetMode {
        self.held(mode)
            .into_iter()
            .fold(NetMode(0), |m, c| m.with(c, true))
    }

    /// `(K, C)` of contact `c`'s linear law; an error for a non-linear law (a rigid law has
    /// none: see [`Self::rigid`]; Hertz and Hunt-Crossley are dopri5's).
    pub fn linear_law(&self, c: usize) -> Result<(f64, f64)> {
        match self.contacts[c].contact.law {
            ContactLaw::Linear { stiffness, damping } => Ok((stiffness, damping)),
            ContactLaw::Rigid { .. } => Err(Error::invalid(
                format!("{}.law", self.contacts[c].name),
                "a rigid contact has no stiffness or damping (internal: asked for its linear law)",
            )),
            _ => Err(Error::invalid(
                format!("{}.law", self.contacts[c].name),
                "the exact method takes linear and rigid contact laws; hertz and hunt-crossley need simulation.method = \"dopri5\"",
            )),
        }
    }

    /// `K_σ`, `C_σ` (`dofs × dofs`) and the forcing `f_σ` (length `dofs`) of a mode (module
    /// documentation); with held rigid contacts, those of the constrained mode
    /// ([`Self::constrained`]).
    pub fn matrices(&self, mode: NetMode) -> Result<(Mat<f64>, Mat<f64>, Vec<f64>)> {
        let (k, c, f) = self.free_matrices(mode)?;
        let held = self.held(mode);
        if held.is_empty() {
            return Ok((k, c, f));
        }
        self.constrained(&held, k, c, f)
    }

    /// `K_σ`, `C_σ`, `f_σ` of the elements of a mode, without the held rigid contacts'
    /// constraints (a rigid contact adds no stiffness, damping or forcing) and without the
    /// closed non-linear contacts (Hertz, Hunt-Crossley: their forces are added by dopri5,
    /// [`crate::integrate::network::dopri5`]).
    fn free_matrices(&self, mode: NetMode) -> Result<(Mat<f64>, Mat<f64>, Vec<f64>)> {
        let nd = self.dofs();
        let n = self.n_modes();
        let mut k = Mat::<f64>::zeros(nd, nd);
        let mut c = Mat::<f64>::zeros(nd, nd);
        for i in 0..n {
            k[(i, i)] = self.structure.omega_rad_per_s[i].powi(2);
            for j in 0..n {
                c[(i, j)] = self.structure.damping[i * n + j];
            }
        }
        let mut add = |a: &[f64], kk: f64, cc: f64| {
            for i in 0..nd {
                if a[i] == 0.0 {
                    continue;
                }
                for j in 0..nd {
                    if a[j] != 0.0 {
                        k[(i, j)] += kk * a[i] * a[j];
                        c[(i, j)] += cc * a[i] * a[j];
                    }
                }
            }
        };
        for (j, s) in self.suspensions.iter().enumerate() {
            let cc = if self.dashpot_on(mode, j) {
                s.damping
            } else {
                0.0
            };
            add(&self.spring_rel[j], s.stiffness, cc);
        }
        let mut f = vec![0.0; nd];
        for (b, body) in self.bodies.iter().enumerate() {
            f[n + b] = body.force;
        }
        for ci in 0..self.contacts.len() {
            if self.closed(mode, ci) && self.contacts[ci].contact.law.is_linear() {
                let (kk, cc) = self.linear_law(ci)?;
                add(&self.rel[ci], kk, cc);
                let g = self.contacts[ci].gap;
                for (fi, ai) in f.iter_mut().zip(&self.rel[ci]) {
                    *fi += kk * g * ai;
                }
            }
        }
        Ok((k, c, f))
    }

    /// The indicators whose signs decide the switches.
    pub fn indicators(&self) -> Result<Vec<NetIndicator>> {
        let nd = self.dofs();
        let mut out = Vec::new();
        for sw in &self.switches {
            match *sw {
                NetSwitch::Contact(ci) => {
                    let a = &self.rel[ci];
                    let g = self.contacts[ci].gap;
                    let mut l = vec![0.0; 2 * nd + 1];
                    l[..nd].copy_from_slice(a);
                    l[2 * nd] = -g;
                    out.push(NetIndicator {
                        kind: IndicatorKind::Overlap(ci),
                        l,
                    });
                    if self.rigid(ci).is_some() {
                        continue;
                    }
                    if self.contacts[ci].contact.release != Release::Force {
                        continue;
                    }
                    // The force's sign function, affine in the state:
                    // K δ + C δ̇ (linear), 1 + 3/2 α δ̇ (Hunt-Crossley); Hertz never pulls.
                    let mut l = vec![0.0; 2 * nd + 1];
                    match self.contacts[ci].contact.law {
                        ContactLaw::Linear { stiffness, damping } if damping != 0.0 => {
                            for i in 0..nd {
                                l[i] = stiffness * a[i];
                                l[nd + i] = damping * a[i];
                            }
                            l[2 * nd] = -stiffness * g;
                        }
                        ContactLaw::HuntCrossley { alpha, .. } if alpha != 0.0 => {
                            for i in 0..nd {
                                l[nd + i] = 1.5 * alpha * a[i];
                            }
                            l[2 * nd] = 1.0;
                        }
                        _ => continue,
                    }
                    out.push(NetIndicator {
                        kind: IndicatorKind::Force(ci),
                        l,
                    });
                }
                NetSwitch::Dashpot(j) => {
                    let mut l = vec![0.0; 2 * nd + 1];
                    l[nd..2 * nd].copy_from_slice(&self.spring_rel[j]);
                    out.push(NetIndicator {
                        kind: IndicatorKind::DashpotVelocity(j),
                        l,
                    });
                }
            }
        }
        Ok(out)
    }

    /// The mode implied by the signs of [`Self::indicators`] (in their order): a contact is
    /// closed when its overlap (and, if searched, its force) is positive; a one-way dashpot
    /// acts when its relative velocity is negative. A sign 0 (identically zero) leaves a
    /// contact open and a dashpot off. A rigid contact is left open: whether it is held is
    /// decided by its impacts and constraint force ([`crate::integrate::network`]).
    pub fn implied(&self, inds: &[NetIndicator], signs: &[f64]) -> NetMode {
        let mut closed: Vec<bool> = (0..self.contacts.len())
            .map(|c| self.rigid(c).is_none())
            .collect();
        let mut mode = NetMode(0);
        for (ind, s) in inds.iter().zip(signs) {
            match ind.kind {
                IndicatorKind::Overlap(c) | IndicatorKind::Force(c) => closed[c] &= *s > 0.0,
                IndicatorKind::DashpotVelocity(j) => {
                    if let Some(k) = self
                        .switches
                        .iter()
                        .position(|w| *w == NetSwitch::Dashpot(j))
                    {
                        mode = mode.with(k, *s < 0.0);
                    }
                }
            }
        }
        for (c, on) in closed.into_iter().enumerate() {
            mode = mode.with(c, on);
        }
        mode
    }

    /// Overlap `δ` and rate `δ̇` of contact `c` at the state `X = [x; ẋ]`.
    pub fn overlap(&self, c: usize, x: &[f64]) -> (f64, f64) {
        let nd = self.dofs();
        let a = &self.rel[c];
        (
            dot(a, &x[..nd]) - self.contacts[c].gap,
            dot(a, &x[nd..2 * nd]),
        )
    }

    /// The force of contact `c` (N) in `mode` at `X`: `K δ + C δ̇` closed, 0 open.
    pub fn contact_force(&self, mode: NetMode, c: usize, x: &[f64]) -> f64 {
        if !self.closed(mode, c) {
            return 0.0;
        }
        let (d, r) = self.overlap(c, x);
        self.contacts[c].contact.law.force(d, r)
    }

    /// Kinetic and potential energy (J) at `X` in `mode`: `½ẋᵀMẋ` and
    /// `½Σω_i²q_i² + Σ_s ½k_sδ_s² + Σ_{closed} ½K_cδ_c²`.
    pub fn energies(&self, mode: NetMode, x: &[f64]) -> (f64, f64) {
        let nd = self.dofs();
        let n = self.n_modes();
        let m = self.mass_diag();
        let ke = 0.5 * (0..nd).map(|i| m[i] * x[nd + i] * x[nd + i]).sum::<f64>();
        let mut pe = 0.5
            * (0..n)
                .map(|i| (self.structure.omega_rad_per_s[i] * x[i]).powi(2))
                .sum::<f64>();
        for (j, s) in self.suspensions.iter().enumerate() {
            pe += 0.5 * s.stiffness * dot(&self.spring_rel[j], &x[..nd]).powi(2);
        }
        for c in 0..self.contacts.len() {
            if self.closed(mode, c) {
                pe += self.contacts[c]
                    .contact
                    .law
                    .potential_energy(self.overlap(c, x).0);
            }
        }
        (ke, pe)
    }

    /// The energy of the bodies at `X`: their kinetic energies and the suspensions' spring
    /// energies (J), the paper's `E_s + E_d` (Eqs. 11-13).
    pub fn body_energy(&self, x: &[f64]) -> f64 {
        let nd = self.dofs();
        let n = self.n_modes();
        let mut e: f64 = self
            .bodies
            .iter()
            .enumerate()
            .map(|(b, body)| 0.5 * body.mass * x[nd + n + b].powi(2))
            .sum();
        for (j, s) in self.suspensions.iter().enumerate() {
            e += 0.5 * s.stiffness * dot(&self.spring_rel[j], &x[..nd]).powi(2);
        }
        e
    }

    /// The work of the constant body forces between `x0` and `x` (J): `Σ_b F_b (z_b − z_b0)`.
    pub fn force_work(&self, x0: &[f64], x: &[f64]) -> f64 {
        let n = self.n_modes();
        self.bodies
            .iter()
            .enumerate()
            .map(|(b, body)| body.force * (x[n + b] - x0[n + b]))
            .sum()
    }

    /// True when something carries force to the floor: the structure's ground reactions, a
    /// suspension anchored to the ground or a contact with the ground.
    pub fn has_floor_force(&self) -> bool {
        self.structure.floor_force.is_some()
            || self.suspensions.iter().any(|s| s.anchor == End::Ground)
            || self.contacts.iter().any(|c| c.ends.contains(&End::Ground))
    }
}

/// Rigid contacts held as constraints.
///
/// With the held contacts' vectors as the columns of `A` (`nd × r`), their gaps `g`,
/// `G = AᵀM⁻¹A` and the M-orthogonal projector `P = I − M⁻¹A G⁻¹Aᵀ` (onto the motions that
/// keep `Aᵀx` fixed), the constrained motion `M ẍ = f − Cẋ − Kx − Aλ`, `Aᵀx = g` is, exactly,
///
/// ```text
/// M ẍ + C' ẋ + K' x = f',   K' = PᵀKP + α₁α₂ A G⁻¹Aᵀ,   C' = PᵀCP + (α₁+α₂) A G⁻¹Aᵀ,
///                           f' = Pᵀ(f − K x_g) + α₁α₂ A G⁻¹ g,   x_g = M⁻¹A G⁻¹ g:
/// ```
///
/// `AᵀM⁻¹` of it gives `z̈ + (α₁+α₂)ż + α₁α₂(z − g) = 0` for `z = Aᵀx` (PᵀA = 0), so a state
/// on the manifold (`Aᵀx = g`, `Aᵀẋ = 0`) stays on it and the α-terms vanish there, and the
/// rest is the constrained dynamics `M P ẍ = Pᵀ(f − C P ẋ − K P x − K x_g)` (with `x = Px + x_g`,
/// `ẋ = Pẋ` on the manifold). `K'`, `C'` are symmetric, so the mode has the same closed form
/// as any other ([`crate::integrate::propagator`]); the two distinct rates
/// `α₁ = ω_r`, `α₂ = 2ω_r` (`ω_r` the Gershgorin bound of the mode's fastest rate, from
/// `M^{-½}KM^{-½}` and `M^{-½}CM^{-½}`; 1 rad/s when it has neither) make the constraint block
/// diagonalisable (a projection alone would leave a defective double zero eigenvalue). The
/// constraint forces (compressive positive) are `λ = G⁻¹AᵀM⁻¹(f − Cẋ − Kx)` of the free `K`,
/// `C`, `f` ([`Network::constraint_forces`]), affine in the state.
impl Network {
    /// `A` (column per held contact, column-major `nd × r`), `G⁻¹` (`r × r`) and `M⁻¹`.
    fn held_system(&self, held: &[usize]) -> Result<(Vec<f64>, Vec<f64>, Vec<f64>)> {
        let nd = self.dofs();
        let r = held.len();
        let minv: Vec<f64> = self.mass_diag().iter().map(|m| 1.0 / m).collect();
        let a: Vec<f64> = held
            .iter()
            .flat_map(|&c| self.rel[c].iter().copied())
            .collect();
        let mut g = vec![0.0; r * r];
        for i in 0..r {
            for j in 0..r {
                g[i * r + j] = (0..nd)
                    .map(|k| a[i * nd + k] * minv[k] * a[j * nd + k])
                    .sum();
            }
        }
        let ginv = invert(&g, r).ok_or_else(|| {
            let names: Vec<&str> = held
                .iter()
                .map(|&c| self.contacts[c].name.as_str())
                .collect();
            Error::invalid(
                format!("{}.between", names[0]),
                format!(
                    "the rigid contacts {} resting at once hold the same motion twice (their vectors aᵀ are dependent): the impulses between them are not determined; make one of them linear",
                    names.join(", ")
                ),
            )
        })?;
        Ok((a, ginv, minv))
    }

    /// `K'`, `C'`, `f'` of the mode with the rigid contacts `held` held (see above).
    pub(crate) fn constrained(
        &self,
        held: &[usize],
        k: Mat<f64>,
        c: Mat<f64>,
        f: Vec<f64>,
    ) -> Result<(Mat<f64>, Mat<f64>, Vec<f64>)> {
        let nd = self.dofs();
        let r = held.len();
        let (a, ginv, minv) = self.held_system(held)?;
        // B = M⁻¹ A G⁻¹ (nd × r), H = A G⁻¹ Aᵀ (nd × nd), P = I − B Aᵀ.
        let b = |i: usize, j: usize| -> f64 {
            (0..r)
                .map(|l| minv[i] * a[l * nd + i] * ginv[l * r + j])
                .sum()
        };
        let bm = Mat::from_fn(nd, r, b);
        let am = Mat::from_fn(nd, r, |i, j| a[j * nd + i]);
        let p = Mat::<f64>::identity(nd, nd) - &bm * am.transpose();
        let h = Mat::<f64>::from_fn(nd, nd, |i, j| {
            (0..r)
                .map(|l| {
                    a[l * nd + i] * (0..r).map(|m| ginv[l * r + m] * a[m * nd + j]).sum::<f64>()
                })
                .sum::<f64>()
        });
        let gaps: Vec<f64> = held.iter().map(|&c| self.contacts[c].gap).collect();
        let xg: Vec<f64> = (0..nd)
            .map(|i| (0..r).map(|j| bm[(i, j)] * gaps[j]).sum())
            .collect();
        let rate = |m: &Mat<f64>| -> f64 {
            (0..nd)
                .map(|i| {
                    (0..nd)
                        .map(|j| m[(i, j)].abs() * (minv[i] * minv[j]).sqrt())
                        .sum::<f64>()
                })
                .fold(0.0, f64::max)
        };
        let mut w = rate(&k).sqrt().max(rate(&c));
        if !(w.is_finite() && w > 0.0) {
            w = 1.0;
        }
        let (a1, a2) = (w, 2.0 * w);
        let mut kp = p.transpose() * &k * &p;
        let mut cp = p.transpose() * &c * &p;
        for i in 0..nd {
            for j in 0..nd {
                // Exactly symmetric (the products above are up to round-off).
                let (ks, cs) = (
                    0.5 * (kp[(i, j)] + kp[(j, i)]),
                    0.5 * (cp[(i, j)] + cp[(j, i)]),
                );
                kp[(i, j)] = ks + a1 * a2 * h[(i, j)];
                cp[(i, j)] = cs + (a1 + a2) * h[(i, j)];
            }
        }
        let kxg: Vec<f64> = (0..nd)
            .map(|i| f[i] - (0..nd).map(|j| k[(i, j)] * xg[j]).sum::<f64>())
            .collect();
        let mut fp: Vec<f64> = (0..nd)
            .map(|i| (0..nd).map(|j| p[(j, i)] * kxg[j]).sum())
            .collect();
        for (i, fi) in fp.iter_mut().enumerate() {
            let ag: f64 = (0..r)
                .map(|l| a[l * nd + i] * (0..r).map(|m| ginv[l * r + m] * gaps[m]).sum::<f64>())
                .sum();
            *fi += a1 * a2 * ag;
        }
        Ok((kp, cp, fp))
    }

    /// The constraint forces of the rigid contacts held in `mode`, as affine functionals
    /// `[ℓ; ℓ₀]` (length `2·dofs + 1`) of the state: `λ = G⁻¹AᵀM⁻¹(f − Cẋ − Kx)` with the
    /// mode's free `K`, `C`, `f` (N, compressive positive), in the order of [`Self::held`].
    pub fn constraint_forces(&self, mode: NetMode) -> Result<Vec<(usize, Vec<f64>)>> {
        let held = self.held(mode);
        if held.is_empty() {
            return Ok(Vec::new());
        }
        let nd = self.dofs();
        let r = held.len();
        let (k, c, f) = self.free_matrices(mode)?;
        let (a, ginv, minv) = self.held_system(&held)?;
        Ok(held
            .iter()
            .enumerate()
            .map(|(row, &ci)| {
                // w = M⁻¹ A G⁻¹ e_row.
                let w: Vec<f64> = (0..nd)
                    .map(|i| {
                        (0..r)
                            .map(|l| minv[i] * a[l * nd + i] * ginv[l * r + row])
                            .sum()
                    })
                    .collect();
                let mut l = vec![0.0; 2 * nd + 1];
                for j in 0..nd {
                    l[j] = -(0..nd).map(|i| w[i] * k[(i, j)]).sum::<f64>();
                    l[nd + j] = -(0..nd).map(|i| w[i] * c[(i, j)]).sum::<f64>();
                }
                l[2 * nd] = dot(&w, &f);
                (ci, l)
            })
            .collect())
    }
}

/// The impulses `P ≥ 0` of simultaneous rigid impacts: the linear complementarity problem
/// `w = G P − b ≥ 0`, `P ≥ 0`, `Pᵀw = 0` (`G = AᵀM⁻¹A` row-major `r × r`, `b_c` the velocity
/// change each contact needs: `(1 + e_c) v_c` closing, `v_c` otherwise; `w_c` is then how much
/// faster than `e_c v_c` contact `c` separates), solved by enumerating the active sets in
/// order of size (exact for the few contacts meeting at one instant; `G` positive definite
/// has exactly one solution). `None` without a solution within round-off, or for more than
/// 16 contacts at once.
pub(crate) fn impulses_lcp(g: &[f64], b: &[f64]) -> Option<Vec<f64>> {
    let r = b.len();
    if r > 16 {
        return None;
    }
    let tol = 1e-12
        * b.iter().fold(0.0_f64, |m, v| m.max(v.abs()))
        * (1.0 + (0..r).map(|i| g[i * r + i]).fold(0.0_f64, f64::max));
    let mut sets: Vec<u32> = (0..(1u32 << r)).collect();
    sets.sort_by_key(|s| (s.count_ones(), *s));
    for set in sets {
        let idx: Vec<usize> = (0..r).filter(|i| set >> i & 1 == 1).collect();
        let k = idx.len();
        let mut p = vec![0.0; r];
        if k > 0 {
            let sub: Vec<f64> = idx
                .iter()
                .flat_map(|&i| idx.iter().map(move |&j| g[i * r + j]))
                .collect();
            let Some(inv) = invert(&sub, k) else {
                continue;
            };
            for (a, &i) in idx.iter().enumerate() {
                p[i] = (0..k).map(|c| inv[a * k + c] * b[idx[c]]).sum();
            }
        }
        if p.iter().any(|v| *v < -tol) {
            continue;
        }
        let ok = (0..r).all(|i| {
            set >> i & 1 == 1 || (0..r).map(|j| g[i * r + j] * p[j]).sum::<f64>() - b[i] >= -tol
        });
        if ok {
            return Some(p.into_iter().map(|v| v.max(0.0)).collect());
        }
    }
    None
}

/// The inverse of the `r × r` row-major matrix `g` by Gauss-Jordan elimination with partial
/// pivoting; `None` when a pivot falls below `1e-12` of the largest diagonal entry (singular).
pub(crate) fn invert(g: &[f64], r: usize) -> Option<Vec<f64>> {
    let scale = (0..r).map(|i| g[i * r + i].abs()).fold(0.0, f64::max);
    let mut m = g.to_vec();
    let mut inv = vec![0.0; r * r];
    for i in 0..r {
        inv[i * r + i] = 1.0;
    }
    for col in 0..r {
        let piv =
            (col..r).max_by(|&x, &y| m[x * r + col].abs().total_cmp(&m[y * r + col].abs()))?;
        let pivot = m[piv * r + col].abs();
        if pivot.is_nan() || pivot <= 1e-12 * scale {
            return None;
        }
        for j in 0..r {
            m.swap(col * r + j, piv * r + j);
            inv.swap(col * r + j, piv * r + j);
        }
        let d = m[col * r + col];
        for j in 0..r {
            m[col * r + j] /= d;
            inv[col * r + j] /= d;
        }
        for i in 0..r {
            if i != col {
                let fct = m[i * r + col];
                if fct != 0.0 {
                    for j in 0..r {
                        m[i * r + j] -= fct * m[col * r + j];
                        inv[i * r + j] -= fct * inv[col * r + j];
                    }
                }
            }
        }
    }
    Some(inv)
}

/// `Σ aᵢbᵢ`.
#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
