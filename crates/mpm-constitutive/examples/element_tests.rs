//! Runs the element tests of Abe et al. (2005) §6(3) and writes every path as CSV.
//!
//! Usage: `cargo run -p mpm-constitutive --example element_tests [-- out.csv]` (stdout when no
//! path is given). Tension positive, SI units; CSV columns are listed in
//! `mpm_constitutive::element_test::CSV_HEADER` (engineering shear `gamma_* = 2 eps_*`).
//!
//! Tests written (the `test` column):
//! - `uniaxial_psi{0,40}`: plane-strain uniaxial compression, σ_xx = 0, the paper's sand with
//!   H = 0 (reference: first yield −28.50 Pa, steady state −36.15 / −42.89 Pa);
//! - `uniaxial_cycle_M{1,0.5,0}`: compression, unloading and reloading in extension with H > 0
//!   under isotropic, mixed and kinematic hardening (the rules differ only after reversal);
//! - `shear_psi{0,10,20,40}`: drained simple shear at σ_yy = −100 Pa (ε_v–γ for several ψ);
//! - `isotropic_{compression,extension}`.

use std::error::Error;
use std::fs::File;
use std::io::{BufWriter, Write};

use mpm_constitutive::element_test::{
    MixedControl, PathPoint, QUASI_STATIC_STEP, isotropic, run_mixed, simple_shear,
    uniaxial_plane_strain, write_csv,
};
use mpm_constitutive::{ConeMatch, DpState, DruckerPrager, DruckerPragerParams, SymTensor};

fn sand(psi: f64, hardening_modulus: f64, mixing: f64) -> Result<DruckerPrager, Box<dyn Error>> {
    Ok(DruckerPrager::new(DruckerPragerParams {
        young: 2.0e6,
        poisson: 0.3,
        cohesion: 10.0,
        friction_angle_deg: 40.0,
        dilatancy_angle_deg: psi,
        hardening_modulus,
        mixing,
        cone_match: ConeMatch::PlaneStrain,
    })?)
}

/// compression to ε_yy = −3e-4, then back to +1e-4 (σ_xx = 0 and ε_zz = 0 throughout).
fn uniaxial_cycle(m: &DruckerPrager) -> Result<Vec<PathPoint<DpState>>, Box<dyn Error>> {
    let mut path = uniaxial_plane_strain(m, SymTensor::ZERO, -3e-4, 300)?;
    let top = *path.last().ok_or("empty path")?;
    let back = MixedControl {
        stress_controlled: [true, false, false, false, false, false],
        increment: [0.0, 4e-4 / 400.0, 0.0, 0.0, 0.0, 0.0],
        dt: QUASI_STATIC_STEP,
    };
    for mut p in run_mixed(m, top.stress, top.state, &back, 400)?.into_iter().skip(1) {
        p.step += top.step;
        p.strain += top.strain;
        path.push(p);
    }
    Ok(path)
}

fn main() -> Result<(), Box<dyn Error>> {
    let mut out: Box<dyn Write> = match std::env::args().nth(1) {
        Some(path) => Box::new(BufWriter::new(File::create(path)?)),
        None => Box::new(BufWriter::new(std::io::stdout().lock())),
    };
    let mut header = true;
    let mut emit = |name: &str, path: &[PathPoint<DpState>]| -> std::io::Result<()> {
        write_csv(&mut out, name, path, header)?;
        header = false;
        Ok(())
    };
    for psi in [0.0, 40.0] {
        let path = uniaxial_plane_strain(&sand(psi, 0.0, 1.0)?, SymTensor::ZERO, -2e-3, 2000)?;
        emit(&format!("uniaxial_psi{psi}"), &path)?;
    }
    for mixing in [1.0, 0.5, 0.0] {
        let path = uniaxial_cycle(&sand(0.0, 2.0e5, mixing)?)?;
        emit(&format!("uniaxial_cycle_M{mixing}"), &path)?;
    }
    let consolidated = SymTensor::new(-50.0, -100.0, -50.0, 0.0, 0.0, 0.0);
    for psi in [0.0, 10.0, 20.0, 40.0] {
        let path = simple_shear(&sand(psi, 0.0, 1.0)?, consolidated, 0.01, 2000)?;
        emit(&format!("shear_psi{psi}"), &path)?;
    }
    let m = sand(0.0, 0.0, 1.0)?;
    emit("isotropic_compression", &isotropic(&m, SymTensor::ZERO, -1e-3, 100)?)?;
    emit("isotropic_extension", &isotropic(&m, SymTensor::ZERO, 1e-4, 100)?)?;
    out.flush()?;
    Ok(())
}
