/* The Exodus II library, loaded when the first Exodus file is read (dlopen), not at every start of the
 * tools: Debian's libexoIIv2c brings netCDF built for MPI, HDF5 for MPI, Open MPI, curl, Kerberos and
 * TLS, 16 of the 83 libraries the tools would load, and about a third of a process's start-up
 * (bench/README). The functions the importer calls, with the library's own prototypes. */
#ifndef TPK_EXODUS_LIB_H
#define TPK_EXODUS_LIB_H

#include <exodusII.h>
#include <stddef.h>

typedef struct tpk_exodus_lib {
    __typeof__(ex_opts) *opts;
    __typeof__(ex_open_int) *open_int;
    __typeof__(ex_close) *close;
    __typeof__(ex_get_init) *get_init;
    __typeof__(ex_inquire_int) *inquire_int;
    __typeof__(ex_get_coord) *get_coord;
    __typeof__(ex_get_elem_blk_ids) *get_elem_blk_ids;
    __typeof__(ex_get_elem_block) *get_elem_block;
    __typeof__(ex_get_elem_conn) *get_elem_conn;
    __typeof__(ex_get_variable_param) *get_variable_param;
    __typeof__(ex_get_variable_name) *get_variable_name;
    __typeof__(ex_get_var) *get_var;
    __typeof__(ex_get_object_truth_vector) *get_object_truth_vector;
    __typeof__(ex_get_id_map) *get_id_map;
    __typeof__(ex_set_int64_status) *set_int64_status;
    __typeof__(ex_get_all_times) *get_all_times;
} tpk_exodus_lib;

/* The library, loaded once (thread-safe); NULL when it cannot be, with the reason in why. */
const tpk_exodus_lib *tpk_exodus_lib_load(char *why, size_t size);

#endif
