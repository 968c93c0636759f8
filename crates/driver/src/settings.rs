//! [`BusSettings`]: everything a [`Bus`](crate::Bus) needs to know about its
//! servos and link, per bus (two buses in one process may differ).

use std::time::Duration;

use servobus_protocol::registers::Series;
use servobus_timing::{LinkDelays, StatusLevel};

/// `with_*` methods, each giving the settings back with one field (or a
/// field of the link) set: `name(field.path: Type);` a line.
macro_rules! builders {
    ($($(#[$doc:meta])* $name:ident($($field:ident).+: $ty:ty);)*) => {$(
        $(#[$doc])*
        pub fn $name(mut self, value: $ty) -> Self {
            self.$($field).+ = value;
            self
        }
    )*};
}

/// Settings of one bus.
///
/// ```
/// use std::time::Duration;
/// use servobus_driver::BusSettings;
/// use servobus_protocol::registers::Series;
///
/// let s = BusSettings::new(Series::Sts)
///     .with_latency(Duration::from_millis(1))
///     .with_retries(2);
/// assert_eq!(s.link.latency, Duration::from_millis(1));
/// ```
///
/// The baud rate is not a setting: it belongs to the transport (given once,
/// when the port or the simulator is opened, and changed with
/// [`Bus::set_baud`](crate::Bus::set_baud)). The bus joins the two in
/// [`Bus::link`](crate::Bus::link).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub struct BusSettings {
    /// The servo family: register layout and byte order of this bus.
    pub series: Series,
    /// Adapter latency, turnaround and margin: with the transport's baud
    /// rate, every reply deadline is derived from them.
    pub link: LinkDelays,
    /// The servos' return delay (register 7; 2 us per unit).
    pub return_delay: Duration,
    /// How many times a failed transaction is tried again (0: never).
    pub retries: u8,
    /// Which instructions the servos answer: their status level (register
    /// 8). Replies are waited for only where this level sends them.
    pub replies: StatusLevel,
    /// Whether the adapter may echo requests back (half-duplex adapters
    /// without automatic direction control). When on (the default), the bus
    /// learns from the traffic whether this port echoes: a copy of a request
    /// that cannot be its reply (a WRITE, say), or a copy before a reply,
    /// shows that it does; a few replies in a row with no copy of the
    /// request before them show that it does not. Where a copy that could be
    /// the reply is all that came back (a PING to a servo whose status is
    /// 0x01, or a missing servo behind an echoing adapter), the bus asks
    /// that servo for one byte, whose copy cannot be its reply, and so
    /// tells the two apart at once. Until it knows, and once
    /// it knows the port echoes, one copy of each request (and any late copy
    /// of the previous one) is skipped; once it knows the port does not, a
    /// reply byte-identical to its request (a PING answered with status
    /// 0x01) is taken as the reply. Turn it off on an adapter known not to
    /// echo: nothing is then skipped, from the first request on. What the
    /// bus has learned is [`Bus::port_echoes`](crate::Bus::port_echoes); it
    /// can be told with [`Bus::set_port_echoes`](crate::Bus::set_port_echoes).
    pub echo: bool,
    /// Whether a reply with error flags set fails the transaction
    /// ([`BusError::Status`](crate::BusError::Status)) instead of returning
    /// the flags with the data.
    pub strict_status: bool,
}

impl BusSettings {
    /// Settings for a bus of `series` servos: no adapter latency, return
    /// delay 0, one retry, every instruction answered, echo looked for
    /// (see [`BusSettings::echo`]).
    pub fn new(series: Series) -> Self {
        BusSettings {
            series,
            link: LinkDelays::DEFAULT,
            return_delay: Duration::ZERO,
            retries: 1,
            replies: StatusLevel::All,
            echo: true,
            strict_status: false,
        }
    }

    builders! {
        /// The same settings for servos of another series.
        with_series(series: Series);
        /// The same settings with the adapter latency set.
        with_latency(link.latency: Duration);
        /// The same settings with the servos' return delay set.
        with_return_delay(return_delay: Duration);
        /// The same settings with the retry count set.
        with_retries(retries: u8);
        /// The same settings with the servos' status level set.
        with_replies(replies: StatusLevel);
        /// The same settings with echo skipping on or off.
        with_echo(echo: bool);
        /// The same settings with strict status on or off.
        with_strict_status(strict_status: bool);
        /// The same settings with the link's delays replaced.
        with_link(link: LinkDelays);
    }
}
