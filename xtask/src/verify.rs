//! `cargo xtask verify`: every verification case of the paper (and beyond it) against its reference, one table,
//! `target/verify/report.md` and PNG plots. A failed row (or a case that could not run) makes the
//! command exit non-zero.
//!
//! The solver-level cases call the drivers of the `mpm-tests` library, the same code the workspace
//! tests assert on; the element tests call `mpm_constitutive::element_test`.

mod flume3d;
mod mixed;
mod mohr_coulomb;
mod open_core;
mod three_d;

use std::fmt::Write as _;
use std::time::Instant;

use anyhow::Result;
use mpm_constitutive::element_test::{
    MixedControl, PathPoint, QUASI_STATIC_STEP, run_mixed, simple_shear, uniaxial_plane_strain,
};
use mpm_constitutive::{
    ConeMatch, ConstitutiveError, ConstitutiveModel, DpState, DruckerPrager, DruckerPragerParams,
    SymTensor,
};
use mpm_solver::{Contact, GeostaticSettings, MassMatrix, Scheme, SolverError};
use mpm_tests::abe2005::{eq21_displacement, eq21_distance, eq21_stop_time, eq22_travel};
use mpm_tests::geostatic::SlopeResult;
use mpm_tests::{
    Discretisation, FreeFall, ShapeKind, bar, free_fall, sliding_horizontal, sliding_inclined,
    swirl_momentum_error, vibrating_bar,
};

use crate::plot::{Mark, Panel, Series, figure};
use crate::table::{Status, Table, num, pct};

/// Horizontal sliding distance: the 1 % (the elastic block departs from the rigid one
/// by a few tenths of a percent, measured).
const SLIDING_DISTANCE_REL: f64 = 0.01;
/// Stop time: the 2 % (the stop is smeared by the block's shear vibration, see
/// `mpm_tests::abe2005::STOPPED`).
const SLIDING_STOP_REL: f64 = 0.02;
/// Inclined travel at t = 2 s against eq 22: the 1 %.
const INCLINED_TRAVEL_REL: f64 = 0.01;
/// No-slip case: the base may move 1 mm (elastic shear of the block is not sliding).
const NO_SLIP_BASE: f64 = 1e-3;
/// Momentum in free flight is exact up to rounding over the ~10³ steps taken.
const MOMENTUM_REL: f64 = 1e-10;
/// Energy growth in free flight: the 1 % (symplectic Euler loses ½ M g² Δt t, 0.08 %).
const FLIGHT_ENERGY: f64 = 0.01;
/// Energy growth through the impact under surface contact: the 1 %.
const IMPACT_ENERGY: f64 = 0.01;
/// The impact energy error of the paper's node contact is O(Δt): dividing Δt by 4 must divide it
/// by ≥ 4.
const IMPACT_CONVERGENCE_RATIO: f64 = 0.25;
/// The paper quotes its element-test stresses to four digits: 0.1 %.
const PAPER_REL: f64 = 1e-3;
/// Elastic closed forms through the element driver's 1e-9 Newton tolerance and rounding.
const ROUNDING_REL: f64 = 1e-10;
/// Plastic volume change with ψ = 0: zero up to rounding of strain sums (strains ≤ 1e-2).
const PLASTIC_VOLUME_ABS: f64 = 1e-12;
/// Vibrating bar: period and energy within the 1 % over five periods.
const BAR_REL: f64 = 0.01;
/// Momentum balance with the consistent mass matrix: its 1e-13 solve tolerance plus the rounding
/// of a few hundred nodal sums.
const CONSISTENT_MOMENTUM_REL: f64 = 1e-12;

/// The K0 layer's stresses, relative: the 1e-6 (the discrete answer is exact; measured
/// ~1e-13).
const GEOSTATIC_K0_REL: f64 = 1e-6;

/// Manufactured solution at A = 0.02 (strains to ±12.6 %), uGIMP and B-splines with either
/// matrix: the observed order of the RMS displacement error between 1/16 and 1/64 m must be at
/// least 1 (measured 1.4 and 1.7 lumped, 1.1 and 1.1 consistent: large strains limit them, as
/// Wallstedt & Guilkey found for GIMP; below 1 a method has lost convergence). The small-amplitude
/// rows are the ones that catch a first-order wall error (B-splines measured 1.0–1.2 at either
/// amplitude before the ghosts behind fixed walls were tied to their images).
const MMS_LARGE_ORDER: f64 = 1.0;
/// At A = 1e-4 (no cell crossing, small strain) second order: measured 2.4 (uGIMP) and 1.9
/// (B-spline) lumped, 1.8 B-spline consistent, between 1/16 and 1/64 m; the bounds leave 0.1–0.4.
const MMS_SMALL_ORDER: [f64; 3] = [2.0, 1.8, 1.5];
/// The energy ledger with the body force's work booked as external work, uGIMP at A = 1e-4 and
/// 1/64 m: measured 6.6e-4 of the initial kinetic energy, the first-order time error at this Δt
/// (1.1e-2 at C = 0.1 of 1/64 m); 5e-3 leaves room. (At A = 0.02 the ledger's small-strain
/// energy σ²V/2E is itself off by O(strain): 1.1e-2.)
const MMS_ENERGY: f64 = 5e-3;
/// B-splines behind fixed walls: the error at 1/8 m may change by 10 % when Δt shrinks eightfold
/// (the ghost's acceleration once kicked the particles by a step-size-free amount each step:
/// 0.15 → 1.84 of A for Δt/32).
const MMS_DT_REL: f64 = 0.1;

