//! `cargo xtask runout`: column collapses against two experiment families, each model and
//! resolution side by side — how far the same sand runs in plane strain (with and without the
//! channel's side walls) and in 3D, with Mohr–Coulomb and each Drucker-Prager cone.
//!
//! The sand is Lube et al.'s fine quartz sand, with only what those experiments report (or the
//! ends of a plausible range where they report nothing — never a value fitted to the runout):
//! - friction angle 29.5°, the sand's angle of repose (Lube, Huppert, Sparks & Freundt 2005,
//!   Phys. Rev. E 72, 041301, tables I–II, as quoted by secondary sources: not read here in the
//!   original), ψ = 0, c = 0 (dry, cohesionless);
//! - bulk density 1 600 kg/m³ (grain density 2 600 kg/m³ at a packing of 0.62; the packing is
//!   not reported, 0.58–0.65 is the range of poured sands);
//! - E = 2 MPa, ν = 0.3 (the granular defaults: the runout of a cohesionless column does not
//!   depend on a stiffness this far above ρ g H);
//! - quasi-2D: a channel 0.1 m wide (secondary sources; not read here in the original), wall
//!   friction not reported: both ends of 15°–25° (sand on perspex or glass) are run;
//! - the rough base as stuck nodes (`"rough"`), and as Coulomb friction at the glued grains'
//!   angle (29.5°) for comparison.
//!
//! Beside the sand, glass beads with the μ(I) rheology (Jop, Forterre & Pouliquen 2006's
//! parameters, [`MU_I_BEADS`]), the grains of Lajeunesse et al.'s experiments: a friction that
//! grows with the flow's inertial number against the sand's one constant angle, from a = 0.5
//! to 8, in plane strain (with and without the channel's walls) and in 3D.
//!
//! References: quasi-2D (Lube et al. 2005; Lajeunesse, Monnier & Homsy 2005, Phys. Fluids 17,
//! 103302) (L∞ − L0)/L0 = 1.2 a below a = 1.8, 1.9 a^(2/3) above 2.8, the band between;
//! H∞/L0 = a for short columns, a^(2/5) for tall ones. Axisymmetric (Lube, Huppert, Sparks &
//! Hallworth 2004, J. Fluid Mech. 508, 175–199) (R∞ − R0)/R0 = 1.24 a below a = 1.7,
//! 1.6 a^(1/2) above; H∞/R0 = a for short columns, 0.88 a^(1/6) for tall ones (the last as the
//! issue quotes it: not read here in the original).
//!
//! Writes `target/runout/runout.csv` (one line per run) and `docs/runout.md` (the table).

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use mpm_run::{RunOptions, RunStatus};

/// The sand's friction angle (°): Lube et al. 2005's fine sand, its angle of repose.
const PHI: f64 = 29.5;
/// The glass beads' μ(I) rheology as Jop, Forterre & Pouliquen (2006, Nature 441, 727–730)
/// fitted it to 0.53 mm beads: μ_s = tan 20.9°, μ_2 = tan 32.76°, I_0 = 0.279, grain density
/// 2 450 kg/m³ (as quoted by secondary sources: not read here in the original); bulk density at a
/// solid fraction of 0.6 (the dense flows' 0.58–0.62).
const MU_I_BEADS: &str = "kind = \"mu_i\"\nyoung = 2.0e6\npoisson = 0.3\ndensity = 1470.0\n\
     mu_s = 0.3819\nmu_2 = 0.6435\ni0 = 0.279\ngrain_diameter = 0.53e-3\ngrain_density = 2450.0\n";
/// The beads' static friction angle (°), μ_s = tan 20.9°.
const MU_I_STATIC_DEG: f64 = 20.9;
/// The quasi-2D channel's width (m).
const CHANNEL: f64 = 0.1;
/// A deposit at rest: kinetic energy below this fraction of its peak for 0.3 s.
const REST: f64 = 1e-5;

