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
//! | [`collision`] | interference of posed meshes: exact (solid), whole-part boxes, cut cells, sweeps, planner edges |
//! | [`db`] | the results database: SQLite by default, PostgreSQL for teams |
//! | [`kinematics`] | kinematic trees, D-H, robot catalog, FK, analytic and numeric IK, motions, programs, drilling |
//! | [`document`] | the assembly document: parts, components, mates, dimensions |
//! | [`planning`] | path planners for one component: greedy ant, RRT family, Floyd, disassembly, insertion |
//! | [`sequence`] | assembly sequences: tasks (base part, assembly part, operation) for a robot |
//! | [`skills`] | skill primitives, part states, task templates and the skill manager that runs them on a manipulator (feature `skills`) |
//! | [`manipulator`] | the manipulator over TCP: ROS-Industrial simple_message, a streaming client, a simulated controller (feature `manipulator`) |
//! | [`workspace`] | a document as a collision scene and every document-level request: interference, contact, clearance, sweeps, planning, revalidation, following |
//! | [`demo`] | the bundled demo cell (seed 000 fig. 11), generated in code |
//! | [`options`] | one vocabulary per request: the option keys of Rhai maps and Python keywords, their kinds, units, defaults and reference tables |
//! | [`script`] | the Rhai sandbox and API bindings |
//! | [`viewer`] | the live 3D viewer (Rerun): documents, robots, paths, interference; `.rrd` recordings |
//! | [`watch`] | watch mode: rerun on every save, exactly once |
//! | [`cli`] | the `fitup` command line |
//! | [`diagnostics`] | errors located in user files, "did you mean" hints |
//! | [`project`] | the project folder that bounds every file a run touches, the path rule, the write rule and the output registry |
//! | [`fsutil`] | atomic writes, capped reads of regular files only, content hashes, file stamps, the held folder |
//! | [`files`] | data files a script reads inside the project: CSV tables, JSON, text |
#![warn(missing_docs)]

#[cfg(feature = "cli")]
pub mod cli;
pub mod collision;
#[cfg(feature = "db")]
pub mod db;
pub mod demo;
pub mod diagnostics;
pub mod document;
pub mod files;
pub mod fsutil;
pub mod kinematics;
#[cfg(feature = "manipulator")]
pub mod manipulator;
pub mod math;
pub mod mesh;
pub mod options;
pub mod planning;
pub mod project;
#[cfg(feature = "script")]
pub mod script;
pub mod sequence;
#[cfg(feature = "skills")]
pub mod skills;
pub mod viewer;
#[cfg(feature = "watch")]
pub mod watch;
pub mod workspace;

#[cfg(test)]
pub(crate) mod test_support;
