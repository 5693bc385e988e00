#!/usr/bin/env bash
# tetpack-mpi convert on real decomposed inputs (a real mesh cut into .pvtu pieces by make_pvtu.py, as a
# solver writes one piece per rank; an OpenFOAM case decomposed by decomposePar; an Exodus mesh cut into
# files per processor by make_exodus_pieces), under mpirun -np 2 and -np 4 (oversubscribed): the part set holds
# the tets and the outer shell of the single-process conversion of the whole mesh, every cut face is
# linked both ways (check 614 and 600..613 clean), and it renders the same picture.
# $1 tetpack, $2 data dir, $3 source dir, $4 tetpack-mpi, $5 make_exodus_pieces.
source "$(dirname "$0")/../cli/common.sh" "$1" "$2" "$3"
MPI_TPK=$4
MAKE_EXO=$5
# Root in containers and CI; --oversubscribe: 4 ranks on a 2-core machine. One thread per rank.
mpi() { local n=$1; shift; mpirun --allow-run-as-root --oversubscribe -np "$n" "$MPI_TPK" "$@"; }

same_as_whole() { # name input ranks pieces [--global-ids]
    local name=$1 input=$2 ranks=$3 pieces=$4
    shift 4
    mkdir -p "$WORK/$name"
    "$PY" "$SRC/tests/mpi/make_pvtu.py" "$input" "$WORK/$name/in.pvtu" "$pieces" "$@"
    set_is_whole "$name" "$input" "$WORK/$name/in.pvtu" "$ranks"
}

# Exodus files per processor (nem_slice's naming, node and element number maps) cut from a real
# multi-block mesh by make_exodus_pieces; INPUT given as the base name mesh.e (the undecomposed file beside
# its pieces, as decomposers leave it) or as one of the pieces.
exodus_same_as_whole() { # name input ranks pieces [piece to name]
    local name=$1 input=$2 ranks=$3 pieces=$4 dir="$WORK/$1"
    mkdir -p "$dir"
    cp "$input" "$dir/mesh.e"
    "$MAKE_EXO" "$dir/mesh.e" "$dir/mesh.e" "$pieces" || fail "$name: make_exodus_pieces failed"
    set_is_whole "$name" "$dir/mesh.e" "$dir/${5:-mesh.e}" "$ranks"
    # The element number maps give each tet the whole file's source cell (TMAP), as in its conversion.
    "$PY" - "$dir/whole.tpk.vtu" "$dir"/set-*.tpk.vtu <<'PYEOF' || fail "$name: source cells differ from the whole's"
import sys, meshio
def cells(paths):
    out = {}
    for path in paths:
        m = meshio.read(path)
        for block, src in zip(m.cells, m.cell_data["source_cell"]):
            for t, c in zip(block.data, src):
                out[tuple(sorted(tuple(m.points[i]) for i in t))] = int(c)
    return out
whole, parts = cells(sys.argv[1:2]), cells(sys.argv[2:])
assert len(whole) == len(parts) and whole == parts, [k for k in whole if whole[k] != parts.get(k)][:3]
PYEOF
}

