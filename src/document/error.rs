//! Why a document operation failed.

use super::equations::EquationError;
use super::mates::SolveError;
use super::robot;
use crate::diagnostics::{Name, SourceError};
use std::path::PathBuf;

/// Why a document operation failed. Load errors carry file, line and column.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DocumentError {
    /// An error in a file the user wrote (YAML, STL, …), located.
    #[error("{0}")]
    Source(#[from] SourceError),
    /// A name that does not exist; the message lists close matches.
    #[error("no {what} named `{name}`: {hint}")]
    NotFound {
        /// "component", "dimension", …
        what: &'static str,
        /// The name asked for.
        name: String,
        /// Close matches or what exists.
        hint: String,
    },
    /// An entry that is not valid (a full name, a mate's entities, a robot's joints).
    /// Boxed: the entry's kinds are large, and every `Result` carrying a
    /// `DocumentError` (the sequence and workspace layers') would grow with them.
    #[error(transparent)]
    Entry(Box<super::EntryError>),
    /// A new name another item already has (`what`: "mate", "component", "part",
    /// "component or sub-assembly", …; a sub-document's names with their prefix).
    #[error("a {what} named `{name}` exists already")]
    NameTaken {
        /// What is named.
        what: &'static str,
        /// The name.
        name: String,
    },
    /// A name that may not be empty (`what`: "part", "custom property").
    #[error("a {what} needs a name")]
    EmptyName {
        /// What is named.
        what: &'static str,
    },
    /// A custom property's value with a control character (tab and newline are
    /// allowed).
    #[error("custom property `{key}`: the value holds a control character")]
    PropertyControl {
        /// The property's name.
        key: Name,
    },
    /// A mate that joins points or coordinate systems has no alignment to set or flip.
    #[error("mate `{mate}` joins points or coordinate systems: it has no alignment to {change}")]
    NoAlignment {
        /// The mate.
        mate: Name,
        /// "set" or "flip".
        change: &'static str,
    },
    /// A mate's dimension that an equation uses: the mate (or, when `component` is
    /// given, the component the mate goes with) cannot be deleted before the equation.
    /// Boxed: it names five things, and every `Result` carrying a `DocumentError`
    /// would grow with it.
    #[error(transparent)]
    DimensionInUse(Box<DimensionInUse>),
    /// A URDF robot link's component: the robot names it and gives its mesh.
    #[error("component `{component}` is a URDF robot link's{}", match edit {
        LinkEdit::Rename => ", named by the robot",
        LinkEdit::ReplacePart => "; its mesh comes from the URDF",
    })]
    UrdfLink {
        /// The component.
        component: Name,
        /// What was asked of it.
        edit: LinkEdit,
    },
    /// A robot's link is removed with its robot, not on its own.
    #[error("component `{component}` is a link of robot `{robot}`: it goes with the robot")]
    RobotLinkRemoval {
        /// The component asked to be removed.
        component: Name,
        /// The robot it is a link of.
        robot: Name,
    },
    /// A component with mates, removed without its mates ([`super::RemoveMates::Refuse`]).
    #[error(
        "component `{component}` has mates {}: delete them first, or remove it with its mates",
        quoted(mates)
    )]
    HasMates {
        /// The component.
        component: Name,
        /// Its mates' names.
        mates: Vec<String>,
    },
    /// A new mate's `about`, value or name that does not fit its type.
    #[error("mate `{mate}`: {problem}")]
    BadMate {
        /// The mate.
        mate: Name,
        /// What is wrong.
        problem: MateProblem,
    },
    /// A mate whose entities are unknown or do not fit its type.
    #[error("mate `{mate}`: {source}")]
    MateEntity {
        /// The mate.
        mate: Name,
        /// Which entity and why (boxed: the entry's kinds are large).
        source: Box<super::EntryError>,
    },
    /// A mate uses a reference the component's new part does not have.
    /// Boxed as [`DocumentError::DimensionInUse`] is.
    #[error(transparent)]
    MissingReference(Box<MissingReference>),
    /// A reference geometry that cannot be set.
    #[error("reference `{reference}` of part `{part}`: {problem}")]
    BadReference {
        /// The part.
        part: Name,
        /// The reference's name.
        reference: Name,
        /// What is wrong.
        problem: ReferenceProblem,
    },
    /// A new part's mesh file cannot be found or read.
    #[error("part `{part}`: {source}")]
    PartMesh {
        /// The part.
        part: Name,
        /// Why.
        source: PartMeshError,
    },
    /// A URDF robot cannot be added: its file, its meshes or its links' names.
    #[error("robot `{robot}`: {source}")]
    Urdf {
        /// The robot.
        robot: Name,
        /// Why (boxed: the mesh problems are large).
        source: Box<UrdfRobotError>,
    },
    /// A robot definition the robot builder refused (its sources, joints or links),
    /// in the builder's words (the same text locates a load's error at its line).
    #[error("robot `{robot}`: {reason}")]
    RobotDefinition {
        /// The robot.
        robot: String,
        /// The builder's reason.
        reason: String,
    },
    /// A dimension that drives a robot joint, refused by the robot.
    #[error("{dimension}: {source}")]
    JointDimension {
        /// The dimension's full name.
        dimension: String,
        /// The robot's refusal.
        source: Box<DocumentError>,
    },
    /// The GLB export could not be built.
    #[error("GLB export: {0}")]
    GlbExport(#[source] crate::mesh::MeshError),
    /// A sub-assembly with no file of its own, asked for its sub-document.
    #[error("`{0}` is no sub-document")]
    NotASubDocument(String),
    /// A sub-assembly's parent (the name before its last `/`) that is no sub-assembly.
    #[error("`{name}`: its parent `{parent}` is no sub-assembly ({hint})")]
    NoParentAssembly {
        /// The name given.
        name: String,
        /// Its parent's name.
        parent: String,
        /// Close matches or what exists.
        hint: String,
    },
    /// A sub-document's mate or equation reaching outside the sub-document.
    /// Boxed as [`DocumentError::DimensionInUse`] is.
    #[error(transparent)]
    OutsideSubDocument(Box<OutsideSubDocument>),
    /// A robot added through the API under a name inside a sub-assembly that is
    /// another document (its robots are that file's).
    #[error("robot `{robot}`: names inside `{at}/` are the sub-document's own robots; name it otherwise")]
    RobotInSubDocument {
        /// The name given.
        robot: String,
        /// The sub-assembly holding another document.
        at: String,
    },
    /// A mate type that does not exist.
    #[error("unknown mate type `{0}` (coincident, concentric, parallel, perpendicular, distance, angle)")]
    UnknownMateKind(String),
    /// A sub-assembly that does not exist (while its sub-document is read in).
    #[error("no sub-assembly `{0}`")]
    NoSubAssembly(String),
    /// The mates cannot all be satisfied: the worst mate and its residual. A load's
    /// error is located at that mate's entry (`at`, whose message is the cause's).
    #[error("{}", mates_message(.at.as_deref(), .source))]
    Mates {
        /// Where the failing mate is written, when it comes from a file.
        at: Option<Box<SourceError>>,
        /// The solver's verdict.
        #[source]
        source: SolveError,
    },
    /// An equation cannot be evaluated (syntax, unknown name, circle, division by
    /// zero, a value that is not finite or that its dimension refuses): which
    /// equation and why. A load's error is located at the equation's line (`at`).
    #[error("{}", equation_message(.at.as_deref(), .source))]
    Equation {
        /// Where the equation is written, when it comes from a file.
        at: Option<Box<SourceError>>,
        /// Which equation and why.
        #[source]
        source: EquationError,
    },
    /// A dimension an equation drives cannot be set by hand (SolidWorks refuses too):
    /// change the equation or the global variables it uses.
    #[error("dimension `{dimension}`{} is driven by equation [{index}] {equation}: change the equation (`set_equation`) or the global variables it uses", joint.as_ref().map_or(String::new(), |j| format!(" ({j})")))]
    DrivenByEquation {
        /// The dimension's full name.
        dimension: String,
        /// Which robot joint it is (`joint 2 of robot \`arm\``), when it is one.
        joint: Option<String>,
        /// The equation's index (`equation(i)`).
        index: usize,
        /// The equation's text (shortened when long).
        equation: String,
    },
    /// A suppressed component whose part is not loaded ([`super::Part::is_loaded`]):
    /// its mesh is not known, so it has no world mesh, mass, box or export.
    #[error(
        "component `{component}` is suppressed and its part `{part}` is not loaded: unsuppress it (`suppressed = false`) to read its mesh"
    )]
    NotLoaded {
        /// The component.
        component: Name,
        /// Its part.
        part: Name,
    },
    /// A part that only suppressed components used, so it was not read when the
    /// document opened, cannot be read now that component `component` needs it
    /// (unsuppressed, added or re-pointed to it); nothing changed. `at` is the
    /// error opening the document would have given: the document file, the line
    /// of the part's `stl:` or `step:`, and the cause.
    #[error("component `{component}` needs part `{part}`, whose file cannot be read (nothing changed): {at}")]
    PartUnreadable {
        /// The component that needs it.
        component: Name,
        /// The part.
        part: Name,
        /// Where and why (boxed: a located error is large).
        at: Box<SourceError>,
    },
    /// A suppressed component is not checked, planned, measured or exported.
    #[error(
        "component `{0}` is suppressed; unsuppress it (`suppressed = false`) to check, plan or export it"
    )]
    Suppressed(Name),
    /// A reference asked for as a coordinate system is another kind.
    #[error("reference `{reference}` of part `{part}` is a {kind}, not a coordinate system")]
    NotACoordinateSystem {
        /// The part.
        part: Name,
        /// The reference's name.
        reference: Name,
        /// What it is (`plane`, `axis`, `point`).
        kind: &'static str,
    },
    /// Fixed components do not move.
    #[error("component `{0}` is fixed; set `fixed: false` to move it")]
    FixedComponent(Name),
    /// A robot's links move with its joints, not on their own.
    #[error("component `{component}` is a link of robot `{robot}`: set the robot's joints (or base) to move it")]
    RobotLink {
        /// The component asked to move.
        component: Name,
        /// The robot that drives it.
        robot: Name,
    },
    /// A value out of range for what it sets.
    #[error("{what}: {value} is out of range: {rule}")]
    OutOfRange {
        /// What was set (a dimension's full name, a pose, cut cells `name`).
        what: String,
        /// The value given (document units: mm or degrees; a pose as text).
        value: String,
        /// What is accepted.
        rule: &'static str,
    },
    /// A new robot's name is empty or taken.
    #[error("robot names must be unique and non-empty: `{0}`")]
    RobotName(Name),
    /// A new robot would add a dimension that exists.
    #[error("robot `{robot}`: dimension `{dimension}` already exists")]
    DimensionTaken {
        /// The robot being added.
        robot: Name,
        /// The dimension's full name.
        dimension: Name,
    },
    /// A name with a control or invisible character (they hide or reorder what is
    /// shown).
    #[error("{what} name `{name}`: {character} is not allowed in names (control and invisible characters hide or reorder what is shown)")]
    HiddenCharacter {
        /// What is named (`robot`, …).
        what: String,
        /// The name, printable.
        name: String,
        /// The character, described.
        character: String,
    },
    /// `save_as` onto one of the document's own meshes.
    #[error("refusing to save over {}: it is the mesh of part `{part}`, a source of the open document", .path.display())]
    OverMesh {
        /// The target path.
        path: PathBuf,
        /// The part whose mesh it is.
        part: Name,
    },
    /// A robot refused an operation (kinematics, joint limits, program).
    #[error(transparent)]
    Robot(#[from] robot::RobotError),
    /// Writing the document failed.
    #[error("cannot write {path}: {cause}")]
    Write {
        /// Target path.
        path: PathBuf,
        /// Why not.
        #[source]
        cause: WriteProblem,
    },
}

