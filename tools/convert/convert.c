/* The conversion driver: runs the pipeline stages in order and writes the chunks of a .tpk. Peak
 * memory stays near the mesh itself: the source mesh hands its arrays over, and positions and layout
 * records are built in blocks that are streamed to the writer. */
#include "convert.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "import/importers.h"
#include "base/clock.h"
#include "levels.h"
#include "merge_vertices.h"
#include "mesh/cell_types.h"
#include "mesh/higher_order.h"
#include "base/output_file.h"
#include "base/parallel.h"
#include "pipeline.h"
#include "parts.h"
#include "refine.h"
#include "write_tpk.h"
#include "base/strbuf.h"
#include "base/text_scan.h"
#include "tetpack.h"

static void announce(tpk_stage_fn stage, void *user, const char *name)
{
    if (stage)
        stage(user, name, 0.0);
}

/* After merging, vertex and tet sources name merged ids: lead them back to the source file's. */
static void map_to_source(tpk_tetmesh *mesh, const tpk_merge_report *merged)
{
    if (merged->point_source)
        for (int64_t v = 0; v < mesh->vertex_count; v++)
            if (mesh->vertex_source[v] >= 0) /* -1: a point added at a cell's centre */
                mesh->vertex_source[v] = merged->point_source[mesh->vertex_source[v]];
    if (merged->cell_source)
        for (int64_t t = 0; t < mesh->tet_count; t++)
            mesh->tet_source[t] = merged->cell_source[mesh->tet_source[t]];
}

/* The tetrahedralizer names cells and points of the mesh it was given: say when merging renumbered them. */
static void note_merged_ids(const tpk_merge_report *merged, tpk_diag *diag)
{
    if (!merged->point_source)
        return;
    size_t used = strlen(diag->message);
    snprintf(diag->message + used, sizeof diag->message - used, " (ids count after --merge-duplicates removed "
             "%lld points%s)", (long long)merged->merged_vertices, merged->cell_source ? " and collapsed cells" : "");
}

/* What one conversion holds between its stages. */
typedef struct conversion {
    const tpk_convert_options *o;
    tpk_convert_report *rep;
    tpk_stage_fn stage;
    void *stage_user;
    tpk_diag *diag;
    tpk_mesh src;
    tpk_tetmesh mesh;
    int32_t *neighbors;
    uint8_t *turned_over; /* per tet: turned over by orient (connect asks whether that folded it) */
    tpk_header_fields header;
    char source_format[32];
    tpk_merge_report merged;
    tpk_higher_split higher;
    tpk_refine_cells source_cells; /* --max-error: the cells as imported, which tet_source names */
} conversion;

static void import_progress(void *user, double fraction)
{
    conversion *c = user;
    c->stage(c->stage_user, "import", fraction);
}

static int read_source(conversion *c)
{
    double t = tpk_now_seconds();
    announce(c->stage, c->stage_user, "import");
    if (c->stage)
        tpk_scan_watch(import_progress, c);
    int rc = tpk_import_any_whole(c->o->input, c->o->format, c->o->tetgen, 1, &c->src, c->diag);
    tpk_scan_watch(NULL, NULL);
    if (rc != 0)
        return -1;
    /* Global ids (Exodus maps) number the pieces of a larger mesh for tetpack-mpi; one file needs none. */
    free(c->src.global_point_ids);
    free(c->src.global_cell_ids);
    c->src.global_point_ids = NULL;
    c->src.global_cell_ids = NULL;
    c->rep->source_points = c->src.point_count;
    c->rep->source_cells = c->src.cell_count;
    memcpy(c->source_format, c->src.format, sizeof c->source_format);
    c->source_format[sizeof c->source_format - 1] = 0;
    c->rep->t_import = tpk_now_seconds() - t;
    return 0;
}

/* Higher-order cells split whole into linear cells at their nodes (or, with --higher-order corners,
 * reduced to their corners) before anything else sees the mesh. */
/* The higher-order cells, counted on all threads by a table of the 256 types (a call per cell, on one
 * core, was 0.4% of a 2-thread convert of grid 120). */
typedef struct higher_job {
    const uint8_t *types;
    unsigned char higher[256];
    int64_t count[TPK_MAX_THREADS];
} higher_job;

