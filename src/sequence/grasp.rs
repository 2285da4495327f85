//! Seed 003 section 2.1 step 3: grasp planes. Parallel face pairs of the part (named
//! planes of the part, else planar faces found on the mesh) whose closing direction
//! is across every mating direction (`G1 ∩ G2 ∩ …`), then the end effector as two
//! finger boxes slid along the grasp plane in the mating direction until they fully
//! grip or collide. Units: mm; grasps are in the part frame.

use super::context::Ctx;
use super::task::Grasp;
use crate::collision::{interferes, Collider};
use crate::document::Reference;
use crate::math::{Point3, Transform, Vec3};
use crate::mesh::Mesh;
use nalgebra::{Matrix3, UnitQuaternion};
use std::collections::HashMap;
use std::sync::Arc;

/// A pair of parallel outward faces, part frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FacePair {
    /// Names of the two faces (reference names, or `mesh_face_<k>`).
    pub faces: [String; 2],
    /// Outward normal of the first face (unit, part frame); the second faces away.
    pub normal: Vec3,
    /// Offset of the first face along `normal` (mm).
    pub offset: f64,
    /// Distance between the faces (mm).
    pub width: f64,
    /// Area found on the mesh (mm²), 0 for named planes.
    pub area: f64,
}

/// Parallel face pairs of a part: its named planes with opposite normals whose second
/// plane lies behind the first (outer faces a gripper can close on), and the planar
/// faces of its mesh paired the same way (largest first, at most 16), as two lists.
pub fn face_pairs(
    part_planes: &[(String, Reference)],
    mesh: &Mesh,
) -> (Vec<FacePair>, Vec<FacePair>) {
    let mut out = Vec::new();
    for (i, (na, a)) in part_planes.iter().enumerate() {
        for (nb, b) in &part_planes[i + 1..] {
            if let (
                Reference::Plane {
                    point: pa,
                    normal: ua,
                },
                Reference::Plane {
                    point: pb,
                    normal: ub,
                },
            ) = (a, b)
            {
                if ua.dot(ub) > -0.9999 {
                    continue;
                }
                let (sa, sb) = (ua.dot(&pa.coords), ua.dot(&pb.coords));
                let (first, second, n, off, w) = if sb < sa {
                    (na, nb, *ua, sa, sa - sb)
                } else {
                    (nb, na, *ub, ub.dot(&pb.coords), sb - sa)
                };
                if w > 1e-6 {
                    out.push(FacePair {
                        faces: [first.clone(), second.clone()],
                        normal: n,
                        offset: off,
                        width: w,
                        area: 0.0,
                    });
                }
            }
        }
    }
    let named = std::mem::take(&mut out);
    // Planar faces of the mesh: triangles grouped by normal and offset.
    // Key: normal and offset, rounded; value: normal, offset, area.
    type Face = (Vec3, f64, f64);
    let mut faces: HashMap<[i64; 4], Face> = HashMap::new();
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle(t);
        let area = 0.5 * (b - a).cross(&(c - a)).norm();
        if area <= 1e-12 {
            continue;
        }
        let n = mesh.triangle_normal(t);
        let off = n.dot(&a.coords);
        let key = [
            (n.x * 1e4).round() as i64,
            (n.y * 1e4).round() as i64,
            (n.z * 1e4).round() as i64,
            (off * 1e3).round() as i64,
        ];
        let e = faces.entry(key).or_insert((n, off, 0.0));
        e.2 += area;
    }
    let mut list: Vec<(Vec3, f64, f64)> = faces.into_values().collect();
    list.sort_by(|a, b| {
        b.2.total_cmp(&a.2)
            .then(a.1.total_cmp(&b.1))
            .then(a.0.x.total_cmp(&b.0.x))
            .then(a.0.y.total_cmp(&b.0.y))
    });
    list.truncate(64);
    for (i, (na, oa, aa)) in list.iter().enumerate() {
        for (j, (nb, ob, ab)) in list.iter().enumerate().skip(i + 1) {
            if na.dot(nb) > -0.9999 {
                continue;
            }
            // nb ≈ −na: the second face at −ob along na lies behind the first.
            let w = oa + ob;
            if w > 1e-6 {
                out.push(FacePair {
                    faces: [format!("mesh_face_{i}"), format!("mesh_face_{j}")],
                    normal: *na,
                    offset: *oa,
                    width: w,
                    area: aa.min(*ab),
                });
            }
        }
    }
    out.sort_by(|a, b| b.area.total_cmp(&a.area));
    out.truncate(16);
    (named, out)
}

