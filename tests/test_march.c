/* Tests of the reference CPU marcher: watertightness on rays through vertices and edges, identical tet
 * sequences for Tet32/20/16, exact segments on linear fields, non-convex shells, hostile records. */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "internal_march.h"
#include "internal_range.h"
#include "internal_threads.h"
#include "march_fixtures.h"
#include "tetpack.h"

#include "import/importers.h"
#include "mesh/mesh.h"
#include "convert/pipeline.h"

/* ---- Recording the segments of one ray ---------------------------------------------------------- */

#define REC_MAX 200000

typedef struct recording {
    int64_t count;
    int overflow;
    int32_t tet[REC_MAX];
    double t_in[REC_MAX], t_out[REC_MAX], s_in[REC_MAX], s_out[REC_MAX];
    int32_t v[REC_MAX][4];
} recording;

static int record_segment(void *user, const tpk_segment *s)
{
    recording *r = user;
    if (r->count == REC_MAX) {
        r->overflow = 1;
        return 1;
    }
    r->tet[r->count] = s->tet;
    r->t_in[r->count] = s->t_in;
    r->t_out[r->count] = s->t_out;
    r->s_in[r->count] = s->scalar_in;
    r->s_out[r->count] = s->scalar_out;
    memcpy(r->v[r->count], s->v, sizeof s->v);
    r->count++;
    return 0;
}

static recording *rec_new(void)
{
    return calloc(1, sizeof(recording));
}

static int shared_vertices(const int32_t *a, const int32_t *b)
{
    int n = 0;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            n += a[i] == b[j];
    return n;
}

static double rec_length(const recording *r)
{
    double sum = 0;
    for (int64_t i = 0; i < r->count; i++)
        sum += r->t_out[i] - r->t_in[i];
    return sum;
}

static int are_neighbors(const fx_mesh *m, int32_t a, int32_t b)
{
    for (int k = 0; k < 4; k++)
        if (m->neighbors[4 * (int64_t)a + k] == b)
            return 1;
    return 0;
}

/* The chain rules of one ray: t_in <= t_out, no tet twice; a piece that continues the previous one (a
 * neighbor starting exactly where it ended) shares a face with it; otherwise a new run starts, not
 * before the previous piece ended (up to rounding where runs meet at one point), and there are at most
 * `runs` runs (a convex mesh: 1). Returns a message or NULL. */
static const char *check_chain(const recording *r, const fx_mesh *m, unsigned char *seen, uint64_t runs)
{
    const char *err = NULL;
    uint64_t starts = r->count > 0;
    for (int64_t i = 0; i < r->count && !err; i++) {
        if (!(r->t_in[i] <= r->t_out[i]))
            err = "t_in > t_out";
        else if (seen[r->tet[i]])
            err = "tet visited twice";
        seen[r->tet[i]] = 1;
        if (i > 0 && !err) {
            int continues = r->t_in[i] == r->t_out[i - 1] && are_neighbors(m, r->tet[i - 1], r->tet[i]);
            if (continues && shared_vertices(&m->tets[4 * r->tet[i - 1]], &m->tets[4 * r->tet[i]]) != 3)
                err = "consecutive tets do not share a face";
            if (!continues) {
                starts++;
                if (r->t_in[i] < r->t_out[i - 1] - 1e-12 * (1 + fabs(r->t_out[i - 1])))
                    err = "a run starts before the previous one ended";
            }
        }
    }
    if (!err && starts > runs)
        err = "more runs in the pieces than the marcher counted";
    for (int64_t i = 0; i < r->count; i++)
        seen[r->tet[i]] = 0;
    return err;
}

static tpk_marcher *make_marcher(const fx_mesh *m, tpk_layout layout)
{
    tpk_mesh_arrays a = fx_arrays(m, layout);
    tpk_marcher *marcher = NULL;
    if (tpk_marcher_create(&marcher, &a) != TPK_OK)
        return NULL;
    return marcher;
}

static const tpk_layout layouts[3] = {TPK_LAYOUT_TET32, TPK_LAYOUT_TET20, TPK_LAYOUT_TET16};

/* ---- Unit pieces -------------------------------------------------------------------------------- */

TPK_TEST(exact_det2_sign)
{
    CHECK_EQ_INT(tpki_det2_sign_exact(1, 2, 3, 4), -1);
    CHECK_EQ_INT(tpki_det2_sign_exact(3, 1, 6, 2), 0);
    /* a*d and b*c equal in double but not exactly */
    double a = 1.0 + ldexp(1, -52), d = 1.0 + ldexp(1, -52), b = 1.0 + ldexp(1, -51), c = 1.0;
    CHECK_EQ_INT(tpki_det2_sign_exact(a, b, c, d), 1);
    CHECK_EQ_INT(tpki_det2_sign_exact(b, a, d, c), -1);
    CHECK_EQ_INT(tpki_det2_sign_exact(0.1, 0.3, 0.1, 0.3), 0);
    CHECK_EQ_INT(tpki_det2_sign_exact(1e-200, 1e200, 1e-200, 1e-200), -1);
}

