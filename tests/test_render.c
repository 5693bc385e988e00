/* Tests of the CPU renderer, the transfer functions and PNG output. */
#include <dirent.h>
#include <math.h>
#include <png.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "harness.h"
#include "march_fixtures.h"
#include "render/render.h"
#include "render/transfer_function.h"
#include "base/parallel.h"

static void base_options(tpk_render_options *opt, const tpk_transfer_function *tf)
{
    tpk_render_options_default(opt);
    opt->width = 64;
    opt->height = 64;
    const double lo[3] = {0, 0, 0}, hi[3] = {8, 8, 8};
    tpk_camera_default(lo, hi, &opt->camera);
    opt->tf = tf;
    opt->range_min = 0;
    opt->range_max = 8;
}

TPK_TEST(render_nonempty_and_deterministic)
{
    fx_mesh m;
    CHECK(fx_render_grid(&m, 1) == 0);
    tpk_mesh_arrays arrays = fx_arrays(&m, TPK_LAYOUT_TET16);
    tpk_transfer_function tf;
    tpk_diag diag = {0};
    CHECK(tpk_tf_load("viridis", &tf, &diag) == 0);
    tpk_render_options opt;
    base_options(&opt, &tf);
    uint8_t *img[3];
    tpk_render_stats st[3];
    for (int i = 0; i < 3; i++) {
        img[i] = malloc(64 * 64 * 4);
        CHECK(img[i]);
        opt.threads = i == 0 ? 1 : i == 1 ? 2 : 5;
        CHECK_MSG(tpk_render_cpu(&arrays, &opt, img[i], &st[i], &diag) == 0, "%s", diag.message);
    }
    CHECK(!memcmp(img[0], img[1], 64 * 64 * 4));
    CHECK(!memcmp(img[0], img[2], 64 * 64 * 4));
    CHECK_EQ_INT(st[0].tet_steps, st[1].tet_steps);
    CHECK_EQ_INT(st[0].rays, 64 * 64);
    /* non-empty: the centre is the volume, the corner is the background (dark gray, opaque) */
    int differ = 0;
    const uint8_t *corner = img[0];
    CHECK(corner[0] == 26 && corner[1] == 26 && corner[2] == 26 && corner[3] == 255);
    for (int p = 0; p < 64 * 64; p++)
        differ += memcmp(&img[0][4 * p], corner, 4) != 0;
    CHECK_MSG(differ > 64 * 64 / 8, "only %d pixels show the volume", differ);
    const uint8_t *centre = &img[0][4 * (32 * 64 + 32)];
    CHECK(memcmp(centre, corner, 4) != 0);
    CHECK(st[0].tet_steps > 1000);
    /* the layouts render the same image */
    arrays = fx_arrays(&m, TPK_LAYOUT_TET32);
    opt.threads = 2;
    CHECK(tpk_render_cpu(&arrays, &opt, img[1], NULL, &diag) == 0);
    CHECK(!memcmp(img[0], img[1], 64 * 64 * 4));
    /* sampling differs from exact integration by little */
    opt.integration = 1;
    CHECK(tpk_render_cpu(&arrays, &opt, img[2], NULL, &diag) == 0);
    int max_diff = 0;
    for (int i = 0; i < 64 * 64 * 4; i++) {
        int d = abs((int)img[0][i] - (int)img[2][i]);
        max_diff = d > max_diff ? d : max_diff;
    }
    CHECK_MSG(max_diff <= 6, "sampling and exact differ by %d", max_diff);
    for (int i = 0; i < 3; i++)
        free(img[i]);
    fx_free(&m);
}

/* One pixel looking down the x axis through the grid: compare with the analytic opacity. */
static int one_pixel(const fx_mesh *m, const tpk_transfer_function *tf, int integration, uint8_t px[4])
{
    tpk_mesh_arrays arrays = fx_arrays(m, TPK_LAYOUT_TET20);
    tpk_render_options opt;
    memset(&opt, 0, sizeof opt); /* zero options: transparent background */
    opt.width = opt.height = 1;
    const tpk_camera cam = {{-10, 4.1, 3.7}, {8, 4.1, 3.7}, {0, 0, 1}, 30};
    opt.camera = cam;
    opt.tf = tf;
    opt.range_min = 0;
    opt.range_max = 8;
    opt.unit_distance = 1;
    opt.integration = integration;
    tpk_diag diag = {0};
    return tpk_render_cpu(&arrays, &opt, px, NULL, &diag);
}

