//! The simulator's memory is the protocol crate's register maps: every
//! register of every model, byte order, access and factory value, checked
//! one by one, so that the simulator and the driver cannot disagree.

use std::time::Duration;

use servobus_protocol::registers::{self, Access, ByteOrder, MODELS};
use servobus_sim::{SimModel, SimServo};

#[test]
fn every_protocol_model_is_simulated() {
    for model in &MODELS {
        let sim = SimModel::by_number(model.number).expect("simulated");
        assert_eq!(sim.model, *model);
        assert_eq!(SimModel::by_name(&model.name.to_lowercase()), Some(sim));
    }
}

#[test]
fn factory_memory_agrees_with_the_protocol_maps_register_by_register() {
    for sim in &SimModel::ALL {
        let map = sim.model.series.map();
        let table = sim.factory_table();
        let mut covered = vec![false; table.len()];
        for reg in map.registers {
            let bytes = &table[usize::from(reg.address)..usize::from(reg.end())];
            let expected = if reg.name == "model_number" {
                i32::from(sim.model.number)
            } else {
                reg.from_raw(u32::from(reg.factory))
            };
            let value = reg.decode(bytes, map.byte_order);
            assert_eq!(value, Ok(expected), "{} {}", sim.name(), reg.name);
            for a in reg.address..(reg.end() as u8) {
                assert_eq!(sim.area(usize::from(a)), reg.access, "{} {a}", sim.name());
                covered[usize::from(a)] = true;
            }
        }
        // Bytes no register covers are reserved: zero and read-only.
        for (a, &c) in covered.iter().enumerate() {
            if !c {
                assert_eq!(table[a], 0, "{} reserved byte {a}", sim.name());
                assert_eq!(
                    sim.area(a),
                    Access::ReadOnly,
                    "{} reserved byte {a}",
                    sim.name()
                );
            }
        }
        assert_eq!(sim.area(table.len() + 3), Access::ReadOnly);
    }
}

#[test]
fn byte_order_and_well_known_factory_values() {
    // Written out by hand from the control-tables reference, not from the
    // maps: model number 777 = 0x0309 little-endian, 1284 = 0x0504 big-endian.
    let sts = SimModel::STS3215.factory_table();
    assert_eq!(&sts[3..5], &[0x09, 0x03]);
    assert_eq!(sts[7], 250, "factory return delay 500 us");
    assert_eq!(&sts[11..13], &[0xFF, 0x0F], "max angle limit 4095");
    assert_eq!(sts[55], 1, "lock closed");
    let scs = SimModel::SCS0009.factory_table();
    assert_eq!(&scs[3..5], &[0x05, 0x04]);
    assert_eq!(&scs[11..13], &[0x03, 0xFF], "max angle limit 1023");
    assert_eq!(scs[48], 1, "SCS lock at 48");
    assert_eq!(SimModel::STS3215.byte_order(), ByteOrder::Little);
    assert_eq!(SimModel::SCS0009.byte_order(), ByteOrder::Big);
}

#[test]
fn a_new_servo_holds_the_factory_eeprom() {
    for sim in &SimModel::ALL {
        let servo = SimServo::new(sim, 7);
        let table = sim.factory_table();
        for reg in sim.map().registers {
            if reg.access != Access::Eeprom {
                continue;
            }
            let got = servo.read(reg.address, usize::from(reg.size));
            let want: &[u8] = if reg.address == registers::addr::ID {
                &[7]
            } else {
                &table[usize::from(reg.address)..usize::from(reg.end())]
            };
            assert_eq!(got, want, "{} {}", sim.name(), reg.name);
        }
    }
}

#[test]
fn signed_registers_use_the_protocol_crates_sign_bits() {
    // Written out by hand from the control-tables reference: the homing
    // offset's sign is bit 11, present speed's bit 15, low byte first.
    let mut servo = SimServo::sts3215(1);
    assert_eq!(
        servo.present_position(),
        2048,
        "a new servo rests at mid-travel"
    );
    // Offset -100: 0x0800 | 100 = 0x0864. Present = raw - offset.
    servo.write(registers::addr::OFFSET, &[0x64, 0x08]);
    assert_eq!(servo.present_position(), 2148);
    servo.write(registers::addr::OFFSET, &[0x64, 0x00]);
    assert_eq!(servo.present_position(), 1948);

    // Moving towards lower positions: a negative speed, sign bit 15 set.
    servo.write(registers::addr::TORQUE_ENABLE, &[1]);
    servo.write(registers::addr::GOAL_POSITION, &1000u16.to_le_bytes());
    servo.advance_to(Duration::from_millis(200));
    let bytes = servo.read(registers::addr::PRESENT_SPEED, 2);
    assert_eq!(bytes[1] & 0x80, 0x80, "sign bit 15 set: {bytes:?}");
    let magnitude = i32::from(u16::from_le_bytes([bytes[0], bytes[1] & 0x7F]));
    assert!(magnitude > 0);
    assert_eq!(servo.present_speed(), -magnitude);
}
