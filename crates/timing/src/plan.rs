//! Cycle planning: can this bus run this cycle at this rate, and if not,
//! what runs instead.

use core::ops::Range;

use servobus_protocol::MAX_ID;

use crate::cost::{CycleCost, CycleSpec, Servo};
pub use crate::error::CycleError;
use crate::fix::{Change, Fixes};
use crate::{servos_per_frame, Block, Link};

/// The most servos one bus can have: one per valid ID (0..=253).
pub const MAX_SERVOS: usize = MAX_ID as usize + 1;

/// The longest block a servo can send back in one reply (its length byte is
/// L + 2 <= 255).
pub const MAX_READ_LEN: u8 = 253;

/// How feedback is spread over cycles: every cycle reads the servos of one
/// group, groups taking turns, so each servo is read every `every` cycles.
///
/// Groups are contiguous runs of `per_cycle` servos in the order given to
/// [`plan`] (the last may be shorter): group `g` is servos
/// `g * per_cycle..(g + 1) * per_cycle`, read in cycles `c` with
/// `c % every == g`. Contiguous groups let a runtime pass a sub-slice of its
/// ID list straight to a SYNC READ encoder.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RoundRobin {
    /// Each servo is read once every this many cycles (1: every cycle).
    pub every: usize,
    /// Servos read per cycle (the size of every group but maybe the last).
    pub per_cycle: usize,
    /// The most expensive cycle of the rotation.
    pub worst: CycleCost,
}

/// A cycle plan for one bus at one rate. Built by [`plan`]; allocation-free
/// and `Copy`, so a runtime can keep it in its control loop.
///
/// The figures of `servobus budget --json` come straight from it, for the
/// full cycle (goals written to and feedback read from every servo):
/// [`servos`](Plan::servos), [`bytes_per_cycle`](Plan::bytes_per_cycle),
/// [`wire_time_us`](Plan::wire_time_us), [`cycle_time_us`](Plan::cycle_time_us),
/// [`max_rate_hz`](Plan::max_rate_hz), [`rate_hz`](Plan::rate_hz) and
/// [`utilisation`](Plan::utilisation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plan {
    link: Link,
    rate_hz: f64,
    write: Option<Block>,
    read: Option<Block>,
    full: CycleCost,
    schedule: RoundRobin,
    fixes: Fixes,
    count: usize,
    ids: [u8; MAX_SERVOS],
}

impl Plan {
    /// The link the plan is for.
    pub fn link(&self) -> &Link {
        &self.link
    }
    /// The block written to every servo each cycle.
    pub fn write(&self) -> Option<Block> {
        self.write
    }
    /// The block read back.
    pub fn read(&self) -> Option<Block> {
        self.read
    }
    /// The number of servos on the bus.
    pub fn servos(&self) -> usize {
        self.count
    }
    /// The servos' IDs in the order given to [`plan`].
    pub fn ids(&self) -> &[u8] {
        &self.ids[..self.count]
    }
    /// The rate the plan is for, Hz.
    pub fn rate_hz(&self) -> f64 {
        self.rate_hz
    }

    /// The full cycle: every servo written and read back.
    pub fn full_cycle(&self) -> &CycleCost {
        &self.full
    }
    /// Bytes on the wire per full cycle, both directions.
    pub fn bytes_per_cycle(&self) -> usize {
        self.full.bytes
    }
    /// Wire time of the full cycle, us.
    pub fn wire_time_us(&self) -> f64 {
        self.full.wire_time_us()
    }
    /// Expected duration of the full cycle with return delays, turnarounds
    /// and adapter latencies, us.
    pub fn cycle_time_us(&self) -> f64 {
        self.full.cycle_time_us()
    }
    /// The highest rate at which the full cycle fits, Hz.
    pub fn max_rate_hz(&self) -> f64 {
        self.full.max_rate_hz()
    }
    /// The fastest rate to offer people: the maximum floored to a whole
    /// hertz ([`floor_rate_hz`](crate::floor_rate_hz)), Hz.
    pub fn fastest_rate_hz(&self) -> f64 {
        self.full.fastest_rate_hz()
    }
    /// The highest rate the wire alone would allow, Hz.
    pub fn wire_limited_rate_hz(&self) -> f64 {
        self.full.wire_limited_rate_hz()
    }
    /// The fraction of each period the full cycle takes at the plan's rate
    /// (above 1.0 when it does not fit).
    pub fn utilisation(&self) -> f64 {
        self.full.utilisation(self.rate_hz)
    }
    /// Whether the full cycle fits the rate (every servo read every cycle).
    pub fn is_feasible(&self) -> bool {
        self.full.fits(self.rate_hz)
    }

