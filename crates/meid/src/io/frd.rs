//! CalculiX `.frd` results (ASCII): the nodes (block `2C`) and the nodal displacements
//! (`DISP`) of the eigenmodes of a `*FREQUENCY` step, for importing modes
//! ([`crate::model::imported`]).
//!
//! # Why hand-written
//!
//! No Rust crate reads `.frd`; the format is the CalculiX GraphiX (cgx) fixed-column text format,
//! and meid needs a small part of it (nodes, displacement blocks of frequency steps, the step
//! parameters `1PGM` and `1PMODE`), with the robustness its other readers have (bounded lines,
//! no allocation from a size field, errors naming file, block and line). Everything else
//! (elements, stresses, other result blocks) is passed over.
//!
//! # Layout read (cgx manual, "Result Format")
//!
//! | line | format | fields |
//! |---|---|---|
//! | `    1C`, `    1U…` | | header, user text (passed over) |
//! | `    2C` | `(1X,'   2','C',18X,I12,37X,I1)` | nodes block: number of nodes, format (0 short, 1 long, 2 binary) |
//! | ` -1` | `(1X,I2,I5/I10,3E12.5)` | node label (5 columns in format 0, 10 in format 1) and x, y, z |
//! | ` -3` | | end of a block |
//! | `    3C` | | elements block: its ` -1`/` -2` lines are passed over to its ` -3`; any other line before the ` -3` is an error |
//! | `    1P…` | `1PSTEP`, `1PGM` (generalised mass φᵀMφ), `1PGK` (generalised stiffness), `1PMODE` (mode number) | step parameters |
//! | `  100C` | `(1X,'  100','C',6A1,E12.5,I12,20A1,I2,I5,10A1,I2)` | results block: set name, **value** (the frequency in cycles per time unit for a frequency step), number of nodes, text, analysis type (2 = frequency), step, analysis name, format |
//! | ` -4` | `(1X,I2,2X,8A1,2I5)` | result name (`DISP`), number of components |
//! | ` -5` | `(1X,I2,2X,8A1,5I5,8A1)` | one per component: name, menu, type, index 1, index 2, exists (1: computed by cgx, not in the data) |
//! | ` -1`, ` -2` | `(1X,I2,I5/I10,6E12.5)` | node label and up to 6 values; ` -2` continues the values |
//! | ` 9999` | | end of the file |
//!
//! Values are read in fixed 12-column fields (negative numbers touch: `2.5E-01-1.3E-02`),
//! with a whitespace-separated fallback for hand-made files. Binary results (format 2/3) are
//! refused (CalculiX writes ASCII unless told otherwise).
//!
//! # Robustness
//!
//! Lines are at most [`MAX_LINE`] bytes; a count in a header is checked against what the block
//! holds, never used to allocate; every value must be finite; every error names the file, the
//! block (its kind and first line), the line and what was expected.

use std::io::{BufRead, Read};
use std::path::Path;

use crate::{Error, Result};

/// An eigenmode of a frequency step.
#[derive(Debug, Clone, PartialEq)]
pub struct FrdMode {
    /// The mode number (`1PMODE`, else the step number of the `100C` line).
    pub number: i64,
    /// Natural frequency (cycles per time unit: Hz for a model in seconds), the `100C` value.
    pub frequency_hz: f64,
    /// The generalised mass `φᵀ M φ` (`1PGM`), when the file gives it (CalculiX writes 1: its
    /// eigenvectors are mass-normalised).
    pub generalised_mass: Option<f64>,
    /// `(node label, [D1, D2, D3])`, in file order.
    pub displacements: Vec<(i64, [f64; 3])>,
}

/// What meid reads from a `.frd` file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrdFile {
    /// `(node label, [x, y, z])` of block `2C`.
    pub nodes: Vec<(i64, [f64; 3])>,
    /// The `DISP` blocks of frequency steps (analysis type 2), in file order.
    pub modes: Vec<FrdMode>,
    /// Result blocks passed over, one line each (name, type, where).
    pub skipped: Vec<String>,
}

/// Longest line accepted (bytes): far beyond any record of the format (a few dozen columns).
pub const MAX_LINE: u64 = 1 << 16;

