/* VTK XML UnstructuredGrid (.vtu) importer. expat parses the XML; the DataArrays' contents are decoded
 * here: ascii numbers, base64 ("binary") and raw or base64 appended data, each with a UInt32 or UInt64
 * header, optionally as zlib-compressed blocks. Raw appended data is not XML, so the buffer is split at
 * the '_' that starts it: expat sees only the XML before, the blocks are read by their offsets.
 * Every size read from the file is checked against the bytes that can hold it before allocating.
 * This file sits on top and calls down: the entry points; import_vtu_xml.c walks the XML and collects
 * the DataArrays, import_vtu_decode.c decodes their contents, import_vtu_mesh.c builds the tpk_mesh,
 * import_vtu_fail.c words the failures for all of them. */
#include <stdlib.h>
#include <string.h>

#include "import_vtu_internal.h"
#include "base/text_scan.h"
#include "import/import_file.h"

/* ---- Entry points ------------------------------------------------------------------------------- */

static void reader_free(vtu_reader *r)
{
    for (int i = 0; i < r->array_count; i++)
        free(r->arrays[i].values);
    free(r->arrays);
    free(r->cur.values);
    free(r->text);
}

int tpk_import_vtu_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    if (!name)
        name = "(input)";
    if (!out)
        return tpk_diag_fail(diag, "%s: no output mesh given", name);
    memset(out, 0, sizeof *out);
    if (diag)
        diag->message[0] = 0;
    vtu_reader r;
    memset(&r, 0, sizeof r);
    r.name = name;
    r.data = (const unsigned char *)data;
    r.size = data ? size : 0;
    r.diag = diag;
    r.header_size = 4;
    int rc = vtu_parse_xml(&r);
    if (rc == 0)
        rc = vtu_decode_appended(&r);
    if (rc == 0)
        rc = vtu_build_mesh(&r, out);
    reader_free(&r);
    if (rc != 0)
        tpk_mesh_free(out);
    return rc;
}

int tpk_import_vtu(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    return tpk_import_mapped_memory(path, tpk_import_vtu_memory, out, diag); /* appended blocks read by offset */
}
