/* Abaqus / CalculiX .inp importer: *NODE and *ELEMENT blocks (solid elements C3D4/6/8/10/15/20/27 and
 * their R/H/I/... variants, higher-order ones whole), element sets (a cell field "elset")
 * and *INCLUDE. Keywords are case-insensitive, "**" starts a comment, data lines are comma-separated and
 * an element's node list may run over several lines. Node and element ids are arbitrary positive
 * integers, mapped to 0-based indices at the end. Other keywords (materials, steps...) are skipped. */
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "tetpack_format.h"

#include "base/text_scan.h"
#include "import_file.h"
#include "importers.h"
#include "mesh/cell_types.h"

/* Nested *INCLUDE depth and the files one reading may open in all (a file included twice at each of 10
 * levels would otherwise be read 2^10 times). */
#define INP_MAX_DEPTH 10
#define INP_MAX_FILES 1000
#define INP_MAX_NODES 27 /* C3D27 */
#define INP_MAX_SETS 65535

typedef struct id_index {
    int64_t id, index;
} id_index;

/* Elements first..last (every step-th) put in set `set`; one id is first == last. Kept as ranges: a
 * GENERATE line of a few bytes may span any number of ids. */
typedef struct elset_range {
    int64_t first, last, step;
    int set;
} elset_range;

typedef struct inp_reader {
    tpk_diag *diag;
    const char *chain[INP_MAX_DEPTH + 1]; /* the files being read, outermost first: a cycle check */
    int depth, files;
    /* nodes as read: their ids, coordinates */
    int64_t node_count, node_cap;
    id_index *node_ids; /* (id, index) */
    double *points;
    /* cells: node ids as written until finish() maps them */
    int64_t cell_count, cell_cap, conn_count, conn_cap;
    uint8_t *types;
    int64_t *offsets;
    int64_t *conn;
    id_index *cell_ids;
    float *cell_sets; /* 1-based set number, 0: in no set */
    elset_range *members; /* from *ELSET lists, in file order (a later one wins) */
    int64_t member_count, member_cap;
    char (*set_names)[TPK_NAME_MAX];
    int set_count;
    int64_t dropped; /* non-solid elements */
    int64_t subset_cells; /* C3D27 with a face node left out, read as C3D20 (their centre node unused) */
    int parts;       /* *PART keywords: each part numbers its nodes and elements on its own */
    int64_t dropped_by_type[256];
} inp_reader;

/* What the current keyword's data lines are. */
enum { DATA_SKIP, DATA_NODE, DATA_ELEMENT, DATA_ELSET };

typedef struct inp_block {
    int kind;
    int cell_type;        /* DATA_ELEMENT: VTK type kept, 0: dropped */
    int nodes, corners;   /* nodes per element as written, nodes kept */
    int set;              /* 1-based set number, 0: none */
    int generate;         /* *ELSET, GENERATE */
    char type_name[32];
    int64_t record[1 + INP_MAX_NODES]; /* an element: its id, then its nodes (may span lines) */
    int filled;
    size_t record_pos;    /* where it started, for messages */
    int64_t record_line;
} inp_block;

/* Grow an array of `*cap` items of `item` bytes to hold `need`. */
static int grow(void **array, int64_t *cap, int64_t need, size_t item)
{
    if (need <= *cap)
        return 0;
    int64_t n = *cap ? *cap : 1024;
    while (n < need)
        n *= 2;
    void *bigger = realloc(*array, (size_t)n * item);
    if (!bigger)
        return -1;
    *array = bigger;
    *cap = n;
    return 0;
}

/* The fields of one comma-separated line, blanks trimmed; an empty last field (a trailing comma) is not
 * counted. Returns the count (at most cap). */
static int split_fields(const char *line, size_t len, const char **field, size_t *flen, int cap)
{
    int n = 0;
    size_t at = 0;
    while (at <= len && n < cap) {
        size_t end = at;
        while (end < len && line[end] != ',')
            end++;
        size_t a = at, b = end;
        while (a < b && (line[a] == ' ' || line[a] == '\t'))
            a++;
        while (b > a && (line[b - 1] == ' ' || line[b - 1] == '\t' || line[b - 1] == '\r'))
            b--;
        if (end == len && a == b && n > 0)
            break;
        field[n] = line + a;
        flen[n++] = b - a;
        at = end + 1;
    }
    return n;
}

