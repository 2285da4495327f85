//! Robots in a document: a [`Robot`] (kinematic tree, base, tool) whose links move
//! components, with current joint values and one driving dimension per joint.
//!
//! A link's component pose is `offset · link_world` (row-vector order: the part frame
//! is placed in the link frame by `offset`, then the link frame in the world), so
//! setting the joints (or a joint's dimension) moves every link component, as a
//! SolidWorks rebuild does. Joint values are radians / mm inside; the file writes
//! degrees / mm.

use super::dimension;
use super::file::{DhFile, LinkFile, RobotFile};
use super::{
    Document, DocumentError, EntryError, PartMeshError, UrdfLinkAt, UrdfMeshProblem, UrdfRobotError,
};
use crate::diagnostics::{locate, suggestion, SourceError};
use crate::kinematics::{
    resolve_mesh_in, robot_by_name, run_program, DhConvention, DhRow, Joint, JointKind,
    JointLimits, KinematicTree, KinematicsError, Link, MotionOptions, PackageFound, Program,
    ProgramRunError, Robot, Trajectory,
};
use crate::math::{Point3, Transform, Vec3};
use crate::mesh::{Mesh, MeshCache};
use crate::project::Project;
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Why a robot of a document refused an operation (carried by
/// [`DocumentError::Robot`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RobotError {
    /// A kinematics error (joint count, non-finite value, …).
    #[error("robot `{robot}`: {source}")]
    Kinematics {
        /// The robot's name.
        robot: String,
        /// The cause.
        #[source]
        source: KinematicsError,
    },
    /// A joint value outside its limits (in document units: degrees or mm).
    #[error("robot `{robot}`: joint {joint} = {value:.4}{unit} is outside its limits [{min:.4}, {max:.4}]{unit}")]
    JointLimit {
        /// The robot's name.
        robot: String,
        /// 1-based joint number.
        joint: usize,
        /// The value (degrees or mm).
        value: f64,
        /// Lower limit (degrees or mm).
        min: f64,
        /// Upper limit (degrees or mm).
        max: f64,
        /// `°` or `mm`.
        unit: &'static str,
    },
    /// A base or tool pose that is not finite.
    #[error("robot `{robot}`: the {what} pose is not finite")]
    NonFinite {
        /// The robot's name.
        robot: String,
        /// `base` or `tool`.
        what: &'static str,
    },
    /// A motion program failed (file, line and motion error).
    #[error("robot `{robot}`: {source}")]
    Program {
        /// The robot's name.
        robot: String,
        /// The failing command and cause (boxed: keeps the error small).
        #[source]
        source: Box<ProgramRunError>,
    },
}

/// How one link is displayed.
#[derive(Debug, Clone, PartialEq)]
pub struct LinkDisplay {
    /// The component that follows the link, if any.
    pub component: Option<usize>,
    /// Pose of the component's part frame in the link frame (mm).
    pub offset: Transform,
}

/// A robot of a document: kinematics, current joints, displayed links, dimensions.
#[derive(Debug, Clone)]
pub struct RobotInstance {
    /// Shared so that scripts can hold the robot without copying its tree.
    robot: Arc<Robot>,
    links: Vec<LinkDisplay>,
    joints: Vec<f64>,
    dimensions: Vec<String>,
    file: RobotFile,
    /// For a `urdf:` robot: the URDF and its mesh files.
    urdf_files: Vec<PathBuf>,
    /// For a `urdf:` robot: its `package_path` folders, resolved.
    package_path: Vec<PathBuf>,
}

impl RobotInstance {
    /// The robot's name.
    pub fn name(&self) -> &str {
        self.robot.name()
    }

    /// The kinematic robot (base and tool as currently set).
    pub fn robot(&self) -> &Robot {
        &self.robot
    }

    /// The kinematic robot, shared: a cheap handle (no copy of the tree) that stays
    /// valid while the document changes (a later base or tool change makes a new one).
    pub fn shared_robot(&self) -> Arc<Robot> {
        Arc::clone(&self.robot)
    }

    /// Current joint values in joint order (rad, or mm for prismatic joints).
    pub fn joints(&self) -> &[f64] {
        &self.joints
    }

    /// Per link of the tree: its component and offset.
    pub fn links(&self) -> &[LinkDisplay] {
        &self.links
    }

    /// Feature names of the joints' driving dimensions, in joint order (the full name
    /// is `D1@<feature>`).
    pub fn dimension_features(&self) -> &[String] {
        &self.dimensions
    }

    /// Full names of the joints' driving dimensions (`D1@角度1`), in joint order.
    pub fn dimension_names(&self) -> Vec<String> {
        self.dimensions
            .iter()
            .map(|d| dimension::full_name(d))
            .collect()
    }

    /// The world pose of the TCP at the current joints (mm).
    pub fn tcp(&self) -> Transform {
        // The joints are checked whenever they are set, so FK cannot fail here.
        self.robot
            .tcp_pose(&self.joints)
            .unwrap_or(Transform::IDENTITY)
    }

    /// World poses of the displayed components for joint values `q`:
    /// `(component index, pose)`.
    pub fn component_poses(&self, q: &[f64]) -> Result<Vec<(usize, Transform)>, RobotError> {
        let poses = self.robot.link_poses(q).map_err(|e| self.kinematics(e))?;
        Ok(self
            .links
            .iter()
            .zip(poses)
            .filter_map(|(l, p)| l.component.map(|c| (c, l.offset * p)))
            .collect())
    }

    fn kinematics(&self, source: KinematicsError) -> RobotError {
        RobotError::Kinematics {
            robot: self.name().to_string(),
            source,
        }
    }

    /// Why `q` is not a valid joint vector for this robot (count, finite, limits),
    /// naming the joint in document units.
    pub fn check_joints(&self, q: &[f64]) -> Result<(), RobotError> {
        self.robot.tcp_pose(q).map_err(|e| self.kinematics(e))?;
        if let Some(j) = self.robot.limit_violation(q) {
            let kinds = self.robot.joint_kinds();
            let limits = self.robot.joint_limits();
            let (v, lo, hi, unit) = match (kinds[j], limits[j]) {
                (JointKind::Prismatic, Some(l)) => (q[j], l.min, l.max, "mm"),
                (_, Some(l)) => (
                    q[j].to_degrees(),
                    l.min.to_degrees(),
                    l.max.to_degrees(),
                    "°",
                ),
                (_, None) => (q[j], f64::NAN, f64::NAN, ""),
            };
            return Err(RobotError::JointLimit {
                robot: self.name().to_string(),
                joint: j + 1,
                value: v,
                min: lo,
                max: hi,
                unit,
            });
        }
        Ok(())
    }

    /// For a robot read from a `urdf:` file: the URDF and the mesh files it names
    /// (the first is the URDF).
    pub fn urdf_files(&self) -> &[PathBuf] {
        &self.urdf_files
    }

