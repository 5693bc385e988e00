/* What the viewer shows: the file's arrays for one layout, field and step, the render options, and the
 * keys that change them (TF preset, field, step, layout, iso, shading, clip box); the scene of it all. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "scene/scene.h"
#include "view_internal.h"

static const tpk_layout layouts[3] = {TPK_LAYOUT_TET16, TPK_LAYOUT_TET20, TPK_LAYOUT_TET32};
static const uint32_t layout_tags[3] = {TPK_TAG_TT16, TPK_TAG_TT20, TPK_TAG_TT32};

static int find_preset(const char *name)
{
    for (int i = 0; tpk_tf_preset(i); i++)
        if (!strcmp(tpk_tf_preset(i), name))
            return i;
    return -1;
}

/* Field `i`'s descriptor into the state (name, association, steps, range): the TF's range follows it. */
static void take_field(view_state *s, const tpk_field_desc *d)
{
    snprintf(s->field, sizeof s->field, "%s", d->name);
    s->tet_field = d->association == TPK_ASSOC_TET;
    s->step_count = d->step_count;
    double lo = d->min_value, hi = d->max_value;
    for (uint32_t p = 1; s->set && p < tpk_partset_part_count(s->set); p++) { /* a set: every part's range */
        tpk_file *part = tpk_partset_file(s->set, p);
        for (uint32_t i = 0; part && i < tpk_field_count(part); i++) {
            tpk_field_desc e;
            if (tpk_get_field(part, i, &e) == TPK_OK && !strcmp(e.name, d->name) && e.min_value <= e.max_value)
                lo = e.min_value < lo ? e.min_value : lo, hi = e.max_value > hi ? e.max_value : hi;
        }
    }
    s->opt.range_min = 0.0, s->opt.range_max = 1.0; /* as render: an empty range maps onto [0, 1] */
    if (lo < hi)
        s->opt.range_min = lo, s->opt.range_max = hi;
    if (s->opt.iso_count)
        s->opt.iso[0] = 0.5 * (s->opt.range_min + s->opt.range_max);
}

/* The arrays of the state's layout, field and step. */
static int load(view_state *s, tpk_diag *diag)
{
    if (s->set_mesh) { /* a part set: the parts' fields gathered by the merged ids */
        char err[512] = "";
        tpk_result r = tpk_set_mesh_arrays(s->set_mesh, s->field[0] && !s->tet_field ? s->field : NULL,
                                           (uint32_t)s->step, &s->mesh, err, sizeof err);
        s->opt.tet_scalars = NULL;
        if (r == TPK_OK && s->tet_field) {
            s->mesh.scalars = NULL;
            r = tpk_set_mesh_tet_field(s->set_mesh, s->field, (uint32_t)s->step, &s->opt.tet_scalars, err, sizeof err);
        }
        return r == TPK_OK ? 0 : tpk_diag_fail(diag, "%s: %s", s->path, err[0] ? err : tpk_result_string(r));
    }
    const char *point_field = s->field[0] && !s->tet_field ? s->field : NULL;
    tpk_result r = tpk_load_arrays(s->file, s->layout, point_field, (uint32_t)s->step, &s->mesh);
    s->opt.tet_scalars = NULL;
    if (r == TPK_OK && s->tet_field) {
        s->mesh.scalars = NULL; /* the tet field replaces any point field */
        r = tpk_load_tet_field(s->file, s->field, (uint32_t)s->step, &s->opt.tet_scalars);
    }
    s->opt.cull = NULL; /* culled iso frames walk only the blocks that may hold a value (render.h) */
    if (r == TPK_OK)
        r = tpk_render_use_cull(s->file, &s->cull, &s->opt);
    return r == TPK_OK ? 0 : tpk_diag_fail(diag, "%s: %s", s->path, tpk_error_text(s->file));
}

