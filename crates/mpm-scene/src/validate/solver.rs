//! `[solver]`: scheme, time step, gravity, thresholds, and the first Δt (eq 13).

use mpm_contact::Wall;
use mpm_solver::{
    BadTimeStep, Boundaries, Contact, MassMatrix, Periodic, PicWeighting, Scheme, SolverConfig,
    SolverError, StepLimit, TimeStep, Transfer, Vector, stable_dt,
};
use mpm_solver::{DEFAULT_COURANT, DEFAULT_SMALL_MASS_RATIO, MAX_COURANT};

use super::{Ctx, finite_pos, num, pair};
use crate::error::SceneError;
use crate::file::SolverSpec;
use crate::presets::{self, PresetSettings};
use crate::scene::{
    DEFAULT_ENERGY_ALARM, DEFAULT_MAX_STEPS, EnergyAlarm, GridBuilt, MaterialsBuilt, Seed,
    StopAtRest,
};

/// The `[solver]` settings, checked, with the preset's and the defaults filled in.
pub(super) struct Settings {
    pub preset: Option<PresetSettings>,
    pub scheme: Scheme,
    pub time_step: TimeStep,
    /// (gx, gy, gz) in m/s²; gz is 0 in a 2D scene.
    pub gravity: [f64; 3],
    pub gravity_ramp: f64,
    pub small_mass_ratio: f64,
    pub alarm: EnergyAlarm,
    pub max_steps: u64,
    pub stop_at_rest: Option<StopAtRest>,
}

