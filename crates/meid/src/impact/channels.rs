//! The response channels meid reports peaks, histories and spectra of.
//!
//! Every channel is a function of the state `X = [x; ẋ]` and the mode `σ` (which contacts are
//! closed, whether the one-way dashpot acts). For linear contact laws it is a linear functional
//! `ℓ_σᵀX` within a mode ([`ChannelMap::vectors`]), so on an exact stretch it is a polynomial
//! (Taylor step) or a sum of exponentials (closed form) and its extrema can be located exactly.
//! At a switch the mode changes and so may `ℓ_σ` (the bed acceleration jumps when a contact
//! closes): both one-sided values belong to the record.
//!
//! | channel | value | unit |
//! |---|---|---|
//! | bed displacement at B | `u_B = φ_Bᵀq` | m |
//! | bed velocity at B | `u̇_B = φ_Bᵀq̇` | m/s |
//! | bed acceleration at B | `ü_B = φ_Bᵀq̈`, `q̈` from Eq. (9) | m/s² |
//! | force to the floor | ground reactions of the structure (+ `f_fd` with the damper on the ground) | N |
//! | slider-bed contact force | `f_bs` (Eq. 5), 0 while open | N |
//! | bed-damper contact force | `f_bd` (Eq. 8), 0 while open | N |
//! | damper spring force | `k_d (z_d − u_f)` (Eq. 6, elastic part) | N |
//! | damper dashpot force | `c_d (ż_d − u̇_f)` while it acts (Eqs. 6-7) | N |

use super::{dot, ContactLaw, DashpotKind, ImpactSystem, Mode, Switch};

/// A response channel. See the module documentation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Channel {
    BedDisplacement,
    BedVelocity,
    BedAcceleration,
    FloorForce,
    ContactSliderBed,
    ContactBedDamper,
    DamperSpring,
    DamperDashpot,
}

/// Number of channels.
pub const N_CHANNELS: usize = 8;

/// All channels, in the order of their index ([`Channel::index`]).
pub const CHANNELS: [Channel; N_CHANNELS] = [
    Channel::BedDisplacement,
    Channel::BedVelocity,
    Channel::BedAcceleration,
    Channel::FloorForce,
    Channel::ContactSliderBed,
    Channel::ContactBedDamper,
    Channel::DamperSpring,
    Channel::DamperDashpot,
];

impl Channel {
    /// Position in [`CHANNELS`].
    #[inline]
    pub fn index(self) -> usize {
        self as usize
    }
    /// Stable key (JSON, CSV), with the SI unit as suffix.
    pub fn key(self) -> &'static str {
        match self {
            Channel::BedDisplacement => "bed_displacement_m",
            Channel::BedVelocity => "bed_velocity_m_per_s",
            Channel::BedAcceleration => "bed_acceleration_m_per_s2",
            Channel::FloorForce => "floor_force_n",
            Channel::ContactSliderBed => "contact_force_slider_bed_n",
            Channel::ContactBedDamper => "contact_force_bed_damper_n",
            Channel::DamperSpring => "damper_spring_force_n",
            Channel::DamperDashpot => "damper_dashpot_force_n",
        }
    }
    /// Human label.
    pub fn label(self) -> &'static str {
        match self {
            Channel::BedDisplacement => "bed displacement at B",
            Channel::BedVelocity => "bed velocity at B",
            Channel::BedAcceleration => "bed acceleration at B",
            Channel::FloorForce => "force to the floor",
            Channel::ContactSliderBed => "contact force slider-bed",
            Channel::ContactBedDamper => "contact force bed-damper",
            Channel::DamperSpring => "damper spring force",
            Channel::DamperDashpot => "damper dashpot force",
        }
    }
    /// SI unit.
    pub fn unit(self) -> &'static str {
        match self {
            Channel::BedDisplacement => "m",
            Channel::BedVelocity => "m/s",
            Channel::BedAcceleration => "m/s²",
            _ => "N",
        }
    }
    /// True for the channels that exist only with an impact damper.
    pub fn needs_damper(self) -> bool {
        matches!(
            self,
            Channel::ContactBedDamper | Channel::DamperSpring | Channel::DamperDashpot
        )
    }
}

/// Evaluates the channels of one system: values at any state (any contact law) and, for
/// linear laws, the vectors `ℓ_σ` with `value = ℓ_σᵀX` in mode `σ`.
///
/// The bed acceleration is Eq. (9) folded with `φ_B` once:
/// `ü_B = wqᵀq + wvᵀq̇ + w_c (f_bs − f_bd) + w_f f_fd` with `wq = −φ_B∘ω²`, `wv = −Dᵀφ_B`,
/// `w_c = φ_Bᵀψ_b`, `w_f = φ_Bᵀψ_f`.
#[derive(Debug, Clone)]
pub struct ChannelMap {
    acc_q: Vec<f64>,
    acc_v: Vec<f64>,
    acc_contact: f64,
    acc_damper: f64,
}

impl ChannelMap {
    pub fn new(sys: &ImpactSystem) -> Self {
        let n = sys.n_modes();
        let phi = &sys.points.measurement;
        let w = &sys.structure.omega_rad_per_s;
        let d = &sys.structure.damping;
        ChannelMap {
            acc_q: (0..n).map(|i| -phi[i] * (w[i] * w[i])).collect(),
            acc_v: (0..n)
                .map(|j| -(0..n).map(|i| phi[i] * d[i * n + j]).sum::<f64>())
                .collect(),
            acc_contact: dot(phi, &sys.points.bed_contact),
            acc_damper: sys
                .points
                .damper_anchor
                .as_ref()
                .map_or(0.0, |f| dot(phi, f)),
        }
    }

