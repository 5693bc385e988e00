#!/usr/bin/env bash
# Renders the bundled sample with each option of the option table (render/render_options.def) on both
# backends (cpu; vulkan where a device or lavapipe is present), saves and replays scenes, and prints one
# "sha256  name" line per output: PNGs, --save-scene files, --json (its timings and device names left
# out), --help, extract --save-scene and the messages of refused values. Used to show that a change
# which should not alter outputs (a refactoring) keeps them byte-identical:
#   tests/golden/render_outputs.sh build/tetpack OUTDIR > before.txt   (then after, diff)
set -uo pipefail
tetpack=$1 out=$2
src=$(cd "$(dirname "$0")/../.." && pwd)
mkdir -p "$out"
tpk="$out/cyl.tpk"
"$tetpack" convert "$src/samples/cylinder.vtk" "$tpk" --layout tet16 --layout tet20 --layout tet32 >/dev/null 2>&1 ||
    { echo "convert failed"; exit 1; }

# --json without what varies from run to run: times, rates, the device, paths.
json_stable() {
    python3 -c '
import json, sys
drop = ("seconds", "_ms", "rate", "per_", "device", "backend_reason", "hits", "cache", "setup", "image")
def keep(k): return not any(d in k for d in drop)
def clean(v):
    if isinstance(v, dict): return {k: clean(x) for k, x in v.items() if keep(k)}
    if isinstance(v, list): return [clean(x) for x in v]
    return v
print(json.dumps(clean(json.load(sys.stdin)), sort_keys=True))'
}

n=0
case_() { # name options...
    local name=$1
    shift
    for backend in cpu vulkan; do
        local tag="$name.$backend"
        if "$tetpack" render "$tpk" -o "$out/$tag.png" --size 64x48 --backend "$backend" --threads 2 \
            --save-scene "$out/$tag.scene.json" --json "$@" > "$out/$tag.json.raw" 2> "$out/$tag.err"; then
            json_stable < "$out/$tag.json.raw" > "$out/$tag.json"
            sed -i 's/"backend": "vulkan"/"backend": "cpu"/' "$out/$tag.scene.json" # the device present decides
            "$tetpack" render "$tpk" -o "$out/$tag.replay.png" --scene "$out/$tag.scene.json" --backend "$backend" \
                --threads 2 > /dev/null 2>&1 || echo "replay-failed $tag"
            (cd "$out" && sha256sum "$tag.png" "$tag.scene.json" "$tag.json" "$tag.replay.png")
        else
            echo "refused($?) $tag: $(head -c 300 "$out/$tag.err" | tr '\n' ' ')"
        fi
    done
    n=$((n + 1))
}

case_ plain
case_ tf_range --tf inferno --range 300,370 --layout tet20
case_ unit --unit-distance 0.002 --integration sampled
case_ midpoint --integration midpoint --layout tet32
case_ iso --iso 320,340 --iso-opacity 0.6
case_ iso_auto --iso auto --shading
case_ shading --shading --light 0.3,0.2,0.2
case_ shadows --shadows --iso 330 --iso-opacity 0.5
case_ ao --ao 3 --ao-radius 0.01 --shading
case_ ao_default --ao 2
case_ vertex --shadows --ao 2 --occlusion vertex --iso 330
case_ clip --clip-box 0,-1,-1,0.08,1,1 --iso 330 --shading
case_ probes --probe sphere:0.05,0,0,0.03:cut --probe plane:0.05,0,0,1,0,0 --shading
case_ everything --clip-box 0,-1,-1,0.08,1,1 --iso 330 --iso-opacity 0.6 --integration midpoint --shading \
    --shadows --light 0.3,0.2,0.2 --ao 2 --ao-radius 0.01 --unit-distance 0.004
case_ camera --camera 0.2,0.1,0.12,0.05,0,0,0,0,1,30 --tf grayscale

# A hand-written scene with every table key, and the command line over it.
cat > "$out/hand.json" <<'JSON'
{"tetpack_scene": 1, "size": [48, 40], "clip_box": [0, -1, -1, 0.08, 1, 1], "iso": [330], "iso_opacity": 0.6,
 "integration": "midpoint", "unit_distance": 0.003,
 "effects": {"shading": true, "shadows": true, "light": [0.3, 0.2, 0.2], "ao_rays": 2, "ao_radius": 0.01,
             "occlusion": "vertex"}}
JSON
for backend in cpu vulkan; do
    "$tetpack" render "$tpk" -o "$out/hand.$backend.png" --scene "$out/hand.json" --backend "$backend" \
        --save-scene "$out/hand.$backend.scene.json" > /dev/null 2>&1 || echo "hand-failed $backend"
    "$tetpack" render "$tpk" -o "$out/hand_over.$backend.png" --scene "$out/hand.json" --backend "$backend" \
        --iso-opacity 0.3 --ao 0 --occlusion ray --integration exact > /dev/null 2>&1 || echo "hand-over-failed $backend"
    sed -i 's/"backend": "vulkan"/"backend": "cpu"/' "$out/hand.$backend.scene.json"
    (cd "$out" && sha256sum "hand.$backend.png" "hand.$backend.scene.json" "hand_over.$backend.png")
done

# extract --save-scene: the scene of the part kept.
"$tetpack" extract "$tpk" "$out/part.tpk" --clip-box 0,-1,-1,0.08,1,1 --scene "$out/hand.json" \
    --save-scene "$out/part.scene.json" > /dev/null 2>&1 || echo "extract-failed"
(cd "$out" && sha256sum part.scene.json)

# Help texts and the messages of refused values (command line and scene).
"$tetpack" render --help > "$out/render.help" 2>&1
"$tetpack" view --help > "$out/view.help" 2>&1
: > "$out/refused.txt"
for bad in "--iso-opacity 0" "--iso-opacity 1.5" "--ao -1" "--ao 2000" "--ao-radius 0" "--unit-distance -1" \
    "--occlusion sky" "--integration fast" "--threads 0" "--max-pixel-step 17" "--level 9" "--max-ms 0"; do
    "$tetpack" render "$tpk" -o "$out/never.png" $bad >> "$out/refused.txt" 2>&1
    echo "exit $?" >> "$out/refused.txt"
done
for bad in '"iso_opacity": 0' '"iso_opacity": "x"' '"unit_distance": 0' '"integration": "fast"' \
    '"effects": {"ao_rays": 1.5}' '"effects": {"ao_radius": -1}' '"effects": {"shading": 1}' \
    '"effects": {"occlusion": "sky"}' '"effects": {"zzz": 1}' '"zzz": 1'; do
    printf '{"tetpack_scene": 1, %s}\n' "$bad" > "$out/bad.json"
    "$tetpack" render "$tpk" -o "$out/never.png" --scene "$out/bad.json" >> "$out/refused.txt" 2>&1
    echo "exit $?" >> "$out/refused.txt"
done
sed -i "s|$out|OUT|g" "$out/refused.txt"
(cd "$out" && sha256sum render.help view.help refused.txt)
[ -e "$out/never.png" ] && echo "a refused render wrote its PNG"
echo "$n cases"
