//! Reader for Gmsh `.msh` shell and frame meshes: MSH 4.1 ASCII, MSH 4.1 binary and MSH 2.2
//! ASCII. All three give the same [`GmshMesh`].
//!
//! Format: Gmsh reference manual, section "MSH file format" (version 4.1; version 2.2 in the
//! "Legacy formats" appendix). Read sections: `$MeshFormat`, `$PhysicalNames` (ASCII in every
//! format), `$Entities` (4.1: which physical groups each point/curve/surface/volume belongs to),
//! `$Nodes` and `$Elements`. Other sections are skipped.
//!
//! - 4.1 (`4.1 0 8`, ASCII; `4.1 1 8`, binary): nodes and elements come in entity blocks; an
//!   element's physical groups are those of its block's entity. In binary files an `int` is 4
//!   bytes, a `double` 8 and a `size_t` `data-size` bytes (4 or 8; Gmsh writes 8); the header line
//!   is followed by the `int` 1, which gives the byte order (little- and big-endian files are
//!   both read). `$Entities`, `$Nodes` and `$Elements` are binary, `$PhysicalNames` stays ASCII.
//! - 2.2 (`2.2 0 8`): `$Nodes` is `tag x y z` per node; `$Elements` is
//!   `tag type number-of-tags physical elementary [partitions…] node-tags…` per element. Gmsh
//!   writes an element once per physical group it belongs to, each copy with a new tag: copies
//!   (same type, elementary entity and nodes) are merged into one element of several groups,
//!   keeping the first copy's tag.
//!
//! Element types are dispatched in one place, [`element_kind`]: 3 (4-node quadrangle) becomes a
//! MITC4 shell, 2 (3-node triangle) a CST + DKT shell ([`super::tri3`]); 1 (2-node line) a frame; 15 (point) and 8 (3-node line) only feed named node sets. Any
//! other type is refused, naming its entity and physical groups. Physical groups become named
//! node sets (all nodes of the group's elements), surface groups named element sets and curve
//! groups named line sets. Degenerate elements are refused, and so are triangles of one surface
//! entity whose node order runs against a neighbour's or that fold back onto it
//! ([`super::tri3::check_orientation`]).
//!
//! Every count is checked against the data (blocks, nodes and elements announced by a header,
//! per-block counts, tag ranges), elements must reference nodes of `$Nodes`, node and element
//! tags must be unique. A count is checked against the bytes left in the file before anything is
//! allocated for it. Errors carry `file:line:column` in ASCII files and `file (byte N)` in
//! binary ones.
//!
//! Hand-written rather than the `mshio` crate: mshio 0.4.2 (its last release, June 2020) reads
//! MSH 4.1 only and refuses 2.2 files, skips `$PhysicalNames` (group names are how a model file
//! refers to a mesh) and, by its own documentation, does not check the mesh for consistency (an
//! element may refer to a missing node); its errors point into the input buffer, not to a line.

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
    /// Where each quadrilateral is in the file: its line (1-based) in an ASCII file, the byte
    /// offset of its tag in a binary one.
    pub quad_lines: Vec<usize>,
    /// Physical group name → node indices (sorted, unique).
    pub node_sets: BTreeMap<String, Vec<usize>>,
    /// Physical surface name → quad indices (sorted, unique).
    pub element_sets: BTreeMap<String, Vec<usize>>,
    /// 3-node triangles (type 2) as node indices.
    pub triangles: Vec<[usize; 3]>,
    /// Gmsh tag of each triangle.
    pub triangle_tags: Vec<usize>,
    /// Where each triangle is in the file (as `quad_lines`).
    pub triangle_lines: Vec<usize>,
    /// Physical surface name → triangle indices (sorted, unique).
    pub triangle_sets: BTreeMap<String, Vec<usize>>,
    /// 2-node lines (type 1) as node indices: frame elements in a general model.
    pub lines: Vec<[usize; 2]>,
    /// Gmsh tag of each line.
    pub line_tags: Vec<usize>,
    /// Physical curve name → line indices (sorted, unique).
    pub line_sets: BTreeMap<String, Vec<usize>>,
}

/// What meid makes of a Gmsh element type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// 4-node quadrangle: a shell element.
    Quad4,
    /// 3-node triangle: a shell element.
    Tri3,
    /// 2-node line: a frame element.
    Line2,
    /// Only its nodes are used (named node sets).
    NodesOnly,
    /// Refused; the text says what to do instead.
    Unsupported(&'static str),
}

/// The one place Gmsh element types are dispatched: (nodes per element, dimension, name, kind)
/// of each type meid recognises; `None` for a type it does not know.
fn element_kind(ty: i64) -> Option<(usize, usize, &'static str, Kind)> {
    const SURF: &str =
        "mesh the surfaces with first-order elements (Mesh.ElementOrder = 1): 4-node quadrangles or 3-node triangles";
    const VOL: &str = "meid reads shell (surface) meshes, not volume meshes";
    Some(match ty {
        1 => (2, 1, "2-node line", Kind::Line2),
        2 => (3, 2, "3-node triangle", Kind::Tri3),
        3 => (4, 2, "4-node quadrangle", Kind::Quad4),
        4 => (4, 3, "4-node tetrahedron", Kind::Unsupported(VOL)),
        5 => (8, 3, "8-node hexahedron", Kind::Unsupported(VOL)),
        6 => (6, 3, "6-node prism", Kind::Unsupported(VOL)),
        7 => (5, 3, "5-node pyramid", Kind::Unsupported(VOL)),
        8 => (3, 1, "3-node line", Kind::NodesOnly),
        9 => (6, 2, "6-node triangle", Kind::Unsupported(SURF)),
        10 => (9, 2, "9-node quadrangle", Kind::Unsupported(SURF)),
        11 => (10, 3, "10-node tetrahedron", Kind::Unsupported(VOL)),
        15 => (1, 0, "point", Kind::NodesOnly),
        16 => (8, 2, "8-node quadrangle", Kind::Unsupported(SURF)),
        17 => (20, 3, "20-node hexahedron", Kind::Unsupported(VOL)),
        _ => return None,
    })
}

