//! Four-node flat shell element (24 DOF): Q4 membrane + MITC4 plate bending + drilling penalty.
//!
//! ## Formulation
//! The quad is flat in its mean plane (see *Geometry*). In local axes the DOFs per node are
//! `[u, v, w, θx, θy, θz]`; with the Mindlin kinematics `u = z βx`, `v = z βy` the section
//! rotations are `βx = θy`, `βy = -θx`.
//!
//! * **Membrane**: bilinear isoparametric plane-stress quad, `Dm = E t/(1-ν²) [1 ν 0; ν 1 0; 0 0 (1-ν)/2]`,
//!   2×2 Gauss integration (passes the constant-strain patch test on distorted meshes).
//! * **Bending**: MITC4 (Bathe & Dvorkin, *Int. J. Numer. Meth. Eng.* 21 (1985) 367-383; Bathe,
//!   *Finite Element Procedures*, 2nd ed., §5.4.2): curvatures `κ = [βx,x, βy,y, βx,y + βy,x]` with
//!   `Db = E t³/(12(1-ν²)) [1 ν 0; ν 1 0; 0 0 (1-ν)/2]`; transverse shear from covariant strains
//!   `e_rz = w,r + βx x,r + βy y,r` tied at the edge mid-points A(0,1), C(0,-1) and
//!   `e_sz` at D(1,0), B(-1,0), interpolated as `e_rz = ½(1+s) e_rz^A + ½(1-s) e_rz^C`,
//!   `e_sz = ½(1+r) e_sz^D + ½(1-r) e_sz^B`, mapped back with `J⁻¹`, shear modulus `κ_s G t`
//!   (`κ_s` = [`ShellElement::shear_factor`], 5/6 by default). Full 2×2 integration: no shear
//!   locking for thin plates and no spurious zero-energy modes; the constant-curvature patch test
//!   is passed because the tied edge shear is exact for quadratic `w`, linear rotations.
//! * **Drilling**: a Hughes-Brezzi-type penalty `α G t ∫ (θz - ω)² dA`, `ω = ½(v,x - u,y)`,
//!   2×2 Gauss, `α` = [`ShellElement::drilling_factor`] = 1e-3 by default. The drilling rotation
//!   gets a fictitious rotary inertia `α ρ t³/12` so that drilling-dominated modes sit near
//!   `sqrt(12 G/(ρ t²))` (far above structural modes) whatever `α` is.
//!
//! **Why this drilling treatment**: a true drilling membrane (Allman / Ibrahimbegovic-Taylor-Wilson)
//! is the alternative; meid instead ties each column end to its plate through a rigid spider
//! ([`super::RigidLink`]) over the surrounding element ring (see [`super::machine`]), so the column's
//! torsion is carried by in-plane translations of the plate and its bending by the plate's bending
//! rotations. The drilling DOF then only needs stabilising; the penalty against the membrane
//! rotation ω (rather than a spring to ground) keeps rigid-body rotation energy-free, so a free
//! shell has exactly six zero modes, and α = 1e-3 changes membrane energies by ≲ 0.1 %.
//!
//! * **Mass**: consistent, `ρ t ∫ NᵢNⱼ dA` for u, v, w and `ρ t³/12 ∫ NᵢNⱼ dA` for θx, θy.
//!
//! ## Geometry
//! Local axes: normal `n` from the cross product of the diagonals, `e1` along the mean r-direction
//! `(x2 + x3 - x1 - x4)/2` projected on the plane, `e2 = n × e1`. Node coordinates are projected on
//! the mean plane through the centroid. Warped quads with out-of-plane distance larger than
//! [`MAX_WARP_RATIO`] times the longer diagonal are rejected (the projection would break the
//! rigid-body property). Degenerate (collapsed corner, zero area) and non-convex or self-intersecting
//! ("inverted") quads are rejected.
//!
//! Node order: counter-clockwise about the element normal, natural coordinates
//! 1(-1,-1), 2(1,-1), 3(1,1), 4(-1,1). Either winding is accepted (the normal follows it).
//!
//! Hand-written because no Rust crate provides shell elements.

