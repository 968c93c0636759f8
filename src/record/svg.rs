//! The SVG text of the plots, tidied. plotters writes a font's size as its
//! pixel size divided by 1.24, in every digit an `f64` has
//! (`font-size="9.67741935483871"`); the plots say it to 0.1 px.

use std::fmt::Write as _;

/// The attribute whose value is rounded.
const FONT_SIZE: &str = "font-size=\"";

/// `svg` with the value of every `font-size` attribute rounded to 0.1 px
/// (`9.7`, and `12` for `12.0`); everything else as it was. Text drawn in
/// the plot cannot hold the attribute: plotters escapes its quotes.
pub(crate) fn round_font_sizes(svg: &str) -> String {
    let mut out = String::with_capacity(svg.len());
    let mut rest = svg;
    while let Some(at) = rest.find(FONT_SIZE) {
        let (head, tail) = rest.split_at(at + FONT_SIZE.len());
        out.push_str(head);
        let (value, after) = tail.split_at(tail.find('"').unwrap_or(tail.len()));
        match value.parse::<f64>() {
            Ok(px) if px.is_finite() => {
                // `+ 0.0`: no `-0`.
                let _ = write!(out, "{}", (px * 10.0).round() / 10.0 + 0.0);
            }
            _ => out.push_str(value),
        }
        rest = after;
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn font_sizes_are_rounded_to_a_tenth_of_a_pixel_and_nothing_else_changes() {
        let svg = "<svg width=\"1200\">\n<text x=\"600\" y=\"5\" dy=\"0.76em\" \
                   font-size=\"19.35483870967742\" opacity=\"1\">\ntitle 13.333333\n</text>\n\
                   <text font-size=\"9.67741935483871\">a</text>\
                   <text font-size=\"12.0\">b</text><text font-size=\"large\">c</text></svg>";
        assert_eq!(
            round_font_sizes(svg),
            "<svg width=\"1200\">\n<text x=\"600\" y=\"5\" dy=\"0.76em\" \
             font-size=\"19.4\" opacity=\"1\">\ntitle 13.333333\n</text>\n\
             <text font-size=\"9.7\">a</text>\
             <text font-size=\"12\">b</text><text font-size=\"large\">c</text></svg>"
        );
        // An attribute cut short is kept as it is.
        assert_eq!(
            round_font_sizes("<text font-size=\"9.6"),
            "<text font-size=\"9.6"
        );
    }
}
