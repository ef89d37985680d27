//! DOF numbering and global assembly of K, M and C.
//!
//! Every node carries six DOFs (global index `6 node + dof`). The *reduced* DOFs are the free
//! DOFs of nodes that are not rigid-link slaves. The map from full to reduced DOFs is a sparse
//! constraint transformation `u_full = T u_red` (Cook et al., *Concepts and Applications of FEA*,
//! 4th ed., §9.2): a free independent DOF maps to itself, a fixed DOF to nothing, and a slave DOF
//! to the linear combination `u_s = u_m + θ_m × (x_s - x_m)`, `θ_s = θ_m` of its master's DOFs.
//! Element matrices are transformed entry by entry, `K_red = Tᵀ K T`, and collected as triplets;
//! [`super::compress`] sums the duplicates into compressed columns (faer's sums, bit for bit).
//!
//! # Parallel and deterministic
//! Frames and shells are assembled in fixed chunks of [`ASSEMBLY_CHUNK`] elements: within a
//! chunk the element matrices and their triplets are computed in parallel (rayon), each element
//! into its own lists; the lists are then appended, and the floor-force terms summed, in element
//! order. The triplet sequence, every floating-point sum and so K, M, C and the floor-force
//! functional are the same bits for any thread count (tests `fem_thread_determinism`).

use std::collections::BTreeMap;

use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;
use rayon::prelude::*;

use super::compress::compress;
use super::frame::{frame_local_axes, frame_matrices_released, LOCAL_DOF_NAMES};
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

/// The triplets and floor-force terms of one element, computed apart from the collector (in
/// parallel) and appended to it in element order.
#[derive(Default)]
struct Scattered {
    k: Vec<Triplet<usize, usize, f64>>,
    m: Vec<Triplet<usize, usize, f64>>,
    /// `(reduced DOF, term)` to subtract from the floor stiffness functional, in order.
    floor_k: Vec<(usize, f64)>,
}

/// Elements assembled per parallel chunk (module docs): large enough to keep both cores busy,
/// small enough that a chunk's element lists stay a few megabytes.
pub const ASSEMBLY_CHUNK: usize = 2048;

