/* Gmsh .msh importer, formats 2.2 and 4.1, ASCII and binary (little-endian, data size 8). A file is a series of sections `$Name ... $EndName`:
 * $MeshFormat first, then $Nodes (node tags may be sparse: they are mapped to 0-based indices),
 * $Elements (volume elements kept in VTK node order, higher-order ones reduced to their corners, points,
 * lines and surfaces dropped with a count), $NodeData/$ElementData (fields; blocks of the same name at
 * several times become one field with several steps), $Entities (4.1: the physical group of each volume
 * entity). Other sections ($PhysicalNames, $Periodic, $PartitionedEntities, unknown ones) are skipped.
 * Each element's physical group becomes the cell field "physical", its elementary entity "entity". */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tetpack_format.h"

#include "cell_types.h"
#include "importers.h"
#include "text_scan.h"

/* Gmsh element types. vtk 0: dropped (points, lines, surfaces). Higher-order kinds list their corner
 * nodes first, in the order of the linear kind. Node order: Gmsh and VTK agree on tetrahedra,
 * hexahedra and pyramids; for prisms, Gmsh's reference prism has nodes (0,0,-1),(1,0,-1),(0,1,-1),
 * (0,0,1),(1,0,1),(0,1,1): the same corners, in the same order, as VTK's wedge parametric corners, so
 * the mapping is the identity. Checked on t3_hex_prism_ascii41.msh (12,308 prisms): every wedge is
 * positive in VTK order (tpk_tetrahedralize reports no mirrored cells; tests/test_gmsh.c). */
typedef struct gmsh_type {
    int type, nodes, vtk, corners;
    const char *name;
} gmsh_type;

static const gmsh_type gmsh_types[] = {
    {1, 2, 0, 0, "line"},           {2, 3, 0, 0, "triangle"},          {3, 4, 0, 0, "quadrangle"},
    {4, 4, 10, 4, "tetrahedron"},   {5, 8, 12, 8, "hexahedron"},       {6, 6, 13, 6, "prism"},
    {7, 5, 14, 5, "pyramid"},       {8, 3, 0, 0, "line3"},             {9, 6, 0, 0, "triangle6"},
    {10, 9, 0, 0, "quadrangle9"},   {11, 10, 10, 4, "tetrahedron10"},  {12, 27, 12, 8, "hexahedron27"},
    {13, 18, 13, 6, "prism18"},     {14, 14, 14, 5, "pyramid14"},      {15, 1, 0, 0, "point"},
    {16, 8, 0, 0, "quadrangle8"},   {17, 20, 12, 8, "hexahedron20"},   {18, 15, 13, 6, "prism15"},
    {19, 13, 14, 5, "pyramid13"},   {20, 9, 0, 0, "triangle9"},        {21, 10, 0, 0, "triangle10"},
    {22, 12, 0, 0, "triangle12"},   {23, 15, 0, 0, "triangle15"},      {24, 15, 0, 0, "triangle15i"},
    {25, 21, 0, 0, "triangle21"},   {26, 4, 0, 0, "line4"},            {27, 5, 0, 0, "line5"},
    {28, 6, 0, 0, "line6"},
};

static const gmsh_type *find_type(int64_t type)
{
    for (size_t i = 0; i < sizeof gmsh_types / sizeof gmsh_types[0]; i++)
        if (gmsh_types[i].type == type)
            return &gmsh_types[i];
    return NULL;
}

typedef struct tag_index {
    int64_t tag;
    int32_t index; /* node index, or cell index (-1: a dropped element) */
} tag_index;

/* One $NodeData/$ElementData block. */
typedef struct data_block {
    char name[TPK_NAME_MAX];
    int association;
    int components;
    double time;
    float *values; /* (points or cells) * components, NaN where not given */
} data_block;

typedef struct entity_phys {
    int64_t tag, physical;
} entity_phys;

typedef struct gmsh_reader {
    tpk_scan s;
    int version; /* 22 or 41; 0 before $MeshFormat */
    int binary;  /* file type 1: little-endian binary data blocks between ASCII lines */
    int64_t point_count; /* -1 until $Nodes */
    double *points;
    tag_index *node_tags; /* sorted by tag */
    int node_dense;       /* tags are 1..point_count in order */
    int have_elements;
    int64_t cell_count, conn_count, cell_cap, conn_cap;
    uint8_t *types;
    int64_t *offsets;
    int32_t *conn;
    float *physical, *entity;
    tag_index *elem_tags; /* every element (dropped ones too), sorted once needed */
    int64_t elem_count, elem_cap;
    int elem_sorted;
    int64_t dropped, reduced;
    entity_phys *volumes; /* 4.1 $Entities: volume tag -> first physical tag */
    int64_t volume_count;
    data_block *blocks;
    int block_count;
    uint64_t block_values; /* sum of items * components over the blocks */
} gmsh_reader;

static size_t bytes_left(const gmsh_reader *r)
{
    return r->s.size - r->s.pos;
}

/* Binary data: `n` bytes at the current position, or the message "expected <what>". */
static int bin_bytes(gmsh_reader *r, void *dst, size_t n, const char *what)
{
    r->s.tok_pos = r->s.pos;
    r->s.tok_line = r->s.line;
    if (bytes_left(r) < n)
        return tpk_scan_fail(&r->s, "expected %s (%zu bytes), found %zu bytes before the end of the file", what,
                             n, bytes_left(r));
    memcpy(dst, r->s.data + r->s.pos, n);
    r->s.pos += n;
    return 0;
}

