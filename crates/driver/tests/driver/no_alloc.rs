//! The hot path — SYNC WRITE then SYNC READ, every control cycle — does not
//! allocate once the bus is built. Counted with a global allocator wrapper,
//! over a transport that itself never allocates.

use std::time::Duration;

use servobus_alloc_count::{allocations, Counting};
use servobus_driver::registers::sts;
use servobus_driver::scripted::{Received, Script, ScriptedPort};
use servobus_driver::{
    Bus, BusSettings, Clock, ManualClock, Missing, MissingReason, Servos, TransportError,
};
use servobus_protocol::registers::Series;
use servobus_protocol::{encode, parse_frame, Instruction, StatusFlags};

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Answers a SYNC READ of 2 bytes from every listed servo (except ID 4,
/// which is silent) with its ID as data, from a fixed buffer.
struct FixedServos {
    out: [u8; 1024],
    len: usize,
    pos: usize,
    /// Length of every frame written, in order (room for 4000).
    sent: [u16; 4000],
    frames: usize,
}

impl Script for FixedServos {
    fn write(&mut self, clock: &ManualClock, bytes: &[u8]) -> Result<(), TransportError> {
        clock.advance(Duration::from_micros(10) * bytes.len() as u32);
        if let Some(slot) = self.sent.get_mut(self.frames) {
            *slot = bytes.len() as u16;
        }
        self.frames += 1;
        let Ok((p, _)) = parse_frame(bytes) else {
            return Ok(());
        };
        if p.instruction() != Some(Instruction::SyncRead) {
            return Ok(());
        }
        self.len = 0;
        self.pos = 0;
        for &id in &p.params()[2..] {
            if id == 4 {
                continue;
            }
            let n = encode::status(&mut self.out[self.len..], id, StatusFlags(0), &[id, 0])
                .map_err(|_| TransportError::Disconnected("buffer".into()))?;
            self.len += n;
        }
        Ok(())
    }

    fn read(&mut self, clock: &ManualClock, buf: &mut [u8], deadline: Duration) -> Received {
        if self.pos == self.len {
            clock.advance_to(deadline);
            return Err(TransportError::TimedOut);
        }
        let n = buf.len().min(self.len - self.pos);
        buf[..n].copy_from_slice(&self.out[self.pos..self.pos + n]);
        self.pos += n;
        clock.advance(Duration::from_micros(10) * n as u32);
        Ok(n)
    }

    fn discard(&mut self, _clock: &ManualClock) {
        self.pos = self.len;
    }
}

/// A bus over [`FixedServos`] at 1 Mbaud, and its clock.
fn fixed_bus() -> (Bus<ScriptedPort<FixedServos>>, ManualClock) {
    let clock = ManualClock::new();
    let servos = FixedServos {
        out: [0; 1024],
        len: 0,
        pos: 0,
        sent: [0; 4000],
        frames: 0,
    };
    let settings = BusSettings::new(Series::Sts).with_latency(Duration::from_millis(1));
    let port = ScriptedPort::new(&clock, servos);
    (Bus::new(port, settings), clock)
}

#[test]
fn sync_write_and_sync_read_do_not_allocate() {
    let (mut bus, clock) = fixed_bus();
    let ids: [u8; 18] = core::array::from_fn(|i| i as u8 + 1);
    let goals = [0x08u8; 36];

    let before = allocations();
    let mut answered = 0;
    let mut missing = 0;
    for _ in 0..1000 {
        bus.sync_write(42, &ids, &goals).expect("sync write");
        let r = bus
            .sync_read_within(56, 2, &ids, Duration::from_millis(10))
            .expect("sync read");
        for res in r.iter() {
            match res {
                Ok(reply) => {
                    assert_eq!(reply.data[0], reply.id);
                    answered += 1;
                }
                Err(m) => {
                    assert_eq!(m.id, 4);
                    missing += 1;
                }
            }
        }
    }
    let allocated = allocations() - before;
    assert_eq!(allocated, 0, "the hot path allocated {allocated} times");
    assert_eq!((answered, missing), (17_000, 1000));
    assert_eq!(bus.servo_counters(4).retries, 1000);
    assert!(clock.now() > Duration::ZERO);
}

#[test]
fn a_sync_write_of_several_frames_does_not_allocate_even_the_first_time() {
    let (mut bus, _clock) = fixed_bus();
    // 64 servos x 7 bytes: 31 servos per frame (length byte 31 x 8 + 4 =
    // 252), so frames of 31, 31 and 2 servos.
    let ids: [u8; 64] = core::array::from_fn(|i| i as u8 + 1);
    let goals = [0x08u8; 64 * 7];

    // No warm-up: the very first call is counted.
    let before = allocations();
    for _ in 0..1000 {
        bus.sync_write(41, &ids, &goals).expect("sync write");
    }
    let allocated = allocations() - before;
    assert_eq!(allocated, 0, "the SYNC WRITE allocated {allocated} times");

    let t = &bus.transport().script;
    assert_eq!(t.frames, 3000);
    // 6 bytes of frame, the address and L, then (ID + 7 bytes) per servo.
    for cycle in t.sent[..3000].chunks(3) {
        assert_eq!(cycle, [8 + 31 * 8, 8 + 31 * 8, 8 + 2 * 8]);
    }
    assert_eq!(bus.counters().transactions, 3000);
}

#[test]
fn typed_sync_read_into_a_callers_buffer_does_not_allocate() {
    let (bus, _clock) = fixed_bus();
    let mut servos = Servos::new(bus);
    let ids: [u8; 6] = [1, 2, 3, 4, 5, 6];
    let mut positions: [Result<i16, Missing>; 6] = [Ok(0); 6];
    // The bus's SYNC READ storage is made with room for any control loop's
    // request, so even the first call is counted.
    let before = allocations();
    for _ in 0..1000 {
        servos
            .sync_read_into(sts::PRESENT_POSITION, &ids, &mut positions)
            .expect("sync read");
    }
    let allocated = allocations() - before;
    assert_eq!(allocated, 0, "sync_read_into allocated {allocated} times");
    // Each servo answers its ID as the low byte; servo 4 is silent.
    for (id, p) in (1i16..).zip(&positions) {
        match p {
            Ok(steps) => assert_eq!(*steps, id),
            Err(m) => assert_eq!((m.id, m.reason), (4, MissingReason::NoReply)),
        }
    }
    assert!(positions[3].is_err());
}
