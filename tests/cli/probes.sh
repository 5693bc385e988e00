#!/usr/bin/env bash
# CSG probes (render.h PROBES) from the command line, on real meshes (samples/cylinder.vtk and Gmsh's t5
# tutorial mesh): the CPU reference and the Vulkan renderer (lavapipe here) draw the same picture (>= 40
# dB) for a sphere, a half-space and a box, kept and cut, alone and combined, with shading and shadows;
# --save-scene writes the probes and --scene replays them byte for byte; extract --scene keeps only the
# tets that may show, and the small file renders the same picture; --iso-raster cuts its triangles with
# the same probes; bad probes are refused by name.
source "$(dirname "$0")/common.sh"

tpk convert "$SRC/samples/cylinder.vtk" "$WORK/cyl.tpk" --quiet || fail "cannot convert the cylinder"
tpk convert "$DATA/gmsh/t5_small_tet_ascii22.msh" "$WORK/t5.tpk" --quiet || fail "cannot convert t5"

# What each probe does to the picture: a keep sphere shows less than the whole, a cut sphere removes some.
tpk render "$WORK/cyl.tpk" -o "$WORK/plain.png" --size 96x96 --backend cpu > /dev/null
tpk render "$WORK/cyl.tpk" -o "$WORK/keep.png" --size 96x96 --backend cpu --probe sphere:0.05,0,0,0.012 > /dev/null
tpk render "$WORK/cyl.tpk" -o "$WORK/cut.png" --size 96x96 --backend cpu --probe sphere:0.05,0,0,0.012:cut > /dev/null
"$PY" - "$WORK/plain.png" "$WORK/keep.png" "$WORK/cut.png" <<'PYEOF' || fail "the probes do not change the picture as they should"
import sys
import numpy as np
from PIL import Image
plain, keep, cut = (np.asarray(Image.open(p).convert("RGBA")).astype(int) for p in sys.argv[1:])
bg = plain[0, 0]
shows = lambda im: (np.abs(im - bg).sum(axis=2) > 6)
assert 0 < shows(keep).sum() < shows(plain).sum(), (shows(keep).sum(), shows(plain).sum())
assert (shows(keep) & ~shows(plain)).sum() == 0
assert np.abs(cut - plain).max() > 20
PYEOF

vulkan=1
if ! tpk render "$WORK/cyl.tpk" -o "$WORK/v.png" --size 8x8 --backend vulkan > /dev/null 2> "$WORK/err"; then
    grep -q "built without Vulkan\|vulkan\|Vulkan" "$WORK/err" || fail "render --backend vulkan failed without saying why"
    vulkan=0
fi
cases=("sphere:0.05,0,0,0.012" "sphere:0.05,0,0,0.012:cut" "plane:0.05,0,0,1,0.5,0" "plane:0.05,0,0,1,0.5,0:cut"
       "box:0.02,-1,-1,0.07,0.005,1" "box:0.02,-1,-1,0.07,0.005,1:cut")