/// Why a document, a sub-document or an export was not written (the cause of a
/// [`DocumentError::Write`]); nothing was written.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum WriteProblem {
    /// The write rule refused the file, or the write failed
    /// ([`crate::project::write_output`]).
    #[error(transparent)]
    Output(crate::project::OutputError),
    /// The operating system refused (its folder, the write).
    #[error(transparent)]
    Io(crate::fsutil::IoCause),
    /// The path has no file name.
    #[error("not a file name")]
    NotAFileName,
    /// The mates cannot be satisfied: the saved file would not open.
    #[error("not saved: the document would not open again ({0}); move the component back, float it, or delete or suppress the mate")]
    Unsolvable(#[source] SolveError),
    /// The text to be written would not load again.
    #[error("not saved: the document would not open again ({})", reload_why(.0))]
    WouldNotReload(#[source] Box<DocumentError>),
    /// The document could not be turned into YAML.
    #[error("{0}")]
    Serialize(#[source] YamlError),
    /// The file changed on disk since the document was loaded.
    #[error("not saved: the file changed on disk since it was loaded (another program or script saved it); open it again and redo the change")]
    ChangedOnDisk,
    /// An existing file that is not a fitup document.
    #[error("refusing to overwrite a file that is not a fitup document")]
    NotADocument,
    /// The existing file could not be read to check it.
    #[error("refusing to overwrite it: {0}")]
    Unreadable(#[source] crate::fsutil::ReadError),
    /// Two sub-document instances of one file changed differently.
    #[error("not saved: `{first}` and `{second}` are both this document and were changed differently (a document holds one content); make the same change in both, or save one with `save_as` under another name")]
    ChangedTwice {
        /// The first instance's name.
        first: String,
        /// The other instance's name.
        second: String,
    },
}

/// A YAML serializer's error kept shareable (a [`WriteProblem`] is `Clone`); two
/// compare equal when their messages do.
#[derive(Debug, Clone, thiserror::Error)]
#[error(transparent)]
pub struct YamlError(std::sync::Arc<serde_yaml::Error>);

impl From<serde_yaml::Error> for YamlError {
    fn from(e: serde_yaml::Error) -> Self {
        YamlError(std::sync::Arc::new(e))
    }
}

impl PartialEq for YamlError {
    fn eq(&self, other: &Self) -> bool {
        self.0.to_string() == other.0.to_string()
    }
}

/// Why a text would not load: a located error's message alone, else the error.
fn reload_why(e: &DocumentError) -> String {
    match e {
        DocumentError::Source(s) => s.message.clone(),
        other => other.to_string(),
    }
}

impl DocumentError {
    /// No `what` is named `name`: the error names the closest of `candidates`.
    pub(crate) fn not_found<'a>(
        what: &'static str,
        name: &str,
        candidates: impl IntoIterator<Item = &'a str> + Clone,
    ) -> Self {
        DocumentError::NotFound {
            what,
            name: name.into(),
            hint: crate::diagnostics::suggestion(name, candidates),
        }
    }

    /// Adds a hint to a located error.
    pub fn with_help(self, help: String) -> Self {
        match self {
            DocumentError::Source(s) => DocumentError::Source(s.with_help(help)),
            other => other,
        }
    }

    /// The message with source snippet for located errors.
    pub fn render(&self) -> String {
        if let DocumentError::PartUnreadable {
            component,
            part,
            at,
        } = self
        {
            return format!(
                "component `{component}` needs part `{part}`, whose file cannot be read (nothing changed):\n{}",
                at.render()
            );
        }
        match self.location() {
            Some(s) => s.render(),
            None => self.to_string(),
        }
    }

    /// Where in a file the error is, for located errors (a file's error, or mates
    /// of a file that cannot be satisfied).
    pub fn location(&self) -> Option<&SourceError> {
        match self {
            DocumentError::Source(s) => Some(s),
            DocumentError::Mates { at, .. } | DocumentError::Equation { at, .. } => at.as_deref(),
            DocumentError::PartUnreadable { at, .. } => Some(at),
            _ => None,
        }
    }
}

/// A mate's dimension that an equation uses ([`DocumentError::DimensionInUse`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}", dimension_in_use(self))]
pub struct DimensionInUse {
    /// The component being removed, when the mate goes with it.
    pub component: Option<String>,
    /// The mate.
    pub mate: String,
    /// The mate's dimension (full name).
    pub dimension: String,
    /// The equation's index (`equation(i)`).
    pub index: usize,
    /// The equation's text (shortened when long).
    pub equation: String,
}

/// A mate using a reference the component's new part does not have
/// ([`DocumentError::MissingReference`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("mate `{mate}` uses `{component}/{reference}`, which part `{part}` does not have")]
pub struct MissingReference {
    /// The mate.
    pub mate: String,
    /// The component whose part is replaced.
    pub component: String,
    /// The reference the mate uses.
    pub reference: String,
    /// The new part.
    pub part: String,
}

/// A sub-document's mate or equation reaching outside it
/// ([`DocumentError::OutsideSubDocument`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}", outside_message(self))]
pub struct OutsideSubDocument {
    /// The sub-document's file as written.
    pub file: String,
    /// The sub-assembly it is loaded as.
    pub at: String,
    /// What reaches out.
    pub item: OutsideItem,
}

/// [`DocumentError::DimensionInUse`]'s message.
fn dimension_in_use(e: &DimensionInUse) -> String {
    let DimensionInUse {
        component,
        mate,
        dimension,
        index,
        equation,
    } = e;
    match component {
        None => format!("mate `{mate}`: equation [{index}] {equation} uses its dimension `{dimension}`; delete or change the equation first"),
        Some(c) => format!("component `{c}`: its mate `{mate}` has the dimension `{dimension}` that equation [{index}] {equation} uses; delete or change the equation first"),
    }
}

/// [`DocumentError::OutsideSubDocument`]'s message.
fn outside_message(e: &OutsideSubDocument) -> String {
    let OutsideSubDocument { file, at, item } = e;
    match item {
        OutsideItem::Mate { mate, component } => format!(
            "mate `{at}/{mate}` of sub-document `{file}` refers to `{component}`, outside it"
        ),
        OutsideItem::Equation { name } => {
            format!("an equation of sub-document `{file}` uses \"{name}\", outside `{at}`")
        }
        OutsideItem::RobotLink { robot, component } => format!(
            "robot `{robot}` of sub-document `{file}` displays `{component}`, outside `{at}`"
        ),
    }
}

/// `names` quoted and joined: `` `a`, `b` ``.
fn quoted(names: &[String]) -> String {
    let names: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
    names.join(", ")
}

/// What was asked of a URDF link's component ([`DocumentError::UrdfLink`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum LinkEdit {
    /// A new name.
    Rename,
    /// Another part.
    ReplacePart,
}

/// What is wrong with a new mate ([`DocumentError::BadMate`]).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MateProblem {
    /// `about` names something other than an axis.
    #[error("`about` must name an axis")]
    AboutNotAnAxis,
    /// A mate type with a dimension (distance, angle) given no value.
    #[error("a {} mate needs a value", .0.name())]
    NeedsValue(super::MateKind),
    /// A mate type without a dimension given a value.
    #[error("a {} mate takes no value", .0.name())]
    TakesNoValue(super::MateKind),
    /// A value not finite or beyond [`super::MAX_ABS_VALUE`].
    #[error("value {0} is not a finite number up to 1e9")]
    ValueOutOfRange(f64),
    /// A negative distance.
    #[error("a distance cannot be negative")]
    NegativeDistance(f64),
    /// The mate's dimension would have a robot joint's dimension's name.
    #[error("a robot joint's dimension has that name")]
    RobotDimension,
}

