/* CSG probes (render.h PROBES) on the CPU reference: a slab between two half-spaces and a sphere, kept
 * and cut away, against their closed forms (a constant TF of extinction k over the 8^3 grid: a pixel's
 * alpha is 1 - exp(-k L), L the length of its ray inside what the probes keep); the spans of a ray, the
 * text form, the check and extract's tet test. Vulkan against the CPU on real meshes:
 * tests/cli/probes.sh. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "march_fixtures.h"
#include "render/render.h"
#include "render/transfer_function.h"

enum { W = 48, H = 48, N = W * H * 4 };
#define K 0.3 /* the TF's alpha 0.3 per unit distance 1 */

static uint8_t *render(const fx_mesh *m, const tpk_render_options *opt)
{
    tpk_mesh_arrays arrays = fx_arrays(m, TPK_LAYOUT_TET16);
    uint8_t *img = malloc(N);
    tpk_diag diag = {0};
    if (img && tpk_render_cpu(&arrays, opt, img, NULL, &diag) != 0) {
        fprintf(stderr, "render: %s\n", diag.message);
        free(img);
        return NULL;
    }
    return img;
}

/* The unit direction of pixel (x, y), as render_cpu.c computes it. */
static void pixel_ray(const tpk_camera *cam, int x, int y, double d[3])
{
    tpk_camera_basis b;
    tpk_diag diag = {0};
    tpk_camera_basis_of(cam, W, H, &b, &diag);
    double px = (2.0 * (x + 0.5) / W - 1.0) * b.tan_half_x, py = (1.0 - 2.0 * (y + 0.5) / H) * b.tan_half_y, len = 0;
    for (int k = 0; k < 3; k++) {
        d[k] = b.forward[k] + px * b.right[k] + py * b.up[k];
        len += d[k] * d[k];
    }
    for (int k = 0; k < 3; k++)
        d[k] /= sqrt(len);
}

/* [t0, t1] of the ray o + t d inside the box [lo, hi]^3; 0 when it misses. */
static int box_span(const double o[3], const double d[3], double lo, double hi, double *t0, double *t1)
{
    *t0 = 0;
    *t1 = INFINITY;
    for (int k = 0; k < 3; k++) {
        double a = (lo - o[k]) / d[k], b = (hi - o[k]) / d[k];
        *t0 = fmax(*t0, fmin(a, b));
        *t1 = fmin(*t1, fmax(a, b));
    }
    return *t0 < *t1;
}

/* Every pixel's alpha is 1 - exp(-K L(ray)) within 1/255, except where L changes fast (within `edge` of a
 * silhouette, said by the caller through `skip`). *shown_out (may be NULL): the pixels that show something. */
typedef double (*length_fn)(const double o[3], const double d[3], int *skip);
static void check_alpha(const uint8_t *img, const tpk_camera *cam, length_fn length, const char *what, int *shown_out)
{
    int bad = 0, shown = 0, checked = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double d[3];
            pixel_ray(cam, x, y, d);
            int skip = 0;
            double L = length(cam->eye, d, &skip);
            const uint8_t *p = &img[4 * (y * W + x)];
            shown += p[3] > 0;
            if (skip)
                continue;
            checked++;
            int expect = (int)(255.0 * (1.0 - exp(-K * L)) + 0.5);
            if (abs(p[3] - expect) > 1) {
                if (bad++ < 3)
                    fprintf(stderr, "%s: pixel (%d, %d) alpha %d, closed form %d (L = %g)\n", what, x, y, p[3], expect, L);
            }
        }
    if (shown_out)
        *shown_out = shown;
    CHECK_MSG(bad == 0, "%s: %d of %d pixels off the closed form", what, bad, checked);
    CHECK_MSG(checked > W * H / 2, "%s: only %d pixels checked", what, checked);
}

/* The slab 3 <= x <= 5 of the grid [0, 8]^3: what two keep half-spaces leave, and what a cut box takes. */
static double slab_kept(const double o[3], const double d[3], int *skip)
{
    double t0, t1;
    if (!box_span(o, d, 0, 8, &t0, &t1))
        return 0;
    double a = fmax(t0, (3 - o[0]) / d[0]), b = fmin(t1, (5 - o[0]) / d[0]);
    *skip = fabs(b - a) < 0.3 && b > a - 0.3; /* a grazing corner */
    return b > a ? b - a : 0;
}

