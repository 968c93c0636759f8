//! Worked examples of cycle plans, each checked by hand in its comments.
//!
//! Byte counts at 1 Mbps: 10 us a byte. SYNC WRITE of L bytes to N servos:
//! 8 + N(L + 1) bytes. SYNC READ of L bytes from N servos: 8 + N request
//! bytes, then N replies of 6 + L bytes. READ: 8 request bytes, a reply of
//! 6 + L bytes.

use core::time::Duration;

use servobus_timing::{plan, Block, Change, CycleError, Link, Plan, Servo};

const US: fn(u64) -> Duration = Duration::from_micros;

/// A 1 Mbps link with no turnaround so the sums stay on paper; `latency`
/// is the adapter's.
fn link(latency: Duration) -> Link {
    Link::new(1_000_000)
        .with_turnaround(Duration::ZERO)
        .with_latency(latency)
}

fn sts(n: usize, return_delay: Duration) -> Vec<Servo> {
    (1..=n as u8)
        .map(|id| Servo::sts(id, return_delay))
        .collect()
}

fn scs(n: usize, return_delay: Duration) -> Vec<Servo> {
    (1..=n as u8)
        .map(|id| Servo::scs(id, return_delay))
        .collect()
}

const POS: Option<Block> = Some(Block::GOAL_POSITION);
const PRESENT: Option<Block> = Some(Block::PRESENT_POSITION);

/// An SO-101 arm: six STS servos with return delay 0, sent goal positions
/// and asked `read` at `rate_hz` over `link`.
fn so101(link: &Link, read: Option<Block>, rate_hz: f64) -> Result<Plan, CycleError> {
    plan(link, &sts(6, Duration::ZERO), POS, read, rate_hz)
}

#[test]
fn so101_six_sts3215_return_delay_zero() {
    // 26 (SYNC WRITE 8 + 6 x 3) + 14 (SYNC READ 8 + 6) + 48 (6 x 8) = 88 bytes
    // = 880 us; nothing else to wait for, so the cycle is the wire:
    // 1 / 880 us = 1136.36 Hz.
    let p = so101(&link(Duration::ZERO), PRESENT, 1000.0).unwrap();
    assert_eq!(p.bytes_per_cycle(), 88);
    assert_eq!(p.full_cycle().wire_time, US(880));
    assert_eq!(p.full_cycle().cycle_time, US(880));
    assert_eq!(p.wire_time_us(), 880.0);
    assert_eq!(p.cycle_time_us(), 880.0);
    assert!((p.max_rate_hz() - 1136.36).abs() < 0.01);
    assert!((p.wire_limited_rate_hz() - 1136.36).abs() < 0.01);
    // At 1 kHz: 880 of every 1000 us.
    assert!((p.utilisation() - 0.88).abs() < 1e-9);
    assert!(p.is_feasible());
    assert_eq!(p.read_every(), 1);
    assert_eq!(p.read_ids(0), &[1, 2, 3, 4, 5, 6]);
    assert_eq!(p.full_cycle().write_frames, 1);
    assert_eq!(p.full_cycle().round_trips, 1);
    assert_eq!(p.cheapest_fix(), None);
}

#[test]
fn so101_with_the_default_turnaround() {
    // Link::new assumes 50 us of servo processing before each reply:
    // 880 + 6 x 50 = 1180 us, 847.46 Hz. The wire time does not change.
    let l = Link::new(1_000_000);
    let p = so101(&l, PRESENT, 500.0).unwrap();
    assert_eq!(p.wire_time_us(), 880.0);
    assert_eq!(p.cycle_time_us(), 1180.0);
    assert!((p.max_rate_hz() - 847.46).abs() < 0.01);
}

