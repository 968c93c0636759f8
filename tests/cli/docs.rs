//! Every command in the docs runs as written.
//!
//! Every fenced block of `README.md` and `docs/*.md` in `sh` (or `bash`,
//! `shell`) is split into its commands, which run in order, one shell per
//! block, in a scratch directory of the document's own (a block starts
//! where the one before ended, `cd` included). Each command must exit 0,
//! and the block must say so otherwise. While they run:
//!
//! - `servobus` is the binary under test, first on the `PATH`, and
//!   `cargo run --release --` is `servobus`;
//! - `/tmp` is the scratch directory's `tmp/` (`TMPDIR` too), so that no
//!   run meets a user's `/tmp/arm`, or another run's;
//! - stdin is not a terminal (as a script's), so the commands that ask a
//!   person (calibrate, teach) go by stillness, as `--yes` makes them.
//!
//! A block that is not shell but holds a command line (one starting with
//! `servobus `, `cargo ` or a `$ ` prompt) is refused: a command is written
//! as `sh`, and run or marked.
//!
//! # Marks
//!
//! A mark is an HTML comment on a line of its own, `<!-- docs-test: MARK
//! -->`, directly before a block's fence (blank lines and other marks may
//! come between); a block may have several. What needs a reason says it in
//! parentheses:
//!
//! - `skip (REASON)`: not run. Only what cannot run here: real servos, a
//!   command that waits for a person or installs, a network server, the
//!   test suite itself.
//! - `exit N`: the block's last command exits `N` (those before it 0).
//! - `writes FILE` (`writes FILE at N rows a second`): after the block,
//!   FILE is what its extension says (a PNG's magic bytes, a whole SVG,
//!   a CSV's header and rows, JSON or YAML that parses), and a CSV whose
//!   first column is the time in s has N rows a second.
//! - `background`: the block's one command runs in the background, as in
//!   a terminal of its own; the next block starts once its `--link`
//!   exists. At the document's end (and 3 s after it started, at least)
//!   it gets Ctrl-C and must exit 0; then its `writes` marks are checked.
//! - `ctrl-c after N s`: the block's one command still runs after N s,
//!   has printed something, and ends on Ctrl-C.
//! - `after N s`: the block starts N s after the document's first
//!   background block did (a simulator twin's scripted hand).
//! - `adds WORDS (REASON)`: WORDS are added to the block's last command
//!   (the flags of a simulator twin).
//! - `retry N on FAULT (REASON)`: a block that fails with `FAULT` in its
//!   output runs again, up to N times in all.
//!
//! Marks for the whole document, anywhere in it (at its top, by habit):
//!
//! - `ignored (REASON)`: the document runs in the ignored test (the gate
//!   runs it: `cargo test --test cli -- --ignored`), not by default.
//! - `port REAL is TWIN (REASON)`: in every command the port REAL (a real
//!   arm's) is TWIN (the simulator twin's).

mod markdown;
mod outputs;
mod runner;

use std::path::PathBuf;

use crate::common::{repo, scratch};
use markdown::{Block, Command, Mark};

