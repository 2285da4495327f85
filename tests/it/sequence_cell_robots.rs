//! `fitup plan-sequence models/cell_robots.yaml` as docs/assembly.md gives it (issue
//! 25): the real binary, from the repository root, default options. The cell's robot
//! links are left out by themselves and its pedestals because the document marks them
//! `fixture: true`; every returned sequence is re-checked by `sequence_real`'s dense
//! removal test (reverse order along the reported paths and straight on in 0.2 mm
//! steps, exact interference), not by the sequencer's own checks.

use super::common;
use super::sequence_real::{dense_removal_json, robot_link_names};
use fitup::document::Document;

/// A JSON array of names as strings.
fn names(v: &serde_json::Value) -> Vec<&str> {
    let array = v.as_array().unwrap_or_else(|| panic!("not an array: {v}"));
    array.iter().map(|n| n.as_str().unwrap()).collect()
}

#[test]
fn the_robot_cell_is_sequenced_with_the_defaults() {
    let root = common::repo();
    let doc = Document::open(&root.join("models/cell_robots.yaml")).unwrap();
    let robot_links = robot_link_names(&doc);
    assert_eq!(robot_links.len(), 14, "{robot_links:?}");
    let fixtures: Vec<String> = doc
        .components()
        .iter()
        .filter(|c| c.fixture)
        .map(|c| c.name.clone())
        .collect();
    assert_eq!(fixtures, ["mz07_a_pedestal", "mz07_b_pedestal"]);
    let left_out: Vec<&String> = robot_links.iter().chain(&fixtures).collect();

    // The documented command, exactly.
    let o = common::fitup()
        .current_dir(&root)
        .args(["plan-sequence", "models/cell_robots.yaml"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", common::short_text(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    let best = text
        .lines()
        .find_map(|l| l.strip_prefix("best: "))
        .unwrap_or_else(|| panic!("no best sequence in\n{text}"));
    let best: Vec<&str> = best.split(" → ").collect();
    assert_eq!(best.first(), Some(&"table"), "{text}");
    for name in &left_out {
        assert!(
            !text
                .split(|c: char| !(c.is_alphanumeric() || c == '_'))
                .any(|w| w == name.as_str()),
            "{name} appears in the plan:\n{text}"
        );
    }

    // The same with --json, for the re-check.
    let o = common::fitup()
        .current_dir(&root)
        .args(["plan-sequence", "models/cell_robots.yaml", "--json"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", common::short_text(&o));
    let plan: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let product = names(&plan["product"]);
    let sequences = plan["sequences"].as_array().unwrap();
    assert!(!sequences.is_empty());
    for s in sequences {
        let order = names(&s["order"]);
        // Every part of the product once, nothing else.
        let mut sorted = order.clone();
        sorted.sort();
        let mut want = product.clone();
        want.sort();
        assert_eq!(sorted, want);
        for name in &left_out {
            assert!(
                !order.contains(&name.as_str()),
                "{name} sequenced: {order:?}"
            );
        }
    }
    for name in &left_out {
        assert!(!product.contains(&name.as_str()), "{name} in the product");
    }
    for part in ["table", "plate_a", "plate_b", "screw1", "screw5"] {
        assert!(product.contains(&part), "{part} missing: {product:?}");
    }
    assert_eq!(
        names(&sequences[0]["order"]),
        best,
        "the text's best is the JSON's first"
    );
    dense_removal_json(&doc, &plan);
}