TPK_TEST(render_integration_analytic)
{
    fx_mesh m;
    CHECK(fx_render_grid(&m, 1) == 0);
    tpk_diag diag = {0};
    tpk_transfer_function tf;
    /* opacity ramp 0 -> 0.2 over the field 0..8: optical depth integral_0^8 0.2 x/8 dx = 0.8 */
    CHECK(tpk_tf_parse("ramp", "0 1 0.5 0 0\n1 1 0.5 0 0.2\n", &tf, &diag) == 0);
    int expect = (int)(255.0 * (1.0 - exp(-0.8)) + 0.5);
    for (int integration = 0; integration < 2; integration++) {
        uint8_t px[4];
        CHECK(one_pixel(&m, &tf, integration, px) == 0);
        CHECK_MSG(abs(px[3] - expect) <= (integration ? 2 : 0), "integration %d: alpha %d, expected %d",
                  integration, px[3], expect);
        CHECK(px[0] == 255 && abs(px[1] - 128) <= 1 && px[2] == 0);
    }
    /* no scalars: constant density, the TF at s = 0.5 (alpha 0.1): depth 0.8 again */
    free(m.scalars);
    m.scalars = NULL;
    uint8_t px[4];
    CHECK(one_pixel(&m, &tf, 0, px) == 0);
    CHECK_MSG(abs(px[3] - expect) <= 0, "alpha %d, expected %d", px[3], expect);
    fx_free(&m);
}

TPK_TEST(render_early_termination)
{
    fx_mesh m;
    CHECK(fx_render_grid(&m, 1) == 0);
    tpk_mesh_arrays arrays = fx_arrays(&m, TPK_LAYOUT_TET16);
    tpk_diag diag = {0};
    tpk_transfer_function opaque, faint;
    CHECK(tpk_tf_parse("opaque", "0 1 1 1 1\n1 1 1 1 1\n", &opaque, &diag) == 0);
    CHECK(tpk_tf_parse("faint", "0 1 1 1 0.001\n1 1 1 1 0.001\n", &faint, &diag) == 0);
    tpk_render_options opt;
    uint8_t *img = malloc(64 * 64 * 4);
    CHECK(img);
    tpk_render_stats st_opaque, st_faint;
    base_options(&opt, &opaque);
    opt.unit_distance = 0.1;
    CHECK(tpk_render_cpu(&arrays, &opt, img, &st_opaque, &diag) == 0);
    base_options(&opt, &faint);
    opt.unit_distance = 0.1;
    CHECK(tpk_render_cpu(&arrays, &opt, img, &st_faint, &diag) == 0);
    CHECK_MSG(st_opaque.tet_steps * 3 < st_faint.tet_steps, "opaque %llu vs faint %llu tet steps",
              (unsigned long long)st_opaque.tet_steps, (unsigned long long)st_faint.tet_steps);
    free(img);
    fx_free(&m);
}

TPK_TEST(render_bad_options)
{
    fx_mesh m;
    CHECK(fx_render_grid(&m, 0) == 0);
    tpk_mesh_arrays arrays = fx_arrays(&m, TPK_LAYOUT_TET16);
    tpk_transfer_function tf;
    tpk_diag diag = {0};
    CHECK(tpk_tf_load("grayscale", &tf, &diag) == 0);
    tpk_render_options opt;
    base_options(&opt, &tf);
    uint8_t img[4 * 64 * 64];
    opt.width = 0;
    CHECK(tpk_render_cpu(&arrays, &opt, img, NULL, &diag) == -1 && strstr(diag.message, "width"));
    base_options(&opt, &tf);
    opt.camera.at[0] = opt.camera.eye[0];
    opt.camera.at[1] = opt.camera.eye[1];
    opt.camera.at[2] = opt.camera.eye[2];
    CHECK(tpk_render_cpu(&arrays, &opt, img, NULL, &diag) == -1 && strstr(diag.message, "camera"));
    base_options(&opt, &tf);
    opt.tf = NULL;
    CHECK(tpk_render_cpu(&arrays, &opt, img, NULL, &diag) == -1);
    /* a broken mesh: the error names a pixel */
    base_options(&opt, &tf);
    for (int64_t t = 0; t < m.tet_count; t++)
        m.tet16[t].nx[0] = m.tet16[t].nx[1] = m.tet16[t].nx[2] = 0x3fffffff;
    CHECK(tpk_render_cpu(&arrays, &opt, img, NULL, &diag) == -1);
    CHECK_MSG(strstr(diag.message, "pixel") && strstr(diag.message, "inconsistent"), "%s", diag.message);
    fx_free(&m);
}

