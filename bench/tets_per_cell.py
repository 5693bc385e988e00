#!/usr/bin/python3
"""Tets produced per input cell by `tetpack convert` (smallest-id diagonals, no new points) against the
cell-centre/face-centre approach that puts a point on every quad face and at every cell centre
(FACE_CENTRE below: hexahedron 24 tets, wedge 14, pyramid 8), on real meshes.
Usage: bench/tets_per_cell.py TETPACK MESH... (prints a Markdown table)"""
import json
import os
import subprocess
import sys
import tempfile

# Face-centre approach (as in umesh-style converters): each quad face gets a centre point and is cut into
# 4 triangles, each triangle coned to a cell-centre point; triangles are coned directly. Tets stay tets.
FACE_CENTRE = {"tetra": 1, "pyramid": 4 + 4, "wedge": 3 * 4 + 2, "hexahedron": 6 * 4}


def main():
    tetpack, meshes = sys.argv[1], sys.argv[2:]
    print("| mesh | tets | pyramids | wedges | hexes (5 / 6 tets) | tets out | tets per cell | "
          "face-centre tets | ratio |")
    print("|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for mesh in meshes:
            out = os.path.join(tmp, "out.tpk")
            proc = subprocess.run([tetpack, "convert", mesh, out, "--json"], capture_output=True,
                                  text=True)
            if proc.returncode:
                print("| %s | conversion failed: %s |" % (os.path.basename(mesh), proc.stderr.strip()[:120]))
                continue
            d = json.loads(proc.stdout)
            s = d["cells_split"]
            hexes = s["hexahedron_into_5"] + s["hexahedron_into_6"]
            # Cells split from a centre point are counted apart by the converter (here: as hexahedra).
            hexes += d["steiner_cells"]
            cells = s["tetra"] + s["pyramid_into_2"] + s["wedge_into_3"] + hexes
            face_centre = (s["tetra"] * FACE_CENTRE["tetra"] + s["pyramid_into_2"] * FACE_CENTRE["pyramid"] +
                           s["wedge_into_3"] * FACE_CENTRE["wedge"] + hexes * FACE_CENTRE["hexahedron"])
            note = " (%d cells with a centre point)" % d["steiner_cells"] if d["steiner_cells"] else ""
            print("| %s | %d | %d | %d | %d / %d | %d%s | %.2f | %d | %.2f |" % (
                os.path.basename(mesh), s["tetra"], s["pyramid_into_2"], s["wedge_into_3"],
                s["hexahedron_into_5"], s["hexahedron_into_6"], d["tets"], note, d["tets"] / cells,
                face_centre, face_centre / d["tets"]))


if __name__ == "__main__":
    main()
