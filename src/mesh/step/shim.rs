//! The Rust side of fitup's STEP shim (`cpp/step_shim.cpp`, through the cxx bridge
//! in `src/mesh/step_ffi.rs`, feature `step`): Open CASCADE's read as plain data
//! ([`RawModel`]), or why it stopped as a [`ShimFailure`]: a cause code with its
//! fields, handed across the C++ boundary as data (never a message to parse), which
//! [`error`] makes a [`StepError`] naming the file.

use super::raw::RawModel;
#[cfg(feature = "step")]
use super::raw::{RawAssembly, RawInstance, RawPart};
use super::{Isolation, OcctFailure, StepError, StepOptions, StepStage};
#[cfg(feature = "step")]
use crate::mesh::step_ffi::ffi;
use std::path::Path;
#[cfg(feature = "step")]
use std::sync::Mutex;

/// Why the shim stopped short of a model, as it says it (the C++ side's `Failure`,
/// or a child reader's answer), before the file and the options make a [`StepError`]
/// of it ([`error`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) enum ShimFailure {
    /// `ReadFile` failed.
    Parse,
    /// `Transfer` failed.
    Transfer,
    /// The time limit passed while Open CASCADE was at this stage.
    TimeLimit(StepStage),
    /// The meshes passed the triangle cap.
    TooManyTriangles,
    /// The assembly tree is deeper than 64 levels, at this path.
    TooDeep {
        /// The assembly path.
        at: String,
    },
    /// An allocation failed.
    OutOfMemory,
    /// An exception: its class and message.
    Exception {
        /// The class (`Standard_NullObject`, `std::exception`, `write`, …).
        kind: String,
        /// Its message (may be empty).
        message: String,
    },
}

/// The shim's failure as a typed error about `path`.
pub(super) fn error(path: &Path, options: &StepOptions, failure: ShimFailure) -> StepError {
    let occt = |failure| StepError::Occt {
        path: path.into(),
        failure,
    };
    match failure {
        ShimFailure::Parse => occt(OcctFailure::Parse),
        ShimFailure::Transfer => occt(OcctFailure::Transfer),
        ShimFailure::TimeLimit(stage) => StepError::TimeLimit {
            path: path.into(),
            limit: options.time_limit,
            stage,
        },
        ShimFailure::TooManyTriangles => occt(OcctFailure::TooManyTriangles {
            cap: options.max_triangles,
        }),
        ShimFailure::TooDeep { at } => occt(OcctFailure::TooDeep { at }),
        ShimFailure::OutOfMemory => match &options.isolation {
            Isolation::Child(c) if c.memory_limit > 0 => StepError::MemoryLimit {
                path: path.into(),
                limit: c.memory_limit,
            },
            _ => occt(OcctFailure::OutOfMemory),
        },
        ShimFailure::Exception { kind, message } => occt(OcctFailure::Exception {
            kind,
            detail: message,
        }),
    }
}

/// Open CASCADE's reader settings are process-wide (`Interface_Static`): one read
/// or write at a time.
#[cfg(feature = "step")]
static OCCT: Mutex<()> = Mutex::new(());

/// The shim's read as plain data, or why it stopped.
#[cfg(feature = "step")]
pub(super) fn read(path: &str, options: &StepOptions) -> Result<RawModel, ShimFailure> {
    let opts = ffi::ReadOptions {
        linear_deflection: options.linear_deflection,
        angular_deflection: options.angular_deflection,
        time_limit_s: options.time_limit.as_secs_f64(),
        max_triangles: options.max_triangles,
    };
    let answer = {
        let _one = OCCT.lock().unwrap_or_else(|e| e.into_inner());
        ffi::read_step(path, &opts)
    };
    checked(answer.failure)?;
    let m = answer.model;
    Ok(RawModel {
        parts: m
            .parts
            .into_iter()
            .map(|p| RawPart {
                name: p.name,
                solid_index: p.solid_index,
                solids_in_product: p.solids_in_product,
                vertices: p.vertices,
                triangles: p.triangles,
                exact_volume: p.exact_volume,
                faces: p.faces,
                unmeshed_faces: p.unmeshed_faces,
                first_unmeshed_face: p.first_unmeshed_face,
            })
            .collect(),
        instances: m
            .instances
            .into_iter()
            .map(|i| RawInstance {
                name: i.name,
                path: i.path,
                part: i.part,
                matrix: i.matrix,
                scale: i.scale,
                parent: i.parent,
            })
            .collect(),
        assemblies: m
            .assemblies
            .into_iter()
            .map(|a| RawAssembly {
                name: a.name,
                path: a.path,
                product: a.product,
                parent: a.parent,
                matrix: a.matrix,
                scale: a.scale,
            })
            .collect(),
        length_unit: m.length_unit,
        read_s: m.read_s,
        transfer_s: m.transfer_s,
        mesh_s: m.mesh_s,
        shells_without_solid: m.shells_without_solid,
        faces_without_solid: m.faces_without_solid,
        open_shells: m.open_shells,
        first_open_shell: m.first_open_shell,
        peak_memory: 0,
    })
}

#[cfg(feature = "step")]
pub(super) fn write_test(kind: &str, path: &str) -> Result<(), ShimFailure> {
    let _one = OCCT.lock().unwrap_or_else(|e| e.into_inner());
    checked(ffi::write_test_step(kind, path))
}

