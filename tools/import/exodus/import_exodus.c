/* Exodus II importer (.exo, .e, .g, .ex2), through the Exodus library (netCDF classic or netCDF-4):
 * element blocks of tetrahedra, hexahedra, wedges and pyramids become cells in VTK node order, which
 * Exodus shares for the corners of all four: its side tables (SEACAS exodus-element-types.md) list the
 * same outward faces as VTK's cells (hexahedra also checked on SEACAS's files). Higher-order blocks are
 * kept whole as VTK's quadratic types (TETRA10, HEX20, HEX27, WEDGE15, WEDGE18, PYRAMID13; TETRA14 as a
 * quadratic tetra with its 4 face centres after the 10, TETRA15 as VTK's 15-node Lagrange tetra, PYRAMID14
 * as a quadratic pyramid with its base centre after the 13: mesh/higher_order.h): Exodus lists the
 * vertical mid-edges of hexahedra and wedges before the top ones, VTK after. Blocks of lower dimension
 * (shells, bars, spheres) are dropped with a count. Nodal and element variables become point and cell
 * fields with every time step, and the time values are kept. The node and element number maps become the mesh's global_point_ids and global_cell_ids
 * (tetpack-mpi matches the points of per-processor files by them and numbers the source cells). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "import/importers.h"
#include "exodus_lib.h"
#include "netcdf_size.h"
#include "tetpack_format.h"
#include "base/parallel.h"
#include "base/text_scan.h"

typedef struct block_kind {
    const char *prefix; /* element type names start with it (case-insensitive) */
    int dim, vtk_type, corners;
} block_kind;

/* Exodus element type names (as written by Cubit, SEACAS and exodus.py): TETRA, TETRA4, TETRA10, TET4,
 * HEX, HEX8, HEX20, HEX27, ... The first match wins, so longer prefixes come first. */
static const block_kind kinds[] = {
    {"TETRA", 3, 10, 4}, {"TET", 3, 10, 4},    {"HEX", 3, 12, 8},     {"WEDGE", 3, 13, 6},  {"PYRAMID", 3, 14, 5},
    {"PYRA", 3, 14, 5},  {"SHELL", 2, 0, 0},   {"QUAD", 2, 0, 0},     {"TRI", 2, 0, 0},     {"BEAM", 1, 0, 0},
    {"BAR", 1, 0, 0},    {"TRUSS", 1, 0, 0},   {"SPHERE", 0, 0, 0},   {"CIRCLE", 0, 0, 0},  {"NULL", 0, 0, 0},
};

/* A volume block's cells as VTK keeps them: its type and node count, from Exodus's nodes per element. */
static int kept_type(const block_kind *kind, int64_t per, int *kept)
{
    static const struct { int linear, at_least, vtk, kept; } quadratic[] = {
        {10, 15, 71, 15}, {10, 14, 24, 14}, {10, 10, 24, 10}, {12, 27, 29, 27}, {12, 20, 25, 20},
        {13, 18, 32, 18}, {13, 15, 26, 15}, {14, 14, 27, 14}, {14, 13, 27, 13}};
    for (size_t i = 0; i < sizeof quadratic / sizeof quadratic[0]; i++)
        if (quadratic[i].linear == kind->vtk_type && per >= quadratic[i].at_least) {
            *kept = quadratic[i].kept;
            return quadratic[i].vtk;
        }
    *kept = kind->corners;
    return kind->vtk_type;
}

/* The Exodus node that VTK node k of a kept cell of VTK type `vtk` is. */
static int exodus_node(int vtk, int k)
{
    /* TETRA14/15: VTK's face centres 012, 013, 123, 023 (vtkLagrangeTetra's 15 nodes), then the body
     * centre; Exodus's 012, 123, 023, 013 (SEACAS's Tet14/Tet15 topologies: faces 4, 2, 3, 1), then the
     * body centre. */
    static const int tet15_faces[5] = {10, 13, 11, 12, 14};
    if ((vtk == 24 || vtk == 71) && k >= 10)
        return tet15_faces[k - 10];
    /* HEX27: VTK's face centres x-, x+, y-, y+, z-, z+ then the cell centre; Exodus has the centre (20)
     * first, then z-, z+, x-, x+, y-, y+ (SEACAS's Hex27 topology). */
    static const int hex27_faces[7] = {23, 24, 25, 26, 21, 22, 20};
    if (vtk == 29 && k >= 20)
        return hex27_faces[k - 20];
    if ((vtk == 25 || vtk == 29) && k >= 12) /* VTK: top mid-edges 12-15, then vertical 16-19; Exodus the other way */
        return k < 16 ? k + 4 : k - 4;
    if ((vtk == 26 || vtk == 32) && k >= 9 && k < 15) /* the same for wedges: 9-11 and 12-14 (WEDGE18's quad-face
                                                         centres 15-17 as VTK's) */
        return k < 12 ? k + 3 : k - 3;
    return k;
}

