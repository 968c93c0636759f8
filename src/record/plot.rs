//! The plot of a run (`play --plot`): planned and measured position per
//! joint and every joint's tracking error, over time; for a robot with a
//! geometry, the measured path of its tool or feet in space.

use std::path::Path;

use anyhow::Context;

use servobus_config::Units;
use servobus_kinematics::Geometry;
use servobus_robot::CycleSample;

use super::frames::FrameTracker;
use super::space;

mod keyframes;

#[derive(Default)]
struct Series {
    /// The planned path (what the joint should be at; the log's
    /// `commanded` column is this path sent `lead` early).
    planned: Vec<(f64, f64)>,
    measured: Vec<(f64, f64)>,
    error: Vec<(f64, f64)>,
    /// The recording the run replays (`play FILE.csv`), at run times;
    /// empty for a motion, or a joint the recording does not name.
    recording: Vec<(f64, f64)>,
}

/// Planned and measured positions and tracking errors over time.
pub struct PlotData {
    names: Vec<String>,
    joints: Vec<Series>,
    /// The name of each joint's bus (said in the error panel's key).
    bus_of: Vec<String>,
    /// Run times at which a keyframe is reached (marked on every chart).
    keyframes: Vec<f64>,
    /// The end of the approach to the first keyframe, s (0: none).
    approach: f64,
    /// The named frames' measured paths, when the robot has a geometry.
    space: Option<SpacePaths>,
    /// What each joint's two lines are.
    key: Key,
}

/// What a joint's two lines are (said in the charts' captions).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Key {
    /// A run (`play`): the planned path and the measured positions.
    Run,
    /// `follow`: the leader's pose, which the follower steps towards (its
    /// planned path), and the follower's measured positions.
    Follow,
}

/// The measured paths of the named frames (tool, feet).
struct SpacePaths {
    tracker: FrameTracker,
    /// One path per frame, a point every [`SPACE_STEP_S`] at most.
    paths: space::Paths,
    /// The time of the last point, s.
    last: f64,
}

/// The plot's paths in space keep a point every 10 ms at most: finer adds
/// nothing a drawing shows.
const SPACE_STEP_S: f64 = 0.01;

/// The height of the row of views in space, px.
const SPACE_ROW: u32 = 430;

/// The colour of a replayed recording's line: a wide grey under the
/// planned and measured ones.
const RECORDING: plotters::style::RGBColor = plotters::style::RGBColor(128, 128, 128);

impl PlotData {
    /// Empty series for the joints `names`, each on the bus named in
    /// `bus_of`.
    pub fn new(names: Vec<String>, bus_of: Vec<String>) -> Self {
        let joints = names.iter().map(|_| Series::default()).collect();
        PlotData {
            names,
            joints,
            bus_of,
            keyframes: Vec::new(),
            approach: 0.0,
            space: None,
            key: Key::Run,
        }
    }

    /// With the robot's `geometry` (samples in `units`), the plot adds the
    /// measured path of every named frame (tool, feet), from above and
    /// from the side.
    pub fn with_frames(mut self, geometry: Option<Geometry>, units: Units) -> Self {
        self.space = geometry
            .and_then(|g| FrameTracker::new(g, units))
            .map(|tracker| SpacePaths {
                paths: tracker
                    .names()
                    .iter()
                    .map(|n| (n.clone(), Vec::new()))
                    .collect(),
                tracker,
                last: f64::NEG_INFINITY,
            });
        self
    }

    /// The plot of `follow`: the planned path is the leader's pose (the
    /// follower's goal), the measured one the follower's, and the captions
    /// say leader and follower.
    pub fn following(mut self) -> Self {
        self.key = Key::Follow;
        self
    }

    /// Marks keyframes reached at these run times, s.
    pub fn mark_keyframes(&mut self, times: impl IntoIterator<Item = f64>) {
        self.keyframes.extend(times);
    }

    /// Marks the approach to the first keyframe, from the start to `end` s.
    pub fn mark_approach(&mut self, end: f64) {
        self.approach = end.max(0.0);
    }

    /// Draws the recording a run replays beside it: per joint (robot
    /// order), its `(time, position)` samples on the path's clock, the
    /// path starting `start` s into the run (after the approach). A joint
    /// with no samples (not recorded) gets no recording line.
    pub fn mark_recording(&mut self, per_joint: &[Vec<(f64, f64)>], start: f64) {
        for (s, samples) in self.joints.iter_mut().zip(per_joint) {
            s.recording = samples.iter().map(|&(t, q)| (t + start, q)).collect();
        }
    }

