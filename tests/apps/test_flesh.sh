#!/usr/bin/env bash
# snh flesh end to end on the procedural limb (tests/data/flesh/limb.gltf: a cylinder whose elbow bends 90°
# in its clip): the render surface per frame for flesh and skinning, the USD stage parsed by the .usda
# grammar, stats and report; the hand fist's volumes; and bad models refused in one line with exit code 2,
# nothing written.
# Usage: test_flesh.sh SNH DATA_DIR (tests/data) MODELS_DIR (data)
set -u
SNH="$1" DATA="$2" MODELS="$3"
HERE="$(cd "$(dirname "$0")" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
pass=0 fail=0
# shellcheck source=lib.sh
. "$(dirname "$0")/lib.sh"  # ok, bad, wait_for, expect_exit, expect_error
limb="$DATA/flesh/limb.gltf"

# The clip is 1 s: 24 frames at the default 24 fps, frame 0 the rest pose.
if "$SNH" flesh "$limb" --resolution 12 --out "$work/limb" > "$work/limb.log" 2>&1; then ok; else bad "limb: $(tail -3 "$work/limb.log")"; fi
grep -q '^model .*limb.gltf (glTF 2.0): .* 3 joints' "$work/limb.log" && ok || bad "limb: header names the model"
grep -q '^bones: 3 binding' "$work/limb.log" && ok || bad "limb: bound vertices per bone printed"
[ -f "$work/limb/surface/024.obj" ] && [ -f "$work/limb/lbs/024.obj" ] && [ ! -f "$work/limb/surface/025.obj" ] && [ -f "$work/limb/024.vtu" ] \
  && ok || bad "limb: surface/, lbs/ and .vtu frames 0-24"
[ "$(grep -c '^v ' "$work/limb/surface/012.obj")" -eq "$(grep -c '^v ' "$work/limb/lbs/012.obj")" ] && ok || bad "limb: flesh and LBS surfaces alike"
python3 "$HERE/check_usda.py" "$work/limb/flesh.usda" 2 25 > "$work/usda.log" 2>&1 && ok || bad "limb: flesh.usda: $(cat "$work/usda.log")"
grep -q '"surface_volume_ratio"' "$work/limb/stats.json" && grep -q '"lbs_volume_ratio"' "$work/limb/stats.json" \
  && grep -q '"all_converged": true' "$work/limb/stats.json" && ok || bad "limb: stats.json"
[ -f "$work/limb/index.html" ] && [ -f "$work/limb/bones.json" ] && ok || bad "limb: report and bones.json"
# --list: the meshes, the joints as a tree, the clips; nothing run, nothing written.
if "$SNH" flesh "$limb" --list --out "$work/listed" > "$work/list.log" 2>&1; then ok; else bad "list: $(tail -3 "$work/list.log")"; fi
grep -q '^skinned meshes (1):' "$work/list.log" && grep -q '^joints (3, hierarchy from the file):' "$work/list.log" \
  && grep -q '^      tip$' "$work/list.log" && grep -q '^  0: "bend", 1 s, 1 channels (played by default)$' "$work/list.log" \
  && ok || bad "list: $(cat "$work/list.log")"
[ ! -e "$work/listed" ] && ok || bad "list: wrote an output folder"
# The point caches: one sample per frame, the model's 386 vertices, 32 bytes of header.
[ "$(stat -c %s "$work/limb/flesh.pc2")" -eq $((32 + 25 * 386 * 12)) ] && [ -f "$work/limb/lbs.pc2" ] && ok || bad "limb: flesh.pc2 size"
# The grammar check is a real one: a broken stage fails it.
sed 's/point3f\[\] points.timeSamples = {/point3f[] points.timeSamples = /' "$work/limb/flesh.usda" > "$work/broken.usda"
python3 "$HERE/check_usda.py" "$work/broken.usda" > /dev/null 2>&1 && bad "check_usda accepts a broken stage" || ok
# Tets, and a second run into the same directory replacing the first.
"$SNH" flesh "$limb" --volume tets --resolution 10 --out "$work/limb" --no-report > "$work/tets.log" 2>&1 && grep -q 'tets (TetGen)' "$work/tets.log" \
  && [ ! -f "$work/limb/index.html" ] && [ -f "$work/limb/surface/024.obj" ] && ok || bad "limb tets: $(tail -2 "$work/tets.log")"
