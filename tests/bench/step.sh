#!/bin/sh
# `fitup import` against Open CASCADE's own C++ reader on the same STEP files, in one
# run (docs/performance.md, "STEP import"). The files are made by OCCT in the tests
# (FITUP_STEP_SAMPLES); the peer is tests/bench/step/occt_peer.cpp, built here with g++
# against Debian's OCCT (libocct-data-exchange-dev, libocct-modeling-algorithms-dev).
# Needs a fitup built with `--features step` in $CARGO_TARGET_DIR (or target/) and GNU
# time. RUNS (3) runs per file and deflection; the load goes with the figures.
set -eu
cd "$(dirname "$0")/../.."
T="${CARGO_TARGET_DIR:-target}"
FITUP="$T/debug/fitup"
RUNS="${RUNS:-3}"
WORK="$(mktemp -d /tmp/fitup-step-bench.XXXXXX)"
trap 'rm -rf "$WORK"' EXIT
FITUP_STEP_SAMPLES="$WORK/samples" cargo test --features step --test step \
  step_import::with_occt::every_test_file_kind_is_a_step_file >/dev/null 2>&1
g++ -O2 -std=c++17 -w -I/usr/include/opencascade tests/bench/step/occt_peer.cpp \
  -lTKXDESTEP -lTKSTEP -lTKSTEPBase -lTKSTEPAttr -lTKSTEP209 -lTKXSBase -lTKXCAF \
  -lTKLCAF -lTKCAF -lTKCDF -lTKMesh -lTKBO -lTKPrim -lTKTopAlgo -lTKShHealing \
  -lTKGeomAlgo -lTKGeomBase -lTKBRep -lTKG3d -lTKG2d -lTKMath -lTKernel \
  -o "$WORK/occt_peer"
uptime
for f in box cylinder_hole assembly inch_box plate_holes; do
  for d in 0.1 0.01; do
    i=0
    while [ "$i" -lt "$RUNS" ]; do
      i=$((i + 1))
      echo "== $f.step D $d run $i ($(wc -c <"$WORK/samples/$f.step") bytes)"
      /usr/bin/time -f "   peer process %e s, max RSS %M kB" \
        "$WORK/occt_peer" "$WORK/samples/$f.step" "$d" 0.5
      rm -rf "$WORK/out"
      /usr/bin/time -f "   fitup process %e s, max RSS %M kB (child included)" \
        "$FITUP" import "$WORK/samples/$f.step" --out "$WORK/out" --deflection "$d" |
        grep -E "Open CASCADE|volume" | sed 's/^/   /'
    done
  done
done
uptime
