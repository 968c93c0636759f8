//! A legged robot seen from above in the world: its base is its body,
//! which walks, so the body's path and heading, and each foot's path
//! there, are found from the feet on the ground (which move under the
//! body by the inverse of its move, as `plan` counts the body's distance
//! and turn).

use plotters::coord::Shift;
use plotters::prelude::*;
use servobus_kinematics::{planar_motion, Vector2, FOOT_PREFIX};

use super::paths::Paths;

/// A foot this close to the ground stands on it, mm: a planned one stands
/// exactly on it, a measured one within the servos' resolution (one
/// STS3215 tick, 0.088 deg, moves a hexapod's foot 0.4 mm at most), and a
/// stepping foot rises tens of mm.
const ON_GROUND_MM: f64 = 1.0;

/// The most a body leans over its planted feet, deg (a hexapod's body
/// moves lean 10 deg).
const MAX_LEAN_DEG: f64 = 30.0;

/// The world view marks the body's heading each time it has gone this
/// far, mm, or turned [`MARK_TURN_DEG`], since the last mark.
const MARK_MM: f64 = 50.0;

/// See [`MARK_MM`].
const MARK_TURN_DEG: f64 = 30.0;

/// The length of a heading mark, mm.
const HEADING_MM: f64 = 60.0;

/// A legged motion seen in the world: where the body is and which way it
/// faces at each sample, and each foot's path there.
pub(super) struct World {
    /// The body's centre (x, y mm) and heading (rad) at each sample, in the
    /// frame the body started in.
    body: Vec<[f64; 3]>,
    /// Each foot's path (x, y mm) in that frame, after its colour's index
    /// in the other views.
    feet: Vec<(usize, Vec<(f64, f64)>)>,
}

impl World {
    /// The world view of the feet of `paths` (those named `foot_<leg>`, in
    /// the body frame); `None` without three feet.
    pub(super) fn of(paths: &Paths) -> Option<World> {
        let (colours, tracks): (Vec<usize>, Vec<&[[f64; 3]]>) = paths
            .iter()
            .enumerate()
            .filter(|(_, (name, _))| name.starts_with(FOOT_PREFIX))
            .map(|(i, (_, path))| (i, path.as_slice()))
            .unzip();
        if tracks.len() < 3 {
            return None;
        }
        let body = body_poses(&tracks);
        let feet = colours
            .into_iter()
            .zip(&tracks)
            .map(|(i, path)| {
                let world = path
                    .iter()
                    .zip(&body)
                    .map(|(p, b)| {
                        let (s, c) = b[2].sin_cos();
                        (b[0] + c * p[0] - s * p[1], b[1] + s * p[0] + c * p[1])
                    })
                    .collect();
                (i, world)
            })
            .collect();
        Some(World { body, feet })
    }

    /// Draws the view in `area`, x and y at one scale (a turn looks like
    /// one).
    pub(super) fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> anyhow::Result<()>
    where
        DB::ErrorType: 'static,
    {
        let points = || {
            self.body
                .iter()
                .map(|b| (b[0], b[1]))
                .chain(self.feet.iter().flat_map(|(_, p)| p.iter().copied()))
        };
        let (w, h) = area.dim_in_pixel();
        // The plotting area: the label areas and margins of `line_chart`
        // and the caption's line taken off.
        let px = (f64::from(w) - 80.0).max(1.0);
        let py = (f64::from(h) - 90.0).max(1.0);
        let (xs, ys) = equal_scale(points(), (px, py));
        let mut chart = ChartBuilder::on(area)
            .caption(
                "Path in space, from above, in the world",
                ("sans-serif", 18),
            )
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(xs, ys)?;
        chart
            .configure_mesh()
            .x_desc("x (mm, where the body started: forward)")
            .y_desc("y (mm, left)")
            .draw()?;
        for (colour, path) in &self.feet {
            let colour = Palette99::pick(*colour).to_rgba();
            chart.draw_series(LineSeries::new(
                path.iter().copied(),
                colour.stroke_width(1),
            ))?;
        }
        let centre = self.body.iter().map(|b| (b[0], b[1]));
        chart
            .draw_series(LineSeries::new(centre, BLACK.stroke_width(3)))?
            .label("body (arrows: its heading)")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLACK.stroke_width(3)));
        chart.draw_series(heading_marks(&self.body).into_iter().map(|b| {
            let (s, c) = b[2].sin_cos();
            let tip = (b[0] + c * HEADING_MM, b[1] + s * HEADING_MM);
            let back = HEADING_MM * 0.3;
            let wing = |side: f64| {
                (
                    tip.0 - c * back - s * back * side * 0.6,
                    tip.1 - s * back + c * back * side * 0.6,
                )
            };
            PathElement::new(
                vec![(b[0], b[1]), tip, wing(1.0), tip, wing(-1.0)],
                BLACK.stroke_width(2),
            )
        }))?;
        if let (Some(first), Some(last)) = (self.body.first(), self.body.last()) {
            let font = ("sans-serif", 14);
            let ends = if (first[0] - last[0]).hypot(first[1] - last[1]) < HEADING_MM {
                vec![("start, end", first)]
            } else {
                vec![("start", first), ("end", last)]
            };
            chart.draw_series(
                ends.into_iter()
                    .map(|(text, b)| Text::new(text, (b[0], b[1]), font)),
            )?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
        Ok(())
    }
}