use faer::Mat;

use super::frame::{block_rotation, to_global};
use super::geom::{cross, dot, norm, scale, sub, unit, V3};
use super::material::Material;
use crate::{Error, Result};

/// Default transverse shear correction factor κ_s (Reissner/Mindlin 5/6).
pub const DEFAULT_SHEAR_FACTOR: f64 = 5.0 / 6.0;
/// Default drilling penalty factor α (penalty modulus α G).
pub const DEFAULT_DRILLING_FACTOR: f64 = 1e-3;
/// Largest accepted out-of-plane node distance from the mean plane, relative to the longer diagonal.
pub const MAX_WARP_RATIO: f64 = 1e-3;

/// A four-node shell element.
#[derive(Debug, Clone, PartialEq)]
pub struct ShellElement {
    /// Node indices, in order around the element.
    pub nodes: [usize; 4],
    pub material: Material,
    /// Thickness t (m).
    pub thickness_m: f64,
    /// Transverse shear correction factor κ_s (5/6 by default; π²/12 matches Mindlin's plate theory).
    pub shear_factor: f64,
    /// Drilling penalty factor α (1e-3 by default).
    pub drilling_factor: f64,
}

impl ShellElement {
    /// Shell element with the default shear and drilling factors.
    pub fn new(nodes: [usize; 4], material: Material, thickness_m: f64) -> Self {
        ShellElement {
            nodes,
            material,
            thickness_m,
            shear_factor: DEFAULT_SHEAR_FACTOR,
            drilling_factor: DEFAULT_DRILLING_FACTOR,
        }
    }
}

/// Flat geometry of a quad: local axes (rows of global → local), local node coordinates.
#[derive(Debug, Clone, Copy)]
pub struct ShellGeometry {
    /// `[e1, e2, n]`.
    pub axes: [V3; 3],
    /// Node coordinates in the mean plane (m), relative to the centroid.
    pub local_xy: [[f64; 2]; 4],
    /// Area of the projected quad (m²).
    pub area_m2: f64,
    /// Largest distance of a node from the mean plane over the longer diagonal.
    pub warp_ratio: f64,
}

