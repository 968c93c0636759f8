//! JSON reports as written: every float without the binary noise of its
//! last digits (`0.23600000000000002`), every field as it was.

use crate::common;

use common::{servobus_ok, stdout};

const WAVE: &str = "configs/motions/arm-wave.yaml";
const SO101: &str = "configs/robots/so101.yaml";

/// The numbers of the JSON text `json` as written (strings skipped).
fn json_numbers(json: &str) -> Vec<&str> {
    let mut numbers = Vec::new();
    let (mut in_string, mut escaped, mut start) = (false, false, None);
    for (i, c) in json.char_indices() {
        if in_string {
            match (escaped, c) {
                (true, _) => escaped = false,
                (false, '\\') => escaped = true,
                (false, '"') => in_string = false,
                _ => {}
            }
            continue;
        }
        // A number starts with a digit or `-` (not the `e` of `true`).
        let begins = c.is_ascii_digit() || c == '-';
        let goes_on = begins || matches!(c, '+' | '.' | 'e' | 'E');
        match (start, begins, goes_on) {
            (None, true, _) => start = Some(i),
            (Some(s), _, false) => {
                numbers.push(&json[s..i]);
                start = None;
            }
            _ => {}
        }
        in_string = c == '"';
    }
    numbers.extend(start.map(|s| &json[s..]));
    numbers
}

/// The significant digits of the JSON number `n` (`0.0236` has 3, `200.0` 1).
fn significant_digits(n: &str) -> usize {
    let mantissa = n.split(['e', 'E']).next().unwrap_or(n);
    let digits: String = mantissa.chars().filter(char::is_ascii_digit).collect();
    digits.trim_start_matches('0').trim_end_matches('0').len()
}

#[test]
fn json_reports_write_floats_without_binary_noise() {
    assert_eq!(
        json_numbers("{\"a\":-0.25,\"b\":\"3.10\",\"c\":[1e-9,2,true,null]}"),
        ["-0.25", "1e-9", "2"]
    );
    assert_eq!(significant_digits("0.23600000000000002"), 17);
    assert_eq!(significant_digits("200.0"), 1);
    for args in [
        &["play", WAVE, "--fast", "--json"][..],
        &["plan", WAVE, "--json"],
        &["budget", "--robot", SO101, "--json"],
    ] {
        let text = stdout(&servobus_ok(args));
        let numbers = json_numbers(&text);
        assert!(numbers.iter().any(|n| n.contains('.')), "{args:?}: {text}");
        for n in numbers {
            assert!(
                significant_digits(n) <= 13,
                "{args:?}: {n} carries float noise:\n{text}"
            );
            let _: f64 = n.parse().unwrap_or_else(|_| panic!("{args:?}: {n:?}"));
        }
    }
}
