//! `[structure.fem.machine]` is a generator of the general model (issue 13, point 3): the
//! paper's machine and a user's `[structure.fem.model]` share every line below
//! [`MachineSpec::generate`].
//!
//! * The path the machine had before it became a generator (its own machine → `Mesh` builder,
//!   kept here only as the reference, copied verbatim from `structure/machine.rs` at commit
//!   76e1da8 minus its input checks) and the generator + general builder give **identical**
//!   K, M (every stored entry, bit for bit), DOF maps, point functionals and floor-force
//!   functionals, for no base (fixed columns), soft and stiff floating bases, non-default mesh
//!   densities, dashpots and added masses; the lowest modes then agree to 1e-12 relative
//!   (they are bitwise equal: same matrices, deterministic solver).
//! * `meid model expand`'s text ([`expand::expand_text`]) reads back to the very
//!   `GeneralSpec` the generator emitted, and run as a model it gives the same modal model
//!   and the same simulation summary (bit for bit) as the machine file.
//! * The structure cache still hits on an expanded model: non-structural fields build
//!   nothing, a structural field builds once.

// Tests index nodes and modes by position, like the formulas they check.
#![allow(clippy::needless_range_loop)]

use std::path::{Path, PathBuf};

use meid::analysis::simulate;
use meid::modal::lanczos::{lowest_modes, LanczosOptions};
use meid::model::{expand, fem, Case, Model, StructureCache};
use meid::structure::discrete::{Dashpot, PointMass, RigidLink, Spring};
use meid::structure::frame::FrameElement;
use meid::structure::machine::{AddedMass, Plate, PlateSpec};
use meid::structure::{FeModel, MachineSpec, Mesh, Support};
use meid::{Error, Result};

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

// ---------------------------------------------------------------------------------------------
// The old machine → Mesh path (reference only).

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

