#!/bin/sh
# fitup against OMPL 1.5 C++ (RRTConnect, KPIECE1, BiTRRT; FCL validity) on the
# rigid-body puzzle classes of issue 23 (models/problems/: twisted_tubes, house,
# plate_hole, twisted_slot, bar_slot, ring_puzzle, rod_corridor, zigzag_tunnel),
# same meshes, bounds, start and goal, in one
# run: `cargo bench --bench planning` with FITUP_PUZZLES=1. Needs the Debian
# packages libompl-dev libfcl-dev libccd-dev libeigen3-dev g++ for the peer (the
# bench says so and runs fitup alone without them). Environment overrides:
# FITUP_BUDGET_MS (fitup's budget per call, 20000), FITUP_OMPL_LIMIT_S (20),
# FITUP_RUNS / FITUP_OMPL_RUNS (seeds, 5 each), FITUP_PROBLEM (name filter),
# FITUP_PROBE_MS (a budget probe per class with smoothing on, 300 ms; 0: off).
# The load before and after goes with the figures (docs/performance.md). The bench
# needs only the library's core layers, so it is built without the default
# features (no SQLite, PostgreSQL, Rhai or CLI in its release build).
set -eu
cd "$(dirname "$0")/../.."
export FITUP_PUZZLES=1
export FITUP_BUDGET_MS="${FITUP_BUDGET_MS:-20000}"
export FITUP_OMPL_LIMIT_S="${FITUP_OMPL_LIMIT_S:-20}"
export FITUP_RUNS="${FITUP_RUNS:-5}"
export FITUP_OMPL_RUNS="${FITUP_OMPL_RUNS:-5}"
export FITUP_VALIDATOR="${FITUP_VALIDATOR:-0}"
export FITUP_PROTOCOL=0
export FITUP_PROBE_MS="${FITUP_PROBE_MS:-300}"
export FITUP_SMOOTHED="${FITUP_SMOOTHED:-0}"
export FITUP_VERBOSE="${FITUP_VERBOSE:-1}"
uptime
cargo bench --no-default-features --bench planning
uptime
