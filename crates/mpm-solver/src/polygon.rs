//! The point-in-polygon test both dimensions fill shapes with: 2D polygons, and the cross-section
//! of a 3D prism.

use glam::DVec2;

/// even-odd rule point-in-polygon test: true when `p` is strictly inside the polygon with these
/// vertices (points on an edge may fall either way).
pub fn inside_polygon(vertices: &[DVec2], p: DVec2) -> bool {
    let mut inside = false;
    let n = vertices.len();
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (vertices[i], vertices[j]);
        if (a.y > p.y) != (b.y > p.y) {
            let x_cross = a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if p.x < x_cross {
                inside = !inside;
            }
        }
        j = i;
    }
    inside
}

/// The crossings of the horizontal line through `y` with the polygon's edges, sorted, into `out`
/// (cleared first): with them, [`inside_row`] answers [`inside_polygon`] for every point of the
/// line, bit for bit (the same crossing formula, the same comparison), at O(log n) per point
/// instead of O(n). For lattices: a row of m points costs O(n log n + m log n), not O(n m).
pub fn row_crossings(vertices: &[DVec2], y: f64, out: &mut Vec<f64>) {
    out.clear();
    let n = vertices.len();
    let mut j = n.wrapping_sub(1);
    for i in 0..n {
        let (a, b) = (vertices[i], vertices[j]);
        if (a.y > y) != (b.y > y) {
            let x = a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y);
            // a NaN crossing (inf/inf, from vertices near the largest doubles) never toggles
            // the point test; left in, it would break the sorted order
            if !x.is_nan() {
                out.push(x);
            }
        }
        j = i;
    }
    out.sort_by(f64::total_cmp);
}

/// whether the point (x, y) is inside, given the sorted [`row_crossings`] of its row `y`: an odd
/// number of crossings lies beyond x (the even-odd rule of [`inside_polygon`]).
pub fn inside_row(crossings: &[f64], x: f64) -> bool {
    (crossings.len() - crossings.partition_point(|&c| c <= x)) % 2 == 1
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A star with collinear and horizontal edges, and points on vertices, on edges and on the
    /// rows of horizontal edges: the row test and the point test agree everywhere (the boundary
    /// cases included, where either answer is allowed but both must be the same).
    #[test]
    fn the_row_test_answers_the_point_test_everywhere() {
        let v: Vec<DVec2> = [
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [3.0, 1.0],
            [1.5, 3.0],
            [1.0, 1.0],
            [0.5, 2.0],
            [0.0, 1.0],
        ]
        .iter()
        .map(|&p| DVec2::from(p))
        .collect();
        let mut xs = Vec::new();
        let (mut inside, mut outside) = (0, 0);
        for k in -4..=64 {
            let y = k as f64 * 0.05;
            row_crossings(&v, y, &mut xs);
            for i in -4..=64 {
                let x = i as f64 * 0.05;
                let want = inside_polygon(&v, DVec2::new(x, y));
                assert_eq!(inside_row(&xs, x), want, "({x}, {y})");
                if want { inside += 1 } else { outside += 1 }
            }
        }
        // both answers occur: the test cannot pass on a constant
        assert!(inside > 100 && outside > 100, "{inside} inside, {outside} outside");
    }
}
