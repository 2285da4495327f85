//! fitup's whole-workflow tests, in one binary (as ripgrep does): the crate and its
//! dependencies are linked once, not once per file. Each module is one area; most drive
//! the real `fitup` binary from the repository root or a scratch project, exactly as a
//! user runs it. Helpers shared with the benchmarks live in `tests/common/`.
//!
//! The STEP tests (`--features step`) are a small binary of their own, `tests/step/`:
//! CI's STEP stage compiles that, not this whole binary again with the feature.

#[path = "../common/mod.rs"]
mod common;

mod api_docs;
mod chain;
mod cli;
mod coordinate_systems;
mod db;
mod equations;
mod hostile_bounds;
mod hostile_db;
mod hostile_files;
mod hostile_memory;
mod hostile_meshes;
mod hostile_names;
#[cfg(unix)]
mod hostile_races;
mod hostile_round3;
mod hostile_round4;
mod hostile_runs;
mod hostile_skills;
mod hostile_writers;
mod layers;
mod manipulator;
mod mass_properties;
mod mesh_formats;
mod models;
mod option_keys;
mod planning_problems;
mod planning_puzzles;
mod precision_manipulator;
mod robots;
mod scripts;
mod sequence;
mod sequence_cell_robots;
mod sequence_fits;
mod sequence_real;
mod sequence_sliced_walls;
mod sequence_watch;
mod simple_message_peer;
mod skills;
mod solidworks;
// The default build's half of the STEP tests (the "rebuild with --features step"
// answers, the store's pruning); with the feature, these files run in the `step`
// binary (tests/step/main.rs), whole.
#[cfg(not(feature = "step"))]
mod step_cache;
#[cfg(not(feature = "step"))]
mod step_import;
mod sub_assemblies;
mod sub_document_robots;
mod sub_documents;
mod ur_ik;
mod ur_real;
mod urdf;
mod viewer;
mod viewer_browser;
mod watch;
