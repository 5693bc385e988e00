/* The renderer's frames in a window's swapchain (render_vk_present.h): each band's pixels are copied on
 * the device into a frame image (R8G8B8A8), which is blitted over the acquired swapchain image and
 * presented. The host reads back the statistics only, and the frame image when a screenshot asks. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render_vk_internal.h"

#define MAX_IMAGES 8 /* swapchain images; drivers give 2 to 4 */

struct tpk_vk_presenter {
    tpk_vk_renderer *renderer;
    const tpk_vk_context *ctx;
    VkSwapchainKHR swapchain;
    VkSurfaceFormatKHR format;
    VkPresentModeKHR mode;
    VkExtent2D extent;
    int asked_width, asked_height; /* the drawable's size it was made for (extent may differ: the surface's) */
    uint32_t image_count;
    VkImage images[MAX_IMAGES];
    VkSemaphore rendered[MAX_IMAGES]; /* per image: a present's wait is over once the image comes back */
    VkSemaphore acquired;
    int out_of_date;           /* the last acquire or present said so: make the swapchain again */
    VkImage frame;             /* the rendered frame, frame_width x frame_height at most */
    VkDeviceMemory frame_memory;
    int frame_width, frame_height;
    int shown_width, shown_height; /* of the last frame shown (its top-left part of the frame image) */
    VkCommandPool pool;
    VkCommandBuffer cmd;
    VkFence fence;
    char description[64];
};

static int vk_check(VkResult r, const char *step, tpk_diag *diag)
{
    if (r == VK_SUCCESS)
        return 0;
    return tpk_diag_fail(diag, "vulkan: %s failed: %s (%d)", step, tpk_vk_result_name(r), (int)r);
}

/* ---- The swapchain -------------------------------------------------------------------------------- */

/* An 8-bit UNORM format, so that the blit copies the renderer's values as they are (an _SRGB format
 * would encode them once more). */
static int pick_format(tpk_vk_presenter *p, tpk_diag *diag)
{
    VkSurfaceFormatKHR formats[64];
    uint32_t n = 64;
    VkResult r = vkGetPhysicalDeviceSurfaceFormatsKHR(p->ctx->physical, p->ctx->surface, &n, formats);
    if (r != VK_SUCCESS && r != VK_INCOMPLETE)
        return vk_check(r, "listing the surface's formats", diag);
    for (uint32_t i = 0; i < n; i++) {
        VkFormat f = formats[i].format;
        if (f != VK_FORMAT_B8G8R8A8_UNORM && f != VK_FORMAT_R8G8B8A8_UNORM)
            continue;
        VkFormatProperties props;
        vkGetPhysicalDeviceFormatProperties(p->ctx->physical, f, &props);
        if (props.optimalTilingFeatures & VK_FORMAT_FEATURE_BLIT_DST_BIT) {
            p->format = formats[i];
            return 0;
        }
    }
    return tpk_diag_fail(diag, "vulkan: the window's surface has no 8-bit UNORM format that can be blitted into");
}

/* Immediate, else mailbox, else FIFO (always there): the renderer is the bottleneck, as the OpenGL
 * path's swap interval 0 says. */
static void pick_mode(tpk_vk_presenter *p)
{
    VkPresentModeKHR modes[16];
    uint32_t n = 16;
    p->mode = VK_PRESENT_MODE_FIFO_KHR;
    VkResult r = vkGetPhysicalDeviceSurfacePresentModesKHR(p->ctx->physical, p->ctx->surface, &n, modes);
    if (r != VK_SUCCESS && r != VK_INCOMPLETE)
        return;
    for (uint32_t i = 0; i < n; i++)
        if (modes[i] == VK_PRESENT_MODE_IMMEDIATE_KHR ||
            (modes[i] == VK_PRESENT_MODE_MAILBOX_KHR && p->mode != VK_PRESENT_MODE_IMMEDIATE_KHR))
            p->mode = modes[i];
}

