//! Two-node 3-D Euler-Bernoulli frame element (12 DOF).
//!
//! Formulation (Przemieniecki, *Theory of Matrix Structural Analysis*, 1968, ch. 5 and 11;
//! also Cook, Malkus, Plesha & Witt, *Concepts and Applications of FEA*, 4th ed., §2.4, §11.3):
//! DOFs per node in local axes `[u, v, w, θx, θy, θz]`, local x from node 1 to node 2.
//!
//! * axial: `EA/L [1 -1; -1 1]`, consistent mass `ρAL/6 [2 1; 1 2]`;
//! * torsion: `GJ/L [1 -1; -1 1]`, consistent torsional inertia `ρ Ip L/6 [2 1; 1 2]` with the polar
//!   moment `Ip = Iy + Iz`;
//! * bending in the x-y plane (v, θz = dv/dx, uses Iz) with the Hermite cubic:
//!   `K = EIz/L³ [12 6L -12 6L; 6L 4L² -6L 2L²; -12 -6L 12 -6L; 6L 2L² -6L 4L²]`,
//!   `M = ρAL/420 [156 22L 54 -13L; 22L 4L² 13L -3L²; 54 13L 156 -22L; -13L -3L² -22L 4L²]`;
//! * bending in the x-z plane (w, θy = -dw/dx, uses Iy): the same matrices with the signs of the
//!   rotation rows/columns flipped.
//!
//! **End releases** (hinges): any of the local DOFs `u` (axial), `θx` (torsion), `θy`, `θz`
//! (bending) at either end may be released, i.e. the element transmits no force or moment on
//! it. The released DOFs `r` are condensed out statically (Cook et al. §2.10; Przemieniecki
//! §6.9): with the retained DOFs `c`, `u_r = −K_rr⁻¹ K_rc u_c`, i.e. `u = T u_c`, and
//! `K* = Tᵀ K T = K_cc − K_cr K_rr⁻¹ K_rc`, `M* = Tᵀ M T` (the consistent mass of the condensed
//! shape functions, e.g. the pinned-clamped cubic when one end rotation is released). The
//! released rows and columns of `K*`, `M*` are zero, so the element no longer couples to that
//! node DOF. A release set whose `K_rr` is singular (axial or torsion released at both ends)
//! leaves the element a mechanism and is an error.
//!
//! Rotary inertia of the cross-section in bending and shear deformation are neglected
//! (Euler-Bernoulli). Local axes: `e1` along the element, `e2` the component of the orientation
//! vector normal to `e1`, `e3 = e1 × e2`. Global matrices are `Tᵀ K T` with `T` = four copies of
//! the rotation `[e1; e2; e3]`.

use faer::Mat;

use super::geom::{cross, dot, norm, scale, sub, unit, V3};
use super::material::Material;
use crate::{Error, Result};

/// Cross-section properties of a frame element (local axes y, z of the section).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Section {
    /// Area A (m²).
    pub area_m2: f64,
    /// Second moment of area about local y, `∫ z² dA` (m⁴): bending with displacement along z.
    pub iy_m4: f64,
    /// Second moment of area about local z, `∫ y² dA` (m⁴): bending with displacement along y.
    pub iz_m4: f64,
    /// Saint-Venant torsion constant J (m⁴).
    pub torsion_constant_m4: f64,
}

impl Section {
    /// Section from given properties (all must be > 0).
    pub fn new(area_m2: f64, iy_m4: f64, iz_m4: f64, torsion_constant_m4: f64) -> Result<Self> {
        let s = Section {
            area_m2,
            iy_m4,
            iz_m4,
            torsion_constant_m4,
        };
        s.validate("section")?;
        Ok(s)
    }

    /// Solid rectangle, `width_m` along local y, `depth_m` along local z.
    /// `Iy = b h³/12`, `Iz = h b³/12`; torsion constant from Roark (*Formulas for Stress and
    /// Strain*, 7th ed., Table 10.7 case 4): `J = a b³ (16/3 - 3.36 b/a (1 - b⁴/(12 a⁴)))` with
    /// half-sides `a ≥ b`.
    pub fn solid_rectangle(width_m: f64, depth_m: f64) -> Result<Self> {
        positive("rectangle width", width_m)?;
        positive("rectangle depth", depth_m)?;
        let (b, h) = (width_m, depth_m);
        let a_half = 0.5 * b.max(h);
        let b_half = 0.5 * b.min(h);
        let r = b_half / a_half;
        let j = a_half * b_half.powi(3) * (16.0 / 3.0 - 3.36 * r * (1.0 - r.powi(4) / 12.0));
        Section::new(b * h, b * h.powi(3) / 12.0, h * b.powi(3) / 12.0, j)
    }

