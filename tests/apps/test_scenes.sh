#!/usr/bin/env bash
# Every scene in scenes/ runs to its end with `snh run` (exit 0), writing its frames and stats;
# `snh run` reports bad scene files in one line with exit code 2; `snh lab` prints and writes its report.
# Usage: test_scenes.sh SNH SCENES_DIR
set -u
SNH="$1" SCENES="$2"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
pass=0 fail=0
# shellcheck source=lib.sh
. "$(dirname "$0")/lib.sh"  # ok, bad, wait_for, expect_exit, expect_error

for scene in "$SCENES"/*.json; do
  name="$(basename "$scene" .json)"
  if "$SNH" run "$scene" --out "$work/$name" > "$work/$name.log" 2>&1; then ok; else bad "$name: $(tail -3 "$work/$name.log")"; fi
  [ -f "$work/$name/000.obj" ] && [ -f "$work/$name/stats.json" ] && [ -f "$work/$name/stats.csv" ] && [ -f "$work/$name/frames.pvd" ] \
    && ok || bad "$name: output files"
  grep -q '"all_converged": true' "$work/$name/stats.json" && ok || bad "$name: stats.json all_converged"
done

# A run whose converged frames hold inverted elements (the crush of a cube to a point) says so on its closing
# line (before the report's).
grep -Eq '^finished, [0-9]+ frames with inverted elements \(warning: flesh turned inside out; at most [0-9]+, in frame [0-9]+\)' \
  "$work/crush_point.log" && ok || bad "crush_point: closing line $(tail -2 "$work/crush_point.log")"

# Bad scene files: one line naming the file and key, exit code 2.
printf '{"gravty": [0, -9.8, 0]}' > "$work/typo.json"
out="$("$SNH" run "$work/typo.json" --out "$work/t" 2>&1)"; code=$?
[ "$code" -eq 2 ] && [ "$(printf '%s\n' "$out" | wc -l)" -eq 1 ] && printf '%s' "$out" | grep -q "typo.json: gravty: unknown key" \
  && ok || bad "typo (exit $code): $out"
out="$("$SNH" run "$work/missing.json" 2>&1)"; code=$?
[ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "missing.json: cannot open the scene file" && ok || bad "missing (exit $code): $out"
# A start outside the energy's domain: reported, exit code 1, frame 0 kept.
printf '{"mesh": {"box": {"res": 2}}, "material": {"name": "neo_hookean"}, "initial": [{"type": "reflect"}]}' > "$work/inv.json"
out="$("$SNH" run "$work/inv.json" --out "$work/inv" 2>&1)"; code=$?
[ "$code" -eq 1 ] && printf '%s' "$out" | grep -q "initial state is outside the domain of neo_hookean" && [ -f "$work/inv/000.obj" ] \
  && ok || bad "inverted start (exit $code): $out"

# --check: the flesh scene's volume and sizes printed, exit 0, nothing written; a bad scene still exit 2.
out="$("$SNH" run "$SCENES/hand_fist.json" --check --out "$work/checked" 2>&1)"; code=$?
[ "$code" -eq 0 ] && printf '%s' "$out" | grep -q "^volume: hexahedral lattice at resolution 24 .*: [0-9]* cells" &&
  printf '%s' "$out" | grep -Eq "^checked: [0-9]+ hexes, [0-9]+ vertices, [0-9]+ free DOFs; no frame run" && [ ! -e "$work/checked" ] \
  && ok || bad "--check (exit $code): $out"
out="$("$SNH" run "$work/typo.json" --check 2>&1)"; code=$?
[ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "gravty: unknown key" && ok || bad "--check of a bad scene (exit $code): $out"

# Shape colliders smaller than the surface's triangles: their barrier keeps them off the points only, so a
# sphere of radius 0.1 between the 0.25-spaced vertices of a falling box passed through it with exit 0. Its
# faces are checked now: a shape meeting them (swept at 50 m or 1e6 m in a frame) fails the frame, one that
# starts on them or inside the body is refused, and one that stays clear runs as before.
shape_scene() {  # FILE COLLIDER-JSON
  printf '{"mesh": {"box": {"element": "hex", "res": 4, "min": [-0.5, 0, -0.5], "max": [0.5, 1, 0.5]}},
  "material": {"name": "stable_neo_hookean", "youngs": 1e5, "poisson": 0.45}, "integrator": "backward_euler",
  "end_time": 0.2, "frames": 4, "gravity": [0, -9.81, 0], "contact": {"dhat": 0.01},
  "colliders": [{"type": "plane", "point": [0, -0.1, 0], "normal": [0, 1, 0]}, %s]}' "$2" > "$1"
}
shape_scene "$work/through.json" '{"type": "sphere", "center": [-25, 0.625, 0.125], "radius": 0.1,
  "motion": [{"type": "translate", "by": [50, 0, 0], "start": 0.05, "end": 0.1}]}'
shape_scene "$work/sweep.json" '{"type": "sphere", "center": [-5e5, 0.625, 0.125], "radius": 0.1,
  "motion": [{"type": "translate", "by": [1e6, 0, 0], "start": 0.05, "end": 0.1}]}'
for name in through sweep; do
  out="$("$SNH" run "$work/$name.json" --no-report --out "$work/$name" 2>&1)"; code=$?
  [ "$code" -eq 1 ] && printf '%s' "$out" | grep -q "^STOPPED: frame 2, colliders\[1\] (sphere) meets the mesh's surface at t = 0.07[0-9]*, triangle [0-9]*, between its points" \
    && [ -f "$work/$name/failed_002.obj" ] && [ ! -e "$work/$name/002.obj" ] && ok || bad "$name (exit $code): $(printf '%s' "$out" | tail -2)"
done
shape_scene "$work/inside.json" '{"type": "sphere", "center": [0, 0.5, 0], "radius": 0.1}'
shape_scene "$work/box_face.json" '{"type": "box", "center": [-0.5, 0.625, 0.125], "size": [0.1, 0.1, 0.1]}'
shape_scene "$work/capsule_face.json" '{"type": "capsule", "a": [-0.6, 0.625, 0.125], "b": [-0.4, 0.625, 0.125], "radius": 0.05}'
shape_scene "$work/clear.json" '{"type": "sphere", "center": [-0.7, 0.625, 0.125], "radius": 0.1}'
expect_error inside "inside.json: colliders\[1\]: the sphere lies inside the mesh's surface at the start \\(winding number 1.00" -- "$SNH" run "$work/inside.json" --out "$work/bad_inside"
expect_error box_face "box_face.json: colliders\[1\] \\(box\\) meets the mesh's surface at t = 0, triangle" -- "$SNH" run "$work/box_face.json" --out "$work/bad_box"
expect_error capsule_face "capsule_face.json: colliders\[1\] \\(capsule\\) meets the mesh's surface at t = 0, triangle" -- "$SNH" run "$work/capsule_face.json" --out "$work/bad_capsule"
"$SNH" run "$work/clear.json" --no-report --out "$work/clear" > "$work/clear.log" 2>&1 && ok || bad "clear: $(tail -2 "$work/clear.log")"

# A sphere driven into a pinned box faster than the box can give: the frame fails with the sphere placed at
# the time reached, a point of the box inside it. Its line says so (it printed a negative "min distance").
printf '{"mesh": {"box": {"element": "hex", "res": 4, "min": [-0.5, 0, -0.5], "max": [0.5, 1, 0.5]}},
  "material": {"name": "stable_neo_hookean", "youngs": 1e5, "poisson": 0.45}, "integrator": "backward_euler",
  "end_time": 0.2, "frames": 4, "gravity": [0, 0, 0], "contact": {"dhat": 0.01},
  "pins": [{"region": {"min": [-1, -1, -1], "max": [1, 0.01, 1]}}],
  "colliders": [{"type": "sphere", "center": [0, 2, 0], "radius": 0.3,
  "motion": [{"type": "translate", "by": [0, -2, 0], "start": 0.05, "end": 0.1}]}]}' > "$work/crush.json"
out="$("$SNH" run "$work/crush.json" --no-report --out "$work/crush" 2>&1)"; code=$?
[ "$code" -eq 1 ] && printf '%s' "$out" | grep -q "^frame   2/4: .*NOT CONVERGED: .*, 1 contact pairs, a point [0-9.e-]* inside a collider$" \
  && ! printf '%s' "$out" | grep -q "min distance -" && ok || bad "crush (exit $code): $(printf '%s' "$out" | tail -2)"

# Self-contact at a d̂ near the surface's spacing or above it: the barrier would push the surface apart from
# itself everywhere, and at d̂ = 1 on the 20 cm hand every primitive paired with every other (915 529 pairs,
# 4.2 GB, over 3 minutes without finishing a frame). Refused before the first frame, naming a d̂ to give.
printf '{"mesh": {"box": {"element": "hex", "res": 4}}, "material": {"name": "stable_neo_hookean"}, "contact": {"dhat": 0.6, "self": true}}' > "$work/crowd.json"
expect_error crowded_box "crowd.json: contact.self: dhat 0.6 puts 100% of the vertices of the mesh's surface \\(98 of 98\\) within dhat of parts of the surface they do not share at the start \\(.* pairs, the closest .* apart\\): the barrier would push the surface apart from itself; give a dhat below" -- "$SNH" run "$work/crowd.json" --out "$work/crowd"
data="$(cd "$SCENES/../data" && pwd)"
sed -e "s|\.\./data/|$data/|" -e 's/"self": true/"self": true, "dhat": 1/' "$SCENES/hand_fist_contact.json" > "$work/hand_dhat.json"
expect_error hand_dhat_1 "hand_dhat.json: contact.self: dhat 1 is too large for the render surface \\(welded\\): more than [0-9]* pairs of its primitives \\(64 a primitive\\) lie within it at the start, .* give a dhat well below its mean edge length 0.0067" -- "$SNH" run "$work/hand_dhat.json" --out "$work/hand_dhat"
[ ! -e "$work/hand_dhat" ] && ok || bad "hand_dhat_1: wrote its directory"

# snh lab: tables by default, JSON with --json, lab.json and the runs' frames written.
out="$("$SNH" lab --quick --energy stable_neo_hookean --out "$work/lab" 2>/dev/null)"; code=$?
[ "$code" -eq 0 ] && printf '%s' "$out" | grep -q "^stable_neo_hookean .*stays at rest" && [ -f "$work/lab/lab.json" ] \
  && [ -f "$work/lab/degeneracy/below_trap/stable_neo_hookean/stats.json" ] && ok || bad "snh lab (exit $code): $out"
"$SNH" lab --quick --energy psi_d --json --out "$work/lab2" 2>/dev/null | grep -q '"energies": \[' && ok || bad "snh lab --json"
out="$("$SNH" lab --energy bogus 2>&1)"; code=$?
[ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "^snh: error: --energy" && ok || bad "lab bad energy (exit $code): $out"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
