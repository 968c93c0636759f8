//! Facts about the build the README states, checked against where they
//! are decided: the minimum Rust against the locked dependencies, the
//! licence against every crate's manifest and the licence files, the crate
//! table against `crates/`.

use crate::common::{cargo_metadata, repo};

/// The value of `key = "VALUE"` in the `[section]` of the TOML `text`
/// (a flat reading: enough for the manifests of this workspace).
fn toml_value(text: &str, section: &str, key: &str) -> Option<String> {
    let mut inside = false;
    for line in text.lines().map(str::trim) {
        if line.starts_with('[') {
            inside = line == format!("[{section}]");
            continue;
        }
        let Some((k, v)) = line.split_once('=') else {
            continue;
        };
        if inside && k.trim() == key {
            return Some(v.trim().trim_matches('"').to_owned());
        }
    }
    None
}

/// `1.88`, `1.85.0` as numbers to compare.
fn version(text: &str) -> Vec<u64> {
    let parts = text
        .split('.')
        .map(|p| p.parse().expect("a numeric version"));
    let mut v: Vec<u64> = parts.collect();
    v.resize(3, 0);
    v
}

fn workspace_package(key: &str) -> String {
    let text = std::fs::read_to_string(repo("Cargo.toml")).expect("Cargo.toml");
    toml_value(&text, "workspace.package", key).unwrap_or_else(|| panic!("no workspace {key}"))
}

/// The crates of `crates/`, by directory name.
fn crates() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(repo("crates"))
        .expect("crates/")
        .map(|e| e.expect("an entry").path())
        .filter(|p| p.join("Cargo.toml").is_file())
        .map(|p| {
            p.file_name()
                .expect("a name")
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    names.sort();
    names
}

#[test]
#[ignore = "runs `cargo metadata --all-features`, which may fetch the optional dependencies' manifests: `cargo test --test cli -- --ignored` (the gate runs it)"]
fn the_rust_version_is_that_of_the_most_demanding_locked_dependency_at_least() {
    let metadata = cargo_metadata(&repo("Cargo.toml"), &["--locked", "--all-features"]);
    let declared = workspace_package("rust-version");
    let members = metadata["workspace_members"].as_array().expect("members");
    let packages = metadata["packages"].as_array().expect("packages");
    // Every package of the lock file is there with every feature on.
    let locked = std::fs::read_to_string(repo("Cargo.lock")).expect("Cargo.lock");
    let in_lock = locked.lines().filter(|l| l.starts_with("name = ")).count();
    assert_eq!(
        packages.len(),
        in_lock,
        "metadata lists every locked package"
    );
    let mut needs = Vec::new();
    for package in packages {
        let name = package["name"].as_str().expect("a name");
        let rust = package["rust_version"].as_str();
        if members.contains(&package["id"]) {
            assert_eq!(
                rust,
                Some(declared.as_str()),
                "{name} inherits the workspace's"
            );
        } else if let Some(rust) = rust {
            needs.push((version(rust), name.to_owned()));
        }
    }
    needs.sort();
    let (most, name) = needs.last().expect("dependencies that say");
    assert!(
        version(&declared) >= *most,
        "rust-version {declared} in Cargo.toml, but {name} needs {most:?}"
    );
}

#[test]
fn the_readme_states_the_minimum_rust_and_the_licence_of_every_crate() {
    let readme = std::fs::read_to_string(repo("README.md")).expect("README.md");
    let rust = workspace_package("rust-version");
    let said = format!("Rust {rust} or newer");
    assert_eq!(
        readme.matches(&said).count(),
        1,
        "the README says `{said}` once"
    );
    assert_eq!(
        readme.matches("Rust 1.").count(),
        1,
        "no other minimum Rust in the README"
    );
    let license = workspace_package("license");
    assert_eq!(license, "MIT OR Apache-2.0");
    assert!(
        readme.contains(&format!("`{license}`")),
        "the README names `{license}`"
    );
    for (file, first_words) in [
        ("LICENSE-MIT", "MIT License"),
        ("LICENSE-APACHE", "Apache License"),
    ] {
        let text = std::fs::read_to_string(repo(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert!(text.trim_start().starts_with(first_words), "{file}");
        assert!(
            readme.contains(&format!("]({file})")),
            "the README links {file}"
        );
    }
    // Every crate takes both from the workspace; the Python extension,
    // outside it but built from its crates, states the same.
    for name in crates()
        .iter()
        .map(|c| format!("crates/{c}/Cargo.toml"))
        .chain(["Cargo.toml".into()])
    {
        let text = std::fs::read_to_string(repo(&name)).expect("a manifest");
        for key in ["license", "rust-version"] {
            assert_eq!(
                toml_value(&text, "package", &format!("{key}.workspace")).as_deref(),
                Some("true"),
                "{name}: {key}"
            );
        }
    }
    let python = std::fs::read_to_string(repo("python/Cargo.toml")).expect("python/Cargo.toml");
    assert_eq!(toml_value(&python, "package", "license"), Some(license));
    assert_eq!(toml_value(&python, "package", "rust-version"), Some(rust));
}

#[test]
fn the_readme_crate_table_lists_every_crate() {
    let readme = std::fs::read_to_string(repo("README.md")).expect("README.md");
    // The table that starts `| where | what |`, to its last row.
    let table = readme.lines().skip_while(|l| *l != "| where | what |");
    let rows: Vec<String> = table
        .take_while(|l| l.starts_with('|'))
        .filter_map(|l| l.strip_prefix("| `crates/"))
        .filter_map(|l| l.split_once("` |").map(|(name, _)| name.to_owned()))
        .collect();
    let mut listed = rows.clone();
    listed.sort();
    assert_eq!(
        listed,
        crates(),
        "the README's crate table, row by row: {rows:?}"
    );
}
