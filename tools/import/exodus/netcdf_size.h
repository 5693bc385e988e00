/* The size a classic netCDF file must have, read from its header (used to refuse truncated files,
 * which the netCDF library would silently read as zeros). */
#ifndef TPK_NETCDF_SIZE_H
#define TPK_NETCDF_SIZE_H

#include <stddef.h>
#include <stdint.h>

/* 0 with *expected = the bytes the header's variables reach, 1 when the data is not classic netCDF
 * (e.g. netCDF-4/HDF5), -1 when the header itself is malformed or cut short. */
int tpk_netcdf_classic_size(const unsigned char *data, size_t size, uint64_t *expected);

#endif
