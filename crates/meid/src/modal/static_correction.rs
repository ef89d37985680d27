//! Static correction (residual flexibility) of a truncated modal basis: the retained modes plus
//! Ritz vectors built from the static responses to unit loads at the named points ("modes +
//! static modes", as Code_Aster's `MODE_STATIQUE` / `PSEUDO_MODE` and the constraint modes of
//! Craig-Bampton; Craig & Kurdila, *Fundamentals of Structural Dynamics*, 2nd ed., §14.5;
//! Géradin & Rixen, *Mechanical Vibrations*, 3rd ed., §5.3).
//!
//! # The vectors
//! For a point P with functional `f_P` (its displacement along the impact axis is `f_Pᵀ u`), the
//! full structure's static response to a unit force at P is `u_P = K⁻¹ f_P` (with rigid-body
//! modes: the elastic, inertia-relief response of [`super::truncation`], `Φ_0ᵀ M u_P = 0`).
//! The retained modes carry `Σ_{retained, ω_i > 0} φ_i ψ_i(P)/ω_i²` of it (`ψ_i(P) = f_Pᵀ φ_i`);
//! the rest is the **residual vector**
//!
//! ```text
//! r_P = u_P − Σ_{retained, ω_i > 0} φ_i ψ_i(P)/ω_i²  = Σ_{not retained, ω_i > 0} φ_i ψ_i(P)/ω_i²,
//! ```
//!
//! which is M- and K-orthogonal to every retained mode (`φ_iᵀ M u_P = ψ_i(P)/ω_i²`,
//! `φ_iᵀ K r_P = 0`). Its missing flexibility is `f_Pᵀ r_P = r_Pᵀ K r_P = G_PP − Ĝ_PP`.
//!
//! # The pseudo-modes
//! The residual vectors are M-orthogonalised against the retained modes (classical Gram-Schmidt,
//! done twice: "twice is enough", Giraud et al., *Numer. Math.* 101 (2005) 87-100) and among
//! themselves (modified Gram-Schmidt, twice) into `R` (`Rᵀ M R = I`). A point whose vector is
//! round-off (its missing share below [`ROUND_OFF_SHARE`]: all its flexibility is retained) or
//! lies in the span of the earlier ones (two points on the same nodes; `‖r‖_M` falls below
//! [`DEPENDENT_NORM`] of its value before) gives none, with a note naming it. The small
//! eigenproblem in their span,
//!
//! ```text
//! (Rᵀ K R) z_j = ω̃_j² z_j,        φ̃_j = R z_j,
//! ```
//!
//! gives the **pseudo-modes** `φ̃_j`, Ritz vectors with frequencies `ω̃_j`. In the augmented
//! basis `[Φ_r, Φ̃]` the reduced mass is `I` and the reduced stiffness `diag(ω_i², ω̃_j²)`
//! (the cross terms `φ_iᵀ K r_P` vanish), so the impact engine integrates them as ordinary
//! modes; they are not modes of the structure and are labelled "static correction".
//!
//! # What it buys
//! The augmented basis contains every `u_P`, so the Ritz static solution under any combination
//! of forces at the corrected points is the full model's exactly: `Σ ψ²/ω²` over the augmented
//! basis equals `G_PP` (and `G_PQ`) up to round-off, and a slowly applied load gives the exact
//! static response. The dynamic part of the missing modes is not recovered: a contact pulse
//! whose spectrum reaches the missing modes still needs them (docs/explanations/fem.md, "Static correction").
//!
//! # Drop rule
//! A pseudo-mode with `ω̃² > MAX_RESOLVED_SPREAD · ω_1²` (ω_1 the lowest retained elastic
//! frequency; [`super::conditioning::MAX_RESOLVED_SPREAD`] ≈ 4.5e9, the spread whose lowest
//! frequency keeps six digits) is left out with a note naming the point whose flexibility it
//! carries most and the share of that flexibility lost: it is a stiff spring's own bounce
//! (a plate on 1e16 N/m edge springs: the edge nodes on those springs at 4e7 Hz), which the
//! closed-form propagator would take apart from the modes only to lose the low frequencies'
//! digits.

use faer::sparse::SparseColMatRef;
use faer::{Mat, MatRef};

use super::conditioning::MAX_RESOLVED_SPREAD;
use super::kernels;
use crate::{Error, Result};

