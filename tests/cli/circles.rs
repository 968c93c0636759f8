//! The command line has no circle of files: in the import graph of the
//! files under `src/` no file reaches itself.
//!
//! Every `.rs` file is a node (test-only modules aside). File A has an edge
//! to file B when A's code names an item of B's module through a path:
//! `use crate::x::y`, `use super::…`, `use child::…` (a re-export
//! `pub use` included), `crate::x::f(…)` or `super::f` in code, `self::m::f`,
//! `$crate::…` in a macro, `servobus::…` from the binary into the library,
//! and a path through a name a `use` bound to a module. A path counts for
//! the file of the longest prefix of it that is a module: `crate::shared::
//! out::errln` for `src/shared/out.rs`, `crate::shared::refused` for
//! `src/shared/mod.rs`. A `mod x;` declaration alone is no edge.
//!
//! The scan blanks comments, strings and character literals first (as
//! `lengths.rs` does), and leaves out `#[cfg(test)]` items.

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::path::Path;

use crate::common::repo;
use crate::rust_code::code_only;

/// A module: the crate it is in (`main` or `lib`), then its path from that
/// crate's root.
type Module = Vec<String>;

/// A path named by the code.
#[derive(Debug)]
struct Named {
    /// The path's segments (`crate`, `shared`, `out`, `errln`).
    segs: Vec<String>,
    /// The line it is on.
    line: usize,
    /// The name a `use` binds it to, if it is a `use` leaf that binds one.
    binds: Option<String>,
    /// Whether it is a glob import (`use super::*`).
    glob: bool,
}

/// A module declared in a scope: by file (`mod x;`) or inline (`mod x { … }`).
enum Decl {
    /// `mod x;`, or `#[cfg(test)] mod x;` (`true`: the file is test code).
    File(String, bool),
    /// `mod x { … }`: the name and the byte range of its body.
    Inline(String, usize, usize),
}

/// One module's part of a file: the paths it names.
struct Scope {
    module: Module,
    file: String,
    named: Vec<Named>,
}

/// An edge of the graph, with the path that makes it.
#[derive(Debug, Clone)]
struct Edge {
    from: String,
    to: String,
    path: String,
    line: usize,
}

/// The import graph of a crate's files.
struct Graph {
    /// Every file reached from the crate roots.
    files: BTreeSet<String>,
    /// Every path that ties one file to another.
    edges: Vec<Edge>,
    /// Files of test-only modules (`#[cfg(test)] mod x;`), not nodes.
    test_only: BTreeSet<String>,
    /// Modules declared whose file was not found.
    missing: Vec<String>,
}

