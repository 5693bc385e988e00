/* The render effects of render.h on an 8^3 grid (6 tets per cube) with the scalar s = x: each one is
 * checked against its closed form (iso plane position and colour, shadow and AO factors), against the
 * plain picture (clip box coverage, darkening), and for thread-count independence. Real meshes:
 * tests/cli/render_effects.sh. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "march_fixtures.h"
#include "render/render.h"
#include "render/transfer_function.h"

enum { W = 64, H = 64, N = W * H * 4 };

/* Options over the grid: range 0..8 (u = x / 8), unit distance 1, transparent black background. */
static void grid_options(tpk_render_options *opt, const tpk_transfer_function *tf, const double eye[3])
{
    memset(opt, 0, sizeof *opt);
    opt->width = W;
    opt->height = H;
    const tpk_camera cam = {{eye[0], eye[1], eye[2]}, {4, 4, 4}, {0, 0, 1}, 40};
    opt->camera = cam;
    opt->tf = tf;
    opt->range_max = 8;
    opt->unit_distance = 1;
}

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

/* The set-up most tests share: the grid, the viridis TF, grid_options from the eye (17, -5, 12). 0, or -1. */
static int viridis_grid(fx_mesh *m, tpk_transfer_function *tf, tpk_render_options *opt)
{
    tpk_diag diag = {0};
    if (fx_render_grid(m, 1) != 0 || tpk_tf_load("viridis", tf, &diag) != 0)
        return -1;
    const double eye[3] = {17, -5, 12};
    grid_options(opt, tf, eye);
    return 0;
}

static const uint8_t *pixel(const uint8_t *img, int x, int y)
{
    return &img[4 * (y * W + x)];
}

/* The unit direction of pixel (x, y), as render_cpu.c computes it. */
static void pixel_ray(const tpk_camera *cam, int x, int y, double d[3])
{
    double f[3], r[3], u[3], len = 0;
    for (int k = 0; k < 3; k++)
        f[k] = cam->at[k] - cam->eye[k];
    len = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (int k = 0; k < 3; k++)
        f[k] /= len;
    r[0] = f[1] * cam->up[2] - f[2] * cam->up[1];
    r[1] = f[2] * cam->up[0] - f[0] * cam->up[2];
    r[2] = f[0] * cam->up[1] - f[1] * cam->up[0];
    len = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    for (int k = 0; k < 3; k++)
        r[k] /= len;
    u[0] = r[1] * f[2] - r[2] * f[1];
    u[1] = r[2] * f[0] - r[0] * f[2];
    u[2] = r[0] * f[1] - r[1] * f[0];
    double ty = tan(0.5 * cam->fovy_deg * M_PI / 180.0), tx = ty * W / H;
    double px = (2.0 * (x + 0.5) / W - 1.0) * tx, py = (1.0 - 2.0 * (y + 0.5) / H) * ty;
    for (int k = 0; k < 3; k++)
        d[k] = f[k] + px * r[k] + py * u[k];
    len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int k = 0; k < 3; k++)
        d[k] /= len;
}

/* Does pixel (x, y) see the plane x = v inside the box [0,8]^3? */
static int sees_plane(const tpk_camera *cam, int x, int y, double v)
{
    double d[3];
    pixel_ray(cam, x, y, d);
    double t = (v - cam->eye[0]) / d[0];
    double py = cam->eye[1] + t * d[1], pz = cam->eye[2] + t * d[2];
    return t > 0 && py >= 0 && py <= 8 && pz >= 0 && pz <= 8;
}

/* The image shows the plane x = v exactly where the ray algebra says, up to pixels on its outline (an
 * 8-neighbour on the other side), and in the TF colour at v, opaque; `alone`: nothing else shows
 * either. *shown_count (may be NULL): the pixels that show something. */
static void check_plane(const uint8_t *img, const tpk_camera *cam, double v, const double rgb[3], int alone,
                        int *shown_count)
{
    int covered = 0, wrong = 0, colour_off = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            int expect = sees_plane(cam, x, y, v), edge = 0;
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++)
                    edge |= sees_plane(cam, x + dx, y + dy, v) != expect;
            const uint8_t *p = pixel(img, x, y);
            int shown = p[3] > 0;
            covered += shown;
            if (shown != expect && !edge && (alone || expect))
                wrong++;
            if (expect && !edge)
                for (int k = 0; k < 3; k++)
                    colour_off += abs(p[k] - (int)(rgb[k] * 255 + 0.5)) > 1 || p[3] != 255;
        }
    CHECK_MSG(wrong == 0, "%d pixels away from the outline disagree with the plane x = %g", wrong, v);
    if (shown_count)
        *shown_count = covered;
    CHECK_MSG(colour_off == 0, "%d plane pixels differ from the TF colour at %g", colour_off, v);
}

