//! The time of a reading is when the servos took it, not when the loop's
//! thread got round to decoding the reply: in virtual time, a thread that
//! is descheduled after the reply's bytes arrived (the clock jumps forward
//! inside the read) tracks exactly as well as one that is not.

use crate::common;

use std::time::Duration;

use servobus_driver::{Bus, ManualClock, Transport, TransportError};
use servobus_runtime::{Finish, Report, VirtualRun};
use servobus_sim::SimBus;

/// A simulated bus whose reader is descheduled: on the first read that
/// brings bytes after a request, the clock moves on by the next delay of
/// `delays` (cycled) before the bytes are handed over, as when the reply
/// arrived and the thread woke that much later.
struct Descheduled {
    inner: SimBus,
    delays: &'static [Duration],
    next: usize,
    /// A request went out and no byte of its answer has been read yet.
    waiting: bool,
}

impl Transport for Descheduled {
    type Clock = ManualClock;

    fn clock(&self) -> &ManualClock {
        self.inner.clock()
    }

    fn baud(&self) -> u32 {
        self.inner.baud()
    }

    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        self.waiting = true;
        self.inner.write_all(bytes)
    }

    fn read(&mut self, buf: &mut [u8], deadline: Duration) -> Result<usize, TransportError> {
        let n = self.inner.read(buf, deadline)?;
        if n > 0 && std::mem::take(&mut self.waiting) {
            let delay = self.delays[self.next % self.delays.len()];
            self.next += 1;
            self.inner.clock().advance(delay);
        }
        Ok(n)
    }

    fn discard_input(&mut self) -> Result<(), TransportError> {
        self.inner.discard_input()
    }
}

/// Delays after a reply came, cycled over the requests: most cycles none,
/// some up to 1.5 ms (of the SO-101's 5 ms cycle, whose bus work takes
/// about 1.7 ms), as a loaded two-core machine shows them.
const STALLS: [Duration; 7] = [
    Duration::ZERO,
    Duration::from_micros(1500),
    Duration::ZERO,
    Duration::from_micros(700),
    Duration::ZERO,
    Duration::ZERO,
    Duration::from_micros(1000),
];

const NO_STALLS: [Duration; 1] = [Duration::ZERO];

fn wave(delays: &'static [Duration]) -> Report {
    let (path, robot) = common::motion("arm-wave.yaml");
    let (buses, _) = common::sim_buses_at(&robot, &path);
    let buses: Vec<Bus<Descheduled>> = buses
        .into_iter()
        .map(|b| {
            let settings = *b.settings();
            let inner = b.into_transport();
            let t = Descheduled {
                inner,
                delays,
                next: 0,
                waiting: false,
            };
            Bus::new(t, settings)
        })
        .collect();
    let r = VirtualRun::new(&robot, path, buses, common::quiet())
        .expect("starts")
        .run();
    assert_eq!(r.finish, Finish::Completed);
    r
}

#[test]
fn a_thread_descheduled_after_the_reply_tracks_as_well_as_a_prompt_one() {
    let prompt = wave(&NO_STALLS);
    let late = wave(&STALLS);
    for (name, r) in [("prompt", &prompt), ("descheduled", &late)] {
        println!(
            "{name:12} lead {:.2} ms  worst max {:.3} deg  worst rms {:.3} deg  timeouts {}",
            r.lead_ms,
            r.worst_max_error(),
            r.worst_rms_error(),
            r.buses[0].timeouts
        );
    }
    // The stalls cost no reading: every delay fits the cycle.
    assert_eq!(late.buses[0].missed_replies, 0, "{:?}", late.buses[0]);
    // Per joint, the descheduled run's worst and RMS errors are the prompt
    // run's (equal in this build; 0.01 deg worst and 0.005 deg RMS allowed
    // for a lead learned a hair apart). Stamped when the thread woke, as
    // before this test was written, a reading 1.5 ms late on a joint at
    // 100 deg/s was compared with the path 0.15 deg further on: the worst
    // error went from 0.42 deg prompt to 0.57 deg descheduled
    // (shoulder_lift 0.21 to 0.29 deg).
    for (p, l) in prompt.joints.iter().zip(&late.joints) {
        let figures = [
            ("worst", l.max_error, p.max_error, 0.01),
            ("rms", l.rms_error, p.rms_error, 0.005),
        ];
        for (what, late, prompt, margin) in figures {
            assert!(
                late <= prompt + margin,
                "{} {what}: {late} vs {prompt}",
                p.name
            );
        }
    }
}
