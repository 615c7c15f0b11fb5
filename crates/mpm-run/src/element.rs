//! `mpm element-test`: the constitutive crate's single-point drivers (the paper's §6(3)) from the
//! command line, writing a CSV and PNG plots.
//!
//! The element tests are not a scene (there is no grid, body or time): they are reached only
//! through this command. By default they drive the paper's Drucker-Prager sand, with several
//! dilatancy angles and mixing parameters at once (each combination is one case: one curve, one
//! block of CSV rows); given materials of a scene (any registered model, as
//! [`mpm_scene::materials::AnyModel`]), they drive each of those instead.

use std::path::PathBuf;

use mpm_constitutive::element_test::{
    PathPoint, oedometric, simple_shear, simple_shear_at_rate, triaxial, uniaxial_plane_strain,
};
use mpm_constitutive::{ConeMatch, DruckerPrager, DruckerPragerParams, SymTensor, TangentModel};
use mpm_scene::materials::AnyModel;

use mpm_output::OutputError;

use crate::error::RunError;

/// (label, first plot's points, second plot's points) of one case.
type Curve = (String, Vec<(f64, f64)>, Vec<(f64, f64)>);
use mpm_output::atomic;
use mpm_output::plots::{self, Chart, Series, Style};

/// Which element test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ElementTest {
    /// plane-strain uniaxial compression: ε_yy prescribed, σ_xx = 0, ε_zz = 0.
    Uniaxial,
    /// drained simple shear at constant vertical stress: γ_xy prescribed, ε_xx = ε_zz = 0.
    SimpleShear,
    /// drained triaxial compression (ε_yy < 0) or extension (> 0) from an isotropic confining
    /// stress held on x and z.
    Triaxial,
    /// one-dimensional (K0) compression: ε_yy prescribed, every other strain zero.
    Oedometric,
}

/// Settings of `mpm element-test`.
#[derive(Clone, Debug)]
pub struct ElementTestOptions {
    /// which test.
    pub test: ElementTest,
    /// Young's modulus (Pa).
    pub young: f64,
    /// Poisson's ratio.
    pub poisson: f64,
    /// cohesion (Pa).
    pub cohesion: f64,
    /// friction angle (degrees).
    pub friction_angle_deg: f64,
    /// dilatancy angles (degrees), one case each.
    pub dilatancy_deg: Vec<f64>,
    /// plastic modulus H (Pa).
    pub hardening_modulus: f64,
    /// mixing parameters M, one case each.
    pub mixing: Vec<f64>,
    /// materials to test instead of the Drucker-Prager sweep above, by name (e.g. a scene's).
    pub materials: Vec<(String, AnyModel)>,
    /// simple shear: the engineering shear rate γ̇ (1/s) for a rate-dependent model such as
    /// μ(I); `None`: quasi-static.
    pub shear_rate: Option<f64>,
    /// final strain: ε_yy (uniaxial, negative = compression) or engineering γ_xy (shear).
    pub strain: f64,
    /// load steps.
    pub steps: usize,
    /// simple shear: initial isotropic stress (Pa, negative = compression), held vertically.
    pub confining_stress: f64,
    /// output directory.
    pub out_dir: PathBuf,
    /// overwrite existing files.
    pub force: bool,
}

/// One case's end point.
#[derive(Clone, Debug, PartialEq)]
pub struct ElementCaseResult {
    /// "ψ = 0°, M = 0.8".
    pub label: String,
    /// σ_yy at the end (Pa).
    pub final_syy: f64,
    /// σ_xy at the end (Pa).
    pub final_sxy: f64,
    /// volumetric strain at the end.
    pub final_eps_vol: f64,
    /// σ_yy at the first plastic step (Pa), if any.
    pub first_yield_syy: Option<f64>,
}

/// One point of a case's path.
struct Point {
    step: usize,
    strain: SymTensor,
    stress: SymTensor,
    eps_p_bar: f64,
    branch: &'static str,
}

impl<S> From<PathPoint<S>> for Point {
    fn from(p: PathPoint<S>) -> Self {
        Self {
            step: p.step,
            strain: p.strain,
            stress: p.stress,
            eps_p_bar: p.eps_p_bar,
            branch: p.branch,
        }
    }
}

