//! Benchmark planning problems generated in code (meshes, obstacle poses, start,
//! goal, bounds), also committed as documents under `models/problems/`.
//!
//! | problem | what makes it hard |
//! |---|---|
//! | [`peg_in_hole`] | Ø20 peg into a 60 mm deep blind hole, radial clearance 0.5 or 0.1 mm |
//! | [`piston_rod_cap`] | seed 002's experiment: a cap leaves its seat through a 0.5 mm channel and slot, 500 mm cube |
//! | [`screw_cell`] | seed 000 fig. 11: a screw from the table into a plate hole (0.5 mm) |
//! | [`ring_puzzle`] | two interlocked rings; the slit ring's gap is 10 % wider than the other's wire |
//! | [`rod_corner`] | a rod twice as long as the corridor is wide turns a right-angle corner under a ceiling |
//! | [`bar_slot`] | a flat bar turns 90° to pass a slot 0.3 mm wider than itself, then turns back |
//! | [`peg_tilt`] | a peg taller than a window enters lying, stands up inside and drops into a 0.2 mm hole |
//! | [`key_ring`] | a small ring threaded on a two-turn split key ring: out only along the spiral |
//! | [`rod_corridor`] | a 12 mm rod turns the corner of a 7 mm corridor under a 5 mm ceiling, near the ladder limit |
//! | [`zigzag_tunnel`] | the same rod through a 7 mm tunnel with four 90° bends, left and right |
//!
//! Test scaffolding, not part of the library: users get the problems as files
//! (`models/problems/<name>.yaml` + `.plan.json`, read with
//! `fitup::planning::ProblemFile`). Included with `#[path]` by
//! `tests/it/planning_problems.rs` (which rewrites the files with `FITUP_BLESS=1`) and
//! the planning benchmark. Lengths in mm, angles in radians.

#![allow(dead_code)]

use fitup::collision::{Collider, CollisionError, SweepMethod};
use fitup::document::file::{ComponentFile, DocumentFile, PartFile};
use fitup::math::{Aabb, Point3, Transform, Vec3};
use fitup::mesh::{write_stl, Mesh, MeshError};
use fitup::planning::{
    plan_insertion, InsertionOptions, MeshValidator, MeshValidatorOptions, PlanError, PlannedPath,
    PlanningSpace,
};
use indexmap::IndexMap;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::path::Path as FsPath;
use std::sync::Arc;

/// A generator's own error (no file, no line).
fn invalid(message: impl Into<String>) -> MeshError {
    MeshError::new(fitup::mesh::MeshErrorKind::Malformed, message)
}

/// Obstacle colliders with their poses (part frame → assembly frame).
pub type PosedColliders = Vec<(Arc<Collider>, Transform)>;

/// A fixed part of a problem.
#[derive(Debug, Clone)]
pub struct ProblemObstacle {
    /// Component name.
    pub name: String,
    /// Part (mesh) name; obstacles sharing a part share the mesh.
    pub part: String,
    /// The mesh in the part frame (mm).
    pub mesh: Arc<Mesh>,
    /// Part frame → assembly frame.
    pub pose: Transform,
}

/// A planning problem: one moving component among fixed ones.
#[derive(Debug, Clone)]
pub struct Problem {
    /// Short name, also the file stem under `models/problems/`.
    pub name: String,
    /// One line: what it is and its clearances.
    pub description: String,
    /// Part name of the moving component.
    pub moving_part: String,
    /// Mesh of the moving component (component frame, mm).
    pub moving: Arc<Mesh>,
    /// The fixed components.
    pub obstacles: Vec<ProblemObstacle>,
    /// Start pose of the moving component (assembly frame).
    pub start: Transform,
    /// Goal pose of the moving component (assembly frame).
    pub goal: Transform,
    /// Translation bounds, rotation freedom and metric.
    pub space: PlanningSpace,
    /// The product's box (assembly frame): disassembly ends when the component's
    /// box leaves it.
    pub product_box: Aabb,
}

/// Why a problem could not be built, written or solved.
#[derive(Debug, thiserror::Error)]
pub enum ProblemError {
    /// A generated mesh is invalid.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// Writing the files failed.
    #[error("{0}")]
    Io(String),
}

impl Problem {
    /// The moving component's box in its own frame (mm).
    pub fn part_box(&self) -> Aabb {
        self.moving
            .bounds()
            .unwrap_or(Aabb::new(Point3::origin(), Point3::origin()))
    }

    /// Colliders of the moving part and the obstacles (one per distinct part).
    pub fn colliders(&self) -> Result<(Arc<Collider>, PosedColliders), CollisionError> {
        let mut cache = fitup::collision::ColliderCache::new();
        let moving = cache.get(&self.moving)?;
        let obstacles = self
            .obstacles
            .iter()
            .map(|o| Ok((cache.get(&o.mesh)?, o.pose)))
            .collect::<Result<Vec<_>, CollisionError>>()?;
        Ok((moving, obstacles))
    }

    /// A [`MeshValidator`] for the problem.
    pub fn validator(
        &self,
        options: MeshValidatorOptions,
    ) -> Result<MeshValidator, CollisionError> {
        let (moving, obstacles) = self.colliders()?;
        MeshValidator::new(moving, obstacles, options)
    }

    /// The validator options the benchmarks and tests use: exact interference with
    /// the default tolerance, continuous edges ([`SweepMethod::CONTINUOUS`]).
    pub fn default_validator_options(&self) -> MeshValidatorOptions {
        MeshValidatorOptions::default()
    }

    /// Stepwise edges at 0.05 mm / (0.05 mm ÷ the part's radius), so no point of the
    /// part moves more than about 0.1 mm between checks: the resolution the OMPL
    /// peer's validity checker is given in the benchmark.
    pub fn stepwise_validator_options(&self) -> MeshValidatorOptions {
        let radius = self
            .moving
            .vertices
            .iter()
            .map(|v| v.coords.norm())
            .fold(1.0, f64::max);
        MeshValidatorOptions {
            edge: SweepMethod::Stepwise {
                step_mm: 0.05,
                step_rad: 0.05 / radius,
            },
            ..Default::default()
        }
    }

    /// Solves the problem with [`plan_insertion`] and `options`.
    ///
    /// # Errors
    /// Only for invalid options.
    pub fn solve_with(
        &self,
        validator: &mut MeshValidator,
        options: &InsertionOptions,
    ) -> Result<PlannedPath, PlanError> {
        plan_insertion(
            validator,
            &self.space,
            &self.start,
            &self.goal,
            &self.part_box(),
            &self.product_box,
            options,
            None,
        )
    }

