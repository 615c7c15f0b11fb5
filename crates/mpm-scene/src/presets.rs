//! `solver.preset`: named speed/accuracy settings, from one table.
//!
//! A preset sets the update scheme, the shape function and the Courant number; any of those
//! given explicitly in `[solver]` wins over the preset. On the terrain grid only bilinear shape
//! functions exist, so there a preset's shape function is replaced by bilinear.
//!
//! The values come from the Pareto front of error against wall time that `cargo xtask study`
//! measures on the sliding block, the vibrating bar and the flume; the study rewrites
//! this table. The figures of each preset are in the table's doc comment and the README.

use mpm_solver::Scheme;

use crate::file::{Preset, ShapeFunctionKind};

/// What a preset sets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PresetSettings {
    /// update scheme.
    pub scheme: Scheme,
    /// shape functions (bilinear on a terrain grid whatever this says).
    pub shape_function: ShapeFunctionKind,
    /// Courant number.
    pub courant: f64,
}

/// The table: (preset, settings), measured by `cargo xtask study` (docs/verification.md, "Presets"):
/// fast: sliding block 0.156 %, bar 0.876 %, flume 13.076 % (worse of error and energy residual), 0.53 s.
/// balanced: sliding block 0.091 %, bar 0.839 %, flume 13.076 % (worse of error and energy residual), 0.53 s.
/// accurate: sliding block 0.017 %, bar 0.358 %, flume 9.682 % (worse of error and energy residual), 3.81 s.
pub const PRESETS: [(Preset, PresetSettings); 3] = [
    (
        Preset::Fast,
        PresetSettings {
            scheme: Scheme::Usavg,
            shape_function: ShapeFunctionKind::Bspline,
            courant: 0.4,
        },
    ),
    (
        Preset::Balanced,
        PresetSettings {
            scheme: Scheme::Usavg,
            shape_function: ShapeFunctionKind::Gimp,
            courant: 0.4,
        },
    ),
    (
        Preset::Accurate,
        PresetSettings {
            scheme: Scheme::Usavg,
            shape_function: ShapeFunctionKind::Bspline,
            courant: 0.05,
        },
    ),
];

/// the settings of `preset`.
pub fn settings(preset: Preset) -> PresetSettings {
    PRESETS.iter().find(|(p, _)| *p == preset).map_or(PRESETS[1].1, |(_, s)| *s)
}

/// The name of a preset as written in scene files.
pub fn name(preset: Preset) -> &'static str {
    match preset {
        Preset::Fast => "fast",
        Preset::Balanced => "balanced",
        Preset::Accurate => "accurate",
    }
}