/// drives `model` along the options' test.
fn drive<M: TangentModel>(model: &M, o: &ElementTestOptions) -> Result<Vec<Point>, RunError> {
    let s = o.confining_stress;
    let confined = SymTensor::new(s, s, s, 0.0, 0.0, 0.0);
    let path = match (o.test, o.shear_rate) {
        (ElementTest::Uniaxial, _) => {
            uniaxial_plane_strain(model, SymTensor::ZERO, o.strain, o.steps)
        }
        (ElementTest::SimpleShear, None) => simple_shear(model, confined, o.strain, o.steps),
        (ElementTest::SimpleShear, Some(rate)) => {
            simple_shear_at_rate(model, confined, o.strain, o.steps, rate)
        }
        (ElementTest::Triaxial, _) => triaxial(model, confined, o.strain, o.steps),
        (ElementTest::Oedometric, _) => oedometric(model, confined, o.strain, o.steps),
    }
    .map_err(|e| RunError::Setup(format!("element test failed: {e}")))?;
    Ok(path.into_iter().map(Point::from).collect())
}

/// Runs the cases and writes `element_test.csv` and plots into `out_dir`.
pub fn run_element_test(o: &ElementTestOptions) -> Result<Vec<ElementCaseResult>, RunError> {
    if !(o.steps >= 1 && o.steps <= 10_000_000) {
        return Err(RunError::Arguments(format!(
            "--steps {} is out of range: give 1 to 10000000 load steps",
            o.steps
        )));
    }
    if !o.strain.is_finite() || o.strain == 0.0 {
        return Err(RunError::Arguments(format!(
            "--strain {} must be finite and non-zero (e.g. -1e-3 for compression, 0.05 for shear)",
            o.strain
        )));
    }
    if o.shear_rate.is_some() && o.test != ElementTest::SimpleShear {
        return Err(RunError::Arguments(
            "--shear-rate applies to simple shear; the other tests are strain-controlled at \
             a quasi-static rate: drop --shear-rate or run `simple-shear`"
                .into(),
        ));
    }
    if let Some(rate) = o.shear_rate
        && !(rate.is_finite() && rate > 0.0 && rate <= 1e6)
    {
        return Err(RunError::Arguments(format!(
            "--shear-rate {rate} is out of range: give a rate 0 < γ̇ ≤ 1e6 1/s (e.g. 10)"
        )));
    }
    if !o.confining_stress.is_finite() {
        return Err(RunError::Arguments("--confining-stress must be finite (Pa)".into()));
    }
    let dir = &o.out_dir;
    let csv_path = dir.join("element_test.csv");
    if csv_path.exists() && !o.force {
        return Err(OutputError::OutputExists(dir.clone()).into());
    }
    std::fs::create_dir_all(dir)
        .map_err(|source| RunError::from(OutputError::Io { path: dir.clone(), source }))?;
    let mut csv = String::from(
        "case,psi_deg,mixing,step,eps_xx,eps_yy,eps_zz,gamma_xy,eps_vol,sigma_xx,sigma_yy,\
         sigma_zz,sigma_xy,eps_p_bar,surface\n",
    );
    let mut results = Vec::new();
    let mut curves: Vec<Curve> = Vec::new();
    let mut add = |label: String, psi: String, mixing: String, path: Vec<Point>| {
        let case = curves.len();
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for p in &path {
            let (e, s) = (p.strain, p.stress);
            let ev = e.trace();
            csv.push_str(&format!(
                "{case},{psi},{mixing},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                p.step,
                e.xx,
                e.yy,
                e.zz,
                2.0 * e.xy,
                ev,
                s.xx,
                s.yy,
                s.zz,
                s.xy,
                p.eps_p_bar,
                p.branch
            ));
            match o.test {
                ElementTest::Uniaxial => a.push((-e.yy, -s.yy)),
                ElementTest::Triaxial => a.push((e.yy, s.yy - s.xx)),
                ElementTest::Oedometric => a.push((-s.yy, -s.xx)),
                ElementTest::SimpleShear => {
                    a.push((2.0 * e.xy, ev));
                    b.push((2.0 * e.xy, s.xy));
                }
            }
        }
        if let Some(last) = path.last() {
            results.push(ElementCaseResult {
                label: label.clone(),
                final_syy: last.stress.yy,
                final_sxy: last.stress.xy,
                final_eps_vol: last.strain.trace(),
                first_yield_syy: path.iter().find(|p| p.branch != "elastic").map(|p| p.stress.yy),
            });
        }
        curves.push((label, a, b));
    };
    if o.materials.is_empty() {
        let dilatancy =
            if o.dilatancy_deg.is_empty() { vec![0.0] } else { o.dilatancy_deg.clone() };
        let mixing = if o.mixing.is_empty() { vec![1.0] } else { o.mixing.clone() };
        for &psi in &dilatancy {
            for &m in &mixing {
                let model = DruckerPrager::new(DruckerPragerParams {
                    young: o.young,
                    poisson: o.poisson,
                    cohesion: o.cohesion,
                    friction_angle_deg: o.friction_angle_deg,
                    dilatancy_angle_deg: psi,
                    hardening_modulus: o.hardening_modulus,
                    mixing: m,
                    cone_match: ConeMatch::PlaneStrain,
                })
                .map_err(|e| RunError::Arguments(format!("material parameters refused: {e}")))?;
                let path = drive(&model, o)?;
                add(format!("ψ = {psi}°, M = {m}"), psi.to_string(), m.to_string(), path);
            }
        }
    } else {
        for (name, model) in &o.materials {
            let path = drive(model, o)?;
            add(format!("{name} ({})", model.title()), String::new(), String::new(), path);
        }
    }
    atomic::write(&csv_path, csv.as_bytes())?;
    write_plots(o.test, dir, &curves)?;
    Ok(results)
}

