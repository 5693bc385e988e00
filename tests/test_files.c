/* Every converted real sample, read back from its .tpk through libtetpack, meets the spec's mesh
 * invariants (spec §11): positive tets on the stored float32 positions (exact), symmetric adjacency,
 * vx, Tet20 neighbors ordered by opposite vertex id, Tet16 = Tet20 xor-folded, every boundary face
 * exactly once in the shell and outward; and TMAP/VMAP lead back to the source cells. The checks here
 * work from the definitions, not from the converter's layout code. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "convert/convert.h"
#include "harness.h"
#include "import/importers.h"
#include "invariants.h"
#include "convert/pipeline.h"
#include "tetpack.h"
#include "tpk_assert.h"

typedef struct loaded {
    tpk_file *file;
    tpk_mesh_arrays a32, a20, a16;
    tpk_tetmesh mesh; /* points (stored frame) and tets from Tet32 */
    int32_t *nb;      /* Tet32 neighbors */
} loaded;

static void loaded_free(loaded *l)
{
    free(l->mesh.points);
    free(l->mesh.tets);
    free(l->nb);
    tpk_close(l->file);
    memset(l, 0, sizeof *l);
}

/* Repairs a sample is converted with (the converter fixes nothing unasked but orientation). */
enum { REPAIR_DROP_DEGENERATE = 1 };

static int convert_sample(const char *input, const char *output, unsigned repairs, char *msg, size_t cap)
{
    tpk_convert_options o;
    memset(&o, 0, sizeof o);
    o.input = input;
    o.output = output;
    o.layouts = TPK_LAYOUT_BIT_TET16 | TPK_LAYOUT_BIT_TET20 | TPK_LAYOUT_BIT_TET32;
    o.drop_degenerate = (repairs & REPAIR_DROP_DEGENERATE) != 0;
    tpk_convert_report report;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_convert_checked(&o, &report, &diag) != 0) {
        snprintf(msg, cap, "%s", diag.message);
        return -1;
    }
    return 0;
}

static int load(const char *path, loaded *l, char *msg, size_t cap)
{
    memset(l, 0, sizeof *l);
    if (tpk_open_path(&l->file, path, NULL, msg, cap) != TPK_OK || tpk_verify(l->file) != TPK_OK ||
        tpk_load_arrays(l->file, TPK_LAYOUT_TET32, NULL, 0, &l->a32) != TPK_OK ||
        tpk_load_arrays(l->file, TPK_LAYOUT_TET20, NULL, 0, &l->a20) != TPK_OK ||
        tpk_load_arrays(l->file, TPK_LAYOUT_TET16, NULL, 0, &l->a16) != TPK_OK) {
        if (l->file)
            snprintf(msg, cap, "%s", tpk_error_text(l->file));
        return -1;
    }
    int64_t V = (int64_t)l->a32.vertex_count, T = (int64_t)l->a32.tet_count;
    l->mesh.vertex_count = V;
    l->mesh.tet_count = T;
    l->mesh.points = malloc(sizeof(double) * 3 * (size_t)V);
    l->mesh.tets = malloc(sizeof(int32_t) * 4 * (size_t)T);
    l->nb = malloc(sizeof(int32_t) * 4 * (size_t)T);
    if (!l->mesh.points || !l->mesh.tets || !l->nb)
        return -1;
    for (int64_t i = 0; i < 3 * V; i++)
        l->mesh.points[i] = l->a32.positions[i];
    for (int64_t t = 0; t < T; t++) {
        const tpk_tet32 *r = &l->a32.tet32[t];
        int32_t *v = l->mesh.tets + 4 * t;
        v[0] = r->v[0];
        v[1] = r->v[1];
        v[2] = r->v[2];
        v[3] = r->vx ^ r->v[0] ^ r->v[1] ^ r->v[2];
        memcpy(l->nb + 4 * t, r->n, sizeof r->n);
    }
    return 0;
}