/* "KEY=VALUE" parameter `key` of a keyword line's fields (from the second on): its value, or NULL.
 * A parameter without '=' matches with an empty value. */
static const char *param(const char **field, const size_t *flen, int n, const char *key, size_t *vlen)
{
    size_t klen = strlen(key);
    for (int i = 1; i < n; i++) {
        const char *f = field[i];
        size_t k = 0;
        while (k < flen[i] && f[k] != '=' && f[k] != ' ')
            k++;
        if (k != klen || strncasecmp(f, key, klen) != 0)
            continue;
        const char *v = memchr(f, '=', flen[i]);
        if (!v) {
            *vlen = 0;
            return f + flen[i];
        }
        v++;
        while (v < f + flen[i] && *v == ' ')
            v++;
        *vlen = (size_t)(f + flen[i] - v);
        if (*vlen >= 2 && *v == '"' && v[*vlen - 1] == '"')
            v++, *vlen -= 2;
        return v;
    }
    return NULL;
}

/* The VTK type of an Abaqus element type: C3D<n> with any prefix (DC3D: heat transfer) and suffix
 * (R, H, I, T...). Abaqus numbers the corners first, in VTK's order for tets and hexahedra; its wedge
 * (C3D6) has the same corner order too: checked by converting gmsh-written files with no cell turned
 * over (tests/cli/inp.sh). Its quadratic solids list their mid-edge nodes as VTK does (C3D10: 01 12 20
 * 03 13 23; C3D20: bottom, top, then vertical edges; C3D15 likewise), so they are kept whole as VTK's
 * quadratic types. A C3D27 (the manual's "21 to 27-node brick": its face nodes may be left out, its
 * centre may not) has the C3D20's 20, then node 21 at the centroid, then 22-27 at the centres of faces
 * 1-6 (1234, 5876, 1562, 2673, 3784, 4851): the order gmsh's .inp writer uses (MHexahedron27::
 * getVertexINP), checked on a gmsh-written C3D27 mesh against gmsh's own .msh of it (tests/cli/inp.sh).
 * It is kept whole as VTK's triquadratic hexahedron (inp_hex27_to_vtk); one with a face node left out
 * (0) is read as its C3D20. Returns the type (0: not a solid, dropped); *corners the nodes kept. */
static int solid_type(const char *name, size_t len, int *nodes, int *corners)
{
    static const struct {
        int nodes, type, corners;
    } solids[] = {{4, TPK_CELL_TETRA, 4}, {10, 24, 10},  {6, TPK_CELL_WEDGE, 6}, {15, 26, 15},
                  {8, TPK_CELL_HEXAHEDRON, 8}, {20, 25, 20}, {27, 29, 27}};
    size_t at = 0;
    while (at + 3 <= len && strncasecmp(name + at, "C3D", 3) != 0)
        at++;
    if (at + 3 > len || (at > 0 && !(at == 1 && (name[0] == 'D' || name[0] == 'd'))))
        return 0;
    int n = 0;
    for (at += 3; at < len && name[at] >= '0' && name[at] <= '9' && n < 1000; at++)
        n = 10 * n + (name[at] - '0');
    for (size_t i = 0; i < sizeof solids / sizeof solids[0]; i++)
        if (solids[i].nodes == n) {
            *nodes = n;
            *corners = solids[i].corners;
            return solids[i].type;
        }
    *nodes = n;
    return -1; /* a solid of a kind not read (C3D5 pyramids...) */
}

/* The number of set `name` (adding it); -1 when there are too many. */
static int set_number(inp_reader *r, const char *name, size_t len)
{
    if (len >= TPK_NAME_MAX)
        len = TPK_NAME_MAX - 1;
    for (int i = 0; i < r->set_count; i++)
        if (strlen(r->set_names[i]) == len && strncasecmp(r->set_names[i], name, len) == 0)
            return i + 1;
    if (r->set_count >= INP_MAX_SETS)
        return -1;
    void *names = realloc(r->set_names, sizeof *r->set_names * (size_t)(r->set_count + 1));
    if (!names)
        return -1;
    r->set_names = names;
    memcpy(r->set_names[r->set_count], name, len);
    r->set_names[r->set_count][len] = 0;
    return ++r->set_count;
}

