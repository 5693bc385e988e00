/* Gmsh importer: $Nodes (tags mapped to 0-based indices), $Elements (volume elements kept in VTK node
 * order, higher-order ones whole, points, lines and surfaces dropped with a count)
 * and 4.1 $Entities (the physical group of each volume entity), for formats 2.2 and 4.1. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "import_gmsh_internal.h"
#include "base/parallel.h"
#include "base/text_scan.h"

/* Gmsh element types. vtk 0: dropped (points, lines, surfaces). Node order: Gmsh and VTK agree on the
 * corners of tetrahedra, hexahedra and pyramids; for prisms, Gmsh's reference prism has nodes
 * (0,0,-1),(1,0,-1),(0,1,-1),(0,0,1),(1,0,1),(0,1,1): the same corners, in the same order, as VTK's
 * wedge parametric corners. Checked on t3_hex_prism_ascii41.msh (12,308 prisms): every wedge is
 * positive in VTK order (tpk_tetrahedralize reports no mirrored cells; tests/test_gmsh.c). Higher-order
 * kinds are kept whole as VTK's quadratic types: `order` gives, for each VTK node, the Gmsh node
 * (Gmsh's "Node ordering": its edges run 01 02 03 12 13 23 for the tetrahedron, 01 03 04 12 15 23 26 37
 * 45 47 56 67 for the hexahedron, then its faces z-, y-, x-, x+, y+, z+; VTK's as mesh/cell_map.c lists
 * them). The 14-node pyramid keeps its base centre (Gmsh's node 13) after the 13 nodes, as the split
 * takes it (mesh/higher_order.h). */
static const signed char tet10[] = {0, 1, 2, 3, 4, 5, 6, 7, 9, 8};
static const signed char hex27[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15,
                                    22, 23, 21, 24, 20, 25, 26};
static const signed char prism18[] = {0, 1, 2, 3, 4, 5, 6, 9, 7, 12, 14, 13, 8, 10, 11, 15, 17, 16};
static const signed char pyramid14[] = {0, 1, 2, 3, 4, 5, 8, 10, 6, 7, 9, 11, 12, 13};

static const gmsh_type gmsh_types[] = {
    {1, 2, 0, 0, "line", NULL},              {2, 3, 0, 0, "triangle", NULL},
    {3, 4, 0, 0, "quadrangle", NULL},        {4, 4, 10, 4, "tetrahedron", NULL},
    {5, 8, 12, 8, "hexahedron", NULL},       {6, 6, 13, 6, "prism", NULL},
    {7, 5, 14, 5, "pyramid", NULL},          {8, 3, 0, 0, "line3", NULL},
    {9, 6, 0, 0, "triangle6", NULL},         {10, 9, 0, 0, "quadrangle9", NULL},
    {11, 10, 24, 10, "tetrahedron10", tet10}, {12, 27, 29, 27, "hexahedron27", hex27},
    {13, 18, 32, 18, "prism18", prism18},    {14, 14, 27, 14, "pyramid14", pyramid14},
    {15, 1, 0, 0, "point", NULL},            {16, 8, 0, 0, "quadrangle8", NULL},
    {17, 20, 25, 20, "hexahedron20", hex27}, {18, 15, 26, 15, "prism15", prism18},
    {19, 13, 27, 13, "pyramid13", pyramid14}, {20, 9, 0, 0, "triangle9", NULL},
    {21, 10, 0, 0, "triangle10", NULL},      {22, 12, 0, 0, "triangle12", NULL},
    {23, 15, 0, 0, "triangle15", NULL},      {24, 15, 0, 0, "triangle15i", NULL},
    {25, 21, 0, 0, "triangle21", NULL},      {26, 4, 0, 0, "line4", NULL},
    {27, 5, 0, 0, "line5", NULL},            {28, 6, 0, 0, "line6", NULL},
};

static const gmsh_type *find_type(int64_t type)
{
    for (size_t i = 0; i < sizeof gmsh_types / sizeof gmsh_types[0]; i++)
        if (gmsh_types[i].type == type)
            return &gmsh_types[i];
    return NULL;
}

/* ---- Tags --------------------------------------------------------------------------------------- */

static int cmp_tag(const void *a, const void *b)
{
    int64_t x = ((const tag_index *)a)->tag, y = ((const tag_index *)b)->tag;
    return (x > y) - (x < y);
}

