//! The fenced blocks of a Markdown document, the `docs-test` marks that
//! come before them, and a shell block split into its commands.

use std::path::{Path, PathBuf};
use std::time::Duration;

/// The languages whose blocks are shell commands, run by the test.
const SHELL: [&str; 3] = ["sh", "bash", "shell"];

/// What a mark before a block says.
#[derive(Debug, Clone, PartialEq)]
pub enum Mark {
    /// Not run, for the reason given.
    Skip(String),
    /// The block's last command exits with this status (the others 0).
    Exit(i32),
    /// After the block this file (relative to where the block ended; for
    /// a background block, where it started) is what its extension says,
    /// with this many rows a second when given (a CSV whose first column
    /// is the time in s).
    Writes {
        path: String,
        rows_per_s: Option<f64>,
    },
    /// The one command runs in the background (as in a terminal of its
    /// own) until the document ends; then Ctrl-C, and it exits 0.
    Background,
    /// The one command runs this long, still running, then gets Ctrl-C.
    CtrlCAfter(Duration),
    /// The block starts this long after the document's first background
    /// block started (a simulator twin's clock).
    After(Duration),
    /// These words are added to the block's last command, for the reason
    /// given (a twin's flags).
    Adds { words: String, why: String },
    /// The block runs again, up to this many times in all, while it fails
    /// with `FAULT` in its output, for the reason given.
    Retry { times: u32, why: String },
}

/// What a mark at the top of a document says.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DocMarks {
    /// The document runs in the ignored (gate) test, for this reason.
    pub ignored: Option<String>,
    /// Every command's word `.0` is `.1` (a real port and its twin's).
    pub ports: Vec<(String, String)>,
}

/// A fenced block.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// Line of its opening fence, from 1.
    pub line: usize,
    /// Its language, as the fence gives it (may be empty).
    pub lang: String,
    /// Its content, without the fence's indentation.
    pub text: String,
    /// The marks just before it.
    pub marks: Vec<Mark>,
}

impl Block {
    /// Whether it holds shell commands.
    pub fn is_shell(&self) -> bool {
        SHELL.contains(&self.lang.as_str())
    }

    /// Why it is not run, if it is marked so.
    pub fn skipped(&self) -> Option<&str> {
        self.marks.iter().find_map(|m| match m {
            Mark::Skip(why) => Some(why.as_str()),
            _ => None,
        })
    }
}

/// A document: its marks and blocks.
#[derive(Debug)]
pub struct Doc {
    pub path: PathBuf,
    pub marks: DocMarks,
    pub blocks: Vec<Block>,
}

/// The text of a mark, when `line` is one: `<!-- docs-test: TEXT -->`.
fn mark_text(line: &str) -> Option<&str> {
    let rest = line.trim().strip_prefix("<!--")?.trim_start();
    let rest = rest.strip_prefix("docs-test:")?;
    Some(rest.strip_suffix("-->")?.trim())
}

/// `(REASON)`, non-empty, or an error naming what is wanted.
fn reason(text: &str, what: &str) -> Result<String, String> {
    let why = text
        .trim()
        .strip_prefix('(')
        .and_then(|t| t.strip_suffix(')'));
    match why.map(str::trim) {
        Some(why) if !why.is_empty() => Ok(why.to_owned()),
        _ => Err(format!("`{what}` needs its reason in parentheses")),
    }
}

/// `N s` as a duration.
fn seconds(text: &str) -> Result<Duration, String> {
    let n = text.trim().strip_suffix(" s").map(str::trim);
    n.and_then(|n| n.parse::<f64>().ok())
        .filter(|n| n.is_finite() && *n >= 0.0)
        .map(Duration::from_secs_f64)
        .ok_or_else(|| format!("`{text}`: seconds as `N s`"))
}

/// One mark: a block's (`Ok(Ok(mark))`) or the document's (`Ok(Err(()))`,
/// applied to `doc`).
fn parse_mark(text: &str, doc: &mut DocMarks) -> Result<Option<Mark>, String> {
    let (word, rest) = text.split_once(' ').unwrap_or((text, ""));
    let mark = match word {
        "skip" => Mark::Skip(reason(rest, "skip")?),
        "exit" => Mark::Exit(
            rest.trim()
                .parse()
                .map_err(|_| format!("`{text}`: exit N"))?,
        ),
        "writes" => {
            let (path, rate) = match rest.split_once(" at ") {
                Some((path, rate)) => {
                    let n = rate.strip_suffix(" rows a second");
                    let n = n.and_then(|n| n.trim().parse::<f64>().ok());
                    let n = n.ok_or_else(|| format!("`{text}`: `at N rows a second`"))?;
                    (path, Some(n))
                }
                None => (rest, None),
            };
            let path = path.trim().to_owned();
            if path.is_empty() || path.contains(' ') {
                return Err(format!("`{text}`: one path"));
            }
            Mark::Writes {
                path,
                rows_per_s: rate,
            }
        }
        "background" if rest.is_empty() => Mark::Background,
        "ctrl-c" => {
            let after = rest.strip_prefix("after ");
            let after = after.ok_or_else(|| format!("`{text}`: ctrl-c after N s"))?;
            Mark::CtrlCAfter(seconds(after.split_once(" (").map_or(after, |(n, _)| n))?)
        }
        // A reason may follow: `after 96 s (the hand lets go at 94 s)`.
        "after" => Mark::After(seconds(rest.split_once(" (").map_or(rest, |(n, _)| n))?),
        "adds" => {
            let (words, why) = rest
                .split_once(" (")
                .ok_or_else(|| format!("`{text}`: a reason"))?;
            let why = reason(&format!("({why}"), "adds")?;
            Mark::Adds {
                words: words.trim().to_owned(),
                why,
            }
        }
        "retry" => {
            let (times, why) = rest
                .split_once(" on FAULT ")
                .ok_or_else(|| format!("`{text}`: retry N on FAULT (reason)"))?;
            let times = times
                .trim()
                .parse()
                .map_err(|_| format!("`{text}`: a count"))?;
            Mark::Retry {
                times,
                why: reason(why, "retry")?,
            }
        }
        "ignored" => {
            doc.ignored = Some(reason(rest, "ignored")?);
            return Ok(None);
        }
        "port" => {
            let (ports, why) = rest
                .split_once(" (")
                .ok_or_else(|| format!("`{text}`: a reason"))?;
            reason(&format!("({why}"), "port")?;
            let (real, twin) = ports
                .split_once(" is ")
                .ok_or_else(|| format!("`{text}`: port REAL is TWIN (reason)"))?;
            doc.ports
                .push((real.trim().to_owned(), twin.trim().to_owned()));
            return Ok(None);
        }
        _ => return Err(format!("unknown mark `{text}`")),
    };
    Ok(Some(mark))
}