/// Whether `c` can be part of an identifier.
fn ident(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

/// The index of the first byte at or after `i` that is not white space.
fn skip_space(code: &[u8], mut i: usize) -> usize {
    while code.get(i).is_some_and(|c| c.is_ascii_whitespace()) {
        i += 1;
    }
    i
}

/// The word at `i` (an identifier, or `$` and one), and the index past it.
fn word(code: &[u8], i: usize) -> (String, usize) {
    let mut j = i + usize::from(code.get(i) == Some(&b'$'));
    while code.get(j).is_some_and(|&c| ident(c)) {
        j += 1;
    }
    (String::from_utf8_lossy(&code[i..j]).into_owned(), j)
}

/// Whether a word starts at `i`: an identifier's first letter or `$`, not
/// inside another word.
fn word_starts(code: &[u8], i: usize) -> bool {
    let c = code[i];
    (c.is_ascii_alphabetic() || c == b'_' || c == b'$') && (i == 0 || !ident(code[i - 1]))
}

/// The index just past the bracket that closes the one at `open`.
fn closing(code: &[u8], open: usize) -> usize {
    let mut depth = 0usize;
    for (k, &c) in code.iter().enumerate().skip(open) {
        match c {
            b'{' | b'(' | b'[' => depth += 1,
            b'}' | b')' | b']' => {
                depth = depth.saturating_sub(1);
                if depth == 0 {
                    return k + 1;
                }
            }
            _ => {}
        }
    }
    code.len()
}

/// The line numbers of a text, by byte offset.
struct Lines(Vec<usize>);

impl Lines {
    /// Where each line of `code` starts.
    fn new(code: &[u8]) -> Self {
        let breaks = code.iter().enumerate().filter(|(_, &c)| c == b'\n');
        Lines(
            std::iter::once(0)
                .chain(breaks.map(|(i, _)| i + 1))
                .collect(),
        )
    }

    /// The line (from 1) of byte `i`.
    fn of(&self, i: usize) -> usize {
        self.0.partition_point(|&start| start <= i)
    }
}

/// Past the item a `#[cfg(test)]` ending at `i` applies to, and the test
/// module it declares by file, if it does. An item the attribute may be on
/// that is not recognised is not skipped.
fn skip_test_item(code: &[u8], i: usize) -> (usize, Option<String>) {
    let mut j = skip_space(code, i);
    while code.get(j) == Some(&b'#') {
        if code.get(j + 1) != Some(&b'[') {
            break;
        }
        j = skip_space(code, closing(code, j + 1));
    }
    if code.len() > j && word_starts(code, j) && word(code, j).0 == "pub" {
        j = skip_space(code, j + 3);
        if code.get(j) == Some(&b'(') {
            j = skip_space(code, closing(code, j));
        }
    }
    if j >= code.len() || !word_starts(code, j) {
        return (i, None);
    }
    let (keyword, after) = word(code, j);
    if keyword == "mod" {
        let (name, end) = word(code, skip_space(code, after));
        let next = skip_space(code, end);
        return match code.get(next) {
            Some(b';') => (next + 1, Some(name)),
            Some(b'{') => (closing(code, next), None),
            _ => (i, None),
        };
    }
    let items = [
        "fn", "impl", "struct", "enum", "const", "static", "trait", "type", "use", "unsafe",
        "async", "extern",
    ];
    if !items.contains(&keyword.as_str()) {
        return (i, None);
    }
    let mut k = after;
    while k < code.len() {
        match code[k] {
            b';' => return (k + 1, None),
            b'{' => return (closing(code, k), None),
            b'(' | b'[' => k = closing(code, k),
            b'}' | b')' | b']' => return (k, None),
            _ => k += 1,
        }
    }
    (code.len(), None)
}

/// The segments of the path starting at `i` (`a::b::c`, stopping before
/// `::<`, `::{` or `::*`) and the index past it.
fn path_at(code: &[u8], i: usize) -> (Vec<String>, usize) {
    let (first, mut end) = word(code, i);
    let mut segs = vec![first];
    loop {
        let sep = skip_space(code, end);
        if !code[sep..].starts_with(b"::") {
            break;
        }
        let next = skip_space(code, sep + 2);
        if next >= code.len() || !word_starts(code, next) {
            break;
        }
        let (seg, past) = word(code, next);
        segs.push(seg);
        end = past;
    }
    (segs, end)
}

/// Whether the word at `i` continues a path (`…::word`) instead of
/// starting one.
fn continues_path(code: &[u8], i: usize) -> bool {
    let mut j = i;
    while j > 0 && code[j - 1].is_ascii_whitespace() {
        j -= 1;
    }
    j >= 2 && &code[j - 2..j] == b"::"
}

/// The tokens of a `use` tree: words, `::`, braces, commas and `*`.
fn use_tokens(code: &[u8]) -> Vec<String> {
    let mut tokens = Vec::new();
    let mut i = 0;
    while i < code.len() {
        if code[i..].starts_with(b"::") {
            tokens.push("::".to_string());
            i += 2;
        } else if word_starts(code, i) {
            let (w, end) = word(code, i);
            tokens.push(w);
            i = end;
        } else {
            if b"{},*".contains(&code[i]) {
                tokens.push((code[i] as char).to_string());
            }
            i += 1;
        }
    }
    tokens
}

/// The leaves of the `use` tree at `tokens[*pos]`, under `prefix`: each
/// full path, the name it binds, and whether it is a glob.
fn use_tree(
    tokens: &[String],
    pos: &mut usize,
    prefix: &[String],
    out: &mut Vec<(Vec<String>, Option<String>, bool)>,
) {
    let at = |p: usize| tokens.get(p).map_or("", String::as_str);
    let mut segs = prefix.to_vec();
    if at(*pos) == "::" {
        // `use ::name`: a crate from outside, never a file of this one.
        segs.push("::".to_string());
        *pos += 1;
    }
    match at(*pos) {
        "{" => {
            *pos += 1;
            while !["}", ""].contains(&at(*pos)) {
                use_tree(tokens, pos, &segs, out);
                if at(*pos) == "," {
                    *pos += 1;
                }
            }
            *pos += 1;
            return;
        }
        "*" => {
            *pos += 1;
            out.push((segs, None, true));
            return;
        }
        _ => {}
    }
    while !["", "::", "{", "}", ",", "*", "as"].contains(&at(*pos)) {
        segs.push(tokens[*pos].clone());
        *pos += 1;
        if at(*pos) != "::" {
            break;
        }
        if ["{", "*"].contains(&at(*pos + 1)) {
            *pos += 1;
            use_tree(tokens, pos, &segs, out);
            return;
        }
        *pos += 1;
    }
    if segs.len() > 1 && segs.last().is_some_and(|s| s == "self") {
        segs.pop();
    }
    let mut binds = segs.last().cloned();
    if at(*pos) == "as" {
        binds = Some(at(*pos + 1).to_string()).filter(|b| b != "_");
        *pos += 2;
    }
    out.push((segs, binds, false));
}

/// The paths named and the modules declared in `code[start..end]` (one
/// module's body), `#[cfg(test)]` items left out.
fn scan_scope(code: &[u8], lines: &Lines, start: usize, end: usize) -> (Vec<Named>, Vec<Decl>) {
    let (mut named, mut decls) = (Vec::new(), Vec::new());
    let mut i = start;
    while i < end {
        if code[i..end].starts_with(b"#[cfg(test)]") {
            let (past, test_mod) = skip_test_item(&code[..end], i + b"#[cfg(test)]".len());
            decls.extend(test_mod.map(|name| Decl::File(name, true)));
            i = past.max(i + 1);
            continue;
        }
        if !word_starts(code, i) {
            i += 1;
            continue;
        }
        let (w, after) = word(code, i);
        if w == "use" {
            let semi = code[after..end]
                .iter()
                .position(|&c| c == b';')
                .map_or(end, |s| after + s);
            let tokens = use_tokens(&code[after..semi]);
            let mut leaves = Vec::new();
            let mut pos = 0;
            while pos < tokens.len() {
                use_tree(&tokens, &mut pos, &[], &mut leaves);
            }
            let line = lines.of(i);
            named.extend(leaves.into_iter().map(|(segs, binds, glob)| Named {
                segs,
                line,
                binds,
                glob,
            }));
            i = semi + 1;
        } else if w == "mod" {
            let (name, past) = word(code, skip_space(code, after));
            let next = skip_space(code, past);
            match code.get(next) {
                Some(b';') => {
                    decls.push(Decl::File(name, false));
                    i = next + 1;
                }
                Some(b'{') => {
                    let close = closing(code, next);
                    decls.push(Decl::Inline(name, next + 1, close - 1));
                    i = close;
                }
                _ => i = past,
            }
        } else {
            let (segs, past) = path_at(code, i);
            if segs.len() > 1 && !continues_path(code, i) {
                let line = lines.of(i);
                named.push(Named {
                    segs,
                    line,
                    binds: None,
                    glob: false,
                });
            }
            i = past;
        }
    }
    (named, decls)
}

/// The directory that holds the files of the modules `file` declares.
fn module_dir(file: &str) -> String {
    let (parent, name) = file.rsplit_once('/').unwrap_or(("", file));
    let stem = name.trim_end_matches(".rs");
    if ["mod", "lib", "main"].contains(&stem) {
        parent.to_string()
    } else {
        format!("{parent}/{stem}")
    }
}

/// The files reached from the crate roots, as scopes: one per module (an
/// inline module is a scope of its file).
struct Walk<'a> {
    sources: &'a BTreeMap<String, String>,
    scopes: Vec<Scope>,
    test_only: BTreeSet<String>,
    missing: Vec<String>,
}

