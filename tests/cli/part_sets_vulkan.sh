#!/usr/bin/env bash
# A part set (spec §15) with the Vulkan renderer (lavapipe here): its parts resident as one mesh
# (libtetpack/set_mesh.c: a vertex on a cut once, a linked face the neighbour across it, the outer faces
# the shell BVH), so rays cross the cuts with the one-file shader. On a real mesh cut into 4 parts: the
# CPU reference's picture (>= 60 dB; emission-absorption on the CPU is the link-following marcher, an
# independent path), with shading, shadows and AO too, and with a tet field; and the picture and device
# memory of the single file the set was cut from.
source "$(dirname "$0")/common.sh"
convert_checked "$DATA/sfepy/elbow.mesh" "$WORK/whole.tpk" > /dev/null
"$TPK" convert "$DATA/sfepy/elbow.mesh" "$WORK/set.tpkset" --parts 4 > /dev/null
if ! tpk render "$WORK/set.tpkset" -o "$WORK/probe.png" --size 8x8 --backend vulkan > /dev/null 2> "$WORK/err"; then
    grep -q "built without Vulkan\|vulkan" "$WORK/err" || fail "render --backend vulkan failed without saying why: $(cat "$WORK/err")"
    skip "no Vulkan device: $(cat "$WORK/err")"
fi
same() { # A.png B.png WHAT: at least 60 dB
    local db
    db=$(psnr "$1" "$2")
    at_least "$db" 60 || fail "$3: $db dB"
    echo "$3: $db dB"
}
field() { "$PY" -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$1" "$2"; }
for fx in "" "--shading --shadows --ao 4"; do
    name=$( [ -z "$fx" ] && echo ea || echo lit )
    # shellcheck disable=SC2086 # $fx: the options, word by word
    for b in cpu vulkan; do
        tpk render "$WORK/set.tpkset" -o "$WORK/${name}_set_$b.png" --size 96x72 $fx --backend $b --json \
            > "$WORK/${name}_set_$b.json" || fail "render the set ($b, $name)"
    done
    # shellcheck disable=SC2086
    tpk render "$WORK/whole.tpk" -o "$WORK/${name}_whole_vulkan.png" --size 96x72 $fx --backend vulkan --json \
        > "$WORK/${name}_whole_vulkan.json" || fail "render the single file ($name)"
    grep -q '"backend":"vulkan"' "$WORK/${name}_set_vulkan.json" || fail "not drawn by Vulkan: $(cat "$WORK/${name}_set_vulkan.json")"
    same "$WORK/${name}_set_cpu.png" "$WORK/${name}_set_vulkan.png" "$name: the set, Vulkan against the CPU reference"
    same "$WORK/${name}_whole_vulkan.png" "$WORK/${name}_set_vulkan.png" "$name: the set against its single file, Vulkan"
    [ "$(field "$WORK/${name}_set_vulkan.json" device_bytes)" = "$(field "$WORK/${name}_whole_vulkan.json" device_bytes)" ] ||
        fail "$name: device memory of the set $(field "$WORK/${name}_set_vulkan.json" device_bytes), of the single file $(field "$WORK/${name}_whole_vulkan.json" device_bytes)"
done
grep -q '"secondary_rays":[1-9]' "$WORK/lit_set_vulkan.json" || fail "no shadow or AO rays: $(cat "$WORK/lit_set_vulkan.json")"
# A tet field (a cell field of the source) across the parts, with shading.
convert_checked "$DATA/sfepy/acoustic_wg.vtk" "$WORK/wg.tpk" --field mat_id > /dev/null
"$TPK" convert "$DATA/sfepy/acoustic_wg.vtk" "$WORK/wg.tpkset" --parts 3 --field mat_id > /dev/null
tpk render "$WORK/wg.tpkset" -o "$WORK/wg_cpu.png" --size 96x72 --field mat_id --shading --backend cpu > /dev/null
tpk render "$WORK/wg.tpkset" -o "$WORK/wg_vulkan.png" --size 96x72 --field mat_id --shading --backend vulkan > /dev/null
same "$WORK/wg_cpu.png" "$WORK/wg_vulkan.png" "tet field: the set, Vulkan against the CPU reference"
echo "part sets on Vulkan: ok"
