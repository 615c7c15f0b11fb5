//! PNG plots with plotters, the project's one chart module: [`chart`] draws lines, dashed lines
//! and points (the energy history, probe displacement against its analytic curve, the runout
//! history, the final deposit, the element tests) and [`figure`] several such charts side by side
//! (`cargo xtask`'s reports).
//!
//! The font (DejaVu Sans, see `assets/DejaVuSans-LICENSE.txt`) is compiled in, so plots need no
//! system font.

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;
use plotters::style::FontStyle;

use crate::OutputError;
use crate::atomic;

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// registers the embedded font as plotters' "sans-serif" (once per process): plotters draws text
/// only with a registered font.
pub(crate) fn register_font() {
    REGISTER.call_once(|| {
        // The embedded font is a valid TTF; if registration failed, text would be missing but
        // the plot would still be drawn.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// a solid line.
    Line,
    /// a dashed line (analytic references).
    Dashed,
    /// small filled circles.
    Points,
    /// a thick solid line (the ground).
    Thick,
}

/// One data series.
#[derive(Clone, Debug)]
pub struct Series {
    /// legend label ("" for none).
    pub name: String,
    /// (x, y) points; non-finite points are skipped.
    pub points: Vec<(f64, f64)>,
    /// how to draw it.
    pub style: Style,
    /// palette index.
    pub color: usize,
}

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(127, 127, 127),
    RGBColor(23, 190, 207),
];

/// A chart's texts and geometry.
#[derive(Clone, Debug)]
pub struct Chart<'a> {
    /// title above the plot.
    pub title: &'a str,
    /// x axis label.
    pub x_label: &'a str,
    /// y axis label.
    pub y_label: &'a str,
    /// image size in pixels.
    pub size: (u32, u32),
    /// equal scales on both axes (geometry plots).
    pub equal_aspect: bool,
}

