//! Functions a reader can hold in mind (issue 30): no function in the workspace's sources
//! (`crates/meid/src`, `crates/meid-cli/src`, `crates/meid-py/src`) is longer than
//! [`MAX_LINES`] lines, from its `fn` line to its closing brace. Read from the source text:
//! comments, string and character literals are blanked first, then each `fn NAME` with a body
//! is matched to the brace that closes it. The functions still being split are listed in
//! [`KNOWN_LONG`], each with its issue.

use std::path::Path;

/// The longest a function may be (lines, `fn` line and closing brace included).
const MAX_LINES: usize = 150;

/// Functions allowed to be longer than [`MAX_LINES`] while their split is under way:
/// `(file under crates/, function name)`. Empty: every function is within the bound (issue 30).
const KNOWN_LONG: [(&str, &str); 0] = [];

use crate::layering::rust_files;

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// `c[i - 1]` is the `b` of a byte literal (`b'x'`, `b"x"`, `br"x"`).
fn byte_prefix(c: &[char], i: usize) -> bool {
    i > 0 && c[i - 1] == 'b' && (i < 2 || !is_ident(c[i - 2]))
}

/// The number of `#` of a raw string starting at `c[i]` (`r"`, `r#"`, ...), if one does.
fn raw_string_at(c: &[char], i: usize) -> Option<usize> {
    if c[i] != 'r' || (i > 0 && is_ident(c[i - 1]) && !byte_prefix(c, i)) {
        return None;
    }
    let hashes = c[i + 1..].iter().take_while(|&&ch| ch == '#').count();
    (c.get(i + 1 + hashes) == Some(&'"')).then_some(hashes)
}