static void destroy_semaphores(tpk_vk_presenter *p)
{
    for (uint32_t i = 0; i < MAX_IMAGES; i++)
        if (p->rendered[i])
            vkDestroySemaphore(p->ctx->device, p->rendered[i], NULL), p->rendered[i] = VK_NULL_HANDLE;
}

/* The swapchain (again) for a drawable of width x height; the old one is retired into it. */
static int make_swapchain(tpk_vk_presenter *p, int width, int height, tpk_diag *diag)
{
    VkSurfaceCapabilitiesKHR caps;
    VkResult r = vkGetPhysicalDeviceSurfaceCapabilitiesKHR(p->ctx->physical, p->ctx->surface, &caps);
    if (r != VK_SUCCESS)
        return vk_check(r, "reading the surface's capabilities", diag);
    if (!(caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_DST_BIT))
        return tpk_diag_fail(diag, "vulkan: the window's swapchain images cannot be copied into");
    VkExtent2D extent = caps.currentExtent;
    if (extent.width == 0xFFFFFFFFu) { /* the surface takes the swapchain's size */
        extent.width = (uint32_t)width, extent.height = (uint32_t)height;
        extent.width = extent.width < caps.minImageExtent.width ? caps.minImageExtent.width : extent.width;
        extent.width = extent.width > caps.maxImageExtent.width ? caps.maxImageExtent.width : extent.width;
        extent.height = extent.height < caps.minImageExtent.height ? caps.minImageExtent.height : extent.height;
        extent.height = extent.height > caps.maxImageExtent.height ? caps.maxImageExtent.height : extent.height;
    }
    uint32_t count = caps.minImageCount + 1;
    if (caps.maxImageCount && count > caps.maxImageCount)
        count = caps.maxImageCount;
    VkCompositeAlphaFlagBitsKHR alpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR; /* a window has no alpha to show */
    for (uint32_t bit = 1; !(caps.supportedCompositeAlpha & alpha) && bit <= 8; bit <<= 1)
        alpha = (VkCompositeAlphaFlagBitsKHR)bit;
    VkSwapchainKHR old = p->swapchain;
    VkSwapchainCreateInfoKHR info = {
        .sType = VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR,
        .surface = p->ctx->surface,
        .minImageCount = count,
        .imageFormat = p->format.format,
        .imageColorSpace = p->format.colorSpace,
        .imageExtent = extent,
        .imageArrayLayers = 1,
        .imageUsage = VK_IMAGE_USAGE_TRANSFER_DST_BIT,
        .imageSharingMode = VK_SHARING_MODE_EXCLUSIVE,
        .preTransform = caps.currentTransform,
        .compositeAlpha = alpha,
        .presentMode = p->mode,
        .clipped = VK_TRUE,
        .oldSwapchain = old,
    };
    vkDeviceWaitIdle(p->ctx->device);
    r = vkCreateSwapchainKHR(p->ctx->device, &info, NULL, &p->swapchain);
    if (old)
        vkDestroySwapchainKHR(p->ctx->device, old, NULL);
    destroy_semaphores(p);
    if (r != VK_SUCCESS) {
        p->swapchain = VK_NULL_HANDLE;
        return vk_check(r, "creating the window's swapchain", diag);
    }
    p->extent = extent;
    p->asked_width = width, p->asked_height = height;
    p->out_of_date = 0;
    p->image_count = MAX_IMAGES;
    r = vkGetSwapchainImagesKHR(p->ctx->device, p->swapchain, &p->image_count, p->images);
    if (r != VK_SUCCESS && r != VK_INCOMPLETE)
        return vk_check(r, "listing the swapchain's images", diag);
    VkSemaphoreCreateInfo semaphore = {.sType = VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    for (uint32_t i = 0; i < p->image_count; i++)
        if (vk_check(vkCreateSemaphore(p->ctx->device, &semaphore, NULL, &p->rendered[i]), "creating a semaphore",
                     diag))
            return -1;
    return 0;
}

/* ---- The frame image ------------------------------------------------------------------------------ */

static void destroy_frame(tpk_vk_presenter *p)
{
    if (p->frame)
        vkDestroyImage(p->ctx->device, p->frame, NULL);
    if (p->frame_memory)
        vkFreeMemory(p->ctx->device, p->frame_memory, NULL);
    p->frame = VK_NULL_HANDLE, p->frame_memory = VK_NULL_HANDLE;
    p->frame_width = p->frame_height = 0;
}

/* A frame image of at least width x height in device memory; made again only when it must grow, so
 * that the smaller frames of a drag reuse it. */
static int need_frame(tpk_vk_presenter *p, int width, int height, tpk_diag *diag)
{
    if (width <= p->frame_width && height <= p->frame_height)
        return 0;
    width = width > p->frame_width ? width : p->frame_width;
    height = height > p->frame_height ? height : p->frame_height;
    vkDeviceWaitIdle(p->ctx->device);
    destroy_frame(p);
    VkImageCreateInfo info = {
        .sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO,
        .imageType = VK_IMAGE_TYPE_2D,
        .format = VK_FORMAT_R8G8B8A8_UNORM,
        .extent = {(uint32_t)width, (uint32_t)height, 1},
        .mipLevels = 1,
        .arrayLayers = 1,
        .samples = VK_SAMPLE_COUNT_1_BIT,
        .tiling = VK_IMAGE_TILING_OPTIMAL,
        .usage = VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
        .sharingMode = VK_SHARING_MODE_EXCLUSIVE,
        .initialLayout = VK_IMAGE_LAYOUT_UNDEFINED,
    };
    VkResult r = vkCreateImage(p->ctx->device, &info, NULL, &p->frame);
    if (r != VK_SUCCESS) {
        p->frame = VK_NULL_HANDLE;
        return vk_check(r, "creating the frame image", diag);
    }
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(p->ctx->device, p->frame, &req);
    uint32_t order[VK_MAX_MEMORY_TYPES];
    int n = tpk_vk_memory_rank(&p->ctx->memory, p->ctx->unified, req.memoryTypeBits, TPK_VK_MEMORY_DEVICE, order);
    r = VK_ERROR_OUT_OF_DEVICE_MEMORY;
    for (int k = 0; k < n && r != VK_SUCCESS; k++) {
        VkMemoryAllocateInfo alloc = {
            .sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, .allocationSize = req.size, .memoryTypeIndex = order[k]};
        r = vkAllocateMemory(p->ctx->device, &alloc, NULL, &p->frame_memory);
    }
    if (r != VK_SUCCESS) {
        p->frame_memory = VK_NULL_HANDLE;
        return vk_check(r, "allocating the frame image", diag);
    }
    if (vk_check(vkBindImageMemory(p->ctx->device, p->frame, p->frame_memory, 0), "binding the frame image", diag))
        return -1;
    p->frame_width = width, p->frame_height = height;
    return 0;
}

static void image_barrier(VkCommandBuffer cmd, VkImage image, VkImageLayout from, VkImageLayout to,
                          VkPipelineStageFlags src_stage, VkAccessFlags src, VkPipelineStageFlags dst_stage,
                          VkAccessFlags dst)
{
    VkImageMemoryBarrier b = {
        .sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER,
        .srcAccessMask = src,
        .dstAccessMask = dst,
        .oldLayout = from,
        .newLayout = to,
        .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
        .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
        .image = image,
        .subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1},
    };
    vkCmdPipelineBarrier(cmd, src_stage, dst_stage, 0, 0, NULL, 0, NULL, 1, &b);
}