    /// The problem as a document (moving component at its start pose, named
    /// `moving`; meshes `meshes/<name>_<part>.stl`).
    pub fn document(&self) -> DocumentFile {
        let part = |p: &str| PartFile::from_stl(format!("meshes/{}_{p}.stl", self.name));
        let mut parts = IndexMap::new();
        parts.insert(self.moving_part.clone(), part(&self.moving_part));
        for o in &self.obstacles {
            parts.entry(o.part.clone()).or_insert_with(|| part(&o.part));
        }
        let mut components: Vec<ComponentFile> = self
            .obstacles
            .iter()
            .map(|o| ComponentFile {
                fixed: true,
                color: Some(serde_yaml::Value::String("#8c8c8c".into())),
                ..ComponentFile::new(&o.name, &o.part, Some(o.pose.to_matrix()))
            })
            .collect();
        components.push(ComponentFile {
            color: Some(serde_yaml::Value::String("#d4a72c".into())),
            ..ComponentFile::new("moving", &self.moving_part, Some(self.start.to_matrix()))
        });
        DocumentFile {
            units: "mm".into(),
            description: Some(self.description.clone()),
            mesh_deflection: None,
            parts,
            components,
            mates: vec![],
            robots: vec![],
            equations: vec![],
            assemblies: vec![],
        }
    }

    /// The planning data (start, goal, bounds, product box, rotation weight) as
    /// JSON; poses as translation (mm) + unit quaternion `[w, x, y, z]` acting on
    /// column vectors (`p' = R p + t`).
    pub fn plan_json(&self) -> serde_json::Value {
        let pose = |t: &Transform| {
            let iso = t.isometry();
            let q = iso.rotation;
            serde_json::json!({
                "t": [iso.translation.x, iso.translation.y, iso.translation.z],
                "q": [q.w, q.i, q.j, q.k],
            })
        };
        serde_json::json!({
            "name": self.name,
            "description": self.description,
            "document": format!("{}.yaml", self.name),
            "moving_component": "moving",
            "start": pose(&self.start),
            "goal": pose(&self.goal),
            "bounds_min": self.space.min.as_slice(),
            "bounds_max": self.space.max.as_slice(),
            "rotation_weight_mm_per_rad": self.space.rotation_weight,
            "product_box_min": self.product_box.lo.coords.as_slice(),
            "product_box_max": self.product_box.hi.coords.as_slice(),
        })
    }

    /// Writes `dir/<name>.yaml`, `dir/<name>.plan.json` and
    /// `dir/meshes/<name>_<part>.stl` (atomically).
    ///
    /// # Errors
    /// File system errors, unwritable meshes.
    pub fn write(&self, dir: &FsPath) -> Result<(), ProblemError> {
        let io = |e: std::io::Error| ProblemError::Io(e.to_string());
        std::fs::create_dir_all(dir.join("meshes")).map_err(io)?;
        let stl = |p: &str| dir.join(format!("meshes/{}_{p}.stl", self.name));
        write_stl(&stl(&self.moving_part), &self.moving)?;
        let mut written = std::collections::HashSet::new();
        for o in &self.obstacles {
            if written.insert(o.part.clone()) {
                write_stl(&stl(&o.part), &o.mesh)?;
            }
        }
        let yaml = self
            .document()
            .to_yaml()
            .map_err(|e| ProblemError::Io(e.to_string()))?;
        fitup::fsutil::write_atomic(&dir.join(format!("{}.yaml", self.name)), yaml.as_bytes())
            .map_err(io)?;
        let json = serde_json::to_string_pretty(&self.plan_json())
            .map_err(|e| ProblemError::Io(e.to_string()))?;
        fitup::fsutil::write_atomic(
            &dir.join(format!("{}.plan.json", self.name)),
            format!("{json}\n").as_bytes(),
        )
        .map_err(io)?;
        Ok(())
    }
}

fn obstacle(name: &str, part: &str, mesh: Mesh, pose: Transform) -> ProblemObstacle {
    ProblemObstacle {
        name: name.into(),
        part: part.into(),
        mesh: Arc::new(mesh),
        pose,
    }
}

fn at(x: f64, y: f64, z: f64) -> Transform {
    Transform::from_translation(Vec3::new(x, y, z))
}

fn boxed(lo: [f64; 3], hi: [f64; 3]) -> Mesh {
    Mesh::cuboid(Point3::from(lo), Point3::from(hi))
}

/// A Ø20 × 100 mm peg (origin at the centre of its bottom face, axis +Z) into a
/// blind hole of radius `10 + clearance` and 60 mm depth in a Ø80 × 70 mm block
/// (64 facets around: the smallest gap between the polygons is
/// `(10 + clearance)·cos(π/64) − 10`, 0.49 mm for 0.5, 0.09 mm for 0.1). Start: the
/// peg lying on its side 120 mm away; goal: resting on the floor of the hole.
///
/// # Errors
/// A clearance that is not finite and in `(0, 20)` mm.
pub fn peg_in_hole(clearance: f64) -> Result<Problem, MeshError> {
    if !(clearance.is_finite() && clearance > 0.0 && clearance < 20.0) {
        return Err(invalid("the peg-in-hole clearance must be in (0, 20) mm"));
    }
    let r = 10.0 + clearance;
    let block = Mesh::lathe(
        &[
            (0.0, 0.0),
            (40.0, 0.0),
            (40.0, 70.0),
            (r, 70.0),
            (r, 10.0),
            (0.0, 10.0),
        ],
        64,
    )?;
    let peg = Mesh::cylinder(10.0, 100.0, 64);
    let lying = turn(Vec3::y(), FRAC_PI_2)?;
    let name = format!("peg_in_hole_{}", (clearance * 1000.0).round() as i64);
    Ok(Problem {
        description: format!(
            "Peg in hole: Ø20 × 100 mm peg into a 60 mm deep blind hole, {clearance} mm radial clearance"
        ),
        name,
        moving_part: "peg".into(),
        moving: Arc::new(peg),
        obstacles: vec![obstacle("block", "block", block, Transform::IDENTITY)],
        start: lying.then(&at(120.0, 30.0, 60.0)),
        goal: at(0.0, 0.0, 10.0),
        space: PlanningSpace::new(Vec3::new(-200.0, -200.0, 0.0), Vec3::new(200.0, 200.0, 250.0))
            .with_rotation_weight(50.0),
        product_box: Aabb::new(Vec3::new(-40.0, -40.0, 0.0), Vec3::new(40.0, 40.0, 70.0)),
    })
}

