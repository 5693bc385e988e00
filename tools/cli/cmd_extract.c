/* tetpack extract: keep only what a scene needs (one layout, one field and its steps, the tets in the clip
 * box) in a smaller, valid .tpk, and report the bytes before and after. */
#include <stdlib.h>
#include <string.h>

#include "base/output_file.h"
#include "base/strbuf.h"
#include "cli.h"
#include "render_args.h"
#include "extract/extract.h"
#include "scene/scene.h"
#include "tetpack.h"

static const char extract_help[] =
    "usage: tetpack extract IN.tpk OUT.tpk [--scene FILE] [options]\n"
    "\n"
    "Writes OUT.tpk with only what a render of the scene reads: one tet layout, the field it shows and its\n"
    "steps (renumbered from 0), and the tets whose bounding box meets the clip box, with the shell rebuilt\n"
    "where the box cuts the mesh. Vertices are renumbered compactly; positions, origin and orientation are\n"
    "kept exactly; TMAP and VMAP are mapped through, so picks still name source cells and points. Options\n"
    "given here override the scene's values.\n"
    "\n"
    "  --scene FILE                 take layout, field, step(s), clip box and probes from a scene file\n"
    "  --layout tet16|tet20|tet32   the layout to keep (default: the one render picks, the first present)\n"
    "  --field NAME                 the field to keep (default: the first point field, as render)\n"
    "  --step N | --steps A:B       the step or steps to keep (default 0)\n"
    "  --clip-box x0,y0,z0,x1,y1,z1 keep the tets that meet this box (default: all tets)\n"
    "  --probe SHAPE:NUMBERS[:cut]  keep the tets that may show through this CSG probe (repeat: up to 4;\n"
    "                               sphere:cx,cy,cz,r, plane:px,py,pz,nx,ny,nz or box:x0,y0,z0,x1,y1,z1)\n"
    "  --level K                    read level of detail K of IN.tpk (spec §16; tetpack info lists them)\n"
    "                               instead of the full mesh: OUT.tpk is that level, as its own file\n"
    "  --zstd LEVEL                 0: store uncompressed, 1..22: zstd (default: as the input stored each)\n"
    "  --save-scene FILE            write the scene for OUT.tpk: steps renumbered, and camera and range\n"
    "                               made explicit from IN.tpk, so it renders the same picture\n"
    "  --threads N                  worker threads (default: all cores)\n"
    "  --json                       print the report, with the chunks before and after, as JSON\n";

typedef struct extract_args {
    tpk_extract_options o;
    const char *scene_path, *save_scene;
    int have_layout, have_steps, have_clip, have_probes, json;
    tpk_scene scene;
} extract_args;

static int parse_steps(const char *text, int *first, int *last)
{
    char *end;
    long a = strtol(text, &end, 10);
    if (end == text || *end != ':')
        return -1;
    const char *rest = end + 1;
    long b = strtol(rest, &end, 10);
    if (end == rest || *end || a < 0 || b < a || b > (1 << 30))
        return -1;
    *first = (int)a;
    *last = (int)b;
    return 0;
}