static void count_higher(void *ctx, int64_t begin, int64_t end, int w)
{
    higher_job *job = ctx;
    int64_t n = 0;
    for (int64_t k = begin; k < end; k++)
        n += job->higher[job->types[k]];
    job->count[w] = n;
}

static int whole_cells(conversion *c)
{
    if (c->o->max_error > 0 || c->o->subdivide > 0) {
        if (tpk_refine_cells_copy(&c->src, &c->source_cells) != 0)
            return tpk_diag_fail(c->diag, "out of memory for the cells of %s (--max-error)", c->o->input);
        int64_t bad = tpk_refine_unbounded_cell(&c->source_cells);
        if (bad >= 0) {
            const tpk_cell_type_info *t = tpk_cell_type(c->source_cells.types[bad]);
            return tpk_diag_fail(c->diag, "%s: cell %lld is a %s (VTK type %d, %lld nodes), whose own functions "
                                 "--max-error cannot bound (it bounds tetrahedra, voxels, hexahedra, wedges and their "
                                 "quadratic kinds, Lagrange tetra of order 3 to 10, hexahedra of order 3 and 4 and "
                                 "wedges of order 3 to 6: degree at most 12; pyramids and polyhedra are not "
                                 "polynomials on their tets, and higher orders and face-centred kinds are not "
                                 "bounded yet); convert without "
                                 "--max-error", c->o->input, (long long)bad, t ? t->name : "cell of unknown type",
                                 c->source_cells.types[bad],
                                 (long long)(c->source_cells.offsets[bad + 1] - c->source_cells.offsets[bad]));
        }
    }
    higher_job job = {.types = c->src.cell_types};
    for (int t = 0; t < 256; t++)
        job.higher[t] = (unsigned char)tpk_is_higher_order_volume(t);
    int threads = tpk_threads_for(c->src.cell_count, tpk_thread_count(c->o->threads), 1 << 20);
    tpk_parallel_for(c->src.cell_count, threads, count_higher, &job);
    int64_t count = 0;
    for (int w = 0; w < threads; w++)
        count += job.count[w];
    c->rep->higher_order_cells = count;
    if (count == 0)
        return 0;
    if (c->o->higher_order_corners) {
        tpk_reduce_higher_order(&c->src, c->o->input, c->diag);
        return 0;
    }
    if (tpk_split_higher_order(&c->src, c->o->input, &c->higher, c->diag) != 0)
        return -1;
    c->rep->higher_order_split = c->higher.split_cells > 0;
    c->rep->higher_order_points = c->higher.added_points;
    return 0;
}

/* Tets and vertices name the cells and points of the split mesh: lead them back to the source file's
 * (added points: -1). */
static void map_whole_cells(tpk_tetmesh *mesh, const tpk_higher_split *higher)
{
    if (!higher->cell_source)
        return;
    for (int64_t v = 0; v < mesh->vertex_count; v++)
        if (mesh->vertex_source[v] >= higher->source_points)
            mesh->vertex_source[v] = -1;
    for (int64_t t = 0; t < mesh->tet_count; t++)
        mesh->tet_source[t] = higher->cell_source[mesh->tet_source[t]];
}

static void tetrahedralize_progress(void *user, double fraction)
{
    conversion *c = user;
    c->stage(c->stage_user, "tetrahedralize", fraction);
}

/* --max-error: the tets refined until the bound holds in every cell (refine.h), on the file's grid. */
static int refine_tets(conversion *c)
{
    announce(c->stage, c->stage_user, "refine");
    double t = tpk_now_seconds();
    tpk_refine_options ro = {c->o->max_error, c->o->max_error_fields, c->o->max_error_field_count, c->o->threads, 0,
                             c->o->subdivide};
    tpk_refine_report rr;
    int rc = tpk_refine_max_error(&c->mesh, &c->source_cells, &ro, &rr, c->diag);
    tpk_refine_cells_free(&c->source_cells);
    if (rc != 0)
        return -1;
    c->rep->max_error.requested = c->o->max_error;
    c->rep->max_error.field_error = rr.field_error;
    c->rep->max_error.geometry_error = rr.geometry_error;
    memcpy(c->rep->max_error.worst_field, rr.worst_field, sizeof rr.worst_field);
    c->rep->max_error.fields = rr.fields_bounded;
    c->rep->max_error.tets_before = rr.tets_before;
    c->rep->max_error.vertices_added = rr.vertices_added;
    c->rep->max_error.passes = rr.rounds;
    c->rep->max_error.subdivide = c->o->subdivide;
    c->rep->max_error.seconds = tpk_now_seconds() - t;
    return 0;
}

