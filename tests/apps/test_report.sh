#!/usr/bin/env bash
# The browser report end to end: runs write index.html (unless --no-report), `snh report` rewrites it
# and reports bad directories in one line, `snh render` checks its arguments and (with Chromium) saves
# a PNG; then the pages are opened in headless Chromium by Playwright (viewer/test/report.test.mjs): a
# stretch run, a scene, a flesh run (the scene's directory made flesh-like by viewer/test/make-flesh-run.mjs)
# and a lab report, and the rendered PNGs.
# Usage: test_report.sh SNH TETCLI VIEWER_DIR SCENES_DIR
set -u
SNH="$1" TETCLI="$2" VIEWER="$3" SCENES="$4"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
pass=0 fail=0
# shellcheck source=lib.sh
. "$(dirname "$0")/lib.sh"  # ok, bad, wait_for, expect_exit, expect_error

# Runs write their report and say where it is.
out="$("$SNH" stretch --res 4 --steps 6 --stretch 2 --out "$work/run" 2>&1)"; code=$?
[ "$code" -eq 0 ] && printf '%s' "$out" | grep -q "^report: $work/run/index.html$" && [ -f "$work/run/report/snh-report.js" ] \
  && [ -f "$work/run/report/frames/006.js" ] && ok || bad "snh stretch writes its report (exit $code): $out"
out="$("$TETCLI" 3 stable_neo_hookean 1.0 10.0 "$work/tetcli" 2>&1)"; code=$?
[ "$code" -eq 0 ] && [ -f "$work/tetcli/index.html" ] && grep -q '"title":"[^"]*tetcli 3 stable_neo_hookean 1.0 10.0' \
  "$work/tetcli/report/data.js" && ok || bad "tetcli writes its report (exit $code): $out"
out="$("$SNH" run "$SCENES/hanging_bar.json" --out "$work/scene" 2>&1)"; code=$?
[ "$code" -eq 0 ] && [ -f "$work/scene/index.html" ] && ok || bad "snh run writes its report (exit $code): $out"
# A flesh run's report: the render surface (surface/, lbs/), bones.json and the USD stage; a malformed
# surface frame is named in one line.
cp -r "$work/scene" "$work/flesh"
out="$(node "$VIEWER/test/make-flesh-run.mjs" "$work/flesh" 2>&1 && "$SNH" report "$work/flesh" 2>&1)"; code=$?
[ "$code" -eq 0 ] && grep -q '"render":{"bones":\["root>middle","middle>tip","tip"\]' "$work/flesh/report/data.js" \
  && grep -q '"render":{"bones":"' "$work/flesh/report/frames/060.js" && ok || bad "snh report of a flesh run (exit $code): $out"
cp -r "$work/flesh" "$work/flesh-bad" && printf 'v 1 2\n' > "$work/flesh-bad/surface/005.obj"
out="$("$SNH" report "$work/flesh-bad" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$(printf '%s\n' "$out" | wc -l)" -eq 1 ] && printf '%s' "$out" | grep -q "^snh: error: $work/flesh-bad/surface/005.obj:1: " \
  && ok || bad "report with a malformed surface frame (exit $code): $out"
# A run with muscles: muscles.json gives the report the fibres of every frame; a malformed one is named in one line.
cat > "$work/muscle.json" <<'EOF'
{"mesh": {"box": {"min": [0, 0, 0], "max": [4, 1, 1], "res": 4}}, "material": {"youngs": 1000, "poisson": 0.45},
 "integrator": "quasi_static", "end_time": 1, "frames": 4,
 "pins": [{"region": {"min": [-0.1, -1, -1], "max": [0.1, 2, 2]}}],
 "muscles": [{"name": "belly", "region": {"min": [-1, -1, -1], "max": [5, 2, 2]}, "fibre": [1, 0, 0], "contraction": 0.3,
              "activation": [{"time": 0, "value": 0}, {"time": 1, "value": 1}]}]}
EOF
out="$("$SNH" run "$work/muscle.json" --out "$work/muscle" 2>&1)"; code=$?
[ "$code" -eq 0 ] && grep -q '"fibres":{"count":64,' "$work/muscle/report/data.js" \
  && grep -q '"fibres":{"activation":\[1.0\],"segments":"' "$work/muscle/report/frames/004.js" && ok || bad "a run with muscles: its report's fibres (exit $code): $out"