const HEADER: [&str; 8] =
    ["case", "quantity", "reference", "source", "computed", "error", "tolerance", "result"];

/// Collects the verification rows.
struct Rows {
    table: Table,
}

impl Rows {
    /// appends a row with its result word.
    fn push(&mut self, mut cells: Vec<String>, status: Status) {
        cells.push(status.word().into());
        self.table.push(cells, status);
    }

    /// relative check |c − r| ≤ tol |r|.
    fn rel(
        &mut self,
        case: &str,
        quantity: &str,
        reference: f64,
        source: &str,
        computed: f64,
        tol: f64,
    ) {
        let err = (computed - reference).abs() / reference.abs();
        let ok = err <= tol;
        self.push(
            vec![
                case.into(),
                quantity.into(),
                num(reference),
                source.into(),
                num(computed),
                pct(err),
                format!("≤ {}", pct(tol)),
            ],
            status(ok),
        );
    }

    /// upper bound: computed ≤ limit (the reference is stated in words).
    fn at_most(
        &mut self,
        (case, quantity): (&str, &str),
        reference: &str,
        source: &str,
        computed: f64,
        limit: f64,
        as_pct: bool,
    ) {
        let ok = computed <= limit && computed.is_finite();
        let f = |x: f64| if as_pct { pct(x) } else { num(x) };
        self.push(
            vec![
                case.into(),
                quantity.into(),
                reference.into(),
                source.into(),
                f(computed),
                f(computed),
                format!("≤ {}", f(limit)),
            ],
            status(ok),
        );
    }

    /// lower bound: computed ≥ limit (the reference is stated in words).
    fn at_least(
        &mut self,
        (case, quantity): (&str, &str),
        reference: &str,
        source: &str,
        computed: f64,
        limit: f64,
    ) {
        let ok = computed >= limit && computed.is_finite();
        self.push(
            vec![
                case.into(),
                quantity.into(),
                reference.into(),
                source.into(),
                num(computed),
                num(computed),
                format!("≥ {}", num(limit)),
            ],
            status(ok),
        );
    }

    /// a reported value with no exact reference.
    fn info(
        &mut self,
        case: &str,
        quantity: &str,
        reference: &str,
        source: &str,
        computed: String,
    ) {
        self.push(
            vec![
                case.into(),
                quantity.into(),
                reference.into(),
                source.into(),
                computed,
                "–".into(),
                "–".into(),
            ],
            Status::Info,
        );
    }

    /// a case that could not run.
    fn failed(&mut self, case: &str, quantity: &str, err: &dyn std::fmt::Display) {
        self.push(
            vec![
                case.into(),
                quantity.into(),
                "–".into(),
                "–".into(),
                format!("error: {err}"),
                "–".into(),
                "–".into(),
            ],
            Status::Fail,
        );
    }
}

fn status(ok: bool) -> Status {
    if ok { Status::Pass } else { Status::Fail }
}

