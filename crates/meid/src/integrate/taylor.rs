//! Taylor steps of one mode, `Ẋ = A X` (or `Ẋ = A X + b` with a constant forcing, by adding
//! [`TaylorMatrix::forced_coefficients`]): the truncated series
//!
//! ```text
//! X(s) = Σ_{k≤P} c_k s^k,   c_k = A^k X₀ / k! = A c_{k−1} / k,   P = 24,
//! ```
//!
//! valid on `[0, τ]` with `τ = r/ρ`, `r = 2.2`, `ρ = ‖D⁻¹AD‖_∞` and
//! `D = diag(1/ν, …, 1/ν, 1, …, 1)` (positions scaled by `ν = √‖A₂₁‖_∞`, the stiffness block's
//! size). Then `‖D⁻¹A^k X₀‖_∞ ≤ ρ^k ‖D⁻¹X₀‖_∞`, so the remainder on `[0, τ]` is at most
//! `Σ_{k>P} r^k/k! < 2.6e-17` of `‖D⁻¹X₀‖_∞`, a quarter of the unit round-off `2⁻⁵³`: the
//! series *is* the exact solution there (the terms peak at `r²/2 = 2.4` and sum to at most
//! `e^r ≈ 9`, so evaluating it loses no more than a few ulps). `r` is the longest reach that
//! keeps the truncation that far below round-off at `P = 24` (at `r = 2.3` it is 0.7 of it).
//! For the first-order form `ρ` is about the fastest frequency, so `τ` is about a third of the
//! fastest period.
//!
//! A step costs `P` products with the lower half of `A` (for `A = [[0, I], [A₂₁, A₂₂]]` the upper
//! half of `c_k` is the lower half of `c_{k−1}` over `k`) and no eigen-decomposition; a linear
//! functional `ℓᵀX(s)` is the polynomial `Σ (ℓᵀc_k) s^k`, cheap to evaluate and with an explicit
//! curvature bound for the event search ([`super::roots`]). The exact integrator
//! ([`super::exact`]) takes Taylor steps for the first stretches of each mode and builds the
//! closed form ([`super::propagator`]) only for modes that stay long. Hand-written: it is a
//! dozen lines on slices, and the structure of `A` (and no allocation per step) is what makes
//! it fast.

use faer::Mat;

use super::roots::Scalar;
use crate::impact::SparseVec;

/// Order `P` of the series.
pub const ORDER: usize = 24;

/// Reach `r` of a step in units of `1/ρ` (the truncation is below `Σ_{k>P} r^k/k! < 2.6e-17`).
const REACH: f64 = 2.2;

/// A mode's first-order matrix prepared for Taylor steps: its growth rate `ρ` and the rows that
/// take products.
#[derive(Debug, Clone)]
pub struct TaylorMatrix {
    n: usize,
    /// `A = [[0, I], [A₂₁, A₂₂]]`: only the lower rows are stored and multiplied.
    structured: bool,
    /// Rows of `A` from `first_row` on (all rows, or the lower half when `structured`), stored
    /// column by column: `cols[j·m + i] = A[first_row + i, j]` with `m` rows kept.
    cols: Vec<f64>,
    rate: f64,
    /// Structured with `A₂₂ ≠ 0` (some damping acts).
    damped: bool,
}

impl TaylorMatrix {
    /// Prepares `a` (square); `None` when it is not square or has non-finite entries.
    pub fn new(a: &Mat<f64>) -> Option<Self> {
        let n = a.nrows();
        if a.ncols() != n {
            return None;
        }
        let mut buf = Vec::with_capacity(n * n);
        for j in 0..n {
            buf.extend_from_slice(a.col_as_slice(j));
        }
        Self::from_col_major(n, &buf)
    }

