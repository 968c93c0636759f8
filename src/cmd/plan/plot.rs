//! `plan --plot`: position and velocity of every joint over time, and the
//! planned paths in space. A legged robot's joints are drawn leg by leg
//! (one panel per leg, its coxa, femur and tibia in the same three colours
//! in every leg): eighteen lines in one chart cannot be told apart.

use std::path::Path;

use servobus_config::Motion;
use servobus_kinematics::{Geometry, FOOT_PREFIX};
use servobus_robot::{path::JointState, Trajectory};

use crate::record::{space, svg};

/// The height of one row of panels, px: one chart per quantity, or a grid
/// of leg panels.
const ROW: u32 = 430;

/// The height of a row of leg panels, px.
const LEG_ROW: u32 = 300;

/// The height of the line above the leg panels that says their colours,
/// px.
const KEY_ROW: u32 = 30;

/// Leg panels side by side.
const LEG_COLUMNS: usize = 3;

/// Samples drawn per joint over the whole motion.
const SAMPLES: usize = 1000;

/// Joints drawn in one panel: a leg's (named by the leg), or every joint.
struct Group {
    leg: Option<String>,
    /// Indices in the motion's joint order.
    joints: Vec<usize>,
}

/// Draws the plot of the planned `traj` (of `motion`, on a robot of
/// `geometry`) with `paths` in space, as SVG, and writes it to `path`
/// whole.
///
/// # Errors
/// Drawing failed, or the file could not be written.
pub(super) fn write(
    motion: &Motion,
    geometry: Option<&Geometry>,
    traj: &Trajectory,
    paths: &space::Paths,
    path: &Path,
) -> anyhow::Result<()> {
    let mut drawing = String::new();
    draw(motion, &groups(motion, geometry), traj, paths, &mut drawing)?;
    let text = svg::round_font_sizes(&drawing);
    servobus_robot::files::write_atomic(path, text.as_bytes())?;
    Ok(())
}

/// One group per leg (the joints of each `foot_<leg>` frame's chain, in
/// the motion's order), then the joints of no leg; without legs, one group
/// of every joint.
fn groups(motion: &Motion, geometry: Option<&Geometry>) -> Vec<Group> {
    let mut groups = Vec::new();
    let mut placed = vec![false; motion.joints.len()];
    if let Some(g) = geometry {
        for f in 0..g.frame_count() {
            let Some(leg) = g.frame_name(f).and_then(|n| n.strip_prefix(FOOT_PREFIX)) else {
                continue;
            };
            let joints: Vec<usize> = g
                .chain_to_frame(f)
                .into_iter()
                .filter_map(|i| g.joint_name(i))
                .filter_map(|name| motion.joints.iter().position(|j| j == name))
                .filter(|&j| !std::mem::replace(&mut placed[j], true))
                .collect();
            if !joints.is_empty() {
                groups.push(Group {
                    leg: Some(leg.to_owned()),
                    joints,
                });
            }
        }
    }
    // Legs in the motion's order (the robot file's), not the frames'.
    groups.sort_by_key(|g| g.joints.first().copied());
    let rest: Vec<usize> = (0..motion.joints.len()).filter(|&j| !placed[j]).collect();
    if !rest.is_empty() {
        groups.push(Group {
            leg: None,
            joints: rest,
        });
    }
    groups
}

