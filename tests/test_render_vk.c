/* The Vulkan renderer against the CPU reference, on lavapipe (no GPU needed): the same picture
 * (PSNR >= 40 dB, max pixel difference printed) for every layout on the sample and on real non-convex
 * and multi-component meshes, a camera inside the volume and one exactly on a shell face, arrays split
 * over several bindings rendering the same as unsplit, and a clean error without a device. */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "render/render.h"
#include "render/transfer_function.h"
#include "render_vk/render_vk.h"
#include "vk_device.h"
#include "tetpack.h"
#include "tpk_assert.h"

#define SIZE 128

typedef struct scene {
    tpk_file *file;
    tpk_mesh_arrays mesh;
    float *scalars; /* a coordinate field for meshes without a point field */
    tpk_file_info info;
    tpk_transfer_function tf;
    tpk_render_options opt;
} scene;

static void scene_free(scene *s)
{
    free(s->scalars);
    tpk_close(s->file);
    memset(s, 0, sizeof *s);
}

/* Convert a real mesh with all three layouts and open it. */
static int scene_open(scene *s, const char *data_file, const char *name)
{
    memset(s, 0, sizeof *s);
    char msg[512];
    tpk_convert_options o;
    memset(&o, 0, sizeof o);
    o.input = data_file;
    o.output = tpk_temp_path(name);
    o.layouts = TPK_LAYOUT_BIT_TET16 | TPK_LAYOUT_BIT_TET20 | TPK_LAYOUT_BIT_TET32;
    tpk_convert_report report;
    tpk_diag diag = {0};
    if (tpk_convert_checked(&o, &report, &diag) != 0) {
        fprintf(stderr, "convert %s: %s\n", data_file, diag.message);
        return -1;
    }
    if (tpk_open_path(&s->file, o.output, NULL, msg, sizeof msg) != TPK_OK || tpk_get_info(s->file, &s->info) != TPK_OK)
        return -1;
    if (tpk_tf_load("viridis", &s->tf, &diag) != 0)
        return -1;
    tpk_render_options_default(&s->opt);
    s->opt.width = s->opt.height = SIZE;
    tpk_camera_default(s->info.bounds_min, s->info.bounds_max, &s->opt.camera);
    s->opt.tf = &s->tf;
    return 0;
}

/* Load a layout; without a point field, the scalar is a linear function of the position, so colour
 * varies inside tets as a real field would. */
static int scene_layout(scene *s, tpk_layout layout)
{
    if (tpk_load_arrays(s->file, layout, NULL, 0, &s->mesh) != TPK_OK)
        return -1;
    if (!s->mesh.scalars) {
        free(s->scalars);
        s->scalars = malloc((s->mesh.vertex_count ? s->mesh.vertex_count : 1) * sizeof(float));
        if (!s->scalars)
            return -1;
        for (uint64_t v = 0; v < s->mesh.vertex_count; v++) {
            const float *p = &s->mesh.positions[3 * v];
            s->scalars[v] = p[0] + 0.5f * p[1] - 0.25f * p[2];
        }
        s->mesh.scalars = s->scalars;
        double lo = INFINITY, hi = -INFINITY;
        for (uint64_t v = 0; v < s->mesh.vertex_count; v++) {
            lo = fmin(lo, s->scalars[v]);
            hi = fmax(hi, s->scalars[v]);
        }
        s->opt.range_min = lo;
        s->opt.range_max = hi;
    } else {
        tpk_field_desc d;
        if (tpk_get_field(s->file, 0, &d) == TPK_OK) {
            s->opt.range_min = d.min_value;
            s->opt.range_max = d.max_value;
        }
    }
    return 0;
}

static double psnr(const uint8_t *a, const uint8_t *b, size_t n, int *max_diff)
{
    double se = 0;
    *max_diff = 0;
    for (size_t i = 0; i < n; i++) {
        int d = abs((int)a[i] - (int)b[i]);
        se += (double)d * d;
        *max_diff = d > *max_diff ? d : *max_diff;
    }
    return se == 0 ? 99.0 : 10.0 * log10(255.0 * 255.0 / (se / (double)n));
}

