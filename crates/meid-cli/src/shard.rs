//! `--shard K/N` (sweep, montecarlo) and `meid merge`: a study split into N independent runs
//! that can go to N machines (e.g. a Slurm job array, docs/explanations/studies.md), then put together into
//! the files the unsharded run writes, byte for byte.
//!
//! Shard K of N (1 ≤ K ≤ N) of a study of T points or samples computes the indices
//! `⌊(K−1)T/N⌋ .. ⌊KT/N⌋` — from the specification alone, with no coordination. Its `-o DIR`
//! holds `shard.json` (the command's arguments, its working directory, K, N, the index range
//! and the study's fingerprint) and `shard.csv` (the rows in exact round-trip form, each
//! followed by its checksum, `meid::input::seal_row`; the header gains `row_fnv1a`). `meid merge
//! DIR... -o OUT` reads the arguments back, rebuilds the study the same way, checks that every
//! shard belongs to it (same fingerprint), that every row matches its checksum and that the
//! shards cover every index exactly once, and writes OUT as the unsharded command would. A
//! row edited or cut short is refused, naming the file and line.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use serde_json::json;

/// `K/N`, parsed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 1-based.
    pub k: usize,
    pub n: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let usage = format!("`{s}`: expected K/N with 1 <= K <= N, e.g. 3/16");
        let (k, n) = s.split_once('/').ok_or_else(|| usage.clone())?;
        let k: usize = k.trim().parse().map_err(|_| usage.clone())?;
        let n: usize = n.trim().parse().map_err(|_| usage.clone())?;
        if n == 0 || k == 0 || k > n {
            return Err(usage);
        }
        Ok(Shard { k, n })
    }
}

impl Shard {
    /// The index range of this shard in a study of `total` indices.
    pub fn range(&self, total: usize) -> std::ops::Range<usize> {
        let at = |k: usize| ((k as u128 * total as u128) / self.n as u128) as usize;
        at(self.k - 1)..at(self.k)
    }
}

/// The command line of this run without `--shard`, `-o/--output` and the output-format flags
/// (`--json`, `-q/--quiet`), which a merge supplies itself.
fn study_args() -> Vec<String> {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    let mut out = Vec::new();
    let mut skip_next = false;
    for a in argv {
        if skip_next {
            skip_next = false;
            continue;
        }
        match a.as_str() {
            "--shard" | "-o" | "--output" => skip_next = true,
            "--json" | "-q" | "--quiet" => {}
            _ if a.starts_with("--shard=") || a.starts_with("--output=") => {}
            _ if a.starts_with("-o") && a.len() > 2 && !a.starts_with("--") => {}
            _ => out.push(a),
        }
    }
    out
}

/// Writes a shard's files into `dir` (an output set, as every `-o DIR`).
pub fn write(
    dir: &Path,
    command: &str,
    shard: Shard,
    range: std::ops::Range<usize>,
    total: usize,
    fingerprint: &str,
    rows: &[u8],
) -> Result<Vec<PathBuf>> {
    let set = crate::outputs::begin(dir)?;
    let cwd = std::env::current_dir().context("cannot read the working directory")?;
    let desc = json!({
        "meid_shard": 2,
        "command": command,
        "args": study_args(),
        "cwd": cwd,
        "shard": shard.k,
        "shards": shard.n,
        "first": range.start,
        "end": range.end,
        "total": total,
        "fingerprint": fingerprint,
    });
    meid::io::write_json(&set.staging().join("shard.json"), &desc)?;
    let mut sealed = String::with_capacity(rows.len() + rows.len() / 4);
    for (i, line) in String::from_utf8_lossy(rows).lines().enumerate() {
        if i == 0 {
            sealed.push_str(line);
            sealed.push_str(",row_fnv1a");
        } else {
            sealed.push_str(&meid::input::seal_row(line));
        }
        sealed.push('\n');
    }
    meid::io::write_atomic(&set.staging().join("shard.csv"), sealed.as_bytes())?;
    Ok(set.commit(&format!("{command} --shard"))?)
}

