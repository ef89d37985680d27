//! The shifted pencil `K - σ M`: one symbolic Cholesky analysis of the union pattern of the
//! lower triangles of `K` and `M`, then numeric factorisations for any number of shifts.
//!
//! * For the operator shift `σ < 0`, `K - σ M` is symmetric positive definite (K positive
//!   semi-definite, M positive definite) and is factored by sparse Cholesky `L Lᵀ` (faer
//!   supernodal/simplicial, AMD ordering). A failure of this factorisation means K is not
//!   positive semi-definite or M is not positive definite.
//! * For the Sturm check at `σ_u`, `K - σ_u M` is indefinite. It is factored by faer's sparse
//!   `L D Lᵀ` *without pivoting* (faer 0.24 has no pivoted sparse LDLᵀ; the "intranode LBLᵀ"
//!   pivots only inside supernodes). faer does not return `D` through an accessor, but the
//!   factor's value array stores `D` on the diagonal of the unit lower factor (simplicial:
//!   the diagonal entry of each column; supernodal: the diagonal of each supernode's dense
//!   diagonal block), which is read here. By Sylvester's law of inertia the number of negative
//!   pivots equals the number of eigenvalues of `K x = λ M x` below `σ_u`
//!   (Parlett, *The Symmetric Eigenvalue Problem*, §3.3; Grimes, Lewis & Simon, SIAM J. Matrix
//!   Anal. Appl. 15 (1994) 228-272, §2). Without pivoting a tiny pivot can break this; the
//!   caller nudges `σ_u` when a pivot is zero or not finite.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, supernodal, LltRef, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

use crate::{Error, Result};

/// `K - σ M` on the union pattern of the lower triangles, with its symbolic factorisation
/// (built by the eigen-solver, [`super::lowest_modes_sharing`], and reused by the static
/// deflections).
pub struct ShiftedPencil {
    pattern: SymbolicSparseColMat<usize>,
    /// K values on the union pattern (lower triangle).
    k_val: Vec<f64>,
    /// M values on the union pattern (lower triangle).
    m_val: Vec<f64>,
    symbolic: SymbolicCholesky<usize>,
    /// The value array of the last factor dropped, for the next factorisation: the Sturm
    /// check's L D Lᵀ follows the operator's L Lᵀ with the same pattern, and a fresh array
    /// (1.2 GB at 10⁶ DOF) would fault in every page again.
    spare: std::sync::Mutex<Vec<f64>>,
}

/// A numeric Cholesky factor of `K - σ M` (σ below the spectrum).
pub(crate) struct ShiftedLlt<'a> {
    pencil: &'a ShiftedPencil,
    l_val: Vec<f64>,
    mem: MemBuffer,
    mem_cols: usize,
    par: Par,
}

