//! Plausibility warnings: values inside their admissible ranges that are most likely a unit or
//! convention mistake (a friction angle written as a coefficient, a density in g/cm³). A
//! warning never stops a run: `mpm check` and `mpm run` print it and `summary.json` lists it. A
//! scene that means the value silences the warning by name: `silence = ["NAME", ...]` at the
//! top of the file.

use std::collections::BTreeMap;

use super::{Ctx, num};
use crate::error::SceneError;
use crate::file::{BoundarySpec, GridKind, MaterialSpec, SceneFile, SpaceFile};
use crate::scene::Warning;

/// The warnings, by name, with what each one flags.
pub const WARNINGS: &[(&str, &str)] = &[
    ("friction_as_degrees", "a boundary `friction` (the coefficient μ) above 2"),
    ("friction_angle_as_radians", "a friction angle between 0 and 2°"),
    ("density_in_g_cm3", "a material density below 10 kg/m³"),
    ("young_below_1kpa", "a Young's modulus below 1 kPa"),
    ("no_floor", "a regular grid under gravity with no ground and no wall"),
    (
        "plane_strain_cone_in_3d",
        "a Drucker-Prager material of a 3D scene without `cone_match` (the default is the \
         plane-strain match)",
    ),
];

/// A boundary coefficient above this is a friction angle in degrees by mistake (μ = 2 is a
/// 63° angle; the steepest rock joints are below μ = 1.5).
const MOST_MU: f64 = 2.0;
/// A friction angle below this (degrees) is an angle in radians or a coefficient by mistake
/// (the lowest lubricated interfaces are a few degrees).
const LEAST_ANGLE_DEG: f64 = 2.0;
/// The lightest plausible soil (kg/m³): dry peat is about 100, pumice 250.
const LEAST_DENSITY: f64 = 10.0;
/// The softest plausible Young's modulus (Pa): a soft clay slurry is about 100 kPa.
const LEAST_YOUNG: f64 = 1.0e3;

/// The scene's warnings, less the silenced ones; an unknown name in `silence` is refused.
pub(super) fn warnings(
    ctx: &Ctx<'_>,
    f: &SceneFile,
    gravity: f64,
) -> Result<Vec<Warning>, SceneError> {
    let b = &f.boundaries;
    let sides = [("ground", b.ground), ("left_wall", b.left_wall), ("right_wall", b.right_wall)];
    let walls = b.walls.iter().enumerate().map(|(k, w)| (format!("walls[{k}]"), Some(w.law)));
    let laws = sides.into_iter().map(|(n, l)| (n.to_string(), l)).chain(walls).collect();
    let floorless = f.grid.kind == GridKind::Regular && b.ground.is_none() && b.walls.is_empty();
    judge(ctx, &f.silence, laws, &f.materials, floorless && gravity > 0.0)
}

/// A 3D scene's warnings: the same names over its five faces, its walls and its materials (the
/// cone warning only for materials a body uses).
pub(super) fn space_warnings(
    ctx: &Ctx<'_>,
    f: &SpaceFile,
    gravity: f64,
) -> Result<Vec<Warning>, SceneError> {
    let b = &f.boundaries;
    let faces = [
        ("ground", b.ground),
        ("left_wall", b.left_wall),
        ("right_wall", b.right_wall),
        ("back_wall", b.back_wall),
        ("front_wall", b.front_wall),
    ];
    let walls = b.walls.iter().enumerate().map(|(k, w)| (format!("walls[{k}]"), Some(w.law)));
    let laws = faces.into_iter().map(|(n, l)| (n.to_string(), l)).chain(walls).collect();
    let floorless = b.ground.is_none() && b.walls.is_empty();
    let mut out = judge(ctx, &f.silence, laws, &f.materials, floorless && gravity > 0.0)?;
    let name = "plane_strain_cone_in_3d";
    if !f.silence.iter().any(|s| s == name) {
        let used = |m: &str| f.bodies.iter().any(|b| b.material == m);
        for (m, spec) in &f.materials {
            let plain_dp =
                spec.kind() == Some("drucker_prager") && !spec.0.contains_key("cone_match");
            if plain_dp && used(m) {
                out.push(Warning {
                    name: name.into(),
                    field: format!("materials.{m}.cone_match"),
                    message: "the Drucker-Prager cone defaults to the paper's plane-strain match \
                              to Mohr-Coulomb, which in 3D is neither the compression nor the \
                              extension corner, and no single cone is right on every stress \
                              path of a flow (at φ = 30° the compression cone acts in plane \
                              strain like φ ≈ 44° to 49°): for a granular flow write \
                              `kind = \"mohr_coulomb\"` with the same cohesion, friction and \
                              dilatancy angles, whose surface is the measured friction angle on \
                              every path; or choose a cone with `cone_match = \"outer\"` \
                              (triaxial compression) or `\"inner\"` (extension)"
                        .into(),
                });
            }
        }
    }
    Ok(out)
}

