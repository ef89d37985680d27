//! Dormand-Prince 5(4) with PI step control, dense output and event location.
//!
//! The explicit Runge-Kutta pair of Dormand & Prince (J. Comput. Appl. Math. 6 (1980) 19-26)
//! as in Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.5 and their `dopri5` code: 7 stages
//! with FSAL, error estimate of order 4, PI step-size control (β = 0.04), and the 4th-order
//! continuous extension for dense output. Hand-written because no Rust ODE crate offers
//! DOPRI5 with dense output, event location and no per-step allocation together
//! (see shared/notes/stack.md).
//!
//! The mode (which contacts are closed) is frozen within a step, so the right-hand side is
//! smooth there; after each accepted step every indicator (all are affine in the state,
//! `g = ℓᵀX + c`) is checked on the dense output with the same crossing search as the exact
//! propagator (values and slopes at the step ends with a Hermite dip test first; the search
//! lifts `g` by its zero band so that a start within it is on its selected side), the step is
//! cut at the first crossing and the run restarts from the interpolated state in the new mode.
//!
//! **Mode selection** (at t = 0 and at each switch, for every contact law): an indicator's
//! side is the sign of its value beyond a zero band (`rtol/10` of its terms, round-off at
//! least), else that of its first non-vanishing time derivative `ℓᵀ y_k`, `y_1 = f_σ(X)`,
//! `y_{k+1} = J_σ(X) y_k` with `J_σ` the Jacobian of the right-hand side (exact for linear
//! laws, where it is `A_σ`, and for the first two derivatives with any law); candidate modes
//! are iterated to a consistent one. An indicator still zero to all orders (a Hertz contact at
//! zero overlap moves with fractional powers of time) is settled by the motion: if the next
//! step leaves it beyond its band on the side its mode excludes, it left zero at once, and the
//! step is redone from its start in the mode that side implies.
//!
//! **Energy**: the dissipated energy is integrated as an extra state component (not under
//! error control): `ẋᵀC_σẋ` with the modal damping, the dashpots and the rate-dependent part
//! `(f − f_elastic) δ̇` of each closed contact; a contact released by the force rule at a
//! positive overlap takes its elastic energy with it ([`contact_energy_jump`]).
//!
//! **Peaks**: every channel ([`Channel`]) is followed on the dense output: its values and
//! slopes at the step ends, and the root of its slope where it changes sign (or where the
//! cubic Hermite interpolant of the ends has critical points), so the extremes and their times
//! do not depend on the output samples. Both one-sided values are offered at each switch.
//!
//! **Path**: [`Solution::path`] has a knot at t = 0, at each mode change, and at each accepted
//! step while a closed contact has a non-linear law.
//!
//! **Guards**: 1000 consecutive rejected steps, 1000 consecutive switches that do not advance
//! time, a step below 16 ulps of `t`, or more than [`MAX_STEPS`] steps end the run with an
//! error naming the time, the mode and the likely cause; a run whose pace projects beyond
//! [`MAX_STEPS`] for four windows of 2²⁰ steps in a row stops then, with the projection
//! ([`Pace`]).
//!
//! **Persistent (held) contacts**: a closed contact that rests, with a step limited by its
//! stability rather than by its motion, is held: its gap frozen, its force the constraint's
//! multiplier, the stiff frequency out of the step size; released when the multiplier would
//! pull ([`Holder`]).
//!
//! **Resting one-way dashpot**: the dashpot's velocity has a zero band of `rtol/10` of the
//! largest size it reached in the run ([`Selector::band`]), so a machine at rest, whose
//! velocities the integration carries only to that accuracy, does not switch the dashpot at
//! every half period of a contact for ever. The dashpot force is continuous at the switch
//! (`c·v` with `v` in the band), so the band moves forces by at most `c` times its width.

use super::peaks::{Extremes, Peaks};
use super::roots::{first_crossing, hermite_dip, Scalar, SearchOptions};
use super::switching::{implied_mode, ModeSelector};
use super::{CollisionEnd, Event, Grid, Observer, Options, PathPoint, Solution, Totals};
use crate::impact::SparseVec;
use crate::impact::{
    dot, Channel, ChannelMap, ContactLaw, DashpotKind, ImpactSystem, Indicator, Mode, Switch,
    N_CHANNELS,
};
use crate::{Error, Result};

// The system is autonomous, so the nodes c_i are not needed.
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// Right-hand side of the impact system for any contact law, in a frozen mode.
struct Rhs<'a> {
    sys: &'a ImpactSystem,
    n: usize,
    nd: usize,
    omega2: Vec<f64>,
    damping: &'a [f64],
    damping_diagonal: bool,
    a_s: SparseVec,
    a_d: SparseVec,
    a_f: SparseVec,
    masses: Vec<f64>,
    /// Linear contact laws only: per mode, the lower half of `A_σ` (`nd` rows of `2·nd`), built
    /// on first use; then `f(y) = A_σ y` and the dissipated power is `−Σ m_i ẋ_i (A₂₂ ẋ)_i`.
    linear_rows: Option<[std::cell::OnceCell<Vec<f64>>; 8]>,
    /// `F/m_s` (m/s²), the constant slider force's acceleration, added to `z̈_s`
    /// ([`ImpactSystem::slider_force`]); 0 without a force.
    force_acc: f64,
}

impl<'a> Rhs<'a> {
    fn new(sys: &'a ImpactSystem) -> Self {
        let n = sys.n_modes();
        let damping = &sys.structure.damping;
        let damping_diagonal = (0..n).all(|i| (0..n).all(|j| i == j || damping[i * n + j] == 0.0));
        let has_d = sys.damper.is_some();
        Rhs {
            sys,
            n,
            nd: sys.dofs(),
            omega2: sys
                .structure
                .omega_rad_per_s
                .iter()
                .map(|w| w * w)
                .collect(),
            damping,
            damping_diagonal,
            a_s: SparseVec::new(sys.relative_vector(Switch::SliderBed)),
            a_d: SparseVec::new(if has_d {
                sys.relative_vector(Switch::BedDamper)
            } else {
                &[]
            }),
            a_f: SparseVec::new(if has_d {
                sys.relative_vector(Switch::Dashpot)
            } else {
                &[]
            }),
            masses: sys.mass_diag(),
            linear_rows: [Switch::SliderBed, Switch::BedDamper]
                .iter()
                .all(|&s| {
                    (s == Switch::BedDamper && sys.damper.is_none())
                        || sys.contact(s).law.is_linear()
                })
                .then(Default::default),
            force_acc: sys.slider_force() / sys.slider.mass,
        }
    }

    /// Linear laws: keeps the lower half of `mode`'s `A_σ` (given column-major, as the mode
    /// selection built it), row by row, for [`Rhs::eval`]. Until a mode's rows are set its
    /// right-hand side takes the general path (the same values, force by force).
    fn set_lower_rows(&self, mode: Mode, a: &[f64]) {
        let Some(cell) = self
            .linear_rows
            .as_ref()
            .and_then(|rows| rows.get(usize::from(mode.0)))
        else {
            return;
        };
        cell.get_or_init(|| {
            let n = 2 * self.nd;
            let mut r = Vec::with_capacity(self.nd * n);
            for i in self.nd..n {
                r.extend((0..n).map(|j| a[j * n + i]));
            }
            r
        });
    }

    /// The lower half of `A_σ`, row by row, once set ([`Rhs::set_lower_rows`]).
    fn lower_rows(&self, mode: Mode) -> Option<&[f64]> {
        self.linear_rows
            .as_ref()?
            .get(usize::from(mode.0))?
            .get()
            .map(|r| &r[..])
    }

    /// `dy = f(y)`, `y = [x; ẋ; E_diss]`: `ẍ = M⁻¹(−K_σx − C_σẋ − contact forces) + b` with
    /// `b = (F/m_s) e_s` the constant slider force ([`ImpactSystem::forcing`]; it does no
    /// dissipation: its work is `F (z_s − z_s0)`, [`ImpactSystem::force_work`]).
    #[inline]
    fn eval(&self, mode: Mode, y: &[f64], dy: &mut [f64]) {
        if mode.any_held() {
            self.eval_held(mode, y, dy);
            return;
        }
        self.eval_unforced(mode, y, dy);
        if self.force_acc != 0.0 {
            dy[self.nd + self.n] += self.force_acc;
        }
    }

    /// [`Rhs::eval`] with held contacts ([`Mode::held`]): the free mode's accelerations
    /// `ẍ_f` ([`Mode::free`], the slider force included) projected so that no held gap
    /// changes, `ẍ = ẍ_f − M⁻¹ A λ`, `G λ = Aᵀ ẍ_f` ([`ImpactSystem::project_held`]). The
    /// dissipated power gains `Σ (λ_c − f_c,el(δ_c)) δ̇_c` over the held contacts: the
    /// difference between the work of the multiplier on the bodies and the change of the
    /// contact's stored energy `E_c(δ_c)` (zero while `δ̇_c = 0`, round-off after the entry's
    /// projection); with it the balance is closed whatever `δ̇_c` is.
    fn eval_held(&self, mode: Mode, y: &[f64], dy: &mut [f64]) {
        let nd = self.nd;
        self.eval_unforced(mode.free(), y, dy);
        if self.force_acc != 0.0 {
            dy[nd + self.n] += self.force_acc;
        }
        let lam = self
            .sys
            .project_held(mode, &mut dy[nd..2 * nd], &self.masses);
        let (x, v) = (&y[..nd], &y[nd..2 * nd]);
        for (ci, (s, a)) in [
            (Switch::SliderBed, &self.a_s),
            (Switch::BedDamper, &self.a_d),
        ]
        .into_iter()
        .enumerate()
        {
            if mode.held(s) {
                let (d, r) = a.dots(x, v);
                dy[2 * nd] += (lam[ci] - elastic(&self.sys.contact(s).law, d)) * r;
            }
        }
    }

    /// The held contacts' forces `λ` at the state `y` and their rates `λ̇` along the state's
    /// derivative `yd` (`λ̇ = G⁻¹ Aᵀ J_f ẏ`, [`Rhs::jvp`] in the free mode).
    fn held_forces(&self, mode: Mode, y: &[f64], yd: &[f64]) -> ([f64; 2], [f64; 2]) {
        let nd = self.nd;
        let mut a = vec![0.0; 2 * nd + 1];
        let free = mode.free();
        self.eval_unforced(free, y, &mut a);
        if self.force_acc != 0.0 {
            a[nd + self.n] += self.force_acc;
        }
        let lam = self
            .sys
            .project_held(mode, &mut a[nd..2 * nd], &self.masses);
        self.jvp(free, y, &yd[..2 * nd], &mut a[..2 * nd]);
        let rate = self
            .sys
            .project_held(mode, &mut a[nd..2 * nd], &self.masses);
        (lam, rate)
    }

