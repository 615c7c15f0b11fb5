//! `[materials.NAME]`: each material built by the registry's model for its `kind`, and the
//! ones the bodies use.

use std::collections::BTreeMap;

use mpm_constitutive::ConstitutiveError;

use super::{Ctx, describe, finite_pos, join, num};
use crate::error::SceneError;
use crate::file::MaterialSpec;
use crate::materials::{AnyModel, BuildError, KINDS, MaterialsBuilt};

/// Builds every declared material, by name.
pub(super) fn build<'a>(
    ctx: &Ctx<'_>,
    materials: &'a BTreeMap<String, MaterialSpec>,
) -> Result<BTreeMap<&'a str, AnyModel>, SceneError> {
    if materials.is_empty() {
        return Err(ctx.err(
            "materials",
            None,
            "no material is defined",
            "at least one [materials.NAME] table",
            "add e.g. [materials.sand] with kind, young, poisson and density",
        ));
    }
    let kinds = || KINDS.iter().map(|k| format!("\"{k}\"")).collect::<Vec<_>>().join(", ");
    let mut built = BTreeMap::new();
    for (name, m) in materials {
        let base = format!("materials.{name}");
        let p = |field: &str| format!("{base}.{field}");
        let kind = match m.0.get("kind") {
            None => {
                return Err(ctx.missing(
                    &p("kind"),
                    "every material names its model",
                    "\"elastic\"",
                ));
            }
            Some(toml::Value::String(k)) => k.as_str(),
            Some(v) => {
                return Err(ctx.err(
                    &p("kind"),
                    Some(v.to_string()),
                    "the kind is a model's name",
                    format!("one of {}", kinds()),
                    "write the kind as a quoted name, e.g. kind = \"drucker_prager\"",
                ));
            }
        };
        let density = match m.0.get("density") {
            None => {
                return Err(ctx.missing(&p("density"), "every material has a density", "1600.0"));
            }
            Some(_) => m.number("density").ok_or_else(|| {
                ctx.err(
                    &p("density"),
                    m.0.get("density").map(ToString::to_string),
                    "the density is a number",
                    "0 < density < 1e6 (kg/m³)",
                    "write the density in kg/m³, e.g. density = 1600.0",
                )
            })?,
        };
        if !(finite_pos(density) && density < 1e6) {
            return Err(ctx.range(
                &p("density"),
                density,
                "0 < density < 1e6 (kg/m³)",
                "give the material's density, e.g. 1600 for dry sand",
            ));
        }
        let mut params = m.0.clone();
        params.remove("kind");
        params.remove("density");
        let material = AnyModel::new(kind, params, density).map_err(|e| match e {
            BuildError::UnknownKind => ctx.err(
                &p("kind"),
                Some(format!("\"{kind}\"")),
                format!("no material model is registered as `{kind}`"),
                format!("one of {}", kinds()),
                "use one of the admissible names (docs/scene-format.md describes each model)",
            ),
            BuildError::Table(inner, message) => {
                let path = if inner == "." { base.clone() } else { join(&base, &inner) };
                let mut e = describe(ctx, &message, path, None);
                if e.problem.starts_with("unknown field") {
                    e.admissible = format!("{} (besides `kind` and `density`)", e.admissible);
                    e.fix = format!(
                        "remove it or correct its spelling, or change `kind` (\"{kind}\") to \
                         the model it belongs to (docs/scene-format.md lists each model's fields)"
                    );
                }
                e
            }
            BuildError::Model(e, fix) => material_error(ctx, &base, e, fix),
        })?;
        built.insert(name.as_str(), material);
    }
    Ok(built)
}

/// The materials the bodies use, in name order (a body's material index is its position here),
/// of one model or of several: (materials, their names).
pub(super) fn select<'a>(
    ctx: &Ctx<'_>,
    materials: &'a BTreeMap<String, MaterialSpec>,
    bodies: &[&'a str],
    built: &BTreeMap<&'a str, AnyModel>,
) -> Result<(MaterialsBuilt, Vec<&'a str>), SceneError> {
    let mut used: Vec<&str> = Vec::new();
    for (b, &material) in bodies.iter().enumerate() {
        if !built.contains_key(material) {
            let names: Vec<String> = materials.keys().map(|n| format!("\"{n}\"")).collect();
            return Err(ctx.err(
                &format!("bodies[{b}].material"),
                Some(format!("\"{material}\"")),
                "no material of this name",
                format!("one of {}", names.join(", ")),
                format!("define [materials.{material}] or use a defined name"),
            ));
        }
        if !used.contains(&material) {
            used.push(material);
        }
    }
    used.sort_unstable();
    if used.is_empty() {
        // `bodies::count` refuses a scene without bodies: this is a guard, not a path a scene
        // can take.
        return Err(ctx.err(
            "bodies",
            None,
            "the scene has no body",
            "at least one [[bodies]] table",
            "add a [[bodies]] table with a defined material",
        ));
    }
    let chosen = used.iter().filter_map(|n| built.get(n).cloned()).collect();
    Ok((MaterialsBuilt::collect(chosen), used))
}

/// A value the model refused, located at its field.
fn material_error(
    ctx: &Ctx<'_>,
    base: &str,
    e: ConstitutiveError,
    fix: fn(&str) -> &'static str,
) -> SceneError {
    let (field, value, admissible) = match &e {
        ConstitutiveError::InvalidParameter { name, value, range } => {
            let field = match *name {
                "bulk" | "shear" => "young",
                other => other,
            };
            (field.to_string(), Some(num(*value)), range.to_string())
        }
        ConstitutiveError::MissingParameter { name, reason } => {
            (name.to_string(), None, reason.to_string())
        }
        ConstitutiveError::IllPosedSoftening { hardening_modulus, lower_bound, .. } => (
            "hardening_modulus".into(),
            Some(num(*hardening_modulus)),
            format!("hardening_modulus > {} Pa", num(*lower_bound)),
        ),
        _ => (String::new(), None, String::new()),
    };
    ctx.err(&join(base, &field), value, e.to_string(), admissible, fix(&field))
}
