//! Runs a document's shell blocks in order, in a scratch directory, with
//! `servobus` the binary under test; checks each command's exit status and
//! the outcomes the marks state.

use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

use super::markdown::{self, Block, Doc, Mark};
use crate::common::BIN;

/// The longest one block may take (the twin's calibration waits some
/// 70 s for the hand; a loaded machine is slow).
const BLOCK_LIMIT: Duration = Duration::from_secs(300);
/// How long a background command may take to come up, or to stop on Ctrl-C.
const PATIENCE: Duration = Duration::from_secs(60);
/// A background command runs at least this long (a stated rate needs rows).
const BACKGROUND_AT_LEAST: Duration = Duration::from_secs(3);

/// `text` in single quotes for the shell.
fn quoted(text: &str) -> String {
    format!("'{}'", text.replace('\'', r"'\''"))
}

/// `text` with each whole word `from` (a path: bounded by the start, a
/// space, `=` or a quote before, and by the end, `/`, a space, `;`, `&`,
/// `)` or a quote after) replaced by `to`.
pub fn replace_word(text: &str, from: &str, to: &str) -> String {
    let mut out = String::new();
    let mut done = 0;
    for (at, _) in text.match_indices(from) {
        let before = text[..at].chars().last();
        let after = text[at + from.len()..].chars().next();
        let starts = before.is_none_or(|c| c.is_whitespace() || "='\"".contains(c));
        let ends = after.is_none_or(|c| c.is_whitespace() || "/;&)'\"".contains(c));
        if starts && ends {
            out.push_str(&text[done..at]);
            out.push_str(to);
            done = at + from.len();
        }
    }
    out.push_str(&text[done..]);
    out
}

/// A block that failed: why, the end of what it printed, and whether its
/// output reports a `FAULT`.
struct Failed {
    why: String,
    printed: String,
    fault: bool,
}

impl Failed {
    fn new(why: String, out: &Path, err: &Path) -> Failed {
        let said = |p: &Path| std::fs::read_to_string(p).unwrap_or_default();
        let fault = said(out).contains("FAULT") || said(err).contains("FAULT");
        Failed {
            why,
            printed: Run::printed(out, err),
            fault,
        }
    }
}

/// A command started in the background, stopped when the document ends.
struct Background {
    child: Child,
    started: Instant,
    dir: PathBuf,
    block: Block,
    command: String,
}

/// One document's run: its scratch directory, where the last block ended,
/// and what still runs.
pub struct Run<'a> {
    doc: &'a Doc,
    name: String,
    scratch: PathBuf,
    tmp: PathBuf,
    path_var: std::ffi::OsString,
    cwd: PathBuf,
    background: Vec<Background>,
    first_background: Option<Instant>,
    /// Process groups a block left running (`cmd &`), killed at the end.
    leftovers: Vec<i32>,
    runs: usize,
}

impl Drop for Run<'_> {
    fn drop(&mut self) {
        let groups = self.background.iter().map(|b| b.child.id() as i32);
        for group in groups.chain(self.leftovers.iter().copied()) {
            // SAFETY: kill(2) on a process group this run started.
            unsafe { libc::kill(-group, libc::SIGKILL) };
        }
        for b in &mut self.background {
            let _ = b.child.wait();
        }
    }
}