static const block_kind *kind_of(const char *type)
{
    for (size_t i = 0; i < sizeof kinds / sizeof kinds[0]; i++)
        if (!strncasecmp(type, kinds[i].prefix, strlen(kinds[i].prefix)))
            return &kinds[i];
    return NULL;
}

typedef struct exo_block {
    int64_t id, count, nodes_per;
    const block_kind *kind;
    int vtk_type, kept; /* as its cells are kept (kept_type) */
    char type[MAX_STR_LENGTH + 1];
    int64_t first_cell; /* index of its first kept cell, or -1 when dropped */
} exo_block;

typedef struct exo_reader {
    const char *path;
    int exoid;
    int64_t nodes, elems, block_count, steps;
    exo_block *blocks;
    tpk_diag *diag;
    const tpk_exodus_lib *x; /* the library's functions (exodus_lib.h) */
} exo_reader;

/* The passes over what the library read (points interleaved, ids made 0-based and checked, values to
 * float) run on all threads (convert's --threads) in contiguous ranges, each item written by one worker
 * alone: the mesh is the same for any count. The library's own reads stay serial (netCDF is not
 * thread-safe). A pass that finds a bad id only flags it; the serial loop behind it then finds the
 * first one and words the message, so that too is the same for any count. */
#define EXO_GRAIN ((int64_t)1 << 16)

static int exo_threads(int64_t count)
{
    return tpk_threads_for(count, tpk_thread_count(0), EXO_GRAIN);
}

typedef struct interleave_job {
    double *points;
    double *const *xyz;
} interleave_job;

static void interleave_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    const interleave_job *job = ctx;
    (void)worker;
    for (int64_t v = begin; v < end; v++)
        for (int k = 0; k < 3; k++)
            job->points[3 * v + k] = job->xyz[k][v];
}

/* Values of one step (double, as the library gives them) to float; NaN where the block lacks them. */
typedef struct to_float_job {
    float *dst;
    const double *src; /* NULL: NaN */
} to_float_job;

static void to_float_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    const to_float_job *job = ctx;
    (void)worker;
    for (int64_t i = begin; i < end; i++)
        job->dst[i] = job->src ? (float)job->src[i] : NAN;
}

static void to_float(float *dst, const double *src, int64_t n)
{
    to_float_job job = {dst, src};
    tpk_parallel_for(n, exo_threads(n), to_float_range, &job);
}

static int read_points(exo_reader *r, tpk_mesh *out, int dim)
{
    double *xyz[3];
    out->points = malloc(sizeof *out->points * 3 * (size_t)(r->nodes ? r->nodes : 1));
    for (int k = 0; k < 3; k++)
        xyz[k] = calloc((size_t)(r->nodes ? r->nodes : 1), sizeof(double));
    int rc = !out->points || !xyz[0] || !xyz[1] || !xyz[2]
                 ? tpk_diag_fail(r->diag, "%s: out of memory for %lld nodes", r->path, (long long)r->nodes)
             : r->x->get_coord(r->exoid, xyz[0], xyz[1], dim == 3 ? xyz[2] : NULL) < 0
                 ? tpk_diag_fail(r->diag, "%s: cannot read the node coordinates", r->path)
                 : 0;
    interleave_job job = {out->points, xyz};
    if (rc == 0)
        tpk_parallel_for(r->nodes, exo_threads(r->nodes), interleave_range, &job);
    for (int k = 0; k < 3; k++)
        free(xyz[k]);
    out->point_count = r->nodes;
    return rc;
}

