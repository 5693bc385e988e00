/* tetpack render of a part set (spec §15): every part loaded; one frame through render_frame.c. The CPU
 * reference marches emission-absorption, isosurfaces, the clip box and probes across the cuts by the
 * links, on the parts' own arrays (tpk_set_marcher); lighting, tet fields and the Vulkan renderer take
 * the parts as one mesh (tpk_set_mesh: a vertex on a cut once, a linked face the neighbor across it, the
 * outer faces the shell), which they draw as the single file the set was cut from. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "render/render.h"
#include "render_args.h"
#include "render_frame.h"
#include "tetpack.h"

typedef struct set_view {
    double bounds_min[3], bounds_max[3]; /* of the parts' headers */
    double range[2];                     /* the field's, over all parts */
    double lo[3], hi[3];                 /* of the stored positions, as one file's */
    int has_scalars;
    int tet_field;                       /* the field shown is a tet field */
} set_view;

/* Part p's arrays and links, merged into the view's boxes and range. */
static int load_part(const render_args *a, tpk_partset *set, uint32_t p, tpk_mesh_arrays *mesh,
                     const tpk_link **links, uint64_t *link_count, set_view *v)
{
    tpk_file *file = tpk_partset_file(set, p);
    int association;
    if (render_args_check_field("render", a, file, &association))
        return TPK_EXIT_USAGE;
    v->tet_field = association == TPK_ASSOC_TET;
    tpk_result r = tpk_load_arrays(file, render_args_layout(file, a->layout), v->tet_field ? NULL : a->field,
                                   (uint32_t)a->step, mesh);
    if (r == TPK_OK)
        r = tpk_partset_links(set, p, links, link_count);
    if (r != TPK_OK)
        return tpk_cli_fail("render", "%s: part %u: %s", a->path, p, tpk_error_text(file));
    tpk_file_info info;
    tpk_get_info(file, &info);
    double range[2];
    render_args_field_range(file, a->field, range);
    v->has_scalars = mesh->scalars != NULL;
    for (int k = 0; k < 3; k++) {
        v->bounds_min[k] = p == 0 || info.bounds_min[k] < v->bounds_min[k] ? info.bounds_min[k] : v->bounds_min[k];
        v->bounds_max[k] = p == 0 || info.bounds_max[k] > v->bounds_max[k] ? info.bounds_max[k] : v->bounds_max[k];
    }
    v->range[0] = p == 0 || range[0] < v->range[0] ? range[0] : v->range[0];
    v->range[1] = p == 0 || range[1] > v->range[1] ? range[1] : v->range[1];
    for (uint64_t i = 0; i < mesh->vertex_count; i++)
        for (int k = 0; k < 3; k++) {
            double x = mesh->positions[3 * i + k];
            v->lo[k] = x < v->lo[k] ? x : v->lo[k];
            v->hi[k] = x > v->hi[k] ? x : v->hi[k];
        }
    return 0;
}

void render_set_extent(const render_args *a, tpk_partset *set, double bounds_min[3], double bounds_max[3],
                       double range[2])
{
    int first = 1;
    for (uint32_t p = 0; p < tpk_partset_part_count(set); p++) {
        tpk_file *file = tpk_partset_file(set, p);
        if (!file)
            continue;
        tpk_file_info info;
        tpk_get_info(file, &info);
        double r[2];
        render_args_field_range(file, a->field, r);
        for (int k = 0; k < 3; k++) {
            bounds_min[k] = first || info.bounds_min[k] < bounds_min[k] ? info.bounds_min[k] : bounds_min[k];
            bounds_max[k] = first || info.bounds_max[k] > bounds_max[k] ? info.bounds_max[k] : bounds_max[k];
        }
        range[0] = first || r[0] < range[0] ? r[0] : range[0];
        range[1] = first || r[1] > range[1] ? r[1] : range[1];
        first = 0;
    }
}

/* The parts as one mesh, with the field shown (a point field in mesh, a tet field in opt). */
static int load_set_mesh(const render_args *a, tpk_partset *set, const set_view *v, tpk_set_mesh **out,
                         tpk_mesh_arrays *mesh, tpk_render_options *opt)
{
    char err[1024] = "";
    tpk_result r = tpk_set_mesh_create(out, set, render_args_layout(tpk_partset_file(set, 0), a->layout), err,
                                       sizeof err);
    if (r == TPK_OK)
        r = tpk_set_mesh_arrays(*out, v->tet_field ? NULL : a->field, (uint32_t)a->step, mesh, err, sizeof err);
    if (r == TPK_OK && v->tet_field) {
        mesh->scalars = NULL; /* the tet field replaces any point field */
        r = tpk_set_mesh_tet_field(*out, a->field, (uint32_t)a->step, &opt->tet_scalars, err, sizeof err);
    }
    if (r != TPK_OK)
        return tpk_cli_fail("render", "%s: cannot take its parts as one mesh: %s", a->path,
                            err[0] ? err : tpk_result_string(r));
    return 0;
}

