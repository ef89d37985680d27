//! Reading input files: one gate for every file a user names (model, Gmsh mesh, UFF, `.frd`,
//! CSV, Parquet, journals, shards).
//!
//! A file is opened only if it is a **regular file** (a directory, a FIFO, a socket or a
//! character or block device such as `/dev/zero` or `/dev/urandom` is refused by name, since
//! it has no end or no size to check), and its size is checked against the memory limit
//! ([`crate::limits::max_memory`]) **before** a byte is read: a file read whole is held in
//! memory at least once, so a file larger than the limit cannot be processed. Reading stops
//! at the size found when opened, plus one byte: a file that grows while it is read is refused
//! instead of followed.
//!
//! Errors quote source lines through [`clip`], so a file whose "line" is gigabytes long is
//! never printed whole.

use std::io::Read;
use std::path::Path;

use crate::{Error, Result};

/// Characters of a quoted source line kept in an error message (then `…`).
pub const CLIP_CHARS: usize = 60;

/// `s` cut to its first [`CLIP_CHARS`] characters, with `…` when something was cut.
pub fn clip(s: &str) -> String {
    let t: String = s.chars().take(CLIP_CHARS).collect();
    if t.len() < s.len() {
        format!("{t}…")
    } else {
        t
    }
}

/// What kind of special file a non-regular file is, for messages.
fn kind_of(ft: std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ft.is_char_device() {
            return "a character device";
        }
        if ft.is_block_device() {
            return "a block device";
        }
        if ft.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if ft.is_socket() {
            return "a socket";
        }
    }
    if ft.is_dir() {
        "a directory"
    } else {
        "not a regular file"
    }
}

/// Opens `path` for reading after the checks of the module docs; returns the file and its
/// size (bytes).
pub fn open(path: &Path) -> Result<(std::fs::File, u64)> {
    open_within(path, crate::limits::max_memory())
}

/// [`open`] with the size bound `limit` (bytes).
fn open_within(path: &Path, limit: u64) -> Result<(std::fs::File, u64)> {
    // The kind is checked before opening (opening a FIFO waits for a writer), and again on
    // the file opened (the path may have been replaced in between).
    let before = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    let file = if before.file_type().is_file() {
        Some(std::fs::File::open(path).map_err(|e| Error::io(path, e))?)
    } else {
        None
    };
    let meta = match &file {
        Some(f) => f.metadata().map_err(|e| Error::io(path, e))?,
        None => before,
    };
    let file = match file {
        Some(f) if meta.file_type().is_file() => f,
        _ => {
            // An I/O error (Python: an OSError; a directory: IsADirectoryError's kind), with
            // the message saying what to give instead.
            let kind = if meta.file_type().is_dir() {
                std::io::ErrorKind::IsADirectory
            } else {
                std::io::ErrorKind::InvalidInput
            };
            let message = format!(
                "is {}, not a regular file; give a file (a device or pipe has no size to check and may never end)",
                kind_of(meta.file_type())
            );
            return Err(Error::io(path, std::io::Error::new(kind, message)));
        }
    };
    let len = meta.len();
    if len > limit {
        return Err(Error::Input {
            location: path.display().to_string(),
            message: format!(
                "the file is {} ({len} bytes), over the memory limit of {} (--max-memory; default half the physical memory); is it the right file? Raise --max-memory to read it",
                crate::limits::format_bytes(len as f64),
                crate::limits::format_bytes(limit as f64)
            ),
        });
    }
    Ok((file, len))
}

/// The bytes of `path`, read whole after the checks of [`open`].
pub fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    let (file, len) = open(path)?;
    let mut data = Vec::with_capacity(usize::try_from(len).unwrap_or(0));
    file.take(len.saturating_add(1))
        .read_to_end(&mut data)
        .map_err(|e| Error::io(path, e))?;
    if data.len() as u64 > len {
        return Err(Error::Input {
            location: path.display().to_string(),
            message: format!(
                "the file grew while it was read (it had {len} bytes when opened); read a file no program is writing"
            ),
        });
    }
    Ok(data)
}

