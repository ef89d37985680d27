//! The finite-element mesh: nodes (6 DOF each), elements, supports and named points, with
//! validation that names the offending node or element and what would be valid.

use std::collections::{BTreeMap, BTreeSet};

use super::discrete::{check_coefficients, Dashpot, PointMass, RigidLink, Spring};
use super::frame::{check_releases, frame_local_axes, FrameElement};
use super::shell::{shell_geometry, ShellElement};
use super::tri3::{tri_geometry, TriShellElement};
use crate::{Error, Result};

/// Degrees of freedom of a node, in global axes; the global DOF index is `6 * node + dof as usize`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Dof {
    Ux = 0,
    Uy = 1,
    Uz = 2,
    Rx = 3,
    Ry = 4,
    Rz = 5,
}

impl Dof {
    /// All six DOFs.
    pub const ALL: [Dof; 6] = [Dof::Ux, Dof::Uy, Dof::Uz, Dof::Rx, Dof::Ry, Dof::Rz];
    /// The three translations.
    pub const TRANSLATIONS: [Dof; 3] = [Dof::Ux, Dof::Uy, Dof::Uz];
    /// The three rotations.
    pub const ROTATIONS: [Dof; 3] = [Dof::Rx, Dof::Ry, Dof::Rz];
}

/// A finite-element mesh. Node and element indices are positions in the vectors.
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    /// Node positions (m).
    pub nodes: Vec<[f64; 3]>,
    pub frames: Vec<FrameElement>,
    pub shells: Vec<ShellElement>,
    /// Three-node shells (CST + DKT, [`super::tri3`]).
    pub triangles: Vec<TriShellElement>,
    pub springs: Vec<Spring>,
    pub dashpots: Vec<Dashpot>,
    pub masses: Vec<PointMass>,
    pub rigid_links: Vec<RigidLink>,
    /// Fixed (zero) global DOFs, `6 * node + dof`.
    pub fixed: BTreeSet<usize>,
    /// Named points: node sets (a single node for a point). Values at a set are set averages.
    pub points: BTreeMap<String, Vec<usize>>,
    /// Named sets of shell elements (e.g. Gmsh physical surfaces).
    pub element_sets: BTreeMap<String, Vec<usize>>,
    /// Named sets of triangles (indices into `triangles`), e.g. Gmsh physical surfaces.
    pub triangle_sets: BTreeMap<String, Vec<usize>>,
    /// Labelled parts (the model file's `part = "..."` on shells, frames and masses).
    pub parts: BTreeMap<String, MeshPart>,
}

/// The elements of one labelled part: indices into [`Mesh::shells`], [`Mesh::triangles`],
/// [`Mesh::frames`] and [`Mesh::masses`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MeshPart {
    pub shells: Vec<usize>,
    pub triangles: Vec<usize>,
    pub frames: Vec<usize>,
    pub masses: Vec<usize>,
}

impl Mesh {
    /// An empty mesh.
    pub fn new() -> Self {
        Self::default()
    }
    /// Adds a node at `position_m` and returns its index.
    pub fn add_node(&mut self, position_m: [f64; 3]) -> usize {
        self.nodes.push(position_m);
        self.nodes.len() - 1
    }
    /// Adds a frame element and returns its index.
    pub fn add_frame(&mut self, el: FrameElement) -> usize {
        self.frames.push(el);
        self.frames.len() - 1
    }
    /// Adds a shell element and returns its index.
    pub fn add_shell(&mut self, el: ShellElement) -> usize {
        self.shells.push(el);
        self.shells.len() - 1
    }
    /// Adds a three-node shell element and returns its index in `triangles`.
    pub fn add_triangle(&mut self, el: TriShellElement) -> usize {
        self.triangles.push(el);
        self.triangles.len() - 1
    }
    /// Adds a spring and returns its index.
    pub fn add_spring(&mut self, s: Spring) -> usize {
        self.springs.push(s);
        self.springs.len() - 1
    }
    /// Adds a dashpot and returns its index.
    pub fn add_dashpot(&mut self, d: Dashpot) -> usize {
        self.dashpots.push(d);
        self.dashpots.len() - 1
    }
    /// Adds a point mass and returns its index.
    pub fn add_mass(&mut self, m: PointMass) -> usize {
        self.masses.push(m);
        self.masses.len() - 1
    }
    /// Adds a rigid link and returns its index.
    pub fn add_rigid_link(&mut self, l: RigidLink) -> usize {
        self.rigid_links.push(l);
        self.rigid_links.len() - 1
    }
    /// Fixes the given DOFs of a node.
    pub fn fix(&mut self, node: usize, dofs: &[Dof]) {
        for d in dofs {
            self.fixed.insert(6 * node + *d as usize);
        }
    }
    /// Fixes all six DOFs of a node (clamp).
    pub fn fix_all(&mut self, node: usize) {
        self.fix(node, &Dof::ALL);
    }
    /// Names a node set (replaces an existing one of the same name).
    pub fn name_point(&mut self, name: impl Into<String>, nodes: Vec<usize>) {
        self.points.insert(name.into(), nodes);
    }

