//! The YAML schema of an assembly document, exactly as written on disk.
//!
//! These structs mirror the file; [`super::Document`] is the validated model built
//! from them. Keeping the two apart lets the model hold derived data (meshes, solved
//! poses) while save writes back only what the user wrote.

use indexmap::IndexMap;
use serde::{Deserialize, Serialize};

/// The whole document file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct DocumentFile {
    /// Length unit of the file; only `mm` is accepted (fitup works in millimetres).
    #[serde(default = "default_units", skip_serializing_if = "is_default_units")]
    pub units: String,
    /// Free text.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// How far the parts' meshes may lie from the exact surfaces they stand for (mm):
    /// the linear deflection of the tessellation that made them (`fitup import`
    /// writes it). Sequence planning judges interference no finer than this.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh_deflection: Option<f64>,
    /// Part definitions by name.
    #[serde(default)]
    pub parts: IndexMap<String, PartFile>,
    /// Sub-assemblies: groups of components, nested by full name (`Cart-1`,
    /// `Cart-1/Axle-1`), parents first (see [`super::assembly`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub assemblies: Vec<AssemblyFile>,
    /// Part instances.
    #[serde(default)]
    pub components: Vec<ComponentFile>,
    /// Mates between reference entities of components.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub mates: Vec<MateFile>,
    /// Robots whose links are displayed by components (see [`RobotFile`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub robots: Vec<RobotFile>,
    /// Equations and global variables, SolidWorks' way: `'"Factor" = 2'`,
    /// `'"D1@lift" = 10 * "Factor"'` (values in mm and degrees; see
    /// [`super::equations`]). Evaluated in dependency order on every rebuild.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub equations: Vec<String>,
}

fn default_units() -> String {
    "mm".into()
}

fn is_default_units(u: &String) -> bool {
    u == "mm"
}

/// A part: a mesh and named reference geometry in the part frame (mm).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartFile {
    /// Mesh file (STL, OBJ, PLY, glTF/GLB), relative to the document's folder; empty
    /// when the part is a `step:` part.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub stl: String,
    /// A STEP file (relative to the document's folder) whose solids, at their
    /// placements in the file, are the part's geometry: tessellated when the document
    /// loads (feature `step`), the result kept in the project's tessellation store.
    /// Exactly one of `stl` and `step` is given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub step: Option<String>,
    /// `step:` parts: the tessellation's linear deflection, mm (default 0.1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deflection: Option<f64>,
    /// `step:` parts: the tessellation's angular deflection, degrees (default 28.6).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle: Option<f64>,
    /// Reference planes: point + normal.
    #[serde(default, skip_serializing_if = "IndexMap::is_empty")]
    pub planes: IndexMap<String, PlaneFile>,
    /// Reference axes: point + direction.
    #[serde(default, skip_serializing_if = "IndexMap::is_empty")]
    pub axes: IndexMap<String, AxisFile>,
    /// Reference points.
    #[serde(default, skip_serializing_if = "IndexMap::is_empty")]
    pub points: IndexMap<String, [f64; 3]>,
    /// Coordinate systems (SolidWorks' `CoordSys` features): origin and axes.
    #[serde(default, skip_serializing_if = "IndexMap::is_empty")]
    pub coordinate_systems: IndexMap<String, CoordinateSystemFile>,
    /// The feature tree (cut cells, …), in order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub features: Vec<FeatureFile>,
    /// Custom properties of the part (SolidWorks' file properties: `Description`,
    /// `Price`, `Material`, …): name → a text, number or true/false, kept as text.
    #[serde(default, skip_serializing_if = "IndexMap::is_empty")]
    pub properties: IndexMap<String, serde_yaml::Value>,
}

impl PartFile {
    /// A part that is only its mesh: `stl` relative to the document's folder, no
    /// reference geometry, no features.
    pub fn from_stl(stl: impl Into<String>) -> Self {
        PartFile {
            stl: stl.into(),
            step: None,
            deflection: None,
            angle: None,
            planes: IndexMap::new(),
            axes: IndexMap::new(),
            points: IndexMap::new(),
            coordinate_systems: IndexMap::new(),
            features: Vec::new(),
            properties: IndexMap::new(),
        }
    }
}

