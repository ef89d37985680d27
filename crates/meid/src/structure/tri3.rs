//! Three-node flat shell element (18 DOF): CST membrane + DKT plate bending + the drilling
//! penalty of the four-node shell ([`super::shell`]).
//!
//! ## Why DKT and not MITC3
//! MITC3 (Lee & Bathe, *Computers & Structures* 82 (2004) 945-962) interpolates `w` and the
//! rotations linearly and ties the transverse shear to its edge-tangential values (the field
//! `e_rt = e_rt⁽¹⁾ + c s`, `e_st = e_st⁽²⁾ - c r`). Counting constraints shows why that is not
//! enough in the thin limit: a triangle mesh with `N` nodes has about `3N` edges, each edge
//! imposes one Kirchhoff constraint `w_j - w_i + ½ L (β_i + β_j)·s = 0`, and the mesh has `3N`
//! bending DOFs, so for `t/L → 0` the admissible space shrinks to a few boundary modes
//! (shear locking that only mesh refinement relieves; MITC3+ adds a condensed cubic bubble to
//! fix it). The Discrete Kirchhoff Triangle (Batoz, Bathe & Ho, *Int. J. Numer. Meth. Eng.* 15
//! (1980) 1771-1812) imposes the Kirchhoff constraint discretely at the corners and edge
//! mid-points instead: it has no transverse-shear energy, so it cannot lock, it passes the
//! constant-curvature patch test on any mesh, and it is the most widely verified 3-node plate
//! element. Its limit is the Kirchhoff theory: transverse shear deformation is not represented,
//! so a plate mode of half-wavelength `ℓ` comes out too stiff by the Mindlin shear correction,
//! `Δf/f ≈ π² t² / (12 κ (1-ν) ℓ²)` (from `ω² = D k⁴/(ρt) / (1 + D k²/(κ G t))`, `k = π/ℓ`):
//! 0.35 % at `t/ℓ = 1/20`, 1.4 % at `1/10` (steel, κ = 5/6). [`super::ShellElement::shear_factor`]
//! therefore has no triangle counterpart; mesh thick plates (`t/ℓ > 1/20`) with quadrangles.
//!
//! ## Formulation (local axes, DOFs per node `[u, v, w, θx, θy, θz]`)
//! Section rotations as in MITC4: `βx = θy`, `βy = -θx` (Mindlin kinematics `u = z βx`,
//! `v = z βy`), Kirchhoff constraint `w,x + βx = 0`, `w,y + βy = 0`. `L1, L2, L3` are the area
//! coordinates, `A` the area, `∂Lᵢ/∂x = bᵢ/(2A)`, `∂Lᵢ/∂y = cᵢ/(2A)` with
//! `bᵢ = y_j - y_k`, `cᵢ = x_k - x_j` (i, j, k cyclic).
//!
//! * **Membrane (CST)**: `u = Σ Lᵢ uᵢ`, `v = Σ Lᵢ vᵢ`, `ε = [u,x, v,y, u,y + v,x]` constant,
//!   `Km = A Bmᵀ Dm Bm`, `Dm = E t/(1-ν²) [1 ν 0; ν 1 0; 0 0 (1-ν)/2]`. Exact for constant strain.
//! * **Bending (DKT)**: `β` is the quadratic 6-node field `β = Σ Nᵢ βᵢ + Σ N_k β_k` with
//!   `Nᵢ = Lᵢ(2Lᵢ - 1)` at the corners and `N_k = 4 Lᵢ L_j` at the mid-point of edge `k = (i, j)`
//!   (length `ℓ`, unit tangent `s` from i to j, in-plane normal `n`). The mid-side rotations are
//!   not DOFs; the discrete Kirchhoff hypotheses give them:
//!   - along the edge `w` is cubic (Hermite, with `w,s = -β·s` at the corners), and
//!     `β_s = -w,s` at the mid-point: `β_s,k = -3/(2ℓ) (w_j - wᵢ) - ¼ (βᵢ + β_j)·s`;
//!   - the normal rotation varies linearly along the edge: `β_n,k = ½ (βᵢ + β_j)·n`;
//!
//!   so `β_k = -3/(2ℓ) (w_j - wᵢ) s + (½ n nᵀ - ¼ s sᵀ)(βᵢ + β_j)`. Curvatures
//!   `κ = [βx,x, βy,y, βx,y + βy,x]` are linear; `Kb = ∫ Bbᵀ Db Bb dA`,
//!   `Db = E t³/(12(1-ν²)) [1 ν 0; ν 1 0; 0 0 (1-ν)/2]`, integrated exactly by the 3-point rule
//!   (points `Lᵢ = 2/3, 1/6, 1/6`, weights `A/3`). For a quadratic `w` (constant curvature) with
//!   `β = -∇w` at the corners, the Hermite slope and the linear `β` are exact at the mid-points,
//!   so the quadratic `β` field and the curvature are exact: the patch test is passed.
//! * **Drilling**: as MITC4, a penalty `α G t ∫ (θz - ω)² dA` with `ω = ½(v,x - u,y)` (constant
//!   here), `θz = Σ Lᵢ θzᵢ`, 3-point rule, `α` = [`TriShellElement::drilling_factor`] (1e-3 by
//!   default). A rigid in-plane rotation has `θz = ω` and no energy, so a free element has
//!   exactly six zero-energy modes, and triangles and quadrangles share nodes in a mixed mesh with
//!   the same drilling stiffness per area.
//! * **Mass**: consistent with linear interpolation of every DOF (`∫ Lᵢ L_j dA = A (1 + δᵢⱼ)/12`):
//!   `ρ t` for u, v, w, rotary inertia `ρ t³/12` for θx, θy and the fictitious `α ρ t³/12` for
//!   θz (MITC4's convention). The transverse inertia uses the linear `w`, not DKT's implied
//!   cubic: the total and first moments of mass are exact and the error falls as `h²`.
//!
//! ## Geometry
//! Local axes: `e1` along edge 1→2, `n = (x₂ - x₁) × (x₃ - x₁)/|…|`, `e2 = n × e1`; either winding
//! is accepted (the normal follows it). Coordinates are taken relative to the centroid. A
//! triangle whose area is at most [`MIN_AREA_RATIO`] times its longest edge squared (coincident
//! or collinear nodes) is degenerate and rejected. Whether a triangle is inverted depends on its
//! neighbours: [`check_orientation`] refuses one whose node order runs against a neighbour's
//! across a shared edge, or which is folded back onto it.
//!
//! Hand-written because no Rust crate provides shell elements.

