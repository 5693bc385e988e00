#!/usr/bin/env bash
# Converts every real mesh in the data corpus and the bundled sample with a fixed set of options,
# exports each result as VTU and PLY, renders it as PNG, and prints one "sha256  name" line per output;
# then makes levels of detail of a few meshes and hashes those files, info and check --json, and
# render --level's picture and --json (convert's and render's --json with their timings left out).
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

# Levels of detail (convert --levels), and the --json of convert, info, check and render --level.
untimed() { sed -E 's/"(seconds|[a-z_]*seconds[a-z_]*|[a-z_]*_ms)":(\{[^}]*\}|[-0-9.e+]+|null)/"\1":-/g'; }
levels() { # tag input levels
    local tag=$1 input=$2 n=$3 tpk="$out/$1.tpk"
    if "$tetpack" convert "$input" "$tpk" --threads 2 --levels "$n" --json 2>"$out/$tag.err" | untimed | sed "s|$out/||g" >"$out/$tag.convert.json"; then
        "$tetpack" info "$tpk" --json 2>&1 | sed "s|$out/||g" >"$out/$tag.info.json"
        "$tetpack" check "$tpk" --json 2>&1 | untimed | sed "s|$out/||g" >"$out/$tag.check.json"
        for k in 0 1 2; do
            TETPACK_RENDER_BACKEND=cpu "$tetpack" render "$tpk" --level $k -o "$out/$tag.l$k.png" --size 96x72 --threads 2 \
                --json 2>&1 | untimed | sed "s|$out/||g" >"$out/$tag.l$k.render.json"
        done
        (cd "$out" && sha256sum "$tag".*)
    else
        echo "refused($?) $tag: $(head -c 300 "$out/$tag.err" | tr '\n' ' ')"
    fi
}
levels lod_sample "$src/samples/cylinder.vtk" 2
for f in "$data"/sfepy/elbow.mesh "$data"/sfepy/piezo_mesh_micro.vtk "$data"/nasa_refine/cube-sphere_cube-sphere.meshb \
         "$data"/tetgen/hinge_small.node "$data"/gmsh/t3_hex_prism_ascii41.msh "$data"/seacas/exomerge_unit_test.e; do
    [ -f "$f" ] || continue
    levels "lod_$(basename "$(dirname "$f")")_$(basename "$f" | tr '.' '_')" "$f" 3
done