TPK_TEST(iso_plane_position_and_colour)
{
    fx_mesh m;
    CHECK(fx_render_grid(&m, 1) == 0);
    tpk_transfer_function tf;
    tpk_diag diag = {0};
    CHECK(tpk_tf_parse("red-blue", "0 1 0 0 0\n1 0 0 1 0\n", &tf, &diag) == 0); /* transparent volume */
    tpk_render_options opt;
    const double eye[3] = {17, -5, 12};
    grid_options(&opt, &tf, eye);
    opt.iso_count = 1;
    opt.iso[0] = 3.3;
    uint8_t *img = render(&m, &opt);
    CHECK(img);
    const double rgb[3] = {1 - 3.3 / 8, 0, 3.3 / 8};
    int covered = 0;
    check_plane(img, &opt.camera, 3.3, rgb, 1, &covered);
    CHECK_MSG(covered > W * H / 8, "the plane covers only %d pixels", covered);
    /* a plane half a unit (about 3 pixels) off would fail the check above */
    int moved = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            int edge = 0, here = sees_plane(&opt.camera, x, y, 3.3);
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++)
                    edge |= sees_plane(&opt.camera, x + dx, y + dy, 3.3) != here;
            moved += !edge && here != sees_plane(&opt.camera, x, y, 3.8);
        }
    CHECK_MSG(moved > 10, "x = 3.3 and x = 3.8 differ in only %d pixels off the outline", moved);
    /* half opacity: alpha 128 over the transparent background, the same colour */
    opt.iso_opacity = 0.5;
    free(img);
    img = render(&m, &opt);
    CHECK(img);
    const uint8_t *centre = pixel(img, W / 2, H / 2);
    CHECK_MSG(centre[3] == 128, "alpha %d", centre[3]);
    /* two values: the nearer one hides the farther one */
    opt.iso_opacity = 1;
    opt.iso_count = 2;
    opt.iso[0] = 2.0;
    opt.iso[1] = 5.0;
    free(img);
    img = render(&m, &opt);
    CHECK(img);
    const double near[3] = {1 - 5.0 / 8, 0, 5.0 / 8};
    check_plane(img, &opt.camera, 5.0, near, 0, NULL);
    free(img);
    fx_free(&m);
}

/* A tet field with 0 for x < 4 and 1 beyond has its iso 0.5 at the plane x = 4 (the cubes' tets do not
 * cross it); a tet field equal to a constant point field renders the same picture; one equal to the
 * tets' mean x differs from the point field s = x but not by much. */
TPK_TEST(tet_field)
{
    fx_mesh m;
    CHECK(fx_render_grid(&m, 1) == 0);
    float *cells = malloc((size_t)m.tet_count * sizeof(float));
    CHECK(cells);
    for (int64_t t = 0; t < m.tet_count; t++) {
        double cx = 0;
        for (int k = 0; k < 4; k++)
            cx += 0.25 * m.positions[3 * m.tets[4 * t + k]];
        cells[t] = cx < 4 ? 0.0f : 1.0f;
    }
    tpk_transfer_function tf;
    tpk_diag diag = {0};
    CHECK(tpk_tf_parse("red-blue", "0 1 0 0 0\n1 0 0 1 0\n", &tf, &diag) == 0);
    tpk_render_options opt;
    const double eye[3] = {17, -5, 12};
    grid_options(&opt, &tf, eye);
    opt.range_max = 1;
    opt.tet_scalars = cells;
    opt.iso_count = 1;
    opt.iso[0] = 0.5;
    uint8_t *img = render(&m, &opt);
    CHECK(img);
    const double rgb[3] = {0.5, 0, 0.5};
    check_plane(img, &opt.camera, 4.0, rgb, 1, NULL);
    free(img);

    /* constant: tet field == point field */
    CHECK(tpk_tf_load("viridis", &tf, &diag) == 0);
    grid_options(&opt, &tf, eye);
    for (int64_t t = 0; t < m.tet_count; t++)
        cells[t] = 3.0f;
    float *xs = m.scalars;
    float *flat = malloc((size_t)m.vertex_count * sizeof(float));
    CHECK(flat);
    for (int64_t v = 0; v < m.vertex_count; v++)
        flat[v] = 3.0f;
    m.scalars = flat;
    uint8_t *point = render(&m, &opt);
    opt.tet_scalars = cells;
    uint8_t *tet = render(&m, &opt);
    CHECK(point && tet && !memcmp(point, tet, N));
    free(point);
    free(tet);
    /* mean x per tet against s = x */
    m.scalars = xs;
    free(flat);
    for (int64_t t = 0; t < m.tet_count; t++) {
        double cx = 0;
        for (int k = 0; k < 4; k++)
            cx += 0.25 * m.positions[3 * m.tets[4 * t + k]];
        cells[t] = (float)cx;
    }
    opt.tet_scalars = NULL;
    point = render(&m, &opt);
    opt.tet_scalars = cells;
    tet = render(&m, &opt);
    CHECK(point && tet);
    long sum = 0;
    int max = 0;
    for (int i = 0; i < N; i++) {
        int d = abs(point[i] - tet[i]);
        sum += d;
        max = d > max ? d : max;
    }
    CHECK_MSG(max > 4 && (double)sum / N < 8, "tet field vs point field: max %d, mean %.2f", max, (double)sum / N);
    free(point);
    free(tet);
    free(cells);
    fx_free(&m);
}