int view_state_init(view_state *s, const tpk_view_options *o, tpk_diag *diag)
{
    memset(s, 0, sizeof *s);
    s->file = o->file;
    s->path = o->path;
    s->opt = o->render;
    s->tf = o->tf;
    s->opt.tf = &s->tf;
    s->tf_preset = find_preset(s->tf.name);
    s->step = o->step;
    s->step_count = 1;
    s->layout = o->layout;
    s->iso_raster = o->iso_raster;
    tpk_file_info info;
    tpk_get_info(o->file, &info);
    memcpy(s->bounds_min, info.bounds_min, sizeof s->bounds_min);
    memcpy(s->bounds_max, info.bounds_max, sizeof s->bounds_max);
    s->set_mesh = o->set_mesh;
    s->set = o->set_mesh ? o->set : NULL;
    if (s->set_mesh) {
        memcpy(s->bounds_min, o->set_bounds_min, sizeof s->bounds_min);
        memcpy(s->bounds_max, o->set_bounds_max, sizeof s->bounds_max);
    }
    for (uint32_t i = 0; i < tpk_field_count(o->file); i++) {
        tpk_field_desc d;
        if (tpk_get_field(o->file, i, &d) == TPK_OK &&
            (o->field ? !strcmp(o->field, d.name) : d.association == TPK_ASSOC_POINT)) {
            tpk_render_options given = s->opt; /* its range and iso are the caller's (--range, a scene) */
            take_field(s, &d);
            s->opt = given;
            break;
        }
    }
    if (tpk_level_set_open(&s->levels, o->file, o->path, diag) != 0)
        return -1;
    if (o->field && !s->field[0])
        return tpk_diag_fail(diag, "%s: no field named '%s'", o->path, o->field);
    if (s->step < 0 || (uint32_t)s->step >= s->step_count)
        return tpk_diag_fail(diag, "%s: field '%s' has %u step(s), step %d asked", o->path, s->field, s->step_count,
                             s->step);
    return load(s, diag);
}

int view_state_set_level(view_state *s, int level, tpk_diag *diag)
{
    if (level == s->level || level < 0 || level >= s->levels.count)
        return 0;
    int before = s->level;
    s->level = level;
    s->file = s->levels.files[level];
    if (load(s, diag) != 0) {
        s->level = before;
        s->file = s->levels.files[before];
        return -1;
    }
    return 1;
}

void view_state_close(view_state *s)
{
    tpk_level_set_close(&s->levels);
    s->level = 0;
    s->file = s->levels.files[0];
}

static int next_field(view_state *s, tpk_diag *diag)
{
    uint32_t n = tpk_field_count(s->file), at = 0;
    if (n == 0 || (n == 1 && s->field[0]))
        return 0;
    if (!s->field[0] || tpk_find_field(s->file, s->field, &at) != TPK_OK)
        at = n - 1; /* no field shown yet: the first one is next */
    tpk_field_desc d;
    if (tpk_get_field(s->file, (at + 1) % n, &d) != TPK_OK)
        return tpk_diag_fail(diag, "%s: %s", s->path, tpk_error_text(s->file));
    view_state before = *s;
    take_field(s, &d);
    s->step = s->step < (int)s->step_count ? s->step : (int)s->step_count - 1;
    if (load(s, diag) != 0) {
        *s = before;
        return -1;
    }
    return 1;
}

static int next_layout(view_state *s, tpk_diag *diag)
{
    if (s->set_mesh)
        return 0; /* the parts were merged into one layout */
    int at = 0;
    while (at < 3 && layouts[at] != s->layout)
        at++;
    for (int k = 1; k <= 3; k++) {
        uint64_t chunk;
        int i = (at + k) % 3;
        if (tpk_find_chunk(s->file, layout_tags[i], 0, 0, &chunk) != TPK_OK)
            continue;
        if (layouts[i] == s->layout)
            return 0;
        tpk_layout before = s->layout;
        s->layout = layouts[i];
        if (load(s, diag) != 0) {
            s->layout = before;
            return -1;
        }
        return 1;
    }
    return 0;
}

