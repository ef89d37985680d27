//! Universal File Format (UFF/UNV) datasets: 58 (function at nodal DOF) in ASCII and binary
//! (58b), 2411 (nodes, double precision), 15 (nodes, single precision), 82 (trace lines), 2412
//! (elements), 55 (data at nodes: normal modes) and 164 (units), read and written.
//!
//! Test geometry (datasets 15, 82, 2412; records as pyuff writes them):
//!
//! | dataset | record | format | fields |
//! |---|---|---|---|
//! | 15 | 1 per node | 4I10,3E13.5 | node label, definition and displacement coordinate systems, colour, x, y, z |
//! | 82 | 1 | 3I10 | trace line number, number of nodes, colour |
//! | 82 | 2 | 80A1 | identification |
//! | 82 | 3 | 8I10 | the nodes (0: move to the next node without drawing) |
//! | 2412 | 1 | 6I10 | element label, FE descriptor (11 rod, 91 thin-shell triangle, 94 thin-shell quadrilateral, …), physical and material property tables, colour, number of nodes |
//! | 2412 | 2 (beams: 11, 21-24) | 3I10 | orientation node, fore- and aft-end cross sections |
//! | 2412 | 3 | 8I10 | the nodes |
//!
//! # Layout read and written (I-DEAS/SDRC Universal File definitions)
//!
//! A file is a sequence of datasets, each framed by lines holding `    -1`; the first line of a
//! dataset holds its number in columns 1-6 (`    58`), and for binary 58b a `b` in column 7 and
//! the binary header `byte order (1 little-endian, 2 big-endian), floating-point format
//! (2 IEEE 754), number of ASCII lines (11), number of bytes of data, 0 0 0 0`.
//!
//! Dataset 58:
//!
//! | record | format | fields |
//! |---|---|---|
//! | 1-5 | 80A1 | ID lines (1: function name, meid's channel name; 3: date) |
//! | 6 | 2(I5,I10),2(1X,10A1,I10,I4) | function type (1 time response), id, version, load case, response entity, node, direction, reference entity, node, direction |
//! | 7 | 3I10,3E13.5 | ordinate data type (2 real single, 4 real double, 5/6 complex), number of points N, spacing (1 even, 0 uneven), abscissa minimum, increment, z value |
//! | 8-11 | I10,3I5,2(1X,20A1) | abscissa / ordinate / ordinate denominator / z axis: specific data type (17 time, 12 acceleration, 13 force, ...), length, force, temperature unit exponents, axis label, **unit label** |
//! | 12 | | data: even real N values; uneven real N pairs (x, y); complex twice (ASCII: single 6E13.5, double 4E20.12; uneven double 2(E13.5,E20.12)) |
//!
//! Units are read from the unit label of records 8 and 9 ([`crate::record::units`]); a label
//! `NONE` or blank falls back to the SI unit of the specific data type (the SI system, unit
//! code 1, is the UFF default when no dataset 164 says otherwise); a file whose dataset 164
//! names another unit system must label its axes. A unit neither label nor type identifies
//! is refused.
//!
//! # Robustness
//!
//! The reader streams (a [`BufRead`]); it never allocates from a size field before the bytes
//! are there: the number of points is checked against the bytes left in the file, binary data
//! is decoded chunk by chunk, and every error names the file, the dataset (its ordinal and
//! first line), the record, the line and what was expected.

use std::io::{BufRead, Read, Write};
use std::path::Path;

use crate::record::units::{parse_unit, Quantity, ACCEPTED_UNITS};
use crate::record::{Abscissa, PointRef, Record};
use crate::{Error, Result};

/// A node of dataset 2411 (coordinates in m as written).
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    pub label: i64,
    pub xyz: [f64; 3],
}

/// A real normal mode of dataset 55 (analysis type 2).
#[derive(Debug, Clone, PartialEq)]
pub struct Mode {
    /// Mode number (record 7).
    pub number: i64,
    /// Frequency (Hz), modal mass, viscous damping ratio (record 8).
    pub frequency_hz: f64,
    pub modal_mass: f64,
    pub damping_ratio: f64,
    /// ID line 1.
    pub name: String,
    /// ID lines 2-5 (free text, 80 columns each). The reader keeps those neither blank nor
    /// `NONE`, trimmed; the writer writes the first four and `NONE` for the rest.
    pub id_lines: Vec<String>,
    /// `(node, [x, y, z] translations)` (the first three values of each node).
    pub shapes: Vec<(i64, [f64; 3])>,
    /// The unit system of the dataset 164 before this one in the file (`None`: no dataset 164
    /// before it, the UFF default, SI). The values above are as written, in those units.
    pub units: Option<Units>,
}

/// A trace line of dataset 82: the lines a viewer draws between nodes.
#[derive(Debug, Clone, PartialEq)]
pub struct TraceLine {
    pub number: i64,
    pub color: i64,
    /// The identification line (trimmed).
    pub name: String,
    /// Node labels in drawing order; 0 moves to the next node without drawing.
    pub nodes: Vec<i64>,
}

/// An element of dataset 2412.
#[derive(Debug, Clone, PartialEq)]
pub struct Element {
    pub label: i64,
    /// FE descriptor id: 11 rod, 91 thin-shell linear triangle, 94 thin-shell linear
    /// quadrilateral, 21 linear beam.
    pub fe_descriptor: i64,
    pub color: i64,
    pub nodes: Vec<i64>,
}

/// FE descriptors of dataset 2412 whose elements carry the beam record (record 2).
const BEAM_DESCRIPTORS: [i64; 5] = [11, 21, 22, 23, 24];

/// Dataset 164: the unit system of the datasets that follow it.
///
/// | record | format | fields |
/// |---|---|---|
/// | 1 | I10,20A1,I10 | unit code (1 SI, 2 BG, 3 MG, 4 BA, 5 MM, 6 CM, 7 IN, 8 GM, 9 user), description, temperature mode |
/// | 2 | 3D25.17 | length, force and temperature factors |
/// | 3 | D25.17 | temperature offset |
///
/// The factors convert the file's units to SI by division: a length `x` in the file is
/// `x / length` m, a force `f` is `f / force` N. Time is always in seconds, so the file's mass
/// unit is its force unit · s² / its length unit and a mass `m` is `m / mass()` kg with
/// `mass() = force / length` (mm, tonne, s, N: length 1000, force 1, mass 0.001).
#[derive(Debug, Clone, PartialEq)]
pub struct Units {
    pub code: i64,
    pub description: String,
    pub length: f64,
    pub force: f64,
}

impl Units {
    /// SI: m, N (kg, s), code 1.
    pub fn si() -> Self {
        Self {
            code: 1,
            description: "SI".into(),
            length: 1.0,
            force: 1.0,
        }
    }

    /// The mass factor: the file's mass unit per kg (`force / length`).
    pub fn mass(&self) -> f64 {
        self.force / self.length
    }

    /// Both factors finite (an unreadable dataset 164 leaves them NaN).
    pub fn known(&self) -> bool {
        self.length.is_finite() && self.force.is_finite()
    }

    /// The same length and force factors to 1e-9 relative (the codes and texts aside).
    pub fn same_factors(&self, other: &Units) -> bool {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
        close(self.length, other.length) && close(self.force, other.force)
    }

    /// E.g. `dataset 164 unit code 9 ('mm t s N': length factor 1000, force factor 1)`.
    pub fn describe(&self) -> String {
        format!(
            "dataset 164 unit code {} ('{}': length factor {}, force factor {})",
            self.code,
            self.description,
            crate::num(self.length),
            crate::num(self.force)
        )
    }
}

/// What a UFF file held that meid reads.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct UffFile {
    /// Time responses of dataset 58 / 58b, values in SI.
    pub records: Vec<Record>,
    pub nodes: Vec<Node>,
    pub modes: Vec<Mode>,
    /// Trace lines (dataset 82) and elements (2412); nodes of dataset 15 are in `nodes`.
    pub traces: Vec<TraceLine>,
    pub elements: Vec<Element>,
    /// Functions of dataset 58 / 58b in frequency: FRFs (type 4), coherences (6), PSDs (9).
    pub functions: Vec<Function>,
    /// Datasets passed over, one line each (type, where, why).
    pub skipped: Vec<String>,
}

/// A dataset 58 function of frequency: an FRF (function type 4), a coherence (6) or a power
/// spectral density (9).
#[derive(Debug, Clone, PartialEq)]
pub struct Function {
    /// 4 FRF, 6 coherence, 9 PSD.
    pub function_type: i64,
    /// ID line 1.
    pub name: String,
    /// ID lines 2-5, those neither blank nor `NONE`, trimmed.
    pub id_lines: Vec<String>,
    /// Response and reference (record 6).
    pub response: PointRef,
    pub reference: PointRef,
    pub frequency_hz: Vec<f64>,
    /// In SI: an FRF in (numerator SI unit)/(denominator SI unit), a PSD in (SI unit)²/Hz, a
    /// coherence as is. A real function has zero imaginary parts.
    pub values: Vec<num_complex::Complex64>,
    /// The ordinate's quantity (records 9) and, for an FRF, the denominator's (record 10).
    pub numerator: Option<Quantity>,
    pub denominator: Option<Quantity>,
    /// Where it came from: "FILE, dataset 3 (58 at line 120)".
    pub origin: String,
}

/// What a dataset 58 holds for meid.
enum Read58 {
    Record(Record),
    Function(Function),
    /// Read past, with the reason.
    Skip(String),
}

/// The header records of a dataset 58, for [`Parser::function_58`].
struct Head58<'a> {
    ds: Ds,
    id: &'a [String],
    r6: &'a str,
    r7_line: usize,
    axes: &'a [(String, usize)],
    even: bool,
    x0: f64,
    dx: f64,
    complex: bool,
    unit_code: Option<i64>,
}

/// Records 1-11 of a dataset 58, as read.
struct Records58 {
    /// Records 1-5 (ID lines).
    id: Vec<String>,
    /// Record 6 and its line.
    r6: String,
    func_type: i64,
    rsp_entity: String,
    rsp_node: i64,
    rsp_dir: i64,
    /// Record 7's line, ordinate data type, number of points, even spacing, minimum, step.
    r7_line: usize,
    ord_type: i64,
    npts: i64,
    even: bool,
    x0: f64,
    dx: f64,
    /// Records 8-11 with their lines.
    axes: Vec<(String, usize)>,
}

/// Reads a UFF file (see the module docs).
pub fn read_uff(path: &Path) -> Result<UffFile> {
    let (f, len) = crate::input::open(path)?;
    let len = Some(len);
    let name = path.display().to_string();
    parse_uff(std::io::BufReader::with_capacity(1 << 16, f), &name, len)
}

/// Parses UFF text/bytes from `reader`; `file` names it in errors; `len` (bytes), when known,
/// bounds every size field.
pub fn parse_uff<R: BufRead>(reader: R, file: &str, len: Option<u64>) -> Result<UffFile> {
    let mut p = Parser {
        r: reader,
        file,
        left: len.unwrap_or(u64::MAX),
        line_no: 0,
        after_binary: false,
        buf: Vec::new(),
    };
    p.run()
}

/// Longest line accepted (bytes): far beyond any record of the format (80 columns).
const MAX_LINE: u64 = 1 << 20;

struct Parser<'a, R: BufRead> {
    r: R,
    file: &'a str,
    /// Bytes not yet read (an upper bound when the length is unknown).
    left: u64,
    /// Number of the last line read (1-based); after binary data, lines are counted on.
    line_no: usize,
    after_binary: bool,
    buf: Vec<u8>,
}

/// Where in a dataset: for messages.
#[derive(Clone, Copy)]
struct Ds {
    ordinal: usize,
    kind: &'static str,
    line: usize,
}

