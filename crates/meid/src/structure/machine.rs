//! Parametric finite-element model of the forging machine of the paper's Fig. 1.
//!
//! The machine is a **generator** of the general model: [`MachineSpec::generate`] emits the
//! [`GeneralSpec`] (`[structure.fem.model]`) that describes it, and [`MachineSpec::build`]
//! hands that to the general model's one builder ([`crate::model::general::build_mesh`]), as
//! for a user's model; `meid model expand` writes it out as a model file to edit.
//!
//! Geometry (global z up, the slider moves in -z, so the model's impact direction is `[0, 0, -1]`):
//! a rectangular **bed** plate centred on the z axis at `z = column length`, four vertical
//! **columns** (frame elements) from the bed down to `z = 0` at `(±(Lx/2 - inset), ±(Ly/2 - inset))`
//! of the bed, and then either
//! * a **floating base** plate at `z = 0` (centred, larger than the bed) on four **coil springs**
//!   (per-direction stiffness, optional dashpots) from its corners (or inset positions) to the
//!   ground; the force to the floor is the sum of the spring forces, or
//! * **fixed column feet** (clamped at `z = 0`); the force to the floor is the column base reaction
//!   `-(K u)` at the clamped DOFs (the paper's `F_t = k_c x_c`).
//!
//! Each column end is tied to its plate by a rigid spider (RBE2) over the column's **footprint**, a
//! square of half-size `spider_half_size_m` centred on the column axis (clipped at the plate
//! edges): the plate node at the axis is the master and every other plate node in the square is a
//! slave (see [`super::shell`] for why a spider and not the drilling DOF). The grid lines pass
//! through the footprint's edges, so the rigid patch is the same physical square on every mesh and
//! refining the mesh converges to one answer (a plate with rigid square inclusions). A spider over
//! "the ring of elements around the node" instead shrinks with the mesh and the bed mode then keeps
//! falling (311 → 272 Hz from 4 to 20 elements per side; docs/explanations/paper-machine.md). Where two
//! footprints overlap, a node joins the first spider only, and a master is never a slave.
//!
//! Named points: `O_b` (bed centre, the slider contact point), `O_f` (base centre, where the
//! damper spring acts; floating base only) and `B` (accelerometer on the bed, offset from the
//! centre). Plate meshes are structured; the grid lines pass through every column, footprint edge,
//! spring, named point and added mass, and the element size is `max(Lx, Ly) / elements_per_side`.
//!
//! Defaults: steel (E = 2.06e11 Pa, ν = 0.3, ρ = 7850 kg/m³); bed 0.32 × 0.20 × 0.020 m
//! (10.05 kg, the paper's m_b = 10 kg); base 0.50 × 0.35 × 0.030 m (41.2 kg, m_f = 41 kg);
//! columns solid Ø25 mm × 0.30 m, 20 mm in from the bed edges; springs 1.5e4 N/m in x, y and z
//! (the paper gives only the vertical k_f; the lateral value is an assumption) 20 mm in from the
//! base corners; B at (0.08, 0.05) m from the bed centre; column footprints 40 × 40 mm
//! (`spider_half_size_m = 0.02`). The geometry is not tuned to the paper's frequencies (the
//! examples `examples/paper-*.toml` are).

use super::assembly::FeModel;
use super::frame::Section;
use super::material::Material;
#[cfg(doc)]
use super::mesh::Mesh;
use crate::model::general::{
    ConstraintSpec, DashpotSpec, FrameSpec, GeneralSpec, MassSpec, NodeRef, RigidLinkSpec,
    ShellSpec, SpringSpec, BED_PART,
};
use crate::model::material::MaterialSpec;
use crate::model::source::Source;
use crate::{Error, Result};

/// A rectangular plate centred on the z axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlateSpec {
    /// Side along x (m).
    pub length_x_m: f64,
    /// Side along y (m).
    pub length_y_m: f64,
    pub thickness_m: f64,
    pub material: Material,
}

