//! The PNG plots at the end of a run: the energy history, the probes against their analytic
//! curve, the runout history and the final deposit over the ground.

use std::path::Path;

use mpm_scene::envelope::{self, Envelope};
use mpm_scene::{RunoutMetrics, Scene, ground_height};
use mpm_solver::Vector;

use crate::OutputError;
use crate::checkpoint::History;
use crate::csv::EnergyRow;
use crate::plots::{self, Chart, Series, Style};

/// The particles drawn in the deposit plot.
pub struct Deposit<'a> {
    /// final positions (m).
    pub positions: &'a [Vector],
    /// initial positions (m).
    pub initial: &'a [Vector],
    /// simulated time of the final positions (s).
    pub time: f64,
}

/// draws the run's plots into `plot_dir` from its `history` and the `deposit`.
pub fn plots(
    plot_dir: &Path,
    scene: &Scene,
    h: &History,
    deposit: &Deposit<'_>,
) -> Result<(), OutputError> {
    let r = scene.resolved();
    energy(plot_dir, &h.energy, "energy (J/m)")?;
    if !r.output.probes.is_empty() {
        probes(plot_dir, scene, h, deposit.time)?;
    }
    runout(plot_dir, &h.runout)?;
    final_deposit(plot_dir, scene, deposit)
}

/// The particles of a 3D run in plan, (x, −z) (north up, as the hazard maps), for its deposit
/// plot.
pub struct PlanDeposit {
    /// final (x, −z) (m).
    pub positions: Vec<(f64, f64)>,
    /// initial (x, −z) (m).
    pub initial: Vec<(f64, f64)>,
    /// simulated time of the final positions (s).
    pub time: f64,
}

/// draws a 3D run's plots into `plot_dir`: `energy.png` (J), `runout.png` (measured in the
/// vertical plane of the runout direction) and `deposit.png`, the particles in plan.
pub fn space_plots(
    plot_dir: &Path,
    energy_rows: &[EnergyRow],
    runout_rows: &[RunoutMetrics],
    deposit: &PlanDeposit,
) -> Result<(), OutputError> {
    energy(plot_dir, energy_rows, "energy (J)")?;
    runout(plot_dir, runout_rows)?;
    let title = format!("Deposit in plan at t = {:.3} s", deposit.time);
    plots::chart(
        &plot_dir.join("deposit.png"),
        &Chart {
            title: &title,
            x_label: "x (m)",
            y_label: "−z (m), north up as in maps/",
            size: (900, 900),
            equal_aspect: true,
        },
        // the final particles first, the initial ones over them (the release is the smaller
        // area of the two)
        &[
            Series {
                name: "final".into(),
                points: deposit.positions.clone(),
                style: Style::Points,
                color: 0,
            },
            Series {
                name: "initial".into(),
                points: deposit.initial.clone(),
                style: Style::Points,
                color: 6,
            },
        ],
    )
}

/// `energy.png`: the ledger's terms over time, `unit` the y axis's label.
fn energy(plot_dir: &Path, rows: &[EnergyRow], unit: &str) -> Result<(), OutputError> {
    let e0 = rows.first().map_or(0.0, |r| r.ledger.potential);
    let line = |name: &str, color, f: &dyn Fn(&EnergyRow) -> f64| Series {
        name: name.into(),
        points: rows.iter().map(|row| (row.time, f(row))).collect(),
        style: Style::Line,
        color,
    };
    plots::chart(
        &plot_dir.join("energy.png"),
        &Chart {
            title: "Energy history",
            x_label: "time (s)",
            y_label: unit,
            size: (900, 560),
            equal_aspect: false,
        },
        &{
            let mut lines = vec![
                line("kinetic", 0, &|r| r.ledger.kinetic),
                line("strain", 2, &|r| r.ledger.strain),
                line("potential − initial", 4, &|r| r.ledger.potential - e0),
                line("dissipated", 1, &|r| r.ledger.dissipated()),
                line("external work", 5, &|r| r.ledger.external_work),
                line("residual (error)", 6, &|r| r.ledger.residual),
            ];
            // what left through outflow sides (its potential leaves "potential − initial" too)
            if rows.iter().any(|r| r.ledger.outflow != 0.0) {
                lines.push(line("carried out (outflow)", 3, &|r| r.ledger.outflow));
            }
            lines
        },
    )?;
    Ok(())
}

