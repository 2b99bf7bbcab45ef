#!/usr/bin/env bash
# bench/figure1.sh on a small lattice (about 2 000 hexes, two frames): the per-step table ends with the
# slowest step and the figure1: line, and REFERENCE compares a run with an earlier one:
#   1. against a copy of its own last run: exit 0, distance 0 at every frame;
#   2. against a copy with one surface vertex moved: exit 1, that frame named;
#   3. REFERENCE not a directory, or without the frames this run makes: exit 2 before anything runs;
#   4. REFERENCE the very directory the run would replace: exit 2, and the directory is left as it was;
#   5. bench/figure1_growth.sh (runs of several sizes) refuses REFERENCE: exit 2, before anything runs;
#   6. figure1_growth.sh draws an earlier table BESIDE its own (exit 0, the plot written), and refuses a BESIDE
#      that is not such a table (another file, a row not of numbers, no file): exit 2, before anything runs.
# Usage: test_bench_figure1.sh SNH REPOSITORY
set -u
SNH="$1"
root="$2"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
pass=0 fail=0
# shellcheck source=lib.sh
. "$(dirname "$0")/lib.sh"  # ok, bad, expect_exit, expect_error

out="$(SNH="$SNH" FRAMES=2 END_TIME=0.1667 OUT="$work/out" bash "$root/bench/figure1.sh" 2000 2>&1)"
code=$?
if [ "$code" -eq 0 ] && printf '%s\n' "$out" | tail -1 | grep -Eq '^figure1: [0-9]+ elements, [0-9]+ dofs, [0-9.]+ newton/step, [0-9]+ cg/step, [0-9.]+ s/step, [0-9]+ MiB$' &&
  printf '%s\n' "$out" | tail -2 | head -1 | grep -Eq '^figure1.sh: slowest step [12]: [0-9.]+ s \([0-9]+ Newton, [0-9]+ CG\)$'; then ok
else bad "the run's last lines (exit $code): $(printf '%s\n' "$out" | tail -3)"; fi

cp -r "$work/out/run" "$work/same"
expect_exit 0 "a reference equal to the run" 'largest distance over 2 frames 0 \(model units\); energies within 0' -- \
  env REFERENCE="$work/same" SNH="$SNH" FRAMES=2 END_TIME=0.1667 OUT="$work/out" bash "$root/bench/figure1.sh" 2000

cp -r "$work/out/run" "$work/moved"
# The first vertex of frame 2's render surface moved by a millimetre in x.
awk 'BEGIN { done = 0 } /^v / && !done { $2 = $2 + 0.001; done = 1 } { print }' "$work/out/run/surface/002.obj" > "$work/moved/surface/002.obj"
expect_exit 1 "a reference whose frame 2 differs" 'frames farther apart than 1e-6: 2$' -- \
  env REFERENCE="$work/moved" SNH="$SNH" FRAMES=2 END_TIME=0.1667 OUT="$work/out" bash "$root/bench/figure1.sh" 2000

expect_exit 2 "a reference that is not a directory" '^figure1.sh: REFERENCE=.*/none is not a directory' -- \
  env REFERENCE="$work/none" SNH="$SNH" OUT="$work/out" bash "$root/bench/figure1.sh" 2000

expect_exit 2 "a reference of fewer frames" 'has no .*/same/surface/003.obj: not an earlier run of 3 frames' -- \
  env REFERENCE="$work/same" SNH="$SNH" FRAMES=3 OUT="$work/out3" bash "$root/bench/figure1.sh" 2000
if [ ! -e "$work/out3/run" ]; then ok; else bad "figure1.sh ran before refusing a reference of fewer frames"; fi

touch "$work/out/run/marker"
before="$(md5sum < "$work/out/run/stats.json")"
expect_exit 2 "a reference the run would replace" 'is the directory this run replaces' -- \
  env REFERENCE="$work/out/run" SNH="$SNH" FRAMES=2 OUT="$work/out" bash "$root/bench/figure1.sh" 2000
if [ -f "$work/out/run/marker" ] && [ "$(md5sum < "$work/out/run/stats.json")" = "$before" ]; then ok
else bad "the refused reference $work/out/run was changed"; fi

expect_exit 2 "figure1_growth.sh with REFERENCE" '^figure1_growth.sh: REFERENCE compares one run' -- \
  env REFERENCE="$work/same" SNH="$SNH" OUT="$work/growth" bash "$root/bench/figure1_growth.sh" 2000
if [ ! -e "$work/growth" ]; then ok; else bad "figure1_growth.sh wrote $work/growth before refusing REFERENCE"; fi

# A one-size growth run with smaller capsules, its own table drawn beside it as an earlier run's would be.
printf 'elements,dofs,newton_per_step,cg_per_step,seconds_per_step,peak_mib\n1000,3000,3.0,20,0.10,100\n2000,6000,3.0,20,0.20,120\n' > "$work/earlier.csv"
expect_exit 0 "figure1_growth.sh with BESIDE" '^plot: .*/growth2/figure1_growth.png$' -- \
  env BESIDE="$work/earlier.csv" BESIDE_LABEL="default capsules" RADIUS_SCALE=0.6 SNH="$SNH" FRAMES=1 END_TIME=0.0833 \
  OUT="$work/growth2" bash "$root/bench/figure1_growth.sh" 2000
if [ -s "$work/growth2/figure1_growth.png" ]; then ok; else bad "figure1_growth.sh with BESIDE drew no plot"; fi
expect_error "BESIDE that is not a growth table" '^figure1_growth.sh: BESIDE=.*/stats.json is not a figure1_growth.csv' -- \
  env BESIDE="$work/same/stats.json" SNH="$SNH" OUT="$work/growth3" bash "$root/bench/figure1_growth.sh" 2000
printf 'elements,dofs,newton_per_step,cg_per_step,seconds_per_step,peak_mib\n1000,3000,3.0,20,fast,100\n' > "$work/words.csv"
expect_error "BESIDE with a row that is not numbers" '^figure1_growth.sh: BESIDE=.*/words.csv is not a figure1_growth.csv' -- \
  env BESIDE="$work/words.csv" SNH="$SNH" OUT="$work/growth3" bash "$root/bench/figure1_growth.sh" 2000
expect_error "BESIDE that does not exist" '^figure1_growth.sh: BESIDE=.*/none.csv is not a figure1_growth.csv' -- \
  env BESIDE="$work/none.csv" SNH="$SNH" OUT="$work/growth3" bash "$root/bench/figure1_growth.sh" 2000
if [ ! -e "$work/growth3" ]; then ok; else bad "figure1_growth.sh wrote $work/growth3 before refusing BESIDE"; fi

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
