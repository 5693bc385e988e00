/* The viewer's renderer, kept across frames: the Vulkan renderer with the arrays uploaded once (made
 * again when the arrays change), presenting to the window's swapchain or read back for OpenGL, or the
 * CPU reference where no Vulkan device is present. */
#include <stdio.h>
#include <string.h>

#include "view_internal.h"
#ifdef TPK_WITH_VULKAN
#include "render_vk/render_vk.h"
#endif

#ifdef TPK_WITH_VULKAN
/* A renderer whose device presents to the window, and its swapchain at the drawable's size. */
static int open_presenting(view_renderer *r, const view_state *s, view_window *window, tpk_diag *diag)
{
    tpk_vk_surface_source surface;
    view_window_surface_source(window, &surface);
    int width, height;
    view_window_size(window, &width, &height);
    if (tpk_vk_renderer_create_presenting(&r->vk, &s->mesh, s->opt.tet_scalars, &surface, diag) != 0 ||
        tpk_vk_presenter_create(&r->present, r->vk, width, height, diag) != 0) {
        view_renderer_close(r);
        return -1;
    }
    r->window = window;
    snprintf(r->device, sizeof r->device, "vulkan: %s, presented (%s)", tpk_vk_renderer_device(r->vk),
             tpk_vk_presenter_describe(r->present));
    return 0;
}
#endif

int view_renderer_open(view_renderer *r, const view_state *s, int cpu, view_window *window, tpk_diag *diag)
{
    view_renderer_close(r);
    (void)s, (void)window, (void)diag; /* without Vulkan: unused */
#ifdef TPK_WITH_VULKAN
    char why[256] = "";
    if (!cpu && !r->cpu_only && !tpk_vulkan_available(why, sizeof why)) {
        fprintf(stderr, "tetpack view: note: no Vulkan device (%s); rendering with the CPU reference\n", why);
        r->cpu_only = 1;
    }
    if (!cpu && !r->cpu_only && s->iso_raster) { /* read back and shown through OpenGL (cmd_view.c) */
        if (tpk_iso_raster_create(&r->raster, &s->mesh, diag) != 0)
            return -1;
        snprintf(r->device, sizeof r->device, "vulkan: %s, isosurface triangles, OpenGL",
                 tpk_iso_raster_device(r->raster));
        return 0;
    }
    if (!cpu && !r->cpu_only && window)
        return open_presenting(r, s, window, diag);
    if (!cpu && !r->cpu_only) {
        if (tpk_vk_renderer_create(&r->vk, &s->mesh, s->opt.tet_scalars, diag) != 0)
            return -1;
        snprintf(r->device, sizeof r->device, "vulkan: %s, OpenGL", tpk_vk_renderer_device(r->vk));
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
    if (r->present) {
        int window_width, window_height;
        view_window_size(r->window, &window_width, &window_height);
        return tpk_vk_presenter_frame(r->present, &opt, window_width, window_height, stats, diag);
    }
    if (r->vk)
        return tpk_vk_renderer_frame(r->vk, &opt, rgba, stats, diag);
    if (r->raster)
        return tpk_iso_raster_frame(r->raster, &opt, rgba, stats, diag);
#endif
    if (!r->cache && !(r->cache = tpk_vertex_cache_create())) /* also keeps the marcher across frames */
        return tpk_diag_fail(diag, "view: out of memory for the frame cache");
    return tpk_render_cpu_cached(&s->mesh, &opt, rgba, r->cache, stats, diag);
}

int view_renderer_read(view_renderer *r, uint8_t *rgba, int width, int height, tpk_diag *diag)
{
    (void)r, (void)rgba, (void)width, (void)height; /* without Vulkan: unused */
#ifdef TPK_WITH_VULKAN
    if (r->present)
        return tpk_vk_presenter_read(r->present, rgba, width, height, diag);
#endif
    return tpk_diag_fail(diag, "view: the renderer does not present");
}

void view_renderer_close(view_renderer *r)
{
#ifdef TPK_WITH_VULKAN
    tpk_vk_presenter_destroy(r->present); /* before the renderer: its device and surface */
    tpk_vk_renderer_destroy(r->vk);
    tpk_iso_raster_destroy(r->raster);
#endif
    tpk_vertex_cache_destroy(r->cache);
    r->cache = NULL;
    r->present = NULL;
    r->vk = NULL;
    r->raster = NULL;
    r->window = NULL;
}
