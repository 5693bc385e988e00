/* VTU export: a .tpk's tets (recovered from the best layout present), world positions, every field at
 * every step, and the source maps, as a VTK XML UnstructuredGrid with raw appended data (version 1.0,
 * UInt64 headers) that ParaView and meshio read. Written atomically. */
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "export_io.h"
#include "exporters.h"

/* One appended array: where it goes, what it is, and where its bytes come from. */
typedef struct vtu_array {
    int cell_data;          /* 0: PointData, 1: CellData, 2: Points, 3: Cells */
    char name[96];
    const char *type;       /* Float32, Float64, Int32, Int64, UInt8 */
    int components;
    uint64_t values;        /* number of scalars (tuples * components) */
    unsigned value_size;
    const void *data;       /* Float32/Int32 source data, written as is */
    uint64_t offset;        /* in the appended block */
} vtu_array;

typedef struct vtu_export {
    tpk_file *file;
    const char *path;
    tpk_diag *diag;
    tpk_file_info info;
    tpk_mesh_arrays mesh;
    int32_t *tets;
    vtu_array *arrays;
    int array_count;
    void **owned;            /* decoded chunks to free */
    int owned_count;
} vtu_export;

static int lib_fail(vtu_export *x, tpk_result r, const char *what)
{
    const char *text = tpk_error_text(x->file);
    return tpk_diag_fail(x->diag, "%s: cannot export: %s: %s", x->path, what, text[0] ? text : tpk_result_string(r));
}

static vtu_array *add_array(vtu_export *x, int section, const char *name, const char *type, int components,
                            uint64_t values, unsigned value_size, const void *data)
{
    vtu_array *grown = realloc(x->arrays, sizeof *grown * (size_t)(x->array_count + 1));
    if (!grown)
        return NULL;
    x->arrays = grown;
    vtu_array *a = &grown[x->array_count++];
    memset(a, 0, sizeof *a);
    a->cell_data = section;
    snprintf(a->name, sizeof a->name, "%s", name);
    a->type = type;
    a->components = components;
    a->values = values;
    a->value_size = value_size;
    a->data = data;
    return a;
}

static int keep_owned(vtu_export *x, void *p)
{
    if (!p)
        return 0;
    void **grown = realloc(x->owned, sizeof *grown * (size_t)(x->owned_count + 1));
    if (!grown) {
        free(p);
        return -1;
    }
    x->owned = grown;
    x->owned[x->owned_count++] = p;
    return 0;
}

/* Every field at every step: NAME for a single step, NAME_t0, NAME_t1, ... otherwise. */
static int collect_fields(vtu_export *x)
{
    uint32_t count = tpk_field_count(x->file);
    for (uint32_t i = 0; i < count; i++) {
        tpk_field_desc desc;
        tpk_result r = tpk_get_field(x->file, i, &desc);
        if (r != TPK_OK)
            return lib_fail(x, r, "field descriptor");
        int cells = desc.association == TPK_ASSOC_TET;
        uint64_t tuples = cells ? x->info.tet_count : x->info.vertex_count;
        uint32_t comps = desc.components ? desc.components : 1;
        char name[65];
        memcpy(name, desc.name, 64);
        name[64] = 0;
        for (uint32_t s = 0; s < desc.step_count; s++) {
            const void *data;
            void *owned;
            int got = tpk_export_load_chunk(x->file, TPK_TAG_FDAT, i, s, 4, tuples * comps, &data, &owned, x->path,
                                            x->diag);
            if (got < 0)
                return -1;
            if (got == 0)
                return tpk_diag_fail(x->diag, "%s: cannot export: field '%s' has no data for step %u", x->path, name, s);
            if (keep_owned(x, owned) != 0)
                return tpk_diag_fail(x->diag, "%s: out of memory", x->path);
            char label[96];
            if (desc.step_count == 1)
                snprintf(label, sizeof label, "%s", name);
            else
                snprintf(label, sizeof label, "%s_t%u", name, s);
            if (!add_array(x, cells, label, "Float32", (int)comps, tuples * comps, 4, data))
                return tpk_diag_fail(x->diag, "%s: out of memory", x->path);
        }
    }
    return 0;
}