/* Tet20 and Tet16 records against their definitions, from the Tet32 vertices and neighbors. */
static int check_sorted_layouts(const loaded *l, char *msg, size_t cap)
{
    for (int64_t t = 0; t < l->mesh.tet_count; t++) {
        const int32_t *v = l->mesh.tets + 4 * t, *n = l->nb + 4 * t;
        int32_t by_rank[4];
        for (int k = 0; k < 4; k++)
            by_rank[tpk_inv_rank(v, k)] = n[k];
        const tpk_tet20 *r20 = &l->a20.tet20[t];
        const tpk_tet16 *r16 = &l->a16.tet16[t];
        int32_t vx = v[0] ^ v[1] ^ v[2] ^ v[3];
        if (r20->vx != vx || r16->vx != vx)
            return tpk_inv_fail(msg, cap, "tet %lld: vx differs between layouts", (long long)t);
        for (int r = 0; r < 4; r++)
            if (r20->n[r] != by_rank[r])
                return tpk_inv_fail(msg, cap, "tet %lld: Tet20 n[%d] = %d, expected %d", (long long)t, r,
                                    r20->n[r], by_rank[r]);
        for (int r = 0; r < 3; r++)
            if (r16->nx[r] != (by_rank[r] ^ by_rank[3]))
                return tpk_inv_fail(msg, cap, "tet %lld: Tet16 nx[%d] wrong", (long long)t, r);
    }
    return 0;
}

/* Every (tet, face) with no neighbor appears exactly once in SHEL, as that face, outward (exact). */
static int check_shell(const loaded *l, char *msg, size_t cap)
{
    int64_t T = l->mesh.tet_count, open = 0;
    for (int64_t i = 0; i < 4 * T; i++)
        open += l->nb[i] == -1;
    if ((int64_t)l->a32.shell_face_count != open)
        return tpk_inv_fail(msg, cap, "%llu shell faces for %lld open tet faces",
                            (unsigned long long)l->a32.shell_face_count, (long long)open);
    unsigned char *seen = calloc((size_t)(4 * T), 1);
    if (!seen)
        return -1;
    int rc = 0;
    for (uint64_t i = 0; rc == 0 && i < l->a32.shell_face_count; i++) {
        const tpk_shell_face *s = &l->a32.shell[i];
        const int32_t *v = l->mesh.tets + 4 * (int64_t)s->t;
        int k = 0;
        while (k < 4 && (v[k] == s->a || v[k] == s->b || v[k] == s->c))
            k++;
        int in_tet = 0;
        for (int j = 0; j < 4; j++)
            in_tet += v[j] == s->a || v[j] == s->b || v[j] == s->c;
        if (k == 4 || in_tet != 3)
            rc = tpk_inv_fail(msg, cap, "shell face %llu is not a face of tet %d", (unsigned long long)i, s->t);
        else if (l->nb[4 * s->t + k] != -1 || seen[4 * s->t + k]++)
            rc = tpk_inv_fail(msg, cap, "shell face %llu: face of tet %d has a neighbor or repeats",
                              (unsigned long long)i, s->t);
        else {
            const double *P = l->mesh.points;
            if (tpk_orient3d_exact(P + 3 * s->a, P + 3 * s->b, P + 3 * s->c, P + 3 * v[k]) >= 0)
                rc = tpk_inv_fail(msg, cap, "shell face %llu is not outward", (unsigned long long)i);
        }
    }
    free(seen);
    return rc;
}

