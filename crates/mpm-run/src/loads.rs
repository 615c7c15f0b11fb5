//! Which boundaries `walls.csv` lists: the grid sides a scene declares, then its walls, then
//! the side walls across the plane of a plane-strain run.

/// (name, index in the solver's loads) of each declared side (`declared[k]` for `sides[k]`),
/// then of each of the `walls` declared walls, named `wall_1`, `wall_2`, … in their order, then
/// `side_walls` when `side_walls`.
pub(crate) fn boundaries(
    sides: &[&str],
    declared: &[bool],
    walls: usize,
    side_walls: bool,
) -> Vec<(String, usize)> {
    let named = sides.iter().zip(declared).enumerate().filter(|(_, (_, d))| **d);
    let named = named.map(|(k, (name, _))| ((*name).to_string(), k));
    let walls_at = |k| (format!("wall_{}", k + 1), declared.len() + k);
    let side = side_walls.then(|| ("side_walls".to_string(), declared.len() + walls));
    named.chain((0..walls).map(walls_at)).chain(side).collect()
}
