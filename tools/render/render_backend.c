/* The default backend's policy (render_backend.h). */
#include <stdio.h>
#include <string.h>

#include "render_backend.h"

static int asks(const char *value, const char *backend) { return value && *value && !strcmp(value, backend); }

int tpk_backend_needs_device(const tpk_backend_request *req)
{
    if (req->flag)
        return asks(req->flag, "vulkan");
    if (req->scene)
        return asks(req->scene, "vulkan");
    return req->vulkan_built && !asks(req->env, "cpu");
}

/* Vulkan asked for by `who` ("--backend vulkan", "TETPACK_RENDER_BACKEND=vulkan"): there must be one. */
static int vulkan_asked(const tpk_backend_request *req, const char *who, tpk_backend_choice *out, tpk_diag *diag)
{
    if (!req->vulkan_built)
        return tpk_diag_fail(diag, "%s: this tetpack was built without Vulkan (TETPACK_WITH_VULKAN=OFF)", who);
    if (req->device == TPK_VK_DEVICE_NONE)
        return tpk_diag_fail(diag, "%s: %s", who, req->device_name ? req->device_name : "no Vulkan device");
    out->vulkan = 1;
    snprintf(out->reason, sizeof out->reason, "%s", who);
    return 0;
}

int tpk_backend_choose(const tpk_backend_request *req, tpk_backend_choice *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    const char *name = req->device_name ? req->device_name : "";
    if (req->flag) {
        if (asks(req->flag, "vulkan"))
            return vulkan_asked(req, "--backend vulkan", out, diag);
        snprintf(out->reason, sizeof out->reason, "--backend cpu");
        return 0;
    }
    if (req->scene) {
        if (!asks(req->scene, "vulkan")) {
            snprintf(out->reason, sizeof out->reason, "the scene's backend cpu");
        } else if (req->vulkan_built && req->device != TPK_VK_DEVICE_NONE) {
            out->vulkan = 1;
            snprintf(out->reason, sizeof out->reason, "the scene's backend vulkan");
        } else {
            out->scene_fallback = 1;
            snprintf(out->reason, sizeof out->reason, "the scene's backend vulkan, but no Vulkan device here: the "
                     "CPU reference draws the same picture");
        }
        return 0;
    }
    if (req->env && *req->env) {
        if (strcmp(req->env, "vulkan") && strcmp(req->env, "cpu"))
            return tpk_diag_fail(diag, "TETPACK_RENDER_BACKEND expects vulkan or cpu, found '%s'", req->env);
        if (asks(req->env, "vulkan"))
            return vulkan_asked(req, "TETPACK_RENDER_BACKEND=vulkan", out, diag);
        snprintf(out->reason, sizeof out->reason, "TETPACK_RENDER_BACKEND=cpu");
        return 0;
    }
    if (req->vulkan_only && req->vulkan_built && req->device != TPK_VK_DEVICE_NONE) {
        out->vulkan = 1;
        snprintf(out->reason, sizeof out->reason, "default: --iso-raster draws with Vulkan (%.180s)", name);
    } else if (!req->vulkan_built)
        snprintf(out->reason, sizeof out->reason, "default: built without Vulkan");
    else if (req->device == TPK_VK_DEVICE_HARDWARE) {
        out->vulkan = 1;
        snprintf(out->reason, sizeof out->reason, "default: a hardware Vulkan device (%.180s)", name);
    } else if (req->device == TPK_VK_DEVICE_SOFTWARE)
        snprintf(out->reason, sizeof out->reason, "default: the only Vulkan device is a software rasterizer "
                 "(%.100s), slower than the CPU reference (--backend vulkan uses it)", name);
    else
        snprintf(out->reason, sizeof out->reason, "default: no Vulkan device (%.180s)", name);
    return 0;
}
