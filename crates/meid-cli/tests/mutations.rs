//! The mutation suite over the examples (issue 15): every key of the four example models is
//! deleted, and every number (also inside arrays and inline tables) set to 0, −1, NaN, inf,
//! 1e308 and a string. `meid simulate --json` on each mutant must either exit 0 with every
//! number of its JSON finite (no `null` where the unmutated example has a number), or exit 2
//! with stderr naming the mutated field (its path, the array holding it, or, for a deleted
//! key, the table missing it and the key). Anything else (a panic, an abort, another exit code,
//! a message that does not name the field, a run longer than [`TIMEOUT`]) is a defect.
//!
//! By default (CI) a deterministic sample runs: every mutation whose index is a multiple of
//! [`STRIDE`] (offset 0), half of the whole (≈ 20 s on 2 cores; the whole suite, 841 mutations, ≈ 40 s). `MEID_MUTATIONS=all` runs them all.
//! Each mutant's simulated time is cut to [`DURATION_S`] (unless the mutation is to
//! `simulation.duration` itself), so the run's cost is the model's build, not its length.
//!
//! Not mutated: `simulation.duration` and `simulation.sample_rate` to 1e308 (a run of 1e308 s,
//! or 1e308 samples per second: bounding such runs is the "unbounded cost" part of the issue,
//! with its own tests).

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use common::{example_file, meid, tmpdir};
use toml::{Table, Value};

/// Simulated time of every mutant (s).
const DURATION_S: f64 = 0.01;
/// The default sample: every STRIDE-th mutation.
const STRIDE: usize = 2;
/// A mutant running longer than this is a defect (a hang).
const TIMEOUT: Duration = Duration::from_secs(120);

const EXAMPLES: [&str; 4] = [
    "paper-lumped.toml",
    "paper-soft-base.toml",
    "paper-stiff-base.toml",
    "paper-no-base.toml",
];

#[derive(Clone, Debug)]
enum Change {
    Delete,
    Set(Value),
}

#[derive(Clone, Debug)]
struct Mutation {
    example: &'static str,
    /// Dotted path of the mutated value, `a.b[2].c`.
    path: String,
    change: Change,
}

impl Mutation {
    fn label(&self) -> String {
        match &self.change {
            Change::Delete => format!("{}: delete {}", self.example, self.path),
            Change::Set(Value::Float(x)) => format!("{}: {} = {x:e}", self.example, self.path),
            Change::Set(v) => format!("{}: {} = {v}", self.example, self.path),
        }
    }
}

/// One segment of a path: a key or an array index.
#[derive(Clone, Debug)]
enum Seg {
    Key(String),
    Index(usize),
}

