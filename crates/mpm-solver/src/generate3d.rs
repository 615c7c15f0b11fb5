//! Particle generation in 3D: regular lattices of material points filling boxes, cylinders and
//! prisms (the 3D build's `generate`).
//!
//! A shape is filled with points at spacing s (n × n × n per cell of size s·n), each point at the
//! centre of its sub-cube and standing for the volume s³. The lattice starts at the shape's
//! lowest corner (a box's `min`, the bounding box of a cylinder or prism), and points are
//! returned in a deterministic order (x fastest, then y, then z), so the same scene always gives
//! the same particle numbering. A cylinder or a prism keeps the lattice points strictly inside.

use glam::DVec2;

use crate::math::{Real, Vector};
pub use crate::polygon::{inside_polygon, inside_row, row_crossings};

/// One generated point: where it is and the volume (m³) it stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seed {
    /// Position (m).
    pub position: Vector,
    /// Volume it represents (m³).
    pub volume: Real,
}

/// A coordinate axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    /// x.
    X,
    /// y (up).
    Y,
    /// z.
    Z,
}

impl Axis {
    /// its index: 0, 1, 2.
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }

    /// the indices of the other two axes, in increasing order: the coordinates a prism's polygon
    /// is given in ((y, z) for x, (x, z) for y, (x, y) for z).
    pub fn others(self) -> [usize; 2] {
        match self {
            Axis::X => [1, 2],
            Axis::Y => [0, 2],
            Axis::Z => [0, 1],
        }
    }
}

/// A shape to fill with particles.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// Axis-aligned box between `min` and `max`.
    Box {
        /// lowest corner
        min: Vector,
        /// highest corner
        max: Vector,
    },
    /// A circular cylinder: its axis runs from `base` (the centre of one end) along the unit
    /// direction `axis` for `height`.
    Cylinder {
        /// centre of the base disc (m)
        base: Vector,
        /// direction of the axis (normalised here; must not be zero)
        axis: Vector,
        /// radius (m)
        radius: Real,
        /// length along the axis (m)
        height: Real,
    },
    /// A simple polygon extruded along a coordinate axis from `from` to `to`; the polygon's
    /// vertices are in the other two coordinates, in increasing axis order ([`Axis::others`]).
    Prism {
        /// the polygon's vertices, in order
        vertices: Vec<DVec2>,
        /// the axis of extrusion
        axis: Axis,
        /// where the prism starts along `axis` (m)
        from: Real,
        /// where it ends along `axis` (m), > `from`
        to: Real,
    },
}

impl Shape {
    /// the axis-aligned box the shape lies in, (lowest, highest) corner.
    pub fn bounds(&self) -> (Vector, Vector) {
        match self {
            Shape::Box { min, max } => (*min, *max),
            Shape::Cylinder { base, axis, radius, height } => {
                let a = axis.normalize_or_zero();
                let top = *base + *height * a;
                // the disc of radius r normal to a reaches r·√(1 − a_k²) along axis k
                let reach = Vector::from_array(
                    a.to_array().map(|c| radius * (1.0 - c * c).max(0.0).sqrt()),
                );
                (base.min(top) - reach, base.max(top) + reach)
            }
            Shape::Prism { vertices, axis, from, to } => {
                let mut lo = [*from; 3];
                let mut hi = [*to; 3];
                let [u, v] = axis.others();
                let (pl, ph) = vertices.iter().fold(
                    (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
                    |(l, h), p| (l.min(*p), h.max(*p)),
                );
                (lo[u], lo[v], hi[u], hi[v]) = (pl.x, pl.y, ph.x, ph.y);
                (Vector::from_array(lo), Vector::from_array(hi))
            }
        }
    }

    /// whether `p` lies strictly inside the shape (a box's faces count as inside).
    pub fn contains(&self, p: Vector) -> bool {
        match self {
            Shape::Box { min, max } => p.cmpge(*min).all() && p.cmple(*max).all(),
            Shape::Cylinder { base, axis, radius, height } => {
                let a = axis.normalize_or_zero();
                let d = p - *base;
                let along = d.dot(a);
                along > 0.0 && along < *height && (d - along * a).length_squared() < radius * radius
            }
            Shape::Prism { vertices, axis, from, to } => {
                let c = p[axis.index()];
                let [u, v] = axis.others();
                c > *from
                    && c < *to
                    && vertices.len() >= 3
                    && inside_polygon(vertices, DVec2::new(p[u], p[v]))
            }
        }
    }
}

/// Fills `shape` with points at spacing `spacing` (m); `spacing` must be positive and finite
/// (otherwise, or for an empty or non-finite shape, no point).
///
/// A box is filled exactly (its volume is the sum of the points' volumes when its sides are
/// multiples of the spacing; otherwise the lattice keeps whole sub-cubes whose centre lies
/// inside); cylinders and prisms keep the lattice points strictly inside.
pub fn fill(shape: &Shape, spacing: Real) -> Vec<Seed> {
    let mut out = Vec::new();
    let (lo, hi) = shape.bounds();
    if !(spacing > 0.0 && spacing.is_finite() && lo.is_finite() && hi.is_finite()) {
        return out;
    }
    // Relative slack so that a size that is an exact multiple of the spacing, up to rounding,
    // gives exactly that many points: 1e-9, and the rounding of hi − lo where the coordinates
    // are large (a box 0.4 m wide at x = 5e6 m measured 7.9999999925 spacings of 0.05 m).
    const SLACK: Real = 1e-9;
    let rounding = 4.0 * Real::EPSILON * lo.abs().max(hi.abs()).max_element() / spacing;
    let count = ((hi - lo) / spacing + (SLACK + rounding)).floor().max(Vector::ZERO);
    let [nx, ny, nz] = count.to_array().map(|c| c as usize);
    let volume = spacing * spacing * spacing;
    let whole = matches!(shape, Shape::Box { .. });
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let at = Vector::new(i as Real + 0.5, j as Real + 0.5, k as Real + 0.5);
                let position = lo + spacing * at;
                if whole || shape.contains(position) {
                    out.push(Seed { position, volume });
                }
            }
        }
    }
    out
}
