/* The Vulkan renderer's effects against the CPU reference's (render.h, "Effect definitions"), on
 * lavapipe: isosurfaces of a point field and of a tet field, gradient shading, the clip box, a tet
 * field, midpoint integration, shadows, ambient occlusion, occlusion at vertices and at the surface, and
 * combinations; PSNR >= 40 dB each, max pixel difference printed. Also on a grid of 998,250 tets, where lavapipe's cap on loop iterations
 * once cut rays short (vk_layout.h, "Slices"). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "march_fixtures.h"
#include "render/render.h"
#include "render/transfer_function.h"
#include "render_vk/render_vk.h"
#include "tetpack.h"
#include "tpk_assert.h"

#define SIZE 64

typedef struct fx_scene {
    tpk_file *file;
    tpk_mesh_arrays mesh;
    float *tet_field; /* centroid x of each tet, a piecewise-constant field */
    tpk_transfer_function tf;
    tpk_render_options opt;
} fx_scene;

static int open_scene(fx_scene *s, const char *input, const char *name)
{
    memset(s, 0, sizeof *s);
    char msg[512];
    tpk_convert_options o;
    memset(&o, 0, sizeof o);
    o.input = input;
    o.output = tpk_temp_path(name);
    o.layouts = TPK_LAYOUT_BIT_TET16 | TPK_LAYOUT_BIT_TET32;
    tpk_convert_report report;
    tpk_diag diag = {0};
    tpk_file_info info;
    if (tpk_convert_checked(&o, &report, &diag) != 0 ||
        tpk_open_path(&s->file, o.output, NULL, msg, sizeof msg) != TPK_OK || tpk_get_info(s->file, &info) != TPK_OK ||
        tpk_tf_load("viridis", &s->tf, &diag) != 0 || tpk_load_arrays(s->file, TPK_LAYOUT_TET32, NULL, 0, &s->mesh))
        return -1;
    s->tet_field = malloc((s->mesh.tet_count ? s->mesh.tet_count : 1) * sizeof(float));
    if (!s->tet_field)
        return -1;
    for (uint64_t t = 0; t < s->mesh.tet_count; t++) {
        const tpk_tet32 *r = &s->mesh.tet32[t];
        int32_t v[4] = {r->v[0], r->v[1], r->v[2], r->vx ^ r->v[0] ^ r->v[1] ^ r->v[2]};
        double x = 0;
        for (int i = 0; i < 4; i++)
            x += s->mesh.positions[3 * v[i]];
        s->tet_field[t] = (float)(x / 4 + s->mesh.origin[0]);
    }
    if (tpk_load_arrays(s->file, TPK_LAYOUT_TET16, NULL, 0, &s->mesh) != TPK_OK)
        return -1;
    tpk_render_options_default(&s->opt);
    s->opt.width = s->opt.height = SIZE;
    tpk_camera_default(info.bounds_min, info.bounds_max, &s->opt.camera);
    s->opt.tf = &s->tf;
    tpk_field_desc d;
    if (tpk_get_field(s->file, 0, &d) == TPK_OK) {
        s->opt.range_min = d.min_value;
        s->opt.range_max = d.max_value;
    }
    return 0;
}

static void close_scene(fx_scene *s)
{
    free(s->tet_field);
    tpk_close(s->file);
}

/* Secondary rays of the last agree() on each backend. */
static uint64_t last_secondary[2];

