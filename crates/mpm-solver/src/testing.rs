//! Test support (compiled for tests only): bodies for tests that run in both builds, over the
//! grids of `mpm_grid::testing` (the plane's x–y as the section z = 0 of a grid four cells
//! deep).

use crate::generate::{Shape, fill};
use crate::math::{Real, Vector};

/// the seeds (position, volume) of a block from `min` to `max` (x, y) filled at `spacing`: in
/// the plane a rectangle (areas per metre of thickness), in space a box four particles deep
/// about z = 0 (from −2·spacing to 2·spacing), so that the plane's block is its section.
pub(crate) fn block(min: [Real; 2], max: [Real; 2], spacing: Real) -> Vec<(Vector, Real)> {
    #[cfg(not(feature = "dim3"))]
    {
        let shape =
            Shape::Rectangle { min: Vector::new(min[0], min[1]), max: Vector::new(max[0], max[1]) };
        fill(&shape, spacing).into_iter().map(|s| (s.position, s.area)).collect()
    }
    #[cfg(feature = "dim3")]
    {
        let depth = 2.0 * spacing;
        let shape = Shape::Box {
            min: Vector::new(min[0], min[1], -depth),
            max: Vector::new(max[0], max[1], depth),
        };
        fill(&shape, spacing).into_iter().map(|s| (s.position, s.volume)).collect()
    }
}