static int parse_option(int argc, char **argv, int *i, extract_args *a)
{
    const char *arg = argv[*i], *v = NULL;
    tpk_extract_options *o = &a->o;
#define VALUE(name) (v = tpk_cli_value(argc, argv, i, name))
    if (!strncmp(arg, "--scene", 7)) {
        if (!VALUE("--scene"))
            return tpk_cli_fail("extract", "--scene expects a scene file");
        a->scene_path = v;
    } else if (!strncmp(arg, "--save-scene", 12)) {
        if (!VALUE("--save-scene"))
            return tpk_cli_fail("extract", "--save-scene expects an output path");
        a->save_scene = v;
    } else if (!strncmp(arg, "--layout", 8)) {
        if (!VALUE("--layout") || (strcmp(v, "tet16") && strcmp(v, "tet20") && strcmp(v, "tet32")))
            return tpk_cli_fail("extract", "--layout expects tet16, tet20 or tet32, found '%s'", v ? v : "");
        o->layout = (tpk_layout)atoi(v + 3);
        a->have_layout = 1;
    } else if (!strncmp(arg, "--field", 7)) {
        if (!VALUE("--field"))
            return tpk_cli_fail("extract", "--field expects a field name");
        o->field = v;
    } else if (!strncmp(arg, "--steps", 7)) {
        if (!VALUE("--steps") || parse_steps(v, &o->step_first, &o->step_last))
            return tpk_cli_fail("extract", "--steps expects A:B with 0 <= A <= B, found '%s'", v ? v : "");
        a->have_steps = 1;
    } else if (!strncmp(arg, "--step", 6)) {
        if (!VALUE("--step") || tpk_cli_parse_int(v, 0, 1 << 30, &o->step_first))
            return tpk_cli_fail("extract", "--step expects a step number >= 0, found '%s'", v ? v : "");
        o->step_last = o->step_first;
        a->have_steps = 1;
    } else if (!strncmp(arg, "--clip-box", 10)) {
        double b[6];
        if (!VALUE("--clip-box") || tpk_cli_parse_doubles(v, b, 6) || !(b[0] < b[3] && b[1] < b[4] && b[2] < b[5]))
            return tpk_cli_fail("extract", "--clip-box expects x0,y0,z0,x1,y1,z1 with min < max on each axis, "
                                "found '%s'", v ? v : "");
        memcpy(o->clip_min, b, sizeof o->clip_min);
        memcpy(o->clip_max, b + 3, sizeof o->clip_max);
        o->clip = a->have_clip = 1;
    } else if (!strncmp(arg, "--probe", 7)) {
        tpk_diag d = {0};
        if (!a->have_probes)
            o->probe_count = 0;
        a->have_probes = 1;
        if (!VALUE("--probe") || o->probe_count >= TPK_RENDER_MAX_PROBES ||
            tpk_probe_parse(v, &o->probes[o->probe_count]))
            return tpk_cli_fail("extract", "--probe expects %s, found '%s'", tpk_option_table[TPK_OPT_PROBE].expects,
                                v ? v : "");
        if (tpk_probe_check(&o->probes[o->probe_count], o->probe_count + 1, &d))
            return tpk_cli_fail("extract", "--probe '%s': %s", v, d.message + strlen("render: "));
        o->probe_count++;
    } else if (!strncmp(arg, "--level", 7)) {
        if (!VALUE("--level") || tpk_cli_parse_int(v, 0, 8, &o->level))
            return tpk_cli_fail("extract", "--level expects a level of detail 0..8 (0: the file itself), found '%s'",
                                v ? v : "");
    } else if (!strncmp(arg, "--zstd", 6)) {
        if (!VALUE("--zstd") || tpk_cli_parse_int(v, 0, 22, &o->zstd_level))
            return tpk_cli_fail("extract", "--zstd expects a level 0..22, found '%s'", v ? v : "");
    } else if (!strncmp(arg, "--threads", 9)) {
        if (!VALUE("--threads") || tpk_cli_parse_int(v, 1, 1024, &o->threads))
            return tpk_cli_fail("extract", "--threads expects 1..1024, found '%s'", v ? v : "");
    } else if (!strcmp(arg, "--json")) {
        a->json = 1;
    } else if (arg[0] == '-' && arg[1]) {
        return tpk_cli_fail("extract", "unknown option '%s' (see tetpack extract --help)", arg);
    } else if (!o->input) {
        o->input = arg;
    } else if (!o->output) {
        o->output = arg;
    } else {
        return tpk_cli_fail("extract", "expected IN.tpk and OUT.tpk, found a third argument '%s'", arg);
    }
#undef VALUE
    return 0;
}

