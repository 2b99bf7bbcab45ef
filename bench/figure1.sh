#!/usr/bin/env bash
# The paper's Figure 1 at its size (issue 15): bones drive a hexahedral lattice of about ELEMENTS cubes
# (default 45 809, the paper's) quasi-statically, stable Neo-Hookean at nu = 0.488. The character is the
# WebXR hand of data/ (25 joints, 29 bones), playing scenes/hand_fist.json's fist (the fingers curl over
# 2 s) to END_TIME in FRAMES frames (by default 5/6 of the way, at the scene's 12 frames a second: at
# 45k hexes the closed fist's last frames squeeze flesh through itself, min det F -0.98, and stall
# without contact); the lattice resolution is the one whose cell count is nearest ELEMENTS
# (`snh run --check`). Prints the paper's three numbers per step (Newton iterations, CG iterations,
# seconds) and ends with the line
#   figure1: E elements, D dofs, N newton/step, C cg/step, S s/step, M MiB
# (D = 3 x vertices, as the paper counts its 156 078; means over the animated frames; M the peak resident set).
#
# Usage: bench/figure1.sh [ELEMENTS]
# Environment: SNH (default build/release/apps/snh), FRAMES (20), END_TIME (1.6667, seconds of the clip),
#   SOLVER (mg; any --solver name), THREADS (0: all cores), JOINT_CELLS (free: see `snh flesh --help`),
#   RADIUS_SCALE (1: the bones' default capsules; below 1 smaller ones, see `snh flesh --help`'s --radius-scale),
#   OUT (default /tmp/snh-figure1/E-SOLVER), COMPARE (a second solver, e.g. cholmod: runs it too and prints
#   the largest distance between the two runs' render surfaces, to show the same answer), REFERENCE (the run
#   directory of an earlier benchmark, e.g. a copy of OUT/run: prints how far this run's render surfaces and
#   energies are from it, frame by frame, to show that a change of the code kept the answers; exit code 1
#   when a frame's surface moved by more than 1e-6), CONTACT (1: self-contact of the skin, as
#   scenes/hand_fist_contact.json, so that the closing fingers do not squeeze flesh through itself).
# Before the figure1: line, the slowest step: `figure1.sh: slowest step K: S s (N Newton, C CG)`.
set -euo pipefail
ELEMENTS="${1:-45809}"
case "$ELEMENTS" in '' | *[!0-9]*) echo "figure1.sh: ELEMENTS must be a positive whole number, got '$ELEMENTS'" >&2; exit 2 ;; esac
root="$(cd "$(dirname "$0")/.." && pwd)"
SNH="${SNH:-$root/build/release/apps/snh}"
FRAMES="${FRAMES:-20}" END_TIME="${END_TIME:-1.6667}" SOLVER="${SOLVER:-mg}" THREADS="${THREADS:-0}" JOINT_CELLS="${JOINT_CELLS:-free}"
RADIUS_SCALE="${RADIUS_SCALE:-1}"
OUT="${OUT:-/tmp/snh-figure1/$ELEMENTS-$SOLVER}"
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3
[ -x "$SNH" ] || { echo "figure1.sh: no snh binary at $SNH (build first, or set SNH)" >&2; exit 2; }
mkdir -p "$OUT"
# REFERENCE is checked before the run: it must be an earlier run's directory, and not one this run replaces.
if [ -n "${REFERENCE:-}" ]; then
  [ -d "$REFERENCE" ] || { echo "figure1.sh: REFERENCE=$REFERENCE is not a directory (an earlier run's, e.g. a copy of OUT/run)" >&2; exit 2; }
  last="$(printf '%s/surface/%03d.obj' "$REFERENCE" "$FRAMES")"
  [ -f "$last" ] || { echo "figure1.sh: REFERENCE=$REFERENCE has no $last: not an earlier run of $FRAMES frames" >&2; exit 2; }
  for replaced in "$OUT/run" "$OUT/compare"; do
    if [ -e "$replaced" ] && [ "$(realpath "$REFERENCE")" = "$(realpath "$replaced")" ]; then
      echo "figure1.sh: REFERENCE=$REFERENCE is the directory this run replaces ($replaced): copy it elsewhere first" >&2
      exit 2
    fi
  done
fi

# scene RES SOLVER DIR FILE: the fist scene at lattice resolution RES.
scene() {
  "$PY" - "$root" "$1" "$2" "$3" "$4" "$FRAMES" "$END_TIME" "$JOINT_CELLS" "${CONTACT:-0}" "$RADIUS_SCALE" <<'EOF'
import json, sys
root, res, solver, out, path, frames, end, joints, contact, radius_scale = sys.argv[1:11]
s = json.load(open(f"{root}/scenes/hand_fist.json"))
s["flesh"]["model"] = f"{root}/data/hand/left.glb"
s["flesh"]["resolution"] = int(res)
s["flesh"]["joint_cells"] = joints
s["flesh"]["radius_scale"] = float(radius_scale)
s["frames"], s["end_time"] = int(frames), float(end)
s["solver"] = {"linear": solver}
s["output"] = {"dir": out}
if contact == "1":
    s["contact"] = {"self": True}
json.dump(s, open(path, "w"), indent=1)
EOF
}
# cells RES: the lattice's cell count at resolution RES.
cells() {
  scene "$1" "$SOLVER" "$OUT/check" "$OUT/check.json"
  "$SNH" run "$OUT/check.json" --check | sed -n 's/^checked: \([0-9]*\) hexes.*/\1/p'
}

