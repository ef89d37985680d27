//! DOF numbering and global assembly of K, M and C.
//!
//! Every node carries six DOFs (global index `6 node + dof`). The *reduced* DOFs are the free
//! DOFs of nodes that are not rigid-link slaves. The map from full to reduced DOFs is a sparse
//! constraint transformation `u_full = T u_red` (Cook et al., *Concepts and Applications of FEA*,
//! 4th ed., §9.2): a free independent DOF maps to itself, a fixed DOF to nothing, and a slave DOF
//! to the linear combination `u_s = u_m + θ_m × (x_s - x_m)`, `θ_s = θ_m` of its master's DOFs.
//! Element matrices are transformed entry by entry, `K_red = Tᵀ K T`, and collected as triplets;
//! faer sums duplicates when it builds the compressed-column matrices.

use std::collections::BTreeMap;

use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;

use super::frame::frame_matrices;
use super::mesh::Mesh;
use super::shell::shell_matrices;
use super::tri3::tri_matrices;
use crate::{Error, Result};

/// Map from full DOFs (`6 node + dof`) to reduced DOFs: `u_full[i] = Σ coeff · u_red[j]`.
#[derive(Debug, Clone)]
pub struct DofMap {
    rows: Vec<Vec<(usize, f64)>>,
    n_free: usize,
    /// For each reduced DOF, the full DOF it is.
    reduced_to_full: Vec<usize>,
}

impl DofMap {
    /// Numbers the DOFs of a (validated) mesh.
    pub fn new(mesh: &Mesh) -> Result<Self> {
        let n_full = 6 * mesh.nodes.len();
        let mut master_of: BTreeMap<usize, usize> = BTreeMap::new();
        for l in &mesh.rigid_links {
            for &s in &l.slaves {
                master_of.insert(s, l.master);
            }
        }
        let mut rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n_full];
        let mut reduced_to_full = Vec::new();
        for node in 0..mesh.nodes.len() {
            if master_of.contains_key(&node) {
                continue;
            }
            for d in 0..6 {
                let i = 6 * node + d;
                if !mesh.fixed.contains(&i) {
                    rows[i].push((reduced_to_full.len(), 1.0));
                    reduced_to_full.push(i);
                }
            }
        }
        for (&s, &m) in &master_of {
            let r = super::geom::sub(mesh.nodes[s], mesh.nodes[m]);
            let mrows: Vec<Vec<(usize, f64)>> = (0..6).map(|d| rows[6 * m + d].clone()).collect();
            let mrow = |d: usize| mrows[d].clone();
            // u_s = u_m + θ × r: x: +θy rz - θz ry; y: +θz rx - θx rz; z: +θx ry - θy rx.
            let terms: [Vec<(usize, f64)>; 3] = [
                vec![(0, 1.0), (4, r[2]), (5, -r[1])],
                vec![(1, 1.0), (5, r[0]), (3, -r[2])],
                vec![(2, 1.0), (3, r[1]), (4, -r[0])],
            ];
            for (d, t) in terms.iter().enumerate() {
                let mut row: Vec<(usize, f64)> = Vec::new();
                for &(md, c) in t {
                    if c != 0.0 {
                        for (j, cm) in mrow(md) {
                            row.push((j, c * cm));
                        }
                    }
                }
                rows[6 * s + d] = row;
            }
            for d in 3..6 {
                rows[6 * s + d] = mrow(d);
            }
        }
        Ok(DofMap {
            rows,
            n_free: reduced_to_full.len(),
            reduced_to_full,
        })
    }

    /// Number of reduced (independent free) DOFs.
    pub fn n_free(&self) -> usize {
        self.n_free
    }
    /// Number of full DOFs (6 per node).
    pub fn n_full(&self) -> usize {
        self.rows.len()
    }
    /// The reduced-DOF combination giving full DOF `i`.
    pub fn row(&self, i: usize) -> &[(usize, f64)] {
        &self.rows[i]
    }
    /// The full DOF that reduced DOF `j` is.
    pub fn full_of(&self, j: usize) -> usize {
        self.reduced_to_full[j]
    }
    /// Reduced index of full DOF `6 node + dof` if it is an independent free DOF.
    pub fn reduced_index(&self, node: usize, dof: usize) -> Option<usize> {
        let i = 6 * node + dof;
        match self.rows.get(i).map(|r| r.as_slice()) {
            Some([(j, c)]) if *c == 1.0 && self.reduced_to_full[*j] == i => Some(*j),
            _ => None,
        }
    }
    /// Full displacement vector `T u_red` (length `6 × nodes`); `u_red` must have
    /// [`DofMap::n_free`] entries.
    pub fn expand(&self, u_red: &[f64]) -> Result<Vec<f64>> {
        if u_red.len() != self.n_free {
            return Err(Error::invalid(
                "reduced displacement vector",
                format!(
                    "has {} entries; the model has {} DOFs",
                    u_red.len(),
                    self.n_free
                ),
            ));
        }
        Ok(self
            .rows
            .iter()
            .map(|r| r.iter().map(|&(j, c)| c * u_red[j]).sum())
            .collect())
    }
}