fn old_build(spec: &MachineSpec) -> Result<FeModel> {
    if !(spec.column_length_m.is_finite() && spec.column_length_m > 0.0) {
        return Err(Error::invalid(
            "column length",
            format!("must be > 0 m (got {})", spec.column_length_m),
        ));
    }
    if spec.elements_per_side < 2
        || spec.column_elements < 1
        || spec.elements_per_side > 400
        || spec.column_elements > 1000
    {
        return Err(Error::invalid(
            "mesh density",
            format!(
                "need 2..=400 elements per plate side and 1..=1000 per column (got {} and {})",
                spec.elements_per_side, spec.column_elements
            ),
        ));
    }
    let half_min = 0.5 * spec.bed.length_x_m.min(spec.bed.length_y_m);
    if !(spec.column_inset_m >= 0.0 && spec.column_inset_m < half_min) {
        return Err(Error::invalid(
            "column inset",
            format!(
                "must lie in [0, {half_min}) m (got {})",
                spec.column_inset_m
            ),
        ));
    }
    if spec.spiders
        && !(spec.spider_half_size_m.is_finite()
            && spec.spider_half_size_m > 0.0
            && spec.spider_half_size_m < half_min)
    {
        return Err(Error::invalid(
            "spider half-size",
            format!(
                "the column footprint half-size must lie in (0, {half_min}) m (got {})",
                spec.spider_half_size_m
            ),
        ));
    }
    inside("point B", spec.b_offset_m, &spec.bed)?;
    let cols = spec.column_positions();
    let mut mesh = Mesh::new();
    let zb = spec.column_length_m;

    // Bed.
    let mut bx = vec![0.0, spec.b_offset_m[0]];
    let mut by = vec![0.0, spec.b_offset_m[1]];
    for c in &cols {
        bx.push(c[0]);
        by.push(c[1]);
    }
    for m in spec.added_masses.iter().filter(|m| m.plate == Plate::Bed) {
        inside("added mass on the bed", m.offset_m, &spec.bed)?;
        bx.push(m.offset_m[0]);
        by.push(m.offset_m[1]);
    }
    let a = spec.spider_half_size_m;
    let col_x: Vec<f64> = cols.iter().map(|c| c[0]).collect();
    let col_y: Vec<f64> = cols.iter().map(|c| c[1]).collect();
    let (bed_fx, bed_fy) = if spec.spiders {
        (
            footprint_lines(&mut bx, &col_x, a, spec.bed.length_x_m),
            footprint_lines(&mut by, &col_y, a, spec.bed.length_y_m),
        )
    } else {
        (Vec::new(), Vec::new())
    };
    let h_bed = spec.bed.length_x_m.max(spec.bed.length_y_m) / spec.elements_per_side as f64;
    let bxs = grid_1d(spec.bed.length_x_m, &bx, h_bed);
    let bys = grid_1d(spec.bed.length_y_m, &by, h_bed);
    let bed_grid = mesh.add_plate_grid(&bxs, &bys, zb, spec.bed.material, spec.bed.thickness_m)?;
    let bed_node = |p: [f64; 2]| (index_of(&bxs, p[0]), index_of(&bys, p[1]));
    let (i, j) = bed_node([0.0, 0.0]);
    mesh.name_point("O_b", vec![bed_grid[i][j]]);
    let (i, j) = bed_node(spec.b_offset_m);
    mesh.name_point("B", vec![bed_grid[i][j]]);

    // Base.
    let mut base_grid = None;
    #[allow(clippy::type_complexity)]
    let mut base_lookup: Option<(Vec<f64>, Vec<f64>, Vec<[f64; 2]>, Vec<[f64; 2]>)> = None;
    if let Support::FloatingBase {
        base,
        spring_stiffness_n_per_m,
        spring_damping_n_s_per_m,
        spring_inset_m,
    } = &spec.support
    {
        for c in &cols {
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
        let springs = [[sx, sy], [-sx, sy], [-sx, -sy], [sx, -sy]];
        let mut xs = vec![0.0];
        let mut ys = vec![0.0];
        for p in cols.iter().chain(springs.iter()) {
            xs.push(p[0]);
            ys.push(p[1]);
        }
        for m in spec.added_masses.iter().filter(|m| m.plate == Plate::Base) {
            inside("added mass on the base", m.offset_m, base)?;
            xs.push(m.offset_m[0]);
            ys.push(m.offset_m[1]);
        }
        let (fx, fy) = if spec.spiders {
            (
                footprint_lines(&mut xs, &col_x, a, base.length_x_m),
                footprint_lines(&mut ys, &col_y, a, base.length_y_m),
            )
        } else {
            (Vec::new(), Vec::new())
        };
        let h = base.length_x_m.max(base.length_y_m) / spec.elements_per_side as f64;
        let gx = grid_1d(base.length_x_m, &xs, h);
        let gy = grid_1d(base.length_y_m, &ys, h);
        let grid = mesh.add_plate_grid(&gx, &gy, 0.0, base.material, base.thickness_m)?;
        mesh.name_point("O_f", vec![grid[index_of(&gx, 0.0)][index_of(&gy, 0.0)]]);
        for p in springs {
            let node = grid[index_of(&gx, p[0])][index_of(&gy, p[1])];
            let k = spring_stiffness_n_per_m;
            if k.iter().any(|&v| v > 0.0) {
                mesh.add_spring(Spring {
                    node,
                    other: None,
                    stiffness: [k[0], k[1], k[2], 0.0, 0.0, 0.0],
                });
            }
            let c = spring_damping_n_s_per_m;
            if c.iter().any(|&v| v > 0.0) {
                mesh.add_dashpot(Dashpot {
                    node,
                    other: None,
                    damping: [c[0], c[1], c[2], 0.0, 0.0, 0.0],
                });
            }
        }
        base_grid = Some(grid);
        base_lookup = Some((gx, gy, fx, fy));
    }

    // Columns and spiders. A plate node joins at most one spider (the first that reaches it)
    // and never one whose master is another column end.
    let mut masters = std::collections::BTreeSet::new();
    for c in &cols {
        let (bi, bj) = bed_node(*c);
        masters.insert(bed_grid[bi][bj]);
        if let (Some(g), Some((gx, gy, _, _))) = (&base_grid, &base_lookup) {
            masters.insert(g[index_of(gx, c[0])][index_of(gy, c[1])]);
        }
    }
    let mut slaved = std::collections::BTreeSet::new();
    let mut spider = |mesh: &mut Mesh, master: usize, candidates: Vec<usize>| {
        let slaves: Vec<usize> = candidates
            .into_iter()
            .filter(|n| !masters.contains(n) && slaved.insert(*n))
            .collect();
        if !slaves.is_empty() {
            mesh.add_rigid_link(RigidLink { master, slaves });
        }
    };
    let mut columns = Vec::new();
    for (k, c) in cols.iter().enumerate() {
        let (bi, bj) = bed_node(*c);
        let top = bed_grid[bi][bj];
        let mut nodes = vec![top];
        let ne = spec.column_elements;
        for e in 1..ne {
            let z = zb * (1.0 - e as f64 / ne as f64);
            nodes.push(mesh.add_node([c[0], c[1], z]));
        }
        let foot = match (&base_grid, &base_lookup) {
            (Some(g), Some((gx, gy, fx, fy))) => {
                let (fi, fj) = (index_of(gx, c[0]), index_of(gy, c[1]));
                if spec.spiders {
                    spider(&mut mesh, g[fi][fj], footprint(g, gx, gy, *c, fx[k], fy[k]));
                }
                g[fi][fj]
            }
            _ => {
                let f = mesh.add_node([c[0], c[1], 0.0]);
                mesh.fix_all(f);
                f
            }
        };
        nodes.push(foot);
        for w in nodes.windows(2) {
            mesh.add_frame(FrameElement::new(
                [w[0], w[1]],
                spec.column_material,
                spec.column_section,
            ));
        }
        if spec.spiders {
            spider(
                &mut mesh,
                top,
                footprint(&bed_grid, &bxs, &bys, *c, bed_fx[k], bed_fy[k]),
            );
        }
        columns.push(nodes);
    }

    for m in &spec.added_masses {
        let node =
            match m.plate {
                Plate::Bed => {
                    let (i, j) = bed_node(m.offset_m);
                    bed_grid[i][j]
                }
                Plate::Base => match (&base_grid, &base_lookup) {
                    (Some(g), Some((gx, gy, _, _))) => {
                        g[index_of(gx, m.offset_m[0])][index_of(gy, m.offset_m[1])]
                    }
                    _ => return Err(Error::invalid(
                        "added mass",
                        "is on the floating base, but the machine has fixed columns and no base",
                    )),
                },
            };
        mesh.add_mass(PointMass {
            node,
            mass_kg: m.mass_kg,
            inertia_kg_m2: m.inertia_kg_m2,
        });
    }

    FeModel::assemble_with_direction(mesh, [0.0, 0.0, -1.0])
}

// ---------------------------------------------------------------------------------------------

/// The machine of an example file.
fn example_machine(name: &str) -> MachineSpec {
    let m = Model::from_file(
        &example(name),
        &["structure.fem.machine.elements_per_side=4".to_string()],
    )
    .unwrap();
    let file = m
        .spec
        .structure
        .fem
        .as_ref()
        .unwrap()
        .machine
        .as_ref()
        .unwrap();
    fem::machine_spec(file).unwrap()
}

/// Sorted (row, col, bits) of a sparse matrix.
fn entries(m: &faer::sparse::SparseColMat<usize, f64>) -> Vec<(usize, usize, u64)> {
    let mut v: Vec<(usize, usize, u64)> = m
        .triplet_iter()
        .map(|t| (t.row, t.col, t.val.to_bits()))
        .collect();
    v.sort_unstable();
    v
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// The configurations compared: the three examples' machines at their own and other mesh
/// densities, and the default machine with dashpots and added masses on both plates.
fn configurations() -> Vec<(String, MachineSpec)> {
    let mut out = Vec::new();
    for (name, eps, ce) in [
        ("paper-no-base.toml", 8, 6),
        ("paper-soft-base.toml", 8, 6),
        ("paper-stiff-base.toml", 8, 6),
        ("paper-soft-base.toml", 13, 3),
        ("paper-no-base.toml", 11, 5),
    ] {
        let mut s = example_machine(name);
        s.elements_per_side = eps;
        s.column_elements = ce;
        out.push((format!("{name} at {eps}/{ce}"), s));
    }
    let mut s = MachineSpec {
        elements_per_side: 10,
        added_masses: vec![
            AddedMass {
                plate: Plate::Bed,
                offset_m: [-0.05, 0.03],
                mass_kg: 2.5,
                inertia_kg_m2: [0.01, 0.02, 0.03],
            },
            AddedMass {
                plate: Plate::Base,
                offset_m: [0.1, -0.07],
                mass_kg: 4.0,
                inertia_kg_m2: [0.0; 3],
            },
        ],
        ..MachineSpec::default()
    };
    if let Support::FloatingBase {
        spring_damping_n_s_per_m,
        ..
    } = &mut s.support
    {
        *spring_damping_n_s_per_m = [30.0, 40.0, 50.0];
    }
    out.push(("default with dashpots and added masses".into(), s));
    let s = MachineSpec {
        spiders: false,
        elements_per_side: 6,
        ..MachineSpec::default()
    };
    out.push(("default without spiders".into(), s));
    out
}

/// K, M, C, the DOF map, the named points and the floor force are the same numbers on both
/// paths, and so are the lowest 12 modes (frequencies to 1e-12 relative; values at O_b, B
/// and O_f to 1e-12 of the largest).
#[test]
fn generator_gives_the_old_matrices() {
    for (what, spec) in configurations() {
        let old = old_build(&spec).unwrap();
        let new = spec.build().unwrap().model;
        assert_eq!(old.mesh.nodes.len(), new.mesh.nodes.len(), "{what}: nodes");
        for (a, b) in old.mesh.nodes.iter().zip(&new.mesh.nodes) {
            assert_eq!(bits(a), bits(b), "{what}: node position");
        }
        assert_eq!(old.n_dofs(), new.n_dofs(), "{what}: DOFs");
        assert_eq!(
            entries(&old.stiffness),
            entries(&new.stiffness),
            "{what}: K"
        );
        assert_eq!(entries(&old.mass), entries(&new.mass), "{what}: M");
        assert_eq!(old.mesh.fixed, new.mesh.fixed, "{what}: supports");
        assert_eq!(
            old.mesh.rigid_links.len(),
            new.mesh.rigid_links.len(),
            "{what}: links"
        );
        let dashpots = |m: &FeModel| {
            m.mesh
                .dashpots
                .iter()
                .map(|d| (d.node, bits(&d.damping)))
                .collect::<Vec<_>>()
        };
        assert_eq!(dashpots(&old), dashpots(&new), "{what}: dashpots");
        assert_eq!(entries(&old.damping), entries(&new.damping), "{what}: C");
        let (g_old, c_old) = old.floor_force_functional().unwrap();
        let (g_new, c_new) = new.floor_force_functional().unwrap();
        assert_eq!(bits(g_old), bits(g_new), "{what}: floor force (K part)");
        assert_eq!(bits(c_old), bits(c_new), "{what}: floor force (C part)");
        for (name, nodes) in &old.mesh.points {
            assert_eq!(
                Some(nodes),
                new.mesh.points.get(name),
                "{what}: point {name}"
            );
            assert_eq!(
                bits(&old.point_functional(name).unwrap()),
                bits(&new.point_functional(name).unwrap()),
                "{what}: point {name}"
            );
        }
        // The only named set the generator adds: the clamped feet (fixed columns).
        let extra: Vec<&String> = new
            .mesh
            .points
            .keys()
            .filter(|k| !old.mesh.points.contains_key(*k))
            .collect();
        let fixed = matches!(spec.support, Support::FixedColumns);
        assert_eq!(
            extra,
            if fixed {
                vec!["column_feet"]
            } else {
                Vec::<&str>::new()
            },
            "{what}"
        );
        // Modes.
        let opts = LanczosOptions {
            count: 12,
            ..LanczosOptions::default()
        };
        let mo = lowest_modes(old.stiffness.as_ref(), old.mass.as_ref(), &opts).unwrap();
        let mn = lowest_modes(new.stiffness.as_ref(), new.mass.as_ref(), &opts).unwrap();
        for i in 0..12 {
            let (a, b) = (mo.frequency_hz[i], mn.frequency_hz[i]);
            assert!(
                (a - b).abs() <= 1e-12 * a.abs().max(1e-300),
                "{what}: mode {} {a} vs {b} Hz",
                i + 1
            );
        }
        for name in old.mesh.points.keys() {
            let f = old.point_functional(name).unwrap();
            let psi = |s: &faer::Mat<f64>, i: usize| -> f64 {
                (0..f.len()).map(|j| f[j] * s[(j, i)]).sum()
            };
            let peak = (0..12)
                .map(|i| psi(&mo.shapes, i).abs())
                .fold(0.0, f64::max);
            for i in 0..12 {
                let (a, b) = (psi(&mo.shapes, i), psi(&mn.shapes, i));
                assert!(
                    (a - b).abs() <= 1e-12 * peak,
                    "{what}: psi_{}({name}) {a} vs {b}",
                    i + 1
                );
            }
        }
        eprintln!(
            "{what}: {} DOFs, K nnz {}, f1..3 = {:?} Hz",
            new.n_dofs(),
            entries(&new.stiffness).len(),
            &mn.frequency_hz[..3]
        );
    }
}

const COARSE: &str = "structure.fem.machine.elements_per_side=6";

/// The expanded file reads back to the generator's `GeneralSpec` (bit for bit) and, run as a
/// model, gives the machine file's modal model and simulation summary.
#[test]
fn expanded_model_runs_like_the_machine() {
    for (file, ov) in [
        ("paper-soft-base.toml", vec![]),
        ("paper-no-base.toml", vec![COARSE.to_string()]),
        ("paper-stiff-base.toml", vec![COARSE.to_string()]),
    ] {
        let path = example(file);
        let text = std::fs::read_to_string(&path).unwrap();
        let expanded = expand::expand_text(file, &text, &ov).unwrap();
        assert!(!expanded.contains("\n[structure.fem.machine]"), "{file}");
        assert!(expanded.contains("\n[structure.fem.model]\n"), "{file}");
        let machine = Model::from_file(&path, &ov).unwrap();
        let fem_spec = machine.spec.structure.fem.as_ref().unwrap();
        let generated =
            fem::machine_general(fem_spec.machine.as_ref().unwrap(), &machine.source).unwrap();
        let model = Model::from_text("expanded.toml", expanded.clone(), &[]).unwrap();
        let read_back = model.spec.structure.fem.as_ref().unwrap();
        assert!(read_back.machine.is_none());
        assert_eq!(
            read_back.model.as_ref(),
            Some(&generated),
            "{file}: GeneralSpec"
        );
        // Everything but the structure section is the file's.
        let mut a = machine.spec.clone();
        let mut b = model.spec.clone();
        a.structure.fem.as_mut().unwrap().machine = None;
        b.structure.fem.as_mut().unwrap().model = None;
        assert_eq!(a, b, "{file}: the rest of the model");
        assert_eq!(machine.structure, model.structure, "{file}: modal model");
        // The bed is labelled `part = "bed"` in the expansion: md/mb still knows m_b (the sum
        // of the plate's element masses against ρ L_x L_y t, to round-off).
        let (mb0, mb1) = (machine.bed_mass().unwrap(), model.bed_mass().unwrap());
        assert!(
            (mb1 / mb0 - 1.0).abs() < 1e-12,
            "{file}: m_b {mb1} vs {mb0} kg"
        );
        let run = |m: &Model| {
            simulate(
                &m.impact_system(Case::AsSpecified).unwrap(),
                &m.options(),
                false,
            )
            .unwrap()
            .summary
        };
        let (s0, s1) = (run(&machine), run(&model));
        assert_eq!(
            serde_json::to_string(&s0).unwrap(),
            serde_json::to_string(&s1).unwrap(),
            "{file}: summary"
        );
        eprintln!(
            "{file}: {} lines, {} modes kept, energy ratio {:?}",
            expanded.lines().count(),
            model.structure.len(),
            s1.energy_ratio
        );
    }
}

/// An edit of the expanded file is a user's model: doubling the bed's thickness adds exactly
/// the bed plate's mass ρ L_x L_y t to the FE model (closed form, 1e-12), and a bad edit is
/// refused at its field.
#[test]
fn expanded_model_can_be_edited() {
    let path = example("paper-stiff-base.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let expanded = expand::expand_text("x.toml", &text, &[COARSE.to_string()]).unwrap();
    let spec = meid::model::spec_from_text("x.toml", &expanded).unwrap();
    let g = spec.structure.fem.as_ref().unwrap().model.as_ref().unwrap();
    let t = g.shells[0].thickness;
    assert_eq!(t, 0.01095, "shells[0] is the bed");
    let thicker = expanded.replacen(
        &format!("thickness = {t}"),
        &format!("thickness = {}", 2.0 * t),
        1,
    );
    assert_ne!(thicker, expanded);
    let mass = |text: &str| -> f64 {
        let m = Model::from_text("x.toml", text.to_string(), &[]).unwrap();
        fem::build_model(m.spec.structure.fem.as_ref().unwrap(), &m.source)
            .unwrap()
            .mesh
            .total_mass_kg()
    };
    let added = mass(&thicker) - mass(&expanded);
    let bed = 7850.0 * 0.432 * 0.2693 * t;
    assert!((added / bed - 1.0).abs() < 1e-12, "{added} kg vs {bed} kg");
    // The bed mass of md/mb follows the edit: m_b is the labelled part's mass.
    let m_b = |text: &str| {
        Model::from_text("x.toml", text.to_string(), &[])
            .unwrap()
            .bed_mass()
    };
    let (b1, b2) = (m_b(&expanded).unwrap(), m_b(&thicker).unwrap());
    assert!((b1 / bed - 1.0).abs() < 1e-12, "m_b {b1} kg vs {bed} kg");
    assert!(
        (b2 / (2.0 * bed) - 1.0).abs() < 1e-12,
        "m_b {b2} kg vs {} kg",
        2.0 * bed
    );
    // Without the label, or with the contact point off the bed, the model cannot tell.
    assert_eq!(
        m_b(&expanded.replace("part = \"bed\"", "part = \"top\"")),
        None
    );
    assert_eq!(
        m_b(&expanded.replace("bed_contact = \"O_b\"", "bed_contact = \"O_f\"")),
        None
    );
    let bad = expanded.replacen(&format!("thickness = {t}"), "thickness = -1.0", 1);
    let e = Model::from_text("x.toml", bad, &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("structure.fem.model.shells[0].thickness"), "{e}");
    // Only a machine is expanded.
    let e = expand::expand_text("x.toml", &expanded, &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("no [structure.fem.machine]"), "{e}");
}

/// The structure cache works on an expanded model as on the machine file: a non-structural
/// field builds nothing, a structural one builds once and is then found.
#[test]
fn structure_cache_hits_on_an_expanded_model() {
    let path = example("paper-soft-base.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let expanded = expand::expand_text("x.toml", &text, &[COARSE.to_string()]).unwrap();
    let base = Model::from_text("x.toml", expanded.clone(), &[]).unwrap();
    let cache = StructureCache::new();
    let d = base
        .with_fields(&["damper.mass=4.0".to_string()], Some(&cache))
        .unwrap();
    assert_eq!(cache.builds(), 0);
    assert_eq!(d.structure, base.structure);
    let f = vec!["structure.fem.damping_ratios=0.02".to_string()];
    let a = base.with_fields(&f, Some(&cache)).unwrap();
    let mut f2 = f.clone();
    f2.push("damper.mass=4.0".into());
    let b = base.with_fields(&f2, Some(&cache)).unwrap();
    assert_eq!(
        cache.builds(),
        1,
        "the second point's structure is the cached one"
    );
    assert_eq!(a.structure, b.structure);
    let fresh = Model::from_text("x.toml", expanded, &f2).unwrap();
    assert_eq!(b.structure, fresh.structure);
    // The machine file with the same field gives the same structure.
    let m = Model::from_file(&path, &[COARSE.to_string(), f[0].clone()]).unwrap();
    assert_eq!(m.structure, a.structure);
}
