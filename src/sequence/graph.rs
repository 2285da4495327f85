//! Seed 003 section 2, steps 1–3: the relation graph from the document's mates, the
//! remaining degrees of freedom ("degrees of separation") of each mate as a 6-vector
//! and their intersections, and loops broken into composite nodes.
//!
//! Units: millimetres and radians; directions are unit vectors in the assembly frame
//! (the document's world frame) unless a doc says "mate frame".

use crate::document::{Document, Mate, MateKind, Reference};
use crate::math::{Transform, Vec3};
use nalgebra::UnitQuaternion;

/// Below this a vector is zero and two directions are equal.
const EPS: f64 = 1e-6;

/// The remaining degrees of freedom of a constraint (or of several, intersected): the
/// translations and rotations it leaves free, as subspaces of the assembly frame, and
/// the mate frame the seed writes them in (`z` along the plane normal or the axis).
#[derive(Debug, Clone, PartialEq)]
pub struct Freedom {
    /// The mate frame: mate frame → assembly frame (origin on the first entity).
    pub frame: Transform,
    /// Orthonormal basis of the free translations (assembly frame).
    pub translations: Vec<Vec3>,
    /// Orthonormal basis of the free rotation axes (assembly frame).
    pub rotations: Vec<Vec3>,
}

/// An orthonormal basis of the span of `vs` (Gram–Schmidt, tolerant).
fn orthonormal(vs: &[Vec3]) -> Vec<Vec3> {
    let mut out: Vec<Vec3> = Vec::new();
    for v in vs {
        let mut w = *v;
        for u in &out {
            w -= u * u.dot(&w);
        }
        if w.norm() > EPS {
            out.push(w.normalize());
        }
    }
    out
}

/// Basis of the intersection of two subspaces of R³ given by orthonormal bases.
fn intersect_spaces(a: &[Vec3], b: &[Vec3]) -> Vec<Vec3> {
    let inside = |basis: &[Vec3], v: &Vec3| {
        let p: Vec3 = basis.iter().map(|u| u * u.dot(v)).sum();
        (p - v).norm() < EPS
    };
    match (a.len(), b.len()) {
        (0, _) | (_, 0) => Vec::new(),
        (3, _) => b.to_vec(),
        (_, 3) => a.to_vec(),
        (1, _) => a.iter().filter(|u| inside(b, u)).copied().collect(),
        (_, 1) => b.iter().filter(|u| inside(a, u)).copied().collect(),
        _ => {
            // Two planes through the origin: equal, or meeting in a line.
            let (na, nb) = (a[0].cross(&a[1]), b[0].cross(&b[1]));
            let line = na.cross(&nb);
            if line.norm() < EPS {
                a.to_vec()
            } else {
                vec![line.normalize()]
            }
        }
    }
}

/// A deterministic orthonormal frame with `z` along `dir` at `origin`; its `x` is the
/// assembly X axis projected on the plane normal to `dir` (Y when `dir` is along X),
/// so axis-aligned assemblies get axis-aligned mate frames.
pub(crate) fn frame_along(origin: Vec3, dir: &Vec3) -> Transform {
    let z = dir.normalize();
    let pick = if z.x.abs() < 0.9 {
        Vec3::x()
    } else {
        Vec3::y()
    };
    let x = (pick - z * z.dot(&pick)).normalize();
    let y = z.cross(&x);
    let m = nalgebra::Matrix3::from_columns(&[x, y, z]);
    let q = UnitQuaternion::from_matrix(&m);
    Transform::from_parts(origin, q)
}

impl Freedom {
    fn new(frame: Transform, t: &[Vec3], r: &[Vec3]) -> Freedom {
        Freedom {
            frame,
            translations: orthonormal(t),
            rotations: orthonormal(r),
        }
    }

