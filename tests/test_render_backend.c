/* The default backend's policy (render/render_backend.h) in every case, with the device injected: a
 * hardware device draws with Vulkan, a software rasterizer (lavapipe) or none with the CPU reference,
 * and --backend, a scene and $TETPACK_RENDER_BACKEND say otherwise, in that order. */
#include <string.h>

#include "harness.h"
#include "render/render_backend.h"

static tpk_backend_request request(tpk_vk_device_kind device)
{
    tpk_backend_request r = {.vulkan_built = 1, .device = device,
                             .device_name = device == TPK_VK_DEVICE_HARDWARE   ? "NVIDIA H100"
                                            : device == TPK_VK_DEVICE_SOFTWARE ? "llvmpipe (LLVM 15.0.6, 256 bits)"
                                                                               : "vulkan: no Vulkan device"};
    return r;
}

/* 1 (Vulkan), 0 (CPU) or -1 (refused); reason into out. */
static int choose(const tpk_backend_request *r, tpk_backend_choice *out)
{
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_backend_choose(r, out, &diag) != 0) {
        snprintf(out->reason, sizeof out->reason, "%.250s", diag.message);
        return -1;
    }
    return out->vulkan;
}

TPK_TEST(default_hardware_is_vulkan)
{
    tpk_backend_request r = request(TPK_VK_DEVICE_HARDWARE);
    tpk_backend_choice c;
    CHECK(tpk_backend_needs_device(&r));
    CHECK_EQ_INT(choose(&r, &c), 1);
    CHECK(strstr(c.reason, "hardware Vulkan device (NVIDIA H100)") != NULL);
}

TPK_TEST(default_software_is_cpu)
{
    tpk_backend_request r = request(TPK_VK_DEVICE_SOFTWARE);
    tpk_backend_choice c;
    CHECK_EQ_INT(choose(&r, &c), 0);
    CHECK(strstr(c.reason, "software rasterizer (llvmpipe") != NULL);
    r.env = ""; /* set but empty: unset */
    CHECK_EQ_INT(choose(&r, &c), 0);
}

TPK_TEST(default_without_device_is_cpu)
{
    tpk_backend_request r = request(TPK_VK_DEVICE_NONE);
    tpk_backend_choice c;
    CHECK_EQ_INT(choose(&r, &c), 0);
    CHECK(strstr(c.reason, "no Vulkan device") != NULL);
    r.vulkan_built = 0;
    CHECK(!tpk_backend_needs_device(&r));
    CHECK_EQ_INT(choose(&r, &c), 0);
    CHECK(strstr(c.reason, "built without Vulkan") != NULL);
}

TPK_TEST(env_overrides_default)
{
    tpk_backend_request r = request(TPK_VK_DEVICE_SOFTWARE);
    tpk_backend_choice c;
    r.env = "vulkan";
    CHECK_EQ_INT(choose(&r, &c), 1);
    CHECK(!strcmp(c.reason, "TETPACK_RENDER_BACKEND=vulkan"));
    r = request(TPK_VK_DEVICE_HARDWARE);
    r.env = "cpu";
    CHECK(!tpk_backend_needs_device(&r)); /* no probe: the CPU was asked for */
    CHECK_EQ_INT(choose(&r, &c), 0);
    CHECK(!strcmp(c.reason, "TETPACK_RENDER_BACKEND=cpu"));
    r.env = "metal";
    CHECK_EQ_INT(choose(&r, &c), -1);
    CHECK(strstr(c.reason, "expects vulkan or cpu, found 'metal'") != NULL);
    r = request(TPK_VK_DEVICE_NONE);
    r.env = "vulkan";
    CHECK_EQ_INT(choose(&r, &c), -1);
    CHECK(strstr(c.reason, "TETPACK_RENDER_BACKEND=vulkan: vulkan: no Vulkan device") != NULL);
}

TPK_TEST(flag_overrides_env_and_scene)
{
    tpk_backend_request r = request(TPK_VK_DEVICE_SOFTWARE);
    tpk_backend_choice c;
    r.flag = "vulkan", r.env = "cpu", r.scene = "cpu";
    CHECK_EQ_INT(choose(&r, &c), 1);
    CHECK(!strcmp(c.reason, "--backend vulkan"));
    r = request(TPK_VK_DEVICE_HARDWARE);
    r.flag = "cpu", r.env = "vulkan";
    CHECK(!tpk_backend_needs_device(&r));
    CHECK_EQ_INT(choose(&r, &c), 0);
    CHECK(!strcmp(c.reason, "--backend cpu"));
    r = request(TPK_VK_DEVICE_NONE);
    r.flag = "vulkan";
    CHECK_EQ_INT(choose(&r, &c), -1);
    CHECK(strstr(c.reason, "--backend vulkan: vulkan: no Vulkan device") != NULL);
    r.vulkan_built = 0;
    CHECK_EQ_INT(choose(&r, &c), -1);
    CHECK(strstr(c.reason, "built without Vulkan") != NULL);
}

TPK_TEST(scene_overrides_env)
{
    tpk_backend_request r = request(TPK_VK_DEVICE_SOFTWARE);
    tpk_backend_choice c;
    r.scene = "vulkan", r.env = "cpu";
    CHECK_EQ_INT(choose(&r, &c), 1); /* a scene that asks for Vulkan gets lavapipe when that is all there is */
    r = request(TPK_VK_DEVICE_NONE);
    r.scene = "vulkan";
    CHECK_EQ_INT(choose(&r, &c), 0); /* none: the CPU draws the same picture, with a note */
    CHECK(c.scene_fallback);
    r = request(TPK_VK_DEVICE_HARDWARE);
    r.scene = "cpu", r.env = "vulkan";
    CHECK_EQ_INT(choose(&r, &c), 0);
    CHECK(!strcmp(c.reason, "the scene's backend cpu"));
}
