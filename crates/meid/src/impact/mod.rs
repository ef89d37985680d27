//! The impact system of the paper (Eqs. 1-9): slider, bed (a modal structure), impact damper.
//!
//! # Coordinates and sign convention
//! All displacements are along one axis `z`, **positive in the direction the slider moves when
//! it strikes** (downwards on a press). Generalised coordinates, in this order:
//!
//! ```text
//! x = [q_1 … q_n,  z_s,  z_d]      (z_d only when there is an impact damper)
//! ```
//!
//! `q_i` are the modal coordinates of the structure (mass-normalised modes, paper Eq. 9),
//! `u_P = Σ_i Ψ_i(P) q_i` the displacement of structure point `P`. All start at rest at 0,
//! with the slider touching the bed (`z_s = u_b = 0`) at `v_s`, and the damper touching the bed
//! from the other side (`u_b = z_d = 0`) without preload (gravity and static preloads of the
//! structure are equilibrium offsets and drop out of the linear dynamics).
//!
//! A constant force `F ≥ 0` on the slider (its weight on a vertical hammer, a drive pressure:
//! [`ImpactSystem::with_slider_force`], model field `slider.force`) acts from t = 0; it does not
//! drop out, because the slider leaves the bed and comes back. With it the equations are
//! `M ẍ + C_σ ẋ + K_σ x = F e_s`: affine, `Ẋ = A_σ X + b`.
//!
//! Forces (paper Eqs. 5-8), each a spring-dashpot acting on a relative displacement `δ = aᵀx`:
//!
//! | element | `δ` | force | acts |
//! |---|---|---|---|
//! | slider-bed contact (K_s, C_s) | `z_s − u_b` (overlap) | `f_bs = K_s δ + C_s δ̇` while closed | `−f_bs` on the slider, `+f_bs` on the bed at O_b |
//! | bed-damper contact (K_d, C_d) | `u_b − z_d` (overlap) | `f_bd = K_d δ + C_d δ̇` while closed | `−f_bd` on the bed, `+f_bd` on the damper |
//! | damper spring + dashpot (k_d, c_d) | `z_d − u_f` | `f_fd = k_d δ + c_d δ̇` | `−f_fd` on the damper, `+f_fd` on the base at O_f |
//!
//! so that `M ẍ + C_σ ẋ + K_σ x = F e_s` (`F = 0` unless set), with `M = diag(1,…,1, m_s, m_d)` and `K_σ`, `C_σ`
//! depending on the *mode* `σ`: which contacts are closed and whether the one-way dashpot acts.
//!
//! # Switching rules
//! * A contact is **closed** while its overlap `δ > 0`. With [`Release::Force`] (the default) it
//!   also needs a compressive force `f > 0`, so a damped contact never pulls: it releases when the
//!   force returns to zero, slightly before the overlap does. [`Release::Overlap`] is Eq. (5)/(8)
//!   literally: the contact holds until `δ = 0` and may pull (`C δ̇ < 0`) just before release.
//!   With `C = 0` the two rules coincide.
//! * The damper dashpot is **one-way** (Eq. 7): `c_d` acts only while `ż_d − u̇_f < 0`,
//!   i.e. while the damper moves back towards the bed; the damper moves away from the bed freely.
//!   [`DashpotKind::TwoWay`] makes it act always.
//!
//! The restitution a contact law gives a free two-body impact, and the damping that gives a
//! requested one: [`restitution`].
//!
//! Between switches the system is linear and time invariant (for [`ContactLaw::Linear`]);
//! [`crate::integrate`] propagates it exactly. Hertz and Hunt-Crossley laws need `dopri5`.

mod channels;
pub mod network;
pub mod restitution;

pub use channels::{Channel, ChannelMap, CHANNELS, N_CHANNELS};

use faer::Mat;

use crate::modal::{FloorForce, ModalModel};
use crate::{Error, Result};

/// Force law of a unilateral contact as a function of overlap `δ > 0` and its rate `δ̇`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactLaw {
    /// `f = K δ + C δ̇` (K in N/m, C in N·s/m): paper Eqs. (5) and (8).
    Linear { stiffness: f64, damping: f64 },
    /// `f = K δ^{3/2}` (K in N/m^1.5): Hertz contact of curved surfaces.
    Hertz { stiffness: f64 },
    /// Hunt-Crossley: `f = K δ^n (1 + 3/2 α δ̇)` (K in N/m^n, α in s/m); `n = 1.5` for Hertzian
    /// geometry. The coefficient of restitution of a free impact at approach velocity `v₀` is
    /// about `1 − α v₀` for small `α v₀`; exactly [`restitution::e_of_x`] of `x = 3/2 α v₀`.
    HuntCrossley {
        stiffness: f64,
        exponent: f64,
        alpha: f64,
    },
    /// Rigid (instantaneous) contact with Newton's restitution `e ∈ [0, 1]`: on closing at an
    /// approach velocity `v_in = aᵀẋ > 0` the impulse `J = (1 + e) v_in / (aᵀM⁻¹a)` along `a`
    /// gives `aᵀẋ⁺ = −e v_in` and removes `½(1 − e²) v_in² / (aᵀM⁻¹a)` (Newton's law of
    /// restitution, e.g. Pfeiffer & Glocker, *Multibody Dynamics with Unilateral Contacts*,
    /// 1996, ch. 6); while resting it is the constraint `aᵀx = g` with a force `λ ≥ 0`. The
    /// stiff limit `K → ∞` of a linear contact with the same restitution. General machines
    /// only ([`crate::integrate::network`]); the paper's engine refuses it.
    Rigid { restitution: f64 },
}

impl ContactLaw {
    /// True for the piecewise-linear law the exact propagator handles.
    pub fn is_linear(&self) -> bool {
        matches!(self, ContactLaw::Linear { .. })
    }

    /// Contact force (N) for overlap `δ` (m) and rate `δ̇` (m/s); the raw law, no clamping.
    #[inline]
    pub fn force(&self, delta: f64, rate: f64) -> f64 {
        match *self {
            ContactLaw::Linear { stiffness, damping } => stiffness * delta + damping * rate,
            ContactLaw::Hertz { stiffness } => stiffness * delta.max(0.0).powf(1.5),
            ContactLaw::HuntCrossley {
                stiffness,
                exponent,
                alpha,
            } => stiffness * delta.max(0.0).powf(exponent) * (1.0 + 1.5 * alpha * rate),
            // Impulsive: no finite force law (the engine books impulses and constraint forces).
            ContactLaw::Rigid { .. } => 0.0,
        }
    }