/// A feature of a part's feature tree.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum FeatureFile {
    /// Seed 000's "finite subdivision": the part cut into cells by arrays of planes,
    /// one box per cell. Give either `cell_size` (mm, cubic cells from the part's
    /// minimum corner) or `planes` (positions in the part frame, mm).
    CutCells {
        /// Feature name (unique in the part).
        name: String,
        /// Edge of the cubic cells, mm.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        cell_size: Option<f64>,
        /// Explicit cut planes.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        planes: Option<PlanesFile>,
    },
}

impl FeatureFile {
    /// The feature's name.
    pub(crate) fn name(&self) -> &str {
        match self {
            FeatureFile::CutCells { name, .. } => name,
        }
    }
}

/// Cut plane positions along each axis of the part frame (mm).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct PlanesFile {
    /// Planes `x = const`.
    #[serde(default)]
    pub x: Vec<f64>,
    /// Planes `y = const`.
    #[serde(default)]
    pub y: Vec<f64>,
    /// Planes `z = const`.
    #[serde(default)]
    pub z: Vec<f64>,
}

/// A reference plane through `point` with unit `normal` (normalised on load).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlaneFile {
    /// A point on the plane, mm.
    pub point: [f64; 3],
    /// The plane normal.
    pub normal: [f64; 3],
}

/// A reference axis through `point` along `direction` (normalised on load).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisFile {
    /// A point on the axis, mm.
    pub point: [f64; 3],
    /// The axis direction.
    pub direction: [f64; 3],
}

/// A coordinate system: its origin and its X and Y axes in the part frame (mm); Z is
/// X × Y. The axes are normalised on load and must be perpendicular (to 1e-6).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CoordinateSystemFile {
    /// The origin, mm.
    pub origin: [f64; 3],
    /// The X axis direction.
    pub x: [f64; 3],
    /// The Y axis direction.
    pub y: [f64; 3],
}

/// A sub-assembly: a group of components in this document.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AssemblyFile {
    /// Full name, levels joined by `/` (`Cart-1/Axle-1`); its parent is listed before.
    pub name: String,
    /// Pose relative to the parent sub-assembly (the assembly at the top), the
    /// component pose layout, mm; identity when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transform: Option<[[f64; 4]; 4]>,
    /// Another fitup document (path relative to this document's folder, inside the
    /// project) whose parts, components, sub-assemblies and mates this sub-assembly
    /// holds, as SolidWorks' `.sldasm` inside an assembly (see
    /// [`super::subdoc`]). Its content is written in that file, not here.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// Suppressed: everything it holds is suppressed (kept, but not checked,
    /// planned around, sequenced, weighed or exported; mates to it inactive).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub suppressed: bool,
}

/// A component: an instance of a part at a pose.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ComponentFile {
    /// Unique component name (SolidWorks style `part-1` or anything); inside a
    /// sub-assembly its full name `Cart-1/Wheel-2`, and then its `transform` is
    /// relative to that sub-assembly.
    pub name: String,
    /// The part it instantiates.
    pub part: String,
    /// Fixed components are never moved by the mate solver.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub fixed: bool,
    /// Display colour: `[r, g, b]` in 0..1 or `"#rrggbb"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<serde_yaml::Value>,
    /// The pose matrix, 4 rows `[a b c n] [d e f o] [g h i p] [j k l m]` (seed 000
    /// formula (1)), translation `j k l` in mm; identity when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transform: Option<[[f64; 4]; 4]>,
    /// Mass in kg (optional, finite and > 0): sequence planning chooses the heaviest
    /// part as the base (else the largest mesh volume).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass: Option<f64>,
    /// The component is screwed in: its assembly task is a `screw` operation.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub threaded: bool,
    /// The component is not part of the product (a fixture, the table, a pedestal, a
    /// robot shown by a plain mesh): sequence planning leaves it out, like robot
    /// links and `exclude`d components.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub fixture: bool,
    /// Suppressed (SolidWorks' suppression): kept in the document but not checked,
    /// planned around, sequenced, weighed or exported; its mates are inactive.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub suppressed: bool,
    /// Hidden: checked like any other component, but not shown or exported.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub hidden: bool,
    /// Custom properties of this instance (SolidWorks' component-level properties):
    /// name → a text, number or true/false, kept as text.
    #[serde(default, skip_serializing_if = "IndexMap::is_empty")]
    pub properties: IndexMap<String, serde_yaml::Value>,
}