/// Checks `[solver]` except what needs the grid, materials and bodies (the first Δt), for a
/// scene of `dim` dimensions (2 or 3: gravity's components).
pub(super) fn settings(ctx: &Ctx<'_>, s: &SolverSpec, dim: usize) -> Result<Settings, SceneError> {
    if !(finite_pos(s.end_time) && s.end_time <= 1e7) {
        return Err(ctx.range(
            "solver.end_time",
            s.end_time,
            "0 < end_time ≤ 1e7 (s)",
            "give the simulated duration in seconds, e.g. `end_time = 3.0`",
        ));
    }
    let preset = s.preset.map(presets::settings);
    let scheme = s.scheme.or(preset.map(|p| p.scheme)).unwrap_or(Scheme::Usavg);
    let time_step = match (s.courant, s.dt) {
        (Some(_), Some(_)) => {
            return Err(ctx.err(
                "solver.dt",
                s.dt.map(num),
                "both `courant` and `dt` are given",
                "one of them: a Courant number (adaptive Δt) or a fixed Δt",
                "remove `dt` (recommended) or `courant`",
            ));
        }
        (Some(c), None) => TimeStep::Courant(c),
        (None, Some(dt)) => TimeStep::Fixed(dt),
        (None, None) => TimeStep::Courant(preset.map_or(DEFAULT_COURANT, |p| p.courant)),
    };
    let time_step = time_step.checked().map_err(|bad| match bad {
        BadTimeStep::Courant(c) => ctx.range(
            "solver.courant",
            c,
            &format!("0 < courant ≤ {MAX_COURANT} (explicit stability, eq 13)"),
            &format!(
                "use the paper's advice `courant = {DEFAULT_COURANT}`; above {MAX_COURANT} the \
                 explicit step is unstable"
            ),
        ),
        BadTimeStep::Dt(dt) => ctx.range(
            "solver.dt",
            dt,
            &format!("0 < dt < ∞ (s), with a Courant number ≤ {MAX_COURANT}"),
            &format!("give a positive time step, or use `courant = {DEFAULT_COURANT}` instead"),
        ),
    })?;
    let gravity = gravity(ctx, s, dim)?;
    let gravity_ramp = s.gravity_ramp.unwrap_or(0.0);
    if !(gravity_ramp.is_finite() && gravity_ramp >= 0.0) {
        return Err(ctx.range(
            "solver.gravity_ramp",
            gravity_ramp,
            "0 ≤ gravity_ramp < ∞ (s); 0 applies gravity at once",
            "remove it or give a non-negative time",
        ));
    }
    let small_mass_ratio = s.small_mass_ratio.unwrap_or(DEFAULT_SMALL_MASS_RATIO);
    if !(0.0..1.0).contains(&small_mass_ratio) {
        return Err(ctx.range(
            "solver.small_mass_ratio",
            small_mass_ratio,
            "0 ≤ small_mass_ratio < 1 (fraction of the mean particle mass)",
            "remove it to use the default 1e-4",
        ));
    }

    let alarm = EnergyAlarm {
        threshold: s.energy_alarm.unwrap_or(DEFAULT_ENERGY_ALARM),
        stop: s.energy_alarm_stop.unwrap_or(false),
    };
    if !(finite_pos(alarm.threshold)) {
        return Err(ctx.range(
            "solver.energy_alarm",
            alarm.threshold,
            "0 < energy_alarm < ∞ (fraction of the run's energy scale)",
            "remove it to use the default 0.2, or give e.g. `energy_alarm = 0.1`",
        ));
    }
    let max_steps = s.max_steps.unwrap_or(DEFAULT_MAX_STEPS as i64);
    if max_steps < 1 {
        return Err(ctx.range(
            "solver.max_steps",
            max_steps as f64,
            "max_steps ≥ 1",
            "remove it to use the default 100 000 000",
        ));
    }
    let max_steps = max_steps as u64;
    let stop_at_rest = match s.stop_at_rest {
        None => None,
        Some(spec) => {
            let rest = StopAtRest {
                kinetic_fraction: spec.kinetic_fraction.unwrap_or(1e-6),
                duration: spec.duration.unwrap_or(1.0),
            };
            if !(rest.kinetic_fraction > 0.0 && rest.kinetic_fraction < 1.0) {
                return Err(ctx.range(
                    "solver.stop_at_rest.kinetic_fraction",
                    rest.kinetic_fraction,
                    "0 < kinetic_fraction < 1 (of the run's peak kinetic energy)",
                    "remove it to use the default 1e-6",
                ));
            }
            if !(finite_pos(rest.duration)) {
                return Err(ctx.range(
                    "solver.stop_at_rest.duration",
                    rest.duration,
                    "0 < duration < ∞ (s)",
                    "remove it to use the default 1 s, or give e.g. `duration = 0.5`",
                ));
            }
            Some(rest)
        }
    };
    Ok(Settings {
        preset,
        scheme,
        time_step,
        gravity,
        gravity_ramp,
        small_mass_ratio,
        alarm,
        max_steps,
        stop_at_rest,
    })
}

/// `solver.gravity` of a scene of `dim` dimensions: `dim` finite components, (0, −g, 0) by
/// default.
fn gravity(ctx: &Ctx<'_>, s: &SolverSpec, dim: usize) -> Result<[f64; 3], SceneError> {
    let space = dim == 3;
    match s.gravity.as_deref() {
        None => Ok([0.0, -mpm_solver::STANDARD_GRAVITY, 0.0]),
        Some(g) if g.len() == dim && g.iter().all(|c| c.is_finite()) => {
            Ok([g[0], g[1], if space { g[2] } else { 0.0 }])
        }
        Some(g) if g.len() == dim => Err(ctx.err(
            "solver.gravity",
            Some(if space { format!("{g:?}") } else { pair([g[0], g[1]]) }),
            "gravity is not finite",
            if space { "[gx, gy, gz], finite (m/s²)" } else { "finite components (m/s²)" },
            if space {
                "use `gravity = [0.0, -9.81, 0.0]`"
            } else {
                "use `gravity = [0.0, -9.81]`"
            },
        )),
        Some(g) if space => Err(ctx.err(
            "solver.gravity",
            Some(format!("{g:?}")),
            "a 3D scene's gravity has 3 components",
            "[gx, gy, gz], finite (m/s²)",
            "use `gravity = [0.0, -9.81, 0.0]`",
        )),
        Some(g) => Err(ctx.err(
            "solver.gravity",
            Some(format!("{g:?}")),
            format!("{} components in a 2D scene", g.len()),
            "[gx, gy] (m/s²) in 2D; [gx, gy, gz] with `dimension = 3` in [grid]",
            "give two components, or add `dimension = 3` to [grid] for a 3D scene",
        )),
    }
}