/* Render the scene on both backends; 0 when the pictures agree to PSNR >= 40 dB. */
static int compare_backends(scene *s, const char *what, uint8_t *vk_out)
{
    size_t n = (size_t)s->opt.width * (size_t)s->opt.height * 4;
    uint8_t *cpu = malloc(n), *vk = vk_out ? vk_out : malloc(n);
    tpk_render_stats cs, vs;
    tpk_diag diag = {0};
    int rc = -1;
    if (!cpu || !vk)
        goto done;
    if (tpk_render_cpu(&s->mesh, &s->opt, cpu, &cs, &diag) != 0) {
        fprintf(stderr, "%s: cpu: %s\n", what, diag.message);
        goto done;
    }
    if (tpk_render_vulkan(&s->mesh, &s->opt, vk, &vs, &diag) != 0) {
        fprintf(stderr, "%s: vulkan: %s\n", what, diag.message);
        goto done;
    }
    int max_diff, covered = 0;
    double db = psnr(cpu, vk, n, &max_diff);
    for (size_t p = 0; p < n / 4; p++)
        covered += memcmp(&cpu[4 * p], cpu, 4) != 0;
    printf("%-40s PSNR %6.2f dB, max pixel difference %3d, tet steps cpu %llu vulkan %llu, %d pixels differ from "
           "the corner\n", what, db, max_diff, (unsigned long long)cs.tet_steps, (unsigned long long)vs.tet_steps,
           covered);
    /* the picture must show the volume, else the comparison proves nothing */
    rc = db >= 40.0 && covered > (int)(n / 4 / 50) && vs.tet_steps > 0 ? 0 : -1;
done:
    free(cpu);
    if (!vk_out)
        free(vk);
    return rc;
}

static int compare_layouts(scene *s, const char *name)
{
    static const tpk_layout layouts[3] = {TPK_LAYOUT_TET16, TPK_LAYOUT_TET20, TPK_LAYOUT_TET32};
    static const char *const names[3] = {"tet16", "tet20", "tet32"};
    size_t n = (size_t)s->opt.width * (size_t)s->opt.height * 4;
    uint8_t *img[3] = {malloc(n), malloc(n), malloc(n)};
    int rc = 0;
    for (int l = 0; l < 3 && rc == 0; l++) {
        char what[128];
        snprintf(what, sizeof what, "%s %s", name, names[l]);
        if (!img[l] || scene_layout(s, layouts[l]) != 0 || compare_backends(s, what, img[l]) != 0)
            rc = -1;
    }
    /* the three marchers visit the same tets with the same decisions: identical pictures */
    if (rc == 0 && (memcmp(img[0], img[1], n) || memcmp(img[0], img[2], n))) {
        fprintf(stderr, "%s: the Vulkan layouts disagree\n", name);
        rc = -1;
    }
    for (int l = 0; l < 3; l++)
        free(img[l]);
    return rc;
}

TPK_TEST(sample_layouts)
{
    if (!have_device())
        return;
    scene s;
    CHECK(scene_open(&s, TPK_SOURCE_DIR "/samples/cylinder.vtk", "cylinder.tpk") == 0);
    CHECK(compare_layouts(&s, "cylinder.vtk") == 0);
    s.opt.integration = 1; /* sampled integration too */
    CHECK(compare_backends(&s, "cylinder.vtk tet32 sampled", NULL) == 0);
    scene_free(&s);
}

/* The shader's three edge tests (shaders/vk_layout.h): doubles always (CPU devices), a float filter
 * with doubles near zero (GPUs), and Dekker products without doubles; each against the CPU. */
TPK_TEST(edge_test_variants)
{
    if (!have_device())
        return;
    scene s;
    CHECK(scene_open(&s, tpk_data_path("hard/nonmanifold_vertex_edge_tets.vtu"), "cubes.tpk") == 0);
    CHECK(scene_layout(&s, TPK_LAYOUT_TET16) == 0);
    setenv("TPK_VK_EXACT", "1", 1);
    CHECK(compare_backends(&s, "cubes, float filter + double", NULL) == 0);
    setenv("TPK_VK_NO_FP64", "1", 1);
    CHECK(compare_backends(&s, "cubes, float filter + Dekker", NULL) == 0);
    unsetenv("TPK_VK_NO_FP64");
    unsetenv("TPK_VK_EXACT");
    scene_free(&s);
}

