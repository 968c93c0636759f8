//! The ground under a walking robot: the stability margin of the feet on
//! the ground, and the planar motion that carries one set of feet onto
//! another.

use nalgebra::{Isometry3, Vector2};

use crate::gait::LOW_MARGIN_MM;

/// The lowest margin, and the dips under [`LOW_MARGIN_MM`].
pub(crate) struct Margins {
    /// The lowest margin seen, mm.
    pub(crate) min: f64,
    /// The dips under [`LOW_MARGIN_MM`]: (time s, lowest margin mm).
    pub(crate) low: Vec<(f64, f64)>,
    in_dip: bool,
}

impl Default for Margins {
    fn default() -> Self {
        Margins {
            min: f64::INFINITY,
            low: Vec::new(),
            in_dip: false,
        }
    }
}

impl Margins {
    /// Takes the margin `m` (mm) at time `t` (s).
    pub(crate) fn add(&mut self, t: f64, m: f64) {
        self.min = self.min.min(m);
        if m < LOW_MARGIN_MM {
            match (self.in_dip, self.low.last_mut()) {
                (true, Some(last)) => last.1 = last.1.min(m),
                _ => self.low.push((t, m)),
            }
            self.in_dip = true;
        } else {
            self.in_dip = false;
        }
    }
}

/// The stability margin: the signed distance (mm) from the body's centre
/// (`body`'s origin) to the nearest edge of the convex hull of the feet on
/// the ground `feet` (x, y, in the same frame as `body`): positive inside;
/// minus infinity with fewer than three feet down.
pub fn support_margin(feet: &[Vector2<f64>], body: &Isometry3<f64>) -> f64 {
    if feet.len() < 3 {
        return f64::NEG_INFINITY;
    }
    let c = Vector2::new(body.translation.x, body.translation.y);
    let hull = convex_hull(feet);
    if hull.len() < 3 {
        return f64::NEG_INFINITY;
    }
    let mut margin = f64::INFINITY;
    for k in 0..hull.len() {
        let a = hull[k];
        let b = hull[(k + 1) % hull.len()];
        let e = b - a;
        let len = e.norm();
        if len <= 0.0 {
            continue;
        }
        // Counter-clockwise hull: the inside is to the left of each edge.
        let d = (e.x * (c.y - a.y) - e.y * (c.x - a.x)) / len;
        margin = margin.min(d);
    }
    margin
}

/// The body's planar move (as [`planar_motion`]: a turn, rad, then a
/// shift, mm, in its frame before) between two samples of its feet in its
/// frame (`now` and `before`, one entry per foot: its x, y when it is on
/// the ground, `None` in the air), from the feet on the ground at both;
/// `None` when fewer than three are.
pub fn move_on_feet(
    now: &[Option<Vector2<f64>>],
    before: &[Option<Vector2<f64>>],
) -> Option<(f64, Vector2<f64>)> {
    let (a, b): (Vec<_>, Vec<_>) = now
        .iter()
        .zip(before)
        .filter_map(|(n, b)| n.zip(*b))
        .unzip();
    (a.len() >= 3).then(|| planar_motion(&a, &b))
}

/// The planar move (a turn about z, rad, then a shift, mm) that takes the
/// points `a` onto the points `b` (x, y; the same points seen twice) in
/// the least-squares sense. Seen from a body, feet planted on the ground
/// move by the inverse of the body's move: with `a` the feet now and `b`
/// the feet before, it is the body's move, in its frame before.
pub fn planar_motion(a: &[Vector2<f64>], b: &[Vector2<f64>]) -> (f64, Vector2<f64>) {
    let n = a.len().min(b.len()).max(1) as f64;
    let ca = a.iter().sum::<Vector2<f64>>() / n;
    let cb = b.iter().sum::<Vector2<f64>>() / n;
    let (mut dot, mut cross) = (0.0f64, 0.0f64);
    for (p, q) in a.iter().zip(b) {
        let (p, q) = (p - ca, q - cb);
        dot += p.dot(&q);
        cross += p.x * q.y - p.y * q.x;
    }
    let angle = cross.atan2(dot);
    let (s, c) = angle.sin_cos();
    let turned = Vector2::new(c * ca.x - s * ca.y, s * ca.x + c * ca.y);
    (angle, cb - turned)
}

/// The convex hull of `points`, counter-clockwise (Andrew's monotone
/// chain).
fn convex_hull(points: &[Vector2<f64>]) -> Vec<Vector2<f64>> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let cross = |o: Vector2<f64>, a: Vector2<f64>, b: Vector2<f64>| {
        (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x)
    };
    let mut hull: Vec<Vector2<f64>> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        for &q in &p {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
        if pass == 0 {
            p.reverse();
        }
    }
    hull
}
