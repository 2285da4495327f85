// The C++ side of fitup's STEP reader (feature `step`): Open CASCADE (Debian's 7.6)
// reads a STEP file through XCAF, meshes every distinct solid once and hands the
// triangles, the exact B-rep volumes and the placed instances to Rust
// (src/mesh/step_ffi.rs declares these functions; src/mesh/step.rs is the API).
#pragma once
#include "rust/cxx.h"

namespace fitup_step {
struct ReadOptions;
struct Answer;
struct Failure;

// Reads, transfers and meshes the STEP file at `path`; lengths in mm. Never throws:
// any Open CASCADE failure, the time limit or the triangle cap is the answer's
// `failure`, a cause code with its fields (src/mesh/step.rs makes a typed error of it).
Answer read_step(rust::Str path, const ReadOptions &options);

// Writes one of the STEP files the tests use (`kind`: box, cylinder_hole,
// assembly, nested, inch_box, open_shell, no_solid, bad_face, plate_holes), made with Open
// CASCADE itself. Never throws: the failure's cause is `Done` when it wrote the file.
Failure write_test_step(rust::Str kind, rust::Str path);
} // namespace fitup_step
