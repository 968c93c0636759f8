//! Benches of servobus-driver: the SYNC WRITE of one control cycle through
//! [`Bus::sync_write`], onto a transport that only counts the bytes (so the
//! figure is the driver's packing and bookkeeping, not a port's).
//!
//! - `driver/sync_write/L7/18`: one frame (18 servos x 7 bytes).
//! - `driver/sync_write/L7/64`: three frames (31 servos per frame at most).

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion};
use servobus_driver::scripted::{Received, Script, ScriptedPort};
use servobus_driver::{Bus, BusSettings, ManualClock, TransportError};
use servobus_protocol::registers::Series;

/// Takes every frame and answers nothing (a SYNC WRITE waits for no reply).
struct Sink {
    bytes: u64,
}

impl Script for Sink {
    fn write(&mut self, _clock: &ManualClock, bytes: &[u8]) -> Result<(), TransportError> {
        self.bytes += bytes.len() as u64;
        Ok(())
    }

    fn read(&mut self, _clock: &ManualClock, _buf: &mut [u8], _deadline: Duration) -> Received {
        Err(TransportError::TimedOut)
    }

    fn discard(&mut self, _clock: &ManualClock) {}
}

/// Registers the benches of this module.
pub fn benches(c: &mut Criterion) {
    let mut g = c.benchmark_group("driver/sync_write");
    let ids: [u8; 64] = core::array::from_fn(|i| i as u8 + 1);
    let data: [u8; 64 * 7] = core::array::from_fn(|i| i as u8);
    let settings = BusSettings::new(Series::Sts);
    let port = ScriptedPort::new(&ManualClock::new(), Sink { bytes: 0 });
    let mut bus = Bus::new(port, settings);
    for n in [18usize, 64] {
        g.bench_function(BenchmarkId::new("L7", n), |b| {
            b.iter(|| {
                bus.sync_write(41, black_box(&ids[..n]), black_box(&data[..n * 7]))
                    .expect("a valid SYNC WRITE")
            })
        });
    }
    black_box(bus.transport().script.bytes);
    g.finish();
}
