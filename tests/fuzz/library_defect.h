/* For the fuzz targets of importers whose files a library we do not control parses (registry rows with
 * `isolated`: HDF5, netCDF, CGNS). tetpack reads those in a child process (tools/import/isolate.c), so a
 * crash inside the library is an error, not a tetpack crash; the fuzzer still runs the reader in
 * process, for coverage. Before it does, the input is read once in a child whose sanitizer report is
 * kept: when the first frame of the report (or of the stack when its time ran out) that is neither the
 * sanitizer runtime, libFuzzer nor the C library lies in the named library, the defect is the library's and the target skips the input. A fault
 * anywhere else (in tetpack) is left to the in-process run, where libFuzzer records it. Not a target
 * itself (no fuzz_ prefix). */
#ifndef TPK_FUZZ_LIBRARY_DEFECT_H
#define TPK_FUZZ_LIBRARY_DEFECT_H

/* Runs read(user) in a child process (for at most `seconds`); 1 when it ended in a defect of a library
 * whose file name contains one of the '|'-separated `libraries` ("libhdf5|libnetcdf"), 0 otherwise (it
 * read, failed cleanly, or crashed in tetpack's own code). TPK_FUZZ_SHOW_REPORT=1 in the environment
 * prints each failed child's report and the verdict. */
int tpk_fuzz_library_defect(void (*read)(void *user), void *user, const char *libraries, int seconds);

/* From now on, this process may map at most `mb` MiB more than it maps now (RLIMIT_AS): a larger
 * allocation fails, and returns NULL with ASan's allocator_may_return_null. */
void tpk_fuzz_limit_address_space(long mb);

#endif
