//! Sequences for real assemblies (issue 38): parts that interfere in the assembled
//! pose (a press fit, a part modelled through another) are fits, reported per pair,
//! not a reason to refuse; a linkage whose clearance joints leave every part more
//! than the contact gap from the others is held across its gaps. Each product is
//! generated here and every sequence returned is re-checked independently
//! (`tests/common/fit_check.rs`, shared with the STEP corpus test): the parts
//! are taken out in reverse order along their paths and straight on (0.25 mm
//! steps), each pose asked against every part placed before it — the exact
//! interference query at the default tolerance for a pair without a reported fit;
//! for a pair with one, a volume test on a grid of points (no point inside both the
//! moved part and the other that the assembled part does not hold: the overlap of
//! the assembled pose and nothing else); the reported fits must be exactly the pairs
//! that interfere in the assembled pose. A reported fit no deeper than `slide_fit_mm`
//! may instead slide: a pose that is the assembled one moved straight along `d`
//! passes when, on every line parallel to `d` (a grid of its own, cut by the meshes'
//! triangles directly, not by the library's colliders), each stretch of the moved
//! part overlaps only the stretches of the other it overlapped assembled, by no more
//! than assembled (within the tolerance).

use fitup::document::Document;
use fitup::math::{Point3, Transform, Vec3};
use fitup::mesh::Mesh;
use fitup::sequence::{plan_sequence, Mode, SequenceOptions, SequencePlan};
use fitup::workspace::SceneCache;
use std::path::{Path, PathBuf};

use crate::common::duct;
use crate::common::fit_check::{checker, dense_removal, fits_are_exact};

/// A closed ring (a tube section) about +Z: outer radius `big`, bore `small`, from
/// `z0` to `z1`, `n` facets around (the phase of [`Mesh::cylinder`]).
fn ring(big: f64, small: f64, z0: f64, z1: f64, n: usize) -> Mesh {
    let mut vertices = Vec::new();
    for (r, z) in [(big, z0), (big, z1), (small, z0), (small, z1)] {
        for i in 0..n {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            vertices.push(Point3::new(r * a.cos(), r * a.sin(), z));
        }
    }
    let n32 = n as u32;
    let (ob, ot, ib, it) = (0, n32, 2 * n32, 3 * n32);
    let mut triangles = Vec::new();
    for i in 0..n32 {
        let j = (i + 1) % n32;
        triangles.push([ob + i, ob + j, ot + j]);
        triangles.push([ob + i, ot + j, ot + i]);
        triangles.push([ib + i, it + j, ib + j]);
        triangles.push([ib + i, it + i, it + j]);
        triangles.push([ot + i, ot + j, it + j]);
        triangles.push([ot + i, it + j, it + i]);
        triangles.push([ob + i, ib + j, ob + j]);
        triangles.push([ob + i, ib + i, ib + j]);
    }
    Mesh::new(vertices, triangles).unwrap()
}

/// A cylinder of `radius` about +Z from `z0` to `z1`.
fn rod(radius: f64, z0: f64, z1: f64, n: usize) -> Mesh {
    Mesh::cylinder(radius, z1 - z0, n)
        .transformed(&Transform::from_translation(Vec3::new(0.0, 0.0, z0)))
}

