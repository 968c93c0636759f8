//! An untimed section: as fast as the limits allow, or, when a timed
//! keyframe follows, scaled uniformly to arrive exactly on its time.

use super::{OnLimit, Sections};
use crate::error::PlanError;
use crate::untimed;

impl Sections<'_> {
    /// Plans the untimed section from entry `i` up to a timed entry (which
    /// it then reaches on time), a boundary or the end; returns the entry
    /// it ends at.
    pub(super) fn untimed(&mut self, i: usize) -> Result<usize, PlanError> {
        let entries = self.entries;
        let last = entries.len() - 1;
        let mut k = i + 1;
        while k < last && entries[k + 1].at.is_none() && !entries[k].boundary {
            k += 1;
        }
        let anchored = k < last && entries[k + 1].at.is_some() && !entries[k].boundary;
        let j = if anchored { k + 1 } else { k };
        self.pos.clear();
        self.pos.extend(entries[i..=j].iter().map(|e| e.pos));
        let start = self.arrival[i];
        let first_piece: Vec<usize> = self.out.iter().map(Vec::len).collect();
        untimed::section(
            self.limits,
            &self.pos,
            start,
            self.options.stop_at_keyframes,
            &mut self.scratch,
            &mut self.out,
        );
        let needed: f64 = self.scratch.durations.iter().sum();
        let mut scale = 1.0;
        if anchored {
            let target = self.base + entries[j].at.unwrap_or(0.0) + self.delay;
            let available = target - start;
            if needed > available * (1.0 + 1e-12) {
                if self.options.on_limit == OnLimit::Error || available <= 0.0 && needed <= 0.0 {
                    return Err(PlanError::TooSoon {
                        keyframe: entries[j].index,
                        needed,
                        available,
                    });
                }
            } else if needed > 0.0 {
                scale = available / needed;
            } else if available > 0.0 {
                // Nothing moves: hold until the keyframe's time.
                self.scratch.durations[0] = available;
                for (o, &f) in self.out.iter_mut().zip(&first_piece) {
                    for p in &mut o[f..] {
                        p.t1 = p.t0 + available;
                    }
                }
            }
        }
        if scale != 1.0 {
            for (o, &f) in self.out.iter_mut().zip(&first_piece) {
                for p in &mut o[f..] {
                    *p = p.stretched(start, scale);
                }
            }
        }
        let mut t = start;
        for (k, d) in self.scratch.durations.iter().enumerate() {
            t += d * scale;
            self.arrival[i + 1 + k] = t;
        }
        Ok(j)
    }
}
