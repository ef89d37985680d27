//! Sparse shift-invert block Lanczos for the lowest modes of large models, with a Sturm
//! (inertia) check that no mode in the returned band was missed.
//!
//! # Why hand-written
//! No pure-Rust crate offers an ARPACK-quality sparse generalised symmetric eigen-solver
//! (shift-invert, restarts, inertia check). faer 0.24 provides the sparse Cholesky/LDLᵀ
//! factorisations and dense kernels; the Lanczos process is written here on top of them.
//!
//! # Formulation
//! For `K φ = λ M φ` (K symmetric positive semi-definite, possibly singular; M symmetric
//! positive definite) and a shift `σ < 0`, the spectral transformation
//!
//! ```text
//! Op = (K - σ M)⁻¹ M,    Op φ = θ φ,    θ = 1 / (λ - σ)
//! ```
//!
//! maps the lowest eigenvalues λ to the largest θ, well separated
//! (Ericsson & Ruhe, Math. Comp. 35 (1980) 1251-1268). `Op` is self-adjoint in the
//! M-inner product `⟨x, y⟩ = xᵀ M y`, so Lanczos in that inner product produces a symmetric
//! projected matrix. `K - σ M` is SPD for σ < 0 and is factored once by sparse Cholesky.
//!
//! Block Lanczos with full reorthogonalisation (Grimes, Lewis & Simon, SIAM J. Matrix Anal.
//! Appl. 15 (1994) 228-272): with an M-orthonormal basis `V = [V₁ … V_p]` (blocks of `b`
//! columns, `Vᵀ M V = I`),
//!
//! ```text
//! Op V = V H + V_{p+1} B_p E_pᵀ,      H = Vᵀ M Op V  (symmetric, block tridiagonal in exact arithmetic)
//! ```
//!
//! Every new block is M-orthogonalised against the whole basis by classical Gram-Schmidt
//! applied three times (once as a block, twice per column; "twice is enough", Giraud et al.,
//! Numer. Math. 101 (2005) 87-100), with `M V` stored so that inner products need no extra
//! sparse products. A column that vanishes (an invariant subspace) is replaced by a random
//! vector, with a zero coupling coefficient.
//!
//! Restarts are thick restarts (Wu & Simon, SIAM J. Matrix Anal. Appl. 22 (2000) 602-616;
//! Stewart's Krylov-Schur): with `H = Y Θ Yᵀ` (θ descending), the `l` leading Ritz vectors
//! `V Y_l` are kept, the projected matrix becomes `diag(θ_1..θ_l)` bordered by the coupling
//! `S = B_p E_pᵀ Y_l`, and the Lanczos process continues from `V_{p+1}`. The Ritz residual
//! of pair i in the operator is `‖Op x_i - θ_i x_i‖_M = ‖S e_i‖₂`.
//!
//! # Convergence and results
//! A Ritz pair is accepted when its operator residual is below `tol_op · θ_i`; the accepted
//! vectors are then refined by a Rayleigh-Ritz step on `(Xᵀ K X, Xᵀ M X)` and checked with the
//! true residual `‖K x - λ M x‖ / (‖K x‖ + |λ| ‖M x‖) ≤ tol`. If that fails, `tol_op` is
//! tightened and the iteration continues. Rigid-body modes are those whose Rayleigh quotient
//! cannot be told from zero, within its round-off `100 ε |x|ᵀ|K||x|` and the uncertainty its
//! residual leaves ([`crate::modal::check`]): no threshold on `max K_ii/M_ii`, which a single stiff spring
//! inflates (springs of 1e16 N/m on a plate's edges made its 49 Hz mode a "rigid-body mode").
//! For them `K x ≈ 0` makes the ratio above 0/0; their residual is taken relative to the terms
//! that cancel in `K x`, `‖K x - λ M x‖ / (‖|K||x|‖ + |λ| ‖M x‖)`. In floating point the
//! attainable residual of an elastic mode is about `ε ‖|K||x|‖ / ‖K x‖` (ε machine precision:
//! the rounding of `K x` itself), so for ill-conditioned models (fine shell meshes) `tol` may be
//! unattainable. A mode is therefore also accepted when its residual is below
//! `4 ε ‖|K||x|‖ / ‖K x‖`, or when `tol_op` has reached 1e-14, or when after tightening the
//! operator residuals, all within `tol_op = tol`, stop decreasing (no halving of the largest
//! `‖Op x - θ x‖_M / θ` over the wanted modes in `STALL_CYCLES` cycles: the solves' rounding,
//! about ε times the condition of `K - σM`, limits the high modes, whose θ is far below the
//! largest); then
//! [`SparseModes::converged_to_tol`] is false and the true residual is reported. Every result is
//! then checked again, against fixed bounds, by the caller ([`crate::modal::check`]).
//!
//! # Shift
//! `s = max_i K_ii / M_ii` estimates the top of the spectrum. If the iteration does not converge
//! with it, it is redone with `s = ` the mass-weighted median of `K_ii / M_ii` (the ratio below
//! which DOFs holding half of `tr M` lie), the stiffness scale of the bulk of the structure: a
//! maximum set by a single very stiff spring (1e16 N/m on a plate's edge) puts the shift decades
//! below the wanted band. The automatic shift is `σ₀ = -1e-6 s`: far enough from zero that
//! `K - σM` stays well conditioned in the bulk (so rigid-body modes are resolved), close enough
//! that the wanted eigenvalues stay separated. If after a cycle the k-th Ritz value `λ̃_k` lies
//! far below `|σ|` (`|σ| > 4 λ̃_k`; slender or very finely meshed models), the factorisation is
//! redone at `σ = -max(λ̃_k, 1e-9 s)` and the iteration restarts from the Ritz vectors. A
//! shift much closer to zero (user-given, e.g. -1e-12 s) makes `K - σM` so ill-conditioned
//! that solve errors stall convergence when rigid-body modes are present; the solver then
//! fails with "no convergence" rather than return a wrong set (the Sturm check guards the
//! rest).
//!
//! # Sturm check
//! After convergence, `K - σ_u M` with `σ_u` just above the largest returned eigenvalue (in
//! the gap before the next Ritz value) is factored by unpivoted sparse `L D Lᵀ`; the number of
//! negative pivots equals the number of eigenvalues below `σ_u` (Sylvester's law of
//! inertia). It must equal the number of computed eigenvalues below `σ_u` (the returned modes
//! plus any further Ritz values in the gap, e.g. the rest of a multiple eigenvalue); otherwise
//! a mode was missed and an error is returned. See `lanczos/shifted.rs` for how D is read from
//! faer's factor (faer 0.24 has no accessor for it).
//!
//! # Threads
//! The result is bit-identical for any number of rayon threads. The factorisations, solves and
//! small dense eigen-problems run sequentially (`Par::Seq`); the sparse products parallelise
//! over rows, each row summed by one task in storage order; the tall products with the basis
//! (`V Y`, `(M V)ᵀ W`, `W - V C`, `Xᵀ K X`) are cut into row chunks of a fixed size and their
//! reductions summed in chunk order (`modal::kernels`). Before, faer's parallel kernels split
//! their reductions by the thread count and the iteration amplified the last-bit differences to
//! 1e-9 in the paper machine's lowest frequency.