# A soft binding shell from the command line: its header line, its settings, every frame converged.
"$SNH" flesh "$limb" --resolution 12 --soft-shell 0.15 --soft-stiffness 5 --out "$work/soft" --no-report > "$work/soft.log" 2>&1 \
  && grep -q '^soft binding: [1-9][0-9]* more volume vertices within 0.15 of the capsules, pulled by springs of 5 x E x h' "$work/soft.log" \
  && grep -q '"stiffness": 5' "$work/soft/stats.json" && grep -q '"all_converged": true' "$work/soft/stats.json" \
  && ok || bad "soft binding: $(tail -2 "$work/soft.log")"
# At resolution 24 the limb's default capsules press the flesh at the bent elbow inside out: the header names the
# two bones; at --radius-scale 0.4 they leave it room, and the header says the radii were scaled.
"$SNH" flesh "$limb" --resolution 24 --out "$work/pressed" --no-report > "$work/pressed.log" 2>&1 \
  && grep -q '^warning: the bones press flesh inside out in [0-9]* frames: in frame 24 (t = 1) \(shoulder>elbow and elbow>tip\|elbow>tip and shoulder>elbow\) carry' "$work/pressed.log" \
  && grep -q '^    "the bones press flesh inside out in [0-9]* frames: in frame 24' "$work/pressed/stats.json" \
  && grep -q '^    "[0-9]* frames converged with elements turned inside out (at most [0-9]*, in frame [0-9]*)"$' "$work/pressed/stats.json" \
  && ok || bad "pressed flesh: $(grep -c 'press flesh' "$work/pressed.log") warnings; $(tail -1 "$work/pressed.log")"
"$SNH" flesh "$limb" --resolution 24 --radius-scale 0.4 --out "$work/roomy" --no-report > "$work/roomy.log" 2>&1 \
  && grep -q '^bones: 3 binding [0-9]* volume vertices, capsule radii 0.4 x the default (shoulder>elbow' "$work/roomy.log" \
  && ! grep -q 'press flesh' "$work/roomy.log" && grep -q '"radius_scale": 0.4' "$work/roomy/stats.json" \
  && ok || bad "--radius-scale 0.4: $(grep -E '^bones|press' "$work/roomy.log" | cut -c1-200)"

# A ground plane the bending limb would pass below (its skin reaches y = -0.35 at the end without it): with
# --ground -0.33 every frame's render surface stays above it, with contact pairs reported; self-contact on.
"$SNH" flesh "$limb" --resolution 10 --out "$work/free" --no-report > "$work/free.log" 2>&1 || bad "limb without ground: $(tail -2 "$work/free.log")"
"$SNH" flesh "$limb" --resolution 10 --ground -0.33 --self-contact --out "$work/ground" --no-report > "$work/ground.log" 2>&1 \
  || bad "limb on the ground: $(tail -2 "$work/ground.log")"
python3 - "$work/free" "$work/ground" <<'PY' && ok || bad "limb on the ground: the surface stays above it"
import json, sys
def lowest(run, f):
    return min(float(l.split()[2]) for l in open(f"{run}/surface/{f:03d}.obj") if l.startswith("v "))
free = min(lowest(sys.argv[1], f) for f in range(25))
ground = [lowest(sys.argv[2], f) for f in range(25)]
s = json.load(open(sys.argv[2] + "/stats.json"))
pairs = [f["contact_pairs"] for f in s["frames"]]
print(f"limb: lowest skin without ground {free:.4f}, with ground at -0.33 {min(ground):.4f}; contact pairs {pairs}")
sys.exit(0 if free < -0.33 and min(ground) > -0.33 and s["all_converged"] and max(pairs) > 0 and s["contact"]["self"] else 1)
PY
grep -q ', [1-9][0-9]* contact pairs, min distance ' "$work/ground.log" && ok || bad "limb on the ground: progress line"
# With --friction 1 the skin pressed onto the ground holds on: still above it, the run converged, its settings
# naming the friction, and the last frame's skin where it touches elsewhere than frictionless (0.023 apart).
"$SNH" flesh "$limb" --resolution 10 --ground -0.33 --self-contact --friction 1 --out "$work/friction" --no-report > "$work/friction.log" 2>&1 \
  || bad "limb on the ground with friction: $(tail -2 "$work/friction.log")"
python3 - "$work/ground" "$work/friction" <<'PY' && ok || bad "limb on the ground with friction"
import json, math, sys
def verts(run, f):
    return [[float(x) for x in l.split()[1:4]] for l in open(f"{run}/surface/{f:03d}.obj") if l.startswith("v ")]
