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
