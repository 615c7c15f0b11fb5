//! The 3D build of the solver (`mpm-solver3d`, the same source as `mpm-solver`) against the rigid
//! block's laws written for a vector, conservation and thread-count independence. The drivers
//! are in `mpm_tests::three_d`; `cargo xtask verify` tabulates the same cases (rows named `3D`).

use mpm_grid3d::RegularShape;
use mpm_solver3d::{Scheme, Transfer};
use mpm_tests::three_d::{
    Numerics, collapse_bits, diagonal, free_fall, rigid_path, slope, thrown, vibrating_bar,
};

/// eq 22 along a fall line oblique to the grid: the travel within 1 % of the rigid block's at
/// 1 s and 2 s (the bar; the 2D inclined case passes at 0.5 %), and across the fall
/// line under 1 % of the travel (it is zero for the rigid block).
#[test]
fn a_block_slides_down_an_oblique_fall_line_as_eq_22_says() {
    let path = slope(&Numerics::paper(0.25)).unwrap();
    for &(t, [along, across], [rigid, _]) in &path.samples {
        eprintln!("t = {t}: along {along:.5} (rigid {rigid:.5}), across {across:.2e}");
        assert!((along - rigid).abs() < 0.01 * rigid, "t = {t}: {along} against {rigid}");
        assert!(across.abs() < 0.01 * rigid, "t = {t}: drift {across} across the fall line");
    }
}

/// thrown across the slope: the path against the rigid block's ODE within 1 % at 1 s and 2 s.
#[test]
fn a_block_thrown_across_the_slope_follows_the_rigid_blocks_ode() {
    let path = thrown(&Numerics::paper(0.25)).unwrap();
    for (t, s, r) in &path.samples {
        eprintln!("t = {t}: {s:?} against {r:?}");
    }
    assert!(path.worst_relative() < 0.01, "{}", path.worst_relative());
}

/// the rigid block's ODE itself: released at rest it is eq 22, ½ g (sin θ − μ cos θ) t².
#[test]
fn the_rigid_path_released_at_rest_is_eq_22() {
    let theta = 30f64.to_radians();
    let a = mpm_solver3d::STANDARD_GRAVITY * (theta.sin() - 0.3 * theta.cos());
    for t in [0.5, 1.0, 2.0] {
        let [along, across] = rigid_path(0.0, t);
        assert!((along - 0.5 * a * t * t).abs() < 1e-9, "{along}");
        assert!(across.abs() < 1e-12);
    }
}

/// eq 21 along the grid's diagonal within 1 %, and no drift across it beyond 1 % of the travel.
#[test]
fn eq_21_holds_along_the_grid_diagonal() {
    let d = diagonal(&Numerics::paper(0.5)).unwrap();
    eprintln!("{d:?}");
    assert!((d.travel - d.expected).abs() < 0.01 * d.expected, "{d:?}");
    assert!(d.across.abs() < 0.01 * d.expected, "{d:?}");
}

/// free fall: the momentum is m g t to round-off, for every shape function and transfer.
/// Tolerance 1e-12: the sums of a few thousand terms of order one.
#[test]
fn free_fall_momentum_is_m_g_t() {
    for shape in RegularShape::ALL {
        for transfer in [Transfer::Flip, Transfer::Apic] {
            let n = Numerics { shape, transfer, scheme: Scheme::Musl, ..Numerics::paper(0.25) };
            let r = free_fall(&n).unwrap();
            assert!(r.momentum_error < 1e-12, "{}: {}", n.name(), r.momentum_error);
        }
    }
}

/// one and two threads give the same bits on a column of 11 520 particles.
#[test]
fn the_3d_collapse_is_bit_identical_on_one_and_two_threads() {
    let on = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| collapse_bits(60).unwrap())
    };
    let (count, one) = on(1);
    assert!(count >= 10_000);
    assert!(one == on(2).1);
}

/// The vibrating bar along z (trilinear MUSL, 1 m cells, C = 0.05, as the 2D test): period and
/// energy within the 1 % over five periods, and the same period as the 2D bar's to
/// 1e-9 (ν = 0: both are the same one-dimensional bar; only the sums' order differs).
#[test]
fn the_vibrating_bar_along_z_has_the_2d_bars_period() {
    let n = Numerics { scheme: Scheme::Musl, courant: 0.05, ..Numerics::paper(1.0) };
    let r = vibrating_bar(&n).unwrap();
    assert!(r.crossings >= 9, "ten zero crossings in five periods, got {}", r.crossings);
    assert!((r.period_ratio - 1.0).abs() < 0.01, "period ratio {}", r.period_ratio);
    assert!(r.worst_energy < 0.01, "energy error {}", r.worst_energy);
    let d = mpm_tests::Discretisation {
        cell: 1.0,
        ppc: 2,
        scheme: mpm_solver::Scheme::Musl,
        shape: mpm_tests::ShapeKind::Bilinear,
        courant: 0.05,
        mass: mpm_tests::MassMatrix::Lumped,
    };
    let plane = mpm_tests::vibrating_bar(&d).unwrap();
    assert!(
        (r.period_ratio - plane.period_ratio).abs() < 1e-9,
        "3D {} against 2D {}",
        r.period_ratio,
        plane.period_ratio
    );
}