/* ---- PNG ----------------------------------------------------------------------------------------- */

/* The whole file's bytes, or NULL. */
static uint8_t *read_all(const char *path, long *size)
{
    FILE *f = fopen(path, "rb");
    uint8_t *data = NULL;
    if (f && fseek(f, 0, SEEK_END) == 0 && (*size = ftell(f)) > 0 && fseek(f, 0, SEEK_SET) == 0 &&
        (data = malloc((size_t)*size)) && fread(data, 1, (size_t)*size, f) != (size_t)*size) {
        free(data);
        data = NULL;
    }
    if (f)
        fclose(f);
    return data;
}

/* Many bands of rows (png_write.c deflates them apart, on threads): libpng reads the pixels back, and
 * 1, 2 and 5 threads write the same bytes. A picture with flat runs and noise, 4 bands and a part. */
TPK_TEST(png_bands_roundtrip_any_threads)
{
    enum { W = 301, H = 3 * 32 + 7 };
    uint8_t *img = malloc(W * H * 4);
    CHECK(img);
    uint32_t rng = 12345;
    for (int i = 0; i < W * H * 4; i++) {
        rng = rng * 1664525u + 1013904223u;
        img[i] = (i / 4) % W < W / 2 ? (uint8_t)(i % 4 == 3 ? 255 : 40) : (uint8_t)(rng >> 24);
    }
    const char *path = tpk_temp_path("bands.png");
    uint8_t *first = NULL;
    long first_size = 0;
    const int threads[3] = {1, 2, 5};
    int previous = tpk_set_default_threads(1);
    for (int k = 0; k < 3; k++) {
        tpk_set_default_threads(threads[k]);
        tpk_diag diag = {0};
        CHECK_MSG(tpk_write_png(path, W, H, img, &diag) == 0, "%s", diag.message);
        long size = 0;
        uint8_t *bytes = read_all(path, &size);
        CHECK(bytes != NULL);
        if (k == 0)
            first = bytes, first_size = size;
        else {
            CHECK_MSG(bytes && size == first_size && !memcmp(bytes, first, (size_t)size), "%d threads", threads[k]);
            free(bytes);
        }
    }
    tpk_set_default_threads(previous);
    png_image image;
    memset(&image, 0, sizeof image);
    image.version = PNG_IMAGE_VERSION;
    CHECK(png_image_begin_read_from_file(&image, path));
    CHECK(image.width == W && image.height == H);
    image.format = PNG_FORMAT_RGBA;
    uint8_t *back = malloc(PNG_IMAGE_SIZE(image));
    CHECK(back && png_image_finish_read(&image, NULL, back, 0, NULL));
    CHECK(back && !memcmp(back, img, W * H * 4));
    free(back);
    free(first);
    free(img);
}

TPK_TEST(png_roundtrip)
{
    enum { W = 37, H = 23 };
    uint8_t *img = malloc(W * H * 4);
    CHECK(img);
    for (int i = 0; i < W * H * 4; i++)
        img[i] = (uint8_t)(i * 7 + i / 5);
    const char *path = tpk_temp_path("out.png");
    tpk_diag diag = {0};
    CHECK_MSG(tpk_write_png(path, W, H, img, &diag) == 0, "%s", diag.message);
    png_image image;
    memset(&image, 0, sizeof image);
    image.version = PNG_IMAGE_VERSION;
    CHECK(png_image_begin_read_from_file(&image, path));
    CHECK_EQ_INT(image.width, W);
    CHECK_EQ_INT(image.height, H);
    image.format = PNG_FORMAT_RGBA;
    uint8_t *back = malloc(PNG_IMAGE_SIZE(image));
    CHECK(back);
    CHECK(png_image_finish_read(&image, NULL, back, 0, NULL));
    CHECK(!memcmp(back, img, W * H * 4));
    /* overwrite in place, and nothing left beside it */
    img[0] ^= 0xff;
    CHECK(tpk_write_png(path, W, H, img, &diag) == 0);
    int leftovers = 0;
    DIR *dir = opendir(tpk_temp_dir());
    CHECK(dir);
    struct dirent *e;
    while ((e = readdir(dir)) != NULL)
        leftovers += strstr(e->d_name, ".tmp.") != NULL;
    closedir(dir);
    CHECK_EQ_INT(leftovers, 0);
    struct stat sb;
    CHECK(stat(path, &sb) == 0 && (sb.st_mode & 0777) == 0644);
    /* an unwritable place fails with a message naming the path */
    CHECK(tpk_write_png("/nonexistent-dir/x.png", W, H, img, &diag) == -1);
    CHECK(strstr(diag.message, "/nonexistent-dir/x.png") != NULL);
    free(back);
    free(img);
}

