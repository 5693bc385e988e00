/* CGNS unstructured zones: element sections to VTK cells. The SIDS (Elements_t, "Unstructured Grid
 * Element Numbering Conventions") number the corners of TETRA_4, PYRA_5, PENTA_6 and HEXA_8 as VTK does
 * for tetra, pyramid, wedge and hexahedron: its face tables give TETRA (1,3,2) (1,2,4) (2,3,4) (3,1,4),
 * PYRA (1,4,3,2) (1,2,5) ..., PENTA (1,2,5,4) (2,3,6,5) (3,1,4,6) (1,3,2) (4,5,6), HEXA (1,4,3,2)
 * (1,2,6,5) ... (5,6,7,8), all outward, which are VTK's faces (tests/test_cgns.c converts the SIDS
 * reference cells and real files and finds none mirrored). Higher-order kinds are kept whole, in VTK's
 * node order (volume_kind). MIXED sections carry a type code before each element; NFACE_n cells list signed
 * NGON_n face numbers (negative: the face's normal points into the cell) and become polyhedra. */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "import_cgns_internal.h"
#include "mesh/polyhedron.h"

int cgns_threads(int64_t items)
{
    return tpk_threads_for(items, tpk_thread_count(0), CGNS_GRAIN);
}

/* CGNS node for each VTK node of the quadratic kinds kept whole: the SIDS list a hexahedron's and a
 * wedge's vertical mid-edges before the top ones (VTK after), and a HEXA_27's face centres bottom, y-,
 * x+, y+, x-, top (VTK: x-, x+, y-, y+, bottom, top); TETRA_10 and PYRA_13 agree with VTK. */
static const signed char penta18[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 13, 14, 9, 10, 11, 15, 16, 17};
static const signed char hexa27[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 16, 17, 18, 19, 12, 13, 14, 15,
                                     24, 22, 21, 23, 20, 25, 26};

typedef struct volume_kind_row {
    const char *prefix;        /* the element type's name, or its start */
    int vtk, nodes;            /* the VTK type kept and its node count */
    const signed char *order;  /* VTK node k is CGNS node order[k]; NULL: the same */
    int reduced;               /* an element of higher order read by its corners alone (TETRA_20, HEXA_64...) */
} volume_kind_row;

/* A volume element type: its VTK type and the nodes kept (*row). 0 for elements of lower dimension (NODE,
 * BAR, TRI, QUAD), -1 for one this reader does not know. PYRA_14 is kept as a quadratic pyramid with its
 * base centre after the 13 nodes (mesh/higher_order.h), as the SIDS lists it. */
static int volume_kind_by_name(CGNS_ENUMT(ElementType_t) type, const volume_kind_row **row)
{
    static const volume_kind_row kinds[] = {
        {"TETRA_10", 24, 10, NULL, 0},  {"PYRA_13", 27, 13, NULL, 0}, {"PYRA_14", 27, 14, NULL, 0},
        {"PENTA_15", 26, 15, penta18, 0}, {"PENTA_18", 32, 18, penta18, 0}, {"HEXA_20", 25, 20, hexa27, 0},
        {"HEXA_27", 29, 27, hexa27, 0}, {"TETRA_4", TPK_CELL_TETRA, 4, NULL, 0},
        {"PYRA_5", TPK_CELL_PYRAMID, 5, NULL, 0}, {"PENTA_6", TPK_CELL_WEDGE, 6, NULL, 0},
        {"HEXA_8", TPK_CELL_HEXAHEDRON, 8, NULL, 0},
        {"TETRA_", TPK_CELL_TETRA, 4, NULL, 1}, {"PYRA_", TPK_CELL_PYRAMID, 5, NULL, 1},
        {"PENTA_", TPK_CELL_WEDGE, 6, NULL, 1}, {"HEXA_", TPK_CELL_HEXAHEDRON, 8, NULL, 1}, {"NODE", 0, 0, NULL, 0},
        {"BAR_", 0, 0, NULL, 0}, {"TRI_", 0, 0, NULL, 0}, {"QUAD_", 0, 0, NULL, 0}};
    const char *name = cg_ElementTypeName(type);
    for (size_t k = 0; name && k < sizeof kinds / sizeof kinds[0]; k++) {
        size_t n = strlen(kinds[k].prefix); /* a name, or with '_' last the start of one (PYRA_5 is not PYRA_55) */
        if (kinds[k].prefix[n - 1] == '_' ? !strncmp(name, kinds[k].prefix, n) : !strcmp(name, kinds[k].prefix)) {
            *row = &kinds[k];
            return kinds[k].vtk ? 1 : 0;
        }
    }
    return -1;
}

