#!/usr/bin/env bash
# The hand's fist with self-contact against without (issue 16's figures): runs scenes/hand_fist.json and
# scenes/hand_fist_contact.json, prints per-frame Newton iterations, seconds, contact pairs, the smallest
# distance, CCD calls and primitive pairs tested, and plots them per frame into OUT/hand_fist_contact_frames.png.
#
# Usage: bench/fist_contact.sh
# Environment: SNH (default build/release/apps/snh), OUT (default /tmp/snh-fist-contact), THREADS (0: all cores).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
SNH="${SNH:-$root/build/release/apps/snh}"
OUT="${OUT:-/tmp/snh-fist-contact}"
THREADS="${THREADS:-0}"
[ -x "$SNH" ] || { echo "fist_contact.sh: no snh binary at $SNH (build first, or set SNH)" >&2; exit 2; }
mkdir -p "$OUT"
for run in hand_fist hand_fist_contact; do
  rm -rf "${OUT:?}/$run"
  "$SNH" run "$root/scenes/$run.json" --out "$OUT/$run" --no-report --threads "$THREADS" > "$OUT/$run.log" 2>&1 \
    || { echo "fist_contact.sh: $run failed: $(tail -2 "$OUT/$run.log")" >&2; exit 1; }
done
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3
"$PY" - "$OUT/hand_fist/stats.json" "$OUT/hand_fist_contact/stats.json" "$OUT/hand_fist_contact_frames.png" <<'EOF'
import json, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
without, with_ = (json.load(open(p))["frames"][1:] for p in sys.argv[1:3])
print(" frame | without: Newton  s     | with: Newton  s      pairs  min distance  CCD calls  CCD tests")
for a, b in zip(without, with_):
    d = b["min_contact_distance"]
    print(f"  {a['frame']:3d}  |  {a['newton_iterations']:3d}  {a['wall_seconds']:7.3f}   |  {b['newton_iterations']:3d}  {b['wall_seconds']:7.3f}"
          f"  {b['contact_pairs']:5d}  {'-' if d is None else f'{d * 1000:8.3f} mm'}  {b['ccd_calls']:4d}  {b['ccd_tests']:8d}")
mean = lambda rows, k: sum(r[k] for r in rows) / len(rows)
print(f"means: without {mean(without, 'newton_iterations'):.1f} Newton, {mean(without, 'wall_seconds'):.3f} s; with "
      f"{mean(with_, 'newton_iterations'):.1f} Newton, {mean(with_, 'wall_seconds'):.3f} s, {mean(with_, 'ccd_tests'):.0f} CCD tests, "
      f"{mean(with_, 'contact_seconds'):.3f} s in contact; whole runs {sum(r['wall_seconds'] for r in without):.2f} s and "
      f"{sum(r['wall_seconds'] for r in with_):.2f} s")
f = [r["frame"] for r in with_]
fig, ax = plt.subplots(3, 1, figsize=(7, 7), dpi=120, sharex=True)
ax[0].plot(f, [r["wall_seconds"] for r in without], "o-", ms=3, label="without contact")
ax[0].plot(f, [r["wall_seconds"] for r in with_], "o-", ms=3, label="with self-contact")
ax[0].plot(f, [r["contact_seconds"] for r in with_], "--", label="of which in the contact terms")
ax[0].set_ylabel("seconds per frame")
ax[0].legend(fontsize=8)
ax[1].bar(f, [r["contact_pairs"] for r in with_], color="tab:orange", label="contact pairs at the solution")
ax[1].plot(f, [r["ccd_calls"] for r in with_], "k.-", label="CCD calls (line searches, guesses)")
ax[1].set_ylabel("count")
ax[1].legend(fontsize=8)
ax[2].plot(f, [None if r["min_contact_distance"] is None else r["min_contact_distance"] * 1000 for r in with_], "o-", ms=3,
           color="tab:green")
ax[2].set_ylabel("smallest distance (mm)")
ax[2].set_xlabel("frame (12 per second; the fingers close by frame 24, then the wrist turns)")
ax[2].set_ylim(bottom=0)
for a in ax:
    a.grid(True, alpha=0.3)
fig.suptitle("The hand's fist: self-contact of the skin against none, per frame")
fig.tight_layout()
fig.savefig(sys.argv[3])
print(f"plot: {sys.argv[3]}")
EOF