/// runs the verification; `Ok(false)` when a row failed.
pub fn run(quick: bool) -> Result<bool> {
    let start = Instant::now();
    let dir = crate::out_dir("verify")?;
    let mut rows = Rows { table: Table::new(&HEADER) };
    let mut notes = String::new();
    let mut figures = Vec::new();

    // Granular flows come to rest (issue 37): the flume run past its stop and the column
    // collapses, the longest rows, run on a thread of their own beside the others (most scenes
    // here are small enough to use one thread each); their rows keep their place in the table.
    let rest_dir = dir.clone();
    let rest = std::thread::spawn(move || -> Result<Table> {
        let mut table = Table::new(&HEADER);
        crate::flume::rest_rows(&mut table, &rest_dir.join("flume_60s"));
        crate::column::verify_rows(&mut table, &rest_dir, quick)?;
        Ok(table)
    });

    // Horizontal and inclined sliding (§5).
    let mut sliding_panels = Vec::new();
    let cells: &[f64] = if quick { &[0.5] } else { &[0.5, 0.125] };
    let mut horizontal = Vec::new();
    for &cell in cells {
        let case = format!("horizontal sliding, {cell} m cells");
        match sliding_horizontal(&Discretisation::paper(cell)) {
            Ok(r) => {
                rows.rel(
                    &case,
                    "travel until stop (m)",
                    eq21_distance(),
                    "eq 21: v0²/(2μg)",
                    r.distance,
                    SLIDING_DISTANCE_REL,
                );
                rows.rel(
                    &case,
                    "time mean speed < 0.1 m/s (s)",
                    eq21_stop_time(),
                    "eq 21: (v0 − 0.1)/(μg)",
                    r.stop_time,
                    SLIDING_STOP_REL,
                );
                rows.info(
                    &case,
                    "worst |energy residual| / KE0",
                    "no exact value",
                    "energy ledger",
                    pct(r.worst_residual),
                );
                horizontal.push(Series::new(format!("MPM, {cell} m cells"), r.history, Mark::Line));
            }
            Err(e) => rows.failed(&case, "travel until stop", &e),
        }
    }
    let rigid: Vec<(f64, f64)> =
        (0..=200).map(|k| k as f64 * 0.02).map(|t| (t, eq21_displacement(t))).collect();
    horizontal.push(Series::new("eq 21 (rigid block)", rigid, Mark::Reference));
    sliding_panels.push(Panel {
        title: "Horizontal sliding, μ = 0.3, v0 = 10 m/s".into(),
        x_label: "t (s)".into(),
        y_label: "displacement (m)".into(),
        series: horizontal,
    });
    let mut inclined = Vec::new();
    match sliding_inclined(30.0, 2.0, 0.0, &Discretisation::paper(0.25)) {
        Ok(r) => {
            rows.rel(
                "inclined sliding 30°, 0.25 m",
                "travel at t = 2 s (m)",
                eq22_travel(30.0, 2.0),
                "eq 22: ½ g(sinθ − μcosθ)t², a = 2.356",
                r.travel,
                INCLINED_TRAVEL_REL,
            );
            inclined.push(Series::new("MPM 30°", r.history, Mark::Line));
        }
        Err(e) => rows.failed("inclined sliding 30°", "travel at t = 2 s", &e),
    }
    match sliding_inclined(15.0, 1.5, 0.5, &Discretisation::paper(0.25)) {
        Ok(r) => {
            rows.at_most(
                ("inclined 15° (μ > tanθ)", "|base travel| at 1.5 s (m)"),
                "0 (sticks)",
                "μ = 0.3 > tan 15° = 0.268",
                r.base_travel.abs(),
                NO_SLIP_BASE,
                false,
            );
            inclined.push(Series::new("MPM 15° (sticks)", r.history, Mark::Line));
        }
        Err(e) => rows.failed("inclined 15°", "base travel", &e),
    }
    let eq22: Vec<(f64, f64)> =
        (0..=100).map(|k| k as f64 * 0.02).map(|t| (t, eq22_travel(30.0, t))).collect();
    inclined.push(Series::new("eq 22, 30°", eq22, Mark::Reference));
    sliding_panels.push(Panel {
        title: "Inclined sliding, μ = 0.3".into(),
        x_label: "t (s)".into(),
        y_label: "travel along the slope (m)".into(),
        series: inclined,
    });
    figures.push(("sliding.png", "Sliding blocks against eqs 21 and 22", sliding_panels, 2usize));

    // Free fall (§4).
    let mut ff_panels = Vec::new();
    let mut growth = Vec::new();
    for scheme in Scheme::ALL {
        let case = format!("free fall {}", scheme.name());
        let coarse = match free_fall(scheme, 0.1, Contact::Surface) {
            Ok(r) => r,
            Err(e) => {
                rows.failed(&case, "run", &e);
                continue;
            }
        };
        rows.at_most(
            (&case, "|p_y − (−m g t)| / (m g t) in flight"),
            "0 (exact)",
            "momentum balance",
            coarse.momentum_error,
            MOMENTUM_REL,
            false,
        );
        rows.at_most(
            (&case, "energy growth in flight, C = 0.1"),
            "0",
            "issue bound",
            coarse.flight_growth,
            FLIGHT_ENERGY,
            true,
        );
        rows.at_most(
            (&case, "energy growth over impact, C = 0.1"),
            "0 (elastic impact)",
            "issue bound",
            coarse.overall_growth,
            IMPACT_ENERGY,
            true,
        );
        rows.info(
            &case,
            "stored / floor / residual at 1 s",
            "0 / 0 / 0",
            "surface contact",
            format!(
                "{} / {} / {}",
                pct(coarse.stored_change),
                pct(coarse.constraint_work),
                pct(coarse.residual)
            ),
        );
        let mut series = vec![Series::new("surface, C = 0.1", pct_history(&coarse), Mark::Line)];
        let mut node_growth = (f64::NAN, f64::NAN);
        match free_fall(scheme, 0.1, Contact::Node) {
            Ok(node) => {
                rows.info(
                    &case,
                    "node contact (paper): growth over impact, C = 0.1",
                    "0 as Δt → 0",
                    "O(Δt) contact error",
                    pct(node.overall_growth),
                );
                node_growth.0 = node.overall_growth;
                series.push(Series::new("node, C = 0.1", pct_history(&node), Mark::Line));
                if scheme != Scheme::Usl && !quick {
                    match free_fall(scheme, 0.025, Contact::Node) {
                        Ok(fine) => {
                            rows.at_most(
                                (&case, "node contact: growth C = 0.025 / C = 0.1"),
                                "≤ 0.25 (first order)",
                                "Δt / 4",
                                fine.overall_growth / node.overall_growth,
                                IMPACT_CONVERGENCE_RATIO,
                                false,
                            );
                            node_growth.1 = fine.overall_growth;
                        }
                        Err(e) => rows.failed(&case, "node contact at C = 0.025", &e),
                    }
                }
            }
            Err(e) => rows.failed(&case, "node contact", &e),
        }
        growth.push(FreeFallRow { scheme, surface: coarse, node: node_growth });
        ff_panels.push(Panel {
            title: format!("Free fall, {}", scheme.name()),
            x_label: "t (s)".into(),
            y_label: "(E − E0)/E0 (%)".into(),
            series,
        });
    }
    figures.push((
        "free_fall_energy.png",
        "Free fall: total energy of the four schemes",
        ff_panels,
        4,
    ));
    free_fall_note(&mut notes, &growth);

    // Element tests (§6(3)).
    let mut element_panels = Vec::new();
    if let Err(e) = element_tests(&mut rows, &mut element_panels) {
        rows.failed("element tests", "run", &e);
    }
    figures.push((
        "element_tests.png",
        "Element tests: hardening rules and dilatancy",
        element_panels,
        3,
    ));

    // Vibrating bar (Bardenhagen 2002).
    let mut bar_series = Vec::new();
    let mut bars = vec![
        (Scheme::Musl, ShapeKind::Bilinear, 1.0, 0.05),
        (Scheme::Usavg, ShapeKind::Bilinear, 1.0, 0.05),
    ];
    // The workspace test runs these at C = 0.05: at C = 0.1 the energy error is 1.1–1.15 %
    // since the ghost nodes mirror the wall (measured), just over the bound.
    if !quick {
        bars.push((Scheme::Musl, ShapeKind::BSpline, 0.25, 0.05));
        bars.push((Scheme::Usavg, ShapeKind::BSpline, 0.25, 0.05));
    }
    for (scheme, shape, cell, courant) in bars {
        let case = format!("vibrating bar {} {} {cell} m C {courant}", scheme.name(), shape.name());
        match vibrating_bar(&Discretisation {
            cell,
            ppc: 2,
            scheme,
            shape,
            courant,
            mass: MassMatrix::Lumped,
        }) {
            Ok(r) => {
                rows.rel(
                    &case,
                    "period (s)",
                    bar::period(),
                    "2π/ω, ω = (π/2L)√(E/ρ)",
                    r.period_ratio * bar::period(),
                    BAR_REL,
                );
                rows.at_most(
                    (&case, "max |E − E0|/E0, 5 periods"),
                    "0",
                    "energy conservation",
                    r.worst_energy,
                    BAR_REL,
                    true,
                );
                if shape == ShapeKind::Bilinear {
                    let pts = r.history.iter().step_by(20).copied().collect();
                    bar_series.push(Series::new(
                        format!("{} {}", scheme.name(), shape.name()),
                        pts,
                        Mark::Line,
                    ));
                }
            }
            Err(e) => rows.failed(&case, "run", &e),
        }
    }
    consistent_mass_rows(&mut rows, quick);
    manufactured_rows(&mut rows);
    geostatic_rows(&mut rows);
    mixed::rows(&mut rows);
    mohr_coulomb::rows(&mut rows);
    mohr_coulomb::runout_rows(&mut rows, quick);
    three_d::rows(&mut rows, quick);
    flume3d::rows(&mut rows, quick);
    let omega = 2.0 * std::f64::consts::PI / bar::period();
    let exact = (0..=1000)
        .map(|k| k as f64 * 0.05)
        .map(|t| (t, 2.0 * bar::V0 / std::f64::consts::PI * (omega * t).cos()))
        .collect();
    bar_series.push(Series::new("exact (2v0/π) cos ωt", exact, Mark::Reference));
    figures.push((
        "vibrating_bar.png",
        "Vibrating bar: mean velocity",
        vec![Panel {
            title: "Vibrating bar, 1 m cells, C = 0.05".into(),
            x_label: "t (s)".into(),
            y_label: "mean velocity (m/s)".into(),
            series: bar_series,
        }],
        1,
    ));

    // The open core: periodic sides, μ(I) rheology.
    let open_panels = open_core::rows(&mut rows, quick);
    figures.push((
        "open_core.png",
        "μ(I) flow down a periodic slope against Bagnold",
        open_panels,
        1,
    ));

    // Granular flows come to rest (issue 37): the rows of the thread started above.
    let rest = rest.join().map_err(|_| anyhow::anyhow!("the rest rows' thread panicked"))??;
    rows.table.rows.extend(rest.rows);

    // The flume (§7): no exact answer.
    if !quick {
        crate::flume::verify_rows(&mut rows.table, &mut notes);
    }

    let text = rows.table.text();
    println!("{text}");
    let failures = rows.table.failures();
    let elapsed = start.elapsed().as_secs_f64();
    println!("{} rows, {failures} failed, {elapsed:.1} s", rows.table.rows.len());

    let mut report = String::new();
    let _ = writeln!(
        report,
        "# Verification report (`cargo xtask verify{}`)\n",
        if quick { " --quick" } else { "" }
    );
    let _ = writeln!(
        report,
        "{} rows, {failures} failed, {elapsed:.1} s wall time.\n",
        rows.table.rows.len()
    );
    report.push_str(&rows.table.markdown());
    report.push('\n');
    report.push_str(&notes);
    for (file, caption, panels, columns) in figures {
        let width = 520 * columns.min(4) as u32;
        let height = 420 * panels.len().div_ceil(columns) as u32;
        figure(&dir.join(file), &panels, columns, width, height)?;
        let _ = writeln!(report, "\n## {caption}\n\n![{caption}]({file})");
    }
    std::fs::write(dir.join("report.md"), report)?;
    println!("report: {}", dir.join("report.md").display());
    write_docs(&rows.table.markdown(), &notes, rows.table.rows.len(), failures, quick)?;
    Ok(failures == 0)
}