/// The text of `path` (UTF-8), read whole after the checks of [`open`].
pub fn read_text(path: &Path) -> Result<String> {
    let data = read_bytes(path)?;
    String::from_utf8(data).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        let line = 1 + bytes[..at].iter().filter(|b| **b == b'\n').count();
        Error::Input {
            location: format!("{}:{line}", path.display()),
            message: format!(
                "not UTF-8 text (an invalid byte at offset {at}); give a text file in UTF-8"
            ),
        }
    })
}

/// FNV-1a 64 of a file's content, streamed, as 16 hex digits, with the file's size (bytes):
/// the content fingerprint of a file a model refers to.
pub fn digest(path: &Path) -> Result<(u64, String)> {
    let (file, _) = open(path)?;
    let mut r = std::io::BufReader::with_capacity(1 << 16, file);
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut n: u64 = 0;
    let mut buf = [0u8; 1 << 16];
    loop {
        let k = r.read(&mut buf).map_err(|e| Error::io(path, e))?;
        if k == 0 {
            break;
        }
        for b in &buf[..k] {
            h ^= u64::from(*b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        n += k as u64;
    }
    Ok((n, format!("{h:016x}")))
}

/// FNV-1a 64 of `bytes` as 16 hex digits.
pub fn fnv1a_hex(bytes: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// A row of a journal or shard file with its checksum appended as a last field:
/// `ROW,H` where `H` is [`fnv1a_hex`] of `ROW` (`row` without its newline). A row edited,
/// cut short or interleaved with another no longer matches its checksum ([`unseal_row`]).
pub fn seal_row(row: &str) -> String {
    format!("{row},{}", fnv1a_hex(row.as_bytes()))
}

/// The row of a [`seal_row`] line (without its newline), or `None` when the line has no
/// checksum or the checksum does not match the row.
pub fn unseal_row(line: &str) -> Option<&str> {
    let (row, h) = line.rsplit_once(',')?;
    (h.len() == 16 && fnv1a_hex(row.as_bytes()) == h).then_some(row)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn special_files_are_refused_by_kind() {
        #[cfg(unix)]
        for (p, kind) in [
            ("/dev/zero", "character device"),
            ("/dev/urandom", "character device"),
        ] {
            let e = read_text(Path::new(p)).unwrap_err().to_string();
            assert!(
                e.contains(p) && e.contains(kind) && e.contains("regular file"),
                "{e}"
            );
        }
        let d = std::env::temp_dir();
        let e = read_bytes(&d).unwrap_err().to_string();
        assert!(e.contains("a directory"), "{e}");
    }

    #[test]
    fn a_file_over_the_memory_limit_is_refused_before_reading() {
        let p = std::env::temp_dir().join(format!("meid-input-{}.txt", std::process::id()));
        std::fs::write(&p, vec![b'x'; 4096]).unwrap();
        let e = open_within(&p, 1000).map(|_| ()).unwrap_err().to_string();
        assert!(open_within(&p, 4096).is_ok());
        std::fs::remove_file(&p).ok();
        assert!(
            e.contains("4096 bytes") && e.contains("--max-memory"),
            "{e}"
        );
    }

    #[test]
    fn clip_keeps_sixty_characters() {
        assert_eq!(clip("abc"), "abc");
        let long = "é".repeat(100);
        let c = clip(&long);
        assert_eq!(c.chars().count(), CLIP_CHARS + 1);
        assert!(c.ends_with('…'));
    }

    #[test]
    fn sealed_rows_detect_an_edit_a_cut_and_a_missing_checksum() {
        let row = "3,1e0,2.5e-1,\"a, quoted error\"";
        let sealed = seal_row(row);
        assert_eq!(unseal_row(&sealed), Some(row));
        assert_eq!(unseal_row(&sealed.replace("2.5e-1", "NaN")), None);
        assert_eq!(unseal_row(&sealed[..sealed.len() - 1]), None);
        assert_eq!(unseal_row(row), None);
        assert_eq!(unseal_row(""), None);
    }

    #[test]
    fn digest_is_fnv1a_of_the_content() {
        let p = std::env::temp_dir().join(format!("meid-digest-{}.txt", std::process::id()));
        std::fs::write(&p, b"foobar").unwrap();
        let d = digest(&p).unwrap();
        std::fs::remove_file(&p).ok();
        // FNV-1a 64 of "foobar" (the published test vector).
        assert_eq!(d, (6, "85944171f73967e8".to_string()));
    }
}
