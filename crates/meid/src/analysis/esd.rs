//! Exact Fourier transforms and energy spectral densities of simulated transients.
//!
//! # Conventions
//! `G(f) = ∫₀^∞ g(t) e^{−iωt} dt`, `ω = 2πf` (unit·s), and the one-sided **energy spectral
//! density** `E(f) = 2|G(f)|²` (unit²·s/Hz: (m/s²)²·s/Hz for the bed acceleration, N²·s/Hz for
//! forces) for `f > 0`, so that Parseval reads `∫₀^∞ E(f) df = ∫₀^∞ g(t)² dt`. Levels are
//! `10·log10(E / E_ref)` dB re 1 (m/s²)²·s/Hz or re 1 N²·s/Hz.
//!
//! # The transform of a piecewise-linear response
//! Between switches the state obeys `Ẋ = A_σ X`, so on a stretch of mode `σ` from `t₀` to `t₁`,
//! `X(t) = e^{A_σ(t−t₀)}X(t₀)`, and a channel `g = ℓ_σᵀX` ([`ChannelMap::vectors`]) has
//!
//! ```text
//! ∫_{t₀}^{t₁} g(t) e^{−iωt} dt = ℓ_σᵀ (A_σ − iωI)⁻¹ [e^{−iωt₁} X(t₁) − e^{−iωt₀} X(t₀)]
//! ```
//!
//! exactly (differentiate `e^{−iωt}(A − iω)⁻¹X(t)`: `e^{−iωt}(A − iω)⁻¹(A − iω)X = e^{−iωt}X`).
//! Consecutive stretches in the same mode telescope. After the last simulated instant `T` the
//! free decay goes on in the final mode: when every pole the channel sees there has `Re λ < 0`
//! it adds `−ℓᵀ(A − iω)⁻¹e^{−iωT}X(T)`; otherwise the transform does not exist (a Dirac line),
//! and [`SpectrumBuilder::build`] says so instead of returning a number.
//!
//! **Evaluation.** Each mode met is decomposed once: the free rigid-body motion (common null
//! space of `M^{-½}KM^{-½}` and `M^{-½}CM^{-½}`: the slider in flight) is split off exactly as in
//! the exact propagator ([`crate::integrate::propagator`]), and the rest `A_r = V Λ V⁻¹` (balanced
//! form, all eigenvalues kept). Then `ℓᵀ(A − iω)⁻¹X = Σ_k (ℓᵀv_k)(w_kᵀX)/(λ_k − iω)`, with
//! `w_kᵀX` computed once per switch: a frequency costs one `e^{−iωt}` per switch and four real
//! multiply-adds per switch and pair of conjugate poles (the pair shares its sums), whatever the
//! sample rate. Where `|λ_k − iω|·L` is small
//! (ω → 0 on a slow pole) the pole's stretches are integrated one by one with
//! `∫₀^L e^{zs} ds = L ψ₀(zL)` (no cancellation); the rigid part, a polynomial `c₀ + c₁s` in time,
//! likewise. When the eigenvectors are ill-conditioned (`‖V‖‖V⁻¹‖ > 1e6`, near-critical damping)
//! the mode falls back to a dense complex solve per frequency (and Van Loan's block exponential
//! for its energy).
//!
//! **Non-linear contacts** (Hertz, Hunt-Crossley; `dopri5` runs) have no `ℓ_σ`: consecutive
//! path points of such a mode are joined by the cubic Hermite interpolant of the state (`X`, `Ẋ`
//! from [`ImpactSystem::accelerations`]), the channel is evaluated on it at five Chebyshev points
//! and its interpolating quartic transformed exactly. [`SpectrumBuilder::refine_nonlinear`] first
//! gives each contact [`NONLINEAR_SUBDIVISIONS`] knots (the integrator run again from the
//! stretch's start with output at the knots). Those parts are **estimates**
//! ([`ExactSpectrum::is_estimate`]); with the knots their error on a Hertz blow is 4e-8 of the
//! pulse's spectrum (test `nonlinear_contact_stretches_are_an_estimate`).
//!
//! # The length of the run
//! Switches after `T` (the one-way dashpot rectifying the base's vibration, the damper returning
//! to the bed) change the tail, so the spectrum is computed from a run continued, without output
//! samples, until the free decay of every channel from the current state carries at most
//! `DecayRule::tail_energy_fraction` (default 1e-12) of the channel's total energy
//! ([`SpectrumBuilder::continue_until_decayed`]). The switches it then ignores act on at most
//! that energy and can change `|G|` by about its square root (1e-6, 1e-5 dB) near the tail's own
//! frequencies, far below the printed digits. The continuation is bounded by
//! `DecayRule::max_continuation_s` (default 600 s) and fails with a clear error beyond it. When
//! the integrator cannot go on (contacts chattering without time advancing as the damper comes
//! to rest against the bed), the continuation creeps up on that instant with shorter runs and
//! stops there if the decay left carries at most `DecayRule::accept_energy_fraction` (1e-8,
//! about 0.002 dB) of each channel's energy, saying so in [`Continuation::stopped_early`].
//!
//! The energies `∫g²dt` are computed in the time domain, independently of the transform: on a
//! linear stretch `g(s) = c₀ + c₁s + Σ_k a_k e^{λ_k s}` is integrated in closed form
//! (`Σ_jk a_j a_k ∫e^{(λ_j+λ_k)s}`, or its Lyapunov form `Q(X₀) − Q(X₁)` when every pair decays).

use std::f64::consts::PI;

use faer::{c64, Mat};
use serde::Serialize;

use super::optimize::{brent_minimize_from, BrentOptions};
use super::quadrature::{self, Quadrature, Tolerance};
use crate::impact::{Channel, ChannelMap, ImpactSystem, Mode, Switch};
use crate::integrate::propagator::{self, Reduced};
use crate::integrate::{self, expm::expm, small, NoOutput, Options, Solution};
use crate::{Error, Result};

/// Largest eigenvector condition number for the pole-sum form.
const MAX_COND: f64 = 1e6;
/// `|λ − iω|·L` below which a pole's stretches are integrated one by one.
const PER_STRETCH: f64 = 1e-2;
/// Relative size under which a pole's weight in a channel counts as not seen (round-off).
const SEEN: f64 = 1e-9;

/// One stretch of a response: from `t0` in `mode` at state `x0`, to `t1` at state `x1`
/// (times in s, states `[x; ẋ]`).
#[derive(Debug, Clone, PartialEq)]
pub struct Stretch {
    pub t0: f64,
    pub t1: f64,
    pub mode: Mode,
    pub x0: Vec<f64>,
    pub x1: Vec<f64>,
}

/// The piecewise response of a run, or of runs chained in time (a blow train, a continuation).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Trajectory {
    pub stretches: Vec<Stretch>,
    /// The last simulated instant: time, the mode from then on, and the state.
    pub end: Option<(f64, Mode, Vec<f64>)>,
}

impl Trajectory {
    /// The stretches of one run ([`Solution::path`] to its end).
    pub fn from_solution(sol: &Solution) -> Self {
        let mut t = Self::default();
        t.append(sol, 0.0);
        t
    }

    /// Appends a run that starts at `t_offset` (its times are relative to its own start). Its
    /// start state may differ from the previous end (a fresh slider at a new blow).
    pub fn append(&mut self, sol: &Solution, t_offset: f64) {
        let p = &sol.path;
        for (i, pt) in p.iter().enumerate() {
            let (t1, x1) = match p.get(i + 1) {
                Some(n) => (n.t, &n.x),
                None => (sol.t_final, &sol.x_final),
            };
            if t1 > pt.t {
                self.stretches.push(Stretch {
                    t0: t_offset + pt.t,
                    t1: t_offset + t1,
                    mode: pt.mode,
                    x0: pt.x.clone(),
                    x1: x1.clone(),
                });
            }
        }
        self.end = Some((t_offset + sol.t_final, sol.mode_final, sol.x_final.clone()));
    }

    /// The last simulated instant (0 when empty).
    pub fn end_time(&self) -> f64 {
        self.end.as_ref().map_or(0.0, |e| e.0)
    }
}

/// A short description of a mode for messages.
pub fn describe_mode(sys: &ImpactSystem, mode: Mode) -> String {
    let mut s = format!(
        "slider-bed {}",
        if mode.on(Switch::SliderBed) {
            "closed"
        } else {
            "open"
        }
    );
    if sys.damper.is_some() {
        s += &format!(
            ", bed-damper {}, damper dashpot {}",
            if mode.on(Switch::BedDamper) {
                "closed"
            } else {
                "open"
            },
            if mode.on(Switch::Dashpot) {
                "acting"
            } else {
                "idle"
            }
        );
    }
    s
}

// ------------------------------------------------------------------ special functions

