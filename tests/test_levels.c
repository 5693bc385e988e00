/* Levels of detail (spec §16): the converter's levels of real meshes open as files, each coarser, every
 * tet positive (exactly, on the stored positions), the full mesh's domain (the same volume and shell area
 * when the shell may not move; else inside it, every shell point of the file within the reported shell
 * distance of the level's shell, by brute force), the full mesh's field at every kept vertex, and `check`
 * finds nothing (600..615) in them; must-fail files (a level
 * compressed, index 0, a level not coarser) are refused; the cost model of --max-ms picks
 * deterministically. CLI and more meshes: tests/cli/levels.sh. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/predicates.h"
#include "check/check.h"
#include "convert/convert.h"
#include "harness.h"
#include "render/budget.h"
#include "tetpack.h"
#include "tpk_assert.h"

static int convert_levels_within(const char *input, const char *output, int levels, double shell_error,
                                 tpk_convert_report *rep)
{
    tpk_convert_options o;
    memset(&o, 0, sizeof o);
    o.input = input;
    o.output = output;
    o.layouts = TPK_LAYOUT_BIT_TET16 | TPK_LAYOUT_BIT_TET32;
    o.levels = levels;
    o.level_shell_error = shell_error;
    o.threads = 2;
    tpk_diag diag = {0};
    memset(rep, 0, sizeof *rep);
    int rc = tpk_convert_checked(&o, rep, &diag);
    if (rc)
        fprintf(stderr, "%s: %s\n", input, diag.message);
    return rc;
}

static int convert_levels(const char *input, const char *output, int levels, tpk_convert_report *rep)
{
    return convert_levels_within(input, output, levels, 0, rep);
}

/* Shell triangles as sorted world-coordinate triples, sorted: the same set for the same shell. */
typedef struct { double p[9]; } tri;
static int compare_tri(const void *a, const void *b)
{
    const double *x = ((const tri *)a)->p, *y = ((const tri *)b)->p;
    for (int k = 0; k < 9; k++)
        if (x[k] != y[k])
            return x[k] < y[k] ? -1 : 1;
    return 0;
}
static int lex3(const double *a, const double *b)
{
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k])
            return a[k] < b[k] ? -1 : 1;
    return 0;
}
static tri *shell_of(const tpk_mesh_arrays *m)
{
    tri *t = malloc(sizeof *t * (m->shell_face_count ? m->shell_face_count : 1));
    for (uint64_t i = 0; t && i < m->shell_face_count; i++) {
        const int32_t v[3] = {m->shell[i].a, m->shell[i].b, m->shell[i].c};
        double p[3][3];
        for (int j = 0; j < 3; j++)
            for (int k = 0; k < 3; k++)
                p[j][k] = m->origin[k] + (double)m->positions[3 * (size_t)v[j] + k];
        for (int i2 = 0; i2 < 2; i2++) /* the three corners in lexicographic order */
            for (int j = 0; j < 2 - i2; j++)
                if (lex3(p[j], p[j + 1]) > 0) {
                    double x[3];
                    memcpy(x, p[j], sizeof x);
                    memcpy(p[j], p[j + 1], sizeof x);
                    memcpy(p[j + 1], x, sizeof x);
                }
        memcpy(t[i].p, p, sizeof t[i].p);
    }
    if (t)
        qsort(t, m->shell_face_count, sizeof *t, compare_tri);
    return t;
}

/* The volume of the mesh's tets, in world coordinates. */
static double volume_of(const tpk_mesh_arrays *m)
{
    int32_t *tets = malloc(sizeof *tets * 4 * (m->tet_count ? m->tet_count : 1));
    double sum = 0;
    if (tets && tpk_recover_tets(m, tets) == TPK_OK)
        for (uint64_t t = 0; t < m->tet_count; t++) {
            double p[4][3];
            for (int j = 0; j < 4; j++)
                for (int a = 0; a < 3; a++)
                    p[j][a] = (double)m->positions[3 * (size_t)tets[4 * t + j] + a];
            double b[3], c[3], d[3];
            for (int a = 0; a < 3; a++)
                b[a] = p[1][a] - p[0][a], c[a] = p[2][a] - p[0][a], d[a] = p[3][a] - p[0][a];
            sum += (b[0] * (c[1] * d[2] - c[2] * d[1]) - b[1] * (c[0] * d[2] - c[2] * d[0]) +
                    b[2] * (c[0] * d[1] - c[1] * d[0])) / 6;
        }
    free(tets);
    return sum;
}