static int step_by(view_state *s, int delta, tpk_diag *diag)
{
    int to = s->step + delta;
    if (to < 0 || (uint32_t)to >= s->step_count)
        return 0;
    s->step = to;
    if (load(s, diag) != 0) {
        s->step -= delta;
        return -1;
    }
    return 1;
}

static int next_tf(view_state *s, tpk_diag *diag)
{
    int next = tpk_tf_preset(s->tf_preset + 1) ? s->tf_preset + 1 : 0;
    if (tpk_tf_load(tpk_tf_preset(next), &s->tf, diag) != 0)
        return -1;
    s->tf_preset = next;
    return 0;
}

/* The first probe's next shape (none, sphere, plane, box, none ...), made at the middle of the bounds:
 * a cut sphere of a quarter of the diagonal, a plane facing the camera that keeps the far half, a cut
 * box from the middle to the upper corner. */
static void next_probe(view_state *s)
{
    tpk_render_options *o = &s->opt;
    int shape = o->probe_count > 0 ? o->probes[0].shape + 1 : TPK_PROBE_SPHERE;
    if (shape > TPK_PROBE_BOX) {
        memmove(o->probes, o->probes + 1, sizeof o->probes[0] * (size_t)(o->probe_count - 1));
        o->probe_count--;
        return;
    }
    if (o->probe_count == 0)
        o->probe_count = 1;
    tpk_probe *p = &o->probes[0];
    double mid[3], diag2 = 0, fwd[3], len = 0;
    for (int k = 0; k < 3; k++) {
        mid[k] = 0.5 * (s->bounds_min[k] + s->bounds_max[k]);
        diag2 += (s->bounds_max[k] - s->bounds_min[k]) * (s->bounds_max[k] - s->bounds_min[k]);
        fwd[k] = o->camera.at[k] - o->camera.eye[k];
        len += fwd[k] * fwd[k];
    }
    memset(p, 0, sizeof *p);
    p->shape = shape;
    memcpy(p->a, mid, sizeof p->a);
    if (shape == TPK_PROBE_SPHERE) {
        p->cut = 1;
        p->radius = diag2 > 0 ? 0.25 * sqrt(diag2) : 1;
    } else if (shape == TPK_PROBE_PLANE) {
        for (int k = 0; k < 3; k++)
            p->b[k] = len > 0 ? -fwd[k] / sqrt(len) : k == 0;
    } else {
        p->cut = 1;
        memcpy(p->b, s->bounds_max, sizeof p->b);
        for (int k = 0; k < 3; k++)
            if (!(p->b[k] > p->a[k]))
                p->b[k] = p->a[k] + 1;
    }
}

/* Move the first probe by a twentieth of the bounds' diagonal along the camera's axis `axis` (0 right,
 * 1 up, 2 forward) times `sign`, or scale it by 1.25^sign (axis 3: a sphere's radius, a box about its
 * middle; a plane has no size). */
static void move_probe(view_state *s, int axis, int sign)
{
    tpk_render_options *o = &s->opt;
    if (o->probe_count == 0)
        return;
    tpk_probe *p = &o->probes[0];
    if (axis == 3) {
        double f = sign > 0 ? 1.25 : 0.8;
        if (p->shape == TPK_PROBE_SPHERE)
            p->radius *= f;
        for (int k = 0; p->shape == TPK_PROBE_BOX && k < 3; k++) {
            double mid = 0.5 * (p->a[k] + p->b[k]), half = 0.5 * (p->b[k] - p->a[k]) * f;
            p->a[k] = mid - half;
            p->b[k] = mid + half;
        }
        return;
    }
    tpk_camera_basis basis;
    tpk_diag quiet = {0};
    if (tpk_camera_basis_of(&o->camera, 1, 1, &basis, &quiet) != 0)
        return;
    const double *dir = axis == 0 ? basis.right : axis == 1 ? basis.up : basis.forward;
    double diag2 = 0;
    for (int k = 0; k < 3; k++)
        diag2 += (s->bounds_max[k] - s->bounds_min[k]) * (s->bounds_max[k] - s->bounds_min[k]);
    double step = sign * (diag2 > 0 ? sqrt(diag2) / 20 : 0.05);
    for (int k = 0; k < 3; k++) {
        p->a[k] += step * dir[k];
        if (p->shape == TPK_PROBE_BOX)
            p->b[k] += step * dir[k];
    }
}

