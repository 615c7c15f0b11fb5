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

/// the embedded scene whose name is nearest to `name` (fewest edits), if it is near enough to
/// be what was meant: at most a third of the name's characters (and at least one) changed.
pub fn nearest_scene(name: &str) -> Option<&'static str> {
    crate::names::nearest(name, SCENES.iter().map(|(n, _)| *n))
}

/// the refusal of an unknown embedded scene's name: the nearest name if one is near, and the
/// list.
pub fn unknown_scene_message(name: &str) -> String {
    let names: Vec<&str> = SCENES.iter().map(|(n, _)| *n).collect();
    let near = nearest_scene(name).map_or(String::new(), |n| format!("did you mean `{n}`? "));
    format!("no embedded scene `{name}`: {near}the embedded scenes are {}", names.join(", "))
}

/// The `title` line of a scene text (for listings), if it has one.
pub fn title_of(text: &str) -> Option<String> {
    let value: toml::Value = toml::from_str(text).ok()?;
    value.get("title")?.as_str().map(str::to_string)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-letter slip finds its scene; a name unlike any finds none, and the message lists
    /// them all either way.
    #[test]
    fn a_mistyped_scene_name_finds_the_nearest_one() {
        assert_eq!(nearest_scene("flum"), Some("flume"));
        assert_eq!(nearest_scene("free-fall"), Some("free_fall"));
        assert_eq!(nearest_scene("avalanche"), None);
        let m = unknown_scene_message("flum");
        assert!(m.contains("did you mean `flume`?") && m.contains("free_fall"), "{m}");
        assert!(!unknown_scene_message("avalanche").contains("did you mean"));
    }
}
