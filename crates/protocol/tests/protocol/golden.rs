//! Golden vectors from the manual (`testdata/manual-vectors.json`), checked in
//! both directions: the encoders give exactly the printed bytes, and parsing
//! the printed bytes (whole, and streamed byte by byte) gives exactly the
//! printed fields.

use std::collections::BTreeSet;

use serde_json::Value;
use servobus_protocol::registers::{ByteOrder, STS};
use servobus_protocol::{
    encode, parse_frame, Decoder, DiscardReason, Event, Instruction, ParseError, StatusFlags,
};

fn vectors() -> Vec<Value> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../testdata/manual-vectors.json"
    );
    let text = std::fs::read_to_string(path).expect("golden vectors file");
    let doc: Value = serde_json::from_str(&text).expect("golden vectors are JSON");
    doc["vectors"].as_array().expect("a vectors array").clone()
}

fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace()
        .map(|b| u8::from_str_radix(b, 16).expect("hex byte"))
        .collect()
}

fn num(v: &Value, key: &str) -> u8 {
    let n = v[key].as_u64().unwrap_or_else(|| panic!("field {key}"));
    u8::try_from(n).expect("a byte")
}

fn encode_op(spec: &Value, buf: &mut [u8]) -> usize {
    let op = spec["op"].as_str().expect("op");
    let r = match op {
        "ping" => encode::ping(buf, num(spec, "id")),
        "read" => encode::read(buf, num(spec, "id"), num(spec, "address"), num(spec, "len")),
        "write" => encode::write(
            buf,
            num(spec, "id"),
            num(spec, "address"),
            &hex(spec["data"].as_str().unwrap()),
        ),
        "reg_write" => encode::reg_write(
            buf,
            num(spec, "id"),
            num(spec, "address"),
            &hex(spec["data"].as_str().unwrap()),
        ),
        "action" => encode::action(buf, num(spec, "id")),
        "reset" => encode::reset(buf, num(spec, "id")),
        "sync_read" => {
            let ids: Vec<u8> = spec["ids"]
                .as_array()
                .unwrap()
                .iter()
                .map(|i| u8::try_from(i.as_u64().unwrap()).unwrap())
                .collect();
            encode::sync_read(buf, num(spec, "address"), num(spec, "len"), &ids)
        }
        "sync_write" => {
            let blocks: Vec<(u8, Vec<u8>)> = spec["blocks"]
                .as_array()
                .unwrap()
                .iter()
                .map(|b| {
                    (
                        u8::try_from(b[0].as_u64().unwrap()).unwrap(),
                        hex(b[1].as_str().unwrap()),
                    )
                })
                .collect();
            encode::sync_write(
                buf,
                num(spec, "address"),
                num(spec, "len"),
                blocks.iter().map(|(id, d)| (*id, d.as_slice())),
            )
        }
        "status" => encode::status(
            buf,
            num(spec, "id"),
            StatusFlags(num(spec, "flags")),
            &hex(spec["params"].as_str().unwrap()),
        ),
        other => panic!("unknown op {other}"),
    };
    r.unwrap_or_else(|e| panic!("{op}: {e}"))
}

#[test]
fn encoders_give_exactly_the_printed_bytes() {
    let mut ops = BTreeSet::new();
    for v in vectors() {
        let name = v["name"].as_str().unwrap();
        let bytes = hex(v["hex"].as_str().unwrap());
        let Some(spec) = v.get("encode") else {
            continue;
        };
        let mut buf = [0u8; 300];
        let n = encode_op(spec, &mut buf);
        assert_eq!(&buf[..n], &bytes[..], "{name}");
        ops.insert(spec["op"].as_str().unwrap().to_owned());
    }
    // Every instruction and the status reply are covered.
    let all = [
        "action",
        "ping",
        "read",
        "reg_write",
        "reset",
        "status",
        "sync_read",
        "sync_write",
        "write",
    ];
    assert_eq!(ops, all.iter().map(|s| s.to_string()).collect());
}

