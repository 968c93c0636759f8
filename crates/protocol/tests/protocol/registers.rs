//! Register maps: lookup, layout invariants and value conversion.

use std::time::Duration;

use servobus_protocol::registers::{
    self, addr, baud_index, baud_rate, model_by_name, model_by_number, next_baud_above,
    return_delay_from_register, Access, ByteOrder, Series, ValueError, FACTORY_RETURN_DELAY,
    MODELS, SCS, STS,
};

#[test]
fn maps_are_sorted_without_overlap() {
    for map in [&STS, &SCS] {
        for pair in map.registers.windows(2) {
            assert!(
                pair[0].end() <= u16::from(pair[1].address),
                "{} overlaps {} in {:?}",
                pair[0].name,
                pair[1].name,
                map.series
            );
        }
        for r in map.registers {
            assert!(r.size == 1 || r.size == 2, "{}", r.name);
            if let Some(bit) = r.sign_bit {
                assert!(bit < 8 * r.size, "{}", r.name);
            }
            // Every canonical name finds itself.
            assert_eq!(map.get(r.name), Some(r));
        }
    }
}

#[test]
fn lookup_is_forgiving() {
    let pos = STS.get("present_position").unwrap();
    for name in [
        "Present_Position",
        "PRESENT-POSITION",
        "presentPosition",
        "present position",
    ] {
        assert_eq!(STS.get(name), Some(pos), "{name}");
    }
    assert_eq!(STS.get("Homing_Offset").unwrap().address, 31);
    assert_eq!(STS.get("goal_velocity").unwrap().address, 46);
    assert_eq!(STS.get("Present_Velocity").unwrap().address, 58);
    assert_eq!(STS.get("no_such_register"), None);
    assert_eq!(STS.get("present_positio"), None);
    // SCS has no offset register.
    assert_eq!(SCS.get("offset"), None);
}

#[test]
fn addr_constants_match_the_sts_map() {
    let pairs = [
        ("firmware_major", addr::FIRMWARE_MAJOR),
        ("firmware_minor", addr::FIRMWARE_MINOR),
        ("model_number", addr::MODEL_NUMBER),
        ("id", addr::ID),
        ("baud_rate", addr::BAUD_RATE),
        ("return_delay", addr::RETURN_DELAY),
        ("status_level", addr::STATUS_LEVEL),
        ("min_angle_limit", addr::MIN_ANGLE_LIMIT),
        ("max_angle_limit", addr::MAX_ANGLE_LIMIT),
        ("offset", addr::OFFSET),
        ("mode", addr::MODE),
        ("torque_enable", addr::TORQUE_ENABLE),
        ("acceleration", addr::ACCELERATION),
        ("goal_position", addr::GOAL_POSITION),
        ("goal_time", addr::GOAL_TIME),
        ("goal_speed", addr::GOAL_SPEED),
        ("torque_limit", addr::TORQUE_LIMIT),
        ("lock", addr::LOCK),
        ("present_position", addr::PRESENT_POSITION),
        ("present_speed", addr::PRESENT_SPEED),
        ("present_load", addr::PRESENT_LOAD),
        ("present_voltage", addr::PRESENT_VOLTAGE),
        ("present_temperature", addr::PRESENT_TEMPERATURE),
        ("async_flag", addr::ASYNC_FLAG),
        ("status", addr::STATUS),
        ("moving", addr::MOVING),
        ("present_current", addr::PRESENT_CURRENT),
    ];
    for (name, a) in pairs {
        assert_eq!(STS.get(name).map(|r| r.address), Some(a), "{name}");
    }
    assert_eq!(SCS.get("lock").unwrap().address, addr::SCS_LOCK);
    assert_eq!(STS.lock_address, 55);
    assert_eq!(SCS.lock_address, 48);
    assert_eq!(STS.at(addr::LOCK).unwrap().access, Access::Ram);
    assert_eq!(STS.at(addr::ID).unwrap().access, Access::Eeprom);
    assert_eq!(
        STS.at(addr::PRESENT_POSITION).unwrap().access,
        Access::ReadOnly
    );
}

#[test]
fn series_properties() {
    assert_eq!(Series::Sts.byte_order(), ByteOrder::Little);
    assert_eq!(Series::Scs.byte_order(), ByteOrder::Big);
    assert!(Series::Sts.has_sync_read());
    assert!(!Series::Scs.has_sync_read());
    assert_eq!(Series::Sts.map().series, Series::Sts);
    assert_eq!(Series::Scs.map().byte_order, ByteOrder::Big);
}

