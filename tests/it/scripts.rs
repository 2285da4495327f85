//! Every example script in `scripts/` runs to completion (each asserts its own results),
//! run exactly as the README shows: `fitup run scripts/NAME.rhai` from the repository
//! root, with no set-up (scripts create the output folder `out/` they write to).

use crate::common;

#[test]
fn every_example_script_runs() {
    let root = common::repo();
    let mut scripts: Vec<_> = std::fs::read_dir(root.join("scripts"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rhai"))
        .collect();
    scripts.sort();
    assert!(
        scripts.len() >= 4,
        "expected the example scripts, found {scripts:?}"
    );
    let mut failures = Vec::new();
    for s in &scripts {
        let rel = s
            .strip_prefix(&root)
            .unwrap()
            .to_string_lossy()
            .into_owned();
        let out = common::run_in(&root, &["run", &rel]);
        if !out.status.success() {
            failures.push(format!("{rel}:\n{}", common::text(&out)));
        }
    }
    assert!(
        failures.is_empty(),
        "failing scripts:\n{}",
        failures.join("\n")
    );
}
