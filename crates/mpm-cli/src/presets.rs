//! `solver.preset`: named speed/accuracy settings, from one table.
//!
//! A preset sets the update scheme, the shape function and the Courant number; any of those
//! given explicitly in `[solver]` wins over the preset. On the terrain grid only bilinear shape
//! functions exist, so there a preset's shape function is replaced by bilinear.
//!
//! **The values below are placeholders** chosen from the paper's advice (USAVG, C ≈ 0.1) and
//! the usual ranking of shape functions; `cargo xtask` measures the speed/accuracy trade
//! (SPEC §7) and updates this table from the measured Pareto front.

use mpm_solver::Scheme;

use crate::scene::{Preset, ShapeFunctionKind};

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

/// The table: (preset, settings). Placeholder values, see the module docs.
pub const PRESETS: [(Preset, PresetSettings); 3] = [
    (
        Preset::Fast,
        PresetSettings {
            scheme: Scheme::Usavg,
            shape_function: ShapeFunctionKind::Bilinear,
            courant: 0.4,
        },
    ),
    (
        Preset::Balanced,
        PresetSettings {
            scheme: Scheme::Usavg,
            shape_function: ShapeFunctionKind::Gimp,
            courant: 0.2,
        },
    ),
    (
        Preset::Accurate,
        PresetSettings {
            scheme: Scheme::Usavg,
            shape_function: ShapeFunctionKind::Bspline,
            courant: 0.1,
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