    /// The remaining degrees of freedom of `mate` in the current poses of `doc`
    /// (`None` for a mate that joins a component to itself).
    ///
    /// Seed 003: coplanar → `{x, y, Rotz}` = (1,1,0,0,0,1), collinear → `{z, Rotz}` =
    /// (0,0,1,0,0,1). fitup adds: point coincident → rotations only; point on a plane
    /// → `{x, y}` and rotations; point on an axis → `{z}` and rotations; parallel →
    /// translations and `Rotz`; perpendicular and angle → translations and the rotation
    /// about the first entity's direction (an approximation: the second entity may
    /// still turn about its own direction, which fitup ignores); two coordinate
    /// systems coincident leave nothing free.
    pub fn of_mate(doc: &Document, mate: &Mate) -> Freedom {
        let poses: Vec<Transform> = doc.components().iter().map(|c| c.transform).collect();
        let [ea, eb] = &mate.entities;
        let a = ea.geometry.posed(&poses[ea.component]);
        let b = eb.geometry.posed(&poses[eb.component]);
        let dir = a.direction().or(b.direction()).unwrap_or_else(Vec3::z);
        let frame = frame_along(a.anchor().coords, &dir);
        let r = frame.rotation();
        let (x, y, z) = (r * Vec3::x(), r * Vec3::y(), r * Vec3::z());
        use Reference::*;
        match (mate.kind, &a, &b) {
            (MateKind::Coincident | MateKind::Distance, Plane { .. }, Plane { .. }) => {
                Freedom::new(frame, &[x, y], &[z])
            }
            (MateKind::Coincident | MateKind::Concentric, Axis { .. }, Axis { .. }) => {
                Freedom::new(frame, &[z], &[z])
            }
            (MateKind::Coincident | MateKind::Distance, Point(_), Point(_)) => {
                Freedom::new(frame, &[], &[x, y, z])
            }
            (MateKind::Coincident | MateKind::Distance, Plane { .. }, Point(_))
            | (MateKind::Coincident | MateKind::Distance, Point(_), Plane { .. }) => {
                Freedom::new(frame, &[x, y], &[x, y, z])
            }
            (MateKind::Coincident, Axis { .. }, Point(_))
            | (MateKind::Coincident, Point(_), Axis { .. }) => {
                Freedom::new(frame, &[z], &[x, y, z])
            }
            (MateKind::Parallel, _, _) => Freedom::new(frame, &[x, y, z], &[z]),
            // Two coordinate systems coincident: nothing is left free.
            (MateKind::Coincident, CoordinateSystem(_), CoordinateSystem(_)) => {
                Freedom::new(frame, &[], &[])
            }
            _ => Freedom::new(frame, &[x, y, z], &[z]),
        }
    }

    /// The seed's 6-vector `(x, y, z, Rotx, Roty, Rotz)` in the mate frame: 1 where
    /// that axis of the mate frame is free.
    pub fn vector(&self) -> [u8; 6] {
        let r = self.frame.rotation();
        let axes = [r * Vec3::x(), r * Vec3::y(), r * Vec3::z()];
        let inside = |basis: &[Vec3], v: &Vec3| {
            let p: Vec3 = basis.iter().map(|u| u * u.dot(v)).sum();
            (p - v).norm() < 1e-6
        };
        let mut out = [0u8; 6];
        for (i, a) in axes.iter().enumerate() {
            out[i] = inside(&self.translations, a) as u8;
            out[i + 3] = inside(&self.rotations, a) as u8;
        }
        out
    }

    /// The number of free degrees (translations + rotations): the seed's count of 1s.
    pub fn count(&self) -> usize {
        self.translations.len() + self.rotations.len()
    }

    /// `self ∩ other` (the seed's `R1 ∩ R2`), written in `self`'s mate frame.
    pub fn intersect(&self, other: &Freedom) -> Freedom {
        Freedom {
            frame: self.frame,
            translations: intersect_spaces(&self.translations, &other.translations),
            rotations: intersect_spaces(&self.rotations, &other.rotations),
        }
    }
}

/// Two components joined by one or more mates (an edge of the relation graph).
#[derive(Debug, Clone, PartialEq)]
pub struct Relation {
    /// The first component (index into the document's components; `a < b`).
    pub a: usize,
    /// The second component.
    pub b: usize,
    /// The mates joining them (indices into [`Document::mates`]).
    pub mates: Vec<usize>,
    /// The remaining freedom of each mate, in `mates` order.
    pub freedoms: Vec<Freedom>,
    /// Their intersection `R1 ∩ R2 ∩ …` (in the first mate's frame).
    pub freedom: Freedom,
}

/// A node of the relation graph: one component, or a composite node of several whose
/// loop was broken (seed 003, section 2.1 step 1). The members are in assembly order:
/// the composite implies it.
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    /// Component indices, assembly order (the first is the node's base part).
    pub members: Vec<usize>,
}

impl Node {
    /// Whether the node is a composite (more than one component).
    pub fn is_composite(&self) -> bool {
        self.members.len() > 1
    }
}

/// The relation graph (seed 003, section 2): components joined by mates, with the
/// loops broken into composite nodes.
#[derive(Debug, Clone, PartialEq)]
pub struct RelationGraph {
    /// Component names, by index.
    pub components: Vec<String>,
    /// The edges: component pairs that share mates.
    pub relations: Vec<Relation>,
    /// The nodes after loop breaking (every component is in exactly one).
    pub nodes: Vec<Node>,
    /// The loops found and how each was broken: the component pair united and the
    /// counts of 1s around the loop (`(a, b, ones)` per edge).
    pub loops: Vec<LoopBreak>,
}

