/* One parallel pass over the reference tets: distinct ids (TPK-M01, 601), positive orientation on the
 * stored positions (M02, 602, exact), symmetric adjacency (M04, 604), no fold-over (M06, 606, exact),
 * neighbor order (M07, 607), and boundary faces missing from SHEL (M09, 609; the shell pass marked the
 * faces it covers). It also classifies every face for the face-use pass (605). */
#include <inttypes.h>
#include <stdlib.h>

#include "check_tpk_internal.h"
#include "base/parallel.h"

static void centroid_world(const tpkc *c, const int32_t q[4], double out[3])
{
    for (int a = 0; a < 3; a++) {
        double sum = 0;
        for (int k = 0; k < 4; k++)
            sum += c->pos[3 * (int64_t)q[k] + a];
        out[a] = c->origin[a] + 0.25 * sum;
    }
}

static void report_orientation(const tpkc *c, tpkc_sink *sink, int64_t t, const int32_t q[4], int sign)
{
    tpk_example *ex = tpkc_hit(sink, 602, "tet");
    if (!ex)
        return;
    tpk_example_ids(ex, 5, (const int64_t[]){t, q[0], q[1], q[2], q[3]});
    double p[3];
    centroid_world(c, q, p);
    tpk_example_point(ex, p);
    tpk_example_note(ex, "det[p1-p0, p2-p0, p3-p0] is %s on the stored positions (exact)",
                     sign < 0 ? "negative" : "zero");
}

/* How many ids tets q and w share; *missing: the position in q of an id w lacks, *apex: the position in
 * w of an id q lacks (meaningful when they share 3). */
static int shared_face(const int32_t q[4], const int32_t w[4], int *missing, int *apex)
{
    int shared = 0;
    *missing = *apex = -1;
    for (int j = 0; j < 4; j++) {
        int in_w = q[j] == w[0] || q[j] == w[1] || q[j] == w[2] || q[j] == w[3];
        shared += in_w;
        *missing = in_w ? *missing : j;
        int in_q = w[j] == q[0] || w[j] == q[1] || w[j] == q[2] || w[j] == q[3];
        *apex = in_q ? *apex : j;
    }
    return shared;
}

/* 606: the fourth vertex y of neighbor u must lie across face k of t from t's own fourth vertex. */
static void check_fold(const tpkc *c, tpkc_sink *sink, int64_t t, const int32_t q[4], int t_sign, int k, int32_t u,
                       int32_t y)
{
    const int *f = tpk_tet_faces[k];
    int sign = tpkc_orient(c, q[f[0]], q[f[1]], q[f[2]], y);
    if (t_sign <= 0) /* t itself is flat or inverted (602): compare the two sides directly */
        sign = sign * -tpkc_orient(c, q[f[0]], q[f[1]], q[f[2]], q[k]);
    if (sign > 0)
        return;
    tpk_example *ex = tpkc_hit(sink, 606, "tet");
    tpk_example_ids(ex, 2, (const int64_t[]){t, u});
    tpk_example_note(ex, "vertex %d of tet %d lies %s the face (%d %d %d) as tet %" PRId64 " (exact)", y, u,
                     sign < 0 ? "on the same side of" : "in the plane of", q[f[0]], q[f[1]], q[f[2]], t);
}

/* Slot k of tet t names u. Returns the face class for 605 and reports 604/606/607 problems;
 * *wrong_slot gets the position whose face u really shares when it is not k. */
static int check_slot(const tpkc *c, tpkc_sink *sink, int64_t t, const int32_t q[4], int t_sign, int k,
                      int32_t u, int *wrong_slot)
{
    int32_t w[4], nu[4];
    if (u < 0 || u >= c->T || u == t) {
        tpk_example *ex = tpkc_hit(sink, 604, "tet");
        tpk_example_ids(ex, 2, (const int64_t[]){t, u});
        tpk_example_note(ex, "neighbor %d across the face opposite %d is %s", u, q[k],
                         u == t ? "the tet itself" : "not a tet id");
        return TPKC_FACE_ONE;
    }
    if (!tpkc_usable(c, u, w))
        return TPKC_FACE_ONE; /* reported where u's ids are */
    int missing, apex, shared = shared_face(q, w, &missing, &apex);
    if (shared != 3) {
        tpk_example *ex = tpkc_hit(sink, 604, "tet");
        tpk_example_ids(ex, 2, (const int64_t[]){t, u});
        tpk_example_note(ex, "names %d as neighbor across the face opposite %d, but they share %d vertices", u,
                         q[k], shared);
        return TPKC_FACE_ONE;
    }
    if (missing != k) {
        *wrong_slot = *wrong_slot >= 0 ? *wrong_slot : k;
        return TPKC_FACE_ONE;
    }
    tpkc_neighbors(c, u, w, nu);
    int names_t = nu[0] == t || nu[1] == t || nu[2] == t || nu[3] == t;
    if (nu[apex] != t && names_t)
        return TPKC_FACE_ONE; /* u names t in another slot: 607, reported with u */
    if (nu[apex] != t) {
        tpk_example *ex = tpkc_hit(sink, 604, "tet");
        tpk_example_ids(ex, 3, (const int64_t[]){t, u, nu[apex]});
        tpk_example_note(ex, "names %d across the face opposite %d, but %d names %d across that face", u, q[k],
                         u, nu[apex]);
        return TPKC_FACE_ONE;
    }
    if (u < t)
        return TPKC_FACE_SKIP; /* the pair counts once, from its lower tet */
    /* Tell u that this slot is verified, sparing it the same random loads; if u is checked first (in
     * another worker's range) it repeats the check and gets the same result. */
    __atomic_fetch_or(&c->covered[u], (uint8_t)(16u << apex), __ATOMIC_RELAXED);
    check_fold(c, sink, t, q, t_sign, k, u, w[apex]);
    return TPKC_FACE_PAIR;
}

