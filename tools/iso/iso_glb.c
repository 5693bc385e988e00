/* glTF 2.0 binary (.glb), written against the spec (registry.khronos.org/glTF, "GLB File Format
 * Specification"): a 12-byte header (magic "glTF", version 2, total length), a JSON chunk padded with
 * spaces to 4 bytes, a BIN chunk padded with zeros. One mesh, one triangle primitive: POSITION (float32,
 * relative to the node's translation, the .tpk's origin, so far-away coordinates keep their digits;
 * min/max as the spec requires), NORMAL (unit), _VALUE (the iso value) and _COLOR_FIELD (the second field)
 * as application-specific attributes, indices UNSIGNED_INT. An empty surface is a valid file with a scene
 * and no mesh (an accessor may not have count 0). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/strbuf.h"
#include "iso_internal.h"

#define GLB_MAGIC 0x46546C67u      /* "glTF" */
#define GLB_CHUNK_JSON 0x4E4F534Au /* "JSON" */
#define GLB_CHUNK_BIN 0x004E4942u  /* "BIN\0" */
#define GLTF_FLOAT 5126
#define GLTF_UNSIGNED_INT 5125
#define GLTF_ARRAY_BUFFER 34962
#define GLTF_ELEMENT_ARRAY_BUFFER 34963

typedef struct glb_view {
    const char *attribute; /* NULL: the indices */
    const char *type;      /* VEC3, SCALAR */
    uint64_t bytes, offset;
} glb_view;

static void json_view(tpk_strbuf *j, const glb_view *v, int comma)
{
    tpk_strbuf_printf(j, "%s{\"buffer\":0,\"byteOffset\":%llu,\"byteLength\":%llu,\"target\":%d}", comma ? "," : "",
                      (unsigned long long)v->offset, (unsigned long long)v->bytes,
                      v->attribute ? GLTF_ARRAY_BUFFER : GLTF_ELEMENT_ARRAY_BUFFER);
}

/* The positions relative to the origin, as stored, with their float32 bounds. */
static float *relative_positions(const tpk_iso_surface *s, const double origin[3], float lo[3], float hi[3])
{
    float *p = malloc(sizeof *p * 3 * (size_t)s->vertex_count);
    if (!p)
        return NULL;
    for (int k = 0; k < 3; k++)
        lo[k] = INFINITY, hi[k] = -INFINITY;
    for (int64_t i = 0; i < 3 * s->vertex_count; i++) {
        int k = (int)(i % 3);
        p[i] = (float)(s->xyz[i] - origin[k]);
        lo[k] = p[i] < lo[k] ? p[i] : lo[k];
        hi[k] = p[i] > hi[k] ? p[i] : hi[k];
    }
    return p;
}

static void json_extras(tpk_strbuf *j, const tpk_iso_surface *s, const tpk_iso_labels *l)
{
    tpk_strbuf_printf(j, "\"extras\":{\"field\":");
    tpk_strbuf_json_string(j, l->field);
    tpk_strbuf_printf(j, ",\"step\":%u,\"values\":[", l->step);
    for (int i = 0; i < s->value_count; i++)
        tpk_strbuf_printf(j, "%s%.17g", i ? "," : "", s->values[i]);
    tpk_strbuf_printf(j, "],\"triangles_per_value\":[");
    for (int i = 0; i < s->value_count; i++)
        tpk_strbuf_printf(j, "%s%lld", i ? "," : "", (long long)s->value_triangles[i]);
    tpk_strbuf_printf(j, "]");
    if (l->color_field) {
        tpk_strbuf_printf(j, ",\"color_field\":");
        tpk_strbuf_json_string(j, l->color_field);
    }
    tpk_strbuf_printf(j, ",\"normals\":\"toward increasing field\"}");
}