/// The stencil sums factorised per axis (`interpolate`, `gradient`, `nodal_forces`) against the
/// node-by-node sums of the weights and gradients they factorise, for trilinear, uGIMP and
/// B-spline functions at points all over a cell. Tolerance: the same terms added in another
/// order, so round-off: 2e-11 on values and gradients (|∇v| up to about 30 with h = 0.08 m) and
/// 5e-10 on forces (up to about 100 N), about 1e-12 of the largest term, where a wrong or missing
/// term would be O(1).
#[test]
fn the_factorised_stencil_sums_are_the_node_by_node_sums() {
    use mpm_grid3d::{Bilinear, Gimp, QuadraticBSpline, RegularGrid, ShapeFunctions};
    use mpm_solver3d::{Matrix, Vector};

    fn check<S: ShapeFunctions<N>, const N: usize>(shape: &S, name: &str) {
        let field = |k: usize| {
            let k = k as f64;
            Vector::new((1.3 * k).sin(), (0.7 * k + 0.2).cos(), 0.1 * k - 1.0)
        };
        let stress = [
            Vector::new(-3.0, 0.4, 0.2),
            Vector::new(0.4, -5.0, -0.3),
            Vector::new(0.2, -0.3, -4.0),
        ];
        let (mass, body, volume) = (2.5, Vector::new(0.3, -9.81, 0.1), 0.8);
        for p in 0..50 {
            let t = p as f64 / 50.0;
            let x = Vector::new(
                1.0 + 0.93 * t,
                1.0 + (7.0 * t).fract() * 0.95,
                1.02 + (13.0 * t).fract() * 0.9,
            );
            let (_, f) = shape.factors(x).unwrap();
            let (w, g) = (shape.weights(&f), shape.gradients(&f));
            let (mut v, mut l) = (Vector::ZERO, Matrix::ZERO);
            for k in 0..N {
                v += w[k] * field(k);
                l += Matrix::from_cols(field(k) * g[k].x, field(k) * g[k].y, field(k) * g[k].z);
            }
            let (v2, l2) = shape.interpolate(&f, field);
            let l3 = shape.gradient(&f, field);
            let scale = 1e-12 * 20.0;
            assert!((v - v2).abs().max_element() < scale, "{name} value at {x}");
            for a in 0..3 {
                assert!(
                    (l.col(a) - l2.col(a)).abs().max_element() < scale,
                    "{name} gradient at {x}"
                );
                assert!(
                    (l.col(a) - l3.col(a)).abs().max_element() < scale,
                    "{name} gradient at {x}"
                );
            }
            let forces = shape.nodal_forces(&f, &w, (mass, body), volume, stress);
            for k in 0..N {
                let sg = stress[0] * g[k].x + stress[1] * g[k].y + stress[2] * g[k].z;
                let want = (mass * w[k]) * body - volume * sg;
                assert!(
                    (forces[k] - want).abs().max_element() < 1e-12 * 500.0,
                    "{name} force {k} at {x}"
                );
            }
        }
    }
    let grid = RegularGrid::new(Vector::ZERO, Vector::new(0.1, 0.125, 0.08), [30, 30, 30]).unwrap();
    check(&Bilinear(grid), "trilinear");
    check(&Gimp::with_particles_per_cell(grid, [2, 2, 2]).unwrap(), "uGIMP");
    check(&QuadraticBSpline::new(grid), "B-spline");
}

/// A block thrown into a wall plane oblique to every grid axis (uGIMP), frictionless and with
/// μ = 0.3: the momentum balance with the wall's impulse to round-off (no other force acts; sums
/// of about 500 terms of order one); frictionless, the impulse along the normal only (each
/// node's impulse is along n, so the sum is to round-off); with friction, the tangential
/// impulse within Coulomb's cone (each node's is, so the sum is) and against the tangential
/// approach (the nodes' trial tangential velocities are nearly that of the block: −0.9 leaves
/// room for the block's spin and strain); the block rebounds, and no particle's centre ever
/// lies behind the plane.
#[test]
fn a_block_rebounds_from_an_oblique_wall_plane_with_its_impulse() {
    use mpm_tests::three_d::oblique_wall;
    let free = oblique_wall(mpm_grid3d::RegularShape::Gimp, 0.0).unwrap();
    assert!(free.balance < 1e-12, "balance {}", free.balance);
    assert!(free.normal_impulse > 0.0);
    assert!(free.tangential_impulse < 1e-12 * free.normal_impulse, "{free:?}");
    assert!(free.normal_velocity_end > 0.0, "{free:?}");
    assert!(free.closest_edge > -1.0, "{free:?}");
    let rough = oblique_wall(mpm_grid3d::RegularShape::Gimp, 0.3).unwrap();
    assert!(rough.balance < 1e-12, "balance {}", rough.balance);
    assert!(rough.tangential_impulse > 0.0, "{rough:?}");
    assert!(rough.tangential_impulse <= 0.3 * rough.normal_impulse * (1.0 + 1e-12), "{rough:?}");
    assert!(rough.tangential_alignment < -0.9, "{rough:?}");
    assert!(rough.normal_velocity_end > 0.0, "{rough:?}");
    assert!(rough.closest_edge > -1.0, "{rough:?}");
}