/// The element types meid reads, for messages.
const VALID_TYPES: &str =
    "1 (2-node line), 2 (3-node triangle), 3 (4-node quadrangle), 8 (3-node line, nodes only), 15 (point, nodes only)";

/// Where something is in a `.msh` file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Loc {
    /// Line and column (1-based) in an ASCII file.
    Text { line: usize, col: usize },
    /// Byte offset in a binary file.
    Byte(usize),
}

impl Loc {
    fn at(self, file: &str) -> String {
        match self {
            Loc::Text { line, col } => format!("{file}:{line}:{col}"),
            Loc::Byte(b) => format!("{file} (byte {b})"),
        }
    }
    /// "on line N" / "at byte N", for "first …" remarks.
    fn phrase(self) -> String {
        match self {
            Loc::Text { line, .. } => format!("on line {line}"),
            Loc::Byte(b) => format!("at byte {b}"),
        }
    }
    fn line_or_byte(self) -> usize {
        match self {
            Loc::Text { line, .. } => line,
            Loc::Byte(b) => b,
        }
    }
}

/// Binary number layout of a 4.1 binary file.
#[derive(Debug, Clone, Copy)]
struct Bin {
    size_t: usize,
    big_endian: bool,
}

/// A cursor over the bytes of a `.msh` file: ASCII tokens, or binary numbers inside the binary
/// sections of a binary file.
struct Lex<'a> {
    data: &'a [u8],
    file: &'a str,
    pos: usize,
    line: usize,
    line_start: usize,
    /// The file is binary: locations are byte offsets.
    binary_file: bool,
    /// Numbers are read in binary (inside `$Entities`, `$Nodes`, `$Elements` of a binary file).
    bin: Option<Bin>,
    /// The section being read and where it opened, for messages.
    section: String,
    section_loc: Loc,
}

fn lossy(b: &[u8]) -> String {
    // At most 4 bytes per character: enough bytes for the clipped text and its `…`.
    let keep = b.len().min(4 * crate::input::CLIP_CHARS + 4);
    let s = String::from_utf8_lossy(&b[..keep]);
    let c = crate::input::clip(&s);
    if keep < b.len() && !c.ends_with('…') {
        format!("{c}…")
    } else {
        c
    }
}

