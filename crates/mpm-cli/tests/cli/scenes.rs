//! The embedded scenes parse, validate and build.

use mpm_run::{SCENES, check_scene, embedded_scene, load_scene_str};

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
    assert_eq!(f.boundaries.ground, Some(mpm_run::scene::BoundarySpec::FrictionAngleDeg(27.0)));
    // 24 × 14, the lattice closest to the paper's 334 particles
    assert_eq!(scene.particle_count(), 336);
    assert_eq!(scene.solver_config().scheme, mpm_run::scene::Scheme::Usavg);
    assert!(scene.solver_config().objective_stress);
}

#[test]
fn an_unknown_scene_name_has_no_text() {
    assert!(embedded_scene("nonexistent").is_none());
    assert!(embedded_scene(mpm_run::DEFAULT_SCENE).is_some());
}

/// The valley example's terrain and release mass come from its DEM and rupture CSV; the GeoTIFF
/// of the same raster gives the same scene particle for particle.
#[test]
fn the_valley_example_reads_the_same_from_its_ascii_grid_and_its_geotiff() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../docs/examples/valley_landslide.toml");
    let asc = mpm_run::load_scene_file(&path).unwrap();
    let text =
        std::fs::read_to_string(&path).unwrap().replace("valley_side.asc", "valley_side.tif");
    let dir = path.parent().unwrap();
    let tif = mpm_scene::load_scene_str_in(&text, "valley (GeoTIFF)", dir).unwrap();
    // ∫ 12 sin²(π s/100) ds over 100 m = 600 m², at 1.25² m² a particle: 384; a column keeps
    // its top particle when at least half of it lies below the ground, which drops one at a thin
    // end of the slide (the lattice is deterministic: the count is exact)
    assert_eq!(asc.particle_count(), 383);
    let (a, b) = (&asc.resolved().seeds, &tif.resolved().seeds);
    assert_eq!(a.len(), b.len());
    // the same f64 heights in both files: the same positions, bit for bit
    assert!(a.iter().zip(b).all(|(p, q)| p.position == q.position));
    assert_eq!(asc.resolved().ground, tif.resolved().ground);
}

