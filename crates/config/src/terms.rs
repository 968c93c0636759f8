//! serde's messages in the terms of the file, not of the Rust code.
//!
//! serde_yaml says what it expected in Rust's words: `expected f64`,
//! `expected u8`, `expected struct RawMotion`, `data did not match any
//! variant of untagged enum LatencySpec`, and it echoes a number as long
//! as it was written. The types of the files name themselves with
//! `#[serde(expecting = ...)]`; this pass turns what is left (primitive
//! types, and any type without such a name) into words, and rounds long
//! numbers.

use super::limits::Rounded;

/// Rust's names of primitive types, as serde says them, and what a file's
/// reader calls them.
const PRIMITIVES: [(&str, &str); 11] = [
    ("f64", "a number"),
    ("f32", "a number"),
    ("u8", "a whole number from 0 to 255"),
    ("u16", "a whole number from 0 to 65535"),
    ("u32", "a whole number from 0 to 4294967295"),
    ("u64", "a whole number from 0 up"),
    ("i8", "a whole number from -128 to 127"),
    ("i16", "a whole number from -32768 to 32767"),
    ("i32", "a whole number from -2147483648 to 2147483647"),
    ("i64", "a whole number"),
    ("path string", "a file path"),
];

/// Digits beyond which a number in a message is rounded.
const LONG_NUMBER: usize = 16;

/// `reason`, a serde message, in the file's terms.
pub(crate) fn user_terms(reason: &str) -> String {
    let mut text = reason.to_owned();
    for (rust, words) in PRIMITIVES {
        text = replace_word(
            &text,
            &format!("expected {rust}"),
            &format!("expected {words}"),
        );
    }
    if let Some(i) = text.find("data did not match any variant of untagged enum") {
        text.replace_range(i.., "not one of the forms this field takes");
    }
    for kind in ["struct ", "enum "] {
        while let Some(i) = text.find(&format!("expected {kind}")) {
            let start = i + "expected ".len();
            let end = start
                + kind.len()
                + text[start + kind.len()..]
                    .find(|c: char| !(c.is_alphanumeric() || c == '_'))
                    .unwrap_or(text.len() - start - kind.len());
            let words = if kind == "struct " {
                "a mapping of fields"
            } else {
                "one of the values this field takes"
            };
            text.replace_range(start..end, words);
        }
    }
    round_long_numbers(&text)
}

/// `text` with `from` replaced where it is followed by a word boundary
/// (`expected u8` but not `expected u80`).
fn replace_word(text: &str, from: &str, to: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(i) = rest.find(from) {
        let after = &rest[i + from.len()..];
        out.push_str(&rest[..i]);
        if after.starts_with(|c: char| c.is_alphanumeric() || c == '_') {
            out.push_str(from);
        } else {
            out.push_str(to);
        }
        rest = after;
    }
    out.push_str(rest);
    out
}

/// Every number of more than [`LONG_NUMBER`] characters written as
/// [`Rounded`] (`1000...0` of 309 digits as `1e308`).
pub(crate) fn round_long_numbers(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find(|c: char| c.is_ascii_digit()) {
        let len = rest[start..]
            .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | 'e' | 'E' | '+' | '-')))
            .unwrap_or(rest.len() - start);
        let number = &rest[start..start + len];
        out.push_str(&rest[..start]);
        match number.parse::<f64>() {
            Ok(v) if len > LONG_NUMBER => out.push_str(&Rounded(v).to_string()),
            _ => out.push_str(number),
        }
        rest = &rest[start + len..];
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::user_terms;

    #[test]
    fn rust_types_become_words() {
        assert_eq!(
            user_terms("invalid type: string \"fast\", expected u32"),
            "invalid type: string \"fast\", expected a whole number from 0 to 4294967295"
        );
        assert_eq!(
            user_terms("invalid type: sequence, expected f64"),
            "invalid type: sequence, expected a number"
        );
        assert_eq!(
            user_terms("invalid type: sequence, expected struct RawMotion"),
            "invalid type: sequence, expected a mapping of fields"
        );
        assert_eq!(
            user_terms("data did not match any variant of untagged enum LatencySpec"),
            "not one of the forms this field takes"
        );
        assert_eq!(
            user_terms("invalid type: map, expected enum Units"),
            "invalid type: map, expected one of the values this field takes"
        );
        assert_eq!(user_terms("expected u80 things"), "expected u80 things");
    }

    #[test]
    fn long_numbers_are_rounded_and_short_ones_kept() {
        let long = format!("invalid value: integer `1{}`, expected u8", "0".repeat(308));
        assert_eq!(
            user_terms(&long),
            "invalid value: integer `1e308`, expected a whole number from 0 to 255"
        );
        assert_eq!(
            user_terms("keyframes[12]: 300 is not 4294967295"),
            "keyframes[12]: 300 is not 4294967295"
        );
        assert_eq!(user_terms("got 0.30000000000000004 here"), "got 0.3 here");
    }
}
