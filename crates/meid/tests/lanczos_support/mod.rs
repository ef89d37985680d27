//! Test models with closed-form or dense-reference spectra for the sparse Lanczos solver.
#![allow(dead_code)]

use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Side};

pub type Sp = SparseColMat<usize, f64>;

pub fn from_triplets(n: usize, t: &[Triplet<usize, usize, f64>]) -> Sp {
    SparseColMat::try_new_from_triplets(n, n, t).unwrap()
}

fn add_spring(t: &mut Vec<Triplet<usize, usize, f64>>, i: Option<usize>, j: usize, k: f64) {
    t.push(Triplet::new(j, j, k));
    if let Some(i) = i {
        t.push(Triplet::new(i, i, k));
        t.push(Triplet::new(i, j, -k));
        t.push(Triplet::new(j, i, -k));
    }
}

/// Fixed-free chain of n masses m (kg) and n springs k (N/m), node 0 tied to ground.
/// ω_j = 2 sqrt(k/m) sin((2j-1)π / (2(2n+1))).
pub fn chain_fixed_free(n: usize, k: f64, m: f64) -> (Sp, Sp) {
    let mut kt = Vec::new();
    let mut mt = Vec::new();
    for j in 0..n {
        add_spring(&mut kt, if j == 0 { None } else { Some(j - 1) }, j, k);
        mt.push(Triplet::new(j, j, m));
    }
    (from_triplets(n, &kt), from_triplets(n, &mt))
}

pub fn chain_fixed_free_omega(n: usize, k: f64, m: f64, j: usize) -> f64 {
    2.0 * (k / m).sqrt()
        * (((2 * j - 1) as f64) * std::f64::consts::PI / (2.0 * (2 * n + 1) as f64)).sin()
}

/// Fixed-free bar of `ne` linear finite elements with **consistent** mass, length L (m),
/// Young's modulus E (Pa), density ρ (kg/m³), area A (m²). Node 0 is clamped (removed).
/// Discrete spectrum (e.g. Cook et al., *Concepts and Applications of FEA*, dispersion of
/// the linear element): λ_j = 6E/(ρh²) (1 - cos θ_j)/(2 + cos θ_j), θ_j = (2j-1)π/(2 ne).
pub fn fe_bar_fixed_free(ne: usize, len: f64, e: f64, rho: f64, area: f64) -> (Sp, Sp) {
    let h = len / ne as f64;
    let ke = e * area / h;
    let me = rho * area * h / 6.0;
    let mut kt = Vec::new();
    let mut mt = Vec::new();
    for el in 0..ne {
        // element nodes el, el+1; DOF index = node - 1 (node 0 clamped)
        let dofs = [el.checked_sub(1), Some(el)];
        let kloc = [[ke, -ke], [-ke, ke]];
        let mloc = [[2.0 * me, me], [me, 2.0 * me]];
        for a in 0..2 {
            for bb in 0..2 {
                if let (Some(i), Some(j)) = (dofs[a], dofs[bb]) {
                    kt.push(Triplet::new(i, j, kloc[a][bb]));
                    mt.push(Triplet::new(i, j, mloc[a][bb]));
                }
            }
        }
    }
    (from_triplets(ne, &kt), from_triplets(ne, &mt))
}

pub fn fe_bar_fixed_free_lambda(ne: usize, len: f64, e: f64, rho: f64, j: usize) -> f64 {
    let h = len / ne as f64;
    let th = ((2 * j - 1) as f64) * std::f64::consts::PI / (2.0 * ne as f64);
    6.0 * e / (rho * h * h) * (1.0 - th.cos()) / (2.0 + th.cos())
}

/// Free-floating nx × ny × nz lattice of point masses m with 3 translational DOF each, joined
/// to their axis neighbours by isotropic ("scalar") springs k that resist relative
/// displacement in every direction. Each displacement component is an independent grid
/// Laplacian, so the spectrum is
/// λ = (k/m) Σ_a 4 sin²(π p_a / (2 N_a)), p_a = 0..N_a-1, each value 3 times;
/// 3 rigid-body (translation) modes.
pub fn scalar_lattice(dims: [usize; 3], k: f64, m: f64) -> (Sp, Sp) {
    let [nx, ny, nz] = dims;
    let node = |x: usize, y: usize, z: usize| (z * ny + y) * nx + x;
    let nn = nx * ny * nz;
    let mut kt = Vec::with_capacity(nn * 3 * 12);
    let mut mt = Vec::with_capacity(nn * 3);
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let a = node(x, y, z);
                let mut nb = Vec::new();
                if x + 1 < nx {
                    nb.push(node(x + 1, y, z));
                }
                if y + 1 < ny {
                    nb.push(node(x, y + 1, z));
                }
                if z + 1 < nz {
                    nb.push(node(x, y, z + 1));
                }
                for c in 0..3 {
                    mt.push(Triplet::new(3 * a + c, 3 * a + c, m));
                    for &bn in &nb {
                        add_spring(&mut kt, Some(3 * a + c), 3 * bn + c, k);
                    }
                }
            }
        }
    }
    (from_triplets(3 * nn, &kt), from_triplets(3 * nn, &mt))
}