s = json.load(open(sys.argv[2] + "/stats.json"))
lowest = min(min(v[1] for v in verts(sys.argv[2], f)) for f in range(25))
moved = max(math.dist(p, q) for p, q in zip(verts(sys.argv[1], 24), verts(sys.argv[2], 24)))
print(f"limb with friction 1: lowest skin {lowest:.4f}, last frame {moved:.4f} from the frictionless one")
sys.exit(0 if s["all_converged"] and s["contact"]["friction"] == 1.0 and lowest > -0.33 and moved > 1e-3 else 1)
PY
expect_error ground_above 'colliders\[0\]: vertex [0-9]* of the render surface \(welded\) is .* on or behind it at the start' -- \
  "$SNH" flesh "$limb" --resolution 10 --ground 0 --out "$work/bad_ground"
expect_error dhat_alone 'dhat and --contact-stiffness need --self-contact or --ground' -- "$SNH" flesh "$limb" --dhat 0.1 --out "$work/bad_dhat"
expect_error friction_alone 'friction needs --self-contact or --ground' -- "$SNH" flesh "$limb" --friction 0.5 --out "$work/bad_friction"
expect_error dhat_negative 'dhat' -- "$SNH" flesh "$limb" --self-contact --dhat -1 --out "$work/bad_dhat2"

# The hand closing into a fist (scenes/hand_fist.json): every frame converges and the flesh keeps the volume
# inside its render surface within 3 % at every frame, while skinning loses more.
if "$SNH" run "$HERE/../../scenes/hand_fist.json" --out "$work/fist" --no-report > "$work/fist.log" 2>&1; then ok; else bad "hand_fist: $(tail -2 "$work/fist.log")"; fi
python3 - "$work/fist/stats.json" <<'PY' && ok || bad "hand_fist: volumes"
import json, sys
s = json.load(open(sys.argv[1]))
flesh = min(f["surface_volume_ratio"] for f in s["frames"])
lbs = min(f["lbs_volume_ratio"] for f in s["frames"])
ok = s["all_converged"] and len(s["frames"]) == 37 and flesh > 0.97 and lbs < flesh
print(f"hand_fist: smallest volume flesh {flesh:.4f}, skinning {lbs:.4f}")
sys.exit(0 if ok else 1)
PY

# A centimetre FBX (huesitos states UnitScaleFactor 1) run dynamically with a ground: gravity 981 cm/s² down y,
# density 1000 kg/m³ as 0.001 kg/cm³, E = 100 kPa as 1000 kg/(cm s²); the ground's plane along y.
huesitos=/usr/share/assimp/models/FBX/huesitos.fbx
if [ -f "$huesitos" ]; then
  if "$SNH" flesh "$huesitos" --dynamic --fps 6 --ground -100 --no-report --out "$work/cm" > "$work/cm.log" 2>&1; then ok; else bad "cm: $(tail -3 "$work/cm.log")"; fi
  python3 - "$work/cm/stats.json" <<'PY' && ok || bad "cm: gravity, density and E in the model's units"
import json, sys
s = json.load(open(sys.argv[1]))
g, rho, mu, lam = s["gravity"], s["density"], s["mu"], s["lambda"]
E = mu * (3 * lam + 2 * mu) / (lam + mu)
ok = abs(g[1] + 981) < 1e-9 and g[0] == 0 and g[2] == 0 and abs(rho - 1e-3) < 1e-12 and abs(E - 1000) < 1e-6
print(f"cm: gravity {g}, density {rho}, E {E}")
sys.exit(0 if ok else 1)
PY
  grep -q '^model: units: the file says 1 unit = 1 cm' "$work/cm.log" && ok || bad "cm: the header says the unit"
fi

# The options a character may need reach the run: --newton-iterations 1 stops the first frame that needs more
# (exit 1, the limit in the header and stats.json), --join-meshes is written to the run's settings.
"$SNH" flesh "$limb" --resolution 12 --newton-iterations 1 --join-meshes --out "$work/one" > "$work/one.log" 2>&1
[ $? -eq 1 ] && grep -q 'or fails after 1 iterations' "$work/one.log" && grep -q 'no convergence in 1 Newton iterations' "$work/one.log" \
  && grep -q '"max_newton_iterations": 1,' "$work/one/stats.json" && grep -q '"join_meshes": true' "$work/one/stats.json" \
  && ok || bad "one: $(tail -3 "$work/one.log")"
