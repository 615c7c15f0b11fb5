//! Verify rows of Mohr–Coulomb's element tests against their closed forms (tension positive):
//! drained triaxial compression and extension peaks, plane-strain simple shear from an
//! isotropic stress (ψ = 0), and one-dimensional compression (K0).

use mpm_constitutive::element_test::{oedometric, simple_shear, triaxial};
use mpm_constitutive::{MohrCoulomb, MohrCoulombParams, SymTensor};

use super::Rows;

/// The element driver's Newton tolerance is 1e-9 of the stress scale: the closed forms hold to
/// a few times that.
const DRIVER_REL: f64 = 1e-8;

fn sand(phi: f64, c: f64, nu: f64) -> Option<MohrCoulomb> {
    MohrCoulomb::new(MohrCoulombParams {
        young: 2.0e6,
        poisson: nu,
        cohesion: c,
        friction_angle_deg: phi,
        dilatancy_angle_deg: 0.0,
        softening: None,
    })
    .ok()
}

/// the rows (a model or driver error becomes a failed row).
pub(super) fn rows(rows: &mut Rows) {
    let (phi, c, conf) = (30.0f64, 5.0, -100.0);
    let (s, co) = phi.to_radians().sin_cos();
    let k = (1.0 + s) / (1.0 - s);
    let cbar = 2.0 * c * co / (1.0 - s);
    let case = "element: Mohr–Coulomb φ 30°, c 5 Pa, σc = −100 Pa";
    let Some(m) = sand(phi, c, 0.3) else {
        return rows.failed(case, "build", &"refused");
    };
    let start = SymTensor::IDENTITY * conf;
    match triaxial(&m, start, -0.002, 1000) {
        Ok(p) => {
            let end = p.last().map_or(f64::NAN, |x| x.stress.yy);
            rows.rel(
                case,
                "triaxial compression peak σ_a (Pa)",
                k * conf - cbar,
                "k σc − 2c cos φ/(1 − sin φ)",
                end,
                DRIVER_REL,
            );
        }
        Err(e) => rows.failed(case, "triaxial compression", &e),
    }
    match triaxial(&m, start, 0.002, 1000) {
        Ok(p) => {
            let end = p.last().map_or(f64::NAN, |x| x.stress.yy);
            rows.rel(
                case,
                "triaxial extension peak σ_a (Pa)",
                (conf + cbar) / k,
                "(σc + 2c cos φ/(1 − sin φ))/k",
                end,
                DRIVER_REL,
            );
        }
        Err(e) => rows.failed(case, "triaxial extension", &e),
    }
    let (phi, c, p0) = (35.0f64, 2.0, -50.0);
    let case = "element: Mohr–Coulomb simple shear, φ 35°, c 2 Pa, ψ 0, p0 = −50 Pa";
    let tau = c * phi.to_radians().cos() - p0 * phi.to_radians().sin();
    match sand(phi, c, 0.25).map(|m| simple_shear(&m, SymTensor::IDENTITY * p0, 0.001, 400)) {
        Some(Ok(p)) => {
            let end = p.last().map_or(f64::NAN, |x| x.stress.xy);
            rows.rel(case, "plateau τ (Pa)", tau, "c cos φ − p0 sin φ", end, DRIVER_REL);
        }
        Some(Err(e)) => rows.failed(case, "simple shear", &e),
        None => rows.failed(case, "build", &"refused"),
    }
    let case = "element: Mohr–Coulomb one-dimensional compression, φ 30°, c 0";
    for (nu, expected, source) in [
        (0.3, 0.3 / 0.7, "K0 = ν/(1 − ν) (elastic)"),
        (0.2, 1.0 / 3.0, "Ka = (1 − sin φ)/(1 + sin φ) (yields)"),
    ] {
        match sand(30.0, 0.0, nu).map(|m| oedometric(&m, SymTensor::ZERO, -1e-3, 10)) {
            Some(Ok(p)) => {
                let end = p.last().map_or(f64::NAN, |x| x.stress.xx / x.stress.yy);
                rows.rel(case, &format!("σ_h/σ_v at ν = {nu}"), expected, source, end, 1e-12);
            }
            Some(Err(e)) => rows.failed(case, "oedometric", &e),
            None => rows.failed(case, "build", &"refused"),
        }
    }
}

/// The bar for the side-wall term against the 3D channel it stands for: runout and
/// final height within 3 %.
const CHANNEL_REL: f64 = 0.03;

/// Runout rows (`cargo xtask runout` has the study): a Mohr–Coulomb column between side walls
/// in plane strain completes at rest, its runout and height reported against the quasi-2D
/// experiments; in the full set, the side-wall term against the 3D channel at a = 1 and 2.
pub(super) fn runout_rows(rows: &mut Rows, quick: bool) {
    use crate::runout::{Base, Case, Model, experiment_height, experiment_runout, run_case};
    let Ok(dir) = crate::out_dir("verify/runout") else {
        return rows.failed("runout", "output directory", &"not writable");
    };
    let case = |dim, a, wall_deg| Case {
        dim,
        a,
        model: Model::MohrCoulomb,
        base: Base::Rough,
        resolution: 10,
        wall_deg,
        pic: None,
    };
    let c = case(2, 1.0, Some(20.0));
    let name = "column a = 1, Mohr–Coulomb φ 29.5°, side walls 0.1 m δ 20°, L0/Δx = 10";
    match run_case(&c, &dir.join("quasi2d")) {
        Ok(o) => {
            let ended = o.status == "at rest" || o.status == "Completed";
            rows.at_least(
                (name, "completes (1: at rest or end time)"),
                "1",
                "issue 54",
                f64::from(u8::from(ended)),
                1.0,
            );
            let (low, _) = experiment_runout(2, 1.0);
            rows.info(
                name,
                "(L∞ − L0)/L0",
                &format!("{low:.2}"),
                "Lube et al. 2005",
                format!("{:.3}", o.runout),
            );
            let h = experiment_height(2, 1.0);
            rows.info(
                name,
                "H∞/L0",
                &format!("{h:.2}"),
                "Lube et al. 2005",
                format!("{:.3}", o.height),
            );
        }
        Err(e) => rows.failed(name, "run", &e),
    }
    if quick {
        return;
    }
    for a in [1.0, 2.0] {
        let name = format!("side walls δ 25°, W 0.1 m: 2D term against the 3D channel, a = {a}");
        let plane = run_case(&case(2, a, Some(25.0)), &dir.join(format!("plane_{a}")));
        let space = run_case(&case(3, a, Some(25.0)), &dir.join(format!("channel_{a}")));
        match (plane, space) {
            (Ok(p), Ok(s)) => {
                // the farthest grain: the one measure both dimensions take alike (the main
                // mass's front is a section's gap rule in 2D, found in plan in 3D)
                let q = "farthest grain (x − L0)/L0";
                rows.rel(&name, q, s.leading, "the 3D channel", p.leading, CHANNEL_REL);
                let h = "final height H∞/L0";
                rows.rel(&name, h, s.height, "the 3D channel", p.height, CHANNEL_REL);
                let f = "main mass front (L∞ − L0)/L0, 2D | 3D";
                rows.info(
                    &name,
                    f,
                    "–",
                    "each dimension's rule",
                    format!("{:.3} | {:.3}", p.runout, s.runout),
                );
            }
            (Err(e), _) | (_, Err(e)) => rows.failed(&name, "run", &e),
        }
    }
}
