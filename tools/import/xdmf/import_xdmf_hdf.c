/* XDMF importer: HDF5 datasets through the HDF5 C library (serial), read as doubles whatever their
 * stored type. The last file stays open: a time series reads many datasets from one file. Built
 * without HDF5 (TETPACK_WITH_HDF5=OFF), HDF data items are refused with a message saying so. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "import_xdmf_internal.h"

#ifdef TPK_HAVE_HDF5
#include <hdf5.h>

/* zlib's deflate packs at most about this many bytes into one (HDF5's common filter). */
#define DEFLATE_MAX_RATIO 1032.0

static int open_file(xdmf_reader *r, const xdmf_node *item, const char *path)
{
    if (r->hdf && r->hdf_path && !strcmp(r->hdf_path, path))
        return 0;
    xdmf_hdf_close(r);
    hid_t fid = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (fid < 0)
        return xdmf_fail(r, item, "cannot open the HDF5 file %s (%s)", path,
                         access(path, R_OK) ? strerror(errno) : "not an HDF5 file, or damaged");
    hid_t *held = malloc(sizeof *held);
    r->hdf_path = strdup(path);
    if (!held || !r->hdf_path) {
        free(held);
        H5Fclose(fid);
        return xdmf_fail(r, item, "out of memory");
    }
    *held = fid;
    r->hdf = held;
    return 0;
}

/* The dataset's element count, checked against `want` and against the bytes it stores. */
static int check_extent(xdmf_reader *r, const xdmf_node *item, const char *path, const char *dataset, hid_t ds,
                        int64_t want)
{
    hid_t space = H5Dget_space(ds);
    int rank = space >= 0 ? H5Sget_simple_extent_ndims(space) : -1;
    hsize_t dims[H5S_MAX_RANK];
    if (rank < 0 || H5Sget_simple_extent_dims(space, dims, NULL) < 0) {
        if (space >= 0)
            H5Sclose(space);
        return xdmf_fail(r, item, "%s:%s: cannot read the dataset's shape", path, dataset);
    }
    H5Sclose(space);
    char shape[160] = "";
    double count = 1;
    for (int k = 0; k < rank; k++) {
        count *= (double)dims[k];
        size_t used = strlen(shape);
        snprintf(shape + used, sizeof shape - used, "%s%llu", k ? " x " : "", (unsigned long long)dims[k]);
    }
    if (count != (double)want)
        return xdmf_fail(r, item, "%s:%s: expected %lld values (the DataItem's Dimensions), found a dataset of "
                         "%s = %.0f", path, dataset, (long long)want, rank ? shape : "one value", count);
    /* A dataset may declare more than it stores (fill values): refuse what no file of this size holds. */
    double stored = (double)H5Dget_storage_size(ds);
    if (count > (stored + 4096.0) * DEFLATE_MAX_RATIO)
        return xdmf_fail(r, item, "%s:%s: declares %.0f values but stores %.0f bytes", path, dataset, count, stored);
    return 0;
}

int xdmf_read_hdf(xdmf_reader *r, const xdmf_node *item, const char *path, const char *dataset, int64_t want,
                  xdmf_values *out)
{
    H5E_auto2_t old_func;
    void *old_data;
    H5Eget_auto2(H5E_DEFAULT, &old_func, &old_data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL); /* the message below says what failed; no HDF5 stack dump */
    int rc = open_file(r, item, path);
    hid_t ds = -1;
    if (rc == 0 && (H5Lexists(*(hid_t *)r->hdf, dataset, H5P_DEFAULT) <= 0 ||
                    (ds = H5Dopen2(*(hid_t *)r->hdf, dataset, H5P_DEFAULT)) < 0))
        rc = xdmf_fail(r, item, "%s: expected a dataset %s, found none", path, dataset);
    if (rc == 0)
        rc = check_extent(r, item, path, dataset, ds, want);
    if (rc == 0 && !(out->v = malloc(sizeof *out->v * (size_t)(want ? want : 1))))
        rc = xdmf_fail(r, item, "out of memory for %lld values", (long long)want);
    if (rc == 0 && want && H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out->v) < 0)
        rc = xdmf_fail(r, item, "%s:%s: cannot read the dataset as numbers", path, dataset);
    if (ds >= 0)
        H5Dclose(ds);
    H5Eset_auto2(H5E_DEFAULT, old_func, old_data);
    if (rc == 0)
        out->count = want;
    return rc;
}

void xdmf_hdf_close(xdmf_reader *r)
{
    if (r->hdf)
        H5Fclose(*(hid_t *)r->hdf);
    free(r->hdf);
    free(r->hdf_path);
    r->hdf = NULL;
    r->hdf_path = NULL;
}

#else

int xdmf_read_hdf(xdmf_reader *r, const xdmf_node *item, const char *path, const char *dataset, int64_t want,
                  xdmf_values *out)
{
    (void)path, (void)dataset, (void)want, (void)out;
    return xdmf_fail(r, item, "HDF data: this tetpack was built without HDF5 (TETPACK_WITH_HDF5=OFF); configure it "
                     "with -DTETPACK_WITH_HDF5=ON (Debian: libhdf5-dev)");
}

void xdmf_hdf_close(xdmf_reader *r)
{
    (void)r;
}

#endif