# The frame where that run stopped is no result: its last iterate is failed_001 (the volume, surface/ and lbs/),
# named in the last line; frames.pvd, flesh.usda, the point caches and the report's frames end at frame 0.
[ -f "$work/one/failed_001.obj" ] && [ -f "$work/one/failed_001.vtu" ] && [ -f "$work/one/surface/failed_001.obj" ] \
  && [ -f "$work/one/lbs/failed_001.obj" ] && [ ! -e "$work/one/001.obj" ] && [ ! -e "$work/one/surface/001.obj" ] \
  && grep -q "^STOPPED: frame 1, .*; its last iterate: failed_001.obj" "$work/one.log" && grep -q "\"failed_frame\": \"failed_001.obj\"" "$work/one/stats.json" && ok || bad "one: failed_001 files"
[ "$(grep -c '<DataSet' "$work/one/frames.pvd")" -eq 1 ] && ! grep -q failed "$work/one/frames.pvd" \
  && python3 "$HERE/check_usda.py" "$work/one/flesh.usda" 2 1 > /dev/null && [ "$(stat -c %s "$work/one/flesh.pc2")" -eq $((32 + 386 * 12)) ] \
  && grep -q 'its last iterate, no result, is failed_001.obj' "$work/one/report/data.js" && ok || bad "one: the failed frame is in no series"
# With --keep-going the frames stay in order, and each one that did not converge is marked: a comment before its
# DataSet in frames.pvd, snh:converged false at its time code in flesh.usda, its label in the report.
"$SNH" flesh "$limb" --resolution 12 --newton-iterations 1 --keep-going --out "$work/kept" > "$work/kept.log" 2>&1
[ $? -eq 1 ] && [ -f "$work/kept/024.obj" ] && ! ls "$work/kept" | grep -q failed_ \
  && [ "$(grep -c '^<!-- frame [0-9]* did not converge: .* -->$' "$work/kept/frames.pvd")" -eq 24 ] \
  && grep -q '^            0: true,$' "$work/kept/flesh.usda" && grep -q '^            24: false,$' "$work/kept/flesh.usda" \
  && python3 "$HERE/check_usda.py" "$work/kept/flesh.usda" 2 25 > /dev/null \
  && grep -q '"label":"frame 24 (did not converge)"' "$work/kept/report/data.js" && ok || bad "kept: $(tail -3 "$work/kept.log")"
# A new run into the stopped run's directory removes its failed_ files with the rest.
"$SNH" flesh "$limb" --resolution 12 --no-report --out "$work/one" > "$work/one_again.log" 2>&1
[ $? -eq 0 ] && ! find "$work/one" -name 'failed_*' | grep -q . && [ -f "$work/one/surface/024.obj" ] && ok || bad "one again: $(tail -2 "$work/one_again.log")"

# Bad input: one line, exit code 2, no output directory.
flesh_error() {  # NAME PATTERN ARGS...
  local name="$1" pattern="$2"
  shift 2
  expect_error "$name" "$pattern" -- "$SNH" flesh "$@" --out "$work/bad_$name"
  [ ! -e "$work/bad_$name" ] || bad "$name: wrote $work/bad_$name"
}
mkdir -p "$work/dir.glb"
head -c 30000 "$MODELS/hand/left.glb" > "$work/cut.glb"
printf 'solid nothing\n' > "$work/text.gltf"
flesh_error directory "dir.glb" "$work/dir.glb"
# A clip whose only channel animates morph target weights moves no joint: said so, not "a single key".
python3 -c "import json, sys; g = json.load(open(sys.argv[1])); g['animations'][0]['channels'][0]['target']['path'] = 'weights'; json.dump(g, open(sys.argv[2], 'w'))" \
  "$limb" "$work/morph.gltf"