static int agree(fx_scene *s, const char *what)
{
    size_t n = (size_t)SIZE * SIZE * 4;
    uint8_t *cpu = malloc(n), *vk = malloc(n);
    tpk_diag diag = {0};
    int rc = -1;
    if (!cpu || !vk)
        goto done;
    tpk_render_stats stats[2];
    if (tpk_render_cpu(&s->mesh, &s->opt, cpu, &stats[0], &diag) != 0) {
        fprintf(stderr, "%s: cpu: %s\n", what, diag.message);
        goto done;
    }
    if (tpk_render_vulkan(&s->mesh, &s->opt, vk, &stats[1], &diag) != 0) {
        fprintf(stderr, "%s: vulkan: %s\n", what, diag.message);
        goto done;
    }
    last_secondary[0] = stats[0].secondary_rays;
    last_secondary[1] = stats[1].secondary_rays;
    double se = 0;
    int max_diff = 0, shown = 0;
    for (size_t i = 0; i < n; i++) {
        int d = abs((int)cpu[i] - (int)vk[i]);
        se += (double)d * d;
        max_diff = d > max_diff ? d : max_diff;
    }
    for (size_t p = 0; p < n / 4; p++)
        shown += memcmp(&cpu[4 * p], cpu, 4) != 0;
    double db = se == 0 ? 99.0 : 10.0 * log10(255.0 * 255.0 / (se / (double)n));
    printf("%-36s PSNR %6.2f dB, max pixel difference %3d, %d pixels show the volume\n", what, db, max_diff, shown);
    rc = db >= 40.0 && shown > (int)(n / 4 / 20) ? 0 : -1;
done:
    free(cpu);
    free(vk);
    return rc;
}

TPK_TEST(point_field_effects)
{
    char why[256];
    if (!tpk_vulkan_available(why, sizeof why)) {
        tpk_test_skip(why);
        return;
    }
    fx_scene s;
    CHECK(open_scene(&s, TPK_SOURCE_DIR "/samples/cylinder.vtk", "cylinder.tpk") == 0);
    double lo = s.opt.range_min, hi = s.opt.range_max;
    s.opt.iso_count = 2;
    s.opt.iso[0] = lo + 0.3 * (hi - lo);
    s.opt.iso[1] = lo + 0.7 * (hi - lo);
    s.opt.iso_opacity = 0.6;
    CHECK(agree(&s, "iso, opacity 0.6") == 0);
    s.opt.shading = 1;
    CHECK(agree(&s, "iso + shading (headlight)") == 0);
    s.opt.iso_count = 0;
    s.opt.have_light = 1;
    s.opt.light[0] = s.opt.camera.eye[0];
    s.opt.light[1] = -s.opt.camera.eye[1];
    s.opt.light[2] = s.opt.camera.eye[2];
    CHECK(agree(&s, "shading, point light") == 0);
    s.opt.shading = 0;
    s.opt.clip = 1;
    for (int k = 0; k < 3; k++) {
        s.opt.clip_min[k] = s.opt.camera.at[k] - 0.3;
        s.opt.clip_max[k] = s.opt.camera.at[k] + 2.0;
    }
    CHECK(agree(&s, "clip box") == 0);
    s.opt.clip = 0;
    s.opt.integration = 2;
    CHECK(agree(&s, "midpoint integration") == 0);
    s.opt.integration = 0;
    s.opt.shading = 1;
    s.opt.shadows = 1;
    CHECK(agree(&s, "shading + shadows") == 0);
    s.opt.iso_count = 1;
    s.opt.iso_opacity = 0.5;
    CHECK(agree(&s, "iso + shading + shadows") == 0);
    s.opt.shadows = 0;
    s.opt.ao_rays = 4;
    CHECK(agree(&s, "iso + shading + AO (4 rays)") == 0);
    s.opt.iso_count = 0;
    s.opt.shadows = 1;
    s.opt.ao_radius = 0.5;
    CHECK(agree(&s, "shading + shadows + AO, radius 0.5") == 0);
    /* render.h OCCLUSION AT VERTICES: the cache's rays, then S and A interpolated at every shade point */
    s.opt.occlusion = TPK_OCCLUSION_VERTEX;
    CHECK(agree(&s, "shading + shadows + AO, vertex cache") == 0);
    CHECK_MSG(last_secondary[0] == last_secondary[1] && last_secondary[0] > 0, "secondary rays: cpu %llu, vulkan %llu",
              (unsigned long long)last_secondary[0], (unsigned long long)last_secondary[1]);
    s.opt.iso_count = 2;
    CHECK(agree(&s, "iso + shading + shadows + AO, vertex cache") == 0);
    /* render.h OCCLUSION AT THE SURFACE: one shade point per pixel, the first iso hit, else the first
     * volume shade point; the same casts on both backends */
    s.opt.occlusion = TPK_OCCLUSION_SURFACE;
    CHECK(agree(&s, "iso + shading + shadows + AO, surface") == 0);
    CHECK_MSG(last_secondary[0] == last_secondary[1] && last_secondary[0] > 0, "secondary rays: cpu %llu, vulkan %llu",
              (unsigned long long)last_secondary[0], (unsigned long long)last_secondary[1]);
    s.opt.iso_count = 0;
    CHECK(agree(&s, "shading + shadows + AO, surface (shell)") == 0);
    CHECK_MSG(last_secondary[0] == last_secondary[1] && last_secondary[0] > 0, "secondary rays: cpu %llu, vulkan %llu",
              (unsigned long long)last_secondary[0], (unsigned long long)last_secondary[1]);
    close_scene(&s);
}

