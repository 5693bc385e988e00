#!/usr/bin/env bash
# tetpack iso --backend vulkan (marching tetrahedra in compute shaders, lavapipe here) writes the same
# files, byte for byte, as the CPU, on a real mesh (SEACAS's exomerge unit test, its z displacement at
# the last step) for PLY, OBJ and glTF; --json names the backend and the device.
source "$(dirname "$0")/common.sh"
# Under the sanitizers CMake sets TPK_VK_PRELOAD (libasan and lavapipe) for the tetpack runs only.
tpk() {
    if [ -n "${TPK_VK_PRELOAD:-}" ]; then LD_PRELOAD="$TPK_VK_PRELOAD" "$TPK" "$@"; else "$TPK" "$@"; fi
}
tpk convert "$DATA/seacas/exomerge_unit_test.e" "$WORK/m.tpk" --quiet || fail "cannot convert the Exodus file"
if ! tpk iso "$WORK/m.tpk" "$WORK/probe.ply" --field disp_z --value -0.01 --backend vulkan > /dev/null 2> "$WORK/err"; then
    grep -q "built without Vulkan\|vulkan" "$WORK/err" || fail "iso --backend vulkan failed without saying why: $(cat "$WORK/err")"
    skip "no Vulkan device: $(cat "$WORK/err")"
fi
for ext in ply obj glb; do
    for backend in cpu vulkan; do
        tpk iso "$WORK/m.tpk" "$WORK/$backend.$ext" --field disp_z --step 4 --value -0.018,-0.012,-0.005,-0.0001 \
            --color-field disp_x --backend "$backend" --json > "$WORK/$backend.$ext.json" || fail "iso --backend $backend .$ext"
    done
    cmp -s "$WORK/cpu.$ext" "$WORK/vulkan.$ext" || fail "the .$ext files of the CPU and Vulkan differ"
    grep -q '"backend":"vulkan","device":"' "$WORK/vulkan.$ext.json" || fail "vulkan json: $(cat "$WORK/vulkan.$ext.json")"
    grep -q '"backend":"cpu"' "$WORK/cpu.$ext.json" || fail "cpu json: $(cat "$WORK/cpu.$ext.json")"
done
triangles=$(grep -o '"triangles":[0-9]*' "$WORK/vulkan.ply.json" | head -1 | cut -d: -f2)
[ "$triangles" -gt 1000 ] || fail "only $triangles triangles"
expect_exit 2 tpk iso "$WORK/m.tpk" "$WORK/x.ply" --value 0 --backend metal
expect_stderr "--backend expects cpu or vulkan, found 'metal'"
echo "iso_vulkan: $triangles triangles, the same files from both backends"
