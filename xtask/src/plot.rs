//! PNG line and scatter charts (plotters with an embedded font; no system font is needed).

use std::path::Path;

use anyhow::{Context, Result, anyhow};
use plotters::prelude::*;

/// plotters draws text only with a registered font: the CLI's embedded DejaVu Sans.
fn register_font() {
    mpm_cli::output::plots::register_font();
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    /// a polyline.
    Line,
    /// a dashed-looking polyline (thin), for references.
    Reference,
    /// points only.
    Points,
}

/// One named data series.
#[derive(Clone, Debug)]
pub struct Series {
    /// legend entry.
    pub name: String,
    /// (x, y) points.
    pub points: Vec<(f64, f64)>,
    /// how it is drawn.
    pub mark: Mark,
}

impl Series {
    /// a series from its name, points and mark.
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>, mark: Mark) -> Self {
        Self { name: name.into(), points, mark }
    }
}

/// One chart of a figure.
#[derive(Clone, Debug)]
pub struct Panel {
    /// title above the chart.
    pub title: String,
    /// x-axis label.
    pub x_label: String,
    /// y-axis label.
    pub y_label: String,
    /// the data.
    pub series: Vec<Series>,
}

const COLOURS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// draws `panels` side by side (`columns` per row) into a PNG of `width` × `height` pixels.
pub fn figure(
    path: &Path,
    panels: &[Panel],
    columns: usize,
    width: u32,
    height: u32,
) -> Result<()> {
    register_font();
    let rows = panels.len().div_ceil(columns.max(1));
    let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
    let areas = root.split_evenly((rows.max(1), columns.max(1)));
    for (panel, area) in panels.iter().zip(areas.iter()) {
        draw_panel(area, panel).with_context(|| format!("chart `{}`", panel.title))?;
    }
    root.present()
        .map_err(|e| anyhow!("{e}"))
        .with_context(|| format!("writing {}", path.display()))
}

fn draw_panel(
    area: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    p: &Panel,
) -> Result<()> {
    let finite =
        p.series.iter().flat_map(|s| &s.points).filter(|(x, y)| x.is_finite() && y.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in finite {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    // Margins so that flat series and end points stay visible.
    let pad = |a: f64, b: f64| {
        let d = (b - a).abs().max(1e-12 * a.abs().max(b.abs())).max(1e-300);
        (a - 0.05 * d, b + 0.05 * d)
    };
    let (x0, x1) = pad(x0, x1);
    let (y0, y1) = pad(y0, y1);
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| anyhow!("{e}"))?;
    chart
        .configure_mesh()
        .x_desc(&p.x_label)
        .y_desc(&p.y_label)
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(|e| anyhow!("{e}"))?;
    for (k, s) in p.series.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        let pts: Vec<(f64, f64)> =
            s.points.iter().copied().filter(|(x, y)| x.is_finite() && y.is_finite()).collect();
        let anno = match s.mark {
            Mark::Line => chart
                .draw_series(LineSeries::new(pts, colour.stroke_width(2)))
                .map_err(|e| anyhow!("{e}"))?,
            Mark::Reference => chart
                .draw_series(LineSeries::new(pts, BLACK.stroke_width(1)))
                .map_err(|e| anyhow!("{e}"))?,
            Mark::Points => chart
                .draw_series(pts.into_iter().map(|p| Circle::new(p, 4, colour.filled())))
                .map_err(|e| anyhow!("{e}"))?,
        };
        let legend_colour = if s.mark == Mark::Reference { BLACK } else { colour };
        anno.label(s.name.clone()).legend(move |(x, y)| {
            PathElement::new(vec![(x, y), (x + 16, y)], legend_colour.stroke_width(2))
        });
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 12))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| anyhow!("{e}"))?;
    Ok(())
}