/// The line of `docs/verification.md` below which the last run's table is written.
const DOCS_MARKER: &str = "<!-- generated by `cargo xtask verify` below this line: do not edit -->";

/// writes the table below [`DOCS_MARKER`] in `docs/verification.md`, so that the figures the
/// documentation shows are those of the last run, never copied by hand.
fn write_docs(table: &str, notes: &str, rows: usize, failures: usize, quick: bool) -> Result<()> {
    let path = crate::workspace_root().join("docs").join("verification.md");
    let text = std::fs::read_to_string(&path)?;
    let Some(at) = text.find(DOCS_MARKER) else {
        println!("{} has no generated section; left alone", path.display());
        return Ok(());
    };
    let set =
        if quick { "`cargo xtask verify --quick` (the CI subset)" } else { "`cargo xtask verify`" };
    let mut out = String::from(&text[..at + DOCS_MARKER.len()]);
    let _ = write!(
        out,
        "\n\n## The table of the last run\n\nWritten by {set}: {rows} rows, {failures} failed. \
         The plots are in `target/verify/`, the column collapses one run per line in \
         `target/verify/columns.csv`.\n\n{table}\n{notes}"
    );
    if !out.ends_with('\n') {
        out.push('\n');
    }
    mpm_output::atomic::write(&path, out.as_bytes())?;
    println!("docs: {}", path.display());
    Ok(())
}