    /// Solid circle: `A = π d²/4`, `I = π d⁴/64`, `J = π d⁴/32`.
    pub fn solid_circle(diameter_m: f64) -> Result<Self> {
        positive("circle diameter", diameter_m)?;
        let d = diameter_m;
        let i = std::f64::consts::PI * d.powi(4) / 64.0;
        Section::new(std::f64::consts::PI * d * d / 4.0, i, i, 2.0 * i)
    }

    /// Circular tube: `I = π (D⁴ - d⁴)/64`, `J = 2 I` (exact for a circular annulus).
    pub fn tube(outer_diameter_m: f64, wall_m: f64) -> Result<Self> {
        positive("tube outer diameter", outer_diameter_m)?;
        positive("tube wall", wall_m)?;
        if 2.0 * wall_m > outer_diameter_m {
            return Err(Error::invalid(
                "tube wall",
                format!(
                    "must be at most half the outer diameter {outer_diameter_m} m (got {wall_m} m)"
                ),
            ));
        }
        let (d_o, d_i) = (outer_diameter_m, outer_diameter_m - 2.0 * wall_m);
        let pi = std::f64::consts::PI;
        let i = pi * (d_o.powi(4) - d_i.powi(4)) / 64.0;
        Section::new(pi * (d_o * d_o - d_i * d_i) / 4.0, i, i, 2.0 * i)
    }

    /// Rectangular tube, outer `width_m` (local y) × `depth_m` (local z), uniform `wall_m`.
    /// Bending properties exact (outer minus inner rectangle); torsion constant by Bredt's
    /// thin-wall formula `J = 4 A_m² t / p_m = 2 t (b - t)² (h - t)² / (b + h - 2t)`.
    pub fn rectangular_tube(width_m: f64, depth_m: f64, wall_m: f64) -> Result<Self> {
        positive("rectangular tube width", width_m)?;
        positive("rectangular tube depth", depth_m)?;
        positive("rectangular tube wall", wall_m)?;
        if 2.0 * wall_m >= width_m.min(depth_m) {
            return Err(Error::invalid(
                "rectangular tube wall",
                format!(
                    "must be less than half the smaller outer side {} m (got {wall_m} m)",
                    width_m.min(depth_m)
                ),
            ));
        }
        let (b, h, t) = (width_m, depth_m, wall_m);
        let (bi, hi) = (b - 2.0 * t, h - 2.0 * t);
        let j = 2.0 * t * (b - t).powi(2) * (h - t).powi(2) / (b + h - 2.0 * t);
        Section::new(
            b * h - bi * hi,
            (b * h.powi(3) - bi * hi.powi(3)) / 12.0,
            (h * b.powi(3) - hi * bi.powi(3)) / 12.0,
            j,
        )
    }

    /// Polar moment of area `Iy + Iz` (m⁴), used for the torsional inertia.
    pub fn polar_moment_m4(&self) -> f64 {
        self.iy_m4 + self.iz_m4
    }

    /// Checks that every property is finite and > 0; `what` names the owner in the error.
    pub fn validate(&self, what: &str) -> Result<()> {
        for (name, v) in [
            ("area A (m^2)", self.area_m2),
            ("Iy (m^4)", self.iy_m4),
            ("Iz (m^4)", self.iz_m4),
            ("torsion constant J (m^4)", self.torsion_constant_m4),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(
                    format!("{what}: {name}"),
                    format!("must be > 0 (got {v})"),
                ));
            }
        }
        Ok(())
    }
}

fn positive(what: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(what, format!("must be > 0 m (got {v})")))
    }
}

/// A frame element between two nodes.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameElement {
    /// Node indices (node 1 → node 2 defines local x).
    pub nodes: [usize; 2],
    pub material: Material,
    pub section: Section,
    /// Orientation vector in global axes: local y lies in the plane of local x and this vector.
    /// `None`: global Z, or global X when the element is within ~0.6° of the Z axis.
    pub orientation: Option<[f64; 3]>,
    /// Released local DOFs `[u, v, w, θx, θy, θz]` at node 1 (`[0]`) and node 2 (`[1]`); only
    /// `u`, `θx`, `θy`, `θz` may be released (module docs). All `false`: a rigid joint.
    pub releases: [[bool; 6]; 2],
}