/* One tet with hand-written records: a ray through its middle, from outside and from inside. */
TPK_TEST(single_tet)
{
    static const float pos[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    static const float scal[4] = {0, 1, 2, 3}; /* = x + 2y + 3z */
    tpk_tet32 t32 = {{0, 1, 2}, 0 ^ 1 ^ 2 ^ 3, {-1, -1, -1, -1}};
    tpk_tet20 t20 = {0 ^ 1 ^ 2 ^ 3, {-1, -1, -1, -1}};
    tpk_tet16 t16 = {0 ^ 1 ^ 2 ^ 3, {0, 0, 0}};
    tpk_shell_face shell[4] = {{1, 2, 3, 0}, {0, 3, 2, 0}, {0, 1, 3, 0}, {0, 2, 1, 0}};
    for (int l = 0; l < 3; l++) {
        tpk_mesh_arrays a = {4, 1, 4, {10, 20, 30}, pos, layouts[l], &t16, &t20, &t32, shell, scal};
        tpk_marcher *m = NULL;
        CHECK_EQ_INT(tpk_marcher_create(&m, &a), TPK_OK);
        recording *r = rec_new();
        const double org[3] = {10.1, 20.2, 29}, dir[3] = {0, 0, 2};
        tpk_march_stats st;
        CHECK_EQ_INT(tpk_march_ray(m, org, dir, 0, INFINITY, record_segment, r, &st), TPK_OK);
        CHECK_EQ_INT(r->count, 1);
        CHECK_EQ_INT(st.tet_steps, 1);
        CHECK_EQ_INT(st.shell_entries, 1);
        CHECK(fabs(r->t_in[0] - 0.5) < 1e-12 && fabs(r->t_out[0] - 0.5 * 1.7) < 1e-12);
        CHECK(fabs(r->s_in[0] - 0.5) < 1e-12 && fabs(r->s_out[0] - (0.5 + 0.7 * 3)) < 1e-12);
        /* from inside: clipped at tmin */
        r->count = 0;
        const double org2[3] = {10.1, 20.2, 30.2}, dir2[3] = {0, 0, 1};
        CHECK_EQ_INT(tpk_march_ray(m, org2, dir2, 0, INFINITY, record_segment, r, NULL), TPK_OK);
        CHECK_EQ_INT(r->count, 1);
        CHECK(r->t_in[0] == 0 && fabs(r->t_out[0] - 0.5) < 1e-12);
        CHECK(fabs(r->s_in[0] - (0.5 + 0.6)) < 1e-12);
        /* pointing away, starting outside: nothing */
        r->count = 0;
        const double dir3[3] = {0, 0, -1};
        CHECK_EQ_INT(tpk_march_ray(m, org, dir3, 0, INFINITY, record_segment, r, &st), TPK_OK);
        CHECK_EQ_INT(r->count, 0);
        CHECK_EQ_INT(st.tet_steps, 1); /* the line's run before tmin is marched, nothing reported */
        /* bad arguments */
        const double zero[3] = {0, 0, 0};
        CHECK_EQ_INT(tpk_march_ray(m, org, zero, 0, 1, record_segment, r, NULL), TPK_ERR_INVALID_ARGUMENT);
        /* another field (a time step), 10 - (x + 2y + 3z): the same ray reads it */
        static const float other[4] = {10, 9, 8, 7};
        CHECK_EQ_INT(tpk_marcher_set_scalars(m, other), TPK_OK);
        r->count = 0;
        CHECK_EQ_INT(tpk_march_ray(m, org, dir, 0, INFINITY, record_segment, r, NULL), TPK_OK);
        CHECK_EQ_INT(r->count, 1);
        CHECK(fabs(r->s_in[0] - 9.5) < 1e-12 && fabs(r->s_out[0] - (9.5 - 0.7 * 3)) < 1e-12);
        CHECK_EQ_INT(tpk_marcher_set_scalars(NULL, other), TPK_ERR_INVALID_ARGUMENT);
        free(r);
        tpk_marcher_destroy(m);
    }
}

/* ---- Watertightness on a grid ------------------------------------------------------------------- */

#define GRID 8

/* Chord length of the line org + t dir (t >= tmin) through [0,GRID]^3 (relative coordinates). */
static double box_chord(const double o[3], const double d[3], double tmin)
{
    double tn = tmin, tf = INFINITY;
    for (int k = 0; k < 3; k++) {
        if (d[k] == 0) {
            if (o[k] < 0 || o[k] > GRID)
                return 0;
            continue;
        }
        double t0 = (0 - o[k]) / d[k], t1 = (GRID - o[k]) / d[k];
        if (t0 > t1) {
            double s = t0;
            t0 = t1;
            t1 = s;
        }
        tn = fmax(tn, t0);
        tf = fmin(tf, t1);
    }
    return tf > tn ? tf - tn : 0;
}

/* Is the line inside a boundary plane of the box (then "inside" is the perturbation's choice)? */
static int on_box_plane(const double o[3], const double d[3])
{
    for (int k = 0; k < 3; k++)
        if (d[k] == 0 && (o[k] == 0 || o[k] == GRID))
            return 1;
    return 0;
}

typedef struct ray_case {
    double org[3], dir[3], tmin;
} ray_case;

/* March one ray on all layouts; check chain, single run, length; compare layouts. */
static const char *watertight_ray(tpk_marcher *const marchers[3], const fx_mesh *m, const ray_case *rc,
                                  recording *recs[3], unsigned char *seen)
{
    double world[3];
    for (int k = 0; k < 3; k++)
        world[k] = rc->org[k] + m->origin[k];
    for (int l = 0; l < 3; l++) {
        recs[l]->count = 0;
        tpk_march_stats st;
        if (tpk_march_ray(marchers[l], world, rc->dir, rc->tmin, INFINITY, record_segment, recs[l], &st) !=
            TPK_OK)
            return "march failed";
        if (st.shell_entries > 1)
            return "more than one run through a convex box";
        const char *e = check_chain(recs[l], m, seen, 1);
        if (e)
            return e;
    }
    for (int l = 1; l < 3; l++) {
        if (recs[l]->count != recs[0]->count ||
            memcmp(recs[l]->tet, recs[0]->tet, (size_t)recs[0]->count * sizeof(int32_t)) ||
            memcmp(recs[l]->t_in, recs[0]->t_in, (size_t)recs[0]->count * sizeof(double)))
            return "layouts disagree";
    }
    double dl = sqrt(rc->dir[0] * rc->dir[0] + rc->dir[1] * rc->dir[1] + rc->dir[2] * rc->dir[2]);
    double len = rec_length(recs[0]) * dl;
    double chord = box_chord(rc->org, rc->dir, rc->tmin) * dl;
    int ok = fabs(len - chord) <= 1e-9 * GRID;
    if (!ok && on_box_plane(rc->org, rc->dir))
        ok = len == 0;
    return ok ? NULL : "length inside differs from the chord";
}

static void run_watertight(const double shift[3], int relabel)
{
    fx_mesh m;
    CHECK(fx_grid(&m, GRID, GRID, GRID, NULL, 1.0, shift) == 0);
    if (relabel)
        CHECK(fx_relabel(&m, 77) == 0);
    CHECK(fx_build(&m) == 0);
    tpk_marcher *marchers[3];
    recording *recs[3];
    for (int l = 0; l < 3; l++) {
        marchers[l] = make_marcher(&m, layouts[l]);
        recs[l] = rec_new();
        CHECK(marchers[l] && recs[l]);
    }
    unsigned char *seen = calloc((size_t)m.tet_count, 1);
    int64_t rays = 0, entered = 0;
    /* Axis-aligned rays on a quarter lattice: through vertices, along edges, in face planes, through
     * face diagonals; from outside (both directions) and from inside (on a vertex plane and between). */
    for (int axis = 0; axis < 3; axis++)
        for (int sgn = -1; sgn <= 1; sgn += 2)
            for (int start = 0; start < 3; start++)
                for (int iu = -2; iu <= 4 * GRID + 2; iu++)
                    for (int iv = -2; iv <= 4 * GRID + 2; iv++) {
                        ray_case rc = {{0, 0, 0}, {0, 0, 0}, 0};
                        int u = (axis + 1) % 3, v = (axis + 2) % 3;
                        rc.org[u] = iu * 0.25;
                        rc.org[v] = iv * 0.25;
                        double along[3] = {-1.0, 3.0, 4.5};
                        rc.org[axis] = sgn > 0 ? along[start] : GRID - along[start];
                        rc.dir[axis] = sgn;
                        const char *e = watertight_ray(marchers, &m, &rc, recs, seen);
                        CHECK_MSG(!e, "%s: org (%g %g %g) dir (%g %g %g)", e, rc.org[0], rc.org[1], rc.org[2],
                                  rc.dir[0], rc.dir[1], rc.dir[2]);
                        rays++;
                        entered += recs[0]->count > 0;
                    }
    /* Oblique rays with integer directions aimed exactly at lattice points (vertices, edge midpoints,
     * face centres, cube centres), from outside and starting exactly at the point. */
    static const double dirs[][3] = {{1, 1, 0}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, -1, 0},
                                     {1, 1, -1}, {2, 1, 0}, {1, 2, 3}, {-1, -1, -1}, {0, -2, 1}};
    for (size_t di = 0; di < sizeof dirs / sizeof dirs[0]; di++)
        for (int i = 0; i <= 2 * GRID; i += 1)
            for (int j = 0; j <= 2 * GRID; j += 1)
                for (int k = 0; k <= 2 * GRID; k += 3)
                    for (int inside = 0; inside < 2; inside++) {
                        ray_case rc;
                        const double point[3] = {i * 0.5, j * 0.5, k * 0.5};
                        for (int a = 0; a < 3; a++) {
                            rc.dir[a] = dirs[di][a];
                            rc.org[a] = inside ? point[a] : point[a] - 20 * dirs[di][a];
                        }
                        rc.tmin = 0;
                        const char *e = watertight_ray(marchers, &m, &rc, recs, seen);
                        CHECK_MSG(!e, "%s: org (%g %g %g) dir (%g %g %g)", e, rc.org[0], rc.org[1], rc.org[2],
                                  rc.dir[0], rc.dir[1], rc.dir[2]);
                        rays++;
                        entered += recs[0]->count > 0;
                    }
    CHECK(rays > 20000 && entered > rays / 2);
    for (int l = 0; l < 3; l++) {
        tpk_marcher_destroy(marchers[l]);
        free(recs[l]);
    }
    free(seen);
    fx_free(&m);
}

TPK_TEST(watertight_grid)
{
    run_watertight(NULL, 0);
}

TPK_TEST(watertight_grid_relabeled_far_origin)
{
    const double shift[3] = {6.4e6, -4.9e6, 1234.5};
    run_watertight(shift, 1);
}

/* ---- Layout equivalence on random rays ---------------------------------------------------------- */

/* Random rays: one third from outside aimed exactly at vertices/edge midpoints (integer directions),
 * one third random lines (whole line, tmin = -inf), one third starting inside (tmin = 0). */
static void random_ray(uint64_t *rng, const fx_mesh *m, double span, double org[3], double dir[3],
                       double *tmin)
{
    int kind = (int)(fx_rand(rng) % 3);
    if (kind == 0) {
        for (int k = 0; k < 3; k++) {
            double target = (double)(fx_rand(rng) % (uint64_t)(2 * span + 1)) * 0.5;
            org[k] = (double)((int64_t)(fx_rand(rng) % (uint64_t)(span + 7)) - 3);
            dir[k] = target - org[k];
        }
        if (dir[0] == 0 && dir[1] == 0 && dir[2] == 0)
            dir[0] = 1;
        *tmin = 0;
    } else {
        for (int k = 0; k < 3; k++) {
            org[k] = kind == 1 ? fx_uniform(rng) * (span + 4) - 2 : fx_uniform(rng) * span;
            dir[k] = fx_uniform(rng) * 2 - 1;
        }
        *tmin = kind == 1 ? -INFINITY : 0;
    }
    for (int k = 0; k < 3; k++)
        org[k] += m->origin[k];
}

/* Print a failing ray and its pieces (with each tet's vertices and neighbors). */
static void dump_ray(const fx_mesh *m, const recording *r, const double org[3], const double dir[3],
                     double tmin, uint64_t runs)
{
    fprintf(stderr, "org %.17g %.17g %.17g dir %.17g %.17g %.17g tmin %g runs %llu\n", org[0], org[1], org[2],
            dir[0], dir[1], dir[2], tmin, (unsigned long long)runs);
    for (int64_t q = 0; q < r->count && q < 200; q++) {
        const int32_t *v = &m->tets[4 * (int64_t)r->tet[q]], *n = &m->neighbors[4 * (int64_t)r->tet[q]];
        fprintf(stderr, "  tet %d [%.17g, %.17g] v %d %d %d %d n %d %d %d %d\n", r->tet[q], r->t_in[q],
                r->t_out[q], v[0], v[1], v[2], v[3], n[0], n[1], n[2], n[3]);
    }
}

typedef void (*ray_generator)(uint64_t *rng, const fx_mesh *m, double org[3], double dir[3], double *tmin);

static void grid_ray(uint64_t *rng, const fx_mesh *m, double org[3], double dir[3], double *tmin)
{
    random_ray(rng, m, GRID, org, dir, tmin);
}

static uint64_t min_multi_run = 100; /* rays with several runs a non-convex mesh must show */

static void check_layouts_agree(fx_mesh *m, ray_generator gen, int64_t ray_count, uint64_t seed, int convex)
{
    tpk_marcher *marchers[3];
    recording *recs[3];
    for (int l = 0; l < 3; l++) {
        marchers[l] = make_marcher(m, layouts[l]);
        recs[l] = rec_new();
        CHECK(marchers[l] && recs[l]);
    }
    unsigned char *seen = calloc((size_t)m->tet_count, 1);
    uint64_t rng = seed, total_runs = 0, multi_run_rays = 0, pieces = 0;
    for (int64_t i = 0; i < ray_count; i++) {
        double org[3], dir[3], tmin;
        gen(&rng, m, org, dir, &tmin);
        for (int l = 0; l < 3; l++) {
            recs[l]->count = 0;
            tpk_march_stats st;
            tpk_result r = tpk_march_ray(marchers[l], org, dir, tmin, INFINITY, record_segment, recs[l], &st);
            CHECK_MSG(r == TPK_OK, "ray %lld layout %d: %s", (long long)i, (int)layouts[l], tpk_result_string(r));
            const char *e = check_chain(recs[l], m, seen, convex ? 1 : st.shell_entries);
            if (e)
                dump_ray(m, recs[l], org, dir, tmin, st.shell_entries);
            CHECK_MSG(!e, "ray %lld layout %d: %s", (long long)i, (int)layouts[l], e);
            if (l == 0) {
                total_runs += st.shell_entries;
                multi_run_rays += st.shell_entries > 1;
            }
        }
        pieces += (uint64_t)recs[0]->count;
        for (int l = 1; l < 3; l++) {
            CHECK_MSG(recs[l]->count == recs[0]->count &&
                          !memcmp(recs[l]->tet, recs[0]->tet, (size_t)recs[0]->count * sizeof(int32_t)) &&
                          !memcmp(recs[l]->t_out, recs[0]->t_out, (size_t)recs[0]->count * sizeof(double)),
                      "ray %lld: layout %d differs from Tet32", (long long)i, (int)layouts[l]);
        }
    }
    CHECK(pieces > (uint64_t)ray_count); /* the rays do go through the mesh */
    if (!convex && min_multi_run > 0)
        CHECK_MSG(multi_run_rays > min_multi_run, "only %llu rays with several runs", (unsigned long long)multi_run_rays);
    (void)total_runs;
    for (int l = 0; l < 3; l++) {
        tpk_marcher_destroy(marchers[l]);
        free(recs[l]);
    }
    free(seen);
}