/* Non-convex (hinge: holes and concave parts), two components, and three cubes touching at a vertex
 * and along an edge (rays through the touching points tie between shell entries). */
TPK_TEST(real_meshes)
{
    if (!have_device())
        return;
    static const char *const files[] = {"tetgen/hinge_small.ele", "hard/two_components_orphans.ele",
                                        "hard/nonmanifold_vertex_edge_tets.vtu"};
    for (int i = 0; i < 3; i++) {
        scene s;
        CHECK_MSG(scene_open(&s, tpk_data_path(files[i]), "real.tpk") == 0, "%s", files[i]);
        CHECK_MSG(compare_layouts(&s, files[i]) == 0, "%s", files[i]);
        scene_free(&s);
    }
}

TPK_TEST(camera_inside)
{
    if (!have_device())
        return;
    scene s;
    CHECK(scene_open(&s, tpk_data_path("sfepy/elbow.mesh"), "elbow.tpk") == 0);
    CHECK(scene_layout(&s, TPK_LAYOUT_TET16) == 0);
    /* the eye on a vertex of the mesh (inside the volume or on its shell), looking at the centre */
    const float *p = &s.mesh.positions[3 * (s.mesh.vertex_count / 2)];
    for (int k = 0; k < 3; k++) {
        s.opt.camera.eye[k] = s.mesh.origin[k] + p[k];
        s.opt.camera.at[k] = 0.5 * (s.info.bounds_min[k] + s.info.bounds_max[k]);
    }
    s.opt.camera.fovy_deg = 90;
    s.opt.unit_distance = 0.02 * (s.info.bounds_max[0] - s.info.bounds_min[0]);
    CHECK(compare_backends(&s, "elbow.mesh, eye on a mesh vertex", NULL) == 0);
    /* the eye at the centre of a tet: strictly inside */
    int32_t tet[4];
    CHECK(scene_layout(&s, TPK_LAYOUT_TET32) == 0);
    const tpk_tet32 *r = &s.mesh.tet32[s.mesh.tet_count / 3];
    tet[0] = r->v[0], tet[1] = r->v[1], tet[2] = r->v[2], tet[3] = r->vx ^ r->v[0] ^ r->v[1] ^ r->v[2];
    for (int k = 0; k < 3; k++) {
        double c = 0;
        for (int j = 0; j < 4; j++)
            c += s.mesh.positions[3 * tet[j] + k];
        s.opt.camera.eye[k] = s.mesh.origin[k] + c / 4;
    }
    CHECK(compare_backends(&s, "elbow.mesh, eye inside a tet", NULL) == 0);
    scene_free(&s);
}

/* The eye exactly on the cube's x = min face (an axis-aligned plane of shell faces), looking in, and
 * looking along the face. */
TPK_TEST(camera_on_shell_face)
{
    if (!have_device())
        return;
    scene s;
    CHECK(scene_open(&s, tpk_data_path("sfepy/cube_medium_tetra.mesh"), "cube.tpk") == 0);
    CHECK(scene_layout(&s, TPK_LAYOUT_TET20) == 0);
    double c[3];
    for (int k = 0; k < 3; k++)
        c[k] = 0.5 * (s.info.bounds_min[k] + s.info.bounds_max[k]);
    s.opt.camera.eye[0] = s.info.bounds_min[0];
    s.opt.camera.eye[1] = c[1] + 0.1234 * (s.info.bounds_max[1] - s.info.bounds_min[1]);
    s.opt.camera.eye[2] = c[2] - 0.0567 * (s.info.bounds_max[2] - s.info.bounds_min[2]);
    memcpy(s.opt.camera.at, c, sizeof c);
    s.opt.camera.fovy_deg = 100;
    CHECK(compare_backends(&s, "cube_medium_tetra, eye on the x=min face", NULL) == 0);
    s.opt.camera.at[0] = s.info.bounds_min[0]; /* look along the face */
    s.opt.camera.at[1] = s.info.bounds_max[1];
    CHECK(compare_backends(&s, "cube_medium_tetra, looking along it", NULL) == 0);
    scene_free(&s);
}

static uint64_t next_pow2(uint64_t x)
{
    uint64_t p = 1;
    while (p < x)
        p *= 2;
    return p;
}

