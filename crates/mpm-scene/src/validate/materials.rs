//! `[materials.NAME]`: each material built and checked, and the ones the bodies use.

use std::collections::BTreeMap;

use mpm_constitutive::{
    ConeMatch, ConstitutiveError, DruckerPrager, DruckerPragerParams, LinearElastic,
};

use super::{Ctx, finite_pos, join, num};
use crate::error::SceneError;
use crate::file::{ConeMatchSpec, MaterialKind, SceneFile};
use crate::scene::MaterialsBuilt;

/// Every declared material by name, built: (kind, elastic, Drucker-Prager).
pub(super) type Built<'a> =
    BTreeMap<&'a str, (MaterialKind, Option<LinearElastic>, Option<DruckerPrager>)>;

/// Builds every declared material.
pub(super) fn build<'a>(ctx: &Ctx<'_>, f: &'a SceneFile) -> Result<Built<'a>, SceneError> {
    if f.materials.is_empty() {
        return Err(ctx.err(
            "materials",
            None,
            "no material is defined",
            "at least one [materials.NAME] table",
            "add e.g. [materials.sand] with kind, young, poisson and density",
        ));
    }
    let mut built = Built::new();
    for (name, m) in &f.materials {
        let base = format!("materials.{name}");
        let p = |field: &str| format!("{base}.{field}");
        if !(finite_pos(m.density) && m.density < 1e6) {
            return Err(ctx.range(
                &p("density"),
                m.density,
                "0 < density < 1e6 (kg/m³)",
                "give the material's density, e.g. 1600 for dry sand",
            ));
        }
        let elastic = LinearElastic::from_young_poisson(m.young, m.poisson)
            .map_err(|e| material_error(ctx, &base, e))?;
        match m.kind {
            MaterialKind::Elastic => {
                for (field, present) in [
                    ("cohesion", m.cohesion.is_some()),
                    ("friction_angle_deg", m.friction_angle_deg.is_some()),
                    ("dilatancy_angle_deg", m.dilatancy_angle_deg.is_some()),
                    ("hardening_modulus", m.hardening_modulus.is_some()),
                    ("mixing", m.mixing.is_some()),
                    ("cone_match", m.cone_match.is_some()),
                ] {
                    if present {
                        return Err(ctx.foreign(
                            &p(field),
                            "an elastic material has only young, poisson and density; \
                             use kind = \"drucker_prager\" for plasticity",
                        ));
                    }
                }
                built.insert(name, (m.kind, Some(elastic), None));
            }
            MaterialKind::DruckerPrager => {
                let cohesion = m.cohesion.ok_or_else(|| {
                    ctx.missing(&p("cohesion"), "Drucker-Prager material", "10.0")
                })?;
                let friction_angle_deg = m.friction_angle_deg.ok_or_else(|| {
                    ctx.missing(&p("friction_angle_deg"), "Drucker-Prager material", "40.0")
                })?;
                let params = DruckerPragerParams {
                    young: m.young,
                    poisson: m.poisson,
                    cohesion,
                    friction_angle_deg,
                    dilatancy_angle_deg: m.dilatancy_angle_deg.unwrap_or(0.0),
                    hardening_modulus: m.hardening_modulus.unwrap_or(0.0),
                    mixing: m.mixing.unwrap_or(1.0),
                    cone_match: match m.cone_match.unwrap_or(ConeMatchSpec::PlaneStrain) {
                        ConeMatchSpec::PlaneStrain => ConeMatch::PlaneStrain,
                        ConeMatchSpec::Inner => ConeMatch::Inner,
                        ConeMatchSpec::Outer => ConeMatch::Outer,
                    },
                };
                let dp = DruckerPrager::new(params).map_err(|e| material_error(ctx, &base, e))?;
                built.insert(name, (m.kind, None, Some(dp)));
            }
        }
    }
    Ok(built)
}