static double area_of(const tri *t, uint64_t count)
{
    double sum = 0;
    for (uint64_t i = 0; t && i < count; i++) {
        const double *p = t[i].p;
        double b[3], c[3];
        for (int a = 0; a < 3; a++)
            b[a] = p[3 + a] - p[a], c[a] = p[6 + a] - p[a];
        double x = b[1] * c[2] - b[2] * c[1], y = b[2] * c[0] - b[0] * c[2], z = b[0] * c[1] - b[1] * c[0];
        sum += sqrt(x * x + y * y + z * z) / 2;
    }
    return sum;
}

/* The distance from p to the triangle t (by projection into its plane, else to its three edges). */
static double distance_to(const double *p, const double *t)
{
    const double *a = t, *b = t + 3, *c = t + 6;
    double best = INFINITY;
    for (int e = 0; e < 3; e++) { /* the edges, as segments */
        const double *x = e == 0 ? a : e == 1 ? b : c, *y = e == 0 ? b : e == 1 ? c : a;
        double d[3], w[3], dd = 0, dw = 0;
        for (int k = 0; k < 3; k++)
            d[k] = y[k] - x[k], w[k] = p[k] - x[k], dd += d[k] * d[k], dw += d[k] * w[k];
        double s = dd > 0 ? dw / dd : 0, r = 0;
        s = s < 0 ? 0 : s > 1 ? 1 : s;
        for (int k = 0; k < 3; k++)
            r += (w[k] - s * d[k]) * (w[k] - s * d[k]);
        best = sqrt(r) < best ? sqrt(r) : best;
    }
    double ab[3], ac[3], ap[3], n[3];
    for (int k = 0; k < 3; k++)
        ab[k] = b[k] - a[k], ac[k] = c[k] - a[k], ap[k] = p[k] - a[k];
    n[0] = ab[1] * ac[2] - ab[2] * ac[1], n[1] = ab[2] * ac[0] - ab[0] * ac[2], n[2] = ab[0] * ac[1] - ab[1] * ac[0];
    double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if (nn > 0) { /* inside: the three sub-triangles turn the same way as the face */
        double h = (ap[0] * n[0] + ap[1] * n[1] + ap[2] * n[2]) / nn, q[3];
        for (int k = 0; k < 3; k++)
            q[k] = p[k] - h * n[k];
        int inside = 1;
        for (int e = 0; e < 3; e++) {
            const double *x = e == 0 ? a : e == 1 ? b : c, *y = e == 0 ? b : e == 1 ? c : a;
            double u[3], v[3];
            for (int k = 0; k < 3; k++)
                u[k] = y[k] - x[k], v[k] = q[k] - x[k];
            double cx = u[1] * v[2] - u[2] * v[1], cy = u[2] * v[0] - u[0] * v[2], cz = u[0] * v[1] - u[1] * v[0];
            inside &= cx * n[0] + cy * n[1] + cz * n[2] >= 0;
        }
        if (inside)
            best = fabs(h) * sqrt(nn) < best ? fabs(h) * sqrt(nn) : best;
    }
    return best;
}

/* The farthest any corner of the file's shell lies from the level's shell, by brute force. */
static double farthest_from(const tri *full, uint64_t full_count, const tri *level, uint64_t level_count)
{
    double worst = 0;
    for (uint64_t i = 0; full && level && i < full_count; i++)
        for (int j = 0; j < 3; j++) {
            double best = INFINITY;
            for (uint64_t f = 0; f < level_count && best > 0; f++) {
                double d = distance_to(full[i].p + 3 * j, level[f].p);
                best = d < best ? d : best;
            }
            worst = best > worst ? best : worst;
        }
    return worst;
}

/* Every level of `path` (as rep reported them): opens, fewer tets, positive tets, the domain (see the
 * top), the same values at the same source points (VMAP), and check 600..615 find nothing. */