/* TMAP and VMAP lead each tet back to a source cell with the same vertices. */
static int check_maps(const loaded *l, const char *source, char *msg, size_t cap)
{
    tpk_mesh src;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_import_any(source, NULL, &src, &diag) != 0)
        return tpk_inv_fail(msg, cap, "%s", diag.message);
    int64_t T = l->mesh.tet_count, V = l->mesh.vertex_count;
    int32_t *tmap = malloc(sizeof *tmap * (size_t)T), *vmap = malloc(sizeof *vmap * (size_t)V);
    uint64_t i;
    int rc = 0;
    if (!tmap || !vmap || tpk_find_chunk(l->file, TPK_TAG_TMAP, 0, 0, &i) != TPK_OK ||
        tpk_read_chunk(l->file, i, tmap, sizeof *tmap * (uint64_t)T) != TPK_OK ||
        tpk_find_chunk(l->file, TPK_TAG_VMAP, 0, 0, &i) != TPK_OK ||
        tpk_read_chunk(l->file, i, vmap, sizeof *vmap * (uint64_t)V) != TPK_OK)
        rc = tpk_inv_fail(msg, cap, "TMAP/VMAP missing or unreadable");
    for (int64_t t = 0; rc == 0 && t < T; t++) {
        int32_t c = tmap[t];
        if (c < 0 || c >= src.cell_count) {
            rc = tpk_inv_fail(msg, cap, "tet %lld maps to bad source cell %d", (long long)t, c);
            break;
        }
        /* A tet of a split cell uses only that cell's corners (a source tet: exactly its 4). */
        const int32_t *corners = src.cell_conn + src.cell_offsets[c];
        int64_t n = src.cell_offsets[c + 1] - src.cell_offsets[c];
        for (int k = 0; k < 4 && rc == 0; k++) {
            int32_t v = vmap[l->mesh.tets[4 * t + k]], found = v == -1; /* -1: a point added at the centre */
            for (int64_t j = 0; j < n; j++)
                found |= corners[j] == v;
            if (!found)
                rc = tpk_inv_fail(msg, cap, "tet %lld: vertex %d is not a corner of source cell %d", (long long)t, v, c);
        }
    }
    for (int64_t v = 0; rc == 0 && v < V; v++)
        for (int k = 0; k < 3 && vmap[v] >= 0; k++)
            if ((float)(src.points[3 * vmap[v] + k] - l->a32.origin[k]) != l->a32.positions[3 * v + k]) {
                rc = tpk_inv_fail(msg, cap, "vertex %lld: position differs from source point %d",
                                  (long long)v, vmap[v]);
                break;
            }
    free(tmap);
    free(vmap);
    tpk_mesh_free(&src);
    return rc;
}

static void check_sample(const char *relative, unsigned repairs)
{
    char msg[1024] = "";
    const char *out = tpk_temp_path("sample.tpk");
    loaded l;
    CHECK_MSG(convert_sample(tpk_data_path(relative), out, repairs, msg, sizeof msg) == 0, "%s: %s", relative, msg);
    CHECK_MSG(load(out, &l, msg, sizeof msg) == 0, "%s: %s", relative, msg);
    int ok = tpk_check_invariants(&l.mesh, l.nb, msg, sizeof msg) == 0 &&
             check_sorted_layouts(&l, msg, sizeof msg) == 0 && check_shell(&l, msg, sizeof msg) == 0 &&
             ((repairs & REPAIR_DROP_DEGENERATE) || check_maps(&l, tpk_data_path(relative), msg, sizeof msg) == 0);
    loaded_free(&l);
    CHECK_MSG(ok, "%s: %s", relative, msg);
}

TPK_TEST(sfepy_cylinder) { check_sample("sfepy/cylinder.vtk", 0); }
TPK_TEST(sfepy_piezo_mesh_micro) { check_sample("sfepy/piezo_mesh_micro.vtk", 0); }
TPK_TEST(gmsh_t5_binary_vtk) { check_sample("gmsh/t5_small_tet_bin.vtk", 0); }
TPK_TEST(tetgen_hinge_small) { check_sample("tetgen/hinge_small.node", 0); }
TPK_TEST(tetgen_part1_small) { check_sample("tetgen/part1_small.node", 0); }
TPK_TEST(hard_inverted_tets) { check_sample("hard/inverted_tets.vtk", 0); } /* turned over by default: test_repair.c */
TPK_TEST(hard_two_components_orphans) { check_sample("hard/two_components_orphans.node", 0); }
TPK_TEST(sfepy_cube_big_tetra_medit) { check_sample("sfepy/cube_big_tetra.mesh", 0); }
TPK_TEST(sfepy_elbow_medit) { check_sample("sfepy/elbow.mesh", 0); }
TPK_TEST(sfepy_cube_cylinder_medit) { check_sample("sfepy/cube_cylinder.mesh", 0); }
/* Hexahedral meshes, split conformally: the invariants (no face in 3 tets, symmetric adjacency, outward
 * shell) and tets made of their source cell's corners. */