static int coverage(const uint8_t *img)
{
    int n = 0;
    for (int i = 0; i < W * H; i++)
        n += img[4 * i + 3] > 0;
    return n;
}

TPK_TEST(clip_box)
{
    fx_mesh m;
    CHECK(fx_render_grid(&m, 1) == 0);
    tpk_transfer_function tf;
    tpk_diag diag = {0};
    CHECK(tpk_tf_parse("constant", "0 1 1 1 0.3\n1 1 1 1 0.3\n", &tf, &diag) == 0);
    tpk_render_options opt;
    const double above[3] = {4, 4, 40}; /* looking down -z: the x extent is across the image */
    grid_options(&opt, &tf, above);
    opt.camera.up[0] = 0;
    opt.camera.up[1] = 1;
    opt.camera.up[2] = 0;
    opt.camera.fovy_deg = 20;
    uint8_t *full = render(&m, &opt);
    opt.clip = 1;
    const double lo[3] = {0, -1, -1}, hi[3] = {4, 9, 9};
    memcpy(opt.clip_min, lo, sizeof lo);
    memcpy(opt.clip_max, hi, sizeof hi);
    uint8_t *half = render(&m, &opt);
    CHECK(full && half);
    double ratio = (double)coverage(half) / coverage(full);
    CHECK_MSG(fabs(ratio - 0.5) < 0.04, "x <= 4 covers %.3f of the full picture", ratio);
    for (int y = 0; y < H; y++) /* the kept half is the same picture where the box is not near */
        for (int x = 0; x < W / 2 - 3; x++)
            CHECK(!memcmp(pixel(half, x, y), pixel(full, x, y), 4) || pixel(full, x, y)[3] == 0);
    /* a box beside the mesh: nothing but background */
    const double far_lo[3] = {10, 10, 10}, far_hi[3] = {12, 12, 12};
    memcpy(opt.clip_min, far_lo, sizeof far_lo);
    memcpy(opt.clip_max, far_hi, sizeof far_hi);
    free(half);
    half = render(&m, &opt);
    CHECK(half && coverage(half) == 0);
    /* a box around the whole mesh changes nothing (rays clipped at the shell itself, within rounding) */
    const double all_lo[3] = {-0.5, -0.5, -0.5}, all_hi[3] = {8.5, 8.5, 8.5};
    memcpy(opt.clip_min, all_lo, sizeof all_lo);
    memcpy(opt.clip_max, all_hi, sizeof all_hi);
    free(half);
    half = render(&m, &opt);
    CHECK(half && !memcmp(half, full, N));
    free(half);
    free(full);
    fx_free(&m);
}

/* An opaque plane at x = 2 seen from -x; between it and a light at +x, a slab of TF alpha 0 up to
 * u = 0.7 (x = 5.6), rising to 0.5 at u = 0.75 (x = 6) and 0.5 beyond: optical depth 0.5 * 0.2 + 0.5 * 2
 * = 1.1 toward the light, so S = exp(-1.1) and m = 0.3 + 0.7 S. */
TPK_TEST(shadows_closed_form)
{
    fx_mesh m;
    CHECK(fx_render_grid(&m, 1) == 0);
    tpk_transfer_function tf;
    tpk_diag diag = {0};
    CHECK(tpk_tf_parse("slab", "0 1 1 1 0\n0.7 1 1 1 0\n0.75 1 1 1 0.5\n1 1 1 1 0.5\n", &tf, &diag) == 0);
    tpk_render_options opt;
    const double eye[3] = {-30, 4.02, 3.97};
    grid_options(&opt, &tf, eye);
    opt.camera.at[0] = 4;
    opt.camera.at[1] = 4.02;
    opt.camera.at[2] = 3.97;
    opt.camera.fovy_deg = 10;
    opt.iso_count = 1;
    opt.iso[0] = 2;
    uint8_t *lit = render(&m, &opt);
    opt.shadows = 1;
    opt.have_light = 1;
    const double light[3] = {40, 4.02, 3.97};
    memcpy(opt.light, light, sizeof light);
    uint8_t *shadowed = render(&m, &opt);
    CHECK(lit && shadowed);
    const uint8_t *a = pixel(lit, W / 2, H / 2), *b = pixel(shadowed, W / 2, H / 2);
    int expect = (int)(255 * (0.3 + 0.7 * exp(-1.1)) + 0.5);
    CHECK_MSG(a[0] == 255 && a[3] == 255, "unshadowed %d %d", a[0], a[3]);
    CHECK_MSG(abs(b[0] - expect) <= 1 && b[3] == 255, "shadowed %d, expected %d", b[0], expect);
    int darker = 0;
    for (int i = 0; i < W * H; i++) {
        CHECK(shadowed[4 * i] <= lit[4 * i]);
        darker += shadowed[4 * i] < lit[4 * i];
    }
    CHECK(darker > W * H / 4);
    /* the light on the viewer's side: nothing between, no darkening */
    opt.light[0] = -40;
    free(shadowed);
    shadowed = render(&m, &opt);
    CHECK(shadowed && !memcmp(shadowed, lit, N));
    free(lit);
    free(shadowed);
    fx_free(&m);
}