fn planes_of(ctx: &Ctx, p: usize) -> Vec<(String, Reference)> {
    let part = &ctx.doc.components()[p].part;
    ctx.doc
        .part(part)
        .map(|pt| {
            pt.references
                .iter()
                .filter(|(_, r)| matches!(r, Reference::Plane { .. }))
                .map(|(n, r)| (n.clone(), *r))
                .collect()
        })
        .unwrap_or_default()
}

/// The face pairs of component `p` valid for every direction of `dirs` (world): the
/// seed's `G1 ∩ G2 ∩ …` (a pair is valid when its closing direction is across the
/// mating direction). Named planes first; the mesh's faces when no named pair fits.
pub(crate) fn grasp_planes(ctx: &Ctx, p: usize, dirs: &[Vec3]) -> Vec<FacePair> {
    let pose = ctx.scene.poses[p];
    let inv = pose.rotation().inverse();
    let local: Vec<Vec3> = dirs.iter().map(|d| inv * d).collect();
    let keep = |v: Vec<FacePair>| -> Vec<FacePair> {
        v.into_iter()
            .filter(|f| f.width <= ctx.opts.gripper.max_opening)
            .filter(|f| local.iter().all(|m| f.normal.dot(m).abs() < 1e-3))
            .collect()
    };
    let (named, mesh) = face_pairs(&planes_of(ctx, p), ctx.doc.mesh_of(p));
    let named = keep(named);
    if named.is_empty() {
        keep(mesh)
    } else {
        named
    }
}

/// The grasp of component `p` for a task with mating direction `mate` (world) and
/// free directions `dirs`, among the components of `mask` at their assembled poses.
pub(crate) fn find_grasp(
    ctx: &Ctx,
    p: usize,
    dirs: &[Vec3],
    mate: &Vec3,
    mask: u128,
) -> Option<Grasp> {
    // Past the deadline the answer is built without grasps (the budget is a limit).
    if ctx.out_of_time() {
        return None;
    }
    let pose = ctx.scene.poses[p];
    let inv = pose.rotation().inverse();
    let m = (inv * mate).normalize();
    let mesh = ctx.doc.mesh_of(p);
    let mut pairs = grasp_planes(ctx, p, dirs);
    if pairs.is_empty() {
        pairs = grasp_planes(ctx, p, &[*mate]);
    }
    let slides: Vec<Slide> = pairs
        .iter()
        .filter_map(|pair| Slide::new(ctx, &pose, mesh, pair, &m))
        .collect();
    // Only the assembled components whose boxes meet the fingers' reach (their
    // boxes from depth 0 to a full slide) can stop a finger: the grasp depends on
    // them alone and is found once per such set.
    let near: u128 = super::context::members_of(mask)
        .filter(|&q| {
            slides
                .iter()
                .any(|s| ctx.boxes[q].overlap(&s.reach).min() > -ctx.opts.tolerance)
        })
        .fold(0, |a, q| a | (1u128 << q));
    let key = (
        p,
        super::context::dir_key(mate),
        dirs.iter().map(super::context::dir_key).collect(),
        near,
    );
    if let Some(g) = ctx.grasps.lock().unwrap().get(&key) {
        return g.clone();
    }
    let found = slides.iter().find_map(|s| s.run(ctx, near));
    ctx.grasps.lock().unwrap().insert(key, found.clone());
    found
}

/// Two finger boxes set up on a face pair, ready to slide along the mating
/// direction (part frame `m`) from behind the part.
struct Slide {
    fingers: [Arc<Collider>; 2],
    /// Finger frame (n, u, m) → part frame.
    rot: Transform,
    /// Part frame → world.
    pose: Transform,
    m: Vec3,
    extent: f64,
    /// Where the grasp point is, before the depth: across, along u, at the trailing end.
    at: Vec3,
    /// World box of every finger position over the whole slide.
    reach: crate::math::Aabb,
    pair: FacePair,
    tool_rot: UnitQuaternion<f64>,
}