impl<R: BufRead> Parser<'_, R> {
    fn loc(&self, ds: Option<Ds>, record: Option<&str>, line: usize) -> String {
        let mut s = self.file.to_string();
        if let Some(d) = ds {
            s.push_str(&format!(
                ": dataset {} ({} starting at line {})",
                d.ordinal, d.kind, d.line
            ));
        }
        if let Some(r) = record {
            s.push_str(&format!(", {r}"));
        }
        s.push_str(&format!(
            ", line {line}{}",
            if self.after_binary {
                " (counting lines after binary data)"
            } else {
                ""
            }
        ));
        s
    }

    fn err(&self, ds: Option<Ds>, record: Option<&str>, line: usize, msg: String) -> Error {
        Error::Input {
            location: self.loc(ds, record, line),
            message: msg,
        }
    }

    /// The next line without its end of line, or `None` at the end of the file.
    fn line(&mut self) -> Result<Option<String>> {
        self.buf.clear();
        let n = (&mut self.r)
            .take(MAX_LINE)
            .read_until(b'\n', &mut self.buf)
            .map_err(|e| Error::io(self.file, e))?;
        if n == 0 {
            return Ok(None);
        }
        self.left = self.left.saturating_sub(n as u64);
        self.line_no += 1;
        if n as u64 == MAX_LINE && self.buf.last() != Some(&b'\n') {
            return Err(self.err(
                None,
                None,
                self.line_no,
                format!("a line longer than {MAX_LINE} bytes: not a Universal File"),
            ));
        }
        while matches!(self.buf.last(), Some(b'\n' | b'\r')) {
            self.buf.pop();
        }
        Ok(Some(String::from_utf8_lossy(&self.buf).into_owned()))
    }

    fn run(&mut self) -> Result<UffFile> {
        let mut out = UffFile::default();
        let mut ordinal = 0usize;
        let mut units: Option<Units> = None;
        // Between datasets: blank lines, then "-1".
        while let Some(l) = self.line()? {
            if l.trim().is_empty() {
                continue;
            }
            if l.trim() != "-1" {
                return Err(self.err(
                    None,
                    None,
                    self.line_no,
                    format!(
                        "expected the start of a dataset ('    -1'), got '{}'",
                        clip(&l)
                    ),
                ));
            }
            let mut start = self.line_no;
            // An empty block ("-1" twice, as some writers leave between datasets) is passed over.
            let h = loop {
                let Some(h) = self.line()? else {
                    return Err(self.err(
                        None,
                        None,
                        self.line_no,
                        "the file ends after a '-1' line: expected a dataset number".into(),
                    ));
                };
                if h.trim() == "-1" {
                    start = self.line_no;
                    continue;
                }
                break h;
            };
            ordinal += 1;
            let tok = h.split_whitespace().next().unwrap_or("");
            let (num, binary) = match tok.strip_suffix(['b', 'B']) {
                Some(n) => (n, true),
                None => (tok, false),
            };
            let Ok(num) = num.parse::<u32>() else {
                return Err(self.err(
                    None,
                    None,
                    self.line_no,
                    format!(
                        "dataset {ordinal}: expected a dataset number (e.g. '    58'), got '{}'",
                        clip(&h)
                    ),
                ));
            };
            match (num, binary) {
                (58, _) => {
                    let ds = Ds {
                        ordinal,
                        kind: if binary { "58b" } else { "58" },
                        line: start,
                    };
                    let unit_code = units.as_ref().map(|u| u.code);
                    match self.dataset_58(ds, &h, binary, unit_code)? {
                        Read58::Record(r) => out.records.push(r),
                        Read58::Function(f) => out.functions.push(f),
                        Read58::Skip(why) => out.skipped.push(format!(
                            "dataset {ordinal} (58 at line {start}): {why}"
                        )),
                    }
                }
                (2411, false) => {
                    let ds = Ds {
                        ordinal,
                        kind: "2411",
                        line: start,
                    };
                    out.nodes.extend(self.dataset_2411(ds)?);
                }
                (15 | 82 | 2412, false) => self.geometry_dataset(num, ordinal, start, &mut out)?,
                (55, false) => {
                    let ds = Ds {
                        ordinal,
                        kind: "55",
                        line: start,
                    };
                    match self.dataset_55(ds)? {
                        Ok(mut m) => {
                            m.units = units.clone();
                            out.modes.push(m)
                        }
                        Err(why) => out.skipped.push(format!(
                            "dataset {ordinal} (55 at line {start}): {why}"
                        )),
                    }
                }
                (164, false) => {
                    let ds = Ds {
                        ordinal,
                        kind: "164",
                        line: start,
                    };
                    let lines = self.skip_to_end(ds)?;
                    units = Some(match self.dataset_164(ds, &lines) {
                        Ok(u) => u,
                        // Unreadable: the datasets after it have unknown units (NaN
                        // factors), which only what needs them refuses.
                        Err(e) => {
                            out.skipped.push(format!(
                                "{e}; the units of the datasets after it are unknown"
                            ));
                            Units {
                                code: 0,
                                description: format!("dataset 164 at line {start}"),
                                length: f64::NAN,
                                force: f64::NAN,
                            }
                        }
                    });
                }
                (n, false) => {
                    let ds = Ds {
                        ordinal,
                        kind: "other",
                        line: start,
                    };
                    self.skip_to_end(ds)?;
                    out.skipped.push(format!(
                        "dataset {ordinal} (type {n} at line {start}): not read by meid"
                    ));
                }
                (n, true) => {
                    return Err(self.err(
                        None,
                        None,
                        start + 1,
                        format!(
                            "dataset {ordinal}: binary dataset {n}b is not supported (binary: 58b only)"
                        ),
                    ))
                }
            }
        }
        Ok(out)
    }

    /// The next line of dataset `ds`; the end of the file here is an error (the dataset's
    /// closing `-1` is missing).
    fn dataset_line(&mut self, ds: Ds) -> Result<String> {
        match self.line()? {
            Some(l) => Ok(l),
            None => Err(self.err(
                Some(ds),
                None,
                self.line_no,
                "the file ends inside the dataset: expected its closing '    -1'".into(),
            )),
        }
    }

    /// Reads lines to the closing "-1"; returns them.
    fn skip_to_end(&mut self, ds: Ds) -> Result<Vec<String>> {
        let mut lines = Vec::new();
        loop {
            let l = self.dataset_line(ds)?;
            if l.trim() == "-1" {
                return Ok(lines);
            }
            if lines.len() < 4 {
                lines.push(l);
            }
        }
    }

    fn need_line(&mut self, ds: Ds, record: &str) -> Result<String> {
        match self.line()? {
            Some(l) if l.trim() == "-1" => Err(self.err(
                Some(ds),
                Some(record),
                self.line_no,
                format!("the dataset ends ('-1') where {record} was expected"),
            )),
            Some(l) => Ok(l),
            None => Err(self.err(
                Some(ds),
                Some(record),
                self.line_no + 1,
                format!("the file ends where {record} was expected"),
            )),
        }
    }

    /// Dataset 58 after its header line: a time response, a function [`Function`] (FRF,
    /// coherence, PSD), or `Skip(why)`: read past.
    /// One dataset 58 (a function at one point): the binary header when `binary`, records
    /// 1-11, the values of record 12, then a time response as a [`Record`] (function type 0
    /// or 1), a [`Function`] (4, 6, 9: [`Self::function_58`]), or a reason to skip it.
    fn dataset_58(
        &mut self,
        ds: Ds,
        header: &str,
        binary: bool,
        unit_code: Option<i64>,
    ) -> Result<Read58> {
        let bin = if binary {
            Some(self.binary_header_58(ds, header)?)
        } else {
            None
        };
        let h = self.records_58(ds)?;
        let (count, single) = self.value_count_58(ds, &h, bin.is_some())?;
        let (values, printed) = self.values_58(ds, &h, bin, count, single)?;
        if matches!(h.func_type, 4 | 6 | 9) {
            let head = Head58 {
                ds,
                id: &h.id,
                r6: &h.r6,
                r7_line: h.r7_line,
                axes: &h.axes,
                even: h.even,
                x0: h.x0,
                dx: h.dx,
                complex: matches!(h.ord_type, 5 | 6),
                unit_code,
            };
            return self.function_58(&head, h.func_type, values);
        }
        if !(h.func_type == 1 || h.func_type == 0) {
            return Ok(Read58::Skip(format!(
                "function type {} ({}), not a time response (1)",
                h.func_type,
                function_name(h.func_type)
            )));
        }
        if matches!(h.ord_type, 5 | 6) {
            return Ok(Read58::Skip("complex ordinate: not a time response".into()));
        }
        self.time_record_58(ds, h, values, &printed, unit_code)
    }

    /// A binary dataset 58's header line: `58b`, byte order, floating-point format, ASCII
    /// lines, bytes, 0 0 0 0. Returns (little-endian, bytes of binary data).
    fn binary_header_58(&self, ds: Ds, header: &str) -> Result<(bool, u64)> {
        let t: Vec<&str> = header.split_whitespace().collect();
        let fail = |msg: String| self.err(Some(ds), Some("binary header"), self.line_no, msg);
        let int = |k: usize, what: &str| -> Result<i64> {
            t.get(k).and_then(|v| v.parse::<i64>().ok()).ok_or_else(|| {
                fail(format!(
                    "field {} ({what}): expected a whole number, got '{}'",
                    k + 1,
                    t.get(k).unwrap_or(&"")
                ))
            })
        };
        let order = int(1, "byte order: 1 little-endian, 2 big-endian")?;
        let fp = int(2, "floating-point format: 2 IEEE 754")?;
        let ascii = int(3, "number of ASCII lines: 11")?;
        let bytes = int(4, "number of bytes of binary data")?;
        if !(order == 1 || order == 2) {
            return Err(fail(format!(
                "byte order {order}: expected 1 (little-endian) or 2 (big-endian)"
            )));
        }
        if fp != 2 {
            return Err(fail(format!(
                "floating-point format {fp}: only 2 (IEEE 754) is read"
            )));
        }
        if ascii != 11 {
            return Err(fail(format!(
                "{ascii} ASCII lines: expected 11 (records 1-11)"
            )));
        }
        if bytes < 0 || bytes as u64 > self.left {
            return Err(fail(format!(
                "{bytes} bytes of binary data announced, but only {} bytes are left in the file",
                self.left
            )));
        }
        Ok((order == 1, bytes as u64))
    }

    /// Records 1-11 of a dataset 58: the ID lines, record 6's function type and response
    /// point, record 7's data layout, records 8-11 (the axes).
    fn records_58(&mut self, ds: Ds) -> Result<Records58> {
        let mut id = Vec::with_capacity(5);
        for k in 1..=5 {
            id.push(self.need_line(ds, &format!("record {k} (ID line {k})"))?);
        }
        let r6 = self.need_line(ds, "record 6")?;
        let r6_line = self.line_no;
        let fx = |line: &str, a: usize, b: usize| -> String { cols(line, a, b).trim().to_string() };
        let int6 = |a: usize, b: usize, what: &str| -> Result<i64> {
            let s = fx(&r6, a, b);
            if s.is_empty() {
                return Ok(0);
            }
            s.parse::<i64>().map_err(|_| {
                self.err(
                    Some(ds),
                    Some("record 6"),
                    r6_line,
                    format!(
                        "{what} (columns {}-{b}): expected a whole number, got '{s}'",
                        a + 1
                    ),
                )
            })
        };
        let func_type = int6(0, 5, "function type")?;
        let rsp_entity = fx(&r6, 31, 41);
        let rsp_node = int6(41, 51, "response node")?;
        let rsp_dir = int6(51, 55, "response direction")?;

        let r7 = self.need_line(ds, "record 7")?;
        let r7_line = self.line_no;
        let (ord_type, npts, even, x0, dx) = parse_record7(&r7).ok_or_else(|| {
            self.err(
                Some(ds),
                Some("record 7"),
                r7_line,
                format!(
                    "expected 3I10,3E13.5: ordinate data type, number of points, spacing (0/1), abscissa minimum, increment, z value; got '{}'",
                    clip(&r7)
                ),
            )
        })?;
        let mut axes = Vec::with_capacity(4);
        for k in 8..=11 {
            let l = self.need_line(ds, &format!("record {k}"))?;
            axes.push((l, self.line_no));
        }
        Ok(Records58 {
            id,
            r6,
            func_type,
            rsp_entity,
            rsp_node,
            rsp_dir,
            r7_line,
            ord_type,
            npts,
            even,
            x0,
            dx,
            axes,
        })
    }

    /// The number of values record 12 holds (points × values per point) and whether they are
    /// single precision; a count the rest of the file cannot hold is refused before anything
    /// is allocated.
    fn value_count_58(&self, ds: Ds, h: &Records58, binary: bool) -> Result<(u64, bool)> {
        let (ord_type, even, npts, r7_line) = (h.ord_type, h.even, h.npts, h.r7_line);
        let per_point: u64 = match (ord_type, even) {
            (2 | 4, true) => 1,
            (2 | 4, false) => 2,
            (5 | 6, true) => 2,
            (5 | 6, false) => 3,
            _ => {
                return Err(self.err(
                    Some(ds),
                    Some("record 7"),
                    r7_line,
                    format!("ordinate data type {ord_type}: expected 2 (real single), 4 (real double), 5 (complex single) or 6 (complex double)"),
                ))
            }
        };
        if npts < 0 {
            return Err(self.err(
                Some(ds),
                Some("record 7"),
                r7_line,
                format!("number of points {npts}: expected ≥ 0"),
            ));
        }
        let count = (npts as u64).checked_mul(per_point).ok_or_else(|| {
            self.err(
                Some(ds),
                Some("record 7"),
                r7_line,
                format!("number of points {npts} is too large"),
            )
        })?;
        let single = matches!(ord_type, 2 | 5);
        // Every value takes at least 2 bytes in ASCII (a digit and a separator) and 4 or 8
        // in binary: a count the file cannot hold is refused before anything is allocated.
        let width: u64 = if single { 4 } else { 8 };
        let min_bytes = if binary {
            count.saturating_mul(width)
        } else {
            count.saturating_mul(2)
        };
        if min_bytes > self.left {
            return Err(self.err(
                Some(ds),
                Some("record 7"),
                r7_line,
                format!("{npts} points ({count} values) announced, but only {} bytes are left in the file", self.left),
            ));
        }
        Ok((count, single))
    }

    /// Record 12's values (binary or ASCII) and, for ASCII, half a unit of each value's last
    /// printed digit.
    fn values_58(
        &mut self,
        ds: Ds,
        h: &Records58,
        bin: Option<(bool, u64)>,
        count: u64,
        single: bool,
    ) -> Result<(Vec<f64>, Vec<f64>)> {
        let (ord_type, even, npts) = (h.ord_type, h.even, h.npts);
        let width: u64 = if single { 4 } else { 8 };
        let mut printed = Vec::new();
        let values = match bin {
            Some((little, bytes)) => {
                // pyuff (2.5.8) announces an uneven record's points, not its (x, y) pairs: the
                // pairs are read, and the closing "-1" right after them confirms the layout.
                let points_only = !even && bytes == count / 2 * width;
                if bytes != count * width && !points_only {
                    return Err(self.err(
                        Some(ds),
                        Some("binary header"),
                        ds.line + 1,
                        format!("{bytes} bytes announced, but record 7's {npts} points of type {ord_type} take {} bytes", count * width),
                    ));
                }
                let v = self.binary_values(ds, count, single, little)?;
                self.after_binary = true;
                // The closing "-1" (after an optional end of line).
                loop {
                    match self.line()? {
                        Some(l) if l.trim().is_empty() => continue,
                        Some(l) if l.trim() == "-1" => break,
                        Some(l) => {
                            return Err(self.err(Some(ds), None, self.line_no, format!("expected the closing '    -1' after {bytes} bytes of binary data, got '{}'", clip(&l))));
                        }
                        None => {
                            return Err(self.err(Some(ds), None, self.line_no, "the file ends after the binary data: expected the closing '    -1'".to_string()));
                        }
                    }
                }
                v
            }
            None => {
                let (v, half) = self.ascii_values(ds, count, ord_type, even)?;
                printed = half;
                v
            }
        };
        Ok((values, printed))
    }

    /// A time response (function type 0 or 1, real ordinate) as a [`Record`] in SI units: the
    /// axes' units, the abscissa (even, or uneven times that are an even grid as printed), the
    /// values' checks and scaling, the channel's name.
    fn time_record_58(
        &self,
        ds: Ds,
        h: Records58,
        values: Vec<f64>,
        printed: &[f64],
        unit_code: Option<i64>,
    ) -> Result<Read58> {
        let Records58 {
            id,
            rsp_entity,
            rsp_node,
            rsp_dir,
            r7_line,
            npts,
            even,
            x0,
            dx,
            axes,
            ..
        } = h;
        // Units: abscissa (record 8) and ordinate (record 9).
        let (xq, xf, xu) =
            self.axis_unit(ds, &axes[0].0, axes[0].1, "record 8 (abscissa)", unit_code)?;
        if xq != Quantity::Time {
            return Ok(Read58::Skip(format!(
                "the abscissa is {} ({xu}), not time",
                xq.name()
            )));
        }
        if let Some(why) = foreign_ordinate(&axes[1].0) {
            return Ok(Read58::Skip(why));
        }
        let (q, f, u) =
            self.axis_unit(ds, &axes[1].0, axes[1].1, "record 9 (ordinate)", unit_code)?;
        if q == Quantity::Time {
            return Err(self.err(Some(ds), Some("record 9 (ordinate)"), axes[1].1, format!("the ordinate unit '{u}' is a time: expected an acceleration, velocity, displacement or force")));
        }
        let n = npts as usize;
        let (abscissa, y) = if even {
            if !(dx.is_finite() && dx > 0.0 && x0.is_finite()) {
                return Err(self.err(Some(ds), Some("record 7"), r7_line, format!("even abscissa with minimum {x0} and increment {dx}: expected a finite minimum and an increment > 0")));
            }
            // The record's times in SI, its length N·Δt and its rate must be finite numbers:
            // an increment of 1e308 s makes the length of two samples infinite.
            let end = (x0 + n as f64 * dx) * xf;
            let rate = 1.0 / (dx * xf);
            if !((x0 * xf).is_finite() && end.is_finite() && rate.is_finite() && rate > 0.0) {
                return Err(self.err(Some(ds), Some("record 7"), r7_line, format!("even abscissa with minimum {} and increment {} ({xu}) over {n} points: the record's end (minimum + N·increment = {} s) or its sample rate ({} Hz) is not a finite number; expected an increment in {xu} that gives finite times (e.g. 1.953125E-05 s for 51.2 kHz)", crate::num(x0), crate::num(dx), crate::num(end), crate::num(rate))));
            }
            (
                Abscissa::Even {
                    start_s: x0 * xf,
                    step_s: dx * xf,
                },
                values,
            )
        } else {
            let mut t = Vec::with_capacity(n);
            let mut y = Vec::with_capacity(n);
            for c in values.chunks_exact(2) {
                t.push(c[0] * xf);
                y.push(c[1]);
            }
            if let Some(k) = t.iter().position(|v| !v.is_finite()) {
                return Err(self.err(Some(ds), Some("record 12"), r7_line + 5, format!("uneven abscissa: the time of point {} is {} s, not a finite number; expected times in {xu} that stay finite in seconds", k + 1, crate::num(t[k]))));
            }
            if let Some(k) = t
                .windows(2)
                .position(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
            {
                return Err(self.err(Some(ds), Some("record 12"), r7_line + 5, format!("uneven abscissa: time {} s at point {} does not increase to {} s at point {}", t[k], k + 1, t[k + 1], k + 2)));
            }
            // Times printed in decimal (ASCII) are even when an even grid lies within half a
            // unit of each one's last printed digit: pyuff's E13.5 rounds 51.2 kHz steps by up
            // to 5e-7 s, the format's rounding, not the sampling.
            let half: Vec<f64> = printed.iter().step_by(2).map(|h| h * xf).collect();
            match crate::record::even_as_printed(&t, &half) {
                Some((start_s, step_s)) => (Abscissa::Even { start_s, step_s }, y),
                None => (Abscissa::Uneven(t), y),
            }
        };
        let mut y = y;
        if let Some(k) = y.iter().position(|v| !v.is_finite()) {
            return Err(self.err(
                Some(ds),
                Some("record 12"),
                r7_line + 5,
                format!("point {} is not a finite number ({})", k + 1, y[k]),
            ));
        }
        if f != 1.0 {
            for v in &mut y {
                *v *= f;
            }
            if let Some(k) = y.iter().position(|v| !v.is_finite()) {
                return Err(self.err(
                    Some(ds),
                    Some("record 12"),
                    r7_line + 5,
                    format!(
                        "point {}: the value × {f} (to SI) is beyond the largest double: expected |value| ≤ {:e}",
                        k + 1,
                        f64::MAX / f
                    ),
                ));
            }
        }
        let name = {
            let n1 = id[0].trim();
            if !n1.is_empty() && n1 != "NONE" {
                n1.to_string()
            } else {
                format!(
                    "{}:{}:{}",
                    if rsp_entity.is_empty() {
                        "NONE"
                    } else {
                        &rsp_entity
                    },
                    rsp_node,
                    rsp_dir
                )
            }
        };
        Ok(Read58::Record(Record {
            name,
            quantity: q,
            source_unit: u,
            point: Some(PointRef {
                entity: rsp_entity,
                node: rsp_node,
                direction: rsp_dir,
            }),
            abscissa,
            values: y,
            origin: format!(
                "{}, dataset {} ({} at line {})",
                self.file, ds.ordinal, ds.kind, ds.line
            ),
        }))
    }

    /// A dataset 58 of function type 4, 6 or 9 ([`Function`]), its values read (`values`: as
    /// record 12 holds them).
    fn function_58(&self, h: &Head58, func_type: i64, values: Vec<f64>) -> Result<Read58> {
        let ds = h.ds;
        let int = |a: usize, b: usize, what: &str| -> Result<i64> {
            let t = cols(h.r6, a, b).trim().to_string();
            if t.is_empty() {
                return Ok(0);
            }
            t.parse::<i64>().map_err(|_| {
                self.err(
                    Some(ds),
                    Some("record 6"),
                    h.r7_line - 1,
                    format!(
                        "{what} (columns {}-{b}): expected a whole number, got '{t}'",
                        a + 1
                    ),
                )
            })
        };
        let response = PointRef {
            entity: cols(h.r6, 31, 41).trim().to_string(),
            node: int(41, 51, "response node")?,
            direction: int(51, 55, "response direction")?,
        };
        let reference = PointRef {
            entity: cols(h.r6, 56, 66).trim().to_string(),
            node: int(66, 76, "reference node")?,
            direction: int(76, 80, "reference direction")?,
        };
        // Abscissa: frequency in Hz (specific data type 18, or a label Hz).
        let (xl, xl_line) = (&h.axes[0].0, h.axes[0].1);
        let xt = cols(xl, 0, 10).trim().parse::<i64>().unwrap_or(0);
        let xu = cols(xl, 47, 67).trim().to_string();
        let hz = xu.eq_ignore_ascii_case("hz");
        if !(hz || ((xu.is_empty() || xu.eq_ignore_ascii_case("NONE")) && matches!(xt, 0 | 18))) {
            return Err(self.err(Some(ds), Some("record 8 (abscissa)"), xl_line, format!("a function of type {func_type} ({}) needs a frequency abscissa in Hz (specific data type 18 or unit label 'Hz'), got data type {xt}, unit '{xu}'", function_name(func_type))));
        }
        let per = if h.complex { 2 } else { 1 } + usize::from(!h.even);
        let mut f = Vec::with_capacity(values.len() / per);
        let mut v = Vec::with_capacity(values.len() / per);
        for (k, c) in values.chunks_exact(per).enumerate() {
            let (x, rest) = if h.even {
                (h.x0 + k as f64 * h.dx, c)
            } else {
                (c[0], &c[1..])
            };
            f.push(x);
            v.push(num_complex::Complex64::new(
                rest[0],
                if h.complex { rest[1] } else { 0.0 },
            ));
        }
        if let Some(k) = f.iter().position(|x| !x.is_finite()) {
            return Err(self.err(
                Some(ds),
                Some("record 12"),
                h.r7_line + 5,
                format!("the frequency of point {} is not a finite number", k + 1),
            ));
        }
        if let Some(k) = v
            .iter()
            .position(|x| !(x.re.is_finite() && x.im.is_finite()))
        {
            return Err(self.err(
                Some(ds),
                Some("record 12"),
                h.r7_line + 5,
                format!("point {} is not a finite number", k + 1),
            ));
        }
        let (numerator, denominator, factor) = match func_type {
            4 => {
                if let Some(why) = foreign_ordinate(&h.axes[1].0) {
                    return Ok(Read58::Skip(why));
                }
                let (qn, fnum, _) = self.axis_unit(
                    ds,
                    &h.axes[1].0,
                    h.axes[1].1,
                    "record 9 (ordinate numerator)",
                    h.unit_code,
                )?;
                let (qd, fden, ud) = self.axis_unit(
                    ds,
                    &h.axes[2].0,
                    h.axes[2].1,
                    "record 10 (ordinate denominator)",
                    h.unit_code,
                )?;
                if qd != Quantity::Force {
                    return Err(self.err(Some(ds), Some("record 10 (ordinate denominator)"), h.axes[2].1, format!("an FRF's denominator must be a force (N, kN, lbf; data type 13), got {} ({ud})", qd.name())));
                }
                (Some(qn), Some(qd), fnum / fden)
            }
            9 => {
                let line = &h.axes[1].0;
                let ty = cols(line, 0, 10).trim().parse::<i64>().unwrap_or(0);
                let label = cols(line, 47, 67).trim().to_string();
                let by_type = Quantity::from_uff_data_type(ty);
                let inner = label
                    .trim_end_matches("/Hz")
                    .trim_end_matches("^2")
                    .trim_end_matches("**2")
                    .trim_end_matches('²')
                    .trim_start_matches('(')
                    .trim_end_matches(')')
                    .to_string();
                match (label.is_empty() || label.eq_ignore_ascii_case("NONE"), by_type) {
                    (true, Some(q)) => (Some(q), None, 1.0),
                    _ => match crate::record::units::parse_unit(&inner) {
                        Some((q, fu)) if by_type.is_none_or(|t| t == q) => (Some(q), None, fu * fu),
                        _ => return Ok(Read58::Skip(format!("power spectral density in '{label}' (data type {ty}): expected (unit)^2/Hz of an acceleration, velocity, displacement or force"))),
                    },
                }
            }
            _ => (None, None, 1.0),
        };
        if factor != 1.0 {
            for x in &mut v {
                *x *= factor;
            }
        }
        let keep = |l: &String| {
            let t = l.trim();
            (!t.is_empty() && t != "NONE").then(|| t.to_string())
        };
        Ok(Read58::Function(Function {
            function_type: func_type,
            name: keep(&h.id[0]).unwrap_or_else(|| {
                format!(
                    "{}:{}:{}",
                    response.entity, response.node, response.direction
                )
            }),
            id_lines: h.id[1..].iter().filter_map(keep).collect(),
            response,
            reference,
            frequency_hz: f,
            values: v,
            numerator,
            denominator,
            origin: format!(
                "{}, dataset {} ({} at line {})",
                self.file, ds.ordinal, ds.kind, ds.line
            ),
        }))
    }

    /// The quantity, factor to SI and unit text of an axis record (8-11).
    fn axis_unit(
        &self,
        ds: Ds,
        line: &str,
        line_no: usize,
        record: &str,
        unit_code: Option<i64>,
    ) -> Result<(Quantity, f64, String)> {
        let ty_s = cols(line, 0, 10).trim().to_string();
        let ty = if ty_s.is_empty() {
            Ok(0)
        } else {
            ty_s.parse::<i64>()
        };
        let Ok(ty) = ty else {
            return Err(self.err(
                Some(ds),
                Some(record),
                line_no,
                format!("specific data type (columns 1-10): expected a whole number, got '{ty_s}'"),
            ));
        };
        let label = cols(line, 47, 67).trim().to_string();
        let by_type = Quantity::from_uff_data_type(ty);
        if label.is_empty() || label.eq_ignore_ascii_case("NONE") {
            return match (by_type, unit_code) {
                (Some(q), None | Some(1)) => Ok((q, 1.0, q.si_unit().to_string())),
                (Some(_), Some(c)) => Err(self.err(Some(ds), Some(record), line_no, format!("no unit label (columns 48-67), and dataset 164 sets unit system {c}, not SI (1): label the axis with its unit ({ACCEPTED_UNITS})"))),
                (None, _) => Err(self.err(Some(ds), Some(record), line_no, format!("no unit label (columns 48-67 are '{label}') and specific data type {ty} ({}) does not say the quantity: expected a unit label ({ACCEPTED_UNITS}) or data type 17 (time), 12 (acceleration), 11 (velocity), 8 (displacement), 13 or 9 (force)", data_type_name(ty)))),
            };
        }
        let Some((q, f)) = parse_unit(&label) else {
            return Err(self.err(
                Some(ds),
                Some(record),
                line_no,
                format!("unknown unit '{label}' (columns 48-67): expected one of {ACCEPTED_UNITS}"),
            ));
        };
        if let Some(tq) = by_type {
            if tq != q {
                return Err(self.err(
                    Some(ds),
                    Some(record),
                    line_no,
                    format!(
                        "the unit '{label}' is a {} but the specific data type {ty} says {}",
                        q.name(),
                        tq.name()
                    ),
                ));
            }
        }
        Ok((q, f, label))
    }

    fn binary_values(
        &mut self,
        ds: Ds,
        count: u64,
        single: bool,
        little: bool,
    ) -> Result<Vec<f64>> {
        let width = if single { 4 } else { 8 };
        let total = count * width as u64;
        let mut v = Vec::with_capacity(count.min(self.left / width as u64) as usize);
        let mut chunk = vec![0u8; 1 << 16];
        let mut done = 0u64;
        while done < total {
            let take = ((total - done) as usize).min(chunk.len());
            let c = &mut chunk[..take];
            self.r.read_exact(c).map_err(|e| {
                if e.kind() == std::io::ErrorKind::UnexpectedEof {
                    self.err(Some(ds), Some("record 12 (binary)"), self.line_no, format!("the file ends inside the binary data: {total} bytes announced, fewer present"))
                } else {
                    Error::io(self.file, e)
                }
            })?;
            self.left = self.left.saturating_sub(take as u64);
            if single {
                for b in c.chunks_exact(4) {
                    let a = [b[0], b[1], b[2], b[3]];
                    v.push(if little {
                        f32::from_le_bytes(a)
                    } else {
                        f32::from_be_bytes(a)
                    } as f64);
                }
            } else {
                for b in c.chunks_exact(8) {
                    let a = [b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]];
                    v.push(if little {
                        f64::from_le_bytes(a)
                    } else {
                        f64::from_be_bytes(a)
                    });
                }
            }
            done += take as u64;
        }
        Ok(v)
    }

    /// The `count` values of an ASCII record 12, and, for an uneven abscissa (`!even`), half a
    /// unit of the last digit each was printed with ([`printed_half_unit`]; empty otherwise).
    fn ascii_values(
        &mut self,
        ds: Ds,
        count: u64,
        ord_type: i64,
        even: bool,
    ) -> Result<(Vec<f64>, Vec<f64>)> {
        // Fixed widths of the fields, for lines whose numbers touch (no blank between).
        let widths: &[usize] = match (ord_type, even) {
            (2 | 5, _) => &[13],
            (4, false) => &[13, 20],
            (6, false) => &[13, 20, 20],
            _ => &[20],
        };
        let mut v: Vec<f64> = Vec::with_capacity(count.min(self.left / 2) as usize);
        let mut half: Vec<f64> = Vec::new();
        let first = self.line_no + 1;
        loop {
            let Some(l) = self.line()? else {
                return Err(self.err(
                    Some(ds),
                    Some("record 12"),
                    self.line_no,
                    format!(
                        "the file ends inside the data: {} of {count} values read",
                        v.len()
                    ),
                ));
            };
            if l.trim() == "-1" {
                break;
            }
            let before = v.len();
            let mut ok = true;
            for tok in l.split_whitespace() {
                match parse_f(tok) {
                    Some(x) => {
                        v.push(x);
                        if !even {
                            half.push(printed_half_unit(tok));
                        }
                    }
                    None => {
                        ok = false;
                        break;
                    }
                }
            }
            if !ok {
                v.truncate(before);
                half.truncate(before.min(half.len()));
                let mut at = 0usize;
                let mut k = 0usize;
                let bytes = l.as_bytes();
                while at < bytes.len() {
                    let w = widths[k % widths.len()];
                    let field =
                        String::from_utf8_lossy(&bytes[at..(at + w).min(bytes.len())]).into_owned();
                    if field.trim().is_empty() {
                        break;
                    }
                    let Some(x) = parse_f(field.trim()) else {
                        return Err(self.err(
                            Some(ds),
                            Some("record 12"),
                            self.line_no,
                            format!(
                                "value {}: expected a number, got '{}'",
                                v.len() + 1,
                                clip(field.trim())
                            ),
                        ));
                    };
                    v.push(x);
                    if !even {
                        half.push(printed_half_unit(field.trim()));
                    }
                    at += w;
                    k += 1;
                }
            }
            if v.len() as u64 > count {
                return Err(self.err(
                    Some(ds),
                    Some("record 12"),
                    self.line_no,
                    format!("more values than the {count} record 7 announces"),
                ));
            }
        }
        if (v.len() as u64) < count {
            return Err(self.err(
                Some(ds),
                Some("record 12"),
                self.line_no,
                format!(
                    "the data (from line {first}) holds {} values; record 7 announces {count}",
                    v.len()
                ),
            ));
        }
        Ok((v, half))
    }

    fn dataset_2411(&mut self, ds: Ds) -> Result<Vec<Node>> {
        let mut out = Vec::new();
        loop {
            let l1 = self.dataset_line(ds)?;
            if l1.trim() == "-1" {
                return Ok(out);
            }
            let n1 = self.line_no;
            let label = l1
                .split_whitespace()
                .next()
                .and_then(|t| t.parse::<i64>().ok())
                .ok_or_else(|| {
                    self.err(
                        Some(ds),
                        Some("record 1"),
                        n1,
                        format!(
                            "expected 4I10 (node label, coordinate systems, colour), got '{}'",
                            clip(&l1)
                        ),
                    )
                })?;
            // Field 3: the displacement coordinate system, in which the node's data (dataset
            // 55's shapes) are given. meid reads them as global: 0 or 1 (the global part
            // system, which meid and pyuff write); a local system (defined by a dataset 2420
            // meid does not read) or none at all is refused, never read as global.
            let ints: Vec<Option<i64>> = l1.split_whitespace().map(|t| t.parse().ok()).collect();
            match ints.get(2) {
                Some(Some(0 | 1)) => {}
                Some(Some(cs)) => {
                    return Err(self.err(
                        Some(ds),
                        Some("record 1"),
                        n1,
                        format!("node {label}: displacement coordinate system {cs} is a local system; meid reads node data in the global system (0 or 1) and does not convert: export the nodes and mode shapes in global coordinates"),
                    ))
                }
                _ => {
                    return Err(self.err(
                        Some(ds),
                        Some("record 1"),
                        n1,
                        format!(
                            "node {label}: no displacement coordinate system (field 3 of 4I10: node label, export system, displacement system, colour), got '{}'; give 1 (global)",
                            clip(&l1)
                        ),
                    ))
                }
            }
            let l2 = self.need_line(ds, "record 2")?;
            let xyz: Vec<f64> = l2.split_whitespace().filter_map(parse_f).collect();
            if xyz.len() != 3 || xyz.iter().any(|v| !v.is_finite()) {
                return Err(self.err(
                    Some(ds),
                    Some("record 2"),
                    self.line_no,
                    format!(
                        "node {label}: expected 3 finite coordinates (1P3D25.16), got '{}'",
                        clip(&l2)
                    ),
                ));
            }
            out.push(Node {
                label,
                xyz: [xyz[0], xyz[1], xyz[2]],
            });
        }
    }

    /// Datasets 15 (nodes), 82 (a trace line) and 2412 (elements) into `out`.
    fn geometry_dataset(
        &mut self,
        num: u32,
        ordinal: usize,
        start: usize,
        out: &mut UffFile,
    ) -> Result<()> {
        let kind = match num {
            15 => "15",
            82 => "82",
            _ => "2412",
        };
        let ds = Ds {
            ordinal,
            kind,
            line: start,
        };
        match num {
            15 => out.nodes.extend(self.dataset_15(ds)?),
            82 => out.traces.push(self.dataset_82(ds)?),
            _ => out.elements.extend(self.dataset_2412(ds)?),
        }
        Ok(())
    }

    /// Dataset 15: one node a line, `4I10,3E13.5` (whitespace-separated when it has 7 fields).
    fn dataset_15(&mut self, ds: Ds) -> Result<Vec<Node>> {
        let mut out = Vec::new();
        loop {
            let l = self.dataset_line(ds)?;
            if l.trim() == "-1" {
                return Ok(out);
            }
            let ws: Vec<&str> = l.split_whitespace().collect();
            let fields: Vec<String> = if ws.len() == 7 {
                ws.iter().map(|t| t.to_string()).collect()
            } else {
                [
                    (0, 10),
                    (10, 20),
                    (20, 30),
                    (30, 40),
                    (40, 53),
                    (53, 66),
                    (66, 79),
                ]
                .iter()
                .map(|&(a, b)| cols(&l, a, b).trim().to_string())
                .collect()
            };
            let label = fields[0].parse::<i64>().ok();
            let xyz: Vec<f64> = fields[4..].iter().filter_map(|t| parse_f(t)).collect();
            match (label, xyz.len() == 3 && xyz.iter().all(|v| v.is_finite())) {
                (Some(label), true) => out.push(Node {
                    label,
                    xyz: [xyz[0], xyz[1], xyz[2]],
                }),
                _ => {
                    return Err(self.err(
                        Some(ds),
                        Some("record 1"),
                        self.line_no,
                        format!(
                            "expected 4I10,3E13.5 (node label, coordinate systems, colour, x, y, z), got '{}'",
                            clip(&l)
                        ),
                    ))
                }
            }
        }
    }

    /// Whole numbers of a line (`what` names them in the error).
    fn ints(&self, ds: Ds, record: &str, l: &str, what: &str) -> Result<Vec<i64>> {
        l.split_whitespace()
            .map(|t| t.parse::<i64>().ok())
            .collect::<Option<Vec<i64>>>()
            .ok_or_else(|| {
                self.err(
                    Some(ds),
                    Some(record),
                    self.line_no,
                    format!("expected whole numbers ({what}), got '{}'", clip(l)),
                )
            })
    }

    /// Dataset 82: a trace line (module docs).
    fn dataset_82(&mut self, ds: Ds) -> Result<TraceLine> {
        let l1 = self.need_line(ds, "record 1")?;
        let head = self.ints(
            ds,
            "record 1",
            &l1,
            "trace line number, number of nodes, colour",
        )?;
        if head.len() < 2 {
            return Err(self.err(
                Some(ds),
                Some("record 1"),
                self.line_no,
                format!(
                    "expected 3I10 (trace line number, number of nodes, colour), got '{}'",
                    clip(&l1)
                ),
            ));
        }
        let name = self.need_line(ds, "record 2")?.trim().to_string();
        let mut nodes = Vec::new();
        loop {
            let l = self.dataset_line(ds)?;
            if l.trim() == "-1" {
                break;
            }
            nodes.extend(self.ints(ds, "record 3", &l, "node labels")?);
        }
        Ok(TraceLine {
            number: head[0],
            color: head.get(2).copied().unwrap_or(0),
            name,
            nodes,
        })
    }

    /// Dataset 2412: elements (module docs).
    fn dataset_2412(&mut self, ds: Ds) -> Result<Vec<Element>> {
        let mut out = Vec::new();
        loop {
            let l1 = self.dataset_line(ds)?;
            if l1.trim() == "-1" {
                return Ok(out);
            }
            let r1 = self.ints(
                ds,
                "record 1",
                &l1,
                "element label, FE descriptor, property tables, colour, number of nodes",
            )?;
            let &[label, fe_descriptor, _, _, color, count] = r1.as_slice() else {
                return Err(self.err(
                    Some(ds),
                    Some("record 1"),
                    self.line_no,
                    format!("expected 6I10, got '{}'", clip(&l1)),
                ));
            };
            if BEAM_DESCRIPTORS.contains(&fe_descriptor) {
                self.need_line(ds, "record 2")?;
            }
            let mut nodes = Vec::new();
            while (nodes.len() as i64) < count {
                let l = self.need_line(ds, "record 3")?;
                nodes.extend(self.ints(ds, "record 3", &l, "node labels")?);
            }
            if nodes.len() as i64 != count {
                return Err(self.err(
                    Some(ds),
                    Some("record 3"),
                    self.line_no,
                    format!(
                        "element {label}: {} node labels, record 1 announces {count}",
                        nodes.len()
                    ),
                ));
            }
            out.push(Element {
                label,
                fe_descriptor,
                color,
                nodes,
            });
        }
    }

    /// Dataset 164's records 1 and 2 ([`Units`]) from its lines.
    fn dataset_164(&self, ds: Ds, lines: &[String]) -> Result<Units> {
        let r1 = lines.first().map_or("", String::as_str);
        let code_s = cols(r1, 0, 10).trim().to_string();
        let Ok(code) = code_s.parse::<i64>() else {
            return Err(self.err(
                Some(ds),
                Some("record 1"),
                ds.line + 2,
                format!("unit code (columns 1-10): expected a whole number (1 SI, 5 MM, 9 user, ...), got '{code_s}'"),
            ));
        };
        let description = cols(r1, 10, 30).trim().to_string();
        let r2 = lines.get(1).map_or("", String::as_str);
        // Whitespace-separated when possible (pyuff writes %25.16e with D), else 3D25.17.
        let ws: Vec<f64> = r2.split_whitespace().filter_map(parse_f).collect();
        let f: Vec<f64> = if ws.len() == 3 {
            ws
        } else {
            (0..3)
                .filter_map(|k| parse_f(cols(r2, 25 * k, 25 * (k + 1)).trim()))
                .collect()
        };
        match f[..] {
            [length, force, _] if length.is_finite() && length > 0.0 && force.is_finite() && force > 0.0 => Ok(Units {
                code,
                description,
                length,
                force,
            }),
            _ => Err(self.err(
                Some(ds),
                Some("record 2"),
                ds.line + 3,
                format!(
                    "expected three unit factors (length, force, temperature; 3D25.17) with length and force finite and > 0 (SI: 1 1 1; mm-t-s: 1000 1 1), got '{}'",
                    clip(r2)
                ),
            )),
        }
    }

    fn dataset_55(&mut self, ds: Ds) -> Result<std::result::Result<Mode, String>> {
        let mut id = Vec::new();
        for k in 1..=5 {
            id.push(self.need_line(ds, &format!("record {k} (ID line {k})"))?);
        }
        let r6 = self.need_line(ds, "record 6")?;
        let ints = |l: &str| -> Vec<i64> {
            l.split_whitespace()
                .filter_map(|t| t.parse().ok())
                .collect()
        };
        let h = ints(&r6);
        if h.len() < 6 {
            return Err(self.err(Some(ds), Some("record 6"), self.line_no, format!("expected 6I10 (model type, analysis type, data characteristic, specific data type, data type, values per node), got '{}'", clip(&r6))));
        }
        let (analysis, data_type, ndv) = (h[1], h[4], h[5]);
        let r7 = self.need_line(ds, "record 7")?;
        let r7v = ints(&r7);
        let r8 = self.need_line(ds, "record 8")?;
        let r8v: Vec<f64> = r8.split_whitespace().filter_map(parse_f).collect();
        let real = matches!(data_type, 2 | 4);
        if analysis != 2 || !real || !(ndv == 3 || ndv == 6) {
            self.skip_to_end(ds)?;
            return Ok(Err(format!("analysis type {analysis}, data type {data_type}, {ndv} values per node: meid reads real normal modes (2, 2 or 4, 3 or 6)")));
        }
        if r7v.len() < 4 || r8v.len() < 3 {
            return Err(self.err(
                Some(ds),
                Some("records 7-8"),
                self.line_no,
                "expected 2 4 load-case mode-number, then frequency, modal mass, damping ratio"
                    .into(),
            ));
        }
        // Record 7 declares the number of integer (NINT) and real (NRDV) values that follow:
        // the data must hold exactly that many.
        let (nint, nrdv) = (r7v[0], r7v[1]);
        if usize::try_from(nint).ok() != Some(r7v.len() - 2) {
            return Err(self.err(
                Some(ds),
                Some("record 7"),
                self.line_no - 1,
                format!(
                    "declares {nint} integer values (NINT, field 1) but holds {}: '{}'",
                    r7v.len() - 2,
                    clip(&r7)
                ),
            ));
        }
        let mut r8v = r8v;
        if usize::try_from(nrdv).ok() != Some(r8v.len()) {
            // Fixed 13-column fields (numbers touching).
            r8v = r8
                .as_bytes()
                .chunks(13)
                .filter_map(|c| parse_f(String::from_utf8_lossy(c).trim()))
                .collect();
        }
        if usize::try_from(nrdv).ok() != Some(r8v.len()) {
            return Err(self.err(Some(ds), Some("record 8"), self.line_no, format!("record 7 declares {nrdv} real values (NRDV, field 2) but record 8 holds {}: '{}'", r8v.len(), clip(&r8))));
        }
        // Read as fixed fields, record 8 may hold fewer numbers than its free-field reading did.
        if r8v.len() < 3 {
            return Err(self.err(
                Some(ds),
                Some("record 8"),
                self.line_no,
                format!(
                    "expected frequency, modal mass and damping ratio (3 real values), got {}: '{}'",
                    r8v.len(),
                    clip(&r8)
                ),
            ));
        }
        let mut shapes = Vec::new();
        loop {
            let l = self.dataset_line(ds)?;
            if l.trim() == "-1" {
                break;
            }
            let node = l.trim().parse::<i64>().map_err(|_| {
                self.err(
                    Some(ds),
                    Some("record 9"),
                    self.line_no,
                    format!("expected a node number (I10), got '{}'", clip(&l)),
                )
            })?;
            let d = self.need_line(ds, "record 10")?;
            let mut v: Vec<f64> = d.split_whitespace().filter_map(parse_f).collect();
            if v.len() != ndv as usize {
                // Fixed 13-column fields (numbers touching).
                v = d
                    .as_bytes()
                    .chunks(13)
                    .filter_map(|c| parse_f(String::from_utf8_lossy(c).trim()))
                    .collect();
            }
            if v.len() != ndv as usize || v.iter().any(|x| !x.is_finite()) {
                return Err(self.err(
                    Some(ds),
                    Some("record 10"),
                    self.line_no,
                    format!(
                        "node {node}: expected {ndv} finite values, got '{}'",
                        clip(&d)
                    ),
                ));
            }
            shapes.push((node, [v[0], v[1], v[2]]));
        }
        Ok(Ok(Mode {
            number: r7v[3],
            frequency_hz: r8v[0],
            modal_mass: r8v[1],
            damping_ratio: r8v[2],
            name: id[0].trim().to_string(),
            id_lines: id[1..]
                .iter()
                .map(|l| l.trim())
                .filter(|l| !l.is_empty() && *l != "NONE")
                .map(str::to_string)
                .collect(),
            shapes,
            units: None,
        }))
    }
}