/* The source mesh freed once it is made into tets, the pages of its large arrays given back on all
 * threads first (tpk_free_spread): one core's munmap of grid 120's 83 MB of cell offsets was 15 ms. */
static void free_source(tpk_mesh *src)
{
    size_t cells = (size_t)(src->cell_count > 0 ? src->cell_count : 0);
    if (src->cell_conn && src->cell_offsets)
        tpk_release_pages(src->cell_conn, sizeof *src->cell_conn * (size_t)src->cell_offsets[cells]);
    if (src->cell_offsets)
        tpk_release_pages(src->cell_offsets, sizeof *src->cell_offsets * (cells + 1));
    if (src->cell_types)
        tpk_release_pages(src->cell_types, cells);
    if (src->points)
        tpk_release_pages(src->points, sizeof *src->points * 3 * (size_t)(src->point_count > 0 ? src->point_count : 0));
    tpk_mesh_free(src);
}

/* Duplicate points merged when asked, source cells into tets on the file's float32 grid, then the
 * points into the stored frame. */
static int make_tets(conversion *c)
{
    const tpk_convert_options *o = c->o;
    tpk_convert_report *rep = c->rep;
    if (o->merge_duplicates) {
        announce(c->stage, c->stage_user, "merge duplicates");
        if (tpk_merge_vertices(&c->src, o->merge_tolerance, o->drop_degenerate, &c->merged, c->diag) != 0)
            return -1;
        rep->merged_vertices = c->merged.merged_vertices;
        rep->collapsed_cells_dropped = c->merged.collapsed_cells;
    }
    announce(c->stage, c->stage_user, "tetrahedralize");
    tpk_tetra_progress progress = {tetrahedralize_progress, c};
    /* The identity tet map left for reorder to write, where nothing before it reads the map: no merge or
     * higher-order split renumbering the cells, no refinement. */
    int source_later = !o->no_reorder && !c->merged.cell_source && !c->higher.cell_source && !(o->max_error > 0) &&
                       !(o->subdivide > 0);
    if (tpk_tetrahedralize_watched(&c->src, o->fields, o->field_count,
                                   (o->skip_bad_cells ? TPK_TETRA_SKIP_BAD_CELLS : 0) |
                                       (o->cell_to_point ? TPK_TETRA_CELL_TO_POINT : 0) |
                                       (o->strict_orientation ? TPK_TETRA_REFUSE_MIRRORED : 0) | TPK_TETRA_FILE_GRID |
                                       (source_later ? TPK_TETRA_IDENTITY_SOURCE_NULL : 0),
                                   o->threads, c->stage ? &progress : NULL, &c->mesh, c->diag) != 0) {
        note_merged_ids(&c->merged, c->diag);
        return -1;
    }
    free_source(&c->src);
    map_to_source(&c->mesh, &c->merged);
    map_whole_cells(&c->mesh, &c->higher);
    memcpy(rep->cells_into, c->mesh.cells_into, sizeof rep->cells_into);
    rep->mirrored_cells = c->mesh.mirrored_cells;
    rep->steiner_cells = c->mesh.steiner_cells;
    rep->fixed_boundary_cells = c->mesh.fixed_boundary_cells;
    rep->face_steiner_points = c->mesh.face_steiner_points;
    rep->polyhedra = c->mesh.polyhedra;
    rep->thin_faces_recut = c->mesh.thin_faces_recut;
    rep->flat_tets = c->mesh.flat_tets;
    rep->bad_cells_skipped = c->mesh.bad_cells_skipped;
    if ((o->max_error > 0 || o->subdivide > 0) && refine_tets(c) != 0)
        return -1;
    return tpk_quantize_points(&c->mesh, &c->header, c->diag);
}