impl PlateSpec {
    /// Mass ρ Lx Ly t (kg).
    pub fn mass_kg(&self) -> f64 {
        self.material.density_kg_per_m3 * self.length_x_m * self.length_y_m * self.thickness_m
    }
    fn validate(&self, what: &str) -> Result<()> {
        for (n, v) in [
            ("length x", self.length_x_m),
            ("length y", self.length_y_m),
            ("thickness", self.thickness_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(
                    format!("{what} {n}"),
                    format!("must be > 0 m (got {v})"),
                ));
            }
        }
        self.material.validate(what)
    }
}

/// How the machine stands on the floor.
#[derive(Debug, Clone, PartialEq)]
pub enum Support {
    /// Columns end on a floating-base plate carried by four springs to the ground.
    FloatingBase {
        base: PlateSpec,
        /// Stiffness of each spring in global `[x, y, z]` (N/m); all zero = no springs (free).
        spring_stiffness_n_per_m: [f64; 3],
        /// Damping of each spring in `[x, y, z]` (N·s/m); zero for none.
        spring_damping_n_s_per_m: [f64; 3],
        /// Distance of the springs from the base edges in x and y (m); 0 = at the corners.
        spring_inset_m: f64,
    },
    /// Column feet clamped to the ground at z = 0.
    FixedColumns,
}

/// Which plate an added mass sits on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plate {
    Bed,
    Base,
}

/// A rigid point mass added on a plate at `offset_m` from the plate centre.
#[derive(Debug, Clone, PartialEq)]
pub struct AddedMass {
    pub plate: Plate,
    pub offset_m: [f64; 2],
    pub mass_kg: f64,
    /// `[Ixx, Iyy, Izz]` about the node (kg·m²).
    pub inertia_kg_m2: [f64; 3],
}

/// Parameters of the machine (see the module documentation for the defaults).
#[derive(Debug, Clone, PartialEq)]
pub struct MachineSpec {
    pub bed: PlateSpec,
    pub column_section: Section,
    pub column_material: Material,
    /// Column length = distance between the bed and base mid-planes (m).
    pub column_length_m: f64,
    /// Distance of the column axes from the bed edges in x and y (m); 0 = at the corners.
    pub column_inset_m: f64,
    /// Frame elements per column.
    pub column_elements: usize,
    /// Shell elements along the longer side of each plate (mesh density).
    pub elements_per_side: usize,
    pub support: Support,
    /// Position of the accelerometer point B relative to the bed centre (m).
    pub b_offset_m: [f64; 2],
    /// Further named points on the bed (strike points, damper points): name and position from
    /// the bed centre (m). Each is a grid node and a one-node set.
    pub bed_points_m: Vec<(String, [f64; 2])>,
    pub added_masses: Vec<AddedMass>,
    /// Tie column ends to their plates by rigid spiders over the column footprint.
    pub spiders: bool,
    /// Half-size of the square column footprint tied rigidly to the plate (m), measured from the
    /// column axis; the same on the bed and the base. Default 0.02 m (a 40 × 40 mm foot).
    pub spider_half_size_m: f64,
}

impl Default for MachineSpec {
    fn default() -> Self {
        let steel = Material::STEEL;
        MachineSpec {
            bed: PlateSpec {
                length_x_m: 0.32,
                length_y_m: 0.20,
                thickness_m: 0.020,
                material: steel,
            },
            column_section: Section {
                area_m2: std::f64::consts::PI * 0.025 * 0.025 / 4.0,
                iy_m4: std::f64::consts::PI * 0.025_f64.powi(4) / 64.0,
                iz_m4: std::f64::consts::PI * 0.025_f64.powi(4) / 64.0,
                torsion_constant_m4: std::f64::consts::PI * 0.025_f64.powi(4) / 32.0,
            },
            column_material: steel,
            column_length_m: 0.30,
            column_inset_m: 0.02,
            column_elements: 6,
            elements_per_side: 8,
            support: Support::FloatingBase {
                base: PlateSpec {
                    length_x_m: 0.50,
                    length_y_m: 0.35,
                    thickness_m: 0.030,
                    material: steel,
                },
                spring_stiffness_n_per_m: [1.5e4; 3],
                spring_damping_n_s_per_m: [0.0; 3],
                spring_inset_m: 0.02,
            },
            b_offset_m: [0.08, 0.05],
            bed_points_m: Vec::new(),
            added_masses: Vec::new(),
            spiders: true,
            spider_half_size_m: 0.02,
        }
    }
}