/* Every array split over several bindings (TPK_VK_SPLIT_BYTES) renders bit-identically to unsplit. */
TPK_TEST(split_bindings)
{
    if (!have_device())
        return;
    scene s;
    CHECK(scene_open(&s, tpk_data_path("tetgen/hinge_small.ele"), "hinge.tpk") == 0);
    size_t n = (size_t)SIZE * SIZE * 4;
    uint8_t *whole = malloc(n), *split = malloc(n);
    CHECK(whole && split);
    static const tpk_layout layouts[3] = {TPK_LAYOUT_TET16, TPK_LAYOUT_TET20, TPK_LAYOUT_TET32};
    static const uint64_t record_bytes[3] = {16, 20, 32};
    for (int l = 0; l < 3; l++) {
        CHECK(scene_layout(&s, layouts[l]) == 0);
        tpk_diag diag = {0};
        unsetenv("TPK_VK_SPLIT_BYTES");
        CHECK_MSG(tpk_render_vulkan(&s.mesh, &s.opt, whole, NULL, &diag) == 0, "%s", diag.message);
        /* the tet records take all 8 bindings (or nearly), the positions (16 bytes a vertex) several */
        uint64_t bytes = next_pow2((record_bytes[l] * s.mesh.tet_count + 7) / 8);
        char value[32];
        snprintf(value, sizeof value, "%llu", (unsigned long long)bytes);
        setenv("TPK_VK_SPLIT_BYTES", value, 1);
        CHECK_MSG(tpk_render_vulkan(&s.mesh, &s.opt, split, NULL, &diag) == 0, "%s", diag.message);
        int max_diff;
        double db = psnr(whole, split, n, &max_diff);
        printf("layout %d, bindings of %s bytes: tets in %llu, positions in %llu: PSNR %.2f, max difference %d\n",
               (int)layouts[l], value, (unsigned long long)((record_bytes[l] * s.mesh.tet_count + bytes - 1) / bytes),
               (unsigned long long)((16 * s.mesh.vertex_count + bytes - 1) / bytes), db, max_diff);
        CHECK(16 * s.mesh.vertex_count > bytes); /* the positions are split too */
        CHECK(max_diff == 0);
    }
    /* Too small a binding for the device's 8 per array: a clear refusal, not a crash. */
    setenv("TPK_VK_SPLIT_BYTES", "256", 1);
    tpk_diag diag = {0};
    CHECK(tpk_render_vulkan(&s.mesh, &s.opt, split, NULL, &diag) != 0);
    printf("refused: %s\n", diag.message);
    CHECK(strstr(diag.message, "larger than the device") != NULL);
    unsetenv("TPK_VK_SPLIT_BYTES");
    free(whole);
    free(split);
    scene_free(&s);
}

/* No device: the probe says why, and the renderer fails with a message instead of crashing. */
TPK_TEST(no_device)
{
    setenv("VK_ICD_FILENAMES", "/nonexistent/tetpack_no_such_icd.json", 1);
    char why[512];
    CHECK(tpk_vulkan_available(why, sizeof why) == 0);
    printf("probe: %s\n", why);
    CHECK(strstr(why, "vulkan:") != NULL);
    scene s;
    CHECK(scene_open(&s, TPK_SOURCE_DIR "/samples/cylinder.vtk", "cylinder.tpk") == 0);
    CHECK(scene_layout(&s, TPK_LAYOUT_TET16) == 0);
    uint8_t *img = malloc((size_t)SIZE * SIZE * 4);
    tpk_diag diag = {0};
    CHECK(tpk_render_vulkan(&s.mesh, &s.opt, img, NULL, &diag) != 0);
    printf("render: %s\n", diag.message);
    CHECK(strstr(diag.message, "vulkan:") != NULL);
    free(img);
    scene_free(&s);
}

/* Render with the Vulkan renderer under the given environment (NULL values unset), image and stats out. */
static int render_env(scene *s, const char *band_pixels, const char *memory, const char *staging, uint8_t *img,
                      tpk_render_stats *st)
{
    const char *names[3] = {"TPK_VK_BAND_PIXELS", "TPK_VK_MEMORY", "TPK_VK_STAGING_BYTES"};
    const char *values[3] = {band_pixels, memory, staging};
    for (int i = 0; i < 3; i++)
        values[i] ? setenv(names[i], values[i], 1) : unsetenv(names[i]);
    tpk_diag diag = {0};
    int rc = tpk_render_vulkan(&s->mesh, &s->opt, img, st, &diag);
    for (int i = 0; i < 3; i++)
        unsetenv(names[i]);
    if (rc != 0)
        fprintf(stderr, "vulkan: %s\n", diag.message);
    return rc;
}