/// Waits for `child` until `limit`; `None` when it still runs.
fn wait_for(child: &mut Child, limit: Duration) -> Option<ExitStatus> {
    let until = Instant::now() + limit;
    loop {
        if let Some(status) = child.try_wait().expect("wait") {
            return Some(status);
        }
        if Instant::now() >= until {
            return None;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// The last `n` lines of the file at `path`.
fn tail(path: &Path, n: usize) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let lines: Vec<&str> = text.lines().collect();
    lines[lines.len().saturating_sub(n)..].join("\n")
}

impl<'a> Run<'a> {
    /// A run of `doc` in the scratch directory `scratch` (emptied first).
    pub fn new(doc: &'a Doc, scratch: PathBuf) -> Run<'a> {
        let _ = std::fs::remove_dir_all(&scratch);
        let (tmp, bin) = (scratch.join("tmp"), scratch.join(".bin"));
        for dir in [&tmp, &bin, &scratch.join(".out")] {
            std::fs::create_dir_all(dir).expect("scratch");
        }
        // `servobus` on the PATH is the binary under test.
        std::os::unix::fs::symlink(BIN, bin.join("servobus")).expect("a link to servobus");
        let mut path_var = bin.into_os_string();
        path_var.push(":");
        path_var.push(std::env::var_os("PATH").unwrap_or_default());
        let name = doc
            .path
            .file_name()
            .expect("a name")
            .to_string_lossy()
            .into_owned();
        Run {
            doc,
            name,
            cwd: scratch.clone(),
            scratch,
            tmp,
            path_var,
            background: Vec::new(),
            first_background: None,
            leftovers: Vec::new(),
            runs: 0,
        }
    }

    /// `command` as it runs here: `cargo run --release --` is `servobus`,
    /// a real port its twin's, `/tmp` the scratch directory's.
    pub fn as_run(&self, command: &str) -> String {
        let mut text = command.replace("cargo run --release --", "servobus");
        for (real, twin) in &self.doc.marks.ports {
            text = replace_word(&text, real, twin);
        }
        replace_word(&text, "/tmp", self.tmp.to_str().expect("a UTF-8 path"))
    }

    /// Where the doc is, for messages: `README.md:16`.
    fn at(&self, block: &Block, line: usize) -> String {
        format!("{}:{}", self.name, block.line + 1 + line)
    }

    /// Starts `script` in `dir`, in a process group of its own, its output
    /// in files `.out/<n>.out` and `.err`.
    fn spawn(&mut self, script: &str, dir: &Path) -> (Child, PathBuf, PathBuf) {
        self.runs += 1;
        let out = self.scratch.join(format!(".out/{}.out", self.runs));
        let err = self.scratch.join(format!(".out/{}.err", self.runs));
        let child = Command::new("bash")
            .args(["-c", script])
            .current_dir(dir)
            .env("PATH", &self.path_var)
            .env("TMPDIR", &self.tmp)
            .stdin(Stdio::null())
            .stdout(std::fs::File::create(&out).expect("an output file"))
            .stderr(std::fs::File::create(&err).expect("an output file"))
            .process_group(0)
            .spawn()
            .expect("bash runs");
        (child, out, err)
    }

    /// What a block printed, for a failure's message.
    fn printed(out: &Path, err: &Path) -> String {
        format!(
            "--- stdout (end)\n{}\n--- stderr (end)\n{}",
            tail(out, 40),
            tail(err, 40)
        )
    }

    /// Runs every block in order, then stops what runs in the background.
    pub fn all(mut self) {
        for block in &self.doc.blocks {
            if !block.is_shell() {
                continue;
            }
            if let Some(why) = block.skipped() {
                eprintln!("{}: skipped ({why})", self.at(block, 0));
                continue;
            }
            let started = Instant::now();
            self.block(block);
            eprintln!(
                "{}: ran in {:.1} s",
                self.at(block, 0),
                started.elapsed().as_secs_f64()
            );
        }
        self.stop_background();
    }

    /// The commands of `block`, as they run here, with its `adds` words.
    fn commands(&self, block: &Block) -> Vec<(usize, String)> {
        let commands = markdown::commands(&block.text)
            .unwrap_or_else(|e| panic!("{}: {e}", self.at(block, 0)));
        let mut commands: Vec<(usize, String)> = commands
            .into_iter()
            .map(|c| (c.line, self.as_run(&c.text)))
            .collect();
        for mark in &block.marks {
            if let Mark::Adds { words, .. } = mark {
                let last = commands.last_mut().expect("a command to add to");
                last.1 = format!("{} {words}", last.1);
            }
        }
        assert!(
            !commands.is_empty(),
            "{}: a shell block with no command",
            self.at(block, 0)
        );
        commands
    }

    fn block(&mut self, block: &Block) {
        for mark in &block.marks {
            if let Mark::After(wait) = mark {
                let first = self.first_background.unwrap_or_else(|| {
                    panic!(
                        "{}: `after` with nothing in the background",
                        self.at(block, 0)
                    )
                });
                std::thread::sleep((first + *wait).saturating_duration_since(Instant::now()));
            }
        }
        let commands = self.commands(block);
        let one = || {
            assert_eq!(commands.len(), 1, "{}: one command only", self.at(block, 0));
            commands[0].1.clone()
        };
        if block.marks.contains(&Mark::Background) {
            let command = one();
            return self.background(block, command);
        }
        if let Some(after) = block.marks.iter().find_map(|m| match m {
            Mark::CtrlCAfter(after) => Some(*after),
            _ => None,
        }) {
            let command = one();
            return self.ctrl_c(block, &command, after);
        }
        let tries = block.marks.iter().find_map(|m| match m {
            Mark::Retry { times, .. } => Some(*times),
            _ => None,
        });
        let tries = tries.unwrap_or(1);
        for attempt in 1..=tries {
            match self.commands_run(block, &commands) {
                Ok(()) => break,
                Err(failed) if attempt < tries && failed.fault => {
                    eprintln!(
                        "{}: with a FAULT, run again ({attempt} of {tries})",
                        failed.why
                    );
                }
                Err(failed) => panic!("{}\n{}", failed.why, failed.printed),
            }
        }
        let dir = self.cwd.clone();
        self.check_writes(block, &dir);
    }

    /// Runs the commands of `block` in one shell, each one's status kept;
    /// the failing command and what the block printed on failure.
    fn commands_run(&mut self, block: &Block, commands: &[(usize, String)]) -> Result<(), Failed> {
        let exit = block.marks.iter().find_map(|m| match m {
            Mark::Exit(code) => Some(*code),
            _ => None,
        });
        let status_file = self.scratch.join(format!(".out/{}.status", self.runs + 1));
        let cwd_file = self.scratch.join(format!(".out/{}.cwd", self.runs + 1));
        let mut script = String::from("set -o pipefail\n");
        for (i, (_, command)) in commands.iter().enumerate() {
            let want = if i + 1 == commands.len() {
                exit.unwrap_or(0)
            } else {
                0
            };
            script += &format!(
                "{command}\n__s=$?; echo \"$__s\" >> {}; [ \"$__s\" -eq {want} ] || exit 97\n",
                quoted(status_file.to_str().expect("UTF-8"))
            );
        }
        script += &format!("pwd > {}\n", quoted(cwd_file.to_str().expect("UTF-8")));
        let dir = self.cwd.clone();
        let (mut child, out, err) = self.spawn(&script, &dir);
        let group = child.id() as i32;
        let Some(_) = wait_for(&mut child, BLOCK_LIMIT) else {
            // SAFETY: kill(2) on the process group just started.
            unsafe { libc::kill(-group, libc::SIGKILL) };
            let _ = child.wait();
            let why = format!("{}: still running after {BLOCK_LIMIT:?}", self.at(block, 0));
            return Err(Failed::new(why, &out, &err));
        };
        // A command left in the background (`cmd &`): stopped at the end.
        // SAFETY: signal 0 only asks whether the group still exists.
        if unsafe { libc::kill(-group, 0) } == 0 {
            self.leftovers.push(group);
        }
        let statuses = std::fs::read_to_string(&status_file).unwrap_or_default();
        let statuses: Vec<i32> = statuses
            .lines()
            .map(|s| s.parse().expect("a status"))
            .collect();
        if statuses.len() == commands.len() && statuses.last().copied() == Some(exit.unwrap_or(0)) {
            let text = std::fs::read_to_string(&cwd_file).expect("the block's last directory");
            self.cwd = PathBuf::from(text.trim_end());
            return Ok(());
        }
        let i = statuses.len().saturating_sub(1).min(commands.len() - 1);
        let want = if i + 1 == commands.len() {
            exit.unwrap_or(0)
        } else {
            0
        };
        let got = statuses
            .get(i)
            .map_or("no status".into(), |s| format!("exit {s}"));
        let why = format!(
            "{}: `{}` gave {got}; the doc says it exits {want}",
            self.at(block, commands[i].0),
            commands[i].1
        );
        Err(Failed::new(why, &out, &err))
    }

    /// Starts a background block and waits until it serves (its `--link`
    /// exists, or it printed something).
    fn background(&mut self, block: &Block, command: String) {
        let dir = self.cwd.clone();
        let (mut child, out, err) = self.spawn(&format!("exec {command}"), &dir);
        let started = Instant::now();
        self.first_background.get_or_insert(started);
        let words: Vec<&str> = command.split_whitespace().collect();
        let link = words
            .windows(2)
            .find(|w| w[0] == "--link")
            .map(|w| dir.join(w[1]));
        let up = || match &link {
            Some(link) => std::fs::symlink_metadata(link).is_ok(),
            None => std::fs::metadata(&out).is_ok_and(|m| m.len() > 0),
        };
        while !up() {
            if let Some(status) = child.try_wait().expect("wait") {
                let printed = Self::printed(&out, &err);
                panic!(
                    "{}: `{command}` ended at once ({status})\n{printed}",
                    self.at(block, 0)
                );
            }
            assert!(
                started.elapsed() < PATIENCE,
                "{}: `{command}` did not come up in {PATIENCE:?}\n{}",
                self.at(block, 0),
                Self::printed(&out, &err)
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        self.background.push(Background {
            child,
            started,
            dir,
            block: block.clone(),
            command,
        });
    }

    /// Ctrl-C for every background block, each of which must exit 0; then
    /// what they write is checked.
    fn stop_background(&mut self) {
        let mut stopped = Vec::new();
        for mut b in std::mem::take(&mut self.background) {
            std::thread::sleep(BACKGROUND_AT_LEAST.saturating_sub(b.started.elapsed()));
            // SAFETY: kill(2) on the process group of a command this run started.
            unsafe { libc::kill(-(b.child.id() as i32), libc::SIGINT) };
            let status = wait_for(&mut b.child, PATIENCE);
            let at = self.at(&b.block, 0);
            let out = self.scratch.join(".out");
            if status.is_none() {
                // SAFETY: as above; it did not stop on Ctrl-C.
                unsafe { libc::kill(-(b.child.id() as i32), libc::SIGKILL) };
            }
            let _ = b.child.wait();
            assert!(
                status.is_some_and(|s| s.success()),
                "{at}: `{}` on Ctrl-C: {status:?} (want exit 0); its output is in {out:?}",
                b.command
            );
            stopped.push(b);
        }
        for b in stopped {
            self.check_writes(&b.block, &b.dir);
        }
    }

    /// Runs the one command of `block` for `after`, then Ctrl-C: it must
    /// have been running, printed something, and end (0 or by the signal).
    fn ctrl_c(&mut self, block: &Block, command: &str, after: Duration) {
        let dir = self.cwd.clone();
        let (mut child, out, err) = self.spawn(&format!("exec {command}"), &dir);
        if let Some(status) = wait_for(&mut child, after) {
            let printed = Self::printed(&out, &err);
            panic!(
                "{}: `{command}` ended before Ctrl-C ({status})\n{printed}",
                self.at(block, 0)
            );
        }
        // SAFETY: kill(2) on the process group just started.
        unsafe { libc::kill(-(child.id() as i32), libc::SIGINT) };
        let status = wait_for(&mut child, PATIENCE);
        if status.is_none() {
            // SAFETY: as above; it did not stop on Ctrl-C.
            unsafe { libc::kill(-(child.id() as i32), libc::SIGKILL) };
            let _ = child.wait();
        }
        let ended = status.is_some_and(|s| s.success() || s.signal() == Some(libc::SIGINT));
        let printed = Self::printed(&out, &err);
        assert!(
            ended,
            "{}: `{command}` on Ctrl-C: {status:?}\n{printed}",
            self.at(block, 0)
        );
        let said = std::fs::metadata(&out).map_or(0, |m| m.len());
        assert!(
            said > 0,
            "{}: `{command}` printed nothing\n{printed}",
            self.at(block, 0)
        );
    }

    /// The `writes` marks of `block`, relative to `dir`.
    fn check_writes(&self, block: &Block, dir: &Path) {
        for mark in &block.marks {
            if let Mark::Writes { path, rows_per_s } = mark {
                let file = dir.join(self.as_run(path));
                super::outputs::check(&file, *rows_per_s)
                    .unwrap_or_else(|e| panic!("{}: {path}: {e}", self.at(block, 0)));
            }
        }
    }
}
