#!/bin/sh
# Regenerates tests/data/openfoam/: real snappyHexMesh meshes (hexahedra, prisms and polyhedra whose faces
# carry points on edges and are not planar) exported by OpenFOAM's own foamToVTK, with OpenFOAM's cell
# volumes, so that tests can check that `tetpack convert` keeps every cell and its volume.
# Needs OpenFOAM (Debian 12: apt-get install openfoam openfoam-examples, OpenFOAM v1912). CI does not run
# this; it runs the tests on the files this wrote (tests/test_openfoam.sh).
#   tests/openfoam/make_cases.sh OUTDIR [CASE...]   (CASE: wind, wind_full, igloo, flange, cavity; default wind igloo flange)
# cavity: the icoFoam cavity's polyMesh as case directories (OUTDIR/cases/cavity_{ascii,binary,gzip}) with a
# cell field p and a point field pp written from known formulas, and foamToVTK's cavity.vtk of the same mesh.
set -eu
OUT=${1:?usage: make_cases.sh OUTDIR [CASE...]}
shift
[ $# -gt 0 ] || set -- wind igloo flange
EXAMPLES=${EXAMPLES:-/usr/share/doc/openfoam-examples/examples}
export WM_PROJECT_DIR=${WM_PROJECT_DIR:-/usr/share/openfoam}
WORK=${WORK:-$(mktemp -d /tmp/tetpack-openfoam.XXXXXX)}
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)

# A tutorial case copied to $WORK/NAME with its gzipped files unpacked.
copy_case() {
    rm -rf "$WORK/$2"
    cp -r "$EXAMPLES/$1" "$WORK/$2"
    find "$WORK/$2" -name '*.gz' -exec gunzip -f {} +
    cd "$WORK/$2"
}

log() { "$@" > "log.$1" 2>&1 || { echo "make_cases.sh: $* failed in $(pwd); see log.$1" >&2; tail -20 "log.$1" >&2; exit 1; }; }

# Mesh, check, write OpenFOAM's cell volumes (17 digits) and export cells (polyhedra kept) to legacy VTK.
finish_case() {
    name=$1
    log checkMesh -constant
    grep -q "Mesh OK" log.checkMesh || { echo "make_cases.sh: checkMesh does not say 'Mesh OK' for $name" >&2; exit 1; }
    foamDictionary -entry writePrecision -set 17 system/controlDict > /dev/null
    foamDictionary -entry writeFormat -set ascii system/controlDict > /dev/null
    log postProcess -func writeCellVolumes -constant
    log foamToVTK -constant -legacy -no-boundary -no-point-data -fields '(V)'
    vtk=$(find VTK -maxdepth 2 -name '*.vtk' | sort | head -1)
    [ -n "$vtk" ] || { echo "make_cases.sh: foamToVTK wrote no .vtk for $name" >&2; exit 1; }
    cp "$vtk" "$OUT/$name.vtk"
    # OpenFOAM's own cell volumes, 17 digits: their count and sum (the VTK's V is float32 only).
    awk '/^internalField/ { getline; n = $1; getline; on = 1; next }
         on && /^\)/ { on = 0 }
         on { sum += $1; count++ }
         END { if (count != n) { print "V lists " count " of " n " cells" > "/dev/stderr"; exit 1 }
               printf "cells %d\nopenfoam_volume_sum %.17g\n", count, sum }' constant/V > "$OUT/$name.volumes.txt"
    # checkMesh's summary (cell counts by type, volumes, "Mesh OK") for the provenance file.
    sed -n '/Mesh stats/,/^End/p' log.checkMesh > "$OUT/$name.checkMesh.txt"
    echo "$name: $(grep -c . "$OUT/$name.checkMesh.txt") lines of checkMesh summary, $(du -k "$OUT/$name.vtk" | cut -f1) KiB"
}

