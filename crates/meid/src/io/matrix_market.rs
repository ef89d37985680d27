//! Sparse matrices in the Matrix Market coordinate format (NIST, "The Matrix Market Exchange
//! Formats: Initial Design", Boisvert, Pozo & Remington, NISTIR 5935, 1996).
//!
//! ```text
//! %%MatrixMarket matrix coordinate real symmetric
//! % comments
//! rows cols entries
//! i j value          (1-based; for `symmetric` only the lower triangle, i ≥ j)
//! ```
//!
//! [`write_symmetric`] writes the lower triangle of a symmetric matrix with 17 significant
//! digits (exact round trip of `f64`), atomically: to a temporary file in the same directory,
//! then renamed over the target. [`read`] accepts `real`/`integer` and `symmetric`/`general`
//! files and returns the matrix with both triangles stored (a symmetric file is mirrored);
//! duplicate entries are summed. Read errors carry `file:line:column`.
//!
//! Hand-written: the format is a few lines of text, and the crates that read it
//! (`sprs`, `matrixmarket-rs`) would pull in another sparse type.

use std::io::{BufRead, BufReader};
use std::path::Path;

use faer::sparse::{SparseColMat, SparseColMatRef, Triplet};

use crate::{Error, Result};

/// Writes the lower triangle of the symmetric matrix `a` as a `real symmetric` coordinate file.
/// Entries above the diagonal are not written (they must mirror the lower ones); `a` must be
/// square. The file appears atomically.
pub fn write_symmetric(path: &Path, a: SparseColMatRef<'_, usize, f64>) -> Result<()> {
    let n = a.nrows();
    if a.ncols() != n {
        return Err(Error::invalid(
            "matrix",
            format!(
                "a symmetric Matrix Market file needs a square matrix, got {}x{}",
                n,
                a.ncols()
            ),
        ));
    }
    let mut entries: Vec<(usize, usize, f64)> = Vec::new();
    for j in 0..n {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            if i >= j {
                if !v.is_finite() {
                    return Err(Error::invalid(
                        "matrix",
                        format!("entry ({i}, {j}) is not finite"),
                    ));
                }
                entries.push((i, j, v));
            }
        }
    }
    entries.sort_by_key(|e| (e.1, e.0));
    use std::fmt::Write as _;
    let mut text = String::with_capacity(48 * (entries.len() + 3));
    text.push_str("%%MatrixMarket matrix coordinate real symmetric\n% written by meid\n");
    let _ = writeln!(text, "{n} {n} {}", entries.len());
    for (i, j, v) in &entries {
        let _ = writeln!(text, "{} {} {:.16e}", i + 1, j + 1, v);
    }
    super::write_atomic(path, text.as_bytes())
}

fn input_error(path: &Path, line: usize, col: usize, message: impl Into<String>) -> Error {
    Error::Input {
        location: format!("{}:{}:{}", path.display(), line, col),
        message: message.into(),
    }
}

/// Splits a line into tokens with their 1-based character columns.
fn tokens(line: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut start = None;
    for (pos, ch) in line.char_indices() {
        if ch.is_whitespace() {
            if let Some(s) = start.take() {
                out.push((s, &line[s..pos]));
            }
        } else if start.is_none() {
            start = Some(pos);
        }
    }
    if let Some(s) = start {
        out.push((s, &line[s..]));
    }
    out.into_iter()
        .map(|(s, t)| (line[..s].chars().count() + 1, t))
        .collect()
}

