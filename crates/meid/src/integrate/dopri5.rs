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
//! smooth there; after each accepted step every indicator is checked on the dense output with
//! the same crossing search as the exact propagator (sampled at 16 points per step with a
//! Hermite dip test for grazing), the step is cut at the first crossing and the run restarts
//! from the interpolated state in the new mode. The dissipated energy is integrated as an
//! extra state component (not under error control).

use super::roots::{first_crossing, hermite_dip, Scalar, SearchOptions};
use super::switching::{implied_mode, ModeSelector};
use super::{CollisionEnd, Event, Grid, Observer, Options, PathPoint, Solution, Totals};
use crate::impact::SparseVec;
use crate::impact::{
    dot, Channel, ChannelMap, ContactLaw, DashpotKind, ImpactSystem, Indicator, Mode, Switch,
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

    /// `dy = f(y)`, `y = [x; ẋ; E_diss]`.
    fn eval(&self, mode: Mode, y: &[f64], dy: &mut [f64]) {
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

/// Dense output of one step: `y(θ) = r1 + θ(r2 + θ₁(r3 + θ(r4 + θ₁ r5)))`, θ = s/h.
struct Dense {
    r: [Vec<f64>; 5],
    h: f64,
}

impl Dense {
    fn eval(&self, s: f64, out: &mut [f64]) {
        let th = s / self.h;
        let th1 = 1.0 - th;
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.r[0][i]
                + th * (self.r[1][i]
                    + th1 * (self.r[2][i] + th * (self.r[3][i] + th1 * self.r[4][i])));
        }
    }
    /// `ℓᵀy(s)` and its time derivative.
    fn functional(&self, l: &[f64], s: f64) -> (f64, f64) {
        let th = s / self.h;
        let th1 = 1.0 - th;
        let (mut v, mut d) = (0.0, 0.0);
        for (i, &li) in l.iter().enumerate() {
            if li == 0.0 {
                continue;
            }
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
            v += li * (r1 + th * ss);
            let dq = -r5;
            let drr = q + th * dq;
            let dss = -rr + th1 * drr;
            d += li * (ss + th * dss) / self.h;
        }
        (v, d)
    }
}

/// An indicator on the dense output of a step (non-linear indicators via state evaluation).
struct OnStep<'a> {
    dense: &'a Dense,
    sys: &'a ImpactSystem,
    ind: Indicator,
    linear: Option<&'a [f64]>,
    scratch: &'a std::cell::RefCell<Vec<f64>>,
}

