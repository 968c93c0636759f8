//! Tick arithmetic across the 4095 -> 0 seam of a full-turn position sensor.
//!
//! An STS servo's sensor counts 4096 ticks per turn and wraps from 4095 to
//! 0. A joint whose range contains that point reads, say, 3900 at one end
//! and 200 at the other. servobus keeps such positions *unwrapped*: the same
//! range is `[3900, 4296]`, one number line, so minimum, maximum, middle
//! and differences mean what they say. Only the register sees wrapped
//! values, and only through the functions here.
//!
//! ```text
//!   0        200                 3900    4095 | 4096     4296
//!   |=========|                     |=========|==========|
//!   wrapped: two pieces              unwrapped: one range
//! ```

/// Ticks per turn of a model whose sensor covers a full turn (STS/SMS:
/// 4096), `None` for one that covers less (SCS: 1024 over about 300
/// degrees), whose positions cannot wrap.
pub fn turn_ticks(model: &servobus_protocol::registers::Model) -> Option<i32> {
    let full = model.range_deg >= 360.0;
    full.then(|| i32::try_from(model.resolution).unwrap_or(i32::MAX))
}

/// `reading` moved by whole turns to lie within half a turn of `near`.
pub fn unwrap_near(reading: f64, near: f64, turn: i32) -> f64 {
    let turn = f64::from(turn);
    reading + ((near - reading) / turn).round() * turn
}

/// Follows one sensor through successive readings and gives its unwrapped
/// position: each step is taken as the shorter way round, which is right
/// as long as the joint turns less than half a turn between two readings
/// (a hand needs well over a second for that; readings come every few ms).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Unwrapper {
    turn: Option<i32>,
    last: i32,
    value: i64,
}

impl Unwrapper {
    /// Starts at `first`, which is also the first unwrapped value.
    pub fn new(first: i32, turn: Option<i32>) -> Self {
        Unwrapper {
            turn,
            last: first,
            value: i64::from(first),
        }
    }

    /// Takes the next reading; returns the unwrapped position.
    pub fn push(&mut self, reading: i32) -> i64 {
        let step = match self.turn {
            Some(turn) => {
                let half = turn / 2;
                (reading - self.last + half).rem_euclid(turn) - half
            }
            None => reading - self.last,
        };
        self.last = reading;
        self.value += i64::from(step);
        self.value
    }

    /// The unwrapped position now.
    pub fn value(&self) -> i64 {
        self.value
    }
}

/// The whole number of turns to subtract from an unwrapped range's
/// minimum so that it lands in `[0, turn)`.
pub fn turns_below(min: i64, turn: i32) -> i64 {
    min.div_euclid(i64::from(turn))
}

/// The largest magnitude of the homing offset register (sign-magnitude
/// with the sign in bit 11).
pub const MAX_HOMING_OFFSET: i32 = 2047;

/// The homing offset and the shift of the present-position frame that put
/// the middle of `range` (unwrapped ticks in the frame of `offset`) at the
/// middle of the turn, so that the range no longer crosses the seam.
///
/// Present position = actual - offset (mod turn). Adding `shift` to the
/// offset subtracts it from every present position. Returns
/// `(new_offset, shift)` with `|new_offset| <= 2047`: a turn of 4096 has one
/// offset, 2048, that the register cannot hold; the shift then moves one
/// tick less, which keeps the range well inside the turn.
pub fn centring_offset(range: [i64; 2], offset: i32, turn: i32) -> (i32, i64) {
    let mid = (range[0] + range[1]).div_euclid(2);
    let mut shift = mid - i64::from(turn / 2);
    let wrapped = |s: i64| -> i32 {
        let t = i64::from(turn);
        let v = (i64::from(offset) + s).rem_euclid(t);
        // v in [0, turn): the representable twin is v or v - turn.
        let v = if v > t / 2 { v - t } else { v };
        i32::try_from(v).unwrap_or(i32::MAX)
    };
    let mut new = wrapped(shift);
    if new.abs() > MAX_HOMING_OFFSET {
        shift -= 1;
        new = wrapped(shift);
    }
    (new, shift)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unwrapping_follows_a_joint_across_the_seam_both_ways() {
        let mut u = Unwrapper::new(4000, Some(4096));
        assert_eq!(u.push(4090), 4090);
        assert_eq!(u.push(5), 4101);
        assert_eq!(u.push(300), 4396);
        assert_eq!(u.push(4080), 4080);
        assert_eq!(u.push(3500), 3500);
        // Below zero the other way.
        let mut d = Unwrapper::new(10, Some(4096));
        assert_eq!(d.push(4000), -96);
        assert_eq!(turns_below(-96, 4096), -1);
    }

    #[test]
    fn a_range_across_the_seam_is_centred_by_the_offset() {
        // Sensor range 3900..4296 with no offset: middle 4098 must become 2048.
        let (offset, shift) = centring_offset([3900, 4296], 0, 4096);
        assert_eq!(shift, 2050);
        assert_eq!(offset, 2050 - 4096);
        // The range in the new frame: inside the turn, middle at 2048.
        assert_eq!([3900 - shift, 4296 - shift], [1850, 2246]);
        // Present = actual - offset, wrapped: the sensor tick 200 (unwrapped
        // 4296) reads 200 + 2046 = 2246.
        assert_eq!((200 - offset).rem_euclid(4096), 2246);
    }

    #[test]
    fn the_unrepresentable_offset_moves_one_tick_less() {
        // Middle at 4096 (sensor 0): an offset of 2048 would be needed.
        let (offset, shift) = centring_offset([4000, 4192], 0, 4096);
        assert!(offset.abs() <= MAX_HOMING_OFFSET, "{offset}");
        assert_eq!(shift, 2047);
        // An offset already present adds up and wraps.
        let (offset, shift) = centring_offset([100, 300], 2000, 4096);
        assert_eq!(shift, 200 - 2048);
        assert_eq!(offset, 2000 + 200 - 2048);
    }

    #[test]
    fn readings_unwrap_near_the_range() {
        assert_eq!(unwrap_near(50.0, 4100.0, 4096), 4146.0);
        assert_eq!(unwrap_near(4090.0, 100.0, 4096), -6.0);
        assert_eq!(unwrap_near(2000.0, 2048.0, 4096), 2000.0);
    }
}