/* The statistics are reduced on the device (one atomic per workgroup, 64-bit sums): tet steps and
 * secondary rays equal the CPU reference's counts, with one band or many (bands of 7 rows and some
 * pixels, not whole workgroups), read in place or copied out through the readback buffer. */
TPK_TEST(device_statistics)
{
    if (!have_device())
        return;
    scene s;
    CHECK(scene_open(&s, TPK_SOURCE_DIR "/samples/cylinder.vtk", "cylinder.tpk") == 0);
    CHECK(scene_layout(&s, TPK_LAYOUT_TET20) == 0);
    size_t n = (size_t)SIZE * SIZE * 4;
    uint8_t *cpu = malloc(n), *one = malloc(n), *many = malloc(n);
    CHECK(cpu && one && many);
    for (int effects = 0; effects < 2; effects++) {
        s.opt.shadows = effects; /* secondary rays too */
        tpk_render_stats cs, vs, bs;
        tpk_diag diag = {0};
        CHECK_MSG(tpk_render_cpu(&s.mesh, &s.opt, cpu, &cs, &diag) == 0, "%s", diag.message);
        CHECK(render_env(&s, NULL, NULL, NULL, one, &vs) == 0);
        CHECK(render_env(&s, "900", "staged", NULL, many, &bs) == 0);
        printf("shadows %d: tet steps cpu %llu, vulkan %llu, in bands %llu; secondary rays %llu, %llu, %llu\n", effects,
               (unsigned long long)cs.tet_steps, (unsigned long long)vs.tet_steps, (unsigned long long)bs.tet_steps,
               (unsigned long long)cs.secondary_rays, (unsigned long long)vs.secondary_rays,
               (unsigned long long)bs.secondary_rays);
        CHECK(cs.tet_steps > 0 && (effects == 0 || cs.secondary_rays > 0));
        CHECK_EQ_INT(vs.tet_steps, cs.tet_steps);
        CHECK_EQ_INT(vs.secondary_rays, cs.secondary_rays);
        CHECK_EQ_INT(bs.tet_steps, cs.tet_steps);
        CHECK_EQ_INT(bs.secondary_rays, cs.secondary_rays);
        CHECK(vs.rays == (uint64_t)SIZE * SIZE && bs.rays == vs.rays);
        CHECK(memcmp(one, many, n) == 0);
    }
    free(cpu);
    free(one);
    free(many);
    scene_free(&s);
}

/* The discrete-GPU path on lavapipe (TPK_VK_MEMORY=staged): arrays through a staging buffer of 256
 * bytes (pieces of 128: every array in many pieces, parts split over bindings too), the image copied
 * out through the readback buffer; the same picture, bit for bit, as written and read in place. */
TPK_TEST(staged_upload)
{
    if (!have_device())
        return;
    scene s;
    CHECK(scene_open(&s, tpk_data_path("tetgen/hinge_small.ele"), "hinge.tpk") == 0);
    size_t n = (size_t)SIZE * SIZE * 4;
    uint8_t *direct = malloc(n), *staged = malloc(n);
    CHECK(direct && staged);
    static const tpk_layout layouts[3] = {TPK_LAYOUT_TET16, TPK_LAYOUT_TET20, TPK_LAYOUT_TET32};
    for (int l = 0; l < 3; l++) {
        CHECK(scene_layout(&s, layouts[l]) == 0);
        tpk_render_stats a, b;
        CHECK(render_env(&s, NULL, NULL, NULL, direct, &a) == 0);
        setenv("TPK_VK_SPLIT_BYTES", "65536", 1);
        int rc = render_env(&s, NULL, "staged", "256", staged, &b);
        unsetenv("TPK_VK_SPLIT_BYTES");
        CHECK(rc == 0);
        printf("layout %d: tet steps %llu and %llu, upload %.3f s and %.3f s\n", (int)layouts[l],
               (unsigned long long)a.tet_steps, (unsigned long long)b.tet_steps, a.setup_upload_seconds,
               b.setup_upload_seconds);
        CHECK(a.tet_steps == b.tet_steps && a.tet_steps > 0);
        CHECK(memcmp(direct, staged, n) == 0);
    }
    free(direct);
    free(staged);
    scene_free(&s);
}

