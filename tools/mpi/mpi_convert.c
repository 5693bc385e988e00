/* tetpack-mpi convert, rank by rank: each rank reads its block of the pieces (a .pvtu's, an OpenFOAM
 * case's processor folders, or Exodus files per processor), the ranks agree on
 * global vertex ids (exchange.h), each rank splits its cells into tets on the whole mesh's float32 grid
 * (ids ascending by global id, so quads split as the single-file converter splits them when the ids come
 * from the file), orients and connects them, the faces on cuts are matched by an exchange, each rank
 * writes its part with its links, and rank 0 the manifest. Every phase ends with an agreement, so a
 * failure on one rank stops all of them at the same place. */
#include "mpi_convert.h"

#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "convert/convert.h"
#include "convert/parts.h"
#include "convert/pipeline.h"
#include "convert/write_tpk.h"
#include "base/clock.h"
#include "base/strbuf.h"
#include "exchange.h"
#include "pieces.h"
#include "pvtu.h"

typedef struct rank_state {
    MPI_Comm comm;
    int rank, size;
    const tpk_mpi_options *o;
    tpk_mpi_rank_report *rep;
    tpk_diag *diag;
    tpk_piece_list list;
    tpk_rank_pieces in;
    int64_t *local_gid;   /* per point after merging: its global id, ascending */
    int64_t *cell_global; /* per cell: its number among the volume cells of all pieces, or -1 */
    int64_t *vertex_gid;  /* per tet-mesh vertex: global id, -1 for a point the converter added */
    double lo[3], hi[3];
    tpk_tetmesh mesh;
    int32_t *neighbors;
    uint8_t *turned_over;
    tpk_header_fields hdr;
    tpk_link *links;
    int64_t link_count;
    tpk_part_record record;
} rank_state;

static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int read_input(rank_state *s)
{
    int rc = tpk_input_pieces(s->o->input, &s->list, s->diag);
    if (rc == 0 && s->list.count < s->size)
        rc = tpk_diag_fail(s->diag, "%s: %d pieces for %d ranks: each rank needs at least one piece", s->o->input,
                           s->list.count, s->size);
    if (tpk_agree(s->comm, rc) != 0)
        return -1;
    int first = (int)((int64_t)s->list.count * s->rank / s->size);
    int last = (int)((int64_t)s->list.count * (s->rank + 1) / s->size);
    s->rep->pieces = last - first;
    rc = tpk_read_pieces(&s->list, first, last, &s->in, s->diag);
    s->rep->points_read = s->in.points_read;
    return tpk_agree(s->comm, rc);
}

