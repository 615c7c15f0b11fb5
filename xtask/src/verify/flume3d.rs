//! The plane-strain equivalence on the flume (issue 40's row): the paper's dry-sand flume in 2D
//! on its terrain-following grid, and extruded 0.2 m (two plan cells) on the 3D terrain grid
//! over a DEM of the same profile, between frictionless front and back walls. The sand mass is
//! the flume's 1.2 × 0.7 m block on the slope as a polygon (a prism in 3D), so that both runs
//! fill it with the same lattice of particles (the 2D scene's `on_slope` body lays its lattice
//! along the slope, which no 3D body does); everything else is the flume's (Table 2, USAVG,
//! C = 0.1, the plane-strain cone in both). The front, the centre of mass's travel and the
//! energy ledger per metre of thickness must agree within 1 %.

use std::fmt::Write as _;

use super::Rows;
use super::three_d::{EQUIVALENCE_REL, equivalence_rows};

/// the flume's ground: 30° over 2.5 m, then level to 5 m.
fn ground(x: f64) -> f64 {
    (2.5 - x).max(0.0) * 30f64.to_radians().tan()
}

/// the sand block's corners: its lower upslope corner on the ground at x = 0.05 m, 1.2 m along
/// the 30° slope and 0.7 m normal to it (the embedded flume's `on_slope` body).
fn block() -> [[f64; 2]; 4] {
    let t = 30f64.to_radians();
    let (d, n) = ([t.cos(), -t.sin()], [t.sin(), t.cos()]);
    let a = [0.05, ground(0.05)];
    let b = [a[0] + 1.2 * d[0], a[1] + 1.2 * d[1]];
    let c = [b[0] + 0.7 * n[0], b[1] + 0.7 * n[1]];
    let e = [a[0] + 0.7 * n[0], a[1] + 0.7 * n[1]];
    [a, b, c, e]
}

/// the materials, boundaries' friction and solver of both runs.
const COMMON: &str = r#"
[materials.sand]
kind = "drucker_prager"
young = 2.0e6
poisson = 0.3
density = 1600.0
cohesion = 10.0
friction_angle_deg = 40.0
dilatancy_angle_deg = 0.0
hardening_modulus = 0.0
mixing = 0.8
cone_match = "plane_strain"
"#;

const SOLVER: &str = r#"
[solver]
scheme = "usavg"
shape_function = "bilinear"
courant = 0.1
end_time = END
objective_stress = true
[output]
vtk = false
plots = false
"#;

/// the 2D flume with the block as a polygon.
fn flume_2d(end: f64) -> String {
    let vertices: Vec<String> = block().iter().map(|p| format!("[{}, {}]", p[0], p[1])).collect();
    format!(
        r#"
[grid]
kind = "terrain"
cell_width = 0.1
row_height = 0.1
rows = 15
profile = [[0.0, {top}], [2.5, 0.0], [5.0, 0.0]]
kink_policy = "reject"
{COMMON}
[[bodies]]
material = "sand"
shape = "polygon"
vertices = [{v}]
particles_per_cell = 2
[boundaries]
ground = {{ friction_angle_deg = 27.0 }}
left_wall = "frictionless"
right_wall = "frictionless"
{solver}"#,
        top = ground(0.0),
        v = vertices.join(", "),
        solver = SOLVER.replace("END", &end.to_string()),
    )
}

/// the flume extruded `width` m on the 3D terrain grid over `dem` (written by [`dem`]).
fn flume_3d(end: f64, width: f64) -> String {
    let vertices: Vec<String> = block().iter().map(|p| format!("[{}, {}]", p[0], p[1])).collect();
    format!(
        r#"
[grid]
dimension = 3
kind = "terrain"
dem = "flume.asc"
from = [0.0, {south}]
to = [5.0, 0.0]
plan_cell = 0.1
layer_height = 0.1
layers = 15
{COMMON}
[[bodies]]
material = "sand"
shape = "prism"
axis = "z"
vertices = [{v}]
from = 0.0
to = {width}
particles_per_cell = 2
[boundaries]
ground = {{ friction_angle_deg = 27.0 }}
left_wall = "frictionless"
right_wall = "frictionless"
back_wall = "frictionless"
front_wall = "frictionless"
{solver}
runout_direction = [1.0, 0.0, 0.0]
"#,
        south = -width,
        v = vertices.join(", "),
        solver = SOLVER.replace("END", &end.to_string()),
    )
}

/// an ESRI ASCII DEM of the flume's profile whose cell centres are the 3D grid's lattice
/// nodes (x = 0, 0.1, …, 5 m; map y = −width … 0), so that its bilinear heights there are the
/// profile's, the kink at x = 2.5 m included.
fn dem(width: f64) -> String {
    let rows = (width / 0.1).round() as usize + 1;
    let mut s = format!(
        "ncols 51\nnrows {rows}\nxllcorner -0.05\nyllcorner {}\ncellsize 0.1\n",
        -width - 0.05
    );
    for _ in 0..rows {
        let line: Vec<String> = (0..=50).map(|c| format!("{}", ground(c as f64 * 0.1))).collect();
        let _ = writeln!(s, "{}", line.join(" "));
    }
    s
}

/// appends the flume's equivalence rows (the full set: a 3 s flume in 3D is ~25 M
/// particle-steps).
pub(super) fn rows(rows: &mut Rows, quick: bool) {
    if quick {
        return;
    }
    let (end, width) = (3.0, 0.2);
    let case = format!(
        "3D plane-strain equivalence: the flume extruded {width} m on the terrain grid over a \
         DEM, to {end} s"
    );
    let run = || -> Result<_, String> {
        let dir = std::path::Path::new("target/verify/flume3d");
        std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
        std::fs::write(dir.join("flume.asc"), dem(width)).map_err(|e| e.to_string())?;
        let plane =
            mpm_run::load_scene_str(&flume_2d(end), "flume 2D").map_err(|e| e.to_string())?;
        let space = mpm_scene::load_space_str_in(&flume_3d(end, width), "flume 3D", dir)
            .map_err(|e| e.to_string())?;
        let opts = mpm_run::RunOptions::default();
        let a = mpm_run::run_scene(&plane, &opts).map_err(|e| e.to_string())?;
        let b = mpm_run::run_space_scene(&space, &opts).map_err(|e| e.to_string())?;
        Ok((a, b))
    };
    let (a, b) = match run() {
        Ok(r) => r,
        Err(e) => return rows.failed(&case, "run", &e),
    };
    let (ra, rb) = (&a.runout.last, &b.runout.last);
    // The front is the farthest grain. The main mass's front (`front_x`) is found by two
    // rules: in 2D the end of the heaviest run of particles with no gap wider than a column, in
    // 3D the heaviest set of plan cells joined by an edge or a corner. With the 2D rule in 3D
    // the grains across closed the section's gaps (3.42 m in 2D, 4.19 m in 3D; each z-layer's
    // own section 3.40–3.68 m); the rules differ, so it is reported, not compared.
    rows.rel(
        &case,
        "front: farthest grain (m)",
        ra.leading_x,
        "the 2D flume",
        rb.leading_x,
        EQUIVALENCE_REL,
    );
    rows.info(
        &case,
        "main mass's front (m)",
        &format!("{:.4} (2D)", ra.front_x),
        "reported: 2D gaps along x, 3D joined plan cells",
        format!("{:.4}", rb.front_x),
    );
    equivalence_rows(rows, &case, "the 2D flume", (&a, &b), width);
}