static int field_int(tpk_scan *s, const char *f, size_t len, int64_t *v, const char *what)
{
    char q[64];
    if (tpk_parse_int64(f, len, v) == 0)
        return 0;
    return tpk_scan_fail(s, "expected %s, found '%s'", what, len ? tpk_scan_quote(f, len, q, sizeof q) : "nothing");
}

static int read_node(inp_reader *r, tpk_scan *s, const char **field, const size_t *flen, int n)
{
    int64_t id;
    if (field_int(s, field[0], flen[0], &id, "a node id (an integer)"))
        return -1;
    if (n < 3)
        return tpk_scan_fail(s, "*NODE %lld: expected an id and 2 or 3 coordinates, found %d values",
                             (long long)id, n);
    if (r->node_count >= INT32_MAX)
        return tpk_scan_fail(s, "more than 2^31-1 nodes");
    int64_t old_cap = r->node_cap;
    if (grow((void **)&r->node_ids, &r->node_cap, r->node_count + 1, sizeof *r->node_ids))
        return tpk_scan_fail(s, "out of memory for %lld nodes", (long long)r->node_count + 1);
    if (r->node_cap != old_cap) {
        double *points = realloc(r->points, sizeof *points * 3 * (size_t)r->node_cap);
        if (!points)
            return tpk_scan_fail(s, "out of memory for %lld nodes", (long long)r->node_count + 1);
        r->points = points;
    }
    double *p = r->points + 3 * r->node_count;
    p[2] = 0;
    for (int k = 0; k < 3 && k + 1 < n; k++) {
        char q[64];
        if (tpk_parse_double(field[k + 1], flen[k + 1], &p[k]) != 0)
            return tpk_scan_fail(s, "*NODE %lld: expected a coordinate, found '%s'", (long long)id,
                                 tpk_scan_quote(field[k + 1], flen[k + 1], q, sizeof q));
    }
    r->node_ids[r->node_count] = (id_index){id, r->node_count};
    r->node_count++;
    return 0;
}

/* VTK's triquadratic hexahedron's nodes 20-26 (centres of faces x-, x+, y-, y+, z-, z+, the centroid)
 * as a C3D27's node indices (0-based: 26 is node 27, the centre of face 4851). */
static const int inp_hex27_to_vtk[7] = {26, 24, 23, 25, 21, 22, 20};

/* An element record is complete: keep its nodes (or count it as dropped). */
static int add_element(inp_reader *r, tpk_scan *s, inp_block *b)
{
    if (!b->cell_type) {
        r->dropped++;
        return 0;
    }
    int type = b->cell_type, kept = b->corners;
    int64_t *node = b->record + 1;
    if (type == 29) {
        int64_t face[7];
        for (int k = 0; k < 7; k++)
            face[k] = node[inp_hex27_to_vtk[k]];
        int omitted = 0;
        for (int k = 0; k < 7; k++)
            omitted |= face[k] == 0;
        if (omitted) /* a face or centre node left out: its C3D20 */
            type = 25, kept = 20;
        else
            memcpy(node + 20, face, sizeof face);
    }
    if (r->cell_count >= INT32_MAX)
        return tpk_scan_fail(s, "more than 2^31-1 elements");
    int64_t cells = r->cell_count + 1, old_cap = r->cell_cap;
    if (grow((void **)&r->cell_ids, &r->cell_cap, cells, sizeof *r->cell_ids))
        return tpk_scan_fail(s, "out of memory for %lld elements", (long long)cells);
    if (r->cell_cap != old_cap) {
        uint8_t *types = realloc(r->types, (size_t)r->cell_cap);
        if (types)
            r->types = types;
        float *sets = realloc(r->cell_sets, sizeof *sets * (size_t)r->cell_cap);
        if (sets)
            r->cell_sets = sets;
        int64_t *offsets = realloc(r->offsets, sizeof *offsets * (size_t)(r->cell_cap + 1));
        if (offsets)
            r->offsets = offsets;
        if (!types || !sets || !offsets)
            return tpk_scan_fail(s, "out of memory for %lld elements", (long long)cells);
    }
    if (grow((void **)&r->conn, &r->conn_cap, r->conn_count + kept, sizeof *r->conn))
        return tpk_scan_fail(s, "out of memory for %lld elements", (long long)cells);
    memcpy(r->conn + r->conn_count, node, sizeof *r->conn * (size_t)kept);
    r->cell_ids[r->cell_count] = (id_index){b->record[0], r->cell_count};
    r->types[r->cell_count] = (uint8_t)type;
    r->cell_sets[r->cell_count] = (float)b->set;
    r->offsets[r->cell_count] = r->conn_count;
    r->conn_count += kept;
    r->offsets[++r->cell_count] = r->conn_count;
    r->subset_cells += b->nodes > kept;
    return 0;
}

