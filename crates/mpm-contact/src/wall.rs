//! Where a boundary is: a plane through a point, or a straight segment of one, with a solid of some
//! thickness behind its face, and the tests that say which material points and nodes it touches.
//!
//! A [`Boundary`] is what the node law needs (a normal and a friction law); a [`Wall`] adds where
//! the boundary lies, so that a solver can decide which grid nodes it holds. The grid's own sides
//! (the ground under a terrain-following grid, the walls at its first and last columns) are walls
//! through a node; a wall declared anywhere else (an inclined retaining wall, a check dam inside the
//! domain) is one whose face lies between nodes.
//!
//! # Geometry
//! - n: the boundary's unit normal, into the material; t = (n_y, −n_x) its tangent.
//! - x₀: a point of the face. d(x) = (x − x₀)·n: signed distance from the face, > 0 in front
//!   (material side), < 0 inside the solid. s(x) = (x − x₀)·t: position along the face.
//! - span [s₀, s₁] along t: (−∞, ∞) for a plane; [0, L] for a segment from a to b, with x₀ = a and
//!   t = (b − a)/L, so that the material lies on the left when walking from a to b.
//! - thickness T: the solid occupies −T ≤ d < 0 over the span (T = ∞: everything behind the face).
//!
//! # Touching (the surface-contact rule)
//! A material point at x with half-size r and velocity v touches the wall over a step Δt when it lies
//! over the span (s₀ − r ≤ s ≤ s₁ + r), its centre is not past the solid's mid-depth (d ≥ −T/2),
//! and its edge is on the face or reaches it within the step:
//! d − r + Δt·min(v·n, 0) ≤ [`TOUCH_TOLERANCE`]·r. A point that has entered the front half of the
//! solid still touches, so that the wall pushes it back out; one past the mid-depth is on the back
//! side, which a wall does not act on (a wall has one face: declare the back of a dam that can be
//! overtopped as a second wall facing the other way).

use serde::{Deserialize, Serialize};

#[cfg(not(feature = "dim3"))]
use crate::boundary::tangent_of;
use crate::{Boundary, ContactError, Friction, Vector};

/// A wall touches a material point when the gap between the point's edge and the face is at most this
/// fraction of the point's half-size: a point resting on the face, whose gap is zero up to rounding,
/// stays in contact.
pub const TOUCH_TOLERANCE: f64 = 0.01;

/// A boundary with a place: a plane or a segment of one, its solid behind it, and its friction law.
///
/// Built by [`Wall::plane`] or [`Wall::segment`], which validate everything; the tests are then
/// branch-light arithmetic, cheap enough to run per particle.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Wall {
    boundary: Boundary,
    point: Vector,
    span: [f64; 2],
    thickness: f64,
}

impl Wall {
    /// the unbounded plane through `point` with unit normal `normal` (into the material), the solid
    /// filling everything behind it.
    pub fn plane(point: Vector, normal: Vector, friction: Friction) -> Result<Self, ContactError> {
        if !point.is_finite() {
            return Err(ContactError::NonFinitePoint { point });
        }
        let boundary = Boundary::new(normal, friction)?;
        Ok(Self {
            boundary,
            point,
            span: [f64::NEG_INFINITY, f64::INFINITY],
            thickness: f64::INFINITY,
        })
    }

    #[cfg(not(feature = "dim3"))]
    /// the segment from `from` to `to`, the material on its left (normal = the direction from → to
    /// turned by +90°), with a solid `thickness` m deep behind it (`f64::INFINITY`: all the way).
    pub fn segment(
        from: Vector,
        to: Vector,
        friction: Friction,
        thickness: f64,
    ) -> Result<Self, ContactError> {
        for point in [from, to] {
            if !point.is_finite() {
                return Err(ContactError::NonFinitePoint { point });
            }
        }
        let length = (to - from).length();
        if !(length > 0.0 && length.is_finite()) {
            return Err(ContactError::DegenerateSegment { from, to });
        }
        if thickness.is_nan() || thickness <= 0.0 {
            return Err(ContactError::InvalidThickness { from, to, thickness });
        }
        let t = (to - from) / length;
        let boundary = Boundary::new(Vector::new(-t.y, t.x), friction)?;
        Ok(Self { boundary, point: from, span: [0.0, length], thickness })
    }

    /// the node law's view of the wall: its normal and friction law.
    pub fn boundary(&self) -> &Boundary {
        &self.boundary
    }

    /// the unit normal n, into the material.
    pub fn normal(&self) -> Vector {
        self.boundary.normal()
    }

    /// the point x₀ of the face that distances and spans are measured from.
    pub fn point(&self) -> Vector {
        self.point
    }

    /// the span [s₀, s₁] along the tangent, from [`Wall::point`].
    pub fn span(&self) -> [f64; 2] {
        self.span
    }

