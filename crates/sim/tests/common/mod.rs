//! Helpers shared by the simulator's integration tests: raw frames in, raw
//! bytes out, in virtual time.
#![allow(dead_code)]

use std::time::Duration;

use servobus_io::{Clock, ManualClock, Transport, TransportError};
use servobus_protocol::{encode, parse_frame};
use servobus_sim::{SimBus, SimServo};

/// A bus at 1 Mbps with STS3215 servos of the given IDs, return delay 0.
pub fn bus_with(ids: &[u8]) -> SimBus {
    let bus = SimBus::new(ManualClock::new(), 1_000_000);
    for &id in ids {
        bus.add_servo(SimServo::sts3215(id).with_return_delay(Duration::ZERO));
    }
    bus
}

/// Sends `frame` and collects every byte that arrives within `wait` after
/// the request has left.
pub fn exchange(bus: &mut SimBus, frame: &[u8], wait: Duration) -> Vec<u8> {
    bus.discard_input().unwrap();
    bus.write_all(frame).unwrap();
    let deadline = bus.clock().now() + wait;
    let mut out = Vec::new();
    let mut buf = [0u8; 64];
    loop {
        match bus.read(&mut buf, deadline) {
            Ok(n) => out.extend_from_slice(&buf[..n]),
            Err(TransportError::TimedOut) => return out,
            Err(e) => panic!("transport failed: {e}"),
        }
    }
}

/// Splits a byte stream into frames (panics on anything else).
pub fn frames(mut bytes: &[u8]) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    while !bytes.is_empty() {
        let (p, n) = parse_frame(bytes).expect("a valid frame");
        out.push(p.bytes().to_vec());
        bytes = &bytes[n..];
    }
    out
}

pub fn ping(id: u8) -> Vec<u8> {
    let mut b = [0u8; 8];
    let n = encode::ping(&mut b, id).unwrap();
    b[..n].to_vec()
}

pub fn read(id: u8, address: u8, len: u8) -> Vec<u8> {
    let mut b = [0u8; 8];
    let n = encode::read(&mut b, id, address, len).unwrap();
    b[..n].to_vec()
}

pub fn write(id: u8, address: u8, data: &[u8]) -> Vec<u8> {
    let mut b = [0u8; 300];
    let n = encode::write(&mut b, id, address, data).unwrap();
    b[..n].to_vec()
}

pub fn reg_write(id: u8, address: u8, data: &[u8]) -> Vec<u8> {
    let mut b = [0u8; 300];
    let n = encode::reg_write(&mut b, id, address, data).unwrap();
    b[..n].to_vec()
}

pub fn action(id: u8) -> Vec<u8> {
    let mut b = [0u8; 8];
    let n = encode::action(&mut b, id).unwrap();
    b[..n].to_vec()
}

pub fn reset(id: u8) -> Vec<u8> {
    let mut b = [0u8; 8];
    let n = encode::reset(&mut b, id).unwrap();
    b[..n].to_vec()
}

pub fn sync_read(address: u8, len: u8, ids: &[u8]) -> Vec<u8> {
    let mut b = [0u8; 300];
    let n = encode::sync_read(&mut b, address, len, ids).unwrap();
    b[..n].to_vec()
}

pub fn sync_write(address: u8, items: &[(u8, &[u8])]) -> Vec<u8> {
    let mut b = [0u8; 300];
    let len = items[0].1.len() as u8;
    let n = encode::sync_write(&mut b, address, len, items.iter().copied()).unwrap();
    b[..n].to_vec()
}

/// The status frame servo `id` sends with error byte `err` and `params`.
pub fn status(id: u8, err: u8, params: &[u8]) -> Vec<u8> {
    let mut b = [0u8; 300];
    let n = encode::status(&mut b, id, servobus_protocol::StatusFlags(err), params).unwrap();
    b[..n].to_vec()
}

pub const MS: Duration = Duration::from_millis(1);

/// Sends `frame` and checks that the servo it names acknowledges it: an
/// empty status without error flags, from that ID.
pub fn assert_acked(bus: &mut SimBus, frame: &[u8]) {
    let id = frame[2];
    assert_eq!(exchange(bus, frame, MS), status(id, 0, &[]), "{frame:02X?}");
}

/// Advances the bus's clock by `d`.
pub fn wait(bus: &SimBus, d: Duration) {
    bus.clock().advance(d);
}

pub fn now(bus: &SimBus) -> Duration {
    bus.clock().now()
}