static int collect_map(vtu_export *x, uint32_t tag, int cells, const char *name)
{
    const void *data;
    void *owned;
    uint64_t count = cells ? x->info.tet_count : x->info.vertex_count;
    int got = tpk_export_load_chunk(x->file, tag, 0, 0, 4, count, &data, &owned, x->path, x->diag);
    if (got <= 0)
        return got;
    if (keep_owned(x, owned) != 0 || !add_array(x, cells, name, "Int32", 1, count, 4, data))
        return tpk_diag_fail(x->diag, "%s: out of memory", x->path);
    return 0;
}

static void write_xml_escaped(tpk_out *o, const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '&': tpk_out_printf(o, "&amp;"); break;
        case '<': tpk_out_printf(o, "&lt;"); break;
        case '>': tpk_out_printf(o, "&gt;"); break;
        case '"': tpk_out_printf(o, "&quot;"); break;
        default: tpk_out_write(o, s, 1); break;
        }
    }
}

static void write_declarations(vtu_export *x, tpk_out *o, int section, const char *indent)
{
    for (int i = 0; i < x->array_count; i++) {
        const vtu_array *a = &x->arrays[i];
        if (a->cell_data != section)
            continue;
        tpk_out_printf(o, "%s<DataArray type=\"%s\" Name=\"", indent, a->type);
        write_xml_escaped(o, a->name);
        tpk_out_printf(o, "\"");
        if (a->components != 1)
            tpk_out_printf(o, " NumberOfComponents=\"%d\"", a->components);
        tpk_out_printf(o, " format=\"appended\" offset=\"%llu\"/>\n", (unsigned long long)a->offset);
    }
}

static void write_points(vtu_export *x, tpk_out *o)
{
    double buf[3 * 1024];
    uint64_t n = x->info.vertex_count;
    for (uint64_t i = 0; i < n; i += 1024) {
        uint64_t m = n - i < 1024 ? n - i : 1024;
        for (uint64_t j = 0; j < m; j++)
            for (int k = 0; k < 3; k++)
                buf[3 * j + k] = x->mesh.origin[k] + (double)x->mesh.positions[3 * (i + j) + k];
        tpk_out_f64le(o, buf, (size_t)(3 * m));
    }
}

static void write_cells(vtu_export *x, tpk_out *o, int which)
{
    int64_t buf[4096];
    uint64_t n = x->info.tet_count;
    if (which == 0) { /* connectivity */
        for (uint64_t i = 0; i < 4 * n; i += 4096) {
            uint64_t m = 4 * n - i < 4096 ? 4 * n - i : 4096;
            for (uint64_t j = 0; j < m; j++)
                buf[j] = x->tets[i + j];
            tpk_out_i64le(o, buf, (size_t)m);
        }
    } else if (which == 1) { /* offsets */
        for (uint64_t i = 0; i < n; i += 4096) {
            uint64_t m = n - i < 4096 ? n - i : 4096;
            for (uint64_t j = 0; j < m; j++)
                buf[j] = (int64_t)(4 * (i + j + 1));
            tpk_out_i64le(o, buf, (size_t)m);
        }
    } else { /* types: VTK_TETRA */
        unsigned char types[4096];
        memset(types, 10, sizeof types);
        for (uint64_t i = 0; i < n; i += sizeof types)
            tpk_out_write(o, types, (size_t)(n - i < sizeof types ? n - i : sizeof types));
    }
}