/// A point whose missing share of static flexibility `(G_PP − Ĝ_PP)/G_PP` is below this gets
/// no correction vector: the retained modes carry its flexibility to round-off (1e-9 changes
/// no printed digit of a share or a peak).
pub const ROUND_OFF_SHARE: f64 = 1e-9;

/// A residual vector whose M-norm after orthogonalisation against the earlier ones is below
/// this fraction of its norm before lies in their span (a repeated or dependent point).
pub const DEPENDENT_NORM: f64 = 1e-8;

/// The static correction of a retained set of modes ([`static_correction`]).
#[derive(Debug, Clone)]
pub struct StaticCorrection {
    /// Pseudo-mode shapes `φ̃_j` (n × q, columns), M-orthonormal and M-, K-orthogonal to the
    /// retained modes.
    pub shapes: Mat<f64>,
    /// `ω̃_j²` (rad²/s²), ascending.
    pub eigenvalues: Vec<f64>,
    /// Per pseudo-mode, the point whose static flexibility it carries the largest share of.
    pub points: Vec<String>,
    /// What was left out and why (points without a vector, pseudo-modes dropped).
    pub notes: Vec<String>,
}

/// The points to correct: (name, functional `f_P`) with the full model's static deflections
/// `u_P` (columns of `deflections`, same order) and flexibilities `G_PP` (m/N).
#[derive(Debug, Clone, Copy)]
pub struct PointLoads<'a> {
    pub functionals: &'a [(String, Vec<f64>)],
    pub deflections: MatRef<'a, f64>,
    pub flexibility: &'a [f64],
}

