//! The three Gmsh formats meid reads (MSH 4.1 ASCII, 4.1 binary, 2.2 ASCII) give the same mesh,
//! and bad input in each is refused with its file, line or byte offset, entity and what is valid.
//!
//! Two sources: a plate written here in every format from one description (so the meshes must
//! be identical, bit for bit), and the same plate written by Gmsh 4.15.2 itself
//! (tests/data/gmsh/plate.py), whose ASCII coordinates carry 16 significant digits: there the
//! node positions agree to 1e-15 m and the frequencies to 1e-9, and mode 1 is checked against
//! Kirchhoff (simply supported square, a/h = 100, f = 2π²/(2π a²) √(D/(ρh)), 16×16, 1 %).

// Tests index nodes and modes by position, like the formulas they check.
#![allow(clippy::needless_range_loop)]

use std::fmt::Write;
use std::path::PathBuf;

use meid::structure::gmsh::{parse_msh, parse_msh_bytes, read_msh, GmshMesh};
use meid::structure::{Dof, FeModel, Material, Mesh};
use meid::Error;

/// An n×n plate of [0, 1]²: points, curves (1 bottom, 2 right, 3 top, 4 left), one surface.
struct Plate {
    n: usize,
}

impl Plate {
    fn node_tag(&self, i: usize, j: usize) -> usize {
        // Non-contiguous tags, as after a Gmsh renumbering with holes.
        10 + 2 * (j * (self.n + 1) + i)
    }
    fn xy(&self, i: usize, j: usize) -> [f64; 3] {
        // Irrational-looking coordinates: a format that rounds them would show.
        let h = 1.0 / self.n as f64;
        [i as f64 * h, (j as f64 * h).sqrt().powi(2), 0.0]
    }
    fn nodes(&self) -> Vec<(usize, [f64; 3])> {
        let n = self.n;
        (0..=n)
            .flat_map(|j| (0..=n).map(move |i| (i, j)))
            .map(|(i, j)| (self.node_tag(i, j), self.xy(i, j)))
            .collect()
    }
    /// Element blocks: (entity dim, entity tag, type, [(tag, node tags)]).
    #[allow(clippy::type_complexity)]
    fn blocks(&self) -> Vec<(i32, i32, i32, Vec<(usize, Vec<usize>)>)> {
        let n = self.n;
        let mut et = 1;
        let mut out = Vec::new();
        out.push((0, 1, 15, vec![(et, vec![self.node_tag(n / 2, n / 2)])]));
        et += 1;
        let edges: [Vec<(usize, usize)>; 4] = [
            (0..=n).map(|i| (i, 0)).collect(),
            (0..=n).map(|j| (n, j)).collect(),
            (0..=n).rev().map(|i| (i, n)).collect(),
            (0..=n).rev().map(|j| (0, j)).collect(),
        ];
        for (c, e) in edges.iter().enumerate() {
            let mut els = Vec::new();
            for w in e.windows(2) {
                els.push((
                    et,
                    vec![self.node_tag(w[0].0, w[0].1), self.node_tag(w[1].0, w[1].1)],
                ));
                et += 1;
            }
            out.push((1, c as i32 + 1, 1, els));
        }
        let mut els = Vec::new();
        for j in 0..n {
            for i in 0..n {
                els.push((
                    et,
                    vec![
                        self.node_tag(i, j),
                        self.node_tag(i + 1, j),
                        self.node_tag(i + 1, j + 1),
                        self.node_tag(i, j + 1),
                    ],
                ));
                et += 1;
            }
        }
        out.push((2, 1, 3, els));
        out
    }
    /// Physical tag of each entity: curves 2, 4 → 1 "x_edges"; 1, 3 → 2 "y_edges"; surface →
    /// 3 "plate"; point → 4 "centre".
    fn phys(dim: i32, tag: i32) -> i32 {
        match (dim, tag) {
            (0, _) => 4,
            (1, 2) | (1, 4) => 1,
            (1, _) => 2,
            _ => 3,
        }
    }
    const NAMES: &'static str =
        "$PhysicalNames\n4\n1 1 \"x_edges\"\n1 2 \"y_edges\"\n2 3 \"plate\"\n0 4 \"centre\"\n$EndPhysicalNames\n";
    fn counts(&self) -> (usize, usize, usize) {
        let b = self.blocks();
        let ne: usize = b.iter().map(|x| x.3.len()).sum();
        (b.len(), ne, (self.n + 1) * (self.n + 1))
    }

