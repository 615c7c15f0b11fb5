//! Stage 4: the grid solve.
//!
//! a_i = f_i / m_i (eq 4), except at small-mass nodes (m_i below the threshold, §2(3)) where the
//! internal force is dropped and a_i = f_i^ext / m_i = b; then the boundary conditions of the contact
//! layer (eqs 14–18), which keep v_i^L = v_i + a_i Δt (eq 5) so that v^L need not be stored. The work of each boundary impulse is booked
//! in the energy ledger, split into its part normal to the node's first boundary (constraint work)
//! and the rest (friction work).

use mpm_constitutive::ConstitutiveModel;
use mpm_contact::{apply_all, constrain_velocity_all};
use mpm_grid::ShapeFunctions;
use rayon::prelude::*;

use crate::math::{Real, Vector};
use crate::solver::Solver;

impl<M: ConstitutiveModel, S: ShapeFunctions<N>, const N: usize> Solver<M, S, N> {
    /// accelerations and end-of-step velocities of every active node, boundary nodes included.
    pub(crate) fn grid_solve(&mut self, dt: Real) {
        let sc = &mut self.scratch;
        let small = self.small_mass;
        let g = self.config.gravity_at(self.time + 0.5 * dt);
        sc.acceleration
            .par_iter_mut()
            .zip(sc.force.par_iter().zip(sc.mass.par_iter()))
            .with_min_len(1024)
            .for_each(|(a, (&f, &m))| {
                *a = if m > small { f / m } else { g };
            });

        let (mut friction, mut constraint) = (0.0, 0.0);
        for b in &sc.boundary {
            let i = b.node as usize;
            let planes = &b.planes[..usize::from(b.count)];
            // A ghost node meets a wall moving with its image's mirrored normal velocity (images
            // are interior nodes, final above); a node on the plane meets a wall at rest.
            let wall = match b.mirror {
                Some(m) => {
                    let j = m.image as usize;
                    let v_image = sc.velocity[j] + sc.acceleration[j] * dt;
                    if m.fixed {
                        // A fixed plane: the velocity field is antisymmetric across it.
                        sc.acceleration[i] = (-v_image - sc.velocity[i]) / dt;
                        continue;
                    }
                    m.wall_velocity(v_image)
                }
                None => Vector::ZERO,
            };
            let v_rel = sc.velocity[i] - wall;
            let out = apply_all(planes, sc.mass[i], v_rel, sc.acceleration[i], dt);
            // v^L = v_rel + a Δt + wall = v + a Δt: the identity still holds.
            sc.acceleration[i] = out.acceleration;
            // Work the boundary impulse J does over the step at the mean nodal velocity relative
            // to the wall: for a node at rest on the ground it is zero (the reaction does no
            // work), for a sliding node it is the friction force times the distance slid. Their
            // sum is the kinetic energy the impulse takes from the node (midpoint rule), which is
            // what closes the ledger; the split along the first plane's normal is indicative
            // only, and either part can be negative in a step where a pressed node was moving
            // away from the wall.
            let mean_v = 0.5 * (v_rel + out.velocity);
            let n = b.planes[0].normal();
            let (jn, vn) = (out.impulse.dot(n), mean_v.dot(n));
            constraint -= jn * vn;
            friction -= out.impulse.dot(mean_v) - jn * vn;
        }
        self.dissipation.friction += friction;
        self.dissipation.constraint += constraint;
    }

    /// v_i ← v_i^L = v_i + a_i Δt (eq 5), for USL's strain increment.
    pub(crate) fn advance_velocity(&mut self, dt: Real) {
        let sc = &mut self.scratch;
        sc.velocity.par_iter_mut().zip(sc.acceleration.par_iter()).with_min_len(1024).for_each(
            |(v, &a)| {
                *v += a * dt;
            },
        );
    }

    /// the velocity constraint (eq 18) on `scratch.velocity` at boundary nodes, for a strain
    /// update. The unconstrained velocities are kept in `scratch.saved` so that
    /// [`Self::unconstrain_velocity`] can put them back before the grid solve: the grid solve must
    /// start from the velocity the particles actually carry, so that the contact's removal of an
    /// approach velocity reaches the particles through the FLIP update (eq 7). Otherwise the same
    /// approach velocity is stopped again at every step, and turned into strain energy each time.
    pub(crate) fn constrain_velocity(&mut self) {
        let sc = &mut self.scratch;
        sc.saved.clear();
        for b in &sc.boundary {
            let i = b.node as usize;
            sc.saved.push(sc.velocity[i]);
        }
        for b in &sc.boundary {
            let i = b.node as usize;
            let planes = &b.planes[..usize::from(b.count)];
            let wall = match b.mirror {
                Some(m) if m.fixed => {
                    sc.velocity[i] = -sc.velocity[m.image as usize];
                    continue;
                }
                Some(m) => m.wall_velocity(sc.velocity[m.image as usize]),
                None => Vector::ZERO,
            };
            sc.velocity[i] = constrain_velocity_all(planes, sc.velocity[i] - wall) + wall;
        }
    }

    /// restores the boundary nodes' velocities saved by [`Self::constrain_velocity`].
    pub(crate) fn unconstrain_velocity(&mut self) {
        let sc = &mut self.scratch;
        for (b, &v) in sc.boundary.iter().zip(&sc.saved) {
            sc.velocity[b.node as usize] = v;
        }
    }
}
