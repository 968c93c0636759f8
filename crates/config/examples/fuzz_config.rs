//! A fuzzer for robot, motion and calibration YAML on the stable toolchain:
//! it mutates the shipped files and the kept inputs, loads every candidate
//! through the real loaders (`common/config_check.rs`, shared with the
//! cargo-fuzz target `config_yaml`), and keeps the candidates whose outcome
//! no kept input had (which load refused it, at which field, why).
//!
//! ```sh
//! cargo run --release -p servobus-config --example fuzz_config -- \
//!     --iterations 1000000 --seed 1
//! ```
//!
//! Every input must load or be refused within [`SLOW`]; one that panics,
//! fails a check or takes longer (twice in a row, so that a busy machine
//! does not count) is saved as `testdata/fuzz-config/crash-<hash>` and the
//! run exits 1. With `--out DIR` the inputs it keeps are written there.
//! `cargo test -p servobus-config --test config config_errors` replays
//! `testdata/fuzz-config/`.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

#[path = "common/config_check.rs"]
mod config_check;

use config_check::{Workspace, MAX_LEN};

/// The longest one input may take.
const SLOW: Duration = Duration::from_secs(1);

/// Text a mutation may insert: YAML's structure, and values at and past
/// the limits.
const TOKENS: [&str; 40] = [
    "[",
    "]",
    "{",
    "}",
    "- ",
    ": ",
    ", ",
    "\n",
    "\n  ",
    "  ",
    "\t",
    "#",
    "\"",
    "'",
    "&a ",
    "*a",
    "<<: *a\n",
    "!!str ",
    "|\n",
    ">-\n",
    "~",
    "null",
    "true",
    "-1",
    "0",
    "1e308",
    "-1e308",
    ".inf",
    ".nan",
    "1e12",
    "4294967296",
    "18446744073709551616",
    "0.001",
    "1e-300",
    "repeat: 1000000000\n",
    "at: 1e12\n",
    "rate: 0.001\n",
    "baud: 12345\n",
    "latency_us: 999999999\n",
    "calibration: nope.yaml\n",
];

/// Numbers a mutation may put in place of one in the text.
const NUMBERS: [&str; 14] = [
    "0",
    "-0",
    "1",
    "-1",
    "255",
    "256",
    "4095",
    "1e9",
    "1e308",
    "-1e-308",
    ".inf",
    ".nan",
    "99999999999999999999",
    "0.000001",
];

fn main() -> ExitCode {
    let mut iterations = 200_000u64;
    let mut seed = 1u64;
    let mut out: Option<PathBuf> = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match (a.as_str(), args.next()) {
            ("--iterations", Some(v)) => iterations = v.parse().unwrap_or(iterations),
            ("--seed", Some(v)) => seed = v.parse().unwrap_or(seed),
            ("--out", Some(v)) => out = Some(PathBuf::from(v)),
            _ => {
                eprintln!("usage: fuzz_config [--iterations N] [--seed N] [--out DIR]");
                return ExitCode::from(2);
            }
        }
    }
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let crashes = repo.join("testdata/fuzz-config");
    let workspace = match Workspace::new(&repo) {
        Ok(w) => w,
        Err(e) => {
            eprintln!("cannot set up the scratch directory: {e}");
            return ExitCode::from(2);
        }
    };
    let mut corpus = seeds(&repo);
    if let Some(dir) = &out {
        if let Err(e) = std::fs::create_dir_all(dir) {
            eprintln!("cannot create {}: {e}", dir.display());
            return ExitCode::from(2);
        }
        corpus.extend(files(dir, |_| true));
    }
    let mut seen = BTreeSet::new();
    for input in &corpus {
        match run(&workspace, input) {
            Ok((features, _)) => seen.extend(features),
            Err(why) => return crash(&crashes, input, &why),
        }
    }
    let (start_inputs, start_features) = (corpus.len(), seen.len());
    let mut rng = Rng(seed.max(1));
    let started = Instant::now();
    let mut slowest = Duration::ZERO;
    for _ in 0..iterations {
        let base = &corpus[rng.below(corpus.len())];
        let other = &corpus[rng.below(corpus.len())];
        let candidate = mutate(base, other, &mut rng);
        let (features, took) = match run(&workspace, &candidate) {
            Ok(r) => r,
            Err(why) => return crash(&crashes, &candidate, &why),
        };
        slowest = slowest.max(took);
        let new: Vec<String> = features.into_iter().filter(|f| !seen.contains(f)).collect();
        if !new.is_empty() {
            seen.extend(new);
            if let Some(dir) = &out {
                let path = dir.join(format!("{:016x}.yaml", hash(&candidate)));
                if let Err(e) = std::fs::write(&path, &candidate) {
                    eprintln!("cannot write {}: {e}", path.display());
                    return ExitCode::from(2);
                }
            }
            corpus.push(candidate);
        }
    }
    let secs = started.elapsed().as_secs_f64();
    println!(
        "{iterations} inputs in {secs:.1} s ({:.0}/s), slowest {:.1} ms; outcomes {start_features} \
         -> {}; corpus {start_inputs} -> {}",
        iterations as f64 / secs.max(1e-9),
        slowest.as_secs_f64() * 1e3,
        seen.len(),
        corpus.len()
    );
    ExitCode::SUCCESS
}

