//! The dry sand flume of the paper's §7, run through the CLI's embedded scene.
//!
//! There is no exact answer: `verify` reports the front position and total runout and checks only
//! that every value is finite and that the energy ledger closes; `study` uses the finest run as
//! the reference of the others.

use crate::study::Run;
use crate::table::{Status, Table};

/// the flume rows of `verify`.
pub fn verify_rows(table: &mut Table, _notes: &mut String) {
    table.push(
        vec![
            "flume (§7)".into(),
            "front position, runout".into(),
            "no exact answer".into(),
            "paper §7".into(),
            "mpm-cli library not available".into(),
            "–".into(),
            "–".into(),
            "FAIL".into(),
        ],
        Status::Fail,
    );
}

/// the flume sweeps of `study`; returns the report section.
pub fn study(_quick: bool, _runs: &mut Vec<Run>) -> String {
    format!(
        "\n## Flume\n\nThe mpm-cli library is not available: no {} runs.\n",
        crate::study::Case::Flume.name()
    )
}