fn pct_history(r: &FreeFall) -> Vec<(f64, f64)> {
    r.history.iter().map(|&(t, g)| (t, 100.0 * g)).collect()
}

/// One scheme's free fall: the surface-contact run, and the node-contact growth at C = 0.1 and
/// C = 0.025 (NaN where not run).
struct FreeFallRow {
    scheme: Scheme,
    surface: FreeFall,
    node: (f64, f64),
}

/// the paragraph on the paper's free-fall finding, from the measured growths.
fn free_fall_note(notes: &mut String, rows: &[FreeFallRow]) {
    let _ = writeln!(notes, "## Free fall: the paper's energy finding\n");
    let _ = writeln!(
        notes,
        "The paper (§4) reports USAVG's total energy nearly constant in free fall and MUSL/USF drifting slightly upward. Measured: largest (E − E0)/E0, where E is stored energy plus the dissipation booked in the ledger; then, for surface contact, where the energy is at 1 s.\n"
    );
    let _ = writeln!(
        notes,
        "| scheme | in flight | surface contact, over the impact | stored / floor / residual at 1 s | node contact (paper), C = 0.1 | node contact, C = 0.025 |\n|---|---|---|---|---|---|"
    );
    let show = |x: f64| if x.is_nan() { "–".to_string() } else { pct(x) };
    for r in rows {
        let s = &r.surface;
        let _ = writeln!(
            notes,
            "| {} | {} | {} | {} / {} / {} | {} | {} |",
            r.scheme.name(),
            pct(s.flight_growth),
            pct(s.overall_growth),
            pct(s.stored_change),
            pct(s.constraint_work),
            pct(s.residual),
            show(r.node.0),
            show(r.node.1)
        );
    }
    let _ = writeln!(
        notes,
        "\nNot reproduced as stated. In free flight every scheme conserves energy to well within 1 % (C = 0.1; the step loses ½ M g² Δt t). With the paper's node contact, MUSL, USF and USAVG all gain energy at the impact by similar amounts, an O(Δt) error that converges away when Δt is divided by four; USL dissipates. With surface contact (the default) no scheme gains: the floor's nodes stop the block's base in a perfectly inelastic collision of those nodes, booked as floor work, and FLIP schemes lose a few per cent more (the residual). USAVG is not singled out by this test in our implementation.\n"
    );
}

/// the paper's element-test material (E = 2e6 Pa, ν = 0.3, c = 10 Pa, φ = 40°) with dilatancy ψ,
/// plastic modulus H and mixing M.
fn sand(psi: f64, h: f64, mixing: f64) -> Result<DruckerPrager, ConstitutiveError> {
    DruckerPrager::new(DruckerPragerParams {
        young: 2.0e6,
        poisson: 0.3,
        cohesion: 10.0,
        friction_angle_deg: 40.0,
        dilatancy_angle_deg: psi,
        hardening_modulus: h,
        mixing,
        cone_match: ConeMatch::PlaneStrain,
    })
}