/// The machine as a general model ([`MachineSpec::generate`]) and where its parts are (inline
/// node indices, which are also the mesh's node indices).
#[derive(Debug, Clone)]
pub struct GeneratedMachine {
    /// What `[structure.fem.model]` would say.
    pub spec: GeneralSpec,
    /// Bed nodes `grid[i][j]`.
    pub bed_grid: Vec<Vec<usize>>,
    /// Base nodes, floating base only.
    pub base_grid: Option<Vec<Vec<usize>>>,
    /// Nodes of each column from the bed down.
    pub columns: Vec<Vec<usize>>,
}

/// A generated machine: the assembled model and where its parts are.
#[derive(Debug, Clone)]
pub struct Machine {
    pub model: FeModel,
    /// Bed nodes `grid[i][j]` at `(xs[i], ys[j])`.
    pub bed_grid: Vec<Vec<usize>>,
    /// Base nodes, floating base only.
    pub base_grid: Option<Vec<Vec<usize>>>,
    /// Nodes of each column from the bed down.
    pub columns: Vec<Vec<usize>>,
}

/// Grid coordinates on `[-len/2, len/2]` through all `required` coordinates, element size ≈ `h`.
fn grid_1d(len: f64, required: &[f64], h: f64) -> Vec<f64> {
    let tol = 1e-9 * len;
    let mut pts: Vec<f64> = required.to_vec();
    pts.push(-0.5 * len);
    pts.push(0.5 * len);
    pts.sort_by(|a, b| a.total_cmp(b));
    pts.dedup_by(|a, b| (*a - *b).abs() <= tol);
    let mut out = vec![pts[0]];
    for w in pts.windows(2) {
        let n = ((w[1] - w[0]) / h).round().max(1.0) as usize;
        for k in 1..=n {
            out.push(w[0] + (w[1] - w[0]) * k as f64 / n as f64);
        }
    }
    out
}

fn index_of(xs: &[f64], x: f64) -> usize {
    xs.iter()
        .enumerate()
        .min_by(|a, b| (a.1 - x).abs().total_cmp(&(b.1 - x).abs()))
        .map(|(i, _)| i)
        .unwrap_or(0)
}

fn inside(what: &str, p: [f64; 2], plate: &PlateSpec) -> Result<()> {
    if p[0].abs() <= 0.5 * plate.length_x_m + 1e-12 && p[1].abs() <= 0.5 * plate.length_y_m + 1e-12
    {
        Ok(())
    } else {
        Err(Error::invalid(
            what,
            format!(
                "position {p:?} m lies outside the {} x {} m plate (coordinates from its centre)",
                plate.length_x_m, plate.length_y_m
            ),
        ))
    }
}

/// A footprint edge closer than `FOOTPRINT_SNAP · a` to a plate edge or to another grid line the
/// mesh must keep (column, spring, named point, added mass) moves onto it, so that no sliver
/// element appears (a 50 µm sliver made `max K_ii/M_ii` ~1e16 and the eigen-solver's rigid-body
/// threshold then swallowed the 6 Hz and 141 Hz modes). The move is a fixed physical distance,
/// independent of the mesh, so the patch is the same on every mesh.
const FOOTPRINT_SNAP: f64 = 0.25;

