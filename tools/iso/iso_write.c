/* The iso writers' entry: the format from the extension, PLY and OBJ here, glTF binary in iso_glb.c; every
 * output through base/output_file.h (unnamed until complete, then linked into place). */
#include <ctype.h>
#include <errno.h>
#include <string.h>

#include "base/output_file.h"
#include "iso_internal.h"

tpk_iso_format tpk_iso_format_of(const char *path)
{
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash))
        return 0;
    char ext[5] = {0};
    for (int i = 0; i < 4 && dot[1 + i]; i++)
        ext[i] = (char)tolower((unsigned char)dot[1 + i]);
    if (strlen(dot + 1) != 3)
        return 0;
    return !strcmp(ext, "ply") ? TPK_ISO_PLY : !strcmp(ext, "obj") ? TPK_ISO_OBJ : !strcmp(ext, "glb") ? TPK_ISO_GLB : 0;
}

/* One line of comment naming what the values are (PLY and OBJ). */
static void describe(FILE *f, const char *prefix, const tpk_iso_surface *s, const tpk_iso_labels *l)
{
    fprintf(f, "%s tetpack iso: field %s step %u, normals toward increasing field, values", prefix, l->field, l->step);
    for (int i = 0; i < s->value_count; i++)
        fprintf(f, " %.9g (%lld triangles)", s->values[i], (long long)s->value_triangles[i]);
    fputc('\n', f);
    if (l->color_field)
        fprintf(f, "%s color: field %s interpolated\n", prefix, l->color_field);
}

/* Binary little-endian PLY: vertex x y z (double), nx ny nz value [color] (float), edge_a edge_b (int: the
 * mesh edge the vertex lies on, for picking and for tests of watertightness), faces as int lists. */
static void write_ply(FILE *f, const tpk_iso_surface *s, const tpk_iso_labels *l)
{
    fputs("ply\nformat binary_little_endian 1.0\n", f);
    describe(f, "comment", s, l);
    fprintf(f, "element vertex %lld\nproperty double x\nproperty double y\nproperty double z\n"
               "property float nx\nproperty float ny\nproperty float nz\nproperty float value\n%s"
               "property int edge_a\nproperty int edge_b\nelement face %lld\nproperty list uchar int vertex_indices\nend_header\n",
            (long long)s->vertex_count, s->color ? "property float color\n" : "", (long long)s->triangle_count);
    for (int64_t v = 0; v < s->vertex_count; v++) {
        iso_put_le(f, s->xyz + 3 * v, 3, 8);
        iso_put_le(f, s->normal + 3 * v, 3, 4);
        iso_put_le(f, s->value + v, 1, 4);
        if (s->color)
            iso_put_le(f, s->color + v, 1, 4);
        iso_put_le(f, s->edge + 2 * v, 2, 4);
    }
    for (int64_t t = 0; t < s->triangle_count; t++) {
        fputc(3, f);
        iso_put_le(f, s->tri + 3 * t, 3, 4);
    }
}

/* ASCII OBJ: positions exact (%.17g), normals, faces 1-based under one `o` per value. */
static void write_obj(FILE *f, const tpk_iso_surface *s, const tpk_iso_labels *l)
{
    describe(f, "#", s, l);
    for (int64_t v = 0; v < s->vertex_count; v++)
        fprintf(f, "v %.17g %.17g %.17g\n", s->xyz[3 * v], s->xyz[3 * v + 1], s->xyz[3 * v + 2]);
    for (int64_t v = 0; v < s->vertex_count; v++)
        fprintf(f, "vn %.9g %.9g %.9g\n", s->normal[3 * v], s->normal[3 * v + 1], s->normal[3 * v + 2]);
    int64_t t = 0;
    for (int i = 0; i < s->value_count; i++) {
        if (s->value_triangles[i])
            fprintf(f, "o iso_%d\n", i);
        for (int64_t end = t + s->value_triangles[i]; t < end; t++) {
            unsigned long long a = s->tri[3 * t] + 1ull, b = s->tri[3 * t + 1] + 1ull, c = s->tri[3 * t + 2] + 1ull;
            fprintf(f, "f %llu//%llu %llu//%llu %llu//%llu\n", a, a, b, b, c, c);
        }
    }
}

int tpk_iso_write(const tpk_iso_surface *s, const tpk_iso_labels *labels, tpk_iso_format format, const char *path,
                  tpk_diag *diag)
{
    if (!format)
        return tpk_diag_fail(diag, "%s: unknown output extension: expected .ply, .obj or .glb", path);
    tpk_output out;
    if (tpk_output_open(&out, path, diag) != 0)
        return -1;
    FILE *f = tpk_output_stream(&out, diag);
    if (!f) {
        tpk_output_abort(&out);
        return -1;
    }
    errno = 0;
    int rc = 0;
    if (format == TPK_ISO_PLY)
        write_ply(f, s, labels);
    else if (format == TPK_ISO_OBJ)
        write_obj(f, s, labels);
    else
        rc = tpk_iso_write_glb(f, s, labels, path, diag);
    if (rc == 0 && ferror(f)) {
        int err = errno ? errno : EIO;
        rc = tpk_diag_fail(diag, "%s: write failed: %s (nothing was written)", path, strerror(err));
    }
    if (rc != 0) {
        tpk_output_abort(&out);
        return -1;
    }
    return tpk_output_commit(&out, diag);
}