/// An assembled finite-element model: reduced sparse K, M, C and the functionals needed by the
/// modal model (named points, force to the floor).
#[derive(Debug, Clone)]
pub struct FeModel {
    pub mesh: Mesh,
    pub dofs: DofMap,
    /// Reduced stiffness (N/m, ...).
    pub stiffness: SparseColMat<usize, f64>,
    /// Reduced mass (kg, ...).
    pub mass: SparseColMat<usize, f64>,
    /// Reduced damping from dashpots (N·s/m, ...).
    pub damping: SparseColMat<usize, f64>,
    /// Unit vector (global) along which the slider moves; point values and the floor force are
    /// components along it. `[0, 0, 1]` unless set.
    pub impact_direction: [f64; 3],
    /// Force on the floor along `impact_direction` = `floor_stiffness · u_red + floor_damping · u̇_red`.
    pub floor_stiffness: Vec<f64>,
    pub floor_damping: Vec<f64>,
    /// True when something transmits force to the ground (supports or springs/dashpots to ground).
    pub grounded: bool,
}

struct Collector<'a> {
    map: &'a DofMap,
    dir: [f64; 3],
    fixed: &'a std::collections::BTreeSet<usize>,
    k: Vec<Triplet<usize, usize, f64>>,
    m: Vec<Triplet<usize, usize, f64>>,
    c: Vec<Triplet<usize, usize, f64>>,
    floor_k: Vec<f64>,
    floor_c: Vec<f64>,
}

#[derive(Clone, Copy)]
enum Kind {
    K,
    M,
    C,
}

impl Collector<'_> {
    /// Adds an element matrix `a` over the full DOFs `dofs`.
    fn add(&mut self, kind: Kind, dofs: &[usize], a: &Mat<f64>) {
        for (p, &dp) in dofs.iter().enumerate() {
            // Support reaction: force on the floor at a fixed translation = -(K u)_f.
            let react = if self.fixed.contains(&dp) && dp % 6 < 3 {
                self.dir[dp % 6]
            } else {
                0.0
            };
            for (q, &dq) in dofs.iter().enumerate() {
                let v = a[(p, q)];
                if v == 0.0 {
                    continue;
                }
                if react != 0.0 {
                    let f = match kind {
                        Kind::K => Some(&mut self.floor_k),
                        Kind::C => Some(&mut self.floor_c),
                        Kind::M => None,
                    };
                    if let Some(f) = f {
                        for &(b, tb) in self.map.row(dq) {
                            f[b] -= react * v * tb;
                        }
                    }
                }
                let list = match kind {
                    Kind::K => &mut self.k,
                    Kind::M => &mut self.m,
                    Kind::C => &mut self.c,
                };
                for &(a_, ta) in self.map.row(dp) {
                    for &(b, tb) in self.map.row(dq) {
                        list.push(Triplet::new(a_, b, ta * tb * v));
                    }
                }
            }
        }
    }
    /// Per-direction coefficients between two nodes or a node and the ground.
    fn add_discrete(&mut self, kind: Kind, node: usize, other: Option<usize>, coef: &[f64; 6]) {
        for (d, &c) in coef.iter().enumerate() {
            if c == 0.0 {
                continue;
            }
            match other {
                Some(o) => {
                    let mut a = Mat::<f64>::zeros(2, 2);
                    a[(0, 0)] = c;
                    a[(1, 1)] = c;
                    a[(0, 1)] = -c;
                    a[(1, 0)] = -c;
                    self.add(kind, &[6 * node + d, 6 * o + d], &a);
                }
                None => {
                    let mut a = Mat::<f64>::zeros(1, 1);
                    a[(0, 0)] = c;
                    self.add(kind, &[6 * node + d], &a);
                    // The ground spring pushes the floor with +c u along its direction.
                    if d < 3 && self.dir[d] != 0.0 {
                        let f = match kind {
                            Kind::K => &mut self.floor_k,
                            _ => &mut self.floor_c,
                        };
                        for &(b, tb) in self.map.row(6 * node + d) {
                            f[b] += self.dir[d] * c * tb;
                        }
                    }
                }
            }
        }
    }
}