/// `ψ_n(z) = ∫₀¹ uⁿ e^{zu} du` for `n = 0..out.len()`: the series `Σ_j z^j/(j!(n+j+1))` for
/// `|z| ≤ 1`, the recurrence `ψ₀ = (e^z − 1)/z`, `ψ_n = (e^z − nψ_{n−1})/z` above (its error
/// grows by at most `n/|z|` per step).
fn psi(z: c64, out: &mut [c64]) {
    if z.norm() <= 1.0 {
        for (n, o) in out.iter_mut().enumerate() {
            let mut term = c64::new(1.0, 0.0);
            let mut s = c64::new(1.0 / (n as f64 + 1.0), 0.0);
            for j in 1..40 {
                term = term * z / j as f64;
                s += term / (n + j + 1) as f64;
                if term.norm() < 1e-18 {
                    break;
                }
            }
            *o = s;
        }
    } else {
        let ez = z.exp();
        let mut prev = (ez - 1.0) / z;
        for (n, o) in out.iter_mut().enumerate() {
            if n > 0 {
                prev = (ez - prev * n as f64) / z;
            }
            *o = prev;
        }
    }
}

/// `∫₀^L sⁿ e^{μs} ds` for `n = 0, 1`; `L = ∞` needs `Re μ < 0`.
fn exp_moments(mu: c64, len: f64) -> [c64; 2] {
    if len.is_infinite() {
        let inv = -1.0 / mu;
        return [inv, inv * inv];
    }
    let mut p = [c64::new(0.0, 0.0); 2];
    psi(mu * len, &mut p);
    [p[0] * len, p[1] * len * len]
}

// ------------------------------------------------------------------ per-mode decomposition

#[derive(Debug, Clone)]
struct Rigid {
    /// Physical pattern `M^{-½} r` (dofs).
    rx: Vec<f64>,
    /// Projection `rᵀM^{½}` (dofs): `α = rprojᵀx`.
    rproj: Vec<f64>,
}

#[derive(Debug, Clone)]
enum Part {
    /// `A_r = V Λ V⁻¹`: poles, `w_k` (rows of `V⁻¹` times the projection, length `2·dofs`) and
    /// per channel `h_k = ℓᵀv_k`.
    Spectral {
        lam: Vec<c64>,
        w: Vec<Vec<c64>>,
        h: Vec<Vec<c64>>,
    },
    /// Dense fallback in the balanced reduced coordinates `z = P X`: `ż = A z`, channel `lᵀz`.
    Dense {
        a: Mat<f64>,
        p: Vec<Vec<f64>>,
        l: Vec<Vec<f64>>,
        eig: Vec<c64>,
    },
}

#[derive(Debug, Clone)]
struct Linear {
    rigid: Vec<Rigid>,
    /// Per channel, per rigid pattern: `(ℓ_xᵀ r_x, ℓ_vᵀ r_x)`.
    seen_rigid: Vec<Vec<(f64, f64)>>,
    part: Part,
}

#[derive(Debug, Clone)]
struct ModeModel {
    mode: Mode,
    /// `None` when a closed contact of the mode has a non-linear law.
    lin: Option<Linear>,
}

/// What the free decay of one channel from a state does.
#[derive(Debug, Clone, Copy, PartialEq)]
enum TailKind {
    /// `∫₀^∞ g² ds` and the slowest decay rate `min(−Re λ)` of the poles it sees (1/s).
    Decays { energy: f64, rate: f64 },
    /// A pole with `Re λ ≥ 0` (or rigid motion) is seen: `λ` (rad/s; 0 for rigid motion).
    Persists(c64),
    /// The mode has a non-linear contact closed.
    NonLinear,
}

impl Linear {
    fn rigid_coeffs(&self, ch: usize, x: &[f64], nd: usize) -> (f64, f64) {
        let mut c0 = 0.0;
        let mut c1 = 0.0;
        for (r, &(px, pv)) in self.rigid.iter().zip(&self.seen_rigid[ch]) {
            if px == 0.0 && pv == 0.0 {
                continue;
            }
            let a0 = dot(&r.rproj, &x[..nd]);
            let a1 = dot(&r.rproj, &x[nd..]);
            c0 += px * a0 + pv * a1;
            c1 += px * a1;
        }
        (c0, c1)
    }

    /// Energy `∫₀^len g² ds` of channel `ch` from state `x0`. `len` may be ∞ (the free decay;
    /// the caller has checked that it decays: rigid motion and poles the channel does not see
    /// are left out). `x1` (the state at `len`, finite only) allows the Lyapunov form.
    fn energy(&self, ch: usize, x0: &[f64], x1: Option<&[f64]>, len: f64, nd: usize) -> f64 {
        let inf = len.is_infinite();
        let (c0, c1) = if inf {
            (0.0, 0.0)
        } else {
            self.rigid_coeffs(ch, x0, nd)
        };
        let mut e = c0 * c0 * len + c0 * c1 * len * len + c1 * c1 * len.powi(3) / 3.0;
        if c0 == 0.0 && c1 == 0.0 {
            e = 0.0;
        }
        let zero = c64::new(0.0, 0.0);
        match &self.part {
            Part::Spectral { lam, w, h } => {
                let amp = |x: &[f64]| -> Vec<c64> {
                    (0..lam.len())
                        .map(|k| {
                            if h[ch][k] == zero {
                                zero
                            } else {
                                h[ch][k] * cdot(&w[k], x)
                            }
                        })
                        .collect()
                };
                let mut a = amp(x0);
                if inf {
                    let scale: f64 = a.iter().map(|v| v.norm()).sum();
                    for ak in a.iter_mut() {
                        if ak.norm() <= SEEN * scale {
                            *ak = zero;
                        }
                    }
                    return e + quad_form(&a, lam);
                }
                if c0 != 0.0 || c1 != 0.0 {
                    for (ak, lk) in a.iter().zip(lam) {
                        let m = exp_moments(*lk, len);
                        e += 2.0 * (ak * (m[0] * c0 + m[1] * c1)).re;
                    }
                }
                if let (Some(x1), true) = (x1, self.lyapunov_ok(ch)) {
                    let mut a1 = amp(x1);
                    let hmax = h[ch].iter().map(|v| v.norm()).fold(0.0, f64::max);
                    for k in 0..lam.len() {
                        if h[ch][k].norm() <= SEEN * hmax {
                            a[k] = zero;
                            a1[k] = zero;
                        }
                    }
                    return e + quad_form(&a, lam) - quad_form(&a1, lam);
                }
                let mut s = 0.0;
                for j in 0..a.len() {
                    if a[j] == zero {
                        continue;
                    }
                    for k in j..a.len() {
                        if a[k] == zero {
                            continue;
                        }
                        let f = if j == k { 1.0 } else { 2.0 };
                        s += f * (a[j] * a[k] * exp_moments(lam[j] + lam[k], len)[0]).re;
                    }
                }
                e + s
            }
            Part::Dense { a, p, l, eig } => {
                let z0: Vec<f64> = p.iter().map(|r| dot(r, x0)).collect();
                if l[ch].iter().all(|v| *v == 0.0) {
                    return e;
                }
                if !inf {
                    let (w, _) = gram(a, &l[ch], len);
                    return e + quad_real(&w, &z0);
                }
                let rate = -eig.iter().map(|l| l.re).fold(f64::NEG_INFINITY, f64::max);
                let h = 5.0 / rate;
                let (w, eh) = gram(a, &l[ch], h);
                let mut z = z0;
                let mut total = 0.0;
                for _ in 0..400 {
                    let de = quad_real(&w, &z);
                    total += de;
                    if de <= 1e-17 * total {
                        break;
                    }
                    z = (0..z.len())
                        .map(|i| (0..z.len()).map(|j| eh[(i, j)] * z[j]).sum())
                        .collect();
                }
                e + total
            }
        }
    }

    /// True when every pair of poles channel `ch` sees decays (`Re(λ_j + λ_k) < 0`), so that
    /// `∫₀^L g² = Q(X₀) − Q(X₁)` with `Q(X) = −Σ_jk a_j a_k/(λ_j + λ_k)`.
    fn lyapunov_ok(&self, ch: usize) -> bool {
        let Part::Spectral { lam, h, .. } = &self.part else {
            return false;
        };
        if self.seen_rigid[ch]
            .iter()
            .any(|&(px, pv)| px != 0.0 || pv != 0.0)
        {
            return false;
        }
        let hmax = h[ch].iter().map(|v| v.norm()).fold(0.0, f64::max);
        let lmax = lam.iter().map(|v| v.norm()).fold(0.0, f64::max);
        h[ch]
            .iter()
            .zip(lam)
            .all(|(hk, lk)| hk.norm() <= SEEN * hmax || lk.re < -1e-9 * lmax)
    }

