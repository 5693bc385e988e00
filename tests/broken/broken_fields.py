"""Corpus cases for the field checks (5xx), on the 6-tet cube of broken_vertices."""
from broken_vertices import CUBE, KUHN, tets
from make_broken import vtk_legacy


def cases():
    cells = tets(KUHN)
    ramp = [x + 2 * y + 3 * z for x, y, z in CUBE]
    out = [{"name": "fields_clean", "text": vtk_legacy(CUBE, cells, point_data={"ramp": ramp},
                                                       cell_data={"id": list(range(6))}),
            "expect": {}, "absent": ["nonfinite_field_value", "field_length_mismatch"]}]
    bad = list(ramp)
    bad[3] = float("nan")
    bad[6] = float("inf")
    out.append({"name": "fields_nonfinite", "text": vtk_legacy(CUBE, cells, point_data={"ramp": bad}),
                "expect": {"nonfinite_field_value": 2}, "exit": 0})
    out.append({"name": "fields_nonfinite_as_error", "text": vtk_legacy(CUBE, cells, point_data={"ramp": bad}),
                "args": ["--warnings-as-errors"], "expect": {"nonfinite_field_value": 2}, "exit": 1})
    # POINT_DATA announces 7 values for 8 points: both arrays of the section are reported and dropped.
    text = vtk_legacy(CUBE, cells, point_data={"ramp": ramp[:7], "other": ramp[:7]})
    text = text.replace("POINT_DATA 8", "POINT_DATA 7")
    out.append({"name": "fields_short_point_data", "text": text, "expect": {"field_length_mismatch": 2}})
    # A FIELD array of 5 tuples in a CELL_DATA section of 6 cells; the SCALARS next to it are fine.
    text = vtk_legacy(CUBE, cells, cell_data={"id": list(range(6))})
    text += "FIELD extra 1\nmat 1 5 float\n1 2 3 4 5\n"
    out.append({"name": "fields_short_field_array", "text": text, "expect": {"field_length_mismatch": 1}})
    # The same cube as VTU (ascii): a point array one value short, a cell array of the right length.
    def vtu(point_values, cell_values):
        pts = " ".join("%r %r %r" % tuple(map(float, p)) for p in CUBE)
        conn = " ".join(str(v) for t in KUHN for v in t)
        return ('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian">\n'
                '<UnstructuredGrid><Piece NumberOfPoints="8" NumberOfCells="6">\n'
                '<PointData><DataArray type="Float64" Name="ramp" format="ascii">%s</DataArray></PointData>\n'
                '<CellData><DataArray type="Int32" Name="id" format="ascii">%s</DataArray></CellData>\n'
                '<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">%s</DataArray></Points>\n'
                '<Cells><DataArray type="Int32" Name="connectivity" format="ascii">%s</DataArray>\n'
                '<DataArray type="Int32" Name="offsets" format="ascii">%s</DataArray>\n'
                '<DataArray type="UInt8" Name="types" format="ascii">%s</DataArray></Cells>\n'
                '</Piece></UnstructuredGrid></VTKFile>\n') % (
                    " ".join(repr(float(v)) for v in point_values), " ".join(str(v) for v in cell_values), pts,
                    conn, " ".join(str(4 * (i + 1)) for i in range(6)), " ".join(["10"] * 6))
    out.append({"name": "fields_vtu_clean", "text": vtu(ramp, range(6)), "ext": ".vtu", "expect": {},
                "absent": ["field_length_mismatch"]})
    out.append({"name": "fields_vtu_short_point_array", "text": vtu(ramp[:7], range(6)), "ext": ".vtu",
                "expect": {"field_length_mismatch": 1}})
    return out