/* ---- Transfer functions ----------------------------------------------------------------------- */

TPK_TEST(tf_presets)
{
    const char *names[] = {"viridis", "cool-warm", "inferno", "grayscale"};
    for (int i = 0; i < 4; i++) {
        tpk_transfer_function tf;
        tpk_diag diag = {0};
        CHECK_MSG(tpk_tf_load(names[i], &tf, &diag) == 0, "%s", diag.message);
        CHECK(tf.count >= 2);
        CHECK(strstr(tpk_tf_preset_names(), names[i]));
        for (int k = 1; k < tf.count; k++)
            CHECK(tf.points[k].s > tf.points[k - 1].s);
        CHECK(tf.points[0].s == 0 && tf.points[tf.count - 1].s == 1);
        double lo[4], hi[4], mid[4];
        tpk_tf_eval(&tf, -5, lo);
        tpk_tf_eval(&tf, 7, hi);
        tpk_tf_eval(&tf, 0.5, mid);
        CHECK(lo[3] >= 0 && hi[3] > 0 && mid[3] > 0 && hi[3] <= 1);
    }
    tpk_transfer_function tf;
    tpk_diag diag = {0};
    CHECK(tpk_tf_load("grayscale", &tf, &diag) == 0);
    double c[4];
    tpk_tf_eval(&tf, 0.25, c);
    CHECK(fabs(c[0] - 0.25) < 1e-12 && fabs(c[3] - 0.05) < 1e-7);
}

TPK_TEST(tf_file_and_errors)
{
    const char *path = tpk_temp_path("tf.txt");
    FILE *f = fopen(path, "w");
    CHECK(f);
    fputs("# my transfer function\n\n0 0 0 0 0   # transparent black\n0.5 1 0 0 0.5\n1.0 1 1 1 1\n", f);
    fclose(f);
    tpk_transfer_function tf;
    tpk_diag diag = {0};
    CHECK_MSG(tpk_tf_load(path, &tf, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(tf.count, 3);
    double c[4];
    tpk_tf_eval(&tf, 0.75, c);
    CHECK(fabs(c[0] - 1) < 1e-12 && fabs(c[1] - 0.5) < 1e-12 && fabs(c[3] - 0.75) < 1e-12);

    static const struct {
        const char *text, *expect;
    } bad[] = {
        {"0 0 0 0 0\n", "at least 2 points"},
        {"", "at least 2 points"},
        {"0 0 0 0 0\n0 1 1 1 1\n", "t.tf:2: expected s greater than 0"},
        {"0 0 0 0 0\n0.5 1 1 1\n", "t.tf:2: expected 5 numbers"},
        {"0 0 0 0 0\n0.5 1 x 1 1\n", "found x where g should be"},
        {"0 0 0 0 0\n1 1 1 1 1 1\n", "extra text"},
        {"0 0 0 0 0\n1 2 1 1 1\n", "t.tf:2: expected r in [0,1], found 2"},
        {"0 0 0 0 nan\n1 1 1 1 1\n", "t.tf:1: expected 5 numbers"},
        {"0 0 0 0 0\n1,1,1,1,1\n", "t.tf:2"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        memset(&diag, 0, sizeof diag);
        CHECK_MSG(tpk_tf_parse("t.tf", bad[i].text, &tf, &diag) == -1, "case %zu parsed", i);
        CHECK_MSG(strstr(diag.message, bad[i].expect), "case %zu: message '%s' lacks '%s'", i, diag.message,
                  bad[i].expect);
    }
    CHECK(tpk_tf_load("no-such-preset-or-file", &tf, &diag) == -1);
    CHECK(strstr(diag.message, "no-such-preset-or-file") && strstr(diag.message, "viridis"));
}