/* Every tet positive (exact), each turned-over one marked for connect. */
static int orient_tets(conversion *c)
{
    announce(c->stage, c->stage_user, "orient");
    double t = tpk_now_seconds();
    tpk_orient_stats os;
    memset(&os, 0, sizeof os);
    if (c->mesh.positive_known) {
        /* Every sign already checked exactly by the split (tpk_tetmesh.positive_known): none to turn, none
         * flat, so no marks either (test_repair's split_signs_* orient such meshes again: nothing). */
    } else if (!(c->turned_over = tpk_alloc_large((size_t)(c->mesh.tet_count ? c->mesh.tet_count : 1)))) {
        return tpk_diag_fail(c->diag, "out of memory for the orientation of %lld tets", (long long)c->mesh.tet_count);
    } else if (tpk_orient_marked(&c->mesh, (c->o->drop_degenerate ? TPK_ORIENT_DROP_DEGENERATE : 0) |
                                        (c->o->strict_orientation ? TPK_ORIENT_REFUSE_INVERTED : 0),
                          c->o->threads, &os, c->turned_over, c->diag) != 0)
        return -1;
    c->rep->inverted_fixed = os.inverted_fixed;
    c->rep->degenerate_dropped = c->o->drop_degenerate ? os.degenerate : 0;
    c->rep->t_orient = tpk_now_seconds() - t;
    if (c->mesh.tet_count == 0)
        return tpk_diag_fail(c->diag, "%s: no tetrahedra left to write", c->o->input);
    return 0;
}

/* Neighbors by face matching, with folds refused, or cut (TPK-M06). */
static int connect_tets(conversion *c)
{
    announce(c->stage, c->stage_user, "connect");
    double t = tpk_now_seconds();
    c->neighbors = tpk_alloc_large(sizeof *c->neighbors * 4 * (size_t)(c->mesh.tet_count ? c->mesh.tet_count : 1));
    if (!c->neighbors)
        return tpk_diag_fail(c->diag, "out of memory for the neighbors of %lld tets", (long long)c->mesh.tet_count);
    /* The neighbors took the kept block that fits them (reorder's old tets); no other fits connect's
     * arrays, and one left kept would stay resident through the converter's peak. */
    tpk_release_kept();
    tpk_unfold_stats unfold;
    if (tpk_connect_unfolded(&c->mesh, c->turned_over, (c->o->skip_bad_cells ? TPK_UNFOLD_SKIP_BAD_TETS : 0) |
                                                           (c->o->cut_folds ? TPK_UNFOLD_CUT_FOLDS : 0),
                             c->o->threads, c->neighbors, &unfold, c->diag) != 0)
        return -1;
    c->rep->inverted_fixed -= unfold.bad_tets; /* left out, not turned over */
    c->rep->bad_cells_skipped += unfold.bad_tets;
    c->rep->folds_cut = unfold.folds_cut;
    tpk_release_kept(); /* the last stage to use them: writing wants no more large arrays */
    c->rep->t_connect = tpk_now_seconds() - t;
    return 0;
}

/* The levels (convert --levels), made between the file's own chunks and its META (tpk_write_begin, end):
 * the mesh's tets and the neighbors are then the simplifier's scratch (tpk_make_levels). */
static int make_levels(conversion *c, tpk_levels *levels, tpk_diag *diag)
{
    announce(c->stage, c->stage_user, "levels");
    double t0 = tpk_now_seconds();
    if (tpk_make_levels(c->o, &c->mesh, c->neighbors, c->o->levels, c->source_format, c->rep, levels, diag) != 0)
        return -1;
    c->rep->t_levels = tpk_now_seconds() - t0;
    c->rep->level_count = levels->count;
    for (int i = 0; i < levels->count; i++) {
        const tpk_level *l = &levels->level[i];
        c->rep->level[i].vertices = l->vertices, c->rep->level[i].tets = l->tets;
        c->rep->level[i].error_samples = l->error_samples;
        c->rep->level[i].error_max = l->error_max, c->rep->level[i].error_rms = l->error_rms;
        c->rep->level[i].shell_distance = l->shell_distance,
        c->rep->level[i].shell_tolerance = l->shell_tolerance, c->rep->level[i].seconds = l->seconds;
        c->rep->level[i].bytes = l->size;
    }
    announce(c->stage, c->stage_user, "write");
    return 0;
}

