//! Several registers of one servo as one EEPROM transaction: all written
//! and persisted, or, when a step fails, the servo as it was.

use servobus_driver::{BusError, SignalHold};
use servobus_protocol::registers::{addr, Series};

use super::setup;

fn address(name: &str) -> u8 {
    Series::Sts.map().get(name).expect("register").address
}

#[test]
fn every_change_is_written_persisted_and_locked() -> Result<(), BusError> {
    let (mut bus, sim) = setup(&[1]);
    let (min, max) = (address("min_angle_limit"), address("max_angle_limit"));
    let w = bus.write_eeprom_all(1, &[(min, &[100, 0]), (max, &[0, 15])])?;
    assert_eq!(w.id, 1);
    assert_eq!(sim.register(1, addr::LOCK), Some(1));
    sim.power_cycle();
    assert_eq!(sim.register(1, min), Some(100));
    assert_eq!(sim.register(1, max + 1), Some(15));
    Ok(())
}

#[test]
fn a_failed_step_puts_back_what_was_written() {
    let (mut bus, sim) = setup(&[1]);
    let min = address("min_angle_limit");
    let before = (sim.register(1, min), sim.register(1, min + 1));
    // The model number is read-only: the servo ignores the write, the
    // read-back differs, and the limit written before it is put back.
    let err = bus
        .write_eeprom_all(1, &[(min, &[100, 0]), (addr::MODEL_NUMBER, &[1, 2])])
        .expect_err("a read-only register cannot be written");
    assert!(matches!(err, BusError::Verify { .. }), "{err}");
    assert_eq!((sim.register(1, min), sim.register(1, min + 1)), before);
    assert_eq!(sim.register(1, addr::LOCK), Some(1));
    sim.power_cycle();
    assert_eq!((sim.register(1, min), sim.register(1, min + 1)), before);
}

#[test]
fn an_id_change_is_not_part_of_a_multi_register_transaction() {
    let (mut bus, sim) = setup(&[1]);
    let err = bus
        .write_eeprom_all(1, &[(addr::ID, &[4])])
        .expect_err("refused");
    assert!(matches!(err, BusError::InvalidRequest(_)), "{err}");
    let err = bus.write_eeprom_all(1, &[(9, &[])]).expect_err("refused");
    assert!(matches!(err, BusError::InvalidRequest(_)), "{err}");
    // Refused before anything went out.
    assert_eq!(sim.register(1, addr::LOCK), Some(1));
    assert_eq!(sim.register(1, addr::ID), Some(1));
}

#[test]
fn a_hold_nests_inside_a_transaction() -> Result<(), BusError> {
    // A program holding signals around several servos' transactions.
    let (mut bus, sim) = setup(&[1, 2]);
    let max_temperature = address("max_temperature");
    let hold = SignalHold::new();
    bus.write_eeprom(1, max_temperature, &[61])?;
    bus.write_eeprom(2, max_temperature, &[62])?;
    drop(hold);
    assert_eq!(sim.register(1, max_temperature), Some(61));
    assert_eq!(sim.register(2, max_temperature), Some(62));
    Ok(())
}
