//! The hazard map as a picture (`maps/hazard_map.png`): the terrain as a hillshade with contour
//! lines, the largest flow height in colour over it, the release and deposit outlines, a colour
//! scale, a scale bar and a north arrow; north up, map x to the right. The rasters beside it hold
//! the numbers: this is the figure a report shows.

use std::path::Path;

use plotters::prelude::*;

use crate::OutputError;
use crate::atomic;
use crate::outline::{area2, polygons, rings};

/// The fewest cells of a patch (or a hole) whose outline the figure draws.
pub const MIN_PATCH: i64 = 4;

/// What the figure is drawn from: rasters of `cols` × `rows` cells of `cell` m, row 0 the
/// northern one, whose north-west corner is at map `corner`.
pub struct MapFigure<'a> {
    /// the title line.
    pub title: &'a str,
    /// cells along x and along north-south.
    pub cols: usize,
    /// rows.
    pub rows: usize,
    /// cell side (m).
    pub cell: f64,
    /// map [x, y] of the north-west corner (m).
    pub corner: [f64; 2],
    /// the terrain's height at each cell's centre (m).
    pub ground: &'a [f64],
    /// the largest flow height in each cell (m), 0 where none came.
    pub height: &'a [f64],
    /// the release's cells.
    pub release: &'a [bool],
    /// the deposit's cells.
    pub deposit: &'a [bool],
    /// the grid's undeclared sides the material reached (`left_wall` west, `right_wall` east,
    /// `back_wall` north, `front_wall` south), drawn as a thick magenta edge: the map is cut
    /// there by the grid, not by the terrain.
    pub edges: &'a [String],
}

/// the colour of an undeclared edge the material reached.
const EDGE: RGBColor = RGBColor(220, 0, 180);

/// the stops of the flow-height colour ramp (pale yellow to dark red).
const RAMP: [(f64, [u8; 3]); 5] = [
    (0.0, [255, 255, 178]),
    (0.25, [254, 204, 92]),
    (0.5, [253, 141, 60]),
    (0.75, [240, 59, 32]),
    (1.0, [160, 0, 38]),
];

/// the ramp's colour at `f` ∈ [0, 1].
fn ramp(f: f64) -> [u8; 3] {
    let f = f.clamp(0.0, 1.0);
    let k = RAMP.iter().rposition(|s| s.0 <= f).unwrap_or(0).min(RAMP.len() - 2);
    let (a, b) = (RAMP[k], RAMP[k + 1]);
    let w = (f - a.0) / (b.0 - a.0);
    let mix = |i: usize| (f64::from(a.1[i]) + w * (f64::from(b.1[i]) - f64::from(a.1[i]))) as u8;
    [mix(0), mix(1), mix(2)]
}

/// a round number near `x` > 0 (1, 2 or 5 times a power of ten).
pub(crate) fn nice(x: f64) -> f64 {
    let p = 10f64.powf(x.log10().floor());
    let m = x / p;
    p * if m < 1.5 {
        1.0
    } else if m < 3.5 {
        2.0
    } else if m < 7.5 {
        5.0
    } else {
        10.0
    }
}

/// the hillshade of the terrain at cell (c, r) ∈ [0, 1]: light from the north-west, 45° up.
fn shade(f: &MapFigure<'_>, c: usize, r: usize) -> f64 {
    let h = |c: usize, r: usize| f.ground[r * f.cols + c];
    let (cl, cr) = (c.saturating_sub(1), (c + 1).min(f.cols - 1));
    let (rn, rs) = (r.saturating_sub(1), (r + 1).min(f.rows - 1));
    let dx = if cr > cl { (h(cr, r) - h(cl, r)) / ((cr - cl) as f64 * f.cell) } else { 0.0 };
    // rows run south: north is row − 1
    let dy = if rs > rn { (h(c, rn) - h(c, rs)) / ((rs - rn) as f64 * f.cell) } else { 0.0 };
    let n = [-dx, -dy, 1.0];
    let len = (n[0] * n[0] + n[1] * n[1] + 1.0).sqrt();
    let (az, alt) = (315f64.to_radians(), 45f64.to_radians());
    let l = [alt.cos() * az.sin(), alt.cos() * az.cos(), alt.sin()];
    ((n[0] * l[0] + n[1] * l[1] + n[2] * l[2]) / len).max(0.0)
}

