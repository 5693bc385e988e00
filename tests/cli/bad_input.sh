# Bad input: exit code 2, a message naming the file and what is wrong, and no output left behind.
source "$(dirname "$0")/common.sh"

expect_exit 2 "$TPK" convert "$WORK/missing.vtk" "$WORK/o.tpk"
expect_stderr "missing.vtk"
[ ! -e "$WORK/o.tpk" ] || fail "output left behind"

printf '# vtk DataFile Version 2.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n0 0 0\n1 0 0\n' > "$WORK/trunc.vtk"
expect_exit 2 "$TPK" convert "$WORK/trunc.vtk" "$WORK/o.tpk"
expect_stderr "trunc.vtk"
[ -z "$(ls "$WORK" | grep -v -e '^trunc.vtk$' -e '^missing' -e '^out$' -e '^err$')" ] || { ls "$WORK"; fail "stray files"; }

# Positions are stored as finite float32 offsets from one origin (spec TPK-M11): a coordinate that is not
# finite, or points spanning more than float32 can hold, are refused by name (the fault suite found both
# written into files that break M11).
for bad in "nan 0 0" "1e300 0 0"; do
    printf '# vtk DataFile Version 2.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n0 0 0\n%s\n0 1 0\n-1e300 0 1\n' \
        "$bad" > "$WORK/nonfinite.vtk"
    printf 'CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n' >> "$WORK/nonfinite.vtk"
    expect_exit 2 "$TPK" convert "$WORK/nonfinite.vtk" "$WORK/n.tpk"
    expect_stderr "nonfinite.vtk: "
    case $bad in
        nan*) expect_stderr "point 1 is (nan, 0, 0): coordinates must be finite numbers" ;;
        *) expect_stderr "more than float32 positions around one origin can hold" ;;
    esac
    [ ! -e "$WORK/n.tpk" ] || fail "output left behind"
done

# Degenerate tets are refused with a message naming one and pointing at --drop-degenerate ...
expect_exit 2 "$TPK" convert "$DATA/hard/degenerate_tets.vtk" "$WORK/d.tpk"
expect_stderr "drop-degenerate"
[ ! -e "$WORK/d.tpk" ] || fail "output left behind"
# ... and dropped (and counted) with it. MANIFEST.md says 20 tets there repeat a node and 20 are "flat",
# but the flat ones were made by moving a node onto a plane in floating point: decided exactly, none of
# them has zero volume (checked with rational arithmetic, in float64 and in the stored float32 frame),
# so exactly 20 are dropped, and 10 of the slivers are negatively oriented in the stored frame: those are
# refused too until --reorient turns them over (nothing is fixed unasked; tests/cli/repair.sh).
expect_exit 2 "$TPK" convert "$DATA/hard/degenerate_tets.vtk" "$WORK/d.tpk" --drop-degenerate
expect_stderr "10 of 8161 tets are inverted; --reorient turns them over"
[ ! -e "$WORK/d.tpk" ] || fail "output left behind"
"$TPK" convert "$DATA/hard/degenerate_tets.vtk" "$WORK/d.tpk" --drop-degenerate --reorient --json > "$WORK/d.json"
"$PY" -c "import json; d=json.load(open('$WORK/d.json')); assert d['degenerate_dropped']==20 and d['tets']==8161-20 and d['inverted_fixed']==10, d"
# Inverted tets are refused, or turned over and counted with --reorient.
expect_exit 2 "$TPK" convert "$DATA/hard/inverted_tets.vtk" "$WORK/i.tpk"
expect_stderr "135 of 1348 tets are inverted; --reorient turns them over"
"$TPK" convert "$DATA/hard/inverted_tets.vtk" "$WORK/i.tpk" --reorient --json > "$WORK/i.json"
"$PY" -c "import json; d=json.load(open('$WORK/i.json')); assert d['inverted_fixed']==135, d"

# A damaged .tpk: info and render refuse it with exit 2.
"$TPK" convert "$SRC/samples/cylinder.vtk" "$WORK/c.tpk" --quiet
cp "$WORK/c.tpk" "$WORK/flip.tpk"
size=$(stat -c %s "$WORK/flip.tpk")
printf '\xff' | dd of="$WORK/flip.tpk" bs=1 seek=$((size / 2)) conv=notrunc status=none
expect_exit 2 "$TPK" info "$WORK/flip.tpk"
expect_stderr "error: $WORK/flip.tpk: chunk "
# A zstd error names the file too (issue 10).
expect_exit 2 "$TPK" info "$SRC/samples/vectors/zstd_skippable_frame.tpk"
expect_stderr "zstd_skippable_frame.tpk: chunk 0 'POS3' at offset 192: a zstd frame of"
# export names the damaged input, not the output it was asked to write (issue 10), and writes nothing.
expect_exit 2 "$TPK" export "$WORK/flip.tpk" --vtu "$WORK/flip.vtu"
expect_stderr "error: $WORK/flip.tpk: chunk "
! grep -q "flip.vtu" "$WORK/err" || { cat "$WORK/err" >&2; fail "export blames its output for a damaged input"; }
[ ! -e "$WORK/flip.vtu" ] || fail "export left an output behind"
expect_exit 2 "$TPK" render "$WORK/flip.tpk" -o "$WORK/flip.png"
[ ! -e "$WORK/flip.png" ] || fail "image left behind"
head -c 100 "$WORK/c.tpk" > "$WORK/short.tpk"
expect_exit 2 "$TPK" info "$WORK/short.tpk"
expect_stderr "short.tpk"

