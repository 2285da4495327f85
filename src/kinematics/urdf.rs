//! URDF import: a ROS robot description (xacro already expanded) as a [`Robot`].
//!
//! # Conventions
//! URDF lengths are **metres**; fitup multiplies them by 1000 (mm). A joint's
//! `<origin xyz rpy>` places the child link frame in the parent link frame at joint
//! value 0 (`rpy`: roll about X, pitch about Y, yaw about Z, fixed axes, i.e.
//! `R = Rz(yaw)·Ry(pitch)·Rx(roll)`); `<axis xyz>` (default `1 0 0`) is in the child
//! frame. fitup stores the same joint as a home transform (the origin) and an axis
//! line in the parent frame (`R_origin·axis` through the origin's position), which
//! gives the identical motion. Joint types: `revolute` and `continuous` (rad;
//! `continuous` has no limits), `prismatic` (limits ×1000, mm), `fixed`; `floating` and
//! `planar` are refused. `<mimic joint multiplier offset>` makes a joint follow its
//! leader ([`crate::kinematics::Mimic`]): it is not a free joint. The robot's flange is
//! the last link of the serial arm unless a tip link is named: the most free joints
//! on links not moved by a mimic joint or a mimic's leader (a gripper's fingers), a
//! link that does not carry such fingers before one that does, then the deepest (e.g.
//! a fixed `tool0`); the tool is the identity. When the chain is an OPW arm the closed-form solver is
//! chosen from the geometry (see [`Robot::analytic`]).
//!
//! Geometry: a link's `<visual>` elements when fitup reads all their meshes (STL, OBJ,
//! PLY, glTF), else its `<collision>` elements when it reads those, else what it reads
//! of either, each mesh left out a warning in [`UrdfRobot::warnings`]. Mesh files are
//! listed in [`UrdfRobot::meshes`] (with the origin and scale); `<box>`, `<cylinder>`
//! and `<sphere>` are meshed into [`UrdfRobot::primitives`]; `package://PKG/rest` URIs resolve to
//! `rest` inside the folder named `PKG`: the URDF's own package, one on a package path,
//! or one beside or above the URDF (an arm and a gripper from two packages), else the
//! URDF's own package folder (ROS-Industrial support packages keep `urdf/` and
//! `meshes/` side by side: a URDF in `PKG/urdf/` resolves `package://PKG/meshes/x.stl`
//! to `PKG/meshes/x.stl` — see [`resolve_mesh_in`] and [`resolve_mesh`]).
//!
//! Errors are [`SourceError`]s naming the file, line and column.

use super::{Joint, JointLimits, KinematicTree, Link, Mimic, Robot};
use crate::diagnostics::SourceError;
use crate::math::{Point3, Transform, Vec3};
use crate::mesh::{Mesh, MeshFormat};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use std::collections::HashMap;
use std::path::Path;

mod packages;
pub use packages::{resolve_mesh, resolve_mesh_in, PackageFound};

/// Largest URDF accepted (bytes): real descriptions are well under a megabyte.
pub const MAX_URDF_BYTES: usize = 8 << 20;

/// A visual mesh of a link.
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfMesh {
    /// Index of the link in the robot's tree.
    pub link: usize,
    /// The `filename` attribute as written (`package://…`, relative or absolute).
    pub uri: String,
    /// Pose of the mesh in the link frame (mm).
    pub origin: Transform,
    /// Scale from the `scale` attribute times 1000 (metres → mm) per axis.
    pub scale: [f64; 3],
    /// Line of the `<mesh>` element in the URDF (for messages).
    pub line: usize,
}

/// A `<box>`, `<cylinder>` or `<sphere>` geometry of a link, meshed.
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfPrimitive {
    /// Index of the link in the robot's tree.
    pub link: usize,
    /// `box`, `cylinder` or `sphere`.
    pub shape: String,
    /// The closed mesh in the link frame (mm), placed by the geometry's origin.
    pub mesh: Mesh,
    /// Line of the shape's element in the URDF.
    pub line: usize,
}

/// A robot read from a URDF, with its link geometry.
#[derive(Debug, Clone)]
pub struct UrdfRobot {
    /// The kinematics (mm, rad).
    pub robot: Robot,
    /// Mesh files per link, in file order (see the module docs for which geometry).
    pub meshes: Vec<UrdfMesh>,
    /// Primitive shapes per link, meshed, in file order.
    pub primitives: Vec<UrdfPrimitive>,
    /// Located warnings: meshes left out (a `.dae` without a readable collision mesh).
    pub warnings: Vec<SourceError>,
}

