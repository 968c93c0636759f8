//! [`WallBus`]: a [`SimBus`] in wall-clock time, in its client's process.
//!
//! `servobus play` on the built-in simulator needs servos that answer in
//! real time, but nothing outside the process talks to them, so a
//! pseudo-terminal would only add the kernel's hand-off between two threads
//! (the pty's line discipline runs in a kernel worker that competes with
//! every other task for the CPU). On a loaded machine that hand-off, not
//! the simulated wire, made replies late and counted healthy servos as
//! missing. Here the client's own thread computes each reply when it reads:
//! a byte is handed over once the wire has carried it (never earlier), and a
//! reply that became due while the client was descheduled is waiting for it
//! when it wakes, as in an adapter's receive buffer.
//!
//! The simulated servos keep their own [`ManualClock`](servobus_io::ManualClock),
//! which every call first moves up to the wall clock's time (plus the fixed
//! offset between the two clocks when the bus was made: a simulated robot
//! may have been settled for a while in virtual time before it goes live),
//! so the servos' dynamics follow the wall clock.

use std::time::Duration;

use servobus_io::{Clock, Transport, TransportError};

use crate::SimBus;

/// A simulated bus whose bytes arrive on the wall clock `C`; see the module
/// docs. It is the transport's clock ([`Transport::clock`]), so a driver's
/// `Bus` built on it measures its reply deadlines from the same epoch as
/// this bus's wire times.
#[derive(Debug, Clone)]
pub struct WallBus<C> {
    sim: SimBus,
    wall: C,
    /// Simulated time minus wall time.
    offset: Duration,
}

impl<C: Clock> WallBus<C> {
    /// `sim` paced by `wall`, from now on: the simulated clock goes on from
    /// where it stands (or from the wall clock's time, if that is later).
    pub fn new(sim: SimBus, wall: C) -> Self {
        let offset = sim.clock().now().saturating_sub(wall.now());
        let bus = WallBus { sim, wall, offset };
        bus.catch_up();
        bus
    }

    /// Moves the simulated time up to now. It may already be ahead: a
    /// request written is on the wire until its last byte's time.
    fn catch_up(&self) {
        self.sim.clock().advance_to(self.wall.now() + self.offset);
    }
}

impl<C: Clock> Transport for WallBus<C> {
    /// The wall clock: the client's deadlines are on its time base.
    type Clock = C;

    fn clock(&self) -> &C {
        &self.wall
    }

    fn baud(&self) -> u32 {
        self.sim.baud()
    }

    fn set_baud(&mut self, baud: u32) -> Result<(), TransportError> {
        self.catch_up();
        Transport::set_baud(&mut self.sim, baud)
    }

    fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        // Like an adapter, the write returns once the bytes are queued; the
        // wire time is spent by whoever waits for the reply.
        self.catch_up();
        self.sim.write_all(bytes)
    }

    fn read(&mut self, buf: &mut [u8], deadline: Duration) -> Result<usize, TransportError> {
        self.catch_up();
        let got = self.sim.read(buf, deadline + self.offset);
        // The simulated clock now stands where the bytes finished arriving
        // (or at the deadline): do not hand them over before that.
        let arrived = self.sim.clock().now().saturating_sub(self.offset);
        self.wall.sleep_until(arrived);
        got
    }

    fn discard_input(&mut self) -> Result<(), TransportError> {
        self.catch_up();
        self.sim.discard_input()
    }
}

#[cfg(test)]
mod tests {
    use servobus_io::ManualClock;
    use servobus_protocol::encode;

    use super::*;
    use crate::SimServo;

    /// The test's wall clock: a second manual clock, moved by hand to play
    /// a client that is descheduled (its `sleep_until` jumps forward).
    type Wall = ManualClock;

    fn ping() -> Vec<u8> {
        let mut frame = [0u8; 16];
        let n = encode::ping(&mut frame, 1).expect("a PING fits");
        frame[..n].to_vec()
    }

    /// Servo 1 behind a wall bus, and a handle on the simulated bus (a
    /// clone shares its servos) to fault them.
    fn bus(wall: &Wall) -> (WallBus<Wall>, SimBus) {
        let sim = SimBus::new(ManualClock::new(), 1_000_000)
            .with_servo(SimServo::sts3215(1).with_return_delay(Duration::ZERO));
        (WallBus::new(sim.clone(), wall.clone()), sim)
    }