/// All eigenvalues of [`scalar_lattice`], ascending.
pub fn scalar_lattice_spectrum(dims: [usize; 3], k: f64, m: f64) -> Vec<f64> {
    let f = |p: usize, nn: usize| {
        let s = (std::f64::consts::PI * p as f64 / (2.0 * nn as f64)).sin();
        4.0 * s * s
    };
    let mut out = Vec::new();
    for px in 0..dims[0] {
        for py in 0..dims[1] {
            for pz in 0..dims[2] {
                let l = k / m * (f(px, dims[0]) + f(py, dims[1]) + f(pz, dims[2]));
                out.extend([l, l, l]);
            }
        }
    }
    out.sort_by(|a, b| a.partial_cmp(b).unwrap());
    out
}

/// Free-floating cubic truss: nodes on an nx × ny × nz grid (spacing 1 m) with masses m,
/// axial springs (k_edge along edges, k_diag along face and body diagonals). With the
/// diagonals the truss is rigid, so it has exactly 6 rigid-body modes. A bar along unit
/// vector e contributes k e eᵀ to the 3×3 blocks (±).
pub fn truss_lattice(dims: [usize; 3], k_edge: f64, k_diag: f64, m: f64) -> (Sp, Sp) {
    let [nx, ny, nz] = dims;
    let node = |x: usize, y: usize, z: usize| (z * ny + y) * nx + x;
    let nn = nx * ny * nz;
    let mut kt = Vec::new();
    let mut mt = Vec::new();
    for a in 0..3 * nn {
        mt.push(Triplet::new(a, a, m * (1.0 + 0.1 * ((a / 3) % 3) as f64)));
    }
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                for dz in 0..=1usize {
                    for dy in -1i64..=1 {
                        for dx in -1i64..=1 {
                            let d = (dx, dy, dz as i64);
                            // each unordered pair once: lexicographically positive offsets
                            if d <= (0, 0, 0) && dz == 0 {
                                continue;
                            }
                            if dz == 0 && (dy < 0 || (dy == 0 && dx <= 0)) {
                                continue;
                            }
                            let (x2, y2, z2) = (x as i64 + dx, y as i64 + dy, z as i64 + d.2);
                            if x2 < 0
                                || y2 < 0
                                || x2 >= nx as i64
                                || y2 >= ny as i64
                                || z2 >= nz as i64
                            {
                                continue;
                            }
                            let b = node(x2 as usize, y2 as usize, z2 as usize);
                            let a = node(x, y, z);
                            let len2 = (dx * dx + dy * dy + d.2 * d.2) as f64;
                            let kk = if len2 == 1.0 { k_edge } else { k_diag };
                            let e = [dx as f64, dy as f64, d.2 as f64].map(|v| v / len2.sqrt());
                            for i in 0..3 {
                                for j in 0..3 {
                                    let v = kk * e[i] * e[j];
                                    kt.push(Triplet::new(3 * a + i, 3 * a + j, v));
                                    kt.push(Triplet::new(3 * b + i, 3 * b + j, v));
                                    kt.push(Triplet::new(3 * a + i, 3 * b + j, -v));
                                    kt.push(Triplet::new(3 * b + i, 3 * a + j, -v));
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    (from_triplets(3 * nn, &kt), from_triplets(3 * nn, &mt))
}

/// Dense reference: all eigenvalues of K x = λ M x by M = L Lᵀ, C = L⁻¹ K L⁻ᵀ and faer's
/// symmetric eigen-solver (independent of the Lanczos code). Ascending.
pub fn dense_eigenvalues(k: &Sp, m: &Sp) -> Vec<f64> {
    let kd = k.to_dense();
    let md = m.to_dense();
    let l = md.llt(Side::Lower).unwrap().L().to_owned();
    let linv = {
        let n = l.nrows();
        let mut x = Mat::<f64>::identity(n, n);
        faer::linalg::triangular_solve::solve_lower_triangular_in_place(
            l.as_ref(),
            x.as_mut(),
            faer::Par::Seq,
        );
        x
    };
    let c = &linv * &kd * linv.transpose();
    let c = Mat::from_fn(c.nrows(), c.ncols(), |i, j| 0.5 * (c[(i, j)] + c[(j, i)]));
    let evd = c.self_adjoint_eigen(Side::Lower).unwrap();
    (0..c.nrows()).map(|i| evd.S()[i]).collect()
}