    /// Prepares the `n × n` matrix stored column-major in `a` (`a[j·n + i] = A_ij`); `None` when
    /// `a.len() != n²` or an entry is not finite.
    pub fn from_col_major(n: usize, a: &[f64]) -> Option<Self> {
        if a.len() != n * n || !a.iter().all(|v| v.is_finite()) {
            return None;
        }
        let nd = n / 2;
        let col = |j: usize| &a[j * n..(j + 1) * n];
        // Row sums of |A| over the position columns and over the velocity columns (stack
        // buffers for the usual sizes).
        let mut stack = [0.0; 64];
        let mut heap = Vec::new();
        let (sum_x, sum_v) = if 2 * n <= stack.len() {
            stack[..2 * n].split_at_mut(n)
        } else {
            heap.resize(2 * n, 0.0);
            heap.split_at_mut(n)
        };
        for (j, c) in a.chunks_exact(n.max(1)).enumerate() {
            let sums = if j < nd { &mut *sum_x } else { &mut *sum_v };
            for (r, v) in sums.iter_mut().zip(c) {
                *r += v.abs();
            }
        }
        // ν² = ‖A₂₁‖_∞: the largest row sum of |A[nd.., ..nd]|.
        let r21 = sum_x[nd..].iter().fold(0.0_f64, |m, v| m.max(*v));
        let nu = if r21 > 0.0 { r21.sqrt() } else { 1.0 };
        // Row sums of |D⁻¹AD| with d = 1/ν for positions, 1 for velocities:
        // |a_ij| d_j / d_i.
        let rate = (0..n).fold(0.0_f64, |m, i| {
            let row = sum_x[i] / nu + sum_v[i];
            m.max(if i < nd { row * nu } else { row })
        });
        let structured = n.is_multiple_of(2)
            && (0..n).all(|j| {
                col(j)[..nd]
                    .iter()
                    .enumerate()
                    .all(|(i, v)| *v == f64::from(j == nd + i))
            });
        if !rate.is_finite() {
            return None;
        }
        let first_row = if structured { nd } else { 0 };
        let mut cols = Vec::with_capacity((n - first_row) * n);
        for j in 0..n {
            cols.extend_from_slice(&col(j)[first_row..]);
        }
        let damped = structured && cols[nd * nd..].iter().any(|v| *v != 0.0);
        Some(Self {
            n,
            structured,
            cols,
            rate,
            damped,
        })
    }

    /// Dimension `n` of the state.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// The growth rate `ρ = ‖D⁻¹AD‖_∞` (1/s).
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// How far a step reaches: `τ = 2.2/ρ` (s).
    pub fn validity(&self) -> f64 {
        if self.rate > 0.0 {
            REACH / self.rate
        } else {
            f64::INFINITY
        }
    }

    /// The lowest degree `d ≤ P` whose truncation on `[0, len]` is bounded as tightly as the
    /// full series on its validity: [`degree_for_reach`] of `r = ρ·len`.
    pub fn degree(&self, len: f64) -> usize {
        degree_for_reach(self.rate * len)
    }

    /// The time scale `2π/ρ` (s) used by the event search.
    pub fn period(&self) -> f64 {
        if self.rate > 0.0 {
            2.0 * std::f64::consts::PI / self.rate
        } else {
            f64::INFINITY
        }
    }

    /// Writes `c_0 … c_P` (rows of `n`, one after the other) from `x0` into `coef`.
    ///
    /// # Panics
    /// When `x0.len() != n` or `coef.len() != (P + 1)·n`.
    pub fn expand(&self, x0: &[f64], coef: &mut [f64]) {
        let n = self.n;
        assert_eq!(x0.len(), n, "Taylor expansion: state length");
        assert_eq!(
            coef.len(),
            (ORDER + 1) * n,
            "Taylor expansion: buffer length"
        );
        let nd = n / 2;
        // Small lumped machines: fixed sizes, fully unrolled (the loops below spend more on
        // their own overhead than on the few products of a column of 2–8 entries).
        if self.structured {
            match nd {
                2 => return self.expand_small::<2, 4>(x0, coef),
                3 => return self.expand_small::<3, 6>(x0, coef),
                4 => return self.expand_small::<4, 8>(x0, coef),
                5 => return self.expand_small::<5, 10>(x0, coef),
                6 => return self.expand_small::<6, 12>(x0, coef),
                7 => return self.expand_small::<7, 14>(x0, coef),
                8 => return self.expand_small::<8, 16>(x0, coef),
                _ => {}
            }
        }
        let first_row = if self.structured { nd } else { 0 };
        let m = n - first_row;
        coef[..n].copy_from_slice(x0);
        // Σ_j A[:, j] c_{k−1, j} over the kept rows, column by column (equal-length slices, so
        // the inner loop has no bounds checks and vectorises).
        let mut acc = vec![0.0; m];
        for k in 1..=ORDER {
            let (done, rest) = coef.split_at_mut(k * n);
            let prev = &done[(k - 1) * n..];
            let next = &mut rest[..n];
            let inv = 1.0 / k as f64;
            if self.structured {
                for i in 0..nd {
                    next[i] = prev[nd + i] * inv;
                }
            }
            acc.fill(0.0);
            for (j, &pj) in prev.iter().enumerate() {
                if pj != 0.0 {
                    axpy(&mut acc, &self.cols[j * m..j * m + m], pj);
                }
            }
            for (nx, v) in next[first_row..].iter_mut().zip(&acc) {
                *nx = v * inv;
            }
        }
    }
}

