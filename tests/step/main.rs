//! The STEP tests (feature `step`: Open CASCADE linked through the C++ shim), in a
//! binary of their own so that CI's STEP stage compiles these modules and not the
//! whole `it` binary again: `cargo test --features step --test step`.
//!
//! `step_import` and `step_cache` are `it`'s files, run here whole with the feature
//! (`it` runs them without it, for the "rebuild with --features step" answers, and
//! leaves them out with it); `step_corpus` reads real CAD exports from
//! `FITUP_STEP_CORPUS` and says it skips when that is unset; `watch` is the watch test
//! of a `step:` part.

#[path = "../common/mod.rs"]
mod common;

#[path = "../it/step_cache.rs"]
mod step_cache;
mod step_corpus;
#[path = "../it/step_import.rs"]
mod step_import;
mod watch;
