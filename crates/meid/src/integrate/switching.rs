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
/// (`comps[i]` for functional `i`; all coordinates when empty) is the part of the state coupled
/// to the functional under `A`: the slider flying away after the blow (metres, m/s) must not
/// make the centimetre-per-second motion of the damper against the bed decades later look
/// like round-off.
///
/// `a` is `A` column-major (`n × n`, `n = x.len()`); `work` is scratch space (reused between
/// calls).
///
/// # Panics
/// When `a.len() != x.len()²`.
fn lex_signs(
    ls: &[Linear],
    comps: &[Vec<usize>],
    a: &[f64],
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
    let (y, next) = work[..2 * n].split_at_mut(n);
    y.copy_from_slice(x);
    let (mut y, mut next) = (y, next);
    for k in 0..=K_MAX {
        // ‖y‖, when a functional coupled to the whole state needs its floor.
        let mut y_norm = None;
        let tol = if k == 0 { 1e-9 } else { 1e-11 };
        for (i, (l, o)) in ls.iter().zip(out.iter_mut()).enumerate() {
            if *o != 0.0 {
                continue;
            }
            let (val, scale) = l.v.dot_abs(y);
            if val.abs() > tol * scale {
                let y_norm = match comps.get(i) {
                    Some(c) if !c.is_empty() => c.iter().map(|&j| y[j] * y[j]).sum::<f64>().sqrt(),
                    _ => *y_norm.get_or_insert_with(|| y.iter().map(|v| v * v).sum::<f64>().sqrt()),
                };
                if val.abs() > 1e-12 * l.norm * y_norm {
                    *o = val.signum();
                    open -= 1;
                }
            }
        }
        if open == 0 || k == K_MAX {
            break;
        }
        mat_vec(a, y, next);
        std::mem::swap(&mut y, &mut next);
    }
}

/// The coordinates coupled to the functional `l` under `A` (column-major, `n × n`): the
/// connected components, in the graph of `A`'s non-zeros taken both ways, of the coordinates
/// `l` reads. Ascending.
fn coupled(a: &[f64], n: usize, l: &[f64]) -> Vec<usize> {
    // Union-find over the coordinates.
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    for j in 0..n {
        for i in 0..n {
            if i != j && a[j * n + i] != 0.0 {
                let (ri, rj) = (root(&mut parent, i), root(&mut parent, j));
                if ri != rj {
                    parent[ri] = rj;
                }
            }
        }
    }
    let roots: Vec<usize> = (0..n)
        .filter(|&i| l.get(i).is_some_and(|v| *v != 0.0))
        .map(|i| root(&mut parent, i))
        .collect();
    (0..n)
        .filter(|&i| {
            let r = root(&mut parent, i);
            roots.contains(&r)
        })
        .collect()
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
    /// Per mode, per indicator: the coordinates coupled to it under `A_σ` ([`lex_signs`]'s
    /// floor); built with the matrix.
    comps: [Vec<Vec<usize>>; MODES],
}

impl<'s> ModeSelector<'s> {
    /// The selector of `sys` ([`ImpactSystem::indicators`] and their vectors).
    pub fn new(sys: &'s ImpactSystem) -> Self {
        let inds = sys.indicators();
        let vecs: Vec<Vec<f64>> = inds.iter().map(|&i| sys.indicator_vector(i)).collect();
        Self {
            sys,
            switches: sys.switches(),
            inds,
            linear: vecs.iter().map(|l| Linear::new(l)).collect(),
            work: Vec::new(),
            vecs,
            n: 2 * sys.dofs(),
            mats: Default::default(),
            comps: Default::default(),
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
        let mi = usize::from(mode.0) % MODES;
        let a = &mut self.mats[mi];
        if a.is_empty() {
            a.resize(n * n, 0.0);
            self.sys.first_order_into(mode, a);
            self.comps[mi] = self.vecs.iter().map(|l| coupled(a, n, l)).collect();
        }
        &self.mats[mi]
    }

    /// The signs of the indicators just after the state `x` under `mode`'s dynamics
    /// ([`lex_signs`]) into `out`.
    pub fn signs(&mut self, mode: Mode, x: &[f64], out: &mut [f64]) {
        self.matrix(mode);
        let mi = usize::from(mode.0) % MODES;
        lex_signs(
            &self.linear,
            &self.comps[mi],
            &self.mats[mi],
            x,
            out,
            &mut self.work,
        );
    }

    /// The mode implied by `signs` (one per indicator).
    fn implied(&self, signs: &[f64]) -> Mode {
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
