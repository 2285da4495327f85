//! The committed models are exactly what the generators in `fitup::demo` produce
//! (regenerate with `FITUP_BLESS=1 cargo test --test models`), and they load.

use std::path::Path;

#[test]
fn committed_demo_cell_matches_generator() {
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    if std::env::var_os("FITUP_BLESS").is_some() {
        fitup::demo::write_cell(&models).unwrap();
    }
    let fresh = tempfile::tempdir().unwrap();
    fitup::demo::write_cell(fresh.path()).unwrap();
    for f in [
        "cell.yaml",
        "meshes/table.stl",
        "meshes/plate_a.stl",
        "meshes/plate_b.stl",
        "meshes/screw.stl",
    ] {
        let committed = std::fs::read(models.join(f)).unwrap_or_else(|e| panic!("models/{f}: {e}"));
        let generated = std::fs::read(fresh.path().join(f)).unwrap();
        assert!(
            committed == generated,
            "models/{f} differs from the generator: run FITUP_BLESS=1 cargo test --test models"
        );
    }
    let doc = fitup::document::Document::open(&models.join("cell.yaml")).unwrap();
    for i in 0..doc.components().len() {
        assert!(
            doc.mesh_of(i).inspect().is_watertight(),
            "{}",
            doc.components()[i].name
        );
    }
}
