//! Plain hints for the YAML mistakes people make most: a tab in the
//! indentation, a `{` or `[` that is never closed, and `key:value` without a
//! space after the colon.
//!
//! serde_yaml reports these with messages about tokens and types (`found
//! character that cannot start any token`, `invalid type: string "10 -
//! pose", expected f64`) at a position that is often after the mistake. The
//! text is scanned from the reported line back to the top for the nearest
//! line that shows one of the three mistakes; the hint names that line.

/// A hint for a syntax or type error reported at 1-based `error_line`, or
/// `None` when no common mistake is seen.
pub(crate) fn hint(text: &str, error_line: usize) -> Option<String> {
    let lines: Vec<&str> = text.lines().collect();
    let last = error_line.min(lines.len());
    let open = unclosed_bracket(&lines[..last]);
    for n in (1..=last).rev() {
        let line = lines[n - 1];
        if indent(line).contains('\t') {
            return Some(format!(
                "line {n} is indented with a tab: YAML needs spaces for indentation"
            ));
        }
        if let Some((at, bracket)) = open {
            if at == n {
                let close = if bracket == '{' { '}' } else { ']' };
                return Some(format!(
                    "the `{bracket}` on line {n} is never closed: end it with `{close}` on the same line"
                ));
            }
        }
        if let Some(key) = key_without_space(line) {
            return Some(format!(
                "line {n}: put a space after the colon of `{key}:` (`{key}: value`)"
            ));
        }
    }
    None
}

/// The leading whitespace of a line.
fn indent(line: &str) -> &str {
    let body = line.trim_start_matches([' ', '\t']);
    &line[..line.len() - body.len()]
}

/// The line (1-based) and bracket of the last `{` or `[` still open at the
/// end of `lines`, ignoring quoted text and comments.
fn unclosed_bracket(lines: &[&str]) -> Option<(usize, char)> {
    let mut stack: Vec<(usize, char)> = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let mut quote: Option<char> = None;
        let mut prev = ' ';
        for c in line.chars() {
            match quote {
                Some(q) if c == q => quote = None,
                Some(_) => {}
                None => match c {
                    '"' | '\'' => quote = Some(c),
                    '#' if prev == ' ' || prev == '\t' => break,
                    '{' | '[' => stack.push((i + 1, c)),
                    '}' | ']' => {
                        stack.pop();
                    }
                    _ => {}
                },
            }
            prev = c;
        }
    }
    stack.last().copied()
}

/// The key of a `key:value` line (a plain key, a colon, then no space).
fn key_without_space(line: &str) -> Option<&str> {
    let body = line.trim_start();
    let body = body.strip_prefix("- ").unwrap_or(body).trim_start();
    let colon = body.find(':')?;
    let (key, rest) = (&body[..colon], &body[colon + 1..]);
    let plain_key = !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    let next = rest.chars().next()?;
    // `http://`, `C:\` and `12:30` are values, not keys missing a space.
    let value_like = next.is_whitespace() || next == '/' || next == '\\' || next == ':';
    (plain_key && !value_like && !key.chars().all(|c| c.is_ascii_digit())).then_some(key)
}

#[cfg(test)]
mod tests {
    use super::hint;

    #[test]
    fn a_tab_in_the_indentation_is_named() {
        let text = "a: 1\nkeyframes:\n\t- pose: x\n";
        let h = hint(text, 3).expect("hint");
        assert!(h.contains("line 3") && h.contains("tab"), "{h}");
    }

    #[test]
    fn an_unclosed_brace_is_named_even_when_reported_later() {
        let text = "robot: r\nkeyframes:\n  - pose: {a: 10\n  - pose: {a: 20}\n";
        let h = hint(text, 4).expect("hint");
        assert!(h.contains("`{` on line 3 is never closed"), "{h}");
        let text = "keyframes:\n  - [1, 2\n";
        let h = hint(text, 2).expect("hint");
        assert!(h.contains("`[` on line 2"), "{h}");
    }

    #[test]
    fn a_missing_space_after_a_colon_is_named() {
        let h = hint("robot: r\nrepeat:2\n", 2).expect("hint");
        assert!(h.contains("line 2") && h.contains("`repeat: value`"), "{h}");
        let h = hint("buses:\n  - name: a\n    baud:1000000\n", 3).expect("hint");
        assert!(h.contains("`baud:`"), "{h}");
    }

    #[test]
    fn correct_lines_give_no_hint() {
        let text = "port: /dev/ttyUSB0 # a comment with { and [\nurl: http://x\nat: 12:30\n";
        assert_eq!(hint(text, 3), None);
        assert_eq!(hint("pose: {a: 1, b: [2, 3]}\nname: \"{x\"\n", 2), None);
    }
}
