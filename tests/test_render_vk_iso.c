/* Marching tetrahedra in Vulkan compute (tools/render_vk/vk_iso.c, shaders/iso.comp) against the CPU's
 * (tools/iso/): the same corner keys in the same order, so the same surface byte for byte; the shader's
 * own float positions within float rounding of the CPU's; values on vertices (at or above), NaN tets,
 * empty surfaces and several groups of dispatches. On lavapipe in CI; skipped without a Vulkan device. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "iso/iso.h"
#include "march_fixtures.h"
#include "render_vk/render_vk.h"
#include "render_vk/render_vk_internal.h"
#include "vk_device.h"

static tpk_iso_input input_of(const fx_mesh *m)
{
    tpk_iso_input in;
    memset(&in, 0, sizeof in);
    in.vertex_count = m->vertex_count;
    in.tet_count = m->tet_count;
    memcpy(in.origin, m->origin, sizeof in.origin);
    in.positions = m->positions;
    in.tets = m->tets;
    in.scalars = m->scalars;
    return in;
}

static int same_surface(const tpk_iso_surface *a, const tpk_iso_surface *b)
{
    size_t v = (size_t)a->vertex_count, t = (size_t)a->triangle_count;
    return a->vertex_count == b->vertex_count && a->triangle_count == b->triangle_count &&
           !memcmp(a->xyz, b->xyz, 3 * v * sizeof *a->xyz) && !memcmp(a->normal, b->normal, 3 * v * sizeof *a->normal) &&
           !memcmp(a->value, b->value, v * sizeof *a->value) && !memcmp(a->edge, b->edge, 2 * v * sizeof *a->edge) &&
           !memcmp(a->tri, b->tri, 3 * t * sizeof *a->tri);
}

/* CPU and Vulkan on one mesh and field: same surface; the shader's positions within float rounding. */
static void compare(const fx_mesh *m, const double *values, int count, int64_t want_triangles_at_least)
{
    tpk_iso_input in = input_of(m);
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    tpk_iso_surface cpu, gpu;
    CHECK_MSG(tpk_iso_extract(&in, values, count, 2, &cpu, &diag) == 0, "%s", diag.message);
    tpk_iso_vk *vk = NULL;
    CHECK_MSG(tpk_iso_vk_create(&vk, &in, &diag) == 0, "%s", diag.message);
    tpk_iso_corners corners = tpk_iso_vk_corners(vk);
    CHECK_MSG(tpk_iso_extract_from(&in, values, count, 2, &corners, &gpu, &diag) == 0, "%s", diag.message);
    CHECK_MSG(same_surface(&cpu, &gpu), "%lld/%lld triangles and %lld/%lld vertices (cpu/vulkan), or their data differ",
              (long long)cpu.triangle_count, (long long)gpu.triangle_count, (long long)cpu.vertex_count,
              (long long)gpu.vertex_count);
    CHECK_MSG(cpu.triangle_count >= want_triangles_at_least, "%lld triangles", (long long)cpu.triangle_count);
    /* the triangle list the shader drew up: each corner near the CPU's vertex of that corner */
    int64_t first = 0;
    for (int i = 0; i < count; i++) {
        uint64_t *keys;
        float *pos;
        int64_t tris;
        CHECK_MSG(tpk_iso_vk_emit(vk, values[i], &keys, &pos, &tris, &diag) == 0, "%s", diag.message);
        CHECK(tris == cpu.value_triangles[i]);
        uint32_t counted = 0; /* the count alone (passes 0..2), as the mesh-shader raster path takes it */
        CHECK_MSG(tpk_iso_vk_triangles(vk, values[i], &counted, &diag) == 0, "%s", diag.message);
        CHECK_MSG((int64_t)counted == tris, "counted %u, emitted %lld", counted, (long long)tris);
        for (int64_t c = 0; c < 3 * tris; c++) {
            uint32_t vtx = cpu.tri[3 * first + c];
            uint64_t key = (uint64_t)(uint32_t)cpu.edge[2 * vtx] << 32 | (uint32_t)cpu.edge[2 * vtx + 1];
            CHECK(keys[c] == key);
            for (int k = 0; k < 3; k++) {
                double want = cpu.xyz[3 * vtx + k] - m->origin[k];
                CHECK_MSG(fabs(pos[3 * c + k] - want) <= 1e-5 * (1 + fabs(want)), "corner %lld: %g, CPU %g",
                          (long long)c, pos[3 * c + k], want);
            }
        }
        first += tris;
        free(keys);
        free(pos);
    }
    /* the passes' device time (timestamps) lies within the wall time of the submissions that held them */
    double timed = tpk_iso_vk_gpu_seconds(vk);
    CHECK_MSG(timed == -1.0 || (timed > 0 && timed <= tpk_iso_vk_seconds(vk)), "timed %g, wall %g", timed,
              tpk_iso_vk_seconds(vk));
    tpk_iso_vk_destroy(vk);
    tpk_iso_surface_free(&cpu);
    tpk_iso_surface_free(&gpu);
}

TPK_TEST(vulkan_equals_cpu)
{
    if (!have_device())
        return;
    fx_mesh m;
    CHECK(fx_grid(&m, 24, 20, 18, NULL, 1.0, NULL) == 0 && fx_build(&m) == 0); /* 51,840 tets: 203 groups */
    m.scalars = malloc(sizeof *m.scalars * (size_t)m.vertex_count);
    for (int64_t v = 0; v < m.vertex_count; v++) {
        const float *p = m.positions + 3 * v;
        m.scalars[v] = (float)(sin(0.4 * p[0]) * cos(0.3 * p[1]) + 0.05 * p[2]);
    }
    const double smooth[] = {0.3, -0.2, 0.77, 5.0}; /* the last one crosses nothing */
    compare(&m, smooth, 4, 1000);
    /* whole numbers: values on vertices exactly (at or above), and a NaN corner */
    for (int64_t v = 0; v < m.vertex_count; v++)
        m.scalars[v] = (float)floor(m.positions[3 * v] / 4);
    m.scalars[m.vertex_count / 2] = NAN;
    const double exact[] = {1.0, 3.0, 2.5};
    compare(&m, exact, 3, 100);
    /* a value between two floats: the float compare must agree with the CPU's double compare */
    for (int64_t v = 0; v < m.vertex_count; v++)
        m.scalars[v] = m.positions[3 * v + 1] == 10.0f ? 0.1f : m.positions[3 * v + 1] < 10.0f ? 0.0f : 1.0f;
    const double between[] = {0.1, nextafter(0.1f, 1.0), nextafter(0.1f, 0.0)};
    compare(&m, between, 3, 100);
    fx_free(&m);
    /* 288,000 tets: 1125 groups of 256, so the scan of the group totals takes two tiles of 1024 */
    CHECK(fx_grid(&m, 40, 40, 30, NULL, 1.0, NULL) == 0 && fx_build(&m) == 0);
    m.scalars = malloc(sizeof *m.scalars * (size_t)m.vertex_count);
    for (int64_t v = 0; v < m.vertex_count; v++) {
        const float *p = m.positions + 3 * v;
        m.scalars[v] = (float)(sin(0.3 * p[0]) * cos(0.25 * p[1]) + 0.02 * p[2]);
    }
    const double tiles[] = {0.1, -0.45};
    compare(&m, tiles, 2, 10000);
    fx_free(&m);
}
