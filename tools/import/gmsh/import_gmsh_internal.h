/* Private to the Gmsh importer (import_gmsh*.c): the reader state and the functions the pieces share.
 * Who owns what, top to bottom (a file calls only the files below it, never back up):
 *   import_gmsh.c       tpk_import_gmsh*, $MeshFormat, the section loop, the final mesh (static)
 *   import_gmsh_data.c  gmsh_read_data, gmsh_build_fields ($NodeData/$ElementData, the fields)
 *   import_gmsh_mesh.c  gmsh_read_nodes, gmsh_read_elements, gmsh_read_entities, gmsh_sort_tags,
 *                       gmsh_node_index
 *   import_gmsh_bulk.c  gmsh_bulk_node_tags, gmsh_bulk_coords, gmsh_bulk_elements (4.1 blocks on all
 *                       threads), gmsh_lookup, gmsh_node_at, gmsh_index_nodes, gmsh_list_node_run
 *   import_gmsh_scan.c  gmsh_bytes_left, gmsh_bin_bytes, gmsh_num, gmsh_real, gmsh_bin_start,
 *                       gmsh_read_count, gmsh_expect_end, gmsh_skip_section
 * Not installed. Every function returning int that can fail returns 0, or -1 with the message in r->s. */
#ifndef TPK_IMPORT_GMSH_INTERNAL_H
#define TPK_IMPORT_GMSH_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "import/importers.h"
#include "tetpack_format.h"
#include "base/text_scan.h"

typedef struct tag_index {
    int64_t tag;
    int32_t index; /* node index, or cell index (-1: a dropped element) */
} tag_index;

/* A Gmsh element type. vtk 0: dropped (points, lines, surfaces). */
typedef struct gmsh_type {
    int type, nodes, vtk, kept; /* kept: the nodes kept, in VTK order */
    const char *name;
    const signed char *order;   /* VTK node k is Gmsh node order[k]; NULL: the same */
} gmsh_type;

/* The Gmsh node that VTK node k of a kept element is. */
static inline int gmsh_node_of(const gmsh_type *t, int k)
{
    return t->order ? t->order[k] : k;
}

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
    int32_t *node_at;     /* not dense, but tags up to 4 a node: node_at[tag] (-1: none) for tag 0..node_at_max */
    int64_t node_at_max;
    int have_elements;
    int64_t cell_count, conn_count, cell_cap, conn_cap;
    uint8_t *types;
    int64_t *offsets;
    int32_t *conn;
    float *physical, *entity;
    /* Every element (dropped ones too), sorted once needed. Listed only once the elements stop being a
     * run: while each is a kept cell whose tag is elem_first_tag plus its index (a mesh of volume
     * elements numbered in order), the table would be the identity, and building it cost 16 bytes of
     * fresh memory per element. */
    tag_index *elem_tags;
    int64_t elem_count, elem_cap, elem_first_tag;
    int elem_listed;
    int elem_sorted;
    int64_t dropped;
    entity_phys *volumes; /* 4.1 $Entities: volume tag -> first physical tag */
    int64_t volume_count;
    data_block *blocks;
    int block_count;
    uint64_t block_values; /* sum of items * components over the blocks */
} gmsh_reader;

/* ---- Numbers, counts, section ends (import_gmsh_scan.c) ----------------------------------------- */

size_t gmsh_bytes_left(const gmsh_reader *r);
/* Binary data: `n` bytes at the current position into dst, or the message "expected <what>". */
int gmsh_bin_bytes(gmsh_reader *r, void *dst, size_t n, const char *what);
/* An integer: ASCII, or in binary files (width 4: int, 8: size_t) a binary one; width 0: ASCII always. */
int gmsh_num(gmsh_reader *r, int64_t *v, const char *what, int width);
/* A double: ASCII, or 8 binary bytes in binary files. */
int gmsh_real(gmsh_reader *r, double *v, const char *what);
/* Binary data starts after the end of the current line. */
int gmsh_bin_start(gmsh_reader *r, const char *after);
/* A count of rows of at least `values` numbers each, checked against the bytes left. */
int gmsh_read_count(gmsh_reader *r, const char *what, int values, int64_t *n, int width);
/* The closing `$EndName` of a section. */
int gmsh_expect_end(gmsh_reader *r, const char *end);
/* Skip a section up to the line starting with `$End` + name (name: the section token without '$'). */
int gmsh_skip_section(gmsh_reader *r, const char *tok, size_t len);

