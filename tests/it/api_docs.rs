//! docs/api.md is exactly what `fitup docs` generates from the registered functions
//! (regenerate with `cargo run -- docs` or `FITUP_BLESS=1 cargo test --test api_docs`).

#[test]
fn committed_api_reference_is_current() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/api.md");
    let generated = fitup::script::api_reference();
    if std::env::var_os("FITUP_BLESS").is_some() {
        std::fs::write(&path, &generated).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "docs/api.md is stale: run `cargo run -- docs`"
    );
}
