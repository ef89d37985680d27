//! Measured time histories in CSV: one header row naming each column's quantity and unit,
//! then one row per sample.
//!
//! A column name is `NAME_UNIT` with a unit suffix of
//! [`crate::record::units::CSV_SUFFIXES`]: `time_s`, `accel_B_m_per_s2`, `accel_B_g`,
//! `force_floor_n`, `force_floor_kn`, `bed_velocity_mm_per_s` ... The channel's name is the
//! column's name without the suffix (`accel_B`). Exactly one column is a time (`_s`, `_ms`,
//! `_us`); meid's own `history.csv` reads as is (its energy columns, `_j`, are passed over).
//! Lines starting with `#` are comments. A column whose unit meid does not know is refused,
//! naming the file, the column and the line.

use std::path::Path;

use crate::record::units::{split_csv_name, Quantity};
use crate::record::{Abscissa, Record, EVEN_TOLERANCE};
use crate::{Error, Result};

/// Reads a CSV file of time histories (module docs).
pub fn read_csv(path: &Path) -> Result<Vec<Record>> {
    let (f, _) = crate::input::open(path)?;
    parse_csv(std::io::BufReader::new(f), &path.display().to_string())
}

/// The field delimiter of a header line: of `,`, `;` and tab, the one it holds most (a comma
/// on a tie or when it holds none).
fn delimiter_of(header: &[u8]) -> u8 {
    let count = |d: u8| header.iter().filter(|&&b| b == d).count();
    let (c, s, t) = (count(b','), count(b';'), count(b'\t'));
    if s > c && s >= t {
        b';'
    } else if t > c && t > s {
        b'\t'
    } else {
        b','
    }
}

/// A number of a field; with a delimiter other than the comma, a decimal comma (`1,5e-3`:
/// one comma, no point) reads as a point, as spreadsheets in many locales write it.
fn parse_number(field: &str, delimiter: u8) -> Option<f64> {
    match field.parse() {
        Ok(v) => Some(v),
        Err(_) if delimiter != b',' && field.matches(',').count() == 1 && !field.contains('.') => {
            field.replacen(',', ".", 1).parse().ok()
        }
        Err(_) => None,
    }
}

/// Parses CSV text from `reader`; `file` names it in errors. The delimiter is found on the
/// header line ([`delimiter_of`]: `,`, `;` or tab); a UTF-8 byte-order mark before it is
/// dropped; CRLF line ends read as LF.
pub fn parse_csv<R: std::io::Read>(reader: R, file: &str) -> Result<Vec<Record>> {
    use std::io::{BufRead as _, Read as _};
    let err = |line: u64, message: String| Error::Input {
        location: format!("{file}:{line}"),
        message,
    };
    // Everything up to and including the header line (comments and blank lines before it),
    // read ahead to find the delimiter, then parsed again by the CSV reader.
    let mut input = std::io::BufReader::new(reader);
    let mut ahead: Vec<u8> = Vec::new();
    let delimiter = loop {
        let mut line = Vec::new();
        let n = (&mut input)
            .take(1 << 20)
            .read_until(b'\n', &mut line)
            .map_err(|e| err(1, format!("cannot read: {e}")))?;
        if ahead.is_empty() {
            if let Some(rest) = line.strip_prefix("\u{feff}".as_bytes()) {
                line = rest.to_vec();
            }
        }
        ahead.extend_from_slice(&line);
        let text = String::from_utf8_lossy(&line);
        let t = text.trim();
        if n == 0 || !(t.is_empty() || t.starts_with('#')) {
            break delimiter_of(t.as_bytes());
        }
    };
    let mut rd = csv::ReaderBuilder::new()
        .has_headers(false)
        .comment(Some(b'#'))
        .delimiter(delimiter)
        .trim(csv::Trim::All)
        .flexible(true)
        .from_reader(std::io::Cursor::new(ahead).chain(input));
    let mut rows = rd.records();
    let header = loop {
        match rows.next() {
            None => return Err(err(
                1,
                "empty file: expected a header row such as 'time_s,accel_B_m_per_s2,force_floor_n'"
                    .into(),
            )),
            Some(Err(e)) => {
                return Err(err(
                    e.position().map_or(1, |p| p.line()),
                    format!("not CSV text: {e}"),
                ))
            }
            Some(Ok(r)) if r.iter().all(|c| c.is_empty()) => continue,
            Some(Ok(r)) => break r,
        }
    };
    let hline = header.position().map_or(1, |p| p.line());
    let names: Vec<String> = header.iter().map(str::to_string).collect();
    let (cols, tc) = column_kinds(&names).map_err(|m| err(hline, m))?;
    let mut data: Vec<Vec<f64>> = vec![Vec::new(); cols.len()];
    for row in rows {
        let row = row.map_err(|e| {
            err(
                e.position().map_or(0, |p| p.line()),
                format!("not CSV text: {e}"),
            )
        })?;
        let line = row.position().map_or(0, |p| p.line());
        if row.iter().all(|c| c.is_empty()) {
            continue;
        }
        if row.len() != cols.len() {
            return Err(err(
                line,
                format!("{} fields; the header has {}", row.len(), cols.len()),
            ));
        }
        for (k, field) in row.iter().enumerate() {
            let Some((name, _, f)) = &cols[k] else {
                continue;
            };
            let v: f64 = parse_number(field, delimiter).ok_or_else(|| {
                err(
                    line,
                    format!(
                        "column {} ({}): expected a number, got '{}'",
                        k + 1,
                        crate::input::clip(name),
                        crate::input::clip(field)
                    ),
                )
            })?;
            if !v.is_finite() {
                return Err(err(
                    line,
                    format!("column {} ({name}): {field} is not a finite number", k + 1),
                ));
            }
            let si = v * f;
            if !si.is_finite() {
                return Err(err(
                    line,
                    format!(
                        "column {} ({name}): {field} × {f} (to SI) is beyond the largest double: expected |value| ≤ {:e}",
                        k + 1,
                        f64::MAX / f
                    ),
                ));
            }
            data[k].push(si);
        }
    }
    let origin = |k: usize| format!("{file}, column {}", k + 1);
    records_from_columns(&names, cols, data, tc, &origin).map_err(|message| err(hline, message))
}

