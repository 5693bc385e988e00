/* The Vulkan renderer's frames shown in a window with no read-back: the renderer's device made with a
 * queue that can present to the window's surface, and each frame's bands copied on the device into an
 * image that is blitted into the acquired swapchain image and presented (vk_present.c). The window
 * system stays the caller's: it hands over a surface maker (GLFW's glfwCreateWindowSurface). Vulkan
 * types appear in this header only; render_vk.h stays free of them. */
#ifndef TPK_RENDER_VK_PRESENT_H
#define TPK_RENDER_VK_PRESENT_H

#include <vulkan/vulkan.h>

#include "render_vk.h"

/* What the renderer needs to present to a window: the instance extensions of its surface
 * (glfwGetRequiredInstanceExtensions) and a function that makes the surface on the renderer's instance
 * (glfwCreateWindowSurface with `user` the window). The surface is destroyed with the renderer. */
typedef struct tpk_vk_surface_source {
    const char *const *instance_extensions;
    uint32_t instance_extension_count;
    VkResult (*create)(VkInstance instance, void *user, VkSurfaceKHR *surface);
    void *user;
} tpk_vk_surface_source;

/* tpk_vk_renderer_create on a device whose compute queue can present to the surface, with
 * VK_KHR_swapchain enabled. -1 with a message when no device can (the caller then shows frames another
 * way). The renderer's frames work as tpk_vk_renderer_frame's do besides. */
int tpk_vk_renderer_create_presenting(tpk_vk_renderer **out, const tpk_mesh_arrays *mesh, const float *tet_scalars,
                                      const tpk_vk_surface_source *surface, tpk_diag *diag);

/* A swapchain on the surface of a presenting renderer (which must outlive it), of width x height pixels
 * where the surface lets the size be chosen. 0, or -1 with a message (no 8-bit UNORM format, no blit
 * into it, a Vulkan error). Not thread-safe; one per renderer. */
typedef struct tpk_vk_presenter tpk_vk_presenter;
int tpk_vk_presenter_create(tpk_vk_presenter **out, tpk_vk_renderer *renderer, int width, int height,
                            tpk_diag *diag);
/* Render opt->width x opt->height and show it stretched over the whole window, whose drawable is width x
 * height now (the swapchain is made again when that changed or the last present found it out of date).
 * Nothing is read back but the statistics (stats as tpk_vk_renderer_frame's; gpu_seconds the render's
 * dispatches). A window of size 0 (minimized) shows nothing and returns 0. 0, or -1 with a message. */
int tpk_vk_presenter_frame(tpk_vk_presenter *p, const tpk_render_options *opt, int width, int height,
                           tpk_render_stats *stats, tpk_diag *diag);
/* The last frame shown, read back (top row first, alpha 255 as a window has none) into rgba of width x
 * height pixels: at most the frame's size. For screenshots. 0, or -1 with a message. */
int tpk_vk_presenter_read(tpk_vk_presenter *p, uint8_t *rgba, int width, int height, tpk_diag *diag);
/* The surface format chosen ("B8G8R8A8_UNORM") and the present mode ("immediate", "mailbox", "fifo"). */
const char *tpk_vk_presenter_describe(const tpk_vk_presenter *p);
void tpk_vk_presenter_destroy(tpk_vk_presenter *p);

#endif
