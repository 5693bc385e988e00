#!/usr/bin/env bash
# Iso-only renders (a TF transparent everywhere) on Vulkan (lavapipe here): the range culling of
# render.comp (the range BVH uploaded, candidate tets' pieces computed as the marcher computes them)
# draws the same picture, byte for byte, as the shader's marcher, on the bundled sample and on a real
# mesh (SEACAS's exomerge unit test, its z displacement): one and several surfaces, partial opacity,
# shading, shadows and AO rays (the march pauses for casts), the clip box, a probe, Tet32, rays in slices
# and in one dispatch; --json says which path ran; each culled picture is the CPU reference's at >= 40 dB.
# Then --steps on one kept renderer against each step alone.
source "$(dirname "$0")/common.sh"
tpk convert "$SRC/samples/cylinder.vtk" "$WORK/cyl.tpk" --quiet || fail "cannot convert the cylinder"
tpk convert "$DATA/seacas/exomerge_unit_test.e" "$WORK/m.tpk" --layout tet16 --layout tet32 --quiet \
    || fail "cannot convert the Exodus file"
if ! tpk render "$WORK/cyl.tpk" -o "$WORK/v.png" --size 8x8 --backend vulkan > /dev/null 2> "$WORK/err"; then
    grep -q "built without Vulkan\|vulkan\|Vulkan" "$WORK/err" || fail "render --backend vulkan failed without saying why"
    skip "no Vulkan device: $(cat "$WORK/err")"
fi
printf '0 0.2 0.4 0.9 0\n0.5 0.9 0.9 0.2 0\n1 0.9 0.2 0.1 0\n' > "$WORK/clear.tf"

# both NAME FILE OPTIONS...: culled and marched on Vulkan (identical), culled against the CPU (>= 40 dB)
both() {
    local name=$1 file=$2
    shift 2
    local base=(--backend vulkan --size 96x72 --tf "$WORK/clear.tf" --json)
    TETPACK_ISO_CULLING=1 tpk render "$file" -o "$WORK/$name.cull.png" "${base[@]}" "$@" > "$WORK/$name.cull.json" \
        || fail "$name: culled render failed"
    TETPACK_ISO_CULLING=0 tpk render "$file" -o "$WORK/$name.march.png" "${base[@]}" "$@" > "$WORK/$name.march.json" \
        || fail "$name: marched render failed"
    grep -q '"backend":"vulkan"' "$WORK/$name.cull.json" || fail "$name: not rendered by Vulkan: $(cat "$WORK/$name.cull.json")"
    grep -q '"iso_culling":true' "$WORK/$name.cull.json" || fail "$name: TETPACK_ISO_CULLING=1 did not cull"
    grep -q '"iso_culling":false' "$WORK/$name.march.json" || fail "$name: TETPACK_ISO_CULLING=0 culled"
    cmp -s "$WORK/$name.cull.png" "$WORK/$name.march.png" || fail "$name: culled and marched pictures differ"
    TETPACK_ISO_CULLING=1 tpk render "$file" -o "$WORK/$name.cpu.png" --backend cpu --size 96x72 --threads 2 \
        --tf "$WORK/clear.tf" "$@" > /dev/null || fail "$name: CPU render failed"
    local db
    db=$(psnr "$WORK/$name.cpu.png" "$WORK/$name.cull.png")
    at_least "$db" 40 || fail "$name: Vulkan culled against the CPU: $db dB"
    echo "ok $name: identical; $db dB against the CPU"
}

both cyl_one "$WORK/cyl.tpk" --iso 330
both sparse "$WORK/m.tpk" --field disp_z --step 4 --iso -0.0195
both several "$WORK/m.tpk" --field disp_z --step 4 --iso -0.018,-0.01,-0.002 --iso-opacity 0.4 --shading
both clipped "$WORK/m.tpk" --field disp_z --step 4 --iso -0.012,-0.005 --clip-box -10,-10,-10,10,10,0.2 --shading
both probe "$WORK/m.tpk" --field disp_z --step 4 --iso -0.012,-0.005 --probe sphere:0,0,0,0.6:cut
both tet32 "$WORK/m.tpk" --field disp_z --step 4 --iso -0.012 --layout tet32 --shading
both occluded "$WORK/m.tpk" --field disp_z --step 4 --iso -0.012 --iso-opacity 0.6 --shading --shadows --ao 2
TPK_VK_SLICED=0 both one_dispatch "$WORK/m.tpk" --field disp_z --step 4 --iso -0.012,-0.005 --iso-opacity 0.5

# the automatic choice (TETPACK_ISO_CULLING unset): the Vulkan renderer marches on every device, a GPU
# too (render.h ISO-ONLY RAYS: the walk cost more than it saved wherever measured), where the CPU
# reference culls this sparse surface; with volume opacity none culls anywhere
tpk render "$WORK/m.tpk" -o "$WORK/auto.png" --backend vulkan --size 96x72 --tf "$WORK/clear.tf" --field disp_z \
    --step 4 --iso -0.0195 --json > "$WORK/auto.json"
