//! The ground as a polyline of points with increasing x: what the runout measures, the
//! envelopes and validation ask of it. Its own module so that the run analysis (summary,
//! envelopes, observed deposit) depends on the ground, not on the scene.

use mpm_solver::Vector;

/// the ground segment under x (the last one for x beyond the profile).
pub fn segment_at(ground: &[Vector], x: f64) -> (Vector, Vector) {
    for w in ground.windows(2) {
        if x < w[1].x {
            return (w[0], w[1]);
        }
    }
    let n = ground.len();
    if n >= 2 { (ground[n - 2], ground[n - 1]) } else { (Vector::ZERO, Vector::X) }
}

/// ground height at x along the polyline (end segments extended).
pub fn ground_height(ground: &[Vector], x: f64) -> f64 {
    let (a, b) = segment_at(ground, x);
    if b.x == a.x { a.y } else { a.y + (b.y - a.y) * (x - a.x) / (b.x - a.x) }
}

/// The free surface: per column of width `column` holding particles, (column centre x, surface
/// height, ground height), the surface being the highest particle above the ground there plus
/// half a spacing.
pub fn surface(
    positions: &[Vector],
    ground: &[Vector],
    spacing: f64,
    column: f64,
) -> Vec<(f64, f64, f64)> {
    let x0 = ground.first().map_or(0.0, |g| g.x);
    let mut tops: std::collections::BTreeMap<i64, f64> = std::collections::BTreeMap::new();
    for p in positions {
        if !p.is_finite() {
            continue;
        }
        let k = ((p.x - x0) / column).floor() as i64;
        let h = p.y - ground_height(ground, p.x) + 0.5 * spacing;
        let e = tops.entry(k).or_insert(f64::NEG_INFINITY);
        *e = e.max(h);
    }
    tops.into_iter()
        .map(|(k, h)| {
            let x = x0 + (k as f64 + 0.5) * column;
            let g = ground_height(ground, x);
            (x, g + h.max(0.0), g)
        })
        .collect()
}
