//! Reader for Gmsh `.msh` version 4.1 ASCII shell meshes (quadrangles and triangles).
//!
//! Format: Gmsh reference manual, section "MSH file format" (version 4.1). Read sections:
//! `$MeshFormat` (must be `4.1 0 <size>`), `$PhysicalNames`, `$Entities` (which physical groups
//! each point/curve/surface belongs to), `$Nodes` (entity blocks: tags, then coordinates, plus
//! parametric coordinates when flagged) and `$Elements` (entity blocks of one element type).
//! Other sections are skipped. Element types: 3 (4-node quadrangle) becomes a MITC4 shell, 2
//! (3-node triangle) a CST + DKT shell ([`super::tri3`]); 1 (2-node line) a frame in a general
//! model; 15 (point) and 8 (3-node line) only feed named node sets; any other surface or volume
//! element is an error. Physical groups become named node sets (all nodes of the group's
//! elements) and, for surfaces, named element sets (quadrangles and triangles separately).
//! Degenerate elements are refused, and so are triangles of one surface entity whose node order
//! runs against a neighbour's or that fold back onto it ([`super::tri3::check_orientation`]).
//! Errors carry `file:line:column`.
//!
//! Hand-written because the Rust `mshio` crate is not in the workspace and the subset needed is
//! small; the reader checks what meid needs (e.g. quads only) with positions in its messages.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use super::material::Material;
use super::mesh::Mesh;
use super::shell::ShellElement;
use super::tri3::TriShellElement;
use crate::{Error, Result};

/// A shell/frame mesh read from a `.msh` file. Indices are 0-based positions in the vectors.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GmshMesh {
    /// Node coordinates (file units, meant to be m).
    pub nodes: Vec<[f64; 3]>,
    /// Gmsh tag of each node.
    pub node_tags: Vec<usize>,
    /// Quadrilaterals as node indices.
    pub quads: Vec<[usize; 4]>,
    /// Gmsh tag of each quadrilateral.
    pub quad_tags: Vec<usize>,
    /// Line of the file each quadrilateral is on (1-based).
    pub quad_lines: Vec<usize>,
    /// Physical group name → node indices (sorted, unique).
    pub node_sets: BTreeMap<String, Vec<usize>>,
    /// Physical surface name → quad indices.
    pub element_sets: BTreeMap<String, Vec<usize>>,
    /// 3-node triangles (type 2) as node indices.
    pub triangles: Vec<[usize; 3]>,
    /// Gmsh tag of each triangle.
    pub triangle_tags: Vec<usize>,
    /// Line of the file each triangle is on (1-based).
    pub triangle_lines: Vec<usize>,
    /// Physical surface name → triangle indices.
    pub triangle_sets: BTreeMap<String, Vec<usize>>,
    /// 2-node lines (type 1) as node indices: frame elements in a general model.
    pub lines: Vec<[usize; 2]>,
    /// Gmsh tag of each line.
    pub line_tags: Vec<usize>,
    /// Physical curve name → line indices.
    pub line_sets: BTreeMap<String, Vec<usize>>,
}

#[derive(Clone, Copy)]
struct Tok<'a> {
    text: &'a str,
    line: usize,
    col: usize,
}

struct Section<'a> {
    name: &'a str,
    start_line: usize,
    lines: Vec<(usize, &'a str)>,
}

struct Cursor<'a, 'f> {
    file: &'f str,
    toks: Vec<Tok<'a>>,
    pos: usize,
    end_line: usize,
    section: &'a str,
}

fn input_err(file: &str, line: usize, col: usize, msg: impl Into<String>) -> Error {
    Error::Input {
        location: format!("{file}:{line}:{col}"),
        message: msg.into(),
    }
}

