//! Energy accounting of a blow (paper Eqs. 10-24) and the summary of a run.
//!
//! At the end of the collision (see [`crate::integrate`]):
//!
//! ```text
//! E_s− = ½ m_s v_s²                         (Eq. 11)
//! E_s+ = ½ m_s ż_s+²                        (Eq. 12)
//! E_d+ = ½ m_d ż_d+² + ½ k_d (z_d − u_f)+²   (Eq. 13)
//! E_p+ = E_s− − E_s+ − E_d+                 (Eq. 10)   energy left in the machine
//! ```
//!
//! The histories are Eqs. (16)-(22): `KE_ms = ½ m_s ż_s²`, `PE_Ks` (stored in the closed
//! slider contact), `KE_p = ½ q̇ᵀq̇`, `PE_p = ½ qᵀΩ²q` (modal mass and stiffness),
//! `KE_md = ½ m_d ż_d²`, `PE_kd = ½ k_d (z_d − u_f)²`, `PE_Kd` (closed damper contact), and
//! the dissipated energy of Eq. (23), `E_s− − Σ(stored)`. Eq. (17)/(22)'s sign factors are read
//! as "while the contact is closed" (the printed `(1 − sgn)/2` would count open contacts).
//!
//! Independently, the integrators integrate the dissipated power `ẋᵀC_σẋ` (exactly for
//! `exact`); the **energy-balance residual** `|E_s− − Σ stored − ∫P dt| / E_s−` checks both.
//!
//! # A constant slider force F
//! With `slider.force = F > 0` ([`ImpactSystem::slider_force`]) the force puts in the work
//!
//! ```text
//! W_F(t) = ∫₀ᵗ F ż_s dt = F (z_s(t) − z_s(0))
//! ```
//!
//! (negative while the slider is above its starting point). The balance is
//! `E_s− + W_F = Σ stored + ∫P dt`, its residual `|E_s− + W_F − Σ stored − ∫P dt| /
//! (E_s− + |W_F|)`. The energy ratio keeps the paper's meaning, the share of the energy put in
//! during the collision that the machine keeps: with `W_F+` the work up to the end of the
//! collision,
//!
//! ```text
//! E_p+ = E_s− + W_F+ − E_s+ − E_d+,   ratio = E_p+ / (E_s− + W_F+)
//! ```
//!
//! which is Eq. (10)/(11) for F = 0. The summary reports `W_F+`, the denominator
//! (`energy_input_j`) and `W_F` at the end of the run beside it. (Stored energies are measured
//! from the unloaded state x = 0, not from the static state under F.)

use serde::Serialize;

use crate::impact::{
    Channel, ChannelMap, ContactLaw, ImpactSystem, Mode, Motions, Switch, CHANNELS,
};
use crate::integrate::peaks::Peaks;
use crate::integrate::{self, Method, Observer, Options, Solution};
use crate::{Error, Result};

/// Stored energies at one instant (J).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct EnergyTerms {
    pub ke_slider: f64,
    pub pe_slider_contact: f64,
    pub ke_machine: f64,
    pub pe_machine: f64,
    pub ke_damper: f64,
    pub pe_damper_spring: f64,
    pub pe_damper_contact: f64,
}

impl EnergyTerms {
    /// Evaluates Eqs. (16)-(22) at state `X` in `mode`.
    pub fn at(sys: &ImpactSystem, mode: Mode, x: &[f64]) -> Self {
        Self::with_motions(sys, mode, x, &sys.motions(x))
    }

    /// [`Self::at`] given the relative motions of the state ([`ImpactSystem::motions`]).
    pub fn with_motions(sys: &ImpactSystem, mode: Mode, x: &[f64], m: &Motions) -> Self {
        let n = sys.n_modes();
        let nd = sys.dofs();
        let mut e = EnergyTerms::default();
        let vs = x[nd + sys.slider_index()];
        e.ke_slider = 0.5 * sys.slider.mass * vs * vs;
        for i in 0..n {
            let w = sys.structure.omega_rad_per_s[i];
            e.ke_machine += 0.5 * x[nd + i] * x[nd + i];
            e.pe_machine += 0.5 * w * w * x[i] * x[i];
        }
        if mode.on(Switch::SliderBed) {
            let d = m[0].0;
            e.pe_slider_contact = sys.slider_bed.law.potential_energy(d);
        }
        if let (Some(dm), Some(c)) = (&sys.damper, &sys.bed_damper) {
            let vd = x[nd + sys.damper_index()];
            e.ke_damper = 0.5 * dm.mass * vd * vd;
            let r = m[2].0;
            e.pe_damper_spring = 0.5 * dm.stiffness * r * r;
            if mode.on(Switch::BedDamper) {
                let d = m[1].0;
                e.pe_damper_contact = c.law.potential_energy(d);
            }
        }
        e
    }

