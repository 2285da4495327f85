//! Shared helpers for the unit tests.

/// A property-test configuration with `cases` cases and a fixed seed.
///
/// Property tests are part of `cargo test`, so they must give the same verdict on every
/// run: the seed is fixed unless `PROPTEST_RNG_SEED` is set, which is how a developer
/// explores new inputs (`PROPTEST_RNG_SEED=$RANDOM cargo test`).
pub(crate) fn proptest_config(cases: u32) -> proptest::test_runner::Config {
    let mut config = proptest::test_runner::Config::with_cases(cases);
    if std::env::var_os("PROPTEST_RNG_SEED").is_none() {
        config.rng_seed = proptest::test_runner::RngSeed::Fixed(0x0f17_0b5e_ed00_0001);
    }
    config
}
