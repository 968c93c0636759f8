//! The instructions (and status replies) as plain data: generated,
//! encoded, and read back through `Packet::command`.

use proptest::prelude::*;
use servobus_protocol::{encode, parse_frame, Command, StatusFlags, BROADCAST_ID, MAX_FRAME_LEN};

/// What the host (or a servo) says, as plain data.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Op {
    Ping(u8),
    Read(u8, u8, u8),
    Write(u8, u8, Vec<u8>),
    RegWrite(u8, u8, Vec<u8>),
    Action(u8),
    Reset(u8),
    SyncRead(u8, u8, Vec<u8>),
    SyncWrite(u8, u8, Vec<(u8, Vec<u8>)>),
    Status(u8, u8, Vec<u8>),
}

pub fn servo_id() -> impl Strategy<Value = u8> {
    0u8..=253
}

fn any_id() -> impl Strategy<Value = u8> {
    prop_oneof![servo_id(), Just(BROADCAST_ID)]
}

pub fn op() -> impl Strategy<Value = Op> {
    let data = proptest::collection::vec(any::<u8>(), 1..=40);
    prop_oneof![
        any_id().prop_map(Op::Ping),
        (servo_id(), any::<u8>(), 1u8..=255).prop_map(|(i, a, l)| Op::Read(i, a, l)),
        (any_id(), any::<u8>(), data.clone()).prop_map(|(i, a, d)| Op::Write(i, a, d)),
        (any_id(), any::<u8>(), data).prop_map(|(i, a, d)| Op::RegWrite(i, a, d)),
        any_id().prop_map(Op::Action),
        any_id().prop_map(Op::Reset),
        (
            any::<u8>(),
            1u8..=255,
            proptest::collection::vec(servo_id(), 1..=30)
        )
            .prop_map(|(a, l, ids)| Op::SyncRead(a, l, ids)),
        (any::<u8>(), 1u8..=12)
            .prop_flat_map(|(a, l)| {
                let block = proptest::collection::vec(any::<u8>(), usize::from(l));
                let max = 251 / (usize::from(l) + 1);
                (
                    Just(a),
                    Just(l),
                    proptest::collection::vec((servo_id(), block), 1..=max.min(20)),
                )
            })
            .prop_map(|(a, l, blocks)| Op::SyncWrite(a, l, blocks)),
        (
            servo_id(),
            any::<u8>(),
            proptest::collection::vec(any::<u8>(), 0..=40)
        )
            .prop_map(|(i, f, p)| Op::Status(i, f, p)),
    ]
}

fn encode_op(op: &Op, buf: &mut [u8]) -> usize {
    let r = match op {
        Op::Ping(id) => encode::ping(buf, *id),
        Op::Read(id, a, l) => encode::read(buf, *id, *a, *l),
        Op::Write(id, a, d) => encode::write(buf, *id, *a, d),
        Op::RegWrite(id, a, d) => encode::reg_write(buf, *id, *a, d),
        Op::Action(id) => encode::action(buf, *id),
        Op::Reset(id) => encode::reset(buf, *id),
        Op::SyncRead(a, l, ids) => encode::sync_read(buf, *a, *l, ids),
        Op::SyncWrite(a, l, blocks) => {
            encode::sync_write(buf, *a, *l, blocks.iter().map(|(i, d)| (*i, d.as_slice())))
        }
        Op::Status(id, f, p) => encode::status(buf, *id, StatusFlags(*f), p),
    };
    r.expect("valid op encodes")
}

pub fn encoded(op: &Op) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode_op(op, &mut buf);
    buf[..n].to_vec()
}

/// Reads a frame back into an [`Op`]: the inverse of [`encode_op`].
pub fn interpret(frame: &[u8], from_servo: bool) -> Op {
    let (p, used) = parse_frame(frame).expect("parses");
    assert_eq!(used, frame.len());
    if from_servo {
        return Op::Status(p.id(), p.status().bits(), p.params().to_vec());
    }
    let id = p.id();
    match p.command().expect("a valid command") {
        Command::Ping => Op::Ping(id),
        Command::Read { address, len } => Op::Read(id, address, len),
        Command::Write { address, data } => Op::Write(id, address, data.to_vec()),
        Command::RegWrite { address, data } => Op::RegWrite(id, address, data.to_vec()),
        Command::Action => Op::Action(id),
        Command::Reset => Op::Reset(id),
        Command::SyncRead { address, len, ids } => {
            assert_eq!(id, BROADCAST_ID);
            Op::SyncRead(address, len, ids.to_vec())
        }
        Command::SyncWrite(s) => {
            assert_eq!(id, BROADCAST_ID);
            Op::SyncWrite(
                s.address,
                s.len,
                s.blocks().map(|(i, d)| (i, d.to_vec())).collect(),
            )
        }
    }
}