impl<'a> Lex<'a> {
    fn new(data: &'a [u8], file: &'a str) -> Self {
        Lex {
            data,
            file,
            pos: 0,
            line: 1,
            line_start: 0,
            binary_file: false,
            bin: None,
            section: String::new(),
            section_loc: Loc::Text { line: 1, col: 1 },
        }
    }
    fn loc(&self) -> Loc {
        if self.binary_file {
            Loc::Byte(self.pos)
        } else {
            Loc::Text {
                line: self.line,
                col: self.pos - self.line_start + 1,
            }
        }
    }
    fn err(&self, loc: Loc, msg: impl Into<String>) -> Error {
        Error::Input {
            location: loc.at(self.file),
            message: msg.into(),
        }
    }
    fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }
    fn skip_ws(&mut self) {
        while let Some(&c) = self.data.get(self.pos) {
            if !c.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
            if c == b'\n' {
                self.line += 1;
                self.line_start = self.pos;
            }
        }
    }
    /// Skips spaces and tabs, not line ends.
    fn skip_ws_inline(&mut self) {
        while self
            .data
            .get(self.pos)
            .is_some_and(|&c| c == b' ' || c == b'\t' || c == b'\r')
        {
            self.pos += 1;
        }
    }
    /// The next whitespace-separated token, or `None` at the end of the file.
    fn token(&mut self) -> Option<(&'a [u8], Loc)> {
        self.skip_ws();
        if self.pos >= self.data.len() {
            return None;
        }
        let loc = self.loc();
        let start = self.pos;
        while self
            .data
            .get(self.pos)
            .is_some_and(|c| !c.is_ascii_whitespace())
        {
            self.pos += 1;
        }
        Some((&self.data[start..self.pos], loc))
    }
    /// The rest of the current line (without its end), and moves past the line end.
    fn rest_of_line(&mut self) -> &'a [u8] {
        let start = self.pos;
        while self.data.get(self.pos).is_some_and(|&c| c != b'\n') {
            self.pos += 1;
        }
        let s = &self.data[start..self.pos];
        if self.pos < self.data.len() {
            self.pos += 1;
            self.line += 1;
            self.line_start = self.pos;
        }
        s
    }
    /// An ASCII token of the section's data; a `$` line or the end of the file is an error.
    fn data_token(&mut self, what: &str) -> Result<(&'a [u8], Loc)> {
        match self.token() {
            None => Err(self.err(
                self.loc(),
                format!(
                    "the file ends inside ${} (opened {}): expected {what}",
                    self.section,
                    self.section_loc.phrase()
                ),
            )),
            Some((t, loc)) if t.starts_with(b"$") => Err(self.err(
                loc,
                format!(
                    "${} ends ('{}') before {what}: its data hold less than its header's counts announce",
                    self.section,
                    lossy(t)
                ),
            )),
            Some(x) => Ok(x),
        }
    }
    /// `n` raw bytes of binary data.
    fn bytes(&mut self, n: usize, what: &str) -> Result<(&'a [u8], Loc)> {
        let loc = Loc::Byte(self.pos);
        if self.remaining() < n {
            return Err(self.err(
                loc,
                format!(
                    "the binary data of ${} end early: {what} needs {n} bytes but the file ends at byte {} (truncated file?)",
                    self.section,
                    self.data.len()
                ),
            ));
        }
        let b = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok((b, loc))
    }
    fn bin_uint(&mut self, bin: Bin, width: usize, what: &str) -> Result<(u64, Loc)> {
        let (b, loc) = self.bytes(width, what)?;
        let mut v: u64 = 0;
        for k in 0..width {
            let byte = if bin.big_endian {
                b[k]
            } else {
                b[width - 1 - k]
            };
            v = (v << 8) | u64::from(byte);
        }
        Ok((v, loc))
    }
    /// A Gmsh `int` (4 bytes in binary).
    fn int(&mut self, what: &str) -> Result<(i64, Loc)> {
        if let Some(bin) = self.bin {
            let (v, loc) = self.bin_uint(bin, 4, what)?;
            return Ok((i64::from(v as u32 as i32), loc));
        }
        let (t, loc) = self.data_token(what)?;
        match std::str::from_utf8(t)
            .ok()
            .and_then(|s| s.parse::<i64>().ok())
        {
            Some(v) => Ok((v, loc)),
            None => Err(self.err(
                loc,
                format!("expected an integer ({what}), found '{}'", lossy(t)),
            )),
        }
    }
    /// A Gmsh `size_t` (`data-size` bytes in binary): a count or a tag.
    fn size(&mut self, what: &str) -> Result<(usize, Loc)> {
        if let Some(bin) = self.bin {
            let (v, loc) = self.bin_uint(bin, bin.size_t, what)?;
            return usize::try_from(v).map(|v| (v, loc)).map_err(|_| {
                self.err(
                    loc,
                    format!("{what} {v} does not fit this machine's memory"),
                )
            });
        }
        let (t, loc) = self.data_token(what)?;
        match std::str::from_utf8(t)
            .ok()
            .and_then(|s| s.parse::<usize>().ok())
        {
            Some(v) => Ok((v, loc)),
            None => Err(self.err(
                loc,
                format!(
                    "expected a non-negative integer ({what}), found '{}'",
                    lossy(t)
                ),
            )),
        }
    }
    /// A node tag in an element: as [`Lex::size`], but an unreadable tag is reported as a
    /// missing node by the caller (`None`).
    fn node_ref(&mut self, what: &str) -> Result<(Option<usize>, String, Loc)> {
        if let Some(bin) = self.bin {
            let (v, loc) = self.bin_uint(bin, bin.size_t, what)?;
            return Ok((usize::try_from(v).ok(), v.to_string(), loc));
        }
        let (t, loc) = self.data_token(what)?;
        let v = std::str::from_utf8(t)
            .ok()
            .and_then(|s| s.parse::<usize>().ok());
        Ok((v, lossy(t), loc))
    }
    /// A Gmsh `double` (8 bytes in binary), finite.
    fn real(&mut self, what: &str) -> Result<f64> {
        if let Some(bin) = self.bin {
            let (v, loc) = self.bin_uint(bin, 8, what)?;
            let x = f64::from_bits(v);
            if !x.is_finite() {
                return Err(self.err(loc, format!("{what} is not a finite number ({x})")));
            }
            return Ok(x);
        }
        let (t, loc) = self.data_token(what)?;
        match std::str::from_utf8(t)
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
        {
            Some(v) if v.is_finite() => Ok(v),
            _ => Err(self.err(
                loc,
                format!("expected a finite number ({what}), found '{}'", lossy(t)),
            )),
        }
    }
    /// Smallest number of bytes one item of `tokens` ASCII numbers (each at least one digit
    /// and one separator) or of the given binary width takes.
    fn min_bytes(&self, tokens: usize, binary_width: usize) -> usize {
        match self.bin {
            Some(_) => binary_width,
            None => 2 * tokens,
        }
    }
    /// Refuses a count whose items cannot fit in the bytes left in the file (before anything
    /// is allocated for them).
    fn check_fits(&self, loc: Loc, count: usize, item_bytes: usize, what: &str) -> Result<()> {
        let need = count.saturating_mul(item_bytes);
        if need > self.remaining() {
            return Err(self.err(
                loc,
                format!(
                    "${} announces {count} {what}, which take at least {need} bytes, but only {} bytes remain in the file: the count is wrong or the file is truncated",
                    self.section,
                    self.remaining()
                ),
            ));
        }
        Ok(())
    }
    /// Opens a section: reads the `$Name` line. `None` at the end of the file.
    fn open_section(&mut self) -> Result<Option<String>> {
        self.skip_ws();
        if self.pos >= self.data.len() {
            return Ok(None);
        }
        let loc = self.loc();
        let line = self.rest_of_line();
        let text = String::from_utf8_lossy(line).trim().to_string();
        let Some(name) = text.strip_prefix('$') else {
            return Err(self.err(loc, format!("text outside any $Section: '{}'", lossy(line))));
        };
        if let Some(end) = name.strip_prefix("End") {
            return Err(self.err(loc, format!("${name} without a matching ${end}")));
        }
        self.section = name.to_string();
        self.section_loc = loc;
        Ok(Some(name.to_string()))
    }
    /// Closes the current section: after its data (which the header's counts delimit) must
    /// come `$EndName` and nothing else.
    fn close_section(&mut self, announced: &str) -> Result<()> {
        self.bin = None;
        let name = self.section.clone();
        let opened = self.section_loc.phrase();
        let end = format!("$End{name}");
        match self.token() {
            None => Err(self.err(
                self.loc(),
                format!("${name} (opened {opened}) is never closed by {end}"),
            )),
            Some((t, _)) if t == end.as_bytes() => {
                self.rest_of_line();
                Ok(())
            }
            Some((t, loc)) if t.starts_with(b"$End") => Err(self.err(
                loc,
                format!("found {} inside ${name} (opened {opened})", lossy(t)),
            )),
            Some((t, loc)) if t.starts_with(b"$") => Err(self.err(
                loc,
                format!("{} starts before ${name} (opened {opened}) ended", lossy(t)),
            )),
            Some((t, loc)) => Err(self.err(
                loc,
                format!(
                    "${name} holds more data ('{}') after the {announced} its header announces: the header's counts disagree with the data (a block or entity missing from the count?)",
                    lossy(t)
                ),
            )),
        }
    }
    /// Skips a section meid does not read, up to its `$EndName`.
    fn skip_section(&mut self) -> Result<()> {
        let name = self.section.clone();
        let end = format!("$End{name}");
        if self.binary_file {
            // Binary data may hold any byte: look for the end marker at a line start.
            let pat = format!("\n{end}");
            let hay = &self.data[self.pos..];
            let found = hay
                .windows(pat.len())
                .position(|w| w == pat.as_bytes())
                .map(|i| i + 1)
                .or_else(|| hay.starts_with(end.as_bytes()).then_some(0));
            return match found {
                Some(i) => {
                    self.pos += i;
                    self.rest_of_line();
                    Ok(())
                }
                None => Err(self.err(
                    self.section_loc,
                    format!("${name} is never closed by {end}"),
                )),
            };
        }
        loop {
            self.skip_ws();
            if self.pos >= self.data.len() {
                return Err(self.err(
                    self.section_loc,
                    format!("${name} is never closed by {end}"),
                ));
            }
            let loc = self.loc();
            let line = self.rest_of_line();
            let t = String::from_utf8_lossy(line).trim().to_string();
            if t == end {
                return Ok(());
            }
            if t.starts_with('$') {
                return Err(self.err(
                    loc,
                    format!(
                        "{t} starts before ${name} (opened {}) ended",
                        self.section_loc.phrase()
                    ),
                ));
            }
        }
    }
}