    /// The partial derivatives `(∂f/∂δ, ∂f/∂δ̇)` of [`ContactLaw::force`] (for `δ > 0`; at
    /// `δ ≤ 0` the non-linear laws give 0).
    pub fn partials(&self, delta: f64, rate: f64) -> (f64, f64) {
        match *self {
            ContactLaw::Linear { stiffness, damping } => (stiffness, damping),
            ContactLaw::Hertz { stiffness } => (1.5 * stiffness * delta.max(0.0).sqrt(), 0.0),
            ContactLaw::HuntCrossley {
                stiffness,
                exponent,
                alpha,
            } => {
                let d = delta.max(0.0);
                let dn = d.powf(exponent);
                let dn1 = if d > 0.0 { exponent * dn / d } else { 0.0 };
                (
                    stiffness * dn1 * (1.0 + 1.5 * alpha * rate),
                    stiffness * dn * 1.5 * alpha,
                )
            }
            ContactLaw::Rigid { .. } => (0.0, 0.0),
        }
    }

    /// A function whose sign is the sign of the force while `δ > 0` (used for the
    /// force-release rule). Linear: `K δ + C δ̇`; Hunt-Crossley: `1 + 3/2 α δ̇`; Hertz: `δ`.
    #[inline]
    pub fn force_sign_function(&self, delta: f64, rate: f64) -> f64 {
        match *self {
            ContactLaw::Linear { stiffness, damping } => stiffness * delta + damping * rate,
            ContactLaw::Hertz { .. } => delta,
            ContactLaw::HuntCrossley { alpha, .. } => 1.0 + 1.5 * alpha * rate,
            ContactLaw::Rigid { .. } => delta,
        }
    }

    /// Stiffness coefficient K of the law (infinite for the rigid law).
    pub fn stiffness(&self) -> f64 {
        match *self {
            ContactLaw::Linear { stiffness, .. }
            | ContactLaw::Hertz { stiffness }
            | ContactLaw::HuntCrossley { stiffness, .. } => stiffness,
            ContactLaw::Rigid { .. } => f64::INFINITY,
        }
    }

    /// True when the law has a rate-dependent (dissipative) part.
    pub fn is_damped(&self) -> bool {
        match *self {
            ContactLaw::Linear { damping, .. } => damping != 0.0,
            ContactLaw::Hertz { .. } => false,
            ContactLaw::HuntCrossley { alpha, .. } => alpha != 0.0,
            ContactLaw::Rigid { restitution } => restitution != 1.0,
        }
    }

    /// Stored elastic energy (J) at overlap `δ > 0`: `K δ²/2` (linear) or `K δ^{n+1}/(n+1)`.
    pub fn potential_energy(&self, delta: f64) -> f64 {
        if delta <= 0.0 {
            return 0.0;
        }
        match *self {
            ContactLaw::Linear { stiffness, .. } => 0.5 * stiffness * delta * delta,
            ContactLaw::Hertz { stiffness } => stiffness * delta.powf(2.5) / 2.5,
            ContactLaw::HuntCrossley {
                stiffness,
                exponent,
                ..
            } => stiffness * delta.powf(exponent + 1.0) / (exponent + 1.0),
            // A rigid contact never overlaps: it stores nothing.
            ContactLaw::Rigid { .. } => 0.0,
        }
    }
}

/// When a damped contact lets go. See the module documentation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Release {
    /// Release when the contact force returns to zero: a contact never pulls (default).
    #[default]
    Force,
    /// Release when the overlap returns to zero (paper Eqs. 5 and 8 literally).
    Overlap,
}

/// A unilateral contact: a force law and a release rule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    pub law: ContactLaw,
    pub release: Release,
}

/// The striking slider (rigid body).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slider {
    /// m_s (kg).
    pub mass: f64,
    /// v_s (m/s), speed at first contact, positive towards the bed.
    pub velocity: f64,
}

/// Whether the damper dashpot acts both ways or only while the damper returns (Eq. 7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DashpotKind {
    /// `c_d` acts only while `ż_d − u̇_f < 0` (paper Eq. 7).
    #[default]
    OneWay,
    /// `c_d` always acts.
    TwoWay,
}

/// The impact-damper mass on its spring and dashpot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Damper {
    /// m_d (kg).
    pub mass: f64,
    /// k_d (N/m).
    pub stiffness: f64,
    /// c_d (N·s/m).
    pub damping: f64,
    pub dashpot: DashpotKind,
}

/// Which structure points the impact system uses: mode-shape values per retained mode.
#[derive(Debug, Clone, PartialEq)]
pub struct Points {
    /// O_b: where the slider strikes and the damper touches the bed.
    pub bed_contact: Vec<f64>,
    /// O_f: where the damper spring is anchored; `None` anchors it to the ground.
    pub damper_anchor: Option<Vec<f64>>,
    /// B: where the bed acceleration is measured.
    pub measurement: Vec<f64>,
}

/// A switch of the piecewise system: a contact or the one-way dashpot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Switch {
    SliderBed,
    BedDamper,
    Dashpot,
}

/// Relative motions `(δ, δ̇)` (m, m/s) of the slider-bed contact, the bed-damper contact and the
/// damper spring/dashpot at one state ([`ImpactSystem::motions`]).
pub type Motions = [(f64, f64); 3];

/// The discrete state: bit 0 slider-bed closed, bit 1 bed-damper closed, bit 2 dashpot acting;
/// bits 3 and 4 (`dopri5` only): the slider-bed / bed-damper contact is **held**, a persistent
/// contact whose gap is kept constant and whose force is the constraint's multiplier `λ`
/// ([`ImpactSystem::held_forces`]). A held contact is also closed (its bit 0 or 1 is set).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, PartialOrd, Ord)]
pub struct Mode(pub u8);

impl Mode {
    pub const SLIDER_BED: u8 = 1;
    pub const BED_DAMPER: u8 = 2;
    pub const DASHPOT: u8 = 4;
    /// The slider-bed contact is held (persistent, [`Mode`]).
    pub const HELD_SLIDER_BED: u8 = 8;
    /// The bed-damper contact is held (persistent, [`Mode`]).
    pub const HELD_BED_DAMPER: u8 = 16;
    const HELD: u8 = Self::HELD_SLIDER_BED | Self::HELD_BED_DAMPER;