/* The whole mesh's box, for the Morton keys and the file origin every part shares. */
static void global_box(rank_state *s)
{
    double lo[3] = {1e308, 1e308, 1e308}, hi[3] = {-1e308, -1e308, -1e308};
    for (int64_t i = 0; i < s->in.mesh.point_count; i++)
        for (int k = 0; k < 3; k++) {
            double x = s->in.mesh.points[3 * i + k];
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
    MPI_Allreduce(lo, s->lo, 3, MPI_DOUBLE, MPI_MIN, s->comm);
    MPI_Allreduce(hi, s->hi, 3, MPI_DOUBLE, MPI_MAX, s->comm);
}

static const int64_t *sort_keys; /* qsort has no user pointer; set only around the call below */

static int compare_by_gid(const void *a, const void *b)
{
    int64_t x = sort_keys[*(const int64_t *)a], y = sort_keys[*(const int64_t *)b];
    return (x > y) - (x < y);
}

/* Points in ascending global id, one per id (pieces on one rank share their boundary points); cells and
 * point fields follow. */
static int merge_points(rank_state *s, const int64_t *gid)
{
    tpk_mesh *m = &s->in.mesh;
    int64_t n = m->point_count, unique = 0;
    int64_t *order = malloc(sizeof *order * (size_t)(n ? n : 1));
    int32_t *new_id = malloc(sizeof *new_id * (size_t)(n ? n : 1));
    s->local_gid = malloc(sizeof *s->local_gid * (size_t)(n ? n : 1));
    double *points = malloc(sizeof *points * 3 * (size_t)(n ? n : 1));
    if (!order || !new_id || !s->local_gid || !points) {
        free(order), free(new_id), free(points);
        return tpk_diag_fail(s->diag, "out of memory for %lld points", (long long)n);
    }
    for (int64_t i = 0; i < n; i++)
        order[i] = i;
    sort_keys = gid;
    qsort(order, (size_t)n, sizeof *order, compare_by_gid);
    sort_keys = NULL;
    for (int64_t k = 0; k < n; k++) {
        int64_t i = order[k];
        if (k == 0 || gid[i] != s->local_gid[unique - 1]) {
            memcpy(points + 3 * unique, m->points + 3 * i, 3 * sizeof *points);
            s->local_gid[unique] = gid[i];
            order[unique++] = i; /* the first occurrence gives field values */
        }
        new_id[i] = (int32_t)(unique - 1);
    }
    for (int64_t c = 0; m->cell_count && c < m->cell_offsets[m->cell_count]; c++)
        m->cell_conn[c] = new_id[m->cell_conn[c]];
    tpk_face_stream_ids(m, 0, new_id, 0);
    for (int64_t c = 0; c < m->cell_count; c++) /* a polyhedron lists its points ascending (mesh.h) */
        if (m->cell_types[c] == TPK_CELL_POLYHEDRON)
            qsort(m->cell_conn + m->cell_offsets[c], (size_t)(m->cell_offsets[c + 1] - m->cell_offsets[c]),
                  sizeof *m->cell_conn, tpk_compare_int32);
    int rc = 0;
    for (int f = 0; rc == 0 && f < m->field_count; f++) {
        tpk_src_field *fld = &m->fields[f];
        if (fld->association != TPK_ASSOC_POINT)
            continue;
        size_t comp = (size_t)fld->components;
        float *values = malloc(sizeof *values * comp * (size_t)fld->step_count * (size_t)unique + 1);
        if (!values) {
            rc = tpk_diag_fail(s->diag, "out of memory for field '%s'", fld->name);
            break;
        }
        for (int st = 0; st < fld->step_count; st++)
            for (int64_t u = 0; u < unique; u++)
                memcpy(values + (st * (size_t)unique + (size_t)u) * comp,
                       fld->values + (st * (size_t)n + (size_t)order[u]) * comp, comp * sizeof *values);
        free(fld->values);
        fld->values = values;
    }
    free(m->points);
    m->points = points;
    m->point_count = unique;
    free(order);
    free(new_id);
    return rc;
}

/* TMAP from the files' cell ids (Exodus element number maps) when every rank has them; -1 on an id
 * past 32 bits. */
static int given_cell_numbers(rank_state *s)
{
    const tpk_mesh *m = &s->in.mesh;
    int bad = -1;
    for (int64_t c = 0; c < m->cell_count; c++)
        if ((s->cell_global[c] = s->in.given_cell_ids[c]) > INT32_MAX - 1 && bad < 0)
            bad = (int)c;
    if (bad >= 0)
        tpk_diag_fail(s->diag, "%s: cell %d has global id %lld, expected an id below 2^31-1 (TMAP holds 32 bits)",
                      s->o->input, bad, (long long)s->in.given_cell_ids[bad]);
    return tpk_agree(s->comm, bad >= 0 ? -1 : 0);
}

/* TMAP numbering (spec §5.3): the files' global cell ids, else volume cells piece after piece in the
 * input's order. */
static int number_cells(rank_state *s)
{
    int64_t *counts = calloc((size_t)s->list.count, sizeof *counts), *sums = calloc((size_t)s->list.count, sizeof *sums);
    tpk_mesh *m = &s->in.mesh;
    s->cell_global = malloc(sizeof *s->cell_global * (size_t)(m->cell_count ? m->cell_count : 1));
    int ok = counts && sums && s->cell_global;
    if (tpk_agree(s->comm, !ok) != 0) {
        free(counts), free(sums);
        return tpk_diag_fail(s->diag, "out of memory for the cell numbers");
    }
    int mine = s->in.given_cell_ids != NULL, all = 0;
    MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, s->comm);
    if (all) {
        free(counts), free(sums);
        return given_cell_numbers(s);
    }
    for (int64_t c = 0; c < m->cell_count; c++)
        if (s->in.cell_volume[c] >= 0)
            counts[s->in.cell_piece[c]]++;
    MPI_Allreduce(counts, sums, s->list.count, MPI_INT64_T, MPI_SUM, s->comm);
    int64_t before = 0;
    for (int k = 0; k < s->list.count; k++) { /* exclusive prefix, in place */
        int64_t here = sums[k];
        sums[k] = before;
        before += here;
    }
    for (int64_t c = 0; c < m->cell_count; c++)
        s->cell_global[c] = s->in.cell_volume[c] >= 0 ? sums[s->in.cell_piece[c]] + s->in.cell_volume[c] : -1;
    free(counts), free(sums);
    return 0;
}