    /// The free decay of channel `ch` from `x` (see [`TailKind`]).
    fn tail(&self, ch: usize, x: &[f64], nd: usize) -> TailKind {
        let (c0, c1) = self.rigid_coeffs(ch, x, nd);
        let mut scale = c0.abs() + c1.abs();
        let persist = match &self.part {
            Part::Spectral { lam, w, h } => {
                let a: Vec<c64> = (0..lam.len()).map(|k| h[ch][k] * cdot(&w[k], x)).collect();
                scale += a.iter().map(|v| v.norm()).sum::<f64>();
                let lmax = lam.iter().map(|v| v.norm()).fold(0.0, f64::max);
                let mut rate = f64::INFINITY;
                let mut persist = None;
                for (ak, lk) in a.iter().zip(lam) {
                    if ak.norm() <= SEEN * scale {
                        continue;
                    }
                    if lk.re >= -1e-12 * lmax {
                        persist = Some(c64::new(lk.re, lk.im.abs()));
                    } else {
                        rate = rate.min(-lk.re);
                    }
                }
                if scale == 0.0 {
                    return TailKind::Decays {
                        energy: 0.0,
                        rate: f64::INFINITY,
                    };
                }
                match persist {
                    Some(l) => Some(l),
                    None if c0.abs() + c1.abs() > SEEN * scale => Some(c64::new(0.0, 0.0)),
                    None => {
                        return TailKind::Decays {
                            energy: self.energy(ch, x, None, f64::INFINITY, nd),
                            rate,
                        }
                    }
                }
            }
            Part::Dense { l, eig, p, .. } => {
                let z: Vec<f64> = p.iter().map(|r| dot(r, x)).collect();
                let seen = dot(&l[ch], &z).abs()
                    + l[ch]
                        .iter()
                        .zip(&z)
                        .map(|(a, b)| (a * b).abs())
                        .sum::<f64>();
                let lmax = eig.iter().map(|v| v.norm()).fold(0.0, f64::max);
                let worst = eig
                    .iter()
                    .copied()
                    .fold(c64::new(f64::NEG_INFINITY, 0.0), |a, b| {
                        if b.re > a.re {
                            b
                        } else {
                            a
                        }
                    });
                if seen == 0.0 && c0 == 0.0 && c1 == 0.0 {
                    return TailKind::Decays {
                        energy: 0.0,
                        rate: f64::INFINITY,
                    };
                }
                if worst.re >= -1e-12 * lmax {
                    Some(c64::new(worst.re, worst.im.abs()))
                } else if c0.abs() + c1.abs() > SEEN * (scale + seen) {
                    Some(c64::new(0.0, 0.0))
                } else {
                    return TailKind::Decays {
                        energy: self.energy(ch, x, None, f64::INFINITY, nd),
                        rate: -worst.re,
                    };
                }
            }
        };
        TailKind::Persists(persist.unwrap_or(c64::new(0.0, 0.0)))
    }
}

/// `−Re Σ_jk a_j a_k/(λ_j + λ_k)` (the energy of the free decay `Σ a_k e^{λ_k s}`).
fn quad_form(a: &[c64], lam: &[c64]) -> f64 {
    let mut s = c64::new(0.0, 0.0);
    for (j, (aj, lj)) in a.iter().zip(lam).enumerate() {
        if *aj == c64::new(0.0, 0.0) {
            continue;
        }
        let mut inner = c64::new(0.0, 0.0);
        for (ak, lk) in a[j + 1..].iter().zip(&lam[j + 1..]) {
            if *ak != c64::new(0.0, 0.0) {
                inner += ak / (lj + lk);
            }
        }
        s += aj * (inner * 2.0 + aj / (lj + lj));
    }
    -s.re
}

/// Van Loan's block exponential: `W = ∫₀^L e^{Aᵀs} l lᵀ e^{As} ds` and `e^{AL}`
/// (C. F. Van Loan, IEEE Trans. Autom. Control 23 (1978) 395-404).
fn gram(a: &Mat<f64>, l: &[f64], len: f64) -> (Mat<f64>, Mat<f64>) {
    let n = a.nrows();
    let c = Mat::<f64>::from_fn(2 * n, 2 * n, |i, j| {
        if i < n && j < n {
            -a[(j, i)]
        } else if i < n {
            l[i] * l[j - n]
        } else if j >= n {
            a[(i - n, j - n)]
        } else {
            0.0
        }
    });
    let f = expm(&c, len);
    let w = Mat::<f64>::from_fn(n, n, |i, j| {
        (0..n).map(|k| f[(n + k, n + i)] * f[(k, n + j)]).sum()
    });
    let e = Mat::<f64>::from_fn(n, n, |i, j| f[(n + i, n + j)]);
    (w, e)
}

fn quad_real(w: &Mat<f64>, z: &[f64]) -> f64 {
    let n = z.len();
    (0..n)
        .map(|i| z[i] * (0..n).map(|j| w[(i, j)] * z[j]).sum::<f64>())
        .sum()
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[inline]
fn cdot(a: &[c64], b: &[f64]) -> c64 {
    a.iter()
        .zip(b)
        .fold(c64::new(0.0, 0.0), |acc, (x, y)| acc + x * y)
}

/// Decomposes mode `mode` (see the module docs).
fn decompose(
    sys: &ImpactSystem,
    map: &ChannelMap,
    mode: Mode,
    channels: &[Channel],
) -> Result<ModeModel> {
    let Some(vecs) = map.vectors(sys, mode) else {
        return Ok(ModeModel { mode, lin: None });
    };
    let ls: Vec<&Vec<f64>> = channels.iter().map(|c| &vecs[c.index()]).collect();
    let nd = sys.dofs();
    let (k, c) = sys.matrices(mode);
    // Rigid directions and the balanced reduced form ζ = [S y; ẏ], as the propagator.
    let Reduced {
        sq,
        q,
        scale,
        r_cols,
        ar,
        ..
    } = propagator::reduce(&k, &c, &sys.mass_diag())?;
    let mr = q.ncols();
    let n2 = 2 * mr;
    // Projection rows (ζ = P X) and the channels in ζ (ℓᵀX_Q = l_ζᵀζ).
    let mut p = vec![vec![0.0; 2 * nd]; n2];
    for j in 0..mr {
        for i in 0..nd {
            p[j][i] = scale[j] * q[(i, j)] * sq[i];
            p[mr + j][nd + i] = q[(i, j)] * sq[i];
        }
    }
    let lz: Vec<Vec<f64>> = ls
        .iter()
        .map(|l| {
            let mut v = vec![0.0; n2];
            for j in 0..mr {
                let (mut a, mut b) = (0.0, 0.0);
                for i in 0..nd {
                    a += q[(i, j)] / sq[i] * l[i];
                    b += q[(i, j)] / sq[i] * l[nd + i];
                }
                v[j] = a / scale[j];
                v[mr + j] = b;
            }
            v
        })
        .collect();
    let rigid: Vec<Rigid> = r_cols
        .iter()
        .map(|r| Rigid {
            rx: (0..nd).map(|i| r[i] / sq[i]).collect(),
            rproj: (0..nd).map(|i| r[i] * sq[i]).collect(),
        })
        .collect();
    let seen_rigid = ls
        .iter()
        .map(|l| {
            rigid
                .iter()
                .map(|r| (dot(&l[..nd], &r.rx), dot(&l[nd..], &r.rx)))
                .collect()
        })
        .collect();
    let part = if n2 == 0 {
        Part::Spectral {
            lam: Vec::new(),
            w: Vec::new(),
            h: vec![Vec::new(); ls.len()],
        }
    } else {
        let (lam, v) = small::real_eigen(&ar)?;
        let spectral = small::inverse(&v).and_then(|vinv| {
            let cond = small::norm_c(&v) * small::norm_c(&vinv);
            (cond.is_finite() && cond <= MAX_COND).then_some(vinv)
        });
        match spectral {
            Some(vinv) => {
                let w = (0..n2)
                    .map(|kk| {
                        let mut row = vec![c64::new(0.0, 0.0); 2 * nd];
                        for (j, pj) in p.iter().enumerate() {
                            let f = vinv[(kk, j)];
                            for (r, pv) in row.iter_mut().zip(pj) {
                                if *pv != 0.0 {
                                    *r += f * pv;
                                }
                            }
                        }
                        row
                    })
                    .collect();
                let h = lz
                    .iter()
                    .map(|l| {
                        (0..n2)
                            .map(|kk| {
                                (0..n2).fold(c64::new(0.0, 0.0), |acc, j| acc + v[(j, kk)] * l[j])
                            })
                            .collect()
                    })
                    .collect();
                Part::Spectral { lam, w, h }
            }
            None => Part::Dense {
                a: ar,
                p,
                l: lz,
                eig: lam,
            },
        }
    };
    Ok(ModeModel {
        mode,
        lin: Some(Linear {
            rigid,
            seen_rigid,
            part,
        }),
    })
}

// ------------------------------------------------------------------ Hermite stretches

/// Chebyshev-Lobatto points on [0, 1] for the quartic of a non-linear stretch.
fn cheb_nodes() -> [f64; 5] {
    std::array::from_fn(|i| 0.5 * (1.0 - (i as f64 * PI / 4.0).cos()))
}

/// Solves `V b = g` for the monomial coefficients of the quartic through `(τ_i, g_i)`.
fn quartic_through(tau: &[f64; 5], g: &[f64; 5]) -> [f64; 5] {
    let mut a = [[0.0; 6]; 5];
    for i in 0..5 {
        for n in 0..5 {
            a[i][n] = tau[i].powi(n as i32);
        }
        a[i][5] = g[i];
    }
    for col in 0..5 {
        let piv = (col..5)
            .max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))
            .unwrap_or(col);
        a.swap(col, piv);
        for r in 0..5 {
            if r != col && a[col][col] != 0.0 {
                let f = a[r][col] / a[col][col];
                for cc in col..6 {
                    a[r][cc] -= f * a[col][cc];
                }
            }
        }
    }
    std::array::from_fn(|i| {
        if a[i][i] != 0.0 {
            a[i][5] / a[i][i]
        } else {
            0.0
        }
    })
}