/// MSH format versions meid reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Version {
    V41,
    V22,
}

/// One element as read, before it is dispatched by type.
struct RawElem {
    ty: i64,
    tag: usize,
    loc: Loc,
    /// (dimension, tag) of its elementary entity.
    entity: (i64, i64),
    /// Offset of its node indices in [`Raw::conn`].
    first: usize,
    nn: usize,
}

/// What the sections hold, in file terms; [`build`] turns it into a [`GmshMesh`].
#[derive(Default)]
struct Raw {
    names: HashMap<(i64, i64), String>,
    /// 4.1 `$Entities`: (dimension, entity tag) → physical tags.
    entities: Option<HashMap<(i64, i64), Vec<i64>>>,
    nodes: Vec<[f64; 3]>,
    node_tags: Vec<usize>,
    index_of_tag: HashMap<usize, usize>,
    nodes_read: bool,
    elems: Vec<RawElem>,
    conn: Vec<usize>,
    elem_tags: HashMap<usize, Loc>,
    /// (dimension, physical tag) → element indices.
    groups: BTreeMap<(i64, i64), Vec<usize>>,
    elements_read: bool,
}

impl Raw {
    fn group_name(&self, dim: i64, tag: i64) -> String {
        self.names
            .get(&(dim, tag))
            .cloned()
            .unwrap_or_else(|| format!("physical{dim}_{tag}"))
    }
    /// "surface 3 (physical groups \"plate\", \"all\")" for messages.
    fn entity_desc(&self, what: &str, dim: i64, tag: i64, phys: &[i64]) -> String {
        let mut s = format!("{what} {tag}");
        if !phys.is_empty() {
            let names: Vec<String> = phys
                .iter()
                .map(|&p| format!("\"{}\"", self.group_name(dim, p)))
                .collect();
            let word = if names.len() == 1 { "group" } else { "groups" };
            s.push_str(&format!(" (physical {word} {})", names.join(", ")));
        } else {
            s.push_str(" (in no physical group)");
        }
        s
    }
}

fn dim_name(dim: i64) -> &'static str {
    match dim {
        0 => "point",
        1 => "curve",
        2 => "surface",
        3 => "volume",
        _ => "entity",
    }
}

/// Reads a `.msh` file: MSH 4.1 ASCII or binary, or MSH 2.2 ASCII.
pub fn read_msh(path: impl AsRef<Path>) -> Result<GmshMesh> {
    let path = path.as_ref();
    let data = crate::input::read_bytes(path)?;
    parse_msh_bytes(&data, &path.display().to_string())
}

/// Parses the text of an ASCII `.msh` file (4.1 or 2.2); `file` names it in error locations.
pub fn parse_msh(text: &str, file: &str) -> Result<GmshMesh> {
    parse_msh_bytes(text.as_bytes(), file)
}

/// Parses the bytes of a `.msh` file (4.1 ASCII or binary, 2.2 ASCII); `file` names it in
/// error locations.
pub fn parse_msh_bytes(data: &[u8], file: &str) -> Result<GmshMesh> {
    let mut lx = Lex::new(data, file);
    let start = lx.loc();
    match lx.open_section()? {
        None => {
            return Err(lx.err(
                start,
                "the file is empty: no $MeshFormat section, not a Gmsh .msh file",
            ))
        }
        Some(name) if name != "MeshFormat" => {
            return Err(lx.err(
                lx.section_loc,
                format!("the file starts with ${name}, not $MeshFormat: not a Gmsh .msh file"),
            ))
        }
        Some(_) => {}
    }
    let (version, bin) = mesh_format(&mut lx)?;
    let mut raw = Raw::default();
    let mut seen: HashMap<String, Loc> = HashMap::new();
    while let Some(name) = lx.open_section()? {
        let known = matches!(
            name.as_str(),
            "MeshFormat" | "PhysicalNames" | "Entities" | "Nodes" | "Elements"
        );
        if known {
            if let Some(prev) = seen.insert(name.clone(), lx.section_loc) {
                return Err(lx.err(
                    lx.section_loc,
                    format!(
                        "a second ${name} section (the first opened {})",
                        prev.phrase()
                    ),
                ));
            }
        }
        match (name.as_str(), version) {
            ("MeshFormat", _) => {
                return Err(lx.err(lx.section_loc, "a second $MeshFormat section"));
            }
            ("PhysicalNames", _) => physical_names(&mut lx, &mut raw)?,
            ("Entities", Version::V41) => {
                lx.bin = bin;
                entities(&mut lx, &mut raw)?;
            }
            ("Nodes", v) => {
                lx.bin = bin;
                match v {
                    Version::V41 => nodes41(&mut lx, &mut raw)?,
                    Version::V22 => nodes22(&mut lx, &mut raw)?,
                }
            }
            ("Elements", v) => {
                if !raw.nodes_read {
                    return Err(lx.err(
                        lx.section_loc,
                        "$Elements comes before $Nodes: Gmsh writes $Nodes first, and elements refer to nodes",
                    ));
                }
                lx.bin = bin;
                match v {
                    Version::V41 => elements41(&mut lx, &mut raw)?,
                    Version::V22 => elements22(&mut lx, &mut raw)?,
                }
            }
            _ => lx.skip_section()?,
        }
    }
    let origin = if lx.binary_file {
        Loc::Byte(0)
    } else {
        Loc::Text { line: 1, col: 1 }
    };
    if !raw.nodes_read {
        return Err(lx.err(origin, "no $Nodes section"));
    }
    if !raw.elements_read {
        return Err(lx.err(origin, "no $Elements section"));
    }
    build(raw, &lx)
}