fn element_tests(rows: &mut Rows, panels: &mut Vec<Panel>) -> Result<(), ConstitutiveError> {
    const SRC: &str = "paper §6(3)";
    // First yield: 2e-9 strain per step resolves the yield point to 0.015 %.
    let path = uniaxial_plane_strain(&sand(0.0, 0.0, 1.0)?, SymTensor::ZERO, -2.0e-5, 10_000)?;
    match path.iter().find(|p| p.branch != "elastic") {
        Some(p) => rows.rel(
            "element: uniaxial plane strain",
            "σ_yy at first yield (Pa)",
            -28.50,
            SRC,
            p.stress.yy,
            PAPER_REL,
        ),
        None => rows.failed("element: uniaxial plane strain", "first yield", &"never yielded"),
    }
    let mut uniaxial = Vec::new();
    for (psi, reference, label) in
        [(0.0, -36.15, "steady σ_yy, ψ = 0 (Pa)"), (40.0, -42.89, "steady σ_yy, ψ = φ (Pa)")]
    {
        let path = uniaxial_plane_strain(&sand(psi, 0.0, 1.0)?, SymTensor::ZERO, -2.0e-3, 2_000)?;
        let last = path.last().map_or(f64::NAN, |p| p.stress.yy);
        let source = if psi == 0.0 { SRC } else { "paper §6(3); 2c cosφ/(1 − sinφ)" };
        rows.rel("element: uniaxial plane strain", label, reference, source, last, PAPER_REL);
        uniaxial.push(Series::new(
            format!("ψ = {psi}°"),
            curve(&path, |p| (-1e3 * p.strain.yy, -p.stress.yy)),
            Mark::Line,
        ));
    }
    panels.push(Panel {
        title: "Uniaxial plane strain, H = 0".into(),
        x_label: "−ε_yy (‰)".into(),
        y_label: "−σ_yy (Pa)".into(),
        series: uniaxial,
    });

    // Simple shear under σ_yy = −100 Pa (K0 = 0.5).
    let sigma0 = SymTensor::new(-50.0, -100.0, -50.0, 0.0, 0.0, 0.0);
    let mut dilatancy = Vec::new();
    for psi in [0.0, 10.0, 20.0, 40.0] {
        let m = sand(psi, 0.0, 1.0)?;
        let path = simple_shear(&m, sigma0, 0.005, 5_000)?;
        let k = m.elasticity().bulk_modulus();
        let i1_0 = path[0].stress.trace();
        let plastic_vol =
            |p: &PathPoint<DpState>| p.strain.trace() - (p.stress.trace() - i1_0) / (3.0 * k);
        let case = format!("element: simple shear ψ = {psi}°");
        if psi == 0.0 {
            let g = m.elasticity().shear_modulus();
            let slope = path
                .iter()
                .skip(1)
                .take_while(|p| p.branch == "elastic")
                .map(|p| p.stress.xy / (2.0 * p.strain.xy))
                .last()
                .unwrap_or(f64::NAN);
            rows.rel(&case, "elastic slope τ/γ (Pa)", g, "G = E/(2(1+ν))", slope, ROUNDING_REL);
            let worst = path.iter().map(|p| plastic_vol(p).abs()).fold(0.0, f64::max);
            rows.at_most(
                (&case, "max |plastic ε_v|"),
                "0",
                "flow rule, αg = 0",
                worst,
                PLASTIC_VOLUME_ABS,
                false,
            );
        } else {
            let last = path.last().map_or(f64::NAN, plastic_vol);
            // The flow rule gives Δεᵖ_v = 3 αg Δλ per step exactly.
            let expected: f64 = path.iter().map(|p| 3.0 * m.alpha_g() * p.delta_lambda).sum();
            rows.rel(
                &case,
                "plastic ε_v at γ = 0.5 % (dilates)",
                expected,
                "flow rule Σ 3αgΔλ > 0",
                last,
                1e-6,
            );
        }
        dilatancy.push(Series::new(
            format!("ψ = {psi}°"),
            curve(&path, |p| (1e3 * 2.0 * p.strain.xy, 1e3 * p.strain.trace())),
            Mark::Line,
        ));
    }
    panels.push(Panel {
        title: "Simple shear, σ_yy = −100 Pa".into(),
        x_label: "γ (‰)".into(),
        y_label: "ε_v (‰, dilation > 0)".into(),
        series: dilatancy,
    });

    // Hardening rules: load and unload under σ_xx = −100 Pa, H = 2e5 Pa.
    let mut hardening = Vec::new();
    for (mixing, label) in
        [(1.0, "M = 1 (isotropic)"), (0.5, "M = 0.5 (mixed)"), (0.0, "M = 0 (kinematic)")]
    {
        let m = sand(0.0, 2.0e5, mixing)?;
        let sigma0 = SymTensor::new(-100.0, -100.0, -100.0, 0.0, 0.0, 0.0);
        let step = |d: f64| MixedControl {
            stress_controlled: [true, false, false, false, false, false],
            increment: [0.0, d, 0.0, 0.0, 0.0, 0.0],
            dt: QUASI_STATIC_STEP,
        };
        let load = run_mixed(&m, sigma0, m.initial_state(), &step(-1e-3 / 500.0), 500)?;
        let Some(end) = load.last().copied() else { continue };
        let unload = run_mixed(&m, end.stress, end.state, &step(1e-3 / 500.0), 500)?;
        let mut pts = curve(&load, |p| (-1e3 * p.strain.yy, -p.stress.yy));
        pts.extend(curve(&unload, |p| (-1e3 * (end.strain.yy + p.strain.yy), -p.stress.yy)));
        hardening.push(Series::new(label, pts, Mark::Line));
    }
    panels.push(Panel {
        title: "Hardening rules, H = 2e5 Pa, load–unload".into(),
        x_label: "−ε_yy (‰)".into(),
        y_label: "−σ_yy (Pa)".into(),
        series: hardening,
    });
    Ok(())
}

fn curve<S>(path: &[PathPoint<S>], f: impl Fn(&PathPoint<S>) -> (f64, f64)) -> Vec<(f64, f64)> {
    let every = (path.len() / 400).max(1);
    path.iter().step_by(every).chain(path.last()).map(f).collect()
}

