/* The file's arrays as texel buffers, split over several bindings when one binding (texel count) or
 * one allocation cannot hold them; and the checks that the shader's record layout is the format's. */
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render_vk_internal.h"
#include "tetpack.h"

/* shaders/vk_layout.h restates the records of format/tetpack_format.h in words; these keep them equal. */
#define WORD(type, field) (offsetof(type, field) / 4)
_Static_assert(sizeof(tpk_tet16) == 4 * TPK_VK_TET16_WORDS && WORD(tpk_tet16, vx) == TPK_VK_TET16_VX &&
                   WORD(tpk_tet16, nx) == TPK_VK_TET16_VX + 1,
               "Tet16 record as vk_layout.h says");
_Static_assert(sizeof(tpk_tet20) == 4 * TPK_VK_TET20_WORDS && WORD(tpk_tet20, vx) == TPK_VK_TET20_VX &&
                   WORD(tpk_tet20, n) == TPK_VK_TET20_VX + 1,
               "Tet20 record as vk_layout.h says");
_Static_assert(sizeof(tpk_tet32) == 4 * TPK_VK_TET32_WORDS && WORD(tpk_tet32, v) == TPK_VK_TET32_V &&
                   WORD(tpk_tet32, vx) == TPK_VK_TET32_VX && WORD(tpk_tet32, n) == TPK_VK_TET32_N,
               "Tet32 record as vk_layout.h says");
_Static_assert(sizeof(tpk_shell_face) == 4 * TPK_VK_SHELL_WORDS && WORD(tpk_shell_face, t) == 3,
               "shell record as vk_layout.h says");
_Static_assert(sizeof(tpk_shell_bvh_node) == 4 * TPK_VK_NODE_WORDS && WORD(tpk_shell_bvh_node, first) == 6,
               "BVH node as vk_layout.h says");
_Static_assert(TPK_VK_LAYOUT_TET32 == TPK_LAYOUT_TET32 && TPK_VK_LAYOUT_TET20 == TPK_LAYOUT_TET20 &&
                   TPK_VK_LAYOUT_TET16 == TPK_LAYOUT_TET16,
               "layout ids as tetpack.h says");

_Static_assert(TPK_VK_RANGE_LEAF == TPK_RANGE_BVH_LEAF, "range BVH leaf as tetpack.h says");

int tpk_vk_tet_faces_match(void)
{
    static const int flat[12] = {TPK_VK_TET_FACES};
    for (int k = 0; k < 4; k++)
        for (int i = 0; i < 3; i++)
            if (flat[3 * k + i] != tpk_tet_faces[k][i])
                return 0;
    return 1;
}

static uint64_t floor_pow2(uint64_t x)
{
    uint64_t p = 1;
    while (p <= x / 2)
        p *= 2;
    return p;
}

uint64_t tpk_vk_part_texels(const tpk_vk_context *ctx, uint32_t texel_size)
{
    uint64_t limit = ctx->props.limits.maxTexelBufferElements;
    uint64_t by_allocation = ctx->max_allocation / texel_size;
    if (by_allocation < limit)
        limit = by_allocation;
    const char *env = getenv("TPK_VK_SPLIT_BYTES");
    if (env && *env) {
        uint64_t forced = strtoull(env, NULL, 10) / texel_size;
        if (forced < limit)
            limit = forced < 1 ? 1 : forced;
    }
    limit = floor_pow2(limit < 1 ? 1 : limit);
    /* The shader indexes texels with 32-bit unsigned ints: a part never holds more than 2^31. */
    return limit > ((uint64_t)1 << 31) ? (uint64_t)1 << 31 : limit;
}

static int log2u(uint64_t p)
{
    int s = 0;
    while (((uint64_t)1 << s) < p)
        s++;
    return s;
}

