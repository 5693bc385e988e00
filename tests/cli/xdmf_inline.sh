#!/usr/bin/env bash
# XDMF with inline XML data as solvers and FEniCS write it by hand (Xdmf 2: Type=, X_Y_Z, References,
# a DOCTYPE; Xdmf 3: dolfinx's per-function Temporal Collections with xi:include), and broken files:
# each must fail naming the file, the line or the dataset, what was expected and what was found.
source "$(dirname "$0")/common.sh" "$@"
# The unit cube's corners in VTK hexahedron order, as a shared DataItem.
cat > "$WORK/hex2.xmf" <<'XML'
<?xml version="1.0" ?>
<!DOCTYPE Xdmf SYSTEM "Xdmf.dtd" []>
<Xdmf Version="2.0">
 <Domain>
  <DataItem Name="z" Format="XML" NumberType="Float" Precision="4" Dimensions="8">0 0 0 0 1 1 1 1</DataItem>
  <Grid Name="cube" GridType="Uniform">
   <Topology Type="Hexahedron" NumberOfElements="1">
    <DataItem Format="XML" NumberType="Int" Dimensions="1 8">0 1 2 3 4 5 6 7</DataItem>
   </Topology>
   <Geometry Type="X_Y_Z">
    <DataItem Format="XML" Dimensions="8">0 1 1 0 0 1 1 0</DataItem>
    <DataItem Format="XML" Dimensions="8">0 0 1 1 0 0 1 1</DataItem>
    <DataItem Reference="XML">/Xdmf/Domain/DataItem[@Name="z"]</DataItem>
   </Geometry>
   <Attribute Name="height" AttributeType="Scalar" Center="Node">
    <DataItem Reference="XML">/Xdmf/Domain/DataItem[@Name="z"]</DataItem>
   </Attribute>
   <Attribute Name="material" Center="Cell"><DataItem Dimensions="1">7</DataItem></Attribute>
  </Grid>
 </Domain>
</Xdmf>
XML
convert_checked "$WORK/hex2.xmf" "$WORK/hex2.tpk" --json --field height --field material > "$WORK/hex2.json"
"$PY" - "$WORK/hex2.json" <<'PYEOF'
import json, sys
j = json.load(open(sys.argv[1]))
assert j["source_cells"] == 1 and j["mirrored_cells"] == 0 and j["vertices"] == 8 and j["fields"] == 2, j
assert j["cells_split"]["hexahedron_into_5"] + j["cells_split"]["hexahedron_into_6"] == 1, j
PYEOF
"$TPK" info "$WORK/hex2.tpk" | grep -q "height .*range \[0, 1\]" || fail "hex2.tpk: height should span 0..1"
# dolfinx writes mesh tags as a second Grid of facets on the mesh's Geometry: dropped with a warning.
sed 's|  </Grid>|  </Grid>\
  <Grid Name="facet_tags"><xi:include xmlns:xi="http://www.w3.org/2001/XInclude" xpointer="xpointer(/Xdmf/Domain/Grid/Geometry)"/>\
   <Topology TopologyType="Quadrilateral" NumberOfElements="1"><DataItem Dimensions="1 4">0 3 2 1</DataItem></Topology>\
   <Attribute Name="facet_tags" Center="Cell"><DataItem Dimensions="1">4</DataItem></Attribute></Grid>|' \
    "$WORK/hex2.xmf" > "$WORK/tags.xmf"
