//! JSON as the command line prints it (`--json` of play, plan, budget,
//! bench, scan, read, doctor, monitor, fk, ik and follow; stream's lines):
//! serde_json's output with every float rounded to [`SIGNIFICANT_DIGITS`]
//! significant digits as it is written.
//!
//! A report's figures are sums and quotients of binary floats, and
//! serde_json writes the shortest decimal that reads back to the same
//! float, so `0.236` computed as `0.059 * 4` prints as
//! `0.23600000000000002`. Thirteen significant digits drop that noise (a
//! few units in the last place sit in the 16th and 17th digits; this
//! leaves room for a thousand) and keep every digit a measurement or a
//! reader's comparison can use: the figures are accurate to far less, and
//! a check to 1e-9 of a figure below 10 000 (a rate in Hz, a time in µs)
//! still holds. The fields and the values themselves are not touched: only
//! their decimal spelling.

use std::io;

use serde::Serialize;
use serde_json::ser::{CompactFormatter, Formatter, PrettyFormatter};

/// Significant digits of a float in the JSON output.
pub const SIGNIFICANT_DIGITS: usize = 13;

/// `value` as JSON on one line (a stream of frames, a short answer).
///
/// # Errors
/// serde_json's, for a value JSON cannot hold (a map with keys that are
/// not strings).
pub fn line<T: Serialize + ?Sized>(value: &T) -> Result<String, serde_json::Error> {
    write(value, Rounding(CompactFormatter))
}

/// `value` as indented JSON (a report).
///
/// # Errors
/// As [`line`].
pub fn pretty<T: Serialize + ?Sized>(value: &T) -> Result<String, serde_json::Error> {
    write(value, Rounding(PrettyFormatter::new()))
}

fn write<T: Serialize + ?Sized, F: Formatter>(
    value: &T,
    formatter: F,
) -> Result<String, serde_json::Error> {
    let mut bytes = Vec::new();
    let mut ser = serde_json::Serializer::with_formatter(&mut bytes, formatter);
    value.serialize(&mut ser)?;
    // serde_json writes UTF-8 only.
    String::from_utf8(bytes).map_err(|e| serde::ser::Error::custom(e.to_string()))
}

/// `value` rounded to [`SIGNIFICANT_DIGITS`] significant digits (the float
/// nearest that decimal); zero, infinities and NaN as they are.
pub fn rounded(value: f64) -> f64 {
    if value == 0.0 || !value.is_finite() {
        return value;
    }
    // `{:.Ne}` rounds the decimal correctly; reading it back gives the
    // float serde_json then writes in its shortest form.
    let text = format!("{value:.prec$e}", prec = SIGNIFICANT_DIGITS - 1);
    text.parse().unwrap_or(value)
}

/// A formatter that writes floats [`rounded`] and everything else as the
/// formatter inside does (the layout of [`PrettyFormatter`] included).
struct Rounding<F>(F);

impl<F: Formatter> Formatter for Rounding<F> {
    fn write_f64<W: ?Sized + io::Write>(&mut self, w: &mut W, value: f64) -> io::Result<()> {
        self.0.write_f64(w, rounded(value))
    }

    fn write_f32<W: ?Sized + io::Write>(&mut self, w: &mut W, value: f32) -> io::Result<()> {
        // An f32 has fewer significant digits than the rounding keeps:
        // written as serde_json writes it.
        self.0.write_f32(w, value)
    }

    fn begin_array<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.0.begin_array(w)
    }

    fn end_array<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.0.end_array(w)
    }

    fn begin_array_value<W: ?Sized + io::Write>(
        &mut self,
        w: &mut W,
        first: bool,
    ) -> io::Result<()> {
        self.0.begin_array_value(w, first)
    }

    fn end_array_value<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.0.end_array_value(w)
    }

    fn begin_object<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.0.begin_object(w)
    }

    fn end_object<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.0.end_object(w)
    }

    fn begin_object_key<W: ?Sized + io::Write>(
        &mut self,
        w: &mut W,
        first: bool,
    ) -> io::Result<()> {
        self.0.begin_object_key(w, first)
    }

    fn end_object_key<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.0.end_object_key(w)
    }

    fn begin_object_value<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.0.begin_object_value(w)
    }

    fn end_object_value<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.0.end_object_value(w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn float_noise_is_dropped_and_the_digits_kept() {
        let v = serde_json::json!({
            "noise": 0.059 * 4.0,
            "sum": 0.1 + 0.2,
            "kept": 0.109_535_201_555_5,
            "small": 1.5e-9,
            "big": 1_700_000_000.25,
            "whole": 200.0,
            "count": 1146,
            "none": f64::NAN,
        });
        assert_eq!(
            line(&v).expect("json"),
            "{\"big\":1700000000.25,\"count\":1146,\"kept\":0.1095352015555,\"noise\":0.236,\
             \"none\":null,\"small\":1.5e-9,\"sum\":0.3,\"whole\":200.0}"
        );
        assert_eq!(rounded(-0.32199999999999995), -0.322);
        assert_eq!(rounded(0.0), 0.0);
    }

    #[test]
    fn pretty_output_keeps_its_layout() {
        let v = serde_json::json!({"a": [1, 0.1 + 0.2], "b": {"c": null}});
        assert_eq!(
            pretty(&v).expect("json"),
            "{\n  \"a\": [\n    1,\n    0.3\n  ],\n  \"b\": {\n    \"c\": null\n  }\n}"
        );
        assert_eq!(
            pretty(&v)
                .expect("json")
                .replace("0.3", "0.30000000000000004"),
            serde_json::to_string_pretty(&v).expect("json")
        );
    }
}