/// Extent `[lo, hi]` along one axis of the footprint of a column at `c` of half-size `a`: `c ± a`
/// clipped to the plate `[-len/2, len/2]`, edges snapped onto `hard` coordinates (see
/// [`FOOTPRINT_SNAP`]).
fn footprint_extent(c: f64, a: f64, len: f64, hard: &[f64]) -> [f64; 2] {
    let snap = |v: f64| -> f64 {
        let v = v.clamp(-0.5 * len, 0.5 * len);
        hard.iter()
            .chain([-0.5 * len, 0.5 * len].iter())
            .copied()
            .filter(|h| (h - v).abs() <= FOOTPRINT_SNAP * a && (h - c).abs() > 0.5 * a)
            .min_by(|x, y| (x - v).abs().total_cmp(&(y - v).abs()))
            .unwrap_or(v)
    };
    [snap(c - a), snap(c + a)]
}

/// Footprint extents of the columns along one axis (see [`footprint_extent`]); their edges are
/// appended to `req` (the grid lines the plate mesh must pass through).
fn footprint_lines(req: &mut Vec<f64>, centres: &[f64], a: f64, len: f64) -> Vec<[f64; 2]> {
    let hard = req.clone();
    let ext: Vec<[f64; 2]> = centres
        .iter()
        .map(|&c| footprint_extent(c, a, len, &hard))
        .collect();
    for e in &ext {
        req.extend_from_slice(e);
    }
    ext
}

/// The nodes of `grid` (coordinates `xs`, `ys`) inside the rectangle `ex × ey`, without the node
/// at `centre` itself.
fn footprint(
    grid: &[Vec<usize>],
    xs: &[f64],
    ys: &[f64],
    centre: [f64; 2],
    ex: [f64; 2],
    ey: [f64; 2],
) -> Vec<usize> {
    let (ic, jc) = (index_of(xs, centre[0]), index_of(ys, centre[1]));
    let tol = 1e-9 * (xs[xs.len() - 1] - xs[0] + ys[ys.len() - 1] - ys[0]);
    let mut out = Vec::new();
    for (i, x) in xs.iter().enumerate() {
        if *x < ex[0] - tol || *x > ex[1] + tol {
            continue;
        }
        for (j, y) in ys.iter().enumerate() {
            if *y >= ey[0] - tol && *y <= ey[1] + tol && (i, j) != (ic, jc) {
                out.push(grid[i][j]);
            }
        }
    }
    out
}

impl MachineSpec {
    /// Column axis positions (x, y) (m).
    pub fn column_positions(&self) -> [[f64; 2]; 4] {
        let cx = 0.5 * self.bed.length_x_m - self.column_inset_m;
        let cy = 0.5 * self.bed.length_y_m - self.column_inset_m;
        [[cx, cy], [-cx, cy], [-cx, -cy], [cx, -cy]]
    }

    /// Builds and assembles the machine: [`MachineSpec::generate`] emits the general model,
    /// and the general model's one builder ([`crate::model::general::build_mesh`]) makes the
    /// mesh, as for a user's `[structure.fem.model]`.
    pub fn build(&self) -> Result<Machine> {
        let g = self.generate()?;
        let src = Source {
            name: "[structure.fem.machine]".to_string(),
            text: String::new(),
            overrides: Vec::new(),
        };
        let (mesh, direction) = crate::model::general::build_mesh(&g.spec, &src)?;
        let model = FeModel::assemble_with_direction(mesh, direction)?;
        Ok(Machine {
            model,
            bed_grid: g.bed_grid,
            base_grid: g.base_grid,
            columns: g.columns,
        })
    }

