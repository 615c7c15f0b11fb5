//! `cargo xtask study`: the speed/accuracy trade, measured.
//!
//! Cases: the horizontal and inclined (30°) sliding blocks against eqs 21–22, the vibrating bar
//! against its exact period, and the sand flume's runout (no exact answer: the finest run is the
//! reference, and the table says so). Around a baseline per case, one factor at a time: cell size
//! (a refinement ladder of at least four levels per shape function), particles per cell (1, 4, 9,
//! 16), scheme (USL, MUSL, USF, USAVG), shape functions (bilinear, uGIMP, B-spline on regular grids;
//! bilinear only on the terrain grid), Courant number (0.05–0.8). A further sweep, scheme ×
//! shape function × Courant on the sliding block and the bar, feeds the presets.
//!
//! Output in `target/study/`: `runs.csv`, `orders.csv`, `pareto.csv`, `presets.md`, PNG plots,
//! and the preset table written into `crates/mpm-scene/src/presets.rs`.
//!
//! Runs are timed one at a time (never two runs at once) so that wall times are comparable.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::time::Instant;

use anyhow::Result;
use mpm_solver::Scheme;
use mpm_tests::abe2005::{eq21_distance, eq22_travel};
use mpm_tests::manufactured::manufactured;
use mpm_tests::{
    CaseError, Cost, Discretisation, MassMatrix, ShapeKind, sliding_horizontal, sliding_inclined,
    vibrating_bar,
};

use crate::plot::{Mark, Panel, Series, figure};
use crate::runs::{COURANTS, Case, Run};
use crate::table::{Status, Table, num, pct};

/// (value, error, energy, cost) of one case run.
type Measure = Result<(f64, f64, f64, Cost), CaseError>;

fn measure(case: Case, d: &Discretisation) -> Measure {
    match case {
        Case::Horizontal => sliding_horizontal(d).map(|r| {
            let reference = eq21_distance();
            (r.distance, (r.distance - reference).abs() / reference, r.worst_residual, r.cost)
        }),
        Case::Inclined => sliding_inclined(30.0, 2.0, 0.0, d).map(|r| {
            let reference = eq22_travel(30.0, 2.0);
            (r.travel, (r.travel - reference).abs() / reference, r.worst_residual, r.cost)
        }),
        Case::Bar => vibrating_bar(d).map(|r| {
            (
                r.period_ratio * mpm_tests::bar::period(),
                (r.period_ratio - 1.0).abs(),
                r.worst_energy,
                r.cost,
            )
        }),
        Case::Manufactured => manufactured(d).map(|r| {
            (
                r.rms_error * mpm_tests::manufactured::AMPLITUDE,
                r.rms_error,
                r.energy_residual,
                r.cost,
            )
        }),
        Case::Flume => {
            Err(CaseError::Setup("the flume runs through mpm-run (see flume.rs)".into()))
        }
    }
}

/// Runs cases once per distinct setting and remembers them (a baseline belongs to several sweeps).
struct Runner {
    cache: BTreeMap<String, Run>,
    runs: Vec<Run>,
}

impl Runner {
    fn run(&mut self, case: Case, sweep: &str, d: Discretisation) {
        let key = format!("{case:?} {d:?}");
        if let Some(r) = self.cache.get(&key) {
            let mut r = r.clone();
            r.sweep = sweep.into();
            self.runs.push(r);
            return;
        }
        let t0 = Instant::now();
        let m = measure(case, &d);
        let wall = t0.elapsed().as_secs_f64();
        let run = match m {
            Ok((value, error, energy, cost)) => Run {
                case,
                sweep: sweep.into(),
                d,
                value,
                error,
                energy,
                wall,
                cost,
                failure: None,
            },
            Err(e) => Run {
                case,
                sweep: sweep.into(),
                d,
                value: f64::NAN,
                error: f64::NAN,
                energy: f64::NAN,
                wall,
                cost: Cost::default(),
                failure: Some(e.to_string()),
            },
        };
        eprintln!(
            "  {:<19} {:<14} h {:<7} ppc {} {:<5} {:<8} C {:<5} error {:<12} wall {:.2} s{}",
            case.name(),
            sweep,
            d.cell,
            d.ppc * d.ppc,
            d.scheme.name(),
            d.shape.name(),
            d.courant,
            pct(run.error),
            wall,
            run.failure.as_deref().map(|f| format!("  FAILED: {f}")).unwrap_or_default()
        );
        self.cache.insert(key, run.clone());
        self.runs.push(run);
    }
}

