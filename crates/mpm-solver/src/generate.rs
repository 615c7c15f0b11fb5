//! Particle generation: regular lattices of material points filling simple shapes.
//!
//! A shape is filled with `n × n` points per cell of size `cell` (spacing s = cell / n), each point at
//! the centre of its sub-square and standing for the area s². Points are returned in a deterministic
//! order (row by row), so the same scene always gives the same particle numbering.

use crate::math::{Real, Vector};

/// One generated point: where it is and the area (m² per metre) it stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seed {
    /// Position (m).
    pub position: Vector,
    /// Area it represents (m² per metre of thickness).
    pub area: Real,
}

/// A shape to fill with particles.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// Axis-aligned rectangle between `min` and `max`.
    Rectangle {
        /// lower-left corner
        min: Vector,
        /// upper-right corner
        max: Vector,
    },
    /// Simple polygon (counter-clockwise or clockwise, not self-intersecting).
    Polygon {
        /// vertices in order
        vertices: Vec<Vector>,
    },
    /// A rectangle resting on an inclined plane: its base starts at `base_start` on the ground and runs
    /// `length` along the direction at angle `angle_rad` (from +x, counter-clockwise); it is
    /// `thickness` thick, measured normal to the ground.
    OnSlope {
        /// lower corner of the base, on the ground
        base_start: Vector,
        /// inclination of the base (rad); negative for ground descending to the right
        angle_rad: Real,
        /// length along the ground (m)
        length: Real,
        /// thickness normal to the ground (m)
        thickness: Real,
    },
    /// The region between two polylines with x increasing: above `bottom` (e.g. a rupture
    /// surface) and below `top` (e.g. the pre-failure ground), where both are defined and
    /// top > bottom; a release mass.
    BetweenProfiles {
        /// upper polyline, x increasing
        top: Vec<Vector>,
        /// lower polyline, x increasing
        bottom: Vec<Vector>,
    },
}

/// The height of the polyline `line` (x increasing) at `x`, linear between its points; `None`
/// outside its x range.
pub fn polyline_height(line: &[Vector], x: Real) -> Option<Real> {
    let (first, last) = (line.first()?, line.last()?);
    if !(x >= first.x && x <= last.x) {
        return None;
    }
    if line.len() == 1 {
        return Some(first.y);
    }
    let k = line.partition_point(|p| p.x <= x).clamp(1, line.len() - 1);
    let (a, b) = (line[k - 1], line[k]);
    if b.x == a.x {
        return Some(a.y.max(b.y));
    }
    Some(a.y + (x - a.x) / (b.x - a.x) * (b.y - a.y))
}

/// Whether `p` lies strictly between `bottom` and `top` (both x increasing) at its x.
pub fn between_profiles(top: &[Vector], bottom: &[Vector], p: Vector) -> bool {
    match (polyline_height(top, p.x), polyline_height(bottom, p.x)) {
        (Some(t), Some(b)) => p.y > b && p.y < t,
        _ => false,
    }
}

/// Fills `shape` with points at spacing `spacing` (m); `spacing` must be positive and finite.
///
/// Rectangles and slope blocks are filled exactly (their area is the sum of the points' areas up to
/// a partial last row when the size is not a multiple of the spacing, in which case the lattice keeps
/// whole sub-squares whose centre lies inside). Polygons keep the lattice points strictly inside.
pub fn fill(shape: &Shape, spacing: Real) -> Vec<Seed> {
    let area = spacing * spacing;
    let mut out = Vec::new();
    match shape {
        Shape::Rectangle { min, max } => {
            lattice(*min, Vector::X, Vector::Y, max.x - min.x, max.y - min.y, spacing, &mut out);
        }
        Shape::OnSlope { base_start, angle_rad, length, thickness } => {
            let t = Vector::new(angle_rad.cos(), angle_rad.sin());
            let n = t.perp();
            lattice(*base_start, t, n, *length, *thickness, spacing, &mut out);
        }
        Shape::Polygon { vertices } => {
            if vertices.len() >= 3 {
                let (lo, hi) = vertices.iter().fold(
                    (Vector::splat(f64::INFINITY), Vector::splat(f64::NEG_INFINITY)),
                    |(lo, hi), v| (lo.min(*v), hi.max(*v)),
                );
                let mut tmp = Vec::new();
                lattice(lo, Vector::X, Vector::Y, hi.x - lo.x, hi.y - lo.y, spacing, &mut tmp);
                out.extend(tmp.into_iter().filter(|s| inside_polygon(vertices, s.position)));
            }
        }
        Shape::BetweenProfiles { top, bottom } => {
            // columns of points stacked from the bottom surface up, (j + ½) spacing above it
            // while below the top: the lowest points sit half a spacing above the (curved)
            // bottom, as a lattice aligned with it would put them, never on it.
            let (Some(t0), Some(b0), Some(t1), Some(b1)) =
                (top.first(), bottom.first(), top.last(), bottom.last())
            else {
                return out;
            };
            let (x0, x1) = (t0.x.max(b0.x), t1.x.min(b1.x));
            let columns = ((x1 - x0) / spacing + 1e-9).floor();
            if !(columns.is_finite() && columns >= 1.0) {
                return out;
            }
            for i in 0..columns as usize {
                let x = x0 + (i as Real + 0.5) * spacing;
                let (Some(t), Some(b)) = (polyline_height(top, x), polyline_height(bottom, x))
                else {
                    continue;
                };
                let rows = ((t - b) / spacing + 0.5 + 1e-9).floor().max(0.0) as usize;
                for j in 0..rows {
                    let y = b + (j as Real + 0.5) * spacing;
                    out.push(Seed { position: Vector::new(x, y), area });
                }
            }
        }
    }
    for s in &mut out {
        s.area = area;
    }
    out
}