    /// Rewrites the `urdf:` path and the `package_path` folders with `relative` (a
    /// file or folder → its path from a new document folder), for `save_as`.
    pub(super) fn rebase_urdf(&mut self, relative: impl Fn(&Path) -> Option<String>) {
        if let (Some(_), Some(f)) = (&self.file.urdf, self.urdf_files.first()) {
            if let Some(rel) = relative(f) {
                self.file.urdf = Some(rel);
            }
        }
        if self.package_path.len() == self.file.package_path.len() {
            for (written, folder) in self.file.package_path.iter_mut().zip(&self.package_path) {
                if let Some(rel) = relative(folder) {
                    *written = rel;
                }
            }
        }
    }

    /// This robot of a sub-document as the assembly holding it sees it: named inside
    /// the sub-assembly `at` (`Cell-1/Arm`, dimensions `Cell-1/角度1@Arm`), its link
    /// components `offset` further on, its base placed by the sub-assembly's `frame`
    /// (sub-document frame → world, mm).
    pub(super) fn nested(&self, at: &str, offset: usize, frame: Transform) -> RobotInstance {
        let name = format!("{at}/{}", self.name());
        let mut robot = (*self.robot).clone().with_name(name.clone());
        robot.set_base(robot.base() * frame);
        RobotInstance {
            robot: Arc::new(robot),
            links: self
                .links
                .iter()
                .map(|l| LinkDisplay {
                    component: l.component.map(|c| c + offset),
                    offset: l.offset,
                })
                .collect(),
            joints: self.joints.clone(),
            dimensions: self
                .dimensions
                .iter()
                .map(|d| format!("{at}/{d}"))
                .collect(),
            file: RobotFile {
                name,
                ..self.file.clone()
            },
            urdf_files: self.urdf_files.clone(),
            package_path: self.package_path.clone(),
        }
    }

    /// [`nested`](Self::nested) undone: the robot as the sub-document at `at` holds
    /// it, its link components renumbered by `index` (assembly index → the
    /// sub-document's), its base back in the sub-document's frame (`inv`: world →
    /// sub-document frame). `Err(component)`: a link component that is not in the
    /// sub-document (renamed out of it).
    pub(super) fn extracted(
        &self,
        at: &str,
        index: &HashMap<usize, usize>,
        inv: Transform,
    ) -> Result<RobotInstance, usize> {
        let strip = |n: &str| {
            n.strip_prefix(at)
                .and_then(|r| r.strip_prefix('/'))
                .unwrap_or(n)
                .to_string()
        };
        let name = strip(self.name());
        let mut robot = (*self.robot).clone().with_name(name.clone());
        robot.set_base(super::snapped(robot.base() * inv));
        let mut links = Vec::with_capacity(self.links.len());
        for l in &self.links {
            let component = match l.component {
                Some(c) => Some(*index.get(&c).ok_or(c)?),
                None => None,
            };
            links.push(LinkDisplay {
                component,
                offset: l.offset,
            });
        }
        Ok(RobotInstance {
            robot: Arc::new(robot),
            links,
            joints: self.joints.clone(),
            dimensions: self.dimensions.iter().map(|d| strip(d)).collect(),
            file: RobotFile {
                name,
                ..self.file.clone()
            },
            urdf_files: self.urdf_files.clone(),
            package_path: self.package_path.clone(),
        })
    }

    /// [`to_file`](Self::to_file) with each link's `component:` the current name of
    /// the component it displays (`name` of an index): a renamed component is
    /// written under its new name.
    pub(super) fn to_file_named(&self, name: impl Fn(usize) -> String) -> RobotFile {
        let mut f = self.to_file();
        for (lf, l) in f.links.iter_mut().zip(&self.links) {
            if let (Some(written), Some(c)) = (&mut lf.component, l.component) {
                *written = name(c);
            }
        }
        f
    }

    /// The robot as written in the file, with the current base, tool and joints.
    pub fn to_file(&self) -> RobotFile {
        let tidy = |m: [[f64; 4]; 4]| m.map(|r| r.map(|x| if x.abs() < 1e-14 { 0.0 } else { x }));
        let kinds = self.robot.joint_kinds();
        let mut f = self.file.clone();
        f.base = Some(tidy(self.robot.base().to_matrix()));
        f.tool = Some(tidy(self.robot.tool().to_matrix()));
        f.joints = Some(
            self.joints
                .iter()
                .zip(kinds)
                .map(|(v, k)| {
                    let v = if k == JointKind::Prismatic {
                        *v
                    } else {
                        v.to_degrees()
                    };
                    if v.abs() < 1e-12 {
                        0.0
                    } else {
                        v
                    }
                })
                .collect(),
        );
        f
    }
}

/// Whether joint `i` of `robot` is prismatic (mm) rather than revolute (radians);
/// joints past the robot's count are taken as revolute.
fn is_prismatic(robot: &Robot, i: usize) -> bool {
    robot
        .joint_links()
        .get(i)
        .is_some_and(|&l| robot.tree().links()[l].joint.kind == JointKind::Prismatic)
}

/// Joint values from document units (degrees / mm) to radians / mm.
pub fn joints_from_document(robot: &Robot, values: &[f64]) -> Vec<f64> {
    let mut q = values.to_vec();
    joints_from_document_in_place(robot, &mut q);
    q
}

/// [`joints_from_document`] in place: degrees become radians, millimetres stay (no
/// allocation, for per-call script conversions).
pub fn joints_from_document_in_place(robot: &Robot, values: &mut [f64]) {
    for (i, v) in values.iter_mut().enumerate() {
        if !is_prismatic(robot, i) {
            *v = v.to_radians();
        }
    }
}

/// Joint values from radians / mm to document units (degrees / mm).
pub fn joints_to_document(robot: &Robot, q: &[f64]) -> Vec<f64> {
    joints_to_document_iter(robot, q).collect()
}

/// [`joints_to_document`] as an iterator (no intermediate vector).
pub fn joints_to_document_iter<'a>(
    robot: &'a Robot,
    q: &'a [f64],
) -> impl Iterator<Item = f64> + 'a {
    q.iter().enumerate().map(move |(i, v)| {
        if is_prismatic(robot, i) {
            *v
        } else {
            v.to_degrees()
        }
    })
}

fn matrix(m: &Option<[[f64; 4]; 4]>, what: &'static str) -> Result<Option<Transform>, EntryError> {
    m.as_ref()
        .map(|m| Transform::from_matrix(m).map_err(|source| EntryError::Matrix { what, source }))
        .transpose()
}

fn joint_kind(s: Option<&str>, default: JointKind) -> Result<JointKind, EntryError> {
    match s {
        None => Ok(default),
        Some("fixed") => Ok(JointKind::Fixed),
        Some("revolute") => Ok(JointKind::Revolute),
        Some("prismatic") => Ok(JointKind::Prismatic),
        Some(other) => Err(EntryError::JointType(other.to_string())),
    }
}

