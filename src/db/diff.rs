//! What changed between two stored runs ([`Database::diff_runs`]): component poses and
//! dimensions of each run's last document snapshot, and the outcome of every path
//! stored under the same name. `fitup db diff A B` prints it; the library returns it
//! as data so a script or a tool can act on it.
//!
//! Units: millimetres and radians.

use super::{Database, DbError, PathQuery, RunRecord, StoredPath};
use crate::document::DimensionKind;

/// How far a component must move (mm) to count as moved: the round trip through the
/// database's columns is exact to far better than this.
pub const MOVED_MM: f64 = 1e-6;

/// How far a component must turn (rad) to count as turned.
pub const TURNED_RAD: f64 = 1e-9;

/// How far a dimension's value must change (mm or rad) to count as changed.
pub const DIMENSION_CHANGED: f64 = 1e-9;

/// The differences between two runs, `a` → `b`.
#[derive(Debug, Clone, PartialEq)]
pub struct RunDiff {
    /// The earlier run (as given).
    pub a: RunRecord,
    /// The later run (as given).
    pub b: RunRecord,
    /// Every difference found, in the order: components, dimensions, paths.
    pub changes: Vec<Change>,
}

/// Which of the two runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Side {
    /// The first run given.
    A,
    /// The second run given.
    B,
}

/// How a stored path ended: what is compared between the runs.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum PathOutcome {
    /// Found, with its key poses and length (mm).
    Found {
        /// The number of key poses.
        poses: usize,
        /// Length of the translation, mm.
        length_mm: f64,
    },
    /// Not found, and why (the planner's failure, for people).
    NotFound {
        /// The failure.
        cause: String,
    },
}

impl std::fmt::Display for PathOutcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PathOutcome::Found { poses, length_mm } => {
                write!(f, "found, {poses} key poses, {length_mm:.1} mm")
            }
            PathOutcome::NotFound { cause } => write!(f, "not found ({cause})"),
        }
    }
}

impl PathOutcome {
    fn of(p: &StoredPath) -> Self {
        match &p.path.failure {
            None => PathOutcome::Found {
                poses: p.pose_count,
                length_mm: p.path.length_mm,
            },
            Some(f) => PathOutcome::NotFound {
                cause: f.to_string(),
            },
        }
    }

    /// Whether two outcomes differ as people read them (lengths to 0.1 mm).
    fn differs(&self, other: &PathOutcome) -> bool {
        self.to_string() != other.to_string()
    }
}

/// One difference between two runs.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Change {
    /// A run has no document snapshot, so components and dimensions were not compared.
    NoSnapshot {
        /// The run without one.
        run: Side,
    },
    /// A component is in one run's snapshot only.
    ComponentOnlyIn {
        /// The component.
        name: String,
        /// The run that has it.
        run: Side,
    },
    /// A component stands elsewhere in `b`.
    ComponentMoved {
        /// The component.
        name: String,
        /// How far its origin moved, mm.
        distance_mm: f64,
        /// How far it turned, radians.
        angle_rad: f64,
    },
    /// A dimension has another value in `b`.
    DimensionChanged {
        /// The dimension's full name (`D1@角度1`).
        name: String,
        /// Length (mm) or angle (rad).
        kind: DimensionKind,
        /// The value in `a` (mm or rad).
        from: f64,
        /// The value in `b` (mm or rad).
        to: f64,
    },
    /// A path name is stored by one run only.
    PathOnlyIn {
        /// The name it was stored under.
        name: String,
        /// The run that stored it.
        run: Side,
    },
    /// A path stored by both runs ended differently (the last one of that name in `b`).
    PathChanged {
        /// The name it was stored under.
        name: String,
        /// How it ended in `a`.
        from: PathOutcome,
        /// How it ended in `b`.
        to: PathOutcome,
    },
}