/// The 2D solver configuration of a scene: its settings, boundaries and [`choices`].
pub(super) fn config(
    ctx: &Ctx<'_>,
    s: &SolverSpec,
    settings: &Settings,
    (boundaries, periodic, walls, side_walls, outflow): (
        Boundaries,
        Option<Periodic>,
        Vec<Wall>,
        Option<mpm_solver::SideWalls>,
        mpm_solver::Outflow,
    ),
    materials: &MaterialsBuilt,
) -> Result<SolverConfig, SceneError> {
    let c = choices(ctx, s, materials)?;
    let config = SolverConfig {
        scheme: settings.scheme,
        time_step: settings.time_step,
        gravity: Vector::new(settings.gravity[0], settings.gravity[1]),
        boundaries,
        periodic,
        outflow,
        walls,
        side_walls,
        small_mass_ratio: settings.small_mass_ratio,
        objective_stress: c.objective_stress,
        gravity_ramp: settings.gravity_ramp,
        transfer: c.transfer,
        pic_fraction: c.pic_fraction,
        pic_relaxation: c.pic_relaxation,
        pic_weighting: c.pic_weighting,
        separation_density: c.separation_density,
        contact: c.contact,
        mass: c.mass,
    };
    config.validate().map_err(|e| solver_error(ctx, e))?;
    Ok(config)
}

/// What a scene chooses of the solver's settings that do not depend on dimension, where it is
/// silent its materials' defaults ([`choices`]).
pub(super) struct Choices {
    pub transfer: Transfer,
    pub pic_fraction: f64,
    pub pic_relaxation: f64,
    pub pic_weighting: PicWeighting,
    pub separation_density: f64,
    pub objective_stress: bool,
    pub contact: Contact,
    pub mass: MassMatrix,
}

/// The transfer, its PIC share, the separation density, the stress rate, the contact rule and
/// the mass matrix of a scene (2D or 3D); where it is silent, its materials' model decides
/// whether the stress rate is objective and, under FLIP, the PIC share and the separation
/// density.
pub(super) fn choices(
    ctx: &Ctx<'_>,
    s: &SolverSpec,
    materials: &MaterialsBuilt,
) -> Result<Choices, SceneError> {
    let transfer = s.transfer.unwrap_or_default();
    // Under APIC neither default applies: APIC damps the grid-invisible noise itself, and a
    // stress-free grain keeps its affine stretching for ever, so separated grains would expand
    // without bound (a = 1 column collapse: thrown to 1.5 × the column's height, measured).
    let flip = transfer == Transfer::Flip;
    let (pic_fraction, pic_relaxation, pic_weighting) = pic_share(ctx, s, flip, materials)?;
    let separation_default = if flip { materials.separation_density() } else { 0.0 };
    Ok(Choices {
        transfer,
        pic_fraction,
        pic_relaxation,
        pic_weighting,
        separation_density: s.separation_density.unwrap_or(separation_default),
        objective_stress: s.objective_stress.unwrap_or_else(|| materials.objective_stress()),
        contact: s.contact.unwrap_or_default(),
        mass: s.mass.unwrap_or_default(),
    })
}