/// `README.md` and every `docs/*.md`, in that order.
fn documents() -> Vec<markdown::Doc> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(repo("docs"))
        .expect("docs/")
        .map(|e| e.expect("an entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    paths.sort();
    paths.insert(0, repo("README.md"));
    paths.iter().map(|p| markdown::read(p)).collect()
}

/// Runs every document for which `ignored` says whether it is marked so.
fn run_documents(ignored: bool) {
    let docs: Vec<_> = documents()
        .into_iter()
        .filter(|d| d.marks.ignored.is_some() == ignored)
        .collect();
    assert!(!docs.is_empty(), "no document to run");
    for doc in &docs {
        let name = doc.path.file_stem().expect("a name").to_string_lossy();
        runner::Run::new(doc, scratch(&format!("docs-{name}"))).all();
    }
}

#[test]
fn every_shell_block_of_the_docs_is_run_or_marked_with_its_reason() {
    let docs = documents();
    let (mut run, mut skipped) = (0, 0);
    for doc in &docs {
        for block in &doc.blocks {
            let at = format!("{}:{}", doc.path.display(), block.line);
            if !block.is_shell() {
                let hidden = markdown::hidden_commands(block);
                assert!(
                    hidden.is_empty(),
                    "{at}: commands in a `{}` block: {hidden:?}",
                    block.lang
                );
                assert!(
                    block.marks.is_empty(),
                    "{at}: marks on a block that is not run"
                );
                continue;
            }
            let commands = markdown::commands(&block.text).unwrap_or_else(|e| panic!("{at}: {e}"));
            assert!(!commands.is_empty(), "{at}: an empty shell block");
            match block.skipped() {
                Some(_) => skipped += 1,
                None => run += 1,
            }
        }
    }
    assert!(run >= 10, "{run} blocks run, {skipped} skipped");
}

#[test]
fn the_readme_and_docs_run_as_written() {
    run_documents(false);
}

#[test]
#[ignore = "the first-arm walkthrough on its simulator twin, about 2 minutes of a scripted hand: `cargo test --test cli -- --ignored` (the gate runs it)"]
fn the_walkthroughs_run_as_written_on_their_simulator_twins() {
    run_documents(true);
}

#[test]
fn a_shell_block_splits_into_its_commands() {
    let text = "servobus plan arm-wave   # nothing moves\n\
                \n\
                servobus sim --robot so101 \\\n    --link /tmp/arm\n\
                python3 -c 'import json\nprint(1)  # kept: quoted\n' | servobus stream\n\
                echo \"a # b\" x#y\n";
    let commands = markdown::commands(text).expect("commands");
    let want = [
        (0, "servobus plan arm-wave"),
        (2, "servobus sim --robot so101 \\\n    --link /tmp/arm"),
        (
            4,
            "python3 -c 'import json\nprint(1)  # kept: quoted\n' | servobus stream",
        ),
        (7, "echo \"a # b\" x#y"),
    ];
    let got: Vec<(usize, &str)> = commands.iter().map(|c| (c.line, c.text.as_str())).collect();
    assert_eq!(got, want);
    assert!(markdown::commands("echo 'open").is_err());
    assert!(markdown::commands("cat <<EOF\nx\nEOF").is_err());
    assert_eq!(
        markdown::commands("a && cd b").expect("one"),
        [Command {
            line: 0,
            text: "a && cd b".into()
        }]
    );
}

#[test]
fn marks_are_read_from_the_comments_before_a_block() {
    let text = "# Title\n\
                <!-- docs-test: ignored (about 2 minutes) -->\n\
                <!-- docs-test: port /dev/ttyACM0 is /tmp/arm (the twin) -->\n\
                \n\
                <!-- docs-test: exit 1 -->\n\
                <!-- docs-test: writes truth.csv at 100 rows a second -->\n\
                \n\
                ```sh\nservobus doctor\n```\n\
                text\n\
                - item\n\n  ```json5\n  {a: 1}\n  ```\n\
                <!-- docs-test: skip (a real arm) -->\n```sh\nservobus play x\n```\n";
    let (doc, blocks) = markdown::parse(text).expect("parses");
    assert_eq!(doc.ignored.as_deref(), Some("about 2 minutes"));
    assert_eq!(
        doc.ports,
        [("/dev/ttyACM0".to_owned(), "/tmp/arm".to_owned())]
    );
    let want = [
        Block {
            line: 8,
            lang: "sh".into(),
            text: "servobus doctor".into(),
            marks: vec![
                Mark::Exit(1),
                Mark::Writes {
                    path: "truth.csv".into(),
                    rows_per_s: Some(100.0),
                },
            ],
        },
        Block {
            line: 14,
            lang: "json5".into(),
            text: "{a: 1}".into(),
            marks: vec![],
        },
        Block {
            line: 18,
            lang: "sh".into(),
            text: "servobus play x".into(),
            marks: vec![Mark::Skip("a real arm".into())],
        },
    ];
    assert_eq!(blocks, want);
    let refused = [
        "<!-- docs-test: skip -->\n```sh\nx\n```\n",
        "<!-- docs-test: skip () -->\n```sh\nx\n```\n",
        "<!-- docs-test: exit one -->\n```sh\nx\n```\n",
        "<!-- docs-test: frobnicate -->\n```sh\nx\n```\n",
        "<!-- docs-test: exit 1 -->\ntext between\n```sh\nx\n```\n",
        "<!-- docs-test: exit 1 -->\n",
        "```sh\nunclosed\n",
    ];
    for text in refused {
        assert!(markdown::parse(text).is_err(), "accepted {text:?}");
    }
}

#[test]
fn paths_are_replaced_as_whole_words_only() {
    let r = |t: &str| runner::replace_word(t, "/tmp", "/s/tmp");
    assert_eq!(r("cd /tmp && mkdir x"), "cd /s/tmp && mkdir x");
    assert_eq!(
        r("--link /tmp/arm --truth=/tmp/t.csv"),
        "--link /s/tmp/arm --truth=/s/tmp/t.csv"
    );
    assert_eq!(r("'/tmp' \"/tmp\""), "'/s/tmp' \"/s/tmp\"");
    assert_eq!(r("/var/tmp /tmpfs x/tmp"), "/var/tmp /tmpfs x/tmp");
}

#[test]
fn outputs_are_what_their_names_say() {
    let dir = scratch("docs-outputs");
    let write = |name: &str, bytes: &[u8]| {
        let path = dir.join(name);
        std::fs::write(&path, bytes).expect("writes");
        path
    };
    let svg_in_png = write("a.png", b"<svg xmlns=\"http://www.w3.org/2000/svg\"></svg>");
    assert!(outputs::check(&svg_in_png, None).is_err());
    let png = write("b.png", b"\x89PNG\r\n\x1a\n....");
    assert!(outputs::check(&png, None).is_ok());
    let svg = write(
        "c.svg",
        b"<svg xmlns=\"http://www.w3.org/2000/svg\">\n</svg>\n",
    );
    assert!(outputs::check(&svg, None).is_ok());
    let cut = write(
        "d.svg",
        b"<svg xmlns=\"http://www.w3.org/2000/svg\">\n<rect",
    );
    assert!(outputs::check(&cut, None).is_err());
    let rows = |step: f64| {
        let mut text = String::from("time_s,a\n");
        for i in 0..200 {
            text += &format!("{:.3},{i}\n", i as f64 * step);
        }
        text
    };
    let at_100 = write("e.csv", rows(0.01).as_bytes());
    assert!(outputs::check(&at_100, Some(100.0)).is_ok());
    assert!(outputs::check(&at_100, Some(50.0)).is_err());
    let ragged = write("f.csv", b"time_s,a\n0.0,1\n0.01\n");
    assert!(outputs::check(&ragged, None).is_err());
    assert!(outputs::check(&dir.join("missing.csv"), None).is_err());
    let list = write("g.yaml", b"- a\n- b\n");
    assert!(outputs::check(&list, None).is_err());
}

/// What `Run::all` panicked with on the page `text`, or `None` when it
/// passed.
fn run_page(name: &str, text: &str) -> Option<String> {
    let dir = scratch("docs-pages");
    let path = dir.join(format!("{name}.md"));
    std::fs::write(&path, text).expect("writes the page");
    let doc = markdown::read(&path);
    let run = || runner::Run::new(&doc, dir.join(name)).all();
    let failed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(run)).err()?;
    let said = failed.downcast_ref::<String>().cloned();
    Some(said.unwrap_or_else(|| "a panic without a message".into()))
}