impl TaylorMatrix {
    /// The coefficients of the forced response from rest, `X_b(s) = ∫₀^s e^{Au} b du =
    /// Σ_{k≥1} A^{k−1} b s^k / k!`, written as `c_0 … c_P` (`c_0 = 0`) into `coef`. With a
    /// constant forcing (`Ẋ = A X + b`) a step's coefficients are [`TaylorMatrix::expand`]'s
    /// plus these (the response is linear in `(X₀, b)`); they depend on the mode only, so a
    /// run computes them once per mode. The remainder beyond `P` on `[0, τ]` is below
    /// `2.6e-17 ‖D⁻¹b‖_∞/ρ` (the bound of the homogeneous series applied to `A^{k−1}b`).
    ///
    /// # Panics
    /// When `b.len() != n` or `coef.len() != (P + 1)·n`.
    pub fn forced_coefficients(&self, b: &[f64], coef: &mut [f64]) {
        let n = self.n;
        // `expand(b)` gives d_k = A^k b / k!; c_k = d_{k−1} / k.
        let mut d = vec![0.0; (ORDER + 1) * n];
        self.expand(b, &mut d);
        coef[..n].fill(0.0);
        for k in 1..=ORDER {
            let inv = 1.0 / k as f64;
            for (c, dv) in coef[k * n..(k + 1) * n]
                .iter_mut()
                .zip(&d[(k - 1) * n..k * n])
            {
                *c = dv * inv;
            }
        }
    }

    /// [`TaylorMatrix::expand`] for the structured form with `ND` degrees of freedom
    /// (`N = 2·ND`), on arrays of fixed size.
    fn expand_small<const ND: usize, const N: usize>(&self, x0: &[f64], coef: &mut [f64]) {
        let mut cols = [[0.0; ND]; N];
        for (c, src) in cols.iter_mut().zip(self.cols.chunks_exact(ND)) {
            c.copy_from_slice(src);
        }
        let mut prev = [0.0; N];
        prev.copy_from_slice(&x0[..N]);
        coef[..N].copy_from_slice(&prev);
        for (k, out) in coef[N..].chunks_exact_mut(N).take(ORDER).enumerate() {
            let inv = 1.0 / (k + 1) as f64;
            let mut acc = [0.0; ND];
            for (c, pj) in cols.iter().zip(&prev) {
                for i in 0..ND {
                    acc[i] += c[i] * pj;
                }
            }
            let mut next = [0.0; N];
            for i in 0..ND {
                next[i] = prev[ND + i] * inv;
                next[ND + i] = acc[i] * inv;
            }
            out.copy_from_slice(&next);
            prev = next;
        }
    }
}

/// 10-point Gauss-Legendre rule on [−1, 1]: the positive nodes and their weights.
const GL10_X: [f64; 5] = [
    0.148_874_338_981_631_22,
    0.433_395_394_129_247_2,
    0.679_409_568_299_024_4,
    0.865_063_366_688_984_5,
    0.973_906_528_517_171_7,
];
const GL10_W: [f64; 5] = [
    0.295_524_224_714_752_87,
    0.269_266_719_309_996_35,
    0.219_086_362_515_982_04,
    0.149_451_349_150_580_6,
    0.066_671_344_308_688_14,
];