    /// [`Rhs::eval`] without the constant slider force.
    fn eval_unforced(&self, mode: Mode, y: &[f64], dy: &mut [f64]) {
        let (n, nd) = (self.n, self.nd);
        let (x, v) = (&y[..nd], &y[nd..2 * nd]);
        dy[..nd].copy_from_slice(v);
        if let Some(rows) = self.lower_rows(mode) {
            // Fixed sizes for small lumped machines (fully unrolled).
            match nd {
                2 => return linear_small::<2>(rows, &self.masses, y, dy),
                3 => return linear_small::<3>(rows, &self.masses, y, dy),
                4 => return linear_small::<4>(rows, &self.masses, y, dy),
                5 => return linear_small::<5>(rows, &self.masses, y, dy),
                6 => return linear_small::<6>(rows, &self.masses, y, dy),
                7 => return linear_small::<7>(rows, &self.masses, y, dy),
                8 => return linear_small::<8>(rows, &self.masses, y, dy),
                _ => {}
            }
            let mut power = 0.0;
            for (i, row) in rows.chunks_exact(2 * nd).enumerate() {
                let (rx, rv) = row.split_at(nd);
                let damp = dot(rv, v);
                dy[nd + i] = dot(rx, x) + damp;
                power -= self.masses[i] * v[i] * damp;
            }
            dy[2 * nd] = power;
            return;
        }
        let acc = &mut dy[nd..2 * nd];
        let mut power = 0.0;
        for i in 0..n {
            let mut c = 0.0;
            if self.damping_diagonal {
                c = self.damping[i * n + i] * v[i];
            } else {
                for j in 0..n {
                    c += self.damping[i * n + j] * v[j];
                }
            }
            power += c * v[i];
            acc[i] = -self.omega2[i] * x[i] - c;
        }
        for a in acc[n..].iter_mut() {
            *a = 0.0;
        }
        if mode.on(Switch::SliderBed) {
            let law = self.sys.slider_bed.law;
            let (d, r) = self.a_s.dots(x, v);
            let f = law.force(d, r);
            power += (f - elastic(&law, d)) * r;
            self.a_s.sub_scaled(f, acc);
        }
        if let (Some(dmp), Some(c)) = (&self.sys.damper, &self.sys.bed_damper) {
            if mode.on(Switch::BedDamper) {
                let (d, r) = self.a_d.dots(x, v);
                let f = c.law.force(d, r);
                power += (f - elastic(&c.law, d)) * r;
                self.a_d.sub_scaled(f, acc);
            }
            let (d, r) = self.a_f.dots(x, v);
            let c_on = dmp.dashpot == DashpotKind::TwoWay || mode.on(Switch::Dashpot);
            let cd = if c_on { dmp.damping } else { 0.0 };
            power += cd * r * r;
            self.a_f.sub_scaled(dmp.stiffness * d + cd * r, acc);
        }
        for i in n..nd {
            acc[i] /= self.masses[i];
        }
        dy[2 * nd] = power;
    }
}

impl Rhs<'_> {
    /// `out = J_σ(y) w` over positions and velocities (`2·dofs` entries): the derivative of
    /// `f_σ` at `y` in the direction `w`, a non-linear law by its partial derivatives
    /// `∂f/∂δ`, `∂f/∂δ̇` ([`ContactLaw::partials`]) at `y`. For linear laws this is `A_σ w`.
    fn jvp(&self, mode: Mode, y: &[f64], w: &[f64], out: &mut [f64]) {
        if mode.any_held() {
            // `J = P J_f`: the free mode's derivative, projected as the accelerations are.
            self.jvp(mode.free(), y, w, out);
            let nd = self.nd;
            self.sys
                .project_held(mode, &mut out[nd..2 * nd], &self.masses);
            return;
        }
        let (n, nd) = (self.n, self.nd);
        let (x, v) = (&y[..nd], &y[nd..2 * nd]);
        let (wx, wv) = (&w[..nd], &w[nd..2 * nd]);
        out[..nd].copy_from_slice(wv);
        let acc = &mut out[nd..2 * nd];
        for i in 0..n {
            let c = if self.damping_diagonal {
                self.damping[i * n + i] * wv[i]
            } else {
                dot(&self.damping[i * n..(i + 1) * n], wv)
            };
            acc[i] = -self.omega2[i] * wx[i] - c;
        }
        for a in acc[n..].iter_mut() {
            *a = 0.0;
        }
        for (s, a) in [
            (Switch::SliderBed, &self.a_s),
            (Switch::BedDamper, &self.a_d),
        ] {
            if !mode.on(s) || (s == Switch::BedDamper && self.sys.damper.is_none()) {
                continue;
            }
            let (d, r) = a.dots(x, v);
            let (fd, fr) = self.sys.contact(s).law.partials(d, r);
            let (dw, rw) = a.dots(wx, wv);
            a.sub_scaled(fd * dw + fr * rw, acc);
        }
        if let Some(dmp) = &self.sys.damper {
            let (dw, rw) = self.a_f.dots(wx, wv);
            let c_on = dmp.dashpot == DashpotKind::TwoWay || mode.on(Switch::Dashpot);
            let cd = if c_on { dmp.damping } else { 0.0 };
            self.a_f.sub_scaled(dmp.stiffness * dw + cd * rw, acc);
        }
        for i in n..nd {
            acc[i] /= self.masses[i];
        }
    }
}

/// [`Rhs::eval`] for linear laws with `ND` degrees of freedom: `ẋ` copied, `ẍ = A₂₁x + A₂₂ẋ`
/// from the rows of `A_σ`'s lower half, the dissipated power `−Σ m_i ẋ_i (A₂₂ẋ)_i`.
fn linear_small<const ND: usize>(rows: &[f64], masses: &[f64], y: &[f64], dy: &mut [f64]) {
    let mut x = [0.0; ND];
    let mut v = [0.0; ND];
    x.copy_from_slice(&y[..ND]);
    v.copy_from_slice(&y[ND..2 * ND]);
    let mut power = 0.0;
    for (i, row) in rows.chunks_exact(2 * ND).take(ND).enumerate() {
        let (mut ax, mut damp) = (0.0, 0.0);
        for j in 0..ND {
            ax += row[j] * x[j];
            damp += row[ND + j] * v[j];
        }
        dy[i] = v[i];
        dy[ND + i] = ax + damp;
        power -= masses[i] * v[i] * damp;
    }
    dy[2 * ND] = power;
}

fn elastic(law: &ContactLaw, d: f64) -> f64 {
    match *law {
        ContactLaw::Linear { stiffness, .. } => stiffness * d,
        _ => law.force(d, 0.0),
    }
}

/// Dense output of one step: `y(θ) = r1 + θ(r2 + θ₁(r3 + θ(r4 + θ₁ r5)))`, θ = s/h, θ₁ = 1 − θ
/// (Hairer, Nørsett & Wanner's `contd5`): a quartic in θ that matches `y`, `y_new` and the
/// slopes `f(y)`, `f(y_new)` at the ends of the step.
pub(crate) struct Dense {
    r: [Vec<f64>; 5],
    h: f64,
}

impl Dense {
    /// An empty dense output for states of `n` components.
    pub(crate) fn new(n: usize) -> Self {
        Self {
            r: std::array::from_fn(|_| vec![0.0; n]),
            h: 0.0,
        }
    }

    /// The dense output of the accepted step of size `h` from `y` to `ynew` with the stages
    /// `k` (Hairer, Nørsett & Wanner's `contd5`).
    pub(crate) fn fill(&mut self, h: f64, y: &[f64], ynew: &[f64], k: &[Vec<f64>; 7]) {
        for i in 0..y.len() {
            let ydiff = ynew[i] - y[i];
            let bspl = h * k[0][i] - ydiff;
            self.r[0][i] = y[i];
            self.r[1][i] = ydiff;
            self.r[2][i] = bspl;
            self.r[3][i] = ydiff - h * k[6][i] - bspl;
            self.r[4][i] = h
                * (D1 * k[0][i]
                    + D3 * k[2][i]
                    + D4 * k[3][i]
                    + D5 * k[4][i]
                    + D6 * k[5][i]
                    + D7 * k[6][i]);
        }
        self.h = h;
    }

    /// The step's size.
    pub(crate) fn h(&self) -> f64 {
        self.h
    }

    pub(crate) fn eval(&self, s: f64, out: &mut [f64]) {
        let th = s / self.h;
        let th1 = 1.0 - th;
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.r[0][i]
                + th * (self.r[1][i]
                    + th1 * (self.r[2][i] + th * (self.r[3][i] + th1 * self.r[4][i])));
        }
    }

    /// The state `y(s)` and its time derivative `ẏ(s)` (the derivative of the quartic).
    pub(crate) fn eval_with_slope(&self, s: f64, out: &mut [f64], slope: &mut [f64]) {
        let th = s / self.h;
        let th1 = 1.0 - th;
        for (i, (o, d)) in out.iter_mut().zip(slope.iter_mut()).enumerate() {
            let (v, dv) = self.component(i, th, th1);
            *o = v;
            *d = dv;
        }
    }

    /// Component `i` and its derivative with respect to time at `θ`.
    #[inline]
    fn component(&self, i: usize, th: f64, th1: f64) -> (f64, f64) {
        let (r1, r2, r3, r4, r5) = (
            self.r[0][i],
            self.r[1][i],
            self.r[2][i],
            self.r[3][i],
            self.r[4][i],
        );
        let q = r4 + th1 * r5;
        let rr = r3 + th * q;
        let ss = r2 + th1 * rr;
        let drr = q - th * r5;
        let dss = -rr + th1 * drr;
        (r1 + th * ss, (ss + th * dss) / self.h)
    }

    /// `ℓᵀy(s)` and its time derivative, `ℓ` given by its non-zeros.
    pub(crate) fn functional(&self, l: &SparseVec, s: f64) -> (f64, f64) {
        let th = s / self.h;
        let th1 = 1.0 - th;
        let (idx, val) = l.parts();
        let (mut v, mut d) = (0.0, 0.0);
        for (&i, &li) in idx.iter().zip(val) {
            let (a, b) = self.component(i, th, th1);
            v += li * a;
            d += li * b;
        }
        (v, d)
    }
}

/// An indicator as the affine function of the state that it is: `g = ℓᵀX + c`. Overlaps,
/// the dashpot velocity and the force-sign functions of the linear and Hertz laws are linear
/// (`c = 0`); Hunt-Crossley's is `1 + 3/2 α δ̇` (`c = 1`).
struct Affine {
    ind: Indicator,
    l: SparseVec,
    c: f64,
    /// `‖ℓ‖` over the positions and over the velocities.
    norm_x: f64,
    norm_v: f64,
}

impl Affine {
    fn new(sys: &ImpactSystem, ind: Indicator) -> Self {
        let l = sys.indicator_vector(ind);
        let c = sys.indicator_value(ind, &vec![0.0; l.len()]);
        let nd = l.len() / 2;
        Affine {
            ind,
            norm_x: norm2(&l[..nd]),
            norm_v: norm2(&l[nd..]),
            l: SparseVec::new(&l),
            c,
        }
    }

    #[inline]
    fn value(&self, x: &[f64]) -> f64 {
        self.l.dot(x) + self.c
    }

    /// The band around zero within which the value at the state `X = [x; ẋ]` (with norms
    /// `(‖x‖, ‖ẋ‖)`) is taken as zero: `rel (Σ|ℓ_i X_i| + |c|)` with `rel` the larger of
    /// `64 ε` (round-off) and a tenth of the run's `rtol` (the integration's own accuracy: an
    /// overlap of 1e-12 m between bodies 3 mm from their start that separate at 1e-8 m/s is
    /// zero to the run), and at least `1e-12 (‖ℓ_x‖ ‖x‖ + ‖ℓ_v‖ ‖ẋ‖)` (a quantity whose terms
    /// are all physically zero, such as the relative velocity of bodies at rest, carries
    /// round-off only), as the lexicographic signs of [`super::switching`] do, unit by unit.
    fn noise(&self, x: &[f64], norms: (f64, f64), rel: f64) -> f64 {
        (rel * self.scale(x)).max(1e-12 * (self.norm_x * norms.0 + self.norm_v * norms.1))
    }

    /// `Σ|ℓ_i X_i| + |c|`: the size of the terms the value is made of.
    #[inline]
    fn scale(&self, x: &[f64]) -> f64 {
        self.l.dot_abs(x).1 + self.c.abs()
    }
}

/// Highest derivative order the mode selection consults (as [`super::switching`]).
const K_MAX: usize = 8;

/// The side of an indicator that `mode` implies: `+1` for a closed contact's overlap and
/// force, `−1` for an open one's; `−1` for the dashpot velocity while the dashpot acts.
fn mode_side(ind: Indicator, mode: Mode) -> f64 {
    match ind {
        Indicator::Overlap(s) | Indicator::Force(s) => {
            if mode.on(s) {
                1.0
            } else {
                -1.0
            }
        }
        Indicator::DashpotVelocity => {
            if mode.on(Switch::Dashpot) {
                -1.0
            } else {
                1.0
            }
        }
    }
}

/// True for an indicator of a contact that `mode` holds ([`Mode::held`]): its overlap is
/// frozen and positive and its force is the multiplier, so it is on the closed side and is not
/// searched; the hold ends by [`HeldForce`] instead.
fn of_held(ind: Indicator, mode: Mode) -> bool {
    match ind {
        Indicator::Overlap(s) | Indicator::Force(s) => mode.held(s),
        Indicator::DashpotVelocity => false,
    }
}

