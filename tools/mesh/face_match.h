/* The face matcher: which faces of a mesh's tets or cells are the same face, for the converter's connect
 * (convert/connect.c) and both face checks (check/check_topo_match.c on any input, check/check_tpk_faces.c
 * on a .tpk). Each calls tpk_face_match with its own items, callbacks and flags.
 *
 * A parallel counting sort puts every item into the buckets of the smallest ids of its faces (a tet into
 * two, by the rule of face_buckets.h), one 32-bit entry each: the item id and the caller's tag. So bucket
 * v holds exactly the faces whose smallest id is v, a few dozen, which a worker expands and groups by
 * their other ids. Two ways to group:
 * - neighbours (`neighbors` set, tets only): a small hash table per bucket writes neighbors[4t + k] (the
 *   tet across face k, or -1), the converter's stage; a face of 3+ tets stops it (TPK_MATCH_SHARED).
 * - runs (`run` set): each bucket sorted by key, item and local face, and every run of equal faces handed
 *   to `run`, for reports whose order must not depend on anything but the mesh.
 * Workers take contiguous item ranges and bucket ranges, so results do not depend on timing or threads.
 * Plain tets in order of their smallest id (connect after reorder) enter only the bucket of their second
 * smallest id: each bucket's tets of that smallest id are one run of the array, merged in by item. */
#ifndef TPK_FACE_MATCH_H
#define TPK_FACE_MATCH_H

#include <stdint.h>

/* A face in a bucket: its ids after the bucket's (smallest) one, ascending. */
typedef struct tpk_match_face {
    uint64_t key;   /* the second and third smallest ids: id1 << 32 | id2 */
    uint32_t key3;  /* the fourth smallest id of a quad, UINT32_MAX for a triangle */
    uint32_t item;  /* the tet or cell */
    uint16_t local; /* its face number there (a tet's: the corner it is opposite to, as tpk_tet_faces) */
    uint8_t tag;    /* the item's tag (tpk_face_matcher.tag) */
    uint8_t odd;    /* neighbours mode with `agreeing`: the parity of the face's outward order (tpk_face_parity) */
} tpk_match_face;

typedef struct tpk_face_matcher {
    int64_t item_count, vertex_count; /* ids must lie in [0, vertex_count) */
    int64_t window_lo, window_hi;     /* buckets matched (0, 0: all): faces with a smallest id outside are left out */
    int windows;                      /* 2 or more: the buckets matched in that many windows of ids, one after
                                       * the other (entries for one window at a time), after one count pass */
    int64_t item_begin, item_end;     /* items scanned (0, 0: all), for a window whose items lie in a range */
    int threads;                      /* workers, as the caller decided (tpk_threads_for) */
    void *user;                       /* passed to every callback */

    /* The items. Tets: `tets` (4 ids per tet), else tet() (0: leave tet t out; called in every pass). Cells
     * (both NULL): cell_buckets() gives the distinct smallest ids of a cell's faces (0 leaves it out) and
     * cell_faces() its faces in one of those buckets (key, key3, local; the matcher sets item and tag). */
    const int32_t *tets;
    int (*tet)(void *user, int64_t t, int32_t v[4]);
    int (*cell_buckets)(void *user, int64_t c, int32_t *buckets);
    int (*cell_faces)(void *user, int64_t c, int32_t bucket, tpk_match_face *faces);
    int max_cell_faces; /* cells: the most faces cell_faces gives */

    /* Optional, per item: keep() in the count pass (0 leaves it out), then tag() as it is bucketed: the
     * item's tag (below 2^tag_bits), or -1 for an item keep() left out (without tag(), keep() is asked
     * again). Items < 2^(32 - tag_bits). */
    int (*keep)(void *user, int64_t item);
    int (*tag)(void *user, int64_t item);
    int tag_bits;

    int check_ids; /* tets: an id out of range or repeated is TPK_MATCH_BAD_ITEM (else the caller vouches) */

    /* Neighbours mode: neighbors[4t + k] for every tet. agreeing(), if set, gets each pair of faces (as
     * 4t + k) whose outward orders agree: for positive tets, the candidates for a fold (the orders are
     * compared by the parity of each tet's sort, so a tet's ids must be distinct: check_ids). */
    int32_t *neighbors;
    void (*agreeing)(void *user, int worker, int64_t slot_a, int64_t slot_b);

    /* Runs mode: every run of n equal faces in bucket `bucket`, in key order, a bucket's runs after the
     * previous bucket's; each worker's buckets follow the previous worker's. */
    void (*run)(void *user, int worker, int64_t bucket, const tpk_match_face *faces, int64_t n);
} tpk_face_matcher;

#define TPK_MATCH_LISTED 16 /* items named for a shared face */

enum {
    TPK_MATCH_OK = 0,
    TPK_MATCH_NOMEM = -1,     /* out of memory: `largest` > 0 when for the bucket scratch */
    TPK_MATCH_LIMIT = -2,     /* more than 2^32 - 1 entries, or items past the tag bits' limit */
    TPK_MATCH_BAD_ITEM = -3,  /* check_ids: tet `bad_item` */
    TPK_MATCH_SHARED = -4,    /* neighbours mode: face (shared_ids) of shared_count tets */
};

/* What went wrong, when tpk_face_match did not return TPK_MATCH_OK. */
typedef struct tpk_match_failure {
    int64_t bad_item;
    int32_t shared_ids[3];                  /* ascending */
    int64_t shared_count;                   /* tets that have it */
    int32_t listed[TPK_MATCH_LISTED];       /* the first of them, ascending */
    int listed_count;
    int64_t largest;                        /* entries of the largest bucket */
} tpk_match_failure;

/* Matches the faces; returns TPK_MATCH_OK or a failure, described in *failure (may be NULL). Callbacks run
 * on worker threads: per worker state goes by the worker index. Not for untrusted ids without check_ids
 * or keep(). */
int tpk_face_match(const tpk_face_matcher *m, tpk_match_failure *failure);

#endif