/// The channels on a non-linear stretch as quartics in `τ = s/L` (see the module docs).
fn hermite_quartics(
    sys: &ImpactSystem,
    map: &ChannelMap,
    channels: &[Channel],
    s: &Stretch,
) -> Vec<[f64; 5]> {
    let nd = sys.dofs();
    let len = s.t1 - s.t0;
    let deriv = |x: &[f64]| {
        let mut d = vec![0.0; 2 * nd];
        d[..nd].copy_from_slice(&x[nd..]);
        sys.accelerations(s.mode, x, &mut d[nd..]);
        d
    };
    let (d0, d1) = (deriv(&s.x0), deriv(&s.x1));
    let tau = cheb_nodes();
    let mut g = vec![[0.0; 5]; channels.len()];
    let mut x = vec![0.0; 2 * nd];
    for (i, &t) in tau.iter().enumerate() {
        let (t2, t3) = (t * t, t * t * t);
        let (h00, h10, h01, h11) = (
            2.0 * t3 - 3.0 * t2 + 1.0,
            t3 - 2.0 * t2 + t,
            -2.0 * t3 + 3.0 * t2,
            t3 - t2,
        );
        for j in 0..2 * nd {
            x[j] = h00 * s.x0[j] + h10 * len * d0[j] + h01 * s.x1[j] + h11 * len * d1[j];
        }
        let v = map.values(sys, s.mode, &x);
        for (gc, c) in g.iter_mut().zip(channels) {
            gc[i] = v[c.index()];
        }
    }
    g.iter().map(|gi| quartic_through(&tau, gi)).collect()
}

// ------------------------------------------------------------------ the builder

/// The rule that decides how long a run is continued for its exact spectrum (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DecayRule {
    /// Largest share of a channel's total energy its free decay after the last simulated
    /// instant may carry (default 1e-12).
    pub tail_energy_fraction: f64,
    /// Longest continuation after the record (s), the cost limit (default 600 s).
    pub max_continuation_s: f64,
    /// When the run cannot be continued (the integrator stops, e.g. on contacts chattering as
    /// the damper comes to rest against the bed), the largest share of a channel's energy the
    /// free decay from the last state reached may carry (default 1e-8: it changes `|G|` by at
    /// most about 2e-4, 0.002 dB, near the tail's own frequencies).
    pub accept_energy_fraction: f64,
}

impl Default for DecayRule {
    fn default() -> Self {
        Self {
            tail_energy_fraction: 1e-12,
            max_continuation_s: 600.0,
            accept_energy_fraction: 1e-8,
        }
    }
}

/// How a run was continued for its spectrum.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Continuation {
    /// End of the record (s).
    pub record_end_s: f64,
    /// End of the continued run (s).
    pub end_s: f64,
    /// Switches between the two.
    pub switches: usize,
    /// Per channel: the free decay's share of the channel's energy at `end_s`.
    pub tail_energy_fraction: Vec<f64>,
    /// Why the continuation stopped before reaching `DecayRule::tail_energy_fraction` (the
    /// integrator could not go on, e.g. contacts chattering as the damper comes to rest against
    /// the bed), if it did; the fractions reached are then at most
    /// `DecayRule::accept_energy_fraction`.
    pub stopped_early: Option<String>,
}

/// Shortest continuation step (s).
const MIN_CHUNK: f64 = 1e-3;

/// Band energies are computed to their relative tolerance or to this share of the channel's
/// energy `∫g²dt`, whichever is larger ([`ExactSpectrum::band_energy`]).
pub const ENERGY_FLOOR: f64 = 1e-13;

/// Knots per contact episode of a non-linear contact ([`SpectrumBuilder::refine_nonlinear`]).
pub const NONLINEAR_SUBDIVISIONS: usize = 48;

/// Records the states on the output grid.
struct States(Vec<(f64, Vec<f64>)>);

impl integrate::Observer for States {
    fn sample(&mut self, t: f64, x: &[f64], _mode: Mode) {
        self.0.push((t, x.to_vec()));
    }
}

/// The continuation a run still needs: the tail-energy fraction `E_tail/(E_rec + E_tail)` of
/// each channel (1 for a persisting or non-linear tail), the last such channel, and the time
/// to continue, `1.1 ln(f/f_max)/(2 rate)` for a decaying tail above the rule (0: done).
struct Tail {
    chunk: f64,
    fractions: Vec<f64>,
    /// The channel whose tail does not decay, with its pole (none: a non-linear contact).
    persistent: Option<(usize, Option<c64>)>,
}

/// [`Tail`] of the free decays `tails` after the energies `e_rec` recorded up to `t_end`
/// (`record_end` the record's end, s).
fn tail_continuation(
    tails: &[TailKind],
    e_rec: &[f64],
    t_end: f64,
    record_end: f64,
    rule: &DecayRule,
) -> Tail {
    let nch = tails.len();
    let mut chunk: f64 = 0.0;
    let mut fractions = vec![0.0; nch];
    let mut persistent = None;
    for (ch, tk) in tails.iter().enumerate() {
        match *tk {
            TailKind::Decays { energy, rate } => {
                let total = e_rec[ch] + energy;
                fractions[ch] = if total > 0.0 { energy / total } else { 0.0 };
                if fractions[ch] > rule.tail_energy_fraction {
                    let r = fractions[ch] / rule.tail_energy_fraction;
                    chunk = chunk.max(1.1 * r.ln() / (2.0 * rate));
                }
            }
            TailKind::Persists(l) => {
                fractions[ch] = 1.0;
                persistent = Some((ch, Some(l)));
                chunk = chunk.max((t_end - record_end).max(record_end).max(1.0));
            }
            TailKind::NonLinear => {
                fractions[ch] = 1.0;
                persistent = Some((ch, None));
                chunk = chunk.max((t_end - record_end).max(1e-3));
            }
        }
    }
    Tail {
        chunk,
        fractions,
        persistent,
    }
}

/// Refuses a decay rule outside its ranges: `tail_energy_fraction` in (0, 1),
/// `max_continuation_s` ≥ 0 s, `accept_energy_fraction` in [tail_energy_fraction, 1).
fn check_rule(rule: &DecayRule) -> Result<()> {
    if !(rule.tail_energy_fraction > 0.0 && rule.tail_energy_fraction < 1.0) {
        return Err(Error::invalid(
            "tail_energy_fraction",
            format!("must lie in (0, 1) (got {})", rule.tail_energy_fraction),
        ));
    }
    if rule.max_continuation_s.is_nan() || rule.max_continuation_s < 0.0 {
        return Err(Error::invalid("max_continuation_s", "must be ≥ 0 s"));
    }
    if !(rule.accept_energy_fraction >= rule.tail_energy_fraction
        && rule.accept_energy_fraction < 1.0)
    {
        return Err(Error::invalid(
            "accept_energy_fraction",
            format!(
                "must lie in [tail_energy_fraction, 1) (got {})",
                rule.accept_energy_fraction
            ),
        ));
    }
    Ok(())
}

/// Builds exact spectra of the response channels of one system: decomposes each mode met once
/// and reuses it for the continuation's checks and the transform.
pub struct SpectrumBuilder<'a> {
    sys: &'a ImpactSystem,
    map: ChannelMap,
    channels: Vec<Channel>,
    models: Vec<ModeModel>,
}

/// The exact spectrum assumes a response that decays to zero: refuse a constant slider force,
/// naming the field.
pub fn check_unforced(sys: &ImpactSystem) -> Result<()> {
    if sys.slider_force() != 0.0 {
        return Err(crate::Error::invalid(
            "slider.force",
            format!(
                "the exact spectrum (ESD) needs a response that decays to zero; with a constant \
                 slider force ({:e} N) it settles at a static state instead. Set \
                 slider.force = 0 for spectra and comparisons, or use the time histories",
                sys.slider_force()
            ),
        ));
    }
    Ok(())
}

impl<'a> SpectrumBuilder<'a> {
    pub fn new(sys: &'a ImpactSystem, channels: &[Channel]) -> Self {
        Self {
            sys,
            map: ChannelMap::new(sys),
            channels: channels.to_vec(),
            models: Vec::new(),
        }
    }

    /// The channels, in the order of every per-channel result.
    pub fn channels(&self) -> &[Channel] {
        &self.channels
    }

    fn model(&mut self, mode: Mode) -> Result<usize> {
        if let Some(i) = self.models.iter().position(|m| m.mode == mode) {
            return Ok(i);
        }
        let m = decompose(self.sys, &self.map, mode, &self.channels)?;
        self.models.push(m);
        Ok(self.models.len() - 1)
    }