/// The indicators' sides at a restart point (the start of the run or a switch).
struct Sides {
    /// `+1` or `−1`: the side each indicator is on just after the point under the selected
    /// mode (a provisional one carries the side its mode implies).
    signs: Vec<f64>,
    /// True for an indicator that is zero with all its derivatives up to [`K_MAX`]
    /// (Hertz-type laws at zero overlap grow with fractional powers of time): its side is
    /// settled by the motion itself, at the end of the next step.
    provisional: Vec<bool>,
    /// [`Affine::noise`] at the point: the crossing search lifts `g` by it.
    noise: Vec<f64>,
    /// Signs imposed at this point (`0` for none): provisional indicators found on the other
    /// side after a step.
    forced: Vec<f64>,
}

/// Mode selection for any contact law: the mode `σ` at a state `X` is consistent when each
/// indicator moves, under `σ`'s dynamics, to the side that implies `σ`. An indicator's side is
/// the sign of its value where that is beyond round-off ([`Affine::noise`]); at zero it is the
/// sign of its first non-vanishing time derivative `g⁽ᵏ⁾ = ℓᵀ y_k` with `y_1 = f_σ(X)` and
/// `y_{k+1} = J_σ(X) y_k` ([`Rhs::jvp`]): exact for linear laws (`J_σ = A_σ`, the lexicographic
/// signs of [`super::switching`]) and for `k ≤ 2` with any law; beyond that a non-linear law
/// enters by its local linearisation. Candidate modes are iterated to a fixed point.
struct Selector<'a> {
    sys: &'a ImpactSystem,
    /// The relative width of the zero band ([`Affine::noise`]).
    rel: f64,
    inds: Vec<Affine>,
    /// The largest [`Affine::scale`] of each indicator over the run so far (at the start and
    /// at the end of every accepted step): the run's own size of that quantity.
    run_scale: Vec<f64>,
    /// Derivative vectors (length `ny`) and the state padded to `ny`.
    work: [Vec<f64>; 2],
    pad: Vec<f64>,
}

fn norm2(v: &[f64]) -> f64 {
    v.iter().map(|a| a * a).sum::<f64>().sqrt()
}

/// `(‖x‖, ‖ẋ‖)` of a state `X = [x; ẋ]` (length `2·dofs`).
fn norms(x: &[f64]) -> (f64, f64) {
    let nd = x.len() / 2;
    (norm2(&x[..nd]), norm2(&x[nd..]))
}

impl<'a> Selector<'a> {
    fn new(sys: &'a ImpactSystem, ny: usize, rtol: f64) -> Self {
        let inds: Vec<Affine> = sys
            .indicators()
            .into_iter()
            .map(|i| Affine::new(sys, i))
            .collect();
        Selector {
            sys,
            rel: (64.0 * f64::EPSILON).max(0.1 * rtol),
            run_scale: vec![0.0; inds.len()],
            inds,
            work: [vec![0.0; ny], vec![0.0; ny]],
            pad: vec![0.0; ny],
        }
    }

    /// Takes the state `x` into the run's scales ([`Selector::run_scale`]).
    fn observe(&mut self, x: &[f64]) {
        for (a, r) in self.inds.iter().zip(self.run_scale.iter_mut()) {
            *r = r.max(a.scale(x));
        }
    }

    /// The zero band of indicator `i` at `x`: [`Affine::noise`], and at least `rel` times the
    /// run's scale of the indicator. The second term is what the integration can resolve: a
    /// one-way dashpot's velocity of 1e-12 m/s in a run struck at 1 m/s, or an overlap of
    /// 1e-13 m in a run that moved millimetres, is below the accuracy `rtol` asks for. Without
    /// it, a machine at rest under a constant force carries an oscillation of that size that
    /// the integration's own error keeps alive (the exact solution decays it), and switches
    /// the dashpot every half period of the contact (every 16 µs on the stiff-base machine)
    /// for ever. With it, a crossing must leave the band on the other side: a switch is a
    /// motion the run resolves.
    fn band(&self, i: usize, x: &[f64], x_norms: (f64, f64)) -> f64 {
        let a = &self.inds[i];
        let noise = a.noise(x, x_norms, self.rel);
        match a.ind {
            Indicator::DashpotVelocity => noise.max(self.rel * self.run_scale[i]),
            _ => noise,
        }
    }

    /// The signs of the indicators just after `x` (positions and velocities) under `mode`'s
    /// dynamics into `sides.signs` (`0` where undecided to order [`K_MAX`]), their noise into
    /// `sides.noise`; forced signs are taken as they are.
    fn signs(&mut self, rhs: &Rhs<'_>, mode: Mode, x: &[f64], sides: &mut Sides) {
        let nx = x.len();
        let x_norms = norms(x);
        let mut open = 0;
        for i in 0..self.inds.len() {
            sides.noise[i] = self.band(i, x, x_norms);
            let a = &self.inds[i];
            sides.signs[i] = if of_held(a.ind, mode) {
                1.0
            } else if sides.forced[i] != 0.0 {
                sides.forced[i]
            } else {
                let g = a.value(x);
                if g.abs() > sides.noise[i] {
                    g.signum()
                } else {
                    open += 1;
                    0.0
                }
            };
        }
        if open == 0 {
            return;
        }
        self.pad[..nx].copy_from_slice(x);
        self.pad[nx] = 0.0;
        rhs.eval(mode, &self.pad, &mut self.work[0]);
        for k in 1..=K_MAX {
            let y = &self.work[0][..nx];
            let y_norm = norms(y);
            for (a, o) in self.inds.iter().zip(sides.signs.iter_mut()) {
                if *o != 0.0 {
                    continue;
                }
                let (val, scale) = a.l.dot_abs(y);
                let floor = 1e-12 * (a.norm_x * y_norm.0 + a.norm_v * y_norm.1);
                if val.abs() > 1e-11 * scale && val.abs() > floor {
                    *o = val.signum();
                    open -= 1;
                }
            }
            if open == 0 || k == K_MAX {
                break;
            }
            let (w0, w1) = self.work.split_at_mut(1);
            rhs.jvp(mode, x, &w0[0], &mut w1[0]);
            self.work.swap(0, 1);
        }
    }

    /// The mode the signs imply (an undecided indicator leaves its contact open and its
    /// dashpot off, [`implied_mode`]).
    fn implied(&self, signs: &[f64]) -> Mode {
        let sign_of = |ind: Indicator| {
            self.inds
                .iter()
                .position(|a| a.ind == ind)
                .map_or(0.0, |p| signs[p])
        };
        implied_mode(self.sys, &sign_of)
    }

    /// Selects a consistent mode at `x` starting from `start`, and the sides of the
    /// indicators under it. Without a consistent mode the last candidate is taken (the search
    /// then finds the switch at once, and the progress guard of [`solve_from`] stops a loop).
    ///
    /// The contacts `start` holds stay held (their indicators are on the closed side,
    /// [`of_held`]); only the other switches are selected.
    fn select(&mut self, rhs: &Rhs<'_>, x: &[f64], start: Mode, sides: &mut Sides) -> Mode {
        let keep = |m: Mode| {
            let mut m = m;
            for s in [Switch::SliderBed, Switch::BedDamper] {
                if start.held(s) {
                    m = m.holding(s, true);
                }
            }
            m
        };
        let mut cand = start;
        let mut seen = 0u32;
        let mut found = None;
        for _ in 0..16 {
            self.signs(rhs, cand, x, sides);
            let next = keep(self.implied(&sides.signs));
            if next == cand {
                found = Some(cand);
                break;
            }
            if seen & (1 << (next.0 & 7)) != 0 {
                break;
            }
            seen |= 1 << (cand.0 & 7);
            cand = next;
        }
        let mode = match found {
            Some(m) => m,
            None => {
                let allowed = self
                    .sys
                    .switches()
                    .iter()
                    .fold(0u8, |a, &s| a | Mode::bit(s));
                let mut pick = None;
                for bits in 0..8u8 {
                    let m = keep(Mode(bits));
                    if Mode(bits).0 & !allowed == 0 {
                        self.signs(rhs, m, x, sides);
                        if keep(self.implied(&sides.signs)) == m {
                            pick = Some(m);
                            break;
                        }
                    }
                }
                pick.unwrap_or_else(|| {
                    self.signs(rhs, cand, x, sides);
                    cand
                })
            }
        };
        for (i, a) in self.inds.iter().enumerate() {
            sides.provisional[i] = sides.signs[i] == 0.0;
            if sides.provisional[i] {
                sides.signs[i] = mode_side(a.ind, mode);
            }
        }
        mode
    }
}

/// An indicator on the dense output of a step, lifted by its noise so that a start within
/// round-off of zero is on the side the selection gave it.
struct OnStep<'a> {
    dense: &'a Dense,
    ind: &'a Affine,
    noise: f64,
}

impl Scalar for OnStep<'_> {
    fn value_slope(&self, s: f64) -> (f64, f64) {
        let (v, d) = self.dense.functional(&self.ind.l, s);
        (v + self.ind.c, d)
    }
    fn curvature_bound(&self, _a: f64, _b: f64) -> f64 {
        f64::INFINITY
    }
    /// Eight steps: the search's grid step is then the whole step (values and slopes at both
    /// ends, a cubic Hermite test for a dip in between, halving only where it dips). The step
    /// is far shorter than the motion's periods, as the error control makes it.
    fn fastest_period(&self) -> f64 {
        8.0 * self.dense.h
    }
    fn noise(&self) -> f64 {
        self.noise
    }
}

/// The response channels ([`Channel`]) along the dense output, as `c = V_σᵀX + N_σ(X)`:
/// `V_σ` the channel's vector ([`ChannelMap::vectors`]) in `σ` with its non-linear contacts
/// taken out, `N_σ` the forces of the closed non-linear contacts (the contact-force channels)
/// and their share `φ_Bᵀψ_b (f_bs − f_bd)` of the bed acceleration. The slope is
/// `V_σᵀẊ + ∂N/∂δ δ̇ + ∂N/∂δ̇ δ̈`.
struct Channels {
    /// Per mode, built on first use: the non-zero vectors `V_σ`.
    lin: Vec<Option<[Option<SparseVec>; N_CHANNELS]>>,
    /// `φ_Bᵀψ_b`.
    w_c: f64,
    /// The contacts' relative vectors and their laws when non-linear.
    contacts: [(Switch, SparseVec, Option<ContactLaw>); 2],
    nd: usize,
}

/// The channel index of each contact's force.
const CONTACT_CHANNEL: [usize; 2] = [4, 5];

impl Channels {
    fn new(sys: &ImpactSystem) -> Self {
        let contact = |s: Switch| {
            let present = s == Switch::SliderBed || sys.damper.is_some();
            let law = sys.contact(s).law;
            (
                s,
                SparseVec::new(if present { sys.relative_vector(s) } else { &[] }),
                (present && !law.is_linear()).then_some(law),
            )
        };
        debug_assert_eq!(
            CONTACT_CHANNEL,
            [
                Channel::ContactSliderBed.index(),
                Channel::ContactBedDamper.index()
            ]
        );
        Channels {
            lin: vec![None; 32],
            w_c: dot(&sys.points.measurement, &sys.points.bed_contact),
            contacts: [contact(Switch::SliderBed), contact(Switch::BedDamper)],
            nd: sys.dofs(),
        }
    }

    /// True when `mode` closes a contact with a non-linear law or holds a contact.
    fn nonlinear(&self, mode: Mode) -> bool {
        mode.any_held()
            || self
                .contacts
                .iter()
                .any(|(s, _, law)| law.is_some() && mode.on(*s))
    }

    /// Is contact `ci` of `mode` a non-linear part of the channels (a non-linear law closed,
    /// or held: its force is the multiplier)?
    fn contact_nonlinear(&self, mode: Mode, ci: usize) -> bool {
        let (s, _, law) = &self.contacts[ci];
        mode.on(*s) && (law.is_some() || mode.held(*s))
    }

    /// Builds `mode`'s vectors.
    fn prepare(&mut self, sys: &ImpactSystem, map: &ChannelMap, mode: Mode) {
        let k = usize::from(mode.0 & 31);
        if self.lin[k].is_some() {
            return;
        }
        let mut m = mode.free();
        for (s, _, law) in &self.contacts {
            if law.is_some() {
                m = m.with(*s, false);
            }
        }
        let vecs = map.vectors(sys, m);
        self.lin[k] = Some(std::array::from_fn(|c| {
            vecs.as_ref()
                .map(|v| SparseVec::new(&v[c]))
                .filter(|v| !v.parts().0.is_empty())
        }));
    }