    /// Is contact `s` held (persistent)? Always false for the dashpot.
    #[inline]
    pub fn held(self, s: Switch) -> bool {
        let bit = match s {
            Switch::SliderBed => Self::HELD_SLIDER_BED,
            Switch::BedDamper => Self::HELD_BED_DAMPER,
            Switch::Dashpot => 0,
        };
        self.0 & bit != 0
    }

    /// Is any contact held?
    #[inline]
    pub fn any_held(self) -> bool {
        self.0 & Self::HELD != 0
    }

    /// This mode with contact `s` held (and closed) or not held (left closed).
    #[inline]
    pub fn holding(self, s: Switch, on: bool) -> Mode {
        let bit = match s {
            Switch::SliderBed => Self::HELD_SLIDER_BED,
            Switch::BedDamper => Self::HELD_BED_DAMPER,
            Switch::Dashpot => return self,
        };
        if on {
            Mode(self.0 | bit | Self::bit(s))
        } else {
            Mode(self.0 & !bit)
        }
    }

    /// The mode without its held contacts (opened, held bits cleared): the dynamics before the
    /// constraint forces are added.
    #[inline]
    pub fn free(self) -> Mode {
        let mut m = Mode(self.0 & !Self::HELD);
        for s in [Switch::SliderBed, Switch::BedDamper] {
            if self.held(s) {
                m = m.with(s, false);
            }
        }
        m
    }
    /// Is this switch on (contact closed, dashpot acting)?
    #[inline]
    pub fn on(self, s: Switch) -> bool {
        self.0 & Self::bit(s) != 0
    }
    #[inline]
    pub fn bit(s: Switch) -> u8 {
        match s {
            Switch::SliderBed => Self::SLIDER_BED,
            Switch::BedDamper => Self::BED_DAMPER,
            Switch::Dashpot => Self::DASHPOT,
        }
    }
    /// This mode with switch `s` set to `on` (opening a held contact also ends its hold).
    #[inline]
    pub fn with(self, s: Switch, on: bool) -> Mode {
        if on {
            Mode(self.0 | Self::bit(s))
        } else {
            Mode(self.0 & !Self::bit(s)).holding(s, false)
        }
    }
}

/// One of the scalar functions whose sign decides a switch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Indicator {
    /// Overlap `δ` of a contact.
    Overlap(Switch),
    /// The force-sign function of a contact (force-release rule only).
    Force(Switch),
    /// Relative velocity `ż_d − u̇_f` of the damper dashpot (one-way dashpot only).
    DashpotVelocity,
}

/// The complete impact system: a modal structure, the slider, an optional damper and contacts.
#[derive(Debug, Clone)]
pub struct ImpactSystem {
    /// The structure (already including an added mass, if that is the case studied).
    pub structure: ModalModel,
    pub points: Points,
    pub slider: Slider,
    pub damper: Option<Damper>,
    pub slider_bed: Contact,
    /// Present exactly when `damper` is.
    pub bed_damper: Option<Contact>,
    /// Added mass fixed to the bed (kg), for reports; already in `structure`.
    pub added_mass: f64,
    floor: FloorForce,
    has_floor: bool,
    /// `a` vectors of the switches (slider-bed, bed-damper, damper spring), built once.
    rel: [Vec<f64>; 3],
    /// The non-zero entries `(i, a_i)` of each `rel` vector (first-order matrices are built
    /// from them).
    rel_nz: [SparseVec; 3],
    /// True when the modal damping matrix is diagonal (modal damping ratios only).
    damping_diagonal: bool,
    /// F (N): constant force on the slider, positive towards the bed
    /// ([`ImpactSystem::with_slider_force`]); 0 by default.
    slider_force: f64,
}

/// What (if anything) is attached to the bed to reduce the blow's effect.
#[derive(Debug, Clone, PartialEq)]
pub enum Absorber {
    /// Nothing: the bare machine.
    None,
    /// A momentum-exchange impact damper with its bed-damper contact.
    Damper(Damper, Contact),
    /// A rigid mass `mass_kg` (kg) fixed to the named structure point `point` (O_b, the
    /// floating base O_f, ...), added by [`ModalModel::with_point_mass`].
    AddedMass { mass_kg: f64, point: String },
}

impl ImpactSystem {
    /// Assembles the system. `bed_contact`, `damper_anchor` (`None` = ground) and `measurement`
    /// name points of `structure`.
    pub fn new(
        structure: &ModalModel,
        bed_contact: &str,
        damper_anchor: Option<&str>,
        measurement: &str,
        slider: Slider,
        slider_bed: Contact,
        absorber: Absorber,
    ) -> Result<Self> {
        structure.validate()?;
        check_positive("slider.mass", slider.mass, "kg")?;
        if !(slider.velocity.is_finite() && slider.velocity > 0.0) {
            return Err(Error::invalid(
                "slider.velocity",
                format!("must be > 0 m/s towards the bed (got {})", slider.velocity),
            ));
        }
        refuse_rigid("contact.slider_bed", &slider_bed)?;
        check_contact("contact.slider_bed", &slider_bed)?;
        let (structure, damper, bed_damper, added_mass) = match absorber {
            Absorber::None => (structure.clone(), None, None, 0.0),
            Absorber::Damper(d, c) => {
                check_positive("damper.mass", d.mass, "kg")?;
                check_non_negative("damper.stiffness", d.stiffness, "N/m")?;
                check_non_negative("damper.damping", d.damping, "N·s/m")?;
                refuse_rigid("contact.bed_damper", &c)?;
                check_contact("contact.bed_damper", &c)?;
                (structure.clone(), Some(d), Some(c), 0.0)
            }
            Absorber::AddedMass { mass_kg, point } => {
                check_positive("added_mass.mass", mass_kg, "kg")?;
                structure.point(&point).map_err(|e| match e {
                    Error::InvalidValue { message, .. } => {
                        Error::invalid("added_mass.point", message)
                    }
                    other => other,
                })?;
                (
                    structure.with_point_mass(&point, mass_kg)?,
                    None,
                    None,
                    mass_kg,
                )
            }
        };
        let points = Points {
            bed_contact: structure.point(bed_contact)?.to_vec(),
            damper_anchor: match damper_anchor {
                Some(p) => Some(structure.point(p)?.to_vec()),
                None => None,
            },
            measurement: structure.point(measurement)?.to_vec(),
        };
        let n = structure.len();
        let (floor, has_floor) = match &structure.floor_force {
            Some(f) => (f.clone(), true),
            None => (
                FloorForce {
                    stiffness: vec![0.0; n],
                    damping: vec![0.0; n],
                },
                false,
            ),
        };
        let mut sys = Self {
            structure,
            points,
            slider,
            damper,
            slider_bed,
            bed_damper,
            added_mass,
            floor,
            has_floor,
            rel: Default::default(),
            rel_nz: Default::default(),
            damping_diagonal: false,
            slider_force: 0.0,
        };
        let nm = sys.structure.len();
        let d = &sys.structure.damping;
        sys.damping_diagonal = (0..nm).all(|i| (0..nm).all(|j| i == j || d[i * nm + j] == 0.0));
        sys.rel = [
            sys.build_relative_vector(Switch::SliderBed),
            sys.build_relative_vector(Switch::BedDamper),
            sys.build_relative_vector(Switch::Dashpot),
        ];
        sys.rel_nz = [0, 1, 2].map(|k| SparseVec::new(&sys.rel[k]));
        Ok(sys)
    }