/* Sort tags (unless already increasing) and refuse duplicates. */
int gmsh_sort_tags(gmsh_reader *r, tag_index *t, int64_t n, const char *what)
{
    int sorted = 1;
    for (int64_t i = 1; i < n && sorted; i++)
        sorted = t[i - 1].tag < t[i].tag;
    if (sorted)
        return 0;
    qsort(t, (size_t)n, sizeof *t, cmp_tag);
    for (int64_t i = 1; i < n; i++)
        if (t[i - 1].tag == t[i].tag)
            return tpk_scan_fail(&r->s, "%s tag %lld is defined twice", what, (long long)t[i].tag);
    return 0;
}

/* Node index of a tag, or -1 with the message. */
int32_t gmsh_node_index(gmsh_reader *r, int64_t tag, const char *user)
{
    int found = 0;
    int32_t i = gmsh_node_at(r, tag, &found);
    if (!found)
        tpk_scan_fail(&r->s, "%s uses node tag %lld, which $Nodes does not define", user, (long long)tag);
    return i;
}

/* ---- $Nodes ------------------------------------------------------------------------------------- */

static int read_node_coords(gmsh_reader *r, int64_t at, int extra)
{
    double *p = &r->points[3 * at], skip;
    for (int k = 0; k < 3; k++)
        if (gmsh_real(r, &p[k], "a node coordinate"))
            return -1;
    for (int k = 0; k < extra; k++)
        if (gmsh_real(r, &skip, "a parametric node coordinate"))
            return -1;
    return 0;
}

static int check_tag(gmsh_reader *r, int64_t tag, const char *what)
{
    if (tag < 1)
        return tpk_scan_fail(&r->s, "expected %s tag of 1 or more, found %lld", what, (long long)tag);
    return 0;
}

/* Node `at` (of n) has `tag`. While the tags are 1, 2, 3, ... there is no table (node_dense); the first
 * other tag writes out the run so far and lists the rest. */
static int note_node_tag(gmsh_reader *r, int64_t at, int64_t tag, int64_t n)
{
    if (!r->node_tags) {
        if (tag == at + 1)
            return 0;
        if (gmsh_list_node_run(r, at, n))
            return -1;
    }
    r->node_tags[at].tag = tag;
    r->node_tags[at].index = (int32_t)at;
    return 0;
}

int gmsh_read_nodes(gmsh_reader *r)
{
    int64_t n, blocks = 0, tmp;
    if (r->point_count >= 0)
        return tpk_scan_fail(&r->s, "expected one $Nodes section, found a second");
    if (r->version == 41 && (gmsh_bin_start(r, "$Nodes") || gmsh_read_count(r, "node entity blocks", 4, &blocks, 8)))
        return -1;
    if (gmsh_read_count(r, "nodes", 4, &n, r->version == 41 ? 8 : 0))
        return -1;
    if (r->version == 41 &&
        (gmsh_num(r, &tmp, "the smallest node tag", 8) || gmsh_num(r, &tmp, "the largest node tag", 8)))
        return -1;
    if (r->version == 22 && gmsh_bin_start(r, "the number of nodes"))
        return -1;
    /* huge-page advised when large (tpk_alloc_large): 1M nodes fault in 2 MiB at a time */
    r->points = tpk_alloc_large(sizeof *r->points * 3 * (size_t)(n ? n : 1));
    if (!r->points)
        return tpk_scan_fail(&r->s, "%lld nodes: out of memory", (long long)n);
    int64_t done = 0;
    if (r->version == 22) {
        for (; done < n; done++) {
            int64_t tag;
            if (gmsh_num(r, &tag, "a node tag", 4) || check_tag(r, tag, "a node") || note_node_tag(r, done, tag, n) ||
                read_node_coords(r, done, 0))
                return -1;
        }
    } else {
        for (int64_t b = 0; b < blocks; b++) {
            int64_t dim, etag, param, count, continue_from;
            if (gmsh_num(r, &dim, "the entity dimension of a node block", 4) ||
                gmsh_num(r, &etag, "the entity tag of a node block", 4) ||
                gmsh_num(r, &param, "the parametric flag of a node block", 4) ||
                gmsh_read_count(r, "nodes in the block", 4, &count, 8))
                return -1;
            if (dim < 0 || dim > 3)
                return tpk_scan_fail(&r->s, "expected an entity dimension 0 to 3, found %lld", (long long)dim);
            if (param != 0 && param != 1)
                return tpk_scan_fail(&r->s, "expected a parametric flag 0 or 1, found %lld", (long long)param);
            if (count > n - done)
                return tpk_scan_fail(&r->s, "node block %lld holds %lld nodes, more than the %lld left of the "
                                            "%lld announced", (long long)b + 1, (long long)count,
                                     (long long)(n - done), (long long)n);
            int64_t bulk = gmsh_bulk_node_tags(r, done, count, n);
            if (bulk < 0)
                return -1;
            for (int64_t i = bulk; i < count; i++) {
                int64_t tag;
                if (gmsh_num(r, &tag, "a node tag", 8) || check_tag(r, tag, "a node") ||
                    note_node_tag(r, done + i, tag, n))
                    return -1;
            }
            continue_from = !param && gmsh_bulk_coords(r, done, count) ? count : 0;
            for (int64_t i = continue_from; i < count; i++)
                if (read_node_coords(r, done + i, param ? (int)dim : 0))
                    return -1;
            done += count;
            tpk_scan_release_consumed(&r->s);
        }
        if (done != n)
            return tpk_scan_fail(&r->s, "expected %lld nodes in the node blocks, found %lld", (long long)n,
                                 (long long)done);
    }
    if (gmsh_expect_end(r, "$EndNodes"))
        return -1;
    r->point_count = n;
    r->node_dense = r->node_tags == NULL; /* no tag broke the run 1, 2, 3, ... (note_node_tag) */
    if (r->node_dense)
        return 0;
    return gmsh_sort_tags(r, r->node_tags, n, "node") ? -1 : gmsh_index_nodes(r);
}