    /// Adds a structured grid of shell elements in the plane `z = z_m` with grid lines at `xs_m`
    /// and `ys_m` (each strictly increasing, at least two values). Returns the node indices as
    /// `grid[i][j]` for the node at `(xs_m[i], ys_m[j])`. Elements are numbered with `i` fastest
    /// and have counter-clockwise nodes about +z.
    pub fn add_plate_grid(
        &mut self,
        xs_m: &[f64],
        ys_m: &[f64],
        z_m: f64,
        material: super::material::Material,
        thickness_m: f64,
    ) -> Result<Vec<Vec<usize>>> {
        for (name, v) in [("x grid", xs_m), ("y grid", ys_m)] {
            if v.len() < 2
                || v.windows(2)
                    .any(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
            {
                return Err(Error::invalid(
                    format!("plate {name}"),
                    "needs at least two strictly increasing coordinates",
                ));
            }
        }
        let grid: Vec<Vec<usize>> = xs_m
            .iter()
            .map(|&x| ys_m.iter().map(|&y| self.add_node([x, y, z_m])).collect())
            .collect();
        for j in 0..ys_m.len() - 1 {
            for i in 0..xs_m.len() - 1 {
                self.add_shell(ShellElement::new(
                    [
                        grid[i][j],
                        grid[i + 1][j],
                        grid[i + 1][j + 1],
                        grid[i][j + 1],
                    ],
                    material,
                    thickness_m,
                ));
            }
        }
        Ok(grid)
    }

    /// The nodes of a named point; the error lists the known names and the closest one.
    pub fn point(&self, name: &str) -> Result<&[usize]> {
        self.points.get(name).map(|v| v.as_slice()).ok_or_else(|| {
            let known: Vec<&str> = self.points.keys().map(|s| s.as_str()).collect();
            let close = known
                .iter()
                .map(|k| (strsim::jaro_winkler(k, name), *k))
                .filter(|(s, _)| *s > 0.7)
                .max_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(_, k)| format!(" (did you mean '{k}'?)"))
                .unwrap_or_default();
            Error::invalid(
                "point",
                format!(
                    "unknown point name '{name}'{close}; known points: {}",
                    if known.is_empty() {
                        "(none)".to_string()
                    } else {
                        known.join(", ")
                    }
                ),
            )
        })
    }

    /// Total translational mass (kg) of shells, frames and point masses (elements with invalid
    /// nodes or geometry are skipped; [`Mesh::validate`] reports them).
    pub fn total_mass_kg(&self) -> f64 {
        let all = MeshPart {
            shells: (0..self.shells.len()).collect(),
            triangles: (0..self.triangles.len()).collect(),
            frames: (0..self.frames.len()).collect(),
            masses: (0..self.masses.len()).collect(),
        };
        self.mass_of(&all)
    }