    /// This system with a constant force `F` (N) on the slider from t = 0, positive towards the
    /// bed (its weight on a vertical hammer, a drive or air pressure): the slider's equation
    /// becomes `m_s z̈_s = F − f_bs`, so the dynamics of every mode are affine,
    /// `Ẋ = A_σ X + b` with `b = (F/m_s) e_{ż_s}`. `F` must be finite and ≥ 0, and with
    /// `F > 0` every structural mode must have a stiffness (ω > 0): a structure free to move as
    /// a rigid body would be pushed away for ever (`slider.force`, `structure` named in the
    /// error).
    pub fn with_slider_force(mut self, force_n: f64) -> Result<Self> {
        check_non_negative("slider.force", force_n, "N (towards the bed)")?;
        if force_n > 0.0 {
            if let Some(i) = self
                .structure
                .omega_rad_per_s
                .iter()
                .position(|w| w.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater))
            {
                return Err(Error::invalid(
                    "slider.force",
                    format!(
                        "a constant force ({force_n:e} N) needs a structure held by springs: \
                         retained mode {} is a rigid-body mode (0 Hz), which the force would \
                         push away for ever; support the structure or set slider.force = 0",
                        i + 1
                    ),
                ));
            }
        }
        self.slider_force = force_n;
        Ok(self)
    }

    /// F (N): the constant force on the slider, positive towards the bed (0 unless set with
    /// [`Self::with_slider_force`]).
    #[inline]
    pub fn slider_force(&self) -> f64 {
        self.slider_force
    }

    /// The constant part `b` of the affine dynamics `Ẋ = A_σ X + b` (length `2·dofs`, the
    /// same in every mode): `F/m_s` in the slider's velocity row, zero elsewhere; `None` when
    /// `F = 0` (the dynamics are linear, `Ẋ = A_σ X`).
    pub fn forcing(&self) -> Option<Vec<f64>> {
        if self.slider_force == 0.0 {
            return None;
        }
        let nd = self.dofs();
        let mut b = vec![0.0; 2 * nd];
        b[nd + self.slider_index()] = self.slider_force / self.slider.mass;
        Some(b)
    }

    /// The work done by the constant slider force between the states `x0` and `x`:
    /// `W_F = ∫ F ż_s dt = F (z_s − z_s0)` (J), energy put into the system (negative while the
    /// slider is above its starting point).
    #[inline]
    pub fn force_work(&self, x0: &[f64], x: &[f64]) -> f64 {
        if self.slider_force == 0.0 {
            return 0.0;
        }
        let i = self.slider_index();
        self.slider_force * (x[i] - x0[i])
    }

    /// Number of structural modes n.
    #[inline]
    pub fn n_modes(&self) -> usize {
        self.structure.len()
    }
    /// Number of second-order coordinates: n + 1 (+1 with a damper).
    #[inline]
    pub fn dofs(&self) -> usize {
        self.n_modes() + 1 + usize::from(self.damper.is_some())
    }
    /// Index of z_s.
    #[inline]
    pub fn slider_index(&self) -> usize {
        self.n_modes()
    }
    /// Index of z_d (only meaningful with a damper).
    #[inline]
    pub fn damper_index(&self) -> usize {
        self.n_modes() + 1
    }
    /// True when the structure has a force path to the floor (or the damper is anchored to it).
    pub fn has_floor_force(&self) -> bool {
        self.has_floor || (self.damper.is_some() && self.points.damper_anchor.is_none())
    }

    /// The switches present in this system, in a fixed order.
    pub fn switches(&self) -> Vec<Switch> {
        let mut s = vec![Switch::SliderBed];
        if let Some(d) = &self.damper {
            s.push(Switch::BedDamper);
            if d.dashpot == DashpotKind::OneWay && d.damping > 0.0 {
                s.push(Switch::Dashpot);
            }
        }
        s
    }

    /// The indicators whose signs decide the switches.
    pub fn indicators(&self) -> Vec<Indicator> {
        let mut out = Vec::new();
        for s in self.switches() {
            match s {
                Switch::Dashpot => out.push(Indicator::DashpotVelocity),
                c => {
                    out.push(Indicator::Overlap(c));
                    let contact = self.contact(c);
                    if contact.release == Release::Force && contact.law.is_damped() {
                        out.push(Indicator::Force(c));
                    }
                }
            }
        }
        out
    }

    /// The contact behind a contact switch.
    pub fn contact(&self, s: Switch) -> &Contact {
        match s {
            Switch::BedDamper => self.bed_damper.as_ref().unwrap_or(&self.slider_bed),
            _ => &self.slider_bed,
        }
    }

    /// Masses of the second-order coordinates: `[1, …, 1, m_s, m_d]`.
    pub fn mass_diag(&self) -> Vec<f64> {
        let mut m = vec![1.0; self.dofs()];
        m[self.slider_index()] = self.slider.mass;
        if let Some(d) = &self.damper {
            m[self.damper_index()] = d.mass;
        }
        m
    }

    /// The vector `a` with `δ = aᵀx` for a switch (overlap for contacts, `z_d − u_f` for the
    /// damper spring and dashpot). Without a damper the damper entries are all zero.
    #[inline]
    pub fn relative_vector(&self, s: Switch) -> &[f64] {
        &self.rel[rel_index(s)]
    }

    fn build_relative_vector(&self, s: Switch) -> Vec<f64> {
        if s != Switch::SliderBed && self.damper.is_none() {
            return vec![0.0; self.dofs()];
        }
        let n = self.n_modes();
        let mut a = vec![0.0; self.dofs()];
        match s {
            Switch::SliderBed => {
                for i in 0..n {
                    a[i] = -self.points.bed_contact[i];
                }
                a[self.slider_index()] = 1.0;
            }
            Switch::BedDamper => {
                a[..n].copy_from_slice(&self.points.bed_contact);
                a[self.damper_index()] = -1.0;
            }
            Switch::Dashpot => {
                if let Some(f) = &self.points.damper_anchor {
                    for i in 0..n {
                        a[i] = -f[i];
                    }
                }
                a[self.damper_index()] = 1.0;
            }
        }
        a
    }

    /// Second-order stiffness and damping matrices `K_σ`, `C_σ` (`dofs × dofs`) of a mode,
    /// for linear contact laws (a non-linear law contributes its linear part, none for Hertz).
    pub fn matrices(&self, mode: Mode) -> (Mat<f64>, Mat<f64>) {
        let nd = self.dofs();
        let mut k = Mat::<f64>::zeros(nd, nd);
        let mut c = Mat::<f64>::zeros(nd, nd);
        self.for_each_entry(mode, |i, j, dk, dc| {
            k[(i, j)] += dk;
            c[(i, j)] += dc;
        });
        (k, c)
    }

    /// Calls `f(i, j, K_ij, C_ij)` with the contributions to `K_σ` and `C_σ` (summed over
    /// repeated `(i, j)`): the structure's modal stiffness and damping, the closed linear
    /// contacts, the damper spring and its dashpot when on.
    fn for_each_entry(&self, mode: Mode, mut f: impl FnMut(usize, usize, f64, f64)) {
        let n = self.n_modes();
        let nd = self.dofs();
        for i in 0..n {
            for j in 0..n {
                let kk = if i == j {
                    self.structure.omega_rad_per_s[i].powi(2)
                } else {
                    0.0
                };
                let cc = self.structure.damping[i * n + j];
                if kk != 0.0 || cc != 0.0 {
                    f(i, j, kk, cc);
                }
            }
        }
        let mut add = |a: &[f64], kk: f64, cc: f64| {
            for i in 0..nd {
                if a[i] == 0.0 {
                    continue;
                }
                for j in 0..nd {
                    if a[j] != 0.0 {
                        f(i, j, kk * a[i] * a[j], cc * a[i] * a[j]);
                    }
                }
            }
        };
        for s in [Switch::SliderBed, Switch::BedDamper] {
            if s == Switch::BedDamper && self.damper.is_none() {
                continue;
            }
            if mode.on(s) {
                if let ContactLaw::Linear { stiffness, damping } = self.contact(s).law {
                    add(self.relative_vector(s), stiffness, damping);
                }
            }
        }
        if let Some(d) = &self.damper {
            let dashpot_on = match d.dashpot {
                DashpotKind::TwoWay => true,
                DashpotKind::OneWay => mode.on(Switch::Dashpot),
            };
            add(
                self.relative_vector(Switch::Dashpot),
                d.stiffness,
                if dashpot_on { d.damping } else { 0.0 },
            );
        }
    }

    /// First-order matrix `A_σ = [[0, I], [−M⁻¹K_σ, −M⁻¹C_σ]]` for the state `X = [x; ẋ]`.
    pub fn first_order(&self, mode: Mode) -> Mat<f64> {
        let n = 2 * self.dofs();
        let mut buf = vec![0.0; n * n];
        self.first_order_into(mode, &mut buf);
        Mat::from_fn(n, n, |i, j| buf[j * n + i])
    }

    /// [`Self::first_order`] written column-major into `out` (length `(2·dofs)²`), without
    /// allocating: the runs build the matrices of the modes they meet with it.
    ///
    /// # Panics
    /// When `out` has the wrong length.
    pub fn first_order_into(&self, mode: Mode, out: &mut [f64]) {
        let nd = self.dofs();
        let n = 2 * nd;
        assert_eq!(out.len(), n * n, "first-order matrix buffer");
        out.fill(0.0);
        for i in 0..nd {
            out[(nd + i) * n + i] = 1.0;
        }
        // K_σ and C_σ summed into the lower rows (column j of K in column j, of C in column
        // nd + j), in the order of `for_each_entry` but over the non-zeros of the relative
        // vectors only, then scaled by −1/m_i.
        let nm = self.n_modes();
        for i in 0..nm {
            let kk = self.structure.omega_rad_per_s[i].powi(2);
            if kk != 0.0 {
                out[i * n + nd + i] += kk;
            }
            for j in 0..nm {
                let cc = self.structure.damping[i * nm + j];
                if cc != 0.0 {
                    out[(nd + j) * n + nd + i] += cc;
                }
            }
        }
        let mut add = |s: Switch, kk: f64, cc: f64| {
            let (idx, val) = self.rel_nz[rel_index(s)].parts();
            for (&i, &ai) in idx.iter().zip(val) {
                for (&j, &aj) in idx.iter().zip(val) {
                    out[j * n + nd + i] += kk * ai * aj;
                    if cc != 0.0 {
                        out[(nd + j) * n + nd + i] += cc * ai * aj;
                    }
                }
            }
        };
        for s in [Switch::SliderBed, Switch::BedDamper] {
            if s == Switch::BedDamper && self.damper.is_none() {
                continue;
            }
            if mode.on(s) {
                if let ContactLaw::Linear { stiffness, damping } = self.contact(s).law {
                    add(s, stiffness, damping);
                }
            }
        }
        if let Some(d) = &self.damper {
            let dashpot_on = match d.dashpot {
                DashpotKind::TwoWay => true,
                DashpotKind::OneWay => mode.on(Switch::Dashpot),
            };
            add(
                Switch::Dashpot,
                d.stiffness,
                if dashpot_on { d.damping } else { 0.0 },
            );
        }
        for col in out.chunks_exact_mut(n) {
            for (i, d) in col[nd..].iter_mut().enumerate() {
                if *d != 0.0 {
                    *d = -*d / self.mass(i);
                }
            }
        }
    }

    /// Mass (kg) of coordinate `i`: 1 for a modal coordinate (mass-normalised modes), `m_s`
    /// for the slider, `m_d` for the damper ([`Self::mass_diag`] entry by entry).
    #[inline]
    pub fn mass(&self, i: usize) -> f64 {
        if i == self.slider_index() {
            self.slider.mass
        } else if i == self.damper_index() {
            self.damper.as_ref().map_or(1.0, |d| d.mass)
        } else {
            1.0
        }
    }

    /// The initial state: everything at rest at 0, the slider moving at `v_s`.
    pub fn initial_state(&self) -> Vec<f64> {
        let nd = self.dofs();
        let mut x = vec![0.0; 2 * nd];
        x[nd + self.slider_index()] = self.slider.velocity;
        x
    }

    /// Row vector `ℓ` with `value = ℓᵀX` for an indicator (linear laws; for Hunt-Crossley's
    /// force indicator this is the rate part only and [`Self::indicator_value`] adds the constant).
    pub fn indicator_vector(&self, ind: Indicator) -> Vec<f64> {
        let nd = self.dofs();
        let mut l = vec![0.0; 2 * nd];
        match ind {
            Indicator::Overlap(s) => {
                l[..nd].copy_from_slice(self.relative_vector(s));
            }
            Indicator::DashpotVelocity => {
                l[nd..].copy_from_slice(self.relative_vector(Switch::Dashpot));
            }
            Indicator::Force(s) => {
                let a = self.relative_vector(s);
                match self.contact(s).law {
                    ContactLaw::Linear { stiffness, damping } => {
                        for i in 0..nd {
                            l[i] = stiffness * a[i];
                            l[nd + i] = damping * a[i];
                        }
                    }
                    // (The paper's system refuses the rigid law: `refuse_rigid`.)
                    ContactLaw::Hertz { .. } | ContactLaw::Rigid { .. } => {
                        l[..nd].copy_from_slice(a)
                    }
                    ContactLaw::HuntCrossley { alpha, .. } => {
                        for i in 0..nd {
                            l[nd + i] = 1.5 * alpha * a[i];
                        }
                    }
                }
            }
        }
        l
    }

    /// Value of an indicator at state `X`.
    pub fn indicator_value(&self, ind: Indicator, x: &[f64]) -> f64 {
        let nd = self.dofs();
        let (s, is_force) = match ind {
            Indicator::Overlap(s) => (s, false),
            Indicator::Force(s) => (s, true),
            Indicator::DashpotVelocity => {
                return dot(self.relative_vector(Switch::Dashpot), &x[nd..])
            }
        };
        let a = self.relative_vector(s);
        let d = dot(a, &x[..nd]);
        if !is_force {
            return d;
        }
        let r = dot(a, &x[nd..]);
        self.contact(s).law.force_sign_function(d, r)
    }

    /// The switch state implied by indicator signs (`+1`, `−1`): contacts closed while the
    /// overlap (and, with force release, the force) is positive; dashpot on while returning.
    pub fn switch_on(&self, s: Switch, sign_of: &dyn Fn(Indicator) -> f64) -> bool {
        match s {
            Switch::Dashpot => sign_of(Indicator::DashpotVelocity) < 0.0,
            c => {
                let contact = self.contact(c);
                let overlap = sign_of(Indicator::Overlap(c)) > 0.0;
                if contact.release == Release::Force && contact.law.is_damped() {
                    overlap && sign_of(Indicator::Force(c)) > 0.0
                } else {
                    overlap
                }
            }
        }
    }

    /// Generalised contact and damper forces at state `X` in mode `mode`, for any law:
    /// returns `(f_bs, f_bd, f_fd)` (N). A held contact's force is its multiplier `λ`
    /// ([`Self::held_forces`]).
    pub fn element_forces(&self, mode: Mode, x: &[f64]) -> (f64, f64, f64) {
        let (fbs, fbd, ffd) = self.element_forces_from(mode, &self.motions(x));
        if !mode.any_held() {
            return (fbs, fbd, ffd);
        }
        let lam = self.held_forces(mode, x);
        (
            if mode.held(Switch::SliderBed) {
                lam[0]
            } else {
                fbs
            },
            if mode.held(Switch::BedDamper) {
                lam[1]
            } else {
                fbd
            },
            ffd,
        )
    }

    /// The forces (N) of the held contacts of `mode` at the state `X = [x; ẋ]` (slider-bed,
    /// bed-damper; 0 for a contact not held): the multipliers `λ` that keep each held gap
    /// constant, `a_cᵀẍ = 0`. With `ẍ_f` the accelerations of [`Mode::free`] (the held
    /// contacts open, every other force and the slider force acting),
    /// `ẍ = ẍ_f − M⁻¹ A λ` and `G λ = Aᵀ ẍ_f`, `G = Aᵀ M⁻¹ A` (1×1 or 2×2; `A` the held
    /// contacts' relative vectors, `M` [`Self::mass_diag`]).
    pub fn held_forces(&self, mode: Mode, x: &[f64]) -> [f64; 2] {
        let mut acc = vec![0.0; self.dofs()];
        self.accelerations(mode.free(), x, &mut acc);
        self.project_held(mode, &mut acc, &self.mass_diag())
    }

    /// Removes from the accelerations `acc` (length `dofs`) their component that changes a
    /// held contact's relative velocity, `acc −= M⁻¹ A G⁻¹ Aᵀ acc` (see
    /// [`Self::held_forces`]), and returns the multipliers `G⁻¹ Aᵀ acc` (slider-bed,
    /// bed-damper; 0 for a contact not held). `masses` is [`Self::mass_diag`].
    pub fn project_held(&self, mode: Mode, acc: &mut [f64], masses: &[f64]) -> [f64; 2] {
        let mut lam = [0.0; 2];
        let held: Vec<(usize, &[f64])> = [Switch::SliderBed, Switch::BedDamper]
            .into_iter()
            .enumerate()
            .filter(|&(_, s)| mode.held(s) && (s == Switch::SliderBed || self.damper.is_some()))
            .map(|(i, s)| (i, self.relative_vector(s)))
            .collect();
        let g = |a: &[f64], b: &[f64]| -> f64 {
            a.iter()
                .zip(b)
                .zip(masses)
                .map(|((ai, bi), m)| ai * bi / m)
                .sum()
        };
        match held[..] {
            [] => return lam,
            [(i, a)] => lam[i] = dot(a, acc) / g(a, a),
            [(i, a), (j, b)] => {
                let (g11, g12, g22) = (g(a, a), g(a, b), g(b, b));
                let (b1, b2) = (dot(a, acc), dot(b, acc));
                let det = g11 * g22 - g12 * g12;
                lam[i] = (g22 * b1 - g12 * b2) / det;
                lam[j] = (g11 * b2 - g12 * b1) / det;
            }
            _ => unreachable!("two contacts at most"),
        }
        for (i, a) in &held {
            for ((o, ak), m) in acc.iter_mut().zip(a.iter()).zip(masses) {
                *o -= ak * lam[*i] / m;
            }
        }
        lam
    }

    /// [`Self::element_forces`] from the relative motions ([`Self::motions`]) of the state.
    pub fn element_forces_from(&self, mode: Mode, m: &Motions) -> (f64, f64, f64) {
        let f = |s: Switch, (del, rate): (f64, f64)| {
            if !mode.on(s) {
                return 0.0;
            }
            self.contact(s).law.force(del, rate)
        };
        let fbs = f(Switch::SliderBed, m[0]);
        let (fbd, ffd) = match &self.damper {
            Some(d) => {
                let (del, rate) = m[2];
                let c_on = match d.dashpot {
                    DashpotKind::TwoWay => true,
                    DashpotKind::OneWay => mode.on(Switch::Dashpot),
                };
                (
                    f(Switch::BedDamper, m[1]),
                    d.stiffness * del + if c_on { d.damping * rate } else { 0.0 },
                )
            }
            None => (0.0, 0.0),
        };
        (fbs, fbd, ffd)
    }

    /// The relative motions `(δ, δ̇)` of the slider-bed contact, the bed-damper contact and the
    /// damper spring (in that order, [`Self::relative_motion`]) at the state `X = [x; ẋ]`; the
    /// damper's are zero without a damper.
    pub fn motions(&self, state: &[f64]) -> Motions {
        [Switch::SliderBed, Switch::BedDamper, Switch::Dashpot]
            .map(|s| self.relative_motion(s, state))
    }

    /// `(δ, δ̇) = (aᵀx, aᵀẋ)` of a switch's relative vector `a` ([`Self::relative_vector`]) at the
    /// state `X = [x; ẋ]`, over `a`'s non-zero entries.
    #[inline]
    pub fn relative_motion(&self, s: Switch, state: &[f64]) -> (f64, f64) {
        let nd = self.dofs();
        let k = rel_index(s);
        let (x, v) = (&state[..nd], &state[nd..2 * nd]);
        let nz = &self.rel_nz[k];
        if 3 * nz.parts().0.len() > nd {
            // Dense (a point of the structure moves in every mode): plain dots.
            let a = &self.rel[k];
            return (dot(a, x), dot(a, v));
        }
        nz.dots(x, v)
    }

    /// Force to the floor (N) at state `X`: the structure's ground reactions plus the damper
    /// spring/dashpot force when the damper is anchored to the ground.
    pub fn floor_force(&self, mode: Mode, x: &[f64]) -> f64 {
        self.floor_force_with(x, self.element_forces(mode, x).2)
    }

    /// [`Self::floor_force`] given the damper force `f_fd` (from [`Self::element_forces`]).
    pub fn floor_force_with(&self, x: &[f64], ffd: f64) -> f64 {
        let n = self.n_modes();
        let nd = self.dofs();
        let mut f = dot(&self.floor.stiffness, &x[..n]) + dot(&self.floor.damping, &x[nd..nd + n]);
        if self.damper.is_some() && self.points.damper_anchor.is_none() {
            f += ffd;
        }
        f
    }
}