mod block;
pub(crate) mod shifted;
pub use shifted::ShiftedPencil;

use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::SparseColMatRef;
use faer::{Accum, Mat, MatMut, Par};

use std::time::Instant;

use super::kernels::{self, mul, mul_rows, mul_rows_into, mul_tn};
use crate::rng::SplitMix64;
use crate::{Error, Result};
use block::{fill_random, m_norm, norm2, project_column, sym_matmul, sym_matmul_with};

/// Automatic shift as a fraction of `s` (the mass-weighted median of `K_ii/M_ii`): `σ₀ = -AUTO_SHIFT_FRACTION · s`.
pub const AUTO_SHIFT_FRACTION: f64 = 1e-6;
/// Floor of the operator tolerance when tightening it to reach the true-residual tolerance.
const TOL_OP_FLOOR: f64 = 1e-14;
/// A new basis column whose M-norm fell below this fraction of its original norm is
/// numerically in the span of the basis and is replaced by a random vector.
const DEFLATION_TOL: f64 = 1e-10;
/// A mode whose residual is below `ATTAINABLE_FACTOR · ε · s / |λ|` (the size of the residual
/// of the exact eigenvector rounded to double precision) is accepted even above `tol`.
const ATTAINABLE_FACTOR: f64 = 4.0;
/// Smallest automatic |σ| as a fraction of s: below it, K - σM has a condition number
/// beyond 1e9 and the solve error (≈ ε · condition) stalls convergence when rigid-body
/// modes are present (observed at 1e-12: see the tests).
const RESHIFT_FLOOR: f64 = 1e-9;
/// Restart cycles without a halving of the largest relative operator residual after which a
/// tightened iteration has stalled at the rounding of its solves (module docs).
const STALL_CYCLES: usize = 5;
/// Largest number of automatic re-shifts.
const MAX_RESHIFTS: usize = 3;

/// Options of [`lowest_modes`].
#[derive(Debug, Clone, PartialEq)]
pub struct LanczosOptions {
    /// Number of lowest modes wanted (k).
    pub count: usize,
    /// Shift σ (rad²/s², must be < 0); `None` chooses it automatically (see module docs).
    pub shift: Option<f64>,
    /// Relative residual tolerance `‖Kx - λMx‖ / (‖Kx‖ + |λ|‖Mx‖)`.
    pub tol: f64,
    /// Lanczos block size b (columns per block solve). At least the largest expected
    /// multiplicity (6 for a free-floating solid) is advisable.
    pub block_size: usize,
    /// Largest number of restart cycles.
    pub max_iter: usize,
    /// Krylov basis size per cycle (rounded up to a multiple of `block_size`);
    /// `None`: `2k + 2b`.
    pub basis_size: Option<usize>,
    /// Seed of the random start block.
    pub seed: u64,
}

impl Default for LanczosOptions {
    fn default() -> Self {
        Self {
            count: 20,
            shift: None,
            tol: 1e-10,
            block_size: 6,
            max_iter: 300,
            basis_size: None,
            seed: 0x6d65_6964,
        }
    }
}

/// Work counters of a run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LanczosStats {
    /// Numeric factorisations (Cholesky at the operator shift(s) + LDLᵀ for the Sturm check).
    pub factorizations: usize,
    /// Block solves with the Cholesky factor.
    pub block_solves: usize,
    /// Right-hand sides solved in total (sum of block widths).
    pub solved_columns: usize,
    /// Sparse matrix-vector products, counted per column.
    pub matvec_columns: usize,
    /// Lanczos block steps (operator applications).
    pub block_steps: usize,
    /// Restart cycles (Rayleigh-Ritz extractions).
    pub cycles: usize,
    /// Automatic re-shifts.
    pub reshifts: usize,
    /// Krylov basis size per cycle.
    pub basis_size: usize,
    /// Stored entries of the Cholesky factor.
    pub factor_nnz: usize,
    /// Wall time (s) in symbolic analysis and numeric factorisations (LLᵀ and LDLᵀ).
    pub factor_s: f64,
    /// Wall time (s) in block solves.
    pub solve_s: f64,
    /// Wall time (s) in M-orthogonalisation (including the M products it needs).
    pub orthogonalise_s: f64,
    /// Wall time (s) in Rayleigh-Ritz extractions, restarts and the final refinement.
    pub ritz_s: f64,
}

/// The lowest modes of a sparse pencil.
#[derive(Debug, Clone)]
pub struct SparseModes {
    /// Eigenvalues λ = ω² (rad²/s²), ascending, as computed (rigid-body ones may be tiny negatives).
    pub eigenvalues: Vec<f64>,
    /// Natural circular frequencies ω (rad/s); rigid-body modes exactly 0.
    pub omega_rad_per_s: Vec<f64>,
    /// Natural frequencies f = ω / 2π (Hz).
    pub frequency_hz: Vec<f64>,
    /// Mass-normalised mode shapes, one column per mode (Φᵀ M Φ = I).
    pub shapes: Mat<f64>,
    /// max |Φᵀ M Φ - I|.
    pub orthonormality_error: f64,
    /// Relative residual per mode (see module docs for the rigid-body normalisation).
    pub residuals: Vec<f64>,
    /// Largest entry of `residuals`.
    pub max_residual: f64,
    /// Whether `max_residual ≤ tol` (false only when tol is below the attainable accuracy).
    pub converged_to_tol: bool,
    /// Modes reported with ω = 0.
    pub rigid_body_modes: usize,
    /// `max_i K_ii / M_ii` (rad²/s²), an estimate of the top of the spectrum (reported only: no
    /// threshold depends on it).
    pub stiffness_scale: f64,
    /// The scale `s` of the automatic shift (rad²/s²): `max K_ii/M_ii`, or the mass-weighted
    /// median of `K_ii / M_ii` when the first did not converge (module docs).
    pub shift_scale: f64,
    /// Final operator shift σ (rad²/s²).
    pub shift: f64,
    /// Shift σ_u of the Sturm check (rad²/s²).
    pub sturm_shift: f64,
    /// Negative pivots of `L D Lᵀ = K - σ_u M` = number of eigenvalues below σ_u.
    pub sturm_count: usize,
    /// Computed eigenvalues below σ_u: the returned modes plus Ritz values in the gap.
    /// Equal to `sturm_count` (checked).
    pub computed_below_sturm_shift: usize,
    /// Work counters.
    pub stats: LanczosStats,
}