/* One block's kept cells from the library's connectivity: types, offsets and 0-based ids, in parallel;
 * bad[worker] set where an id is out of range (block_cells_checked then words the message). */
typedef struct block_job {
    const exo_block *blk;
    const int *ids_in;
    int64_t nodes, c0, at0;
    tpk_mesh *out;
    int bad[TPK_MAX_THREADS];
} block_job;

static void block_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    block_job *job = ctx;
    const exo_block *blk = job->blk;
    int node[32];
    for (int k = 0; k < blk->kept; k++)
        node[k] = exodus_node(blk->vtk_type, k);
    int bad = 0;
    for (int64_t e = begin; e < end; e++) {
        int64_t c = job->c0 + e, at = job->at0 + e * blk->kept;
        const int *in = job->ids_in + e * blk->nodes_per;
        job->out->cell_types[c] = (uint8_t)blk->vtk_type;
        job->out->cell_offsets[c] = at;
        for (int k = 0; k < blk->kept; k++) {
            int id = in[node[k]];
            bad |= id < 1 || id > job->nodes;
            job->out->cell_conn[at + k] = id - 1;
        }
    }
    job->bad[worker] |= bad;
}

/* The block's cells at out cell c0, connectivity entry at0: on all threads, then, if an id was out of
 * range, the serial loop for the first one. */
static int block_cells(exo_reader *r, const exo_block *blk, const int *ids_in, int64_t c0, int64_t at0, tpk_mesh *out)
{
    block_job job = {.blk = blk, .ids_in = ids_in, .nodes = r->nodes, .c0 = c0, .at0 = at0, .out = out};
    int threads = exo_threads(blk->count), bad = 0;
    tpk_parallel_for(blk->count, threads, block_range, &job);
    for (int w = 0; w < threads; w++)
        bad |= job.bad[w];
    for (int64_t e = 0; bad && e < blk->count; e++)
        for (int k = 0; k < blk->kept; k++) {
            int id = ids_in[e * blk->nodes_per + exodus_node(blk->vtk_type, k)];
            if (id < 1 || id > r->nodes)
                return tpk_diag_fail(r->diag, "%s: block %lld element %lld uses node %d, expected 1 to %lld",
                                     r->path, (long long)blk->id, (long long)e + 1, id, (long long)r->nodes);
        }
    return 0;
}