/* ---- $Elements, $Entities ----------------------------------------------------------------------- */

/* The implicit run (see elem_tags) written out as a table, with the capacity the table would have had. */
static int list_elem_tags(gmsh_reader *r)
{
    int64_t cap = 1024;
    while (cap <= r->elem_count)
        cap *= 2;
    if (r->elem_count == 0)
        cap = 0; /* add_elem_tag allocates the first 1024 */
    tag_index *t = cap ? malloc(sizeof *t * (size_t)cap) : NULL;
    if (cap && !t)
        return tpk_scan_fail(&r->s, "out of memory");
    for (int64_t i = 0; i < r->elem_count; i++) {
        t[i].tag = r->elem_first_tag + i;
        t[i].index = (int32_t)i;
    }
    r->elem_tags = t;
    r->elem_cap = cap;
    r->elem_listed = 1;
    return 0;
}

static int add_elem_tag(gmsh_reader *r, int64_t tag, int32_t cell)
{
    if (!r->elem_listed) {
        if (r->elem_count == 0)
            r->elem_first_tag = tag; /* a run starts at a tag of 1 or more (tag - first cannot overflow) */
        if (cell == r->elem_count && r->elem_first_tag >= 1 && tag >= r->elem_first_tag &&
            tag - r->elem_first_tag == r->elem_count) {
            r->elem_count++;
            return 0;
        }
        if (list_elem_tags(r))
            return -1;
    }
    if (r->elem_count == r->elem_cap) {
        int64_t cap = r->elem_cap ? 2 * r->elem_cap : 1024;
        tag_index *t = realloc(r->elem_tags, sizeof *t * (size_t)cap);
        if (!t)
            return tpk_scan_fail(&r->s, "out of memory");
        r->elem_tags = t;
        r->elem_cap = cap;
    }
    r->elem_tags[r->elem_count].tag = tag;
    r->elem_tags[r->elem_count++].index = cell;
    return 0;
}

/* realloc, except that a first block of 2 MiB or more comes huge-page aligned and advised
 * (tpk_alloc_large): a 1M-element block then faults in 2 MiB at a time instead of 4 KiB (the page faults
 * were a quarter of reading a binary file). Either kind is realloc'd and freed as usual. */
static void *grow(void *old, size_t bytes)
{
    return old || bytes < ((size_t)2 << 20) ? realloc(old, bytes) : tpk_alloc_large(bytes);
}

/* Room for `cells` more cells with `nodes` corners in all: a block's worth when its count is known (4.1),
 * else one cell at a time, doubling. */