    /// `∫ g² dt` over one stretch, per channel.
    fn stretch_energy(&mut self, s: &Stretch) -> Result<Vec<f64>> {
        let nd = self.sys.dofs();
        let mi = self.model(s.mode)?;
        let len = s.t1 - s.t0;
        Ok(match &self.models[mi].lin {
            Some(lin) => (0..self.channels.len())
                .map(|ch| lin.energy(ch, &s.x0, Some(&s.x1), len, nd))
                .collect(),
            None => hermite_quartics(self.sys, &self.map, &self.channels, s)
                .iter()
                .map(|b| {
                    let mut e = 0.0;
                    for (i, bi) in b.iter().enumerate() {
                        for (j, bj) in b.iter().enumerate() {
                            e += bi * bj / (i + j + 1) as f64;
                        }
                    }
                    e * len
                })
                .collect(),
        })
    }

    /// The free decay of every channel from `x` in `mode`.
    fn tails(&mut self, mode: Mode, x: &[f64]) -> Result<Vec<TailKind>> {
        let nd = self.sys.dofs();
        let mi = self.model(mode)?;
        Ok(match &self.models[mi].lin {
            Some(lin) => (0..self.channels.len())
                .map(|ch| lin.tail(ch, x, nd))
                .collect(),
            None => vec![TailKind::NonLinear; self.channels.len()],
        })
    }

    /// Continues the run behind `traj` (from its end, without output samples) until the free
    /// decay of every channel carries at most `rule.tail_energy_fraction` of the channel's
    /// energy; see the module docs. `opts` gives the method and tolerances (its duration and
    /// sample rate are replaced).
    pub fn continue_until_decayed(
        &mut self,
        opts: &Options,
        traj: &mut Trajectory,
        rule: &DecayRule,
    ) -> Result<Continuation> {
        check_rule(rule)?;
        let record_end = traj.end_time();
        let nch = self.channels.len();
        let mut e_rec = vec![0.0; nch];
        let mut counted = 0;
        let mut switches = 0;
        let mut shrink = 1.0;
        loop {
            let new: Vec<Stretch> = traj.stretches[counted..].to_vec();
            for s in &new {
                for (e, de) in e_rec.iter_mut().zip(self.stretch_energy(s)?) {
                    *e += de;
                }
            }
            counted = traj.stretches.len();
            let Some((t_end, mode, x)) = traj.end.clone() else {
                return Err(Error::invalid("trajectory", "the run has no end state"));
            };
            let tails = self.tails(mode, &x)?;
            let Tail {
                chunk,
                fractions,
                persistent,
            } = tail_continuation(&tails, &e_rec, t_end, record_end, rule);
            if chunk == 0.0 {
                return Ok(Continuation {
                    record_end_s: record_end,
                    end_s: t_end,
                    switches,
                    tail_energy_fraction: fractions,
                    stopped_early: None,
                });
            }
            let done = t_end - record_end;
            if done >= rule.max_continuation_s {
                return Err(self.not_decayed(mode, persistent, &fractions, rule, done));
            }
            // Continue by at most the time simulated so far (at least 1 s): the prediction from
            // the slowest decay rate of the current mode overshoots when a switch (the dashpot
            // acting again) speeds up the decay.
            let chunk = chunk.min(t_end.max(1.0));
            let o = Options {
                duration: (chunk * shrink)
                    .clamp(MIN_CHUNK, rule.max_continuation_s - done + MIN_CHUNK),
                sample_rate: None,
                stop_at_collision_end: false,
                ..*opts
            };
            let sol = match integrate::solve_from(self.sys, &x, &o, &mut NoOutput) {
                Ok(sol) if sol.x_final.iter().all(|v| v.is_finite()) => sol,
                failed => {
                    let why = match failed {
                        Err(e) => format!("continuing from t = {t_end:.9e} s: {e}"),
                        Ok(_) => format!(
                            "continuing from t = {t_end:.9e} s: the state became non-finite"
                        ),
                    };
                    // The integrator cannot go on (e.g. the damper coming to rest against the
                    // bed: contacts chattering without time advancing). Creep up on that instant
                    // with shorter continuations; then stop there if the decay left is
                    // negligible at the accepted level.
                    if o.duration > MIN_CHUNK {
                        shrink *= 0.25;
                        continue;
                    }
                    let worst = fractions.iter().copied().fold(0.0, f64::max);
                    if worst <= rule.accept_energy_fraction {
                        return Ok(Continuation {
                            record_end_s: record_end,
                            end_s: t_end,
                            switches,
                            tail_energy_fraction: fractions,
                            stopped_early: Some(why),
                        });
                    }
                    return Err(Error::numerical(
                        "exact spectrum",
                        format!(
                            "{why} (for the spectrum); the free decay from there still carries {worst:.3e} of a channel's energy (> {:e} accepted)",
                            rule.accept_energy_fraction
                        ),
                    ));
                }
            };
            shrink = (shrink * 2.0).min(1.0);
            switches += sol.events.len();
            traj.append(&sol, t_end);
        }
    }

    /// The error of a run whose free decay is still too large when the continuation reaches
    /// `rule.max_continuation_s` (`done` s past the record): a pole with Re λ ≥ 0, a non-linear
    /// contact still closed, or the channel with the largest tail-energy fraction.
    fn not_decayed(
        &self,
        mode: Mode,
        persistent: Option<(usize, Option<c64>)>,
        fractions: &[f64],
        rule: &DecayRule,
        done: f64,
    ) -> Error {
        let what = match persistent {
            Some((ch, Some(l))) => format!(
                "the {} does not decay in the final mode ({}): it sees a pole λ = {:.6e} {:+.6e}i 1/s ({:.6} Hz) with Re λ ≥ 0 (an undamped or rigid-body motion), so its Fourier transform does not exist",
                self.channels[ch].label(),
                describe_mode(self.sys, mode),
                l.re,
                l.im,
                l.im.abs() / (2.0 * PI)
            ),
            Some((ch, None)) => format!(
                "the {} is still in a non-linear contact",
                self.channels[ch].label()
            ),
            None => {
                let (ch, f) = fractions
                    .iter()
                    .enumerate()
                    .fold((0, 0.0), |b, (i, &f)| if f > b.1 { (i, f) } else { b });
                format!(
                    "the {}'s free decay still carries {f:.3e} of its energy (> {:e})",
                    self.channels[ch].label(),
                    rule.tail_energy_fraction
                )
            }
        };
        Error::numerical(
            "exact spectrum",
            format!(
                "{what} (the run was continued {done:.1} s past the record); the exact spectrum would depend on the record length. Add damping, or use the windowed FFT of the record (--spectrum fft)"
            ),
        )
    }

    /// Subdivides the stretches with a non-linear contact closed, whose states are known only
    /// at their ends (path points): each contact episode (consecutive such stretches of one
    /// mode) gets about [`NONLINEAR_SUBDIVISIONS`] knots, the states there from the same
    /// integrator (`opts`: method and tolerances) run again from the stretch's start with
    /// output samples at the knots. The cubic Hermite interpolant between knots then has an
    /// error of order `(h/T_c)⁴` of the pulse (`h` the knot spacing, `T_c` the contact
    /// duration). Returns the number of knots added. Linear stretches are left as they are.
    pub fn refine_nonlinear(&mut self, opts: &Options, traj: &mut Trajectory) -> Result<usize> {
        let n = traj.stretches.len();
        let mut out = Vec::with_capacity(n);
        let mut added = 0;
        let mut i = 0;
        while i < n {
            let s = &traj.stretches[i];
            let mi = self.model(s.mode)?;
            if self.models[mi].lin.is_some() {
                out.push(s.clone());
                i += 1;
                continue;
            }
            let mut j = i;
            while j + 1 < n
                && traj.stretches[j + 1].mode == s.mode
                && traj.stretches[j + 1].t0 == traj.stretches[j].t1
            {
                j += 1;
            }
            let total = traj.stretches[j].t1 - s.t0;
            for st in &traj.stretches[i..=j] {
                let len = st.t1 - st.t0;
                let k = ((NONLINEAR_SUBDIVISIONS as f64 * len / total).ceil() as usize).max(1);
                if k == 1 {
                    out.push(st.clone());
                    continue;
                }
                let o = Options {
                    duration: len,
                    sample_rate: Some(k as f64 / len),
                    stop_at_collision_end: false,
                    ..*opts
                };
                let mut rec = States(Vec::new());
                integrate::solve_from(self.sys, &st.x0, &o, &mut rec).map_err(|e| {
                    Error::numerical(
                        "exact spectrum",
                        format!(
                            "re-integrating the non-linear contact stretch at t = {:.6e} s for its knots: {e}",
                            st.t0
                        ),
                    )
                })?;
                let mut prev = (st.t0, st.x0.clone());
                for (t, x) in rec.0 {
                    if t > 0.0 && t < len * (1.0 - 1e-9) && x.iter().all(|v| v.is_finite()) {
                        let t = st.t0 + t;
                        out.push(Stretch {
                            t0: prev.0,
                            t1: t,
                            mode: st.mode,
                            x0: prev.1,
                            x1: x.clone(),
                        });
                        prev = (t, x);
                        added += 1;
                    }
                }
                out.push(Stretch {
                    t0: prev.0,
                    t1: st.t1,
                    mode: st.mode,
                    x0: prev.1,
                    x1: st.x1.clone(),
                });
            }
            i = j + 1;
        }
        traj.stretches = out;
        Ok(added)
    }