/// lattice of sub-square centres in the frame (origin, e1, e2), `a` long along e1 and `b` along e2.
fn lattice(
    origin: Vector,
    e1: Vector,
    e2: Vector,
    a: Real,
    b: Real,
    spacing: Real,
    out: &mut Vec<Seed>,
) {
    if !(spacing > 0.0 && spacing.is_finite() && a.is_finite() && b.is_finite()) {
        return;
    }
    // Relative slack so that a size that is an exact multiple of the spacing, up to rounding,
    // gives exactly that many points: 1e-9, and the rounding of the sizes where the coordinates
    // are large (a box 0.4 m wide at x = 5e6 m measures 7.9999999925 spacings of 0.05 m).
    const SLACK: Real = 1e-9;
    let rounding = 4.0 * Real::EPSILON * (origin.abs().max_element() + a + b) / spacing;
    let na = ((a / spacing) + (SLACK + rounding)).floor().max(0.0) as usize;
    let nb = ((b / spacing) + (SLACK + rounding)).floor().max(0.0) as usize;
    for j in 0..nb {
        for i in 0..na {
            let s = (i as Real + 0.5) * spacing;
            let t = (j as Real + 0.5) * spacing;
            out.push(Seed { position: origin + s * e1 + t * e2, area: spacing * spacing });
        }
    }
}

pub use crate::polygon::{inside_polygon, inside_row, row_crossings};

#[cfg(all(test, not(feature = "dim3")))]
mod tests {
    use super::*;

    /// Areas are sums of a few products of exact binary fractions.
    const AREA_TOL: Real = 1e-12;

    #[test]
    fn the_mass_between_two_profiles_fills_only_where_the_top_is_above() {
        // top: y = 1 on x ∈ [0, 4]; bottom: y = x − 1 (above the top for x > 2)
        let top = vec![Vector::new(0.0, 1.0), Vector::new(4.0, 1.0)];
        let bottom = vec![Vector::new(0.0, -1.0), Vector::new(4.0, 3.0)];
        let seeds = fill(&Shape::BetweenProfiles { top, bottom }, 0.01);
        // the triangle between y = x − 1 and y = 1 for x ∈ [0, 2]: area 2. Each column of
        // points rounds its height to whole spacings: at most half a spacing per column, of
        // either sign, over 200 columns (measured well inside that).
        let area: f64 = seeds.iter().map(|s| s.area).sum();
        assert!((area - 2.0).abs() < 200.0 * 0.5 * 0.01 * 0.01, "{area}");
        // every point half a spacing or more above the bottom, its centre not above the top
        for s in &seeds {
            let p = s.position;
            assert!(p.x < 2.0 && p.y >= p.x - 1.0 + 0.005 - 1e-12 && p.y <= 1.0 + 1e-12, "{p}");
        }
    }

    #[test]
    fn rectangle_fills_n_by_n_per_cell() {
        let pts = fill(&Shape::Rectangle { min: Vector::ZERO, max: Vector::new(1.0, 0.5) }, 0.25);
        assert_eq!(pts.len(), 4 * 2);
        let area: Real = pts.iter().map(|s| s.area).sum();
        assert!((area - 0.5).abs() < AREA_TOL);
        assert_eq!(pts[0].position, Vector::new(0.125, 0.125));
    }

    #[test]
    fn slope_block_points_lie_above_the_ground_line() {
        let angle = -30f64.to_radians();
        let pts = fill(
            &Shape::OnSlope {
                base_start: Vector::ZERO,
                angle_rad: angle,
                length: 1.0,
                thickness: 0.5,
            },
            0.1,
        );
        assert_eq!(pts.len(), 50);
        let n = Vector::new(angle.cos(), angle.sin()).perp();
        for s in &pts {
            let height = s.position.dot(n);
            assert!(height > 0.0 && height < 0.5);
        }
    }

    #[test]
    fn polygon_keeps_only_inside_points() {
        // A right triangle with legs 1: half the unit square's lattice, diagonal excluded.
        let tri = vec![Vector::ZERO, Vector::new(1.0, 0.0), Vector::new(0.0, 1.0)];
        // Spacing 1/8 keeps every coordinate exact: centres (i + ½)/8 with i + j ≤ 6 lie strictly
        // inside (28 of them); the 8 with i + j = 7 lie on the hypotenuse and are excluded.
        let pts = fill(&Shape::Polygon { vertices: tri }, 0.125);
        assert_eq!(pts.len(), 28);
        assert!(pts.iter().all(|s| s.position.x + s.position.y < 1.0));
    }
}