# Fields: unknown at convert time (the message lists what there is); render needs a point field.
expect_exit 2 "$TPK" convert "$SRC/samples/cylinder.vtk" "$WORK/f.tpk" --field nosuch
expect_stderr "available fields: mat_id (cell), temperature (point)"
"$TPK" convert "$SRC/samples/cylinder.vtk" "$WORK/m.tpk" --field mat_id --quiet
expect_exit 2 "$TPK" render "$WORK/m.tpk" -o "$WORK/m.png" --field mat_id
expect_stderr "per-tet field 'mat_id'; render needs a per-point field (this file has no point field)"
expect_exit 2 "$TPK" render "$WORK/c.tpk" -o "$WORK/m.png" --field nope
expect_stderr "point fields: temperature"
expect_exit 2 "$TPK" render "$WORK/c.tpk" -o "$WORK/m.png" --step 3
[ ! -e "$WORK/m.png" ] || fail "image left behind"
# A twisted hexahedron (sfepy's cross3d.mesh, cell 2) cannot be split without a new point: it gets one at
# its centre. A bow-tie hexahedron (top face turned half a turn) cannot be split even so: refused by
# name, or left out and counted with --skip-bad-cells. A non-tpk file is refused by its magic.
"$TPK" convert "$DATA/sfepy/cross3d.mesh" "$WORK/x.tpk" --json > "$WORK/x.json"
"$PY" -c "import json; d=json.load(open('$WORK/x.json')); assert d['steiner_cells']==1 and d['tets']==48 and d['vertices']==33, d"
printf '# vtk DataFile Version 2.0\nbow-tie\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 16 double\n' > "$WORK/bow.vtk"
printf '0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n' >> "$WORK/bow.vtk"
printf '3 0 0\n4 0 0\n4 1 0\n3 1 0\n3 0 1\n4 0 1\n4 1 1\n3 1 1\n' >> "$WORK/bow.vtk"
printf 'CELLS 2 18\n8 0 1 2 3 4 5 6 7\n8 8 9 10 11 14 15 12 13\nCELL_TYPES 2\n12\n12\n' >> "$WORK/bow.vtk"
expect_exit 2 "$TPK" convert "$WORK/bow.vtk" "$WORK/h.tpk"
expect_stderr "cell 1 (a hexahedron) is too warped, non-convex or degenerate to split"
[ ! -e "$WORK/h.tpk" ] || fail "output left behind"
"$TPK" convert "$WORK/bow.vtk" "$WORK/h.tpk" --skip-bad-cells --json > "$WORK/h.json"
"$PY" -c "import json; d=json.load(open('$WORK/h.json')); assert d['bad_cells_skipped']==1 and d['tets'] in (5, 6), d"
expect_exit 2 "$TPK" info "$DATA/sfepy/cylinder.vtk"
expect_stderr "not a tetpack file"

# Usage errors.
expect_exit 2 "$TPK" convert
expect_exit 2 "$TPK" convert a b --layout tet99
expect_exit 2 "$TPK" render "$WORK/c.tpk" -o "$WORK/x.png" --size 0x5
expect_exit 2 "$TPK" nosuchcommand
expect_exit 0 "$TPK" convert --help
echo "1 passed, 0 failed"
# What convert refuses as unusable, check does not call clean (issue 10): no cells at all, only a cell of
# VTK type 0, a polyhedron whose points coincide. Exit 1 and the check id on stdout.
printf '# vtk DataFile Version 2.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 0 double\nCELLS 0 0\nCELL_TYPES 0\n' > "$WORK/empty.vtk"
printf '# vtk DataFile Version 2.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n0 0 0\n1 0 0\n0 1 0\n0 0 1\nCELLS 1 1\n0\nCELL_TYPES 1\n0\n' > "$WORK/type0.vtk"
printf '# vtk DataFile Version 2.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n1 1 1\n1 1 1\n1 1 1\n1 1 1\nCELLS 1 18\n17 4 3 0 1 2 3 0 1 3 3 0 2 3 3 1 2 3\nCELL_TYPES 1\n42\n' > "$WORK/flatpoly.vtk"
for unusable in empty:214 type0:214 flatpoly:215; do
    name=${unusable%%:*} id=${unusable##*:}
    expect_exit 2 "$TPK" convert "$WORK/$name.vtk" "$WORK/$name.tpk"
    expect_exit 1 "$TPK" check "$WORK/$name.vtk"
    grep -q "^  $id error" "$WORK/out" || fail "check $name.vtk: no $id: $(cat "$WORK/out")"
done