/// Reads a Matrix Market coordinate file (`real` or `integer`, `symmetric` or `general`).
/// A symmetric file is returned with both triangles stored.
pub fn read(path: &Path) -> Result<SparseColMat<usize, f64>> {
    let (file, _) = crate::input::open(path)?;
    let mut lines = BufReader::new(file).lines().enumerate();
    let mut next_line = || -> Result<Option<(usize, String)>> {
        match lines.next() {
            None => Ok(None),
            Some((no, Ok(l))) => Ok(Some((no + 1, l))),
            Some((_, Err(e))) => Err(Error::io(path, e)),
        }
    };

    let (hline, header) = next_line()?
        .ok_or_else(|| input_error(path, 1, 1, "empty file; expected a %%MatrixMarket header"))?;
    let symmetric = parse_header(path, hline, &header)?;

    // Size line (after comments and blank lines).
    let (sline, size) = loop {
        match next_line()? {
            None => {
                return Err(input_error(
                    path,
                    hline + 1,
                    1,
                    "missing size line `rows cols entries`",
                ))
            }
            Some((no, l)) => {
                let t = l.trim_start();
                if t.is_empty() || t.starts_with('%') {
                    continue;
                }
                break (no, l);
            }
        }
    };
    let [nrows, ncols, nnz] = parse_size(path, sline, &size, symmetric)?;

    let mut triplets = Vec::with_capacity(if symmetric { 2 * nnz } else { nnz });
    let mut read_entries = 0usize;
    let mut last_line = sline;
    while let Some((no, l)) = next_line()? {
        last_line = no;
        let t = l.trim_start();
        if t.is_empty() || t.starts_with('%') {
            continue;
        }
        let tk = tokens(&l);
        if tk.len() != 3 {
            return Err(input_error(
                path,
                no,
                1,
                format!("expected `row col value`, found {} fields", tk.len()),
            ));
        }
        if read_entries == nnz {
            return Err(input_error(
                path,
                no,
                1,
                format!("more entries than the {nnz} announced on line {sline}"),
            ));
        }
        let (i, j, v) = parse_entry(path, no, &tk, nrows, ncols)?;
        if symmetric {
            if i < j {
                return Err(input_error(
                    path,
                    no,
                    tk[0].0,
                    format!(
                        "entry ({}, {}) is above the diagonal; a symmetric file stores the lower triangle only",
                        i + 1,
                        j + 1
                    ),
                ));
            }
            triplets.push(Triplet::new(i, j, v));
            if i != j {
                triplets.push(Triplet::new(j, i, v));
            }
        } else {
            triplets.push(Triplet::new(i, j, v));
        }
        read_entries += 1;
    }
    if read_entries != nnz {
        return Err(input_error(
            path,
            last_line,
            1,
            format!("file ends after {read_entries} entries, {nnz} were announced on line {sline}"),
        ));
    }
    SparseColMat::try_new_from_triplets(nrows, ncols, &triplets).map_err(|e| {
        Error::numerical(
            "matrix market reader",
            format!("could not build the matrix: {e:?}"),
        )
    })
}

/// The header line `%%MatrixMarket matrix coordinate FIELD SYMMETRY` (line `hline`): FIELD
/// `real` or `integer`, SYMMETRY `symmetric` (returns true) or `general` (false).
fn parse_header(path: &Path, hline: usize, header: &str) -> Result<bool> {
    let h = tokens(header);
    if h.len() != 5 || !h[0].1.eq_ignore_ascii_case("%%MatrixMarket") {
        return Err(input_error(
            path,
            hline,
            1,
            "expected the header `%%MatrixMarket matrix coordinate real symmetric`",
        ));
    }
    let want = ["matrix", "coordinate"];
    for (tok, w) in h[1..3].iter().zip(want) {
        if !tok.1.eq_ignore_ascii_case(w) {
            return Err(input_error(
                path,
                hline,
                tok.0,
                format!(
                    "`{}` is not supported; expected `{w}`",
                    crate::input::clip(tok.1)
                ),
            ));
        }
    }
    let field = h[3].1.to_ascii_lowercase();
    if field != "real" && field != "integer" {
        return Err(input_error(
            path,
            hline,
            h[3].0,
            format!(
                "field `{}` is not supported; expected `real` or `integer`",
                crate::input::clip(h[3].1)
            ),
        ));
    }
    let symmetry = h[4].1.to_ascii_lowercase();
    match symmetry.as_str() {
        "symmetric" => Ok(true),
        "general" => Ok(false),
        _ => Err(input_error(
            path,
            hline,
            h[4].0,
            format!(
                "symmetry `{}` is not supported; expected `symmetric` or `general`",
                crate::input::clip(h[4].1)
            ),
        )),
    }
}

/// The size line `rows cols entries` (line `sline`) as `[rows, cols, entries]`; a symmetric
/// matrix must be square.
fn parse_size(path: &Path, sline: usize, size: &str, symmetric: bool) -> Result<[usize; 3]> {
    let st = tokens(size);
    if st.len() != 3 {
        return Err(input_error(
            path,
            sline,
            1,
            format!("expected `rows cols entries`, found {} fields", st.len()),
        ));
    }
    let mut dims = [0usize; 3];
    for (d, (col, t)) in dims.iter_mut().zip(&st) {
        *d = t.parse().map_err(|_| {
            input_error(
                path,
                sline,
                *col,
                format!("`{}` is not a non-negative integer", crate::input::clip(t)),
            )
        })?;
    }
    let [nrows, ncols, _] = dims;
    if symmetric && nrows != ncols {
        return Err(input_error(
            path,
            sline,
            1,
            format!("a symmetric matrix must be square, got {nrows}x{ncols}"),
        ));
    }
    Ok(dims)
}