TETPACK_ISO_CULLING= tpk render "$WORK/m.tpk" -o "$WORK/auto_cpu.png" --backend cpu --size 96x72 --tf "$WORK/clear.tf" \
    --field disp_z --step 4 --iso -0.0195 --json > "$WORK/auto_cpu.json"
grep -q '"iso_culling":false' "$WORK/auto.json" || fail "Vulkan culled by default: $(cat "$WORK/auto.json")"
grep -q '"iso_culling":true' "$WORK/auto_cpu.json" || fail "the CPU no longer culls this case: $(cat "$WORK/auto_cpu.json")"
tpk render "$WORK/m.tpk" -o "$WORK/vol.png" --backend vulkan --size 96x72 --field disp_z --iso -0.0195 --json > "$WORK/vol.json"
grep -q '"iso_culling":false' "$WORK/vol.json" || fail "a render with volume opacity was culled"

# --steps keeps one Vulkan renderer and hands it each step's field (tpk_vk_renderer_set_field): every
# frame must be that step rendered alone, culled (the range tree made again for each field; also through
# the discrete GPU's staging path), with
# vertex AO (its cache follows the field), and for a tet field; steps must differ.
tpk render "$WORK/m.tpk" -o "$WORK/vs_%d.png" --backend vulkan --size 96x72 --tf "$WORK/clear.tf" --field disp_z \
    --iso -0.012,-0.005 --steps 2:4 --json > "$WORK/vs.json" || fail "--steps on Vulkan failed"
[ "$(grep -c '"backend":"vulkan"' "$WORK/vs.json")" = 3 ] || fail "--steps 2:4 did not draw 3 Vulkan frames: $(cat "$WORK/vs.json")"
TETPACK_ISO_CULLING=1 tpk render "$WORK/m.tpk" -o "$WORK/vc_%d.png" --backend vulkan --size 96x72 \
    --tf "$WORK/clear.tf" --field disp_z --iso -0.012,-0.005 --steps 2:4 > /dev/null || fail "--steps, culled, failed"
TPK_VK_MEMORY=staged TETPACK_ISO_CULLING=1 tpk render "$WORK/m.tpk" -o "$WORK/vm_%d.png" --backend vulkan --size 96x72 \
    --tf "$WORK/clear.tf" --field disp_z --iso -0.012,-0.005 --steps 2:4 > /dev/null || fail "--steps, staged, failed"
tpk render "$WORK/m.tpk" -o "$WORK/va_%d.png" --backend vulkan --size 96x72 --field disp_z --ao 2 --occlusion vertex \
    --steps 2:4 > /dev/null || fail "--steps with vertex AO failed"
tpk convert "$DATA/seacas/exomerge_unit_test.e" "$WORK/e.tpk" --field pressure --quiet || fail "cannot convert pressure"
tpk render "$WORK/e.tpk" -o "$WORK/vt_%d.png" --backend vulkan --size 96x72 --field pressure --range 0,1.4e9 \
    --steps 2:4 > /dev/null || fail "--steps of a tet field failed"
for s in 2 4; do
    TETPACK_ISO_CULLING=0 tpk render "$WORK/m.tpk" -o "$WORK/one.png" --backend vulkan --size 96x72 \
        --tf "$WORK/clear.tf" --field disp_z --iso -0.012,-0.005 --step $s > /dev/null
    cmp -s "$WORK/vs_$s.png" "$WORK/one.png" || fail "--steps: Vulkan frame $s differs from --step $s alone"
    cmp -s "$WORK/vc_$s.png" "$WORK/one.png" || fail "--steps: Vulkan frame $s, culled, differs from --step $s alone"
    cmp -s "$WORK/vm_$s.png" "$WORK/one.png" || fail "--steps: Vulkan frame $s, culled, staged, differs from --step $s"
    tpk render "$WORK/m.tpk" -o "$WORK/one_a.png" --backend vulkan --size 96x72 --field disp_z --ao 2 \
        --occlusion vertex --step $s > /dev/null
    cmp -s "$WORK/va_$s.png" "$WORK/one_a.png" || fail "--steps: Vulkan frame $s with vertex AO differs from --step $s"
    tpk render "$WORK/e.tpk" -o "$WORK/one_t.png" --backend vulkan --size 96x72 --field pressure --range 0,1.4e9 \
        --step $s > /dev/null
    cmp -s "$WORK/vt_$s.png" "$WORK/one_t.png" || fail "--steps: Vulkan frame $s of a tet field differs from --step $s"
done
for f in vs va vt; do
    cmp -s "$WORK/${f}_2.png" "$WORK/${f}_4.png" && fail "--steps: Vulkan frames 2 and 4 ($f) look the same"
done
echo "render_vk_iso_culling: culled Vulkan pictures identical to marched ones; --steps frames those of one step"