/* One renderer over several frames with --occlusion vertex (view's case): a half of the cache whose
 * inputs did not change is kept (A under any camera move, S under a fixed light), the other cast again;
 * every frame's picture is byte for byte a fresh renderer's, and the kept half casts no rays. */
static void frame_on(tpk_vk_renderer *r, fx_scene *s, uint8_t *kept, uint8_t *fresh, uint64_t *kept_rays,
                     uint64_t *fresh_rays)
{
    size_t n = (size_t)SIZE * SIZE * 4;
    tpk_diag diag = {0};
    tpk_render_stats a, b;
    CHECK_MSG(tpk_vk_renderer_frame(r, &s->opt, kept, &a, &diag) == 0, "%s", diag.message);
    CHECK_MSG(tpk_render_vulkan(&s->mesh, &s->opt, fresh, &b, &diag) == 0, "%s", diag.message);
    CHECK_MSG(memcmp(kept, fresh, n) == 0, "the kept cache's picture differs from a fresh renderer's");
    *kept_rays = a.secondary_rays, *fresh_rays = b.secondary_rays;
}

TPK_TEST(vertex_cache_kept_across_frames)
{
    char why[256];
    if (!tpk_vulkan_available(why, sizeof why)) {
        tpk_test_skip(why);
        return;
    }
    fx_scene s;
    CHECK(open_scene(&s, TPK_SOURCE_DIR "/samples/cylinder.vtk", "cylinder_cache.tpk") == 0);
    s.opt.occlusion = TPK_OCCLUSION_VERTEX;
    s.opt.shading = s.opt.shadows = 1;
    s.opt.ao_rays = 4;
    s.opt.have_light = 1;
    for (int k = 0; k < 3; k++)
        s.opt.light[k] = s.opt.camera.eye[k] + (k == 1 ? 0.05 : 0.0);
    size_t n = (size_t)SIZE * SIZE * 4;
    uint8_t *kept = malloc(n), *fresh = malloc(n);
    tpk_vk_renderer *r = NULL;
    tpk_diag diag = {0};
    CHECK(kept && fresh);
    CHECK_MSG(tpk_vk_renderer_create(&r, &s.mesh, NULL, &diag) == 0, "%s", diag.message);
    uint64_t kept_rays, fresh_rays;
    frame_on(r, &s, kept, fresh, &kept_rays, &fresh_rays); /* the whole cache, as a fresh renderer */
    CHECK_MSG(kept_rays == fresh_rays && fresh_rays > 0, "first frame: %llu rays, fresh %llu",
              (unsigned long long)kept_rays, (unsigned long long)fresh_rays);
    const uint64_t full = fresh_rays;
    s.opt.camera.eye[0] += 0.02; /* the camera moves, the light stays: nothing is cast */
    frame_on(r, &s, kept, fresh, &kept_rays, &fresh_rays);
    CHECK_MSG(kept_rays == 0 && fresh_rays == full, "camera move: %llu rays (fresh %llu)", (unsigned long long)kept_rays,
              (unsigned long long)fresh_rays);
    s.opt.have_light = 0; /* a headlight: S again at every camera move, A kept */
    frame_on(r, &s, kept, fresh, &kept_rays, &fresh_rays);
    CHECK_MSG(kept_rays > 0 && kept_rays < full, "headlight: %llu rays of %llu", (unsigned long long)kept_rays,
              (unsigned long long)full);
    s.opt.camera.eye[1] += 0.02;
    frame_on(r, &s, kept, fresh, &kept_rays, &fresh_rays);
    CHECK_MSG(kept_rays > 0 && kept_rays < full, "headlight, moved: %llu rays of %llu", (unsigned long long)kept_rays,
              (unsigned long long)full);
    s.opt.ao_radius = 0.004; /* A's input: A again, S (same headlight) kept */
    frame_on(r, &s, kept, fresh, &kept_rays, &fresh_rays);
    CHECK_MSG(kept_rays > 0 && kept_rays < full, "AO radius: %llu rays of %llu", (unsigned long long)kept_rays,
              (unsigned long long)full);
    s.opt.range_max += 1; /* the TF's mapping: both again */
    frame_on(r, &s, kept, fresh, &kept_rays, &fresh_rays);
    CHECK_MSG(kept_rays == fresh_rays, "range: %llu rays, fresh %llu", (unsigned long long)kept_rays,
              (unsigned long long)fresh_rays);
    tpk_vk_renderer_destroy(r);
    free(kept);
    free(fresh);
    close_scene(&s);
}