fn tokenize<'a>(lines: &[(usize, &'a str)]) -> Vec<Tok<'a>> {
    let mut out = Vec::new();
    for &(ln, text) in lines {
        let mut start = None;
        for (i, ch) in text.char_indices() {
            if ch.is_whitespace() {
                if let Some(s) = start.take() {
                    out.push(Tok {
                        text: &text[s..i],
                        line: ln,
                        col: s + 1,
                    });
                }
            } else if start.is_none() {
                start = Some(i);
            }
        }
        if let Some(s) = start {
            out.push(Tok {
                text: &text[s..],
                line: ln,
                col: s + 1,
            });
        }
    }
    out
}

impl<'a> Cursor<'a, '_> {
    /// Refuses data left after what the section's header announced.
    fn finish(&self, announced: &str) -> Result<()> {
        match self.toks.get(self.pos) {
            None => Ok(()),
            Some(t) => Err(input_err(
                self.file,
                t.line,
                t.col,
                format!(
                    "${} holds more data ('{}') after the {announced} its header announces: the header's counts disagree with the data (a block or entity missing from the count?)",
                    self.section, t.text
                ),
            )),
        }
    }
    fn next(&mut self, what: &str) -> Result<Tok<'a>> {
        let t = self.toks.get(self.pos).copied().ok_or_else(|| {
            input_err(
                self.file,
                self.end_line,
                1,
                format!("${} ends early: expected {what}", self.section),
            )
        })?;
        self.pos += 1;
        Ok(t)
    }
    fn int(&mut self, what: &str) -> Result<i64> {
        let t = self.next(what)?;
        t.text.parse::<i64>().map_err(|_| {
            input_err(
                self.file,
                t.line,
                t.col,
                format!("expected an integer ({what}), found '{}'", t.text),
            )
        })
    }
    fn count(&mut self, what: &str) -> Result<usize> {
        let t = self.next(what)?;
        t.text.parse::<usize>().map_err(|_| {
            input_err(
                self.file,
                t.line,
                t.col,
                format!(
                    "expected a non-negative integer ({what}), found '{}'",
                    t.text
                ),
            )
        })
    }
    fn real(&mut self, what: &str) -> Result<f64> {
        let t = self.next(what)?;
        match t.text.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(input_err(
                self.file,
                t.line,
                t.col,
                format!("expected a finite number ({what}), found '{}'", t.text),
            )),
        }
    }
}

/// Nodes per element for the Gmsh element types meid recognises, with a name and dimension.
fn element_info(ty: i64) -> Option<(usize, usize, &'static str)> {
    Some(match ty {
        1 => (2, 1, "2-node line"),
        2 => (3, 2, "3-node triangle"),
        3 => (4, 2, "4-node quadrangle"),
        4 => (4, 3, "4-node tetrahedron"),
        5 => (8, 3, "8-node hexahedron"),
        6 => (6, 3, "6-node prism"),
        7 => (5, 3, "5-node pyramid"),
        8 => (3, 1, "3-node line"),
        9 => (6, 2, "6-node triangle"),
        10 => (9, 2, "9-node quadrangle"),
        11 => (10, 3, "10-node tetrahedron"),
        15 => (1, 0, "point"),
        16 => (8, 2, "8-node quadrangle"),
        17 => (20, 3, "20-node hexahedron"),
        _ => return None,
    })
}

/// Reads a `.msh` 4.1 ASCII file.
pub fn read_msh(path: impl AsRef<Path>) -> Result<GmshMesh> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_msh(&text, &path.display().to_string())
}

fn cursor<'a, 'f>(s: &Section<'a>, file: &'f str) -> Cursor<'a, 'f> {
    Cursor {
        file,
        toks: tokenize(&s.lines),
        pos: 0,
        end_line: s.lines.last().map(|l| l.0 + 1).unwrap_or(s.start_line + 1),
        section: s.name,
    }
}