for c in "$@"; do
    case $c in
    wind|wind_full)
        # The issue's mesh (wind_full: the tutorial as shipped, 185,237 cells); wind: a background mesh of
        # 12 x 10 x 5 instead of 25 x 20 x 10, surface level 2 and region level 1, so that the file stays small.
        copy_case incompressible/simpleFoam/windAroundBuildings "$c"
        if [ "$c" = wind ]; then
            sed -i -e 's/level (3 3)/level (2 2)/' -e 's/levels ((1E15 2))/levels ((1E15 1))/' system/snappyHexMeshDict
            sed -i -e 's/xCells  *25;/xCells 12;/' -e 's/yCells  *20;/yCells 10;/' -e 's/zCells  *10;/zCells 5;/' \
                system/blockMeshDict
        fi
        log surfaceFeatureExtract
        log blockMesh
        log snappyHexMesh -overwrite
        finish_case "$c" ;;
    igloo)
        copy_case heatTransfer/buoyantBoussinesqSimpleFoam/iglooWithFridges igloo
        sed -i -e 's/(20 20 10)/(10 10 5)/' system/blockMeshDict
        log blockMesh
        log snappyHexMesh -overwrite
        finish_case igloo ;;
    flange)
        copy_case mesh/snappyHexMesh/flange flange
        cp "$EXAMPLES/resources/geometry/flange.stl.gz" constant/triSurface/
        gunzip -f constant/triSurface/flange.stl.gz
        sed -i -e 's/(20 16 12)/(10 8 6)/' system/blockMeshDict
        log blockMesh
        log surfaceFeatureExtract
        log snappyHexMesh -overwrite
        finish_case flange
        # The same mesh as a case directory: binary (foamFormatConvert), each polyMesh file gzipped here
        # (v1912 leaves constant/polyMesh uncompressed with writeCompression on).
        foamDictionary -entry writeFormat -set binary system/controlDict > /dev/null
        log foamFormatConvert -constant
        rm -rf "$OUT/cases/flange_binary" && mkdir -p "$OUT/cases/flange_binary/constant/polyMesh"
        for f in points faces owner neighbour; do
            gzip -9n -c "constant/polyMesh/$f" > "$OUT/cases/flange_binary/constant/polyMesh/$f.gz"
        done
        touch "$OUT/cases/flange_binary/flange.foam" ;;
    cavity)
        copy_case incompressible/icoFoam/cavity/cavity cavity
        log blockMesh
        log checkMesh -constant
        foamDictionary -entry writePrecision -set 17 system/controlDict > /dev/null
        log foamToVTK -constant -legacy -no-boundary -no-point-data
        cp "$(find VTK -maxdepth 2 -name '*.vtk' | sort | head -1)" "$OUT/cavity.vtk"
        # Fields with values a test can recompute: p = 0.5 + cell id / 1000 at time 0.5, pp = point id at
        # time 0.5 (a pointScalarField), p uniform 2 and pp uniform 1 at time 0.25 (time steps sort numerically, not by name).
        n=$(sed -n 's/.*nCells:\([0-9]*\).*/\1/p' constant/polyMesh/owner)
        np=$(awk '/^[0-9]+$/ { print; exit }' constant/polyMesh/points)
        mkdir -p 0.5 0.25
        field() { # CLASS NAME TIME INTERNAL
            printf 'FoamFile\n{\n    version 2.0;\n    format ascii;\n    class %s;\n    object %s;\n}\n\n' "$1" "$2"
            printf 'dimensions [0 2 -2 0 0 0 0];\n\ninternalField %s;\n\nboundaryField\n{\n    ".*"\n    {\n        type calculated;\n    }\n}\n' "$4"
        }
        field volScalarField p 0.5 "nonuniform List<scalar> $n ($(awk -v n="$n" 'BEGIN { for (i = 0; i < n; i++) printf "%s%.17g", i ? " " : "", 0.5 + i / 1000 }'))" > 0.5/p
        field pointScalarField pp 0.5 "nonuniform List<scalar> $np ($(awk -v n="$np" 'BEGIN { for (i = 0; i < n; i++) printf "%s%d", i ? " " : "", i }'))" > 0.5/pp
        field volScalarField p 0.25 "uniform 2" > 0.25/p
        field pointScalarField pp 0.25 "uniform 1" > 0.25/pp
        # U (volVectorField): uniform (1 2 3) at 0.25; (cell id, -cell id, 0.25) at 0.5.
        field volVectorField U 0.25 "uniform (1 2 3)" > 0.25/U
        field volVectorField U 0.5 "nonuniform List<vector> $n ($(awk -v n="$n" 'BEGIN { for (i = 0; i < n; i++) printf "%s(%d %d 0.25)", i ? " " : "", i, -i }'))" > 0.5/U
        rm -rf "$OUT/cases"/cavity_* && mkdir -p "$OUT/cases"
        for form in ascii binary gzip; do
            rm -rf "$WORK/cavity_$form" && mkdir -p "$WORK/cavity_$form"
            cp -r system constant 0.25 0.5 "$WORK/cavity_$form/"
            case $form in
            binary) foamDictionary -entry writeFormat -set binary "$WORK/cavity_$form/system/controlDict" > /dev/null ;;
            gzip) foamDictionary -entry writeCompression -set on "$WORK/cavity_$form/system/controlDict" > /dev/null ;;
            esac
            [ $form = ascii ] || (cd "$WORK/cavity_$form" && log foamFormatConvert -constant && log foamFormatConvert -time 0.25,0.5)
            mkdir -p "$OUT/cases/cavity_$form/constant"
            cp -r "$WORK/cavity_$form/constant/polyMesh" "$OUT/cases/cavity_$form/constant/"
            cp -r "$WORK/cavity_$form/0.25" "$WORK/cavity_$form/0.5" "$OUT/cases/cavity_$form/"
            rm -f "$OUT/cases/cavity_$form/constant/polyMesh/boundary"*
            touch "$OUT/cases/cavity_$form/cavity.foam"
        done
        echo "cavity: $n cells, $np points" ;;
    *) echo "make_cases.sh: unknown case '$c' (wind, wind_full, igloo, flange, cavity)" >&2; exit 2 ;;
    esac
done