/// Reads a CalculiX `.frd` file (see the module docs).
pub fn read_frd(path: &Path) -> Result<FrdFile> {
    let (f, _) = crate::input::open(path)?;
    parse_frd(
        std::io::BufReader::with_capacity(1 << 16, f),
        &path.display().to_string(),
    )
}

/// Parses `.frd` text from `reader`; `file` names it in errors.
pub fn parse_frd<R: BufRead>(reader: R, file: &str) -> Result<FrdFile> {
    let mut p = Parser {
        r: reader,
        file,
        line_no: 0,
        buf: Vec::new(),
    };
    p.run()
}

struct Parser<'a, R: BufRead> {
    r: R,
    file: &'a str,
    line_no: usize,
    buf: Vec<u8>,
}

/// A block, for messages: its kind and first line.
#[derive(Clone, Copy)]
struct Block<'k> {
    kind: &'k str,
    line: usize,
}

/// The `100C` line of a results block.
struct ResultsHead {
    /// The value: a frequency step's frequency.
    value: f64,
    /// The number of nodes.
    count: u64,
    /// The analysis type (2: frequency) and the step number, when given.
    ictype: Option<i64>,
    numstep: Option<i64>,
    /// 0 or 1 (ASCII; 1 when not given).
    format: u8,
}

/// Step parameters (`1P…` lines) seen since the last results block.
#[derive(Default)]
struct StepParams {
    mode: Option<i64>,
    generalised_mass: Option<f64>,
}