/// The PIC share of a scene's transfer as (per step, relaxation time τ in s, weighting), one of
/// the first two 0: what the scene gives (one key at most), else under FLIP for granular
/// materials [`crate::GRANULAR_PIC_FRACTION`] per step, else none; uniform unless the scene
/// weights it by noise (not under APIC, which has no share).
fn pic_share(
    ctx: &Ctx<'_>,
    s: &SolverSpec,
    flip: bool,
    materials: &MaterialsBuilt,
) -> Result<(f64, f64, PicWeighting), SceneError> {
    let weighting = match s.pic_weighting {
        Some(w @ PicWeighting::Noise) if !flip => {
            return Err(ctx.err(
                "solver.pic_weighting",
                Some(format!("\"{}\"", w.name())),
                "cannot go with `transfer = \"apic\"`",
                "a weighting of the FLIP update's PIC share; APIC has no such share",
                "remove `pic_weighting`, or use `transfer = \"flip\"`",
            ));
        }
        Some(w) => w,
        None => PicWeighting::Uniform,
    };
    match (s.pic_fraction, s.pic_relaxation) {
        (Some(_), Some(_)) => Err(ctx.err(
            "solver.pic_relaxation",
            None,
            "cannot go with `pic_fraction`",
            "the PIC share is given either per step or as a relaxation time, not both",
            "remove one of `pic_fraction` and `pic_relaxation`",
        )),
        (Some(beta), None) => Ok((beta, 0.0, weighting)),
        (None, Some(tau)) => Ok((0.0, tau, weighting)),
        (None, None) => Ok((if flip { materials.pic_fraction() } else { 0.0 }, 0.0, weighting)),
    }
}

/// the smallest cell size of a 2D grid (m).
fn min_cell(grid: &GridBuilt) -> f64 {
    match grid {
        GridBuilt::Terrain(t) => t.min_cell_size(),
        GridBuilt::Regular(r) => r.min_cell_size(),
    }
}

/// The Δt of the first step, by the solver's own rule ([`mpm_solver::stable_dt`]) applied to the
/// seeds, and the refusal of a scene that cannot finish within `max_steps`.
pub(super) fn first_dt(
    ctx: &Ctx<'_>,
    s: &SolverSpec,
    config: &SolverConfig,
    grid: &GridBuilt,
    materials: &MaterialsBuilt,
    seeds: &[Seed],
    max_steps: u64,
) -> Result<f64, SceneError> {
    let min_cell = min_cell(grid);
    let p_modulus = materials.p_wave_moduli();
    let (signal, fastest) = seeds.iter().enumerate().fold((0.0f64, 0usize), |acc, (i, s)| {
        let c = (p_modulus[usize::from(s.material)] / s.density).sqrt() + s.velocity.length();
        if c > acc.0 { (c, i) } else { acc }
    });
    let v_max = seeds.iter().map(|s| s.velocity.length()).fold(0.0, f64::max);
    let g_abs = config.gravity.length();
    let initial_dt = match stable_dt(config.time_step, min_cell, g_abs, signal, v_max) {
        Ok(dt) => dt,
        Err(StepLimit::Courant { courant, dt }) => {
            return Err(ctx.err(
                "solver.dt",
                Some(num(dt)),
                format!(
                    "the fixed time step gives a Courant number {courant:.3} > {MAX_COURANT} at t = 0 \
                     (particle {fastest}: wave speed + speed {} m/s, smallest cell {} m)",
                    num(signal),
                    num(min_cell)
                ),
                format!(
                    "dt ≤ {} s (Courant number ≤ {MAX_COURANT}, eq 13)",
                    num(MAX_COURANT * min_cell / signal)
                ),
                format!(
                    "use `dt = {}` (Courant {DEFAULT_COURANT}) or replace `dt` by \
                     `courant = {DEFAULT_COURANT}`",
                    num(DEFAULT_COURANT * min_cell / signal)
                ),
            ));
        }
        Err(StepLimit::Displacement { cells, dt }) => {
            let most = mpm_solver::displacement_dt(min_cell, v_max, g_abs);
            return Err(ctx.err(
                "solver.dt",
                Some(num(dt)),
                format!(
                    "with the fixed time step, gravity and the initial speed carry a particle \
                     {cells:.3} cells in the first step (smallest cell {} m)",
                    num(min_cell)
                ),
                format!("dt ≤ {} s (at most one cell per step)", num(most)),
                format!(
                    "use `courant = {DEFAULT_COURANT}` instead of `dt` (Δt then follows the \
                     material)"
                ),
            ));
        }
    };
    let steps = (s.end_time / initial_dt).ceil();
    if steps.is_nan() || steps > max_steps as f64 {
        let shown = if steps < 1e15 { format!("{steps:.0}") } else { format!("{steps:.3e}") };
        let (path, value) = match (s.dt, s.courant) {
            (Some(dt), _) => ("solver.dt", dt),
            (None, Some(c)) => ("solver.courant", c),
            (None, None) => ("solver.end_time", s.end_time),
        };
        return Err(ctx.err(
            path,
            Some(num(value)),
            format!(
                "the run would take {shown} steps or more (initial Δt {} s to end_time {} s), \
                 above max_steps = {max_steps}; the fastest signal is {} m/s at particle \
                 {fastest} (wave speed √(M/ρ) of its material plus its speed)",
                num(initial_dt),
                num(s.end_time),
                num(signal)
            ),
            format!("end_time / Δt ≤ max_steps = {max_steps}"),
            "check the material's density and stiffness and the Courant number or dt (they set \
             Δt, eq 13), shorten end_time, or raise `[solver] max_steps`",
        ));
    }
    Ok(initial_dt)
}