    /// Sum of all stored terms.
    pub fn total(&self) -> f64 {
        self.ke_slider
            + self.pe_slider_contact
            + self.ke_machine
            + self.pe_machine
            + self.ke_damper
            + self.pe_damper_spring
            + self.pe_damper_contact
    }
}

/// Time histories on the output grid (one entry per sample), SI units.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct History {
    pub time_s: Vec<f64>,
    pub bed_displacement_m: Vec<f64>,
    pub bed_velocity_m_per_s: Vec<f64>,
    pub bed_acceleration_m_per_s2: Vec<f64>,
    pub floor_force_n: Vec<f64>,
    pub contact_force_slider_bed_n: Vec<f64>,
    pub contact_force_bed_damper_n: Vec<f64>,
    pub damper_force_n: Vec<f64>,
    pub slider_displacement_m: Vec<f64>,
    pub slider_velocity_m_per_s: Vec<f64>,
    pub damper_displacement_m: Vec<f64>,
    pub damper_velocity_m_per_s: Vec<f64>,
    pub energy: Vec<EnergyTerms>,
    /// Eq. (23): `E_s− − Σ stored` (J); with a constant slider force F,
    /// `E_s− + F (z_s − z_s0) − Σ stored`.
    pub dissipated_j: Vec<f64>,
}

impl History {
    /// Sample `i` in [`crate::io::HISTORY_COLUMNS`] order (the last value is Eq. (24),
    /// `KE_p + PE_p + dissipated`).
    pub fn row(&self, i: usize) -> [f64; 21] {
        let e = &self.energy[i];
        [
            self.time_s[i],
            self.bed_displacement_m[i],
            self.bed_velocity_m_per_s[i],
            self.bed_acceleration_m_per_s2[i],
            self.floor_force_n[i],
            self.contact_force_slider_bed_n[i],
            self.contact_force_bed_damper_n[i],
            self.damper_force_n[i],
            self.slider_displacement_m[i],
            self.slider_velocity_m_per_s[i],
            self.damper_displacement_m[i],
            self.damper_velocity_m_per_s[i],
            e.ke_slider,
            e.pe_slider_contact,
            e.ke_machine,
            e.pe_machine,
            e.ke_damper,
            e.pe_damper_spring,
            e.pe_damper_contact,
            self.dissipated_j[i],
            e.ke_machine + e.pe_machine + self.dissipated_j[i],
        ]
    }

    /// Reserves room for `samples` more samples in every series.
    pub fn reserve(&mut self, samples: usize) {
        for v in [
            &mut self.time_s,
            &mut self.bed_displacement_m,
            &mut self.bed_velocity_m_per_s,
            &mut self.bed_acceleration_m_per_s2,
            &mut self.floor_force_n,
            &mut self.contact_force_slider_bed_n,
            &mut self.contact_force_bed_damper_n,
            &mut self.damper_force_n,
            &mut self.slider_displacement_m,
            &mut self.slider_velocity_m_per_s,
            &mut self.damper_displacement_m,
            &mut self.damper_velocity_m_per_s,
            &mut self.dissipated_j,
        ] {
            v.reserve(samples);
        }
        self.energy.reserve(samples);
    }

    /// Appends one sample given as [`Self::row`] returns it.
    pub fn push_row(&mut self, r: &[f64; 21]) {
        self.time_s.push(r[0]);
        self.bed_displacement_m.push(r[1]);
        self.bed_velocity_m_per_s.push(r[2]);
        self.bed_acceleration_m_per_s2.push(r[3]);
        self.floor_force_n.push(r[4]);
        self.contact_force_slider_bed_n.push(r[5]);
        self.contact_force_bed_damper_n.push(r[6]);
        self.damper_force_n.push(r[7]);
        self.slider_displacement_m.push(r[8]);
        self.slider_velocity_m_per_s.push(r[9]);
        self.damper_displacement_m.push(r[10]);
        self.damper_velocity_m_per_s.push(r[11]);
        self.energy.push(EnergyTerms {
            ke_slider: r[12],
            pe_slider_contact: r[13],
            ke_machine: r[14],
            pe_machine: r[15],
            ke_damper: r[16],
            pe_damper_spring: r[17],
            pe_damper_contact: r[18],
        });
        self.dissipated_j.push(r[19]);
    }

    /// Bytes a history of `samples` samples holds in memory (20 `f64` per sample), for
    /// estimates ([`crate::limits`]).
    pub fn bytes_for(samples: f64) -> f64 {
        samples * HISTORY_SAMPLE_BYTES
    }
}