/// Parses URDF text; `path` names the file in errors (and is not read); `tip` names
/// the flange link (default: see the module docs).
///
/// # Examples
/// ```
/// use fitup::kinematics::parse_urdf;
/// let urdf = r#"<robot name="r">
///   <link name="base"/><link name="arm"/>
///   <joint name="j1" type="revolute">
///     <origin xyz="0 0 0.5"/><parent link="base"/><child link="arm"/>
///     <axis xyz="0 0 1"/><limit lower="-1" upper="1"/>
///   </joint>
/// </robot>"#;
/// let r = parse_urdf(std::path::Path::new("r.urdf"), urdf, None).unwrap().robot;
/// assert_eq!(r.dof(), 1);
/// assert!((r.tcp_pose(&[0.3]).unwrap().translation().z - 500.0).abs() < 1e-9); // mm
/// ```
pub fn parse_urdf(path: &Path, text: &str, tip: Option<&str>) -> Result<UrdfRobot, SourceError> {
    let whole = |m: String| SourceError::new(path, 1, 1, m);
    if text.len() > MAX_URDF_BYTES {
        return Err(whole(format!(
            "{} bytes: larger than the {MAX_URDF_BYTES}-byte limit for a URDF",
            text.len()
        )));
    }
    let doc = roxmltree::Document::parse(text).map_err(|e| {
        let p = e.pos();
        SourceError::new(
            path,
            p.row as usize,
            p.col as usize,
            format!("not valid XML: {e}"),
        )
    })?;
    let at = |node: roxmltree::Node, m: String| {
        let p = doc.text_pos_at(node.range().start);
        SourceError::new(path, p.row as usize, p.col as usize, m)
    };
    let root = doc.root_element();
    if root.tag_name().name() != "robot" {
        return Err(at(
            root,
            format!(
                "the root element is <{}>, not <robot>",
                root.tag_name().name()
            ),
        ));
    }
    // The robot's name follows the one name rule too (it is the robot's `name`).
    let raw = root.attribute("name").unwrap_or("urdf");
    let name = crate::diagnostics::checked_name(raw)
        .map_err(|c| at(root, hidden_in_name("robot", raw, c)))?
        .into_owned();
    // Links, in file order.
    let mut link_nodes = Vec::new();
    let mut link_index: HashMap<String, usize> = HashMap::new();
    for n in root.children().filter(|n| n.has_tag_name("link")) {
        let raw = n
            .attribute("name")
            .ok_or_else(|| at(n, "<link> without a name".into()))?;
        // The one name rule (documents' too): no control or invisible character, and
        // kept in NFC, so `café` composed and decomposed are one link (a twin is
        // defined twice) and either spelling reaches it.
        let ln = crate::diagnostics::checked_name(raw)
            .map_err(|c| at(n, hidden_in_name("link", raw, c)))?
            .into_owned();
        if link_index.contains_key(ln.as_str()) {
            return Err(at(
                n,
                format!("link `{ln}` is defined twice (names are compared in Unicode NFC)"),
            ));
        }
        link_index.insert(ln, link_nodes.len());
        link_nodes.push(n);
    }
    if link_nodes.is_empty() {
        return Err(at(root, "the robot has no <link>".into()));
    }
    // Joints: child link → (joint node, parent link, kind, origin, axis, limits).
    struct J<'a> {
        node: roxmltree::Node<'a, 'a>,
        parent: usize,
        joint: Joint,
        home: Transform,
    }
    impl JointOf for J<'_> {
        fn movable(&self) -> bool {
            self.joint.kind.is_movable()
        }
        fn prismatic(&self) -> bool {
            self.joint.kind == super::JointKind::Prismatic
        }
    }
    let mut parent_of: HashMap<usize, J> = HashMap::new();
    // Joint name → child link (file order), and the `<mimic>` elements to resolve.
    let mut joint_child: HashMap<String, usize> = HashMap::new();
    let mut mimic_nodes: Vec<(usize, roxmltree::Node)> = Vec::new();
    for n in root.children().filter(|n| n.has_tag_name("joint")) {
        let raw = n.attribute("name").unwrap_or("");
        let jn = crate::diagnostics::checked_name(raw)
            .map_err(|c| at(n, hidden_in_name("joint", raw, c)))?
            .into_owned();
        let jn = jn.as_str();
        let err = |node: roxmltree::Node, m: String| at(node, format!("joint `{jn}`: {m}"));
        let link_ref = |tag: &str| -> Result<usize, SourceError> {
            let e = n
                .children()
                .find(|c| c.has_tag_name(tag))
                .ok_or_else(|| err(n, format!("no <{tag}>")))?;
            let l = e
                .attribute("link")
                .ok_or_else(|| err(e, format!("<{tag}> without a link")))?;
            link_index
                .get(crate::diagnostics::nfc(l).as_ref())
                .copied()
                .ok_or_else(|| err(e, format!("{tag} link `{l}` is not defined")))
        };
        let (parent, child) = (link_ref("parent")?, link_ref("child")?);
        let numbers = |node: roxmltree::Node, attr: &str, default: [f64; 3], unit: f64| {
            attribute_numbers(&doc, path, node, attr, default, unit).map_err(|mut e| {
                e.message = format!("joint `{jn}`: {}", e.message);
                e
            })
        };
        let home = match n.children().find(|c| c.has_tag_name("origin")) {
            Some(o) => origin(
                numbers(o, "xyz", [0.0; 3], 1000.0)?,
                numbers(o, "rpy", [0.0; 3], 1.0)?,
            ),
            None => Transform::IDENTITY,
        };
        let axis_node = n.children().find(|c| c.has_tag_name("axis"));
        let axis = match axis_node {
            Some(a) => numbers(a, "xyz", [1.0, 0.0, 0.0], 1.0)?,
            None => [1.0, 0.0, 0.0],
        };
        let axis = home.isometry().rotation * Vec3::new(axis[0], axis[1], axis[2]);
        let kind = n.attribute("type").unwrap_or("");
        let limit = n.children().find(|c| c.has_tag_name("limit"));
        let bound = |attr: &str, scale: f64| -> Result<Option<f64>, SourceError> {
            let Some(l) = limit else { return Ok(None) };
            if l.attribute(attr).is_none() {
                return Ok(None);
            }
            let [v] = attribute_numbers(&doc, path, l, attr, [0.0], scale).map_err(|mut e| {
                e.message = format!("joint `{jn}`: {}", e.message);
                e
            })?;
            Ok(Some(v * scale))
        };
        let limits = |scale: f64| -> Result<Option<JointLimits>, SourceError> {
            match (bound("lower", scale)?, bound("upper", scale)?) {
                (None, None) => Ok(None),
                (lo, hi) => {
                    let (lo, hi) = (lo.unwrap_or(0.0), hi.unwrap_or(0.0));
                    if lo > hi {
                        return Err(err(limit.unwrap_or(n), format!("lower {lo} > upper {hi}")));
                    }
                    // URDF writes lower = upper = 0 for "no limits given".
                    Ok((lo < hi).then(|| JointLimits::new(lo, hi)))
                }
            }
        };
        if axis.norm() < 1e-12 && matches!(kind, "revolute" | "continuous" | "prismatic") {
            return Err(err(
                axis_node.unwrap_or(n),
                "the axis has zero length".into(),
            ));
        }
        let origin_point = Point3::from(home.translation());
        let joint = match kind {
            "fixed" => Joint::fixed(),
            "revolute" => {
                let mut j = Joint::revolute(axis, origin_point);
                j.limits = limits(1.0)?;
                j
            }
            "continuous" => Joint::revolute(axis, origin_point),
            "prismatic" => {
                let mut j = Joint::prismatic(axis);
                j.limits = limits(1000.0)?;
                j
            }
            other => {
                return Err(err(n, format!("joint type `{other}` is not supported (revolute, continuous, prismatic, fixed)")))
            }
        };
        if parent == child {
            return Err(err(n, "a link cannot be its own parent".into()));
        }
        if let Some(prev) = parent_of.get(&child) {
            let p = doc.text_pos_at(prev.node.range().start);
            return Err(err(
                n,
                format!(
                    "link `{}` already has a parent joint (line {}): a URDF is a tree",
                    link_name(link_nodes[child]),
                    p.row
                ),
            ));
        }
        joint_child.entry(jn.to_string()).or_insert(child);
        if let Some(m) = n.children().find(|c| c.has_tag_name("mimic")) {
            mimic_nodes.push((child, m));
        }
        parent_of.insert(
            child,
            J {
                node: n,
                parent,
                joint,
                home,
            },
        );
    }
    let roots: Vec<usize> = (0..link_nodes.len())
        .filter(|i| !parent_of.contains_key(i))
        .collect();
    match roots.len() {
        0 => {
            return Err(at(
                root,
                "every link has a parent: the joints form a cycle".into(),
            ))
        }
        1 => {}
        _ => {
            return Err(at(
                link_nodes[roots[1]],
                format!(
                    "two root links (`{}` and `{}`): every link but one needs a parent joint",
                    link_name(link_nodes[roots[0]]),
                    link_name(link_nodes[roots[1]])
                ),
            ))
        }
    }
    // Order parents first (breadth-first from the root); links not reached sit on a cycle.
    let mut children: HashMap<usize, Vec<usize>> = HashMap::new();
    for (&c, j) in &parent_of {
        children.entry(j.parent).or_default().push(c);
    }
    for v in children.values_mut() {
        v.sort_unstable();
    }
    let mut order = vec![roots[0]];
    let mut k = 0;
    while k < order.len() {
        if let Some(cs) = children.get(&order[k]) {
            order.extend(cs);
        }
        k += 1;
    }
    if order.len() != link_nodes.len() {
        let lost = (0..link_nodes.len())
            .find(|i| !order.contains(i))
            .unwrap_or(0);
        return Err(at(
            link_nodes[lost],
            format!(
                "link `{}` is on a cycle of joints, not connected to the root",
                link_name(link_nodes[lost])
            ),
        ));
    }
    let new_index: HashMap<usize, usize> = order.iter().enumerate().map(|(i, &l)| (l, i)).collect();
    let mimics = mimics(
        &doc,
        path,
        &mimic_nodes,
        &joint_child,
        &parent_of,
        &new_index,
        &link_nodes,
    )?;
    let follower: HashMap<usize, Mimic> = mimics.iter().copied().collect();
    let leaders: std::collections::HashSet<usize> = mimics.iter().map(|(_, m)| m.leader).collect();
    let mut links = Vec::with_capacity(order.len());
    // Per link (new order): free joints above and at it (mimic joints do not count),
    // depth, whether a follower moves it, and whether its last free joint leads a
    // mimic (a gripper's driving finger: the hand, not the arm).
    let mut free_depth = vec![0usize; order.len()];
    let mut depth = vec![0usize; order.len()];
    let mut under_follower = vec![false; order.len()];
    let mut last_free_leads = vec![false; order.len()];
    let mut holds_gripper = vec![false; order.len()];
    for (i, &l) in order.iter().enumerate() {
        let lname = link_name(link_nodes[l]);
        match parent_of.get(&l) {
            None => links.push(Link::new(lname, None, Transform::IDENTITY, Joint::fixed())),
            Some(j) => {
                let p = new_index[&j.parent];
                let free = j.joint.kind.is_movable() && !follower.contains_key(&i);
                free_depth[i] = free_depth[p] + usize::from(free);
                depth[i] = depth[p] + 1;
                under_follower[i] = under_follower[p] || follower.contains_key(&i);
                last_free_leads[i] = if free {
                    leaders.contains(&i)
                } else {
                    last_free_leads[p]
                };
                if follower.contains_key(&i) || leaders.contains(&i) {
                    holds_gripper[p] = true;
                }
                links.push(Link::new(lname, Some(p), j.home, j.joint));
            }
        }
    }
    let flange = match tip {
        Some(t) => {
            let i = *link_index
                .get(t)
                .map(|l| &new_index[l])
                .ok_or_else(|| whole(format!("tip link `{t}` is not defined")))?;
            if under_follower[i] {
                return Err(whole(format!(
                    "tip link `{t}` moves with a mimic joint: the arm's chain cannot hold one (name a link above it)"
                )));
            }
            i
        }
        None => {
            // The serial arm's last link: the most free joints, a link that does not
            // carry a gripper's fingers (the flange they hang on, or a TCP frame below
            // the gripper body, rather than the body), then the deepest (a fixed
            // `tool0` after the last joint), then the first in breadth-first order.
            // Links moved by a mimic joint or by a mimic's leader are the hand's.
            let arm = |i: usize| !under_follower[i] && !last_free_leads[i];
            let key = |i: usize| (free_depth[i], !holds_gripper[i], depth[i]);
            let best = (0..order.len()).filter(|&i| arm(i)).map(key).max();
            match best {
                Some(b) if b.0 > 0 => (0..order.len())
                    .position(|i| arm(i) && key(i) == b)
                    .unwrap_or(0),
                // No free joint outside the hand: the most free joints anywhere.
                _ => {
                    let key = |i: usize| (free_depth[i], depth[i]);
                    let b = (0..order.len())
                        .filter(|&i| !under_follower[i])
                        .map(key)
                        .max()
                        .unwrap_or((0, 0));
                    (0..order.len())
                        .position(|i| !under_follower[i] && key(i) == b)
                        .unwrap_or(0)
                }
            }
        }
    };
    let tree = KinematicTree::new(links)
        .and_then(|t| t.with_mimics(&mimics))
        .map_err(|e| whole(e.to_string()))?;
    let robot = Robot::new(name, tree, flange, Transform::IDENTITY)
        .map_err(|e| whole(e.to_string()))?
        .with_limits_source(format!("URDF {}", path.display()));
    let mut meshes = Vec::new();
    let mut primitives = Vec::new();
    let mut primitive_triangles = 0usize;
    let mut warnings = Vec::new();
    for (i, &l) in order.iter().enumerate() {
        // One geometry per link for display and interference: its `<visual>`
        // elements when fitup reads all of them, else its `<collision>` elements when
        // it reads all of those (a visual `.dae` with an STL collision mesh), else
        // what it reads of either, with a warning for each mesh left out.
        let with_geometry = |tag: &str| {
            link_nodes[l]
                .children()
                .filter(|c| c.has_tag_name(tag))
                .filter(|c| c.children().any(|g| g.has_tag_name("geometry")))
                .collect::<Vec<_>>()
        };
        let readable = |v: &roxmltree::Node| match v.descendants().find(|c| c.has_tag_name("mesh"))
        {
            Some(m) => m
                .attribute("filename")
                .is_none_or(|f| MeshFormat::from_path(Path::new(f)).is_some()),
            None => true,
        };
        let visual = with_geometry("visual");
        let collision = with_geometry("collision");
        let geometry = if !visual.is_empty() && visual.iter().all(readable) {
            visual
        } else if !collision.is_empty() && collision.iter().all(readable) {
            collision
        } else {
            let from = if visual.iter().any(readable) || collision.is_empty() {
                visual
            } else {
                collision
            };
            let lname = link_name(link_nodes[l]);
            for v in from.iter().filter(|v| !readable(v)) {
                if let Some(m) = v.descendants().find(|c| c.has_tag_name("mesh")) {
                    let p = attribute_pos(&doc, m, "filename");
                    warnings.push(SourceError::new(
                        path,
                        p.0,
                        p.1,
                        format!(
                            "link `{lname}`: mesh `{}` is not a format fitup reads (STL, OBJ, PLY, glTF) and the link has no <collision> mesh it reads: left out (no display, no interference); convert it, e.g. to STL",
                            short(m.attribute("filename").unwrap_or(""))
                        ),
                    ));
                }
            }
            from.into_iter().filter(readable).collect()
        };
        for v in geometry {
            let Some(g) = v.children().find(|c| c.has_tag_name("geometry")) else {
                continue;
            };
            let num3 = |node: roxmltree::Node, attr: &str, d: [f64; 3], unit: f64| {
                attribute_numbers(&doc, path, node, attr, d, unit)
            };
            let origin_t = match v.children().find(|c| c.has_tag_name("origin")) {
                Some(o) => origin(
                    num3(o, "xyz", [0.0; 3], 1000.0)?,
                    num3(o, "rpy", [0.0; 3], 1.0)?,
                ),
                None => Transform::IDENTITY,
            };
            let Some(shape) = g.children().find(|c| c.is_element()) else {
                return Err(at(g, "<geometry> is empty".into()));
            };
            let line = doc.text_pos_at(shape.range().start).row as usize;
            if !["mesh", "box", "cylinder", "sphere"].contains(&shape.tag_name().name()) {
                // SDF-style shapes (capsule, …): the link loads without them.
                let p = doc.text_pos_at(shape.range().start);
                warnings.push(SourceError::new(
                    path,
                    p.row as usize,
                    p.col as usize,
                    format!(
                        "link `{}`: <{}> geometry is not supported (mesh, box, cylinder, sphere): left out",
                        link_name(link_nodes[l]),
                        short(shape.tag_name().name())
                    ),
                ));
                continue;
            }
            if !shape.has_tag_name("mesh") {
                let mesh = primitive(&doc, path, shape)?.transformed(&origin_t);
                // Counted before it is kept: thousands of spheres on a link stop at the
                // cap, not in the memory (link meshes are added to the same count when
                // the document reads them).
                primitive_triangles += mesh.triangles.len();
                if primitive_triangles > crate::mesh::MAX_TRIANGLES {
                    return Err(at(
                        shape,
                        format!(
                            "link `{}`: the robot's primitive shapes make {}",
                            link_name(link_nodes[l]),
                            crate::mesh::MeshError::too_many(
                                crate::mesh::MAX_TRIANGLES,
                                "triangles"
                            )
                            .message
                        ),
                    ));
                }
                primitives.push(UrdfPrimitive {
                    link: i,
                    shape: shape.tag_name().name().to_string(),
                    mesh,
                    line,
                });
                continue;
            }
            let m = shape;
            let uri = m
                .attribute("filename")
                .ok_or_else(|| at(m, "<mesh> without a filename".into()))?;
            // The scale times 1000 (m → mm) multiplies every vertex: in range, not 0.
            let s = num3(m, "scale", [1.0; 3], 1000.0)?;
            if s.contains(&0.0) {
                let p = attribute_pos(&doc, m, "scale");
                return Err(SourceError::new(
                    path,
                    p.0,
                    p.1,
                    "scale has a 0: the mesh would be flat",
                ));
            }
            meshes.push(UrdfMesh {
                link: i,
                uri: uri.to_string(),
                origin: origin_t,
                scale: s.map(|x| x * 1000.0),
                line,
            });
        }
    }
    Ok(UrdfRobot {
        robot,
        meshes,
        primitives,
        warnings,
    })
}

