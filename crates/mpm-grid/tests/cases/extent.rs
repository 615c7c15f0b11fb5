//! Node storage follows the material: a 10 km long terrain grid holding a 1 m² body stores and
//! iterates what the body needs, as does the grid itself.

use std::time::Instant;

use mpm_grid::{
    ActiveNodes, Bilinear, KinkPolicy, ShapeFunctions, Stencil, TerrainGrid, TerrainGridSpec,
    Vector,
};

fn slope(length: f64) -> Bilinear<TerrainGrid> {
    let t = 30f64.to_radians().tan();
    // a 30° slope of the given length, then a 100 m runout.
    Bilinear(
        TerrainGrid::new(TerrainGridSpec {
            profile: vec![
                Vector::new(0.0, length * t),
                Vector::new(length, 0.0),
                Vector::new(length + 100.0, 0.0),
            ],
            cell_width: 0.1,
            row_height: 0.1,
            rows: 40,
            kink_policy: KinkPolicy::Reject,
        })
        .unwrap(),
    )
}

/// stencils of a 1 m × 1 m block of 20 × 20 particles whose lower-left corner sits `x_left` m
/// along the grid, resting on the ground.
fn body(sf: &Bilinear<TerrainGrid>, x_left: f64) -> Vec<Stencil<4>> {
    let mut out = Vec::with_capacity(400);
    for a in 0..20 {
        for b in 0..20 {
            let x = x_left + (f64::from(a) + 0.5) * 0.05;
            let y = sf.0.ground_height(x).unwrap() + (f64::from(b) + 0.5) * 0.05;
            out.push(sf.stencil(Vector::new(x, y)).unwrap());
        }
    }
    out
}

#[test]
fn ten_km_domain_holding_a_one_square_metre_body_costs_what_the_body_costs() {
    let short = slope(20.0);
    let long = slope(10_000.0);
    assert_eq!(long.0.columns(), 101_000);
    let mut a_short = ActiveNodes::new();
    let mut a_long = ActiveNodes::new();
    // same position relative to the column boundaries, 10 m and 9 990 m down the slope.
    a_short.rebuild_from_stencils(&body(&short, 10.0));
    a_long.rebuild_from_stencils(&body(&long, 9_990.0));
    // the body covers 10 × 10 cells of 0.1 m exactly (its edges on cell edges, particles
    // inside): 11 × 11 nodes.
    assert_eq!(a_short.len(), a_long.len());
    assert_eq!(a_short.len(), 11 * 11);
    assert_eq!(a_short.block_count(), a_long.block_count());
    assert!(a_long.heap_bytes() <= 16 * 1024, "{} bytes", a_long.heap_bytes());
    // the grid itself is O(profile points): 3 points whatever the length.
    assert_eq!(short.0.heap_bytes(), long.0.heap_bytes());
    assert!(long.0.heap_bytes() < 256);
    // and locating the body does not walk the domain: the same work takes about the same time
    // (bounded loosely against timer noise: a per-column walk would be ~500× slower).
    let time = |sf: &Bilinear<TerrainGrid>, x_left: f64| {
        let t = Instant::now();
        let mut active = ActiveNodes::new();
        for _ in 0..20 {
            active.rebuild_from_stencils(&body(sf, x_left));
        }
        t.elapsed().as_secs_f64()
    };
    let (ts, tl) = (time(&short, 10.0), time(&long, 9_990.0));
    assert!(tl < 20.0 * ts + 1e-3, "10 km: {tl} s, 20 m: {ts} s");
}
