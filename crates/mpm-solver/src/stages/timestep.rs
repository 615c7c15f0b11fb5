//! Stage 1: the time step from the Courant condition (eq 13, SPEC §1 "Time step").
//!
//! c_p = √((λ + 2G)/ρ*_p) is the dilatational wave speed at particle p, L the smallest cell size.
//! The fastest signal is s = max_p (c_p + |v_p|); Δt = C·L/s for a Courant number C, or a fixed Δt
//! whose Courant number Δt·s/L must stay ≤ 1.
//!
//! **Which density.** The signal that sets Δt is s_p = max(ŝ_p, (C/C_max)·s̃_p) with
//! s̃_p = c̃_p + |v_p| the particle's true signal (c̃_p = √(M/ρ_p), current density) and
//! ŝ_p = ĉ_p + |v_p| its capped signal (ĉ_p = √(M/max(ρ_p, ρ_ref)), ρ_ref the lightest initial
//! density of the particle's material). So a particle compacted above ρ_ref counts with its
//! current density; a dilated one with ρ_ref, but never so far that its own Courant number
//! Δt·s̃_p/L exceeds C_max = 1 ([`MAX_COURANT`](crate::MAX_COURANT)). Eq 13 with the current
//! density alone lets the loosest particle set Δt for everyone, and the loosest particles are
//! those that have separated from the mass: grains thrown off the free surface or the front,
//! whose volume grows by the FLIP strain increments of the few nodes they share with nothing,
//! carry no stress (a cohesionless material cannot hold the tension) and transmit no wave. Their √(V_p/V_0) made
//! the flume take 2.7× and a collapsing cohesionless column 3–5× the steps of the initial
//! estimate. The bound keeps what eq 13 is for: at C = 0.1 a grain must dilate a hundredfold
//! before it shortens Δt, at C = 0.8 by 1.56 (without the bound, a flume at C = 0.4 threw a
//! grain dilated sevenfold, true Courant number 1.06, out of the grid). A fixed Δt is checked
//! against the true signal.
//!
//! **How far a particle moves.** The wave speed bounds how far a signal travels in a step, not
//! how far the material does: a very soft or stress-free body (c ≈ 0) at rest would otherwise
//! take one huge step in which gravity alone carries it through the floor. So Δt is also bounded
//! by the displacement of the fastest particle under gravity, |v|_max Δt + ½ |g| Δt² ≤ C·L
//! ([`displacement_dt`]; the full |g|, also during a gravity ramp): no particle moves more than
//! the Courant number's fraction of a cell per step. On any stiff material (c ≫ |v|) this bound
//! is far above eq 13's and never binds, so it changes no result of such a scene. A fixed Δt must
//! keep that displacement within one cell ([`SolverError::StepTooLong`]).
//!
//! The signal needs every particle's final velocity and volume. Where a scheme's last particle loop
//! sees both (the stress update that ends USL, MUSL and USAVG), that loop computes it for the next
//! step with [`particle_signal`] and [`faster`], which saves a pass over the particles; otherwise
//! (USF, the first step, after `particles_mut`) [`Solver::fastest_signal`] does. Both give the
//! same bits.

use mpm_constitutive::ConstitutiveModel;
use mpm_grid::ShapeFunctions;

use crate::config::TimeStep;
use crate::error::{Field, SolverError};
use crate::math::Real;
use crate::par::{chunk_len, reduce_chunks};
use crate::signal::{Fastest, SLOWEST, StepLimit, particle_signal, stable_dt, wave_modulus};
use crate::solver::Solver;

impl<M: ConstitutiveModel, S: ShapeFunctions<N>, const N: usize> Solver<M, S, N> {
    /// the weight C/C_max of a particle's true signal against its capped one (module docs): 1
    /// for a fixed Δt, whose Courant number is the true one.
    pub(crate) fn true_signal_weight(&self) -> Real {
        match self.config.time_step {
            TimeStep::Courant(c) => c / crate::MAX_COURANT,
            TimeStep::Fixed(_) => 1.0,
        }
    }

