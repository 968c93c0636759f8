//! The one error type of configuration loading, and the source text it points into.

use std::fmt;
use std::path::{Path, PathBuf};

use super::files::{builtin_text, is_builtin_path};
use super::limits::{read_capped, MAX_FILE_BYTES, MAX_NESTING};
use super::locate::{locate_nearest, FieldPath, Part};
use super::nesting::too_deep;
use super::syntax::hint;
use super::terms::{round_long_numbers, user_terms};

/// Why a robot or motion file was refused.
///
/// Every refusal of a file's content names the file, the 1-based line and
/// column and the field (`buses[0].joints[2].min`), so that it prints as
/// `file:line:column: field: reason` — the form editors and terminals turn
/// into a link.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// The file could not be read. The operating system's reason is part of
    /// the message (said once, in plain words), not a separate source.
    #[error("{}: cannot read: {}", path.display(), io_reason(error))]
    Read {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        error: std::io::Error,
    },
    /// The file is larger than the limit for its kind (or never ends, as
    /// `/dev/zero`): it was not read past the limit.
    #[error(
        "{}: larger than {}, the limit for this kind of file; is it the right file?",
        path.display(),
        bytes_text(*limit)
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// The limit, bytes.
        limit: u64,
    },
    /// The file was read but its content is wrong.
    #[error("{}", InvalidDisplay::new(.file, .line, .column, .field, .reason))]
    Invalid {
        /// The file.
        file: PathBuf,
        /// 1-based line of the offending node.
        line: usize,
        /// 1-based column of the offending node.
        column: usize,
        /// Path of the field (`keyframes[3].pose.elbow_flex`); empty for the
        /// document as a whole.
        field: String,
        /// What is wrong and, where it helps, what would be right.
        reason: String,
    },
}

impl ConfigError {
    /// A content error at an explicit position. Long numbers in `reason`
    /// are rounded.
    pub fn invalid(
        file: impl Into<PathBuf>,
        line: usize,
        column: usize,
        field: impl Into<String>,
        reason: impl Into<String>,
    ) -> Self {
        ConfigError::Invalid {
            file: file.into(),
            line,
            column,
            field: field.into(),
            // However a value was formatted, a message never echoes a
            // 309-digit number.
            reason: round_long_numbers(&reason.into()),
        }
    }

    /// The file the error is about.
    pub fn file(&self) -> &Path {
        match self {
            ConfigError::Read { path, .. } | ConfigError::TooLarge { path, .. } => path,
            ConfigError::Invalid { file, .. } => file,
        }
    }

    /// Line and column (1-based), when the error is about content.
    pub fn position(&self) -> Option<(usize, usize)> {
        match self {
            ConfigError::Read { .. } | ConfigError::TooLarge { .. } => None,
            ConfigError::Invalid { line, column, .. } => Some((*line, *column)),
        }
    }

    /// The field path, when the error is about content.
    pub fn field(&self) -> Option<&str> {
        match self {
            ConfigError::Read { .. } | ConfigError::TooLarge { .. } => None,
            ConfigError::Invalid { field, .. } => Some(field),
        }
    }
}

/// A byte count as `1 MiB` when it is a whole number of MiB.
fn bytes_text(bytes: u64) -> String {
    const MIB: u64 = 1 << 20;
    if bytes >= MIB && bytes.is_multiple_of(MIB) {
        format!("{} MiB", bytes / MIB)
    } else {
        format!("{bytes} bytes")
    }
}

/// The operating system's reason in plain words, without the `(os error N)`
/// that `std::io::Error` appends.
fn io_reason(error: &std::io::Error) -> String {
    use std::io::ErrorKind;
    match error.kind() {
        ErrorKind::NotFound => "no such file".to_owned(),
        ErrorKind::PermissionDenied => "permission denied".to_owned(),
        ErrorKind::InvalidData => "not UTF-8 text".to_owned(),
        _ => {
            let text = error.to_string();
            match text.find(" (os error") {
                Some(i) => text[..i].to_owned(),
                None => text,
            }
        }
    }
}