/// A bad observed deposit is refused naming its file and what to fix; a surface is turned into
/// the thickness above the ground.
#[test]
fn an_observed_deposit_is_read_checked_and_explained() {
    let dir = crate::temp_dir("observed_files");
    std::fs::create_dir_all(&dir).unwrap();
    let text = format!(
        "{}\nobserved = {{ deposit = \"o.csv\" }}\n",
        mpm_run::embedded_scene("sliding_horizontal").unwrap()
    );
    let load = |csv: &str| {
        std::fs::write(dir.join("o.csv"), csv).unwrap();
        mpm_scene::load_scene_str_in(&text, "observed.toml", &dir).map_err(|e| e.to_string())
    };
    for (csv, expect) in [
        ("1,0\n2,0.5\n", "no header line"),
        ("x,y\n1,0\n2,0.5\n", "names one of `thickness`"),
        ("station,thickness\n1,0\n2,0.5\n", "`x,thickness` or `x,surface`"),
        // negative thickness (a depletion zone) counts as none
        ("x,thickness\n1,0\n2,-0.5\n", "no deposit"),
        ("x,thickness\n1,0\n1,0.5\n", "x does not increase at x = 1 then 1"),
        ("x,thickness\n1,0\n2,0\n", "no deposit"),
        ("x,thickness\n1,0\n2,abc\n", "line 3: column 2 is not a finite number"),
        // the floor is at y = 0: a surface below it is no deposit
        ("x,surface\n1,-0.2\n2,-0.1\n", "no deposit"),
    ] {
        let err = load(csv).unwrap_err();
        assert!(err.contains("o.csv") && err.contains(expect), "{csv:?}: {err}");
        assert!(err.contains("output.observed.deposit"), "{err}");
    }
    let s = load("x,surface\n1,-0.2\n2,0.3\n3,0.0\n").unwrap();
    let o = s.resolved().output.observed.as_ref().unwrap();
    assert_eq!(o.points, vec![[1.0, 0.0], [2.0, 0.3], [3.0, 0.0]]);
    std::fs::remove_file(dir.join("o.csv")).unwrap();
    let err = mpm_scene::load_scene_str_in(&text, "observed.toml", &dir).unwrap_err().to_string();
    assert!(err.contains("o.csv") && err.contains("cannot read"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `[solver] mass`: the consistent matrix is accepted with FLIP and refused, at its line, with
/// APIC (unstable, `stages/mass.rs`).
#[test]
fn the_consistent_mass_matrix_is_accepted_with_flip_and_refused_with_apic() {
    let base = embedded_scene("free_fall").unwrap();
    assert!(base.contains("[solver]\n"), "the scene has a [solver] table");
    let with = |extra: &str| base.replace("[solver]\n", &format!("[solver]\n{extra}"));
    let scene = load_scene_str(&with("mass = \"consistent\"\n"), "consistent.toml").unwrap();
    assert_eq!(scene.solver_config().mass, mpm_solver::MassMatrix::Consistent);
    let text = with("mass = \"consistent\"\ntransfer = \"apic\"\n");
    let err = load_scene_str(&text, "apic.toml").unwrap_err().to_string();
    assert!(err.contains("apic.toml:") && err.contains("solver.mass"), "{err}");
    assert!(err.contains("use FLIP") && err.contains("`transfer`"), "the fix is named: {err}");
}

/// A rupture surface written as spreadsheets and GIS write it in much of Europe (`x;y`,
/// decimal commas: `150;157,86`) gives the valley example's scene particle for particle (it was
/// read as (150, 157): 417 particles instead of 383); a decimal comma in a comma-separated file
/// is refused at its line, never read as another number.
#[test]
fn a_csv_with_decimal_commas_is_understood_or_refused_never_misread() {
    let examples = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/examples");
    let scene_path = examples.join("valley_landslide.toml");
    let original = mpm_run::load_scene_file(&scene_path).unwrap();
    let dir = crate::temp_dir("european-csv");
    std::fs::create_dir_all(dir.join("valley")).unwrap();
    std::fs::copy(examples.join("valley/valley_side.asc"), dir.join("valley/valley_side.asc"))
        .unwrap();
    let csv = std::fs::read_to_string(examples.join("valley/rupture.csv")).unwrap();
    let european: String =
        csv.lines()
            .map(|l| {
                if l.starts_with('#') {
                    l.to_string()
                } else {
                    l.replace(',', ";").replace('.', ",")
                }
            })
            .collect::<Vec<_>>()
            .join("\n");
    assert!(european.contains("150;157,86"), "{}", &european[..120]);
    std::fs::write(dir.join("valley/rupture.csv"), &european).unwrap();
    let text = std::fs::read_to_string(&scene_path).unwrap();
    let scene = mpm_scene::load_scene_str_in(&text, "valley (European CSV)", &dir).unwrap();
    assert_eq!(scene.particle_count(), 383);
    let (a, b) = (&original.resolved().seeds, &scene.resolved().seeds);
    assert!(a.iter().zip(b).all(|(p, q)| p.position == q.position));
    // tab-separated with an empty last column (a note): the same scene
    let tabs: String =
        csv.lines()
            .map(|l| {
                if l.starts_with('#') {
                    l.to_string()
                } else {
                    format!("{}\t", l.replace(',', "\t"))
                }
            })
            .collect::<Vec<_>>()
            .join("\n");
    std::fs::write(dir.join("valley/rupture.csv"), &tabs).unwrap();
    let scene = mpm_scene::load_scene_str_in(&text, "valley (TSV)", &dir).unwrap();
    assert_eq!(scene.particle_count(), 383);
    // one decimal comma in a comma-separated file: its line, not a silent (150, 157)
    let broken = csv.replacen("155,155.05292443915386", "155,155,05292443915386", 1);
    std::fs::write(dir.join("valley/rupture.csv"), &broken).unwrap();
    let e = mpm_scene::load_scene_str_in(&text, "valley (broken CSV)", &dir).unwrap_err();
    let line = 1 + broken.lines().position(|l| l.starts_with("155,")).unwrap();
    assert!(e.to_string().contains(&format!("line {line}: 3 fields")), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}