static double slab_cut(const double o[3], const double d[3], int *skip)
{
    double t0, t1;
    if (!box_span(o, d, 0, 8, &t0, &t1))
        return 0;
    double a = fmax(t0, (3 - o[0]) / d[0]), b = fmin(t1, (5 - o[0]) / d[0]);
    *skip = fabs(t1 - t0) < 0.3;
    return (t1 - t0) - (b > a ? b - a : 0);
}

/* The sphere of center (4, 4, 4), radius 2.5 (inside the grid). */
static double chord(const double o[3], const double d[3], double *t0, double *t1)
{
    double q = 0, c = -2.5 * 2.5;
    for (int k = 0; k < 3; k++) {
        q += d[k] * (o[k] - 4);
        c += (o[k] - 4) * (o[k] - 4);
    }
    double disc = q * q - c;
    *t0 = disc > 0 ? -q - sqrt(disc) : 0;
    *t1 = disc > 0 ? -q + sqrt(disc) : 0;
    return disc > 0 ? 2 * sqrt(disc) : 0;
}

static double sphere_kept(const double o[3], const double d[3], int *skip)
{
    double t0, t1, L = chord(o, d, &t0, &t1);
    *skip = L > 0 && L < 0.5; /* near the outline alpha changes by more than 1/255 per pixel */
    return L;
}

static double sphere_cut(const double o[3], const double d[3], int *skip)
{
    double t0, t1, b0, b1, L = chord(o, d, &t0, &t1);
    if (!box_span(o, d, 0, 8, &b0, &b1))
        return 0;
    *skip = (L > 0 && L < 0.5) || b1 - b0 < 0.3;
    return (b1 - b0) - L;
}

static void probe_options(tpk_render_options *opt, const tpk_transfer_function *tf, const double eye[3])
{
    memset(opt, 0, sizeof *opt);
    opt->width = W;
    opt->height = H;
    const tpk_camera cam = {{eye[0], eye[1], eye[2]}, {4, 4, 4}, {0, 0, 1}, 30};
    opt->camera = cam;
    opt->tf = tf;
    opt->range_max = 8;
    opt->unit_distance = 1;
}

TPK_TEST(slab_and_sphere_closed_form)
{
    fx_mesh m;
    CHECK(fx_render_grid(&m, 1) == 0);
    tpk_transfer_function tf;
    tpk_diag diag = {0};
    CHECK(tpk_tf_parse("constant", "0 1 1 1 0.3\n1 1 1 1 0.3\n", &tf, &diag) == 0);
    tpk_render_options opt;
    const double eye[3] = {-14, 9, 7}; /* oblique: rays cross the slab's faces and the grid's sides */
    probe_options(&opt, &tf, eye);
    uint8_t *full = render(&m, &opt);
    CHECK(full);

    /* keep x <= 5 and x >= 3 (normals point away from what is kept; any length) */
    const tpk_probe below5 = {TPK_PROBE_PLANE, 0, {5, 0, 0}, {2, 0, 0}, 0};
    const tpk_probe above3 = {TPK_PROBE_PLANE, 0, {3, 7, -1}, {-1, 0, 0}, 0};
    opt.probe_count = 2;
    opt.probes[0] = below5;
    opt.probes[1] = above3;
    uint8_t *img = render(&m, &opt);
    CHECK(img);
    int shown_slab = 0, shown_ball = 0;
    check_alpha(img, &opt.camera, slab_kept, "slab kept", &shown_slab);
    free(img);
    /* the same slab cut away by a box that reaches past the grid */
    const tpk_probe box = {TPK_PROBE_BOX, 1, {3, -1, -1}, {5, 9, 9}, 0};
    opt.probe_count = 1;
    opt.probes[0] = box;
    img = render(&m, &opt);
    CHECK(img);
    check_alpha(img, &opt.camera, slab_cut, "slab cut", NULL);
    free(img);

    const tpk_probe ball = {TPK_PROBE_SPHERE, 0, {4, 4, 4}, {0, 0, 0}, 2.5};
    opt.probes[0] = ball;
    img = render(&m, &opt);
    CHECK(img);
    check_alpha(img, &opt.camera, sphere_kept, "sphere kept", &shown_ball);
    free(img);
    opt.probes[0].cut = 1;
    img = render(&m, &opt);
    CHECK(img);
    check_alpha(img, &opt.camera, sphere_cut, "sphere cut", NULL);
    free(img);
    CHECK(shown_slab > 0 && shown_ball > 0 && shown_ball < shown_slab);

    /* a keep probe around the whole grid, and a cut probe beside it, change nothing (within rounding) */
    const tpk_probe around = {TPK_PROBE_SPHERE, 0, {4, 4, 4}, {0, 0, 0}, 100};
    const tpk_probe beside = {TPK_PROBE_BOX, 1, {20, 20, 20}, {30, 30, 30}, 0};
    opt.probe_count = 2;
    opt.probes[0] = around;
    opt.probes[1] = beside;
    img = render(&m, &opt);
    CHECK(img);
    int off = 0;
    for (int i = 0; i < N; i++)
        off += abs(img[i] - full[i]) > 1;
    CHECK_MSG(off == 0, "%d bytes differ from the picture without probes", off);
    free(img);
    /* a keep probe beside the grid: nothing shows */
    opt.probe_count = 1;
    opt.probes[0] = beside;
    opt.probes[0].cut = 0;
    img = render(&m, &opt);
    CHECK(img);
    int any = 0;
    for (int i = 0; i < W * H; i++)
        any += img[4 * i + 3] != 0;
    CHECK_EQ_INT(any, 0);
    free(img);
    free(full);
    fx_free(&m);
}

