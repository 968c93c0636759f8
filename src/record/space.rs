//! The plots' views of a motion in space (`plan --plot`'s planned paths,
//! `play --plot`'s measured ones): the tool's path, or every foot's, seen
//! from above (x, y) and from the side (x, z), in mm.

use plotters::coord::Shift;
use plotters::prelude::*;
use servobus_runtime::config::SpatialSummary;

/// Named paths of points (mm, x y z): the tool, or each foot.
pub(crate) type Paths = Vec<(String, Vec<[f64; 3]>)>;

/// The paths a summary has: the tool's, else the feet's.
pub(crate) fn paths(summary: Option<&SpatialSummary>) -> Paths {
    let Some(s) = summary else {
        return Vec::new();
    };
    if let Some(tool) = &s.tool {
        return vec![("tool".to_owned(), tool.path.clone())];
    }
    s.feet
        .as_ref()
        .map(|f| {
            f.paths
                .iter()
                .map(|(leg, p)| (format!("foot_{leg}"), p.clone()))
                .collect()
        })
        .unwrap_or_default()
}

/// Draws the top and side views of `paths` side by side in `area`.
pub(crate) fn draw<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    paths: &Paths,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let (w, _) = area.dim_in_pixel();
    let (left, right) = area.split_horizontally(w / 2);
    for (view, (a, b), names) in [
        (&left, (0usize, 1usize), ("from above", "x (mm)", "y (mm)")),
        (&right, (0, 2), ("from the side", "x (mm)", "z (mm)")),
    ] {
        let range = |k: usize| {
            let (lo, hi) = paths
                .iter()
                .flat_map(|(_, p)| p.iter().map(move |v| v[k]))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(v), hi.max(v))
                });
            let pad = ((hi - lo) * 0.05).max(1.0);
            (lo - pad)..(hi + pad)
        };
        let lines = paths
            .iter()
            .map(|(name, points)| (name.clone(), points.iter().map(|p| (p[a], p[b]))));
        line_chart(
            view,
            &format!("Path in space, {}", names.0),
            (range(a), range(b)),
            (names.1, names.2),
            lines,
        )?;
    }
    Ok(())
}

/// One chart in `area`: each `(label, points)` of `lines` a coloured line
/// with its legend entry, over `ranges` (x, y) with axis titles `desc`.
pub(crate) fn line_chart<DB, L, P>(
    area: &DrawingArea<DB, Shift>,
    caption: &str,
    ranges: (std::ops::Range<f64>, std::ops::Range<f64>),
    desc: (&str, &str),
    lines: L,
) -> anyhow::Result<()>
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    L: IntoIterator<Item = (String, P)>,
    P: IntoIterator<Item = (f64, f64)>,
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
    for (i, (label, points)) in lines.into_iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        chart
            .draw_series(LineSeries::new(points, color.stroke_width(2)))?
            .label(label)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}
