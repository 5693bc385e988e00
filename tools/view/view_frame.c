/* The viewer's renderer, kept across frames: the Vulkan renderer with the arrays uploaded once (made
 * again when the arrays change), or the CPU reference where no Vulkan device is present. */
#include <stdio.h>
#include <string.h>

#include "view_internal.h"
#ifdef TPK_WITH_VULKAN
#include "render_vk/render_vk.h"
#endif

int view_renderer_open(view_renderer *r, const view_state *s, int cpu, tpk_diag *diag)
{
    view_renderer_close(r);
    (void)s, (void)diag; /* without Vulkan: unused */
#ifdef TPK_WITH_VULKAN
    char why[256] = "";
    if (!cpu && !r->cpu_only && !tpk_vulkan_available(why, sizeof why)) {
        fprintf(stderr, "tetpack view: note: no Vulkan device (%s); rendering with the CPU reference\n", why);
        r->cpu_only = 1;
    }
    if (!cpu && !r->cpu_only) {
        if (tpk_vk_renderer_create(&r->vk, &s->mesh, s->opt.tet_scalars, diag) != 0)
            return -1;
        snprintf(r->device, sizeof r->device, "vulkan: %s", tpk_vk_renderer_device(r->vk));
        return 0;
    }
#else
    if (!cpu && !r->cpu_only)
        fprintf(stderr, "tetpack view: note: built without Vulkan; rendering with the CPU reference\n");
#endif
    r->cpu_only = 1;
    snprintf(r->device, sizeof r->device, "cpu");
    return 0;
}

int view_renderer_frame(view_renderer *r, const view_state *s, int width, int height, uint8_t *rgba,
                        tpk_render_stats *stats, tpk_diag *diag)
{
    (void)r; /* without Vulkan: unused */
    tpk_render_options opt = s->opt;
    opt.width = width;
    opt.height = height;
#ifdef TPK_WITH_VULKAN
    if (r->vk)
        return tpk_vk_renderer_frame(r->vk, &opt, rgba, stats, diag);
#endif
    return tpk_render_cpu(&s->mesh, &opt, rgba, stats, diag);
}

void view_renderer_close(view_renderer *r)
{
#ifdef TPK_WITH_VULKAN
    tpk_vk_renderer_destroy(r->vk);
#endif
    r->vk = NULL;
}
