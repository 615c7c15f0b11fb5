//! The embedded scenes (compiled in from `scenes/*.toml`).
//!
//! The paper's element tests are not a scene (no grid, body or time): run them with
//! `mpm element-test`.

/// (name, TOML text) of every embedded scene; the first is the default of `mpm run`.
pub const SCENES: [(&str, &str); 4] = [
    ("flume", include_str!("../scenes/flume.toml")),
    ("free_fall", include_str!("../scenes/free_fall.toml")),
    ("sliding_horizontal", include_str!("../scenes/sliding_horizontal.toml")),
    ("sliding_inclined", include_str!("../scenes/sliding_inclined.toml")),
];

/// The scene `mpm run` runs without an argument.
pub const DEFAULT_SCENE: &str = "flume";

/// The text of the embedded scene `name`.
pub fn embedded_scene(name: &str) -> Option<&'static str> {
    SCENES.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
}

/// The `title` line of a scene text (for listings), if it has one.
pub fn title_of(text: &str) -> Option<String> {
    let value: toml::Value = toml::from_str(text).ok()?;
    value.get("title")?.as_str().map(str::to_string)
}