/* render.h OCCLUSION AT VERTICES cast on the device (tpk_vk_renderer_vertex_cache, what a frame with
 * --occlusion vertex uploads) against the CPU reference's cache (tpk_render_vertex_cache), vertex by
 * vertex. The device marches in float, the CPU in double: a secondary ray's optical depth differs by a
 * few float roundings per piece (relative 1e-6 each, a few hundred pieces), so S_v and A_v agree to
 * about 1e-4. Two things move a vertex further, both at a threshold: a ray whose transmittance crosses
 * the stop at 0.02 one piece apart on the two (both values then lie in [0, 0.02], so at most 0.02 apart,
 * and an AO mean moves by at most that), and an iso crossing at the self-shadowing epsilon counted by one
 * only (a factor 1 - iso_opacity on that ray). Bounds: the mean difference <= 1e-4, at most 0.5% of the
 * vertices more than 1e-3 off, every one within 0.02 + 1e-4 without iso values; the same ray count. */
static void compare_casts(fx_scene *s, const char *what, int with_iso)
{
    tpk_diag diag = {0};
    size_t n = (size_t)s->mesh.vertex_count;
    float *cs = malloc(n * sizeof *cs), *ca = malloc(n * sizeof *ca), *gs = malloc(n * sizeof *gs),
          *ga = malloc(n * sizeof *ga);
    CHECK(cs && ca && gs && ga);
    tpk_render_stats cpu, vk;
    CHECK_MSG(tpk_render_vertex_cache(&s->mesh, &s->opt, cs, ca, &cpu, &diag) == 0, "%s: cpu: %s", what, diag.message);
    tpk_vk_renderer *r = NULL;
    CHECK_MSG(tpk_vk_renderer_create(&r, &s->mesh, s->opt.tet_scalars, &diag) == 0, "%s", diag.message);
    CHECK_MSG(tpk_vk_renderer_vertex_cache(r, &s->opt, gs, ga, &vk, &diag) == 0, "%s: vulkan: %s", what, diag.message);
    tpk_vk_renderer_destroy(r);
    double sum = 0, worst = 0;
    size_t off = 0, worst_at = 0;
    for (size_t v = 0; v < n; v++) {
        double d[2] = {fabs((double)cs[v] - gs[v]), fabs((double)ca[v] - ga[v])};
        for (int h = 0; h < 2; h++) {
            sum += d[h];
            off += d[h] > 1e-3;
            if (d[h] > worst)
                worst = d[h], worst_at = v;
        }
    }
    double mean = sum / (2.0 * (double)n);
    printf("%-40s %zu vertices: mean |difference| %.2e, max %.2e (vertex %zu), %zu values > 1e-3; rays cpu %llu, "
           "vulkan %llu\n",
           what, n, mean, worst, worst_at, off, (unsigned long long)cpu.secondary_rays,
           (unsigned long long)vk.secondary_rays);
    CHECK_MSG(mean <= 1e-4 && off <= n / 100 && (with_iso || worst <= 0.0201), "%s: mean %.2e, max %.2e, %zu off", what,
              mean, worst, off);
    CHECK_MSG(cpu.secondary_rays == vk.secondary_rays && vk.secondary_rays > 0, "%s: rays cpu %llu, vulkan %llu", what,
              (unsigned long long)cpu.secondary_rays, (unsigned long long)vk.secondary_rays);
    free(cs);
    free(ca);
    free(gs);
    free(ga);
}