impl<R: BufRead> Parser<'_, R> {
    fn err(&self, block: Option<Block>, line: usize, msg: String) -> Error {
        let mut location = self.file.to_string();
        if let Some(b) = block {
            location.push_str(&format!(": block {} starting at line {}", b.kind, b.line));
        }
        location.push_str(&format!(", line {line}"));
        Error::Input {
            location,
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
        self.line_no += 1;
        if n as u64 == MAX_LINE && self.buf.last() != Some(&b'\n') {
            return Err(self.err(
                None,
                self.line_no,
                format!("a line longer than {MAX_LINE} bytes: not a CalculiX .frd file"),
            ));
        }
        while matches!(self.buf.last(), Some(b'\n' | b'\r')) {
            self.buf.pop();
        }
        Ok(Some(String::from_utf8_lossy(&self.buf).into_owned()))
    }

    fn need_line(&mut self, block: Block) -> Result<String> {
        match self.line()? {
            Some(l) => Ok(l),
            None => Err(self.err(
                Some(block),
                self.line_no,
                "the file ends inside the block: expected its closing ' -3'".into(),
            )),
        }
    }

    fn run(&mut self) -> Result<FrdFile> {
        let mut out = FrdFile::default();
        let mut params = StepParams::default();
        let mut seen_end = false;
        while let Some(l) = self.line()? {
            let t = l.trim();
            if t.is_empty() {
                continue;
            }
            if seen_end {
                return Err(self.err(
                    None,
                    self.line_no,
                    format!(
                        "expected nothing after the end line '9999', got '{}'",
                        clip(t)
                    ),
                ));
            }
            let key = t.split_whitespace().next().unwrap_or("");
            match key {
                "9999" => seen_end = true,
                // Header (`1C` with an optional name) and user lines (`1U…`).
                k if k.starts_with("1C") || k.starts_with("1U") => {}
                "2C" => {
                    let block = Block {
                        kind: "2C (nodes)",
                        line: self.line_no,
                    };
                    let (count, format) = self.header_count_format(&l, block)?;
                    let nodes = self.node_block(block, format)?;
                    if nodes.len() as u64 != count {
                        return Err(self.err(
                            Some(block),
                            block.line,
                            format!(
                                "the header announces {count} nodes; the block holds {}",
                                nodes.len()
                            ),
                        ));
                    }
                    out.nodes.extend(nodes);
                }
                "3C" => {
                    let block = Block {
                        kind: "3C (elements)",
                        line: self.line_no,
                    };
                    self.skip_block(block)?;
                }
                k if k.starts_with("1P") => {
                    let value = t[k.len()..].trim();
                    match k {
                        "1PSTEP" => params = StepParams::default(),
                        "1PMODE" => {
                            params.mode = Some(value.parse::<i64>().map_err(|_| {
                                self.err(
                                    None,
                                    self.line_no,
                                    format!("1PMODE: expected a whole mode number, got '{}'", clip(value)),
                                )
                            })?)
                        }
                        "1PGM" => {
                            params.generalised_mass =
                                Some(parse_f(value).filter(|v| v.is_finite()).ok_or_else(|| {
                                    self.err(
                                        None,
                                        self.line_no,
                                        format!(
                                            "1PGM: expected the generalised mass (a finite number), got '{}'",
                                            clip(value)
                                        ),
                                    )
                                })?)
                        }
                        _ => {}
                    }
                }
                k if k.starts_with("100C") => {
                    let step = std::mem::take(&mut params);
                    self.results_block(&l, step, &mut out)?;
                }
                _ => {
                    return Err(self.err(
                        None,
                        self.line_no,
                        format!(
                            "expected a block key ('    2C' nodes, '    3C' elements, '    1P…' step parameters, '  100C' results, ' 9999' end), got '{}'",
                            clip(t)
                        ),
                    ))
                }
            }
        }
        if !seen_end && out.nodes.is_empty() && out.modes.is_empty() {
            return Err(self.err(
                None,
                self.line_no,
                "no nodes and no results: expected a CalculiX .frd file (a '    2C' nodes block, results under '  100C', ending with ' 9999')".into(),
            ));
        }
        Ok(out)
    }

    /// The count (columns 25-36 or the first number) and format (the last token) of a `2C`
    /// or `3C` header.
    fn header_count_format(&self, l: &str, block: Block) -> Result<(u64, u8)> {
        let toks: Vec<&str> = l.split_whitespace().collect();
        let count = toks.get(1).and_then(|s| s.parse::<u64>().ok());
        let format = toks.get(2).and_then(|s| s.parse::<u8>().ok()).unwrap_or(1);
        let Some(count) = count else {
            return Err(self.err(
                Some(block),
                self.line_no,
                format!(
                    "expected '    2C  <number of nodes>  <format>', got '{}'",
                    clip(l)
                ),
            ));
        };
        if format > 1 {
            return Err(self.err(
                Some(block),
                self.line_no,
                format!("format {format} (binary) is not read: meid reads ASCII .frd files (formats 0 and 1, CalculiX's default)"),
            ));
        }
        Ok((count, format))
    }

    fn node_block(&mut self, block: Block, format: u8) -> Result<Vec<(i64, [f64; 3])>> {
        let mut nodes = Vec::new();
        loop {
            let l = self.need_line(block)?;
            let key = cols(&l, 0, 3);
            match key.trim() {
                "-3" => return Ok(nodes),
                "-1" => {
                    let (label, v) = self.data_line(&l, format, 3, block, "node")?;
                    nodes.push((label, [v[0], v[1], v[2]]));
                }
                _ => {
                    return Err(self.err(
                        Some(block),
                        self.line_no,
                        format!(
                            "expected a node line ' -1  <label> <x> <y> <z>' or the block end ' -3', got '{}'",
                            clip(&l)
                        ),
                    ))
                }
            }
        }
    }

    /// A ` -1` line: the label (5 or 10 columns by `format`) and `want` values (12 columns
    /// each, or whitespace-separated).
    fn data_line(
        &self,
        l: &str,
        format: u8,
        want: usize,
        block: Block,
        what: &str,
    ) -> Result<(i64, Vec<f64>)> {
        let w = if format == 0 { 5 } else { 10 };
        let fixed = || -> Option<(i64, Vec<f64>)> {
            let label = cols(l, 3, 3 + w).trim().parse::<i64>().ok()?;
            let v = fields12(&cols(l, 3 + w, l.len()))?;
            Some((label, v))
        };
        let loose = || -> Option<(i64, Vec<f64>)> {
            let mut it = l.split_whitespace().skip(1);
            let label = it.next()?.parse::<i64>().ok()?;
            let v: Option<Vec<f64>> = it.map(parse_f).collect();
            Some((label, v?))
        };
        let got = fixed()
            .filter(|(_, v)| v.len() >= want.min(6))
            .or_else(|| loose().filter(|(_, v)| v.len() >= want.min(6)));
        match got {
            Some((label, v)) if v.iter().all(|x| x.is_finite()) => Ok((label, v)),
            _ => Err(self.err(
                Some(block),
                self.line_no,
                format!(
                    "expected a {what} line ' -1', a label ({w} columns) and {} finite numbers (12 columns each), got '{}'",
                    want.min(6),
                    clip(l)
                ),
            )),
        }
    }

    /// Passes over a block's data lines (` -1`, ` -2`) to its closing ` -3`. Any other line
    /// means the block does not end where the format says (its ` -3` is missing): an error
    /// naming the line, never a silent skip into the next block.
    fn skip_block(&mut self, block: Block) -> Result<()> {
        loop {
            let l = self.need_line(block)?;
            match cols(&l, 0, 3).trim() {
                "-3" => return Ok(()),
                "-1" | "-2" => {}
                _ => {
                    return Err(self.err(
                        Some(block),
                        self.line_no,
                        format!(
                            "expected a data line (' -1', ' -2') or the block end ' -3', got '{}': the block's closing ' -3' is missing",
                            clip(&l)
                        ),
                    ))
                }
            }
        }
    }

    fn results_block(&mut self, head: &str, step: StepParams, out: &mut FrdFile) -> Result<()> {
        let block = Block {
            kind: "100C (results)",
            line: self.line_no,
        };
        let ResultsHead {
            value,
            count,
            ictype,
            numstep,
            format,
        } = self.results_head(head, block)?;
        let (name, in_data, first_data) = self.components(block)?;
        let wanted = name == "DISP" && ictype == Some(2);
        if !wanted {
            out.skipped.push(format!(
                "line {}: results '{name}' (analysis type {}) passed over: meid reads DISP of frequency steps (type 2)",
                block.line,
                ictype.map(|t| t.to_string()).unwrap_or_else(|| "?".into())
            ));
            if cols(&first_data, 0, 3).trim() == "-3" {
                return Ok(());
            }
            return self.skip_block(block);
        }
        if in_data < 3 {
            return Err(self.err(
                Some(block),
                block.line,
                format!("DISP with {in_data} components in the data: expected D1, D2, D3"),
            ));
        }
        let disp = self.disp_lines(first_data, format, in_data, block)?;
        if disp.len() as u64 != count {
            return Err(self.err(
                Some(block),
                block.line,
                format!(
                    "the header announces {count} nodes; the DISP block holds {}",
                    disp.len()
                ),
            ));
        }
        if !value.is_finite() {
            return Err(self.err(
                Some(block),
                block.line,
                format!("the frequency (the '  100C' value) must be finite, got {value}"),
            ));
        }
        out.modes.push(FrdMode {
            number: step.mode.or(numstep).unwrap_or(out.modes.len() as i64 + 1),
            frequency_hz: value,
            generalised_mass: step.generalised_mass,
            displacements: disp,
        });
        Ok(())
    }

    /// The `100C` line `head` of the results `block` (binary formats refused).
    fn results_head(&self, head: &str, block: Block) -> Result<ResultsHead> {
        // (1X,'  100','C',6A1,E12.5,I12,20A1,I2,I5,10A1,I2)
        let value = parse_f(cols(head, 12, 24).trim());
        let count = cols(head, 24, 36).trim().parse::<u64>().ok();
        let ictype = cols(head, 56, 58).trim().parse::<i64>().ok();
        let numstep = cols(head, 58, 63).trim().parse::<i64>().ok();
        let format = cols(head, 73, 75).trim().parse::<u8>().ok().unwrap_or(1);
        let (Some(value), Some(count)) = (value, count) else {
            return Err(self.err(
                Some(block),
                block.line,
                format!(
                    "expected (1X,'  100','C',6A1,E12.5,I12,20A1,I2,I5,10A1,I2): set name, value, number of nodes, text, analysis type, step, analysis name, format; got '{}'",
                    clip(head)
                ),
            ));
        };
        if format > 1 {
            return Err(self.err(
                Some(block),
                block.line,
                format!("format {format} (binary) is not read: meid reads ASCII .frd files (formats 0 and 1, CalculiX's default)"),
            ));
        }
        Ok(ResultsHead {
            value,
            count,
            ictype,
            numstep,
            format,
        })
    }

    /// The `-4` line (the result's name) and the `-5` lines (one per component; those marked
    /// "exists = 1" are not in the data) of the results `block`: the name, the number of
    /// components in the data and the first line after the `-5` lines.
    fn components(&mut self, block: Block) -> Result<(String, usize, String)> {
        // -4: the result's name and number of components.
        let l4 = self.need_line(block)?;
        if cols(&l4, 0, 3).trim() != "-4" {
            return Err(self.err(
                Some(block),
                self.line_no,
                format!(
                    "expected ' -4  <name> <components> <type>' after the '  100C' line, got '{}'",
                    clip(&l4)
                ),
            ));
        }
        let name = cols(&l4, 5, 13).trim().to_string();
        let mut in_data = 0usize;
        let first_data = loop {
            let l = self.need_line(block)?;
            if cols(&l, 0, 3).trim() != "-5" {
                break l;
            }
            let exists = cols(&l, 33, 38).trim().parse::<i64>().unwrap_or(0);
            if exists != 1 {
                in_data += 1;
            }
        };
        Ok((name, in_data, first_data))
    }

    /// The `DISP` data lines of a results `block` from `first` to the block end ` -3`: per
    /// node its label and `[D1, D2, D3]` (of `in_data` values, continuation lines included).
    fn disp_lines(
        &mut self,
        first: String,
        format: u8,
        in_data: usize,
        block: Block,
    ) -> Result<Vec<(i64, [f64; 3])>> {
        let mut disp = Vec::new();
        let mut l = first;
        loop {
            match cols(&l, 0, 3).trim() {
                "-3" => break,
                "-1" => {
                    let (label, mut v) = self.data_line(&l, format, in_data, block, "DISP")?;
                    self.continuation(label, &mut v, format, in_data, block)?;
                    if v.len() > in_data {
                        return Err(self.err(
                            Some(block),
                            self.line_no,
                            format!("node {label}: {} values; the ' -5' lines announce {in_data}", v.len()),
                        ));
                    }
                    disp.push((label, [v[0], v[1], v[2]]));
                }
                _ => {
                    return Err(self.err(
                        Some(block),
                        self.line_no,
                        format!(
                            "expected a DISP line ' -1  <node> <D1> <D2> <D3>' or the block end ' -3', got '{}'",
                            clip(&l)
                        ),
                    ))
                }
            }
            l = self.need_line(block)?;
        }
        Ok(disp)
    }

    /// The continuation lines (` -2`) of node `label`'s data line, which carry values 7, 8,
    /// ..., appended to `v` until it holds `in_data` values.
    fn continuation(
        &mut self,
        label: i64,
        v: &mut Vec<f64>,
        format: u8,
        in_data: usize,
        block: Block,
    ) -> Result<()> {
        while v.len() < in_data {
            let c = self.need_line(block)?;
            if cols(&c, 0, 3).trim() != "-2" {
                return Err(self.err(
                    Some(block),
                    self.line_no,
                    format!(
                        "node {label}: {} of {in_data} values read; expected a continuation line ' -2', got '{}'",
                        v.len(),
                        clip(&c)
                    ),
                ));
            }
            let w = if format == 0 { 5 } else { 10 };
            let more = fields12(&cols(&c, 3 + w, c.len()))
                .filter(|m| !m.is_empty() && m.iter().all(|x| x.is_finite()))
                .ok_or_else(|| {
                    self.err(
                        Some(block),
                        self.line_no,
                        format!(
                            "node {label}: expected finite values (12 columns each), got '{}'",
                            clip(&c)
                        ),
                    )
                })?;
            v.extend(more);
        }
        Ok(())
    }
}

