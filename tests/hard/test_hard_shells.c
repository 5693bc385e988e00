/* Hard cases for shells and cameras (issue 13), each with a measured outcome asserted: non-convex shells
 * with a tunnel, a cavity and components touching at a vertex and along an edge; cells of 1e-3 at an
 * offset of 1e7; a camera exactly on a shell face, on a shell vertex, on an inner vertex and inside a tet,
 * and rays grazing a shell face. */
#include "hard_common.h"
#include "render/render.h"

/* ---- a non-convex union of unit cubes -------------------------------------------------------------- */

enum { G = 8 }; /* grid of G^3 cube slots; the block is cubes 0..5 on each axis */

/* The block minus a tunnel along z at (3,3) and a closed cavity at (1,1,3), plus a cube touching the block
 * only at the vertex (6,6,6) and one touching it only along the edge x = 6, y = 6, 2 <= z <= 3. */
static int shell_keep(int i, int j, int k)
{
    if (i <= 5 && j <= 5 && k <= 5)
        return !(i == 3 && j == 3) && !(i == 1 && j == 1 && k == 3);
    return (i == 6 && j == 6 && k == 6) || (i == 6 && j == 6 && k == 2);
}

/* Chord through the union: the sum over kept cubes (their interiors are disjoint). */
static double union_chord(const double org[3], const double dir[3])
{
    double sum = 0;
    for (int k = 0; k < G; k++)
        for (int j = 0; j < G; j++)
            for (int i = 0; i < G; i++)
                if (shell_keep(i, j, k)) {
                    const double lo[3] = {i, j, k}, hi[3] = {i + 1, j + 1, k + 1};
                    sum += hard_box_chord(lo, hi, org, dir, 0);
                }
    return sum;
}

