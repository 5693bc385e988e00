# tetpack render --backend vulkan|cpu: both backends write the same picture (PSNR >= 40 dB, compared
# with numpy), --json names the backend, the device and why, the default is Vulkan on a hardware device
# and the CPU otherwise (lavapipe only, as here, or none), and every Vulkan failure is a clear message with exit 2, never a crash.
source "$(dirname "$0")/common.sh"

convert_checked "$SRC/samples/cylinder.vtk" "$WORK/cyl.tpk" --layout tet16 --layout tet20 > /dev/null
tpk render --help > "$WORK/help.txt" # (not piped into grep -q: a help longer than stdio's buffer would get SIGPIPE)
grep -q -- "--backend vulkan|cpu" "$WORK/help.txt" || fail "render --help lacks --backend"

for layout in tet16 tet20; do
    for backend in cpu vulkan; do
        tpk render "$WORK/cyl.tpk" -o "$WORK/$backend-$layout.png" --size 96x80 --layout $layout \
            --backend $backend --json > "$WORK/$backend.json" 2> "$WORK/err" || { cat "$WORK/err"; fail "render $backend"; }
    done
    grep -q '"backend":"vulkan","device":"llvmpipe' "$WORK/vulkan.json" || fail "vulkan json: $(cat "$WORK/vulkan.json")"
    grep -q '"backend":"cpu","device":"cpu"' "$WORK/cpu.json" || fail "cpu json: $(cat "$WORK/cpu.json")"
    "$PY" - "$WORK/cpu-$layout.png" "$WORK/vulkan-$layout.png" <<'PYEOF' || fail "vulkan and cpu pictures differ ($layout)"
import sys, numpy as np, vtkmodules.vtkIOImage as io
from vtkmodules.util.numpy_support import vtk_to_numpy
def read(path):
    r = io.vtkPNGReader(); r.SetFileName(path); r.Update()
    return vtk_to_numpy(r.GetOutput().GetPointData().GetScalars()).astype(float)
a, b = read(sys.argv[1]), read(sys.argv[2])
mse = ((a - b) ** 2).mean()
psnr = 99.0 if mse == 0 else 10 * np.log10(255.0 ** 2 / mse)
print("PSNR %.2f dB, max pixel difference %d" % (psnr, abs(a - b).max()))
sys.exit(0 if psnr >= 40 and a.std() > 0 else 1)
PYEOF
done

# the default: here the only Vulkan device is lavapipe, a software rasterizer, so the CPU reference (a
# hardware device would be the default: tests/test_render_backend.c); TETPACK_RENDER_BACKEND and --backend
# override it, and --json and -v say which and why
unset TETPACK_RENDER_BACKEND
tpk render "$WORK/cyl.tpk" -o "$WORK/default.png" --size 32x32 --json -v > "$WORK/default.json" 2> "$WORK/default.err"
grep -q '"backend":"cpu"' "$WORK/default.json" || fail "default backend: $(cat "$WORK/default.json")"
grep -q '"backend_reason":"default: the only Vulkan device is a software rasterizer (llvmpipe' "$WORK/default.json" \
    || fail "default backend_reason: $(cat "$WORK/default.json")"
grep -q "backend cpu (cpu): default: the only Vulkan device is a software rasterizer" "$WORK/default.err" \
    || fail "-v: $(cat "$WORK/default.err")"
TETPACK_RENDER_BACKEND=vulkan tpk render "$WORK/cyl.tpk" -o "$WORK/env.png" --size 32x32 --json > "$WORK/env.json"
grep -q '"backend":"vulkan".*"backend_reason":"TETPACK_RENDER_BACKEND=vulkan"' "$WORK/env.json" \
    || fail "TETPACK_RENDER_BACKEND=vulkan: $(cat "$WORK/env.json")"
TETPACK_RENDER_BACKEND=cpu tpk render "$WORK/cyl.tpk" -o "$WORK/env.png" --size 32x32 --json > "$WORK/env.json"
grep -q '"backend":"cpu"' "$WORK/env.json" || fail "TETPACK_RENDER_BACKEND=cpu: $(cat "$WORK/env.json")"
TETPACK_RENDER_BACKEND=cpu tpk render "$WORK/cyl.tpk" -o "$WORK/env.png" --size 32x32 --json --backend vulkan > "$WORK/env.json"
grep -q '"backend":"vulkan".*"backend_reason":"--backend vulkan"' "$WORK/env.json" || fail "--backend over the environment: $(cat "$WORK/env.json")"
export TETPACK_RENDER_BACKEND=metal
expect_exit 2 tpk render "$WORK/cyl.tpk" -o "$WORK/env.png" --size 32x32
expect_stderr "TETPACK_RENDER_BACKEND expects vulkan or cpu"
unset TETPACK_RENDER_BACKEND