#[test]
fn parsing_gives_exactly_the_printed_fields() {
    let mut incomplete = 0;
    for v in vectors() {
        let name = v["name"].as_str().unwrap();
        let bytes = hex(v["hex"].as_str().unwrap());
        let d = &v["decode"];
        if let Some(inc) = d.get("incomplete") {
            let needed = inc["needed"].as_u64().unwrap() as usize;
            let available = inc["available"].as_u64().unwrap() as usize;
            assert_eq!(
                parse_frame(&bytes),
                Err(ParseError::Incomplete { needed, available }),
                "{name}"
            );
            incomplete += 1;
            continue;
        }
        let (p, used) = parse_frame(&bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(used, bytes.len(), "{name}");
        assert_eq!(p.id(), num(d, "id"), "{name}");
        assert_eq!(p.code(), num(d, "code"), "{name}");
        assert_eq!(
            p.params(),
            &hex(d["params"].as_str().unwrap())[..],
            "{name}"
        );
        assert_eq!(p.bytes(), &bytes[..], "{name}");
        assert_eq!(usize::from(p.length_byte()), p.params().len() + 2, "{name}");
        match v["from"].as_str().unwrap() {
            "host" => assert_eq!(
                p.instruction().map(Instruction::code),
                Some(p.code()),
                "{name}"
            ),
            _ => assert!(p.status().is_ok(), "{name}"),
        }
        assert_eq!(p.is_broadcast(), p.id() == 0xFE, "{name}");
    }
    assert_eq!(
        incomplete, 1,
        "exactly the misprinted Example 4 is incomplete"
    );
}

/// Every vector streamed one byte at a time through the decoder: complete
/// frames come out as one packet each, the misprint as pending bytes that
/// `finish` reports as one truncated range.
#[test]
fn streaming_gives_the_same_packets() {
    for v in vectors() {
        let name = v["name"].as_str().unwrap();
        let bytes = hex(v["hex"].as_str().unwrap());
        let mut dec = Decoder::new();
        let mut packets = Vec::new();
        for b in &bytes {
            let mut input = std::slice::from_ref(b);
            while let Some(ev) = dec.decode(&mut input) {
                match ev {
                    Event::Packet { packet, start } => {
                        packets.push((packet.bytes().to_vec(), start))
                    }
                    other => panic!("{name}: unexpected {other:?}"),
                }
            }
        }
        if v["decode"].get("incomplete").is_some() {
            assert!(packets.is_empty(), "{name}");
            assert_eq!(dec.pending(), bytes.len(), "{name}");
            let ev = dec.finish();
            assert_eq!(
                ev,
                Some(Event::Discarded {
                    start: 0,
                    len: bytes.len(),
                    reason: DiscardReason::Truncated
                }),
                "{name}"
            );
            assert_eq!(dec.finish(), None);
        } else {
            assert_eq!(packets, vec![(bytes.clone(), 0)], "{name}");
            assert_eq!(dec.pending(), 0, "{name}");
        }
    }
}

/// The misprinted Example 4 followed by the reply it gets: the decoder must
/// not merge the reply's first byte into the short frame as a wrong packet.
#[test]
fn misprint_followed_by_a_reply_yields_only_the_reply() {
    let mut stream = hex("FF FF 01 09 03 2A 00 08 00 E8 03 D5");
    stream.extend(hex("FF FF 01 02 00 FC"));
    let mut dec = Decoder::new();
    let mut input = &stream[..];
    let mut seen = Vec::new();
    while let Some(ev) = dec.decode_to_end(&mut input) {
        match ev {
            Event::Packet { packet, start } => seen.push(format!("packet {start} {}", packet.id())),
            Event::ChecksumError { start, .. } => seen.push(format!("checksum {start}")),
            Event::Discarded { start, len, .. } => seen.push(format!("discard {start}+{len}")),
            Event::Echo { .. } => seen.push("echo".into()),
        }
    }
    assert_eq!(seen, ["checksum 0", "discard 0+12", "packet 12 1"]);
}

#[test]
fn the_two_reset_misprints_are_both_valid_frames() {
    let (text, table) = (hex("FF FF 01 02 06 F6"), hex("FF FF 00 02 06 F7"));
    let (a, _) = parse_frame(&text).unwrap();
    let (b, _) = parse_frame(&table).unwrap();
    assert_eq!((a.id(), b.id()), (1, 0));
    assert_eq!(a.instruction(), Some(Instruction::Reset));
    assert_eq!(b.instruction(), Some(Instruction::Reset));
}

#[test]
fn example_2_reply_reads_as_position_1304() {
    let frame = hex("FF FF 01 04 00 18 05 DD");
    let (p, _) = parse_frame(&frame).unwrap();
    let reg = STS.get("present_position").unwrap();
    assert_eq!(reg.decode(p.params(), ByteOrder::Little), Ok(1304));
}
