# Surfaces and point clouds through `tetpack convert` (TetGen): real parts as STL/OFF/PLY, a CSV point
# cloud, the --tetgen-* options, and refusals (open surface, bad files, unsafe switches) with exit 2,
# a message naming the file and place, and nothing written. Built without TetGen: refused saying so.
source "$(dirname "$0")/common.sh"

# The boundary of tetgen/part1_small (its .face triangles) as ASCII STL, binary STL and OFF.
"$PY" - "$DATA/tetgen/part1_small" "$WORK/part" <<'PYEOF'
import struct, sys
stem, out = sys.argv[1], sys.argv[2]
rows = lambda p: [l.split() for l in open(p) if l.strip() and not l.lstrip().startswith('#')]
nodes = rows(stem + '.node'); faces = rows(stem + '.face')
P = {int(r[0]): tuple(map(float, r[1:4])) for r in nodes[1:int(nodes[0][0]) + 1]}
T = [tuple(map(int, r[1:4])) for r in faces[1:int(faces[0][0]) + 1]]
used = sorted({v for t in T for v in t}); idx = {v: i for i, v in enumerate(used)}
with open(out + '.stl', 'w') as f:
    f.write('solid part\n')
    for t in T:
        f.write('facet normal 0 0 0\nouter loop\n' + ''.join('vertex %.17g %.17g %.17g\n' % P[v] for v in t) + 'endloop\nendfacet\n')
    f.write('endsolid part\n')
with open(out + '_bin.stl', 'wb') as f:
    f.write(b'solid but binary'.ljust(80, b'\0') + struct.pack('<I', len(T)))
    for t in T:
        f.write(struct.pack('<3f', 0, 0, 0) + b''.join(struct.pack('<3f', *P[v]) for v in t) + b'\0\0')
with open(out + '.off', 'w') as f:
    f.write('OFF\n%d %d 0\n' % (len(used), len(T)) + ''.join('%.17g %.17g %.17g\n' % P[v] for v in used))
    f.write(''.join('3 %d %d %d\n' % tuple(idx[v] for v in t) for t in T))
with open(out + '_open.off', 'w') as f:
    f.write('OFF\n%d %d 0\n' % (len(used), len(T) - 1) + ''.join('%.17g %.17g %.17g\n' % P[v] for v in used))
    f.write(''.join('3 %d %d %d\n' % tuple(idx[v] for v in t) for t in T[1:]))
PYEOF

if ! "$TPK" convert "$WORK/part.off" "$WORK/probe.tpk" --quiet 2>"$WORK/err"; then
    expect_stderr "built without TetGen"
    [ ! -e "$WORK/probe.tpk" ] || fail "output left behind"
    skip "tetpack built without TetGen: refusal checked, nothing else to test"
fi

# Each form converts; --json stdout is JSON alone (TetGen's printing is kept off stdout); the .tpk checks.
for f in part.stl part_bin.stl part.off; do
    convert_checked "$WORK/$f" "$WORK/$f.tpk" --json > "$WORK/$f.json"
    "$PY" -c "import json; d=json.load(open('$WORK/$f.json')); assert d['tets'] > 5000 and d['inverted_fixed'] == 0 and d['degenerate_dropped'] == 0, d"
    "$TPK" check "$WORK/$f.tpk" > /dev/null || fail "tetpack check failed on $f.tpk"
done
# The options reach TetGen: a volume bound gives more tets; unsafe switches are refused.
convert_checked "$WORK/part.off" "$WORK/fine.tpk" --tetgen-max-volume 0.01 --tetgen-quality 1.2/10 --json > "$WORK/fine.json"
"$PY" -c "import json; a=json.load(open('$WORK/part.off.json')); b=json.load(open('$WORK/fine.json')); assert b['tets'] > 2 * a['tets'], (a['tets'], b['tets'])"
expect_exit 2 "$TPK" convert "$WORK/part.off" "$WORK/x.tpk" --tetgen-switches pqr
expect_stderr "'r' at position 3 is not allowed"
expect_exit 2 "$TPK" convert "$WORK/part.off" "$WORK/x.tpk" --tetgen-quality 0.5
expect_stderr "radius-edge ratio must be from 1.0"
[ ! -e "$WORK/x.tpk" ] || fail "output left behind"

# A point cloud with a value column: Delaunay, the value kept as a point field.
"$PY" - "$DATA/sfepy/cylinder.vtk" "$WORK/cyl.csv" <<'PYEOF'
import sys, meshio
m = meshio.read(sys.argv[1])
with open(sys.argv[2], 'w') as f:
    f.write('x,y,z,height\n' + ''.join('%.17g,%.17g,%.17g,%.9g\n' % (x, y, z, z) for x, y, z in m.points))
PYEOF
# Its end caps are x = 1e-18-ish, not 0, so the Delaunay slivers across them are positive. The box
# straddles x = 0, so the stored frame has origin 0 on x (spec §6.8) and float32 keeps those tiny
# coordinates: the slivers stay positive and nothing is dropped. (With the box centre as origin they
# were rounded flat and refused.)
convert_checked "$WORK/cyl.csv" "$WORK/cyl.tpk" --json > "$WORK/cyl.json"
"$PY" -c "import json; d=json.load(open('$WORK/cyl.json')); assert d['vertices'] == 354 and d['fields'] == 1 and d['tets'] == 2193 and d['degenerate_dropped'] == 0, d"
"$TPK" info "$WORK/cyl.tpk" | grep -q height || fail "field 'height' missing"

# Refusals: exit 2, the file and the place named, nothing written.
expect_exit 2 "$TPK" convert "$WORK/part_open.off" "$WORK/x.tpk"
expect_stderr "part_open.off: edge ("
expect_stderr "lies in only one face"
head -c 1000 "$WORK/part_bin.stl" > "$WORK/cut.stl"
expect_exit 2 "$TPK" convert "$WORK/cut.stl" "$WORK/x.tpk"
expect_stderr "cut.stl: byte 984: truncated binary STL"
sed '2s/.*/9999 2182 0/' "$WORK/part.off" > "$WORK/counts.off"
expect_exit 2 "$TPK" convert "$WORK/counts.off" "$WORK/x.tpk"
expect_stderr "counts.off:1094: expected end of line after the 3 coordinates of vertex 1091"
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty quux z\nend_header\n' > "$WORK/bad.ply"
expect_exit 2 "$TPK" convert "$WORK/bad.ply" "$WORK/x.tpk"
expect_stderr "bad.ply:6: expected a PLY type"
[ ! -e "$WORK/x.tpk" ] || fail "output left behind"
echo "surface CLI tests passed"
