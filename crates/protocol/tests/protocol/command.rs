//! Instruction packets read back as commands, including malformed ones.

use servobus_protocol::{checksum, parse_frame, Command, CommandError, Instruction};

/// A frame with any fifth byte and parameters (valid checksum).
fn frame(id: u8, code: u8, params: &[u8]) -> Vec<u8> {
    let mut f = vec![0xFF, 0xFF, id, params.len() as u8 + 2, code];
    f.extend_from_slice(params);
    let sum = checksum(&f[2..]);
    f.push(sum);
    f
}

fn command(f: &[u8]) -> Result<Command<'_>, CommandError> {
    parse_frame(f).expect("valid frame").0.command()
}

#[test]
fn well_formed_commands() {
    let f = frame(1, 0x02, &[56, 2]);
    let c = command(&f).unwrap();
    assert_eq!(
        c,
        Command::Read {
            address: 56,
            len: 2
        }
    );
    assert_eq!(c.span(), Some((56, 2)));
    assert_eq!(c.instruction(), Instruction::Read);

    let f = frame(0xFE, 0x83, &[42, 2, 1, 0x00, 0x08, 2, 0xFF, 0x0F]);
    let Command::SyncWrite(s) = command(&f).unwrap() else {
        panic!("not a SYNC WRITE")
    };
    assert_eq!(s.servos(), 2);
    assert_eq!(s.block_for(2), Some(&[0xFF, 0x0F][..]));
    assert_eq!(s.block_for(3), None);
    let blocks: Vec<_> = s.blocks().collect();
    assert_eq!(blocks, [(1, &[0x00, 0x08][..]), (2, &[0xFF, 0x0F][..])]);

    let f = frame(0xFE, 0x82, &[56, 2, 1, 2, 3]);
    assert_eq!(
        command(&f).unwrap(),
        Command::SyncRead {
            address: 56,
            len: 2,
            ids: &[1, 2, 3]
        }
    );
    let f = frame(1, 0x05, &[]);
    assert_eq!(command(&f).unwrap().span(), None);
}

#[test]
fn malformed_commands_are_typed_errors() {
    let cases: [(u8, &[u8], Instruction); 8] = [
        (0x01, &[0], Instruction::Ping),
        (0x02, &[56], Instruction::Read),
        (0x02, &[56, 2, 0], Instruction::Read),
        (0x03, &[42], Instruction::Write),
        (0x04, &[], Instruction::RegWrite),
        (0x82, &[56, 2], Instruction::SyncRead),
        (0x83, &[42, 2, 1, 0], Instruction::SyncWrite),
        (0x83, &[42, 0], Instruction::SyncWrite),
    ];
    for (code, params, inst) in cases {
        let f = frame(1, code, params);
        match command(&f) {
            Err(CommandError::BadParams {
                instruction, len, ..
            }) => {
                assert_eq!((instruction, len), (inst, params.len()), "{code:02X}");
            }
            other => panic!("{code:02X} {params:?}: {other:?}"),
        }
    }
    let f = frame(1, 0x55, &[]);
    assert_eq!(command(&f), Err(CommandError::UnknownInstruction(0x55)));
}

#[test]
fn every_command_encodes_back_to_the_frame_it_was_read_from() {
    // Frames built byte by byte (not by the encoders under test), one per
    // instruction.
    let frames = [
        frame(3, 0x01, &[]),
        frame(3, 0x02, &[56, 2]),
        frame(3, 0x03, &[42, 0x00, 0x08]),
        frame(0xFE, 0x04, &[40, 1]),
        frame(0xFE, 0x05, &[]),
        frame(3, 0x06, &[]),
        frame(0xFE, 0x82, &[56, 2, 1, 2, 3]),
        frame(0xFE, 0x83, &[42, 2, 1, 0x00, 0x08, 2, 0xFF, 0x0F]),
    ];
    for f in &frames {
        let c = command(f).unwrap();
        let mut buf = [0u8; 64];
        let n = servobus_protocol::encode::command(&mut buf, f[2], &c)
            .unwrap_or_else(|e| panic!("{c:?} does not encode: {e}"));
        assert_eq!(&buf[..n], &f[..], "{c:?}");
    }
    // One frame with its checksum worked by hand, so that a checksum the
    // encoder and `frame` got wrong alike cannot pass: ~(3 + 4 + 2 + 56 + 2)
    // = ~67 = 0xBC.
    assert_eq!(frames[1], [0xFF, 0xFF, 3, 4, 0x02, 56, 2, 0xBC]);
}