impl crate::io::HistoryRows for History {
    fn samples(&self) -> usize {
        self.time_s.len()
    }
    fn row(&self, i: usize) -> [f64; 21] {
        History::row(self, i)
    }
}

/// Memory of one sample of a [`History`]: 13 `f64` series and the 7 energy terms.
pub const HISTORY_SAMPLE_BYTES: f64 = 20.0 * 8.0;

/// The samples a run of `duration` s at `rate` Hz records: `⌊duration · rate⌋ + 1`.
pub fn sample_count(duration_s: f64, rate_hz: Option<f64>) -> f64 {
    match rate_hz {
        Some(r) => (duration_s * r).floor() + 1.0,
        None => 0.0,
    }
}

/// Evaluates the history's quantities of one sample (see [`History::row`]).
struct Sampler<'a> {
    sys: &'a ImpactSystem,
    map: ChannelMap,
    e_in: f64,
    /// z_s at the start of the run (for the constant force's work, `F (z_s − z_s0)`).
    z0: f64,
}

impl<'a> Sampler<'a> {
    fn new(sys: &'a ImpactSystem) -> Self {
        Sampler {
            sys,
            map: ChannelMap::new(sys),
            e_in: 0.5 * sys.slider.mass * sys.slider.velocity.powi(2),
            z0: 0.0,
        }
    }

    fn row(&self, t: f64, x: &[f64], mode: Mode) -> [f64; 21] {
        let sys = self.sys;
        let nd = sys.dofs();
        let v = self.map.values(sys, mode, x);
        let ch = |c: Channel| v[c.index()];
        let (zd, vd) = if sys.damper.is_some() {
            (x[sys.damper_index()], x[nd + sys.damper_index()])
        } else {
            (0.0, 0.0)
        };
        let e = EnergyTerms::at(sys, mode, x);
        let w_f = sys.slider_force() * (x[sys.slider_index()] - self.z0);
        let dissipated = self.e_in + w_f - e.total();
        [
            t,
            ch(Channel::BedDisplacement),
            ch(Channel::BedVelocity),
            ch(Channel::BedAcceleration),
            ch(Channel::FloorForce),
            ch(Channel::ContactSliderBed),
            ch(Channel::ContactBedDamper),
            ch(Channel::DamperSpring) + ch(Channel::DamperDashpot),
            x[sys.slider_index()],
            x[nd + sys.slider_index()],
            zd,
            vd,
            e.ke_slider,
            e.pe_slider_contact,
            e.ke_machine,
            e.pe_machine,
            e.ke_damper,
            e.pe_damper_spring,
            e.pe_damper_contact,
            dissipated,
            e.ke_machine + e.pe_machine + dissipated,
        ]
    }
}

/// Observer that records the histories on the output grid. Peaks do not come from here: the
/// integrators locate them on the continuous solution ([`crate::integrate::peaks`]).
pub struct Recorder<'a> {
    sampler: Sampler<'a>,
    pub history: History,
}

impl<'a> Recorder<'a> {
    pub fn new(sys: &'a ImpactSystem) -> Self {
        Recorder {
            sampler: Sampler::new(sys),
            history: History::default(),
        }
    }

    /// The recorder of a run starting from `x0` (chained blows): the constant slider force's
    /// work is counted from `x0`'s slider position.
    pub fn starting_at(mut self, x0: &[f64]) -> Self {
        self.sampler.z0 = x0[self.sampler.sys.slider_index()];
        self
    }
}

impl Observer for Recorder<'_> {
    fn sample(&mut self, t: f64, x: &[f64], mode: Mode) {
        let r = self.sampler.row(t, x, mode);
        self.history.push_row(&r);
    }
}

/// Observer that writes each sample straight to a CSV writer ([`crate::io::HistoryWriter`]):
/// a history of any length in constant memory, byte for byte what
/// [`crate::io::history_csv`] of the recorded [`History`] would be. The first write error
/// stops the writing and is returned by [`Self::finish`].
pub struct StreamRecorder<'a, W: std::io::Write> {
    sampler: Sampler<'a>,
    out: crate::io::HistoryWriter<W>,
    error: Option<std::io::Error>,
    sketch: Option<super::sketch::HistorySketch>,
}

impl<'a, W: std::io::Write> StreamRecorder<'a, W> {
    /// Writes the header to `out`.
    pub fn new(sys: &'a ImpactSystem, out: W) -> std::io::Result<Self> {
        Ok(StreamRecorder {
            sampler: Sampler::new(sys),
            out: crate::io::HistoryWriter::new(out)?,
            error: None,
            sketch: None,
        })
    }