static int reserve_cells(gmsh_reader *r, int64_t cells, int64_t nodes)
{
    if (r->cell_count + cells > r->cell_cap) {
        int64_t cap = r->cell_cap ? 2 * r->cell_cap : 1024;
        if (cap < r->cell_count + cells)
            cap = r->cell_count + cells;
        if (cap > (int64_t)INT32_MAX)
            return tpk_scan_fail(&r->s, "more than 2^31-1 volume elements");
        uint8_t *t = grow(r->types, (size_t)cap);
        if (t)
            r->types = t;
        int64_t *o = grow(r->offsets, sizeof *o * (size_t)(cap + 1));
        if (o)
            r->offsets = o;
        float *ph = grow(r->physical, sizeof *ph * (size_t)cap);
        if (ph)
            r->physical = ph;
        float *en = grow(r->entity, sizeof *en * (size_t)cap);
        if (en)
            r->entity = en;
        if (!t || !o || !ph || !en)
            return tpk_scan_fail(&r->s, "out of memory for %lld elements", (long long)cap);
        r->cell_cap = cap;
    }
    if (r->conn_count + nodes > r->conn_cap) {
        int64_t cap = r->conn_cap ? 2 * r->conn_cap : 4096;
        if (cap < r->conn_count + nodes)
            cap = r->conn_count + nodes;
        int32_t *c = grow(r->conn, sizeof *c * (size_t)cap);
        if (!c)
            return tpk_scan_fail(&r->s, "out of memory for %lld element nodes", (long long)cap);
        r->conn = c;
        r->conn_cap = cap;
    }
    return 0;
}

static int64_t volume_physical(const gmsh_reader *r, int64_t entity)
{
    for (int64_t i = 0; i < r->volume_count; i++)
        if (r->volumes[i].tag == entity)
            return r->volumes[i].physical;
    return 0;
}

/* One element's nodes (after its tag, type and tags are read). */
/* gmsh_node_index for a node of element `tag`; the element is named (snprintf costs more than the rest
 * of reading an element) only when the node is not there. */
static int32_t element_node_index(gmsh_reader *r, int64_t id, int64_t tag, const gmsh_type *t)
{
    int found;
    int32_t i = gmsh_node_at(r, id, &found);
    if (found)
        return i;
    char user[96];
    snprintf(user, sizeof user, "element %lld (%s)", (long long)tag, t->name);
    return gmsh_node_index(r, id, user);
}

/* The cell whose nodes are at r->conn + conn_count: counted, typed, tagged. */
static int finish_cell(gmsh_reader *r, int64_t tag, const gmsh_type *t, int64_t physical, int64_t entity)
{
    int64_t c = r->cell_count;
    if (add_elem_tag(r, tag, (int32_t)c))
        return -1;
    r->types[c] = (uint8_t)t->vtk;
    r->offsets[c] = r->conn_count;
    r->physical[c] = (float)physical;
    r->entity[c] = (float)entity;
    r->conn_count += t->kept;
    r->cell_count++;
    r->offsets[r->cell_count] = r->conn_count;
    return 0;
}

static int read_element_nodes(gmsh_reader *r, int64_t tag, const gmsh_type *t, int64_t physical,
                              int64_t entity)
{
    int width = r->version == 41 ? 8 : 4;
    if (!t->vtk) {
        for (int k = 0; k < t->nodes; k++) {
            int64_t id;
            if (gmsh_num(r, &id, "an element node tag", width) || element_node_index(r, id, tag, t) < 0)
                return -1;
        }
        r->dropped++;
        return add_elem_tag(r, tag, -1);
    }
    if (reserve_cells(r, 1, t->nodes))
        return -1;
    int32_t ids[27];
    for (int k = 0; k < t->nodes; k++) {
        int64_t id;
        if (gmsh_num(r, &id, "an element node tag", width))
            return -1;
        if ((ids[k] = element_node_index(r, id, tag, t)) < 0)
            return -1;
    }
    for (int k = 0; k < t->kept; k++)
        r->conn[r->conn_count + k] = ids[gmsh_node_of(t, k)];
    return finish_cell(r, tag, t, physical, entity);
}

/* 4.1: one element of a block, its tag and nodes. */
static int read_one_element(gmsh_reader *r, const gmsh_type *t, int64_t physical, int64_t entity)
{
    int64_t tag;
    if (gmsh_num(r, &tag, "an element tag", 8) || check_tag(r, tag, "an element"))
        return -1;
    return read_element_nodes(r, tag, t, physical, entity);
}

/* `which` names the element (2.2) or the element block (4.1) in the message. */
static const gmsh_type *element_type(gmsh_reader *r, int64_t type, const char *which)
{
    const gmsh_type *t = find_type(type);
    if (!t)
        tpk_scan_fail(&r->s, "%s has element type %lld, which this reader does not know (it reads Gmsh types "
                             "1 to 28: points, lines, surfaces, and tetrahedra, hexahedra, prisms and pyramids "
                             "up to second order)", which, (long long)type);
    return t;
}