impl TaylorMatrix {
    /// The energy `∫₀^len ẋᵀ C ẋ ds` dissipated over `[0, len]` of a step with coefficients
    /// `coef` (`len` within the step's validity), for the structured form
    /// `A = [[0, I], [−M⁻¹K, −M⁻¹C]]` with `masses` the diagonal of `M`: then
    /// `ẋᵀCẋ = −Σ_i m_i ẋ_i (A₂₂ ẋ)_i`. `None` when the matrix is not of that form.
    ///
    /// 10-point Gauss-Legendre; the rule's error is `L^21 (10!)^4 / (21 (20!)^3) · max|f⁽²⁰⁾|`.
    /// With `ẋ⁽ʲ⁾ = (AʲX)_velocity`, `|ẋ⁽ʲ⁾| ≤ ρʲ ‖D⁻¹X(s)‖_∞ ≤ ρʲ e^{ρs} ‖D⁻¹X₀‖_∞`, so
    /// `|f⁽²⁰⁾| ≤ (2ρ)^20 e^{2ρL} Σ|C_ij| ‖D⁻¹X₀‖²_∞` (Leibniz), and for `L ≤ 2.2/ρ` the error is
    /// at most `4.4^20 (10!)^4 / (21 (20!)^3) · e^{4.4} ≈ 3.5e-16` of
    /// `L Σ|C_ij| ‖D⁻¹X₀‖²_∞`, the integrand's scale: a few units of round-off in the worst case
    /// (the bound ignores that a damped state does not grow). `work` is scratch space for systems of more
    /// than 8 degrees of freedom (reused between calls).
    ///
    /// # Panics
    /// When `coef` or `masses` do not match the matrix.
    pub fn dissipated(
        &self,
        coef: &[f64],
        masses: &[f64],
        len: f64,
        work: &mut Vec<f64>,
    ) -> Option<f64> {
        if !self.structured {
            return None;
        }
        let nd = self.n / 2;
        assert_eq!(
            coef.len(),
            (ORDER + 1) * self.n,
            "dissipation: coefficients"
        );
        assert_eq!(masses.len(), nd, "dissipation: masses");
        if !self.damped || len <= 0.0 {
            return Some(0.0);
        }
        // The 10 nodes and weights on [0, len].
        let mut s = [0.0; 10];
        let mut w = [0.0; 10];
        for (q, (xi, wi)) in GL10_X.iter().zip(GL10_W).enumerate() {
            s[2 * q] = 0.5 * len * (1.0 - xi);
            s[2 * q + 1] = 0.5 * len * (1.0 + xi);
            w[2 * q] = 0.5 * len * wi;
            w[2 * q + 1] = 0.5 * len * wi;
        }
        let a22 = &self.cols[nd * nd..];
        Some(match nd {
            2 => dissipated_small::<2>(coef, a22, masses, &s, &w),
            3 => dissipated_small::<3>(coef, a22, masses, &s, &w),
            4 => dissipated_small::<4>(coef, a22, masses, &s, &w),
            5 => dissipated_small::<5>(coef, a22, masses, &s, &w),
            6 => dissipated_small::<6>(coef, a22, masses, &s, &w),
            7 => dissipated_small::<7>(coef, a22, masses, &s, &w),
            8 => dissipated_small::<8>(coef, a22, masses, &s, &w),
            _ => {
                // Node by node: ẋ (Horner) and A₂₂ẋ column by column.
                work.clear();
                work.resize(2 * nd, 0.0);
                let (v, av) = work.split_at_mut(nd);
                let mut total = 0.0;
                for (sq, wq) in s.iter().zip(&w) {
                    v.fill(0.0);
                    for ck in coef.chunks_exact(2 * nd).rev() {
                        for (vi, &c) in v.iter_mut().zip(&ck[nd..]) {
                            *vi = *vi * sq + c;
                        }
                    }
                    av.fill(0.0);
                    for (col, &vj) in a22.chunks_exact(nd).zip(v.iter()) {
                        if vj != 0.0 {
                            axpy(av, col, vj);
                        }
                    }
                    let f: f64 = (0..nd).map(|i| masses[i] * v[i] * av[i]).sum();
                    total -= wq * f;
                }
                total
            }
        })
    }
}

/// [`TaylorMatrix::dissipated`] for `ND` degrees of freedom: `ẋ` at the 10 nodes at once (Horner
/// over the coefficients), then `−Σ_q w_q Σ_i m_i ẋ_i (A₂₂ẋ)_i`, on arrays of fixed size.
fn dissipated_small<const ND: usize>(
    coef: &[f64],
    a22: &[f64],
    masses: &[f64],
    s: &[f64; 10],
    w: &[f64; 10],
) -> f64 {
    // Five nodes at a time, all components at once: the velocity half of each coefficient is
    // contiguous, so the Horner recurrence runs on whole rows, and the five nodes' recurrences
    // are independent chains (latency overlapped).
    let mut v = [[0.0; 10]; ND];
    for half in 0..2 {
        let sq: [f64; 5] = std::array::from_fn(|b| s[5 * half + b]);
        let mut acc = [[0.0; ND]; 5];
        for ck in coef.chunks_exact(2 * ND).rev() {
            if let Ok(cv) = <&[f64; ND]>::try_from(&ck[ND..]) {
                for (ab, &sb) in acc.iter_mut().zip(&sq) {
                    for i in 0..ND {
                        ab[i] = ab[i] * sb + cv[i];
                    }
                }
            }
        }
        for (b, ab) in acc.iter().enumerate() {
            for i in 0..ND {
                v[i][5 * half + b] = ab[i];
            }
        }
    }
    let mut total = 0.0;
    for i in 0..ND {
        let mut av = [0.0; 10];
        for (j, vj) in v.iter().enumerate() {
            let aij = a22[j * ND + i];
            if aij != 0.0 {
                for q in 0..10 {
                    av[q] += aij * vj[q];
                }
            }
        }
        let mut f = 0.0;
        for q in 0..10 {
            f += w[q] * v[i][q] * av[q];
        }
        total -= masses[i] * f;
    }
    total
}