impl ShiftedPencil {
    /// Builds the union pattern and the symbolic analysis. `k` and `m` are square with the
    /// same size; entries above the diagonal are ignored here (symmetry is checked elsewhere).
    pub(crate) fn new(
        k: SparseColMatRef<'_, usize, f64>,
        m: SparseColMatRef<'_, usize, f64>,
    ) -> Result<Self> {
        let n = k.ncols();
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0usize);
        let mut row_idx: Vec<usize> = Vec::new();
        let mut rows: Vec<usize> = Vec::new();
        for j in 0..n {
            rows.clear();
            rows.extend(k.row_idx_of_col_raw(j).iter().copied().filter(|&i| i >= j));
            rows.extend(m.row_idx_of_col_raw(j).iter().copied().filter(|&i| i >= j));
            rows.push(j); // keep the diagonal even if both matrices omit it
            rows.sort_unstable();
            rows.dedup();
            row_idx.extend_from_slice(&rows);
            col_ptr.push(row_idx.len());
        }
        let nnz = row_idx.len();
        let mut k_val = vec![0.0; nnz];
        let mut m_val = vec![0.0; nnz];
        for (src, dst) in [(k, &mut k_val), (m, &mut m_val)] {
            for j in 0..n {
                let pat = &row_idx[col_ptr[j]..col_ptr[j + 1]];
                for (&i, &v) in src.row_idx_of_col_raw(j).iter().zip(src.val_of_col(j)) {
                    if i >= j {
                        // `pat` holds every such row by construction.
                        if let Ok(p) = pat.binary_search(&i) {
                            dst[col_ptr[j] + p] += v;
                        }
                    }
                }
            }
        }
        let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let symbolic = factorize_symbolic_cholesky(
            pattern.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            Default::default(),
        )
        .map_err(|e| {
            Error::numerical(
                "sparse eigen-solver",
                format!("symbolic Cholesky analysis failed: {e:?}"),
            )
        })?;
        Ok(Self {
            pattern,
            k_val,
            m_val,
            symbolic,
            spare: std::sync::Mutex::new(Vec::new()),
        })
    }

    /// The pencil held in `slot`, built from `k` and `m` when the slot is empty (a caller that
    /// factors the same pencil again passes the same slot).
    pub(crate) fn in_slot<'s>(
        slot: &'s mut Option<Self>,
        k: SparseColMatRef<'_, usize, f64>,
        m: SparseColMatRef<'_, usize, f64>,
    ) -> Result<&'s Self> {
        match slot {
            Some(p) => Ok(p),
            None => Ok(slot.insert(Self::new(k, m)?)),
        }
    }

    /// Number of stored entries in the factor (a measure of memory and solve cost).
    pub(crate) fn factor_nnz(&self) -> usize {
        self.symbolic.len_val()
    }

    /// A zeroed value array of the factor's length, reusing the last dropped one.
    fn factor_values(&self) -> Vec<f64> {
        let len = self.symbolic.len_val();
        let mut v = match self.spare.lock() {
            Ok(mut g) => std::mem::take(&mut *g),
            Err(_) => Vec::new(),
        };
        v.clear();
        v.resize(len, 0.0);
        v
    }

    /// Keeps `v` for the next factorisation.
    fn keep_values(&self, v: Vec<f64>) {
        if let Ok(mut g) = self.spare.lock() {
            *g = v;
        }
    }

    fn shifted_values(&self, sigma: f64) -> Vec<f64> {
        self.k_val
            .iter()
            .zip(&self.m_val)
            .map(|(&kv, &mv)| kv - sigma * mv)
            .collect()
    }

    /// Cholesky factorisation of `K - σ M` (parallel as `par`; its solves are sequential). The
    /// solver passes `Par::Seq`: faer's parallel supernodal kernels make the factor's last bits
    /// depend on the thread count.
    /// Fails if the matrix is not numerically positive definite.
    pub(crate) fn factor_llt(&self, sigma: f64, par: Par) -> Result<ShiftedLlt<'_>> {
        let values = self.shifted_values(sigma);
        let a = SparseColMatRef::new(self.pattern.as_ref(), &values);
        let mut l_val = self.factor_values();
        let mut mem = MemBuffer::try_new(
            self.symbolic
                .factorize_numeric_llt_scratch::<f64>(par, Default::default()),
        )
        .map_err(|_| {
            Error::numerical("sparse eigen-solver", "out of memory for the factorisation")
        })?;
        self.symbolic
            .factorize_numeric_llt(
                &mut l_val,
                a,
                Side::Lower,
                LltRegularization::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| {
                Error::numerical(
                    "sparse eigen-solver",
                    format!(
                        "K - σM with σ = {sigma:.6e} is not positive definite ({e:?}): the stiffness \
                         matrix is not positive semi-definite or the mass matrix is not positive definite"
                    ),
                )
            })?;
        Ok(ShiftedLlt {
            pencil: self,
            l_val,
            mem: MemBuffer::new(faer::dyn_stack::StackReq::empty()),
            mem_cols: 0,
            // Triangular solves are memory-bound; faer's parallel supernodal solve was up to
            // 10x slower than the sequential one on the shared 2-core machine (barrier waits).
            par: Par::Seq,
        })
    }

    /// Inertia of `K - σ M` by unpivoted `L D Lᵀ`: returns the number of negative pivots, or
    /// `None` when a pivot is zero or not finite (the caller should move σ).
    pub(crate) fn negative_pivots(&self, sigma: f64, par: Par) -> Result<Option<usize>> {
        let values = self.shifted_values(sigma);
        let a = SparseColMatRef::new(self.pattern.as_ref(), &values);
        let mut l_val = self.factor_values();
        let mut mem = MemBuffer::try_new(
            self.symbolic
                .factorize_numeric_ldlt_scratch::<f64>(par, Default::default()),
        )
        .map_err(|_| {
            Error::numerical(
                "sparse eigen-solver",
                "out of memory for the LDLᵀ factorisation",
            )
        })?;
        let res = self.symbolic.factorize_numeric_ldlt(
            &mut l_val,
            a,
            Side::Lower,
            LdltRegularization::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        );
        if res.is_err() {
            return Ok(None);
        }
        let mut negative = 0usize;
        let mut bad = false;
        let mut visit = |d: f64| {
            if !d.is_finite() || d == 0.0 {
                bad = true;
            } else if d < 0.0 {
                negative += 1;
            }
        };
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(sym) => {
                let factor = sym.factor();
                let cp = factor.col_ptr();
                let ri = factor.row_idx();
                for j in 0..sym.nrows() {
                    let range = cp[j]..cp[j + 1];
                    match ri[range.clone()].iter().position(|&i| i == j) {
                        Some(p) => visit(l_val[range.start + p]),
                        None => visit(f64::NAN),
                    }
                }
            }
            SymbolicCholeskyRaw::Supernodal(sym) => {
                let ldlt = supernodal::SupernodalLdltRef::new(sym, &l_val);
                for s in 0..sym.n_supernodes() {
                    let val = ldlt.supernode(s).val();
                    for c in 0..val.ncols() {
                        visit(val[(c, c)]);
                    }
                }
            }
        }
        self.keep_values(l_val);
        Ok(if bad { None } else { Some(negative) })
    }
}

