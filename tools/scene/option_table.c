/* The option table (option_table.h): every option of a render, with its flag, its scene key, and the
 * texts of --help and of the scene spec. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "option_table.h"
#include "render/render.h"

const tpk_option_row tpk_option_table[TPK_OPT_COUNT] = {
    {TPK_OPT_VERSION,
     .scene_key = "tetpack_scene", .scene_type = "integer",
     .meaning = "scene format version",
     .scene_default = "1", .constraint = "MUST be 1"},
    {TPK_OPT_CAMERA,
     .flag = "--camera", .metavar = "ex,ey,ez,ax,ay,az,ux,uy,uz,fovy", .expects = "10 numbers "
             "ex,ey,ez,ax,ay,az,ux,uy,uz,fovy (fovy in (0,180))",
     .help = "eye, look-at point, up vector, vertical field of view in degrees\n"
             "(default: a 3/4 view framing the bounds)",
     .help_rank = 3,
     .scene_key = "camera", .scene_type = "object",
     .meaning = "eye, look-at point and up vector in world coordinates, vertical field of view",
     .scene_default = "a 3/4 view framing the bounds", .constraint = "all four keys below present"},
    {TPK_OPT_CAMERA_EYE,
     .scene_key = "camera.eye", .scene_type = "[number ×3]",
     .meaning = "eye position",
     .scene_default = "—", .constraint = "finite"},
    {TPK_OPT_CAMERA_AT,
     .scene_key = "camera.at", .scene_type = "[number ×3]",
     .meaning = "look-at point",
     .scene_default = "—", .constraint = "finite, ≠ `eye`"},
    {TPK_OPT_CAMERA_UP,
     .scene_key = "camera.up", .scene_type = "[number ×3]",
     .meaning = "up vector",
     .scene_default = "—", .constraint = "finite, not zero, not parallel to `at − eye`"},
    {TPK_OPT_CAMERA_FOVY,
     .scene_key = "camera.fovy", .scene_type = "number",
     .meaning = "vertical field of view, degrees",
     .scene_default = "—", .constraint = "0 < fovy < 180",
     .kind = TPK_OPT_KIND_NUMBER, .lo = 0, .hi = 180, .lo_open = 1, .hi_open = 1},
    {TPK_OPT_TF,
     .flag = "--tf", .metavar = "PRESET|FILE", .expects = "a preset name or a file",
     .help = "transfer function: a preset (viridis, cool-warm, inferno,\n"
             "grayscale) or a text file of lines 's r g b a' (default viridis)",
     .help_rank = 4,
     .scene_key = "tf", .scene_type = "object",
     .meaning = "transfer function: exactly one of the three keys below",
     .scene_default = "`{\"preset\": \"viridis\"}`", .constraint = "exactly one key"},
    {TPK_OPT_TF_PRESET,
     .scene_key = "tf.preset", .scene_type = "string",
     .meaning = "a built-in transfer function",
     .scene_default = "—", .constraint = "`viridis`, `cool-warm`, `inferno`, `grayscale`"},
    {TPK_OPT_TF_FILE,
     .scene_key = "tf.file", .scene_type = "string",
     .meaning = "a text file of lines `s r g b a` (as `render --tf FILE`); a relative path is taken from the "
                "scene file's folder",
     .scene_default = "—", .constraint = "the file loads (its errors are reported with its own line)"},
    {TPK_OPT_TF_POINTS,
     .scene_key = "tf.points", .scene_type = "[[number ×5] …]",
     .meaning = "control points `[s, r, g, b, a]` inline",
     .scene_default = "—", .constraint = "2 to 256 points; every number in [0, 1]; `s` strictly increasing"},
    {TPK_OPT_FIELD,
     .flag = "--field", .metavar = "NAME", .expects = "a field name",
     .help = "field to render: a point field (linear in each tet) or a tet\n"
             "field (constant in each tet) (default: the first point field)",
     .help_rank = 5,
     .scene_key = "field", .scene_type = "string",
     .meaning = "the field to render (a point field, or a tet field where the renderer supports it)",
     .scene_default = "the first point field", .constraint = "1..63 bytes"},
    {TPK_OPT_STEP,
     .flag = "--step", .metavar = "N", .expects = "a step number >= 0",
     .help = "time step of the field (default 0)",
     .help_rank = 6,
     .scene_key = "step", .scene_type = "integer",
     .meaning = "the time step of the field",
     .scene_default = "0", .constraint = "0 ≤ step ≤ 2^30",
     .kind = TPK_OPT_KIND_INT, .lo = 0, .hi = 1 << 30},
    {TPK_OPT_STEPS,
     .flag = "--steps", .metavar = "A:B", .expects = "A:B with 0 <= A <= B, at most 100000 steps",
     .help = "render steps A..B, one PNG each: -o must hold one %d\n"
             "conversion for the step, e.g. -o frame_%04d.png",
     .help_rank = 7, .render_only = 1,
     .scene_key = "steps", .scene_type = "[integer ×2]",
     .meaning = "a range of steps `[first, last]` (an animation; `render` then needs `--step N` to pick one)",
     .scene_default = "—", .constraint = "0 ≤ first ≤ last ≤ 2^30; not together with `step`"},
    {TPK_OPT_RANGE,
     .flag = "--range", .metavar = "LO,HI", .expects = "LO,HI with LO < HI",
     .help = "scalar range mapped onto the TF (default: the field's range)",
     .help_rank = 8,
     .scene_key = "range", .scene_type = "[number ×2]",
     .meaning = "scalar range `[low, high]` mapped onto the TF's s ∈ [0, 1]",
     .scene_default = "the field's min and max", .constraint = "finite, low < high"},
    {TPK_OPT_UNIT_DISTANCE,
     .flag = "--unit-distance", .metavar = "D", .expects = "a positive number",
     .help = "TF opacity is per distance D (default: bounds diagonal / 30, so\n"
             "a ray across the whole mesh at the presets' mid opacity 0.08 keeps\n"
             "9% of the light behind it, not 0.03%: inner structure shows; the\n"
             "old default was diagonal / 100: give that D for the old pictures)",
     .help_rank = 10,
     .scene_key = "unit_distance", .scene_type = "number",
     .meaning = "the TF's opacity is per this distance",
     .scene_default = "bounds diagonal / 30", .constraint = "> 0",
     .kind = TPK_OPT_KIND_NUMBER, .lo = 0, .hi = INFINITY, .lo_open = 1, .hi_open = 1},
    {TPK_OPT_CLIP_BOX,
     .flag = "--clip-box", .metavar = "x0,y0,z0,x1,y1,z1", .expects = "6 numbers x0,y0,z0,x1,y1,z1 with x0 <= "
             "x1, y0 <= y1, z0 <= z1",
     .help = "show only the volume inside this box (world coordinates)",
     .help_rank = 14, .effect = 1,
     .scene_key = "clip_box", .scene_type = "[number ×6]",
     .meaning = "`[x0, y0, z0, x1, y1, z1]`: only the volume inside the box shows",
     .scene_default = "no clip", .constraint = "finite, x0 ≤ x1, y0 ≤ y1, z0 ≤ z1"},
    {TPK_OPT_PROBE,
     .flag = "--probe", .metavar = "SHAPE:NUMBERS[:cut]", .expects = "sphere:cx,cy,cz,r, plane:px,py,pz,nx,ny,nz or "
             "box:x0,y0,z0,x1,y1,z1, then :keep (the default) or :cut; at most 4 probes",
     .help = "a CSG probe (repeat: up to 4): a sphere, a half-space (the\n"
             "side of the plane its normal points away from) or a box;\n"
             ":keep shows only what is inside it, :cut cuts that away",
     .help_rank = 15, .effect = 1,
     .scene_key = "probes", .scene_type = "[probe ×1..4]",
     .meaning = "CSG probes, each `{\"shape\": \"sphere\", \"center\": [x, y, z], \"radius\": r}`, "
                "`{\"shape\": \"plane\", \"point\": [x, y, z], \"normal\": [x, y, z]}` or "
                "`{\"shape\": \"box\", \"min\": [x, y, z], \"max\": [x, y, z]}`, with `\"mode\": \"keep\"` "
                "(only the inside shows) or `\"cut\"` (the inside is cut away)",
     .scene_default = "none", .constraint = "radius > 0, normal ≠ 0, min ≤ max; mode keep (default) or cut"},
    {TPK_OPT_ISO,
     .flag = "--iso", .metavar = "V[,V...]|auto", .expects = "1 to 4 comma-separated finite numbers, or auto",
     .help = "up to 4 exact isosurfaces of the field (scalar units), coloured\n"
             "by the TF at V; auto: one at the median of the field's values\n"
             "(the step shown; --json's iso_auto and -v give it)",
     .help_rank = 12, .effect = 1,
     .scene_key = "iso", .scene_type = "[number ×1..4]",
     .meaning = "exact isosurfaces at these scalar values",
     .scene_default = "none", .constraint = "1 to 4 finite values"},
    {TPK_OPT_ISO_OPACITY,
     .flag = "--iso-opacity", .metavar = "A", .expects = "a number in (0,1]",
     .help = "opacity of an isosurface, in (0,1] (default 1)",
     .help_rank = 13, .effect = 1,
     .scene_key = "iso_opacity", .scene_type = "number",
     .meaning = "opacity of an isosurface hit",
     .scene_default = "1", .constraint = "0 < value ≤ 1",
     .kind = TPK_OPT_KIND_NUMBER, .lo = 0, .hi = 1, .lo_open = 1},
    {TPK_OPT_EFFECTS,
     .scene_key = "effects", .scene_type = "object",
     .meaning = "the keys below",
     .scene_default = "all off", .constraint = "only the keys below"},
    {TPK_OPT_SHADING,
     .flag = "--shading", .metavar = NULL, .expects = NULL,
     .help = "gradient shading (two-sided Lambert, ambient 0.3)",
     .help_rank = 16, .effect = 1,
     .scene_key = "effects.shading", .scene_type = "boolean",
     .meaning = "gradient (Lambert) shading",
     .scene_default = "false", .constraint = ""},
    {TPK_OPT_SHADOWS,
     .flag = "--shadows", .metavar = NULL, .expects = NULL,
     .help = "shadows: transmittance marched toward the light",
     .help_rank = 17, .effect = 1,
     .scene_key = "effects.shadows", .scene_type = "boolean",
     .meaning = "shadows from the point light, transmittance marched through the volume",
     .scene_default = "false", .constraint = ""},
    {TPK_OPT_LIGHT,
     .flag = "--light", .metavar = "x,y,z", .expects = "3 numbers x,y,z",
     .help = "point light position (default: at the eye)",
     .help_rank = 18, .effect = 1,
     .scene_key = "effects.light", .scene_type = "[number ×3]",
     .meaning = "point light position, world coordinates",
     .scene_default = "a headlight at the eye", .constraint = "finite"},
    {TPK_OPT_AO_RAYS,
     .flag = "--ao", .metavar = "N", .expects = "a ray count 0..1024 (0: off)",
     .help = "ambient occlusion from N hemisphere rays (0..1024; 0: off)",
     .help_rank = 19, .effect = 1,
     .scene_key = "effects.ao_rays", .scene_type = "integer",
     .meaning = "ambient occlusion with this many hemisphere rays; 0 is off",
     .scene_default = "0", .constraint = "0..1024",
     .kind = TPK_OPT_KIND_INT, .lo = 0, .hi = TPK_RENDER_MAX_AO_RAYS},
    {TPK_OPT_AO_RADIUS,
     .flag = "--ao-radius", .metavar = "R", .expects = "a positive length",
     .help = "length of the AO rays (default: bounds diagonal / 10)",
     .help_rank = 20, .effect = 1,
     .scene_key = "effects.ao_radius", .scene_type = "number",
     .meaning = "length of the AO rays",
     .scene_default = "bounds diagonal / 10", .constraint = "> 0",
     .kind = TPK_OPT_KIND_NUMBER, .lo = 0, .hi = INFINITY, .lo_open = 1, .hi_open = 1},
    {TPK_OPT_OCCLUSION,
     .flag = "--occlusion", .metavar = "ray|vertex", .expects = "ray or vertex",
     .help = "where shadow and AO rays start: at each pixel's shade points\n"
             "(ray, default) or once per frame at the mesh vertices, then\n"
             "interpolated (vertex: far fewer rays)",
     .help_rank = 21, .effect = 1,
     .scene_key = "effects.occlusion", .scene_type = "string",
     .meaning = "where shadow and AO rays start: `ray` at the shade points of every pixel, `vertex` at the mesh "
                "vertices (AO over the whole sphere), interpolated in each tet",
     .scene_default = "`ray`", .constraint = "`ray`, `vertex`",
     .kind = TPK_OPT_KIND_CHOICE, .choices = "ray vertex"},
    {TPK_OPT_LAYOUT,
     .flag = "--layout", .metavar = "tet16|tet20|tet32", .expects = "tet16, tet20 or tet32",
     .help = "which stored layout to march (default: the first present)",
     .help_rank = 9,
     .scene_key = "layout", .scene_type = "string",
     .meaning = "the tet layout to march",
     .scene_default = "the first present of Tet16, Tet20, Tet32", .constraint = "`tet16`, `tet20`, `tet32`",
     .kind = TPK_OPT_KIND_CHOICE, .choices = "tet16 tet20 tet32"},
    {TPK_OPT_SIZE,
     .flag = "--size", .metavar = "WxH", .expects = "WxH (1..16384)",
     .help = "image size (default 512x512)",
     .help_rank = 2,
     .scene_key = "size", .scene_type = "[integer ×2]",
     .meaning = "image `[width, height]` in pixels",
     .scene_default = "512 × 512", .constraint = "1..16384 each"},
    {TPK_OPT_BACKEND,
     .flag = "--backend", .metavar = "vulkan|cpu", .expects = "vulkan or cpu",
     .help = "vulkan: compute shaders on the first Vulkan device (a GPU, else\n"
             "lavapipe); cpu: the reference renderer. Same options, same picture.\n"
             "Default: $TETPACK_RENDER_BACKEND if set, else vulkan on a hardware\n"
             "Vulkan device, else cpu (with only a software rasterizer such as\n"
             "lavapipe the CPU reference is faster; part sets: cpu)",
     .help_rank = 23,
     .scene_key = "backend", .scene_type = "string",
     .meaning = "renderer; `render --backend` overrides it, and it overrides `$TETPACK_RENDER_BACKEND`; where "
                "there is no Vulkan device (or a build without the Vulkan renderer) `vulkan` is drawn by the "
                "CPU reference with a note (the same picture by definition); a saved scene records the "
                "backend that drew it",
     .scene_default = "the default backend", .constraint = "`cpu`, `vulkan`",
     .kind = TPK_OPT_KIND_CHOICE, .choices = "cpu vulkan"},
    {TPK_OPT_INTEGRATION,
     .flag = "--integration", .metavar = "exact|sampled|midpoint", .expects = "exact, sampled or midpoint",
     .help = "per-piece integration as above (default), point samples at\n"
             "most unit-distance/2 apart, or one sample per tet piece at its\n"
             "midpoint",
     .help_rank = 11,
     .scene_key = "integration", .scene_type = "string",
     .meaning = "`exact` per tet piece, `sampled` at most unit_distance / 2 apart, or `midpoint` (one sample "
                "per tet piece)",
     .scene_default = "`exact`", .constraint = "`exact`, `sampled`, `midpoint`",
     .kind = TPK_OPT_KIND_CHOICE, .choices = "exact sampled midpoint"},
    {TPK_OPT_OUTPUT,
     .flag = "--output", .alias = "-o", .metavar = "IMAGE.png", .expects = "an output PNG path",
     .help = "output image (written atomically)",
     .help_rank = 1, .render_only = 1},
    {TPK_OPT_THREADS,
     .flag = "--threads", .metavar = "N", .expects = "1..1024",
     .help = "worker threads of the CPU backend (default: all cores)",
     .help_rank = 22,
     .kind = TPK_OPT_KIND_INT, .lo = 1, .hi = 1024},
    {TPK_OPT_SCENE,
     .flag = "--scene", .metavar = "FILE", .expects = "a scene file",
     .help = "a scene file (spec/scene-json.md): its values first, then the\n"
             "options given here override them",
     .help_rank = 24},
    {TPK_OPT_SAVE_SCENE,
     .flag = "--save-scene", .metavar = "FILE", .expects = "an output path",
     .help = "write the scene of this render (every value it used) as JSON",
     .help_rank = 25},
    {TPK_OPT_JSON,
     .flag = "--json", .metavar = NULL, .expects = NULL,
     .help = "print render statistics as JSON (with the backend and\n"
             "backend_reason: why that backend)",
     .help_rank = 26, .render_only = 1},
    {TPK_OPT_LEGEND,
     .flag = "--legend", .metavar = NULL, .expects = NULL,
     .help = "draw a colour bar of the TF on the image: the field's name and\n"
             "units, its range and ticks (cairo; TETPACK_WITH_CAIRO)",
     .help_rank = 27, .render_only = 1},
    {TPK_OPT_SAVE_TPK,
     .flag = "--save-tpk", .metavar = "FILE", .expects = "an output .tpk path",
     .help = "FILE may be any mesh tetpack convert reads: it is converted\n"
             "in memory with convert's defaults; --save-tpk keeps the .tpk",
     .help_rank = 28},
    {TPK_OPT_VERBOSE,
     .flag = "--verbose", .alias = "-v", .metavar = NULL, .expects = NULL,
     .help = "say on stderr which backend renders and why, and what was\n"
             "converted",
     .help_rank = 29, .render_only = 1},
    {TPK_OPT_ISO_RASTER,
     .flag = "--iso-raster", .metavar = NULL, .expects = NULL,
     .help = "draw the --iso surfaces as triangles (Vulkan: compute extraction\n"
             "and an indirect draw, depth-tested), opaque, with --shading at most;\n"
             "no volume. The ray-marched surface's picture up to rasterization",
     .help_rank = 30},
    {TPK_OPT_LEVEL,
     .flag = "--level", .metavar = "K", .expects = "a level of detail 0..8 (0: the full mesh)",
     .help = "render level of detail K of the file (convert --levels; tetpack\n"
             "info lists them), with the full mesh's camera and range",
     .help_rank = 31, .render_only = 1, .kind = TPK_OPT_KIND_INT, .lo = 0, .hi = 8},
    {TPK_OPT_MAX_MS,
     .flag = "--max-ms", .metavar = "T", .expects = "a time in milliseconds > 0",
     .help = "a time budget: the finest level of detail whose predicted frame\n"
             "time fits T ms (a cost model fitted on two small frames of the\n"
             "coarsest level, then on every frame drawn); where even the\n"
             "coarsest does not fit, rays at every d-th pixel only\n"
             "(--max-pixel-step), the picture between them interpolated;\n"
             "--json reports the level, its field error, the pixel step and\n"
             "the prediction. view: while the view moves; at rest it draws\n"
             "the full mesh at every pixel",
     .help_rank = 32, .kind = TPK_OPT_KIND_NUMBER, .lo = 0, .hi = INFINITY, .lo_open = 1,
     .hi_open = 1},
    {TPK_OPT_MAX_PIXEL_STEP,
     .flag = "--max-pixel-step", .metavar = "D", .expects = "a pixel step from 1 to 16",
     .help = "with --max-ms, the largest pixel step the budget may take\n"
             "(default 8; 1: every pixel, whatever the budget)",
     .help_rank = 33, .kind = TPK_OPT_KIND_INT, .lo = 1, .hi = 16},
};

const char *tpk_option_scene_leaf(tpk_option_id id)
{
    const char *key = tpk_option_table[id].scene_key;
    const char *dot = key ? strchr(key, '.') : NULL;
    return dot ? dot + 1 : key;
}

int tpk_option_scene_keys(const char *parent, const char **names, int cap)
{
    size_t n = strlen(parent);
    int count = 0;
    for (int i = 0; i < TPK_OPT_COUNT && count < cap; i++) {
        const char *key = tpk_option_table[i].scene_key;
        if (!key)
            continue;
        const char *dot = strchr(key, '.');
        if (n == 0 ? dot == NULL : (dot && (size_t)(dot - key) == n && !strncmp(key, parent, n)))
            names[count++] = n == 0 ? key : dot + 1;
    }
    return count;
}

int tpk_option_int_ok(tpk_option_id id, double v)
{
    const tpk_option_row *r = &tpk_option_table[id];
    return r->kind == TPK_OPT_KIND_INT && v == floor(v) && v >= r->lo && v <= r->hi;
}

int tpk_option_number_ok(tpk_option_id id, double v)
{
    const tpk_option_row *r = &tpk_option_table[id];
    return r->kind == TPK_OPT_KIND_NUMBER && isfinite(v) && (r->lo_open ? v > r->lo : v >= r->lo) &&
           (r->hi_open ? v < r->hi : v <= r->hi);
}

int tpk_option_choice(tpk_option_id id, const char *text)
{
    const tpk_option_row *r = &tpk_option_table[id];
    if (r->kind != TPK_OPT_KIND_CHOICE || !text)
        return -1;
    size_t n = strlen(text);
    int index = 0;
    for (const char *at = r->choices; *at; index++) {
        size_t len = strcspn(at, " ");
        if (len == n && n > 0 && !strncmp(at, text, n))
            return index;
        at += len;
        at += strspn(at, " ");
    }
    return -1;
}

const char *tpk_option_choice_name(tpk_option_id id, int index, char *buf, size_t cap)
{
    const tpk_option_row *r = &tpk_option_table[id];
    buf[0] = 0;
    if (r->kind != TPK_OPT_KIND_CHOICE || index < 0)
        return buf;
    const char *at = r->choices;
    for (int i = 0; *at; i++) {
        size_t len = strcspn(at, " ");
        if (i == index) {
            snprintf(buf, cap, "%.*s", (int)len, at);
            return buf;
        }
        at += len;
        at += strspn(at, " ");
    }
    return buf;
}
