//! The front ends (the command line, the Python bindings, the Zenoh node)
//! drive the robot through the facade alone: their manifests name no
//! servobus crate below it but the pure-data ones it re-exports anyway,
//! and their sources import none.

use std::path::Path;

use crate::common::{cargo_metadata, repo};

/// The crates a front end may depend on: the facade, the pure-data crates
/// it re-exports, and (for the command line's `zenoh` feature) the node.
const ALLOWED: [&str; 5] = [
    "servobus-robot",
    "servobus-config",
    "servobus-protocol",
    "servobus-kinematics",
    "servobus-node",
];

/// The crates below the facade that no front end may name.
const BELOW: [&str; 6] = ["runtime", "driver", "sim", "io", "timing", "trajectory"];

/// `(package, its normal servobus dependencies)` of the manifest at `path`.
fn normal_deps(manifest: &Path) -> Vec<(String, Vec<String>)> {
    let metadata = cargo_metadata(manifest, &["--no-deps", "--offline"]);
    let packages = metadata["packages"].as_array().expect("packages");
    packages
        .iter()
        .map(|p| {
            let name = p["name"].as_str().expect("a name").to_owned();
            let deps = p["dependencies"]
                .as_array()
                .expect("dependencies")
                .iter()
                .filter(|d| d["kind"].is_null())
                .filter_map(|d| d["name"].as_str())
                .filter(|d| d.starts_with("servobus"))
                .map(str::to_owned)
                .collect();
            (name, deps)
        })
        .collect()
}

#[test]
fn the_front_ends_depend_on_the_facade_and_the_data_crates_alone() {
    let mut checked = Vec::new();
    let workspace = normal_deps(&repo("Cargo.toml"));
    let python = normal_deps(&repo("python/Cargo.toml"));
    for (name, deps) in workspace.iter().chain(&python) {
        if !matches!(
            name.as_str(),
            "servobus" | "servobus-node" | "servobus-python"
        ) {
            continue;
        }
        let beyond: Vec<&String> = deps
            .iter()
            .filter(|d| !ALLOWED.contains(&d.as_str()))
            .collect();
        assert!(beyond.is_empty(), "{name} depends on {beyond:?}");
        assert!(
            deps.iter().any(|d| d == "servobus-robot"),
            "{name}: {deps:?}"
        );
        checked.push(name.clone());
    }
    checked.sort();
    assert_eq!(checked, ["servobus", "servobus-node", "servobus-python"]);
}

/// Every `.rs` file under `dir`.
fn sources(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("a source directory") {
        let path = entry.expect("an entry").path();
        if path.is_dir() {
            sources(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn the_front_ends_import_nothing_below_the_facade() {
    let mut files = Vec::new();
    for dir in ["src", "python/src", "crates/node/src"] {
        sources(&repo(dir), &mut files);
    }
    assert!(files.len() > 50, "{} files", files.len());
    let mut found = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).expect("a source file");
        for (n, line) in text.lines().enumerate() {
            for below in BELOW {
                if line.contains(&format!("servobus_{below}::")) {
                    found.push(format!("{}:{}: {}", file.display(), n + 1, line.trim()));
                }
            }
        }
    }
    assert!(found.is_empty(), "{}", found.join("\n"));
}

/// The command modules under `src/cmd/`: each is a command (or a family,
/// like `bus` and `fk`; `serve_hint` is `serve` in a build without Zenoh),
/// and none imports another.
const COMMANDS: [&str; 19] = [
    "bench",
    "budget",
    "bus",
    "calibrate",
    "decode",
    "docs",
    "doctor",
    "fk",
    "follow",
    "init",
    "list",
    "monitor",
    "plan",
    "play",
    "serve",
    "serve_hint",
    "sim",
    "stream",
    "teach",
];

#[test]
fn src_cmd_holds_one_module_per_command_and_nothing_else() {
    let mut others = Vec::new();
    let mut seen = 0;
    for entry in std::fs::read_dir(repo("src/cmd")).expect("src/cmd") {
        let name = entry.expect("an entry").file_name();
        let name = name.to_string_lossy();
        if name == "mod.rs" {
            continue;
        }
        if COMMANDS.contains(&name.trim_end_matches(".rs")) {
            seen += 1;
        } else {
            others.push(name.into_owned());
        }
    }
    assert!(seen >= COMMANDS.len(), "{seen} command entries");
    assert!(
        others.is_empty(),
        "not a command (shared code goes to src/shared/): {others:?}"
    );
}

#[test]
fn no_command_imports_another() {
    let cmd = repo("src/cmd");
    let mut files = Vec::new();
    sources(&cmd, &mut files);
    let mut found = Vec::new();
    let mut commands_seen = 0;
    for file in &files {
        let rel = file.strip_prefix(&cmd).expect("under src/cmd");
        let first = rel.components().next().expect("a component");
        let own = first.as_os_str().to_string_lossy();
        let own = own.trim_end_matches(".rs");
        if !COMMANDS.contains(&own) {
            continue;
        }
        commands_seen += 1;
        let text = std::fs::read_to_string(file).expect("a source file");
        for (n, line) in text.lines().enumerate() {
            for other in COMMANDS.iter().filter(|&&c| c != own) {
                let by_super = format!("super::{other}::");
                let by_crate = format!("crate::cmd::{other}::");
                let by_parent = format!("super::super::{other}::");
                // `super::` in a command's own submodule is the command.
                let nested = rel.components().count() > 1;
                if (!nested && line.contains(&by_super))
                    || line.contains(&by_crate)
                    || line.contains(&by_parent)
                {
                    found.push(format!("{}:{}: {}", file.display(), n + 1, line.trim()));
                }
            }
        }
    }
    assert!(
        commands_seen >= COMMANDS.len(),
        "{commands_seen} command files"
    );
    assert!(found.is_empty(), "{}", found.join("\n"));
}