/* The band target: the band's rows into the frame image (in TRANSFER_DST_OPTIMAL for the whole frame). */
static void record_band_copy(VkCommandBuffer cmd, VkBuffer pixels, int width, int row0, int rows, void *user)
{
    const tpk_vk_presenter *p = user;
    VkBufferImageCopy region = {
        .imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
        .imageOffset = {0, row0, 0},
        .imageExtent = {(uint32_t)width, (uint32_t)rows, 1},
    };
    vkCmdCopyBufferToImage(cmd, pixels, p->frame, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region);
}

/* ---- Commands ------------------------------------------------------------------------------------- */

static int begin(tpk_vk_presenter *p, tpk_diag *diag)
{
    VkCommandBufferBeginInfo info = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO, .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT};
    if (vk_check(vkResetCommandBuffer(p->cmd, 0), "resetting the present commands", diag) ||
        vk_check(vkBeginCommandBuffer(p->cmd, &info), "recording the present commands", diag))
        return -1;
    return 0;
}

/* End, submit (waiting for `wait` at the transfer stage and signalling `signal`, either may be null)
 * and wait for the commands. */
static int submit(tpk_vk_presenter *p, VkSemaphore wait, VkSemaphore signal, tpk_diag *diag)
{
    const VkPipelineStageFlags stage = VK_PIPELINE_STAGE_TRANSFER_BIT;
    VkSubmitInfo info = {
        .sType = VK_STRUCTURE_TYPE_SUBMIT_INFO,
        .waitSemaphoreCount = wait ? 1 : 0,
        .pWaitSemaphores = &wait,
        .pWaitDstStageMask = &stage,
        .commandBufferCount = 1,
        .pCommandBuffers = &p->cmd,
        .signalSemaphoreCount = signal ? 1 : 0,
        .pSignalSemaphores = &signal,
    };
    if (vk_check(vkEndCommandBuffer(p->cmd), "recording the present commands", diag) ||
        vk_check(vkResetFences(p->ctx->device, 1, &p->fence), "resetting a fence", diag) ||
        vk_check(vkQueueSubmit(p->ctx->queue, 1, &info, p->fence), "submitting the present commands", diag) ||
        vk_check(vkWaitForFences(p->ctx->device, 1, &p->fence, VK_TRUE, UINT64_MAX), "waiting for the present commands",
                 diag))
        return -1;
    return 0;
}

