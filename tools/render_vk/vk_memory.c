/* Which memory type each buffer of the renderer goes in: a pure function of the device's memory
 * properties (no Vulkan call), so that it is tested against the tables of real devices
 * (tests/test_render_vk_memory.c). The rules are those of GPU renderers and VMA's usages:
 *   - what shaders read (mesh arrays, BVH, image) lives in DEVICE_LOCAL memory, on a discrete GPU the
 *     type that is not host-visible: a host-visible device-local type there is the PCIe BAR, 256 MiB
 *     without resizable BAR, and uncached for the CPU either way;
 *   - staging is host-visible, coherent, write-combined (not cached), in system memory;
 *   - readback is host-visible and HOST_CACHED: reading uncached memory costs a bus transaction a word;
 *   - on unified memory (CPU devices, integrated GPUs) device-local memory is host-visible and the CPU
 *     writes and reads it directly: a staging copy there would only add a pass over the data.
 * AMD's DEVICE_COHERENT / DEVICE_UNCACHED types are for debugging markers and come last; protected and
 * lazily allocated memory is never taken. */
#include "vk_memory.h"

#define AMD_FLAGS (VK_MEMORY_PROPERTY_DEVICE_COHERENT_BIT_AMD | VK_MEMORY_PROPERTY_DEVICE_UNCACHED_BIT_AMD)

int tpk_vk_memory_unified(const VkPhysicalDeviceMemoryProperties *m, VkPhysicalDeviceType type)
{
    if (type == VK_PHYSICAL_DEVICE_TYPE_CPU || type == VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU)
        return 1;
    for (uint32_t h = 0; h < m->memoryHeapCount; h++)
        if (!(m->memoryHeaps[h].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT))
            return 0;
    return m->memoryHeapCount > 0;
}

/* Preferences in decreasing weight; a type's score is the bits of those it meets, -1 when it cannot
 * serve `use` at all. */
static int score(VkMemoryPropertyFlags f, int unified, tpk_vk_memory_use use)
{
    const int dl = (f & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT) != 0, hv = (f & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT) != 0,
              hc = (f & VK_MEMORY_PROPERTY_HOST_COHERENT_BIT) != 0, cached = (f & VK_MEMORY_PROPERTY_HOST_CACHED_BIT) != 0,
              plain = !(f & AMD_FLAGS);
    if (f & (VK_MEMORY_PROPERTY_PROTECTED_BIT | VK_MEMORY_PROPERTY_LAZILY_ALLOCATED_BIT))
        return -1;
    switch (use) {
    case TPK_VK_MEMORY_DEVICE:
        if (unified) /* written and read in place by the CPU: host-visible, coherent, write-combined */
            return plain << 4 | dl << 3 | (hv && hc) << 2 | hv << 1 | !cached;
        return plain << 4 | dl << 3 | !hv << 2; /* system memory only when the device memory is full */
    case TPK_VK_MEMORY_UPLOAD:
        if (!hv)
            return -1;
        return plain << 4 | hc << 3 | (unified || !dl) << 2 | !cached << 1;
    case TPK_VK_MEMORY_READBACK:
        if (!hv)
            return -1;
        return plain << 4 | cached << 3 | hc << 2 | (unified || !dl) << 1;
    }
    return -1;
}

int tpk_vk_memory_rank(const VkPhysicalDeviceMemoryProperties *m, int unified, uint32_t type_bits,
                       tpk_vk_memory_use use, uint32_t order[VK_MAX_MEMORY_TYPES])
{
    int scores[VK_MAX_MEMORY_TYPES], n = 0;
    const uint32_t count = m->memoryTypeCount < VK_MAX_MEMORY_TYPES ? m->memoryTypeCount : VK_MAX_MEMORY_TYPES;
    for (uint32_t i = 0; i < count; i++) {
        if (!(type_bits & (1u << i)))
            continue;
        int s = score(m->memoryTypes[i].propertyFlags, unified, use);
        if (s < 0)
            continue;
        /* insertion sort, stable: among equal scores the driver's order (it lists faster types first) */
        int k = n++;
        while (k > 0 && scores[k - 1] < s) {
            scores[k] = scores[k - 1];
            order[k] = order[k - 1];
            k--;
        }
        scores[k] = s;
        order[k] = i;
    }
    return n;
}
