//! Property tests of the parsers (the stable counterpart of the cargo-fuzz targets in `fuzz/`,
//! with the same properties from `fuzz_support`): arbitrary text and structured mutations of
//! valid inputs never make a parser panic; an accepted input keeps its promises (indices in
//! range, finite values, names that read back as themselves).
//!
//! Case counts are bounded so that the whole file runs in a few seconds on two cores; the
//! fuzzers (`cargo +nightly fuzz run TARGET`) search much longer. A failure prints the minimal
//! input; proptest keeps it in `fuzz_parsers.proptest-regressions` to replay first next time.

use crate::fuzz_support;

use std::path::PathBuf;

use proptest::prelude::*;

use fuzz_support::{
    check_gmsh, check_gmsh_bytes, check_model, check_spec, FE_SOFT_BASE, LUMPED, PLATE_MSH,
    PLATE_MSH_22, PLATE_MSH_B41,
};

/// Values a mutation puts in place of a model value or a Gmsh token: the boundary numbers,
/// non-numbers, wrong types and wrong shapes.
const VALUES: &[&str] = &[
    "0",
    "-1",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "1e-308",
    "-0.0",
    "0.02",
    "2",
    "18446744073709551616",
    "\"x\"",
    "\"2%\"",
    "true",
    "[]",
    "{}",
    "[1.2, 5.0]",
    "[\"a\", \"b\", \"c\", \"d\"]",
    "{ mass = 1.0 }",
    "\"supports\"",
];

/// Fragments a mutation inserts: TOML and Gmsh punctuation and keywords.
const SNIPPETS: &[&str] = &[
    "=",
    "[",
    "]",
    "[[",
    "]]",
    "{",
    "}",
    "\"",
    "'",
    ",",
    ".",
    "\n",
    "#",
    " ",
    "[structure.fem]",
    "[damper]",
    "$Nodes",
    "$EndNodes",
    "$Elements",
    "$EndElements",
    "$PhysicalNames",
    "1 ",
    "-1 ",
    "0 ",
];