/// One shard read back.
pub struct ShardFiles {
    pub dir: PathBuf,
    pub command: String,
    pub args: Vec<String>,
    pub cwd: PathBuf,
    pub first: usize,
    pub end: usize,
    pub total: usize,
    pub fingerprint: String,
    /// `shard.csv` without the row checksums (each verified), lines as in the file.
    pub rows: Vec<u8>,
}

/// Reads `DIR/shard.json` and `DIR/shard.csv`.
pub fn read(dir: &Path) -> Result<ShardFiles> {
    let jp = dir.join("shard.json");
    if !jp.exists() {
        bail!(
            "{}: not a shard (no shard.json; write shards with --shard K/N -o DIR)",
            dir.display()
        );
    }
    let text = meid::input::read_text(&jp)?;
    let v: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{}", jp.display()))?;
    let bad = |f: &str| anyhow::anyhow!("{}: field `{f}` missing or invalid", jp.display());
    let s = |f: &str| -> Result<String> {
        Ok(v.get(f)
            .and_then(|x| x.as_str())
            .ok_or_else(|| bad(f))?
            .to_string())
    };
    let u = |f: &str| -> Result<usize> {
        Ok(v.get(f).and_then(|x| x.as_u64()).ok_or_else(|| bad(f))? as usize)
    };
    match v.get("meid_shard").and_then(|x| x.as_u64()) {
        Some(2) => {}
        Some(1) => bail!(
            "{}: a shard of an older meid (version 1, rows without checksums, which cannot be verified); run the shard again",
            jp.display()
        ),
        _ => bail!("{}: not a meid shard (`meid_shard` must be 2)", jp.display()),
    }
    let args = v
        .get("args")
        .and_then(|a| a.as_array())
        .ok_or_else(|| bad("args"))?
        .iter()
        .map(|x| x.as_str().map(String::from).ok_or_else(|| bad("args")))
        .collect::<Result<Vec<_>>>()?;
    let cp = dir.join("shard.csv");
    let rows = unseal(&cp, &meid::input::read_bytes(&cp)?)?;
    Ok(ShardFiles {
        dir: dir.to_path_buf(),
        command: s("command")?,
        args,
        cwd: PathBuf::from(s("cwd")?),
        first: u("first")?,
        end: u("end")?,
        total: u("total")?,
        fingerprint: s("fingerprint")?,
        rows,
    })
}

/// The lines of `shard.csv` (`data`) without their checksums: the header without its
/// `row_fnv1a` column, every row checked against its checksum (an edited or cut row is
/// refused, naming `path` and the line).
fn unseal(path: &Path, data: &[u8]) -> Result<Vec<u8>> {
    let text = std::str::from_utf8(data)
        .map_err(|_| anyhow::anyhow!("{}: not UTF-8 text", path.display()))?;
    let mut out = String::with_capacity(text.len());
    for (i, line) in text.split_inclusive('\n').enumerate() {
        let Some(line) = line.strip_suffix('\n') else {
            bail!(
                "{}:{}: the last line is cut short (no newline); run the shard again",
                path.display(),
                i + 1
            );
        };
        let plain = if i == 0 {
            line.strip_suffix(",row_fnv1a").ok_or_else(|| {
                anyhow::anyhow!(
                    "{}:1: the header does not end with the checksum column `row_fnv1a`",
                    path.display()
                )
            })?
        } else {
            meid::input::unseal_row(line).ok_or_else(|| {
                anyhow::anyhow!(
                    "{}:{}: the row does not match its checksum (edited or damaged: '{}'); run the shard again",
                    path.display(),
                    i + 1,
                    meid::input::clip(line)
                )
            })?
        };
        out.push_str(plain);
        out.push('\n');
    }
    Ok(out.into_bytes())
}

