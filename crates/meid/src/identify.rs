//! Experimental modal identification from frequency response functions: poles by the
//! (poly-reference) least-squares complex frequency-domain method with a stabilisation diagram,
//! stable poles selected by a stated rule, residues and mode shapes by least-squares frequency
//! domain (LSFD) with upper and lower residuals.
//!
//! Sources: P. Guillaume, P. Verboven, S. Vanlanduit, H. Van der Auweraer, B. Peeters, "A
//! poly-reference implementation of the least-squares complex frequency-domain estimator",
//! IMAC XXI (2003); B. Peeters, H. Van der Auweraer, P. Guillaume, J. Leuridan, "The PolyMAX
//! frequency-domain method: a new standard for modal parameter estimation?", Shock and
//! Vibration 11 (2004) 395-409 (equations below numbered as there).
//!
//! # Model and data
//!
//! `H_{oi}(ω_k)`, output `o` of `N_o`, input (reference) `i` of `N_i`, at lines `ω_k` in the band
//! `[ω_lo, ω_hi]` (the DC line is left out). The modal model of a receptance (PolyMAX Eq. 12):
//!
//! ```text
//! H(ω) = Σ_r [ R_r/(iω − λ_r) + R_r*/(iω − λ_r*) ] + UR − LR/ω²,   R_r = φ_r l_rᵀ
//! ```
//!
//! with `λ_r = −ζ_r ω_r + iω_r √(1 − ζ_r²)`; a mobility is `iω` times it and an accelerance
//! `(iω)²` times it, so the same poles and residues describe all three (the residuals are those
//! of the receptance).
//!
//! # LSCF / pLSCF (poles)
//!
//! A right matrix-fraction model per output row, in the z domain on the band:
//! `H_o(ω) = B_o(ω) A(ω)⁻¹`, `B_o = Σ_{r=0}^{p} Ω_r β_{o,r}` (1 × N_i), `A = Σ_{r=0}^{p} Ω_r α_r`
//! (N_i × N_i), `Ω_r(ω) = e^{iωΔt r}`, `Δt = 1/(2 f_hi)` (Eqs. 1-2), real coefficients. The
//! linearised equation error `W_o(ω_k) (B_o − H_o A)` (weight `W_o = 1/rms_k |H_o|`, so every
//! output counts alike) gives the normal equations; eliminating the `β_o` (Eqs. 5-7)
//!
//! ```text
//! R_o = Re(X_oᴴX_o),  S_o = Re(X_oᴴY_o),  T_o = Re(Y_oᴴY_o),
//! X_o[k, r] = W_o Ω_r(ω_k),  Y_o[k, (r, i)] = −W_o Ω_r(ω_k) H_{oi}(ω_k),
//! M = 2 Σ_o (T_o − S_oᵀ R_o⁻¹ S_o),   M α = 0
//! ```
//!
//! solved with `α_p = I` (Eq. 8): `[α_0; …; α_{p−1}] = −M_{11}⁻¹ M_{12}`. Every sum over the lines
//! depends on `r − s` only (`Σ_k Ω_r* Ω_s (…)`), so `R, S, T` are built once at the highest order
//! and sliced for the lower ones. The poles are the eigenvalues `z` of the companion matrix of
//! `A` (Eq. 9), `λ = ln(z)/Δt`; the physical ones have `Im λ > 0` (their conjugates come with
//! them: the coefficients are real), `Re λ < 0`, and lie in the band.
//!
//! # Stabilisation and selection
//!
//! Model orders `p = 1 … P`. A pole of order `p` is **stable** in frequency when a pole of order
//! `p − 1` lies within `δ_f` (default 1 %) of its frequency; in damping when that pole's damping
//! ratio is also within `δ_ζ` (5 %) of its own; in vector when, besides, the MAC of their mode
//! shapes (an LSFD with that order's poles, below) is at least `MAC_min` (0.98). With one output
//! the shape is a single number and the vector criterion holds trivially.
//!
//! **Selection rule**: the poles stable in all three are sorted by frequency and grouped, a pole
//! joining a group when it lies within `δ_f` of the group's median frequency; a group is a mode
//! when it holds poles of at least `max(3, ⌈P/4⌉)` orders. Its frequency and damping ratio are
//! those of its median-frequency member; their **uncertainty** is the standard deviation over the
//! group's members (the spread over model orders). With a number of modes asked, the groups with
//! the most orders are kept. Two modes closer than `δ_f` fall in one group.
//!
//! # LSFD (residues, shapes)
//!
//! With the selected poles fixed, per output and input the real unknowns
//! `Re R_r, Im R_r, UR, LR` are the linear least-squares solution (QR) of
//!
//! ```text
//! (iω_k)^d [ Σ_r Re R_r (1/(iω_k − λ_r) + 1/(iω_k − λ_r*)) + Im R_r (i/(iω_k − λ_r) − i/(iω_k − λ_r*))
//!            + UR − LR/ω_k² ] = H(ω_k),     d = 0, 1, 2 (receptance, mobility, accelerance)
//! ```
//!
//! over the real and imaginary parts of every line. The shape `φ_r` is the residue column
//! `R_{·i,r}` of the reference `i` with the largest `Σ_o |R_{oi,r}|²`, divided by its entry of
//! largest modulus (complex shape); the real-normalised shape is it turned by the angle
//! `θ = arg(Σ_o φ_o²)/2` that makes it most nearly real, its real part scaled to a largest
//! entry of +1. **Modal phase collinearity** `MPC = ((μ_1 − μ_2)/(μ_1 + μ_2))²`, `μ` the
//! eigenvalues of `[[Σ x², Σ xy], [Σ xy, Σ y²]]`, `x + iy = φ` (1: a real mode); **mean phase
//! deviation** MPD, the `|φ_o|`-weighted mean angle (degrees) between the entries and that line.
//!
//! # Exponential window
//!
//! An exponential window `e^{−t/τ}` on the records moves every pole by `−σ_w`, `σ_w = 1/τ`:
//! the FRF identified is that of the poles `λ_w = λ − σ_w` (the decaying record `h(t) e^{−σ_w t}`).
//! The stabilisation works on the poles as identified; the modes are reported with
//! `λ = λ_w + σ_w`, so `ω = |λ|`, `ζ = −Re λ/|λ|` exactly (not the first-order `ζ_w − 1/(ωτ)`).
//!
//! # Check of the FRF type
//!
//! For a normal (real) mode of a proportionally damped structure the receptance residues are
//! `R_r = φ_r φ_rᵀ/(2iω_d,r)`, mass-normalised `φ_r` (D. J. Ewins, *Modal Testing: Theory,
//! Practice and Application*, 2nd ed., 2000, ch. 2): imaginary, whatever `ζ_r`, and an
//! exponential window does not turn them (it multiplies `h(t)` by `e^{−σ_w t}` and moves the poles
//! only). FRFs of another type than the one stated by an odd power of `iω` (an accelerance read
//! as a mobility, a mobility as a receptance or an accelerance) are fitted with residues
//! `≈ R_r (iω_r)^{±1}`: turned by 90°, onto the real axis; the fit is then wrong for every mode,
//! and the upper residual has no term in it (the data hold `(iω)^d UR` with their own `d`, the
//! model `(iω)^{d'} UR` with the stated one), so a real upper residual spoils the residues of
//! the outputs that carry it. **Rule**: per mode,
//! the angle `θ_R` of the principal line of its residue column (as for MPD, module docs above;
//! `θ_R ∈ (−90°, 90°]`); a mode with `MPC ≥` [`NEAR_REAL_MPC`] is *turned* when
//! `|θ_R| < 45°` (nearer the real axis than the imaginary one). When more than half of the
//! near-real modes are turned, a warning says the FRFs' stated type is likely wrong by one power
//! of `iω`. A type wrong by two powers (an accelerance read as a receptance) only flips the
//! residues' sign, which the check cannot see without knowing the driving point.
//!
//! The module imports only the base: data in, numbers out.