/// Seed 002's experiment, simplified: a piston-rod cap (Ø60 × 20 mm disc with a
/// Ø30 × 15 mm boss) seated in a housing in the 0..500 mm cube. The seat is a
/// channel 61 mm wide and 20.5 mm high (0.5 mm clearance around the disc) under a
/// cover plate whose slot is 31 mm wide (0.5 mm around the boss): the cap can only
/// leave by sliding 130 mm along +X before it can lift. Start: above the housing,
/// turned; goal: seated.
///
/// # Errors
/// None in practice (the generated meshes are valid).
pub fn piston_rod_cap() -> Result<Problem, MeshError> {
    let cap = Mesh::lathe(
        &[
            (0.0, 0.0),
            (30.0, 0.0),
            (30.0, 20.0),
            (15.0, 20.0),
            (15.0, 35.0),
            (0.0, 35.0),
        ],
        48,
    )?;
    let (x0, x1, y0, y1) = (150.0, 350.0, 190.0, 310.0);
    let (floor, top, cover) = (200.0, 220.5, 235.0);
    let pieces = [
        ("floor", [x0, y0, 180.0], [x1, y1, floor]),
        ("wall_left", [x0, y0, floor], [x1, 219.5, top]),
        ("wall_right", [x0, 280.5, floor], [x1, y1, top]),
        ("back", [x0, 219.5, floor], [219.5, 280.5, top]),
        ("cover_left", [x0, y0, top], [x1, 234.5, cover]),
        ("cover_right", [x0, 265.5, top], [x1, y1, cover]),
        ("cover_back", [x0, 234.5, top], [234.5, 265.5, cover]),
    ];
    let obstacles = pieces
        .iter()
        .map(|(n, lo, hi)| obstacle(n, n, boxed(*lo, *hi), Transform::IDENTITY))
        .collect();
    let turned = Transform::from_xyzabc(
        Vec3::new(250.0, 250.0, 380.0),
        [0.4, -0.3, 0.8],
        Default::default(),
    );
    Ok(Problem {
        name: "piston_rod_cap".into(),
        description: "Seed 002 experiment (simplified): piston-rod cap into a seat with 0.5 mm clearances, 500 mm cube".into(),
        moving_part: "cap".into(),
        moving: Arc::new(cap),
        obstacles,
        start: turned,
        goal: at(250.0, 250.0, floor),
        space: PlanningSpace::new(Vec3::zeros(), Vec3::repeat(500.0)).with_rotation_weight(35.0),
        product_box: Aabb::new(Vec3::new(x0, y0, 180.0), Vec3::new(x1, y1, cover)),
    })
}

/// Seed 000's fig. 11 cell: screw 4 goes from the table into plate B's first hole
/// (radius 4.5 mm around the r = 4 mm shank: 0.5 mm clearance); the table, both
/// plates, the three seated screws of plate A and screw 5 are obstacles. Start and
/// goal rest on the table (touching).
///
/// # Errors
/// None in practice (the generated meshes are valid).
pub fn screw_cell() -> Result<Problem, MeshError> {
    use fitup::demo::{screw_mesh, table_mesh, HOLE_RADIUS, PLATE_THICKNESS, TABLE_TOP};
    let screw = Arc::new(screw_mesh()?);
    let plate_a = Mesh::perforated_plate(3, 2, 100.0, PLATE_THICKNESS, HOLE_RADIUS, 8, |i, j| {
        [(0, 0), (1, 1), (2, 0)].contains(&(i, j))
    })?;
    let plate_b = Mesh::perforated_plate(2, 2, 100.0, PLATE_THICKNESS, HOLE_RADIUS, 8, |i, j| {
        [(0, 0), (1, 1)].contains(&(i, j))
    })?;
    let mut obstacles = vec![
        obstacle("table", "table", table_mesh(), Transform::IDENTITY),
        obstacle("plate_a", "plate_a", plate_a, at(100.0, 150.0, TABLE_TOP)),
        obstacle("plate_b", "plate_b", plate_b, at(700.0, 300.0, TABLE_TOP)),
    ];
    for (k, (x, y)) in [(150.0, 200.0), (250.0, 300.0), (350.0, 200.0)]
        .into_iter()
        .enumerate()
    {
        obstacles.push(ProblemObstacle {
            name: format!("screw{}", k + 1),
            part: "screw".into(),
            mesh: screw.clone(),
            pose: at(x, y, TABLE_TOP),
        });
    }
    obstacles.push(ProblemObstacle {
        name: "screw5".into(),
        part: "screw".into(),
        mesh: screw.clone(),
        pose: at(650.0, 650.0, TABLE_TOP),
    });
    Ok(Problem {
        name: "screw_cell".into(),
        description: "Seed 000 fig. 11 cell: screw 4 from the table into plate B's hole (0.5 mm radial clearance)".into(),
        moving_part: "screw".into(),
        moving: screw,
        obstacles,
        start: at(600.0, 650.0, TABLE_TOP),
        goal: at(750.0, 350.0, TABLE_TOP),
        space: PlanningSpace::new(
            Vec3::new(0.0, 0.0, TABLE_TOP),
            Vec3::new(1200.0, 800.0, TABLE_TOP + 250.0),
        )
        .with_rotation_weight(15.0),
        product_box: Aabb::new(
            Vec3::new(700.0, 300.0, TABLE_TOP),
            Vec3::new(900.0, 500.0, TABLE_TOP + PLATE_THICKNESS),
        ),
    })
}

