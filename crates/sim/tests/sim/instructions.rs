//! Every instruction, answered byte for byte as the real servo does.

use crate::common;

use std::time::Duration;

use common::*;
use servobus_sim::{addr, SimBus, SimServo};

#[test]
fn ping_is_answered_with_an_empty_status() {
    let mut bus = bus_with(&[1]);
    assert_eq!(exchange(&mut bus, &ping(1), MS), status(1, 0, &[]));
    assert_eq!(exchange(&mut bus, &ping(2), MS), Vec::<u8>::new());
}

#[test]
fn read_returns_the_factory_table_with_model_and_firmware() {
    let mut bus = bus_with(&[1]);
    // Firmware 3.10, model 777 little-endian at 3, ID 1, baud 0, return delay 0.
    let got = exchange(&mut bus, &read(1, 0, 9), MS);
    assert_eq!(got, status(1, 0, &[3, 10, 0, 0x09, 0x03, 1, 0, 0, 1]));
    // Max angle limit 4095, max temperature 70.
    let got = exchange(&mut bus, &read(1, addr::MAX_ANGLE_LIMIT, 3), MS);
    assert_eq!(got, status(1, 0, &[0xFF, 0x0F, 70]));
}

#[test]
fn reads_past_the_table_end_answer_zeros() {
    let mut bus = bus_with(&[1]);
    // The STS table ends at 86: bytes 85 and 86 are real, 87.. read as 0.
    let got = exchange(&mut bus, &read(1, 85, 4), MS);
    assert_eq!(got, status(1, 0, &[150, 50, 0, 0]));
    let got = exchange(&mut bus, &read(1, 250, 6), MS);
    assert_eq!(got, status(1, 0, &[0; 6]));
}

#[test]
fn write_applies_and_read_only_registers_refuse() {
    let mut bus = bus_with(&[1]);
    assert_acked(&mut bus, &write(1, addr::ACCELERATION, &[20]));
    assert_eq!(bus.register(1, addr::ACCELERATION), Some(20));
    // Model number and present position are read-only: acknowledged, unchanged.
    assert_acked(&mut bus, &write(1, addr::MODEL_NUMBER, &[0, 0]));
    assert_eq!(bus.servo(1, |s| s.read_u16(addr::MODEL_NUMBER)), Some(777));
    let before = bus.present_position(1);
    exchange(&mut bus, &write(1, addr::PRESENT_POSITION, &[0, 0]), MS);
    assert_eq!(bus.present_position(1), before);
}

#[test]
fn status_level_zero_answers_only_ping_and_read() {
    let mut bus = bus_with(&[1]);
    bus.servo(1, |s| s.write(addr::STATUS_LEVEL, &[0]));
    assert!(exchange(&mut bus, &write(1, addr::ACCELERATION, &[5]), MS).is_empty());
    assert_eq!(
        bus.register(1, addr::ACCELERATION),
        Some(5),
        "the write still applies"
    );
    assert!(exchange(&mut bus, &reg_write(1, addr::ACCELERATION, &[6]), MS).is_empty());
    assert!(exchange(&mut bus, &action(1), MS).is_empty());
    assert_eq!(bus.register(1, addr::ACCELERATION), Some(6));
    assert_eq!(exchange(&mut bus, &ping(1), MS), status(1, 0, &[]));
    assert_eq!(
        exchange(&mut bus, &read(1, addr::ACCELERATION, 1), MS),
        status(1, 0, &[6])
    );
}

#[test]
fn scs_status_levels_have_three_steps() {
    let mut bus = SimBus::new(servobus_io::ManualClock::new(), 1_000_000)
        .with_servo(SimServo::scs0009(3).with_status_level(0));
    assert_eq!(exchange(&mut bus, &ping(3), MS), status(3, 0, &[]));
    assert!(exchange(&mut bus, &read(3, 5, 1), MS).is_empty());
    bus.servo(3, |s| s.write(addr::STATUS_LEVEL, &[1]));
    assert_eq!(exchange(&mut bus, &read(3, 5, 1), MS), status(3, 0, &[3]));
    assert!(exchange(&mut bus, &write(3, addr::ACCELERATION, &[1]), MS).is_empty());
    bus.servo(3, |s| s.write(addr::STATUS_LEVEL, &[2]));
    assert_acked(&mut bus, &write(3, addr::ACCELERATION, &[1]));
}