/// `y += a·x` on equal-length slices, in blocks of four of fixed size (unrolled and vectorised
/// also for the short columns of a lumped machine).
#[inline]
fn axpy(y: &mut [f64], x: &[f64], a: f64) {
    let mut yb = y.chunks_exact_mut(4);
    let mut xb = x.chunks_exact(4);
    for (yq, xq) in (&mut yb).zip(&mut xb) {
        if let (Ok(yq), Ok(xq)) = (<&mut [f64; 4]>::try_from(yq), <&[f64; 4]>::try_from(xq)) {
            for q in 0..4 {
                yq[q] += xq[q] * a;
            }
        }
    }
    for (yi, xi) in yb.into_remainder().iter_mut().zip(xb.remainder()) {
        *yi += xi * a;
    }
}

/// A functional `ℓᵀX` prepared for [`Projector::apply`]: its non-zero entries (an indicator or a
/// contact force touches a few coordinates: two or three modal coordinates and a body), so a
/// projection costs `(P + 1)·m` products for `m` non-zeros instead of `(P + 1)·n`.
#[derive(Debug, Clone)]
pub struct Projector {
    v: SparseVec,
    n: usize,
}

impl Projector {
    /// The functional `ℓ` (length `n`, the state's).
    pub fn new(l: &[f64]) -> Self {
        Self {
            v: SparseVec::new(l),
            n: l.len(),
        }
    }

    /// The coefficients `ℓᵀc_k`, k = 0..=P, of `ℓᵀX(s)` into `out` (rows of `n` in `coef`), a
    /// dot over `ℓ`'s non-zeros per coefficient, with fixed-size code for up to 4 of them.
    pub fn apply(&self, coef: &[f64], out: &mut [f64]) {
        fn fixed<const M: usize>(
            idx: &[usize],
            val: &[f64],
            n: usize,
            coef: &[f64],
            out: &mut [f64],
        ) {
            let mut ix = [0usize; M];
            let mut lv = [0.0; M];
            ix.copy_from_slice(&idx[..M]);
            lv.copy_from_slice(&val[..M]);
            for (o, ck) in out.iter_mut().zip(coef.chunks_exact(n)) {
                let mut t = 0.0;
                for q in 0..M {
                    t += lv[q] * ck[ix[q]];
                }
                *o = t;
            }
        }
        let ((idx, val), n) = (self.v.parts(), self.n);
        if n == 0 {
            out.iter_mut().for_each(|o| *o = 0.0);
            return;
        }
        match idx.len() {
            0 => out.iter_mut().for_each(|o| *o = 0.0),
            1 => fixed::<1>(idx, val, n, coef, out),
            2 => fixed::<2>(idx, val, n, coef, out),
            3 => fixed::<3>(idx, val, n, coef, out),
            4 => fixed::<4>(idx, val, n, coef, out),
            _ => {
                for (o, ck) in out.iter_mut().zip(coef.chunks_exact(n)) {
                    *o = self.v.dot(ck);
                }
            }
        }
    }
}

/// `X(s) = Σ c_k s^k` into `out` (Horner).
pub fn state(coef: &[f64], s: f64, out: &mut [f64]) {
    let n = out.len();
    let p = coef.len().checked_div(n).unwrap_or(0);
    if p == 0 {
        out.iter_mut().for_each(|o| *o = 0.0);
        return;
    }
    out.copy_from_slice(&coef[(p - 1) * n..p * n]);
    for c in coef[..(p - 1) * n].chunks_exact(n).rev() {
        for (o, ci) in out.iter_mut().zip(c) {
            *o = *o * s + ci;
        }
    }
}