/* One frame of the set: the options from the arguments, with the set's box and range as defaults. */
static int render_set_frame(const render_args *a, tpk_partset *set, const tpk_set_marcher *marcher,
                            const set_view *v)
{
    tpk_transfer_function tf;
    if (render_args_load_tf("render", a, &tf))
        return TPK_EXIT_USAGE;
    tpk_render_options opt;
    tpk_render_options_default(&opt);
    render_args_to_options(a, tpk_partset_file(set, 0), &tf, &opt);
    if (!a->have_camera)
        tpk_camera_default(v->bounds_min, v->bounds_max, &opt.camera);
    if (!a->have_range)
        opt.range_min = v->range[0], opt.range_max = v->range[1];
    double d2 = 0;
    for (int k = 0; k < 3; k++)
        d2 += v->hi[k] > v->lo[k] ? (v->hi[k] - v->lo[k]) * (v->hi[k] - v->lo[k]) : 0;
    if (!(a->unit_distance > 0)) /* the default scale of the whole set, not of part 0 */
        opt.unit_distance = render_args_default_unit(v->bounds_min, v->bounds_max);
    tpk_field_desc field;
    int have_field = render_args_field_desc(tpk_partset_file(set, 0), a->field, &field) == 0;
    if (have_field && !a->have_range)
        field.min_value = (float)v->range[0], field.max_value = (float)v->range[1];
    frame_source src = {.set = marcher, .has_scalars = v->has_scalars, .diagonal = sqrt(d2),
                        .field = have_field ? &field : NULL, .iso_auto = NAN};
    tpk_set_mesh *one = NULL;
    tpk_mesh_arrays mesh;
    if (!marcher) {
        if (load_set_mesh(a, set, v, &one, &mesh, &opt)) {
            tpk_set_mesh_destroy(one);
            return TPK_EXIT_USAGE;
        }
        src.set = NULL;
        src.mesh = &mesh;
    }
    uint8_t *rgba = malloc((size_t)a->width * (size_t)a->height * 4);
    int rc = rgba ? render_frame(a, &src, &opt, a->output, rgba)
                  : tpk_cli_fail("render", "out of memory for a %dx%d image", a->width, a->height);
    free(rgba);
    tpk_set_mesh_destroy(one);
    if (rc == TPK_EXIT_OK && a->save_scene && render_save_scene(a, tpk_partset_file(set, 0), &opt) != 0)
        return TPK_EXIT_USAGE;
    return rc;
}

/* Whether the set is drawn as one mesh: by Vulkan, or with what the link-following marcher cannot give
 * (lighting reads a tet's neighbors' vertices, a tet field its tets; both index one mesh). */
static int as_one_mesh(const render_args *a, const set_view *v)
{
    return !strcmp(a->backend, "vulkan") || v->tet_field || a->shading || a->shadows || a->ao_rays > 0;
}

int render_part_set(const render_args *a)
{
    if (a->have_steps)
        return tpk_cli_fail("render", "%s: a part set renders one step (--step N), not a range", a->path);
    if (a->iso_auto)
        return tpk_cli_fail("render", "%s: --iso auto takes one file's median; for a part set give --iso V", a->path);
    tpk_partset *set = NULL;
    char err[1024] = "";
    tpk_result r = tpk_partset_open(&set, a->path, NULL, NULL, NULL, err, sizeof err);
    if (r != TPK_OK)
        return tpk_cli_fail("render", "%s", err[0] ? err : tpk_result_string(r));
    uint32_t n = tpk_partset_part_count(set);
    tpk_mesh_arrays *meshes = calloc(n, sizeof *meshes);
    const tpk_link **links = calloc(n, sizeof *links);
    uint64_t *link_counts = calloc(n, sizeof *link_counts);
    set_view v = {.lo = {INFINITY, INFINITY, INFINITY}, .hi = {-INFINITY, -INFINITY, -INFINITY}};
    int rc = meshes && links && link_counts ? 0 : tpk_cli_fail("render", "out of memory for %u parts", n);
    for (uint32_t p = 0; rc == 0 && p < n; p++)
        rc = load_part(a, set, p, &meshes[p], &links[p], &link_counts[p], &v);
    tpk_set_marcher *marcher = NULL;
    if (rc == 0 && !as_one_mesh(a, &v) &&
        (r = tpk_set_marcher_create(&marcher, n, meshes, links, link_counts)) != TPK_OK)
        rc = tpk_cli_fail("render", "%s: cannot march across its parts: %s", a->path, tpk_result_string(r));
    if (rc == 0)
        rc = render_set_frame(a, set, marcher, &v);
    tpk_set_marcher_destroy(marcher);
    free(meshes);
    free(links);
    free(link_counts);
    tpk_partset_close(set);
    return rc;
}
