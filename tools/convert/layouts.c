/* Tet record layouts (pipeline stage 5), exactly as spec/tetpack-format.md §6 defines them:
 * Tet32 keeps three vertices and neighbors by stored vertex; Tet20 orders neighbors by the rank of the
 * opposite vertex's id; Tet16 stores n[r] ^ n[3] so a marcher knowing where it came from recovers all. */
#include "pipeline.h"

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

void tpk_build_tet20(const int32_t *tets, const int32_t *neighbors, int64_t tet_count, tpk_tet20 *dst)
{
    for (int64_t t = 0; t < tet_count; t++) {
        const int32_t *v = tets + 4 * t;
        dst[t].vx = v[0] ^ v[1] ^ v[2] ^ v[3];
        neighbors_by_rank(v, neighbors + 4 * t, dst[t].n);
    }
}

void tpk_build_tet16(const int32_t *tets, const int32_t *neighbors, int64_t tet_count, tpk_tet16 *dst)
{
    for (int64_t t = 0; t < tet_count; t++) {
        const int32_t *v = tets + 4 * t;
        int32_t n20[4];
        neighbors_by_rank(v, neighbors + 4 * t, n20);
        dst[t].vx = v[0] ^ v[1] ^ v[2] ^ v[3];
        for (int r = 0; r < 3; r++)
            dst[t].nx[r] = n20[r] ^ n20[3];
    }
}