/// Terms summed for the truncation remainders of [`degree_for_reach`] (beyond them
/// `r^k/k! < 1e-30` for `r ≤ 2.2`).
const TAIL_TERMS: usize = ORDER + 13;

/// `Σ_{k>P} REACH^k/k!`: the remainder bound of a full step (in units of `‖D⁻¹X₀‖_∞`).
const FULL_TAIL: f64 = {
    let mut term = 1.0;
    let mut k = 1;
    let mut tail = 0.0;
    while k < TAIL_TERMS {
        term = term * REACH / k as f64;
        if k > ORDER {
            tail += term;
        }
        k += 1;
    }
    tail
};

/// The lowest degree `d` (`2 ≤ d ≤ P`) with
///
/// `Σ_{k>d} r^k/k! ≤ Σ_{k>P} REACH^k/k!`  (`r = ρ·len`):
///
/// since `‖D⁻¹c_k‖_∞ len^k ≤ (ρ·len)^k/k! ‖D⁻¹X₀‖_∞` (see the module docs; the forced
/// coefficients `A^{k−1}b/k!` decay alike, scaled by `‖D⁻¹b‖_∞/ρ`), the series truncated at
/// degree `d` on `[0, len]` is within the same bound of the solution as the full series
/// (degree `P`) is on its validity `[0, τ]`: below a quarter of the unit round-off of
/// `‖D⁻¹X₀‖_∞`. A stretch much shorter than `τ` (a dashpot that switches off after 1e-3 of
/// the period) needs only a few terms: `r = 0.01` gives `d = 5`. Non-finite or
/// `r ≥ REACH` gives `P`; at least 2 (a forced step with `ρ = 0` has `c₁ = b`, `c₂ = 0`).
pub fn degree_for_reach(r: f64) -> usize {
    if !(0.0..REACH).contains(&r) {
        return ORDER;
    }
    let mut terms = [0.0; TAIL_TERMS];
    let mut term = 1.0;
    terms[0] = term;
    for (k, t) in terms.iter_mut().enumerate().skip(1) {
        term *= r / k as f64;
        *t = term;
    }
    // Remainder after degree d: Σ_{k>d} terms[k], summed from the smallest term up.
    let mut tail = 0.0;
    for d in (2..TAIL_TERMS).rev() {
        tail += terms[d];
        if tail > FULL_TAIL {
            return d.min(ORDER);
        }
    }
    2
}

/// The `P + 1` coefficients of a polynomial of a Taylor step (fixed size, so that loops over
/// them are unrolled).
pub type Coefficients = [f64; ORDER + 1];

/// `k(k−1)` for k = 0..=P (the curvature bound's weights).
pub(crate) const K_K1: Coefficients = {
    let mut t = [0.0; ORDER + 1];
    let mut k = 2;
    while k <= ORDER {
        t[k] = (k * (k - 1)) as f64;
        k += 1;
    }
    t
};

/// `Σ_{k<M} c(k) x^k` in four interleaved Horner chains on `x⁴` (`Σ_r x^r Σ_g c(4g + r) x^{4g}`):
/// about the operations of one Horner chain (a few more to combine the chains) and a quarter of
/// its latency (each step of a chain waits for the previous multiply and add; four independent
/// chains keep the pipeline busy). It rounds differently from one chain, with an error of the
/// same order. Polynomial evaluation is most of an event search on a Taylor step.
#[inline(always)]
pub(crate) fn poly4<const M: usize>(x: f64, c: impl Fn(usize) -> f64) -> f64 {
    let x2 = x * x;
    let t = x2 * x2;
    let mut v = [0.0; 4];
    for g in (0..M.div_ceil(4)).rev() {
        for (r, vr) in v.iter_mut().enumerate() {
            let k = 4 * g + r;
            if k < M {
                *vr = *vr * t + c(k);
            }
        }
    }
    (v[0] + x * v[1]) + x2 * (v[2] + x * v[3])
}

/// `p(s) = Σ a_k s^k`.
#[cfg(test)]
pub(crate) fn eval(a: &Coefficients, s: f64) -> f64 {
    poly4::<{ ORDER + 1 }>(s, |k| a[k])
}

/// `Σ |a_k| x^k` (x ≥ 0): a bound of `|p(s)|` on `[0, x]`.
#[inline]
pub(crate) fn abs_horner(a: &Coefficients, x: f64) -> f64 {
    poly4::<{ ORDER + 1 }>(x, |k| a[k].abs())
}

