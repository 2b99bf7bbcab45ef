#!/usr/bin/env bash
# Pictures and videos of a flesh run (issue 35), on the WebXR hand of data/ (Chromium and ffmpeg):
#   the flesh's distance from its skinned surface is zero (to a micron) where the bones move it rigidly and
#   millimetres where the fist closes; the framing holds the shape in every view (viewer/test/report.test.mjs
#   on the real hand); --video writes an .mp4 and a .gif with the frames and size asked for (ffprobe); bad
#   video options are one line each, a missing ffmpeg names its Debian package, Ctrl-C during a video
#   leaves nothing.
# Usage: test_pictures.sh SNH DATA_DIR VIEWER_DIR
set -u
SNH="$1" DATA="$(cd "$2" && pwd)" VIEWER="$3"
work="$(mktemp -d)"
pid=""
trap '[ -n "$pid" ] && kill -9 "$pid" 2> /dev/null; rm -rf "$work"' EXIT
pass=0 fail=0
# shellcheck source=lib.sh
. "$(dirname "$0")/lib.sh"  # ok, bad, wait_for, expect_exit, expect_error
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3

# hand NAME KEYS: a short hand run at lattice resolution 12, its wrist (the root) or fingers turned by KEYS.
hand() {
  cat > "$work/$1.json" <<JSON
{"flesh": {"model": "$DATA/hand/left.glb", "volume": "lattice", "resolution": 12, "keyframes": [$2]},
 "end_time": 1, "frames": 6, "output": {"dir": "$work/$1"}}
JSON
  "$SNH" run "$work/$1.json" > "$work/$1.log" 2>&1 || bad "the $1 run: $(tail -1 "$work/$1.log")"
}
hand rigid '{"joints": ["wrist"], "keys": [{"time": 0, "axis": [0, 1, 0], "degrees": 0}, {"time": 1, "axis": [0.3, 1, 0.2], "degrees": 70}]}'
hand fist '{"joints": ["index-finger-phalanx-proximal", "middle-finger-phalanx-proximal"], "keys": [{"time": 0, "axis": [1, 0, 0], "degrees": 0}, {"time": 1, "axis": [1, 0, 0], "degrees": 80}]}'