TPK_TEST(sfepy_acoustic_wg_hexahedra) { check_sample("sfepy/acoustic_wg.vtk", 0); }
TPK_TEST(sfepy_cube_medium_hexa_medit) { check_sample("sfepy/cube_medium_hexa.mesh", 0); }
TPK_TEST(sfepy_acoustics_mesh3d_hexahedra) { check_sample("sfepy/acoustics_mesh3d.mesh", 0); }
TPK_TEST(hard_hanging_nodes_hex) { check_sample("hard/hanging_nodes_hex.vtk", 0); }
TPK_TEST(sfepy_cross3d_twisted_hexahedron) { check_sample("sfepy/cross3d.mesh", 0); }
TPK_TEST(nasa_refine_cube_cylinder_ugrid) { check_sample("nasa_refine/cube_cylinder_ega.ugrid", 0); }
TPK_TEST(hard_huge_offset_hex_vtu) { check_sample("hard/huge_offset_hex.vtu", 0); }
TPK_TEST(hard_nonmanifold_vertex_edge_vtu) { check_sample("hard/nonmanifold_vertex_edge_tets.vtu", 0); }
TPK_TEST(gmsh_t3_tets_and_wedges_41) { check_sample("gmsh/t3_hex_prism_ascii41.msh", 0); }
TPK_TEST(gmsh_t5_tets_22) { check_sample("gmsh/t5_small_tet_ascii22.msh", 0); }
TPK_TEST(seacas_exomerge_exodus) { check_sample("seacas/exomerge_unit_test.e", 0); }
TPK_TEST(seacas_block_crush_exodus) { check_sample("seacas/block_crush_1.ex2", 0); }
TPK_TEST(nasa_refine_om6_meshb) { check_sample("nasa_refine/om6_om6-curv-no-geom.meshb", 0); }
TPK_TEST(nasa_refine_cube_sphere_meshb) { check_sample("nasa_refine/cube-sphere_cube-sphere.meshb", 0); }

/* docs/ARCHITECTURE.md §7: float32 absolute coordinates lose cells far from the origin. The cylinder (0.1 m long,
 * 0.04 m across) moved to (6.4e6, -4.9e6, 1.2e3), as in a UTM frame: every invariant still holds, and
 * positions read back (origin + float32) are within 1e-8 m of the source, where float32 absolute
 * coordinates would be off by up to 0.25 m. */
TPK_TEST(far_from_origin)
{
    tpk_mesh src;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    CHECK_MSG(tpk_import_any(tpk_data_path("sfepy/cylinder.vtk"), NULL, &src, &diag) == 0, "%s", diag.message);
    const double shift[3] = {6.4e6, -4.9e6, 1.2e3};
    const char *vtk = tpk_temp_path("far.vtk");
    FILE *f = fopen(vtk, "w");
    CHECK(f != NULL);
    fprintf(f, "# vtk DataFile Version 2.0\nfar\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS %lld double\n",
            (long long)src.point_count);
    for (int64_t v = 0; v < src.point_count; v++)
        fprintf(f, "%.17g %.17g %.17g\n", src.points[3 * v] + shift[0], src.points[3 * v + 1] + shift[1],
                src.points[3 * v + 2] + shift[2]);
    fprintf(f, "CELLS %lld %lld\n", (long long)src.cell_count, (long long)(5 * src.cell_count));
    for (int64_t c = 0; c < src.cell_count; c++) {
        const int32_t *n = src.cell_conn + src.cell_offsets[c];
        fprintf(f, "4 %d %d %d %d\n", n[0], n[1], n[2], n[3]);
    }
    fprintf(f, "CELL_TYPES %lld\n", (long long)src.cell_count);
    for (int64_t c = 0; c < src.cell_count; c++)
        fprintf(f, "10\n");
    fclose(f);

    char msg[1024] = "";
    const char *out = tpk_temp_path("far.tpk");
    loaded l;
    int ok = convert_sample(vtk, out, 0, msg, sizeof msg) == 0 && load(out, &l, msg, sizeof msg) == 0;
    if (!ok)
        tpk_mesh_free(&src);
    CHECK_MSG(ok, "%s", msg);
    ok = tpk_check_invariants(&l.mesh, l.nb, msg, sizeof msg) == 0 && check_shell(&l, msg, sizeof msg) == 0 &&
         check_maps(&l, vtk, msg, sizeof msg) == 0;
    double worst = 0;
    uint64_t i;
    int32_t *vmap = malloc(sizeof *vmap * (size_t)l.mesh.vertex_count);
    if (ok && vmap && tpk_find_chunk(l.file, TPK_TAG_VMAP, 0, 0, &i) == TPK_OK &&
        tpk_read_chunk(l.file, i, vmap, sizeof *vmap * (uint64_t)l.mesh.vertex_count) == TPK_OK)
        for (int64_t v = 0; v < l.mesh.vertex_count; v++)
            for (int k = 0; k < 3; k++) {
                double world = l.a32.origin[k] + (double)l.a32.positions[3 * v + k];
                double error = fabs(world - (src.points[3 * vmap[v] + k] + shift[k]));
                worst = error > worst ? error : worst;
            }
    free(vmap);
    loaded_free(&l);
    tpk_mesh_free(&src);
    CHECK_MSG(ok, "%s", msg);
    CHECK_MSG(worst < 1e-8, "worst position error %g m", worst);
}

