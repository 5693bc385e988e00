# Same input and options give byte-identical files, whatever the output name and thread count: every
# importer's real sample (and the forms a reader has several paths for: VTK ASCII and binary, old and 5.1
# cells; VTU raw, zlib, appended) converted at 1, 2 and 3 threads, and --levels, --zstd and --max-error
# likewise.
source "$(dirname "$0")/common.sh"
passed=0
# same_threads NAME INPUT [options]: converted at 1, 2 and 3 threads (the first checked against the
# spec's MUSTs), the three files byte-identical
same_threads() {
    local name=$1 input=$2
    shift 2
    convert_checked "$input" "$WORK/$name-1.tpk" --threads 1 --quiet "$@"
    for threads in 2 3; do
        "$TPK" convert "$input" "$WORK/$name-$threads.tpk" --threads $threads --quiet "$@"
        cmp "$WORK/$name-1.tpk" "$WORK/$name-$threads.tpk" || fail "$name: outputs of 1 and $threads threads differ"
    done
    rm -f "$WORK/$name"-[123].tpk
    passed=$((passed + 1))
}
convert_checked "$DATA/sfepy/piezo_mesh_micro.vtk" "$WORK/a.tpk" --layout tet16 --layout tet32 --threads 1 --quiet
convert_checked "$DATA/sfepy/piezo_mesh_micro.vtk" "$WORK/b.tpk" --layout tet16 --layout tet32 --threads 2 --quiet
cmp "$WORK/a.tpk" "$WORK/b.tpk" || fail "outputs differ"
# With zstd chunks too (the records are built on worker threads, then compressed in pieces as they come):
# the bytes must not depend on how many threads.
convert_checked "$DATA/sfepy/piezo_mesh_micro.vtk" "$WORK/z1.tpk" --zstd 5 --layout tet16 --layout tet32 --threads 1 --quiet
for threads in 2 3 8; do
    convert_checked "$DATA/sfepy/piezo_mesh_micro.vtk" "$WORK/z$threads.tpk" --zstd 5 --layout tet16 --layout tet32 \
        --threads $threads --quiet
    cmp "$WORK/z1.tpk" "$WORK/z$threads.tpk" || fail "zstd outputs differ between 1 and $threads threads"
done
# Chunks over zstd's 8 MiB job (the 40-grid's TT32: 12 MB, TT16: 6 MB, in one file) are compressed by as
# many of zstd's workers as threads, into one frame each (check_6xx: rule 16): the same bytes at 1, 2 and
# 3 threads, and they decode to the chunks of the uncompressed file (each entry's checksum is over the raw
# bytes, and check_6xx checks it against the decoded ones).
"$PY" "$SRC/bench/make_grid_vtk.py" 40 "$WORK/g40.vtk" 2> /dev/null
"$TPK" convert "$WORK/g40.vtk" "$WORK/g40_raw.tpk" --layout tet32 --layout tet16 --quiet
same_threads zstd_jobs "$WORK/g40.vtk" --zstd 3 --layout tet32 --layout tet16
"$TPK" convert "$WORK/g40.vtk" "$WORK/g40_zstd.tpk" --zstd 3 --layout tet32 --layout tet16 --threads 2 --quiet
"$PY" - "$WORK/g40_raw.tpk" "$WORK/g40_zstd.tpk" <<'PYEOF'
import struct, sys
def entries(path):
    data = open(path, "rb").read()
    offset, count = struct.unpack_from("<QQ", data, 32)
    out = {}
    for i in range(count):
        e = data[offset + 64 * i: offset + 64 * (i + 1)]
        tag, codec, index, raw, checksum, step = e[:4], e[6], *struct.unpack_from("<I", e, 12), \
            *struct.unpack_from("<QQ", e, 40), *struct.unpack_from("<I", e, 56)
        out[(tag, index, step)] = (codec, raw, checksum)
    return out
raw, packed = entries(sys.argv[1]), entries(sys.argv[2])
assert raw.keys() == packed.keys(), (raw.keys(), packed.keys())
big = 0
for key, (codec, size, checksum) in raw.items():
    assert codec == 0 and packed[key][0] == 1, (key, codec, packed[key][0])
    if key[0] != b"META":  # it holds the command line
        assert packed[key][1:] == (size, checksum), (key, packed[key], size, checksum)
        big += size > 8 << 20