/// Columns `[a, b)` of a line (byte positions; a short line gives what there is).
fn cols(line: &str, a: usize, b: usize) -> String {
    let bytes = line.as_bytes();
    if a >= bytes.len() || a >= b {
        return String::new();
    }
    String::from_utf8_lossy(&bytes[a..b.min(bytes.len())]).into_owned()
}

/// The numbers of consecutive 12-column fields (a trailing blank field is ignored); `None`
/// when a field is not a number.
fn fields12(s: &str) -> Option<Vec<f64>> {
    let s = s.trim_end();
    s.as_bytes()
        .chunks(12)
        .map(|c| parse_f(String::from_utf8_lossy(c).trim()))
        .collect()
}

/// A number in Fortran or C notation (`1.5E+00`, `1.5D+00`, `1.5e0`).
fn parse_f(s: &str) -> Option<f64> {
    if s.is_empty() {
        return None;
    }
    s.replace(['D', 'd'], "E").parse::<f64>().ok()
}

use crate::input::clip;

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: &str = "    1C
    1UUSER
    2C                             2                                     1
 -1         1 0.00000E+00 0.00000E+00 0.00000E+00
 -1         2 1.00000E+00-2.50000E-01 0.00000E+00
 -3
    3C                             1                                     1
 -1         1    1    0    1
 -2         1         2
 -3
    1PSTEP                         1           1           1
    1PGM                1.000000E+00
    1PMODE                         1
  100CL  101 16.70645389           2                     2    1MODAL      1
 -4  DISP        4    1
 -5  D1          1    2    1    0
 -5  D2          1    2    2    0
 -5  D3          1    2    3    0
 -5  ALL         1    2    0    0    1ALL
 -1         1 0.00000E+00 0.00000E+00 0.00000E+00
 -1         2-1.00000E-01-2.00000E-01 7.50000E-01
 -3
 9999
