//! Helpers that let one test serve both builds of this source; not part of the API (the
//! solver's tests use them too). A test written in the plane's x–y runs in space on the
//! section z = 0 of a grid [`LAYERS`] cells deep, z = 0 half-way between two node layers: there
//! a trilinear stencil's weights are the bilinear ones halved on each layer, so a sum over a
//! stencil is the plane's, and a sheet of particles on z = 0 loads both layers alike (no node of
//! its stencil is without mass, and nothing drives it along z).

use crate::{DIM, GridError, NodeId, RegularGrid, Vector};

/// nodes of the linear stencil: 4 (bilinear) in the plane, 8 (trilinear) in space.
pub const LINEAR: usize = 1 << DIM;

/// cell layers of a test grid in space (along z).
pub const LAYERS: usize = 4;

/// the point or vector (x, y); in space (x, y, 0).
pub fn at(x: f64, y: f64) -> Vector {
    with_z(x, y, 0.0)
}

/// (x, y) in the plane, (x, y, z) in space.
pub fn with_z(x: f64, y: f64, z: f64) -> Vector {
    #[cfg(not(feature = "dim3"))]
    {
        let _ = z;
        Vector::new(x, y)
    }
    #[cfg(feature = "dim3")]
    Vector::new(x, y, z)
}

/// node (i, j); in space (i, j, [`LAYERS`]/2 − 1), the node layer just below z = 0 of a grid
/// from [`grid`] (the corner of the cell that holds z = 0).
pub fn node(i: i32, j: i32) -> NodeId {
    #[cfg(not(feature = "dim3"))]
    return NodeId::new(i, j);
    #[cfg(feature = "dim3")]
    NodeId::new(i, j, LAYERS as i32 / 2 - 1)
}

/// the cell counts [nx, ny]; in space [nx, ny, [`LAYERS`]].
pub fn cells(counts: [usize; 2]) -> [usize; DIM] {
    let mut all = [LAYERS; DIM];
    all[..2].copy_from_slice(&counts);
    all
}

/// a regular grid from `origin` (x, y) with cells `cell` (w × h) and `counts` cells; in space
/// [`LAYERS`] cells of depth w from z = −(LAYERS/2 − ½)·w, so that z = 0 is half-way between
/// two node layers.
pub fn grid(
    origin: [f64; 2],
    cell: [f64; 2],
    counts: [usize; 2],
) -> Result<RegularGrid, GridError> {
    let depth = cell[0];
    RegularGrid::new(
        with_z(origin[0], origin[1], -(LAYERS as f64 / 2.0 - 0.5) * depth),
        with_z(cell[0], cell[1], depth),
        cells(counts),
    )
}

/// the volume of a particle of `side` along each axis: side² in the plane (per metre of
/// thickness), side³ in space.
pub fn volume(side: f64) -> f64 {
    side.powi(DIM as i32)
}