/// Computes and checks the flat geometry of a quad with nodes `x` (global, m).
/// Errors name the failure; the caller adds which element it is.
pub fn shell_geometry(x: &[V3; 4]) -> Result<ShellGeometry> {
    let d1 = sub(x[2], x[0]);
    let d2 = sub(x[3], x[1]);
    let diag = norm(d1).max(norm(d2));
    let nn = cross(d1, d2);
    let area = 0.5 * norm(nn);
    if diag.is_nan() || area.is_nan() || diag <= 0.0 || area <= 1e-10 * diag * diag {
        return Err(Error::invalid(
            "shell geometry",
            "degenerate quad (zero area: coincident nodes or crossing diagonals); give four distinct corners in order around the element",
        ));
    }
    let n = scale(nn, 0.5 / area);
    let c = scale(
        [
            x[0][0] + x[1][0] + x[2][0] + x[3][0],
            x[0][1] + x[1][1] + x[2][1] + x[3][1],
            x[0][2] + x[1][2] + x[2][2] + x[3][2],
        ],
        0.25,
    );
    let warp = x
        .iter()
        .map(|p| dot(sub(*p, c), n).abs())
        .fold(0.0, f64::max)
        / diag;
    if warp > MAX_WARP_RATIO {
        return Err(Error::invalid(
            "shell geometry",
            format!(
                "warped quad: a node lies {:.3e} x the diagonal off the mean plane (at most {MAX_WARP_RATIO:e} accepted); split it into flatter quads",
                warp
            ),
        ));
    }
    let dr = sub(
        scale(
            [x[1][0] + x[2][0], x[1][1] + x[2][1], x[1][2] + x[2][2]],
            0.5,
        ),
        scale(
            [x[0][0] + x[3][0], x[0][1] + x[3][1], x[0][2] + x[3][2]],
            0.5,
        ),
    );
    let e1 = unit(sub(dr, scale(n, dot(dr, n))))
        .ok_or_else(|| Error::invalid("shell geometry", "degenerate quad (no r-direction)"))?;
    let e2 = cross(n, e1);
    let mut xy = [[0.0; 2]; 4];
    for i in 0..4 {
        let p = sub(x[i], c);
        xy[i] = [dot(p, e1), dot(p, e2)];
    }
    // Corner Jacobians: z-component of (x_{i+1} - x_i) × (x_{i-1} - x_i) must be > 0.
    for i in 0..4 {
        let a = xy[(i + 1) % 4];
        let b = xy[(i + 3) % 4];
        let (ax, ay) = (a[0] - xy[i][0], a[1] - xy[i][1]);
        let (bx, by) = (b[0] - xy[i][0], b[1] - xy[i][1]);
        let cz = ax * by - ay * bx;
        if cz.abs() <= 1e-8 * diag * diag {
            return Err(Error::invalid(
                "shell geometry",
                format!("degenerate quad: collapsed corner at its node {} (corner angle 0 or 180 degrees)", i + 1),
            ));
        }
        if cz < 0.0 {
            return Err(Error::invalid(
                "shell geometry",
                format!("inverted quad: non-convex or self-intersecting at its node {} (order the nodes around the element)", i + 1),
            ));
        }
    }
    Ok(ShellGeometry {
        axes: [e1, e2, n],
        local_xy: xy,
        area_m2: area,
        warp_ratio: warp,
    })
}

const NODE_RS: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

/// Bilinear shape functions and their natural derivatives at (r, s).
fn shape(r: f64, s: f64) -> ([f64; 4], [f64; 4], [f64; 4]) {
    let mut n = [0.0; 4];
    let mut nr = [0.0; 4];
    let mut ns = [0.0; 4];
    for i in 0..4 {
        let (ri, si) = (NODE_RS[i][0], NODE_RS[i][1]);
        n[i] = 0.25 * (1.0 + r * ri) * (1.0 + s * si);
        nr[i] = 0.25 * ri * (1.0 + s * si);
        ns[i] = 0.25 * si * (1.0 + r * ri);
    }
    (n, nr, ns)
}

/// Jacobian `[[x_r, y_r], [x_s, y_s]]` at (r, s).
fn jacobian(xy: &[[f64; 2]; 4], nr: &[f64; 4], ns: &[f64; 4]) -> [[f64; 2]; 2] {
    let mut j = [[0.0; 2]; 2];
    for i in 0..4 {
        j[0][0] += nr[i] * xy[i][0];
        j[0][1] += nr[i] * xy[i][1];
        j[1][0] += ns[i] * xy[i][0];
        j[1][1] += ns[i] * xy[i][1];
    }
    j
}

/// Covariant transverse shear rows `(e_rz, e_sz)` (each 24 long, local DOFs) at (r, s), without tying.
fn covariant_shear(xy: &[[f64; 2]; 4], r: f64, s: f64) -> ([f64; 24], [f64; 24]) {
    let (n, nr, ns) = shape(r, s);
    let j = jacobian(xy, &nr, &ns);
    let mut er = [0.0; 24];
    let mut es = [0.0; 24];
    for i in 0..4 {
        // e_rz = w,r + βx x,r + βy y,r with βx = θy, βy = -θx.
        er[6 * i + 2] = nr[i];
        er[6 * i + 4] = n[i] * j[0][0];
        er[6 * i + 3] = -n[i] * j[0][1];
        es[6 * i + 2] = ns[i];
        es[6 * i + 4] = n[i] * j[1][0];
        es[6 * i + 3] = -n[i] * j[1][1];
    }
    (er, es)
}