/// Lowest `opts.count` eigenpairs of `K φ = λ M φ`.
///
/// `k` (stiffness, N/m) and `m` (mass, kg) are square sparse matrices of one size, stored
/// with **both** triangles (as assembled); symmetry is checked. K must be positive
/// semi-definite and M positive definite.
pub fn lowest_modes(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    opts: &LanczosOptions,
) -> Result<SparseModes> {
    lowest_modes_sharing(k, m, opts, &mut None)
}

/// [`lowest_modes`] with the symbolic analysis of `K − σM` kept in `pencil`: built there
/// when it is `None` (after the input checks), used as it is otherwise. A caller that factors
/// the same pencil again (the static deflections, [`crate::modal::truncation`]) passes the
/// same slot and saves the pattern, the ordering and the symbolic factorisation (5 % of a
/// `meid modes` run at 10⁶ DOF). `pencil` must hold the analysis of this `k` and `m`.
pub fn lowest_modes_sharing(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    opts: &LanczosOptions,
    pencil: &mut Option<ShiftedPencil>,
) -> Result<SparseModes> {
    match lowest_modes_scaled(k, m, opts, false, pencil) {
        // A few very stiff entries (springs acting as constraints) put max K_ii/M_ii decades
        // above the bulk of the structure, and the shift -1e-6 max K_ii/M_ii then lies so far
        // below the wanted band that its eigenvalues are not separated: retry with the bulk
        // scale (the mass-weighted median of K_ii/M_ii).
        Err(Error::Numerical { message, .. })
            if opts.shift.is_none() && message.starts_with("no convergence") =>
        {
            lowest_modes_scaled(k, m, opts, true, pencil)
        }
        other => other,
    }
}

fn lowest_modes_scaled(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    opts: &LanczosOptions,
    bulk_scale: bool,
    pencil: &mut Option<ShiftedPencil>,
) -> Result<SparseModes> {
    let n = k.nrows();
    validate(k, m, opts)?;
    let want = opts.count;
    let b = opts.block_size;

    let (s_max, s_ref) = stiffness_scales(k, m, bulk_scale)?;

    let basis = basis_size(n, opts)?;

    // Sequential factorisations: faer's parallel supernodal kernels split their reductions by the
    // thread count (the results' last bits would change with it, see `modal::kernels`).
    let par = Par::Seq;
    let mut stats = LanczosStats {
        basis_size: basis,
        ..Default::default()
    };
    let clock = Instant::now();
    let pencil = ShiftedPencil::in_slot(pencil, k, m)?;
    stats.factor_nnz = pencil.factor_nnz();

    let mut sigma = opts.shift.unwrap_or(-AUTO_SHIFT_FRACTION * s_ref);
    let mut llt = pencil.factor_llt(sigma, par)?;
    stats.factorizations += 1;
    stats.factor_s += clock.elapsed().as_secs_f64();

    let mut rng = SplitMix64::new(opts.seed);
    let mut st = Basis::new(n, basis, b);
    // Random start block.
    st.w.copy_from(random_block(&mut rng, n, b));
    st.append_block(m, &mut rng, &mut stats, false)?;

    let mut tol_op = opts.tol;
    let mut best_converged = 0usize;
    let (mut best_worst, mut since_halved) = (f64::INFINITY, 0usize);
    for _cycle in 0..opts.max_iter {
        // Fill the basis.
        while st.next < basis {
            let clock = Instant::now();
            st.w.copy_from(st.mv.get(.., st.next..st.next + b));
            llt.solve_in_place(st.w.as_mut())?;
            stats.block_solves += 1;
            stats.solved_columns += b;
            stats.block_steps += 1;
            stats.solve_s += clock.elapsed().as_secs_f64();
            let clock = Instant::now();
            st.append_block(m, &mut rng, &mut stats, true)?;
            stats.orthogonalise_s += clock.elapsed().as_secs_f64();
        }
        stats.cycles += 1;
        let mut clock = Instant::now();

        // Rayleigh-Ritz on the projected operator.
        let (theta, y) = st.ritz()?;
        let coupling = mul(st.h.get(basis..basis + b, ..basis), y.as_ref()); // b × basis
        let res: Vec<f64> = (0..basis).map(|i| norm2(coupling.col(i))).collect();
        let n_conv = (0..want)
            .take_while(|&i| res[i] <= tol_op * theta[i])
            .count();
        best_converged = best_converged.max(n_conv);
        // Stall: after a refinement asked for more than `tol`, the operator residuals of high
        // modes can stop decreasing at the rounding of the solves (ε times the condition of
        // K − σM), far above the tightened `tol_op`. While every wanted mode still meets `tol`
        // (a Ritz value newly entering the wanted set does not), no halving of the largest
        // relative operator residual in STALL_CYCLES cycles ends the iteration.
        let worst = (0..want).map(|i| res[i] / theta[i]).fold(0.0_f64, f64::max);
        if worst < 0.5 * best_worst {
            best_worst = worst;
            since_halved = 0;
        } else {
            since_halved += 1;
        }
        let at_tol = (0..want).all(|i| res[i] <= opts.tol * theta[i]);
        let stalled = at_tol && tol_op < opts.tol && since_halved >= STALL_CYCLES;

        if n_conv == want || stalled {
            let x = mul_rows(st.v.get(.., ..basis), y.get(.., ..want));
            let fin = finalize(k, m, x, s_max, &mut stats)?;
            stats.ritz_s += clock.elapsed().as_secs_f64();
            clock = Instant::now();
            let max_res = fin.residuals.iter().fold(0.0_f64, |a, &r| a.max(r));
            // Accept a mode at tol or at its attainable accuracy 4 ε s / |λ|.
            let acceptable = fin
                .residuals
                .iter()
                .zip(&fin.attainable)
                .all(|(&r, &a)| r <= opts.tol || r <= a);
            let at_floor = tol_op <= TOL_OP_FLOOR || stalled;
            if acceptable || at_floor {
                // Ritz estimates of the eigenvalues beyond the returned ones, with lower bounds
                // λ ≥ σ + 1/(θ + r) from the residual bound |θ - θ̃| ≤ r.
                let beyond: Vec<(f64, f64)> = (want..basis)
                    .map(|i| (sigma + 1.0 / theta[i], sigma + 1.0 / (theta[i] + res[i])))
                    .collect();
                // The operator's factor and the Krylov basis are not needed by the Sturm
                // check: freed before its L D Lᵀ is allocated (at 10⁶ DOF they hold 2.2 GB
                // of the 5.2 GB the run would otherwise peak at).
                drop(llt);
                drop(st);
                return sturm_and_assemble(
                    pencil,
                    fin,
                    &beyond,
                    s_ref,
                    s_max,
                    sigma,
                    max_res <= opts.tol,
                    par,
                    stats,
                );
            }
            tol_op = (tol_op * (0.5 * opts.tol / max_res).clamp(1e-4, 0.5)).max(TOL_OP_FLOOR);
        }

        // Automatic re-shift when the wanted band lies far below |σ|.
        let lam_k = sigma + 1.0 / theta[want - 1];
        if opts.shift.is_none()
            && stats.reshifts < MAX_RESHIFTS
            && lam_k > 0.0
            && -sigma > 4.0 * lam_k
        {
            sigma = -lam_k.max(RESHIFT_FLOOR * s_ref);
            drop(llt);
            let fclock = Instant::now();
            llt = pencil.factor_llt(sigma, par)?;
            stats.factor_s += fclock.elapsed().as_secs_f64();
            stats.factorizations += 1;
            stats.reshifts += 1;
            // A new operator: its residuals start afresh, and so does the stall's reference.
            (best_worst, since_halved) = (f64::INFINITY, 0);
            // New start block: the Ritz vectors folded into b columns.
            let w = folded_ritz_block(&st, &y, basis, basis.min(want + b), b);
            st.reset();
            st.w.copy_from(w);
            st.append_block(m, &mut rng, &mut stats, false)?;
            continue;
        }

        st.thick_restart(&theta, &y, &coupling, want)?;
        stats.ritz_s += clock.elapsed().as_secs_f64();
    }
    Err(no_convergence(sigma, s_ref, opts, best_converged))
}

