#!/usr/bin/env bash
# spirv-val (SPIRV-Tools) on every SPIR-V module glslc made for the binary: DIR holds glslc's -mfmt=c
# outputs (*.inc: comma-separated 32-bit words in braces), which embed_spirv.cmake wraps into C. Each is
# turned back into a binary module and validated for Vulkan 1.2, the renderer's target; the names of the
# modules expected are listed, so a shader left out of the build fails here too.
set -euo pipefail
dir=$1
if ! command -v spirv-val > /dev/null; then
    [ "${TETPACK_REQUIRE_ALL:-0}" = 1 ] && { echo "FAIL: spirv-val (spirv-tools) is missing" >&2; exit 1; }
    echo "SKIP: spirv-val (Debian: spirv-tools) is not installed"
    exit 77
fi
work=$(mktemp -d "${TMPDIR:-/tmp}/tpk_spirv_XXXXXX")
trap 'rm -rf "$work"' EXIT
for name in render_fp64 render_fp32 render_fp64_one render_fp32_one iso iso_raster_vert iso_raster_frag iso_mesh_task iso_mesh_mesh iso_vis64 iso_vis32 \
    iso_resolve; do
    [ -f "$dir/$name.inc" ] || { echo "FAIL: $dir/$name.inc was not built" >&2; exit 1; }
    /usr/bin/python3 - "$dir/$name.inc" "$work/$name.spv" <<'PY'
import re, struct, sys
words = [int(w, 16) for w in re.findall(r"0x[0-9a-fA-F]+", open(sys.argv[1]).read())]
if not words or words[0] != 0x07230203:
    sys.exit("%s: not SPIR-V (magic %s)" % (sys.argv[1], hex(words[0]) if words else "none"))
open(sys.argv[2], "wb").write(struct.pack("<%dI" % len(words), *words))
PY
    spirv-val --target-env vulkan1.2 "$work/$name.spv" || { echo "FAIL: $name breaks the SPIR-V rules (above)" >&2; exit 1; }
    echo "ok $name: $(($(stat -c %s "$work/$name.spv") / 4)) words, valid for Vulkan 1.2"
done