use std::collections::HashMap;

use faer::Mat;

use super::frame::{block_rotation, to_global};
use super::geom::{cross, dot, norm, scale, sub, unit, V3};
use super::material::Material;
use super::shell::{add_btdb, DEFAULT_DRILLING_FACTOR};
use crate::{Error, Result};

/// Smallest accepted area relative to the longest edge squared (an equilateral triangle has
/// √3/4 ≈ 0.433; a triangle with a 1e-6 rad corner has about 5e-7).
pub const MIN_AREA_RATIO: f64 = 1e-8;

/// A three-node shell element (CST membrane + DKT bending + drilling penalty).
#[derive(Debug, Clone, PartialEq)]
pub struct TriShellElement {
    /// Node indices.
    pub nodes: [usize; 3],
    pub material: Material,
    /// Thickness t (m).
    pub thickness_m: f64,
    /// Drilling penalty factor α (1e-3 by default, as for quadrangles).
    pub drilling_factor: f64,
}

impl TriShellElement {
    /// Triangle with the default drilling factor.
    pub fn new(nodes: [usize; 3], material: Material, thickness_m: f64) -> Self {
        TriShellElement {
            nodes,
            material,
            thickness_m,
            drilling_factor: DEFAULT_DRILLING_FACTOR,
        }
    }
}