/// One edit of a text, line- and token-wise (the text stays valid UTF-8). Each number picks
/// a line, token, character or list entry modulo the count there is.
#[derive(Debug, Clone)]
enum Edit {
    DeleteLine(usize),
    DuplicateLine(usize),
    SwapLines(usize, usize),
    /// Line, token, value: replaces the value of a `key = value` line with `VALUES[value]`,
    /// or else one whitespace-separated token of the line.
    ReplaceValue(usize, usize, usize),
    /// Line, character, snippet.
    Insert(usize, usize, usize),
    Truncate(usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    let u = any::<usize>;
    prop_oneof![
        1 => u().prop_map(Edit::DeleteLine),
        1 => u().prop_map(Edit::DuplicateLine),
        1 => (u(), u()).prop_map(|(a, b)| Edit::SwapLines(a, b)),
        3 => (u(), u(), u()).prop_map(|(l, t, v)| Edit::ReplaceValue(l, t, v)),
        1 => (u(), u(), u()).prop_map(|(l, c, s)| Edit::Insert(l, c, s)),
        1 => u().prop_map(Edit::Truncate),
    ]
}

/// One edit of a binary file. Positions are taken near a section start (`$Name` line) with
/// probability one half, since the headers' counts and the block headers sit there.
#[derive(Debug, Clone)]
enum ByteEdit {
    /// Section, offset after its `$Name` line, value.
    SetNear(usize, usize, u8),
    Set(usize, u8),
    Delete(usize, usize),
    Insert(usize, Vec<u8>),
    Truncate(usize),
}

fn byte_edit() -> impl Strategy<Value = ByteEdit> {
    let u = any::<usize>;
    let value = prop_oneof![
        Just(0u8),
        Just(1),
        Just(0x7f),
        Just(0x80),
        Just(0xff),
        any::<u8>()
    ];
    prop_oneof![
        4 => (u(), 0usize..64, value.clone()).prop_map(|(s, o, v)| ByteEdit::SetNear(s, o, v)),
        2 => (u(), value).prop_map(|(i, v)| ByteEdit::Set(i, v)),
        1 => (u(), 1usize..16).prop_map(|(i, n)| ByteEdit::Delete(i, n)),
        1 => (u(), prop::collection::vec(any::<u8>(), 1..16)).prop_map(|(i, b)| ByteEdit::Insert(i, b)),
        1 => u().prop_map(ByteEdit::Truncate),
    ]
}

fn apply_bytes(data: &[u8], edits: &[ByteEdit]) -> Vec<u8> {
    let mut b = data.to_vec();
    for e in edits {
        let n = b.len().max(1);
        match e {
            ByteEdit::SetNear(s, o, v) => {
                let starts: Vec<usize> = b
                    .windows(2)
                    .enumerate()
                    .filter(|(_, w)| w[0] == b'\n' && w[1] == b'$')
                    .filter_map(|(i, _)| {
                        b[i + 1..]
                            .iter()
                            .position(|&c| c == b'\n')
                            .map(|k| i + 2 + k)
                    })
                    .collect();
                if !starts.is_empty() {
                    let at = starts[s % starts.len()] + o;
                    if at < b.len() {
                        b[at] = *v;
                    }
                }
            }
            ByteEdit::Set(i, v) => {
                if !b.is_empty() {
                    b[i % n] = *v;
                }
            }
            ByteEdit::Delete(i, k) => {
                let at = i % n;
                let end = (at + k).min(b.len());
                if at < end {
                    b.drain(at..end);
                }
            }
            ByteEdit::Insert(i, bytes) => {
                let at = i % (b.len() + 1);
                b.splice(at..at, bytes.iter().copied());
            }
            ByteEdit::Truncate(i) => b.truncate(i % n),
        }
    }
    b
}

fn apply(text: &str, edits: &[Edit]) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    for e in edits {
        if lines.is_empty() {
            lines.push(String::new());
        }
        let n = lines.len();
        match e {
            Edit::DeleteLine(i) => {
                lines.remove(i % n);
            }
            Edit::DuplicateLine(i) => {
                let k = i % n;
                lines.insert(k, lines[k].clone());
            }
            Edit::SwapLines(a, b) => lines.swap(a % n, b % n),
            Edit::ReplaceValue(l, t, v) => {
                let line = &mut lines[l % n];
                let value = VALUES[v % VALUES.len()];
                if let Some((key, _)) = line.split_once('=') {
                    *line = format!("{key}= {value}");
                } else {
                    let mut toks: Vec<&str> = line.split_whitespace().collect();
                    if toks.is_empty() {
                        *line = value.to_string();
                    } else {
                        let k = t % toks.len();
                        toks[k] = value;
                        *line = toks.join(" ");
                    }
                }
            }
            Edit::Insert(l, c, s) => {
                let line = &mut lines[l % n];
                let at = line
                    .char_indices()
                    .map(|(i, _)| i)
                    .chain([line.len()])
                    .nth(c % (line.chars().count() + 1))
                    .unwrap_or(line.len());
                line.insert_str(at, SNIPPETS[s % SNIPPETS.len()]);
            }
            Edit::Truncate(i) => lines.truncate(i % n),
        }
    }
    lines.join("\n")
}

/// The leaf paths of a model in `--set` form (`a.b.c`, `a.b[2]`).
fn leaf_paths(text: &str) -> Vec<String> {
    fn walk(prefix: &str, v: &toml::Value, out: &mut Vec<String>) {
        match v {
            toml::Value::Table(t) => {
                for (k, x) in t {
                    let p = if prefix.is_empty() {
                        k.clone()
                    } else {
                        format!("{prefix}.{k}")
                    };
                    walk(&p, x, out);
                }
            }
            toml::Value::Array(a) => {
                out.push(prefix.to_string());
                for (i, x) in a.iter().enumerate() {
                    walk(&format!("{prefix}[{i}]"), x, out);
                }
            }
            _ => out.push(prefix.to_string()),
        }
    }
    let mut out = Vec::new();
    walk(
        "",
        &toml::Value::Table(toml::from_str(text).expect("example parses")),
        &mut out,
    );
    out
}