/// The shim's verdict as a [`ShimFailure`] (`Ok` when its cause is `Done`).
#[cfg(feature = "step")]
fn checked(f: ffi::Failure) -> Result<(), ShimFailure> {
    Err(match f.cause {
        ffi::Cause::Done => return Ok(()),
        ffi::Cause::Parse => ShimFailure::Parse,
        ffi::Cause::Transfer => ShimFailure::Transfer,
        ffi::Cause::TimeLimit => ShimFailure::TimeLimit(match f.stage {
            ffi::Stage::Transferring => StepStage::Transferring,
            ffi::Stage::Meshing => StepStage::Meshing,
            _ => StepStage::Reading,
        }),
        ffi::Cause::TooManyTriangles => ShimFailure::TooManyTriangles,
        ffi::Cause::TooDeep => ShimFailure::TooDeep { at: f.at },
        ffi::Cause::OutOfMemory => ShimFailure::OutOfMemory,
        ffi::Cause::Exception => ShimFailure::Exception {
            kind: f.kind,
            message: f.message,
        },
        other => ShimFailure::Exception {
            kind: "unknown".into(),
            message: format!("the shim gave cause {}", other.repr),
        },
    })
}

/// What this build's shim says ([`read_step`](super::read_step) and
/// [`write_test_step`](super::write_test_step) answer [`StepError::NotBuilt`] before
/// they get here).
#[cfg(not(feature = "step"))]
fn not_built() -> ShimFailure {
    ShimFailure::Exception {
        kind: "NotBuilt".into(),
        message: "this build has no Open CASCADE".into(),
    }
}

#[cfg(not(feature = "step"))]
pub(super) fn read(_: &str, _: &StepOptions) -> Result<RawModel, ShimFailure> {
    Err(not_built())
}

#[cfg(not(feature = "step"))]
pub(super) fn write_test(_: &str, _: &str) -> Result<(), ShimFailure> {
    Err(not_built())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::step::{ChildReader, DEFAULT_MAX_TRIANGLES};
    #[cfg(feature = "step")]
    use std::time::Duration;

    #[test]
    fn shim_failures_become_typed_errors() {
        let p = Path::new("a.step");
        let o = StepOptions {
            isolation: Isolation::Child(ChildReader {
                program: "fitup".into(),
                memory_limit: 1 << 30,
            }),
            ..StepOptions::default()
        };
        assert!(matches!(
            error(p, &o, ShimFailure::TimeLimit(StepStage::Meshing)),
            StepError::TimeLimit {
                stage: StepStage::Meshing,
                ..
            }
        ));
        // Out of memory is the child's cap where it has one, else Open CASCADE's.
        assert!(matches!(
            error(p, &o, ShimFailure::OutOfMemory),
            StepError::MemoryLimit { limit, .. } if limit == 1 << 30
        ));
        assert!(matches!(
            error(p, &StepOptions::default(), ShimFailure::OutOfMemory),
            StepError::Occt {
                failure: OcctFailure::OutOfMemory,
                ..
            }
        ));
        let e = error(
            p,
            &o,
            ShimFailure::Exception {
                kind: "Standard_NullObject".into(),
                message: "null handle: at #12".into(),
            },
        );
        assert_eq!(
            e,
            StepError::Occt {
                path: p.into(),
                failure: OcctFailure::Exception {
                    kind: "Standard_NullObject".into(),
                    detail: "null handle: at #12".into()
                }
            }
        );
        assert_eq!(
            e.to_string(),
            "a.step: Open CASCADE failed: Standard_NullObject: null handle: at #12"
        );
        assert!(matches!(
            error(p, &o, ShimFailure::TooDeep { at: "/a/b".into() }),
            StepError::Occt { failure: OcctFailure::TooDeep { at }, .. } if at == "/a/b"
        ));
        let e = error(p, &o, ShimFailure::TooManyTriangles);
        assert!(
            matches!(
                e,
                StepError::Occt {
                    failure: OcctFailure::TooManyTriangles {
                        cap: DEFAULT_MAX_TRIANGLES
                    },
                    ..
                }
            ),
            "{e}"
        );
    }

    /// The shim's own verdicts, through the C++ boundary: each cause arrives as its
    /// variant with its fields, no text parsed.
    #[cfg(feature = "step")]
    #[test]
    fn the_shim_hands_its_causes_across_as_data() {
        let dir = tempfile::tempdir().unwrap();
        let notes = dir.path().join("notes.step");
        std::fs::write(&notes, "ISO-10303-21;\nthese are my notes\n").unwrap();
        let o = StepOptions::default();
        assert_eq!(
            read(notes.to_str().unwrap(), &o).unwrap_err(),
            ShimFailure::Parse
        );
        assert_eq!(
            write_test("torus", "x.step").unwrap_err(),
            ShimFailure::Exception {
                kind: "write".into(),
                message: "unknown test file kind torus".into()
            }
        );
        let file = dir.path().join("cell.step");
        write_test("assembly", file.to_str().unwrap()).unwrap();
        let tight = StepOptions {
            time_limit: Duration::from_nanos(1),
            ..StepOptions::default()
        };
        let stopped = read(file.to_str().unwrap(), &tight).unwrap_err();
        assert!(
            matches!(
                stopped,
                ShimFailure::TimeLimit(StepStage::Transferring | StepStage::Meshing)
            ),
            "{stopped:?}"
        );
        let few = StepOptions {
            max_triangles: 10,
            ..StepOptions::default()
        };
        assert_eq!(
            read(file.to_str().unwrap(), &few).unwrap_err(),
            ShimFailure::TooManyTriangles
        );
        let m = read(file.to_str().unwrap(), &o).unwrap();
        assert_eq!(m.instances.len(), 4);
    }
}