/// Flat geometry of a triangle.
#[derive(Debug, Clone, Copy)]
pub struct TriGeometry {
    /// `[e1, e2, n]` (rows of global → local).
    pub axes: [V3; 3],
    /// Node coordinates in the element plane relative to the centroid (m).
    pub local_xy: [[f64; 2]; 3],
    /// Area (m²).
    pub area_m2: f64,
}

/// Computes and checks the geometry of a triangle with nodes `x` (global, m).
pub fn tri_geometry(x: &[V3; 3]) -> Result<TriGeometry> {
    let a = sub(x[1], x[0]);
    let b = sub(x[2], x[0]);
    let c = sub(x[2], x[1]);
    let longest = norm(a).max(norm(b)).max(norm(c));
    let nn = cross(a, b);
    let area = 0.5 * norm(nn);
    if !(longest.is_finite() && area.is_finite())
        || longest <= 0.0
        || area <= MIN_AREA_RATIO * longest * longest
    {
        return Err(Error::invalid(
            "shell geometry",
            format!(
                "degenerate triangle: area {area:.3e} m² is at most {MIN_AREA_RATIO:e} x its longest edge squared ({:.3e} m²): coincident or collinear nodes",
                longest * longest
            ),
        ));
    }
    let n = scale(nn, 0.5 / area);
    let e1 = unit(a).ok_or_else(|| Error::invalid("shell geometry", "degenerate triangle"))?;
    let e2 = cross(n, e1);
    let cen = scale(
        [
            x[0][0] + x[1][0] + x[2][0],
            x[0][1] + x[1][1] + x[2][1],
            x[0][2] + x[1][2] + x[2][2],
        ],
        1.0 / 3.0,
    );
    let local_xy = std::array::from_fn(|i| {
        let p = sub(x[i], cen);
        [dot(p, e1), dot(p, e2)]
    });
    Ok(TriGeometry {
        axes: [e1, e2, n],
        local_xy,
        area_m2: area,
    })
}

/// Rows `[βx, βy]` of a corner rotation in local DOFs: `βx = θy`, `βy = -θx`.
fn corner_beta(i: usize) -> [[f64; 18]; 2] {
    let mut r = [[0.0; 18]; 2];
    r[0][6 * i + 4] = 1.0;
    r[1][6 * i + 3] = -1.0;
    r
}

