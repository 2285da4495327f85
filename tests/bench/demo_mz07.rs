//! The benches' demo MZ07 (`fitup::demo::write_robots`) in a temporary project.

use fitup::document::Document;
use fitup::kinematics::Robot;
use fitup::math::Transform;

/// Writes the demo robots into a new temporary project (`models/`, and an empty
/// `scripts/`) and opens the MZ07: (the project folder, removed when dropped; the
/// robot; joints 10, -20, 30, 40, -50, 60 degrees in radians, off every singularity;
/// the TCP pose there).
pub fn demo_mz07() -> (tempfile::TempDir, Robot, Vec<f64>, Transform) {
    let dir = tempfile::tempdir().unwrap();
    fitup::demo::write_robots(&dir.path().join("models")).unwrap();
    std::fs::create_dir(dir.path().join("scripts")).unwrap();
    let doc = Document::open(&dir.path().join("models/mz07.yaml")).unwrap();
    let robot = doc.robot("mz07").unwrap().robot().clone();
    let q: Vec<f64> = [10.0f64, -20.0, 30.0, 40.0, -50.0, 60.0]
        .iter()
        .map(|v| v.to_radians())
        .collect();
    let target = robot.tcp_pose(&q).unwrap();
    (dir, robot, q, target)
}