static void check_levels_of(const char *path, int expect_levels, const tpk_convert_report *rep)
{
    tpk_file *file = NULL;
    CHECK(tpk_open_path(&file, path, NULL, NULL, 0) == TPK_OK);
    if (!file)
        return;
    CHECK_MSG((int)tpk_level_count(file) >= expect_levels, "%s: %u levels", path, tpk_level_count(file));
    tpk_mesh_arrays full;
    CHECK(tpk_load_arrays(file, TPK_LAYOUT_TET32, NULL, 0, &full) == TPK_OK);
    tri *full_shell = shell_of(&full);
    double full_volume = volume_of(&full), full_area = area_of(full_shell, full.shell_face_count), diagonal = 0;
    for (int a = 0; a < 3; a++) {
        double lo = INFINITY, hi = -INFINITY;
        for (uint64_t v = 0; v < full.vertex_count; v++)
            lo = fmin(lo, full.positions[3 * v + a]), hi = fmax(hi, full.positions[3 * v + a]);
        diagonal += full.vertex_count ? (hi - lo) * (hi - lo) : 0;
    }
    diagonal = sqrt(diagonal);
    uint64_t i;
    const int32_t *full_vmap = NULL;
    const void *view;
    uint64_t size;
    if (tpk_find_chunk(file, TPK_TAG_VMAP, 0, 0, &i) == TPK_OK && tpk_view_chunk(file, i, &view, &size) == TPK_OK)
        full_vmap = view;
    uint64_t before = full.tet_count;
    for (uint32_t k = 1; k <= tpk_level_count(file); k++) {
        tpk_file *lf = NULL;
        char err[512] = "";
        CHECK_MSG(tpk_open_level(file, k, NULL, &lf, err, sizeof err) == TPK_OK, "level %u: %s", k, err);
        if (!lf)
            continue;
        tpk_mesh_arrays m;
        CHECK(tpk_load_arrays(lf, TPK_LAYOUT_TET32, NULL, 0, &m) == TPK_OK);
        CHECK_MSG(m.tet_count < before, "level %u: %llu tets, not fewer than %llu", k, (unsigned long long)m.tet_count,
                  (unsigned long long)before);
        before = m.tet_count;
        int negative = 0;
        int32_t *tets = malloc(sizeof *tets * 4 * (m.tet_count ? m.tet_count : 1));
        CHECK(tets && tpk_recover_tets(&m, tets) == TPK_OK);
        for (uint64_t t = 0; tets && t < m.tet_count; t++) {
            double p[4][3];
            for (int j = 0; j < 4; j++)
                for (int a = 0; a < 3; a++)
                    p[j][a] = m.positions[3 * (size_t)tets[4 * t + j] + a];
            negative += tpk_orient3d_exact(p[0], p[1], p[2], p[3]) <= 0;
        }
        free(tets);
        CHECK_MSG(negative == 0, "level %u: %d tets not positive", k, negative);
        CHECK_MSG(m.shell_face_count <= full.shell_face_count, "level %u: %llu shell faces, the file %llu", k,
                  (unsigned long long)m.shell_face_count, (unsigned long long)full.shell_face_count);
        tri *shell = shell_of(&m);
        double volume = volume_of(&m), area = area_of(shell, m.shell_face_count), moved = rep->level[k - 1].shell_distance;
        if (rep->level[k - 1].shell_tolerance == 0) /* only flat pieces moved: the same surface */
            CHECK_MSG(moved == 0 && fabs(volume - full_volume) <= 1e-9 * full_volume &&
                          fabs(area - full_area) <= 1e-9 * full_area,
                      "level %u: shell distance %g, volume %.17g and area %.17g against the file's %.17g and %.17g", k,
                      moved, volume, area, full_volume, full_area);
        else /* moved inward, within the distance reported (positions are floats: 1e-6 of the diagonal) */
            CHECK_MSG(moved <= rep->level[k - 1].shell_tolerance * (1 + 1e-9) && volume <= full_volume * (1 + 1e-9) &&
                          volume >= full_volume - moved * full_area * (1 + 1e-9),
                      "level %u: shell distance %g (allowed %g), volume %.17g against the file's %.17g", k, moved,
                      rep->level[k - 1].shell_tolerance, volume, full_volume);
        double farthest = farthest_from(full_shell, full.shell_face_count, shell, m.shell_face_count);
        CHECK_MSG(farthest <= moved * (1 + 1e-9) + 1e-6 * diagonal, "level %u: a shell point of the file lies %.17g "
                  "from the level's shell, which reports %.17g", k, farthest, moved);
        free(shell);
        /* the kept vertices keep their positions and values: by VMAP (source point ids) */
        if (full_vmap && full.scalars && m.scalars && tpk_find_chunk(lf, TPK_TAG_VMAP, 0, 0, &i) == TPK_OK &&
            tpk_view_chunk(lf, i, &view, &size) == TPK_OK) {
            const int32_t *vmap = view;
            int64_t max_src = 0;
            for (uint64_t v = 0; v < full.vertex_count; v++)
                max_src = full_vmap[v] > max_src ? full_vmap[v] : max_src;
            int32_t *by_src = malloc(sizeof *by_src * (size_t)(max_src + 1));
            for (int64_t sidx = 0; by_src && sidx <= max_src; sidx++)
                by_src[sidx] = -1;
            for (uint64_t v = 0; by_src && v < full.vertex_count; v++)
                if (full_vmap[v] >= 0)
                    by_src[full_vmap[v]] = (int32_t)v;
            int differ = 0;
            for (uint64_t v = 0; by_src && v < m.vertex_count; v++) {
                if (vmap[v] < 0)
                    continue;
                int32_t f = by_src[vmap[v]];
                differ += f < 0 || m.scalars[v] != full.scalars[f] ||
                          memcmp(m.positions + 3 * v, full.positions + 3 * (size_t)f, 3 * sizeof(float));
            }
            CHECK_MSG(differ == 0, "level %u: %d vertices differ from the file's vertex of their source point", k,
                      differ);
            free(by_src);
        }
        tpk_close(lf);
    }
    free(full_shell);
    tpk_close(file);
    /* and the validator: no 6xx finding in the file or any level, and 615 clean */
    tpk_check_report report;
    tpk_check_options o;
    tpk_check_options_default(&o);
    o.threads = 2;
    CHECK(tpk_check_report_init(&report, &o) == 0);
    tpk_diag diag = {0};
    CHECK(tpk_open_path(&file, path, NULL, NULL, 0) == TPK_OK);
    CHECK(tpk_check_tpk_file(path, file, &report, &diag) == 0);
    CHECK(tpk_check_levels(path, file, &report, &diag) == 0);
    for (int id = 600; id <= 615; id++)
        CHECK_MSG(tpk_check_finding(&report, id)->count == 0, "%s: check %d: %lld", path, id,
                  (long long)tpk_check_finding(&report, id)->count);
    tpk_close(file);
    tpk_check_report_free(&report);
}

