//! `check`: what a run of a scene of either dimension would do, without running it: its
//! particles, grid, scheme, first Δt, step count, memory and frames, and its warnings.

use std::fmt;

use mpm_scene::{AnyScene, Warning};
use mpm_solver::{Scheme, TimeStep, Transfer};

use crate::common::CheckReport;
use crate::error::RunError;

/// A scene checked: what it declares and what its run would need ([`check`]); its `Display` is
/// what `mpm check` prints.
#[derive(Clone, Debug)]
pub struct Checked {
    /// how messages name the scene (a path or `embedded:NAME`).
    pub origin: String,
    /// 2 (plane strain) or 3.
    pub dimension: usize,
    /// what the run would need.
    pub report: CheckReport,
    /// the update scheme.
    pub scheme: Scheme,
    /// the shape functions' name (`bilinear` in 2D is `trilinear` in 3D).
    pub shape_function: &'static str,
    /// the particle ↔ grid velocity transfer.
    pub transfer: Transfer,
    /// the time-step control.
    pub time_step: TimeStep,
    /// the end time (s).
    pub end_time: f64,
    /// the plausibility warnings, less the silenced ones.
    pub warnings: Vec<Warning>,
}

/// checks a scene of either dimension ([`crate::check_scene`], [`crate::check_space_scene`]).
pub fn check(scene: &AnyScene) -> Result<Checked, RunError> {
    Ok(match scene {
        AnyScene::Plane(s) => {
            let c = s.solver_config();
            Checked {
                origin: s.origin().to_string(),
                dimension: 2,
                report: crate::check_scene(s)?,
                scheme: c.scheme,
                shape_function: s.shape_function().name(),
                transfer: c.transfer,
                time_step: c.time_step,
                end_time: s.end_time(),
                warnings: s.resolved().warnings.clone(),
            }
        }
        AnyScene::Space(s) => {
            let c = &s.config;
            Checked {
                origin: s.origin().to_string(),
                dimension: 3,
                report: crate::check_space_scene(s)?,
                scheme: c.scheme,
                shape_function: s.shape_function.name_in(3),
                transfer: c.transfer,
                time_step: c.time_step,
                end_time: s.end_time,
                warnings: s.warnings.clone(),
            }
        }
    })
}

impl fmt::Display for Checked {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.report;
        let space = if self.dimension == 3 { " (3D)" } else { "" };
        writeln!(f, "{}: valid{space}", self.origin)?;
        for w in &self.warnings {
            writeln!(f, "  warning: {w}")?;
        }
        writeln!(f, "  particles:        {}", r.particles)?;
        let cells: Vec<String> = r.cells.iter().map(ToString::to_string).collect();
        writeln!(
            f,
            "  grid:             {} cells, {} active nodes at t = 0",
            cells.join(" × "),
            r.active_nodes
        )?;
        writeln!(
            f,
            "  scheme:           {}, {} shape functions, {} transfer, time step {:?}",
            self.scheme.name(),
            self.shape_function,
            self.transfer.name(),
            self.time_step
        )?;
        writeln!(f, "  initial Δt:       {:.4e} s", r.initial_dt)?;
        writeln!(
            f,
            "  steps:            {} or more to t = {} s (Δt shrinks as the material speeds up or \
             dilates)",
            r.estimated_steps, self.end_time
        )?;
        if let Some(n) = r.initial_state_steps {
            writeln!(f, "  initial state:    gravity ramp, {n} steps or more before t = 0")?;
        }
        writeln!(f, "  memory:           about {:.2} MB", r.memory_bytes as f64 / 1e6)?;
        write!(
            f,
            "  frames:           {} (about {:.1} MB on disk)",
            r.frames,
            r.frame_bytes as f64 / 1e6
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // One check for both dimensions: each counts its scene's own particles (a 0.4 × 0.2 × 0.4 m
    // box at 2 × 2 × 2 per 0.1 m cell is 4 × 2 × 4 cells × 8 = 256), its grid's cells along each
    // axis, and names its own shape functions.
    #[test]
    fn one_check_for_both_dimensions() {
        let plane = AnyScene::from_str(crate::embedded_scene("flume").unwrap(), "flume").unwrap();
        let c = check(&plane).unwrap();
        let AnyScene::Plane(s) = &plane else { unreachable!("the flume is plane strain") };
        assert_eq!((c.dimension, c.shape_function), (2, "bilinear"));
        assert_eq!(c.report.particles, s.resolved().seeds.len());
        assert_eq!(c.report.cells.len(), 2);
        assert!(c.to_string().starts_with("flume: valid\n"));

        let text = r#"
[grid]
dimension = 3
kind = "regular"
origin = [0.0, 0.0, 0.0]
cell = [0.1, 0.1, 0.1]
cells = [20, 4, 10]
[materials.block]
kind = "elastic"
young = 1.0e6
poisson = 0.3
density = 1600.0
[[bodies]]
material = "block"
shape = "box"
min = [0.2, 0.0, 0.3]
max = [0.6, 0.2, 0.7]
[boundaries]
ground = "frictionless"
[solver]
end_time = 1.0
"#;
        let space = AnyScene::from_str(text, "block3d").unwrap();
        let c = check(&space).unwrap();
        assert_eq!((c.dimension, c.shape_function), (3, "trilinear"));
        assert_eq!(c.report.particles, 256);
        assert_eq!(c.report.cells, vec![20, 4, 10]);
        let shown = c.to_string();
        assert!(shown.starts_with("block3d: valid (3D)\n"), "{shown}");
        assert!(shown.contains("20 × 4 × 10 cells"), "{shown}");
    }
}
