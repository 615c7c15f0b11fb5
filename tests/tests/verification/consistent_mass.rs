//! The consistent mass matrix (`mpm_solver::MassMatrix::Consistent`, `stages/mass.rs`): its rows
//! sum to the lumped masses and it is symmetric, so the particles' momentum changes by exactly
//! the nodal forces' impulse. The vibrating bar's comparison with the lumped matrix is in
//! `bardenhagen2002.rs`.

use mpm_solver::Scheme;
use mpm_tests::{Discretisation, MassMatrix, ShapeKind, swirl_momentum_error};

/// Momentum balance of a swirling, stressed block in free flight over 40 steps: the solver's
/// 1e-13 tolerance plus the rounding of a few hundred nodes' sums stays below 1e-12 (measured
/// at most a few 1e-15 for both matrices).
const MOMENTUM_REL: f64 = 1e-12;

#[test]
fn consistent_mass_conserves_momentum_for_every_scheme_and_shape() {
    for shape in [ShapeKind::Bilinear, ShapeKind::BSpline, ShapeKind::Gimp] {
        for scheme in Scheme::ALL {
            for mass in [MassMatrix::Lumped, MassMatrix::Consistent] {
                let d = Discretisation { shape, scheme, mass, ..Discretisation::paper(0.25) };
                let error = swirl_momentum_error(&d).unwrap();
                assert!(error < MOMENTUM_REL, "{shape:?} {scheme:?} {mass:?}: {error:e}");
            }
        }
    }
}