TPK_TEST(layouts_agree_convex_relabeled)
{
    fx_mesh m;
    const double shift[3] = {-3.25, 100, 0.5};
    CHECK(fx_grid(&m, GRID, GRID, GRID, NULL, 1.0, shift) == 0);
    CHECK(fx_relabel(&m, 12345) == 0);
    CHECK(fx_build(&m) == 0);
    check_layouts_agree(&m, grid_ray, 100000, 1, 1);
    fx_free(&m);
}

TPK_TEST(layouts_agree_nonconvex)
{
    /* 30% of the cubes removed: holes, tunnels, pieces touching along edges and at corners. */
    unsigned char keep[GRID * GRID * GRID];
    uint64_t rng = 99;
    for (int i = 0; i < GRID * GRID * GRID; i++)
        keep[i] = fx_uniform(&rng) >= 0.3;
    for (int relabel = 0; relabel < 2; relabel++) {
        fx_mesh m;
        CHECK(fx_grid(&m, GRID, GRID, GRID, keep, 1.0, NULL) == 0);
        if (relabel)
            CHECK(fx_relabel(&m, 4242) == 0);
        CHECK(fx_build(&m) == 0);
        check_layouts_agree(&m, grid_ray, 100000, 7 + (uint64_t)relabel, 0);
        fx_free(&m);
    }
}

/* A U-shaped block: a ray across both arms has two runs with exact lengths. */
TPK_TEST(nonconvex_u_shape_runs)
{
    unsigned char keep[4 * 1 * 3];
    for (int k = 0; k < 3; k++)
        for (int i = 0; i < 4; i++)
            keep[i + 4 * k] = !(k >= 1 && (i == 1 || i == 2)); /* remove the middle of the upper two rows */
    fx_mesh m;
    CHECK(fx_grid(&m, 4, 1, 3, keep, 1.0, NULL) == 0);
    CHECK(fx_build(&m) == 0);
    for (int l = 0; l < 3; l++) {
        tpk_marcher *mr = make_marcher(&m, layouts[l]);
        recording *r = rec_new();
        CHECK(mr && r);
        const double org[3] = {-1, 0.5, 2.5}, dir[3] = {1, 0, 0};
        tpk_march_stats st;
        CHECK_EQ_INT(tpk_march_ray(mr, org, dir, 0, INFINITY, record_segment, r, &st), TPK_OK);
        CHECK_EQ_INT(st.shell_entries, 2);
        CHECK(fabs(rec_length(r) - 2.0) < 1e-12);
        CHECK(fabs(r->t_in[0] - 1.0) < 1e-12 && fabs(r->t_out[r->count - 1] - 5.0) < 1e-12);
        /* starting inside the second arm: one run, from tmin */
        r->count = 0;
        CHECK_EQ_INT(tpk_march_ray(mr, org, dir, 4.5, INFINITY, record_segment, r, &st), TPK_OK);
        CHECK_EQ_INT(st.shell_entries, 1);
        CHECK(r->t_in[0] == 4.5 && fabs(rec_length(r) - 0.5) < 1e-12);
        /* between the arms, tmax before the second: only the first arm's run is marched (it starts
         * before tmin), nothing is reported */
        r->count = 0;
        CHECK_EQ_INT(tpk_march_ray(mr, org, dir, 2.5, 3.5, record_segment, r, &st), TPK_OK);
        CHECK_EQ_INT(r->count, 0);
        CHECK_EQ_INT(st.shell_entries, 1);
        /* the ray along the bottom passes through one run */
        r->count = 0;
        const double org2[3] = {-1, 0.5, 0.5};
        CHECK_EQ_INT(tpk_march_ray(mr, org2, dir, 0, INFINITY, record_segment, r, &st), TPK_OK);
        CHECK_EQ_INT(st.shell_entries, 1);
        CHECK(fabs(rec_length(r) - 4.0) < 1e-12);
        free(r);
        tpk_marcher_destroy(mr);
    }
    fx_free(&m);
}

/* ---- Segments ------------------------------------------------------------------------------------ */

TPK_TEST(segments_linear_field_exact)
{
    fx_mesh m;
    const double shift[3] = {1000, -2000, 0.125};
    CHECK(fx_grid(&m, GRID, GRID, GRID, NULL, 0.75, shift) == 0);
    CHECK(fx_relabel(&m, 5) == 0);
    CHECK(fx_build(&m) == 0);
    const double coef[4] = {0.3, -0.7, 1.1, 2.0};
    m.scalars = malloc((size_t)m.vertex_count * sizeof(float));
    CHECK(m.scalars);
    double scale = 0;
    for (int64_t v = 0; v < m.vertex_count; v++) {
        const float *p = &m.positions[3 * v];
        /* the field at the float positions; values chosen exactly representable in float */
        double f = coef[0] * p[0] + coef[1] * p[1] + coef[2] * p[2] + coef[3];
        m.scalars[v] = (float)f;
        scale = fmax(scale, fabs(f));
    }
    tpk_marcher *mr = make_marcher(&m, TPK_LAYOUT_TET16);
    recording *r = rec_new();
    CHECK(mr && r);
    uint64_t rng = 3;
    int64_t checked = 0;
    for (int i = 0; i < 20000; i++) {
        double org[3], dir[3], tmin;
        random_ray(&rng, &m, GRID * 0.75, org, dir, &tmin);
        if (tmin < 0)
            tmin = -50;
        r->count = 0;
        double tmax = fx_uniform(&rng) < 0.5 ? INFINITY : tmin + fx_uniform(&rng) * 20;
        CHECK_EQ_INT(tpk_march_ray(mr, org, dir, tmin, tmax, record_segment, r, NULL), TPK_OK);
        for (int64_t s = 0; s < r->count; s++) {
            double f[2], tt[2] = {r->t_in[s], r->t_out[s]};
            for (int e = 0; e < 2; e++) {
                double x[3];
                for (int k = 0; k < 3; k++)
                    x[k] = (org[k] - shift[k]) + tt[e] * dir[k];
                f[e] = coef[0] * x[0] + coef[1] * x[1] + coef[2] * x[2] + coef[3];
            }
            /* float scalars: the field values are exact to float rounding of the vertex values */
            CHECK_MSG(fabs(r->s_in[s] - f[0]) <= 1e-6 * scale && fabs(r->s_out[s] - f[1]) <= 1e-6 * scale,
                      "ray %d piece %lld: %.17g vs %.17g", i, (long long)s, r->s_in[s], f[0]);
            CHECK(r->t_in[s] >= tmin && r->t_out[s] <= tmax);
            checked++;
        }
    }
    CHECK(checked > 10000);
    free(r);
    tpk_marcher_destroy(mr);
    fx_free(&m);
}

/* Each segment names its tet's four vertices, the first three being the face the ray came in through:
 * within a run that face is shared with the previous tet (the renderer's gradients and tet-field iso
 * normals rely on both). */
TPK_TEST(segments_carry_vertices)
{
    fx_mesh m;
    CHECK(fx_grid(&m, GRID, GRID, GRID, NULL, 1.0, NULL) == 0);
    CHECK(fx_relabel(&m, 9) == 0);
    CHECK(fx_build(&m) == 0);
    recording *r = rec_new();
    CHECK(r);
    uint64_t rng = 11;
    int64_t shared = 0;
    for (int layout = 0; layout < 3; layout++) {
        const tpk_layout lay = layout == 0 ? TPK_LAYOUT_TET16 : layout == 1 ? TPK_LAYOUT_TET20 : TPK_LAYOUT_TET32;
        tpk_marcher *mr = make_marcher(&m, lay);
        CHECK(mr);
        for (int i = 0; i < 500; i++) {
            double org[3], dir[3], tmin;
            random_ray(&rng, &m, GRID, org, dir, &tmin);
            r->count = 0;
            CHECK_EQ_INT(tpk_march_ray(mr, org, dir, -INFINITY, INFINITY, record_segment, r, NULL), TPK_OK);
            for (int64_t s = 0; s < r->count; s++) {
                CHECK_EQ_INT(shared_vertices(r->v[s], &m.tets[4 * r->tet[s]]), 4);
                if (s > 0 && r->t_in[s] == r->t_out[s - 1]) {
                    const int32_t face[4] = {r->v[s][0], r->v[s][1], r->v[s][2], -2};
                    CHECK_EQ_INT(shared_vertices(face, &m.tets[4 * r->tet[s - 1]]), 3);
                    shared++;
                }
            }
        }
        tpk_marcher_destroy(mr);
    }
    CHECK(shared > 5000);
    free(r);
    fx_free(&m);
}

/* With exactly representable vertex values (integers on integer points) the interpolation is exact to
 * double rounding: 1e-9 relative. */
TPK_TEST(segments_linear_field_1e9)
{
    fx_mesh m;
    CHECK(fx_grid(&m, GRID, GRID, GRID, NULL, 1.0, NULL) == 0);
    CHECK(fx_build(&m) == 0);
    m.scalars = malloc((size_t)m.vertex_count * sizeof(float));
    CHECK(m.scalars);
    for (int64_t v = 0; v < m.vertex_count; v++) {
        const float *p = &m.positions[3 * v];
        m.scalars[v] = 3 * p[0] - 5 * p[1] + 7 * p[2] + 11;
    }
    for (int l = 0; l < 3; l++) {
        tpk_marcher *mr = make_marcher(&m, layouts[l]);
        recording *r = rec_new();
        CHECK(mr && r);
        uint64_t rng = 11;
        for (int i = 0; i < 5000; i++) {
            double org[3], dir[3], tmin;
            random_ray(&rng, &m, GRID, org, dir, &tmin);
            r->count = 0;
            CHECK_EQ_INT(tpk_march_ray(mr, org, dir, tmin, INFINITY, record_segment, r, NULL), TPK_OK);
            for (int64_t s = 0; s < r->count; s++) {
                double tt[2] = {r->t_in[s], r->t_out[s]}, got[2] = {r->s_in[s], r->s_out[s]};
                for (int e = 0; e < 2; e++) {
                    double x[3];
                    for (int k = 0; k < 3; k++)
                        x[k] = org[k] + tt[e] * dir[k];
                    double f = 3 * x[0] - 5 * x[1] + 7 * x[2] + 11;
                    CHECK_MSG(fabs(got[e] - f) <= 1e-9 * fmax(1.0, fabs(f)) + 1e-9 * 100,
                              "%.17g vs %.17g", got[e], f);
                }
            }
        }
        free(r);
        tpk_marcher_destroy(mr);
    }
    fx_free(&m);
}

