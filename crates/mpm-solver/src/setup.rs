//! What [`Solver::new`](crate::Solver::new) checks of the particles it is handed and the
//! reference density it derives from them, and the memory a solver will hold, estimated before
//! anything is built.

use mpm_contact::Wall;
use mpm_grid::{BLOCK_SIDE, NodeId};

use crate::error::SolverError;
use crate::math::{DIM, Matrix, Real, Vector};
use crate::particles::Particles;
use crate::scratch::PatchSums;

/// the most bytes the factors of a 4-node stencil take (`Bilinear<TerrainGrid>`: a, b, ∂b/∂x).
pub(crate) const FACTORS_4: usize = 3 * size_of::<Real>();
/// the most bytes the factors of a wide stencil take (uGIMP, B-spline: 3 (weight, slope) pairs
/// along each axis; 3 × 3 × 3 in space is 18 numbers, not the plane's 12: the 3D estimate
/// charged 48 B per particle too few until the solver's tests ran in both builds).
pub(crate) const FACTORS_9: usize = 6 * DIM * size_of::<Real>();

/// heap bytes a running solver of `particles` particles, `nodes` active nodes, stencils of
/// `stencil` nodes, a constitutive state of `state_bytes` bytes and (with `apic`) affine
/// matrices holds: about what [`Solver::heap_bytes`](crate::Solver::heap_bytes) reports once it runs (the patches of
/// partial sums are charged for blocks half full of nodes), computed without building it, so
/// that a front end can refuse a scene that does not fit in memory before allocating anything.
pub fn estimated_bytes(
    particles: usize,
    nodes: usize,
    stencil: usize,
    state_bytes: usize,
    apic: bool,
) -> u64 {
    let per_particle = 3 * size_of::<Vector>()
        + 2 * size_of::<Real>()
        + size_of::<crate::math::Stress>()
        + state_bytes
        + 2 * size_of::<u16>()
        + if apic { size_of::<Matrix>() } else { 0 }
        // first node id, dense indices, and the factors of the weights and gradients: at most
        // 3 numbers for a 4-node stencil, 3 (weight, slope) pairs per axis for a wide one
        + size_of::<NodeId>()
        + stencil * size_of::<u32>()
        + (if stencil <= 4 { FACTORS_4 } else { FACTORS_9 })
        // bin entry, place in the block's patch
        + size_of::<u32>()
        + 1;
    // Each block of 64 nodes (8 × 8, in space 4 × 4 × 4) holds a patch of side² (side³)
    // partial sums whatever its fill, plus its bin start, neighbours and sort counters: charged
    // per node as if blocks were half full (a full block costs half this, a thin strip of
    // material more).
    let w = (1..=stencil).find(|w| w.pow(DIM as u32) >= stencil).unwrap_or(1);
    let side = BLOCK_SIDE as usize + w - 1;
    let per_block = side.pow(DIM as u32) * size_of::<PatchSums>() + 20 + 64;
    let per_node = size_of::<NodeId>()
        + 8
        // block rank, place in the patch, referenced, boundary position
        + size_of::<u32>() + 2 + size_of::<u32>()
        + size_of::<Real>()
        + 3 * size_of::<Vector>()
        + per_block.div_ceil(32);
    (particles as u64) * per_particle as u64 + (nodes as u64) * per_node as u64
}

/// the time step's reference density of each material: the checkpoint's (a resumed run keeps the
/// density it started with), or in a new run the lightest density of each material's particles
/// (a material no particle uses gets +∞, which leaves its particles uncapped should any appear).
pub(crate) fn reference_density<St>(
    p: &Particles<St>,
    materials: usize,
    saved: Vec<Real>,
) -> Result<Vec<Real>, SolverError> {
    if saved.is_empty() {
        let mut lightest = vec![Real::INFINITY; materials];
        for i in 0..p.len() {
            let m = usize::from(p.material[i]);
            lightest[m] = lightest[m].min(p.density(i));
        }
        return Ok(lightest);
    }
    if saved.len() != materials {
        return Err(SolverError::InvalidSetting {
            name: "checkpoint.reference_density",
            value: saved.len() as f64,
            expected: "one reference density per material",
        });
    }
    if let Some(&bad) = saved.iter().find(|r| r.is_nan() || **r <= 0.0) {
        return Err(SolverError::InvalidSetting {
            name: "checkpoint.reference_density",
            value: bad,
            expected: "a positive density (kg/m³)",
        });
    }
    Ok(saved)
}

/// refuses a new run with a particle inside a wall's solid: the wall would push it out through
/// the material in the first steps (a scene error, not physics).
pub(crate) fn outside_walls<St>(p: &Particles<St>, walls: &[Wall]) -> Result<(), SolverError> {
    for (k, wall) in walls.iter().enumerate() {
        if let Some(i) = p.position.iter().position(|&x| wall.contains(x)) {
            return Err(SolverError::InvalidParticle {
                particle: i,
                position: p.position[i],
                reason: format!(
                    "inside the solid of wall {k} (face through ({}, {}), normal ({}, {}))",
                    wall.point().x,
                    wall.point().y,
                    wall.normal().x,
                    wall.normal().y
                ),
            });
        }
    }
    Ok(())
}

pub(crate) fn validate_particles<St>(
    p: &Particles<St>,
    materials: usize,
) -> Result<(), SolverError> {
    if !p.is_consistent() {
        return Err(SolverError::InvalidSetting {
            name: "particles",
            value: p.len() as f64,
            expected: "particle arrays of equal length",
        });
    }
    for i in 0..p.len() {
        let bad = |reason: String| SolverError::InvalidParticle {
            particle: i,
            position: p.position[i],
            reason,
        };
        if !p.position[i].is_finite() {
            return Err(bad("position is not finite".into()));
        }
        if !p.velocity[i].is_finite() {
            return Err(bad("velocity is not finite".into()));
        }
        if !(p.mass[i] > 0.0 && p.mass[i].is_finite()) {
            return Err(bad(format!("mass {} must be positive and finite", p.mass[i])));
        }
        if !(p.volume[i] > 0.0 && p.volume[i].is_finite()) {
            return Err(bad(format!("volume {} must be positive and finite", p.volume[i])));
        }
        if !p.stress[i].is_finite() {
            return Err(bad("stress is not finite".into()));
        }
        if usize::from(p.material[i]) >= materials {
            return Err(bad(format!(
                "material index {} but only {materials} material(s) are defined",
                p.material[i]
            )));
        }
    }
    Ok(())
}