/* An integer: ASCII, or in binary files (width 4: int, 8: size_t) a binary one; width 0: ASCII always. */
static int num(gmsh_reader *r, int64_t *v, const char *what, int width)
{
    if (!r->binary || width == 0)
        return tpk_scan_int64(&r->s, v, what);
    if (width == 4) {
        int32_t x = 0;
        if (bin_bytes(r, &x, 4, what))
            return -1;
        *v = x;
        return 0;
    }
    uint64_t x = 0;
    if (bin_bytes(r, &x, 8, what))
        return -1;
    if (x > (uint64_t)INT64_MAX)
        return tpk_scan_fail(&r->s, "expected %s, found %llu", what, (unsigned long long)x);
    *v = (int64_t)x;
    return 0;
}

static int real(gmsh_reader *r, double *v, const char *what)
{
    if (!r->binary)
        return tpk_scan_double(&r->s, v, what);
    return bin_bytes(r, v, 8, what);
}

/* Binary data starts after the end of the current line. */
static int bin_start(gmsh_reader *r, const char *after)
{
    return r->binary ? tpk_scan_end_line(&r->s, after) : 0;
}

/* A count of rows of at least `values` numbers each, checked against the bytes left (each number takes
 * a character and a separator), so absurd counts fail before anything is allocated. */
static int read_count(gmsh_reader *r, const char *what, int values, int64_t *n, int width)
{
    char w[96];
    snprintf(w, sizeof w, "the number of %s", what);
    if (num(r, n, w, width))
        return -1;
    size_t left = bytes_left(r);
    if (*n < 0)
        return tpk_scan_fail(&r->s, "expected the number of %s (0 or more), found %lld", what, (long long)*n);
    if ((uint64_t)*n > left / (2 * (uint64_t)values) + 1)
        return tpk_scan_fail(&r->s, "%lld %s cannot fit in the %zu bytes left (wrong count or truncated file)",
                             (long long)*n, what, left);
    if (*n > INT32_MAX)
        return tpk_scan_fail(&r->s, "%lld %s: more than 2^31-1", (long long)*n, what);
    return 0;
}

/* The closing `$EndName` of a section. */
static int expect_end(gmsh_reader *r, const char *end)
{
    const char *tok;
    char q[64];
    size_t len = tpk_scan_token(&r->s, &tok);
    if (len == strlen(end) && !memcmp(tok, end, len))
        return 0;
    if (!len)
        return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "expected '%s', found end of file", end);
    return tpk_scan_fail(&r->s, "expected '%s', found '%s'", end, tpk_scan_quote(tok, len, q, sizeof q));
}

/* Skip a section up to the line starting with `$End` + name (name: the section token without '$'). */
static int skip_section(gmsh_reader *r, const char *tok, size_t len)
{
    char end[80], q[64];
    if (len > 60)
        return tpk_scan_fail(&r->s, "expected a section name, found '%s'", tpk_scan_quote(tok, len, q, sizeof q));
    snprintf(end, sizeof end, "$End%.*s", (int)len - 1, tok + 1);
    size_t elen = strlen(end);
    const unsigned char *d = r->s.data;
    size_t p = r->s.pos;
    int64_t line = r->s.line;
    while (p < r->s.size) {
        if (d[p] == '\n') {
            line++;
            p++;
            continue;
        }
        /* at a line start or after the section token */
        size_t q0 = p;
        while (q0 < r->s.size && (d[q0] == ' ' || d[q0] == '\t' || d[q0] == '\r'))
            q0++;
        if (r->s.size - q0 >= elen && !memcmp(d + q0, end, elen) &&
            (r->s.size - q0 == elen || d[q0 + elen] <= ' ')) {
            r->s.pos = q0 + elen;
            r->s.line = line;
            return 0;
        }
        const unsigned char *nl = memchr(d + p, '\n', r->s.size - p);
        p = nl ? (size_t)(nl - d) : r->s.size;
    }
    return tpk_scan_fail(&r->s, "expected '%s' closing '%s', found end of file", end,
                         tpk_scan_quote(tok, len, q, sizeof q));
}

static int read_format(gmsh_reader *r)
{
    const char *tok;
    char q[64];
    size_t len = tpk_scan_token(&r->s, &tok);
    int64_t file_type, data_size;
    if (!len)
        return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "expected the format version, found end of file");
    if (len == 3 && !memcmp(tok, "2.2", 3))
        r->version = 22;
    else if (len == 3 && !memcmp(tok, "4.1", 3))
        r->version = 41;
    else
        return tpk_scan_fail(&r->s, "expected format version 2.2 or 4.1, found '%s'",
                             tpk_scan_quote(tok, len, q, sizeof q));
    if (tpk_scan_int64(&r->s, &file_type, "the file type (0 ASCII, 1 binary)"))
        return -1;
    if (file_type != 0 && file_type != 1)
        return tpk_scan_fail(&r->s, "expected file type 0 (ASCII) or 1 (binary), found %lld", (long long)file_type);
    if (tpk_scan_int64(&r->s, &data_size, "the data size"))
        return -1;
    if (data_size != 8)
        return tpk_scan_fail(&r->s, "expected data size 8, found %lld", (long long)data_size);
    if (file_type == 1) {
        /* binary: the integer 1 follows, written in the file's byte order; messages give byte offsets */
        int32_t one = 0;
        if (tpk_scan_end_line(&r->s, "the data size"))
            return -1;
        r->binary = 1;
        r->s.byte_places = 1;
        if (bin_bytes(r, &one, 4, "the integer 1 (byte order mark)"))
            return -1;
        if (one != 1)
            return tpk_scan_fail(&r->s, "expected the integer 1 in little-endian byte order, found %d "
                                        "(big-endian binary files are not read)", one);
    }
    return expect_end(r, "$EndMeshFormat");
}