/// The SVG of [`write`], drawn into `svg`: a row of position and one of
/// velocity (each a grid of leg panels for a legged robot), then, with
/// `paths` (a tool's or feet's positions), the views in space.
fn draw(
    motion: &Motion,
    groups: &[Group],
    traj: &Trajectory,
    paths: &space::Paths,
    svg: &mut String,
) -> anyhow::Result<()> {
    use plotters::prelude::*;

    let u = motion.units;
    let layout = Layout::new(motion, groups, traj.duration().max(1e-3));
    let (pos, vel) = sample(traj, motion.units, layout.duration);
    let block = layout.block();
    let space_row = if paths.is_empty() { 0 } else { ROW };
    let height = 40 + 2 * block + space_row;
    let root = SVGBackend::with_string(svg, (1200, height)).into_drawing_area();
    root.fill(&WHITE)?;
    let title = format!(
        "{} — planned path, {:.2} s",
        motion
            .path
            .file_name()
            .map_or_else(String::new, |f| f.to_string_lossy().into_owned()),
        traj.duration()
    );
    let root = root.titled(&title, ("sans-serif", 24))?;
    let (top, rest) = root.split_vertically(block);
    let (bottom, space_area) = rest.split_vertically(block);
    if !paths.is_empty() {
        space::draw(&space_area, paths)?;
    }
    layout.draw_quantity(&top, &pos, "Position", &u.to_string())?;
    layout.draw_quantity(&bottom, &vel, "Velocity", &format!("{u}/s"))?;
    root.present()?;
    Ok(())
}

/// How the panels of one quantity are laid out: the groups' panels in a
/// grid, under the leg panels' key if they share one.
struct Layout<'a> {
    /// The motion drawn (its joints' names).
    motion: &'a Motion,
    /// The joints of each panel.
    groups: &'a [Group],
    /// Panels are a leg's each (else one panel of every joint).
    legged: bool,
    /// Panels side by side.
    cols: usize,
    /// Rows of panels per quantity.
    grid: usize,
    /// The leg panels' colours, said once above them (`None`: each panel
    /// has a legend of its own).
    key: Option<Vec<String>>,
    /// The height of the line of the key, px (0 without one).
    key_row: u32,
    /// The end of the time axis, s.
    duration: f64,
}

impl<'a> Layout<'a> {
    /// The layout of `groups` of `motion`, over `duration` s.
    fn new(motion: &'a Motion, groups: &'a [Group], duration: f64) -> Self {
        let legged = groups.iter().any(|g| g.leg.is_some());
        let cols = if legged { LEG_COLUMNS } else { 1 };
        // The leg panels' colours are said once, above them.
        let key = if legged {
            leg_key(motion, groups)
        } else {
            None
        };
        Layout {
            motion,
            groups,
            legged,
            cols,
            grid: groups.len().div_ceil(cols).max(1),
            key_row: if key.is_some() { KEY_ROW } else { 0 },
            key,
            duration,
        }
    }

    /// The height of one quantity's panels and their key, px.
    fn block(&self) -> u32 {
        let panel = if self.legged { LEG_ROW } else { ROW };
        self.key_row + panel * self.grid as u32
    }

    /// Draws `what` (in `unit`) of every joint on `area`, from `series`:
    /// the key, then a panel per group, all on one scale.
    fn draw_quantity<DB>(
        &self,
        area: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
        series: &Series,
        what: &str,
        unit: &str,
    ) -> anyhow::Result<()>
    where
        DB: plotters::prelude::DrawingBackend,
        DB::ErrorType: 'static,
    {
        use plotters::prelude::*;

        // One scale for every panel of a quantity: the legs compare.
        let range = range(series);
        let y_desc = format!("{} ({unit})", what.to_lowercase());
        let (head, area) = area.split_vertically(self.key_row);
        if let Some(key) = &self.key {
            draw_key(&head, &format!("{what} of each leg's joints:"), key)?;
        }
        let legend = || {
            self.key
                .is_none()
                .then_some(SeriesLabelPosition::UpperRight)
        };
        let cells = area.split_evenly((self.grid, self.cols));
        for (group, cell) in self.groups.iter().zip(cells) {
            let caption = match &group.leg {
                Some(leg) => format!("{what}, leg {leg}"),
                None if self.legged => format!("{what}, other joints"),
                None => format!("{what} of every joint"),
            };
            let lines = group.joints.iter().enumerate().map(|(k, &j)| {
                let name = self.motion.joints.get(j).map_or("?", String::as_str);
                // In a leg's panel, a joint is named by its part of the
                // leg (`coxa`), coloured as that part in every leg.
                let label = match &group.leg {
                    Some(leg) => part(name, leg),
                    None => name,
                };
                let colour = match group.leg {
                    Some(_) => space::colour(k),
                    None => Palette99::pick(j).to_rgba(),
                };
                ((label.to_owned(), series[j].iter().copied()), colour)
            });
            space::line_chart(
                &cell,
                &caption,
                (0.0..self.duration, range.clone()),
                ("time (s)", &y_desc),
                lines,
                legend(),
            )?;
        }
        Ok(())
    }
}

