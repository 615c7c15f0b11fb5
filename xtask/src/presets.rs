//! The three named presets (`fast`, `balanced`, `accurate`) from the measured Pareto front, and
//! the code that writes them into the scene library's preset table (`crates/mpm-scene/src/presets.rs`).
//!
//! A preset fixes the scheme, the shape functions and the Courant number (the resolution stays the
//! scene's). The candidates are the runs of the `preset-sweep`: scheme (MUSL, USAVG) × shape ×
//! Courant on the horizontal sliding block and the vibrating bar at their baseline resolution, and
//! scheme × Courant on the flume (on the terrain grid a preset's shape function becomes bilinear,
//! so a candidate's flume run is the bilinear one with its scheme and Courant number). A run's
//! accuracy is the worse of its error and its energy residual; a candidate's score is the
//! geometric mean over the cases of (its accuracy / the best accuracy of that case) and its cost
//! the sum of its wall times. On the Pareto front of (cost, score):
//! - `accurate`: the smallest score;
//! - `fast`: the cheapest point whose accuracy meets [`FAST_TOLERANCE`] on the two cases with an
//!   exact reference (the cheapest point of the front if none does);
//! - `balanced`: the front point with the smallest cost × score other than those two (or, on a
//!   front of two points, the best such candidate between them).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use anyhow::{Context, Result, anyhow, bail};
use mpm_solver::Scheme;
use mpm_tests::ShapeKind;

use crate::runs::{Case, Run};
use crate::table::{Status, Table, num, pct};

/// The `fast` preset must still pass the verification tolerance of 1 % on both cases.
pub const FAST_TOLERANCE: f64 = 0.01;

/// One candidate setting and what it measured.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// scheme.
    pub scheme: Scheme,
    /// shape functions.
    pub shape: ShapeKind,
    /// Courant number.
    pub courant: f64,
    /// (case, relative error, wall time) of each case.
    pub cases: Vec<(Case, f64, f64)>,
    /// geometric mean of error / best error.
    pub score: f64,
    /// summed wall time (s).
    pub cost: f64,
}