/// A `--set` override: a real path of the model (sometimes with a bad index or suffix) and a
/// value from [`VALUES`], or arbitrary text.
fn set_override(paths: Vec<String>) -> impl Strategy<Value = String> {
    let suffixes = prop_oneof![
        Just(String::new()),
        Just("[-1]".to_string()),
        Just("[abc]".to_string()),
        Just("[0]x".to_string()),
        Just("[99999999999999999999]".to_string()),
        Just("[7]".to_string()),
        Just(".extra".to_string()),
        "[a-z_.\\[\\]0-9]{0,6}",
    ];
    prop_oneof![
        4 => (any::<usize>(), suffixes, any::<usize>()).prop_map(move |(p, suf, v)| {
            format!("{}{suf}={}", paths[p % paths.len()], VALUES[v % VALUES.len()])
        }),
        1 => "\\PC{0,40}",
    ]
}

fn plate_toml() -> (String, String) {
    let p =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../meid-cli/tests/data/clamped_plate.toml");
    let text = std::fs::read_to_string(&p).expect("clamped_plate.toml");
    (p.display().to_string(), text)
}

/// A number as a CLI user might type it, boundary values included.
const NUM: &str = "(-?[0-9]{0,4}(\\.[0-9]{0,3})?(e-?[0-9]{1,3})?|nan|inf|-inf|1e308|0|-0)";

fn rx(pattern: &str) -> BoxedStrategy<String> {
    proptest::string::string_regex(pattern)
        .expect("a valid pattern")
        .boxed()
}

fn spec() -> impl Strategy<Value = String> {
    let name = "(wd/ws|ws/w_ref|wd/w_ref|md/mb|wd/wx|damper\\.mass|slider\\.velocity|damper\\.stiffness|contact\\.slider_bed\\.stiffness|structure\\.lumped\\.damping_ratios\\[[-0-9a]{0,3}\\]|simulation\\.duration|[a-z_.\\[\\]0-9]{0,16})";
    prop_oneof![
        // --vary NAME=LIST
        rx(&format!("{name}=({NUM},){{0,4}}{NUM}")),
        // --vary NAME=A..B:N[:log]
        rx(&format!(
            "{name}={NUM}\\.\\.{NUM}(:[0-9]{{0,4}})?(:log|:lin|:)?"
        )),
        // montecarlo --vary PATH=DIST(a,b) and the distribution alone
        rx(&format!(
            "({name}=)?(normal|lognormal|uniform|Normal|beta|)\\(({NUM},?){{0,3}}\\)?"
        )),
        // optimize --bounds PATH=LO..HI
        rx(&format!("{name}={NUM}\\.\\.{NUM}")),
        // a name alone (--over), an objective, a case
        rx(name),
        rx("(energy|bed-accel|floor-force|as-specified|none|damper|added-mass)[a-z-]{0,2}"),
        // anything
        rx("\\PC{0,60}"),
        any::<String>().boxed(),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2048))]

    #[test]
    fn model_parser_any_text(text in "\\PC{0,400}") {
        check_model("fuzz.toml", &text, &[]);
    }

    #[test]
    fn model_parser_lumped_mutations(edits in prop::collection::vec(edit(), 1..5)) {
        check_model("paper-lumped.toml", &apply(LUMPED, &edits), &[]);
    }

    #[test]
    fn set_overrides_on_the_lumped_model(
        sets in prop::collection::vec(set_override(leaf_paths(LUMPED)), 1..4)
    ) {
        check_model("paper-lumped.toml", LUMPED, &sets);
    }

    #[test]
    fn gmsh_reader_any_text(text in "\\PC{0,400}") {
        check_gmsh(&text);
    }

    #[test]
    fn gmsh_reader_mutations(edits in prop::collection::vec(edit(), 1..6)) {
        check_gmsh(&apply(PLATE_MSH, &edits));
    }

    #[test]
    fn gmsh_binary_mutations(edits in prop::collection::vec(byte_edit(), 1..6)) {
        check_gmsh_bytes(&apply_bytes(PLATE_MSH_B41, &edits));
    }

    #[test]
    fn gmsh_msh22_mutations(edits in prop::collection::vec(edit(), 1..6)) {
        check_gmsh(&apply(PLATE_MSH_22, &edits));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(8192))]

    #[test]
    fn cli_specifications(s in spec()) {
        check_spec(&s);
    }
}

