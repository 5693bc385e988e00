/* Reading a file in a child process, for the importers whose files are parsed by a library we do not
 * control (HDF5 for VTKHDF and XDMF's heavy data, netCDF for Exodus, CGNS): such a library can crash,
 * or abort, on a damaged file (HDF5 1.10.8 dereferences NULL in H5F__accum_read on a 1,856-byte file the
 * fuzzer made). The child reads; its warnings and then its result, the mesh with it, come back through a
 * pipe; a child that dies becomes an error naming the file, the library and the signal, and the caller
 * goes on. The registry runs a row's read and probe this way when the row says `isolated`. */
#ifndef TPK_IMPORT_ISOLATE_H
#define TPK_IMPORT_ISOLATE_H

#include "base/diag.h"
#include "mesh/mesh.h"

/* TETPACK_ISOLATE=0 in the environment reads in process (a debugger, a profiler); anything else or unset:
 * in a child. */
int tpk_isolate_enabled(void);

/* read(path, out, diag) in a child process. `what` names the library for the message ("HDF5"). The same
 * return, mesh, message, warnings (forwarded as they come) and field problems as the reader's own;
 * a child that dies: -1, out empty, "PATH: the HDF5 library crashed (signal 11, SIGSEGV) reading this
 * file: it is damaged or not what it claims; nothing was read". */
int tpk_isolated_read(int (*read)(const char *path, tpk_mesh *out, tpk_diag *diag), const char *what,
                      const char *path, tpk_mesh *out, tpk_diag *diag);

/* probe(path) in a child process; 0 (not this format) when the child dies. */
int tpk_isolated_probe(int (*probe)(const char *path), const char *path);

#endif