/// Columns `[a, b)` of a line (byte positions; a short line gives what there is).
fn cols(line: &str, a: usize, b: usize) -> String {
    let bytes = line.as_bytes();
    if a >= bytes.len() {
        return String::new();
    }
    String::from_utf8_lossy(&bytes[a..b.min(bytes.len())]).into_owned()
}

/// A number in Fortran or C notation (`1.5E+00`, `1.5D+00`, `1.5e0`).
/// Half a unit of the last digit of a number printed in decimal (`1.95312E-05` → 0.5e-10,
/// `0.25` → 0.005, `12` → 0.5; Fortran's `D` exponent as `E`): the rounding the printing may
/// have made. Infinite for a token that is not such a number (no precision to rely on).
fn printed_half_unit(tok: &str) -> f64 {
    let t = tok.trim_start_matches(['+', '-']);
    let (mantissa, exponent) = match t.find(['E', 'e', 'D', 'd']) {
        Some(i) => (&t[..i], t[i + 1..].parse::<i32>().ok()),
        None => (t, Some(0)),
    };
    let Some(e) = exponent else {
        return f64::INFINITY;
    };
    let decimals = match mantissa.split_once('.') {
        Some((_, frac)) => frac.len() as i32,
        None => 0,
    };
    0.5 * 10f64.powi(e.saturating_sub(decimals))
}