impl ImpactSystem {
    /// Generalised accelerations `ẍ` at state `X` in `mode` (any contact law), written to `out`
    /// (length `dofs`): `q̈ = −Ω²q − D q̇ + ψ_b f_bs − ψ_b f_bd + ψ_f f_fd`,
    /// `z̈_s = (F − f_bs)/m_s` (F the constant slider force, [`Self::slider_force`]),
    /// `z̈_d = (f_bd − f_fd)/m_d`.
    pub fn accelerations(&self, mode: Mode, x: &[f64], out: &mut [f64]) {
        self.accelerations_with(x, self.element_forces(mode, x), out);
    }

    /// [`Self::accelerations`] given the element forces `(f_bs, f_bd, f_fd)` at `x` (from
    /// [`Self::element_forces`]).
    pub fn accelerations_with(&self, x: &[f64], forces: (f64, f64, f64), out: &mut [f64]) {
        let n = self.n_modes();
        let nd = self.dofs();
        let (fbs, fbd, ffd) = forces;
        let d = &self.structure.damping;
        let w = &self.structure.omega_rad_per_s;
        let (q, qd) = (&x[..n], &x[nd..nd + n]);
        let psi_b = &self.points.bed_contact;
        let contact = fbs - fbd;
        if self.damping_diagonal {
            let rows = out[..n].iter_mut().zip(q).zip(qd).zip(w).zip(psi_b);
            for (i, ((((o, qi), vi), wi), pi)) in rows.enumerate() {
                *o = -(wi * wi) * qi - d[i * n + i] * vi + pi * contact;
            }
        } else {
            for i in 0..n {
                let c = dot(&d[i * n..(i + 1) * n], qd);
                out[i] = -(w[i] * w[i]) * q[i] - c + psi_b[i] * contact;
            }
        }
        if let Some(f) = &self.points.damper_anchor {
            for (o, fi) in out[..n].iter_mut().zip(f) {
                *o += fi * ffd;
            }
        }
        out[self.slider_index()] = if self.slider_force != 0.0 {
            (self.slider_force - fbs) / self.slider.mass
        } else {
            -fbs / self.slider.mass
        };
        if let Some(dm) = &self.damper {
            out[self.damper_index()] = (fbd - ffd) / dm.mass;
        }
    }
}