/// Parses the text of a `.msh` 4.1 ASCII file; `file` names it in error locations.
pub fn parse_msh(text: &str, file: &str) -> Result<GmshMesh> {
    // Split into sections.
    let mut sections: Vec<Section> = Vec::new();
    let mut current: Option<Section> = None;
    for (i, raw) in text.lines().enumerate() {
        let ln = i + 1;
        let t = raw.trim();
        if let Some(name) = t.strip_prefix('$') {
            if let Some(end) = name.strip_prefix("End") {
                match current.take() {
                    Some(s) if s.name == end => sections.push(s),
                    Some(s) => {
                        return Err(input_err(
                            file,
                            ln,
                            1,
                            format!(
                                "found ${name} inside ${} (opened at line {})",
                                s.name, s.start_line
                            ),
                        ))
                    }
                    None => {
                        return Err(input_err(
                            file,
                            ln,
                            1,
                            format!("${name} without a matching ${end}"),
                        ))
                    }
                }
            } else {
                if let Some(s) = &current {
                    return Err(input_err(
                        file,
                        ln,
                        1,
                        format!(
                            "${name} starts before ${} (opened at line {}) ended",
                            s.name, s.start_line
                        ),
                    ));
                }
                current = Some(Section {
                    name,
                    start_line: ln,
                    lines: Vec::new(),
                });
            }
        } else if let Some(s) = &mut current {
            s.lines.push((ln, raw));
        } else if !t.is_empty() {
            return Err(input_err(
                file,
                ln,
                1,
                format!("text outside any $Section: '{t}'"),
            ));
        }
    }
    if let Some(s) = current {
        return Err(input_err(
            file,
            s.start_line,
            1,
            format!("${} is never closed by $End{}", s.name, s.name),
        ));
    }
    let find = |name: &str| sections.iter().find(|s| s.name == name);

    // $MeshFormat
    let fmt = find("MeshFormat")
        .ok_or_else(|| input_err(file, 1, 1, "no $MeshFormat section: not a Gmsh .msh file"))?;
    let mut c = cursor(fmt, file);
    let v = c.next("version")?;
    if v.text != "4.1" {
        return Err(input_err(
            file,
            v.line,
            v.col,
            format!("MSH version {} is not supported; export as version 4.1 ASCII (Mesh.MshFileVersion = 4.1)", v.text),
        ));
    }
    let ft = c.next("file type")?;
    if ft.text != "0" {
        return Err(input_err(
            file,
            ft.line,
            ft.col,
            "binary .msh is not supported; export as ASCII (Mesh.Binary = 0)",
        ));
    }

    // $PhysicalNames: dim tag "name"
    let mut phys_names: HashMap<(i64, i64), String> = HashMap::new();
    if let Some(s) = find("PhysicalNames") {
        let mut lines = s.lines.iter().filter(|l| !l.1.trim().is_empty());
        let (ln, first) = lines.next().copied().unwrap_or((s.start_line + 1, ""));
        let n: usize = first.trim().parse().map_err(|_| {
            input_err(
                file,
                ln,
                1,
                format!(
                    "expected the number of physical names, found '{}'",
                    first.trim()
                ),
            )
        })?;
        for _ in 0..n {
            let (ln, l) = lines.next().copied().ok_or_else(|| {
                input_err(
                    file,
                    s.start_line,
                    1,
                    format!("$PhysicalNames announces {n} names but has fewer"),
                )
            })?;
            let mut parts = l.trim().splitn(3, char::is_whitespace);
            let dim = parts.next().and_then(|x| x.parse::<i64>().ok());
            let tag = parts.next().and_then(|x| x.parse::<i64>().ok());
            let name = parts.next().map(|x| x.trim());
            match (dim, tag, name) {
                (Some(d), Some(t), Some(nm))
                    if nm.len() >= 2 && nm.starts_with('"') && nm.ends_with('"') =>
                {
                    phys_names.insert((d, t), nm[1..nm.len() - 1].to_string());
                }
                _ => {
                    return Err(input_err(
                        file,
                        ln,
                        1,
                        format!("expected 'dimension tag \"name\"', found '{}'", l.trim()),
                    ))
                }
            }
        }
    }
    let group_name = |dim: i64, tag: i64| -> String {
        phys_names
            .get(&(dim, tag))
            .cloned()
            .unwrap_or_else(|| format!("physical{dim}_{tag}"))
    };

    // $Entities: (dim, tag) → physical tags
    let mut entity_groups: HashMap<(i64, i64), Vec<i64>> = HashMap::new();
    if let Some(s) = find("Entities") {
        let mut c = cursor(s, file);
        let counts = [
            c.count("number of points")?,
            c.count("number of curves")?,
            c.count("number of surfaces")?,
            c.count("number of volumes")?,
        ];
        for (dim, &n) in counts.iter().enumerate() {
            for _ in 0..n {
                let tag = c.int("entity tag")?;
                let nbox = if dim == 0 { 3 } else { 6 };
                for _ in 0..nbox {
                    c.real("entity bounding box")?;
                }
                let np = c.count("number of physical tags")?;
                let mut tags = Vec::new();
                for _ in 0..np {
                    tags.push(c.int("physical tag")?);
                }
                if dim > 0 {
                    let nb = c.count("number of bounding entities")?;
                    for _ in 0..nb {
                        c.int("bounding entity tag")?;
                    }
                }
                entity_groups.insert((dim as i64, tag), tags);
            }
        }
    }

    // $Nodes
    let nodes_sec = find("Nodes").ok_or_else(|| input_err(file, 1, 1, "no $Nodes section"))?;
    let mut c = cursor(nodes_sec, file);
    let nblocks = c.count("number of node blocks")?;
    let total = c.count("number of nodes")?;
    let min_tag = c.count("minimum node tag")?;
    let max_tag = c.count("maximum node tag")?;
    let mut mesh = GmshMesh::default();
    let mut index_of_tag: HashMap<usize, usize> = HashMap::new();
    for _ in 0..nblocks {
        let dim = c.int("entity dimension")?;
        c.int("entity tag")?;
        let parametric = c.int("parametric flag")?;
        let n = c.count("number of nodes in block")?;
        let mut tags = Vec::new();
        for _ in 0..n {
            let t = c.next("node tag")?;
            let tag: usize = t.text.parse().map_err(|_| {
                input_err(
                    file,
                    t.line,
                    t.col,
                    format!("expected a node tag, found '{}'", t.text),
                )
            })?;
            if index_of_tag
                .insert(tag, mesh.nodes.len() + tags.len())
                .is_some()
            {
                return Err(input_err(
                    file,
                    t.line,
                    t.col,
                    format!("node tag {tag} appears twice"),
                ));
            }
            tags.push(tag);
        }
        let extra = if parametric != 0 {
            dim.clamp(0, 3) as usize
        } else {
            0
        };
        for &tag in &tags {
            let x = [c.real("x")?, c.real("y")?, c.real("z")?];
            for _ in 0..extra {
                c.real("parametric coordinate")?;
            }
            mesh.nodes.push(x);
            mesh.node_tags.push(tag);
        }
    }
    c.finish(&format!("{nblocks} node blocks"))?;
    if mesh.nodes.len() != total {
        return Err(input_err(
            file,
            nodes_sec.start_line + 1,
            1,
            format!(
                "$Nodes announces {total} nodes but its {nblocks} blocks hold {}",
                mesh.nodes.len()
            ),
        ));
    }
    check_tag_range(
        file,
        nodes_sec.start_line + 1,
        "node",
        &mesh.node_tags,
        min_tag,
        max_tag,
    )?;

    // $Elements
    let el_sec = find("Elements").ok_or_else(|| input_err(file, 1, 1, "no $Elements section"))?;
    let mut c = cursor(el_sec, file);
    let nblocks = c.count("number of element blocks")?;
    let total_el = c.count("number of elements")?;
    let min_el = c.count("minimum element tag")?;
    let max_el = c.count("maximum element tag")?;
    let mut sets: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    let mut all_tags: Vec<usize> = Vec::with_capacity(total_el.min(1 << 24));
    let mut seen_tags: HashMap<usize, usize> = HashMap::new();
    let mut tri_entity: Vec<(i64, i64)> = Vec::new();
    for _ in 0..nblocks {
        let dim = c.int("entity dimension")?;
        let etag = c.int("entity tag")?;
        let tt = c.next("element type")?;
        let ty: i64 = tt.text.parse().map_err(|_| {
            input_err(
                file,
                tt.line,
                tt.col,
                format!("expected an element type, found '{}'", tt.text),
            )
        })?;
        let n = c.count("number of elements in block")?;
        let (nn, edim, ename) = element_info(ty).ok_or_else(|| {
            input_err(
                file,
                tt.line,
                tt.col,
                format!(
                    "unsupported Gmsh element type {ty}; meid reads 4-node quadrangles (type 3), 3-node triangles (type 2) and 2-node lines (type 1)"
                ),
            )
        })?;
        if edim >= 2 && ty != 3 && ty != 2 {
            let hint = if edim == 2 {
                "mesh the surfaces with first-order elements (Mesh.ElementOrder = 1): 4-node quadrangles or 3-node triangles"
            } else {
                "meid reads shell (surface) meshes, not volume meshes"
            };
            return Err(input_err(
                file,
                tt.line,
                tt.col,
                format!("element type {ty} ({ename}) is not supported: {hint}"),
            ));
        }
        let groups: Vec<String> = entity_groups
            .get(&(dim, etag))
            .map(|v| v.iter().map(|&p| group_name(dim, p)).collect())
            .unwrap_or_default();
        for _ in 0..n {
            let tag_tok = c.next("element tag")?;
            let tag: usize = tag_tok.text.parse().map_err(|_| {
                input_err(
                    file,
                    tag_tok.line,
                    tag_tok.col,
                    format!("expected an element tag, found '{}'", tag_tok.text),
                )
            })?;
            if let Some(prev) = seen_tags.insert(tag, tag_tok.line) {
                return Err(input_err(
                    file,
                    tag_tok.line,
                    tag_tok.col,
                    format!("element tag {tag} appears twice (first on line {prev})"),
                ));
            }
            all_tags.push(tag);
            let mut conn = Vec::with_capacity(nn);
            for _ in 0..nn {
                let t = c.next("element node tag")?;
                let idx = t
                    .text
                    .parse::<usize>()
                    .ok()
                    .and_then(|nt| index_of_tag.get(&nt).copied())
                    .ok_or_else(|| {
                        input_err(
                            file,
                            t.line,
                            t.col,
                            format!(
                                "element {tag} refers to node '{}', which is not in $Nodes",
                                t.text
                            ),
                        )
                    })?;
                conn.push(idx);
            }
            for g in &groups {
                sets.entry(g.clone())
                    .or_default()
                    .extend(conn.iter().copied());
            }
            if ty == 1 {
                if conn[0] == conn[1] {
                    return Err(input_err(
                        file,
                        tag_tok.line,
                        1,
                        format!(
                            "line {tag} is degenerate: both ends are node {}",
                            mesh.node_tags[conn[0]]
                        ),
                    ));
                }
                for g in &groups {
                    if dim == 1 {
                        mesh.line_sets
                            .entry(g.clone())
                            .or_default()
                            .push(mesh.lines.len());
                    }
                }
                mesh.lines.push([conn[0], conn[1]]);
                mesh.line_tags.push(tag);
            }
            if ty == 2 {
                for g in &groups {
                    if dim == 2 {
                        mesh.triangle_sets
                            .entry(g.clone())
                            .or_default()
                            .push(mesh.triangles.len());
                    }
                }
                mesh.triangles.push([conn[0], conn[1], conn[2]]);
                mesh.triangle_tags.push(tag);
                mesh.triangle_lines.push(tag_tok.line);
                tri_entity.push((dim, etag));
            }
            if ty == 3 {
                let q = [conn[0], conn[1], conn[2], conn[3]];
                for g in &groups {
                    if dim == 2 {
                        mesh.element_sets
                            .entry(g.clone())
                            .or_default()
                            .push(mesh.quads.len());
                    }
                }
                mesh.quads.push(q);
                mesh.quad_tags.push(tag);
                mesh.quad_lines.push(tag_tok.line);
            }
        }
    }
    c.finish(&format!("{nblocks} element blocks"))?;
    if all_tags.len() != total_el {
        return Err(input_err(
            file,
            el_sec.start_line + 1,
            1,
            format!(
                "$Elements announces {total_el} elements but its {nblocks} blocks hold {}: the file is truncated or its header is wrong",
                all_tags.len()
            ),
        ));
    }
    check_tag_range(
        file,
        el_sec.start_line + 1,
        "element",
        &all_tags,
        min_el,
        max_el,
    )?;
    // Element geometry: four distinct nodes, a non-degenerate, convex, not self-intersecting quad.
    for (q, (&tag, &line)) in mesh
        .quads
        .iter()
        .zip(mesh.quad_tags.iter().zip(&mesh.quad_lines))
    {
        let mut distinct = q.to_vec();
        distinct.sort_unstable();
        distinct.dedup();
        let tags = q.map(|i| mesh.node_tags[i]);
        if distinct.len() < 4 {
            return Err(input_err(
                file,
                line,
                1,
                format!("quadrangle {tag} (nodes {tags:?}) is degenerate: a node is repeated; a quadrangle needs four distinct nodes"),
            ));
        }
        super::shell::shell_geometry(&q.map(|i| mesh.nodes[i])).map_err(|e| {
            let msg = match e {
                Error::InvalidValue { message, .. } => message,
                other => other.to_string(),
            };
            input_err(
                file,
                line,
                1,
                format!("quadrangle {tag} (nodes {tags:?}): {msg}"),
            )
        })?;
    }
    check_triangles(file, &mesh, &tri_entity)?;
    for (name, mut v) in sets {
        v.sort_unstable();
        v.dedup();
        mesh.node_sets.insert(name, v);
    }
    if mesh.quads.is_empty() && mesh.triangles.is_empty() && mesh.lines.is_empty() {
        return Err(input_err(
            file,
            el_sec.start_line,
            1,
            "the mesh has no 4-node quadrangles (element type 3), 3-node triangles (type 2) or 2-node lines (type 1)",
        ));
    }
    Ok(mesh)
}

