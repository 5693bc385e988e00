/* Face matching by smallest id, the rule that the converter's connect (convert/connect.c) and both
 * face checks (check/check_topo_match.c on any input, check/check_tpk_faces.c on a .tpk) share.
 *
 * With a tet's ids sorted s0 <= s1 <= s2 <= s3, its three faces that hold s0 have s0 as their smallest
 * id and the face opposite s0 has s1. So a tet goes to bucket s0 with three faces and to bucket s1 with
 * one, and bucket v holds exactly the faces whose smallest id is v: a counting sort by smallest id puts
 * every face in one small bucket (about 24 faces in a typical mesh), where equal faces are equal keys of
 * their two other ids. Header only: the checks run it once per tet in their hottest loops (the matcher,
 * mesh/face_match.c, sorts in registers by the same rule). The three faces that hold s0 go in the order
 * of the corner they leave out, s3, s2, s1. */
#ifndef TPK_FACE_BUCKETS_H
#define TPK_FACE_BUCKETS_H

#include <stdint.h>

#include "tetpack_format.h" /* tpk_tet_faces */

/* A tet's ids ascending, and where each came from: id[r] = v[local[r]]. */
typedef struct tpk_sorted_tet {
    int32_t id[4];
    int local[4];
} tpk_sorted_tet;

/* Sorts the 4 ids by rank, without branches: rank = how many of the others are smaller, ties broken by
 * position, so the ranks are a permutation even when ids repeat (the callers that need distinct ids
 * check that themselves). */
static inline void tpk_sort_tet(const int32_t *v, tpk_sorted_tet *s)
{
    int c01 = v[0] > v[1], c02 = v[0] > v[2], c03 = v[0] > v[3];
    int c12 = v[1] > v[2], c13 = v[1] > v[3], c23 = v[2] > v[3];
    int rank[4] = {c01 + c02 + c03, 1 - c01 + c12 + c13, 2 - c02 - c12 + c23, 3 - c03 - c13 - c23};
    for (int k = 0; k < 4; k++) {
        s->id[rank[k]] = v[k];
        s->local[rank[k]] = k;
    }
}

/* The bucket of face `k` of a sorted tet: s1 for the face opposite s0, else s0. */
static inline int32_t tpk_tet_face_bucket(const tpk_sorted_tet *s, int k)
{
    return k == s->local[0] ? s->id[1] : s->id[0];
}

/* 1 when the face opposite local vertex k of tet v, in outward order, is an odd permutation of its ids in
 * ascending order (0 when even). Two positive tets that share a face see it with different parities
 * unless it is folded (connect's fold candidates, tpk_find_folds). */
static inline int tpk_face_parity(const int32_t *v, int k)
{
    int32_t a = v[tpk_tet_faces[k][0]], b = v[tpk_tet_faces[k][1]], c = v[tpk_tet_faces[k][2]];
    return (a > b) ^ (a > c) ^ (b > c);
}

#endif