convert_checked "$WORK/tags.xmf" "$WORK/tags.tpk" --json > "$WORK/tags.json" 2> "$WORK/err"
expect_stderr "tags.xmf: line 20: Grid 'facet_tags' has no volume cells (TopologyType Quadrilateral): dropped"
grep -q '"source_cells":1,' "$WORK/tags.json" || fail "tags.xmf: $(cat "$WORK/tags.json")"
# No extension tetpack knows: found by its first bytes, "<Xdmf", also after an XML declaration and a
# DOCTYPE (which VTU's "<?xml" magic would claim otherwise).
sed '1,2d' "$WORK/hex2.xmf" > "$WORK/hex2.dat"
convert_checked "$WORK/hex2.dat" "$WORK/hex2_dat.tpk" > /dev/null
cp "$WORK/hex2.xmf" "$WORK/hex2_decl.dat"
convert_checked "$WORK/hex2_decl.dat" "$WORK/hex2_decl.tpk" > /dev/null
"$TPK" info "$WORK/hex2_decl.tpk" | grep -q '"format":"xdmf"' || fail "hex2_decl.dat: not read as XDMF"
# A quadratic tet (Tetrahedron_10) split whole into 8 at its nodes (with --higher-order corners: one
# tet, its corners), a triangle dropped, in a Mixed topology (codes 38 and 4).
cat > "$WORK/tet10.xdmf" <<'XML'
<Xdmf Version="3.0"><Domain><Grid Name="q">
 <Topology TopologyType="Mixed" NumberOfElements="2">
  <DataItem DataType="Int" Dimensions="15">38 0 1 2 3 4 5 6 7 8 9  4 0 2 1</DataItem>
 </Topology>
 <Geometry GeometryType="XYZ"><DataItem Dimensions="10 3">
  0 0 0  1 0 0  0 1 0  0 0 1  .5 0 0  .5 .5 0  0 .5 0  0 0 .5  .5 0 .5  0 .5 .5
 </DataItem></Geometry>
</Grid></Domain></Xdmf>
XML
"$TPK" convert "$WORK/tet10.xdmf" "$WORK/tet10.tpk" --json > "$WORK/tet10.json" 2> "$WORK/err"
check_6xx "$WORK/tet10.tpk"
expect_stderr "dropped cells that are not volumes: 1 cells (1 triangle)"
grep -q '"tets":8,' "$WORK/tet10.json" && grep -q '"mirrored_cells":0' "$WORK/tet10.json" &&
    grep -q '"inverted_tets":0' "$WORK/tet10.json" || fail "tet10: $(cat "$WORK/tet10.json")"
"$TPK" convert "$WORK/tet10.xdmf" "$WORK/tet10c.tpk" --higher-order corners --json > "$WORK/tet10.json" 2> "$WORK/err"
check_6xx "$WORK/tet10c.tpk"
expect_stderr "reduced higher-order cells to their corner nodes: 1 cells (1 quadratic tetra)"
grep -q '"tets":1,' "$WORK/tet10.json" && grep -q '"mirrored_cells":0' "$WORK/tet10.json" || fail "tet10: $(cat "$WORK/tet10.json")"
# dolfinx: the mesh Grid first, then one Temporal Collection per function, each step xi:including the
# mesh; the two functions' steps merge by time (given out of order here).
cat > "$WORK/dolfinx.xdmf" <<'XML'
<?xml version="1.0"?>
<!DOCTYPE Xdmf SYSTEM "Xdmf.dtd" []>
<Xdmf Version="3.0" xmlns:xi="http://www.w3.org/2001/XInclude">
  <Domain>
    <Grid Name="mesh" GridType="Uniform">
      <Topology TopologyType="Tetrahedron" NumberOfElements="1" NodesPerElement="4">
        <DataItem Dimensions="1 4" NumberType="Int" Format="XML">0 1 2 3</DataItem>
      </Topology>
      <Geometry GeometryType="XYZ">
        <DataItem Dimensions="4 3" Format="XML">0 0 0 1 0 0 0 1 0 0 0 1</DataItem>
      </Geometry>
    </Grid>
    <Grid Name="u" GridType="Collection" CollectionType="Temporal">
      <Grid Name="u" GridType="Uniform">
        <xi:include xpointer="xpointer(/Xdmf/Domain/Grid[@GridType='Uniform'][1]/*[self::Topology or self::Geometry])" />
        <Time Value="1" />
        <Attribute Name="u" AttributeType="Scalar" Center="Node"><DataItem Dimensions="4 1" Format="XML">10 11 12 13</DataItem></Attribute>
      </Grid>
      <Grid Name="u" GridType="Uniform">
        <xi:include xpointer="xpointer(/Xdmf/Domain/Grid[@GridType='Uniform'][1]/*[self::Topology or self::Geometry])" />
        <Time Value="0" />
        <Attribute Name="u" AttributeType="Scalar" Center="Node"><DataItem Dimensions="4 1" Format="XML">0 1 2 3</DataItem></Attribute>
      </Grid>
    </Grid>
    <Grid Name="p" GridType="Collection" CollectionType="Temporal">
      <Grid Name="p" GridType="Uniform">
        <xi:include xpointer="xpointer(/Xdmf/Domain/Grid[@GridType='Uniform'][1]/*[self::Topology or self::Geometry])" />
        <Time Value="0" />
        <Attribute Name="p" AttributeType="Scalar" Center="Cell"><DataItem Dimensions="1 1" Format="XML">5</DataItem></Attribute>
      </Grid>
      <Grid Name="p" GridType="Uniform">
        <xi:include xpointer="xpointer(/Xdmf/Domain/Grid[@GridType='Uniform'][1]/*[self::Topology or self::Geometry])" />
        <Time Value="1" />
        <Attribute Name="p" AttributeType="Scalar" Center="Cell"><DataItem Dimensions="1 1" Format="XML">6</DataItem></Attribute>
      </Grid>
    </Grid>
  </Domain>
