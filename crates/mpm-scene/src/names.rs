//! The nearest of some names to a mistyped one (a scene's table or key, an embedded scene).

/// the one of `names` nearest to `name` (fewest edits) if it is near enough to be what was
/// meant: at most a third of its characters (and at least one) changed.
pub(crate) fn nearest<'a>(name: &str, names: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    let limit = (name.chars().count() / 3).max(1);
    names
        .map(|n| (strsim::levenshtein(name, n), n))
        .filter(|&(d, _)| d <= limit)
        .min_by_key(|&(d, _)| d)
        .map(|(_, n)| n)
}
