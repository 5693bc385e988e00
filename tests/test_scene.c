/* Scene files (tools/scene/, spec/scene-json.md): every kind of bad scene gets its exact message with
 * file, line, column and key; a scene written and read back gives the same values; a scene applied to
 * render options sets exactly what it gives. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "harness.h"
#include "scene/scene.h"

/* Parse `text` as scene "s.json"; the message (or "" when it parses). */
static const char *parse_message(const char *text, tpk_scene *scene)
{
    static tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_scene_parse("s.json", text, NULL, scene, &diag) == 0)
        return "";
    return diag.message;
}

#define CHECK_PARSE_ERROR(text, expected)                                                          \
    do {                                                                                           \
        tpk_scene scene_;                                                                          \
        const char *got_ = parse_message(text, &scene_);                                           \
        CHECK_MSG(!strcmp(got_, expected), "\n  expected: %s\n  got:      %s", expected, got_);    \
    } while (0)

TPK_TEST(syntax_error_line)
{
    CHECK_PARSE_ERROR("{\n  \"size\": [64, 48],\n  \"camera\": {\n    \"eye\": [1, 2, 3],\n    \"at\": [0, 0 0]\n  }\n}\n",
                      "s.json:5:17: JSON syntax error in key 'camera.at' at '0]'");
    CHECK_PARSE_ERROR("{\n  \"size\": [64, 48],\n", "s.json:3:1: JSON syntax error in key 'size': the text ends too early");
    CHECK_PARSE_ERROR("", "s.json:1:1: JSON syntax error: the text ends too early");
    CHECK_PARSE_ERROR("{\"size\": [64, 48]} x", "s.json:1:20: JSON syntax error at 'x'");
}

TPK_TEST(wrong_type)
{
    CHECK_PARSE_ERROR("{\n  \"effects\": {\n    \"shading\": true,\n    \"ao_rays\": \"many\"\n  }\n}",
                      "s.json:4:5: key 'effects.ao_rays': expected an integer in 0..1024, found \"many\"");
    CHECK_PARSE_ERROR("{\n  \"field\": 3\n}", "s.json:2:3: key 'field': expected a field name (1..63 bytes), found 3");
    CHECK_PARSE_ERROR("{\"effects\": {\"shadows\": 1}}",
                      "s.json:1:14: key 'effects.shadows': expected true or false, found 1");
    CHECK_PARSE_ERROR("{\"layout\": \"tet24\"}",
                      "s.json:1:2: key 'layout': expected \"tet16\", \"tet20\" or \"tet32\", found \"tet24\"");
    CHECK_PARSE_ERROR("[1, 2]", "s.json:1:1: expected a JSON object at the top of a scene, found [1,2]");
    CHECK_PARSE_ERROR("{\"camera\": {\"eye\": [1, 1], \"at\": [0, 0, 0], \"up\": [0, 0, 1], \"fovy\": 30}}",
                      "s.json:1:13: key 'camera.eye': expected [x, y, z], found [1,1]");
}

TPK_TEST(unknown_key)
{
    CHECK_PARSE_ERROR("{\n  \"size\": [64, 48],\n  \"feild\": \"temperature\"\n}",
                      "s.json:3:3: key 'feild': unknown key (did you mean 'field'?); known keys: tetpack_scene, camera, "
                      "tf, field, step, steps, range, unit_distance, clip_box, probes, iso, iso_opacity, effects, layout, size, "
                      "backend, integration");
    CHECK_PARSE_ERROR("{\"effects\": {\"glow\": true}}",
                      "s.json:1:14: key 'effects.glow': unknown key; known keys of effects: shading, shadows, light, "
                      "ao_rays, ao_radius, occlusion");
    CHECK_PARSE_ERROR("{\"size\": [64, 48],\n \"size\": [8, 8]}",
                      "s.json:2:2: key 'size': appears twice in the same object (remove one)");
}