/// The body's centre (x, y mm) and heading (rad) at each sample of `feet`
/// (each foot's path in the body frame), in the frame it started in: each
/// step the feet on the ground at both samples give the body's move
/// ([`planar_motion`]); with fewer than three on the ground it stays.
fn body_poses(feet: &[&[[f64; 3]]]) -> Vec<[f64; 3]> {
    let samples = feet.iter().map(|p| p.len()).min().unwrap_or(0);
    let mut out = Vec::with_capacity(samples);
    let (mut x, mut y, mut heading) = (0.0f64, 0.0f64, 0.0f64);
    let mut before: Vec<Option<Vector2<f64>>> = vec![None; feet.len()];
    for k in 0..samples {
        let at: Vec<[f64; 3]> = feet.iter().map(|p| p[k]).collect();
        let now: Vec<Option<Vector2<f64>>> = on_ground(&at)
            .into_iter()
            .zip(&at)
            .map(|(down, p)| down.then(|| Vector2::new(p[0], p[1])))
            .collect();
        let (a, b): (Vec<_>, Vec<_>) = now
            .iter()
            .zip(&before)
            .filter_map(|(n, b)| n.zip(*b))
            .unzip();
        if a.len() >= 3 {
            // The body's move in its frame before: turned into the world.
            let (angle, shift) = planar_motion(&a, &b);
            let (s, c) = heading.sin_cos();
            x += c * shift.x - s * shift.y;
            y += s * shift.x + c * shift.y;
            heading += angle;
        }
        before = now;
        out.push([x, y, heading]);
    }
    out
}

/// Which of `feet` (body frame, mm) stand on the ground: those on the
/// plane through three of them that has no foot under it and the most on
/// it (the most level of such planes). The ground is that plane, not a
/// height: a body that leans or rises over its planted feet moves the
/// ground in its own frame, and stepping feet are above it.
fn on_ground(feet: &[[f64; 3]]) -> Vec<bool> {
    let sub = |a: &[f64; 3], b: &[f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: &[f64; 3], b: &[f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let n = feet.len();
    // The most feet on it, then the most level: a plane through two
    // planted feet and one just lifting can hold as many.
    let mut best: (usize, f64, Vec<bool>) = (0, 0.0, vec![false; n]);
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                let (u, v) = (sub(&feet[j], &feet[i]), sub(&feet[k], &feet[i]));
                let mut normal = [
                    u[1] * v[2] - u[2] * v[1],
                    u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0],
                ];
                let len = dot(&normal, &normal).sqrt();
                // Three feet in a line (or at one point) make no plane.
                if len < 1e-6 {
                    continue;
                }
                // Up: the ground is under the body, whichever way it leans.
                let up = if normal[2] < 0.0 { -1.0 } else { 1.0 };
                normal = normal.map(|c| c * up / len);
                // A plane as steep as three feet of one side nearly in a
                // line can make is no ground a body leans over.
                if normal[2] < MAX_LEAN_DEG.to_radians().cos() {
                    continue;
                }
                let height: Vec<f64> = feet
                    .iter()
                    .map(|p| dot(&sub(p, &feet[i]), &normal))
                    .collect();
                if height.iter().any(|&h| h < -ON_GROUND_MM) {
                    continue;
                }
                let down: Vec<bool> = height.iter().map(|h| h.abs() < ON_GROUND_MM).collect();
                let count = down.iter().filter(|&&d| d).count();
                if count > best.0 || (count == best.0 && normal[2] > best.1) {
                    best = (count, normal[2], down);
                }
            }
        }
    }
    best.2
}