fn limits(l: Option<[f64; 2]>, kind: JointKind) -> Result<Option<JointLimits>, EntryError> {
    let Some([lo, hi]) = l else { return Ok(None) };
    if !(lo.is_finite() && hi.is_finite()) {
        return Err(EntryError::LimitsNotFinite { lo, hi });
    }
    if lo > hi {
        return Err(EntryError::LimitsInverted { lo, hi });
    }
    Ok(Some(if kind == JointKind::Prismatic {
        JointLimits::new(lo, hi)
    } else {
        JointLimits::degrees(lo, hi)
    }))
}

fn dh_robot(name: &str, dh: &DhFile) -> Result<Robot, EntryError> {
    let convention = match dh.convention.as_deref() {
        None | Some("standard") => DhConvention::Standard,
        Some("modified") => DhConvention::Modified,
        Some(o) => return Err(EntryError::DhConvention(o.to_string())),
    };
    let mut rows = Vec::with_capacity(dh.rows.len());
    for (i, r) in dh.rows.iter().enumerate() {
        let in_row = |e: EntryError| EntryError::DhRow {
            row: i + 1,
            source: Box::new(e),
        };
        let kind = joint_kind(r.joint.as_deref(), JointKind::Revolute).map_err(in_row)?;
        let (theta, alpha) = (r.theta.to_radians(), r.alpha.to_radians());
        let mut row = match kind {
            JointKind::Revolute => DhRow::revolute(theta, r.d, r.a, alpha),
            JointKind::Prismatic => DhRow::prismatic(theta, r.d, r.a, alpha),
            JointKind::Fixed => return Err(in_row(EntryError::DhFixedRow)),
        };
        if let Some(l) = limits(r.limits, kind).map_err(in_row)? {
            row = row.with_limits(l);
        }
        rows.push(row);
    }
    if rows.is_empty() {
        return Err(EntryError::DhEmpty);
    }
    Ok(Robot::from_dh(
        name,
        &rows,
        convention,
        Transform::IDENTITY,
    )?)
}

/// An explicit tree; errors carry a needle (the failing link's name) and a message.
fn explicit_robot(f: &RobotFile) -> Result<Robot, (String, String)> {
    let whole = |m: String| (format!("name: {}", f.name), m);
    let mut index: HashMap<&str, usize> = HashMap::new();
    let mut links = Vec::with_capacity(f.links.len());
    for (i, l) in f.links.iter().enumerate() {
        let name = l
            .name
            .as_deref()
            .ok_or_else(|| whole(format!("link {} needs a `name`", i + 1)))?;
        let err = |m: String| (format!("name: {name}"), format!("link `{name}`: {m}"));
        if index.insert(name, i).is_some() {
            return Err(err("duplicate link name".into()));
        }
        let parent = match l.parent.as_deref() {
            None => None,
            Some(p) => Some(*index.get(p).ok_or_else(|| {
                err(format!(
                    "parent `{p}` is not a link listed before it ({})",
                    suggestion(p, index.keys().copied())
                ))
            })?),
        };
        let kind =
            joint_kind(l.joint.as_deref(), JointKind::Fixed).map_err(|e| err(e.to_string()))?;
        let v = |a: [f64; 3]| Vec3::new(a[0], a[1], a[2]);
        let mut joint = match kind {
            JointKind::Fixed => Joint::fixed(),
            JointKind::Revolute => Joint::revolute(
                v(l.axis
                    .ok_or_else(|| err("a revolute joint needs an `axis`".into()))?),
                Point3::from(v(l.point.unwrap_or([0.0; 3]))),
            ),
            JointKind::Prismatic => Joint::prismatic(v(l
                .axis
                .ok_or_else(|| err("a prismatic joint needs an `axis`".into()))?)),
        };
        if kind == JointKind::Fixed && (l.axis.is_some() || l.limits.is_some()) {
            return Err(err("a fixed link takes no `axis` or `limits`".into()));
        }
        if let Some(lim) = limits(l.limits, kind).map_err(|e| err(e.to_string()))? {
            joint = joint.with_limits(lim);
        }
        let home = matrix(&l.home, "home")
            .map_err(|e| err(e.to_string()))?
            .unwrap_or(Transform::IDENTITY);
        links.push(Link::new(name, parent, home, joint));
    }
    let tree = KinematicTree::new(links).map_err(|e| whole(e.to_string()))?;
    let flange = match f.flange.as_deref() {
        Some(n) => tree.find(n).ok_or_else(|| {
            (
                format!("flange: {n}"),
                format!("flange `{n}` is not a link"),
            )
        })?,
        None => tree
            .len()
            .checked_sub(1)
            .ok_or_else(|| whole("a robot needs `catalog`, `dh` or `links`".into()))?,
    };
    Robot::new(&f.name, tree, flange, Transform::IDENTITY).map_err(|e| whole(e.to_string()))
}

/// The most triangles the `urdf:` robots of one document may make together (every
/// link's meshes, scaled and placed, and its primitives), counted before each link
/// mesh is copied: a link mesh is a copy of its file's mesh, so one 2-million-triangle
/// file named by 400 links would otherwise make 800 million triangles (a 490 KB URDF
/// took 16 GB). Measured at the cap: `fitup check` peaks at about 500 MB (4 links of a
/// 1,000,000-triangle STL and the fifth refused; docs/document.md).
pub const MAX_URDF_TRIANGLES: usize = 4_000_000;

/// A URDF robot of a document with its generated link components.
#[derive(Debug, Clone)]
pub(super) struct UrdfLoaded {
    /// The kinematics.
    pub robot: Robot,
    /// The URDF file on disk (for watch mode and `save_as`).
    pub path: PathBuf,
    /// The folders of the robot's `package_path`, resolved (for `save_as`).
    pub package_path: Vec<PathBuf>,
    /// Per link of the tree: its merged mesh (link frame, mm), if it has one.
    pub meshes: Vec<Option<Mesh>>,
    /// The URDF and every mesh file read (for watch mode).
    pub files: Vec<PathBuf>,
    /// Located warnings of the URDF (meshes left out), `file:line:column: …`.
    pub warnings: Vec<String>,
}

