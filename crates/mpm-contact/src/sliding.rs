//! The rigid-body reference of a Coulomb boundary: a block sliding on a plane (eqs 21–22).
//!
//! A rigid block on a plane inclined at θ (down-slope positive), with Coulomb friction μ under
//! gravity g, has the constant along-slope acceleration a = g (sin θ − μ cos θ). Started at the
//! down-slope speed v0 ≥ 0 it travels s(t) = v0 t + ½ a t² until its speed v0 + a t reaches 0
//! (when a < 0) and stays there: static friction then holds it, since μ cos θ > sin θ. Eq 21 is
//! the horizontal case (θ = 0, a = −μg: it stops after v0/(μg), having travelled v0²/(2μg)), eq 22
//! the slide from rest down a slope steeper than the friction angle (s = ½ a t²).
//!
//! ```
//! use mpm_contact::RigidSlide;
//!
//! // Eq 21: 10 m/s on the level with μ = 0.3 stops after 16.99 m.
//! let eq21 = RigidSlide { gravity: 9.81, mu: 0.3, slope_rad: 0.0, v0: 10.0 };
//! assert!((eq21.displacement(10.0) - 100.0 / (2.0 * 0.3 * 9.81)).abs() < 1e-12);
//! // Eq 22: from rest down 30° with μ = 0.3, a = g (sin 30° − 0.3 cos 30°) = 2.356 m/s².
//! let eq22 = RigidSlide { gravity: 9.81, mu: 0.3, slope_rad: 30f64.to_radians(), v0: 0.0 };
//! assert!((eq22.acceleration() - 2.3563).abs() < 1e-4);
//! ```

/// A rigid block sliding on a plane with Coulomb friction (module docs). SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidSlide {
    /// |g| (m/s²).
    pub gravity: f64,
    /// the Coulomb coefficient μ ≥ 0 of the plane.
    pub mu: f64,
    /// the plane's inclination θ (rad), positive: the block moves down-slope.
    pub slope_rad: f64,
    /// the initial down-slope speed (m/s), ≥ 0.
    pub v0: f64,
}

impl RigidSlide {
    /// a = g (sin θ − μ cos θ) (m/s²) while the block slides.
    pub fn acceleration(&self) -> f64 {
        self.gravity * (self.slope_rad.sin() - self.mu * self.slope_rad.cos())
    }

    /// the time the block stops (s): v0/|a| when friction decelerates it, 0 when it starts at
    /// rest and friction holds it, +∞ when it never stops.
    pub fn stop_time(&self) -> f64 {
        let a = self.acceleration();
        if a < 0.0 {
            self.v0 / -a
        } else if a == 0.0 && self.v0 == 0.0 {
            0.0
        } else {
            f64::INFINITY
        }
    }

    /// the down-slope distance travelled at time t ≥ 0 (m): eq 21 on the level, eq 22 from rest.
    pub fn displacement(&self, t: f64) -> f64 {
        let a = self.acceleration();
        if a <= 0.0 && self.v0 == 0.0 {
            return 0.0;
        }
        if a < 0.0 && t >= self.stop_time() {
            // stopped: v0²/(2|a|), which stays finite (zero) where friction so large that a
            // overflows made the sliding form ∞ × 0
            return self.v0 * self.v0 / (2.0 * -a);
        }
        self.v0 * t + 0.5 * a * t * t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: f64 = 9.81;

    /// eq 21 in closed form: the stop at v0/(μg) after v0²/(2μg), then no further travel.
    #[test]
    fn eq21_stops_at_the_closed_form_distance() {
        let s = RigidSlide { gravity: G, mu: 0.3, slope_rad: 0.0, v0: 10.0 };
        let t_stop = 10.0 / (0.3 * G);
        assert_eq!(s.stop_time(), t_stop);
        let d = 100.0 / (2.0 * 0.3 * G);
        // 1e-12 relative: the two forms differ by a few roundings.
        assert!((s.displacement(t_stop) - d).abs() < 1e-12 * d);
        assert_eq!(s.displacement(2.0 * t_stop), s.displacement(t_stop));
        // friction so large that a overflows (μ = 1e308): stopped at once, after no travel.
        let stuck = RigidSlide { mu: 1e308, ..s };
        assert_eq!(stuck.displacement(0.0), 0.0);
        assert_eq!(stuck.displacement(1.0), 0.0);
        // frictionless: uniform motion for ever.
        let free = RigidSlide { mu: 0.0, ..s };
        assert_eq!(free.stop_time(), f64::INFINITY);
        assert_eq!(free.displacement(3.0), 30.0);
    }

    /// eq 22: ½ a t² down a slope steeper than the friction angle; at rest on a gentler one.
    #[test]
    fn eq22_accelerates_only_above_the_friction_angle() {
        let theta = 30f64.to_radians();
        let s = RigidSlide { gravity: G, mu: 0.3, slope_rad: theta, v0: 0.0 };
        let a = G * (theta.sin() - 0.3 * theta.cos());
        assert_eq!(s.displacement(2.0), 0.5 * a * 4.0);
        let held = RigidSlide { mu: 1.0, ..s };
        assert_eq!(held.stop_time(), 0.0);
        assert_eq!(held.displacement(5.0), 0.0);
        // thrown down a slope that holds it: decelerates at |a| and stops after v0²/(2|a|).
        let thrown = RigidSlide { v0: 2.0, ..held };
        let a = -held.acceleration();
        assert!((thrown.displacement(100.0) - 4.0 / (2.0 * a)).abs() < 1e-12);
    }
}