/* The scene's values where the command line gave none. */
static int merge_scene(extract_args *a)
{
    if (!a->scene_path)
        return 0;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    const tpk_scene *s = &a->scene;
    if (tpk_scene_load(a->scene_path, &a->scene, &diag) != 0)
        return tpk_cli_fail("extract", "%s", diag.message);
    if (!a->have_layout && (s->given & TPK_SCENE_LAYOUT))
        a->o.layout = s->layout;
    if (!a->o.field && (s->given & TPK_SCENE_FIELD))
        a->o.field = s->field;
    if (!a->have_steps && (s->given & TPK_SCENE_STEP))
        a->o.step_first = s->step_first, a->o.step_last = s->step_last;
    if (!a->have_clip && (s->given & TPK_SCENE_CLIP)) {
        a->o.clip = 1;
        memcpy(a->o.clip_min, s->clip_min, sizeof a->o.clip_min);
        memcpy(a->o.clip_max, s->clip_max, sizeof a->o.clip_max);
    }
    if (!a->have_probes && (s->given & TPK_SCENE_PROBES)) {
        a->o.probe_count = s->probe_count;
        memcpy(a->o.probes, s->probes, sizeof a->o.probes);
    }
    return 0;
}

/* The scene for OUT.tpk: what it keeps (layout, field, steps from 0, clip box), and the camera, range,
 * unit distance and AO radius a render of IN.tpk would have taken by default, since OUT.tpk's bounds and
 * field range are smaller. */
static int save_scene(const extract_args *a, const tpk_extract_report *r)
{
    tpk_scene s = a->scene;
    s.given |= TPK_SCENE_LAYOUT | TPK_SCENE_STEP;
    s.layout = r->layout;
    s.step_first = 0;
    s.step_last = a->o.step_last - a->o.step_first;
    s.step_range = s.step_last > 0;
    if (r->field[0]) {
        s.given |= TPK_SCENE_FIELD;
        snprintf(s.field, sizeof s.field, "%s", r->field);
    }
    if (a->o.clip) {
        s.given |= TPK_SCENE_CLIP;
        memcpy(s.clip_min, a->o.clip_min, sizeof s.clip_min);
        memcpy(s.clip_max, a->o.clip_max, sizeof s.clip_max);
    }
    if (a->o.probe_count > 0) {
        s.given |= TPK_SCENE_PROBES;
        s.probe_count = a->o.probe_count;
        memcpy(s.probes, a->o.probes, sizeof s.probes);
    }
    if (!(s.given & TPK_SCENE_CAMERA)) {
        s.given |= TPK_SCENE_CAMERA;
        tpk_camera_default(r->bounds_min, r->bounds_max, &s.camera);
    }
    if (!(s.given & TPK_SCENE_UNIT_DISTANCE)) { /* the renderer's defaults follow the mesh's size */
        s.given |= TPK_SCENE_UNIT_DISTANCE;
        s.unit_distance = render_args_default_unit(r->bounds_min, r->bounds_max); /* render's own default */
    }
    if ((s.given & TPK_SCENE_AO_RAYS) && s.ao_rays > 0 && !(s.given & TPK_SCENE_AO_RADIUS)) {
        s.given |= TPK_SCENE_AO_RADIUS;
        s.ao_radius = r->diagonal / 10.0;
    }
    if (!(s.given & TPK_SCENE_RANGE) && r->field[0]) { /* render's default: the field's range, else [0, 1] */
        s.given |= TPK_SCENE_RANGE;
        int have = r->field_min < r->field_max;
        s.range[0] = have ? r->field_min : 0.0;
        s.range[1] = have ? r->field_max : 1.0;
    }
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_scene_write(a->save_scene, &s, &diag) != 0)
        return tpk_cli_fail("extract", "%s", diag.message);
    return 0;
}

/* [{"tag":"POS3","index":0,"step":0,"stored":N,"raw":N}, ...] of the file at path. */
static void chunks_json(tpk_strbuf *sb, const char *path)
{
    tpk_file *file = NULL;
    tpk_strbuf_printf(sb, "[");
    if (tpk_open_path(&file, path, NULL, NULL, 0) == TPK_OK) {
        tpk_file_info info;
        tpk_get_info(file, &info);
        for (uint64_t i = 0; i < info.chunk_count; i++) {
            tpk_dir_entry e;
            if (tpk_get_chunk(file, i, &e) != TPK_OK)
                continue;
            char tag[5] = {(char)(e.tag & 0xff), (char)((e.tag >> 8) & 0xff), (char)((e.tag >> 16) & 0xff),
                           (char)(e.tag >> 24), 0};
            tpk_strbuf_printf(sb, "%s{\"tag\":", i ? "," : "");
            tpk_strbuf_json_string(sb, tag);
            tpk_strbuf_printf(sb, ",\"index\":%u,\"step\":%u,\"stored\":%llu,\"raw\":%llu}", e.index, e.step,
                              (unsigned long long)e.stored_size, (unsigned long long)e.raw_size);
        }
        tpk_close(file);
    }
    tpk_strbuf_printf(sb, "]");
}

