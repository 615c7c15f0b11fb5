//! `[output]`: frame and series intervals, VTK fields, probes and the analytic reference curve.

use mpm_contact::{Friction, RigidSlide};
use mpm_solver::{Boundaries, Vector};

use super::{Ctx, finite_pos, num, pair, polyline};
use crate::error::SceneError;
use crate::file::{ObservedSpec, OutputSpec, ProbeSpec, ReferenceCurve, VtkField, VtkFormat};
use crate::ground::{ground_height, segment_at};
use crate::limits::MAX_PROBES;
use crate::observed::ObservedDeposit;
use crate::scene::{GridBuilt, Reference, ResolvedOutput, Seed};

/// The output plan of a run that ends at `end_time` (s).
pub(super) fn build(
    ctx: &Ctx<'_>,
    o: &OutputSpec,
    end_time: f64,
    seeds: &[Seed],
    (grid, ground): (&GridBuilt, &[Vector]),
    boundaries: &Boundaries,
    gravity: Vector,
) -> Result<ResolvedOutput, SceneError> {
    if o.hazard_maps == Some(true) {
        return Err(ctx.err(
            "output.hazard_maps",
            Some("true".into()),
            "hazard maps are drawn in plan, from a 3D run",
            "`hazard_maps` in a 3D scene; in 2D, `envelope = true`",
            "use `envelope = true` (per ground station along the section)",
        ));
    }
    if let Some(d) = o.runout_direction {
        return Err(ctx.err(
            "output.runout_direction",
            Some(format!("{d:?}")),
            "a 2D scene's runout is measured along its x axis",
            "`runout_direction` in a 3D scene only",
            "remove it (a 2D section runs along x)",
        ));
    }
    let c = cadence(ctx, o, end_time)?;
    let probes = probes(ctx, o, seeds.len(), 2, |at| {
        let at = Vector::new(at[0], at[1]);
        nearest(seeds.iter().map(|s| s.position.distance_squared(at)))
    })?;
    let reference = match o.reference {
        None => None,
        Some(curve) => Some(reference(ctx, curve, &probes, seeds, grid, boundaries, gravity)?),
    };
    Ok(ResolvedOutput {
        interval: c.interval,
        series_interval: c.series_interval,
        exact_times: c.exact_times,
        fields: c.fields,
        vtk: c.vtk,
        vtk_format: c.vtk_format,
        plots: c.plots,
        probes,
        reference,
        checkpoint_interval: c.checkpoint_interval,
        envelope: c.envelope,
        observed: match &o.observed {
            None => None,
            Some(spec) => Some(observed(ctx, spec, grid, ground)?),
        },
    })
}

/// What `[output]` means alike in both dimensions: when frames, series rows and checkpoints are
/// taken, which fields a frame holds, and whether plots and envelopes are drawn.
pub(super) struct Cadence {
    pub(super) interval: f64,
    pub(super) series_interval: f64,
    pub(super) checkpoint_interval: Option<f64>,
    pub(super) exact_times: bool,
    pub(super) fields: Vec<VtkField>,
    pub(super) vtk: bool,
    pub(super) vtk_format: VtkFormat,
    pub(super) plots: bool,
    pub(super) envelope: bool,
}

/// `[output]`'s intervals (at most 1e6 frames or checkpoints and 1e7 series rows over
/// `end_time`), its fields (each once) and its switches, for a scene of either dimension.
pub(super) fn cadence(ctx: &Ctx<'_>, o: &OutputSpec, end_time: f64) -> Result<Cadence, SceneError> {
    let interval = o.interval.unwrap_or(end_time / 50.0);
    if !(finite_pos(interval) && end_time / interval <= 1e6) {
        return Err(ctx.range(
            "output.interval",
            interval,
            "0 < interval, at most 1e6 frames over end_time (s)",
            "give the time between frames in seconds, e.g. end_time / 50",
        ));
    }
    let series_interval = o.series_interval.unwrap_or(interval.min(end_time / 200.0));
    if !(finite_pos(series_interval) && end_time / series_interval <= 1e7) {
        return Err(ctx.range(
            "output.series_interval",
            series_interval,
            "0 < series_interval, at most 1e7 rows over end_time (s)",
            "remove it to use the default min(interval, end_time / 200)",
        ));
    }
    if let Some(c) = o.checkpoint_interval {
        // (a bound like the frames': with `exact_times` every mark is also a step's end)
        if !(finite_pos(c) && end_time / c <= 1e6) {
            return Err(ctx.range(
                "output.checkpoint_interval",
                c,
                "0 < checkpoint_interval, at most 1e6 checkpoints over end_time (s of simulated \
                 time)",
                "give the simulated time between checkpoints, or remove it",
            ));
        }
    }
    if let Some(fields) = &o.fields {
        if let Some(k) = (1..fields.len()).find(|&k| fields[..k].contains(&fields[k])) {
            let name = toml::Value::try_from(fields[k]).map(|v| v.to_string()).unwrap_or_default();
            return Err(ctx.err(
                &format!("output.fields[{k}]"),
                Some(name),
                "the field is listed twice (each .vtp would hold two arrays of that name)",
                "each field at most once",
                "remove the repeated entry",
            ));
        }
    }
    Ok(Cadence {
        interval,
        series_interval,
        checkpoint_interval: o.checkpoint_interval,
        exact_times: o.exact_times.unwrap_or(false),
        fields: o.fields.clone().unwrap_or_else(|| VtkField::ALL.to_vec()),
        vtk: o.vtk.unwrap_or(true),
        vtk_format: o.vtk_format.unwrap_or_default(),
        plots: o.plots.unwrap_or(true),
        envelope: o.envelope.unwrap_or(false),
    })
}