flesh_error morph "animation \"bend\" moves none of the skin's joints" "$work/morph.gltf"
flesh_error truncated "cut.glb" "$work/cut.glb"
flesh_error not_gltf "text.gltf" "$work/text.gltf"
flesh_error missing "missing.glb" "$work/missing.glb"
flesh_error no_clip "no animation clip" "$MODELS/hand/left.glb"
flesh_error clip_name 'no animation clip "wave"' "$limb" --animation wave
flesh_error lame "go together" "$limb" --mu 1
flesh_error soft_stiffness "flesh.soft_binding.stiffness: must be > 0, got 0" "$limb" --soft-stiffness 0
flesh_error joint_cells "joint-cells: loose not in" "$limb" --joint-cells loose
flesh_error radius_scale "radius-scale" "$limb" --radius-scale 0
flesh_error soft_shell "flesh.soft_binding.shell: must be > 0, got -1" "$limb" --soft-shell -1
flesh_error integrator_alone "--integrator requires --dynamic" "$limb" --integrator bdf2
flesh_error integrator_unknown "--integrator: rk4 not in" "$limb" --dynamic --integrator rk4
# --dynamic --integrator bdf2 (and tr_bdf2) runs the limb by BDF2 (TR-BDF2), as its settings say. Its frames
# record the skin's largest offset from skinning: none at rest, some once gravity and the bend act, and at
# the skeleton's end (the wrist) no more than anywhere.
for integrator in bdf2:BDF2 tr_bdf2:TR-BDF2; do
  name=${integrator%%:*} label=${integrator#*:}
  "$SNH" flesh "$limb" --resolution 10 --dynamic --integrator "$name" --no-report --out "$work/$name" > "$work/$name.log" 2>&1 \
    && grep -q "^$label, 24 frames" "$work/$name.log" && python3 - "$work/$name/stats.json" "$name" <<'PY' && ok || bad "limb by $label: $(tail -2 "$work/$name.log")"
import json, sys
s = json.load(open(sys.argv[1]))
f = s["frames"]
print(f"limb by {sys.argv[2]}: skin offset from skinning at most {max(r['lbs_distance'] for r in f):.4f}, at the wrist {max(r['tip_distance'] for r in f):.4f}")
sys.exit(0 if s["integrator"] == sys.argv[2] and s["all_converged"] and f[0]["lbs_distance"] < 1e-9
         and max(r["lbs_distance"] for r in f) > 1e-3 and all(r["tip_distance"] <= r["lbs_distance"] for r in f) else 1)
PY
done
# A lattice whose run cannot fit is refused before it is built (it took 6 GB and more at resolution 1000), so
# with little memory (under 800 MB of address space, where building it failed), also under a ulimit -v that
# the run's own check would find too small.
flesh_error huge_lattice "^snh: error: not enough memory: snh flesh: a lattice at resolution 1000 \(at least [0-9.e+]* cells\) with mg" "$limb" --resolution 1000
( ulimit -v 800000; "$SNH" flesh "$limb" --resolution 1000 --out "$work/bad_huge" > "$work/huge.log" 2>&1 )
[ $? -eq 2 ] && grep -q '^snh: error: not enough memory: snh flesh: a lattice at resolution 1000 (at least' "$work/huge.log" && [ ! -e "$work/bad_huge" ] \
  && ok || bad "huge lattice under ulimit: $(tail -2 "$work/huge.log")"
( ulimit -v 1500000; "$SNH" flesh "$limb" --resolution 150 --out "$work/bad_limited" > "$work/limited.log" 2>&1 )
[ $? -eq 2 ] && grep -q 'a lattice at resolution 150 .* more than the limit of .* (ulimit -v)' "$work/limited.log" && [ ! -e "$work/bad_limited" ] \
  && ok || bad "limited: $(tail -2 "$work/limited.log")"
# A glTF's images are never decoded, and their files are not read: a 900 MB texture (sparse here) next to the
# limb took 914 MiB and 7 s; under 800 MB of address space the run now fits.
mkdir -p "$work/textured"
sed 's/^{/{"images":[{"uri":"big%20tex.png"}],/' "$limb" > "$work/textured/limb.gltf"
truncate -s 900M "$work/textured/big tex.png"
( ulimit -v 800000; "$SNH" flesh "$work/textured/limb.gltf" --resolution 6 --no-report --out "$work/textured/run" > "$work/textured.log" 2>&1 )
[ $? -eq 0 ] && [ -f "$work/textured/run/flesh.usda" ] && ok || bad "textured: $(tail -2 "$work/textured.log")"
rm -f "$work/textured/big tex.png"
# Numbers: nan and inf name the option; a frame rate too low for one frame of the clip is refused.
flesh_error fps_nan "^snh: error: --fps: must be a finite number, got nan" "$limb" --fps nan
flesh_error ground_inf "^snh: error: --ground: must be a finite number, got inf" "$limb" --ground inf
flesh_error fps_tiny "fps: 1e-300 frames per second makes less than one frame of the 1 s to run" "$limb" --fps 1e-300
# A frame rate that is not a whole number stays what it is: 7.5 fps over the 1 s clip is 8 frames to 16/15 s.
if "$SNH" flesh "$limb" --fps 7.5 --resolution 12 --no-report --out "$work/fps" > "$work/fps.log" 2>&1 \
   && grep -q '^quasi-static, 8 frames to t = 1.06667' "$work/fps.log" && grep -q 'timeCodesPerSecond = 7.5$' "$work/fps/flesh.usda" \
   && [ -f "$work/fps/surface/008.obj" ] && [ ! -f "$work/fps/surface/009.obj" ]; then ok; else bad "fps 7.5: $(tail -3 "$work/fps.log")"; fi

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