/// Local 18×18 stiffness and consistent mass of a flat triangle with local node coordinates
/// `xy` (counter-clockwise, i.e. positive area).
pub fn tri_local_matrices(
    xy: &[[f64; 2]; 3],
    material: &Material,
    thickness_m: f64,
    drilling_factor: f64,
) -> (Mat<f64>, Mat<f64>) {
    let e = material.youngs_modulus_pa;
    let nu = material.poisson_ratio;
    let g = material.shear_modulus_pa();
    let rho = material.density_kg_per_m3;
    let t = thickness_m;
    let plane = |f: f64| -> Vec<Vec<f64>> {
        vec![
            vec![f, f * nu, 0.0],
            vec![f * nu, f, 0.0],
            vec![0.0, 0.0, f * 0.5 * (1.0 - nu)],
        ]
    };
    let dm = plane(e * t / (1.0 - nu * nu));
    let db = plane(e * t.powi(3) / (12.0 * (1.0 - nu * nu)));
    let dd = vec![vec![drilling_factor * g * t]];

    let two_a = (xy[1][0] - xy[0][0]) * (xy[2][1] - xy[0][1])
        - (xy[2][0] - xy[0][0]) * (xy[1][1] - xy[0][1]);
    let area = 0.5 * two_a;
    // ∂Lᵢ/∂x = bᵢ/(2A), ∂Lᵢ/∂y = cᵢ/(2A).
    let mut lx = [0.0; 3];
    let mut ly = [0.0; 3];
    for i in 0..3 {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        lx[i] = (xy[j][1] - xy[k][1]) / two_a;
        ly[i] = (xy[k][0] - xy[j][0]) / two_a;
    }

    // Mid-side rotations β_k (rows over the 18 DOFs) of edges k = (i, i+1).
    let mut mid = [[[0.0; 18]; 2]; 3];
    for k in 0..3 {
        let (i, j) = (k, (k + 1) % 3);
        let dx = xy[j][0] - xy[i][0];
        let dy = xy[j][1] - xy[i][1];
        let len = (dx * dx + dy * dy).sqrt();
        let s = [dx / len, dy / len];
        let n = [s[1], -s[0]];
        // Q = ½ n nᵀ - ¼ s sᵀ
        let q = [
            [
                0.5 * n[0] * n[0] - 0.25 * s[0] * s[0],
                0.5 * n[0] * n[1] - 0.25 * s[0] * s[1],
            ],
            [
                0.5 * n[1] * n[0] - 0.25 * s[1] * s[0],
                0.5 * n[1] * n[1] - 0.25 * s[1] * s[1],
            ],
        ];
        let (bi, bj) = (corner_beta(i), corner_beta(j));
        for d in 0..2 {
            mid[k][d][6 * j + 2] += -1.5 / len * s[d];
            mid[k][d][6 * i + 2] += 1.5 / len * s[d];
            for c in 0..18 {
                mid[k][d][c] += q[d][0] * (bi[0][c] + bj[0][c]) + q[d][1] * (bi[1][c] + bj[1][c]);
            }
        }
    }
    let corners: [[[f64; 18]; 2]; 3] = std::array::from_fn(corner_beta);

    // Membrane (constant strain).
    let mut bm = [[0.0; 18]; 3];
    for i in 0..3 {
        let o = 6 * i;
        bm[0][o] = lx[i];
        bm[1][o + 1] = ly[i];
        bm[2][o] = ly[i];
        bm[2][o + 1] = lx[i];
    }
    let mut k = Mat::<f64>::zeros(18, 18);
    let mut m = Mat::<f64>::zeros(18, 18);
    add_btdb(&mut k, &bm, &dm, area);

    let rot = rho * t.powi(3) / 12.0;
    let dof_mass = [rho * t, rho * t, rho * t, rot, rot, drilling_factor * rot];
    const PTS: [[f64; 3]; 3] = [
        [2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0],
        [1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0],
        [1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0],
    ];
    let w = area / 3.0;
    for l in PTS {
        // Derivatives of the 6-node shape functions: corners Nᵢ = Lᵢ(2Lᵢ - 1),
        // mid-sides N_k = 4 Lᵢ L_j (k = (i, i+1)).
        let mut nx = [0.0; 6];
        let mut ny = [0.0; 6];
        for i in 0..3 {
            nx[i] = (4.0 * l[i] - 1.0) * lx[i];
            ny[i] = (4.0 * l[i] - 1.0) * ly[i];
            let j = (i + 1) % 3;
            nx[3 + i] = 4.0 * (lx[i] * l[j] + l[i] * lx[j]);
            ny[3 + i] = 4.0 * (ly[i] * l[j] + l[i] * ly[j]);
        }
        let mut bb = [[0.0; 18]; 3];
        for a in 0..6 {
            let beta = if a < 3 { &corners[a] } else { &mid[a - 3] };
            for c in 0..18 {
                // κxx = βx,x; κyy = βy,y; κxy = βx,y + βy,x.
                bb[0][c] += nx[a] * beta[0][c];
                bb[1][c] += ny[a] * beta[1][c];
                bb[2][c] += ny[a] * beta[0][c] + nx[a] * beta[1][c];
            }
        }
        add_btdb(&mut k, &bb, &db, w);
        // Drilling: θz - ω, ω = ½(v,x - u,y).
        let mut bd = [[0.0; 18]; 1];
        for i in 0..3 {
            bd[0][6 * i + 5] = l[i];
            bd[0][6 * i] = 0.5 * ly[i];
            bd[0][6 * i + 1] = -0.5 * lx[i];
        }
        add_btdb(&mut k, &bd, &dd, w);
        for a in 0..3 {
            for b in 0..3 {
                let nn = l[a] * l[b] * w;
                for d in 0..6 {
                    m[(6 * a + d, 6 * b + d)] += dof_mass[d] * nn;
                }
            }
        }
    }
    (k, m)
}