/// `$MeshFormat`: `version file-type data-size`, then (binary) the `int` 1 that gives the byte
/// order.
fn mesh_format(lx: &mut Lex) -> Result<(Version, Option<Bin>)> {
    let (v, vloc) = lx.data_token("the MSH version")?;
    let version = match v {
        b"4.1" => Version::V41,
        b"2.2" => Version::V22,
        _ => {
            return Err(lx.err(
                vloc,
                format!(
                    "MSH version {} is not supported: meid reads 4.1 (ASCII or binary) and 2.2 (ASCII); export with Mesh.MshFileVersion = 4.1",
                    lossy(v)
                ),
            ))
        }
    };
    let (ft, ftloc) = lx.data_token("the file type (0 ASCII, 1 binary)")?;
    let binary = match ft {
        b"0" => false,
        b"1" => true,
        _ => {
            return Err(lx.err(
                ftloc,
                format!(
                    "file type '{}' is not valid: 0 (ASCII) or 1 (binary)",
                    lossy(ft)
                ),
            ))
        }
    };
    let (ds, dsloc) = lx.size("the data size")?;
    if binary && version == Version::V22 {
        return Err(lx.err(
            ftloc,
            "binary MSH 2.2 is not supported: export as 2.2 ASCII (Mesh.Binary = 0) or as 4.1 (Mesh.MshFileVersion = 4.1)",
        ));
    }
    if !binary {
        lx.close_section("header line")?;
        return Ok((version, None));
    }
    if ds != 4 && ds != 8 {
        return Err(lx.err(
            dsloc,
            format!("data size {ds} is not valid for a binary .msh: the byte width of a size_t, 8 (what Gmsh writes) or 4"),
        ));
    }
    let rest = lx.rest_of_line();
    if rest.iter().any(|c| !c.is_ascii_whitespace()) {
        return Err(lx.err(
            dsloc,
            format!("unexpected text after the data size: '{}'", lossy(rest)),
        ));
    }
    lx.binary_file = true;
    let (b, loc) = lx.bytes(4, "the byte-order check (the int 1)")?;
    let b = [b[0], b[1], b[2], b[3]];
    let big_endian = if i32::from_le_bytes(b) == 1 {
        false
    } else if i32::from_be_bytes(b) == 1 {
        true
    } else {
        return Err(lx.err(
            loc,
            format!(
                "the byte-order check after the header line must be the int 1 (01 00 00 00 little-endian or 00 00 00 01 big-endian), found {:02x} {:02x} {:02x} {:02x}",
                b[0], b[1], b[2], b[3]
            ),
        ));
    };
    lx.close_section("header")?;
    Ok((
        version,
        Some(Bin {
            size_t: ds,
            big_endian,
        }),
    ))
}

/// `$PhysicalNames` (ASCII in every format): a count, then `dimension tag "name"` lines.
fn physical_names(lx: &mut Lex, raw: &mut Raw) -> Result<()> {
    let (n, nloc) = lx.size("the number of physical names")?;
    lx.check_fits(nloc, n, 7, "physical names")?;
    for _ in 0..n {
        let (dim, _) = lx.int("the dimension of a physical name")?;
        let (tag, _) = lx.int("the tag of a physical name")?;
        lx.skip_ws_inline();
        let loc = lx.loc();
        let line = lx.rest_of_line();
        let text = std::str::from_utf8(line)
            .map_err(|_| lx.err(loc, "a physical name must be UTF-8 text"))?
            .trim();
        if !(text.len() >= 2 && text.starts_with('"') && text.ends_with('"')) {
            return Err(lx.err(
                loc,
                format!("expected 'dimension tag \"name\"', found '{dim} {tag} {text}'"),
            ));
        }
        raw.names
            .insert((dim, tag), text[1..text.len() - 1].to_string());
    }
    lx.close_section(&format!("{n} names"))
}

/// 4.1 `$Entities`: points (tag, x y z, physical tags), curves, surfaces and volumes (tag,
/// bounding box, physical tags, bounding entities).
fn entities(lx: &mut Lex, raw: &mut Raw) -> Result<()> {
    let mut counts = [0usize; 4];
    let mut locs = [Loc::Byte(0); 4];
    for (d, what) in ["points", "curves", "surfaces", "volumes"]
        .iter()
        .enumerate()
    {
        let (n, loc) = lx.size(&format!("the number of {what}"))?;
        counts[d] = n;
        locs[d] = loc;
    }
    let mut map: HashMap<(i64, i64), Vec<i64>> = HashMap::new();
    for (dim, &n) in counts.iter().enumerate() {
        let item = lx.min_bytes(5, 4 + 24 + 8);
        lx.check_fits(locs[dim], n, item, &format!("{}s", dim_name(dim as i64)))?;
        for _ in 0..n {
            let (tag, loc) = lx.int("entity tag")?;
            let nbox = if dim == 0 { 3 } else { 6 };
            for _ in 0..nbox {
                lx.real("entity bounding box")?;
            }
            let (np, _) = lx.size("number of physical tags")?;
            let mut tags = Vec::new();
            for _ in 0..np {
                tags.push(lx.int("physical tag")?.0);
            }
            if dim > 0 {
                let (nb, _) = lx.size("number of bounding entities")?;
                for _ in 0..nb {
                    lx.int("bounding entity tag")?;
                }
            }
            if map.insert((dim as i64, tag), tags).is_some() {
                return Err(lx.err(
                    loc,
                    format!("{} {tag} appears twice in $Entities", dim_name(dim as i64)),
                ));
            }
        }
    }
    raw.entities = Some(map);
    lx.close_section(&format!(
        "{} points, {} curves, {} surfaces and {} volumes",
        counts[0], counts[1], counts[2], counts[3]
    ))
}

