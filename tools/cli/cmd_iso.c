/* tetpack iso: isosurfaces of a point field as triangles (tools/iso/), written as PLY, OBJ or glTF binary. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/output_file.h"
#include "base/strbuf.h"
#include "cli.h"
#include "iso/iso.h"
#ifdef TPK_WITH_VULKAN
#include "render_vk/render_vk.h"
#endif

static const char iso_help[] =
    "usage: tetpack iso IN.tpk OUT.ply|.obj|.glb --value V[,V...] [--field NAME] [--step N] [options]\n"
    "\n"
    "Extracts the isosurfaces of a point field with marching tetrahedra on all cores. One vertex per tet\n"
    "edge the surface crosses (shared by every tet around that edge), so the surface is watertight wherever\n"
    "the mesh is conforming: open edges lie only on the mesh's shell. Triangles are counter-clockwise seen\n"
    "from the higher values: normals point toward increasing field. A mesh vertex whose value equals V\n"
    "counts as above V (zero-area triangles there are kept, so the surface stays closed). The output is the\n"
    "same, byte for byte, for any --threads.\n"
    "\n"
    "  --value V[,V...]     iso values (1 to 64 numbers); a value that crosses no tet gives an empty surface\n"
    "                       and a warning (naming the field's range when it lies outside it)\n"
    "  --field NAME         the point field (default: the first point field). A tet field (one value per\n"
    "                       tet) is refused: convert the source with --cell-to-point to average it to points\n"
    "  --step N             the field's time step (default 0)\n"
    "  --color-field NAME   a second point field interpolated onto the vertices (its step N, or 0 when it\n"
    "                       has one step)\n"
    "  --threads N          worker threads (default: all cores)\n"
    "  --backend cpu|vulkan where tets are classified and triangles emitted: the CPU (default) or Vulkan\n"
    "                       compute shaders; vertices and normals are then made as on the CPU, so the\n"
    "                       output is the same, byte for byte\n"
    "  --json               print the report as JSON (triangles, vertices, seconds, per value counts)\n"
    "\n"
    "Outputs, by extension (written atomically):\n"
    "  .ply  binary little-endian: float64 x y z, float32 nx ny nz, 'value' (the iso value), 'color'\n"
    "        (--color-field), int 'edge_a' 'edge_b' (the mesh vertices of the edge it lies on), faces\n"
    "  .obj  ASCII: v (exact float64), vn, f; one 'o iso_K' per value; no values (OBJ has no place)\n"
    "  .glb  glTF 2.0 binary: POSITION (float32, relative to the node's translation, the file's origin),\n"
    "        NORMAL, _VALUE, _COLOR_FIELD, UNSIGNED_INT indices; field and values in the mesh's extras\n";

/* "V[,V...]": finite numbers, at most TPK_ISO_MAX_VALUES. Returns the count, -1 when bad. */
static int parse_values(const char *text, double *out)
{
    int n = 0;
    const char *p = text;
    for (;;) {
        char *end;
        double v = strtod(p, &end);
        if (end == p || !isfinite(v) || n == TPK_ISO_MAX_VALUES || (*end && *end != ','))
            return -1;
        out[n++] = v;
        if (!*end)
            return n;
        p = end + 1;
    }
}

