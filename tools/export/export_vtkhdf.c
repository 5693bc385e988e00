/* VTKHDF export: a .tpk's tets, world positions, every field at every step and the source maps, as a
 * VTKHDF UnstructuredGrid (one partition). One step: Version 1.0, which every vtkHDFReader reads (VTK
 * 9.1 on). Several steps: Version 2.0 with a Steps group (one mesh, offsets 0; each field's values one
 * step after another), which VTK 9.3 on reads as time steps; VTK 9.1 and 9.2 read only step 0, warning
 * that the version is newer. The HDF5 file is built in memory (the core driver, never on disk) and its
 * image written through an output file, so the path gets the whole file or nothing. */
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "export_io.h"
#include "exporters.h"

#ifdef TPK_HAVE_HDF5
#include <hdf5.h>

typedef struct vh_export {
    tpk_file *file;
    const char *path;
    tpk_diag *diag;
    tpk_file_info info;
    tpk_mesh_arrays mesh;
    int32_t *tets;
    uint32_t steps;     /* the most steps of any field (1 when none) */
    hid_t h5, root;
} vh_export;

static int lib_fail(vh_export *x, tpk_result r, const char *what)
{
    const char *text = tpk_error_text(x->file);
    return tpk_diag_fail(x->diag, "%s: cannot export: %s: %s", x->path, what, text[0] ? text : tpk_result_string(r));
}

static int h5_fail(vh_export *x, const char *what)
{
    return tpk_diag_fail(x->diag, "%s: cannot export: HDF5 could not write %s (out of memory?)", x->path, what);
}

/* An empty dataset of rows x cols (cols 0: rank 1) under `group`; -1 on failure. */
static hid_t create(hid_t group, const char *name, hid_t type, uint64_t rows, uint64_t cols)
{
    hsize_t dims[2] = {rows, cols};
    hid_t space = H5Screate_simple(cols ? 2 : 1, dims, NULL);
    hid_t ds = space >= 0 ? H5Dcreate2(group, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT) : -1;
    if (space >= 0)
        H5Sclose(space);
    return ds;
}

/* Rows [first, first + count) of dataset `ds` (cols 0: rank 1) from `data` of `mem` type. */
static int write_rows(hid_t ds, hid_t mem, uint64_t first, uint64_t count, uint64_t cols, const void *data)
{
    if (count == 0)
        return 0;
    hsize_t start[2] = {first, 0}, size[2] = {count, cols};
    hid_t file_space = H5Dget_space(ds);
    hid_t mem_space = H5Screate_simple(cols ? 2 : 1, size, NULL);
    int ok = file_space >= 0 && mem_space >= 0 &&
             H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start, NULL, size, NULL) >= 0 &&
             H5Dwrite(ds, mem, mem_space, file_space, H5P_DEFAULT, data) >= 0;
    if (mem_space >= 0)
        H5Sclose(mem_space);
    if (file_space >= 0)
        H5Sclose(file_space);
    return ok ? 0 : -1;
}

static int write_whole(hid_t group, const char *name, hid_t type, hid_t mem, uint64_t rows, uint64_t cols,
                       const void *data)
{
    hid_t ds = create(group, name, type, rows, cols);
    int rc = ds >= 0 ? write_rows(ds, mem, 0, rows, cols, data) : -1;
    if (ds >= 0)
        H5Dclose(ds);
    return rc;
}

static int write_attributes(vh_export *x)
{
    int64_t version[2] = {x->steps > 1 ? 2 : 1, 0};
    hsize_t two = 2;
    hid_t space = H5Screate_simple(1, &two, NULL);
    hid_t a = space >= 0 ? H5Acreate2(x->root, "Version", H5T_STD_I64LE, space, H5P_DEFAULT, H5P_DEFAULT) : -1;
    int ok = a >= 0 && H5Awrite(a, H5T_NATIVE_INT64, version) >= 0;
    if (a >= 0)
        H5Aclose(a);
    if (space >= 0)
        H5Sclose(space);
    /* VTK's own writer: a fixed-length ASCII string, not HDF5's variable-length one. */
    static const char type_name[] = "UnstructuredGrid";
    hid_t str = H5Tcopy(H5T_C_S1);
    space = H5Screate(H5S_SCALAR);
    ok = ok && str >= 0 && H5Tset_size(str, sizeof type_name - 1) >= 0 && H5Tset_strpad(str, H5T_STR_NULLPAD) >= 0 &&
         H5Tset_cset(str, H5T_CSET_ASCII) >= 0 && space >= 0;
    a = ok ? H5Acreate2(x->root, "Type", str, space, H5P_DEFAULT, H5P_DEFAULT) : -1;
    ok = ok && a >= 0 && H5Awrite(a, str, type_name) >= 0;
    if (a >= 0)
        H5Aclose(a);
    if (space >= 0)
        H5Sclose(space);
    if (str >= 0)
        H5Tclose(str);
    return ok ? 0 : h5_fail(x, "the /VTKHDF attributes");
}

