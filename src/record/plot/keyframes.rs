//! The keyframes on the plot's charts, and the error panel's caption that
//! says what the marks are.

use super::{plot_err, Chart, Key, PlotData};

/// Above this many keyframes, they are marked by ticks along the top of
/// each chart only: full-height lines that close together would grey the
/// whole chart out and hide the curves.
const KEYFRAME_LINES_UP_TO: usize = 60;

/// Keyframes closer together than this share of the time axis (3 px on a
/// joint's chart) are one run, marked by a bracket along the top from its
/// first to its last: a walk's or a line's samples, 20 ms apart, would
/// otherwise be a tick each and together a solid bar.
const KEYFRAME_RUN_GAP: f64 = 1.0 / 150.0;

impl PlotData {
    /// The error panel's caption: what the error is, and the marks on
    /// the charts that there are.
    pub(super) fn error_caption(&self) -> String {
        let mut caption = match self.key {
            Key::Run => "tracking error (planned minus measured)",
            Key::Follow => {
                "the follower's error against its leader (the leader's pose, as the follower's \
                 goal, minus the follower's)"
            }
        }
        .to_owned();
        if self.approach > 0.0 {
            caption += "; grey band: approach";
        }
        if !self.keyframes.is_empty() {
            caption += "; black line: first keyframe";
        }
        let (single, runs) = self.keyframe_marks();
        if !single.is_empty() {
            caption += "; grey: keyframes";
        }
        if !runs.is_empty() {
            caption += "; grey bracket on top: keyframes too close to mark one by one";
        }
        caption
    }

    /// The keyframes after the first, as marks: each on its own, and runs
    /// `(first, last)` of keyframes less than [`KEYFRAME_RUN_GAP`] of the
    /// time axis apart.
    fn keyframe_marks(&self) -> (Vec<f64>, Vec<(f64, f64)>) {
        let gap = self.t_end() * KEYFRAME_RUN_GAP;
        let (mut single, mut runs) = (Vec::new(), Vec::new());
        let mut rest = self.keyframes.iter().skip(1).copied().peekable();
        while let Some(first) = rest.next() {
            let mut last = first;
            while let Some(&next) = rest.peek() {
                if next - last >= gap {
                    break;
                }
                last = next;
                rest.next();
            }
            if last > first {
                runs.push((first, last));
            } else {
                single.push(first);
            }
        }
        (single, runs)
    }

    /// The approach as a light band, the first keyframe as a black line,
    /// the others as thin grey lines (as ticks along the top only when
    /// there are more than [`KEYFRAME_LINES_UP_TO`]), and runs of keyframes
    /// too close to tell apart as a grey bracket along the top.
    pub(super) fn draw_keyframes<DB: plotters::prelude::DrawingBackend>(
        &self,
        chart: &mut Chart<'_, DB>,
        range: &std::ops::Range<f64>,
    ) -> anyhow::Result<()>
    where
        DB::ErrorType: 'static,
    {
        use plotters::prelude::*;
        if self.approach > 0.0 {
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(0.0, range.start), (self.approach, range.end)],
                    RGBColor(225, 225, 225).filled(),
                )))
                .map_err(plot_err)?;
        }
        let grey = RGBColor(150, 150, 150).stroke_width(1);
        let (single, runs) = self.keyframe_marks();
        let tick = range.end - (range.end - range.start) * 0.06;
        let from = if single.len() > KEYFRAME_LINES_UP_TO {
            tick
        } else {
            range.start
        };
        chart
            .draw_series(
                single
                    .iter()
                    .map(|&t| PathElement::new([(t, from), (t, range.end)], grey)),
            )
            .map_err(plot_err)?;
        chart
            .draw_series(runs.iter().flat_map(|&(a, b)| {
                // |---| under the top edge: a tick at each end, a line
                // between.
                let bar = range.end - (range.end - range.start) * 0.03;
                [
                    PathElement::new([(a, tick), (a, range.end)], grey.stroke_width(2)),
                    PathElement::new([(a, bar), (b, bar)], grey.stroke_width(2)),
                    PathElement::new([(b, tick), (b, range.end)], grey.stroke_width(2)),
                ]
            }))
            .map_err(plot_err)?;
        if let Some(&t) = self.keyframes.first() {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    [(t, range.start), (t, range.end)],
                    BLACK.stroke_width(2),
                )))
                .map_err(plot_err)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keyframes_too_close_to_tell_apart_are_one_run_the_others_single() {
        let mut plot = PlotData::new(vec!["a".to_owned()], vec!["b".to_owned()]);
        // A time axis of 16 s (a run gap under 0.107 s): a pose at 1 s,
        // a walk's 400 samples 20 ms apart from 2 s, two poses 1 s apart.
        let mut times = vec![0.5, 1.0];
        times.extend((0..400).map(|k| 2.0 + 0.02 * f64::from(k)));
        times.extend([12.0, 13.0]);
        plot.mark_keyframes(times);
        plot.joints[0].planned.extend([(0.0, 0.0), (16.0, 0.0)]);
        let (single, runs) = plot.keyframe_marks();
        assert_eq!(single, vec![1.0, 12.0, 13.0]);
        assert_eq!(runs.len(), 1);
        assert!((runs[0].0 - 2.0).abs() < 1e-12 && (runs[0].1 - 9.98).abs() < 1e-9);
    }
}