    /// (Δt, Courant number) of the next step, with Δt ≤ `max_dt`.
    pub(crate) fn time_step(&mut self, max_dt: Real) -> Result<(Real, Real), SolverError> {
        let fastest = match self.next_signal.take() {
            Some(known) => known,
            None => self.fastest_signal(),
        };
        let (signal, particle) = fastest.signal;
        let speed = self.particles.velocity[particle.min(self.particles.len() - 1)].length();
        if !signal.is_finite() {
            // A NaN or infinite velocity or volume: name it before it spreads through the grid.
            let p = &self.particles;
            let field =
                if p.velocity[particle].is_finite() { Field::Volume } else { Field::Velocity };
            return Err(SolverError::NonFinite {
                step: self.step + 1,
                particle,
                position: p.position[particle],
                field,
            });
        }
        let l = self.cell_size;
        let (v_max, moving) = fastest.speed;
        match stable_dt(self.config.time_step, l, self.config.gravity.length(), signal, v_max) {
            Ok(dt) => {
                let dt = dt.min(max_dt);
                Ok((dt, dt * signal / l))
            }
            Err(StepLimit::Courant { courant, dt }) => Err(SolverError::CourantExceeded {
                step: self.step + 1,
                particle,
                courant,
                speed,
                dt,
            }),
            Err(StepLimit::Displacement { cells, dt }) => {
                let moving = moving.min(self.particles.len() - 1);
                Err(SolverError::StepTooLong {
                    step: self.step + 1,
                    particle: moving,
                    position: self.particles.position[moving],
                    cells,
                    dt,
                })
            }
        }
    }

    /// max_p (c_p + |v_p|) and max_p |v_p|, with their particles. Ties go to the lowest index, so
    /// the answer does not depend on the thread count; a non-finite signal counts as infinite so
    /// that the first such particle is the one reported.
    fn fastest_signal(&self) -> Fastest {
        let p = &self.particles;
        let n = p.len();
        let chunk = chunk_len(n);
        let weight = self.true_signal_weight();
        let chunk_best = |c: usize| {
            let mut best = SLOWEST;
            for i in c * chunk..((c + 1) * chunk).min(n) {
                let m = usize::from(p.material[i]);
                let (modulus, cap) = wave_modulus(
                    &self.materials[m],
                    &p.state[i],
                    self.p_modulus[m],
                    self.signal_cap[m],
                    self.reference_density[m],
                );
                let speed = p.velocity[i].length();
                let signal = particle_signal(modulus, cap, weight, p.volume[i], p.mass[i], speed);
                best = best.with(signal, speed, i);
            }
            best
        };
        reduce_chunks(n.div_ceil(chunk), SLOWEST, &chunk_best, Fastest::merge)
    }
}

#[cfg(test)]
mod tests {
    use glam::DMat3;
    use mpm_constitutive::LinearElastic;
    use mpm_constitutive::{ConstitutiveError, ConstitutiveModel, SymTensor, UpdateReport};
    use mpm_grid::testing::{LINEAR, at, grid, volume};
    use mpm_grid::{Bilinear, RegularGrid};

    use crate::particles::{NewParticle, Particles};
    use crate::{Scheme, Solver, SolverConfig, SolverError, TimeStep, Vector};

    /// Two particles at rest of one material (ρ₀ = 1000 kg/m³, E = 1 MPa) on 0.25 m cells.
    fn pair() -> Solver<LinearElastic, Bilinear<RegularGrid>, LINEAR> {
        let grid = grid([0.0; 2], [0.25; 2], [8, 8]).unwrap();
        let mut particles = Particles::default();
        for x in [0.6, 1.4] {
            let position = at(x, 1.0);
            particles.push(NewParticle::unstressed(
                position,
                Vector::ZERO,
                volume(0.125),
                1000.0,
                (),
            ));
        }
        let config = SolverConfig {
            gravity: Vector::ZERO,
            time_step: TimeStep::Courant(0.5),
            ..Default::default()
        };
        let material = LinearElastic::from_young_poisson(1e6, 0.3).unwrap();
        Solver::new(Bilinear(grid), vec![material], particles, config).unwrap()
    }

    /// Δt of eq 13 with c = √(M/ρ) and no speed: C·L/c.
    fn expected_dt(s: &Solver<LinearElastic, Bilinear<RegularGrid>, LINEAR>, density: f64) -> f64 {
        0.5 * 0.25 / (s.materials()[0].p_wave_modulus() / density).sqrt()
    }

    /// One rounding of a square root and a division.
    const DT_TOL: f64 = 1e-14;

    /// Elasticity whose P-wave modulus is (1 + n) M₀ after n updates: a model whose wave speed
    /// varies with the state.
    #[derive(Clone)]
    struct Stiffening(LinearElastic);

