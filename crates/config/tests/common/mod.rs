//! Shared helpers of the configuration's tests: the shipped files and
//! scratch files.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// A file under the workspace's `configs/`.
pub fn config(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../configs")
        .join(rel)
}

/// The path of file `name` in `dir`, a folder of its own under Cargo's
/// temporary directory for tests (made if missing).
pub fn temp_path(dir: &str, name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(dir);
    std::fs::create_dir_all(&d).expect("temp dir");
    d.join(name)
}

/// Writes `text` to [`temp_path`]`(dir, name)` and returns the path.
pub fn temp_file(dir: &str, name: &str, text: &str) -> PathBuf {
    let p = temp_path(dir, name);
    std::fs::write(&p, text).expect("temp file");
    p
}