/// What is wrong with a reference geometry ([`DocumentError::BadReference`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ReferenceProblem {
    /// A built-in name (`origin`, `front`, …) or an empty one.
    #[error("a built-in or empty name cannot be redefined")]
    ReservedName,
    /// A coordinate not finite or beyond [`super::MAX_ABS_VALUE`].
    #[error("its numbers must be finite and at most 1e9")]
    NotFinite,
    /// A plane with a zero normal.
    #[error("a zero normal")]
    ZeroNormal,
    /// An axis with a zero direction.
    #[error("a zero direction")]
    ZeroDirection,
}

/// Why a new part's mesh cannot be had ([`DocumentError::PartMesh`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PartMeshError {
    /// The mesh path the project rule refuses.
    #[error("mesh {0}")]
    Path(#[source] crate::project::PathError),
    /// The mesh file cannot be read.
    #[error(transparent)]
    Read(crate::mesh::MeshError),
    /// No project holds the document's file (the operating system's refusal).
    #[error(transparent)]
    Project(crate::fsutil::IoCause),
    /// The STEP file cannot be read or tessellated (or the build has no `step`
    /// feature: the message says how to add it).
    #[error(transparent)]
    Step(Box<crate::mesh::step::StepError>),
}

impl PartMeshError {
    /// The cause without the `mesh` prefix of a path refusal.
    fn cause(&self) -> String {
        match self {
            PartMeshError::Path(e) => e.to_string(),
            other => other.to_string(),
        }
    }
}