/// The `<mimic joint multiplier offset>` elements resolved to (follower link, leader
/// link) in the tree's order, a chain of mimics folded onto its first leader, units
/// converted (offsets of prismatic joints m → mm; the multiplier by the ratio of the
/// follower's to the leader's unit). Errors name the `<mimic>` element.
fn mimics(
    doc: &roxmltree::Document,
    path: &Path,
    nodes: &[(usize, roxmltree::Node)],
    joint_child: &HashMap<String, usize>,
    parent_of: &HashMap<usize, impl JointOf>,
    new_index: &HashMap<usize, usize>,
    link_nodes: &[roxmltree::Node],
) -> Result<Vec<(usize, Mimic)>, SourceError> {
    let at = |node: roxmltree::Node, m: String| {
        let p = doc.text_pos_at(node.range().start);
        SourceError::new(path, p.row as usize, p.col as usize, m)
    };
    // follower (file index) → (leader file index, multiplier, offset), URDF units.
    let mut raw: HashMap<usize, (usize, f64, f64, roxmltree::Node)> = HashMap::new();
    for &(child, m) in nodes {
        let lname = link_name(link_nodes[child]);
        let leader_name = m
            .attribute("joint")
            .ok_or_else(|| at(m, format!("link `{lname}`: <mimic> without a joint")))?;
        let leader = *joint_child
            .get(crate::diagnostics::nfc(leader_name).as_ref())
            .ok_or_else(|| {
                at(
                    m,
                    format!(
                        "link `{lname}`: mimic joint `{}` is not defined",
                        short(leader_name)
                    ),
                )
            })?;
        let [k] = attribute_numbers(doc, path, m, "multiplier", [1.0], 1.0)?;
        let [o] = attribute_numbers(doc, path, m, "offset", [0.0], 1000.0)?;
        for (link, role) in [(child, "mimic"), (leader, "leader")] {
            if !parent_of.get(&link).is_some_and(|j| j.movable()) {
                return Err(at(
                    m,
                    format!(
                        "link `{lname}`: the {role} joint must be revolute, continuous or prismatic"
                    ),
                ));
            }
        }
        if leader == child {
            return Err(at(
                m,
                format!("link `{lname}`: a joint cannot mimic itself"),
            ));
        }
        raw.insert(child, (leader, k, o, m));
    }
    let unit = |link: usize| {
        if parent_of.get(&link).is_some_and(|j| j.prismatic()) {
            1000.0
        } else {
            1.0
        }
    };
    let mut out = Vec::with_capacity(raw.len());
    for (&f, &(leader, k, o, node)) in &raw {
        // f = k·l + o, l = k2·l2 + o2, … down to a joint that leads only.
        let (mut lead, mut k, mut o) = (leader, k, o);
        let mut steps = 0;
        while let Some(&(next, k2, o2, _)) = raw.get(&lead) {
            steps += 1;
            if steps > raw.len() {
                return Err(at(
                    node,
                    "mimic joints that follow each other in a cycle".into(),
                ));
            }
            o += k * o2;
            k *= k2;
            lead = next;
        }
        let mimic = Mimic {
            leader: new_index[&lead],
            multiplier: k * unit(f) / unit(lead),
            offset: o * unit(f),
        };
        if !(mimic.multiplier.is_finite() && mimic.multiplier.abs() <= crate::math::MAX_ABS_VALUE) {
            return Err(at(node, "the mimic multiplier is out of range".into()));
        }
        out.push((new_index[&f], mimic));
    }
    out.sort_by_key(|(f, _)| *f);
    Ok(out)
}

