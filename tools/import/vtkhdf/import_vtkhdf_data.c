/* VTKHDF importer: datasets and their shapes under /VTKHDF, read through the HDF5 C library with any
 * stored numeric type converted (HDF5 converts on read), every shape checked before allocating. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "import_vtkhdf_internal.h"

#ifdef TPK_HAVE_HDF5

/* zlib's deflate packs at most about this many bytes into one (HDF5's common filter). */
#define DEFLATE_MAX_RATIO 1032.0

int vh_exists(hid_t group, const char *name)
{
    return H5Lexists(group, name, H5P_DEFAULT) > 0;
}

static hid_t open_dataset(vh_reader *r, const char *path)
{
    /* H5Lexists wants each link on the way to exist: check "PointData" before "PointData/u". */
    char prefix[256];
    for (const char *slash = path; (slash = strchr(slash, '/')); slash++) {
        snprintf(prefix, sizeof prefix, "%.*s", (int)(slash - path), path);
        if (!vh_exists(r->root, prefix))
            return -1;
    }
    if (!vh_exists(r->root, path))
        return -1;
    return H5Dopen2(r->root, path, H5P_DEFAULT);
}

int vh_shape(vh_reader *r, const char *path, int64_t *rows, int64_t *cols)
{
    hid_t ds = open_dataset(r, path);
    if (ds < 0)
        return vh_fail(r, "expected a dataset /VTKHDF/%s, found none", path);
    hid_t space = H5Dget_space(ds);
    int rank = space >= 0 ? H5Sget_simple_extent_ndims(space) : -1;
    hsize_t dims[H5S_MAX_RANK] = {0};
    if (rank >= 0 && rank <= H5S_MAX_RANK)
        H5Sget_simple_extent_dims(space, dims, NULL);
    if (space >= 0)
        H5Sclose(space);
    double stored = (double)H5Dget_storage_size(ds);
    hid_t type = H5Dget_type(ds);
    H5T_class_t kind = type >= 0 ? H5Tget_class(type) : H5T_NO_CLASS;
    if (type >= 0)
        H5Tclose(type);
    H5Dclose(ds);
    if (rank != 1 && rank != 2)
        return vh_fail(r, "/VTKHDF/%s: expected a dataset of rank 1 or 2, found rank %d", path, rank);
    if (kind != H5T_INTEGER && kind != H5T_FLOAT)
        return vh_fail(r, "/VTKHDF/%s: expected integers or floating-point numbers, found HDF5 type class %d", path,
                       (int)kind);
    *rows = (int64_t)dims[0];
    *cols = rank == 2 ? (int64_t)dims[1] : 1;
    double count = (double)dims[0] * (double)*cols;
    /* A dataset may declare more than it stores (fill values): refuse what no file of this size holds. */
    if (dims[0] > (hsize_t)INT64_MAX / 8 || count > (stored + 4096.0) * DEFLATE_MAX_RATIO)
        return vh_fail(r, "/VTKHDF/%s: declares %.0f values but stores %.0f bytes", path, count, stored);
    return 0;
}

int vh_read_rows(vh_reader *r, const char *path, int64_t first, int64_t count, int64_t cols, hid_t memtype,
                 void *dst, const char *what)
{
    int64_t rows, have_cols;
    if (vh_shape(r, path, &rows, &have_cols))
        return -1;
    if (have_cols != cols)
        return vh_fail(r, "/VTKHDF/%s: expected %lld column%s, found %lld", path, (long long)cols,
                       cols == 1 ? "" : "s", (long long)have_cols);
    if (first < 0 || count < 0 || first > rows || count > rows - first) /* (the end in double: no overflow) */
        return vh_fail(r, "/VTKHDF/%s: %s: expected rows %lld to %.0f, found %lld rows", path, what,
                       (long long)first, (double)first + (double)count - 1, (long long)rows);
    if (count == 0)
        return 0;
    hid_t ds = H5Dopen2(r->root, path, H5P_DEFAULT);
    hid_t space = ds >= 0 ? H5Dget_space(ds) : -1;
    hsize_t start[2] = {(hsize_t)first, 0}, size[2] = {(hsize_t)count, (hsize_t)cols};
    int rank = space >= 0 ? H5Sget_simple_extent_ndims(space) : 0;
    hid_t mem = H5Screate_simple(rank, size, NULL);
    int ok = ds >= 0 && space >= 0 && mem >= 0 &&
             H5Sselect_hyperslab(space, H5S_SELECT_SET, start, NULL, size, NULL) >= 0 &&
             H5Dread(ds, memtype, mem, space, H5P_DEFAULT, dst) >= 0;
    if (mem >= 0)
        H5Sclose(mem);
    if (space >= 0)
        H5Sclose(space);
    if (ds >= 0)
        H5Dclose(ds);
    if (!ok)
        return vh_fail(r, "/VTKHDF/%s: %s: cannot read rows %lld to %lld as numbers (damaged data, or a filter "
                       "this HDF5 lacks)", path, what, (long long)first, (long long)(first + count - 1));
    return 0;
}

int vh_read_ints(vh_reader *r, const char *path, int64_t want, int64_t **out, int64_t *count)
{
    int64_t rows, cols;
    *out = NULL;
    if (vh_shape(r, path, &rows, &cols))
        return -1;
    if (cols != 1)
        return vh_fail(r, "/VTKHDF/%s: expected one column, found %lld", path, (long long)cols);
    if (want >= 0 && rows != want)
        return vh_fail(r, "/VTKHDF/%s: expected %lld values, found %lld", path, (long long)want, (long long)rows);
    if (!(*out = malloc(sizeof **out * (size_t)(rows ? rows : 1))))
        return vh_fail(r, "/VTKHDF/%s: out of memory for %lld values", path, (long long)rows);
    if (vh_read_rows(r, path, 0, rows, 1, H5T_NATIVE_INT64, *out, "all of it")) {
        free(*out);
        *out = NULL;
        return -1;
    }
    if (count)
        *count = rows;
    return 0;
}

#endif