</Xdmf>
XML
convert_checked "$WORK/dolfinx.xdmf" "$WORK/dolfinx.tpk" --json --field u --field p > "$WORK/dolfinx.json"
"$TPK" export "$WORK/dolfinx.tpk" --vtu "$WORK/dolfinx_back.vtu"
"$PY" - "$WORK/dolfinx.json" "$WORK/dolfinx_back.vtu" <<'PYEOF'
import json, sys
import meshio, numpy as np
j = json.load(open(sys.argv[1]))
assert j["steps"] == 2 and j["fields"] == 2 and j["tets"] == 1, j
m = meshio.read(sys.argv[2])
order = m.point_data["source_point"].astype(int)
# Step 0 is time 0 (listed second in the file), step 1 time 1.
assert np.array_equal(m.point_data["u_t0"], order.astype(float)), m.point_data["u_t0"]
assert np.array_equal(m.point_data["u_t1"], order + 10.0), m.point_data["u_t1"]
assert [m.cell_data["p_t0"][0][0], m.cell_data["p_t1"][0][0]] == [5, 6], m.cell_data
PYEOF

# ---- Broken files -------------------------------------------------------------------------------
# broken NAME 'stderr text'...: NAME.xdmf fails with exit 2 and each text in its message.
broken() {
    local name=$1
    shift
    expect_exit 2 "$TPK" convert "$WORK/$name.xdmf" "$WORK/$name.tpk"
    for text in "$@"; do expect_stderr "$text"; done
    [ ! -e "$WORK/$name.tpk" ] || fail "$name.tpk written for a broken input"
}
# hdf_file NAME DATAITEM: the tet of dolfinx.xdmf with its geometry in DATAITEM.
hdf_file() {
    cat > "$WORK/$1.xdmf" <<XML
<Xdmf Version="3.0"><Domain><Grid Name="g">
 <Topology TopologyType="Tetrahedron"><DataItem Dimensions="1 4" DataType="Int">0 1 2 3</DataItem></Topology>
 <Geometry GeometryType="XYZ">
  $2
 </Geometry>
</Grid></Domain></Xdmf>
XML
}
"$PY" -c "
import h5py, numpy as np, sys
with h5py.File(sys.argv[1], 'w') as f:
    f['/mesh/geometry'] = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