impl Collector<'_> {
    /// The triplets of a stiffness (`floor` = Some) or mass element matrix `a` over the full
    /// DOFs `dofs`, with the support reactions `-(K u)_f` at fixed translations pushed to
    /// `floor`, one `(reduced DOF, term)` per term in the order the sum takes them.
    fn scatter(
        &self,
        dofs: &[usize],
        a: &Mat<f64>,
        list: &mut Vec<Triplet<usize, usize, f64>>,
        mut floor: Option<&mut Vec<(usize, f64)>>,
    ) {
        for (p, &dp) in dofs.iter().enumerate() {
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
                    if let Some(f) = floor.as_deref_mut() {
                        for &(b, tb) in self.map.row(dq) {
                            f.push((b, react * v * tb));
                        }
                    }
                }
                for &(a_, ta) in self.map.row(dp) {
                    for &(b, tb) in self.map.row(dq) {
                        list.push(Triplet::new(a_, b, ta * tb * v));
                    }
                }
            }
        }
    }

    /// Assembles the elements `elems` whose stiffness and mass matrices (and full DOFs)
    /// `matrices` gives, chunk by chunk in parallel, appending in element order (module docs).
    /// The first failing element (in element order) is the error.
    fn add_elements<E: Sync>(
        &mut self,
        elems: &[E],
        matrices: impl Fn(usize, &E) -> Result<(Vec<usize>, Mat<f64>, Mat<f64>)> + Sync,
    ) -> Result<()> {
        for (c, chunk) in elems.chunks(ASSEMBLY_CHUNK).enumerate() {
            let this = &*self;
            let parts: Vec<Result<Scattered>> = chunk
                .par_iter()
                .enumerate()
                .map(|(i, e)| {
                    let (dofs, k, m) = matrices(c * ASSEMBLY_CHUNK + i, e)?;
                    let mut s = Scattered::default();
                    // One triplet per entry when every DOF maps to one reduced DOF (most do):
                    // sized once instead of grown push by push.
                    s.k.reserve(dofs.len() * dofs.len());
                    s.m.reserve(dofs.len() * dofs.len());
                    this.scatter(&dofs, &k, &mut s.k, Some(&mut s.floor_k));
                    this.scatter(&dofs, &m, &mut s.m, None);
                    Ok(s)
                })
                .collect();
            for part in parts {
                let s = part?;
                self.k.extend_from_slice(&s.k);
                self.m.extend_from_slice(&s.m);
                for (b, t) in s.floor_k {
                    self.floor_k[b] -= t;
                }
            }
        }
        Ok(())
    }

    /// Adds an element matrix `a` over the full DOFs `dofs` (support reactions of K and C to
    /// the floor functional, [`Collector::scatter`]).
    fn add(&mut self, kind: Kind, dofs: &[usize], a: &Mat<f64>) {
        let mut list = std::mem::take(match kind {
            Kind::K => &mut self.k,
            Kind::M => &mut self.m,
            Kind::C => &mut self.c,
        });
        let mut floor = Vec::new();
        let with_floor = !matches!(kind, Kind::M);
        self.scatter(dofs, a, &mut list, with_floor.then_some(&mut floor));
        let (target, f) = match kind {
            Kind::K => (&mut self.k, &mut self.floor_k),
            Kind::M => (&mut self.m, &mut self.floor_k),
            Kind::C => (&mut self.c, &mut self.floor_c),
        };
        *target = list;
        for (b, t) in floor {
            f[b] -= t;
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

/// A released frame end leaves its node DOF a mechanism when nothing else at the node has
/// stiffness or inertia along the released direction `e` (global): with K, M positive
/// semi-definite, `eᵀ K e = 0` means `K e = 0`, so the node turns freely along `e` and the
/// pencil (K, M) is singular when `eᵀ M e = 0` too. Such a node is an error naming it; with
/// inertia (a point mass's rotary inertia) it is a zero-frequency mode, which the modal solver's
/// rigid-body check reports. `e` is projected on the node's free independent DOFs (a fixed DOF
/// holds its component); rigid-link slaves are left to their master.
fn check_released_dofs(
    mesh: &Mesh,
    map: &DofMap,
    k: &SparseColMat<usize, f64>,
    m: &SparseColMat<usize, f64>,
) -> Result<()> {
    // (node, block 0 = translations / 1 = rotations, global direction, label)
    let mut dirs: Vec<(usize, usize, [f64; 3], String)> = Vec::new();
    for (i, f) in mesh.frames.iter().enumerate() {
        if !f.has_releases() {
            continue;
        }
        let axes = frame_local_axes(
            mesh.nodes[f.nodes[0]],
            mesh.nodes[f.nodes[1]],
            f.orientation,
        )?;
        for (end, rel) in f.releases.iter().enumerate() {
            for (d, &r) in rel.iter().enumerate() {
                if r {
                    dirs.push((
                        f.nodes[end],
                        d / 3,
                        axes[d % 3],
                        format!(
                            "{} (local) of frame element {i} at its end {}",
                            LOCAL_DOF_NAMES[d],
                            end + 1
                        ),
                    ));
                }
            }
        }
    }
    if dirs.is_empty() {
        return Ok(());
    }
    // Reduced indices of the blocks concerned and their 3×3 entries of K and M.
    let mut want: BTreeMap<usize, (usize, usize)> = BTreeMap::new();
    for &(node, block, _, _) in &dirs {
        for c in 0..3 {
            if let Some(j) = map.reduced_index(node, 3 * block + c) {
                want.insert(j, (node, block));
            }
        }
    }
    let mut blk: BTreeMap<(usize, usize), [[[f64; 3]; 3]; 2]> = BTreeMap::new();
    for (which, a) in [k, m].into_iter().enumerate() {
        for t in a.triplet_iter() {
            if let (Some(&(n1, b1)), Some(&(n2, b2))) = (want.get(&t.row), want.get(&t.col)) {
                if (n1, b1) == (n2, b2) {
                    let (r, c) = (map.full_of(t.row) % 3, map.full_of(t.col) % 3);
                    blk.entry((n1, b1)).or_insert([[[0.0; 3]; 3]; 2])[which][r][c] += *t.val;
                }
            }
        }
    }
    for (node, block, e, label) in dirs {
        let free: Vec<bool> = (0..3)
            .map(|c| map.reduced_index(node, 3 * block + c).is_some())
            .collect();
        if !free.iter().any(|&f| f) {
            continue;
        }
        let ep: Vec<f64> = (0..3).map(|c| if free[c] { e[c] } else { 0.0 }).collect();
        if ep.iter().map(|x| x * x).sum::<f64>() < 1e-12 {
            continue;
        }
        let b = blk
            .get(&(node, block))
            .copied()
            .unwrap_or([[[0.0; 3]; 3]; 2]);
        let q = |a: &[[f64; 3]; 3]| -> (f64, f64) {
            let mut s = 0.0;
            let mut mx: f64 = 0.0;
            for r in 0..3 {
                mx = mx.max(a[r][r].abs());
                for c in 0..3 {
                    s += ep[r] * a[r][c] * ep[c];
                }
            }
            (s, mx)
        };
        let (qk, kmax) = q(&b[0]);
        let (qm, mmax) = q(&b[1]);
        if qk <= 1e-12 * kmax && qm <= 1e-12 * mmax {
            let what = if block == 0 {
                "translation"
            } else {
                "rotation"
            };
            return Err(Error::invalid(
                format!("node {node}"),
                format!(
                    "the release {label} leaves the node's {what} along {e:.3?} (global) with neither stiffness nor inertia: a mechanism. Keep one frame end at the node rigid, or constrain that DOF (`constraints`)"
                ),
            ));
        }
    }
    Ok(())
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
        let node_dofs = |nodes: &[usize]| -> Vec<usize> {
            nodes
                .iter()
                .flat_map(|&nd| (0..6).map(move |d| 6 * nd + d))
                .collect()
        };
        col.add_elements(&mesh.frames, |i, f| {
            let (k, m) = frame_matrices_released(
                mesh.nodes[f.nodes[0]],
                mesh.nodes[f.nodes[1]],
                &f.material,
                &f.section,
                f.orientation,
                &f.releases,
            )
            .map_err(|e| Error::invalid(format!("frame element {i}"), e.to_string()))?;
            Ok((node_dofs(&f.nodes), k, m))
        })?;
        col.add_elements(&mesh.shells, |i, s| {
            let x = s.nodes.map(|nd| mesh.nodes[nd]);
            let (k, m) = shell_matrices(&x, s)
                .map_err(|e| Error::invalid(format!("shell element {i}"), e.to_string()))?;
            Ok((node_dofs(&s.nodes), k, m))
        })?;
        col.add_elements(&mesh.triangles, |i, s| {
            let x = s.nodes.map(|nd| mesh.nodes[nd]);
            let (k, m) = tri_matrices(&x, s)
                .map_err(|e| Error::invalid(format!("triangle {i}"), e.to_string()))?;
            Ok((node_dofs(&s.nodes), k, m))
        })?;
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
        // Each triplet list is freed once compressed (at 10⁶ DOF K's is ~1.4 GB).
        let stiffness = compress(n, &std::mem::take(&mut col.k), "stiffness")?;
        let mass = compress(n, &std::mem::take(&mut col.m), "mass")?;
        let damping = compress(n, &std::mem::take(&mut col.c), "damping")?;
        check_released_dofs(&mesh, &map, &stiffness, &mass)?;
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
    /// when the elements give none, `k / (K_ii − k)`, the other springs' stiffness there.
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
    /// slaves) are skipped. On a DOF no element stiffens, the spring is compared with the other
    /// springs there, `k / (K_ii − k) ≥ ratio`; a spring that is the DOF's only stiffness is
    /// never a constraint (without it the DOF is a mechanism: a chain of point masses and
    /// springs). Sorted by descending ratio.
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
                // No element stiffens the DOF (a discrete spring-mass model, a point mass on a
                // spring): compared with the other springs there, `K_ii − k`. A spring that is
                // the DOF's only stiffness holds what would be a mechanism: no constraint.
                let r = if own > 0.0 {
                    k / own
                } else {
                    let other = diag[j] - k;
                    if other > f64::EPSILON * diag[j] {
                        k / other
                    } else {
                        0.0
                    }
                };
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