/* 2.2: an element's tags after their count (physical, elementary, then partitions: the first two are
 * kept), then its nodes. */
static int read_tags_and_nodes(gmsh_reader *r, int64_t tag, const gmsh_type *t, int64_t ntags)
{
    int64_t physical = 0, entity = 0, v;
    for (int64_t k = 0; k < ntags; k++) {
        if (gmsh_num(r, &v, "an element tag (physical, elementary, partitions)", 4))
            return -1;
        if (k == 0)
            physical = v;
        else if (k == 1)
            entity = v;
    }
    return read_element_nodes(r, tag, t, physical, entity);
}

/* 2.2 binary: groups of elements of one type and tag count; per element its tag, tags and nodes (all
 * int). */
static int read_elements_22_binary(gmsh_reader *r, int64_t n)
{
    if (gmsh_bin_start(r, "the number of elements"))
        return -1;
    for (int64_t e = 0; e < n;) {
        int64_t type, follow, ntags, tag;
        if (gmsh_num(r, &type, "an element type", 4) ||
            gmsh_num(r, &follow, "the number of elements of a group", 4) ||
            gmsh_num(r, &ntags, "the number of element tags", 4))
            return -1;
        char which[64];
        snprintf(which, sizeof which, "element group at element %lld", (long long)e + 1);
        const gmsh_type *t = element_type(r, type, which);
        if (!t)
            return -1;
        if (follow < 1 || follow > n - e)
            return tpk_scan_fail(&r->s, "expected 1 to %lld elements in a group, found %lld", (long long)(n - e),
                                 (long long)follow);
        if (ntags < 0 || (uint64_t)ntags > gmsh_bytes_left(r) / 4)
            return tpk_scan_fail(&r->s, "expected a number of element tags that fits the %zu bytes left, "
                                        "found %lld", gmsh_bytes_left(r), (long long)ntags);
        if ((uint64_t)follow > gmsh_bytes_left(r) / (4 * (uint64_t)(1 + ntags + t->nodes)))
            return tpk_scan_fail(&r->s, "%lld elements of %lld numbers cannot fit in the %zu bytes left "
                                        "(wrong count or truncated file)", (long long)follow,
                                 (long long)(1 + ntags + t->nodes), gmsh_bytes_left(r));
        for (int64_t i = 0; i < follow; i++, e++)
            if (gmsh_num(r, &tag, "an element tag", 4) || check_tag(r, tag, "an element") ||
                read_tags_and_nodes(r, tag, t, ntags))
                return -1;
        tpk_scan_release_consumed(&r->s);
    }
    return 0;
}

/* 2.2 ASCII: per element its tag, type, tag count, tags and nodes. */
static int read_elements_22_text(gmsh_reader *r, int64_t n)
{
    for (int64_t e = 0; e < n; e++) {
        int64_t tag, type, ntags;
        if (tpk_scan_int64(&r->s, &tag, "an element tag") || check_tag(r, tag, "an element") ||
            tpk_scan_int64(&r->s, &type, "an element type"))
            return -1;
        char which[48];
        snprintf(which, sizeof which, "element %lld", (long long)tag);
        const gmsh_type *t = element_type(r, type, which);
        if (!t || gmsh_read_count(r, "element tags", 1, &ntags, 0) || read_tags_and_nodes(r, tag, t, ntags))
            return -1;
        if ((e & 0xffff) == 0)
            tpk_scan_release_consumed(&r->s);
    }
    return 0;
}

/* 4.1: blocks of one entity and type; the plain part of each block straight from the bytes, the rest
 * element by element. */