    /// How feedback is spread over cycles (`every == 1` when the full cycle
    /// fits).
    pub fn schedule(&self) -> &RoundRobin {
        &self.schedule
    }
    /// Each servo is read once every this many cycles.
    pub fn read_every(&self) -> usize {
        self.schedule.every
    }
    /// The most expensive cycle actually run: the full one, or the worst of
    /// the round-robin rotation.
    pub fn worst_cycle(&self) -> &CycleCost {
        &self.schedule.worst
    }
    /// Indices (into the servos given to [`plan`]) of the servos read back
    /// in cycle number `cycle` (counting from 0); empty when nothing is read.
    pub fn reads_in_cycle(&self, cycle: u64) -> Range<usize> {
        if self.read.is_none() {
            return 0..0;
        }
        let every = self.schedule.every as u64;
        // `every` >= 1, and the group index is below `every` <= 254.
        let group = (cycle % every) as usize;
        let start = group * self.schedule.per_cycle;
        let end = (start + self.schedule.per_cycle).min(self.count);
        start.min(end)..end
    }
    /// IDs of the servos read back in cycle number `cycle`, in request order.
    pub fn read_ids(&self, cycle: u64) -> &[u8] {
        &self.ids[self.reads_in_cycle(cycle)]
    }

    /// The changes that would make the full cycle fit, cheapest first
    /// (empty when it fits).
    pub fn fixes(&self) -> &Fixes {
        &self.fixes
    }
    /// The cheapest change that would make the full cycle fit.
    pub fn cheapest_fix(&self) -> Option<Change> {
        self.fixes.cheapest()
    }
}

/// Plans the cycle of a bus: every servo gets the `write` block (one or more
/// SYNC WRITE frames), then the `read` block comes back (one SYNC READ for
/// the servos that support it, one READ for each that does not), `rate_hz`
/// times a second.
///
/// When the full cycle does not fit, the plan reads a round-robin subset of
/// the servos each cycle (the fewest groups that fit, see [`RoundRobin`]) and
/// lists the changes that would make the full cycle fit ([`Plan::fixes`]).
/// Nothing allocates.
///
/// For a bus of a robot file, build the link as
/// `Link::new(bus.baud).with_latency(bus.latency)` and one
/// `Servo::new(joint.id, bus.return_delay, series.has_sync_read())` per
/// joint, in the order of the file; `servobus budget` plans
/// `Some(Block::GOAL_POSITION)` and `Some(Block::PRESENT_POSITION)` at the
/// robot's rate.
///
/// ```
/// use core::time::Duration;
/// use servobus_timing::{plan, Block, Link, Servo};
///
/// let link = Link::new(1_000_000).with_turnaround(Duration::ZERO);
/// let servos: [Servo; 6] = core::array::from_fn(|i| Servo::sts(i as u8 + 1, Duration::ZERO));
/// let p = plan(&link, &servos, Some(Block::GOAL_POSITION), Some(Block::PRESENT_POSITION), 500.0)?;
/// assert_eq!(p.bytes_per_cycle(), 26 + 14 + 48);
/// assert_eq!(p.cycle_time_us(), 880.0);
/// assert!(p.is_feasible());
/// # Ok::<(), servobus_timing::CycleError>(())
/// ```
///
/// # Errors
/// [`CycleError::NoServos`], [`CycleError::TooManyServos`],
/// [`CycleError::InvalidId`], [`CycleError::DuplicateId`],
/// [`CycleError::InvalidRate`], [`CycleError::InvalidBlock`], or
/// [`CycleError::Infeasible`] when no round-robin subset fits either (it names
/// the cheapest change that would make the full cycle fit).
pub fn plan(
    link: &Link,
    servos: &[Servo],
    write: Option<Block>,
    read: Option<Block>,
    rate_hz: f64,
) -> Result<Plan, CycleError> {
    check_request(servos, write, read, rate_hz)?;
    let ids = collect_ids(servos)?;
    let count = servos.len();
    let spec = CycleSpec {
        link: *link,
        written: count,
        write,
        read_len: read.map(|b| b.len),
        zero_return_delay: false,
    };
    let full = spec.cost(servos);
    let (schedule, fixes) = choose_schedule(&spec, servos, &full, rate_hz)?;
    Ok(Plan {
        link: *link,
        rate_hz,
        write,
        read,
        full,
        schedule,
        fixes,
        count,
        ids,
    })
}

