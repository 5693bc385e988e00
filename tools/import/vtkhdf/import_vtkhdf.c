/* VTKHDF importer (VTK's HDF5 format, .vtkhdf / .hdf): UnstructuredGrid, Version 1 and 2, partitions
 * merged by their points, PointData and CellData as fields, Steps as time steps, polyhedra
 * (FaceConnectivity, FaceOffsets, PolyhedronToFaces, PolyhedronOffsets) wherever the file has them.
 * This file opens the file (a path, or an image in memory for fuzzing), checks the /VTKHDF group's
 * Version and Type and reads Steps; the others read the mesh (import_vtkhdf_internal.h). Built without
 * HDF5 (TETPACK_WITH_HDF5=OFF), every reader says so. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "base/fd_io.h"
#include "import/importers.h"

#ifdef TPK_HAVE_HDF5
#include "import/import_file.h"
#include "import_vtkhdf_internal.h"

/* The newest Version major this reader knows. */
#define VTKHDF_MAX_MAJOR 2

static int read_version(vh_reader *r)
{
    if (H5Aexists(r->root, "Version") <= 0)
        return vh_fail(r, "/VTKHDF: expected an attribute Version (2 integers), found none");
    hid_t a = H5Aopen(r->root, "Version", H5P_DEFAULT);
    hid_t space = a >= 0 ? H5Aget_space(a) : -1;
    hssize_t n = space >= 0 ? H5Sget_simple_extent_npoints(space) : -1;
    int ok = n == 2 && H5Aread(a, H5T_NATIVE_INT64, r->version) >= 0;
    if (space >= 0)
        H5Sclose(space);
    if (a >= 0)
        H5Aclose(a);
    if (!ok)
        return vh_fail(r, "/VTKHDF: attribute Version: expected 2 integers (major, minor), found %lld values%s",
                       (long long)n, n == 2 ? " that are not integers" : "");
    if (r->version[0] < 1 || r->version[0] > VTKHDF_MAX_MAJOR)
        return vh_fail(r, "/VTKHDF: attribute Version: expected major version 1 or 2, found %lld.%lld",
                       (long long)r->version[0], (long long)r->version[1]);
    return 0;
}

static int read_type(vh_reader *r)
{
    if (H5Aexists(r->root, "Type") <= 0)
        return vh_fail(r, "/VTKHDF: expected an attribute Type (\"UnstructuredGrid\"), found none");
    char text[64] = "";
    hid_t a = H5Aopen(r->root, "Type", H5P_DEFAULT);
    hid_t type = a >= 0 ? H5Aget_type(a) : -1;
    int ok = type >= 0 && H5Tget_class(type) == H5T_STRING;
    if (ok && H5Tis_variable_str(type) > 0) {
        char *vlen = NULL;
        hid_t mem = H5Tcopy(H5T_C_S1);
        H5Tset_size(mem, H5T_VARIABLE);
        ok = H5Aread(a, mem, &vlen) >= 0 && vlen;
        if (ok)
            snprintf(text, sizeof text, "%s", vlen);
        H5free_memory(vlen);
        H5Tclose(mem);
    } else if (ok) {
        size_t size = H5Tget_size(type);
        char *fixed = size < 4096 ? calloc(1, size + 1) : NULL;
        ok = fixed && H5Aread(a, type, fixed) >= 0;
        if (ok)
            snprintf(text, sizeof text, "%.*s", (int)size, fixed);
        free(fixed);
    }
    if (type >= 0)
        H5Tclose(type);
    if (a >= 0)
        H5Aclose(a);
    if (!ok)
        return vh_fail(r, "/VTKHDF: attribute Type: expected a string, found another type");
    if (strcmp(text, "UnstructuredGrid") != 0)
        return vh_fail(r, "/VTKHDF: attribute Type: expected \"UnstructuredGrid\" (the only VTKHDF type with tet "
                       "meshes), found \"%s\"", text);
    return 0;
}