/// The constitutive model of the sand.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// Mohr–Coulomb.
    MohrCoulomb,
    /// Drucker-Prager, the paper's plane-strain cone.
    DpPlaneStrain,
    /// Drucker-Prager through the triaxial-compression corners.
    DpOuter,
    /// Drucker-Prager through the triaxial-extension corners.
    DpInner,
    /// the μ(I) rheology with the glass beads of Jop, Forterre & Pouliquen (2006) — not the
    /// sand: a rate-dependent friction set against the constant one.
    MuI,
    /// the same beads without the rate dependence (μ_2 = μ_s): the same cone, so that the
    /// difference from [`Model::MuI`] is the rate dependence alone.
    MuIStatic,
}

impl Model {
    fn name(self) -> &'static str {
        match self {
            Model::MohrCoulomb => "Mohr-Coulomb",
            Model::DpPlaneStrain => "DP plane-strain cone",
            Model::DpOuter => "DP outer cone",
            Model::DpInner => "DP inner cone",
            Model::MuI => "μ(I) glass beads",
            Model::MuIStatic => "μ(I) glass beads, μ_2 = μ_s",
        }
    }

    /// how much farther than the sand's grid this model's grid reaches in `dim`: the beads run
    /// up to 92 % beyond the experiments in plane strain (the glued a = 8 column's front came
    /// within two cells of the grid's end; no grain reached it).
    fn reach(self, dim: u8) -> f64 {
        match (self, dim) {
            (Model::MuI | Model::MuIStatic, 2) => 1.2,
            (Model::MuI | Model::MuIStatic, _) => 1.3,
            _ => 1.0,
        }
    }

    /// the static friction angle (°): the sand's, or the beads' μ_s = tan 20.9°.
    fn static_angle(self) -> f64 {
        if matches!(self, Model::MuI | Model::MuIStatic) { MU_I_STATIC_DEG } else { PHI }
    }

    fn toml(self) -> String {
        let common = format!(
            "young = 2.0e6\npoisson = 0.3\ndensity = 1600.0\ncohesion = 0.0\n\
             friction_angle_deg = {PHI}\ndilatancy_angle_deg = 0.0\n"
        );
        let kind = match self {
            Model::MohrCoulomb => "kind = \"mohr_coulomb\"\n".to_string(),
            Model::DpPlaneStrain => {
                "kind = \"drucker_prager\"\ncone_match = \"plane_strain\"\n".into()
            }
            Model::DpOuter => "kind = \"drucker_prager\"\ncone_match = \"outer\"\n".into(),
            Model::DpInner => "kind = \"drucker_prager\"\ncone_match = \"inner\"\n".into(),
            Model::MuI => return MU_I_BEADS.into(),
            Model::MuIStatic => return MU_I_BEADS.replace("mu_2 = 0.6435", "mu_2 = 0.3819"),
        };
        format!("{kind}{common}")
    }
}

/// The floor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Base {
    /// stuck nodes.
    Rough,
    /// Coulomb friction at the glued grains' static angle (the sand's 29.5°, the beads' 20.9°).
    Glued,
}

impl Base {
    fn name(self, model: Model) -> String {
        match self {
            Base::Rough => "rough (stuck)".into(),
            Base::Glued => format!("Coulomb {}°", model.static_angle()),
        }
    }
    fn toml(self, model: Model) -> String {
        match self {
            Base::Rough => "\"rough\"".into(),
            Base::Glued => format!("{{ friction_angle_deg = {} }}", model.static_angle()),
        }
    }
}

/// A PIC share other than the default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pic {
    /// β per step (`pic_fraction`).
    PerStep(f64),
    /// a relaxation time of this many √(Δx/g) (`pic_relaxation`).
    Relaxation(f64),
    /// the default share, 0.001 per step, weighted by noise (`pic_weighting = "noise"`).
    Noise,
}

impl Pic {
    fn name(self) -> String {
        match self {
            Pic::PerStep(b) => format!("{b:e} per step"),
            Pic::Relaxation(k) => format!("τ = {k} √(Δx/g)"),
            Pic::Noise => "0.001 per step, weighted by noise".into(),
        }
    }
}