/// Refuses an empty or oversized bus, a rate that is not positive, and a
/// block no frame can carry.
fn check_request(
    servos: &[Servo],
    write: Option<Block>,
    read: Option<Block>,
    rate_hz: f64,
) -> Result<(), CycleError> {
    let count = servos.len();
    if count == 0 {
        return Err(CycleError::NoServos);
    }
    if count > MAX_SERVOS {
        return Err(CycleError::TooManyServos { count });
    }
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(CycleError::InvalidRate { rate_hz });
    }
    if let Some(block) = write {
        if !block.is_valid() || servos_per_frame(block.len) == 0 {
            return Err(CycleError::InvalidBlock { block });
        }
    }
    if let Some(block) = read {
        if !block.is_valid() || block.len > MAX_READ_LEN {
            return Err(CycleError::InvalidBlock { block });
        }
    }
    Ok(())
}

/// The servos' IDs in order (at most [`MAX_SERVOS`] of them), refusing an
/// invalid or repeated one.
fn collect_ids(servos: &[Servo]) -> Result<[u8; MAX_SERVOS], CycleError> {
    let mut ids = [0u8; MAX_SERVOS];
    let mut seen = [0u64; 4];
    for (slot, s) in ids.iter_mut().zip(servos) {
        if s.id > MAX_ID {
            return Err(CycleError::InvalidId { id: s.id });
        }
        let (word, bit) = (usize::from(s.id / 64), 1u64 << (s.id % 64));
        if seen[word] & bit != 0 {
            return Err(CycleError::DuplicateId { id: s.id });
        }
        seen[word] |= bit;
        *slot = s.id;
    }
    Ok(ids)
}

/// Every servo read each cycle when the `full` cycle fits, else the
/// round-robin schedule and the fixes; [`CycleError::Infeasible`] when no
/// schedule fits.
fn choose_schedule(
    spec: &CycleSpec,
    servos: &[Servo],
    full: &CycleCost,
    rate_hz: f64,
) -> Result<(RoundRobin, Fixes), CycleError> {
    if full.fits(rate_hz) {
        let all = RoundRobin {
            every: 1,
            per_cycle: servos.len(),
            worst: *full,
        };
        return Ok((all, Fixes::default()));
    }
    let fixes = Fixes::find(spec, servos, full, rate_hz);
    match round_robin(spec, servos, rate_hz) {
        Some(rr) => Ok((rr, fixes)),
        None => {
            // The cheapest cycle possible: everything written, the
            // cheapest single servo read (or nothing, if nothing is read).
            let min_cycle_time = if spec.read_len.is_some() {
                servos
                    .chunks(1)
                    .map(|one| spec.cost(one).cycle_time)
                    .min()
                    .unwrap_or(full.cycle_time)
            } else {
                full.cycle_time
            };
            let fix = fixes.cheapest().unwrap_or(Change::LowerRate {
                rate_hz: full.fastest_rate_hz(),
            });
            Err(CycleError::Infeasible {
                rate_hz,
                min_cycle_time,
                fix,
            })
        }
    }
}

/// The round-robin schedule with the fewest groups whose worst cycle fits,
/// or `None` when even one servo per cycle does not (or nothing is read).
fn round_robin(spec: &CycleSpec, servos: &[Servo], rate_hz: f64) -> Option<RoundRobin> {
    spec.read_len?;
    let n = servos.len();
    let uniform = servos
        .windows(2)
        .all(|w| w[0].return_delay == w[1].return_delay && w[0].sync_read == w[1].sync_read);
    for every in 2..=n {
        // Balanced groups: the smallest group size that gives `every` groups.
        let per_cycle = n.div_ceil(every);
        if n.div_ceil(per_cycle) != every {
            // The same group size as a smaller `every` already tried.
            continue;
        }
        let worst = if uniform {
            // Alike servos: the first group is the largest, so the costliest.
            spec.cost(&servos[..per_cycle])
        } else {
            servos
                .chunks(per_cycle)
                .map(|group| spec.cost(group))
                .max_by_key(|c| c.cycle_time)?
        };
        if worst.fits(rate_hz) {
            return Some(RoundRobin {
                every,
                per_cycle,
                worst,
            });
        }
    }
    None
}