/// A tube of `nv` facets around, swept along a curve: `point(t, v)` is the surface
/// point at curve parameter `t` and angle `v` around the wire, `centre(t)` the
/// curve point (for the end caps). `n` facets along, from `t0` over `span`;
/// `closed`: the tube joins itself (no caps), else flat end caps close it.
/// Outward-oriented whatever the parametrisation's handedness.
fn swept_tube(
    point: impl Fn(f64, f64) -> Point3,
    centre: impl Fn(f64) -> Point3,
    (t0, span): (f64, f64),
    n: usize,
    nv: usize,
    closed: bool,
) -> Result<Mesh, MeshError> {
    let rows = if closed { n } else { n + 1 };
    let at = |i: usize| t0 + span * i as f64 / n as f64;
    let mut vertices = Vec::with_capacity(rows * nv + 2);
    for i in 0..rows {
        for j in 0..nv {
            vertices.push(point(at(i), TAU * j as f64 / nv as f64));
        }
    }
    let idx = |i: usize, j: usize| ((i % rows) * nv + j % nv) as u32;
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..nv {
            let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    if !closed {
        // each cap runs its boundary edges opposite to the tube's
        for (i, t, first) in [(0usize, t0, true), (n, t0 + span, false)] {
            let c = vertices.len() as u32;
            vertices.push(centre(t));
            for j in 0..nv {
                triangles.push(if first {
                    [c, idx(i, j), idx(i, j + 1)]
                } else {
                    [c, idx(i, j + 1), idx(i, j)]
                });
            }
        }
    }
    let mut mesh = Mesh::new(vertices, triangles)?;
    mesh.orient_outward();
    Ok(mesh)
}

/// A ring of centre radius `big` and wire radius `wire` in its XY plane around the
/// origin, leaving out the angles within `gap / 2` of +X (0: a closed torus; > 0:
/// a slit ring closed by flat end caps). `nu` facets along, `nv` around the wire.
fn ring(big: f64, wire: f64, gap: f64, nu: usize, nv: usize) -> Result<Mesh, MeshError> {
    let closed = gap <= 0.0;
    let range = if closed {
        (0.0, TAU)
    } else {
        (gap / 2.0, TAU - gap)
    };
    swept_tube(
        |u, v| {
            let rr = big + wire * v.cos();
            Point3::new(rr * u.cos(), rr * u.sin(), wire * v.sin())
        },
        |u| Point3::new(big * u.cos(), big * u.sin(), 0.0),
        range,
        nu,
        nv,
        closed,
    )
}

/// Two interlocked rings (centre radius 30 mm, wire radius 3 mm): the fixed one in
/// the XY plane, the moving one in the XZ plane through its centre, with a slit
/// whose narrowest width (at the inner edge) is 6.6 mm, 10 % wider than the 6 mm
/// wire. Out only by threading the fixed wire through the slit: coordinated
/// rotation and translation. Start: interlocked; goal: apart, 150 mm away.
///
/// # Errors
/// None in practice (the generated meshes are valid).
pub fn ring_puzzle() -> Result<Problem, MeshError> {
    let (big, wire): (f64, f64) = (30.0, 3.0);
    let slit = 1.10 * 2.0 * wire;
    let gap = 2.0 * (slit / (2.0 * (big - wire))).asin();
    let fixed = ring(big, wire, 0.0, 96, 16)?;
    let slit_ring = ring(big, wire, gap, 96, 16)?;
    let upright = turn(Vec3::x(), FRAC_PI_2)?;
    // The slit faces away from the fixed ring's wire (local +X → world -X side turned).
    let start = turn(Vec3::z(), PI / 2.0)?
        .then(&upright)
        .then(&at(big, 0.0, 0.0));
    Ok(Problem {
        name: "ring_puzzle".into(),
        description: format!(
            "Ring puzzle: two interlocked rings (R 30, wire r 3 mm); the moving ring's slit is {slit:.1} mm wide"
        ),
        moving_part: "slit_ring".into(),
        moving: Arc::new(slit_ring),
        obstacles: vec![obstacle("ring", "ring", fixed, Transform::IDENTITY)],
        start,
        goal: upright.then(&at(150.0, 0.0, 0.0)),
        space: PlanningSpace::new(Vec3::repeat(-120.0), Vec3::repeat(200.0))
            .with_rotation_weight(33.0),
        product_box: Aabb::new(
            Vec3::new(-big - wire, -big - wire, -wire),
            Vec3::new(big + wire, big + wire, wire),
        ),
    })
}

/// A rotation by `angle` (rad) about `axis` through the origin.
fn turn(axis: Vec3, angle: f64) -> Result<Transform, MeshError> {
    Transform::from_rotation_about(Point3::origin(), axis, angle)
        .map_err(|e| invalid(e.to_string()))
}

/// A rod round a corner: a Ø6 × 40 mm rod (origin at its centre, axis X) in an
/// L-shaped corridor 20 mm wide and 12 mm high (floor, ceiling, outer walls and the
/// inner corner block). The rod is twice as long as the corridor is wide, so it
/// turns the corner only by rotating about Z while it moves. Start: in the X leg;
/// goal: in the Y leg.
///
/// # Errors
/// None in practice (the generated meshes are valid).
pub fn rod_corner() -> Result<Problem, MeshError> {
    let rod = Mesh::cylinder(3.0, 40.0, 24)
        .transformed(&at(0.0, 0.0, -20.0))
        .transformed(&turn(Vec3::y(), FRAC_PI_2)?);
    let (w, h) = (20.0, 12.0);
    let pieces = [
        ("floor", [-110.0, -5.0, -5.0], [w + 5.0, 130.0, 0.0]),
        ("ceiling", [-110.0, -5.0, h], [w + 5.0, 130.0, h + 5.0]),
        ("outer_south", [-110.0, -5.0, 0.0], [w + 5.0, 0.0, h]),
        ("outer_east", [w, 0.0, 0.0], [w + 5.0, 130.0, h]),
        ("inner", [-110.0, w, 0.0], [0.0, 130.0, h]),
    ];
    let obstacles = pieces
        .iter()
        .map(|(n, lo, hi)| obstacle(n, n, boxed(*lo, *hi), Transform::IDENTITY))
        .collect();
    Ok(Problem {
        name: "rod_corner".into(),
        description:
            "Rod round a corner: Ø6 × 40 mm rod, L-shaped corridor 20 mm wide and 12 mm high".into(),
        moving_part: "rod".into(),
        moving: Arc::new(rod),
        obstacles,
        start: at(-60.0, w / 2.0, h / 2.0),
        goal: turn(Vec3::z(), FRAC_PI_2)?.then(&at(w / 2.0, 80.0, h / 2.0)),
        space: PlanningSpace::new(Vec3::new(-90.0, 0.0, 0.0), Vec3::new(w, 110.0, h))
            .with_rotation_weight(20.0),
        product_box: Aabb::new(
            Vec3::new(-110.0, -5.0, -5.0),
            Vec3::new(w + 5.0, 130.0, h + 5.0),
        ),
    })
}

/// A flat bar through a slot: a 40 × 20 × 4 mm bar (origin at its centre, lying
/// flat) crosses a 5 mm wall through a vertical slot 4.3 × 20.3 mm, 0.3 mm wider
/// than the bar each way. It must roll 90° about its length to pass, then roll
/// back. Start and goal: lying flat on either side of the wall.
///
/// # Errors
/// None in practice (the generated meshes are valid).
pub fn bar_slot() -> Result<Problem, MeshError> {
    let bar = boxed([-20.0, -10.0, -2.0], [20.0, 10.0, 2.0]);
    let (sy, sz) = (4.3 / 2.0, 20.3 / 2.0);
    let (t, e) = (5.0, 90.0);
    let pieces = [
        ("wall_low", [0.0, -e, -e], [t, e, -sz]),
        ("wall_high", [0.0, -e, sz], [t, e, e]),
        ("wall_left", [0.0, -e, -sz], [t, -sy, sz]),
        ("wall_right", [0.0, sy, -sz], [t, e, sz]),
    ];
    let obstacles = pieces
        .iter()
        .map(|(n, lo, hi)| obstacle(n, n, boxed(*lo, *hi), Transform::IDENTITY))
        .collect();
    Ok(Problem {
        name: "bar_slot".into(),
        description: "Flat bar through a slot: 40 × 20 × 4 mm bar, slot 4.3 × 20.3 mm in a 5 mm wall: roll 90°, pass, roll back".into(),
        moving_part: "bar".into(),
        moving: Arc::new(bar),
        obstacles,
        start: at(-40.0, 0.0, 0.0),
        goal: at(45.0, 0.0, 0.0),
        space: PlanningSpace::new(Vec3::new(-60.0, -40.0, -40.0), Vec3::new(65.0, 40.0, 40.0))
            .with_rotation_weight(22.0),
        product_box: Aabb::new(Vec3::new(0.0, -e, -e), Vec3::new(t, e, e)),
    })
}

/// A peg that needs a tilt: a Ø20 × 30 mm peg (origin at the centre of its bottom
/// face, axis Z) enters a closed chamber through a window 30 mm wide and only
/// 25 mm high, so it must come in lying down, stand up inside (the chamber is 40 mm
/// high) and drop into a blind hole of radius 10.2 mm (0.2 mm clearance), 10 mm
/// deep, in the chamber floor. Start: lying outside the window; goal: in the hole.
///
/// # Errors
/// None in practice (the generated meshes are valid).
pub fn peg_tilt() -> Result<Problem, MeshError> {
    let peg = Mesh::cylinder(10.0, 30.0, 48);
    let (floor, top) = (20.0, 60.0);
    let base = Mesh::lathe(
        &[
            (0.0, 0.0),
            (62.0, 0.0),
            (62.0, floor),
            (10.2, floor),
            (10.2, floor - 10.0),
            (0.0, floor - 10.0),
        ],
        48,
    )?;
    let (win_y, win_z) = (15.0, floor + 25.0);
    let pieces = [
        ("roof", [-45.0, -45.0, top], [45.0, 45.0, top + 5.0]),
        ("wall_back", [-45.0, -45.0, floor], [-40.0, 45.0, top]),
        ("wall_south", [-40.0, -45.0, floor], [40.0, -40.0, top]),
        ("wall_north", [-40.0, 40.0, floor], [40.0, 45.0, top]),
        ("front_left", [40.0, -45.0, floor], [45.0, -win_y, top]),
        ("front_right", [40.0, win_y, floor], [45.0, 45.0, top]),
        ("front_lintel", [40.0, -win_y, win_z], [45.0, win_y, top]),
    ];
    let mut obstacles = vec![obstacle("base", "base", base, Transform::IDENTITY)];
    obstacles.extend(
        pieces
            .iter()
            .map(|(n, lo, hi)| obstacle(n, n, boxed(*lo, *hi), Transform::IDENTITY)),
    );
    let lying = turn(Vec3::y(), FRAC_PI_2)?;
    Ok(Problem {
        name: "peg_tilt".into(),
        description: "Peg that needs a tilt: Ø20 × 30 mm peg through a 25 mm high window, stood up inside a 40 mm high chamber, into a hole with 0.2 mm clearance".into(),
        moving_part: "peg".into(),
        moving: Arc::new(peg),
        obstacles,
        start: lying.then(&at(90.0, 0.0, floor + 11.0)),
        goal: at(0.0, 0.0, floor - 10.0),
        space: PlanningSpace::new(Vec3::new(-40.0, -40.0, floor - 10.0), Vec3::new(120.0, 40.0, top))
            .with_rotation_weight(18.0),
        product_box: Aabb::new(Vec3::new(-62.0, -62.0, 0.0), Vec3::new(62.0, 62.0, top + 5.0)),
    })
}

/// A closed tube of wire radius `wire` along the helix of radius `radius` and
/// `pitch` (mm per turn) around +Z, `turns` turns from angle 0, capped flat at
/// both ends; `nu` facets per turn along, `nv` around the wire.
fn helix_tube(
    radius: f64,
    pitch: f64,
    turns: f64,
    wire: f64,
    nu: usize,
    nv: usize,
) -> Result<Mesh, MeshError> {
    let n = ((nu as f64) * turns).ceil().max(2.0) as usize;
    swept_tube(
        |t, v| {
            let (centre, tangent) = helix_frame(radius, pitch, t);
            let normal = Vec3::new(t.cos(), t.sin(), 0.0);
            let binormal = tangent.cross(&normal);
            centre + (normal * v.cos() + binormal * v.sin()) * wire
        },
        |t| helix_frame(radius, pitch, t).0,
        (0.0, TAU * turns),
        n,
        nv,
        false,
    )
}

/// The point and unit tangent of the helix of radius `radius` and `pitch` (mm per
/// turn) around +Z at angle `t` (rad, from +X).
fn helix_frame(radius: f64, pitch: f64, t: f64) -> (Point3, Vec3) {
    let lead = pitch / TAU;
    (
        Point3::new(radius * t.cos(), radius * t.sin(), lead * t),
        Vec3::new(-radius * t.sin(), radius * t.cos(), lead).normalize(),
    )
}

/// A twisted puzzle in the spirit of the alpha puzzle: a split key ring (helix of
/// radius 15 mm, pitch 7.6 mm, two turns, wire radius 1.5 mm) holds a small closed
/// ring (centre radius 4.5 mm, wire radius 1 mm) threaded on it one turn from its
/// end. The ring comes off only by following the spiral — turning with its tangent
/// while it climbs — with its wire passing between the key ring's turns (4.6 mm
/// apart) and the neighbouring turn clearing its rim by about 0.6 mm. Start:
/// threaded; goal: free, 60 mm away.
///
/// # Errors
/// None in practice (the generated meshes are valid).
pub fn key_ring() -> Result<Problem, MeshError> {
    let (radius, pitch, turns) = (15.0, 7.6, 2.0);
    let spiral = helix_tube(radius, pitch, turns, 1.5, 64, 12)?;
    let small = ring(4.5, 1.0, 0.0, 32, 10)?;
    // On the spiral one turn from its end: centre on the wire, ring plane normal
    // to the wire's tangent (the ring's axis Z along the tangent).
    let t0 = TAU * (turns - 1.0);
    let (on_wire, tangent) = helix_frame(radius, pitch, t0);
    let align = Transform::from_parts(
        Vec3::zeros(),
        nalgebra::UnitQuaternion::rotation_between(&Vec3::z(), &tangent)
            .ok_or_else(|| invalid("degenerate key ring tangent"))?,
    );
    let start = align.then(&Transform::from_translation(on_wire.coords));
    Ok(Problem {
        name: "key_ring".into(),
        description: "Key ring: a ring (R 4.5, wire r 1 mm) threaded on a two-turn split key ring (R 15, pitch 7.6, wire r 1.5 mm), off only along the spiral".into(),
        moving_part: "small_ring".into(),
        moving: Arc::new(small),
        obstacles: vec![obstacle("key_ring", "key_ring", spiral, Transform::IDENTITY)],
        start,
        goal: at(75.0, 0.0, 8.0),
        space: PlanningSpace::new(Vec3::new(-30.0, -30.0, -20.0), Vec3::new(90.0, 30.0, 35.0))
            .with_rotation_weight(6.0),
        product_box: Aabb::new(Vec3::new(-16.5, -16.5, -1.5), Vec3::new(16.5, 16.5, 16.7)),
    })
}

/// Boxes merged into one mesh (no vertex merging: each box stays a closed shell).
fn boxes(pieces: &[([f64; 3], [f64; 3])]) -> Mesh {
    let mut m = boxed(pieces[0].0, pieces[0].1);
    for (lo, hi) in &pieces[1..] {
        m.append(&boxed(*lo, *hi));
    }
    m
}

/// A frame in the plane x = `x0 .. x1` around a rectangular hole `±hy × ±hz` (mm),
/// outer half-size `e` (the side boxes 1 mm less): four boxes in one mesh, turned
/// by `roll` (rad) about X.
fn holed_frame(x0: f64, x1: f64, hy: f64, hz: f64, e: f64, roll: f64) -> Result<Mesh, MeshError> {
    let m = boxes(&[
        ([x0, -e, -e], [x1, e, -hz]),
        ([x0, -e, hz], [x1, e, e]),
        // Inset 1 mm from the outer edge: no edge of one box coincides with an
        // edge of another, so the mesh stays manifold once STL merges vertices.
        ([x0, 1.0 - e, -hz], [x1, -hy, hz]),
        ([x0, hy, -hz], [x1, e - 1.0, hz]),
    ]);
    Ok(if roll == 0.0 {
        m
    } else {
        m.transformed(&turn(Vec3::x(), roll)?)
    })
}

/// Alpha-puzzle class: two interlocked twisted tubes. The fixed one is a helical
/// tube (radius 15 mm, pitch 24 mm, 1.5 turns, wire radius 2 mm); the moving one a
/// closed tube loop twisted out of its plane (centre radius 6.5 mm, ±1.5 mm
/// saddle, wire radius 1.5 mm) threaded on it 0.75 turns from either end. The loop
/// comes off only over an end, so the way out is a long screw-like motion:
/// ≈ 70 mm along the helix while turning 270° with its tangent. Start: threaded;
/// goal: free, beside the helix.
///
/// # Errors
/// None in practice (the generated meshes are valid).
pub fn twisted_tubes() -> Result<Problem, MeshError> {
    let (radius, pitch, turns) = (15.0, 24.0, 1.5);
    let helix = helix_tube(radius, pitch, turns, 2.0, 48, 12)?;
    let (r, a, wire): (f64, f64, f64) = (6.5, 1.5, 1.5);
    let centre = move |u: f64| Point3::new(r * u.cos(), r * u.sin(), a * (2.0 * u).sin());
    let twisted = swept_tube(
        move |u, v| {
            let tangent =
                Vec3::new(-r * u.sin(), r * u.cos(), 2.0 * a * (2.0 * u).cos()).normalize();
            let radial = Vec3::new(u.cos(), u.sin(), 0.0);
            let normal = (radial - tangent * radial.dot(&tangent)).normalize();
            let binormal = tangent.cross(&normal);
            centre(u) + (normal * v.cos() + binormal * v.sin()) * wire
        },
        centre,
        (0.0, TAU),
        48,
        10,
        true,
    )?;
    let t0 = TAU * 0.75;
    let (on_wire, tangent) = helix_frame(radius, pitch, t0);
    let align = Transform::from_parts(
        Vec3::zeros(),
        nalgebra::UnitQuaternion::rotation_between(&Vec3::z(), &tangent)
            .ok_or_else(|| invalid("degenerate helix tangent"))?,
    );
    Ok(Problem {
        name: "twisted_tubes".into(),
        description: "Alpha-puzzle class: a twisted tube loop (R 6.5, wire r 1.5 mm) threaded on a helical tube (R 15, pitch 24, 1.5 turns, wire r 2 mm), off only by a long screw-like motion".into(),
        moving_part: "loop".into(),
        moving: Arc::new(twisted),
        obstacles: vec![obstacle("helix", "helix", helix, Transform::IDENTITY)],
        start: align.then(&Transform::from_translation(on_wire.coords)),
        goal: at(55.0, 0.0, 18.0),
        space: PlanningSpace::new(Vec3::new(-35.0, -35.0, -15.0), Vec3::new(65.0, 35.0, 50.0))
            .with_rotation_weight(8.0),
        product_box: Aabb::new(Vec3::new(-17.0, -17.0, -2.0), Vec3::new(17.0, 17.0, 38.0)),
    })
}

/// Home class: a piano mover in a three-room house (rooms about 100 × 100 mm,
/// 40 mm high, under a ceiling). An L-shaped body (a 50 × 8 × 8 mm arm with a 22 mm
/// leg at one end: 30 mm across) goes from room A through a door 24 mm wide and
/// 34 mm high into room B, then through a second such door into room C: it fits a
/// door only rolled so that its leg stands up, and it must yaw 90° in room B.
/// Start: lying in room A; goal: lying in room C, turned 90°.
///
/// # Errors
/// None in practice (the generated meshes are valid).
pub fn house() -> Result<Problem, MeshError> {
    let body = boxes(&[
        ([-25.0, -4.0, -4.0], [25.0, 4.0, 4.0]),
        // 0.5 mm short of the arm's end: no shared edge once STL merges vertices
        ([17.0, 4.0, -4.0], [24.5, 26.0, 4.0]),
    ]);
    let (h, door_h) = (40.0, 34.0);
    let pieces: [(&str, [f64; 3], [f64; 3]); 15] = [
        ("floor", [-4.0, -4.0, -5.0], [204.0, 204.0, 0.0]),
        ("ceiling", [-4.0, -4.0, h], [204.0, 204.0, h + 5.0]),
        ("south", [-4.0, -4.0, 0.0], [204.0, 0.0, h]),
        ("west_a", [-4.0, 0.0, 0.0], [0.0, 102.0, h]),
        ("north_a", [-4.0, 98.0, 0.0], [98.0, 102.0, h]),
        ("west_c", [98.0, 98.0, 0.0], [102.0, 204.0, h]),
        ("north_c", [98.0, 200.0, 0.0], [204.0, 204.0, h]),
        ("east", [200.0, 0.0, 0.0], [204.0, 200.0, h]),
        // A | B at x = 98..102, door y = 38..62
        ("ab_south", [98.0, 0.0, 0.0], [102.0, 38.0, h]),
        ("ab_north", [98.0, 62.0, 0.0], [102.0, 98.0, h]),
        ("ab_lintel", [98.0, 38.0, door_h], [102.0, 62.0, h]),
        // B | C at y = 98..102, door x = 138..162
        ("bc_west", [102.0, 98.0, 0.0], [138.0, 102.0, h]),
        ("bc_east", [162.0, 98.0, 0.0], [200.0, 102.0, h]),
        ("bc_lintel", [138.0, 98.0, door_h], [162.0, 102.0, h]),
        ("corner", [98.0, 98.0, 0.0], [102.0, 102.0, h]),
    ];
    let obstacles = pieces
        .iter()
        .map(|(n, lo, hi)| obstacle(n, n, boxed(*lo, *hi), Transform::IDENTITY))
        .collect();
    Ok(Problem {
        name: "house".into(),
        description: "Home class: an L-shaped body (50 × 30 × 8 mm) through two doors 24 × 34 mm of a three-room house: roll to pass, yaw 90° between the doors".into(),
        moving_part: "l_body".into(),
        moving: Arc::new(body),
        obstacles,
        start: at(35.0, 40.0, 4.5),
        goal: turn(Vec3::z(), FRAC_PI_2)?.then(&at(170.0, 150.0, 4.5)),
        space: PlanningSpace::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(200.0, 200.0, h))
            .with_rotation_weight(25.0),
        product_box: Aabb::new(Vec3::new(-4.0, -4.0, -5.0), Vec3::new(204.0, 204.0, h + 5.0)),
    })
}