    /// The exact transform of `traj`'s channels: over the trajectory only (`free_decay` false,
    /// the record `[t₀, T]` as if the response stopped at T), or with the final mode's free decay
    /// to ∞ (`free_decay` true; an error when a channel does not decay, see the module docs).
    ///
    /// A system with a constant slider force (`slider.force > 0`) is refused: its response
    /// tends to a static state, not to zero, so the transform of the transient does not exist
    /// as defined here (the error names the field).
    pub fn build(&mut self, traj: &Trajectory, free_decay: bool) -> Result<ExactSpectrum> {
        check_unforced(self.sys)?;
        let nd = self.sys.dofs();
        let nch = self.channels.len();
        // Merge consecutive linear stretches of one mode (knots, restarts): one LTI motion.
        let mut merged: Vec<Stretch> = Vec::with_capacity(traj.stretches.len());
        for s in &traj.stretches {
            let mi = self.model(s.mode)?;
            let linear = self.models[mi].lin.is_some();
            if let Some(last) = merged.last_mut() {
                if linear && last.mode == s.mode && last.t1 == s.t0 && last.x1 == s.x0 {
                    last.t1 = s.t1;
                    last.x1.clone_from(&s.x1);
                    continue;
                }
            }
            merged.push(s.clone());
        }
        let mut tail_stretch = None;
        if free_decay {
            let Some((t, mode, x)) = traj.end.clone() else {
                return Err(Error::invalid("trajectory", "the run has no end state"));
            };
            for (ch, tk) in self.tails(mode, &x)?.into_iter().enumerate() {
                match tk {
                    TailKind::Decays { .. } => {}
                    TailKind::Persists(l) => {
                        return Err(Error::numerical(
                            "exact spectrum",
                            format!(
                                "the {} does not decay after t = {t:.6e} s in the final mode ({}): it sees a pole λ = {:.6e} {:+.6e}i 1/s ({:.6} Hz) with Re λ ≥ 0, so its Fourier transform does not exist",
                                self.channels[ch].label(),
                                describe_mode(self.sys, mode),
                                l.re,
                                l.im,
                                l.im.abs() / (2.0 * PI)
                            ),
                        ))
                    }
                    TailKind::NonLinear => {
                        return Err(Error::numerical(
                            "exact spectrum",
                            format!(
                                "the run ends at t = {t:.6e} s with a non-linear contact closed; continue it until the contacts are open"
                            ),
                        ))
                    }
                }
            }
            tail_stretch = Some(Stretch {
                t0: t,
                t1: f64::INFINITY,
                mode,
                x0: x.clone(),
                x1: x,
            });
        }
        let all: Vec<&Stretch> = merged.iter().chain(tail_stretch.iter()).collect();
        let mut which = Vec::with_capacity(all.len());
        for s in &all {
            which.push(self.model(s.mode)?);
        }
        let sys = self.sys;
        let models = &self.models;
        let mut times: Vec<f64> = Vec::new();
        let time_index = |t: f64, times: &mut Vec<f64>| -> usize {
            if times.last() != Some(&t) {
                times.push(t);
            }
            times.len() - 1
        };
        let mut modes: Vec<ModeTerms> = Vec::new();
        let mut rigid = Vec::new();
        let mut hermite = Vec::new();
        let mut energy = vec![0.0; nch];
        for (s, &mi) in all.iter().zip(&which) {
            let len = s.t1 - s.t0;
            let ti0 = time_index(s.t0, &mut times);
            let Some(lin) = &models[mi].lin else {
                let coef = hermite_quartics(sys, &self.map, &self.channels, s);
                for (e, b) in energy.iter_mut().zip(&coef) {
                    let mut v = 0.0;
                    for (i, bi) in b.iter().enumerate() {
                        for (j, bj) in b.iter().enumerate() {
                            v += bi * bj / (i + j + 1) as f64;
                        }
                    }
                    *e += v * len;
                }
                hermite.push(PolyStretch { ti0, len, coef });
                continue;
            };
            for (ch, e) in energy.iter_mut().enumerate() {
                let x1 = len.is_finite().then_some(&s.x1[..]);
                *e += lin.energy(ch, &s.x0, x1, len, nd);
            }
            let mt = match modes.iter().position(|m| m.mode == s.mode) {
                Some(i) => i,
                None => {
                    modes.push(ModeTerms::new(s.mode, lin));
                    modes.len() - 1
                }
            };
            let e_out = modes[mt].push(ti0, &s.x0, -1.0);
            modes[mt].stretches.push((e_out, len));
            if len.is_finite() {
                let ti1 = time_index(s.t1, &mut times);
                modes[mt].push(ti1, &s.x1, 1.0);
                modes[mt].lmax = modes[mt].lmax.max(len);
                let c: Vec<(f64, f64)> =
                    (0..nch).map(|ch| lin.rigid_coeffs(ch, &s.x0, nd)).collect();
                if c.iter().any(|&(a, b)| a != 0.0 || b != 0.0) {
                    rigid.push(RigidStretch { ti0, len, c });
                }
            }
        }
        // The damped natural frequencies where the density can have a narrow peak: lightly
        // damped poles (ζ < 0.3) of modes the response stays in for ten of their periods (or
        // decays freely in); within 1e-3 of each other they count once. They start the band
        // integrations' subdivisions and the peak searches' candidates.
        let mut poles = Vec::new();
        for m in &modes {
            let Part::Spectral { lam, .. } = &m.part else {
                continue;
            };
            let longest = m.stretches.iter().map(|s| s.1).fold(0.0, f64::max);
            poles.extend(
                lam.iter()
                    .filter(|l| l.im > 0.0 && -l.re < 0.3 * l.norm() && longest * l.im > 20.0 * PI)
                    .map(|l| l.im / (2.0 * PI)),
            );
        }
        poles.sort_by(f64::total_cmp);
        poles.dedup_by(|a, b| (*a - *b).abs() <= 1e-3 * b.abs());
        Ok(ExactSpectrum {
            channels: self.channels.clone(),
            times,
            modes,
            rigid,
            hermite,
            energy,
            free_decay,
            t_start: traj.stretches.first().map_or(0.0, |s| s.t0),
            t_end: traj.end_time(),
            pole_hz: poles,
        })
    }
}

/// The telescoped boundary terms of one mode.
#[derive(Debug, Clone)]
struct ModeTerms {
    mode: Mode,
    part: Part,
    /// The columns kept: a pole (spectral) or a coordinate (dense), with the index of its
    /// complex-conjugate partner when it has one (spectral: `w_k̄ = conj(w_k)`, so the partner's
    /// sums follow from the same products).
    cols: Vec<(usize, Option<usize>)>,
    /// Time index of each entry.
    entry_t: Vec<usize>,
    /// `±w_kᵀX` (spectral) or `±P X` (dense) per entry and kept column (row-major). Real and
    /// imaginary parts apart, so that the accumulation over entries vectorises.
    yr: Vec<f64>,
    yi: Vec<f64>,
    /// Stretches: (index of the start entry, length; ∞ for the free decay).
    stretches: Vec<(usize, f64)>,
    /// Longest finite stretch (s).
    lmax: f64,
}

impl ModeTerms {
    fn new(mode: Mode, lin: &Linear) -> Self {
        let cols = match &lin.part {
            Part::Spectral { lam, .. } => {
                let mut c = Vec::new();
                let mut k = 0;
                while k < lam.len() {
                    if lam[k].im > 0.0 && k + 1 < lam.len() && lam[k + 1] == lam[k].conj() {
                        c.push((k, Some(k + 1)));
                        k += 2;
                    } else {
                        c.push((k, None));
                        k += 1;
                    }
                }
                c
            }
            Part::Dense { p, .. } => (0..p.len()).map(|j| (j, None)).collect(),
        };
        Self {
            mode,
            part: lin.part.clone(),
            cols,
            entry_t: Vec::new(),
            yr: Vec::new(),
            yi: Vec::new(),
            stretches: Vec::new(),
            lmax: 0.0,
        }
    }

    fn width(&self) -> usize {
        self.cols.len()
    }

    fn push(&mut self, ti: usize, x: &[f64], sign: f64) -> usize {
        self.entry_t.push(ti);
        match &self.part {
            Part::Spectral { w, .. } => {
                for &(k, _) in &self.cols {
                    let v = cdot(&w[k], x) * sign;
                    self.yr.push(v.re);
                    self.yi.push(v.im);
                }
            }
            Part::Dense { p, .. } => {
                for r in p {
                    self.yr.push(dot(r, x) * sign);
                    self.yi.push(0.0);
                }
            }
        }
        self.entry_t.len() - 1
    }
}