TPK_TEST(vertex_casts_on_device)
{
    char why[256];
    if (!tpk_vulkan_available(why, sizeof why)) {
        tpk_test_skip(why);
        return;
    }
    fx_scene s;
    CHECK(open_scene(&s, TPK_SOURCE_DIR "/samples/cylinder.vtk", "cylinder_casts.tpk") == 0);
    s.opt.shadows = 1;
    s.opt.ao_rays = 4;
    s.opt.have_light = 1;
    for (int k = 0; k < 3; k++)
        s.opt.light[k] = s.opt.camera.eye[k] + (k == 1 ? 0.05 : 0.0);
    compare_casts(&s, "cylinder: shadows + AO 4", 0);
    double lo = s.opt.range_min, hi = s.opt.range_max;
    s.opt.iso_count = 2;
    s.opt.iso[0] = lo + 0.3 * (hi - lo);
    s.opt.iso[1] = lo + 0.7 * (hi - lo);
    s.opt.iso_opacity = 0.6;
    s.opt.ao_radius = 0.5;
    compare_casts(&s, "cylinder: iso + shadows + AO 4", 1);
    close_scene(&s);
    CHECK(open_scene(&s, tpk_data_path("sfepy/elbow.mesh"), "elbow_casts.tpk") == 0);
    s.opt.shadows = 1;
    s.opt.ao_rays = 8;
    compare_casts(&s, "elbow: shadows (headlight) + AO 8", 0);
    close_scene(&s);
}

TPK_TEST(tet_field_effects)
{
    char why[256];
    if (!tpk_vulkan_available(why, sizeof why)) {
        tpk_test_skip(why);
        return;
    }
    fx_scene s;
    CHECK(open_scene(&s, tpk_data_path("sfepy/elbow.mesh"), "elbow.tpk") == 0);
    float lo = INFINITY, hi = -INFINITY;
    for (uint64_t t = 0; t < s.mesh.tet_count; t++) {
        lo = fminf(lo, s.tet_field[t]);
        hi = fmaxf(hi, s.tet_field[t]);
    }
    s.opt.tet_scalars = s.tet_field;
    s.opt.range_min = lo;
    s.opt.range_max = hi;
    CHECK(agree(&s, "tet field") == 0);
    s.opt.iso_count = 1;
    s.opt.iso[0] = lo + 0.5 * (hi - lo);
    s.opt.iso_opacity = 0.8;
    CHECK(agree(&s, "tet field iso") == 0);
    s.opt.shading = 1;
    CHECK(agree(&s, "tet field iso + shading") == 0);
    s.opt.shadows = 1;
    s.opt.ao_rays = 3;
    CHECK(agree(&s, "tet field iso + shadows + AO") == 0);
    s.opt.occlusion = TPK_OCCLUSION_SURFACE;
    CHECK(agree(&s, "tet field iso + shadows + AO, surface") == 0);
    close_scene(&s);
}