TPK_TEST(nonconvex_tunnel_cavity_touching)
{
    hard_mesh m = {0};
    const double zero[3] = {0, 0, 0};
    hard_hex_grid(&m, G, 1.0, zero, shell_keep, 5);
    CHECK(hard_mesh_write(&m, tpk_temp_path("shell.vtk")) == 0);
    hard_mesh_free(&m);
    tpk_convert_report rep;
    tpk_diag diag;
    CHECK_MSG(hard_convert(tpk_temp_path("shell.vtk"), tpk_temp_path("shell.tpk"), 0, &rep, &diag) == 0, "%s",
              diag.message);
    hard_tpk t;
    CHECK(hard_tpk_open(&t, tpk_temp_path("shell.tpk")) == 0);
    hard_ray *r = malloc(sizeof *r);
    CHECK(r);
    long rays = 0, multi_entry = 0, max_entries = 0;
    double max_err = 0, max_overlap = 0;
    /* axis-aligned rays through cube centres' lines: the shell entries equal the runs of kept cubes */
    for (int axis = 0; axis < 3; axis++)
        for (int a = 0; a < G; a++)
            for (int b = 0; b < G; b++) {
                double org[3], dir[3] = {0, 0, 0};
                int u = (axis + 1) % 3, v = (axis + 2) % 3;
                org[u] = a + 0.5, org[v] = b + 0.5, org[axis] = -2, dir[axis] = 1;
                long runs = 0, kept = 0;
                for (int c = 0, prev = 0; c < G; c++) {
                    int ijk[3];
                    ijk[u] = a, ijk[v] = b, ijk[axis] = c;
                    int in = shell_keep(ijk[0], ijk[1], ijk[2]);
                    runs += in && !prev, kept += in, prev = in;
                }
                for (int l = 0; l < 3; l++) {
                    tpk_march_stats st;
                    CHECK(hard_march(&t, l, org, dir, 0, r, &st) == TPK_OK);
                    CHECK_MSG((long)st.shell_entries == runs && fabs(r->length - (double)kept) <= 1e-12 * G,
                              "axis %d at (%d %d): entries %llu of %ld runs, length %.17g of %ld", axis, a, b,
                              (unsigned long long)st.shell_entries, runs, r->length, kept);
                    multi_entry += l == 0 && runs > 1;
                    max_entries = runs > max_entries ? runs : max_entries;
                }
                rays++;
            }
    /* rays exactly through the touching vertex (6,6,6) and across the touching edge (6,6,z), from many
     * directions, and random rays: length = chord through the union */
    uint64_t rng = 3;
    for (int i = 0; i < 4000; i++) {
        double target[3], org[3], dir[3];
        int kind = i % 4;
        for (int k = 0; k < 3; k++) {
            target[k] = kind == 0 ? 6.0 : kind == 1 ? (k == 2 ? 2 + hard_uniform(&rng) : 6.0) : G * hard_uniform(&rng);
            dir[k] = 2 * hard_uniform(&rng) - 1;
        }
        if (kind < 2 && i % 8 < 2) /* the diagonal through the vertex, and across the edge */
            dir[0] = 1, dir[1] = 1, dir[2] = kind == 0 ? 1 : 0;
        for (int k = 0; k < 3; k++)
            org[k] = target[k] - 20 * dir[k];
        double chord = union_chord(org, dir);
        for (int l = 0; l < 3; l++) {
            tpk_result res = hard_march(&t, l, org, dir, 0, r, NULL);
            CHECK_MSG(res == TPK_OK, "layout %d, ray (%.17g %.17g %.17g) dir (%.17g %.17g %.17g) kind %d: %s (pieces %d, "
                      "backwards %d)", l, org[0], org[1], org[2], dir[0], dir[1], dir[2], kind, tpk_result_string(res),
                      r->pieces, r->backwards);
            double err = fabs(r->length - chord);
            max_err = fmax(max_err, err);
            max_overlap = fmax(max_overlap, r->overlap);
            CHECK_MSG(err <= 1e-9, "ray (%.17g %.17g %.17g) dir (%.17g %.17g %.17g): length %.17g, chord %.17g", org[0],
                      org[1], org[2], dir[0], dir[1], dir[2], r->length, chord);
        }
        rays++;
    }
    hard_report("nonconvex_tunnel_cavity_touching", "shell entries = runs of cubes; length = chord through the union",
                "\"tets\":%lld,\"shell_faces\":%lld,\"rays\":%ld,\"rays_with_several_entries\":%ld,\"most_entries\":%ld,"
                "\"rays_through_touching_vertex_or_edge\":2000,\"max_length_error\":%.3g,"
                "\"max_reentry_overlap\":%.3g",
                (long long)rep.tets, (long long)rep.shell_faces, rays, multi_entry, max_entries, max_err, max_overlap);
    free(r);
    hard_tpk_close(&t);
}

/* ---- cells of 1e-3 at an offset of 1e7 --------------------------------------------------------------- */

