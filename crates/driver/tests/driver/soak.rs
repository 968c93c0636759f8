//! Soak in virtual time: SYNC WRITE + SYNC READ cycles on 18 simulated
//! servos with 1 % of replies dropped and 1 % corrupted. No panic, every
//! loss counted, no reply attributed to the wrong servo.
//!
//! The full 100,000 cycles run in release builds (`cargo test --release -p
//! servobus-driver --test driver soak`); debug builds run 20,000 so that CI
//! stays fast. `SERVOBUS_SOAK_CYCLES` overrides both.

use std::time::Duration;

use servobus_driver::{Bus, BusError, BusSettings, ManualClock, MissingReason, SyncRead};
use servobus_protocol::registers::{addr, Series};
use servobus_sim::{Faults, SimBus, SimServo};

const BAUD: u32 = 1_000_000;
const SERVOS: u8 = 18;

fn cycles() -> u64 {
    let default = if cfg!(debug_assertions) {
        20_000
    } else {
        100_000
    };
    std::env::var("SERVOBUS_SOAK_CYCLES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// Each servo sits at its own position, 100 ticks from the next: a reply
/// given to the wrong servo would show.
fn home(id: u8) -> u16 {
    1000 + 100 * u16::from(id)
}

/// What the soak's SYNC READs found, servo by servo.
#[derive(Debug, Default)]
struct Tally {
    answered: u64,
    missing: u64,
    no_reply: u64,
    /// Corrupted replies, of the wrong length included.
    garbled: u64,
    wrong_length: u64,
}

impl Tally {
    /// Adds one SYNC READ of `ids`, checking that every answer is its own
    /// servo's and every missing servo says why.
    fn add(&mut self, read: &SyncRead<'_>, ids: &[u8]) {
        assert_eq!(read.len(), ids.len());
        for (res, &id) in read.iter().zip(ids) {
            match res {
                Ok(reply) => {
                    assert_eq!(reply.id, id);
                    let pos = u16::from_le_bytes([reply.data[0], reply.data[1]]);
                    assert!(
                        pos.abs_diff(home(id)) <= 20,
                        "servo {id} got {pos}, its position is {}",
                        home(id)
                    );
                    self.answered += 1;
                }
                Err(m) => {
                    assert_eq!(m.id, id);
                    self.missing += 1;
                    match m.reason {
                        MissingReason::NoReply => self.no_reply += 1,
                        MissingReason::Corrupt => self.garbled += 1,
                        MissingReason::WrongLength => {
                            self.garbled += 1;
                            self.wrong_length += 1;
                        }
                        other => panic!("servo {id}: unexpected {other}"),
                    }
                }
            }
        }
    }
}

/// One control cycle: every servo sent its goal, then asked its position.
fn cycle(
    bus: &mut Bus<SimBus>,
    ids: &[u8],
    goals: &[u8],
    tally: &mut Tally,
) -> Result<(), BusError> {
    bus.sync_write(addr::GOAL_POSITION, ids, goals)?;
    tally.add(&bus.sync_read(addr::PRESENT_POSITION, 2, ids)?, ids);
    Ok(())
}

#[test]
fn soak_sync_write_sync_read_with_lossy_replies() {
    let ids: Vec<u8> = (1..=SERVOS).collect();
    let clock = ManualClock::new();
    let sim = SimBus::new(clock.clone(), BAUD).with_servos(ids.iter().map(|&id| {
        SimServo::sts3215(id)
            .with_return_delay(Duration::ZERO)
            .with_position(i32::from(home(id)))
    }));
    let settings = BusSettings::new(Series::Sts).with_latency(Duration::from_millis(1));
    let mut bus = Bus::new(sim.clone(), settings);

    // Torque on, every goal at the servo's own position: they hold still.
    let mut goals = Vec::with_capacity(2 * ids.len());
    for &id in &ids {
        goals.extend_from_slice(&home(id).to_le_bytes());
    }
    let torque = vec![1u8; ids.len()];
    bus.sync_write(addr::TORQUE_ENABLE, &ids, &torque)
        .expect("torque on");
    sim.set_faults(Faults::seeded(2024).drop(0.01).corrupt(0.01));

    let n = cycles();
    let mut tally = Tally::default();
    for _ in 0..n {
        cycle(&mut bus, &ids, &goals, &mut tally).expect("a cycle runs");
    }
    let Tally {
        answered,
        missing,
        no_reply,
        garbled,
        wrong_length,
    } = tally;

    let stats = sim.stats();
    let c = *bus.counters();
    let per_servo_failures: u64 = ids.iter().map(|&id| bus.servo_counters(id).failures).sum();
    println!(
        "{n} cycles: {answered} answered, {missing} missing ({no_reply} no reply, \
         {garbled} garbled); sim dropped {} corrupted {}; bus {c:?}",
        stats.dropped, stats.corrupted
    );
    assert_eq!(answered + missing, n * u64::from(SERVOS));
    // Every loss the simulator injected is a missing servo, and counted. A
    // corrupted length byte whose checksum happens to match (1 in 256) makes
    // a frame of the wrong length that swallows the next reply: that is the
    // only way one fault costs two servos, and the extra one is counted too.
    let injected = stats.dropped + stats.corrupted;
    assert!(missing >= injected, "{missing} < {injected}");
    assert!(
        missing <= injected + wrong_length,
        "{missing} > {injected} + {wrong_length}"
    );
    assert_eq!(c.failures, missing);
    assert_eq!(per_servo_failures, missing);
    assert_eq!(c.timeouts, no_reply);
    assert!(c.checksum_errors + c.discarded_bytes > 0);
    // 1 % + 1 % of 18 replies per cycle: about 0.36 losses per cycle.
    let expected = 0.02 * (n * u64::from(SERVOS)) as f64;
    assert!((missing as f64) > 0.8 * expected && (missing as f64) < 1.2 * expected);
    assert_eq!(c.transactions, 2 * n + 1);
}