/// What of a sub-document reaches outside it ([`DocumentError::OutsideSubDocument`]).
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum OutsideItem {
    /// A mate (named inside the sub-document) with an entity on `component`.
    Mate {
        /// The mate.
        mate: String,
        /// The component outside.
        component: String,
    },
    /// An equation using `name`.
    Equation {
        /// The name outside.
        name: String,
    },
    /// A robot (full name) with a link displayed by `component`, outside.
    RobotLink {
        /// The robot.
        robot: String,
        /// The component outside.
        component: String,
    },
}

/// Why a URDF robot cannot be added ([`DocumentError::Urdf`]; a load's error is
/// located at the robot's `urdf:` line with this message).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum UrdfRobotError {
    /// No project holds the document's file (the operating system's refusal).
    #[error("cannot find the project: {0}")]
    Project(#[source] crate::fsutil::IoCause),
    /// The URDF path or a `package_path` entry the project rule refuses.
    #[error("{what} {source}")]
    Path {
        /// "URDF" or "package_path".
        what: &'static str,
        /// Why.
        source: crate::project::PathError,
    },
    /// A `package_path` entry that is not a folder.
    #[error("package_path `{0}` is not a folder")]
    NotAFolder(PathBuf),
    /// The URDF itself cannot be read or parsed (located in it).
    #[error(transparent)]
    Read(Box<SourceError>),
    /// A link's mesh: where it is named and what is wrong with it.
    #[error("{}{}: {problem}", .urdf.display(), match .link { Some(l) => format!(":{}: link `{}`", l.line, l.link), None => String::new() })]
    Mesh {
        /// The URDF file.
        urdf: PathBuf,
        /// The link and line naming the mesh, none for the primitives together.
        link: Option<UrdfLinkAt>,
        /// What is wrong (boxed: the readers' errors are large).
        problem: Box<UrdfMeshProblem>,
    },
    /// A link whose generated part or component name is taken.
    #[error("the part or component `{name}` (made for link `{link}` of the URDF) already exists")]
    LinkNameTaken {
        /// The generated name.
        name: Name,
        /// The link.
        link: Name,
    },
}