struct InvalidDisplay<'a> {
    file: &'a Path,
    line: usize,
    column: usize,
    field: &'a str,
    reason: &'a str,
}

impl<'a> InvalidDisplay<'a> {
    fn new(file: &'a Path, line: &usize, column: &usize, field: &'a str, reason: &'a str) -> Self {
        InvalidDisplay {
            file,
            line: *line,
            column: *column,
            field,
            reason,
        }
    }
}

impl fmt::Display for InvalidDisplay<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}: ", self.file.display(), self.line, self.column)?;
        if !self.field.is_empty() {
            write!(f, "{}: ", self.field)?;
        }
        f.write_str(self.reason)
    }
}

/// A file's path and text, kept while loading so that errors found after
/// parsing can be located.
#[derive(Debug, Clone)]
pub struct Source {
    pub(crate) path: PathBuf,
    pub(crate) text: String,
}

impl Source {
    /// Reads `path`: a built-in file (see [`super::files`]) or one on disk
    /// of at most [`MAX_FILE_BYTES`].
    pub fn read(path: &Path) -> Result<Self, ConfigError> {
        Self::read_capped(path, MAX_FILE_BYTES)
    }

    /// Reads `path`, refusing it past `limit` bytes.
    pub(crate) fn read_capped(path: &Path, limit: u64) -> Result<Self, ConfigError> {
        let text = if is_builtin_path(path) {
            builtin_text(path)
                .map(str::to_owned)
                .ok_or_else(|| ConfigError::Read {
                    path: path.to_owned(),
                    error: std::io::ErrorKind::NotFound.into(),
                })?
        } else {
            let bytes = read_capped(path, limit)?;
            String::from_utf8(bytes).map_err(|_| ConfigError::Read {
                path: path.to_owned(),
                error: std::io::ErrorKind::InvalidData.into(),
            })?
        };
        Ok(Source {
            path: path.to_owned(),
            text,
        })
    }

    /// A text that is no file, called `name` in errors, of at most
    /// [`MAX_FILE_BYTES`] as a file would be.
    pub(crate) fn text(name: &Path, text: &str) -> Result<Self, ConfigError> {
        if text.len() as u64 > MAX_FILE_BYTES {
            return Err(ConfigError::TooLarge {
                path: name.to_owned(),
                limit: MAX_FILE_BYTES,
            });
        }
        Ok(Source {
            path: name.to_owned(),
            text: text.to_owned(),
        })
    }

    /// Deserializes the whole text, turning serde_yaml's error into ours.
    /// A text nested deeper than [`MAX_NESTING`] is refused before serde_yaml
    /// sees it.
    pub fn parse<T: serde::de::DeserializeOwned>(&self) -> Result<T, ConfigError> {
        if let Some((line, column)) = too_deep(&self.text, MAX_NESTING) {
            return Err(ConfigError::invalid(
                &self.path,
                line,
                column,
                "",
                format!(
                    "nested more than {MAX_NESTING} levels deep (mappings and lists inside \
                     each other), the limit for this kind of file"
                ),
            ));
        }
        serde_yaml::from_str(&self.text).map_err(|e| self.yaml_error(&e))
    }

    /// An error about the value at `path`.
    pub fn error(&self, path: &FieldPath, reason: impl Into<String>) -> ConfigError {
        self.error_at(path, Part::Value, reason)
    }

    /// An error about the key of the last segment of `path` (an unknown name).
    pub fn key_error(&self, path: &FieldPath, reason: impl Into<String>) -> ConfigError {
        self.error_at(path, Part::Key, reason)
    }

    fn error_at(&self, path: &FieldPath, part: Part, reason: impl Into<String>) -> ConfigError {
        let (line, column) = locate_nearest(&self.text, path, part);
        ConfigError::invalid(&self.path, line, column, path.to_string(), reason)
    }