/// The stiffness scales of the pencil: `s_max = max K_ii/M_ii` and the reference scale of the
/// shift, `s_max` or (`bulk_scale`) the mass-weighted median of `K_ii/M_ii` (module docs).
/// Refuses a diagonal entry of M ≤ 0 or of K < 0, and a K without a positive diagonal entry.
fn stiffness_scales(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    bulk_scale: bool,
) -> Result<(f64, f64)> {
    let n = k.nrows();
    // Stiffness scale s = max K_ii / M_ii (and the necessary diagonal conditions).
    let kd = diagonal(k);
    let md = diagonal(m);
    let mut s_max = 0.0_f64;
    for i in 0..n {
        if md[i] <= 0.0 {
            return Err(Error::invalid(
                "mass matrix",
                format!("diagonal entry {i} is {:.3e}; a positive definite mass matrix needs every diagonal entry > 0 (a degree of freedom without mass?)", md[i]),
            ));
        }
        if kd[i] < 0.0 {
            return Err(Error::invalid(
                "stiffness matrix",
                format!("diagonal entry {i} is {:.3e}; a positive semi-definite stiffness matrix needs every diagonal entry ≥ 0", kd[i]),
            ));
        }
        s_max = s_max.max(kd[i] / md[i]);
    }
    if s_max <= 0.0 || !s_max.is_finite() {
        return Err(Error::invalid(
            "stiffness matrix",
            "has no positive diagonal entry (all modes would be rigid-body modes)",
        ));
    }

    // The bulk stiffness scale: the mass-weighted median of K_ii/M_ii (module docs).
    let s_ref = if bulk_scale {
        weighted_median_ratio(&kd, &md).max(f64::MIN_POSITIVE)
    } else {
        s_max
    };
    Ok((s_max, s_ref))
}

/// The Lanczos basis size: `opts.basis_size` (default `2 count + 2 b`, at least `count + b`)
/// rounded up to whole blocks of `b`, and at most `n − b`; refuses fewer than `count + b`.
fn basis_size(n: usize, opts: &LanczosOptions) -> Result<usize> {
    let want = opts.count;
    let b = opts.block_size;
    let basis = {
        let target = opts.basis_size.unwrap_or(2 * want + 2 * b).max(want + b);
        let mut mm = target.div_ceil(b) * b;
        if mm + b > n {
            mm = n.saturating_sub(b) / b * b;
        }
        mm
    };
    if basis < want + b {
        return Err(Error::invalid(
            "eigen-solver size",
            format!(
                "{n} degrees of freedom are too few for {want} modes with block size {b} (need a basis of at least {} vectors plus one block); use modal::dense for small models",
                want + b
            ),
        ));
    }
    Ok(basis)
}

/// A block of `b` random columns of length `n` (the Lanczos start block).
fn random_block(rng: &mut SplitMix64, n: usize, b: usize) -> Mat<f64> {
    let mut w = Mat::<f64>::zeros(n, b);
    for c in 0..b {
        w.col_mut(c).copy_from(fill_random(rng, n));
    }
    w
}

/// The first `count` Ritz vectors `V[:, ..basis] y` folded (summed column `i` into `i mod b`) into one
/// start block of `b` columns, after a re-shift.
fn folded_ritz_block(st: &Basis, y: &Mat<f64>, basis: usize, count: usize, b: usize) -> Mat<f64> {
    let x = mul_rows(st.v.get(.., ..basis), y.get(.., ..count));
    let mut w = Mat::<f64>::zeros(st.v.nrows(), b);
    for i in 0..x.ncols() {
        let mut col = w.col_mut(i % b);
        col += x.col(i);
    }
    w
}

/// The error when the restart cycles run out: how many modes converged, and what to change
/// (a shift too close to zero for the stiffness scale `s_ref`, else the iteration sizes).
fn no_convergence(sigma: f64, s_ref: f64, opts: &LanczosOptions, best_converged: usize) -> Error {
    let want = opts.count;
    let hint = if -sigma < RESHIFT_FLOOR * s_ref {
        format!(
            "; the shift σ = {sigma:.3e} is closer to zero than 1e-9 × the stiffness scale {s_ref:.3e}, so K - σM is nearly singular: use a more negative shift or the automatic one"
        )
    } else {
        "; raise max_iter, block_size or basis_size".to_string()
    };
    Error::numerical(
        "sparse eigen-solver",
        format!(
            "no convergence after {} restart cycles ({} of {want} modes converged){hint}",
            opts.max_iter, best_converged
        ),
    )
}

fn validate(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    opts: &LanczosOptions,
) -> Result<()> {
    let n = k.nrows();
    if k.ncols() != n || m.nrows() != n || m.ncols() != n {
        return Err(Error::invalid(
            "stiffness/mass matrices",
            format!(
                "need square matrices of one size (K {}x{}, M {}x{})",
                k.nrows(),
                k.ncols(),
                m.nrows(),
                m.ncols()
            ),
        ));
    }
    if opts.count == 0 {
        return Err(Error::invalid("mode count", "must be at least 1"));
    }
    if opts.block_size == 0 {
        return Err(Error::invalid("block size", "must be at least 1"));
    }
    if opts.max_iter == 0 {
        return Err(Error::invalid("max_iter", "must be at least 1"));
    }
    if !(opts.tol.is_finite() && opts.tol > 0.0 && opts.tol < 1.0) {
        return Err(Error::invalid(
            "tolerance",
            format!("{} is not in (0, 1)", opts.tol),
        ));
    }
    if let Some(s) = opts.shift {
        if !(s.is_finite() && s < 0.0) {
            return Err(Error::invalid(
                "shift",
                format!(
                    "{s} must be finite and negative (rad²/s²) so that K - σM is positive definite"
                ),
            ));
        }
    }
    check_symmetric(k, "stiffness matrix")?;
    check_symmetric(m, "mass matrix")?;
    Ok(())
}