/// True when `sign·p > 0` on all of `[0, len]` (`p(s) = Σ a_k s^k`, `len ≥ 0`), by a concave
/// lower bound: with `b_k = sign·a_k`, dropping the positive terms of degree ≥ 2 leaves
/// `h(s) = b₀ + b₁s + Σ_{k≥2} min(b_k, 0) s^k ≤ sign·p(s)` for `s ≥ 0`, and `h` is concave
/// there, so `h(0) = b₀ > 0` and `h(len) > 0` prove `sign·p > 0` on the whole interval. A
/// certificate that needs no search: it holds for an indicator far from zero and for one
/// moving away from zero (an overlap growing, a contact separating further).
///
/// It needs only the coefficients, so the step's indicators are tested before a [`Poly`] (with
/// its derivative and round-off size) is built for a search.
pub fn keeps_sign(a: &Coefficients, sign: f64, len: f64) -> bool {
    let b0 = sign * a[0];
    if b0.is_nan() || b0 <= 0.0 {
        return false;
    }
    // Σ_{k≥2} min(b_k, 0) len^(k−2).
    let neg = poly4::<{ ORDER - 1 }>(len, |k| (sign * a[k + 2]).min(0.0));
    b0 + len * (sign * a[1] + len * neg) > 0.0
}

/// A polynomial `Σ a_k s^k` on `[0, τ]`, as a [`Scalar`] for the event search (it holds its
/// coefficients and those of its derivative, so a buffer of searches can be reused from one step
/// to the next without borrowing the step's data).
#[derive(Debug, Clone, Copy)]
pub struct Poly {
    a: Coefficients,
    /// `(k + 1) a_{k+1}`: the derivative.
    da: Coefficients,
    period: f64,
    noise: f64,
}

impl Poly {
    /// The polynomial with coefficients `a`, used on `[0, tau]`, with the search's time scale
    /// `period`. Its round-off is taken as 64 ulps of `Σ|a_k| τ^k`.
    pub fn new(a: &Coefficients, tau: f64, period: f64) -> Self {
        let mut da = [0.0; ORDER + 1];
        for (k, d) in da.iter_mut().take(ORDER).enumerate() {
            *d = (k + 1) as f64 * a[k + 1];
        }
        Self {
            a: *a,
            da,
            period,
            noise: 64.0 * f64::EPSILON * abs_horner(a, tau),
        }
    }

    /// The coefficients `(k + 1) a_{k+1}` of the derivative `p'`.
    pub fn derivative(&self) -> &Coefficients {
        &self.da
    }

    /// [`keeps_sign`] of this polynomial.
    pub fn keeps_sign(&self, sign: f64, len: f64) -> bool {
        keeps_sign(&self.a, sign, len)
    }

    /// `p(s)`.
    pub fn value(&self, s: f64) -> f64 {
        poly4::<{ ORDER + 1 }>(s, |k| self.a[k])
    }
}

impl Scalar for Poly {
    #[inline]
    fn value_slope(&self, s: f64) -> (f64, f64) {
        (
            poly4::<{ ORDER + 1 }>(s, |k| self.a[k]),
            poly4::<ORDER>(s, |k| self.da[k]),
        )
    }
    /// `Σ k(k−1)|a_k| b^{k−2}` (s ≥ 0).
    #[inline]
    fn curvature_bound(&self, _a: f64, b: f64) -> f64 {
        poly4::<{ ORDER - 1 }>(b.abs(), |k| K_K1[k + 2] * self.a[k + 2].abs())
    }
    fn fastest_period(&self) -> f64 {
        self.period
    }
    fn noise(&self) -> f64 {
        self.noise
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic stream of numbers in [−1, 1) (64-bit LCG).
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
    }

    /// `Σ c_k x^k` term by term (summed from the highest power) and `Σ|c_k x^k|`.
    fn naive(c: &[f64], x: f64) -> (f64, f64) {
        let terms: Vec<f64> = c
            .iter()
            .enumerate()
            .map(|(k, ck)| ck * x.powi(k as i32))
            .collect();
        let size = terms.iter().map(|t| t.abs()).sum::<f64>();
        (terms.iter().rev().sum(), size)
    }