/// Twistycool class: a wall with a twisted narrow slot. The wall (26 mm thick) is
/// pierced by three slot sections 4 mm deep, each 21 × 5 mm, turned 0°, 45° and
/// 90° about the wall normal, joined by two chambers 7 mm deep and 26 mm square. A
/// 5 × 20 × 4 mm plate (0.5 mm clearance in every slot) passes a slot only aligned
/// with it and can turn only while wholly inside a chamber (1 mm of play along the
/// wall normal). Start and goal: either side of the wall, untwisted.
///
/// # Errors
/// None in practice (the generated meshes are valid).
pub fn twisted_slot() -> Result<Problem, MeshError> {
    let plate = boxed([-2.5, -10.0, -2.0], [2.5, 10.0, 2.0]);
    let (hy, hz, chamber) = (10.5, 2.5, 13.0);
    let q = std::f64::consts::FRAC_PI_4;
    let sections = [
        ("slot_0", holed_frame(0.0, 4.0, hy, hz, 40.0, 0.0)?),
        (
            "chamber_1",
            holed_frame(4.0, 11.0, chamber, chamber, 40.0, 0.0)?,
        ),
        ("slot_45", holed_frame(11.0, 15.0, hy, hz, 40.0, q)?),
        (
            "chamber_2",
            holed_frame(15.0, 22.0, chamber, chamber, 40.0, 0.0)?,
        ),
        ("slot_90", holed_frame(22.0, 26.0, hy, hz, 40.0, 2.0 * q)?),
        ("outer", holed_frame(0.0, 26.0, 28.0, 28.0, 90.0, 0.0)?),
    ];
    let obstacles = sections
        .into_iter()
        .map(|(n, m)| obstacle(n, n, m, Transform::IDENTITY))
        .collect();
    Ok(Problem {
        name: "twisted_slot".into(),
        description: "Twistycool class: a 5 × 20 × 4 mm plate through a slot 21 × 5 mm that turns 0°, 45°, 90° through a 26 mm wall (0.5 mm clearance, turning only in two 7 mm chambers)".into(),
        moving_part: "plate".into(),
        moving: Arc::new(plate),
        obstacles,
        start: at(-20.0, 0.0, 0.0),
        goal: at(46.0, 0.0, 0.0),
        space: PlanningSpace::new(Vec3::new(-30.0, -40.0, -40.0), Vec3::new(56.0, 40.0, 40.0))
            .with_rotation_weight(10.0),
        product_box: Aabb::new(Vec3::new(0.0, -90.0, -90.0), Vec3::new(26.0, 90.0, 90.0)),
    })
}

