//! The embedded scenes parse, validate and build.

use mpm_cli::{SCENES, check_scene, embedded_scene, load_scene_str};

#[test]
fn every_embedded_scene_is_valid_and_builds() {
    for (name, text) in SCENES {
        let scene = load_scene_str(text, name).unwrap_or_else(|e| panic!("{name}: {e}"));
        let r = check_scene(&scene).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(r.particles > 0 && r.active_nodes > 0 && r.initial_dt > 0.0, "{name}: {r:?}");
    }
}

#[test]
fn flume_has_the_papers_table_2() {
    let scene = load_scene_str(embedded_scene("flume").unwrap(), "flume").unwrap();
    let f = scene.file();
    let sand = &f.materials["sand"];
    assert_eq!(sand.kind(), Some("drucker_prager"));
    let n = |field: &str| sand.number(field);
    assert_eq!((n("young"), n("poisson"), n("density")), (Some(2.0e6), Some(0.3), Some(1600.0)));
    assert_eq!(n("cohesion"), Some(10.0));
    assert_eq!(n("friction_angle_deg"), Some(40.0));
    assert_eq!(n("dilatancy_angle_deg"), Some(0.0));
    assert_eq!(n("hardening_modulus"), Some(0.0));
    assert_eq!(n("mixing"), Some(0.8));
    assert_eq!(f.grid.cell_width, Some(0.1));
    assert_eq!(f.grid.row_height, Some(0.1));
    // slope 30°
    let p = f.grid.profile.as_ref().and_then(|p| p.points()).unwrap();
    let slope = ((p[0][1] - p[1][1]) / (p[1][0] - p[0][0])).atan().to_degrees();
    assert!((slope - 30.0).abs() < 1e-9);
    assert_eq!(f.boundaries.ground, Some(mpm_cli::scene::BoundarySpec::FrictionAngleDeg(27.0)));
    // 24 × 14, the lattice closest to the paper's 334 particles
    assert_eq!(scene.particle_count(), 336);
    assert_eq!(scene.solver_config().scheme, mpm_cli::scene::Scheme::Usavg);
    assert!(scene.solver_config().objective_stress);
}

#[test]
fn an_unknown_scene_name_has_no_text() {
    assert!(embedded_scene("nonexistent").is_none());
    assert!(embedded_scene(mpm_cli::DEFAULT_SCENE).is_some());
}
