//! The general finite-element model section, `[structure.fem.model]`: any structure of nodes,
//! shells, frames, springs, dashpots, point masses, rigid links and constraints, inline or from a
//! Gmsh mesh (see `docs/reference/model-file.md`).
//!
//! ```toml
//! [structure.fem.model]
//! mesh = "press.msh"              # optional Gmsh 4.1 ASCII file (relative to the model file):
//!                                 # quadrangles and triangles → shells, 2-node lines → frames,
//!                                 # physical groups → sets
//! nodes = [[0, 0, 0], [0, 0, 2]]  # inline nodes (m), referenced by 0-based index
//! sets = { top = [1] }            # inline node sets (indices into `nodes`)
//! material = { youngs_modulus = 2.1e11, poisson_ratio = 0.3, density = 7850 }   # default
//! shells = [{ set = "plate", thickness = 0.02, shear_factor = 0.8333 }]         # per element set
//! frames = [{ nodes = [0, 1], divisions = 10, area = 1e-3, iy = 1e-6, iz = 1e-6, j = 2e-6,
//!             orientation = [1, 0, 0],                                         # or set = "columns"
//!             releases = [{ node = 1, dofs = ["ry", "rz"] }] }]                # hinge at node 1
//! springs = [{ node = "feet", stiffness = [0, 0, 1e6, 0, 0, 0] }]  # to ground, or `to = <node>`
//! dashpots = [{ node = "feet", damping = [0, 0, 1e3, 0, 0, 0] }]
//! masses = [{ node = 1, mass = 10.0, inertia = [0.1, 0.1, 0.2] }]
//! # part = "bed" on shells, frames or masses marks the bed: its mass is m_b for md/mb studies
//! rigid_links = [{ master = 1, slaves = "top_ring" }]
//! constraints = [{ set = "base", dofs = ["ux", "uy", "uz"] }]
//! points = { O_b = "top", B = "top" }     # meid's points: node sets (every set is a point too)
//! impact_direction = [0, 0, -1]
//! ```
//!
//! A node reference (`node`, `to`, `master`, `slaves`) is an inline node index (integer), the
//! name of a node set (string: a Gmsh physical group or an entry of `sets`) or a list of inline
//! node indices. Springs, dashpots and masses given on a set or list act at each of its nodes.
//! `frames[].nodes` is a chain `[a, b, c, ...]`: one straight member per consecutive pair. The
//! paper's machine (`[structure.fem.machine]`) generates this model
//! ([`crate::structure::MachineSpec::generate`]) and is built by [`build_mesh`] too. Units: m, kg, N/m, N·m/rad, N·s/m, Pa,
//! kg/m³, m², m⁴, kg·m². Rigid links are eliminated exactly (master-slave transformation,
//! [`crate::structure::discrete`]); constraints remove DOFs and their reactions are part of the
//! floor force.
//!
//! `part = "<label>"` on a `shells`, `frames` or `masses` entry labels its elements
//! ([`Mesh::parts`]). The label `"bed"` is meid's: the bed's mass (`ρ t A` of its shells,
//! `ρ A L` of its frames, plus its point masses) is the bed mass m_b of `md/mb` studies when
//! `points.bed_contact` lies on it ([`crate::model::Model::bed_mass`]).

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::material::{check_material, MaterialSpec};
use super::Source;
use crate::structure::{
    Dashpot, FeModel, FrameElement, Material, Mesh, MeshPart, PointMass, RigidLink, Section,
    ShellElement, Spring, TriShellElement,
};
use crate::{Error, Result};

/// A node by inline index, a node set by name, or a list of inline node indices.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(untagged)]
pub enum NodeRef {
    Index(usize),
    Set(String),
    /// Inline node indices, in order (e.g. the slaves of a rigid link).
    List(Vec<usize>),
}

/// `[structure.fem.model]` (module docs).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct GeneralSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<String>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub nodes: Vec<[f64; 3]>,
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub sets: BTreeMap<String, Vec<usize>>,
    #[serde(default)]
    pub material: Option<MaterialSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub shells: Vec<ShellSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub frames: Vec<FrameSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub springs: Vec<SpringSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub dashpots: Vec<DashpotSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub masses: Vec<MassSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub rigid_links: Vec<RigidLinkSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub constraints: Vec<ConstraintSpec>,
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub points: BTreeMap<String, String>,
    #[serde(default)]
    pub impact_direction: Option<[f64; 3]>,
}

/// Shells of one section: the quadrangles and triangles of a Gmsh physical surface and/or inline
/// quadrangles (MITC4) and triangles (CST + DKT, Kirchhoff: `shear_factor` acts on quadrangles).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShellSpec {
    /// Gmsh physical surface.
    #[serde(default)]
    pub set: Option<String>,
    /// Inline quadrangles (node indices, in order around the element).
    #[serde(default)]
    pub quads: Vec<[usize; 4]>,
    /// Inline triangles (node indices; the triangles of one entry must be ordered alike).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub triangles: Vec<[usize; 3]>,
    /// m.
    pub thickness: f64,
    #[serde(default)]
    pub material: Option<MaterialSpec>,
    /// Transverse shear correction factor κ (default 5/6; π²/12 matches Mindlin's plate).
    #[serde(default)]
    pub shear_factor: Option<f64>,
    /// Part label (docs/reference/model-file.md): `part = "bed"` marks the bed, whose mass is the
    /// bed mass m_b of `md/mb` studies.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub part: Option<String>,
}