set_is_whole() { # name whole-input set-input ranks
    local name=$1 input=$2 set_input=$3 ranks=$4 dir="$WORK/$1"
    convert_checked "$input" "$dir/whole.tpk" > /dev/null
    mpi "$ranks" convert "$set_input" "$dir/set.tpkset" --threads 1 --json > "$dir/report.json" ||
        fail "$name: tetpack-mpi failed"
    local files=("$dir"/set-*.tpk)
    [ "${#files[@]}" -eq "$ranks" ] || fail "$name: expected $ranks parts, found ${#files[@]}"
    for f in "${files[@]}"; do check_6xx "$f"; done
    expect_exit 0 "$TPK" check "$dir/set.tpkset"
    "$TPK" info "$dir/set.tpkset" --json > "$dir/info.json"
    "$TPK" info "$dir/whole.tpk" --json > "$dir/whole.json"
    "$PY" - "$dir/info.json" "$dir/whole.json" "$dir/report.json" "$ranks" <<'PYEOF' || fail "$name: totals"
import json, sys
s, w, rep = (json.load(open(p)) for p in sys.argv[1:4])
n = int(sys.argv[4])
assert s["part_count"] == n and s["tets"] == w["tets"] and s["shell_faces"] == w["shell_faces"], (s, w)
assert s["cut_faces"] > 0 and len(rep["ranks"]) == n, rep
assert sum(r["tets"] for r in rep["ranks"]) == w["tets"]
assert all(r["exchanged_bytes"] > 0 and r["peak_rss_bytes"] > 0 for r in rep["ranks"]), rep
PYEOF
    keys "$dir/whole.keys" "$dir/whole.tpk"
    keys "$dir/set.keys" "${files[@]}"
    cmp -s "$dir/whole.keys" "$dir/set.keys" ||
        fail "$name: not the tets and outer shell of the whole ($(head -1 "$dir/set.keys") vs $(head -1 "$dir/whole.keys"))"
    "$TPK" render "$dir/whole.tpk" -o "$dir/whole.png" --size 160x120 > /dev/null
    "$TPK" render "$dir/set.tpkset" -o "$dir/set.png" --size 160x120 > /dev/null
    cmp -s "$dir/whole.png" "$dir/set.png" || fail "$name: the part set renders a different picture"
    if "$TPK" info "${files[0]}" | grep -q GlobalPointIds; then fail "$name: GlobalPointIds kept as a field"; fi
}

# Tets, boundary points shared by exact coordinates only.
same_as_whole cylinder_np2 "$SRC/samples/cylinder.vtk" 2 4
same_as_whole cylinder_np4 "$SRC/samples/cylinder.vtk" 4 7
# Hexahedra with the decomposer's GlobalPointIds: quads split through the same smallest id as the whole.
same_as_whole acoustic_np4 "$DATA/sfepy/acoustic_wg.vtk" 4 6 --global-ids
same_as_whole tetra_np2 "$DATA/sfepy/cube_medium_tetra.mesh" 2 3 --no-point-data

# Exodus: 64 hexahedra in 8 blocks (every piece holds empty blocks), 12 nodal and 9 element variables over 11
# steps; vertex identity from the node number maps, so quads split as in the whole file.
exodus_same_as_whole exo_np2 "$DATA/seacas/8-block.g" 2 2
exodus_same_as_whole exo_np4 "$DATA/seacas/8-block.g" 4 4 mesh.e.4.2
exodus_same_as_whole exo_np2_of4 "$DATA/seacas/8-block.g" 2 4 mesh.e.4.0
grep -q '"format":"exodus","pieces":4' "$WORK/exo_np4/set.tpkset" || fail "exo_np4: the manifest does not name the Exodus pieces"

# OpenFOAM: blockMesh's prisms and hexahedra (tests/cli/openfoam_prisms/, read as polyhedra), decomposed by
# decomposePar into processor0..3; the point ids come from each processor's pointProcAddressing.
export WM_PROJECT_DIR=${WM_PROJECT_DIR:-/usr/share/openfoam}
foam="$WORK/foam"
cp -r "$SRC/tests/cli/openfoam_prisms" "$foam"
mkdir -p "$foam/constant"
cat > "$foam/system/decomposeParDict" <<'FOAM'
FoamFile { version 2.0; format ascii; class dictionary; object decomposeParDict; }
numberOfSubdomains 4;
method simple;
simpleCoeffs { n (2 2 1); delta 0.001; }
FOAM
(cd "$foam" && blockMesh > log.blockMesh 2>&1 && decomposePar -force > log.decomposePar 2>&1) ||
    { tail "$foam/log."*; fail "OpenFOAM failed"; }