/* The shell faces of level k of the file at path (-1 when it does not open). */
static int64_t level_shell_faces(const char *path, uint32_t k)
{
    tpk_file *file = NULL, *lf = NULL;
    int64_t n = -1;
    char err[256];
    if (tpk_open_path(&file, path, NULL, NULL, 0) == TPK_OK && tpk_open_level(file, k, NULL, &lf, err, sizeof err) == TPK_OK) {
        tpk_file_info info;
        tpk_get_info(lf, &info);
        n = (int64_t)info.shell_face_count;
    }
    tpk_close(lf);
    tpk_close(file);
    return n;
}

TPK_TEST(real_meshes_levels_valid)
{
    const char *out = tpk_temp_path("cyl.tpk");
    tpk_convert_report rep;
    char sample[4096]; /* the bundled sample: a point field, "temperature" */
    snprintf(sample, sizeof sample, "%s/samples/cylinder.vtk", TPK_SOURCE_DIR);
    CHECK(convert_levels(sample, out, 3, &rep) == 0);
    CHECK_MSG(rep.level_count >= 1, "cylinder: %d levels", rep.level_count);
    CHECK(rep.level[0].error_samples > 0 && rep.level[0].error_max >= rep.level[0].error_rms &&
          rep.level[0].shell_distance == 0);
    check_levels_of(out, 1, &rep);
    /* the cylinder's flat ends coarsen with the shell kept exactly (check_levels_of: the same volume and area) */
    CHECK_MSG(level_shell_faces(out, 1) > 0 && level_shell_faces(out, 1) < rep.shell_faces,
              "cylinder: level 1 has %lld shell faces, the file %lld", (long long)level_shell_faces(out, 1),
              (long long)rep.shell_faces);
    /* the shell moved inward too, within a tolerance: fewer shell faces, the distance measured */
    int64_t exact_tets = rep.level[0].tets;
    const char *moved = tpk_temp_path("cyl_moved.tpk");
    CHECK(convert_levels_within(sample, moved, 3, 0.005, &rep) == 0);
    CHECK_MSG(rep.level_count >= 1 && rep.level[0].shell_tolerance > 0 && rep.level[0].tets <= exact_tets,
              "cylinder within 0.005: %d levels, %lld tets (%lld exactly)", rep.level_count,
              rep.level_count ? (long long)rep.level[0].tets : -1LL, (long long)exact_tets);
    check_levels_of(moved, 1, &rep);
    const char *t5 = tpk_temp_path("t5.tpk");
    CHECK(convert_levels(tpk_data_path("gmsh/t5_small_tet_ascii22.msh"), t5, 4, &rep) == 0);
    CHECK_MSG(rep.level_count >= 1, "t5: %d levels", rep.level_count);
    check_levels_of(t5, 1, &rep);
    const char *blocks = tpk_temp_path("blocks.tpk");
    CHECK(convert_levels(tpk_data_path("seacas/8-block.g"), blocks, 2, &rep) == 0);
    check_levels_of(blocks, 1, &rep);
}

