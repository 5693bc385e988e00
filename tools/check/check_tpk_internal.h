/* Private to the .tpk checks (check_tpk*.c): the verified file's arrays, the reference tets every
 * invariant is checked against, and per-worker finding collectors merged in a fixed order.
 *
 * The reference layout is Tet32 when the file has it (its ids are stored), else Tet20, else Tet16 (ids
 * recovered by a walk from the shell, spec §6.6). The mesh invariants that concern one layout (M01, M02,
 * M04 to M07, M09, M10) are checked on the reference; every other layout present is compared with it
 * record by record (M03 vx, M07 neighbor order, M08 same neighbors / Tet16 decoding), so each layout is
 * held to every MUST of §11.
 *
 * Who defines what. check_tpk.c, the entry (tpk_check_tpk_file*, check.h), sits on top and runs the
 * passes; each pass has its file: tpkc_walk (check_tpk_walk.c), tpkc_check_shell (check_tpk_shell.c),
 * tpkc_check_tets (check_tpk_tets.c), tpkc_check_faces (check_tpk_faces.c), tpkc_check_layouts
 * (check_tpk_layouts.c), tpkc_check_values (check_tpk_values.c), tpkc_check_cull (check_tpk_cull.c).
 * Below them check_tpk_context.c holds
 * what they share: tpkc_hit, tpkc_merge, tpkc_run_tet_pass, tpkc_example_ids32. The
 * inline accessors (tpkc_tet, tpkc_neighbors, tpkc_orient, ...) live here. A pass calls down (the
 * context, check_report.c, check_progress.c), never back into check_tpk.c. */
#ifndef TPK_CHECK_TPK_INTERNAL_H
#define TPK_CHECK_TPK_INTERNAL_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "base/predicates.h"
#include "tetpack.h"

#define TPKC_FIRST_ID 600
#define TPKC_ID_COUNT 17 /* 600 .. 616 (614 and 615 are the set's and the levels', never a pass's) */

/* Findings of one worker (or one serial pass): count per check and the first examples. */
typedef struct tpkc_list {
    int64_t count;
    int kept;
    tpk_example *examples;
} tpkc_list;

typedef struct tpkc_sink {
    tpkc_list lists[TPKC_ID_COUNT];
    int max_examples;
} tpkc_sink;

/* Count one item of check `id` (600..616); the example slot to fill, or NULL when enough are kept. */
tpk_example *tpkc_hit(tpkc_sink *sink, int id, const char *kind);
/* Move the sinks' findings into the report in sink order (so the lowest ids come first when sink w
 * covered the w-th range), then free them. */
void tpkc_merge(tpk_check_report *report, tpkc_sink *sinks, int count);
/* A pass over the tets on worker threads: worker w reports into sinks[w]. */
typedef struct tpkc_pass {
    struct tpkc *c;
    tpkc_sink *sinks;
    void *user; /* what the pass's caller gave tpkc_run_pass */
} tpkc_pass;
/* Run fn (its ctx is a tpkc_pass) over [0, c->T) with one sink per worker, then merge them in order. */
int tpkc_run_tet_pass(struct tpkc *c, void (*fn)(void *ctx, int64_t begin, int64_t end, int worker),
                      tpk_diag *diag);
/* The same over [0, count), at least `grain` items a worker (the blocks of CULL, for one), with `user`
 * in the tpkc_pass. */
int tpkc_run_pass(struct tpkc *c, int64_t count, int64_t grain,
                  void (*fn)(void *ctx, int64_t begin, int64_t end, int worker), void *user, tpk_diag *diag);
/* Fill an example's ids from int32 values. */
void tpkc_example_ids32(tpk_example *ex, int count, const int32_t *ids);

/* Per-face classes for the face-use check (605), 2 bits per face in one byte per tet. */
enum { TPKC_FACE_SKIP = 0, TPKC_FACE_ONE = 1, TPKC_FACE_BOUNDARY = 2, TPKC_FACE_PAIR = 3 };

/* Why a walk could not give a tet its ids (kept for the tets it never assigned). */
enum { TPKC_WALK_UNREACHED = 0, TPKC_WALK_BAD_APEX = 1, TPKC_WALK_NO_BACKLINK = 2, TPKC_WALK_BAD_DECODE = 3 };

typedef struct tpkc {
    tpk_file *file;
    tpk_check_report *report;
    int threads;
    int64_t V, T, S;
    double origin[3];
    const float *pos;            /* 3V, relative to origin */
    const tpk_tet32 *tet32;      /* NULL when the file has no such layout */
    const tpk_tet20 *tet20;
    const tpk_tet16 *tet16;
    const tpk_shell_face *shell;
    tpk_layout ref;              /* the reference layout */
    int32_t *walked;             /* walk reference, 5 per tet (one cache line for both): the 4 ids, then the
                                    tet it was entered from (-1: the shell); walked[5t] = -1 when not
                                    recovered */
    uint8_t *face_class;         /* per tet: class of face k in bits 2k, 2k+1 */
    uint8_t *covered;            /* per tet: bit k set when face k has a SHEL record; bit 4 + k when the
                                    lower tet across face k found the pair consistent */
    int64_t unrecovered;         /* tets the walk could not give ids */
    int serial_walk;             /* walk on one thread (the deterministic walk) */
    int walked_in_parallel;      /* the reference came from the parallel walk (see check_tpk_walk.c) */
} tpkc;

