//! Distances between two posed parts, in millimetres: the clearance that agrees
//! with [`contact`](super::contact), the exact surface distance, and the cheaper
//! lower bound continuous sweeps advance by. All are one branch-and-bound search
//! over the two trees' box pairs in the first part's frame.

use super::containment::contained;
use super::exact::{check_pose, eps, size, tri_box};
use super::relative::Relative;
use super::shape::Collider;
use super::triangle::{tri_distance, Tri};
use super::CollisionError;
use crate::math::{Aabb, Transform};

/// The clearance between parts `a` at `pa` and `b` at `pb` (mm): the distance between
/// their surfaces, searched up to `cap` mm (returns `cap` when nothing is nearer), and
/// 0 when they meet or one solid lies inside the other — the same geometry
/// [`contact`] judges, so the two agree at every tolerance `tol` ≥ 0:
/// `Touching` or `Interfering` ⇒ clearance ≤ `tol` (0 for crossing or contained
/// parts), and clearance > `tol` ⇒ `Separate`.
///
/// A surface distance within the pair's numerical slack (the colliders' `eps`, the
/// distance at which [`contact`] counts surfaces as meeting) is reported as 0.
pub fn clearance(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    cap: f64,
) -> Result<f64, CollisionError> {
    // The full search (stop 0): a `stop` above 0 would return the first leaf pair's
    // distance below it, not the minimum (clearance once answered 23 mm for touching
    // parts that way).
    let cap = if cap.is_nan() {
        f64::INFINITY
    } else {
        cap.max(0.0)
    };
    let d = distance_search(a, pa, b, pb, 0.0, cap, 0.0)?;
    let eps = eps(a, b, pa, pb);
    // `tri_tri` counts pairs within `eps` of each other's planes as meeting; their
    // distance may be a few `eps` (corner to edge), never more than 4·eps.
    if d <= 4.0 * eps {
        return Ok(0.0);
    }
    // Surfaces apart: one solid may still hold the other (contact says Interfering).
    if contained(a, pa, b, pb, eps).is_some() {
        return Ok(0.0);
    }
    Ok(d)
}

/// Minimum distance between the surfaces of `a` at `pa` and `b` at `pb`, mm (0 when
/// they touch or cross; for one part inside another it is the gap between the
/// surfaces). Pruned by box distances; stops early once below `stop`.
pub fn surface_distance(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    stop: f64,
) -> Result<f64, CollisionError> {
    distance_search(a, pa, b, pb, stop, f64::INFINITY, 0.0)
}

/// A lower bound `d` of the surface distance `d*` between `a` at `pa` and `b` at
/// `pb` (mm) for conservative advancement, cheaper than [`surface_distance`]:
/// `d ≤ d* ≤ (1 + slack) · d` when `d* < cap`, else `d ≥ cap / (1 + slack)`
/// (the search drops every box pair farther than what it needs). Stops early once
/// below `stop`. `slack ≥ 0` (0.25 loses a fifth of each advance and skips most
/// of the exact search).
pub fn distance_lower_bound(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    stop: f64,
    cap: f64,
    slack: f64,
) -> Result<f64, CollisionError> {
    distance_search(a, pa, b, pb, stop, cap, slack.max(0.0))
}

/// Branch and bound over box pairs; a pair is dropped when its box distance times
/// `1 + slack` reaches the best distance found (initially `cap`), so the true
/// distance is at least `best / (1 + slack)`, which is returned.
fn distance_search(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    stop: f64,
    cap: f64,
    slack: f64,
) -> Result<f64, CollisionError> {
    check_pose(pa)?;
    check_pose(pb)?;
    let rel = Relative::new(pa, pb);
    let grow = 1.0 + slack;
    let mut best = if cap.is_nan() {
        f64::INFINITY
    } else {
        cap * grow
    };
    let mut stack: Vec<(u32, u32, f64)> = vec![(0, 0, 0.0)];
    let mut moved_boxes: Vec<(Tri, Aabb)> = Vec::with_capacity(8);
    let mut tally = super::EffortTally(0);
    while let Some((i, j, lb)) = stack.pop() {
        tally.0 += 1;
        if lb * grow >= best {
            continue;
        }
        let (na, nb) = (&a.nodes[i as usize], &b.nodes[j as usize]);
        if na.count > 0 && nb.count > 0 {
            moved_boxes.clear();
            moved_boxes.extend(b.leaf_tris(nb).map(|t| {
                let m = rel.tri(&t);
                (m, tri_box(&m))
            }));
            for ta in a.leaf_tris(na) {
                let ba = tri_box(&ta);
                for (tb, bb) in &moved_boxes {
                    // the triangles' boxes bound their distance from below
                    if ba.distance_to_box(bb) * grow < best {
                        best = best.min(tri_distance(&ta, tb));
                    }
                }
            }
            if best < stop {
                return Ok(best / grow);
            }
            continue;
        }
        let split_a = nb.count > 0 || (na.count == 0 && size(na) >= size(nb));
        let children = if split_a {
            [(na.first, j), (na.first + 1, j)]
        } else {
            [(i, nb.first), (i, nb.first + 1)]
        };
        let mut next = children.map(|(ci, cj)| {
            let d = rel.obb_gap(&a.obbs[ci as usize], &b.obbs[cj as usize]);
            (ci, cj, d)
        });
        // nearer pair last so it is explored first
        if next[0].2 < next[1].2 {
            next.swap(0, 1);
        }
        stack.extend(next.into_iter().filter(|c| c.2 * grow < best));
    }
    Ok(best / grow)
}
