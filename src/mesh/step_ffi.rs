//! The cxx bridge to fitup's STEP shim (`cpp/step_shim.cpp`, feature `step`): plain
//! data only, failures included (a cause code and its fields, never text to parse);
//! [`super::step`] checks and converts it.

#[cxx::bridge(namespace = "fitup_step")]
pub(crate) mod ffi {
    /// How to read and mesh (lengths in mm, angles in radians).
    struct ReadOptions {
        /// BRepMesh's linear deflection, mm.
        linear_deflection: f64,
        /// BRepMesh's angular deflection, radians.
        angular_deflection: f64,
        /// The whole read's time limit (transfer and meshing poll it), s.
        time_limit_s: f64,
        /// The most triangles of all solids together.
        max_triangles: u64,
    }

    /// One distinct solid, meshed once in its own frame.
    struct SolidPart {
        /// The product's name (empty when the file gives none).
        name: String,
        /// Which solid of the product (1-based) and how many it has.
        solid_index: u32,
        solids_in_product: u32,
        /// xyz of each vertex, mm (face meshes side by side, not welded).
        vertices: Vec<f64>,
        /// Vertex indices, three per triangle, counter-clockwise seen from outside.
        triangles: Vec<u32>,
        /// BRepGProp's volume of the B-rep, mm³.
        exact_volume: f64,
        /// Faces of the solid, faces without triangles, and the first of them (1-based).
        faces: u32,
        unmeshed_faces: u32,
        first_unmeshed_face: u32,
    }

    /// One placed solid.
    struct Instance {
        /// The assembly component's name (NAUO), else the product's.
        name: String,
        /// Names from the root, `/`-separated.
        path: String,
        /// Index into `Model::parts`.
        part: u32,
        /// Rotation and translation (mm), row-major 3 × 4, column-vector convention.
        matrix: Vec<f64>,
        /// The placement's scale factor (1 for a rigid placement; negative: mirrored).
        scale: f64,
        /// The assembly occurrence holding it: 1-based index into `Model::assemblies`,
        /// 0 when it is a free shape (no assembly above it).
        parent: u32,
    }

    /// One placed assembly (a root, or a sub-assembly occurrence), listed before
    /// everything it holds.
    struct Assembly {
        /// The occurrence's name (NAUO), else the product's.
        name: String,
        /// Names from the root, `/`-separated.
        path: String,
        /// The assembly product's name.
        product: String,
        /// The assembly holding it, as [`Instance::parent`].
        parent: u32,
        /// Its placement: assembly frame → root, row-major 3 × 4, mm.
        matrix: Vec<f64>,
        /// The placement's scale factor.
        scale: f64,
    }

    /// What the shim read.
    struct Model {
        parts: Vec<SolidPart>,
        instances: Vec<Instance>,
        /// Placed assemblies, in the tree's order (each before what it holds).
        assemblies: Vec<Assembly>,
        /// The file's length unit as its header names it (`MM`, `INCH`, …).
        length_unit: String,
        /// Parsing (ReadFile), transfer and meshing times, s.
        read_s: f64,
        transfer_s: f64,
        mesh_s: f64,
        /// Shells outside any solid, faces outside any shell (surface models).
        shells_without_solid: u32,
        faces_without_solid: u32,
        /// Shells outside any solid that are not closed, and where the first is.
        open_shells: u32,
        first_open_shell: String,
    }

    /// Why the shim stopped short of its answer (src/mesh/step.rs makes a `StepError`
    /// of it with the file and the options).
    enum Cause {
        /// It did not: the answer is whole.
        Done,
        /// `ReadFile` failed.
        Parse,
        /// `Transfer` failed.
        Transfer,
        /// The time limit passed (where: `Failure::stage`).
        TimeLimit,
        /// The meshes passed `ReadOptions::max_triangles`.
        TooManyTriangles,
        /// The assembly tree is deeper than 64 levels (where: `Failure::at`).
        TooDeep,
        /// An allocation failed.
        OutOfMemory,
        /// An exception (`Failure::kind`, `Failure::message`).
        Exception,
    }

    /// What Open CASCADE was doing when the time limit passed.
    enum Stage {
        Reading,
        Transferring,
        Meshing,
    }

    /// The shim's verdict on a call: a cause and what goes with it.
    struct Failure {
        cause: Cause,
        /// With `Cause::TimeLimit`.
        stage: Stage,
        /// With `Cause::TooDeep`: the assembly path where it stopped.
        at: String,
        /// With `Cause::Exception`: the exception's class (`Standard_NullObject`,
        /// `std::exception`, …; `write` for the test writer's own refusals).
        kind: String,
        /// With `Cause::Exception`: its message (may be empty).
        message: String,
    }

    /// A read's answer: the model, whole only when `failure.cause` is `Done`.
    struct Answer {
        model: Model,
        failure: Failure,
    }

    unsafe extern "C++" {
        include!("fitup/cpp/step_shim.h");

        /// Reads and meshes the STEP file at `path`; never throws.
        fn read_step(path: &str, options: &ReadOptions) -> Answer;

        /// Writes a STEP file the tests use, made with Open CASCADE; never throws.
        fn write_test_step(kind: &str, path: &str) -> Failure;
    }
}
