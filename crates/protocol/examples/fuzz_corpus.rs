//! A small fuzzer for the streaming decoder on the stable toolchain: it
//! mutates the kept inputs, runs every candidate through the fuzz target's
//! checks (`tests/common/fuzz_check.rs`), and keeps the candidates that
//! make the decoder do something no kept input made it do.
//!
//! "Something new" is a feature of the decoder's output on the candidate:
//! an event kind (packet, echo, checksum error, discard and its reason)
//! with its length rounded to a power of two, or a pair of kinds in a row.
//! cargo-fuzz (nightly) measures code coverage instead; this needs nothing
//! but the decoder's public API and is deterministic for a given seed.
//!
//! ```sh
//! cargo run --release -p servobus-protocol --example fuzz_corpus -- \
//!     --iterations 300000 --seed 1 --out testdata/fuzz/corpus
//! ```
//!
//! It reads the hand-made seeds in `testdata/fuzz/`, the kept corpus in
//! `testdata/fuzz/corpus/` and everything already in `--out` (by default
//! that corpus), writes each kept input to `--out` under a hash of its bytes,
//! and exits 1 (saving the input as `testdata/fuzz/crash-<hash>`) when a
//! check fails. `cargo test -p servobus-protocol --test protocol fuzz_regressions`
//! replays the seeds and the whole kept corpus.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use servobus_protocol::{Decoder, Event};

#[path = "../tests/common/fuzz_check.rs"]
mod fuzz_check;

/// Inputs longer than this are not kept (the fuzz target's `-max_len`).
const MAX_LEN: usize = 600;

fn main() -> ExitCode {
    let mut iterations = 300_000u64;
    let mut seed = 1u64;
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/fuzz");
    let mut out = root.join("corpus");
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let value = args.next();
        match (a.as_str(), value) {
            ("--iterations", Some(v)) => iterations = v.parse().unwrap_or(iterations),
            ("--seed", Some(v)) => seed = v.parse().unwrap_or(seed),
            ("--out", Some(v)) => out = PathBuf::from(v),
            _ => {
                eprintln!("usage: fuzz_corpus [--iterations N] [--seed N] [--out DIR]");
                return ExitCode::from(2);
            }
        }
    }
    if let Err(e) = std::fs::create_dir_all(&out) {
        eprintln!("cannot create {}: {e}", out.display());
        return ExitCode::from(2);
    }
    let kept_dir = root.join("corpus");
    let mut corpus: Vec<Vec<u8>> = inputs(&root);
    corpus.extend(inputs(&kept_dir));
    if out.canonicalize().ok() != kept_dir.canonicalize().ok() {
        corpus.extend(inputs(&out));
    }
    if corpus.is_empty() {
        corpus.push(vec![0, 0]);
    }
    let mut seen = BTreeSet::new();
    for input in &corpus {
        seen.extend(features(input));
    }
    let (start_inputs, start_features) = (corpus.len(), seen.len());
    let mut rng = Rng(seed.max(1));
    let mut kept = 0;
    for _ in 0..iterations {
        let base = &corpus[rng.below(corpus.len())];
        let other = &corpus[rng.below(corpus.len())];
        let candidate = mutate(base, other, &mut rng);
        if std::panic::catch_unwind(|| fuzz_check::check_input(&candidate)).is_err() {
            let path = root.join(format!("crash-{:016x}", hash(&candidate)));
            let _ = std::fs::write(&path, &candidate);
            eprintln!("a check failed; input saved as {}", path.display());
            return ExitCode::FAILURE;
        }
        let new: Vec<String> = features(&candidate)
            .into_iter()
            .filter(|f| !seen.contains(f))
            .collect();
        if !new.is_empty() && candidate.len() <= MAX_LEN {
            seen.extend(new);
            let path = out.join(format!("{:016x}", hash(&candidate)));
            if let Err(e) = std::fs::write(&path, &candidate) {
                eprintln!("cannot write {}: {e}", path.display());
                return ExitCode::from(2);
            }
            corpus.push(candidate);
            kept += 1;
        }
    }
    println!(
        "{iterations} inputs checked; features {start_features} -> {}; corpus {start_inputs} -> {} \
         ({kept} kept in {})",
        seen.len(),
        corpus.len(),
        out.display()
    );
    ExitCode::SUCCESS
}

