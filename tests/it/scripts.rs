//! Every example script in `scripts/` runs to completion (each asserts its own results),
//! run exactly as the README shows: `fitup run scripts/NAME.rhai` from the repository
//! root, with no set-up (scripts create the output folder `out/` they write to).

use crate::common;

#[test]
fn every_example_script_runs() {
    let scripts = common::repo_scripts("scripts");
    assert!(
        scripts.len() >= 4,
        "expected the example scripts, found {scripts:?}"
    );
    let failures = common::failing_repo_runs(&scripts);
    assert!(
        failures.is_empty(),
        "failing scripts:\n{}",
        failures.join("\n")
    );
}