static int read_elements_41(gmsh_reader *r, int64_t n, int64_t blocks)
{
    int64_t done = 0;
    for (int64_t b = 0; b < blocks; b++) {
        int64_t dim, etag, type, count;
        if (gmsh_num(r, &dim, "the entity dimension of an element block", 4) ||
            gmsh_num(r, &etag, "the entity tag of an element block", 4) ||
            gmsh_num(r, &type, "the element type of an element block", 4))
            return -1;
        char which[96];
        snprintf(which, sizeof which, "element block %lld (entity %lld, dimension %lld)", (long long)b + 1,
                 (long long)etag, (long long)dim);
        const gmsh_type *t = element_type(r, type, which);
        if (!t || gmsh_read_count(r, "elements in the block", 1 + t->nodes, &count, 8))
            return -1;
        if (count > n - done)
            return tpk_scan_fail(&r->s, "element block %lld holds %lld elements, more than the %lld left "
                                        "of the %lld announced", (long long)b + 1, (long long)count,
                                 (long long)(n - done), (long long)n);
        int64_t physical = dim == 3 ? volume_physical(r, etag) : 0;
        /* count fits the bytes left (gmsh_read_count): room for the whole block at once */
        if (t->vtk && reserve_cells(r, count, count * t->nodes))
            return -1;
        /* On all threads what needs only copying; an element that needs more is read one by one, and
         * after one that broke the implicit tag run, the rest on all threads again. */
        int64_t e = 0;
        for (int again = 1, tries = 0; again && tries < 2 && e < count; tries++) {
            int64_t plain = gmsh_bulk_elements(r, t, count - e, physical, etag, &again);
            if (plain < 0)
                return -1;
            e += plain;
            if (again && e < count) {
                if (read_one_element(r, t, physical, etag))
                    return -1;
                e++;
            }
        }
        for (; e < count; e++)
            if (read_one_element(r, t, physical, etag))
                return -1;
        done += count;
        tpk_scan_release_consumed(&r->s);
    }
    if (done != n)
        return tpk_scan_fail(&r->s, "expected %lld elements in the element blocks, found %lld", (long long)n,
                             (long long)done);
    return 0;
}

int gmsh_read_elements(gmsh_reader *r)
{
    int64_t n, blocks = 0, tmp;
    if (r->point_count < 0)
        return tpk_scan_fail(&r->s, "expected $Nodes before $Elements");
    if (r->have_elements)
        return tpk_scan_fail(&r->s, "expected one $Elements section, found a second");
    r->have_elements = 1;
    if (r->version == 41 &&
        (gmsh_bin_start(r, "$Elements") || gmsh_read_count(r, "element entity blocks", 4, &blocks, 8)))
        return -1;
    if (gmsh_read_count(r, "elements", 2, &n, r->version == 41 ? 8 : 0))
        return -1;
    if (r->version == 41 &&
        (gmsh_num(r, &tmp, "the smallest element tag", 8) || gmsh_num(r, &tmp, "the largest element tag", 8)))
        return -1;
    int rc = r->version == 41 ? read_elements_41(r, n, blocks)
             : r->binary      ? read_elements_22_binary(r, n)
                              : read_elements_22_text(r, n);
    return rc ? rc : gmsh_expect_end(r, "$EndElements");
}

/* 4.1 $Entities: keep the first physical tag of each volume. */
int gmsh_read_entities(gmsh_reader *r)
{
    int64_t counts[4];
    static const char *const kinds[4] = {"points", "curves", "surfaces", "volumes"};
    if (r->version != 41)
        return gmsh_skip_section(r, "$Entities", 9);
    if (r->volumes)
        return tpk_scan_fail(&r->s, "expected one $Entities section, found a second");
    if (gmsh_bin_start(r, "$Entities"))
        return -1;
    for (int d = 0; d < 4; d++)
        if (gmsh_read_count(r, kinds[d], 4, &counts[d], 8))
            return -1;
    r->volumes = malloc(sizeof *r->volumes * (size_t)(counts[3] ? counts[3] : 1));
    if (!r->volumes)
        return tpk_scan_fail(&r->s, "out of memory");
    for (int d = 0; d < 4; d++)
        for (int64_t i = 0; i < counts[d]; i++) {
            int64_t tag, np, nb, v, physical = 0;
            double x;
            if (gmsh_num(r, &tag, "an entity tag", 4))
                return -1;
            for (int k = 0; k < (d ? 6 : 3); k++)
                if (gmsh_real(r, &x, "an entity coordinate"))
                    return -1;
            if (gmsh_read_count(r, "physical tags", 1, &np, 8))
                return -1;
            for (int64_t k = 0; k < np; k++) {
                if (gmsh_num(r, &v, "a physical tag", 4))
                    return -1;
                if (k == 0)
                    physical = v;
            }
            if (d) {
                if (gmsh_read_count(r, "bounding entities", 1, &nb, 8))
                    return -1;
                for (int64_t k = 0; k < nb; k++)
                    if (gmsh_num(r, &v, "a bounding entity tag", 4))
                        return -1;
            }
            if (d == 3) {
                r->volumes[r->volume_count].tag = tag;
                r->volumes[r->volume_count++].physical = physical;
            }
        }
    return gmsh_expect_end(r, "$EndEntities");
}