/* volume_kind_by_name of every valid type code, found once: a MIXED section asks for each element's. */
static signed char kind_of_code[NofValidElementTypes];
static const volume_kind_row *row_of_code[NofValidElementTypes];
static pthread_once_t codes_once = PTHREAD_ONCE_INIT;

static void find_codes(void)
{
    for (int t = 0; t < NofValidElementTypes; t++)
        kind_of_code[t] = (signed char)volume_kind_by_name((CGNS_ENUMT(ElementType_t))t, &row_of_code[t]);
}

static int volume_kind(CGNS_ENUMT(ElementType_t) type, const volume_kind_row **row)
{
    if ((int)type < 0 || (int)type >= NofValidElementTypes)
        return volume_kind_by_name(type, row);
    pthread_once(&codes_once, find_codes);
    if (kind_of_code[type] >= 0)
        *row = row_of_code[type];
    return kind_of_code[type];
}

static int is_poly_storage(CGNS_ENUMT(ElementType_t) type)
{
    return type == CGNS_ENUMV(MIXED) || type == CGNS_ENUMV(NGON_n) || type == CGNS_ENUMV(NFACE_n);
}

static int by_start(const void *a, const void *b)
{
    const cgns_section *x = a, *y = b;
    return (x->start > y->start) - (x->start < y->start);
}

/* ElementStartOffset: starts at 0, never decreases, ends at the data size. */
static int check_offsets(const cgns_reader *r, const cgns_zone *zone, const cgns_section *sec)
{
    cgsize_t count = sec->end - sec->start + 1;
    for (cgsize_t i = 0; i < count; i++)
        if (sec->offsets[i] < 0 || sec->offsets[i + 1] < sec->offsets[i] || sec->offsets[i + 1] > sec->data_size ||
            (i == 0 && sec->offsets[0] != 0))
            return tpk_diag_fail(r->diag, "%s: zone '%s' section '%s' element %lld: ElementStartOffset %lld to %lld, "
                                 "expected increasing offsets from 0 within the %lld connectivity entries",
                                 r->path, zone->name, sec->name, (long long)(sec->start + i), (long long)sec->offsets[i],
                                 (long long)sec->offsets[i + 1], (long long)sec->data_size);
    if (sec->offsets[count] != sec->data_size)
        return tpk_diag_fail(r->diag, "%s: zone '%s' section '%s': its offsets end at %lld, expected %lld (the "
                             "connectivity's size)", r->path, zone->name, sec->name, (long long)sec->offsets[count],
                             (long long)sec->data_size);
    return 0;
}

/* Read section S's header and data; checks sizes before allocating. */
static int read_section(const cgns_reader *r, const cgns_zone *zone, cgns_section *sec)
{
    int boundary = 0, parent_flag = 0;
    if (cg_section_read(r->fn, r->base, zone->index, sec->index, sec->name, &sec->type, &sec->start, &sec->end,
                        &boundary, &parent_flag) ||
        cg_ElementDataSize(r->fn, r->base, zone->index, sec->index, &sec->data_size))
        return CGNS_FAIL(r, "zone '%s': cannot read element section %d", zone->name, sec->index);
    int64_t count = (int64_t)sec->end - sec->start + 1;
    int npe = 0;
    if (sec->start < 1 || count < 1 || count > r->file_size || sec->data_size < count || sec->data_size > r->file_size)
        return tpk_diag_fail(r->diag, "%s: zone '%s' section '%s': elements %lld to %lld with %lld connectivity "
                             "entries, expected a range from 1 and at most one entry per byte of the file",
                             r->path, zone->name, sec->name, (long long)sec->start, (long long)sec->end,
                             (long long)sec->data_size);
    if (!is_poly_storage(sec->type) && (cg_npe(sec->type, &npe) || npe < 1 || sec->data_size != count * npe))
        return tpk_diag_fail(r->diag, "%s: zone '%s' section '%s' (%s): %lld connectivity entries, expected %lld "
                             "(%lld elements of %d nodes)", r->path, zone->name, sec->name,
                             cg_ElementTypeName(sec->type), (long long)sec->data_size, (long long)count * npe,
                             (long long)count, npe);
    sec->elements = malloc(sizeof *sec->elements * (size_t)sec->data_size);
    if (is_poly_storage(sec->type))
        sec->offsets = malloc(sizeof *sec->offsets * (size_t)(count + 1));
    if (!sec->elements || (is_poly_storage(sec->type) && !sec->offsets))
        return tpk_diag_fail(r->diag, "%s: out of memory for section '%s'", r->path, sec->name);
    int failed = sec->offsets ? cg_poly_elements_read(r->fn, r->base, zone->index, sec->index, sec->elements,
                                                      sec->offsets, NULL)
                              : cg_elements_read(r->fn, r->base, zone->index, sec->index, sec->elements, NULL);
    if (failed)
        return CGNS_FAIL(r, "zone '%s': cannot read the connectivity of section '%s'", zone->name, sec->name);
    return sec->offsets ? check_offsets(r, zone, sec) : 0;
}