use faer::linalg::solvers::{Solve, SolveLstsq};
use faer::Mat;
use num_complex::Complex64 as C;
use serde::Serialize;

use crate::{num, Error, Result};

/// Least MPC of a mode whose residues' phase enters the check of the FRF type (module docs,
/// "Check of the FRF type"): a near-real mode, whose residues lie on one line.
pub const NEAR_REAL_MPC: f64 = 0.9;

/// What an FRF's response is per unit force: displacement, velocity or acceleration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum FrfKind {
    /// m/N.
    Receptance,
    /// (m/s)/N.
    Mobility,
    /// (m/s²)/N.
    Accelerance,
}

impl FrfKind {
    /// `d` with `H = (iω)^d × receptance`.
    pub fn power(self) -> i32 {
        match self {
            FrfKind::Receptance => 0,
            FrfKind::Mobility => 1,
            FrfKind::Accelerance => 2,
        }
    }
    /// The name (`receptance`, …).
    pub fn name(self) -> &'static str {
        match self {
            FrfKind::Receptance => "receptance",
            FrfKind::Mobility => "mobility",
            FrfKind::Accelerance => "accelerance",
        }
    }
}

/// FRFs sampled on common lines: `h[o * inputs + i][k]` is output `o`, input `i`, line `k`.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfData {
    pub frequency_hz: Vec<f64>,
    pub outputs: usize,
    pub inputs: usize,
    pub h: Vec<Vec<C>>,
    pub kind: FrfKind,
    /// The decay rate an exponential window added to every pole, `σ_w = 1/τ` (1/s; 0 for none).
    pub window_decay_per_s: f64,
}

/// The stabilisation criteria (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Criteria {
    /// Relative frequency change (default 0.01).
    pub frequency: f64,
    /// Relative damping-ratio change (default 0.05).
    pub damping: f64,
    /// Least MAC between the shapes (default 0.98).
    pub mac: f64,
}

impl Default for Criteria {
    fn default() -> Self {
        Criteria {
            frequency: 0.01,
            damping: 0.05,
            mac: 0.98,
        }
    }
}