#[test]
fn so101_with_the_factory_return_delay() {
    // Each of the 6 replies waits 500 us: 880 + 6 x 500 = 3880 us, 257.73 Hz.
    let servos = sts(6, US(500));
    let p = plan(&link(Duration::ZERO), &servos, POS, PRESENT, 200.0).unwrap();
    assert_eq!(p.wire_time_us(), 880.0);
    assert_eq!(p.cycle_time_us(), 3880.0);
    assert!((p.max_rate_hz() - 257.73).abs() < 0.01);
    // 3880 of 5000 us.
    assert!((p.utilisation() - 0.776).abs() < 1e-9);
    assert!(p.is_feasible());

    // At 500 Hz (2000 us) the full cycle does not fit. Round robin:
    // 2 groups of 3: 26 + (8 + 3) + 3 x 8 = 61 bytes = 610 us + 3 x 500 = 2110 us: no.
    // 3 groups of 2: 26 + (8 + 2) + 2 x 8 = 52 bytes = 520 us + 2 x 500 = 1520 us: fits.
    let p = plan(&link(Duration::ZERO), &servos, POS, PRESENT, 500.0).unwrap();
    assert!(!p.is_feasible());
    assert!(p.utilisation() > 1.0);
    assert_eq!(p.read_every(), 3);
    assert_eq!(p.schedule().per_cycle, 2);
    assert_eq!(p.worst_cycle().cycle_time, US(1520));
    assert_eq!(p.worst_cycle().bytes, 52);
    assert_eq!(p.read_ids(0), &[1, 2]);
    assert_eq!(p.read_ids(1), &[3, 4]);
    assert_eq!(p.read_ids(2), &[5, 6]);
    assert_eq!(p.read_ids(3), &[1, 2]);
    assert_eq!(p.reads_in_cycle(u64::MAX), 0..2); // u64::MAX % 3 == 0
                                                  // Cheapest fix: return delay 0 brings the full cycle back to 880 us.
                                                  // Reading 1 byte instead of 2 saves only 6 bytes (3820 us): no help.
                                                  // Already at 1 Mbps, no latency: neither of those either.
                                                  // Lower rate: floor(257.73) = 257 Hz.
    let fixes: Vec<Change> = p.fixes().iter().collect();
    assert_eq!(
        fixes,
        [
            Change::ReturnDelayZero {
                cycle_time: US(880)
            },
            Change::LowerRate { rate_hz: 257.0 }
        ]
    );
}

#[test]
fn hexapod_eighteen_sts_servos() {
    // Write goal position: 8 + 18 x 3 = 62 bytes (one frame: up to 83 fit).
    // Read present position: 8 + 18 = 26, then 18 x 8 = 144. Total 232 bytes
    // = 2320 us = 431.03 Hz.
    let servos = sts(18, Duration::ZERO);
    let p = plan(&link(Duration::ZERO), &servos, POS, PRESENT, 200.0).unwrap();
    assert_eq!(p.bytes_per_cycle(), 232);
    assert_eq!(p.cycle_time_us(), 2320.0);
    assert!((p.max_rate_hz() - 431.03).abs() < 0.01);
    assert!((p.utilisation() - 0.464).abs() < 1e-9);

    // At 500 Hz: 2 groups of 9: 62 + 17 + 72 = 151 bytes = 1510 us: fits.
    // Reading 1 byte: 62 + 26 + 18 x 7 = 214 bytes = 2140 us > 2000: no help.
    let p = plan(&link(Duration::ZERO), &servos, POS, PRESENT, 500.0).unwrap();
    assert_eq!((p.read_every(), p.schedule().per_cycle), (2, 9));
    assert_eq!(p.worst_cycle().cycle_time, US(1510));
    assert_eq!(p.reads_in_cycle(0), 0..9);
    assert_eq!(p.reads_in_cycle(1), 9..18);
    assert_eq!(p.cheapest_fix(), Some(Change::LowerRate { rate_hz: 431.0 }));
}

#[test]
fn hexapod_full_feedback_with_acceleration_goals() {
    // Write acceleration + position + time + speed (L = 7 at 41): 8 + 18 x 8
    // = 152 bytes (one frame: up to 31 fit). Read the whole feedback block
    // (L = 15 at 56): 26 + 18 x 21 = 404. Total 556 bytes = 5560 us, 179.86 Hz.
    let servos = sts(18, Duration::ZERO);
    let w = Some(Block::ACCEL_POSITION_TIME_SPEED);
    let r = Some(Block::FEEDBACK);
    let p = plan(&link(Duration::ZERO), &servos, w, r, 100.0).unwrap();
    assert_eq!(p.bytes_per_cycle(), 556);
    assert_eq!(p.cycle_time_us(), 5560.0);
    assert!((p.max_rate_hz() - 179.86).abs() < 0.01);

    // At 200 Hz (5000 us, 500 bytes): reading L bytes costs 152 + 26 + 18(6 + L)
    // <= 500 -> L <= 11 (484 bytes); L = 12 gives 502. Cheapest fix: read at
    // most 11 bytes. Round robin: 2 groups of 9: 152 + 17 + 9 x 21 = 358 bytes.
    let p = plan(&link(Duration::ZERO), &servos, w, r, 200.0).unwrap();
    assert_eq!(p.cheapest_fix(), Some(Change::FewerReadBytes { len: 11 }));
    assert_eq!(p.read_every(), 2);
    assert_eq!(p.worst_cycle().bytes, 358);
    let fixes: Vec<Change> = p.fixes().iter().collect();
    assert_eq!(fixes[1], Change::LowerRate { rate_hz: 179.0 });
}