/// 3-D Euler-Bernoulli frames of one section: the 2-node lines of a Gmsh physical curve, or a
/// chain of inline nodes `[a, b, c, ...]` (one member per consecutive pair, each straight and
/// cut into `divisions` elements).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FrameSpec {
    #[serde(default)]
    pub set: Option<String>,
    #[serde(default)]
    pub nodes: Option<Vec<usize>>,
    #[serde(default)]
    pub divisions: Option<usize>,
    /// m².
    pub area: f64,
    /// m⁴, about local y.
    pub iy: f64,
    /// m⁴, about local z.
    pub iz: f64,
    /// Torsion constant, m⁴.
    pub j: f64,
    /// Local y lies in the plane of the element axis and this vector (default global Z, or X
    /// for members along Z).
    #[serde(default)]
    pub orientation: Option<[f64; 3]>,
    #[serde(default)]
    pub material: Option<MaterialSpec>,
    /// End releases (hinges): at the element ends of this member that lie on `node`, the
    /// element transmits no force or moment on the listed local DOFs (condensed out statically,
    /// [`crate::structure::frame`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub releases: Vec<ReleaseSpec>,
    /// Part label (docs/reference/model-file.md): `part = "bed"` marks the bed, whose mass is the
    /// bed mass m_b of `md/mb` studies.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub part: Option<String>,
}

/// `{ node = <node or set>, dofs = ["ry", "rz"] }`: local DOFs `ux` (axial), `rx` (torsion),
/// `ry`, `rz` (bending rotations about the local y, z axes) released at that member end.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ReleaseSpec {
    pub node: NodeRef,
    pub dofs: Vec<String>,
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SpringSpec {
    pub node: NodeRef,
    /// Other end (one node); ground when absent.
    #[serde(default)]
    pub to: Option<NodeRef>,
    /// `[x, y, z, rx, ry, rz]`: N/m and N·m/rad.
    pub stiffness: [f64; 6],
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DashpotSpec {
    pub node: NodeRef,
    #[serde(default)]
    pub to: Option<NodeRef>,
    /// `[x, y, z, rx, ry, rz]`: N·s/m and N·m·s/rad.
    pub damping: [f64; 6],
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MassSpec {
    pub node: NodeRef,
    /// kg.
    pub mass: f64,
    /// `[Ixx, Iyy, Izz]` about global axes through the node (kg·m²).
    #[serde(default)]
    pub inertia: Option<[f64; 3]>,
    /// Part label (docs/reference/model-file.md): `part = "bed"` marks the bed, whose mass is the
    /// bed mass m_b of `md/mb` studies.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub part: Option<String>,
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RigidLinkSpec {
    pub master: NodeRef,
    pub slaves: NodeRef,
}

struct Builder<'a> {
    src: &'a Source,
    mesh: Mesh,
    gmsh: Option<crate::structure::gmsh::GmshMesh>,
    /// Gmsh node index → mesh node (added when used).
    gmap: Vec<Option<usize>>,
    /// Inline node index → mesh node.
    inline: Vec<usize>,
    sets: BTreeMap<String, Vec<usize>>,
}

/// Zero displacement of some DOFs at every node of a set.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ConstraintSpec {
    /// Node set (Gmsh physical group or `[structure.fem.model]` set).
    pub set: String,
    /// Any of "ux", "uy", "uz", "rx", "ry", "rz", or "all", "translations", "rotations".
    pub dofs: Vec<String>,
}

/// The DOFs a list of names gives (`field` names the list in errors).
pub fn parse_dofs(names: &[String], field: &str) -> Result<Vec<crate::structure::Dof>> {
    use crate::structure::Dof;
    let mut out = Vec::new();
    if names.is_empty() {
        return Err(Error::invalid(
            field,
            "is empty; give some of \"ux\", \"uy\", \"uz\", \"rx\", \"ry\", \"rz\", \"all\", \"translations\", \"rotations\"",
        ));
    }
    for n in names {
        match n.as_str() {
            "all" => out.extend(Dof::ALL),
            "translations" => out.extend(Dof::TRANSLATIONS),
            "rotations" => out.extend(Dof::ROTATIONS),
            other => match crate::structure::DOF_NAMES.iter().position(|d| *d == other) {
                Some(i) => out.push(Dof::ALL[i]),
                None => {
                    return Err(Error::invalid(
                        field,
                        format!("unknown DOF '{other}'; valid: ux, uy, uz, rx, ry, rz, all, translations, rotations"),
                    ))
                }
            },
        }
    }
    out.sort_unstable();
    out.dedup();
    Ok(out)
}

/// The part label of the bed in a general model (`part = "bed"`): its mass is the bed mass m_b
/// of `md/mb` ([`super::Model::bed_mass`]).
pub const BED_PART: &str = "bed";

const BASE: &str = "structure.fem.model";

impl Builder<'_> {
    /// Records an element in its labelled part, if it has one.
    fn in_part(&mut self, part: &Option<String>, add: impl FnOnce(&mut MeshPart)) {
        if let Some(name) = part {
            add(self.mesh.parts.entry(name.clone()).or_default());
        }
    }
    fn err(&self, field: &str, msg: impl std::fmt::Display) -> crate::Error {
        let f = format!("{BASE}.{field}");
        self.src.error(&f, format!("{f}: {msg}"))
    }
    fn gnode(&mut self, i: usize) -> usize {
        if let Some(x) = self.gmap[i] {
            return x;
        }
        let p = self.gmsh.as_ref().map(|g| g.nodes[i]).unwrap_or([0.0; 3]);
        let x = self.mesh.add_node(p);
        self.gmap[i] = Some(x);
        x
    }
    fn inline_node(&self, i: usize, field: &str) -> Result<usize> {
        self.inline.get(i).copied().ok_or_else(|| {
            self.err(
                field,
                format!(
                    "node {i} does not exist; `nodes` holds {} nodes (0..{})",
                    self.inline.len(),
                    self.inline.len().saturating_sub(1)
                ),
            )
        })
    }
    fn nodes_of(&mut self, r: &NodeRef, field: &str) -> Result<Vec<usize>> {
        match r {
            NodeRef::Index(i) => Ok(vec![self.inline_node(*i, field)?]),
            NodeRef::List(v) => {
                if v.is_empty() {
                    return Err(self.err(field, "is an empty list of nodes"));
                }
                v.iter().map(|&i| self.inline_node(i, field)).collect()
            }
            NodeRef::Set(name) => {
                if let Some(v) = self.sets.get(name) {
                    return Ok(v.clone());
                }
                if let Some(g) = self
                    .gmsh
                    .as_ref()
                    .and_then(|g| g.node_sets.get(name))
                    .cloned()
                {
                    let v: Vec<usize> = g.iter().map(|&i| self.gnode(i)).collect();
                    self.sets.insert(name.clone(), v.clone());
                    return Ok(v);
                }
                let mut known: Vec<String> = self.sets.keys().cloned().collect();
                if let Some(g) = &self.gmsh {
                    known.extend(g.node_sets.keys().cloned());
                }
                known.sort();
                known.dedup();
                Err(self.err(
                    field,
                    format!(
                        "unknown node set '{name}'; known sets: {}",
                        if known.is_empty() {
                            "(none)".into()
                        } else {
                            known.join(", ")
                        }
                    ),
                ))
            }
        }
    }
    fn one_node(&mut self, r: &NodeRef, field: &str) -> Result<usize> {
        let v = self.nodes_of(r, field)?;
        match v.as_slice() {
            [one] => Ok(*one),
            _ => Err(self.err(
                field,
                format!("must be one node; the set holds {} nodes", v.len()),
            )),
        }
    }
    fn material(
        &self,
        m: &Option<MaterialSpec>,
        default: Material,
        field: &str,
    ) -> Result<Material> {
        match m {
            Some(spec) => {
                check_material(spec, &format!("{BASE}.{field}"), self.src)?;
                Ok(Material::from(*spec))
            }
            None => Ok(default),
        }
    }
}