/// `Σ a_i b_i` (over the shorter length); from 8 entries on in four interleaved partial sums (so
/// that the loop vectorises; the grouping differs from a left-to-right sum by round-off only).
#[inline]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    let m = a.len().min(b.len());
    let (a, b) = (&a[..m], &b[..m]);
    if m < 8 {
        // Short (a lumped machine's coordinates): one sum, no set-up.
        return a.iter().zip(b).map(|(x, y)| x * y).sum();
    }
    let mut acc = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for q in 0..4 {
            acc[q] += x[q] * y[q];
        }
    }
    let mut tail = 0.0;
    for (x, y) in ra.iter().zip(rb) {
        tail += x * y;
    }
    (acc[0] + acc[2]) + (acc[1] + acc[3]) + tail
}

/// A vector by its non-zero entries (a contact's relative vector, an indicator: a few coordinates
/// of many), built once per system or per run: the sparse dots and updates of the system's
/// matrices and of the integrators.
#[derive(Debug, Clone, Default)]
pub(crate) struct SparseVec {
    idx: Vec<usize>,
    val: Vec<f64>,
}

impl SparseVec {
    /// The non-zeros of `l` (allocated to size).
    pub(crate) fn new(l: &[f64]) -> Self {
        let m = l.iter().filter(|v| **v != 0.0).count();
        let (mut idx, mut val) = (Vec::with_capacity(m), Vec::with_capacity(m));
        for (i, &v) in l.iter().enumerate() {
            if v != 0.0 {
                idx.push(i);
                val.push(v);
            }
        }
        Self { idx, val }
    }