static int stop_after_first(void *user, const tpk_segment *s)
{
    (void)s;
    (*(int *)user)++;
    return 1;
}

TPK_TEST(clip_and_early_stop)
{
    fx_mesh m;
    CHECK(fx_grid(&m, GRID, GRID, GRID, NULL, 1.0, NULL) == 0);
    CHECK(fx_build(&m) == 0);
    tpk_marcher *mr = make_marcher(&m, TPK_LAYOUT_TET20);
    recording *r = rec_new();
    CHECK(mr && r);
    const double org[3] = {-1, 2.3, 4.6}, dir[3] = {1, 0, 0};
    tpk_march_stats full, clipped, stopped;
    CHECK_EQ_INT(tpk_march_ray(mr, org, dir, 0, INFINITY, record_segment, r, &full), TPK_OK);
    r->count = 0;
    CHECK_EQ_INT(tpk_march_ray(mr, org, dir, 3.5, 5.25, record_segment, r, &clipped), TPK_OK);
    CHECK(r->count > 0 && r->t_in[0] == 3.5 && r->t_out[r->count - 1] == 5.25);
    CHECK(fabs(rec_length(r) - 1.75) < 1e-12);
    CHECK(clipped.tet_steps < full.tet_steps); /* marched from the entry, stopped at tmax */
    int calls = 0;
    CHECK_EQ_INT(tpk_march_ray(mr, org, dir, 0, INFINITY, stop_after_first, &calls, &stopped), TPK_OK);
    CHECK_EQ_INT(calls, 1);
    CHECK_EQ_INT(stopped.tet_steps, 1);
    CHECK_EQ_INT(tpk_march_ray(mr, org, dir, 0, INFINITY, NULL, NULL, &stopped), TPK_OK);
    CHECK_EQ_INT(stopped.tet_steps, full.tet_steps);
    free(r);
    tpk_marcher_destroy(mr);
    fx_free(&m);
}

/* ---- Hostile records ----------------------------------------------------------------------------- */

TPK_TEST(hostile_tet16_garbage)
{
    fx_mesh m;
    CHECK(fx_grid(&m, 4, 4, 4, NULL, 1.0, NULL) == 0);
    CHECK(fx_build(&m) == 0);
    const double org[3] = {-1, 1.3, 2.2}, dir[3] = {1, 0.1, 0.05};
    /* decoded ids far out of range */
    for (int64_t t = 0; t < m.tet_count; t++)
        for (int r = 0; r < 3; r++)
            m.tet16[t].nx[r] = 0x3fffffff;
    tpk_marcher *mr = make_marcher(&m, TPK_LAYOUT_TET16);
    CHECK(mr);
    CHECK_EQ_INT(tpk_march_ray(mr, org, dir, 0, INFINITY, NULL, NULL, NULL), TPK_ERR_MESH);
    tpk_marcher_destroy(mr);
    /* random garbage in every field of every layout: must end (OK or ERR_MESH), never crash or hang */
    uint64_t rng = 8;
    int64_t mesh_errors = 0;
    for (int round = 0; round < 50; round++) {
        for (int64_t t = 0; t < m.tet_count; t++) {
            uint64_t x = fx_rand(&rng);
            int32_t small = (int32_t)(x % (uint64_t)(m.tet_count + 2)) - 1;
            int32_t junk = round % 2 ? small : (int32_t)(x >> 32);
            m.tet16[t].nx[x % 3] = junk;
            m.tet20[t].n[(x >> 8) % 4] = junk;
            m.tet32[t].n[(x >> 16) % 4] = junk;
            if (round % 5 == 4)
                m.tet16[t].vx = m.tet20[t].vx = m.tet32[t].vx = (int32_t)(x >> 40);
        }
        for (int l = 0; l < 3; l++) {
            mr = make_marcher(&m, layouts[l]);
            CHECK(mr);
            for (int i = 0; i < 200; i++) {
                double o[3], d[3], tmin;
                random_ray(&rng, &m, 4, o, d, &tmin);
                tpk_result r = tpk_march_ray(mr, o, d, tmin, INFINITY, NULL, NULL, NULL);
                CHECK(r == TPK_OK || r == TPK_ERR_MESH);
                mesh_errors += r == TPK_ERR_MESH;
            }
            tpk_marcher_destroy(mr);
        }
    }
    CHECK(mesh_errors > 100);
    fx_free(&m);
}

TPK_TEST(hostile_positions)
{
    fx_mesh m;
    CHECK(fx_grid(&m, 4, 4, 4, NULL, 1.0, NULL) == 0);
    CHECK(fx_build(&m) == 0);
    uint64_t rng = 31;
    for (int i = 0; i < 40; i++) {
        int64_t v = (int64_t)(fx_rand(&rng) % (uint64_t)m.vertex_count);
        m.positions[3 * v + i % 3] = i % 4 == 0 ? NAN : i % 4 == 1 ? INFINITY : i % 4 == 2 ? -1e38f : 1e-40f;
    }
    for (int l = 0; l < 3; l++) {
        tpk_marcher *mr = make_marcher(&m, layouts[l]);
        CHECK(mr);
        for (int i = 0; i < 2000; i++) {
            double o[3], d[3], tmin;
            random_ray(&rng, &m, 4, o, d, &tmin);
            tpk_result r = tpk_march_ray(mr, o, d, tmin, INFINITY, NULL, NULL, NULL);
            CHECK(r == TPK_OK || r == TPK_ERR_MESH);
        }
        tpk_marcher_destroy(mr);
    }
    fx_free(&m);
}

TPK_TEST(hostile_cycle_detected)
{
    /* Two tets glued on a face whose records point at each other across every face: a ray bounces
     * between them until the step limit catches the cycle. */
    fx_mesh m;
    CHECK(fx_grid(&m, 1, 1, 1, NULL, 1.0, NULL) == 0);
    CHECK(fx_build(&m) == 0);
    for (int64_t t = 0; t < m.tet_count; t++)
        for (int k = 0; k < 4; k++) {
            m.tet32[t].n[k] = (int32_t)t;
            m.tet20[t].n[k] = (int32_t)t;
        }
    for (int l = 0; l < 2; l++) {
        tpk_marcher *mr = make_marcher(&m, layouts[l]);
        CHECK(mr);
        const double org[3] = {-1, 0.3, 0.6}, dir[3] = {1, 0.01, 0.02};
        CHECK_EQ_INT(tpk_march_ray(mr, org, dir, 0, INFINITY, NULL, NULL, NULL), TPK_ERR_MESH);
        tpk_marcher_destroy(mr);
    }
    fx_free(&m);
}

TPK_TEST(hostile_shell_records)
{
    fx_mesh m;
    CHECK(fx_grid(&m, 2, 2, 2, NULL, 1.0, NULL) == 0);
    CHECK(fx_build(&m) == 0);
    tpk_mesh_arrays a = fx_arrays(&m, TPK_LAYOUT_TET16);
    tpk_marcher *mr = NULL;
    m.shell[3].t = (int32_t)m.tet_count;
    CHECK_EQ_INT(tpk_marcher_create(&mr, &a), TPK_ERR_MESH);
    CHECK(mr == NULL);
    m.shell[3].t = 0;
    m.shell[5].b = -7;
    CHECK_EQ_INT(tpk_marcher_create(&mr, &a), TPK_ERR_MESH);
    m.shell[5].b = m.shell[5].a;
    CHECK_EQ_INT(tpk_marcher_create(&mr, &a), TPK_ERR_MESH);
    a.tet16 = NULL;
    CHECK_EQ_INT(tpk_marcher_create(&mr, &a), TPK_ERR_INVALID_ARGUMENT);
    CHECK_EQ_INT(tpk_marcher_create(&mr, NULL), TPK_ERR_INVALID_ARGUMENT);
    tpk_marcher_destroy(NULL);
    fx_free(&m);
}

/* ---- Real meshes --------------------------------------------------------------------------------- */

/* Import, tetrahedralize, orient, then layouts and shell as the converter does. */
/* A real mesh, tetrahedralized and oriented as the converter does; reorder: in the file's order (Hilbert,
 * tpk_reorder), else the source's. */
static int load_real_in(const char *relative, fx_mesh *m, int reorder)
{
    memset(m, 0, sizeof *m);
    tpk_mesh src;
    tpk_tetmesh tm;
    memset(&src, 0, sizeof src);
    memset(&tm, 0, sizeof tm);
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    tpk_orient_stats ost;
    if (tpk_import_any(tpk_data_path(relative), NULL, &src, &diag) != 0 ||
        tpk_tetrahedralize(&src, NULL, 0, 0, &tm, &diag) != 0 || (reorder && tpk_reorder(&tm, 0, &diag) != 0) ||
        tpk_orient(&tm, 0, 0, &ost, &diag) != 0) {
        fprintf(stderr, "%s: %s\n", relative, diag.message);
        tpk_mesh_free(&src);
        tpk_tetmesh_free(&tm);
        return -1;
    }
    m->vertex_count = tm.vertex_count;
    m->tet_count = tm.tet_count;
    m->points = malloc((size_t)m->vertex_count * 3 * sizeof(double));
    m->positions = malloc((size_t)m->vertex_count * 3 * sizeof(float));
    m->tets = malloc((size_t)m->tet_count * 4 * sizeof(int32_t));
    if (!m->points || !m->positions || !m->tets)
        return -1;
    for (int k = 0; k < 3; k++)
        m->origin[k] = tm.vertex_count ? tm.points[k] : 0;
    for (int64_t i = 0; i < 3 * m->vertex_count; i++) {
        m->positions[i] = (float)(tm.points[i] - m->origin[i % 3]);
        m->points[i] = m->origin[i % 3] + (double)m->positions[i];
    }
    memcpy(m->tets, tm.tets, (size_t)m->tet_count * 4 * sizeof(int32_t));
    tpk_mesh_free(&src);
    tpk_tetmesh_free(&tm);
    return fx_build(m);
}