/// `probes.png`: the probes' displacement, with the scene's analytic curve.
fn probes(plot_dir: &Path, scene: &Scene, h: &History, time: f64) -> Result<(), OutputError> {
    let r = scene.resolved();
    let mut series = Vec::new();
    for (k, &i) in r.output.probes.iter().enumerate() {
        series.push(Series {
            name: {
                let x = r.seeds[i].position;
                format!("probe {} (particle {i}, from ({:.3}, {:.3}) m)", k + 1, x.x, x.y)
            },
            points: h.probes.iter().filter(|p| p.probe == k).map(|p| (p.time, p.along)).collect(),
            style: Style::Line,
            color: k,
        });
    }
    let label = match r.output.reference {
        Some(rf) => {
            let t_end = time;
            let n = 200;
            series.push(Series {
                name: format!("{} (rigid block)", rf.curve.name()),
                points: (0..=n)
                    .map(|j| {
                        let t = t_end * j as f64 / n as f64;
                        (t, rf.displacement(t))
                    })
                    .collect(),
                style: Style::Dashed,
                color: 1,
            });
            if rf.direction == Vector::X {
                "displacement along x (m)"
            } else if rf.direction == -Vector::X {
                "displacement along −x (m)"
            } else {
                "displacement down the slope (m)"
            }
        }
        None => "displacement along x (m)",
    };
    plots::chart(
        &plot_dir.join("probes.png"),
        &Chart {
            title: "Probe displacement",
            x_label: "time (s)",
            y_label: label,
            size: (900, 560),
            equal_aspect: false,
        },
        &series,
    )?;
    Ok(())
}

/// `runout.png`: front, tail and centre-of-mass travel over time.
fn runout(plot_dir: &Path, rows: &[RunoutMetrics]) -> Result<(), OutputError> {
    let runout_line = |name: &str, color, f: &dyn Fn(&RunoutMetrics) -> f64| Series {
        name: name.into(),
        points: rows.iter().map(|m| (m.time, f(m))).collect(),
        style: Style::Line,
        color,
    };
    plots::chart(
        &plot_dir.join("runout.png"),
        &Chart {
            title: "Runout",
            x_label: "time (s)",
            y_label: "position / thickness (m)",
            size: (900, 560),
            equal_aspect: false,
        },
        &[
            runout_line("front", 0, &|m| m.front_x),
            runout_line("tail", 2, &|m| m.tail_x),
            runout_line("max thickness", 3, &|m| m.max_thickness),
            runout_line("centre-of-mass travel", 4, &|m| m.com_travel),
        ],
    )?;
    Ok(())
}