/// Settings of [`identify`].
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// Band (Hz); `None`: every line above 0 Hz.
    pub band_hz: Option<(f64, f64)>,
    /// Highest model order `P` (orders 1 … P; default 32).
    pub max_order: usize,
    pub criteria: Criteria,
    /// Modes asked for (`None`: every group the rule accepts).
    pub modes: Option<usize>,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            band_hz: None,
            max_order: 32,
            criteria: Criteria::default(),
            modes: None,
        }
    }
}

/// How a pole of the stabilisation diagram compares with the order below.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, PartialOrd, Ord)]
#[serde(rename_all = "kebab-case")]
pub enum Stability {
    /// No pole of the order below within the frequency criterion.
    New,
    /// Stable in frequency.
    Frequency,
    /// Stable in frequency and damping.
    Damping,
    /// Stable in frequency, damping and vector (MAC).
    Vector,
}

/// A pole of one model order, as identified (window not removed).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Pole {
    pub frequency_hz: f64,
    pub damping_ratio: f64,
    pub stability: Stability,
    #[serde(skip)]
    pub lambda: C,
}

/// The poles of one model order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OrderPoles {
    pub order: usize,
    pub poles: Vec<Pole>,
}

/// An identified mode.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Mode {
    /// Undamped natural frequency `|λ|/2π` (Hz), window removed.
    pub frequency_hz: f64,
    /// `−Re λ/|λ|`, window removed.
    pub damping_ratio: f64,
    /// The damping ratio as identified from the windowed FRFs.
    pub damping_ratio_windowed: f64,
    /// Standard deviations over the stable orders (module docs).
    pub frequency_std_hz: f64,
    pub damping_ratio_std: f64,
    /// Model orders at which the mode is stable in frequency, damping and vector.
    pub stable_orders: usize,
    /// Complex shape at the outputs (largest entry 1), as `[re, im]` pairs.
    pub shape_complex: Vec<[f64; 2]>,
    /// Real-normalised shape (largest entry +1).
    pub shape: Vec<f64>,
    /// Modal phase collinearity (1: real mode).
    pub mpc: f64,
    /// Mean phase deviation (degrees).
    pub mpd_deg: f64,
    /// The reference (input) whose residues give the shape.
    pub reference: usize,
    /// Residues `R_{o,reference}` (receptance units, m/N) as `[re, im]`.
    pub residues: Vec<[f64; 2]>,
}

/// Upper and lower residuals of one output/input pair, and the LSFD fit's relative error.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PairFit {
    pub output: usize,
    pub input: usize,
    /// `UR` (m/N) and `LR` (N⁻¹·m·s⁻²… i.e. the receptance's `−LR/ω²` term), module docs.
    pub upper_residual: f64,
    pub lower_residual: f64,
    /// `‖H − Ĥ‖/‖H‖` over the band.
    pub relative_error: f64,
}

/// The result of [`identify`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Identification {
    pub modes: Vec<Mode>,
    pub band_hz: (f64, f64),
    pub lines: usize,
    pub max_order: usize,
    pub criteria: Criteria,
    /// Orders a group needs to be a mode (module docs).
    pub min_stable_orders: usize,
    pub window_decay_per_s: f64,
    pub fits: Vec<PairFit>,
    pub diagram: Vec<OrderPoles>,
    pub warnings: Vec<String>,
    pub notes: Vec<String>,
}

/// MAC of two complex vectors, `|aᴴb|²/((aᴴa)(bᴴb))` (0 for a zero vector).
pub fn mac(a: &[C], b: &[C]) -> f64 {
    let ab: C = a.iter().zip(b).map(|(x, y)| x.conj() * y).sum();
    let aa: f64 = a.iter().map(|x| x.norm_sqr()).sum();
    let bb: f64 = b.iter().map(|x| x.norm_sqr()).sum();
    if aa > 0.0 && bb > 0.0 {
        ab.norm_sqr() / (aa * bb)
    } else {
        0.0
    }
}

/// MAC of two real vectors.
pub fn mac_real(a: &[f64], b: &[f64]) -> f64 {
    let ab: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    let aa: f64 = a.iter().map(|x| x * x).sum();
    let bb: f64 = b.iter().map(|x| x * x).sum();
    if aa > 0.0 && bb > 0.0 {
        ab * ab / (aa * bb)
    } else {
        0.0
    }
}

/// The lines of the band and their indices.
struct Band {
    k: Vec<usize>,
    w: Vec<f64>,
    lo: f64,
    hi: f64,
}

fn band(d: &FrfData, s: &Settings) -> Result<Band> {
    let f = &d.frequency_hz;
    let positive: Vec<f64> = f.iter().copied().filter(|v| *v > 0.0).collect();
    let (Some(&first), Some(&last)) = (positive.first(), positive.last()) else {
        return Err(Error::invalid("FRF", "no line above 0 Hz"));
    };
    let (lo, hi) = s.band_hz.unwrap_or((first, last));
    if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && hi > lo) {
        return Err(Error::invalid(
            "band",
            format!("{}..{} Hz: expected 0 ≤ LO < HI", num(lo), num(hi)),
        ));
    }
    let k: Vec<usize> = (0..f.len())
        .filter(|&k| f[k] > 0.0 && f[k] >= lo && f[k] <= hi)
        .collect();
    let w: Vec<f64> = k
        .iter()
        .map(|&k| 2.0 * std::f64::consts::PI * f[k])
        .collect();
    let need = 2 * (s.max_order + 1) * (d.inputs + 1);
    if k.len() < need {
        return Err(Error::invalid(
            "band",
            format!(
                "{}..{} Hz holds {} lines of the FRFs ({}..{} Hz); model order {} with {} reference(s) needs at least {need}: widen the band or lower --max-order",
                num(lo),
                num(hi),
                k.len(),
                num(first),
                num(last),
                s.max_order,
                d.inputs
            ),
        ));
    }
    Ok(Band {
        k,
        w,
        lo,
        hi: hi.min(last),
    })
}