static void print_json(const tpk_iso_options *o, const tpk_iso_report *r, const char *backend, const char *device,
                       double device_seconds, double gpu_seconds)
{
    tpk_strbuf j = {0};
    double seconds = r->seconds_load + r->seconds_extract + r->seconds_write;
    tpk_strbuf_printf(&j, "{\"input\":");
    tpk_strbuf_json_string(&j, o->input);
    tpk_strbuf_printf(&j, ",\"output\":");
    tpk_strbuf_json_string(&j, o->output);
    tpk_strbuf_printf(&j, ",\"field\":");
    tpk_strbuf_json_string(&j, r->field);
    tpk_strbuf_printf(&j, ",\"step\":%u,\"color_field\":", o->step);
    if (r->color_field[0])
        tpk_strbuf_json_string(&j, r->color_field);
    else
        tpk_strbuf_printf(&j, "null");
    tpk_strbuf_printf(&j, ",\"field_range\":[");
    tpk_strbuf_json_number(&j, r->field_min);
    tpk_strbuf_printf(&j, ",");
    tpk_strbuf_json_number(&j, r->field_max);
    tpk_strbuf_printf(&j, "],\"threads\":%d,\"tets\":%lld,\"triangles\":%lld,\"vertices\":%lld,\"seconds\":", r->threads,
                      (long long)r->tets, (long long)r->triangles, (long long)r->vertices);
    tpk_strbuf_json_number(&j, seconds);
    tpk_strbuf_printf(&j, ",\"seconds_load\":");
    tpk_strbuf_json_number(&j, r->seconds_load);
    tpk_strbuf_printf(&j, ",\"seconds_extract\":");
    tpk_strbuf_json_number(&j, r->seconds_extract);
    tpk_strbuf_printf(&j, ",\"seconds_write\":");
    tpk_strbuf_json_number(&j, r->seconds_write);
    double extract = r->seconds_extract > 0 ? r->seconds_extract : 1e-9;
    tpk_strbuf_printf(&j, ",\"tets_per_second\":");
    tpk_strbuf_json_number(&j, floor((double)r->tets * r->value_count / extract));
    tpk_strbuf_printf(&j, ",\"triangles_per_second\":");
    tpk_strbuf_json_number(&j, floor((double)r->triangles / extract));
    tpk_strbuf_printf(&j, ",\"values\":[");
    for (int i = 0; i < r->value_count; i++) {
        tpk_strbuf_printf(&j, "%s{\"value\":", i ? "," : "");
        tpk_strbuf_json_number(&j, r->values[i]);
        tpk_strbuf_printf(&j, ",\"triangles\":%lld,\"vertices\":%lld,\"in_range\":%s}", (long long)r->value_triangles[i],
                          (long long)r->value_vertices[i],
                          r->values[i] >= r->field_min && r->values[i] <= r->field_max ? "true" : "false");
    }
    tpk_strbuf_printf(&j, "],\"backend\":\"%s\",\"device\":", backend);
    tpk_strbuf_json_string(&j, device ? device : "");
    tpk_strbuf_printf(&j, ",\"device_seconds\":");
    tpk_strbuf_json_number(&j, device_seconds);
    tpk_strbuf_printf(&j, ",\"gpu_seconds\":");
    if (gpu_seconds >= 0)
        tpk_strbuf_json_number(&j, gpu_seconds);
    else
        tpk_strbuf_printf(&j, "null");
    tpk_strbuf_printf(&j, "}\n");
    if (!j.failed)
        fputs(j.data, stdout);
    tpk_strbuf_free(&j);
}

/* The Vulkan extractor, made at the first value (tpk_iso_corners gets the mesh then). */
typedef struct vk_source {
    const char *device; /* after the first value */
#ifdef TPK_WITH_VULKAN
    tpk_iso_vk *vk;
#endif
} vk_source;

#ifdef TPK_WITH_VULKAN
static int vk_emit(void *user, const tpk_iso_input *in, double value, uint64_t **keys, int64_t *triangles,
                   tpk_diag *diag)
{
    vk_source *s = user;
    if (!s->vk && tpk_iso_vk_create(&s->vk, in, diag) != 0)
        return -1;
    s->device = tpk_iso_vk_device(s->vk);
    return tpk_iso_vk_emit(s->vk, value, keys, NULL, triangles, diag);
}
#endif

