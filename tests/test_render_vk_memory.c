/* The Vulkan renderer's memory-type choice (tools/render_vk/vk_memory.h) against the memory tables of
 * real devices, written from their published vulkaninfo reports (gpuinfo.org, and issue 19 for the
 * H200). No device is needed: the choice is a pure function. For each device: where the mesh arrays and
 * the image go, where the staging and readback buffers go, and whether the device counts as unified
 * memory (arrays written and the image read in place). */
#include <string.h>

#include "harness.h"
#include "render_vk/vk_memory.h"

#define DL VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT
#define HV VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT
#define HC VK_MEMORY_PROPERTY_HOST_COHERENT_BIT
#define CACHED VK_MEMORY_PROPERTY_HOST_CACHED_BIT
#define AMD (VK_MEMORY_PROPERTY_DEVICE_COHERENT_BIT_AMD | VK_MEMORY_PROPERTY_DEVICE_UNCACHED_BIT_AMD)
#define GIB(x) ((VkDeviceSize)((x) * 1073741824.0))

typedef struct profile {
    const char *name;
    VkPhysicalDeviceType type;
    uint32_t heap_count;
    struct {
        VkDeviceSize size;
        VkMemoryHeapFlags flags;
    } heaps[4];
    uint32_t type_count;
    struct {
        VkMemoryPropertyFlags flags;
        uint32_t heap;
    } types[10];
    int unified;                       /* expected */
    int device, upload, readback;      /* expected first choices */
} profile;

static const profile PROFILES[] = {
    /* NVIDIA H200, driver 580 (issue 19): resizable BAR, the whole 140 GiB host-visible */
    {"nvidia h200 (resizable BAR)", VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU, 2,
     {{GIB(140), VK_MEMORY_HEAP_DEVICE_LOCAL_BIT}, {GIB(94), 0}},
     5, {{0, 1}, {DL, 0}, {HV | HC, 1}, {HV | HC | CACHED, 1}, {DL | HV | HC, 0}},
     0, 1, 2, 3},
    /* NVIDIA GeForce RTX 3080, driver 535, Linux, no resizable BAR: a 246 MiB BAR heap */
    {"nvidia rtx 3080 (no resizable BAR)", VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU, 3,
     {{GIB(10), VK_MEMORY_HEAP_DEVICE_LOCAL_BIT}, {GIB(31.3), 0}, {246u << 20, VK_MEMORY_HEAP_DEVICE_LOCAL_BIT}},
     6, {{0, 1}, {DL, 0}, {DL, 0}, {HV | HC, 1}, {HV | HC | CACHED, 1}, {DL | HV | HC, 2}},
     0, 1, 3, 4},
    /* AMD Radeon RX 6800 XT, RADV (Mesa 22), no Smart Access Memory: AMD's device-coherent types too */
    {"amd rx 6800 xt (radv)", VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU, 3,
     {{GIB(15.7), VK_MEMORY_HEAP_DEVICE_LOCAL_BIT}, {GIB(15.6), 0}, {256u << 20, VK_MEMORY_HEAP_DEVICE_LOCAL_BIT}},
     8,
     {{DL, 0}, {HV | HC, 1}, {DL | HV | HC, 2}, {HV | HC | CACHED, 1}, {DL | AMD, 0}, {HV | HC | AMD, 1},
      {DL | HV | HC | AMD, 2}, {HV | HC | CACHED | AMD, 1}},
     0, 0, 1, 3},
    /* Intel Iris Xe (TGL), ANV: one device-local heap, which is system memory */
    {"intel iris xe (anv)", VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU, 1,
     {{GIB(11.6), VK_MEMORY_HEAP_DEVICE_LOCAL_BIT}},
     3, {{DL, 0}, {DL | HV | HC, 0}, {DL | HV | HC | CACHED, 0}},
     1, 1, 1, 2},
    /* llvmpipe (lavapipe), Mesa 22.3: one type with every host flag */
    {"lavapipe", VK_PHYSICAL_DEVICE_TYPE_CPU, 1,
     {{GIB(2), VK_MEMORY_HEAP_DEVICE_LOCAL_BIT}},
     1, {{DL | HV | HC | CACHED, 0}},
     1, 0, 0, 0},
    /* AMD Radeon 780M (APU), RADV: integrated, with a host heap (GTT) beside the carve-out */
    {"amd radeon 780m (radv apu)", VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU, 2,
     {{GIB(0.5), VK_MEMORY_HEAP_DEVICE_LOCAL_BIT}, {GIB(15), 0}},
     4, {{DL, 0}, {HV | HC, 1}, {DL | HV | HC, 0}, {HV | HC | CACHED, 1}},
     1, 2, 1, 3},
};
#define PROFILE_COUNT ((int)(sizeof PROFILES / sizeof PROFILES[0]))

static void props_of(const profile *p, VkPhysicalDeviceMemoryProperties *m)
{
    memset(m, 0, sizeof *m);
    m->memoryHeapCount = p->heap_count;
    for (uint32_t h = 0; h < p->heap_count; h++) {
        m->memoryHeaps[h].size = p->heaps[h].size;
        m->memoryHeaps[h].flags = p->heaps[h].flags;
    }
    m->memoryTypeCount = p->type_count;
    for (uint32_t t = 0; t < p->type_count; t++) {
        m->memoryTypes[t].propertyFlags = p->types[t].flags;
        m->memoryTypes[t].heapIndex = p->types[t].heap;
    }
}

static int first_choice(const VkPhysicalDeviceMemoryProperties *m, int unified, uint32_t bits, tpk_vk_memory_use use)
{
    uint32_t order[VK_MAX_MEMORY_TYPES];
    return tpk_vk_memory_rank(m, unified, bits, use, order) > 0 ? (int)order[0] : -1;
}