fn sparse(
    n: usize,
    t: &[Triplet<usize, usize, f64>],
    what: &str,
) -> Result<SparseColMat<usize, f64>> {
    SparseColMat::try_new_from_triplets(n, n, t)
        .map_err(|e| Error::numerical("assembly", format!("building sparse {what}: {e:?}")))
}

/// Memory (bytes) per free DOF of assembling a model and solving its lowest modes with the
/// sparse solver: the element triplets, the sparse K, M, C, the factorisation and the Lanczos
/// basis. Measured peak resident memory of `meid modes` on the paper machine
/// (`elements_per_side` 64, 96, 128: 31 k, 68 k, 125 k DOFs) is 5.3-5.9 KiB per DOF; 6 KiB
/// with the process's own ~10 MiB is the estimate.
pub const BYTES_PER_DOF: f64 = 6.0 * 1024.0;

/// Refuses a model of `n` free DOFs whose assembly and modal solve
/// (`n ×` [`BYTES_PER_DOF`]) would exceed [`crate::limits::max_memory`].
pub fn check_memory(n: usize) -> Result<()> {
    crate::limits::check_memory(
        &format!(
            "the finite-element model ({n} DOFs × {} KiB: assembly and eigen-solver)",
            BYTES_PER_DOF / 1024.0
        ),
        n as f64 * BYTES_PER_DOF,
        "mesh",
        "structure.fem.machine.elements_per_side (parametric machine) or the number of \
         elements of the Gmsh mesh",
    )
}

impl FeModel {
    /// Validates the mesh and assembles it with the impact direction +Z.
    pub fn assemble(mesh: Mesh) -> Result<Self> {
        Self::assemble_with_direction(mesh, [0.0, 0.0, 1.0])
    }

