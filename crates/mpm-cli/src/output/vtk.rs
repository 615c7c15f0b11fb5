//! VTK XML PolyData (`.vtp`) particle frames and the `.pvd` collection that ParaView opens as a
//! time series.
//!
//! Each particle is a vertex cell. Point data (selectable with `output.fields`): `stress` (full
//! 3×3 Cauchy tensor, Pa, tension positive, σ_zz of plane strain included), `pressure` (mean
//! stress tr σ/3, Pa), `velocity` and `displacement` (3 components, z = 0), `plastic_strain`
//! (ε̄ᵖ), `body` and `material` (indices), `density` (kg/m³). ASCII format, full f64 precision.

use std::fmt::Write;

use mpm_solver::Particles;

use crate::model::SceneModel;
use crate::scene::VtkField;

fn array(
    out: &mut String,
    ty: &str,
    name: &str,
    components: usize,
    values: impl Iterator<Item = String>,
) {
    let _ = writeln!(
        out,
        "        <DataArray type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{components}\" format=\"ascii\">"
    );
    let mut line = String::new();
    for (k, v) in values.enumerate() {
        if k > 0 {
            line.push(' ');
        }
        line.push_str(&v);
        if line.len() > 4000 {
            let _ = writeln!(out, "          {line}");
            line.clear();
        }
    }
    if !line.is_empty() {
        let _ = writeln!(out, "          {line}");
    }
    out.push_str("        </DataArray>\n");
}

/// one frame of particles at time `time` (s).
pub(crate) fn frame<M: SceneModel>(
    p: &Particles<M::State>,
    materials: &[M],
    fields: &[VtkField],
    time: f64,
) -> String {
    let n = p.len();
    let mut out = String::with_capacity(200 + n * 200);
    out.push_str("<?xml version=\"1.0\"?>\n");
    out.push_str("<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n");
    out.push_str("  <PolyData>\n    <FieldData>\n");
    let _ = writeln!(
        out,
        "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">{time}</DataArray>"
    );
    out.push_str("    </FieldData>\n");
    let _ = writeln!(
        out,
        "    <Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"{n}\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">"
    );
    out.push_str("      <PointData>\n");
    for field in fields {
        match field {
            VtkField::Stress => array(
                &mut out,
                "Float64",
                "stress",
                9,
                p.stress.iter().flat_map(|s| {
                    [s.xx, s.xy, s.zx, s.xy, s.yy, s.yz, s.zx, s.yz, s.zz].map(|v| v.to_string())
                }),
            ),
            VtkField::Pressure => array(
                &mut out,
                "Float64",
                "pressure",
                1,
                p.stress.iter().map(|s| (s.trace() / 3.0).to_string()),
            ),
            VtkField::Velocity => array(
                &mut out,
                "Float64",
                "velocity",
                3,
                p.velocity.iter().flat_map(|v| [v.x.to_string(), v.y.to_string(), "0".into()]),
            ),
            VtkField::Displacement => array(
                &mut out,
                "Float64",
                "displacement",
                3,
                p.position.iter().zip(&p.initial_position).flat_map(|(x, x0)| {
                    let u = *x - *x0;
                    [u.x.to_string(), u.y.to_string(), "0".into()]
                }),
            ),
            VtkField::PlasticStrain => array(
                &mut out,
                "Float64",
                "plastic_strain",
                1,
                p.state.iter().zip(&p.material).map(|(st, &m)| {
                    materials
                        .get(usize::from(m))
                        .map_or(0.0, |mat| mat.equivalent_plastic_strain(st))
                        .to_string()
                }),
            ),
            VtkField::Body => {
                array(&mut out, "Int32", "body", 1, p.body.iter().map(|b| b.to_string()))
            }
            VtkField::Material => {
                array(&mut out, "Int32", "material", 1, p.material.iter().map(|b| b.to_string()))
            }
            VtkField::Density => {
                array(&mut out, "Float64", "density", 1, (0..n).map(|i| p.density(i).to_string()))
            }
        }
    }
    out.push_str("      </PointData>\n      <Points>\n");
    array(
        &mut out,
        "Float64",
        "position",
        3,
        p.position.iter().flat_map(|x| [x.x.to_string(), x.y.to_string(), "0".into()]),
    );
    out.push_str("      </Points>\n      <Verts>\n");
    array(&mut out, "Int64", "connectivity", 1, (0..n).map(|i| i.to_string()));
    array(&mut out, "Int64", "offsets", 1, (1..=n).map(|i| i.to_string()));
    out.push_str("      </Verts>\n    </Piece>\n  </PolyData>\n</VTKFile>\n");
    out
}

/// the ParaView collection of `frames` (time, file relative to the `.pvd`).
pub(crate) fn pvd(frames: &[(f64, String)]) -> String {
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\"?>\n");
    out.push_str("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n");
    out.push_str("  <Collection>\n");
    for (t, file) in frames {
        let _ =
            writeln!(out, "    <DataSet timestep=\"{t}\" group=\"\" part=\"0\" file=\"{file}\"/>");
    }
    out.push_str("  </Collection>\n</VTKFile>\n");
    out
}
