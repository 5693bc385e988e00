/* Uploads through a staging buffer of bounded size (TPK_VK_STAGING_BYTES, 64 MiB), in pieces: the
 * buffer is two slots, and the GPU copies one slot into the device buffer while the CPU fills the
 * other, so a mesh of any size needs 64 MiB of staging and no host copy of itself. On unified memory
 * (tpk_vk_context.staged == 0) the arrays are written in place and no stager is made. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render_vk_internal.h"

static int vk_check(VkResult r, const char *step, tpk_diag *diag)
{
    if (r == VK_SUCCESS)
        return 0;
    return tpk_diag_fail(diag, "vulkan: %s failed: %s", step, tpk_vk_result_name(r));
}

int tpk_vk_stager_create(const tpk_vk_context *ctx, uint64_t largest, tpk_vk_stager *s, tpk_diag *diag)
{
    memset(s, 0, sizeof *s);
    uint64_t budget = TPK_VK_STAGING_BYTES;
    const char *env = getenv("TPK_VK_STAGING_BYTES"); /* tests: many small pieces */
    if (env && *env && strtoull(env, NULL, 10) >= 2 * 64)
        budget = strtoull(env, NULL, 10);
    /* a slot holds whole texels of every size (4, 16 and 32 bytes) */
    uint64_t slot = (budget / 2) & ~(uint64_t)63;
    uint64_t need = (largest + 63) & ~(uint64_t)63;
    s->slot_bytes = need < slot ? (need ? need : 64) : slot;
    VkCommandPoolCreateInfo pool = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO,
        .flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT | VK_COMMAND_POOL_CREATE_TRANSIENT_BIT,
        .queueFamilyIndex = ctx->queue_family,
    };
    if (vk_check(vkCreateCommandPool(ctx->device, &pool, NULL, &s->pool), "creating the upload command pool", diag))
        goto fail;
    VkCommandBufferAllocateInfo alloc = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
        .commandPool = s->pool,
        .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
        .commandBufferCount = 2,
    };
    if (vk_check(vkAllocateCommandBuffers(ctx->device, &alloc, s->cmd), "allocating upload commands", diag))
        goto fail;
    for (int k = 0; k < 2; k++) {
        VkFenceCreateInfo fence = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO,
                                   .flags = VK_FENCE_CREATE_SIGNALED_BIT};
        if (vk_check(vkCreateFence(ctx->device, &fence, NULL, &s->fence[k]), "creating an upload fence", diag) ||
            tpk_vk_buffer_create(ctx, s->slot_bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, TPK_VK_MEMORY_UPLOAD,
                                 "the staging buffer", &s->slots[k], diag) != 0)
            goto fail;
        if (!s->slots[k].mapped) {
            tpk_diag_fail(diag, "vulkan: the staging buffer is not host-visible");
            goto fail;
        }
    }
    return 0;
fail:
    tpk_vk_stager_destroy(ctx, s);
    return -1;
}

/* Wait until slot k is free again (its copy done). */
static int wait_slot(const tpk_vk_context *ctx, tpk_vk_stager *s, int k, tpk_diag *diag)
{
    return vk_check(vkWaitForFences(ctx->device, 1, &s->fence[k], VK_TRUE, UINT64_MAX), "waiting for an upload", diag);
}

int tpk_vk_stager_copy(const tpk_vk_context *ctx, tpk_vk_stager *s, const tpk_vk_source *src, uint64_t first,
                       uint64_t count, VkBuffer dst, tpk_diag *diag)
{
    const uint64_t per_piece = s->slot_bytes / src->texel_size;
    for (uint64_t done = 0; done < count;) {
        uint64_t n = count - done < per_piece ? count - done : per_piece;
        int k = s->next;
        s->next ^= 1;
        if (wait_slot(ctx, s, k, diag) != 0)
            return -1;
        tpk_vk_source_fill(src, s->slots[k].mapped, first + done, n);
        if (tpk_vk_buffer_flush(ctx, &s->slots[k], diag) != 0)
            return -1;
        VkCommandBufferBeginInfo begin = {
            .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
            .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT,
        };
        VkBufferCopy region = {0, done * src->texel_size, n * src->texel_size};
        if (vk_check(vkResetCommandBuffer(s->cmd[k], 0), "resetting upload commands", diag) ||
            vk_check(vkBeginCommandBuffer(s->cmd[k], &begin), "recording upload commands", diag))
            return -1;
        vkCmdCopyBuffer(s->cmd[k], s->slots[k].buffer, dst, 1, &region);
        VkSubmitInfo submit = {
            .sType = VK_STRUCTURE_TYPE_SUBMIT_INFO, .commandBufferCount = 1, .pCommandBuffers = &s->cmd[k]};
        if (vk_check(vkEndCommandBuffer(s->cmd[k]), "recording upload commands", diag) ||
            vk_check(vkResetFences(ctx->device, 1, &s->fence[k]), "resetting an upload fence", diag) ||
            vk_check(vkQueueSubmit(ctx->queue, 1, &submit, s->fence[k]), "submitting an upload", diag))
            return -1;
        s->bytes += n * src->texel_size;
        s->pieces++;
        done += n;
    }
    return 0;
}

int tpk_vk_stager_finish(const tpk_vk_context *ctx, tpk_vk_stager *s, tpk_diag *diag)
{
    /* the queue runs the copies in order and the render's own submission waits for none of them: a
     * barrier in the frame's commands would, but waiting here keeps the renderer's frames simple */
    return wait_slot(ctx, s, 0, diag) != 0 || wait_slot(ctx, s, 1, diag) != 0 ? -1 : 0;
}

void tpk_vk_stager_destroy(const tpk_vk_context *ctx, tpk_vk_stager *s)
{
    if (!ctx->device)
        return;
    for (int k = 0; k < 2; k++) {
        if (s->fence[k]) {
            vkWaitForFences(ctx->device, 1, &s->fence[k], VK_TRUE, UINT64_MAX);
            vkDestroyFence(ctx->device, s->fence[k], NULL);
        }
        tpk_vk_buffer_destroy(ctx, &s->slots[k]);
    }
    if (s->pool)
        vkDestroyCommandPool(ctx->device, s->pool, NULL);
    memset(s, 0, sizeof *s);
}

void tpk_vk_source_fill(const tpk_vk_source *src, void *dst, uint64_t first, uint64_t count)
{
    if (src->fill)
        src->fill(dst, first, count, src->user);
    else if (src->data)
        memcpy(dst, (const char *)src->data + first * src->texel_size, count * src->texel_size);
    else
        memset(dst, 0, count * src->texel_size);
}