    /// The indices and values of the non-zeros.
    #[inline]
    pub(crate) fn parts(&self) -> (&[usize], &[f64]) {
        (&self.idx, &self.val)
    }

    /// `aᵀx` (the same sum as over all entries: the zeros add nothing).
    #[inline]
    pub(crate) fn dot(&self, x: &[f64]) -> f64 {
        self.idx
            .iter()
            .zip(&self.val)
            .map(|(&i, &a)| a * x[i])
            .sum()
    }

    /// `(aᵀx, aᵀv)`.
    #[inline]
    pub(crate) fn dots(&self, x: &[f64], v: &[f64]) -> (f64, f64) {
        let (mut d, mut r) = (0.0, 0.0);
        for (&i, &a) in self.idx.iter().zip(&self.val) {
            d += a * x[i];
            r += a * v[i];
        }
        (d, r)
    }

    /// `(aᵀy, Σ|a_i y_i|)`.
    #[inline]
    pub(crate) fn dot_abs(&self, y: &[f64]) -> (f64, f64) {
        let (mut val, mut scale) = (0.0, 0.0);
        for (&i, &a) in self.idx.iter().zip(&self.val) {
            let t = a * y[i];
            val += t;
            scale += t.abs();
        }
        (val, scale)
    }

    /// `acc −= a f`.
    #[inline]
    pub(crate) fn sub_scaled(&self, f: f64, acc: &mut [f64]) {
        for (&i, &a) in self.idx.iter().zip(&self.val) {
            acc[i] -= a * f;
        }
    }
}