/* make_grid_vtk.py's 55^3 cubes (998,250 tets) and field, without its jitter and shuffle: rays long enough
 * that shadow and AO rays ran lavapipe past 65535 loop iterations per shader, where it silently ends
 * every loop (34 dB for shadows, 25 dB for AO and a fifth of the AO rays, before slices). */
TPK_TEST(grid_55_effects)
{
    char why[256];
    if (!tpk_vulkan_available(why, sizeof why)) {
        tpk_test_skip(why);
        return;
    }
    enum { N = 55 };
    fx_mesh m;
    CHECK(fx_grid(&m, N, N, N, NULL, 1.0, NULL) == 0 && fx_build(&m) == 0);
    m.scalars = malloc((size_t)m.vertex_count * sizeof(float));
    CHECK(m.scalars != NULL);
    float lo = INFINITY, hi = -INFINITY;
    for (int64_t v = 0; v < m.vertex_count; v++) {
        const float *p = &m.positions[3 * v];
        double r = sqrt(pow(p[0] - 0.5 * N, 2) + pow(p[1] - 0.5 * N, 2) + pow(p[2] - 0.5 * N, 2));
        m.scalars[v] = (float)(sin(r * 0.5) * cos(p[2] * 0.2));
        lo = fminf(lo, m.scalars[v]);
        hi = fmaxf(hi, m.scalars[v]);
    }
    fx_scene s;
    memset(&s, 0, sizeof s);
    s.mesh = fx_arrays(&m, TPK_LAYOUT_TET16);
    tpk_diag diag = {0};
    CHECK(tpk_tf_load("viridis", &s.tf, &diag) == 0);
    tpk_render_options_default(&s.opt);
    s.opt.width = s.opt.height = SIZE;
    double bmin[3] = {0, 0, 0}, bmax[3] = {N, N, N};
    tpk_camera_default(bmin, bmax, &s.opt.camera);
    s.opt.tf = &s.tf;
    s.opt.range_min = lo;
    s.opt.range_max = hi;
    const char *names[3] = {"grid 55: shadows", "grid 55: AO (4 rays)", "grid 55: shading + shadows + AO (2 rays)"};
    for (int c = 0; c < 3; c++) {
        s.opt.shading = c == 2;
        s.opt.shadows = c != 1;
        s.opt.ao_rays = c == 0 ? 0 : c == 1 ? 4 : 2;
        CHECK_MSG(agree(&s, names[c]) == 0, "%s", names[c]);
        /* the same shade points: the counts differ only where float and double decide a 1/32 step apart */
        double cpu = (double)last_secondary[0], vk = (double)last_secondary[1];
        CHECK_MSG(cpu > 0 && fabs(vk - cpu) <= 0.005 * cpu, "%s: secondary rays: cpu %.0f, vulkan %.0f", names[c], cpu,
                  vk);
    }
    /* the seed paper's effects (render.h OCCLUSION AT THE SURFACE): an opaque isosurface, shading,
     * shadows and AO 4 cast from its first hit alone, the volume in front and behind the occluder */
    s.opt.shading = s.opt.shadows = 1;
    s.opt.ao_rays = 4;
    s.opt.iso_count = 1;
    s.opt.iso[0] = 0.5 * (lo + hi);
    s.opt.iso_opacity = 1;
    s.opt.occlusion = TPK_OCCLUSION_SURFACE;
    CHECK(agree(&s, "grid 55: iso + shading + shadows + AO 4, surface") == 0);
    double cpu = (double)last_secondary[0], vk = (double)last_secondary[1];
    CHECK_MSG(cpu > 0 && cpu <= 5.0 * SIZE * SIZE && fabs(vk - cpu) <= 0.005 * cpu,
              "surface: secondary rays: cpu %.0f, vulkan %.0f", cpu, vk);
    fx_free(&m);
}
