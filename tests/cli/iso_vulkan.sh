#!/usr/bin/env bash
# tetpack iso --backend vulkan (marching tetrahedra in compute shaders, lavapipe here) writes the same
# files, byte for byte, as the CPU, on a real mesh (SEACAS's exomerge unit test, its z displacement at
# the last step) for PLY, OBJ and glTF; --json names the backend and the device.
source "$(dirname "$0")/common.sh"
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

# render --iso-raster: the surfaces drawn as triangles (--iso-raster-path auto: whichever of the compute
# rasterizer and the graphics path drew faster on the first frame) against the ray-marched ones of the
# CPU reference, opaque, iso-only (a TF transparent everywhere), with shading, two values and a clip box:
# the same picture up to rasterization
printf '0 0.2 0.4 0.9 0\n1 0.9 0.2 0.1 0\n' > "$WORK/clear.tf"
for opts in "--iso -0.005" "--iso -0.018,-0.005 --shading" "--iso -0.005 --shading --clip-box -10,-10,-10,10,0.2,10"; do
    # shellcheck disable=SC2086
    tpk render "$WORK/m.tpk" -o "$WORK/raster.png" --backend vulkan --size 128x96 --field disp_z --step 4 --tf "$WORK/clear.tf" \
        $opts --iso-raster --json > "$WORK/raster.json" || fail "--iso-raster $opts"
    # shellcheck disable=SC2086
    tpk render "$WORK/m.tpk" -o "$WORK/ray.png" --backend cpu --size 128x96 --field disp_z --step 4 --tf "$WORK/clear.tf" \
        $opts > /dev/null || fail "ray-marched $opts"
    grep -q '"iso_raster":{"triangles":[1-9][0-9]*,"draw_gpu_seconds":\(null\|[0-9.]*\),"path":"\(compute extraction + indirect draw\|task and mesh shaders\|compute rasterizer, 64-bit atomics\)","mesh_shader":"VK_EXT_mesh_shader[^"]*","choice":"measured on this frame","measured_seconds":{"graphics":[0-9.]*,"compute":[0-9.]*}}' \
        "$WORK/raster.json" || fail "--iso-raster json: $(cat "$WORK/raster.json")"
    db=$("$PY" "$SRC/tests/cli/psnr.py" "$WORK/ray.png" "$WORK/raster.png" | sed -n 's/^psnr \([0-9.inf]*\).*/\1/p')
    "$PY" -c "import sys; d = float(sys.argv[1]); sys.exit(0 if d >= 40 else 1)" "$db" || fail "--iso-raster $opts: PSNR $db dB against the ray-marched picture"
    echo "ok --iso-raster $opts: $db dB against the ray-marched picture"
done