/// The files directly in `dir` (not `*.md`), in name order.
fn inputs(dir: &Path) -> Vec<Vec<u8>> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut paths: Vec<PathBuf> = entries
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.is_file() && p.extension() != Some("md".as_ref()))
        .collect();
    paths.sort();
    paths.iter().filter_map(|p| std::fs::read(p).ok()).collect()
}

/// What the decoder does with an input's stream, whole and without echo:
/// each event's kind and length class, and each pair of kinds in a row.
fn features(input: &[u8]) -> Vec<String> {
    let stream = input.get(2..).unwrap_or_default();
    let mut dec = Decoder::new();
    let mut kinds = Vec::new();
    let mut rest = stream;
    let push = |ev: Event<'_>, kinds: &mut Vec<(String, u32)>| {
        let (kind, len) = match ev {
            Event::Packet { packet, .. } => {
                // The instruction (or status) byte distinguishes kinds of frame.
                let b = packet.bytes();
                (
                    format!("packet{:02x}", b.get(4).copied().unwrap_or(0) & 0xF0),
                    b.len(),
                )
            }
            Event::Echo { len, .. } => ("echo".into(), len),
            Event::Discarded { len, reason, .. } => (format!("{reason:?}"), len),
            Event::ChecksumError { .. } => ("checksum".into(), 0),
        };
        kinds.push((kind, usize::BITS - len.leading_zeros()));
    };
    while let Some(ev) = dec.decode(&mut rest) {
        push(ev, &mut kinds);
    }
    while let Some(ev) = dec.finish() {
        push(ev, &mut kinds);
    }
    let mut out: Vec<String> = kinds.iter().map(|(k, l)| format!("{k}/{l}")).collect();
    out.extend(kinds.windows(2).map(|w| format!("{}>{}", w[0].0, w[1].0)));
    out
}

/// One mutation of `base`, sometimes spliced with `other`.
fn mutate(base: &[u8], other: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut v = base.to_vec();
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(v.len() + 1);
        match rng.below(8) {
            0 if !v.is_empty() => {
                let i = at.min(v.len() - 1);
                v[i] ^= 1 << rng.below(8);
            }
            1 if !v.is_empty() => {
                let i = at.min(v.len() - 1);
                v[i] = rng.byte();
            }
            2 => v.insert(at, rng.byte()),
            3 if at < v.len() => {
                let end = (at + 1 + rng.below(8)).min(v.len());
                v.drain(at..end);
            }
            4 => {
                let from = rng.below(other.len() + 1);
                let end = (from + rng.below(32)).min(other.len());
                v.splice(at..at, other[from..end].iter().copied());
            }
            5 => {
                let frame = frame(rng);
                v.splice(at..at, frame);
            }
            6 => v.splice(at..at, [0xFF, 0xFF]).for_each(drop),
            _ if v.len() >= 2 => v[rng.below(2)] = rng.byte(),
            _ => v.push(rng.byte()),
        }
    }
    v.truncate(MAX_LEN + 64);
    v
}

/// A well-formed frame: FF FF, ID, length, instruction, parameters and the
/// complement of the byte sum from the ID on.
fn frame(rng: &mut Rng) -> Vec<u8> {
    let params = rng.below(8);
    let mut f = vec![
        0xFF,
        0xFF,
        rng.byte() % 0xFE,
        (params + 2) as u8,
        rng.byte(),
    ];
    f.extend((0..params).map(|_| rng.byte()));
    let sum = f[2..].iter().fold(0u8, |s, &b| s.wrapping_add(b));
    f.push(!sum);
    f
}

/// FNV-1a: a stable file name for an input.
fn hash(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// xorshift64: deterministic for a seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }
    fn byte(&mut self) -> u8 {
        self.next() as u8
    }
}
