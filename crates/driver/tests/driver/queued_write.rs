//! A write returns once its bytes are queued, as on a real serial port: a
//! request sent right after a long SYNC WRITE starts on the wire only when
//! the SYNC WRITE is through, and its reply deadline counts from there.
//! `WallBus` over a manual "wall" clock plays such a port in virtual time
//! (its write does not wait for the wire; a read waits for the bytes).

use std::time::Duration;

use servobus_driver::{Bus, BusSettings, Clock, ManualClock};
use servobus_protocol::registers::{addr, Series};
use servobus_sim::{SimBus, SimServo, WallBus};

const BAUD: u32 = 1_000_000;

#[test]
fn a_sync_read_after_a_long_sync_write_gets_its_replies_in_time() {
    let ids: Vec<u8> = (1..=18).collect();
    let sim = SimBus::new(ManualClock::new(), BAUD).with_servos(
        ids.iter()
            .map(|&id| SimServo::sts3215(id).with_return_delay(Duration::ZERO)),
    );
    let wall = ManualClock::new();
    // No adapter latency allowed: the deadlines are the wire, the
    // turnarounds and the margin alone.
    let settings = BusSettings::new(Series::Sts).with_retries(0);
    let mut bus = Bus::new(WallBus::new(sim, wall.clone()), settings);
    // 18 servos x (ID + 6 bytes of goal position, time and speed) + 8
    // bytes of frame: 134 bytes, 1.34 ms on the wire at 1 Mbaud, far more
    // than any margin of the read's deadline.
    let data = [0u8; 18 * 6];
    bus.sync_write(addr::GOAL_POSITION, &ids, &data)
        .expect("sync write");
    assert_eq!(
        wall.now(),
        Duration::ZERO,
        "the write only queued its bytes"
    );
    let read = bus
        .sync_read(addr::PRESENT_POSITION, 2, &ids)
        .expect("sync read");
    let answered = read.iter().filter(|r| r.is_ok()).count();
    assert_eq!(answered, 18, "every servo answered in time");
    // The read's request (8 + 18 = 26 bytes) followed the 134 bytes of the
    // SYNC WRITE; each of 18 replies is 50 us of turnaround and 8 bytes:
    // 1340 + 260 + 18 x (50 + 80) = 3940 us.
    assert_eq!(wall.now(), Duration::from_micros(3940));
    assert_eq!(bus.counters().timeouts, 0);
}