/// `deposit.png`: the particles at the end over their initial place, the free surface, the
/// ground, and the observed deposit's surface when the scene gives one.
fn final_deposit(plot_dir: &Path, scene: &Scene, deposit: &Deposit<'_>) -> Result<(), OutputError> {
    let Deposit { positions, initial, time } = *deposit;
    let r = scene.resolved();
    let column = r.grid.column_width();
    let xs: Vec<f64> = positions.iter().chain(initial).map(|q| q.x).collect();
    let lo = xs.iter().copied().fold(f64::INFINITY, f64::min) - 0.5;
    let hi = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max) + 0.5;
    let mut ground_sorted: Vec<(f64, f64)> = r
        .ground
        .iter()
        .filter(|g| g.x > lo && g.x < hi)
        .map(|g| (g.x, g.y))
        .chain([lo, hi].map(|x| (x, ground_height(&r.ground, x))))
        .collect();
    ground_sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    // the free surface, down to the ground across empty columns (not a line bridging a gap)
    let mut surface: Vec<(f64, f64)> = Vec::new();
    let mut last_x = f64::NEG_INFINITY;
    for (x, top, _) in mpm_scene::surface(positions, &r.ground, r.spacing, column) {
        if x - last_x > 1.5 * column && last_x.is_finite() {
            let (a, b) = (last_x + column, x - column);
            surface.push((a, ground_height(&r.ground, a)));
            surface.extend(r.ground.iter().filter(|g| g.x > a && g.x < b).map(|g| (g.x, g.y)));
            surface.push((b, ground_height(&r.ground, b)));
        }
        surface.push((x, top));
        last_x = x;
    }
    let title = format!("Deposit at t = {:.3} s", time);
    plots::chart(
        &plot_dir.join("deposit.png"),
        &Chart {
            title: &title,
            x_label: "x (m)",
            y_label: "y (m)",
            size: (1000, 560),
            equal_aspect: true,
        },
        &[
            Series {
                name: "initial".into(),
                points: initial.iter().map(|q| (q.x, q.y)).collect(),
                style: Style::Points,
                color: 6,
            },
            Series {
                name: "final".into(),
                points: positions.iter().map(|q| (q.x, q.y)).collect(),
                style: Style::Points,
                color: 0,
            },
            Series { name: "free surface".into(), points: surface, style: Style::Line, color: 1 },
            Series { name: "ground".into(), points: ground_sorted, style: Style::Thick, color: 5 },
        ]
        .into_iter()
        .chain(r.output.observed.as_ref().map(|o| Series {
            name: "observed deposit".into(),
            points:
                o.points.iter().map(|p| (p[0], ground_height(&r.ground, p[0]) + p[1])).collect(),
            style: Style::Line,
            color: 3,
        }))
        .collect::<Vec<_>>(),
    )
}

/// `envelope.png`: along the path, the ground with the highest flow surface and the final
/// deposit above it (and, at x of each of `edges`, the ends of the grid the scene left
/// undeclared that the flow reached, as a thick vertical line), then the three maxima: flow
/// thickness, speed (depth-averaged and of a particle) and impact pressure.
pub fn envelope(
    plot_dir: &Path,
    e: &Envelope,
    deposit: &[(f64, f64, f64)],
    edges: &[f64],
) -> Result<(), OutputError> {
    let along = |f: &dyn Fn(&envelope::Station) -> f64| -> Vec<(f64, f64)> {
        e.stations.iter().filter(|s| s.arrival.is_some()).map(|s| (s.x, f(s))).collect()
    };
    let series =
        |name: &str, points, style, color| Series { name: name.into(), points, style, color };
    let ground: Vec<(f64, f64)> = e.stations.iter().map(|s| (s.x, s.ground)).collect();
    let (low, high) = e.stations.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| {
        (a.min(s.ground), b.max(s.ground + s.max_thickness))
    });
    let mut profile = vec![
        series("ground", ground, Style::Thick, 6),
        series("ground + max thickness", along(&|s| s.ground + s.max_thickness), Style::Line, 1),
        series(
            "ground + deposit thickness",
            deposit.iter().filter(|d| d.2 > 0.0).map(|d| (d.0, d.1 + d.2)).collect(),
            Style::Points,
            0,
        ),
    ];
    for &x in edges.iter().filter(|_| low <= high) {
        profile.push(series("grid edge reached", vec![(x, low), (x, high)], Style::Thick, 3));
    }
    let thickness = [series("max thickness", along(&|s| s.max_thickness), Style::Line, 1)];
    let speed = [
        series("depth-averaged", along(&|s| s.max_mean_speed), Style::Line, 0),
        series("particle", along(&|s| s.max_speed), Style::Dashed, 3),
    ];
    let pressure = [series("max ρū²", along(&|s| 1e-3 * s.max_pressure), Style::Line, 4)];
    let chart = |title, y_label| Chart {
        title,
        x_label: "x (m)",
        y_label,
        size: (0, 0),
        equal_aspect: false,
    };
    plots::figure(
        &plot_dir.join("envelope.png"),
        &[
            (chart("Path: ground, highest flow surface, deposit", "height (m)"), &profile[..]),
            (
                chart("Maximum flow thickness (normal to the ground)", "thickness (m)"),
                &thickness[..],
            ),
            (chart("Maximum speed", "speed (m/s)"), &speed[..]),
            (chart("Maximum impact pressure", "pressure (kPa)"), &pressure[..]),
        ],
        1,
        (1000, 1400),
    )
}
