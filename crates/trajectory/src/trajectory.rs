//! The planned path: sampling, cursor, and the figures `servobus plan` prints.

use crate::piece::Piece;
use std::sync::atomic::{AtomicU64, Ordering};

mod summary;

pub use summary::JointSummary;

/// Position, velocity and acceleration of one joint.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct JointState {
    /// Position, in the limits' unit.
    pub position: f64,
    /// Velocity, unit per second.
    pub velocity: f64,
    /// Acceleration, unit per second squared.
    pub acceleration: f64,
}

impl JointState {
    /// A joint at rest at `position`.
    pub fn at_rest(position: f64) -> Self {
        JointState {
            position,
            velocity: 0.0,
            acceleration: 0.0,
        }
    }
}

/// When one segment (the motion arriving at a keyframe) starts and ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentTiming {
    /// Index, in the keyframe list given to [`plan`](crate::plan), of the
    /// keyframe this segment arrives at.
    pub keyframe: usize,
    /// Which repetition (0-based) of the keyframe list.
    pub cycle: usize,
    /// Start time, s.
    pub start: f64,
    /// End time (arrival at the keyframe), s.
    pub end: f64,
}

/// A multi-joint path: a sequence of polynomial pieces per joint, all
/// starting at time 0 and ending at [`duration`](Self::duration). Before 0
/// it holds the start state and after the end it holds the final position
/// at rest.
#[derive(Debug, Clone)]
pub struct Trajectory {
    /// Identifies the piece layout for cursors (clones share it: same
    /// layout).
    pub(crate) id: u64,
    pub(crate) duration: f64,
    /// Per joint, its pieces in time order (never empty). Kept as the
    /// planner built them (no copy into one array: sampling reads the
    /// cursor's copies, not these).
    pub(crate) pieces: Vec<Vec<Piece>>,
    pub(crate) segments: Vec<SegmentTiming>,
    /// Final position per joint (held at rest from `duration` on).
    pub(crate) end: Vec<f64>,
    /// Every piece is of degree <= 3 (constant-jerk phases and cubic
    /// splines: every untimed or cubic plan), so sampling can skip the
    /// quintic terms without testing each piece.
    pub(crate) cubic: bool,
}

/// Remembers, per joint, the piece last sampled, so that sampling at
/// increasing (or slowly changing) times is O(1). Made once by
/// [`Trajectory::cursor`]; reusable across trajectories (it falls back to a
/// binary search when its memory does not fit).
#[derive(Debug, Clone, Default)]
pub struct Cursor {
    /// The trajectory `index` refers to.
    id: u64,
    /// Per joint, an index into the trajectory's pieces of that joint.
    index: Vec<usize>,
    /// Per joint, a copy of `pieces[j][index[j]]`: while `t` stays inside
    /// the current pieces, sampling reads only these contiguous arrays (no
    /// indirection, no bounds check per joint). Same length as `index`.
    hot: Hot,
}

/// The cursor's copies of the current pieces, one array per field (struct
/// of arrays): the loop over joints reads every field contiguously and can
/// evaluate two joints per vector instruction.
#[derive(Debug, Clone, Default)]
struct Hot {
    t0: Vec<f64>,
    t1: Vec<f64>,
    /// `c[k][j]`: coefficient `k` of joint `j`'s piece.
    c: [Vec<f64>; 6],
}

impl Hot {
    fn len(&self) -> usize {
        self.t0.len()
    }

    /// Joint `j`'s piece becomes `p`.
    fn set(&mut self, j: usize, p: &Piece) {
        self.t0[j] = p.t0;
        self.t1[j] = p.t1;
        for (c, &v) in self.c.iter_mut().zip(&p.c) {
            c[j] = v;
        }
    }
}

/// Source of trajectory ids (0 is never used, so a default cursor matches
/// nothing).
static NEXT_ID: AtomicU64 = AtomicU64::new(1);