impl Scalar for OnStep<'_> {
    fn value_slope(&self, s: f64) -> (f64, f64) {
        if let Some(l) = self.linear {
            return self.dense.functional(l, s);
        }
        let mut y = self.scratch.borrow_mut();
        let eps = 1e-7 * self.dense.h;
        self.dense.eval(s, &mut y);
        let g0 = self.sys.indicator_value(self.ind, &y);
        self.dense.eval(s + eps, &mut y);
        let g1 = self.sys.indicator_value(self.ind, &y);
        (g0, (g1 - g0) / eps)
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
    let rhs = Rhs::new(sys);
    let nd = sys.dofs();
    let nx = 2 * nd;
    let ny = nx + 1;
    let all_linear = [Switch::SliderBed, Switch::BedDamper].iter().all(|&s| {
        (s == Switch::BedDamper && sys.damper.is_none()) || sys.contact(s).law.is_linear()
    });
    let inds = sys.indicators();
    let linear_vecs: Vec<Option<Vec<f64>>> = inds
        .iter()
        .map(|&i| {
            let nonlinear = match i {
                Indicator::Overlap(_) | Indicator::DashpotVelocity => false,
                Indicator::Force(s) => !sys.contact(s).law.is_linear(),
            };
            if nonlinear {
                None
            } else {
                Some(sys.indicator_vector(i))
            }
        })
        .collect();

    // The linear indicators by their non-zero entries (the per-step pre-check).
    let linear_sparse: Vec<SparseVec> = linear_vecs
        .iter()
        .map(|l| SparseVec::new(l.as_deref().unwrap_or(&[])))
        .collect();
    let mut selector = ModeSelector::new(sys);
    // The signs the mode selection works with (the step's own are `signs`, below).
    let mut selected_signs = vec![0.0; inds.len()];
    // `δ` and `δ̇` of each contact as functionals of the dense output.
    let peak_vecs: Vec<(Vec<f64>, Vec<f64>)> = [Switch::SliderBed, Switch::BedDamper]
        .into_iter()
        .map(|s| {
            let (mut lx, mut lv) = (vec![0.0; ny], vec![0.0; ny]);
            if s == Switch::SliderBed || sys.damper.is_some() {
                let a = sys.relative_vector(s);
                lx[..nd].copy_from_slice(&a[..nd]);
                lv[nd..2 * nd].copy_from_slice(&a[..nd]);
            }
            (lx, lv)
        })
        .collect();
    let mut y = vec![0.0; ny];
    y[..nx].copy_from_slice(x0);
    let mut t = 0.0;
    let t_end = opts.duration;
    let mut mode = if all_linear {
        selector.select(&y[..nx], Mode(0), &mut selected_signs).0
    } else {
        initial_mode_numeric(sys, &y[..nx])
    };
    let mut grid = Grid::new(opts.sample_rate);
    let mut k: [Vec<f64>; 7] = std::array::from_fn(|_| vec![0.0; ny]);
    let mut ytmp = vec![0.0; ny];
    let mut ynew = vec![0.0; ny];
    let mut dense = Dense {
        r: std::array::from_fn(|_| vec![0.0; ny]),
        h: 1.0,
    };
    let mut ybuf = vec![0.0; ny];
    let mut events = Vec::new();
    let map = ChannelMap::new(sys);
    let mut path = vec![PathPoint {
        t: 0.0,
        mode,
        x: y[..nx].to_vec(),
    }];
    let mut totals = Totals::default();
    // Interim: channel values at the start and at every step end and switch (both sides).
    totals
        .peaks
        .offer_all(&map.values(sys, mode, &y[..nx]), 0.0);
    let mut collision_end = None;
    let (mut steps, mut rejected) = (0usize, 0usize);
    let mut signs = vec![0.0; inds.len()];
    let scratch = std::cell::RefCell::new(vec![0.0; ny]);

    let sc = |a: f64, b: f64| opts.atol + opts.rtol * a.abs().max(b.abs());
    let err_norm = |y0: &[f64], y1: &[f64], e: &[f64]| -> f64 {
        let mut s = 0.0;
        for i in 0..nx {
            let r = e[i] / sc(y0[i], y1[i]);
            s += r * r;
        }
        (s / nx as f64).sqrt()
    };

    // Emit t = 0.
    if let Some(g) = grid.as_mut() {
        obs.sample(0.0, &y[..nx], mode);
        g.next = 1;
    }
    let mut h = 0.0;
    let mut facold: f64 = 1e-4;
    let mut need_k1 = true;
    let mut last_reject = false;
    'outer: loop {
        if need_k1 {
            if all_linear {
                // The mode's first-order matrix, shared with the mode selection.
                rhs.set_lower_rows(mode, selector.matrix(mode));
            }
            rhs.eval(mode, &y, &mut k[0]);
            // Indicator sides at the (re)start.
            if all_linear {
                // Lexicographic signs under the mode's dynamics (`switching::lex_signs`).
                selector.signs(mode, &y[..nx], &mut signs);
            } else {
                for (i, &ind) in inds.iter().enumerate() {
                    signs[i] = start_sign(sys, ind, mode, &y[..nx]);
                }
            }
            if h == 0.0 {
                let (k0, k1) = k.split_at_mut(1);
                h = initial_step(
                    &rhs,
                    mode,
                    &y,
                    &k0[0],
                    opts,
                    t_end - t,
                    &mut ytmp,
                    &mut k1[0],
                    &sc,
                );
            }
            need_k1 = false;
        }
        if t >= t_end * (1.0 - 1e-15) {
            break;
        }
        h = h.min(t_end - t);
        if h < 1e-15 * t.max(1e-9) * 1e-3 {
            return Err(Error::numerical(
                "dopri5",
                format!("step size underflow at t = {t:.9e} s"),
            ));
        }
        // Stages: `out = y + h Σ c_j k_j`, one contiguous pass per term.
        let (k0, rest) = k.split_at_mut(1);
        let k0 = &k0[0];
        {
            combo(&mut ytmp, &y, h, &[(A21, k0)]);
            let (k1, rest) = rest.split_at_mut(1);
            let k1 = &mut k1[0];
            rhs.eval(mode, &ytmp, k1);
            combo(&mut ytmp, &y, h, &[(A31, k0), (A32, k1)]);
            let (k2, rest) = rest.split_at_mut(1);
            let k2 = &mut k2[0];
            rhs.eval(mode, &ytmp, k2);
            combo(&mut ytmp, &y, h, &[(A41, k0), (A42, k1), (A43, k2)]);
            let (k3, rest) = rest.split_at_mut(1);
            let k3 = &mut k3[0];
            rhs.eval(mode, &ytmp, k3);
            combo(
                &mut ytmp,
                &y,
                h,
                &[(A51, k0), (A52, k1), (A53, k2), (A54, k3)],
            );
            let (k4, rest) = rest.split_at_mut(1);
            let k4 = &mut k4[0];
            rhs.eval(mode, &ytmp, k4);
            combo(
                &mut ytmp,
                &y,
                h,
                &[(A61, k0), (A62, k1), (A63, k2), (A64, k3), (A65, k4)],
            );
            let (k5, rest) = rest.split_at_mut(1);
            let k5 = &mut k5[0];
            rhs.eval(mode, &ytmp, k5);
            combo(
                &mut ynew,
                &y,
                h,
                &[(A71, k0), (A73, k2), (A74, k3), (A75, k4), (A76, k5)],
            );
            let k6 = &mut rest[0];
            rhs.eval(mode, &ynew, k6);
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
        let err = err_norm(&y, &ynew, &ytmp);
        let expo1 = 0.2 - 0.04 * 0.75;
        let fac11 = err.powf(expo1);
        if err > 1.0 || !err.is_finite() {
            rejected += 1;
            let f = if err.is_finite() {
                (fac11 / 0.9).min(5.0)
            } else {
                10.0
            };
            h /= f.max(1.0);
            last_reject = true;
            continue;
        }
        // Accepted: dense output.
        steps += 1;
        for i in 0..ny {
            let ydiff = ynew[i] - y[i];
            let bspl = h * k[0][i] - ydiff;
            dense.r[0][i] = y[i];
            dense.r[1][i] = ydiff;
            dense.r[2][i] = bspl;
            dense.r[3][i] = ydiff - h * k[6][i] - bspl;
            dense.r[4][i] = h
                * (D1 * k[0][i]
                    + D3 * k[2][i]
                    + D4 * k[3][i]
                    + D5 * k[4][i]
                    + D6 * k[5][i]
                    + D7 * k[6][i]);
        }
        dense.h = h;
        // Events on the step.
        let mut s_end = h;
        let mut switched = false;
        for (i, &ind) in inds.iter().enumerate() {
            if signs[i] == 0.0 {
                continue;
            }
            if linear_vecs[i].is_some() {
                // Values and slopes at the step ends come from the state and the stages
                // (k₁ = f(y), k₇ = f(y_new)); the search on the dense output runs only where the
                // step may hold a crossing: a sign change at the end, or a dip of the cubic
                // Hermite interpolant in between (what its first interval would test).
                let sg = signs[i];
                let sl = &linear_sparse[i];
                let ga = (sg * sl.dot(&y[..nx])).max(0.0);
                let da = sg * sl.dot(&k[0][..nx]);
                let gb = sg * sl.dot(&ynew[..nx]);
                let db = sg * sl.dot(&k[6][..nx]);
                if gb >= 0.0 && hermite_dip(ga, da, gb, db, h).is_none() {
                    continue;
                }
            }
            let f = OnStep {
                dense: &dense,
                sys,
                ind,
                linear: linear_vecs[i].as_deref(),
                scratch: &scratch,
            };
            if let Some(s) = first_crossing(&f, s_end, signs[i], SearchOptions::default()) {
                if s < s_end || (s == s_end && !switched) {
                    s_end = s;
                    switched = true;
                }
            }
        }
        // Output samples inside (t, t + s_end].
        if let Some(g) = grid.as_mut() {
            loop {
                let tj = g.time(g.next);
                if tj > t + s_end || tj > t_end * (1.0 + 1e-12) {
                    break;
                }
                dense.eval(tj - t, &mut ybuf);
                obs.sample(tj, &ybuf[..nx], mode);
                g.next += 1;
            }
        }
        // Peak contact forces and closed times on [0, s_end].
        for (ci, s) in [Switch::SliderBed, Switch::BedDamper]
            .into_iter()
            .enumerate()
        {
            if mode.on(s) && (ci == 0 || sys.damper.is_some()) {
                totals.closed_time[ci] += s_end;
                let law = sys.contact(s).law;
                let rel = sys.relative_vector(s);
                let start = force_slope_at(&law, rel, &y, &k[0], nd);
                let end = if switched {
                    None
                } else {
                    Some(force_slope_at(&law, rel, &ynew, &k[6], nd))
                };
                let peak = peak_on_step(&law, &peak_vecs[ci], &dense, s_end, start, end);
                // Interim: the value of the peak (its time is the step's start).
                totals.peaks.0[Channel::ContactSliderBed.index() + ci].offer(peak, t);
            }
        }
        if switched {
            dense.eval(s_end, &mut ybuf);
            y.copy_from_slice(&ybuf);
            t += s_end;
            totals.dissipated = y[nx];
            let new_mode = if all_linear {
                selector.select(&y[..nx], mode, &mut selected_signs).0
            } else {
                mode_after_numeric(sys, &inds, &signs, &dense, s_end, &y[..nx])
            };
            totals.peaks.offer_all(&map.values(sys, mode, &y[..nx]), t);
            totals
                .peaks
                .offer_all(&map.values(sys, new_mode, &y[..nx]), t);
            if new_mode != mode {
                path.push(PathPoint {
                    t,
                    mode: new_mode,
                    x: y[..nx].to_vec(),
                });
                events.push(Event {
                    t,
                    from: mode,
                    to: new_mode,
                });
                if events.len() > opts.max_events {
                    return Err(Error::numerical(
                        "dopri5",
                        format!(
                            "more than {} switching events before t = {t:.6} s",
                            opts.max_events
                        ),
                    ));
                }
            }
            mode = new_mode;
            need_k1 = true;
            if collision_end.is_none() && !mode.on(Switch::SliderBed) && !mode.on(Switch::BedDamper)
            {
                collision_end = Some(CollisionEnd {
                    t,
                    x: y[..nx].to_vec(),
                    totals,
                });
                if opts.stop_at_collision_end {
                    break 'outer;
                }
            }
            // Keep the step size (the new mode may be as stiff).
            continue;
        }
        y.copy_from_slice(&ynew);
        k.swap(0, 6);
        t += h;
        totals.peaks.offer_all(&map.values(sys, mode, &y[..nx]), t);
        totals.dissipated = y[nx];
        // PI control.
        let mut fac = fac11 / facold.powf(0.04);
        fac = (fac / 0.9).clamp(0.1, 5.0);
        let mut hnew = h / fac;
        if last_reject {
            hnew = hnew.min(h);
        }
        last_reject = false;
        facold = err.max(1e-4);
        h = hnew;
    }
    let mode_final = mode;
    Ok(Solution {
        events,
        path,
        collision_end,
        t_final: t,
        x_final: y[..nx].to_vec(),
        mode_final,
        totals,
        steps,
        taylor_steps: 0,
        rejected,
        fallback_modes: 0,
    })
}