impl Database {
    /// What changed from run `a` to run `b`: the poses and dimensions of each run's
    /// last document snapshot, and every path name's outcome.
    ///
    /// Fails with [`DbError::NotFound`] when a run does not exist.
    pub fn diff_runs(&mut self, a: i64, b: i64) -> Result<RunDiff, DbError> {
        let (ra, rb) = (self.run(a)?, self.run(b)?);
        let mut changes = Vec::new();
        let last = |v: Vec<(i64, super::Snapshot)>| v.into_iter().last().map(|(_, s)| s);
        match (
            last(self.snapshots(Some(a))?),
            last(self.snapshots(Some(b))?),
        ) {
            (Some(sa), Some(sb)) => {
                for (name, ta) in &sa.poses {
                    match sb.poses.iter().find(|(n, _)| n == name) {
                        None => changes.push(Change::ComponentOnlyIn {
                            name: name.clone(),
                            run: Side::A,
                        }),
                        Some((_, tb)) => {
                            let (angle_rad, distance_mm) = ta.distance_to(tb);
                            if distance_mm > MOVED_MM || angle_rad > TURNED_RAD {
                                changes.push(Change::ComponentMoved {
                                    name: name.clone(),
                                    distance_mm,
                                    angle_rad,
                                });
                            }
                        }
                    }
                }
                for (name, _) in sb
                    .poses
                    .iter()
                    .filter(|(n, _)| !sa.poses.iter().any(|(m, _)| m == n))
                {
                    changes.push(Change::ComponentOnlyIn {
                        name: name.clone(),
                        run: Side::B,
                    });
                }
                for (name, kind, from) in &sa.dimensions {
                    if let Some((_, _, to)) = sb.dimensions.iter().find(|(n, _, _)| n == name) {
                        if (from - to).abs() > DIMENSION_CHANGED {
                            changes.push(Change::DimensionChanged {
                                name: name.clone(),
                                kind: *kind,
                                from: *from,
                                to: *to,
                            });
                        }
                    }
                }
            }
            (None, _) => changes.push(Change::NoSnapshot { run: Side::A }),
            (Some(_), None) => changes.push(Change::NoSnapshot { run: Side::B }),
        }
        let q = |run| PathQuery {
            run_id: Some(run),
            without_poses: true,
            ..Default::default()
        };
        let (pa, pb) = (self.paths(&q(a))?, self.paths(&q(b))?);
        for p in &pa {
            match pb.iter().rev().find(|x| x.name == p.name) {
                None => changes.push(Change::PathOnlyIn {
                    name: p.name.clone(),
                    run: Side::A,
                }),
                Some(x) => {
                    let (from, to) = (PathOutcome::of(p), PathOutcome::of(x));
                    if from.differs(&to) {
                        changes.push(Change::PathChanged {
                            name: p.name.clone(),
                            from,
                            to,
                        });
                    }
                }
            }
        }
        for p in pb.iter().filter(|x| !pa.iter().any(|y| y.name == x.name)) {
            changes.push(Change::PathOnlyIn {
                name: p.name.clone(),
                run: Side::B,
            });
        }
        Ok(RunDiff {
            a: ra,
            b: rb,
            changes,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::db::{NewRun, RunStatus, Snapshot, Target};
    use crate::math::{Transform, Vec3};

    fn snapshot(x: f64, dim: f64, extra: bool) -> Snapshot {
        let mut poses = vec![(
            "peg".to_string(),
            Transform::from_translation(Vec3::new(x, 0.0, 0.0)),
        )];
        if extra {
            poses.push(("lid".into(), Transform::IDENTITY));
        }
        Snapshot {
            document: "cell.yaml".into(),
            poses,
            dimensions: vec![("D1@角度1".into(), DimensionKind::Angle, dim)],
        }
    }

    #[test]
    fn moves_dimensions_and_missing_components_are_found() {
        let dir = tempfile::tempdir().unwrap();
        let mut db = Database::open(&Target::Sqlite(dir.path().join("fitup.db"))).unwrap();
        let mut run = |s: Option<Snapshot>| {
            let id = db.start_run(&NewRun::script("scripts/a.rhai")).unwrap();
            if let Some(s) = s {
                db.save_snapshot(Some(id), &s).unwrap();
            }
            db.finish_run(id, RunStatus::Ok, "").unwrap();
            id
        };
        let a = run(Some(snapshot(0.0, 0.5, true)));
        let b = run(Some(snapshot(2.5, 0.75, false)));
        let c = run(None);
        let d = db.diff_runs(a, b).unwrap();
        assert_eq!(d.changes.len(), 3, "{:?}", d.changes);
        assert!(d.changes.iter().any(|c| matches!(c,
            Change::ComponentMoved { name, distance_mm, .. } if name == "peg" && (distance_mm - 2.5).abs() < 1e-9)));
        assert!(d.changes.contains(&Change::ComponentOnlyIn {
            name: "lid".into(),
            run: Side::A
        }));
        assert!(d.changes.iter().any(|c| matches!(c,
            Change::DimensionChanged { from, to, .. } if *from == 0.5 && *to == 0.75)));
        assert!(db.diff_runs(a, a).unwrap().changes.is_empty());
        assert_eq!(
            db.diff_runs(a, c).unwrap().changes,
            vec![Change::NoSnapshot { run: Side::B }]
        );
        assert!(matches!(
            db.diff_runs(a, 999),
            Err(DbError::NotFound { .. })
        ));
    }
}