/* Timestamps around the dispatches (lavapipe has them): the GPU time of a frame is positive and no
 * longer than the frame; the setup is reported apart. */
TPK_TEST(gpu_timestamps)
{
    if (!have_device())
        return;
    scene s;
    CHECK(scene_open(&s, TPK_SOURCE_DIR "/samples/cylinder.vtk", "cylinder.tpk") == 0);
    CHECK(scene_layout(&s, TPK_LAYOUT_TET16) == 0);
    uint8_t *img = malloc((size_t)SIZE * SIZE * 4);
    CHECK(img);
    tpk_render_stats st;
    CHECK(render_env(&s, NULL, NULL, NULL, img, &st) == 0);
    printf("seconds %.4f, gpu %.4f; setup: device %.4f, upload %.4f, pipeline %.4f, first frame %.4f\n", st.seconds,
           st.gpu_seconds, st.setup_device_seconds, st.setup_upload_seconds, st.setup_pipeline_seconds,
           st.first_frame_seconds);
    CHECK(st.gpu_seconds > 0 && st.gpu_seconds <= st.first_frame_seconds);
    CHECK(st.setup_device_seconds > 0 && st.setup_upload_seconds > 0 && st.setup_pipeline_seconds > 0);
    CHECK(st.setup_device_seconds + st.setup_upload_seconds + st.setup_pipeline_seconds + st.first_frame_seconds <=
          st.seconds);
    free(img);
    scene_free(&s);
}

/* The pipeline cache on disk ($XDG_CACHE_HOME/tetpack): the first run writes it, the second loads it
 * and hands it to the driver; a damaged file is
 * ignored and rewritten; a cache directory that cannot be made is no error. */
TPK_TEST(pipeline_cache)
{
    if (!have_device())
        return;
    scene s;
    CHECK(scene_open(&s, TPK_SOURCE_DIR "/samples/cylinder.vtk", "cylinder.tpk") == 0);
    CHECK(scene_layout(&s, TPK_LAYOUT_TET16) == 0);
    s.opt.width = s.opt.height = 16;
    uint8_t img[16 * 16 * 4];
    char dir[1024];
    snprintf(dir, sizeof dir, "%s", tpk_temp_path("xdg_cache"));
    setenv("XDG_CACHE_HOME", dir, 1);
    tpk_render_stats first, second, damaged;
    CHECK(render_env(&s, NULL, NULL, NULL, img, &first) == 0);
    CHECK(render_env(&s, NULL, NULL, NULL, img, &second) == 0);
    printf("first run: loaded %llu bytes; second: loaded %llu bytes, %d hits\n",
           (unsigned long long)first.pipeline_cache_bytes, (unsigned long long)second.pipeline_cache_bytes,
           second.pipeline_cache_hits);
    CHECK(first.pipeline_cache_bytes == 0 && second.pipeline_cache_bytes > 0);
    /* hits: 1 where the driver keeps compiled pipelines in its cache data, -1 where it does not say;
     * lavapipe (Mesa 22.3) writes only the cache header, so it finds nothing and compiles again */
    CHECK(second.pipeline_cache_hits >= -1 && second.pipeline_cache_hits <= 1);
    /* flip a byte of the driver's data: the checksum no longer holds, the file is not given to the driver */
    /* in C, not with dd: under the sanitizers every child of this test has libasan preloaded (the Vulkan
     * tests' environment), and dd's aligned_alloc(4096, 1) is refused there */
    char sub[1100], file[1400] = "";
    snprintf(sub, sizeof sub, "%s/tetpack", dir);
    DIR *d = opendir(sub);
    CHECK(d != NULL);
    int files = 0;
    for (struct dirent *e; d && (e = readdir(d)) != NULL;)
        if (e->d_name[0] != '.') {
            files++;
            if (!strncmp(e->d_name, "pipelines-", 10))
                snprintf(file, sizeof file, "%s/%s", sub, e->d_name);
        }
    if (d)
        closedir(d);
    CHECK(files == 1 && file[0]);
    FILE *f = fopen(file, "r+b");
    CHECK(f && fseek(f, 80, SEEK_SET) == 0 && fputc(0xff, f) == 0xff);
    if (f)
        fclose(f);
    CHECK(render_env(&s, NULL, NULL, NULL, img, &damaged) == 0);
    CHECK(damaged.pipeline_cache_bytes == 0);
    CHECK(render_env(&s, NULL, NULL, NULL, img, &second) == 0); /* rewritten by the damaged run */
    CHECK(second.pipeline_cache_bytes > 0);
    /* XDG_CACHE_HOME is a file: no cache, no error */
    setenv("XDG_CACHE_HOME", tpk_temp_path("cylinder.tpk"), 1);
    CHECK(render_env(&s, NULL, NULL, NULL, img, &second) == 0);
    CHECK(second.pipeline_cache_bytes == 0);
    unsetenv("XDG_CACHE_HOME");
    scene_free(&s);
}