    /// All channel values at the state `X = [x; ẋ]` in `mode` (any contact law), indexed by
    /// [`Channel::index`].
    pub fn values(&self, sys: &ImpactSystem, mode: Mode, x: &[f64]) -> [f64; N_CHANNELS] {
        let n = sys.n_modes();
        let nd = sys.dofs();
        let m = sys.motions(x);
        let (fbs, fbd, ffd) = if mode.any_held() {
            sys.element_forces(mode, x)
        } else {
            sys.element_forces_from(mode, &m)
        };
        let phi = &sys.points.measurement;
        let a_b = dot(&self.acc_q, &x[..n])
            + dot(&self.acc_v, &x[nd..nd + n])
            + self.acc_contact * (fbs - fbd)
            + self.acc_damper * ffd;
        let (spring, dashpot) = match &sys.damper {
            Some(d) => {
                let on = d.dashpot == DashpotKind::TwoWay || mode.on(Switch::Dashpot);
                (
                    d.stiffness * m[2].0,
                    if on { d.damping * m[2].1 } else { 0.0 },
                )
            }
            None => (0.0, 0.0),
        };
        [
            dot(phi, &x[..n]),
            dot(phi, &x[nd..nd + n]),
            a_b,
            sys.floor_force_with(x, ffd),
            fbs,
            fbd,
            spring,
            dashpot,
        ]
    }

    /// The vectors `ℓ_σ` (length `2·dofs`) with `value = ℓ_σᵀX` in `mode`, indexed by
    /// [`Channel::index`], written into `out`; `None` when a closed contact of `mode` has a
    /// non-linear law (its force is not linear in the state). A channel that is identically
    /// zero in `mode` (an open contact's force, the dashpot while it does not act) gets the
    /// zero vector.
    pub fn vectors(&self, sys: &ImpactSystem, mode: Mode) -> Option<[Vec<f64>; N_CHANNELS]> {
        let m = 2 * sys.dofs();
        let mut flat = vec![0.0; N_CHANNELS * m];
        self.vectors_into(sys, mode, &mut flat)?;
        let mut rows = flat.chunks_exact(m).map(<[f64]>::to_vec);
        Some(std::array::from_fn(|_| rows.next().unwrap_or_default()))
    }

    /// [`Self::vectors`] without allocating: channel `c`'s vector into
    /// `out[c·2·dofs .. (c+1)·2·dofs]` (`out` of length `N_CHANNELS · 2 · dofs`, overwritten).
    /// `None` (with `out` partly written) when a closed contact of `mode` is non-linear.
    ///
    /// # Panics
    /// When `out` has the wrong length.
    pub fn vectors_into(&self, sys: &ImpactSystem, mode: Mode, out: &mut [f64]) -> Option<()> {
        let n = sys.n_modes();
        let nd = sys.dofs();
        let m = 2 * nd;
        assert_eq!(out.len(), N_CHANNELS * m, "channel vector buffer");
        out.fill(0.0);
        if mode.any_held() {
            // A held contact's force is a multiplier, not `K aᵀx + C aᵀẋ`.
            return None;
        }
        let row = |c: Channel| c.index() * m;
        // f = K aᵀx + C aᵀẋ of a closed linear contact.
        for (s, c) in [
            (Switch::SliderBed, Channel::ContactSliderBed),
            (Switch::BedDamper, Channel::ContactBedDamper),
        ] {
            if s == Switch::BedDamper && sys.damper.is_none() || !mode.on(s) {
                continue;
            }
            let ContactLaw::Linear { stiffness, damping } = sys.contact(s).law else {
                return None;
            };
            let a = sys.relative_vector(s);
            let l = &mut out[row(c)..row(c) + m];
            for i in 0..nd {
                l[i] = stiffness * a[i];
                l[nd + i] = damping * a[i];
            }
        }
        if let Some(d) = &sys.damper {
            let a = sys.relative_vector(Switch::Dashpot);
            let on = d.dashpot == DashpotKind::TwoWay || mode.on(Switch::Dashpot);
            let (rs, rd) = (row(Channel::DamperSpring), row(Channel::DamperDashpot));
            for i in 0..nd {
                out[rs + i] = d.stiffness * a[i];
                if on {
                    out[rd + nd + i] = d.damping * a[i];
                }
            }
        }
        let phi = &sys.points.measurement;
        let (rx, rv, ra, rf) = (
            row(Channel::BedDisplacement),
            row(Channel::BedVelocity),
            row(Channel::BedAcceleration),
            row(Channel::FloorForce),
        );
        out[rx..rx + n].copy_from_slice(phi);
        out[rv + nd..rv + nd + n].copy_from_slice(phi);
        out[ra..ra + n].copy_from_slice(&self.acc_q);
        out[ra + nd..ra + nd + n].copy_from_slice(&self.acc_v);
        out[rf..rf + n].copy_from_slice(&sys.floor.stiffness);
        out[rf + nd..rf + nd + n].copy_from_slice(&sys.floor.damping);
        let anchored_to_ground = sys.damper.is_some() && sys.points.damper_anchor.is_none();
        let (rbs, rbd) = (
            row(Channel::ContactSliderBed),
            row(Channel::ContactBedDamper),
        );
        let (rs, rd) = (row(Channel::DamperSpring), row(Channel::DamperDashpot));
        for i in 0..m {
            let ffd = out[rs + i] + out[rd + i];
            out[ra + i] += self.acc_contact * (out[rbs + i] - out[rbd + i]) + self.acc_damper * ffd;
            if anchored_to_ground {
                out[rf + i] += ffd;
            }
        }
        Some(())
    }
}