TPK_TEST(offset_1e7_cells_1e3)
{
    enum { N = 6 };
    const double h = 1e-3, shift[2][3] = {{0, 0, 0}, {1e7, -1e7, 1e7 + 0.25}};
    double lengths[2][3 * 4 * N * 4 * N];
    long rays = 0;
    for (int s = 0; s < 2; s++) {
        hard_mesh m = {0};
        hard_hex_grid(&m, N, h, shift[s], NULL, 13);
        const char *vtk = s ? "far.vtk" : "near.vtk", *tpk = s ? "far.tpk" : "near.tpk";
        CHECK(hard_mesh_write(&m, tpk_temp_path(vtk)) == 0);
        hard_mesh_free(&m);
        tpk_convert_report rep;
        tpk_diag diag;
        CHECK_MSG(hard_convert(tpk_temp_path(vtk), tpk_temp_path(tpk), 0, &rep, &diag) == 0, "%s", diag.message);
        hard_tpk t;
        CHECK(hard_tpk_open(&t, tpk_temp_path(tpk)) == 0);
        hard_ray *r = malloc(sizeof *r);
        CHECK(r);
        long n = 0;
        for (int axis = 0; axis < 3; axis++)
            for (int a = 0; a < 4 * N; a++)
                for (int b = 0; b < 4 * N; b++, n++) {
                    /* lines at odd eighths of a cell: inside, off every face plane */
                    double org[3], dir[3] = {0, 0, 0};
                    int u = (axis + 1) % 3, v = (axis + 2) % 3;
                    org[u] = shift[s][u] + (a + 0.5) * 0.25 * h, org[v] = shift[s][v] + (b + 0.5) * 0.25 * h;
                    org[axis] = shift[s][axis] - h, dir[axis] = 1;
                    CHECK(hard_march(&t, 2, org, dir, 0, r, NULL) == TPK_OK);
                    lengths[s][n] = r->length;
                }
        rays = n;
        free(r);
        hard_tpk_close(&t);
    }
    /* float32 relative to the origin keeps the cells: the far grid's chords match the near grid's and N h */
    double max_far = 0, max_diff = 0;
    for (long i = 0; i < rays; i++) {
        max_far = fmax(max_far, fabs(lengths[1][i] - N * h) / (N * h));
        max_diff = fmax(max_diff, fabs(lengths[1][i] - lengths[0][i]) / (N * h));
    }
    CHECK_MSG(max_far <= 1e-6 && max_diff <= 1e-6, "relative chord error %.3g, far against near %.3g", max_far, max_diff);
    hard_report("offset_1e7_cells_1e3", "every ray crosses the far grid as the near one",
                "\"cells\":%d,\"cell\":%g,\"offset\":1e7,\"rays\":%ld,\"max_rel_chord_error\":%.3g,"
                "\"max_rel_diff_far_vs_near\":%.3g",
                N * N * N, h, rays, max_far, max_diff);
}

/* ---- cameras on the shell, on vertices and inside, and grazing rays ----------------------------------- */

enum { B = 4 }; /* the box [0,4]^3 of unit hexahedra */

/* tpk_render_cpu of constant density (no field): the pixel's alpha must be 1 - exp(-a chord / unit) for
 * the chord from the eye through the box (the camera math is render_cpu.c's); returns the largest error
 * in units of 1/255, or -1 when the render fails. */
static double camera_error(const tpk_mesh_arrays *arrays, const double eye[3], const double at[3], int size)
{
    tpk_transfer_function tf;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_tf_parse("constant", "0 1 1 1 0.3\n1 1 1 1 0.3\n", &tf, &diag) != 0)
        return -1;
    tpk_render_options opt;
    memset(&opt, 0, sizeof opt);
    opt.width = opt.height = size;
    memcpy(opt.camera.eye, eye, sizeof opt.camera.eye);
    memcpy(opt.camera.at, at, sizeof opt.camera.at);
    opt.camera.up[2] = 1;
    opt.camera.fovy_deg = 100;
    opt.tf = &tf;
    opt.unit_distance = 4; /* optical depth at most 0.3 * 7 / 4: below the 98% stop */
    opt.threads = 2;
    uint8_t *img = malloc((size_t)size * (size_t)size * 4);
    if (!img || tpk_render_cpu(arrays, &opt, img, NULL, &diag) != 0) {
        fprintf(stderr, "render: %s\n", diag.message);
        free(img);
        return -1;
    }
    double f[3], r[3], u[3], len = 0;
    for (int k = 0; k < 3; k++)
        f[k] = at[k] - eye[k], len += f[k] * f[k];
    for (int k = 0; k < 3; k++)
        f[k] /= sqrt(len);
    r[0] = f[1], r[1] = -f[0], r[2] = 0; /* f x (0,0,1) */
    len = sqrt(r[0] * r[0] + r[1] * r[1]);
    r[0] /= len, r[1] /= len;
    u[0] = r[1] * f[2] - r[2] * f[1], u[1] = r[2] * f[0] - r[0] * f[2], u[2] = r[0] * f[1] - r[1] * f[0];
    double th = tan(0.5 * 100 * M_PI / 180), worst = 0;
    const double lo[3] = {0, 0, 0}, hi[3] = {B, B, B};
    for (int y = 0; y < size; y++)
        for (int x = 0; x < size; x++) {
            double px = (2.0 * (x + 0.5) / size - 1) * th, py = (1 - 2.0 * (y + 0.5) / size) * th, d[3], l2 = 0;
            for (int k = 0; k < 3; k++)
                d[k] = f[k] + px * r[k] + py * u[k], l2 += d[k] * d[k];
            for (int k = 0; k < 3; k++)
                d[k] /= sqrt(l2);
            double expect = 1 - exp(-0.3 * hard_box_chord(lo, hi, eye, d, 0) / 4);
            worst = fmax(worst, fabs(img[4 * (y * size + x) + 3] - 255 * expect));
        }
    free(img);
    return worst;
}