fn parse_f(s: &str) -> Option<f64> {
    if s.contains(['D', 'd']) {
        s.replace(['D', 'd'], "E").parse().ok()
    } else {
        s.parse().ok()
    }
}

/// Record 7: whitespace-separated when possible, else fixed columns 3I10,3E13.5.
fn parse_record7(l: &str) -> Option<(i64, i64, bool, f64, f64)> {
    let t: Vec<&str> = l.split_whitespace().collect();
    let ws = || -> Option<(i64, i64, i64, f64, f64)> {
        if t.len() < 5 {
            return None;
        }
        Some((
            t[0].parse().ok()?,
            t[1].parse().ok()?,
            t[2].parse().ok()?,
            parse_f(t[3])?,
            parse_f(t[4])?,
        ))
    };
    let fixed = || -> Option<(i64, i64, i64, f64, f64)> {
        Some((
            cols(l, 0, 10).trim().parse().ok()?,
            cols(l, 10, 20).trim().parse().ok()?,
            cols(l, 20, 30).trim().parse().ok()?,
            parse_f(cols(l, 30, 43).trim())?,
            parse_f(cols(l, 43, 56).trim())?,
        ))
    };
    let (a, b, c, d, e) = ws().or_else(fixed)?;
    match c {
        0 => Some((a, b, false, d, e)),
        1 => Some((a, b, true, d, e)),
        _ => None,
    }
}