assert big >= 1, "no chunk over one zstd job"
PYEOF
rm -f "$WORK"/g40*.tpk

# Every importer's real sample.
same_threads vtk_ascii_hex "$DATA/sfepy/acoustic_wg.vtk" --cell-to-point
same_threads vtk_binary "$DATA/gmsh/t5_small_tet_bin.vtk" --layout tet20
same_threads vtk51_binary "$DATA/hard/degenerate_tets.vtk" --drop-degenerate --skip-bad-cells
same_threads vtk51_ascii_hex "$DATA/hard/hanging_nodes_hex.vtk"
same_threads vtu_raw "$DATA/hard/huge_offset_hex.vtu"
same_threads vtu_appended "$DATA/hard/nonmanifold_vertex_edge_tets.vtu"
same_threads gmsh41 "$DATA/gmsh/t3_hex_prism_ascii41.msh"
same_threads gmsh22 "$DATA/gmsh/t5_small_tet_ascii22.msh"
same_threads medit "$DATA/sfepy/cube_big_tetra.mesh" --zstd 3 --layout tet32
same_threads medit_hex "$DATA/sfepy/cube_medium_hexa.mesh"
same_threads meshb "$DATA/nasa_refine/cube-sphere_cube-sphere.meshb"
same_threads ugrid "$DATA/nasa_refine/cube_cylinder_ega.ugrid"
same_threads exodus "$DATA/seacas/exomerge_unit_test.e"
same_threads tetgen "$DATA/tetgen/hinge_small.node"
same_threads dolfin "$SRC/tests/cli/dolfin/unit_cube_hexes.xml"
same_threads openfoam "$SRC/tests/data/openfoam/cases/flange_binary/flange.foam"
same_threads openfoam_steps "$SRC/tests/data/openfoam/cases/cavity_binary/cavity.foam"
if "$TPK" formats | grep "^cgns " | grep -q " tets "; then
    same_threads cgns "$DATA/seacas/generated.cgns"
fi
# The formats no file in ../shared/data comes in, written by meshio from a real mesh: VTU with zlib
# blocks (base64), XDMF with HDF5 data, Abaqus .inp; a .pvd series of the VTU.
"$PY" - "$DATA" "$WORK" <<'PYEOF'
import sys
import meshio
data, work = sys.argv[1:]
m = meshio.read(data + "/gmsh/t3_hex_prism_ascii41.msh")
m = meshio.Mesh(m.points, [c for c in m.cells if c.type in ("hexahedron", "wedge", "tetra")])
meshio.write(work + "/zlib.vtu", m, binary=True, compression="zlib")
meshio.write(work + "/h5.xdmf", m)
meshio.write(work + "/mesh.inp", m)
with open(work + "/series.pvd", "w") as f:
    f.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n<Collection>\n'
            '<DataSet timestep="0" file="zlib.vtu"/>\n<DataSet timestep="1" file="zlib.vtu"/>\n'
            '</Collection>\n</VTKFile>\n')
PYEOF
same_threads vtu_zlib "$WORK/zlib.vtu"
same_threads xdmf "$WORK/h5.xdmf"
same_threads inp "$WORK/mesh.inp"
same_threads pvd "$WORK/series.pvd"
# VTKHDF as tetpack's own exporter writes it, where built with HDF5.
"$TPK" convert "$DATA/sfepy/cube_cylinder.mesh" "$WORK/cc.tpk" --quiet
if "$TPK" export "$WORK/cc.tpk" --vtkhdf "$WORK/cc.vtkhdf" > /dev/null 2>&1; then
    same_threads vtkhdf "$WORK/cc.vtkhdf"