/* The NGON_n face numbered `id`: its nodes and their count; NULL when no NGON_n section holds it. */
static const cgsize_t *find_face(const cgns_zone *zone, cgsize_t id, cgsize_t *n)
{
    for (int s = 0; s < zone->section_count; s++) {
        const cgns_section *sec = &zone->sections[s];
        if (sec->type == CGNS_ENUMV(NGON_n) && id >= sec->start && id <= sec->end) {
            cgsize_t i = id - sec->start;
            *n = sec->offsets[i + 1] - sec->offsets[i];
            return sec->elements + sec->offsets[i];
        }
    }
    return NULL;
}

/* NFACE_n cell i of `sec`: its face stream's length (nfaces, then per face npts and the ids). */
static int polyhedron_size(const cgns_reader *r, const cgns_zone *zone, const cgns_section *sec, cgsize_t i,
                           int64_t *size)
{
    *size = 1;
    for (cgsize_t f = sec->offsets[i]; f < sec->offsets[i + 1]; f++) {
        cgsize_t id = sec->elements[f] < 0 ? -sec->elements[f] : sec->elements[f], n = 0;
        if (!find_face(zone, id, &n))
            return tpk_diag_fail(r->diag, "%s: zone '%s' section '%s' element %lld uses face %lld, which no NGON_n "
                                 "section of the zone holds", r->path, zone->name, sec->name,
                                 (long long)(sec->start + i), (long long)sec->elements[f]);
        *size += 1 + n;
    }
    return 0;
}

/* Add one element of type `type` (nodes at `nodes`) to the zone's counts. */
static int count_element(const cgns_reader *r, cgns_zone *zone, const cgns_section *sec, cgsize_t i,
                         CGNS_ENUMT(ElementType_t) type)
{
    const volume_kind_row *row = NULL;
    int kind = volume_kind(type, &row);
    if (type == CGNS_ENUMV(NGON_n))
        return 0; /* faces, used by NFACE_n */
    if (type == CGNS_ENUMV(NFACE_n)) {
        int64_t size = 0;
        if (polyhedron_size(r, zone, sec, i, &size))
            return -1;
        zone->cells++, zone->polyhedra++, zone->conn += size;
        return 0;
    }
    if (kind < 0)
        return tpk_diag_fail(r->diag, "%s: zone '%s' section '%s' element %lld has type %s (code %d), expected a "
                             "volume (TETRA, PYRA, PENTA, HEXA, NFACE_n) or a face, edge or node", r->path,
                             zone->name, sec->name, (long long)(sec->start + i), cg_ElementTypeName(type), (int)type);
    if (kind == 0)
        zone->dropped++;
    else
        zone->cells++, zone->conn += row->nodes, zone->reduced += row->reduced;
    return 0;
}

/* A MIXED element: its type code and node count fit the offsets. */
static int mixed_type(const cgns_reader *r, const cgns_zone *zone, const cgns_section *sec, cgsize_t i,
                      CGNS_ENUMT(ElementType_t) *type)
{
    cgsize_t at = sec->offsets[i], len = sec->offsets[i + 1] - at;
    int npe = -1;
    *type = len > 0 ? (CGNS_ENUMT(ElementType_t))sec->elements[at] : CGNS_ENUMV(ElementTypeNull);
    if (len < 1 || is_poly_storage(*type) || cg_npe(*type, &npe) || npe < 1 || len != 1 + npe)
        return tpk_diag_fail(r->diag, "%s: zone '%s' section '%s' (MIXED) element %lld: type code %lld with %lld "
                             "node ids, expected a fixed element type followed by its node count (%d)", r->path,
                             zone->name, sec->name, (long long)(sec->start + i), len > 0 ? (long long)*type : -1LL,
                             (long long)(len - 1), npe);
    return 0;
}

