//! Helpers shared by the integration tests: a scratch project with the demo cell,
//! and the `fitup` binary.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The built `fitup` binary.
pub fn fitup() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fitup"))
}

/// A temporary project folder (`fitup demo`): `fitup.toml`, `models/cell.yaml` and its
/// meshes.
pub fn project() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    fitup::demo::write_project(dir.path()).unwrap();
    std::fs::create_dir(dir.path().join("scripts")).unwrap();
    dir
}

/// Runs `fitup ARGS` in `dir`.
pub fn run_in(dir: &Path, args: &[&str]) -> Output {
    fitup().current_dir(dir).args(args).output().unwrap()
}

/// The repository root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Stdout and stderr as text.
pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}