/// Triangles: three distinct nodes, a nonzero area, and, within one surface entity, a node
/// order consistent with the neighbours' and no fold back onto a neighbour.
fn check_triangles(file: &str, mesh: &GmshMesh, entity: &[(i64, i64)]) -> Result<()> {
    let describe = |t: usize| {
        format!(
            "triangle {} (nodes {:?})",
            mesh.triangle_tags[t],
            mesh.triangles[t].map(|i| mesh.node_tags[i])
        )
    };
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let line = mesh.triangle_lines[t];
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
            return Err(input_err(
                file,
                line,
                1,
                format!(
                    "{} is degenerate: a node is repeated; a triangle needs three distinct nodes",
                    describe(t)
                ),
            ));
        }
        super::tri3::tri_geometry(&tri.map(|i| mesh.nodes[i])).map_err(|e| {
            let msg = match e {
                Error::InvalidValue { message, .. } => message,
                other => other.to_string(),
            };
            input_err(file, line, 1, format!("{}: {msg}", describe(t)))
        })?;
    }
    let mut by_entity: BTreeMap<(i64, i64), Vec<usize>> = BTreeMap::new();
    for (t, e) in entity.iter().enumerate() {
        by_entity.entry(*e).or_default().push(t);
    }
    for ((_, etag), ids) in by_entity {
        let polys: Vec<&[usize]> = ids.iter().map(|&t| &mesh.triangles[t][..]).collect();
        if let Some(f) = super::tri3::check_orientation(&polys, &mesh.nodes) {
            let (a, b) = (ids[f.elements[0]], ids[f.elements[1]]);
            let edge = f.edge.map(|i| mesh.node_tags[i]);
            let why = if f.same_direction {
                "runs their shared edge in the same direction: it is inverted (order its nodes like its neighbours')"
            } else {
                "is folded back onto it (normals more than 154 degrees apart): it is inverted"
            };
            return Err(input_err(
                file,
                mesh.triangle_lines[b],
                1,
                format!(
                    "{} of surface {etag} {why}; neighbour {} across nodes {edge:?}",
                    describe(b),
                    describe(a)
                ),
            ));
        }
    }
    Ok(())
}