/// A URDF line that names a link's mesh ([`UrdfRobotError::Mesh`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UrdfLinkAt {
    /// 1-based line in the URDF.
    pub line: usize,
    /// The link's name.
    pub link: String,
}

/// What is wrong with a URDF link's mesh ([`UrdfRobotError::Mesh`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum UrdfMeshProblem {
    /// The document's URDF robots together would pass [`super::robot::MAX_URDF_TRIANGLES`].
    #[error("{}the URDF robots of the document would make more than {} triangles together ({} more, {} before; MAX_URDF_TRIANGLES): use coarser link meshes", .mesh.as_ref().map_or(String::new(), |m| format!("mesh `{m}`: ")), count(super::robot::MAX_URDF_TRIANGLES), count(*.more), count(*.before))]
    TooManyTriangles {
        /// The mesh file as the URDF names it; none for the primitives.
        mesh: Option<String>,
        /// The triangles this mesh (or the primitives) would add.
        more: usize,
        /// The triangles the document's URDF robots had before.
        before: usize,
    },
    /// A file format fitup does not read (`.dae`, …).
    #[error("mesh `{0}` is not a format fitup reads (STL, OBJ, PLY, glTF)")]
    Format(String),
    /// The mesh file cannot be found or read.
    #[error("mesh `{mesh}`: {}{}", .source.cause(), .own_package.as_ref().map_or(String::new(), |p| format!(" (no folder named `{p}` in the URDF's folders, on `package_path` or beside or above the URDF inside the project, so the URDF's own package was used; name the folder that holds it with `package_path:`)")))]
    Unreadable {
        /// The mesh file as the URDF names it.
        mesh: String,
        /// Why.
        source: PartMeshError,
        /// A `package://` whose package no folder is named after: its name.
        own_package: Option<String>,
    },
    /// The scaled mesh reaches beyond [`super::MAX_ABS_VALUE`].
    #[error("mesh `{mesh}` scaled by {scale:?} (mm per unit) reaches {reach:e} mm, beyond the {:e} mm fitup accepts", crate::math::MAX_ABS_VALUE)]
    Scaled {
        /// The mesh file as the URDF names it.
        mesh: String,
        /// The scale (mm per unit).
        scale: [f64; 3],
        /// The coordinate it reaches (mm).
        reach: f64,
    },
}

/// `n` grouped by thousands.
fn count(n: usize) -> String {
    crate::math::format::count(n as u64)
}

/// A mate failure's message: located (`file:line:col: …`) when it comes from a file.
fn mates_message(at: Option<&SourceError>, source: &SolveError) -> String {
    match at {
        Some(at) => at.to_string(),
        None => source.to_string(),
    }
}

/// An equation failure's message: located (`file:line:col: …`) when it comes from a
/// file.
fn equation_message(at: Option<&SourceError>, source: &EquationError) -> String {
    match at {
        Some(at) => at.to_string(),
        None => source.to_string(),
    }
}

impl From<super::EntryError> for DocumentError {
    fn from(e: super::EntryError) -> Self {
        Self::Entry(Box::new(e))
    }
}