fn path_text(segs: &[Seg]) -> String {
    let mut s = String::new();
    for seg in segs {
        match seg {
            Seg::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(k);
            }
            Seg::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

fn number_values() -> Vec<Value> {
    vec![
        Value::Float(0.0),
        Value::Float(-1.0),
        Value::Float(f64::NAN),
        Value::Float(f64::INFINITY),
        Value::Float(1e308),
        Value::String("x".into()),
    ]
}

/// Every mutation of `v` at `segs` and below.
fn walk(v: &Value, segs: &mut Vec<Seg>, out: &mut Vec<(Vec<Seg>, Change)>) {
    match v {
        Value::Table(t) => {
            for (k, child) in t {
                segs.push(Seg::Key(k.clone()));
                out.push((segs.clone(), Change::Delete));
                walk(child, segs, out);
                segs.pop();
            }
        }
        Value::Array(a) => {
            for (i, child) in a.iter().enumerate() {
                segs.push(Seg::Index(i));
                walk(child, segs, out);
                segs.pop();
            }
        }
        Value::Integer(_) | Value::Float(_) => {
            let p = path_text(segs);
            for new in number_values() {
                let huge = matches!(new, Value::Float(x) if x == 1e308);
                if huge && (p == "simulation.duration" || p == "simulation.sample_rate") {
                    continue; // module docs
                }
                out.push((segs.clone(), Change::Set(new)));
            }
        }
        _ => {}
    }
}

fn all_mutations() -> Vec<(Mutation, Vec<Seg>)> {
    let mut all = Vec::new();
    for example in EXAMPLES {
        let table = base_table(example);
        let mut found = Vec::new();
        walk(&Value::Table(table), &mut Vec::new(), &mut found);
        for (segs, change) in found {
            all.push((
                Mutation {
                    example,
                    path: path_text(&segs),
                    change,
                },
                segs,
            ));
        }
    }
    all
}

/// The example with its simulated time cut to [`DURATION_S`].
fn base_table(example: &str) -> Table {
    let text = std::fs::read_to_string(example_file(example)).unwrap();
    let mut t: Table = toml::from_str(&text).unwrap();
    let sim = t
        .entry("simulation")
        .or_insert_with(|| Value::Table(Table::new()))
        .as_table_mut()
        .unwrap();
    sim.insert("duration".into(), Value::Float(DURATION_S));
    t
}

fn apply(table: &mut Table, segs: &[Seg], change: &Change) {
    let (first, rest) = segs.split_first().unwrap();
    let Seg::Key(k) = first else {
        panic!("a path starts with a key")
    };
    if rest.is_empty() {
        match change {
            Change::Delete => {
                table.remove(k);
            }
            Change::Set(v) => {
                table.insert(k.clone(), v.clone());
            }
        }
    } else {
        apply_value(table.get_mut(k).unwrap(), rest, change);
    }
}

fn apply_value(v: &mut Value, segs: &[Seg], change: &Change) {
    match (&segs[0], v) {
        (Seg::Key(_), Value::Table(t)) => apply(t, segs, change),
        (Seg::Index(i), Value::Array(a)) => {
            if segs.len() == 1 {
                match change {
                    Change::Delete => {
                        a.remove(*i);
                    }
                    Change::Set(x) => a[*i] = x.clone(),
                }
            } else {
                apply_value(&mut a[*i], &segs[1..], change);
            }
        }
        _ => panic!("the path does not match the table"),
    }
}

/// The paths (in the JSON of `meid simulate --json`) holding `null`.
fn nulls(v: &serde_json::Value, at: &str, out: &mut Vec<String>) {
    match v {
        serde_json::Value::Null => out.push(at.to_string()),
        serde_json::Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                nulls(x, &format!("{at}[{i}]"), out);
            }
        }
        serde_json::Value::Object(o) => {
            for (k, x) in o {
                nulls(x, &format!("{at}.{k}"), out);
            }
        }
        _ => {}
    }
}