    /// Translational mass (kg) of the elements of `part`: `ρ A L` per frame, `ρ t A` per
    /// shell (its area `A` as the element integrates it), plus the point masses (elements with
    /// invalid nodes or geometry are skipped; [`Mesh::validate`] reports them).
    pub fn mass_of(&self, part: &MeshPart) -> f64 {
        let at = |n: &[usize]| -> Option<Vec<[f64; 3]>> {
            n.iter().map(|&i| self.nodes.get(i).copied()).collect()
        };
        let mut m = 0.0;
        for f in part.frames.iter().filter_map(|&i| self.frames.get(i)) {
            if let Some(x) = at(&f.nodes) {
                let l = super::geom::norm(super::geom::sub(x[1], x[0]));
                m += f.material.density_kg_per_m3 * f.section.area_m2 * l;
            }
        }
        for s in part.shells.iter().filter_map(|&i| self.shells.get(i)) {
            if let Some(g) =
                at(&s.nodes).and_then(|x| shell_geometry(&[x[0], x[1], x[2], x[3]]).ok())
            {
                m += s.material.density_kg_per_m3 * s.thickness_m * g.area_m2;
            }
        }
        for s in part.triangles.iter().filter_map(|&i| self.triangles.get(i)) {
            if let Some(g) = at(&s.nodes).and_then(|x| tri_geometry(&[x[0], x[1], x[2]]).ok()) {
                m += s.material.density_kg_per_m3 * s.thickness_m * g.area_m2;
            }
        }
        m + part
            .masses
            .iter()
            .filter_map(|&i| self.masses.get(i))
            .map(|p| p.mass_kg)
            .sum::<f64>()
    }

    /// The nodes the elements of `part` connect (sorted, without repeats).
    pub fn nodes_of_part(&self, part: &MeshPart) -> Vec<usize> {
        let mut v: Vec<usize> = Vec::new();
        v.extend(
            part.frames
                .iter()
                .filter_map(|&i| self.frames.get(i))
                .flat_map(|e| e.nodes),
        );
        v.extend(
            part.shells
                .iter()
                .filter_map(|&i| self.shells.get(i))
                .flat_map(|e| e.nodes),
        );
        v.extend(
            part.triangles
                .iter()
                .filter_map(|&i| self.triangles.get(i))
                .flat_map(|e| e.nodes),
        );
        v.extend(
            part.masses
                .iter()
                .filter_map(|&i| self.masses.get(i))
                .map(|e| e.node),
        );
        v.sort_unstable();
        v.dedup();
        v
    }

    fn check_node(&self, what: &str, node: usize) -> Result<()> {
        if node < self.nodes.len() {
            Ok(())
        } else {
            Err(Error::invalid(
                what,
                format!(
                    "refers to node {node}, but the mesh has nodes 0..{}",
                    self.nodes.len().saturating_sub(1)
                ),
            ))
        }
    }

    /// Checks the whole mesh: node references, materials, sections, thicknesses, element
    /// geometry (degenerate, inverted, warped), discrete coefficients, rigid links, supports,
    /// named points, and that every node is used by something.
    pub fn validate(&self) -> Result<()> {
        if self.nodes.is_empty() {
            return Err(Error::invalid("mesh", "has no nodes"));
        }
        for (i, p) in self.nodes.iter().enumerate() {
            if p.iter().any(|c| !c.is_finite()) {
                return Err(Error::invalid(
                    format!("node {i}"),
                    format!("position {p:?} is not finite"),
                ));
            }
        }
        let mut used = vec![false; self.nodes.len()];
        self.check_frames(&mut used)?;
        self.check_shells(&mut used)?;
        self.check_triangles(&mut used)?;
        self.check_discrete(&mut used)?;
        let slave_of = self.check_rigid_links(&mut used)?;
        for &dof in &self.fixed {
            let node = dof / 6;
            self.check_node(&format!("support on DOF {dof}"), node)?;
            if let Some(j) = slave_of.get(&node) {
                return Err(Error::invalid(
                    format!("support on node {node}"),
                    format!("the node is a slave of rigid link {j}; fix its master instead"),
                ));
            }
        }
        self.check_sets()?;
        if let Some(n) = used.iter().position(|u| !u) {
            return Err(Error::invalid(
                format!("node {n}"),
                format!(
                    "at {:?} is used by no element, spring, dashpot, mass or rigid link; remove it or connect it",
                    self.nodes[n]
                ),
            ));
        }
        Ok(())
    }