/// `K += w Bᵀ D B` for strain rows `B` of length `N` (the element's DOFs: 24 for MITC4, 18 for
/// the triangle).
pub(super) fn add_btdb<const N: usize>(
    k: &mut Mat<f64>,
    rows: &[[f64; N]],
    d: &[Vec<f64>],
    w: f64,
) {
    let nr = rows.len();
    // db = D B
    let mut db = vec![[0.0; N]; nr];
    for a in 0..nr {
        for b in 0..nr {
            let dab = d[a][b];
            if dab != 0.0 {
                for c in 0..N {
                    db[a][c] += dab * rows[b][c];
                }
            }
        }
    }
    for p in 0..N {
        for a in 0..nr {
            let bp = rows[a][p];
            if bp == 0.0 {
                continue;
            }
            for q in 0..N {
                k[(p, q)] += w * bp * db[a][q];
            }
        }
    }
}

/// Local 24×24 stiffness and consistent mass of a flat quad with local node coordinates `xy`.
pub fn shell_local_matrices(
    xy: &[[f64; 2]; 4],
    material: &Material,
    thickness_m: f64,
    shear_factor: f64,
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
    let ds = vec![
        vec![shear_factor * g * t, 0.0],
        vec![0.0, shear_factor * g * t],
    ];
    let dd = vec![vec![drilling_factor * g * t]];

    // Tied covariant shear at A(0,1), C(0,-1) (e_rz) and D(1,0), B(-1,0) (e_sz).
    let (era, _) = covariant_shear(xy, 0.0, 1.0);
    let (erc, _) = covariant_shear(xy, 0.0, -1.0);
    let (_, esd) = covariant_shear(xy, 1.0, 0.0);
    let (_, esb) = covariant_shear(xy, -1.0, 0.0);

    let mut k = Mat::<f64>::zeros(24, 24);
    let mut m = Mat::<f64>::zeros(24, 24);
    let gp = 1.0 / 3.0_f64.sqrt();
    let rot = rho * t.powi(3) / 12.0;
    let dof_mass = [rho * t, rho * t, rho * t, rot, rot, drilling_factor * rot];
    for &r in &[-gp, gp] {
        for &s in &[-gp, gp] {
            let (n, nr, ns) = shape(r, s);
            let j = jacobian(xy, &nr, &ns);
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            let inv = [
                [j[1][1] / det, -j[0][1] / det],
                [-j[1][0] / det, j[0][0] / det],
            ];
            let mut nx = [0.0; 4];
            let mut ny = [0.0; 4];
            for i in 0..4 {
                nx[i] = inv[0][0] * nr[i] + inv[0][1] * ns[i];
                ny[i] = inv[1][0] * nr[i] + inv[1][1] * ns[i];
            }
            let mut bm = [[0.0; 24]; 3];
            let mut bb = [[0.0; 24]; 3];
            let mut bd = [[0.0; 24]; 1];
            for i in 0..4 {
                let o = 6 * i;
                bm[0][o] = nx[i];
                bm[1][o + 1] = ny[i];
                bm[2][o] = ny[i];
                bm[2][o + 1] = nx[i];
                // κxx = βx,x = θy,x; κyy = βy,y = -θx,y; κxy = βx,y + βy,x.
                bb[0][o + 4] = nx[i];
                bb[1][o + 3] = -ny[i];
                bb[2][o + 4] = ny[i];
                bb[2][o + 3] = -nx[i];
                // θz - ω, ω = ½(v,x - u,y).
                bd[0][o + 5] = n[i];
                bd[0][o] = 0.5 * ny[i];
                bd[0][o + 1] = -0.5 * nx[i];
            }
            let mut bs = [[0.0; 24]; 2];
            for c in 0..24 {
                let er = 0.5 * (1.0 + s) * era[c] + 0.5 * (1.0 - s) * erc[c];
                let es = 0.5 * (1.0 + r) * esd[c] + 0.5 * (1.0 - r) * esb[c];
                bs[0][c] = inv[0][0] * er + inv[0][1] * es;
                bs[1][c] = inv[1][0] * er + inv[1][1] * es;
            }
            add_btdb(&mut k, &bm, &dm, det);
            add_btdb(&mut k, &bb, &db, det);
            add_btdb(&mut k, &bs, &ds, det);
            add_btdb(&mut k, &bd, &dd, det);
            for a in 0..4 {
                for b in 0..4 {
                    let nn = n[a] * n[b] * det;
                    for d in 0..6 {
                        m[(6 * a + d, 6 * b + d)] += dof_mass[d] * nn;
                    }
                }
            }
        }
    }
    (k, m)
}