static int count_section(const cgns_reader *r, cgns_zone *zone, const cgns_section *sec)
{
    cgsize_t count = sec->end - sec->start + 1;
    const volume_kind_row *row = NULL;
    int kind = is_poly_storage(sec->type) ? -1 : volume_kind(sec->type, &row);
    if (kind >= 0) { /* one type for the whole section: its counts at once */
        if (kind == 0)
            zone->dropped += count;
        else
            zone->cells += count, zone->conn += (int64_t)count * row->nodes, zone->reduced += count * row->reduced;
        return 0;
    }
    for (cgsize_t i = 0; i < count; i++) {
        CGNS_ENUMT(ElementType_t) type = sec->type;
        if (sec->type == CGNS_ENUMV(MIXED) && mixed_type(r, zone, sec, i, &type))
            return -1;
        if (count_element(r, zone, sec, i, type))
            return -1;
    }
    return 0;
}

int cgns_sections_load(const cgns_reader *r, cgns_zone *zone)
{
    int count = 0;
    if (cg_nsections(r->fn, r->base, zone->index, &count))
        return CGNS_FAIL(r, "zone '%s': cannot read its element sections", zone->name);
    zone->sections = calloc((size_t)(count > 0 ? count : 1), sizeof *zone->sections);
    if (!zone->sections)
        return tpk_diag_fail(r->diag, "%s: out of memory for %d sections", r->path, count);
    for (int s = 0; s < count; s++) {
        zone->section_count++;
        zone->sections[s].index = s + 1;
        if (read_section(r, zone, &zone->sections[s]))
            return -1;
    }
    /* Cell-centred data follows the volume elements in element-number order. */
    qsort(zone->sections, (size_t)count, sizeof *zone->sections, by_start);
    for (int s = 1; s < count; s++)
        if (zone->sections[s].start <= zone->sections[s - 1].end)
            return tpk_diag_fail(r->diag, "%s: zone '%s': sections '%s' and '%s' both number element %lld, expected "
                                 "disjoint element ranges", r->path, zone->name, zone->sections[s - 1].name,
                                 zone->sections[s].name, (long long)zone->sections[s].start);
    for (int s = 0; s < count; s++)
        if (count_section(r, zone, &zone->sections[s]))
            return -1;
    return 0;
}

/* One node id of element `element` (its number), 1-based in the zone, to a 0-based id of the mesh. */
static int node_id(const cgns_reader *r, const cgns_zone *zone, const cgns_section *sec, cgsize_t element,
                   cgsize_t id, int32_t *out)
{
    if (id < 1 || id > zone->vertices)
        return tpk_diag_fail(r->diag, "%s: zone '%s' section '%s' element %lld uses vertex %lld, expected 1 to %lld",
                             r->path, zone->name, sec->name, (long long)element, (long long)id,
                             (long long)zone->vertices);
    *out = (int32_t)(zone->first_point + id - 1);
    return 0;
}

/* NFACE_n cell i as a VTK face stream at out->cell_conn + *at, faces turned outward. */
static int emit_polyhedron(const cgns_reader *r, const cgns_zone *zone, const cgns_section *sec, cgsize_t i,
                           tpk_mesh *out, int64_t *at)
{
    int64_t begin = *at;
    out->cell_conn[(*at)++] = (int32_t)(sec->offsets[i + 1] - sec->offsets[i]);
    for (cgsize_t f = sec->offsets[i]; f < sec->offsets[i + 1]; f++) {
        cgsize_t id = sec->elements[f] < 0 ? -sec->elements[f] : sec->elements[f], n = 0;
        const cgsize_t *nodes = find_face(zone, id, &n);
        out->cell_conn[(*at)++] = (int32_t)n;
        for (cgsize_t k = 0; k < n; k++)
            if (node_id(r, zone, sec, sec->start + i, nodes[sec->elements[f] < 0 ? n - 1 - k : k], &out->cell_conn[(*at)++]))
                return -1;
    }
    int64_t bad_at = 0;
    char why[160];
    if (tpk_face_stream_check(out->cell_conn + begin, *at - begin, out->point_count, &bad_at, why, sizeof why))
        return tpk_diag_fail(r->diag, "%s: zone '%s' section '%s' element %lld: %s", r->path, zone->name, sec->name,
                             (long long)(sec->start + i), why);
    return 0;
}