/* The frame image made ready for the bands' copies (its old contents dropped). */
static int prepare_frame(tpk_vk_presenter *p, tpk_diag *diag)
{
    if (begin(p, diag) != 0)
        return -1;
    image_barrier(p->cmd, p->frame, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                  VK_PIPELINE_STAGE_TRANSFER_BIT, 0, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
    return submit(p, VK_NULL_HANDLE, VK_NULL_HANDLE, diag);
}

/* Acquire an image (the swapchain made again once when out of date), blit the frame over it, present. */
static int show(tpk_vk_presenter *p, int width, int height, tpk_diag *diag)
{
    uint32_t index = 0;
    VkResult r = vkAcquireNextImageKHR(p->ctx->device, p->swapchain, UINT64_MAX, p->acquired, VK_NULL_HANDLE, &index);
    if (r == VK_ERROR_OUT_OF_DATE_KHR) {
        if (make_swapchain(p, width, height, diag) != 0)
            return -1;
        r = vkAcquireNextImageKHR(p->ctx->device, p->swapchain, UINT64_MAX, p->acquired, VK_NULL_HANDLE, &index);
    }
    if (r == VK_SUBOPTIMAL_KHR)
        p->out_of_date = 1, r = VK_SUCCESS;
    if (vk_check(r, "acquiring a swapchain image", diag) || begin(p, diag) != 0)
        return -1;
    VkImage target = p->images[index];
    image_barrier(p->cmd, p->frame, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                  VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                  VK_ACCESS_TRANSFER_READ_BIT);
    image_barrier(p->cmd, target, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                  VK_PIPELINE_STAGE_TRANSFER_BIT, 0, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
    VkImageBlit blit = {
        .srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
        .srcOffsets = {{0, 0, 0}, {p->shown_width, p->shown_height, 1}},
        .dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
        .dstOffsets = {{0, 0, 0}, {(int32_t)p->extent.width, (int32_t)p->extent.height, 1}},
    };
    /* nearest: a reduced frame of a drag shows as blocks, as the OpenGL path's glPixelZoom shows it */
    vkCmdBlitImage(p->cmd, p->frame, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, target, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                   1, &blit, VK_FILTER_NEAREST);
    image_barrier(p->cmd, target, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR,
                  VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT,
                  0);
    if (submit(p, p->acquired, p->rendered[index], diag) != 0)
        return -1;
    VkPresentInfoKHR present = {
        .sType = VK_STRUCTURE_TYPE_PRESENT_INFO_KHR,
        .waitSemaphoreCount = 1,
        .pWaitSemaphores = &p->rendered[index],
        .swapchainCount = 1,
        .pSwapchains = &p->swapchain,
        .pImageIndices = &index,
    };
    r = vkQueuePresentKHR(p->ctx->queue, &present);
    if (r == VK_ERROR_OUT_OF_DATE_KHR || r == VK_SUBOPTIMAL_KHR) /* a resize: the next frame makes it again */
        p->out_of_date = 1, r = VK_SUCCESS;
    return vk_check(r, "presenting", diag);
}

/* ---- Entry points --------------------------------------------------------------------------------- */

int tpk_vk_presenter_frame(tpk_vk_presenter *p, const tpk_render_options *opt, int width, int height,
                           tpk_render_stats *stats, tpk_diag *diag)
{
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (width < 1 || height < 1) /* minimized */
        return 0;
    if ((p->out_of_date || width != p->asked_width || height != p->asked_height) &&
        make_swapchain(p, width, height, diag) != 0)
        return -1;
    if (need_frame(p, opt->width, opt->height, diag) != 0 || prepare_frame(p, diag) != 0)
        return -1;
    tpk_vk_band_target target = {record_band_copy, p};
    if (tpk_vk_renderer_frame_to(p->renderer, opt, &target, stats, diag) != 0)
        return -1;
    p->shown_width = opt->width, p->shown_height = opt->height;
    return show(p, width, height, diag);
}

int tpk_vk_presenter_read(tpk_vk_presenter *p, uint8_t *rgba, int width, int height, tpk_diag *diag)
{
    if (width > p->shown_width || height > p->shown_height)
        return tpk_diag_fail(diag, "vulkan: %dx%d asked of a %dx%d frame", width, height, p->shown_width,
                             p->shown_height);
    tpk_vk_buffer host;
    size_t row = (size_t)width * 4;
    if (tpk_vk_buffer_create(p->ctx, (VkDeviceSize)row * (VkDeviceSize)height, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                             TPK_VK_MEMORY_READBACK, "the screenshot", &host, diag) != 0)
        return -1;
    int rc = host.mapped ? begin(p, diag) : tpk_diag_fail(diag, "vulkan: no host-visible memory for the screenshot");
    if (rc == 0) { /* the frame image stays in TRANSFER_SRC_OPTIMAL after show() until the next frame */
        VkBufferImageCopy region = {
            .imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
            .imageExtent = {(uint32_t)width, (uint32_t)height, 1},
        };
        vkCmdCopyImageToBuffer(p->cmd, p->frame, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, host.buffer, 1, &region);
        VkMemoryBarrier b = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER,
                             .srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT,
                             .dstAccessMask = VK_ACCESS_HOST_READ_BIT};
        vkCmdPipelineBarrier(p->cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &b, 0, NULL, 0,
                             NULL);
        rc = submit(p, VK_NULL_HANDLE, VK_NULL_HANDLE, diag);
    }
    if (rc == 0 && (rc = tpk_vk_buffer_invalidate(p->ctx, &host, diag)) == 0) {
        memcpy(rgba, host.mapped, row * (size_t)height);
        for (size_t i = 3; i < row * (size_t)height; i += 4)
            rgba[i] = 255; /* the window has no alpha to show */
    }
    tpk_vk_buffer_destroy(p->ctx, &host);
    return rc;
}

int tpk_vk_presenter_create(tpk_vk_presenter **out, tpk_vk_renderer *renderer, int width, int height,
                            tpk_diag *diag)
{
    *out = NULL;
    const tpk_vk_context *ctx = tpk_vk_renderer_context(renderer);
    if (!ctx->surface)
        return tpk_diag_fail(diag, "vulkan: the renderer was made without a window's surface");
    tpk_vk_presenter *p = calloc(1, sizeof *p);
    if (!p)
        return tpk_diag_fail(diag, "out of memory");
    p->renderer = renderer;
    p->ctx = ctx;
    VkFormatProperties rgba;
    vkGetPhysicalDeviceFormatProperties(ctx->physical, VK_FORMAT_R8G8B8A8_UNORM, &rgba);
    VkCommandPoolCreateInfo pool = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO,
        .flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT,
        .queueFamilyIndex = ctx->queue_family,
    };
    VkFenceCreateInfo fence = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkSemaphoreCreateInfo semaphore = {.sType = VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    int rc = !(rgba.optimalTilingFeatures & VK_FORMAT_FEATURE_BLIT_SRC_BIT)
                 ? tpk_diag_fail(diag, "vulkan: R8G8B8A8_UNORM images cannot be blitted from on this device")
                 : pick_format(p, diag);
    if (rc == 0)
        rc = vk_check(vkCreateCommandPool(ctx->device, &pool, NULL, &p->pool), "creating a command pool", diag);
    if (rc == 0) {
        VkCommandBufferAllocateInfo alloc = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
                                             .commandPool = p->pool,
                                             .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
                                             .commandBufferCount = 1};
        rc = vk_check(vkAllocateCommandBuffers(ctx->device, &alloc, &p->cmd), "allocating a command buffer", diag);
    }
    if (rc == 0)
        rc = vk_check(vkCreateFence(ctx->device, &fence, NULL, &p->fence), "creating a fence", diag);
    if (rc == 0)
        rc = vk_check(vkCreateSemaphore(ctx->device, &semaphore, NULL, &p->acquired), "creating a semaphore", diag);
    if (rc == 0) {
        pick_mode(p);
        rc = make_swapchain(p, width, height, diag);
    }
    if (rc != 0) {
        tpk_vk_presenter_destroy(p);
        return -1;
    }
    snprintf(p->description, sizeof p->description, "%s, %s",
             p->format.format == VK_FORMAT_B8G8R8A8_UNORM ? "B8G8R8A8_UNORM" : "R8G8B8A8_UNORM",
             p->mode == VK_PRESENT_MODE_IMMEDIATE_KHR ? "immediate"
             : p->mode == VK_PRESENT_MODE_MAILBOX_KHR ? "mailbox"
                                                      : "fifo");
    *out = p;
    return 0;
}

const char *tpk_vk_presenter_describe(const tpk_vk_presenter *p)
{
    return p->description;
}

void tpk_vk_presenter_destroy(tpk_vk_presenter *p)
{
    if (!p)
        return;
    VkDevice device = p->ctx->device;
    vkDeviceWaitIdle(device);
    destroy_frame(p);
    destroy_semaphores(p);
    if (p->swapchain)
        vkDestroySwapchainKHR(device, p->swapchain, NULL);
    if (p->acquired)
        vkDestroySemaphore(device, p->acquired, NULL);
    if (p->fence)
        vkDestroyFence(device, p->fence, NULL);
    if (p->pool)
        vkDestroyCommandPool(device, p->pool, NULL);
    free(p);
}