/// the test's plots of the cases' curves into `dir`.
fn write_plots(test: ElementTest, dir: &std::path::Path, curves: &[Curve]) -> Result<(), RunError> {
    let series = |pick: &dyn Fn(&Curve) -> Vec<(f64, f64)>| {
        curves
            .iter()
            .enumerate()
            .map(|(k, c)| Series {
                name: c.0.clone(),
                points: pick(c),
                style: Style::Line,
                color: k,
            })
            .collect::<Vec<_>>()
    };
    let chart = |title, x_label, y_label| Chart {
        title,
        x_label,
        y_label,
        size: (900, 560),
        equal_aspect: false,
    };
    match test {
        ElementTest::Uniaxial => plots::chart(
            &dir.join("uniaxial.png"),
            &chart(
                "Plane-strain uniaxial compression",
                "axial strain −ε_yy",
                "axial stress −σ_yy (Pa)",
            ),
            &series(&|c| c.1.clone()),
        )?,
        ElementTest::Triaxial => plots::chart(
            &dir.join("triaxial.png"),
            &chart(
                "Drained triaxial test (compression: ε_yy < 0)",
                "axial strain ε_yy",
                "deviator σ_yy − σ_xx (Pa)",
            ),
            &series(&|c| c.1.clone()),
        )?,
        ElementTest::Oedometric => plots::chart(
            &dir.join("oedometric.png"),
            &chart(
                "One-dimensional compression: stress path",
                "vertical stress −σ_yy (Pa)",
                "lateral stress −σ_xx (Pa)",
            ),
            &series(&|c| c.1.clone()),
        )?,
        ElementTest::SimpleShear => {
            plots::chart(
                &dir.join("simple_shear_volume.png"),
                &chart(
                    "Simple shear: volume change",
                    "shear strain γ_xy",
                    "volumetric strain ε_vol",
                ),
                &series(&|c| c.1.clone()),
            )?;
            plots::chart(
                &dir.join("simple_shear_stress.png"),
                &chart("Simple shear: stress", "shear strain γ_xy", "shear stress σ_xy (Pa)"),
                &series(&|c| c.2.clone()),
            )?;
        }
    }
    Ok(())
}
