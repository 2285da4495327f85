//! # fitup
//!
//! A scripting engine for robotic assembly that does what SolidWorks-API macros did,
//! without SolidWorks: an assembly document (YAML + STL meshes) driven by Rhai scripts.
//!
//! Units everywhere inside: **millimetres and radians**. Degrees appear only in
//! user-facing pose triples (`X Y Z A B C`) and joint arrays of the scripting API;
//! `system_value` of a dimension alone mirrors SolidWorks' SI units (metres, radians).
//!
//! | module | what lives there |
//! |---|---|
//! | [`math`] | [`Transform`](math::Transform) (the pose matrix), angle conventions |
//! | [`mesh`] | triangle meshes, STL I/O, the mesh cache |
//! | [`fsutil`] | atomic writes, content hashes |
//! | [`collision`] | interference: exact, whole-part boxes, cut cells, sweeps |
pub mod collision;
pub mod fsutil;
pub mod math;
pub mod mesh;