fn cuboid(lo: [f64; 3], hi: [f64; 3]) -> Mesh {
    Mesh::cuboid(Point3::from(lo), Point3::from(hi))
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("fitup_fits_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write_doc(dir: &Path, parts: &[(&str, Mesh)]) -> Document {
    for (name, m) in parts {
        assert!(m.signed_volume() > 0.0, "{name} is outward");
    }
    Document::open(&duct::write_doc(dir, parts)).unwrap()
}

fn plan(doc: &Document, mode: Mode) -> SequencePlan {
    let o = SequenceOptions {
        mode,
        max_sequences: 3,
        ..SequenceOptions::default()
    };
    match plan_sequence(doc, &mut SceneCache::new(), &o) {
        Ok(p) => p,
        Err(e) => panic!("{mode:?}: {e}"),
    }
}

/// A ring of `n` points of radius `r` at height `z`, the first at angle `phase`.
fn circle(r: f64, n: usize, z: f64, phase: f64) -> Vec<Point3> {
    (0..n)
        .map(|i| {
            let a = phase + std::f64::consts::TAU * i as f64 / n as f64;
            Point3::new(r * a.cos(), r * a.sin(), z)
        })
        .collect()
}

/// Triangles joining two closed rings of points (any counts) by their angles about
/// +Z, each wound so its normal points along `outward(centroid)`: a faceted band
/// whose facets twist where the rings' points do not line up, as a CAD mesher's
/// do between edges meshed apart.
fn band(a: &[Point3], b: &[Point3], outward: impl Fn(&Point3) -> Vec3, out: &mut Vec<[Point3; 3]>) {
    let ang = |p: &Point3, wrapped: bool| {
        p.y.atan2(p.x).rem_euclid(std::f64::consts::TAU)
            + if wrapped { std::f64::consts::TAU } else { 0.0 }
    };
    let (na, nb) = (a.len(), b.len());
    let (mut i, mut j) = (0, 0);
    while i < na || j < nb {
        let next_a = if i < na {
            ang(&a[(i + 1) % na], i + 1 >= na)
        } else {
            f64::INFINITY
        };
        let next_b = if j < nb {
            ang(&b[(j + 1) % nb], j + 1 >= nb)
        } else {
            f64::INFINITY
        };
        let t = if next_a <= next_b {
            i += 1;
            [a[(i - 1) % na], a[i % na], b[j % nb]]
        } else {
            j += 1;
            [a[i % na], b[j % nb], b[(j - 1) % nb]]
        };
        let n = (t[1] - t[0]).cross(&(t[2] - t[0]));
        let c = Point3::from((t[0].coords + t[1].coords + t[2].coords) / 3.0);
        out.push(if n.dot(&outward(&c)) < 0.0 {
            [t[0], t[2], t[1]]
        } else {
            t
        });
    }
}

fn mesh_of(tris: &[[Point3; 3]]) -> Mesh {
    let vertices: Vec<Point3> = tris.iter().flatten().copied().collect();
    let triangles = (0..tris.len() as u32)
        .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
        .collect();
    Mesh::new(vertices, triangles).unwrap()
}

/// A rod of radius 5 through a 10 mm plate's bore of radius 5 (a line-to-line fit,
/// as CAD models a bolt in its clearance-free hole), each faceted the way Open
/// CASCADE meshes such faces: 12 points round one end and 16 (turned 0.2 rad) round
/// the other, so facets twist and the two meshes cross by up to the chord sag
/// 5·(1 − cos 15°) = 0.170 mm, by a different amount wherever the rod slides.
fn twisted_rod_in_bore() -> (Mesh, Mesh) {
    let radial = |c: &Point3| Vec3::new(c.x, c.y, 0.0);
    let inward = |c: &Point3| Vec3::new(-c.x, -c.y, 0.0);
    let (up, down) = (|_: &Point3| Vec3::z(), |_: &Point3| -Vec3::z());
    let mut plate = Vec::new();
    let (ob, ot) = (circle(20.0, 12, 0.0, 0.0), circle(20.0, 12, 10.0, 0.0));
    let (ib, it) = (circle(5.0, 16, 0.0, 0.2), circle(5.0, 12, 10.0, 0.0));
    band(&ob, &ot, radial, &mut plate);
    band(&ib, &it, inward, &mut plate);
    band(&ot, &it, up, &mut plate);
    band(&ob, &ib, down, &mut plate);
    let mut rod = Vec::new();
    let (rb, rt) = (circle(5.0, 12, -10.0, 0.0), circle(5.0, 16, 20.0, 0.2));
    band(&rb, &rt, radial, &mut rod);
    for (ring, z, n) in [(&rt, 20.0, Vec3::z()), (&rb, -10.0, -Vec3::z())] {
        let c = Point3::new(0.0, 0.0, z);
        for k in 0..ring.len() {
            let t = [c, ring[k], ring[(k + 1) % ring.len()]];
            let tn = (t[1] - t[0]).cross(&(t[2] - t[0]));
            rod.push(if tn.dot(&n) < 0.0 {
                [t[0], t[2], t[1]]
            } else {
                t
            });
        }
    }
    (mesh_of(&plate), mesh_of(&rod))
}

/// Issue 38, the as1 bolts: a rod in a bore of its diameter, both tessellated (twisted
/// facets, up to 0.17 mm from the exact cylinder), is blocked in every direction at
/// the default tolerance (its facets enter the bore's anew wherever it slides); with
/// the document's `mesh_deflection` (what `fitup import` writes) the checks judge no
/// finer than the meshes are known, and the rod comes out along its axis.
#[test]
fn a_tessellated_line_to_line_fit_slides_at_the_mesh_deflection() {
    let d = dir("twisted");
    let (plate, rod) = twisted_rod_in_bore();
    let doc = write_doc(&d, &[("plate", plate), ("rod", rod)]);
    assert_eq!(doc.mesh_deflection(), None);
    let o = SequenceOptions {
        mode: Mode::Geometry,
        ..SequenceOptions::default()
    };
    let e = plan_sequence(&doc, &mut SceneCache::new(), &o).unwrap_err();
    // The refusal names what blocks along the freest way out and the option.
    let e = e.to_string();
    assert!(e.contains("rod is blocked along all"), "{e}");
    assert!(
        e.contains("by plate only, which touches it where assembled")
            && e.contains("raise `tolerance`"),
        "{e}"
    );
    // The same document with the tessellation's deflection recorded.
    let yaml = doc.path().to_path_buf();
    let text = std::fs::read_to_string(&yaml).unwrap();
    std::fs::write(&yaml, format!("mesh_deflection: 0.18\n{text}")).unwrap();
    let doc = Document::open(&yaml).unwrap();
    assert_eq!(doc.mesh_deflection(), Some(0.18));
    let p = plan(&doc, Mode::Geometry);
    assert_eq!(p.tolerance, 0.18);
    let c = checker(&doc, &p);
    fits_are_exact(&c, &p);
    dense_removal(&c, &p);
    for s in &p.sequences {
        let t = &s.tasks[0];
        assert!(
            t.mating_direction.z.abs() > 1.0 - 1e-9,
            "{:?}",
            t.mating_direction
        );
    }
    // A mesh deflection that is not a length is refused where it is written.
    std::fs::write(&yaml, format!("mesh_deflection: -1\n{text}")).unwrap();
    let e = Document::open(&yaml).unwrap_err().to_string();
    assert!(e.contains(":1:") && e.contains("mesh_deflection"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_press_fit_is_a_fit_not_a_refusal() {
    let d = dir("press");
    // A pin 0.05 mm over its bore (on a 32-facet pin in a 32-facet bore: 0.05 mm of
    // radial interference everywhere), a washer with clearance on top.
    let doc = write_doc(
        &d,
        &[
            ("housing", ring(20.0, 5.0, 0.0, 10.0, 32)),
            ("pin", rod(5.05, -5.0, 25.0, 32)),
            ("washer", ring(9.0, 5.5, 10.0, 12.0, 32)),
        ],
    );
    for mode in [Mode::Mates, Mode::Geometry] {
        let p = plan(&doc, mode);
        assert_eq!(p.fits.len(), 1, "{:?}", p.fits);
        let f = &p.fits[0];
        assert_eq!((f.a.as_str(), f.b.as_str()), ("housing", "pin"));
        assert!(f.depth > 0.02 && f.depth < 0.1, "{f:?}");
        assert!(!f.contained);
        let c = checker(&doc, &p);
        fits_are_exact(&c, &p);
        dense_removal(&c, &p);
        // The pin goes in along its axis only: sideways it is held by the fit.
        for s in &p.sequences {
            let t = s.tasks.iter().find(|t| t.part == "pin");
            if let Some(t) = t {
                assert!(
                    t.mating_direction.z.abs() > 1.0 - 1e-9,
                    "{:?}",
                    t.mating_direction
                );
            }
        }
        // The check is not a blanket pass: the pin 1 mm sideways is refused.
        let (pin, housing) = (
            doc.component_index("pin").unwrap(),
            doc.component_index("housing").unwrap(),
        );
        let aside = Transform::from_translation(Vec3::new(1.0, 0.0, 0.0));
        assert!(c.hits(pin, &aside, housing));
        // The report names the fit.
        assert!(
            p.summary().contains("fit: housing and pin"),
            "{}",
            p.summary()
        );
        assert_eq!(p.to_json_value()["fits"][0]["b"], "pin");
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_part_modelled_through_another_is_sequenced() {
    let d = dir("through");
    // A 10 mm bar modelled straight through an 82 mm block that has no hole for
    // it (82 mm of overlap along the bar), a cap on the bar's top.
    let doc = write_doc(
        &d,
        &[
            ("block", cuboid([-20.0, -20.0, 0.0], [20.0, 20.0, 82.0])),
            ("bar", cuboid([-5.0, -5.0, -19.0], [5.0, 5.0, 101.0])),
            ("cap", cuboid([-8.0, -8.0, 101.0], [8.0, 8.0, 105.0])),
        ],
    );
    for mode in [Mode::Mates, Mode::Geometry] {
        let p = plan(&doc, mode);
        assert_eq!(p.fits.len(), 1, "{:?}", p.fits);
        let f = &p.fits[0];
        assert_eq!((f.a.as_str(), f.b.as_str()), ("block", "bar"));
        assert!(f.depth > 1.0, "{f:?}");
        let c = checker(&doc, &p);
        fits_are_exact(&c, &p);
        dense_removal(&c, &p);
        // Between block and bar only the bar's axis is free.
        for s in &p.sequences {
            let order = s.order();
            let (b, k) = (
                order.iter().position(|o| o == "bar").unwrap(),
                order.iter().position(|o| o == "block").unwrap(),
            );
            let later = s.tasks.iter().find(|t| t.part == order[b.max(k)]).unwrap();
            assert!(
                later.mating_direction.z.abs() > 1.0 - 1e-9,
                "{order:?}: {} along {:?}",
                later.part,
                later.mating_direction
            );
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_clearance_linkage_is_held_across_its_gaps() {
    let d = dir("linkage");
    // A ground bracket and a link, 2 mm apart, joined by a pin with 2 mm of
    // clearance in both bores: nothing touches within the default 1.5 mm gap.
    let doc = write_doc(
        &d,
        &[
            ("ground", ring(14.0, 5.0, 0.0, 5.0, 32)),
            ("link", ring(10.0, 5.0, 7.0, 12.0, 32)),
            ("pin", rod(3.0, -3.0, 15.0, 32)),
        ],
    );
    for mode in [Mode::Mates, Mode::Geometry] {
        let p = plan(&doc, mode);
        assert!(p.fits.is_empty(), "{:?}", p.fits);
        // Three groups, joined by two links of 2 mm.
        assert_eq!(p.support_gaps.len(), 2, "{:?}", p.support_gaps);
        for g in &p.support_gaps {
            let gap = g.gap_mm.unwrap();
            assert!((gap - 2.0).abs() < 0.05, "{g:?}");
        }
        assert_eq!(p.best().base, "ground", "the largest part");
        let c = checker(&doc, &p);
        fits_are_exact(&c, &p);
        dense_removal(&c, &p);
        // Every part placed is held: within the widest reported link of a part
        // placed before it (surface distance, asked here).
        let widest = p
            .support_gaps
            .iter()
            .filter_map(|g| g.gap_mm)
            .fold(1.5f64, f64::max);
        for s in &p.sequences {
            let order = s.order();
            for k in 1..order.len() {
                let i = doc.component_index(&order[k]).unwrap();
                let held = order[..k].iter().any(|o| {
                    let q = doc.component_index(o).unwrap();
                    c.clearance(i, q, widest + 1.0) <= widest + 1e-6
                });
                assert!(held, "{} floats in {order:?}", order[k]);
            }
        }
        assert!(p.summary().contains("held across a gap"), "{}", p.summary());
    }
    // Support off still works, and with a contact gap wider than the joints nothing
    // needs a link.
    let wide = SequenceOptions {
        contact_gap_mm: 2.5,
        ..SequenceOptions::default()
    };
    let p = plan_sequence(&doc, &mut SceneCache::new(), &wide).unwrap();
    assert!(p.support_gaps.is_empty(), "{:?}", p.support_gaps);
    let _ = std::fs::remove_dir_all(&d);
}

/// A real export whose parts the file places apart (issue 38's Onshape and CATIA
/// assemblies: two sub-products a frame the file leaves out would hold): a pin in a
/// block, and 200 mm away a peg in another block, touching nothing of the first
/// group and farther than any support link reaches. Each group's first part needs
/// no support and the plan names the groups; inside a group every part added
/// touches one placed before it.
#[test]
fn groups_the_file_places_apart_are_sequenced_each_held_inside() {
    let d = dir("apart");
    let far = |m: Mesh| m.transformed(&Transform::from_translation(Vec3::new(200.0, 0.0, 0.0)));
    let doc = write_doc(
        &d,
        &[
            ("block", ring(14.0, 3.0, 0.0, 10.0, 32)),
            ("pin", rod(3.0, 0.0, 20.0, 32)),
            ("block2", far(ring(12.0, 2.0, 0.0, 8.0, 32))),
            ("peg", far(rod(2.0, 0.0, 15.0, 32))),
        ],
    );
    for mode in [Mode::Mates, Mode::Geometry] {
        let p = plan(&doc, mode);
        assert_eq!(
            p.separate_groups,
            vec![
                vec!["block".to_string(), "pin".to_string()],
                vec!["block2".to_string(), "peg".to_string()]
            ],
            "{mode:?}"
        );
        assert!(p.support_gaps.is_empty(), "{:?}", p.support_gaps);
        let c = checker(&doc, &p);
        fits_are_exact(&c, &p);
        dense_removal(&c, &p);
        // Inside each group, every part after its group's first touches (1.5 mm) a
        // part of its group placed before it.
        for s in &p.sequences {
            let order = s.order();
            for (k, name) in order.iter().enumerate() {
                let group = p.separate_groups.iter().find(|g| g.contains(name)).unwrap();
                let before: Vec<&String> =
                    order[..k].iter().filter(|o| group.contains(o)).collect();
                if before.is_empty() {
                    continue;
                }
                let i = doc.component_index(name).unwrap();
                let held = before.iter().any(|o| {
                    let q = doc.component_index(o).unwrap();
                    c.clearance(i, q, 2.5) <= 1.5
                });
                assert!(held, "{name} floats in {order:?}");
            }
        }
        assert!(
            p.summary().contains("held by nothing modelled"),
            "{}",
            p.summary()
        );
        let json = p.to_json_value();
        assert_eq!(
            json["separate_groups"].as_array().unwrap().len(),
            2,
            "{json}"
        );
    }
    // One group: nothing listed.
    let d1 = dir("apart_one");
    let one = write_doc(
        &d1,
        &[
            ("block", ring(14.0, 3.0, 0.0, 10.0, 32)),
            ("pin", rod(3.0, 0.0, 20.0, 32)),
        ],
    );
    assert!(plan(&one, Mode::Geometry).separate_groups.is_empty());
    let _ = std::fs::remove_dir_all(&d1);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn every_option_a_refusal_names_is_an_option_of_every_face() {
    use fitup::options::{Options, Sequence};
    use fitup::sequence::{RejectReason, SequenceError, Stuck};
    // Every message the refusals can give, with each variant's option names.
    let stuck = [
        Stuck::Floats {
            part: "a".into(),
            gap_mm: 1.5,
        }
        .to_string(),
        Stuck::Blocked {
            part: "a".into(),
            directions: 6,
            by: vec!["b".into()],
            least: ([0.0, 0.0, 1.0], vec!["b".into()]),
            in_contact: true,
            tolerance: 0.01,
            deflection: None,
            deep_fits: Vec::new(),
            slide_fit_mm: 2.0,
        }
        .to_string(),
        Stuck::Blocked {
            part: "a".into(),
            directions: 6,
            by: vec!["b".into()],
            least: ([0.0, 0.0, 1.0], vec!["b".into()]),
            in_contact: true,
            tolerance: 0.1,
            deflection: Some(0.1),
            deep_fits: vec![("b".into(), 2.5)],
            slide_fit_mm: 2.0,
        }
        .to_string(),
    ];
    // The tolerance already at the meshes' deflection: raising it to that is not
    // offered.
    let at_deflection = Stuck::Blocked {
        part: "a".into(),
        directions: 6,
        by: vec!["b".into()],
        least: ([0.0, 0.0, 1.0], vec!["b".into()]),
        in_contact: true,
        tolerance: 0.1,
        deflection: Some(0.1),
        deep_fits: Vec::new(),
        slide_fit_mm: 2.0,
    }
    .to_string();
    assert!(
        !at_deflection.contains('`') && at_deflection.contains("already the meshes' deflection"),
        "{at_deflection}"
    );
    let texts = [
        stuck.join("; "),
        RejectReason::InactiveBase {
            base: "a".into(),
            size: 1.0,
            largest_related: 10.0,
        }
        .to_string(),
        SequenceError::NoSequence {
            timed_out: true,
            rejected: Vec::new(),
        }
        .to_string(),
        SequenceError::TimeLimit(5.0).to_string(),
    ];
    let mut named = Vec::new();
    for t in &texts {
        for (i, piece) in t.split('`').enumerate() {
            if i % 2 == 1 {
                named.push(piece.to_string());
            }
        }
    }
    for must in [
        "contact_gap_mm",
        "tolerance",
        "support",
        "time_limit_ms",
        "small_base_ratio",
        "base",
        "slide_fit_mm",
    ] {
        assert!(named.iter().any(|n| n == must), "{must} in {texts:?}");
    }
    for name in &named {
        // The one table (scripts' maps and Python's keywords read it).
        assert!(
            Sequence::VOCABULARY.key(name).is_some(),
            "`{name}` named by a refusal is not a sequence option"
        );
        // The command line takes it through `--option`.
        let key = Sequence::VOCABULARY.key(name).unwrap();
        let sample = match key.kind {
            fitup::options::Kind::Bool => "false",
            fitup::options::Kind::Text => "ground",
            _ => "2.5",
        };
        let map = Sequence::VOCABULARY
            .map_from_args(&[format!("{name}={sample}")])
            .unwrap();
        Sequence::from_value(serde_json::Value::Object(map)).unwrap();
    }
    // `tolerance` too (the old refusal named it).
    assert!(Sequence::VOCABULARY.key("tolerance").is_some());
}

#[test]
fn the_command_line_reaches_the_options_table() {
    let d = dir("cli");
    write_doc(
        &d,
        &[
            ("ground", ring(14.0, 5.0, 0.0, 5.0, 16)),
            ("link", ring(10.0, 5.0, 7.0, 12.0, 16)),
            ("pin", rod(3.0, -3.0, 15.0, 16)),
        ],
    );
    let doc = d.join("product.yaml");
    let doc = doc.to_str().unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec!["plan-sequence", doc, "--json"];
        args.extend_from_slice(extra);
        crate::common::run_in(&d, &args)
    };
    let out = run(&["--option", "contact_gap_mm=2.5", "-o", "tolerance=0.02"]);
    assert!(out.status.success(), "{}", crate::common::text(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["support_gaps"], serde_json::json!([]));
    let out = run(&[]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["support_gaps"].as_array().unwrap().len(), 2, "{v}");
    // A key outside the table is refused by name, with a close match.
    let bad = run(&["--option", "contact_gap=2"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(
        crate::common::text(&bad).contains("contact_gap_mm"),
        "{}",
        crate::common::text(&bad)
    );
    let bad = run(&["--option", "tolerance"]);
    assert_eq!(bad.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(&d);
}

/// A part that an early choice shuts in for good ends that branch at once (issue 38,
/// the SolidWorks 6-DOF arm of the STEP corpus: the servo horn put on before the
/// gripper base it clamps, with 20 other parts to go, filled the 30 s budget). Here a
/// post on a plate carries a disk that overhangs a collar around the post: the disk
/// leaves first by every sort the search uses, and once it is on, the collar can
/// leave in no direction. With 18 loose blocks on the plate besides, the search used
/// to try every order of the blocks under the disk first (2^18 nodes) and gave up;
/// the disk-first branch must be refused right after the disk, naming the collar.
#[test]
fn a_part_shut_in_by_an_early_choice_ends_that_branch_at_once() {
    let d = dir("shut_in");
    let mut parts: Vec<(String, Mesh)> = vec![
        (
            "plate".into(),
            cuboid([-70.0, -70.0, -5.0], [70.0, 70.0, 0.0]),
        ),
        ("post".into(), rod(5.0, 0.0, 30.0, 16)),
        ("disk".into(), rod(15.0, 30.0, 33.0, 16)),
        ("collar".into(), ring(12.0, 5.2, 0.0, 10.0, 16)),
    ];
    for i in 0..18 {
        let (x, y) = (-60.0 + 20.0 * (i % 6) as f64, 25.0 + 15.0 * (i / 6) as f64);
        parts.push((
            format!("block{i}"),
            cuboid([x, y, 0.0], [x + 4.0, y + 4.0, 4.0]),
        ));
    }
    let named: Vec<(&str, Mesh)> = parts.iter().map(|(n, m)| (n.as_str(), m.clone())).collect();
    let doc = write_doc(&d, &named);
    let o = SequenceOptions {
        max_sequences: 1,
        ..SequenceOptions::default()
    };
    let p = match plan_sequence(&doc, &mut SceneCache::new(), &o) {
        Ok(p) => p,
        Err(e) => panic!("{e}"),
    };
    let order = p.best().order();
    let at = |n: &str| order.iter().position(|o| o == n).unwrap();
    assert!(at("collar") < at("disk"), "{order:?}");
    let shut = p
        .rejected
        .iter()
        .find(|r| r.order == ["plate", "post", "disk"]);
    let shut = shut.unwrap_or_else(|| panic!("{:#?}", p.rejected));
    let why = shut.reason.to_string();
    assert!(why.contains("collar is blocked along all"), "{why}");
    let c = checker(&doc, &p);
    fits_are_exact(&c, &p);
    dense_removal(&c, &p);
    let _ = std::fs::remove_dir_all(&d);
}

/// A U-channel along +Y: outer half-width `w_out`, slot half-width `w_in`, floor
/// `0..floor`, walls up to `top`, from `y0` to `y1` (the cross-section in X–Z
/// extruded, its caps split into six triangles on its own corners).
fn channel(w_out: f64, w_in: f64, floor: f64, top: f64, y0: f64, y1: f64) -> Mesh {
    // The U counter-clockwise in (x, z).
    let u = [
        (-w_out, 0.0),
        (w_out, 0.0),
        (w_out, top),
        (w_in, top),
        (w_in, floor),
        (-w_in, floor),
        (-w_in, top),
        (-w_out, top),
    ];
    let mut vertices = Vec::new();
    for y in [y0, y1] {
        for &(x, z) in &u {
            vertices.push(Point3::new(x, y, z));
        }
    }
    // At y0 the counter-clockwise (x, z) triangles face −Y (outward); at y1 flipped.
    let cap = [
        [0, 1, 4],
        [0, 4, 5],
        [1, 2, 3],
        [1, 3, 4],
        [0, 5, 6],
        [0, 6, 7],
    ];
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    for t in cap {
        triangles.push(t);
        triangles.push([t[0] + 8, t[2] + 8, t[1] + 8]);
    }
    for a in 0..8u32 {
        let b = (a + 1) % 8;
        triangles.push([a, b + 8, b]);
        triangles.push([a, a + 8, b + 8]);
    }
    Mesh::new(vertices, triangles).unwrap()
}

/// Issue 38's press-fit slide, first class (the servo arm pressed 0.69 mm onto its
/// shaft in Aryanbrb's robot arm): a hub pressed 0.3 mm onto a shaft that stands on
/// a plate. The shaft is the larger, so the cut-out model carves the hub's room out
/// of it and the hub slid along the shaft meets shaft the room does not cover: the
/// pair could never part. A fit no deeper than `slide_fit_mm` slides: the hub comes
/// off along the shaft, sideways it is still held, and the independent re-check
/// allows exactly that slide.
#[test]
fn a_hub_pressed_onto_a_shaft_slides_off_along_it() {
    let d = dir("hub");
    let doc = write_doc(
        &d,
        &[
            ("plate", cuboid([-30.0, -30.0, -5.0], [30.0, 30.0, 0.0])),
            ("shaft", rod(5.3, 0.0, 60.0, 32)),
            ("hub", ring(9.0, 5.0, 20.0, 30.0, 32)),
        ],
    );
    let (hub, shaft) = (
        doc.component_index("hub").unwrap(),
        doc.component_index("shaft").unwrap(),
    );
    for mode in [Mode::Mates, Mode::Geometry] {
        let p = plan(&doc, mode);
        assert_eq!(p.fits.len(), 1, "{:?}", p.fits);
        let f = &p.fits[0];
        assert_eq!((f.a.as_str(), f.b.as_str()), ("shaft", "hub"));
        assert!(f.depth > 0.2 && f.depth < 0.4, "{f:?}");
        let c = checker(&doc, &p);
        fits_are_exact(&c, &p);
        dense_removal(&c, &p);
        for s in &p.sequences {
            let order = s.order();
            let later = if order.iter().position(|o| o == "hub")
                > order.iter().position(|o| o == "shaft")
            {
                "hub"
            } else {
                "shaft"
            };
            let t = s.tasks.iter().find(|t| t.part == later).unwrap();
            // Whichever goes second slides along the shaft's axis.
            assert!(
                t.mating_direction.z.abs() > 1.0 - 1e-9,
                "{order:?}: {later} along {:?}",
                t.mating_direction
            );
            assert_eq!(t.slides, vec![if later == "hub" { "shaft" } else { "hub" }]);
        }
        // The re-check allows the slide and nothing else: 10 mm up the shaft is
        // free, 0.5 mm sideways (the overlap grows on one side) is not, nor 2 mm up
        // turned 0.1 rad.
        let at = |v: Vec3| Transform::from_translation(v);
        assert!(!c.hits(hub, &at(Vec3::new(0.0, 0.0, 10.0)), shaft));
        assert!(c.hits(hub, &at(Vec3::new(0.5, 0.0, 0.0)), shaft));
        let turned = Transform::from_rotation_about(Point3::origin(), Vec3::x(), 0.1)
            .unwrap()
            .then(&at(Vec3::new(0.0, 0.0, 2.0)));
        assert!(c.hits(hub, &turned, shaft));
    }
    // Sliding off: no sequence, and the refusal names the fit and the option.
    let off = SequenceOptions {
        slide_fit_mm: 0.0,
        ..SequenceOptions::default()
    };
    let e = plan_sequence(&doc, &mut SceneCache::new(), &off)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("`slide_fit_mm` (0 mm) may not slide") && e.contains("mm"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// The second class (the tweezer grinder's PCB, 0.2 mm wider than the guides it
/// slides down): a board pressed 0.1 mm into each wall of a slot in a U-channel
/// longer than the board (the slot runs on past it along Y). The channel is the
/// larger part, so the cut-out model blocks the board every way; as a sliding fit
/// it leaves up out of the slot or along it, never down into the floor or sideways
/// into a wall, and the re-check allows exactly that.
#[test]
fn a_board_pressed_into_a_slot_slides_out_of_it() {
    let d = dir("board");
    let doc = write_doc(
        &d,
        &[
            ("channel", channel(15.0, 5.0, 4.0, 30.0, -40.0, 40.0)),
            ("board", cuboid([-5.1, -10.0, 4.0], [5.1, 10.0, 25.0])),
        ],
    );
    let (board, chan) = (
        doc.component_index("board").unwrap(),
        doc.component_index("channel").unwrap(),
    );
    for mode in [Mode::Mates, Mode::Geometry] {
        let p = plan(&doc, mode);
        assert_eq!(p.fits.len(), 1, "{:?}", p.fits);
        assert!(p.fits[0].depth < 0.2, "{:?}", p.fits);
        let c = checker(&doc, &p);
        fits_are_exact(&c, &p);
        dense_removal(&c, &p);
        for s in &p.sequences {
            let t = &s.tasks[0];
            // The board out of the slot up (inserted along −Z) or along it (±Y),
            // never across (the channel onto the board: the same, reversed).
            let m = if t.part == "board" {
                t.mating_direction
            } else {
                -t.mating_direction
            };
            assert!(
                m.x.abs() < 1e-9 && m.z < 1e-9,
                "{} along {:?}",
                t.part,
                t.mating_direction
            );
        }
        let at = |v: Vec3| Transform::from_translation(v);
        for free in [Vec3::new(0.0, 0.0, 8.0), Vec3::new(0.0, 12.0, 0.0)] {
            assert!(!c.hits(board, &at(free), chan), "{free:?}");
        }
        // (The re-check's volume grid is about 1 mm here: a sideways step it can
        // see.)
        for held in [
            Vec3::new(1.5, 0.0, 0.0),
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(1.5, 0.0, 8.0),
        ] {
            assert!(c.hits(board, &at(held), chan), "{held:?}");
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}