#[test]
fn one_millisecond_usb_adapter() {
    // The SO-101 cycle behind a CDC adapter: one round trip (the SYNC READ)
    // waits 1 ms: 880 + 1000 = 1880 us, 531.91 Hz; the wire is unchanged.
    let ms = Duration::from_millis(1);
    let p = so101(&link(ms), PRESENT, 200.0).unwrap();
    assert_eq!(p.wire_time_us(), 880.0);
    assert_eq!(p.cycle_time_us(), 1880.0);
    assert!((p.max_rate_hz() - 531.91).abs() < 0.01);
    assert!((p.utilisation() - 0.376).abs() < 1e-9);
}

#[test]
fn scs_hexapod_behind_a_usb_adapter_reads_one_servo_at_a_time() {
    // 18 SCS servos have no SYNC READ: 18 READs of 8 + 8 bytes, each its own
    // 1 ms round trip. Bytes: 62 + 18 x 16 = 350 = 3500 us on the wire;
    // cycle 3500 + 18 x 1000 = 21500 us, 46.51 Hz.
    let ms = Duration::from_millis(1);
    let servos = scs(18, Duration::ZERO);
    let p = plan(&link(ms), &servos, POS, PRESENT, 50.0).unwrap();
    assert_eq!(p.bytes_per_cycle(), 350);
    assert_eq!(p.full_cycle().round_trips, 18);
    assert_eq!(p.cycle_time_us(), 21500.0);
    // At 50 Hz (20000 us): 2 groups of 9: 62 + 9 x 16 = 206 bytes = 2060 us
    // + 9 ms = 11060 us.
    assert_eq!(p.read_every(), 2);
    assert_eq!(p.worst_cycle().cycle_time, US(11060));
    // Cheapest fix: the latency that fits, (20000 - 3500) / 18 = 916.67 ->
    // 916 us per transaction.
    assert_eq!(
        p.cheapest_fix(),
        Some(Change::LowerLatency { latency: US(916) })
    );
}

#[test]
fn ftdi_at_its_default_latency_timer_is_refused_with_the_fix() {
    // 16 ms per round trip can never fit a 5 ms period, whatever is read:
    // the shortest cycle writes everything and reads one servo,
    // 26 + 9 + 8 = 43 bytes = 430 us + 16 ms = 16430 us.
    // The fix: (5000 - 880) / 1 = 4120 us of latency at most.
    let ftdi = link(Duration::from_millis(16));
    let err = so101(&ftdi, PRESENT, 200.0).unwrap_err();
    assert_eq!(
        err,
        CycleError::Infeasible {
            rate_hz: 200.0,
            min_cycle_time: US(16430),
            fix: Change::LowerLatency { latency: US(4120) },
        }
    );
    let msg = err.to_string();
    assert!(msg.contains("16430 us"), "{msg}");
    assert!(msg.contains("4120 us"), "{msg}");
}

#[test]
fn a_slow_baud_rate_names_the_baud_that_fits() {
    // 6 servos at 115200: 88 bytes x 86.8 us = 7638.9 us. At 200 Hz
    // (5000 us): 250000 baud gives 88 x 40 = 3520 us; 128000 gives
    // 88 x 78.125 = 6875 us, too slow. Round robin at 115200: 2 groups of 3:
    // 26 + 11 + 24 = 61 bytes = 5295.2 us, no; 3 groups of 2: 52 bytes =
    // 4513.9 us, fits.
    let l = Link::new(115_200).with_turnaround(Duration::ZERO);
    let p = so101(&l, PRESENT, 200.0).unwrap();
    assert_eq!(p.full_cycle().wire_time, Duration::from_nanos(7_638_889));
    assert_eq!(p.cheapest_fix(), Some(Change::HigherBaud { baud: 250_000 }));
    assert_eq!(p.read_every(), 3);
}