static int global_vertices(rank_state *s)
{
    global_box(s);
    int64_t *gid = malloc(sizeof *gid * (size_t)(s->in.mesh.point_count ? s->in.mesh.point_count : 1));
    if (tpk_agree(s->comm, !gid) != 0)
        return tpk_diag_fail(s->diag, "out of memory for global ids");
    int rc = tpk_global_ids(s->comm, &s->in.mesh, s->in.given_ids, s->lo, s->hi, gid, &s->rep->global_vertices,
                            &s->rep->exchanged_bytes, s->diag);
    if (rc == 0)
        rc = merge_points(s, gid);
    free(gid);
    if (tpk_agree(s->comm, rc) != 0)
        return -1;
    return number_cells(s);
}

/* Cells into positive, connected tets on the whole mesh's float32 grid. Local work: no exchange. */
static int make_tets(rank_state *s)
{
    int64_t local_points = s->in.mesh.point_count;
    double corners[6];
    memcpy(corners, s->lo, sizeof s->lo);
    memcpy(corners + 3, s->hi, sizeof s->hi);
    s->in.mesh.has_grid_origin = 1; /* every rank on the grid of the whole (spec §15.4: one origin) */
    tpk_points_origin(corners, 2, s->in.mesh.grid_origin);
    /* The scalar point fields, as the single-file converter keeps them; GlobalPointIds was the vertex
     * identity and is not data. */
    const char *names[64];
    int name_count = 0;
    for (int f = 0; f < s->in.mesh.field_count && name_count < 64; f++) {
        const tpk_src_field *fld = &s->in.mesh.fields[f];
        if (fld->association == TPK_ASSOC_POINT && fld->components == 1 && strcmp(fld->name, "GlobalPointIds"))
            names[name_count++] = fld->name;
    }
    if (tpk_tetrahedralize_consume(&s->in.mesh, names, name_count, TPK_TETRA_FILE_GRID, &s->mesh, s->diag) != 0)
        return -1;
    tpk_tetmesh *m = &s->mesh;
    s->vertex_gid = malloc(sizeof *s->vertex_gid * (size_t)(m->vertex_count ? m->vertex_count : 1));
    s->turned_over = malloc((size_t)(m->tet_count ? m->tet_count : 1));
    s->neighbors = malloc(sizeof *s->neighbors * 4 * (size_t)(m->tet_count ? m->tet_count : 1));
    if (!s->vertex_gid || !s->turned_over || !s->neighbors)
        return tpk_diag_fail(s->diag, "out of memory for %lld tets", (long long)m->tet_count);
    for (int64_t v = 0; v < m->vertex_count; v++) {
        int32_t src = m->vertex_source[v];
        s->vertex_gid[v] = src >= 0 && src < local_points ? s->local_gid[src] : -1;
        m->vertex_source[v] = (int32_t)s->vertex_gid[v]; /* VMAP: the set's global vertex numbering */
    }
    for (int64_t t = 0; t < m->tet_count; t++)
        m->tet_source[t] = (int32_t)s->cell_global[m->tet_source[t]];
    if (tpk_quantize_points(m, &s->hdr, s->diag) != 0)
        return -1;
    tpk_orient_stats os;
    if (tpk_orient_marked(m, 0, s->o->threads, &os, s->turned_over, s->diag) != 0)
        return -1;
    tpk_unfold_stats us;
    return tpk_connect_unfolded(m, s->turned_over, 0, s->o->threads, s->neighbors, &us, s->diag);
}

static int write_part(rank_state *s)
{
    char *path = NULL;
    if (tpk_part_path(s->o->output, s->rank, s->size, &s->record, &path, s->diag) != 0)
        return -1;
    tpk_convert_options co;
    memset(&co, 0, sizeof co);
    co.input = s->o->input;
    co.output = path;
    co.layouts = s->o->layouts;
    co.zstd_level = s->o->zstd_level;
    co.threads = s->o->threads;
    co.command_line = s->o->command_line;
    tpk_convert_report cr;
    memset(&cr, 0, sizeof cr);
    cr.source_points = s->rep->points_read;
    tpk_part_extras extras = {s->links, s->link_count, s->rank, s->size};
    int rc = tpk_write_tpk(&co, &s->mesh, s->neighbors, &s->hdr, &cr, s->list.format, &extras, s->diag);
    if (rc == 0)
        rc = tpk_read_header_checksum(path, &s->record.header_checksum, s->diag);
    if (rc == 0) {
        s->record.file_size = cr.output_bytes;
        s->record.vertex_count = s->hdr.vertex_count;
        s->record.tet_count = s->hdr.tet_count;
        s->record.shell_face_count = s->hdr.shell_face_count;
        s->record.link_count = (uint64_t)s->link_count;
        memcpy(s->record.bounds_min, s->hdr.bounds_min, sizeof s->hdr.bounds_min);
        memcpy(s->record.bounds_max, s->hdr.bounds_max, sizeof s->hdr.bounds_max);
        s->rep->file_bytes = (int64_t)cr.output_bytes;
    }
    free(path);
    return rc;
}

