//! The committed models are exactly what the generators in `fitup::demo` produce
//! (regenerate with `FITUP_BLESS=1 cargo test --test it models`), and they load.

use crate::common;

#[test]
fn committed_demo_cell_matches_generator() {
    common::assert_models_generated(
        fitup::demo::write_cell,
        &[
            "cell.yaml",
            "meshes/table.stl",
            "meshes/plate_a.stl",
            "meshes/plate_b.stl",
            "meshes/screw.stl",
        ],
        "models::committed_demo_cell",
    );
    let models = common::repo().join("models");
    let doc = fitup::document::Document::open(&models.join("cell.yaml")).unwrap();
    for i in 0..doc.components().len() {
        assert!(
            doc.mesh_of(i).inspect().is_watertight(),
            "{}",
            doc.components()[i].name
        );
    }
}

/// The robot models (`mz07.yaml`, `cell_robots.yaml` and the link meshes) are what
/// `fitup::demo::write_robots` produces, load, and their link components sit where the
/// robot's forward kinematics puts the links.
#[test]
fn committed_robot_models_match_generator() {
    let mut files = vec![
        "mz07.yaml".to_string(),
        "cell_robots.yaml".to_string(),
        "meshes/pedestal.stl".to_string(),
    ];
    for (name, _) in fitup::demo::mz07_link_meshes() {
        files.push(format!("meshes/{name}.stl"));
    }
    let files: Vec<&str> = files.iter().map(String::as_str).collect();
    common::assert_models_generated(
        fitup::demo::write_robots,
        &files,
        "models::committed_robot_models",
    );
    let models = common::repo().join("models");
    for doc in ["mz07.yaml", "cell_robots.yaml"] {
        let doc = fitup::document::Document::open(&models.join(doc)).unwrap();
        for i in 0..doc.components().len() {
            assert!(
                doc.mesh_of(i).inspect().is_watertight(),
                "{}",
                doc.components()[i].name
            );
        }
    }
    let cell = fitup::document::Document::open(&models.join("cell_robots.yaml")).unwrap();
    assert_eq!(cell.robots().len(), 2);
    // Robot B faces robot A across the table: its tool point at zero is mirrored.
    let a = cell.robot("mz07_a").unwrap().tcp().translation();
    let b = cell.robot("mz07_b").unwrap().tcp().translation();
    assert!((a.x - 600.0).abs() < 1e-9 && (b.x - 600.0).abs() < 1e-9);
    assert!((a.y - (-350.0 + 390.0)).abs() < 1e-9);
    assert!((b.y - (1150.0 - 390.0)).abs() < 1e-9);
    assert!((a.z - (fitup::demo::PEDESTAL_HEIGHT + 198.1)).abs() < 1e-9);
}

/// The URDF example's link meshes (`models/urdf/meshes/*.stl`, metres) are what
/// `fitup::demo::write_arm6_meshes` produces, and the cell document holding the URDF
/// robot loads with one component per meshed link.
#[test]
fn committed_urdf_meshes_match_generator() {
    let models = common::repo().join("models");
    if std::env::var_os("FITUP_BLESS").is_some() {
        fitup::demo::write_arm6_meshes(&models).unwrap();
    }
    let fresh = tempfile::tempdir().unwrap();
    fitup::demo::write_arm6_meshes(fresh.path()).unwrap();
    let files = fitup::demo::arm6_link_meshes()
        .into_iter()
        .map(|(name, _)| format!("urdf/meshes/{name}.stl"))
        .chain(["urdf/obstacle.stl".to_string()]);
    for f in files {
        let committed =
            std::fs::read(models.join(&f)).unwrap_or_else(|e| panic!("models/{f}: {e}"));
        let generated = std::fs::read(fresh.path().join(&f)).unwrap();
        assert!(
            committed == generated,
            "models/{f} differs from the generator: run FITUP_BLESS=1 cargo test --test models"
        );
    }
    let doc = fitup::document::Document::open(&models.join("urdf/arm6_cell.yaml")).unwrap();
    let arm = doc.robot("arm6").unwrap();
    let shown = arm.links().iter().filter(|l| l.component.is_some()).count();
    assert_eq!(shown, fitup::demo::arm6_link_meshes().len());
}