fn positive(b: &Builder<'_>, field: &str, v: f64, unit: &str) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(b.err(
            field,
            format!("must be a finite number > 0 {unit} (got {})", crate::num(v)),
        ))
    }
}

fn nonnegative(b: &Builder<'_>, field: &str, v: &[f64], unit: &str) -> Result<()> {
    match v.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
        None => Ok(()),
        Some(i) => Err(b.err(
            field,
            format!(
                "component {} ({}) must be finite and >= 0 {unit} (got {})",
                i + 1,
                ["x", "y", "z", "rx", "ry", "rz"][i.min(5)],
                crate::num(v[i])
            ),
        )),
    }
}

/// Builds the mesh a `[structure.fem.model]` describes and assembles it.
pub fn build(spec: &GeneralSpec, src: &Source) -> Result<FeModel> {
    let (mesh, d) = build_mesh(spec, src)?;
    FeModel::assemble_with_direction(mesh, d).map_err(|e| src.error(BASE, format!("{BASE}: {e}")))
}

/// The mesh a `[structure.fem.model]` describes and its unit impact direction, not yet
/// assembled: the one path from a general model to elements, shared by users' models and the
/// paper's machine ([`crate::structure::MachineSpec::generate`]). Inline nodes are the first
/// mesh nodes, in their order; nodes of Gmsh elements and of `divisions` follow.
pub fn build_mesh(spec: &GeneralSpec, src: &Source) -> Result<(Mesh, [f64; 3])> {
    let mut b = Builder::start(spec, src)?;
    let default_mat = b.material(&spec.material, Material::STEEL, "material")?;
    b.add_shells(spec, default_mat)?;
    b.add_frames(spec, default_mat)?;
    b.add_discrete(spec)?;
    b.add_links_and_constraints(spec)?;
    b.name_points(spec)?;
    let d = spec.impact_direction.unwrap_or([0.0, 0.0, -1.0]);
    let norm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return Err(b.err("impact_direction", "must be a nonzero finite vector"));
    }
    check_coincident_nodes(&b, spec)?;
    Ok((b.mesh, [d[0] / norm, d[1] / norm, d[2] / norm]))
}

/// Which shell section (`shells[k]`) each Gmsh quadrangle and triangle has taken so far:
/// every one must get exactly one.
struct ShellSections {
    quads: Vec<Option<usize>>,
    triangles: Vec<Option<usize>>,
}

impl<'a> Builder<'a> {
    /// Reads the Gmsh mesh (relative to the model file), adds the inline `nodes` in their order
    /// and resolves the inline `sets`.
    fn start(spec: &GeneralSpec, src: &'a Source) -> Result<Self> {
        let gmsh = match &spec.mesh {
            Some(file) => {
                let dir = Path::new(&src.name)
                    .parent()
                    .map(Path::to_path_buf)
                    .unwrap_or_default();
                Some(crate::structure::gmsh::read_msh(dir.join(file))?)
            }
            None => None,
        };
        let ng = gmsh.as_ref().map(|g| g.nodes.len()).unwrap_or(0);
        let mut b = Builder {
            src,
            mesh: Mesh::new(),
            gmsh,
            gmap: vec![None; ng],
            inline: Vec::new(),
            sets: BTreeMap::new(),
        };
        for (i, p) in spec.nodes.iter().enumerate() {
            if p.iter().any(|c| !c.is_finite()) {
                return Err(b.err(&format!("nodes[{i}]"), "coordinates must be finite (m)"));
            }
            let x = b.mesh.add_node(*p);
            b.inline.push(x);
        }
        for (name, v) in &spec.sets {
            let mut nodes = Vec::with_capacity(v.len());
            for &i in v {
                nodes.push(b.inline_node(i, &format!("sets.{name}"))?);
            }
            if nodes.is_empty() {
                return Err(b.err(&format!("sets.{name}"), "is empty"));
            }
            b.sets.insert(name.clone(), nodes);
        }
        Ok(b)
    }
}

