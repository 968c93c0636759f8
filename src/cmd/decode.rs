//! `servobus decode`: frames written in hex, explained.
//!
//! The bytes go through the same streaming decoder the driver uses, so what
//! this prints is what the runtime would make of them: each packet (ID,
//! instruction or status flags, parameters, the registers its address range
//! covers, checksum), and each problem (garbage, bad checksum, impossible
//! header, truncated frame) with its offset in the input.

use std::fmt::Write as _;
use std::process::ExitCode;

use anyhow::Context;

use crate::shared::exit::input;
use crate::shared::out::outln;
use serde_json::{json, Map, Value};
use servobus_protocol::registers::{self, RegisterMap};
use servobus_protocol::{Command, Decoder, DiscardReason, Event, Packet, FRAME_OVERHEAD};

/// Who sent the frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Sender {
    /// The host: the fifth byte is an instruction.
    Host,
    /// A servo: the fifth byte is its status (error flags).
    Servo,
}

/// Arguments of `servobus decode`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Who sent the frames: the host (instructions) or a servo (status replies).
    #[arg(long, value_enum, default_value = "host")]
    pub from: Sender,
    /// Frames in hex; spaces optional; several may be concatenated
    /// (`0x` prefixes, commas and colons are ignored).
    #[arg(required = true)]
    pub hex: Vec<String>,
    /// Servo model (or series, `sts`/`scs`) whose register map names the addresses.
    #[arg(long, default_value = "sts3215")]
    pub model: String,
    /// Print one JSON object per packet or problem.
    #[arg(long)]
    pub json: bool,
}

/// Runs `servobus decode`: exits 0 when every byte belongs to a clean packet,
/// 1 when a problem was found, 2 for input that is not hex.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let map = register_map(&args.model)?;
    let bytes = parse_hex(&args.hex)?;
    let items = decode(&bytes, args.from, map);
    for item in &items {
        if args.json {
            outln!("{}", Value::Object(item.json.clone()))?;
        } else {
            outln!("{}", item.text)?;
        }
    }
    let packets = items.iter().filter(|i| i.is_packet).count();
    if !args.json {
        let problems = items.len() - packets;
        outln!(
            "{} byte(s): {packets} packet(s), {problems} problem(s)",
            bytes.len()
        )?;
    }
    // Like every command: 0 when all is well, 1 when a problem was found
    // (garbage, a bad checksum, a bad header, a truncated frame).
    Ok(if packets == items.len() && packets > 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(crate::shared::exit::PROBLEM)
    })
}

fn register_map(model: &str) -> anyhow::Result<&'static RegisterMap> {
    match model.to_ascii_lowercase().as_str() {
        "sts" | "sms" => return Ok(&registers::STS),
        "scs" => return Ok(&registers::SCS),
        _ => {}
    }
    match registers::model_by_name(model) {
        Some(m) => Ok(m.map()),
        None => {
            let known: Vec<_> = registers::MODELS.iter().map(|m| m.name).collect();
            Err(input(format!(
                "unknown model {model:?}; known: {}, or a series: sts, scs",
                known.join(", ")
            )))
        }
    }
}

/// Hex digits from every argument; whitespace, commas, colons and `0x`
/// prefixes are ignored.
fn parse_hex(args: &[String]) -> anyhow::Result<Vec<u8>> {
    let mut digits = String::new();
    for arg in args {
        for token in arg.split(|c: char| c.is_whitespace() || c == ',' || c == ':') {
            let t = token
                .strip_prefix("0x")
                .or_else(|| token.strip_prefix("0X"))
                .unwrap_or(token);
            if let Some(bad) = t.chars().find(|c| !c.is_ascii_hexdigit()) {
                return Err(input(format!("{bad:?} in {token:?} is not a hex digit")));
            }
            digits.push_str(t);
        }
    }
    if digits.is_empty() {
        return Err(input("no hex digits given"));
    }
    if !digits.len().is_multiple_of(2) {
        return Err(input(format!(
            "odd number of hex digits ({}): each byte needs two",
            digits.len()
        )));
    }
    (0..digits.len())
        .step_by(2)
        .map(|i| {
            u8::from_str_radix(&digits[i..i + 2], 16)
                .with_context(|| format!("bad hex byte {:?}", &digits[i..i + 2]))
        })
        .collect()
}

fn hex(bytes: &[u8]) -> String {
    let mut s = String::with_capacity(bytes.len() * 3);
    for (i, b) in bytes.iter().enumerate() {
        if i > 0 {
            s.push(' ');
        }
        let _ = write!(s, "{b:02X}");
    }
    s
}

/// One line of the report, in both renderings.
struct Item {
    is_packet: bool,
    text: String,
    json: Map<String, Value>,
}