    /// The machine as a general model (`[structure.fem.model]`, [`GeneralSpec`]): inline nodes
    /// (bed grid, base grid, column nodes, clamped feet), one shell set per plate with its
    /// quadrangles, one frame chain per column, the coil springs and dashpots on the list of
    /// their base nodes, the added masses, one rigid link per column footprint (master = the
    /// plate node on the column axis, slaves = the other plate nodes of the footprint), the
    /// clamped feet (`constraints` on the set `column_feet`, fixed columns only) and the named
    /// points `O_b`, `B` and `O_f` as one-node sets. Inline node `i` is mesh node `i`.
    ///
    /// This is the only thing the machine section adds to the general model: what it emits
    /// can be written out (`meid model expand`), edited and read back as a model file, and
    /// gives the same matrices.
    pub fn generate(&self) -> Result<GeneratedMachine> {
        self.check_dimensions()?;
        let cols = self.column_positions();
        let mut g = GeneralSpec {
            impact_direction: Some([0.0, 0.0, -1.0]),
            ..GeneralSpec::default()
        };
        let bed = self.bed_plate(&mut g, &cols)?;
        let base = self.base_plate(&mut g, &cols)?;
        let columns = self.add_columns(&mut g, &cols, &bed, base.as_ref());
        self.add_masses(&mut g, &bed, base.as_ref())?;
        Ok(GeneratedMachine {
            spec: g,
            bed_grid: bed.grid,
            base_grid: base.map(|b| b.grid),
            columns,
        })
    }

    /// Refuses a machine whose bed, column section or material is invalid, whose column length
    /// is not > 0 m, whose mesh density is outside 2..=400 per plate side and 1..=1000 per
    /// column, whose column inset or spider half-size does not fit the bed, or whose point B
    /// lies outside the bed.
    fn check_dimensions(&self) -> Result<()> {
        self.bed.validate("bed")?;
        self.column_section.validate("column section")?;
        self.column_material.validate("column")?;
        if !(self.column_length_m.is_finite() && self.column_length_m > 0.0) {
            return Err(Error::invalid(
                "column length",
                format!("must be > 0 m (got {})", self.column_length_m),
            ));
        }
        if self.elements_per_side < 2
            || self.column_elements < 1
            || self.elements_per_side > 400
            || self.column_elements > 1000
        {
            return Err(Error::invalid(
                "mesh density",
                format!(
                    "need 2..=400 elements per plate side and 1..=1000 per column (got {} and {})",
                    self.elements_per_side, self.column_elements
                ),
            ));
        }
        let half_min = 0.5 * self.bed.length_x_m.min(self.bed.length_y_m);
        if !(self.column_inset_m >= 0.0 && self.column_inset_m < half_min) {
            return Err(Error::invalid(
                "column inset",
                format!(
                    "must lie in [0, {half_min}) m (got {})",
                    self.column_inset_m
                ),
            ));
        }
        if self.spiders
            && !(self.spider_half_size_m.is_finite()
                && self.spider_half_size_m > 0.0
                && self.spider_half_size_m < half_min)
        {
            return Err(Error::invalid(
                "spider half-size",
                format!(
                    "the column footprint half-size must lie in (0, {half_min}) m (got {})",
                    self.spider_half_size_m
                ),
            ));
        }
        inside("point B", self.b_offset_m, &self.bed)
    }