/* Points (world, float64), Connectivity, Offsets, Types and the partition counts. */
static int write_mesh(vh_export *x)
{
    uint64_t v = x->info.vertex_count, t = x->info.tet_count;
    int64_t counts[3] = {(int64_t)v, (int64_t)t, (int64_t)(4 * t)};
    double *xyz = malloc(sizeof *xyz * 3 * (size_t)(v ? v : 1));
    int64_t *offsets = malloc(sizeof *offsets * (size_t)(t + 1));
    uint8_t *types = malloc((size_t)(t ? t : 1));
    int rc = xyz && offsets && types ? 0 : tpk_diag_fail(x->diag, "%s: out of memory", x->path);
    if (rc == 0) {
        for (uint64_t i = 0; i < v; i++)
            for (int k = 0; k < 3; k++)
                xyz[3 * i + k] = x->mesh.origin[k] + (double)x->mesh.positions[3 * i + k];
        for (uint64_t c = 0; c <= t; c++)
            offsets[c] = (int64_t)(4 * c);
        memset(types, 10, (size_t)(t ? t : 1)); /* VTK_TETRA */
        if (write_whole(x->root, "NumberOfPoints", H5T_STD_I64LE, H5T_NATIVE_INT64, 1, 0, &counts[0]) ||
            write_whole(x->root, "NumberOfCells", H5T_STD_I64LE, H5T_NATIVE_INT64, 1, 0, &counts[1]) ||
            write_whole(x->root, "NumberOfConnectivityIds", H5T_STD_I64LE, H5T_NATIVE_INT64, 1, 0, &counts[2]) ||
            write_whole(x->root, "Points", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v, 3, xyz) ||
            write_whole(x->root, "Connectivity", H5T_STD_I64LE, H5T_NATIVE_INT32, 4 * t, 0, x->tets) ||
            write_whole(x->root, "Offsets", H5T_STD_I64LE, H5T_NATIVE_INT64, t + 1, 0, offsets) ||
            write_whole(x->root, "Types", H5T_STD_U8LE, H5T_NATIVE_UINT8, t, 0, types))
            rc = h5_fail(x, "the mesh");
    }
    free(xyz);
    free(offsets);
    free(types);
    return rc;
}

/* Where each step's values of an array start: step s at s * tuples, or all at 0 for one-step arrays. */
static int write_step_offsets(vh_export *x, hid_t offsets_group, const char *name, uint32_t step_count,
                              uint64_t tuples)
{
    if (x->steps <= 1)
        return 0;
    int64_t *at = malloc(sizeof *at * x->steps);
    if (!at)
        return tpk_diag_fail(x->diag, "%s: out of memory", x->path);
    for (uint32_t s = 0; s < x->steps; s++)
        at[s] = step_count > 1 ? (int64_t)(s * tuples) : 0;
    int rc = write_whole(offsets_group, name, H5T_STD_I64LE, H5T_NATIVE_INT64, x->steps, 0, at);
    free(at);
    return rc ? h5_fail(x, "Steps offsets") : 0;
}

/* One field, every step, as PointData/NAME or CellData/NAME (float32; a column per component). */
static int write_field(vh_export *x, uint32_t i, hid_t groups[2], hid_t offsets[2])
{
    tpk_field_desc desc;
    tpk_result r = tpk_get_field(x->file, i, &desc);
    if (r != TPK_OK)
        return lib_fail(x, r, "field descriptor");
    int cells = desc.association == TPK_ASSOC_TET;
    uint64_t tuples = cells ? x->info.tet_count : x->info.vertex_count;
    uint32_t comps = desc.components ? desc.components : 1;
    char name[65];
    memcpy(name, desc.name, 64);
    name[64] = 0;
    if (!name[0] || strchr(name, '/') || !strcmp(name, "."))
        return tpk_diag_fail(x->diag, "%s: cannot export field '%s': an HDF5 dataset name cannot be empty, \".\" or "
                             "hold '/'", x->path, name);
    hid_t ds = create(groups[cells], name, H5T_IEEE_F32LE, tuples * desc.step_count, comps > 1 ? comps : 0);
    if (ds < 0)
        return h5_fail(x, name);
    int rc = 0;
    for (uint32_t s = 0; rc == 0 && s < desc.step_count; s++) {
        const void *data;
        void *owned;
        int got = tpk_export_load_chunk(x->file, TPK_TAG_FDAT, i, s, 4, tuples * comps, &data, &owned, x->path,
                                        x->diag);
        if (got == 0)
            rc = tpk_diag_fail(x->diag, "%s: cannot export: field '%s' has no data for step %u", x->path, name, s);
        else if (got < 0)
            rc = -1;
        else if (write_rows(ds, H5T_NATIVE_FLOAT, s * tuples, tuples, comps > 1 ? comps : 0, data))
            rc = h5_fail(x, name);
        if (got > 0)
            free(owned);
    }
    H5Dclose(ds);
    return rc ? -1 : write_step_offsets(x, offsets[cells], name, desc.step_count, tuples);
}