/// What [`mimics`] asks of a parsed joint.
trait JointOf {
    fn movable(&self) -> bool;
    fn prismatic(&self) -> bool;
}

/// The closed mesh of a URDF `<box size>`, `<cylinder radius length>` (along Z) or
/// `<sphere radius>`, centred on the geometry's origin, in mm. Errors name the
/// attribute.
fn primitive(
    doc: &roxmltree::Document,
    path: &Path,
    shape: roxmltree::Node,
) -> Result<Mesh, SourceError> {
    let name = shape.tag_name().name();
    let positive = |attr: &str, v: f64| {
        if v > 0.0 {
            Ok(v * 1000.0)
        } else {
            let p = attribute_pos(doc, shape, attr);
            Err(SourceError::new(
                path,
                p.0,
                p.1,
                format!("<{name}> {attr} must be > 0, not {v}"),
            ))
        }
    };
    let need = |attr: &str| {
        if shape.attribute(attr).is_none() {
            let p = doc.text_pos_at(shape.range().start);
            return Err(SourceError::new(
                path,
                p.row as usize,
                p.col as usize,
                format!("<{name}> needs a `{attr}`"),
            ));
        }
        Ok(())
    };
    match name {
        "box" => {
            need("size")?;
            let s = attribute_numbers(doc, path, shape, "size", [0.0; 3], 1000.0)?;
            let h = [
                positive("size", s[0])? / 2.0,
                positive("size", s[1])? / 2.0,
                positive("size", s[2])? / 2.0,
            ];
            Ok(Mesh::cuboid(
                Point3::new(-h[0], -h[1], -h[2]),
                Point3::new(h[0], h[1], h[2]),
            ))
        }
        "cylinder" => {
            need("radius")?;
            need("length")?;
            let [r] = attribute_numbers(doc, path, shape, "radius", [0.0], 1000.0)?;
            let [l] = attribute_numbers(doc, path, shape, "length", [0.0], 1000.0)?;
            let (r, l) = (positive("radius", r)?, positive("length", l)?);
            Ok(Mesh::cylinder(r, l, PRIMITIVE_SEGMENTS)
                .transformed(&Transform::from_translation(Vec3::new(0.0, 0.0, -l / 2.0))))
        }
        "sphere" => {
            need("radius")?;
            let [r] = attribute_numbers(doc, path, shape, "radius", [0.0], 1000.0)?;
            let r = positive("radius", r)?;
            Ok(Mesh::uv_sphere(r, PRIMITIVE_SEGMENTS))
        }
        other => {
            let p = doc.text_pos_at(shape.range().start);
            Err(SourceError::new(
                path,
                p.row as usize,
                p.col as usize,
                format!(
                    "<{}> geometry is not supported (mesh, box, cylinder, sphere)",
                    short(other)
                ),
            ))
        }
    }
}

