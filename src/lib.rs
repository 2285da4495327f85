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
//! | [`kinematics`] | kinematic trees, D-H, robot catalog, FK, analytic and numeric IK, motions, programs, drilling |
pub mod kinematics;
pub mod math;