int view_state_apply(view_state *s, view_action action, tpk_diag *diag)
{
    switch (action) {
    case VIEW_NEXT_TF: return next_tf(s, diag);
    case VIEW_NEXT_FIELD: return next_field(s, diag);
    case VIEW_STEP_BACK: return step_by(s, -1, diag);
    case VIEW_STEP_FORWARD: return step_by(s, 1, diag);
    case VIEW_NEXT_LAYOUT: return next_layout(s, diag);
    case VIEW_ISO:
        s->opt.iso_count = !s->opt.iso_count;
        s->opt.iso[0] = 0.5 * (s->opt.range_min + s->opt.range_max);
        return 0;
    case VIEW_SHADING: s->opt.shading = !s->opt.shading; return 0;
    case VIEW_CLIP: /* the half of the bounds below the middle of x */
        s->opt.clip = !s->opt.clip;
        memcpy(s->opt.clip_min, s->bounds_min, sizeof s->opt.clip_min);
        memcpy(s->opt.clip_max, s->bounds_max, sizeof s->opt.clip_max);
        s->opt.clip_max[0] = 0.5 * (s->bounds_min[0] + s->bounds_max[0]);
        return 0;
    case VIEW_PROBE: next_probe(s); return 0;
    case VIEW_PROBE_MODE:
        if (s->opt.probe_count > 0)
            s->opt.probes[0].cut = !s->opt.probes[0].cut;
        return 0;
    case VIEW_PROBE_LEFT: move_probe(s, 0, -1); return 0;
    case VIEW_PROBE_RIGHT: move_probe(s, 0, 1); return 0;
    case VIEW_PROBE_UP: move_probe(s, 1, 1); return 0;
    case VIEW_PROBE_DOWN: move_probe(s, 1, -1); return 0;
    case VIEW_PROBE_AWAY: move_probe(s, 2, 1); return 0;
    case VIEW_PROBE_NEAR: move_probe(s, 2, -1); return 0;
    case VIEW_PROBE_GROW: move_probe(s, 3, 1); return 0;
    case VIEW_PROBE_SHRINK: move_probe(s, 3, -1); return 0;
    default: return 0;
    }
}

int view_state_write_scene(const view_state *s, const char *path, int vulkan, tpk_diag *diag)
{
    tpk_scene scene;
    tpk_scene_from_options(&s->opt, s->field, s->step, s->layout, &scene);
    scene.backend = vulkan ? TPK_SCENE_BACKEND_VULKAN : TPK_SCENE_BACKEND_CPU;
    return tpk_scene_write(path, &scene, diag);
}

void view_state_describe(const view_state *s, char *out, size_t n)
{
    snprintf(out, n, "%s: %s%s step %d/%u, tet%d, %s%s%s%s%s%s", s->path, s->field[0] ? s->field : "(no field)",
             s->tet_field ? " (tet)" : "", s->step, s->step_count, (int)s->layout, s->tf.name,
             s->opt.iso_count ? ", iso" : "", s->opt.shading ? ", shading" : "", s->opt.clip ? ", clip" : "",
             s->opt.probe_count ? ", probe " : "",
             s->opt.probe_count ? tpk_probe_shape_name(s->opt.probes[0].shape) : "");
    if (s->level > 0 && strlen(out) + 32 < n)
        snprintf(out + strlen(out), n - strlen(out), ", level %d (%lld tets)", s->level, (long long)s->levels.tets[s->level]);
}
