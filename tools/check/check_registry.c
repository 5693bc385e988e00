/* The table of every check `tetpack check` runs. Ids and names are stable: a check may be added with a
 * new id, never renumbered or renamed (scripts match on them; spec/tetpack-format.md §11 names the 6xx
 * ids that verify each MUST). The ids 601..613 verify the mesh invariants TPK-M01..TPK-M13. */
#include <string.h>

#include "check.h"

#define E TPK_SEV_ERROR
#define W TPK_SEV_WARNING
#define I TPK_SEV_INFO

static const tpk_check_def registry[] = {
    /* vertices */
    {101, "nonfinite_vertex", E, "vertices", "a vertex coordinate is NaN or infinite"},
    {102, "duplicate_vertex", W, "vertices", "two vertices have exactly the same coordinates"},
    {103, "near_duplicate_vertex", W, "vertices",
     "two vertices lie closer than --tol times the bounding-box diagonal (exact duplicates excluded)"},
    {104, "unused_vertex", W, "vertices", "a vertex no cell uses"},
    /* cells */
    {201, "index_out_of_range", E, "cells", "a cell names a vertex id outside [0, vertices)"},
    {202, "repeated_vertex", E, "cells", "a cell names the same vertex twice"},
    {203, "zero_volume_cell", E, "cells",
     "a tet has exactly zero volume; for a voxel, hexahedron, wedge or pyramid: a tet of its conformal split "
     "(the one convert makes, quads cut through their smallest id) does (exact predicate)"},
    {204, "inverted_cell", E, "cells",
     "a tet is negatively oriented; for a voxel, hexahedron, wedge or pyramid: every tet of its conformal split "
     "is (mirrored node order; exact predicate)"},
    {205, "nonplanar_face", W, "cells",
     "a quad face of a hex, wedge or pyramid is warped by more than --warp-deg: the larger angle between the "
     "normals of its two triangles over both diagonals (exactly planar faces never count); one per face and cell"},
    {206, "nonconvex_cell", W, "cells",
     "a hex, wedge or pyramid is not convex: a corner lies strictly beyond the plane of a triangle of a face it "
     "is not on (both diagonals of quads; exact)"},
    {207, "self_intersecting_cell", E, "cells",
     "two boundary triangles of one cell (quads cut as convert cuts them) share a point besides their common "
     "corners and edge: a bow-tie or folded cell (exact)"},
    {208, "split_inverts", W, "cells",
     "the conformal split (smallest-id diagonals) of a hex, wedge or pyramid has tets of both signs or a flat "
     "one; the converter then adds a point at its centre or needs --skip-bad-cells"},
    {209, "sliver_tet", W, "cells", "a tet's minimum dihedral angle is below --sliver-deg (zero-volume tets excluded)"},
    {210, "poor_radius_ratio", I, "cells",
     "a tet's radius ratio (3 r_in / r_circ, 1 for the regular tet) is below --radius-ratio"},
    {211, "duplicate_cell", E, "cells",
     "a volume cell has the same set of vertices as a lower-numbered one, whatever the types"},
    {212, "unsupported_cell", E, "cells",
     "a cell type the converter cannot tetrahedralize (unknown, or 3-D but not a linear tetra, voxel, hexahedron, "
     "wedge, pyramid or polyhedron), or a cell with the wrong number of nodes"},
    {213, "lower_dimensional_cell", I, "cells", "a cell of dimension < 3 (vertices, lines, faces), ignored"},
    {214, "no_volume_cells", E, "cells",
     "the mesh has no 3-D cell (no cells at all, or only empty or lower-dimensional ones the importer drops): "
     "there is nothing to convert, and convert refuses it"},
    {215, "flat_polyhedron", E, "cells",
     "a polyhedron whose points all lie in one plane or coincide (exact): its faces enclose no volume, and "
     "convert refuses it"},
    /* connectivity */
    {301, "nonmanifold_face", E, "connectivity", "a face (same sorted vertex ids) shared by more than two cells"},
    {302, "inconsistent_orientation", E, "connectivity",
     "two cells that share a face both traverse it in the same direction (one of them is turned over)"},
    {303, "nonconforming_face", E, "connectivity",
     "a boundary face lies inside the volume against faces of other cells (hanging node, T-junction, "
     "mismatched quad split): coplanar, facing each other, overlapping with positive area (exact); "
     "counts faces"},
    {304, "components", I, "connectivity",
     "number of face-connected components (as checkMesh's regions; the summary says how many remain once "
     "nonconforming faces, 303, join them) and their sizes in cells; reported only when there is more than one"},
    {305, "folded_face", E, "connectivity",
     "two cells that share a face lie on the same side of its plane (fold-over, exact; quads: each "
     "triangle of the smallest-id diagonal split; faces of polyhedra: each triangle about their centre)"},
    /* shell */
    {401, "nonmanifold_edge", E, "shell",
     "a shell edge is used by more than two shell faces (the shell: faces of one cell, quads as quads)"},
    {402, "nonmanifold_vertex", E, "shell",
     "the shell faces around a vertex form more than one fan (volumes touching at a vertex; fans joined "
     "through any shared edge, so the ends of a non-manifold edge count as 401 only)"},
    {403, "shell_orientation", E, "shell",
     "two shell faces sharing an edge traverse it in the same direction"},
    {404, "open_shell", E, "shell", "a shell edge is used by one shell face only: the boundary is not closed"},
    {405, "euler_characteristic", I, "shell",
     "V - E + F of the shell per component (faces joined through edges of two faces); only components "
     "whose value is not 2 (a sphere) are reported, e.g. 0 for a torus"},
    {406, "shell_self_intersection", E, "shell",
     "two shell faces that share no vertex intersect or touch, or coplanar ones facing the same way "
     "overlap (exact CGAL predicates on the smallest-id triangle split); counts face pairs"},
    /* fields */
    {501, "nonfinite_field_value", W, "fields", "a field value is NaN or infinite"},
    {502, "field_length_mismatch", E, "fields",
     "a field's value count does not match its points or cells times components and steps"},
    /* .tpk files */
    {600, "file_rule", E, "file",
     "a reader rule of the spec (§9) fails: checksum, counts, ids, descriptors (tpk_verify)"},
    {601, "tpk_m01_tet_ids", E, "file", "TPK-M01: a tet's vertex ids are not distinct or not in [0, V)"},
    {602, "tpk_m02_orientation", E, "file", "TPK-M02: a tet is not positively oriented on the stored positions"},
    {603, "tpk_m03_vx", E, "file", "TPK-M03: vx differs from the xor of the tet's vertex ids"},
    {604, "tpk_m04_adjacency", E, "file", "TPK-M04: adjacency is not symmetric"},
    {605, "tpk_m05_face_use", E, "file",
     "TPK-M05: a face is used by more than two tets, or a face's neighbor is -1 while another tet has it "
     "(allowed only at a cut fold: both tets on the same side, both -1)"},
    {606, "tpk_m06_fold", E, "file", "TPK-M06: two tets stored as neighbors lie on the same side of their face"},
    {607, "tpk_m07_neighbor_order", E, "file",
     "TPK-M07: a neighbor is not the tet opposite the vertex its slot names"},
    {608, "tpk_m08_layouts", E, "file",
     "TPK-M08: Tet16 does not decode to Tet20, or the layouts in the file disagree"},
    {609, "tpk_m09_shell_complete", E, "file",
     "TPK-M09: a boundary face is missing from SHEL, listed twice, or a SHEL record is not a boundary face"},
    {610, "tpk_m10_shell_outward", E, "file", "TPK-M10: a SHEL record does not face outward"},
    {611, "tpk_m11_positions", E, "file",
     "TPK-M11: a position is not finite, or the header bounds are not exactly the box of the positions"},
    {612, "tpk_m12_field_range", E, "file",
     "TPK-M12: a field descriptor's min/max are not exactly the extremes of its values"},
    {613, "tpk_m13_values", E, "file", "TPK-M13: a TIME value is not finite, or a TMAP/VMAP value is out of range"},
    {614, "tpk_s01_links", E, "file",
     "TPK-S01 (part sets): a LINK record is not answered by the same face from the other part (its link back, "
     "its tet, the same three vertex positions, the same order of their ids); ids: face, part, other part, "
     "other face, other tet"},
    {615, "tpk_l01_levels", E, "file",
     "TPK-L01 (levels of detail): a LEVL chunk is not a level of this file (it does not open; not numbered "
     "1..n; not fewer tets than the level before; other fields or layouts; positions outside the file's "
     "bounds; levels, parts or links of its own); id: the level"},
    {616, "tpk_b01_blocks", E, "file",
     "TPK-B01 (culling blocks): in CULL, a seed's ids are not an even permutation of its tet's positive order "
     "or its n3 is not the neighbor opposite the largest id; a tet of a block is not reached from the block's "
     "seeds within the block; a tet's vertex lies in none of its block's intervals; ids: block, tet, seed"},
};

const tpk_check_def *tpk_check_registry(int *count)
{
    *count = (int)(sizeof registry / sizeof registry[0]);
    return registry;
}

const tpk_check_def *tpk_check_by_id(int id)
{
    for (size_t i = 0; i < sizeof registry / sizeof registry[0]; i++)
        if (registry[i].id == id)
            return &registry[i];
    return NULL;
}

const tpk_check_def *tpk_check_by_name(const char *name)
{
    for (size_t i = 0; i < sizeof registry / sizeof registry[0]; i++)
        if (!strcmp(registry[i].name, name))
            return &registry[i];
    return NULL;
}