/// A plate hole reached by a straight line: a 20 × 20 × 30 mm square peg (origin
/// at the centre of its bottom face) goes down into a 20.4 × 20.4 mm square hole
/// through a 10 mm plate (0.2 mm clearance each side) until it stands 10 mm
/// through. The straight line from start (above, aligned) to goal is free.
///
/// # Errors
/// None in practice (the generated meshes are valid).
pub fn plate_hole() -> Result<Problem, MeshError> {
    let peg = boxed([-10.0, -10.0, 0.0], [10.0, 10.0, 30.0]);
    let h = 10.2;
    let plate = boxes(&[
        ([-50.0, -50.0, 0.0], [50.0, -h, 10.0]),
        ([-50.0, h, 0.0], [50.0, 50.0, 10.0]),
        ([-49.0, -h, 0.0], [-h, h, 10.0]),
        ([h, -h, 0.0], [49.0, h, 10.0]),
    ]);
    Ok(Problem {
        name: "plate_hole".into(),
        description: "Plate hole on a straight line: 20 × 20 mm square peg into a 20.4 mm square hole through a 10 mm plate (0.2 mm clearance), the straight line free".into(),
        moving_part: "peg".into(),
        moving: Arc::new(peg),
        obstacles: vec![obstacle("plate", "plate", plate, Transform::IDENTITY)],
        start: at(0.0, 0.0, 40.0),
        goal: at(0.0, 0.0, -10.0),
        space: PlanningSpace::new(Vec3::new(-80.0, -80.0, -40.0), Vec3::new(80.0, 80.0, 80.0))
            .with_rotation_weight(20.0),
        product_box: Aabb::new(Vec3::new(-50.0, -50.0, 0.0), Vec3::new(50.0, 50.0, 10.0)),
    })
}