impl FrameElement {
    /// Frame element with the default orientation.
    pub fn new(nodes: [usize; 2], material: Material, section: Section) -> Self {
        FrameElement {
            nodes,
            material,
            section,
            orientation: None,
            releases: [[false; 6]; 2],
        }
    }

    /// Whether any DOF of either end is released.
    pub fn has_releases(&self) -> bool {
        self.releases.iter().flatten().any(|&r| r)
    }
}

/// Names of the local DOFs of a frame end, as model files give them in releases.
pub const LOCAL_DOF_NAMES: [&str; 6] = ["ux", "uy", "uz", "rx", "ry", "rz"];

/// Checks that `releases` only release `u`, `θx`, `θy`, `θz` and leave no mechanism within the
/// element (`K_rr` positive definite); the error says which release to drop.
pub fn check_releases(releases: &[[bool; 6]; 2]) -> Result<()> {
    for (e, end) in releases.iter().enumerate() {
        for d in [1usize, 2] {
            if end[d] {
                return Err(Error::invalid(
                    "frame release",
                    format!(
                        "{} at end {} is a shear release, which is not supported; release ux (axial), rx (torsion), ry or rz (bending rotations)",
                        LOCAL_DOF_NAMES[d],
                        e + 1
                    ),
                ));
            }
        }
    }
    // Unit section and length: singularity of K_rr does not depend on the values.
    let sec = Section {
        area_m2: 1.0,
        iy_m4: 1.0,
        iz_m4: 1.0,
        torsion_constant_m4: 1.0,
    };
    let mat = Material {
        youngs_modulus_pa: 1.0,
        poisson_ratio: 0.3,
        density_kg_per_m3: 1.0,
    };
    let (k, _) = frame_local_matrices(1.0, &mat, &sec);
    condense(&k, &k, releases).map(|_| ())
}

/// Static condensation of the released DOFs (module docs): `(Tᵀ K T, Tᵀ M T)` with
/// `T = I` on the retained DOFs and `u_r = −K_rr⁻¹ K_rc u_c`.
fn condense(k: &Mat<f64>, m: &Mat<f64>, releases: &[[bool; 6]; 2]) -> Result<(Mat<f64>, Mat<f64>)> {
    let r: Vec<usize> = (0..12).filter(|&i| releases[i / 6][i % 6]).collect();
    if r.is_empty() {
        return Ok((k.clone(), m.clone()));
    }
    let nr = r.len();
    // Cholesky K_rr = L Lᵀ with a relative pivot test: a pivot that vanishes against its
    // diagonal entry means a rigid-body motion of the element lives on the released DOFs.
    let mut l = vec![vec![0.0; nr]; nr];
    for j in 0..nr {
        let mut d = k[(r[j], r[j])];
        for p in 0..j {
            d -= l[j][p] * l[j][p];
        }
        if d.is_nan() || d <= 1e-9 * k[(r[j], r[j])].abs() {
            let names: Vec<String> = r
                .iter()
                .map(|&i| format!("{} at end {}", LOCAL_DOF_NAMES[i % 6], i / 6 + 1))
                .collect();
            return Err(Error::invalid(
                "frame release",
                format!(
                    "releasing {} leaves the element a mechanism (it could move without straining); release fewer DOFs, e.g. the axial ux or the torsion rx at one end only",
                    names.join(", ")
                ),
            ));
        }
        l[j][j] = d.sqrt();
        for i in j + 1..nr {
            let mut s = k[(r[i], r[j])];
            for p in 0..j {
                s -= l[i][p] * l[j][p];
            }
            l[i][j] = s / l[j][j];
        }
    }
    // T = I − E_r X with X = K_rr⁻¹ K_r,: (columns of released DOFs dropped).
    let mut t = Mat::<f64>::identity(12, 12);
    for c in 0..12 {
        if r.contains(&c) {
            for &ri in &r {
                t[(ri, c)] = 0.0;
            }
            t[(c, c)] = 0.0;
            continue;
        }
        // Solve L Lᵀ x = K_rc[:, c].
        let mut y = vec![0.0; nr];
        for i in 0..nr {
            let mut s = k[(r[i], c)];
            for p in 0..i {
                s -= l[i][p] * y[p];
            }
            y[i] = s / l[i][i];
        }
        let mut x = vec![0.0; nr];
        for i in (0..nr).rev() {
            let mut s = y[i];
            for p in i + 1..nr {
                s -= l[p][i] * x[p];
            }
            x[i] = s / l[i][i];
        }
        for (i, &ri) in r.iter().enumerate() {
            t[(ri, c)] = -x[i];
        }
    }
    Ok((to_global(k, &t), to_global(m, &t)))
}

