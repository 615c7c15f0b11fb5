//! Outlines of a set of raster cells as polygons in map coordinates, for GeoJSON: the deposit, the
//! affected area and the release of a 3D run, which a GIS overlays on its own maps.
//!
//! The cells' boundary edges are walked with the set on the left, so that outer rings run
//! counter-clockwise and holes clockwise (the orientation RFC 7946 asks for); at a vertex where
//! two cells touch only by a corner the walk turns left, which keeps such cells apart rather than
//! joining them through the corner. Each hole goes to the smallest outer ring around it.

use std::collections::HashMap;
use std::fmt::Write as _;

/// A lattice vertex (column, row counted from the south edge).
type Vertex = (i64, i64);

/// The rings bounding the cells of `mask` (`cols` × `rows`, row 0 the northern one, as rasters
/// are written), in lattice vertices (column, row counted from the south), each closed (its first
/// vertex repeated at the end) and without collinear vertices: outer rings counter-clockwise,
/// holes clockwise.
pub fn rings(mask: &[bool], cols: usize, rows: usize) -> Vec<Vec<Vertex>> {
    let filled = |c: i64, s: i64| {
        c >= 0
            && s >= 0
            && (c as usize) < cols
            && (s as usize) < rows
            && mask[(rows - 1 - s as usize) * cols + c as usize]
    };
    // the directed boundary edges, by start vertex
    let mut out: HashMap<Vertex, Vec<Vertex>> = HashMap::new();
    let mut edges = Vec::new();
    for s in 0..rows as i64 {
        for c in 0..cols as i64 {
            if !filled(c, s) {
                continue;
            }
            for (neighbour, from, to) in [
                ((c, s - 1), (c, s), (c + 1, s)),
                ((c + 1, s), (c + 1, s), (c + 1, s + 1)),
                ((c, s + 1), (c + 1, s + 1), (c, s + 1)),
                ((c - 1, s), (c, s + 1), (c, s)),
            ] {
                if !filled(neighbour.0, neighbour.1) {
                    out.entry(from).or_default().push(to);
                    edges.push((from, to));
                }
            }
        }
    }
    let mut rings = Vec::new();
    for &(first, second) in &edges {
        let Some(next) = out.get_mut(&first) else { continue };
        let Some(k) = next.iter().position(|&v| v == second) else { continue };
        next.swap_remove(k);
        let mut ring = vec![first, second];
        let (mut prev, mut at) = (first, second);
        while at != first {
            let d = (at.0 - prev.0, at.1 - prev.1);
            let Some(next) = out.get_mut(&at) else { break };
            // left turn, straight on, right turn
            let turns = [(-d.1, d.0), d, (d.1, -d.0)];
            let Some(k) =
                turns.iter().find_map(|t| next.iter().position(|&v| v == (at.0 + t.0, at.1 + t.1)))
            else {
                break;
            };
            let v = next.swap_remove(k);
            (prev, at) = (at, v);
            ring.push(v);
        }
        rings.push(simplify(ring));
    }
    rings
}

/// the ring without its collinear vertices (still closed).
fn simplify(ring: Vec<Vertex>) -> Vec<Vertex> {
    let n = ring.len() - 1; // (closed: the last repeats the first)
    let turn =
        |a: Vertex, b: Vertex, c: Vertex| (b.0 - a.0) * (c.1 - b.1) - (b.1 - a.1) * (c.0 - b.0);
    let mut kept: Vec<Vertex> = (0..n)
        .filter(|&i| turn(ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]) != 0)
        .map(|i| ring[i])
        .collect();
    kept.push(kept[0]);
    kept
}

/// twice the signed area of a closed ring (> 0 counter-clockwise).
pub(crate) fn area2(ring: &[Vertex]) -> i64 {
    ring.windows(2).map(|w| w[0].0 * w[1].1 - w[1].0 * w[0].1).sum()
}

/// whether point `p` (in lattice units) lies inside closed ring `ring` (even-odd rule).
fn inside(ring: &[Vertex], p: (f64, f64)) -> bool {
    let mut c = false;
    for w in ring.windows(2) {
        let (a, b) = ((w[0].0 as f64, w[0].1 as f64), (w[1].0 as f64, w[1].1 as f64));
        if (a.1 > p.1) != (b.1 > p.1) && p.0 < a.0 + (p.1 - a.1) / (b.1 - a.1) * (b.0 - a.0) {
            c = !c;
        }
    }
    c
}

/// The polygons of `rings`: each outer ring with the holes it holds.
pub fn polygons(rings: Vec<Vec<Vertex>>) -> Vec<Vec<Vec<Vertex>>> {
    let (outer, holes): (Vec<_>, Vec<_>) = rings.into_iter().partition(|r| area2(r) > 0);
    let mut polygons: Vec<Vec<Vec<Vertex>>> = outer.into_iter().map(|r| vec![r]).collect();
    for hole in holes {
        // a point just inside the cells along the hole's first edge (they are on its left)
        let (a, b) = (hole[0], hole[1]);
        let (dx, dy) = ((b.0 - a.0) as f64, (b.1 - a.1) as f64);
        let p = (0.5 * (a.0 + b.0) as f64 - 0.25 * dy, 0.5 * (a.1 + b.1) as f64 + 0.25 * dx);
        let owner = polygons
            .iter()
            .enumerate()
            .filter(|(_, poly)| inside(&poly[0], p))
            .min_by_key(|(_, poly)| area2(&poly[0]))
            .map(|(k, _)| k);
        if let Some(k) = owner {
            polygons[k].push(hole);
        }
    }
    polygons
}