/// One entry line's tokens `row col value` (line `no`) as 0-based `(i, j, value)`: indices in
/// 1..=rows and 1..=cols, a finite value.
fn parse_entry(
    path: &Path,
    no: usize,
    tk: &[(usize, &str)],
    nrows: usize,
    ncols: usize,
) -> Result<(usize, usize, f64)> {
    let mut idx = [0usize; 2];
    for (k, lim) in [(0, nrows), (1, ncols)] {
        let (col, s) = tk[k];
        let v: usize = s.parse().map_err(|_| {
            input_error(
                path,
                no,
                col,
                format!(
                    "`{}` is not a positive integer index",
                    crate::input::clip(s)
                ),
            )
        })?;
        if v == 0 || v > lim {
            return Err(input_error(
                path,
                no,
                col,
                format!("index {v} is outside 1..={lim}"),
            ));
        }
        idx[k] = v - 1;
    }
    let (col, s) = tk[2];
    let v: f64 = s.parse().map_err(|_| {
        input_error(
            path,
            no,
            col,
            format!("`{}` is not a number", crate::input::clip(s)),
        )
    })?;
    if !v.is_finite() {
        return Err(input_error(path, no, col, format!("`{s}` is not finite")));
    }
    Ok((idx[0], idx[1], v))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmpdir(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("meid-mm-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn round_trip_is_exact() {
        let t = [
            Triplet::new(0, 0, 4.0),
            Triplet::new(1, 0, -1.0 / 3.0),
            Triplet::new(0, 1, -1.0 / 3.0),
            Triplet::new(1, 1, 2.0e-300),
            Triplet::new(2, 2, std::f64::consts::PI),
            Triplet::new(2, 0, 1e17),
            Triplet::new(0, 2, 1e17),
        ];
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(3, 3, &t).unwrap();
        let d = tmpdir("rt");
        let p = d.join("a.mtx");
        write_symmetric(&p, a.as_ref()).unwrap();
        let b = read(&p).unwrap();
        assert_eq!(a.to_dense(), b.to_dense());
        // no temporary file left behind
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
    }

    #[test]
    fn errors_name_file_line_and_column() {
        let d = tmpdir("err");
        let p = d.join("bad.mtx");
        std::fs::write(
            &p,
            "%%MatrixMarket matrix coordinate real symmetric\n% c\n3 3 2\n1 1 2.0\n2 x 1.0\n",
        )
        .unwrap();
        let e = read(&p).unwrap_err().to_string();
        assert!(e.contains("bad.mtx:5:3"), "{e}");
        std::fs::write(
            &p,
            "%%MatrixMarket matrix coordinate real symmetric\n3 3 2\n1 1 2.0\n1 2 1.0\n",
        )
        .unwrap();
        let e = read(&p).unwrap_err().to_string();
        assert!(
            e.contains("bad.mtx:4:1") && e.contains("above the diagonal"),
            "{e}"
        );
        std::fs::write(
            &p,
            "%%MatrixMarket matrix coordinate real symmetric\n3 3 2\n1 1 2.0\n4 1 1.0\n",
        )
        .unwrap();
        let e = read(&p).unwrap_err().to_string();
        assert!(e.contains("bad.mtx:4:1") && e.contains("outside"), "{e}");
        std::fs::write(
            &p,
            "%%MatrixMarket matrix coordinate complex symmetric\n3 3 0\n",
        )
        .unwrap();
        let e = read(&p).unwrap_err().to_string();
        assert!(e.contains("bad.mtx:1:34"), "{e}");
        std::fs::write(
            &p,
            "%%MatrixMarket matrix coordinate real general\n2 2 3\n1 1 2.0\n",
        )
        .unwrap();
        let e = read(&p).unwrap_err().to_string();
        assert!(
            e.contains("bad.mtx:3:1") && e.contains("1 entries, 3"),
            "{e}"
        );
    }
}