static void report_missing_shell(tpkc_sink *sink, int64_t t, const int32_t q[4], int k)
{
    tpk_example *ex = tpkc_hit(sink, 609, "face");
    const int *f = tpk_tet_faces[k];
    tpk_example_ids(ex, 4, (const int64_t[]){t, q[f[0]], q[f[1]], q[f[2]]});
    tpk_example_note(ex, "boundary face (neighbor -1) of tet %" PRId64 " opposite %d has no SHEL record", t, q[k]);
}

static void report_wrong_slot(const tpkc *c, tpkc_sink *sink, int64_t t, const int32_t q[4],
                              const int32_t n[4], int k)
{
    tpk_example *ex = tpkc_hit(sink, 607, "tet");
    tpk_example_ids(ex, 2, (const int64_t[]){t, n[k]});
    if (c->ref == TPK_LAYOUT_TET32)
        tpk_example_note(ex, "Tet32 n[%d] = %d, but that tet is not across the face opposite %d", k, n[k], q[k]);
    else
        tpk_example_note(ex, "%s n[rank %d] = %d, but that tet is not across the face opposite %d",
                         tpkc_layout_name(c->ref), tpkc_rank(q, k), n[k], q[k]);
}

static void check_tet(tpkc *c, tpkc_sink *sink, int64_t t)
{
    int32_t q[4], n[4];
    if (!tpkc_tet(c, t, q))
        return; /* not recovered: reported by the walk */
    if (!tpkc_distinct(q)) {
        tpk_example *ex = tpkc_hit(sink, 601, "tet");
        tpk_example_ids(ex, 5, (const int64_t[]){t, q[0], q[1], q[2], q[3]});
        tpk_example_note(ex, "a vertex id is repeated");
        return;
    }
    int sign = tpkc_orient(c, q[0], q[1], q[2], q[3]);
    if (sign <= 0)
        report_orientation(c, sink, t, q, sign);
    tpkc_neighbors(c, t, q, n);
    int classes = 0, wrong_slot = -1;
    for (int k = 0; k < 4; k++) {
        int cls = TPKC_FACE_BOUNDARY;
        uint8_t covered = __atomic_load_n(&c->covered[t], __ATOMIC_RELAXED);
        if (n[k] == -1) {
            if (!(covered & (1u << k)))
                report_missing_shell(sink, t, q, k);
        } else if (covered & (16u << k)) {
            cls = TPKC_FACE_SKIP; /* a mutual pair, checked from the lower tet */
        } else {
            cls = check_slot(c, sink, t, q, sign, k, n[k], &wrong_slot);
        }
        classes |= cls << (2 * k);
    }
    if (wrong_slot >= 0)
        report_wrong_slot(c, sink, t, q, n, wrong_slot);
    c->face_class[t] = (uint8_t)classes;
}

/* Start loading what checking tet t will touch at random: its neighbors' records and its positions.
 * Checking is bound by those cache misses, and a few tets ahead they overlap. */
static void prefetch_tet(const tpkc *c, int64_t t)
{
    int32_t q[4], n[4];
    if (!tpkc_usable(c, t, q))
        return;
    tpkc_neighbors(c, t, q, n);
    for (int k = 0; k < 4; k++) {
        __builtin_prefetch(c->pos + 3 * (int64_t)q[k]);
        if (n[k] < 0 || n[k] >= c->T)
            continue;
        if (c->ref == TPK_LAYOUT_TET32)
            __builtin_prefetch(c->tet32 + n[k]);
        else
            __builtin_prefetch(c->walked + 5 * (int64_t)n[k]);
        if (c->ref == TPK_LAYOUT_TET16)
            __builtin_prefetch(c->tet16 + n[k]);
        else if (c->ref == TPK_LAYOUT_TET20)
            __builtin_prefetch(c->tet20 + n[k]);
    }
}

#define PREFETCH_AHEAD 12

static void tet_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    tpkc_pass *pass = ctx;
    for (int64_t t = begin; t < end; t++) {
        if (t + PREFETCH_AHEAD < end)
            prefetch_tet(pass->c, t + PREFETCH_AHEAD);
        check_tet(pass->c, &pass->sinks[worker], t);
        if (worker == 0 && (t & 0xffff) == 0)
            tpk_check_progress(pass->c->report, "tpk tets", 0.3 + 0.3 * (double)(t - begin) / (double)(end - begin));
    }
}

int tpkc_check_tets(tpkc *c, tpk_diag *diag)
{
    return tpkc_run_tet_pass(c, tet_range, diag);
}
