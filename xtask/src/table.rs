//! Result tables: one row per checked quantity, printed as aligned text and written as Markdown.

use std::fmt::Write as _;

/// Whether a row passed its check.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// within tolerance.
    Pass,
    /// outside tolerance (or the run failed): the command exits non-zero.
    Fail,
    /// reported only: the quantity has no exact reference (labelled as such).
    Info,
}

impl Status {
    /// the word printed in the table.
    pub fn word(self) -> &'static str {
        match self {
            Status::Pass => "pass",
            Status::Fail => "FAIL",
            Status::Info => "info",
        }
    }
}

/// A generic table: a header and rows of cells, with the status of each row.
#[derive(Clone, Debug, Default)]
pub struct Table {
    /// column titles.
    pub header: Vec<String>,
    /// rows of cells (as many as the header) and their status.
    pub rows: Vec<(Vec<String>, Status)>,
}

impl Table {
    /// an empty table with these column titles.
    pub fn new(header: &[&str]) -> Self {
        Self { header: header.iter().map(|s| s.to_string()).collect(), rows: Vec::new() }
    }

    /// appends a row.
    pub fn push(&mut self, cells: Vec<String>, status: Status) {
        self.rows.push((cells, status));
    }

    /// number of failed rows.
    /// a pass/fail row of the verification table against a bound stated in words: case,
    /// quantity, reference, its source, computed value, an error column left empty, tolerance.
    pub fn bound(
        &mut self,
        [case, quantity, reference, source, computed, tol]: [String; 6],
        ok: bool,
    ) {
        let status = if ok { Status::Pass } else { Status::Fail };
        let cells = vec![case, quantity, reference, source, computed, "–".into(), tol];
        self.push(cells.into_iter().chain([status.word().to_string()]).collect(), status);
    }

    pub fn failures(&self) -> usize {
        self.rows.iter().filter(|(_, s)| *s == Status::Fail).count()
    }

    /// aligned plain text (what the terminal shows).
    pub fn text(&self) -> String {
        let ncol = self.header.len();
        let mut width = vec![0; ncol];
        for row in std::iter::once(&self.header).chain(self.rows.iter().map(|(r, _)| r)) {
            for (w, c) in width.iter_mut().zip(row) {
                *w = (*w).max(c.chars().count());
            }
        }
        let mut out = String::new();
        let line = |out: &mut String, row: &[String]| {
            for (k, (w, c)) in width.iter().zip(row).enumerate() {
                let pad = w - c.chars().count();
                out.push_str(c);
                if k + 1 < ncol {
                    out.push_str(&" ".repeat(pad + 2));
                }
            }
            out.push('\n');
        };
        line(&mut out, &self.header);
        let total: usize = width.iter().sum::<usize>() + 2 * ncol.saturating_sub(1);
        out.push_str(&"-".repeat(total));
        out.push('\n');
        for (row, _) in &self.rows {
            line(&mut out, row);
        }
        out
    }

    /// a Markdown table.
    pub fn markdown(&self) -> String {
        let mut out = String::new();
        let esc = |c: &str| c.replace('|', "\\|");
        let _ = writeln!(
            out,
            "| {} |",
            self.header.iter().map(|h| esc(h)).collect::<Vec<_>>().join(" | ")
        );
        let _ = writeln!(out, "|{}", "---|".repeat(self.header.len()));
        for (row, _) in &self.rows {
            let _ =
                writeln!(out, "| {} |", row.iter().map(|c| esc(c)).collect::<Vec<_>>().join(" | "));
        }
        out
    }
}

/// A number in a compact form: 4 significant digits, scientific outside [1e-3, 1e5).
pub fn num(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let a = x.abs();
    if a == 0.0 {
        "0".into()
    } else if (1e-3..1e5).contains(&a) {
        let digits = (3 - a.log10().floor() as i32).clamp(0, 6) as usize;
        format!("{x:.digits$}")
    } else {
        format!("{x:.3e}")
    }
}

/// A fraction as a percentage with three significant digits.
pub fn pct(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let p = 100.0 * x;
    if p.abs() >= 0.01 || p == 0.0 { format!("{p:.3} %") } else { format!("{p:.2e} %") }
}
