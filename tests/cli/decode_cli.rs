//! `servobus decode` end to end: the built binary on frames from the manual,
//! with garbage, bad checksums and truncated frames, in text and JSON.

use crate::common;

use std::process::Output;

use common::{servobus, stdout};
use serde_json::Value;

/// Runs with `--json` and parses one object per line.
fn json(args: &[&str]) -> (Vec<Value>, Output) {
    let mut all = vec!["decode", "--json"];
    all.extend_from_slice(args);
    let out = servobus(&all);
    let objects = stdout(&out)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l:?}: {e}")))
        .collect();
    (objects, out)
}

#[test]
fn ping_in_text() {
    let out = servobus(&["decode", "FF FF 01 02 01 FB"]);
    assert!(out.status.success());
    let text = stdout(&out);
    assert!(text.contains("ID 1, PING"), "{text}");
    assert!(text.contains("checksum ok (0xFB)"), "{text}");
}

#[test]
fn sync_write_names_registers_and_values() {
    let frame = "FF FF FE 20 83 2A 06 01 00 08 00 00 E8 03 02 00 08 00 00 E8 03 03 00 08 00 00 \
                 E8 03 04 00 08 00 00 E8 03 58";
    let (objs, out) = json(&[frame]);
    assert!(out.status.success());
    assert_eq!(objs.len(), 1);
    let p = &objs[0];
    assert_eq!(p["kind"], "packet");
    assert_eq!(p["id"], 254);
    assert_eq!(p["broadcast"], true);
    assert_eq!(p["instruction"], "SYNC WRITE");
    assert_eq!(p["checksum"], "ok");
    assert_eq!(p["address"], 42);
    assert_eq!(
        p["registers"],
        serde_json::json!(["goal_position", "goal_time", "goal_speed"])
    );
    let servos = p["servos"].as_array().expect("servos");
    assert_eq!(servos.len(), 4);
    assert_eq!(servos[3]["id"], 4);
    assert_eq!(servos[3]["values"]["goal_position"], 2048);
    assert_eq!(servos[3]["values"]["goal_speed"], 1000);

    let text = stdout(&servobus(&["decode", frame]));
    assert!(text.contains("ID 254 (broadcast), SYNC WRITE"), "{text}");
    assert!(text.contains("goal_position=2048"), "{text}");
}

#[test]
fn concatenated_frames_without_spaces() {
    // A READ of present position, then a PING, written without spaces.
    let (objs, out) = json(&["FFFF0104023802BE", "ffff0102 01fb"]);
    assert!(out.status.success());
    let kinds: Vec<_> = objs.iter().map(|o| o["instruction"].clone()).collect();
    assert_eq!(kinds, ["READ", "PING"]);
    assert_eq!(
        objs[0]["registers"],
        serde_json::json!(["present_position"])
    );
    assert_eq!(objs[1]["offset"], 8);
}

#[test]
fn status_reply_flags() {
    let (objs, out) = json(&[
        "--from",
        "servo",
        "FF FF 01 04 00 18 05 DD",
        "FF FF 02 02 24 D7",
    ]);
    assert!(out.status.success());
    assert_eq!(objs[0]["status"]["ok"], true);
    assert_eq!(objs[0]["params"], "18 05");
    // 0x24 = overheat + overload.
    assert_eq!(objs[1]["status"]["ok"], false);
    assert_eq!(
        objs[1]["status"]["flags"],
        serde_json::json!(["overheat", "overload"])
    );
}

#[test]
fn problems_are_reported_and_good_packets_still_decode() {
    // Garbage, a bad checksum (BE -> BF), then a valid PING.
    let (objs, out) = json(&["00 13", "FF FF 01 04 02 38 02 BF", "FF FF 01 02 01 FB"]);
    assert_eq!(
        out.status.code(),
        Some(1),
        "a problem was found, though a packet decoded"
    );
    let kinds: Vec<_> = objs.iter().map(|o| o["kind"].as_str().unwrap()).collect();
    assert_eq!(kinds, ["garbage", "bad_checksum", "packet"]);
    assert_eq!(objs[0]["offset"], 0);
    assert_eq!(objs[1]["offset"], 2);
    assert_eq!(objs[1]["found"], 0xBF);
    assert_eq!(objs[1]["expected"], 0xBE);
    assert_eq!(objs[2]["offset"], 10);
}

#[test]
fn misprinted_example_4_is_truncated_and_fails() {
    let (objs, out) = json(&["FF FF 01 09 03 2A 00 08 00 E8 03 D5"]);
    assert_eq!(out.status.code(), Some(1), "a problem found");
    assert_eq!(objs.len(), 1);
    assert_eq!(objs[0]["kind"], "truncated");
    assert_eq!(objs[0]["needed"], 13);
    assert_eq!(objs[0]["available"], 12);

    let out = servobus(&["decode", "FF FF 01 09 03 2A 00 08 00 E8 03 D5"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stdout(&out).contains("truncated frame at 0"));
}

#[test]
fn leading_garbage_and_a_bad_checksum_are_both_problems() {
    let garbage = servobus(&["decode", "00 FF FF 01 02 01 FB"]);
    let checksum = servobus(&["decode", "FF FF 01 02 01 FA"]);
    let clean = servobus(&["decode", "FF FF 01 02 01 FB"]);
    assert_eq!(garbage.status.code(), Some(1));
    assert_eq!(checksum.status.code(), Some(1));
    assert_eq!(clean.status.code(), Some(0));
}

#[test]
fn a_run_of_header_bytes_is_reported_once_per_problem() {
    let out = servobus(&["decode", "FF FF FF FF FF"]);
    assert_eq!(out.status.code(), Some(1));
    let text = stdout(&out);
    assert_eq!(text.matches("truncated").count(), 1, "{text}");
    assert!(
        text.contains("truncated frame at 3: input ends inside the header: FF FF"),
        "{text}"
    );
    assert_eq!(text.matches("invalid header").count(), 1, "{text}");
    assert!(
        text.contains("5 byte(s): 0 packet(s), 2 problem(s)"),
        "{text}"
    );
}

#[test]
fn only_garbage_fails() {
    let out = servobus(&["decode", "01 02 03"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stdout(&out).contains("garbage at 0: 3 byte(s)"));
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    for args in [
        &["decode", "FF F"][..],
        &["decode", "FF ZZ"],
        &["decode", "--model", "nope", "FF FF 01 02 01 FB"],
    ] {
        let out = servobus(args);
        assert_eq!(out.status.code(), Some(2), "input error: {args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("error"), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

#[test]
fn scs_model_reads_big_endian() {
    // WRITE goal position 0x0200 = 512 to an SCS servo: high byte first.
    let frame = {
        let body = [0x01u8, 0x05, 0x03, 0x2A, 0x02, 0x00];
        let sum: u8 = body.iter().fold(0u8, |a, b| a.wrapping_add(*b));
        let mut f = vec![0xFF, 0xFF];
        f.extend(body);
        f.push(!sum);
        f.iter()
            .map(|b| format!("{b:02X}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let (objs, _) = json(&["--model", "scs0009", &frame]);
    assert_eq!(objs[0]["values"]["goal_position"], 512);
    let (objs, _) = json(&[&frame]);
    assert_eq!(objs[0]["values"]["goal_position"], 2);
}
