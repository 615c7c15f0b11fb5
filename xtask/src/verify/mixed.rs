//! Verify rows of a scene with two constitutive models (`docs/examples/sand_on_slab.toml`): a
//! Drucker-Prager sand layer settled by the implicit initial state on an elastic slab, each
//! particle updated by its own material's model.

use anyhow::{Context, Result, anyhow};
use mpm_constitutive::PlaneTensor;
use mpm_grid::ShapeFunctions;
use mpm_scene::{InitialState, Job, Scene, SceneModel, dispatch};
use mpm_solver::Solver;

use super::Rows;

/// The bound on the slab's base stress against the overburden of both layers.
const OVERBURDEN_REL: f64 = 0.02;
/// A zero increment leaves a state on or inside the cone unchanged: rounding of the return
/// mapping (as the slope's row).
const ON_CONE: f64 = 1e-12;
/// The slab's lateral stress ratio against ν/(1 − ν): the Newton tolerance's share of a linear
/// elastic solve (measured 1.5e-12).
const K0_REL: f64 = 1e-6;
/// Gravity of the scene (m/s², its default).
const GRAVITY: f64 = 9.81;

/// What the layered column measured after the implicit initial state.
struct Layered {
    /// mean σ_yy of the slab's lowest row of cells over the overburden at its centre, − 1.
    base_error: f64,
    /// sand particles on their cone (plastic), of all sand particles.
    sand_plastic_share: f64,
    /// max over the sand of |Δσ|/|σ| of a zero increment (0: on or inside the cone).
    sand_outside_cone: f64,
    /// max over the slab of |σ_xx/σ_yy − ν/(1 − ν)|.
    slab_k0_error: f64,
    /// min over the slab of |Δσ|/|σ| of a zero increment of the sand's model at the slab's
    /// stress: > 0 when the sand's cone refuses the slab's state.
    slab_outside_sand_cone: f64,
}

/// builds the solver, solves the initial state and measures.
struct Measure;

impl Job for Measure {
    type Output = Result<Layered>;

    fn run<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        self,
        scene: &Scene,
        shape: S,
        materials: Vec<M>,
    ) -> Result<Layered> {
        let r = scene.resolved();
        let InitialState::Implicit(settings) = r.initial_state else {
            return Err(anyhow!("the scene asks no implicit initial state"));
        };
        let particles = mpm_scene::dispatch::particles(&r.seeds, &materials);
        let mut s = Solver::new(shape, materials, particles, r.config.clone())?;
        s.solve_geostatic(&settings)?;
        // materials in name order: 0 = sand, 1 = slab; bodies in file order: 0 = slab.
        let (sand, slab) = (&s.materials()[0], &s.materials()[1]);
        let zero_step = |m: &M, st: &PlaneTensor, state: &M::State| -> Result<f64> {
            let (mut sigma, mut state) = (*st, *state);
            m.update_plane(&mut sigma, &mut state, &PlaneTensor::ZERO, 1.0, None)?;
            Ok((sigma - *st).norm() / st.norm())
        };
        let p = s.particles();
        let (cell, overburden) = (0.1, GRAVITY * (1600.0 * 1.0 + 2500.0 * 0.95));
        let (mut base_sum, mut base_n) = (0.0, 0.0);
        let mut out = Layered {
            base_error: 0.0,
            sand_plastic_share: 0.0,
            sand_outside_cone: 0.0,
            slab_k0_error: 0.0,
            slab_outside_sand_cone: f64::INFINITY,
        };
        let (mut sand_n, mut sand_plastic) = (0.0, 0.0);
        for q in 0..p.len() {
            let (st, state, y) = (&p.stress[q], &p.state[q], p.position[q].y);
            if p.body[q] == 0 {
                if y < cell {
                    base_sum += st.yy;
                    base_n += 1.0;
                }
                let k0 = 0.2 / (1.0 - 0.2);
                out.slab_k0_error = out.slab_k0_error.max((st.xx / st.yy - k0).abs());
                let sand_state = sand.initial_state();
                out.slab_outside_sand_cone =
                    out.slab_outside_sand_cone.min(zero_step(sand, st, &sand_state)?);
                // the slab's own model leaves it as it is
                out.slab_k0_error = out.slab_k0_error.max(zero_step(slab, st, state)?);
            } else {
                sand_n += 1.0;
                if sand.equivalent_plastic_strain(state) > 0.0 {
                    sand_plastic += 1.0;
                }
                out.sand_outside_cone = out.sand_outside_cone.max(zero_step(sand, st, state)?);
            }
        }
        out.base_error = (base_sum / base_n / -overburden - 1.0).abs();
        out.sand_plastic_share = sand_plastic / sand_n;
        Ok(out)
    }
}

/// appends the rows.
pub(super) fn rows(rows: &mut Rows) {
    let case = "sand 1 m (DP φ 30°) on elastic slab 1 m, implicit initial state";
    let path = crate::workspace_root().join("docs/examples/sand_on_slab.toml");
    let measured = mpm_scene::load_scene_file(&path)
        .map_err(|e| anyhow!("{e}"))
        .and_then(|scene| dispatch(&scene, Measure).map_err(|e| anyhow!("{e}"))?)
        .with_context(|| path.display().to_string());
    let m = match measured {
        Ok(m) => m,
        Err(e) => return rows.failed(case, "run", &format!("{e:#}")),
    };
    rows.at_most(
        (case, "|σ_yy slab base / overburden − 1|"),
        "g (ρ_sand h_sand + ρ_slab h_slab)",
        "equilibrium of both layers",
        m.base_error,
        OVERBURDEN_REL,
        true,
    );
    rows.at_most(
        (case, "max |σ_xx/σ_yy − ν/(1 − ν)| in the slab"),
        "K0 = 0.25 (elastic)",
        "the slab follows its own model",
        m.slab_k0_error,
        K0_REL,
        false,
    );
    rows.at_least(
        (case, "min |Δσ|/|σ| of the sand's cone at the slab's stress"),
        "> 0 (the cone refuses K0 = 0.25)",
        "the slab is not the sand",
        m.slab_outside_sand_cone,
        0.01,
    );
    rows.at_most(
        (case, "max |Δσ|/|σ| of a zero increment, sand"),
        "0 (on or inside its cone)",
        "the sand follows its own model",
        m.sand_outside_cone,
        ON_CONE,
        false,
    );
    rows.at_least(
        (case, "sand particles on their cone"),
        "all (K0 = 0.25 < active limit)",
        "plastic in 1D compression",
        m.sand_plastic_share,
        1.0,
    );
}