#[test]
fn scs_is_big_endian_has_its_lock_at_48_and_no_sync_read() {
    let mut bus = SimBus::new(servobus_io::ManualClock::new(), 1_000_000)
        .with_servo(SimServo::scs0009(1).with_position(300));
    // Model 1284 = 0x0504, high byte first.
    assert_eq!(
        exchange(&mut bus, &read(1, addr::MODEL_NUMBER, 2), MS),
        status(1, 0, &[0x05, 0x04])
    );
    assert_eq!(
        exchange(&mut bus, &read(1, addr::PRESENT_POSITION, 2), MS),
        status(1, 0, &[0x01, 0x2C])
    );
    assert!(exchange(&mut bus, &sync_read(addr::PRESENT_POSITION, 2, &[1]), MS).is_empty());
    // Open the lock at 48, write the max temperature, power-cycle: it stays.
    exchange(&mut bus, &write(1, addr::SCS_LOCK, &[0]), MS);
    exchange(&mut bus, &write(1, addr::MAX_TEMPERATURE, &[60]), MS);
    bus.power_cycle();
    assert_eq!(bus.register(1, addr::MAX_TEMPERATURE), Some(60));
    let lock = bus.register(1, addr::SCS_LOCK);
    assert_eq!(lock, Some(1), "the lock closes at power-up");
}

#[test]
fn lock_decides_what_survives_a_power_cycle_not_what_applies() {
    let mut bus = bus_with(&[1]);
    // Locked (the power-up state): the write applies at once...
    assert_eq!(bus.register(1, addr::LOCK), Some(1));
    exchange(&mut bus, &write(1, addr::MAX_TEMPERATURE, &[65]), MS);
    assert_eq!(bus.register(1, addr::MAX_TEMPERATURE), Some(65));
    // ...and is lost at the power cycle.
    bus.power_cycle();
    assert_eq!(bus.register(1, addr::MAX_TEMPERATURE), Some(70));
    // Unlocked: it is saved.
    exchange(&mut bus, &write(1, addr::LOCK, &[0]), MS);
    exchange(&mut bus, &write(1, addr::MAX_TEMPERATURE, &[65]), MS);
    exchange(&mut bus, &write(1, addr::LOCK, &[1]), MS);
    // RAM is never saved.
    exchange(&mut bus, &write(1, addr::ACCELERATION, &[9]), MS);
    bus.power_cycle();
    assert_eq!(bus.register(1, addr::MAX_TEMPERATURE), Some(65));
    assert_eq!(bus.register(1, addr::ACCELERATION), Some(0));
}

#[test]
fn id_write_is_answered_from_the_old_id_then_the_new_one_answers() {
    let mut bus = bus_with(&[1]);
    assert_acked(&mut bus, &write(1, addr::ID, &[7]));
    assert!(exchange(&mut bus, &ping(1), MS).is_empty());
    assert_eq!(exchange(&mut bus, &ping(7), MS), status(7, 0, &[]));
    // Written locked: the ID is not saved.
    bus.power_cycle();
    assert_eq!(exchange(&mut bus, &ping(1), MS), status(1, 0, &[]));
}

#[test]
fn reg_write_is_held_until_action() {
    let mut bus = bus_with(&[1, 2]);
    assert_acked(&mut bus, &reg_write(1, addr::ACCELERATION, &[33]));
    assert_eq!(
        exchange(&mut bus, &read(1, addr::ACCELERATION, 1), MS),
        status(1, 0, &[0]),
        "the register still reads the old value"
    );
    assert_eq!(bus.register(1, addr::ASYNC_FLAG), Some(1));
    // Broadcast ACTION: executed, not answered.
    assert!(exchange(&mut bus, &action(0xFE), MS).is_empty());
    assert_eq!(bus.register(1, addr::ACCELERATION), Some(33));
    assert_eq!(bus.register(1, addr::ASYNC_FLAG), Some(0));
    assert_eq!(bus.register(2, addr::ACCELERATION), Some(0));
    // ACTION to one ID is answered.
    assert_eq!(exchange(&mut bus, &action(2), MS), status(2, 0, &[]));
}