/* Element data: an id then the nodes, over as many lines as it takes; each element starts a line. */
static int read_element_line(inp_reader *r, tpk_scan *s, inp_block *b, const char **field, const size_t *flen,
                             int n)
{
    for (int i = 0; i < n; i++) {
        if (b->filled == 0 && i > 0) /* values left on the line of a complete element */
            return tpk_scan_fail(s, "element %lld (%s): expected %d node ids, found %d or more (each element "
                                    "starts a data line; is the element of another type than its *ELEMENT says?)",
                                 (long long)b->record[0], b->type_name, b->nodes, b->nodes + n - i);
        if (b->filled == 0) {
            b->record_pos = s->tok_pos;
            b->record_line = s->tok_line;
        }
        if (field_int(s, field[i], flen[i], &b->record[b->filled],
                      b->filled ? "a node id (an integer)" : "an element id (an integer)"))
            return -1;
        if (++b->filled == b->nodes + 1) {
            if (add_element(r, s, b))
                return -1;
            b->filled = 0;
        }
    }
    return 0;
}

static int add_member(inp_reader *r, tpk_scan *s, int64_t first, int64_t last, int64_t step, int set)
{
    if (grow((void **)&r->members, &r->member_cap, r->member_count + 1, sizeof *r->members))
        return tpk_scan_fail(s, "out of memory for element set members");
    r->members[r->member_count++] = (elset_range){first, last, step, set};
    return 0;
}

/* *ELSET data: element ids, or with GENERATE first, last[, step]. Names of other sets are not expanded. */
static int read_elset_line(inp_reader *r, tpk_scan *s, inp_block *b, const char **field, const size_t *flen,
                           int n)
{
    int64_t v[3] = {0, 0, 1};
    if (b->generate) {
        if (n < 2 || n > 3)
            return tpk_scan_fail(s, "*ELSET, GENERATE: expected first, last[, step], found %d values", n);
        for (int i = 0; i < n; i++)
            if (field_int(s, field[i], flen[i], &v[i], "an element id (an integer)"))
                return -1;
        if (v[2] < 1 || v[1] < v[0])
            return tpk_scan_fail(s, "*ELSET, GENERATE: expected first <= last and a step of 1 or more, found %lld, "
                                    "%lld, %lld",
                                 (long long)v[0], (long long)v[1], (long long)v[2]);
        return add_member(r, s, v[0], v[1], v[2], b->set);
    }
    for (int i = 0; i < n; i++) {
        int64_t e;
        if (tpk_parse_int64(field[i], flen[i], &e) != 0) {
            char q[64];
            tpk_diag_warn(r->diag, "%s:%lld: *ELSET %s: member set '%s' not expanded", s->name, (long long)s->line,
                          r->set_names[b->set - 1], tpk_scan_quote(field[i], flen[i], q, sizeof q));
            continue;
        }
        if (add_member(r, s, e, e, 1, b->set))
            return -1;
    }
    return 0;
}

static int read_file(inp_reader *r, const char *name, const char *data, size_t size);

