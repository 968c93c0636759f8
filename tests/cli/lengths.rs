//! No function of the project's own code (the CLI, the crates, the Python
//! bindings; tests, benches and examples aside) runs over 80 lines, from
//! its `fn` line to its closing brace, but the few listed in [`KEPT`],
//! each with the reason it reads better whole.
//!
//! The scan reads Rust as tokens far enough to be right about braces:
//! comments, strings (raw, byte, continued over lines) and character
//! literals are skipped, so a `{{` in a format string or a `'{'` counts
//! nothing. Code compiled only for tests (`#[cfg(test)] mod m { .. }` and
//! `#[cfg(test)] mod m;` files) is left out.

use std::path::{Path, PathBuf};

use crate::common::repo;
use crate::rust_code::code_only;

/// The longest a function may be, in lines.
const MOST: usize = 80;

/// Functions kept over [`MOST`] lines: the file (from the repository's
/// root), the function's name, and why it stays whole. At most 5.
const KEPT: [(&str, &str, &str); 0] = [];

/// A function found by the scan: where it starts and how long it is.
#[derive(Debug)]
struct Function {
    file: String,
    line: usize,
    name: String,
    lines: usize,
}

/// Whether `word` stands at `i` of `code` as a whole word.
fn word_at(code: &[u8], i: usize, word: &[u8]) -> bool {
    let ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    code[i..].starts_with(word)
        && (i == 0 || !ident(code[i - 1]))
        && code.get(i + word.len()).is_none_or(|&c| !ident(c))
}

/// The identifier after `i` (past spaces).
fn ident_after(code: &[u8], mut i: usize) -> (String, usize) {
    while code.get(i).is_some_and(|c| c.is_ascii_whitespace()) {
        i += 1;
    }
    let start = i;
    while code
        .get(i)
        .is_some_and(|&c| c.is_ascii_alphanumeric() || c == b'_')
    {
        i += 1;
    }
    (String::from_utf8_lossy(&code[start..i]).into_owned(), i)
}

/// The index just past the brace that closes the one at `open`.
fn closing(code: &[u8], open: usize) -> usize {
    let mut depth = 0usize;
    for (k, &c) in code.iter().enumerate().skip(open) {
        match c {
            b'{' => depth += 1,
            b'}' => {
                depth -= 1;
                if depth == 0 {
                    return k + 1;
                }
            }
            _ => {}
        }
    }
    code.len()
}

/// The functions of one file, and the names of the modules it declares
/// for tests only (`#[cfg(test)] mod name;`), whose files are skipped.
fn scan(file: &str, text: &str) -> (Vec<Function>, Vec<String>) {
    let code = code_only(text);
    let line_of = |i: usize| code[..i].iter().filter(|&&c| c == b'\n').count() + 1;
    let (mut found, mut test_files) = (Vec::new(), Vec::new());
    let mut i = 0;
    while i < code.len() {
        if code[i..].starts_with(b"#[cfg(test)]") {
            let after = i + b"#[cfg(test)]".len();
            let next = after
                + code[after..]
                    .iter()
                    .position(|c| !c.is_ascii_whitespace())
                    .unwrap_or(0);
            let next = if word_at(&code, next, b"pub") {
                ident_after(&code, next + 3).1
            } else {
                next
            };
            let next = next
                + code[next..]
                    .iter()
                    .position(|c| !c.is_ascii_whitespace())
                    .unwrap_or(0);
            if word_at(&code, next, b"mod") {
                let (name, end) = ident_after(&code, next + 3);
                let rest = &code[end..];
                let stop = rest.iter().position(|&c| c == b'{' || c == b';');
                match stop.map(|s| (end + s, rest[s])) {
                    Some((open, b'{')) => {
                        i = closing(&code, open);
                        continue;
                    }
                    Some((semi, _)) => {
                        test_files.push(name);
                        i = semi + 1;
                        continue;
                    }
                    None => {}
                }
            }
            i = after;
        } else if word_at(&code, i, b"fn") {
            let (name, end) = ident_after(&code, i + 2);
            let rest = &code[end..];
            match rest.iter().position(|&c| c == b'{' || c == b';') {
                Some(s) if rest[s] == b'{' && !name.is_empty() => {
                    let close = closing(&code, end + s);
                    let (first, last) = (line_of(i), line_of(close - 1));
                    found.push(Function {
                        file: file.to_string(),
                        line: first,
                        name,
                        lines: last - first + 1,
                    });
                    // Go on inside: a function may hold functions.
                    i = end + s + 1;
                }
                _ => i = end.max(i + 2),
            }
        } else {
            i += 1;
        }
    }
    (found, test_files)
}