/// One collapse.
#[derive(Clone, Debug)]
pub struct Case {
    /// 2 (plane strain, quasi-2D experiments) or 3 (quarter cylinder, axisymmetric ones).
    pub dim: u8,
    /// a = H0/L0 (2D) or H0/R0 (3D).
    pub a: f64,
    /// the sand's model.
    pub model: Model,
    /// the floor.
    pub base: Base,
    /// L0/Δx or R0/Δx.
    pub resolution: u32,
    /// side walls' friction angle: in 2D the side-wall term, in 3D the plane-strain column
    /// extruded across a channel between two Coulomb walls (`None`: plane strain without walls;
    /// in 3D the axisymmetric quarter column).
    pub wall_deg: Option<f64>,
    /// the FLIP update's PIC share (`None`: the granular default, 0.001 per step).
    pub pic: Option<Pic>,
}

impl Case {
    fn label(&self) -> String {
        let walls = match (self.dim, self.wall_deg) {
            (3, None) => "axisymmetric (quarter)".to_string(),
            (3, Some(d)) => format!("channel W = {CHANNEL} m between Coulomb walls δ = {d}°"),
            (_, None) => "plane strain".to_string(),
            (_, Some(d)) => format!("side walls W = {CHANNEL} m, δ = {d}°"),
        };
        let pic = self.pic.map_or(String::new(), |p| match p {
            Pic::PerStep(b) => format!(" β {b:e}"),
            Pic::Relaxation(k) => format!(" τ {k}"),
            Pic::Noise => " noise-weighted".into(),
        });
        format!(
            "{}D a = {} {} {} {} res {}{pic}",
            self.dim,
            self.a,
            self.model.name(),
            self.base.name(self.model),
            walls,
            self.resolution
        )
    }

    /// the `[solver]` line of a PIC share other than the default, on cells of `dx`.
    fn pic_toml(&self, dx: f64) -> String {
        match self.pic {
            None => String::new(),
            Some(Pic::PerStep(b)) => format!("pic_fraction = {b:e}\n"),
            Some(Pic::Relaxation(k)) => format!("pic_relaxation = {}\n", k * (dx / 9.81).sqrt()),
            Some(Pic::Noise) => "pic_weighting = \"noise\"\n".into(),
        }
    }
}

/// the experiments' normalised runout (low, high) at a.
pub fn experiment_runout(dim: u8, a: f64) -> (f64, f64) {
    experiment_runout_of(dim == 2, a)
}

/// the quasi-2D (`channel`) or axisymmetric experiments' normalised runout (low, high) at a.
fn experiment_runout_of(channel: bool, a: f64) -> (f64, f64) {
    if channel {
        crate::column::experimental_runout(a)
    } else if a <= 1.7 {
        (1.24 * a, 1.24 * a)
    } else {
        let p = 1.6 * a.sqrt();
        (p, p)
    }
}

/// the experiments' normalised final height at a.
pub fn experiment_height(dim: u8, a: f64) -> f64 {
    experiment_height_of(dim == 2, a)
}

fn experiment_height_of(channel: bool, a: f64) -> f64 {
    if channel { a.min(a.powf(0.4)) } else { a.min(0.88 * a.powf(1.0 / 6.0)) }
}

/// A quasi-2D column's section on its grid: L0, Δx, H0, cells along and up, and the end time
/// (room for 1.6 × the experiments' runout times the model's reach, 1.3 H0 above; a dozen
/// free-fall times).
struct Section {
    l0: f64,
    dx: f64,
    h0: f64,
    nx: u32,
    ny: u32,
    end: f64,
}

impl Section {
    fn of(c: &Case) -> Self {
        let l0 = crate::column::L0;
        let dx = l0 / f64::from(c.resolution);
        let h0 = c.a * l0;
        let (_, upper) = experiment_runout_of(true, c.a);
        let nx = ((l0 * (1.0 + 1.6 * c.model.reach(2) * upper) + 2.0 * dx) / dx).ceil() as u32;
        let ny = ((1.3 * h0 + 3.0 * dx) / dx).ceil() as u32;
        let end = (12.0 * (2.0 * h0 / 9.81).sqrt()).max(3.0);
        Self { l0, dx, h0, nx, ny, end }
    }
}