/// A column's channel name, quantity and factor to SI; `None` for a column passed over.
pub(crate) type ColumnKind = Option<(String, Quantity, f64)>;

/// Each column's (channel, quantity, factor to SI) from its `NAME_UNIT` name (`None`: an
/// energy, `_j`, passed over), and the time column. `Err`: the message naming the column.
pub(crate) fn column_kinds(
    names: &[String],
) -> std::result::Result<(Vec<ColumnKind>, usize), String> {
    let mut cols: Vec<ColumnKind> = Vec::new();
    let mut time_col = None;
    for (k, name) in names.iter().enumerate() {
        if name.to_ascii_lowercase().ends_with("_j") {
            cols.push(None);
            continue;
        }
        let Some((n, q, f)) = split_csv_name(name) else {
            return Err(format!(
                "column {} '{}': the name does not end in a unit meid knows; expected NAME_UNIT with UNIT one of s, ms, us, m_per_s2, mm_per_s2, g, mg, m_per_s, mm_per_s, m, mm, um, in, n, kn, lbf (e.g. time_s, accel_B_m_per_s2, accel_B_g, force_floor_n)",
                k + 1,
                crate::input::clip(name)
            ));
        };
        if q == Quantity::Time {
            if let Some(t) = time_col {
                return Err(format!(
                    "columns {} and {} are both times: expected exactly one time column",
                    t + 1,
                    k + 1
                ));
            }
            time_col = Some(k);
        }
        cols.push(Some((n, q, f)));
    }
    let Some(tc) = time_col else {
        return Err("no time column: expected one named like time_s or time_ms".into());
    };
    Ok((cols, tc))
}