/// Global 18×18 stiffness and consistent mass of a triangle with node positions `x`.
pub fn tri_matrices(x: &[V3; 3], el: &TriShellElement) -> Result<(Mat<f64>, Mat<f64>)> {
    let geo = tri_geometry(x)?;
    let (kl, ml) = tri_local_matrices(
        &geo.local_xy,
        &el.material,
        el.thickness_m,
        el.drilling_factor,
    );
    let t = block_rotation(&geo.axes, 6);
    Ok((to_global(&kl, &t), to_global(&ml, &t)))
}

/// How two elements of one surface meet badly across a shared edge.
#[derive(Debug, Clone, PartialEq)]
pub struct OrientationFault {
    /// Positions (in the slice given to [`check_orientation`]) of the two elements.
    pub elements: [usize; 2],
    /// The shared edge (node indices).
    pub edge: [usize; 2],
    /// `true`: both run the edge in the same direction (one is inverted against the other);
    /// `false`: consistent order but folded back (normals within 25° of opposite).
    pub same_direction: bool,
}

/// Checks that the elements of one surface (polygons as node lists, positions `x`) are
/// consistently oriented: two elements sharing an edge must run it in opposite directions, and
/// their normals must not be folded back onto each other (`n₁·n₂ < -0.9`). Every pair of
/// elements on an edge is checked, so an edge of one surface holds at most two elements (a
/// third runs it in the same direction as one of them: it overlaps that one). Returns the
/// first fault found.
pub fn check_orientation(elements: &[&[usize]], x: &[V3]) -> Option<OrientationFault> {
    let normal = |e: &[usize]| -> V3 {
        let p = |i: usize| x[e[i % e.len()]];
        // Newell's normal of the polygon.
        let mut nrm = [0.0; 3];
        for i in 0..e.len() {
            let (a, b) = (p(i), p(i + 1));
            nrm[0] += (a[1] - b[1]) * (a[2] + b[2]);
            nrm[1] += (a[2] - b[2]) * (a[0] + b[0]);
            nrm[2] += (a[0] - b[0]) * (a[1] + b[1]);
        }
        unit(nrm).unwrap_or([0.0; 3])
    };
    // Every element met on an edge so far, with its direction along it: an element is checked
    // against each of them (an edge of three elements, the third overlapping one of the
    // others, runs the edge in the same direction as one of them).
    let mut seen: HashMap<[usize; 2], Vec<(usize, bool)>> = HashMap::new();
    for (ei, e) in elements.iter().enumerate() {
        for k in 0..e.len() {
            let (a, b) = (e[k], e[(k + 1) % e.len()]);
            let key = [a.min(b), a.max(b)];
            let forward = a < b;
            let on_edge = seen.entry(key).or_default();
            for &(other, fwd) in on_edge.iter() {
                if fwd == forward {
                    return Some(OrientationFault {
                        elements: [other, ei],
                        edge: [a, b],
                        same_direction: true,
                    });
                }
                if dot(normal(elements[other]), normal(e)) < -0.9 {
                    return Some(OrientationFault {
                        elements: [other, ei],
                        edge: [a, b],
                        same_direction: false,
                    });
                }
            }
            on_edge.push((ei, forward));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sym_eigs(k: &Mat<f64>) -> Vec<f64> {
        let evd = k.self_adjoint_eigen(faer::Side::Lower).unwrap();
        (0..k.nrows()).map(|i| evd.S()[i]).collect()
    }

    fn tilted(xy: [[f64; 2]; 3]) -> [V3; 3] {
        let axes = [[0.6, 0.8, 0.0], [-0.48, 0.36, 0.8], [0.64, -0.48, 0.6]];
        std::array::from_fn(|i| {
            let (a, b) = (xy[i][0], xy[i][1]);
            [
                a * axes[0][0] + b * axes[1][0] + 1.0,
                a * axes[0][1] + b * axes[1][1],
                a * axes[0][2] + b * axes[1][2] - 2.0,
            ]
        })
    }

    /// A single distorted triangle in a tilted plane has exactly six zero-energy modes (either
    /// winding), and its consistent mass carries ρ t A in each translation.
    #[test]
    fn single_element_has_six_rigid_modes() {
        for xy in [
            [[0.0, 0.0], [0.11, 0.01], [0.03, 0.08]],
            [[0.0, 0.0], [0.03, 0.08], [0.11, 0.01]],
        ] {
            let x = tilted(xy);
            let el = TriShellElement::new([0, 1, 2], Material::STEEL, 0.004);
            let (k, m) = tri_matrices(&x, &el).unwrap();
            let ev = sym_eigs(&k);
            let max = ev.iter().fold(0.0_f64, |a, b| a.max(b.abs()));
            let zeros = ev.iter().filter(|v| v.abs() < 1e-9 * max).count();
            assert_eq!(zeros, 6, "{ev:?}");
            assert!(ev.iter().all(|v| *v > -1e-9 * max));
            let area = tri_geometry(&x).unwrap().area_m2;
            let exact_area = 0.5 * (0.11 * 0.08 - 0.03 * 0.01);
            assert!((area - exact_area).abs() < 1e-12);
            let mass = 7850.0 * 0.004 * area;
            for d in 0..3 {
                let mut s = 0.0;
                for a in 0..3 {
                    for b in 0..3 {
                        s += m[(6 * a + d, 6 * b + d)];
                    }
                }
                assert!((s - mass).abs() < 1e-12 * mass, "{s} vs {mass}");
            }
        }
    }

    #[test]
    fn degenerate_triangles_are_rejected() {
        let flat =
            |p: [[f64; 2]; 3]| -> [V3; 3] { std::array::from_fn(|i| [p[i][0], p[i][1], 0.0]) };
        for bad in [
            flat([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]),
            flat([[0.0, 0.0], [0.0, 0.0], [0.0, 1.0]]),
            flat([[0.0, 0.0], [1.0, 0.0], [0.5, 1e-10]]),
        ] {
            let e = tri_geometry(&bad).unwrap_err().to_string();
            assert!(e.contains("degenerate triangle"), "{e}");
        }
        assert!(tri_geometry(&flat([[0.0, 0.0], [1.0, 0.0], [0.5, 1e-3]])).is_ok());
    }

    #[test]
    fn orientation_faults_are_found() {
        let x: Vec<V3> = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.5, 0.2, 0.0],
        ];
        let good: [&[usize]; 2] = [&[0, 1, 2], &[0, 2, 3]];
        assert_eq!(check_orientation(&good, &x), None);
        let flipped: [&[usize]; 2] = [&[0, 1, 2], &[0, 3, 2]];
        let f = check_orientation(&flipped, &x).unwrap();
        assert!(f.same_direction && f.elements == [0, 1]);
        // node 4 lies on the same side of edge 0-2 as node 1: (0, 2, 4) runs the edge against
        // (0, 1, 2), as it should, but is folded back onto it.
        let folded: [&[usize]; 2] = [&[0, 1, 2], &[0, 2, 4]];
        let f = check_orientation(&folded, &x).unwrap();
        assert!(!f.same_direction && f.elements == [0, 1], "{f:?}");
        // Edge 0-2 shared by three triangles: the third, (0, 2, 4), runs it against the first
        // (0, 1, 2) as a neighbour should, but in the same direction as the second (0, 2, 3),
        // which it overlaps (node 4 lies on node 3's side of the edge).
        let x3: Vec<V3> = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.3, 0.7, 0.0],
        ];
        let three: [&[usize]; 3] = [&[0, 1, 2], &[0, 2, 3], &[0, 2, 4]];
        let f = check_orientation(&three, &x3).unwrap();
        assert!(f.same_direction && f.elements == [1, 2], "{f:?}");
    }
}