/* Element i of `sec` (type `type`, nodes at `nodes`) appended to out, if it is a volume. */
static int emit_element(const cgns_reader *r, const cgns_zone *zone, const cgns_section *sec, cgsize_t i,
                        CGNS_ENUMT(ElementType_t) type, const cgsize_t *nodes, tpk_mesh *out, int64_t *at)
{
    static const volume_kind_row polyhedron = {"NFACE_n", TPK_CELL_POLYHEDRON, 0, NULL, 0};
    const volume_kind_row *row = &polyhedron;
    int64_t c = out->cell_count;
    if (type != CGNS_ENUMV(NFACE_n) && volume_kind(type, &row) != 1)
        return 0;
    int vtk = row->vtk;
    out->cell_types[c] = (uint8_t)vtk;
    out->cell_offsets[c] = *at;
    if (vtk == TPK_CELL_POLYHEDRON && emit_polyhedron(r, zone, sec, i, out, at))
        return -1;
    for (int k = 0; k < row->nodes; k++)
        if (node_id(r, zone, sec, sec->start + i, nodes[row->order ? row->order[k] : k], &out->cell_conn[(*at)++]))
            return -1;
    out->cell_count = c + 1;
    out->cell_offsets[c + 1] = *at;
    return 0;
}

/* A section of one volume type, on all threads: element i is cell c0 + i, its ids at at0 + i * nodes. */
typedef struct fixed_job {
    const cgns_section *sec;
    const volume_kind_row *row;
    int npe;
    int64_t c0, at0, first_point, vertices;
    tpk_mesh *out;
    int bad[TPK_MAX_THREADS];
} fixed_job;

static void fixed_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    fixed_job *job = ctx;
    const volume_kind_row *row = job->row;
    int bad = 0;
    for (int64_t i = begin; i < end; i++) {
        const cgsize_t *nodes = job->sec->elements + i * job->npe;
        int64_t c = job->c0 + i, at = job->at0 + i * row->nodes;
        job->out->cell_types[c] = (uint8_t)row->vtk;
        job->out->cell_offsets[c] = at;
        for (int k = 0; k < row->nodes; k++) {
            cgsize_t id = nodes[row->order ? row->order[k] : k];
            bad |= id < 1 || id > job->vertices;
            job->out->cell_conn[at + k] = (int32_t)(job->first_point + id - 1);
        }
    }
    job->bad[worker] |= bad;
}

/* A section of one element type other than NGON_n: 0 when emitted (or, for faces, edges and nodes, left
 * out), 1 when a node id is out of range, for the serial loop to name the first (out's counts as they
 * were). */
static int emit_fixed(const cgns_zone *zone, const cgns_section *sec, tpk_mesh *out, int64_t *at)
{
    const volume_kind_row *row = NULL;
    int npe = 0;
    int kind = volume_kind(sec->type, &row);
    if (kind == 0)
        return 0;
    if (kind < 0 || cg_npe(sec->type, &npe) || npe < row->nodes)
        return 1;
    int64_t count = (int64_t)sec->end - sec->start + 1;
    fixed_job job = {.sec = sec, .row = row, .npe = npe, .c0 = out->cell_count, .at0 = *at,
                     .first_point = zone->first_point, .vertices = zone->vertices, .out = out};
    int threads = cgns_threads(count), bad = 0;
    tpk_parallel_for(count, threads, fixed_range, &job);
    for (int w = 0; w < threads; w++)
        bad |= job.bad[w];
    if (bad)
        return 1;
    out->cell_count += count;
    *at += count * row->nodes;
    out->cell_offsets[out->cell_count] = *at;
    return 0;
}

/* A MIXED section on all threads, in two passes over the same ranges: the volume cells and ids of each
 * range, then (from their prefix sums) the cells themselves. Every element's type and size were checked
 * when the section was counted (mixed_type). */
typedef struct mixed_job {
    const cgns_section *sec;
    int64_t first_point, vertices;
    int64_t cells[TPK_MAX_THREADS], ids[TPK_MAX_THREADS]; /* a range's counts, then its first cell and id */
    tpk_mesh *out;
    int bad[TPK_MAX_THREADS];
} mixed_job;