/// The observed deposit of `[output] observed`: its CSV read and checked, a surface turned into
/// the thickness above `ground`.
fn observed(
    ctx: &Ctx<'_>,
    spec: &ObservedSpec,
    grid: &GridBuilt,
    ground: &[Vector],
) -> Result<ObservedDeposit, SceneError> {
    let field = "output.observed.deposit";
    let surface = std::cell::Cell::new(false);
    let columns = |cells: &[&str]| {
        let at = |n: &str| cells.iter().position(|c| c.eq_ignore_ascii_case(n));
        let x = at("x").ok_or("name the columns in the header: `x,thickness` or `x,surface`")?;
        match (at("thickness"), at("surface")) {
            (Some(h), None) => Ok((x, h)),
            (None, Some(z)) => {
                surface.set(true);
                Ok((x, z))
            }
            _ => Err("the header names one of `thickness` (vertical, m) or `surface` (m)".into()),
        }
    };
    let path = polyline::file_path(ctx, &spec.deposit);
    let (mut points, header) = polyline::read_pairs(ctx, field, &path, &columns)?;
    let name = path.display();
    let fail = |problem: String, fix: &str| ctx.err(field, None, problem, "", fix);
    if !header {
        return Err(fail(
            format!("{name}: no header line"),
            "begin the file with `x,thickness` (vertical thickness, m) or `x,surface` (the \
             deposit's top elevation, m)",
        ));
    }
    if let Some(w) = points.windows(2).find(|w| w[1][0] <= w[0][0]) {
        return Err(fail(
            format!("{name}: x does not increase at x = {} then {}", w[0][0], w[1][0]),
            "sort the points by x, one per x",
        ));
    }
    for p in &mut points {
        if surface.get() {
            p[1] -= ground_height(ground, p[0]);
        }
        // below the ground (a depletion zone in a DEM difference, a survey's noise): no deposit
        p[1] = p[1].max(0.0);
    }
    // a deposit no run on this grid can make (a thickness of 1e308 hung the deposit plot)
    let height = match grid {
        GridBuilt::Terrain(t) => t.rows() as f64 * t.row_height(),
        GridBuilt::Regular(g) => g.upper_corner().y - g.origin().y,
    };
    if let Some(p) = points.iter().find(|p| p[1] > height) {
        return Err(fail(
            format!(
                "{name}: the deposit is {} m thick at x = {}, more than the grid's height {} m",
                num(p[1]),
                num(p[0]),
                num(height)
            ),
            "give thicknesses in metres (a surface as `x,surface`), or raise the grid",
        ));
    }
    if points.iter().all(|p| p[1] <= 0.0) {
        return Err(fail(
            format!("{name}: no deposit (the thickness is zero everywhere)"),
            "give the deposit's thickness where it lies",
        ));
    }
    Ok(ObservedDeposit { file: spec.deposit.clone(), points })
}

/// The probed particles' indices in a scene of `count` particles and `dim` dimensions, a point's
/// nearest particle found by `nearest` (given the point's `dim` finite coordinates).
pub(super) fn probes(
    ctx: &Ctx<'_>,
    o: &OutputSpec,
    count: usize,
    dim: usize,
    nearest: impl Fn(&[f64]) -> usize,
) -> Result<Vec<usize>, SceneError> {
    if let Some(list) = o.probes.as_ref().filter(|l| l.len() > MAX_PROBES) {
        return Err(ctx.err(
            "output.probes",
            Some(format!("{} probes", list.len())),
            "too many probes",
            format!("at most {MAX_PROBES} probes (each writes a row per series interval)"),
            "probe a few particles; the particle frames hold every particle",
        ));
    }
    let point = if dim == 3 { "[x, y, z]" } else { "[x, y]" };
    let mut probes = Vec::new();
    for (k, probe) in o.probes.iter().flatten().enumerate() {
        let path = format!("output.probes[{k}]");
        match probe {
            &ProbeSpec::Index(i) => {
                if !(i >= 0 && (i as usize) < count) {
                    return Err(ctx.err(
                        &path,
                        Some(i.to_string()),
                        "no particle has this index",
                        format!("0 ≤ index < {count} (the scene's particle count)"),
                        format!("use a smaller index, or {{ nearest = {point} }}"),
                    ));
                }
                probes.push(i as usize);
            }
            ProbeSpec::Nearest(at) if at.len() != dim => {
                return Err(ctx.err(
                    &format!("{path}.nearest"),
                    Some(format!("{at:?}")),
                    format!("{} coordinates in a {dim}D scene", at.len()),
                    format!("the point {point} (m)"),
                    format!("give {dim} coordinates"),
                ));
            }
            ProbeSpec::Nearest(at) => {
                if !at.iter().all(|c| c.is_finite()) {
                    return Err(ctx.err(
                        &path,
                        Some(if dim == 3 { format!("{at:?}") } else { pair([at[0], at[1]]) }),
                        "the point is not finite",
                        "finite coordinates (m)",
                        "give a point inside a body",
                    ));
                }
                probes.push(nearest(at));
            }
        }
    }
    Ok(probes)
}