/// `text` with comments (nested block comments too), string literals (raw ones too) and
/// character literals replaced by spaces, newlines kept: what is left is code, so its braces
/// are the code's. A lifetime (`'a`) is code.
fn blank_literals(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let n = c.len();
    let mut out = String::with_capacity(text.len());
    let blank = |out: &mut String, s: &[char]| {
        for &ch in s {
            out.push(if ch == '\n' { '\n' } else { ' ' });
        }
    };
    let mut i = 0;
    while i < n {
        let prev_ident = i > 0 && is_ident(c[i - 1]) && !byte_prefix(&c, i);
        if c[i] == '/' && i + 1 < n && c[i + 1] == '/' {
            let mut j = i;
            while j < n && c[j] != '\n' {
                j += 1;
            }
            blank(&mut out, &c[i..j]);
            i = j;
        } else if c[i] == '/' && i + 1 < n && c[i + 1] == '*' {
            let (mut j, mut depth) = (i + 2, 1);
            while j < n && depth > 0 {
                if c[j] == '/' && j + 1 < n && c[j + 1] == '*' {
                    depth += 1;
                    j += 2;
                } else if c[j] == '*' && j + 1 < n && c[j + 1] == '/' {
                    depth -= 1;
                    j += 2;
                } else {
                    j += 1;
                }
            }
            blank(&mut out, &c[i..j.min(n)]);
            i = j.min(n);
        } else if let Some(hashes) = raw_string_at(&c, i) {
            // A raw string r#"..."#: ends at `"` followed by as many `#`.
            let mut j = i + 2 + hashes;
            while j < n && !(c[j] == '"' && (1..=hashes).all(|h| c.get(j + h) == Some(&'#'))) {
                j += 1;
            }
            let j = (j + 1 + hashes).min(n);
            blank(&mut out, &c[i..j]);
            i = j;
        } else if c[i] == '"' {
            let mut j = i + 1;
            while j < n && c[j] != '"' {
                j += if c[j] == '\\' { 2 } else { 1 };
            }
            let j = (j + 1).min(n);
            blank(&mut out, &c[i..j]);
            i = j;
        } else if c[i] == '\'' && !prev_ident {
            // A character literal ('x', '\n', '\'', '\u{..}'), or a lifetime (left as code).
            let end = if i + 1 < n && c[i + 1] == '\\' {
                (i + 3..n).find(|&j| c[j] == '\'')
            } else if i + 2 < n && c[i + 2] == '\'' {
                Some(i + 2)
            } else {
                None
            };
            match end {
                Some(e) => {
                    blank(&mut out, &c[i..=e]);
                    i = e + 1;
                }
                None => {
                    out.push(c[i]);
                    i += 1;
                }
            }
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// Every function with a body in `code` (literals blanked): its name, first line (1-based)
/// and length in lines, from the `fn` line to the line of its closing brace.
fn functions(code: &str) -> Vec<(String, usize, usize)> {
    let c: Vec<char> = code.chars().collect();
    let n = c.len();
    let line_of = |k: usize| 1 + c[..k].iter().filter(|&&ch| ch == '\n').count();
    let mut out = Vec::new();
    let mut i = 0;
    while i + 2 < n {
        let is_fn = c[i] == 'f'
            && c[i + 1] == 'n'
            && c[i + 2].is_whitespace()
            && (i == 0 || !is_ident(c[i - 1]));
        if !is_fn {
            i += 1;
            continue;
        }
        let mut j = i + 2;
        while j < n && c[j].is_whitespace() {
            j += 1;
        }
        let name: String = c[j..].iter().take_while(|&&ch| is_ident(ch)).collect();
        if name.is_empty() {
            i += 2;
            continue;
        }
        // The body's `{`: the first outside parentheses and brackets (a `;` first: no body).
        let mut depth = 0i64;
        let mut k = j + name.len();
        let mut open = None;
        while k < n {
            match c[k] {
                '(' | '[' => depth += 1,
                ')' | ']' => depth -= 1,
                ';' if depth <= 0 => break,
                '{' if depth <= 0 => {
                    open = Some(k);
                    break;
                }
                _ => {}
            }
            k += 1;
        }
        if let Some(o) = open {
            let mut d = 0i64;
            let mut e = o;
            while e < n {
                match c[e] {
                    '{' => d += 1,
                    '}' => {
                        d -= 1;
                        if d == 0 {
                            break;
                        }
                    }
                    _ => {}
                }
                e += 1;
            }
            let (first, last) = (line_of(i), line_of(e.min(n - 1)));
            out.push((name.clone(), first, last - first + 1));
        }
        i = j + name.len();
    }
    out
}

#[test]
fn the_scan_measures_functions_as_written() {
    // Braces, `fn` and semicolons inside literals and comments do not count; a lifetime is
    // no character literal; a declaration without a body is no function.
    let src = r##"
trait T { fn declared(&self) -> [u8; 2]; }
fn short<'a>(x: &'a str) -> (char, &'a str) {
    let s = "} fn fake() { {";
    let r = r#"}"#;
    let c = '}';
    let q = '\'';
    // }
    /* } /* nested } */ } */
    (c, x)
}
fn longer() -> Result<[f64; 3], ()> {
    Ok([0.0; 3])

}
"##;
    let f = functions(&blank_literals(src));
    let found: Vec<(&str, usize, usize)> = f.iter().map(|(n, a, b)| (n.as_str(), *a, *b)).collect();
    assert_eq!(found, vec![("short", 3, 9), ("longer", 12, 4)]);
}

#[test]
fn no_function_is_longer_than_150_lines() {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files = Vec::new();
    for c in ["meid/src", "meid-cli/src", "meid-py/src"] {
        let dir = crates.join(c);
        if dir.is_dir() {
            rust_files(&dir, &mut files);
        }
    }
    assert!(files.len() > 100, "found only {} source files", files.len());
    let mut long = Vec::new();
    let mut still_long = Vec::new();
    for f in &files {
        let rel = f
            .strip_prefix(&crates)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        let text = std::fs::read_to_string(f).unwrap();
        for (name, line, len) in functions(&blank_literals(&text)) {
            let known = KNOWN_LONG.contains(&(rel.as_str(), name.as_str()));
            if len > MAX_LINES && !known {
                long.push(format!("crates/{rel}:{line} {name}: {len} lines"));
            } else if len > MAX_LINES {
                still_long.push((rel.clone(), name));
            }
        }
    }
    assert!(
        long.is_empty(),
        "functions longer than {MAX_LINES} lines (split them along their phases):\n{}",
        long.join("\n")
    );
    // A listed function that was split (or renamed) leaves the list, so the list stays true.
    let stale: Vec<_> = KNOWN_LONG
        .iter()
        .filter(|(f, n)| !still_long.iter().any(|(g, m)| g == f && m == n))
        .collect();
    assert!(
        stale.is_empty(),
        "no longer over {MAX_LINES} lines (or gone): remove from KNOWN_LONG: {stale:?}"
    );
}