cp -r "$work/muscle" "$work/muscle-bad" && echo '{"regions": 3}' > "$work/muscle-bad/muscles.json"
out="$("$SNH" report "$work/muscle-bad" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$out" = "snh: error: $work/muscle-bad/muscles.json: not a muscles file: it needs a \"regions\" array" ] \
  && ok || bad "report with a malformed muscles.json (exit $code): $out"
"$SNH" stretch --res 2 --steps 2 --no-report --out "$work/quiet" > "$work/quiet.log" 2>&1
[ -f "$work/quiet/stats.json" ] && [ ! -e "$work/quiet/index.html" ] && ! grep -q "^report:" "$work/quiet.log" \
  && ok || bad "--no-report writes no report"
out="$("$SNH" lab --quick --energy stable_neo_hookean --energy neo_hookean --out "$work/lab" 2>&1)"; code=$?
[ "$code" -eq 0 ] && [ -f "$work/lab/index.html" ] && [ -f "$work/lab/rest/free_cube/neo_hookean/index.html" ] \
  && grep -q 'src="../../../report/snh-report.js"' "$work/lab/rest/free_cube/neo_hookean/index.html" \
  && [ ! -e "$work/lab/rest/free_cube/neo_hookean/report/snh-report.js" ] && ok || bad "snh lab writes its reports (exit $code): $out"

# snh report rewrites a report, and names what is wrong with a directory in one line (exit 2).
rm -rf "$work/quiet/report"
out="$("$SNH" report "$work/quiet" 2>&1)"; code=$?
[ "$code" -eq 0 ] && [ "$out" = "stretch report (3 frames): $work/quiet/index.html" ] && ok || bad "snh report (exit $code): $out"
out="$("$SNH" report "$work/none" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$out" = "snh: error: $work/none: does not exist" ] && ok || bad "report of a missing dir (exit $code): $out"
echo "not a run" > "$work/afile"
out="$("$SNH" report "$work/afile" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$out" = "snh: error: $work/afile: is not a directory (the output directory of a run is expected)" ] \
  && ok || bad "report of a file (exit $code): $out"
mkdir -p "$work/empty"
out="$("$SNH" report "$work/empty" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$(printf '%s\n' "$out" | wc -l)" -eq 1 ] && printf '%s' "$out" | grep -q "no stats.json or lab.json here" \
  && ok || bad "report of an empty dir (exit $code): $out"
cp -r "$work/quiet" "$work/broken" && rm "$work/broken/001.vtu"
out="$("$SNH" report "$work/broken" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$out" = "snh: error: frame 1: $work/broken/001.vtu: cannot open the mesh file" ] \
  && ok || bad "report with a missing frame (exit $code): $out"

# snh render: arguments checked before any browser starts (exit 2); a clear error without a browser.
out="$("$SNH" render "$work/run" --frame 9 --out "$work/x.png" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$out" = "snh: error: frame 9 does not exist: $work/run has frames 0 to 6" ] && ok || bad "render bad frame: $out"
out="$("$SNH" render "$work/run" --field sigma --out "$work/x.png" 2>&1)"; code=$?
[ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "unknown field 'sigma' (this run has: J, psi, displacement)" && ok || bad "render bad field: $out"
out="$("$SNH" render "$work/afile" --out "$work/x.png" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$out" = "snh: error: $work/afile: is not a directory (the output directory of a run is expected)" ] \
  && ok || bad "render of a file (exit $code): $out"
# --out must be a regular file (or a new one) in an existing directory: a directory, a FIFO or a device
# there is refused, and left as it was.
mkdir -p "$work/outdir"
out="$("$SNH" render "$work/run" --out "$work/outdir" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$out" = "snh: error: $work/outdir: is a directory (--out takes the PNG file to write)" ] && [ -d "$work/outdir" ] \
  && ok || bad "render --out a directory (exit $code): $out"