fi
# VTK ASCII blocks large enough (64k numbers) to be read on all threads, in both cell forms, and with a
# bad number in each block, and the binary form with bad counts and ids: the same files, and the same
# message as the serial reader's, at any count.
"$PY" "$SRC/bench/make_grid_vtk.py" 30 "$WORK/g30.vtk" 2> /dev/null
"$PY" - "$WORK" <<'PYEOF'
import sys
import meshio
import numpy as np
work = sys.argv[1]
m = meshio.read(work + "/g30.vtk")
meshio.write(work + "/g30_51.vtk", m, binary=False)
pts, tets = m.points, m.cells[0].data
with open(work + "/g30_old.vtk", "w") as f:
    f.write("# vtk DataFile Version 3.0\nascii grid\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS %d double\n" % len(pts))
    np.savetxt(f, pts, fmt="%.17g")
    f.write("CELLS %d %d\n" % (len(tets), 5 * len(tets)))
    np.savetxt(f, np.hstack([np.full((len(tets), 1), 4), tets]), fmt="%d")
    f.write("CELL_TYPES %d\n" % len(tets))
    np.savetxt(f, np.full(len(tets), 10), fmt="%d")
# the binary grid's CELLS (old form, 5 numbers a cell) with a bad count or id, or both in either order
import struct
binary = open(work + "/g30.vtk", "rb").read()
at = binary.index(b"\n", binary.index(b"CELLS ")) + 1
for n, changes in enumerate([[(5000, 0, 3)], [(7000, 2, -1)], [(3000, 1, -7), (5000, 0, 5)],
                             [(3000, 0, 6), (5000, 3, -2)], [(100, 0, 100000000)], [(len(tets) - 1, 4, -1)]]):
    bad = bytearray(binary)
    for cell, k, value in changes:
        struct.pack_into(">i", bad, at + 4 * (5 * cell + k), value)
    open("%s/bad_binary_%d.vtk" % (work, n), "wb").write(bad)
