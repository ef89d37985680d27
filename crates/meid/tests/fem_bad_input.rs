//! Bad finite-element input (issue 13, "Bad input"): Gmsh files whose counts disagree with their
//! headers, elements referencing missing nodes, degenerate or inverted elements, and zero or
//! negative section properties are refused with the file, line, entity and valid range.
//!
//! Before: a `$Elements` section whose header announced one block too few was read up to that
//! count and the rest ignored, dropping half of a plate (floor force 36 N instead of 3,640 N).

use std::fmt::Write;

use meid::structure::gmsh::parse_msh;
use meid::Error;

/// A 2×1 quad mesh of [0, 2] × [0, 1] in two element blocks (one quad each) plus a point block.
fn good() -> String {
    let mut s = String::new();
    s.push_str("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    s.push_str("$PhysicalNames\n1\n2 1 \"plate\"\n$EndPhysicalNames\n");
    s.push_str("$Entities\n0 0 2 0\n1 0 0 0 1 1 0 1 1 0\n2 1 0 0 2 1 0 1 1 0\n$EndEntities\n");
    s.push_str("$Nodes\n1 6 1 6\n2 1 0 6\n1\n2\n3\n4\n5\n6\n");
    for (x, y) in [(0, 0), (1, 0), (2, 0), (0, 1), (1, 1), (2, 1)] {
        writeln!(s, "{x} {y} 0").unwrap();
    }
    s.push_str("$EndNodes\n");
    s.push_str("$Elements\n2 2 1 2\n2 1 3 1\n1 1 2 5 4\n2 2 3 1\n2 2 3 6 5\n$EndElements\n");
    s
}

fn input_error(text: &str) -> (String, String) {
    match parse_msh(text, "plate.msh") {
        Err(Error::Input { location, message }) => (location, message),
        other => panic!("expected an input error, got {other:?}"),
    }
}

#[test]
fn good_mesh_reads() {
    let m = parse_msh(&good(), "plate.msh").unwrap();
    assert_eq!(m.quads.len(), 2);
    assert_eq!(m.quad_lines, vec![32, 34]);
}

/// The header announces one element block but the section holds two: refused at the first
/// token past the announced data (line 33, the second block), not silently half a plate.
#[test]
fn one_block_too_few_in_the_header_is_refused() {
    let bad = good().replace("$Elements\n2 2 1 2\n", "$Elements\n1 1 1 1\n");
    let (loc, msg) = input_error(&bad);
    assert_eq!(loc, "plate.msh:33:1", "{msg}");
    assert!(msg.contains("after the 1 element blocks"), "{msg}");
}

#[test]
fn element_count_disagreeing_with_the_blocks_is_refused() {
    let bad = good().replace("$Elements\n2 2 1 2\n", "$Elements\n2 3 1 3\n");
    let (loc, msg) = input_error(&bad);
    assert_eq!(loc, "plate.msh:30:1");
    assert!(
        msg.contains("announces 3 elements but its 2 blocks hold 2"),
        "{msg}"
    );
}

#[test]
fn tag_range_disagreeing_with_the_data_is_refused() {
    let bad = good().replace("$Nodes\n1 6 1 6\n", "$Nodes\n1 6 1 7\n");
    let (_, msg) = input_error(&bad);
    assert!(
        msg.contains("node tags 1 to 7 but the data hold tags 1 to 6"),
        "{msg}"
    );
    let bad = good().replace("$Elements\n2 2 1 2\n", "$Elements\n2 2 0 2\n");
    let (_, msg) = input_error(&bad);
    assert!(msg.contains("element tags 0 to 2"), "{msg}");
}

#[test]
fn node_count_disagreeing_with_the_blocks_is_refused() {
    let bad = good().replace("$Nodes\n1 6 1 6\n", "$Nodes\n1 7 1 6\n");
    let (_, msg) = input_error(&bad);
    assert!(msg.contains("announces 7 nodes"), "{msg}");
}