mkfifo "$work/fifo"
out="$("$SNH" render "$work/run" --out "$work/fifo" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$out" = "snh: error: $work/fifo: is a FIFO, not a regular file: refusing to replace it" ] \
  && [ -p "$work/fifo" ] && ok || bad "render --out a FIFO (exit $code): $out"
ln -s fifo "$work/fifo-link"
out="$("$SNH" render "$work/run" --out "$work/fifo-link" 2>&1)"; code=$?
[ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "fifo-link: is a FIFO, not a regular file: refusing to replace it" && [ -L "$work/fifo-link" ] \
  && ok || bad "render --out a link to a FIFO (exit $code): $out"
if mknod "$work/null" c 1 3 2> /dev/null; then
  out="$("$SNH" render "$work/run" --out "$work/null" 2>&1)"; code=$?
  [ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "null: is a character device, not a regular file: refusing to replace it" && [ -c "$work/null" ] \
    && ok || bad "render --out a device (exit $code): $out"
fi
out="$("$SNH" render "$work/run" --out "$work/nodir/x.png" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$out" = "snh: error: $work/nodir: the directory does not exist" ] && ok || bad "render --out in a missing dir (exit $code): $out"
# A browser that is missing or fails is a failure at run time (exit 1), not a bad argument.
out="$(PATH=/nonexistent SNH_CHROMIUM= "$SNH" render "$work/run" --out "$work/x.png" 2>&1)"; code=$?
[ "$code" -eq 1 ] && printf '%s' "$out" | grep -q "snh render needs Chromium, and none was found on PATH: install the Debian package chromium" \
  && [ ! -e "$work/x.png" ] && ok || bad "render without a browser (exit $code): $out"
printf '#!/bin/sh\necho "no display here" >&2\nexit 5\n' > "$work/failing-browser"
chmod +x "$work/failing-browser"
out="$("$SNH" render "$work/run" --browser "$work/failing-browser" --out "$work/x.png" 2>&1)"; code=$?
[ "$code" -eq 1 ] && [ "$out" = "snh: error: the browser $work/failing-browser ended (exit status 5) during Target.createTarget: no display here" ] \
  && [ ! -e "$work/x.png" ] && ok || bad "render with a failing browser (exit $code): $out"

# In the browser (Debian's chromium, Playwright from viewer/node_modules).
if ! command -v chromium > /dev/null; then
  bad "chromium is not installed (scripts/install-deps installs it)"
else
  out="$("$SNH" render "$work/run" --frame 4 --field psi --width 640 --height 480 --out "$work/run4.png" 2>&1)"; code=$?
  [ "$code" -eq 0 ] && [ "$out" = "$work/run4.png (640x480)" ] && ok || bad "snh render (exit $code): $out"
  run_node() {  # run_node LABEL ENV...: the Playwright checks with these variables
    local label="$1"
    shift
    if (cd "$VIEWER" && env "$@" node --test test/report.test.mjs > "$work/node.log" 2>&1); then ok
    else bad "browser checks, $label:"; grep -E "not ok|Error|assert|expected|actual|%" "$work/node.log" | head -20; fi
  }
  run_node "stretch run, lab and render" SNH_TEST_RUN_DIR="$work/run" SNH_TEST_CHECK_MIN_J=1 SNH_TEST_LAB_DIR="$work/lab" \
    SNH_TEST_RENDER_PNG="$work/run4.png" SNH_TEST_RENDER_SIZE=640x480
  run_node "scene" SNH_TEST_RUN_DIR="$work/scene"
  out="$("$SNH" render "$work/flesh" --width 640 --height 480 --out "$work/flesh.png" 2>&1)"; code=$?
  [ "$code" -eq 0 ] && [ "$out" = "$work/flesh.png (640x480)" ] && ok || bad "snh render of a flesh run (exit $code): $out"
  run_node "flesh run and its render" SNH_TEST_FLESH_DIR="$work/flesh" SNH_TEST_RENDER_PNG="$work/flesh.png" SNH_TEST_RENDER_SIZE=640x480
  run_node "a lab simulation's own report" SNH_TEST_RUN_DIR="$work/lab/inversion/reflected/stable_neo_hookean"
  run_node "muscle fibres" SNH_TEST_MUSCLE_DIR="$work/muscle"
fi

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