/// `y = A x` for a sparse `A` stored with both triangles.
fn sparse_mul(a: SparseColMatRef<'_, usize, f64>, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; a.nrows()];
    for (j, xj) in x.iter().enumerate() {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            y[i] += v * xj;
        }
    }
    y
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `v ← v − Σ_c q_c (q_cᵀ M v)` over the M-orthonormal columns `q` (classical Gram-Schmidt,
/// applied `passes` times).
fn m_orthogonalise(
    m: SparseColMatRef<'_, usize, f64>,
    q: &[Vec<f64>],
    v: &mut [f64],
    passes: usize,
) {
    for _ in 0..passes {
        let mv = sparse_mul(m, v);
        let c: Vec<f64> = q.iter().map(|qc| dot(qc, &mv)).collect();
        for (qc, a) in q.iter().zip(c) {
            for (vi, qi) in v.iter_mut().zip(qc) {
                *vi -= a * qi;
            }
        }
    }
}

/// The residual vectors `r_P` of the module docs, M-orthonormalised: `(vectors, notes)`. `retained` are the retained modes' shapes (M-orthonormal columns) and `omega` their
/// frequencies (rad/s).
fn residual_basis(
    m: SparseColMatRef<'_, usize, f64>,
    retained: MatRef<'_, f64>,
    omega: &[f64],
    loads: &PointLoads<'_>,
) -> (Vec<Vec<f64>>, Vec<String>) {
    let n = retained.nrows();
    let phi: Vec<Vec<f64>> = (0..retained.ncols())
        .map(|c| retained.col(c).iter().copied().collect())
        .collect();
    let (mut basis, mut names, mut notes) = (Vec::new(), Vec::new(), Vec::new());
    for (p, (name, f)) in loads.functionals.iter().enumerate() {
        let g = loads.flexibility[p];
        let mut r: Vec<f64> = (0..n).map(|i| loads.deflections[(i, p)]).collect();
        for (phi_i, w) in phi.iter().zip(omega) {
            if *w > 0.0 {
                let a = dot(f, phi_i) / (w * w);
                for (ri, v) in r.iter_mut().zip(phi_i) {
                    *ri -= a * v;
                }
            }
        }
        let missing = dot(f, &r);
        if !(g > 0.0 && missing > ROUND_OFF_SHARE * g) {
            notes.push(format!(
                "static correction: point '{name}' needs none: the retained modes carry its \
                 static flexibility to round-off (missing share {:.1e})",
                if g > 0.0 { missing / g } else { 0.0 }
            ));
            continue;
        }
        m_orthogonalise(m, &phi, &mut r, 2);
        let before = dot(&r, &sparse_mul(m, &r)).max(0.0).sqrt();
        m_orthogonalise(m, &basis, &mut r, 2);
        let after = dot(&r, &sparse_mul(m, &r)).max(0.0).sqrt();
        if after.is_nan() || after <= DEPENDENT_NORM * before {
            notes.push(format!(
                "static correction: point '{name}' adds no vector: its static response lies in \
                 the span of the modes and of the correction at {} (the same nodes, or a \
                 combination of them)",
                names
                    .iter()
                    .map(|q| format!("'{q}'"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
            continue;
        }
        r.iter_mut().for_each(|v| *v /= after);
        basis.push(r);
        names.push(name.clone());
    }
    (basis, notes)
}

/// The static correction of the retained modes `retained` (M-orthonormal columns over the n
/// DOFs of `(K, M)`; frequencies `omega`, rad/s) at the points of `loads` (module docs): the
/// pseudo-modes left after the drop rule, with notes for what was left out.
pub fn static_correction(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    retained: MatRef<'_, f64>,
    omega: &[f64],
    loads: &PointLoads<'_>,
) -> Result<StaticCorrection> {
    let n = k.nrows();
    let p = loads.functionals.len();
    if retained.nrows() != n
        || retained.ncols() != omega.len()
        || loads.deflections.nrows() != n
        || loads.deflections.ncols() != p
        || loads.flexibility.len() != p
        || loads.functionals.iter().any(|(_, f)| f.len() != n)
    {
        return Err(Error::invalid(
            "static correction",
            format!("the modes, point functionals and static deflections need {n} rows, one per degree of freedom, and one deflection and flexibility per point"),
        ));
    }
    let (basis, mut notes) = residual_basis(m, retained, omega, loads);
    let q = basis.len();
    let kq: Vec<Vec<f64>> = basis.iter().map(|r| sparse_mul(k, r)).collect();
    let kr = Mat::<f64>::from_fn(q, q, |a, b| {
        0.5 * (dot(&basis[a], &kq[b]) + dot(&basis[b], &kq[a]))
    });
    let (lam, z) =
        kernels::self_adjoint_eigen(kr.as_ref(), "static correction (Ritz eigenproblem)")?;
    let shapes_all =
        Mat::<f64>::from_fn(n, q, |i, j| (0..q).map(|a| basis[a][i] * z[(a, j)]).sum());
    let lowest = omega
        .iter()
        .filter(|w| **w > 0.0)
        .map(|w| w * w)
        .fold(f64::INFINITY, f64::min);
    let unnamed = String::from("?");
    let mut keep = Vec::new();
    let mut points = Vec::new();
    for j in 0..q {
        // The point whose flexibility pseudo-mode j carries the largest share of.
        let (share, at) = loads
            .functionals
            .iter()
            .zip(loads.flexibility)
            .filter(|(_, g)| **g > 0.0)
            .map(|((name, f), g)| {
                let psi: f64 = (0..n).map(|i| f[i] * shapes_all[(i, j)]).sum();
                (psi * psi / (lam[j] * g), name)
            })
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap_or((0.0, &unnamed));
        if !(lam[j] > 0.0 && lam[j].is_finite()) {
            return Err(Error::numerical(
                "static correction",
                format!("the Ritz eigenvalue of the correction at '{at}' is {lam:?}: the stiffness matrix is not positive definite on the residual vectors", lam = lam[j]),
            ));
        }
        if lowest.is_finite() && lam[j] > MAX_RESOLVED_SPREAD * lowest {
            notes.push(format!(
                "static correction: the pseudo-mode at {:.4e} Hz (mostly point '{at}') is left \
                 out: ω̃²/ω_1² = {:.3e} exceeds {:.2e}, the spread double precision resolves to \
                 six digits (a stiff spring's own bounce); '{at}' loses {:.4} % of its static \
                 flexibility with it",
                lam[j].sqrt() / (2.0 * std::f64::consts::PI),
                lam[j] / lowest,
                MAX_RESOLVED_SPREAD,
                100.0 * share
            ));
            continue;
        }
        keep.push(j);
        points.push(at.clone());
    }
    Ok(StaticCorrection {
        shapes: Mat::<f64>::from_fn(n, keep.len(), |i, c| shapes_all[(i, keep[c])]),
        eigenvalues: keep.iter().map(|&j| lam[j]).collect(),
        points,
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::modal::{dense, truncation};
    use faer::sparse::{SparseColMat, Triplet};

    /// A chain of masses `m[i]` joined by springs `k[i]` (spring 0 to the ground when
    /// `grounded`, else spring i joins masses i−1 and i, i ≥ 1): sparse K and M.
    fn chain(
        m: &[f64],
        k: &[f64],
        grounded: bool,
    ) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
        let n = m.len();
        let mut t = Vec::new();
        for (i, &ki) in k.iter().enumerate() {
            if i == 0 {
                if grounded {
                    t.push(Triplet::new(0, 0, ki));
                }
                continue;
            }
            t.extend([
                Triplet::new(i - 1, i - 1, ki),
                Triplet::new(i, i, ki),
                Triplet::new(i - 1, i, -ki),
                Triplet::new(i, i - 1, -ki),
            ]);
        }
        let kk = SparseColMat::try_new_from_triplets(n, n, &t).unwrap();
        let tm: Vec<_> = m
            .iter()
            .enumerate()
            .map(|(i, &v)| Triplet::new(i, i, v))
            .collect();
        (kk, SparseColMat::try_new_from_triplets(n, n, &tm).unwrap())
    }

    fn dense_of(a: &SparseColMat<usize, f64>) -> Mat<f64> {
        let mut d = Mat::<f64>::zeros(a.nrows(), a.ncols());
        for t in a.triplet_iter() {
            d[(t.row, t.col)] += *t.val;
        }
        d
    }

    fn unit(n: usize, i: usize) -> Vec<f64> {
        (0..n).map(|j| if j == i { 1.0 } else { 0.0 }).collect()
    }

    /// The modes of a chain, the first `keep` (from `first`) retained, corrected at `points`:
    /// (all modes, retained shapes and ω, the correction, the functionals).
    struct Case {
        kk: SparseColMat<usize, f64>,
        mm: SparseColMat<usize, f64>,
        retained: Mat<f64>,
        omega: Vec<f64>,
        corr: StaticCorrection,
        functionals: Vec<(String, Vec<f64>)>,
        g: Vec<Vec<f64>>,
    }

    fn case(
        m: &[f64],
        k: &[f64],
        grounded: bool,
        keep: std::ops::Range<usize>,
        points: &[(&str, usize)],
    ) -> Case {
        let (kk, mm) = chain(m, k, grounded);
        let n = m.len();
        let modes = dense::solve(dense_of(&kk).as_ref(), dense_of(&mm).as_ref()).unwrap();
        let rigid: Vec<Vec<f64>> = (0..n)
            .filter(|&i| modes.omega_rad_per_s[i] == 0.0)
            .map(|i| modes.shapes.col(i).iter().copied().collect())
            .collect();
        let lowest = modes
            .omega_rad_per_s
            .iter()
            .find(|w| **w > 0.0)
            .map(|w| w * w);
        let functionals: Vec<(String, Vec<f64>)> = points
            .iter()
            .map(|(p, i)| (p.to_string(), unit(n, *i)))
            .collect();
        let f: Vec<Vec<f64>> = functionals.iter().map(|(_, f)| f.clone()).collect();
        let u =
            truncation::static_deflections(kk.as_ref(), mm.as_ref(), &f, &rigid, lowest).unwrap();
        let g = truncation::flexibility_of_deflections(&f, u.as_ref());
        let gpp: Vec<f64> = (0..g.len()).map(|i| g[i][i]).collect();
        let retained = Mat::<f64>::from_fn(n, keep.len(), |i, c| modes.shapes[(i, keep.start + c)]);
        let omega = modes.omega_rad_per_s[keep].to_vec();
        let loads = PointLoads {
            functionals: &functionals,
            deflections: u.as_ref(),
            flexibility: &gpp,
        };
        let corr =
            static_correction(kk.as_ref(), mm.as_ref(), retained.as_ref(), &omega, &loads).unwrap();
        Case {
            kk,
            mm,
            retained,
            omega,
            corr,
            functionals,
            g,
        }
    }

    impl Case {
        /// The augmented basis: shapes (columns) and ω.
        fn basis(&self) -> (Vec<Vec<f64>>, Vec<f64>) {
            let mut shapes: Vec<Vec<f64>> = (0..self.retained.ncols())
                .map(|c| self.retained.col(c).iter().copied().collect())
                .collect();
            shapes.extend(
                (0..self.corr.shapes.ncols())
                    .map(|c| self.corr.shapes.col(c).iter().copied().collect()),
            );
            let mut w = self.omega.clone();
            w.extend(self.corr.eigenvalues.iter().map(|l| l.sqrt()));
            (shapes, w)
        }
        fn psi(&self, p: usize) -> Vec<f64> {
            self.basis()
                .0
                .iter()
                .map(|s| dot(&self.functionals[p].1, s))
                .collect()
        }
    }

    const M8: [f64; 8] = [1.0, 2.0, 1.5, 3.0, 0.5, 2.5, 1.0, 4.0];
    const K8: [f64; 8] = [4e5, 2e5, 3e5, 1e5, 5e5, 2.5e5, 1.5e5, 3.5e5];

    /// A fixed-free chain of eight springs: a unit force at mass j deflects mass i by
    /// `Σ_{s ≤ min(i, j)} 1/k_s` (springs in series). With the lowest two modes and the
    /// correction at masses 7 (tip) and 3, the augmented basis gives these to 1e-10; the two
    /// modes alone miss a share of several per cent.
    #[test]
    fn corrected_chain_carries_the_exact_static_flexibility() {
        let c = case(&M8, &K8, true, 0..2, &[("tip", 7), ("mid", 3)]);
        assert_eq!(c.corr.eigenvalues.len(), 2, "{:?}", c.corr.notes);
        let series = |i: usize| -> f64 { K8[..=i].iter().map(|k| 1.0 / k).sum() };
        let (_, w) = c.basis();
        let (p0, p1) = (c.psi(0), c.psi(1));
        let modal = |a: &[f64], b: &[f64]| -> f64 {
            (0..w.len()).map(|i| a[i] * b[i] / (w[i] * w[i])).sum()
        };
        for (got, want) in [
            (modal(&p0, &p0), series(7)),
            (modal(&p1, &p1), series(3)),
            (modal(&p0, &p1), series(3)),
        ] {
            assert!((got - want).abs() <= 1e-10 * want, "{got:e} vs {want:e}");
        }
        // The full static solution itself against the closed form, and the modes alone short.
        assert!((c.g[0][0] - series(7)).abs() <= 1e-13 * series(7));
        let alone: f64 = (0..2).map(|i| p0[i] * p0[i] / (w[i] * w[i])).sum();
        assert!(
            alone / series(7) < 0.995,
            "the two modes alone carry {}",
            alone / series(7)
        );
    }

    /// The pseudo-modes are M-orthonormal and K-diagonal, and M- and K-orthogonal to the
    /// retained modes to 1e-12 (K scaled by the frequencies: `φ̃ᵀ K φ / (ω̃ ω)`).
    #[test]
    fn pseudo_modes_are_orthogonal_to_the_retained_modes() {
        let c = case(
            &M8,
            &K8,
            true,
            0..3,
            &[("tip", 7), ("mid", 3), ("second", 1)],
        );
        let (shapes, w) = c.basis();
        let q = shapes.len();
        for a in 0..q {
            let (ka, ma) = (
                sparse_mul(c.kk.as_ref(), &shapes[a]),
                sparse_mul(c.mm.as_ref(), &shapes[a]),
            );
            for b in 0..q {
                let (mab, kab) = (dot(&shapes[b], &ma), dot(&shapes[b], &ka) / (w[a] * w[b]));
                let id = if a == b { 1.0 } else { 0.0 };
                assert!((mab - id).abs() <= 1e-12, "M[{a}][{b}] = {mab:e}");
                assert!((kab - id).abs() <= 1e-12, "K[{a}][{b}]/(w w) = {kab:e}");
            }
        }
    }

    /// A load applied slowly, `F(t) = F₀ (1 − cos(π t/T))/2` over T, then held: each mode
    /// responds (closed form, zero initial state) `q(T) = ψ F₀/2 [1/ω² + 1/(ω² − Ω²)] +
    /// A cos ωT`, `A = ψ F₀ Ω²/(2ω²(ω² − Ω²))`, Ω = π/T. With Ω = 1e-4 ω₁ the corrected basis
    /// gives the exact static deflection `F₀ Σ 1/k_s` at the tip to 1e-7; the modes alone miss
    /// what their share misses.
    #[test]
    fn slowly_applied_load_gives_the_exact_static_response() {
        let c = case(&M8, &K8, true, 0..2, &[("tip", 7)]);
        let (_, w) = c.basis();
        let psi = c.psi(0);
        let f0 = 250.0;
        let big_omega = 1e-4 * w[0];
        let t = std::f64::consts::PI / big_omega;
        let q = |i: usize| -> f64 {
            let (wi, p) = (w[i], psi[i]);
            let (w2, o2) = (wi * wi, big_omega * big_omega);
            let a = p * f0 * o2 / (2.0 * w2 * (w2 - o2));
            p * f0 / 2.0 * (1.0 / w2 + 1.0 / (w2 - o2)) + a * (wi * t).cos()
        };
        let x_tip: f64 = (0..w.len()).map(|i| psi[i] * q(i)).sum();
        let exact = f0 * K8.iter().map(|k| 1.0 / k).sum::<f64>();
        assert!(
            (x_tip - exact).abs() <= 1e-7 * exact,
            "{x_tip:e} vs {exact:e}"
        );
        let modes_only: f64 = (0..2).map(|i| psi[i] * q(i)).sum();
        assert!((modes_only - exact).abs() > 1e-3 * exact);
    }

    /// A free chain (one rigid-body mode retained with the lowest elastic one): the corrected
    /// basis carries the inertia-relief flexibility, `Σ ψ²/ω²` over all elastic modes of the
    /// full problem, to 1e-10.
    #[test]
    fn free_chain_uses_the_inertia_relief_response() {
        let c = case(&M8, &K8, false, 0..2, &[("end", 0), ("tip", 7)]);
        let (kk, mm) = chain(&M8, &K8, false);
        let all = dense::solve(dense_of(&kk).as_ref(), dense_of(&mm).as_ref()).unwrap();
        for (p, idx) in [(0usize, 0usize), (1, 7)] {
            let full: f64 = (0..8)
                .filter(|&i| all.omega_rad_per_s[i] > 0.0)
                .map(|i| all.shapes[(idx, i)].powi(2) / all.eigenvalues[i])
                .sum();
            let (_, w) = c.basis();
            let psi = c.psi(p);
            let got: f64 = (0..w.len())
                .filter(|&i| w[i] > 0.0)
                .map(|i| psi[i] * psi[i] / (w[i] * w[i]))
                .sum();
            assert!(
                (got - full).abs() <= 1e-10 * full,
                "{p}: {got:e} vs {full:e}"
            );
        }
    }

    /// Two names for one mass give one vector and a note naming the second; with every mode
    /// retained a point needs no vector (its missing share is round-off), with a note.
    #[test]
    fn dependent_and_round_off_points_are_noted_by_name() {
        let c = case(&M8, &K8, true, 0..2, &[("tip", 7), ("tip too", 7)]);
        assert_eq!(c.corr.eigenvalues.len(), 1);
        assert!(
            c.corr
                .notes
                .iter()
                .any(|n| n.contains("'tip too' adds no vector")),
            "{:?}",
            c.corr.notes
        );
        let c = case(&M8, &K8, true, 0..8, &[("tip", 7)]);
        assert!(c.corr.eigenvalues.is_empty());
        assert!(
            c.corr.notes.iter().any(|n| n.contains("'tip' needs none")),
            "{:?}",
            c.corr.notes
        );
    }

    /// A mass on a 1e16 N/m spring to the ground under a soft chain: the correction at that
    /// mass is the mass bouncing on the stiff spring (ω̃² ≈ 1e16/m), beyond the six-digit spread
    /// of the lowest retained mode: left out, with a note naming the point and the share lost
    /// (almost all of its 1e-16 m/N).
    #[test]
    fn pseudo_mode_beyond_the_resolved_spread_is_left_out() {
        let k = [1e16, 1e4, 1e4, 1e4];
        let m = [1.0, 1.0, 1.0, 1.0];
        let c = case(&m, &k, true, 0..1, &[("edge", 0), ("tip", 3)]);
        assert_eq!(c.corr.eigenvalues.len(), 1, "{:?}", c.corr.notes);
        assert_eq!(c.corr.points, vec!["tip".to_string()]);
        let note = c
            .corr
            .notes
            .iter()
            .find(|n| n.contains("left out"))
            .expect("a note");
        let lost: f64 = note
            .split("'edge' loses ")
            .nth(1)
            .and_then(|t| t.split(' ').next())
            .and_then(|v| v.parse().ok())
            .unwrap_or(0.0);
        assert!(lost > 99.99, "{note}");
    }
}