#[allow(clippy::too_many_arguments)]
fn initial_step(
    rhs: &Rhs<'_>,
    mode: Mode,
    y: &[f64],
    f0: &[f64],
    opts: &Options,
    span: f64,
    ytmp: &mut [f64],
    f1: &mut [f64],
    sc: &dyn Fn(f64, f64) -> f64,
) -> f64 {
    // Hairer, Nørsett & Wanner, Solving ODEs I, §II.4 ("starting step size").
    let nx = y.len() - 1;
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
    rhs.eval(mode, ytmp, f1);
    let diff: Vec<f64> = f1.iter().zip(f0).map(|(a, b)| a - b).collect();
    let d2 = norm(&diff) / h0;
    let h1 = if d1.max(d2) <= 1e-15 {
        (h0 * 1e-3).max(1e-6)
    } else {
        (0.01 / d1.max(d2)).powf(0.2)
    };
    let _ = opts;
    (100.0 * h0).min(h1).min(span)
}

/// The side of indicator `ind` at `x` when a contact law is not linear: its value's sign, or at
/// zero the side the mode implies.
fn start_sign(sys: &ImpactSystem, ind: Indicator, mode: Mode, x: &[f64]) -> f64 {
    let v = sys.indicator_value(ind, x);
    if v != 0.0 {
        return v.signum();
    }
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

fn initial_mode_numeric(sys: &ImpactSystem, x: &[f64]) -> Mode {
    let nd = sys.dofs();
    let sign_of = |ind: Indicator| {
        let v = sys.indicator_value(ind, x);
        if v != 0.0 {
            return v.signum();
        }
        // At zero: the direction it is moving in.
        match ind {
            Indicator::Overlap(s) => {
                dot(sys.relative_vector(s), &x[nd..]).signum()
                    * f64::from(u8::from(dot(sys.relative_vector(s), &x[nd..]) != 0.0))
            }
            _ => 0.0,
        }
    };
    implied_mode(sys, &sign_of)
}

fn mode_after_numeric(
    sys: &ImpactSystem,
    inds: &[Indicator],
    signs: &[f64],
    dense: &Dense,
    s: f64,
    x: &[f64],
) -> Mode {
    let y = std::cell::RefCell::new(vec![0.0; x.len() + 1]);
    let sign_of = |ind: Indicator| {
        let mut y = y.borrow_mut();
        let p = inds.iter().position(|&i| i == ind).unwrap_or(0);
        let v = sys.indicator_value(ind, x);
        let scale = 1e-9 * (1.0 + v.abs());
        if v.abs() > scale {
            return v.signum();
        }
        // At zero: compare with the value just before the event.
        dense.eval((s * (1.0 - 1e-6)).max(0.0), &mut y);
        let before = sys.indicator_value(ind, &y[..x.len()]);
        if before.signum() == signs[p] {
            -signs[p]
        } else {
            signs[p]
        }
    };
    implied_mode(sys, &sign_of)
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

/// Contact force and its time derivative from `δ`, `δ̇`, `δ̈`: `f(δ, δ̇)` and
/// `∂f/∂δ·δ̇ + ∂f/∂δ̇·δ̈` ([`ContactLaw::partials`]).
fn force_and_slope(law: &ContactLaw, d: f64, r: f64, acc: f64) -> (f64, f64) {
    let (fd, fr) = law.partials(d, r);
    (law.force(d, r), fd * r + fr * acc)
}

/// Force and slope at a step end from the state `y` and its derivative `dy` (a stage).
fn force_slope_at(law: &ContactLaw, a: &[f64], y: &[f64], dy: &[f64], nd: usize) -> (f64, f64) {
    let d = dot(&a[..nd], &y[..nd]);
    let r = dot(&a[..nd], &y[nd..2 * nd]);
    let acc = dot(&a[..nd], &dy[nd..2 * nd]);
    force_and_slope(law, d, r, acc)
}

/// Largest contact force on `[0, len]` of a step. A step is far shorter than any period of
/// the motion (the error control sees to that), so the force has at most one interior maximum
/// there, and only if its slope goes from positive at the start to negative at the end: then
/// the slope's root is found by safeguarded secant steps on the dense output. Otherwise the
/// maximum is at an end. `start` and `end` are `(f, f')` at the ends (`end` is `None` when the
/// step was cut at an event: then it comes from the dense output).
fn peak_on_step(
    law: &ContactLaw,
    vecs: &(Vec<f64>, Vec<f64>),
    dense: &Dense,
    len: f64,
    start: (f64, f64),
    end: Option<(f64, f64)>,
) -> f64 {
    let (lx, lv) = vecs;
    let force_slope = |t: f64| -> (f64, f64) {
        let (d, _) = dense.functional(lx, t);
        let (r, dr) = dense.functional(lv, t);
        force_and_slope(law, d, r, dr)
    };
    let (f0, s0) = start;
    let (f1, s1) = end.unwrap_or_else(|| force_slope(len));
    let mut best = f0.max(f1);
    if s0 > 0.0 && s1 < 0.0 {
        let (mut lo, mut hi, mut slo, mut shi) = (0.0, len, s0, s1);
        for _ in 0..60 {
            if hi - lo <= 1e-12 * len {
                break;
            }
            // Secant point, kept away from the ends (bisection otherwise).
            let mut m = lo + (hi - lo) * slo / (slo - shi);
            if !(m > lo + 0.01 * (hi - lo) && m < hi - 0.01 * (hi - lo)) {
                m = 0.5 * (lo + hi);
            }
            let (fm, sm) = force_slope(m);
            best = best.max(fm);
            if sm > 0.0 {
                lo = m;
                slo = sm;
            } else if sm < 0.0 {
                hi = m;
                shi = sm;
            } else {
                break;
            }
        }
    }
    best
}
