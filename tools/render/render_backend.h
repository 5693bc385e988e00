/* Which renderer draws a picture: the policy of `tetpack render`'s default backend, as a pure function so
 * that every case is tested without the device it needs (tests/test_render_backend.c). Owner:
 * render_backend.c; the probe of the device is render_vk's tpk_vulkan_probe. */
#ifndef TPK_RENDER_BACKEND_H
#define TPK_RENDER_BACKEND_H

#include "base/diag.h"

/* The Vulkan device the renderer would use (TPK_VK_DEVICE, else the first discrete, integrated, virtual,
 * then any): a GPU, a software rasterizer (VK_PHYSICAL_DEVICE_TYPE_CPU: lavapipe), or none. */
typedef enum tpk_vk_device_kind {
    TPK_VK_DEVICE_NONE,
    TPK_VK_DEVICE_HARDWARE,
    TPK_VK_DEVICE_SOFTWARE
} tpk_vk_device_kind;

typedef struct tpk_backend_request {
    const char *flag;         /* --backend vulkan|cpu, or NULL */
    const char *scene;        /* the scene file's "backend", or NULL */
    const char *env;          /* $TETPACK_RENDER_BACKEND, or NULL (empty: unset) */
    int vulkan_built;         /* this tetpack has the Vulkan renderer */
    tpk_vk_device_kind device;
    const char *device_name;  /* the device's name, or why there is none */
    int vulkan_only;          /* an option only the Vulkan renderer has (--iso-raster): the default is Vulkan on any
                                 device, software rasterizers included */
} tpk_backend_request;

typedef struct tpk_backend_choice {
    int vulkan;               /* 1: the Vulkan renderer, 0: the CPU reference */
    int scene_fallback;       /* the scene asked for Vulkan and there is none: the CPU draws it (a note) */
    char reason[256];         /* why, for --json's backend_reason and -v */
} tpk_backend_choice;

/* Does the choice depend on the device (so that the caller must probe it first)? */
int tpk_backend_needs_device(const tpk_backend_request *req);

/* The backend: --backend, else the scene's, else $TETPACK_RENDER_BACKEND, else Vulkan on a hardware
 * device and the CPU reference with a software rasterizer only (it is several times faster there: no
 * shader compilation per run, no LLVM-emulated GPU) or none. A request that cannot be met (vulkan asked
 * for by the flag or the environment without a device or a build with it, an unknown environment value)
 * returns -1 with a message; else 0. Pure. */
int tpk_backend_choose(const tpk_backend_request *req, tpk_backend_choice *out, tpk_diag *diag);

#endif