/// the 2D scene: a column L0 = 0.2 m wide against a frictionless back wall (the symmetry plane
/// of a column twice as wide, or the experiment's end wall).
fn scene_2d(c: &Case) -> String {
    let Section { l0, dx, h0, nx, ny, end } = Section::of(c);
    let walls = c.wall_deg.map_or(String::new(), |d| {
        format!("side_walls = {{ width = {CHANNEL}, friction_angle_deg = {d} }}\n")
    });
    format!(
        "title = \"{label}\"\n\
         [grid]\nkind = \"regular\"\norigin = [0.0, 0.0]\ncell = [{dx}, {dx}]\ncells = [{nx}, {ny}]\n\
         [materials.sand]\n{material}\
         [[bodies]]\nname = \"column\"\nmaterial = \"sand\"\nshape = \"rectangle\"\n\
         min = [0.0, 0.0]\nmax = [{l0}, {h0}]\nparticles_per_cell = 2\n\
         [boundaries]\nground = {ground}\nleft_wall = \"frictionless\"\n{walls}\
         [solver]\n{pic}end_time = {end}\n\
         stop_at_rest = {{ kinetic_fraction = {REST}, duration = 0.3 }}\n\
         [output]\ninterval = {end}\nseries_interval = 0.01\nplots = false\nvtk = false\n",
        label = c.label(),
        material = c.model.toml(),
        ground = c.base.toml(c.model),
        pic = c.pic_toml(dx),
    )
}

/// the 3D scene: a quarter of a cylinder R0 = 0.1 m, its axis on the grid's corner edge
/// between two frictionless symmetry faces (x = 0, z = 0), a prism over a 64-sided arc.
fn scene_3d(c: &Case) -> String {
    let r0 = 0.1;
    let dx = r0 / f64::from(c.resolution);
    let h0 = c.a * r0;
    let (_, upper) = experiment_runout(3, c.a);
    let reach = r0 * (1.0 + 1.5 * c.model.reach(3) * upper) + 2.0 * dx;
    let n = (reach / dx).ceil() as u32;
    let ny = ((1.3 * h0 + 3.0 * dx) / dx).ceil() as u32;
    let end = (12.0 * (2.0 * h0 / 9.81).sqrt()).max(2.0);
    let mut arc = String::from("[0.0, 0.0]");
    for k in 0..=64 {
        let t = std::f64::consts::FRAC_PI_2 * f64::from(k) / 64.0;
        let _ = write!(arc, ", [{}, {}]", r0 * t.cos(), r0 * t.sin());
    }
    format!(
        "title = \"{label}\"\n\
         [grid]\ndimension = 3\nkind = \"regular\"\norigin = [0.0, 0.0, 0.0]\n\
         cell = [{dx}, {dx}, {dx}]\ncells = [{n}, {ny}, {n}]\n\
         [materials.sand]\n{material}\
         [[bodies]]\nname = \"column\"\nmaterial = \"sand\"\nshape = \"prism\"\naxis = \"y\"\n\
         vertices = [{arc}]\nfrom = 0.0\nto = {h0}\n\
         [boundaries]\nground = {ground}\nleft_wall = \"frictionless\"\n\
         back_wall = \"frictionless\"\n\
         [solver]\n{pic}end_time = {end}\n\
         stop_at_rest = {{ kinetic_fraction = {REST}, duration = 0.3 }}\n\
         [output]\ninterval = {end}\nseries_interval = 0.01\nplots = false\nvtk = false\n",
        label = c.label(),
        material = c.model.toml(),
        ground = c.base.toml(c.model),
        pic = c.pic_toml(dx),
    )
}