# The compute rasterizer (--iso-raster-path compute: a visibility buffer filled by 64-bit atomics, and by
# 32-bit ones in two passes where TPK_VK_NO_INT64_ATOMICS=1 takes the variant for devices without them)
# against the ray-marched surfaces at >= 50 dB and against the graphics path; three values, shading, a
# clip box, a camera inside the mesh (triangles cut at the near distance) and a size where triangles
# cover many pixels (the large-triangle pass).
for opts in "--iso -0.005 --size 160x120" "--iso -0.018,-0.012,-0.005 --shading --clip-box -10,-10,-10,10,0.2,10 --size 200x150" \
    "--iso -0.018,-0.005,-0.012 --shading --camera 0.3,0.6,0.2,0.9,0.1,0.8,0,0,1,90 --size 256x192" \
    "--iso -0.018,-0.005 --shading --size 640x480"; do
    # shellcheck disable=SC2086
    tpk render "$WORK/m.tpk" -o "$WORK/ray.png" --backend cpu --field disp_z --step 4 --tf "$WORK/clear.tf" $opts \
        > /dev/null || fail "ray-marched $opts"
    # shellcheck disable=SC2086
    tpk render "$WORK/m.tpk" -o "$WORK/graphics.png" --backend vulkan --field disp_z --step 4 --tf "$WORK/clear.tf" \
        $opts --iso-raster --iso-raster-path graphics --json > "$WORK/graphics.json" || fail "--iso-raster-path graphics $opts"
    grep -q '"path":"\(compute extraction + indirect draw\|task and mesh shaders\)",.*"choice":"--iso-raster-path"' \
        "$WORK/graphics.json" || fail "graphics path json: $(cat "$WORK/graphics.json")"
    for bits in 64 32; do
        no64=0
        [ $bits = 32 ] && no64=1
        # shellcheck disable=SC2086
        TPK_VK_NO_INT64_ATOMICS=$no64 tpk render "$WORK/m.tpk" -o "$WORK/compute$bits.png" --backend vulkan --field disp_z \
            --step 4 --tf "$WORK/clear.tf" $opts --iso-raster --iso-raster-path compute --json > "$WORK/compute.json" ||
            fail "--iso-raster-path compute $opts ($bits-bit atomics)"
        if ! grep -q "\"path\":\"compute rasterizer, $bits-bit atomics\",.*\"choice\":\"--iso-raster-path\"" "$WORK/compute.json"; then
            # a device without 64-bit buffer atomics draws with 32-bit ones, and says so
            [ $bits = 64 ] && grep -q '"path":"compute rasterizer, 32-bit atomics"' "$WORK/compute.json" ||
                fail "compute path json: $(cat "$WORK/compute.json")"
        fi
        db=$("$PY" "$SRC/tests/cli/psnr.py" "$WORK/ray.png" "$WORK/compute$bits.png" | sed -n 's/^psnr \([0-9.inf]*\).*/\1/p')
        "$PY" -c "import sys; d = float(sys.argv[1]); sys.exit(0 if d >= 50 else 1)" "$db" ||
            fail "--iso-raster-path compute $opts ($bits-bit atomics): PSNR $db dB against the ray-marched picture"
        gdb=$("$PY" "$SRC/tests/cli/psnr.py" "$WORK/graphics.png" "$WORK/compute$bits.png" | sed -n 's/^psnr \([0-9.inf]*\).*/\1/p')
        "$PY" -c "import sys; d = float(sys.argv[1]); sys.exit(0 if d >= 50 else 1)" "$gdb" ||
            fail "--iso-raster-path compute $opts ($bits-bit atomics): PSNR $gdb dB against the graphics path"
        echo "ok compute rasterizer $opts, $bits-bit atomics: $db dB against the ray-marched picture, $gdb dB against graphics"
    done
    cmp -s "$WORK/compute64.png" "$WORK/compute32.png" || fail "--iso-raster-path compute $opts: 64-bit and 32-bit atomics differ"
done
# auto where the compute rasterizer cannot draw (its visibility buffer over the device's
# maxStorageBufferRange: 7000x5000 needs 280 MB, lavapipe binds 128 MB): the graphics path draws, and
# --json says why; forced, the same is an error that names the limit
tpk render "$WORK/m.tpk" -o "$WORK/big.png" --backend vulkan --field disp_z --step 4 --iso -0.005 --iso-raster \
    --size 7000x5000 --json > "$WORK/big.json" || fail "--iso-raster auto at 7000x5000"
case "$(cat "$WORK/big.json")" in
*'"choice":"the compute rasterizer could not draw at this size"'*)
    grep -q '"path":"\(compute extraction + indirect draw\|task and mesh shaders\)"' "$WORK/big.json" ||
        fail "auto without the compute rasterizer: $(cat "$WORK/big.json")"
    expect_exit 2 tpk render "$WORK/m.tpk" -o "$WORK/big.png" --backend vulkan --field disp_z --iso -0.005 --iso-raster \
        --iso-raster-path compute --size 7000x5000
    expect_stderr "Vulkan limit maxStorageBufferRange" ;;
*'"choice":"measured on this frame"'*) echo "iso_vulkan: this device binds a 7000x5000 visibility buffer" ;;
*) fail "--iso-raster auto at 7000x5000: $(cat "$WORK/big.json")" ;;
esac
expect_exit 2 tpk render "$WORK/m.tpk" -o "$WORK/x.png" --backend vulkan --field disp_z --iso -0.005 --iso-raster \
    --iso-raster-path fast
