//! `[initial_state]`: how a new run finds its initial stresses (stress-free, one implicit
//! solve, or an explicit gravity ramp), each method's fields checked against it.

use mpm_solver::GeostaticSettings;
use mpm_solver::geostatic;

use super::{Ctx, num};
use crate::error::SceneError;
use crate::file::{InitialStateMethod, InitialStateSpec};
use crate::scene::InitialState;

/// What of the rest of the scene `[initial_state]` is checked against.
pub(super) struct Around {
    /// `[solver] gravity_ramp` (s).
    pub gravity_ramp: f64,
    /// whether the scene has periodic sides.
    pub periodic: bool,
    /// the first step's Δt (s) and the most steps a run may take: a gravity ramp that would
    /// take more steps is refused, as a run would be.
    pub initial_dt: f64,
    pub max_steps: u64,
}

/// Checks `[initial_state]`.
pub(super) fn build(
    ctx: &Ctx<'_>,
    spec: Option<&InitialStateSpec>,
    around: &Around,
) -> Result<InitialState, SceneError> {
    let Around { gravity_ramp, periodic, initial_dt, max_steps } = *around;
    let Some(s) = spec else { return Ok(InitialState::None) };
    let implicit_fields = [
        ("load_steps", s.load_steps.is_some()),
        ("max_iterations", s.max_iterations.is_some()),
        ("tolerance", s.tolerance.is_some()),
    ];
    let ramp_fields =
        [("ramp_time", s.ramp_time.is_some()), ("settle_time", s.settle_time.is_some())];
    let foreign = |fields: &[(&str, bool)], why: &str| -> Result<(), SceneError> {
        match fields.iter().find(|f| f.1) {
            Some((name, _)) => Err(ctx.foreign(&format!("initial_state.{name}"), why)),
            None => Ok(()),
        }
    };
    if s.method != InitialStateMethod::None && gravity_ramp > 0.0 {
        return Err(ctx.err(
            "solver.gravity_ramp",
            Some(num(gravity_ramp)),
            "a gravity ramp during the run cannot follow an initial state already under gravity",
            "gravity_ramp = 0 with an `[initial_state]`",
            "remove `gravity_ramp`, or use `[initial_state] method = \"gravity_ramp\"`",
        ));
    }
    match s.method {
        InitialStateMethod::None => {
            foreign(&implicit_fields, "method = \"none\"")?;
            foreign(&ramp_fields, "method = \"none\"")?;
            Ok(InitialState::None)
        }
        InitialStateMethod::Implicit => {
            foreign(&ramp_fields, "they belong to method = \"gravity_ramp\"")?;
            if periodic {
                return Err(ctx.err(
                    "initial_state.method",
                    Some("\"implicit\"".into()),
                    "the implicit solve does not pair the columns of periodic sides",
                    "\"none\" or \"gravity_ramp\" with `[boundaries] periodic = true`",
                    "use method = \"gravity_ramp\"",
                ));
            }
            let d = GeostaticSettings::default();
            let count = |name: &str, v: Option<i64>, default: u32, most: i64, fix: &str| match v {
                None => Ok(default),
                Some(n) if (1..=most).contains(&n) => Ok(n as u32),
                Some(n) => Err(ctx.range(
                    &format!("initial_state.{name}"),
                    n as f64,
                    &format!("1 ≤ {name} ≤ {most}"),
                    fix,
                )),
            };
            let load_steps = count(
                "load_steps",
                s.load_steps,
                d.load_steps,
                i64::from(geostatic::MAX_LOAD_STEPS),
                "1 for an elastic material; 4–10 to follow a plastic loading path",
            )?;
            let max_iterations = count(
                "max_iterations",
                s.max_iterations,
                d.max_iterations,
                i64::from(geostatic::MAX_NEWTON_ITERATIONS),
                &format!("the default {} is plenty for a state that exists", d.max_iterations),
            )?;
            let tolerance = s.tolerance.unwrap_or(d.tolerance);
            let (low, high) = geostatic::TOLERANCE_RANGE;
            if !(tolerance > low && tolerance < high) {
                return Err(ctx.range(
                    "initial_state.tolerance",
                    tolerance,
                    &format!("{low:e} < tolerance < {high}"),
                    &format!(
                        "use the default {:e} (Newton reaches it in a few iterations)",
                        d.tolerance
                    ),
                ));
            }
            Ok(InitialState::Implicit(GeostaticSettings {
                load_steps,
                max_iterations,
                tolerance,
                ..d
            }))
        }
        InitialStateMethod::GravityRamp => {
            foreign(&implicit_fields, "they belong to method = \"implicit\"")?;
            let Some(ramp) = s.ramp_time else {
                return Err(ctx.missing(
                    "initial_state.ramp_time",
                    "the gravity ramp's duration",
                    "1.0",
                ));
            };
            if !(ramp.is_finite() && ramp > 0.0 && ramp <= 1e4) {
                return Err(ctx.range(
                    "initial_state.ramp_time",
                    ramp,
                    "0 < ramp_time ≤ 1e4 (s)",
                    "several periods of the body's slowest mode, e.g. 1.0",
                ));
            }
            let hold = s.settle_time.unwrap_or(0.0);
            if !(hold.is_finite() && (0.0..=1e4).contains(&hold)) {
                return Err(ctx.range(
                    "initial_state.settle_time",
                    hold,
                    "0 ≤ settle_time ≤ 1e4 (s)",
                    "e.g. half the ramp time",
                ));
            }
            let steps = (ramp + hold) / initial_dt;
            if steps > max_steps as f64 {
                return Err(ctx.err(
                    "initial_state.ramp_time",
                    Some(num(ramp)),
                    format!(
                        "the ramp and hold need about {steps:.3e} steps at the first Δt \
                         ({initial_dt:.3e} s), more than max_steps = {max_steps}"
                    ),
                    format!("(ramp_time + settle_time) / Δt ≤ max_steps = {max_steps}"),
                    "a shorter ramp, or method = \"implicit\" (one solve, no steps)",
                ));
            }
            Ok(InitialState::GravityRamp { ramp, hold })
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::scene::InitialState;
    use crate::scenes::embedded_scene;
    use crate::validate::load_scene_str;
    use crate::{Scene, SceneError};

    fn flume_with(section: &str) -> Result<Scene, SceneError> {
        let text = format!("{}\n[initial_state]\n{section}\n", embedded_scene("flume").unwrap());
        load_scene_str(&text, "t.toml")
    }

    /// Each method takes its own fields; another's, a missing ramp time or a count out of range
    /// is refused at its line, as is a run-time gravity ramp beside an initial state.
    #[test]
    fn each_method_takes_only_its_own_fields() {
        let s = flume_with("method = \"implicit\"\nload_steps = 4").unwrap();
        assert!(
            matches!(s.resolved().initial_state, InitialState::Implicit(g) if g.load_steps == 4)
        );
        let s = flume_with("method = \"gravity_ramp\"\nramp_time = 0.5").unwrap();
        assert_eq!(s.resolved().initial_state, InitialState::GravityRamp { ramp: 0.5, hold: 0.0 });
        for (section, path) in [
            ("method = \"implicit\"\nramp_time = 1.0", "initial_state.ramp_time"),
            ("method = \"gravity_ramp\"", "initial_state.ramp_time"),
            (
                "method = \"gravity_ramp\"\nramp_time = 1.0\ntolerance = 1e-8",
                "initial_state.tolerance",
            ),
            ("method = \"implicit\"\nload_steps = 0", "initial_state.load_steps"),
            ("method = \"implicit\"\ntolerance = 2.0", "initial_state.tolerance"),
        ] {
            let e = flume_with(section).unwrap_err();
            assert_eq!(e.path, path, "{section}: {e}");
            assert!(e.line.is_some(), "{e}");
        }
        let ramped = embedded_scene("flume")
            .unwrap()
            .replace("end_time = 3.0", "end_time = 3.0\ngravity_ramp = 0.2");
        let text = format!("{ramped}\n[initial_state]\nmethod = \"implicit\"\n");
        let e = load_scene_str(&text, "t.toml").unwrap_err();
        assert_eq!(e.path, "solver.gravity_ramp", "{e}");
        // a ramp longer than the run's step budget (the flume's Δt is about 2e-4 s)
        let budget = embedded_scene("flume")
            .unwrap()
            .replace("end_time = 3.0", "end_time = 3.0\nmax_steps = 20000");
        let text =
            format!("{budget}\n[initial_state]\nmethod = \"gravity_ramp\"\nramp_time = 10.0\n");
        let e = load_scene_str(&text, "t.toml").unwrap_err();
        assert_eq!(e.path, "initial_state.ramp_time", "{e}");
        assert!(e.problem.contains("max_steps"), "{e}");
    }
}
