//! One field of a scene changed by its path, for scripted studies (`Scene::with_value`): the
//! text is edited in place (comments and layout kept), then validated again as a whole, so a
//! changed scene is refused exactly as the same file would be.

use toml_edit::{DocumentMut, Item, Value};

use super::load;
use super::space::load_space;
use crate::error::SceneError;
use crate::scene::Scene;
use crate::space::SpaceScene;

/// One step of a field path: a key of a table, or an index into an array (of tables).
#[derive(Debug, PartialEq)]
enum Step<'a> {
    Key(&'a str),
    Index(usize),
}

/// `materials.sand.friction_angle_deg`, `bodies[0].min`, `bodies.0.min`, `grid.cells[1]`.
fn steps(path: &str) -> Option<Vec<Step<'_>>> {
    let mut out = Vec::new();
    for part in path.split('.') {
        let (key, mut rest) = part.split_once('[').map_or((part, ""), |(k, r)| (k, r));
        if !key.is_empty() {
            out.push(match key.parse::<usize>() {
                Ok(i) => Step::Index(i),
                Err(_) => Step::Key(key),
            });
        } else if rest.is_empty() {
            return None; // an empty segment: `a..b`, `.a`
        }
        while !rest.is_empty() {
            let (index, after) = rest.split_once(']')?;
            out.push(Step::Index(index.trim().parse().ok()?));
            rest = after.strip_prefix('[').unwrap_or(after);
            if !after.is_empty() && !after.starts_with('[') {
                return None; // `a[0]b`
            }
        }
    }
    (!out.is_empty()).then_some(out)
}

impl Scene {
    /// the same scene with the field at `path` set to `value`, a TOML value as written in a scene
    /// file (`35.0`, `"musl"`, `[0.0, 1.2]`, `{ kind = "coulomb", friction_deg = 20.0 }`), and
    /// validated again. A table on the path that the scene lacks is created; a field the format
    /// does not have is refused by the validation, located in the edited text, whose origin
    /// names the change.
    ///
    /// ```
    /// use mpm_scene::{embedded_scene, load_scene_str};
    ///
    /// let flume = load_scene_str(embedded_scene("flume").unwrap(), "flume").unwrap();
    /// let steeper = flume.with_value("materials.sand.friction_angle_deg", "35.0").unwrap();
    /// assert!(steeper.text().contains("friction_angle_deg = 35.0"));
    /// let e = flume.with_value("materials.sand.friction_angle_deg", "95.0").unwrap_err();
    /// assert_eq!(e.path, "materials.sand.friction_angle_deg");
    /// ```
    pub fn with_value(&self, path: &str, value: &str) -> Result<Scene, SceneError> {
        let text = edited(&self.text, &self.origin, path, value)?;
        self.reloaded(&text, &format!("with {path} = {value}"))
    }

    /// the same scene without the field at `path` (its default then applies), validated again:
    /// e.g. `solver.courant` removed before `solver.dt` is set.
    pub fn without_value(&self, path: &str) -> Result<Scene, SceneError> {
        let text = removed(&self.text, &self.origin, path)?;
        self.reloaded(&text, &format!("without {path}"))
    }

    /// the edited `text` validated as a whole, its refusals naming the `change`; it keeps this
    /// scene's origin and finds its files where this one found them.
    fn reloaded(&self, text: &str, change: &str) -> Result<Scene, SceneError> {
        let origin = format!("{} ({change})", self.origin);
        load(text, &origin, self.files_base()).map(|mut scene| {
            scene.origin = self.origin.clone();
            scene
        })
    }
}

impl SpaceScene {
    /// the same 3D scene without the field at `path`, validated again (as
    /// [`Scene::without_value`]).
    pub fn without_value(&self, path: &str) -> Result<SpaceScene, SceneError> {
        let text = removed(&self.text, &self.origin, path)?;
        self.reloaded(&text, &format!("without {path}"))
    }

    /// [`Scene::reloaded`] for a 3D scene.
    fn reloaded(&self, text: &str, change: &str) -> Result<SpaceScene, SceneError> {
        let origin = format!("{} ({change})", self.origin);
        load_space(text, &origin, self.files_base()).map(|mut scene| {
            scene.origin = self.origin.clone();
            scene
        })
    }
}