TPK_TEST(out_of_range)
{
    CHECK_PARSE_ERROR("{\n  \"camera\": {\"eye\": [1, 1, 1], \"at\": [0, 0, 0], \"up\": [0, 0, 1], \"fovy\": 190}\n}",
                      "s.json:2:66: key 'camera.fovy': expected a number of degrees in (0, 180), found 190");
    CHECK_PARSE_ERROR("{\"size\": [0, 48]}",
                      "s.json:1:2: key 'size': expected [width, height] with integers in 1..16384, found [0,48]");
    CHECK_PARSE_ERROR("{\"range\": [5, 5]}", "s.json:1:2: key 'range': expected low < high, found [5, 5]");
    CHECK_PARSE_ERROR("{\"clip_box\": [0, 0, 0, 1, -1, 1]}",
                      "s.json:1:2: key 'clip_box': expected min <= max on every axis, found 0 > -1 on axis y");
    CHECK_PARSE_ERROR("{\"iso\": [1, 2, 3, 4, 5]}",
                      "s.json:1:2: key 'iso': expected an array of 1..4 iso values, found [1,2,3,4,5]");
    CHECK_PARSE_ERROR("{\"step\": 1, \"steps\": [0, 2]}",
                      "s.json:1:13: key 'steps': a scene gives either 'step' (one) or 'steps' (a range), not both");
    CHECK_PARSE_ERROR("{\"steps\": [3, 2]}",
                      "s.json:1:2: key 'steps': expected [first, last] with integers 0 <= first <= last <= 1073741824, "
                      "found [3,2]");
    CHECK_PARSE_ERROR("{\"tf\": {\"points\": [[0, 0, 0, 0, 0], [0, 1, 1, 1, 1]]}}",
                      "s.json:1:9: key 'tf.points': point 1: s must increase strictly, found 0 after 0");
    CHECK_PARSE_ERROR("{\"tf\": {\"preset\": \"jet\"}}",
                      "s.json:1:9: key 'tf.preset': expected one of viridis, cool-warm, inferno, grayscale, found \"jet\"");
    /* An empty name is no preset (it made the old substring search loop for ever). */
    CHECK_PARSE_ERROR("{\"tf\": {\"preset\": \"\"}}",
                      "s.json:1:9: key 'tf.preset': expected one of viridis, cool-warm, inferno, grayscale, found \"\"");
    CHECK_PARSE_ERROR("{\"tf\": {\"preset\": \"cool\"}}",
                      "s.json:1:9: key 'tf.preset': expected one of viridis, cool-warm, inferno, grayscale, found \"cool\"");
    CHECK_PARSE_ERROR("{\"tetpack_scene\": 2}",
                      "s.json:1:2: key 'tetpack_scene': expected 1 (the scene format this tetpack reads), found 2");
    CHECK_PARSE_ERROR("{\"camera\": {\"eye\": [1, 1, 1], \"at\": [0, 0, 0], \"up\": [0, 0, 1]}}",
                      "s.json:1:2: key 'camera.fovy': missing: a camera gives eye, at, up and fovy");
    CHECK_PARSE_ERROR("{\"camera\": {\"eye\": [1, 1, 1], \"at\": [0, 0, 0], \"up\": [2, 2, 2], \"fovy\": 30}}",
                      "s.json:1:48: key 'camera.up': is zero or parallel to the view direction (at - eye)");
    CHECK_PARSE_ERROR("{\"unit_distance\": 1e999}", "s.json:1:2: key 'unit_distance': expected a positive number, "
                      "found a number beyond the range of a double");
}

TPK_TEST(load_names_file)
{
    const char *path = tpk_temp_path("bad.json");
    FILE *f = fopen(path, "w");
    CHECK(f);
    fputs("{\n  \"tf\": {\"file\": \"missing_tf.txt\"}\n}\n", f);
    fclose(f);
    tpk_scene scene;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    CHECK(tpk_scene_load(path, &scene, &diag) != 0);
    char expected[1024];
    snprintf(expected, sizeof expected, "%s:2:10: key 'tf.file': %s/missing_tf.txt: not a transfer function preset", path,
             tpk_temp_dir());
    CHECK_MSG(!strncmp(diag.message, expected, strlen(expected)), "got %s", diag.message);
}

/* A TF file that is a FIFO is refused at once, not waited on. */
TPK_TEST(tf_file_fifo_refused)
{
    const char *fifo = tpk_temp_path("tf.fifo");
    unlink(fifo);
    CHECK(mkfifo(fifo, 0600) == 0);
    const char *path = tpk_temp_path("fifo.json");
    FILE *f = fopen(path, "w");
    CHECK(f);
    fprintf(f, "{\"tf\": {\"file\": \"%s\"}}\n", fifo);
    fclose(f);
    tpk_scene scene;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    CHECK(tpk_scene_load(path, &scene, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "key 'tf.file': ") && strstr(diag.message, "tf.fifo: not a regular file"), "got %s",
              diag.message);
    unlink(fifo);
}

static const char full_scene[] =
    "{\n"
    "  \"tetpack_scene\": 1,\n"
    "  \"camera\": {\"eye\": [0.1, 0.2, 0.30000000000000004], \"at\": [0, 1e-9, -2.5], \"up\": [0, 0, 1], \"fovy\": 33.3},\n"
    "  \"tf\": {\"points\": [[0, 0, 0, 1, 0], [0.3333333333333333, 0.5, 0.25, 0.125, 0.0625], [1, 1, 1, 1, 1]]},\n"
    "  \"field\": \"temperature\",\n"
    "  \"steps\": [2, 7],\n"
    "  \"range\": [290.5, 380.25],\n"
    "  \"unit_distance\": 0.001,\n"
    "  \"clip_box\": [-1, -2, -3, 1, 2, 3.5],\n"
    "  \"iso\": [300, 310.5],\n"
    "  \"iso_opacity\": 0.5,\n"
    "  \"effects\": {\"shading\": true, \"shadows\": false, \"light\": [1, 2, 3], \"ao_rays\": 8, \"ao_radius\": 0.01,\n"
    "              \"occlusion\": \"vertex\"},\n"
    "  \"layout\": \"tet20\",\n"
    "  \"size\": [320, 200],\n"
    "  \"backend\": \"vulkan\",\n"
    "  \"integration\": \"sampled\"\n"
    "}\n";