#[test]
fn element_referencing_a_missing_node_is_refused() {
    let bad = good().replace("2 2 3 6 5\n", "2 2 3 9 5\n");
    let (loc, msg) = input_error(&bad);
    assert_eq!(loc, "plate.msh:34:7");
    assert!(msg.contains("refers to node '9'"), "{msg}");
}

#[test]
fn duplicate_element_tag_is_refused() {
    let bad = good().replace("2 2 3 6 5\n", "1 2 3 6 5\n");
    let (loc, msg) = input_error(&bad);
    assert_eq!(loc, "plate.msh:34:1");
    assert!(
        msg.contains("element tag 1 appears twice (first on line 32)"),
        "{msg}"
    );
}

/// A repeated node, a collapsed corner (three collinear nodes), a reflex corner and a
/// self-intersecting ("bow-tie") order are refused at the element's line with its tag and nodes.
#[test]
fn degenerate_and_inverted_quads_are_refused() {
    let bad = good().replace("2 2 3 6 5\n", "2 2 3 6 6\n");
    let (loc, msg) = input_error(&bad);
    assert_eq!(loc, "plate.msh:34:1");
    assert!(
        msg.contains("quadrangle 2 (nodes [2, 3, 6, 6]) is degenerate"),
        "{msg}"
    );
    // Node 6 moved to (1.5, 0.5), on the line from node 3 (2, 0) to node 5 (1, 1): corner 180°.
    let bad = good().replace("\n2 1 0\n", "\n1.5 0.5 0\n");
    let (loc, msg) = input_error(&bad);
    assert_eq!(loc, "plate.msh:34:1");
    assert!(
        msg.contains("quadrangle 2 (nodes [2, 3, 6, 5])") && msg.contains("collapsed corner"),
        "{msg}"
    );
    // Node 6 moved to (1.2, 0.2), inside the triangle of nodes 2, 3, 5: a reflex corner.
    let bad = good().replace("\n2 1 0\n", "\n1.2 0.2 0\n");
    let (loc, msg) = input_error(&bad);
    assert_eq!(loc, "plate.msh:34:1");
    assert!(
        msg.contains("quadrangle 2 (nodes [2, 3, 6, 5])") && msg.contains("inverted quad"),
        "{msg}"
    );
    // Nodes in crossing ("bow-tie") order: zero area.
    let bad = good().replace("2 2 3 6 5\n", "2 2 3 5 6\n");
    let (_, msg) = input_error(&bad);
    assert!(msg.contains("crossing diagonals"), "{msg}");
}

/// Zero or negative section and material properties in a model file are refused at their key.
#[test]
fn zero_or_negative_section_properties_are_refused() {
    let dir = std::env::temp_dir().join(format!("meid-bad-input-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("plate.msh"), good()).unwrap();
    let model = |mesh_extra: &str| {
        format!(
            r#"name = "bad"
[structure]
reference_mode = 1
[structure.fem]
select = [1]
count = 3
[structure.fem.mesh]
file = "plate.msh"
{mesh_extra}
points = {{ O_b = "plate", B = "plate" }}
fixed = ["plate"]
[points]
bed_contact = "O_b"
measurement = "B"
[slider]
mass = 1.0
velocity = 1.0
[contact.slider_bed]
law = "linear"
stiffness = 1.0e8
damping = 0.0
release = "force"
[simulation]
method = "exact"
duration = 0.02
sample_rate = 20000.0
"#
        )
    };
    for (extra, key, range) in [
        ("thickness = 0.0", "structure.fem.mesh.thickness", "> 0 m"),
        ("thickness = -0.01", "structure.fem.mesh.thickness", "> 0 m"),
        (
            "thickness = 0.01\nmaterial = { youngs_modulus = -2e11, poisson_ratio = 0.3, density = 7850.0 }",
            "structure.fem.mesh.material.youngs_modulus",
            "> 0 Pa",
        ),
        (
            "thickness = 0.01\nmaterial = { youngs_modulus = 2e11, poisson_ratio = 0.3, density = 0.0 }",
            "structure.fem.mesh.material.density",
            "> 0 kg/m³",
        ),
        (
            "thickness = 0.01\nmaterial = { youngs_modulus = 2e11, poisson_ratio = 0.5, density = 7850.0 }",
            "structure.fem.mesh.material.poisson_ratio",
            "(-1, 0.5)",
        ),
    ] {
        let path = dir.join("bad.toml");
        std::fs::write(&path, model(extra)).unwrap();
        let e = meid::model::Model::from_file(&path, &[]).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, Error::Input { .. }), "{msg}");
        assert!(msg.contains(key) && msg.contains(range), "{extra}: {msg}");
    }
}

