//! test scenes