/// the geostatic initial state (`mpm_tests::geostatic`): the K0 layer's exact stresses, and a
/// cohesionless slope that stands below its friction angle and fails above it.
fn geostatic_rows(rows: &mut Rows) {
    use mpm_tests::geostatic::{k0_layer, sand_slope};
    let case = "elastic layer 2 m, ν 0.3, implicit initial state";
    match k0_layer(2.0, 0.3) {
        Ok(r) => {
            rows.at_most(
                (case, "max |σ_yy/σ_yy,exact − 1|"),
                "−ρ g (H − y)",
                "at rest under gravity (1e-6: the issue)",
                r.vertical_error,
                GEOSTATIC_K0_REL,
                false,
            );
            rows.at_most(
                (case, "max |σ_xx/σ_yy − ν/(1 − ν)|, σ_zz too"),
                "K0 = ν/(1 − ν)",
                "plane strain, laterally confined",
                r.lateral_error,
                GEOSTATIC_K0_REL,
                false,
            );
        }
        Err(e) => rows.failed(case, "run", &e),
    }
    let case = "sand slope 25°, φ 35°, c 0, implicit initial state";
    match sand_slope(25.0, 35.0) {
        Ok(r) => match r.outcome {
            Ok(g) => {
                rows.at_most(
                    (case, "‖R‖/‖f_gravity‖"),
                    "0 (equilibrium)",
                    "Newton converges below φ",
                    g.residual,
                    GeostaticSettings::default().tolerance,
                    false,
                );
                rows.at_most(
                    (case, "max |Δσ| of a zero increment / |σ|"),
                    "0 (on or inside the cone)",
                    "no stress outside the yield surface",
                    r.outside_cone,
                    1e-12,
                    false,
                );
            }
            Err(e) => rows.failed(case, "solve", &e),
        },
        Err(e) => rows.failed(case, "run", &e),
    }
    let case = "sand slope 50°, φ 35°, c 0, implicit initial state";
    match sand_slope(50.0, 35.0) {
        Ok(SlopeResult { outcome: Err(SolverError::InitialState { load_factor, .. }), .. }) => rows
            .at_most(
                (case, "share of gravity in equilibrium"),
                "0 (no equilibrium: fails, exit 3)",
                "steeper than φ: reported, not solved",
                load_factor,
                0.01,
                false,
            ),
        Ok(r) => rows.failed(case, "report the failure", &format!("{:?}", r.outcome)),
        Err(e) => rows.failed(case, "run", &e),
    }
}

/// The manufactured solution of Wallstedt & Guilkey (2008) (`mpm_tests::manufactured`): observed
/// orders of the RMS displacement error per shape function and mass matrix over 1/16, 1/32 and
/// 1/64 m cells (MUSL, 2 × 2 particles per cell, one Δt on every level).
fn manufactured_rows(rows: &mut Rows) {
    use mpm_tests::manufactured::{AMPLITUDE, Manufactured, manufactured_at};
    let cells = [1.0 / 16.0, 1.0 / 32.0, 1.0 / 64.0];
    let base = mpm_tests::manufactured::baseline();
    let ladder = |shape, mass, a| -> Result<Vec<Manufactured>, mpm_tests::CaseError> {
        let run = |cell| manufactured_at(&Discretisation { cell, shape, mass, ..base }, a);
        cells.iter().map(|&cell| run(cell)).collect()
    };
    let order = |errors: &[f64]| {
        let xy: Vec<(f64, f64)> = cells.iter().zip(errors).map(|(h, e)| (h.ln(), e.ln())).collect();
        crate::study::slope(&xy)
    };
    let shown = |errors: &[f64]| errors.iter().map(|&e| num(e)).collect::<Vec<_>>().join(", ");
    let mut cases = vec![
        (ShapeKind::Gimp, MassMatrix::Lumped, AMPLITUDE, MMS_LARGE_ORDER),
        (ShapeKind::Gimp, MassMatrix::Consistent, AMPLITUDE, MMS_LARGE_ORDER),
        (ShapeKind::BSpline, MassMatrix::Lumped, AMPLITUDE, MMS_LARGE_ORDER),
        (ShapeKind::BSpline, MassMatrix::Consistent, AMPLITUDE, MMS_LARGE_ORDER),
        (ShapeKind::Gimp, MassMatrix::Lumped, 1e-4, MMS_SMALL_ORDER[0]),
        (ShapeKind::BSpline, MassMatrix::Lumped, 1e-4, MMS_SMALL_ORDER[1]),
        (ShapeKind::BSpline, MassMatrix::Consistent, 1e-4, MMS_SMALL_ORDER[2]),
    ];
    // bilinear: no order to bound (it diverges once particles cross cells); reported
    cases.push((ShapeKind::Bilinear, MassMatrix::Lumped, AMPLITUDE, f64::NAN));
    for (shape, mass, a, bound) in cases {
        let mass_name = mass.name();
        let case = format!("manufactured solution A = {a} m {} {mass_name}", shape.name());
        let runs = ladder(shape, mass, a);
        let errors = runs.as_ref().map(|r| r.iter().map(|m| m.rms_error).collect::<Vec<_>>());
        match errors {
            Ok(errors) if bound.is_nan() => rows.info(
                &case,
                "RMS |x − x_exact| / A at 1/16, 1/32, 1/64 m",
                "→ 0",
                "Wallstedt & Guilkey 2008",
                format!("{} (order {:.2}: cell crossing)", shown(&errors), order(&errors)),
            ),
            Ok(errors) => {
                let observed = order(&errors);
                let ok = observed >= bound;
                rows.push(
                    vec![
                        case.clone(),
                        format!("order of RMS |x − x_exact| / A ({})", shown(&errors)),
                        "converges".into(),
                        "Wallstedt & Guilkey 2008".into(),
                        format!("{observed:.2}"),
                        "–".into(),
                        format!("≥ {bound}"),
                    ],
                    status(ok),
                );
            }
            Err(e) => rows.failed(&case, "run", &e),
        }
        if let (Ok(runs), true) = (&runs, a < AMPLITUDE && shape == ShapeKind::Gimp) {
            rows.at_most(
                (&case, "|energy residual| / initial kinetic energy at 1/64 m"),
                "0",
                "body force's work booked",
                runs[2].energy_residual,
                MMS_ENERGY,
                true,
            );
        }
    }
    // Mode 3 (even about the middle): in mode 2 the impulses cancel by symmetry whatever the
    // walls book.
    for (shape, mass) in [
        (ShapeKind::Gimp, MassMatrix::Lumped),
        (ShapeKind::BSpline, MassMatrix::Lumped),
        (ShapeKind::Gimp, MassMatrix::Consistent),
        (ShapeKind::BSpline, MassMatrix::Consistent),
    ] {
        let case = format!("manufactured solution mode 3 {} {} 1/16 m", shape.name(), mass.name());
        let d = Discretisation { cell: 1.0 / 16.0, shape, mass, ..base };
        match mpm_tests::manufactured::manufactured_mode(&d, AMPLITUDE, 3) {
            Ok(m) => rows.at_most(
                (&case, "|Δp − body force impulse − walls' impulse| / Σ m|b|Δt"),
                "0",
                "momentum balance",
                m.momentum_error,
                CONSISTENT_MOMENTUM_REL,
                false,
            ),
            Err(e) => rows.failed(&case, "run", &e),
        }
    }
    let case = "manufactured solution B-spline lumped 1/8 m, Δt and Δt/8";
    let at = |courant| {
        let d = Discretisation { cell: 0.125, shape: ShapeKind::BSpline, courant, ..base };
        manufactured_at(&d, AMPLITUDE).map(|m| m.rms_error)
    };
    match (at(1.6), at(0.2)) {
        (Ok(coarse), Ok(fine)) => rows.rel(
            case,
            "RMS |x − x_exact| / A, Δt/8 against Δt",
            coarse,
            "the same spatial error",
            fine,
            MMS_DT_REL,
        ),
        (Err(e), _) | (_, Err(e)) => rows.failed(case, "run", &e),
    }
}

