//! Terminal conventions of the command line: standard output that survives a closed pipe,
//! the colour choice (`--color`, `NO_COLOR`, `CLICOLOR_FORCE`) and coloured `error:` /
//! `warning:` prefixes.
//!
//! Every `print!`/`println!` of this crate goes through [`write_stdout`] (the crate shadows the
//! standard macros in `main.rs`), so no subcommand can panic on `meid … | head -1`: once the
//! reader has gone, later output is dropped and the run finishes normally (its `-o` files are
//! still written whole). Any other failure to write standard output (a full disk behind
//! `> file`) is kept and reported by `main` as an error with exit code 2.

use std::io::{self, IsTerminal, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// `--color`: when to colour the output.
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ColorChoice {
    /// Colour a stream that is a terminal, unless `NO_COLOR` is set (non-empty);
    /// `CLICOLOR_FORCE` (non-empty, not `0`) colours even when it is not a terminal.
    #[default]
    Auto,
    /// Always colour (even into a pipe or a file).
    Always,
    /// Never colour.
    Never,
}

impl ColorChoice {
    /// The value of `--color` in `args` (the last one wins, as for clap), before clap parses
    /// them, so that clap's own messages follow it too. `Auto` when absent or not a valid
    /// value (clap then reports the invalid value).
    pub fn from_args<I: IntoIterator<Item = std::ffi::OsString>>(args: I) -> Self {
        let mut choice = ColorChoice::Auto;
        let mut next_is_value = false;
        for a in args.into_iter().skip(1) {
            let a = a.to_string_lossy().into_owned();
            let value = if next_is_value {
                next_is_value = false;
                Some(a.as_str())
            } else if a == "--" {
                break;
            } else if a == "--color" {
                next_is_value = true;
                None
            } else {
                a.strip_prefix("--color=")
            };
            if let Some(v) = value {
                choice = match v {
                    "always" => ColorChoice::Always,
                    "never" => ColorChoice::Never,
                    _ => ColorChoice::Auto,
                };
            }
        }
        choice
    }

    /// Whether a stream is coloured: `Always`/`Never` as said; `Auto` by the environment
    /// (`no_color`: `NO_COLOR` set and non-empty; `force`: `CLICOLOR_FORCE` set, non-empty
    /// and not `0`) and
    /// whether the stream is a terminal. `NO_COLOR` wins over `CLICOLOR_FORCE`.
    pub fn colours(self, is_terminal: bool, no_color: bool, force: bool) -> bool {
        match self {
            ColorChoice::Always => true,
            ColorChoice::Never => false,
            ColorChoice::Auto => !no_color && (force || is_terminal),
        }
    }

    /// clap's equivalent, for clap's own help and usage errors.
    pub fn to_clap(self) -> clap::ColorChoice {
        match self {
            ColorChoice::Auto => clap::ColorChoice::Auto,
            ColorChoice::Always => clap::ColorChoice::Always,
            ColorChoice::Never => clap::ColorChoice::Never,
        }
    }
}

/// `NO_COLOR` is set to a non-empty value (any value, `0` included: no-color.org).
fn no_color_env() -> bool {
    std::env::var_os("NO_COLOR").is_some_and(|v| !v.is_empty())
}

/// `CLICOLOR_FORCE` is set, non-empty and not `0`.
fn clicolor_force_env() -> bool {
    std::env::var_os("CLICOLOR_FORCE").is_some_and(|v| !v.is_empty() && v != "0")
}

static COLOR_STDOUT: AtomicBool = AtomicBool::new(false);
static COLOR_STDERR: AtomicBool = AtomicBool::new(false);
static STDOUT_CLOSED: AtomicBool = AtomicBool::new(false);
static STDOUT_ERROR: Mutex<Option<io::Error>> = Mutex::new(None);

/// Decides the colouring of both streams once, at start-up.
pub fn init_color(choice: ColorChoice) {
    let no_color = no_color_env();
    let force = clicolor_force_env();
    COLOR_STDOUT.store(
        choice.colours(io::stdout().is_terminal(), no_color, force),
        Ordering::Relaxed,
    );
    COLOR_STDERR.store(
        choice.colours(io::stderr().is_terminal(), no_color, force),
        Ordering::Relaxed,
    );
}

/// True when standard output is coloured (bold figures of `simulate`'s report).
pub fn color_stdout() -> bool {
    COLOR_STDOUT.load(Ordering::Relaxed)
}

/// `text` in bold when standard output is coloured.
pub fn bold(text: &str) -> String {
    if color_stdout() {
        format!("\x1b[1m{text}\x1b[0m")
    } else {
        text.to_string()
    }
}

/// Writes to standard output (the crate's `print!`/`println!`). A closed pipe (`EPIPE`) marks
/// standard output closed and drops this and every later write; another error is kept for
/// [`finish_stdout`] and also closes the stream.
pub fn write_stdout(args: std::fmt::Arguments, newline: bool) {
    if STDOUT_CLOSED.load(Ordering::Relaxed) {
        return;
    }
    let mut out = io::stdout().lock();
    let mut r = out.write_fmt(args);
    if r.is_ok() && newline {
        r = out.write_all(b"\n");
    }
    if let Err(e) = r {
        fail_stdout(e);
    }
}

fn fail_stdout(e: io::Error) {
    STDOUT_CLOSED.store(true, Ordering::Relaxed);
    if e.kind() != io::ErrorKind::BrokenPipe {
        if let Ok(mut slot) = STDOUT_ERROR.lock() {
            slot.get_or_insert(e);
        }
    }
}

/// Writes raw bytes to standard output with the same closed-pipe handling as [`write_stdout`].
pub fn write_stdout_bytes(bytes: &[u8]) {
    if STDOUT_CLOSED.load(Ordering::Relaxed) {
        return;
    }
    if let Err(e) = io::stdout().lock().write_all(bytes) {
        fail_stdout(e);
    }
}

/// Flushes standard output at the end of a run: `Err` with the first write error other than a
/// closed pipe (a closed pipe is a normal end: the reader had what it wanted).
pub fn finish_stdout() -> io::Result<()> {
    if !STDOUT_CLOSED.load(Ordering::Relaxed) {
        if let Err(e) = io::stdout().lock().flush() {
            fail_stdout(e);
        }
    }
    match STDOUT_ERROR.lock() {
        Ok(mut slot) => slot.take().map_or(Ok(()), Err),
        Err(_) => Ok(()),
    }
}

/// Writes to standard error (the crate's `eprint!`/`eprintln!`), ignoring failures: there is
/// nowhere left to report them, and a closed standard error must not turn into a panic.
pub fn write_stderr(args: std::fmt::Arguments, newline: bool) {
    let mut err = io::stderr().lock();
    let _ = err.write_fmt(args);
    if newline {
        let _ = err.write_all(b"\n");
    }
}

/// The prefix `label:` (`error:`, `warning:`), in bold `sgr` colour when standard error is
/// coloured.
fn prefix(label: &str, sgr: &str) -> String {
    if COLOR_STDERR.load(Ordering::Relaxed) {
        format!("\x1b[1;{sgr}m{label}:\x1b[0m")
    } else {
        format!("{label}:")
    }
}

/// `error: MESSAGE` on standard error (`error:` in bold red on a coloured stream).
pub fn error(message: impl std::fmt::Display) {
    write_stderr(format_args!("{} {message}", prefix("error", "31")), true);
}

/// `warning: MESSAGE` on standard error (`warning:` in bold yellow on a coloured stream).
pub fn warning(message: impl std::fmt::Display) {
    write_stderr(format_args!("{} {message}", prefix("warning", "33")), true);
}

#[cfg(test)]
mod tests {
    use super::ColorChoice;

    fn args(a: &[&str]) -> Vec<std::ffi::OsString> {
        a.iter().map(|s| s.into()).collect()
    }

    #[test]
    fn color_flag_is_found_before_clap() {
        use ColorChoice::*;
        assert_eq!(
            ColorChoice::from_args(args(&["meid", "modes", "m.toml"])),
            Auto
        );
        assert_eq!(
            ColorChoice::from_args(args(&["meid", "--color", "never", "modes"])),
            Never
        );
        assert_eq!(
            ColorChoice::from_args(args(&["meid", "modes", "--color=always"])),
            Always
        );
        // The last one wins; after `--` nothing is an option.
        assert_eq!(
            ColorChoice::from_args(args(&["meid", "--color=always", "--color", "never"])),
            Never
        );
        assert_eq!(
            ColorChoice::from_args(args(&["meid", "x", "--", "--color=always"])),
            Auto
        );
    }

    #[test]
    fn auto_colours_a_terminal_unless_no_color() {
        use ColorChoice::*;
        // (is_terminal, NO_COLOR, CLICOLOR_FORCE)
        assert!(Auto.colours(true, false, false));
        assert!(!Auto.colours(false, false, false));
        assert!(!Auto.colours(true, true, false));
        assert!(Auto.colours(false, false, true));
        assert!(!Auto.colours(false, true, true), "NO_COLOR wins");
        assert!(
            Always.colours(false, true, false),
            "the flag wins over NO_COLOR"
        );
        assert!(!Never.colours(true, false, true));
    }
}