    /// Also keeps a bounded [`HistorySketch`](super::sketch::HistorySketch) of the rows
    /// written, for pictures (`expected_samples`: the history's estimated length).
    pub fn with_sketch(mut self, expected_samples: f64) -> Self {
        self.sketch = Some(super::sketch::HistorySketch::new(expected_samples));
        self
    }

    /// The sketch kept since [`Self::with_sketch`] (`None` without one, or once taken).
    pub fn take_sketch(&mut self) -> Option<super::sketch::HistorySketch> {
        self.sketch.take()
    }

    /// Rows written.
    pub fn rows(&self) -> u64 {
        self.out.rows()
    }

    /// The writer back, or the first write error.
    pub fn finish(self) -> std::io::Result<W> {
        match self.error {
            Some(e) => Err(e),
            None => self.out.into_inner(),
        }
    }
}

impl<W: std::io::Write> Observer for StreamRecorder<'_, W> {
    fn sample(&mut self, t: f64, x: &[f64], mode: Mode) {
        if self.error.is_some() {
            return;
        }
        let r = self.sampler.row(t, x, mode);
        if let Some(sk) = &mut self.sketch {
            sk.push(&r);
        }
        if let Err(e) = self.out.row(&r) {
            self.error = Some(e);
        }
    }
}

/// The exact peak of one response channel over a run ([`crate::integrate::peaks`]): located on
/// the continuous solution, so it does not depend on the output sample rate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelPeak {
    /// Channel key with its unit ([`Channel::key`]).
    pub channel: &'static str,
    /// Human label ([`Channel::label`]).
    pub label: &'static str,
    pub unit: &'static str,
    /// Largest magnitude.
    pub peak: f64,
    /// Time of the peak (s).
    pub time_s: f64,
    /// Largest and smallest values, with their times (s).
    pub max: f64,
    pub max_time_s: f64,
    pub min: f64,
    pub min_time_s: f64,
}

/// The peaks of every channel the system has, in [`CHANNELS`] order.
pub fn channel_peaks(sys: &ImpactSystem, peaks: &Peaks) -> Vec<ChannelPeak> {
    CHANNELS
        .into_iter()
        .filter(|c| !(c.needs_damper() && sys.damper.is_none()))
        .map(|c| {
            let e = peaks.get(c);
            let (v, t) = e.peak();
            let set = e.is_set();
            ChannelPeak {
                channel: c.key(),
                label: c.label(),
                unit: c.unit(),
                peak: v.abs(),
                time_s: if set { t } else { 0.0 },
                max: if set { e.max } else { 0.0 },
                max_time_s: if set { e.t_max } else { 0.0 },
                min: if set { e.min } else { 0.0 },
                min_time_s: if set { e.t_min } else { 0.0 },
            }
        })
        .collect()
}

/// How exact the channel peaks of a run are, in words (printed beside them, and the summary's
/// `peak_accuracy`). With `exact` every stretch is a closed form or a Taylor polynomial exact to
/// round-off, and the extremes are located on it: exact to round-off. With `dopri5` they are
/// located on the dense output, whose error is the integration's: on the paper's four machines at
/// rtol 1e-8 the peaks differ from `exact`'s by at most 4e-7 of their value (the no-base machine's
/// bed displacement), so the last of seven printed digits is not certain.
pub fn peak_accuracy(opts: &Options) -> String {
    match opts.method {
        Method::Exact => "exact, on the continuous solution".into(),
        Method::Dopri5 => format!(
            "estimates on dopri5's dense output, as accurate as the integration at rtol {}, atol {}",
            crate::error::num(opts.rtol),
            crate::error::num(opts.atol)
        ),
    }
}

/// The energy-balance residual a run of `method` must stay within (relative to the blow's
/// energy E_s−): `1e-9` for `exact` (closed forms, round-off only), `max(1e-6, 100·rtol)` for
/// `dopri5` (1e-6 at the default rtol 1e-8).
pub fn residual_bound(opts: &Options) -> f64 {
    match opts.method {
        Method::Exact => 1e-9,
        Method::Dopri5 => (100.0 * opts.rtol).max(1e-6),
    }
}

/// The bound on [`Balance::residual_transferred`], the relative error the energy left in the
/// machine (E_p+, J) may carry: ten times [`residual_bound`] (1e-8 for `exact`, 1e-5 for
/// `dopri5` at the default rtol). A blow in which the slider gives away a tenth of its energy or
/// more passes it whenever it passes the first bound; a run in which E_p+ is a difference of
/// numbers far larger than itself (a slider much heavier than the machine) is refused.
pub fn transferred_bound(opts: &Options) -> f64 {
    10.0 * residual_bound(opts)
}