#[test]
fn scs_registers_moved_from_the_sts_layout() {
    // The SCS control table puts these at other addresses than STS/SMS
    // does (protection at 37 and 38 instead of 34 and 35, the lock at 48
    // instead of 55); what they are is the same.
    // Sizes, kinds and units as the manual's SCS table gives them.
    for (name, scs_at, sts_at, access, unit) in [
        ("protective_torque", 37, 34, Access::Eeprom, "%"),
        ("protection_time", 38, 35, Access::Eeprom, "10 ms"),
        ("lock", 48, 55, Access::Ram, ""),
    ] {
        let (scs, sts) = (SCS.get(name).unwrap(), STS.get(name).unwrap());
        assert_eq!((scs.address, sts.address), (scs_at, sts_at), "{name}");
        assert_eq!(
            (scs.size, scs.access, scs.unit),
            (1, access, unit),
            "{name}"
        );
    }
}

#[test]
fn sign_bits_are_as_documented() {
    let bit = |name| STS.get(name).unwrap().sign_bit;
    assert_eq!(bit("goal_position"), Some(15));
    assert_eq!(bit("goal_speed"), Some(15));
    assert_eq!(bit("present_position"), Some(15));
    assert_eq!(bit("present_speed"), Some(15));
    assert_eq!(bit("present_load"), Some(10));
    assert_eq!(bit("offset"), Some(11));
    assert_eq!(bit("present_current"), Some(15));
    assert_eq!(bit("goal_time"), None);
    assert_eq!(SCS.get("goal_position").unwrap().sign_bit, None);
}

#[test]
fn covering_finds_every_touched_register() {
    // A 7-byte block from 41: acceleration, goal position, time, speed.
    let names: Vec<_> = STS.covering(41, 7).map(|r| r.name).collect();
    assert_eq!(
        names,
        ["acceleration", "goal_position", "goal_time", "goal_speed"]
    );
    // Starting inside a register still names it.
    let names: Vec<_> = STS.covering(57, 2).map(|r| r.name).collect();
    assert_eq!(names, ["present_position", "present_speed"]);
    assert_eq!(STS.covering(2, 1).count(), 0);
    assert_eq!(STS.containing(57).unwrap().name, "present_position");
    assert_eq!(STS.at(57), None);
    // Reaching past 255 does not overflow.
    assert_eq!(STS.covering(255, 255).count(), 0);
}

#[test]
fn signed_values_in_both_byte_orders() {
    let pos = STS.get("goal_position").unwrap();
    let mut b = [0u8; 2];
    pos.encode(-2047, ByteOrder::Little, &mut b).unwrap();
    assert_eq!(b, [0xFF, 0x87]);
    assert_eq!(pos.decode(&b, ByteOrder::Little), Ok(-2047));
    pos.encode(-2047, ByteOrder::Big, &mut b).unwrap();
    assert_eq!(b, [0x87, 0xFF]);
    assert_eq!(pos.decode(&b, ByteOrder::Big), Ok(-2047));
    pos.encode(4095, ByteOrder::Little, &mut b).unwrap();
    assert_eq!(b, [0xFF, 0x0F]);

    let load = STS.get("present_load").unwrap();
    assert_eq!(load.decode(&[0xE8, 0x07], ByteOrder::Little), Ok(-1000));
    assert_eq!(load.decode(&[0x03, 0xE8], ByteOrder::Big), Ok(1000));
    assert_eq!(load.range(), (-1023, 1023));

    let offset = STS.get("offset").unwrap();
    assert_eq!(offset.range(), (-2047, 2047));
    assert_eq!(offset.decode(&[0x00, 0x08], ByteOrder::Little), Ok(0)); // "-0"
    assert_eq!(offset.decode(&[0x01, 0x08], ByteOrder::Little), Ok(-1));
}

#[test]
fn range_and_length_errors() {
    let offset = STS.get("offset").unwrap();
    let mut b = [0u8; 2];
    assert_eq!(
        offset.encode(2048, ByteOrder::Little, &mut b),
        Err(ValueError::OutOfRange {
            register: "offset",
            value: 2048,
            min: -2047,
            max: 2047
        })
    );
    let id = STS.get("id").unwrap();
    assert_eq!(id.range(), (0, 255));
    assert!(matches!(
        id.encode(-1, ByteOrder::Little, &mut b[..1]),
        Err(ValueError::OutOfRange { value: -1, .. })
    ));
    assert_eq!(
        id.encode(1, ByteOrder::Little, &mut b),
        Err(ValueError::Length {
            register: "id",
            expected: 1,
            actual: 2
        })
    );
    assert!(matches!(
        STS.get("goal_time").unwrap().decode(&[1], ByteOrder::Big),
        Err(ValueError::Length {
            expected: 2,
            actual: 1,
            ..
        })
    ));
    let time = STS.get("goal_time").unwrap();
    time.encode(65535, ByteOrder::Big, &mut b).unwrap();
    assert_eq!(b, [0xFF, 0xFF]);
    assert!(time.encode(65536, ByteOrder::Big, &mut b).is_err());
}