    fn vectors(&self, mode: Mode) -> &[Option<SparseVec>; N_CHANNELS] {
        const NONE: [Option<SparseVec>; N_CHANNELS] =
            [None, None, None, None, None, None, None, None];
        self.lin[usize::from(mode.0 & 31)].as_ref().unwrap_or(&NONE)
    }

    /// Does channel `c` have a non-linear part in `mode`?
    fn has_nonlinear(&self, mode: Mode, c: usize) -> bool {
        (c == Channel::BedAcceleration.index() || CONTACT_CHANNEL.contains(&c))
            && (0..2).any(|ci| {
                self.contact_nonlinear(mode, ci)
                    && (c == CONTACT_CHANNEL[ci] || c == Channel::BedAcceleration.index())
            })
    }

    /// All channels' values and slopes at the state `x` with derivative `xd` in `mode`
    /// (prepared). A held contact's force is its multiplier `λ`, its slope `λ̇`
    /// ([`Rhs::held_forces`]).
    fn at(
        &self,
        rhs: &Rhs<'_>,
        mode: Mode,
        x: &[f64],
        xd: &[f64],
        v: &mut [f64; N_CHANNELS],
        d: &mut [f64; N_CHANNELS],
    ) {
        let nd = self.nd;
        for (c, l) in self.vectors(mode).iter().enumerate() {
            (v[c], d[c]) = match l {
                Some(l) => (l.dot(x), l.dot(xd)),
                None => (0.0, 0.0),
            };
        }
        let held = if mode.any_held() {
            rhs.held_forces(mode, x, xd)
        } else {
            ([0.0; 2], [0.0; 2])
        };
        for (ci, (s, a, law)) in self.contacts.iter().enumerate() {
            if !self.contact_nonlinear(mode, ci) {
                continue;
            }
            let (f, fdot) = match law {
                _ if mode.held(*s) => (held.0[ci], held.1[ci]),
                Some(law) => {
                    let (del, rate) = a.dots(&x[..nd], &x[nd..2 * nd]);
                    let (_, acc) = a.dots(&xd[..nd], &xd[nd..2 * nd]);
                    let (fd, fr) = law.partials(del, rate);
                    (law.force(del, rate), fd * rate + fr * acc)
                }
                None => continue,
            };
            let sign = if ci == 0 { 1.0 } else { -1.0 };
            let cc = CONTACT_CHANNEL[ci];
            v[cc] += f;
            d[cc] += fdot;
            let ab = Channel::BedAcceleration.index();
            v[ab] += sign * self.w_c * f;
            d[ab] += sign * self.w_c * fdot;
        }
    }

    /// Channel `c`'s value and slope at `s` on the dense output (`buf`, `bufd`: scratch of
    /// length `ny`).
    #[allow(clippy::too_many_arguments)]
    fn on_dense(
        &self,
        rhs: &Rhs<'_>,
        mode: Mode,
        c: usize,
        dense: &Dense,
        s: f64,
        buf: &mut [f64],
        bufd: &mut [f64],
    ) -> (f64, f64) {
        if !self.has_nonlinear(mode, c) {
            return match &self.vectors(mode)[c] {
                Some(l) => dense.functional(l, s),
                None => (0.0, 0.0),
            };
        }
        dense.eval_with_slope(s, buf, bufd);
        let (mut v, mut d) = ([0.0; N_CHANNELS], [0.0; N_CHANNELS]);
        self.at(rhs, mode, buf, bufd, &mut v, &mut d);
        (v[c], d[c])
    }
}

/// The extremes of every channel on `[0, len]` of a step (in `mode`, starting at time `t`),
/// offered to `peaks`: the end value (the start was offered as the previous end), and each
/// interior extremum where the slope changes sign. Values and slopes at the ends (`v0`, `d0`,
/// `v1`, `d1`) come from the states and stages; only where the slopes differ in sign, or the
/// cubic Hermite interpolant of the ends has critical points inside (then the slope is
/// sampled between them), is the slope's root located on the dense output (Illinois
/// regula falsi to `1e-12` of the step): a step without an interior extremum costs the end
/// values only.
#[allow(clippy::too_many_arguments)]
fn step_extremes(
    ch: &Channels,
    rhs: &Rhs<'_>,
    mode: Mode,
    dense: &Dense,
    t: f64,
    len: f64,
    ends: (
        &[f64; N_CHANNELS],
        &[f64; N_CHANNELS],
        &[f64; N_CHANNELS],
        &[f64; N_CHANNELS],
    ),
    peaks: &mut Peaks,
    buf: &mut [f64],
    bufd: &mut [f64],
) {
    let (v0, d0, v1, d1) = ends;
    for c in 0..N_CHANNELS {
        extremes_on_step(
            |s| ch.on_dense(rhs, mode, c, dense, s, buf, bufd),
            (v0[c], d0[c], v1[c], d1[c]),
            t,
            len,
            &mut peaks.0[c],
        );
    }
}

/// The extremes of one channel `g` over a step of length `len` from `t` into `ext`: its end
/// value, and each interior extremum where its slope changes sign. `ends = (g(0), g'(0),
/// g(len), g'(len))`; `on(s) = (g(s), g'(s))` on the dense output. Only where the end slopes
/// differ in sign, or the cubic Hermite interpolant of the ends has critical points inside
/// (then the slope is sampled between them), is the slope's root located (Illinois regula
/// falsi to `1e-12` of the step).
pub(crate) fn extremes_on_step(
    mut on: impl FnMut(f64) -> (f64, f64),
    ends: (f64, f64, f64, f64),
    t: f64,
    len: f64,
    ext: &mut Extremes,
) {
    let (v0, d0, v1, d1) = ends;
    ext.offer(v1, t + len);
    if len <= 0.0 {
        return;
    }
    // The extremum where the slope changes sign between `a` and `b`.
    fn extremum<F: FnMut(f64) -> (f64, f64)>(
        on: &mut F,
        (a, b, da, db): (f64, f64, f64, f64),
        (t, len): (f64, f64),
        ext: &mut Extremes,
    ) {
        let s = slope_root(|s| on(s).1, a, b, da, db, 1e-12 * len);
        let (v, _) = on(s);
        ext.offer(v, t + s);
    }
    if d0 * d1 < 0.0 {
        extremum(&mut on, (0.0, len, d0, d1), (t, len), ext);
        return;
    }
    // Critical points of the Hermite cubic through the ends (u ∈ (0, 1)): the slope is
    // sampled between them, where the cubic's slope has the other sign.
    let crit = hermite_critical_points(v0, d0, v1, d1, len);
    if crit[0].is_nan() {
        return;
    }
    let mut knots = [0.0; 4];
    let mut nk = 1;
    for u in crit.into_iter().filter(|u| !u.is_nan()) {
        knots[nk] = u;
        nk += 1;
    }
    knots[nk] = 1.0;
    let (mut sa, mut da) = (0.0, d0);
    for k in 0..nk {
        let sm = 0.5 * (knots[k] + knots[k + 1]) * len;
        let dm = on(sm).1;
        if da * dm < 0.0 {
            extremum(&mut on, (sa, sm, da, dm), (t, len), ext);
        }
        if dm != 0.0 {
            (sa, da) = (sm, dm);
        }
    }
    if da * d1 < 0.0 {
        extremum(&mut on, (sa, len, da, d1), (t, len), ext);
    }
}

/// The critical points `u ∈ (0, 1)` (ascending, `NaN` for none) of the cubic Hermite
/// interpolant through `(0, ga, da)`, `(len, gb, db)` in `u = s/len`.
fn hermite_critical_points(ga: f64, da: f64, gb: f64, db: f64, len: f64) -> [f64; 2] {
    let c2 = 3.0 * (2.0 * ga + len * da - 2.0 * gb + len * db);
    let c1 = 2.0 * (-3.0 * ga - 2.0 * len * da + 3.0 * gb - len * db);
    let c0 = len * da;
    let mut r = [f64::NAN; 2];
    let mut roots = [f64::NAN; 2];
    if c2.abs() > 1e-300 {
        let disc = c1 * c1 - 4.0 * c2 * c0;
        if disc >= 0.0 {
            let q = -0.5 * (c1 + c1.signum() * disc.sqrt());
            roots = [q / c2, if q != 0.0 { c0 / q } else { f64::NAN }];
        }
    } else if c1.abs() > 1e-300 {
        roots[0] = -c0 / c1;
    }
    let mut k = 0;
    for u in roots {
        if u > 0.0 && u < 1.0 {
            r[k] = u;
            k += 1;
        }
    }
    if k == 2 && r[0] > r[1] {
        r.swap(0, 1);
    }
    r
}

/// A root of `f` in `[a, b]` with `f(a) = fa`, `f(b) = fb` of opposite signs, by the Illinois
/// variant of regula falsi, to `tol`.
fn slope_root(
    mut f: impl FnMut(f64) -> f64,
    mut a: f64,
    mut b: f64,
    mut fa: f64,
    mut fb: f64,
    tol: f64,
) -> f64 {
    let mut side = 0;
    for _ in 0..100 {
        if b - a <= tol {
            break;
        }
        let mut m = (a * fb - b * fa) / (fb - fa);
        if !(m > a && m < b) {
            m = 0.5 * (a + b);
        }
        let fm = f(m);
        if fm == 0.0 {
            return m;
        }
        if (fm > 0.0) == (fa > 0.0) {
            a = m;
            fa = fm;
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        } else {
            b = m;
            fb = fm;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        }
    }
    if fa.abs() < fb.abs() {
        a
    } else {
        b
    }
}

/// Consecutive rejected steps, or switches that do not advance time, before a run gives up.
const MAX_STALLED: usize = 1000;

/// Steps (accepted and rejected) a run may take: 60 s of the paper's machines take 2e5 to 3e5;
/// a contact so stiff that the explicit method's stability limit needs more gives up with an
/// error instead of running for hours.
const MAX_STEPS: usize = 100_000_000;

/// Steps in one window of the pace check ([`Pace`]).
const PACE_WINDOW: usize = 1 << 20;
/// Consecutive windows whose pace projects beyond [`MAX_STEPS`] before the run stops.
const PACE_STRIKES: u32 = 4;

/// The run's pace, checked every [`PACE_WINDOW`] steps: the steps the rest of the run would
/// take at the rate of the last window. A run that would exceed [`MAX_STEPS`] at that rate
/// for [`PACE_STRIKES`] windows in a row (about four million steps, a few seconds) stops
/// then with the projection, instead of after 10⁸ steps: an explicit method's step on a
/// closed stiff contact is bounded by its stability (`h ≲ 3.3/ω`), so a body resting on a
/// 1 MHz contact for a minute needs about 10⁸ steps however smooth the motion is.
struct Pace {
    next_check: usize,
    window_start: (usize, f64),
    strikes: u32,
}

impl Pace {
    fn new() -> Self {
        Pace {
            next_check: PACE_WINDOW,
            window_start: (0, 0.0),
            strikes: 0,
        }
    }

    fn check(&mut self, n: usize, t: f64, t_end: f64, mode: Mode) -> Result<()> {
        let (n0, t0) = self.window_start;
        let mean_h = (t - t0) / (n - n0) as f64;
        let projected = n as f64 + (t_end - t) / mean_h.max(f64::MIN_POSITIVE);
        self.window_start = (n, t);
        self.next_check = n + PACE_WINDOW;
        if projected <= MAX_STEPS as f64 {
            self.strikes = 0;
            return Ok(());
        }
        self.strikes += 1;
        if self.strikes < PACE_STRIKES {
            return Ok(());
        }
        let closed: Vec<&str> = [
            (Switch::SliderBed, "slider-bed"),
            (Switch::BedDamper, "bed-damper"),
        ]
        .into_iter()
        .filter(|(s, _)| mode.on(*s))
        .map(|(_, name)| name)
        .collect();
        Err(Error::numerical(
            "dopri5",
            format!(
                "the run would take about {projected:.2e} steps, more than the limit of \
                 {MAX_STEPS:.0e}: at t = {t:.6} s of {t_end} s its last {PACE_WINDOW} steps \
                 averaged {mean_h:.3e} s (closed contacts: {}). An explicit method's step on a \
                 closed stiff contact is bounded by stability (h ≲ 3.3/ω; a step of that size \
                 is the limit for ω ≈ {:.3e} rad/s), however smooth the motion. Use \
                 method = \"exact\" (every contact law linear), a shorter simulation.duration, \
                 or a softer contact stiffness",
                if closed.is_empty() {
                    "none".to_string()
                } else {
                    closed.join(", ")
                },
                3.3 / mean_h
            ),
        ))
    }
}

