/* The layouts other than the reference, record by record against the reference tets: vx (TPK-M03,
 * 603), Tet20 neighbor order by rank (M07, 607, decided by which face the named tet shares), and the same
 * neighbors in every layout, Tet16 decoding to them (M08, 608). In the reference itself vx defines the
 * fourth id, so a wrong vx there shows as 601, 602 or 604 instead. */
#include <inttypes.h>
#include <stdlib.h>

#include "check_tpk_internal.h"
#include "base/parallel.h"

static void check_vx(tpkc_sink *sink, int64_t t, tpk_layout layout, int32_t stored, int32_t expected)
{
    if (stored == expected)
        return;
    tpk_example *ex = tpkc_hit(sink, 603, "tet");
    tpk_example_ids(ex, 1, (const int64_t[]){t});
    tpk_example_note(ex, "%s vx = %d, but the tet's ids xor to %d", tpkc_layout_name(layout), stored, expected);
}

/* Tet20 n[r] must be the tet across the face opposite the vertex of rank r: 607 when a named tet shares
 * another face of t. */
static void check_tet20_order(const tpkc *c, tpkc_sink *sink, int64_t t, const int32_t q[4], const tpk_tet20 *r)
{
    for (int rank = 0; rank < 4; rank++) {
        int32_t u = r->n[rank], w[4];
        if (u < 0 || u == t || !tpkc_usable(c, u, w))
            continue;
        int shared = 0, missing = -1;
        for (int k = 0; k < 4; k++) {
            int in_u = q[k] == w[0] || q[k] == w[1] || q[k] == w[2] || q[k] == w[3];
            shared += in_u;
            missing = in_u ? missing : k;
        }
        if (shared == 3 && tpkc_rank(q, missing) != rank) {
            tpk_example *ex = tpkc_hit(sink, 607, "tet");
            tpk_example_ids(ex, 2, (const int64_t[]){t, u});
            tpk_example_note(ex, "Tet20 n[rank %d] = %d, but that tet is across the face opposite vertex %d "
                             "(rank %d)", rank, u, q[missing], tpkc_rank(q, missing));
            return;
        }
    }
}

static void report_disagreement(const tpkc *c, tpkc_sink *sink, int64_t t, const char *what,
                                const int32_t stored[4], const int32_t expected[4])
{
    tpk_example *ex = tpkc_hit(sink, 608, "tet");
    tpk_example_ids(ex, 1, (const int64_t[]){t});
    tpk_example_note(ex, "%s {%d, %d, %d, %d}, but %s gives {%d, %d, %d, %d}", what, stored[0], stored[1], stored[2],
                     stored[3], tpkc_layout_name(c->ref), expected[0], expected[1], expected[2], expected[3]);
}

static void check_record(const tpkc *c, tpkc_sink *sink, int64_t t)
{
    int32_t q[4], n[4], by_rank[4];
    if (!tpkc_usable(c, t, q))
        return;
    tpkc_neighbors(c, t, q, n);
    for (int k = 0; k < 4; k++)
        by_rank[tpkc_rank(q, k)] = n[k];
    int32_t vx = q[0] ^ q[1] ^ q[2] ^ q[3];
    if (c->tet20 && c->ref != TPK_LAYOUT_TET20) {
        const tpk_tet20 *r = &c->tet20[t];
        check_vx(sink, t, TPK_LAYOUT_TET20, r->vx, vx);
        check_tet20_order(c, sink, t, q, r);
        if (memcmp(r->n, by_rank, sizeof by_rank))
            report_disagreement(c, sink, t, "Tet20 n (by rank) is", r->n, by_rank);
    }
    if (c->tet16 && c->ref != TPK_LAYOUT_TET16) {
        const tpk_tet16 *r = &c->tet16[t];
        check_vx(sink, t, TPK_LAYOUT_TET16, r->vx, vx);
        int32_t expected[3] = {by_rank[0] ^ by_rank[3], by_rank[1] ^ by_rank[3], by_rank[2] ^ by_rank[3]};
        if (memcmp(r->nx, expected, sizeof expected)) {
            tpk_example *ex = tpkc_hit(sink, 608, "tet");
            tpk_example_ids(ex, 1, (const int64_t[]){t});
            tpk_example_note(ex, "Tet16 nx = {%d, %d, %d} does not decode to the neighbors %s gives: n[r] ^ n[3] = "
                             "{%d, %d, %d}", r->nx[0], r->nx[1], r->nx[2], tpkc_layout_name(c->ref), expected[0],
                             expected[1], expected[2]);
        }
    }
}

static void layout_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    tpkc_pass *pass = ctx;
    for (int64_t t = begin; t < end; t++)
        check_record(pass->c, &pass->sinks[worker], t);
}

int tpkc_check_layouts(tpkc *c, tpk_diag *diag)
{
    int others = (c->tet20 && c->ref != TPK_LAYOUT_TET20) + (c->tet16 && c->ref != TPK_LAYOUT_TET16);
    if (!others)
        return 0;
    return tpkc_run_tet_pass(c, layout_range, diag);
}