/// the 3D channel: the 2D scene's column extruded W across, between two Coulomb walls of
/// friction δ (`back_wall`, `front_wall`): what the 2D side-wall term stands for.
fn scene_channel(c: &Case, delta: f64) -> String {
    let Section { l0, dx, h0, nx, ny, end } = Section::of(c);
    let nz = (CHANNEL / dx).round() as u32;
    // (the box spans the whole channel: W/Δx cells, whole at every resolution the study uses)
    let depth = f64::from(nz) * dx;
    format!(
        "title = \"{label}\"\n\
         [grid]\ndimension = 3\nkind = \"regular\"\norigin = [0.0, 0.0, 0.0]\n\
         cell = [{dx}, {dx}, {dx}]\ncells = [{nx}, {ny}, {nz}]\n\
         [materials.sand]\n{material}\
         [[bodies]]\nname = \"column\"\nmaterial = \"sand\"\nshape = \"box\"\n\
         min = [0.0, 0.0, 0.0]\nmax = [{l0}, {h0}, {depth}]\n\
         [boundaries]\nground = {ground}\nleft_wall = \"frictionless\"\n\
         back_wall = {{ friction_angle_deg = {delta} }}\nfront_wall = {{ friction_angle_deg = {delta} }}\n\
         [solver]\n{pic}end_time = {end}\n\
         stop_at_rest = {{ kinetic_fraction = {REST}, duration = 0.3 }}\n\
         [output]\ninterval = {end}\nseries_interval = 0.01\nplots = false\nvtk = false\n",
        label = c.label(),
        material = c.model.toml(),
        ground = c.base.toml(c.model),
        pic = c.pic_toml(dx),
    )
}

/// What one collapse measured.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// how it ended, with the error if any.
    pub status: String,
    /// (front − L0)/L0 of the main mass at the end.
    pub runout: f64,
    /// final height / L0.
    pub height: f64,
    /// (farthest particle − L0)/L0 at the end: the same measure in 2D and 3D (the main mass's
    /// front is found by a section's gap rule in 2D, in plan in 3D).
    pub leading: f64,
    /// steps.
    pub steps: u64,
    /// particles.
    pub particles: usize,
    /// wall time (s).
    pub wall: f64,
}

/// runs one case into `dir`.
pub fn run_case(c: &Case, dir: &Path) -> Result<Outcome, String> {
    let options =
        RunOptions { out_dir: Some(dir.to_path_buf()), force: true, ..Default::default() };
    let start = Instant::now();
    let (s, l0) = if c.dim == 2 {
        let scene = mpm_run::load_scene_str(&scene_2d(c), &c.label()).map_err(|e| e.to_string())?;
        (mpm_run::run_scene(&scene, &options).map_err(|e| e.to_string())?, crate::column::L0)
    } else if let Some(delta) = c.wall_deg {
        let scene = mpm_run::load_space_str(&scene_channel(c, delta), &c.label())
            .map_err(|e| e.to_string())?;
        (mpm_run::run_space_scene(&scene, &options).map_err(|e| e.to_string())?, crate::column::L0)
    } else {
        let scene = mpm_run::load_space_str(&scene_3d(c), &c.label()).map_err(|e| e.to_string())?;
        (mpm_run::run_space_scene(&scene, &options).map_err(|e| e.to_string())?, 0.1)
    };
    let status = match (&s.status, &s.error) {
        (_, Some(e)) => format!("{:?}: {e}", s.status),
        (RunStatus::AtRest, None) => "at rest".into(),
        (other, None) => format!("{other:?}"),
    };
    let r = &s.runout.last;
    Ok(Outcome {
        status,
        runout: (r.front_x - l0) / l0,
        height: r.max_thickness / l0,
        leading: (r.leading_x - l0) / l0,
        steps: s.steps,
        particles: s.particles,
        wall: start.elapsed().as_secs_f64(),
    })
}