    /// Whether a recording is drawn beside the run.
    fn has_recording(&self) -> bool {
        self.joints.iter().any(|s| !s.recording.is_empty())
    }

    /// Adds the joints of `sample`.
    pub fn record(&mut self, sample: &CycleSample) {
        let t = sample.time_s;
        if let Some(sp) = &mut self.space {
            sp.tracker.update(sample);
            if let Some(positions) = sp.tracker.positions() {
                if t - sp.last >= SPACE_STEP_S {
                    sp.last = t;
                    for ((_, path), p) in sp.paths.iter_mut().zip(positions) {
                        path.push(*p);
                    }
                }
            }
        }
        for j in sample.joints() {
            let Some(s) = self.joints.get_mut(j.joint) else {
                continue;
            };
            s.planned.push((t, j.planned));
            if let Some(m) = j.measured {
                if !j.stale {
                    s.measured.push((t, m));
                    s.error.push((t, j.error));
                }
            }
        }
    }

    /// Draws one chart per joint (planned and measured position) and one
    /// of every joint's tracking error, as SVG or (for a `.png` path) PNG,
    /// and writes it to `path` whole (an earlier file there is replaced
    /// only by a complete drawing).
    ///
    /// # Errors
    /// Drawing or encoding failed, or the file could not be written (the
    /// error names it).
    pub fn draw(&self, path: &Path, title: &str, units: &str) -> anyhow::Result<()> {
        let png = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("png"));
        let bytes = self
            .render(png, title, units)
            .with_context(|| format!("cannot draw {}", path.display()))?;
        servobus_robot::files::write_atomic(path, &bytes)?;
        Ok(())
    }

    /// The drawing of [`draw`](PlotData::draw), encoded as PNG or SVG.
    fn render(&self, png: bool, title: &str, units: &str) -> anyhow::Result<Vec<u8>> {
        let n = self.joints.len().max(1);
        let cols = if n <= 4 { 2 } else { 3 };
        let rows = n.div_ceil(cols);
        let width = 520 * cols as u32;
        let height = 60 + 300 * rows as u32 + 340 + self.space_row();
        if png {
            let mut rgb = vec![0u8; width as usize * height as usize * 3];
            let root = plotters::prelude::BitMapBackend::with_buffer(&mut rgb, (width, height));
            self.draw_on(root, title, units, rows, cols)?;
            let mut bytes = Vec::new();
            let mut encoder = png::Encoder::new(&mut bytes, width, height);
            encoder.set_color(png::ColorType::Rgb);
            encoder.set_depth(png::BitDepth::Eight);
            // A filter chosen per row: half the size of one filter for all.
            encoder.set_adaptive_filter(png::AdaptiveFilterType::Adaptive);
            let mut writer = encoder.write_header()?;
            writer.write_image_data(&rgb)?;
            writer.finish()?;
            Ok(bytes)
        } else {
            let mut svg = String::new();
            let root = plotters::prelude::SVGBackend::with_string(&mut svg, (width, height));
            self.draw_on(root, title, units, rows, cols)?;
            Ok(super::svg::round_font_sizes(&svg).into_bytes())
        }
    }

    /// Lays the drawing out on `backend`: the title, a grid of `rows` x
    /// `cols` joint panels, the error panel and its key, and the views in
    /// space below.
    fn draw_on<DB>(
        &self,
        backend: DB,
        title: &str,
        units: &str,
        rows: usize,
        cols: usize,
    ) -> anyhow::Result<()>
    where
        DB: plotters::prelude::DrawingBackend,
        DB::ErrorType: 'static,
    {
        use plotters::prelude::*;

        let root = backend.into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        let root = root.titled(title, ("sans-serif", 26)).map_err(plot_err)?;
        let (_, h) = root.dim_in_pixel();
        let (root, space_area) = root.split_vertically(h.saturating_sub(self.space_row()));
        if let Some(sp) = &self.space {
            space::draw(&space_area, &sp.paths)?;
        }
        let (_, h) = root.dim_in_pixel();
        let (grid, bottom) = root.split_vertically(h.saturating_sub(340));
        let cells = grid.split_evenly((rows, cols));
        for (j, (series, area)) in self.joints.iter().zip(cells.iter()).enumerate() {
            self.draw_joint(area, j, series, units)?;
        }
        // The error panel: chart on the left, its key beside it (never on
        // the curves); a colour of its own for every joint.
        let bw = bottom.dim_in_pixel().0;
        let (left, key) = bottom.split_horizontally(bw.saturating_sub(190));
        let colours = self.colours();
        self.draw_errors(&left, &colours, units)?;
        self.draw_error_key(&key, &colours)?;
        root.present().map_err(plot_err)?;
        Ok(())
    }

    /// Draws joint `j`'s panel on `area`: its planned and measured
    /// positions, over the recording it replays if any.
    fn draw_joint<DB>(
        &self,
        area: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
        j: usize,
        series: &Series,
        units: &str,
    ) -> anyhow::Result<()>
    where
        DB: plotters::prelude::DrawingBackend,
        DB::ErrorType: 'static,
    {
        use plotters::prelude::*;

        let name = self.names.get(j).map_or("?", String::as_str);
        let range = span(
            series
                .planned
                .iter()
                .chain(&series.measured)
                .chain(&series.recording),
        );
        // The key is in the caption: a legend box would cover curves.
        let caption = match self.key {
            Key::Run if self.has_recording() => {
                format!("{name}  (blue dashes: planned, red: measured, grey: recording)")
            }
            Key::Run => format!("{name}  (blue dashes: planned, red line: measured)"),
            Key::Follow => format!("{name}  (blue dashes: leader, red line: follower)"),
        };
        let y_desc = format!("position ({units})");
        let mut chart = self.panel(area, (&caption, 15), 32, range, y_desc, 2)?;
        // Under the others: where the replay keeps to the recording,
        // the grey shows either side of the planned and measured lines.
        if !series.recording.is_empty() {
            chart
                .draw_series(LineSeries::new(
                    series.recording.iter().copied(),
                    RECORDING.stroke_width(4),
                ))
                .map_err(plot_err)?;
        }
        chart
            .draw_series(DashedLineSeries::new(
                series.planned.iter().copied(),
                7,
                4,
                BLUE.stroke_width(2),
            ))
            .map_err(plot_err)?;
        chart
            .draw_series(LineSeries::new(
                series.measured.iter().copied(),
                RED.stroke_width(1),
            ))
            .map_err(plot_err)?;
        Ok(())
    }

    /// Draws every joint's tracking error on `area`, each in its colour of
    /// `colours`.
    fn draw_errors<DB>(
        &self,
        area: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
        colours: &[plotters::style::RGBColor],
        units: &str,
    ) -> anyhow::Result<()>
    where
        DB: plotters::prelude::DrawingBackend,
        DB::ErrorType: 'static,
    {
        use plotters::prelude::*;

        let range = span(self.joints.iter().flat_map(|s| s.error.iter()));
        let caption = self.error_caption();
        let mut chart = self.panel(
            area,
            (&caption, 16),
            36,
            range,
            format!("error ({units})"),
            10, // plotters' default
        )?;
        for (series, &color) in self.joints.iter().zip(colours) {
            chart
                .draw_series(LineSeries::new(
                    series.error.iter().copied(),
                    color.stroke_width(1),
                ))
                .map_err(plot_err)?;
        }
        Ok(())
    }

    /// Draws the error panel's key on `key`: a line of each joint's colour
    /// of `colours`, and its name and bus.
    fn draw_error_key<DB>(
        &self,
        key: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
        colours: &[plotters::style::RGBColor],
    ) -> anyhow::Result<()>
    where
        DB: plotters::prelude::DrawingBackend,
        DB::ErrorType: 'static,
    {
        use plotters::prelude::*;

        let rows = self.names.len().max(1) as i32;
        let (_, kh) = key.dim_in_pixel();
        let line = ((kh as i32 - 40) / rows).clamp(10, 22);
        let font = ("sans-serif", (line - 2).clamp(10, 15));
        for (j, (name, &color)) in self.names.iter().zip(colours).enumerate() {
            let y = 30 + j as i32 * line;
            key.draw(&PathElement::new([(4, y), (26, y)], color.stroke_width(3)))
                .map_err(plot_err)?;
            let bus = self.bus_of.get(j).map_or("?", String::as_str);
            key.draw(&Text::new(
                format!("{name} ({bus})"),
                (32, y - line / 2 + 2),
                font,
            ))
            .map_err(plot_err)?;
        }
        Ok(())
    }
}