/* Block ids, kinds and counts; the kept cells' connectivity into out (1-based ids checked). */
static int read_blocks(exo_reader *r, tpk_mesh *out)
{
    int *ids = calloc((size_t)(r->block_count ? r->block_count : 1), sizeof *ids);
    r->blocks = calloc((size_t)(r->block_count ? r->block_count : 1), sizeof *r->blocks);
    if (!ids || !r->blocks || (r->block_count && r->x->get_elem_blk_ids(r->exoid, ids) < 0)) {
        free(ids);
        return tpk_diag_fail(r->diag, "%s: cannot read the element block ids", r->path);
    }
    int64_t cells = 0, conn = 0, dropped = 0, unused = 0;
    for (int64_t b = 0; b < r->block_count; b++) {
        exo_block *blk = &r->blocks[b];
        int count = 0, per = 0, attrs = 0;
        blk->id = ids[b];
        if (r->x->get_elem_block(r->exoid, ids[b], blk->type, &count, &per, &attrs) < 0) {
            free(ids);
            return tpk_diag_fail(r->diag, "%s: cannot read element block %lld", r->path, (long long)blk->id);
        }
        blk->count = count, blk->nodes_per = per, blk->kind = kind_of(blk->type), blk->first_cell = -1;
        if (!blk->kind) {
            free(ids);
            return tpk_diag_fail(r->diag, "%s: element block %lld has element type '%s', which this reader does not "
                                          "know (tetra, hex, wedge and pyramid blocks are read; shells, bars and "
                                          "spheres dropped)",
                                 r->path, (long long)blk->id, blk->type);
        }
        if (blk->kind->dim < 3) {
            dropped += count;
            continue;
        }
        if (per < blk->kind->corners) {
            free(ids);
            return tpk_diag_fail(r->diag, "%s: element block %lld (%s) has %d nodes per element, expected at least %d",
                                 r->path, (long long)blk->id, blk->type, per, blk->kind->corners);
        }
        blk->first_cell = cells;
        cells += count;
        int kept;
        blk->vtk_type = kept_type(blk->kind, per, &kept);
        blk->kept = kept;
        conn += (int64_t)count * kept;
        if (kept < per && blk->vtk_type != blk->kind->vtk_type)
            unused += count;
    }
    free(ids);
    if (dropped)
        tpk_diag_warn(r->diag, "%s: dropped %lld elements that are not volumes (shells, bars, spheres)", r->path,
                      (long long)dropped);
    if (unused)
        tpk_diag_warn(r->diag, "%s: %lld higher-order elements read without some of their nodes (each as the fullest "
                      "kind its first nodes make: HEX27, WEDGE18, TETRA15, TETRA14, PYRAMID14 or the quadratic ones)",
                      r->path, (long long)unused);
    if (cells == 0)
        return tpk_diag_fail(r->diag, "%s: no volume cells (%lld elements in %lld blocks, none tetra, hex, wedge or "
                             "pyramid)",
                             r->path, (long long)r->elems, (long long)r->block_count);
    out->cell_count = cells;
    out->cell_types = malloc((size_t)cells);
    out->cell_offsets = malloc(sizeof *out->cell_offsets * (size_t)(cells + 1));
    out->cell_conn = malloc(sizeof *out->cell_conn * (size_t)conn);
    if (!out->cell_types || !out->cell_offsets || !out->cell_conn)
        return tpk_diag_fail(r->diag, "%s: out of memory for %lld cells", r->path, (long long)cells);
    int64_t c = 0, at = 0;
    for (int64_t b = 0; b < r->block_count; b++) {
        exo_block *blk = &r->blocks[b];
        if (blk->first_cell < 0)
            continue;
        int *ids_in = malloc(sizeof *ids_in * (size_t)(blk->count * blk->nodes_per + 1));
        if (!ids_in || r->x->get_elem_conn(r->exoid, blk->id, ids_in) < 0) {
            free(ids_in);
            return tpk_diag_fail(r->diag, "%s: cannot read the connectivity of block %lld", r->path, (long long)blk->id);
        }
        int rc = block_cells(r, blk, ids_in, c, at, out);
        free(ids_in);
        if (rc)
            return rc;
        c += blk->count;
        at += blk->count * blk->kept;
    }
    out->cell_offsets[c] = at;
    return 0;
}

/* Nodal (point) and element (cell) variables, every step; element variables missing on a block (its
 * truth table) are NaN there. */
static int read_variables(exo_reader *r, tpk_mesh *out, ex_entity_type type)
{
    int count = 0;
    if (r->x->get_variable_param(r->exoid, type, &count) < 0 || count <= 0 || r->steps <= 0)
        return 0;
    int64_t per_step = type == EX_NODAL ? r->nodes : out->cell_count;
    double *buf = malloc(sizeof *buf * (size_t)(r->nodes > r->elems ? r->nodes + 1 : r->elems + 1));
    int *truth = calloc((size_t)count, sizeof *truth);
    char name[MAX_STR_LENGTH + 1];
    int rc = buf && truth ? 0 : tpk_diag_fail(r->diag, "%s: out of memory", r->path);
    for (int v = 1; rc == 0 && v <= count; v++) {
        if (r->x->get_variable_name(r->exoid, type, v, name) < 0)
            snprintf(name, sizeof name, "%s_%d", type == EX_NODAL ? "nodal" : "element", v);
        float *values = malloc(sizeof *values * (size_t)(per_step * r->steps));
        if (!values) {
            rc = tpk_diag_fail(r->diag, "%s: out of memory for variable '%s'", r->path, name);
            break;
        }
        for (int64_t s = 0; rc == 0 && s < r->steps; s++) {
            float *dst = values + s * per_step;
            if (type == EX_NODAL) {
                if (r->x->get_var(r->exoid, (int)s + 1, EX_NODAL, v, 1, r->nodes, buf) < 0)
                    rc = tpk_diag_fail(r->diag, "%s: cannot read nodal variable '%s' at step %lld", r->path, name,
                                       (long long)s + 1);
                if (rc == 0)
                    to_float(dst, buf, r->nodes);
                continue;
            }
            for (int64_t b = 0; rc == 0 && b < r->block_count; b++) {
                exo_block *blk = &r->blocks[b];
                if (blk->first_cell < 0)
                    continue;
                int present = r->x->get_object_truth_vector(r->exoid, EX_ELEM_BLOCK, blk->id, count, truth) < 0 ||
                              truth[v - 1];
                if (present && r->x->get_var(r->exoid, (int)s + 1, EX_ELEM_BLOCK, v, blk->id, blk->count, buf) < 0)
                    present = 0;
                to_float(dst + blk->first_cell, present ? buf : NULL, blk->count);
            }
        }
        if (rc == 0 && tpk_mesh_add_field(out, name, type == EX_NODAL ? TPK_ASSOC_POINT : TPK_ASSOC_TET, 1,
                                          (int)r->steps, values))
            rc = tpk_diag_fail(r->diag, "%s: out of memory", r->path);
        if (rc)
            free(values);
    }
    free(buf);
    free(truth);
    return rc;
}