/// The runs: with `quick`, one per family at the coarsest resolution; else the study.
pub fn cases(quick: bool) -> Vec<Case> {
    let mut out = Vec::new();
    let case = |dim, a, model, base, resolution, wall_deg| Case {
        dim,
        a,
        model,
        base,
        resolution,
        wall_deg,
        pic: None,
    };
    if quick {
        out.push(case(2, 1.0, Model::MohrCoulomb, Base::Rough, 10, Some(20.0)));
        out.push(case(3, 1.0, Model::MohrCoulomb, Base::Rough, 6, None));
        return out;
    }
    // quasi-2D: both models without walls, Mohr–Coulomb between the walls at both ends of δ
    for &res in &[10, 20] {
        for &a in &[0.5, 1.0, 2.0, 4.0] {
            for model in [Model::MohrCoulomb, Model::DpPlaneStrain] {
                out.push(case(2, a, model, Base::Rough, res, None));
            }
            for d in [15.0, 25.0] {
                out.push(case(2, a, Model::MohrCoulomb, Base::Rough, res, Some(d)));
            }
        }
    }
    // the third resolution (Richardson) at a = 1, and the glued base
    for d in [15.0, 25.0] {
        out.push(case(2, 1.0, Model::MohrCoulomb, Base::Rough, 40, Some(d)));
    }
    for &a in &[1.0, 2.0, 4.0, 8.0] {
        out.push(case(2, a, Model::MohrCoulomb, Base::Glued, 20, Some(25.0)));
    }
    // axisymmetric: the three models at R0/Δx = 8 (a 3D run at 10 or more takes 10–40 min on
    // two cores: the convergence study in 3D is left to a larger machine)
    for &a in &[1.0, 2.0] {
        for model in [Model::MohrCoulomb, Model::DpOuter, Model::DpInner] {
            out.push(case(3, a, model, Base::Rough, 8, None));
        }
        // the rough base as Coulomb friction at the glued grains' angle instead of stuck
        // nodes (which hold a whole cell's layer still), with the default and the
        // noise-weighted share: how much of the 3D answer the base and the damping decide
        let glued = case(3, a, Model::MohrCoulomb, Base::Glued, 8, None);
        out.push(glued.clone());
        out.push(Case { pic: Some(Pic::Noise), ..glued });
    }
    // the glued base at a = 1 on coarser and finer grids (R0/Δx = 4 to 16; 12 takes 6–8 min
    // and 16 about half an hour on two cores): which way the 3D runout moves with the cells
    for res in [4, 6, 12, 16] {
        let glued = case(3, 1.0, Model::MohrCoulomb, Base::Glued, res, None);
        out.push(glued.clone());
        out.push(Case { pic: Some(Pic::Noise), ..glued });
    }
    // the aspect ratios 0.5 to 8 on the glued base at R0/Δx = 8 (a = 8 takes about 40 min on
    // one core): which way the error turns as the columns get taller
    for &a in &[0.5, 4.0, 8.0] {
        out.push(case(3, a, Model::MohrCoulomb, Base::Glued, 8, None));
    }
    // a friction that grows with the flow's inertial number against one constant friction: the
    // μ(I) beads in plane strain (both bases, and between the channel's walls) and in 3D, with
    // the sand's plane-strain column at a = 8 for the trend
    out.push(case(2, 8.0, Model::MohrCoulomb, Base::Rough, 20, None));
    out.push(case(2, 8.0, Model::MohrCoulomb, Base::Glued, 20, None));
    for &a in &[0.5, 1.0, 2.0, 4.0, 8.0] {
        out.push(case(2, a, Model::MuI, Base::Rough, 20, None));
        out.push(case(2, a, Model::MuIStatic, Base::Rough, 20, None));
        out.push(case(2, a, Model::MuI, Base::Glued, 20, None));
        out.push(case(2, a, Model::MuI, Base::Glued, 20, Some(25.0)));
    }
    for &a in &[1.0, 2.0, 4.0, 8.0] {
        out.push(case(3, a, Model::MuI, Base::Glued, 8, None));
    }
    // the side-wall term against the channel it stands for: the 2D runs with δ = 25° at
    // L0/Δx = 10 against the column extruded 0.1 m between two 25° walls in 3D
    for &a in &[1.0, 2.0] {
        out.push(case(3, a, Model::MohrCoulomb, Base::Rough, 10, Some(25.0)));
    }
    // the FLIP update's PIC share: 1e-4 per step, a relaxation time 2 √(Δx/g) and the default
    // weighted by noise, beside the default 0.001 per step: how much of the runout is the transfer's numerical damping
    // (Mohr–Coulomb, quarter columns and quasi-2D sections)
    for pic in [Some(Pic::PerStep(1e-4)), Some(Pic::Relaxation(2.0)), Some(Pic::Noise)] {
        for &a in &[1.0, 2.0] {
            out.push(Case { pic, ..case(3, a, Model::MohrCoulomb, Base::Rough, 8, None) });
            for d in [None, Some(15.0), Some(25.0)] {
                out.push(Case { pic, ..case(2, a, Model::MohrCoulomb, Base::Rough, 20, d) });
            }
        }
    }
    out
}

