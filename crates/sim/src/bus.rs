//! [`SimBus`]: many simulated servos on one bus, in virtual time.

use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use servobus_io::{Clock, ManualClock, Transport, TransportError};

use crate::engine::{Engine, SimStats};
use crate::{Faults, SimServo};

/// A simulated bus of servos that implements [`Transport`] in virtual time.
///
/// Every byte costs its wire time at the bus's baud rate on the shared
/// [`ManualClock`]: [`write_all`](Transport::write_all) moves the clock to the
/// end of the request; [`read`](Transport::read) moves it to when the next
/// bytes arrive, or to the deadline when none do (then
/// [`TransportError::TimedOut`]). A read returns the contiguous burst of
/// bytes that began arriving first (as a USB adapter delivers a reply once
/// the line goes idle), cut at the deadline.
///
/// The bus is a cheap handle: clones share the same servos, so a test can
/// hand one clone to the code under test and inspect the servos through
/// another.
///
/// ```
/// use std::time::Duration;
/// use servobus_io::{Clock, ManualClock, Transport};
/// use servobus_protocol::encode;
/// use servobus_sim::{SimBus, SimServo};
///
/// let clock = ManualClock::new();
/// let mut bus = SimBus::new(clock.clone(), 1_000_000)
///     .with_servo(SimServo::sts3215(1).with_return_delay(Duration::ZERO));
/// let mut frame = [0u8; 16];
/// let n = encode::ping(&mut frame, 1).unwrap();
/// bus.write_all(&frame[..n]).unwrap();
/// assert_eq!(clock.now(), Duration::from_micros(60)); // 6 bytes at 10 us
/// let mut reply = [0u8; 16];
/// let got = bus.read(&mut reply, Duration::from_millis(1)).unwrap();
/// assert_eq!(&reply[..got], &[0xFF, 0xFF, 0x01, 0x02, 0x00, 0xFC]);
/// // 50 us of the servo's turnaround, then 6 bytes.
/// assert_eq!(clock.now(), Duration::from_micros(170));
/// ```
#[derive(Debug, Clone)]
pub struct SimBus {
    clock: ManualClock,
    engine: Arc<Mutex<Engine>>,
}

impl SimBus {
    /// An empty bus at `baud` on `clock`.
    pub fn new(clock: ManualClock, baud: u32) -> SimBus {
        SimBus {
            clock,
            engine: Arc::new(Mutex::new(Engine::new(baud))),
        }
    }

    fn engine(&self) -> MutexGuard<'_, Engine> {
        // A panic while the lock was held leaves the engine consistent
        // enough for tests to report what they see: recover the guard.
        self.engine.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The bus with `servo` added.
    #[must_use]
    pub fn with_servo(self, servo: SimServo) -> SimBus {
        self.add_servo(servo);
        self
    }

    /// The bus with every servo of `servos` added.
    #[must_use]
    pub fn with_servos(self, servos: impl IntoIterator<Item = SimServo>) -> SimBus {
        for s in servos {
            self.add_servo(s);
        }
        self
    }

    /// The bus with `faults` injected (the random source is reseeded).
    #[must_use]
    pub fn with_faults(self, faults: Faults) -> SimBus {
        self.set_faults(faults);
        self
    }

    /// The bus echoing every request back, as a half-duplex adapter without
    /// direction control does.
    #[must_use]
    pub fn with_echo(self, on: bool) -> SimBus {
        self.engine().faults.echo = on;
        self
    }

    /// The bus with a processing time `turnaround` added before every
    /// servo's return delay, instead of its model's turnaround (the figure
    /// the budget charges).
    #[must_use]
    pub fn with_turnaround(self, turnaround: Duration) -> SimBus {
        self.engine().turnaround = Some(turnaround);
        self
    }

    /// The bus with a host adapter that delivers each byte `latency` after
    /// it arrived (default 0).
    #[must_use]
    pub fn with_latency(self, latency: Duration) -> SimBus {
        self.engine().latency = latency;
        self
    }

    /// Changes the host adapter's latency from now on (a link that slows
    /// down or speeds up mid-run).
    pub fn set_latency(&self, latency: Duration) {
        self.engine().latency = latency;
    }

    /// Adds a servo and returns its index (servos are numbered in the order
    /// they were added).
    pub fn add_servo(&self, servo: SimServo) -> usize {
        let now = self.clock.now();
        let mut servo = servo;
        servo.advance_to(now);
        self.engine().add_servo(servo)
    }

    /// Replaces the injected faults (and reseeds the random source).
    pub fn set_faults(&self, faults: Faults) {
        self.engine().set_faults(faults);
    }

    /// The injected faults.
    pub fn faults(&self) -> Faults {
        self.engine().faults.clone()
    }

    /// The clock the bus runs on.
    pub fn clock(&self) -> &ManualClock {
        &self.clock
    }

