//! Which boundaries `walls.csv` lists: the grid sides a scene declares, then its walls.

/// (name, index in the solver's loads) of each declared side (`declared[k]` for `sides[k]`),
/// then of each of the `walls` declared walls, named `wall_1`, `wall_2`, … in their order.
pub(crate) fn boundaries(sides: &[&str], declared: &[bool], walls: usize) -> Vec<(String, usize)> {
    let sides = sides.iter().zip(declared).enumerate().filter(|(_, (_, d))| **d);
    let sides = sides.map(|(k, (name, _))| ((*name).to_string(), k));
    sides.chain((0..walls).map(|k| (format!("wall_{}", k + 1), declared.len() + k))).collect()
}