/* The error is measured at every vertex a level removed, in a mesh whose blocks lie against each other
 * without sharing faces (exomerge: a walk from the last point's tet cannot cross to another block, so
 * before the walk also started from the vertex the removed one ended on, 69 of 573 were measured). */
TPK_TEST(levels_error_at_every_removed_vertex)
{
    const char *out = tpk_temp_path("exomerge.tpk");
    tpk_convert_report rep;
    CHECK(convert_levels_within(tpk_data_path("seacas/exomerge_unit_test.e"), out, 1, TPK_LEVEL_SHELL_ERROR, &rep) == 0);
    CHECK_MSG(rep.level_count == 1, "exomerge: %d levels", rep.level_count);
    int64_t removed = rep.vertices - rep.level[0].vertices;
    CHECK_MSG(removed > 0 && rep.level[0].error_samples == removed, "exomerge: error at %lld of %lld removed vertices",
              (long long)rep.level[0].error_samples, (long long)removed);
    check_levels_of(out, 1, &rep);
}

/* A copy of `src` (every chunk decoded and written again) with one LEVL chunk of `level` bytes. */
static int write_with_level(const char *src, const char *dst, const void *level, size_t size, uint32_t index,
                            int codec)
{
    tpk_file *f = NULL;
    if (tpk_open_path(&f, src, NULL, NULL, 0) != TPK_OK)
        return -1;
    tpk_file_info info;
    tpk_get_info(f, &info);
    tpk_writer *w = NULL;
    int rc = tpk_writer_open(&w, dst, NULL, NULL, 0) == TPK_OK ? 0 : -1;
    for (uint64_t i = 0; rc == 0 && i < info.chunk_count; i++) {
        tpk_dir_entry e;
        tpk_get_chunk(f, i, &e);
        if (e.tag == TPK_TAG_LEVL)
            continue;
        void *data = malloc(e.raw_size ? e.raw_size : 1);
        tpk_chunk_desc d = {.tag = e.tag, .flags = e.flags, .codec = TPK_CODEC_NONE, .elem_type = e.elem_type,
                            .elem_size = e.elem_size, .index = e.index, .step = e.step, .elem_count = e.elem_count};
        rc = data && tpk_read_chunk(f, i, data, e.raw_size) == TPK_OK && tpk_writer_add_chunk(w, &d, data) == TPK_OK
                 ? 0 : -1;
        free(data);
    }
    tpk_chunk_desc l = {.tag = TPK_TAG_LEVL, .codec = (uint8_t)codec, .elem_type = TPK_ELEM_BYTE, .elem_size = 1,
                        .index = index, .elem_count = size};
    if (rc == 0 && tpk_writer_add_chunk(w, &l, level) != TPK_OK)
        rc = -1;
    tpk_header_fields h = {info.vertex_count, info.tet_count, info.shell_face_count, {0}, {0}, {0}};
    memcpy(h.origin, info.origin, sizeof h.origin);
    memcpy(h.bounds_min, info.bounds_min, sizeof h.bounds_min);
    memcpy(h.bounds_max, info.bounds_max, sizeof h.bounds_max);
    if (rc == 0)
        rc = tpk_writer_finish(w, &h) == TPK_OK ? 0 : -1;
    else if (w)
        tpk_writer_abort(w);
    tpk_close(f);
    return rc;
}

static void *file_bytes(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    *size = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    void *b = malloc(*size);
    if (b && fread(b, 1, *size, f) != *size) {
        free(b);
        b = NULL;
    }
    fclose(f);
    return b;
}