    /// Validates the mesh and assembles reduced K, M, C; `impact_direction` (global, normalised
    /// here) is the direction the slider moves.
    pub fn assemble_with_direction(mesh: Mesh, impact_direction: [f64; 3]) -> Result<Self> {
        mesh.validate()?;
        let dir = super::geom::unit(impact_direction).ok_or_else(|| {
            Error::invalid(
                "impact direction",
                format!("{impact_direction:?} is not a nonzero vector"),
            )
        })?;
        let map = DofMap::new(&mesh)?;
        let n = map.n_free();
        if n == 0 {
            return Err(Error::invalid("mesh", "every degree of freedom is fixed"));
        }
        check_memory(n)?;
        let mut col = Collector {
            map: &map,
            dir,
            fixed: &mesh.fixed,
            k: Vec::new(),
            m: Vec::new(),
            c: Vec::new(),
            floor_k: vec![0.0; n],
            floor_c: vec![0.0; n],
        };
        for (i, f) in mesh.frames.iter().enumerate() {
            let (k, m) = frame_matrices(
                mesh.nodes[f.nodes[0]],
                mesh.nodes[f.nodes[1]],
                &f.material,
                &f.section,
                f.orientation,
            )
            .map_err(|e| Error::invalid(format!("frame element {i}"), e.to_string()))?;
            let dofs: Vec<usize> = f
                .nodes
                .iter()
                .flat_map(|&nd| (0..6).map(move |d| 6 * nd + d))
                .collect();
            col.add(Kind::K, &dofs, &k);
            col.add(Kind::M, &dofs, &m);
        }
        for (i, s) in mesh.shells.iter().enumerate() {
            let x = s.nodes.map(|nd| mesh.nodes[nd]);
            let (k, m) = shell_matrices(&x, s)
                .map_err(|e| Error::invalid(format!("shell element {i}"), e.to_string()))?;
            let dofs: Vec<usize> = s
                .nodes
                .iter()
                .flat_map(|&nd| (0..6).map(move |d| 6 * nd + d))
                .collect();
            col.add(Kind::K, &dofs, &k);
            col.add(Kind::M, &dofs, &m);
        }
        for (i, s) in mesh.triangles.iter().enumerate() {
            let x = s.nodes.map(|nd| mesh.nodes[nd]);
            let (k, m) = tri_matrices(&x, s)
                .map_err(|e| Error::invalid(format!("triangle {i}"), e.to_string()))?;
            let dofs: Vec<usize> = s
                .nodes
                .iter()
                .flat_map(|&nd| (0..6).map(move |d| 6 * nd + d))
                .collect();
            col.add(Kind::K, &dofs, &k);
            col.add(Kind::M, &dofs, &m);
        }
        for s in &mesh.springs {
            col.add_discrete(Kind::K, s.node, s.other, &s.stiffness);
        }
        for d in &mesh.dashpots {
            col.add_discrete(Kind::C, d.node, d.other, &d.damping);
        }
        for pm in &mesh.masses {
            let mut a = Mat::<f64>::zeros(6, 6);
            for d in 0..3 {
                a[(d, d)] = pm.mass_kg;
                a[(d + 3, d + 3)] = pm.inertia_kg_m2[d];
            }
            let dofs: Vec<usize> = (0..6).map(|d| 6 * pm.node + d).collect();
            col.add(Kind::M, &dofs, &a);
        }
        let grounded = !mesh.fixed.is_empty()
            || mesh.springs.iter().any(|s| s.other.is_none())
            || mesh.dashpots.iter().any(|s| s.other.is_none());
        let stiffness = sparse(n, &col.k, "stiffness")?;
        let mass = sparse(n, &col.m, "mass")?;
        let damping = sparse(n, &col.c, "damping")?;
        let (floor_stiffness, floor_damping) = (col.floor_k, col.floor_c);
        Ok(FeModel {
            mesh,
            dofs: map,
            stiffness,
            mass,
            damping,
            impact_direction: dir,
            floor_stiffness,
            floor_damping,
            grounded,
        })
    }

    /// Number of reduced DOFs.
    pub fn n_dofs(&self) -> usize {
        self.dofs.n_free()
    }
    /// Dense reduced stiffness.
    pub fn dense_stiffness(&self) -> Mat<f64> {
        self.stiffness.to_dense()
    }
    /// Dense reduced mass.
    pub fn dense_mass(&self) -> Mat<f64> {
        self.mass.to_dense()
    }
    /// Dense reduced damping.
    pub fn dense_damping(&self) -> Mat<f64> {
        self.damping.to_dense()
    }
    /// All modes by the dense shift-invert solver [`crate::modal::dense::solve_shift_invert`]
    /// with its default shift (small models, up to a few thousand DOFs).
    pub fn solve_dense(&self) -> Result<crate::modal::dense::DenseModes> {
        crate::modal::dense::solve_shift_invert(
            self.dense_stiffness().as_ref(),
            self.dense_mass().as_ref(),
            None,
        )
    }
}

/// A spring DOF so stiff next to the structure's own stiffness that it acts as a constraint
/// ([`FeModel::constraint_like_springs`]).
#[derive(Debug, Clone, PartialEq)]
pub struct StiffSpring {
    /// Index in `mesh.springs`.
    pub spring: usize,
    /// Node of the spring.
    pub node: usize,
    /// DOF (0..6: ux, uy, uz, rx, ry, rz).
    pub dof: usize,
    /// The spring's stiffness (N/m or N·m/rad).
    pub stiffness: f64,
    /// `k / K_own`, K_own the diagonal stiffness of the elements (not the springs) at the DOF;
    /// infinite when the elements give none.
    pub ratio: f64,
}