TPK_TEST(round_trip)
{
    tpk_scene a, b;
    const char *msg = parse_message(full_scene, &a);
    CHECK_MSG(!msg[0], "%s", msg);
    uint64_t every = 0; /* every key given: the rows of the keys of the scene, "steps" on step's bit */
    const tpk_option_id keys[] = {TPK_OPT_CAMERA, TPK_OPT_TF, TPK_OPT_FIELD, TPK_OPT_STEP, TPK_OPT_RANGE,
                                  TPK_OPT_UNIT_DISTANCE, TPK_OPT_CLIP_BOX, TPK_OPT_ISO, TPK_OPT_ISO_OPACITY,
                                  TPK_OPT_SHADING, TPK_OPT_SHADOWS, TPK_OPT_LIGHT, TPK_OPT_AO_RAYS, TPK_OPT_AO_RADIUS,
                                  TPK_OPT_OCCLUSION, TPK_OPT_LAYOUT, TPK_OPT_SIZE, TPK_OPT_BACKEND, TPK_OPT_INTEGRATION};
    for (size_t k = 0; k < sizeof keys / sizeof keys[0]; k++)
        every |= TPK_SCENE_GIVEN(keys[k]);
    CHECK(a.given == every);
    const char *path = tpk_temp_path("round.json");
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    CHECK_MSG(tpk_scene_write(path, &a, &diag) == 0, "%s", diag.message);
    CHECK_MSG(tpk_scene_load(path, &b, &diag) == 0, "%s", diag.message);
    /* Inline points stay inline; the TF's name is "inline" both times: the whole struct agrees. */
    CHECK(memcmp(&a, &b, sizeof a) == 0);
    CHECK(a.camera.eye[2] == 0.30000000000000004 && a.tf.points[1].s == 1.0 / 3.0);
    CHECK(a.step_first == 2 && a.step_last == 7 && a.step_range == 1 && a.layout == TPK_LAYOUT_TET20);
    /* A preset stays a preset. */
    CHECK(!parse_message("{\"tf\": {\"preset\": \"inferno\"}, \"step\": 3}", &a)[0]);
    char *text = tpk_scene_to_json(&a);
    CHECK(text && strstr(text, "\"preset\":\t\"inferno\"") && strstr(text, "\"step\":\t3"));
    CHECK(!parse_message(text, &b)[0] && memcmp(&a, &b, sizeof a) == 0);
    free(text);
}

TPK_TEST(apply_and_from_options)
{
    tpk_scene s, back;
    CHECK(!parse_message(full_scene, &s)[0]);
    tpk_render_options opt;
    tpk_render_options_default(&opt);
    tpk_scene_apply(&s, &opt);
    CHECK(opt.width == 320 && opt.height == 200 && opt.tf == &s.tf && opt.range_min == 290.5 && opt.range_max == 380.25);
    CHECK(opt.clip && opt.clip_max[2] == 3.5 && opt.iso_count == 2 && opt.iso[1] == 310.5 && opt.iso_opacity == 0.5);
    CHECK(opt.shading == 1 && opt.shadows == 0 && opt.have_light && opt.light[2] == 3 && opt.ao_rays == 8);
    CHECK(opt.ao_radius == 0.01 && opt.integration == 1 && opt.unit_distance == 0.001 && opt.camera.fovy_deg == 33.3);
    CHECK(opt.occlusion == TPK_OCCLUSION_VERTEX);
    tpk_scene_from_options(&opt, "temperature", 2, TPK_LAYOUT_TET20, &back);
    tpk_render_options again;
    tpk_render_options_default(&again);
    tpk_scene_apply(&back, &again);
    again.tf = opt.tf; /* back.tf is a copy of the same points */
    CHECK(memcmp(&opt, &again, sizeof opt) == 0);
    CHECK(!memcmp(&back.tf, &s.tf, sizeof s.tf) && back.tf_kind == TPK_SCENE_TF_POINTS);
    /* An empty scene changes nothing. */
    tpk_render_options plain, same;
    tpk_render_options_default(&plain);
    same = plain;
    CHECK(!parse_message("{}", &s)[0] && s.given == 0);
    tpk_scene_apply(&s, &same);
    CHECK(memcmp(&plain, &same, sizeof plain) == 0);
}