/// Reads the URDF `uri` of robot `name` (relative to the document folder `dir`,
/// inside `project`) and its links' geometry: each mesh file (STL, OBJ, PLY, glTF,
/// read through `cache`) resolved by [`resolve_mesh`] and checked to lie inside the
/// project, scaled (metres → mm and the URDF `scale`), moved by its visual origin into
/// the link frame; box, cylinder and sphere primitives meshed; the geometry of one link
/// merged. `tip` names the arm's last link (default: see
/// [`crate::kinematics::parse_urdf`]). Meshes fitup does not read (`.dae`) are left
/// out by the parser with located warnings (in [`UrdfLoaded::warnings`]) unless the
/// link's collision geometry stands in.
pub(super) fn read_urdf_robot(
    project: &Project,
    dir: &Path,
    uri: &str,
    package_path: &[String],
    tip: Option<&str>,
    cache: &mut MeshCache,
    left: &mut usize,
) -> Result<UrdfLoaded, UrdfRobotError> {
    let path = project
        .resolve_from(dir, uri)
        .map_err(|source| UrdfRobotError::Path {
            what: "URDF",
            source,
        })?;
    let mut roots = Vec::with_capacity(package_path.len());
    for p in package_path {
        let root = project
            .resolve_from(dir, p)
            .map_err(|source| UrdfRobotError::Path {
                what: "package_path",
                source,
            })?;
        if project.folder(&root, false).is_err() {
            return Err(UrdfRobotError::NotAFolder(p.into()));
        }
        roots.push(root);
    }
    let u = crate::kinematics::read_urdf_in(project, &path, tip)
        .map_err(|e| UrdfRobotError::Read(Box::new(e)))?;
    let tree = u.robot.tree();
    let mut meshes: Vec<Option<Mesh>> = vec![None; tree.len()];
    let mut files = vec![path.clone()];
    let mut add = |link: usize, mesh: Mesh| match &mut meshes[link] {
        Some(all) => all.append(&mesh),
        slot => *slot = Some(mesh),
    };
    let over = |mesh: Option<&str>, more: usize, left: usize| UrdfMeshProblem::TooManyTriangles {
        mesh: mesh.map(str::to_string),
        more,
        before: MAX_URDF_TRIANGLES.saturating_sub(left),
    };
    let primitive: usize = u.primitives.iter().map(|p| p.mesh.triangles.len()).sum();
    if primitive > *left {
        return Err(UrdfRobotError::Mesh {
            urdf: path.clone(),
            link: None,
            problem: Box::new(over(None, primitive, *left)),
        });
    }
    *left -= primitive;
    for p in &u.primitives {
        add(p.link, p.mesh.clone());
    }
    for m in &u.meshes {
        let link = tree.links()[m.link].name.clone().unwrap_or_default();
        let at = |problem| UrdfRobotError::Mesh {
            urdf: path.clone(),
            link: Some(UrdfLinkAt {
                line: m.line,
                link: link.clone(),
            }),
            problem: Box::new(problem),
        };
        if crate::mesh::MeshFormat::from_path(Path::new(&m.uri)).is_none() {
            return Err(at(UrdfMeshProblem::Format(m.uri.clone())));
        }
        let (resolved, found) = resolve_mesh_in(project, &path, &m.uri, &roots);
        // A package no folder is named after: say so beside the missing file.
        let unreadable = |source| UrdfMeshProblem::Unreadable {
            mesh: m.uri.clone(),
            source,
            own_package: match (found, m.uri.strip_prefix("package://")) {
                (PackageFound::OwnPackage, Some(rest)) => {
                    Some(rest.split('/').next().unwrap_or_default().to_string())
                }
                _ => None,
            },
        };
        let file = project
            .resolve_from(dir, &resolved.to_string_lossy())
            .map_err(|e| at(unreadable(PartMeshError::Path(e))))?;
        let mesh = cache
            .get_in(project, &file)
            .map_err(|e| at(unreadable(PartMeshError::Read(e))))?;
        files.push(file);
        // Counted before the copy is made.
        if mesh.triangles.len() > *left {
            return Err(at(over(Some(&m.uri), mesh.triangles.len(), *left)));
        }
        *left -= mesh.triangles.len();
        let [sx, sy, sz] = m.scale;
        let scaled = Mesh {
            vertices: mesh
                .vertices
                .iter()
                .map(|v| Point3::new(v.x * sx, v.y * sy, v.z * sz))
                .collect(),
            triangles: mesh.triangles.clone(),
        }
        .transformed(&m.origin);
        // Scale and origin are each in range, their product with the mesh may not be.
        let max = crate::math::MAX_ABS_VALUE;
        if let Some(v) = scaled
            .vertices
            .iter()
            .flat_map(|p| p.coords.iter())
            .find(|v| !v.is_finite() || v.abs() > max)
        {
            return Err(at(UrdfMeshProblem::Scaled {
                mesh: m.uri.clone(),
                scale: m.scale,
                reach: *v,
            }));
        }
        add(m.link, scaled);
    }
    Ok(UrdfLoaded {
        robot: u.robot,
        path,
        package_path: roots,
        meshes,
        files,
        warnings: u.warnings.iter().map(|w| w.to_string()).collect(),
    })
}

/// The part and component name of a URDF link's mesh: `<robot>:<link>` (`/` in the
/// names, which component names cannot hold, becomes `_`).
pub(super) fn urdf_component_name(robot: &str, link: &str) -> String {
    format!("{robot}:{link}").replace('/', "_")
}

/// Builds one robot of a file; `components` maps component names to indices; `urdf`
/// is the robot read from its `urdf:` file (see [`read_urdf_robot`]).
fn build(
    f: &RobotFile,
    components: &HashMap<String, usize>,
    urdf: Option<&UrdfLoaded>,
) -> Result<RobotInstance, (String, String)> {
    // Errors carry a needle to locate (a line of this robot) and the message.
    let whole = |m: String| (format!("name: {}", f.name), m);
    let sources = [f.catalog.is_some(), f.dh.is_some(), f.urdf.is_some()];
    if sources.iter().filter(|&&x| x).count() > 1 {
        return Err(whole(
            "give one of `catalog`, `dh` or `urdf`, not several".into(),
        ));
    }
    if let (Some(t), None) = (&f.tip, &f.urdf) {
        return Err((
            format!("tip: {t}"),
            "`tip` names the arm's last link of a `urdf:` robot; an explicit tree names `flange`"
                .into(),
        ));
    }
    let robot = kinematics_of(f, urdf)?;
    let links = link_displays(f, &robot, components, urdf)?;
    let dimensions = joint_dimensions(f, &robot)?;
    let joints = match &f.joints {
        None => vec![0.0; robot.dof()],
        Some(v) => {
            if v.len() != robot.dof() {
                return Err((
                    "joints:".into(),
                    format!(
                        "{} joint values given, the robot has {}",
                        v.len(),
                        robot.dof()
                    ),
                ));
            }
            joints_from_document(&robot, v)
        }
    };
    let inst = RobotInstance {
        robot: Arc::new(robot),
        links,
        joints,
        dimensions,
        file: RobotFile {
            base: None,
            tool: None,
            joints: None,
            ..f.clone()
        },
        urdf_files: urdf.map(|u| u.files.clone()).unwrap_or_default(),
        package_path: urdf.map(|u| u.package_path.clone()).unwrap_or_default(),
    };
    inst.check_joints(&inst.joints)
        .map_err(|m| ("joints:".to_string(), m.to_string()))?;
    Ok(inst)
}