/* Shadows see the probes too: an opaque iso plane x = 2 lit from +x through a slab of alpha; cutting the
 * slab away with a probe takes its shadow away. */
TPK_TEST(shadow_rays_are_cut)
{
    fx_mesh m;
    CHECK(fx_render_grid(&m, 1) == 0);
    tpk_transfer_function tf;
    tpk_diag diag = {0};
    CHECK(tpk_tf_parse("slab", "0 1 1 1 0\n0.7 1 1 1 0\n0.75 1 1 1 0.5\n1 1 1 1 0.5\n", &tf, &diag) == 0);
    tpk_render_options opt;
    const double eye[3] = {-30, 4.02, 3.97};
    probe_options(&opt, &tf, eye);
    opt.camera.fovy_deg = 10;
    opt.iso_count = 1;
    opt.iso[0] = 2;
    opt.shadows = 1;
    opt.have_light = 1;
    const double light[3] = {40, 4.02, 3.97};
    memcpy(opt.light, light, sizeof light);
    uint8_t *shadowed = render(&m, &opt);
    const tpk_probe cut = {TPK_PROBE_PLANE, 1, {5, 0, 0}, {-1, 0, 0}, 0}; /* cuts x >= 5 away */
    opt.probe_count = 1;
    opt.probes[0] = cut;
    uint8_t *lit = render(&m, &opt);
    CHECK(shadowed && lit);
    const uint8_t *a = &shadowed[4 * (H / 2 * W + W / 2)], *b = &lit[4 * (H / 2 * W + W / 2)];
    int expect = (int)(255 * (0.3 + 0.7 * exp(-1.1)) + 0.5);
    CHECK_MSG(abs(a[0] - expect) <= 1, "shadowed %d, expected %d", a[0], expect);
    CHECK_MSG(b[0] == 255 && b[3] == 255, "with the slab cut away %d %d, expected 255 255", b[0], b[3]);
    free(shadowed);
    free(lit);
    fx_free(&m);
}

