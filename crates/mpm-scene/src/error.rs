//! A scene that cannot run, with its file, line, column, field path, value, admissible range
//! and fix.

/// Why a scene was refused, before any step ran.
///
/// Displayed as
/// ```text
/// flume.toml:14:22: `materials.sand.friction_angle_deg` = 95: friction angle out of range
///   admissible: 0 ≤ φ < 90 (degrees)
///   fix: ...
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct SceneError {
    /// the file (or embedded scene) the text came from.
    pub origin: String,
    /// 1-based line, when the field (or its table) is in the text.
    pub line: Option<usize>,
    /// 1-based column (characters).
    pub column: Option<usize>,
    /// dotted field path, e.g. `materials.sand.friction_angle_deg`, `bodies[0].min` ("" for the
    /// whole file).
    pub path: String,
    /// the offending value as written, if there is one.
    pub value: Option<String>,
    /// what is wrong.
    pub problem: String,
    /// what would be admissible.
    pub admissible: String,
    /// how to fix it.
    pub fix: String,
}

impl std::fmt::Display for SceneError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.origin)?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(col) = self.column {
                write!(f, ":{col}")?;
            }
        }
        f.write_str(": ")?;
        if !self.path.is_empty() {
            write!(f, "`{}`", self.path)?;
            if let Some(v) = &self.value {
                write!(f, " = {v}")?;
            }
            f.write_str(": ")?;
        }
        write!(f, "{}", self.problem)?;
        if !self.admissible.is_empty() {
            write!(f, "\n  admissible: {}", self.admissible)?;
        }
        if !self.fix.is_empty() {
            write!(f, "\n  fix: {}", self.fix)?;
        }
        Ok(())
    }
}

impl std::error::Error for SceneError {}