impl Walk<'_> {
    /// Scans the file `file`, the module `module`, and the files of the
    /// modules it declares.
    fn file(&mut self, file: &str, module: Module) {
        let Some(text) = self.sources.get(file) else {
            return;
        };
        let code = code_only(text);
        let lines = Lines::new(&code);
        self.scope(
            file,
            &code,
            &lines,
            (0, code.len()),
            module,
            module_dir(file),
        );
    }

    /// Scans one module's body `range` of `file`, and the modules it declares
    /// (their files in `dir`).
    fn scope(
        &mut self,
        file: &str,
        code: &[u8],
        lines: &Lines,
        range: (usize, usize),
        module: Module,
        dir: String,
    ) {
        let (named, decls) = scan_scope(code, lines, range.0, range.1);
        self.scopes.push(Scope {
            module: module.clone(),
            file: file.to_string(),
            named,
        });
        for decl in decls {
            match decl {
                Decl::File(name, test) => {
                    let candidates = [format!("{dir}/{name}.rs"), format!("{dir}/{name}/mod.rs")];
                    if test {
                        self.test_only.extend(candidates);
                        continue;
                    }
                    let mut child = module.clone();
                    child.push(name);
                    match candidates.iter().find(|c| self.sources.contains_key(*c)) {
                        Some(path) => self.file(&path.clone(), child),
                        None => self
                            .missing
                            .push(format!("{file}: mod {}", child.join("::"))),
                    }
                }
                Decl::Inline(name, from, to) => {
                    let mut child = module.clone();
                    child.push(name.clone());
                    let dir = format!("{dir}/{name}");
                    self.scope(file, code, lines, (from, to), child, dir);
                }
            }
        }
    }
}