#[derive(Debug, Clone)]
struct RigidStretch {
    ti0: usize,
    len: f64,
    /// Per channel `(c₀, c₁)`: the rigid part `c₀ + c₁ s`.
    c: Vec<(f64, f64)>,
}

#[derive(Debug, Clone)]
struct PolyStretch {
    ti0: usize,
    len: f64,
    /// Per channel: quartic coefficients in `τ = s/L`.
    coef: Vec<[f64; 5]>,
}

/// The largest value of an exact ESD near a frequency, located by refinement.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct EsdPeak {
    pub frequency_hz: f64,
    /// `E(f)` there (unit²·s/Hz).
    pub esd: f64,
    /// True when the largest value is at an end of the searched band (no interior maximum).
    pub at_band_edge: bool,
}

/// The exact transform of some channels of one response (see the module docs).
#[derive(Debug, Clone)]
pub struct ExactSpectrum {
    channels: Vec<Channel>,
    times: Vec<f64>,
    modes: Vec<ModeTerms>,
    rigid: Vec<RigidStretch>,
    hermite: Vec<PolyStretch>,
    energy: Vec<f64>,
    free_decay: bool,
    t_start: f64,
    t_end: f64,
    pole_hz: Vec<f64>,
}

impl ExactSpectrum {
    /// The channels, in the order of every per-channel result.
    pub fn channels(&self) -> &[Channel] {
        &self.channels
    }

    /// Position of `c` among [`Self::channels`].
    pub fn channel_index(&self, c: Channel) -> Option<usize> {
        self.channels.iter().position(|x| *x == c)
    }

    /// True when part of the response had a non-linear contact closed: those stretches are
    /// interpolated between knots (an estimate; see the module docs).
    pub fn is_estimate(&self) -> bool {
        !self.hermite.is_empty()
    }

    /// Modes evaluated by the dense fallback (ill-conditioned eigenvectors, see the module docs).
    pub fn fallback_modes(&self) -> usize {
        self.modes
            .iter()
            .filter(|m| matches!(m.part, Part::Dense { .. }))
            .count()
    }

    /// True when the free decay after the last simulated instant is included.
    pub fn includes_free_decay(&self) -> bool {
        self.free_decay
    }

    /// The simulated span `[t_start, t_end]` (s).
    pub fn span_s(&self) -> (f64, f64) {
        (self.t_start, self.t_end)
    }

    /// `∫ g² dt` per channel, computed in the time domain (module docs), over the trajectory
    /// and, if included, the free decay.
    pub fn energy(&self) -> &[f64] {
        &self.energy
    }

    /// The damped natural frequencies `Im λ/2π > 0` of the modes met (Hz), sorted.
    pub fn pole_frequencies_hz(&self) -> &[f64] {
        &self.pole_hz
    }

    /// `G(f)` of every channel (unit·s), written into `out` (length = channels).
    pub fn transform_into(&self, f_hz: f64, out: &mut [c64]) {
        let w = 2.0 * PI * f_hz;
        let iw = c64::new(0.0, w);
        out.iter_mut().for_each(|o| *o = c64::new(0.0, 0.0));
        let phases: Vec<c64> = self
            .times
            .iter()
            .map(|t| {
                let (s, c) = (w * t).sin_cos();
                c64::new(c, -s)
            })
            .collect();
        // Σ_e (c + is)(y_r + iy_i) and, for a conjugate partner, Σ_e (c + is) conj(y) =
        // conj(Σ_e (c − is) y), from the four real sums Σcy_r, Σsy_i, Σcy_i, Σsy_r.
        let mut sums = [Vec::new(), Vec::new(), Vec::new(), Vec::new()];
        let mut acc: Vec<c64> = Vec::new();
        for mt in &self.modes {
            let m = mt.width();
            for v in sums.iter_mut() {
                v.clear();
                v.resize(m, 0.0);
            }
            let [p1, p2, p3, p4] = &mut sums;
            for (e, &ti) in mt.entry_t.iter().enumerate() {
                let (c, sn) = (phases[ti].re, phases[ti].im);
                let yr = &mt.yr[e * m..(e + 1) * m];
                let yi = &mt.yi[e * m..(e + 1) * m];
                for ((((a1, a2), a3), a4), (r, i)) in p1
                    .iter_mut()
                    .zip(p2.iter_mut())
                    .zip(p3.iter_mut())
                    .zip(p4.iter_mut())
                    .zip(yr.iter().zip(yi))
                {
                    *a1 += c * r;
                    *a2 += sn * i;
                    *a3 += c * i;
                    *a4 += sn * r;
                }
            }
            match &mt.part {
                Part::Spectral { lam, h, .. } => {
                    // (pole, sums, conjugated y?)
                    let mut poles: Vec<(usize, c64, usize, bool)> = Vec::with_capacity(2 * m);
                    for (j, &(k, partner)) in mt.cols.iter().enumerate() {
                        poles.push((k, c64::new(p1[j] - p2[j], p3[j] + p4[j]), j, false));
                        if let Some(kp) = partner {
                            poles.push((kp, c64::new(p1[j] + p2[j], p4[j] - p3[j]), j, true));
                        }
                    }
                    for (k, a, j, conj) in poles {
                        let z = lam[k] - iw;
                        let s = if z.norm() * mt.lmax >= PER_STRETCH {
                            a / z
                        } else {
                            // One stretch at a time: ∫₀^L (w·X₀) e^{zs} ds e^{−iωt₀}.
                            let mut s = c64::new(0.0, 0.0);
                            let mut p = [c64::new(0.0, 0.0)];
                            for &(e, len) in &mt.stretches {
                                let y = c64::new(mt.yr[e * m + j], mt.yi[e * m + j]);
                                let y = if conj { y.conj() } else { y };
                                let y0 = -y * phases[mt.entry_t[e]];
                                if len.is_infinite() {
                                    s += y0 * (-1.0 / z);
                                } else {
                                    psi(z * len, &mut p);
                                    s += y0 * p[0] * len;
                                }
                            }
                            s
                        };
                        for (o, hc) in out.iter_mut().zip(h) {
                            *o += hc[k] * s;
                        }
                    }
                }
                Part::Dense { a, l, .. } => {
                    let n = a.nrows();
                    let mut mat = Mat::<c64>::from_fn(n, n, |i, j| c64::new(a[(i, j)], 0.0));
                    for i in 0..n {
                        mat[(i, i)] -= iw;
                    }
                    acc.clear();
                    acc.extend((0..m).map(|j| c64::new(p1[j] - p2[j], p3[j] + p4[j])));
                    let v = solve_complex(mat, &acc);
                    for (o, lc) in out.iter_mut().zip(l) {
                        *o += v
                            .iter()
                            .zip(lc)
                            .fold(c64::new(0.0, 0.0), |s, (vi, li)| s + vi * li);
                    }
                }
            }
        }
        let a = -iw;
        let mut p = [c64::new(0.0, 0.0); 5];
        for r in &self.rigid {
            psi(a * r.len, &mut p[..2]);
            let (m0, m1) = (p[0] * r.len, p[1] * r.len * r.len);
            let ph = phases[r.ti0];
            for (o, &(c0, c1)) in out.iter_mut().zip(&r.c) {
                *o += ph * (m0 * c0 + m1 * c1);
            }
        }
        for hs in &self.hermite {
            psi(a * hs.len, &mut p);
            let ph = phases[hs.ti0] * hs.len;
            for (o, b) in out.iter_mut().zip(&hs.coef) {
                let s = b
                    .iter()
                    .zip(&p)
                    .fold(c64::new(0.0, 0.0), |s, (bi, pi)| s + pi * *bi);
                *o += ph * s;
            }
        }
    }

    /// `G(f)` of every channel.
    pub fn transform(&self, f_hz: f64) -> Vec<c64> {
        let mut out = vec![c64::new(0.0, 0.0); self.channels.len()];
        self.transform_into(f_hz, &mut out);
        out
    }

    /// The one-sided ESD `E(f) = 2|G(f)|²` of every channel (unit²·s/Hz).
    pub fn esd(&self, f_hz: f64) -> Vec<f64> {
        self.transform(f_hz)
            .iter()
            .map(|g| 2.0 * g.norm_sqr())
            .collect()
    }

    fn esd_one(&self, ch: usize, f_hz: f64, buf: &mut [c64]) -> f64 {
        self.transform_into(f_hz, buf);
        2.0 * buf[ch].norm_sqr()
    }