/// What in the model most likely makes a run fail its checks: the contact laws and
/// stiffnesses, and the spread of the time scales (the structure's frequencies against the
/// contact frequencies `√(K/m)`).
fn likely_causes(sys: &ImpactSystem) -> String {
    let law = |c: &crate::impact::Contact| match c.law {
        ContactLaw::Linear { stiffness, damping } => {
            format!("linear, K = {stiffness:e} N/m, C = {damping:e} N·s/m")
        }
        ContactLaw::Hertz { stiffness } => format!("hertz, K = {stiffness:e} N/m^1.5"),
        ContactLaw::HuntCrossley {
            stiffness,
            exponent,
            alpha,
        } => format!("hunt-crossley, K = {stiffness:e} N/m^{exponent}, alpha = {alpha:e} s/m"),
        ContactLaw::Rigid { restitution } => format!("rigid, e = {restitution}"),
    };
    let mut out = format!("contact.slider_bed ({})", law(&sys.slider_bed));
    if let (Some(c), Some(d)) = (&sys.bed_damper, &sys.damper) {
        out += &format!(
            ", contact.bed_damper ({}), damper (m_d = {:e} kg, k_d = {:e} N/m, c_d = {:e} N·s/m)",
            law(c),
            d.mass,
            d.stiffness,
            d.damping
        );
    }
    let w = &sys.structure.omega_rad_per_s;
    let w_max = w.iter().copied().fold(0.0, f64::max);
    let w_min = w
        .iter()
        .copied()
        .filter(|v| *v > 0.0)
        .fold(f64::INFINITY, f64::min);
    if w_max > 0.0 && w_min.is_finite() {
        out += &format!(
            ", structure modes {:.4e}-{:.4e} Hz",
            w_min / (2.0 * std::f64::consts::PI),
            w_max / (2.0 * std::f64::consts::PI)
        );
    }
    out
}

/// Checks a finished run: a finite state and finite peaks, and an energy balance within
/// [`residual_bound`], both relative to the energy put in and relative to the energy the slider
/// gave away (see [`Balance`]). `balances` are the balances to check (the run's end, and the
/// collision's end when it ended).
pub fn check_run(
    sys: &ImpactSystem,
    opts: &Options,
    sol: &Solution,
    balances: &[Balance],
) -> Result<()> {
    if let Some(c) = sol.totals.peaks.non_finite() {
        return Err(Error::numerical(
            "simulation",
            format!(
                "the {} became non-finite (by t = {:.6e} s): the state overflowed. Likely cause: {}",
                c.label(),
                sol.t_final,
                likely_causes(sys)
            ),
        ));
    }
    if sol.x_final.iter().any(|v| !v.is_finite())
        || balances
            .iter()
            .any(|b| !b.residual.is_finite() || !b.residual_transferred.is_finite())
    {
        return Err(Error::numerical(
            "simulation",
            format!(
                "the state became non-finite by t = {:.6e} s. Likely cause: {}",
                sol.t_final,
                likely_causes(sys)
            ),
        ));
    }
    let bound = residual_bound(opts);
    let bound_transferred = transferred_bound(opts);
    let method = match opts.method {
        Method::Exact => "exact".to_string(),
        Method::Dopri5 => format!("dopri5, rtol {:e}", opts.rtol),
    };
    let tolerance = atol_hint(opts, sol);
    for b in balances {
        if b.residual > bound {
            return Err(Error::numerical(
                "simulation",
                format!(
                    "energy balance violated at t = {:.6e} s: residual {:.3e} of the blow's \
                     energy > {bound:e} allowed ({method}). Likely cause: {tolerance}{}",
                    b.t,
                    b.residual,
                    likely_causes(sys)
                ),
            ));
        }
        if b.residual_transferred > bound_transferred {
            return Err(Error::numerical(
                "simulation",
                format!(
                    "energy balance cannot be trusted at t = {:.6e} s: the discrepancy {:.3e} J is \
                     {:.3e} of the energy the slider gave the machine and damper ({:.3e} J), > \
                     {bound_transferred:e} allowed ({method}); the slider keeps {:.3e} J. The energies left in \
                     the machine are differences of numbers {:.1e} times larger than themselves, \
                     beyond what double precision carries. Likely cause: {tolerance}slider.mass = {:e} kg \
                     (a slider so heavy that it hardly slows down), or: {}",
                    b.t,
                    b.discrepancy_j,
                    b.residual_transferred,
                    b.transferred_j,
                    b.slider_kinetic_j,
                    b.slider_kinetic_j / b.transferred_j.max(f64::MIN_POSITIVE),
                    sys.slider.mass,
                    likely_causes(sys)
                ),
            ));
        }
    }
    Ok(())
}