    fn ascii41(&self) -> String {
        let mut s = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
        s.push_str(Self::NAMES);
        s.push_str("$Entities\n1 4 1 0\n1 0.5 0.5 0 1 4\n");
        for c in 1..=4 {
            writeln!(s, "{c} 0 0 0 1 1 0 1 {} 2 1 -2", Self::phys(1, c)).unwrap();
        }
        s.push_str("1 0 0 0 1 1 0 1 3 4 1 2 3 4\n$EndEntities\n");
        let nodes = self.nodes();
        let (nb, ne, nn) = self.counts();
        let tmax = nodes.iter().map(|x| x.0).max().unwrap();
        writeln!(s, "$Nodes\n1 {nn} 10 {tmax}\n2 1 0 {nn}").unwrap();
        for (t, _) in &nodes {
            writeln!(s, "{t}").unwrap();
        }
        for (_, x) in &nodes {
            writeln!(s, "{} {} {}", x[0], x[1], x[2]).unwrap();
        }
        writeln!(s, "$EndNodes\n$Elements\n{nb} {ne} 1 {ne}").unwrap();
        for (d, e, ty, els) in self.blocks() {
            writeln!(s, "{d} {e} {ty} {}", els.len()).unwrap();
            for (t, conn) in els {
                let c: Vec<String> = conn.iter().map(|x| x.to_string()).collect();
                writeln!(s, "{t} {}", c.join(" ")).unwrap();
            }
        }
        s.push_str("$EndElements\n");
        s
    }

    /// MSH 4.1 binary with `size_t` of `st` bytes, little- or big-endian.
    fn binary41(&self, st: usize, big: bool) -> Vec<u8> {
        let mut b: Vec<u8> = Vec::new();
        let int = |b: &mut Vec<u8>, v: i32| {
            b.extend(if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            })
        };
        let size = |b: &mut Vec<u8>, v: usize| {
            let v = v as u64;
            let bytes = if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            };
            if big {
                b.extend(&bytes[8 - st..]);
            } else {
                b.extend(&bytes[..st]);
            }
        };
        let dbl = |b: &mut Vec<u8>, v: f64| {
            b.extend(if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            })
        };
        b.extend(format!("$MeshFormat\n4.1 1 {st}\n").as_bytes());
        int(&mut b, 1);
        b.extend(b"\n$EndMeshFormat\n");
        b.extend(Self::NAMES.as_bytes());
        b.extend(b"$Entities\n");
        for c in [1, 4, 1, 0] {
            size(&mut b, c);
        }
        int(&mut b, 1);
        for x in [0.5, 0.5, 0.0] {
            dbl(&mut b, x);
        }
        size(&mut b, 1);
        int(&mut b, 4);
        for (dim, tag, bound) in [
            (1, 1, vec![1, -2]),
            (1, 2, vec![1, -2]),
            (1, 3, vec![1, -2]),
            (1, 4, vec![1, -2]),
            (2, 1, vec![1, 2, 3, 4]),
        ] {
            int(&mut b, tag);
            for x in [0.0, 0.0, 0.0, 1.0, 1.0, 0.0] {
                dbl(&mut b, x);
            }
            size(&mut b, 1);
            int(&mut b, Self::phys(dim, tag));
            size(&mut b, bound.len());
            for t in bound {
                int(&mut b, t);
            }
        }
        b.extend(b"\n$EndEntities\n$Nodes\n");
        let nodes = self.nodes();
        let (nb, ne, nn) = self.counts();
        let tmax = nodes.iter().map(|x| x.0).max().unwrap();
        for v in [1, nn, 10, tmax] {
            size(&mut b, v);
        }
        for v in [2, 1, 0] {
            int(&mut b, v);
        }
        size(&mut b, nn);
        for (t, _) in &nodes {
            size(&mut b, *t);
        }
        for (_, x) in &nodes {
            for &c in x {
                dbl(&mut b, c);
            }
        }
        b.extend(b"\n$EndNodes\n$Elements\n");
        for v in [nb, ne, 1, ne] {
            size(&mut b, v);
        }
        for (d, e, ty, els) in self.blocks() {
            for v in [d, e, ty] {
                int(&mut b, v);
            }
            size(&mut b, els.len());
            for (t, conn) in els {
                size(&mut b, t);
                for c in conn {
                    size(&mut b, c);
                }
            }
        }
        b.extend(b"\n$EndElements\n");
        b
    }

    /// MSH 2.2 ASCII: `tag type 2 physical elementary nodes…`.
    fn ascii22(&self) -> String {
        let mut s = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n");
        s.push_str(Self::NAMES);
        let nodes = self.nodes();
        writeln!(s, "$Nodes\n{}", nodes.len()).unwrap();
        for (t, x) in &nodes {
            writeln!(s, "{t} {} {} {}", x[0], x[1], x[2]).unwrap();
        }
        let (_, ne, _) = self.counts();
        writeln!(s, "$EndNodes\n$Elements\n{ne}").unwrap();
        for (d, e, ty, els) in self.blocks() {
            for (t, conn) in els {
                let c: Vec<String> = conn.iter().map(|x| x.to_string()).collect();
                writeln!(s, "{t} {ty} 2 {} {e} {}", Self::phys(d, e), c.join(" ")).unwrap();
            }
        }
        s.push_str("$EndElements\n");
        s
    }
}