/// Checks the shapes of the data.
fn check(d: &FrfData, s: &Settings) -> Result<()> {
    if d.outputs == 0 || d.inputs == 0 || d.h.len() != d.outputs * d.inputs {
        return Err(Error::invalid(
            "FRF",
            format!(
                "{} functions for {} outputs × {} inputs",
                d.h.len(),
                d.outputs,
                d.inputs
            ),
        ));
    }
    if let Some(k) = d.h.iter().position(|h| h.len() != d.frequency_hz.len()) {
        return Err(Error::invalid(
            "FRF",
            format!(
                "function {} has {} lines, the frequencies {}",
                k + 1,
                d.h[k].len(),
                d.frequency_hz.len()
            ),
        ));
    }
    if s.max_order == 0 || s.max_order > 200 {
        return Err(Error::invalid(
            "max-order",
            format!("{}: expected 1 … 200", s.max_order),
        ));
    }
    for (j, h) in d.h.iter().enumerate() {
        if let Some(k) = h
            .iter()
            .position(|v| !(v.re.is_finite() && v.im.is_finite()))
        {
            return Err(Error::invalid(
                "FRF",
                format!(
                    "function {} (output {}, input {}) at {} Hz is not a finite number",
                    j + 1,
                    j / d.inputs + 1,
                    j % d.inputs + 1,
                    num(d.frequency_hz[k])
                ),
            ));
        }
    }
    if !(d.window_decay_per_s.is_finite() && d.window_decay_per_s >= 0.0) {
        return Err(Error::invalid(
            "window decay",
            format!("{}: expected ≥ 0 1/s", num(d.window_decay_per_s)),
        ));
    }
    Ok(())
}

/// The reduced normal equations of LSCF at the highest order, per output summed:
/// `r_d[d + P] = Σ_k Ω_d`, `s_d[o][i][d + P] = Σ_k W² Ω_d H_oi`, `t_d[o][i][j][d + P] =
/// Σ_k W² Ω_d conj(H_oi) H_oj` with `Ω_d = e^{iω_kΔt d}`, `d = s − r ∈ [−P, P]`.
struct Sums {
    p: usize,
    ni: usize,
    r: Vec<C>,
    s: Vec<Vec<Vec<C>>>,
    t: Vec<Vec<Vec<Vec<C>>>>,
    w2: Vec<f64>,
}

fn sums(d: &FrfData, b: &Band, dt: f64, p: usize) -> Sums {
    let (no, ni) = (d.outputs, d.inputs);
    let nd = 2 * p + 1;
    let mut out = Sums {
        p,
        ni,
        r: vec![C::new(0.0, 0.0); nd],
        s: vec![vec![vec![C::new(0.0, 0.0); nd]; ni]; no],
        t: vec![vec![vec![vec![C::new(0.0, 0.0); nd]; ni]; ni]; no],
        w2: vec![0.0; no],
    };
    for o in 0..no {
        let ms: f64 = (0..ni)
            .flat_map(|i| b.k.iter().map(move |&k| (i, k)))
            .map(|(i, k)| d.h[o * ni + i][k].norm_sqr())
            .sum::<f64>()
            / (b.k.len() * ni) as f64;
        out.w2[o] = if ms > 0.0 { 1.0 / ms } else { 0.0 };
    }
    for (n, &k) in b.k.iter().enumerate() {
        let omega: Vec<C> = (0..nd)
            .map(|j| C::from_polar(1.0, b.w[n] * dt * (j as f64 - p as f64)))
            .collect();
        for j in 0..nd {
            out.r[j] += omega[j];
        }
        for o in 0..no {
            let w2 = out.w2[o];
            for i in 0..ni {
                let hi = d.h[o * ni + i][k];
                for j in 0..nd {
                    out.s[o][i][j] += omega[j] * hi * w2;
                }
                for jj in 0..ni {
                    let c = hi.conj() * d.h[o * ni + jj][k] * w2;
                    for j in 0..nd {
                        out.t[o][i][jj][j] += omega[j] * c;
                    }
                }
            }
        }
    }
    out
}