// Finite-element models take ~0.1 s to build when the edit leaves them valid: fewer cases.
proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn model_parser_fe_mutations(edits in prop::collection::vec(edit(), 1..4)) {
        check_model("paper-soft-base.toml", &apply(FE_SOFT_BASE, &edits), &[]);
    }

    #[test]
    fn set_overrides_on_an_fe_model(
        sets in prop::collection::vec(set_override(leaf_paths(FE_SOFT_BASE)), 1..3)
    ) {
        check_model("paper-soft-base.toml", FE_SOFT_BASE, &sets);
    }

    #[test]
    fn gmsh_model_mutations(edits in prop::collection::vec(edit(), 1..4)) {
        let (name, text) = plate_toml();
        check_model(&name, &apply(&text, &edits), &[]);
    }
}

/// The edits reach the parser's error paths and also leave valid models (a suite whose every
/// input failed at the first byte would test little).
#[test]
fn edits_give_both_errors_and_valid_models() {
    use meid::model::Model;
    let load = |t: &str| Model::from_text("m.toml", t.to_string(), &[]);
    assert!(load(LUMPED).is_ok());
    let line = |pred: &dyn Fn(&str) -> bool| LUMPED.lines().position(pred).unwrap();
    let value = |v: &str| VALUES.iter().position(|x| *x == v).unwrap();
    // A comment deleted: still valid.
    let comment = line(&|l| l.starts_with('#'));
    assert!(load(&apply(LUMPED, &[Edit::DeleteLine(comment)])).is_ok());
    // The slider's velocity replaced by nan or a string: refused, naming the field.
    let velocity = line(&|l| l.trim_start().starts_with("velocity"));
    for v in ["nan", "\"x\""] {
        let text = apply(LUMPED, &[Edit::ReplaceValue(velocity, 0, value(v))]);
        assert!(text.contains(&format!("velocity = {v}")), "{text}");
        let e = load(&text).expect_err("refused");
        assert!(e.to_string().contains("velocity"), "{e}");
    }
    // Insertions keep the text UTF-8 and land where asked.
    let t = apply("ab\ncd", &[Edit::Insert(1, 1, 0)]);
    assert_eq!(t, "ab\nc=d");
    // The --set paths are real ones.
    let paths = leaf_paths(LUMPED);
    assert!(paths.iter().any(|p| p == "slider.velocity"), "{paths:?}");
}