/// Checks finiteness and `|A_ij - A_ji| ≤ 1e-12 max|A|` by merging each column with the
/// matching row (a counting-sort transpose).
/// Checks that `a` is symmetric to `1e-12 max|a_ij|` and finite. When every column's row
/// indices are strictly increasing (as assembled), each entry `(i, j)` is compared with
/// `(j, i)` found by binary search in column `i`, without extra memory (a transposed copy of K
/// at 10⁶ DOF is about 1 GB); otherwise, or when an entry fails, the transpose-based check
/// below decides and words the error.
fn check_symmetric(a: SparseColMatRef<'_, usize, f64>, name: &str) -> Result<()> {
    if symmetric_sorted(a) == Some(true) {
        return Ok(());
    }
    check_symmetric_by_transpose(a, name)
}

/// `Some(true)` if `a` (strictly increasing row indices in every column) is finite and
/// symmetric to `1e-12 max|a_ij|`; `Some(false)` if not; `None` if a column is not sorted.
fn symmetric_sorted(a: SparseColMatRef<'_, usize, f64>) -> Option<bool> {
    let n = a.ncols();
    let mut amax = 0.0_f64;
    for j in 0..n {
        let rows = a.row_idx_of_col_raw(j);
        if rows.windows(2).any(|w| w[0] >= w[1]) {
            return None;
        }
        for &v in a.val_of_col(j) {
            if !v.is_finite() {
                return Some(false);
            }
            amax = amax.max(v.abs());
        }
    }
    let tol = 1e-12 * amax;
    for j in 0..n {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            let other = match a.row_idx_of_col_raw(i).binary_search(&j) {
                Ok(p) => a.val_of_col(i)[p],
                Err(_) => 0.0,
            };
            if (v - other).abs() > tol {
                return Some(false);
            }
        }
    }
    Some(true)
}

fn check_symmetric_by_transpose(a: SparseColMatRef<'_, usize, f64>, name: &str) -> Result<()> {
    let n = a.ncols();
    let mut amax = 0.0_f64;
    let mut count = vec![0usize; n + 1];
    for j in 0..n {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            if !v.is_finite() {
                return Err(Error::invalid(
                    name,
                    format!("entry ({i}, {j}) is not finite"),
                ));
            }
            amax = amax.max(v.abs());
            count[i + 1] += 1;
        }
    }
    for i in 0..n {
        count[i + 1] += count[i];
    }
    // Transpose: column i of Aᵀ holds row i of A (sorted by column index by construction).
    let nnz = count[n];
    let mut t_row = vec![0usize; nnz];
    let mut t_val = vec![0.0; nnz];
    let mut fill = count.clone();
    for j in 0..n {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            t_row[fill[i]] = j;
            t_val[fill[i]] = v;
            fill[i] += 1;
        }
    }
    let tol = 1e-12 * amax;
    let mut col: Vec<(usize, f64)> = Vec::new();
    for j in 0..n {
        col.clear();
        col.extend(
            a.row_idx_of_col_raw(j)
                .iter()
                .copied()
                .zip(a.val_of_col(j).iter().copied()),
        );
        for p in count[j]..count[j + 1] {
            col.push((t_row[p], -t_val[p]));
        }
        col.sort_unstable_by_key(|e| e.0);
        let mut p = 0;
        while p < col.len() {
            let i = col[p].0;
            let mut d = 0.0;
            while p < col.len() && col[p].0 == i {
                d += col[p].1;
                p += 1;
            }
            if d.abs() > tol {
                return Err(Error::invalid(
                    name,
                    format!("is not symmetric: entry ({i}, {j}) differs from ({j}, {i}) by {d:.3e}; store both triangles of a symmetric matrix"),
                ));
            }
        }
    }
    Ok(())
}

fn diagonal(a: SparseColMatRef<'_, usize, f64>) -> Vec<f64> {
    let n = a.ncols();
    let mut d = vec![0.0; n];
    for (j, dj) in d.iter_mut().enumerate() {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            if i == j {
                *dj += v;
            }
        }
    }
    d
}

/// The Lanczos basis `V` (n × (m+b)), `M V`, and the projected matrix `H` ((m+b) × m).
struct Basis {
    v: Mat<f64>,
    mv: Mat<f64>,
    h: Mat<f64>,
    /// The block being appended (n × b): the operator's image, or a start block. Kept with
    /// `mw` and `xr` across block steps: at 10⁶ DOF a block is 48 MB, and a fresh allocation
    /// of that size is a new mapping whose pages fault in (and whose unmapping interrupts the
    /// other threads) at every step.
    w: Mat<f64>,
    /// `M w` (n × b).
    mw: Mat<f64>,
    /// Row-major copy of a block for the sparse products ([`block::sym_matmul_with`]).
    xr: Vec<f64>,
    /// Basis columns filled.
    nv: usize,
    /// First column whose operator image is not yet in the basis.
    next: usize,
    m: usize,
    b: usize,
}

impl Basis {
    fn new(n: usize, m: usize, b: usize) -> Self {
        Self {
            v: Mat::zeros(n, m + b),
            mv: Mat::zeros(n, m + b),
            h: Mat::zeros(m + b, m),
            w: Mat::zeros(n, b),
            mw: Mat::zeros(n, b),
            xr: Vec::new(),
            nv: 0,
            next: 0,
            m,
            b,
        }
    }

    fn reset(&mut self) {
        self.h.fill(0.0);
        self.nv = 0;
        self.next = 0;
    }

    /// M-orthonormalises the block `self.w` against the basis and appends it. If `is_image`,
    /// `w` is `Op V[:, next..next+b]` and the coefficients go into column block `next` of H.
    ///
    /// Two block Gram-Schmidt passes against the basis (`W -= V (MVᵀ W)`, twice), then
    /// modified Gram-Schmidt inside the block (twice per column). A column that lost more
    /// than three digits inside the block gets one more pass against the whole basis; a
    /// column that vanished is replaced by a random direction with zero coupling.
    fn append_block(
        &mut self,
        m: SparseColMatRef<'_, usize, f64>,
        rng: &mut SplitMix64,
        stats: &mut LanczosStats,
        is_image: bool,
    ) -> Result<()> {
        let mut w = std::mem::replace(&mut self.w, Mat::new());
        let mut mw = std::mem::replace(&mut self.mw, Mat::new());
        let done = self.orthonormalise_into_basis(w.as_mut(), mw.as_mut(), m, rng, stats, is_image);
        self.w = w;
        self.mw = mw;
        done
    }