fn bounds(series: &[Series]) -> (f64, f64, f64, f64) {
    let (mut x0, mut x1, mut y0, mut y1) =
        (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for s in series {
        for &(x, y) in &s.points {
            if x.is_finite() && y.is_finite() {
                x0 = x0.min(x);
                x1 = x1.max(x);
                y0 = y0.min(y);
                y1 = y1.max(y);
            }
        }
    }
    if !x0.is_finite() {
        return (0.0, 1.0, 0.0, 1.0);
    }
    let pad = |a: f64, b: f64| {
        let span = b - a;
        let d = if span > 0.0 { 0.05 * span } else { 0.5 * a.abs().max(1.0) };
        (a - d, b + d)
    };
    let (x0, x1) = pad(x0, x1);
    let (y0, y1) = pad(y0, y1);
    (x0, x1, y0, y1)
}

/// draws `series` into the PNG at `path` (written atomically).
pub fn chart(path: &Path, c: &Chart<'_>, series: &[Series]) -> Result<(), OutputError> {
    figure(path, &[(c.clone(), series)], 1, c.size)
}

/// draws `panels` side by side, `columns` per row, into one PNG of `size` pixels at `path`
/// (written atomically); each panel's own `size` is ignored.
pub fn figure(
    path: &Path,
    panels: &[(Chart<'_>, &[Series])],
    columns: usize,
    size: (u32, u32),
) -> Result<(), OutputError> {
    register_font();
    let tmp = atomic::temp_path(path);
    let fail =
        |e: String| OutputError::Io { path: path.to_path_buf(), source: std::io::Error::other(e) };
    let drawn = (|| {
        let root = BitMapBackend::new(&tmp, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let rows = panels.len().div_ceil(columns.max(1)).max(1);
        let areas = root.split_evenly((rows, columns.max(1)));
        for ((c, series), area) in panels.iter().zip(&areas) {
            panel(area, c, series).map_err(|e| format!("chart `{}`: {e}", c.title))?;
        }
        root.present().map_err(|e| e.to_string())
    })();
    match drawn {
        Ok(()) => atomic::commit(&tmp, path),
        Err(e) => {
            // plotters writes what it drew when the backend is dropped: leave no partial file
            let _ = std::fs::remove_file(&tmp);
            Err(fail(e))
        }
    }
}

/// draws one chart into `area`.
fn panel(
    area: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    c: &Chart<'_>,
    series: &[Series],
) -> Result<(), String> {
    let (mut x0, mut x1, mut y0, mut y1) = bounds(series);
    if c.equal_aspect {
        // plotting area ≈ size minus margins and label areas
        let (w, h) = area.dim_in_pixel();
        let (w, h) = (f64::from(w) - 110.0, f64::from(h) - 110.0);
        let (sx, sy) = ((x1 - x0) / w, (y1 - y0) / h);
        if sx > sy {
            let mid = 0.5 * (y0 + y1);
            y0 = mid - 0.5 * sx * h;
            y1 = mid + 0.5 * sx * h;
        } else {
            let mid = 0.5 * (x0 + x1);
            x0 = mid - 0.5 * sy * w;
            x1 = mid + 0.5 * sy * w;
        }
    }
    let y_top = y1;
    let legend = legend_corner(area.dim_in_pixel(), series, (x0, x1), &mut y1, y0);
    if c.equal_aspect && y1 != y_top {
        // keep the aspect: widen x by the factor the legend's band raised y
        x1 = x0 + (x1 - x0) * (y1 - y0) / (y_top - y0);
    }
    let fail = |e: &dyn std::fmt::Display| e.to_string();
    let mut chart = ChartBuilder::on(area)
        .caption(c.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| fail(&e))?;
    chart
        .configure_mesh()
        .x_desc(c.x_label)
        .y_desc(c.y_label)
        .label_style(("sans-serif", 14))
        .x_label_formatter(&|v| tick(snap(*v, x1 - x0)))
        .y_label_formatter(&|v| tick(snap(*v, y1 - y0)))
        .axis_desc_style(("sans-serif", 16))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(|e| fail(&e))?;
    let mut any_legend = false;
    for s in series {
        let color = PALETTE[s.color % PALETTE.len()];
        let pts: Vec<(f64, f64)> =
            s.points.iter().copied().filter(|p| p.0.is_finite() && p.1.is_finite()).collect();
        let anno = match s.style {
            Style::Line | Style::Thick => {
                let width = if s.style == Style::Thick { 3 } else { 2 };
                chart
                    .draw_series(LineSeries::new(pts, color.stroke_width(width)))
                    .map_err(|e| fail(&e))?
            }
            Style::Dashed => chart
                .draw_series(DashedLineSeries::new(pts, 8, 5, color.stroke_width(2)))
                .map_err(|e| fail(&e))?,
            Style::Points => chart
                .draw_series(pts.into_iter().map(|p| Circle::new(p, 2, color.filled())))
                .map_err(|e| fail(&e))?,
        };
        if !s.name.is_empty() {
            any_legend = true;
            anno.label(s.name.clone()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        }
    }
    if let (true, Some(corner)) = (any_legend, legend) {
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .position(corner)
            .draw()
            .map_err(|e| fail(&e))?;
    }
    Ok(())
}

/// a tick at `v` on an axis spanning `span`: 0 where `v` is the round-off of a zero tick (a
/// tick at −5.55e-17 on a 1.4 m axis is the rounding of 0, not a value to print).
fn snap(v: f64, span: f64) -> f64 {
    if v.abs() <= 1e-9 * span.abs() { 0.0 } else { v }
}

/// a tick label readable at any magnitude: plain with at most three decimals between 0.01 and
/// 10 000, else in scientific notation (a residual of 3e8 J/m is `3e8`, not `300000000.0`
/// cut by the label area).
fn tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-2..1e4).contains(&a) {
        // three decimals of mantissa, trailing zeros off: 10 000, 10 500, 11 000 read 1e4,
        // 1.05e4, 1.1e4 (one decimal made two of them 1.1e4)
        let s = format!("{v:.3e}");
        let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        format!("{mantissa}e{exponent}")
    } else {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// Where the legend goes so that it covers no data: the first corner of the plotting area
/// (upper right, upper left, lower right, lower left) whose legend-sized box holds no point of
/// any series; when every corner holds some, the y range is raised (`y1`) until the band above
/// the data fits the legend, which then sits upper right. `None` without named series.
fn legend_corner(
    (width, height): (u32, u32),
    series: &[Series],
    (x0, x1): (f64, f64),
    y1: &mut f64,
    y0: f64,
) -> Option<SeriesLabelPosition> {
    let named: Vec<&Series> = series.iter().filter(|s| !s.name.is_empty()).collect();
    if named.is_empty() {
        return None;
    }
    // the plotting area (the chart's margins and label areas off) and the legend's box in it:
    // 18 px a line plus its frame, 7 px a character plus the sample line
    let (w, h) = ((f64::from(width) - 100.0).max(50.0), (f64::from(height) - 100.0).max(50.0));
    let chars = named.iter().map(|s| s.name.chars().count()).max().unwrap_or(0) as f64;
    let (fw, fh) =
        (((chars * 7.5 + 50.0) / w).min(0.9), ((named.len() as f64 * 18.0 + 16.0) / h).min(0.9));
    let span_y = *y1 - y0;
    let inside = |(bx0, bx1): (f64, f64), (by0, by1): (f64, f64)| {
        series.iter().flat_map(|s| &s.points).any(|&(x, y)| {
            let (u, v) = ((x - x0) / (x1 - x0), (y - y0) / span_y);
            u >= bx0 && u <= bx1 && v >= by0 && v <= by1
        })
    };
    let (left, right, low, high) = ((0.0, fw), (1.0 - fw, 1.0), (0.0, fh), (1.0 - fh, 1.0));
    for (corner, bx, by) in [
        (SeriesLabelPosition::UpperRight, right, high),
        (SeriesLabelPosition::UpperLeft, left, high),
        (SeriesLabelPosition::LowerRight, right, low),
        (SeriesLabelPosition::LowerLeft, left, low),
    ] {
        if !inside(bx, by) {
            return Some(corner);
        }
    }
    // a free band on top, with a gap of 2 % of the axis: the data's span becomes (1 − fh − 0.02)
    // of it
    *y1 = y0 + span_y / (1.0 - fh - 0.02);
    Some(SeriesLabelPosition::UpperRight)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(name: &str, points: Vec<(f64, f64)>) -> Series {
        Series { name: name.into(), points, style: Style::Line, color: 0 }
    }

    /// the fraction of the legend's box (as `legend_corner` sizes it) at `corner` that holds a
    /// point of `series`, over the axis ranges given.
    fn covered(
        series: &[Series],
        corner: &SeriesLabelPosition,
        (x0, x1, y0, y1): (f64, f64, f64, f64),
        (fw, fh): (f64, f64),
    ) -> bool {
        let (bx, by) = match corner {
            SeriesLabelPosition::UpperRight => ((1.0 - fw, 1.0), (1.0 - fh, 1.0)),
            SeriesLabelPosition::UpperLeft => ((0.0, fw), (1.0 - fh, 1.0)),
            SeriesLabelPosition::LowerRight => ((1.0 - fw, 1.0), (0.0, fh)),
            _ => ((0.0, fw), (0.0, fh)),
        };
        series.iter().flat_map(|s| &s.points).any(|&(x, y)| {
            let (u, v) = ((x - x0) / (x1 - x0), (y - y0) / (y1 - y0));
            (bx.0..=bx.1).contains(&u) && (by.0..=by.1).contains(&v)
        })
    }

    /// A decaying curve (an energy plot) fills the upper left: the legend goes where no point
    /// is. Curves through every corner: the axis grows a free band on top and the legend sits
    /// in it. 600 × 420 px, two series of 16-character names (the box `legend_corner` sizes:
    /// (16 × 7.5 + 50)/500 wide, (2 × 18 + 16)/320 high).
    #[test]
    fn the_legend_covers_no_point() {
        let size = (600, 420);
        let fb = ((16.0 * 7.5 + 50.0) / 500.0, (2.0 * 18.0 + 16.0) / 320.0);
        let decay: Vec<(f64, f64)> =
            (0..=100).map(|i| (i as f64, (-(i as f64) / 10.0).exp())).collect();
        let flat: Vec<(f64, f64)> = (0..=100).map(|i| (i as f64, 0.5)).collect();
        let s = [line("kinetic energy..", decay), line("dissipated......", flat)];
        let (x0, x1, y0, mut y1) = (0.0, 100.0, 0.0, 1.0);
        let corner = legend_corner(size, &s, (x0, x1), &mut y1, y0).unwrap();
        assert_eq!(y1, 1.0, "a free corner needs no band");
        assert!(!covered(&s, &corner, (x0, x1, y0, y1), fb), "{corner:?}");
        // every corner holds a point
        let corners = vec![(0.0, 0.0), (100.0, 0.0), (0.0, 1.0), (100.0, 1.0)];
        let s = [line("kinetic energy..", corners), line("dissipated......", vec![])];
        let (x0, x1, y0, mut y1) = (0.0, 100.0, 0.0, 1.0);
        let corner = legend_corner(size, &s, (x0, x1), &mut y1, y0).unwrap();
        assert!(y1 > 1.0 / (1.0 - fb.1) - 1e-12, "the top band fits the legend: y1 = {y1}");
        assert!(!covered(&s, &corner, (x0, x1, y0, y1), fb), "{corner:?}");
        // no named series, no legend
        let mut y1 = 1.0;
        assert!(
            legend_corner(size, &[line("", vec![(0.0, 0.0)])], (0.0, 1.0), &mut y1, 0.0).is_none()
        );
    }

    #[test]
    fn tick_labels_stay_short_at_any_magnitude() {
        assert_eq!(tick(0.0), "0");
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(1500.0), "1500");
        assert_eq!(tick(-3.0e8), "-3e8");
        assert_eq!(
            (tick(1.0e4), tick(1.05e4), tick(1.1e4)),
            ("1e4".into(), "1.05e4".into(), "1.1e4".into())
        );
        assert_eq!(tick(2.5e-5), "2.5e-5");
        // a zero tick's round-off on a 1.4 m axis reads 0; a small value on a small axis stays
        assert_eq!(tick(snap(-5.551e-17, 1.4)), "0");
        assert_eq!(tick(snap(2.5e-5, 1e-4)), "2.5e-5");
        for v in [1e-300, 3.7e-7, 0.0123, 12.5, 9999.0, 1e12, -4.4e20] {
            assert!(tick(v).len() <= 8, "{v}: {}", tick(v));
        }
    }
}