/* Write a unit cube (one VTK hexahedron) with its low corner at `corner`, convert it and read back the
 * origin and the stored float32 positions. */
static int convert_cube(const double corner[3], const char *name, loaded *l, char *msg, size_t cap)
{
    static const int unit[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                   {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    const char *vtk = tpk_temp_path(name);
    FILE *f = fopen(vtk, "w");
    if (!f)
        return tpk_inv_fail(msg, cap, "cannot write %s", vtk);
    fprintf(f, "# vtk DataFile Version 2.0\ncube\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 8 double\n");
    for (int v = 0; v < 8; v++)
        fprintf(f, "%.17g %.17g %.17g\n", corner[0] + unit[v][0], corner[1] + unit[v][1], corner[2] + unit[v][2]);
    fprintf(f, "CELLS 1 9\n8 0 1 2 3 4 5 6 7\nCELL_TYPES 1\n12\n");
    fclose(f);
    const char *out = tpk_temp_path("cube.tpk");
    return convert_sample(vtk, out, 0, msg, cap) == 0 && load(out, l, msg, cap) == 0 ? 0 : -1;
}

/* Issue 9: the origin was the box centre 0.5000000000000001 for a unit cube, so a source 0 was stored
 * as 1.1e-16. The origin rule of spec §6.8 keeps exactly representable coordinates exact: a cube at 0
 * gets origin 0 and stores 0 and 1; a cube at (10, -3, 1e6) gets an integer origin in the box, and
 * every stored position is an integer and origin + position exactly its source coordinate. */
TPK_TEST(origin_keeps_exact_coordinates)
{
    static const double corners[2][3] = {{0, 0, 0}, {10, -3, 1e6}};
    for (int c = 0; c < 2; c++) {
        loaded l;
        char msg[1024] = "";
        CHECK_MSG(convert_cube(corners[c], "cube.vtk", &l, msg, sizeof msg) == 0, "%s", msg);
        int exact = 1;
        for (int k = 0; k < 3; k++) {
            exact &= c > 0 || l.a32.origin[k] == 0.0;
            for (uint64_t v = 0; v < l.a32.vertex_count; v++) {
                double rel = l.a32.positions[3 * v + k], world = l.a32.origin[k] + rel;
                exact &= rel == floor(rel) && (world == corners[c][k] || world == corners[c][k] + 1.0);
            }
        }
        double origin[3] = {l.a32.origin[0], l.a32.origin[1], l.a32.origin[2]};
        loaded_free(&l);
        CHECK_MSG(exact, "cube at (%g, %g, %g): origin (%.17g, %.17g, %.17g), stored positions not exactly the source",
                  corners[c][0], corners[c][1], corners[c][2], origin[0], origin[1], origin[2]);
    }
}