    /// The work of [`Basis::append_block`] on the block `w` with the buffer `mw`.
    fn orthonormalise_into_basis(
        &mut self,
        mut w: MatMut<'_, f64>,
        mut mw: MatMut<'_, f64>,
        m: SparseColMatRef<'_, usize, f64>,
        rng: &mut SplitMix64,
        stats: &mut LanczosStats,
        is_image: bool,
    ) -> Result<()> {
        let b = self.b;
        let nv = self.nv;
        let mut coef_v = Mat::<f64>::zeros(nv, b);
        let mut norm2_removed = vec![0.0; b];
        if nv > 0 {
            for _pass in 0..2 {
                // C = (M V)ᵀ W, W -= V C: row chunks of fixed size, thread-count independent.
                let c = mul_tn(self.mv.get(.., ..nv), w.rb());
                mul_rows_into(
                    w.rb_mut(),
                    Accum::Add,
                    self.v.get(.., ..nv),
                    c.as_ref(),
                    -1.0,
                );
                coef_v += &c;
            }
            for (cc, r) in norm2_removed.iter_mut().enumerate() {
                *r = coef_v.col(cc).iter().map(|x| x * x).sum::<f64>();
            }
        }
        sym_matmul_with(m, w.rb(), mw.rb_mut(), &mut self.xr);
        stats.matvec_columns += b;

        for (c, &removed) in norm2_removed.iter().enumerate() {
            let col = nv + c;
            let mut coef = vec![0.0; col + 1];
            for (dst, src) in coef[..nv].iter_mut().zip(coef_v.col(c).iter()) {
                *dst = *src;
            }
            let mut wc = w.rb_mut().get_mut(.., c..c + 1);
            let mut mwc = mw.rb_mut().get_mut(.., c..c + 1);
            let own = m_norm(wc.rb(), mwc.rb());
            let before = (removed + own * own).sqrt();
            // In-block MGS: against the block's previous columns only.
            let mut in_block = vec![0.0; c];
            for _ in 0..2 {
                project_column(
                    self.v.get(.., nv..).as_ref(),
                    self.mv.get(.., nv..).as_ref(),
                    c,
                    wc.rb_mut(),
                    mwc.rb_mut(),
                    &mut in_block,
                );
            }
            for (dst, src) in coef[nv..col].iter_mut().zip(&in_block) {
                *dst += *src;
            }
            let mut eta = m_norm(wc.rb(), mwc.rb());
            if eta < 1e-3 * own && eta > DEFLATION_TOL * before {
                // Heavy cancellation inside the block: restore orthogonality to the basis.
                project_column(
                    self.v.as_ref(),
                    self.mv.as_ref(),
                    col,
                    wc.rb_mut(),
                    mwc.rb_mut(),
                    &mut coef,
                );
                eta = m_norm(wc.rb(), mwc.rb());
            }
            if eta <= DEFLATION_TOL * before || !eta.is_finite() {
                // Numerically in the span of the basis: continue with a random direction.
                coef[col] = 0.0;
                eta = self.random_direction(m, rng, stats, col, wc.rb_mut(), mwc.rb_mut())?;
            } else {
                coef[col] = eta;
            }
            let inv = 1.0 / eta;
            for (dst, src) in [(&mut self.v, wc.rb()), (&mut self.mv, mwc.rb())] {
                for (d, s) in dst.col_mut(col).iter_mut().zip(src.col(0).iter()) {
                    *d = *s * inv;
                }
            }
            if is_image {
                let hc = self.next + c;
                for (r, &cv) in coef.iter().enumerate() {
                    self.h[(r, hc)] = cv;
                }
            }
        }
        self.nv += b;
        if is_image {
            self.next += b;
        }
        Ok(())
    }

    /// A random direction M-orthogonal to the basis' first `col` columns, in `wc` (with
    /// `mwc = M wc`); returns its M-norm. Up to three tries; an error if every one lies in
    /// the basis' span (the basis spans the whole space).
    fn random_direction(
        &self,
        m: SparseColMatRef<'_, usize, f64>,
        rng: &mut SplitMix64,
        stats: &mut LanczosStats,
        col: usize,
        mut wc: MatMut<'_, f64>,
        mut mwc: MatMut<'_, f64>,
    ) -> Result<f64> {
        let n = wc.nrows();
        for _attempt in 0..3 {
            let r = fill_random(rng, n);
            wc.rb_mut().col_mut(0).copy_from(&r);
            sym_matmul(m, wc.rb(), mwc.rb_mut());
            stats.matvec_columns += 1;
            let r0 = m_norm(wc.rb(), mwc.rb());
            let mut dummy = vec![0.0; col];
            for _ in 0..2 {
                project_column(
                    self.v.as_ref(),
                    self.mv.as_ref(),
                    col,
                    wc.rb_mut(),
                    mwc.rb_mut(),
                    &mut dummy,
                );
            }
            let eta = m_norm(wc.rb(), mwc.rb());
            if eta > 1e-8 * r0 {
                return Ok(eta);
            }
        }
        Err(Error::numerical(
            "sparse eigen-solver",
            "could not extend the Krylov basis (the basis spans the whole space); use modal::dense",
        ))
    }

    /// Eigen-decomposition of the symmetrised projected matrix, θ descending.
    fn ritz(&self) -> Result<(Vec<f64>, Mat<f64>)> {
        let m = self.m;
        let mut t = self.h.get(..m, ..m).to_owned();
        for j in 0..m {
            for i in 0..j {
                let s = 0.5 * (t[(i, j)] + t[(j, i)]);
                t[(i, j)] = s;
                t[(j, i)] = s;
            }
        }
        let (s, u) =
            kernels::self_adjoint_eigen(t.as_ref(), "sparse eigen-solver (projected matrix)")?;
        let theta: Vec<f64> = (0..m).rev().map(|i| s[i]).collect();
        let y = Mat::from_fn(m, m, |i, j| u[(i, m - 1 - j)]);
        Ok((theta, y))
    }

    /// Keeps the leading Ritz vectors and continues from the residual block.
    fn thick_restart(
        &mut self,
        theta: &[f64],
        y: &Mat<f64>,
        coupling: &Mat<f64>,
        want: usize,
    ) -> Result<()> {
        let (m, b) = (self.m, self.b);
        // l ≥ want with (m - l) a multiple of b; keep about half of the unwanted Ritz vectors.
        let q = ((m - want) / (2 * b)).max(1);
        let l = m - q * b;
        let yl = y.get(.., ..l);
        kernels::mul_rows_leading_in_place(self.v.as_mut(), m, yl);
        kernels::mul_rows_leading_in_place(self.mv.as_mut(), m, yl);
        // The residual block moves from columns m..m+b to l..l+b (l + b ≤ m: no overlap).
        for a in [&mut self.v, &mut self.mv] {
            let (left, right) = a.as_mut().split_at_col_mut(m);
            left.get_mut(.., l..l + b).copy_from(right.get(.., ..b));
        }
        self.h.fill(0.0);
        for i in 0..l {
            self.h[(i, i)] = theta[i];
            for r in 0..b {
                self.h[(l + r, i)] = coupling[(r, i)];
            }
        }
        self.nv = l + b;
        self.next = l;
        Ok(())
    }
}