    #[test]
    fn a_reply_is_handed_over_when_the_wire_has_carried_it() {
        let wall = Wall::default();
        wall.advance_to(Duration::from_millis(5));
        let (mut bus, _) = bus(&wall);
        bus.write_all(&ping()).expect("write");
        let mut reply = [0u8; 16];
        let n = bus
            .read(&mut reply, Duration::from_millis(6))
            .expect("the servo answers");
        assert_eq!(&reply[..n], &[0xFF, 0xFF, 0x01, 0x02, 0x00, 0xFC]);
        // 6 request bytes (60 us at 1 Mbaud), the STS3215's 50 us
        // turnaround, 6 reply bytes (60 us): 170 us after the write.
        assert_eq!(wall.now(), Duration::from_micros(5_170));
    }

    #[test]
    fn a_simulated_clock_ahead_of_the_wall_keeps_its_lead() {
        let wall = Wall::default();
        wall.advance_to(Duration::from_millis(1));
        let sim = SimBus::new(ManualClock::new(), 1_000_000)
            .with_servo(SimServo::sts3215(1).with_return_delay(Duration::ZERO));
        // The robot was settled for 10 s of virtual time before going live.
        sim.clock().advance_to(Duration::from_secs(10));
        let mut bus = WallBus::new(sim.clone(), wall.clone());
        bus.write_all(&ping()).expect("write");
        let mut reply = [0u8; 16];
        // The deadline is the wall clock's: 1 ms from its now.
        let n = bus
            .read(&mut reply, Duration::from_millis(2))
            .expect("the servo answers within the wall clock's deadline");
        assert_eq!(n, 6);
        assert_eq!(wall.now(), Duration::from_micros(1_170));
        assert_eq!(sim.clock().now(), Duration::from_micros(10_000_170));
    }

    #[test]
    fn a_reply_due_while_the_client_slept_is_waiting_for_it() {
        let wall = Wall::default();
        let (mut bus, _) = bus(&wall);
        bus.write_all(&ping()).expect("write");
        // The client is descheduled for 20 ms, far past its 1 ms deadline.
        wall.advance_to(Duration::from_millis(20));
        let mut reply = [0u8; 16];
        let n = bus
            .read(&mut reply, Duration::from_millis(1))
            .expect("the reply arrived while the client was away");
        assert_eq!(n, 6);
        assert_eq!(wall.now(), Duration::from_millis(20), "no extra wait");
    }

    #[test]
    fn a_silent_servo_costs_exactly_the_deadline() {
        let wall = Wall::default();
        let (mut bus, sim) = bus(&wall);
        sim.set_faults(crate::Faults {
            vanish: vec![1],
            ..crate::Faults::default()
        });
        bus.write_all(&ping()).expect("write");
        let mut reply = [0u8; 16];
        let got = bus.read(&mut reply, Duration::from_micros(900));
        assert!(matches!(got, Err(TransportError::TimedOut)), "{got:?}");
        assert_eq!(wall.now(), Duration::from_micros(900));
    }

    #[test]
    fn a_servo_told_to_vanish_after_2_ms_answers_until_then() {
        let faults: crate::Faults = "vanish=1@0.002".parse().expect("spec");
        assert_eq!(
            faults,
            crate::Faults::none().vanish_after(1, Duration::from_millis(2))
        );
        assert!("vanish=1@soon".parse::<crate::Faults>().is_err());
        assert!("vanish=1@-1".parse::<crate::Faults>().is_err());
        let wall = Wall::default();
        let (mut bus, sim) = bus(&wall);
        sim.set_faults(faults);
        let mut reply = [0u8; 16];
        // The first byte at 0 starts the 2 ms; at 1 ms it still answers.
        bus.write_all(&ping()).expect("write");
        assert!(bus.read(&mut reply, Duration::from_millis(1)).is_ok());
        wall.advance_to(Duration::from_millis(2));
        bus.write_all(&ping()).expect("write");
        let got = bus.read(&mut reply, Duration::from_millis(3));
        assert!(matches!(got, Err(TransportError::TimedOut)), "{got:?}");
    }
}