fn decode(bytes: &[u8], from: Sender, map: &RegisterMap) -> Vec<Item> {
    let mut dec = Decoder::new();
    let mut items = Vec::new();
    let mut input = bytes;
    // A checksum failure is followed by the discard of the bad frame's bytes;
    // both are reported as one problem.
    let mut bad_checksum: Option<(u8, u8, u8)> = None;
    let mut pending: Option<Discard> = None;
    while let Some(ev) = dec.decode_to_end(&mut input) {
        match ev {
            Event::Packet { packet, start } => {
                flush(&mut pending, bytes, &mut items);
                items.push(packet_item(&packet, start, from, map));
            }
            Event::Echo { .. } => {}
            Event::ChecksumError {
                id,
                expected,
                found,
                ..
            } => bad_checksum = Some((id, expected, found)),
            Event::Discarded { start, len, reason } => {
                let at = usize::try_from(start).unwrap_or(usize::MAX);
                let checksum = if reason == DiscardReason::Checksum {
                    bad_checksum.take()
                } else {
                    None
                };
                // The decoder skips a run of bad bytes one at a time (each
                // `FF` of `FF FF FF` is a header that cannot start a frame);
                // adjacent discards for the same reason are one problem.
                match &mut pending {
                    Some(p) if p.reason == reason && p.at + p.len == at && checksum.is_none() => {
                        p.len += len;
                    }
                    _ => {
                        flush(&mut pending, bytes, &mut items);
                        pending = Some(Discard {
                            at,
                            len,
                            reason,
                            checksum,
                        });
                    }
                }
            }
        }
    }
    flush(&mut pending, bytes, &mut items);
    items
}

/// Bytes the decoder discarded, not yet reported.
struct Discard {
    at: usize,
    len: usize,
    reason: DiscardReason,
    checksum: Option<(u8, u8, u8)>,
}

fn flush(pending: &mut Option<Discard>, bytes: &[u8], items: &mut Vec<Item>) {
    if let Some(d) = pending.take() {
        let span = bytes.get(d.at..d.at.saturating_add(d.len)).unwrap_or(&[]);
        items.push(problem_item(bytes, d.at, span, d.reason, d.checksum));
    }
}

fn packet_item(packet: &Packet<'_>, start: u64, from: Sender, map: &RegisterMap) -> Item {
    let mut j = Map::new();
    j.insert("kind".into(), json!("packet"));
    j.insert("offset".into(), json!(start));
    j.insert("len".into(), json!(packet.bytes().len()));
    j.insert("bytes".into(), json!(hex(packet.bytes())));
    j.insert("id".into(), json!(packet.id()));
    j.insert("broadcast".into(), json!(packet.is_broadcast()));
    j.insert("params".into(), json!(hex(packet.params())));
    j.insert("checksum".into(), json!("ok"));

    let who = if packet.is_broadcast() {
        format!("ID {} (broadcast)", packet.id())
    } else {
        format!("ID {}", packet.id())
    };
    let mut text = format!("packet at {start}: {who}, ");
    let mut details = Vec::new();
    match from {
        Sender::Servo => {
            let flags = packet.status();
            j.insert("from".into(), json!("servo"));
            j.insert(
                "status".into(),
                json!({
                    "byte": flags.bits(),
                    "ok": flags.is_ok(),
                    "flags": flags.names().collect::<Vec<_>>(),
                    "unknown_bits": flags.unknown_bits(),
                }),
            );
            let _ = write!(text, "status {flags}");
            if !packet.params().is_empty() {
                let _ = write!(text, ", params {}", hex(packet.params()));
            }
        }
        Sender::Host => {
            j.insert("from".into(), json!("host"));
            j.insert("code".into(), json!(packet.code()));
            match packet.instruction() {
                Some(inst) => {
                    j.insert("instruction".into(), json!(inst.name()));
                    let _ = write!(text, "{inst}");
                }
                None => {
                    j.insert("instruction".into(), Value::Null);
                    let _ = write!(text, "unknown instruction 0x{:02X}", packet.code());
                }
            }
            match packet.command() {
                Ok(cmd) => describe_command(&cmd, map, &mut j, &mut text, &mut details),
                Err(e) if packet.instruction().is_some() => {
                    j.insert("error".into(), json!(e.to_string()));
                    let _ = write!(text, " (malformed: {e})");
                }
                Err(_) => {}
            }
        }
    }
    let _ = write!(text, ", checksum ok (0x{:02X})", packet.checksum());
    for d in details {
        text.push_str("\n    ");
        text.push_str(&d);
    }
    Item {
        is_packet: true,
        text,
        json: j,
    }
}