static int cmp_tag(const void *a, const void *b)
{
    int64_t x = ((const tag_index *)a)->tag, y = ((const tag_index *)b)->tag;
    return (x > y) - (x < y);
}

/* Sort tags (unless already increasing) and refuse duplicates. */
static int sort_tags(gmsh_reader *r, tag_index *t, int64_t n, const char *what)
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

static int32_t lookup(const tag_index *t, int64_t n, int64_t tag, int *found)
{
    int64_t lo = 0, hi = n;
    while (lo < hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (t[mid].tag < tag)
            lo = mid + 1;
        else
            hi = mid;
    }
    *found = lo < n && t[lo].tag == tag;
    return *found ? t[lo].index : -1;
}

/* Node index of a tag, or -1 with the message. */
static int32_t node_index(gmsh_reader *r, int64_t tag, const char *user)
{
    if (r->node_dense && tag >= 1 && tag <= r->point_count)
        return (int32_t)(tag - 1);
    int found;
    int32_t i = lookup(r->node_tags, r->point_count, tag, &found);
    if (!found)
        tpk_scan_fail(&r->s, "%s uses node tag %lld, which $Nodes does not define", user, (long long)tag);
    return i;
}

static int read_node_coords(gmsh_reader *r, int64_t at, int extra)
{
    double *p = &r->points[3 * at], skip;
    for (int k = 0; k < 3; k++)
        if (real(r, &p[k], "a node coordinate"))
            return -1;
    for (int k = 0; k < extra; k++)
        if (real(r, &skip, "a parametric node coordinate"))
            return -1;
    return 0;
}

static int check_tag(gmsh_reader *r, int64_t tag, const char *what)
{
    if (tag < 1)
        return tpk_scan_fail(&r->s, "expected a %s tag of 1 or more, found %lld", what, (long long)tag);
    return 0;
}

static int read_nodes(gmsh_reader *r)
{
    int64_t n, blocks = 0, tmp;
    if (r->point_count >= 0)
        return tpk_scan_fail(&r->s, "expected one $Nodes section, found a second");
    if (r->version == 41 && (bin_start(r, "$Nodes") || read_count(r, "node entity blocks", 4, &blocks, 8)))
        return -1;
    if (read_count(r, "nodes", 4, &n, r->version == 41 ? 8 : 0))
        return -1;
    if (r->version == 41 && (num(r, &tmp, "the smallest node tag", 8) || num(r, &tmp, "the largest node tag", 8)))
        return -1;
    if (r->version == 22 && bin_start(r, "the number of nodes"))
        return -1;
    r->points = malloc(sizeof *r->points * 3 * (size_t)(n ? n : 1));
    r->node_tags = malloc(sizeof *r->node_tags * (size_t)(n ? n : 1));
    if (!r->points || !r->node_tags)
        return tpk_scan_fail(&r->s, "%lld nodes: out of memory", (long long)n);
    int64_t done = 0;
    if (r->version == 22) {
        for (; done < n; done++) {
            if (num(r, &r->node_tags[done].tag, "a node tag", 4) ||
                check_tag(r, r->node_tags[done].tag, "node") || read_node_coords(r, done, 0))
                return -1;
            r->node_tags[done].index = (int32_t)done;
        }
    } else {
        for (int64_t b = 0; b < blocks; b++) {
            int64_t dim, etag, param, count;
            if (num(r, &dim, "the entity dimension of a node block", 4) ||
                num(r, &etag, "the entity tag of a node block", 4) ||
                num(r, &param, "the parametric flag of a node block", 4) ||
                read_count(r, "nodes in the block", 4, &count, 8))
                return -1;
            if (dim < 0 || dim > 3)
                return tpk_scan_fail(&r->s, "expected an entity dimension 0 to 3, found %lld", (long long)dim);
            if (param != 0 && param != 1)
                return tpk_scan_fail(&r->s, "expected a parametric flag 0 or 1, found %lld", (long long)param);
            if (count > n - done)
                return tpk_scan_fail(&r->s, "node block %lld holds %lld nodes, more than the %lld left of the "
                                            "%lld announced", (long long)b + 1, (long long)count,
                                     (long long)(n - done), (long long)n);
            for (int64_t i = 0; i < count; i++) {
                if (num(r, &r->node_tags[done + i].tag, "a node tag", 8) ||
                    check_tag(r, r->node_tags[done + i].tag, "node"))
                    return -1;
                r->node_tags[done + i].index = (int32_t)(done + i);
            }
            for (int64_t i = 0; i < count; i++)
                if (read_node_coords(r, done + i, param ? (int)dim : 0))
                    return -1;
            done += count;
            tpk_scan_release_consumed(&r->s);
        }
        if (done != n)
            return tpk_scan_fail(&r->s, "expected %lld nodes in the node blocks, found %lld", (long long)n,
                                 (long long)done);
    }
    if (expect_end(r, "$EndNodes"))
        return -1;
    r->point_count = n;
    r->node_dense = 1;
    for (int64_t i = 0; i < n && r->node_dense; i++)
        r->node_dense = r->node_tags[i].tag == i + 1;
    return r->node_dense ? 0 : sort_tags(r, r->node_tags, n, "node");
}

