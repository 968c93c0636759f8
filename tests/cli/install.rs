//! `cargo install --path .` gives a `servobus` that works from any
//! directory: the shipped robots and motions are built in, and the starter
//! files of `servobus init` play.
//!
//! The install shares the workspace's target directory (`--target-dir`) and
//! stays offline. By default it installs the dev profile (`--debug`), which
//! reuses what `cargo test` has just compiled: seconds instead of the minutes
//! of a release build of every dependency on a fresh clone. With
//! `SERVOBUS_INSTALL_RELEASE=1` it installs the release profile, as a user
//! would, and checks that the binary carries no debug info (its size).

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Instant;

/// The workspace's target directory: this test runs from `target/<profile>/deps/`.
fn target_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("test executable");
    exe.ancestors()
        .nth(3)
        .expect("target/<profile>/deps/<test>")
        .to_owned()
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("servobus-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// The installed `servobus ARGS`, run in `dir`, which must succeed.
fn run(bin: &Path, dir: &Path, args: &[&str]) -> Output {
    let out = Command::new(bin).args(args).current_dir(dir).output();
    common::succeeded(out.expect("the installed servobus runs"), args)
}

#[test]
fn installed_binary_works_from_an_empty_directory() {
    let release = std::env::var_os("SERVOBUS_INSTALL_RELEASE").is_some_and(|v| v == "1");
    let root = scratch("install-root");
    let started = Instant::now();
    let install = Command::new(env!("CARGO"))
        .args([
            "install",
            "--path",
            env!("CARGO_MANIFEST_DIR"),
            "--offline",
            "--locked",
        ])
        .args(if release { &[][..] } else { &["--debug"][..] })
        .arg("--root")
        .arg(&root)
        .arg("--target-dir")
        .arg(target_dir())
        .output()
        .expect("cargo install runs");
    assert!(
        install.status.success(),
        "cargo install: {}",
        String::from_utf8_lossy(&install.stderr)
    );
    // After `cargo test --workspace` nothing is compiled: the install has
    // the test build's feature set (see `serde` in the workspace Cargo.toml).
    let compiled = String::from_utf8_lossy(&install.stderr)
        .lines()
        .filter(|l| l.trim_start().starts_with("Compiling "))
        .count();
    eprintln!(
        "cargo install took {:.1} s and compiled {compiled} crates",
        started.elapsed().as_secs_f64()
    );
    let bin = root.join("bin").join("servobus");
    let size = std::fs::metadata(&bin).expect("installed binary").len();
    eprintln!("installed binary: {size} bytes");
    if release {
        assert!(
            size < 15_000_000,
            "installed binary is {size} bytes: debug info left in?"
        );
    }

    let empty = scratch("install-empty");
    let play = common::json(&run(
        &bin,
        &empty,
        &["play", "arm-wave", "--fast", "--json"],
    ));
    assert_eq!(play["finish"], "completed", "{play}");
    assert_eq!(play["joints"][0]["name"], "shoulder_pan", "{play}");
    assert!(play["cycles"].as_u64().unwrap_or(0) > 1000, "{play}");

    let budget = common::json(&run(
        &bin,
        &empty,
        &["budget", "--robot", "hexapod", "--json"],
    ));
    assert_eq!(budget["buses"][0]["servos"], 18, "{budget}");

    run(&bin, &empty, &["init"]);
    assert!(empty.join("robot.yaml").is_file() && empty.join("motion.yaml").is_file());
    let mine = common::json(&run(
        &bin,
        &empty,
        &["play", "motion.yaml", "--fast", "--json"],
    ));
    assert_eq!(mine["finish"], "completed", "{mine}");
    assert!(mine["fault"].is_null(), "{mine}");
    // The starter motion moves the joints of the robot file init wrote.
    let moved = mine["joints"].as_array().expect("joints");
    assert_eq!(moved.len(), 6, "{mine}");
    let entries = std::fs::read_dir(&empty).expect("dir").count();
    assert_eq!(entries, 2, "only init's two files were written");

    // The README's simulator with a body, by names only, from an empty
    // directory: it serves, and writes its truth file.
    let sim_dir = scratch("install-sim");
    let link = sim_dir.join("arm");
    let truth = sim_dir.join("truth.csv");
    let mut sim = common::Running::start_bin(
        &bin,
        Some(&sim_dir),
        &[
            "sim",
            "--robot",
            "so101",
            "--link",
            common::arg(&link),
            "--mounting",
            "so101-mounting",
            "--hand",
            "so101-hand",
            "--truth",
            common::arg(&truth),
        ],
    );
    sim.wait_for(false, "serving", |l| l.starts_with("serving 6 servos on"));
    // One servo answers (a full scan on a loaded machine may see a late
    // reply as a clash; the bus tools' own tests cover scanning).
    let ping = run(
        &bin,
        &sim_dir,
        &["ping", "--port", common::arg(&link), "--id", "1"],
    );
    assert!(
        String::from_utf8_lossy(&ping.stdout).contains("servo 1 answered"),
        "ping: {}",
        String::from_utf8_lossy(&ping.stdout)
    );
    sim.interrupt();
    let (status, _, err) = sim.finish();
    assert!(status.success(), "sim: {err}");
    assert!(truth.is_file(), "the truth file");
    assert!(!link.exists(), "the link is removed");

    let _ = std::fs::remove_dir_all(&root);
    let _ = std::fs::remove_dir_all(&empty);
    let _ = std::fs::remove_dir_all(&sim_dir);
}

#[test]
fn python_tests_sh_says_what_it_creates_and_runs_before_it_starts() {
    // A fresh SERVOBUS_VENVS and a Python that does not exist: the script
    // stops at its first step, after saying what it would have done.
    let venvs = common::scratch("python-tests-plan");
    let out = Command::new("bash")
        .arg(common::repo("scripts/python_tests.sh"))
        .env("SERVOBUS_VENVS", &venvs)
        .env("SERVOBUS_PYTHON", "/nonexistent/python3")
        .env_remove("SERVOBUS_LEROBOT_PYTHON")
        .output()
        .expect("bash runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    let venv = venvs.join("python-servobus");
    let first = err.lines().next().unwrap_or_default();
    assert_eq!(
        first,
        format!(
            "python_tests.sh: creates the virtualenv {} (SERVOBUS_VENVS sets where; kept for later runs)",
            venv.display()
        ),
        "{err}"
    );
    for said in [
        "installs maturin==1.16.0 pytest==8.3.4 numpy==2.2.6 into it with pip",
        "pip install ./python into that virtualenv",
        "pytest python/tests",
        "the LeRobot check is left out: SERVOBUS_LEROBOT_PYTHON is not set",
        "FAIL the Python package needs Python >= 3.10",
    ] {
        assert!(err.contains(said), "missing {said:?} in:\n{err}");
    }
    assert!(!venv.exists(), "nothing created before the Python check");
    let _ = std::fs::remove_dir_all(&venvs);
}