/// A method of [`Trajectory`] that is `sample_hot_any` compiled for one
/// vector extension of x86-64. The arithmetic is the same, operation for
/// operation (no fused multiply-add), so the samples are the same to the
/// bit. An `unsafe fn`: the caller checks the CPU.
macro_rules! sample_hot_for {
    ($(#[$doc:meta])* $name:ident, $feature:literal) => {
        $(#[$doc])*
        ///
        /// # Safety
        #[doc = concat!("The CPU must have `", $feature, "`.")]
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $feature)]
        unsafe fn $name(&self, hot: &mut Hot, index: &mut [usize], t: f64, out: &mut [JointState]) {
            self.sample_hot_any(hot, index, t, out);
        }
    };
}

impl Trajectory {
    /// Builds from per-joint pieces covering `[0, end]` (gaps are not
    /// allowed; a joint without pieces holds `hold[j]`).
    pub(crate) fn from_joints(
        per_joint: Vec<Vec<Piece>>,
        hold: &[f64],
        duration: f64,
        segments: Vec<SegmentTiming>,
    ) -> Self {
        let mut pieces = per_joint;
        // Whether every piece kept is a cubic, learnt in the same pass over
        // the pieces as the empty ones are dropped.
        let mut cubic = true;
        for (joint, &h) in pieces.iter_mut().zip(hold) {
            joint.retain(|p| {
                let keep = p.duration() > 0.0;
                cubic &= !keep || (p.c[4] == 0.0 && p.c[5] == 0.0);
                keep
            });
            // The planner reserves for the worst case; keep only what is
            // used (shrinking in place, as allocators usually do), unless
            // only the one spare piece for a final rest is left over.
            if joint.capacity() > joint.len() + 1 {
                joint.shrink_to_fit();
            }
            if let Some(last) = joint.last_mut() {
                // Rounding in accumulated phase times may leave the last
                // piece a few ulps short of (or past) the end: snap it.
                last.t1 = duration.max(last.t0);
            } else {
                joint.push(Piece::hold(0.0, duration, h));
            }
        }
        let end = pieces
            .iter()
            .map(|joint| joint.last().map_or(0.0, |p| p.eval(duration).0))
            .collect();
        Trajectory {
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
            duration,
            pieces,
            segments,
            end,
            cubic,
        }
    }

    /// Number of joints.
    pub fn joints(&self) -> usize {
        self.pieces.len()
    }

    /// Total duration, s.
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// Start and end time of every segment, in order.
    pub fn segments(&self) -> &[SegmentTiming] {
        &self.segments
    }

    /// A cursor for [`sample_with`](Self::sample_with). Allocates once.
    pub fn cursor(&self) -> Cursor {
        let n = self.joints();
        let index = vec![0; n];
        let mut hot = Hot {
            t0: vec![0.0; n],
            t1: vec![0.0; n],
            c: core::array::from_fn(|_| vec![0.0; n]),
        };
        for (j, joint) in self.pieces.iter().enumerate() {
            hot.set(j, &joint[0]);
        }
        Cursor {
            id: self.id,
            index,
            hot,
        }
    }

    fn joint_pieces(&self, j: usize) -> &[Piece] {
        &self.pieces[j]
    }

    /// Samples every joint at time `t` (s) into `out` by binary search;
    /// O(log n) per joint, no allocation. Writes `min(out.len(), joints)`
    /// entries.
    pub fn sample(&self, t: f64, out: &mut [JointState]) {
        if t >= self.duration {
            self.final_state(out);
            return;
        }
        let t = t.max(0.0);
        for (j, o) in out.iter_mut().enumerate().take(self.joints()) {
            let ps = self.joint_pieces(j);
            let i = ps.partition_point(|p| p.t1 < t).min(ps.len() - 1);
            *o = state(&ps[i], t);
        }
    }