    /// The frame elements: nodes, material, section, local axes (a nonzero length, an
    /// orientation off the axis) and end releases; marks their nodes used.
    fn check_frames(&self, used: &mut [bool]) -> Result<()> {
        for (i, f) in self.frames.iter().enumerate() {
            let what = format!("frame element {i} (nodes {}, {})", f.nodes[0], f.nodes[1]);
            for &n in &f.nodes {
                self.check_node(&what, n)?;
                used[n] = true;
            }
            f.material.validate(&what)?;
            f.section.validate(&what)?;
            frame_local_axes(
                self.nodes[f.nodes[0]],
                self.nodes[f.nodes[1]],
                f.orientation,
            )
            .map_err(|e| Error::invalid(what.clone(), e.to_string()))?;
            check_releases(&f.releases).map_err(|e| Error::invalid(what.clone(), e.to_string()))?;
        }
        Ok(())
    }

    /// The quadrilateral shells: nodes, material, thickness, shear and drilling factors > 0,
    /// four distinct nodes and a proper geometry (not degenerate, inverted or warped); marks
    /// their nodes used.
    fn check_shells(&self, used: &mut [bool]) -> Result<()> {
        for (i, s) in self.shells.iter().enumerate() {
            let what = format!(
                "shell element {i} (nodes {}, {}, {}, {})",
                s.nodes[0], s.nodes[1], s.nodes[2], s.nodes[3]
            );
            for &n in &s.nodes {
                self.check_node(&what, n)?;
                used[n] = true;
            }
            s.material.validate(&what)?;
            if !(s.thickness_m.is_finite() && s.thickness_m > 0.0) {
                return Err(Error::invalid(
                    format!("{what}: thickness"),
                    format!("must be > 0 m (got {})", s.thickness_m),
                ));
            }
            if !(s.shear_factor.is_finite() && s.shear_factor > 0.0) {
                return Err(Error::invalid(
                    format!("{what}: shear factor"),
                    format!("must be > 0 (5/6 is usual; got {})", s.shear_factor),
                ));
            }
            if !(s.drilling_factor.is_finite() && s.drilling_factor > 0.0) {
                return Err(Error::invalid(
                    format!("{what}: drilling factor"),
                    format!(
                        "must be > 0 (1e-3 is the default; got {})",
                        s.drilling_factor
                    ),
                ));
            }
            let mut distinct = s.nodes.to_vec();
            distinct.sort_unstable();
            distinct.dedup();
            if distinct.len() < 4 {
                return Err(Error::invalid(
                    what,
                    "is degenerate: a node is repeated; a quad needs four distinct nodes",
                ));
            }
            shell_geometry(&s.nodes.map(|n| self.nodes[n]))
                .map_err(|e| Error::invalid(what.clone(), e.to_string()))?;
        }
        Ok(())
    }

    /// The triangular shells: nodes, material, thickness and drilling factor > 0, three
    /// distinct nodes and a proper geometry; marks their nodes used.
    fn check_triangles(&self, used: &mut [bool]) -> Result<()> {
        for (i, s) in self.triangles.iter().enumerate() {
            let what = format!(
                "triangle {i} (nodes {}, {}, {})",
                s.nodes[0], s.nodes[1], s.nodes[2]
            );
            for &n in &s.nodes {
                self.check_node(&what, n)?;
                used[n] = true;
            }
            s.material.validate(&what)?;
            if !(s.thickness_m.is_finite() && s.thickness_m > 0.0) {
                return Err(Error::invalid(
                    format!("{what}: thickness"),
                    format!("must be > 0 m (got {})", s.thickness_m),
                ));
            }
            if !(s.drilling_factor.is_finite() && s.drilling_factor > 0.0) {
                return Err(Error::invalid(
                    format!("{what}: drilling factor"),
                    format!(
                        "must be > 0 (1e-3 is the default; got {})",
                        s.drilling_factor
                    ),
                ));
            }
            if s.nodes[0] == s.nodes[1] || s.nodes[1] == s.nodes[2] || s.nodes[0] == s.nodes[2] {
                return Err(Error::invalid(
                    what,
                    "is degenerate: a node is repeated; a triangle needs three distinct nodes",
                ));
            }
            tri_geometry(&s.nodes.map(|n| self.nodes[n]))
                .map_err(|e| Error::invalid(what.clone(), e.to_string()))?;
        }
        Ok(())
    }

