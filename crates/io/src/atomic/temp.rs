//! The temporaries of [`AtomicFile`](super::AtomicFile): their names, and
//! the removal of those a killed run left behind.
//!
//! | target name                | temporary                                    |
//! |----------------------------|----------------------------------------------|
//! | `log.csv`                  | `.log.csv.<pid>.tmp` (`.<pid>.<n>.tmp` when taken) |
//! | a name of 229+ bytes       | `.<first bytes>~<hash>.<pid>.tmp`, 255 bytes at most |
//!
//! A file system takes names of at most 255 bytes (`NAME_MAX`), so a
//! legal target name of 250 bytes would make an illegal temporary: a long
//! name is cut to a prefix and the 64-bit FNV-1a hash of the whole name
//! (stable from one build to the next, so that a later run recognises the
//! temporaries of an earlier one), which keeps temporaries of different
//! targets apart.
//!
//! A run killed outright (SIGKILL, power loss) leaves its temporary behind.
//! The next run that writes the same target removes every temporary of it
//! whose process no longer runs (Linux, where `/proc` tells; elsewhere they
//! are kept). A temporary of a process that still runs is never touched.

use std::fs;
use std::path::Path;

/// The longest file name, bytes (Linux, macOS and the BSDs: `NAME_MAX`).
pub(crate) const NAME_MAX: usize = 255;

/// The longest suffix a temporary adds after its base: `.` + a 10-digit
/// pid + `.` + a 10-digit serial + `.tmp`.
const SUFFIX_MAX: usize = 1 + 10 + 1 + 10 + 4;

/// Bytes of the hash that stands for a cut name: `~` and 16 hex digits.
const HASH_LEN: usize = 17;

/// The most directory entries looked at for stale temporaries: a
/// directory of a million files is not scanned to the end on every write.
const SCAN_MAX: usize = 100_000;

/// The base of the temporaries of a target named `name`: `.<name>`, or,
/// when `.<name>` with the longest suffix would pass [`NAME_MAX`],
/// `.<prefix>~<hash>` with the prefix cut at a character boundary.
pub(crate) fn base(name: &str) -> String {
    let whole = format!(".{name}");
    if whole.len() + SUFFIX_MAX <= NAME_MAX {
        return whole;
    }
    let room = NAME_MAX - SUFFIX_MAX - HASH_LEN;
    let mut cut = room.min(whole.len());
    while !whole.is_char_boundary(cut) {
        cut -= 1;
    }
    format!("{}~{:016x}", &whole[..cut], fnv1a(name.as_bytes()))
}

/// The 64-bit FNV-1a hash of `bytes`.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The process id of a temporary named `file` of base `base`: the `<pid>`
/// of `<base>.<pid>.tmp` or `<base>.<pid>.<n>.tmp`; `None` for any other
/// name.
pub(crate) fn owner(file: &str, base: &str) -> Option<u32> {
    let rest = file.strip_prefix(base)?.strip_prefix('.')?;
    let rest = rest.strip_suffix(".tmp")?;
    let (pid, serial) = match rest.split_once('.') {
        Some((pid, n)) => (pid, Some(n)),
        None => (rest, None),
    };
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if !digits(pid) || serial.is_some_and(|n| !digits(n)) {
        return None;
    }
    pid.parse().ok()
}

/// Whether process `pid` runs, when that can be told (`None` elsewhere
/// than on a system with `/proc`).
fn running(pid: u32) -> Option<bool> {
    let proc = Path::new("/proc");
    if !proc.join("self").exists() {
        return None;
    }
    Some(proc.join(pid.to_string()).exists())
}

/// Removes from `dir` the temporaries of base `base` whose process no
/// longer runs (never this process's), best effort: a temporary that
/// cannot be removed is left. Returns how many were removed.
pub(crate) fn remove_stale(dir: &Path, base: &str) -> usize {
    let Ok(entries) = fs::read_dir(dir) else {
        return 0;
    };
    let me = std::process::id();
    let mut removed = 0;
    for entry in entries.take(SCAN_MAX).flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(|n| owner(n, base)) else {
            continue;
        };
        if pid == me || running(pid) != Some(false) {
            continue;
        }
        // Only a regular file: a directory or a link of that name is not
        // one of ours.
        let is_file = entry.file_type().is_ok_and(|t| t.is_file());
        if is_file && fs::remove_file(entry.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}