static int load_real(const char *relative, fx_mesh *m)
{
    return load_real_in(relative, m, 0);
}

/* Rays for an arbitrary mesh: random lines through its box, rays from inside (tet centroids), rays
 * aimed through vertices, and axis-parallel rays through vertices exactly. */
static void real_ray(uint64_t *rng, const fx_mesh *m, double org[3], double dir[3], double *tmin)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int64_t v = 0; v < m->vertex_count; v += 1 + m->vertex_count / 64)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], m->points[3 * v + k]);
            hi[k] = fmax(hi[k], m->points[3 * v + k]);
        }
    int kind = (int)(fx_rand(rng) % 4);
    const double *vp = &m->points[3 * (int64_t)(fx_rand(rng) % (uint64_t)m->vertex_count)];
    for (int k = 0; k < 3; k++)
        dir[k] = fx_uniform(rng) * 2 - 1;
    *tmin = 0;
    if (kind == 0) {
        for (int k = 0; k < 3; k++)
            org[k] = lo[k] + (hi[k] - lo[k]) * (fx_uniform(rng) * 1.4 - 0.2);
        *tmin = -INFINITY;
    } else if (kind == 1) {
        const int32_t *t = &m->tets[4 * (int64_t)(fx_rand(rng) % (uint64_t)m->tet_count)];
        for (int k = 0; k < 3; k++)
            org[k] = 0.25 * (m->points[3 * t[0] + k] + m->points[3 * t[1] + k] + m->points[3 * t[2] + k] +
                             m->points[3 * t[3] + k]);
    } else if (kind == 2) {
        for (int k = 0; k < 3; k++) {
            org[k] = vp[k] - dir[k] * (hi[k] - lo[k]);
        }
    } else {
        int axis = (int)(fx_rand(rng) % 3);
        for (int k = 0; k < 3; k++) {
            org[k] = vp[k];
            dir[k] = k == axis ? 1.0 : 0.0;
        }
        org[axis] = lo[axis] - 1.0;
    }
}

static void real_mesh_layouts(const char *relative, int64_t rays, int nonconvex)
{
    fx_mesh m;
    if (load_real(relative, &m) != 0) {
        CHECK_MSG(0, "cannot load %s", relative);
    }
    CHECK(m.tet_count > 1000 && m.shell_count > 100);
    min_multi_run = nonconvex ? 100 : 0;
    check_layouts_agree(&m, real_ray, rays, 2024, 0);
    min_multi_run = 100;
    fx_free(&m);
}

TPK_TEST(layouts_agree_hinge_small)
{
    real_mesh_layouts("tetgen/hinge_small.node", 100000, 1);
}

TPK_TEST(layouts_agree_cylinder)
{
    real_mesh_layouts("sfepy/cylinder.vtk", 100000, 0);
}

/* ---- Range culling for iso rays (libtetpack/range_bvh.c) ----------------------------------------- */

typedef struct crossing_filter {
    recording *rec;
    const double *values;
    int count;
} crossing_filter;

/* The marcher's pieces that cross a value by the renderers' rule, recorded. */
static int record_crossing(void *user, const tpk_segment *s)
{
    crossing_filter *f = user;
    for (int j = 0; j < f->count; j++) {
        double v = f->values[j];
        if ((s->scalar_in < v && v <= s->scalar_out) || (s->scalar_in > v && v >= s->scalar_out))
            return record_segment(f->rec, s);
    }
    return 0;
}

static void swap_pieces(recording *r, int64_t a, int64_t b)
{
#define SWAP(field)                                                                                         \
    do {                                                                                                    \
        __typeof__(r->field[0]) tmp_;                                                                       \
        memcpy(&tmp_, &r->field[a], sizeof tmp_);                                                           \
        memcpy(&r->field[a], &r->field[b], sizeof tmp_);                                                    \
        memcpy(&r->field[b], &tmp_, sizeof tmp_);                                                           \
    } while (0)
    SWAP(tet);
    SWAP(t_in);
    SWAP(t_out);
    SWAP(s_in);
    SWAP(s_out);
    SWAP(v);
#undef SWAP
}

/* Runs of pieces whose t_in are within an ulp or two, sorted by tet (insertion sort: runs are short). */
static void sort_equal_t_runs(recording *r)
{
    for (int64_t i = 1; i < r->count; i++)
        for (int64_t k = i; k > 0 && fabs(r->t_in[k] - r->t_in[k - 1]) <= 4 * DBL_EPSILON * (fabs(r->t_in[k]) + 1) &&
                            r->tet[k] < r->tet[k - 1];
             k--)
            swap_pieces(r, k, k - 1);
}

/* Every piece tpk_march_ray_values reports equals, bit for bit and in order, a crossing piece of
 * tpk_march_ray, and none is missing: on each layout, for `rays` rays of `gen`. Scalars `field`. */
static void check_culling_agrees(fx_mesh *m, ray_generator gen, int64_t rays, const double *values, int count)
{
    static recording marched, culled;
    for (int run = 0; run < 6; run++) {
        int l = run / 2, sel = run % 2; /* each layout with the file-order tree, then the selected one */
        tpk_marcher *marcher = make_marcher(m, layouts[l]);
        CHECK(marcher != NULL);
        tpk_range_bvh *bvh = NULL;
        CHECK(tpk_range_bvh_create(&bvh, marcher) == TPK_OK);
        if (sel)
            CHECK(tpk_range_bvh_select(bvh, values, count) == TPK_OK);
        uint64_t rng = 77 + (uint64_t)l;
        int64_t pieces = 0, rays_with = 0, clamped = 0;
        for (int64_t i = 0; i < rays; i++) {
            double org[3], dir[3], tmin;
            gen(&rng, m, org, dir, &tmin);
            double tmax = (i % 5 == 0) ? 0.5 * (fabs(org[0]) + 1.0) : INFINITY; /* some rays end inside */
            marched.count = culled.count = 0;
            crossing_filter f = {&marched, values, count};
            tpk_march_stats st;
            CHECK(tpk_march_ray(marcher, org, dir, tmin, tmax, record_crossing, &f, NULL) == TPK_OK);
            CHECK(tpk_march_ray_values(bvh, org, dir, tmin, tmax, values, count, record_segment, &culled, &st) ==
                  TPK_OK);
            CHECK_MSG(marched.count == culled.count, "layout %d%s ray %lld: %lld crossing pieces marched, %lld culled",
                      l, sel ? " (selected tree)" : "", (long long)i, (long long)marched.count, (long long)culled.count);
            /* pieces of one t (a ray through a vertex or an edge, where several tets have a piece of
             * length 0 or an ulp) come in the order of the marcher's path or of the tet numbers: sort
             * such runs of both by tet */
            sort_equal_t_runs(&marched);
            sort_equal_t_runs(&culled);
            for (int64_t k = 0; k < marched.count; k++) {
                /* t: equal but where the marcher clamped an exit that rounding put before its entry (then
                 * the tets after it carry that t: a few ulps, at a point where the ray meets a vertex or an
                 * edge, or in a sliver) */
                double tol = 8 * DBL_EPSILON * (fabs(marched.t_in[k]) + fabs(marched.t_out[k]) + 1.0);
                int t_exact = marched.t_in[k] == culled.t_in[k] && marched.t_out[k] == culled.t_out[k];
                clamped += !t_exact;
                CHECK_MSG(marched.tet[k] == culled.tet[k] && fabs(marched.t_in[k] - culled.t_in[k]) <= tol &&
                              fabs(marched.t_out[k] - culled.t_out[k]) <= tol && marched.s_in[k] == culled.s_in[k] &&
                              marched.s_out[k] == culled.s_out[k] &&
                              !memcmp(marched.v[k], culled.v[k], sizeof marched.v[k]),
                          "layout %d ray %lld piece %lld: tet %d [%.17g, %.17g] s %.17g..%.17g marched, tet %d "
                          "[%.17g, %.17g] s %.17g..%.17g culled", l, (long long)i, (long long)k, marched.tet[k],
                          marched.t_in[k], marched.t_out[k], marched.s_in[k], marched.s_out[k], culled.tet[k],
                          culled.t_in[k], culled.t_out[k], culled.s_in[k], culled.s_out[k]);
            }
            pieces += marched.count;
            rays_with += marched.count > 0;
        }
        CHECK_MSG(rays_with > rays / 10 && pieces > rays / 10, "layout %d: only %lld of %lld rays met a value", l,
                  (long long)rays_with, (long long)rays);
        /* the clamped ones are rare: these rays aim at vertices and run along axes through them on purpose */
        CHECK_MSG(clamped * 20 < pieces, "layout %d: %lld of %lld pieces differ in t", l, (long long)clamped,
                  (long long)pieces);
        if (getenv("TPK_TEST_VERBOSE"))
            fprintf(stderr, "layout %d: %lld pieces, %lld with t a few ulps off\n", l, (long long)pieces,
                    (long long)clamped);
        tpk_range_bvh_destroy(bvh);
        tpk_marcher_destroy(marcher);
    }
}

/* scalar = a smooth wave, or (exact) floor of 2x: a value then lies exactly on whole faces and vertices. */
static void set_field(fx_mesh *m, int exact)
{
    free(m->scalars);
    m->scalars = malloc((size_t)m->vertex_count * sizeof(float));
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int64_t v = 0; v < m->vertex_count; v++)
        for (int k = 0; k < 3; k++)
            lo[k] = fmin(lo[k], m->points[3 * v + k]), hi[k] = fmax(hi[k], m->points[3 * v + k]);
    for (int64_t v = 0; v < m->vertex_count; v++) {
        double u[3];
        for (int k = 0; k < 3; k++)
            u[k] = (m->points[3 * v + k] - lo[k]) / (hi[k] - lo[k] > 0 ? hi[k] - lo[k] : 1);
        m->scalars[v] = exact ? (float)floor(4 * u[0]) : (float)(sin(7 * u[0]) * cos(5 * u[1]) + 0.3 * u[2]);
    }
}