/// The consistent mass matrix (`[solver] mass = "consistent"`): on the vibrating bar its energy
/// and period errors are below the lumped matrix's at the same resolution and Δt, the sliding
/// blocks meet eqs 21–22 as the lumped matrix does, and with no boundary it conserves momentum
/// to rounding under every scheme.
fn consistent_mass_rows(rows: &mut Rows, quick: bool) {
    let mut bars = vec![(ShapeKind::Bilinear, 1.0)];
    if !quick {
        bars.push((ShapeKind::BSpline, 0.25));
    }
    for (shape, cell) in bars {
        let bar_with = |mass| {
            let scheme = Scheme::Musl;
            vibrating_bar(&Discretisation { cell, ppc: 2, scheme, shape, courant: 0.05, mass })
        };
        let case = format!("vibrating bar MUSL {} {cell} m C 0.05, consistent mass", shape.name());
        match (bar_with(MassMatrix::Lumped), bar_with(MassMatrix::Consistent)) {
            (Ok(l), Ok(c)) => {
                rows.at_most(
                    (&case, "max |E − E0|/E0, 5 periods"),
                    &format!("lumped: {}", pct(l.worst_energy)),
                    "below the lumped matrix's",
                    c.worst_energy,
                    l.worst_energy,
                    true,
                );
                rows.at_most(
                    (&case, "|period / exact − 1|"),
                    &format!("lumped: {}", pct((l.period_ratio - 1.0).abs())),
                    "below the lumped matrix's",
                    (c.period_ratio - 1.0).abs(),
                    (l.period_ratio - 1.0).abs(),
                    true,
                );
            }
            (Err(e), _) | (_, Err(e)) => rows.failed(&case, "run", &e),
        }
    }
    // The paper's sliding blocks (eqs 21–22) with the consistent matrix: the nodes a Coulomb
    // plane holds keep their lumped row (`stages/mass.rs`); on coupled rows the level block
    // stopped 4.4 % short (bilinear) and 22 % (B-spline).
    for shape in [ShapeKind::Bilinear, ShapeKind::BSpline] {
        let case = format!("horizontal sliding {} 0.5 m, consistent mass", shape.name());
        let d =
            Discretisation { shape, mass: MassMatrix::Consistent, ..Discretisation::paper(0.5) };
        match sliding_horizontal(&d) {
            Ok(r) => rows.rel(
                &case,
                "travel distance (m)",
                eq21_distance(),
                "eq 21",
                r.distance,
                SLIDING_DISTANCE_REL,
            ),
            Err(e) => rows.failed(&case, "run", &e),
        }
    }
    let case = "inclined sliding 30° bilinear 0.25 m, consistent mass";
    let d = Discretisation { mass: MassMatrix::Consistent, ..Discretisation::paper(0.25) };
    match sliding_inclined(30.0, 2.0, 0.0, &d) {
        Ok(r) => rows.rel(
            case,
            "travel at t = 2 s (m)",
            eq22_travel(30.0, 2.0),
            "eq 22",
            r.travel,
            INCLINED_TRAVEL_REL,
        ),
        Err(e) => rows.failed(case, "run", &e),
    }
    for scheme in Scheme::ALL {
        let case = format!("swirling block in flight {}, consistent mass", scheme.name());
        let d =
            Discretisation { scheme, mass: MassMatrix::Consistent, ..Discretisation::paper(0.25) };
        match swirl_momentum_error(&d) {
            Ok(error) => rows.at_most(
                (&case, "|p − p0 − M g t| / scale, 40 steps"),
                "0",
                "momentum conservation",
                error,
                CONSISTENT_MOMENTUM_REL,
                false,
            ),
            Err(e) => rows.failed(&case, "run", &e),
        }
    }
}