/// Runs `meid simulate FILE --json` with a time limit: (exit code, stdout, stderr), `None`
/// for the code when the limit was hit.
fn run(file: &Path) -> (Option<i32>, String, String) {
    let mut child = meid()
        .args(["simulate", file.to_str().unwrap(), "--json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let out_pipe = child.stdout.take().unwrap();
    let err_pipe = child.stderr.take().unwrap();
    let read = |mut p: Box<dyn std::io::Read + Send>| {
        std::thread::spawn(move || {
            let mut s = String::new();
            let _ = p.read_to_string(&mut s);
            s
        })
    };
    let out_t = read(Box::new(out_pipe));
    let err_t = read(Box::new(err_pipe));
    let t0 = Instant::now();
    let code = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status.code();
        }
        if t0.elapsed() > TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    (code, out_t.join().unwrap(), err_t.join().unwrap())
}

/// Does `stderr` name the mutated field?
fn names_field(stderr: &str, m: &Mutation, segs: &[Seg]) -> bool {
    if stderr.contains(&m.path) {
        return true;
    }
    // A mutation of the structure that changes which modes are retained leaves the file's
    // `structure.reference_mode` (a structure mode number) naming a mode no longer kept: the
    // error names that dependent field and lists the retained modes, which is what to fix.
    if stderr.contains("structure.reference_mode") && stderr.contains("the retained modes are") {
        return true;
    }
    // The array holding a mutated element (`damping_ratios` for `damping_ratios[1]`).
    if let Some(Seg::Index(_)) = segs.last() {
        let parent = path_text(&segs[..segs.len() - 1]);
        if !parent.is_empty() && stderr.contains(&format!("{parent}:")) {
            return true;
        }
    }
    // A deleted key: the key (a missing required field) or the table missing it (an
    // optional field whose default does not fit the rest of the model).
    if let (Change::Delete, Some(Seg::Key(k))) = (&m.change, segs.last()) {
        let parent = path_text(&segs[..segs.len() - 1]);
        if stderr.contains(&format!("`{k}`")) || (!parent.is_empty() && stderr.contains(&parent)) {
            return true;
        }
    }
    false
}

#[test]
fn every_mutation_of_the_examples_gives_finite_output_or_an_error_naming_the_field() {
    let bin_dir = tmpdir("mutations", "files");
    let all = all_mutations();
    let total = all.len();
    let every = std::env::var("MEID_MUTATIONS").is_ok_and(|v| v == "all");
    let chosen: Vec<(Mutation, Vec<Seg>)> = all
        .into_iter()
        .enumerate()
        .filter(|(i, _)| every || i % STRIDE == 0)
        .map(|(_, m)| m)
        .collect();
    // The unmutated examples: their JSON's nulls are the baseline.
    let mut base_nulls = std::collections::BTreeMap::new();
    for example in EXAMPLES {
        let file = bin_dir.join(format!("base-{example}"));
        std::fs::write(&file, toml::to_string(&base_table(example)).unwrap()).unwrap();
        let (code, out, err) = run(&file);
        assert_eq!(code, Some(0), "{example} itself fails: {err}");
        let json: serde_json::Value = serde_json::from_str(&out).unwrap();
        let mut n = Vec::new();
        nulls(&json, "", &mut n);
        base_nulls.insert(example, n);
    }
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let next = AtomicUsize::new(0);
    let failures: Mutex<Vec<String>> = Mutex::new(Vec::new());
    let counts = Mutex::new([0usize; 2]); // [exit 0, exit 2]
    let t0 = Instant::now();
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some((m, segs)) = chosen.get(i) else {
                    break;
                };
                let mut table = base_table(m.example);
                apply(&mut table, segs, &m.change);
                let file: PathBuf = bin_dir.join(format!("m{i}.toml"));
                std::fs::write(&file, toml::to_string(&table).unwrap()).unwrap();
                let (code, out, err) = run(&file);
                let _ = std::fs::remove_file(&file);
                let verdict = match code {
                    Some(0) => match serde_json::from_str::<serde_json::Value>(&out) {
                        Ok(json) => {
                            let mut n = Vec::new();
                            nulls(&json, "", &mut n);
                            let base = &base_nulls[m.example];
                            // Without a damper its summary entries are null by design.
                            let no_damper = matches!(m.change, Change::Delete)
                                && (m.path == "damper" || m.path == "contact.bed_damper");
                            // An impact's restitution is null by design when it closes
                            // with no approach velocity (a contact touching at the strike);
                            // the impact rows' order follows the machine.
                            let undefined_restitution = |p: &str| {
                                p.starts_with(".impacts[") && p.ends_with("].restitution")
                            };
                            let new: Vec<&String> = n
                                .iter()
                                .filter(|p| !base.contains(p))
                                .filter(|p| !(no_damper && p.contains("damper")))
                                .filter(|p| !undefined_restitution(p))
                                .collect();
                            if new.is_empty() {
                                counts.lock().unwrap()[0] += 1;
                                None
                            } else {
                                Some(format!("exit 0 with non-finite values at {new:?}"))
                            }
                        }
                        Err(e) => Some(format!("exit 0 but stdout is not JSON: {e}")),
                    },
                    Some(2) if names_field(&err, m, segs) => {
                        counts.lock().unwrap()[1] += 1;
                        None
                    }
                    Some(2) => Some(format!("exit 2 without naming the field: {}", err.trim())),
                    Some(c) => Some(format!("exit {c}: {}", err.trim())),
                    None => Some(format!("no answer within {} s", TIMEOUT.as_secs())),
                };
                if let Some(v) = verdict {
                    failures.lock().unwrap().push(format!(
                        "{}\n    {}",
                        m.label(),
                        v.replace('\n', "\n    ")
                    ));
                }
            });
        }
    });
    let _ = std::fs::remove_dir_all(&bin_dir);
    let failures = failures.into_inner().unwrap();
    let [ok, refused] = counts.into_inner().unwrap();
    eprintln!(
        "mutations: {} of {total} run ({}) in {:.1} s on {threads} threads: {ok} exit 0 with finite output, {refused} refused naming the field, {} defects",
        chosen.len(),
        if every { "all" } else { "sample" },
        t0.elapsed().as_secs_f64(),
        failures.len()
    );
    assert!(
        failures.is_empty(),
        "{} of {} mutations misbehave:\n{}",
        failures.len(),
        chosen.len(),
        failures.join("\n")
    );
}
