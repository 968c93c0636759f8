//! How deeply a YAML text nests, measured before serde_yaml parses it.
//!
//! serde_yaml stops at 128 levels, but on some shapes (`{a: {a: {a: ...`)
//! it takes time quadratic in the depth before it gets there: a 400 KB file
//! nested 100,000 deep takes a minute. This scan is linear and cheap. It
//! counts open flow brackets (`[`, `{`) outside quoted text and comments,
//! the indentation levels of block mappings and lists still open, and each
//! `- ` that opens a list on the same line. It may count a level too many
//! on unusual layouts (a plain scalar continued on a more indented line),
//! never far fewer, which is all a limit needs.

/// The 1-based line and column where `text` first nests deeper than
/// `limit` levels, or `None` when it never does.
pub(crate) fn too_deep(text: &str, limit: usize) -> Option<(usize, usize)> {
    let mut scan = Scan::default();
    for (n, line) in text.lines().enumerate() {
        if let Some(column) = scan.line(line, limit) {
            return Some((n + 1, column));
        }
    }
    None
}

/// What a quoted scalar needs to end.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Quote {
    Double,
    Single,
}

/// The state of the scan between lines.
#[derive(Default)]
struct Scan {
    /// Indentation of the block levels still open, increasing.
    indents: Vec<usize>,
    /// Flow brackets still open.
    flow: usize,
    /// Block levels open at the last line outside flow brackets (a flow
    /// collection over several lines sits at that depth).
    block_depth: usize,
    /// Inside a quoted scalar that continues on the next line.
    quote: Option<Quote>,
    /// Inside a block scalar (`|`, `>`) whose key or dash is at this
    /// indentation: lines indented further are its text.
    block_scalar: Option<usize>,
}

impl Scan {
    /// Scans one line; the 1-based column where the depth first exceeds
    /// `limit`.
    fn line(&mut self, line: &str, limit: usize) -> Option<usize> {
        let bytes = line.as_bytes();
        let indent = bytes.iter().take_while(|&&b| b == b' ').count();
        let blank = bytes[indent..]
            .iter()
            .all(|b| b.is_ascii_whitespace() || *b == b'\r');
        if let Some(at) = self.block_scalar {
            if blank || indent > at {
                return None;
            }
            self.block_scalar = None;
        }
        let mut i = 0;
        if self.flow == 0 && self.quote.is_none() {
            if blank || bytes[indent] == b'#' {
                return None;
            }
            i = self.open_blocks(bytes, indent);
            if self.block_depth > limit {
                return Some(indent + 1);
            }
        }
        self.scan_rest(bytes, i, indent, limit)
    }

    /// Sets the block levels open at a line indented `indent` (outside
    /// flow brackets and quotes), counting each `- ` that opens a list on
    /// it; returns the index of the first byte after them.
    fn open_blocks(&mut self, bytes: &[u8], indent: usize) -> usize {
        while self.indents.last().is_some_and(|&top| top > indent) {
            self.indents.pop();
        }
        if self.indents.last() != Some(&indent) {
            self.indents.push(indent);
        }
        self.block_depth = self.indents.len();
        let mut i = indent;
        // Each `- ` opening a list on this line is one more level.
        while i < bytes.len() && bytes[i] == b'-' && bytes.get(i + 1).is_none_or(|b| *b == b' ') {
            self.block_depth += 1;
            i += 1;
            while bytes.get(i) == Some(&b' ') {
                i += 1;
            }
        }
        i
    }

    /// Scans the line (indented `indent`) from byte `i` for quotes,
    /// comments, flow brackets and block scalars; the 1-based column where
    /// a bracket first takes the depth past `limit`.
    fn scan_rest(
        &mut self,
        bytes: &[u8],
        mut i: usize,
        indent: usize,
        limit: usize,
    ) -> Option<usize> {
        let mut prev: Option<u8> = None;
        while i < bytes.len() {
            let b = bytes[i];
            match self.quote {
                Some(quote) => i = self.quoted(quote, bytes, i),
                None => {
                    // Where a quote or a bracket opens something, not the
                    // middle of a plain scalar (`x[1]`).
                    let starters: &[u8] = if self.flow > 0 { b"[{,:-?" } else { b":-?" };
                    let token_start = prev.is_none_or(|p| starters.contains(&p));
                    match b {
                        b'#' if i == 0 || bytes[i - 1] == b' ' || bytes[i - 1] == b'\t' => break,
                        b'"' if token_start => self.quote = Some(Quote::Double),
                        b'\'' if token_start => self.quote = Some(Quote::Single),
                        b'[' | b'{' if token_start || self.flow > 0 => {
                            self.flow += 1;
                            if self.block_depth + self.flow > limit {
                                return Some(i + 1);
                            }
                        }
                        b']' | b'}' if self.flow > 0 => self.flow -= 1,
                        b'|' | b'>' if token_start && self.flow == 0 => {
                            self.block_scalar = Some(indent);
                        }
                        _ => {}
                    }
                }
            }
            if !b.is_ascii_whitespace() {
                prev = Some(b);
            }
            i += 1;
        }
        None
    }

    /// Reads byte `i` inside a `quote`d scalar, ending the quote at its
    /// closing mark; returns the index of the last byte read (an escape
    /// or a doubled single quote takes two).
    fn quoted(&mut self, quote: Quote, bytes: &[u8], i: usize) -> usize {
        match (quote, bytes[i]) {
            (Quote::Double, b'\\') => return i + 1,
            (Quote::Double, b'"') => self.quote = None,
            (Quote::Single, b'\'') => {
                if bytes.get(i + 1) == Some(&b'\'') {
                    return i + 1;
                }
                self.quote = None;
            }
            _ => {}
        }
        i
    }
}

#[cfg(test)]
mod tests {
    use super::too_deep;

    #[test]
    fn flow_brackets_count_outside_quotes_and_comments() {
        assert_eq!(too_deep("a: [[[1]]]\n", 4), None);
        assert_eq!(too_deep("a: [[[[1]]]]\n", 4), Some((1, 7)));
        assert_eq!(too_deep("a: \"[[[[[[\"\nb: '{{{{{'  # [[[[[[\n", 2), None);
        assert_eq!(too_deep("a: x[[[[[[\n", 2), None);
        // A flow collection over several lines keeps its depth.
        assert_eq!(too_deep("a: [\n  [\n   [1]]]\n", 3), Some((3, 4)));
        assert_eq!(too_deep(&"{a: ".repeat(100_000), 32), Some((1, 125)));
    }

    #[test]
    fn block_levels_count_by_indentation_and_dashes() {
        let robot = "name: r\nbuses:\n  - name: a\n    joints:\n      - name: j\n        id: 1\n";
        assert_eq!(too_deep(robot, 5), None);
        assert_eq!(too_deep(robot, 4), Some((5, 7)));
        let deep: String = (0..40).map(|i| format!("{}a:\n", " ".repeat(i))).collect();
        assert_eq!(too_deep(&deep, 32), Some((33, 33)));
        assert_eq!(
            too_deep(&format!("{}x\n", "- ".repeat(40)), 32),
            Some((1, 1))
        );
        // Lists at the indentation of their key are one level, not two.
        assert_eq!(too_deep("k:\n- a\n- b\n", 2), None);
    }

    #[test]
    fn block_scalars_and_comments_are_text() {
        let text = "a: |\n  x\n    y\n      z\nb: 1\n";
        assert_eq!(too_deep(text, 2), None);
        assert_eq!(too_deep("# {{{{{{{{\n   # - - - - -\nb: 1\n", 2), None);
    }
}