/// Unit labels of quantities meid does not process (sound pressure, voltage, current,
/// strain, temperature, rotational speed, frequency, level, mass), matched exactly after
/// trimming.
const FOREIGN_UNITS: [&str; 28] = [
    "Pa", "kPa", "MPa", "mPa", "bar", "mbar", "psi", "V", "mV", "uV", "µV", "A", "mA", "uE", "µE",
    "ue", "µε", "strain", "°C", "degC", "C", "K", "°F", "rpm", "RPM", "Hz", "dB", "kg",
];

/// Why a dataset 58's ordinate (record 9 line `line`) is a quantity meid does not process (a
/// microphone, strain gauge, thermocouple or tachometer channel recorded beside the
/// accelerometers), so that the dataset is passed over rather than the file refused: a specific
/// data type of 2 or more that is none of meid's (17, 12, 11, 8, 9, 13), or, for types 0
/// (unknown) and 1 (general), a unit label of [`FOREIGN_UNITS`]. `None`: the ordinate is for
/// [`Parser::axis_unit`] to read (or refuse).
fn foreign_ordinate(line: &str) -> Option<String> {
    let ty = cols(line, 0, 10).trim().parse::<i64>().unwrap_or(0);
    let label = cols(line, 47, 67).trim().to_string();
    let shown = if label.is_empty() { "NONE" } else { &label };
    if ty >= 2 && Quantity::from_uff_data_type(ty).is_none() {
        return Some(format!(
            "the ordinate is specific data type {ty} ({}, unit '{shown}'), not an acceleration, velocity, displacement or force",
            data_type_name(ty)
        ));
    }
    if matches!(ty, 0 | 1) && FOREIGN_UNITS.contains(&label.as_str()) {
        return Some(format!(
            "the ordinate's unit '{label}' (specific data type {ty}, {}) is not an acceleration, velocity, displacement or force",
            data_type_name(ty)
        ));
    }
    None
}

use crate::input::clip;

fn function_name(t: i64) -> &'static str {
    match t {
        0 => "general or unknown",
        1 => "time response",
        2 => "auto spectrum",
        3 => "cross spectrum",
        4 => "frequency response function",
        5 => "transmissibility",
        6 => "coherence",
        9 => "power spectral density",
        _ => "other",
    }
}

fn data_type_name(t: i64) -> &'static str {
    match t {
        0 => "unknown",
        1 => "general",
        2 => "stress",
        3 => "strain",
        5 => "temperature",
        6 => "heat flux",
        15 => "pressure",
        16 => "mass",
        18 => "frequency",
        19 => "rpm",
        20 => "order",
        _ => "not a quantity meid reads",
    }
}

// ------------------------------------------------------------------------------------ writing

/// One channel to write as dataset 58 (even abscissa, time in s, values in SI).
#[derive(Debug, Clone)]
pub struct Channel58<'a> {
    /// ID line 1 (the channel name).
    pub name: &'a str,
    /// Response entity (≤ 10 characters are kept), node and direction (3 = +Z).
    pub point: PointRef,
    pub quantity: Quantity,
    pub start_s: f64,
    pub step_s: f64,
    /// Values in [`Quantity::si_unit`].
    pub values: &'a [f64],
}

/// `v` as C's `%W.De` (sign, `D` decimals, exponent with a sign and at least 2 digits),
/// right-aligned in `width`.
pub fn format_e(v: f64, decimals: usize, width: usize) -> String {
    let s = format!("{v:.decimals$e}");
    let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
    let e: i32 = e.parse().unwrap_or(0);
    let t = format!("{m}e{}{:02}", if e < 0 { '-' } else { '+' }, e.abs());
    format!("{t:>width$}")
}

/// `v` in a 13-column field with as many digits as fit after one blank (the shortest form
/// that reads back exactly when it fits; the abscissa of record 7).
fn format_e13(v: f64) -> String {
    let s = format!("{v:e}");
    let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
    let e: i32 = e.parse().unwrap_or(0);
    let t = format!("{m}e{}{:02}", if e < 0 { '-' } else { '+' }, e.abs());
    if t.len() <= 12 {
        return format!("{t:>13}");
    }
    for d in (1..=8).rev() {
        let t = format_e(v, d, 0);
        if t.len() <= 12 {
            return format!("{t:>13}");
        }
    }
    format_e(v, 5, 13)
}

fn finite(values: &[f64], what: &str) -> Result<()> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(k) => Err(Error::invalid(
            what,
            format!("sample {k} is not finite ({})", values[k]),
        )),
        None => Ok(()),
    }
}

/// Writes one dataset 58 (function type 1, time response). ASCII: real double precision,
/// four values a line in `%20.12e` (13 significant digits, as history.csv; a negative value with a three-digit exponent fills all 20 columns, which fixed-width readers such as pyuff and meid read). Binary (58b): little-endian IEEE
/// doubles, exact. Records 8 and 9 carry the SI unit labels and the specific data types.
pub fn write_58<W: Write>(w: &mut W, ch: &Channel58, binary: bool) -> std::io::Result<()> {
    if let Err(e) = finite(ch.values, ch.name) {
        return Err(std::io::Error::other(e.to_string()));
    }
    let n = ch.values.len();
    write!(w, "{:>6}\n{:>6}", -1, 58)?;
    if binary {
        writeln!(
            w,
            "b{:>6}{:>6}{:>12}{:>12}{:>6}{:>6}{:>12}{:>12}",
            1,
            2,
            11,
            n * 8,
            0,
            0,
            0,
            0
        )?;
    } else {
        writeln!(w, "{:74}", "")?;
    }
    let line80 = |s: &str| -> String {
        let t: String = s.chars().filter(|c| !c.is_control()).take(80).collect();
        format!("{t:<80}")
    };
    writeln!(w, "{}", line80(ch.name))?;
    writeln!(w, "{}", line80("written by meid"))?;
    writeln!(w, "{}", line80("NONE"))?;
    writeln!(w, "{}", line80("NONE"))?;
    writeln!(w, "{}", line80("NONE"))?;
    let ent: String = ch
        .point
        .entity
        .chars()
        .filter(|c| !c.is_whitespace())
        .take(10)
        .collect();
    let ent = if ent.is_empty() {
        "NONE".to_string()
    } else {
        ent
    };
    writeln!(
        w,
        "{:>5}{:>10}{:>5}{:>10} {:>10}{:>10}{:>4} {:>10}{:>10}{:>4}",
        1, 0, 0, 0, ent, ch.point.node, ch.point.direction, "NONE", 0, 0
    )?;
    writeln!(
        w,
        "{:>10}{:>10}{:>10}{}{}{}",
        4,
        n,
        1,
        format_e13(ch.start_s),
        format_e13(ch.step_s),
        format_e13(0.0)
    )?;
    let axis = |w: &mut W, q: Option<Quantity>, label: &str| -> std::io::Result<()> {
        let (ty, (le, fe, te), unit) = match q {
            Some(q) => (q.uff_data_type(), q.uff_exponents(), q.si_unit()),
            None => (0, (0, 0, 0), "NONE"),
        };
        writeln!(w, "{ty:>10}{le:>5}{fe:>5}{te:>5} {label:<20} {unit:<20}")
    };
    axis(w, Some(Quantity::Time), "Time")?;
    axis(w, Some(ch.quantity), &capitalise(ch.quantity.name()))?;
    axis(w, None, "NONE")?;
    axis(w, None, "NONE")?;
    if binary {
        let mut buf = Vec::with_capacity(n.min(8192) * 8);
        for c in ch.values.chunks(8192) {
            buf.clear();
            for v in c {
                buf.extend_from_slice(&v.to_le_bytes());
            }
            w.write_all(&buf)?;
        }
    } else {
        write_e20_lines(w, ch.values)?;
    }
    writeln!(w, "{:>6}", -1)
}