# largest DIR: the largest |distance| (mm) of the flesh from the skinned surface over the report's frames.
largest() {
  "$PY" - "$1" <<'PY'
import base64, json, struct, sys, glob
worst = 0.0
for path in sorted(glob.glob(sys.argv[1] + "/report/frames/*.js")):
    text = open(path).read()
    frame = json.loads(text[text.index(",") + 1:text.rindex(")")])
    raw = base64.b64decode(frame["render"]["distance"])
    worst = max([worst] + [abs(v) for v in struct.unpack("<%df" % (len(raw) // 4), raw)])
print(worst)
PY
}
rigid=$(largest "$work/rigid") fist=$(largest "$work/fist")
"$PY" -c "import sys; sys.exit(0 if float('$rigid') < 1e-3 else 1)" && ok || bad "a rigid motion: the flesh lies $rigid mm from its skinned surface"
"$PY" -c "import sys; sys.exit(0 if float('$fist') > 1.0 else 1)" && ok || bad "fingers bending: the flesh lies only $fist mm from its skinned surface"
# The report's plot of the largest distance per frame: one point per frame, zero (to a micron) for the rigid run.
"$PY" - "$work/rigid/report/data.js" <<'PY' && ok || bad "the rigid run's lbs_surface_distance plot"
import json, sys
text = open(sys.argv[1]).read()
d = json.loads(text[text.index("=") + 1:].strip().rstrip(";"))
p = [p for p in d["plots"] if p["id"] == "lbs_surface_distance"][0]
ys = p["series"][0]["y"] + p["series"][1]["y"]
sys.exit(0 if len(p["x"]) == 7 and all(y is not None and 0 <= y < 1e-3 for y in ys) else 1)
PY

# The framing and the views in the browser, on this real character.
if (cd "$VIEWER" && SNH_TEST_FRAMING_DIR="$work/fist" node --test test/report.test.mjs > "$work/node.log" 2>&1) \
  && grep -q "^# pass 1$" "$work/node.log"; then ok
else bad "framing the hand:"; grep -E "not ok|Error|assert|expected|actual" "$work/node.log" | head -10; fi

# Two runs of the hand compared: a picture; runs with other frame counts are refused.
out="$("$SNH" render "$work/fist" --compare "$work/rigid" --show flesh,difference --width 320 --height 240 --out "$work/cmp.png" 2>&1)"; code=$?
[ "$code" -eq 0 ] && [ "$out" = "$work/cmp.png (320x240)" ] && ok || bad "--compare (exit $code): $out"
sed 's/"frames": 6/"frames": 4/; s#"dir": "[^"]*"#"dir": "'"$work"'/short"#' "$work/rigid.json" > "$work/short.json"
"$SNH" run "$work/short.json" > /dev/null 2>&1 || bad "the short run"
expect_error "--compare with other frames" "^snh: error: --compare: .*/short has 5 frames, .*/fist has 7: runs of one animation" -- \
  "$SNH" render "$work/fist" --compare "$work/short" --out "$work/x.png"

# Videos: every frame (or a range) at the size asked for, at the run's rate (6 frames a second here).
out="$("$SNH" render "$work/fist" --video "$work/fist.mp4" --width 320 --height 240 --show flesh,lbs 2>&1)"; code=$?
[ "$code" -eq 0 ] && [ "$out" = "$work/fist.mp4 (320x240, 7 frames at 6 a second)" ] && ok || bad "--video .mp4 (exit $code): $out"
probe() { ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames,width,height -of csv=p=0 "$1" 2>&1; }
[ "$(probe "$work/fist.mp4")" = "320,240,7" ] && ok || bad "the .mp4: $(probe "$work/fist.mp4")"
out="$("$SNH" render "$work/fist" --video "$work/fist.gif" --width 200 --height 150 --frames 2:5 --show difference 2>&1)"; code=$?
[ "$code" -eq 0 ] && [ "$(probe "$work/fist.gif")" = "200,150,4" ] && ok || bad "--video .gif --frames 2:5 (exit $code): $out $(probe "$work/fist.gif")"
expect_error "--frames past the end" "^snh: error: --frames 3:9: .* has frames 0 to 6$" -- "$SNH" render "$work/fist" --video "$work/x.mp4" --frames 3:9
expect_error "--frames backwards" "^snh: error: --frames 5:2: " -- "$SNH" render "$work/fist" --video "$work/x.mp4" --frames 5:2
expect_error "--frames without a colon" "^snh: error: --frames 3: expected FIRST:LAST" -- "$SNH" render "$work/fist" --video "$work/x.mp4" --frames 3
expect_error "an odd size for .mp4" "needs an even width and height .* got 321x240$" -- "$SNH" render "$work/fist" --video "$work/x.mp4" --width 321 --height 240
expect_error "a video of another kind" "x.avi: a video is .mp4 \(H.264\) or .gif" -- "$SNH" render "$work/fist" --video "$work/x.avi"
expect_error "--frame with a video" "--frame picks a picture's frame; a video takes --frames" -- "$SNH" render "$work/fist" --video "$work/x.mp4" --frame 2
expect_error "--out and --video" "excludes|give --out" -- "$SNH" render "$work/fist" --video "$work/x.mp4" --out "$work/x.png"
expect_error "neither --out nor --video" "give --out PICTURE.png, or --video" -- "$SNH" render "$work/fist"
[ ! -e "$work/x.mp4" ] && [ ! -e "$work/x.png" ] && ok || bad "a refused video wrote a file"
# Without ffmpeg: exit 1, the package named, nothing written.
mkdir -p "$work/bin" && ln -s "$(command -v chromium)" "$work/bin/chromium"
out="$(PATH="$work/bin" "$SNH" render "$work/fist" --video "$work/none.mp4" --width 160 --height 120 2>&1)"; code=$?
[ "$code" -eq 1 ] && printf '%s' "$out" | grep -q "needs ffmpeg, and it could not be run: install the Debian package ffmpeg" && [ ! -e "$work/none.mp4" ] \
  && ok || bad "--video without ffmpeg (exit $code): $out"
# Ctrl-C while the frames are drawn: exit 130, no video, no temporary files.
mkdir -p "$work/tmp"
TMPDIR="$work/tmp" "$SNH" render "$work/fist" --video "$work/stopped.mp4" --width 320 --height 240 > "$work/stopped.log" 2>&1 &
pid=$!
for ((i = 0; i < 500; i++)); do [ -n "$(ls "$work/tmp"/*/frame00001.png 2> /dev/null)" ] && break; sleep 0.02; done
kill -INT "$pid"
wait "$pid"
code=$?
pid=""
sleep 0.2
[ "$code" -eq 130 ] && [ ! -e "$work/stopped.mp4" ] && [ -z "$(ls -A "$work/tmp")" ] && ok \
  || bad "Ctrl-C during a video (exit $code): $(cat "$work/stopped.log"), left: $(ls -A "$work/tmp")"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
