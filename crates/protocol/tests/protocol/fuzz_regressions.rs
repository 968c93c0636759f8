//! Replays every input under `testdata/fuzz/` (hand-made seeds and inputs
//! the fuzzer once found failing) and the whole kept corpus in
//! `testdata/fuzz/corpus/` (grown by `examples/fuzz_corpus.rs`) with the
//! fuzz target's checks.

use crate::common;

use std::path::{Path, PathBuf};

/// The input files directly in `dir` (not `*.md`).
fn inputs(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("readable entry").path())
        .filter(|p| p.is_file() && p.extension() != Some("md".as_ref()))
        .collect()
}

fn replay(paths: &[PathBuf]) {
    for path in paths {
        let data = std::fs::read(path).expect("readable input");
        let run = std::panic::catch_unwind(|| common::fuzz_check::check_input(&data));
        assert!(run.is_ok(), "{} fails", path.display());
    }
}

#[test]
fn fuzz_inputs_hold_every_invariant() {
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../testdata/fuzz"));
    let seeds = inputs(dir);
    assert!(seeds.len() >= 5, "only {} inputs found", seeds.len());
    replay(&seeds);
}

#[test]
fn the_kept_corpus_holds_every_invariant() {
    let dir = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../testdata/fuzz/corpus"
    ));
    let corpus = inputs(dir);
    // The corpus as grown when it was committed (see testdata/fuzz/README.md).
    assert!(corpus.len() >= 100, "only {} corpus inputs", corpus.len());
    replay(&corpus);
}