/// Values as ASCII `4E20.12` lines (four to a line), the layout of dataset 58's data.
fn write_e20_lines(w: &mut impl Write, values: &[f64]) -> std::io::Result<()> {
    let mut line = String::with_capacity(82);
    for c in values.chunks(4) {
        line.clear();
        for v in c {
            line.push_str(&format_e(*v, 12, 20));
        }
        line.push('\n');
        w.write_all(line.as_bytes())?;
    }
    Ok(())
}

/// Writes a [`Function`] as one dataset 58 (ASCII): an FRF (type 4) as complex double
/// (`4E20.12`, two values a line) with records 9 and 10 the numerator's and the denominator's SI
/// units and data types; a coherence (6) or PSD (9) as real double. The frequencies must be
/// even (`f_0 + kΔf`).
pub fn write_58_function<W: Write>(w: &mut W, f: &Function) -> std::io::Result<()> {
    let n = f.values.len();
    if n < 2 || f.frequency_hz.len() != n {
        return Err(std::io::Error::other(format!(
            "function '{}': {n} values for {} frequencies (at least 2)",
            f.name,
            f.frequency_hz.len()
        )));
    }
    let f0 = f.frequency_hz[0];
    let df = (f.frequency_hz[n - 1] - f0) / (n - 1) as f64;
    if !(df > 0.0 && df.is_finite())
        || f.values
            .iter()
            .any(|v| !(v.re.is_finite() && v.im.is_finite()))
    {
        return Err(std::io::Error::other(format!(
            "function '{}': the frequencies must increase evenly and the values be finite",
            f.name
        )));
    }
    let complex = f.function_type == 4;
    writeln!(w, "{:>6}\n{:>6}{:74}", -1, 58, "")?;
    let line80 = |s: &str| -> String {
        let t: String = s.chars().filter(|c| !c.is_control()).take(80).collect();
        format!("{t:<80}")
    };
    writeln!(w, "{}", line80(&f.name))?;
    for k in 0..4 {
        writeln!(
            w,
            "{}",
            line80(f.id_lines.get(k).map_or("NONE", String::as_str))
        )?;
    }
    let ent = |p: &PointRef| -> String {
        let e: String = p
            .entity
            .chars()
            .filter(|c| !c.is_whitespace())
            .take(10)
            .collect();
        if e.is_empty() {
            "NONE".into()
        } else {
            e
        }
    };
    writeln!(
        w,
        "{:>5}{:>10}{:>5}{:>10} {:>10}{:>10}{:>4} {:>10}{:>10}{:>4}",
        f.function_type,
        0,
        0,
        0,
        ent(&f.response),
        f.response.node,
        f.response.direction,
        ent(&f.reference),
        f.reference.node,
        f.reference.direction
    )?;
    writeln!(
        w,
        "{:>10}{:>10}{:>10}{}{}{}",
        if complex { 6 } else { 4 },
        n,
        1,
        format_e13(f0),
        format_e13(df),
        format_e13(0.0)
    )?;
    writeln!(
        w,
        "{:>10}{:>5}{:>5}{:>5} {:<20} {:<20}",
        18, 0, 0, 0, "Frequency", "Hz"
    )?;
    let axis = |w: &mut W, q: Option<Quantity>, label: &str| -> std::io::Result<()> {
        let (ty, (le, fe, te), unit) = match q {
            Some(q) => (q.uff_data_type(), q.uff_exponents(), q.si_unit()),
            None => (0, (0, 0, 0), "NONE"),
        };
        writeln!(w, "{ty:>10}{le:>5}{fe:>5}{te:>5} {label:<20} {unit:<20}")
    };
    let name = |q: Option<Quantity>| q.map_or("NONE".to_string(), |q| capitalise(q.name()));
    axis(w, f.numerator, &name(f.numerator))?;
    axis(w, f.denominator, &name(f.denominator))?;
    axis(w, None, "NONE")?;
    let flat: Vec<f64> = if complex {
        f.values.iter().flat_map(|v| [v.re, v.im]).collect()
    } else {
        f.values.iter().map(|v| v.re).collect()
    };
    write_e20_lines(w, &flat)?;
    writeln!(w, "{:>6}", -1)
}

fn capitalise(s: &str) -> String {
    let mut c = s.chars();
    match c.next() {
        Some(f) => f.to_uppercase().chain(c).collect(),
        None => String::new(),
    }
}

/// Writes dataset 164 (the unit system of the datasets after it, [`Units`]): records 1-3 as
/// pyuff writes them (`%10i%20s%10i`, then the factors `%25.16e` with a `D` exponent; the
/// temperature factor 1, mode 1 (absolute), offset 273.15).
pub fn write_164<W: Write>(w: &mut W, units: &Units) -> std::io::Result<()> {
    writeln!(w, "{:>6}\n{:>6}{:74}", -1, 164, "")?;
    let description: String = units
        .description
        .chars()
        // Byte columns: ASCII only.
        .map(|c| {
            if c.is_ascii() && !c.is_control() {
                c
            } else {
                '?'
            }
        })
        .take(20)
        .collect();
    writeln!(w, "{:>10}{description:>20}{:>10}", units.code, 1)?;
    let d = |x: f64| {
        // Rust writes `1e3` as `1.0000000000000000e3`: the exponent gets its sign and two digits.
        let t = format!("{x:.16e}");
        let (m, e) = t.split_once('e').unwrap_or((&t, "0"));
        let e: i32 = e.parse().unwrap_or(0);
        format!(
            "{:>25}",
            format!("{m}D{}{:02}", if e < 0 { '-' } else { '+' }, e.abs())
        )
    };
    writeln!(w, "{}{}{}", d(units.length), d(units.force), d(1.0))?;
    writeln!(w, "{}", d(273.15))?;
    writeln!(w, "{:>6}", -1)
}

/// Writes dataset 2411 (nodes, double precision: 4I10 then 1P3D25.16, here `%25.16e`).
pub fn write_2411<W: Write>(w: &mut W, nodes: &[Node]) -> std::io::Result<()> {
    writeln!(w, "{:>6}\n{:>6}{:74}", -1, 2411, "")?;
    for n in nodes {
        writeln!(w, "{:>10}{:>10}{:>10}{:>10}", n.label, 1, 1, 11)?;
        writeln!(
            w,
            "{}{}{}",
            format_e(n.xyz[0], 16, 25),
            format_e(n.xyz[1], 16, 25),
            format_e(n.xyz[2], 16, 25)
        )?;
    }
    writeln!(w, "{:>6}", -1)
}

/// Writes dataset 15 (nodes, single precision: `4I10,3E13.5`, as pyuff writes it; global
/// coordinate systems 0).
pub fn write_15<W: Write>(w: &mut W, nodes: &[Node]) -> std::io::Result<()> {
    writeln!(w, "{:>6}\n{:>6}{:74}", -1, 15, "")?;
    for n in nodes {
        writeln!(
            w,
            "{:>10}{:>10}{:>10}{:>10}{}{}{}",
            n.label,
            0,
            0,
            11,
            format_e(n.xyz[0], 5, 13),
            format_e(n.xyz[1], 5, 13),
            format_e(n.xyz[2], 5, 13)
        )?;
    }
    writeln!(w, "{:>6}", -1)
}

/// Node labels `8I10` a line.
fn write_i10_lines<W: Write>(w: &mut W, labels: &[i64]) -> std::io::Result<()> {
    for chunk in labels.chunks(8) {
        let line: String = chunk.iter().map(|n| format!("{n:>10}")).collect();
        writeln!(w, "{line}")?;
    }
    Ok(())
}

/// Writes dataset 82 (one trace line; module docs).
pub fn write_82<W: Write>(w: &mut W, t: &TraceLine) -> std::io::Result<()> {
    writeln!(w, "{:>6}\n{:>6}{:74}", -1, 82, "")?;
    writeln!(w, "{:>10}{:>10}{:>10}", t.number, t.nodes.len(), t.color)?;
    let name: String = t
        .name
        .chars()
        .filter(|c| !c.is_control())
        .take(80)
        .collect();
    writeln!(
        w,
        "{:<80}",
        if name.is_empty() { "NONE".into() } else { name }
    )?;
    write_i10_lines(w, &t.nodes)?;
    writeln!(w, "{:>6}", -1)
}

/// Writes dataset 2412 (elements; module docs): property tables 1, beams with orientation
/// node 0 and cross sections 0.
pub fn write_2412<W: Write>(w: &mut W, elements: &[Element]) -> std::io::Result<()> {
    writeln!(w, "{:>6}\n{:>6}{:74}", -1, 2412, "")?;
    for e in elements {
        writeln!(
            w,
            "{:>10}{:>10}{:>10}{:>10}{:>10}{:>10}",
            e.label,
            e.fe_descriptor,
            1,
            1,
            e.color,
            e.nodes.len()
        )?;
        if BEAM_DESCRIPTORS.contains(&e.fe_descriptor) {
            writeln!(w, "{:>10}{:>10}{:>10}", 0, 0, 0)?;
        }
        write_i10_lines(w, &e.nodes)?;
    }
    writeln!(w, "{:>6}", -1)
}

/// Writes dataset 55 for one real normal mode (analysis type 2, 3 translations per node,
/// data type 2 as pyuff and most readers expect: `%13.5e` values, 6 significant digits).
/// Modal mass 1 means mass-normalised shapes. ID line 1 is `mode.name`, ID lines 2-5
/// `mode.id_lines` (clipped to 80 characters, `NONE` where there is none).
pub fn write_55<W: Write>(w: &mut W, mode: &Mode) -> std::io::Result<()> {
    writeln!(w, "{:>6}\n{:>6}{:74}", -1, 55, "")?;
    let line80 = |s: &str| -> String {
        format!(
            "{:<80}",
            s.chars()
                .filter(|c| !c.is_control())
                .take(80)
                .collect::<String>()
        )
    };
    writeln!(w, "{}", line80(&mode.name))?;
    for k in 0..4 {
        let l = mode.id_lines.get(k).map_or("NONE", String::as_str);
        writeln!(w, "{}", line80(l))?;
    }
    // Structural model, normal mode, 3 DOF translation, displacement, real single, 3 values.
    writeln!(w, "{:>10}{:>10}{:>10}{:>10}{:>10}{:>10}", 1, 2, 2, 8, 2, 3)?;
    writeln!(w, "{:>10}{:>10}{:>10}{:>10}", 2, 4, 1, mode.number)?;
    writeln!(
        w,
        "{}{}{}{}",
        format_e(mode.frequency_hz, 5, 13),
        format_e(mode.modal_mass, 5, 13),
        format_e(mode.damping_ratio, 5, 13),
        format_e(0.0, 5, 13)
    )?;
    for (node, v) in &mode.shapes {
        writeln!(w, "{node:>10}")?;
        writeln!(
            w,
            "{}{}{}",
            format_e(v[0], 5, 13),
            format_e(v[1], 5, 13),
            format_e(v[2], 5, 13)
        )?;
    }
    writeln!(w, "{:>6}", -1)
}

/// Writes evenly sampled records as datasets 58, one per record, in order; the response node
/// is the record's position (1-based) unless the record names its point. `file` names the
/// destination in errors (a full disk is reported as that file's error).
pub fn write_records<W: Write>(
    w: &mut W,
    records: &[Record],
    binary: bool,
    file: &Path,
) -> Result<()> {
    for (k, r) in records.iter().enumerate() {
        let (start_s, step_s) = r.even()?;
        let point = r.point.clone().unwrap_or(PointRef {
            entity: r.name.split('_').next().unwrap_or("NONE").to_string(),
            node: k as i64 + 1,
            direction: 3,
        });
        let ch = Channel58 {
            name: &r.name,
            point,
            quantity: r.quantity,
            start_s,
            step_s,
            values: &r.values,
        };
        write_58(w, &ch, binary).map_err(|e| Error::io(file, e))?;
    }
    Ok(())
}

/// Node numbering of [`modes_uff_points`]: node label `k` (1-based) is the `k`-th named point of
/// the modal model in name order (byte order of the names, the order of the
/// `psi_<P>_per_sqrt_kg` columns of `modes.csv`). Returns `(label, name)` pairs.
pub fn point_node_labels(m: &crate::modal::ModalModel) -> Vec<(i64, String)> {
    m.points
        .keys()
        .enumerate()
        .map(|(k, p)| (k as i64 + 1, p.clone()))
        .collect()
}