/// Refined modes before the Sturm check.
struct Finalized {
    eigenvalues: Vec<f64>,
    shapes: Mat<f64>,
    residuals: Vec<f64>,
    /// Attainable residual per mode, `4 ε ‖|K||x|‖ / ‖K x‖` (elastic) or `4 ε` (rigid).
    attainable: Vec<f64>,
    /// Rigid-body mode per mode ([`crate::modal::check::is_rigid`]).
    rigid: Vec<bool>,
    orthonormality_error: f64,
}

/// The mass-weighted median of `K_ii / M_ii` (DOFs with `M_ii > 0`): the ratio below which DOFs
/// holding half of `tr M` lie. 0 when there are none.
fn weighted_median_ratio(kd: &[f64], md: &[f64]) -> f64 {
    let mut r: Vec<(f64, f64)> = kd
        .iter()
        .zip(md)
        .filter(|(_, &m)| m > 0.0)
        .map(|(&k, &m)| (k / m, m))
        .collect();
    r.sort_by(|a, b| a.0.total_cmp(&b.0));
    let half = 0.5 * r.iter().map(|x| x.1).sum::<f64>();
    let mut acc = 0.0;
    for (ratio, w) in &r {
        acc += w;
        if acc >= half {
            return *ratio;
        }
    }
    0.0
}

/// `z = |A| |x|` for one column (A sparse with both triangles; sequential, in storage order).
fn abs_product_into(a: SparseColMatRef<'_, usize, f64>, x: &[f64], z: &mut [f64]) {
    z.fill(0.0);
    for (j, &xj) in x.iter().enumerate() {
        let xj = xj.abs();
        if xj == 0.0 {
            continue;
        }
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            z[i] += v.abs() * xj;
        }
    }
}

/// Column `j` of a column-major matrix as a slice.
fn col_slice(a: &Mat<f64>, j: usize) -> &[f64] {
    match a.col(j).try_as_col_major() {
        Some(c) => c.as_slice(),
        // A `Mat`'s columns are contiguous.
        None => unreachable!("Mat columns are contiguous"),
    }
}

/// Rayleigh-Ritz of `(Xᵀ K X, Xᵀ M X)` on the converged Ritz vectors (better eigenvalues,
/// exact M-orthonormality), then true residuals with fresh sparse products. `x` becomes the
/// mode shapes in place; the n × p products share one packing buffer (at 10⁶ DOF each n × 20
/// matrix is 160 MB).
fn finalize(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    mut x: Mat<f64>,
    s_max: f64,
    stats: &mut LanczosStats,
) -> Result<Finalized> {
    let (n, p) = (x.nrows(), x.ncols());
    let mut xr = Vec::new();
    let mut kx = Mat::<f64>::zeros(n, p);
    let mut mx = Mat::<f64>::zeros(n, p);
    sym_matmul_with(k, x.as_ref(), kx.as_mut(), &mut xr);
    sym_matmul_with(m, x.as_ref(), mx.as_mut(), &mut xr);
    stats.matvec_columns += 2 * p;
    let a = symmetrised(mul_tn(x.as_ref(), kx.as_ref()));
    let bm = symmetrised(mul_tn(x.as_ref(), mx.as_ref()));
    let l = kernels::llt_lower(bm.as_ref()).ok_or_else(|| {
        Error::numerical(
            "sparse eigen-solver",
            "Ritz vectors are not M-independent (lost orthogonality)",
        )
    })?;
    let l = l.as_ref();
    let mut t = a.clone();
    solve_lower_triangular_in_place(l, t.as_mut(), Par::Seq);
    let mut c = t.transpose().to_owned();
    solve_lower_triangular_in_place(l, c.as_mut(), Par::Seq);
    let c = symmetrised(c);
    let (eigenvalues, mut g) =
        kernels::self_adjoint_eigen(c.as_ref(), "sparse eigen-solver (Rayleigh-Ritz)")?;
    solve_upper_triangular_in_place(l.transpose(), g.as_mut(), Par::Seq);
    // Shapes Φ = X G, and K Φ = (K X) G, M Φ = (M X) G (exact; rounding of the order of a
    // fresh product's, ε |K||φ|): no second pair of sparse products. The caller's check
    // (`modal::check`) recomputes K φ and M φ afresh.
    kernels::mul_rows_leading_in_place(x.as_mut(), p, g.as_ref());
    kernels::mul_rows_leading_in_place(kx.as_mut(), p, g.as_ref());
    kernels::mul_rows_leading_in_place(mx.as_mut(), p, g.as_ref());
    drop(xr);
    let shapes = x;
    let gram = mul_tn(shapes.as_ref(), mx.as_ref());
    let mut orth = 0.0_f64;
    for j in 0..p {
        for i in 0..p {
            let target = if i == j { 1.0 } else { 0.0 };
            orth = orth.max((gram[(i, j)] - target).abs());
        }
    }
    let mut residuals = Vec::with_capacity(p);
    let mut attainable = Vec::with_capacity(p);
    let mut rigid = Vec::with_capacity(p);
    let mdiag = diagonal(m);
    let mut akx = vec![0.0; n];
    for j in 0..p {
        let lam = eigenvalues[j];
        let (phi, kxj, mxj) = (col_slice(&shapes, j), col_slice(&kx, j), col_slice(&mx, j));
        abs_product_into(k, phi, &mut akx);
        let mut r2 = 0.0;
        for (kv, mv) in kxj.iter().zip(mxj) {
            let r = kv - lam * mv;
            r2 += r * r;
        }
        let (lam_r, floor, u) = crate::modal::check::rigid_measures(phi, kxj, &akx, mxj, &mdiag);
        let is_rigid = crate::modal::check::is_rigid(lam_r, floor, u);
        let kn = norm2(kx.col(j));
        let mn = norm2(mx.col(j));
        let akn = akx.iter().map(|v| v * v).sum::<f64>().sqrt();
        // Rigid-body modes: K x ≈ 0 has no scale of its own; the terms that cancel in it do.
        let denom = if is_rigid {
            akn + lam.abs() * mn
        } else {
            kn + lam.abs() * mn
        };
        residuals.push(if denom > 0.0 { r2.sqrt() / denom } else { 0.0 });
        // The stopping rule also keeps the former estimate `4 ε max(K_ii/M_ii) / |λ|`: it only
        // ends the iteration; the caller checks the result against fixed bounds
        // (`modal::check`).
        let componentwise = if is_rigid || kn == 0.0 {
            ATTAINABLE_FACTOR * f64::EPSILON
        } else {
            ATTAINABLE_FACTOR * f64::EPSILON * akn / kn
        };
        attainable.push(componentwise.max(ATTAINABLE_FACTOR * f64::EPSILON * s_max / lam.abs()));
        rigid.push(is_rigid);
    }
    Ok(Finalized {
        eigenvalues,
        shapes,
        residuals,
        attainable,
        rigid,
        orthonormality_error: orth,
    })
}