/// The blocks and marks of Markdown `text`; an error names its line.
pub fn parse(text: &str) -> Result<(DocMarks, Vec<Block>), String> {
    let mut doc = DocMarks::default();
    let mut blocks = Vec::new();
    // Block marks waiting for their fence: (line, mark).
    let mut pending: Vec<(usize, Mark)> = Vec::new();
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    while let Some((n, line)) = lines.next() {
        if let Some(mark) = mark_text(line) {
            if let Some(mark) = parse_mark(mark, &mut doc).map_err(|e| format!("line {n}: {e}"))? {
                pending.push((n, mark));
            }
            continue;
        }
        let indent = line.len() - line.trim_start().len();
        let Some(lang) = line.trim_start().strip_prefix("```") else {
            if let Some((at, _)) = pending.first().filter(|_| !line.trim().is_empty()) {
                return Err(format!(
                    "line {at}: a mark not directly before a fenced block"
                ));
            }
            continue;
        };
        let mut content = Vec::new();
        loop {
            let (_, inner) = lines
                .next()
                .ok_or_else(|| format!("line {n}: unclosed fence"))?;
            if inner.trim() == "```" {
                break;
            }
            let cut = inner.len() - inner.trim_start().len();
            content.push(&inner[cut.min(indent)..]);
        }
        blocks.push(Block {
            line: n,
            lang: lang.trim().to_owned(),
            text: content.join("\n"),
            marks: pending.drain(..).map(|(_, m)| m).collect(),
        });
    }
    if let Some((at, _)) = pending.first() {
        return Err(format!("line {at}: a mark with no block after it"));
    }
    Ok((doc, blocks))
}

/// Reads and parses the document at `path`.
pub fn read(path: &Path) -> Doc {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let (marks, blocks) = parse(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    Doc {
        path: path.to_owned(),
        marks,
        blocks,
    }
}

/// A command of a shell block: its first line in the block (from 0) and
/// its text, comments left out, continuation lines kept.
#[derive(Debug, Clone, PartialEq)]
pub struct Command {
    pub line: usize,
    pub text: String,
}

/// The commands of shell `text`: one per line, but for a line that ends in
/// `\` or inside quotes; `#` outside quotes at a word's start comments out
/// the rest of the line. Here-documents are not supported.
pub fn commands(text: &str) -> Result<Vec<Command>, String> {
    #[derive(PartialEq)]
    enum In {
        Words,
        Single,
        Double,
        Comment,
    }
    let mut state = In::Words;
    let (mut out, mut current, mut start, mut line) = (Vec::new(), String::new(), 0, 0);
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match (&state, c) {
            (In::Comment, '\n') => state = In::Words,
            (In::Comment, _) => continue,
            (In::Words, '#') if current.is_empty() || current.ends_with([' ', '\t', '\n']) => {
                state = In::Comment;
                continue;
            }
            (In::Words, '\'') => state = In::Single,
            (In::Single, '\'') => state = In::Words,
            (In::Words, '"') => state = In::Double,
            (In::Double, '"') => state = In::Words,
            (In::Words | In::Double, '\\') => {
                current.push(c);
                if let Some(next) = chars.next() {
                    line += usize::from(next == '\n');
                    current.push(next);
                }
                continue;
            }
            _ => {}
        }
        if c == '\n' && state != In::Single && state != In::Double {
            line += 1;
            if !current.trim().is_empty() {
                out.push(Command {
                    line: start,
                    text: current.trim_end().to_owned(),
                });
            }
            current.clear();
            start = line;
            continue;
        }
        if c == '<' && chars.peek() == Some(&'<') && state == In::Words {
            return Err(format!("line {line}: here-documents are not supported"));
        }
        line += usize::from(c == '\n');
        if current.trim().is_empty() && c.is_whitespace() {
            current.clear();
            start = line;
            continue;
        }
        current.push(c);
    }
    if state == In::Single || state == In::Double {
        return Err("an unclosed quote".to_owned());
    }
    if !current.trim().is_empty() {
        out.push(Command {
            line: start,
            text: current.trim_end().to_owned(),
        });
    }
    Ok(out)
}

/// The lines of a block that is not shell but holds commands: a line that
/// starts with a prompt, `servobus ` or `cargo `.
pub fn hidden_commands(block: &Block) -> Vec<&str> {
    let starts = ["$ ", "servobus ", "cargo "];
    let lines = block.text.lines().map(str::trim_start);
    lines
        .filter(|l| starts.iter().any(|s| l.starts_with(s)))
        .collect()
}