TPK_TEST(culled_iso_pieces_equal_marched)
{
    static const double smooth[] = {0.3, -0.45}, exact[] = {1.0, 2.0};
    const char *meshes[] = {"sfepy/cylinder.vtk", "tetgen/hinge_small.node"};
    for (int i = 0; i < 2; i++) {
        fx_mesh m;
        CHECK_MSG(load_real(meshes[i], &m) == 0, "cannot load %s", meshes[i]);
        set_field(&m, 0);
        check_culling_agrees(&m, real_ray, 4000, smooth, 2);
        set_field(&m, 1);
        check_culling_agrees(&m, real_ray, 4000, exact, 2);
        fx_free(&m);
    }
}

TPK_TEST(culled_iso_refuses_and_stops)
{
    fx_mesh m;
    CHECK(fx_render_grid(&m, 0) == 0);
    tpk_marcher *marcher = make_marcher(&m, TPK_LAYOUT_TET16);
    tpk_range_bvh *bvh = (tpk_range_bvh *)1;
    CHECK(tpk_range_bvh_create(&bvh, marcher) == TPK_ERR_INVALID_ARGUMENT && bvh == NULL); /* no scalars */
    tpk_marcher_destroy(marcher);
    fx_free(&m);
    CHECK(fx_render_grid(&m, 1) == 0); /* scalar = x, 0..8 */
    marcher = make_marcher(&m, TPK_LAYOUT_TET16);
    CHECK(tpk_range_bvh_create(&bvh, marcher) == TPK_OK);
    const double values[] = {2.5, 5.5};
    const double org[3] = {-1, 3.3, 4.1}, dir[3] = {1, 0.01, 0.02};
    static recording rec;
    rec.count = 0;
    CHECK(tpk_march_ray_values(bvh, org, dir, 0, INFINITY, values, 2, record_segment, &rec, NULL) == TPK_OK);
    CHECK_MSG(rec.count == 2 && rec.t_in[0] < rec.t_in[1], "%lld pieces", (long long)rec.count);
    int seen = 0;
    CHECK(tpk_march_ray_values(bvh, org, dir, 0, INFINITY, values, 2, stop_after_first, &seen, NULL) == TPK_OK);
    CHECK(seen == 1);
    CHECK(tpk_range_bvh_active(bvh, values, 2) > 0 && tpk_range_bvh_active(bvh, values, 2) < 1);
    CHECK(tpk_range_bvh_active(bvh, (const double[]){100.0}, 1) == 0.0);
    CHECK(tpk_march_ray_values(bvh, org, (const double[3]){0, 0, 0}, 0, 1, values, 2, record_segment, &rec, NULL) ==
          TPK_ERR_INVALID_ARGUMENT);
    /* the selected tree: the same pieces and stop; other values walk the file-order tree; none held */
    CHECK(tpk_range_bvh_select(NULL, values, 2) == TPK_ERR_INVALID_ARGUMENT);
    CHECK(tpk_range_bvh_select(bvh, NULL, 2) == TPK_ERR_INVALID_ARGUMENT);
    CHECK(tpk_range_bvh_select(bvh, values, 2) == TPK_OK);
    static recording sel;
    sel.count = 0;
    CHECK(tpk_march_ray_values(bvh, org, dir, 0, INFINITY, values, 2, record_segment, &sel, NULL) == TPK_OK);
    CHECK(sel.count == 2 && sel.tet[0] == rec.tet[0] && sel.tet[1] == rec.tet[1] && sel.t_in[0] == rec.t_in[0] &&
          sel.t_in[1] == rec.t_in[1]);
    seen = 0;
    CHECK(tpk_march_ray_values(bvh, org, dir, 0, INFINITY, values, 2, stop_after_first, &seen, NULL) == TPK_OK);
    CHECK(seen == 1);
    sel.count = 0;
    CHECK(tpk_march_ray_values(bvh, org, dir, 0, INFINITY, values + 1, 1, record_segment, &sel, NULL) == TPK_OK);
    CHECK(sel.count == 1 && sel.tet[0] == rec.tet[1]);
    CHECK(tpk_range_bvh_select(bvh, (const double[]){100.0}, 1) == TPK_OK);
    sel.count = 0;
    CHECK(tpk_march_ray_values(bvh, org, dir, 0, INFINITY, (const double[]){100.0}, 1, record_segment, &sel, NULL) ==
          TPK_OK);
    CHECK(sel.count == 0);
    CHECK(tpk_range_bvh_select(bvh, NULL, 0) == TPK_OK); /* drops it */
    tpk_range_bvh_destroy(bvh);
    tpk_marcher_destroy(marcher);
    fx_free(&m);
}

/* ---- Packets of iso rays ------------------------------------------------------------------------ */

#define LOG_MAX 256

/* A ray's pieces, bit for bit, for a ray that stops after stop_after of them (0: never). */
typedef struct piece_log {
    int64_t count;
    int stop_after, overflow;
    tpk_segment seg[LOG_MAX];
} piece_log;

static int log_piece(void *user, const tpk_segment *s)
{
    piece_log *l = user;
    if (l->count == LOG_MAX) {
        l->overflow = 1;
        return 1;
    }
    l->seg[l->count++] = *s;
    return l->stop_after > 0 && l->count >= l->stop_after;
}

static piece_log alone_log_for_refusals;

static int same_pieces(const piece_log *a, const piece_log *b)
{
    if (a->count != b->count || a->overflow || b->overflow)
        return 0;
    for (int64_t k = 0; k < a->count; k++) {
        const tpk_segment *x = &a->seg[k], *y = &b->seg[k];
        if (x->tet != y->tet || memcmp(&x->t_in, &y->t_in, sizeof x->t_in) ||
            memcmp(&x->t_out, &y->t_out, sizeof x->t_out) || memcmp(&x->scalar_in, &y->scalar_in, sizeof x->scalar_in) ||
            memcmp(&x->scalar_out, &y->scalar_out, sizeof x->scalar_out) || memcmp(x->v, y->v, sizeof x->v))
            return 0;
    }
    return 1;
}

/* Packets of rays from one origin (a camera outside the mesh or a point inside it), around a random
 * direction, close together (pixels apart) or far apart: each ray of tpk_march_packet_values must hand
 * on exactly what tpk_march_ray_values hands on for it alone, with stops, tmin and tmax per ray. */
static void check_packets_agree(fx_mesh *m, const double *values, int count, int64_t packets)
{
    static piece_log alone[TPK_MARCH_PACKET], packed[TPK_MARCH_PACKET];
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int64_t v = 0; v < m->vertex_count; v++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], m->points[3 * v + k]);
            hi[k] = fmax(hi[k], m->points[3 * v + k]);
        }
    for (int l = 0; l < 3; l += 2) {
        tpk_marcher *marcher = make_marcher(m, layouts[l]);
        tpk_range_bvh *bvh = NULL;
        CHECK(marcher && tpk_range_bvh_create(&bvh, marcher) == TPK_OK);
        CHECK(tpk_range_bvh_select(bvh, values, count) == TPK_OK);
        uint64_t rng = 991 + (uint64_t)l, steps_alone = 0, steps_packed = 0;
        int64_t rays = 0, rays_with = 0, stopped = 0;
        for (int64_t pk = 0; pk < packets; pk++) {
            double org[3], center[3], u[3], w[3], dirs[TPK_MARCH_PACKET][3], tmin[TPK_MARCH_PACKET],
                tmax[TPK_MARCH_PACKET];
            const int32_t *t = &m->tets[4 * (int64_t)(fx_rand(&rng) % (uint64_t)m->tet_count)];
            double aim[3];
            for (int k = 0; k < 3; k++)
                aim[k] = 0.25 * (m->points[3 * t[0] + k] + m->points[3 * t[1] + k] + m->points[3 * t[2] + k] +
                                 m->points[3 * t[3] + k]);
            int inside = fx_rand(&rng) % 4 == 0;
            for (int k = 0; k < 3; k++) {
                double e = hi[k] - lo[k];
                org[k] = inside ? aim[k] : lo[k] + e * (fx_uniform(&rng) * 3 - 1);
                center[k] = inside ? fx_uniform(&rng) * 2 - 1 : aim[k] - org[k];
                u[k] = fx_uniform(&rng) * 2 - 1;
            }
            /* w = center x u, u = w x center: the packet's two across-directions */
            w[0] = center[1] * u[2] - center[2] * u[1], w[1] = center[2] * u[0] - center[0] * u[2];
            w[2] = center[0] * u[1] - center[1] * u[0];
            u[0] = w[1] * center[2] - w[2] * center[1], u[1] = w[2] * center[0] - w[0] * center[2];
            u[2] = w[0] * center[1] - w[1] * center[0];
            double cl = sqrt(center[0] * center[0] + center[1] * center[1] + center[2] * center[2]);
            double ul = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]), wl = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
            double spread = pk % 3 == 0 ? 0.2 : pk % 3 == 1 ? 2e-3 : 1e-5;
            int n = 1 + (int)(fx_rand(&rng) % TPK_MARCH_PACKET), side = pk % 2 ? 4 : 2;
            tpk_segment_fn fns[TPK_MARCH_PACKET];
            void *users[TPK_MARCH_PACKET];
            tpk_march_stats st[TPK_MARCH_PACKET];
            for (int i = 0; i < n; i++) {
                double a = spread * ((i % side) - 0.5 * (side - 1)), c = spread * ((i / side) - 0.5 * (side - 1));
                for (int k = 0; k < 3; k++)
                    dirs[i][k] = center[k] / cl + a * u[k] / ul + c * w[k] / wl;
                if (i == 0 && pk % 4 == 3 && !inside) /* exactly through a corner of the aimed-at tet */
                    for (int k = 0; k < 3; k++)
                        dirs[i][k] = m->points[3 * t[pk % 16 / 4] + k] - org[k];
                uint64_t z = fx_rand(&rng);
                tmin[i] = z % 7 == 0 ? -INFINITY : z % 7 == 1 ? 0.3 * cl : 0.0;
                tmax[i] = z % 5 == 0 ? 0.8 * cl : INFINITY;
                alone[i].count = packed[i].count = 0;
                alone[i].overflow = packed[i].overflow = 0;
                alone[i].stop_after = packed[i].stop_after = (int)(fx_rand(&rng) % 3);
                fns[i] = log_piece;
                users[i] = &packed[i];
                CHECK(tpk_march_ray_values(bvh, org, dirs[i], tmin[i], tmax[i], values, count, log_piece, &alone[i],
                                           &st[i]) == TPK_OK);
                steps_alone += st[i].tet_steps;
            }
            CHECK(tpk_march_packet_values(bvh, org, n, (const double(*)[3])dirs, tmin, tmax, values, count, fns,
                                          users, st) == TPK_OK);
            for (int i = 0; i < n; i++) {
                steps_packed += st[i].tet_steps;
                CHECK_MSG(same_pieces(&alone[i], &packed[i]),
                          "layout %d packet %lld ray %d of %d (spread %g): %lld pieces alone, %lld in the packet", l,
                          (long long)pk, i, n, spread, (long long)alone[i].count, (long long)packed[i].count);
                rays_with += alone[i].count > 0;
                stopped += alone[i].stop_after > 0 && alone[i].count == alone[i].stop_after;
            }
            rays += n;
        }
        CHECK_MSG(rays_with > rays / 5 && stopped > rays / 20, "layout %d: %lld of %lld rays met a value, %lld stopped",
                  l, (long long)rays_with, (long long)rays, (long long)stopped);
        /* the packets did walk together: fewer tets tested exactly */
        CHECK_MSG(steps_packed < steps_alone, "layout %d: %llu tets tested in packets, %llu alone", l,
                  (unsigned long long)steps_packed, (unsigned long long)steps_alone);
        tpk_range_bvh_destroy(bvh);
        tpk_marcher_destroy(marcher);
    }
}