/// The materials the bodies use, in name order (a body's material index is its position here),
/// all of one kind: (materials, their names, their kind).
pub(super) fn select<'a>(
    ctx: &Ctx<'_>,
    f: &'a SceneFile,
    built: &Built<'a>,
) -> Result<(MaterialsBuilt, Vec<&'a str>, MaterialKind), SceneError> {
    // Material indices: the used materials, in name order.
    let mut used: Vec<&str> = Vec::new();
    let mut kind: Option<(MaterialKind, usize)> = None;
    for (b, body) in f.bodies.iter().enumerate() {
        let path = format!("bodies[{b}].material");
        let Some((k, _, _)) = built.get(body.material.as_str()) else {
            let names: Vec<String> = f.materials.keys().map(|n| format!("\"{n}\"")).collect();
            return Err(ctx.err(
                &path,
                Some(format!("\"{}\"", body.material)),
                "no material of this name",
                format!("one of {}", names.join(", ")),
                format!("define [materials.{}] or use a defined name", body.material),
            ));
        };
        match kind {
            Some((k0, b0)) if k0 != *k => {
                return Err(ctx.err(
                    &path,
                    Some(format!("\"{}\"", body.material)),
                    format!(
                        "this body is {} but bodies[{b0}] is {}: a run uses one constitutive \
                         model for all bodies, so elastic and Drucker-Prager bodies cannot be \
                         mixed in one scene",
                        k.name(),
                        k0.name()
                    ),
                    "all bodies of a scene with materials of one kind",
                    "give every body a material of the same kind (or run the bodies in \
                     separate scenes)",
                ));
            }
            None => kind = Some((*k, b)),
            _ => {}
        }
        if !used.contains(&body.material.as_str()) {
            used.push(body.material.as_str());
        }
    }
    used.sort_unstable();
    let (material_kind, _) = kind.unwrap_or((MaterialKind::Elastic, 0));
    let materials = match material_kind {
        MaterialKind::Elastic => MaterialsBuilt::Elastic(
            used.iter().filter_map(|n| built.get(n).and_then(|b| b.1)).collect(),
        ),
        MaterialKind::DruckerPrager => MaterialsBuilt::Plastic(
            used.iter().filter_map(|n| built.get(n).and_then(|b| b.2.clone())).collect(),
        ),
    };
    Ok((materials, used, material_kind))
}

pub(super) fn material_error(ctx: &Ctx<'_>, base: &str, e: ConstitutiveError) -> SceneError {
    let (field, value, admissible) = match &e {
        ConstitutiveError::InvalidParameter { name, value, range } => {
            let field = match *name {
                "bulk" | "shear" => "young",
                other => other,
            };
            (field.to_string(), Some(num(*value)), range.to_string())
        }
        ConstitutiveError::IllPosedSoftening { hardening_modulus, lower_bound, .. } => (
            "hardening_modulus".into(),
            Some(num(*hardening_modulus)),
            format!("hardening_modulus > {} Pa", num(*lower_bound)),
        ),
        _ => (String::new(), None, String::new()),
    };
    let fix = match field.as_str() {
        "young" => "give Young's modulus in Pa, e.g. 2e6 for loose sand",
        "poisson" => "use a Poisson's ratio below 0.5, e.g. 0.3",
        "cohesion" => "use a cohesion ≥ 0 in Pa (10 Pa in the paper's sand)",
        "friction_angle_deg" => "use a friction angle below 90°, e.g. 40 for dry sand",
        "dilatancy_angle_deg" => "use 0 ≤ ψ ≤ φ (0 in the paper)",
        "mixing" => "use M between 0 (kinematic) and 1 (isotropic); 0.8 in the paper",
        "hardening_modulus" => "use H ≥ 0 (0 in the paper) or a milder softening",
        _ => "see docs/scene-format.md",
    };
    ctx.err(&join(base, &field), value, e.to_string(), admissible, fix)
}
