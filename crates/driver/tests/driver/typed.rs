//! The typed API ([`Servos`]) against the simulator in virtual time:
//! registers by name, values as Rust types with the sign handled, one result
//! per servo, and writes that cannot carry a block of the wrong width.

use std::time::Duration;

use servobus_driver::registers::{addr, scs, sts};
use servobus_driver::{Bus, BusError, BusSettings, ManualClock, MissingReason, Series, Servos};
use servobus_sim::{SimBus, SimServo};

const BAUD: u32 = 1_000_000;

fn servos(sim: &SimBus, series: Series) -> Servos<SimBus> {
    Servos::new(Bus::new(sim.clone(), BusSettings::new(series)))
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
    let (sim, _clock) = arm(1..=6);
    let mut bus = servos(&sim, Series::Sts);
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
    let mut bus = servos(&sim, Series::Sts);
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
    let (sim, _clock) = arm(1..=3);
    let mut bus = servos(&sim, Series::Sts);
    bus.sync_write(sts::GOAL_POSITION, &[(1, 500), (2, -300), (3, 4000)])?;
    let goals: Vec<i32> = (1..=3)
        .map(|id| sim.servo(id, |s| s.goal_position()).unwrap_or(i32::MIN))
        .collect();
    assert_eq!(goals, [500, -300, 4000]);
    Ok(())
}

#[test]
fn bad_writes_send_nothing() {
    let (sim, _clock) = arm(1..=2);
    let mut bus = servos(&sim, Series::Sts);
    let before = sim.stats().bytes_from_host;
    // An offset beyond +-2047 does not fit sign bit 11.
    let err = bus.sync_write(sts::OFFSET, &[(1, 0), (2, 3000)]);
    assert!(matches!(err, Err(BusError::Value(_))), "{err:?}");
    let err = bus.sync_write(sts::GOAL_POSITION, &[(1, 0), (1, 5)]);
    assert!(
        matches!(err, Err(BusError::DuplicateId { id: 1 })),
        "{err:?}"
    );
    // Present position is at address 56.
    let err = bus.write(1, sts::PRESENT_POSITION, 5);
    assert!(
        matches!(err, Err(BusError::ReadOnly { address: 56 })),
        "{err:?}"
    );
    // STS registers on an SCS bus: the signed STS position is not the SCS one.
    let mut scs_bus = servos(&sim, Series::Scs);
    let err = scs_bus.read(1, sts::PRESENT_POSITION);
    assert!(
        matches!(
            err,
            Err(BusError::WrongSeries {
                address: 56,
                series: Series::Scs
            })
        ),
        "{err:?}"
    );
    let mut out = [Ok(0i16); 3];
    let err = bus.sync_read_into(sts::PRESENT_POSITION, &[1, 2], &mut out);
    assert!(
        matches!(
            err,
            Err(BusError::BufferLength {
                expected: 2,
                actual: 3
            })
        ),
        "{err:?}"
    );
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
    let mut bus = servos(&sim, Series::Scs);
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
    let (sim, _clock) = arm(1..=90);
    let mut bus = servos(&sim, Series::Sts);
    let goals: Vec<(u8, i16)> = (1..=90).map(|id| (id, 10 * i16::from(id))).collect();
    bus.sync_write(sts::GOAL_POSITION, &goals)?;
    assert_eq!(bus.bus().counters().transactions, 2);
    for (id, goal) in goals {
        assert_eq!(sim.servo(id, |s| s.goal_position()), Some(i32::from(goal)));
    }
    Ok(())
}

#[test]
fn sync_read_into_fills_the_callers_buffer() -> Result<(), BusError> {
    let (sim, _clock) = arm(1..=4);
    let mut bus = servos(&sim, Series::Sts);
    sim.servo(3, |s| s.set_offline(true));
    let mut out = [Ok(-1i16); 4];
    bus.sync_read_into(sts::PRESENT_POSITION, &[4, 3, 2, 1], &mut out)?;
    // In the order asked: 1000 + 100 x ID, servo 3 missing.
    assert_eq!(out[0], Ok(1400));
    assert!(matches!(out[1], Err(m) if m.id == 3 && m.reason == MissingReason::NoReply));
    assert_eq!((out[2], out[3]), (Ok(1200), Ok(1100)));
    Ok(())
}

