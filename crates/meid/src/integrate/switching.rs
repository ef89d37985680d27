//! Choosing the mode after a switch: consistent with the state and with where it is heading.
//!
//! At an event some indicators are zero. The new mode must be *consistent*: with its own
//! dynamics `A_σ`, every indicator moves to the side that implies the same mode. The side of an
//! indicator `g = ℓᵀX` that is zero is the sign of its first non-vanishing derivative
//! `ℓᵀA_σᵏX` (k = 0, 1, 2, …), which resolves grazing and simultaneous switches alike.
//! Candidate modes are iterated to a fixed point; if none exists the switch rule of the last
//! candidate is taken (and the next search starts from it).

use faer::Mat;

use crate::impact::{ImpactSystem, Indicator, Mode, Switch};

/// Highest derivative order consulted.
const K_MAX: usize = 8;

/// Sign (+1, −1, or 0 when identically zero to order `K_MAX`) of `ℓᵀX(t)` just after `t`.
///
/// A derivative `ℓᵀy` (`y = Aᵏ X`) counts as zero when it is below round-off of its own terms
/// (`1e-9 Σ|ℓᵢyᵢ|` for the value itself, which root location leaves at ~1e-13 of its terms,
/// `1e-11` for higher orders) or below `1e-12 ‖ℓ‖‖y‖`: the latter catches quantities whose terms
/// are all physically zero (bodies at rest, forces zero) and only carry round-off.
pub fn lex_sign(l: &[f64], a: &Mat<f64>, x: &[f64]) -> f64 {
    let mut out = [0.0];
    lex_signs(std::slice::from_ref(&l), a, x, &mut out);
    out[0]
}

/// [`lex_sign`] of several functionals at once (`out[i]` for `ls[i]`): the derivatives `Aᵏ X`
/// are computed once, as far as the last undecided functional needs them.
pub fn lex_signs<L: AsRef<[f64]>>(ls: &[L], a: &Mat<f64>, x: &[f64], out: &mut [f64]) {
    let n = x.len();
    out.iter_mut().for_each(|o| *o = 0.0);
    let mut open = ls.len();
    // Stack buffers for the usual sizes (no allocation per call).
    let mut stack = [0.0; 128];
    let mut heap = Vec::new();
    let (y, next) = if 2 * n <= stack.len() {
        stack[..2 * n].split_at_mut(n)
    } else {
        heap.resize(2 * n, 0.0);
        heap.split_at_mut(n)
    };
    y.copy_from_slice(x);
    let (mut y, mut next) = (y, next);
    let mut decided = [false; 16];
    let mut decided_heap = Vec::new();
    let decided: &mut [bool] = if ls.len() <= decided.len() {
        &mut decided[..ls.len()]
    } else {
        decided_heap.resize(ls.len(), false);
        &mut decided_heap
    };
    for k in 0..=K_MAX {
        let y_norm = y.iter().map(|v| v * v).sum::<f64>().sqrt();
        let tol = if k == 0 { 1e-9 } else { 1e-11 };
        for (i, l) in ls.iter().enumerate() {
            if decided[i] {
                continue;
            }
            let l = l.as_ref();
            let (mut val, mut scale, mut l2) = (0.0, 0.0, 0.0);
            for (li, yi) in l.iter().zip(y.iter()) {
                let t = li * yi;
                val += t;
                scale += t.abs();
                l2 += li * li;
            }
            let floor = 1e-12 * l2.sqrt() * y_norm;
            if val.abs() > tol * scale && val.abs() > floor {
                out[i] = val.signum();
                decided[i] = true;
                open -= 1;
            }
        }
        if open == 0 || k == K_MAX {
            break;
        }
        mat_vec(a, y, next);
        std::mem::swap(&mut y, &mut next);
    }
}

/// `out = A y`, column by column (contiguous in faer's column-major storage); fixed-size columns
/// for the small first-order systems of lumped machines (4 to 16 states), where a loop of
/// run-time length costs more than its products.
fn mat_vec(a: &Mat<f64>, y: &[f64], out: &mut [f64]) {
    fn fixed<const N: usize>(a: &Mat<f64>, y: &[f64], out: &mut [f64]) {
        let mut acc = [0.0; N];
        for (j, &yj) in y.iter().enumerate().take(N) {
            if yj != 0.0 {
                if let Ok(col) = <&[f64; N]>::try_from(a.col_as_slice(j)) {
                    for i in 0..N {
                        acc[i] += col[i] * yj;
                    }
                }
            }
        }
        out[..N].copy_from_slice(&acc);
    }
    match y.len() {
        4 => fixed::<4>(a, y, out),
        6 => fixed::<6>(a, y, out),
        8 => fixed::<8>(a, y, out),
        10 => fixed::<10>(a, y, out),
        12 => fixed::<12>(a, y, out),
        14 => fixed::<14>(a, y, out),
        16 => fixed::<16>(a, y, out),
        _ => {
            out.iter_mut().for_each(|v| *v = 0.0);
            for (j, &yj) in y.iter().enumerate() {
                if yj != 0.0 {
                    for (nx, aij) in out.iter_mut().zip(a.col_as_slice(j)) {
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

/// Selects a consistent mode at state `x`, starting the iteration from `start`.
/// `matrix(mode)` gives `A_σ`; `vecs` are the vectors of the system's indicators
/// ([`ImpactSystem::indicators`], [`ImpactSystem::indicator_vector`]). Returns the mode,
/// whether it is consistent, and the indicators' signs under that mode's dynamics.
pub fn select_mode(
    sys: &ImpactSystem,
    x: &[f64],
    start: Mode,
    vecs: &[Vec<f64>],
    matrix: &mut dyn FnMut(Mode) -> std::rc::Rc<Mat<f64>>,
) -> (Mode, bool, Vec<f64>) {
    let inds = sys.indicators();
    let switches = sys.switches();
    let implied =
        |m: Mode, signs: &mut [f64], matrix: &mut dyn FnMut(Mode) -> std::rc::Rc<Mat<f64>>| {
            let a = matrix(m);
            lex_signs(vecs, &a, x, signs);
            let sign_of = |ind: Indicator| {
                inds.iter()
                    .position(|&i| i == ind)
                    .map_or(0.0, |p| signs[p])
            };
            implied_mode_of(sys, &switches, &sign_of)
        };
    let mut signs = vec![0.0; vecs.len()];
    let mut cand = start;
    // Modes tried, one bit each (three switch bits: modes 0-7).
    let mut seen = 0u32;
    for _ in 0..16 {
        let next = implied(cand, &mut signs, matrix);
        if next == cand {
            return (cand, true, signs);
        }
        if seen & (1 << (next.0 & 31)) != 0 {
            break;
        }
        seen |= 1 << (cand.0 & 31);
        cand = next;
    }
    let last_signs = signs.clone();
    // No fixed point along the iteration: try every mode.
    let allowed = switches.iter().fold(0u8, |a, &s| a | Mode::bit(s));
    for bits in 0..8u8 {
        let m = Mode(bits);
        if m.0 & !allowed == 0 {
            let next = implied(m, &mut signs, matrix);
            if next == m {
                return (m, true, signs);
            }
        }
    }
    (cand, false, last_signs)
}