/// The first likely cause of a `dopri5` run's failed balance when its absolute tolerance is not
/// small against the motion: `simulation.atol` (m and m/s alike) above 1e-6 of the largest bed
/// displacement or velocity at B (a blow at 1e-12 m/s moves the bed by 1e-16 m, below the default
/// 1e-14, so the error control accepts any step). Empty otherwise, and for `exact`.
fn atol_hint(opts: &Options, sol: &Solution) -> String {
    if opts.method != Method::Dopri5 {
        return String::new();
    }
    let p = &sol.totals.peaks;
    let x = p.get(Channel::BedDisplacement).abs_peak();
    let v = p.get(Channel::BedVelocity).abs_peak();
    let motion = x.min(v);
    if !(motion.is_finite() && opts.atol > 1e-6 * motion) {
        return String::new();
    }
    format!(
        "simulation.atol = {} is not small against the motion (largest bed displacement {:.3e} m, \
         velocity {:.3e} m/s at B): give {} (below 1e-6 of it), or use method \"exact\" \
         (linear contact laws); or: ",
        crate::error::num(opts.atol),
        x,
        v,
        crate::error::num(10f64.powf((1e-6 * motion).log10().floor()))
    )
}

/// The energy balance of a run at one instant `t`:
///
/// ```text
/// discrepancy = E_in + W_F − Σ stored − ∫P dt
/// residual             = |discrepancy| / (E_in + |W_F|)
/// residual_transferred = |discrepancy| / (Σ stored − KE_ms + ∫P dt)
/// ```
///
/// `residual` is the issue's measure, relative to the energy put in. The energy left in the
/// machine (Eq. 10, `E_p+ = E_s− − E_s+ − E_d+`) is a difference: when the slider keeps
/// nearly all of its energy (a slider far heavier than the machine) the balance can hold to
/// 1e-16 of `E_s−` while E_p+ has lost every digit. `residual_transferred` measures the same
/// discrepancy against what the slider gave away (everything stored outside the slider's
/// kinetic energy, plus what was dissipated: a sum of non-negative parts, free of
/// cancellation), so it bounds the relative error of E_p+ and of the energy ratio.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Balance {
    /// Time of the balance (s, from the run's start).
    pub t: f64,
    pub residual: f64,
    pub residual_transferred: f64,
    /// `E_in + W_F − Σ stored − ∫P dt` (J).
    pub discrepancy_j: f64,
    /// `Σ stored − KE_ms + ∫P dt` (J).
    pub transferred_j: f64,
    /// KE_ms (J).
    pub slider_kinetic_j: f64,
}

impl Balance {
    /// The balance at `t` of a run put in `e_in` (J) and the slider force's work `w_f` (J),
    /// with the stored energies `e` and the energy dissipated so far (J).
    pub fn new(t: f64, e_in: f64, w_f: f64, e: &EnergyTerms, dissipated: f64) -> Self {
        let stored = e.total();
        let discrepancy_j = e_in + w_f - stored - dissipated;
        let transferred_j = (e.pe_slider_contact
            + e.ke_machine
            + e.pe_machine
            + e.ke_damper
            + e.pe_damper_spring
            + e.pe_damper_contact)
            + dissipated;
        let residual_transferred = if discrepancy_j == 0.0 {
            0.0
        } else {
            discrepancy_j.abs() / transferred_j.max(f64::MIN_POSITIVE)
        };
        Self {
            t,
            residual: balance_residual(e_in, w_f, stored, dissipated),
            residual_transferred,
            discrepancy_j,
            transferred_j,
            slider_kinetic_j: e.ke_slider,
        }
    }
}

