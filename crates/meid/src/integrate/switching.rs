//! Choosing the mode after a switch: consistent with the state and with where it is heading.
//!
//! At an event some indicators are zero. The new mode must be *consistent*: with its own
//! dynamics `A_σ`, every indicator moves to the side that implies the same mode. The side of an
//! indicator `g = ℓᵀX` that is zero is the sign of its first non-vanishing derivative
//! `ℓᵀA_σᵏX` (k = 0, 1, 2, …), which resolves grazing and simultaneous switches alike.
//! Candidate modes are iterated to a fixed point; if none exists the switch rule of the last
//! candidate is taken (and the next search starts from it).
//!
//! Matrices here are square and stored column-major in plain slices (`a[j·n + i] = A_ij`): the
//! runs build the first-order matrices of the modes they meet into such buffers
//! ([`ModeSelector`]), without faer's aligned allocations, and the small products below are
//! hand-unrolled for the sizes of lumped machines.

use crate::impact::SparseVec;
use crate::impact::{ImpactSystem, Indicator, Mode, Switch};

/// Number of modes: three switch bits (slider-bed, bed-damper, dashpot).
pub(crate) const MODES: usize = 8;

/// Highest derivative order consulted.
const K_MAX: usize = 8;

/// A functional `ℓ` prepared for [`lex_signs`]: its non-zero entries (an indicator touches a
/// few coordinates) and its norm.
#[derive(Debug, Clone)]
struct Linear {
    v: SparseVec,
    norm: f64,
}

impl Linear {
    fn new(l: &[f64]) -> Self {
        Self {
            v: SparseVec::new(l),
            norm: l.iter().map(|v| v * v).sum::<f64>().sqrt(),
        }
    }
}

/// Signs (+1, −1, or 0 when identically zero to order `K_MAX`) of the functionals `ℓᵀX(t)`
/// just after `t` (`out[i]` for `ls[i]`), from the first non-vanishing derivative `ℓᵀAᵏX`; the
/// derivatives `Aᵏ X` are computed once, as far as the last undecided functional needs them.
///
/// A derivative `ℓᵀy` (`y = Aᵏ X`) counts as zero when it is below round-off of its own terms
/// (`1e-9 Σ|ℓᵢyᵢ|` for the value itself, which root location leaves at ~1e-13 of its terms,
/// `1e-11` for higher orders) or below `1e-12 ‖ℓ‖‖y_S‖`: the latter catches quantities whose
/// terms are all physically zero (bodies at rest, forces zero) and only carry round-off. `S`
/// is the whole state, or, for a functional with `skip[i]` set, the state without the
/// coordinates `skip_idx` (the slider's, in a mode where its contact is open and it moves on
/// its own, uncoupled): the slider flying away after the blow (metres, m/s) must not make the
/// micrometre motion of the damper against the bed seconds later look like round-off.
///
/// `a` is `A` column-major (`n × n`, `n = x.len()`), `b` the constant forcing of affine
/// dynamics `Ẋ = A X + b` (then `Ẋ = A X + b` and `X⁽ᵏ⁾ = A^{k−1}Ẋ`); `work` is scratch space
/// (reused between calls).
///
/// # Panics
/// When `a.len() != x.len()²`.
#[allow(clippy::too_many_arguments)]
fn lex_signs(
    ls: &[Linear],
    skip: &[bool],
    skip_idx: &[usize],
    a: &[f64],
    b: Option<&[f64]>,
    x: &[f64],
    out: &mut [f64],
    work: &mut Vec<f64>,
) {
    let n = x.len();
    assert_eq!(a.len(), n * n, "lexicographic signs: matrix size");
    // `out[i] == 0` marks functional i as undecided.
    out.iter_mut().for_each(|o| *o = 0.0);
    let mut open = ls.len();
    if work.len() < 2 * n {
        work.resize(2 * n, 0.0);
    }
    // With a forcing, the sizes of the terms of each derivative: `T₀ = |X|`,
    // `T₁ = |A| T₀ + |b|`, `T_{k+1} = |A| T_k` (elementwise). At rest under a constant force
    // `A X + b = 0` is a cancellation of terms of the size of the static forces, so a
    // derivative counts as zero below `1e-11 Σ|ℓ_i| T_k,i` (its round-off band), not only
    // relative to its own (round-off) entries.
    let mut terms = b.map(|_| {
        let mut t = vec![0.0; 2 * n];
        for (ti, xi) in t.iter_mut().zip(x) {
            *ti = xi.abs();
        }
        t
    });
    let (y, next) = work[..2 * n].split_at_mut(n);
    y.copy_from_slice(x);
    let (mut y, mut next) = (y, next);
    for k in 0..=K_MAX {
        // ‖y‖ and ‖y_S‖, when a functional needs its floor.
        let mut y_norm = None;
        let mut y_part = None;
        let tol = if k == 0 { 1e-9 } else { 1e-11 };
        for (i, (l, o)) in ls.iter().zip(out.iter_mut()).enumerate() {
            if *o != 0.0 {
                continue;
            }
            let (val, scale) = l.v.dot_abs(y);
            if val.abs() > tol * scale {
                let y_norm = if skip.get(i).copied().unwrap_or(false) {
                    *y_part.get_or_insert_with(|| {
                        let s: f64 = y
                            .iter()
                            .enumerate()
                            .filter(|(j, _)| !skip_idx.contains(j))
                            .map(|(_, v)| v * v)
                            .sum();
                        s.sqrt()
                    })
                } else {
                    *y_norm.get_or_insert_with(|| y.iter().map(|v| v * v).sum::<f64>().sqrt())
                };
                let band = match &terms {
                    Some(t) if k > 0 => {
                        let (idx, lv) = l.v.parts();
                        1e-11
                            * idx
                                .iter()
                                .zip(lv)
                                .map(|(&j, v)| v.abs() * t[j])
                                .sum::<f64>()
                    }
                    _ => 0.0,
                };
                if val.abs() > 1e-12 * l.norm * y_norm && val.abs() > band {
                    *o = val.signum();
                    open -= 1;
                }
            }
        }
        if open == 0 || k == K_MAX {
            break;
        }
        mat_vec(a, y, next);
        if let (0, Some(b)) = (k, b) {
            // Affine dynamics: Ẋ = A X + b, and X⁽ᵏ⁺¹⁾ = A X⁽ᵏ⁾ from there on.
            for (v, bi) in next.iter_mut().zip(b) {
                *v += bi;
            }
        }
        if let Some(t) = terms.as_mut() {
            let (tk, tn) = t.split_at_mut(n);
            tn.fill(0.0);
            for (j, &tj) in tk.iter().enumerate() {
                if tj != 0.0 {
                    for (o, aij) in tn.iter_mut().zip(&a[j * n..(j + 1) * n]) {
                        *o += aij.abs() * tj;
                    }
                }
            }
            if let (0, Some(b)) = (k, b) {
                for (o, bi) in tn.iter_mut().zip(b) {
                    *o += bi.abs();
                }
            }
            tk.copy_from_slice(tn);
        }
        std::mem::swap(&mut y, &mut next);
    }
}

