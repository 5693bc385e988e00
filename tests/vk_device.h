/* For the Vulkan tests: whether a Vulkan device is here; where none is, the running test is skipped with
 * the reason (a failure under TETPACK_REQUIRE_ALL=1, harness.h). */
#ifndef TPK_TEST_VK_DEVICE_H
#define TPK_TEST_VK_DEVICE_H

#include "harness.h"
#include "render_vk/render_vk.h"

static inline int have_device(void)
{
    char why[512];
    if (tpk_vulkan_available(why, sizeof why))
        return 1;
    tpk_test_skip(why);
    return 0;
}

#endif