/// `cargo xtask runout [--quick]`: runs the cases, writes the CSV and the table.
pub fn run(quick: bool) -> anyhow::Result<bool> {
    let dir = crate::out_dir("runout")?;
    let only: Option<String> = std::env::var("RUNOUT_ONLY").ok();
    let mut csv = String::from(
        "dim,a,model,base,side_wall_deg,pic_fraction,resolution,status,runout,experiment_low,\
         experiment_high,runout_error,height,experiment_height,height_error,steps,particles,wall_s\n",
    );
    let mut rows = Vec::new();
    let mut ok = true;
    for c in cases(quick) {
        let label = c.label();
        if only.as_ref().is_some_and(|o| !label.contains(o.as_str())) {
            continue;
        }
        let run_dir = dir.join(label.replace([' ', ',', '=', '/', '°', '(', ')', '.'], "_"));
        eprintln!("runout: {label}");
        let o = match run_case(&c, &run_dir) {
            Ok(o) => o,
            Err(e) => {
                ok = false;
                eprintln!("  error: {e}");
                continue;
            }
        };
        let channel = c.dim == 2 || c.wall_deg.is_some();
        let (low, high) = experiment_runout_of(channel, c.a);
        let err = if o.runout < low {
            (o.runout - low) / low
        } else if o.runout > high {
            (o.runout - high) / high
        } else {
            0.0
        };
        let h = experiment_height_of(channel, c.a);
        let herr = (o.height - h) / h;
        eprintln!(
            "  {}: runout {:.3} (experiments {low:.2}–{high:.2}, {:+.1} %), height {:.3} ({h:.2}, \
             {:+.1} %), {} steps, {:.0} s",
            o.status,
            o.runout,
            100.0 * err,
            o.height,
            100.0 * herr,
            o.steps,
            o.wall
        );
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            c.dim,
            c.a,
            c.model.name(),
            c.base.name(c.model),
            c.wall_deg.map_or("none".into(), |d| d.to_string()),
            c.pic.map_or("0.001 per step".into(), Pic::name),
            c.resolution,
            o.status.replace(',', ";"),
            o.runout,
            low,
            high,
            err,
            o.height,
            h,
            herr,
            o.steps,
            o.particles,
            o.wall
        );
        rows.push((c, o, (low, high, err, h, herr)));
    }
    let name = only.as_ref().map_or("runout.csv".to_string(), |o| {
        format!("runout-{}.csv", o.replace(|c: char| !c.is_ascii_alphanumeric(), "_"))
    });
    std::fs::write(dir.join(name), &csv)?;
    if only.is_none() && !quick {
        // the table is generated; what is written about it (from `## What the table says` on)
        // is kept as it was
        let doc = crate::workspace_root().join("docs/runout.md");
        let old = std::fs::read_to_string(&doc).unwrap_or_default();
        let kept = old.find(WRITTEN).map_or("", |at| &old[at..]);
        std::fs::write(&doc, format!("{}\n{kept}", table(&rows)))?;
    } else {
        let name = only.as_ref().map_or("runout-quick".to_string(), |o| {
            format!("runout-{}", o.replace(|c: char| !c.is_ascii_alphanumeric(), "_"))
        });
        std::fs::write(dir.join(format!("{name}.md")), table(&rows))?;
    }
    println!("{}", table(&rows));
    Ok(ok)
}

type Row = (Case, Outcome, (f64, f64, f64, f64, f64));

/// where the hand-written part of `docs/runout.md` begins.
const WRITTEN: &str = "## What the table says";

