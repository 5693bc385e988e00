/* A cell's boundary triangles judged in-process before TetGen is asked (convert/fixed_boundary.h): pairs
 * that surely cross (an edge through the other's interior, apart, at a shared corner, or folded over a
 * shared edge) and pairs that only touch or meet properly; then points TetGen cannot take (coordinates
 * past its arithmetic, all on one plane) refused by name without starting its child process. */
#include <string.h>

#include "convert/fixed_boundary.h"
#include "harness.h"

/* Two triangles (0 1 2) and (3 4 5) over the given six points. */
static int pair_crosses(const double p[18])
{
    static const int32_t tris[6] = {0, 1, 2, 3, 4, 5};
    return tpk_fixed_boundary_surely_crosses(p, 6, tris, 2);
}

TPK_TEST(triangles_apart_cross_when_an_edge_pierces_the_other)
{
    /* (0 1 2) in z = 0; (3 4 5) stands upright through its middle */
    double p[18] = {0, 0, 0, 4, 0, 0, 0, 4, 0, 1, 1, -1, 1, 1, 1, 3, 3, 1};
    CHECK_EQ_INT(pair_crosses(p), 1);
    /* moved off to x > 4: they miss */
    double q[18] = {0, 0, 0, 4, 0, 0, 0, 4, 0, 5, 1, -1, 5, 1, 1, 7, 3, 1};
    CHECK_EQ_INT(pair_crosses(q), 0);
    /* the standing one's edge ends in the plane, on the other: touching, not surely crossing */
    double r[18] = {0, 0, 0, 4, 0, 0, 0, 4, 0, 1, 1, 0, 1, 1, 1, 3, 3, 1};
    CHECK_EQ_INT(pair_crosses(r), 0);
    /* its edge through the other's edge: a zero sign, so not sure */
    double s[18] = {0, 0, 0, 4, 0, 0, 0, 4, 0, 2, 0, -1, 2, 0, 1, 3, 3, 1};
    CHECK_EQ_INT(pair_crosses(s), 0);
    /* coordinates past 1e100: never sure */
    double t[18] = {0, 0, 0, 4e101, 0, 0, 0, 4e101, 0, 1, 1, -1, 1, 1, 1, 3, 3, 1};
    CHECK_EQ_INT(pair_crosses(t), 0);
}

TPK_TEST(triangles_sharing_a_corner_or_an_edge)
{
    /* sharing corner 0: (0 1 2) in z = 0, (0 3 4) standing in x = y, its far edge through the first */
    double corner[15] = {0, 0, 0, 4, 0, 0, 0, 4, 0, 1, 1, -1, 1, 1, 1};
    static const int32_t crossing[6] = {0, 1, 2, 0, 3, 4};
    CHECK_EQ_INT(tpk_fixed_boundary_surely_crosses(corner, 5, crossing, 2), 1);
    /* the second swung the other way (x, y < 0): they meet at the corner alone */
    double apart[15] = {0, 0, 0, 4, 0, 0, 0, 4, 0, -2, -2, -1, -2, -2, 1};
    CHECK_EQ_INT(tpk_fixed_boundary_surely_crosses(apart, 5, crossing, 2), 0);
    /* sharing edge 0-1: a fold (both on one side, one plane) crosses; a flat pair on either side, and a
     * bent pair, do not */
    static const int32_t edge[6] = {0, 1, 2, 1, 0, 3};
    double fold[12] = {0, 0, 0, 4, 0, 0, 1, 2, 0, 3, 1, 0};
    CHECK_EQ_INT(tpk_fixed_boundary_surely_crosses(fold, 4, edge, 2), 1);
    double flat[12] = {0, 0, 0, 4, 0, 0, 1, 2, 0, 3, -1, 0};
    CHECK_EQ_INT(tpk_fixed_boundary_surely_crosses(flat, 4, edge, 2), 0);
    double bent[12] = {0, 0, 0, 4, 0, 0, 1, 2, 0, 3, 1, 1};
    CHECK_EQ_INT(tpk_fixed_boundary_surely_crosses(bent, 4, edge, 2), 0);
    /* the same triangle twice, and one with a corner repeated: nothing to tell (and nothing read past) */
    static const int32_t twice[6] = {0, 1, 2, 2, 0, 1}, repeated[6] = {0, 0, 1, 0, 1, 2};
    CHECK_EQ_INT(tpk_fixed_boundary_surely_crosses(fold, 4, twice, 2), 0);
    CHECK_EQ_INT(tpk_fixed_boundary_surely_crosses(fold, 4, repeated, 2), 0);
}

/* The unit cube's 12 outward triangles: a closed surface whose triangles only meet. */
TPK_TEST(a_cube_surface_does_not_cross)
{
    double p[24];
    for (int i = 0; i < 8; i++)
        p[3 * i] = i >> 2, p[3 * i + 1] = (i >> 1) & 1, p[3 * i + 2] = i & 1;
    static const int32_t tris[36] = {0, 1, 3, 0, 3, 2, 4, 6, 7, 4, 7, 5, 0, 4, 5, 0, 5, 1,
                                     2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4, 1, 5, 7, 1, 7, 3};
    CHECK_EQ_INT(tpk_fixed_boundary_surely_crosses(p, 8, tris, 12), 0);
    /* one corner pushed through the opposite face: now two of them cross */
    p[3 * 7] = -0.5, p[3 * 7 + 1] = 0.5, p[3 * 7 + 2] = 0.5;
    CHECK_EQ_INT(tpk_fixed_boundary_surely_crosses(p, 8, tris, 12), 1);
}

TPK_TEST(points_tetgen_cannot_take_are_refused_by_name)
{
    if (!tpk_fixed_boundary_available())
        TPK_SKIP("built without TetGen");
    double p[24];
    for (int i = 0; i < 8; i++)
        p[3 * i] = i >> 2, p[3 * i + 1] = (i >> 1) & 1, p[3 * i + 2] = i & 1;
    static const int32_t tris[36] = {0, 1, 3, 0, 3, 2, 4, 6, 7, 4, 7, 5, 0, 4, 5, 0, 5, 1,
                                     2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4, 1, 5, 7, 1, 7, 3};
    tpk_fixed_tets out;
    char why[600] = "";
    CHECK_EQ_INT(tpk_fixed_boundary_tets(p, 8, tris, 12, &out, why, sizeof why), 0); /* the cube itself */
    CHECK(out.tet_count >= 5);
    tpk_fixed_tets_free(&out);
    p[3 * 5 + 1] = 1.7976931348623157e306; /* a damaged file's coordinate */
    CHECK_EQ_INT(tpk_fixed_boundary_tets(p, 8, tris, 12, &out, why, sizeof why), 1);
    CHECK_MSG(strstr(why, "TetGen cannot take its boundary: point 5 has coordinate") != NULL, "%s", why);
    CHECK_EQ_INT(tpk_fixed_boundary_crossing(p, 8, tris, 12, why, sizeof why), 1);
    CHECK_MSG(strstr(why, "beyond what TetGen's double arithmetic holds") != NULL, "%s", why);
    for (int i = 0; i < 8; i++) /* flattened onto z = 0 */
        p[3 * i] = i >> 2, p[3 * i + 1] = (i >> 1) & 1, p[3 * i + 2] = 0;
    CHECK_EQ_INT(tpk_fixed_boundary_crossing(p, 8, tris, 12, why, sizeof why), 1);
    CHECK_MSG(strstr(why, "lie on one plane") != NULL, "%s", why);
}