n=0
for mesh in cyl t5; do
    for c in "${cases[@]}" "combined"; do
        if [ "$mesh" = t5 ]; then # t5's box is [-0.05, 1.05]^3 (a cube with a cut corner and holes)
            c=${c//0.05,0,0,0.012/0.5,0.5,0.5,0.35}; c=${c//0.05,0,0,1,0.5,0/0.5,0.5,0.5,1,0.5,0.2}
            c=${c//0.02,-1,-1,0.07,0.005,1/0.2,-1,-1,0.7,0.55,2}
        fi
        if [ "$c" = combined ]; then # a keep half-space, a cut sphere and a cut box together
            opts=(--probe "plane:0.06,0,0,1,0,0" --probe "sphere:0.04,0,0,0.01:cut" --probe "box:0,0.01,-1,1,1,1:cut")
            [ "$mesh" = t5 ] && opts=(--probe "plane:0.8,0,0,1,0,0" --probe "sphere:0.4,0.5,0.5,0.3:cut" --probe "box:0,0.7,-1,1,2,2:cut")
        else
            opts=(--probe "$c")
        fi
        tpk render "$WORK/$mesh.tpk" -o "$WORK/cpu.png" --size 64x64 --backend cpu --shading --shadows "${opts[@]}" \
            --save-scene "$WORK/s.json" > /dev/null || fail "cpu render $mesh ${opts[*]}"
        grep -q '"probes"' "$WORK/s.json" || fail "--save-scene wrote no probes: $(cat "$WORK/s.json")"
        tpk render "$WORK/$mesh.tpk" -o "$WORK/replay.png" --scene "$WORK/s.json" > /dev/null || fail "replay $mesh ${opts[*]}"
        cmp -s "$WORK/cpu.png" "$WORK/replay.png" || fail "$mesh ${opts[*]}: --scene of the saved scene draws another picture"
        if [ "$vulkan" = 1 ]; then
            tpk render "$WORK/$mesh.tpk" -o "$WORK/vk.png" --size 64x64 --backend vulkan --shading --shadows "${opts[@]}" \
                > /dev/null || fail "vulkan render $mesh ${opts[*]}"
            db=$(psnr "$WORK/cpu.png" "$WORK/vk.png")
            at_least "$db" 40 || fail "$mesh ${opts[*]}: Vulkan against the CPU $db dB"
            echo "ok $mesh ${opts[*]}: Vulkan against the CPU $db dB"
        fi
        n=$((n + 1))
    done
done
[ "$vulkan" = 1 ] || skip "no Vulkan device: $(cat "$WORK/err") (the CPU checks passed)"

# extract --scene keeps the tets that may show; the small file renders the same picture
tpk render "$WORK/t5.tpk" -o "$WORK/full.png" --size 96x96 --backend cpu --probe "sphere:0.5,0.5,0.5,0.45" \
    --probe "plane:0.5,0.5,0.5,0,0,1:cut" --save-scene "$WORK/t5.json" > /dev/null
tpk extract "$WORK/t5.tpk" "$WORK/small.tpk" --scene "$WORK/t5.json" --save-scene "$WORK/small.json" --json \
    > "$WORK/extract.json" || fail "extract --scene with probes"
"$PY" - "$WORK/extract.json" <<'PYEOF' || fail "extract kept every tet: $(cat "$WORK/extract.json")"
import json, sys
r = json.load(open(sys.argv[1]))
assert 0 < r["tets_after"] < 0.8 * r["tets_before"], (r["tets_before"], r["tets_after"])
PYEOF
check_6xx "$WORK/small.tpk"
tpk render "$WORK/small.tpk" -o "$WORK/small.png" --scene "$WORK/small.json" > /dev/null
cmp -s "$WORK/full.png" "$WORK/small.png" || fail "the extracted file renders another picture ($(psnr "$WORK/full.png" "$WORK/small.png") dB)"

# refused by name
expect_exit 2 tpk render "$WORK/cyl.tpk" -o "$WORK/x.png" --probe cone:1,2,3,4
expect_stderr "--probe expects sphere:cx,cy,cz,r"
expect_exit 2 tpk render "$WORK/cyl.tpk" -o "$WORK/x.png" --probe sphere:0,0,0,-1
expect_stderr "probe 1: expected a sphere radius > 0, found -1"
expect_exit 2 tpk render "$WORK/cyl.tpk" -o "$WORK/x.png" --probe plane:0,0,0,0,0,0
expect_stderr "probe 1: the plane's normal is zero"
expect_exit 2 tpk render "$WORK/cyl.tpk" -o "$WORK/x.png" --probe box:0,0,0,1,1,1 --probe box:0,0,0,1,1,1 \
    --probe box:0,0,0,1,1,1 --probe box:0,0,0,1,1,1 --probe box:0,0,0,1,1,1
expect_stderr "at most 4 probes"
printf '{"probes": [{"shape": "sphere", "center": [0, 0, 0], "radius": 1, "mode": "erase"}]}' > "$WORK/bad.json"
expect_exit 2 tpk render "$WORK/cyl.tpk" -o "$WORK/x.png" --scene "$WORK/bad.json"
expect_stderr "bad.json:1:2: key 'probes': probe 1: expected \"mode\": \"keep\" or \"cut\", found \"erase\""
printf '{"probes": [{"shape": "box", "min": [0, 0, 0], "max": [1, -1, 1]}]}' > "$WORK/bad.json"
expect_exit 2 tpk extract "$WORK/cyl.tpk" "$WORK/x.tpk" --scene "$WORK/bad.json"
expect_stderr "probe 1: box min 0 above max -1 on axis y"
[ ! -e "$WORK/x.tpk" ] || fail "extract wrote a file for a bad scene"
# --iso-raster (isosurfaces drawn as triangles): a fragment the probes leave out is discarded, so the
# surface behind it shows, as for a ray that passes the cut part: against the CPU's ray-marched surfaces
# (a TF transparent everywhere), and each probe set must change the picture
printf '0 0.2 0.4 0.9 0\n1 0.9 0.2 0.1 0\n' > "$WORK/clear.tf"
tpk render "$WORK/cyl.tpk" -o "$WORK/raster-none.png" --backend vulkan --size 96x96 --tf "$WORK/clear.tf" --iso 320,350 \
    --shading --iso-raster > /dev/null || fail "--iso-raster without probes"
for probes in "--probe sphere:0.05,0,0,0.012" "--probe sphere:0.05,0,0,0.012:cut" "--probe plane:0.04,0,0,1,0.3,0" \
    "--probe box:0.02,-0.02,-0.01,0.08,0.01,0.02:cut --probe plane:0,0,0.005,0,0,1"; do
    # shellcheck disable=SC2086
    tpk render "$WORK/cyl.tpk" -o "$WORK/raster.png" --backend vulkan --size 96x96 --tf "$WORK/clear.tf" --iso 320,350 \
        --shading --iso-raster $probes > /dev/null || fail "--iso-raster $probes"
    # shellcheck disable=SC2086
    tpk render "$WORK/cyl.tpk" -o "$WORK/ray.png" --backend cpu --size 96x96 --tf "$WORK/clear.tf" --iso 320,350 \
        --shading $probes > /dev/null || fail "ray-marched $probes"
    db=$(psnr "$WORK/ray.png" "$WORK/raster.png")
    at_least "$db" 40 || fail "--iso-raster $probes: $db dB against the ray-marched surfaces"
    cmp -s "$WORK/raster.png" "$WORK/raster-none.png" && fail "--iso-raster $probes: the probes change nothing"
    echo "ok --iso-raster $probes: $db dB against the ray-marched surfaces"
done
echo "probes: $n probe sets, CPU and Vulkan agree; scenes replay; extract keeps what shows"