/// Local 12×12 stiffness and consistent mass with the end `releases` condensed out (module
/// docs); an error when the releases leave the element a mechanism.
pub fn frame_local_matrices_released(
    length_m: f64,
    material: &Material,
    section: &Section,
    releases: &[[bool; 6]; 2],
) -> Result<(Mat<f64>, Mat<f64>)> {
    check_releases(releases)?;
    let (k, m) = frame_local_matrices(length_m, material, section);
    condense(&k, &m, releases)
}

/// Local axes `[e1, e2, e3]` (rows of the rotation global → local) of a frame element.
pub fn frame_local_axes(x1: V3, x2: V3, orientation: Option<V3>) -> Result<[V3; 3]> {
    let d = sub(x2, x1);
    let len = norm(d);
    let e1 = unit(d).ok_or_else(|| {
        Error::invalid(
            "frame element",
            format!("zero length (both nodes at {x1:?}); the two nodes must differ"),
        )
    })?;
    let v = match orientation {
        Some(v) => v,
        None => {
            if e1[2].abs() > 0.99995 {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 0.0, 1.0]
            }
        }
    };
    let vn = norm(v);
    let e2_raw = sub(v, scale(e1, dot(v, e1)));
    if vn.is_nan() || vn <= 0.0 || norm(e2_raw) <= 1e-6 * vn || len <= 0.0 {
        return Err(Error::invalid(
            "frame element orientation",
            format!("orientation vector {v:?} is zero or parallel to the element axis {e1:?}; give a vector not parallel to the element"),
        ));
    }
    let e2 = scale(e2_raw, 1.0 / norm(e2_raw));
    let e3 = cross(e1, e2);
    Ok([e1, e2, e3])
}

/// Local 12×12 stiffness and consistent mass of a straight frame element of length `length_m`.
pub fn frame_local_matrices(
    length_m: f64,
    material: &Material,
    section: &Section,
) -> (Mat<f64>, Mat<f64>) {
    let l = length_m;
    let e = material.youngs_modulus_pa;
    let g = material.shear_modulus_pa();
    let rho = material.density_kg_per_m3;
    let a = section.area_m2;
    let mut k = Mat::<f64>::zeros(12, 12);
    let mut m = Mat::<f64>::zeros(12, 12);
    // Two-node rods: axial (0, 6) and torsion (3, 9).
    let rod = |mat: &mut Mat<f64>, i: usize, j: usize, s: f64, diag: f64, off: f64| {
        mat[(i, i)] += s * diag;
        mat[(j, j)] += s * diag;
        mat[(i, j)] += s * off;
        mat[(j, i)] += s * off;
    };
    rod(&mut k, 0, 6, e * a / l, 1.0, -1.0);
    rod(&mut m, 0, 6, rho * a * l / 6.0, 2.0, 1.0);
    rod(&mut k, 3, 9, g * section.torsion_constant_m4 / l, 1.0, -1.0);
    rod(
        &mut m,
        3,
        9,
        rho * section.polar_moment_m4() * l / 6.0,
        2.0,
        1.0,
    );
    // Hermite beam in [v1, θ1, v2, θ2] with θ = dv/dx.
    let kb = [
        [12.0, 6.0 * l, -12.0, 6.0 * l],
        [6.0 * l, 4.0 * l * l, -6.0 * l, 2.0 * l * l],
        [-12.0, -6.0 * l, 12.0, -6.0 * l],
        [6.0 * l, 2.0 * l * l, -6.0 * l, 4.0 * l * l],
    ];
    let mb = [
        [156.0, 22.0 * l, 54.0, -13.0 * l],
        [22.0 * l, 4.0 * l * l, 13.0 * l, -3.0 * l * l],
        [54.0, 13.0 * l, 156.0, -22.0 * l],
        [-13.0 * l, -3.0 * l * l, -22.0 * l, 4.0 * l * l],
    ];
    let mass_b = rho * a * l / 420.0;
    // x-y plane: v (1, 7), θz (5, 11), θz = +dv/dx.
    let xy = [1usize, 5, 7, 11];
    let sxy = [1.0, 1.0, 1.0, 1.0];
    // x-z plane: w (2, 8), θy (4, 10), θy = -dw/dx.
    let xz = [2usize, 4, 8, 10];
    let sxz = [1.0, -1.0, 1.0, -1.0];
    let kxy = e * section.iz_m4 / l.powi(3);
    let kxz = e * section.iy_m4 / l.powi(3);
    for p in 0..4 {
        for q in 0..4 {
            k[(xy[p], xy[q])] += kxy * kb[p][q] * sxy[p] * sxy[q];
            m[(xy[p], xy[q])] += mass_b * mb[p][q] * sxy[p] * sxy[q];
            k[(xz[p], xz[q])] += kxz * kb[p][q] * sxz[p] * sxz[q];
            m[(xz[p], xz[q])] += mass_b * mb[p][q] * sxz[p] * sxz[q];
        }
    }
    (k, m)
}