/// The module `segs` names from the module `at` (with the modules `uses`
/// bound to names), and whether the whole path is that module. `None` for
/// a path outside the crate's files.
fn resolve(
    segs: &[String],
    at: &[String],
    uses: &BTreeMap<String, Module>,
    modules: &BTreeMap<Module, String>,
) -> Option<(Module, bool)> {
    let join = |base: &[String], seg: &str| -> Module {
        let mut m = base.to_vec();
        m.push(seg.to_string());
        m
    };
    let first = segs.first()?.as_str();
    let (mut base, mut rest) = match first {
        "crate" | "$crate" => (at[..1].to_vec(), 1),
        "self" => (at.to_vec(), 1),
        "super" => {
            let ups = segs.iter().take_while(|s| *s == "super").count();
            if ups >= at.len() {
                return None;
            }
            (at[..at.len() - ups].to_vec(), ups)
        }
        name if modules.contains_key(&join(at, name)) => (join(at, name), 1),
        name if uses.contains_key(name) => (uses[name].clone(), 1),
        "servobus" if at[0] == "main" && modules.contains_key(&["lib".to_string()][..]) => {
            (vec!["lib".to_string()], 1)
        }
        _ => return None,
    };
    while let Some(seg) = segs.get(rest) {
        let next = join(&base, seg);
        if !modules.contains_key(&next) {
            break;
        }
        base = next;
        rest += 1;
    }
    Some((base, rest == segs.len()))
}

