#!/usr/bin/env bash
# The biceps bulge of scenes/arm_flex.json (issue 33's figures): runs the scene as it is (the biceps contracts
# by its line of action as the elbow flexes) and with its contraction set to 0 (the same materials and
# fibres, passive), then measures the upper arm's cross-section at the biceps' middle (the skin vertices whose
# rest x lies in [0.13, 0.17]; the shoulder does not move, so the humerus stays on the x axis): the front's
# height (largest y), the thickness (largest y − smallest y) and the mean distance from the axis, at rest and
# at the last frame of both runs.
#
# Usage: bench/arm_bulge.sh
# Environment: SNH (default build/release/apps/snh), OUT (default /tmp/snh-arm-bulge).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
SNH="${SNH:-$root/build/release/apps/snh}"
OUT="${OUT:-/tmp/snh-arm-bulge}"
[ -x "$SNH" ] || { echo "arm_bulge.sh: no snh binary at $SNH (build first, or set SNH)" >&2; exit 2; }
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3
mkdir -p "$OUT"
# The passive copy: contraction 0, its model and region files found from the scenes directory.
"$PY" - "$root/scenes/arm_flex.json" "$OUT/arm_passive.json" "$root/scenes" <<'EOF2'
import json, os, sys
s = json.load(open(sys.argv[1]))
base = sys.argv[3]
s["flesh"]["model"] = os.path.normpath(os.path.join(base, s["flesh"]["model"]))
for m in s["muscles"]:
    m["contraction"] = 0
    m["region"]["mesh"] = os.path.normpath(os.path.join(base, m["region"]["mesh"]))
json.dump(s, open(sys.argv[2], "w"), indent=1)
EOF2
for run in active passive; do
  scene="$root/scenes/arm_flex.json"
  [ "$run" = passive ] && scene="$OUT/arm_passive.json"
  rm -rf "${OUT:?}/$run"
  "$SNH" run "$scene" --out "$OUT/$run" --no-report > "$OUT/$run.log" 2>&1 \
    || { echo "arm_bulge.sh: $run failed: $(tail -2 "$OUT/$run.log")" >&2; exit 1; }
done
"$PY" - "$OUT/active" "$OUT/passive" "$OUT/arm_bulge.png" <<'EOF2'
import glob, math, sys
def read(path):
    return [tuple(map(float, l.split()[1:4])) for l in open(path) if l.startswith("v ")]
def section(rest, now):
    pts = [p for r, p in zip(rest, now) if 0.13 <= r[0] <= 0.17]
    ys = [p[1] for p in pts]
    return max(ys), max(ys) - min(ys), sum(math.hypot(p[1], p[2]) for p in pts) / len(pts)
rows = []
for d in sys.argv[1:3]:
    frames = sorted(glob.glob(d + "/surface/[0-9][0-9][0-9].obj"))
    rest = read(frames[0])
    rows.append((d, section(rest, rest), section(rest, read(frames[-1]))))
print("cross-section at x in [0.13, 0.17] (metres)  front height  thickness  mean radius")
print("rest                                          %.4f        %.4f     %.4f" % rows[0][1])
for name, (d, _, last) in zip(("flexed, biceps passive", "flexed, biceps active"), (rows[1], rows[0])):
    print("%-45s %.4f        %.4f     %.4f" % ((name,) + last))
a, p = rows[0][2], rows[1][2]
print("the active biceps raises the front by %.1f mm and thickens the arm by %.1f mm (%.1f%%)"
      % (1000 * (a[0] - p[0]), 1000 * (a[1] - p[1]), 100 * (a[1] / p[1] - 1)))
# The front's profile along the upper arm: per ring of the skin (its vertices share their rest x), the
# largest y, at rest and at the last frame of both runs.
try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    sys.exit(0)
def profile(rest, now):
    rings = {}
    for r, p in zip(rest, now):
        if r[0] <= 0.27:
            key = round(r[0], 6)
            rings[key] = max(rings.get(key, -1.0), p[1])
    xs = sorted(rings)
    return xs, [1000 * rings[x] for x in xs]
fig, (ax, cut) = plt.subplots(1, 2, figsize=(10, 3.4), dpi=110, gridspec_kw={"width_ratios": [1.7, 1]})
active_frames = sorted(glob.glob(sys.argv[1] + "/surface/[0-9][0-9][0-9].obj"))
passive_frames = sorted(glob.glob(sys.argv[2] + "/surface/[0-9][0-9][0-9].obj"))
rest = read(active_frames[0])
for label, path, style in (("rest", active_frames[0], ":"), ("flexed 110°, biceps passive", passive_frames[-1], "--"),
                           ("flexed 110°, biceps active (contraction 0.3)", active_frames[-1], "-")):
    xs, ys = profile(rest, read(path))
    ax.plot([100 * x for x in xs], ys, style, label=label)
ax.axvspan(5, 25, color="0.9", zorder=0, label="biceps region")
ax.set_xlabel("distance from the shoulder along the upper arm (cm)")
ax.set_ylabel("front of the skin, y (mm)")
ax.legend(fontsize=8, loc="lower center")
ax.set_title("scenes/arm_flex.json: the upper arm's front at the last frame", fontsize=9)
# The cross-section at the biceps' middle: the skin's ring nearest x = 0.15 at rest, in the plane across the arm.
ring_x = min({round(r[0], 6) for r in rest}, key=lambda x: abs(x - 0.15))
for label, path, style in (("rest", active_frames[0], ":"), ("passive", passive_frames[-1], "--"), ("active", active_frames[-1], "-")):
    now = read(path)
    pts = [(p[2], p[1]) for r, p in zip(rest, now) if round(r[0], 6) == ring_x]
    pts.sort(key=lambda q: math.atan2(q[1], q[0]))
    pts.append(pts[0])
    cut.plot([1000 * q[0] for q in pts], [1000 * q[1] for q in pts], style, label=label)
cut.set_aspect("equal")
cut.set_xlabel("z (mm)")
cut.set_ylabel("y (mm), the front up")
cut.set_title("the skin's ring at x = %.1f cm" % (100 * ring_x), fontsize=9)
cut.legend(fontsize=8, loc="lower center")
fig.tight_layout()
fig.savefig(sys.argv[3])
print("plot: " + sys.argv[3])
EOF2