/// Index of a switch's relative vector in `ImpactSystem::rel` (and `rel_nz`).
#[inline]
fn rel_index(s: Switch) -> usize {
    match s {
        Switch::SliderBed => 0,
        Switch::BedDamper => 1,
        Switch::Dashpot => 2,
    }
}

fn check_positive(field: &str, v: f64, unit: &str) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(
            field,
            format!("must be a finite number > 0 {unit} (got {v})"),
        ))
    }
}

fn check_non_negative(field: &str, v: f64, unit: &str) -> Result<()> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(
            field,
            format!("must be a finite number >= 0 {unit} (got {v})"),
        ))
    }
}

fn check_contact(field: &str, c: &Contact) -> Result<()> {
    match c.law {
        ContactLaw::Linear { stiffness, damping } => {
            check_positive(&format!("{field}.stiffness"), stiffness, "N/m")?;
            check_non_negative(&format!("{field}.damping"), damping, "N·s/m")
        }
        ContactLaw::Hertz { stiffness } => {
            check_positive(&format!("{field}.stiffness"), stiffness, "N/m^1.5")
        }
        ContactLaw::HuntCrossley {
            stiffness,
            exponent,
            alpha,
        } => {
            check_positive(&format!("{field}.stiffness"), stiffness, "N/m^n")?;
            check_positive(&format!("{field}.exponent"), exponent, "")?;
            check_non_negative(&format!("{field}.alpha"), alpha, "s/m")
        }
        ContactLaw::Rigid { restitution } => {
            if (0.0..=1.0).contains(&restitution) {
                Ok(())
            } else {
                Err(Error::invalid(
                    format!("{field}.restitution"),
                    format!("the rigid law's coefficient of restitution must be in [0, 1] (0: plastic, 1: elastic; got {})", crate::num(restitution)),
                ))
            }
        }
    }
}

/// The paper's engine takes compliant laws only: a rigid law there is refused, saying how to
/// write the machine as a general one.
fn refuse_rigid(field: &str, c: &Contact) -> Result<()> {
    if let ContactLaw::Rigid { .. } = c.law {
        return Err(Error::invalid(format!("{field}.law"), RIGID_PAPER_FORM));
    }
    Ok(())
}

/// Why the paper's machine refuses the rigid law, and what to write instead.
pub const RIGID_PAPER_FORM: &str = "the rigid law (instantaneous impacts) runs on general machines only: the paper's engine integrates compliant contacts. Write the same machine as a general one: an [[impactor]] for the slider (mass, velocity, force), a [[damper]] per damper (point, anchor), and a [[contact]] per contact with between = [A, B] (\"slider\" → the struck point for slider_bed), law = \"rigid\" and restitution = e (docs/reference/model-file.md, \"General machines\"; examples/hammer-rigid.toml)";

#[cfg(test)]
mod tests {
    use super::ContactLaw;

    /// The analytic partial derivatives against central differences of the force: truncation
    /// error ~1e-12 relative at a relative step of 1e-6, plus the differences' round-off,
    /// `ε |f| / step`.
    #[test]
    fn partials_match_central_differences() {
        let laws = [
            ContactLaw::Linear {
                stiffness: 1.2e8,
                damping: 350.0,
            },
            ContactLaw::Hertz { stiffness: 3.1e10 },
            ContactLaw::HuntCrossley {
                stiffness: 3.1e10,
                exponent: 1.5,
                alpha: 0.4,
            },
        ];
        for law in laws {
            for (d, r) in [(1e-6, 0.3), (2.5e-5, -1.1), (4e-4, 0.0)] {
                let (fd, fr) = law.partials(d, r);
                let (ed, er) = (1e-6 * d, 1e-6 * r.abs().max(1e-3));
                let nd = (law.force(d + ed, r) - law.force(d - ed, r)) / (2.0 * ed);
                let nr = (law.force(d, r + er) - law.force(d, r - er)) / (2.0 * er);
                let f = law.force(d, r).abs();
                let noise = |step: f64| 4.0 * f64::EPSILON * f / step;
                assert!(
                    (fd - nd).abs() <= 1e-9 * nd.abs() + noise(ed),
                    "{law:?} ∂δ at {d}: {fd} vs {nd}"
                );
                assert!(
                    (fr - nr).abs() <= 1e-9 * nr.abs() + noise(er),
                    "{law:?} ∂δ̇ at {d}, {r}: {fr} vs {nr}"
                );
            }
        }
    }
}