/// The kinematics of a file's robot (catalog, D-H table, URDF or explicit tree), named
/// as the document names it, with its base and tool. Errors as [`build`]'s.
fn kinematics_of(f: &RobotFile, urdf: Option<&UrdfLoaded>) -> Result<Robot, (String, String)> {
    let whole = |m: String| (format!("name: {}", f.name), m);
    let mut robot = match (&f.catalog, &f.dh) {
        _ if f.urdf.is_some() => match urdf {
            Some(u) => u.robot.clone(),
            None => return Err(whole("the URDF was not read".into())),
        },
        (Some(_), Some(_)) => return Err(whole("give either `catalog` or `dh`, not both".into())),
        (Some(c), None) => robot_by_name(c).ok_or_else(|| {
            (
                format!("catalog: {c}"),
                format!(
                    "unknown catalog robot `{c}` ({})",
                    suggestion(c, crate::kinematics::catalog_names())
                ),
            )
        })?,
        (None, Some(dh)) => {
            dh_robot(&f.name, dh).map_err(|m| ("dh:".to_string(), m.to_string()))?
        }
        (None, None) => explicit_robot(f)?,
    };
    let robot_name = f.name.clone();
    // Catalog robots keep their catalog name in the kinematics; use the document's.
    if robot.name() != robot_name {
        robot = robot.with_name(robot_name.clone());
    }
    if let Some(t) = matrix(&f.base, "base").map_err(|m| ("base:".to_string(), m.to_string()))? {
        robot.set_base(t);
    }
    if let Some(t) = matrix(&f.tool, "tool").map_err(|m| ("tool:".to_string(), m.to_string()))? {
        robot.set_tool(t);
    }
    Ok(robot)
}

/// How each link of a file's robot is displayed: its component and the component's
/// offset in the link frame. Errors as [`build`]'s.
fn link_displays(
    f: &RobotFile,
    robot: &Robot,
    components: &HashMap<String, usize>,
    urdf: Option<&UrdfLoaded>,
) -> Result<Vec<LinkDisplay>, (String, String)> {
    let whole = |m: String| (format!("name: {}", f.name), m);
    let explicit = f.catalog.is_none() && f.dh.is_none() && f.urdf.is_none();
    let tree = robot.tree().clone();
    if f.links.len() > tree.len() {
        return Err(whole(format!(
            "{} links listed, the robot has {}",
            f.links.len(),
            tree.len()
        )));
    }
    let zero = tree
        .link_poses(&Transform::IDENTITY, &vec![0.0; tree.len()])
        .map_err(|e| whole(e.to_string()))?;
    let mut links = Vec::with_capacity(tree.len());
    for (i, link) in tree.links().iter().enumerate() {
        let lf = f.links.get(i).cloned().unwrap_or_default();
        let link_name = link.name.clone().unwrap_or_else(|| format!("link{i}"));
        let err = |m: String| {
            let needle = lf
                .component
                .as_ref()
                .map(|c| format!("component: {c}"))
                .unwrap_or_else(|| format!("name: {}", f.name));
            (needle, format!("link `{link_name}`: {m}"))
        };
        if !explicit {
            if lf.name.as_ref().is_some_and(|n| n != &link_name) {
                return Err(err(format!(
                    "is named `{link_name}` by the {} (link {i})",
                    if f.catalog.is_some() {
                        "catalog"
                    } else if f.urdf.is_some() {
                        "URDF"
                    } else {
                        "D-H table"
                    }
                )));
            }
            if lf.parent.is_some()
                || lf.joint.is_some()
                || lf.axis.is_some()
                || lf.point.is_some()
                || lf.home.is_some()
                || lf.limits.is_some()
            {
                return Err(err(
                    "parent, joint, axis, point, home and limits come from the catalog, D-H table or URDF"
                        .into(),
                ));
            }
        }
        let component = match &lf.component {
            // A URDF link with a mesh is displayed by its generated component.
            None => urdf
                .and_then(|u| u.meshes[i].as_ref())
                .and_then(|_| components.get(&urdf_component_name(&f.name, &link_name)))
                .copied(),
            Some(c) => Some(*components.get(c).ok_or_else(|| {
                err(format!(
                    "unknown component `{c}` ({})",
                    suggestion(c, components.keys().map(String::as_str))
                ))
            })?),
        };
        let offset = match matrix(&lf.offset, "offset").map_err(|e| err(e.to_string()))? {
            Some(t) => t,
            None if f.drawn_at_zero => zero[i].inverse(),
            None => Transform::IDENTITY,
        };
        links.push(LinkDisplay { component, offset });
    }
    Ok(links)
}

/// The dimension name of each joint of a file's robot (`角度<n>@<robot>` or
/// `距离<n>@<robot>` unless the link names one). Errors as [`build`]'s.
fn joint_dimensions(f: &RobotFile, robot: &Robot) -> Result<Vec<String>, (String, String)> {
    let whole = |m: String| (format!("name: {}", f.name), m);
    let mut dimensions = Vec::with_capacity(robot.dof());
    let kinds = robot.joint_kinds();
    for (j, &li) in robot.joint_links().iter().enumerate() {
        let name = match f.links.get(li).and_then(|l| l.dimension.clone()) {
            Some(d) => d,
            None if kinds[j] == JointKind::Prismatic => format!("距离{}@{}", j + 1, f.name),
            None => format!("角度{}@{}", j + 1, f.name),
        };
        if name.is_empty() {
            return Err(whole(format!("joint {}: empty dimension name", j + 1)));
        }
        dimensions.push(name);
    }
    for (i, lf) in f.links.iter().enumerate() {
        if lf.dimension.is_some() && !robot.joint_links().contains(&i) {
            return Err((
                format!("dimension: {}", lf.dimension.clone().unwrap_or_default()),
                format!(
                    "link {i} is not a joint of the arm (fixed, or off the flange chain): it has no dimension"
                ),
            ));
        }
    }
    Ok(dimensions)
}

/// The explicit-tree file form of `robot` (links, axes, homes, limits, flange, base,
/// tool), named `name`: how a robot built in code is written to a document.
fn explicit_file(name: &str, robot: &Robot) -> RobotFile {
    let tree = robot.tree();
    let link_name = |i: usize| {
        tree.links()[i]
            .name
            .clone()
            .filter(|n| !n.is_empty())
            .unwrap_or_else(|| format!("link{i}"))
    };
    let links = tree
        .links()
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let kind = l.joint.kind;
            let a = |v: Vec3| [v.x, v.y, v.z];
            LinkFile {
                name: Some(link_name(i)),
                component: None,
                offset: None,
                parent: l.parent.map(link_name),
                joint: match kind {
                    JointKind::Fixed => None,
                    JointKind::Revolute => Some("revolute".into()),
                    JointKind::Prismatic => Some("prismatic".into()),
                },
                axis: kind.is_movable().then(|| a(l.joint.axis)),
                point: (kind == JointKind::Revolute).then(|| a(l.joint.point.coords)),
                home: (l.home != Transform::IDENTITY).then(|| l.home.to_matrix()),
                limits: l.joint.limits.map(|lim| match kind {
                    JointKind::Prismatic => [lim.min, lim.max],
                    _ => [lim.min.to_degrees(), lim.max.to_degrees()],
                }),
                dimension: None,
            }
        })
        .collect();
    RobotFile {
        name: name.to_string(),
        catalog: None,
        dh: None,
        urdf: None,
        package_path: Vec::new(),
        base: Some(robot.base().to_matrix()),
        tool: Some(robot.tool().to_matrix()),
        flange: Some(link_name(robot.flange())),
        tip: None,
        drawn_at_zero: false,
        links,
        joints: None,
    }
}