/* Rank 0 gathers the part records and writes the manifest, once every part is on disk. */
static int write_manifest(rank_state *s)
{
    tpk_part_record *records = s->rank == 0 ? calloc((size_t)s->size, sizeof *records) : NULL;
    int rc = s->rank == 0 && !records ? tpk_diag_fail(s->diag, "out of memory") : 0;
    MPI_Gather(&s->record, (int)sizeof s->record, MPI_BYTE, records, (int)sizeof s->record, MPI_BYTE, 0, s->comm);
    if (rc == 0 && s->rank == 0) {
        tpk_strbuf sb = {0};
        tpk_strbuf_printf(&sb, "{\"converter\":{\"name\":\"tetpack-mpi\",\"version\":\"%s\"},\"source\":{\"path\":",
                          TPK_LIBRARY_VERSION);
        tpk_strbuf_json_string(&sb, s->o->input);
        tpk_strbuf_printf(&sb, ",\"format\":\"%s\",\"pieces\":%d},\"part_set\":{\"parts\":%d,\"vertices\":%lld,"
                          "\"cut\":\"ranks\"}}", s->list.format, s->list.count, s->size, (long long)s->rep->global_vertices);
        rc = sb.failed ? tpk_diag_fail(s->diag, "out of memory")
                       : tpk_write_manifest(s->o->output, s->hdr.origin, records, s->size, sb.data, s->diag);
        tpk_strbuf_free(&sb);
    }
    free(records);
    return tpk_agree(s->comm, rc);
}

static void free_state(rank_state *s)
{
    tpk_piece_list_free(&s->list);
    tpk_rank_pieces_free(&s->in);
    tpk_tetmesh_free(&s->mesh);
    free(s->local_gid), free(s->cell_global), free(s->vertex_gid), free(s->neighbors), free(s->turned_over);
    free(s->links);
}

/* A phase: its wall and CPU seconds, then the ranks agree (a failure anywhere stops every rank here). */
#define PHASE(call, t, cpu)                         \
    do {                                            \
        double t0_ = tpk_now_seconds(), c0_ = cpu_seconds(); \
        rc = (call);                                \
        (cpu) = cpu_seconds() - c0_;                \
        (t) = tpk_now_seconds() - t0_;                  \
        if (tpk_agree(s.comm, rc) != 0) {           \
            rc = -1;                                \
            goto done;                              \
        }                                           \
    } while (0)

int tpk_mpi_convert(MPI_Comm comm, const tpk_mpi_options *o, tpk_mpi_rank_report *rep, tpk_diag *diag)
{
    rank_state s;
    memset(&s, 0, sizeof s);
    memset(rep, 0, sizeof *rep);
    s.comm = comm, s.o = o, s.rep = rep, s.diag = diag;
    MPI_Comm_rank(comm, &s.rank);
    MPI_Comm_size(comm, &s.size);
    double start = tpk_now_seconds();
    int rc = 0;
    PHASE(read_input(&s), rep->t_read, rep->cpu_read);
    PHASE(global_vertices(&s), rep->t_ids, rep->cpu_ids);
    PHASE(make_tets(&s), rep->t_tets, rep->cpu_tets);
    PHASE(tpk_cut_faces(comm, s.mesh.tets, s.neighbors, s.mesh.tet_count, s.vertex_gid, &s.links, &s.link_count,
                        &rep->exchanged_bytes, diag),
          rep->t_cut, rep->cpu_cut);
    PHASE(write_part(&s), rep->t_write, rep->cpu_write);
    double t_manifest = 0, cpu_manifest = 0;
    PHASE(write_manifest(&s), t_manifest, cpu_manifest);
    rep->t_write += t_manifest;
    rep->cpu_write += cpu_manifest;
    rep->vertices = s.mesh.vertex_count;
    rep->tets = s.mesh.tet_count;
    rep->shell_faces = (int64_t)s.hdr.shell_face_count;
    rep->links = s.link_count;
done:
    rep->t_total = tpk_now_seconds() - start;
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) == 0)
        rep->peak_rss_bytes = (int64_t)ru.ru_maxrss * 1024;
    free_state(&s);
    return rc;
}
