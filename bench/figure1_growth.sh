#!/usr/bin/env bash
# Growth of bench/figure1.sh with the lattice's size (issue 15): runs it at each ELEMENTS (default about
# 25k, 50k, 100k and 200k hexes), with FRAMES (default 8) frames over END_TIME (default 2/3 s: the same
# motion per frame as figure1.sh's default 24 frames over 2 s), and writes figure1_growth.csv and
# figure1_growth.png (seconds per step against elements, log-log, with the line of linear growth) in OUT.
# Usage: bench/figure1_growth.sh [ELEMENTS ...]
# Environment: as figure1.sh (SNH, SOLVER, THREADS, JOINT_CELLS, RADIUS_SCALE, CONTACT; not REFERENCE, which is refused),
# OUT (default /tmp/snh-figure1-growth), BESIDE (an earlier run's figure1_growth.csv, drawn beside this run's
# curve in the plot, e.g. the same sizes with the default capsules) and BESIDE_LABEL (its legend, default
# "earlier run").
# With contact, run the frames where the fingers meet too: CONTACT=1 FRAMES=20 END_TIME=1.6667.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
# figure1.sh's REFERENCE names one earlier run, of one size: it cannot serve every size here.
if [ -n "${REFERENCE:-}" ]; then
  echo "figure1_growth.sh: REFERENCE compares one run with an earlier run of the same size: use it with bench/figure1.sh" >&2
  exit 2
fi
# BESIDE is checked before anything runs: a table this script wrote.
if [ -n "${BESIDE:-}" ]; then
  # Its header, then rows of six numbers (the plot reads them only after every run).
  if [ ! -f "$BESIDE" ] || [ "$(head -1 "$BESIDE" 2>/dev/null)" != "elements,dofs,newton_per_step,cg_per_step,seconds_per_step,peak_mib" ] ||
    ! tail -n +2 "$BESIDE" | awk -F, 'NF != 6 { exit 1 } { for (i = 1; i <= 6; ++i) if ($i !~ /^[0-9]+(\.[0-9]+)?$/ || (i == 5 && $i + 0 <= 0)) exit 1 }'; then
    echo "figure1_growth.sh: BESIDE=$BESIDE is not a figure1_growth.csv (an earlier run's table, from its OUT)" >&2
    exit 2
  fi
fi
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(25000 50000 100000 200000)
OUT="${OUT:-/tmp/snh-figure1-growth}"
export FRAMES="${FRAMES:-8}" END_TIME="${END_TIME:-0.6667}"
mkdir -p "$OUT"
csv="$OUT/figure1_growth.csv"
echo "elements,dofs,newton_per_step,cg_per_step,seconds_per_step,peak_mib" > "$csv"
failed=()
for e in "${sizes[@]}"; do
  if ! OUT="$OUT/$e" "$here/figure1.sh" "$e" 2>&1 | tee "$OUT/$e.log"; then
    # A size whose run stops (a step that does not converge) is left out of the table and the plot, and named.
    failed+=("$e")
    continue
  fi
  tail -1 "$OUT/$e.log" | sed -n 's/^figure1: \([0-9]*\) elements, \([0-9]*\) dofs, \([0-9.]*\) newton\/step, \([0-9]*\) cg\/step, \([0-9.]*\) s\/step, \([0-9]*\) MiB$/\1,\2,\3,\4,\5,\6/p' >> "$csv"
done
cat "$csv"
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3
[ "$(wc -l < "$csv")" -gt 1 ] && "$PY" - "$csv" "$OUT/figure1_growth.png" "${CONTACT:-0}" "${RADIUS_SCALE:-1}" "${BESIDE:-}" \
  "${BESIDE_LABEL:-earlier run}" <<'EOF'
import csv, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
radius_scale, beside, beside_label = float(sys.argv[4]), sys.argv[5], sys.argv[6]


def curve(path):
    rows = list(csv.DictReader(open(path)))
    return rows, [int(r["elements"]) for r in rows], [float(r["seconds_per_step"]) for r in rows]


rows, e, s = curve(sys.argv[1])
fig, ax = plt.subplots(figsize=(6, 4), dpi=120)
label = "snh (mg), seconds per step"
if radius_scale != 1.0:
    label += f", capsule radii {radius_scale:g} x the default"
ax.loglog(e, s, "o-", label=label)
if beside:
    _, be, bs = curve(beside)
    ax.loglog(be, bs, "s-", color="tab:red", label=f"{beside_label}, seconds per step")
ax.loglog(e, [s[0] * x / e[0] for x in e], "--", color="gray", label="linear growth from the smallest")
for x, y, r in zip(e, s, rows):
    ax.annotate(f"{float(r['newton_per_step']):.1f} Newton, {r['cg_per_step']} CG", (x, y), textcoords="offset points",
                xytext=(6, -12), fontsize=7)
ax.set_xlabel("hexahedra")
ax.set_ylabel("seconds per quasi-static step")
# Two lines: with ", self-contact" one line was wider than the figure and was cut at both ends.
ax.set_title("Bone-driven hand lattice (nu = 0.488)" + (", self-contact" if sys.argv[3] == "1" else "") + "\ntime per step against size",
             fontsize=10)
ax.legend(fontsize=8)
ax.grid(True, which="both", alpha=0.3)
fig.tight_layout()
fig.savefig(sys.argv[2])
print(f"plot: {sys.argv[2]}")
EOF
if [ ${#failed[@]} -gt 0 ]; then
  echo "figure1_growth.sh: the runs at ${failed[*]} hexes stopped (their logs: $OUT/<hexes>.log); left out above" >&2
  exit 1
fi