/// Builds the robots of a document file. `taken` holds the mate dimension names
/// (feature part, without `D1@`); `nested` the robots its sub-documents brought
/// (their names, dimensions and link components taken too); errors are located in
/// `text`.
pub(super) fn load(
    files: &[RobotFile],
    components: &HashMap<String, usize>,
    urdf: &HashMap<String, UrdfLoaded>,
    taken: &HashSet<String>,
    nested: &[RobotInstance],
    text: &str,
    path: &Path,
) -> Result<Vec<RobotInstance>, DocumentError> {
    let section = locate(text, "robots:", 1).map(|l| l.0).unwrap_or(1);
    let mut names: HashSet<String> = nested.iter().map(|r| r.name().to_string()).collect();
    let mut dims: HashSet<String> = taken.clone();
    dims.extend(nested.iter().flat_map(|r| r.dimensions.iter().cloned()));
    let mut shown: HashMap<usize, String> = nested
        .iter()
        .flat_map(|r| {
            r.links
                .iter()
                .filter_map(|l| l.component.map(|c| (c, r.name().to_string())))
        })
        .collect();
    let mut out = Vec::with_capacity(files.len());
    for f in files {
        let from = locate(text, &format!("name: {}", f.name), section)
            .map(|l| l.0)
            .unwrap_or(section);
        let at = |needle: &str, message: String| -> DocumentError {
            let (line, col) = locate(text, needle, from).unwrap_or((from, 1));
            SourceError::new(path, line, col, format!("robot `{}`: {message}", f.name)).into()
        };
        if f.name.is_empty() || !names.insert(f.name.clone()) {
            return Err(at(
                "name:",
                "robot names must be unique and non-empty".into(),
            ));
        }
        let inst = build(f, components, urdf.get(&f.name)).map_err(|(n, m)| at(&n, m))?;
        for d in &inst.dimensions {
            if !dims.insert(d.clone()) {
                return Err(at(
                    d,
                    format!(
                        "duplicate dimension name `D1@{d}` (mates and joints share one namespace)"
                    ),
                ));
            }
        }
        for l in &inst.links {
            if let Some(c) = l.component {
                if let Some(other) = shown.insert(c, f.name.clone()) {
                    let cname = components
                        .iter()
                        .find(|(_, &i)| i == c)
                        .map(|(n, _)| n.clone())
                        .unwrap_or_default();
                    return Err(at(
                        &format!("component: {cname}"),
                        format!("component `{cname}` already displays a link of robot `{other}`"),
                    ));
                }
            }
        }
        out.push(inst);
    }
    Ok(out)
}

impl Document {
    /// The robots, in file order.
    pub fn robots(&self) -> &[RobotInstance] {
        &self.robots
    }

    /// The index of a robot, or an error listing close matches.
    pub fn robot_index(&self, name: &str) -> Result<usize, DocumentError> {
        let nfc = super::nfc_name(name);
        self.robots
            .iter()
            .position(|r| r.name() == nfc)
            .ok_or_else(|| {
                DocumentError::not_found("robot", name, self.robots.iter().map(|r| r.name()))
            })
    }

    /// A robot by name.
    pub fn robot(&self, name: &str) -> Result<&RobotInstance, DocumentError> {
        Ok(&self.robots[self.robot_index(name)?])
    }

    /// A robot by index, or [`DocumentError::NotFound`].
    pub fn robot_at(&self, index: usize) -> Result<&RobotInstance, DocumentError> {
        self.robots
            .get(index)
            .ok_or_else(|| DocumentError::NotFound {
                what: "robot",
                name: format!("#{index}"),
                hint: format!("the document has {} robots", self.robots.len()),
            })
    }

    /// The robot of `file` built (see [`build`]) for this document, refused when
    /// one of its joint dimensions is a dimension the document already has.
    fn build_new_robot(
        &self,
        file: &RobotFile,
        components: &HashMap<String, usize>,
        urdf: Option<&UrdfLoaded>,
    ) -> Result<RobotInstance, DocumentError> {
        let inst = build(file, components, urdf).map_err(|(_, reason)| {
            DocumentError::RobotDefinition {
                robot: file.name.clone(),
                reason,
            }
        })?;
        let taken = self.dimensions();
        if let Some(d) = inst
            .dimension_names()
            .into_iter()
            .find(|d| taken.contains(d))
        {
            return Err(DocumentError::DimensionTaken {
                robot: file.name.clone().into(),
                dimension: d.into(),
            });
        }
        Ok(inst)
    }

    /// Adds a robot built in code (catalog, [`OpwParameters`](crate::kinematics::OpwParameters),
    /// D-H table, URDF, explicit tree) under `name`, its root placed at `base` (world
    /// pose, mm; the robot's own base when `None`). It displays no components; its
    /// joints start at 0 (clamped into the limits) and get driving dimensions
    /// `角度<n>@<name>` / `距离<n>@<name>`. Saving writes it as an explicit tree.
    /// Returns its index.
    pub fn add_robot(
        &mut self,
        name: &str,
        robot: &Robot,
        base: Option<Transform>,
    ) -> Result<usize, DocumentError> {
        let name = super::new_name(name, "robot")?;
        let name = name.as_str();
        let base = base.unwrap_or(robot.base());
        self.check_new_robot(name, &base)?;
        let mut file = explicit_file(name, robot);
        file.base = Some(base.to_matrix());
        let zero: Vec<f64> = robot
            .joint_limits()
            .iter()
            .map(|l| l.map_or(0.0, |l| 0.0f64.clamp(l.min, l.max)))
            .collect();
        file.joints = Some(joints_to_document(robot, &zero));
        let mut inst = self.build_new_robot(&file, &HashMap::new(), None)?;
        Arc::make_mut(&mut inst.robot).set_limits_source(robot.limits_source().map(String::from));
        self.robots.push(inst);
        self.revision += 1;
        Ok(self.robots.len() - 1)
    }

    /// Refuses a new robot's `name` (empty, taken, or inside a sub-document) and a
    /// `base` pose that is not finite.
    fn check_new_robot(&self, name: &str, base: &Transform) -> Result<(), DocumentError> {
        if name.is_empty() || self.robots.iter().any(|r| r.name() == name) {
            return Err(DocumentError::RobotName(name.into()));
        }
        if let Some(a) = self.owning_sub_document(name) {
            return Err(DocumentError::RobotInSubDocument {
                robot: name.to_string(),
                at: a.name.clone(),
            });
        }
        if !base.is_finite() {
            return Err(RobotError::NonFinite {
                robot: name.to_string(),
                what: "base",
            }
            .into());
        }
        Ok(())
    }