TPK_TEST(spans)
{
    const double o[3] = {-10, 0, 0}, d[3] = {1, 0, 0};
    double s[TPK_RENDER_MAX_PROBES + 1][2];
    tpk_probe p[4] = {{TPK_PROBE_SPHERE, 1, {0, 0, 0}, {0, 0, 0}, 1}};
    /* a cut sphere splits [0, 20] in two */
    CHECK_EQ_INT(tpk_probe_spans(p, 1, o, d, 0, 20, s), 2);
    CHECK(s[0][0] == 0 && s[0][1] == 9 && s[1][0] == 11 && s[1][1] == 20);
    /* four cut spheres along the ray: five spans, in order */
    for (int i = 0; i < 4; i++) {
        p[i] = p[0];
        p[i].a[0] = -6 + 4 * i;
        p[i].radius = 0.5;
    }
    CHECK_EQ_INT(tpk_probe_spans(p, 4, o, d, 0, 20, s), 5);
    for (int i = 0; i < 4; i++)
        CHECK(s[i][1] < s[i + 1][0]);
    /* a keep sphere the ray misses: nothing; a cut one it misses: unchanged */
    tpk_probe miss = {TPK_PROBE_SPHERE, 0, {0, 5, 0}, {0, 0, 0}, 1};
    CHECK_EQ_INT(tpk_probe_spans(&miss, 1, o, d, 0, 20, s), 0);
    miss.cut = 1;
    CHECK_EQ_INT(tpk_probe_spans(&miss, 1, o, d, 0, 20, s), 1);
    CHECK(s[0][0] == 0 && s[0][1] == 20);
    /* a half-space parallel to the ray: all of it or nothing */
    tpk_probe side = {TPK_PROBE_PLANE, 0, {0, 1, 0}, {0, 1, 0}, 0}; /* keeps y <= 1: the ray is inside */
    CHECK_EQ_INT(tpk_probe_spans(&side, 1, o, d, 0, 20, s), 1);
    side.b[1] = -1; /* keeps y >= 1: the ray is outside */
    CHECK_EQ_INT(tpk_probe_spans(&side, 1, o, d, 0, 20, s), 0);
    /* a cut that takes a span to zero length drops it; an empty range gives nothing */
    tpk_probe all = {TPK_PROBE_BOX, 1, {-100, -1, -1}, {100, 1, 1}, 0};
    CHECK_EQ_INT(tpk_probe_spans(&all, 1, o, d, 0, 20, s), 0);
    CHECK_EQ_INT(tpk_probe_spans(&miss, 1, o, d, 5, 5, s), 0);
    /* points */
    const double in[3] = {0, 0, 0}, out[3] = {0, 3, 0};
    tpk_probe ball = {TPK_PROBE_SPHERE, 0, {0, 0, 0}, {0, 0, 0}, 1};
    CHECK(tpk_probe_keeps(&ball, 1, in) && !tpk_probe_keeps(&ball, 1, out));
    ball.cut = 1;
    CHECK(!tpk_probe_keeps(&ball, 1, in) && tpk_probe_keeps(&ball, 1, out));
}

TPK_TEST(may_show_is_conservative)
{
    const double inside[4][3] = {{0, 0, 0}, {0.1, 0, 0}, {0, 0.1, 0}, {0, 0, 0.1}};
    const double across[4][3] = {{0, 0, 0}, {3, 0, 0}, {0, 0.1, 0}, {0, 0, 0.1}};
    const double far[4][3] = {{5, 5, 5}, {5.1, 5, 5}, {5, 5.1, 5}, {5, 5, 5.1}};
    tpk_probe ball = {TPK_PROBE_SPHERE, 1, {0, 0, 0}, {0, 0, 0}, 1};
    CHECK(!tpk_probe_may_show(&ball, 1, inside)); /* wholly in a cut sphere */
    CHECK(tpk_probe_may_show(&ball, 1, across));
    CHECK(tpk_probe_may_show(&ball, 1, far));
    ball.cut = 0;
    CHECK(tpk_probe_may_show(&ball, 1, inside) && tpk_probe_may_show(&ball, 1, across));
    CHECK(!tpk_probe_may_show(&ball, 1, far)); /* its box misses a keep sphere */
    tpk_probe plane = {TPK_PROBE_PLANE, 0, {2, 0, 0}, {1, 1, 0}, 0}; /* keeps x + y <= 2 */
    CHECK(tpk_probe_may_show(&plane, 1, inside) && tpk_probe_may_show(&plane, 1, across));
    CHECK(!tpk_probe_may_show(&plane, 1, far));
    /* every point a render can see is in a tet may_show keeps: sampled over random tets and points */
    uint32_t seed = 12345;
    int kept_points = 0;
    for (int trial = 0; trial < 2000; trial++) {
        double c[4][3];
        for (int j = 0; j < 4; j++)
            for (int k = 0; k < 3; k++) {
                seed = seed * 1664525u + 1013904223u;
                c[j][k] = -2 + 4.0 * (seed >> 8) / (1u << 24);
            }
        tpk_probe pr[2] = {{TPK_PROBE_SPHERE, 0, {0.3, 0, 0}, {0, 0, 0}, 1.5},
                           {TPK_PROBE_BOX, 1, {-0.5, -0.5, -3}, {0.5, 0.5, 3}, 0}};
        int may = tpk_probe_may_show(pr, 2, c);
        for (int s = 0; s < 20; s++) {
            double w[4], sum = 0, x[3] = {0, 0, 0};
            for (int j = 0; j < 4; j++) {
                seed = seed * 1664525u + 1013904223u;
                w[j] = (seed >> 8) / (double)(1u << 24);
                sum += w[j];
            }
            for (int j = 0; j < 4; j++)
                for (int k = 0; k < 3; k++)
                    x[k] += w[j] / sum * c[j][k];
            if (tpk_probe_keeps(pr, 2, x)) {
                kept_points++;
                CHECK_MSG(may, "trial %d: a kept point in a tet may_show drops", trial);
            }
        }
    }
    CHECK(kept_points > 1000);
}

