//! Cost limits: what a run may allocate, estimated and checked **before** it allocates.
//!
//! Every study that could grow without bound with its inputs (the samples of a history, the
//! blows of a train, Monte Carlo samples, sweep points, finite-element matrices and their
//! factorisation) estimates its memory from those inputs and calls [`check_memory`] first. A
//! run over the limit is refused with an [`Error::InvalidValue`] naming the input to reduce,
//! the estimate, the limit and how to change it — never an out-of-memory abort.
//!
//! The limit is process-wide ([`set_max_memory`]; the CLI's global `--max-memory`). Its
//! default is half the physical memory (`MemTotal` of `/proc/meminfo`), or
//! [`FALLBACK_MAX_MEMORY_BYTES`] where that cannot be read.

use std::sync::atomic::{AtomicU64, Ordering};

use crate::{Error, Result};

/// The memory limit when the physical memory cannot be read (4 GiB).
pub const FALLBACK_MAX_MEMORY_BYTES: u64 = 4 << 30;

/// 0: not set (use [`default_max_memory`]).
static MAX_MEMORY: AtomicU64 = AtomicU64::new(0);

/// Half of `MemTotal` in `/proc/meminfo`, or [`FALLBACK_MAX_MEMORY_BYTES`].
pub fn default_max_memory() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find_map(|l| l.strip_prefix("MemTotal:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        })
        .filter(|kib| *kib > 0)
        .map_or(FALLBACK_MAX_MEMORY_BYTES, |kib| {
            kib.saturating_mul(1024) / 2
        })
}

/// The memory limit in force (bytes).
pub fn max_memory() -> u64 {
    match MAX_MEMORY.load(Ordering::Relaxed) {
        0 => default_max_memory(),
        v => v,
    }
}

/// Sets the process-wide memory limit (bytes, > 0).
pub fn set_max_memory(bytes: u64) {
    MAX_MEMORY.store(bytes.max(1), Ordering::Relaxed);
}

/// Parses a size: a whole number of bytes, optionally with a unit `B`, `KiB`, `MiB`, `GiB`,
/// `TiB` (powers of 1024; `K`, `M`, `G`, `T` too) or `kB`, `MB`, `GB`, `TB` (powers of 1000),
/// e.g. `2GiB`, `512 MiB`, `1.5G`.
pub fn parse_bytes(s: &str) -> Result<u64> {
    let t = s.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e' || c == 'E' || c == '+'))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let bad = || {
        Error::invalid(
            "--max-memory",
            format!(
                "`{s}` is not a size; give bytes or a number with a unit, e.g. 2GiB, 512MiB, 8e9"
            ),
        )
    };
    let v: f64 = num.parse().map_err(|_| bad())?;
    let scale = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kib" => 1024.0,
        "m" | "mib" => 1024f64.powi(2),
        "g" | "gib" => 1024f64.powi(3),
        "t" | "tib" => 1024f64.powi(4),
        "kb" => 1e3,
        "mb" => 1e6,
        "gb" => 1e9,
        "tb" => 1e12,
        _ => return Err(bad()),
    };
    let b = v * scale;
    if b.is_nan() || b < 1.0 {
        return Err(Error::invalid(
            "--max-memory",
            format!("`{s}` is {} bytes; give at least 1 byte", crate::num(b)),
        ));
    }
    // u64::MAX as f64 = 2^64: the largest size a u64 holds after rounding lies just below it.
    if b >= u64::MAX as f64 {
        return Err(Error::invalid(
            "--max-memory",
            format!(
                "`{s}` is too large ({} bytes); the largest size accepted is just below 2^64 \
                 bytes = {} B (16 EiB, e.g. 1.8e19 or 16000000TiB)",
                crate::num(b),
                crate::num(u64::MAX as f64)
            ),
        ));
    }
    Ok(b.round() as u64)
}

/// A size for people: `1.50 GiB`, `312.0 MiB`, `4.2e18 B` beyond the exbibytes.
pub fn format_bytes(b: f64) -> String {
    const UNITS: [&str; 6] = ["B", "KiB", "MiB", "GiB", "TiB", "PiB"];
    if !b.is_finite() || b >= 1024f64.powi(6) {
        return format!("{b:.2e} B");
    }
    let mut v = b;
    let mut u = 0;
    while v >= 1024.0 && u < UNITS.len() - 1 {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{v:.0} B")
    } else {
        format!("{v:.2} {}", UNITS[u])
    }
}

/// Refuses `estimate_bytes` above [`max_memory`]. `what` names the quantity and how it was
/// estimated ("the history: 1e12 samples × 160 B"), `field` the input responsible and `reduce`
/// what to lower. The message names all of them, the limit and how to raise it.
pub fn check_memory(what: &str, estimate_bytes: f64, field: &str, reduce: &str) -> Result<()> {
    let limit = max_memory();
    if estimate_bytes.is_nan() || estimate_bytes > limit as f64 {
        return Err(Error::invalid(
            field,
            format!(
                "{what} would need about {} of memory, over the limit of {} (--max-memory; \
                 default half the physical memory). Reduce {reduce}, or raise --max-memory",
                format_bytes(estimate_bytes),
                format_bytes(limit as f64)
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_and_decimal_units() {
        assert_eq!(parse_bytes("1024").unwrap(), 1024);
        assert_eq!(parse_bytes("2GiB").unwrap(), 2 << 30);
        assert_eq!(parse_bytes("512 MiB").unwrap(), 512 << 20);
        assert_eq!(parse_bytes("1.5G").unwrap(), 3 << 29);
        assert_eq!(parse_bytes("3GB").unwrap(), 3_000_000_000);
        assert_eq!(parse_bytes("8e9").unwrap(), 8_000_000_000);
        for bad in ["", "x", "-1", "0", "1 parsec", "inf", "1e400"] {
            let e = parse_bytes(bad).unwrap_err().to_string();
            assert!(e.contains("--max-memory"), "{bad}: {e}");
        }
    }

    #[test]
    fn sizes_print_in_binary_units() {
        assert_eq!(format_bytes(512.0), "512 B");
        assert_eq!(format_bytes(1536.0), "1.50 KiB");
        assert_eq!(format_bytes(3.0 * 1024f64.powi(3)), "3.00 GiB");
        assert!(format_bytes(1e30).ends_with("e30 B"));
    }

    #[test]
    fn default_limit_is_half_the_physical_memory() {
        let d = default_max_memory();
        if let Ok(t) = std::fs::read_to_string("/proc/meminfo") {
            let kib: u64 = t
                .lines()
                .find_map(|l| l.strip_prefix("MemTotal:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
                .unwrap();
            assert_eq!(d, kib * 1024 / 2);
        } else {
            assert_eq!(d, FALLBACK_MAX_MEMORY_BYTES);
        }
    }

    #[test]
    fn an_estimate_over_the_limit_names_field_estimate_and_limit() {
        // Over any plausible limit: 1e30 bytes.
        let e = check_memory(
            "the history (1e27 samples × 1000 B)",
            1e30,
            "simulation.duration",
            "--duration or --rate",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("simulation.duration"), "{e}");
        assert!(e.contains("1.00e30 B"), "{e}");
        assert!(e.contains("--max-memory"), "{e}");
        assert!(e.contains("--duration or --rate"), "{e}");
        assert!(check_memory("a little", 1024.0, "x", "y").is_ok());
        assert!(check_memory("NaN", f64::NAN, "x", "y").is_err());
    }
}
