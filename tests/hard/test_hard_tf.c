/* Hard cases for the transfer function (issue 13): opacity stepping from 0 to 1 within 1e-6 of the range,
 * and opacity so high that every ray saturates within 1e-4 of the bounds diagonal. The CPU renderer
 * (tpk_render_cpu, exact integration) on a converted box with the field s = x must match the closed form
 * within a stated bound on every pixel. */
#include "hard_common.h"
#include "render/render.h"

enum { B = 4, SIZE = 48 };

typedef struct tf_scene {
    hard_tpk t;
    float *scalars;
    tpk_render_options opt;
    double f[3], r[3], u[3], th;
} tf_scene;

static int tf_scene_open(tf_scene *s)
{
    memset(s, 0, sizeof *s);
    hard_mesh m = {0};
    const double zero[3] = {0, 0, 0};
    hard_hex_grid(&m, B, 1.0, zero, NULL, 29);
    tpk_convert_report rep;
    tpk_diag diag;
    if (hard_mesh_write(&m, tpk_temp_path("tf.vtk")) != 0 ||
        hard_convert(tpk_temp_path("tf.vtk"), tpk_temp_path("tf.tpk"), 0, &rep, &diag) != 0 ||
        hard_tpk_open(&s->t, tpk_temp_path("tf.tpk")) != 0) {
        hard_mesh_free(&m);
        return -1;
    }
    hard_mesh_free(&m);
    tpk_mesh_arrays *a = &s->t.arrays[2];
    s->scalars = malloc(sizeof(float) * (size_t)a->vertex_count);
    if (!s->scalars)
        return -1;
    for (uint64_t v = 0; v < a->vertex_count; v++) /* s = x, exact: integer points */
        s->scalars[v] = (float)(a->origin[0] + a->positions[3 * v]);
    a->scalars = s->scalars;
    memset(&s->opt, 0, sizeof s->opt);
    s->opt.width = s->opt.height = SIZE;
    const double lo[3] = {0, 0, 0}, hi[3] = {B, B, B};
    tpk_camera_default(lo, hi, &s->opt.camera);
    s->opt.range_min = 0, s->opt.range_max = B;
    s->opt.threads = 2;
    /* the pixel rays of render_cpu.c, for the closed form */
    const tpk_camera *c = &s->opt.camera;
    double len = 0;
    for (int k = 0; k < 3; k++)
        s->f[k] = c->at[k] - c->eye[k], len += s->f[k] * s->f[k];
    for (int k = 0; k < 3; k++)
        s->f[k] /= sqrt(len);
    s->r[0] = s->f[1] * c->up[2] - s->f[2] * c->up[1], s->r[1] = s->f[2] * c->up[0] - s->f[0] * c->up[2];
    s->r[2] = s->f[0] * c->up[1] - s->f[1] * c->up[0];
    len = sqrt(s->r[0] * s->r[0] + s->r[1] * s->r[1] + s->r[2] * s->r[2]);
    for (int k = 0; k < 3; k++)
        s->r[k] /= len;
    s->u[0] = s->r[1] * s->f[2] - s->r[2] * s->f[1], s->u[1] = s->r[2] * s->f[0] - s->r[0] * s->f[2];
    s->u[2] = s->r[0] * s->f[1] - s->r[1] * s->f[0];
    s->th = tan(0.5 * c->fovy_deg * M_PI / 180.0);
    return 0;
}

static void tf_scene_close(tf_scene *s)
{
    hard_tpk_close(&s->t);
    free(s->scalars);
}

static void pixel_dir(const tf_scene *s, int x, int y, double d[3])
{
    double px = (2.0 * (x + 0.5) / SIZE - 1) * s->th, py = (1 - 2.0 * (y + 0.5) / SIZE) * s->th, l2 = 0;
    for (int k = 0; k < 3; k++)
        d[k] = s->f[k] + px * s->r[k] + py * s->u[k], l2 += d[k] * d[k];
    for (int k = 0; k < 3; k++)
        d[k] /= sqrt(l2);
}

/* Opacity from 0 to 1 per unit distance at s = 0.575 (x = 2.3, inside the tets, not on their faces), white:
 * alpha = 1 - exp(-L / unit) with L the chord in x >= 2.3. Returns the largest alpha error in 1/255 for the integration given. */