/// The baseline and ladders of a case.
struct Plan {
    case: Case,
    baseline: Discretisation,
    cells: Vec<f64>,
    shapes: Vec<ShapeKind>,
}

fn plans(quick: bool) -> Vec<Plan> {
    let ladder = |full: &[f64], q: usize| if quick { full[..q].to_vec() } else { full.to_vec() };
    vec![
        Plan {
            case: Case::Horizontal,
            baseline: Discretisation::paper(0.25),
            cells: ladder(&[0.5, 0.25, 0.125, 0.0625], 3),
            shapes: ShapeKind::ALL.to_vec(),
        },
        Plan {
            case: Case::Inclined,
            baseline: Discretisation::paper(0.25),
            cells: ladder(&[0.5, 0.25, 0.125, 0.0625], 3),
            shapes: vec![ShapeKind::Bilinear],
        },
        Plan {
            case: Case::Bar,
            baseline: Discretisation {
                cell: 0.5,
                ppc: 2,
                scheme: Scheme::Usavg,
                shape: ShapeKind::Bilinear,
                courant: 0.1,
                mass: MassMatrix::Lumped,
            },
            cells: ladder(&[1.0, 0.5, 0.25, 0.125], 3),
            shapes: ShapeKind::ALL.to_vec(),
        },
        // Refinement ladders only (the convergence orders): Δt is that of C = 0.1 at 1/64 m on
        // every level, so the ladder measures the spatial error.
        Plan {
            case: Case::Manufactured,
            baseline: mpm_tests::manufactured::baseline(),
            cells: ladder(&[0.125, 0.0625, 0.03125, 0.015625], 3),
            shapes: ShapeKind::ALL.to_vec(),
        },
    ]
}