/// the value at `path` in a scene's `text` (`None` when the scene does not give it: its default
/// applies), or why the path is not one.
pub(crate) fn value_at(
    text: &str,
    origin: &str,
    path: &str,
) -> Result<Option<toml::Value>, SceneError> {
    let refuse = |problem: &str| SceneError {
        origin: origin.to_string(),
        line: None,
        column: None,
        path: path.to_string(),
        value: None,
        problem: problem.to_string(),
        admissible: String::new(),
        fix: "name the field as in the scene file, its tables joined by dots and array \
              elements by their index: `materials.sand.friction_angle_deg`, `bodies[0].min`"
            .into(),
    };
    let steps = steps(path).ok_or_else(|| refuse("not a field path"))?;
    let mut v: toml::Value = toml::from_str(text).map_err(|_| refuse("the scene's text"))?;
    for step in &steps {
        let next = match (step, v) {
            (Step::Key(k), toml::Value::Table(mut t)) => {
                // absent, or mistyped: a key of a near name is what was meant
                if !t.contains_key(*k) {
                    if let Some(near) = crate::names::nearest(k, t.keys().map(String::as_str)) {
                        return Err(SceneError {
                            problem: format!("the scene has no `{k}` here: did you mean `{near}`?"),
                            ..refuse("")
                        });
                    }
                }
                t.remove(*k)
            }
            (Step::Index(i), toml::Value::Array(mut a)) if *i < a.len() => Some(a.swap_remove(*i)),
            _ => None,
        };
        match next {
            Some(n) => v = n,
            None => return Ok(None),
        }
    }
    Ok(Some(v))
}

/// `text` without the field at `path` (comments and layout of the rest kept), or why not.
fn removed(text: &str, origin: &str, path: &str) -> Result<String, SceneError> {
    let refuse = |problem: String| SceneError {
        origin: origin.to_string(),
        line: None,
        column: None,
        path: path.to_string(),
        value: None,
        problem,
        admissible: String::new(),
        fix: "name a field the scene gives, its tables joined by dots: `solver.courant`".into(),
    };
    let steps = steps(path).ok_or_else(|| refuse("not a field path".into()))?;
    let (Step::Key(last), parents) = steps.split_last().ok_or_else(|| refuse("empty".into()))?
    else {
        return Err(refuse("an array element cannot be removed: set the whole array".into()));
    };
    let mut doc: DocumentMut =
        text.parse().map_err(|e| refuse(format!("the scene's text cannot be edited: {e}")))?;
    if !remove_in_item(doc.as_item_mut(), parents, last) {
        return Err(refuse("the scene does not give it".into()));
    }
    Ok(doc.to_string())
}