/// Adds a node; refuses a tag seen before.
fn add_node(lx: &Lex, raw: &mut Raw, tag: usize, loc: Loc, where_: &str) -> Result<()> {
    let idx = raw.node_tags.len();
    if raw.index_of_tag.insert(tag, idx).is_some() {
        return Err(lx.err(
            loc,
            format!("node tag {tag} appears twice ({where_}); node tags must be unique"),
        ));
    }
    raw.node_tags.push(tag);
    Ok(())
}

/// 4.1 `$Nodes`: `numEntityBlocks numNodes minNodeTag maxNodeTag`, then per block
/// `entityDim entityTag parametric numNodesInBlock`, the block's tags, then its coordinates.
fn nodes41(lx: &mut Lex, raw: &mut Raw) -> Result<()> {
    let (nblocks, hloc) = lx.size("the number of node blocks")?;
    let (total, tloc) = lx.size("the number of nodes")?;
    let (min_tag, _) = lx.size("the minimum node tag")?;
    let (max_tag, _) = lx.size("the maximum node tag")?;
    let size_t = lx.bin.map(|b| b.size_t).unwrap_or(8);
    lx.check_fits(hloc, nblocks, lx.min_bytes(4, 12 + size_t), "node blocks")?;
    lx.check_fits(tloc, total, lx.min_bytes(4, size_t + 24), "nodes")?;
    raw.nodes.reserve_exact(total);
    raw.node_tags.reserve_exact(total);
    raw.index_of_tag.reserve(total);
    for b in 0..nblocks {
        let (dim, _) = lx.int("entity dimension")?;
        let (etag, _) = lx.int("entity tag")?;
        let (parametric, ploc) = lx.int("parametric flag")?;
        let (n, nloc) = lx.size("number of nodes in block")?;
        let block = format!("node block {} of {} {etag}", b + 1, dim_name(dim));
        if parametric != 0 && parametric != 1 {
            return Err(lx.err(
                ploc,
                format!("{block}: the parametric flag is {parametric}; valid: 0 or 1"),
            ));
        }
        let sofar = raw.node_tags.len();
        if n > total - sofar {
            return Err(lx.err(
                nloc,
                format!(
                    "{block} holds {n} nodes, but $Nodes announces {total} in all and the blocks before hold {sofar}: the header's counts disagree with the data"
                ),
            ));
        }
        let extra = if parametric == 1 {
            dim.clamp(0, 3) as usize
        } else {
            0
        };
        for _ in 0..n {
            let (tag, loc) = lx.size("node tag")?;
            add_node(lx, raw, tag, loc, &block)?;
        }
        for _ in 0..n {
            let x = [lx.real("x")?, lx.real("y")?, lx.real("z")?];
            for _ in 0..extra {
                lx.real("parametric coordinate")?;
            }
            raw.nodes.push(x);
        }
    }
    lx.close_section(&format!("{nblocks} node blocks"))?;
    if raw.nodes.len() != total {
        return Err(lx.err(
            hloc,
            format!(
                "$Nodes announces {total} nodes but its {nblocks} blocks hold {}",
                raw.nodes.len()
            ),
        ));
    }
    check_tag_range(lx, hloc, "node", &raw.node_tags, min_tag, max_tag)?;
    raw.nodes_read = true;
    Ok(())
}

/// 2.2 `$Nodes`: `numNodes`, then `tag x y z` per node.
fn nodes22(lx: &mut Lex, raw: &mut Raw) -> Result<()> {
    let (total, tloc) = lx.size("the number of nodes")?;
    lx.check_fits(tloc, total, lx.min_bytes(4, 32), "nodes")?;
    raw.nodes.reserve_exact(total);
    raw.node_tags.reserve_exact(total);
    raw.index_of_tag.reserve(total);
    for _ in 0..total {
        let (tag, loc) = lx.size("node tag")?;
        add_node(lx, raw, tag, loc, "$Nodes")?;
        raw.nodes
            .push([lx.real("x")?, lx.real("y")?, lx.real("z")?]);
    }
    lx.close_section(&format!("{total} nodes"))?;
    raw.nodes_read = true;
    Ok(())
}

/// Element type of a block or element: its node count and kind, or an error naming where it
/// is and what is valid.
fn element_type(lx: &Lex, ty: i64, loc: Loc, desc: &str) -> Result<(usize, usize)> {
    match element_kind(ty) {
        None => Err(lx.err(
            loc,
            format!(
                "unsupported Gmsh element type {ty} in {desc}; meid reads types {VALID_TYPES}"
            ),
        )),
        Some((_, _, name, Kind::Unsupported(hint))) => Err(lx.err(
            loc,
            format!(
                "element type {ty} ({name}) in {desc} is not supported: {hint}; meid reads types {VALID_TYPES}"
            ),
        )),
        Some((nn, edim, _, _)) => Ok((nn, edim)),
    }
}

/// Reads one element's tag and node tags (resolved to node indices) into `raw`; returns its
/// index.
#[allow(clippy::too_many_arguments)]
fn read_element(
    lx: &mut Lex,
    raw: &mut Raw,
    ty: i64,
    nn: usize,
    tag: usize,
    loc: Loc,
    entity: (i64, i64),
    desc: &str,
) -> Result<usize> {
    if let Some(prev) = raw.elem_tags.insert(tag, loc) {
        return Err(lx.err(
            loc,
            format!(
                "element tag {tag} appears twice (first {}); element tags must be unique",
                prev.phrase()
            ),
        ));
    }
    let first = raw.conn.len();
    for _ in 0..nn {
        let (v, text, nloc) = lx.node_ref("element node tag")?;
        match v.and_then(|t| raw.index_of_tag.get(&t).copied()) {
            Some(i) => raw.conn.push(i),
            None => {
                return Err(lx.err(
                    nloc,
                    format!(
                        "element {tag} (in {desc}) refers to node '{}', which is not in $Nodes",
                        crate::input::clip(&text)
                    ),
                ))
            }
        }
    }
    raw.elems.push(RawElem {
        ty,
        tag,
        loc,
        entity,
        first,
        nn,
    });
    Ok(raw.elems.len() - 1)
}

