//! Repeated eigenvalues: which modes share one, and a basis of their eigenspace that does not
//! depend on the eigen-solver.
//!
//! A symmetric structure (a square column, a plate with two axes of symmetry, the six rigid-body
//! modes of a free machine) has eigenvalues of multiplicity `m > 1`. Any M-orthonormal basis of
//! the eigenspace is a valid set of modes, and each solver returns its own: the dense solver and
//! Lanczos (and, in principle, two builds of either) give shapes that differ by an arbitrary
//! rotation `Q` (`m × m`, orthogonal) within the space. Whatever depends on the basis and not on
//! the space alone, the exported shapes (`modes.csv`, `.vtu`, `.uff`), the modal participation
//! of one member of the pair, a selection keeping one member, per-mode damping ratios that
//! differ within the pair, would then depend on the solver.
//!
//! [`canonical_basis`] replaces the basis `Φ` (`n × m`) of each cluster with one that depends
//! only on the space. Column `j` is the unit vector of what is left of the space (the part
//! M-orthogonal to columns `0..j`, spanned by the orthonormal `Φ_j`) that is largest at its
//! *pivot* `f` (a row vector: a named point's displacement functional, or one DOF):
//!
//! ```text
//! φ_j = Φ_j u / ‖u‖,   u = (f Φ_j)ᵀ,   so that f φ_j = ‖f Φ_j‖ > 0 and f φ_i = 0 for i > j
//! ```
//!
//! The pivot is the first of the given *probes* (the named points along the impact, in the
//! order given) that the space still moves, `‖f Φ_j‖ > 0` and `‖f Φ_j‖ ≥ 10⁻⁶ Σ|f| max_r ‖Φ_j(r, ·)‖`
//! (a probe that reads no free DOF, `f = 0`, as at a point whose impact direction is constrained,
//! never pivots); when none
//! does, the first DOF `r` (in DOF order) with `‖Φ_j(r, ·)‖ ≥ (1 − 10⁻⁶) max_s ‖Φ_j(s, ·)‖`. So the
//! first mode of a bending pair of a square column is the one that moves the impact point along
//! the impact, and the second does not move it. The norms `‖f Φ_j‖` and the vector `Φ_j u` are
//! invariant under `Φ_j → Φ_j U` (`U` orthogonal), so the result is the same whatever basis the
//! solver returned, up to round-off; the 10⁻⁶ tie rule (as in
//! [`crate::modal::dense::orient_modes`]) keeps two DOFs that symmetry makes equal from being
//! picked by round-off. Each step is a Householder reflection of the columns still free, so the
//! basis stays M-orthonormal: `(ΦH)ᵀM(ΦH) = HᵀH = I`.
//!
//! Clusters are found by [`degenerate_clusters`]: consecutive modes within
//! [`DEGENERATE_TOLERANCE`] of the cluster's first frequency, or all rigid-body modes.

use faer::Mat;

/// Relative gap `|ω_i − ω_j| ≤ DEGENERATE_TOLERANCE · ω_j` under which two modes share an
/// eigenvalue (a repeated eigenvalue of a symmetric structure comes out of either solver with
/// a spread of ~1e-12; the closest distinct pair of the tests, FV2's 17.6808/17.7094 Hz, is
/// 1.6e-3 apart).
pub const DEGENERATE_TOLERANCE: f64 = 1e-8;

/// Relative tolerance of the pivot choice: DOFs within it of the largest count as tied.
const PIVOT_TIE: f64 = 1e-6;

/// A probe `f` pivots when `‖fΦ_j‖ > 0` and `‖fΦ_j‖ ≥ PROBE_FLOOR · Σ|f| · max_r ‖Φ_j(r, ·)‖`: the space moves it
/// well above round-off (module docs).
const PROBE_FLOOR: f64 = 1e-6;

/// For each mode (ascending ω), the range of modes sharing its eigenvalue: consecutive modes
/// within [`DEGENERATE_TOLERANCE`] of the cluster's first, or all rigid-body modes (ω = 0).
pub fn degenerate_clusters(omega: &[f64]) -> Vec<std::ops::Range<usize>> {
    let n = omega.len();
    let mut out = vec![0..0; n];
    let mut start = 0;
    while start < n {
        let w0 = omega[start];
        let mut end = start + 1;
        while end < n && (omega[end] - w0).abs() <= DEGENERATE_TOLERANCE * omega[end].abs() {
            end += 1;
        }
        if w0 == 0.0 {
            while end < n && omega[end] == 0.0 {
                end += 1;
            }
        }
        for r in out.iter_mut().take(end).skip(start) {
            *r = start..end;
        }
        start = end;
    }
    out
}