/// Register names of `[address, address + len)`, and `name=value` for the
/// registers `data` (starting at `address`) fully holds.
fn registers_of(
    map: &RegisterMap,
    address: u8,
    len: usize,
    data: Option<&[u8]>,
) -> (Vec<&'static str>, Vec<(&'static str, i32)>) {
    let names = map.covering(address, len).map(|r| r.name).collect();
    let mut values = Vec::new();
    if let Some(data) = data {
        for r in map.covering(address, len) {
            let Some(off) = usize::from(r.address).checked_sub(usize::from(address)) else {
                continue;
            };
            if let Some(raw) = data.get(off..off + usize::from(r.size)) {
                if let Ok(v) = r.decode(raw, map.byte_order) {
                    values.push((r.name, v));
                }
            }
        }
    }
    (names, values)
}

fn describe_command(
    cmd: &Command<'_>,
    map: &RegisterMap,
    j: &mut Map<String, Value>,
    text: &mut String,
    details: &mut Vec<String>,
) {
    let Some((address, len)) = cmd.span() else {
        return;
    };
    j.insert("address".into(), json!(address));
    j.insert("data_len".into(), json!(len));
    let data = match cmd {
        Command::Write { data, .. } | Command::RegWrite { data, .. } => Some(*data),
        _ => None,
    };
    let (names, values) = registers_of(map, address, len, data);
    j.insert("registers".into(), json!(names));
    let list = if names.is_empty() {
        "no known register".to_owned()
    } else {
        names.join(", ")
    };
    let _ = write!(
        text,
        " {len} byte(s) at {address} (0x{address:02X}): {list}"
    );
    if !values.is_empty() {
        j.insert("values".into(), values_json(&values));
        details.push(values_text(&values));
    }
    match cmd {
        Command::SyncRead { ids, .. } => {
            j.insert("ids".into(), json!(ids));
            let _ = write!(text, "; from IDs {ids:?}");
        }
        Command::SyncWrite(s) => {
            let mut servos = Vec::new();
            for (id, block) in s.blocks() {
                let (_, values) = registers_of(map, address, len, Some(block));
                servos.push(json!({
                    "id": id,
                    "data": hex(block),
                    "values": values_json(&values),
                }));
                details.push(format!(
                    "servo {id}: {}  {}",
                    hex(block),
                    values_text(&values)
                ));
            }
            j.insert("servos".into(), Value::Array(servos));
            let _ = write!(text, "; {} servo(s)", s.servos());
        }
        _ => {}
    }
}

fn values_json(values: &[(&str, i32)]) -> Value {
    Value::Object(
        values
            .iter()
            .map(|(n, v)| ((*n).to_owned(), json!(v)))
            .collect(),
    )
}

fn values_text(values: &[(&str, i32)]) -> String {
    values
        .iter()
        .map(|(n, v)| format!("{n}={v}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn problem_item(
    stream: &[u8],
    at: usize,
    span: &[u8],
    reason: DiscardReason,
    checksum: Option<(u8, u8, u8)>,
) -> Item {
    let mut j = Map::new();
    j.insert("offset".into(), json!(at));
    j.insert("len".into(), json!(span.len()));
    j.insert("bytes".into(), json!(hex(span)));
    let n = span.len();
    let text = match (reason, checksum) {
        (DiscardReason::Checksum, Some((id, expected, found))) => {
            j.insert("kind".into(), json!("bad_checksum"));
            j.insert("id".into(), json!(id));
            j.insert("checksum".into(), json!("bad"));
            j.insert("found".into(), json!(found));
            j.insert("expected".into(), json!(expected));
            format!(
                "bad checksum at {at}: frame from ID {id} carries 0x{found:02X}, its bytes give \
                 0x{expected:02X}; {n} byte(s) skipped: {}",
                hex(span)
            )
        }
        (DiscardReason::Truncated, _) => {
            j.insert("kind".into(), json!("truncated"));
            // The length byte, when present, says how long the frame was meant to be.
            let needed = stream
                .get(at + 3)
                .map(|&l| FRAME_OVERHEAD + usize::from(l).saturating_sub(2));
            let available = stream.len() - at;
            j.insert("needed".into(), json!(needed));
            j.insert("available".into(), json!(available));
            match needed {
                Some(needed) => format!(
                    "truncated frame at {at}: needs {needed} bytes, the input has {available}: {}",
                    hex(span)
                ),
                None => format!(
                    "truncated frame at {at}: input ends inside the header: {}",
                    hex(span)
                ),
            }
        }
        (DiscardReason::InvalidId, _) => {
            j.insert("kind".into(), json!("invalid_id"));
            format!(
                "invalid header at {at} (ID byte 0xFF), {n} byte(s) skipped: {}",
                hex(span)
            )
        }
        (DiscardReason::BadLength, _) => {
            j.insert("kind".into(), json!("bad_length"));
            format!(
                "impossible length byte at {at} (below 2), {n} byte(s) skipped: {}",
                hex(span)
            )
        }
        _ => {
            j.insert("kind".into(), json!("garbage"));
            format!("garbage at {at}: {n} byte(s): {}", hex(span))
        }
    };
    Item {
        is_packet: false,
        text,
        json: j,
    }
}
