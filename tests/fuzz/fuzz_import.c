/* One fuzz target per importer of the registry (tools/import/registry.c): CMake builds this file once
 * for each row that has a memory reader, as fuzz_<name>, with TPK_FUZZ_FORMAT naming the row. The first
 * input byte picks one of the row's extensions for the name the reader sees (UGRID takes its encoding
 * from it); the rest is the file. Each input is read strictly (convert) and leniently (tetpack check:
 * wrong-length field arrays recorded and dropped); a strict read's higher-order cells are then split whole
 * (mesh/higher_order.h) as the converter splits them, and a small mesh (up to 32 cells) is then split
 * into tets and refined to a bound as convert --max-error does (convert/refine.h). A failure must leave the mesh empty and say why;
 * a crash, a sanitizer report or a leak is a bug. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "convert/pipeline.h"
#include "convert/refine.h"
#include "import/importers.h"
#include "mesh/higher_order.h"
#include "library_defect.h"
#include "support.h"

#ifndef TPK_FUZZ_FORMAT
#error "TPK_FUZZ_FORMAT names the registry row to fuzz"
#endif

static void ignore_warning(void *user, const char *text)
{
    (void)user;
    (void)text;
}

/* "fuzz" + the pick-th (modulo their count) of the row's space-separated extensions. */
static void file_name(const char *extensions, unsigned pick, char *name, size_t cap)
{
    unsigned count = 0;
    for (const char *at = extensions; *at; at += strspn(at, " "))
        if (*at != ' ')
            count++, at += strcspn(at, " ");
    const char *at = extensions + strspn(extensions, " ");
    for (unsigned k = count ? pick % count : 0; k > 0; k--) {
        at += strcspn(at, " ");
        at += strspn(at, " ");
    }
    snprintf(name, cap, "fuzz%.*s", (int)strcspn(at, " "), at);
}

/* A reader that cannot allocate must say so, not crash: ASan returns NULL for an allocation past its
 * limit (HDF5 asks for 2^52 bytes when a damaged header says so) rather than reporting it. */
const char *__asan_default_options(void);
const char *__asan_default_options(void)
{
    return "allocator_may_return_null=1";
}

/* The rows whose memory reader calls a library we do not control, with that library's file name (the
 * registry's `isolated` rows read in a child process; XDMF's memory reader does not touch HDF5). */
static const struct {
    const char *format, *library;
} library_readers[] = {{"vtkhdf", "libhdf5"}};

/* LeakSanitizer: what HDF5 1.10.8 leaks on its own error paths (an H5FL block per failed open). */
const char *__lsan_default_suppressions(void);
const char *__lsan_default_suppressions(void)
{
    return strcmp(TPK_FUZZ_FORMAT, "vtkhdf") == 0 ? "leak:libhdf5\n" : "";
}

typedef struct read_job {
    const tpk_import_format *row;
    const char *name;
    const uint8_t *data;
    size_t size;
} read_job;

static void read_both_ways(void *user);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const tpk_import_format *row;
    if (!row && !(row = tpk_import_format_named(TPK_FUZZ_FORMAT, NULL)))
        abort();
    if (size == 0 || !row->read_memory)
        return 0;
    char name[64];
    file_name(row->extensions, data[0], name, sizeof name);
    if (getenv("TPK_FUZZ_KEEP")) { /* ./dev fuzz: the file as tetpack would read it */
        char path[512];
        snprintf(path, sizeof path, "%s/%s", tpk_fuzz_fresh_dir(NULL), name);
        tpk_fuzz_write(path, data + 1, size - 1);
    }
    read_job job = {row, name, data, size};
    static const char *library;
    static int looked;
    if (!looked) {
        looked = 1;
        for (size_t i = 0; i < sizeof library_readers / sizeof library_readers[0]; i++)
            if (strcmp(library_readers[i].format, TPK_FUZZ_FORMAT) == 0)
                library = library_readers[i].library;
    }
    /* The bound tetpack's isolated reader gives the library (tools/import/isolate.c): what the file could
     * decode to at zlib's largest ratio (1032:1) plus 1 GiB, here on top of what the process maps now (the
     * sanitizer's shadow), for the screen's child and the read in process alike; an allocation past it
     * fails (NULL). HDF5 took 1.9 GB under ASan for a 14 kB file of the campaign without it. */
    if (library)
        tpk_fuzz_limit_address_space(1024 + (long)((1032.0 * (double)size) / 1048576.0));
    /* the screen's time: under half of the campaign's -timeout=20, the read in process coming after it */
    if (library && tpk_fuzz_library_defect(read_both_ways, &job, library, 5))
        return 0; /* the library's own defect, which tetpack survives by reading in a child */
    read_both_ways(&job);
    return 0;
}

/* What convert --max-error does with a small mesh: cells kept, higher-order ones split, tets on the file
 * grid, ids led back to the source's, refined (a coarse bound and few tets, for the fuzzer's pace). Cells
 * the bound cannot cover (pyramids, Lagrange cells past order 2, ...) are split and tetrahedralized as a
 * plain convert does, not refined. */
static void refine_small(tpk_mesh *mesh, const char *name, tpk_diag *diag)
{
    tpk_refine_cells cells;
    tpk_higher_split split;
    memset(&split, 0, sizeof split);
    if (mesh->cell_count > 32 || tpk_refine_cells_copy(mesh, &cells) != 0)
        return;
    tpk_tetmesh tets;
    memset(&tets, 0, sizeof tets);
    int bounded = tpk_refine_unbounded_cell(&cells) < 0;
    if (tpk_split_higher_order(mesh, name, &split, diag) == 0 &&
        tpk_tetrahedralize(mesh, NULL, 0, TPK_TETRA_FILE_GRID, &tets, diag) == 0 && bounded) {
        for (int64_t v = 0; split.cell_source && v < tets.vertex_count; v++)
            if (tets.vertex_source[v] >= split.source_points)
                tets.vertex_source[v] = -1;
        for (int64_t t = 0; split.cell_source && t < tets.tet_count; t++)
            tets.tet_source[t] = split.cell_source[tets.tet_source[t]];
        tpk_refine_options options = {.max_error = 0.05, .threads = 1, .max_tets = 4096};
        tpk_refine_report report;
        tpk_refine_max_error(&tets, &cells, &options, &report, diag);
    }
    tpk_tetmesh_free(&tets);
    free(split.cell_source);
    tpk_refine_cells_free(&cells);
}

static void read_both_ways(void *user)
{
    const read_job *job = user;
    const tpk_import_format *row = job->row;
    const char *name = job->name;
    const uint8_t *data = job->data;
    size_t size = job->size;
    for (int lenient = 0; lenient < 2; lenient++) {
        tpk_mesh mesh;
        tpk_diag diag;
        memset(&diag, 0, sizeof diag);
        diag.warn = ignore_warning;
        diag.lenient_fields = lenient;
        if (row->read_memory(name, (const char *)data + 1, size - 1, &mesh, &diag) == 0) {
            /* what convert does next with a mesh read whole: its higher-order cells split at their nodes */
            tpk_higher_split split;
            if (!lenient && mesh.cell_count <= 32)
                refine_small(&mesh, name, &diag);
            else if (!lenient && tpk_split_higher_order(&mesh, name, &split, &diag) == 0)
                free(split.cell_source);
            tpk_mesh_free(&mesh);
        }
        else if (mesh.points || mesh.cell_conn || mesh.fields || mesh.cell_count || !diag.message[0])
            abort(); /* a failure must leave the mesh empty and say why */
    }
}