    /// Line and column of the value at `path` (or its nearest ancestor).
    pub(crate) fn position(&self, path: &FieldPath) -> (usize, usize) {
        locate_nearest(&self.text, path, Part::Value)
    }

    /// serde_yaml prints `path: message at line L column C`; split that into
    /// our fields so every error prints the same way.
    fn yaml_error(&self, e: &serde_yaml::Error) -> ConfigError {
        let (mut line, mut column) = e.location().map_or((1, 1), |l| (l.line(), l.column()));
        let mut text = e.to_string();
        let suffix = format!(" at line {line} column {column}");
        if let Some(i) = text.find(&suffix) {
            text.replace_range(i..i + suffix.len(), "");
        }
        let (field, reason) = split_path(&text);
        let mut reason = user_terms(reason);
        // serde_yaml places a duplicate key at the start of its mapping:
        // point at the second one, and say where the first is.
        let duplicate = reason
            .strip_prefix("duplicate field `")
            .and_then(|rest| rest.split_once('`'))
            .and_then(|(key, _)| duplicate_key(&self.text, line, column, key));
        if let Some((first, second)) = duplicate {
            (line, column) = second;
            reason = format!("{reason} (first given at line {first})");
        }
        let reason = match hint(&self.text, line) {
            Some(h) => format!("{reason} ({h})"),
            None => reason,
        };
        ConfigError::invalid(&self.path, line, column, field, reason)
    }
}

/// The lines (1-based) where `key` is given first and second in the block
/// mapping that starts at `line`, `column`, and the second one's position:
/// the keys at the mapping's indentation, up to the first line indented
/// less. `None` for a flow mapping (`{a: 1, a: 2}`), or when the key is not
/// found twice.
fn duplicate_key(
    text: &str,
    line: usize,
    column: usize,
    key: &str,
) -> Option<(usize, (usize, usize))> {
    let indent = column.checked_sub(1)?;
    let mut first = None;
    for (n, l) in text.lines().enumerate().skip(line.checked_sub(1)?) {
        // The mapping's first key may follow a list item's `- `.
        let body = if n + 1 == line {
            l.get(indent..)?
        } else {
            let body = l.trim_start_matches(' ');
            if body.is_empty() || body.starts_with('#') {
                continue;
            }
            match (l.len() - body.len()).cmp(&indent) {
                std::cmp::Ordering::Less => break,
                std::cmp::Ordering::Greater => continue,
                std::cmp::Ordering::Equal => body,
            }
        };
        let is_key = body
            .strip_prefix(key)
            .is_some_and(|rest| rest.trim_start_matches(' ').starts_with(':'));
        if is_key {
            match first {
                None => first = Some(n + 1),
                Some(f) => return Some((f, (n + 1, column))),
            }
        }
    }
    None
}

/// serde's messages, which follow serde_yaml's field path and `: `.
const SERDE_MESSAGES: [&str; 8] = [
    "invalid type",
    "invalid value",
    "invalid length",
    "unknown field",
    "unknown variant",
    "missing field",
    "duplicate field",
    "data did not match",
];

/// serde_yaml's `path: message` as (path, message). The path is what comes
/// before the first `: ` that starts one of serde's messages (a key of the
/// path may hold spaces and colons); failing that, before the first `: `
/// when that part has no spaces (a visitor's own message).
fn split_path(text: &str) -> (String, &str) {
    let mut from = 0;
    while let Some(i) = text[from..].find(": ").map(|i| from + i) {
        let rest = &text[i + 2..];
        if SERDE_MESSAGES.iter().any(|m| rest.starts_with(m)) {
            return (text[..i].to_owned(), rest);
        }
        from = i + 2;
    }
    match text.split_once(": ") {
        Some((head, rest)) if !head.contains(' ') && !head.is_empty() => (head.to_owned(), rest),
        _ => (String::new(), text),
    }
}
