//! The paths the space views draw: the tool's, or each foot's, as a
//! motion's spatial summary gives them.

use servobus_config::SpatialSummary;
use servobus_kinematics::FOOT_PREFIX;

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
                .map(|(leg, p)| (format!("{FOOT_PREFIX}{leg}"), p.clone()))
                .collect()
        })
        .unwrap_or_default()
}