# The resolution: the hand's lattice grows as res³ (29 847 cells at 88); step to the nearest count.
res=$("$PY" -c "print(max(4, round(88 * ($ELEMENTS / 29847) ** (1 / 3))))")
n=$(cells "$res")
if [ "$n" -lt "$ELEMENTS" ]; then dir=1; else dir=-1; fi
while :; do
  next=$((res + dir))
  [ "$next" -ge 4 ] || break
  m=$(cells "$next")
  if [ $(((m - ELEMENTS) * (m - ELEMENTS))) -lt $(((n - ELEMENTS) * (n - ELEMENTS))) ]; then res=$next n=$m; else break; fi
done
echo "figure1.sh: lattice resolution $res: $n hexes (asked for about $ELEMENTS); $FRAMES frames to t = $END_TIME s, solver $SOLVER"

# run SOLVER DIR: the benchmark run; prints the per-step table.
run() {
  rm -rf "$2"
  scene "$res" "$1" "$2" "$OUT/$1.json"
  local flags=(--no-report)
  [ "$THREADS" != 0 ] && flags+=(--threads "$THREADS")
  local code=0
  "$SNH" run "$OUT/$1.json" "${flags[@]}" > "$2.log" 2>&1 || code=$?
  if [ "$code" -ne 0 ]; then echo "figure1.sh: the $1 run stopped (exit $code): $(tail -2 "$2.log")" >&2; return 1; fi
}
run "$SOLVER" "$OUT/run"
"$PY" - "$OUT/run/stats.json" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
steps = [f for f in d["frames"] if f["frame"] > 0]
print(f"{'step':>5} {'Newton':>7} {'CG':>7} {'seconds':>9}")
for f in steps:
    print(f"{f['frame']:>5} {f['newton_iterations']:>7} {f['linear_iterations']:>7} {f['wall_seconds']:>9.3f}")
k = len(steps)
newton = sum(f["newton_iterations"] for f in steps) / k
cg = sum(f["linear_iterations"] for f in steps) / k
sec = sum(f["wall_seconds"] for f in steps) / k
slow = max(steps, key=lambda f: f["wall_seconds"])
print(f"figure1.sh: slowest step {slow['frame']}: {slow['wall_seconds']:.2f} s ({slow['newton_iterations']} Newton, "
      f"{slow['linear_iterations']} CG)")
print(f"figure1: {d['cells']} elements, {3 * d['vertices']} dofs, {newton:.1f} newton/step, {cg:.0f} cg/step, "
      f"{sec:.2f} s/step, {d['peak_memory_mib']:.0f} MiB")
EOF
# same_answers A B LABEL_A LABEL_B STRICT: how far run B's render surfaces (and, where both runs have them,
# energies) are from run A's, frame by frame; the frames whose surfaces differ by more than 1e-6 model units
# (far above the OBJ files' rounding, far below a contact's d-hat) are named, and with STRICT 1 the script
# then exits 1.
same_answers() {
  "$PY" - "$1" "$2" "$FRAMES" "$3" "$4" "$5" <<'EOF' >&2
import json, os, sys
a, b, frames, la, lb, strict = sys.argv[1:7]
def verts(path):
    return [tuple(map(float, l.split()[1:4])) for l in open(path) if l.startswith("v ")]
def energies(run):
    path = f"{run}/stats.json"
    return {f["frame"]: f["total_energy"] for f in json.load(open(path))["frames"]} if os.path.isfile(path) else {}
ea, eb = energies(a), energies(b)
worst, worst_frame, apart, de = 0.0, 0, [], 0.0
for f in range(1, int(frames) + 1):
    pa, pb = f"{a}/surface/{f:03d}.obj", f"{b}/surface/{f:03d}.obj"
    if not (os.path.isfile(pa) and os.path.isfile(pb)):
        print(f"figure1.sh: frame {f} is missing: no {pa if not os.path.isfile(pa) else pb}")
        sys.exit(1)
    p, q = verts(pa), verts(pb)
    if len(p) != len(q):
        print(f"figure1.sh: frame {f}: {len(p)} surface vertices in {la}, {len(q)} in {lb}: not the same surface")
        sys.exit(1)
    d = max(abs(x - y) for u, v in zip(p, q) for x, y in zip(u, v))
    if d > worst:
        worst, worst_frame = d, f
    if d > 1e-6:
        apart.append(f)
    if f in ea and f in eb:
        de = max(de, abs(ea[f] - eb[f]) / max(1e-300, abs(ea[f])))
print(f"figure1.sh: render surfaces of {la} and {lb}: largest distance over {frames} frames {worst:.3g} (model units)"
      + (f", at frame {worst_frame}" if worst_frame else "") + (f"; energies within {de:.2g} (relative)" if ea and eb else ""))
if apart:
    print(f"figure1.sh: frames farther apart than 1e-6: {', '.join(map(str, apart))}")
    sys.exit(1 if strict == "1" else 0)
EOF
}
if [ -n "${COMPARE:-}" ]; then
  run "$COMPARE" "$OUT/compare"
  same_answers "$OUT/run" "$OUT/compare" "$SOLVER" "$COMPARE" 0
fi
if [ -n "${REFERENCE:-}" ]; then
  same_answers "$REFERENCE" "$OUT/run" "the reference $REFERENCE" "this run" 1
fi
