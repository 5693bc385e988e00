# %% [markdown]
# # A walk through a .tpk in Python (notebook-style: run it whole, or cell by cell in an editor
# that knows `# %%` cells). From the repository root after `./dev build`:
#     PYTHONPATH=build/python python3 samples/python_walkthrough.py      (writes into out/)

# %%
import os
import sys

import numpy as np

import tetpack

out = sys.argv[1] if len(sys.argv) > 1 else "out"
os.makedirs(out, exist_ok=True)
source = os.path.join(os.path.dirname(__file__), "cylinder.vtk")
plain, packed = os.path.join(out, "walk.tpk"), os.path.join(out, "walk_zstd.tpk")
tetpack.convert(source, plain, layouts=(32, 20, 16))
tetpack.convert(source, packed, layouts=(16,), zstd=9)
f, z = tetpack.open(plain), tetpack.open(packed)
print(f.file_size, "bytes plain,", z.file_size, "bytes with zstd")

# %% [markdown]
# Uncompressed chunks are NumPy views into the mapped file; zstd chunks are decoded into new arrays.
# `chunk_bytes(i)` says which: (bytes, zero_copy).

# %%
for i, chunk in enumerate(f.chunks()):
    print(chunk["tag"], chunk["elem_count"], "view" if f.chunk_bytes(i)[1] else "copy")
print("zstd file:", [(c["tag"], z.chunk_bytes(i)[1]) for i, c in enumerate(z.chunks())][:3])

# %% [markdown]
# Positions are float32 relative to a float64 origin; the layouts are structured arrays
# (tetpack.TET32, TET20, TET16); `tets()` recovers vertex quadruples from any of them.

# %%
print("origin", f.origin, "bounds", f.bounds)
print(f.tet32()[:2], f.tet16()[:2], sep="\n")
same = np.array_equal(np.sort(f.tets(32), axis=1), np.sort(z.tets(16), axis=1))
print("Tet32 and zstd Tet16 give the same tets:", same)

# %% [markdown]
# The shell (boundary faces, outward) and the maps back to the source mesh.

# %%
shell = f.shell()
print(len(shell), "shell faces; first:", shell[0])
print("tet 0 came from source cell", f.tmap()[0], "; vertex 0 from source point", f.vmap()[0])

# %% [markdown]
# Hand the mesh to meshio and VTK.

# %%
import meshio  # noqa: E402

mesh = f.to_meshio()
meshio.write(os.path.join(out, "walk_meshio.vtu"), mesh)
print(meshio.read(plain))  # tetpack registered .tpk with meshio on import

from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter, vtkXMLUnstructuredGridWriter  # noqa: E402

for writer, data, name in ((vtkXMLUnstructuredGridWriter(), f.to_vtk(), "walk_vtk.vtu"),
                           (vtkXMLPolyDataWriter(), f.shell_to_vtk(), "walk_shell.vtp")):
    writer.SetInputData(data)
    writer.SetFileName(os.path.join(out, name))
    writer.Write()
print("wrote", os.path.join(out, "walk_vtk.vtu"), "and walk_shell.vtp")

# %% [markdown]
# A closed file refuses calls; arrays taken before stay valid (they keep the mapping alive).

# %%
positions = f.positions()
f.close()
z.close()
print("after close:", positions[:1])
try:
    f.positions()
except tetpack.Error as err:
    print("tetpack.Error", err.code, err.code_name, "-", err)
