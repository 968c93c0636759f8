//! The hot path — SYNC WRITE then SYNC READ, every control cycle — does not
//! allocate once the bus is built. Counted with a global allocator wrapper,
//! over a transport that itself never allocates.

use std::time::Duration;

use servobus_alloc_count::{allocations, Counting};
use servobus_driver::{Bus, BusSettings, Clock, ManualClock, Transport, TransportError};
use servobus_protocol::registers::Series;
use servobus_protocol::{encode, parse_frame, Instruction, StatusFlags};

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Answers a SYNC READ of 2 bytes from every listed servo (except ID 4,
/// which is silent) with its ID as data, from a fixed buffer.
struct FixedServos {
    clock: ManualClock,
    out: [u8; 1024],
    len: usize,
    pos: usize,
}

impl Transport for FixedServos {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        self.clock
            .advance(Duration::from_micros(10) * bytes.len() as u32);
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

    fn read(&mut self, buf: &mut [u8], deadline: Duration) -> Result<usize, TransportError> {
        if self.pos == self.len {
            self.clock.advance_to(deadline);
            return Err(TransportError::TimedOut);
        }
        let n = buf.len().min(self.len - self.pos);
        buf[..n].copy_from_slice(&self.out[self.pos..self.pos + n]);
        self.pos += n;
        self.clock.advance(Duration::from_micros(10) * n as u32);
        Ok(n)
    }

    fn discard_input(&mut self) -> Result<(), TransportError> {
        self.pos = self.len;
        Ok(())
    }
}

#[test]
fn sync_write_and_sync_read_do_not_allocate() {
    let clock = ManualClock::new();
    let transport = FixedServos {
        clock: clock.clone(),
        out: [0; 1024],
        len: 0,
        pos: 0,
    };
    let settings = BusSettings::new(Series::Sts, 1_000_000).with_latency(Duration::from_millis(1));
    let mut bus = Bus::new(transport, clock.clone(), settings);
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
