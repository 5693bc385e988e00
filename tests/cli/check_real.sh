#!/usr/bin/env bash
# tetpack check on real meshes: clean files report no error or warning (and exit 0), the broken ones in
# hard/ are caught with the counts their makers documented (MANIFEST.md), and the CLI contract holds.
source "$(dirname "$0")/common.sh"

# clean NAME: exit 0 and no finding of severity error or warning.
clean() {
    local f=$DATA/$1
    shift
    expect_exit 0 "$TPK" check "$f" --json --no-progress "$@"
    $PY - "$WORK/out" "$f" <<'PY' || fail "$f is reported as broken"
import json, sys
r = json.load(open(sys.argv[1]))
bad = [x for x in r["findings"] if x["severity"] in ("error", "warning")]
for x in bad:
    print("  %d %s %d %s" % (x["id"], x["name"], x["count"], x["examples"][:1]), file=sys.stderr)
sys.exit(1 if bad else 0)
PY
}

for f in sfepy/cylinder.vtk sfepy/piezo_mesh_micro.vtk sfepy/acoustic_wg.vtk \
         sfepy/cube_big_tetra.mesh sfepy/cube_cylinder.mesh sfepy/cube_medium_hexa.mesh \
         sfepy/cube_medium_tetra.mesh sfepy/elbow.mesh sfepy/acoustics_mesh3d.mesh \
         tetgen/hinge_small.node tetgen/part1_small.node gmsh/t5_small_tet_ascii22.msh \
         gmsh/t5_small_tet_bin.vtk gmsh/t3_hex_prism_ascii41.msh nasa_refine/cube_polar1.ugrid \
         nasa_refine/cube_cylinder_ega.ugrid nasa_refine/cube-sphere_cube-sphere.meshb \
         nasa_refine/om6_om6-curv-no-geom.meshb seacas/8-block.g seacas/cube.g \
         seacas/two-block.g hard/huge_offset_hex.vtu; do
    clean "$f"
done

# findings EXIT FILE NAME=COUNT...: exit status and exact counts of the named findings.
findings() {
    local want=$1 f=$DATA/$2
    shift 2
    expect_exit "$want" "$TPK" check "$f" --json --no-progress --max-examples 2
    $PY - "$WORK/out" "$f" "$@" <<'PY' || fail "$f: unexpected findings"
import json, sys
r = json.load(open(sys.argv[1]))
found = {x["name"]: x["count"] for x in r["findings"]}
ok = True
for spec in sys.argv[3:]:
    name, count = spec.split("=")
    if found.get(name, 0) != int(count):
        print("  %s: %d, expected %s" % (name, found.get(name, 0), count), file=sys.stderr)
        ok = False
sys.exit(0 if ok else 1)
PY
}

# exomerge's unit-test file: five blocks of different resolution that share no nodes (43 exact duplicates,
# 101 more within 1e-16 of another node), touching along faces that do not match (105 boundary faces
# against other cells' faces, 1667 crossing shell face pairs); its element variables are NaN on the
# blocks where they are undefined.
findings 1 seacas/exomerge_unit_test.e duplicate_vertex=43 near_duplicate_vertex=101 nonfinite_field_value=133000 \
    nonconforming_face=105 shell_self_intersection=1667
# With --tol 0 only the exact duplicates remain.
expect_exit 1 "$TPK" check "$DATA/seacas/exomerge_unit_test.e" --tol 0 --json --no-progress
grep -q '"near_duplicate_vertex"' "$WORK/out" && fail "--tol 0 still reports near duplicates"
# Two blocks in contact with unmerged nodes.
findings 1 seacas/block_crush_1.ex2 nonconforming_face=33 shell_self_intersection=64
# sfepy's fibre slab: 97 of its hexahedra list their nodes in the mirrored order (all 8 corner Jacobians
# negative, checked apart with numpy), which also shows as faces traversed the same way by two cells.
findings 1 sfepy/matrix_fiber_rand.vtk inverted_cell=97 inconsistent_orientation=32 shell_orientation=68
# The derived broken files (MANIFEST.md): 135 inverted tets; 20 tets with a repeated node and 20 "flat"
# ones that are not exactly flat (9 of them land just below their plane, inverted); 250 hexahedra split
# 1 -> 8 (100 coarse faces against 400 fine ones; their 121 shared corners are non-manifold on the shell);
# three cubes, one touching at a vertex, one along an edge (6 mesh edges); two copies of a genus-5 part
# and 5 unused nodes.
findings 1 hard/inverted_tets.vtk inverted_cell=135 zero_volume_cell=0
findings 1 hard/degenerate_tets.vtk repeated_vertex=20 zero_volume_cell=0 inverted_cell=9 sliver_tet=20
findings 1 hard/hanging_nodes_hex.vtk nonconforming_face=500 nonmanifold_vertex=121 components=2
findings 1 hard/nonmanifold_vertex_edge_tets.vtu nonmanifold_edge=6 nonmanifold_vertex=1 components=3
findings 0 hard/two_components_orphans.node components=2 unused_vertex=5

# The CLI contract.
expect_exit 0 "$TPK" check --list
grep -q "inverted_cell" "$WORK/out" || fail "--list lacks inverted_cell"
expect_exit 0 "$TPK" check --help
expect_exit 2 "$TPK" check
expect_exit 2 "$TPK" check "$DATA/sfepy/cylinder.vtk" --bogus
expect_stderr "unknown option"
expect_exit 2 "$TPK" check "$WORK/missing.vtk"
expect_stderr "missing.vtk"
expect_exit 2 "$TPK" check "$DATA/sfepy/cylinder.vtk" --tol -1
printf '# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 2 float\n0 0\n' > "$WORK/cut.vtk"
expect_exit 2 "$TPK" check "$WORK/cut.vtk"
expect_stderr "cut.vtk"
echo "check_real: ok"