/// The walls of a planar tunnel of height `h` (mm, z = 0 .. h) inside the region
/// `region` (x and y ranges), open where one of the axis-aligned rectangles
/// `corridors` (`([x0, x1], [y0, y1])`) is: the region minus the corridors cut on
/// the grid of all their edges, runs along X merged, each run one obstacle
/// (`{prefix}_wall_{k}`), plus a floor and a ceiling 3 mm thick. Separate meshes:
/// boxes that touch share no mesh, so every mesh stays a closed solid.
fn planar_tunnel(
    prefix: &str,
    region: ([f64; 2], [f64; 2]),
    corridors: &[([f64; 2], [f64; 2])],
    h: f64,
) -> Vec<ProblemObstacle> {
    let mut xs = vec![region.0[0], region.0[1]];
    let mut ys = vec![region.1[0], region.1[1]];
    for (cx, cy) in corridors {
        xs.extend(cx);
        ys.extend(cy);
    }
    for v in [&mut xs, &mut ys] {
        v.sort_by(f64::total_cmp);
        v.dedup();
    }
    let open = |x: f64, y: f64| {
        corridors
            .iter()
            .any(|(cx, cy)| x > cx[0] && x < cx[1] && y > cy[0] && y < cy[1])
    };
    let mut out = Vec::new();
    for j in 0..ys.len() - 1 {
        let y = 0.5 * (ys[j] + ys[j + 1]);
        let mut run: Option<f64> = None;
        for i in 0..xs.len() - 1 {
            let solid = !open(0.5 * (xs[i] + xs[i + 1]), y);
            match (solid, run) {
                (true, None) => run = Some(xs[i]),
                (false, Some(x0)) => {
                    let name = format!("{prefix}_wall_{}", out.len());
                    out.push(obstacle(
                        &name,
                        &name,
                        boxed([x0, ys[j], 0.0], [xs[i], ys[j + 1], h]),
                        Transform::IDENTITY,
                    ));
                    run = None;
                }
                _ => {}
            }
        }
        if let Some(x0) = run {
            let name = format!("{prefix}_wall_{}", out.len());
            out.push(obstacle(
                &name,
                &name,
                boxed([x0, ys[j], 0.0], [*xs.last().unwrap(), ys[j + 1], h]),
                Transform::IDENTITY,
            ));
        }
    }
    let (lo, hi) = ([region.0[0], region.1[0]], [region.0[1], region.1[1]]);
    for (name, z0, z1) in [("floor", -3.0, 0.0), ("ceiling", h, h + 3.0)] {
        let name = format!("{prefix}_{name}");
        out.push(obstacle(
            &name,
            &name,
            boxed([lo[0], lo[1], z0], [hi[0], hi[1], z1]),
            Transform::IDENTITY,
        ));
    }
    out
}