/* dst[i] = src[i] - 1 for 1-based ids, in parallel (dst may be src); first[worker] = 1 + the index of
 * the first id below 1 in its range (that id left as it was), or 0. */
typedef struct ids_job {
    int64_t *dst;
    const int64_t *src;
    int64_t first[TPK_MAX_THREADS];
} ids_job;

static void ids_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    ids_job *job = ctx;
    for (int64_t i = begin; i < end; i++) {
        int64_t id = job->src[i];
        if (id < 1) {
            job->first[worker] = i + 1;
            return;
        }
        job->dst[i] = id - 1;
    }
}

/* 0 when every id of src[0, n) is at least 1 (dst then holds them 0-based); else 1 + the index of the
 * first that is not (the ranges are in order: the first worker that found one found it), where dst
 * still holds it. */
static int64_t ids_to_zero_based(int64_t *dst, const int64_t *src, int64_t n)
{
    ids_job job = {.dst = dst, .src = src};
    int threads = exo_threads(n);
    tpk_parallel_for(n, threads, ids_range, &job);
    for (int w = 0; w < threads; w++)
        if (job.first[w])
            return job.first[w];
    return 0;
}

/* The node number map (global node ids, 1-based, as a decomposer such as nem_slice writes in each
 * processor's file; 1..nodes when the file stores none) into out->global_point_ids, 0-based. Read as
 * int64 so that ids past 2^31 stay exact. */
static int read_node_map(exo_reader *r, tpk_mesh *out)
{
    out->global_point_ids = malloc(sizeof *out->global_point_ids * (size_t)(r->nodes ? r->nodes : 1));
    if (!out->global_point_ids)
        return tpk_diag_fail(r->diag, "%s: out of memory for the node number map", r->path);
    r->x->set_int64_status(r->exoid, EX_MAPS_INT64_API);
    if (r->x->get_id_map(r->exoid, EX_NODE_MAP, out->global_point_ids) < 0)
        return tpk_diag_fail(r->diag, "%s: cannot read the node number map", r->path);
    int64_t bad = ids_to_zero_based(out->global_point_ids, out->global_point_ids, r->nodes);
    if (bad)
        return tpk_diag_fail(r->diag, "%s: node number map: node %lld has id %lld, expected an id >= 1", r->path,
                             (long long)bad, (long long)out->global_point_ids[bad - 1]);
    return 0;
}

/* The element number map (1-based over the elements of all blocks) for the kept cells, 0-based, into
 * out->global_cell_ids. */
static int read_element_map(exo_reader *r, tpk_mesh *out)
{
    int64_t *map = malloc(sizeof *map * (size_t)(r->elems ? r->elems : 1));
    out->global_cell_ids = malloc(sizeof *out->global_cell_ids * (size_t)out->cell_count);
    if (!map || !out->global_cell_ids) {
        free(map);
        return tpk_diag_fail(r->diag, "%s: out of memory for the element number map", r->path);
    }
    int rc = r->x->get_id_map(r->exoid, EX_ELEM_MAP, map) < 0
                 ? tpk_diag_fail(r->diag, "%s: cannot read the element number map", r->path) : 0;
    int64_t element = 0; /* the block's first element among all elements */
    for (int64_t b = 0; rc == 0 && b < r->block_count; element += r->blocks[b++].count) {
        const exo_block *blk = &r->blocks[b];
        if (element + blk->count > r->elems)
            rc = tpk_diag_fail(r->diag, "%s: element blocks hold more than the %lld elements of the header", r->path,
                               (long long)r->elems);
        int64_t bad = rc == 0 && blk->first_cell >= 0
                          ? ids_to_zero_based(out->global_cell_ids + blk->first_cell, map + element, blk->count) : 0;
        if (bad)
            rc = tpk_diag_fail(r->diag, "%s: element number map: element %lld has id %lld, expected an id >= 1",
                               r->path, (long long)(element + bad), (long long)map[element + bad - 1]);
    }
    free(map);
    return rc;
}

