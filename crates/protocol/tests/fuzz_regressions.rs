//! Replays every input under `testdata/fuzz/` (hand-made seeds and inputs
//! the fuzzer once found failing) with the fuzz target's checks.

mod common;

#[test]
fn fuzz_inputs_hold_every_invariant() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../testdata/fuzz");
    let mut replayed = 0;
    for entry in std::fs::read_dir(dir).expect("testdata/fuzz exists") {
        let path = entry.expect("readable entry").path();
        if path.extension().is_some_and(|e| e == "md") {
            continue;
        }
        let data = std::fs::read(&path).expect("readable input");
        let run = std::panic::catch_unwind(|| common::fuzz_check::check_input(&data));
        assert!(run.is_ok(), "{} fails", path.display());
        replayed += 1;
    }
    assert!(replayed >= 5, "only {replayed} inputs found");
}
