#!/usr/bin/env bash
# Iso-only renders (a TF transparent everywhere): range culling (libtetpack's tpk_march_ray_values) gives
# the same picture, byte for byte, as marching every tet, on a real mesh (SEACAS's exomerge unit test,
# its z displacement), with shading, clipping, several surfaces, partial opacity, AO and the vertex
# cache, on Tet16 and Tet32, and with the file's culling blocks (convert --cull); --json says which path
# ran; the automatic choice culls a sparse surface.
source "$(dirname "$0")/common.sh"

"$TPK" convert "$DATA/seacas/exomerge_unit_test.e" "$WORK/m.tpk" --layout tet16 --layout tet32 --quiet \
    || fail "cannot convert the Exodus file"
printf '0 0.2 0.4 0.9 0\n0.5 0.9 0.9 0.2 0\n1 0.9 0.2 0.1 0\n' > "$WORK/clear.tf"
base=(--backend cpu --size 96x72 --threads 2 --tf "$WORK/clear.tf" --field disp_z --step 4 --json)

# both NAME OPTIONS...: the picture culled and marched, compared
both() {
    local name=$1
    shift
    TETPACK_ISO_CULLING=1 "$TPK" render "$WORK/m.tpk" -o "$WORK/$name.cull.png" "${base[@]}" "$@" > "$WORK/$name.cull.json" \
        || fail "$name: culled render failed"
    TETPACK_ISO_CULLING=0 "$TPK" render "$WORK/m.tpk" -o "$WORK/$name.march.png" "${base[@]}" "$@" > "$WORK/$name.march.json" \
        || fail "$name: marched render failed"
    grep -q '"iso_culling":true' "$WORK/$name.cull.json" || fail "$name: TETPACK_ISO_CULLING=1 did not cull"
    grep -q '"iso_culling":false' "$WORK/$name.march.json" || fail "$name: TETPACK_ISO_CULLING=0 culled"
    cmp -s "$WORK/$name.cull.png" "$WORK/$name.march.png" || fail "$name: culled and marched pictures differ"
    local steps_cull steps_march
    steps_cull=$(grep -o '"tet_steps":[0-9]*' "$WORK/$name.cull.json" | cut -d: -f2)
    steps_march=$(grep -o '"tet_steps":[0-9]*' "$WORK/$name.march.json" | cut -d: -f2)
    echo "ok $name: identical; tets tested $steps_cull culled, $steps_march marched"
}

both one --iso -0.012
both sparse --iso -0.0195
both shaded --iso -0.012 --shading
both several --iso -0.018,-0.01,-0.002 --iso-opacity 0.4 --shading
both clipped --iso -0.012,-0.005 --clip-box -10,-10,-10,10,10,0.2 --shading
both tet32 --iso -0.012 --layout tet32 --shading
both occluded --iso -0.012 --shading --ao 2
both vertex_cache --iso -0.012 --shading --ao 2 --occlusion vertex

# Culling blocks (convert --cull, spec §17): the culled picture walks only the blocks that may hold a
# value, in each layout and over several steps (each step's field reads the blocks' ranges again), and is
# still the marched one, byte for byte.
"$TPK" convert "$DATA/seacas/exomerge_unit_test.e" "$WORK/c.tpk" --layout tet16 --layout tet20 --layout tet32 \
    --cull --quiet || fail "cannot convert the Exodus file with --cull"
"$TPK" info "$WORK/c.tpk" | grep -q "CULL" || fail "convert --cull wrote no CULL chunk"
for layout in tet16 tet20 tet32; do
    for iso in -0.0195 -0.012; do
        TETPACK_ISO_CULLING=1 "$TPK" render "$WORK/c.tpk" -o "$WORK/c_$layout.png" "${base[@]}" --iso $iso \
            --layout $layout --shading > "$WORK/c.json" || fail "--cull file, $layout, iso $iso: culled render failed"
        grep -q '"iso_culling":true' "$WORK/c.json" || fail "--cull file, $layout: TETPACK_ISO_CULLING=1 did not cull"
        TETPACK_ISO_CULLING=0 "$TPK" render "$WORK/m.tpk" -o "$WORK/m_$layout.png" "${base[@]}" --iso $iso \
            --shading > /dev/null || fail "iso $iso: marched render failed"
        cmp -s "$WORK/c_$layout.png" "$WORK/m_$layout.png" \
            || fail "--cull file, $layout, iso $iso: the culled picture differs from the marched one"
    done
done
steps=(--backend cpu --size 96x72 --threads 2 --tf "$WORK/clear.tf" --field disp_z --steps 2:4 --iso -0.012)
TETPACK_ISO_CULLING=1 "$TPK" render "$WORK/c.tpk" -o "$WORK/cs_%d.png" "${steps[@]}" || fail "--cull file: --steps failed"
TETPACK_ISO_CULLING=0 "$TPK" render "$WORK/m.tpk" -o "$WORK/ms_%d.png" "${steps[@]}" || fail "marched --steps failed"
for s in 2 3 4; do
    cmp -s "$WORK/cs_$s.png" "$WORK/ms_$s.png" || fail "--cull file: step $s differs from the marched picture"
done
echo "ok culling blocks: Tet16, Tet20, Tet32 and steps 2-4 identical to marched pictures"

# the automatic choice: a sparse surface is culled; with volume opacity (the default TF) nothing is
"$TPK" render "$WORK/m.tpk" -o "$WORK/auto.png" "${base[@]}" --iso -0.015 > "$WORK/auto.json" # a sparse one
grep -q '"iso_culling":true' "$WORK/auto.json" || fail "a sparse iso-only surface was not culled: $(cat "$WORK/auto.json")"
"$TPK" render "$WORK/m.tpk" -o "$WORK/vol.png" --backend cpu --size 96x72 --field disp_z --iso -0.0195 --json > "$WORK/vol.json"
grep -q '"iso_culling":false' "$WORK/vol.json" || fail "a render with volume opacity was culled"
echo "render_iso_culling: culled pictures identical to marched ones"