/// the markdown table, and the Richardson estimates where three resolutions were run.
fn table(rows: &[Row]) -> String {
    let mut s = String::from(
        "# Runout against the column-collapse experiments\n\n\
         Generated by `cargo xtask runout` (see `xtask/src/runout.rs` for the sand, its sources \
         and the experiments' laws). Runout is (L∞ − L0)/L0 in 2D, (R∞ − R0)/R0 in 3D; height \
         is H∞/L0 (H∞/R0); errors are against the experiments' law (against the nearer edge of \
         the band between the two laws for 1.8 < a < 2.8 in 2D).\n\n\
         | dim | a | model | base | walls | PIC β | L0/Δx | status | runout | experiments | \
         error | height | experiments | error | steps | particles | wall (s) |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for (c, o, (low, high, err, h, herr)) in rows {
        let walls = match (c.dim, c.wall_deg) {
            (3, None) => "–".to_string(),
            (3, Some(d)) => format!("3D channel {CHANNEL} m, δ {d}°"),
            (_, None) => "none".into(),
            (_, Some(d)) => format!("{CHANNEL} m, δ {d}°"),
        };
        let exp = if low == high { format!("{low:.2}") } else { format!("{low:.2}–{high:.2}") };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {:.3} | {} | {:+.1} % | {:.3} | {:.2} | \
             {:+.1} % | {} | {} | {:.0} |",
            c.dim,
            c.a,
            c.model.name(),
            c.base.name(c.model),
            walls,
            c.pic.map_or("0.001 per step".into(), Pic::name),
            c.resolution,
            o.status,
            o.runout,
            exp,
            100.0 * err,
            o.height,
            h,
            100.0 * herr,
            o.steps,
            o.particles,
            o.wall
        );
    }
    // Richardson: the same case at r, 2r, 4r
    let mut rich = String::new();
    for (c, o, _) in rows {
        let same = |r: u32| {
            rows.iter().find(|(d, _, _)| {
                d.dim == c.dim
                    && d.a == c.a
                    && d.model == c.model
                    && d.base == c.base
                    && d.wall_deg == c.wall_deg
                    && d.pic == c.pic
                    && d.resolution == r
            })
        };
        let (Some((_, o2, _)), Some((_, o3, _))) = (same(2 * c.resolution), same(4 * c.resolution))
        else {
            continue;
        };
        let (f1, f2, f3) = (o.runout, o2.runout, o3.runout);
        let ratio = (f2 - f1) / (f3 - f2);
        // an order below ½ is not the asymptotic range: its extrapolation would run away
        if ratio > 2f64.sqrt() && ratio.is_finite() {
            let p = ratio.log2();
            let limit = f3 + (f3 - f2) / (2f64.powf(p) - 1.0);
            let (low, high) = experiment_runout_of(c.dim == 2 || c.wall_deg.is_some(), c.a);
            let _ = writeln!(
                rich,
                "| {} | {} | {} | {} | {:.3} / {:.3} / {:.3} | {p:.2} | {limit:.3} | {} |",
                c.dim,
                c.a,
                c.model.name(),
                c.wall_deg.map_or("none".into(), |d| format!("δ {d}°")),
                f1,
                f2,
                f3,
                if low == high { format!("{low:.2}") } else { format!("{low:.2}–{high:.2}") }
            );
        } else {
            let _ = writeln!(
                rich,
                "| {} | {} | {} | {} | {:.3} / {:.3} / {:.3} | not in the asymptotic range \
                 (order < ½ or not monotone) | – | – |",
                c.dim,
                c.a,
                c.model.name(),
                c.wall_deg.map_or("none".into(), |d| format!("δ {d}°")),
                f1,
                f2,
                f3
            );
        }
    }
    if !rich.is_empty() {
        s.push_str(
            "\n## Richardson estimates of the converged runout\n\n\
             | dim | a | model | walls | runout at L0/Δx = r, 2r, 4r | order | converged | \
             experiments |\n|---|---|---|---|---|---|---|---|\n",
        );
        s.push_str(&rich);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::Model;

    /// the beads without the rate dependence differ from the beads in μ_2 alone, set to μ_s.
    #[test]
    fn static_beads_are_the_beads_with_mu_2_at_mu_s() {
        let (rate, flat) = (Model::MuI.toml(), Model::MuIStatic.toml());
        assert!(rate.contains("mu_2 = 0.6435") && rate.contains("mu_s = 0.3819"), "{rate}");
        assert_eq!(flat, rate.replace("mu_2 = 0.6435", "mu_2 = 0.3819"));
        assert_ne!(flat, rate);
    }
}
