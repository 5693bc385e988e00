# tetpack formats and the importer registry (issue 8): one table drives --format, detection, the help
# lists and the fuzz targets; every row is listed, as text and as JSON, and each name reads a real file.
source "$(dirname "$0")/common.sh"
BIN=$(dirname "$TPK")

"$TPK" formats > "$WORK/table"
"$TPK" formats --json > "$WORK/formats.json"
names=$("$PY" -c "import json; print(' '.join(f['name'] for f in json.load(open('$WORK/formats.json'))['formats']))")
for want in vtk vtu pvd gmsh tetgen medit meshb ugrid inp dolfin exodus stl off ply csv surface points; do
    case " $names " in *" $want "*) ;; *) fail "formats --json lacks $want (has: $names)" ;; esac
    grep -q "^$want " "$WORK/table" || fail "the formats table lacks $want"
done
# Every format with a memory reader has its fuzz target built and a seed corpus; the others have none.
"$PY" - "$WORK/formats.json" "$BIN/tests/fuzz" "$SRC/tests/fuzz/corpus" <<'PYEOF'
import json, os, sys
rows = json.load(open(sys.argv[1]))["formats"]
fuzzed = [r for r in rows if r["fuzz_target"]]
assert len(fuzzed) >= 10, fuzzed
for r in fuzzed:
    t = r["fuzz_target"]
    assert t == "fuzz_" + r["name"], r
    assert os.path.isfile(os.path.join(sys.argv[2], t + "_replay")), "not built: " + t
    assert os.listdir(os.path.join(sys.argv[3], t)), "no seeds: " + t
for r in rows:
    assert r["extensions"] or r["reader"] == "tetgen", r
    assert set(r["supports"]) <= {"tets", "hexahedra", "wedges", "pyramids", "voxels", "polyhedra", "surface",
                                  "point-cloud", "point-fields", "cell-fields", "time-steps", "gzip"}, r
    # FILE.gz goes to the memory reader: only rows that have one (TetGen's needs two files) say gzip.
    if "gzip" in r["supports"]:
        assert r["fuzz_target"] and r["reader"] == "file" and r["name"] != "tetgen", r
assert {r["name"] for r in rows if "gzip" in r["supports"]} >= {"vtk", "vtu", "gmsh", "medit", "inp"}, rows
PYEOF

# The list of inputs in docs/USAGE.md names every extension of the registry (prose, kept by hand).
"$PY" - "$WORK/formats.json" "$SRC/docs/USAGE.md" <<'PYEOF'
import json, sys
usage = open(sys.argv[2]).read().lower()
missing = [e for r in json.load(open(sys.argv[1]))["formats"] for e in r["extensions"] if e.lower() not in usage]
assert not missing, "docs/USAGE.md does not name " + ", ".join(missing)
PYEOF

# The help of convert and check lists the same rows.
for cmd in convert check; do
    "$TPK" $cmd --help > "$WORK/help"
    for n in $names; do grep -q "^  $n[ |]" "$WORK/help" || fail "$cmd --help lacks the format $n"; done
done

# A forced name reads a file whose extension says nothing; an alias works; an unknown name lists the names.
# (Files converted by different command lines differ in META's command line: compare their VTU exports.)
same() { # same A.tpk B.tpk what
    "$TPK" export "$1" --vtu "$1.vtu" >/dev/null
    "$TPK" export "$2" --vtu "$2.vtu" >/dev/null
    cmp -s "$1.vtu" "$2.vtu" || fail "$3"
}
cp "$DATA/sfepy/cylinder.vtk" "$WORK/cylinder.dat"
convert_checked "$WORK/cylinder.dat" "$WORK/a.tpk" --format vtk --quiet
convert_checked "$WORK/cylinder.dat" "$WORK/b.tpk" --format vtk-legacy --quiet
same "$WORK/a.tpk" "$WORK/b.tpk" "--format vtk-legacy differs from --format vtk"
convert_checked "$DATA/nasa_refine/om6_om6-curv-no-geom.meshb" "$WORK/m.tpk" --format medit --quiet
convert_checked "$DATA/nasa_refine/om6_om6-curv-no-geom.meshb" "$WORK/n.tpk" --format meshb --quiet
same "$WORK/m.tpk" "$WORK/n.tpk" "--format medit on a .meshb differs from --format meshb"
expect_exit 2 "$TPK" convert "$WORK/cylinder.dat" "$WORK/c.tpk" --format obj
# The list follows the registry's order; optional rows (cgns: TETPACK_WITH_CGNS) may sit between.
expect_stderr "unknown input format 'obj'; supported: vtk, tetgen, dolfin, vtu, pvd, gmsh, medit, ugrid, exodus, "
expect_stderr ", stl, off, ply, csv, surface, points"
# CGNS: its HDF5 signature is Exodus's too, so the extension must pick its row, which reads the file
# when built (the row then carries cells) and says why not otherwise.
grep -q "^cgns " "$WORK/table" || fail "the formats table lacks cgns"
if grep "^cgns " "$WORK/table" | grep -q " tets "; then
    convert_checked "$DATA/seacas/generated.cgns" "$WORK/g.tpk" --quiet
else
    expect_exit 2 "$TPK" convert "$DATA/seacas/generated.cgns" "$WORK/g.tpk"
    expect_stderr "built without CGNS (TETPACK_WITH_CGNS=OFF)"
fi
# Detection by content when the extension says nothing: VTK legacy and Gmsh by their first bytes.
convert_checked "$WORK/cylinder.dat" "$WORK/d.tpk" --quiet
same "$WORK/a.tpk" "$WORK/d.tpk" "content detection of VTK legacy"
cp "$DATA/gmsh/t5_small_tet_ascii22.msh" "$WORK/t5.txt"
convert_checked "$WORK/t5.txt" "$WORK/g.tpk" --json > "$WORK/g.json"
"$PY" -c "import json; d=json.load(open('$WORK/g.json')); assert d['tets']==13391, d"
expect_exit 2 "$TPK" formats --bogus
expect_stderr "unknown option '--bogus'"
echo "formats: ok"