impl Builder<'_> {
    /// Adds every `shells` entry's quadrangles and triangles, then refuses a Gmsh quadrangle or
    /// triangle that no entry gave a section.
    fn add_shells(&mut self, spec: &GeneralSpec, default_mat: Material) -> Result<()> {
        let nq = self.gmsh.as_ref().map(|g| g.quads.len()).unwrap_or(0);
        let nt = self.gmsh.as_ref().map(|g| g.triangles.len()).unwrap_or(0);
        let mut taken = ShellSections {
            quads: vec![None; nq],
            triangles: vec![None; nt],
        };
        for (si, s) in spec.shells.iter().enumerate() {
            self.add_shell(si, s, default_mat, &mut taken)?;
        }
        if let Some(q) = taken.quads.iter().position(|s| s.is_none()) {
            let tag = self.gmsh.as_ref().map(|g| g.quad_tags[q]).unwrap_or(0);
            return Err(self.err(
                "shells",
                format!("quadrangle {tag} of the mesh is in no `shells` set: give its physical surface a section"),
            ));
        }
        if let Some(t) = taken.triangles.iter().position(|s| s.is_none()) {
            let tag = self.gmsh.as_ref().map(|g| g.triangle_tags[t]).unwrap_or(0);
            return Err(self.err(
                "shells",
                format!("triangle {tag} of the mesh is in no `shells` set: give its physical surface a section"),
            ));
        }
        Ok(())
    }

    /// One `shells[si]` entry: checks its thickness (against its own extent too), material and
    /// shear factor κ, gathers its elements (Gmsh set, inline quads, inline triangles) and adds
    /// them to the mesh and its part.
    fn add_shell(
        &mut self,
        si: usize,
        s: &ShellSpec,
        default_mat: Material,
        taken: &mut ShellSections,
    ) -> Result<()> {
        let field = format!("shells[{si}]");
        positive(self, &format!("{field}.thickness"), s.thickness, "m")?;
        let mat = self.material(&s.material, default_mat, &format!("{field}.material"))?;
        let kappa = s
            .shear_factor
            .unwrap_or(crate::structure::shell::DEFAULT_SHEAR_FACTOR);
        positive(
            self,
            &format!("{field}.shear_factor"),
            kappa,
            "(5/6 is usual)",
        )?;
        let mut quads: Vec<[usize; 4]> = Vec::new();
        let mut tris: Vec<[usize; 3]> = Vec::new();
        if let Some(set) = &s.set {
            self.shell_set_elements(si, &field, set, taken, &mut quads, &mut tris)?;
        }
        for (k, q) in s.quads.iter().enumerate() {
            let mut nodes = [0; 4];
            for (c, &i) in q.iter().enumerate() {
                nodes[c] = self.inline_node(i, &format!("{field}.quads[{k}]"))?;
            }
            quads.push(nodes);
        }
        self.inline_triangles(&field, s, &mut tris)?;
        if quads.is_empty() && tris.is_empty() {
            return Err(self.err(
                &field,
                "has no elements: give `set` (a Gmsh physical surface), `quads` or `triangles`",
            ));
        }
        let extent = bounding_diagonal(
            quads
                .iter()
                .flatten()
                .chain(tris.iter().flatten())
                .map(|&n| self.mesh.nodes[n]),
        );
        if let Some(msg) = thickness_fault(s.thickness, extent) {
            return Err(self.err(&format!("{field}.thickness"), msg));
        }
        for q in quads {
            let mut el = ShellElement::new(q, mat, s.thickness);
            el.shear_factor = kappa;
            let e = self.mesh.add_shell(el);
            self.in_part(&s.part, |p| p.shells.push(e));
        }
        for t in tris {
            let e = self
                .mesh
                .add_triangle(TriShellElement::new(t, mat, s.thickness));
            self.in_part(&s.part, |p| p.triangles.push(e));
        }
        Ok(())
    }

    /// The quadrangles and triangles of the Gmsh physical surface `set` for `shells[si]`,
    /// refusing an element another entry already gave a section.
    fn shell_set_elements(
        &mut self,
        si: usize,
        field: &str,
        set: &str,
        taken: &mut ShellSections,
        quads: &mut Vec<[usize; 4]>,
        tris: &mut Vec<[usize; 3]>,
    ) -> Result<()> {
        let g = self.gmsh.as_ref();
        let tri_ids = g
            .and_then(|g| g.triangle_sets.get(set))
            .cloned()
            .unwrap_or_default();
        let ids = g
            .and_then(|g| g.element_sets.get(set))
            .cloned()
            .or_else(|| (!tri_ids.is_empty()).then(Vec::new))
            .ok_or_else(|| {
                let mut known: Vec<String> = g
                    .map(|g| {
                        g.element_sets
                            .keys()
                            .chain(g.triangle_sets.keys())
                            .cloned()
                            .collect()
                    })
                    .unwrap_or_default();
                known.sort();
                known.dedup();
                self.err(
                    &format!("{field}.set"),
                    format!(
                        "no physical surface '{set}' of quadrangles or triangles in the mesh; known: {}",
                        if known.is_empty() {
                            "(none)".to_string()
                        } else {
                            known.join(", ")
                        }
                    ),
                )
            })?;
        for q in ids {
            if let Some(prev) = taken.quads[q] {
                let tag = self.gmsh.as_ref().map(|g| g.quad_tags[q]).unwrap_or(0);
                return Err(self.err(
                    &format!("{field}.set"),
                    format!("quadrangle {tag} already has the section of shells[{prev}]; give each quadrangle one section"),
                ));
            }
            taken.quads[q] = Some(si);
            let gq = self.gmsh.as_ref().map(|g| g.quads[q]).unwrap_or([0; 4]);
            quads.push(gq.map(|i| self.gnode(i)));
        }
        for t in tri_ids {
            if let Some(prev) = taken.triangles[t] {
                let tag = self.gmsh.as_ref().map(|g| g.triangle_tags[t]).unwrap_or(0);
                return Err(self.err(
                    &format!("{field}.set"),
                    format!("triangle {tag} already has the section of shells[{prev}]; give each triangle one section"),
                ));
            }
            taken.triangles[t] = Some(si);
            let gt = self.gmsh.as_ref().map(|g| g.triangles[t]).unwrap_or([0; 3]);
            tris.push(gt.map(|i| self.gnode(i)));
        }
        Ok(())
    }

    /// The inline `triangles` of a shell entry, appended to `tris`: each must have three
    /// distinct nodes and a proper geometry, and neighbours must be ordered alike (no inverted
    /// triangle against one sharing its edge).
    fn inline_triangles(
        &mut self,
        field: &str,
        s: &ShellSpec,
        tris: &mut Vec<[usize; 3]>,
    ) -> Result<()> {
        let inline_tris = tris.len();
        for (k, t) in s.triangles.iter().enumerate() {
            let f = format!("{field}.triangles[{k}]");
            let nodes = [
                self.inline_node(t[0], &f)?,
                self.inline_node(t[1], &f)?,
                self.inline_node(t[2], &f)?,
            ];
            if nodes[0] == nodes[1] || nodes[1] == nodes[2] || nodes[0] == nodes[2] {
                return Err(self.err(
                    &f,
                    format!("{t:?} is degenerate: a node is repeated; a triangle needs three distinct nodes"),
                ));
            }
            crate::structure::tri3::tri_geometry(&nodes.map(|n| self.mesh.nodes[n]))
                .map_err(|e| self.err(&f, format!("nodes {t:?}: {e}")))?;
            tris.push(nodes);
        }
        let polys: Vec<&[usize]> = tris[inline_tris..].iter().map(|t| &t[..]).collect();
        if let Some(fault) = crate::structure::tri3::check_orientation(&polys, &self.mesh.nodes) {
            let (a, c) = (fault.elements[0], fault.elements[1]);
            return Err(self.err(
                &format!("{field}.triangles[{c}]"),
                format!(
                    "{:?} is inverted against triangles[{a}] {:?} ({}); order the nodes of one surface alike",
                    s.triangles[c],
                    s.triangles[a],
                    if fault.same_direction {
                        "both run their shared edge in the same direction"
                    } else {
                        "it folds back onto it"
                    }
                ),
            ));
        }
        Ok(())
    }

    /// Adds every `frames` entry; a Gmsh line may take one frame section only.
    fn add_frames(&mut self, spec: &GeneralSpec, default_mat: Material) -> Result<()> {
        let nl = self.gmsh.as_ref().map(|g| g.lines.len()).unwrap_or(0);
        let mut line_section: Vec<Option<usize>> = vec![None; nl];
        for (fi, f) in spec.frames.iter().enumerate() {
            self.add_frame(fi, f, default_mat, &mut line_section)?;
        }
        Ok(())
    }

    /// One `frames[fi]` entry: checks its section (A, I_y, I_z, J > 0), material and
    /// orientation, divides it into 2-node elements, applies its end releases and adds the
    /// elements to the mesh and its part.
    fn add_frame(
        &mut self,
        fi: usize,
        f: &FrameSpec,
        default_mat: Material,
        line_section: &mut [Option<usize>],
    ) -> Result<()> {
        let field = format!("frames[{fi}]");
        for (k, v) in [("area", f.area), ("iy", f.iy), ("iz", f.iz), ("j", f.j)] {
            positive(
                self,
                &format!("{field}.{k}"),
                v,
                if k == "area" { "m²" } else { "m⁴" },
            )?;
        }
        let section =
            Section::new(f.area, f.iy, f.iz, f.j).map_err(|e| self.err(&field, e.to_string()))?;
        let mat = self.material(&f.material, default_mat, &format!("{field}.material"))?;
        if let Some(o) = f.orientation {
            let n2 = o.iter().map(|x| x * x).sum::<f64>();
            if !(n2.is_finite() && n2 > 0.0) {
                return Err(self.err(
                    &format!("{field}.orientation"),
                    "must be a nonzero finite vector",
                ));
            }
        }
        let segs = self.frame_segments(fi, &field, f, line_section)?;
        check_slenderness(self, &field, f, &segs)?;
        let rel = self.frame_releases(&field, f, &segs)?;
        for (k, s) in segs.into_iter().enumerate() {
            let mut el = FrameElement::new(s, mat, section);
            el.orientation = f.orientation;
            el.releases = rel[k];
            crate::structure::frame::check_releases(&el.releases)
                .map_err(|e| self.err(&format!("{field}.releases"), e.to_string()))?;
            let e = self.mesh.add_frame(el);
            self.in_part(&f.part, |p| p.frames.push(e));
        }
        Ok(())
    }

    /// The 2-node elements of a frame entry: the lines of its Gmsh physical curve, or its
    /// inline chain `nodes = [a, b, ...]` with each segment divided into `divisions` equal
    /// elements (new nodes at `p_a + (k/n)(p_b − p_a)`).
    fn frame_segments(
        &mut self,
        fi: usize,
        field: &str,
        f: &FrameSpec,
        line_section: &mut [Option<usize>],
    ) -> Result<Vec<[usize; 2]>> {
        let mut segs: Vec<[usize; 2]> = Vec::new();
        match (&f.set, &f.nodes) {
            (Some(set), None) => {
                if f.divisions.is_some() {
                    return Err(self.err(
                        &format!("{field}.divisions"),
                        "applies to `nodes = [a, b, ...]` only; a Gmsh curve is already divided",
                    ));
                }
                let ids = self
                    .gmsh
                    .as_ref()
                    .and_then(|g| g.line_sets.get(set))
                    .cloned()
                    .ok_or_else(|| {
                        self.err(
                            &format!("{field}.set"),
                            format!("no physical curve '{set}' of 2-node lines in the mesh"),
                        )
                    })?;
                for l in ids {
                    if line_section[l].replace(fi).is_some() {
                        return Err(self.err(
                            &format!("{field}.set"),
                            "a line already has another frame section",
                        ));
                    }
                    let gl = self.gmsh.as_ref().map(|g| g.lines[l]).unwrap_or([0; 2]);
                    segs.push(gl.map(|i| self.gnode(i)));
                }
            }
            (None, Some(chain)) => {
                if chain.len() < 2 {
                    return Err(self.err(
                        &format!("{field}.nodes"),
                        format!("needs at least two nodes [a, b, ...] (got {})", chain.len()),
                    ));
                }
                let nd = f.divisions.unwrap_or(1);
                if nd == 0 || nd > 100_000 {
                    return Err(self.err(
                        &format!("{field}.divisions"),
                        format!("must be in 1..=100000 (got {nd})"),
                    ));
                }
                for pair in chain.windows(2) {
                    let a = self.inline_node(pair[0], &format!("{field}.nodes"))?;
                    let c = self.inline_node(pair[1], &format!("{field}.nodes"))?;
                    let (pa, pc) = (self.mesh.nodes[a], self.mesh.nodes[c]);
                    let mut prev = a;
                    for k in 1..=nd {
                        let next = if k == nd {
                            c
                        } else {
                            let t = k as f64 / nd as f64;
                            self.mesh
                                .add_node([0, 1, 2].map(|d| pa[d] + t * (pc[d] - pa[d])))
                        };
                        segs.push([prev, next]);
                        prev = next;
                    }
                }
            }
            _ => {
                return Err(self.err(
                    field,
                    "give either `set` (a Gmsh physical curve of 2-node lines) or `nodes = [a, b, ...]`",
                ));
            }
        }
        Ok(segs)
    }

    /// The end releases of a frame entry's elements (per element, per end, per local DOF
    /// u_x, u_y, u_z, r_x, r_y, r_z): each `releases` entry frees its DOFs at every element end
    /// at its node(s), which must be an end of some element of the member.
    fn frame_releases(
        &mut self,
        field: &str,
        f: &FrameSpec,
        segs: &[[usize; 2]],
    ) -> Result<Vec<[[bool; 6]; 2]>> {
        let mut rel: Vec<[[bool; 6]; 2]> = vec![[[false; 6]; 2]; segs.len()];
        for (ri, r) in f.releases.iter().enumerate() {
            let rfield = format!("{field}.releases[{ri}]");
            let mut mask = [false; 6];
            if r.dofs.is_empty() {
                return Err(self.err(
                    &format!("{rfield}.dofs"),
                    "is empty; give some of \"ux\" (axial), \"rx\" (torsion), \"ry\", \"rz\" (bending rotations, local axes)",
                ));
            }
            for name in &r.dofs {
                match ["ux", "rx", "ry", "rz"].iter().position(|n| n == name) {
                    Some(p) => mask[[0, 3, 4, 5][p]] = true,
                    None => {
                        return Err(self.err(
                            &format!("{rfield}.dofs"),
                            format!("unknown or unsupported release '{name}'; valid: \"ux\" (axial), \"rx\" (torsion), \"ry\", \"rz\" (bending rotations about the local y, z axes)"),
                        ))
                    }
                }
            }
            let at = self.nodes_of(&r.node, &format!("{rfield}.node"))?;
            let mut hit = false;
            for (k, s) in segs.iter().enumerate() {
                for end in 0..2 {
                    if at.contains(&s[end]) {
                        hit = true;
                        for d in 0..6 {
                            rel[k][end][d] |= mask[d];
                        }
                    }
                }
            }
            if !hit {
                return Err(self.err(
                    &format!("{rfield}.node"),
                    "is not an end of any element of this member; give the member's end node (or a set holding it)",
                ));
            }
        }
        Ok(rel)
    }

    /// Adds the discrete elements: springs and dashpots (to ground or to a `to` node; K, C ≥ 0
    /// per DOF) and point masses (m > 0, rotary inertia ≥ 0), at every node of their reference.
    fn add_discrete(&mut self, spec: &GeneralSpec) -> Result<()> {
        for (i, s) in spec.springs.iter().enumerate() {
            let field = format!("springs[{i}]");
            nonnegative(
                self,
                &format!("{field}.stiffness"),
                &s.stiffness,
                "N/m or N·m/rad",
            )?;
            let to = match &s.to {
                Some(r) => Some(self.one_node(r, &format!("{field}.to"))?),
                None => None,
            };
            for n in self.nodes_of(&s.node, &format!("{field}.node"))? {
                self.mesh.add_spring(Spring {
                    node: n,
                    other: to,
                    stiffness: s.stiffness,
                });
            }
        }
        for (i, s) in spec.dashpots.iter().enumerate() {
            let field = format!("dashpots[{i}]");
            nonnegative(
                self,
                &format!("{field}.damping"),
                &s.damping,
                "N·s/m or N·m·s/rad",
            )?;
            let to = match &s.to {
                Some(r) => Some(self.one_node(r, &format!("{field}.to"))?),
                None => None,
            };
            for n in self.nodes_of(&s.node, &format!("{field}.node"))? {
                self.mesh.add_dashpot(Dashpot {
                    node: n,
                    other: to,
                    damping: s.damping,
                });
            }
        }
        for (i, m) in spec.masses.iter().enumerate() {
            let field = format!("masses[{i}]");
            positive(self, &format!("{field}.mass"), m.mass, "kg")?;
            let inertia = m.inertia.unwrap_or([0.0; 3]);
            nonnegative(self, &format!("{field}.inertia"), &inertia, "kg·m²")?;
            for n in self.nodes_of(&m.node, &format!("{field}.node"))? {
                let e = self.mesh.add_mass(PointMass {
                    node: n,
                    mass_kg: m.mass,
                    inertia_kg_m2: inertia,
                });
                self.in_part(&m.part, |p| p.masses.push(e));
            }
        }
        Ok(())
    }

    /// Adds the rigid links (a master and at least one other slave) and the constraints (zero
    /// displacement of the named DOFs at every node of a set).
    fn add_links_and_constraints(&mut self, spec: &GeneralSpec) -> Result<()> {
        for (i, l) in spec.rigid_links.iter().enumerate() {
            let field = format!("rigid_links[{i}]");
            let master = self.one_node(&l.master, &format!("{field}.master"))?;
            let slaves: Vec<usize> = self
                .nodes_of(&l.slaves, &format!("{field}.slaves"))?
                .into_iter()
                .filter(|&s| s != master)
                .collect();
            if slaves.is_empty() {
                return Err(self.err(
                    &format!("{field}.slaves"),
                    "holds no node other than the master",
                ));
            }
            self.mesh.add_rigid_link(RigidLink { master, slaves });
        }
        for (i, c) in spec.constraints.iter().enumerate() {
            let field = format!("constraints[{i}]");
            let dofs = parse_dofs(&c.dofs, &format!("{BASE}.{field}.dofs"))
                .map_err(|e| self.err(&format!("{field}.dofs"), e))?;
            for n in self.nodes_of(&NodeRef::Set(c.set.clone()), &format!("{field}.set"))? {
                self.mesh.fix(n, &dofs);
            }
        }
        Ok(())
    }

    /// Names the mesh's points: every Gmsh node group whose nodes are all in the model, every
    /// inline set, then the `points` aliases.
    fn name_points(&mut self, spec: &GeneralSpec) -> Result<()> {
        let gsets: Vec<String> = self
            .gmsh
            .as_ref()
            .map(|g| g.node_sets.keys().cloned().collect())
            .unwrap_or_default();
        for name in gsets {
            // Only groups whose nodes are in the model (used by an element or a reference).
            let all_used = self
                .gmsh
                .as_ref()
                .is_some_and(|g| g.node_sets[&name].iter().all(|&i| self.gmap[i].is_some()));
            if all_used {
                let v = self.nodes_of(&NodeRef::Set(name.clone()), "points")?;
                self.mesh.name_point(name, v);
            }
        }
        for (name, v) in self.sets.clone() {
            self.mesh.name_point(name, v);
        }
        for (p, set) in &spec.points {
            let v = self.nodes_of(&NodeRef::Set(set.clone()), &format!("points.{p}"))?;
            self.mesh.name_point(p.clone(), v);
        }
        Ok(())
    }
}