/// The mesh without the file positions of its quadrangles (lines in ASCII, bytes in binary).
fn content(mut g: GmshMesh) -> GmshMesh {
    g.quad_lines.clear();
    g
}

fn input_error(r: meid::Result<GmshMesh>) -> (String, String) {
    match r {
        Err(Error::Input { location, message }) => (location, message),
        Err(e) => panic!("expected an input error, got {e}"),
        Ok(_) => panic!("expected an input error, the mesh was read"),
    }
}

#[test]
fn the_three_formats_give_identical_meshes() {
    let p = Plate { n: 6 };
    let a41 = parse_msh(&p.ascii41(), "a41.msh").unwrap();
    assert_eq!(a41.quads.len(), 36);
    assert_eq!(a41.lines.len(), 24);
    assert_eq!(a41.node_sets["centre"].len(), 1);
    assert_eq!(a41.element_sets["plate"].len(), 36);
    assert_eq!(a41.line_sets["x_edges"].len(), 12);
    let a22 = parse_msh(&p.ascii22(), "a22.msh").unwrap();
    assert_eq!(content(a22), content(a41.clone()));
    for (st, big) in [(8, false), (8, true), (4, false), (4, true)] {
        let b = parse_msh_bytes(&p.binary41(st, big), "b41.msh").unwrap();
        assert_eq!(
            content(b.clone()),
            content(a41.clone()),
            "size_t {st}, big {big}"
        );
        // Binary positions are byte offsets: strictly increasing, inside the file.
        assert!(b.quad_lines.windows(2).all(|w| w[0] < w[1]));
    }
}