/// The records of a table of columns (CSV, Parquet): `names` the column names, `cols` each
/// column's (channel, quantity, factor) or `None` when passed over, `data` the values in SI,
/// `tc` the time column. The time must increase; an abscissa even to [`EVEN_TOLERANCE`] is
/// even. `Err`: the message (the caller adds the location).
pub(crate) fn records_from_columns(
    names: &[String],
    cols: Vec<ColumnKind>,
    mut data: Vec<Vec<f64>>,
    tc: usize,
    origin: &dyn Fn(usize) -> String,
) -> std::result::Result<Vec<Record>, String> {
    let t = std::mem::take(&mut data[tc]);
    if t.len() < 2 {
        return Err(format!("{} rows of data: expected at least 2", t.len()));
    }
    if let Some(i) = t
        .windows(2)
        .position(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
    {
        return Err(format!(
            "the time column does not increase at data row {} ({} s then {} s)",
            i + 2,
            t[i],
            t[i + 1]
        ));
    }
    let n = t.len();
    let mean = (t[n - 1] - t[0]) / (n - 1) as f64;
    let worst = t
        .windows(2)
        .map(|w| ((w[1] - w[0]) - mean).abs())
        .fold(0.0, f64::max);
    let abscissa = if worst <= EVEN_TOLERANCE * mean {
        Abscissa::Even {
            start_s: t[0],
            step_s: mean,
        }
    } else {
        Abscissa::Uneven(t)
    };
    let mut out = Vec::new();
    for (k, c) in cols.into_iter().enumerate() {
        let Some((name, q, _)) = c else { continue };
        if k == tc {
            continue;
        }
        let header_name = names.get(k).cloned().unwrap_or_default();
        let unit = header_name[name.len().min(header_name.len())..]
            .trim_start_matches('_')
            .to_string();
        out.push(Record {
            name,
            quantity: q,
            source_unit: unit,
            point: None,
            abscissa: abscissa.clone(),
            values: std::mem::take(&mut data[k]),
            origin: origin(k),
        });
    }
    if out.is_empty() {
        return Err("no data column besides the time".into());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_units_and_names() {
        let text = "# a comment\ntime_s,accel_B_g,force_floor_kn,ke_slider_j\n0,1,2,9\n0.001,0.5,-1,9\n0.002,0,0,9\n";
        let r = parse_csv(text.as_bytes(), "lab.csv").unwrap();
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].name, "accel_B");
        assert_eq!(r[0].values, vec![9.80665, 0.5 * 9.80665, 0.0]);
        assert_eq!(r[1].name, "force_floor");
        assert_eq!(r[1].quantity, Quantity::Force);
        assert_eq!(r[1].values, vec![2e3, -1e3, 0.0]);
        assert_eq!(r[1].source_unit, "kn");
        let (t0, dt) = r[0].even().unwrap();
        assert_eq!(t0, 0.0);
        assert!((dt - 1e-3).abs() < 1e-15);
    }

    /// Files as spreadsheets and DAQ software write them (session 12 audit: a semicolon or
    /// tab file was refused with "no time column", as its header read as one column): the
    /// delimiter is found on the header; with `;` or tab a decimal comma reads; a UTF-8
    /// byte-order mark and CRLF line ends are dropped; errors still name line and column.
    #[test]
    fn semicolons_tabs_decimal_commas_bom_and_crlf_read() {
        let want = |r: &[Record]| {
            assert_eq!(r.len(), 2, "{r:?}");
            assert_eq!(r[0].name, "accel_B");
            assert_eq!(r[0].values, vec![9.80665 * 1.5, -0.25 * 9.80665]);
            assert_eq!(r[1].name, "force_floor");
            assert_eq!(r[1].values, vec![2e3, -1e3]);
            let (t0, dt) = r[0].even().unwrap();
            assert_eq!(t0, 0.0);
            assert!((dt - 1e-3).abs() < 1e-15);
        };
        for text in [
            "# Messung 3\r\naccel_B_g;time_s;force_floor_kn\r\n1,5;0;2\r\n-0,25;0,001;-1\r\n",
            "\u{feff}accel_B_g\ttime_s\tforce_floor_kn\n1.5\t0\t2\n-0.25\t0.001\t-1\n",
            "\u{feff}accel_B_g,time_s,force_floor_kn\r\n1.5,0,2\r\n-0.25,0.001,-1\r\n",
            "accel_B_g ; time_s ; force_floor_kn\n1.5 ; 0 ; 2e0\n-2,5E-1 ; 1,0e-3 ; -1\n",
        ] {
            want(&parse_csv(text.as_bytes(), "lab.csv").unwrap());
        }
        // A comma-delimited file has no decimal comma: a field "1,5" is two fields.
        let e = parse_csv("time_s,accel_B_g\n0,1,5\n".as_bytes(), "lab.csv")
            .unwrap_err()
            .to_string();
        assert!(e.contains("lab.csv:2: 3 fields; the header has 2"), "{e}");
        let e = parse_csv("time_s;accel_B_g\n0;1,5,2\n".as_bytes(), "lab.csv")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("lab.csv:2: column 2 (accel_B): expected a number, got '1,5,2'"),
            "{e}"
        );
    }

    #[test]
    fn errors_name_line_and_column() {
        let e = parse_csv("time_s,accel_B_furlongs\n0,1\n".as_bytes(), "lab.csv")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("lab.csv:1: column 2 'accel_B_furlongs'"),
            "{e}"
        );
        let e = parse_csv("time_s,accel_B_g\n0,1\n0.1,x\n".as_bytes(), "lab.csv")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("lab.csv:3: column 2 (accel_B): expected a number, got 'x'"),
            "{e}"
        );
        let e = parse_csv("time_s,accel_B_g\n0,1\n0,2\n".as_bytes(), "lab.csv")
            .unwrap_err()
            .to_string();
        assert!(e.contains("does not increase"), "{e}");
        let e = parse_csv("accel_B_g\n0\n".as_bytes(), "lab.csv")
            .unwrap_err()
            .to_string();
        assert!(e.contains("no time column"), "{e}");
        let e = parse_csv("time_s,accel_B_g\n0,1,3\n".as_bytes(), "lab.csv")
            .unwrap_err()
            .to_string();
        assert!(e.contains("3 fields; the header has 2"), "{e}");
    }
}