/// 4.1 `$Elements`: `numEntityBlocks numElements minElementTag maxElementTag`, then per block
/// `entityDim entityTag elementType numElementsInBlock` and `tag node-tags…` per element.
fn elements41(lx: &mut Lex, raw: &mut Raw) -> Result<()> {
    let (nblocks, hloc) = lx.size("the number of element blocks")?;
    let (total, tloc) = lx.size("the number of elements")?;
    let (min_tag, _) = lx.size("the minimum element tag")?;
    let (max_tag, _) = lx.size("the maximum element tag")?;
    let size_t = lx.bin.map(|b| b.size_t).unwrap_or(8);
    lx.check_fits(
        hloc,
        nblocks,
        lx.min_bytes(4, 12 + size_t),
        "element blocks",
    )?;
    lx.check_fits(tloc, total, lx.min_bytes(2, 2 * size_t), "elements")?;
    raw.elems.reserve_exact(total);
    raw.elem_tags.reserve(total);
    for b in 0..nblocks {
        let (dim, _) = lx.int("entity dimension")?;
        let (etag, eloc) = lx.int("entity tag")?;
        let (ty, tyloc) = lx.int("element type")?;
        let (n, nloc) = lx.size("number of elements in block")?;
        let phys: Vec<i64> = match &raw.entities {
            None => Vec::new(),
            Some(map) => match map.get(&(dim, etag)) {
                Some(p) => p.clone(),
                None => {
                    return Err(lx.err(
                        eloc,
                        format!(
                            "element block {} is on {} {etag}, which $Entities does not list",
                            b + 1,
                            dim_name(dim)
                        ),
                    ))
                }
            },
        };
        let desc = format!(
            "element block {} of {}",
            b + 1,
            raw.entity_desc(dim_name(dim), dim, etag, &phys)
        );
        let (nn, _) = element_type(lx, ty, tyloc, &desc)?;
        let sofar = raw.elems.len();
        if n > total - sofar {
            return Err(lx.err(
                nloc,
                format!(
                    "{desc} holds {n} elements, but $Elements announces {total} in all and the blocks before hold {sofar}: the header's counts disagree with the data"
                ),
            ));
        }
        lx.check_fits(
            nloc,
            n,
            lx.min_bytes(1 + nn, (1 + nn) * size_t),
            &format!("elements of {nn} nodes in {desc}"),
        )?;
        raw.conn.reserve(n * nn);
        let start = raw.elems.len();
        for _ in 0..n {
            let (tag, loc) = lx.size("element tag")?;
            read_element(lx, raw, ty, nn, tag, loc, (dim, etag), &desc)?;
        }
        for &p in &phys {
            raw.groups
                .entry((dim, p))
                .or_default()
                .extend(start..raw.elems.len());
        }
    }
    lx.close_section(&format!("{nblocks} element blocks"))?;
    if raw.elems.len() != total {
        return Err(lx.err(
            hloc,
            format!(
                "$Elements announces {total} elements but its {nblocks} blocks hold {}: the file is truncated or its header is wrong",
                raw.elems.len()
            ),
        ));
    }
    let tags: Vec<usize> = raw.elems.iter().map(|e| e.tag).collect();
    check_tag_range(lx, hloc, "element", &tags, min_tag, max_tag)?;
    raw.elements_read = true;
    Ok(())
}

/// 2.2 `$Elements`: `numElements`, then `tag type number-of-tags tags… node-tags…` per element,
/// the first tag the physical group (0: none), the second the elementary entity. Copies of an
/// element (one per physical group, as Gmsh writes them) become one element of several groups.
fn elements22(lx: &mut Lex, raw: &mut Raw) -> Result<()> {
    let (total, tloc) = lx.size("the number of elements")?;
    lx.check_fits(tloc, total, lx.min_bytes(4, 16), "elements")?;
    raw.elems.reserve_exact(total);
    raw.elem_tags.reserve(total);
    let mut copies: HashMap<(i64, i64, Vec<usize>), usize> = HashMap::new();
    for _ in 0..total {
        let (tag, loc) = lx.size("element tag")?;
        let (ty, tyloc) = lx.int("element type")?;
        let (ntags, ntloc) = lx.size("number of tags")?;
        lx.check_fits(ntloc, ntags, 2, "tags of one element")?;
        let mut tags = Vec::with_capacity(ntags);
        for _ in 0..ntags {
            tags.push(lx.int("element tag (physical, elementary, partitions)")?.0);
        }
        let phys = tags.first().copied().unwrap_or(0);
        let elementary = tags.get(1).copied().unwrap_or(0);
        let edim = element_kind(ty).map(|k| k.1 as i64).unwrap_or(-1);
        let plist: Vec<i64> = if phys != 0 { vec![phys] } else { Vec::new() };
        let desc = raw.entity_desc("elementary entity", edim, elementary, &plist);
        let (nn, _) = element_type(lx, ty, tyloc, &desc)?;
        let idx = read_element(lx, raw, ty, nn, tag, loc, (edim, elementary), &desc)?;
        let e = &raw.elems[idx];
        let key = (ty, elementary, raw.conn[e.first..e.first + nn].to_vec());
        let idx = match copies.get(&key) {
            Some(&orig) => {
                // A copy for another physical group: drop it, keep the group.
                raw.elems.pop();
                raw.conn.truncate(raw.conn.len() - nn);
                orig
            }
            None => {
                copies.insert(key, idx);
                idx
            }
        };
        if phys != 0 {
            raw.groups.entry((edim, phys)).or_default().push(idx);
        }
    }
    lx.close_section(&format!("{total} elements"))?;
    raw.elements_read = true;
    Ok(())
}

/// The header's minimum and maximum tags must be those of the data.
fn check_tag_range(
    lx: &Lex,
    loc: Loc,
    what: &str,
    tags: &[usize],
    min: usize,
    max: usize,
) -> Result<()> {
    let (lo, hi) = tags
        .iter()
        .fold((usize::MAX, 0), |(a, b), &t| (a.min(t), b.max(t)));
    if !tags.is_empty() && (lo != min || hi != max) {
        return Err(lx.err(
            loc,
            format!("the header announces {what} tags {min} to {max} but the data hold tags {lo} to {hi}: the header's counts disagree with the data"),
        ));
    }
    Ok(())
}