/// Every prefix of a binary file is refused with a message, never a panic; inside the binary
/// sections the message gives the byte offset and says the data end early.
#[test]
fn truncated_binary_is_refused_at_every_length() {
    let full = Plate { n: 2 }.binary41(8, false);
    let nodes_at = full.windows(7).position(|w| w == b"$Nodes\n").unwrap() + 7;
    for len in 0..full.len() - 1 {
        let r = parse_msh_bytes(&full[..len], "cut.msh");
        let (loc, msg) = input_error(r);
        assert!(loc.starts_with("cut.msh"), "{len}: {loc}");
        if len > nodes_at && len < nodes_at + 32 {
            assert!(
                msg.contains("end early") && loc.contains("(byte "),
                "{len}: {loc}: {msg}"
            );
        }
    }
    // A cut inside a header field: the offset of the field.
    let cut = nodes_at + 8 + 3;
    let (loc, msg) = input_error(parse_msh_bytes(&full[..cut], "cut.msh"));
    assert_eq!(loc, format!("cut.msh (byte {})", nodes_at + 8));
    assert!(
        msg.contains("the binary data of $Nodes end early: the number of nodes needs 8 bytes")
            && msg.contains(&format!("the file ends at byte {cut}")),
        "{msg}"
    );
    // A cut in the middle of the coordinates: refused from the header's count, before reading
    // or allocating for the nodes (9 nodes of 8 + 24 bytes; 96 bytes left after the header).
    let cut = nodes_at + 4 * 8 + 3 * 4 + 8 + 9 * 8 + 4;
    let (loc, msg) = input_error(parse_msh_bytes(&full[..cut], "cut.msh"));
    assert_eq!(loc, format!("cut.msh (byte {})", nodes_at + 8));
    assert!(
        msg.contains("$Nodes announces 9 nodes, which take at least 288 bytes, but only 96 bytes remain in the file"),
        "{msg}"
    );
}

/// A binary header announcing one element block too few: the data left over are refused at
/// the byte offset where the announced blocks end.
#[test]
fn binary_counts_disagreeing_with_the_data_are_refused() {
    let p = Plate { n: 2 };
    let good = p.binary41(8, false);
    let el = good.windows(10).position(|w| w == b"$Elements\n").unwrap() + 10;
    let (nb, ne, nn) = p.counts();
    // numEntityBlocks one too few.
    let mut bad = good.clone();
    bad[el..el + 8].copy_from_slice(&((nb - 1) as u64).to_le_bytes());
    let (loc, msg) = input_error(parse_msh_bytes(&bad, "b.msh"));
    assert!(loc.starts_with("b.msh (byte "), "{loc}");
    assert!(
        msg.contains(&format!("after the {} element blocks", nb - 1)),
        "{msg}"
    );
    // numElements one too many.
    let mut bad = good.clone();
    bad[el + 8..el + 16].copy_from_slice(&((ne + 1) as u64).to_le_bytes());
    let (loc, msg) = input_error(parse_msh_bytes(&bad, "b.msh"));
    assert_eq!(loc, format!("b.msh (byte {el})"));
    assert!(
        msg.contains(&format!(
            "$Elements announces {} elements but its {nb} blocks hold {ne}",
            ne + 1
        )),
        "{msg}"
    );
    // A block announcing more elements than the header's total.
    let mut bad = good.clone();
    let first_block_n = el + 32 + 12;
    bad[first_block_n..first_block_n + 8].copy_from_slice(&((ne + 5) as u64).to_le_bytes());
    let (loc, msg) = input_error(parse_msh_bytes(&bad, "b.msh"));
    assert_eq!(loc, format!("b.msh (byte {first_block_n})"));
    assert!(
        msg.contains(&format!(
            "holds {} elements, but $Elements announces {ne} in all",
            ne + 5
        )),
        "{msg}"
    );
    // numNodes one too many.
    let nd = good.windows(7).position(|w| w == b"$Nodes\n").unwrap() + 7;
    let mut bad = good.clone();
    bad[nd + 8..nd + 16].copy_from_slice(&((nn + 1) as u64).to_le_bytes());
    let (_, msg) = input_error(parse_msh_bytes(&bad, "b.msh"));
    assert!(
        msg.contains(&format!("$Nodes announces {} nodes", nn + 1)),
        "{msg}"
    );
}