impl Slide {
    fn new(ctx: &Ctx, pose: &Transform, mesh: &Mesh, pair: &FacePair, m: &Vec3) -> Option<Slide> {
        let n = pair.normal;
        // (n, u, m) right-handed.
        let u = m.cross(&n).try_normalize(1e-9)?;
        let proj = |d: &Vec3| {
            mesh.vertices
                .iter()
                .map(|v| d.dot(&v.coords))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                    (a.min(x), b.max(x))
                })
        };
        let (lo_m, hi_m) = proj(m);
        let (lo_u, hi_u) = proj(&u);
        let extent = hi_m - lo_m;
        if extent <= 0.0 {
            return None;
        }
        let g = &ctx.opts.gripper;
        let t = g.finger_thickness.max(1e-3);
        let w = if g.finger_width > 0.0 {
            g.finger_width
        } else {
            0.5 * (hi_u - lo_u)
        };
        let cu = 0.5 * (lo_u + hi_u);
        let gap = ctx.opts.tolerance.max(1e-3) * 2.0;
        let s1 = pair.offset;
        let s2 = s1 - pair.width;
        // Finger boxes in the (n, u, m) frame, at depth 0: just behind the part's
        // trailing end (the side opposite the mating direction).
        let frame = UnitQuaternion::from_matrix(&Matrix3::from_columns(&[n, u, *m]));
        let finger = |a: f64, b: f64| -> Option<Arc<Collider>> {
            let mesh = Mesh::cuboid(
                Point3::new(a, cu - w / 2.0, lo_m - extent),
                Point3::new(b, cu + w / 2.0, lo_m),
            );
            Collider::new(Arc::new(mesh)).ok().map(Arc::new)
        };
        let fingers = [
            finger(s1 + gap, s1 + gap + t)?,
            finger(s2 - gap - t, s2 - gap)?,
        ];
        let rot = Transform::from_parts(Vec3::zeros(), frame);
        let mut slide = Slide {
            fingers,
            rot,
            pose: *pose,
            m: *m,
            extent,
            at: n * (0.5 * (s1 + s2)) + u * cu + m * lo_m,
            reach: crate::math::Aabb::new(Point3::origin(), Point3::origin()),
            pair: pair.clone(),
            // Tool frame: z along the mating direction (approach), x the closing
            // direction.
            tool_rot: UnitQuaternion::from_matrix(&Matrix3::from_columns(&[n, m.cross(&n), *m])),
        };
        // A box translated along a line stays within the hull of its two ends.
        let mut reach: Option<crate::math::Aabb> = None;
        for depth in [0.0, extent] {
            let world = slide.world(depth);
            for f in &slide.fingers {
                let b = f.world_bounds(&world);
                reach = Some(match reach {
                    None => b,
                    Some(r) => crate::math::Aabb::new(r.lo.inf(&b.lo), r.hi.sup(&b.hi)),
                });
            }
        }
        slide.reach = reach?;
        Some(slide)
    }

    /// Finger frame → world with the fingers slid `depth` along the mating direction.
    fn world(&self, depth: f64) -> Transform {
        self.rot
            .then(&Transform::from_translation(self.m * depth))
            .then(&self.pose)
    }

    /// Slides the fingers in 20 steps until they collide with a component of `mask`
    /// or fully grip; `None` when even the first step collides.
    fn run(&self, ctx: &Ctx, mask: u128) -> Option<Grasp> {
        let hits = |depth: f64| {
            let world = self.world(depth);
            self.fingers.iter().any(|f| {
                let b = f.world_bounds(&world);
                super::context::members_of(mask).any(|q| {
                    ctx.boxes[q].overlap(&b).min() > -ctx.opts.tolerance
                        && interferes(
                            f,
                            &world,
                            &ctx.scene.colliders[q],
                            &ctx.scene.poses[q],
                            ctx.opts.tolerance,
                        )
                        .unwrap_or(true)
                })
            })
        };
        let steps = 20;
        let mut depth = 0.0;
        for k in 1..=steps {
            if ctx.out_of_time() {
                return None;
            }
            let d = self.extent * k as f64 / steps as f64;
            if hits(d) {
                break;
            }
            depth = d;
        }
        if depth <= 0.0 {
            return None;
        }
        let point = self.at + self.m * (0.5 * depth);
        Some(Grasp {
            faces: self.pair.faces.clone(),
            normal: self.pair.normal,
            width: self.pair.width,
            point,
            depth,
            tool_in_part: Transform::from_parts(point, self.tool_rot),
        })
    }
}