/* *INCLUDE, INPUT=file: relative to the including file's folder. */
static int include_file(inp_reader *r, tpk_scan *s, const char *file, size_t len)
{
    if (!len)
        return tpk_scan_fail(s, "*INCLUDE: expected INPUT=<file>, found none");
    if (r->depth >= INP_MAX_DEPTH)
        return tpk_scan_fail(s, "*INCLUDE: more than %d nested includes", INP_MAX_DEPTH);
    if (++r->files > INP_MAX_FILES)
        return tpk_scan_fail(s, "*INCLUDE: more than %d files included in all", INP_MAX_FILES);
    char path[4096];
    const char *slash = strrchr(s->name, '/');
    int dir = file[0] == '/' || !slash ? 0 : (int)(slash - s->name + 1);
    if (snprintf(path, sizeof path, "%.*s%.*s", dir, s->name, (int)len, file) >= (int)sizeof path)
        return tpk_scan_fail(s, "*INCLUDE: the path is too long");
    for (int i = 0; i <= r->depth; i++)
        if (!strcmp(r->chain[i], path))
            return tpk_scan_fail(s, "*INCLUDE: %s includes itself (through %d files)", path, r->depth - i + 1);
    const char *bytes;
    size_t n;
    if (tpk_map_file(path, &bytes, &n, r->diag) != 0) {
        char why[sizeof r->diag->message];
        snprintf(why, sizeof why, "%s", r->diag ? r->diag->message : "");
        return tpk_scan_fail(s, "*INCLUDE: %.700s", why);
    }
    r->chain[++r->depth] = path;
    int rc = read_file(r, path, bytes, n);
    r->depth--;
    tpk_unmap_file(bytes, n);
    return rc;
}

/* A keyword line ("*ELEMENT, TYPE=C3D4, ELSET=x"): sets up the block its data lines belong to. */
static int read_keyword(inp_reader *r, tpk_scan *s, inp_block *b, const char *line, size_t len)
{
    const char *field[16];
    size_t flen[16], vlen;
    char q[64];
    if (b->filled)
        return tpk_scan_fail_at(s, b->record_pos, b->record_line,
                                "element %lld (%s): expected %d node ids, found %d before the next keyword",
                                (long long)b->record[0], b->type_name, b->nodes, b->filled - 1);
    int n = split_fields(line + 1, len - 1, field, flen, 16);
    memset(b, 0, sizeof *b);
    const char *key = n ? field[0] : "";
    size_t klen = n ? flen[0] : 0;
    const char *v;
    if (tpk_token_is(key, klen, "NODE")) {
        b->kind = DATA_NODE;
    } else if (tpk_token_is(key, klen, "ELEMENT")) {
        b->kind = DATA_ELEMENT;
        if (!(v = param(field, flen, n, "TYPE", &vlen)) || !vlen)
            return tpk_scan_fail(s, "*ELEMENT: expected TYPE=<element type>, found none");
        snprintf(b->type_name, sizeof b->type_name, "%.*s", (int)(vlen < 31 ? vlen : 31), v);
        b->cell_type = solid_type(v, vlen, &b->nodes, &b->corners);
        if (b->cell_type < 0)
            return tpk_scan_fail(s, "*ELEMENT: type %s is a solid this reader does not read (it reads C3D4, "
                                    "C3D6, C3D8, C3D10, C3D15, C3D20 and C3D27 and their variants)",
                                 b->type_name);
    } else if (tpk_token_is(key, klen, "ELSET")) {
        b->kind = DATA_ELSET;
        b->generate = param(field, flen, n, "GENERATE", &vlen) != NULL;
    } else if (tpk_token_is(key, klen, "INCLUDE")) {
        v = param(field, flen, n, "INPUT", &vlen);
        return include_file(r, s, v ? v : "", v ? vlen : 0);
    } else if (!klen) {
        return tpk_scan_fail(s, "expected a keyword after '*', found '%s'", tpk_scan_quote(line, len, q, sizeof q));
    } else if (tpk_token_is(key, klen, "PART")) {
        r->parts++;
    }
    if (b->kind != DATA_SKIP && param(field, flen, n, "INPUT", &vlen))
        return tpk_scan_fail(s, "*%.*s, INPUT=: data read from another file is not supported here; *INCLUDE it "
                                "instead", (int)(klen < 20 ? klen : 20), key);
    if ((b->kind == DATA_ELEMENT || b->kind == DATA_ELSET) && (v = param(field, flen, n, "ELSET", &vlen)) && vlen &&
        (b->set = set_number(r, v, vlen)) < 0)
        return tpk_scan_fail(s, "more than %d element sets, or out of memory", INP_MAX_SETS);
    if (b->kind == DATA_ELSET && !b->set)
        return tpk_scan_fail(s, "*ELSET: expected ELSET=<name>, found none");
    return 0;
}