/// Found by this suite: `lognormal(2,1e308)` was accepted and drew NaN and infinite values
/// (s² = ln(1 + cov²) = inf), as did `normal(0,1e308)` (1e308 z overflows) and
/// `uniform(-1e308,1e308)` (high − low overflows). Each is now refused, saying why; the
/// largest finite cases are still accepted. And `uniform(1e308,1e308)` reported an infinite
/// mean ((low + high)/2 overflowed): the mean is now low/2 + high/2.
#[test]
fn distributions_that_draw_infinity_are_refused() {
    use meid::analysis::montecarlo::Distribution;
    for bad in [
        "lognormal(2,1e308)",
        "lognormal(1e308,0.1)",
        "normal(0,1e308)",
        "normal(1.7e308,1e307)",
        "uniform(-1e308,1e308)",
    ] {
        let e = Distribution::parse(bad).expect_err(bad).to_string();
        assert!(e.contains("beyond the range of numbers"), "{bad}: {e}");
    }
    for good in [
        "lognormal(2,1e150)",
        "lognormal(1e300,0.1)",
        "normal(0,1e300)",
        "uniform(-1e307,1e307)",
        "normal(1.7e308,1)",
    ] {
        let d = Distribution::parse(good).expect(good);
        let mut rng = meid::analysis::montecarlo::SplitMix64::new(7);
        assert!((0..1000).all(|_| d.sample(&mut rng).is_finite()), "{good}");
    }
    let d = Distribution::parse("uniform(1e308,1.5e308)").unwrap();
    assert_eq!(d.mean(), 1.25e308);
    let d = Distribution::parse("uniform(-3,5)").unwrap();
    assert_eq!(d.mean(), 1.0);
}

// Issue 27: `model expand` refuses exactly what a model load refuses (item 8), on `--set`
// mutations of the FE soft base (each case solves the machine once or twice: few cases).
proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn model_expand_refuses_what_a_load_refuses(
        sets in prop::collection::vec(set_override(leaf_paths(FE_SOFT_BASE)), 1..2)
    ) {
        use meid::model::Model;
        let load = Model::from_text("paper-soft-base.toml", FE_SOFT_BASE.to_string(), &sets);
        let expand = meid::model::expand::expand_text("paper-soft-base.toml", FE_SOFT_BASE, &sets);
        match (&load, &expand) {
            (Err(a), Err(b)) => prop_assert_eq!(a.to_string(), b.to_string()),
            (Ok(_), Ok(text)) => {
                // The expanded file loads too.
                prop_assert!(Model::from_text("x.toml", text.clone(), &[]).is_ok());
            }
            // A set that removes the machine: expand refuses, a load may run.
            (Ok(_), Err(e)) => prop_assert!(e.to_string().contains("structure"), "{e}"),
            (Err(e), Ok(_)) => prop_assert!(false, "expand wrote a model the load refuses: {e}"),
        }
    }
}

/// A small sweep of the lumped example and its journal (fresh run).
fn journal_sweep(dir: &std::path::Path) -> (meid::analysis::sweep::Sweep, String, Vec<u8>) {
    use meid::analysis::sweep::{Sweep, Vary};
    let m = meid::model::Model::from_text("paper-lumped.toml", LUMPED.to_string(), &[]).unwrap();
    let s = Sweep::new(m, vec![Vary::parse("damper.mass=2,3.5,5").unwrap()]).unwrap();
    std::fs::create_dir_all(dir).unwrap();
    let j = dir.join("j.csv");
    let r = s.run_resumable(&j, false, &|_, _| {}).unwrap();
    (s, r.csv(), std::fs::read(&j).unwrap())
}

// Issue 27, item 4: whatever bytes of a sweep journal's rows are changed, `--resume` gives the
// table of a fresh run, byte for byte: a changed row fails its checksum (or its cells are
// refused) and is computed again; nothing of an edited row reaches the table.
proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn an_edited_journal_resumes_to_the_fresh_table(edits in prop::collection::vec(byte_edit(), 1..4)) {
        let dir = std::env::temp_dir().join(format!("meid-fuzz-journal-{}", std::process::id()));
        let (s, want, journal) = journal_sweep(&dir);
        // Keep the first line and the header: edit the rows.
        let head = journal
            .iter()
            .enumerate()
            .filter(|(_, b)| **b == b'\n')
            .nth(1)
            .map(|(i, _)| i + 1)
            .unwrap();
        let mut rows = apply_bytes(&journal[head..], &edits);
        let mut text = journal[..head].to_vec();
        text.append(&mut rows);
        let j = dir.join("j.csv");
        std::fs::write(&j, &text).unwrap();
        let r = s.run_resumable(&j, true, &|_, _| {}).unwrap();
        prop_assert_eq!(r.csv(), want);
    }
}