TPK_TEST(must_fail_levels)
{
    tpk_convert_report rep;
    const char *plain = tpk_temp_path("plain.tpk");
    CHECK(convert_levels(tpk_data_path("sfepy/cylinder.vtk"), plain, 0, &rep) == 0);
    size_t size = 0;
    void *bytes = file_bytes(plain, &size);
    CHECK(bytes && size > 0);
    if (!bytes)
        return;
    /* the file itself as its own level 1: not coarser (615) */
    const char *same = tpk_temp_path("same.tpk");
    CHECK(write_with_level(plain, same, bytes, size, 1, TPK_CODEC_NONE) == 0);
    tpk_check_report report;
    tpk_check_options o;
    tpk_check_options_default(&o);
    CHECK(tpk_check_report_init(&report, &o) == 0);
    tpk_file *file = NULL;
    tpk_diag diag = {0};
    CHECK(tpk_open_path(&file, same, NULL, NULL, 0) == TPK_OK);
    CHECK(file && tpk_check_levels(same, file, &report, &diag) == 0);
    CHECK_MSG(tpk_check_finding(&report, 615)->count == 1, "615: %lld", (long long)tpk_check_finding(&report, 615)->count);
    tpk_close(file);
    tpk_check_report_free(&report);
    /* a level that is not a tetpack file: 615 (it does not open) */
    const char *junk = tpk_temp_path("junk.tpk");
    CHECK(write_with_level(plain, junk, "not a tetpack file", 18, 1, TPK_CODEC_NONE) == 0);
    CHECK(tpk_check_report_init(&report, &o) == 0);
    CHECK(tpk_open_path(&file, junk, NULL, NULL, 0) == TPK_OK);
    tpk_file *lf = NULL;
    char err[512] = "";
    CHECK(tpk_open_level(file, 1, NULL, &lf, err, sizeof err) != TPK_OK && !lf && strstr(err, "level 1"));
    CHECK(tpk_open_level(file, 2, NULL, &lf, err, sizeof err) == TPK_ERR_NOT_FOUND && strstr(err, "no level 2"));
    CHECK(file && tpk_check_levels(junk, file, &report, &diag) == 0 && tpk_check_finding(&report, 615)->count == 1);
    tpk_close(file);
    tpk_check_report_free(&report);
    /* refused at open (rule 14): a compressed level, a level 0 (the writer refuses to write them) */
    const char *zstd = tpk_temp_path("zstd.tpk"), *zero = tpk_temp_path("zero.tpk");
    CHECK(write_with_level(plain, zstd, bytes, size, 1, TPK_CODEC_ZSTD) != 0);
    CHECK(write_with_level(plain, zero, bytes, size, 0, TPK_CODEC_NONE) != 0);
    free(bytes);
}

TPK_TEST(cost_model)
{
    tpk_cost_model m = {0};
    int64_t tets[3] = {1000000, 125000, 8000}; /* cube roots 100, 50, 20 */
    CHECK_EQ_INT(tpk_cost_model_pick(&m, 1e4, tets, 3, 1.0), 0); /* no frames: predicts 0, the finest */
    /* frames of 0.1 s + 1e-8 s per pixel and cube root of tets, at two sizes: the fit recovers both */
    tpk_cost_model_add(&m, 4096, 8000, 0.1 + 1e-8 * 4096 * 20);
    tpk_cost_model_add(&m, 16384, 8000, 0.1 + 1e-8 * 16384 * 20);
    double fixed, rate;
    tpk_cost_model_fit(&m, &fixed, &rate);
    CHECK_MSG(fabs(fixed - 0.1) < 1e-9 && fabs(rate - 1e-8) < 1e-15, "fixed %g rate %g", fixed, rate);
    double px = 262144; /* 512^2: 0.1 + 0.262 (level 0), + 0.131 (1), + 0.052 (2) */
    CHECK(fabs(tpk_cost_model_predict(&m, px, 1000000) - (0.1 + 1e-8 * px * 100)) < 1e-9);
    CHECK_EQ_INT(tpk_cost_model_pick(&m, px, tets, 3, 0.40), 0);
    CHECK_EQ_INT(tpk_cost_model_pick(&m, px, tets, 3, 0.30), 1);
    CHECK_EQ_INT(tpk_cost_model_pick(&m, px, tets, 3, 0.20), 2);
    CHECK_EQ_INT(tpk_cost_model_pick(&m, px, tets, 3, 0.01), 2); /* none fits: the coarsest */
    /* one size only: the line through the origin */
    tpk_cost_model one = {0};
    tpk_cost_model_add(&one, 1000, 1000, 0.5);
    tpk_cost_model_fit(&one, &fixed, &rate);
    CHECK(fixed == 0 && fabs(rate - 0.5 / (1000 * 10)) < 1e-15);
    /* nonsense frames are not learnt from */
    tpk_cost_model_add(&one, 0, 1000, 1);
    tpk_cost_model_add(&one, 1000, 1000, NAN);
    CHECK(one.n == 1);
}