/// How one loop of the relation graph was broken.
#[derive(Debug, Clone, PartialEq)]
pub struct LoopBreak {
    /// The loop's edges as (component, component, 1s of the intersection); for a
    /// composite node its base part's index stands for the node.
    pub edges: Vec<(usize, usize, usize)>,
    /// The two nodes united (their base parts' indices).
    pub united: (usize, usize),
}

impl RelationGraph {
    /// Builds the graph of `doc` from its mates (step 1), the freedoms (step 2) and
    /// breaks loops (step 3) with the seed's rule: around a loop, the pair whose
    /// intersection has the fewest 1s constrains each other fully and becomes one
    /// node; the larger of the two (by `size`) is the composite's base part.
    /// Repeated until no loop is left.
    pub fn build(doc: &Document, size: &dyn Fn(usize) -> f64) -> RelationGraph {
        let n = doc.components().len();
        let mut relations: Vec<Relation> = Vec::new();
        for (k, mate) in doc.mates().iter().enumerate() {
            let (ca, cb) = (mate.entities[0].component, mate.entities[1].component);
            if ca == cb {
                continue;
            }
            let (a, b) = (ca.min(cb), ca.max(cb));
            let f = Freedom::of_mate(doc, mate);
            match relations.iter_mut().find(|r| r.a == a && r.b == b) {
                Some(r) => {
                    r.freedom = r.freedom.intersect(&f);
                    r.mates.push(k);
                    r.freedoms.push(f);
                }
                None => relations.push(Relation {
                    a,
                    b,
                    mates: vec![k],
                    freedoms: vec![f.clone()],
                    freedom: f,
                }),
            }
        }
        let mut nodes: Vec<Node> = (0..n).map(|i| Node { members: vec![i] }).collect();
        let mut loops = Vec::new();
        // Each union removes a node, so this ends after at most n rounds.
        for _ in 0..n {
            let Some(cycle) = find_cycle(&nodes, &relations) else {
                break;
            };
            // The freedom between two nodes: every relation across them intersected.
            let ones = |x: usize, y: usize| -> usize {
                let mut f: Option<Freedom> = None;
                for r in &relations {
                    let (ia, ib) = (node_of(&nodes, r.a), node_of(&nodes, r.b));
                    if (ia == x && ib == y) || (ia == y && ib == x) {
                        f = Some(match f {
                            Some(g) => g.intersect(&r.freedom),
                            None => r.freedom.clone(),
                        });
                    }
                }
                f.map_or(6, |f| f.count())
            };
            let mut edges = Vec::new();
            let mut best = (usize::MAX, 0, 0);
            for i in 0..cycle.len() {
                let (x, y) = (cycle[i], cycle[(i + 1) % cycle.len()]);
                let c = ones(x, y);
                edges.push((nodes[x].members[0], nodes[y].members[0], c));
                if c < best.0 {
                    best = (c, x, y);
                }
            }
            let (_, x, y) = best;
            let sx: f64 = nodes[x].members.iter().map(|&m| size(m)).sum();
            let sy: f64 = nodes[y].members.iter().map(|&m| size(m)).sum();
            let (keep, other) = if sx >= sy { (x, y) } else { (y, x) };
            loops.push(LoopBreak {
                edges,
                united: (nodes[keep].members[0], nodes[other].members[0]),
            });
            let moved = nodes[other].members.clone();
            nodes[keep].members.extend(moved);
            nodes.remove(other);
        }
        RelationGraph {
            components: doc.components().iter().map(|c| c.name.clone()).collect(),
            relations,
            nodes,
            loops,
        }
    }

    /// The index of the node holding component `c`.
    pub fn node_of(&self, c: usize) -> usize {
        node_of(&self.nodes, c)
    }

    /// The components related to `c` by mates.
    pub fn neighbours(&self, c: usize) -> Vec<usize> {
        self.relations
            .iter()
            .filter_map(|r| {
                if r.a == c {
                    Some(r.b)
                } else if r.b == c {
                    Some(r.a)
                } else {
                    None
                }
            })
            .collect()
    }

    /// The relation between components `a` and `b`, if any.
    pub fn relation(&self, a: usize, b: usize) -> Option<&Relation> {
        let (a, b) = (a.min(b), a.max(b));
        self.relations.iter().find(|r| r.a == a && r.b == b)
    }
}

fn node_of(nodes: &[Node], c: usize) -> usize {
    nodes
        .iter()
        .position(|n| n.members.contains(&c))
        .unwrap_or(usize::MAX)
}

