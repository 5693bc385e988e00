/* Boundary faces (pipeline stage 6) as outward int4 records: each face of a tet with no neighbor, in
 * the outward order of tpk_tet_faces (format/tetpack_format.h, which says why it is outward). Tests
 * check it exactly. */
#include "pipeline.h"

int64_t tpk_count_shell_faces(const int32_t *neighbors, int64_t tet_count)
{
    int64_t count = 0;
    for (int64_t i = 0; i < 4 * tet_count; i++)
        count += neighbors[i] < 0;
    return count;
}

void tpk_build_shell(const int32_t *tets, const int32_t *neighbors, int64_t tet_count,
                     tpk_shell_face *dst)
{
    int64_t out = 0;
    for (int64_t t = 0; t < tet_count; t++) {
        const int32_t *v = tets + 4 * t;
        for (int k = 0; k < 4; k++) {
            if (neighbors[4 * t + k] >= 0)
                continue;
            tpk_shell_face *f = &dst[out++];
            f->a = v[tpk_tet_faces[k][0]];
            f->b = v[tpk_tet_faces[k][1]];
            f->c = v[tpk_tet_faces[k][2]];
            f->t = (int32_t)t;
        }
    }
}