/// runs the study; `Ok(false)` when a run failed.
pub fn run(quick: bool) -> Result<bool> {
    let start = Instant::now();
    let dir = crate::out_dir("study")?;
    let mut runner = Runner { cache: BTreeMap::new(), runs: Vec::new() };
    for plan in plans(quick) {
        eprintln!("{}:", plan.case.name());
        let b = plan.baseline;
        // Refinement ladders per shape function, with the lumped and the consistent mass matrix
        // (the flume's are in flume.rs).
        for &shape in &plan.shapes {
            for (mass, suffix) in
                [(MassMatrix::Lumped, ""), (MassMatrix::Consistent, "-consistent")]
            {
                for &cell in &plan.cells {
                    let d = Discretisation { cell, shape, mass, ..b };
                    runner.run(plan.case, &format!("cell-{}{suffix}", shape.name()), d);
                }
            }
        }
        if plan.case == Case::Manufactured {
            continue;
        }
        for ppc in 1..=4 {
            runner.run(plan.case, "ppc", Discretisation { ppc, ..b });
        }
        for scheme in Scheme::ALL {
            runner.run(plan.case, "scheme", Discretisation { scheme, ..b });
        }
        for courant in COURANTS {
            runner.run(plan.case, "courant", Discretisation { courant, ..b });
        }
        // The preset sweep: shape × Courant for the two schemes that remap (MUSL, USAVG).
        if plan.case != Case::Inclined {
            let schemes: &[Scheme] =
                if quick { &[Scheme::Usavg] } else { &[Scheme::Musl, Scheme::Usavg] };
            for &scheme in schemes {
                for &shape in &plan.shapes {
                    for courant in COURANTS {
                        runner.run(
                            plan.case,
                            "preset-sweep",
                            Discretisation { scheme, shape, courant, ..b },
                        );
                    }
                }
            }
        }
    }
    let flume = crate::flume::study(quick, &mut runner.runs);
    let runs = runner.runs;

    // CSV of every run.
    let mut csv = String::from(
        "case,sweep,cell_m,particles_per_cell,scheme,shape,mass,courant,value,error,energy_residual,wall_s,steps,particles,particle_steps_per_s,failure\n",
    );
    for r in &runs {
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{:?},{},{:e},{:e},{:e},{:.4},{},{},{:.4e},{}",
            r.case.name(),
            r.sweep,
            r.d.cell,
            r.d.ppc * r.d.ppc,
            r.d.scheme.name(),
            r.d.shape.name(),
            r.d.mass,
            r.d.courant,
            r.value,
            r.error,
            r.energy,
            r.wall,
            r.cost.steps,
            r.cost.particles,
            r.throughput(),
            r.failure.as_deref().unwrap_or("").replace(',', ";")
        );
    }
    std::fs::write(dir.join("runs.csv"), csv)?;

    // Convergence orders: least-squares slope of ln(error) against ln(h) per case × shape ladder.
    let mut orders =
        Table::new(&["case", "shape", "scheme", "cells (m)", "errors", "observed order"]);
    let mut order_csv = String::from("case,shape,levels,order\n");
    let mut conv_panels = Vec::new();
    let mut cases: Vec<Case> = runs.iter().map(|r| r.case).collect();
    cases.dedup();
    for &case in &cases {
        let mut series = Vec::new();
        let ladders = ShapeKind::ALL.into_iter().flat_map(|s| [(s, ""), (s, "-consistent")]);
        for (shape, mass) in ladders {
            let sweep = format!("cell-{}{mass}", shape.name());
            let pts: Vec<&Run> = runs
                .iter()
                .filter(|r| r.case == case && r.sweep == sweep && r.ok() && r.error > 0.0)
                .collect();
            if pts.len() < 2 {
                continue;
            }
            let xy: Vec<(f64, f64)> = pts.iter().map(|r| (r.d.cell.ln(), r.error.ln())).collect();
            let order = slope(&xy);
            orders.push(
                vec![
                    case.name().into(),
                    format!("{}{mass}", shape.name()),
                    pts[0].d.scheme.name().into(),
                    pts.iter().map(|r| num(r.d.cell)).collect::<Vec<_>>().join(", "),
                    pts.iter().map(|r| pct(r.error)).collect::<Vec<_>>().join(", "),
                    format!("{order:.2}"),
                ],
                Status::Info,
            );
            let _ = writeln!(
                order_csv,
                "{},{}{mass},{},{order:.4}",
                case.name(),
                shape.name(),
                pts.len()
            );
            series.push(Series::new(
                format!("{}{mass} (order {order:.2})", shape.name()),
                pts.iter().map(|r| (r.d.cell.log10(), r.error.log10())).collect(),
                Mark::Line,
            ));
        }
        if !series.is_empty() {
            conv_panels.push(Panel {
                title: format!("{}: error vs cell size", case.name()),
                x_label: "log10 cell size (m)".into(),
                y_label: "log10 relative error".into(),
                series,
            });
        }
    }
    std::fs::write(dir.join("orders.csv"), order_csv)?;

    // Pareto fronts of error against wall time, per case.
    let mut pareto_csv =
        String::from("case,sweep,cell_m,particles_per_cell,scheme,shape,courant,error,wall_s\n");
    let mut pareto_panels = Vec::new();
    for &case in &cases {
        let all: Vec<&Run> =
            runs.iter().filter(|r| r.case == case && r.ok() && r.error > 0.0).collect();
        let front = pareto(&all);
        for r in &front {
            let _ = writeln!(
                pareto_csv,
                "{},{},{},{},{},{},{},{:e},{:.4}",
                case.name(),
                r.sweep,
                r.d.cell,
                r.d.ppc * r.d.ppc,
                r.d.scheme.name(),
                r.d.shape.name(),
                r.d.courant,
                r.error,
                r.wall
            );
        }
        pareto_panels.push(Panel {
            title: format!("{}: error vs wall time", case.name()),
            x_label: "log10 wall time (s)".into(),
            y_label: "log10 relative error".into(),
            series: vec![
                Series::new(
                    "all runs",
                    all.iter().map(|r| (r.wall.log10(), r.error.log10())).collect(),
                    Mark::Points,
                ),
                Series::new(
                    "Pareto front",
                    front.iter().map(|r| (r.wall.log10(), r.error.log10())).collect(),
                    Mark::Line,
                ),
            ],
        });
    }
    std::fs::write(dir.join("pareto.csv"), pareto_csv)?;
    figure(
        &dir.join("convergence.png"),
        &conv_panels,
        2,
        1040,
        420 * conv_panels.len().div_ceil(2) as u32,
    )?;
    figure(
        &dir.join("pareto.png"),
        &pareto_panels,
        2,
        1040,
        420 * pareto_panels.len().div_ceil(2) as u32,
    )?;

    // Presets from the preset sweep.
    let presets = crate::presets::derive(&runs);
    let mut report = String::new();
    let _ = writeln!(
        report,
        "# Speed/accuracy study (`cargo xtask study{}`)\n",
        if quick { " --quick" } else { "" }
    );
    let failures = runs.iter().filter(|r| !r.ok()).count();
    let _ = writeln!(
        report,
        "{} runs, {failures} failed, {:.1} s wall time in all.\n",
        runs.len(),
        start.elapsed().as_secs_f64()
    );
    for r in runs.iter().filter(|r| !r.ok()) {
        let _ = writeln!(
            report,
            "- failed (a measured outcome, not an error of the study): {} {} h {} ppc {} {} {} C {}: {}",
            r.case.name(),
            r.sweep,
            r.d.cell,
            r.d.ppc * r.d.ppc,
            r.d.scheme.name(),
            r.d.shape.name(),
            r.d.courant,
            r.failure.as_deref().unwrap_or("non-finite error")
        );
    }
    let _ = writeln!(report);
    let _ = writeln!(report, "Errors:\n");
    for &case in &cases {
        let _ = writeln!(report, "- {}: {}", case.name(), case.error_definition());
    }
    let _ = writeln!(report, "\n## Observed convergence orders\n\n{}", orders.markdown());
    let _ = writeln!(report, "![convergence](convergence.png)\n\n![pareto](pareto.png)\n");
    report.push_str(&flume);
    match &presets {
        Ok(p) => {
            report.push_str(&p.markdown);
            std::fs::write(dir.join("presets.md"), &p.markdown)?;
            if !quick {
                crate::presets::write_table(&p.chosen)?;
                println!("wrote the presets into crates/mpm-scene/src/presets.rs");
            }
        }
        Err(e) => {
            let _ = writeln!(report, "\nNo presets: {e}\n");
        }
    }
    std::fs::write(dir.join("report.md"), &report)?;
    println!("{}", orders.text());
    if let Ok(p) = &presets {
        println!("{}", p.table.text());
    }
    println!(
        "{} runs, {failures} failed, {:.1} s; report: {}",
        runs.len(),
        start.elapsed().as_secs_f64(),
        dir.join("report.md").display()
    );
    // A configuration that fails (e.g. USL's bar inverting) is a measured outcome, listed in the
    // CSV and the report; only a study that cannot derive its presets fails the command.
    Ok(presets.is_ok())
}

/// least-squares slope of y against x.
pub fn slope(xy: &[(f64, f64)]) -> f64 {
    let n = xy.len() as f64;
    let (mx, my) = xy.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let (sxy, sxx) = xy
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + (x - mx) * (y - my), b + (x - mx) * (x - mx)));
    sxy / sxx
}

/// the runs not dominated in (wall time, error), by increasing wall time.
pub fn pareto<'a>(runs: &[&'a Run]) -> Vec<&'a Run> {
    let mut sorted: Vec<&Run> = runs.to_vec();
    sorted.sort_by(|a, b| a.wall.total_cmp(&b.wall).then(a.error.total_cmp(&b.error)));
    let mut front: Vec<&Run> = Vec::new();
    for r in sorted {
        if front.last().is_none_or(|l| r.error < l.error) {
            front.push(r);
        }
    }
    front
}