/// The summary of a run: what happened to the blow's energy. Keys are stable (JSON output).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    pub method: &'static str,
    /// E_p+ / E_s− (Eq. 10 over Eq. 11); `None` if the collision did not end within the run.
    /// With a constant slider force F: `E_p+ / (E_s− + W_F+)`, `E_p+ = E_s− + W_F+ − E_s+ −
    /// E_d+` (see the module documentation).
    pub energy_ratio: Option<f64>,
    /// F (N), the constant force on the slider (0 without one).
    pub slider_force_n: f64,
    /// W_F+ = F (z_s − z_s0) at the end of the collision (J): the work of the slider force
    /// during the collision; `None` if the collision did not end.
    pub force_work_after_j: Option<f64>,
    /// The energy ratio's denominator `E_s− + W_F+` (J; `E_s−` when F = 0).
    pub energy_input_j: Option<f64>,
    /// W_F at the end of the run (J).
    pub force_work_run_end_j: f64,
    pub collision_end_s: Option<f64>,
    pub slider_energy_before_j: f64,
    pub slider_energy_after_j: Option<f64>,
    pub damper_energy_after_j: Option<f64>,
    pub machine_energy_after_j: Option<f64>,
    /// Parts of E_p+: kinetic and potential energy of the structure, and energy dissipated
    /// (structural damping, dashpots, contact damping) up to the end of the collision.
    pub machine_kinetic_energy_after_j: Option<f64>,
    pub machine_potential_energy_after_j: Option<f64>,
    pub dissipated_energy_after_j: Option<f64>,
    /// ż_s at the end of the collision (negative: moving away from the bed).
    pub slider_rebound_velocity_m_per_s: Option<f64>,
    pub damper_velocity_m_per_s: Option<f64>,
    pub contact_time_slider_bed_s: Option<f64>,
    pub contact_time_bed_damper_s: Option<f64>,
    /// Peak contact forces during the collision (during the run if it did not end).
    pub peak_contact_force_slider_bed_n: f64,
    pub peak_contact_force_bed_damper_n: f64,
    /// Largest |bed acceleration at B| and |force to the floor| over the run, on the
    /// continuous solution (independent of the output sample rate), and their times.
    pub peak_bed_acceleration_m_per_s2: f64,
    pub peak_bed_acceleration_time_s: f64,
    pub peak_floor_force_n: f64,
    pub peak_floor_force_time_s: f64,
    /// The peaks of every channel over the run, located on the continuous solution.
    pub peaks: Vec<ChannelPeak>,
    /// How exact [`Summary::peaks`] are ([`peak_accuracy`]): to round-off for `exact`, to the
    /// integration tolerance for `dopri5`.
    pub peak_accuracy: String,
    /// |E_s− − Σ stored − ∫ P_diss dt| / E_s− at the end of the collision; with a constant
    /// slider force `|E_s− + W_F − Σ stored − ∫ P_diss dt| / (E_s− + |W_F|)`.
    pub energy_balance_residual: Option<f64>,
    /// The same at the end of the run.
    pub energy_balance_residual_run_end: f64,
    /// The same discrepancy relative to the energy the slider gave away (everything stored
    /// outside its kinetic energy, plus what was dissipated; [`Balance`]): the relative error
    /// E_p+ and the energy ratio may carry. At the end of the collision, and of the run.
    pub energy_balance_residual_transferred: Option<f64>,
    pub energy_balance_residual_transferred_run_end: f64,
    pub simulated_time_s: f64,
    pub switching_events: usize,
    pub steps: usize,
}

/// The energy-balance residual `|E_in + W_F − stored − dissipated| / (E_in + |W_F|)`: the
/// energy put in (`E_in`, and the constant slider force's work `W_F`, 0 without one) against
/// what is stored and what was dissipated, relative to the energy that went through the system.
/// For `W_F = 0` this is `|E_in − stored − dissipated| / E_in`, bit for bit.
pub fn balance_residual(e_in: f64, w_f: f64, stored: f64, dissipated: f64) -> f64 {
    if w_f == 0.0 {
        (e_in - stored - dissipated).abs() / e_in
    } else {
        (e_in + w_f - stored - dissipated).abs() / (e_in + w_f.abs())
    }
}

/// A finished run.
#[derive(Debug, Clone)]
pub struct Run {
    pub summary: Summary,
    pub history: Option<History>,
    pub solution: Solution,
}

/// Simulates `sys`, records histories when `record` is true, and summarises. The history is
/// held in memory: its estimate (`samples ×` [`HISTORY_SAMPLE_BYTES`]) is checked against
/// [`crate::limits::max_memory`] first. To write a long history to a file, use
/// [`simulate_observed`] with a [`StreamRecorder`].
pub fn simulate(sys: &ImpactSystem, opts: &Options, record: bool) -> Result<Run> {
    let mut rec = Recorder::new(sys);
    if record {
        let n = sample_count(opts.duration, opts.sample_rate);
        crate::limits::check_memory(
            &format!("the history ({n:.3e} samples × {HISTORY_SAMPLE_BYTES} B)"),
            History::bytes_for(n),
            "simulation.duration",
            "simulation.duration (--duration) or simulation.sample_rate (--rate), or write the \
             history to a file (simulate -o streams it)",
        )?;
    }
    if record {
        // Exactly the estimate checked above: no doubling growth of the series.
        rec.history
            .reserve(sample_count(opts.duration, opts.sample_rate) as usize + 2);
    }
    let (summary, solution) = simulate_observed(sys, opts, record.then_some(&mut rec as _))?;
    let history = if record { Some(rec.history) } else { None };
    Ok(Run {
        summary,
        history,
        solution,
    })
}