/// refuses probes in a run with outflow faces: a probe names a particle by its place in the
/// arrays, which changes when one leaves (2D and 3D alike).
pub(super) fn no_probes_beside_outflow(
    ctx: &Ctx<'_>,
    outflow: bool,
    probes: &[usize],
) -> Result<(), SceneError> {
    if outflow && !probes.is_empty() {
        return Err(ctx.err(
            "output.probes",
            None,
            "probes cannot follow particles beside outflow faces yet (a probe is a particle's \
             place in the run, which changes when particles leave)",
            "probes, or outflow faces",
            "remove the probes, or give the outflow faces a friction law",
        ));
    }
    Ok(())
}

/// the index of the least of `distances` (the first on a tie; 0 for none).
pub(super) fn nearest(distances: impl Iterator<Item = f64>) -> usize {
    distances.enumerate().min_by(|a, b| a.1.total_cmp(&b.1)).map_or(0, |(i, _)| i)
}

/// The rigid block (eqs 21–22) the first probe is compared with, its friction from the ground.
fn reference(
    ctx: &Ctx<'_>,
    curve: ReferenceCurve,
    probes: &[usize],
    seeds: &[Seed],
    grid: &GridBuilt,
    boundaries: &Boundaries,
    gravity: Vector,
) -> Result<Reference, SceneError> {
    let path = "output.reference";
    let value = Some(format!("\"{}\"", curve.name()));
    let Some(&probe) = probes.first() else {
        return Err(ctx.err(
            path,
            value,
            "a reference curve is compared with probe particles, but there are none",
            "at least one entry in output.probes",
            "add `probes = [0]` (or { nearest = [x, y] }) to [output]",
        ));
    };
    let mu = match boundaries.ground {
        Some(Friction::Coulomb { mu }) => mu,
        _ => {
            return Err(ctx.err(
                path,
                value,
                "the reference curve needs Coulomb friction on the ground",
                "boundaries.ground = { friction = μ }, { friction_angle_deg = φ } or \
                 \"frictionless\"",
                "declare the ground's friction in [boundaries]",
            ));
        }
    };
    let gravity = gravity.length();
    match curve {
        ReferenceCurve::Abe2005Eq21 => {
            // the block slides along ±x, whichever way the probe starts
            let vx = seeds[probe].velocity.x;
            Ok(Reference {
                curve,
                slide: RigidSlide { gravity, mu, slope_rad: 0.0, v0: vx.abs() },
                direction: if vx < 0.0 { -Vector::X } else { Vector::X },
            })
        }
        ReferenceCurve::Abe2005Eq22 => {
            let GridBuilt::Terrain(t) = grid else {
                return Err(ctx.err(
                    path,
                    value,
                    "eq 22 is a slide down an inclined ground, but the grid is regular",
                    "a terrain grid whose ground under the probe is inclined",
                    "use `kind = \"terrain\"` with a sloping profile, or abe2005_eq21",
                ));
            };
            let (a, b) = segment_at(t.profile(), seeds[probe].position.x);
            let d = (b - a).normalize_or_zero();
            let down = if d.y <= 0.0 { d } else { -d };
            Ok(Reference {
                curve,
                slide: RigidSlide { gravity, mu, slope_rad: (-down.y).asin(), v0: 0.0 },
                direction: down,
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::{embedded_scene, load_scene_str};

    /// Eq 21 is the mirror image for a block thrown towards −x: the same travel along −x (before
    /// this, a negative speed gave a negative stop time and a reference that never moved).
    #[test]
    fn eq21_follows_the_probe_whichever_way_it_starts() {
        let text = embedded_scene("sliding_horizontal").unwrap();
        let right = load_scene_str(text, "embedded:sliding_horizontal").unwrap();
        let left = right
            .modified(|f| {
                for b in &mut f.bodies {
                    b.velocity = b.velocity.map(|v| [-v[0], v[1]]);
                }
            })
            .unwrap();
        let r = right.resolved().output.reference.unwrap();
        let l = left.resolved().output.reference.unwrap();
        assert_eq!(l.direction, -r.direction);
        for t in [0.5, 2.0, 5.0] {
            assert_eq!(l.displacement(t), r.displacement(t));
        }
        // 10 m/s with μ = 0.3: 10·0.5 − ½·0.3·9.81·0.25 m after 0.5 s (1e-12: two roundings).
        let expected = 10.0 * 0.5 - 0.5 * 0.3 * 9.81 * 0.25;
        assert!((r.displacement(0.5) - expected).abs() < 1e-12, "{}", r.displacement(0.5));
    }
}