    /// The host's baud rate.
    pub fn baud(&self) -> u32 {
        self.engine().link.baud
    }

    /// Changes the host's baud rate; servos whose baud-rate register differs
    /// no longer understand it.
    pub fn set_baud(&self, baud: u32) {
        self.engine().link = servobus_timing::Link::new(baud);
    }

    /// Number of servos on the bus, connected or not.
    pub fn servo_count(&self) -> usize {
        self.engine().servos.len()
    }

    /// The IDs of the servos, in the order they were added.
    pub fn ids(&self) -> Vec<u8> {
        self.engine().servos.iter().map(SimServo::id).collect()
    }

    /// Runs `f` on the first servo whose current ID is `id`, after stepping
    /// it to the clock's time; `None` when there is none.
    pub fn servo<R>(&self, id: u8, f: impl FnOnce(&mut SimServo) -> R) -> Option<R> {
        let now = self.clock.now();
        let mut e = self.engine();
        let s = e.servos.iter_mut().find(|s| s.id() == id)?;
        s.advance_to(now);
        Some(f(s))
    }

    /// Runs `f` on the servo with index `index` (see [`SimBus::add_servo`]).
    pub fn servo_at<R>(&self, index: usize, f: impl FnOnce(&mut SimServo) -> R) -> Option<R> {
        let now = self.clock.now();
        let mut e = self.engine();
        let s = e.servos.get_mut(index)?;
        s.advance_to(now);
        Some(f(s))
    }

    /// A copy of servo `id` as it is now.
    pub fn snapshot(&self, id: u8) -> Option<SimServo> {
        self.servo(id, |s| s.clone())
    }

    /// One register byte of servo `id`.
    pub fn register(&self, id: u8, address: u8) -> Option<u8> {
        self.servo(id, |s| s.register(address))
    }

    /// Present position of servo `id`.
    pub fn present_position(&self, id: u8) -> Option<i32> {
        self.servo(id, |s| s.present_position())
    }

    /// Power-cycles every servo (see [`SimServo::power_cycle`]).
    pub fn power_cycle(&self) {
        let now = self.clock.now();
        let mut e = self.engine();
        for s in &mut e.servos {
            s.advance_to(now);
            s.power_cycle();
        }
    }

    /// Unplugs (or replugs) the adapter: every transport call fails with
    /// [`TransportError::Disconnected`] while unplugged.
    pub fn set_disconnected(&self, disconnected: bool) {
        self.engine().disconnected = disconnected;
    }

    /// What happened on the bus so far.
    pub fn stats(&self) -> SimStats {
        self.engine().stats
    }

    /// Bytes sent towards the host that it has not read yet, including
    /// those still on the wire.
    pub fn pending_bytes(&self) -> usize {
        self.engine().rx.len()
    }

    /// Steps every servo's dynamics to the clock's time.
    pub fn settle(&self) {
        let now = self.clock.now();
        self.engine().advance_servos(now);
    }
}

fn unplugged() -> TransportError {
    TransportError::Disconnected("simulated adapter unplugged".into())
}

impl Transport for SimBus {
    type Clock = ManualClock;

    fn clock(&self) -> &ManualClock {
        &self.clock
    }

    fn baud(&self) -> u32 {
        SimBus::baud(self)
    }

    /// Any positive rate: the servos whose baud-rate register selects
    /// another one stop hearing the bus (see [`SimBus::set_baud`]).
    fn set_baud(&mut self, baud: u32) -> Result<(), TransportError> {
        if baud == 0 {
            return Err(TransportError::BaudRefused {
                requested: baud,
                current: SimBus::baud(self),
            });
        }
        SimBus::set_baud(self, baud);
        Ok(())
    }

    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        let now = self.clock.now();
        let end = {
            let mut e = self.engine();
            if e.disconnected {
                return Err(unplugged());
            }
            e.transmit(bytes, now)
        };
        self.clock.advance_to(end);
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], deadline: Duration) -> Result<usize, TransportError> {
        if buf.is_empty() {
            return Ok(0);
        }
        let now = self.clock.now();
        let mut e = self.engine();
        if e.disconnected {
            return Err(unplugged());
        }
        match e.next_ready() {
            Some(ready) if ready <= deadline.max(now) => {
                let until = e.burst_end(now, deadline, buf.len());
                self.clock.advance_to(until);
                Ok(e.take_ready(until.max(now), buf))
            }
            _ => {
                drop(e);
                self.clock.advance_to(deadline);
                Err(TransportError::TimedOut)
            }
        }
    }

    fn discard_input(&mut self) -> Result<(), TransportError> {
        let now = self.clock.now();
        let mut e = self.engine();
        if e.disconnected {
            return Err(unplugged());
        }
        e.discard(now);
        Ok(())
    }
}