impl ComponentFile {
    /// A component of `part` named `name` at `transform` (mm), with nothing else set.
    pub fn new(
        name: impl Into<String>,
        part: impl Into<String>,
        transform: Option<[[f64; 4]; 4]>,
    ) -> Self {
        ComponentFile {
            name: name.into(),
            part: part.into(),
            transform,
            ..ComponentFile::default()
        }
    }
}

/// A mate between two reference entities `component/reference`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MateFile {
    /// Mate name; a distance or angle mate's driving dimension is `D1@<name>`.
    pub name: String,
    /// `coincident`, `concentric`, `parallel`, `perpendicular`, `distance` or `angle`.
    #[serde(rename = "type")]
    pub kind: String,
    /// The two entities, `component/reference` (`reference` is a plane, axis or point of
    /// the component's part; `origin` is the part origin).
    pub entities: [String; 2],
    /// Driving value of distance (mm) and angle (degrees) mates.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value: Option<f64>,
    /// Align the normals/directions instead of opposing them (SolidWorks "aligned"
    /// vs "anti-aligned"); coincident planes default to anti-aligned.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aligned: Option<bool>,
    /// For angle mates: the axis (`component/axis`) about which the angle is measured,
    /// making it a signed angle over the full turn.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub about: Option<String>,
    /// Suppressed: kept in the document, not solved.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub suppressed: bool,
}

/// A robot: a kinematic tree (from the catalog, a D-H table or explicit links) placed
/// at `base`, with a tool frame and current joint values; its links move components.
///
/// Exactly one of `catalog`, `dh`, `urdf` or a `links` list with joints describes the
/// tree. With `catalog`, `dh` or `urdf`, `links` only attaches components (link 0 is the base, link
/// `i` carries D-H frame `i`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotFile {
    /// Unique robot name.
    pub name: String,
    /// A catalog arm (`nachi_mz07`, `abb_irb2400`, …).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub catalog: Option<String>,
    /// A D-H table.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dh: Option<DhFile>,
    /// A URDF file (path relative to the document's folder, inside the project): its
    /// kinematics, and its links' STL meshes as generated parts and components (see
    /// `docs/robots.md`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub urdf: Option<String>,
    /// `urdf:` robots: folders (relative to the document's folder, inside the project)
    /// where `package://PKG/…` mesh URIs find the folder `PKG`, searched after the
    /// URDF's own package and before the folders beside and above it (ROS's package
    /// path; see `docs/robots.md`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub package_path: Vec<String>,
    /// World pose of the robot's root link (pose matrix like components; identity when
    /// absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base: Option<[[f64; 4]; 4]>,
    /// The tool centre point in the flange frame (pose matrix); the catalog tool, or
    /// the flange itself, when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool: Option<[[f64; 4]; 4]>,
    /// Explicit trees: the name of the link carrying the tool (default: the last link).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flange: Option<String>,
    /// `urdf:` robots: the arm's last link, carrying the tool (default: the last link
    /// of the serial arm, not a gripper finger; see `docs/robots.md`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tip: Option<String>,
    /// Components' part frames coincide with the robot base frame when every joint is
    /// at 0 (meshes drawn in the zero configuration, as CAD models of robots usually
    /// are): the default `offset` of each link is then the inverse of its zero pose.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub drawn_at_zero: bool,
    /// The links (parents first).
    #[serde(default)]
    pub links: Vec<LinkFile>,
    /// Current joint values in joint order: degrees (revolute), mm (prismatic); all 0
    /// when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joints: Option<Vec<f64>>,
}

/// A D-H table (angles in degrees, lengths in mm).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DhFile {
    /// `standard` (seed 000 table 2, default) or `modified` (Craig).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub convention: Option<String>,
    /// One row per joint.
    pub rows: Vec<DhRowFile>,
}