/// Least slenderness `L/r` of a frame member (`r = sqrt(max(iy, iz)/area)` its radius of
/// gyration): a member shorter than its radius of gyration is no beam (Euler-Bernoulli needs
/// `L/r` of ~10 and more; the paper's columns have 31, NAFEMS FV2's arms 139); such a section is
/// a unit slip (area in mm² or I in m⁴ next to lengths in m: `area = 400, iy = 13333` on a 1 m
/// member gives `L/r = 0.17`).
pub const MIN_FRAME_SLENDERNESS: f64 = 1.0;

/// Refuses a frame entry whose member (an inline chain's segment `nodes[k]`–`nodes[k+1]`, or a
/// Gmsh curve set's extent) is shorter than [`MIN_FRAME_SLENDERNESS`] radii of gyration.
fn check_slenderness(
    b: &Builder<'_>,
    field: &str,
    f: &FrameSpec,
    segs: &[[usize; 2]],
) -> Result<()> {
    let r = (f.iy.max(f.iz) / f.area).sqrt();
    let member = match &f.nodes {
        // The shortest member of the chain (segments between consecutive given nodes).
        Some(chain) => chain
            .windows(2)
            .filter_map(|p| Some((b.inline.get(p[0])?, b.inline.get(p[1])?)))
            .map(|(&a, &c)| distance(b.mesh.nodes[a], b.mesh.nodes[c]))
            .fold(f64::INFINITY, f64::min),
        // A Gmsh curve set: its extent (the bounding-box diagonal of its nodes).
        None => bounding_box(segs.iter().flatten().map(|&n| b.mesh.nodes[n]))
            .map_or(f64::INFINITY, |(lo, hi)| distance(lo, hi)),
    };
    if member.is_finite() && r.is_finite() && member < MIN_FRAME_SLENDERNESS * r {
        return Err(b.err(
            field,
            format!(
                "a member {} m long with a radius of gyration sqrt(max(iy, iz)/area) = {} m (area = {} m², iy = {} m⁴, iz = {} m⁴) is no beam (L/r = {:.3e} < {}); lengths are in m, area in m², iy, iz, j in m⁴ (a 20 mm square: area = 4e-4, iy = iz = 1.333e-8); a short stiff connection is a rigid link",
                crate::num(member),
                crate::num(r),
                crate::num(f.area),
                crate::num(f.iy),
                crate::num(f.iz),
                member / r,
                crate::num(MIN_FRAME_SLENDERNESS)
            ),
        ));
    }
    Ok(())
}

