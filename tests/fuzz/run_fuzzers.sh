#!/usr/bin/env bash
# Builds the libFuzzer harnesses (fuzz/, clang with ASan + UBSan) in BUILD_DIR and runs each for SECONDS
# (default 6: about a minute for the eight readers, the scene JSON, checkpoint.bin and glTF) from its seed corpus in fuzz/corpus/. New inputs go
# to a temporary directory, not into the repository. Fails on any crash, sanitizer report, leak,
# timeout or out-of-memory, leaving the reproducer in BUILD_DIR/crashes.
# Usage: run_fuzzers.sh SOURCE_DIR BUILD_DIR [SECONDS]
set -euo pipefail
SRC="$1" BUILD="$2" SECONDS_EACH="${3:-6}"
if ! command -v clang++ > /dev/null; then
  echo "run_fuzzers: clang++ is missing (scripts/install-deps installs clang)" >&2
  exit 1
fi
cmake -S "$SRC/fuzz" -B "$BUILD" -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo > "$BUILD.configure.log" 2>&1 \
  || { cat "$BUILD.configure.log"; exit 1; }
cmake --build "$BUILD" -j "$(nproc)" > "$BUILD.build.log" 2>&1 || { tail -30 "$BUILD.build.log"; exit 1; }
mkdir -p "$BUILD/crashes"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
status=0
for format in msh mesh vtu tetgen obj off ply stl scene_json checkpoint gltf; do
  mkdir -p "$work/$format"
  seeds=("$SRC/fuzz/corpus/$format") max_len=4096
  [ "$format" = scene_json ] && seeds=("$SRC/scenes" "$SRC/tests/data/malformed_scenes")  # the example and malformed scenes
  [ "$format" = gltf ] && seeds=("$SRC/tests/data/flesh" "$SRC/data/hand") max_len=200000  # the limb (JSON) and the hand (GLB)
  if "$BUILD/fuzz_$format" "$work/$format" "${seeds[@]}" -max_total_time="$SECONDS_EACH" -timeout=10 \
       -rss_limit_mb=2048 -max_len="$max_len" -artifact_prefix="$BUILD/crashes/$format-" -print_final_stats=1 \
       > "$work/$format.log" 2>&1; then
    echo "fuzz_$format: $(grep -o 'stat::number_of_executed_units: [0-9]*' "$work/$format.log" | grep -o '[0-9]*$') inputs, no failure"
  else
    status=1
    echo "fuzz_$format FAILED:"
    grep -E "ERROR|SUMMARY|Test unit written" "$work/$format.log" | head -5
  fi
done
exit $status