/// ID lines 2-5 of the datasets 55 of [`modes_uff_points`]: who wrote the file, the numbering
/// rule and as many `label = name` pairs as two more lines of 80 columns hold (the list ends
/// with `...` when it is cut; the rule of line 3 holds for every node).
fn point_id_lines(labels: &[(i64, String)]) -> Vec<String> {
    let mut lines = vec![
        "written by meid: lumped/tabulated model; z translation = signed psi, 1/sqrt(kg)"
            .to_string(),
        "node k = k-th point by name as in modes.csv; node at x = k-1 m (no geometry)".to_string(),
    ];
    // " 1 = base," ... " n = name": whole pairs only, on "nodes:" and one more line; when not
    // all fit, the second line keeps 4 columns for " ...".
    let items: Vec<String> = labels
        .iter()
        .enumerate()
        .map(|(k, (label, name))| {
            let comma = if k + 1 < labels.len() { "," } else { "" };
            format!(" {label} = {name}{comma}")
        })
        .collect();
    let pack = |last_cap: usize| -> (Vec<String>, usize) {
        let mut out = vec![String::from("nodes:")];
        let mut placed = 0;
        for it in &items {
            let cap = if out.len() == 1 { 80 } else { last_cap };
            let cur = out.last().map_or(0, |l| l.chars().count());
            if cur + it.chars().count() <= cap {
                if let Some(l) = out.last_mut() {
                    l.push_str(it);
                }
            } else if out.len() == 1 && it.chars().count() - 1 <= last_cap {
                out.push(it.trim_start().to_string());
            } else {
                break;
            }
            placed += 1;
        }
        (out, placed)
    };
    let (mut list, placed) = pack(80);
    if placed < items.len() {
        list = pack(76).0;
        if let Some(l) = list.last_mut() {
            l.push_str(" ...");
        }
    }
    lines.extend(list);
    lines
}

/// The unit system meid's mode exports declare (dataset 164, code 1).
fn si_units() -> Units {
    Units {
        description: "SI - m, N, kg, s".into(),
        ..Units::si()
    }
}

/// Dataset 164 (SI) + 2411 + one dataset 55 per mode of a modal model's named points. A lumped or
/// tabulated model has no geometry: node `k` is the `k`-th named point in name order
/// ([`point_node_labels`], the column order of `modes.csv`), placed at x = k − 1 m, y = z = 0
/// (coordinates for display only). Its z translation is the signed mass-normalised shape value
/// `ψ_i(P)` along the impact direction (1/√kg, modal mass 1; import it back with
/// `impact_direction = [0, 0, 1]`); x and y are 0. ID line 1 is the mode's label, ID lines 2-5
/// state this rule and the `label = name` pairs. Damping ratios are `D_ii / (2 ω_i)` (0 for
/// rigid-body modes).
pub fn modes_uff_points(m: &crate::modal::ModalModel) -> Result<Vec<u8>> {
    let labels = point_node_labels(m);
    let nodes: Vec<Node> = labels
        .iter()
        .map(|(label, _)| Node {
            label: *label,
            xyz: [(*label - 1) as f64, 0.0, 0.0],
        })
        .collect();
    let id_lines = point_id_lines(&labels);
    let n = m.omega_rad_per_s.len();
    let mut out = Vec::new();
    write_164(&mut out, &si_units()).map_err(|e| Error::io("modes.uff (in memory)", e))?;
    write_2411(&mut out, &nodes).map_err(|e| Error::io("modes.uff (in memory)", e))?;
    for i in 0..n {
        let w = m.omega_rad_per_s[i];
        let d = m.damping.get(i * n + i).copied().unwrap_or(0.0);
        let mode = Mode {
            number: i as i64 + 1,
            frequency_hz: w / (2.0 * std::f64::consts::PI),
            modal_mass: 1.0,
            damping_ratio: if w > 0.0 { d / (2.0 * w) } else { 0.0 },
            name: m
                .labels
                .get(i)
                .cloned()
                .unwrap_or_else(|| format!("mode {}", i + 1)),
            id_lines: id_lines.clone(),
            shapes: labels
                .iter()
                .map(|(label, p)| (*label, [0.0, 0.0, m.points[p][i]]))
                .collect(),
            units: Some(si_units()),
        };
        write_55(&mut out, &mode).map_err(|e| Error::io("modes.uff (in memory)", e))?;
    }
    Ok(out)
}