/// The denominator coefficients of order `p`, negated: `−[α_0; …; α_{p−1}]` (p·N_i × N_i, module
/// docs).
fn lscf_alpha(sm: &Sums, p: usize) -> Result<Mat<f64>> {
    let (ni, pp) = (sm.ni, sm.p);
    let n1 = p + 1;
    let nb = n1 * ni;
    let at = |d: i64| (d + pp as i64) as usize;
    // R[r][s] = Re Σ conj(Ω_r) Ω_s = Re r_d[s − r].
    let rm = Mat::<f64>::from_fn(n1, n1, |r, s| sm.r[at(s as i64 - r as i64)].re);
    let lu = rm.partial_piv_lu();
    let mut m = Mat::<f64>::zeros(nb, nb);
    for o in 0..sm.s.len() {
        if sm.w2[o] == 0.0 {
            continue;
        }
        // S[r][(s, i)] = Re Σ conj(Ω_r)(−Ω_s H_oi) W², T[(r, i)][(s, j)] = Re Σ conj(Ω_r H_oi) Ω_s H_oj W².
        let so = Mat::<f64>::from_fn(n1, nb, |r, c| {
            let (s, i) = (c / ni, c % ni);
            -sm.s[o][i][at(s as i64 - r as i64)].re
        });
        let rinv_s = lu.solve(&so);
        let sts = so.transpose() * &rinv_s;
        for a in 0..nb {
            for c in 0..nb {
                let (r, i) = (a / ni, a % ni);
                let (s, j) = (c / ni, c % ni);
                // Rescaled R: R is the same for all outputs, S and T carry W².
                let t = sm.t[o][i][j][at(s as i64 - r as i64)].re;
                m[(a, c)] += 2.0 * (t - sts[(a, c)] / sm.w2[o]);
            }
        }
    }
    let k = p * ni;
    let m11 = Mat::<f64>::from_fn(k, k, |a, c| m[(a, c)]);
    let m12 = Mat::<f64>::from_fn(k, ni, |a, c| m[(a, k + c)]);
    let minus_alpha = m11.partial_piv_lu().solve(&m12);
    for a in 0..k {
        for c in 0..ni {
            if !minus_alpha[(a, c)].is_finite() {
                return Err(Error::numerical(
                    "LSCF",
                    format!("order {p}: the normal equations are singular"),
                ));
            }
        }
    }
    Ok(minus_alpha)
}

/// The poles of order `p`: eigenvalues of the companion matrix, `λ = ln z/Δt`, the physical ones
/// in the band (module docs), sorted by frequency.
fn poles_of_order(sm: &Sums, p: usize, dt: f64, b: &Band) -> Result<Vec<C>> {
    let ni = sm.ni;
    let minus_alpha = lscf_alpha(sm, p)?;
    let n = p * ni;
    let mut c = Mat::<f64>::zeros(n, n);
    for a in 0..n.saturating_sub(ni) {
        c[(a, a + ni)] = 1.0;
    }
    for i in 0..ni {
        for col in 0..n {
            // Last block row: −α_r (rows of α_r are the block's rows).
            let (r, j) = (col / ni, col % ni);
            c[(n - ni + i, col)] = minus_alpha[(r * ni + i, j)];
        }
    }
    let z = c
        .eigenvalues()
        .map_err(|e| Error::numerical("LSCF companion matrix", format!("order {p}: {e:?}")))?;
    let two_pi = 2.0 * std::f64::consts::PI;
    let mut out: Vec<C> = z
        .into_iter()
        .filter(|z| z.norm() > 0.0)
        .map(|z| C::new(z.norm().ln(), z.arg()) / dt)
        .filter(|l| l.im > 0.0 && l.re < 0.0)
        .filter(|l| {
            let f = l.norm() / two_pi;
            f >= b.lo && f <= b.hi
        })
        .collect();
    out.sort_by(|a, b| a.norm().total_cmp(&b.norm()));
    Ok(out)
}

/// The LSFD fit with poles `lambda` (module docs): per pair, the residues (receptance), UR, LR
/// and the relative error.
struct Lsfd {
    residues: Vec<Vec<C>>,
    upper: Vec<f64>,
    lower: Vec<f64>,
    error: Vec<f64>,
}

