/* The vertex cache kept across frames (render.h: tpk_vertex_cache): render.h OCCLUSION AT VERTICES says
 * what S_v and A_v depend on; a half whose inputs are the last update's is kept, the other cast alone by
 * tpk_render_vertex_cache with the kept half's effect off (its rays are separate: S_v is the same with or
 * without AO rays, A_v with or without shadow rays). */
#include <stdlib.h>
#include <string.h>

#include "render_internal.h"
#include "transfer_function.h"

/* The options of the table (render_options.def) that the vertex cache keys. */
enum {
    TABLE_OPTIONS = 0
#define TPK_OPTION(ID, name, kind, R, ...) +R
#include "render_options.def"
#undef TPK_OPTION
};

/* What one half depends on, zeroed and then filled, so that equal inputs compare equal bytewise. */
typedef struct cache_key {
    const tpk_mesh_arrays *mesh; /* the arrays' identity: */
    const float *positions, *scalars, *tet_scalars;
    uint64_t vertex_count, tet_count;
    tpk_transfer_function tf;
    double range[2], iso[TPK_RENDER_MAX_ISO], clip[6], light[3];
    double option[TABLE_OPTIONS]; /* each table option's value where half `which` depends on it, else 0 */
    int iso_count, clip_on, probe_count;
    tpk_probe probes[TPK_RENDER_MAX_PROBES];
} cache_key;

struct tpk_vertex_cache {
    float *s, *a;
    uint64_t count; /* floats allocated in each */
    int valid[2];   /* S, A */
    cache_key key[2];
    render_keep keep; /* the marcher and range trees of the frames */
};

/* The table's options half `which` depends on (TPK_USE's cache column, where its `when` holds). */
static void key_options(const tpk_render_options *opt, int which, cache_key *k)
{
    int n = 0;
#define TPK_USE(init, when, always, cache, ...) ((TPK_OPTION_CACHE_##cache >> which & 1) && (when))
#define TPK_OPTION(ID, name, kind, R, A, S, rule, cli, key, use, vk) \
    TPK_IF(R, k->option[n++] = use ? (double)opt->name : 0;)
#include "render_options.def"
#undef TPK_OPTION
#undef TPK_USE
}

/* Half `which` (0: S, 1: A): the light for S only (and the table's options of each half). */
static void key_of(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, int which, cache_key *k)
{
    memset(k, 0, sizeof *k);
    k->mesh = mesh;
    k->positions = mesh->positions;
    k->scalars = mesh->scalars;
    k->tet_scalars = opt->tet_scalars;
    k->vertex_count = mesh->vertex_count;
    k->tet_count = mesh->tet_count;
    if (opt->tf) {
        k->tf.count = opt->tf->count;
        memcpy(k->tf.points, opt->tf->points, sizeof k->tf.points[0] * (size_t)opt->tf->count);
    }
    k->range[0] = opt->range_min, k->range[1] = opt->range_max;
    k->iso_count = opt->iso_count;
    memcpy(k->iso, opt->iso, sizeof k->iso);
    k->clip_on = opt->clip;
    if (opt->clip)
        for (int i = 0; i < 3; i++)
            k->clip[i] = opt->clip_min[i], k->clip[3 + i] = opt->clip_max[i];
    k->probe_count = opt->probe_count;
    memcpy(k->probes, opt->probes, sizeof k->probes[0] * (size_t)opt->probe_count);
    key_options(opt, which, k);
    for (int i = 0; i < 3 && which == 0 && opt->shadows; i++) /* a headlight is the eye: it moves with the camera */
        k->light[i] = opt->have_light ? opt->light[i] : opt->camera.eye[i];
}

tpk_vertex_cache *tpk_vertex_cache_create(void)
{
    return calloc(1, sizeof(tpk_vertex_cache));
}

void tpk_vertex_cache_destroy(tpk_vertex_cache *c)
{
    if (!c)
        return;
    free(c->s);
    free(c->a);
    render_keep_free(&c->keep);
    free(c);
}

void tpk_vertex_cache_frames_per_field(tpk_vertex_cache *c, int frames)
{
    if (c)
        c->keep.frames = frames > 0 ? frames : 0;
}