    /// The bed plate at the columns' height: its grid lines through the centre, B, the further
    /// bed points, the column axes, the bed's added masses and the column footprints' edges,
    /// its shells (part `bed`), and the one-node sets `O_b`, `B` and one per bed point.
    fn bed_plate(&self, g: &mut GeneralSpec, cols: &[[f64; 2]; 4]) -> Result<PlateMesh> {
        let mut bx = vec![0.0, self.b_offset_m[0]];
        let mut by = vec![0.0, self.b_offset_m[1]];
        for (name, p) in &self.bed_points_m {
            if ["O_b", "B", "O_f", FEET].contains(&name.as_str()) || name.is_empty() {
                return Err(Error::invalid(
                    format!("bed_points.{name}"),
                    format!("'{name}' is not a usable bed point name (empty, or one of O_b, B, O_f, {FEET}, which the machine names itself)"),
                ));
            }
            inside(&format!("bed_points.{name}"), *p, &self.bed)?;
            bx.push(p[0]);
            by.push(p[1]);
        }
        for c in cols {
            bx.push(c[0]);
            by.push(c[1]);
        }
        for m in self.added_masses.iter().filter(|m| m.plate == Plate::Bed) {
            inside("added mass on the bed", m.offset_m, &self.bed)?;
            bx.push(m.offset_m[0]);
            by.push(m.offset_m[1]);
        }
        let a = self.spider_half_size_m;
        let col_x: Vec<f64> = cols.iter().map(|c| c[0]).collect();
        let col_y: Vec<f64> = cols.iter().map(|c| c[1]).collect();
        let (bed_fx, bed_fy) = if self.spiders {
            (
                footprint_lines(&mut bx, &col_x, a, self.bed.length_x_m),
                footprint_lines(&mut by, &col_y, a, self.bed.length_y_m),
            )
        } else {
            (Vec::new(), Vec::new())
        };
        let h_bed = self.bed.length_x_m.max(self.bed.length_y_m) / self.elements_per_side as f64;
        let bxs = grid_1d(self.bed.length_x_m, &bx, h_bed);
        let bys = grid_1d(self.bed.length_y_m, &by, h_bed);
        let bed_grid = plate_grid(
            g,
            &bxs,
            &bys,
            self.column_length_m,
            &self.bed,
            Some(BED_PART),
        )?;
        let bed = PlateMesh {
            grid: bed_grid,
            xs: bxs,
            ys: bys,
            fx: bed_fx,
            fy: bed_fy,
        };
        g.sets.insert("O_b".into(), vec![bed.node([0.0, 0.0])]);
        g.sets.insert("B".into(), vec![bed.node(self.b_offset_m)]);
        for (name, p) in &self.bed_points_m {
            g.sets.insert(name.clone(), vec![bed.node(*p)]);
        }
        Ok(bed)
    }

    /// The floating base at z = 0, if the machine stands on one: its checks (plate, column feet
    /// on it, spring inset, coefficients), its grid lines through the centre, the column axes,
    /// the springs, its added masses and the footprints' edges, its shells, the set `O_f`, and
    /// the coil springs and dashpots (translations only) at the four spring nodes.
    fn base_plate(&self, g: &mut GeneralSpec, cols: &[[f64; 2]; 4]) -> Result<Option<PlateMesh>> {
        let Support::FloatingBase {
            base,
            spring_stiffness_n_per_m,
            spring_damping_n_s_per_m,
            spring_inset_m,
        } = &self.support
        else {
            return Ok(None);
        };
        base.validate("floating base")?;
        for c in cols {
            inside("column foot on the floating base", *c, base)?;
        }
        let sx = 0.5 * base.length_x_m - spring_inset_m;
        let sy = 0.5 * base.length_y_m - spring_inset_m;
        if !(*spring_inset_m >= 0.0 && sx > 0.0 && sy > 0.0) {
            return Err(Error::invalid(
                "spring inset",
                format!(
                    "must lie in [0, {}) m (got {spring_inset_m})",
                    0.5 * base.length_x_m.min(base.length_y_m)
                ),
            ));
        }
        super::discrete::check_coefficients("spring stiffness", "N/m", spring_stiffness_n_per_m)?;
        super::discrete::check_coefficients("spring damping", "N s/m", spring_damping_n_s_per_m)?;
        let springs = [[sx, sy], [-sx, sy], [-sx, -sy], [sx, -sy]];
        let mut xs = vec![0.0];
        let mut ys = vec![0.0];
        for p in cols.iter().chain(springs.iter()) {
            xs.push(p[0]);
            ys.push(p[1]);
        }
        for m in self.added_masses.iter().filter(|m| m.plate == Plate::Base) {
            inside("added mass on the base", m.offset_m, base)?;
            xs.push(m.offset_m[0]);
            ys.push(m.offset_m[1]);
        }
        let a = self.spider_half_size_m;
        let col_x: Vec<f64> = cols.iter().map(|c| c[0]).collect();
        let col_y: Vec<f64> = cols.iter().map(|c| c[1]).collect();
        let (fx, fy) = if self.spiders {
            (
                footprint_lines(&mut xs, &col_x, a, base.length_x_m),
                footprint_lines(&mut ys, &col_y, a, base.length_y_m),
            )
        } else {
            (Vec::new(), Vec::new())
        };
        let h = base.length_x_m.max(base.length_y_m) / self.elements_per_side as f64;
        let gx = grid_1d(base.length_x_m, &xs, h);
        let gy = grid_1d(base.length_y_m, &ys, h);
        let grid = plate_grid(g, &gx, &gy, 0.0, base, None)?;
        let plate = PlateMesh {
            grid,
            xs: gx,
            ys: gy,
            fx,
            fy,
        };
        g.sets.insert("O_f".into(), vec![plate.node([0.0, 0.0])]);
        let at: Vec<usize> = springs.iter().map(|p| plate.node(*p)).collect();
        let k = spring_stiffness_n_per_m;
        if k.iter().any(|&v| v > 0.0) {
            g.springs.push(SpringSpec {
                node: NodeRef::List(at.clone()),
                to: None,
                stiffness: [k[0], k[1], k[2], 0.0, 0.0, 0.0],
            });
        }
        let c = spring_damping_n_s_per_m;
        if c.iter().any(|&v| v > 0.0) {
            g.dashpots.push(DashpotSpec {
                node: NodeRef::List(at),
                to: None,
                damping: [c[0], c[1], c[2], 0.0, 0.0, 0.0],
            });
        }
        Ok(Some(plate))
    }