static int parse_args(int argc, char **argv, tpk_iso_options *o, double *values, int *json, int *vulkan)
{
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i], *v = NULL;
#define VALUE(name) (v = tpk_cli_value(argc, argv, &i, name))
        int step;
        if (!strncmp(arg, "--value", 7)) {
            if (!VALUE("--value") || (o->value_count = parse_values(v, values)) < 0)
                return tpk_cli_fail("iso", "--value expects 1 to %d finite numbers separated by commas, found '%s'",
                                    TPK_ISO_MAX_VALUES, v ? v : "");
        } else if (!strncmp(arg, "--field", 7)) {
            if (!VALUE("--field"))
                return tpk_cli_fail("iso", "--field expects a field name");
            o->field = v;
        } else if (!strncmp(arg, "--color-field", 13)) {
            if (!VALUE("--color-field"))
                return tpk_cli_fail("iso", "--color-field expects a field name");
            o->color_field = v;
        } else if (!strncmp(arg, "--step", 6)) {
            if (!VALUE("--step") || tpk_cli_parse_int(v, 0, 1 << 30, &step))
                return tpk_cli_fail("iso", "--step expects a step number >= 0, found '%s'", v ? v : "");
            o->step = (uint32_t)step;
        } else if (!strncmp(arg, "--threads", 9)) {
            if (!VALUE("--threads") || tpk_cli_parse_int(v, 1, 1024, &o->threads))
                return tpk_cli_fail("iso", "--threads expects 1..1024, found '%s'", v ? v : "");
        } else if (!strncmp(arg, "--backend", 9)) {
            if (!VALUE("--backend") || (strcmp(v, "cpu") && strcmp(v, "vulkan")))
                return tpk_cli_fail("iso", "--backend expects cpu or vulkan, found '%s'", v ? v : "");
            *vulkan = !strcmp(v, "vulkan");
        } else if (!strcmp(arg, "--json")) {
            *json = 1;
        } else if (arg[0] == '-' && arg[1]) {
            return tpk_cli_fail("iso", "unknown option '%s' (see tetpack iso --help)", arg);
        } else if (!o->input) {
            o->input = arg;
        } else if (!o->output) {
            o->output = arg;
        } else {
            return tpk_cli_fail("iso", "expected IN.tpk and OUT, found a third argument '%s'", arg);
        }
#undef VALUE
    }
    if (!o->input || !o->output || !o->value_count)
        return tpk_cli_fail("iso", "expected IN.tpk OUT.ply|.obj|.glb --value V[,V...] (see tetpack iso --help)");
    if (!tpk_iso_format_of(o->output))
        return tpk_cli_fail("iso", "OUTPUT '%s': unknown extension; expected .ply, .obj or .glb", o->output);
    return 0;
}

int tpk_cmd_iso(int argc, char **argv)
{
    for (int i = 1; i < argc; i++)
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            fputs(iso_help, stdout);
            return TPK_EXIT_OK;
        }
    tpk_iso_options o;
    memset(&o, 0, sizeof o);
    double values[TPK_ISO_MAX_VALUES];
    int json = 0, vulkan = 0;
    if (parse_args(argc, argv, &o, values, &json, &vulkan))
        return TPK_EXIT_USAGE;
    vk_source source;
    memset(&source, 0, sizeof source);
#ifdef TPK_WITH_VULKAN
    tpk_iso_corners corners = {vk_emit, &source};
    if (vulkan)
        o.corners = &corners;
#else
    if (vulkan)
        return tpk_cli_fail("iso", "--backend vulkan: this tetpack was built without Vulkan (TETPACK_WITH_VULKAN=OFF)");
#endif
    o.values = values;
    tpk_output_input input = {.arg = "IN.tpk", .given = o.input};
    if (tpk_cli_check_output("iso", "OUTPUT", o.output, &input, 1))
        return TPK_EXIT_USAGE;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    tpk_iso_report r;
    int rc = tpk_iso_run(&o, &r, &diag);
    double device_seconds = 0, gpu_seconds = -1;
#ifdef TPK_WITH_VULKAN
    if (source.vk) {
        device_seconds = tpk_iso_vk_seconds(source.vk);
        gpu_seconds = tpk_iso_vk_gpu_seconds(source.vk);
    }
    char device[256];
    snprintf(device, sizeof device, "%s", source.device ? source.device : "");
    tpk_iso_vk_destroy(source.vk);
    source.device = device;
#endif
    if (rc != 0)
        return tpk_cli_fail("iso", "%s", diag.message);
    if (json)
        print_json(&o, &r, vulkan ? "vulkan" : "cpu", vulkan ? source.device : "cpu", device_seconds,
                   gpu_seconds);
    else
        printf("%s: %lld triangles, %lld vertices (%d value%s of '%s', step %u) in %.3f s (extraction %.3f s)\n",
               o.output, (long long)r.triangles, (long long)r.vertices, r.value_count, r.value_count == 1 ? "" : "s",
               r.field, o.step, r.seconds_load + r.seconds_extract + r.seconds_write, r.seconds_extract);
    return TPK_EXIT_OK;
}