/* Two planes x = 3.5 (black, opacity 0.5) and x = 4 (white, opacity 0.5) seen from -x over a
 * transparent volume, AO radius 1 with 8 rays: from the x = 4 hit the rays of cos theta > 0.5 (4 of the
 * 8 Fibonacci rows) cross the x = 3.5 plane, so A = (4 * 0.5 + 4) / 8 = 0.75 there; the x = 3.5 hit sees
 * nothing (A = 1). Pixel colour: 0.25 * A * white over alpha 0.75. */
TPK_TEST(ao_closed_form)
{
    fx_mesh m;
    CHECK(fx_render_grid(&m, 1) == 0);
    tpk_transfer_function tf;
    tpk_diag diag = {0};
    CHECK(tpk_tf_parse("bw", "0 0 0 0 0\n0.4375 0 0 0 0\n0.5 1 1 1 0\n1 1 1 1 0\n", &tf, &diag) == 0);
    tpk_render_options opt;
    const double eye[3] = {-30, 4.02, 3.97};
    grid_options(&opt, &tf, eye);
    opt.camera.at[1] = 4.02;
    opt.camera.at[2] = 3.97;
    opt.camera.fovy_deg = 2;
    opt.iso_count = 2;
    opt.iso[0] = 3.5;
    opt.iso[1] = 4.0;
    opt.iso_opacity = 0.5;
    uint8_t *plain = render(&m, &opt);
    opt.ao_rays = 8;
    opt.ao_radius = 1;
    uint8_t *occluded = render(&m, &opt);
    CHECK(plain && occluded);
    for (int i = 0; i < W * H; i++) {
        const uint8_t *p = &plain[4 * i], *q = &occluded[4 * i];
        CHECK_MSG(abs(p[0] - (int)(255 / 3.0 + 0.5)) <= 1 && p[3] == 191, "plain %d %d", p[0], p[3]);
        CHECK_MSG(abs(q[0] - (int)(255 * 0.25 + 0.5)) <= 1 && q[3] == 191, "AO %d %d", q[0], q[3]);
    }
    free(plain);
    free(occluded);
    fx_free(&m);
}

/* Shading of the plane x = 2 with the light straight ahead on the axis: |n . L| = cos of the angle to
 * the light at each point; at the centre about 1. Everything with shading is at most as bright as
 * without, and AO never brightens. */
TPK_TEST(shading_and_darkening)
{
    fx_mesh m;
    tpk_transfer_function tf;
    tpk_render_options opt;
    tpk_diag diag = {0};
    CHECK(viridis_grid(&m, &tf, &opt) == 0);
    opt.iso_count = 1;
    opt.iso[0] = 5.5;
    uint8_t *plain = render(&m, &opt);
    opt.shading = 1;
    opt.have_light = 1;
    const double light[3] = {20, 4, 40};
    memcpy(opt.light, light, sizeof light);
    uint8_t *shaded = render(&m, &opt);
    opt.ao_rays = 6;
    uint8_t *ao = render(&m, &opt);
    CHECK(plain && shaded && ao);
    int darker = 0, brighter = 0, ao_darker = 0, ao_brighter = 0;
    for (int i = 0; i < W * H; i++)
        for (int k = 0; k < 3; k++) {
            darker += shaded[4 * i + k] + 1 < plain[4 * i + k];
            brighter += shaded[4 * i + k] > plain[4 * i + k] + 1;
            ao_darker += ao[4 * i + k] + 1 < shaded[4 * i + k];
            ao_brighter += ao[4 * i + k] > shaded[4 * i + k] + 1;
        }
    CHECK_MSG(brighter == 0 && darker > W * H / 4, "shading: %d darker, %d brighter", darker, brighter);
    CHECK_MSG(ao_brighter == 0 && ao_darker > W * H / 8, "AO: %d darker, %d brighter", ao_darker, ao_brighter);
    /* closed form at one plane pixel over a transparent white volume: the point where the ray meets
     * x = 5.5, n = (1, 0, 0) */
    CHECK(tpk_tf_parse("white", "0 1 1 1 0\n1 1 1 1 0\n", &tf, &diag) == 0);
    opt.ao_rays = 0;
    free(shaded);
    shaded = render(&m, &opt);
    CHECK(shaded);
    double d[3];
    pixel_ray(&opt.camera, W / 2, H / 2, d);
    const double *eye = opt.camera.eye; /* viridis_grid's */
    double t = (5.5 - eye[0]) / d[0], x[3], l[3], len = 0;
    for (int k = 0; k < 3; k++) {
        x[k] = eye[k] + t * d[k];
        l[k] = light[k] - x[k];
        len += l[k] * l[k];
    }
    double c[4], f = 0.3 + 0.7 * fabs(l[0]) / sqrt(len);
    tpk_tf_eval(&tf, 5.5 / 8, c);
    for (int k = 0; k < 3; k++)
        CHECK_MSG(abs(pixel(shaded, W / 2, H / 2)[k] - (int)(255 * f * c[k] + 0.5)) <= 1, "channel %d: %d vs %g", k,
                  pixel(shaded, W / 2, H / 2)[k], 255 * f * c[k]);
    free(plain);
    free(shaded);
    free(ao);
    fx_free(&m);
}