/// The header's minimum and maximum tags must be those of the data.
fn check_tag_range(
    file: &str,
    line: usize,
    what: &str,
    tags: &[usize],
    min: usize,
    max: usize,
) -> Result<()> {
    let (lo, hi) = tags
        .iter()
        .fold((usize::MAX, 0), |(a, b), &t| (a.min(t), b.max(t)));
    if !tags.is_empty() && (lo != min || hi != max) {
        return Err(input_err(
            file,
            line,
            1,
            format!("the header announces {what} tags {min} to {max} but the data hold tags {lo} to {hi}: the header's counts disagree with the data"),
        ));
    }
    Ok(())
}

impl GmshMesh {
    /// Adds the quads and triangles to `mesh` as shell elements of one material and thickness.
    /// Only nodes used by a shell are added; node sets become named points and element sets become element sets
    /// (with the new indices). Returns, for each node of this mesh, its index in `mesh` (if added).
    pub fn add_to_mesh(
        &self,
        mesh: &mut Mesh,
        material: Material,
        thickness_m: f64,
    ) -> Result<Vec<Option<usize>>> {
        let mut map: Vec<Option<usize>> = vec![None; self.nodes.len()];
        let first_shell = mesh.shells.len();
        for q in &self.quads {
            let mut nodes = [0usize; 4];
            for (k, &i) in q.iter().enumerate() {
                let idx = match map[i] {
                    Some(x) => x,
                    None => {
                        let x = mesh.add_node(self.nodes[i]);
                        map[i] = Some(x);
                        x
                    }
                };
                nodes[k] = idx;
            }
            mesh.add_shell(ShellElement::new(nodes, material, thickness_m));
        }
        let first_tri = mesh.triangles.len();
        for t in &self.triangles {
            let nodes = t.map(|i| *map[i].get_or_insert_with(|| mesh.add_node(self.nodes[i])));
            mesh.add_triangle(TriShellElement::new(nodes, material, thickness_m));
        }
        for (name, set) in &self.node_sets {
            let mut v = Vec::with_capacity(set.len());
            for &i in set {
                match map[i] {
                    Some(x) => v.push(x),
                    None => {
                        return Err(Error::invalid(
                            format!("physical group {name}"),
                            format!(
                                "contains node tag {} at {:?}, which belongs to no quadrangle or triangle; put the group's points on the meshed surface",
                                self.node_tags[i], self.nodes[i]
                            ),
                        ))
                    }
                }
            }
            mesh.name_point(name.clone(), v);
        }
        for (name, set) in &self.element_sets {
            mesh.element_sets
                .insert(name.clone(), set.iter().map(|&e| first_shell + e).collect());
        }
        for (name, set) in &self.triangle_sets {
            mesh.triangle_sets
                .insert(name.clone(), set.iter().map(|&e| first_tri + e).collect());
        }
        Ok(map)
    }
}