fn lsfd(d: &FrfData, b: &Band, lambda: &[C]) -> Result<Lsfd> {
    let (m, nl) = (lambda.len(), b.k.len());
    let ncol = 2 * m + 2;
    let pw = d.kind.power();
    let mut a = Mat::<f64>::zeros(2 * nl, ncol);
    for (n, &w) in b.w.iter().enumerate() {
        let s = C::new(0.0, w);
        let g = s.powi(pw);
        let mut put = |col: usize, v: C| {
            a[(2 * n, col)] = v.re;
            a[(2 * n + 1, col)] = v.im;
        };
        for (r, l) in lambda.iter().enumerate() {
            let p1 = (s - l).inv();
            let p2 = (s - l.conj()).inv();
            put(2 * r, g * (p1 + p2));
            put(2 * r + 1, g * C::new(0.0, 1.0) * (p1 - p2));
        }
        put(2 * m, g);
        put(2 * m + 1, -g / (w * w));
    }
    // Columns scaled to unit norm for the QR.
    let scale: Vec<f64> = (0..ncol)
        .map(|c| {
            let nrm = (0..2 * nl).map(|r| a[(r, c)].powi(2)).sum::<f64>().sqrt();
            if nrm > 0.0 {
                1.0 / nrm
            } else {
                1.0
            }
        })
        .collect();
    let asc = Mat::<f64>::from_fn(2 * nl, ncol, |r, c| a[(r, c)] * scale[c]);
    let pairs = d.h.len();
    let rhs = Mat::<f64>::from_fn(2 * nl, pairs, |r, j| {
        let v = d.h[j][b.k[r / 2]];
        if r % 2 == 0 {
            v.re
        } else {
            v.im
        }
    });
    let x = asc.qr().solve_lstsq(&rhs);
    let fit = &asc * &x;
    let mut out = Lsfd {
        residues: Vec::with_capacity(pairs),
        upper: Vec::with_capacity(pairs),
        lower: Vec::with_capacity(pairs),
        error: Vec::with_capacity(pairs),
    };
    for j in 0..pairs {
        let c = |col: usize| x[(col, j)] * scale[col];
        out.residues
            .push((0..m).map(|r| C::new(c(2 * r), c(2 * r + 1))).collect());
        out.upper.push(c(2 * m));
        out.lower.push(c(2 * m + 1));
        let (mut e, mut h) = (0.0, 0.0);
        for r in 0..2 * nl {
            e += (fit[(r, j)] - rhs[(r, j)]).powi(2);
            h += rhs[(r, j)].powi(2);
        }
        out.error.push(if h > 0.0 { (e / h).sqrt() } else { 0.0 });
    }
    if out
        .residues
        .iter()
        .flatten()
        .any(|v| !(v.re.is_finite() && v.im.is_finite()))
    {
        return Err(Error::numerical("LSFD", "the residues are not finite"));
    }
    Ok(out)
}

/// Per mode, the reference of largest residue norm and its residue column (outputs).
fn shape_columns(d: &FrfData, fit: &Lsfd, m: usize) -> Vec<(usize, Vec<C>)> {
    (0..m)
        .map(|r| {
            let col = |i: usize| -> Vec<C> {
                (0..d.outputs)
                    .map(|o| fit.residues[o * d.inputs + i][r])
                    .collect()
            };
            let best = (0..d.inputs)
                .max_by(|&a, &b| {
                    let na: f64 = col(a).iter().map(|v| v.norm_sqr()).sum();
                    let nb: f64 = col(b).iter().map(|v| v.norm_sqr()).sum();
                    na.total_cmp(&nb)
                })
                .unwrap_or(0);
            (best, col(best))
        })
        .collect()
}

/// The stabilisation diagram: poles per order, each marked against the order below.
fn diagram(d: &FrfData, b: &Band, s: &Settings, sm: &Sums, dt: f64) -> Result<Vec<OrderPoles>> {
    let cr = s.criteria;
    let mut out: Vec<OrderPoles> = Vec::with_capacity(s.max_order);
    let mut prev: Vec<(C, Vec<C>)> = Vec::new();
    for p in 1..=s.max_order {
        let lambda = poles_of_order(sm, p, dt, b)?;
        let shapes: Vec<Vec<C>> = if lambda.is_empty() {
            Vec::new()
        } else {
            let fit = lsfd(d, b, &lambda)?;
            shape_columns(d, &fit, lambda.len())
                .into_iter()
                .map(|x| x.1)
                .collect()
        };
        let mut poles = Vec::with_capacity(lambda.len());
        for (l, v) in lambda.iter().zip(&shapes) {
            let (f, z) = (l.norm(), -l.re / l.norm());
            let near = prev
                .iter()
                .min_by(|a, b| (a.0.norm() - f).abs().total_cmp(&(b.0.norm() - f).abs()));
            let stability = match near {
                Some((q, u)) if (q.norm() - f).abs() <= cr.frequency * f => {
                    let zq = -q.re / q.norm();
                    if (zq - z).abs() > cr.damping * z {
                        Stability::Frequency
                    } else if mac(u, v) < cr.mac {
                        Stability::Damping
                    } else {
                        Stability::Vector
                    }
                }
                _ => Stability::New,
            };
            poles.push(Pole {
                frequency_hz: f / (2.0 * std::f64::consts::PI),
                damping_ratio: z,
                stability,
                lambda: *l,
            });
        }
        prev = lambda.into_iter().zip(shapes).collect();
        out.push(OrderPoles { order: p, poles });
    }
    Ok(out)
}

/// Groups of stable poles (module docs): `(pole, order)` members, sorted by frequency.
fn groups(diagram: &[OrderPoles], cr: &Criteria) -> Vec<Vec<(C, usize)>> {
    let mut stable: Vec<(C, usize)> = diagram
        .iter()
        .flat_map(|o| {
            o.poles
                .iter()
                .filter(|p| p.stability == Stability::Vector)
                .map(move |p| (p.lambda, o.order))
        })
        .collect();
    stable.sort_by(|a, b| a.0.norm().total_cmp(&b.0.norm()));
    let mut out: Vec<Vec<(C, usize)>> = Vec::new();
    for m in stable {
        let joins = out.last().is_some_and(|g| {
            let med = g[g.len() / 2].0.norm();
            (m.0.norm() - med).abs() <= cr.frequency * med
        });
        if joins {
            if let Some(g) = out.last_mut() {
                g.push(m);
            }
        } else {
            out.push(vec![m]);
        }
    }
    out
}