/// Consecutive accepted steps a closed contact must qualify before it is held ([`Holder`]).
const HOLD_STEPS: u32 = 16;

/// The persistent ("held") contact of `dopri5`: when a closed contact rests, its gap is
/// kept constant and its force becomes the constraint's multiplier `λ`
/// ([`ImpactSystem::held_forces`]), so that the contact's frequency, which only the
/// explicit method's stability still resolves, drops out of the step size.
///
/// **Entry.** A closed, not yet held contact `c` qualifies at the end of an accepted step of
/// size `h` when (1) its own oscillation about its quasi-static state is within its zero
/// band: `w = √((δ̇_c − λ̇_c/k_c)² + ((f_c − λ_c) ω_c/k_c)²) ≤ (rtol/10)·V_c`, with `λ_c`,
/// `λ̇_c` the force the contact would carry if held and its rate, `k_c = ∂f_c/∂δ`, and `V_c`
/// the largest `Σ|a_i ẋ_i|` of the run so far (as the dashpot's band): the bodies move
/// together, up to the contact's quasi-static compression rate `λ̇_c/k_c`, (2) the step is
/// stability-limited by the contact, `h·ω_c ≥ 1` with `ω_c² = (∂f_c/∂δ)·a_cᵀM⁻¹a_c` (a step
/// that resolved the contact's motion to the tolerance would be far shorter, `h·ω_c ≈ 0.1`),
/// and (3) the contact is loaded quasi-statically: its law's force `f_c(δ, δ̇) > 0` and the
/// multiplier it would carry if held matches it, `|λ_c − f_c| ≤ f_c/2`. After [`HOLD_STEPS`]
/// consecutive qualifying steps (each at least `1/ω_c` long, several contact periods in
/// all) the contact is held. The velocities are projected (mass-weighted) so that no held gap
/// moves, `ẋ ← ẋ − M⁻¹A G⁻¹Aᵀẋ`: a plastic impulse that stops the relative velocity
/// `δ̇_c ≈ λ̇_c/k_c` (the quasi-static compression rate, which the rigid constraint drops);
/// the kinetic energy it takes, `½ δ̇ᵀG⁻¹δ̇`, is counted as dissipated.
///
/// **Release** is an event located on the dense output like the other switches: `λ_c`
/// crossing `−(rtol/10)·λ_c,entry` (the force would pull). The contact then continues as a
/// compliant closed contact from its frozen gap (the law's force at that gap pushes the
/// bodies apart, and the contact opens by its own indicators within about a quarter of its
/// period). The hold does not end on a mismatch between `λ_c` and the law's force at the
/// frozen gap: that difference is the rigid-contact approximation's error, a gap error
/// `|λ_c − f_c(δ₀)|/(∂f/∂δ)` (the overlap the compliant contact would have minus the frozen
/// one) and a stored-energy error of about `δ₀·|λ_c − f_c(δ₀)|`; releasing on it would
/// restart the stiff contact oscillation it measures. Re-entry needs [`HOLD_STEPS`] new
/// qualifying steps of positive length and `λ_c ≥ f_c/2 > 0`: a release and a re-entry
/// cannot chatter at one instant.
struct Holder {
    /// `a_cᵀ M⁻¹ a_c` per contact.
    g: [f64; 2],
    /// `V_c`: the largest `Σ|a_i ẋ_i|` of the run so far.
    rate_scale: [f64; 2],
    /// Consecutive qualifying steps.
    count: [u32; 2],
    /// The release threshold's size: `(rtol/10)·λ_c` at entry.
    release_noise: [f64; 2],
    rel: f64,
}

const CONTACTS: [Switch; 2] = [Switch::SliderBed, Switch::BedDamper];

impl Holder {
    fn new(rhs: &Rhs<'_>, rel: f64) -> Self {
        let g = |a: &SparseVec| {
            let (idx, val) = a.parts();
            idx.iter()
                .zip(val)
                .map(|(&i, &v)| v * v / rhs.masses[i])
                .sum()
        };
        Holder {
            g: [g(&rhs.a_s), g(&rhs.a_d)],
            rate_scale: [0.0; 2],
            count: [0; 2],
            release_noise: [0.0; 2],
            rel,
        }
    }

    fn relative<'a>(rhs: &'a Rhs<'_>, ci: usize) -> &'a SparseVec {
        if ci == 0 {
            &rhs.a_s
        } else {
            &rhs.a_d
        }
    }

    /// After an accepted step of size `h` ending at `y` (with `f(y) = yd`) in `mode`: the mode
    /// with the contacts that now qualify ([`Holder`]) held, if any.
    fn entry(&mut self, rhs: &Rhs<'_>, mode: Mode, y: &[f64], yd: &[f64], h: f64) -> Option<Mode> {
        let nd = rhs.nd;
        let (x, v) = (&y[..nd], &y[nd..2 * nd]);
        let mut enter = mode;
        for (ci, s) in CONTACTS.into_iter().enumerate() {
            if ci == 1 && rhs.sys.damper.is_none() {
                continue;
            }
            let a = Self::relative(rhs, ci);
            let speed = a.dot_abs(v).1;
            self.rate_scale[ci] = self.rate_scale[ci].max(speed);
            if !mode.on(s) || mode.held(s) {
                self.count[ci] = 0;
                continue;
            }
            let law = rhs.sys.contact(s).law;
            let (d, r) = a.dots(x, v);
            let band = (self.rel * self.rate_scale[ci]).max(1e-12 * speed);
            let f = law.force(d, r);
            let omega = (law.partials(d, r).0 * self.g[ci]).max(0.0).sqrt();
            let kc = law.partials(d, r).0;
            let mut ok = d > 0.0 && f > 0.0 && kc > 0.0 && h * omega >= 1.0;
            if ok {
                let (lam, rate) = rhs.held_forces(mode.holding(s, true), y, yd);
                let (lam, rate) = (lam[ci], rate[ci]);
                // The contact's own oscillation about its quasi-static state (`δ̇ = λ̇/k_c`,
                // `f = λ`), in velocity units.
                let w = (r - rate / kc).hypot((f - lam) * omega / kc);
                ok = w <= band && lam > 0.0 && (lam - f).abs() <= 0.5 * f;
                if ok && self.count[ci] + 1 >= HOLD_STEPS {
                    self.release_noise[ci] = self.rel * lam;
                }
            }
            self.count[ci] = if ok { self.count[ci] + 1 } else { 0 };
            if self.count[ci] >= HOLD_STEPS {
                self.count[ci] = 0;
                enter = enter.holding(s, true);
            }
        }
        (enter != mode).then_some(enter)
    }
}

/// The multiplier of held contact `ci` on the dense output of a step (its release
/// indicator, [`Holder`]).
struct HeldForce<'a, 'b> {
    rhs: &'a Rhs<'b>,
    mode: Mode,
    dense: &'a Dense,
    ci: usize,
    noise: f64,
}

impl Scalar for HeldForce<'_, '_> {
    fn value_slope(&self, s: f64) -> (f64, f64) {
        let ny = self.dense.r[0].len();
        let (mut b, mut d) = (vec![0.0; ny], vec![0.0; ny]);
        self.dense.eval_with_slope(s, &mut b, &mut d);
        let (l, r) = self.rhs.held_forces(self.mode, &b, &d);
        (l[self.ci], r[self.ci])
    }
    fn curvature_bound(&self, _a: f64, _b: f64) -> f64 {
        f64::INFINITY
    }
    fn fastest_period(&self) -> f64 {
        8.0 * self.dense.h
    }
    fn noise(&self) -> f64 {
        self.noise
    }
}

/// The kinetic energy `½ Σ m_i ẋ_i²` (J) of the velocities `v` with masses `m`.
fn kinetic(v: &[f64], m: &[f64]) -> f64 {
    0.5 * v.iter().zip(m).map(|(v, m)| m * v * v).sum::<f64>()
}

/// Runs Dormand-Prince 5(4). See the module documentation.
pub fn solve(sys: &ImpactSystem, opts: &Options, obs: &mut dyn Observer) -> Result<Solution> {
    solve_from(sys, &sys.initial_state(), opts, obs)
}

/// As [`solve`], from the state `x0 = [x; ẋ]` (length `2 · dofs`) at t = 0 instead of
/// [`ImpactSystem::initial_state`] (used to chain blows).
pub fn solve_from(
    sys: &ImpactSystem,
    x0: &[f64],
    opts: &Options,
    obs: &mut dyn Observer,
) -> Result<Solution> {
    if !(opts.rtol > 0.0 && opts.rtol < 1.0 && opts.atol > 0.0) {
        return Err(Error::invalid(
            "simulation.rtol/atol",
            format!(
                "need 0 < rtol < 1 and atol > 0 (got rtol {}, atol {})",
                opts.rtol, opts.atol
            ),
        ));
    }
    let mut run = Run::new(sys, x0, opts);
    run.first_sample(obs);
    loop {
        if run.need_k1 {
            run.restart();
        }
        if run.t >= run.t_end * (1.0 - 1e-15) {
            break;
        }
        run.guard()?;
        run.stages();
        let err = run.err_norm();
        let expo1 = 0.2 - 0.04 * 0.75;
        let fac11 = err.powf(expo1);
        if err > 1.0 || !err.is_finite() {
            run.reject(err, fac11)?;
            continue;
        }
        run.stalled_rejects = 0;
        if run.settle_provisional()? {
            continue;
        }
        // Accepted: dense output, events, samples, extremes.
        run.steps += 1;
        run.dense_output();
        let (s_end, switched) = run.indicator_crossing();
        let (s_end, switched, release) = run.held_release(s_end, switched);
        run.samples(s_end, obs);
        run.book_step(s_end, switched);
        if switched {
            if run.switch_at(s_end, release)? && opts.stop_at_collision_end {
                break;
            }
            // Keep the step size (the new mode may be as stiff).
            continue;
        }
        run.advance();
        run.control(err, fac11);
        run.hold()?;
    }
    Ok(run.finish())
}

/// The error scale `atol + rtol · max(|a|, |b|)` of a component with values `a`, `b` at the
/// step's ends.
pub(crate) fn scale(opts: &Options, a: f64, b: f64) -> f64 {
    opts.atol + opts.rtol * a.abs().max(b.abs())
}

/// The error of a run that makes no progress at `t` in `mode` (`what` says how).
fn stalled(opts: &Options, what: &str, t: f64, mode: Mode) -> Error {
    Error::numerical(
        "dopri5",
        format!(
            "no progress at t = {t:.9e} s ({what}, mode: slider-bed {}, bed-damper {}, \
             dashpot {}). Likely cause: a contact stiffness too high for the tolerance \
             (rtol {:e}, atol {:e}) or contacts that chatter",
            if mode.on(Switch::SliderBed) {
                "closed"
            } else {
                "open"
            },
            if mode.on(Switch::BedDamper) {
                "closed"
            } else {
                "open"
            },
            if mode.on(Switch::Dashpot) {
                "on"
            } else {
                "off"
            },
            opts.rtol,
            opts.atol
        ),
    )
}