/// removes key `last` of the table at `steps` under `item`; false if there is none.
fn remove_in_item(item: &mut Item, steps: &[Step<'_>], last: &str) -> bool {
    match (steps.split_first(), item) {
        (None, Item::Table(t)) => t.remove(last).is_some(),
        (Some((Step::Key(k), rest)), Item::Table(t)) => {
            t.get_mut(k).is_some_and(|i| remove_in_item(i, rest, last))
        }
        (Some((Step::Index(i), rest)), Item::ArrayOfTables(a)) => {
            a.get_mut(*i).is_some_and(|t| remove_in_table(t, rest, last))
        }
        (_, Item::Value(v)) => remove_in_value(v, steps, last),
        _ => false,
    }
}

/// [`remove_in_item`] under a table of an array of tables.
fn remove_in_table(t: &mut toml_edit::Table, steps: &[Step<'_>], last: &str) -> bool {
    match steps.split_first() {
        None => t.remove(last).is_some(),
        Some((Step::Key(k), rest)) => t.get_mut(k).is_some_and(|i| remove_in_item(i, rest, last)),
        Some((Step::Index(_), _)) => false,
    }
}

/// [`remove_in_item`] inside an inline value (an inline table or an array).
fn remove_in_value(v: &mut Value, steps: &[Step<'_>], last: &str) -> bool {
    match (steps.split_first(), v) {
        (None, Value::InlineTable(t)) => t.remove(last).is_some(),
        (Some((Step::Key(k), rest)), Value::InlineTable(t)) => {
            t.get_mut(k).is_some_and(|v| remove_in_value(v, rest, last))
        }
        (Some((Step::Index(i), rest)), Value::Array(a)) => {
            a.get_mut(*i).is_some_and(|v| remove_in_value(v, rest, last))
        }
        _ => false,
    }
}

impl SpaceScene {
    /// the same 3D scene with the field at `path` set to `value`, validated again (as
    /// [`Scene::with_value`]).
    pub fn with_value(&self, path: &str, value: &str) -> Result<SpaceScene, SceneError> {
        let text = edited(&self.text, &self.origin, path, value)?;
        self.reloaded(&text, &format!("with {path} = {value}"))
    }
}

/// `text` with the field at `path` set to `value` (comments and layout kept), or why not.
fn edited(text: &str, origin: &str, path: &str, value: &str) -> Result<String, SceneError> {
    let refuse = |problem: String, fix: &str| SceneError {
        origin: origin.to_string(),
        line: None,
        column: None,
        path: path.to_string(),
        value: Some(value.to_string()),
        problem,
        admissible: String::new(),
        fix: fix.to_string(),
    };
    // a value longer than a scene may be is refused before it is parsed
    if value.len() as u64 > crate::limits::MAX_SCENE_BYTES {
        return Err(refuse(
            format!("the value alone is larger than a scene may be ({} bytes)", value.len()),
            "long outlines belong in fewer points (a polygon of at most 10 000 vertices)",
        ));
    }
    let Some(steps) = steps(path) else {
        return Err(refuse(
            "not a field path".into(),
            "name the field as in the scene file, its tables joined by dots and array \
             elements by their index: `materials.sand.friction_angle_deg`, `bodies[0].min`",
        ));
    };
    let new = parse_value(value).ok_or_else(|| {
        refuse(
            "not a TOML value".into(),
            "write the value as in a scene file: 35.0, \"musl\", true, [0.0, 1.2], \
             { kind = \"coulomb\", friction_deg = 20.0 }",
        )
    })?;
    let mut doc: DocumentMut = text.parse().map_err(|e| {
        refuse(format!("the scene's text cannot be edited: {e}"), "load the scene again")
    })?;
    set(doc.as_item_mut(), &steps, new)
        .map_err(|why| refuse(why, "name a field of the scene format (docs/scene-format.md)"))?;
    let text = doc.to_string();
    // edits add up: the scene as a whole stays within the size a scene file may have
    if text.len() as u64 > crate::limits::MAX_SCENE_BYTES {
        return Err(refuse(
            format!(
                "the edited scene would be {} bytes, more than a scene may be ({} bytes)",
                text.len(),
                crate::limits::MAX_SCENE_BYTES
            ),
            "long outlines belong in fewer points (a polygon of at most 10 000 vertices)",
        ));
    }
    Ok(text)
}

/// a TOML value written alone.
fn parse_value(text: &str) -> Option<Value> {
    let doc: DocumentMut = format!("v = {text}\n").parse().ok()?;
    let item = doc.get("v")?.clone();
    // `v = 1\nw = 2` would parse too: one value only
    (doc.len() == 1).then_some(())?;
    item.into_value().ok()
}

/// sets `steps` under `item` to `value`, creating missing tables on the way.
fn set(item: &mut Item, steps: &[Step<'_>], value: Value) -> Result<(), String> {
    let (first, rest) = steps.split_first().ok_or("an empty path")?;
    match (first, item) {
        (Step::Key(_), Item::Table(t)) => set_in_table(t, steps, value),
        (Step::Index(i), Item::ArrayOfTables(a)) => {
            let len = a.len();
            let t = a.get_mut(*i).ok_or(format!("index {i} beyond the {len} tables there"))?;
            if rest.is_empty() {
                return Err("a whole table cannot be set: set its fields one by one".into());
            }
            set_in_table(t, rest, value)
        }
        (_, Item::Value(v)) => set_value(v, steps, value),
        (Step::Key(k), _) => Err(format!("`{k}` is not under a table")),
        (Step::Index(i), _) => Err(format!("[{i}] is not an index of an array")),
    }
}

/// [`set`] under a table: the first step is a key of it.
fn set_in_table(t: &mut toml_edit::Table, steps: &[Step<'_>], value: Value) -> Result<(), String> {
    let (first, rest) = steps.split_first().ok_or("an empty path")?;
    let Step::Key(k) = first else {
        return Err("an index where a table's field was expected".into());
    };
    if rest.is_empty() {
        match t.get_mut(k) {
            // the key and its comments stay; the value takes the old one's spacing and comment
            Some(Item::Value(old)) => replace_keeping_decor(old, value),
            _ => {
                t.insert(k, Item::Value(value));
            }
        }
        return Ok(());
    }
    // a missing table is created, unless the scene has one of a near name: a typo
    // (`materials.snd.friction_angle_deg`) would otherwise make a new material without a kind
    if !t.contains_key(k) {
        let tables = t.iter().filter(|(_, i)| i.is_table() || i.is_inline_table());
        if let Some(name) = crate::names::nearest(k, tables.map(|(name, _)| name)) {
            return Err(format!(
                "the scene has no table `{k}` here: did you mean `{name}`? (to add a table of \
                 that name, set it whole, e.g. `{k}` = {{ kind = ... }})"
            ));
        }
    }
    let next = t.entry(k).or_insert_with(|| {
        let mut new = toml_edit::Table::new();
        new.set_implicit(true);
        Item::Table(new)
    });
    set(next, rest, value)
}

/// `old` becomes `new`, with `old`'s surrounding whitespace and trailing comment.
fn replace_keeping_decor(old: &mut Value, mut new: Value) {
    *new.decor_mut() = old.decor().clone();
    *old = new;
}

/// [`set`] inside an inline value (an inline table or an array).
fn set_value(v: &mut Value, steps: &[Step<'_>], value: Value) -> Result<(), String> {
    let (first, rest) = steps.split_first().ok_or("an empty path")?;
    match (first, v) {
        (Step::Key(k), Value::InlineTable(t)) => {
            if rest.is_empty() {
                match t.get_mut(k) {
                    Some(old) => replace_keeping_decor(old, value),
                    None => {
                        t.insert(*k, value);
                    }
                }
                return Ok(());
            }
            let v =
                t.entry(*k).or_insert_with(|| Value::InlineTable(toml_edit::InlineTable::new()));
            set_value(v, rest, value)
        }
        (Step::Index(i), Value::Array(a)) => {
            let len = a.len();
            if *i >= len {
                return Err(format!("index {i} beyond the {len} elements there"));
            }
            if rest.is_empty() {
                if let Some(old) = a.get_mut(*i) {
                    replace_keeping_decor(old, value);
                }
                return Ok(());
            }
            let element = a.get_mut(*i).ok_or(format!("index {i} beyond the array"))?;
            set_value(element, rest, value)
        }
        (Step::Key(k), _) => Err(format!("`{k}` is not under a table")),
        (Step::Index(i), _) => Err(format!("[{i}] is not an index of an array")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flume() -> Scene {
        crate::load_scene_str(crate::embedded_scene("flume").unwrap(), "flume").unwrap()
    }

    /// Switching from `courant` to `dt` needs the first removed (both given are refused);
    /// removing a field the scene does not give, or an array element, is refused at its path.
    #[test]
    fn a_removed_field_takes_its_default_and_an_absent_one_is_refused() {
        let f = flume();
        assert!(f.with_value("solver.dt", "1e-4").is_err());
        let fixed = f.without_value("solver.courant").unwrap().with_value("solver.dt", "1e-4");
        let fixed = fixed.unwrap();
        assert!(!fixed.text().contains("courant") && fixed.text().contains("dt = 1e-4"));
        // the comments of the rest stay
        assert!(fixed.text().contains("# centre, front toe"));
        for (path, why) in [
            ("solver.dt", "does not give it"),
            ("nothing.here", "does not give it"),
            ("output.probes[0]", "array element"),
            ("a..b", "not a field path"),
        ] {
            let e = f.without_value(path).unwrap_err();
            assert!(e.problem.contains(why) && e.path == path, "{path}: {}", e.problem);
        }
    }

    /// Edits add up to at most the size of a scene file: two values each under the limit are
    /// refused once their sum is over it (R3-10: Python's `set` made a 12 MB scene).
    #[test]
    fn edits_that_grow_a_scene_past_the_file_limit_are_refused() {
        let half = crate::limits::MAX_SCENE_BYTES as usize / 2 + 10;
        let title = format!("\"{}\"", "x".repeat(half));
        let once = flume().with_value("title", &title).unwrap();
        let e = once.with_value("grid.title_again", &title).unwrap_err();
        assert!(e.problem.contains("more than a scene may be"), "{}", e.problem);
    }

    /// `value_at` reads what the text gives, and `None` where a default applies.
    #[test]
    fn a_field_is_read_by_its_path() {
        let any = crate::AnyScene::Plane(Box::new(flume()));
        assert_eq!(any.value_at("solver.courant").unwrap(), Some(toml::Value::Float(0.1)));
        assert_eq!(
            any.value_at("output.probes[1].nearest[0]").unwrap(),
            Some(toml::Value::Float(1.07))
        );
        assert_eq!(any.value_at("solver.dt").unwrap(), None);
        let e = any.value_at("solver.courrant").unwrap_err();
        assert!(e.problem.contains("did you mean `courant`?"), "{}", e.problem);
        assert_eq!(any.value_at("output.probes[7]").unwrap(), None);
        assert!(any.value_at("a..b").is_err());
    }

    /// A mistyped table is refused with the nearest name instead of being created (a new
    /// material without a kind, whose message asked for its `kind`).
    #[test]
    fn a_mistyped_table_is_refused_with_the_nearest_name() {
        let e = flume().with_value("materials.snd.friction_angle_deg", "30.0").unwrap_err();
        assert!(e.problem.contains("did you mean `sand`?"), "{}", e.problem);
        assert_eq!(e.path, "materials.snd.friction_angle_deg");
        // a table of no near name is still created: a second material
        let two = flume().with_value("materials.gravel.kind", "\"elastic\"");
        assert!(two.is_err_and(|e| !e.problem.contains("did you mean")));
        // a table of a near name is added whole
        let whole = "{ kind = \"elastic\", young = 1e6, poisson = 0.3, density = 1600.0 }";
        assert!(flume().with_value("materials.sand2", whole).is_ok());
    }

    #[test]
    fn paths_are_split_into_keys_and_indices() {
        use Step::{Index, Key};
        assert_eq!(steps("a.b"), Some(vec![Key("a"), Key("b")]));
        assert_eq!(steps("bodies[0].min"), Some(vec![Key("bodies"), Index(0), Key("min")]));
        assert_eq!(
            steps("bodies.1.min[1]"),
            Some(vec![Key("bodies"), Index(1), Key("min"), Index(1)])
        );
        for bad in ["", "a..b", ".a", "a[x]", "a[0]b", "a[0"] {
            assert_eq!(steps(bad), None, "{bad}");
        }
    }

    /// A changed value keeps the comments above its key and after its value (the flume's
    /// header comment is the decoration of its first key, `title`).
    #[test]
    fn a_changed_value_keeps_the_comments_around_it() {
        let text = crate::scenes::embedded_scene("flume").unwrap();
        let flume = crate::validate::load_scene_str(text, "flume").unwrap();
        let titled = flume.with_value("title", "\"renamed\"").unwrap();
        assert!(titled.text().starts_with("# The dry-sand flume"), "{}", &titled.text()[..200]);
        assert!(titled.text().contains("\ntitle = \"renamed\"\n"));
        let quiet = flume.with_value("output.envelope", "false").unwrap();
        assert!(quiet.text().contains("envelope = false        # envelope.csv, deposit.csv"));
        let ground = flume.with_value("boundaries.ground.friction_angle_deg", "25.0").unwrap();
        assert!(ground.text().contains("ground = { friction_angle_deg = 25.0 }"));
        let probe = flume.with_value("output.probes[1].nearest[0]", "1.1").unwrap();
        assert!(probe.text().contains("{ nearest = [1.1, 0.86] }]   # centre, front toe"));
        // the same refusal as the file's, located in the edited text and naming the change
        let e = flume.with_value("materials.sand.friction_angle_deg", "95.0").unwrap_err();
        assert_eq!((e.path.as_str(), e.line), ("materials.sand.friction_angle_deg", Some(38)));
        assert!(e.origin.contains("with materials.sand.friction_angle_deg = 95.0"), "{e}");
        assert!(flume.with_value("bodies[7].min", "[0.0, 0.0]").is_err());
        assert!(flume.with_value("solver.end_time", "3.0 4.0").is_err());
    }
}
