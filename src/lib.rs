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
//! | [`math`] | [`Transform`](math::Transform) (the pose matrix), angle conventions, the seeded RNG |
//! | [`mesh`] | triangle meshes, STL I/O, generated shapes, the mesh cache |
//! | [`collision`] | interference: exact (solid), whole-part boxes, cut cells, sweeps |
//! | [`db`] | the results database: SQLite by default, PostgreSQL for teams |
//! | [`kinematics`] | kinematic trees, D-H, robot catalog, FK, analytic and numeric IK, motions, programs, drilling |
//! | [`document`] | the assembly document: parts, components, mates, dimensions |
//! | [`planning`] | path planners for one component: greedy ant, RRT family, Floyd, disassembly |
//! | [`demo`] | the bundled demo cell (seed 000 fig. 11), generated in code |
//! | [`script`] | the Rhai sandbox and API bindings |
//! | [`watch`] | watch mode: rerun on every save, exactly once |
//! | [`cli`] | the `fitup` command line |
//! | [`diagnostics`] | errors located in user files, "did you mean" hints |
//! | [`fsutil`] | atomic writes, content hashes, file stamps |
pub mod cli;
pub mod collision;
pub mod db;
pub mod demo;
pub mod diagnostics;
pub mod document;
pub mod fsutil;
pub mod kinematics;
pub mod math;
pub mod mesh;
pub mod planning;
pub mod script;
pub mod watch;