";

    #[test]
    fn reads_nodes_and_a_mode_with_touching_fields() {
        let f = parse_frd(SMALL.as_bytes(), "t.frd").unwrap();
        assert_eq!(f.nodes, vec![(1, [0.0; 3]), (2, [1.0, -0.25, 0.0])]);
        assert_eq!(f.modes.len(), 1);
        let m = &f.modes[0];
        assert_eq!(m.number, 1);
        assert_eq!(m.frequency_hz, 16.70645389);
        assert_eq!(m.generalised_mass, Some(1.0));
        assert_eq!(m.displacements[1], (2, [-0.1, -0.2, 0.75]));
    }

    #[test]
    fn a_count_mismatch_names_block_and_line() {
        let bad = SMALL.replace(
            "    2C                             2",
            "    2C                             3",
        );
        let e = parse_frd(bad.as_bytes(), "t.frd").unwrap_err().to_string();
        assert!(
            e.contains("t.frd: block 2C (nodes) starting at line 3, line 3"),
            "{e}"
        );
        assert!(e.contains("announces 3 nodes; the block holds 2"), "{e}");
    }

    #[test]
    fn a_bad_value_names_the_line_and_what_was_expected() {
        let bad = SMALL.replace("-2.00000E-01", "-2.0000XE-01");
        let e = parse_frd(bad.as_bytes(), "t.frd").unwrap_err().to_string();
        assert!(e.contains("line 21"), "{e}");
        assert!(e.contains("expected a DISP line"), "{e}");
    }

    #[test]
    fn an_elements_block_without_its_closing_line_is_an_error_naming_the_line() {
        // Without the ` -3` after the elements, the old reader passed over the step
        // parameters and the first mode's header up to that mode's ` -3`, losing the mode.
        let bad = SMALL.replacen(
            " -2         1         2\n -3\n",
            " -2         1         2\n",
            1,
        );
        assert_ne!(bad, SMALL);
        let e = parse_frd(bad.as_bytes(), "t.frd").unwrap_err().to_string();
        assert!(
            e.contains("t.frd: block 3C (elements) starting at line 7, line 10"),
            "{e}"
        );
        assert!(e.contains("closing ' -3' is missing"), "{e}");
        assert!(e.contains("1PSTEP"), "{e}");
    }

    #[test]
    fn binary_results_are_refused_by_name() {
        let bad = SMALL.replace(
            "2                                     1\n -1         1 0",
            "2                                     2\n -1         1 0",
        );
        let e = parse_frd(bad.as_bytes(), "t.frd").unwrap_err().to_string();
        assert!(e.contains("binary"), "{e}");
    }
}