/* Steps: NSteps, Values, and per step the partitions it uses. Without Steps, one step of every partition. */
static int read_steps(vh_reader *r)
{
    if (!vh_exists(r->root, "Steps")) {
        r->step_count = 1;
        r->steps = malloc(sizeof *r->steps);
        if (!r->steps)
            return vh_fail(r, "out of memory");
        r->steps[0].part0 = 0;
        r->steps[0].parts = r->partitions;
        return 0;
    }
    hid_t g = H5Gopen2(r->root, "Steps", H5P_DEFAULT);
    long long nsteps = -1;
    int have = g >= 0 && H5Aexists(g, "NSteps") > 0;
    if (have) {
        hid_t a = H5Aopen(g, "NSteps", H5P_DEFAULT);
        have = a >= 0 && H5Aread(a, H5T_NATIVE_LLONG, &nsteps) >= 0;
        if (a >= 0)
            H5Aclose(a);
    }
    if (g >= 0)
        H5Gclose(g);
    if (!have || nsteps < 1 || nsteps > INT32_MAX)
        return vh_fail(r, "/VTKHDF/Steps: expected an integer attribute NSteps of 1 or more, found %s%lld",
                       have ? "" : "none: ", have ? nsteps : 0);
    r->step_count = nsteps;
    int64_t *parts = NULL, *part0 = NULL;
    int rc = vh_read_ints(r, "Steps/NumberOfParts", nsteps, &parts, NULL);
    if (rc == 0)
        rc = vh_read_ints(r, "Steps/PartOffsets", nsteps, &part0, NULL);
    if (rc == 0) {
        int64_t rows, cols;
        rc = vh_shape(r, "Steps/Values", &rows, &cols);
        if (rc == 0 && (rows != nsteps || cols != 1))
            rc = vh_fail(r, "/VTKHDF/Steps/Values: expected %lld times (NSteps), found %lld x %lld", nsteps,
                         (long long)rows, (long long)cols);
    }
    r->times = rc ? NULL : malloc(sizeof *r->times * (size_t)nsteps);
    r->steps = rc ? NULL : malloc(sizeof *r->steps * (size_t)nsteps);
    if (rc == 0 && (!r->times || !r->steps))
        rc = vh_fail(r, "out of memory for %lld steps", nsteps);
    if (rc == 0)
        rc = vh_read_rows(r, "Steps/Values", 0, nsteps, 1, H5T_NATIVE_DOUBLE, r->times, "the times");
    for (int64_t s = 0; rc == 0 && s < nsteps; s++) {
        r->steps[s].part0 = part0[s];
        r->steps[s].parts = parts[s];
        if (part0[s] < 0 || parts[s] < 1 || part0[s] > r->partitions || parts[s] > r->partitions - part0[s])
            rc = vh_fail(r, "/VTKHDF/Steps: step %lld: expected partitions within the file's %lld, found %lld from "
                         "%lld (NumberOfParts, PartOffsets)", (long long)s, (long long)r->partitions,
                         (long long)parts[s], (long long)part0[s]);
    }
    free(parts);
    free(part0);
    return rc;
}

/* Every step must have step 0's mesh: tetpack holds one mesh with fields over time. */
static int check_static_mesh(vh_reader *r, const tpk_mesh *first)
{
    for (int64_t s = 1; s < r->step_count; s++) {
        if (r->steps[s].part0 == r->steps[0].part0 && r->steps[s].parts == r->steps[0].parts)
            continue;
        tpk_mesh other;
        memset(&other, 0, sizeof other);
        int rc = vh_read_geometry(r, s, 0, &other);
        int same = rc == 0 && tpk_mesh_same_cells(first, &other);
        tpk_mesh_free(&other);
        if (rc)
            return -1;
        if (!same)
            return vh_fail(r, "/VTKHDF/Steps: step %lld (time %g) has another mesh than step 0: expected the same "
                           "points and cells at every step (tetpack keeps one mesh with fields over time)",
                           (long long)s, r->times ? r->times[s] : 0.0);
    }
    return 0;
}

static void reader_free(vh_reader *r)
{
    free(r->part_points), free(r->part_cells), free(r->part_conn);
    free(r->part_faces), free(r->part_face_conn), free(r->part_poly_faces);
    free(r->point_start), free(r->cell_start), free(r->conn_start);
    free(r->face_start), free(r->face_conn_start), free(r->poly_face_start);
    free(r->steps), free(r->times), free(r->merged_of), free(r->first_raw), free(r->kept);
}