/* Past the coarsest level, the pixel step: the smallest that the model predicts to fit, by its closed
 * form (0.1 s + 1e-8 s per ray and cube root of tets). */
TPK_TEST(pixel_step)
{
    tpk_cost_model m = {0};
    CHECK_EQ_INT(tpk_cost_model_pixel_step(&m, 262144, 8000, 1e-9, 8), 1); /* no frames: every pixel */
    tpk_cost_model_add(&m, 4096, 8000, 0.1 + 1e-8 * 4096 * 20);
    tpk_cost_model_add(&m, 16384, 8000, 0.1 + 1e-8 * 16384 * 20);
    /* 512^2 on 8000 tets: 0.1 + 0.0524 s; at step d, 0.1 + 0.0524 / d^2 */
    CHECK_EQ_INT(tpk_cost_model_pixel_step(&m, 262144, 8000, 0.16, 8), 1);
    CHECK_EQ_INT(tpk_cost_model_pixel_step(&m, 262144, 8000, 0.12, 8), 2);  /* d^2 >= 2.6 */
    CHECK_EQ_INT(tpk_cost_model_pixel_step(&m, 262144, 8000, 0.104, 8), 4); /* d^2 >= 13.1 */
    CHECK_EQ_INT(tpk_cost_model_pixel_step(&m, 262144, 8000, 0.101, 16), 8);
    CHECK_EQ_INT(tpk_cost_model_pixel_step(&m, 262144, 8000, 0.104, 3), 3); /* the cap */
    CHECK_EQ_INT(tpk_cost_model_pixel_step(&m, 262144, 8000, 0.05, 8), 8);  /* below the fixed cost */
    CHECK_EQ_INT(tpk_cost_model_pixel_step(&m, 262144, 8000, 0.05, 1), 1);
    int w, h;
    tpk_pixel_step_size(512, 512, 3, &w, &h);
    CHECK(w == 171 && h == 171);
    tpk_pixel_step_size(1000, 700, 8, &w, &h);
    CHECK(w == 125 && h == 88);
    tpk_pixel_step_size(5, 3, 8, &w, &h);
    CHECK(w == 1 && h == 1);
}

/* The upscaled picture against closed forms: a picture at its own size comes back as it was; a linear
 * ramp stays the same ramp, the point of the small picture seen in the same direction as each pixel
 * (a small picture of another aspect ratio too, its field of view following it); a transparent pixel
 * lends no color. */