/// Largest shell thickness over the extent of its surface (the bounding-box diagonal of its
/// elements' nodes): a "shell" thicker than half its own extent is no shell (Kirchhoff and
/// Mindlin plates need `t/L` of ~1/10 and less; the paper's bed has 0.053 of its diagonal); such
/// a thickness is a unit slip (`thickness = 20` for 20 mm on a surface measured in m).
pub const MAX_SHELL_THICKNESS_RATIO: f64 = 0.5;

/// The bounding box `(lo, hi)` of `points` (`None` for none).
fn bounding_box(points: impl Iterator<Item = [f64; 3]>) -> Option<([f64; 3], [f64; 3])> {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo[0] <= hi[0]).then_some((lo, hi))
}

/// The distance (m) between two points.
fn distance(a: [f64; 3], c: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - c[k]).powi(2)).sum::<f64>().sqrt()
}

/// The diagonal (m) of the bounding box of `points` (0 for none).
pub(crate) fn bounding_diagonal(points: impl Iterator<Item = [f64; 3]>) -> f64 {
    bounding_box(points).map_or(0.0, |(lo, hi)| distance(lo, hi))
}

/// Why a shell thickness `t` (m) cannot belong to a surface of extent `extent` (m, its
/// bounding-box diagonal): more than [`MAX_SHELL_THICKNESS_RATIO`] of it.
pub(crate) fn thickness_fault(t: f64, extent: f64) -> Option<String> {
    (extent > 0.0 && t > MAX_SHELL_THICKNESS_RATIO * extent).then(|| {
        format!(
            "a shell {} m thick on a surface {} m across (its bounding-box diagonal) is no shell (t/L = {:.3} > {}); thickness is in m, like the lengths and coordinates (20 mm is 0.02)",
            crate::num(t),
            crate::num(extent),
            t / extent,
            crate::num(MAX_SHELL_THICKNESS_RATIO)
        )
    })
}