/// draws the figure into a PNG at `path` (atomically).
pub fn write(path: &Path, f: &MapFigure<'_>) -> Result<(), OutputError> {
    crate::plots::register_font();
    let fail = |e: String| OutputError::Io { path: path.into(), source: std::io::Error::other(e) };
    let n = f.cols * f.rows;
    let lengths = [f.ground.len(), f.height.len(), f.release.len(), f.deposit.len()];
    if f.cols == 0 || f.rows == 0 || lengths != [n; 4] {
        return Err(fail(format!("a {} × {} map with mismatched rasters", f.cols, f.rows)));
    }
    // pixels per cell: the map about 900 px across its longer side
    let px = (900 / f.cols.max(f.rows)).clamp(1, 40) as i32;
    let (w, h) = (f.cols as i32 * px, f.rows as i32 * px);
    let (left, top, legend) = (30, 50, 140);
    let size = ((left + w + legend) as u32, (top + h + 70) as u32);
    let tmp = atomic::temp_path(path);
    let drawn = (|| -> Result<(), String> {
        let root = BitMapBackend::new(&tmp, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        let hmax = f.height.iter().copied().fold(0.0, f64::max);
        // the cells: hillshade, the flow height blended over it
        for r in 0..f.rows {
            for c in 0..f.cols {
                let g = 70.0 + 175.0 * shade(f, c, r);
                let mut rgb = [g, g, g];
                let v = f.height[r * f.cols + c];
                if v > 0.0 && hmax > 0.0 {
                    let col = ramp(v / hmax);
                    for i in 0..3 {
                        rgb[i] = 0.2 * rgb[i] + 0.8 * f64::from(col[i]);
                    }
                }
                let (x, y) = (left + c as i32 * px, top + r as i32 * px);
                let colour = RGBColor(rgb[0] as u8, rgb[1] as u8, rgb[2] as u8);
                root.draw(&Rectangle::new([(x, y), (x + px, y + px)], colour.filled()))
                    .map_err(e)?;
            }
        }
        // contours of the terrain at cell centres (marching squares), about a dozen levels
        let (lo, hi) = f
            .ground
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
        if hi > lo {
            let step = nice((hi - lo) / 12.0);
            let centre = |c: f64, r: f64| {
                (
                    left + ((c + 0.5) * f64::from(px)) as i32,
                    top + ((r + 0.5) * f64::from(px)) as i32,
                )
            };
            let contour = RGBColor(60, 40, 20).mix(0.55);
            let mut level = (lo / step).ceil() * step;
            while level <= hi {
                for r in 0..f.rows - 1 {
                    for c in 0..f.cols - 1 {
                        let z = |dc: usize, dr: usize| f.ground[(r + dr) * f.cols + c + dc];
                        // corners in order around the square, and where the level crosses
                        // each side
                        let corners = [(0, 0), (1, 0), (1, 1), (0, 1)];
                        let mut cut = Vec::with_capacity(4);
                        for k in 0..4 {
                            let (a, b) = (corners[k], corners[(k + 1) % 4]);
                            let (za, zb) = (z(a.0, a.1), z(b.0, b.1));
                            if (za < level) != (zb < level) {
                                let t = (level - za) / (zb - za);
                                let x = c as f64 + a.0 as f64 + t * (b.0 as f64 - a.0 as f64);
                                let y = r as f64 + a.1 as f64 + t * (b.1 as f64 - a.1 as f64);
                                cut.push(centre(x, y));
                            }
                        }
                        for pair in cut.chunks_exact(2) {
                            root.draw(&PathElement::new(vec![pair[0], pair[1]], contour))
                                .map_err(e)?;
                        }
                    }
                }
                level += step;
            }
        }
        // the outlines, without the patches and holes of fewer than MIN_PATCH cells (isolated
        // grains, which `outlines.geojson` keeps)
        for (mask, colour) in [(f.release, RGBColor(20, 60, 200)), (f.deposit, BLACK)] {
            for polygon in polygons(rings(mask, f.cols, f.rows)) {
                let big = |ring: &Vec<(i64, i64)>| area2(ring).abs() >= 2 * MIN_PATCH;
                if !big(&polygon[0]) {
                    continue;
                }
                for ring in polygon.into_iter().filter(big) {
                    let points: Vec<(i32, i32)> = ring
                        .iter()
                        .map(|&(c, s)| {
                            (left + c as i32 * px, top + (f.rows as i32 - s as i32) * px)
                        })
                        .collect();
                    root.draw(&PathElement::new(points, colour.stroke_width(2))).map_err(e)?;
                }
            }
        }
        // the undeclared sides the material reached
        for name in f.edges {
            let (x0, y0, x1, y1) = (left, top, left + w, top + h);
            let line = match name.as_str() {
                "left_wall" => [(x0, y0), (x0, y1)],
                "right_wall" => [(x1, y0), (x1, y1)],
                "back_wall" => [(x0, y0), (x1, y0)],
                "front_wall" => [(x0, y1), (x1, y1)],
                _ => continue,
            };
            root.draw(&PathElement::new(line.to_vec(), EDGE.stroke_width(5))).map_err(e)?;
        }
        // title
        let text = |size: u32| ("sans-serif", size).into_font().color(&BLACK);
        root.draw(&Text::new(f.title.to_string(), (left, 12), text(18))).map_err(e)?;
        // scale bar under the map, a fifth of its width
        let width_m = f.cols as f64 * f.cell;
        let bar = nice(width_m / 5.0);
        let bar_px = (bar / f.cell * f64::from(px)) as i32;
        let (bx, by) = (left, top + h + 20);
        for k in 0..2 {
            let x0 = bx + k * bar_px / 2;
            let fill = if k == 0 { BLACK.filled() } else { WHITE.filled() };
            root.draw(&Rectangle::new([(x0, by), (x0 + bar_px / 2, by + 8)], fill)).map_err(e)?;
        }
        root.draw(&Rectangle::new([(bx, by), (bx + bar_px, by + 8)], BLACK)).map_err(e)?;
        root.draw(&Text::new(format!("{bar} m"), (bx + bar_px + 8, by - 3), text(14)))
            .map_err(e)?;
        // north arrow, top right of the map
        let (nx, ny) = (left + w - 24, top + 12);
        root.draw(&Polygon::new(vec![(nx, ny), (nx - 9, ny + 26), (nx, ny + 19)], BLACK.filled()))
            .map_err(e)?;
        root.draw(&PathElement::new(vec![(nx, ny), (nx + 9, ny + 26), (nx, ny + 19)], BLACK))
            .map_err(e)?;
        root.draw(&Text::new("N", (nx - 5, ny + 28), text(14))).map_err(e)?;
        // colour scale and key
        let (lx, ly, lh) = (left + w + 20, top + 20, (h - 120).max(80));
        root.draw(&Text::new("largest flow", (lx, top - 16), text(13))).map_err(e)?;
        root.draw(&Text::new("height (m)", (lx, top), text(13))).map_err(e)?;
        for k in 0..lh {
            let col = ramp(1.0 - f64::from(k) / f64::from(lh));
            let colour = RGBColor(col[0], col[1], col[2]);
            root.draw(&PathElement::new(vec![(lx, ly + k), (lx + 18, ly + k)], colour))
                .map_err(e)?;
        }
        root.draw(&Rectangle::new([(lx, ly), (lx + 18, ly + lh)], BLACK)).map_err(e)?;
        for k in 0..=4 {
            let v = hmax * (1.0 - f64::from(k) / 4.0);
            let y = ly + k * lh / 4;
            root.draw(&Text::new(format!("{v:.1}"), (lx + 24, y - 7), text(12))).map_err(e)?;
        }
        let mut keys = vec![("release", RGBColor(20, 60, 200)), ("deposit", BLACK)];
        if !f.edges.is_empty() {
            keys.push(("grid edge reached", EDGE));
        }
        for (k, (name, colour)) in keys.into_iter().enumerate() {
            let y = ly + lh + 20 + 18 * k as i32;
            root.draw(&PathElement::new(vec![(lx, y), (lx + 18, y)], colour.stroke_width(2)))
                .map_err(e)?;
            root.draw(&Text::new(name, (lx + 24, y - 7), text(12))).map_err(e)?;
        }
        if hi > lo {
            let contour = format!("contours {} m", nice((hi - lo) / 12.0));
            let y = ly + lh + 56 + if f.edges.is_empty() { 0 } else { 18 };
            root.draw(&Text::new(contour, (lx, y), text(11))).map_err(e)?;
        }
        root.present().map_err(|e| e.to_string())
    })();
    match drawn {
        Ok(()) => atomic::commit(&tmp, path),
        Err(why) => {
            let _ = std::fs::remove_file(&tmp);
            Err(fail(why))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_numbers_and_the_ramp_ends() {
        assert_eq!(nice(0.13), 0.1);
        assert_eq!(nice(27.0), 20.0);
        assert_eq!(nice(43.0), 50.0);
        assert_eq!(nice(80.0), 100.0);
        assert_eq!(ramp(0.0), RAMP[0].1);
        assert_eq!(ramp(1.0), RAMP[4].1);
        assert_eq!(ramp(2.0), RAMP[4].1);
    }

    /// a small map over a tilted plane draws a PNG of the stated size, and mismatched rasters
    /// are refused without a file.
    #[test]
    fn a_map_is_drawn_and_a_bad_one_refused() {
        let (cols, rows) = (30, 20);
        let ground: Vec<f64> = (0..cols * rows).map(|k| (k % cols) as f64 * 0.5).collect();
        let height: Vec<f64> = (0..cols * rows)
            .map(|k| if (10..20).contains(&(k % cols)) { 1.5 } else { 0.0 })
            .collect();
        let release: Vec<bool> = (0..cols * rows).map(|k| (12..15).contains(&(k % cols))).collect();
        let deposit: Vec<bool> = (0..cols * rows).map(|k| (16..20).contains(&(k % cols))).collect();
        let dir = std::env::temp_dir().join(format!("mpm-mapfig-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("hazard_map.png");
        let mut fig = MapFigure {
            title: "test",
            cols,
            rows,
            cell: 5.0,
            corner: [0.0, 100.0],
            ground: &ground,
            height: &height,
            release: &release,
            deposit: &deposit,
            edges: &["right_wall".to_string()],
        };
        write(&path, &fig).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        // width and height in the IHDR chunk: 30 + 30·30 + 140 by 50 + 20·30 + 70
        let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
        assert_eq!((be(16), be(20)), (1070, 720));
        std::fs::remove_file(&path).unwrap();
        fig.height = &height[1..];
        assert!(write(&path, &fig).is_err());
        assert!(!path.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