    /// The largest value of channel `ch`'s ESD in `[f_lo, f_hi]` (Hz): candidates on a
    /// 600-point logarithmic grid and at the damped natural frequencies in the band, then
    /// Brent's parabolic/golden-section search between the best candidate's neighbours to
    /// `1e-10` of the frequency.
    pub fn peak(&self, ch: usize, f_lo: f64, f_hi: f64) -> Result<EsdPeak> {
        if !(f_lo > 0.0 && f_hi > f_lo && f_hi.is_finite()) || ch >= self.channels.len() {
            return Err(Error::invalid(
                "band",
                format!("needs 0 < f_lo < f_hi, got [{f_lo}, {f_hi}] Hz (channel {ch})"),
            ));
        }
        let n = 600;
        let mut cand: Vec<f64> = (0..=n)
            .map(|i| f_lo * (f_hi / f_lo).powf(i as f64 / n as f64))
            .collect();
        cand.extend(self.pole_hz.iter().filter(|f| **f > f_lo && **f < f_hi));
        cand.sort_by(f64::total_cmp);
        cand.dedup();
        let mut buf = vec![c64::new(0.0, 0.0); self.channels.len()];
        let vals: Vec<f64> = cand
            .iter()
            .map(|&f| self.esd_one(ch, f, &mut buf))
            .collect();
        let (ib, _) =
            vals.iter().enumerate().fold(
                (0, f64::NEG_INFINITY),
                |b, (i, &v)| if v > b.1 { (i, v) } else { b },
            );
        if ib == 0 || ib == cand.len() - 1 {
            return Ok(EsdPeak {
                frequency_hz: cand[ib],
                esd: vals[ib],
                at_band_edge: true,
            });
        }
        let (f, v) = brent_max(
            |f| self.esd_one(ch, f, &mut buf),
            cand[ib - 1],
            (cand[ib], vals[ib]),
            cand[ib + 1],
        )?;
        Ok(EsdPeak {
            frequency_hz: f,
            esd: v,
            at_band_edge: false,
        })
    }

    /// `∫_{f_lo}^{f_hi} E(f) df` of channel `ch` (unit²·s) by adaptive Gauss-Kronrod with the
    /// damped natural frequencies as breakpoints, to `rtol` or to [`ENERGY_FLOOR`] of the
    /// channel's energy `∫g²dt`, whichever is larger (below that the density is round-off of
    /// the boundary sums); the result carries its error estimate.
    pub fn band_energy(&self, ch: usize, f_lo: f64, f_hi: f64, rtol: f64) -> Quadrature {
        let mut buf = vec![c64::new(0.0, 0.0); self.channels.len()];
        quadrature::integrate(
            |f| self.esd_one(ch, f, &mut buf),
            f_lo,
            f_hi,
            &self.pole_hz,
            Tolerance {
                rtol,
                atol: ENERGY_FLOOR * self.energy[ch],
                max_evaluations: 200_000,
            },
        )
    }

    /// `∫_{f_lo}^{f_hi} E(f) df` of every channel at once (see [`Self::band_energy`]).
    pub fn band_energies(&self, f_lo: f64, f_hi: f64, rtol: f64) -> Vec<Quadrature> {
        let mut buf = vec![c64::new(0.0, 0.0); self.channels.len()];
        // Each channel in units of its energy, so that one absolute floor fits all.
        let scale: Vec<f64> = self
            .energy
            .iter()
            .map(|e| if *e > 0.0 { 1.0 / e } else { 1.0 })
            .collect();
        let mut q = quadrature::integrate_many(
            |f, out| {
                self.transform_into(f, &mut buf);
                for ((o, g), s) in out.iter_mut().zip(&buf).zip(&scale) {
                    *o = 2.0 * g.norm_sqr() * s;
                }
            },
            self.channels.len(),
            f_lo,
            f_hi,
            &self.pole_hz,
            Tolerance {
                rtol,
                atol: ENERGY_FLOOR,
                max_evaluations: 200_000,
            },
        );
        for (qi, s) in q.iter_mut().zip(&scale) {
            qi.value /= s;
            qi.error /= s;
        }
        q
    }

    /// `∫₀^∞ E(f) df` of channel `ch` (Parseval: equals [`Self::energy`]), by adaptive
    /// Gauss-Kronrod on `f = c·u/(1−u)`, `u ∈ [0, 1)`, `c` the median damped natural frequency.
    pub fn esd_integral(&self, ch: usize, rtol: f64) -> Quadrature {
        let c = if self.pole_hz.is_empty() {
            1.0
        } else {
            self.pole_hz[self.pole_hz.len() / 2]
        };
        let mut buf = vec![c64::new(0.0, 0.0); self.channels.len()];
        let breaks: Vec<f64> = self.pole_hz.iter().map(|f| f / (f + c)).collect();
        quadrature::integrate(
            |u| {
                let f = c * u / (1.0 - u);
                self.esd_one(ch, f, &mut buf) * c / ((1.0 - u) * (1.0 - u))
            },
            0.0,
            1.0,
            &breaks,
            Tolerance {
                rtol,
                atol: 0.1 * ENERGY_FLOOR * self.energy[ch],
                max_evaluations: 400_000,
            },
        )
    }
}

/// Solves `A v = b` (complex, small) by Gaussian elimination with partial pivoting; NaN when
/// singular.
fn solve_complex(mut a: Mat<c64>, b: &[c64]) -> Vec<c64> {
    let n = b.len();
    let mut v = b.to_vec();
    for col in 0..n {
        let piv = (col..n)
            .max_by(|&x, &y| a[(x, col)].norm().total_cmp(&a[(y, col)].norm()))
            .unwrap_or(col);
        if a[(piv, col)].norm() == 0.0 {
            return vec![c64::new(f64::NAN, f64::NAN); n];
        }
        if piv != col {
            for j in 0..n {
                let t = a[(piv, j)];
                a[(piv, j)] = a[(col, j)];
                a[(col, j)] = t;
            }
            v.swap(piv, col);
        }
        let d = a[(col, col)];
        for r in col + 1..n {
            let f = a[(r, col)] / d;
            if f == c64::new(0.0, 0.0) {
                continue;
            }
            for j in col..n {
                let t = a[(col, j)];
                a[(r, j)] -= f * t;
            }
            let t = v[col];
            v[r] -= f * t;
        }
    }
    for col in (0..n).rev() {
        let mut s = v[col];
        for j in col + 1..n {
            s -= a[(col, j)] * v[j];
        }
        v[col] = s / a[(col, col)];
    }
    v
}

/// The maximum of `f` on `[a, b]` bracketed by the interior point `x` with value `fx`
/// (`f(x) ≥ f(a), f(b)`), by Brent's method ([`crate::analysis::optimize`]) on `−f`, to
/// `1e-10·|x|`.
fn brent_max(
    mut f: impl FnMut(f64) -> f64,
    a: f64,
    (x, fx): (f64, f64),
    b: f64,
) -> Result<(f64, f64)> {
    let options = BrentOptions {
        x_tolerance: 1e-300,
        relative_tolerance: 1e-10,
        max_evaluations: 200,
    };
    let m = brent_minimize_from(|u| -f(u), a, (x, -fx), b, &options)?;
    Ok((m.x, -m.f))
}

/// `10·log10(E/E_ref)` dB (−∞ for 0).
pub fn esd_level_db(esd: f64, reference: f64) -> f64 {
    10.0 * (esd / reference).log10()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn psi_series_and_recurrence_agree() {
        for z in [
            c64::new(0.3, -0.9),
            c64::new(-0.99, 0.05),
            c64::new(1.0, 0.0),
            c64::new(-3.0, 40.0),
        ] {
            let mut p = [c64::new(0.0, 0.0); 5];
            psi(z, &mut p);
            // Simpson on 20001 points.
            let n = 20_000;
            for (k, pk) in p.iter().enumerate() {
                let mut s = c64::new(0.0, 0.0);
                for i in 0..=n {
                    let u = i as f64 / n as f64;
                    let wgt = if i == 0 || i == n {
                        1.0
                    } else if i % 2 == 1 {
                        4.0
                    } else {
                        2.0
                    };
                    s += (z * u).exp() * u.powi(k as i32) * wgt;
                }
                s /= 3.0 * n as f64;
                assert!(
                    (s - pk).norm() < 1e-9 * s.norm().max(1e-3),
                    "{z} {k}: {s} vs {pk}"
                );
            }
        }
    }

    #[test]
    fn brent_finds_a_lorentzian_peak() {
        let f = |x: f64| 1.0 / ((x - 3.123_456_789).powi(2) + 1e-6);
        let (x, v) = brent_max(f, 3.0, (3.1, f(3.1)), 3.2).unwrap();
        assert!((x - 3.123_456_789).abs() < 1e-8, "{x}");
        assert!((v - 1e6).abs() < 1e-3, "{v}");
    }

    #[test]
    fn quad_form_is_the_decay_energy() {
        // g = e^{-s} + 2 e^{-3s}: ∫ g² = 1/2 + 4·1/4·... = 1/2 + 4/4·... compute: 1/2 + 2·2/4 + 4/6.
        let a = [c64::new(1.0, 0.0), c64::new(2.0, 0.0)];
        let l = [c64::new(-1.0, 0.0), c64::new(-3.0, 0.0)];
        let e = quad_form(&a, &l);
        assert!((e - (0.5 + 1.0 + 4.0 / 6.0)).abs() < 1e-15, "{e}");
    }
}