/* The tet -> source cell and vertex -> source point maps, as the VTU export writes them. */
static int write_map(vh_export *x, uint32_t tag, int cells, const char *name, hid_t groups[2], hid_t offsets[2])
{
    const void *data;
    void *owned;
    uint64_t count = cells ? x->info.tet_count : x->info.vertex_count;
    int got = tpk_export_load_chunk(x->file, tag, 0, 0, 4, count, &data, &owned, x->path, x->diag);
    if (got <= 0)
        return got;
    int rc = write_whole(groups[cells], name, H5T_STD_I32LE, H5T_NATIVE_INT32, count, 0, data) ? h5_fail(x, name) : 0;
    free(owned);
    return rc ? -1 : write_step_offsets(x, offsets[cells], name, 1, count);
}

/* Steps: NSteps, Values (the file's times, else 0, 1, ...), one partition per step, mesh offsets 0. */
static int write_steps(vh_export *x, hid_t steps)
{
    double *values = malloc(sizeof *values * x->steps);
    int64_t *ones = malloc(sizeof *ones * x->steps), *zeros = calloc(x->steps, sizeof *zeros);
    int rc = values && ones && zeros ? 0 : tpk_diag_fail(x->diag, "%s: out of memory", x->path);
    for (uint32_t s = 0; rc == 0 && s < x->steps; s++) {
        ones[s] = 1;
        if (tpk_get_time(x->file, s, &values[s]) != TPK_OK)
            values[s] = s;
    }
    int64_t nsteps = x->steps;
    hid_t space = H5Screate(H5S_SCALAR);
    hid_t a = space >= 0 ? H5Acreate2(steps, "NSteps", H5T_STD_I64LE, space, H5P_DEFAULT, H5P_DEFAULT) : -1;
    if (rc == 0 && (a < 0 || H5Awrite(a, H5T_NATIVE_INT64, &nsteps) < 0 ||
                    write_whole(steps, "Values", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, x->steps, 0, values) ||
                    write_whole(steps, "NumberOfParts", H5T_STD_I64LE, H5T_NATIVE_INT64, x->steps, 0, ones) ||
                    write_whole(steps, "PartOffsets", H5T_STD_I64LE, H5T_NATIVE_INT64, x->steps, 0, zeros) ||
                    write_whole(steps, "PointOffsets", H5T_STD_I64LE, H5T_NATIVE_INT64, x->steps, 0, zeros) ||
                    write_whole(steps, "CellOffsets", H5T_STD_I64LE, H5T_NATIVE_INT64, x->steps, 1, zeros) ||
                    write_whole(steps, "ConnectivityIdOffsets", H5T_STD_I64LE, H5T_NATIVE_INT64, x->steps, 1, zeros)))
        rc = h5_fail(x, "Steps");
    if (a >= 0)
        H5Aclose(a);
    if (space >= 0)
        H5Sclose(space);
    free(values);
    free(ones);
    free(zeros);
    return rc;
}