TPK_TEST(culled_iso_packets_equal_single_rays)
{
    static const double smooth[] = {0.3, -0.45}, exact[] = {1.0, 2.0}, near_one[] = {1.0 + 0x1p-24};
    const char *meshes[] = {"sfepy/cylinder.vtk", "tetgen/hinge_small.node"};
    for (int i = 0; i < 2; i++) {
        fx_mesh m;
        CHECK_MSG(load_real(meshes[i], &m) == 0, "cannot load %s", meshes[i]);
        set_field(&m, 0);
        check_packets_agree(&m, smooth, 2, 1500);
        set_field(&m, 1);
        check_packets_agree(&m, exact, 2, 1500);
        /* scalars a few ulps around the value: the float tests must not decide what rounding decides */
        uint64_t rng = 5;
        for (int64_t v = 0; v < m.vertex_count; v++)
            m.scalars[v] = nextafterf(1.0f, (float)(fx_rand(&rng) % 2 ? INFINITY : -INFINITY)) + 0x1p-23f * (float)(fx_rand(&rng) % 3);
        check_packets_agree(&m, near_one, 1, 1500);
        fx_free(&m);
    }
    /* refusals: no arrays, too many rays; 0 rays is nothing to do */
    fx_mesh m;
    CHECK(fx_render_grid(&m, 1) == 0);
    tpk_marcher *marcher = make_marcher(&m, TPK_LAYOUT_TET16);
    tpk_range_bvh *bvh = NULL;
    CHECK(tpk_range_bvh_create(&bvh, marcher) == TPK_OK);
    const double org[3] = {-1, 3.3, 4.1}, dirs[1][3] = {{1, 0.01, 0.02}}, tmin[1] = {0}, tmax[1] = {INFINITY};
    const double values[] = {2.5};
    tpk_segment_fn fns[1] = {log_piece};
    void *users[1] = {&alone_log_for_refusals};
    CHECK(tpk_march_packet_values(bvh, org, 1, NULL, tmin, tmax, values, 1, fns, users, NULL) == TPK_ERR_INVALID_ARGUMENT);
    CHECK(tpk_march_packet_values(bvh, org, TPK_MARCH_PACKET + 1, dirs, tmin, tmax, values, 1, fns, users, NULL) ==
          TPK_ERR_INVALID_ARGUMENT);
    CHECK(tpk_march_packet_values(bvh, org, 0, dirs, tmin, tmax, values, 1, fns, users, NULL) == TPK_OK);
    alone_log_for_refusals.count = 0;
    CHECK(tpk_march_packet_values(bvh, org, 1, dirs, tmin, tmax, values, 1, fns, users, NULL) == TPK_OK); /* file-order tree */
    CHECK(alone_log_for_refusals.count == 1);
    tpk_range_bvh_destroy(bvh);
    tpk_marcher_destroy(marcher);
    fx_free(&m);
}

/* A 4x4 packet whose directions' y changes sign between its second and third rows (a camera's pixels
 * along the line where that happens) cannot walk as one; its halves, rows 0-1 and 2-3, can: each ray
 * hands on what it does alone, and the packet tests fewer tets exactly than its rays alone (one by one,
 * it would test as many). */
TPK_TEST(culled_iso_packet_splits_at_a_sign_change)
{
    static piece_log alone[TPK_MARCH_PACKET], packed[TPK_MARCH_PACKET];
    static const double values[] = {0.3, -0.45};
    fx_mesh m;
    CHECK_MSG(load_real("sfepy/cylinder.vtk", &m) == 0, "cannot load sfepy/cylinder.vtk");
    set_field(&m, 0);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int64_t v = 0; v < m.vertex_count; v++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], m.points[3 * v + k]);
            hi[k] = fmax(hi[k], m.points[3 * v + k]);
        }
    tpk_marcher *marcher = make_marcher(&m, TPK_LAYOUT_TET16);
    tpk_range_bvh *bvh = NULL;
    CHECK(marcher && tpk_range_bvh_create(&bvh, marcher) == TPK_OK);
    CHECK(tpk_range_bvh_select(bvh, values, 2) == TPK_OK);
    uint64_t steps_alone = 0, steps_packed = 0;
    int64_t pieces = 0;
    /* eyes on the plane y = centre, looking along +x through the mesh at several heights */
    for (int e = 0; e < 8; e++) {
        const double org[3] = {lo[0] - (hi[0] - lo[0]), 0.5 * (lo[1] + hi[1]), lo[2] + (hi[2] - lo[2]) * (e + 0.5) / 8};
        double dirs[TPK_MARCH_PACKET][3], tmin[TPK_MARCH_PACKET], tmax[TPK_MARCH_PACKET];
        tpk_segment_fn fns[TPK_MARCH_PACKET];
        void *users[TPK_MARCH_PACKET];
        tpk_march_stats st[TPK_MARCH_PACKET];
        for (int i = 0; i < TPK_MARCH_PACKET; i++) {
            dirs[i][0] = 1.0;
            dirs[i][1] = 1e-3 * ((i / 4) - 1.5); /* rows 0-1 below 0, rows 2-3 above */
            dirs[i][2] = 1e-3 * ((i % 4) + 0.5);
            tmin[i] = 0, tmax[i] = INFINITY;
            alone[i].count = packed[i].count = 0;
            alone[i].overflow = packed[i].overflow = 0;
            alone[i].stop_after = packed[i].stop_after = 0;
            fns[i] = log_piece;
            users[i] = &packed[i];
            CHECK(tpk_march_ray_values(bvh, org, dirs[i], tmin[i], tmax[i], values, 2, log_piece, &alone[i], &st[i]) ==
                  TPK_OK);
            steps_alone += st[i].tet_steps;
        }
        CHECK(tpk_march_packet_values(bvh, org, TPK_MARCH_PACKET, (const double(*)[3])dirs, tmin, tmax, values, 2,
                                      fns, users, st) == TPK_OK);
        for (int i = 0; i < TPK_MARCH_PACKET; i++) {
            steps_packed += st[i].tet_steps;
            pieces += alone[i].count;
            CHECK_MSG(same_pieces(&alone[i], &packed[i]), "eye %d ray %d: %lld pieces alone, %lld in the packet", e, i,
                      (long long)alone[i].count, (long long)packed[i].count);
        }
    }
    CHECK_MSG(pieces > 0, "no ray met a value");
    CHECK_MSG(steps_packed < steps_alone, "%llu tets tested in the packets, %llu alone", (unsigned long long)steps_packed,
              (unsigned long long)steps_alone);
    tpk_range_bvh_destroy(bvh);
    tpk_marcher_destroy(marcher);
    fx_free(&m);
}

/* The range trees on 1, 2 and 3 threads (tpk_range_bvh_set_threads): the same bytes, the file-order tree
 * and the selected one, on a real mesh in the file's order with several values, enough tets holding one
 * that every thread gets blocks of the clustering; each such tet in one leaf slot, once. */
