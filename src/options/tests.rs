use super::*;
use serde_json::json;

/// A value of `kind` that the key must accept.
pub(crate) fn sample(kind: &Kind) -> Value {
    match kind {
        Kind::Number => json!(1.5),
        Kind::Count => json!(3),
        Kind::Bool => json!(true),
        Kind::Text => json!("x"),
        Kind::Choice(names) => json!(names[names.len() - 1]),
        Kind::Names => json!(["a", "b"]),
        Kind::Vector => json!([0, 0, -1]),
        Kind::Box => box_value(&Aabb::new([0.0, 0.0, 0.0], [1.0, 2.0, 3.0])),
        Kind::Pose => pose_value(&Transform::from_translation(crate::math::Vec3::new(
            1.0, 2.0, 3.0,
        ))),
        Kind::NumberMap => json!({"a": 2.5}),
        Kind::Switch(_) => json!({}),
    }
}

/// The vocabulary is its struct's: the same keys in the same order, and every key
/// takes a value of its kind into the struct (and the struct's defaults print).
fn holds<T: Options + std::fmt::Debug>() {
    let v = T::VOCABULARY;
    assert_eq!(v.names(), struct_fields::<T>(), "{}", v.request);
    for k in v.keys {
        assert!(!k.meaning.is_empty(), "{}: {}", v.request, k.name);
        let parsed = T::from_value(json!({ k.name: sample(&k.kind) }))
            .unwrap_or_else(|e| panic!("{}.{}: {e}", v.request, k.name));
        assert!(parsed.warnings.is_empty());
    }
    let table = T::markdown();
    assert_eq!(table.lines().count(), 2 + v.keys.len() + v.deprecated.len());
    for d in v.deprecated {
        assert!(v.key(d.new).is_some(), "{} → {}", d.old, d.new);
    }
    assert!(T::from_value(json!({})).unwrap().warnings.is_empty());
}

#[test]
fn every_vocabulary_is_its_structs() {
    holds::<Plan>();
    holds::<Narrow>();
    holds::<Check>();
    holds::<Sweep>();
    holds::<Sequence>();
    holds::<Motion>();
    holds::<Drill>();
    holds::<AddMate>();
    #[cfg(feature = "db")]
    {
        holds::<PathFilter>();
        holds::<Limits>();
    }
    assert_eq!(
        vocabularies().len(),
        if cfg!(feature = "db") { 10 } else { 8 }
    );
}

#[test]
fn unknown_keys_name_close_matches() {
    let e = Plan::from_value(json!({"time_limt_ms": 5})).unwrap_err();
    assert_eq!(
        e.to_string(),
        "unknown planning option `time_limt_ms`: did you mean `time_limit_ms`?"
    );
    let e = Plan::from_value(json!({"narrow": {"max_turn": 5}})).unwrap_err();
    assert!(
        e.to_string().contains("`narrow.max_turn`") && e.to_string().contains("max_turn_deg"),
        "{e}"
    );
    let e = Check::from_value(json!([1])).unwrap_err();
    assert!(
        matches!(&e, OptionError::NotAMap { value, .. } if *value == json!([1])),
        "{e}"
    );
    assert_eq!(
        e.to_string(),
        format!(
            "{} options must be a map of key: value, not [1]",
            Check::VOCABULARY.request
        )
    );
    let long = Check::from_value(json!("x".repeat(100)))
        .unwrap_err()
        .to_string();
    assert!(
        long.ends_with(&format!(
            ", not {}",
            crate::diagnostics::shorten(&format!("\"{}\"", "x".repeat(100)), 60)
        )),
        "{long}"
    );
}

#[test]
fn values_are_checked_against_their_kind_with_unit() {
    let e = Plan::from_value(json!({"step": "fast"})).unwrap_err();
    assert_eq!(
        e.to_string(),
        "planning option `step` must be a number (mm), not \"fast\""
    );
    let e = Plan::from_value(json!({"seed": -1})).unwrap_err();
    assert!(e.to_string().contains("whole number"), "{e}");
    let e = Plan::from_value(json!({"planner": "rrt_conect"})).unwrap_err();
    assert!(e.to_string().contains("did you mean `rrt_connect`"), "{e}");
    let e = Plan::from_value(json!({"bounds": {"lo": [0, 0, 0], "hi": [1, -1, 1]}})).unwrap_err();
    assert!(e.to_string().contains("min below max"), "{e}");
    let e = Plan::from_value(json!({"narrow": 3})).unwrap_err();
    assert!(e.to_string().contains("true, false or a map"), "{e}");
    // A whole float is a count; null is absent.
    let p = Plan::from_value(json!({"max_iterations": 1e5, "step": null})).unwrap();
    assert_eq!(p.options.max_iterations, 100_000);
    assert_eq!(p.options.step, None);
    let e = Plan::from_value(json!({"max_iterations": 2.5})).unwrap_err();
    assert!(e.to_string().contains("max_iterations"), "{e}");
}