#[test]
fn every_value_in_range_round_trips() {
    for map in [&STS, &SCS] {
        for r in map.registers {
            let (min, max) = r.range();
            let step = ((max - min) / 997).max(1);
            let mut v = min;
            while v <= max {
                for order in [ByteOrder::Little, ByteOrder::Big] {
                    let mut b = [0u8; 2];
                    let out = &mut b[..usize::from(r.size)];
                    r.encode(v, order, out).unwrap();
                    assert_eq!(r.decode(out, order), Ok(v), "{} {v}", r.name);
                }
                v += step;
            }
        }
    }
}

#[test]
fn models() {
    assert_eq!(model_by_number(777).unwrap().name, "STS3215");
    assert_eq!(model_by_number(2825).unwrap().name, "STS3250");
    assert_eq!(model_by_number(11272).unwrap().name, "SM8512BL");
    let scs = model_by_number(1284).unwrap();
    assert_eq!((scs.name, scs.series), ("SCS0009", Series::Scs));
    assert_eq!(scs.resolution, 1024);
    assert_eq!(model_by_name("sts3215").unwrap().number, 777);
    assert_eq!(model_by_name("STS-3215").unwrap().number, 777);
    assert_eq!(model_by_name("scs15").unwrap().series, Series::Scs);
    assert!(model_by_name("xl330").is_none());
    assert!(model_by_number(0).is_none());
    let sts = model_by_name("sts3215").unwrap();
    assert!((sts.deg_per_tick() - 360.0 / 4096.0).abs() < 1e-12);
    assert_eq!(sts.max_position(), 4095);
    for m in &MODELS {
        assert_eq!(model_by_number(m.number), Some(m));
        assert_eq!(m.map().series, m.series);
    }
}

#[test]
fn a_model_register_is_read_in_either_byte_order() {
    // STS3215 = 777 = 0x0309, little-endian on the wire: 09 03.
    assert_eq!(
        registers::model_by_register([0x09, 0x03]).map(|m| m.name),
        Some("STS3215")
    );
    // SCS0009 = 1284 = 0x0504, big-endian on the wire: 05 04.
    assert_eq!(
        registers::model_by_register([0x05, 0x04]).map(|m| m.name),
        Some("SCS0009")
    );
    assert!(registers::model_by_register([0, 0]).is_none());
    // No model's number, byte-swapped, is another model's.
    for m in &MODELS {
        let swapped = m.number.swap_bytes();
        assert!(model_by_number(swapped).is_none(), "{}", m.name);
    }
}

#[test]
fn baud_table() {
    assert_eq!(baud_rate(0), Some(1_000_000));
    assert_eq!(baud_rate(5), Some(76_800));
    assert_eq!(baud_rate(7), Some(38_400));
    assert_eq!(baud_rate(8), None);
    assert_eq!(baud_rate(255), None);
    assert_eq!(baud_rate(4), Some(115_200));
    for i in 0..8 {
        assert_eq!(baud_index(baud_rate(i).unwrap()), Some(i));
    }
    assert_eq!(baud_index(9600), None);
    assert_eq!(next_baud_above(38_400), Some(57_600));
    assert_eq!(next_baud_above(100_000), Some(115_200));
    assert_eq!(next_baud_above(1_000_000), None);
    assert_eq!(next_baud_above(0), Some(38_400));
    assert_eq!(FACTORY_RETURN_DELAY, Duration::from_micros(500));
    assert_eq!(return_delay_from_register(255), Duration::from_micros(510));
    assert_eq!(registers::sign_magnitude(0x8001, 15), -1);
}

#[test]
fn goal_and_present_speed_are_sign_magnitude_at_zero_one_and_the_top() {
    // The manual's rule for a wheel's speed (steps/s): bit 15 is the
    // direction, the other 15 bits the magnitude; low byte first on STS.
    for name in ["goal_speed", "present_speed"] {
        let reg = STS.get(name).unwrap();
        let (lo, hi) = reg.range();
        assert_eq!((lo, hi), (-0x7FFF, 0x7FFF), "{name}");
        let mut b = [0u8; 2];
        for (value, bytes) in [
            (0, [0x00, 0x00]),
            (1, [0x01, 0x00]),
            (-1, [0x01, 0x80]),
            (hi, [0xFF, 0x7F]),
            (lo, [0xFF, 0xFF]),
            (3000, [0xB8, 0x0B]),
            (-3000, [0xB8, 0x8B]),
        ] {
            reg.encode(value, ByteOrder::Little, &mut b).unwrap();
            assert_eq!(b, bytes, "{name} {value}");
            assert_eq!(reg.decode(&bytes, ByteOrder::Little), Ok(value), "{name}");
        }
        // "-0": the sign bit alone is 0, as a servo may report at rest.
        assert_eq!(
            reg.decode(&[0x00, 0x80], ByteOrder::Little),
            Ok(0),
            "{name}"
        );
        assert!(
            reg.encode(hi + 1, ByteOrder::Little, &mut b).is_err(),
            "{name}"
        );
    }
}