#[test]
fn the_series_is_found_by_a_ping_and_a_model_read() -> Result<(), BusError> {
    // SCS0009 servos (model 1284, big-endian) behind a bus opened as STS.
    let clock = ManualClock::new();
    let sim = SimBus::new(clock.clone(), BAUD).with_servos([3, 5].map(|id| {
        SimServo::scs0009(id)
            .with_return_delay(Duration::ZERO)
            .with_position(700)
    }));
    let mut bus = servos(&sim, Series::Sts);
    let (id, model) = bus.detect()?;
    assert_eq!((id, model.name), (3, "SCS0009"));
    assert_eq!(bus.bus().settings().series, Series::Scs);
    // The SCS registers now read right: unsigned and big-endian.
    assert_eq!(bus.read(5, scs::PRESENT_POSITION)?, 700);

    // STS3215 servos (model 777) behind a bus opened as SCS.
    let (sim, _clock) = arm([2]);
    let mut bus = servos(&sim, Series::Scs);
    assert_eq!(bus.detect_series(2)?.name, "STS3215");
    // One exchange: the model read alone (a PING first would say nothing
    // more, a silent servo being silent to both).
    assert_eq!(bus.bus().counters().transactions, 1);
    assert_eq!(bus.bus().settings().series, Series::Sts);
    assert_eq!(bus.read(2, sts::PRESENT_POSITION)?, 1200);

    // Nobody there.
    let sim = SimBus::new(ManualClock::new(), BAUD);
    let mut bus = servos(&sim, Series::Sts);
    let err = bus.detect();
    assert!(
        matches!(err, Err(BusError::NoServo { baud: 1_000_000 })),
        "{err:?}"
    );
    // A model number nobody knows.
    let (sim, _clock) = arm([1]);
    sim.servo(1, |s| s.poke(addr::MODEL_NUMBER, &[0x34, 0x12]));
    let err = servos(&sim, Series::Sts).detect_series(1);
    assert!(
        matches!(
            err,
            Err(BusError::UnknownModel {
                id: 1,
                number: 0x1234
            })
        ),
        "{err:?}"
    );
    Ok(())
}

/// `Servos::open` on a serial port: here the simulator's pseudo-terminal
/// (wall-clock time) with SCS0009 servos, found by a PING and a model read
/// and then read with the SCS registers. `open_series` skips the asking.
#[cfg(unix)]
#[test]
fn servos_open_finds_scs_servos_on_a_port() -> Result<(), BusError> {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    let servos = [1, 2].map(|id| {
        SimServo::scs0009(id)
            .with_return_delay(Duration::ZERO)
            .with_position(400 + 100 * i32::from(id))
    });
    let Ok(mut server) = servobus_sim::PtyServer::open(BAUD, servos) else {
        // No pseudo-terminals in this environment: nothing to open.
        return Ok(());
    };
    server.set_pacing(false);
    let path = server.path().to_string_lossy().into_owned();
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let thread = std::thread::spawn(move || server.serve(&flag));

    let result = (|| {
        let mut found = Servos::open(&path, BAUD)?;
        let series = found.bus().settings().series;
        // A pty on a loaded host may miss a reply now and then (the reader
        // waits for the scheduler): a few tries, each a whole SYNC READ.
        let mut positions = found.sync_read(scs::PRESENT_POSITION, &[1, 2])?;
        for _ in 0..4 {
            if positions.iter().all(Result::is_ok) {
                break;
            }
            positions = found.sync_read(scs::PRESENT_POSITION, &[1, 2])?;
        }
        drop(found);
        let mut given = Servos::open_series(&path, BAUD, Series::Scs)?;
        let one = given.read(1, scs::PRESENT_POSITION)?;
        Ok::<_, BusError>((series, positions, one))
    })();
    stop.store(true, Ordering::SeqCst);
    let served = thread.join();
    let (series, positions, one) = result?;
    assert!(matches!(served, Ok(Ok(()))), "{served:?}");
    assert_eq!(series, Series::Scs);
    assert_eq!(positions, [Ok(500), Ok(600)]);
    assert_eq!(one, 500);
    Ok(())
}