" "$WORK/data.h5"
hdf_file hdf_ok '<DataItem Dimensions="4 3" Format="HDF">data.h5:/mesh/geometry</DataItem>'
convert_checked "$WORK/hdf_ok.xdmf" "$WORK/hdf_ok.tpk" > /dev/null
# The .h5 is an input too: an output there is refused, the data left as it was.
sha1sum "$WORK/data.h5" > "$WORK/h5.sum"
expect_exit 2 "$TPK" convert "$WORK/hdf_ok.xdmf" "$WORK/data.h5"
expect_stderr "OUTPUT '$WORK/data.h5' is a file the input reads (same file as '$WORK/data.h5', read for INPUT '$WORK/hdf_ok.xdmf')"
sha1sum -c --quiet "$WORK/h5.sum" || fail "data.h5 changed"
hdf_file missing_h5 '<DataItem Dimensions="4 3" Format="HDF">gone.h5:/mesh/geometry</DataItem>'
broken missing_h5 "missing_h5.xdmf: line 4: <DataItem>: cannot open the HDF5 file .*gone.h5 (No such file"
hdf_file wrong_dataset '<DataItem Dimensions="4 3" Format="HDF">data.h5:/mesh/geometri</DataItem>'
broken wrong_dataset "wrong_dataset.xdmf: line 4: <DataItem>: .*data.h5: expected a dataset /mesh/geometri, found none"
hdf_file wrong_dims '<DataItem Dimensions="5 3" Format="HDF">data.h5:/mesh/geometry</DataItem>'
broken wrong_dims "expected 15 values (the DataItem's Dimensions), found a dataset of 4 x 3 = 12"
hdf_file not_hdf '<DataItem Dimensions="4 3" Format="HDF">hdf_ok.xdmf:/mesh/geometry</DataItem>'
broken not_hdf "cannot open the HDF5 file .*hdf_ok.xdmf (not an HDF5 file, or damaged)"
hdf_file short_xml '<DataItem Dimensions="4 3">0 0 0 1 0 0 0 1 0 0 0</DataItem>'
broken short_xml "short_xml.xdmf: line 4: <DataItem>: expected 12 numbers (Dimensions \"4 3\"), found 11"
hdf_file bad_number '<DataItem Dimensions="4 3">0 0 0 1 0 0 0 1 0 0 0 x</DataItem>'
broken bad_number "value 11: expected a number, found 'x'"
hdf_file binary '<DataItem Dimensions="4 3" Format="Binary">data.bin</DataItem>'
broken binary "expected Format XML or HDF, found \"Binary\""
head -c 150 "$WORK/hdf_ok.xdmf" > "$WORK/truncated.xdmf"
broken truncated "truncated.xdmf: line 2: not well-formed XML: unclosed token" "(truncated file?)"
sed 's/0 1 2 3/0 1 2 4/' "$WORK/hdf_ok.xdmf" > "$WORK/bad_id.xdmf"
broken bad_id "cell 0 (Tetrahedron) uses point id 4, expected 0 to 3"
sed 's/Tetrahedron/Tetrahedra/' "$WORK/hdf_ok.xdmf" > "$WORK/bad_type.xdmf"
broken bad_type "expected TopologyType Tetrahedron, .*found \"Tetrahedra\""
sed 's/Grid Name="g"/Grid Name="g" GridType="Collection" CollectionType="Spatial"/' "$WORK/hdf_ok.xdmf" > "$WORK/spatial.xdmf"
broken spatial "spatial collections, partitioned meshes, are not read"
# A time series whose step at time 1 (u's first Grid) moves a point instead of including the mesh.
"$PY" - "$WORK/dolfinx.xdmf" "$WORK/moving.xdmf" <<'PYEOF'
import re, sys
text = open(sys.argv[1]).read()
own = ('<Topology TopologyType="Tetrahedron"><DataItem Dimensions="1 4" DataType="Int">0 1 2 3</DataItem></Topology>'
       '<Geometry><DataItem Dimensions="4 3">0 0 0 2 0 0 0 1 0 0 0 1</DataItem></Geometry>')
open(sys.argv[2], "w").write(re.sub(r"<xi:include [^>]*>(\s*<Time Value=\"1\")", own + r"\1", text, count=1))
PYEOF
broken moving "moving.xdmf: line 14: <Grid>: Grid 'u' holds a different mesh (points or cells) than the first time step's Grid 'u' (line 19)"
# A function with no value at one of the times.
sed '0,/Time Value="1"/ s//Time Value="3"/' "$WORK/dolfinx.xdmf" > "$WORK/gap.xdmf"
broken gap "gap.xdmf: Attribute 'u' has no value at time 1 (step 1 of 3)"
# An xpointer that names nothing.
sed "s|@GridType='Uniform'|@Name='nomesh'|" "$WORK/dolfinx.xdmf" > "$WORK/dangling.xdmf"
broken dangling "dangling.xdmf: line 20: <xi:include>: xpointer \"xpointer(/Xdmf/Domain/Grid\[@Name='nomesh'\].*names no element"
# A relative path in an xpointer (only absolute ones are read).
sed 's|xpointer(/Xdmf|xpointer(Xdmf|' "$WORK/dolfinx.xdmf" > "$WORK/relative.xdmf"
broken relative "relative.xdmf: line 20: <xi:include>: path \"Xdmf/Domain/.*\": expected an absolute path starting with '/' at character 1, found 'X'"
echo "1 passed, 0 failed"
