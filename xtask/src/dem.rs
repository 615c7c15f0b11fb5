//! `cargo xtask dem`: writes the worked example's terrain — a synthetic valley side as an ESRI
//! ASCII grid and as a GeoTIFF (the same heights), and the rupture surface of its landslide —
//! into `docs/examples/valley/`.
//!
//! The valley side falls from about 197 m to the valley floor along +x (east), steepest (40°)
//! at x = 250 m, to a floor 6.3 m high at x ≈ 472 m (under the gully), which rises again into
//! the foot of the opposite side (31° at x = 540 m, 48 m high at the east edge); a gully 6 m deep
//! runs down the valley side along y = 150 m and fades out on the floor:
//!
//! ```text
//! z(x, y) = 100 (1 − tanh((x − 250)/120)) + 25 (1 + tanh((x − 540)/40))
//!           − 6 exp(−((y − 150)/40)²) · ½(1 − tanh((x − 300)/100))
//! ```
//!
//! on 120 × 60 cells of 5 m (x ∈ [0, 600], y ∈ [0, 300]). The rupture surface lies under the
//! section along the gully (from (10, 150) to (590, 150)): between stations 150 and 250 m (on
//! ground sloping 26°–40°) it is `12 sin²(π (s − 150)/100)` m below the ground, a 100 m long
//! slide up to 12 m deep whose rupture surface meets the ground tangentially. The 3D slide
//! (`rupture3d.asc`, 120 × 120 m from (150, 90)) tapers that depth across the gully
//! ([`rupture_depth`]).

use std::path::Path;

use anyhow::{Context, Result};
use mpm_dem::Raster;

/// the valley side's height at map point (x, y) (m).
pub fn height(x: f64, y: f64) -> f64 {
    let gully = 6.0 * (-((y - 150.0) / 40.0).powi(2)).exp();
    100.0 * (1.0 - ((x - 250.0) / 120.0).tanh()) + 25.0 * (1.0 + ((x - 540.0) / 40.0).tanh())
        - gully * 0.5 * (1.0 - ((x - 300.0) / 100.0).tanh())
}

/// writes the rasters and the rupture surface; returns whether it succeeded.
pub fn run() -> Result<bool> {
    let dir = Path::new("docs/examples/valley");
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let (cols, rows, cell, north) = (120usize, 60usize, 5.0, 300.0);
    let mut z = Vec::with_capacity(cols * rows);
    for r in 0..rows {
        for c in 0..cols {
            z.push(height((c as f64 + 0.5) * cell, north - (r as f64 + 0.5) * cell));
        }
    }
    let raster = Raster::new("valley_side", [cols, rows], cell, [0.0, north], z, None)?;
    mpm_dem::ascii::write(&raster, &dir.join("valley_side.asc"))?;
    mpm_dem::geotiff::write(&raster, &dir.join("valley_side.tif"))?;
    // the rupture surface under the section along y = 150 m, station s = x − 10
    let mut csv = String::from("# rupture surface under the section (10, 150) → (590, 150)\nx,y\n");
    for k in 0..=20 {
        let s = 150.0 + 5.0 * k as f64;
        let depth = 12.0 * (std::f64::consts::PI * (s - 150.0) / 100.0).sin().powi(2);
        let ground = raster.height(s + 10.0, 150.0)?;
        csv.push_str(&format!("{s},{}\n", ground - depth.max(0.0)));
    }
    std::fs::write(dir.join("rupture.csv"), csv)?;
    // the 3D slide's rupture surface: the section's, tapered across the gully
    let (c0, r0, n3) = (30usize, 18usize, 24usize);
    let mut z3 = Vec::with_capacity(n3 * n3);
    for r in 0..n3 {
        for c in 0..n3 {
            let (x, y) =
                ((c0 + c) as f64 * cell + 0.5 * cell, north - (r0 + r) as f64 * cell - 0.5 * cell);
            z3.push(height(x, y) - rupture_depth(x, y));
        }
    }
    let west = c0 as f64 * cell;
    let top = north - r0 as f64 * cell;
    let rupture = Raster::new("rupture3d", [n3, n3], cell, [west, top], z3, None)?;
    mpm_dem::ascii::write(&rupture, &dir.join("rupture3d.asc"))?;
    println!(
        "wrote {0}/valley_side.asc, {0}/valley_side.tif ({cols} × {rows} cells of {cell} m), \
         {0}/rupture.csv and {0}/rupture3d.asc",
        dir.display()
    );
    Ok(true)
}

/// The 3D slide's depth below the ground at map point (x, y) (m): the section's
/// `12 sin²(π (x − 160)/100)` between x = 160 and 260 m (stations 150–250), times
/// `cos²(π (y − 150)/80)` within 40 m of the gully's axis: a spoon 100 m long, 80 m wide and up
/// to 12 m deep, meeting the ground tangentially all round.
pub fn rupture_depth(x: f64, y: f64) -> f64 {
    if !((160.0..=260.0).contains(&x) && (y - 150.0).abs() <= 40.0) {
        return 0.0;
    }
    let pi = std::f64::consts::PI;
    12.0 * (pi * (x - 160.0) / 100.0).sin().powi(2) * (pi * (y - 150.0) / 80.0).cos().powi(2)
}