    /// The four interleaved chains equal the plain sum for every length used (25, 24, 23) and
    /// for the edge cases 0 and 1, to a few ulps of `Σ|c_k x^k|`.
    #[test]
    fn four_chains_equal_the_plain_sum() {
        let mut r = Lcg(7);
        let c: Vec<f64> = (0..ORDER + 1).map(|_| r.next()).collect();
        for x in [0.0, 0.37, -0.8, 1.0, 2.2] {
            let check = |got: f64, m: usize| {
                let (want, size) = naive(&c[..m], x);
                assert!(
                    (got - want).abs() <= 16.0 * f64::EPSILON * size.max(f64::MIN_POSITIVE),
                    "M = {m}, x = {x}: {got} vs {want}"
                );
            };
            check(poly4::<25>(x, |k| c[k]), 25);
            check(poly4::<24>(x, |k| c[k]), 24);
            check(poly4::<23>(x, |k| c[k]), 23);
            check(poly4::<1>(x, |k| c[k]), 1);
            assert_eq!(poly4::<0>(x, |k| c[k]), 0.0);
        }
    }

    /// Value, slope and curvature bound of a `Poly` against term-by-term sums; the bound holds
    /// the second derivative at sampled points.
    #[test]
    fn poly_value_slope_and_curvature() {
        let mut r = Lcg(11);
        let mut a = [0.0; ORDER + 1];
        for (k, ak) in a.iter_mut().enumerate() {
            // Coefficients of a Taylor step: |a_k| τ^k ~ 2.2^k / k!.
            *ak = r.next() * 2.2_f64.powi(k as i32) / (1..=k).map(|i| i as f64).product::<f64>();
        }
        let p = Poly::new(&a, 1.0, 6.0);
        let da: Vec<f64> = (1..=ORDER).map(|k| k as f64 * a[k]).collect();
        let d2: Vec<f64> = (2..=ORDER).map(|k| (k * (k - 1)) as f64 * a[k]).collect();
        for s in [0.0, 0.25, 0.6, 1.0] {
            let (v, d) = p.value_slope(s);
            let (wv, sv) = naive(&a, s);
            let (wd, sd) = naive(&da, s);
            assert!((v - wv).abs() <= 16.0 * f64::EPSILON * sv, "value at {s}");
            assert!((d - wd).abs() <= 16.0 * f64::EPSILON * sd, "slope at {s}");
            assert!((p.value(s) - wv).abs() <= 16.0 * f64::EPSILON * sv);
            let bound = p.curvature_bound(0.0, s);
            let (abs_d2, _) = naive(&d2.iter().map(|x| x.abs()).collect::<Vec<_>>(), s);
            assert!((bound - abs_d2).abs() <= 16.0 * f64::EPSILON * abs_d2);
            for t in [0.0, 0.5 * s, s] {
                assert!(
                    naive(&d2, t).0.abs() <= bound * (1.0 + 1e-12),
                    "|p''({t})| ≤ bound"
                );
            }
        }
    }

    /// The sign certificate is sound: whenever it says `sign·p > 0` on `[0, len]`, a fine grid
    /// finds no point where `sign·p ≤ 0`; it holds for a polynomial moving away from zero, and
    /// fails for one that dips through zero.
    #[test]
    fn sign_certificate_is_sound() {
        let mut r = Lcg(3);
        let mut proved = 0;
        for case in 0..2000 {
            let mut a = [0.0; ORDER + 1];
            for (k, ak) in a.iter_mut().enumerate().take(6) {
                *ak = r.next() / (1..=k).map(|i| i as f64).product::<f64>();
            }
            a[0] = 0.05 + 0.5 * r.next().abs();
            let len = 0.2 + 2.0 * r.next().abs();
            for sign in [1.0, -1.0] {
                let q = Poly::new(&a, len, 6.0);
                if q.keeps_sign(sign, len) {
                    proved += 1;
                    for i in 0..=400 {
                        let s = len * i as f64 / 400.0;
                        assert!(
                            sign * q.value(s) > 0.0,
                            "case {case}: proved but p({s}) ≤ 0"
                        );
                    }
                }
            }
        }
        assert!(
            proved > 200,
            "the certificate proved only {proved} of 4000 cases"
        );
        // Moving away: p = 1e-3 + s − s²/2 on [0, 1.5] (the constant alone does not dominate).
        let mut a = [0.0; ORDER + 1];
        (a[0], a[1], a[2]) = (1e-3, 1.0, -0.5);
        assert!(Poly::new(&a, 1.5, 6.0).keeps_sign(1.0, 1.5));
        // Dips through zero: p = 0.1 − s + s² has roots at 0.113 and 0.887.
        (a[0], a[1], a[2]) = (0.1, -1.0, 1.0);
        assert!(!Poly::new(&a, 1.0, 6.0).keeps_sign(1.0, 1.0));
    }
}