/* ---- Nodes, elements, entities (import_gmsh_mesh.c) --------------------------------------------- */

/* Sort tags (unless already increasing) and refuse duplicates. */
int gmsh_sort_tags(gmsh_reader *r, tag_index *t, int64_t n, const char *what);
/* Node index of a tag, or -1 with the message. */
int32_t gmsh_node_index(gmsh_reader *r, int64_t tag, const char *user);
int gmsh_read_nodes(gmsh_reader *r);
int gmsh_read_elements(gmsh_reader *r);
/* 4.1 $Entities: keep the first physical tag of each volume (2.2: skipped). */
int gmsh_read_entities(gmsh_reader *r);

/* ---- 4.1 blocks on all threads (import_gmsh_bulk.c) ------------------------------------------ */

/* The index of `tag` in t[0 .. n) sorted by tag; *found says whether it is there (-1 when not). */
int32_t gmsh_lookup(const tag_index *t, int64_t n, int64_t tag, int *found);
/* The index of node `tag` (dense, node_at, or looked up in node_tags); *found says whether it is there. */
int32_t gmsh_node_at(const gmsh_reader *r, int64_t tag, int *found);
/* After $Nodes, sparse tags sorted: node_at where the largest tag is at most 4 a node (plus 4096). */
int gmsh_index_nodes(gmsh_reader *r);
/* The first tag that breaks the run 1, 2, 3, ...: node_tags made for n nodes, the `at` nodes before it
 * written out as (i + 1, i). 0, or -1 with the message (out of memory). */
int gmsh_list_node_run(gmsh_reader *r, int64_t at, int64_t n);
/* The tags of nodes at .. at + count - 1 (of n), binary from the mapping or ASCII in pieces: noted as
 * note-by-note reading would (no table while they run 1, 2, 3, ...). Returns how many it took: the first
 * tag it does not take (below 1, or not a number) and all after it are left to the one-by-one reader,
 * which words the failure, with the scanner where that reader would have it. -1: out of memory. */
int64_t gmsh_bulk_node_tags(gmsh_reader *r, int64_t at, int64_t count, int64_t n);
/* The coordinates of `count` nodes from `at`, without parametric ones: 1 when read (binary: copied;
 * ASCII: tpk_scan_numbers), 0 when left to the one-by-one reader. */
int gmsh_bulk_coords(gmsh_reader *r, int64_t at, int64_t count);
/* Elements of a kept type (room for `count` reserved) that need no more than copying: a tag of 1 or more
 * (continuing the implicit run while there is one), nodes $Nodes defines. Binary records from the
 * mapping, ASCII in pieces of tpk_scan_numbers; the cells land where one-by-one reading puts them, for
 * any thread count. Returns how many it took (the next element is left to the one-by-one reader, with
 * the scanner where that reader would have it), or -1 with the message; *again says whether calling it
 * once more after that element is worth it (0: a number did not read, the one-by-one reader fails). */
int64_t gmsh_bulk_elements(gmsh_reader *r, const gmsh_type *t, int64_t count, int64_t physical, int64_t entity,
                           int *again);

/* ---- Data blocks and fields (import_gmsh_data.c) ------------------------------------------------ */

/* One $NodeData (TPK_ASSOC_POINT) or $ElementData (TPK_ASSOC_TET) block into r->blocks. */
int gmsh_read_data(gmsh_reader *r, int association);
/* Blocks of the same name and association become one field of `out`, their times the steps. */
int gmsh_build_fields(gmsh_reader *r, tpk_mesh *out);

#endif