convert_checked "$foam" "$WORK/foam_whole.tpk" > /dev/null
keys "$WORK/foam_whole.keys" "$WORK/foam_whole.tpk"
"$TPK" render "$WORK/foam_whole.tpk" -o "$WORK/foam_whole.png" --size 160x120 > /dev/null
for ranks in 2 4; do
    mpi "$ranks" convert "$foam" "$WORK/foam$ranks.tpkset" --threads 1 --quiet || fail "foam, $ranks ranks: failed"
    expect_exit 0 "$TPK" check "$WORK/foam$ranks.tpkset"
    keys "$WORK/foam$ranks.keys" "$WORK"/foam$ranks-*.tpk
    cmp -s "$WORK/foam_whole.keys" "$WORK/foam$ranks.keys" || fail "foam, $ranks ranks: not the tets of the whole case"
    "$TPK" render "$WORK/foam$ranks.tpkset" -o "$WORK/foam$ranks.png" --size 160x120 > /dev/null
    cmp -s "$WORK/foam_whole.png" "$WORK/foam$ranks.png" || fail "foam, $ranks ranks: a different picture"
done

# Hexahedra without global ids: ids follow space, so quads may split along the other diagonal than in the
# single file; the set is still sound, its links answered, and it holds as many tets.
dir="$WORK/hex_coords"
mkdir -p "$dir"
"$PY" "$SRC/tests/mpi/make_pvtu.py" "$DATA/sfepy/cube_medium_hexa.mesh" "$dir/in.pvtu" 4
mpi 4 convert "$dir/in.pvtu" "$dir/set.tpkset" --threads 1 --quiet || fail "hex_coords: tetpack-mpi failed"
expect_exit 0 "$TPK" check "$dir/set.tpkset"

# Unusable input: every rank stops, exit 2, the reason on stderr.
expect_exit 2 mpi 4 convert "$WORK/tetra_np2/in.pvtu" "$WORK/x.tpkset"
expect_stderr "each rank needs at least one piece"
rm "$WORK/cylinder_np2/in_1.vtu"
expect_exit 2 mpi 2 convert "$WORK/cylinder_np2/in.pvtu" "$WORK/y.tpkset"
expect_stderr "in_1.vtu"
[ ! -e "$WORK/y.tpkset" ] || fail "a manifest was written for a failed conversion"
# Exodus: a missing piece is named; two processor counts beside one base name, or none, are refused.
rm "$WORK/exo_np4/mesh.e.4.2"
expect_exit 2 mpi 2 convert "$WORK/exo_np4/mesh.e.4.0" "$WORK/z.tpkset"
expect_stderr "exo_np4/mesh.e.4.2: missing: expected piece 2 of the 4 Exodus files"
expect_exit 2 mpi 2 convert "$WORK/exo_np4/mesh.e.4.2" "$WORK/z.tpkset"
expect_stderr "exo_np4/mesh.e.4.2: missing"
cp "$WORK/exo_np2/mesh.e.2.0" "$WORK/exo_np4/"
expect_exit 2 mpi 2 convert "$WORK/exo_np4/mesh.e" "$WORK/z.tpkset"
expect_stderr "found .*mesh.e.2.\* and .*mesh.e.4.\*"
expect_exit 2 mpi 2 convert "$WORK/cylinder_np4/in_0.vtu" "$WORK/z.tpkset"
expect_stderr "or Exodus files per processor"
[ ! -e "$WORK/z.tpkset" ] || fail "a manifest was written for a failed conversion"
# --max-error and --subdivide are refused by name (docs/ARCHITECTURE.md §10: not refined alike across ranks).
for opt in --max-error --subdivide; do
    expect_exit 2 mpi 2 convert "$WORK/cylinder_np4/in.pvtu" "$WORK/w.tpkset" $opt 1
    expect_stderr "$opt is not offered here"
    [ ! -e "$WORK/w.tpkset" ] || fail "a manifest was written for a refused $opt"
done
echo "tetpack-mpi: ok"