fn solver_error(ctx: &Ctx<'_>, e: SolverError) -> SceneError {
    match e {
        SolverError::InvalidSetting { name, value, expected } => ctx.range(
            &format!("solver.{name}"),
            value,
            expected,
            "see docs/scene-format.md for the admissible range",
        ),
        SolverError::Incompatible { setting, with, reason } => ctx.err(
            &format!("solver.{setting}"),
            None,
            format!("cannot go with `{with}`"),
            reason,
            format!("remove `{setting}` (its default) or change `{with}`"),
        ),
        other => ctx.err("solver", None, other.to_string(), String::new(), String::new()),
    }
}

#[cfg(test)]
mod tests {
    use crate::scenes::embedded_scene;
    use crate::validate::load_scene_str;

    /// A granular scene's PIC share is 0.001 per step, the same for every particle, unless the
    /// scene gives a share per step, a relaxation time (both at once are refused: `malformed/`)
    /// or a weighting of its own; under APIC there is none, and a weighting is refused; an
    /// elastic scene has none.
    #[test]
    fn granular_scenes_take_the_pic_share_they_give_or_the_default() {
        use mpm_solver::PicWeighting::{Noise, Uniform};
        let flume = load_scene_str(embedded_scene("flume").unwrap(), "flume").unwrap();
        let c = &flume.resolved().config;
        assert_eq!(
            (c.pic_fraction, c.pic_relaxation, c.pic_weighting),
            (crate::GRANULAR_PIC_FRACTION, 0.0, Uniform)
        );
        let timed = flume.modified(|f| f.solver.pic_relaxation = Some(0.2)).unwrap();
        let c = &timed.resolved().config;
        assert_eq!((c.pic_fraction, c.pic_relaxation, c.pic_weighting), (0.0, 0.2, Uniform));
        let noise = flume.modified(|f| f.solver.pic_weighting = Some(Noise)).unwrap();
        let c = &noise.resolved().config;
        assert_eq!((c.pic_fraction, c.pic_weighting), (crate::GRANULAR_PIC_FRACTION, Noise));
        let apic =
            flume.modified(|f| f.solver.transfer = Some(mpm_solver::Transfer::Apic)).unwrap();
        let c = &apic.resolved().config;
        assert_eq!((c.pic_fraction, c.pic_relaxation, c.pic_weighting), (0.0, 0.0, Uniform));
        let e = apic.modified(|f| f.solver.pic_weighting = Some(Noise)).unwrap_err().to_string();
        assert!(e.contains("`solver.pic_weighting`") && e.contains("apic"), "{e}");
        let elastic = load_scene_str(embedded_scene("free_fall").unwrap(), "free_fall").unwrap();
        let c = &elastic.resolved().config;
        assert_eq!((c.pic_fraction, c.pic_weighting), (0.0, Uniform));
    }
}