static int add_elem_tag(gmsh_reader *r, int64_t tag, int32_t cell)
{
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

/* Room for one more cell of `nodes` corners. */
static int reserve_cell(gmsh_reader *r, int nodes)
{
    if (r->cell_count + 1 > r->cell_cap) {
        int64_t cap = r->cell_cap ? 2 * r->cell_cap : 1024;
        if (cap > (int64_t)INT32_MAX)
            return tpk_scan_fail(&r->s, "more than 2^31-1 volume elements");
        uint8_t *t = realloc(r->types, (size_t)cap);
        if (t)
            r->types = t;
        int64_t *o = realloc(r->offsets, sizeof *o * (size_t)(cap + 1));
        if (o)
            r->offsets = o;
        float *ph = realloc(r->physical, sizeof *ph * (size_t)cap);
        if (ph)
            r->physical = ph;
        float *en = realloc(r->entity, sizeof *en * (size_t)cap);
        if (en)
            r->entity = en;
        if (!t || !o || !ph || !en)
            return tpk_scan_fail(&r->s, "out of memory for %lld elements", (long long)cap);
        r->cell_cap = cap;
    }
    if (r->conn_count + nodes > r->conn_cap) {
        int64_t cap = r->conn_cap ? 2 * r->conn_cap : 4096;
        int32_t *c = realloc(r->conn, sizeof *c * (size_t)cap);
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
static int read_element_nodes(gmsh_reader *r, int64_t tag, const gmsh_type *t, int64_t physical,
                              int64_t entity)
{
    char user[96];
    int width = r->version == 41 ? 8 : 4;
    snprintf(user, sizeof user, "element %lld (%s)", (long long)tag, t->name);
    if (!t->vtk) {
        for (int k = 0; k < t->nodes; k++) {
            int64_t id;
            if (num(r, &id, "an element node tag", width) || node_index(r, id, user) < 0)
                return -1;
        }
        r->dropped++;
        return add_elem_tag(r, tag, -1);
    }
    if (reserve_cell(r, t->corners))
        return -1;
    for (int k = 0; k < t->nodes; k++) {
        int64_t id;
        if (num(r, &id, "an element node tag", width))
            return -1;
        int32_t i = node_index(r, id, user);
        if (i < 0)
            return -1;
        if (k < t->corners)
            r->conn[r->conn_count + k] = i; /* identity mapping for all four kinds (see gmsh_types) */
    }
    if (t->corners != t->nodes)
        r->reduced++;
    int64_t c = r->cell_count;
    if (add_elem_tag(r, tag, (int32_t)c))
        return -1;
    r->types[c] = (uint8_t)t->vtk;
    r->offsets[c] = r->conn_count;
    r->physical[c] = (float)physical;
    r->entity[c] = (float)entity;
    r->conn_count += t->corners;
    r->cell_count++;
    r->offsets[r->cell_count] = r->conn_count;
    return 0;
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

static int read_elements(gmsh_reader *r)
{
    int64_t n, blocks = 0, tmp;
    if (r->point_count < 0)
        return tpk_scan_fail(&r->s, "expected $Nodes before $Elements");
    if (r->have_elements)
        return tpk_scan_fail(&r->s, "expected one $Elements section, found a second");
    r->have_elements = 1;
    if (r->version == 41 && (bin_start(r, "$Elements") || read_count(r, "element entity blocks", 4, &blocks, 8)))
        return -1;
    if (read_count(r, "elements", 2, &n, r->version == 41 ? 8 : 0))
        return -1;
    if (r->version == 41 &&
        (num(r, &tmp, "the smallest element tag", 8) || num(r, &tmp, "the largest element tag", 8)))
        return -1;
    if (r->version == 22 && r->binary) {
        /* groups: type, count, number of tags; then per element its tag, tags and nodes (all int) */
        if (bin_start(r, "the number of elements"))
            return -1;
        for (int64_t e = 0; e < n;) {
            int64_t type, follow, ntags, tag, v;
            if (num(r, &type, "an element type", 4) || num(r, &follow, "the number of elements of a group", 4) ||
                num(r, &ntags, "the number of element tags", 4))
                return -1;
            char which[64];
            snprintf(which, sizeof which, "element group at element %lld", (long long)e + 1);
            const gmsh_type *t = element_type(r, type, which);
            if (!t)
                return -1;
            if (follow < 1 || follow > n - e)
                return tpk_scan_fail(&r->s, "expected 1 to %lld elements in a group, found %lld", (long long)(n - e),
                                     (long long)follow);
            if (ntags < 0 || (uint64_t)ntags > bytes_left(r) / 4)
                return tpk_scan_fail(&r->s, "expected a number of element tags that fits the %zu bytes left, "
                                            "found %lld", bytes_left(r), (long long)ntags);
            if ((uint64_t)follow > bytes_left(r) / (4 * (uint64_t)(1 + ntags + t->nodes)))
                return tpk_scan_fail(&r->s, "%lld elements of %lld numbers cannot fit in the %zu bytes left "
                                            "(wrong count or truncated file)", (long long)follow,
                                     (long long)(1 + ntags + t->nodes), bytes_left(r));
            for (int64_t i = 0; i < follow; i++, e++) {
                int64_t physical = 0, entity = 0;
                if (num(r, &tag, "an element tag", 4) || check_tag(r, tag, "element"))
                    return -1;
                for (int64_t k = 0; k < ntags; k++) {
                    if (num(r, &v, "an element tag (physical, elementary, partitions)", 4))
                        return -1;
                    if (k == 0)
                        physical = v;
                    else if (k == 1)
                        entity = v;
                }
                if (read_element_nodes(r, tag, t, physical, entity))
                    return -1;
            }
            tpk_scan_release_consumed(&r->s);
        }
    } else if (r->version == 22) {
        for (int64_t e = 0; e < n; e++) {
            int64_t tag, type, ntags, physical = 0, entity = 0, v;
            if (tpk_scan_int64(&r->s, &tag, "an element tag") || check_tag(r, tag, "element") ||
                tpk_scan_int64(&r->s, &type, "an element type"))
                return -1;
            char which[48];
            snprintf(which, sizeof which, "element %lld", (long long)tag);
            const gmsh_type *t = element_type(r, type, which);
            if (!t || read_count(r, "element tags", 1, &ntags, 0))
                return -1;
            for (int64_t k = 0; k < ntags; k++) {
                if (tpk_scan_int64(&r->s, &v, "an element tag (physical, elementary, partitions)"))
                    return -1;
                if (k == 0)
                    physical = v;
                else if (k == 1)
                    entity = v;
            }
            if (read_element_nodes(r, tag, t, physical, entity))
                return -1;
            if ((e & 0xffff) == 0)
                tpk_scan_release_consumed(&r->s);
        }
    } else {
        int64_t done = 0;
        for (int64_t b = 0; b < blocks; b++) {
            int64_t dim, etag, type, count;
            if (num(r, &dim, "the entity dimension of an element block", 4) ||
                num(r, &etag, "the entity tag of an element block", 4) ||
                num(r, &type, "the element type of an element block", 4))
                return -1;
            char which[96];
            snprintf(which, sizeof which, "element block %lld (entity %lld, dimension %lld)", (long long)b + 1,
                     (long long)etag, (long long)dim);
            const gmsh_type *t = element_type(r, type, which);
            if (!t || read_count(r, "elements in the block", 1 + t->nodes, &count, 8))
                return -1;
            if (count > n - done)
                return tpk_scan_fail(&r->s, "element block %lld holds %lld elements, more than the %lld left "
                                            "of the %lld announced", (long long)b + 1, (long long)count,
                                     (long long)(n - done), (long long)n);
            int64_t physical = dim == 3 ? volume_physical(r, etag) : 0;
            for (int64_t e = 0; e < count; e++) {
                int64_t tag;
                if (num(r, &tag, "an element tag", 8) || check_tag(r, tag, "element") ||
                    read_element_nodes(r, tag, t, physical, etag))
                    return -1;
            }
            done += count;
            tpk_scan_release_consumed(&r->s);
        }
        if (done != n)
            return tpk_scan_fail(&r->s, "expected %lld elements in the element blocks, found %lld", (long long)n,
                                 (long long)done);
    }
    return expect_end(r, "$EndElements");
}

/* 4.1 $Entities: keep the first physical tag of each volume. */
static int read_entities(gmsh_reader *r)
{
    int64_t counts[4];
    static const char *const kinds[4] = {"points", "curves", "surfaces", "volumes"};
    if (r->version != 41)
        return skip_section(r, "$Entities", 9);
    if (r->volumes)
        return tpk_scan_fail(&r->s, "expected one $Entities section, found a second");
    if (bin_start(r, "$Entities"))
        return -1;
    for (int d = 0; d < 4; d++)
        if (read_count(r, kinds[d], 4, &counts[d], 8))
            return -1;
    r->volumes = malloc(sizeof *r->volumes * (size_t)(counts[3] ? counts[3] : 1));
    if (!r->volumes)
        return tpk_scan_fail(&r->s, "out of memory");
    for (int d = 0; d < 4; d++)
        for (int64_t i = 0; i < counts[d]; i++) {
            int64_t tag, np, nb, v, physical = 0;
            double x;
            if (num(r, &tag, "an entity tag", 4))
                return -1;
            for (int k = 0; k < (d ? 6 : 3); k++)
                if (real(r, &x, "an entity coordinate"))
                    return -1;
            if (read_count(r, "physical tags", 1, &np, 8))
                return -1;
            for (int64_t k = 0; k < np; k++) {
                if (num(r, &v, "a physical tag", 4))
                    return -1;
                if (k == 0)
                    physical = v;
            }
            if (d) {
                if (read_count(r, "bounding entities", 1, &nb, 8))
                    return -1;
                for (int64_t k = 0; k < nb; k++)
                    if (num(r, &v, "a bounding entity tag", 4))
                        return -1;
            }
            if (d == 3) {
                r->volumes[r->volume_count].tag = tag;
                r->volumes[r->volume_count++].physical = physical;
            }
        }
    return expect_end(r, "$EndEntities");
}

/* A string tag: "quoted, may hold spaces" or one token. */
static int read_string(gmsh_reader *r, char *dst, size_t cap)
{
    tpk_scan_skip_space(&r->s);
    const unsigned char *d = r->s.data;
    size_t p = r->s.pos;
    r->s.tok_pos = p;
    r->s.tok_line = r->s.line;
    if (p >= r->s.size)
        return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "expected a string tag, found end of file");
    size_t start, end;
    if (d[p] == '"') {
        start = p + 1;
        end = start;
        while (end < r->s.size && d[end] != '"' && d[end] != '\n')
            end++;
        if (end >= r->s.size || d[end] != '"')
            return tpk_scan_fail(&r->s, "expected a closing '\"' on the line of a string tag, found %s",
                                 end >= r->s.size ? "end of file" : "end of line");
        r->s.pos = end + 1;
    } else {
        const char *tok;
        size_t len = tpk_scan_token(&r->s, &tok);
        start = (size_t)((const unsigned char *)tok - d);
        end = start + len;
    }
    size_t len = end - start;
    if (len >= cap)
        len = cap - 1;
    memcpy(dst, d + start, len);
    dst[len] = 0;
    for (size_t i = 0; i < len; i++)
        if ((unsigned char)dst[i] < ' ')
            dst[i] = '_';
    return 0;
}

static int read_data(gmsh_reader *r, int association)
{
    const char *section = association == TPK_ASSOC_POINT ? "$NodeData" : "$ElementData";
    int64_t ns, nr, ni, v;
    char name[TPK_NAME_MAX] = "";
    double time = 0, x;
    int64_t step = 0, components = 1, count = 0;
    if (association == TPK_ASSOC_POINT ? r->point_count < 0 : !r->have_elements)
        return tpk_scan_fail(&r->s, "expected %s before %s", association == TPK_ASSOC_POINT ? "$Nodes" : "$Elements",
                             section);
    if (read_count(r, "string tags", 1, &ns, 0))
        return -1;
    for (int64_t k = 0; k < ns; k++) {
        char buf[TPK_NAME_MAX];
        if (read_string(r, buf, sizeof buf))
            return -1;
        if (k == 0)
            memcpy(name, buf, sizeof name);
    }
    if (!name[0])
        snprintf(name, sizeof name, "%s", association == TPK_ASSOC_POINT ? "node_data" : "element_data");
    if (read_count(r, "real tags", 1, &nr, 0))
        return -1;
    for (int64_t k = 0; k < nr; k++) {
        if (tpk_scan_double(&r->s, &x, "a real tag (the time)"))
            return -1;
        if (k == 0)
            time = x;
    }
    if (read_count(r, "integer tags", 1, &ni, 0))
        return -1;
    if (ni < 3)
        return tpk_scan_fail(&r->s, "%s: expected 3 or more integer tags (step, components, count), found %lld",
                             section, (long long)ni);
    for (int64_t k = 0; k < ni; k++) {
        if (tpk_scan_int64(&r->s, &v, "an integer tag"))
            return -1;
        if (k == 0)
            step = v;
        else if (k == 1)
            components = v;
        else if (k == 2)
            count = v;
    }
    if (bin_start(r, "the integer tags"))
        return -1;
    (void)step;
    if (components < 1 || components > 9)
        return tpk_scan_fail(&r->s, "%s '%s': expected 1 to 9 components, found %lld", section, name,
                             (long long)components);
    int64_t items = association == TPK_ASSOC_POINT ? r->point_count : r->cell_count;
    if (count < 0 || (uint64_t)count > bytes_left(r) / (2 * (uint64_t)(components + 1)) + 1)
        return tpk_scan_fail(&r->s, "%s '%s': %lld values cannot fit in the %zu bytes left (wrong count or "
                                    "truncated file)", section, name, (long long)count, bytes_left(r));
    if (association != TPK_ASSOC_POINT && !r->elem_sorted) {
        if (sort_tags(r, r->elem_tags, r->elem_count, "element"))
            return -1;
        r->elem_sorted = 1;
    }
    /* Each block is stored whole (items * components values): bound their sum by the file size, so that
     * many tiny blocks over a large mesh cannot claim unbounded memory. Dense blocks take at least
     * 2 bytes per value in the file, far below this bound. */
    r->block_values += (uint64_t)items * (uint64_t)components;
    if (r->block_values > 8 * (uint64_t)r->s.size + (1u << 20))
        return tpk_scan_fail(&r->s, "%s '%s': %llu field values in all for a %zu-byte file (too many data "
                                    "blocks for the mesh size)", section, name,
                             (unsigned long long)r->block_values, r->s.size);
    if (r->block_count >= 65536)
        return tpk_scan_fail(&r->s, "%s '%s': more than 65536 data blocks (fields times time steps)", section, name);
    data_block *blocks = realloc(r->blocks, sizeof *blocks * (size_t)(r->block_count + 1));
    if (!blocks)
        return tpk_scan_fail(&r->s, "out of memory");
    r->blocks = blocks;
    data_block *b = &r->blocks[r->block_count];
    memset(b, 0, sizeof *b);
    b->values = malloc(sizeof *b->values * (size_t)(items ? items : 1) * (size_t)components);
    if (!b->values)
        return tpk_scan_fail(&r->s, "out of memory");
    r->block_count++;
    memcpy(b->name, name, sizeof b->name);
    b->association = association;
    b->components = (int)components;
    b->time = time;
    for (int64_t i = 0; i < items * components; i++)
        b->values[i] = NAN;
    for (int64_t i = 0; i < count; i++) {
        int64_t tag;
        int32_t at;
        char user[96];
        if (num(r, &tag, association == TPK_ASSOC_POINT ? "a node tag" : "an element tag", 4))
            return -1;
        if (association == TPK_ASSOC_POINT) {
            snprintf(user, sizeof user, "%s '%s'", section, name);
            if ((at = node_index(r, tag, user)) < 0)
                return -1;
        } else {
            int found;
            at = lookup(r->elem_tags, r->elem_count, tag, &found);
            if (!found)
                return tpk_scan_fail(&r->s, "%s '%s' uses element tag %lld, which $Elements does not define",
                                     section, name, (long long)tag);
        }
        for (int64_t k = 0; k < components; k++) {
            if (real(r, &x, "a field value"))
                return -1;
            if (at >= 0)
                b->values[at * components + k] = (float)x;
        }
    }
    return expect_end(r, association == TPK_ASSOC_POINT ? "$EndNodeData" : "$EndElementData");
}

/* One section. Returns 0, or -1. */
static int read_section(gmsh_reader *r, const char *tok, size_t len)
{
    char q[64];
    if (tok[0] != '$')
        return tpk_scan_fail(&r->s, "expected a section ('$Name'), found '%s'", tpk_scan_quote(tok, len, q, sizeof q));
    if (tpk_token_is(tok, len, "$MeshFormat"))
        return tpk_scan_fail(&r->s, "expected one $MeshFormat section, found a second");
    if (tpk_token_is(tok, len, "$Nodes"))
        return read_nodes(r);
    if (tpk_token_is(tok, len, "$Elements"))
        return read_elements(r);
    if (tpk_token_is(tok, len, "$Entities"))
        return read_entities(r);
    if (tpk_token_is(tok, len, "$NodeData"))
        return read_data(r, TPK_ASSOC_POINT);
    if (tpk_token_is(tok, len, "$ElementData"))
        return read_data(r, TPK_ASSOC_TET);
    if (len >= 4 && !memcmp(tok, "$End", 4))
        return tpk_scan_fail(&r->s, "found '%s' without its section", tpk_scan_quote(tok, len, q, sizeof q));
    /* $PhysicalNames, $PartitionedEntities, $Periodic, $ElementNodeData, $InterpolationScheme, $Parametrizations,
     * $GhostElements, unknown sections: nothing a volume renderer uses. */
    return skip_section(r, tok, len);
}

/* Blocks of the same name and association become one field, their times the steps. */
static int build_fields(gmsh_reader *r, tpk_mesh *out)
{
    int max_steps = 1, first_multi = -1;
    int *group = calloc((size_t)(r->block_count ? r->block_count : 1), sizeof *group);
    if (!group)
        return tpk_scan_fail(&r->s, "out of memory");
    int *heads = malloc(sizeof *heads * 1024);
    int head_count = 0;
    if (!heads) {
        free(group);
        return tpk_scan_fail(&r->s, "out of memory");
    }
    for (int i = 0; i < r->block_count; i++) {
        group[i] = i;
        for (int h = 0; h < head_count; h++) {
            int j = heads[h];
            if (r->blocks[j].association == r->blocks[i].association && !strcmp(r->blocks[j].name, r->blocks[i].name)) {
                group[i] = j;
                break;
            }
        }
        if (group[i] != i)
            continue;
        if (head_count == 1024) {
            free(heads);
            free(group);
            return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "more than 1024 fields in $NodeData and "
                                                                 "$ElementData");
        }
        heads[head_count++] = i;
    }
    free(heads);
    for (int i = 0; i < r->block_count; i++) {
        if (group[i] != i)
            continue;
        int steps = 0;
        for (int j = i; j < r->block_count; j++)
            steps += group[j] == i;
        if (steps > max_steps) {
            max_steps = steps;
            first_multi = i;
        }
    }
    int rc = 0;
    for (int i = 0; i < r->block_count && !rc; i++) {
        if (group[i] != i)
            continue;
        data_block *b = &r->blocks[i];
        int steps = 0;
        for (int j = i; j < r->block_count; j++)
            if (group[j] == i && r->blocks[j].components != b->components) {
                rc = tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "field '%s': %d components in one step, %d in "
                                      "another", b->name, b->components, r->blocks[j].components);
                break;
            } else
                steps += group[j] == i;
        if (rc)
            break;
        if (steps != 1 && steps != max_steps) {
            tpk_diag_warn(r->s.diag, "%s: field '%s' has %d time steps, others %d: only its first is kept",
                          r->s.name, b->name, steps, max_steps);
            steps = 1;
        }
        int64_t items = b->association == TPK_ASSOC_POINT ? r->point_count : r->cell_count;
        size_t per = (size_t)items * (size_t)b->components;
        float *values = malloc(sizeof *values * (per ? per : 1) * (size_t)steps);
        if (!values) {
            rc = tpk_scan_fail(&r->s, "out of memory");
            break;
        }
        int s = 0;
        for (int j = i; j < r->block_count && s < steps; j++)
            if (group[j] == i)
                memcpy(values + per * (size_t)s++, r->blocks[j].values, sizeof *values * per);
        if (tpk_mesh_add_field(out, b->name, b->association, b->components, steps, values)) {
            free(values);
            rc = tpk_scan_fail(&r->s, "out of memory");
        }
    }
    if (!rc && max_steps > 1) {
        out->times = malloc(sizeof *out->times * (size_t)max_steps);
        if (!out->times)
            rc = tpk_scan_fail(&r->s, "out of memory");
        int s = 0;
        for (int j = first_multi; !rc && j < r->block_count; j++)
            if (group[j] == first_multi)
                out->times[s++] = r->blocks[j].time;
    }
    out->step_count = max_steps;
    free(group);
    return rc;
}

static int finish(gmsh_reader *r, tpk_mesh *out)
{
    if (r->point_count < 0)
        return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "expected a $Nodes section, found end of file");
    if (!r->have_elements)
        return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "expected an $Elements section, found end of file");
    if (r->dropped)
        tpk_diag_warn(r->s.diag, "%s: dropped %lld point, line and surface elements", r->s.name,
                      (long long)r->dropped);
    if (r->reduced)
        tpk_diag_warn(r->s.diag, "%s: reduced %lld higher-order elements to their corner nodes", r->s.name,
                      (long long)r->reduced);
    out->point_count = r->point_count;
    out->points = r->points;
    out->cell_count = r->cell_count;
    out->cell_types = r->types;
    out->cell_offsets = r->offsets;
    out->cell_conn = r->conn;
    r->points = NULL;
    r->types = NULL;
    r->offsets = NULL;
    r->conn = NULL;
    if (!out->cell_offsets && !(out->cell_offsets = calloc(1, sizeof *out->cell_offsets)))
        return tpk_scan_fail(&r->s, "out of memory");
    if (!out->cell_types && !(out->cell_types = malloc(1)))
        return tpk_scan_fail(&r->s, "out of memory");
    if (!out->cell_conn && !(out->cell_conn = malloc(sizeof *out->cell_conn)))
        return tpk_scan_fail(&r->s, "out of memory");
    if (!r->physical && !(r->physical = malloc(sizeof *r->physical)))
        return tpk_scan_fail(&r->s, "out of memory");
    if (!r->entity && !(r->entity = malloc(sizeof *r->entity)))
        return tpk_scan_fail(&r->s, "out of memory");
    if (tpk_mesh_add_field(out, "physical", TPK_ASSOC_TET, 1, 1, r->physical))
        return tpk_scan_fail(&r->s, "out of memory");
    r->physical = NULL;
    if (tpk_mesh_add_field(out, "entity", TPK_ASSOC_TET, 1, 1, r->entity))
        return tpk_scan_fail(&r->s, "out of memory");
    r->entity = NULL;
    if (build_fields(r, out))
        return -1;
    snprintf(out->format, sizeof out->format, "gmsh-%s-%s", r->version == 22 ? "2.2" : "4.1",
             r->binary ? "binary" : "ascii");
    return 0;
}