TPK_TEST(text_form_and_check)
{
    tpk_probe p, q;
    CHECK(tpk_probe_parse("sphere:1,2,3,0.5", &p) == 0);
    CHECK(p.shape == TPK_PROBE_SPHERE && !p.cut && p.a[2] == 3 && p.radius == 0.5);
    CHECK(tpk_probe_parse("plane:0,0,0.1,0,0,-1:cut", &p) == 0);
    CHECK(p.shape == TPK_PROBE_PLANE && p.cut && p.a[2] == 0.1 && p.b[2] == -1);
    CHECK(tpk_probe_parse("box:0,0,0,1,1,1:keep", &p) == 0 && p.shape == TPK_PROBE_BOX && p.b[0] == 1);
    char text[256];
    const tpk_probe odd = {TPK_PROBE_SPHERE, 1, {0.1, 1e-300, -3.3333333333333335}, {0, 0, 0}, 0.7};
    tpk_probe_format(&odd, text, sizeof text);
    CHECK(tpk_probe_parse(text, &q) == 0 && !memcmp(&q, &odd, sizeof q)); /* exactly back */
    const char *bad[] = {"sphere:1,2,3", "sphere:1,2,3,4,5", "cone:1,2,3,4", "plane:1,2,3,4,5,6:both", "box:1,2,3,4,5,x",
                         "sphere:1,2,3,4:", "box", "", "sphere:1,2,3,1e999", "plane:1,,3,4,5,6"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        CHECK_MSG(tpk_probe_parse(bad[i], &p) == -1, "'%s' parsed", bad[i]);
    tpk_diag diag = {0};
    const tpk_probe flat = {TPK_PROBE_SPHERE, 0, {0, 0, 0}, {0, 0, 0}, 0};
    CHECK(tpk_probe_check(&flat, 1, &diag) == -1);
    CHECK_MSG(strstr(diag.message, "probe 1: expected a sphere radius > 0, found 0"), "%s", diag.message);
    const tpk_probe zero = {TPK_PROBE_PLANE, 0, {0, 0, 0}, {0, 0, 0}, 0};
    CHECK(tpk_probe_check(&zero, 2, &diag) == -1);
    CHECK_MSG(strstr(diag.message, "probe 2: the plane's normal is zero"), "%s", diag.message);
    const tpk_probe inverted = {TPK_PROBE_BOX, 0, {0, 2, 0}, {1, 1, 1}, 0};
    CHECK(tpk_probe_check(&inverted, 3, &diag) == -1);
    CHECK_MSG(strstr(diag.message, "probe 3: box min 2 above max 1 on axis y"), "%s", diag.message);
    const tpk_probe nan_box = {TPK_PROBE_BOX, 0, {0, NAN, 0}, {1, 1, 1}, 0};
    CHECK(tpk_probe_check(&nan_box, 1, &diag) == -1);
    CHECK_MSG(strstr(diag.message, "must be finite"), "%s", diag.message);
    const tpk_probe shape = {7, 0, {0, 0, 0}, {1, 1, 1}, 0};
    CHECK(tpk_probe_check(&shape, 1, &diag) == -1);
    CHECK_MSG(strstr(diag.message, "expected shape sphere (1), plane (2) or box (3), found 7"), "%s", diag.message);
}