/* One file: its own chunks, the levels (with --levels), then META and the levels' chunks. */
static int write_file(conversion *c, tpk_levels *levels)
{
    tpk_write_session ws;
    if (tpk_write_begin(&ws, c->o, &c->mesh, c->neighbors, &c->header, c->diag) != 0)
        return -1;
    if (c->o->levels > 0 && make_levels(c, levels, c->diag) != 0) {
        tpk_write_abort(&ws);
        return -1;
    }
    return tpk_write_end(&ws, c->o, &c->header, c->rep, c->source_format, NULL, levels, c->diag);
}

static int write_output(conversion *c)
{
    announce(c->stage, c->stage_user, "write");
    double t = tpk_now_seconds();
    c->rep->vertices = c->mesh.vertex_count;
    c->rep->tets = c->mesh.tet_count;
    c->rep->field_count = c->mesh.field_count;
    c->rep->step_count = c->mesh.step_count > 0 ? c->mesh.step_count : 1;
    tpk_levels levels = {0};
    int rc = c->o->parts > 0 ? tpk_write_part_set(c->o, &c->mesh, c->neighbors, &c->header, c->rep, c->source_format,
                                                  c->diag)
                             : write_file(c, &levels);
    tpk_levels_free(&levels);
    if (rc != 0)
        return -1;
    c->rep->t_write = tpk_now_seconds() - t - c->rep->t_levels;
    return 0;
}

/* Before the frees of a finished conversion: the pages of its largest arrays given back on all of its
 * threads (tpk_release_pages), so that the frees' unmapping, after the timed stages but part of the
 * command's time, is not all on one core (grid 120 at 2 threads: 30 ms of munmap on one core). */
static void release_result_pages(const conversion *c)
{
    size_t tets = (size_t)(c->mesh.tet_count > 0 ? c->mesh.tet_count : 0);
    size_t vertices = (size_t)(c->mesh.vertex_count > 0 ? c->mesh.vertex_count : 0);
    if (c->neighbors)
        tpk_release_pages(c->neighbors, sizeof *c->neighbors * 4 * tets);
    if (c->mesh.tets)
        tpk_release_pages(c->mesh.tets, sizeof *c->mesh.tets * 4 * tets);
    if (c->mesh.tet_source)
        tpk_release_pages(c->mesh.tet_source, sizeof *c->mesh.tet_source * tets);
    if (c->mesh.points)
        tpk_release_pages(c->mesh.points, sizeof *c->mesh.points * 3 * vertices);
}

int tpk_convert(const tpk_convert_options *o, tpk_convert_report *rep, tpk_stage_fn stage,
                void *stage_user, tpk_diag *diag)
{
    conversion c;
    memset(&c, 0, sizeof c);
    memset(rep, 0, sizeof *rep);
    c.o = o, c.rep = rep, c.stage = stage, c.stage_user = stage_user, c.diag = diag;
    double t0 = tpk_now_seconds();
    int default_threads = tpk_set_default_threads(o->threads); /* the importers' threads too */
    int rc = read_source(&c);
    if (rc == 0) {
        double t = tpk_now_seconds();
        rc = whole_cells(&c);
        if (rc == 0)
            rc = make_tets(&c);
        rep->t_tetrahedralize = tpk_now_seconds() - t;
    }
    /* Reorder before orienting: orientation reads 4 points per tet, which are then near each other. */
    if (rc == 0 && !o->no_reorder) {
        double t = tpk_now_seconds();
        announce(stage, stage_user, "reorder");
        rc = tpk_reorder(&c.mesh, o->threads, diag);
        rep->t_reorder = tpk_now_seconds() - t;
    }
    if (rc == 0)
        rc = orient_tets(&c);
    if (rc == 0)
        rc = connect_tets(&c);
    if (rc == 0)
        rc = write_output(&c);
    rep->t_total = tpk_now_seconds() - t0;
    if (rc == 0) /* the arrays as the stages left them: sized by the counts */
        release_result_pages(&c);
    tpk_set_default_threads(default_threads);
    free(c.neighbors);
    free(c.turned_over);
    tpk_merge_report_free(&c.merged);
    free(c.higher.cell_source);
    tpk_refine_cells_free(&c.source_cells);
    tpk_mesh_free(&c.src);
    tpk_tetmesh_free(&c.mesh);
    return rc ? -1 : 0;
}