/// Every `.rs` file under `dir`, tests, benches, examples and test-only
/// modules aside.
fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
    entries.sort();
    for path in entries {
        let name = path
            .file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned());
        if path.is_dir() {
            if !["tests", "benches", "examples", "target"].contains(&name.as_str()) {
                walk(&path, out);
            }
        } else if name.ends_with(".rs") && name != "tests.rs" {
            out.push(path);
        }
    }
}

/// The files a test-only `mod name;` in `file` stands for.
fn module_files(file: &Path, name: &str) -> [PathBuf; 2] {
    let dir = file.parent().unwrap_or(Path::new("."));
    let stem = file
        .file_stem()
        .map_or(String::new(), |s| s.to_string_lossy().into_owned());
    let base = if ["mod", "lib", "main"].contains(&stem.as_str()) {
        dir.to_path_buf()
    } else {
        dir.join(stem)
    };
    [
        base.join(format!("{name}.rs")),
        base.join(name).join("mod.rs"),
    ]
}

/// Every function of the project's own code.
fn functions() -> Vec<Function> {
    let root = repo("");
    let mut files = Vec::new();
    walk(&root.join("src"), &mut files);
    walk(&root.join("python/src"), &mut files);
    let crates = std::fs::read_dir(root.join("crates")).expect("crates/");
    let mut crates: Vec<PathBuf> = crates.flatten().map(|e| e.path().join("src")).collect();
    crates.sort();
    for dir in crates {
        walk(&dir, &mut files);
    }
    let mut all = Vec::new();
    let mut test_only = Vec::new();
    for path in &files {
        let text = std::fs::read_to_string(path).expect("a readable source");
        let name = path
            .strip_prefix(&root)
            .unwrap_or(path)
            .to_string_lossy()
            .into_owned();
        let (found, tests) = scan(&name, &text);
        for module in tests {
            test_only.extend(module_files(path, &module));
        }
        all.push((path.clone(), found));
    }
    all.into_iter()
        .filter(|(path, _)| !test_only.contains(path))
        .flat_map(|(_, found)| found)
        .collect()
}

#[test]
fn the_scan_counts_braces_of_code_only() {
    let text = "fn a() {\n    let s = \"{{ }\";\n    let c = '{';\n    // }\n    \
                let r = r#\"}\"#;\n    b(|x: &'static str| x);\n}\n\
                #[cfg(test)]\nmod tests {\n    fn long() {\n    }\n}\n\
                #[cfg(test)]\nmod testing;\nfn z(\n    x: u8,\n) -> u8 {\n    x\n}\n";
    let (found, tests) = scan("x.rs", text);
    let seen: Vec<(&str, usize, usize)> = found
        .iter()
        .map(|f| (f.name.as_str(), f.line, f.lines))
        .collect();
    assert_eq!(seen, [("a", 1, 7), ("z", 15, 5)]);
    assert_eq!(tests, ["testing"]);
}

#[test]
fn no_function_runs_over_80_lines_but_the_few_kept_with_a_reason() {
    let all = functions();
    // The scan finds the code at all: a few thousand functions.
    assert!(all.len() > 1000, "{} functions found", all.len());
    let long: Vec<&Function> = all.iter().filter(|f| f.lines > MOST).collect();
    let unlisted: Vec<String> = long
        .iter()
        .filter(|f| {
            !KEPT
                .iter()
                .any(|(file, name, _)| *file == f.file && *name == f.name)
        })
        .map(|f| format!("{}:{} {} ({} lines)", f.file, f.line, f.name, f.lines))
        .collect();
    assert!(
        unlisted.is_empty(),
        "functions over {MOST} lines: split them, or keep one with its reason in KEPT:\n{}",
        unlisted.join("\n")
    );
    // The list stays honest: each kept function is still over the line,
    // has a reason, and there are few.
    assert!(KEPT.len() <= 5, "{} kept", KEPT.len());
    for (file, name, why) in KEPT {
        assert!(
            long.iter().any(|f| f.file == file && f.name == name),
            "{file} {name} is no longer over {MOST} lines: take it off KEPT"
        );
        assert!(why.len() > 20, "{file} {name}: say why it stays whole");
    }
}
