//! The typed API ([`Servos`]) against the simulator in virtual time:
//! registers by name, values as Rust types with the sign handled, one result
//! per servo, and writes that cannot carry a block of the wrong width.

use std::time::Duration;

use servobus_driver::registers::{scs, sts};
use servobus_driver::{Bus, BusError, BusSettings, ManualClock, MissingReason, Series, Servos};
use servobus_sim::{SimBus, SimServo};

const BAUD: u32 = 1_000_000;

fn servos(sim: &SimBus, clock: &ManualClock, series: Series) -> Servos<SimBus, ManualClock> {
    Servos::new(Bus::new(
        sim.clone(),
        clock.clone(),
        BusSettings::new(series, BAUD),
    ))
}

fn arm(ids: impl IntoIterator<Item = u8>) -> (SimBus, ManualClock) {
    let clock = ManualClock::new();
    let sim = SimBus::new(clock.clone(), BAUD).with_servos(ids.into_iter().map(|id| {
        SimServo::sts3215(id)
            .with_return_delay(Duration::ZERO)
            .with_position(1000 + 100 * i32::from(id))
    }));
    (sim, clock)
}

#[test]
fn six_positions_are_six_typed_results() -> Result<(), BusError> {
    let (sim, clock) = arm(1..=6);
    let mut bus = servos(&sim, &clock, Series::Sts);
    let ids = [1, 2, 3, 4, 5, 6];
    let positions: Vec<Result<i16, _>> = bus.sync_read(sts::PRESENT_POSITION, &ids)?;
    assert_eq!(positions.len(), 6);
    for (id, p) in ids.iter().zip(&positions) {
        assert_eq!(p.as_ref().ok(), Some(&(1000 + 100 * i16::from(*id))));
    }
    // A servo that does not answer is one Err among Oks, named by ID.
    sim.servo(4, |s| s.set_offline(true));
    let positions = bus.sync_read(sts::PRESENT_POSITION, &ids)?;
    let missing = positions[3].as_ref().expect_err("servo 4 is offline");
    assert_eq!((missing.id, missing.reason), (4, MissingReason::NoReply));
    assert_eq!(positions.iter().filter(|p| p.is_ok()).count(), 5);
    Ok(())
}

#[test]
fn the_sign_bit_is_handled_both_ways() -> Result<(), BusError> {
    let (sim, clock) = arm([1]);
    let mut bus = servos(&sim, &clock, Series::Sts);
    // Moving down from 1100 to 100: the speed is negative, sent as sign
    // bit 15 + magnitude.
    bus.write(1, sts::TORQUE_ENABLE, 1)?;
    bus.write(1, sts::GOAL_POSITION, 100)?;
    clock.advance(Duration::from_millis(100));
    let speed = bus.read(1, sts::PRESENT_SPEED)?;
    assert!(speed < -100, "{speed}");
    assert_eq!(
        sim.register(1, 59).map(|b| b & 0x80),
        Some(0x80),
        "sign bit on the wire"
    );
    bus.write(1, sts::OFFSET, 1300)?;
    assert_eq!(bus.read(1, sts::OFFSET)?, 1300);
    bus.write(1, sts::OFFSET, -5)?;
    assert_eq!(sim.register(1, 32), Some(0x08), "offset sign is bit 11");
    assert_eq!(bus.read(1, sts::OFFSET)?, -5);
    Ok(())
}

#[test]
fn sync_write_gives_each_servo_its_own_value() -> Result<(), BusError> {
    let (sim, clock) = arm(1..=3);
    let mut bus = servos(&sim, &clock, Series::Sts);
    bus.sync_write(sts::GOAL_POSITION, &[(1, 500), (2, -300), (3, 4000)])?;
    let goals: Vec<i32> = (1..=3)
        .map(|id| sim.servo(id, |s| s.goal_position()).unwrap_or(i32::MIN))
        .collect();
    assert_eq!(goals, [500, -300, 4000]);
    Ok(())
}

#[test]
fn bad_writes_send_nothing() {
    let (sim, clock) = arm(1..=2);
    let mut bus = servos(&sim, &clock, Series::Sts);
    let before = sim.stats().bytes_from_host;
    // An offset beyond +-2047 does not fit sign bit 11.
    let err = bus.sync_write(sts::OFFSET, &[(1, 0), (2, 3000)]);
    assert!(matches!(err, Err(BusError::Value(_))), "{err:?}");
    let err = bus.sync_write(sts::GOAL_POSITION, &[(1, 0), (1, 5)]);
    assert!(matches!(err, Err(BusError::InvalidRequest(_))), "{err:?}");
    let err = bus.write(1, sts::PRESENT_POSITION, 5);
    assert!(matches!(err, Err(BusError::InvalidRequest(_))), "{err:?}");
    // STS registers on an SCS bus: the signed STS position is not the SCS one.
    let mut scs_bus = servos(&sim, &clock, Series::Scs);
    let err = scs_bus.read(1, sts::PRESENT_POSITION);
    assert!(matches!(err, Err(BusError::InvalidRequest(_))), "{err:?}");
    assert_eq!(sim.stats().bytes_from_host, before);
}

#[test]
fn scs_positions_are_unsigned_and_big_endian() -> Result<(), BusError> {
    let clock = ManualClock::new();
    let sim = SimBus::new(clock.clone(), BAUD).with_servos((1..=2).map(|id| {
        SimServo::scs0009(id)
            .with_return_delay(Duration::ZERO)
            .with_position(300 * i32::from(id))
    }));
    let mut bus = servos(&sim, &clock, Series::Scs);
    let positions = bus.sync_read(scs::PRESENT_POSITION, &[1, 2])?;
    let positions: Vec<u16> = positions.into_iter().flatten().collect();
    assert_eq!(positions, [300, 600]);
    bus.write(2, scs::GOAL_POSITION, 1000)?;
    assert_eq!(sim.register(2, 42), Some(0x03), "high byte first");
    Ok(())
}

#[test]
fn a_sync_write_too_long_for_one_frame_reaches_every_servo() -> Result<(), BusError> {
    // 90 servos x 3 bytes: the packer's limit is 83 a frame, so two frames.
    let (sim, clock) = arm(1..=90);
    let mut bus = servos(&sim, &clock, Series::Sts);
    let goals: Vec<(u8, i16)> = (1..=90).map(|id| (id, 10 * i16::from(id))).collect();
    bus.sync_write(sts::GOAL_POSITION, &goals)?;
    assert_eq!(bus.bus().counters().transactions, 2);
    for (id, goal) in goals {
        assert_eq!(sim.servo(id, |s| s.goal_position()), Some(i32::from(goal)));
    }
    Ok(())
}