fn symmetrised(mut a: Mat<f64>) -> Mat<f64> {
    let p = a.nrows();
    for j in 0..p {
        for i in 0..j {
            let s = 0.5 * (a[(i, j)] + a[(j, i)]);
            a[(i, j)] = s;
            a[(j, i)] = s;
        }
    }
    a
}

/// Sturm check and the final result. `beyond` holds (Ritz estimate, lower bound) of the
/// eigenvalues after the returned ones, ascending by estimate.
#[allow(clippy::too_many_arguments)]
fn sturm_and_assemble(
    pencil: &ShiftedPencil,
    fin: Finalized,
    beyond: &[(f64, f64)],
    s_ref: f64,
    s_max: f64,
    sigma: f64,
    converged_to_tol: bool,
    par: Par,
    mut stats: LanczosStats,
) -> Result<SparseModes> {
    let p = fin.eigenvalues.len();
    let lam_top = fin.eigenvalues[p - 1];
    let scale = lam_top.abs().max(1e-8 * s_ref);
    let min_offset = 1e-6 * scale;
    // Place σ_u a quarter into the gap to the next eigenvalue's lower bound, at least
    // `min_offset` above the largest returned eigenvalue.
    let next_lb = beyond.iter().map(|e| e.1).fold(f64::INFINITY, f64::min);
    let mut offset = if next_lb.is_finite() && next_lb > lam_top + 4.0 * min_offset {
        0.25 * (next_lb - lam_top)
    } else {
        min_offset
    };
    for _attempt in 0..6 {
        let sigma_u = lam_top + offset;
        stats.factorizations += 1;
        let clock = Instant::now();
        let inertia = pencil.negative_pivots(sigma_u, par)?;
        stats.factor_s += clock.elapsed().as_secs_f64();
        if let Some(count) = inertia {
            let computed = fin.eigenvalues.iter().filter(|&&l| l < sigma_u).count()
                + beyond.iter().filter(|e| e.0 < sigma_u).count();
            if count != computed {
                return Err(Error::numerical(
                    "sparse eigen-solver (Sturm check)",
                    format!(
                        "K - σM at σ = {sigma_u:.6e} has {count} negative pivots (eigenvalues below σ) but {computed} eigenvalues were computed below it: {}; raise block_size or basis_size",
                        if count > computed { "a mode was missed" } else { "the inertia count is unreliable" }
                    ),
                ));
            }
            let mut rigid = 0;
            let mut omega = Vec::with_capacity(p);
            for (i, &lam) in fin.eigenvalues.iter().enumerate() {
                if fin.rigid[i] {
                    rigid += 1;
                    omega.push(0.0);
                } else if lam < 0.0 {
                    return Err(Error::numerical(
                        "sparse eigen-solver",
                        format!("eigenvalue {} = {lam:.3e} is negative beyond round-off: the stiffness matrix is not positive semi-definite", i + 1),
                    ));
                } else {
                    omega.push(lam.sqrt());
                }
            }
            let max_residual = fin.residuals.iter().fold(0.0_f64, |a, &r| a.max(r));
            return Ok(SparseModes {
                frequency_hz: omega
                    .iter()
                    .map(|w| w / (2.0 * std::f64::consts::PI))
                    .collect(),
                omega_rad_per_s: omega,
                eigenvalues: fin.eigenvalues,
                shapes: fin.shapes,
                orthonormality_error: fin.orthonormality_error,
                residuals: fin.residuals,
                max_residual,
                converged_to_tol,
                rigid_body_modes: rigid,
                stiffness_scale: s_max,
                shift_scale: s_ref,
                shift: sigma,
                sturm_shift: sigma_u,
                sturm_count: count,
                computed_below_sturm_shift: computed,
                stats,
            });
        }
        // Zero or non-finite pivot: nudge σ_u inside the gap.
        offset *= 0.7;
    }
    Err(Error::numerical(
        "sparse eigen-solver (Sturm check)",
        "the LDLᵀ factorisation of K - σ_u M met a zero pivot at every trial shift",
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::{SparseColMat, SymbolicSparseColMat};

    fn csc(n: usize, cols: &[&[(usize, f64)]], sorted: bool) -> SparseColMat<usize, f64> {
        let mut col_ptr = vec![0];
        let (mut rows, mut vals) = (Vec::new(), Vec::new());
        for c in cols {
            for &(i, v) in c.iter() {
                rows.push(i);
                vals.push(v);
            }
            col_ptr.push(rows.len());
        }
        let sym = if sorted {
            SymbolicSparseColMat::new_checked(n, n, col_ptr, None, rows)
        } else {
            SymbolicSparseColMat::new_unsorted_checked(n, n, col_ptr, None, rows)
        };
        SparseColMat::new(sym, vals)
    }

    /// The binary-search check accepts a symmetric matrix, finds an entry whose mirror differs
    /// or is missing, and leaves unsorted columns to the transpose-based check, which words
    /// the error with the pair's indices.
    #[test]
    fn symmetry_check_by_binary_search_and_its_fall_back() {
        let sym = csc(
            3,
            &[
                &[(0, 2.0), (1, -1.0)],
                &[(0, -1.0), (1, 2.0), (2, -1.0)],
                &[(1, -1.0), (2, 1.0)],
            ],
            true,
        );
        assert_eq!(symmetric_sorted(sym.as_ref()), Some(true));
        assert!(check_symmetric(sym.as_ref(), "K").is_ok());
        let off = csc(
            3,
            &[
                &[(0, 2.0), (1, -1.0)],
                &[(0, -1.5), (1, 2.0), (2, -1.0)],
                &[(1, -1.0), (2, 1.0)],
            ],
            true,
        );
        assert_eq!(symmetric_sorted(off.as_ref()), Some(false));
        let e = check_symmetric(off.as_ref(), "K").unwrap_err().to_string();
        assert!(e.contains("not symmetric") && e.contains("(1, 0)"), "{e}");
        let missing = csc(3, &[&[(0, 2.0), (2, 0.5)], &[(1, 2.0)], &[(2, 1.0)]], true);
        assert_eq!(symmetric_sorted(missing.as_ref()), Some(false));
        assert!(check_symmetric(missing.as_ref(), "K").is_err());
        let unsorted = csc(
            3,
            &[&[(1, -1.0), (0, 2.0)], &[(0, -1.0), (1, 2.0)], &[(2, 1.0)]],
            false,
        );
        assert_eq!(symmetric_sorted(unsorted.as_ref()), None);
        assert!(check_symmetric(unsorted.as_ref(), "K").is_ok());
    }
}