/* Rays in slices (vk_layout.h, "Slices": on by default on lavapipe) against rays in one dispatch: the
 * state saved between slices is the whole state, so the pictures are the same bit for bit and the
 * counts equal, with shadow rays (a ray pauses for its casts) and in bands of 900 pixels. With AO rays
 * too, a ray in one dispatch passes lavapipe's 65535 loop iterations here and is cut short; in slices
 * its counts are the CPU reference's (within the AO directions' float rounding). */
TPK_TEST(slices)
{
    if (!have_device())
        return;
    scene s;
    CHECK(scene_open(&s, TPK_SOURCE_DIR "/samples/cylinder.vtk", "cylinder.tpk") == 0);
    CHECK(scene_layout(&s, TPK_LAYOUT_TET16) == 0);
    size_t n = (size_t)SIZE * SIZE * 4;
    uint8_t *whole = malloc(n), *sliced = malloc(n);
    CHECK(whole && sliced);
    s.opt.shading = 1;
    s.opt.shadows = 1;
    tpk_render_stats a, b, c;
    setenv("TPK_VK_SLICED", "0", 1);
    int rc = render_env(&s, NULL, NULL, NULL, whole, &a);
    setenv("TPK_VK_SLICED", "1", 1);
    rc |= render_env(&s, "900", NULL, NULL, sliced, &b);
    CHECK(rc == 0);
    printf("shadows: tet steps %llu and %llu, secondary rays %llu and %llu\n", (unsigned long long)a.tet_steps,
           (unsigned long long)b.tet_steps, (unsigned long long)a.secondary_rays, (unsigned long long)b.secondary_rays);
    CHECK(a.secondary_rays > 0);
    CHECK_EQ_INT(b.tet_steps, a.tet_steps);
    CHECK_EQ_INT(b.secondary_rays, a.secondary_rays);
    CHECK(memcmp(whole, sliced, n) == 0);

    s.opt.ao_rays = 3;
    s.opt.iso_count = 1;
    s.opt.iso[0] = 0.5 * (s.opt.range_min + s.opt.range_max);
    s.opt.iso_opacity = 0.4;
    tpk_diag diag = {0};
    CHECK_MSG(tpk_render_cpu(&s.mesh, &s.opt, whole, &c, &diag) == 0, "%s", diag.message);
    CHECK(render_env(&s, "900", NULL, NULL, sliced, &b) == 0);
    unsetenv("TPK_VK_SLICED");
    printf("iso + shadows + AO: tet steps cpu %llu, sliced %llu; secondary rays %llu, %llu\n",
           (unsigned long long)c.tet_steps, (unsigned long long)b.tet_steps, (unsigned long long)c.secondary_rays,
           (unsigned long long)b.secondary_rays);
    CHECK(c.secondary_rays > 0);
    CHECK(fabs((double)b.secondary_rays - (double)c.secondary_rays) <= 0.005 * (double)c.secondary_rays);
    CHECK(fabs((double)b.tet_steps - (double)c.tet_steps) <= 0.005 * (double)c.tet_steps);
    free(whole);
    free(sliced);
    scene_free(&s);
}