/// Counts far beyond the file are refused before anything is allocated for them.
#[test]
fn counts_beyond_the_file_length_are_refused_before_allocation() {
    let p = Plate { n: 2 };
    let good = p.binary41(8, false);
    let nd = good.windows(7).position(|w| w == b"$Nodes\n").unwrap() + 7;
    let mut bad = good.clone();
    bad[nd + 8..nd + 16].copy_from_slice(&(1u64 << 40).to_le_bytes());
    let (loc, msg) = input_error(parse_msh_bytes(&bad, "b.msh"));
    assert_eq!(loc, format!("b.msh (byte {})", nd + 8));
    assert!(
        msg.contains("$Nodes announces 1099511627776 nodes, which take at least 35184372088832 bytes, but only"),
        "{msg}"
    );
    let text = p.ascii41();
    let bad = text.replace("$Elements\n6 13 1 13\n", "$Elements\n6 99999999999 1 13\n");
    assert_ne!(bad, text);
    let (_, msg) = input_error(parse_msh(&bad, "a.msh"));
    assert!(
        msg.contains("$Elements announces 99999999999 elements") && msg.contains("truncated"),
        "{msg}"
    );
    let bad = p
        .ascii22()
        .replace("$Nodes\n9\n", "$Nodes\n18446744073709551615\n");
    let (loc, msg) = input_error(parse_msh(&bad, "c.msh"));
    assert_eq!(loc, "c.msh:12:1");
    assert!(msg.contains("18446744073709551615 nodes"), "{msg}");
}

#[test]
fn binary_header_errors() {
    let good = Plate { n: 2 }.binary41(8, false);
    let with_header = |h: &[u8]| {
        let mut b = h.to_vec();
        b.extend(&good[b"$MeshFormat\n4.1 1 8\n".len()..]);
        b
    };
    let (loc, msg) = input_error(parse_msh_bytes(
        &with_header(b"$MeshFormat\n4.1 1 16\n"),
        "b.msh",
    ));
    assert_eq!(loc, "b.msh:2:7");
    assert!(
        msg.contains("data size 16 is not valid") && msg.contains("8 (what Gmsh writes) or 4"),
        "{msg}"
    );
    let (_, msg) = input_error(parse_msh_bytes(
        &with_header(b"$MeshFormat\n2.2 1 8\n"),
        "b.msh",
    ));
    assert!(msg.contains("binary MSH 2.2 is not supported"), "{msg}");
    let mut bad = good.clone();
    let at = b"$MeshFormat\n4.1 1 8\n".len();
    bad[at..at + 4].copy_from_slice(&[2, 0, 0, 0]);
    let (loc, msg) = input_error(parse_msh_bytes(&bad, "b.msh"));
    assert_eq!(loc, format!("b.msh (byte {at})"));
    assert!(
        msg.contains("byte-order check") && msg.contains("found 02 00 00 00"),
        "{msg}"
    );
    let (loc, msg) = input_error(parse_msh("$MeshFormat\n4.0 0 8\n$EndMeshFormat\n", "v.msh"));
    assert_eq!(loc, "v.msh:2:1");
    assert!(
        msg.contains("MSH version 4.0 is not supported") && msg.contains("2.2 (ASCII)"),
        "{msg}"
    );
}