static void reader_free(gmsh_reader *r)
{
    free(r->points);
    free(r->node_tags);
    free(r->types);
    free(r->offsets);
    free(r->conn);
    free(r->physical);
    free(r->entity);
    free(r->elem_tags);
    free(r->volumes);
    for (int i = 0; i < r->block_count; i++)
        free(r->blocks[i].values);
    free(r->blocks);
}

static int import_buffer(const char *name, const char *data, size_t size, int mapped, tpk_mesh *out,
                         tpk_diag *diag)
{
    if (!out)
        return tpk_diag_fail(diag, "%s: no output mesh given", name ? name : "(input)");
    memset(out, 0, sizeof *out);
    if (diag)
        diag->message[0] = 0;
    gmsh_reader r;
    memset(&r, 0, sizeof r);
    tpk_scan_init(&r.s, name, data, size, diag);
    r.s.mapped = mapped;
    r.point_count = -1;
    const char *tok;
    char q[64];
    size_t len = tpk_scan_token(&r.s, &tok);
    int rc;
    if (!len || !tpk_token_is(tok, len, "$MeshFormat"))
        rc = tpk_scan_fail(&r.s, "expected '$MeshFormat' (a Gmsh .msh file), found '%s'",
                           len ? tpk_scan_quote(tok, len, q, sizeof q) : "end of file");
    else
        rc = read_format(&r);
    while (rc == 0) {
        len = tpk_scan_token(&r.s, &tok);
        if (!len)
            break;
        rc = read_section(&r, tok, len);
        tpk_scan_release_consumed(&r.s);
    }
    if (rc == 0)
        rc = finish(&r, out);
    reader_free(&r);
    if (rc != 0)
        tpk_mesh_free(out);
    return rc ? -1 : 0;
}

int tpk_import_gmsh_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    return import_buffer(name, data, size, 0, out, diag);
}

int tpk_import_gmsh(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    return tpk_import_mapped(path, import_buffer, out, diag);
}