#[test]
fn a_block_that_does_not_do_what_its_page_says_fails() {
    // A frame cut short: decode finds a problem and exits 1.
    let cut = "```sh\nservobus list\nservobus decode FF FF 01\nservobus list\n```\n";
    let said = run_page("cut", cut).expect("the run fails");
    assert!(
        said.contains("cut.md:3: `servobus decode FF FF 01` gave exit 1"),
        "{said}"
    );
    let marked = format!(
        "<!-- docs-test: exit 1 -->\n{}",
        cut.replacen("\nservobus list\n```", "\n```", 1)
    );
    assert_eq!(run_page("marked", &marked), None);
    let svg =
        "<!-- docs-test: writes plan.svg -->\n```sh\nservobus plan arm-wave --plot plan.svg\n```\n";
    assert_eq!(run_page("svg", svg), None);
    let missing = "<!-- docs-test: writes none.svg -->\n```sh\nservobus list\n```\n";
    let said = run_page("missing", missing).expect("no such file");
    assert!(said.contains("none.svg: not written"), "{said}");
    let early = "<!-- docs-test: ctrl-c after 5 s -->\n```sh\nservobus list\n```\n";
    let said = run_page("early", early).expect("it ended at once");
    assert!(said.contains("ended before Ctrl-C"), "{said}");
    // `cd` carries over to the next block; `/tmp` is the run's own.
    let cd = "```sh\nmkdir -p /tmp/here && cd /tmp/here\n```\n\
              <!-- docs-test: writes /tmp/here/robot.yaml -->\n```sh\nservobus init\n```\n";
    assert_eq!(run_page("cd", cd), None);
}