#[test]
fn a_full_bus_splits_both_writes_and_reads() {
    // 254 servos (IDs 0..=253): SYNC WRITE of 2 bytes, 83 per frame -> 4
    // frames: 4 x 8 + 254 x 3 = 794 bytes. SYNC READ lists at most 251 IDs ->
    // 2 requests: 2 x 8 + 254 + 254 x 8 = 2302 bytes. 3096 bytes in all.
    let servos: Vec<Servo> = (0..=253u8)
        .map(|id| Servo::sts(id, Duration::ZERO))
        .collect();
    let p = plan(&link(Duration::ZERO), &servos, POS, PRESENT, 10.0).unwrap();
    assert_eq!(p.full_cycle().write_frames, 4);
    assert_eq!(p.full_cycle().round_trips, 2);
    assert_eq!(p.bytes_per_cycle(), 3096);
    assert_eq!(p.servos(), 254);
}

#[test]
fn a_mixed_bus_uses_sync_read_where_it_can() {
    // 2 STS + 1 SCS, 2 bytes each: write 8 + 9 = 17; SYNC READ 8 + 2 + 2 x 8
    // = 26; READ 8 + 8 = 16. 59 bytes, 2 round trips.
    let servos = [
        Servo::sts(1, Duration::ZERO),
        Servo::scs(2, Duration::ZERO),
        Servo::sts(3, Duration::ZERO),
    ];
    let p = plan(&link(US(100)), &servos, POS, PRESENT, 100.0).unwrap();
    assert_eq!(p.bytes_per_cycle(), 59);
    assert_eq!(p.full_cycle().round_trips, 2);
    assert_eq!(p.full_cycle().cycle_time, US(590 + 200));
}

#[test]
fn bad_input_is_refused() {
    let l = link(Duration::ZERO);
    let two = sts(2, Duration::ZERO);
    assert_eq!(
        plan(&l, &[], POS, PRESENT, 100.0),
        Err(CycleError::NoServos)
    );
    assert_eq!(
        plan(&l, &two, POS, PRESENT, 0.0),
        Err(CycleError::InvalidRate { rate_hz: 0.0 })
    );
    assert!(matches!(
        plan(&l, &two, POS, PRESENT, f64::NAN),
        Err(CycleError::InvalidRate { .. })
    ));
    assert_eq!(
        plan(
            &l,
            &[Servo::sts(1, Duration::ZERO), Servo::scs(1, Duration::ZERO)],
            POS,
            PRESENT,
            1.0
        ),
        Err(CycleError::DuplicateId { id: 1 })
    );
    assert_eq!(
        plan(&l, &[Servo::sts(254, Duration::ZERO)], POS, PRESENT, 1.0),
        Err(CycleError::InvalidId { id: 254 })
    );
    let bad = Block::new(250, 10);
    assert_eq!(
        plan(&l, &two, Some(bad), PRESENT, 1.0),
        Err(CycleError::InvalidBlock { block: bad })
    );
    assert_eq!(
        plan(&l, &two, POS, Some(Block::new(0, 254)), 1.0),
        Err(CycleError::InvalidBlock {
            block: Block::new(0, 254)
        })
    );
}

#[test]
fn write_only_cycles_have_no_round_trips() {
    // 6 servos, goal position, nothing read: 26 bytes, latency never waited on.
    let p = so101(&link(Duration::from_millis(16)), None, 1000.0).unwrap();
    assert_eq!(p.cycle_time_us(), 260.0);
    assert_eq!(p.reads_in_cycle(0), 0..0);
    assert!(p.read_ids(5).is_empty());
}

#[test]
fn round_robin_sizes_groups_by_their_costliest_member() {
    // 4 servos, the last two with a 400 us return delay. Full cycle: 20 + 44
    // bytes = 640 us + 2 x 400 = 1440 us: not at 1 kHz. Two groups of 2:
    // the first takes 20 + 10 + 16 = 46 bytes = 460 us, but the second
    // 460 + 800 = 1260 us: no. (3 groups would still be groups of 2.)
    // Four groups of 1: the worst is 20 + 9 + 8 = 37 bytes = 370 + 400 = 770 us.
    let servos = [
        Servo::sts(1, Duration::ZERO),
        Servo::sts(2, Duration::ZERO),
        Servo::sts(3, US(400)),
        Servo::sts(4, US(400)),
    ];
    let p = plan(&link(Duration::ZERO), &servos, POS, PRESENT, 1000.0).unwrap();
    assert_eq!(p.cycle_time_us(), 1440.0);
    assert_eq!(p.read_every(), 4);
    assert_eq!(p.worst_cycle().cycle_time, US(770));
    assert_eq!(p.read_ids(2), &[3]);
    // Return delay 0 would bring the full cycle to 640 us.
    assert_eq!(
        p.cheapest_fix(),
        Some(Change::ReturnDelayZero {
            cycle_time: US(640)
        })
    );
}
