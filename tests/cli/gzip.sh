#!/usr/bin/env bash
# Gzip-compressed inputs: real files of each format whose row says gzip, compressed by gzip(1), convert to
# the same mesh as the files themselves (and pass the 6xx checks); detection by the inner extension and,
# without one, by the inflated first bytes; formats without a memory reader, and broken .gz files, are
# refused by name.
source "$(dirname "$0")/common.sh" "$@"

same_mesh() { # a.json b.json what: the summaries agree on what was built
    "$PY" - "$1" "$2" "$3" <<'PYEOF' || fail "$3: the .gz gives another mesh"
import json, sys
a, b = (json.load(open(f)) for f in sys.argv[1:3])
for k in ("source_cells", "tets", "vertices", "shell_faces", "fields", "cells_split"):
    assert a[k] == b[k], (sys.argv[3], k, a[k], b[k])
PYEOF
}

for f in sfepy/cube_medium_tetra.mesh sfepy/cylinder.vtk gmsh/t5_small_tet_ascii22.msh gmsh/t3_hex_prism_ascii41.msh \
         nasa_refine/om6_om6-curv-no-geom.meshb nasa_refine/cube_polar1.ugrid; do
    name=$(basename "$f")
    gzip -c "$DATA/$f" > "$WORK/$name.gz"
    convert_checked "$DATA/$f" "$WORK/plain.tpk" --json > "$WORK/plain.json"
    convert_checked "$WORK/$name.gz" "$WORK/gz.tpk" --json > "$WORK/gz.json"
    same_mesh "$WORK/plain.json" "$WORK/gz.json" "$name.gz"
done
# meshio's .vtu (binary, zlib inside) gzipped again; and one with no inner extension, told by its bytes.
"$PY" -c "import meshio; meshio.read('$DATA/sfepy/cube_medium_hexa.mesh').write('$WORK/h.vtu')"
gzip -c "$WORK/h.vtu" > "$WORK/h.vtu.gz"
gzip -c "$WORK/h.vtu" > "$WORK/h_vtu.gz"
convert_checked "$WORK/h.vtu" "$WORK/plain.tpk" --json > "$WORK/plain.json"
for gz in h.vtu.gz h_vtu.gz; do
    convert_checked "$WORK/$gz" "$WORK/gz.tpk" --json > "$WORK/gz.json"
    same_mesh "$WORK/plain.json" "$WORK/gz.json" "$gz"
done

# Refusals: a format read from files only, a broken stream, a parse error placed in the inflated text.
cp "$DATA/seacas/8-block.g" "$WORK/m.exo"
gzip "$WORK/m.exo"
expect_exit 2 "$TPK" convert "$WORK/m.exo.gz" "$WORK/x.tpk"
expect_stderr "m.exo.gz: exodus input is not read compressed"
head -c 300 "$WORK/cube_medium_tetra.mesh.gz" > "$WORK/cut.mesh.gz"
expect_exit 2 "$TPK" convert "$WORK/cut.mesh.gz" "$WORK/x.tpk"
expect_stderr "cut.mesh.gz: byte 300 of the compressed data: cannot inflate: the data ends early"
printf 'MeshVersionFormatted 2\nDimension 3\nVertices\n1\n0 0 zero 0\n' | gzip > "$WORK/bad.mesh.gz"
expect_exit 2 "$TPK" convert "$WORK/bad.mesh.gz" "$WORK/x.tpk"
expect_stderr "bad.mesh.gz:5: expected a vertex coordinate, found 'zero'"
[ ! -e "$WORK/x.tpk" ] || fail "output left behind"
echo "1 passed, 0 failed"