#[test]
fn deprecated_keys_are_converted_with_a_warning() {
    let p =
        Plan::from_value(json!({"edge": "step", "edge_step_rad": 0.5f64.to_radians()})).unwrap();
    assert!((p.options.edge_step_deg - 0.5).abs() < 1e-12);
    assert_eq!(p.warnings.len(), 1);
    assert!(
        p.warnings[0].contains("`edge_step_rad` is deprecated")
            && p.warnings[0].contains("`edge_step_deg`"),
        "{:?}",
        p.warnings
    );
    let e = Plan::from_value(json!({"edge_step_rad": 0.1, "edge_step_deg": 1})).unwrap_err();
    assert!(matches!(e, OptionError::Both { .. }), "{e}");
}

#[test]
fn the_default_plan_is_the_default_request() {
    let r = Plan::default().request("rrt_connect").unwrap();
    let d = crate::workspace::PlanRequest::default();
    assert_eq!(r.planner.name(), d.planner.name());
    assert_eq!(r.validator, d.validator);
    assert_eq!(r.margin_mm, d.margin_mm);
    assert_eq!(r.rotation, d.rotation);
    assert_eq!(
        r.planner.limits().budget_ms(),
        d.planner.limits().budget_ms()
    );
    assert_eq!(
        r.planner.limits().max_iterations,
        d.planner.limits().max_iterations
    );
    assert_eq!(
        Narrow::default().passage(),
        crate::planning::NarrowPassage::default()
    );
    assert_eq!(
        NarrowSwitch::On(false).passage(),
        crate::planning::NarrowPassage::OFF
    );
    // The stepwise edge in degrees reaches the validator in radians.
    let p = Plan::from_value(json!({"edge": "step", "edge_step": 0.2, "edge_step_deg": 2}))
        .unwrap()
        .options;
    assert_eq!(
        p.request("rrt").unwrap().validator.edge,
        SweepMethod::Stepwise {
            step_mm: 0.2,
            step_rad: 2f64.to_radians()
        }
    );
    // An option the planner does not have is the library's refusal.
    let p = Plan::from_value(json!({"goal_bias": 0.2})).unwrap().options;
    assert!(matches!(
        p.request("rrt_connect"),
        Err(crate::planning::PlanError::NotAnOption { .. })
    ));
    assert_eq!(
        Check::default().check_options(),
        crate::workspace::CheckOptions::default()
    );
    assert_eq!(
        Sweep::default().sweep_options().method,
        crate::collision::SweepOptions::default().method
    );
}

use crate::collision::SweepMethod;

#[test]
fn the_other_defaults_are_the_librarys() {
    let s = Sequence::default().sequence_options();
    let d = crate::sequence::SequenceOptions::default();
    assert_eq!(
        (
            s.max_sequences,
            s.tolerance,
            s.support,
            s.max_tilt,
            s.sphere_directions
        ),
        (
            d.max_sequences,
            d.tolerance,
            d.support,
            d.max_tilt,
            d.sphere_directions
        )
    );
    let p = Sequence::from_value(json!({"max_tilt": std::f64::consts::FRAC_PI_2})).unwrap();
    assert!((p.options.max_tilt_deg - 90.0).abs() < 1e-9 && p.warnings.len() == 1);
    assert!((p.options.sequence_options().max_tilt - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    let m = Motion::default().motion_options();
    let d = crate::kinematics::MotionOptions::default();
    assert!((m.joint_speed - d.joint_speed).abs() < 1e-12 && m.linear_speed == d.linear_speed);
    let dr = Drill::default().drill_options();
    let d = crate::kinematics::DrillOptions::default();
    assert_eq!(
        (dr.tool_axis, dr.approach, dr.spin_samples),
        (d.tool_axis, d.approach, d.spin_samples)
    );
    assert_eq!(
        Drill::VOCABULARY.keys.len(),
        6 + Motion::VOCABULARY.keys.len()
    );
}