/* Every effect at once: the same bytes on 1, 2 and 3 threads; midpoint integration (one sample per
 * piece) close to exact. */
TPK_TEST(effects_deterministic)
{
    fx_mesh m;
    tpk_transfer_function tf;
    tpk_render_options opt;
    CHECK(viridis_grid(&m, &tf, &opt) == 0);
    opt.unit_distance = 4;
    opt.iso_count = 2;
    opt.iso[0] = 2.5;
    opt.iso[1] = 6.5;
    opt.iso_opacity = 0.6;
    opt.clip = 1;
    const double lo[3] = {0, 0, 0}, hi[3] = {8, 6, 7};
    memcpy(opt.clip_min, lo, sizeof lo);
    memcpy(opt.clip_max, hi, sizeof hi);
    opt.shading = opt.shadows = 1;
    opt.ao_rays = 4;
    uint8_t *img[3];
    for (int i = 0; i < 3; i++) {
        opt.threads = i + 1;
        img[i] = render(&m, &opt);
        CHECK(img[i]);
    }
    CHECK(!memcmp(img[0], img[1], N) && !memcmp(img[0], img[2], N));
    /* midpoint against exact without effects: close on this smooth field */
    opt.iso_count = opt.clip = opt.shading = opt.shadows = opt.ao_rays = 0;
    uint8_t *exact = render(&m, &opt);
    opt.integration = TPK_INTEGRATION_MIDPOINT;
    uint8_t *mid = render(&m, &opt);
    CHECK(exact && mid);
    int max = 0;
    long sum = 0;
    for (int i = 0; i < N; i++) {
        max = abs(exact[i] - mid[i]) > max ? abs(exact[i] - mid[i]) : max;
        sum += abs(exact[i] - mid[i]);
    }
    /* measured: max 10, mean 0.13 (one sample per ~1-unit piece where the TF bends) */
    CHECK_MSG(max > 0 && max <= 12 && (double)sum / N < 0.5, "midpoint differs from exact by max %d, mean %.3f",
              max, (double)sum / N);
    for (int i = 0; i < 3; i++)
        free(img[i]);
    free(exact);
    free(mid);
    fx_free(&m);
}

/* Length of [0, len] of the ray p + t w inside the box [0, 8]^3 (p inside or on it). */
static double inside_box(const double p[3], const double w[3], double len)
{
    double lo = 0, hi = len;
    for (int k = 0; k < 3; k++) {
        if (w[k] == 0)
            continue;
        double ta = (0 - p[k]) / w[k], tb = (8 - p[k]) / w[k];
        lo = fmax(lo, fmin(ta, tb));
        hi = fmin(hi, fmax(ta, tb));
    }
    return hi > lo ? hi - lo : 0;
}

