/* The memory-type choice of the Vulkan renderer: a pure function of a device's memory properties (no
 * Vulkan call, so the tables of real devices test it without those devices: test_render_vk_memory.c). */
#ifndef TPK_VK_MEMORY_H
#define TPK_VK_MEMORY_H

#include <stdint.h>
#include <vulkan/vulkan.h>

/* What a buffer is for. */
typedef enum tpk_vk_memory_use {
    TPK_VK_MEMORY_DEVICE,   /* read and written by shaders: mesh arrays, BVH, image, counters */
    TPK_VK_MEMORY_UPLOAD,   /* written by the CPU, copied to the device: the staging buffer */
    TPK_VK_MEMORY_READBACK, /* written by the device, read by the CPU: image and counters copied out */
} tpk_vk_memory_use;

/* 1 when the device's memory is the host's (CPU devices such as lavapipe, integrated GPUs, or every
 * heap device-local): device-local memory is then host-visible, and the CPU writes the arrays and
 * reads the image in place, with no staging copy; 0 for a discrete GPU. */
int tpk_vk_memory_unified(const VkPhysicalDeviceMemoryProperties *m, VkPhysicalDeviceType type);

/* The memory types among `type_bits` (VkMemoryRequirements.memoryTypeBits) that can serve `use`, best
 * first, into order; returns how many (0: none can). Allocation tries them in that order, so a full
 * heap falls back to the next. Device: DEVICE_LOCAL, on a discrete GPU not host-visible (the BAR
 * heap is small without resizable BAR), system memory last; on unified memory host-visible, coherent,
 * not cached. Upload: host-visible, coherent, not device-local on a discrete GPU, not cached.
 * Readback: host-visible and HOST_CACHED, then coherent. AMD's device-coherent types come after all
 * others; protected and lazily allocated types never. Among equals, the driver's order. */
int tpk_vk_memory_rank(const VkPhysicalDeviceMemoryProperties *m, int unified, uint32_t type_bits,
                       tpk_vk_memory_use use, uint32_t order[VK_MAX_MEMORY_TYPES]);

#endif