/// The names each scope's `use`s bind to modules of the crate, glob imports
/// (`use super::*`) bringing in the names the globbed module has.
fn bound_names(
    scopes: &[Scope],
    modules: &BTreeMap<Module, String>,
) -> Vec<BTreeMap<String, Module>> {
    let index: BTreeMap<&Module, usize> = scopes
        .iter()
        .enumerate()
        .map(|(k, s)| (&s.module, k))
        .collect();
    let mut bound: Vec<BTreeMap<String, Module>> = vec![BTreeMap::new(); scopes.len()];
    // A name bound through another name settles in a few rounds.
    for _ in 0..8 {
        let mut changed = false;
        for (k, scope) in scopes.iter().enumerate() {
            for named in &scope.named {
                let Some((module, true)) = resolve(&named.segs, &scope.module, &bound[k], modules)
                else {
                    continue;
                };
                let mut add: Vec<(String, Module)> = Vec::new();
                if let Some(name) = &named.binds {
                    add.push((name.clone(), module));
                } else if named.glob {
                    let children = modules
                        .keys()
                        .filter(|m| m.len() == module.len() + 1 && m.starts_with(&module));
                    add.extend(children.map(|m| (m[m.len() - 1].clone(), m.clone())));
                    if let Some(&g) = index.get(&module) {
                        add.extend(bound[g].iter().map(|(n, m)| (n.clone(), m.clone())));
                    }
                }
                for (name, module) in add {
                    if bound[k].get(&name) != Some(&module) {
                        bound[k].insert(name, module);
                        changed = true;
                    }
                }
            }
        }
        if !changed {
            break;
        }
    }
    bound
}

/// The import graph of `sources` (file paths from the package's root, such
/// as `src/main.rs`, with their text); `src/main.rs` and `src/lib.rs` are the
/// crate roots.
fn graph(sources: &BTreeMap<String, String>) -> Graph {
    let mut walk = Walk {
        sources,
        scopes: Vec::new(),
        test_only: BTreeSet::new(),
        missing: Vec::new(),
    };
    for (root, krate) in [("src/main.rs", "main"), ("src/lib.rs", "lib")] {
        walk.file(root, vec![krate.to_string()]);
    }
    let modules: BTreeMap<Module, String> = walk
        .scopes
        .iter()
        .map(|s| (s.module.clone(), s.file.clone()))
        .collect();
    let bound = bound_names(&walk.scopes, &modules);
    let mut edges = Vec::new();
    for (scope, uses) in walk.scopes.iter().zip(&bound) {
        for named in &scope.named {
            let Some((module, _)) = resolve(&named.segs, &scope.module, uses, &modules) else {
                continue;
            };
            let to = &modules[&module];
            if *to != scope.file {
                edges.push(Edge {
                    from: scope.file.clone(),
                    to: to.clone(),
                    path: named.segs.join("::"),
                    line: named.line,
                });
            }
        }
    }
    Graph {
        files: walk.scopes.iter().map(|s| s.file.clone()).collect(),
        edges,
        test_only: walk.test_only,
        missing: walk.missing,
    }
}

impl Graph {
    /// Each file's successors (each pair once).
    fn successors(&self) -> BTreeMap<&str, BTreeSet<&str>> {
        let mut next: BTreeMap<&str, BTreeSet<&str>> = self
            .files
            .iter()
            .map(|f| (f.as_str(), BTreeSet::new()))
            .collect();
        for e in &self.edges {
            next.entry(e.from.as_str())
                .or_default()
                .insert(e.to.as_str());
        }
        next
    }

    /// The number of distinct edges (pairs of files).
    fn edge_count(&self) -> usize {
        self.successors().values().map(BTreeSet::len).sum()
    }