/// `meid merge`.
#[derive(clap::Args)]
pub struct MergeArgs {
    /// Shard directories (written by `meid sweep|montecarlo … --shard K/N -o DIR`).
    #[arg(required = true, value_name = "DIR")]
    shards: Vec<PathBuf>,
    /// Output directory: the files the unsharded run writes.
    #[arg(short, long, value_name = "DIR", required = true)]
    output: PathBuf,
    #[command(flatten)]
    print: crate::args::PrintArgs,
}

/// `meid merge`: the shards read and checked to be one study's, the study's command line
/// rebuilt (with the merge's `-o` and print flags) and its working directory entered; then
/// `merge_study` runs the study's own merge. It is given the shards' command name and their
/// parsed command line and answers `None` when that is no sharded study: this module writes
/// and reads shards for any study and knows none of them.
pub fn merge(
    a: MergeArgs,
    merge_study: impl FnOnce(&str, crate::Command, &[ShardFiles]) -> Option<Result<()>>,
) -> Result<()> {
    let shards = a
        .shards
        .iter()
        .map(|d| read(d))
        .collect::<Result<Vec<_>>>()?;
    let first = &shards[0];
    for s in &shards[1..] {
        if s.command != first.command || s.fingerprint != first.fingerprint {
            bail!(
                "{} and {} are shards of different studies ({} {} vs {} {})",
                first.dir.display(),
                s.dir.display(),
                first.command,
                first.args.join(" "),
                s.command,
                s.args.join(" ")
            );
        }
    }
    // Paths given relative to the merge's directory, before moving to the study's.
    let output = std::path::absolute(&a.output).context("-o")?;
    let mut argv = vec!["meid".to_string()];
    argv.extend(first.args.iter().cloned());
    argv.push("-o".into());
    argv.push(output.display().to_string());
    if a.print.json {
        argv.push("--json".into());
    }
    if a.print.quiet {
        argv.push("-q".into());
    }
    let cli = <crate::Cli as clap::Parser>::try_parse_from(&argv)
        .map_err(|e| anyhow::anyhow!("the shards' command line does not parse: {e}"))?;
    std::env::set_current_dir(&first.cwd).with_context(|| {
        format!(
            "cannot enter the shards' working directory {} (model paths are relative to it)",
            first.cwd.display()
        )
    })?;
    merge_study(&first.command, cli.command, &shards).unwrap_or_else(|| {
        bail!(
            "{}: cannot merge shards of `{}`",
            first.dir.display(),
            first.command
        )
    })
}

/// Checks that `shards` (whose fingerprints must be `fingerprint`) cover `0..total` exactly
/// once, naming the gap or the overlap.
pub fn check_cover(shards: &[ShardFiles], fingerprint: &str, total: usize) -> Result<()> {
    for s in shards {
        if s.fingerprint != fingerprint {
            bail!(
                "{}: this shard was computed from another model or options than the study rebuilt now (fingerprint {} vs {fingerprint}); was the model file changed?",
                s.dir.display(),
                s.fingerprint
            );
        }
        if s.total != total {
            bail!(
                "{}: a shard of a study of {} indices, this one has {total}",
                s.dir.display(),
                s.total
            );
        }
    }
    let mut ranges: Vec<(usize, usize, &Path)> = shards
        .iter()
        .map(|s| (s.first, s.end, s.dir.as_path()))
        .collect();
    ranges.sort();
    let mut at = 0;
    for (a, b, d) in ranges {
        if a > at {
            bail!("indices {at}..{a} are in no shard given (of {total}); add the missing shard(s)");
        }
        if a < at {
            bail!(
                "{} overlaps another shard (indices {a}..{}); give each shard once",
                d.display(),
                at.min(b)
            );
        }
        at = b;
    }
    if at != total {
        bail!("indices {at}..{total} are in no shard given; add the missing shard(s)");
    }
    Ok(())
}