/// Names of the six DOFs of a node, as model files give them.
pub const DOF_NAMES: [&str; 6] = ["ux", "uy", "uz", "rx", "ry", "rz"];

impl FeModel {
    /// Spring DOFs (to ground or between nodes) whose stiffness is at least `ratio` times the
    /// diagonal stiffness the elements give that DOF, `K_ii − Σ k_springs`: the DOF then moves
    /// `≲ 1/ratio` of what the structure alone would let it, i.e. the spring acts as a constraint,
    /// and its stiffness only spreads the spectrum (the eigenvalues it adds are ~`k/m` of the
    /// node, far above the structure's). DOFs that are not independent (fixed, rigid-link
    /// slaves) are skipped. Sorted by descending ratio.
    pub fn constraint_like_springs(&self, ratio: f64) -> Vec<StiffSpring> {
        let n = self.n_dofs();
        let mut diag = vec![0.0; n];
        for t in self.stiffness.triplet_iter() {
            if t.row == t.col {
                diag[t.row] += *t.val;
            }
        }
        let mut spring_sum = vec![0.0; n];
        let mut cand = Vec::new();
        for (si, s) in self.mesh.springs.iter().enumerate() {
            for (d, &k) in s.stiffness.iter().enumerate() {
                if k <= 0.0 {
                    continue;
                }
                for node in std::iter::once(s.node).chain(s.other) {
                    if let Some(j) = self.dofs.reduced_index(node, d) {
                        spring_sum[j] += k;
                        cand.push((si, node, d, k, j));
                    }
                }
            }
        }
        let mut out: Vec<StiffSpring> = cand
            .into_iter()
            .filter_map(|(spring, node, dof, k, j)| {
                let own = diag[j] - spring_sum[j];
                // Round-off of the subtraction: an own stiffness below ε K_ii is none.
                let own = if own > f64::EPSILON * diag[j] {
                    own
                } else {
                    0.0
                };
                let r = if own > 0.0 { k / own } else { f64::INFINITY };
                (r >= ratio).then_some(StiffSpring {
                    spring,
                    node,
                    dof,
                    stiffness: k,
                    ratio: r,
                })
            })
            .collect();
        out.sort_by(|a, b| b.ratio.total_cmp(&a.ratio));
        out
    }

    /// A sentence on the springs that act as constraints (`None` if none does), for notes and
    /// error messages: how many, how stiff relative to the structure, an example node, and the
    /// constraint to give instead.
    pub fn constraint_like_note(&self, ratio: f64) -> Option<String> {
        let v = self.constraint_like_springs(ratio);
        let first = v.first()?;
        let mut dofs: Vec<&str> = v.iter().map(|s| DOF_NAMES[s.dof]).collect();
        dofs.sort_unstable();
        dofs.dedup();
        let min = v.iter().map(|s| s.ratio).fold(f64::INFINITY, f64::min);
        let p = self.mesh.nodes[first.node];
        Some(format!(
            "{} spring DOF(s) ({}) are {min:.1e} to {:.1e} times the stiffness the elements give \
             those DOFs (e.g. node {} at [{}, {}, {}] m, {}: {:e}): they act as constraints and only \
             spread the spectrum beyond what double precision resolves; constrain those DOFs instead \
             (`constraints = [{{ set = ..., dofs = [{}] }}]`)",
            v.len(),
            dofs.join(", "),
            first.ratio,
            first.node,
            p[0],
            p[1],
            p[2],
            DOF_NAMES[first.dof],
            first.stiffness,
            dofs.iter().map(|d| format!("\"{d}\"")).collect::<Vec<_>>().join(", ")
        ))
    }

    /// All modes by [`crate::modal::dense::solve_shift_invert_lowest`] with the default shift:
    /// every resolved mode, at least the lowest `count`.
    pub fn solve_dense_lowest(&self, count: usize) -> Result<crate::modal::dense::DenseModes> {
        crate::modal::dense::solve_shift_invert_lowest(
            self.dense_stiffness().as_ref(),
            self.dense_mass().as_ref(),
            None,
            Some(count),
        )
    }
}