/// `out = A y` with `A` column-major; fixed-size columns for the small first-order systems of
/// lumped machines (4 to 16 states), where a loop of run-time length costs more than its
/// products.
fn mat_vec(a: &[f64], y: &[f64], out: &mut [f64]) {
    fn fixed<const N: usize>(a: &[f64], y: &[f64], out: &mut [f64]) {
        let mut acc = [0.0; N];
        for (col, &yj) in a.chunks_exact(N).zip(y) {
            if yj != 0.0 {
                if let Ok(col) = <&[f64; N]>::try_from(col) {
                    for i in 0..N {
                        acc[i] += col[i] * yj;
                    }
                }
            }
        }
        out[..N].copy_from_slice(&acc);
    }
    let n = y.len();
    match n {
        4 => fixed::<4>(a, y, out),
        6 => fixed::<6>(a, y, out),
        8 => fixed::<8>(a, y, out),
        10 => fixed::<10>(a, y, out),
        12 => fixed::<12>(a, y, out),
        14 => fixed::<14>(a, y, out),
        16 => fixed::<16>(a, y, out),
        _ => {
            out.iter_mut().for_each(|v| *v = 0.0);
            for (col, &yj) in a.chunks_exact(n.max(1)).zip(y) {
                if yj != 0.0 {
                    for (nx, aij) in out.iter_mut().zip(col) {
                        *nx += aij * yj;
                    }
                }
            }
        }
    }
}

/// The mode implied by indicator signs. An indicator that is identically zero (sign 0: no
/// overlap and none coming, no relative velocity) leaves its contact open and its dashpot off:
/// either choice exerts no force, and "open" ends a collision whose bodies merely touch.
pub fn implied_mode(sys: &ImpactSystem, sign_of: &dyn Fn(Indicator) -> f64) -> Mode {
    implied_mode_of(sys, &sys.switches(), sign_of)
}

/// [`implied_mode`] over the given `switches` (the system's, computed once by the caller).
fn implied_mode_of(
    sys: &ImpactSystem,
    switches: &[Switch],
    sign_of: &dyn Fn(Indicator) -> f64,
) -> Mode {
    let mut mode = Mode(0);
    for &s in switches {
        let on = match s {
            Switch::Dashpot => sign_of(Indicator::DashpotVelocity) < 0.0,
            _ => sys.switch_on(s, sign_of),
        };
        mode = mode.with(s, on);
    }
    mode
}