/// The derived presets.
pub struct Presets {
    /// (name, candidate) for fast, balanced, accurate.
    pub chosen: Vec<(&'static str, Candidate)>,
    /// the table as printed.
    pub table: Table,
    /// the Markdown section of the report.
    pub markdown: String,
}

/// The accuracy of a run for the presets: the worse of its error against the reference and its
/// energy residual (a preset must not buy speed with energy).
fn accuracy(r: &Run) -> f64 {
    r.error.max(if r.energy.is_finite() { r.energy } else { f64::INFINITY })
}

/// derives the presets from the `preset-sweep` runs.
pub fn derive(runs: &[Run]) -> Result<Presets> {
    let sweep: Vec<&Run> =
        runs.iter().filter(|r| r.sweep == "preset-sweep" && r.error.is_finite()).collect();
    let mut cases = vec![Case::Horizontal, Case::Bar];
    if sweep.iter().any(|r| r.case == Case::Flume) {
        cases.push(Case::Flume);
    }
    let best: BTreeMap<Case, f64> = cases
        .iter()
        .map(|&c| {
            let b = sweep
                .iter()
                .filter(|r| r.case == c && accuracy(r) > 0.0)
                .map(|r| accuracy(r))
                .fold(f64::INFINITY, f64::min);
            (c, b)
        })
        .collect();
    let mut by_key: BTreeMap<String, Candidate> = BTreeMap::new();
    for r in sweep.iter().filter(|r| r.case != Case::Flume) {
        let key = format!("{:?} {:?} {}", r.d.scheme, r.d.shape, r.d.courant);
        let c = by_key.entry(key).or_insert_with(|| Candidate {
            scheme: r.d.scheme,
            shape: r.d.shape,
            courant: r.d.courant,
            cases: Vec::new(),
            score: f64::NAN,
            cost: 0.0,
        });
        c.cases.push((r.case, accuracy(r), r.wall));
    }
    // On the terrain grid a preset runs bilinear: its flume run is the one with its scheme and C.
    for c in by_key.values_mut() {
        if let Some(f) = sweep
            .iter()
            .find(|r| r.case == Case::Flume && r.d.scheme == c.scheme && r.d.courant == c.courant)
        {
            c.cases.push((Case::Flume, accuracy(f), f.wall));
        }
    }
    let mut candidates: Vec<Candidate> = by_key
        .into_values()
        .filter(|c| {
            cases
                .iter()
                .all(|k| c.cases.iter().any(|(cc, e, _)| cc == k && e.is_finite() && *e > 0.0))
        })
        .map(|mut c| {
            let logs: f64 = c.cases.iter().map(|(k, e, _)| (e / best[k]).ln()).sum::<f64>();
            c.score = (logs / c.cases.len() as f64).exp();
            c.cost = c.cases.iter().map(|(_, _, w)| w).sum();
            c
        })
        .collect();
    if candidates.is_empty() {
        bail!("no preset-sweep setting completed on every case");
    }
    candidates.sort_by(|a, b| a.cost.total_cmp(&b.cost).then(a.score.total_cmp(&b.score)));
    let mut front: Vec<Candidate> = Vec::new();
    for c in &candidates {
        if front.last().is_none_or(|l| c.score < l.score) {
            front.push(c.clone());
        }
    }
    let accurate = front.last().cloned().context("empty front")?;
    // Only the cases with an exact reference take part in the tolerance test (the flume's error
    // is measured against its own finest run).
    let within = |c: &Candidate| {
        c.cases.iter().filter(|(k, _, _)| *k != Case::Flume).all(|(_, e, _)| *e <= FAST_TOLERANCE)
    };
    let fast = front.iter().find(|c| within(c)).cloned().unwrap_or_else(|| front[0].clone());
    let same = |a: &Candidate, b: &Candidate| {
        a.scheme == b.scheme && a.shape == b.shape && a.courant == b.courant
    };
    let knee = |c: &&Candidate| c.cost * c.score;
    let balanced = front
        .iter()
        .filter(|c| c.cost > fast.cost && !same(c, &accurate) && !same(c, &fast))
        .min_by(|a, b| knee(a).total_cmp(&knee(b)))
        .or_else(|| {
            candidates
                .iter()
                .filter(|c| c.cost > fast.cost && c.cost < accurate.cost && c.score < fast.score)
                .min_by(|a, b| knee(a).total_cmp(&knee(b)))
        })
        .cloned()
        .unwrap_or_else(|| accurate.clone());
    let chosen = vec![("fast", fast), ("balanced", balanced), ("accurate", accurate)];

    let mut table = Table::new(&[
        "preset",
        "scheme",
        "shape",
        "Courant",
        "sliding: max(error, energy)",
        "bar: max(error, energy)",
        "flume: max(error, closure)",
        "wall sliding + bar + flume (s)",
        "relative cost",
    ]);
    let base_cost = chosen[0].1.cost;
    for (name, c) in &chosen {
        let get =
            |k: Case| c.cases.iter().find(|x| x.0 == k).copied().unwrap_or((k, f64::NAN, f64::NAN));
        let (h, b, f) = (get(Case::Horizontal), get(Case::Bar), get(Case::Flume));
        table.push(
            vec![
                (*name).into(),
                c.scheme.name().into(),
                c.shape.name().into(),
                num(c.courant),
                pct(h.1),
                pct(b.1),
                pct(f.1),
                format!("{:.3} + {:.3} + {:.3}", h.2, b.2, f.2),
                format!("{:.2}×", c.cost / base_cost),
            ],
            Status::Info,
        );
    }
    let mut markdown = String::new();
    let _ = writeln!(markdown, "\n## Presets\n");
    let _ = writeln!(
        markdown,
        "From the preset sweep (MUSL/USAVG × bilinear/uGIMP/B-spline × C ∈ {{0.05, 0.1, 0.2, 0.4, 0.8}}) on the horizontal \
         sliding block (0.25 m cells) and the vibrating bar (0.5 m cells), plus the flume (0.1 m cells, bilinear: what a \
         preset runs on the terrain grid), 2 × 2 particles per cell. A run's accuracy is the worse of its error and its \
         energy residual; score = geometric mean over the cases of accuracy / best accuracy; cost = summed wall time. \
         Pareto front ({} points): accurate = smallest score; fast = cheapest front point within {} on the sliding \
         block and the bar; balanced = smallest cost × score in between.\n",
        front.len(),
        pct(FAST_TOLERANCE)
    );
    markdown.push_str(&table.markdown());
    let _ = writeln!(
        markdown,
        "\nFront: {}",
        front
            .iter()
            .map(|c| format!(
                "{} {} C {} (score {:.2}, {:.2} s)",
                c.scheme.name(),
                c.shape.name(),
                c.courant,
                c.score,
                c.cost
            ))
            .collect::<Vec<_>>()
            .join("; ")
    );
    Ok(Presets { chosen, table, markdown })
}

/// writes `chosen` into the `PRESETS` table of `crates/mpm-scene/src/presets.rs` (only that table).
pub fn write_table(chosen: &[(&'static str, Candidate)]) -> Result<()> {
    let path = crate::workspace_root().join("crates/mpm-scene/src/presets.rs");
    let text =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    let start = text
        .find("pub const PRESETS")
        .ok_or_else(|| anyhow!("no `pub const PRESETS` in {}", path.display()))?;
    let doc_start = text[..start].rfind("\n///").map(|i| {
        // include the contiguous doc comment right above the table
        let mut s = i + 1;
        while let Some(prev) = text[..s - 1].rfind('\n') {
            if text[prev + 1..s].starts_with("///") {
                s = prev + 1;
            } else {
                break;
            }
        }
        s
    });
    let doc_start = doc_start.filter(|&d| !text[d..start].contains("\n\n")).unwrap_or(start);
    let end = text[start..]
        .find("\n];")
        .map(|i| start + i + 3)
        .ok_or_else(|| anyhow!("unterminated PRESETS table"))?;
    let mut table = String::new();
    let _ = writeln!(
        table,
        "/// The table: (preset, settings), measured by `cargo xtask study` (docs/verification.md, \"Presets\"):"
    );
    for (name, c) in chosen {
        let get = |k: Case| c.cases.iter().find(|x| x.0 == k).map_or(f64::NAN, |x| x.1);
        let _ = writeln!(
            table,
            "/// {name}: sliding block {}, bar {}, flume {} (worse of error and energy residual), {:.2} s.",
            pct(get(Case::Horizontal)),
            pct(get(Case::Bar)),
            pct(get(Case::Flume)),
            c.cost
        );
    }
    table.push_str("pub const PRESETS: [(Preset, PresetSettings); 3] = [\n");
    for (name, c) in chosen {
        let preset = match *name {
            "fast" => "Fast",
            "balanced" => "Balanced",
            _ => "Accurate",
        };
        let scheme = match c.scheme {
            Scheme::Usl => "Usl",
            Scheme::Musl => "Musl",
            Scheme::Usf => "Usf",
            Scheme::Usavg => "Usavg",
        };
        let shape = match c.shape {
            ShapeKind::Bilinear => "Bilinear",
            ShapeKind::Gimp => "Gimp",
            ShapeKind::BSpline => "Bspline",
        };
        let _ = write!(
            table,
            "    (\n        Preset::{preset},\n        PresetSettings {{\n            scheme: Scheme::{scheme},\n            shape_function: ShapeFunctionKind::{shape},\n            courant: {:?},\n        }},\n    ),\n",
            c.courant
        );
    }
    table.push_str("];");
    let new = format!("{}{}{}", &text[..doc_start], table, &text[end..]);
    std::fs::write(&path, new).with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}