/// One feature of [`geojson`]: a name, the cells it covers (as for [`rings`]) and its properties
/// as (key, value) pairs of numbers.
pub struct Outline<'a> {
    /// the feature's `name` property.
    pub name: &'a str,
    /// the cells it covers, row 0 the northern one.
    pub mask: &'a [bool],
    /// more numeric properties.
    pub properties: Vec<(&'a str, f64)>,
}

/// A GeoJSON FeatureCollection of `outlines` over a raster of `cols` × `rows` cells of `cell` m
/// whose north-west corner is at map `corner` [x, y]: one MultiPolygon feature per outline.
pub fn geojson(
    outlines: &[Outline<'_>],
    cols: usize,
    rows: usize,
    cell: f64,
    corner: [f64; 2],
) -> String {
    let south = corner[1] - rows as f64 * cell;
    let mut s = String::from("{\"type\":\"FeatureCollection\",\"features\":[");
    for (k, o) in outlines.iter().enumerate() {
        if k > 0 {
            s.push(',');
        }
        let _ = write!(s, "{{\"type\":\"Feature\",\"properties\":{{\"name\":\"{}\"", o.name);
        for (key, value) in &o.properties {
            let _ = write!(s, ",\"{key}\":{}", if value.is_finite() { *value } else { 0.0 });
        }
        s.push_str("},\"geometry\":{\"type\":\"MultiPolygon\",\"coordinates\":[");
        for (p, polygon) in polygons(rings(o.mask, cols, rows)).iter().enumerate() {
            s.push_str(if p > 0 { ",[" } else { "[" });
            for (r, ring) in polygon.iter().enumerate() {
                s.push_str(if r > 0 { ",[" } else { "[" });
                for (v, &(c, row)) in ring.iter().enumerate() {
                    let (x, y) = (corner[0] + c as f64 * cell, south + row as f64 * cell);
                    let _ = write!(s, "{}[{x},{y}]", if v > 0 { "," } else { "" });
                }
                s.push(']');
            }
            s.push(']');
        }
        s.push_str("]}}");
    }
    s.push_str("]}\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mask(rows: &[&str]) -> (Vec<bool>, usize, usize) {
        let cols = rows[0].len();
        (rows.iter().flat_map(|r| r.chars().map(|c| c == '#')).collect(), cols, rows.len())
    }

    /// a ring of cells around an empty one: one outer ring (counter-clockwise, 4 corners) holding
    /// one hole (clockwise, 4 corners); two cells that touch at a corner stay two polygons.
    #[test]
    fn a_ring_of_cells_is_a_polygon_with_a_hole_and_corner_neighbours_stay_apart() {
        let (m, c, r) = mask(&["###.", "#.#.", "###.", "...#"]);
        let polys = polygons(rings(&m, c, r));
        assert_eq!(polys.len(), 2, "{polys:?}");
        let big = polys.iter().find(|p| p.len() == 2).expect("the ring with its hole");
        assert_eq!(big[0].len(), 5, "{big:?}");
        assert_eq!(area2(&big[0]), 18, "3 × 3 cells, counter-clockwise");
        assert_eq!(area2(&big[1]), -2, "one cell, clockwise");
        let small = polys.iter().find(|p| p.len() == 1).unwrap();
        assert_eq!(small[0], vec![(3, 0), (4, 0), (4, 1), (3, 1), (3, 0)]);
        // the total area of the polygons is the number of cells
        let cells = m.iter().filter(|&&f| f).count() as i64;
        let area: i64 = polys.iter().flatten().map(|r| area2(r)).sum();
        assert_eq!(area, 2 * cells);
    }

    /// an island inside the hole of a larger polygon: the island is its own polygon, not a second
    /// hole, and the GeoJSON places the corners on the map.
    #[test]
    fn an_island_in_a_hole_is_its_own_polygon_on_the_map() {
        let (m, c, r) = mask(&["#####", "#...#", "#.#.#", "#...#", "#####"]);
        let polys = polygons(rings(&m, c, r));
        assert_eq!(polys.len(), 2);
        assert_eq!(polys.iter().map(Vec::len).max(), Some(2));
        let (m, c, r) = mask(&["#"]);
        let text = geojson(
            &[Outline { name: "deposit", mask: &m, properties: vec![("area_m2", 4.0)] }],
            c,
            r,
            2.0,
            [100.0, 50.0],
        );
        assert!(text.contains("[[[[100,48],[102,48],[102,50],[100,50],[100,48]]]]"), "{text}");
        assert!(text.contains("\"name\":\"deposit\",\"area_m2\":4"));
    }
}
