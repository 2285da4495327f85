#!/bin/sh
# `fitup import` on real CAD exports against Open CASCADE's own reading of the same
# files, in one run (docs/performance.md, "STEP import: a real SolidWorks export"). The files
# are third-party and never committed: FITUP_STEP_CORPUS names a folder of .step/.stp
# files. Builds tests/bench/step/occt_check.cpp (the independent reference: placements,
# exact volumes, product names, unit) and occt_peer.cpp (the timing peer) with g++
# against Debian's OCCT, runs tests/it/step_corpus.rs with the reference, then times
# both on every file RUNS (3) times. Needs a fitup built with `--features step` in
# $CARGO_TARGET_DIR (or target/) and GNU time; the load goes with the figures.
set -eu
: "${FITUP_STEP_CORPUS:?name a folder of real STEP exports}"
cd "$(dirname "$0")/../.."
T="${CARGO_TARGET_DIR:-target}"
FITUP="$T/debug/fitup"
RUNS="${RUNS:-3}"
WORK="$(mktemp -d /tmp/fitup-step-corpus.XXXXXX)"
trap 'rm -rf "$WORK"' EXIT
LIBS="-lTKXDESTEP -lTKSTEP -lTKSTEPBase -lTKSTEPAttr -lTKSTEP209 -lTKXSBase -lTKXCAF \
  -lTKLCAF -lTKCAF -lTKCDF -lTKMesh -lTKBO -lTKPrim -lTKTopAlgo -lTKShHealing \
  -lTKGeomAlgo -lTKGeomBase -lTKBRep -lTKG3d -lTKG2d -lTKMath -lTKernel"
for tool in occt_check occt_peer; do
  # shellcheck disable=SC2086
  g++ -O2 -std=c++17 -w -I/usr/include/opencascade "tests/bench/step/$tool.cpp" $LIBS \
    -o "$WORK/$tool"
done
uptime
FITUP_OCCT_CHECK="$WORK/occt_check" cargo test --features step --test step \
  step_corpus:: -- --nocapture 2>&1 | grep -E "^test |test result|panicked|: fitup import"
for f in "$FITUP_STEP_CORPUS"/*.step "$FITUP_STEP_CORPUS"/*.STEP "$FITUP_STEP_CORPUS"/*.stp \
  "$FITUP_STEP_CORPUS"/*.STP; do
  [ -f "$f" ] || continue
  echo "== $(basename "$f") ($(wc -c <"$f") bytes; $(grep -m1 -o "'SolidWorks[^']*'\|'CATIA[^']*'" "$f" || echo "?"))"
  i=0
  while [ "$i" -lt "$RUNS" ]; do
    i=$((i + 1))
    /usr/bin/time -f "   peer process %e s, max RSS %M kB" "$WORK/occt_peer" "$f" 0.1 0.5
    rm -rf "$WORK/out"
    /usr/bin/time -f "   fitup process %e s, max RSS %M kB (child included)" \
      "$FITUP" import "$f" --out "$WORK/out" | grep -E "Open CASCADE" | sed 's/^/   /'
  done
done
uptime
