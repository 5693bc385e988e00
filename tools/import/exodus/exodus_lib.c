/* The Exodus II library loaded on first use (exodus_lib.h). TPK_EXODUS_SONAME is the name the build
 * linked against (tools/CMakeLists.txt reads it from the library). */
#include "exodus_lib.h"

#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>

#ifndef TPK_EXODUS_SONAME
#define TPK_EXODUS_SONAME "libexoIIv2c.so"
#endif

static pthread_once_t once = PTHREAD_ONCE_INIT;
static tpk_exodus_lib lib;
static int loaded;
static char reason[256];

/* dlsym into the pointer p (a function pointer held as an object: POSIX gives dlsym's result so). */
static int resolve(void *handle, void *p, const char *name)
{
    void *symbol = dlsym(handle, name);
    if (!symbol) {
        snprintf(reason, sizeof reason, "%s has no %s", TPK_EXODUS_SONAME, name);
        return -1;
    }
    memcpy(p, &symbol, sizeof symbol);
    return 0;
}

static void load(void)
{
    void *handle = dlopen(TPK_EXODUS_SONAME, RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
        const char *error = dlerror();
        snprintf(reason, sizeof reason, "%s", error ? error : "dlopen failed");
        return;
    }
    int rc = resolve(handle, &lib.opts, "ex_opts") || resolve(handle, &lib.open_int, "ex_open_int") ||
             resolve(handle, &lib.close, "ex_close") || resolve(handle, &lib.get_init, "ex_get_init") ||
             resolve(handle, &lib.inquire_int, "ex_inquire_int") || resolve(handle, &lib.get_coord, "ex_get_coord") ||
             resolve(handle, &lib.get_elem_blk_ids, "ex_get_elem_blk_ids") ||
             resolve(handle, &lib.get_elem_block, "ex_get_elem_block") ||
             resolve(handle, &lib.get_elem_conn, "ex_get_elem_conn") ||
             resolve(handle, &lib.get_variable_param, "ex_get_variable_param") ||
             resolve(handle, &lib.get_variable_name, "ex_get_variable_name") || resolve(handle, &lib.get_var, "ex_get_var") ||
             resolve(handle, &lib.get_object_truth_vector, "ex_get_object_truth_vector") ||
             resolve(handle, &lib.get_id_map, "ex_get_id_map") ||
             resolve(handle, &lib.set_int64_status, "ex_set_int64_status") || resolve(handle, &lib.get_all_times, "ex_get_all_times");
    loaded = rc == 0; /* the handle stays open for the process: the library keeps state for open files */
}

const tpk_exodus_lib *tpk_exodus_lib_load(char *why, size_t size)
{
    pthread_once(&once, load);
    if (!loaded && why && size)
        snprintf(why, size, "%s", reason);
    return loaded ? &lib : NULL;
}
