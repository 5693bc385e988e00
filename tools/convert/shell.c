/* Boundary faces (pipeline stage 6) as outward int4 records.
 * For a positive tet (p0,p1,p2,p3), det[p1-p0, p2-p0, p3-p0] = ((p1-p0) x (p2-p0)) . (p3-p0) > 0, so
 * (p0,p1,p2) faces p3 and (p0,p2,p1) faces out. The other faces follow from the parity of the vertex
 * permutation: (p1,p2,p3,p0) is odd, so (p1,p2,p3) already faces away from p0; (p0,p2,p3,p1) is even,
 * so (p0,p3,p2) faces out; (p0,p1,p3,p2) is odd, so (p0,p1,p3) faces out. Tests check it exactly. */
#include "pipeline.h"

const int tpk_outward_face[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

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
            f->a = v[tpk_outward_face[k][0]];
            f->b = v[tpk_outward_face[k][1]];
            f->c = v[tpk_outward_face[k][2]];
            f->t = (int32_t)t;
        }
    }
}