/* The JSON chunk's text for the views (offsets filled in) and bounds. */
static void json_document(tpk_strbuf *j, const tpk_iso_surface *s, const tpk_iso_labels *l, const glb_view *views,
                          int view_count, const float lo[3], const float hi[3], uint64_t bin_bytes)
{
    tpk_strbuf_printf(j, "{\"asset\":{\"version\":\"2.0\",\"generator\":\"tetpack iso %s\"},\"scene\":0,",
                      TPK_LIBRARY_VERSION);
    if (s->triangle_count == 0) {
        tpk_strbuf_printf(j, "\"scenes\":[{");
        json_extras(j, s, l);
        tpk_strbuf_printf(j, "}]}");
        return;
    }
    tpk_strbuf_printf(j, "\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0");
    if (l->origin[0] != 0 || l->origin[1] != 0 || l->origin[2] != 0)
        tpk_strbuf_printf(j, ",\"translation\":[%.17g,%.17g,%.17g]", l->origin[0], l->origin[1], l->origin[2]);
    tpk_strbuf_printf(j, "}],\"materials\":[{\"doubleSided\":true,\"pbrMetallicRoughness\":{\"metallicFactor\":0}}],"
                         "\"meshes\":[{\"primitives\":[{\"attributes\":{");
    for (int i = 0; i < view_count - 1; i++)
        tpk_strbuf_printf(j, "%s\"%s\":%d", i ? "," : "", views[i].attribute, i);
    tpk_strbuf_printf(j, "},\"indices\":%d,\"material\":0,\"mode\":4}],", view_count - 1);
    json_extras(j, s, l);
    tpk_strbuf_printf(j, "}],\"buffers\":[{\"byteLength\":%llu}],\"bufferViews\":[", (unsigned long long)bin_bytes);
    for (int i = 0; i < view_count; i++)
        json_view(j, &views[i], i);
    tpk_strbuf_printf(j, "],\"accessors\":[");
    for (int i = 0; i < view_count; i++) {
        int index = views[i].attribute == NULL;
        unsigned long long count = index ? 3ull * (uint64_t)s->triangle_count : (uint64_t)s->vertex_count;
        tpk_strbuf_printf(j, "%s{\"bufferView\":%d,\"componentType\":%d,\"count\":%llu,\"type\":\"%s\"", i ? "," : "", i,
                          index ? GLTF_UNSIGNED_INT : GLTF_FLOAT, count, views[i].type);
        if (i == 0)
            tpk_strbuf_printf(j, ",\"min\":[%.9g,%.9g,%.9g],\"max\":[%.9g,%.9g,%.9g]", lo[0], lo[1], lo[2], hi[0],
                              hi[1], hi[2]);
        tpk_strbuf_printf(j, "}");
    }
    tpk_strbuf_printf(j, "]}");
}

int tpk_iso_write_glb(FILE *f, const tpk_iso_surface *s, const tpk_iso_labels *l, const char *path, tpk_diag *diag)
{
    uint64_t nv = (uint64_t)s->vertex_count, nt = (uint64_t)s->triangle_count;
    glb_view views[5] = {{"POSITION", "VEC3", 12 * nv, 0}, {"NORMAL", "VEC3", 12 * nv, 0}, {"_VALUE", "SCALAR", 4 * nv, 0}};
    int n = 3;
    if (s->color)
        views[n++] = (glb_view){"_COLOR_FIELD", "SCALAR", 4 * nv, 0};
    views[n++] = (glb_view){NULL, "SCALAR", 12 * nt, 0};
    uint64_t bin = 0;
    for (int i = 0; i < n; i++) /* every view a multiple of 4 bytes: no padding between them */
        views[i].offset = bin, bin += views[i].bytes;
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0}, *rel = NULL;
    if (nt && !(rel = relative_positions(s, l->origin, lo, hi)))
        return tpk_diag_fail(diag, "%s: out of memory for %llu positions", path, (unsigned long long)nv);
    tpk_strbuf j = {0};
    json_document(&j, s, l, views, n, lo, hi, bin);
    if (j.failed) {
        free(rel);
        tpk_strbuf_free(&j);
        return tpk_diag_fail(diag, "%s: out of memory for the glTF JSON", path);
    }
    uint64_t json_bytes = (j.length + 3) & ~(uint64_t)3;
    uint64_t total = 12 + 8 + json_bytes + (nt ? 8 + bin : 0);
    if (total > UINT32_MAX) {
        free(rel);
        tpk_strbuf_free(&j);
        return tpk_diag_fail(diag, "%s: the surface needs %llu bytes, beyond the 4 GiB a .glb can hold (its length "
                             "is 32 bits): write .ply instead", path, (unsigned long long)total);
    }
    iso_put_u32(f, GLB_MAGIC);
    iso_put_u32(f, 2);
    iso_put_u32(f, (uint32_t)total);
    iso_put_u32(f, (uint32_t)json_bytes);
    iso_put_u32(f, GLB_CHUNK_JSON);
    fwrite(j.data, 1, j.length, f);
    for (uint64_t i = j.length; i < json_bytes; i++)
        fputc(' ', f);
    if (nt) {
        iso_put_u32(f, (uint32_t)bin);
        iso_put_u32(f, GLB_CHUNK_BIN);
        iso_put_le(f, rel, 3 * nv, 4);
        iso_put_le(f, s->normal, 3 * nv, 4);
        iso_put_le(f, s->value, nv, 4);
        if (s->color)
            iso_put_le(f, s->color, nv, 4);
        iso_put_le(f, s->tri, 3 * nt, 4);
    }
    free(rel);
    tpk_strbuf_free(&j);
    return 0;
}