static double step_error(tf_scene *s, int integration)
{
    tpk_transfer_function tf;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_tf_parse("step", "0 1 1 1 0\n0.575 1 1 1 0\n0.575001 1 1 1 1\n1 1 1 1 1\n", &tf, &diag) != 0)
        return -1;
    s->opt.tf = &tf;
    s->opt.unit_distance = 4; /* optical depth at most 7 / 4: below the 98% stop */
    s->opt.integration = integration;
    uint8_t img[SIZE * SIZE * 4];
    if (tpk_render_cpu(&s->t.arrays[2], &s->opt, img, NULL, &diag) != 0)
        return fprintf(stderr, "%s\n", diag.message), -1;
    const double lo[3] = {2.3, 0, 0}, hi[3] = {B, B, B};
    double worst = 0;
    for (int y = 0; y < SIZE; y++)
        for (int x = 0; x < SIZE; x++) {
            double d[3];
            pixel_dir(s, x, y, d);
            double expect = 1 - exp(-hard_box_chord(lo, hi, s->opt.camera.eye, d, 0) / 4);
            worst = fmax(worst, fabs(img[4 * (y * SIZE + x) + 3] - 255 * expect));
        }
    return worst;
}

TPK_TEST(opacity_step)
{
    tf_scene s;
    CHECK(tf_scene_open(&s) == 0);
    double exact = step_error(&s, 0), sampled = step_error(&s, 1);
    tf_scene_close(&s);
    /* exact: 8-bit rounding plus the step's 1e-6 width; sampled: its samples 2 apart miss the step */
    CHECK_MSG(exact >= 0 && exact <= 1.0, "exact integration off by %.3g / 255", exact);
    CHECK_MSG(sampled > 2 * exact, "sampled %.3g not worse than exact %.3g: the step is not inside a piece", sampled, exact);
    hard_report("opacity_step", "exact integration within 1/255 of the closed form",
                "\"max_alpha_error_exact_255\":%.3g,\"max_alpha_error_sampled_255\":%.3g,\"pixels\":%d", exact, sampled,
                SIZE * SIZE);
}

/* Opacity 1 per unit distance with unit = diagonal / 1e5: every ray that enters stops within a few units,
 * so the pixel shows the TF colour at the entry scalar, c(s) = (s, 1 - s, 0.5), opaque. */
TPK_TEST(very_high_opacity)
{
    tf_scene s;
    CHECK(tf_scene_open(&s) == 0);
    tpk_transfer_function tf;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    CHECK(tpk_tf_parse("ramp", "0 0 1 0.5 1\n1 1 0 0.5 1\n", &tf, &diag) == 0);
    s.opt.tf = &tf;
    s.opt.unit_distance = B * sqrt(3.0) / 1e5;
    uint8_t img[SIZE * SIZE * 4];
    CHECK_MSG(tpk_render_cpu(&s.t.arrays[2], &s.opt, img, NULL, &diag) == 0, "%s", diag.message);
    const double lo[3] = {0, 0, 0}, hi[3] = {B, B, B};
    double worst_color = 0, worst_alpha = 0;
    int hits = 0;
    for (int y = 0; y < SIZE; y++)
        for (int x = 0; x < SIZE; x++) {
            double d[3], tn = 0, tf_ = INFINITY;
            pixel_dir(&s, x, y, d);
            const uint8_t *px = &img[4 * (y * SIZE + x)];
            if (hard_box_chord(lo, hi, s.opt.camera.eye, d, 0) < 1e-2) { /* misses, or grazes a corner */
                continue;
            }
            for (int k = 0; k < 3; k++) { /* entry point */
                double t0 = (lo[k] - s.opt.camera.eye[k]) / d[k], t1 = (hi[k] - s.opt.camera.eye[k]) / d[k];
                tn = fmax(tn, fmin(t0, t1)), tf_ = fmin(tf_, fmax(t0, t1));
            }
            double sx = (s.opt.camera.eye[0] + tn * d[0]) / B, expect[3] = {sx, 1 - sx, 0.5};
            for (int k = 0; k < 3; k++)
                worst_color = fmax(worst_color, fabs(px[k] - 255 * expect[k]));
            worst_alpha = fmax(worst_alpha, 255 - px[3]);
            hits++;
        }
    tf_scene_close(&s);
    /* the 98% stop leaves alpha in [0.98, 1]; the colour is the entry's to 8-bit rounding */
    CHECK_MSG(hits > SIZE * SIZE / 8 && worst_color <= 1.0 && worst_alpha <= 0.02 * 255 + 1,
              "hits %d, colour off by %.3g / 255, alpha short by %.3g / 255", hits, worst_color, worst_alpha);
    hard_report("very_high_opacity", "opaque at the entry, the entry's colour within 1/255",
                "\"optical_depth_per_diagonal\":1e5,\"pixels_hit\":%d,\"max_color_error_255\":%.3g,"
                "\"max_alpha_shortfall_255\":%.3g",
                hits, worst_color, worst_alpha);
}