/// Two nodes of elements closer than this times the model's size (bounding-box diagonal) are
/// the same point.
pub const COINCIDENT_NODE_TOLERANCE: f64 = 1e-9;

/// Refuses two element nodes at the same point (within [`COINCIDENT_NODE_TOLERANCE`] × the
/// bounding-box diagonal) that no spring, dashpot or rigid link joins: the elements on either
/// side share no DOF there, so the structure is cut along them (a Gmsh mesh of surfaces that
/// were not fused, or whose duplicate nodes were not removed). Such a cut left the free part of a
/// clamped plate with six 0 Hz modes and a truncation table over them. The error names both
/// nodes (Gmsh tags or `nodes[i]`), where they are and what to do.
fn check_coincident_nodes(b: &Builder<'_>, spec: &GeneralSpec) -> Result<()> {
    let pairs = coincident_node_pairs(&b.mesh);
    let Some(&(i, j)) = pairs.first() else {
        return Ok(());
    };
    // A mesh node's name in the input: `nodes[k]` (inline), Gmsh node tag, or a frame's
    // `divisions` node.
    let name = |m: usize| -> String {
        if let Some(k) = b.inline.iter().position(|&x| x == m) {
            return format!("nodes[{k}]");
        }
        if let (Some(g), Some(k)) = (&b.gmsh, b.gmap.iter().position(|&x| x == Some(m))) {
            return format!(
                "node {} of {}",
                g.node_tags[k],
                spec.mesh.as_deref().unwrap_or("the mesh")
            );
        }
        format!("node {m} (made by a frame's `divisions`)")
    };
    let field = if spec.mesh.is_some() { "mesh" } else { "nodes" };
    Err(b.err(
        field,
        coincident_message(&name(i), &name(j), b.mesh.nodes[i], pairs.len()),
    ))
}