/// The body poses to mark: the first, then each after [`MARK_MM`] of
/// travel or [`MARK_TURN_DEG`] of turn since the last mark, and the last.
fn heading_marks(body: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut marks: Vec<[f64; 3]> = Vec::new();
    for b in body {
        let due = marks.last().is_none_or(|m| {
            (b[0] - m[0]).hypot(b[1] - m[1]) >= MARK_MM
                || (b[2] - m[2]).abs() >= MARK_TURN_DEG.to_radians()
        });
        if due {
            marks.push(*b);
        }
    }
    if let (Some(last), Some(mark)) = (body.last(), marks.last()) {
        if last != mark {
            marks.push(*last);
        }
    }
    marks
}

/// Ranges (x, y) holding `points` with one scale for both on a plotting
/// area of `pixels` (width, height): the axis with less to show is widened.
fn equal_scale(
    points: impl Iterator<Item = (f64, f64)>,
    (px, py): (f64, f64),
) -> (std::ops::Range<f64>, std::ops::Range<f64>) {
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for (x, y) in points {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if !x0.is_finite() || !y0.is_finite() {
        return (-1.0..1.0, -1.0..1.0);
    }
    let pad = |lo: f64, hi: f64| ((hi - lo) * 0.05).max(HEADING_MM);
    let (px_pad, py_pad) = (pad(x0, x1), pad(y0, y1));
    let (mut x0, mut x1, mut y0, mut y1) = (x0 - px_pad, x1 + px_pad, y0 - py_pad, y1 + py_pad);
    // mm per pixel, the larger of the two for both.
    let scale = ((x1 - x0) / px).max((y1 - y0) / py);
    let widen = |lo: &mut f64, hi: &mut f64, span: f64| {
        let more = (span - (*hi - *lo)) / 2.0;
        *lo -= more;
        *hi += more;
    };
    widen(&mut x0, &mut x1, scale * px);
    widen(&mut y0, &mut y1, scale * py);
    (x0..x1, y0..y1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_body_walking_forward_then_turning_is_found_from_its_planted_feet() {
        // Three feet planted in the world at (100, 0), (0, 100), (-100, 0)
        // while the body goes 10 mm forward, then turns 90 deg on the spot:
        // seen from the body, the feet move back, then turn the other way.
        let world = [[100.0, 0.0], [0.0, 100.0], [-100.0, 0.0]];
        let seen = |x: f64, heading: f64| -> Vec<[f64; 3]> {
            let (s, c) = heading.sin_cos();
            world
                .iter()
                .map(|w| {
                    let (dx, dy) = (w[0] - x, w[1]);
                    [c * dx + s * dy, -s * dx + c * dy, -40.0]
                })
                .collect()
        };
        let poses = [
            (0.0, 0.0),
            (5.0, 0.0),
            (10.0, 0.0),
            (10.0, 0.5),
            (10.0, 1.0),
        ];
        let samples: Vec<Vec<[f64; 3]>> = poses.iter().map(|&(x, h)| seen(x, h)).collect();
        let tracks: Vec<Vec<[f64; 3]>> = (0..3)
            .map(|f| samples.iter().map(|s| s[f]).collect())
            .collect();
        let refs: Vec<&[[f64; 3]]> = tracks.iter().map(Vec::as_slice).collect();
        let body = body_poses(&refs);
        for (b, &(x, h)) in body.iter().zip(&poses) {
            assert!((b[0] - x).abs() < 1e-9, "{b:?} vs {x}");
            assert!(b[1].abs() < 1e-9, "{b:?}");
            assert!((b[2] - h).abs() < 1e-9, "{b:?} vs {h}");
        }
    }

    #[test]
    fn the_ground_is_the_plane_of_the_planted_feet_however_the_body_leans() {
        // Six feet, the body leaning 10 deg to the right over them (the
        // ground rises to the left in its frame), two feet stepping 20 mm
        // above the ground.
        let lean = 10f64.to_radians().tan();
        let foot = |x: f64, y: f64, lift: f64| [x, y, -40.0 + y * lean + lift];
        let feet = [
            foot(150.0, 300.0, 0.0),
            foot(0.0, 330.0, 20.0),
            foot(-150.0, 300.0, 0.0),
            foot(150.0, -300.0, 0.0),
            foot(0.0, -330.0, 0.0),
            foot(-150.0, -300.0, 20.0),
        ];
        assert_eq!(on_ground(&feet), vec![true, false, true, true, true, false]);
    }
}