/// A link's name as the robot keeps it (NFC; checked when the links were read).
fn link_name(n: roxmltree::Node) -> String {
    crate::diagnostics::nfc(n.attribute("name").unwrap_or("")).into_owned()
}

/// The message for a URDF name with a control or invisible character.
fn hidden_in_name(what: &str, name: &str, c: char) -> String {
    format!(
        "{what} name `{}`: {} is not allowed in names (control and invisible characters hide or reorder what is shown)",
        crate::diagnostics::printable(name, false),
        crate::diagnostics::describe_char(c)
    )
}

/// Facets around a meshed cylinder or sphere: the volume is within 0.2 % (cylinder)
/// and 0.5 % (sphere) of the exact one.
const PRIMITIVE_SEGMENTS: usize = 64;

/// Reads and parses a URDF file (see [`parse_urdf`]).
pub fn read_urdf(path: &Path, tip: Option<&str>) -> Result<UrdfRobot, SourceError> {
    let meta = std::fs::metadata(path).map_err(|e| SourceError::new(path, 0, 0, e.to_string()))?;
    if !meta.is_file() {
        return Err(SourceError::new(path, 0, 0, "not a regular file"));
    }
    if meta.len() > MAX_URDF_BYTES as u64 {
        return Err(SourceError::new(
            path,
            0,
            0,
            format!(
                "{} bytes: larger than the {MAX_URDF_BYTES}-byte limit for a URDF",
                meta.len()
            ),
        ));
    }
    let text =
        std::fs::read_to_string(path).map_err(|e| SourceError::new(path, 0, 0, e.to_string()))?;
    parse_urdf(path, &text, tip)
}