/// The rod of [`rod_corridor`] and [`zigzag_tunnel`]: Ø3 × 12 mm, origin at its
/// centre, axis X.
fn short_rod() -> Result<Mesh, MeshError> {
    Ok(Mesh::cylinder(1.5, 12.0, 24)
        .transformed(&at(0.0, 0.0, -6.0))
        .transformed(&turn(Vec3::y(), FRAC_PI_2)?))
}

/// Rod round a 7 mm corridor corner (issue 23's corridor class): a Ø3 × 12 mm rod
/// in an L-shaped corridor 7 mm wide and 5 mm high. The rod is 1.7 times as long
/// as the corridor is wide and cannot tilt much under the ceiling, so it passes
/// the corner only turning about Z while it moves, close to the ladder limit
/// (2·(√2·7 − 3) ≈ 13.8 mm for a 3 mm thick rod). Start: lying along the X leg;
/// goal: along the Y leg, turned 90°.
///
/// # Errors
/// None in practice (the generated meshes are valid).
pub fn rod_corridor() -> Result<Problem, MeshError> {
    let (w, h) = (7.0, 5.0);
    let c = w / 2.0;
    let obstacles = planar_tunnel(
        "corridor",
        ([-44.0, 8.0], [-8.0, 44.0]),
        &[([-40.0, c], [-c, c]), ([-c, c], [-c, 40.0])],
        h,
    );
    Ok(Problem {
        name: "rod_corridor".into(),
        description: "Rod round a 7 mm corridor corner: Ø3 × 12 mm rod, L-shaped corridor 7 mm wide and 5 mm high".into(),
        moving_part: "rod".into(),
        moving: Arc::new(short_rod()?),
        obstacles,
        start: at(-25.0, 0.0, h / 2.0),
        goal: turn(Vec3::z(), FRAC_PI_2)?.then(&at(0.0, 25.0, h / 2.0)),
        space: PlanningSpace::new(Vec3::new(-38.0, -c, 0.0), Vec3::new(c, 38.0, h))
            .with_rotation_weight(6.0),
        product_box: Aabb::new(Vec3::new(-44.0, -8.0, -3.0), Vec3::new(8.0, 44.0, h + 3.0)),
    })
}

/// Zigzag tunnel (issue 23's tunnel class): the Ø3 × 12 mm rod of
/// [`rod_corridor`] through a staircase tunnel 7 mm wide and 5 mm high that turns
/// left, right, left, right (legs 28, 21, 21, 21 and 28 mm between the bends'
/// centres), so the rod turns +90° and −90° about Z four times, each while it
/// moves. Start and goal: lying along X in the first and the last leg.
///
/// # Errors
/// None in practice (the generated meshes are valid).
pub fn zigzag_tunnel() -> Result<Problem, MeshError> {
    let (w, h) = (7.0, 5.0);
    let c = w / 2.0;
    // the centreline's bends: (28, 0), (28, 21), (49, 21), (49, 42)
    let corridors = [
        ([-6.0, 28.0 + c], [-c, c]),
        ([28.0 - c, 28.0 + c], [-c, 21.0 + c]),
        ([28.0 - c, 49.0 + c], [21.0 - c, 21.0 + c]),
        ([49.0 - c, 49.0 + c], [21.0 - c, 42.0 + c]),
        ([49.0 - c, 83.0], [42.0 - c, 42.0 + c]),
    ];
    let obstacles = planar_tunnel("tunnel", ([-10.0, 87.0], [-8.0, 50.0]), &corridors, h);
    Ok(Problem {
        name: "zigzag_tunnel".into(),
        description: "Zigzag tunnel: Ø3 × 12 mm rod through a staircase tunnel 7 mm wide and 5 mm high with four 90° bends, left and right".into(),
        moving_part: "rod".into(),
        moving: Arc::new(short_rod()?),
        obstacles,
        start: at(4.0, 0.0, h / 2.0),
        goal: at(75.0, 42.0, h / 2.0),
        space: PlanningSpace::new(Vec3::new(0.0, -c, 0.0), Vec3::new(77.0, 42.0 + c, h))
            .with_rotation_weight(6.0),
        product_box: Aabb::new(Vec3::new(-10.0, -8.0, -3.0), Vec3::new(87.0, 50.0, h + 3.0)),
    })
}

/// The standard rigid-body puzzle classes of issue 23, the ones fitup solves
/// first (so a benchmark cut short still has them): the twisted tubes, the house,
/// the plate hole on a straight line, the twisted slot, the slot roll
/// ([`bar_slot`]), then the rings with a slit ([`ring_puzzle`]), the rod round a
/// 7 mm corridor corner ([`rod_corridor`]) and the zigzag tunnel
/// ([`zigzag_tunnel`]).
///
/// # Errors
/// None in practice (the generated meshes are valid).
pub fn puzzles() -> Result<Vec<Problem>, MeshError> {
    Ok(vec![
        twisted_tubes()?,
        house()?,
        plate_hole()?,
        twisted_slot()?,
        bar_slot()?,
        ring_puzzle()?,
        rod_corridor()?,
        zigzag_tunnel()?,
    ])
}

/// Every benchmark problem: peg in hole at 0.5 and 0.1 mm, piston-rod cap, screw
/// cell, ring puzzle, rod round a corner, bar through a slot, peg that needs a
/// tilt, key ring, and the puzzles of [`puzzles`] not listed before.
///
/// # Errors
/// None in practice (the generated meshes are valid).
pub fn all() -> Result<Vec<Problem>, MeshError> {
    Ok(vec![
        peg_in_hole(0.5)?,
        peg_in_hole(0.1)?,
        piston_rod_cap()?,
        screw_cell()?,
        ring_puzzle()?,
        rod_corner()?,
        bar_slot()?,
        peg_tilt()?,
        key_ring()?,
        twisted_tubes()?,
        house()?,
        twisted_slot()?,
        plate_hole()?,
        rod_corridor()?,
        zigzag_tunnel()?,
    ])
}