/* The whole import from an open HDF5 file. */
static int read_file(const char *name, hid_t file, tpk_mesh *out, tpk_diag *diag)
{
    vh_reader r;
    memset(&r, 0, sizeof r);
    r.name = name;
    r.diag = diag;
    r.root = -1;
    int rc = 0;
    if (!vh_exists(file, "VTKHDF") || (r.root = H5Gopen2(file, "VTKHDF", H5P_DEFAULT)) < 0)
        rc = vh_fail(&r, "expected a group /VTKHDF (a VTKHDF file), found none: an HDF5 file of another kind");
    if (rc == 0)
        rc = read_version(&r);
    if (rc == 0)
        rc = read_type(&r);
    if (rc == 0)
        rc = vh_read_partitions(&r);
    if (rc == 0)
        rc = read_steps(&r);
    if (rc == 0)
        rc = vh_read_geometry(&r, 0, 1, out);
    if (rc == 0)
        rc = check_static_mesh(&r, out);
    if (rc == 0)
        rc = vh_read_fields(&r, out);
    if (rc == 0) {
        out->step_count = (int)r.step_count;
        out->times = r.times;
        r.times = NULL;
        snprintf(out->format, sizeof out->format, "vtkhdf-%lld.%lld", (long long)r.version[0],
                 (long long)r.version[1]);
    }
    if (r.root >= 0)
        H5Gclose(r.root);
    reader_free(&r);
    if (rc)
        tpk_mesh_free(out);
    return rc;
}

/* HDF5's own error stack stays quiet: the messages say what failed. */
typedef struct quiet_hdf5 {
    H5E_auto2_t func;
    void *data;
} quiet_hdf5;

static quiet_hdf5 hdf5_quiet(void)
{
    quiet_hdf5 q;
    H5Eget_auto2(H5E_DEFAULT, &q.func, &q.data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    return q;
}

static void hdf5_restore(quiet_hdf5 q)
{
    H5Eset_auto2(H5E_DEFAULT, q.func, q.data);
}

int tpk_import_vtkhdf(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    if (tpk_import_begin(path, out, diag))
        return -1;
    quiet_hdf5 q = hdf5_quiet();
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    int rc = file < 0 ? tpk_diag_fail(diag, "%s: cannot open it as an HDF5 file (missing, unreadable, not HDF5, "
                                            "or damaged)", path)
                      : read_file(path, file, out, diag);
    if (file >= 0)
        H5Fclose(file);
    hdf5_restore(q);
    return rc;
}

int tpk_import_vtkhdf_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    if (tpk_import_begin(name, out, diag))
        return -1;
    /* The bytes go into a temporary file that HDF5 opens by name, as the file reader does, and that is
     * unlinked once open (HDF5 wants a real path: not /proc/self/fd of an unnamed file), so that a memory
     * image meets the same code as a file. */
    const char *dir = getenv("TMPDIR");
    char path[4096];
    snprintf(path, sizeof path, "%s/tetpack-vtkhdf-XXXXXX", dir && *dir ? dir : "/tmp");
    int fd = mkstemp(path);
    int written = fd >= 0 && tpk_fd_write_all(fd, data, size) == 0;
    if (fd >= 0)
        close(fd);
    quiet_hdf5 q = hdf5_quiet();
    hid_t file = written && size > 0 ? H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT) : -1;
    if (fd >= 0)
        unlink(path); /* HDF5 keeps its own descriptor */
    int rc = !written ? tpk_diag_fail(diag, "%s: cannot make a temporary file for its %zu bytes", name, size)
             : file < 0 ? tpk_diag_fail(diag, "%s: cannot open it as an HDF5 file (not HDF5, or damaged)", name)
                        : read_file(name, file, out, diag);
    if (file >= 0)
        H5Fclose(file);
    hdf5_restore(q);
    return rc;
}

int tpk_import_vtkhdf_probe(const char *path)
{
    quiet_hdf5 q = hdf5_quiet();
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    int found = file >= 0 && vh_exists(file, "VTKHDF");
    if (file >= 0)
        H5Fclose(file);
    hdf5_restore(q);
    return found;
}

#else

static int not_built(const char *name, tpk_mesh *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    return tpk_diag_fail(diag, "%s: VTKHDF: this tetpack was built without HDF5 (TETPACK_WITH_HDF5=OFF); configure "
                         "it with -DTETPACK_WITH_HDF5=ON (Debian: libhdf5-dev)", name);
}

int tpk_import_vtkhdf(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    return not_built(path, out, diag);
}

int tpk_import_vtkhdf_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    (void)data, (void)size;
    return not_built(name, out, diag);
}

int tpk_import_vtkhdf_probe(const char *path)
{
    (void)path;
    return 0;
}

#endif