/// [`read_urdf`] of a file inside `project` (absolute, as
/// [`crate::project::Project::resolve`] returns it), read through the project's held
/// root folder: a folder swapped for a symbolic link after the path was checked is
/// refused, never followed.
pub fn read_urdf_in(
    project: &crate::project::Project,
    path: &Path,
    tip: Option<&str>,
) -> Result<UrdfRobot, SourceError> {
    let bytes = project
        .open_file(path)
        .and_then(|f| {
            use std::io::Read;
            let len = f.metadata()?.len();
            if len > MAX_URDF_BYTES as u64 {
                return Ok(Err(len));
            }
            let mut bytes = Vec::with_capacity(len as usize);
            f.take(MAX_URDF_BYTES as u64 + 1).read_to_end(&mut bytes)?;
            Ok(Ok(bytes))
        })
        .map_err(|e| SourceError::new(path, 0, 0, e.to_string()))?
        .map_err(|len| {
            SourceError::new(
                path,
                0,
                0,
                format!("{len} bytes: larger than the {MAX_URDF_BYTES}-byte limit for a URDF"),
            )
        })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        SourceError::new(
            path,
            0,
            0,
            format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
        )
    })?;
    parse_urdf(path, &text, tip)
}

/// The 1-based line and column of attribute `attr`'s value of `node` (the node's
/// start when the attribute is missing).
fn attribute_pos(doc: &roxmltree::Document, node: roxmltree::Node, attr: &str) -> (usize, usize) {
    let at = node
        .attribute_node(attr)
        .map_or(node.range().start, |a| a.range_value().start);
    let p = doc.text_pos_at(at);
    (p.row as usize, p.col as usize)
}