/* Element i's row when it is a volume (NULL: a face, edge or node), and its nodes. */
static const volume_kind_row *mixed_row(const cgns_section *sec, int64_t i, const cgsize_t **nodes)
{
    const volume_kind_row *row = NULL;
    CGNS_ENUMT(ElementType_t) type = (CGNS_ENUMT(ElementType_t))sec->elements[sec->offsets[i]];
    *nodes = sec->elements + sec->offsets[i] + 1;
    return volume_kind(type, &row) == 1 ? row : NULL;
}

static void mixed_count(void *ctx, int64_t begin, int64_t end, int worker)
{
    mixed_job *job = ctx;
    int64_t cells = 0, ids = 0;
    for (int64_t i = begin; i < end; i++) {
        const cgsize_t *nodes;
        const volume_kind_row *row = mixed_row(job->sec, i, &nodes);
        if (row)
            cells++, ids += row->nodes;
    }
    job->cells[worker] = cells, job->ids[worker] = ids;
}

static void mixed_fill(void *ctx, int64_t begin, int64_t end, int worker)
{
    mixed_job *job = ctx;
    int64_t c = job->cells[worker], at = job->ids[worker];
    int bad = 0;
    for (int64_t i = begin; i < end; i++) {
        const cgsize_t *nodes;
        const volume_kind_row *row = mixed_row(job->sec, i, &nodes);
        if (!row)
            continue;
        job->out->cell_types[c] = (uint8_t)row->vtk;
        job->out->cell_offsets[c++] = at;
        for (int k = 0; k < row->nodes; k++) {
            cgsize_t id = nodes[row->order ? row->order[k] : k];
            bad |= id < 1 || id > job->vertices;
            job->out->cell_conn[at++] = (int32_t)(job->first_point + id - 1);
        }
    }
    job->bad[worker] |= bad;
}

/* As emit_fixed, for a MIXED section. */
static int emit_mixed(const cgns_zone *zone, const cgns_section *sec, tpk_mesh *out, int64_t *at)
{
    int64_t count = (int64_t)sec->end - sec->start + 1;
    mixed_job *job = calloc(1, sizeof *job);
    if (!job)
        return 1;
    *job = (mixed_job){.sec = sec, .first_point = zone->first_point, .vertices = zone->vertices, .out = out};
    int threads = cgns_threads(count), bad = 0;
    tpk_parallel_for(count, threads, mixed_count, job);
    int64_t cells = out->cell_count, ids = *at;
    for (int w = 0; w < threads; w++) {
        int64_t c = job->cells[w], n = job->ids[w];
        job->cells[w] = cells, job->ids[w] = ids;
        cells += c, ids += n;
    }
    tpk_parallel_for(count, threads, mixed_fill, job);
    for (int w = 0; w < threads; w++)
        bad |= job->bad[w];
    free(job);
    if (bad)
        return 1;
    out->cell_count = cells;
    *at = ids;
    out->cell_offsets[cells] = ids;
    return 0;
}

int cgns_sections_emit(const cgns_reader *r, const cgns_zone *zone, tpk_mesh *out)
{
    int64_t at = out->cell_offsets[out->cell_count];
    for (int s = 0; s < zone->section_count; s++) {
        const cgns_section *sec = &zone->sections[s];
        cgsize_t count = sec->end - sec->start + 1;
        int npe = 0;
        if (sec->type == CGNS_ENUMV(NGON_n))
            continue; /* faces, used through NFACE_n */
        if (!is_poly_storage(sec->type) && emit_fixed(zone, sec, out, &at) == 0)
            continue;
        if (sec->type == CGNS_ENUMV(MIXED) && emit_mixed(zone, sec, out, &at) == 0)
            continue;
        if (!is_poly_storage(sec->type))
            cg_npe(sec->type, &npe);
        for (cgsize_t i = 0; i < count; i++) {
            CGNS_ENUMT(ElementType_t) type = sec->type;
            const cgsize_t *nodes = sec->elements + (int64_t)i * npe;
            if (sec->type == CGNS_ENUMV(MIXED))
                type = (CGNS_ENUMT(ElementType_t))sec->elements[sec->offsets[i]], nodes = sec->elements + sec->offsets[i] + 1;
            if (emit_element(r, zone, sec, i, type, nodes, out, &at))
                return -1;
        }
    }
    return 0;
}

void cgns_sections_free(cgns_zone *zone)
{
    for (int s = 0; s < zone->section_count; s++) {
        free(zone->sections[s].elements);
        free(zone->sections[s].offsets);
    }
    free(zone->sections);
    zone->sections = NULL;
    zone->section_count = 0;
}