TPK_TEST(range_tree_same_for_any_thread_count)
{
    fx_mesh m;
    CHECK(load_real_in("sfepy/cube_big_tetra.mesh", &m, 1) == 0);
    set_field(&m, 0);
    tpk_marcher *marcher = make_marcher(&m, TPK_LAYOUT_TET16);
    const double values[4] = {-0.5, 0.0, 0.3, 0.7};
    tpk_range_bvh *bvh[3] = {NULL, NULL, NULL};
    for (int i = 0; i < 3; i++) { /* the third walks the Tet16 records on 3 threads too */
        CHECK(marcher && (i < 2 ? tpk_range_bvh_create(&bvh[i], marcher)
                                : tpk_range_bvh_create_threads(&bvh[i], marcher, 3)) == TPK_OK);
        CHECK(tpk_range_bvh_set_threads(bvh[i], i + 1) == TPK_OK);
        CHECK(tpk_range_bvh_select(bvh[i], values, 4) == TPK_OK);
    }
    const tpk_range_bvh *a = bvh[0];
    int64_t active = 0;
    for (int64_t t = 0; t < m.tet_count; t++)
        active += tpki_range_holds(a->tet_range[2 * t], a->tet_range[2 * t + 1], values, 4);
    CHECK_MSG(active > 3 * 8192 && a->wide_count > 1, "%lld of %lld tets hold a value, %lld wide nodes",
              (long long)active, (long long)m.tet_count, (long long)a->wide_count);
    const int64_t nodes = a->level_start[a->levels - 1] + 1;
    for (int i = 1; i < 3; i++) {
        const tpk_range_bvh *b = bvh[i];
        CHECK(b->levels == a->levels && b->wide_count == a->wide_count);
        CHECK(!memcmp(b->tets, a->tets, sizeof *a->tets * 4 * (size_t)m.tet_count));
        CHECK(!memcmp(b->tet_range, a->tet_range, sizeof *a->tet_range * 2 * (size_t)m.tet_count));
        CHECK(!memcmp(b->nodes, a->nodes, sizeof *a->nodes * (size_t)nodes));
        CHECK(!memcmp(b->node_range, a->node_range, sizeof *a->node_range * 2 * (size_t)nodes));
        CHECK_MSG(!memcmp(b->wide, a->wide, sizeof *a->wide * (size_t)a->wide_count), "%d threads", i + 1);
        CHECK(!memcmp(b->active_tets, a->active_tets, sizeof *a->active_tets * (size_t)active));
        CHECK(!memcmp(b->active_slots, a->active_slots, sizeof *a->active_slots * (size_t)active));
        CHECK(!memcmp(b->active_scalars, a->active_scalars, sizeof *a->active_scalars * (size_t)active));
    }
    uint8_t *seen = calloc((size_t)m.tet_count, 1);
    CHECK(seen != NULL);
    int64_t once = 0;
    for (int64_t i = 0; seen && i < active; i++) {
        int32_t t = a->active_tets[i];
        once += t >= 0 && t < m.tet_count && !seen[t] &&
                tpki_range_holds(a->tet_range[2 * t], a->tet_range[2 * t + 1], values, 4);
        if (t >= 0 && t < m.tet_count)
            seen[t] = 1;
    }
    CHECK_MSG(once == active, "%lld of %lld slots hold a distinct tet that holds a value", (long long)once,
              (long long)active);
    free(seen);
    for (int i = 0; i < 3; i++)
        tpk_range_bvh_destroy(bvh[i]);
    tpk_marcher_destroy(marcher);
    fx_free(&m);
}

/* A time step (tpk_marcher_set_scalars, then tpk_range_bvh_set_scalars): the trees read the new field's
 * ranges and keep the rest, and are then the bytes a fresh tpk_range_bvh_create on the new field gives,
 * the selected tree included once made; without a field, or without a bvh, refused. */
TPK_TEST(range_tree_new_field_equals_a_fresh_one)
{
    fx_mesh m;
    CHECK(load_real_in("sfepy/piezo_mesh_micro.vtk", &m, 1) == 0);
    set_field(&m, 0);
    float *first = m.scalars;
    m.scalars = NULL;
    set_field(&m, 1); /* the second field: floor(4 x) */
    float *second = m.scalars;
    m.scalars = first;
    tpk_marcher *marcher = make_marcher(&m, TPK_LAYOUT_TET16);
    const double values[2] = {0.5, 2.5}, old_values[1] = {0.3};
    tpk_range_bvh *kept = NULL, *fresh = NULL;
    CHECK(marcher && tpk_range_bvh_create(&kept, marcher) == TPK_OK);
    CHECK(tpk_range_bvh_select(kept, old_values, 1) == TPK_OK && kept->wide_count > 0);
    CHECK(tpk_marcher_set_scalars(marcher, second) == TPK_OK);
    CHECK(tpk_range_bvh_set_scalars(kept) == TPK_OK);
    CHECK(kept->wide_count == 0 && kept->active_value_count == 0); /* the old field's selection dropped */
    CHECK(tpk_range_bvh_create(&fresh, marcher) == TPK_OK);
    const int64_t nodes = kept->level_start[kept->levels - 1] + 1;
    CHECK(!memcmp(kept->tets, fresh->tets, sizeof *kept->tets * 4 * (size_t)m.tet_count));
    CHECK(!memcmp(kept->tet_range, fresh->tet_range, sizeof *kept->tet_range * 2 * (size_t)m.tet_count));
    CHECK(!memcmp(kept->nodes, fresh->nodes, sizeof *kept->nodes * (size_t)nodes));
    CHECK(!memcmp(kept->node_range, fresh->node_range, sizeof *kept->node_range * 2 * (size_t)nodes));
    CHECK(tpk_range_bvh_select(kept, values, 2) == TPK_OK && tpk_range_bvh_select(fresh, values, 2) == TPK_OK);
    CHECK(kept->wide_count > 0 && kept->wide_count == fresh->wide_count);
    CHECK(!memcmp(kept->wide, fresh->wide, sizeof *kept->wide * (size_t)kept->wide_count));
    CHECK(tpk_range_bvh_set_scalars(NULL) == TPK_ERR_INVALID_ARGUMENT);
    CHECK(tpk_marcher_set_scalars(marcher, NULL) == TPK_OK);
    CHECK(tpk_range_bvh_set_scalars(kept) == TPK_ERR_INVALID_ARGUMENT);
    tpk_range_bvh_destroy(kept);
    tpk_range_bvh_destroy(fresh);
    tpk_marcher_destroy(marcher);
    free(second);
    fx_free(&m);
}

/* tpk_range_bvh_heap (what the Vulkan renderer uploads): the tree in heap order, each inner node the
 * union of its two children, each leaf holding its tets' corners and scalar range, the rest empty; the
 * tets as tpk_range_bvh_tets gives them, positive (the mesh's own tets, in order). */
TPK_TEST(range_bvh_heap_is_the_tree)
{
    fx_mesh m;
    CHECK(load_real("sfepy/cylinder.vtk", &m) == 0);
    set_field(&m, 0);
    tpk_marcher *marcher = make_marcher(&m, TPK_LAYOUT_TET16);
    tpk_range_bvh *bvh = NULL;
    CHECK(marcher && tpk_range_bvh_create(&bvh, marcher) == TPK_OK);
    const int64_t leaves = (m.tet_count + TPK_RANGE_BVH_LEAF - 1) / TPK_RANGE_BVH_LEAF;
    const int64_t base = tpk_range_bvh_heap(bvh, NULL);
    CHECK_MSG(base >= leaves && base < 2 * leaves && (base & (base - 1)) == 0, "base %lld for %lld leaves",
              (long long)base, (long long)leaves);
    float *nodes = malloc(sizeof *nodes * 16 * (size_t)base);
    CHECK(nodes && tpk_range_bvh_heap(bvh, nodes) == base);
    const int32_t *tets = tpk_range_bvh_tets(bvh);
    CHECK(tets != NULL);
    for (int64_t t = 0; t < m.tet_count; t++) { /* the file's tet t, its corners in an even permutation */
        int same = 0, parity = 0;
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++)
                same += tets[4 * t + i] == m.tets[4 * t + j];
        int perm[4];
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++)
                if (tets[4 * t + i] == m.tets[4 * t + j])
                    perm[i] = j;
        for (int i = 0; i < 4; i++)
            for (int j = i + 1; j < 4; j++)
                parity ^= perm[i] > perm[j];
        CHECK_MSG(same == 4 && parity == 0, "tet %lld", (long long)t);
    }
    for (int64_t n = 2 * base - 1; n >= 1; n--) {
        const float *d = nodes + 8 * n;
        if (n >= base && n - base >= leaves) {
            CHECK(d[0] == INFINITY && d[3] == INFINITY && d[4] == -INFINITY && d[7] == -INFINITY);
            continue;
        }
        if (n >= base) { /* a leaf: its tets inside */
            for (int64_t t = (n - base) * TPK_RANGE_BVH_LEAF; t < (n - base + 1) * TPK_RANGE_BVH_LEAF && t < m.tet_count; t++)
                for (int i = 0; i < 4; i++) {
                    int32_t v = tets[4 * t + i];
                    for (int k = 0; k < 3; k++)
                        CHECK(d[k] <= m.positions[3 * v + k] && m.positions[3 * v + k] <= d[4 + k]);
                    CHECK(d[3] < m.scalars[v] && m.scalars[v] < d[7]);
                }
            continue;
        }
        const float *a = nodes + 16 * n, *b = a + 8; /* the children 2n, 2n + 1 */
        for (int k = 0; k < 4; k++)
            CHECK_MSG(d[k] == fminf(a[k], b[k]) && d[4 + k] == fmaxf(a[4 + k], b[4 + k]), "node %lld", (long long)n);
    }
    CHECK(nodes[0] == INFINITY && nodes[7] == -INFINITY); /* node 0: unused */
    free(nodes);
    tpk_range_bvh_destroy(bvh);
    tpk_marcher_destroy(marcher);
    fx_free(&m);
}

/* ---- The shares of a job on threads (threads.c) ---------------------------------------------------- */

typedef struct share_tally {
    int calls[TPKI_THREADS_MAX];
    int shares_seen[TPKI_THREADS_MAX];
} share_tally;

static void tally_share(void *arg, int share, int shares)
{
    share_tally *t = arg;
    if (share >= 0 && share < TPKI_THREADS_MAX) {
        __atomic_add_fetch(&t->calls[share], 1, __ATOMIC_RELAXED);
        t->shares_seen[share] = shares;
    }
}

/* Every share runs once, told the clamped share count, whatever count is asked; the cores are in range. */
TPK_TEST(threads_every_share_once)
{
    const int asked[] = {-5, 0, 1, 2, 7, TPKI_THREADS_MAX, TPKI_THREADS_MAX + 1, 1000};
    for (size_t a = 0; a < sizeof asked / sizeof *asked; a++) {
        int n = asked[a] < 1 ? 1 : asked[a] > TPKI_THREADS_MAX ? TPKI_THREADS_MAX : asked[a];
        share_tally t = {{0}, {0}};
        tpki_run_threads(asked[a], tally_share, &t);
        for (int i = 0; i < TPKI_THREADS_MAX; i++) {
            CHECK_MSG(t.calls[i] == (i < n), "asked %d: share %d ran %d times", asked[a], i, t.calls[i]);
            CHECK_MSG(i >= n || t.shares_seen[i] == n, "asked %d: share %d told %d shares", asked[a], i, t.shares_seen[i]);
        }
    }
    CHECK(tpki_cores() >= 1 && tpki_cores() <= TPKI_THREADS_MAX);
}