/// Global 12×12 stiffness and consistent mass of a frame element between `x1` and `x2`.
pub fn frame_matrices(
    x1: V3,
    x2: V3,
    material: &Material,
    section: &Section,
    orientation: Option<V3>,
) -> Result<(Mat<f64>, Mat<f64>)> {
    frame_matrices_released(x1, x2, material, section, orientation, &[[false; 6]; 2])
}

/// [`frame_matrices`] with end releases (local DOFs, module docs) condensed out.
pub fn frame_matrices_released(
    x1: V3,
    x2: V3,
    material: &Material,
    section: &Section,
    orientation: Option<V3>,
    releases: &[[bool; 6]; 2],
) -> Result<(Mat<f64>, Mat<f64>)> {
    let axes = frame_local_axes(x1, x2, orientation)?;
    let (kl, ml) = frame_local_matrices_released(norm(sub(x2, x1)), material, section, releases)?;
    let t = block_rotation(&axes, 4);
    Ok((to_global(&kl, &t), to_global(&ml, &t)))
}

/// Block-diagonal rotation with `blocks` copies of the 3×3 matrix whose rows are `axes`.
pub(crate) fn block_rotation(axes: &[V3; 3], blocks: usize) -> Mat<f64> {
    let n = 3 * blocks;
    let mut t = Mat::<f64>::zeros(n, n);
    for b in 0..blocks {
        for r in 0..3 {
            for c in 0..3 {
                t[(3 * b + r, 3 * b + c)] = axes[r][c];
            }
        }
    }
    t
}