static int read_data(inp_reader *r, tpk_scan *s, inp_block *b, const char *line, size_t len)
{
    const char *field[1 + INP_MAX_NODES];
    size_t flen[1 + INP_MAX_NODES];
    int n = split_fields(line, len, field, flen, 1 + INP_MAX_NODES);
    switch (b->kind) {
    case DATA_NODE:
        return read_node(r, s, field, flen, n);
    case DATA_ELEMENT:
        if (!b->cell_type) { /* a dropped element: one line each (surface, beam and truss elements fit) */
            r->dropped++;
            return 0;
        }
        return read_element_line(r, s, b, field, flen, n);
    case DATA_ELSET:
        return read_elset_line(r, s, b, field, flen, n);
    }
    return 0;
}

static int read_file(inp_reader *r, const char *name, const char *data, size_t size)
{
    tpk_scan s;
    tpk_scan_init(&s, name, data, size, r->diag);
    inp_block *b = calloc(1, sizeof *b);
    if (!b)
        return tpk_diag_fail(r->diag, "%s: out of memory", name);
    int rc = 0;
    while (rc == 0 && s.pos < s.size) {
        const char *line = (const char *)s.data + s.pos;
        const char *nl = memchr(line, '\n', s.size - s.pos);
        size_t len = nl ? (size_t)(nl - line) : s.size - s.pos;
        s.tok_pos = s.pos;
        s.tok_line = s.line;
        size_t lead = 0;
        while (lead < len && (line[lead] == ' ' || line[lead] == '\t' || line[lead] == '\r'))
            lead++;
        if (lead == len || (len >= 2 && line[0] == '*' && line[1] == '*'))
            ; /* blank or a comment */
        else if (line[0] == '*')
            rc = read_keyword(r, &s, b, line, len);
        else
            rc = read_data(r, &s, b, line, len);
        s.pos += len + (nl != NULL);
        s.line++;
    }
    if (rc == 0 && b->filled)
        rc = tpk_scan_fail_at(&s, b->record_pos, b->record_line,
                              "element %lld (%s): expected %d node ids, found %d before the end of the file",
                              (long long)b->record[0], b->type_name, b->nodes, b->filled - 1);
    free(b);
    return rc;
}

static int compare_ids(const void *a, const void *b)
{
    const id_index *x = a, *y = b;
    return x->id < y->id ? -1 : x->id > y->id;
}

static int64_t find_id(const id_index *sorted, int64_t n, int64_t id)
{
    if (n == 0)
        return -1; /* no array at all: bsearch must not see NULL */
    const id_index key = {id, 0};
    const id_index *hit = bsearch(&key, sorted, (size_t)n, sizeof *sorted, compare_ids);
    return hit ? hit->index : -1;
}

/* Sort ids for lookup; a repeated id is an error. */
static int sort_ids(inp_reader *r, const char *name, id_index *ids, int64_t n, const char *what)
{
    if (n)
        qsort(ids, (size_t)n, sizeof *ids, compare_ids);
    for (int64_t i = 1; i < n; i++)
        if (ids[i].id == ids[i - 1].id)
            return tpk_diag_fail(r->diag, "%s: %s id %lld is defined twice%s", name, what, (long long)ids[i].id,
                                 r->parts > 1 ? " (the file has several *PART blocks, each numbering its own ids: "
                                                "an assembly of parts is not read yet; export the flattened "
                                                "input file)"
                                              : "");
    return 0;
}

/* Put the cells of one *ELSET range into its set: walk the sorted element ids from the first in range.
 * Returns 1 for a single id that names no solid element (dropped shells are listed too), else 0. */
static int apply_range(inp_reader *r, const elset_range *m)
{
    int64_t lo = 0, hi = r->cell_count;
    while (lo < hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (r->cell_ids[mid].id < m->first)
            lo = mid + 1;
        else
            hi = mid;
    }
    int hit = 0;
    for (int64_t i = lo; i < r->cell_count && r->cell_ids[i].id <= m->last; i++)
        if (((uint64_t)r->cell_ids[i].id - (uint64_t)m->first) % (uint64_t)m->step == 0) { /* id >= first */
            r->cell_sets[r->cell_ids[i].index] = (float)m->set;
            hit = 1;
        }
    return !hit && m->first == m->last;
}