static int write_vtu(vtu_export *x)
{
    /* Points and cells go first in the appended block, then the data arrays. */
    uint64_t v = x->info.vertex_count, t = x->info.tet_count;
    /* Indices, not pointers: add_array may move the array. */
    int pts = x->array_count, conn = pts + 1, offs = pts + 2, types = pts + 3;
    if (!add_array(x, 2, "Points", "Float64", 3, 3 * v, 8, NULL) ||
        !add_array(x, 3, "connectivity", "Int64", 1, 4 * t, 8, NULL) ||
        !add_array(x, 3, "offsets", "Int64", 1, t, 8, NULL) || !add_array(x, 3, "types", "UInt8", 1, t, 1, NULL))
        return tpk_diag_fail(x->diag, "%s: out of memory", x->path);
    /* Offsets in write order: sections 2, 3, then the fields in their order. */
    uint64_t offset = 0;
    static const int order[4] = {2, 3, 0, 1};
    for (int s = 0; s < 4; s++)
        for (int i = 0; i < x->array_count; i++)
            if (x->arrays[i].cell_data == order[s]) {
                x->arrays[i].offset = offset;
                offset += 8 + x->arrays[i].values * x->arrays[i].value_size;
            }

    tpk_out o;
    if (tpk_out_open(&o, x->path, x->diag) != 0)
        return -1;
    tpk_out_printf(&o, "<?xml version=\"1.0\"?>\n"
                       "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
                       "header_type=\"UInt64\">\n"
                       "  <UnstructuredGrid>\n"
                       "    <Piece NumberOfPoints=\"%llu\" NumberOfCells=\"%llu\">\n",
                   (unsigned long long)v, (unsigned long long)t);
    tpk_out_printf(&o, "      <PointData>\n");
    write_declarations(x, &o, 0, "        ");
    tpk_out_printf(&o, "      </PointData>\n      <CellData>\n");
    write_declarations(x, &o, 1, "        ");
    tpk_out_printf(&o, "      </CellData>\n      <Points>\n");
    write_declarations(x, &o, 2, "        ");
    tpk_out_printf(&o, "      </Points>\n      <Cells>\n");
    write_declarations(x, &o, 3, "        ");
    tpk_out_printf(&o, "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _");
    for (int s = 0; s < 4; s++) {
        for (int i = 0; i < x->array_count; i++) {
            vtu_array *a = &x->arrays[i];
            if (a->cell_data != order[s])
                continue;
            tpk_out_u64le(&o, a->values * a->value_size);
            if (i == pts)
                write_points(x, &o);
            else if (i == conn)
                write_cells(x, &o, 0);
            else if (i == offs)
                write_cells(x, &o, 1);
            else if (i == types)
                write_cells(x, &o, 2);
            else if (!strcmp(a->type, "Int32"))
                tpk_out_i32le(&o, a->data, (size_t)a->values);
            else
                tpk_out_f32le(&o, a->data, (size_t)a->values);
        }
    }
    tpk_out_printf(&o, "\n  </AppendedData>\n</VTKFile>\n");
    return tpk_out_commit(&o, x->diag);
}

int tpk_export_vtu(tpk_file *file, const char *path, tpk_diag *diag)
{
    if (!file || !path)
        return tpk_diag_fail(diag, "tpk_export_vtu: no file or output path given");
    vtu_export x;
    memset(&x, 0, sizeof x);
    x.file = file;
    x.path = path;
    x.diag = diag;
    tpk_layout layout = TPK_LAYOUT_TET32;
    tpk_result r = tpk_get_info(file, &x.info);
    int rc = -1;
    if (r != TPK_OK) {
        lib_fail(&x, r, "header");
        goto done;
    }
    if (tpk_export_pick_layout(x.file, x.path, &layout, x.diag) != 0)
        goto done;
    r = tpk_load_arrays(file, layout, NULL, 0, &x.mesh);
    if (r != TPK_OK) {
        lib_fail(&x, r, "loading the mesh arrays");
        goto done;
    }
    x.tets = malloc(sizeof(int32_t) * 4 * (size_t)(x.info.tet_count ? x.info.tet_count : 1));
    if (!x.tets) {
        tpk_diag_fail(diag, "%s: out of memory for %llu tets", path, (unsigned long long)x.info.tet_count);
        goto done;
    }
    r = tpk_recover_tets_threads(&x.mesh, x.tets, tpk_thread_count(0));
    if (r != TPK_OK) {
        lib_fail(&x, r, "recovering the tets' vertices");
        goto done;
    }
    if (collect_fields(&x) != 0 || collect_map(&x, TPK_TAG_VMAP, 0, "source_point") != 0 ||
        collect_map(&x, TPK_TAG_TMAP, 1, "source_cell") != 0)
        goto done;
    rc = write_vtu(&x);
done:
    for (int i = 0; i < x.owned_count; i++)
        free(x.owned[i]);
    free(x.owned);
    free(x.arrays);
    free(x.tets);
    return rc;
}