/// A panel: time across, one quantity up.
type Chart<'a, DB> = plotters::prelude::ChartContext<
    'a,
    DB,
    plotters::prelude::Cartesian2d<
        plotters::coord::types::RangedCoordf64,
        plotters::coord::types::RangedCoordf64,
    >,
>;

impl PlotData {
    /// The height of the row of views in space: none without a path.
    fn space_row(&self) -> u32 {
        match &self.space {
            Some(sp) if sp.paths.iter().any(|(_, p)| !p.is_empty()) => SPACE_ROW,
            _ => 0,
        }
    }

    /// The end of the plots' time axis: the last planned sample (at least
    /// 1 ms, so that an empty recording still has an axis).
    fn t_end(&self) -> f64 {
        self.joints
            .iter()
            .flat_map(|s| s.planned.last())
            .map(|p| p.0)
            .fold(1e-3, f64::max)
    }

    /// A panel on `area`: `caption` (text, font size) above, time from 0 to
    /// the end across (`x_labels` pixels of labels), `range` up, named
    /// `y_desc`, a mesh with at most `light_lines` light lines per label,
    /// and the keyframes drawn.
    fn panel<'a, DB>(
        &self,
        area: &'a plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
        (caption, size): (&str, u32),
        x_labels: u32,
        range: std::ops::Range<f64>,
        y_desc: String,
        light_lines: usize,
    ) -> anyhow::Result<Chart<'a, DB>>
    where
        DB: plotters::prelude::DrawingBackend,
        DB::ErrorType: 'static,
    {
        use plotters::prelude::*;
        let mut chart = ChartBuilder::on(area)
            .caption(caption, ("sans-serif", size))
            .margin(8)
            .x_label_area_size(x_labels)
            .y_label_area_size(56)
            .build_cartesian_2d(0.0..self.t_end(), range.clone())
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc(y_desc)
            .max_light_lines(light_lines)
            .draw()
            .map_err(plot_err)?;
        self.draw_keyframes(&mut chart, &range)?;
        Ok(chart)
    }

    /// A colour of its own for every joint (the palette repeats past 20).
    fn colours(&self) -> Vec<plotters::style::RGBColor> {
        (0..self.names.len())
            .map(|j| {
                let (r, g, b) = space::PALETTE[j % space::PALETTE.len()];
                plotters::style::RGBColor(r, g, b)
            })
            .collect()
    }
}