/// Mode selection for one run: the system's indicators and their vectors, and the first-order
/// matrices `A_σ` of the modes met (built on first use, [`ImpactSystem::first_order_into`]).
pub struct ModeSelector<'s> {
    sys: &'s ImpactSystem,
    inds: Vec<Indicator>,
    switches: Vec<Switch>,
    vecs: Vec<Vec<f64>>,
    /// The indicators prepared for [`lex_signs`], and its scratch space.
    linear: Vec<Linear>,
    work: Vec<f64>,
    n: usize,
    /// `A_σ` per mode (index `σ`), column-major; empty until first used.
    mats: [Vec<f64>; MODES],
    /// Per indicator: true when it does not read the slider (its round-off floor leaves the
    /// slider out in modes where the slider flies free, [`lex_signs`]).
    no_slider: Vec<bool>,
    /// The slider's coordinates `z_s`, `ż_s` in the state.
    slider_idx: [usize; 2],
    /// The constant forcing `b` of `Ẋ = A_σ X + b` ([`ImpactSystem::forcing`]).
    forcing: Option<Vec<f64>>,
}

impl<'s> ModeSelector<'s> {
    /// The selector of `sys` ([`ImpactSystem::indicators`] and their vectors).
    pub fn new(sys: &'s ImpactSystem) -> Self {
        let inds = sys.indicators();
        let vecs: Vec<Vec<f64>> = inds.iter().map(|&i| sys.indicator_vector(i)).collect();
        let (zs, vs) = (sys.slider_index(), sys.dofs() + sys.slider_index());
        let vecs_ref_no_slider = vecs.iter().map(|l| l[zs] == 0.0 && l[vs] == 0.0).collect();
        Self {
            sys,
            switches: sys.switches(),
            inds,
            linear: vecs.iter().map(|l| Linear::new(l)).collect(),
            work: Vec::new(),
            vecs,
            n: 2 * sys.dofs(),
            mats: Default::default(),
            no_slider: vecs_ref_no_slider,
            slider_idx: [sys.slider_index(), sys.dofs() + sys.slider_index()],
            forcing: sys.forcing(),
        }
    }

    /// The indicators, in the order of the signs.
    pub fn indicators(&self) -> &[Indicator] {
        &self.inds
    }

    /// The vectors `ℓ` of the indicators (`g = ℓᵀX`).
    pub fn vectors(&self) -> &[Vec<f64>] {
        &self.vecs
    }

    /// `A_σ` of `mode`, column-major (`n × n`, `n = 2·dofs`).
    pub fn matrix(&mut self, mode: Mode) -> &[f64] {
        let n = self.n;
        let a = &mut self.mats[usize::from(mode.0) % MODES];
        if a.is_empty() {
            a.resize(n * n, 0.0);
            self.sys.first_order_into(mode, a);
        }
        a
    }

    /// The signs of the indicators just after the state `x` under `mode`'s dynamics
    /// ([`lex_signs`]) into `out`.
    pub fn signs(&mut self, mode: Mode, x: &[f64], out: &mut [f64]) {
        self.matrix(mode);
        let mi = usize::from(mode.0) % MODES;
        // With the slider-bed contact open the slider moves on its own.
        let free = if mode.on(Switch::SliderBed) {
            &[][..]
        } else {
            &self.no_slider[..]
        };
        lex_signs(
            &self.linear,
            free,
            &self.slider_idx,
            &self.mats[mi],
            self.forcing.as_deref(),
            x,
            out,
            &mut self.work,
        );
    }

    /// The mode implied by `signs` (one per indicator).
    pub(crate) fn implied(&self, signs: &[f64]) -> Mode {
        let sign_of = |ind: Indicator| {
            self.inds
                .iter()
                .position(|&i| i == ind)
                .map_or(0.0, |p| signs[p])
        };
        implied_mode_of(self.sys, &self.switches, &sign_of)
    }

    /// Selects a consistent mode at state `x`, starting the iteration from `start`. Returns the
    /// mode and whether it is consistent; `signs` (one per indicator) receives the indicators'
    /// signs under the returned mode's dynamics.
    pub fn select(&mut self, x: &[f64], start: Mode, signs: &mut [f64]) -> (Mode, bool) {
        let mut cand = start;
        // Modes tried, one bit each (three switch bits: modes 0-7).
        let mut seen = 0u32;
        for _ in 0..16 {
            self.signs(cand, x, signs);
            let next = self.implied(signs);
            if next == cand {
                return (cand, true);
            }
            if seen & (1 << (next.0 & 31)) != 0 {
                break;
            }
            seen |= 1 << (cand.0 & 31);
            cand = next;
        }
        // No fixed point along the iteration: try every mode.
        let allowed = self.switches.iter().fold(0u8, |a, &s| a | Mode::bit(s));
        for bits in 0..8u8 {
            let m = Mode(bits);
            if m.0 & !allowed == 0 {
                self.signs(m, x, signs);
                if self.implied(signs) == m {
                    return (m, true);
                }
            }
        }
        // None consistent: the last candidate, with its own signs.
        self.signs(cand, x, signs);
        (cand, false)
    }
}