    /// the depth T of the solid behind the face, m.
    pub fn thickness(&self) -> f64 {
        self.thickness
    }

    /// d(x): signed distance of `x` from the face, > 0 on the material side.
    #[inline]
    pub fn distance(&self, x: Vector) -> f64 {
        (x - self.point).dot(self.normal())
    }

    /// true when `x` lies over the span widened by `margin` m at both ends, at a depth behind the
    /// face of at most `depth` m: s₀ − margin ≤ s(x) ≤ s₁ + margin and d(x) ≥ −depth.
    #[inline]
    fn covers(&self, x: Vector, margin: f64, depth: f64) -> bool {
        #[cfg(not(feature = "dim3"))]
        let over = {
            let s = (x - self.point).dot(tangent_of(self.normal()));
            s >= self.span[0] - margin && s <= self.span[1] + margin
        };
        // a 3D wall is an unbounded plane: every point is over it
        #[cfg(feature = "dim3")]
        let over = {
            let _ = margin;
            true
        };
        over && self.distance(x) >= -depth
    }

    /// true when `x` lies inside the solid: over the span, behind the face, within the thickness.
    pub fn contains(&self, x: Vector) -> bool {
        self.distance(x) < 0.0 && self.covers(x, 0.0, self.thickness)
    }

    /// true when a node at `x` lies on the face or inside the solid (the paper's rule holds such
    /// nodes whatever the material does; a node on the face is within 1e-9 of the face's scale).
    pub fn holds_node(&self, x: Vector) -> bool {
        let slack = 1e-9 * (x - self.point).length().max(1.0);
        self.distance(x) <= slack && self.covers(x, slack, self.thickness + slack)
    }

    /// the touching rule of the module documentation, for a material point at `x` of half-size
    /// `half_size`, moving at `velocity` over a step `dt`.
    #[inline]
    pub fn touches(&self, x: Vector, half_size: f64, velocity: Vector, dt: f64) -> bool {
        let n = self.normal();
        let gap = self.distance(x) - half_size + dt * velocity.dot(n).min(0.0);
        gap <= TOUCH_TOLERANCE * half_size && self.covers(x, half_size, 0.5 * self.thickness)
    }

    /// true when some point within `reach` m of `x` lies over the wall and within `reach` of its
    /// face or inside its solid: the nodes a solver must watch, `reach` being how far a touching
    /// material point can be from the nodes of its stencil.
    pub fn near(&self, x: Vector, reach: f64) -> bool {
        self.distance(x) <= reach && self.covers(x, reach, self.thickness + reach)
    }
}

/// the serialised form of a wall, validated on the way in.
#[derive(Deserialize)]
struct WallDef {
    boundary: Boundary,
    point: Vector,
    span: [f64; 2],
    thickness: f64,
}

impl<'de> Deserialize<'de> for Wall {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let WallDef { boundary, point, span, thickness } = WallDef::deserialize(deserializer)?;
        if !point.is_finite() {
            return Err(serde::de::Error::custom(format!("wall at {point}: point is not finite")));
        }
        // (a plane's span is (−∞, ∞): compared, not subtracted)
        if span[0].partial_cmp(&span[1]) != Some(std::cmp::Ordering::Less)
            || thickness.is_nan()
            || thickness <= 0.0
        {
            return Err(serde::de::Error::custom(format!(
                "wall at {point}: span {span:?} must have s0 < s1 and thickness {thickness} must be \
                 positive"
            )));
        }
        Ok(Self { boundary, point, span, thickness })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// (x, y) in the plane, (x, y, 0.4) in space: the plane tests hold on any section.
    fn at(x: f64, y: f64) -> Vector {
        #[cfg(not(feature = "dim3"))]
        return Vector::new(x, y);
        #[cfg(feature = "dim3")]
        Vector::new(x, y, 0.4)
    }

    /// the direction (x, y), in the x–y plane in both builds.
    fn along(x: f64, y: f64) -> Vector {
        at(x, y) - at(0.0, 0.0)
    }

    const FREE: Friction = Friction::Coulomb { mu: 0.0 };

    #[cfg(not(feature = "dim3"))]
    #[test]
    fn a_segment_faces_its_left_and_measures_from_its_start() {
        // from (1, 0) up to (1, 2): the material is on the left, at x < 1.
        let w = Wall::segment(Vector::new(1.0, 0.0), Vector::new(1.0, 2.0), FREE, 0.5).unwrap();
        assert_eq!(w.normal(), Vector::new(-1.0, 0.0));
        assert_eq!(w.distance(Vector::new(0.25, 1.0)), 0.75);
        assert!(w.contains(Vector::new(1.25, 1.0)));
        // beyond the thickness, above the top, below the foot: outside the solid
        assert!(!w.contains(Vector::new(1.75, 1.0)));
        assert!(!w.contains(Vector::new(1.25, 2.5)));
        assert!(!w.contains(Vector::new(1.25, -0.5)));
    }