/// Elements referencing missing nodes and duplicate node tags, in each format.
#[test]
fn missing_nodes_and_duplicate_node_tags_are_refused_in_every_format() {
    let p = Plate { n: 2 };
    // 2.2: element 18 (the last quad) refers to node 999.
    let a22 = p.ascii22();
    let last = a22
        .lines()
        .position(|l| l.starts_with("13 3 2 3 1 "))
        .unwrap();
    let bad = a22.replace("13 3 2 3 1 18 20 26 24", "13 3 2 3 1 18 20 999 24");
    assert_ne!(bad, a22);
    let (loc, msg) = input_error(parse_msh(&bad, "a22.msh"));
    assert_eq!(loc, format!("a22.msh:{}:18", last + 1));
    assert!(
        msg.contains("element 13 (in elementary entity 1 (physical group \"plate\")) refers to node '999', which is not in $Nodes"),
        "{msg}"
    );
    // 2.2: node tag 12 twice.
    let bad = a22.replace("\n14 1 0 0\n", "\n12 1 0 0\n");
    assert_ne!(bad, a22);
    let (loc, msg) = input_error(parse_msh(&bad, "a22.msh"));
    assert_eq!(loc, "a22.msh:15:1");
    assert!(msg.contains("node tag 12 appears twice ($Nodes)"), "{msg}");
    // 4.1 ASCII: node tag 12 twice.
    let a41 = p.ascii41();
    let bad = a41.replacen("\n14\n", "\n12\n", 1);
    let (loc, msg) = input_error(parse_msh(&bad, "a41.msh"));
    assert_eq!(loc, "a41.msh:25:1");
    assert!(
        msg.contains("node tag 12 appears twice (node block 1 of surface 1)"),
        "{msg}"
    );
    // 4.1 binary: node tag 12 twice, and an element referring to node 999.
    let good = p.binary41(8, false);
    let nd = good.windows(7).position(|w| w == b"$Nodes\n").unwrap() + 7;
    let tags_at = nd + 32 + 12 + 8;
    let mut bad = good.clone();
    bad[tags_at + 16..tags_at + 24].copy_from_slice(&12u64.to_le_bytes());
    let (loc, msg) = input_error(parse_msh_bytes(&bad, "b.msh"));
    assert_eq!(loc, format!("b.msh (byte {})", tags_at + 16));
    assert!(msg.contains("node tag 12 appears twice"), "{msg}");
    let mut bad = good.clone();
    let end = good.len() - b"\n$EndElements\n".len();
    bad[end - 8..end].copy_from_slice(&999u64.to_le_bytes());
    let (loc, msg) = input_error(parse_msh_bytes(&bad, "b.msh"));
    assert_eq!(loc, format!("b.msh (byte {})", end - 8));
    assert!(
        msg.contains("refers to node '999', which is not in $Nodes")
            && msg.contains("surface 1 (physical group \"plate\")"),
        "{msg}"
    );
}

/// An element type meid does not read inside a physical group is refused, naming the entity,
/// the group and the valid types.
#[test]
fn unsupported_element_types_name_their_group() {
    let p = Plate { n: 2 };
    // 4.1: the quadrangle block turned into 9-node quadrangles (type 10) of surface 1.
    let a41 = p.ascii41();
    let bad = a41.replace("2 1 3 4\n", "2 1 10 4\n");
    assert_ne!(bad, a41);
    let line = bad.lines().position(|l| l == "2 1 10 4").unwrap() + 1;
    let (loc, msg) = input_error(parse_msh(&bad, "a41.msh"));
    assert_eq!(loc, format!("a41.msh:{line}:5"));
    assert!(
        msg.contains("element type 10 (9-node quadrangle) in element block 6 of surface 1 (physical group \"plate\") is not supported")
            && msg.contains("meid reads types 1 (2-node line), 2 (3-node triangle), 3 (4-node quadrangle)"),
        "{msg}"
    );
    // 2.2: a 4-node tetrahedron in physical volume 3.
    let a22 = p.ascii22();
    let bad = a22.replace("13 3 2 3 1 ", "13 4 2 3 1 ");
    let (_, msg) = input_error(parse_msh(&bad, "a22.msh"));
    assert!(
        msg.contains("element type 4 (4-node tetrahedron) in elementary entity 1 (physical group \"physical3_3\") is not supported: meid reads shell (surface) meshes"),
        "{msg}"
    );
    // An unknown type number.
    let bad = a41.replace("2 1 3 4\n", "2 1 77 4\n");
    let (_, msg) = input_error(parse_msh(&bad, "a41.msh"));
    assert!(
        msg.contains("unsupported Gmsh element type 77 in element block 6 of surface 1"),
        "{msg}"
    );
}

fn gmsh_file(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/gmsh")
        .join(name)
}