TPK_TEST(image_upscale)
{
    enum { SW = 6, SH = 4 };
    uint8_t src[SW * SH * 4], same[SW * SH * 4];
    for (int i = 0; i < SW * SH; i++)
        for (int k = 0; k < 4; k++)
            src[4 * i + k] = (uint8_t)(k == 3 ? 1 + (i * 37) % 255 : (i * 11 + k * 50) % 256);
    CHECK(tpk_image_upscale(src, SW, SH, same, SW, SH) == 0);
    for (int i = 0; i < SW * SH * 4; i++)
        if (same[i] != src[i]) {
            CHECK_MSG(0, "byte %d: %d, expected %d", i, same[i], src[i]);
            break;
        }
    /* red = 40 x + 20 (x the small picture's column), green = 60 y + 10, opaque */
    for (int y = 0; y < SH; y++)
        for (int x = 0; x < SW; x++) {
            uint8_t *p = &src[4 * (y * SW + x)];
            p[0] = (uint8_t)(40 * x + 20), p[1] = (uint8_t)(60 * y + 10), p[2] = 0, p[3] = 255;
        }
    const int sizes[2][2] = {{24, 16}, {30, 16}}; /* 4 times; and wider than 6 x 4 at that height */
    for (int c = 0; c < 2; c++) {
        int dw = sizes[c][0], dh = sizes[c][1];
        uint8_t *dst = malloc((size_t)dw * dh * 4);
        CHECK(dst && tpk_image_upscale(src, SW, SH, dst, dw, dh) == 0);
        if (!dst)
            return;
        double s = (double)SH / dh;
        for (int y = 0; y < dh; y++)
            for (int x = 0; x < dw; x++) {
                double fx = (x + 0.5 - 0.5 * dw) * s + 0.5 * SW - 0.5, fy = (y + 0.5) * s - 0.5;
                fx = fx < 0 ? 0 : fx > SW - 1 ? SW - 1 : fx;
                fy = fy < 0 ? 0 : fy > SH - 1 ? SH - 1 : fy;
                const uint8_t *p = &dst[4 * (y * dw + x)];
                CHECK_MSG(fabs(p[0] - (40 * fx + 20)) <= 0.5 + 1e-3 && fabs(p[1] - (60 * fy + 10)) <= 0.5 + 1e-3 &&
                              p[2] == 0 && p[3] == 255,
                          "%dx%d pixel (%d, %d): %d %d %d %d", dw, dh, x, y, p[0], p[1], p[2], p[3]);
            }
        free(dst);
    }
    /* opaque red beside transparent blue: half way, half the alpha and all of it red */
    const uint8_t two[8] = {255, 0, 0, 255, 0, 0, 255, 0};
    uint8_t out[4 * 2 * 4]; /* 4 x 2 pixels */
    CHECK(tpk_image_upscale(two, 2, 1, out, 4, 2) == 0);
    CHECK(out[0] == 255 && out[2] == 0 && out[3] == 255);              /* clamped at the edge */
    CHECK(out[4] == 255 && out[5] == 0 && out[6] == 0 && out[7] == 191); /* a quarter of the way */
    CHECK(out[12 + 3] == 0);
    CHECK(memcmp(out, out + 16, 16) == 0); /* one row in: both rows out the same */
}

/* The committed vectors of spec §13 (format 1.3): two_tets_levels.tpk's level is tet 0 alone, with the
 * parent's fields; level_not_coarser.tpk is check 615. */
TPK_TEST(level_vectors)
{
    char path[4096], bad[4096];
    snprintf(path, sizeof path, "%s/samples/vectors/two_tets_levels.tpk", TPK_SOURCE_DIR);
    snprintf(bad, sizeof bad, "%s/samples/vectors/level_not_coarser.tpk", TPK_SOURCE_DIR);
    tpk_file *file = NULL, *lf = NULL;
    CHECK(tpk_open_path(&file, path, NULL, NULL, 0) == TPK_OK);
    if (!file)
        return;
    tpk_file_info info;
    tpk_get_info(file, &info);
    CHECK(info.version_minor == 3 && tpk_level_count(file) == 1);
    char err[256] = "";
    CHECK(tpk_open_level(file, 1, NULL, &lf, err, sizeof err) == TPK_OK);
    if (lf) {
        tpk_mesh_arrays m;
        CHECK(tpk_load_arrays(lf, TPK_LAYOUT_TET16, "temperature", 1, &m) == TPK_OK);
        CHECK(m.tet_count == 1 && m.vertex_count == 4 && m.shell_face_count == 4 && m.scalars[3] == 314);
        CHECK(tpk_verify(lf) == TPK_OK);
        tpk_close(lf);
    }
    tpk_check_report report;
    tpk_check_options o;
    tpk_check_options_default(&o);
    CHECK(tpk_check_report_init(&report, &o) == 0);
    tpk_diag diag = {0};
    CHECK(tpk_check_tpk_file(path, file, &report, &diag) == 0 && tpk_check_levels(path, file, &report, &diag) == 0);
    for (int id = 600; id <= 615; id++)
        CHECK_MSG(tpk_check_finding(&report, id)->count == 0, "check %d", id);
    tpk_check_report_free(&report);
    tpk_close(file);
    CHECK(tpk_open_path(&file, bad, NULL, NULL, 0) == TPK_OK);
    CHECK(tpk_check_report_init(&report, &o) == 0);
    CHECK(file && tpk_check_levels(bad, file, &report, &diag) == 0 && tpk_check_finding(&report, 615)->count == 1);
    tpk_check_report_free(&report);
    tpk_close(file);
}