    /// Adds the robot of the URDF file `urdf` (a path inside the document's project)
    /// under `name`, as a `urdf:` entry (saved as the URDF's path relative to the
    /// document): its links' STL meshes become components `<name>:<link>` that follow
    /// the links (shown and checked for interference like any component), its root at
    /// `base` (world pose, mm; identity when `None`). Joints start at 0 (clamped into
    /// the limits). Mesh rules as for a document's `urdf:` entry
    /// (see `docs/robots.md`). `package_path`: folders inside the project where
    /// `package://NAME/…` meshes of other packages are looked for (each folder itself
    /// when it is named NAME, else its child NAME), as a document's `package_path:`
    /// (saved relative to the document); an arm and a gripper from two packages load
    /// this way. Nothing changes on error. Returns the robot's index.
    pub fn add_urdf_robot(
        &mut self,
        name: &str,
        urdf: &Path,
        base: Option<Transform>,
        package_path: &[&Path],
    ) -> Result<usize, DocumentError> {
        let name = super::new_name(name, "robot")?;
        let name = name.as_str();
        let invalid = |source| DocumentError::Urdf {
            robot: name.into(),
            source: Box::new(source),
        };
        let base = base.unwrap_or(Transform::IDENTITY);
        self.check_new_robot(name, &base)?;
        let project = Project::for_file(&self.path)
            .or_else(|e| {
                crate::project::unless_missing(e, self.path.parent().unwrap_or(Path::new(".")))
            })
            .map_err(|e| invalid(UrdfRobotError::Project(e.into())))?;
        let dir = std::path::absolute(&self.path)
            .ok()
            .and_then(|p| p.parent().and_then(|d| d.canonicalize().ok()))
            .unwrap_or_else(|| project.root().to_path_buf());
        let relative = |p: &Path| {
            crate::fsutil::relative_path(p, &dir)
                .unwrap_or_else(|| p.to_string_lossy().into_owned())
        };
        let uri = relative(urdf);
        let packages: Vec<String> = package_path.iter().map(|p| relative(p)).collect();
        // The document's URDF robots share one count (MAX_URDF_TRIANGLES).
        let mut left = MAX_URDF_TRIANGLES.saturating_sub(self.generated_triangles());
        let loaded = read_urdf_robot(
            &project,
            &dir,
            &uri,
            &packages,
            None,
            &mut MeshCache::new(),
            &mut left,
        )
        .map_err(invalid)?;
        let mut next = self.clone();
        next.add_urdf_parts(name, &uri, &loaded).map_err(invalid)?;
        let zero: Vec<f64> = loaded
            .robot
            .joint_limits()
            .iter()
            .map(|l| l.map_or(0.0, |l| 0.0f64.clamp(l.min, l.max)))
            .collect();
        let file = RobotFile {
            name: name.to_string(),
            catalog: None,
            dh: None,
            urdf: Some(uri),
            package_path: packages,
            base: Some(base.to_matrix()),
            tool: None,
            flange: None,
            tip: None,
            drawn_at_zero: false,
            links: Vec::new(),
            joints: Some(joints_to_document(&loaded.robot, &zero)),
        };
        let inst = next.build_new_robot(&file, &next.by_name, Some(&loaded))?;
        next.robots.push(inst);
        next.apply_robots();
        next.revision += 1;
        *self = next;
        Ok(self.robots.len() - 1)
    }

    /// Sets a robot's joints (rad / mm, joint order) and moves its link components.
    /// Values outside the limits, of the wrong count or not finite are refused and
    /// nothing changes; so is a new value for a joint whose dimension an equation
    /// drives ([`DocumentError::DrivenByEquation`], naming the equation, as SolidWorks
    /// refuses to edit a driven dimension): change the equation instead.
    pub fn set_robot_joints(&mut self, robot: usize, q: &[f64]) -> Result<(), DocumentError> {
        let r = self.robot_at(robot)?;
        for (j, name) in r.dimension_names().iter().enumerate() {
            let (Some(&new), Some(&now)) = (q.get(j), r.joints.get(j)) else {
                break; // the count is checked below
            };
            if new == now {
                continue;
            }
            if let Some(index) = self.driving_equation(name) {
                return Err(DocumentError::DrivenByEquation {
                    dimension: name.clone(),
                    joint: Some(format!("joint {} of robot `{}`", j + 1, r.name())),
                    index,
                    equation: super::equations::shown(&self.equations[index].text()),
                });
            }
        }
        self.move_robot_joints(robot, q)
    }

    /// [`Self::set_robot_joints`] without the equation check: how equations set the
    /// joints they drive.
    pub(crate) fn move_robot_joints(
        &mut self,
        robot: usize,
        q: &[f64],
    ) -> Result<(), DocumentError> {
        let r = self.robot_at(robot)?;
        r.check_joints(q)?;
        let poses = r.component_poses(q)?;
        self.robots[robot].joints = q.to_vec();
        for (c, p) in poses {
            self.components[c].transform = p;
        }
        self.revision += 1;
        Ok(())
    }

    /// Moves a robot's base (world pose of its root, mm) and its link components.
    pub fn set_robot_base(&mut self, robot: usize, base: Transform) -> Result<(), DocumentError> {
        self.check_robot_frame(robot, &base, "base", "the base pose")?;
        let r = &mut self.robots[robot];
        Arc::make_mut(&mut r.robot).set_base(base);
        let q = r.joints.clone();
        self.set_robot_joints(robot, &q)
    }

    /// Sets a robot's tool frame (TCP in the flange frame, mm).
    pub fn set_robot_tool(&mut self, robot: usize, tool: Transform) -> Result<(), DocumentError> {
        self.check_robot_frame(robot, &tool, "tool", "the tool frame")?;
        let r = &mut self.robots[robot];
        Arc::make_mut(&mut r.robot).set_tool(tool);
        self.revision += 1;
        Ok(())
    }

    /// Refuses a base or tool `frame` (`what`) for robot `robot` that is not finite
    /// (a robot error) or beyond the document's range (as any pose, `described`).
    fn check_robot_frame(
        &self,
        robot: usize,
        frame: &Transform,
        what: &'static str,
        described: &str,
    ) -> Result<(), DocumentError> {
        let name = self.robot_at(robot)?.name().to_string();
        if !frame.is_finite() {
            return Err(RobotError::NonFinite { robot: name, what }.into());
        }
        super::check_pose(frame, described)
    }

    /// Runs a motion program on a robot from its current joints; on success the robot
    /// (and its link components) ends where the program ends. Errors name the program
    /// file and line (`file:line: cause`).
    pub fn run_robot_program(
        &mut self,
        robot: usize,
        program: &Program,
        options: &MotionOptions,
    ) -> Result<Trajectory, DocumentError> {
        let r = self.robot_at(robot)?;
        let t = run_program(program, &r.robot, &r.joints, options).map_err(|source| {
            RobotError::Program {
                robot: r.name().to_string(),
                source: Box::new(source),
            }
        })?;
        if let Some(q) = t.last_joints() {
            let q = q.to_vec();
            self.set_robot_joints(robot, &q)?;
        }
        Ok(t)
    }