/// The warnings of the boundary `laws` (field name, law), the materials and a missing floor,
/// less those `silence` names; an unknown name in `silence` is refused.
fn judge(
    ctx: &Ctx<'_>,
    silence: &[String],
    laws: Vec<(String, Option<BoundarySpec>)>,
    materials: &BTreeMap<String, MaterialSpec>,
    floorless: bool,
) -> Result<Vec<Warning>, SceneError> {
    for (k, name) in silence.iter().enumerate() {
        if !WARNINGS.iter().any(|(n, _)| n == name) {
            let names: Vec<String> = WARNINGS.iter().map(|(n, _)| format!("\"{n}\"")).collect();
            return Err(ctx.err(
                &format!("silence[{k}]"),
                Some(format!("\"{name}\"")),
                "no warning of this name",
                format!("one of {}", names.join(", ")),
                "use a name that `mpm check` printed",
            ));
        }
    }
    let mut out = Vec::new();
    let mut warn = |name: &'static str, field: String, message: String| {
        if !silence.iter().any(|s| s == name) {
            out.push(Warning { name: name.into(), field, message });
        }
    };
    for (name, law) in laws {
        match law {
            Some(BoundarySpec::Friction(mu)) if mu > MOST_MU => warn(
                "friction_as_degrees",
                format!("boundaries.{name}.friction"),
                if mu < 90.0 {
                    format!(
                        "μ = {} is a friction coefficient (tan φ), i.e. φ = {:.1}°: if {} is \
                         an angle in degrees, write `friction_angle_deg = {}` (μ = {:.3})",
                        num(mu),
                        mu.atan().to_degrees(),
                        num(mu),
                        num(mu),
                        mu.to_radians().tan()
                    )
                } else {
                    format!(
                        "μ = {} is rougher than any surface: for a base that never slides, \
                         write `\"rough\"`",
                        num(mu)
                    )
                },
            ),
            Some(BoundarySpec::FrictionAngleDeg(a)) if a > 0.0 && a < LEAST_ANGLE_DEG => warn(
                "friction_angle_as_radians",
                format!("boundaries.{name}.friction_angle_deg"),
                angle_message(a),
            ),
            _ => {}
        }
    }
    for (name, m) in materials {
        let field = |k: &str| format!("materials.{name}.{k}");
        if let Some(a) = m.number("friction_angle_deg").filter(|a| *a > 0.0 && *a < LEAST_ANGLE_DEG)
        {
            warn("friction_angle_as_radians", field("friction_angle_deg"), angle_message(a));
        }
        if let Some(rho) = m.number("density").filter(|r| *r < LEAST_DENSITY) {
            warn(
                "density_in_g_cm3",
                field("density"),
                format!(
                    "{} kg/m³ is lighter than any soil: if it is in g/cm³ or t/m³, write {} \
                     (kg/m³)",
                    num(rho),
                    num(rho * 1000.0)
                ),
            );
        }
        if let Some(e) = m.number("young").filter(|e| *e < LEAST_YOUNG) {
            warn(
                "young_below_1kpa",
                field("young"),
                format!(
                    "E = {} Pa is softer than any soil: if it is in kPa or MPa, write {} or {} \
                     (Pa)",
                    num(e),
                    num(e * 1e3),
                    num(e * 1e6)
                ),
            );
        }
    }
    if floorless {
        warn(
            "no_floor",
            "boundaries.ground".into(),
            "nothing holds the bodies under gravity (no ground, no wall): they fall until they \
             leave the grid, which stops the run; give `ground = \"rough\"` or another law"
                .into(),
        );
    }
    Ok(out)
}

/// the warning of a friction angle that looks like radians or a coefficient.
fn angle_message(a: f64) -> String {
    format!(
        "{}° is a very small friction angle: if it is in radians, write {:.1}; if it is the \
         coefficient μ, write {:.1}",
        num(a),
        a.to_degrees(),
        a.atan().to_degrees()
    )
}

#[cfg(test)]
mod tests {
    use crate::file::BoundarySpec;
    use crate::scenes::embedded_scene;
    use crate::validate::load_scene_str;

    /// the names of the warnings of the flume with `edit` applied.
    fn names(edit: impl FnOnce(&mut crate::file::SceneFile)) -> Vec<String> {
        let flume = load_scene_str(embedded_scene("flume").unwrap(), "flume").unwrap();
        let scene = flume.modified(edit).unwrap();
        scene.resolved().warnings.iter().map(|w| w.name.clone()).collect()
    }

    /// Each likely slip is flagged once, at its field; the flume as given has none; a silenced
    /// warning is gone and an unknown name is refused.
    #[test]
    fn likely_unit_slips_are_flagged_and_can_be_silenced() {
        assert!(names(|_| {}).is_empty());
        assert_eq!(
            names(|f| f.boundaries.ground = Some(BoundarySpec::Friction(27.0))),
            ["friction_as_degrees"]
        );
        assert_eq!(
            names(|f| {
                let sand = f.materials.get_mut("sand").unwrap();
                sand.set("friction_angle_deg", 0.7);
                sand.set("density", 1.6);
                sand.set("young", 2.0);
            }),
            ["friction_angle_as_radians", "density_in_g_cm3", "young_below_1kpa"]
        );
        let silenced = names(|f| {
            f.boundaries.ground = Some(BoundarySpec::Friction(27.0));
            f.silence = vec!["friction_as_degrees".into()];
        });
        assert!(silenced.is_empty(), "{silenced:?}");
        let flume = load_scene_str(embedded_scene("flume").unwrap(), "flume").unwrap();
        let e = flume.modified(|f| f.silence = vec!["friction".into()]).unwrap_err();
        assert!(e.to_string().contains("silence[0]") && e.to_string().contains("no_floor"), "{e}");
    }
}
