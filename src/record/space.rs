//! The plots' views of a motion in space (`plan --plot`'s planned paths,
//! `play --plot`'s measured ones): the tool's path, or every foot's, seen
//! from above (x, y) and from the side (x, z), in mm, in the robot's base
//! frame. A legged robot's base is its body, which walks: a first view
//! shows it from above in the world, the body's path and heading and each
//! foot's path there, found from the feet on the ground (which move under
//! the body by the inverse of its move, as `plan` counts the body's
//! distance and turn).

use plotters::coord::Shift;
use plotters::prelude::*;

mod paths;
mod world;

pub(crate) use paths::{paths, Paths};
use world::World;

/// One colour per joint, distinct from its neighbours (a qualitative
/// palette of 20: ten hues, each dark then light).
pub(crate) const PALETTE: [(u8, u8, u8); 20] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
    (174, 199, 232),
    (255, 187, 120),
    (152, 223, 138),
    (255, 152, 150),
    (197, 176, 213),
    (196, 156, 148),
    (247, 182, 210),
    (199, 199, 199),
    (219, 219, 141),
    (158, 218, 229),
];

/// Colour `i` of [`PALETTE`] (it repeats past 20).
pub(crate) fn colour(i: usize) -> RGBAColor {
    let (r, g, b) = PALETTE[i % PALETTE.len()];
    RGBColor(r, g, b).to_rgba()
}

/// Draws the views of `paths` side by side in `area`: from above and from
/// the side; for feet, first from above in the world.
pub(crate) fn draw<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    paths: &Paths,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let (w, _) = area.dim_in_pixel();
    let world = World::of(paths);
    let (world_area, body_views) = match &world {
        Some(_) => area.split_horizontally(w / 3),
        None => area.split_horizontally(0),
    };
    if let Some(world) = &world {
        world.draw(&world_area)?;
    }
    let (w, _) = body_views.dim_in_pixel();
    let (left, right) = body_views.split_horizontally(w / 2);
    // A legged robot's feet stand round the body, far from its middle,
    // where the key of the view from above goes.
    let (above, side, key) = match &world {
        Some(_) => (
            "Path in space, from above, body frame",
            "Path in space, from the side, body frame",
            SeriesLabelPosition::MiddleMiddle,
        ),
        None => (
            "Path in space, from above",
            "Path in space, from the side",
            SeriesLabelPosition::UpperRight,
        ),
    };
    for (view, (a, b), names, key) in [
        (&left, (0usize, 1usize), (above, "x (mm)", "y (mm)"), key),
        (
            &right,
            (0, 2),
            (side, "x (mm)", "z (mm)"),
            SeriesLabelPosition::UpperRight,
        ),
    ] {
        let colours = (0..).map(|i| Palette99::pick(i).to_rgba());
        let lines = paths
            .iter()
            .map(|(name, points)| (name.clone(), points.iter().map(|p| (p[a], p[b]))))
            .zip(colours);
        let mut up = range(paths, b);
        if b == 2 && world.is_some() {
            // Room above the steps for the key of six feet.
            up.end += (up.end - up.start) * 0.6;
        }
        line_chart(
            view,
            names.0,
            (range(paths, a), up),
            (names.1, names.2),
            lines,
            Some(key),
        )?;
    }
    Ok(())
}

/// The span of coordinate `k` over every point of `paths`, padded by 5 %
/// (at least 1 mm).
fn range(paths: &Paths, k: usize) -> std::ops::Range<f64> {
    let (lo, hi) = paths
        .iter()
        .flat_map(|(_, p)| p.iter().map(move |v| v[k]))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return -1.0..1.0;
    }
    let pad = ((hi - lo) * 0.05).max(1.0);
    (lo - pad)..(hi + pad)
}

/// One chart in `area`: each `((label, points), colour)` of `lines` a
/// line with its legend entry where `legend` says (none: the key is
/// elsewhere), over `ranges` (x, y) with axis titles `desc`.
pub(crate) fn line_chart<DB, L, P, C>(
    area: &DrawingArea<DB, Shift>,
    caption: &str,
    ranges: (std::ops::Range<f64>, std::ops::Range<f64>),
    desc: (&str, &str),
    lines: L,
    legend: Option<SeriesLabelPosition>,
) -> anyhow::Result<()>
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    L: IntoIterator<Item = ((String, P), C)>,
    P: IntoIterator<Item = (f64, f64)>,
    C: Color,
{
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(ranges.0, ranges.1)?;
    chart
        .configure_mesh()
        .x_desc(desc.0)
        .y_desc(desc.1)
        .draw()?;
    for ((label, points), color) in lines {
        let color = color.to_rgba();
        chart
            .draw_series(LineSeries::new(points, color.stroke_width(2)))?
            .label(label)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    if let Some(position) = legend {
        chart
            .configure_series_labels()
            .position(position)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
    }
    Ok(())
}