/// The state of a run between steps ([`solve_from`]).
struct Run<'s, 'o> {
    sys: &'s ImpactSystem,
    opts: &'o Options,
    rhs: Rhs<'s>,
    nd: usize,
    nx: usize,
    all_linear: bool,
    /// The first-order matrices of linear modes (the right-hand side's rows).
    matrices: ModeSelector<'s>,
    selector: Selector<'s>,
    sides: Sides,
    map: ChannelMap,
    channels: Channels,
    /// The state `[x; ẋ; dissipated energy]` at `t`, and the mode.
    y: Vec<f64>,
    t: f64,
    t_end: f64,
    mode: Mode,
    grid: Option<Grid>,
    /// The stages (`k[0] = f(y)`, `k[6] = f(y_new)`), the stage state (then the error
    /// estimate), the step's end state and its dense output.
    k: [Vec<f64>; 7],
    ytmp: Vec<f64>,
    ynew: Vec<f64>,
    dense: Dense,
    /// The state and its derivative at the end of the step (cut at a switch); scratch.
    ybuf: Vec<f64>,
    ydot: Vec<f64>,
    buf: Vec<f64>,
    bufd: Vec<f64>,
    events: Vec<Event>,
    path: Vec<PathPoint>,
    totals: Totals,
    collision_end: Option<CollisionEnd>,
    steps: usize,
    rejected: usize,
    /// Consecutive rejected steps and switches without progress (the guards).
    stalled_rejects: usize,
    stalled_switches: usize,
    /// Channel values and slopes at the start and the end of the step.
    cv0: [f64; N_CHANNELS],
    cd0: [f64; N_CHANNELS],
    cv1: [f64; N_CHANNELS],
    cd1: [f64; N_CHANNELS],
    pace: Pace,
    holder: Holder,
    /// The step size, the last accepted error (PI control), whether the next step needs
    /// `f(y)` anew (after a switch), and whether the last step was rejected.
    h: f64,
    facold: f64,
    need_k1: bool,
    last_reject: bool,
    /// The size of the last accepted step.
    h_step: f64,
}

impl<'s, 'o> Run<'s, 'o> {
    /// The initial state, its mode and the channels' values there, and the workspaces.
    fn new(sys: &'s ImpactSystem, x0: &[f64], opts: &'o Options) -> Self {
        let rhs = Rhs::new(sys);
        let nd = sys.dofs();
        let nx = 2 * nd;
        let ny = nx + 1;
        let all_linear = rhs.linear_rows.is_some();
        let matrices = ModeSelector::new(sys);
        let mut selector = Selector::new(sys, ny, opts.rtol);
        let m = selector.inds.len();
        let mut sides = Sides {
            signs: vec![0.0; m],
            provisional: vec![false; m],
            noise: vec![0.0; m],
            forced: vec![0.0; m],
        };
        let map = ChannelMap::new(sys);
        let channels = Channels::new(sys);
        let mut y = vec![0.0; ny];
        y[..nx].copy_from_slice(x0);
        selector.observe(&y[..nx]);
        let mode = selector.select(&rhs, &y[..nx], Mode(0), &mut sides);
        let grid = Grid::new(opts);
        let path = vec![PathPoint {
            t: 0.0,
            mode,
            x: y[..nx].to_vec(),
        }];
        let mut totals = Totals::default();
        totals
            .peaks
            .offer_all(&map.values(sys, mode, &y[..nx]), 0.0);
        let holder = Holder::new(&rhs, selector.rel);
        Run {
            sys,
            opts,
            rhs,
            nd,
            nx,
            all_linear,
            matrices,
            selector,
            sides,
            map,
            channels,
            y,
            t: 0.0,
            t_end: opts.duration,
            mode,
            grid,
            k: std::array::from_fn(|_| vec![0.0; ny]),
            ytmp: vec![0.0; ny],
            ynew: vec![0.0; ny],
            dense: Dense {
                r: std::array::from_fn(|_| vec![0.0; ny]),
                h: 1.0,
            },
            ybuf: vec![0.0; ny],
            ydot: vec![0.0; ny],
            buf: vec![0.0; ny],
            bufd: vec![0.0; ny],
            events: Vec::new(),
            path,
            totals,
            collision_end: None,
            steps: 0,
            rejected: 0,
            stalled_rejects: 0,
            stalled_switches: 0,
            cv0: [0.0; N_CHANNELS],
            cd0: [0.0; N_CHANNELS],
            cv1: [0.0; N_CHANNELS],
            cd1: [0.0; N_CHANNELS],
            pace: Pace::new(),
            holder,
            h: 0.0,
            facold: 1e-4,
            need_k1: true,
            last_reject: false,
            h_step: 0.0,
        }
    }

    /// The sample at t = 0 (with a phase φ > 0 the first sample, at φ, comes from the steps).
    fn first_sample(&mut self, obs: &mut dyn Observer) {
        if let Some(g) = self.grid.as_mut().filter(|g| g.phase == 0.0) {
            obs.sample(0.0, &self.y[..self.nx], self.mode);
            g.next = 1;
        }
    }

    /// A (re)start in the current mode: its right-hand side's rows (linear laws), its channels,
    /// `k[0] = f(y)` and the channels' values and slopes there, and the first step size.
    fn restart(&mut self) {
        let mode = self.mode;
        if self.all_linear && !mode.any_held() {
            // The mode's first-order matrix: its rows are the right-hand side.
            self.rhs.set_lower_rows(mode, self.matrices.matrix(mode));
        }
        self.channels.prepare(self.sys, &self.map, mode);
        self.rhs.eval(mode, &self.y, &mut self.k[0]);
        let (cv0, cd0) = (&mut self.cv0, &mut self.cd0);
        self.channels
            .at(&self.rhs, mode, &self.y, &self.k[0], cv0, cd0);
        if self.h == 0.0 {
            let opts = self.opts;
            let sc = |a: f64, b: f64| scale(opts, a, b);
            let (k0, k1) = self.k.split_at_mut(1);
            let rhs = &self.rhs;
            self.h = initial_step(
                |y, dy| rhs.eval(mode, y, dy),
                self.nx,
                &self.y,
                &k0[0],
                self.t_end - self.t,
                &mut self.ytmp,
                &mut k1[0],
                &sc,
            );
        }
        self.need_k1 = false;
    }

    /// The step size cut to the end of the run, and the guards: a step below 16 ulps of `t`,
    /// more than [`MAX_STEPS`] steps, or a pace beyond it ([`Pace`]) is an error.
    fn guard(&mut self) -> Result<()> {
        let (t, mode) = (self.t, self.mode);
        self.h = self.h.min(self.t_end - t);
        let h = self.h;
        if h.is_nan() || h <= 16.0 * f64::EPSILON * t.abs() {
            return Err(stalled(self.opts, "step size underflow", t, mode));
        }
        let n = self.steps + self.rejected;
        if n > MAX_STEPS {
            return Err(stalled(
                self.opts,
                &format!("{MAX_STEPS} steps taken, the last of {h:.3e} s"),
                t,
                mode,
            ));
        }
        if n >= self.pace.next_check {
            self.pace.check(n, t, self.t_end, mode)?;
        }
        Ok(())
    }

    /// The stages of a step of size `h`: `ynew = y + h Σ a_7j k_j`, `k[6] = f(ynew)`, and the
    /// error estimate `ytmp = h Σ e_j k_j`. Each stage state is `y + h Σ a_ij k_j`, one
    /// contiguous pass per term.
    fn stages(&mut self) {
        let (rhs, mode) = (&self.rhs, self.mode);
        stages(
            |y, dy| rhs.eval(mode, y, dy),
            self.h,
            &self.y,
            &mut self.k,
            &mut self.ytmp,
            &mut self.ynew,
        );
    }

    /// The step's error, the RMS over the state (not the dissipated energy) of the estimate
    /// `ytmp` in units of [`scale`].
    fn err_norm(&self) -> f64 {
        let (y0, y1, e) = (&self.y, &self.ynew, &self.ytmp);
        let nx = self.nx;
        let mut s = 0.0;
        for i in 0..nx {
            let r = e[i] / scale(self.opts, y0[i], y1[i]);
            s += r * r;
        }
        (s / nx as f64).sqrt()
    }

