//! The figures of `cargo xtask`'s reports: panels of line and scatter charts, drawn by the
//! project's one chart module (`mpm_output::plots`, plotters with an embedded font).

use std::path::Path;

use anyhow::{Result, anyhow};
use mpm_output::plots::{self, Chart, Style};

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    /// a polyline.
    Line,
    /// a dashed polyline, for references.
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

/// draws `panels` side by side (`columns` per row) into a PNG of `width` × `height` pixels,
/// with the CLI's chart module (one chart code for the whole project): each series takes the
/// palette colour of its position, references are dashed.
pub fn figure(
    path: &Path,
    panels: &[Panel],
    columns: usize,
    width: u32,
    height: u32,
) -> Result<()> {
    let charts: Vec<(Chart<'_>, Vec<plots::Series>)> = panels
        .iter()
        .map(|p| {
            let chart = Chart {
                title: &p.title,
                x_label: &p.x_label,
                y_label: &p.y_label,
                size: (width, height),
                equal_aspect: false,
            };
            let series = p
                .series
                .iter()
                .enumerate()
                .map(|(k, s)| plots::Series {
                    name: s.name.clone(),
                    points: s.points.clone(),
                    style: match s.mark {
                        Mark::Line => Style::Line,
                        Mark::Reference => Style::Dashed,
                        Mark::Points => Style::Points,
                    },
                    color: k,
                })
                .collect();
            (chart, series)
        })
        .collect();
    let charts: Vec<(Chart<'_>, &[plots::Series])> =
        charts.iter().map(|(c, s)| (c.clone(), s.as_slice())).collect();
    plots::figure(path, &charts, columns, (width, height)).map_err(|e| anyhow!("{e}"))
}