/// Replaces the columns of `shapes` that share an eigenvalue (`omega`, ascending, one per
/// column; [`degenerate_clusters`]) with the solver-independent basis of their eigenspace
/// described in the module docs, pivoting on `probes` (dense row vectors of length
/// `shapes.nrows()`, in order of priority) before single DOFs. Columns of a simple eigenvalue
/// are left as they are. Returns the clusters of two or more modes that were rewritten.
pub fn canonical_basis(
    shapes: &mut Mat<f64>,
    omega: &[f64],
    probes: &[&[f64]],
) -> Vec<std::ops::Range<usize>> {
    let m = omega.len().min(shapes.ncols());
    let clusters = degenerate_clusters(&omega[..m]);
    let mut done = Vec::new();
    let mut start = 0;
    while start < m {
        let c = clusters[start].clone();
        start = c.end;
        if c.len() < 2 {
            continue;
        }
        canonical_cluster(shapes, c.clone(), probes);
        done.push(c);
    }
    done
}

/// [`canonical_basis`] on the columns `cols` of one cluster.
fn canonical_cluster(shapes: &mut Mat<f64>, cols: std::ops::Range<usize>, probes: &[&[f64]]) {
    let n = shapes.nrows();
    for j in cols.clone() {
        let free = j..cols.end;
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let row_norm = |r: usize| {
            free.clone()
                .map(|c| shapes[(r, c)].powi(2))
                .sum::<f64>()
                .sqrt()
        };
        let max_row = (0..n).fold(0.0_f64, |a, r| a.max(row_norm(r)));
        if max_row == 0.0 {
            return;
        }
        let on_probe = |f: &&[f64]| -> Option<Vec<f64>> {
            if f.len() != n {
                return None;
            }
            let y: Vec<f64> = free
                .clone()
                .map(|c| (0..n).map(|r| f[r] * shapes[(r, c)]).sum())
                .collect();
            let l1: f64 = f.iter().map(|x| x.abs()).sum();
            // A probe that reads no DOF (a point whose impact-direction DOFs are all
            // constrained: f = 0) or that the space does not move cannot pivot: `‖fΦ_j‖ = 0`
            // would give `u = 0/0`.
            let moved = norm(&y);
            (moved > 0.0 && moved >= PROBE_FLOOR * l1 * max_row).then_some(y)
        };
        let tie = (1.0 - PIVOT_TIE) * max_row;
        let Some(y) = probes.iter().find_map(on_probe).or_else(|| {
            (0..n)
                .find(|&r| row_norm(r) >= tie)
                .map(|r| free.clone().map(|c| shapes[(r, c)]).collect())
        }) else {
            return;
        };
        let len = norm(&y);
        if !(len > 0.0 && len.is_finite()) {
            return;
        }
        let u: Vec<f64> = y.iter().map(|x| x / len).collect();
        // Householder H = I − 2vvᵀ/vᵀv, v = u + s e₁ (s = sign u₁): Hu = −s e₁, so the first
        // column of ΦH is −s Φu and the pivot's values of the others, (yᵀH)_i = −s‖y‖(e₁)_i,
        // vanish. A single free column (u = ±1) is only signed.
        let s = if u[0] >= 0.0 { 1.0 } else { -1.0 };
        if free.len() > 1 {
            let mut v = u.clone();
            v[0] += s;
            let vv: f64 = v.iter().map(|x| x * x).sum();
            for r in 0..n {
                let dot: f64 = free
                    .clone()
                    .zip(&v)
                    .map(|(c, vi)| shapes[(r, c)] * vi)
                    .sum();
                let f = 2.0 * dot / vv;
                for (c, vi) in free.clone().zip(&v) {
                    shapes[(r, c)] -= f * vi;
                }
            }
        }
        // Column j is now −sΦu (or sΦu for a single column, u = s): make it +Φu.
        let flip = if free.len() > 1 { s > 0.0 } else { s < 0.0 };
        if flip {
            for r in 0..n {
                shapes[(r, j)] = -shapes[(r, j)];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64 as Rng;

    /// `cols` orthonormal columns of length `rows` (Gram-Schmidt of Gaussian columns); with
    /// `rows = cols` a random orthogonal matrix.
    fn random_orthonormal(rng: &mut Rng, rows: usize, cols: usize) -> Mat<f64> {
        let mut q = Mat::from_fn(rows, cols, |_, _| rng.next_normal());
        for j in 0..cols {
            for i in 0..j {
                let d: f64 = (0..rows).map(|r| q[(r, i)] * q[(r, j)]).sum();
                for r in 0..rows {
                    q[(r, j)] -= d * q[(r, i)];
                }
            }
            let nn: f64 = (0..rows).map(|r| q[(r, j)].powi(2)).sum::<f64>().sqrt();
            for r in 0..rows {
                q[(r, j)] /= nn;
            }
        }
        q
    }

    fn random_orthogonal(rng: &mut Rng, m: usize) -> Mat<f64> {
        random_orthonormal(rng, m, m)
    }

    /// Orthonormal columns `Φ` (n × 6) with eigenvalues [0, 0, 0, 5, 7, 7] (a rigid-body triple,
    /// a simple mode and a pair).
    fn shapes(rng: &mut Rng, n: usize) -> (Mat<f64>, Vec<f64>) {
        (
            random_orthonormal(rng, n, 6),
            vec![0.0, 0.0, 0.0, 5.0, 7.0, 7.0 * (1.0 + 1e-12)],
        )
    }

    /// Rotating each cluster's basis by a random orthogonal matrix (what another solver may
    /// return) gives the same canonical basis to round-off; the simple mode is untouched; the
    /// columns stay orthonormal and span the same spaces.
    #[test]
    fn the_canonical_basis_does_not_depend_on_the_input_basis() {
        let mut rng = Rng::new(7);
        for trial in 0..20 {
            let n = 9 + trial % 5;
            let (phi, omega) = shapes(&mut rng, n);
            let mut a = phi.clone();
            let done = canonical_basis(&mut a, &omega, &[]);
            assert_eq!(done, vec![0..3, 4..6]);
            let mut b = phi.clone();
            for c in [0..3, 4..6] {
                let q = random_orthogonal(&mut rng, c.len());
                let block = b.subcols(c.start, c.len()).to_owned();
                let rot = &block * &q;
                for (jj, j) in c.clone().enumerate() {
                    for r in 0..n {
                        b[(r, j)] = rot[(r, jj)];
                    }
                }
            }
            canonical_basis(&mut b, &omega, &[]);
            for j in 0..6 {
                for r in 0..n {
                    assert!(
                        (a[(r, j)] - b[(r, j)]).abs() < 1e-12,
                        "trial {trial} ({r}, {j})"
                    );
                }
            }
            for r in 0..n {
                assert_eq!(a[(r, 3)], phi[(r, 3)]);
            }
            let g = a.transpose() * &a;
            for i in 0..6 {
                for j in 0..6 {
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!((g[(i, j)] - want).abs() < 1e-13, "{i} {j} {}", g[(i, j)]);
                }
            }
            // Same spaces: each new column is a combination of its cluster's old columns.
            for c in [0..3, 4..6] {
                for j in c.clone() {
                    let mut res = a.col(j).to_owned();
                    for i in c.clone() {
                        let d: f64 = (0..n).map(|r| phi[(r, i)] * a[(r, j)]).sum();
                        for r in 0..n {
                            res[r] -= d * phi[(r, i)];
                        }
                    }
                    assert!(res.norm_l2() < 1e-13);
                }
            }
        }
    }

    /// Column `j` is largest at its pivot, positive there, and zero at the earlier columns'
    /// pivots: on a pair spanning e₀ and e₁ (any rotation of them), the basis is e₀, e₁.
    #[test]
    fn a_pair_along_two_dofs_becomes_those_dofs() {
        let (c, s) = (0.6_f64, -0.8_f64);
        let mut phi = Mat::from_fn(4, 2, |r, j| match (r, j) {
            (0, 0) => c,
            (1, 0) => s,
            (0, 1) => -s,
            (1, 1) => c,
            _ => 0.0,
        });
        canonical_basis(&mut phi, &[3.0, 3.0], &[]);
        let want = [[1.0, 0.0], [0.0, 1.0], [0.0, 0.0], [0.0, 0.0]];
        for r in 0..4 {
            for j in 0..2 {
                assert!((phi[(r, j)] - want[r][j]).abs() < 1e-15, "{r} {j}");
            }
        }
    }

    /// With probes: the first column of each cluster is the direction that moves the first probe
    /// the space moves (positively), the others do not move it; a probe the space does not move
    /// (orthogonal to it) is passed over; the result still does not depend on the input basis.
    #[test]
    fn the_first_mode_of_a_cluster_moves_the_first_probe_it_can() {
        let mut rng = Rng::new(11);
        for trial in 0..20 {
            let n = 10 + trial % 4;
            let (phi, omega) = shapes(&mut rng, n);
            // A probe orthogonal to the pair 4..6 (and to the rigid triple), then a random one.
            let mut dead: Vec<f64> = (0..n).map(|_| rng.next_normal()).collect();
            for i in [0, 1, 2, 4, 5] {
                let d: f64 = (0..n).map(|r| phi[(r, i)] * dead[r]).sum();
                for r in 0..n {
                    dead[r] -= d * phi[(r, i)];
                }
            }
            let live: Vec<f64> = (0..n).map(|_| rng.next_normal()).collect();
            let probes: Vec<&[f64]> = vec![&dead, &live];
            let mut a = phi.clone();
            canonical_basis(&mut a, &omega, &probes);
            let on = |x: &Mat<f64>, f: &[f64], j: usize| -> f64 {
                (0..n).map(|r| f[r] * x[(r, j)]).sum()
            };
            for c in [0..3, 4..6] {
                assert!(on(&a, &live, c.start) > 0.0);
                for j in c.start + 1..c.end {
                    assert!(on(&a, &live, j).abs() < 1e-13, "trial {trial} col {j}");
                }
            }
            let mut b = phi.clone();
            for c in [0..3, 4..6] {
                let q = random_orthogonal(&mut rng, c.len());
                let rot = b.subcols(c.start, c.len()).to_owned() * &q;
                for (jj, j) in c.clone().enumerate() {
                    for r in 0..n {
                        b[(r, j)] = rot[(r, jj)];
                    }
                }
            }
            canonical_basis(&mut b, &omega, &probes);
            for j in 0..6 {
                for r in 0..n {
                    assert!(
                        (a[(r, j)] - b[(r, j)]).abs() < 1e-12,
                        "trial {trial} ({r}, {j})"
                    );
                }
            }
        }
    }

    /// A probe that reads no DOF (f = 0: a point whose impact direction is constrained) is
    /// passed over, not divided by: the basis stays finite and M-orthonormal, and it is the
    /// basis the next probe (or the DOF rule) gives.
    #[test]
    fn a_zero_probe_is_passed_over() {
        let mut rng = Rng::new(5);
        let n = 11;
        let (phi, omega) = shapes(&mut rng, n);
        let zero = vec![0.0; n];
        let live: Vec<f64> = (0..n).map(|_| rng.next_normal()).collect();
        for (with, without) in [
            (vec![zero.as_slice()], Vec::<&[f64]>::new()),
            (
                vec![zero.as_slice(), live.as_slice()],
                vec![live.as_slice()],
            ),
        ] {
            let mut a = phi.clone();
            canonical_basis(&mut a, &omega, &with);
            let mut b = phi.clone();
            canonical_basis(&mut b, &omega, &without);
            for j in 0..6 {
                for r in 0..n {
                    assert!(a[(r, j)].is_finite(), "({r}, {j}) = {}", a[(r, j)]);
                    assert_eq!(a[(r, j)], b[(r, j)], "({r}, {j})");
                }
            }
            let g = a.transpose() * &a;
            for i in 0..6 {
                for j in 0..6 {
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!((g[(i, j)] - want).abs() < 1e-13, "{i} {j} {}", g[(i, j)]);
                }
            }
        }
    }

    #[test]
    fn clusters_are_consecutive_close_frequencies_and_all_rigid_body_modes() {
        let w = [0.0, 0.0, 1.0, 1.0 + 1e-10, 1.0 + 1e-6, 2.0];
        assert_eq!(
            degenerate_clusters(&w),
            vec![0..2, 0..2, 2..4, 2..4, 4..5, 5..6]
        );
    }
}