    /// The columns: one frame chain per column from its bed node down to its foot (the base's
    /// node on its axis, or a clamped foot node in the set [`FEET`]), with the spiders (rigid
    /// links) of its footprints. A plate node joins at most one spider (the first that reaches
    /// it) and never one whose master is another column end. Returns each column's nodes.
    fn add_columns(
        &self,
        g: &mut GeneralSpec,
        cols: &[[f64; 2]; 4],
        bed: &PlateMesh,
        base: Option<&PlateMesh>,
    ) -> Vec<Vec<usize>> {
        let mut masters = std::collections::BTreeSet::new();
        for c in cols {
            masters.insert(bed.node(*c));
            if let Some(b) = base {
                masters.insert(b.node(*c));
            }
        }
        let mut slaved = std::collections::BTreeSet::new();
        let mut spider = |g: &mut GeneralSpec, master: usize, candidates: Vec<usize>| {
            let slaves: Vec<usize> = candidates
                .into_iter()
                .filter(|n| !masters.contains(n) && slaved.insert(*n))
                .collect();
            if !slaves.is_empty() {
                g.rigid_links.push(RigidLinkSpec {
                    master: NodeRef::Index(master),
                    slaves: NodeRef::List(slaves),
                });
            }
        };
        let column_material = material_spec(self.column_material);
        let s = self.column_section;
        let zb = self.column_length_m;
        let mut columns = Vec::new();
        let mut feet = Vec::new();
        for (k, c) in cols.iter().enumerate() {
            let top = bed.node(*c);
            let mut nodes = vec![top];
            let ne = self.column_elements;
            for e in 1..ne {
                let z = zb * (1.0 - e as f64 / ne as f64);
                nodes.push(add_node(g, [c[0], c[1], z]));
            }
            let foot = match base {
                Some(b) => {
                    if self.spiders {
                        spider(g, b.node(*c), b.footprint(k, *c));
                    }
                    b.node(*c)
                }
                None => {
                    let f = add_node(g, [c[0], c[1], 0.0]);
                    feet.push(f);
                    f
                }
            };
            nodes.push(foot);
            g.frames.push(FrameSpec {
                set: None,
                nodes: Some(nodes.clone()),
                divisions: None,
                area: s.area_m2,
                iy: s.iy_m4,
                iz: s.iz_m4,
                j: s.torsion_constant_m4,
                orientation: None,
                material: Some(column_material),
                releases: Vec::new(),
                part: None,
            });
            if self.spiders {
                spider(g, top, bed.footprint(k, *c));
            }
            columns.push(nodes);
        }
        if !feet.is_empty() {
            g.sets.insert(FEET.into(), feet);
            g.constraints.push(ConstraintSpec {
                set: FEET.into(),
                dofs: vec!["all".into()],
            });
        }
        columns
    }