fn std_dev(v: &[f64]) -> f64 {
    let n = v.len() as f64;
    if v.len() < 2 {
        return 0.0;
    }
    let mean = v.iter().sum::<f64>() / n;
    (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
}

/// Complex shape (largest entry 1), real-normalised shape, MPC, MPD (module docs).
pub fn shape_measures(v: &[C]) -> (Vec<C>, Vec<f64>, f64, f64) {
    let big = v
        .iter()
        .copied()
        .max_by(|a, b| a.norm().total_cmp(&b.norm()))
        .unwrap_or(C::new(1.0, 0.0));
    let big = if big.norm() > 0.0 {
        big
    } else {
        C::new(1.0, 0.0)
    };
    let complex: Vec<C> = v.iter().map(|x| x / big).collect();
    let sq: C = complex.iter().map(|x| x * x).sum();
    let turn = C::from_polar(1.0, -sq.arg() / 2.0);
    let re: Vec<f64> = complex.iter().map(|x| (x * turn).re).collect();
    let top = re
        .iter()
        .copied()
        .max_by(|a, b| a.abs().total_cmp(&b.abs()))
        .unwrap_or(1.0);
    let real: Vec<f64> = re
        .iter()
        .map(|x| if top != 0.0 { x / top } else { *x })
        .collect();
    let (sxx, syy, sxy) = complex.iter().fold((0.0, 0.0, 0.0), |(a, b, c), x| {
        (a + x.re * x.re, b + x.im * x.im, c + x.re * x.im)
    });
    let tr = sxx + syy;
    let disc = ((sxx - syy).powi(2) + 4.0 * sxy * sxy).sqrt();
    let mpc = if tr > 0.0 { (disc / tr).powi(2) } else { 1.0 };
    // The principal line's angle and each entry's deviation from it (mod π).
    let line = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let (mut num_, mut den) = (0.0, 0.0);
    for x in &complex {
        if x.norm() > 0.0 {
            let mut dev = (x.arg() - line).rem_euclid(std::f64::consts::PI);
            if dev > std::f64::consts::FRAC_PI_2 {
                dev = std::f64::consts::PI - dev;
            }
            num_ += x.norm() * dev;
            den += x.norm();
        }
    }
    let mpd = if den > 0.0 {
        (num_ / den).to_degrees()
    } else {
        0.0
    };
    (complex, real, mpc, mpd)
}

/// Identifies the modes of `d` (module docs).
pub fn identify(d: &FrfData, s: &Settings) -> Result<Identification> {
    check(d, s)?;
    let b = band(d, s)?;
    let dt = 1.0 / (2.0 * b.hi);
    let sm = sums(d, &b, dt, s.max_order);
    let diagram = diagram(d, &b, s, &sm, dt)?;
    let min_orders = 3.max(s.max_order.div_ceil(4));
    let mut warnings = Vec::new();
    let mut notes = Vec::new();
    let mut chosen: Vec<Vec<(C, usize)>> = groups(&diagram, &s.criteria)
        .into_iter()
        .filter(|g| {
            let mut orders: Vec<usize> = g.iter().map(|m| m.1).collect();
            orders.sort_unstable();
            orders.dedup();
            orders.len() >= min_orders
        })
        .collect();
    if let Some(n) = s.modes {
        if chosen.len() > n {
            chosen.sort_by_key(|g| std::cmp::Reverse(g.len()));
            chosen.truncate(n);
            chosen.sort_by(|a, b| a[0].0.norm().total_cmp(&b[0].0.norm()));
        } else if chosen.len() < n {
            warnings.push(format!(
                "{n} modes asked, {} found stable in {}..{} Hz at {min_orders} or more of the orders 1..{}: raise --max-order, widen the band, or check the coherence",
                chosen.len(),
                num(b.lo),
                num(b.hi),
                s.max_order
            ));
        }
        if n > d.outputs {
            warnings.push(format!(
                "{n} modes asked from {} measured point(s): their shapes span at most {} dimension(s), so the shapes cannot tell the modes apart (MAC between them is meaningless); measure more points",
                d.outputs, d.outputs
            ));
        }
    }
    if d.outputs == 1 {
        notes.push("one output: each shape is a single number and the vector (MAC) criterion of the stabilisation holds trivially".into());
    }
    let picked: Vec<(C, f64, f64, usize)> = chosen
        .iter()
        .map(|g| {
            let sw = d.window_decay_per_s;
            let fr: Vec<f64> = g
                .iter()
                .map(|m| (m.0 + sw).norm() / (2.0 * std::f64::consts::PI))
                .collect();
            let zr: Vec<f64> = g
                .iter()
                .map(|m| -(m.0 + sw).re / (m.0 + sw).norm())
                .collect();
            let mut orders: Vec<usize> = g.iter().map(|m| m.1).collect();
            orders.sort_unstable();
            orders.dedup();
            (g[g.len() / 2].0, std_dev(&fr), std_dev(&zr), orders.len())
        })
        .collect();
    let lambda: Vec<C> = picked.iter().map(|p| p.0).collect();
    let (modes, fits) = if lambda.is_empty() {
        warnings.push(format!(
            "no mode found: no pole is stable (frequency {} %, damping {} %, MAC {}) at {min_orders} or more of the orders 1..{} in {}..{} Hz",
            s.criteria.frequency * 100.0,
            s.criteria.damping * 100.0,
            s.criteria.mac,
            s.max_order,
            num(b.lo),
            num(b.hi)
        ));
        (Vec::new(), Vec::new())
    } else {
        finish(d, &b, &picked, &mut warnings)?
    };
    Ok(Identification {
        modes,
        band_hz: (b.lo, b.hi),
        lines: b.k.len(),
        max_order: s.max_order,
        criteria: s.criteria,
        min_stable_orders: min_orders,
        window_decay_per_s: d.window_decay_per_s,
        fits,
        diagram,
        warnings,
        notes,
    })
}

/// The final LSFD with the selected poles: modes and pair fits.
fn finish(
    d: &FrfData,
    b: &Band,
    picked: &[(C, f64, f64, usize)],
    warnings: &mut Vec<String>,
) -> Result<(Vec<Mode>, Vec<PairFit>)> {
    let lambda: Vec<C> = picked.iter().map(|p| p.0).collect();
    let fit = lsfd(d, b, &lambda)?;
    let cols = shape_columns(d, &fit, lambda.len());
    let mut modes = Vec::with_capacity(lambda.len());
    let mut angles = Vec::with_capacity(lambda.len());
    for ((l, fs, zs, n), (reference, col)) in picked.iter().zip(cols) {
        let lc = l + d.window_decay_per_s;
        let w = lc.norm();
        let zeta = -lc.re / w;
        if zeta <= 0.0 {
            warnings.push(format!(
                "the mode at {} Hz has damping ratio {} once the window's decay σ_w = {} 1/s is removed (as identified {}): the window's time constant or the records do not fit",
                num(w / (2.0 * std::f64::consts::PI)),
                num(zeta),
                num(d.window_decay_per_s),
                num(-l.re / l.norm())
            ));
        }
        let (complex, real, mpc, mpd) = shape_measures(&col);
        angles.push(principal_line_deg(&col));
        modes.push(Mode {
            frequency_hz: w / (2.0 * std::f64::consts::PI),
            damping_ratio: zeta,
            damping_ratio_windowed: -l.re / l.norm(),
            frequency_std_hz: *fs,
            damping_ratio_std: *zs,
            stable_orders: *n,
            shape_complex: complex.iter().map(|v| [v.re, v.im]).collect(),
            shape: real,
            mpc,
            mpd_deg: mpd,
            reference,
            residues: col.iter().map(|v| [v.re, v.im]).collect(),
        });
    }
    if let Some(w) = type_check(d.kind, &modes, &angles) {
        warnings.push(w);
    }
    let fits = (0..d.h.len())
        .map(|j| PairFit {
            output: j / d.inputs,
            input: j % d.inputs,
            upper_residual: fit.upper[j],
            lower_residual: fit.lower[j],
            relative_error: fit.error[j],
        })
        .collect();
    Ok((modes, fits))
}

/// The angle (degrees, in (−90°, 90°]) of the principal line of the complex numbers `v`:
/// `θ = ½ atan2(2 Σ xy, Σ x² − Σ y²)`, `x + iy = v` (as for MPD, module docs).
pub fn principal_line_deg(v: &[C]) -> f64 {
    let (sxx, syy, sxy) = v.iter().fold((0.0, 0.0, 0.0), |(a, b, c), x| {
        (a + x.re * x.re, b + x.im * x.im, c + x.re * x.im)
    });
    let deg = (0.5 * (2.0 * sxy).atan2(sxx - syy)).to_degrees();
    if deg <= -90.0 {
        deg + 180.0
    } else {
        deg
    }
}

/// The check of the FRF type (module docs): a warning when more than half of the near-real modes
/// (MPC ≥ [`NEAR_REAL_MPC`]) have residues whose principal line (`angles`, degrees) lies within
/// 45° of the real axis.
fn type_check(kind: FrfKind, modes: &[Mode], angles: &[f64]) -> Option<String> {
    let near_real: Vec<(&Mode, f64)> = modes
        .iter()
        .zip(angles)
        .filter(|(m, _)| m.mpc >= NEAR_REAL_MPC)
        .map(|(m, a)| (m, *a))
        .collect();
    let turned: Vec<String> = near_real
        .iter()
        .filter(|(_, a)| a.abs() < 45.0)
        .map(|(m, a)| format!("{:.2} Hz at {:.0}°", m.frequency_hz, a))
        .collect();
    if turned.is_empty() || 2 * turned.len() <= near_real.len() {
        return None;
    }
    Some(format!(
        "the residues of {} of the {} near-real mode(s) lie nearer the real axis than the imaginary one ({}), where a normal mode's receptance residues φφᵀ/(2iω_d) are imaginary: the FRFs, stated as {}, are likely off by one power of iω (an accelerance read as a mobility, a mobility as a receptance or an accelerance); check the FRF type",
        turned.len(),
        near_real.len(),
        turned.join(", "),
        kind.name()
    ))
}