    /// Moves the bases of the robots named inside `prefix` (`Cell-1/`) by `motion`
    /// (world → world, mm) and places their links: a sub-assembly moved rigidly.
    pub(super) fn move_robots_inside(&mut self, prefix: &str, motion: Transform) {
        let mut moved = false;
        for r in &mut self.robots {
            if r.name().starts_with(prefix) {
                let base = r.robot.base() * motion;
                Arc::make_mut(&mut r.robot).set_base(base);
                moved = true;
            }
        }
        if moved {
            self.apply_robots();
        }
    }

    /// Whether a component is moved by a robot link (the mate solver then treats it as
    /// fixed).
    pub fn is_robot_driven(&self, component: usize) -> bool {
        self.driving_robot(component).is_some()
    }

    /// The name of the robot whose link a component displays.
    pub fn driving_robot(&self, component: usize) -> Option<&str> {
        self.robots
            .iter()
            .find(|r| r.links.iter().any(|l| l.component == Some(component)))
            .map(|r| r.name())
    }

    /// After component `removed` left the document: the later components' indices
    /// in the robots' links shift down by one.
    pub(super) fn shift_robot_links(&mut self, removed: usize) {
        for r in &mut self.robots {
            for l in &mut r.links {
                if let Some(c) = &mut l.component {
                    if *c > removed {
                        *c -= 1;
                    }
                }
            }
        }
    }

    /// Places every robot link component at its robot's current joints.
    pub(super) fn apply_robots(&mut self) {
        for r in &self.robots {
            if let Ok(poses) = r.component_poses(&r.joints) {
                for (c, p) in poses {
                    self.components[c].transform = p;
                }
            }
        }
    }

    /// Per component: whether the mate solver must keep it in place (fixed by the user
    /// or driven by a robot).
    pub(super) fn solver_fixed(&self) -> Vec<bool> {
        (0..self.components.len())
            .map(|i| self.components[i].fixed || self.is_robot_driven(i))
            .collect()
    }

    /// The dimension target of a robot joint feature name (without `D1@`).
    pub(super) fn robot_dimension(&self, feature: &str) -> Option<dimension::DimensionTarget> {
        self.robots.iter().enumerate().find_map(|(ri, r)| {
            r.dimensions.iter().position(|d| d == feature).map(|j| {
                dimension::DimensionTarget::Joint {
                    robot: ri,
                    joint: j,
                }
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::document::file::{DhRowFile, LinkFile};
    use crate::kinematics::Catalog;

    fn row(theta: f64, d: f64, a: f64, alpha: f64) -> DhRowFile {
        DhRowFile {
            theta,
            d,
            a,
            alpha,
            joint: None,
            limits: None,
        }
    }

    /// In-place and allocating unit conversions agree and invert each other.
    #[test]
    fn joint_unit_conversions_invert_each_other() {
        let robot = Catalog::NachiMz07.robot();
        let start: Vec<f64> = [10.0f64, -20.0, 30.0, 40.0, -50.0, 60.0]
            .iter()
            .map(|v| v.to_radians())
            .collect();
        let deg = joints_to_document(&robot, &start);
        let mut back = deg.clone();
        joints_from_document_in_place(&robot, &mut back);
        assert_eq!(back, joints_from_document(&robot, &deg));
        for (a, b) in back.iter().zip(&start) {
            assert!((a - b).abs() < 1e-12);
        }
    }

    /// Seed 000's table 2 written as a D-H table in the file (flange at 80 mm, as the
    /// catalog models it) gives the catalog's flange poses.
    #[test]
    fn dh_rows_in_degrees_match_the_catalog() {
        let dh = DhFile {
            convention: None,
            rows: vec![
                row(0.0, 340.0, 50.0, 90.0),
                row(90.0, 0.0, 330.0, 0.0),
                row(0.0, 0.0, 45.0, 90.0),
                row(0.0, 340.0, 0.0, 90.0),
                row(90.0, 0.0, 0.0, 90.0),
                row(0.0, -80.0, 0.0, 0.0),
            ],
        };
        let r = dh_robot("t", &dh).unwrap();
        let c = Catalog::NachiMz07.robot();
        let q = [0.1, -0.2, 0.3, -0.4, 0.5, -0.6];
        assert!(r
            .flange_pose(&q)
            .unwrap()
            .approx_eq(&c.flange_pose(&q).unwrap(), 1e-9, 1e-12));
        let bad = DhFile {
            convention: Some("craig".into()),
            rows: vec![],
        };
        assert!(matches!(
            dh_robot("t", &bad),
            Err(EntryError::DhConvention(_))
        ));
    }

    #[test]
    fn limits_are_checked_and_converted() {
        assert!(matches!(
            limits(Some([10.0, -10.0]), JointKind::Revolute),
            Err(EntryError::LimitsInverted { .. })
        ));
        assert!(matches!(
            limits(Some([f64::NAN, 1.0]), JointKind::Revolute),
            Err(EntryError::LimitsNotFinite { .. })
        ));
        let l = limits(Some([-90.0, 45.0]), JointKind::Revolute)
            .unwrap()
            .unwrap();
        assert!((l.min + std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        let p = limits(Some([0.0, 500.0]), JointKind::Prismatic)
            .unwrap()
            .unwrap();
        assert_eq!((p.min, p.max), (0.0, 500.0));
    }

    /// `drawn_at_zero` offsets put every link component at the base pose when the
    /// joints are 0, and a component follows `offset · link pose` otherwise.
    #[test]
    fn drawn_at_zero_offsets() {
        let f = RobotFile {
            name: "r".into(),
            catalog: Some("nachi_mz07".into()),
            dh: None,
            urdf: None,
            package_path: Vec::new(),
            base: Some(Transform::from_translation(Vec3::new(100.0, 0.0, 50.0)).to_matrix()),
            tool: None,
            flange: None,
            tip: None,
            drawn_at_zero: true,
            links: (0..7)
                .map(|i| LinkFile {
                    component: Some(format!("c{i}")),
                    ..LinkFile::default()
                })
                .collect(),
            joints: None,
        };
        let components: HashMap<String, usize> = (0..7).map(|i| (format!("c{i}"), i)).collect();
        let inst = build(&f, &components, None).unwrap();
        let base = inst.robot().base();
        for (_, p) in inst.component_poses(&[0.0; 6]).unwrap() {
            assert!(p.approx_eq(&base, 1e-9, 1e-12));
        }
        let q = [0.3, -0.2, 0.1, 0.4, -0.5, 0.6];
        let links = inst.robot().link_poses(&q).unwrap();
        for (c, p) in inst.component_poses(&q).unwrap() {
            assert!(p.approx_eq(&(inst.links()[c].offset * links[c]), 1e-9, 1e-12));
        }
        assert_eq!(inst.dimension_features()[0], "角度1@r");
        // Joint values outside the limits are refused with the joint named in degrees.
        let msg = inst
            .check_joints(&[0.0, 0.0, 0.0, 0.0, 2.5, 0.0])
            .unwrap_err()
            .to_string();
        assert!(msg.contains("joint 5") && msg.contains("143.2394"), "{msg}");
    }
}