/// A leg's joint named by its part of the leg: `coxa` for
/// `front_left_coxa` of leg `front_left` (the whole name otherwise).
fn part<'a>(joint: &'a str, leg: &str) -> &'a str {
    joint
        .strip_prefix(leg)
        .and_then(|r| r.strip_prefix('_'))
        .unwrap_or(joint)
}

/// The colours of the leg panels, said once for them all: each part's
/// name (`coxa`, `femur`, `tibia`) with its colour; `None` when the legs'
/// parts are not named alike (each panel then has a legend of its own).
fn leg_key(motion: &Motion, groups: &[Group]) -> Option<Vec<String>> {
    let parts = |g: &Group| -> Option<Vec<String>> {
        let leg = g.leg.as_deref()?;
        Some(
            g.joints
                .iter()
                .map(|&j| part(motion.joints.get(j).map_or("?", String::as_str), leg).to_owned())
                .collect(),
        )
    };
    let first = groups.iter().find_map(parts)?;
    groups
        .iter()
        .filter(|g| g.leg.is_some())
        .all(|g| parts(g).as_ref() == Some(&first))
        .then_some(first)
}

/// `title`, then a short line in each part's colour followed by its name,
/// along `area`.
fn draw_key<DB>(
    area: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    parts: &[String],
) -> anyhow::Result<()>
where
    DB: plotters::prelude::DrawingBackend,
    DB::ErrorType: 'static,
{
    use plotters::prelude::*;
    let font = ("sans-serif", 18);
    let (_, h) = area.dim_in_pixel();
    let y = h as i32 / 2;
    let mut x = 70;
    area.draw(&Text::new(
        title.to_owned(),
        (x, y - 9),
        font.into_font().color(&BLACK),
    ))?;
    x += 9 * title.len() as i32 + 20;
    for (k, name) in parts.iter().enumerate() {
        let colour = space::colour(k);
        area.draw(&PathElement::new(
            [(x, y), (x + 30, y)],
            colour.stroke_width(3),
        ))?;
        area.draw(&Text::new(name.clone(), (x + 36, y - 9), font))?;
        x += 36 + 9 * name.len() as i32 + 30;
    }
    Ok(())
}

/// One `(time s, value)` path per joint.
type Series = Vec<Vec<(f64, f64)>>;

/// Each joint's position and velocity (the motion's units) at
/// [`SAMPLES`] + 1 times from 0 to `duration`.
fn sample(traj: &Trajectory, u: servobus_config::Units, duration: f64) -> (Series, Series) {
    let n = traj.joints();
    let mut out = vec![JointState::default(); n];
    let mut pos: Series = vec![Vec::with_capacity(SAMPLES + 1); n];
    let mut vel: Series = vec![Vec::with_capacity(SAMPLES + 1); n];
    let mut cursor = traj.cursor();
    for k in 0..=SAMPLES {
        let t = duration * k as f64 / SAMPLES as f64;
        traj.sample_with(&mut cursor, t, &mut out);
        for (j, s) in out.iter().enumerate() {
            pos[j].push((t, u.from_rad(s.position)));
            vel[j].push((t, u.from_rad(s.velocity)));
        }
    }
    (pos, vel)
}

/// The y range of every series, padded by 5 % (at least a little).
fn range(series: &Series) -> std::ops::Range<f64> {
    let (lo, hi) = series
        .iter()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(_, y)| {
            (lo.min(y), hi.max(y))
        });
    if !lo.is_finite() {
        return -1.0..1.0;
    }
    let pad = ((hi - lo) * 0.05).max(1e-3);
    (lo - pad)..(hi + pad)
}