static inline int tpkc_distinct(const int32_t q[4])
{
    return q[0] != q[1] && q[0] != q[2] && q[0] != q[3] && q[1] != q[2] && q[1] != q[3] && q[2] != q[3];
}

static inline int tpkc_rank(const int32_t q[4], int k)
{
    return (q[0] < q[k]) + (q[1] < q[k]) + (q[2] < q[k]) + (q[3] < q[k]);
}

/* The reference ids of tet t (any order the file defines); 0 when the walk did not recover them. */
static inline int tpkc_tet(const tpkc *c, int64_t t, int32_t q[4])
{
    if (c->ref == TPK_LAYOUT_TET32) {
        const tpk_tet32 *r = &c->tet32[t];
        q[0] = r->v[0];
        q[1] = r->v[1];
        q[2] = r->v[2];
        q[3] = r->vx ^ r->v[0] ^ r->v[1] ^ r->v[2];
        return 1;
    }
    const int32_t *p = c->walked + 5 * t;
    if (p[0] < 0)
        return 0;
    memcpy(q, p, 4 * sizeof *q);
    return 1;
}

/* Ids usable by the geometric and adjacency checks: recovered and pairwise distinct (601 reports the
 * rest). Rule 17 already put Tet32 ids in range; walks only assign ids in range. */
static inline int tpkc_usable(const tpkc *c, int64_t t, int32_t q[4])
{
    return tpkc_tet(c, t, q) && tpkc_distinct(q);
}

/* Neighbors of a usable tet by position: n[k] is across the face opposite q[k]. Tet20 stores them by
 * rank; Tet16 is decoded from the tet the walk entered it from (its apex q[3] is opposite that tet). */
static inline void tpkc_neighbors(const tpkc *c, int64_t t, const int32_t q[4], int32_t n[4])
{
    if (c->ref == TPK_LAYOUT_TET32) {
        memcpy(n, c->tet32[t].n, 4 * sizeof *n);
        return;
    }
    int32_t by_rank[4];
    if (c->ref == TPK_LAYOUT_TET20) {
        memcpy(by_rank, c->tet20[t].n, sizeof by_rank);
    } else {
        const int32_t *nx = c->tet16[t].nx;
        int entry = tpkc_rank(q, 3);
        int32_t from = c->walked[5 * t + 4];
        by_rank[3] = entry == 3 ? from : nx[entry] ^ from;
        for (int r = 0; r < 3; r++)
            by_rank[r] = nx[r] ^ by_rank[3];
    }
    for (int k = 0; k < 4; k++)
        n[k] = by_rank[tpkc_rank(q, k)];
}

/* Exact sign of det[b-a, c-a, d-a] over the stored positions. */
static inline int tpkc_orient(const tpkc *c, int32_t v0, int32_t v1, int32_t v2, int32_t v3)
{
    double pa[3], pb[3], pc[3], pd[3]; /* float -> double is exact: the predicate sees the stored values */
    for (int k = 0; k < 3; k++) {
        pa[k] = c->pos[3 * (int64_t)v0 + k];
        pb[k] = c->pos[3 * (int64_t)v1 + k];
        pc[k] = c->pos[3 * (int64_t)v2 + k];
        pd[k] = c->pos[3 * (int64_t)v3 + k];
    }
    int s = tpk_orient3d_filter(pa, pb, pc, pd);
    if (s != 0)
        return s;
    for (int k = 0; k < 3; k++)
        if (!isfinite(pa[k]) || !isfinite(pb[k]) || !isfinite(pc[k]) || !isfinite(pd[k]))
            return 1; /* undecidable; 611 reports the position, the other checks pass over it */
    return tpk_orient3d_cgal(pa, pb, pc, pd);
}

static inline const char *tpkc_layout_name(tpk_layout layout)
{
    return layout == TPK_LAYOUT_TET32 ? "Tet32" : layout == TPK_LAYOUT_TET20 ? "Tet20" : "Tet16";
}

/* The passes, in the order check_tpk.c runs them. Each returns 0 or -1 (out of memory, diag set). */
int tpkc_walk(tpkc *c, tpk_diag *diag);              /* reference ids for Tet20/Tet16; reports tets it cannot recover */
int tpkc_check_shell(tpkc *c, tpk_diag *diag);       /* 609 records, 610 */
int tpkc_check_tets(tpkc *c, tpk_diag *diag);        /* 601, 602, 604, 606, 607, 609 missing faces */
int tpkc_check_faces(tpkc *c, tpk_diag *diag);       /* 605 */
int tpkc_check_layouts(tpkc *c, tpk_diag *diag);     /* 603, 607, 608 of the other layouts */
int tpkc_check_values(tpkc *c, tpk_diag *diag);      /* 611, 612, 613, and §7.1 text rules under 600 */
int tpkc_check_cull(tpkc *c, tpk_diag *diag);        /* 616: the culling blocks (CULL) against the reference */

#endif