/// Global 24×24 stiffness and consistent mass of a shell element with node positions `x`.
pub fn shell_matrices(x: &[V3; 4], el: &ShellElement) -> Result<(Mat<f64>, Mat<f64>)> {
    let geo = shell_geometry(x)?;
    let (kl, ml) = shell_local_matrices(
        &geo.local_xy,
        &el.material,
        el.thickness_m,
        el.shear_factor,
        el.drilling_factor,
    );
    let t = block_rotation(&geo.axes, 8);
    Ok((to_global(&kl, &t), to_global(&ml, &t)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sym_eigs(k: &Mat<f64>) -> Vec<f64> {
        let evd = k.self_adjoint_eigen(faer::Side::Lower).unwrap();
        (0..k.nrows()).map(|i| evd.S()[i]).collect()
    }

    /// A single element (distorted, in a tilted plane) has exactly six zero-energy modes.
    #[test]
    fn single_element_has_six_rigid_modes() {
        let xy = [[0.0, 0.0], [1.1, 0.1], [1.3, 0.9], [-0.1, 0.8]];
        let axes = [[0.6, 0.8, 0.0], [-0.48, 0.36, 0.8], [0.64, -0.48, 0.6]];
        let x: [V3; 4] = std::array::from_fn(|i| {
            let (a, b) = (xy[i][0] * 0.1, xy[i][1] * 0.1);
            [
                a * axes[0][0] + b * axes[1][0] + 1.0,
                a * axes[0][1] + b * axes[1][1],
                a * axes[0][2] + b * axes[1][2] - 2.0,
            ]
        });
        let el = ShellElement::new([0, 1, 2, 3], Material::STEEL, 0.004);
        let (k, m) = shell_matrices(&x, &el).unwrap();
        let ev = sym_eigs(&k);
        let max = ev.iter().fold(0.0_f64, |a, b| a.max(b.abs()));
        let zeros = ev.iter().filter(|v| v.abs() < 1e-9 * max).count();
        assert_eq!(zeros, 6, "{ev:?}");
        // consistent mass: total mass in each translation = ρ t A
        let area = shell_geometry(&x).unwrap().area_m2;
        let mass = 7850.0 * 0.004 * area;
        for d in 0..3 {
            let mut s = 0.0;
            for a in 0..4 {
                for b in 0..4 {
                    s += m[(6 * a + d, 6 * b + d)];
                }
            }
            assert!((s - mass).abs() < 1e-12 * mass);
        }
    }

    #[test]
    fn bad_geometry_is_rejected() {
        let sq = |p: [[f64; 2]; 4]| -> [V3; 4] { std::array::from_fn(|i| [p[i][0], p[i][1], 0.0]) };
        let bow = sq([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]);
        assert!(shell_geometry(&bow)
            .unwrap_err()
            .to_string()
            .contains("degenerate"));
        let concave = sq([[0.0, 0.0], [1.0, 0.0], [0.2, 0.2], [0.0, 1.0]]);
        assert!(shell_geometry(&concave)
            .unwrap_err()
            .to_string()
            .contains("inverted"));
        let mut warped = sq([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        warped[2][2] = 0.05;
        assert!(shell_geometry(&warped)
            .unwrap_err()
            .to_string()
            .contains("warped"));
    }
}