static int write_content(vh_export *x)
{
    hid_t groups[2] = {-1, -1}, offsets[2] = {-1, -1}, steps = -1;
    groups[0] = H5Gcreate2(x->root, "PointData", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    groups[1] = H5Gcreate2(x->root, "CellData", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (x->steps > 1) {
        steps = H5Gcreate2(x->root, "Steps", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        offsets[0] = steps >= 0 ? H5Gcreate2(steps, "PointDataOffsets", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT) : -1;
        offsets[1] = steps >= 0 ? H5Gcreate2(steps, "CellDataOffsets", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT) : -1;
    }
    int rc = groups[0] < 0 || groups[1] < 0 || (x->steps > 1 && (offsets[0] < 0 || offsets[1] < 0))
                 ? h5_fail(x, "the groups")
                 : 0;
    if (rc == 0)
        rc = write_attributes(x);
    if (rc == 0)
        rc = write_mesh(x);
    for (uint32_t i = 0; rc == 0 && i < tpk_field_count(x->file); i++)
        rc = write_field(x, i, groups, offsets);
    if (rc == 0)
        rc = write_map(x, TPK_TAG_VMAP, 0, "source_point", groups, offsets);
    if (rc == 0)
        rc = write_map(x, TPK_TAG_TMAP, 1, "source_cell", groups, offsets);
    if (rc == 0 && steps >= 0)
        rc = write_steps(x, steps);
    for (int k = 0; k < 2; k++) {
        if (groups[k] >= 0)
            H5Gclose(groups[k]);
        if (offsets[k] >= 0)
            H5Gclose(offsets[k]);
    }
    if (steps >= 0)
        H5Gclose(steps);
    return rc;
}

/* The in-memory HDF5 file's image to `path`, atomically. */
static int write_image(vh_export *x)
{
    H5Fflush(x->h5, H5F_SCOPE_GLOBAL);
    ssize_t size = H5Fget_file_image(x->h5, NULL, 0);
    void *image = size > 0 ? malloc((size_t)size) : NULL;
    if (!image || H5Fget_file_image(x->h5, image, (size_t)size) != size) {
        free(image);
        return h5_fail(x, "the file image");
    }
    tpk_out o;
    int rc = tpk_out_open(&o, x->path, x->diag);
    if (rc == 0) {
        tpk_out_write(&o, image, (size_t)size);
        rc = tpk_out_commit(&o, x->diag);
    }
    free(image);
    return rc;
}

static int load(vh_export *x)
{
    tpk_layout layout = TPK_LAYOUT_TET32;
    tpk_result r = tpk_get_info(x->file, &x->info);
    if (r != TPK_OK)
        return lib_fail(x, r, "header");
    if (tpk_export_pick_layout(x->file, x->path, &layout, x->diag) != 0)
        return -1;
    r = tpk_load_arrays(x->file, layout, NULL, 0, &x->mesh);
    if (r != TPK_OK)
        return lib_fail(x, r, "loading the mesh arrays");
    x->tets = malloc(sizeof(int32_t) * 4 * (size_t)(x->info.tet_count ? x->info.tet_count : 1));
    if (!x->tets)
        return tpk_diag_fail(x->diag, "%s: out of memory for %llu tets", x->path, (unsigned long long)x->info.tet_count);
    r = tpk_recover_tets_threads(&x->mesh, x->tets, tpk_thread_count(0));
    if (r != TPK_OK)
        return lib_fail(x, r, "recovering the tets' vertices");
    x->steps = 1;
    for (uint32_t i = 0; i < tpk_field_count(x->file); i++) {
        tpk_field_desc desc;
        if ((r = tpk_get_field(x->file, i, &desc)) != TPK_OK)
            return lib_fail(x, r, "field descriptor");
        if (desc.step_count > x->steps)
            x->steps = desc.step_count;
    }
    return 0;
}

int tpk_export_vtkhdf(tpk_file *file, const char *path, tpk_diag *diag)
{
    if (!file || !path)
        return tpk_diag_fail(diag, "tpk_export_vtkhdf: no file or output path given");
    vh_export x;
    memset(&x, 0, sizeof x);
    x.file = file, x.path = path, x.diag = diag, x.h5 = -1, x.root = -1;
    H5E_auto2_t old_func;
    void *old_data;
    H5Eget_auto2(H5E_DEFAULT, &old_func, &old_data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL); /* the messages say what failed */
    int rc = load(&x);
    hid_t fapl = rc == 0 ? H5Pcreate(H5P_FILE_ACCESS) : -1;
    if (rc == 0 && (fapl < 0 || H5Pset_fapl_core(fapl, (size_t)1 << 24, 0) < 0 ||
                    (x.h5 = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, fapl)) < 0 ||
                    (x.root = H5Gcreate2(x.h5, "VTKHDF", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT)) < 0))
        rc = h5_fail(&x, "an HDF5 file in memory");
    if (rc == 0)
        rc = write_content(&x);
    if (x.root >= 0)
        H5Gclose(x.root);
    if (rc == 0)
        rc = write_image(&x);
    if (x.h5 >= 0)
        H5Fclose(x.h5);
    if (fapl >= 0)
        H5Pclose(fapl);
    H5Eset_auto2(H5E_DEFAULT, old_func, old_data);
    free(x.tets);
    return rc;
}

#else

int tpk_export_vtkhdf(tpk_file *file, const char *path, tpk_diag *diag)
{
    (void)file;
    return tpk_diag_fail(diag, "%s: VTKHDF: this tetpack was built without HDF5 (TETPACK_WITH_HDF5=OFF); configure "
                         "it with -DTETPACK_WITH_HDF5=ON (Debian: libhdf5-dev)", path);
}

#endif