impl Drop for ShiftedLlt<'_> {
    fn drop(&mut self) {
        self.pencil.keep_values(std::mem::take(&mut self.l_val));
    }
}

impl ShiftedLlt<'_> {
    /// Overwrites `rhs` (n × b) with `(K - σM)⁻¹ rhs` (one block solve).
    pub(crate) fn solve_in_place(&mut self, rhs: MatMut<'_, f64>) -> Result<()> {
        let b = rhs.ncols();
        if b > self.mem_cols {
            let req = self
                .pencil
                .symbolic
                .solve_in_place_scratch::<f64>(b, self.par);
            self.mem = MemBuffer::try_new(req).map_err(|_| {
                Error::numerical("sparse eigen-solver", "out of memory for the block solve")
            })?;
            self.mem_cols = b;
        }
        let llt = LltRef::new(&self.pencil.symbolic, &self.l_val);
        llt.solve_in_place_with_conj(Conj::No, rhs, self.par, MemStack::new(&mut self.mem));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::{SparseColMat, Triplet};

    /// Chain K (tridiagonal 2,-1) with M = I has eigenvalues 4 sin²(jπ/(2(n+1))); the number
    /// of negative LDLᵀ pivots of K - σI must equal the number of those below σ (Sylvester).
    #[test]
    fn inertia_matches_closed_form_count() {
        let n = 50;
        let mut kt = Vec::new();
        let mut mt = Vec::new();
        for i in 0..n {
            kt.push(Triplet::new(i, i, 2.0));
            mt.push(Triplet::new(i, i, 1.0));
            if i + 1 < n {
                kt.push(Triplet::new(i, i + 1, -1.0));
                kt.push(Triplet::new(i + 1, i, -1.0));
            }
        }
        let k = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &kt).unwrap();
        let m = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &mt).unwrap();
        let p = ShiftedPencil::new(k.as_ref(), m.as_ref()).unwrap();
        let lam = |j: usize| {
            let s = (j as f64 * std::f64::consts::PI / (2.0 * (n + 1) as f64)).sin();
            4.0 * s * s
        };
        for sigma in [0.01, 0.5, 1.3, 2.0 + 1e-3, 3.9] {
            let expected = (1..=n).filter(|&j| lam(j) < sigma).count();
            let got = p.negative_pivots(sigma, Par::Seq).unwrap();
            assert_eq!(got, Some(expected), "σ = {sigma}");
        }
        // σ below the spectrum: SPD, Cholesky succeeds and solves K - σM exactly.
        let mut f = p.factor_llt(-0.5, Par::Seq).unwrap();
        let mut x = faer::Mat::<f64>::from_fn(n, 2, |i, c| (i + c) as f64);
        let rhs = x.clone();
        f.solve_in_place(x.as_mut()).unwrap();
        let mut kx = faer::Mat::<f64>::zeros(n, 2);
        super::super::block::sym_matmul(k.as_ref(), x.as_ref(), kx.as_mut());
        let ks = kx + &x * faer::Scale(0.5);
        assert!((ks - rhs).norm_max() < 1e-10);
    }
}
