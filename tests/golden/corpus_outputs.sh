#!/usr/bin/env bash
# Converts every real mesh in the data corpus and the bundled sample with a fixed set of options,
# exports each result as VTU and PLY, renders it as PNG, and prints one "sha256  name" line per output.
# Used to show that a change which should not alter outputs (a refactoring) keeps them byte-identical:
#   tests/golden/corpus_outputs.sh build/tetpack ../shared/data OUTDIR > before.txt   (then after, diff)
# Inputs that convert refuses are listed with their exit code, so a change in refusals shows too.
set -uo pipefail
tetpack=$1 data=$2 out=$3
src=$(cd "$(dirname "$0")/../.." && pwd)
mkdir -p "$out"

one() { # tag input convert-options...
    local tag=$1 input=$2
    shift 2
    local tpk="$out/$tag.tpk"
    if "$tetpack" convert "$input" "$tpk" --threads 2 "$@" >/dev/null 2>"$out/$tag.err"; then
        "$tetpack" export "$tpk" --vtu "$out/$tag.vtu" --shell "$out/$tag.ply" >/dev/null 2>&1 || echo "export-failed $tag"
        TETPACK_RENDER_BACKEND=cpu "$tetpack" render "$tpk" -o "$out/$tag.png" --size 96x72 --threads 2 >/dev/null 2>&1 || echo "render-failed $tag"
        (cd "$out" && sha256sum "$tag.tpk" "$tag.vtu" "$tag.ply" "$tag.png" 2>/dev/null)
    else
        echo "refused($?) $tag: $(head -c 300 "$out/$tag.err" | tr '\n' ' ')"
    fi
}

one sample "$src/samples/cylinder.vtk" --layout tet16 --layout tet20 --layout tet32
one sample_zstd "$src/samples/cylinder.vtk" --layout tet20 --zstd 3 --no-reorder
for f in "$data"/sfepy/* "$data"/seacas/*.{g,e,ex2} "$data"/nasa_refine/* "$data"/gmsh/*.msh "$data"/gmsh/*.vtk \
         "$data"/hard/*.vtk "$data"/hard/*.vtu "$data"/hard/*.node "$data"/tetgen/*.node; do
    [ -f "$f" ] || continue
    tag=$(basename "$(dirname "$f")")_$(basename "$f" | tr '.' '_')
    one "$tag" "$f" --layout tet16 --layout tet32
    one "${tag}_repair" "$f" --layout tet20 --reorient --drop-degenerate --merge-duplicates --cell-to-point
done