    impl ConstitutiveModel for Stiffening {
        type State = f64;
        const IS_PLASTIC: bool = false;
        const BRANCHES: &'static [&'static str] = &["elastic"];
        const WAVE_SPEED_VARIES: bool = true;
        fn initial_state(&self) -> f64 {
            0.0
        }
        fn p_wave_modulus(&self, updates: &f64) -> f64 {
            (1.0 + updates) * self.0.p_wave_modulus()
        }
        fn stored_energy_density(&self, sigma: &SymTensor, _state: &f64) -> f64 {
            self.0.strain_energy_density(sigma)
        }
        fn update(
            &self,
            sigma: &mut SymTensor,
            updates: &mut f64,
            d_eps: &SymTensor,
            dt: f64,
        ) -> Result<UpdateReport, ConstitutiveError> {
            let report = self.0.update(sigma, &mut (), d_eps, dt)?;
            *updates += 1.0;
            Ok(report)
        }
        fn rotate_state(&self, _state: &mut f64, _r: &DMat3) {}
        fn equivalent_plastic_strain(&self, _state: &f64) -> f64 {
            0.0
        }
    }

    /// The time step asks the model for its wave speed at each particle's current state: after
    /// one update the modulus doubles, so Δt shrinks by √2, both where the stress update computes
    /// the next signal (USL) and where a separate pass does (after `particles_mut`).
    #[test]
    fn the_time_step_follows_a_state_dependent_wave_speed() {
        let elastic = LinearElastic::from_young_poisson(1e6, 0.3).unwrap();
        let grid = grid([0.0; 2], [0.25; 2], [8, 8]).unwrap();
        let mut particles = Particles::default();
        for x in [0.6, 1.4] {
            let position = at(x, 1.0);
            let volume = volume(0.125);
            particles.push(NewParticle::unstressed(position, Vector::ZERO, volume, 1000.0, 0.0));
        }
        let config = SolverConfig {
            gravity: Vector::ZERO,
            time_step: TimeStep::Courant(0.5),
            scheme: Scheme::Usl,
            ..Default::default()
        };
        let mut s =
            Solver::new(Bilinear(grid), vec![Stiffening(elastic)], particles, config).unwrap();
        let dt0 = 0.5 * 0.25 / (elastic.p_wave_modulus() / 1000.0).sqrt();
        let first = s.step().unwrap();
        assert!((first.dt / dt0 - 1.0).abs() < DT_TOL);
        let second = s.step().unwrap();
        assert!((second.dt / (dt0 / 2f64.sqrt()) - 1.0).abs() < DT_TOL, "{}", second.dt / dt0);
        let _ = s.particles_mut();
        let (third, _) = s.time_step(f64::INFINITY).unwrap();
        assert!((third / (dt0 / 3f64.sqrt()) - 1.0).abs() < DT_TOL, "{}", third / dt0);
    }

    #[test]
    fn a_dilated_particle_does_not_shrink_the_time_step() {
        let mut s = pair();
        let dt0 = s.time_step(f64::INFINITY).unwrap().0;
        assert!((dt0 / expected_dt(&s, 1000.0) - 1.0).abs() < DT_TOL);
        // 3.5 times its volume (a grain thrown off the mass): the current density would give a
        // √3.5 shorter step; the reference density keeps it (its own Courant number,
        // 0.5·√3.5 = 0.94, stays below 1).
        s.particles_mut().volume[1] *= 3.5;
        let dt = s.time_step(f64::INFINITY).unwrap().0;
        assert_eq!(dt, dt0);
    }

    #[test]
    fn dilation_cannot_raise_a_particles_own_courant_number_above_one() {
        let mut s = pair();
        let dt0 = s.time_step(f64::INFINITY).unwrap().0;
        // C = 0.5: a particle dilated fourfold has a true Courant number of exactly 1 at the
        // initial Δt; dilated ninefold (true wave speed ×3) it must shorten Δt by 3/2.
        s.particles_mut().volume[1] *= 4.0;
        assert_eq!(s.time_step(f64::INFINITY).unwrap().0, dt0);
        s.particles_mut().volume[1] *= 9.0 / 4.0;
        let dt = s.time_step(f64::INFINITY).unwrap().0;
        assert!((dt / (dt0 / 1.5) - 1.0).abs() < DT_TOL, "{dt} vs {}", dt0 / 1.5);
        let c_true = (s.materials()[0].p_wave_modulus() * s.particles().volume[1]
            / s.particles().mass[1])
            .sqrt();
        assert!(dt * c_true / 0.25 <= crate::MAX_COURANT * (1.0 + DT_TOL));
    }

    #[test]
    fn a_compacted_particle_counts_with_its_current_density() {
        let mut s = pair();
        // Both compacted to 80 % of their volume: ρ = 1250 kg/m³ sets the (longer) step.
        for v in &mut s.particles_mut().volume {
            *v *= 0.8;
        }
        let dt = s.time_step(f64::INFINITY).unwrap().0;
        assert!((dt / expected_dt(&s, 1250.0) - 1.0).abs() < DT_TOL);
        // and speed still adds to the signal: 10 m/s on one particle.
        s.particles_mut().velocity[0] = at(10.0, 0.0);
        let c = (s.materials()[0].p_wave_modulus() / 1250.0).sqrt();
        let dt = s.time_step(f64::INFINITY).unwrap().0;
        assert!((dt / (0.5 * 0.25 / (c + 10.0)) - 1.0).abs() < DT_TOL);
    }

    #[test]
    fn a_stress_free_body_moves_at_most_the_courant_fraction_of_a_cell_per_step() {
        // E = 1 mPa: c = 1.2e-3 m/s, so eq 13 alone gives Δt ≈ 100 s, in which gravity would
        // carry the block 50 km through the floor. The displacement bound gives ½ g Δt² = C L.
        let mut s = pair();
        s.materials = vec![LinearElastic::from_young_poisson(1e-3, 0.3).unwrap()];
        s.p_modulus = vec![s.materials[0].p_wave_modulus()];
        s.signal_cap = vec![s.p_modulus[0] / 1000.0];
        s.config.gravity = at(0.0, -9.81);
        let (c, l, g): (f64, f64, f64) = (0.5, 0.25, 9.81);
        let dt = s.time_step(f64::INFINITY).unwrap().0;
        assert!((dt / (2.0 * c * l / g).sqrt() - 1.0).abs() < DT_TOL, "{dt}");
        // moving at 3 m/s: 3 Δt + ½ g Δt² = C L.
        s.particles_mut().velocity[1] = at(3.0, 0.0);
        let dt = s.time_step(f64::INFINITY).unwrap().0;
        assert!(((3.0 * dt + 0.5 * g * dt * dt) / (c * l) - 1.0).abs() < DT_TOL, "{dt}");
        // A fixed Δt that lets gravity carry a particle over a cell is refused, naming it:
        // 0.3 s at rest falls 0.44 m, 1.77 cells (its Courant number is 1.4e-3).
        s.particles_mut().velocity[1] = Vector::ZERO;
        s.particles_mut().velocity[0] = at(0.0, -1e-3);
        s.config.time_step = TimeStep::Fixed(0.3);
        let e = s.time_step(f64::INFINITY).unwrap_err();
        let expected = (1e-3 * 0.3 + 0.5 * g * 0.09) / l;
        assert!(
            matches!(e, SolverError::StepTooLong { particle: 0, cells, .. }
                if (cells - expected).abs() < 1e-12),
            "{e}"
        );
    }

    #[test]
    fn the_displacement_bound_leaves_a_stiff_body_alone() {
        // E = 1 MPa at rest under gravity: eq 13 (Δt = 3.4e-3 s) binds, not ½ g Δt² = C L
        // (Δt = 0.16 s), so stiff scenes keep their time steps bit for bit.
        let mut s = pair();
        s.config.gravity = at(0.0, -9.81);
        let dt = s.time_step(f64::INFINITY).unwrap().0;
        assert_eq!(dt, 0.5 * 0.25 / (s.materials()[0].p_wave_modulus() / 1000.0).sqrt());
    }

    #[test]
    fn a_resumed_run_keeps_the_reference_density_of_its_start() {
        let mut s = pair();
        let dt0 = s.time_step(f64::INFINITY).unwrap().0;
        // Every particle dilates, then the run is checkpointed and resumed: the reference stays
        // at the initial density instead of becoming the dilated one.
        for v in &mut s.particles_mut().volume {
            *v *= 4.0;
        }
        let c = s.checkpoint();
        assert_eq!(c.reference_density, vec![1000.0]);
        let (shape, materials, config) =
            (s.shape().clone(), s.materials().to_vec(), s.config().clone());
        let mut resumed = Solver::from_checkpoint(shape, materials, config, c).unwrap();
        assert_eq!(resumed.time_step(f64::INFINITY).unwrap().0, dt0);
    }
}