const float *tpk_vertex_cache_s(const tpk_vertex_cache *c)
{
    return c->s;
}

const float *tpk_vertex_cache_a(const tpk_vertex_cache *c)
{
    return c->a;
}

static int cpu_caster(void *user, const tpk_mesh_arrays *mesh, const tpk_render_options *opt, float *s, float *a,
                      tpk_render_stats *stats, tpk_diag *diag)
{
    (void)user;
    return tpk_render_vertex_cache(mesh, opt, s, a, stats, diag);
}

int tpk_vertex_cache_update(tpk_vertex_cache *c, const tpk_mesh_arrays *mesh, const tpk_render_options *opt,
                            int *changed, tpk_render_stats *cast, tpk_diag *diag)
{
    return tpk_vertex_cache_update_with(c, mesh, opt, cpu_caster, NULL, changed, cast, diag);
}

int tpk_vertex_cache_update_with(tpk_vertex_cache *c, const tpk_mesh_arrays *mesh, const tpk_render_options *opt,
                                 tpk_vertex_caster caster, void *user, int *changed, tpk_render_stats *cast,
                                 tpk_diag *diag)
{
    if (changed)
        *changed = 0;
    if (cast)
        memset(cast, 0, sizeof *cast);
    cache_key key[2];
    int stale[2];
    for (int h = 0; h < 2; h++) {
        key_of(mesh, opt, h, &key[h]);
        stale[h] = !c->valid[h] || memcmp(&key[h], &c->key[h], sizeof key[h]) != 0;
    }
    if (!stale[0] && !stale[1])
        return 0;
    uint64_t n = mesh->vertex_count ? mesh->vertex_count : 1;
    if (c->count < n) {
        free(c->s), free(c->a);
        c->s = malloc(sizeof *c->s * n), c->a = malloc(sizeof *c->a * n);
        c->count = c->s && c->a ? n : 0;
        c->valid[0] = c->valid[1] = 0;
        stale[0] = stale[1] = 1;
        if (!c->count)
            return tpk_diag_fail(diag, "render: out of memory for the vertex cache");
    }
    float *s = malloc(sizeof *s * n), *a = malloc(sizeof *a * n);
    tpk_render_options one = *opt;
    if (!stale[0])
        one.shadows = 0; /* A alone */
    if (!stale[1])
        one.ao_rays = 0; /* S alone */
    c->valid[0] = c->valid[1] = 0; /* until the new halves are in */
    int rc = !s || !a ? tpk_diag_fail(diag, "render: out of memory for the vertex cache")
                      : caster(user, mesh, &one, s, a, cast, diag);
    if (rc == 0) {
        if (stale[0])
            memcpy(c->s, s, sizeof *s * mesh->vertex_count);
        if (stale[1])
            memcpy(c->a, a, sizeof *a * mesh->vertex_count);
        for (int h = 0; h < 2; h++)
            c->key[h] = key[h], c->valid[h] = 1;
        if (changed)
            *changed = 1;
    }
    free(s);
    free(a);
    return rc;
}

int tpk_render_cpu_cached(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                          tpk_vertex_cache *cache, tpk_render_stats *stats, tpk_diag *diag)
{
    if (!cache || !opt || !mesh)
        return tpk_render_cpu(mesh, opt, rgba, stats, diag);
    if (opt->occlusion != TPK_OCCLUSION_VERTEX)
        return render_cpu_keeping(mesh, opt, rgba, NULL, NULL, &cache->keep, stats, diag);
    tpk_render_stats cast;
    if (tpk_render_check_options(opt, diag) != 0 || tpk_vertex_cache_update(cache, mesh, opt, NULL, &cast, diag) != 0)
        return -1;
    int rc = render_cpu_keeping(mesh, opt, rgba, cache->s, cache->a, &cache->keep, stats, diag);
    if (rc == 0 && stats) { /* the frame's work and time include the cache's */
        stats->tet_steps += cast.tet_steps;
        stats->secondary_rays += cast.secondary_rays;
        stats->seconds += cast.seconds;
        stats->vertex_cache_seconds = cast.seconds;
    }
    return rc;
}