static int read_times(exo_reader *r, tpk_mesh *out)
{
    out->step_count = r->steps > 0 ? (int)r->steps : 1;
    if (r->steps <= 0)
        return 0;
    out->times = malloc(sizeof *out->times * (size_t)r->steps);
    if (!out->times || r->x->get_all_times(r->exoid, out->times) < 0)
        return tpk_diag_fail(r->diag, "%s: cannot read the %lld time values", r->path, (long long)r->steps);
    return 0;
}

int tpk_import_exodus(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    if (!out || !path)
        return tpk_diag_fail(diag, "%s: no path or output mesh given", path ? path : "(null)");
    memset(out, 0, sizeof *out);
    if (diag)
        diag->message[0] = 0;
    /* A classic netCDF file cut short would read as zeros where the data is missing: check its size. */
    const char *bytes;
    size_t size;
    if (tpk_map_file(path, &bytes, &size, diag) != 0)
        return -1;
    uint64_t expected = 0;
    int classic = tpk_netcdf_classic_size((const unsigned char *)bytes, size, &expected);
    tpk_unmap_file(bytes, size);
    if (classic < 0)
        return tpk_diag_fail(diag, "%s: the netCDF header is malformed or cut short", path);
    if (classic == 0 && size < expected)
        return tpk_diag_fail(diag, "%s: truncated: its netCDF header describes %llu bytes of data, the file has %zu",
                             path, (unsigned long long)expected, size);
    int cpu_ws = sizeof(double), io_ws = 0;
    float version = 0;
    char why[256];
    const tpk_exodus_lib *x = tpk_exodus_lib_load(why, sizeof why);
    if (!x)
        return tpk_diag_fail(diag, "%s: cannot read Exodus II files here: the Exodus library did not load (%s)", path,
                             why);
    x->opts(0); /* errors come back as codes; no messages on stderr, no abort */
    exo_reader r = {path, x->open_int(path, EX_READ, &cpu_ws, &io_ws, &version, EX_API_VERS_NODOT), 0, 0, 0, 0, NULL,
                    diag, x};
    if (r.exoid < 0)
        return tpk_diag_fail(diag, "%s: cannot open it as an Exodus II file (netCDF classic or netCDF-4)", path);
    char title[MAX_LINE_LENGTH + 1];
    int dim = 0, nodes = 0, elems = 0, blocks = 0, node_sets = 0, side_sets = 0;
    int rc = x->get_init(r.exoid, title, &dim, &nodes, &elems, &blocks, &node_sets, &side_sets) < 0
                 ? tpk_diag_fail(diag, "%s: cannot read the Exodus header", path)
             : dim != 3 ? tpk_diag_fail(diag, "%s: expected a 3-D mesh, found %d dimensions", path, dim)
                        : 0;
    r.nodes = nodes, r.elems = elems, r.block_count = blocks;
    r.steps = rc == 0 ? x->inquire_int(r.exoid, EX_INQ_TIME) : 0;
    if (rc == 0)
        rc = read_points(&r, out, dim);
    if (rc == 0)
        rc = read_node_map(&r, out);
    if (rc == 0)
        rc = read_blocks(&r, out);
    if (rc == 0)
        rc = read_element_map(&r, out);
    if (rc == 0)
        rc = read_times(&r, out);
    if (rc == 0)
        rc = read_variables(&r, out, EX_NODAL);
    if (rc == 0)
        rc = read_variables(&r, out, EX_ELEM_BLOCK);
    x->close(r.exoid);
    free(r.blocks);
    if (rc == 0)
        snprintf(out->format, sizeof out->format, "exodus-ii");
    else
        tpk_mesh_free(out);
    return rc ? -1 : 0;
}