/// Mode-1 frequency (Hz) of the plate, simply supported on its four edges (hard support).
fn ss_frequencies(g: &GmshMesh, h: f64) -> Vec<f64> {
    let mut mesh = Mesh::new();
    g.add_to_mesh(&mut mesh, Material::STEEL, h).unwrap();
    for nd in 0..mesh.nodes.len() {
        mesh.fix(nd, &[Dof::Ux, Dof::Uy, Dof::Rz]);
    }
    for nd in mesh.point("x_edges").unwrap().to_vec() {
        mesh.fix(nd, &[Dof::Uz, Dof::Rx]);
    }
    for nd in mesh.point("y_edges").unwrap().to_vec() {
        mesh.fix(nd, &[Dof::Uz, Dof::Ry]);
    }
    mesh.points.retain(|k, _| k == "centre");
    let model = FeModel::assemble(mesh).unwrap();
    let modes = model.solve_dense().unwrap();
    modes
        .omega_rad_per_s
        .iter()
        .take(4)
        .map(|w| w / (2.0 * std::f64::consts::PI))
        .collect()
}

/// The plate written by Gmsh 4.15.2 in the three formats: the same nodes (to 1e-15 m: the ASCII
/// files print 16 digits), quadrangles, physical groups and frequencies, mode 1 within 1 % of
/// Kirchhoff. In 2.2 each quadrangle is written twice (groups "plate" and "all"): the copies
/// become one element of both groups.
#[test]
fn gmsh_written_plate_reads_alike_in_the_three_formats() {
    let a41 = read_msh(gmsh_file("gmsh_plate_a41.msh")).unwrap();
    let b41 = read_msh(gmsh_file("gmsh_plate_b41.msh")).unwrap();
    let a22 = read_msh(gmsh_file("gmsh_plate_a22.msh")).unwrap();
    let n = 16;
    for g in [&a41, &b41, &a22] {
        assert_eq!(g.nodes.len(), (n + 1) * (n + 1));
        assert_eq!(g.quads.len(), n * n);
        assert_eq!(g.lines.len(), 4 * n);
        assert_eq!(g.element_sets["plate"], (0..n * n).collect::<Vec<_>>());
        assert_eq!(g.element_sets["all"], g.element_sets["plate"]);
        assert_eq!(g.node_sets["x_edges"].len(), 2 * (n + 1));
        assert_eq!(g.line_sets["y_edges"].len(), 2 * n);
        let c = g.node_sets["centre"][0];
        assert!((g.nodes[c][0] - 0.5).abs() < 1e-12 && (g.nodes[c][1] - 0.5).abs() < 1e-12);
    }
    for g in [&b41, &a22] {
        assert_eq!(g.node_tags, a41.node_tags);
        assert_eq!(g.quads, a41.quads);
        assert_eq!(g.lines, a41.lines);
        assert_eq!(g.node_sets, a41.node_sets);
        assert_eq!(g.line_sets, a41.line_sets);
        for (x, y) in g.nodes.iter().zip(&a41.nodes) {
            for k in 0..3 {
                assert!((x[k] - y[k]).abs() <= 1e-15, "{x:?} vs {y:?}");
            }
        }
    }
    // 4.1 numbers elements once; 2.2 gives each copy its own tag, the first copy's is kept.
    assert_eq!(b41.quad_tags, a41.quad_tags);
    assert_eq!(b41.line_tags, a41.line_tags);
    assert_eq!(a22.line_tags, a41.line_tags);
    assert!(a22.quad_tags.windows(2).all(|w| w[1] == w[0] + 2));

    let h: f64 = 0.01;
    let m = Material::STEEL;
    let d = m.youngs_modulus_pa * h.powi(3) / (12.0 * (1.0 - m.poisson_ratio.powi(2)));
    let exact = 2.0 * std::f64::consts::PI.powi(2) / (2.0 * std::f64::consts::PI)
        * (d / (m.density_kg_per_m3 * h)).sqrt();
    let fa = ss_frequencies(&a41, h);
    assert!((fa[0] / exact - 1.0).abs() < 0.01, "{} vs {exact}", fa[0]);
    for g in [&b41, &a22] {
        let f = ss_frequencies(g, h);
        for (x, y) in f.iter().zip(&fa) {
            assert!((x / y - 1.0).abs() < 1e-9, "{x} vs {y}");
        }
    }
}