    /// The circles: each group of two or more files that reach one another
    /// (a strongly connected component), its files in order.
    fn circles(&self) -> Vec<Vec<String>> {
        let next = self.successors();
        let reach = |from: &str| -> BTreeSet<&str> {
            let mut seen = BTreeSet::new();
            let mut todo = vec![from];
            while let Some(f) = todo.pop() {
                for &n in next.get(f).into_iter().flatten() {
                    if seen.insert(n) {
                        todo.push(n);
                    }
                }
            }
            seen
        };
        let reached: BTreeMap<&str, BTreeSet<&str>> =
            self.files.iter().map(|f| (f.as_str(), reach(f))).collect();
        let mut done = BTreeSet::new();
        let mut circles = Vec::new();
        for f in &self.files {
            if done.contains(f.as_str()) || !reached[f.as_str()].contains(f.as_str()) {
                continue;
            }
            let group: Vec<String> = reached[f.as_str()]
                .iter()
                .filter(|g| reached[**g].contains(f.as_str()))
                .map(|g| g.to_string())
                .collect();
            done.extend(group.iter().cloned());
            circles.push(group);
        }
        circles
    }

    /// A shortest circle through the first file of `group`, as files.
    fn shortest_loop(&self, group: &[String]) -> Vec<String> {
        let next = self.successors();
        let start = group[0].as_str();
        let mut came: BTreeMap<&str, &str> = BTreeMap::new();
        let mut todo = VecDeque::from([start]);
        while let Some(f) = todo.pop_front() {
            for &n in next.get(f).into_iter().flatten() {
                if n == start {
                    let mut files = vec![f];
                    while let Some(&p) = came.get(files[files.len() - 1]) {
                        files.push(p);
                    }
                    files.reverse();
                    files.push(start);
                    return files.into_iter().map(String::from).collect();
                }
                if !came.contains_key(n) && n != start {
                    came.insert(n, f);
                    todo.push_back(n);
                }
            }
        }
        Vec::new()
    }

    /// A circle said in full: a shortest loop through it, then every edge
    /// between its files with the paths that make it.
    fn describe(&self, group: &[String]) -> String {
        let mut text = format!(
            "circle of {} files: {}\n",
            group.len(),
            self.shortest_loop(group).join(" -> ")
        );
        for e in &self.edges {
            if group.contains(&e.from) && group.contains(&e.to) {
                text += &format!(
                    "  {} -> {}: `{}` ({}:{})\n",
                    e.from, e.to, e.path, e.from, e.line
                );
            }
        }
        text
    }
}