/// A block announcing more elements than the section header's total is refused at the block's
/// count (before its elements are read), naming the block, its surface and physical group.
#[test]
fn block_count_beyond_the_header_total_is_refused() {
    let bad = good().replace(
        "$Elements\n2 2 1 2\n2 1 3 1\n",
        "$Elements\n2 2 1 2\n2 1 3 3\n",
    );
    let (loc, msg) = input_error(&bad);
    assert_eq!(loc, "plate.msh:31:7");
    assert!(
        msg.contains("element block 1 of surface 1 (physical group \"plate\") holds 3 elements, but $Elements announces 2 in all and the blocks before hold 0"),
        "{msg}"
    );
}

/// A header announcing far more nodes than the file can hold is refused before allocation.
#[test]
fn node_count_beyond_the_file_is_refused() {
    let bad = good().replace("$Nodes\n1 6 1 6\n", "$Nodes\n1 600000000000 1 6\n");
    let (loc, msg) = input_error(&bad);
    assert_eq!(loc, "plate.msh:14:3");
    assert!(
        msg.contains(
            "$Nodes announces 600000000000 nodes, which take at least 4800000000000 bytes"
        ),
        "{msg}"
    );
}

/// A model in mm-t-s units (the Euler-Bernoulli cantilever of `tests/data/eb_cantilever.toml`
/// with nodes in mm, E = 2.1e5 N/mm², ρ = 7.85e-9 t/mm³, A in mm², I in mm⁴) was accepted as SI:
/// the same frequencies (16.7103 Hz), but a bar of 3.1e-3 "kg" instead of 3.14 kg, effective
/// masses 0.002 "kg" and a tip flexibility of 0.119 "m/N" (L³/3EI = 1.19e-4 m/N in SI), silently
/// coupled to the slider's 0.1 kg. Now refused at the material, naming SI; so are E given in MPa
/// or GPa next to ρ in kg/m³ (wave speed sqrt(E/ρ) 5.2 or 0.16 m/s), in the general model, a
/// Gmsh mesh and the machine.
#[test]
fn materials_in_other_unit_systems_are_refused() {
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let si = std::fs::read_to_string(data.join("eb_cantilever.toml")).unwrap();
    let dir = std::env::temp_dir().join(format!("meid-units-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mm = si
        .replace("[1.0, 0.0, 0.0]", "[1000.0, 0.0, 0.0]")
        .replace("youngs_modulus = 2.1e11", "youngs_modulus = 2.1e5")
        .replace("density = 7850.0", "density = 7.85e-9")
        .replace(
            "area = 4.0e-4, iy = 1.3333333333333333e-8, iz = 1.3333333333333333e-8, j = 2.25e-8",
            "area = 400.0, iy = 13333.333333333334, iz = 13333.333333333334, j = 22500.0",
        );
    assert_ne!(mm, si);
    let mpa = si.replace("youngs_modulus = 2.1e11", "youngs_modulus = 2.1e5");
    let gpa = si.replace("youngs_modulus = 2.1e11", "youngs_modulus = 210.0");
    let path = dir.join("m.toml");
    for (text, key, what) in [
        (&mm, "structure.fem.model.material.density", "7.85e-9 kg/m³"),
        (
            &mpa,
            "structure.fem.model.material.youngs_modulus",
            "5.1722e0 m/s",
        ),
        (
            &gpa,
            "structure.fem.model.material.youngs_modulus",
            "1.6356e-1 m/s",
        ),
    ] {
        std::fs::write(&path, text).unwrap();
        let e = meid::model::Model::from_file(&path, &[]).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, Error::Input { .. }), "{msg}");
        assert!(
            msg.contains(key) && msg.contains(what) && msg.contains("SI units"),
            "{msg}"
        );
    }
    // The SI file still reads.
    std::fs::write(&path, &si).unwrap();
    meid::model::Model::from_file(&path, &[]).unwrap();
    // The machine's materials, through --set.
    let soft = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/paper-soft-base.toml");
    for (set, key) in [
        (
            "structure.fem.machine.column_material={ youngs_modulus = 2.06e5, poisson_ratio = 0.3, density = 7.85e-9 }",
            "structure.fem.machine.column_material.density",
        ),
        (
            "structure.fem.machine.bed.material={ youngs_modulus = 2.06e5, poisson_ratio = 0.3, density = 7850.0 }",
            "structure.fem.machine.bed.material.youngs_modulus",
        ),
    ] {
        let e = meid::model::Model::from_file(&soft, &[set.to_string()]).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, Error::Input { .. }), "{msg}");
        assert!(msg.contains(key) && msg.contains("SI units"), "{set}: {msg}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A 4 × 2 quad plate 0.4 × 0.2 m (MSH 2.2), clamped on x = 0 (group "x0"), "tip" the node at
/// (0.4, 0.1) m, whose middle column of nodes (x = 0.2 m, tags 3, 8, 13) is duplicated when
/// `crack`: the right half's quads use nodes 16, 17, 18, copies of them (a mesh of two surfaces
/// Gmsh did not fuse). Point groups "p3", "p8", "p13", "p16", "p17", "p18" name those nodes.
fn plate_msh(crack: bool) -> String {
    let (nx, ny) = (4usize, 2usize);
    let tag = |i: usize, j: usize| j * (nx + 1) + i + 1;
    let dup = |j: usize| (nx + 1) * (ny + 1) + j + 1;
    let mut s = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n9\n");
    s.push_str("1 1 \"x0\"\n2 2 \"plate\"\n0 3 \"tip\"\n");
    let named = [3usize, 8, 13, 16, 17, 18];
    for (k, t) in named.iter().enumerate() {
        writeln!(s, "0 {} \"p{t}\"", 4 + k).unwrap();
    }
    s.push_str("$EndPhysicalNames\n");
    let n = (nx + 1) * (ny + 1) + ny + 1;
    writeln!(s, "$Nodes\n{n}").unwrap();
    for j in 0..=ny {
        for i in 0..=nx {
            writeln!(s, "{} {} {} 0", tag(i, j), i as f64 * 0.1, j as f64 * 0.1).unwrap();
        }
    }
    for j in 0..=ny {
        // Uncut: the copies are placed off the plate (and used by no element).
        let y = j as f64 * 0.1;
        let z = if crack { 0.0 } else { 1.0 };
        writeln!(s, "{} 0.2 {y} {z}", dup(j)).unwrap();
    }
    s.push_str("$EndNodes\n");
    let mut els = Vec::new();
    for j in 0..ny {
        els.push(format!("1 2 1 1 {} {}", tag(0, j), tag(0, j + 1)));
    }
    els.push(format!("15 2 3 3 {}", tag(nx, 1)));
    if crack {
        for (k, t) in named.iter().enumerate() {
            els.push(format!("15 2 {} {} {t}", 4 + k, 4 + k));
        }
    }
    for j in 0..ny {
        for i in 0..nx {
            // The right half (i >= 2) takes the copies of the x = 0.2 m nodes.
            let c = |ii: usize, jj: usize| {
                if crack && i >= 2 && ii == 2 {
                    dup(jj)
                } else {
                    tag(ii, jj)
                }
            };
            els.push(format!(
                "3 2 2 2 {} {} {} {}",
                c(i, j),
                c(i + 1, j),
                c(i + 1, j + 1),
                c(i, j + 1)
            ));
        }
    }
    writeln!(s, "$Elements\n{}", els.len()).unwrap();
    for (k, e) in els.iter().enumerate() {
        writeln!(s, "{} {e}", k + 1).unwrap();
    }
    s.push_str("$EndElements\n");
    s
}

/// The impact part of the plate models below: O_b and B at the plate's "tip".
const PLATE_TAIL: &str = r#"points = { O_b = "tip", B = "tip" }
[points]
bed_contact = "O_b"
measurement = "B"
[slider]
mass = 0.1
velocity = 0.1
[contact.slider_bed]
law = "linear"
stiffness = 1.0e6
damping = 0.0
release = "force"
[simulation]
method = "exact"
duration = 0.02
sample_rate = 20000.0
"#;

const PLATE_HEAD: &str =
    "name = \"plate\"\n[structure]\nreference_mode = 1\n[structure.fem]\nselect = [1]\ncount = 4\n";

/// A model of the Gmsh plate `file` ([`plate_msh`]) as `[structure.fem.model]` shells of
/// thickness `t` (m), clamped on "x0", with `extra` lines in the table.
fn plate_model_general(file: &str, t: f64, extra: &str) -> String {
    format!("{PLATE_HEAD}[structure.fem.model]\nmesh = \"{file}\"\nshells = [{{ set = \"plate\", thickness = {t:?} }}]\nconstraints = [{{ set = \"x0\", dofs = [\"all\"] }}]\n{extra}{PLATE_TAIL}")
}

/// The same plate as `[structure.fem.mesh]`.
fn plate_model_mesh(file: &str, t: f64) -> String {
    format!("{PLATE_HEAD}[structure.fem.mesh]\nfile = \"{file}\"\nthickness = {t:?}\nfixed = [\"x0\"]\n{PLATE_TAIL}")
}

/// Duplicate nodes cut a Gmsh plate in two. Before: read without a word; the clamped plate had
/// six 0 Hz modes (its right half floating), `meid modes` exited 0 with a truncation table of
/// G_PP = 3.983e-8 m/N, modal "-0.000000e0", share "-0.000 %". Now refused in both the general
/// model and `[structure.fem.mesh]`, naming the file, both Gmsh node tags and the point; joined
/// by rigid links (a cut that is meant) it reads, and so does the uncut plate.
#[test]
fn coincident_unjoined_nodes_are_refused() {
    let dir = std::env::temp_dir().join(format!("meid-coincident-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("crack.msh"), plate_msh(true)).unwrap();
    std::fs::write(dir.join("plate.msh"), plate_msh(false)).unwrap();
    let general = |file: &str, extra: &str| plate_model_general(file, 0.01, extra);
    let mesh = |file: &str| plate_model_mesh(file, 0.01);
    let path = dir.join("m.toml");
    for (text, key) in [
        (general("crack.msh", ""), "structure.fem.model.mesh"),
        (mesh("crack.msh"), "structure.fem.mesh.file"),
    ] {
        std::fs::write(&path, &text).unwrap();
        let e = meid::model::Model::from_file(&path, &[]).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, Error::Input { .. }), "{msg}");
        assert!(
            msg.contains(key)
                && msg.contains("node 3 of crack.msh and node 16 of crack.msh")
                && msg.contains("[0.2, 0, 0] m (3 such pair(s)"),
            "{msg}"
        );
    }
    let joined = "rigid_links = [{ master = \"p3\", slaves = \"p16\" }, { master = \"p8\", slaves = \"p17\" }, { master = \"p13\", slaves = \"p18\" }]\n";
    for text in [
        general("plate.msh", ""),
        mesh("plate.msh"),
        general("crack.msh", joined),
    ] {
        std::fs::write(&path, &text).unwrap();
        meid::model::Model::from_file(&path, &[]).unwrap();
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A frame section given in mm² and mm⁴ next to lengths in m (the 1 m cantilever of
/// `tests/data/eb_cantilever.toml` with `area = 400, iy = iz = 13333.3`): before, accepted as a
/// 400 m² bar (radius of gyration 5.77 m on a 1 m member) with 16.7103 Hz; now refused at
/// `frames[0]`, naming L/r and the SI units. The SI section reads.
#[test]
fn a_frame_shorter_than_its_radius_of_gyration_is_refused() {
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let si = std::fs::read_to_string(data.join("eb_cantilever.toml")).unwrap();
    let mm = si.replace(
        "area = 4.0e-4, iy = 1.3333333333333333e-8, iz = 1.3333333333333333e-8, j = 2.25e-8",
        "area = 400.0, iy = 13333.333333333334, iz = 13333.333333333334, j = 22500.0",
    );
    assert_ne!(mm, si);
    let dir = std::env::temp_dir().join(format!("meid-slender-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("m.toml");
    std::fs::write(&path, &mm).unwrap();
    let e = meid::model::Model::from_file(&path, &[]).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, Error::Input { .. }), "{msg}");
    assert!(
        msg.contains("structure.fem.model.frames[0]") && msg.contains("L/r = 1.732e-1"),
        "{msg}"
    );
    std::fs::write(&path, &si).unwrap();
    meid::model::Model::from_file(&path, &[]).unwrap();
    std::fs::remove_dir_all(&dir).ok();
}

/// A shell thickness in mm next to coordinates in m: before, `thickness = 10` (10 mm meant) on
/// the 0.4 × 0.2 m plate was read as a 10 m thick plate, 2.2e5 times stiffer in bending, and
/// the machine's bed with `thickness = 20` likewise; now refused at the thickness, naming t/L
/// and the unit. Covered: `[structure.fem.model]` shells, `[structure.fem.mesh]` and the
/// machine's plates. 0.2 (half the plate's 0.447 m diagonal, a block rather than a shell, but
/// below the limit) still reads.
#[test]
fn a_shell_thicker_than_half_its_surface_is_refused() {
    let dir = std::env::temp_dir().join(format!("meid-thick-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("plate.msh"), plate_msh(false)).unwrap();
    let general = |t: f64| plate_model_general("plate.msh", t, "");
    let mesh = |t: f64| plate_model_mesh("plate.msh", t);
    let path = dir.join("m.toml");
    for (text, key) in [
        (general(10.0), "structure.fem.model.shells[0].thickness"),
        (mesh(10.0), "structure.fem.mesh.thickness"),
    ] {
        std::fs::write(&path, &text).unwrap();
        let e = meid::model::Model::from_file(&path, &[]).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, Error::Input { .. }), "{msg}");
        assert!(
            msg.contains(key) && msg.contains("t/L = 22.361") && msg.contains("20 mm is 0.02"),
            "{msg}"
        );
    }
    for text in [general(0.2), mesh(0.2), general(0.01)] {
        std::fs::write(&path, &text).unwrap();
        meid::model::Model::from_file(&path, &[]).unwrap();
    }
    let soft = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/paper-soft-base.toml");
    let e = meid::model::Model::from_file(
        &soft,
        &["structure.fem.machine.bed.thickness=20".to_string()],
    )
    .unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, Error::Input { .. }), "{msg}");
    assert!(
        msg.contains("structure.fem.machine.bed.thickness") && msg.contains("t/L = 39.288"),
        "{msg}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