    #[test]
    fn touching_needs_the_edge_on_the_face_or_reaching_it_within_the_step() {
        let w = Wall::plane(Vector::ZERO, Vector::Y, FREE).unwrap();
        let r = 0.1;
        assert!(w.touches(at(3.0, r), r, Vector::ZERO, 1e-3));
        assert!(w.touches(at(3.0, r * 1.005), r, Vector::ZERO, 1e-3));
        assert!(!w.touches(at(3.0, r * 1.02), r, Vector::ZERO, 1e-3));
        // 1 cm above, falling at 1 m/s: reached within 0.02 s, not within 0.005 s
        assert!(w.touches(at(3.0, r + 0.01), r, -Vector::Y, 0.02));
        assert!(!w.touches(at(3.0, r + 0.01), r, -Vector::Y, 0.005));
        // a point that has entered the solid still touches
        assert!(w.touches(at(3.0, -0.5), r, Vector::ZERO, 1e-3));
    }

    #[cfg(not(feature = "dim3"))]
    #[test]
    fn a_point_beside_a_segment_does_not_touch_it() {
        // a check dam 1 m high at x = 2, thickness 0.2 m, material on its left
        let w = Wall::segment(Vector::new(2.0, 0.0), Vector::new(2.0, 1.0), FREE, 0.2).unwrap();
        let r = 0.05;
        assert!(w.touches(Vector::new(2.0 - r, 0.5), r, Vector::ZERO, 1e-3));
        // passing over the top: beyond the span by more than r
        assert!(!w.touches(Vector::new(2.0 - r, 1.0 + 2.0 * r), r, Vector::ZERO, 1e-3));
        // past the solid's mid-depth (0.1 m): the back side, which this wall does not act on
        assert!(w.touches(Vector::new(2.09, 0.5), r, Vector::ZERO, 1e-3));
        assert!(!w.touches(Vector::new(2.11, 0.5), r, Vector::ZERO, 1e-3));
        assert!(!w.touches(Vector::new(2.0 + 0.2 + r, 0.5), r, Vector::ZERO, 1e-3));
        assert!(w.near(Vector::new(1.5, 0.5), 0.6));
        assert!(!w.near(Vector::new(1.3, 0.5), 0.6));
    }

    #[test]
    fn nodes_on_the_face_are_held_by_the_paper_rule() {
        let w = Wall::plane(at(0.0, 1.0), along(0.6, 0.8), FREE).unwrap();
        let on_face = at(0.0, 1.0) + 3.0 * along(0.8, -0.6);
        assert!(w.normal().dot(along(0.8, -0.6)).abs() < 1e-15, "a direction along the face");
        assert!(w.holds_node(on_face));
        assert!(w.holds_node(on_face - 0.1 * w.normal()));
        assert!(!w.holds_node(on_face + 0.1 * w.normal()));
    }

    #[test]
    fn a_plane_through_no_point_is_refused() {
        assert!(matches!(
            Wall::plane(at(f64::NAN, 0.0), Vector::Y, FREE),
            Err(ContactError::NonFinitePoint { .. })
        ));
        assert!(Wall::plane(at(0.0, 0.0), Vector::ZERO, FREE).is_err(), "no normal");
    }

    #[cfg(not(feature = "dim3"))]
    #[test]
    fn bad_walls_are_refused() {
        let p = Vector::new(1.0, 1.0);
        assert!(matches!(
            Wall::segment(p, p, FREE, 1.0),
            Err(ContactError::DegenerateSegment { .. })
        ));
        for t in [0.0, -1.0, f64::NAN] {
            assert!(matches!(
                Wall::segment(Vector::ZERO, p, FREE, t),
                Err(ContactError::InvalidThickness { .. })
            ));
        }
        assert!(matches!(
            Wall::plane(Vector::new(f64::NAN, 0.0), Vector::Y, FREE),
            Err(ContactError::NonFinitePoint { .. })
        ));
        assert!(Wall::segment(Vector::ZERO, p, Friction::Coulomb { mu: -1.0 }, 1.0).is_err());
        let json = r#"{"boundary":{"normal":[0.0,1.0],"friction":"Rough"},"point":[0.0,0.0],
            "span":[1.0,0.0],"thickness":1.0}"#;
        assert!(serde_json::from_str::<Wall>(json).is_err());
        let json = json.replace("[1.0,0.0]", "[1.0,1.0]");
        assert!(serde_json::from_str::<Wall>(&json).is_err(), "a zero-length span");
    }
}
