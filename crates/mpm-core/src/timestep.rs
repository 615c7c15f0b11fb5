//! The time-step rule (eq 13): the stable Δt from the fastest signal and speed, for a Courant
//! number or a fixed Δt, and the displacement bound. The solver calls it before every step and a
//! front end for the first one, so that both apply one rule.

use crate::settings::{MAX_COURANT, Real, TimeStep};

/// The largest Δt for which a particle at speed `v` under gravity `g` moves at most `d`:
/// the root of v Δt + ½ g Δt² = d (+∞ when nothing moves). The time step's second bound
/// (no particle moves more than C·L in a step: the solver's time-step stage explains why),
/// exported so that a front end can predict the first Δt.
pub fn displacement_dt(d: Real, v: Real, g: Real) -> Real {
    // 2d / (v + √(v² + 2gd)): the rationalised root, exact also for g = 0 (d/v).
    2.0 * d / (v + (v * v + 2.0 * g * d).sqrt())
}

/// Why a fixed Δt cannot run (a Courant Δt always can).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepLimit {
    /// the fixed Δt gives the fastest signal a Courant number above 1 (eq 13).
    Courant {
        /// Δt·s/L.
        courant: Real,
        /// the fixed Δt (s).
        dt: Real,
    },
    /// gravity and the fastest speed carry a particle more than one cell in the fixed Δt.
    Displacement {
        /// (|v|_max Δt + ½ |g| Δt²) / L.
        cells: Real,
        /// the fixed Δt (s).
        dt: Real,
    },
}

/// The Δt of a step (eq 13 and the displacement bound, module docs) from the fastest signal
/// `signal` = max_p s_p (m/s) and the fastest speed `v_max` (m/s), with `cell` the smallest cell
/// size L (m) and `gravity` = |g| (m/s²): C·L/s bounded by [`displacement_dt`] for a Courant
/// number C, or the fixed Δt after checking it. The solver calls it before every step and a
/// front end for the first one, so both apply one rule (a front end computing c = √(M/ρ) from
/// the initial density may differ from the solver's M·V/m in the last bit).
pub fn stable_dt(
    time_step: TimeStep,
    cell: Real,
    gravity: Real,
    signal: Real,
    v_max: Real,
) -> Result<Real, StepLimit> {
    match time_step {
        TimeStep::Courant(c) => {
            Ok((c * cell / signal).min(displacement_dt(c * cell, v_max, gravity)))
        }
        TimeStep::Fixed(dt) => {
            let courant = dt * signal / cell;
            if courant > MAX_COURANT {
                return Err(StepLimit::Courant { courant, dt });
            }
            let cells = (v_max * dt + 0.5 * gravity * dt * dt) / cell;
            if cells > MAX_COURANT {
                return Err(StepLimit::Displacement { cells, dt });
            }
            Ok(dt)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // The displacement bound is the root of v Δt + ½ g Δt² = d: put back into the equation it
    // gives d to rounding (a few ulps of the terms).
    #[test]
    fn displacement_dt_is_the_root_of_the_motion() {
        for (d, v, g) in [(0.1, 0.0, 9.81), (0.1, 3.0, 9.81), (0.02, 40.0, 0.0), (1.0, 0.5, 1.0)] {
            let dt = displacement_dt(d, v, g);
            let moved = v * dt + 0.5 * g * dt * dt;
            assert!((moved - d).abs() <= 1e-14 * d, "d {d} v {v} g {g}: moved {moved}");
        }
        assert_eq!(displacement_dt(0.1, 0.0, 0.0), Real::INFINITY);
    }

    // A Courant Δt is C L / s unless the displacement bound is shorter; a fixed Δt above the
    // bound is refused with its Courant number, one at it runs.
    #[test]
    fn stable_dt_applies_eq_13() {
        let dt = stable_dt(TimeStep::Courant(0.5), 0.1, 0.0, 100.0, 0.0).unwrap();
        assert_eq!(dt, 0.5 * 0.1 / 100.0);
        let slow_signal = stable_dt(TimeStep::Courant(1.0), 0.1, 0.0, 1e-3, 10.0).unwrap();
        assert!((slow_signal - 0.01).abs() < 1e-15, "{slow_signal}: the 10 m/s particle's cell");
        assert_eq!(stable_dt(TimeStep::Fixed(1e-3), 0.1, 0.0, 100.0, 0.0), Ok(1e-3));
        assert_eq!(
            stable_dt(TimeStep::Fixed(2e-3), 0.1, 0.0, 100.0, 0.0),
            Err(StepLimit::Courant { courant: 2e-3 * 100.0 / 0.1, dt: 2e-3 })
        );
        let Err(StepLimit::Displacement { cells, .. }) =
            stable_dt(TimeStep::Fixed(0.2), 0.1, 9.81, 0.1, 0.0)
        else {
            panic!("a 0.2 s step under gravity moves 2 cells");
        };
        assert!((cells - 0.5 * 9.81 * 0.04 / 0.1).abs() < 1e-12);
    }

    // The bounds of the one range check: C = 1 is admissible, anything above, zero, negative or
    // not a number is not; a fixed Δt must be positive and finite.
    #[test]
    fn time_step_ranges() {
        use crate::settings::BadTimeStep;
        assert_eq!(TimeStep::Courant(MAX_COURANT).checked(), Ok(TimeStep::Courant(1.0)));
        for c in [1.0 + 1e-15, 0.0, -0.1, Real::NAN] {
            assert!(matches!(TimeStep::Courant(c).checked(), Err(BadTimeStep::Courant(_))), "{c}");
        }
        for dt in [0.0, -1e-3, Real::INFINITY, Real::NAN] {
            assert!(matches!(TimeStep::Fixed(dt).checked(), Err(BadTimeStep::Dt(_))), "{dt}");
        }
        assert_eq!(TimeStep::Fixed(1e-9).checked(), Ok(TimeStep::Fixed(1e-9)));
    }
}