#[test]
fn broadcast_gets_no_reply_except_ping_which_comes_one_servo_after_another() {
    let mut bus = bus_with(&[3, 1, 2]);
    assert!(exchange(&mut bus, &write(0xFE, addr::ACCELERATION, &[4]), MS).is_empty());
    for id in 1..=3 {
        assert_eq!(bus.register(id, addr::ACCELERATION), Some(4));
    }
    let got = exchange(&mut bus, &ping(0xFE), MS);
    assert_eq!(
        frames(&got),
        vec![status(1, 0, &[]), status(2, 0, &[]), status(3, 0, &[])]
    );
}

#[test]
fn sync_write_sets_each_listed_servo_and_is_not_answered() {
    let mut bus = bus_with(&[1, 2, 3]);
    let got = exchange(
        &mut bus,
        &sync_write(addr::ACCELERATION, &[(1, &[10]), (3, &[30])]),
        MS,
    );
    assert!(got.is_empty());
    assert_eq!(bus.register(1, addr::ACCELERATION), Some(10));
    assert_eq!(bus.register(2, addr::ACCELERATION), Some(0));
    assert_eq!(bus.register(3, addr::ACCELERATION), Some(30));
}

#[test]
fn sync_read_answers_in_list_order_and_skips_missing_ids() {
    let mut bus = SimBus::new(servobus_io::ManualClock::new(), 1_000_000).with_servos(
        [(1, 100), (2, 200), (4, 400)].map(|(id, p)| {
            SimServo::sts3215(id)
                .with_return_delay(Duration::ZERO)
                .with_position(p)
        }),
    );
    let got = exchange(
        &mut bus,
        &sync_read(addr::PRESENT_POSITION, 2, &[4, 3, 1, 2]),
        MS,
    );
    assert_eq!(
        frames(&got),
        vec![
            status(4, 0, &400u16.to_le_bytes()),
            status(1, 0, &100u16.to_le_bytes()),
            status(2, 0, &200u16.to_le_bytes()),
        ]
    );
}

#[test]
fn reset_restores_factory_values_but_keeps_the_id() {
    let mut bus = bus_with(&[5]);
    exchange(&mut bus, &write(5, addr::MAX_TEMPERATURE, &[50]), MS);
    exchange(&mut bus, &write(5, addr::ACCELERATION, &[50]), MS);
    assert_eq!(exchange(&mut bus, &reset(5), MS), status(5, 0, &[]));
    assert_eq!(bus.register(5, addr::MAX_TEMPERATURE), Some(70));
    assert_eq!(bus.register(5, addr::ACCELERATION), Some(0));
    assert_eq!(bus.register(5, addr::RETURN_DELAY), Some(250));
    bus.power_cycle();
    let kept = bus.register(5, addr::MAX_TEMPERATURE);
    assert_eq!(kept, Some(70), "RESET is saved");
}

#[test]
fn bad_checksum_and_leading_garbage() {
    let mut bus = bus_with(&[1]);
    let mut bad = ping(1);
    *bad.last_mut().unwrap() ^= 0x55;
    assert!(exchange(&mut bus, &bad, MS).is_empty());
    let mut noisy = vec![0x00, 0x13, 0xFF];
    noisy.extend(ping(1));
    assert_eq!(exchange(&mut bus, &noisy, MS), status(1, 0, &[]));
    assert!(bus.stats().bytes_ignored >= 3);
}

#[test]
fn a_servo_at_another_baud_rate_does_not_hear() {
    let mut bus = bus_with(&[1]);
    exchange(&mut bus, &write(1, addr::BAUD_RATE, &[4]), MS);
    assert!(exchange(&mut bus, &ping(1), MS).is_empty());
    bus.set_baud(115_200);
    assert_eq!(exchange(&mut bus, &ping(1), 2 * MS), status(1, 0, &[]));
}

#[test]
fn torque_enable_128_makes_the_present_position_the_midpoint() {
    let mut bus = SimBus::new(servobus_io::ManualClock::new(), 1_000_000)
        .with_servo(SimServo::sts3215(1).with_position(3000));
    exchange(&mut bus, &write(1, addr::TORQUE_ENABLE, &[128]), MS);
    assert_eq!(bus.present_position(1), Some(2048));
    // Offset 952, sign-magnitude bit 11, little-endian.
    assert_eq!(bus.servo(1, |s| s.read_u16(addr::OFFSET)), Some(952));
}