static void report(const extract_args *a, const tpk_extract_report *r)
{
    if (!a->json) {
        printf("%s: Tet%d, %s%s; %llu of %llu tets, %llu of %llu vertices, %llu shell faces; %llu bytes, "
               "%.1f%% of %llu\n", a->o.output, (int)r->layout, r->field[0] ? "field " : "no field",
               r->field, (unsigned long long)r->tets_after, (unsigned long long)r->tets_before,
               (unsigned long long)r->vertices_after, (unsigned long long)r->vertices_before,
               (unsigned long long)r->shell_after, (unsigned long long)r->bytes_after,
               r->bytes_before ? 100.0 * (double)r->bytes_after / (double)r->bytes_before : 0.0,
               (unsigned long long)r->bytes_before);
        return;
    }
    tpk_strbuf sb = {0};
    tpk_strbuf_printf(&sb, "{\"input\":");
    tpk_strbuf_json_string(&sb, a->o.input);
    tpk_strbuf_printf(&sb, ",\"output\":");
    tpk_strbuf_json_string(&sb, a->o.output);
    tpk_strbuf_printf(&sb, ",\"layout\":%d,\"field\":", (int)r->layout);
    tpk_strbuf_json_string(&sb, r->field);
    tpk_strbuf_printf(&sb, ",\"steps\":%d,\"bytes_before\":%llu,\"bytes_after\":%llu,\"tets_before\":%llu,"
                      "\"tets_after\":%llu,\"vertices_before\":%llu,\"vertices_after\":%llu,\"shell_faces_before\":%llu,"
                      "\"shell_faces_after\":%llu,\"chunks_before\":", r->steps, (unsigned long long)r->bytes_before,
                      (unsigned long long)r->bytes_after, (unsigned long long)r->tets_before,
                      (unsigned long long)r->tets_after, (unsigned long long)r->vertices_before,
                      (unsigned long long)r->vertices_after, (unsigned long long)r->shell_before,
                      (unsigned long long)r->shell_after);
    chunks_json(&sb, a->o.input);
    tpk_strbuf_printf(&sb, ",\"chunks_after\":");
    chunks_json(&sb, a->o.output);
    tpk_strbuf_printf(&sb, "}\n");
    if (!sb.failed)
        fputs(sb.data, stdout);
    tpk_strbuf_free(&sb);
}

int tpk_cmd_extract(int argc, char **argv)
{
    extract_args a;
    memset(&a, 0, sizeof a);
    a.o.zstd_level = -1;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            fputs(extract_help, stdout);
            return TPK_EXIT_OK;
        }
        int rc = parse_option(argc, argv, &i, &a);
        if (rc)
            return rc;
    }
    if (!a.o.input || !a.o.output)
        return tpk_cli_fail("extract", "expected IN.tpk and OUT.tpk (see tetpack extract --help)");
    tpk_output_input inputs[2] = {{.arg = "IN.tpk", .given = a.o.input}, {.arg = "--scene", .given = a.scene_path}};
    size_t count = a.scene_path ? 2 : 1;
    if (tpk_cli_check_output("extract", "OUT.tpk", a.o.output, inputs, count) ||
        (a.save_scene && tpk_cli_check_output("extract", "--save-scene", a.save_scene, inputs, count)) ||
        merge_scene(&a))
        return TPK_EXIT_USAGE;
    a.o.command_line = tpk_cli_joined(argc, argv, a.o.output);
    tpk_extract_report r;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_extract(&a.o, &r, &diag) != 0)
        return tpk_cli_fail("extract", "%s", diag.message);
    if (a.save_scene && save_scene(&a, &r))
        return TPK_EXIT_USAGE;
    report(&a, &r);
    return TPK_EXIT_OK;
}