/* The first choice of every profile for every use. */
TPK_TEST(memory_type_profiles)
{
    for (int i = 0; i < PROFILE_COUNT; i++) {
        const profile *p = &PROFILES[i];
        VkPhysicalDeviceMemoryProperties m;
        props_of(p, &m);
        int unified = tpk_vk_memory_unified(&m, p->type);
        CHECK_MSG(unified == p->unified, "%s: unified %d", p->name, unified);
        int device = first_choice(&m, unified, ~0u, TPK_VK_MEMORY_DEVICE),
            upload = first_choice(&m, unified, ~0u, TPK_VK_MEMORY_UPLOAD),
            readback = first_choice(&m, unified, ~0u, TPK_VK_MEMORY_READBACK);
        printf("%-36s unified %d  device %d  upload %d  readback %d\n", p->name, unified, device, upload, readback);
        CHECK_MSG(device == p->device, "%s: device memory type %d, expected %d", p->name, device, p->device);
        CHECK_MSG(upload == p->upload, "%s: upload memory type %d, expected %d", p->name, upload, p->upload);
        CHECK_MSG(readback == p->readback, "%s: readback memory type %d, expected %d", p->name, readback,
                  p->readback);
    }
}

/* Every ranked type meets the use's needs; the device list keeps device-local types ahead of system
 * memory (among plain types), so that a mesh never lands in system memory while device memory is left;
 * AMD's device-coherent types come after every plain one. */
TPK_TEST(memory_type_fallbacks)
{
    for (int i = 0; i < PROFILE_COUNT; i++) {
        const profile *p = &PROFILES[i];
        VkPhysicalDeviceMemoryProperties m;
        props_of(p, &m);
        int unified = tpk_vk_memory_unified(&m, p->type);
        for (int use = TPK_VK_MEMORY_DEVICE; use <= TPK_VK_MEMORY_READBACK; use++) {
            uint32_t order[VK_MAX_MEMORY_TYPES];
            int n = tpk_vk_memory_rank(&m, unified, ~0u, (tpk_vk_memory_use)use, order);
            CHECK_MSG(n > 0, "%s: no type for use %d", p->name, use);
            int seen_host = 0;
            for (int k = 0; k < n; k++) {
                VkMemoryPropertyFlags f = m.memoryTypes[order[k]].propertyFlags;
                if (use != TPK_VK_MEMORY_DEVICE)
                    CHECK_MSG(f & HV, "%s: use %d ranks type %u, not host-visible", p->name, use, order[k]);
                else if (f & AMD)
                    continue;
                else if (!(f & DL))
                    seen_host = 1;
                else
                    CHECK_MSG(!seen_host, "%s: device-local type %u after system memory", p->name, order[k]);
            }
            for (int k = 1; k < n; k++) /* AMD's device-coherent types last */
                CHECK_MSG(!(m.memoryTypes[order[k - 1]].propertyFlags & AMD) ||
                              (m.memoryTypes[order[k]].propertyFlags & AMD),
                          "%s: a plain type after an AMD device-coherent one", p->name);
        }
    }
}

/* memoryTypeBits restricts the choice: without the NVIDIA VRAM type the mesh goes in the BAR, then
 * in system memory; a buffer that allows no host-visible type has no staging or readback type. */
TPK_TEST(memory_type_bits)
{
    VkPhysicalDeviceMemoryProperties m;
    props_of(&PROFILES[1], &m); /* RTX 3080 */
    CHECK_EQ_INT(first_choice(&m, 0, ~0u & ~(1u << 1) & ~(1u << 2), TPK_VK_MEMORY_DEVICE), 5);
    CHECK_EQ_INT(first_choice(&m, 0, (1u << 0) | (1u << 3), TPK_VK_MEMORY_DEVICE), 0);
    CHECK_EQ_INT(first_choice(&m, 0, (1u << 1) | (1u << 2), TPK_VK_MEMORY_UPLOAD), -1);
    CHECK_EQ_INT(first_choice(&m, 0, (1u << 1) | (1u << 2), TPK_VK_MEMORY_READBACK), -1);
    CHECK_EQ_INT(first_choice(&m, 0, 0, TPK_VK_MEMORY_DEVICE), -1);
    /* protected and lazily allocated memory is never taken */
    m.memoryTypes[1].propertyFlags |= VK_MEMORY_PROPERTY_PROTECTED_BIT;
    m.memoryTypes[2].propertyFlags |= VK_MEMORY_PROPERTY_LAZILY_ALLOCATED_BIT;
    CHECK_EQ_INT(first_choice(&m, 0, ~0u, TPK_VK_MEMORY_DEVICE), 5);
    /* a readback without a cached type takes a coherent one */
    props_of(&PROFILES[0], &m); /* H200 */
    CHECK_EQ_INT(first_choice(&m, 0, ~0u & ~(1u << 3), TPK_VK_MEMORY_READBACK), 2);
}

/* A device that says discrete but has only device-local heaps (no system heap) is unified memory. */
TPK_TEST(memory_type_unified_heaps)
{
    VkPhysicalDeviceMemoryProperties m;
    props_of(&PROFILES[4], &m); /* lavapipe's table */
    CHECK_EQ_INT(tpk_vk_memory_unified(&m, VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU), 1);
    props_of(&PROFILES[0], &m);
    CHECK_EQ_INT(tpk_vk_memory_unified(&m, VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU), 0);
    CHECK_EQ_INT(tpk_vk_memory_unified(&m, VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU), 0);
}