/* One part's texels: written in place on unified memory, else copied through the stager. */
static int fill_part(const tpk_vk_context *ctx, tpk_vk_stager *stager, const tpk_vk_source *src, uint64_t first,
                     uint64_t count, tpk_vk_buffer *part, tpk_diag *diag)
{
    if (!ctx->staged && part->mapped) {
        tpk_vk_source_fill(src, part->mapped, first, count);
        return tpk_vk_buffer_flush(ctx, part, diag);
    }
    if (!stager)
        return tpk_diag_fail(diag, "vulkan: device memory that is not host-visible and no staging buffer");
    return tpk_vk_stager_copy(ctx, stager, src, first, count, part->buffer, diag);
}

int tpk_vk_array_refill(const tpk_vk_context *ctx, tpk_vk_stager *stager, const tpk_vk_source *src,
                        uint64_t texel_count, tpk_vk_array *a, tpk_diag *diag)
{
    const uint64_t per_part = (uint64_t)1 << a->shift;
    for (int k = 0; k < a->part_count; k++) {
        uint64_t first = (uint64_t)k * per_part;
        if (first >= texel_count)
            break;
        uint64_t count = texel_count - first < per_part ? texel_count - first : per_part;
        if (fill_part(ctx, stager, src, first, count, &a->parts[k], diag) != 0)
            return -1;
    }
    return 0;
}

int tpk_vk_array_upload(const tpk_vk_context *ctx, tpk_vk_stager *stager, const char *what, VkFormat format,
                        const tpk_vk_source *src, uint64_t texel_count, tpk_vk_array *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    const uint32_t texel_size = src->texel_size;
    const tpk_vk_source zero = {.texel_size = texel_size};
    const uint64_t per_part = tpk_vk_part_texels(ctx, texel_size);
    out->shift = log2u(per_part);
    const uint64_t stored = texel_count > 0 ? texel_count : 1;
    const uint64_t parts = (stored + per_part - 1) / per_part;
    if (parts > TPK_VK_MAX_PARTS || stored > ((uint64_t)1 << 32))
        return tpk_diag_fail(diag, "vulkan: %s: %llu texels of %u bytes need %llu bindings of at most %llu texels; "
                             "this device allows %d per array (the file is larger than the device's limits)",
                             what, (unsigned long long)stored, texel_size, (unsigned long long)parts,
                             (unsigned long long)per_part, TPK_VK_MAX_PARTS);
    for (uint64_t k = 0; k < parts; k++) {
        uint64_t first = k * per_part, count = stored - first < per_part ? stored - first : per_part;
        char name[160];
        snprintf(name, sizeof name, "%s (part %llu of %llu)", what, (unsigned long long)k + 1,
                 (unsigned long long)parts);
        if (tpk_vk_buffer_create(ctx, count * texel_size,
                                 VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                 TPK_VK_MEMORY_DEVICE, name, &out->parts[k], diag) != 0) {
            tpk_vk_array_destroy(ctx, out);
            return -1;
        }
        out->part_count = (int)k + 1;
        if (fill_part(ctx, stager, texel_count > 0 ? src : &zero, first, count, &out->parts[k], diag) != 0) {
            tpk_vk_array_destroy(ctx, out);
            return -1;
        }
        VkBufferViewCreateInfo view = {
            .sType = VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO,
            .buffer = out->parts[k].buffer,
            .format = format,
            .offset = 0,
            .range = VK_WHOLE_SIZE,
        };
        VkResult r = vkCreateBufferView(ctx->device, &view, NULL, &out->views[k]);
        if (r != VK_SUCCESS) {
            out->views[k] = VK_NULL_HANDLE;
            tpk_vk_array_destroy(ctx, out);
            return tpk_diag_fail(diag, "vulkan: a texel view of %s failed: %s", name, tpk_vk_result_name(r));
        }
    }
    return 0;
}

void tpk_vk_array_destroy(const tpk_vk_context *ctx, tpk_vk_array *a)
{
    for (int k = 0; k < TPK_VK_MAX_PARTS; k++) {
        if (a->views[k])
            vkDestroyBufferView(ctx->device, a->views[k], NULL);
        tpk_vk_buffer_destroy(ctx, &a->parts[k]);
    }
    memset(a, 0, sizeof *a);
}