/// Simulates `sys` and summarises; `obs` (when given) receives the samples of
/// `opts.sample_rate` (without it, no sample is computed).
pub fn simulate_observed(
    sys: &ImpactSystem,
    opts: &Options,
    obs: Option<&mut dyn Observer>,
) -> Result<(Summary, Solution)> {
    // A bed no mode moves takes no energy: the run's energy ratios would be 0/0.
    if let Some(why) =
        crate::modal::immovable_point("the bed contact point", &sys.points.bed_contact)
    {
        return Err(Error::invalid("points.bed_contact", why));
    }
    let sol = match obs {
        Some(o) => integrate::solve(sys, opts, o)?,
        None => integrate::solve(
            sys,
            &Options {
                sample_rate: None,
                ..*opts
            },
            &mut integrate::NoOutput,
        )?,
    };
    let nd = sys.dofs();
    let e_in = 0.5 * sys.slider.mass * sys.slider.velocity.powi(2);
    let end = sol.collision_end.as_ref();
    let at_end = end.map(|c| {
        let mode = Mode(0); // both contacts open at the end of the collision
        let e = EnergyTerms::at(sys, mode, &c.x);
        let vs = c.x[nd + sys.slider_index()];
        let vd = if sys.damper.is_some() {
            Some(c.x[nd + sys.damper_index()])
        } else {
            None
        };
        (e, vs, vd, c)
    });
    let e_final = EnergyTerms::at(sys, sol.mode_final, &sol.x_final);
    let x0 = sys.initial_state();
    let w_end = sys.force_work(&x0, &sol.x_final);
    let run_end = Balance::new(sol.t_final, e_in, w_end, &e_final, sol.totals.dissipated);
    let w_ce = end.map(|c| sys.force_work(&x0, &c.x));
    let collision = at_end
        .zip(w_ce)
        .map(|((e, .., c), w)| Balance::new(c.t, e_in, w, &e, c.totals.dissipated));
    let balances: Vec<Balance> = std::iter::once(run_end).chain(collision).collect();
    check_run(sys, opts, &sol, &balances)?;
    let pk = |c: Channel| sol.totals.peaks.get(c).peak();
    let summary = Summary {
        method: match opts.method {
            Method::Exact => "exact",
            Method::Dopri5 => "dopri5",
        },
        energy_ratio: at_end.zip(w_ce).map(|((e, ..), w)| {
            (e_in + w - e.ke_slider - e.ke_damper - e.pe_damper_spring) / (e_in + w)
        }),
        slider_force_n: sys.slider_force(),
        force_work_after_j: w_ce,
        energy_input_j: w_ce.map(|w| e_in + w),
        force_work_run_end_j: w_end,
        collision_end_s: end.map(|c| c.t),
        slider_energy_before_j: e_in,
        slider_energy_after_j: at_end.map(|(e, ..)| e.ke_slider),
        damper_energy_after_j: at_end.map(|(e, ..)| e.ke_damper + e.pe_damper_spring),
        machine_energy_after_j: at_end
            .zip(w_ce)
            .map(|((e, ..), w)| e_in + w - e.ke_slider - e.ke_damper - e.pe_damper_spring),
        machine_kinetic_energy_after_j: at_end.map(|(e, ..)| e.ke_machine),
        machine_potential_energy_after_j: at_end.map(|(e, ..)| e.pe_machine),
        dissipated_energy_after_j: at_end.map(|(.., c)| c.totals.dissipated),
        slider_rebound_velocity_m_per_s: at_end.map(|(_, vs, ..)| vs),
        damper_velocity_m_per_s: at_end.and_then(|(_, _, vd, _)| vd),
        contact_time_slider_bed_s: end.map(|c| c.totals.closed_time[0]),
        contact_time_bed_damper_s: end.map(|c| c.totals.closed_time[1]),
        peak_contact_force_slider_bed_n: end
            .map_or(sol.totals.peak_force(0), |c| c.totals.peak_force(0)),
        peak_contact_force_bed_damper_n: end
            .map_or(sol.totals.peak_force(1), |c| c.totals.peak_force(1)),
        peak_bed_acceleration_m_per_s2: pk(Channel::BedAcceleration).0.abs(),
        peak_bed_acceleration_time_s: pk(Channel::BedAcceleration).1,
        peak_floor_force_n: pk(Channel::FloorForce).0.abs(),
        peak_floor_force_time_s: pk(Channel::FloorForce).1,
        peaks: channel_peaks(sys, &sol.totals.peaks),
        peak_accuracy: peak_accuracy(opts),
        energy_balance_residual: collision.map(|b| b.residual),
        energy_balance_residual_run_end: run_end.residual,
        energy_balance_residual_transferred: collision.map(|b| b.residual_transferred),
        energy_balance_residual_transferred_run_end: run_end.residual_transferred,
        simulated_time_s: sol.t_final,
        switching_events: sol.events.len(),
        steps: sol.steps,
    };
    Ok((summary, sol))
}