/// The error text for coincident nodes `a` and `b` at `p` (`count` pairs in all).
pub(super) fn coincident_message(a: &str, b: &str, p: [f64; 3], count: usize) -> String {
    format!(
        "{a} and {b} are at the same point [{}, {}, {}] m ({count} such pair(s) in all) but no element, spring or rigid link joins them: the structure is cut there. Merge them (Gmsh: fuse the surfaces, or `Coherence Mesh;` / gmsh.model.mesh.removeDuplicateNodes() before saving), or join them with `rigid_links` or `springs` if the cut is meant",
        crate::num(p[0]),
        crate::num(p[1]),
        crate::num(p[2]),
    )
}

/// Pairs `(i, j)`, `i < j`, ascending, of nodes of elements (frames, shells, triangles) within
/// [`COINCIDENT_NODE_TOLERANCE`] × the bounding-box diagonal of each other that no chain of
/// springs, dashpots or rigid links connects.
pub(super) fn coincident_node_pairs(mesh: &Mesh) -> Vec<(usize, usize)> {
    let n = mesh.nodes.len();
    let mut in_element = vec![false; n];
    for f in &mesh.frames {
        f.nodes.iter().for_each(|&i| in_element[i] = true);
    }
    for s in &mesh.shells {
        s.nodes.iter().for_each(|&i| in_element[i] = true);
    }
    for t in &mesh.triangles {
        t.nodes.iter().for_each(|&i| in_element[i] = true);
    }
    let nodes: Vec<usize> = (0..n).filter(|&i| in_element[i]).collect();
    if nodes.len() < 2 {
        return Vec::new();
    }
    let Some((lo, hi)) = bounding_box(nodes.iter().map(|&i| mesh.nodes[i])) else {
        return Vec::new();
    };
    let diag = distance(lo, hi);
    if !(diag.is_finite() && diag > 0.0) {
        return Vec::new();
    }
    let tol = COINCIDENT_NODE_TOLERANCE * diag;
    // Grid of cells of side `tol`: a pair within `tol` lies in neighbouring cells.
    let cell = |p: [f64; 3]| -> [i64; 3] {
        std::array::from_fn(|k| ((p[k] - lo[k]) / tol).floor() as i64)
    };
    let mut grid: std::collections::HashMap<[i64; 3], Vec<usize>> =
        std::collections::HashMap::new();
    for &i in &nodes {
        grid.entry(cell(mesh.nodes[i])).or_default().push(i);
    }
    // Nodes joined by springs, dashpots or rigid links, as connected groups (union-find with
    // path halving): a rigid link of `s` slaves costs `s` unions, not `s²/2` pairs.
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut join = |a: usize, c: usize| {
        if a < n && c < n {
            let (ra, rc) = (root(&mut parent, a), root(&mut parent, c));
            parent[ra.max(rc)] = ra.min(rc);
        }
    };
    for s in &mesh.springs {
        if let Some(o) = s.other {
            join(s.node, o);
        }
    }
    for d in &mesh.dashpots {
        if let Some(o) = d.other {
            join(d.node, o);
        }
    }
    for l in &mesh.rigid_links {
        for &c in &l.slaves {
            join(l.master, c);
        }
    }
    let mut pairs: Vec<(usize, usize)> = Vec::new();
    for &i in &nodes {
        let c = cell(mesh.nodes[i]);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(v) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                        continue;
                    };
                    for &j in v {
                        if j <= i {
                            continue;
                        }
                        let dist = (0..3)
                            .map(|k| (mesh.nodes[i][k] - mesh.nodes[j][k]).powi(2))
                            .sum::<f64>()
                            .sqrt();
                        if dist <= tol && root(&mut parent, i) != root(&mut parent, j) {
                            pairs.push((i, j));
                        }
                    }
                }
            }
        }
    }
    pairs.sort_unstable();
    pairs
}