/// Dataset 164 (SI) + 2411 (every mesh node, label = index + 1, coordinates in m) + one dataset 55 per
/// computed mode (nodal translations of the mass-normalised shapes, modal mass 1) of an FE
/// analysis; `zeta[i]` the modal damping ratios (missing: 0).
pub fn modes_uff_fe(
    model: &crate::structure::assembly::FeModel,
    modes: &crate::modal::dense::DenseModes,
    zeta: &[f64],
) -> Result<Vec<u8>> {
    let nodes: Vec<Node> = model
        .mesh
        .nodes
        .iter()
        .enumerate()
        .map(|(k, p)| Node {
            label: k as i64 + 1,
            xyz: *p,
        })
        .collect();
    let mut out = Vec::new();
    write_164(&mut out, &si_units()).map_err(|e| Error::io("modes.uff (in memory)", e))?;
    write_2411(&mut out, &nodes).map_err(|e| Error::io("modes.uff (in memory)", e))?;
    for i in 0..modes.omega_rad_per_s.len() {
        let t = super::vtk::mode_translations(model, modes, i)?;
        let mode = Mode {
            number: i as i64 + 1,
            frequency_hz: modes.omega_rad_per_s[i] / (2.0 * std::f64::consts::PI),
            modal_mass: 1.0,
            damping_ratio: zeta.get(i).copied().unwrap_or(0.0),
            name: format!("mode {}", i + 1),
            id_lines: vec![
                "written by meid: FE mesh; node label = mesh node index + 1 (modes.vtu order)"
                    .into(),
                "x y z translations of the mass-normalised shape (1/sqrt(kg)), global axes".into(),
            ],
            shapes: t
                .iter()
                .enumerate()
                .map(|(k, v)| (k as i64 + 1, *v))
                .collect(),
            units: Some(si_units()),
        };
        write_55(&mut out, &mode).map_err(|e| Error::io("modes.uff (in memory)", e))?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ch(values: &[f64]) -> Channel58<'_> {
        Channel58 {
            name: "bed_acceleration",
            point: PointRef {
                entity: "bed".into(),
                node: 1,
                direction: 3,
            },
            quantity: Quantity::Acceleration,
            start_s: 0.0,
            step_s: 1.0 / 51200.0,
            values,
        }
    }

    #[test]
    fn format_e_is_c_style() {
        assert_eq!(format_e(1.0, 11, 20), "   1.00000000000e+00");
        assert_eq!(format_e(-1.5e-100, 11, 20), " -1.50000000000e-100");
        assert_eq!(format_e13(1.0 / 51200.0), " 1.953125e-05");
        assert_eq!(format_e13(5e-5), "        5e-05");
        assert_eq!(format_e13(1.0 / 3.0).len(), 13);
        assert_eq!(
            parse_f(format_e13(1.0 / 51200.0).trim()),
            Some(1.0 / 51200.0)
        );
    }

    #[test]
    fn binary_58b_round_trips_exactly_and_ascii_to_13_digits() {
        let v: Vec<f64> = (0..103)
            .map(|i| (i as f64 * 0.37).sin() * 1e3 + 1e-7 * i as f64)
            .collect();
        for binary in [true, false] {
            let mut buf = Vec::new();
            write_58(&mut buf, &ch(&v), binary).unwrap();
            write_58(&mut buf, &ch(&v[..5]), binary).unwrap();
            let f = parse_uff(&buf[..], "mem.uff", Some(buf.len() as u64)).unwrap();
            assert_eq!(f.records.len(), 2);
            let r = &f.records[0];
            assert_eq!(r.name, "bed_acceleration");
            assert_eq!(r.quantity, Quantity::Acceleration);
            assert_eq!(r.point.as_ref().unwrap().label(), "bed:1 +Z");
            assert_eq!(r.even().unwrap(), (0.0, 1.0 / 51200.0));
            for (a, b) in r.values.iter().zip(&v) {
                if binary {
                    assert_eq!(a, b);
                } else {
                    assert!((a - b).abs() <= 5e-13 * b.abs().max(1e-300), "{a} {b}");
                }
            }
            assert_eq!(f.records[1].values.len(), 5);
        }
    }

    fn header(unit: &str, ty: i64, n: usize, even: i64) -> String {
        format!(
            "    -1\n    58\nacc g\nNONE\nNONE\nNONE\nNONE\n    1         0    0         0 NONE               1   3 NONE               0   0\n         2{n:>10}{even:>10}  0.00000e+00  1.00000e-03  0.00000e+00\n        17    0    0    0 Time                 s                   \n{ty:>10}    0    0    0 Acc                  {unit:<20}\n         0    0    0    0 NONE                 NONE                \n         0    0    0    0 NONE                 NONE                \n"
        )
    }

    #[test]
    fn g_and_mm_per_s2_convert_and_uneven_abscissa_reads() {
        let text = format!(
            "{}  1.00000e+00  2.00000e+00 -5.00000e-01\n    -1\n",
            header("g", 12, 3, 1)
        );
        let f = parse_uff(text.as_bytes(), "g.uff", None).unwrap();
        let r = &f.records[0];
        assert_eq!(r.values, vec![9.80665, 2.0 * 9.80665, -0.5 * 9.80665]);
        assert_eq!(r.source_unit, "g");
        let text = format!("{}  0.00000e+00  1.00000e+03  1.00000e-03  2.00000e+03  2.50000e-03  0.00000e+00\n    -1\n", header("mm/s^2", 0, 3, 0));
        let f = parse_uff(text.as_bytes(), "u.uff", None).unwrap();
        let r = &f.records[0];
        assert_eq!(r.values, vec![1.0, 2.0, 0.0]);
        assert_eq!(r.abscissa, Abscissa::Uneven(vec![0.0, 1e-3, 2.5e-3]));
        assert!(r.even().is_err());
    }

    /// Python's `%13.5e` (pyuff's abscissa field): 6 significant digits, an exponent of at
    /// least two digits, right-aligned in 13 columns.
    fn py_e(x: f64, decimals: usize, width: usize) -> String {
        let s = format!("{x:.decimals$e}");
        let (m, e) = s.split_once('e').unwrap();
        let e: i32 = e.parse().unwrap();
        let sign = if e < 0 { '-' } else { '+' };
        format!("{:>width$}", format!("{m}e{sign}{:02}", e.abs()))
    }

    /// An ASCII dataset 58 of real double (x, y) pairs written as pyuff writes them,
    /// `2(E13.5,E20.12)` a line (record 7: type 4, spacing 0).
    fn pairs_58(t: &[f64], y: &[f64]) -> String {
        let mut s = format!(
            "    -1\n    58\nacc\nNONE\nNONE\nNONE\nNONE\n    1         0    0         0 NONE               1   3 NONE               0   0\n         4{:>10}         0  0.00000e+00  0.00000e+00  0.00000e+00\n        17    0    0    0 Time                 s                   \n        12    0    0    0 Acc                  m/s^2               \n         0    0    0    0 NONE                 NONE                \n         0    0    0    0 NONE                 NONE                \n",
            t.len()
        );
        for (k, (tk, yk)) in t.iter().zip(y).enumerate() {
            s += &py_e(*tk, 5, 13);
            s += &py_e(*yk, 12, 20);
            if k % 2 == 1 || k + 1 == y.len() {
                s.push('\n');
            }
        }
        s + "    -1\n"
    }

    /// pyuff writes an even 51.2 kHz grid over 1 s as (x, y) pairs with 6 significant digits in
    /// x: its steps read 19.5312 or 19.5313 µs (up to 5.3e-7 s off near 1 s), the printing's
    /// rounding. Even within half a unit of each time's last printed digit, it reads as even at
    /// 51.2 kHz. A time moved by 2 units of its last digit (2e-6 s, a tenth of a step) is a grid
    /// no printing explains: uneven, and refused for spectra.
    #[test]
    fn times_printed_to_six_digits_are_judged_by_their_printed_precision() {
        assert_eq!(printed_half_unit("1.95312e-05"), 0.5e-10);
        assert_eq!(printed_half_unit("1.0D+00"), 0.05);
        assert_eq!(printed_half_unit("-0.25"), 0.005);
        assert_eq!(printed_half_unit("12"), 0.5);
        let fs = 51200.0;
        let t: Vec<f64> = (0..51200).map(|k| k as f64 / fs).collect();
        let y: Vec<f64> = t.iter().map(|t| (1775.0 * t).sin()).collect();
        let text = pairs_58(&t, &y);
        assert!(text.contains("  9.99980e-01"), "pyuff's layout");
        let f = parse_uff(text.as_bytes(), "pyuff.uff", None).unwrap();
        let r = &f.records[0];
        let Abscissa::Even { start_s, step_s } = r.abscissa else {
            panic!("{:?}", &r.abscissa);
        };
        assert!(start_s.abs() <= 1e-12, "{start_s}");
        assert!((step_s * fs - 1.0).abs() <= 1e-9, "{step_s}");
        assert!((r.sample_rate_hz().unwrap() - fs).abs() <= 1e-6 * fs);
        for (a, b) in r.values.iter().zip(&y) {
            assert!((a - b).abs() <= 1e-12, "{a} {b}");
        }
        let mut moved = t.clone();
        moved[25600] += 2e-6;
        let f = parse_uff(pairs_58(&moved, &y).as_bytes(), "moved.uff", None).unwrap();
        let r = &f.records[0];
        assert!(matches!(r.abscissa, Abscissa::Uneven(_)));
        let e = r.even().unwrap_err().to_string();
        assert!(e.contains("uneven") && e.contains("moved.uff"), "{e}");
    }

    /// Channels of quantities meid does not process, recorded beside the accelerometer (a
    /// microphone in Pa, type 15; a strain gauge, type 3; a bridge in V, type 1), are passed over
    /// with the reason, and the file's other channels read (session 12 audit: a microphone
    /// channel made the whole file unreadable, "unknown unit 'Pa'"). A contradiction (type 12
    /// in N) or an unknown unit of one of meid's types is still refused.
    #[test]
    fn channels_of_other_quantities_are_passed_over_not_refused() {
        let data = "  1.00000e+00  2.00000e+00 -5.00000e-01\n    -1\n";
        let text = [
            header("g", 12, 3, 1),
            data.into(),
            header("Pa", 15, 3, 1),
            data.into(),
            header("NONE", 3, 3, 1),
            data.into(),
            header("V", 1, 3, 1),
            data.into(),
        ]
        .concat();
        let f = parse_uff(text.as_bytes(), "lab.uff", None).unwrap();
        assert_eq!(f.records.len(), 1);
        assert_eq!(f.records[0].values[1], 2.0 * 9.80665);
        assert_eq!(f.skipped.len(), 3, "{:?}", f.skipped);
        assert!(
            f.skipped[0].starts_with("dataset 2 (58 at line 16)")
                && f.skipped[0].contains("specific data type 15 (pressure, unit 'Pa')"),
            "{:?}",
            f.skipped
        );
        assert!(f.skipped[1].contains("type 3 (strain, unit 'NONE')"));
        assert!(f.skipped[2].contains("unit 'V' (specific data type 1, general)"));
        // Type 0 without a unit says nothing of the quantity: refused, as before.
        let text = format!("{}{data}", header("NONE", 0, 3, 1));
        let e = parse_uff(text.as_bytes(), "lab.uff", None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("does not say the quantity"), "{e}");
    }

    /// Binary uneven 58b whose header announces the points' bytes rather than the (x, y)
    /// pairs' (pyuff 2.5.8) reads, the closing "-1" after the pairs confirming the layout;
    /// any other count is refused.
    #[test]
    fn binary_uneven_with_the_points_bytes_announced_reads() {
        let file = |announced: usize| -> Vec<u8> {
            let mut b = format!("    -1\n    58b     1     2          11{announced:>12}     0     0           0           0\nacc\nNONE\nNONE\nNONE\nNONE\n    1         0    0         0 NONE               1   3 NONE               0   0\n         4         3         0  0.00000e+00  0.00000e+00  0.00000e+00\n        17    0    0    0 Time                 s                   \n        12    0    0    0 Acc                  g                   \n         0    0    0    0 NONE                 NONE                \n         0    0    0    0 NONE                 NONE                \n").into_bytes();
            for (t, y) in [(0.0f64, 1.0f64), (1e-3, 2.0), (2.5e-3, -0.5)] {
                b.extend_from_slice(&t.to_le_bytes());
                b.extend_from_slice(&y.to_le_bytes());
            }
            b.extend_from_slice(b"\n    -1\n");
            b
        };
        for announced in [48, 24] {
            let f = parse_uff(&file(announced)[..], "u.uff", None).unwrap();
            let r = &f.records[0];
            assert_eq!(r.values, vec![9.80665, 2.0 * 9.80665, -0.5 * 9.80665]);
            assert_eq!(r.abscissa, Abscissa::Uneven(vec![0.0, 1e-3, 2.5e-3]));
        }
        let e = parse_uff(&file(40)[..], "u.uff", None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("40 bytes announced"), "{e}");
    }

    /// A finite value that overflows when converted to SI (1e308 g) is refused naming the
    /// dataset, record and point, with the valid bound (session 11: no inf reaches a spectrum).
    #[test]
    fn values_beyond_the_largest_double_in_si_are_refused() {
        let text = format!(
            "{}  1.00000e+00  1.00000e+308 -5.00000e-01\n    -1\n",
            header("g", 12, 3, 1)
        );
        let e = parse_uff(text.as_bytes(), "g.uff", None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("g.uff: dataset 1")
                && e.contains("record 12")
                && e.contains("point 2")
                && e.contains("beyond the largest double"),
            "{e}"
        );
    }

    #[test]
    fn errors_name_file_dataset_record_and_line() {
        let text = format!("{}  1.0\n    -1\n", header("furlong/s^2", 12, 1, 1));
        let e = parse_uff(text.as_bytes(), "lab.uff", None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("lab.uff: dataset 1 (58 starting at line 1), record 9 (ordinate), line 11")
                && e.contains("unknown unit 'furlong/s^2'"),
            "{e}"
        );
        let text = format!("{}  1.0\n    -1\n", header("N", 12, 1, 1));
        let e = parse_uff(text.as_bytes(), "lab.uff", None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("is a force but the specific data type 12 says acceleration"),
            "{e}"
        );
        let text = format!("{}  1.0  2.0\n    -1\n", header("g", 12, 3, 1));
        let e = parse_uff(text.as_bytes(), "lab.uff", None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("record 12") && e.contains("holds 2 values; record 7 announces 3"),
            "{e}"
        );
        // A huge point count is refused before any allocation.
        let text = format!("{}  1.0\n    -1\n", header("g", 12, 1_000_000_000, 1));
        let e = parse_uff(text.as_bytes(), "lab.uff", Some(text.len() as u64))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("record 7") && e.contains("bytes are left"),
            "{e}"
        );
        let e = parse_uff(&b"    -1\n    58b     1     2          11    999999999     0     0           0           0\n"[..], "b.uff", Some(90)).unwrap_err().to_string();
        assert!(
            e.contains("binary header") && e.contains("bytes are left"),
            "{e}"
        );
    }

    /// ID lines of a lumped model's modes: the rule, then `label = name` pairs over two lines
    /// of at most 80 columns, cut with `...` when they do not fit.
    #[test]
    fn point_id_lines_list_the_names_within_80_columns() {
        let few = vec![(1, "base".to_string()), (2, "bed".to_string())];
        let l = point_id_lines(&few);
        assert_eq!(l.len(), 3);
        assert_eq!(l[2], "nodes: 1 = base, 2 = bed");
        assert!(l.iter().all(|x| x.chars().count() <= 80), "{l:?}");
        let many: Vec<(i64, String)> = (1..=40).map(|k| (k, format!("point_{k:02}"))).collect();
        let l = point_id_lines(&many);
        assert_eq!(l.len(), 4);
        assert!(l.iter().all(|x| x.chars().count() <= 80), "{l:?}");
        assert!(
            l[2].starts_with("nodes: 1 = point_01, 2 = point_02,"),
            "{l:?}"
        );
        assert!(l[3].ends_with(" ..."), "{l:?}");
        // Every pair listed is whole and right.
        let listed: Vec<&str> = l[2]
            .trim_start_matches("nodes:")
            .split(',')
            .chain(l[3].trim_end_matches(" ...").split(','))
            .map(str::trim)
            .filter(|x| !x.is_empty())
            .collect();
        assert!(listed.len() > 8, "{listed:?}");
        for (k, x) in listed.iter().enumerate() {
            assert_eq!(*x, format!("{} = point_{:02}", k + 1, k + 1));
        }
    }

    #[test]
    fn nodes_and_modes_round_trip() {
        let nodes = vec![
            Node {
                label: 1,
                xyz: [0.0, 0.5, 1.25],
            },
            Node {
                label: 7,
                xyz: [-1.0, 2.0, 3.0e-3],
            },
        ];
        let mode = Mode {
            number: 2,
            frequency_hz: 283.0,
            modal_mass: 1.0,
            damping_ratio: 0.01,
            name: "mode 2".into(),
            id_lines: vec!["written by meid".into(), "second line".into()],
            shapes: vec![(1, [0.0, 0.0, 0.25]), (7, [0.0, 0.0, -0.125])],
            units: Some(Units {
                code: 9,
                description: "mm t s N".into(),
                length: 1000.0,
                force: 1.0,
            }),
        };
        let mut buf = Vec::new();
        write_164(&mut buf, mode.units.as_ref().unwrap()).unwrap();
        write_2411(&mut buf, &nodes).unwrap();
        write_55(&mut buf, &mode).unwrap();
        let text = String::from_utf8(buf.clone()).unwrap();
        // pyuff's layout (`%10i%20s%10i`, `%25.16e` with D exponents).
        assert!(text.contains(
            "         9            mm t s N         1\n   1.0000000000000000D+03   1.0000000000000000D+00   1.0000000000000000D+00\n   2.7314999999999998D+02\n"
        ), "{text}");
        let f = parse_uff(&buf[..], "m.unv", None).unwrap();
        assert_eq!(f.nodes, nodes);
        assert_eq!(f.modes, vec![mode]);
        // Without a dataset 164 a mode has no units (the UFF default, SI).
        let mut plain = Vec::new();
        write_55(&mut plain, &f.modes[0]).unwrap();
        let g = parse_uff(&plain[..], "p.unv", None).unwrap();
        assert_eq!(g.modes[0].units, None);
    }

    /// A 2411 node in a local displacement coordinate system (or with none given) is refused,
    /// naming the node: its shapes would be read in the wrong axes. 0 and 1 (global) read.
    #[test]
    fn nodes_in_a_local_or_undefined_coordinate_system_are_refused() {
        let nodes = vec![Node {
            label: 5,
            xyz: [0.0, 0.5, 1.25],
        }];
        let mut buf = Vec::new();
        write_2411(&mut buf, &nodes).unwrap();
        let text = String::from_utf8(buf).unwrap();
        let line = "         5         1         1        11";
        assert!(text.contains(line), "{text}");
        for (cs, ok) in [("0", true), ("1", true), ("3", false)] {
            let t = text.replace(line, &format!("         5         1{cs:>10}        11"));
            let r = parse_uff(t.as_bytes(), "n.unv", None);
            assert_eq!(r.is_ok(), ok, "{cs}: {r:?}");
            if !ok {
                let e = r.unwrap_err().to_string();
                assert!(
                    e.contains("record 1")
                        && e.contains("node 5: displacement coordinate system 3 is a local system"),
                    "{e}"
                );
            }
        }
        let t = text.replace(line, "         5");
        let e = parse_uff(t.as_bytes(), "n.unv", None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("node 5: no displacement coordinate system"),
            "{e}"
        );
    }

    /// Record 7 of a dataset 55 declares NINT integer and NRDV real values: data that hold
    /// another number are refused, naming the record.
    #[test]
    fn a_mode_whose_value_counts_disagree_with_record_7_is_refused() {
        let mode = Mode {
            number: 1,
            frequency_hz: 10.0,
            modal_mass: 1.0,
            damping_ratio: 0.0,
            name: "m".into(),
            id_lines: Vec::new(),
            shapes: vec![(1, [0.0, 0.0, 0.5])],
            units: None,
        };
        let mut buf = Vec::new();
        write_55(&mut buf, &mode).unwrap();
        let text = String::from_utf8(buf).unwrap();
        assert!(parse_uff(text.as_bytes(), "m.unv", None).is_ok());
        let r7 = "         2         4         1         1";
        assert!(text.contains(r7), "{text}");
        let bad = text.replace(r7, "         2         5         1         1");
        let e = parse_uff(bad.as_bytes(), "m.unv", None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("record 8") && e.contains("declares 5 real values (NRDV"),
            "{e}"
        );
        let bad = text.replace(r7, "         3         4         1         1");
        let e = parse_uff(bad.as_bytes(), "m.unv", None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("record 7") && e.contains("declares 3 integer values"),
            "{e}"
        );
    }

    /// An even abscissa whose increment makes the record's times infinite (1e308 s over two
    /// points) is refused, naming the increment (before: read, and `measure` printed "inf").
    #[test]
    fn an_increment_that_makes_times_infinite_is_refused() {
        let text = format!(
            "{}  1.00000e+00  2.00000e+00\n    -1\n",
            header("g", 12, 2, 1)
        )
        .replace("1.00000e-03", "1.00000e+308");
        let e = parse_uff(text.as_bytes(), "s.uff", None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("record 7") && e.contains("increment 1e308"),
            "{e}"
        );
        let ok = format!(
            "{}  1.00000e+00  2.00000e+00\n    -1\n",
            header("g", 12, 2, 1)
        );
        assert!(parse_uff(ok.as_bytes(), "s.uff", None).is_ok());
    }

    /// A write error (a full disk) names the file written.
    #[test]
    fn a_write_error_names_the_file() {
        struct Full;
        impl std::io::Write for Full {
            fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
                Err(std::io::Error::from_raw_os_error(28))
            }
            fn flush(&mut self) -> std::io::Result<()> {
                Ok(())
            }
        }
        let r = Record {
            name: "bed_acceleration".into(),
            quantity: Quantity::Acceleration,
            source_unit: "m/s^2".into(),
            point: None,
            abscissa: Abscissa::Even {
                start_s: 0.0,
                step_s: 1e-3,
            },
            values: vec![0.0, 1.0],
            origin: "test".into(),
        };
        let e = write_records(&mut Full, &[r], false, Path::new("out/history.uff"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("out/history.uff: "), "{e}");
    }

    #[test]
    fn an_unreadable_unit_dataset_is_passed_over_and_leaves_units_unknown() {
        let mode = Mode {
            number: 1,
            frequency_hz: 10.0,
            modal_mass: 1.0,
            damping_ratio: 0.0,
            name: "m".into(),
            id_lines: Vec::new(),
            shapes: vec![(1, [0.0, 0.0, 0.5])],
            units: None,
        };
        let mut after = Vec::new();
        write_55(&mut after, &mode).unwrap();
        let after = String::from_utf8(after).unwrap();
        for (records, what) in [
            (
                "         5    mm (milli newton)         1\n   0.0000000000000000D+00   1.0000000000000000D+00   1.0000000000000000D+00\n   2.7314999999999998D+02\n",
                ["record 2", "line 4", "unit factors"],
            ),
            (
                "         5    mm (milli newton)         1\n   1.0D+03\n",
                ["record 2", "line 4", "unit factors"],
            ),
            ("       SI\n", ["record 1", "line 3", "unit code"]),
        ] {
            let text = format!("    -1\n   164\n{records}    -1\n{after}");
            let f = parse_uff(text.as_bytes(), "u.unv", None).unwrap();
            let skipped = f.skipped.join("\n");
            for w in what {
                assert!(skipped.contains(w) && skipped.contains("unknown"), "{skipped}");
            }
            let u = f.modes[0].units.as_ref().unwrap();
            assert!(!u.known(), "{u:?}");
        }
    }
}