    /// The springs, dashpots (not joining a node to itself; coefficients finite and ≥ 0) and
    /// point masses; marks their nodes used.
    fn check_discrete(&self, used: &mut [bool]) -> Result<()> {
        for (i, s) in self.springs.iter().enumerate() {
            let what = format!("spring {i} (node {})", s.node);
            self.check_node(&what, s.node)?;
            used[s.node] = true;
            if let Some(o) = s.other {
                self.check_node(&what, o)?;
                used[o] = true;
                if o == s.node {
                    return Err(Error::invalid(what, "joins a node to itself"));
                }
            }
            check_coefficients(&what, "N/m or N m/rad", &s.stiffness)?;
        }
        for (i, d) in self.dashpots.iter().enumerate() {
            let what = format!("dashpot {i} (node {})", d.node);
            self.check_node(&what, d.node)?;
            used[d.node] = true;
            if let Some(o) = d.other {
                self.check_node(&what, o)?;
                used[o] = true;
                if o == d.node {
                    return Err(Error::invalid(what, "joins a node to itself"));
                }
            }
            check_coefficients(&what, "N s/m or N m s/rad", &d.damping)?;
        }
        for (i, m) in self.masses.iter().enumerate() {
            let what = format!("point mass {i} (node {})", m.node);
            self.check_node(&what, m.node)?;
            used[m.node] = true;
            check_coefficients(&format!("{what} mass"), "kg", &[m.mass_kg])?;
            check_coefficients(&format!("{what} inertia"), "kg m^2", &m.inertia_kg_m2)?;
        }
        Ok(())
    }

    /// The rigid links: a node is the slave of one link only, never of its own link, and no
    /// master is another link's slave (no chains); marks their nodes used. Returns each slave's
    /// link.
    fn check_rigid_links(&self, used: &mut [bool]) -> Result<BTreeMap<usize, usize>> {
        let mut slave_of: BTreeMap<usize, usize> = BTreeMap::new();
        for (i, l) in self.rigid_links.iter().enumerate() {
            let what = format!("rigid link {i} (master node {})", l.master);
            self.check_node(&what, l.master)?;
            used[l.master] = true;
            for &s in &l.slaves {
                self.check_node(&what, s)?;
                used[s] = true;
                if s == l.master {
                    return Err(Error::invalid(what, "lists its master node as a slave"));
                }
                if let Some(j) = slave_of.insert(s, i) {
                    return Err(Error::invalid(
                        what,
                        format!("node {s} is already a slave of rigid link {j}; a node can be the slave of one link only (merge the links)"),
                    ));
                }
            }
        }
        for (i, l) in self.rigid_links.iter().enumerate() {
            if let Some(j) = slave_of.get(&l.master) {
                return Err(Error::invalid(
                    format!("rigid link {i} (master node {})", l.master),
                    format!("its master is a slave of rigid link {j}; chained rigid links are not supported (merge them)"),
                ));
            }
        }
        Ok(slave_of)
    }

    /// The named points (at least one existing node each) and the element and triangle sets
    /// (existing elements).
    fn check_sets(&self) -> Result<()> {
        for (name, set) in &self.points {
            if set.is_empty() {
                return Err(Error::invalid(format!("point {name}"), "names no node"));
            }
            for &n in set {
                self.check_node(&format!("point {name}"), n)?;
            }
        }
        for (name, set) in &self.element_sets {
            for &e in set {
                if e >= self.shells.len() {
                    return Err(Error::invalid(
                        format!("element set {name}"),
                        format!(
                            "refers to shell element {e}, but the mesh has {}",
                            self.shells.len()
                        ),
                    ));
                }
            }
        }
        for (name, set) in &self.triangle_sets {
            if let Some(&e) = set.iter().find(|&&e| e >= self.triangles.len()) {
                return Err(Error::invalid(
                    format!("triangle set {name}"),
                    format!(
                        "refers to triangle {e}, but the mesh has {}",
                        self.triangles.len()
                    ),
                ));
            }
        }
        Ok(())
    }
}