static uint32_t hash32(uint32_t x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

/* render.h OCCLUSION AT VERTICES over a volume of constant extinction k = 0.25: S_v = exp(-k d), d the
 * length of the segment from the vertex toward the light inside the grid's box, and A_v the mean of
 * exp(-k d_i) over the sphere directions of the definition, each clipped by the box. */
TPK_TEST(vertex_cache_closed_form)
{
    fx_mesh m;
    CHECK(fx_render_grid(&m, 1) == 0);
    tpk_transfer_function tf;
    tpk_diag diag = {0};
    CHECK(tpk_tf_parse("fog", "0 1 1 1 0.25\n1 1 1 1 0.25\n", &tf, &diag) == 0);
    tpk_render_options opt;
    const double eye[3] = {17, -5, 12}, light[3] = {30, 1.5, 20};
    grid_options(&opt, &tf, eye);
    opt.shadows = 1;
    opt.have_light = 1;
    memcpy(opt.light, light, sizeof light);
    opt.ao_rays = 6;
    opt.ao_radius = 3;
    opt.occlusion = TPK_OCCLUSION_VERTEX;
    tpk_mesh_arrays arrays = fx_arrays(&m, TPK_LAYOUT_TET16);
    float *s = malloc(arrays.vertex_count * sizeof *s), *a = malloc(arrays.vertex_count * sizeof *a);
    CHECK(s && a);
    tpk_render_stats st;
    CHECK_MSG(tpk_render_vertex_cache(&arrays, &opt, s, a, &st, &diag) == 0, "%s", diag.message);
    CHECK(st.secondary_rays == arrays.vertex_count * 7 && st.tet_steps > 0);
    double worst_s = 0, worst_a = 0;
    for (uint64_t v = 0; v < arrays.vertex_count; v++) {
        double p[3], w[3], len = 0;
        for (int k = 0; k < 3; k++) {
            p[k] = arrays.origin[k] + m.positions[3 * v + k];
            w[k] = light[k] - p[k];
            len += w[k] * w[k];
        }
        len = sqrt(len);
        for (int k = 0; k < 3; k++)
            w[k] /= len;
        worst_s = fmax(worst_s, fabs(s[v] - exp(-0.25 * inside_box(p, w, len))));
        double rot = hash32((uint32_t)v) * (1.0 / 4294967296.0), sum = 0;
        for (int i = 0; i < 6; i++) {
            double z = 1 - 2 * (i + 0.5) / 6, r = sqrt(1 - z * z), f = i * 0.6180339887498949 + rot;
            double phi = 2 * M_PI * (f - floor(f));
            const double d[3] = {r * cos(phi), r * sin(phi), z};
            sum += exp(-0.25 * inside_box(p, d, 3));
        }
        worst_a = fmax(worst_a, fabs(a[v] - sum / 6));
    }
    CHECK_MSG(worst_s < 1e-5 && worst_a < 1e-5, "S off by %g, A off by %g", worst_s, worst_a);
    free(s);
    free(a);
    fx_free(&m);
}

/* The vertex mode renders: the same bytes on 1 and 3 threads, never brighter than without effects,
 * close to the per-ray definition (the two differ by definition: AO over the sphere, interpolation),
 * counts the cache's rays, and without shadows or AO is the plain picture. */
TPK_TEST(vertex_occlusion_render)
{
    fx_mesh m;
    tpk_transfer_function tf;
    tpk_render_options opt;
    tpk_diag diag = {0};
    CHECK(viridis_grid(&m, &tf, &opt) == 0);
    opt.unit_distance = 4;
    uint8_t *plain = render(&m, &opt);
    opt.occlusion = TPK_OCCLUSION_VERTEX;
    uint8_t *same = render(&m, &opt);
    CHECK(plain && same && !memcmp(plain, same, N));
    opt.iso_count = 1;
    opt.iso[0] = 6.5;
    opt.iso_opacity = 0.6;
    opt.shading = opt.shadows = 1;
    opt.ao_rays = 4;
    opt.threads = 1;
    uint8_t *one = render(&m, &opt);
    opt.threads = 3;
    uint8_t *three = render(&m, &opt);
    opt.occlusion = TPK_OCCLUSION_RAY;
    uint8_t *ray = render(&m, &opt);
    CHECK(one && three && ray && !memcmp(one, three, N));
    double se = 0;
    for (int i = 0; i < N; i++)
        se += (double)(one[i] - ray[i]) * (one[i] - ray[i]);
    double psnr = 10 * log10(255.0 * 255.0 / (se / N + 1e-12));
    CHECK_MSG(psnr > 25, "vertex against ray: %.1f dB", psnr);
    tpk_mesh_arrays arrays = fx_arrays(&m, TPK_LAYOUT_TET16);
    tpk_render_stats st;
    opt.occlusion = TPK_OCCLUSION_VERTEX;
    CHECK(tpk_render_cpu(&arrays, &opt, one, &st, &diag) == 0);
    CHECK_MSG(st.secondary_rays == arrays.vertex_count * 5, "%llu secondary rays",
              (unsigned long long)st.secondary_rays);
    free(plain);
    free(same);
    free(one);
    free(three);
    free(ray);
    fx_free(&m);
}

/* render.h OCCLUSION AT THE SURFACE: over a transparent volume with an opaque isosurface the first hit
 * is every pixel's one shade point either way, so `surface` is `ray` byte for byte; over a volume that
 * absorbs, a pixel casts at most 1 + ao_rays rays (the ray mode's volume shade points many more), the
 * same whatever the thread count; without iso values the first volume shade point casts, once. */
static uint8_t *render_stats(const fx_mesh *m, const tpk_render_options *opt, tpk_render_stats *st)
{
    tpk_mesh_arrays arrays = fx_arrays(m, TPK_LAYOUT_TET16);
    uint8_t *img = malloc(N);
    tpk_diag diag = {0};
    if (img && tpk_render_cpu(&arrays, opt, img, st, &diag) != 0) {
        fprintf(stderr, "render: %s\n", diag.message);
        free(img);
        return NULL;
    }
    return img;
}

TPK_TEST(surface_occlusion)
{
    fx_mesh m;
    tpk_transfer_function tf, clear;
    tpk_render_options opt;
    tpk_diag diag = {0};
    CHECK(viridis_grid(&m, &tf, &opt) == 0);
    CHECK(tpk_tf_parse("clear", "0 1 1 1 0\n1 0.2 0.5 1 0\n", &clear, &diag) == 0);
    opt.tf = &clear;
    opt.iso_count = 1;
    opt.iso[0] = 5.5;
    opt.iso_opacity = 1;
    opt.shading = opt.shadows = 1;
    opt.ao_rays = 4;
    opt.ao_radius = 3;
    opt.have_light = 1;
    const double light[3] = {20, 4, 40};
    memcpy(opt.light, light, sizeof light);
    tpk_render_stats a, b;
    uint8_t *ray = render_stats(&m, &opt, &a);
    opt.occlusion = TPK_OCCLUSION_SURFACE;
    uint8_t *surface = render_stats(&m, &opt, &b);
    CHECK(ray && surface && !memcmp(ray, surface, N));
    CHECK_MSG(a.secondary_rays == b.secondary_rays && a.secondary_rays > 0, "secondary rays: ray %llu, surface %llu",
              (unsigned long long)a.secondary_rays, (unsigned long long)b.secondary_rays);
    free(ray);
    free(surface);
    /* an absorbing volume in front of and behind a half-transparent surface */
    opt.tf = &tf;
    opt.iso_opacity = 0.6;
    opt.occlusion = TPK_OCCLUSION_RAY;
    ray = render_stats(&m, &opt, &a);
    opt.occlusion = TPK_OCCLUSION_SURFACE;
    opt.threads = 1;
    surface = render_stats(&m, &opt, &b);
    opt.threads = 3;
    tpk_render_stats c;
    uint8_t *three = render_stats(&m, &opt, &c);
    CHECK(ray && surface && three && !memcmp(surface, three, N) && b.secondary_rays == c.secondary_rays);
    CHECK_MSG(b.secondary_rays > 0 && b.secondary_rays <= (uint64_t)W * H * 5 && 2 * b.secondary_rays < a.secondary_rays,
              "secondary rays: surface %llu, ray %llu", (unsigned long long)b.secondary_rays,
              (unsigned long long)a.secondary_rays);
    int differ = 0;
    for (int i = 0; i < N; i++)
        differ += ray[i] != surface[i];
    CHECK(differ > 0);
    /* without iso values: the first volume shade point, 5 rays for each pixel that shows the volume (and
     * for a few at grazing edges whose opacity rounds to 0), none for the others */
    opt.iso_count = 0;
    free(surface);
    surface = render_stats(&m, &opt, &b);
    int shown = 0;
    for (int i = 0; surface && i < W * H; i++)
        shown += surface[4 * i + 3] != 0;
    CHECK_MSG(surface && shown > 0 && b.secondary_rays % 5 == 0 && b.secondary_rays >= (uint64_t)shown * 5 &&
                  b.secondary_rays <= (uint64_t)shown * 5 * 21 / 20,
              "%d pixels, %llu secondary rays", shown, (unsigned long long)b.secondary_rays);
    free(ray);
    free(surface);
    free(three);
    fx_free(&m);
}

/* The vertex cache kept across frames (tpk_vertex_cache, view's CPU frames): every frame byte for byte
 * tpk_render_cpu's, casting nothing when the camera moves under a fixed light, S alone (one ray per
 * vertex) under a headlight, A alone (ao_rays per vertex) when the AO radius changes, both when the TF
 * changes; and an update that changes nothing says so. */
static void cached_frame(const tpk_mesh_arrays *arrays, const tpk_render_options *opt, tpk_vertex_cache *c,
                         uint64_t want_rays, const char *what, int *culled)
{
    uint8_t *kept = malloc(N), *fresh = malloc(N);
    tpk_render_stats st;
    tpk_diag diag = {0};
    CHECK(kept && fresh);
    CHECK_MSG(tpk_render_cpu_cached(arrays, opt, kept, c, &st, &diag) == 0, "%s: %s", what, diag.message);
    CHECK_MSG(tpk_render_cpu(arrays, opt, fresh, NULL, &diag) == 0, "%s: %s", what, diag.message);
    CHECK_MSG(memcmp(kept, fresh, N) == 0, "%s: the kept cache's picture differs", what);
    CHECK_MSG(st.secondary_rays == want_rays, "%s: %llu secondary rays, expected %llu", what,
              (unsigned long long)st.secondary_rays, (unsigned long long)want_rays);
    free(kept);
    free(fresh);
    if (culled)
        *culled = st.iso_culling;
}

TPK_TEST(vertex_cache_kept_across_frames)
{
    fx_mesh m;
    tpk_transfer_function tf;
    tpk_render_options opt;
    tpk_diag diag = {0};
    CHECK(viridis_grid(&m, &tf, &opt) == 0);
    opt.unit_distance = 4;
    opt.occlusion = TPK_OCCLUSION_VERTEX;
    opt.shading = opt.shadows = 1;
    opt.ao_rays = 4;
    opt.ao_radius = 3;
    opt.have_light = 1;
    opt.light[0] = 30, opt.light[1] = 1.5, opt.light[2] = 20;
    tpk_mesh_arrays arrays = fx_arrays(&m, TPK_LAYOUT_TET16);
    const uint64_t n = arrays.vertex_count;
    tpk_vertex_cache *c = tpk_vertex_cache_create();
    CHECK(c != NULL);
    cached_frame(&arrays, &opt, c, 5 * n, "first frame", NULL);
    opt.camera.eye[0] += 1.5;
    cached_frame(&arrays, &opt, c, 0, "camera move, fixed light", NULL);
    opt.have_light = 0;
    cached_frame(&arrays, &opt, c, n, "headlight", NULL);
    opt.camera.eye[2] -= 2;
    cached_frame(&arrays, &opt, c, n, "headlight, camera move", NULL);
    opt.ao_radius = 2;
    cached_frame(&arrays, &opt, c, 4 * n, "AO radius", NULL);
    opt.range_max = 9;
    cached_frame(&arrays, &opt, c, 5 * n, "range", NULL);
    int changed = 1;
    tpk_render_stats st;
    CHECK(tpk_vertex_cache_update(c, &arrays, &opt, &changed, &st, &diag) == 0);
    CHECK(changed == 0 && st.secondary_rays == 0);
    tpk_vertex_cache_destroy(c);
    fx_free(&m);
}

/* The same cache keeps the marcher and, for iso-only frames, the range culling's trees (render.h
 * tpk_render_cpu_cached): every frame byte for byte tpk_render_cpu's, culled, through a camera move, new
 * iso values, a new field (another scalar array) and another layout (other arrays: a new marcher). */
TPK_TEST(frame_cache_keeps_marcher_and_range_trees)
{
    fx_mesh m;
    tpk_transfer_function tf;
    tpk_render_options opt;
    CHECK(viridis_grid(&m, &tf, &opt) == 0); /* scalar = x, 0..8 */
    for (int i = 0; i < tf.count; i++)
        tf.points[i].a = 0.0; /* iso-only rays */
    opt.iso_count = 1;
    opt.iso[0] = 2.5;
    tpk_mesh_arrays arrays = fx_arrays(&m, TPK_LAYOUT_TET16);
    tpk_vertex_cache *c = tpk_vertex_cache_create();
    CHECK(c != NULL);
    int culled = 0;
    cached_frame(&arrays, &opt, c, 0, "first iso frame", &culled);
    CHECK(culled);
    opt.camera.eye[0] += 1.5;
    cached_frame(&arrays, &opt, c, 0, "camera move", &culled);
    CHECK(culled);
    opt.iso[0] = 5.5;
    cached_frame(&arrays, &opt, c, 0, "a new iso value", &culled);
    CHECK(culled);
    opt.iso[1] = 1.25, opt.iso_count = 2;
    cached_frame(&arrays, &opt, c, 0, "two iso values", NULL);
    opt.iso_count = 1;
    float *shifted = malloc(sizeof *shifted * (size_t)m.vertex_count);
    CHECK(shifted != NULL);
    for (int64_t v = 0; v < m.vertex_count; v++)
        shifted[v] = m.scalars[v] + 1.0f;
    tpk_mesh_arrays other_field = arrays;
    other_field.scalars = shifted;
    cached_frame(&other_field, &opt, c, 0, "another field", &culled);
    CHECK(culled);
    tpk_mesh_arrays tet32 = fx_arrays(&m, TPK_LAYOUT_TET32);
    cached_frame(&tet32, &opt, c, 0, "another layout", &culled);
    CHECK(culled);
    opt.iso_count = 0;
    tf.points[0].a = 0.5;
    cached_frame(&tet32, &opt, c, 0, "emission-absorption, the marcher kept", &culled);
    CHECK(!culled);
    free(shifted);
    tpk_vertex_cache_destroy(c);
    fx_free(&m);
}

TPK_TEST(effects_bad_options)
{
    fx_mesh m;
    CHECK(fx_render_grid(&m, 1) == 0);
    tpk_transfer_function tf;
    tpk_diag diag = {0};
    CHECK(tpk_tf_load("viridis", &tf, &diag) == 0);
    tpk_mesh_arrays arrays = fx_arrays(&m, TPK_LAYOUT_TET16);
    uint8_t *img = malloc(N);
    CHECK(img);
    const double eye[3] = {17, -5, 12};
    static const struct {
        int what;
        const char *expect;
    } cases[] = {{0, "iso values"}, {1, "iso value 1"}, {2, "clip box min"}, {3, "AO rays"}, {4, "integration"},
                 {5, "light"}, {6, "occlusion"}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        tpk_render_options opt;
        grid_options(&opt, &tf, eye);
        switch (cases[c].what) {
        case 0: opt.iso_count = 5; break;
        case 1: opt.iso_count = 1; opt.iso[0] = NAN; break;
        case 2: opt.clip = 1; opt.clip_min[1] = 2; opt.clip_max[1] = 1; break;
        case 3: opt.ao_rays = -1; break;
        case 4: opt.integration = 3; break;
        case 6: opt.occlusion = 3; break;
        default: opt.have_light = 1; opt.light[2] = INFINITY; break;
        }
        CHECK_MSG(tpk_render_cpu(&arrays, &opt, img, NULL, &diag) == -1 && strstr(diag.message, cases[c].expect),
                  "case %zu: %s", c, diag.message);
    }
    free(img);
    fx_free(&m);
}
