//! The open core: a periodic pair of sides and a rate-dependent model, each against an exact
//! reference (a conservation law; Bagnold's profile).

use mpm_grid::RegularShape;
use mpm_tests::open_core::{bagnold, periodic_block};

/// Nothing acts on the block, and the fold of the periodic sides adds forces pairwise: the
/// momentum is its initial one to rounding of the sums (1e-12 relative, a few hundred steps of
/// ~1e-16 each), and every particle is where the translation puts it to rounding of x + Δt v
/// over the steps (1e-12 m).
const MOMENTUM_REL: f64 = 1e-12;
const POSITION_ABS: f64 = 1e-12;

#[test]
fn a_block_leaves_through_one_periodic_side_and_enters_through_the_other() {
    for kind in [RegularShape::Bilinear, RegularShape::BSpline] {
        let r = periodic_block(kind).unwrap();
        assert_eq!(r.wrapped, r.particles, "{kind:?}: every particle crossed");
        assert!(r.momentum_drift <= MOMENTUM_REL, "{kind:?}: drift {:e}", r.momentum_drift);
        let change = (r.momentum_end - r.momentum_start).length() / r.momentum_start.length();
        assert!(change <= MOMENTUM_REL, "{kind:?}: {change:e}");
        assert!(r.position_error <= POSITION_ABS, "{kind:?}: {:e} m", r.position_error);
    }
}

/// The bound: Bagnold's profile to 2 % of the surface speed at 16 cells over the depth.
const BAGNOLD_REL: f64 = 0.02;

#[test]
fn steady_mu_i_flow_down_a_periodic_slope_has_bagnolds_profile() {
    // from rest, the layer approaches its steady state over ~0.5 s (measured: 80 % of the
    // surface speed at 0.5 s, within 1 % at 1.5 s).
    let r = bagnold(16, 2.0).unwrap();
    assert!(r.change <= BAGNOLD_REL, "not steady: {:e}", r.change);
    assert!(r.worst <= BAGNOLD_REL, "worst {:.4}", r.worst);
}