/* Node ids to 0-based indices, *ELSET members onto their cells; the mesh takes over the arrays. */
static int finish(inp_reader *r, const char *name, tpk_mesh *out)
{
    if (sort_ids(r, name, r->node_ids, r->node_count, "node") ||
        sort_ids(r, name, r->cell_ids, r->cell_count, "element"))
        return -1;
    int32_t *conn = malloc(sizeof *conn * (size_t)(r->conn_count ? r->conn_count : 1));
    if (!conn)
        return tpk_diag_fail(r->diag, "%s: out of memory", name);
    for (int64_t c = 0; c < r->cell_count; c++)
        for (int64_t k = r->offsets[c]; k < r->offsets[c + 1]; k++) {
            int64_t v = find_id(r->node_ids, r->node_count, r->conn[k]);
            if (v < 0) {
                free(conn);
                int64_t element = 0;
                for (int64_t i = 0; i < r->cell_count; i++)
                    if (r->cell_ids[i].index == c)
                        element = r->cell_ids[i].id;
                return tpk_diag_fail(r->diag, "%s: element %lld uses node %lld, which no *NODE line defines",
                                     name, (long long)element, (long long)r->conn[k]);
            }
            conn[k] = (int32_t)v;
        }
    int64_t unknown = 0;
    for (int64_t i = 0; i < r->member_count; i++)
        unknown += apply_range(r, &r->members[i]);
    if (unknown) /* sets of dropped surface elements list them too */
        tpk_diag_warn(r->diag, "%s: %lld *ELSET members are not solid elements (ignored)", name, (long long)unknown);
    if (r->dropped)
        tpk_diag_warn(r->diag, "%s: dropped %lld elements that are not solids (surfaces, shells, beams...)", name,
                      (long long)r->dropped);
    if (r->subset_cells)
        tpk_diag_warn(r->diag, "%s: %lld C3D27 elements with face nodes left out (0) read as C3D20, without "
                               "their face and centre nodes", name, (long long)r->subset_cells);
    if (tpk_import_take_cells(out, r->node_count, &r->points, r->cell_count, &r->types, &r->offsets, &conn))
        return tpk_diag_fail(r->diag, "%s: out of memory", name);
    if (r->set_count) {
        if (tpk_mesh_add_field(out, "elset", TPK_ASSOC_TET, 1, 1, r->cell_sets))
            return tpk_diag_fail(r->diag, "%s: out of memory", name);
        r->cell_sets = NULL;
    }
    out->step_count = 1;
    snprintf(out->format, sizeof out->format, "abaqus-inp");
    return 0;
}

static void reader_free(inp_reader *r)
{
    free(r->node_ids);
    free(r->points);
    free(r->types);
    free(r->offsets);
    free(r->conn);
    free(r->cell_ids);
    free(r->cell_sets);
    free(r->members);
    free(r->set_names);
}

static int import_buffer(const char *name, const char *data, size_t size, int mapped, tpk_mesh *out,
                         tpk_diag *diag)
{
    (void)mapped;
    if (tpk_import_begin(name, out, diag) != 0)
        return -1;
    inp_reader *r = calloc(1, sizeof *r);
    if (!r)
        return tpk_diag_fail(diag, "%s: out of memory", name);
    r->diag = diag;
    r->chain[0] = name;
    int rc = read_file(r, name, data, size);
    if (rc == 0 && r->node_count == 0 && r->cell_count == 0)
        rc = tpk_diag_fail(diag, "%s: expected *NODE and *ELEMENT keywords (an Abaqus/CalculiX .inp file), "
                                 "found none", name);
    if (rc == 0)
        rc = finish(r, name, out);
    reader_free(r);
    free(r);
    return tpk_import_end(rc, out);
}

int tpk_import_inp_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    return import_buffer(name, data, size, 0, out, diag);
}

int tpk_import_inp(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    return tpk_import_mapped(path, import_buffer, out, diag);
}