    /// A rejected step (error `err`, `fac11 = err^0.17`): the step size shrinks (by up to 5,
    /// by 10 on a non-finite error); more than [`MAX_STALLED`] rejections in a row is an error.
    fn reject(&mut self, err: f64, fac11: f64) -> Result<()> {
        self.rejected += 1;
        self.stalled_rejects += 1;
        if self.stalled_rejects > MAX_STALLED {
            return Err(stalled(
                self.opts,
                &format!(
                    "{MAX_STALLED} consecutive rejected steps, last h = {:.3e} s",
                    self.h
                ),
                self.t,
                self.mode,
            ));
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

    /// Provisional indicators (zero to all orders at the restart), settled by where the step
    /// took them. One that left zero towards the other side of its mode did so at once: the
    /// mode it implies holds from the step's start, which is redone in it (returns true).
    fn settle_provisional(&mut self) -> Result<bool> {
        let nx = self.nx;
        let mut redo = None;
        for i in 0..self.selector.inds.len() {
            if !self.sides.provisional[i] {
                continue;
            }
            let ynew = &self.ynew[..nx];
            let g = self.selector.inds[i].value(ynew);
            if g.abs() <= self.selector.band(i, ynew, norms(ynew)) {
                continue;
            }
            self.sides.provisional[i] = false;
            if g.signum() == self.sides.signs[i] {
                continue;
            }
            self.sides.forced[i] = g.signum();
            redo = Some(());
        }
        if redo.is_none() {
            return Ok(false);
        }
        let start = self.mode;
        let forced = self.sides.forced.clone();
        let new_mode = self
            .selector
            .select(&self.rhs, &self.y[..nx], start, &mut self.sides);
        self.sides.forced = forced;
        if new_mode == self.mode {
            return Ok(false);
        }
        self.rejected += 1;
        self.record_switch(new_mode)?;
        self.mode = new_mode;
        self.totals.dissipated = self.y[nx];
        self.need_k1 = true;
        Ok(true)
    }

    /// The dense output of the accepted step (Hairer, Nørsett & Wanner's `contd5`).
    fn dense_output(&mut self) {
        self.dense.fill(self.h, &self.y, &self.ynew, &self.k);
    }

    /// The first crossing of an indicator on the step (not provisional, not of a held
    /// contact): `(s_end, switched)`, `s_end = h` without one.
    fn indicator_crossing(&self) -> (f64, bool) {
        let (h, nx, mode) = (self.h, self.nx, self.mode);
        let (y, ynew, k) = (&self.y, &self.ynew, &self.k);
        let mut s_end = h;
        let mut switched = false;
        for (i, a) in self.selector.inds.iter().enumerate() {
            if self.sides.provisional[i] || of_held(a.ind, mode) {
                continue;
            }
            // Values and slopes at the step ends come from the state and the stages
            // (k₁ = f(y), k₇ = f(y_new)); the search on the dense output runs only where the
            // step may hold a crossing: a sign change at the end, or a dip of the cubic
            // Hermite interpolant in between (what its first interval would test).
            let sg = self.sides.signs[i];
            let lift = self.sides.noise[i];
            let ga = (sg * a.value(&y[..nx]) + lift).max(0.0);
            let da = sg * a.l.dot(&k[0][..nx]);
            let gb = sg * a.value(&ynew[..nx]) + lift;
            let db = sg * a.l.dot(&k[6][..nx]);
            if gb >= 0.0 && hermite_dip(ga, da, gb, db, h).is_none() {
                continue;
            }
            let f = OnStep {
                dense: &self.dense,
                ind: a,
                noise: lift,
            };
            if let Some(s) = first_crossing(&f, s_end, sg, SearchOptions::default()) {
                if s < s_end || (s == s_end && !switched) {
                    s_end = s;
                    switched = true;
                }
            }
        }
        (s_end, switched)
    }

    /// Held contacts: the release, `λ_c` crossing below `−noise` ([`Holder`]), if before (or
    /// at) the step's end `s_end` so far: `(s_end, switched, release)`, `release` the held bits
    /// of the contacts released there.
    fn held_release(&self, mut s_end: f64, mut switched: bool) -> (f64, bool, u8) {
        let mut release = 0u8;
        let (h, mode) = (self.h, self.mode);
        if !mode.any_held() {
            return (s_end, switched, release);
        }
        let rhs = &self.rhs;
        let (la, lda) = rhs.held_forces(mode, &self.y, &self.k[0]);
        let (lb, ldb) = rhs.held_forces(mode, &self.ynew, &self.k[6]);
        for (ci, sw) in CONTACTS.into_iter().enumerate() {
            if !mode.held(sw) {
                continue;
            }
            let lift = self.holder.release_noise[ci];
            let ga = (la[ci] + lift).max(0.0);
            let gb = lb[ci] + lift;
            if gb >= 0.0 && hermite_dip(ga, lda[ci], gb, ldb[ci], h).is_none() {
                continue;
            }
            let f = HeldForce {
                rhs,
                mode,
                dense: &self.dense,
                ci,
                noise: lift,
            };
            let bit = Mode(0).holding(sw, true).0 & !Mode::bit(sw);
            if let Some(s) = first_crossing(&f, s_end, 1.0, SearchOptions::default()) {
                if s < s_end || (s == s_end && !switched) {
                    s_end = s;
                    switched = true;
                    release = bit;
                } else if s == s_end {
                    release |= bit;
                }
            }
        }
        (s_end, switched, release)
    }

    /// The output samples inside `(t, t + s_end]`, from the dense output.
    fn samples(&mut self, s_end: f64, obs: &mut dyn Observer) {
        let (t, nx) = (self.t, self.nx);
        if let Some(g) = self.grid.as_mut() {
            loop {
                let tj = g.time(g.next);
                if tj > t + s_end || tj > self.t_end * (1.0 + 1e-12) {
                    break;
                }
                self.dense.eval(tj - t, &mut self.ybuf);
                obs.sample(tj, &self.ybuf[..nx], self.mode);
                g.next += 1;
            }
        }
    }

    /// The state at the step's end (cut at a switch) and its derivative into `ybuf`, `ydot`;
    /// the channels' extremes and the closed times on `[0, s_end]`.
    fn book_step(&mut self, s_end: f64, switched: bool) {
        let mode = self.mode;
        if switched {
            self.dense
                .eval_with_slope(s_end, &mut self.ybuf, &mut self.ydot);
        } else {
            self.ybuf.copy_from_slice(&self.ynew);
            self.ydot.copy_from_slice(&self.k[6]);
        }
        let (cv1, cd1) = (&mut self.cv1, &mut self.cd1);
        self.channels
            .at(&self.rhs, mode, &self.ybuf, &self.ydot, cv1, cd1);
        step_extremes(
            &self.channels,
            &self.rhs,
            mode,
            &self.dense,
            self.t,
            s_end,
            (&self.cv0, &self.cd0, &self.cv1, &self.cd1),
            &mut self.totals.peaks,
            &mut self.buf,
            &mut self.bufd,
        );
        for (ci, s) in [Switch::SliderBed, Switch::BedDamper]
            .into_iter()
            .enumerate()
        {
            if mode.on(s) && (ci == 0 || self.sys.damper.is_some()) {
                self.totals.closed_time[ci] += s_end;
            }
        }
    }

    /// The switch at `t + s_end` (state in `ybuf`): the run restarts there in the mode
    /// selected (a released contact stays closed, compliant, from its frozen gap); more than
    /// [`MAX_STALLED`] switches in a row without time advancing is an error. Returns true if
    /// the collision ended now (both contacts open for the first time).
    fn switch_at(&mut self, s_end: f64, release: u8) -> Result<bool> {
        let nx = self.nx;
        let t_old = self.t;
        self.y.copy_from_slice(&self.ybuf);
        self.selector.observe(&self.y[..nx]);
        self.t += s_end;
        let t = self.t;
        if t - t_old <= 16.0 * f64::EPSILON * t.abs() {
            self.stalled_switches += 1;
            if self.stalled_switches > MAX_STALLED {
                return Err(stalled(
                    self.opts,
                    &format!("{MAX_STALLED} consecutive switches without time advancing"),
                    t,
                    self.mode,
                ));
            }
        } else {
            self.stalled_switches = 0;
        }
        self.sides.forced.iter_mut().for_each(|f| *f = 0.0);
        self.holder.count = [0; 2];
        let start = Mode(self.mode.0 & !release);
        let new_mode = self
            .selector
            .select(&self.rhs, &self.y[..nx], start, &mut self.sides);
        if new_mode != self.mode {
            self.record_switch(new_mode)?;
        } else if self.channels.nonlinear(self.mode) {
            self.path.push(PathPoint {
                t,
                mode: self.mode,
                x: self.y[..nx].to_vec(),
            });
        }
        self.mode = new_mode;
        self.totals.dissipated = self.y[nx];
        self.need_k1 = true;
        let mode = self.mode;
        if self.collision_end.is_none()
            && !mode.on(Switch::SliderBed)
            && !mode.on(Switch::BedDamper)
        {
            self.collision_end = Some(CollisionEnd {
                t,
                x: self.y[..nx].to_vec(),
                totals: self.totals,
            });
            return Ok(true);
        }
        Ok(false)
    }

    /// The accepted step taken whole: the state, `k[0] = f(y)` (FSAL), `t`, the channels'
    /// values at the start of the next step, and a path knot while a contact is non-linear.
    fn advance(&mut self) {
        let nx = self.nx;
        self.y.copy_from_slice(&self.ynew);
        self.selector.observe(&self.y[..nx]);
        self.k.swap(0, 6);
        self.t += self.h;
        (self.cv0, self.cd0) = (self.cv1, self.cd1);
        self.totals.dissipated = self.y[nx];
        if self.channels.nonlinear(self.mode) {
            // A knot of the non-linear stretch (see `PathPoint`).
            self.path.push(PathPoint {
                t: self.t,
                mode: self.mode,
                x: self.y[..nx].to_vec(),
            });
        }
    }

    /// PI step-size control (β = 0.04) after an accepted step of error `err`
    /// (`fac11 = err^0.17`): no growth right after a rejection.
    fn control(&mut self, err: f64, fac11: f64) {
        let h = self.h;
        let mut fac = fac11 / self.facold.powf(0.04);
        fac = (fac / 0.9).clamp(0.1, 5.0);
        let mut hnew = h / fac;
        if self.last_reject {
            hnew = hnew.min(h);
        }
        self.last_reject = false;
        self.facold = err.max(1e-4);
        self.h_step = h;
        self.h = hnew;
    }

    /// A resting contact becomes held ([`Holder`]) after the step of size `h_step`: the
    /// velocities projected so that no held gap moves (the kinetic energy taken counted as
    /// dissipated), and the run restarts in the held mode.
    fn hold(&mut self) -> Result<()> {
        let (nd, nx) = (self.nd, self.nx);
        let Some(held) = self
            .holder
            .entry(&self.rhs, self.mode, &self.y, &self.k[0], self.h_step)
        else {
            return Ok(());
        };
        let masses = &self.rhs.masses;
        let ke0 = kinetic(&self.y[nd..nx], masses);
        self.sys.project_held(held, &mut self.y[nd..nx], masses);
        self.y[nx] += ke0 - kinetic(&self.y[nd..nx], masses);
        self.sides.forced.iter_mut().for_each(|f| *f = 0.0);
        let new_mode = self
            .selector
            .select(&self.rhs, &self.y[..nx], held, &mut self.sides);
        self.record_switch(new_mode)?;
        self.mode = new_mode;
        self.totals.dissipated = self.y[nx];
        self.need_k1 = true;
        Ok(())
    }

    /// The mode change to `new_mode` at `t` ([`switch_to`]), its energy jump added to the
    /// dissipated energy.
    fn record_switch(&mut self, new_mode: Mode) -> Result<()> {
        let nx = self.nx;
        self.y[nx] += switch_to(
            &self.map,
            self.sys,
            &mut self.totals,
            &mut self.events,
            &mut self.path,
            self.t,
            &self.y[..nx],
            self.mode,
            new_mode,
            self.opts.max_events,
        )?;
        Ok(())
    }

    /// The finished run.
    fn finish(self) -> Solution {
        Solution {
            events: self.events,
            path: self.path,
            collision_end: self.collision_end,
            t_final: self.t,
            x_final: self.y[..self.nx].to_vec(),
            mode_final: self.mode,
            totals: self.totals,
            steps: self.steps,
            taylor_steps: 0,
            rejected: self.rejected,
            fallback_modes: 0,
        }
    }
}

/// A mode change at `t`: the channels on both sides of the switch, the event and the path point.
#[allow(clippy::too_many_arguments)]
fn switch_to(
    map: &ChannelMap,
    sys: &ImpactSystem,
    totals: &mut Totals,
    events: &mut Vec<Event>,
    path: &mut Vec<PathPoint>,
    t: f64,
    x: &[f64],
    from: Mode,
    to: Mode,
    max_events: usize,
) -> Result<f64> {
    totals.peaks.offer_all(&map.values(sys, from, x), t);
    totals.peaks.offer_all(&map.values(sys, to, x), t);
    path.push(PathPoint {
        t,
        mode: to,
        x: x.to_vec(),
    });
    events.push(Event { t, from, to });
    if events.len() > max_events {
        return Err(super::too_many_events("dopri5", events, max_events, t));
    }
    Ok(contact_energy_jump(sys, from, to, x))
}

/// The elastic energy (J) the contacts lose when the mode changes from `from` to `to` at the
/// state `x`: `Σ_c [c closed in from] E_c(δ_c) − [c closed in to] E_c(δ_c)` with `E_c` the
/// law's potential energy ([`ContactLaw::potential_energy`]). A contact released by the force
/// rule lets go at a positive overlap (`K δ + C δ̇ = 0` with `δ̇ < 0`), and its elastic energy
/// `E_c(δ) > 0` leaves with it: the massless contact spring holds it and nothing else takes it.
/// It is counted as dissipated (negative when a contact closes at a positive overlap, which the
/// force rule also allows). Zero for switches at zero overlap (the overlap rule, the dashpot).
pub(crate) fn contact_energy_jump(sys: &ImpactSystem, from: Mode, to: Mode, x: &[f64]) -> f64 {
    let mut jump = 0.0;
    for s in [Switch::SliderBed, Switch::BedDamper] {
        if s == Switch::BedDamper && sys.damper.is_none() || from.on(s) == to.on(s) {
            continue;
        }
        let e = sys
            .contact(s)
            .law
            .potential_energy(sys.relative_motion(s, x).0);
        jump += if from.on(s) { e } else { -e };
    }
    jump
}

/// The first step size (Hairer, Nørsett & Wanner's `hinit`) for `ẏ = f(y)` from `y` with
/// `f0 = f(y)`, over the first `nx` components (the error-controlled state).
#[allow(clippy::too_many_arguments)]
pub(crate) fn initial_step(
    f: impl Fn(&[f64], &mut [f64]),
    nx: usize,
    y: &[f64],
    f0: &[f64],
    span: f64,
    ytmp: &mut [f64],
    f1: &mut [f64],
    sc: &dyn Fn(f64, f64) -> f64,
) -> f64 {
    // Hairer, Nørsett & Wanner, Solving ODEs I, §II.4 ("starting step size").
    let norm = |v: &[f64]| {
        (v[..nx]
            .iter()
            .zip(y)
            .map(|(a, b)| (a / sc(*b, *b)).powi(2))
            .sum::<f64>()
            / nx as f64)
            .sqrt()
    };
    let d0 = norm(y);
    let d1 = norm(f0);
    let mut h0 = if d0 < 1e-5 || d1 < 1e-5 {
        1e-6
    } else {
        0.01 * d0 / d1
    };
    h0 = h0.min(span);
    for i in 0..y.len() {
        ytmp[i] = y[i] + h0 * f0[i];
    }
    f(ytmp, f1);
    let mut d2 = 0.0;
    for i in 0..nx {
        d2 += ((f1[i] - f0[i]) / sc(y[i], y[i])).powi(2);
    }
    let d2 = (d2 / nx as f64).sqrt() / h0;
    let h1 = if d1.max(d2) <= 1e-15 {
        (h0 * 1e-3).max(1e-6)
    } else {
        (0.01 / d1.max(d2)).powf(0.2)
    };
    (100.0 * h0).min(h1).min(span)
}

/// `out = y + h Σ c_j k_j`.
fn combo(out: &mut [f64], y: &[f64], h: f64, terms: &[(f64, &Vec<f64>)]) {
    out.copy_from_slice(y);
    for &(c, kj) in terms {
        let hc = h * c;
        for (o, &v) in out.iter_mut().zip(kj.iter()) {
            *o += hc * v;
        }
    }
}

/// The stages of a Dormand-Prince 5(4) step of size `h` from `y` for `ẏ = f(y)` (`k[0] = f(y)`
/// given): `ynew = y + h Σ a_7j k_j`, `k[6] = f(ynew)` (FSAL), and the error estimate
/// `ytmp = h Σ e_j k_j` (Hairer, Nørsett & Wanner, *Solving ODEs I*, Table II.5.2). Each stage
/// state is `y + h Σ a_ij k_j`, one contiguous pass per term.
pub(crate) fn stages(
    f: impl Fn(&[f64], &mut [f64]),
    h: f64,
    y: &[f64],
    k: &mut [Vec<f64>; 7],
    ytmp: &mut [f64],
    ynew: &mut [f64],
) {
    let (k0, rest) = k.split_at_mut(1);
    let k0 = &k0[0];
    combo(ytmp, y, h, &[(A21, k0)]);
    let (k1, rest) = rest.split_at_mut(1);
    let k1 = &mut k1[0];
    f(ytmp, k1);
    combo(ytmp, y, h, &[(A31, k0), (A32, k1)]);
    let (k2, rest) = rest.split_at_mut(1);
    let k2 = &mut k2[0];
    f(ytmp, k2);
    combo(ytmp, y, h, &[(A41, k0), (A42, k1), (A43, k2)]);
    let (k3, rest) = rest.split_at_mut(1);
    let k3 = &mut k3[0];
    f(ytmp, k3);
    combo(ytmp, y, h, &[(A51, k0), (A52, k1), (A53, k2), (A54, k3)]);
    let (k4, rest) = rest.split_at_mut(1);
    let k4 = &mut k4[0];
    f(ytmp, k4);
    combo(
        ytmp,
        y,
        h,
        &[(A61, k0), (A62, k1), (A63, k2), (A64, k3), (A65, k4)],
    );
    let (k5, rest) = rest.split_at_mut(1);
    let k5 = &mut k5[0];
    f(ytmp, k5);
    combo(
        ynew,
        y,
        h,
        &[(A71, k0), (A73, k2), (A74, k3), (A75, k4), (A76, k5)],
    );
    let k6 = &mut rest[0];
    f(ynew, k6);
    ytmp.iter_mut().for_each(|v| *v = 0.0);
    for (c, kj) in [
        (E1, k0),
        (E3, &*k2),
        (E4, &*k3),
        (E5, &*k4),
        (E6, &*k5),
        (E7, &*k6),
    ] {
        let hc = h * c;
        for (o, &v) in ytmp.iter_mut().zip(kj.iter()) {
            *o += hc * v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::impact::{Absorber, Contact, Damper, Release, Slider};
    use crate::integrate::{Method, NoOutput};
    use crate::modal::ModalModel;

    /// A two-mode structure with the damper anchored to it: every term of the right-hand side
    /// and of the channels is present.
    fn system(sb: ContactLaw, bd: ContactLaw, dashpot: DashpotKind) -> ImpactSystem {
        let w = vec![
            2.0 * std::f64::consts::PI * 6.35,
            2.0 * std::f64::consts::PI * 283.0,
        ];
        let mut s = ModalModel::with_damping_ratios(w, &[0.01, 0.02]).unwrap();
        s.points.insert("b".into(), vec![0.14, -0.29]);
        s.points.insert("f".into(), vec![0.15, 0.05]);
        let c = |law| Contact {
            law,
            release: Release::Force,
        };
        ImpactSystem::new(
            &s,
            "b",
            Some("f"),
            "b",
            Slider {
                mass: 1.2,
                velocity: 1.2,
            },
            c(sb),
            Absorber::Damper(
                Damper {
                    mass: 3.5,
                    stiffness: 1.8e3,
                    damping: 700.0,
                    dashpot,
                },
                c(bd),
            ),
        )
        .unwrap()
    }

    const LINEAR: ContactLaw = ContactLaw::Linear {
        stiffness: 4.3e7,
        damping: 300.0,
    };
    const HERTZ: ContactLaw = ContactLaw::Hertz { stiffness: 1.7e10 };
    const HUNT_CROSSLEY: ContactLaw = ContactLaw::HuntCrossley {
        stiffness: 5e10,
        exponent: 1.5,
        alpha: 0.2,
    };

    /// A state with every contact overlapping (so that non-linear laws act) and moving.
    fn state(sys: &ImpactSystem) -> Vec<f64> {
        let nd = sys.dofs();
        let mut y = vec![0.0; 2 * nd + 1];
        y[0] = 2e-6;
        y[1] = -1e-6;
        y[sys.slider_index()] = 5e-6;
        y[sys.damper_index()] = -3e-6;
        for (i, v) in [0.3, -0.2, 0.7, -0.4].iter().enumerate() {
            y[nd + i] = *v;
        }
        y
    }

    /// For linear laws `J_σ w = A_σ w` in every mode.
    #[test]
    fn jvp_is_the_first_order_matrix_for_linear_laws() {
        let sys = system(LINEAR, LINEAR, DashpotKind::OneWay);
        let rhs = Rhs::new(&sys);
        let y = state(&sys);
        let n = 2 * sys.dofs();
        let w: Vec<f64> = (0..n).map(|i| 1.0 + 0.37 * i as f64).collect();
        let mut out = vec![0.0; n];
        for bits in 0..8u8 {
            let mode = Mode(bits);
            rhs.jvp(mode, &y, &w, &mut out);
            let a = sys.first_order(mode);
            for i in 0..n {
                let e: f64 = (0..n).map(|j| a[(i, j)] * w[j]).sum();
                assert!((out[i] - e).abs() <= 1e-12 * e.abs().max(1.0), "{bits} {i}");
            }
        }
    }

    /// For non-linear laws `J_σ w` is the derivative of `f_σ` along `w` (central differences,
    /// truncation `~h²`, relative step 1e-6).
    #[test]
    fn jvp_is_the_derivative_of_the_right_hand_side() {
        for (sb, bd) in [(HERTZ, HUNT_CROSSLEY), (HUNT_CROSSLEY, LINEAR)] {
            let sys = system(sb, bd, DashpotKind::OneWay);
            let rhs = Rhs::new(&sys);
            let y = state(&sys);
            let n = 2 * sys.dofs();
            let w: Vec<f64> = (0..n).map(|i| y[i] * (0.5 + 0.1 * i as f64)).collect();
            let eps = 1e-6;
            let (mut yp, mut ym) = (y.clone(), y.clone());
            for i in 0..n {
                yp[i] += eps * w[i];
                ym[i] -= eps * w[i];
            }
            let (mut fp, mut fm, mut out) = (vec![0.0; n + 1], vec![0.0; n + 1], vec![0.0; n]);
            for bits in [3u8, 7] {
                let mode = Mode(bits);
                rhs.eval(mode, &yp, &mut fp);
                rhs.eval(mode, &ym, &mut fm);
                rhs.jvp(mode, &y, &w, &mut out);
                for i in 0..n {
                    let fd = (fp[i] - fm[i]) / (2.0 * eps);
                    assert!(
                        (out[i] - fd).abs() <= 1e-6 * fd.abs() + 1e-9,
                        "{sb:?} {bits} {i}: {} vs {fd}",
                        out[i]
                    );
                }
            }
        }
    }

    /// `Channels::at` gives [`ChannelMap::values`] in every mode for every law, and slopes
    /// equal to the derivative of the values along the state's derivative (central
    /// differences).
    #[test]
    fn channels_on_the_dense_output_are_the_channel_map() {
        for (sb, bd, dashpot) in [
            (LINEAR, LINEAR, DashpotKind::OneWay),
            (HERTZ, HUNT_CROSSLEY, DashpotKind::OneWay),
            (HUNT_CROSSLEY, HERTZ, DashpotKind::TwoWay),
        ] {
            let sys = system(sb, bd, dashpot);
            let map = ChannelMap::new(&sys);
            let mut ch = Channels::new(&sys);
            let rhs = Rhs::new(&sys);
            let y = state(&sys);
            let n = 2 * sys.dofs();
            let mut yd = vec![0.0; n + 1];
            for bits in 0..8u8 {
                let mode = Mode(bits);
                ch.prepare(&sys, &map, mode);
                rhs.eval(mode, &y, &mut yd);
                let (mut v, mut d) = ([0.0; N_CHANNELS], [0.0; N_CHANNELS]);
                ch.at(&rhs, mode, &y, &yd, &mut v, &mut d);
                let e = map.values(&sys, mode, &y[..n]);
                let eps = 1e-7;
                let yp: Vec<f64> = (0..n).map(|i| y[i] + eps * yd[i]).collect();
                let ym: Vec<f64> = (0..n).map(|i| y[i] - eps * yd[i]).collect();
                let (ep, em) = (map.values(&sys, mode, &yp), map.values(&sys, mode, &ym));
                for c in 0..N_CHANNELS {
                    assert!(
                        (v[c] - e[c]).abs() <= 1e-12 * e[c].abs().max(1e-9),
                        "{sb:?} {bits} {c}: {} vs {}",
                        v[c],
                        e[c]
                    );
                    let fd = (ep[c] - em[c]) / (2.0 * eps);
                    assert!(
                        (d[c] - fd).abs() <= 1e-5 * fd.abs() + 1e-6,
                        "{sb:?} {bits} {c}: slope {} vs {fd}",
                        d[c]
                    );
                }
            }
        }
    }

    /// A contact let go by the force rule at `δ > 0` takes `½ K δ²` with it; closing at
    /// `δ > 0` brings it back; the dashpot switch and open-open changes take nothing.
    #[test]
    fn released_contact_takes_its_elastic_energy() {
        let sys = system(LINEAR, HERTZ, DashpotKind::OneWay);
        let y = state(&sys);
        let n = 2 * sys.dofs();
        let (d, _) = sys.relative_motion(Switch::SliderBed, &y[..n]);
        let e = 0.5 * 4.3e7 * d * d;
        assert!(d > 0.0);
        let j = contact_energy_jump(&sys, Mode(1), Mode(0), &y[..n]);
        assert!((j - e).abs() <= 1e-15 * e, "{j} vs {e}");
        assert_eq!(contact_energy_jump(&sys, Mode(0), Mode(1), &y[..n]), -j);
        assert_eq!(contact_energy_jump(&sys, Mode(1), Mode(5), &y[..n]), 0.0);
        let (dd, _) = sys.relative_motion(Switch::BedDamper, &y[..n]);
        let eh = HERTZ.potential_energy(dd);
        let jh = contact_energy_jump(&sys, Mode(2), Mode(0), &y[..n]);
        assert!(eh > 0.0 && (jh - eh).abs() <= 1e-15 * eh);
    }

    #[test]
    fn hermite_critical_points_and_slope_roots() {
        // p(u) = u³ − u² + …: the Hermite cubic of g(s) = s (s − 1)(s − 0.5) on [0, 1]
        // (g' = 3s² − 3s + 0.5): critical points (3 ∓ √3)/6.
        let g = |s: f64| s * (s - 1.0) * (s - 0.5);
        let dg = |s: f64| 3.0 * s * s - 3.0 * s + 0.5;
        let c = hermite_critical_points(g(0.0), dg(0.0), g(1.0), dg(1.0), 1.0);
        let r = 3f64.sqrt() / 6.0;
        assert!((c[0] - (0.5 - r)).abs() < 1e-14 && (c[1] - (0.5 + r)).abs() < 1e-14);
        let c = hermite_critical_points(0.0, 1.0, 2.0, 1.0, 2.0);
        assert!(c[0].is_nan() && c[1].is_nan());
        let root = slope_root(dg, 0.0, 0.5, dg(0.0), dg(0.5), 1e-15);
        assert!((root - (0.5 - r)).abs() < 1e-14, "{root}");
    }

    /// A run whose right-hand side is not finite (a slider mass of NaN, past the checks) stops
    /// with an error naming the time instead of halving its step forever.
    #[test]
    fn a_run_without_progress_is_an_error() {
        let mut sys = system(LINEAR, LINEAR, DashpotKind::OneWay);
        sys.slider.mass = f64::NAN;
        let opts = Options {
            method: Method::Dopri5,
            duration: 0.01,
            sample_rate: None,
            ..Options::default()
        };
        let e = solve(&sys, &opts, &mut NoOutput).unwrap_err().to_string();
        assert!(e.contains("no progress at t = 0"), "{e}");
    }
}
