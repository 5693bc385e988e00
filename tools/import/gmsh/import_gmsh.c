/* Gmsh .msh importer, formats 2.2 and 4.1, ASCII and binary (little-endian, data size 8). A file is a series of sections `$Name ... $EndName`:
 * $MeshFormat first, then $Nodes (node tags may be sparse: they are mapped to 0-based indices),
 * $Elements (volume elements kept in VTK node order, higher-order ones whole, points,
 * lines and surfaces dropped with a count), $NodeData/$ElementData (fields; blocks of the same name at
 * several times become one field with several steps), $Entities (4.1: the physical group of each volume
 * entity). Other sections ($PhysicalNames, $Periodic, $PartitionedEntities, unknown ones) are skipped.
 * Each element's physical group becomes the cell field "physical", its elementary entity "entity".
 * This file sits on top and calls down: $MeshFormat, the section loop, the final mesh and the entry
 * points; import_gmsh_mesh.c reads $Nodes, $Elements and $Entities, import_gmsh_data.c
 * $NodeData/$ElementData and builds the fields from them, import_gmsh_scan.c reads the numbers
 * (ASCII or binary) for all of them. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "import_gmsh_internal.h"
#include "base/text_scan.h"
#include "import/import_file.h"

/* ---- $MeshFormat and the section loop ----------------------------------------------------------- */

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
        if (gmsh_bin_bytes(r, &one, 4, "the integer 1 (byte order mark)"))
            return -1;
        if (one != 1)
            return tpk_scan_fail(&r->s, "expected the integer 1 in little-endian byte order, found %d "
                                        "(big-endian binary files are not read)", one);
    }
    return gmsh_expect_end(r, "$EndMeshFormat");
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
        return gmsh_read_nodes(r);
    if (tpk_token_is(tok, len, "$Elements"))
        return gmsh_read_elements(r);
    if (tpk_token_is(tok, len, "$Entities"))
        return gmsh_read_entities(r);
    if (tpk_token_is(tok, len, "$NodeData"))
        return gmsh_read_data(r, TPK_ASSOC_POINT);
    if (tpk_token_is(tok, len, "$ElementData"))
        return gmsh_read_data(r, TPK_ASSOC_TET);
    if (len >= 4 && !memcmp(tok, "$End", 4))
        return tpk_scan_fail(&r->s, "found '%s' without its section", tpk_scan_quote(tok, len, q, sizeof q));
    /* $PhysicalNames, $PartitionedEntities, $Periodic, $ElementNodeData, $InterpolationScheme, $Parametrizations,
     * $GhostElements, unknown sections: nothing a volume renderer uses. */
    return gmsh_skip_section(r, tok, len);
}

/* ---- The mesh and the entry points -------------------------------------------------------------- */

static int finish(gmsh_reader *r, tpk_mesh *out)
{
    if (r->point_count < 0)
        return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "expected a $Nodes section, found end of file");
    if (!r->have_elements)
        return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "expected an $Elements section, found end of file");
    if (r->dropped)
        tpk_diag_warn(r->s.diag, "%s: dropped %lld point, line and surface elements", r->s.name,
                      (long long)r->dropped);
    if (tpk_import_take_cells(out, r->point_count, &r->points, r->cell_count, &r->types, &r->offsets, &r->conn))
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
    if (gmsh_build_fields(r, out))
        return -1;
    snprintf(out->format, sizeof out->format, "gmsh-%s-%s", r->version == 22 ? "2.2" : "4.1",
             r->binary ? "binary" : "ascii");
    return 0;
}

static void reader_free(gmsh_reader *r)
{
    free(r->points);
    free(r->node_tags);
    free(r->node_at);
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
    if (tpk_import_begin(name, out, diag) != 0)
        return -1;
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
    return tpk_import_end(rc, out);
}

int tpk_import_gmsh_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    return import_buffer(name, data, size, 0, out, diag);
}

int tpk_import_gmsh(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    return tpk_import_mapped(path, import_buffer, out, diag);
}