/// A cycle of the node graph (node indices in order), if any.
fn find_cycle(nodes: &[Node], relations: &[Relation]) -> Option<Vec<usize>> {
    let n = nodes.len();
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); n];
    for r in relations {
        let (x, y) = (node_of(nodes, r.a), node_of(nodes, r.b));
        if x != y && x < n && y < n && !adj[x].contains(&y) {
            adj[x].push(y);
            adj[y].push(x);
        }
    }
    let mut parent = vec![usize::MAX; n];
    let mut seen = vec![false; n];
    for root in 0..n {
        if seen[root] {
            continue;
        }
        let mut stack = vec![(root, usize::MAX)];
        while let Some((v, from)) = stack.pop() {
            if seen[v] {
                continue;
            }
            seen[v] = true;
            parent[v] = from;
            for &w in &adj[v] {
                if w == from {
                    continue;
                }
                if seen[w] {
                    // A back edge v–w closes a cycle: walk both up to their meeting.
                    let path_up = |mut u: usize| {
                        let mut p = vec![u];
                        while parent[u] != usize::MAX {
                            u = parent[u];
                            p.push(u);
                        }
                        p
                    };
                    let (pv, pw) = (path_up(v), path_up(w));
                    let Some(meet) = pv.iter().find(|u| pw.contains(u)).copied() else {
                        continue;
                    };
                    let mut cycle: Vec<usize> =
                        pv.iter().take_while(|&&u| u != meet).copied().collect();
                    cycle.push(meet);
                    let back: Vec<usize> = pw.iter().take_while(|&&u| u != meet).copied().collect();
                    cycle.extend(back.into_iter().rev());
                    if cycle.len() >= 3 {
                        return Some(cycle);
                    }
                } else {
                    stack.push((w, v));
                }
            }
        }
    }
    None
}

/// The separation directions a mate offers the component `mover` (unit, assembly
/// frame): both signs of each free translation, and for planes in contact (coincident
/// or distance) the normal pointing away from the other side — the seed separates the
/// shaft along the plane's normal although coplanarity does not list it.
pub(crate) fn separation_directions(
    doc: &Document,
    mate: &Mate,
    mover: usize,
    freedom: &Freedom,
) -> Vec<Vec3> {
    let mut out: Vec<Vec3> = Vec::new();
    for t in &freedom.translations {
        out.push(*t);
        out.push(-t);
    }
    let [ea, eb] = &mate.entities;
    let poses: Vec<Transform> = doc.components().iter().map(|c| c.transform).collect();
    if matches!(mate.kind, MateKind::Coincident | MateKind::Distance) {
        let other = if ea.component == mover { eb } else { ea };
        let mine = if ea.component == mover { ea } else { eb };
        if let (
            Reference::Plane {
                point: po,
                normal: no,
            },
            Reference::Plane {
                point: pm,
                normal: nm,
            },
        ) = (
            other.geometry.posed(&poses[other.component]),
            mine.geometry.posed(&poses[mine.component]),
        ) {
            if no.dot(&nm) > 0.0 {
                // Aligned planes (both facing the same way) do not touch face to
                // face: no side to leave on.
                return out;
            }
            // Leave on the side of the other plane the mover lies on (its normal's
            // side when the planes meet).
            let s = no.dot(&(pm - po));
            out.push(if s < -1e-9 { -no } else { no });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seed_vectors_and_intersection() {
        let f = frame_along(Vec3::zeros(), &Vec3::z());
        let r = f.rotation();
        let (x, y, z) = (r * Vec3::x(), r * Vec3::y(), r * Vec3::z());
        let coplanar = Freedom::new(f, &[x, y], &[z]);
        let collinear = Freedom::new(f, &[z], &[z]);
        assert_eq!(coplanar.vector(), [1, 1, 0, 0, 0, 1]);
        assert_eq!(collinear.vector(), [0, 0, 1, 0, 0, 1]);
        let both = coplanar.intersect(&collinear);
        assert_eq!(both.vector(), [0, 0, 0, 0, 0, 1]);
        assert_eq!(both.count(), 1);
        // A vertical plane (normal X) contains the vertical axis: the pair keeps z; a
        // tilted plane does not.
        let wall = frame_along(Vec3::zeros(), &Vec3::x());
        let rw = wall.rotation();
        let plane = Freedom::new(wall, &[rw * Vec3::x(), rw * Vec3::y()], &[rw * Vec3::z()]);
        let i = plane.intersect(&collinear);
        assert_eq!(i.translations.len(), 1);
        assert!(i.translations[0].cross(&Vec3::z()).norm() < 1e-9);
        assert!(i.rotations.is_empty());
        let tilted = frame_along(Vec3::zeros(), &Vec3::new(1.0, 0.0, 1.0));
        let rt = tilted.rotation();
        let plane = Freedom::new(tilted, &[rt * Vec3::x(), rt * Vec3::y()], &[rt * Vec3::z()]);
        assert_eq!(plane.intersect(&collinear).count(), 0);
    }
}