fn plot_err<E: std::error::Error + Send + Sync + 'static>(e: E) -> anyhow::Error {
    anyhow::Error::new(e)
}

/// The y range of some points, padded by 5 % (at least a little).
fn span<'a>(points: impl Iterator<Item = &'a (f64, f64)>) -> std::ops::Range<f64> {
    let (lo, hi) = points.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(_, y)| {
        (lo.min(y), hi.max(y))
    });
    if !lo.is_finite() || !hi.is_finite() {
        return -1.0..1.0;
    }
    let pad = ((hi - lo) * 0.05).max(0.05);
    (lo - pad)..(hi + pad)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn svg(plot: &PlotData) -> String {
        let bytes = plot.render(false, "t", "deg").expect("drawn");
        String::from_utf8(bytes).expect("SVG text")
    }

    #[test]
    fn the_follow_plot_says_which_line_is_the_leader_and_which_the_follower() {
        let names = vec!["elbow".to_owned()];
        let bus = vec!["arm".to_owned()];
        let play = svg(&PlotData::new(names.clone(), bus.clone()));
        assert!(play.contains("blue dashes: planned, red line: measured"));
        let follow = svg(&PlotData::new(names, bus).following());
        assert!(
            follow.contains("elbow  (blue dashes: leader, red line: follower)"),
            "{follow}"
        );
        assert!(follow.contains("error against its leader"), "{follow}");
        // Nothing of a planned run is said: no keyframes, no approach.
        for word in ["planned", "keyframe", "approach"] {
            assert!(!follow.contains(word), "`{word}` in the follow plot");
        }
    }

    #[test]
    fn a_replayed_recording_is_drawn_beside_the_run_and_said_in_the_key() {
        let names = vec!["elbow".to_owned(), "wrist".to_owned()];
        let bus = vec!["arm".to_owned(); 2];
        let plain = svg(&PlotData::new(names.clone(), bus.clone()));
        assert!(!plain.contains("recording"), "{plain}");
        assert!(!plain.contains("#808080"), "{plain}");
        let mut replay = PlotData::new(names, bus);
        // The wrist not recorded: no line of its own.
        replay.mark_recording(&[vec![(0.0, 1.0), (0.5, 2.0)], Vec::new()], 0.25);
        assert_eq!(replay.joints[0].recording, [(0.25, 1.0), (0.75, 2.0)]);
        assert!(replay.joints[1].recording.is_empty());
        let drawn = svg(&replay);
        assert!(
            drawn.contains("elbow  (blue dashes: planned, red: measured, grey: recording)"),
            "{drawn}"
        );
        assert_eq!(drawn.matches("stroke=\"#808080\"").count(), 1, "{drawn}");
    }
}