TPK_TEST(camera_on_face_vertex_inside_and_grazing)
{
    hard_mesh m = {0};
    const double zero[3] = {0, 0, 0};
    hard_hex_grid(&m, B, 1.0, zero, NULL, 17);
    CHECK(hard_mesh_write(&m, tpk_temp_path("box.vtk")) == 0);
    hard_mesh_free(&m);
    tpk_convert_report rep;
    tpk_diag diag;
    CHECK_MSG(hard_convert(tpk_temp_path("box.vtk"), tpk_temp_path("box.tpk"), 0, &rep, &diag) == 0, "%s", diag.message);
    hard_tpk t;
    CHECK(hard_tpk_open(&t, tpk_temp_path("box.tpk")) == 0);
    static const struct {
        const char *name;
        double eye[3], at[3];
    } cams[] = {{"on a shell face", {2.3, 1.7, 0}, {2, 2, 2}},     {"on a shell vertex (face)", {2, 2, 0}, {2.1, 1.9, 2}},
                {"on the box corner", {0, 0, 0}, {2, 2, 2}},       {"on an inner vertex", {2, 2, 2}, {4, 3, 1}},
                {"inside a tet", {1.3, 2.1, 1.7}, {0, 4, 3}},       {"on a shell edge", {4, 2, 4}, {1, 1, 1}}};
    char figures[1024] = "";
    size_t used = 0;
    double worst_all = 0;
    for (size_t c = 0; c < sizeof cams / sizeof cams[0]; c++) {
        for (int l = 0; l < 3; l++) {
            double err = camera_error(&t.arrays[l], cams[c].eye, cams[c].at, 48);
            CHECK_MSG(err >= 0 && err <= 1.0, "camera %s, layout %d: alpha off by %.3g / 255", cams[c].name, l, err);
            worst_all = fmax(worst_all, err);
            if (l == 2)
                used += (size_t)snprintf(figures + used, sizeof figures - used, "\"%s\":%.3g,", cams[c].name, err);
        }
    }
    /* grazing: rays in the plane z = 0 of a shell face give 0 or the chord; 1e-12 inside, the chord;
     * 1e-12 outside, nothing */
    hard_ray *r = malloc(sizeof *r);
    CHECK(r);
    const double lo[3] = {0, 0, 0}, hi[3] = {B, B, B};
    long grazing = 0;
    for (int i = 0; i < 200; i++) {
        double angle = 0.01 + i * (2 * M_PI / 200), dir[3] = {cos(angle), sin(angle), 0};
        for (int side = -1; side <= 1; side++) {
            double org[3] = {2 - 10 * dir[0], 2 - 10 * dir[1], side * 1e-12};
            double chord = hard_box_chord(lo, hi, org, dir, 0);
            CHECK(hard_march(&t, i % 3, org, dir, 0, r, NULL) == TPK_OK);
            if (side < 0)
                CHECK_MSG(r->length == 0, "below the face: %.17g", r->length);
            else if (side > 0)
                CHECK_MSG(fabs(r->length - chord) <= 1e-12, "above the face: %.17g of %.17g", r->length, chord);
            else
                CHECK_MSG(r->length == 0 || fabs(r->length - chord) <= 1e-12, "in the face: %.17g", r->length);
            grazing++;
        }
    }
    free(r);
    hard_tpk_close(&t);
    hard_report("camera_on_face_vertex_inside_and_grazing",
                "constant-density images within 1/255 of the exact alpha; grazing rays 0 or the chord",
                "%s\"grazing_rays\":%ld,\"worst_alpha_error_255\":%.3g", figures, grazing, worst_all);
}