/// Checks `input`; its features and how long it took, or why it failed.
fn run(workspace: &Workspace, input: &[u8]) -> Result<(Vec<String>, Duration), String> {
    let once = || {
        let t = Instant::now();
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| workspace.check(input)))
            .map(|f| (f, t.elapsed()))
            .map_err(|_| "a check failed (see the panic above)".to_owned())
    };
    let (features, took) = once()?;
    if took <= SLOW {
        return Ok((features, took));
    }
    // Once more: a busy machine can stall one run, not two.
    let (features, again) = once()?;
    if again <= SLOW {
        return Ok((features, took.min(again)));
    }
    Err(format!(
        "took {:.2} s and {:.2} s, over the limit of {} s",
        took.as_secs_f64(),
        again.as_secs_f64(),
        SLOW.as_secs()
    ))
}

/// Saves `input` as `dir/crash-<hash>` and says why; exit 1.
fn crash(dir: &Path, input: &[u8], why: &str) -> ExitCode {
    let path = dir.join(format!("crash-{:016x}", hash(input)));
    let saved = std::fs::create_dir_all(dir).and_then(|()| std::fs::write(&path, input));
    match saved {
        Ok(()) => eprintln!("{why}; input saved as {}", path.display()),
        Err(e) => eprintln!("{why}; cannot save the input as {}: {e}", path.display()),
    }
    ExitCode::FAILURE
}

/// The shipped robots, motions and simulator files, the bad-input corpus,
/// and the kept inputs of `testdata/fuzz-config/`.
fn seeds(repo: &Path) -> Vec<Vec<u8>> {
    let yaml = |p: &Path| p.extension().is_some_and(|e| e == "yaml");
    let mut all = Vec::new();
    for dir in [
        "configs/robots",
        "configs/motions",
        "configs/sim",
        "tests/bad_inputs",
    ] {
        all.extend(files(&repo.join(dir), yaml));
    }
    all.extend(files(&repo.join("testdata/fuzz-config"), |p| {
        p.extension() != Some("md".as_ref())
    }));
    all.retain(|input| input.len() <= MAX_LEN);
    if all.is_empty() {
        all.push(b"name: x\n".to_vec());
    }
    all
}

/// The files directly in `dir` that `keep` accepts, in name order.
fn files(dir: &Path, keep: impl Fn(&Path) -> bool) -> Vec<Vec<u8>> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut paths: Vec<PathBuf> = entries
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.is_file() && keep(p))
        .collect();
    paths.sort();
    paths.iter().filter_map(|p| std::fs::read(p).ok()).collect()
}

/// One to four mutations of `base`, some taking text from `other`.
fn mutate(base: &[u8], other: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut v = base.to_vec();
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(v.len() + 1);
        match rng.below(10) {
            0 if at < v.len() => v[at] ^= 1 << rng.below(8),
            1 if at < v.len() => {
                let end = (at + 1 + rng.below(16)).min(v.len());
                v.drain(at..end);
            }
            2 => {
                let token = TOKENS[rng.below(TOKENS.len())].as_bytes();
                v.splice(at..at, token.iter().copied());
            }
            3 => replace_number(&mut v, rng),
            4 => {
                // A line of `other` inserted at a line start of `v`.
                let line = line_at(other, rng.below(other.len() + 1));
                let start = line_start(&v, at);
                v.splice(start..start, line.iter().copied());
            }
            5 => {
                // A line of `v` repeated, or removed.
                let line = line_at(&v, at).to_vec();
                let start = line_start(&v, at);
                if rng.below(2) == 0 {
                    v.splice(start..start, line);
                } else {
                    v.drain(start..(start + line.len()).min(v.len()));
                }
            }
            6 => {
                // Indentation changed at a line start.
                let start = line_start(&v, at);
                if rng.below(2) == 0 {
                    v.splice(start..start, *b"  ");
                } else if v[start..].starts_with(b"  ") {
                    v.drain(start..start + 2);
                }
            }
            7 => {
                let from = rng.below(other.len() + 1);
                let end = (from + rng.below(64)).min(other.len());
                v.splice(at..at, other[from..end].iter().copied());
            }
            8 => v.insert(at, rng.byte()),
            _ => v.insert(at, b" -:[]{},#\n"[rng.below(10)]),
        }
    }
    v.truncate(MAX_LEN);
    v
}

/// Replaces one number of `v` (a run of digits, dots and signs) with one
/// of [`NUMBERS`].
fn replace_number(v: &mut Vec<u8>, rng: &mut Rng) {
    let digits: Vec<usize> = (0..v.len()).filter(|&i| v[i].is_ascii_digit()).collect();
    if digits.is_empty() {
        return;
    }
    let mut start = digits[rng.below(digits.len())];
    while start > 0 && matches!(v[start - 1], b'0'..=b'9' | b'.' | b'-') {
        start -= 1;
    }
    let mut end = start;
    while end < v.len() && matches!(v[end], b'0'..=b'9' | b'.' | b'-' | b'e') {
        end += 1;
    }
    let number = NUMBERS[rng.below(NUMBERS.len())].as_bytes();
    v.splice(start..end, number.iter().copied());
}

/// The start of the line holding byte `at`.
fn line_start(v: &[u8], at: usize) -> usize {
    let at = at.min(v.len());
    v[..at]
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1)
}

/// The line holding byte `at`, with its newline.
fn line_at(v: &[u8], at: usize) -> &[u8] {
    let start = line_start(v, at);
    let end = v[start..]
        .iter()
        .position(|&b| b == b'\n')
        .map_or(v.len(), |i| start + i + 1);
    &v[start..end]
}

/// FNV-1a: a stable file name for an input.
fn hash(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// A xorshift generator: the same inputs for the same seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }

    /// A number in `0..n` (0 when `n` is 0).
    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }

    fn byte(&mut self) -> u8 {
        (self.next() >> 24) as u8
    }
}
