#!/usr/bin/env python3
"""Secondary motion: the arm's elbow flexes 90 degrees in 0.15 s and stops (scenes/arm_flick.json); how far the
skin is from where skinning puts it, frame by frame, by backward Euler, BDF2 and TR-BDF2 (the same scene,
the same dt and damping), and by BDF2 without the scene's damping. Backward Euler's flesh comes to rest at
once; BDF2's and TR-BDF2's swing about their offset and settle; undamped it keeps swinging.

  python3 bench/secondary_motion.py [--snh build/release/apps/snh] [--plot docs/arm_flick.png]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--snh", default=os.path.join(ROOT, "build/release/apps/snh"))
    p.add_argument("--plot", help="write a PNG of the skin's largest offset from skinning over time")
    a = p.parse_args()
    scene = json.load(open(os.path.join(ROOT, "scenes/arm_flick.json")))
    scene["flesh"]["model"] = os.path.join(ROOT, "data/arm/arm.gltf")
    runs = {}
    with tempfile.TemporaryDirectory() as work:
        damping = scene["damping"]
        for label, integrator, damped in (("backward Euler", "backward_euler", True), ("BDF2", "bdf2", True),
                                          ("TR-BDF2", "tr_bdf2", True), ("BDF2, undamped", "bdf2", False)):
            scene["integrator"] = integrator
            if damped:
                scene["damping"] = damping
            else:
                scene.pop("damping", None)
            path = os.path.join(work, integrator + ".json")
            json.dump(scene, open(path, "w"))
            out = os.path.join(work, integrator + ("" if damped else "_undamped"))
            subprocess.run([a.snh, "run", path, "--out", out, "--no-report"], check=True, stdout=subprocess.DEVNULL)
            s = json.load(open(os.path.join(out, "stats.json")))
            runs[label] = ([f["time"] for f in s["frames"]], [1000 * f["lbs_distance"] for f in s["frames"]], s["total_seconds"])
    stop = 0.15
    print(f"elbow 0 -> 90 degrees in {stop} s, then held; the skin's largest offset from skinning (mm)")
    print(f"{'integrator':<16} {'at the stop':>12} {'swing after it (max - min)':>28} {'over the last 0.1 s':>20} {'seconds':>8}")
    for label, (t, d, seconds) in runs.items():
        after = [x for ti, x in zip(t, d) if ti > stop + 1e-9]
        last = [x for ti, x in zip(t, d) if ti > t[-1] - 0.1 + 1e-9]
        at_stop = d[min(range(len(t)), key=lambda i: abs(t[i] - stop))]
        print(f"{label:<16} {at_stop:12.1f} {max(after) - min(after):28.1f} {max(last) - min(last):20.2f} {seconds:8.1f}")
    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(8, 3.4), dpi=110)
        for label, (t, d, _) in runs.items():
            ax.plot(t, d, label=label, lw=1.5 if "undamped" not in label else 1.0)
        ax.axvline(stop, color="0.6", lw=0.8, ls="--")
        ax.text(stop, ax.get_ylim()[1], " the elbow stops", va="top", fontsize=8, color="0.4")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("largest skin offset (mm)")
        ax.set_title("Secondary motion: the arm's skin against skinning after a 90° flex in 0.15 s")
        ax.legend(loc="lower right", fontsize=8)
        fig.tight_layout()
        fig.savefig(a.plot)
        print(f"wrote {a.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
