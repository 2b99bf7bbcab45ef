#!/usr/bin/env bash
# Remakes the documentation's gallery (`make gallery`): runs the fist with self-contact, a character from
# Debian's assimp-testmodels and the muscle arm, renders each as docs/gallery.md shows it, and writes that
# page anew with every picture and the command that made it. About a minute on two cores.
# Usage: scripts/gallery.sh   Environment: SNH (default build/release/apps/snh), OUT (runs, default
# output/gallery).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
SNH="${SNH:-build/release/apps/snh}"
OUT="${OUT:-output/gallery}"
[ -x "$SNH" ] || { echo "gallery.sh: no snh binary at $SNH (make build first, or set SNH)" >&2; exit 2; }
HUESITOS=/usr/share/assimp/models/FBX/huesitos.fbx
[ -f "$HUESITOS" ] || { echo "gallery.sh: $HUESITOS is missing: apt-get install assimp-testmodels (scripts/install-deps)" >&2; exit 2; }
pics=docs/gallery
mkdir -p "$pics" "$OUT"
page="$(mktemp)"
trap 'rm -f "$page"' EXIT

# step COMMAND...: runs it (shown as `snh …`), and adds it to the page's current code block.
step() {
  echo "+ $*" >&2
  "$SNH" "$@" > /dev/null
  printf 'snh %s\n' "$*" >> "$page"
}
# picture TITLE FILE TEXT: the page's next entry, its picture (docs/gallery/FILE) and text; the commands follow.
picture() {
  printf '\n## %s\n\n![%s](gallery/%s)\n\n%s\n\n```sh\n' "$1" "$1" "$2" "$3" >> "$page"
}
end() { printf '```\n' >> "$page"; }

cat > "$page" <<'EOF'
# Gallery

What flesh simulation buys over skinning alone, in pictures. `make gallery` remakes this page and every
picture on it (`scripts/gallery.sh`), running each command shown; they run from the repository's root with
`snh` standing for `build/release/apps/snh`. `snh render` is described in [the report's page](report.md#snh-render-pictures-and-videos).
EOF

picture "The fist, framed" fist.png "The WebXR hand of \`data/\` closing into a fist with the skin's self-contact \
(\`scenes/hand_fist_contact.json\`), frame 24. The camera fits the frame shown, from the three-quarter view."
step run scenes/hand_fist_contact.json --out "$OUT/fist"
step render "$OUT/fist" --frame 24 --width 800 --height 600 --out "$pics/fist.png"
end

picture "Flesh and skinning side by side" fist_flesh_lbs.png "The same frame from the front: on the left the \
flesh, on the right the skin as linear blend skinning (LBS) poses it from the same bones. Skinning lets the \
fingers sink into the palm; the flesh keeps them out."
step render "$OUT/fist" --frame 24 --view front --show flesh,lbs --width 1200 --height 600 --out "$pics/fist_flesh_lbs.png"
end

picture "Where they differ" fist_difference.png "The flesh coloured by its signed distance from the LBS surface, \
in millimetres: red where the flesh lies outside the skinned surface (volume that skinning loses, or a \
finger that skinning pushes into the palm), blue inside. The legend's range is the whole run's."
step render "$OUT/fist" --frame 24 --show difference --width 800 --height 600 --out "$pics/fist_difference.png"
end

picture "A close-up on a knuckle" fist_knuckle.png "\`--focus\` names a joint: the camera closes in on the \
surface around it, here the index finger's first knuckle, with the bones drawn over it."
step render "$OUT/fist" --frame 24 --show difference --focus index-finger-phalanx-proximal --bones --width 800 --height 600 --out "$pics/fist_knuckle.png"
end

picture "Two runs: with and without contact" fist_contact_vs_none.png "\`--compare\` puts a second run of the \
same model and frames in the place of the skinned surface: here \`scenes/hand_fist.json\`, the same fist \
without the skin's self-contact. The colours are the distance of the contact run's skin from the other's: \
contact holds the fingers up to 5 mm off where they would sink into each other and the palm."
step run scenes/hand_fist.json --out "$OUT/fist_no_contact"
step render "$OUT/fist" --compare "$OUT/fist_no_contact" --frame 24 --show difference --width 800 --height 600 --out "$pics/fist_contact_vs_none.png"
end

picture "The whole run, moving" fist.gif "\`--video\` makes an .mp4 (H.264) or, as here, a GIF for web pages, \
at the run's frame rate (12 a second), the camera still: it fits every frame."
step render "$OUT/fist" --show difference --width 640 --height 480 --video "$pics/fist.gif"
end

picture "A character nobody here made" huesitos.png "\`huesitos.fbx\`, an FBX arm of Debian's \
assimp-testmodels with its own skeleton and clip, run by \`snh flesh\` with its defaults; flesh and \
distance side by side at the last frame, the colours spanning this frame's distances (\`--range frame\`: \
the run's own range holds a frame where the coarse flesh turned inside out, and the run says so)."
step flesh "$HUESITOS" --out "$OUT/huesitos"
step render "$OUT/huesitos" --show flesh,difference --range frame --width 1200 --height 600 --out "$pics/huesitos.png"
end

picture "A muscle that contracts" arm.png "The arm of \`scenes/arm_flex.json\`: the elbow bends and the biceps \
contracts along its fibres (drawn yellow: fully active). The distance from the skinned surface shows the \
bulge that skinning cannot make, and the flesh folding at the elbow."
step run scenes/arm_flex.json --out "$OUT/arm"
step render "$OUT/arm" --show difference --width 800 --height 600 --out "$pics/arm.png"
end

mv "$page" docs/gallery.md
trap - EXIT
echo "gallery: docs/gallery.md and $(ls "$pics" | wc -l) files in $pics"