    /// Samples every joint at time `t` (s) into `out`, starting the search
    /// at the cursor's pieces: O(1) when `t` moves forward in steps shorter
    /// than a piece, as in a control loop. No allocation. Writes
    /// `min(out.len(), joints)` entries.
    #[inline]
    pub fn sample_with(&self, cursor: &mut Cursor, t: f64, out: &mut [JointState]) {
        if t >= self.duration {
            // At rest at the end (a trapezoid's last piece still decelerates
            // at its very end).
            self.final_state(out);
            return;
        }
        let t = t.max(0.0);
        let n = self.joints().min(out.len());
        if cursor.id != self.id {
            if cursor.index.len() < self.joints() || cursor.hot.len() < self.joints() {
                // A cursor of another trajectory with fewer joints (or a
                // default one): cannot grow without allocating, so search.
                self.sample(t, out);
                return;
            }
            self.reset(cursor);
        }
        // Invariant from here: for every joint `j < joints`,
        // `index[j] < pieces[j].len()` and the `hot` entries of joint `j`
        // are those of `pieces[j][index[j]]`.
        let (hot, index) = (&mut cursor.hot, &mut cursor.index);
        // The widest vectors the CPU has (the checks are cached).
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU has AVX-512F, the one feature the function
            // is compiled for (checked just above).
            unsafe { self.sample_hot_avx512(hot, index, t, &mut out[..n]) };
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, the one feature the function is
            // compiled for (checked just above).
            unsafe { self.sample_hot_avx2(hot, index, t, &mut out[..n]) };
            return;
        }
        self.sample_hot_any(hot, index, t, &mut out[..n]);
    }

    /// [`sample_hot`](Self::sample_hot) of this trajectory's degree.
    #[inline(always)]
    fn sample_hot_any(&self, hot: &mut Hot, index: &mut [usize], t: f64, out: &mut [JointState]) {
        if self.cubic {
            self.sample_hot::<true>(hot, index, t, out);
        } else {
            self.sample_hot::<false>(hot, index, t, out);
        }
    }

    sample_hot_for! {
        /// [`sample_hot_any`](Self::sample_hot_any) compiled for AVX-512F:
        /// eight joints per vector instruction instead of two. 18 joints
        /// sample in about 2/3 of the time.
        sample_hot_avx512, "avx512f"
    }

    sample_hot_for! {
        /// [`sample_hot_any`](Self::sample_hot_any) compiled for AVX2: four
        /// joints per vector instruction.
        sample_hot_avx2, "avx2"
    }

    /// The loop of `sample_with` over the joints of `out`; `CUBIC`: every
    /// piece is of degree <= 3. `hot` and `index` have at least as many
    /// entries as `out`.
    ///
    /// Every joint is evaluated in its current piece first, with no branch
    /// and no call in the loop (so `t` and the constants stay in registers
    /// and the evaluations of consecutive joints overlap); the rare joints
    /// whose piece did not hold `t` are then moved on and sampled again.
    #[inline(always)]
    fn sample_hot<const CUBIC: bool>(
        &self,
        hot: &mut Hot,
        index: &mut [usize],
        t: f64,
        out: &mut [JointState],
    ) {
        let n = out.len().min(hot.len()).min(index.len());
        let out = &mut out[..n];
        let (t0, t1) = (&hot.t0[..n], &hot.t1[..n]);
        let [c0, c1, c2, c3, c4, c5] = &hot.c;
        let (c0, c1, c2, c3) = (&c0[..n], &c1[..n], &c2[..n], &c3[..n]);
        let (c4, c5) = (&c4[..n], &c5[..n]);
        let mut miss = false;
        for j in 0..n {
            // Inside the piece `t - t0` is within `[0, t1 - t0]` (float
            // subtraction is monotone), so no clamp is needed; outside it
            // the value is overwritten below.
            miss |= (t < t0[j]) | (t > t1[j]);
            let x = t - t0[j];
            out[j] = if CUBIC {
                // `Piece::eval_local`'s arithmetic for degree <= 3.
                JointState {
                    position: c0[j] + x * (c1[j] + x * (c2[j] + x * c3[j])),
                    velocity: c1[j] + x * (2.0 * c2[j] + x * (3.0 * c3[j])),
                    acceleration: 2.0 * c2[j] + x * (6.0 * c3[j]),
                }
            } else {
                let p = Piece {
                    t0: t0[j],
                    t1: t1[j],
                    c: [c0[j], c1[j], c2[j], c3[j], c4[j], c5[j]],
                };
                local_state(&p, x)
            };
        }
        if miss {
            for (j, o) in out.iter_mut().enumerate() {
                if t < hot.t0[j] || t > hot.t1[j] {
                    let p = self.seek(j, &mut index[j], t);
                    hot.set(j, p);
                    *o = state(p, t);
                }
            }
        }
    }

    /// Points `cursor` at the first piece of every joint of this trajectory.
    /// Precondition: the cursor has at least `joints` entries.
    #[cold]
    fn reset(&self, cursor: &mut Cursor) {
        let n = self.joints();
        cursor.index[..n].fill(0);
        for (j, joint) in self.pieces.iter().enumerate() {
            cursor.hot.set(j, &joint[0]);
        }
        cursor.id = self.id;
    }

    /// Slow path of `sample_with`: moves joint `j`'s cursor to the piece
    /// holding `t` (or the nearest one, which only matters if rounding left
    /// a gap between pieces: sampling clamps to it).
    #[cold]
    #[inline(never)]
    fn seek(&self, j: usize, idx: &mut usize, t: f64) -> &Piece {
        let joint = &self.pieces[j];
        let mut i = *idx;
        if t > joint[i].t1 {
            // Usually one of the next few pieces (short jerk phases may
            // be skipped in one control period); otherwise search.
            let mut steps = 0;
            while i + 1 < joint.len() && t > joint[i].t1 && steps < 4 {
                i += 1;
                steps += 1;
            }
            if t > joint[i].t1 {
                i = joint.partition_point(|p| p.t1 < t);
            }
        } else {
            i = joint.partition_point(|p| p.t1 < t);
        }
        let i = i.min(joint.len() - 1);
        *idx = i;
        &joint[i]
    }

    /// The state of every joint at the end (at rest at the last keyframe).
    pub fn final_state(&self, out: &mut [JointState]) {
        for (o, &p) in out.iter_mut().zip(&self.end) {
            *o = JointState::at_rest(p);
        }
    }
}