    /// The added masses at their plate nodes (the bed's in the part `bed`); one on the base of
    /// a machine without a floating base is refused.
    fn add_masses(
        &self,
        g: &mut GeneralSpec,
        bed: &PlateMesh,
        base: Option<&PlateMesh>,
    ) -> Result<()> {
        for m in &self.added_masses {
            let node = match m.plate {
                Plate::Bed => bed.node(m.offset_m),
                Plate::Base => match base {
                    Some(b) => b.node(m.offset_m),
                    None => return Err(Error::invalid(
                        "added mass",
                        "is on the floating base, but the machine has fixed columns and no base",
                    )),
                },
            };
            g.masses.push(MassSpec {
                node: NodeRef::Index(node),
                mass: m.mass_kg,
                inertia: Some(m.inertia_kg_m2),
                part: (m.plate == Plate::Bed).then(|| BED_PART.to_string()),
            });
        }
        Ok(())
    }
}

/// A generated plate: its nodes `grid[i][j]` at the grid lines `xs`, `ys` (m), and each
/// column's footprint extent in x and y (`fx[k]`, `fy[k]`; empty without spiders).
struct PlateMesh {
    grid: Vec<Vec<usize>>,
    xs: Vec<f64>,
    ys: Vec<f64>,
    fx: Vec<[f64; 2]>,
    fy: Vec<[f64; 2]>,
}

impl PlateMesh {
    /// The plate's node at the grid point (x, y) (m), which must be on the grid.
    fn node(&self, p: [f64; 2]) -> usize {
        self.grid[index_of(&self.xs, p[0])][index_of(&self.ys, p[1])]
    }

    /// The plate nodes in column `k`'s footprint around its axis `centre`, but the axis node.
    fn footprint(&self, k: usize, centre: [f64; 2]) -> Vec<usize> {
        footprint(
            &self.grid, &self.xs, &self.ys, centre, self.fx[k], self.fy[k],
        )
    }
}

/// The name of the node set of the clamped column feet (fixed columns).
pub const FEET: &str = "column_feet";

fn material_spec(m: Material) -> MaterialSpec {
    MaterialSpec {
        youngs_modulus: m.youngs_modulus_pa,
        poisson_ratio: m.poisson_ratio,
        density: m.density_kg_per_m3,
    }
}

fn add_node(g: &mut GeneralSpec, p: [f64; 3]) -> usize {
    g.nodes.push(p);
    g.nodes.len() - 1
}

/// A structured grid of quadrangles in the plane `z = z_m` with grid lines at `xs_m` and `ys_m`
/// (each strictly increasing, at least two values), as one shell set of `plate`'s thickness
/// and material. Returns the inline node indices as `grid[i][j]` for the node at
/// `(xs_m[i], ys_m[j])`. Nodes are numbered with `j` fastest, quadrangles with `i` fastest,
/// counter-clockwise about +z (as [`Mesh::add_plate_grid`]). `part` labels the shells (the
/// bed plate is [`BED_PART`]).
fn plate_grid(
    g: &mut GeneralSpec,
    xs_m: &[f64],
    ys_m: &[f64],
    z_m: f64,
    plate: &PlateSpec,
    part: Option<&str>,
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
        .map(|&x| ys_m.iter().map(|&y| add_node(g, [x, y, z_m])).collect())
        .collect();
    let mut quads = Vec::with_capacity((xs_m.len() - 1) * (ys_m.len() - 1));
    for j in 0..ys_m.len() - 1 {
        for i in 0..xs_m.len() - 1 {
            quads.push([
                grid[i][j],
                grid[i + 1][j],
                grid[i + 1][j + 1],
                grid[i][j + 1],
            ]);
        }
    }
    g.shells.push(ShellSpec {
        set: None,
        quads,
        triangles: Vec::new(),
        thickness: plate.thickness_m,
        material: Some(material_spec(plate.material)),
        shear_factor: None,
        part: part.map(str::to_string),
    });
    Ok(grid)
}