/// One D-H row: θ (joint offset) and α in degrees, d and a in mm.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DhRowFile {
    /// Joint offset θ (degrees).
    pub theta: f64,
    /// Offset along z (mm).
    pub d: f64,
    /// Length along x (mm).
    pub a: f64,
    /// Twist about x (degrees).
    pub alpha: f64,
    /// `revolute` (default) or `prismatic`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint: Option<String>,
    /// `[min, max]`: degrees (revolute) or mm (prismatic).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limits: Option<[f64; 2]>,
}

/// A link of a robot: which component displays it, and (explicit trees only) its
/// parent and joint. Axis and point are in the parent link's frame (seed 001).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct LinkFile {
    /// Link name (required for explicit trees; catalog and D-H links are `base`,
    /// `link1`, …).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The component whose pose follows this link.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub component: Option<String>,
    /// Pose of the component's part frame in the link frame (pose matrix); identity,
    /// or the inverse zero pose with `drawn_at_zero`, when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offset: Option<[[f64; 4]; 4]>,
    /// Explicit trees: the parent link's name (none for the root).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parent: Option<String>,
    /// Explicit trees: `fixed` (default), `revolute` or `prismatic`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint: Option<String>,
    /// Explicit trees: the joint axis direction in the parent frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis: Option<[f64; 3]>,
    /// Explicit trees: a point on a revolute axis in the parent frame (mm).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<[f64; 3]>,
    /// Explicit trees: the link frame in the parent frame at joint value 0 (pose
    /// matrix; identity when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub home: Option<[[f64; 4]; 4]>,
    /// Explicit trees: `[min, max]` in degrees (revolute) or mm (prismatic).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limits: Option<[f64; 2]>,
    /// The driving dimension's feature name (full name `D1@<dimension>`); default
    /// `角度<n>@<robot>` (revolute) or `距离<n>@<robot>` (prismatic), n = joint number.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dimension: Option<String>,
}

impl DocumentFile {
    /// The YAML text of the document, with number lists (points, vectors, matrix rows)
    /// written inline as `[x, y, z]` so that a pose reads as the 4×4 matrix it is.
    pub fn to_yaml(&self) -> Result<String, serde_yaml::Error> {
        let block = serde_yaml::to_string(self)?;
        let flow = inline_number_lists(&block);
        // The rewrite is purely presentational; never let it change the content.
        match serde_yaml::from_str::<DocumentFile>(&flow) {
            Ok(back) if back == *self => Ok(flow),
            _ => Ok(block),
        }
    }
}

fn number_item<'a>(line: &'a str, prefix: &str) -> Option<&'a str> {
    let rest = line.strip_prefix(prefix)?;
    (rest.parse::<f64>().is_ok() || matches!(rest, ".nan" | ".inf" | "-.inf")).then_some(rest)
}

/// Rewrites `key:` followed by `- <number>` lines as `key: [a, b, c]`, and `key:`
/// followed by rows of numbers (`- - a` / `  - b`) as `- [a, b]` rows.
fn inline_number_lists(yaml: &str) -> String {
    let lines: Vec<&str> = yaml.lines().collect();
    let mut out = String::with_capacity(yaml.len());
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        let indent = &line[..line.len() - line.trim_start().len()];
        if line.ends_with(':') {
            let item = format!("{indent}- ");
            let mut j = i + 1;
            let mut nums = Vec::new();
            while let Some(n) = lines.get(j).and_then(|l| number_item(l, &item)) {
                nums.push(n);
                j += 1;
            }
            if !nums.is_empty() {
                out += &format!("{line} [{}]\n", nums.join(", "));
                i = j;
                continue;
            }
            // A matrix: rows `- - a` then `  - b`.
            let row_start = format!("{indent}- - ");
            let row_more = format!("{indent}  - ");
            let mut rows = Vec::new();
            while let Some(first) = lines.get(j).and_then(|l| number_item(l, &row_start)) {
                let mut row = vec![first];
                j += 1;
                while let Some(n) = lines.get(j).and_then(|l| number_item(l, &row_more)) {
                    row.push(n);
                    j += 1;
                }
                rows.push(row);
            }
            if !rows.is_empty() {
                out += line;
                out.push('\n');
                for r in rows {
                    out += &format!("{indent}- [{}]\n", r.join(", "));
                }
                i = j;
                continue;
            }
        }
        out += line;
        out.push('\n');
        i += 1;
    }
    out
}