/// The `N` numbers of attribute `attr` of `node` (`default` when it is missing), as
/// written. Every number must parse, be finite and, times `unit` (1000 for metres →
/// mm, 1 for radians and plain factors), lie within the document range
/// ([`MAX_ABS_VALUE`](crate::math::MAX_ABS_VALUE)); an error names the file and the
/// attribute's line and column, quoting at most a short excerpt.
fn attribute_numbers<const N: usize>(
    doc: &roxmltree::Document,
    path: &Path,
    node: roxmltree::Node,
    attr: &str,
    default: [f64; N],
    unit: f64,
) -> Result<[f64; N], SourceError> {
    let Some(s) = node.attribute(attr) else {
        return Ok(default);
    };
    let (line, column) = attribute_pos(doc, node, attr);
    let fail = |m: String| SourceError::new(path, line, column, m);
    let shown = short(s);
    let what = match N {
        1 => "a number".to_string(),
        n => format!("{n} numbers"),
    };
    let mut out = [0.0; N];
    let mut tokens = s.split_whitespace();
    for slot in out.iter_mut() {
        let Some(t) = tokens.next() else {
            return Err(fail(format!("{attr}=\"{shown}\" is not {what}")));
        };
        let v: f64 = t
            .parse()
            .map_err(|_| fail(format!("{attr}=\"{shown}\" is not {what}")))?;
        let max = crate::math::MAX_ABS_VALUE;
        let t = short(t);
        if !v.is_finite() {
            return Err(fail(format!("{attr}=\"{shown}\": {t} is not finite")));
        }
        if !(v * unit).is_finite() || (v * unit).abs() > max {
            let units = if unit == 1000.0 {
                " mm (metres × 1000)"
            } else {
                ""
            };
            return Err(fail(format!(
                "{attr}=\"{shown}\": {t} is out of range: fitup accepts magnitudes up to {max:e}{units}"
            )));
        }
        *slot = v;
    }
    if tokens.next().is_some() {
        return Err(fail(format!("{attr}=\"{shown}\" is not {what}")));
    }
    Ok(out)
}

/// At most 40 characters of an attribute value, for messages (a value may be megabytes).
fn short(s: &str) -> String {
    if s.chars().count() <= 40 {
        s.to_string()
    } else {
        format!("{}…", s.chars().take(40).collect::<String>())
    }
}

/// A URDF origin (metres, rpy radians) as a transform in mm.
fn origin(xyz: [f64; 3], rpy: [f64; 3]) -> Transform {
    Transform::from_isometry(Isometry3::from_parts(
        Translation3::new(xyz[0] * 1000.0, xyz[1] * 1000.0, xyz[2] * 1000.0),
        UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
    ))
}

#[cfg(test)]
mod tests;
