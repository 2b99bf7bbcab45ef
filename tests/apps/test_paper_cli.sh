#!/usr/bin/env bash
# End-to-end checks of tetcli / tetccli / hexcli and `snh stretch`: the paper's arguments, the 26 frames,
# and one-line errors with a non-zero exit code before any work is done.
# Usage: test_paper_cli.sh TETCLI TETCCLI HEXCLI SNH
set -u
TETCLI="$1" TETCCLI="$2" HEXCLI="$3" SNH="$4"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
pass=0
fail=0
# shellcheck source=lib.sh
. "$(dirname "$0")/lib.sh"  # ok, bad, wait_for, expect_exit, expect_error


# A small run of each program: 26 frames 000..025 with (res+1)^3 vertices and 12 res^2 triangles.
# Tets at res 3 and hexes at res 2: on the res-2 tet and res-3/4 hex meshes the symmetric state at the end
# of the stretch is a saddle point (the true Hessian there has a negative eigenvalue, measured), so
# whether Newton stops next to it or leaves it towards a lower, buckled state depends on rounding.
for prog in "$TETCLI" "$TETCCLI" "$HEXCLI"; do
  dir="$work/$(basename "$prog")"
  if [ "$prog" = "$HEXCLI" ]; then res=2; else res=3; fi
  nv=$(( (res + 1) ** 3 )) nf=$(( 12 * res * res ))
  if out="$("$prog" "$res" stable_neo_hookean 1.0 10.0 "$dir" 2>&1)"; then ok; else bad "$prog run: $out"; fi
  n=$(ls "$dir"/*.obj 2>/dev/null | wc -l)
  [ "$n" -eq 26 ] && ok || bad "$prog wrote $n frames"
  [ -f "$dir/000.obj" ] && [ -f "$dir/025.obj" ] && [ -f "$dir/stats.json" ] && [ -f "$dir/stats.csv" ] && ok || bad "$prog files"
  v=$(grep -c '^v ' "$dir/025.obj"); f=$(grep -c '^f ' "$dir/025.obj")
  [ "$v" -eq "$nv" ] && [ "$f" -eq "$nf" ] && ok || bad "$prog 025.obj has $v vertices, $f faces"
  printf '%s' "$out" | grep -Eq "resolution $res, material stable_neo_hookean, mu 1, lambda 10" && ok || bad "$prog header: $out"
  printf '%s' "$out" | grep -Eq "^$nv vertices, ($(( 6 * res ** 3 )) tets|$(( res ** 3 )) cubes)" && ok || bad "$prog counts: $out"
  [ "$(printf '%s\n' "$out" | grep -c '^step ')" -eq 25 ] && ok || bad "$prog step lines"
done
# tetccli is tetcli under the thesis' name: identical frames.
cmp -s "$work/$(basename "$TETCLI")/025.obj" "$work/$(basename "$TETCCLI")/025.obj" && ok || bad "tetccli differs from tetcli"

# Errors, before any work (no frame written).
expect_exit 2 "usage" "expected 4 or 5 arguments" -- "$TETCLI" 10 stable_neo_hookean 1.0
expect_error "resolution" "resolution must be an integer from 1 to 400, got 'ten'" -- "$TETCLI" ten stable_neo_hookean 1 10 "$work/e1"
expect_error "resolution 0" "resolution must be an integer from 1 to 400, got '0'" -- "$HEXCLI" 0 stable_neo_hookean 1 10 "$work/e1"
expect_error "material" "unknown material 'stable_neohookean'" -- "$TETCLI" 2 stable_neohookean 1 10 "$work/e1"
expect_error "mu" "mu must be a finite number, got 'abc'" -- "$TETCLI" 2 stable_neo_hookean abc 10 "$work/e1"
expect_error "mu negative" "mu must be a finite number > 0, got -1" -- "$TETCLI" 2 stable_neo_hookean -1 10 "$work/e1"
expect_error "lambda nan" "lambda must be a finite number, got 'nan'" -- "$TETCLI" 2 stable_neo_hookean 1 nan "$work/e1"
[ ! -e "$work/e1" ] || [ -z "$(ls -A "$work/e1")" ] && ok || bad "an error left files behind"
touch "$work/file"
expect_exit 2 "output is a file" "exists and is not a directory" -- "$TETCLI" 2 stable_neo_hookean 1 10 "$work/file"
expect_exit 3 "unwritable" "cannot create output directory|not writable" -- "$TETCLI" 2 stable_neo_hookean 1 10 /proc/snh-not-here
"$TETCLI" --help | grep -q "usage: tetcli resolution material_model mu lambda" && ok || bad "tetcli --help"

# snh stretch: named options, any material.
if "$SNH" stretch --element hex --res 2 --steps 3 --stretch 1.5 --material stable_neo_hookean_log --solver ldlt --out "$work/s" > "$work/s.log" 2>&1; then ok; else bad "snh stretch: $(cat "$work/s.log")"; fi
[ "$(ls "$work/s"/*.obj | wc -l)" -eq 4 ] && ok || bad "snh stretch frames"
grep -q '"solver": "ldlt"' "$work/s/stats.json" && ok || bad "stats.json solver"
head -1 "$work/s/stats.csv" | grep -q "^step,converged,newton_iterations,line_search_steps,linear_iterations,factorizations,residual,energy" && ok || bad "stats.csv header"
# --refactorize: a factorization for every Newton matrix, none reused.
"$SNH" stretch --element tet --res 2 --steps 3 --stretch 1.5 --refactorize --out "$work/r" > /dev/null 2>&1 && ok || bad "snh stretch --refactorize"
grep -q '"reuse_factor": false' "$work/r/stats.json" && ok || bad "stats.json reuse_factor"
its=$(sed -n 's/^  "newton_iterations": \([0-9]*\),/\1/p' "$work/r/stats.json")
facts=$(sed -n 's/^  "factorizations": \([0-9]*\),/\1/p' "$work/r/stats.json")
[ -n "$its" ] && [ "$its" -gt 0 ] && [ "$facts" -ge "$its" ] && ok || bad "--refactorize: $facts factorizations for $its Newton iterations"
expect_error "stretch solver" "solver" -- "$SNH" stretch --solver umfpack --out "$work/s2"
expect_error "stretch poisson" "Poisson's ratio must satisfy" -- "$SNH" stretch --youngs 100 --poisson 0.5 --out "$work/s3"

# Ctrl-C: the run stops cleanly with exit code 130, keeping its frames and stats.
# The signal goes once frame 0 is on disk (the run is stepping): one sent during start-up, which a loaded
# machine can stretch past any fixed delay, ends the run before its first step, with no STOPPED line.
"$SNH" stretch --element hex --res 30 --out "$work/int" > "$work/int.log" 2>&1 &
run_pid=$!
for ((i = 0; i < 3000; i++)); do [ -f "$work/int/000.obj" ] && break; sleep 0.02; done
sleep 0.5
kill -INT "$run_pid"; wait "$run_pid"; code=$?
[ "$code" -eq 130 ] && grep -q '"interrupted_by_signal": 2' "$work/int/stats.json" && [ -f "$work/int/000.obj" ] \
  && grep -q "STOPPED: interrupted" "$work/int.log" && ok || bad "SIGINT (exit $code): $(tail -2 "$work/int.log")"

# --resume: a completed run resumes at its end; an empty directory has nothing to resume.
"$SNH" stretch --element tet --res 2 --steps 3 --stretch 1.5 --out "$work/res" > /dev/null 2>&1
out="$("$SNH" stretch --element tet --res 2 --steps 3 --stretch 1.5 --out "$work/res" --resume 2>&1)"; code=$?
[ "$code" -eq 0 ] && printf '%s' "$out" | grep -q "resuming after step 3" && ok || bad "resume complete run (exit $code): $out"
out="$("$SNH" stretch --res 2 --out "$work/empty" --resume 2>&1)"; code=$?
[ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "cannot resume: .* has no checkpoint.bin" && ok || bad "resume nothing (exit $code): $out"

# A frame that could not be written (a directory in its place, in a directory given with --force) is refused
# before any work: exit 2, nothing written, the obstacle left; once it is gone the run goes through.
mkdir -p "$work/blocked/003.obj"
out="$("$SNH" stretch --element tet --res 2 --steps 5 --stretch 1.5 --out "$work/blocked" --force 2>&1)"; code=$?
[ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "snh: error: .*003.obj: is a directory, not a regular file: refusing to replace it" \
  && [ ! -e "$work/blocked/000.obj" ] && [ -d "$work/blocked/003.obj" ] && ok || bad "unwritable frame (exit $code): $out"
rmdir "$work/blocked/003.obj"
"$SNH" stretch --element tet --res 2 --steps 5 --stretch 1.5 --out "$work/blocked" --force > /dev/null 2>&1 && [ -f "$work/blocked/005.obj" ] \
  && ok || bad "the run after the obstacle is gone"

# Issue 13: option mixes that were silently ignored, and an empty --out, are refused naming both options
# (exit 2, before any work).
"$SNH" mesh box --res 1 "$work/cube.mesh" > /dev/null 2>&1 || true
for opt in "--element hex" "--res 4" "--tet-split mirrored"; do
  # shellcheck disable=SC2086
  expect_error "stretch --mesh with $opt" "(--mesh excludes ${opt%% *}|${opt%% *} excludes --mesh)" -- "$SNH" stretch --mesh "$work/cube.mesh" $opt --out "$work/mix"
done
expect_error "stability with F" "(--stability excludes --F|--F excludes --stability)" -- "$SNH" material --stability --F "1 0 0 0 1 0 0 0 1"
expect_error "stability with stretch" "(--stability excludes --stretch|--stretch excludes --stability)" -- "$SNH" material --stability --stretch 1 1 1
expect_error "stability with a name" "--stability measures every energy: drop the energy name 'stvk'" -- "$SNH" material --stability stvk
[ ! -e "$work/mix" ] && ok || bad "a refused mix wrote $work/mix"
for cmd in "stretch" "lab --quick" "run $work/none.json" "flesh $work/none.obj"; do
  # shellcheck disable=SC2086
  expect_error "$cmd --out ''" "--out: is empty: give an output directory" -- "$SNH" $cmd --out ""
done
for prog in "$TETCLI" "$HEXCLI"; do
  expect_error "$(basename "$prog") empty output_directory" "output_directory is empty" -- "$prog" 2 stable_neo_hookean 1 10 ""
done
# An output directory holding someone else's files is refused before any work (tetcli once wrote its
# frames and report/ into /), and a file that cannot be written (a file size limit: EFBIG, as a full disk)
# exits 3.
mkdir -p "$work/theirs" && echo "mine" > "$work/theirs/notes.txt"
out="$("$TETCLI" 2 stable_neo_hookean 1 10 "$work/theirs" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$out" = "tetcli: error: $work/theirs: is not empty and holds no snh run (it has notes.txt): refusing to write a run into it; choose an empty or new output directory" ] \
  && [ "$(ls -A "$work/theirs")" = "notes.txt" ] && ok || bad "tetcli into a foreign directory (exit $code): $out"
out="$( (trap '' XFSZ; ulimit -f 1; timeout 60 "$TETCLI" 2 stable_neo_hookean 1 10 "$work/full") 2>&1)"; code=$?
[ "$code" -eq 3 ] && printf '%s' "$out" | grep -q "tetcli: error: .*cannot write $work/full/.*: File too large" \
  && ok || bad "tetcli onto a full disk (exit $code): $out"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
