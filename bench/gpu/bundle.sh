#!/usr/bin/env bash
# A relocatable bundle of the GPU benchmark, for a GPU machine with a Vulkan driver but no compiler:
#   bench/gpu/bundle.sh [OUT_DIR]   (default bench/gpu/bundle)
# builds Release without the optional importers, view, MPI, Python and tests (build-gpu-bundle), and
# writes OUT_DIR/tetpack-gpu.tar.xz: bin/ (tetpack, bench_gpu), lib/ (every shared library they link,
# found with ldd, but glibc's, libstdc++ and libgcc_s, which the target has), bench/gpu/, the grid
# generator, the sample and the benchmark's meshes from ../shared/data; and OUT_DIR/run-gpu-bench.sh,
# which unpacks it beside itself and runs bench/gpu/run.sh on the bundle's binaries:
#   ./run-gpu-bench.sh [run.sh options]       VK_DRIVER_FILES=/usr/share/vulkan/icd.d/nvidia_icd.json ...
#   ./run-gpu-bench.sh --targets              the open GPU targets of issues 21 and 22 (targets.sh)
#   ./run-gpu-bench.sh --convert              issue 22's conversion target on the host's cores (convert_ratio.sh)
#   ./run-gpu-bench.sh --scaling              issue 37's scaling table on the host's cores (bench/scaling.sh)
#   ./run-gpu-bench.sh --partset              issue 39's 1G-tet part set on one GPU (partset.sh; in stages:
#                                             TPK_GPU_PARTSET_STAGE=grid, then convert, then render)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
OUT=$(mkdir -p "${1:-$ROOT/bench/gpu/bundle}" && cd "${1:-$ROOT/bench/gpu/bundle}" && pwd)
BUILD=${TPK_BUNDLE_BUILD:-$ROOT/build-gpu-bundle}
DATA=${TPK_DATA_DIR:-$ROOT/../shared/data}
cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DTETPACK_WITH_TESTS=OFF -DTETPACK_WITH_VIEW=OFF \
    -DTETPACK_WITH_MPI=OFF -DTETPACK_WITH_PYTHON=OFF -DTETPACK_WITH_CGNS=OFF -DTETPACK_WITH_HDF5=OFF \
    -DTETPACK_WITH_TETGEN=OFF -DTETPACK_WITH_OPENMESH=OFF -DTETPACK_WITH_VULKAN=ON >/dev/null
cmake --build "$BUILD" -j"$(nproc)" --target tetpack_cli bench_gpu >/dev/null

STAGE=$OUT/tetpack-gpu
rm -rf "$STAGE"
mkdir -p "$STAGE/bin" "$STAGE/lib" "$STAGE/bench/gpu" "$STAGE/samples" "$STAGE/data/sfepy" "$STAGE/data/nasa_refine"
cp "$BUILD/tetpack" "$BUILD/bench/bench_gpu" "$STAGE/bin/"
# the libraries they link, but those of the C and C++ runtimes (the target's own must be used)
for exe in "$STAGE/bin/tetpack" "$STAGE/bin/bench_gpu"; do
    ldd "$exe" | awk '/=> \// { print $3 }'
done | sort -u | while read -r lib; do
    case "$(basename "$lib")" in
        libc.so* | libm.so* | libpthread.so* | libdl.so* | librt.so* | ld-linux* | libstdc++.so* | libgcc_s.so*) ;;
        *) cp -L "$lib" "$STAGE/lib/" ;;
    esac
done
cp "$ROOT/bench/gpu/run.sh" "$ROOT/bench/gpu/targets.sh" "$ROOT/bench/gpu/convert_ratio.sh" "$ROOT/bench/gpu/table.py" \
    "$ROOT/bench/gpu/partset.sh" "$STAGE/bench/gpu/"
mkdir -p "$STAGE/tests/cli"
cp "$ROOT/tests/cli/psnr.py" "$ROOT/tests/cli/png_read.py" "$STAGE/tests/cli/" # partset.sh's PSNR
cp "$ROOT/bench/make_grid_vtk.py" "$ROOT/bench/scaling.sh" "$ROOT/bench/scaling_table.py" "$STAGE/bench/"
cp "$ROOT/samples/cylinder.vtk" "$STAGE/samples/"
cp "$DATA/sfepy/cube_big_tetra.mesh" "$STAGE/data/sfepy/"
cp "$DATA/nasa_refine/om6_om6-curv-no-geom.meshb" "$STAGE/data/nasa_refine/"
cat > "$STAGE/run.sh" <<'INNER'
#!/usr/bin/env bash
# Run the GPU benchmark on this bundle's binaries and libraries (bench/gpu/run.sh's options apply).
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
export LD_LIBRARY_PATH="$HERE/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export TPK_DATA_DIR=${TPK_DATA_DIR:-$HERE/data}
[ -n "${VK_DRIVER_FILES:-}" ] && echo "# VK_DRIVER_FILES=$VK_DRIVER_FILES" >&2
exec "$HERE/bench/gpu/run.sh" --bin "$HERE/bin" --out "${TPK_GPU_OUT:-$HERE/out}" "$@"
INNER
chmod +x "$STAGE/run.sh"
tar -C "$OUT" -cJf "$OUT/tetpack-gpu.tar.xz" tetpack-gpu
rm -rf "$STAGE"
cat > "$OUT/run-gpu-bench.sh" <<'OUTER'
#!/usr/bin/env bash
# Unpack tetpack-gpu.tar.xz beside this script (once) and run the GPU benchmark; results in
# tetpack-gpu/out (results.jsonl, results.md). VK_DRIVER_FILES names the vendor's ICD JSON when the
# loader does not find it, e.g. VK_DRIVER_FILES=/usr/share/vulkan/icd.d/nvidia_icd.json.
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
[ -x "$HERE/tetpack-gpu/run.sh" ] || tar -C "$HERE" -xJf "$HERE/tetpack-gpu.tar.xz"
exec "$HERE/tetpack-gpu/run.sh" "$@"
OUTER
chmod +x "$OUT/run-gpu-bench.sh"
echo "$OUT/tetpack-gpu.tar.xz ($(du -h "$OUT/tetpack-gpu.tar.xz" | cut -f1)) and $OUT/run-gpu-bench.sh"