/// `Tᵀ A T`, symmetrised (sequential products: faer's `*` would follow the global parallelism).
pub(crate) fn to_global(a: &Mat<f64>, t: &Mat<f64>) -> Mat<f64> {
    use crate::modal::kernels::mul;
    let mut g = mul(mul(t.transpose(), a.as_ref()).as_ref(), t.as_ref());
    let n = g.nrows();
    for j in 0..n {
        for i in 0..j {
            let s = 0.5 * (g[(i, j)] + g[(j, i)]);
            g[(i, j)] = s;
            g[(j, i)] = s;
        }
    }
    g
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::prelude::Solve;

    #[test]
    fn cantilever_tip_deflection_matches_beam_theory() {
        // One element is exact for a tip load: δ = P L³ / (3 E I), θ = P L² / (2 E I).
        let sec = Section::solid_rectangle(0.02, 0.04).unwrap();
        let mat = Material::STEEL;
        let l = 0.7;
        let (k, _) = frame_matrices([0.0; 3], [l, 0.0, 0.0], &mat, &sec, None).unwrap();
        // Free DOFs at node 2 (6..12): solve K22 u = f with f = P in global z.
        let k22 = k.submatrix(6, 6, 6, 6).to_owned();
        let mut f = Mat::<f64>::zeros(6, 1);
        let p = 100.0;
        f[(2, 0)] = p;
        let u = k22.full_piv_lu().solve(&f);
        // Default orientation: local y = global Z; local z = e1 × e2 = -global Y, so displacement
        // along global z bends about local z (Iz).
        let ei = mat.youngs_modulus_pa * sec.iz_m4;
        let d = p * l.powi(3) / (3.0 * ei);
        assert!((u[(2, 0)] - d).abs() < 1e-12 * d.abs().max(1e-30) * 1e3);
        // rotation about global y is -dw/dx
        let th = p * l * l / (2.0 * ei);
        assert!((u[(4, 0)] + th).abs() < 1e-9 * th);
    }

    #[test]
    fn element_mass_is_total_mass_in_each_direction() {
        let sec = Section::tube(0.05, 0.004).unwrap();
        let mat = Material::STEEL;
        let (x1, x2) = ([0.1, 0.2, 0.3], [0.5, -0.1, 0.9]);
        let (_, m) = frame_matrices(x1, x2, &mat, &sec, None).unwrap();
        let mass = mat.density_kg_per_m3 * sec.area_m2 * norm(sub(x2, x1));
        for dir in 0..3 {
            let mut s = 0.0;
            for i in [dir, dir + 6] {
                for j in [dir, dir + 6] {
                    s += m[(i, j)];
                }
            }
            assert!((s - mass).abs() < 1e-12 * mass, "{s} vs {mass}");
        }
    }

    /// One element clamped at node 1 with both bending rotations released at node 2: the
    /// condensed transverse stiffness at node 2 is the propped value `3EI/L³` (a cantilever's
    /// tip under a force with the moment-free end), not `12EI/L³`, and its mass coefficient is
    /// that of the clamped-pinned cubic `N = (3ξ² − ξ³)/2`: `ρAL ∫N² = 33/140 ρAL`. Released
    /// rows and columns are zero.
    #[test]
    fn released_end_rotation_condenses_to_the_propped_values() {
        let sec = Section::new(2e-3, 3e-7, 5e-7, 1e-6).unwrap();
        let mat = Material::STEEL;
        let l = 1.3;
        let mut rel = [[false; 6]; 2];
        rel[1][4] = true;
        rel[1][5] = true;
        let (k, m) = frame_local_matrices_released(l, &mat, &sec, &rel).unwrap();
        let e = mat.youngs_modulus_pa;
        let mass = mat.density_kg_per_m3 * sec.area_m2 * l;
        // v2 (7) bends with Iz, w2 (8) with Iy.
        for (dof, i) in [(7usize, sec.iz_m4), (8, sec.iy_m4)] {
            let want = 3.0 * e * i / l.powi(3);
            assert!(
                (k[(dof, dof)] - want).abs() < 1e-10 * want,
                "{}",
                k[(dof, dof)]
            );
            let mw = 33.0 / 140.0 * mass;
            assert!(
                (m[(dof, dof)] - mw).abs() < 1e-12 * mass,
                "{}",
                m[(dof, dof)]
            );
        }
        for d in [10usize, 11] {
            for j in 0..12 {
                assert_eq!(k[(d, j)], 0.0);
                assert_eq!(m[(j, d)], 0.0);
            }
        }
        // Axial and torsion untouched.
        let (k0, _) = frame_local_matrices(l, &mat, &sec);
        assert_eq!(k[(0, 0)], k0[(0, 0)]);
        assert_eq!(k[(3, 9)], k0[(3, 9)]);
    }

    /// Axial (or torsion) released at both ends, or every bending DOF of a plane, leaves the
    /// element a mechanism: an error; shear releases are refused.
    #[test]
    fn mechanism_releases_are_errors() {
        let mut rel = [[false; 6]; 2];
        rel[0][0] = true;
        rel[1][0] = true;
        let e = check_releases(&rel).unwrap_err().to_string();
        assert!(e.contains("mechanism"), "{e}");
        let mut rel = [[false; 6]; 2];
        rel[0][3] = true;
        rel[1][3] = true;
        assert!(check_releases(&rel).is_err());
        let mut rel = [[false; 6]; 2];
        rel[0][1] = true;
        let e = check_releases(&rel).unwrap_err().to_string();
        assert!(e.contains("shear"), "{e}");
        // Pinned-pinned in both planes plus torsion at one end is fine.
        let mut rel = [[false; 6]; 2];
        for d in [3, 4, 5] {
            rel[0][d] = true;
        }
        rel[1][4] = true;
        rel[1][5] = true;
        check_releases(&rel).unwrap();
    }

    #[test]
    fn parallel_orientation_is_rejected() {
        let err = frame_local_axes([0.0; 3], [1.0, 0.0, 0.0], Some([2.0, 0.0, 0.0]))
            .unwrap_err()
            .to_string();
        assert!(err.contains("parallel"), "{err}");
    }
}
