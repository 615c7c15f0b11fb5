//! The one place where a choice of shape functions on a regular grid becomes a type: front ends
//! and test drivers name the shape functions at run time ([`RegularShape`]) and run work that is
//! generic over them ([`ShapeJob`]), monomorphised, with no per-point dynamic dispatch.

use crate::error::GridError;
use crate::{Bilinear, Gimp, QuadraticBSpline, RegularGrid, ShapeFunctions};

/// The shape functions a regular grid offers (the terrain grid offers bilinear only).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RegularShape {
    /// bilinear (N = 4; trilinear in 3D, N = 8).
    Bilinear,
    /// uGIMP with the particle size of n × n (n × n × n) particles per cell (N = 9; 27 in 3D).
    Gimp,
    /// quadratic B-splines (N = 9; 27 in 3D).
    BSpline,
}

impl RegularShape {
    /// every kind, cheapest first.
    pub const ALL: [RegularShape; 3] =
        [RegularShape::Bilinear, RegularShape::Gimp, RegularShape::BSpline];

    /// short name for tables and legends.
    pub fn name(self) -> &'static str {
        match self {
            RegularShape::Bilinear => "bilinear",
            RegularShape::Gimp => "uGIMP",
            RegularShape::BSpline => "B-spline",
        }
    }
}

/// Work generic over the shape functions.
pub trait ShapeJob {
    /// what the work returns.
    type Output;
    /// runs with concrete shape functions.
    fn run<S: ShapeFunctions<N>, const N: usize>(self, shape: S) -> Self::Output;
}

/// Builds the shape functions `kind` on `grid` and runs `job` with them; uGIMP's particle size
/// is that of `particles_per_cell` particles per cell along each axis (refused when 0).
pub fn with_regular_shape<J: ShapeJob>(
    kind: RegularShape,
    grid: RegularGrid,
    particles_per_cell: usize,
    job: J,
) -> Result<J::Output, GridError> {
    Ok(match kind {
        RegularShape::Bilinear => job.run(Bilinear(grid)),
        RegularShape::Gimp => {
            job.run(Gimp::with_particles_per_cell(grid, [particles_per_cell; crate::DIM])?)
        }
        RegularShape::BSpline => job.run(QuadraticBSpline::new(grid)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// the stencil size N of the shape functions a kind builds.
    struct StencilSize;

    impl ShapeJob for StencilSize {
        type Output = usize;
        fn run<S: ShapeFunctions<N>, const N: usize>(self, _shape: S) -> usize {
            N
        }
    }

    #[test]
    fn each_kind_builds_its_own_stencil_and_gimp_refuses_no_particles() {
        let grid = crate::testing::grid([0.0; 2], [0.1; 2], [10, 10]).unwrap();
        let (linear, wide) = (crate::testing::LINEAR, 3usize.pow(crate::DIM as u32));
        assert_eq!((linear, wide), if crate::DIM == 3 { (8, 27) } else { (4, 9) });
        assert_eq!(
            with_regular_shape(RegularShape::Bilinear, grid, 2, StencilSize).unwrap(),
            linear
        );
        assert_eq!(with_regular_shape(RegularShape::Gimp, grid, 2, StencilSize).unwrap(), wide);
        assert_eq!(with_regular_shape(RegularShape::BSpline, grid, 2, StencilSize).unwrap(), wide);
        assert!(with_regular_shape(RegularShape::Gimp, grid, 0, StencilSize).is_err());
    }
}