expect_stderr "--iso-raster-path expects auto, compute or graphics, found 'fast'"

# The mesh-shader path (task shaders cull clusters of 32 tets by value range, mesh shaders emit the
# triangles) where the device has VK_EXT_mesh_shader: the same triangles as the compute path
# (TETPACK_ISO_MESH_SHADER=0), so the same count and the same picture up to the order of equal depths.
# Without the extension (lavapipe) it is not run, and this says so; the compute path above was checked.
json=$(cat "$WORK/graphics.json")
case "$json" in
*'"path":"task and mesh shaders"'*)
    for opts in "--iso -0.005" "--iso -0.018,-0.012,-0.005 --shading --clip-box -10,-10,-10,10,0.2,10"; do
        for mesh in 1 0; do
            # shellcheck disable=SC2086
            TETPACK_ISO_MESH_SHADER=$mesh tpk render "$WORK/m.tpk" -o "$WORK/mesh$mesh.png" --backend vulkan --size 256x192 \
                --field disp_z --step 4 --tf "$WORK/clear.tf" $opts --iso-raster --iso-raster-path graphics --json > "$WORK/mesh$mesh.json" ||
                fail "--iso-raster $opts, TETPACK_ISO_MESH_SHADER=$mesh"
        done
        grep -q '"path":"task and mesh shaders","mesh_shader":"VK_EXT_mesh_shader used"' "$WORK/mesh1.json" ||
            fail "mesh path json: $(cat "$WORK/mesh1.json")"
        grep -q '"path":"compute extraction + indirect draw","mesh_shader":"VK_EXT_mesh_shader present, not used: TETPACK_ISO_MESH_SHADER=0"' \
            "$WORK/mesh0.json" || fail "compute path json: $(cat "$WORK/mesh0.json")"
        t1=$(grep -o '"iso_raster":{"triangles":[0-9]*' "$WORK/mesh1.json" | grep -o '[0-9]*$')
        t0=$(grep -o '"iso_raster":{"triangles":[0-9]*' "$WORK/mesh0.json" | grep -o '[0-9]*$')
        [ "$t1" = "$t0" ] || fail "--iso-raster $opts: $t1 triangles by mesh shaders, $t0 by compute"
        db=$("$PY" "$SRC/tests/cli/psnr.py" "$WORK/mesh0.png" "$WORK/mesh1.png" | sed -n 's/^psnr \([0-9.inf]*\).*/\1/p')
        "$PY" -c "import sys; d = float(sys.argv[1]); sys.exit(0 if d >= 60 else 1)" "$db" ||
            fail "--iso-raster $opts: mesh shaders against compute: PSNR $db dB"
        echo "ok mesh shaders $opts: $t1 triangles, $db dB against the compute path"
    done ;;
*'"mesh_shader":"VK_EXT_mesh_shader absent"'*)
    echo "iso_vulkan: the mesh-shader path not run: this device ($(grep -o '"device":"[^"]*"' <<< "$json" | head -1)) has no VK_EXT_mesh_shader" ;;
*) fail "--iso-raster json names neither path: $json" ;;
esac
expect_exit 2 tpk render "$WORK/m.tpk" -o "$WORK/x.png" --backend cpu --field disp_z --iso -0.005 --iso-raster
expect_stderr "--iso-raster draws with Vulkan"
expect_exit 2 tpk render "$WORK/m.tpk" -o "$WORK/x.png" --backend vulkan --field disp_z --iso -0.005 --iso-raster --shadows
expect_stderr "without --shadows, --ao and --iso-opacity"
expect_exit 2 tpk render "$WORK/m.tpk" -o "$WORK/x.png" --backend vulkan --field disp_z --iso-raster
expect_stderr "give --iso V"
echo "iso_vulkan: --iso-raster matches the ray-marched surfaces"