/// Every `.rs` file under `dir`, as paths from `root` with `/` between names.
fn rust_files(root: &Path, dir: &Path, out: &mut BTreeMap<String, String>) {
    let entries = std::fs::read_dir(dir).expect("a readable directory");
    for path in entries.flatten().map(|e| e.path()) {
        if path.is_dir() {
            rust_files(root, &path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let name = path.strip_prefix(root).unwrap_or(&path);
            let name = name
                .components()
                .map(|c| c.as_os_str().to_string_lossy())
                .collect::<Vec<_>>()
                .join("/");
            let text = std::fs::read_to_string(&path).expect("a readable source");
            out.insert(name, text);
        }
    }
}

/// Fake sources from `(path, text)` pairs.
fn fake(files: &[(&str, &str)]) -> BTreeMap<String, String> {
    files
        .iter()
        .map(|(p, t)| (p.to_string(), t.to_string()))
        .collect()
}

#[test]
fn the_graph_builder_finds_circles_and_only_circles() {
    // Two sibling files naming each other through `super::`.
    let through_super = graph(&fake(&[
        ("src/main.rs", "mod a;\nmod b;\nfn main() {}\n"),
        ("src/a.rs", "pub fn f() {\n    super::b::g();\n}\n"),
        ("src/b.rs", "pub fn g() {\n    super::a::f()\n}\n"),
    ]));
    assert_eq!(through_super.circles(), [["src/a.rs", "src/b.rs"]]);
    let said = through_super.describe(&through_super.circles()[0]);
    assert!(said.contains("src/a.rs -> src/b.rs -> src/a.rs"), "{said}");
    assert!(said.contains("`super::b::g` (src/a.rs:2)"), "{said}");

    // Through `crate::a::b`: `a/b.rs` names `c`, `c` imports from `a::b`;
    // `a.rs` only declares `b`. Comments, strings and test code name nothing.
    let through_crate = graph(&fake(&[
        ("src/main.rs", "mod a;\nmod c;\n"),
        ("src/a.rs", "pub mod b;\n// crate::c::y\n"),
        ("src/a/b.rs", "pub fn x() -> u8 { crate::c::y() }\n"),
        (
            "src/c.rs",
            "use crate::a::b::x;\npub fn y() -> u8 { 1 }\nconst S: &str = \"crate::a\";\n",
        ),
    ]));
    assert_eq!(through_crate.circles(), [["src/a/b.rs", "src/c.rs"]]);
    assert_eq!(through_crate.edge_count(), 2);

    // A parent declaring its child, which uses the parent: one way only.
    let declared = graph(&fake(&[
        ("src/main.rs", "mod a;\n"),
        (
            "src/a/mod.rs",
            "mod b;\npub fn f() {}\n#[cfg(test)]\nmod tests {\n    use super::b::*;\n}\n",
        ),
        ("src/a/b.rs", "use super::f;\nfn g() { f() }\n"),
    ]));
    assert!(declared.circles().is_empty());
    assert_eq!(declared.edges.len(), 1);
    assert_eq!(declared.edges[0].to, "src/a/mod.rs");

    // A path resolves to its longest module prefix; a re-export is an edge;
    // a name bound to a module carries its path on.
    let prefix = graph(&fake(&[
        ("src/main.rs", "mod shared;\nmod cmd;\n"),
        (
            "src/shared/mod.rs",
            "pub(crate) mod out;\nmod refusal;\npub(crate) use refusal::refused;\n",
        ),
        ("src/shared/out.rs", "pub fn errln() {}\n"),
        ("src/shared/refusal.rs", "pub fn refused() {}\n"),
        (
            "src/cmd.rs",
            "use crate::shared;\nfn r() { crate::shared::refused(); shared::out::errln() }\n",
        ),
    ]));
    let mut seen: Vec<(&str, &str)> = prefix
        .edges
        .iter()
        .map(|e| (e.to.as_str(), e.path.as_str()))
        .collect();
    seen.sort();
    assert_eq!(
        seen,
        [
            ("src/shared/mod.rs", "crate::shared"),
            ("src/shared/mod.rs", "crate::shared::refused"),
            ("src/shared/out.rs", "shared::out::errln"),
            ("src/shared/refusal.rs", "refusal::refused"),
        ]
    );
}

// What several files of a module share lives in a file of its own that
// they all import (`play/args.rs`, `bus/open.rs`, `record/space/paths.rs`),
// and the flags of several commands in `shared/flags.rs`: no child reaches
// back up into the file that declares it.
#[test]
fn the_cli_has_no_circle_of_files() {
    let root = repo("");
    let mut sources = BTreeMap::new();
    rust_files(&root, &root.join("src"), &mut sources);
    let graph = graph(&sources);
    assert!(
        graph.missing.is_empty(),
        "modules without a file: {:?}",
        graph.missing
    );
    // Every file is reached from a crate root (or is test code): the walk
    // sees the whole CLI.
    let unreached: Vec<&String> = sources
        .keys()
        .filter(|f| !graph.files.contains(*f) && !graph.test_only.contains(*f))
        .collect();
    assert!(
        unreached.is_empty(),
        "files no crate root reaches: {unreached:?}"
    );
    // The scan finds the code at all.
    let (files, edges) = (graph.files.len(), graph.edge_count());
    assert!(files > 40 && edges > 60, "{files} files, {edges} edges");
    let circles: Vec<String> = graph.circles().iter().map(|g| graph.describe(g)).collect();
    assert!(
        circles.is_empty(),
        "{} circles among the CLI's {files} files ({edges} edges):\n{}",
        circles.len(),
        circles.join("\n")
    );
}