# no Vulkan driver: --backend vulkan is an error (exit 2), the default falls back to the CPU
export VK_ICD_FILENAMES="$WORK/no_such_icd.json"
expect_exit 2 tpk render "$WORK/cyl.tpk" -o "$WORK/none.png" --size 32x32 --backend vulkan
expect_stderr "vulkan: creating the instance"
[ ! -e "$WORK/none.png" ] || fail "an image was written after a Vulkan error"
tpk render "$WORK/cyl.tpk" -o "$WORK/fallback.png" --size 32x32 --json > "$WORK/fallback.json"
grep -q '"backend":"cpu".*"backend_reason":"default: no Vulkan device' "$WORK/fallback.json" || fail "fallback backend: $(cat "$WORK/fallback.json")"
unset VK_ICD_FILENAMES

# a binding limit the file cannot fit in: refused with exit 2 and a message, not a crash
export TPK_VK_SPLIT_BYTES=64
expect_exit 2 tpk render "$WORK/cyl.tpk" -o "$WORK/small.png" --size 32x32 --backend vulkan
expect_stderr "larger than the device"
unset TPK_VK_SPLIT_BYTES
expect_exit 2 tpk render "$WORK/cyl.tpk" -o "$WORK/x.png" --backend metal
expect_stderr "backend expects vulkan or cpu"

# The scene's backend is used on replay (over $TETPACK_RENDER_BACKEND; --backend overrides it); without a
# Vulkan device the CPU reference draws it, with a note. A saved scene records the backend that drew it.
printf '{"size": [32, 24], "backend": "vulkan"}' > "$WORK/vk.json"
TETPACK_RENDER_BACKEND=cpu tpk render "$WORK/cyl.tpk" -o "$WORK/vk.png" --scene "$WORK/vk.json" --json --save-scene "$WORK/vk_saved.json" > "$WORK/vk.txt"
grep -q '"backend":"vulkan"' "$WORK/vk.txt" || fail "the scene's backend was not used: $(cat "$WORK/vk.txt")"
grep -q '"backend":[[:space:]]*"vulkan"' "$WORK/vk_saved.json" || fail "the saved scene does not record vulkan"
tpk render "$WORK/cyl.tpk" -o "$WORK/vk_cpu.png" --scene "$WORK/vk.json" --backend cpu --json > "$WORK/vk.txt"
grep -q '"backend":"cpu"' "$WORK/vk.txt" || fail "--backend cpu did not override the scene: $(cat "$WORK/vk.txt")"
VK_ICD_FILENAMES=/nonexistent/icd.json tpk render "$WORK/cyl.tpk" -o "$WORK/vk_none.png" --scene "$WORK/vk.json" \
    --json > "$WORK/vk.txt" 2> "$WORK/vk.err" || fail "a Vulkan scene without a device failed: $(cat "$WORK/vk.err")"
grep -q "no Vulkan device here, so the CPU reference renders it" "$WORK/vk.err" || fail "no note: $(cat "$WORK/vk.err")"
grep -q '"backend":"cpu"' "$WORK/vk.txt" || fail "no CPU fallback: $(cat "$WORK/vk.txt")"
# Device memory per layout (--json device_bytes): the mesh arrays as they are, so Tet20 holds 4 bytes per
# tet more than Tet16; the CPU reference holds none.
convert_checked "$SRC/samples/cylinder.vtk" "$WORK/cyl3.tpk" --layout tet16 --layout tet20 --layout tet32 > /dev/null
for layout in tet16 tet20 tet32; do
    tpk render "$WORK/cyl3.tpk" -o "$WORK/mem.png" --size 16x16 --backend vulkan --layout $layout --json > "$WORK/mem_$layout.json"
done
tpk render "$WORK/cyl3.tpk" -o "$WORK/mem.png" --size 16x16 --backend cpu --json > "$WORK/mem_cpu.json"
"$TPK" info "$WORK/cyl3.tpk" --json > "$WORK/cyl3_info.json"
$PY - "$WORK" <<'PY' || fail "device_bytes per layout"
import json, sys
w = sys.argv[1]
b = {l: json.load(open(f"{w}/mem_{l}.json"))["device_bytes"] for l in ("tet16", "tet20", "tet32", "cpu")}
tets = json.load(open(f"{w}/cyl3_info.json"))["tets"]
assert b["cpu"] == 0 and b["tet16"] > 16 * tets, b
assert b["tet20"] - b["tet16"] == 4 * tets and b["tet32"] - b["tet20"] == 12 * tets, (b, tets)
PY
echo "render_vulkan: ok"