#[inline(always)]
fn local_state(p: &Piece, x: f64) -> JointState {
    joint_state(p.eval_local(x))
}

#[inline(always)]
fn state(p: &Piece, t: f64) -> JointState {
    joint_state(p.eval(t))
}

#[inline(always)]
fn joint_state((position, velocity, acceleration): (f64, f64, f64)) -> JointState {
    JointState {
        position,
        velocity,
        acceleration,
    }
}

#[cfg(test)]
mod tests {
    use crate::{plan, JointLimits, JointState, Keyframe, PlanOptions};

    #[test]
    fn the_cursor_samples_as_the_search_does_to_the_bit() {
        // Seven joints (a vector's worth and some over, whatever its
        // width), through four keyframes, sampled at 1 kHz: the cursor's
        // loop (vectorised for the CPU at hand) and the search agree.
        let limits = vec![JointLimits::new(2.0, 10.0, Some(100.0)); 7];
        let pose = |k: f64| (0..7).map(|j| (k + f64::from(j)).sin()).collect::<Vec<_>>();
        let keyframes: Vec<Keyframe> = (0..4).map(|k| Keyframe::new(pose(f64::from(k)))).collect();
        let traj = plan(&limits, &keyframes, &PlanOptions::default()).expect("it plans");
        let mut cursor = traj.cursor();
        let (mut a, mut b) = ([JointState::default(); 7], [JointState::default(); 7]);
        let mut k = 0u32;
        while f64::from(k) * 1e-3 <= traj.duration() + 0.01 {
            let t = f64::from(k) * 1e-3;
            traj.sample_with(&mut cursor, t, &mut a);
            traj.sample(t, &mut b);
            assert_eq!(a, b, "at {t} s");
            k += 1;
        }
        assert!(k > 1000, "{k} samples");
    }
}