for name in ("g30_old", "g30_51"):
    lines = open("%s/%s.vtk" % (work, name)).read().split("\n")
    for k, i in [(k, i) for i, l in enumerate(lines) for k in ("POINTS", "CELLS", "CONNECTIVITY", "OFFSETS", "CELL_TYPES")
                 if l.startswith(k)]:
        j = i + 1 if name == "g30_51" else i + 20000
        for n, bad in enumerate(("x1", "-5", "4294967296")):
            bad_lines = list(lines)
            toks = bad_lines[j].split(" ")
            toks[len(toks) // 2] = bad
            bad_lines[j] = " ".join(toks)
            open("%s/bad_%s_%s_%d.vtk" % (work, name, k, n), "w").write("\n".join(bad_lines))
PYEOF
same_threads vtk_ascii_old "$WORK/g30_old.vtk"
same_threads vtk_ascii_51 "$WORK/g30_51.vtk"
for bad in "$WORK"/bad_*.vtk; do
    expect_exit 2 "$TPK" convert "$bad" "$WORK/bad.tpk" --threads 1
    mv "$WORK/err" "$WORK/err1"
    expect_exit 2 "$TPK" convert "$bad" "$WORK/bad.tpk" --threads 3
    cmp -s "$WORK/err1" "$WORK/err" || fail "$(basename "$bad"): the messages of 1 and 3 threads differ"
done
# Gmsh 4.1 blocks large enough to be read on all threads (tpk_scan_numbers pieces in ASCII, records in
# binary): t5.geo meshed by gmsh (volume blocks only), saved ASCII and binary; the 30-grid written here in
# the layouts a reader has several paths for (surface elements first, so the element tags are listed;
# node tags 2, 4, 6, ..., so each node is looked up; two volume blocks with a gap between their tags),
# ASCII and binary; and bad forms, which must give the serial reader's message at any thread count.
if command -v gmsh > /dev/null; then
    gmsh "$DATA/gmsh/t5.geo" -3 -clscale 0.5 -format msh41 -o "$WORK/t5.msh" > /dev/null
    gmsh "$WORK/t5.msh" -0 -format msh41 -bin -o "$WORK/t5_bin.msh" > /dev/null
    same_threads gmsh41_t5_ascii "$WORK/t5.msh"
    same_threads gmsh41_t5_binary "$WORK/t5_bin.msh"
fi
"$PY" - "$WORK" <<'PYEOF'
import sys
import meshio
import numpy as np
work = sys.argv[1]
m = meshio.read(work + "/g30.vtk")
pts, tets = m.points, m.cells[0].data.astype(np.int64)

def write(name, binary, node_step=1, surfaces=False, gap=False, bad=None):
    """Gmsh 4.1: one node block (tags 1, 1 + step, ...), then elements: a triangle block first when
    surfaces, the tets in one block, or two with a gap of 1000 tags between them."""
    n = len(pts)
    node_tags = 1 + node_step * np.arange(n, dtype=np.int64)
    blocks, tag = [], 1
    if surfaces:
        tri = tets[:5000, :3]
        blocks.append((2, 1, 2, np.arange(tag, tag + len(tri)), tri))
        tag += len(tri)
    halves = [tets[: len(tets) // 2], tets[len(tets) // 2:]] if gap else [tets]
    for k, h in enumerate(halves):
        blocks.append((3, 1 + k, 4, np.arange(tag, tag + len(h)), h))
        tag += len(h) + (1000 if gap else 0)
    count = sum(len(b[3]) for b in blocks)
    max_tag = max(int(b[3][-1]) for b in blocks)
    with open(work + "/" + name, "wb") as f:
        w = f.write
        if binary:
            w(b"$MeshFormat\n4.1 1 8\n" + np.int32(1).tobytes() + b"\n$EndMeshFormat\n$Nodes\n")
            w(np.array([1, n, node_tags[0], node_tags[-1]], np.uint64).tobytes())
            w(np.array([3, 1, 0], np.int32).tobytes() + np.uint64(n).tobytes())
            w(node_tags.astype(np.uint64).tobytes() + pts.astype(np.float64).tobytes())
            w(b"\n$EndNodes\n$Elements\n")
            w(np.array([len(blocks), count, 1, max_tag], np.uint64).tobytes())
            for dim, ent, typ, tags, conn in blocks:
                w(np.array([dim, ent, typ], np.int32).tobytes() + np.uint64(len(tags)).tobytes())
                rows = np.hstack([tags[:, None], node_tags[conn]]).astype(np.uint64)
                if bad is not None and typ == 4:
                    rows[bad[0], bad[1]] = np.uint64(bad[2] % (1 << 64))
                w(rows.tobytes())
            w(b"\n$EndElements\n")
        else:
            w(b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n")
            w(b"1 %d %d %d\n3 1 0 %d\n" % (n, node_tags[0], node_tags[-1], n))
            np.savetxt(f, node_tags, fmt="%d")
            np.savetxt(f, pts, fmt="%.17g")
            w(b"$EndNodes\n$Elements\n%d %d 1 %d\n" % (len(blocks), count, max_tag))
            for dim, ent, typ, tags, conn in blocks:
                w(b"%d %d %d %d\n" % (dim, ent, typ, len(tags)))
                rows = np.hstack([tags[:, None], node_tags[conn]]).astype(object)
                if bad is not None and typ == 4:
                    rows[bad[0], bad[1]] = bad[2]
                np.savetxt(f, rows, fmt="%s")
            w(b"$EndElements\n")

for binary, kind in ((False, "ascii"), (True, "binary")):
    write("g30_%s.msh" % kind, binary)
    write("g30_%s_listed.msh" % kind, binary, node_step=2, surfaces=True)
    write("g30_%s_gap.msh" % kind, binary, gap=True)
    # a tet's node that $Nodes lacks, its tag 0, a node tag too large for int64 (binary) or not a number
    for n, bad in enumerate([(90000, 2, 10 ** 9), (120000, 0, 0), (150000, 4, -3)]):
        write("badmsh_%s_%d.msh" % (kind, n), binary, bad=bad)
    if not binary:
        write("badmsh_ascii_3.msh", False, bad=(100000, 1, "x7"))
        write("badmsh_ascii_4.msh", False, node_step=2, surfaces=True, bad=(70000, 3, 4))
PYEOF
for kind in ascii binary; do
    for form in "" _listed _gap; do
        same_threads "gmsh41_g30_$kind$form" "$WORK/g30_$kind$form.msh"
    done
done
for bad in "$WORK"/badmsh_*.msh; do
    expect_exit 2 "$TPK" convert "$bad" "$WORK/bad.tpk" --threads 1
    mv "$WORK/err" "$WORK/err1"
    expect_exit 2 "$TPK" convert "$bad" "$WORK/bad.tpk" --threads 3
    cmp -s "$WORK/err1" "$WORK/err" || fail "$(basename "$bad"): the messages of 1 and 3 threads differ"
done
# VTKHDF large enough for its cells to be converted on all threads (the 30-grid, 162,000 tets, as
# tetpack's exporter writes it), with a triangle among the tets (dropped, counted in the warning), and
# with a point id out of range or an unknown cell type in the middle: the same file, and the serial
# reader's message, at any thread count.
"$TPK" convert "$WORK/g30.vtk" "$WORK/g30.tpk" --quiet
if "$TPK" export "$WORK/g30.tpk" --vtkhdf "$WORK/g30.vtkhdf" > /dev/null 2>&1; then
    same_threads vtkhdf_g30 "$WORK/g30.vtkhdf"
    "$PY" - "$WORK" <<'PYEOF'
import shutil, sys
import h5py
work = sys.argv[1]
for n, (name, at, value) in enumerate([("Connectivity", 300001, 10 ** 7), ("Connectivity", 5, -1),
                                       ("Types", 100000, 99)]):
    shutil.copy(work + "/g30.vtkhdf", "%s/badhdf_%d.vtkhdf" % (work, n))
    with h5py.File("%s/badhdf_%d.vtkhdf" % (work, n), "r+") as f:
        f["VTKHDF/" + name][at] = value
shutil.copy(work + "/g30.vtkhdf", work + "/dropped.vtkhdf")
with h5py.File(work + "/dropped.vtkhdf", "r+") as f:
    f["VTKHDF/Types"][70000] = 5  # a triangle: dropped with a warning
PYEOF
    same_threads vtkhdf_dropped "$WORK/dropped.vtkhdf"
    for bad in "$WORK"/badhdf_*.vtkhdf; do
        expect_exit 2 "$TPK" convert "$bad" "$WORK/bad.tpk" --threads 1
        mv "$WORK/err" "$WORK/err1"
        expect_exit 2 "$TPK" convert "$bad" "$WORK/bad.tpk" --threads 3
        cmp -s "$WORK/err1" "$WORK/err" || fail "$(basename "$bad"): the messages of 1 and 3 threads differ"
    done
fi
# Levels of detail: the collapses run on all threads, the levels must not depend on how many.
same_threads levels "$DATA/sfepy/cube_cylinder.mesh" --levels 3
# convert --max-error: the bound, the tets by vertex, the midpoints and the bisection rounds run on all
# threads. Exodus hexahedra with 8 fields x 5 steps (222k tets at 1%), and gmsh t5 at order 2 with a
# point field (685k tets at 0.3%: the tets by vertex are split between workers too).
same_threads max_error_exodus "$DATA/seacas/exomerge_unit_test.e" --max-error 1%
if command -v gmsh > /dev/null; then
    gmsh -3 -nt 1 -order 2 -format msh22 "$DATA/gmsh/t5.geo" -o "$WORK/t5_p2.msh" > /dev/null
    "$PY" - "$WORK/t5_p2.msh" "$WORK/t5_p2_field.msh" <<'PYEOF'
import math, sys
lines = open(sys.argv[1]).read().split("\n")
i = lines.index("$Nodes"); n = int(lines[i + 1]); vals = []
for line in lines[i + 2:i + 2 + n]:
    k, x, y, z = line.split()[:4]
    vals.append("%s %.17g" % (k, math.sin(3 * float(x)) * math.cos(2 * float(y)) + float(z) ** 2))
open(sys.argv[2], "w").write("\n".join(lines).rstrip("\n") + "\n" +
    '$NodeData\n1\n"f"\n1\n0.0\n3\n0\n1\n%d\n%s\n$EndNodeData\n' % (n, "\n".join(vals)))
PYEOF
    same_threads max_error_t5 "$WORK/t5_p2_field.msh" --max-error 0.3%
fi
echo "$((passed + 2)) passed, 0 failed"