/// Turns what the sections hold into a [`GmshMesh`]: elements dispatched by type, physical
/// groups into named sets, quadrangle geometry checked.
fn build(raw: Raw, lx: &Lex) -> Result<GmshMesh> {
    let mut mesh = GmshMesh {
        nodes: raw.nodes,
        node_tags: raw.node_tags,
        ..GmshMesh::default()
    };
    // Index of each element among the quads / lines (usize::MAX: neither).
    let mut slot = vec![usize::MAX; raw.elems.len()];
    let mut quad_locs: Vec<Loc> = Vec::new();
    let mut tri_locs: Vec<Loc> = Vec::new();
    let mut tri_entity: Vec<(i64, i64)> = Vec::new();
    for (k, e) in raw.elems.iter().enumerate() {
        let conn = &raw.conn[e.first..e.first + e.nn];
        match element_kind(e.ty).map(|k| k.3) {
            Some(Kind::Quad4) => {
                slot[k] = mesh.quads.len();
                mesh.quads.push([conn[0], conn[1], conn[2], conn[3]]);
                mesh.quad_tags.push(e.tag);
                mesh.quad_lines.push(e.loc.line_or_byte());
                quad_locs.push(line_start(e.loc));
            }
            Some(Kind::Tri3) => {
                slot[k] = mesh.triangles.len();
                mesh.triangles.push([conn[0], conn[1], conn[2]]);
                mesh.triangle_tags.push(e.tag);
                mesh.triangle_lines.push(e.loc.line_or_byte());
                tri_locs.push(line_start(e.loc));
                tri_entity.push(e.entity);
            }
            Some(Kind::Line2) => {
                if conn[0] == conn[1] {
                    return Err(lx.err(
                        line_start(e.loc),
                        format!(
                            "line {} is degenerate: both ends are node {}",
                            e.tag, mesh.node_tags[conn[0]]
                        ),
                    ));
                }
                slot[k] = mesh.lines.len();
                mesh.lines.push([conn[0], conn[1]]);
                mesh.line_tags.push(e.tag);
            }
            Some(Kind::NodesOnly) | Some(Kind::Unsupported(_)) | None => {}
        }
    }
    let mut node_sets: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for (&(dim, phys), elems) in &raw.groups {
        let name = raw
            .names
            .get(&(dim, phys))
            .cloned()
            .unwrap_or_else(|| format!("physical{dim}_{phys}"));
        let set = node_sets.entry(name.clone()).or_default();
        for &k in elems {
            let e = &raw.elems[k];
            set.extend_from_slice(&raw.conn[e.first..e.first + e.nn]);
        }
        let kinds = elems
            .iter()
            .filter(|&&k| slot[k] != usize::MAX)
            .map(|&k| (element_kind(raw.elems[k].ty).map(|x| x.3), slot[k]));
        for (kind, s) in kinds {
            match (kind, dim) {
                (Some(Kind::Quad4), 2) => {
                    mesh.element_sets.entry(name.clone()).or_default().push(s)
                }
                (Some(Kind::Tri3), 2) => {
                    mesh.triangle_sets.entry(name.clone()).or_default().push(s)
                }
                (Some(Kind::Line2), 1) => mesh.line_sets.entry(name.clone()).or_default().push(s),
                _ => {}
            }
        }
    }
    for v in node_sets
        .values_mut()
        .chain(mesh.element_sets.values_mut())
        .chain(mesh.triangle_sets.values_mut())
        .chain(mesh.line_sets.values_mut())
    {
        v.sort_unstable();
        v.dedup();
    }
    mesh.node_sets = node_sets;
    // Element geometry: four distinct nodes, a non-degenerate, convex, not self-intersecting quad.
    for (q, (&tag, &loc)) in mesh.quads.iter().zip(mesh.quad_tags.iter().zip(&quad_locs)) {
        let mut distinct = q.to_vec();
        distinct.sort_unstable();
        distinct.dedup();
        let tags = q.map(|i| mesh.node_tags[i]);
        if distinct.len() < 4 {
            return Err(lx.err(
                loc,
                format!("quadrangle {tag} (nodes {tags:?}) is degenerate: a node is repeated; a quadrangle needs four distinct nodes"),
            ));
        }
        super::shell::shell_geometry(&q.map(|i| mesh.nodes[i])).map_err(|e| {
            let msg = match e {
                Error::InvalidValue { message, .. } => message,
                other => other.to_string(),
            };
            lx.err(loc, format!("quadrangle {tag} (nodes {tags:?}): {msg}"))
        })?;
    }
    check_triangles(&mesh, &tri_locs, &tri_entity, lx)?;
    if mesh.quads.is_empty() && mesh.triangles.is_empty() && mesh.lines.is_empty() {
        return Err(lx.err(
            if lx.binary_file {
                Loc::Byte(0)
            } else {
                Loc::Text { line: 1, col: 1 }
            },
            "the mesh has no 4-node quadrangles (element type 3), 3-node triangles (type 2) or 2-node lines (type 1)",
        ));
    }
    Ok(mesh)
}

/// Triangles: three distinct nodes, a nonzero area, and, within one surface entity, a node
/// order consistent with the neighbours' and no fold back onto a neighbour.
fn check_triangles(mesh: &GmshMesh, locs: &[Loc], entity: &[(i64, i64)], lx: &Lex) -> Result<()> {
    let describe = |t: usize| {
        format!(
            "triangle {} (nodes {:?})",
            mesh.triangle_tags[t],
            mesh.triangles[t].map(|i| mesh.node_tags[i])
        )
    };
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
            return Err(lx.err(
                locs[t],
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
            lx.err(locs[t], format!("{}: {msg}", describe(t)))
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
            return Err(lx.err(
                locs[b],
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

/// An element's location for element-level messages: column 1 of its line in ASCII files.
fn line_start(loc: Loc) -> Loc {
    match loc {
        Loc::Text { line, .. } => Loc::Text { line, col: 1 },
        b => b,
    }
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
