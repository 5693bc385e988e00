/* The Vulkan instance, device and compute queue of the renderer (with the window's surface and a queue
 * that can present to it, for tetpack view), and its buffers. Every
 * failure becomes a message naming the step and the VkResult: the caller exits cleanly. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render_vk_internal.h"

const char *tpk_vk_result_name(VkResult r)
{
    switch (r) {
    case VK_SUCCESS: return "VK_SUCCESS";
    case VK_NOT_READY: return "VK_NOT_READY";
    case VK_TIMEOUT: return "VK_TIMEOUT";
    case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY (out of host memory)";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY (out of device memory)";
    case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST: return "VK_ERROR_DEVICE_LOST (the device stopped, e.g. a GPU time-out)";
    case VK_ERROR_LAYER_NOT_PRESENT: return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT: return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_INCOMPATIBLE_DRIVER: return "VK_ERROR_INCOMPATIBLE_DRIVER (no usable Vulkan driver)";
    case VK_ERROR_TOO_MANY_OBJECTS: return "VK_ERROR_TOO_MANY_OBJECTS";
    case VK_ERROR_OUT_OF_POOL_MEMORY: return "VK_ERROR_OUT_OF_POOL_MEMORY";
    case VK_ERROR_SURFACE_LOST_KHR: return "VK_ERROR_SURFACE_LOST_KHR";
    case VK_ERROR_NATIVE_WINDOW_IN_USE_KHR: return "VK_ERROR_NATIVE_WINDOW_IN_USE_KHR";
    case VK_ERROR_OUT_OF_DATE_KHR: return "VK_ERROR_OUT_OF_DATE_KHR";
    default: return "a Vulkan error";
    }
}

static int vk_fail(tpk_diag *diag, const char *step, VkResult r)
{
    return tpk_diag_fail(diag, "vulkan: %s failed: %s (%d)", step, tpk_vk_result_name(r), (int)r);
}

static int create_instance(tpk_vk_context *ctx, const tpk_vk_surface_source *surface, tpk_diag *diag)
{
    VkApplicationInfo app = {
        .sType = VK_STRUCTURE_TYPE_APPLICATION_INFO,
        .pApplicationName = "tetpack",
        .pEngineName = "tetpack",
        .apiVersion = VK_API_VERSION_1_2,
    };
    VkInstanceCreateInfo info = {
        .sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO,
        .pApplicationInfo = &app,
        .enabledExtensionCount = surface ? surface->instance_extension_count : 0,
        .ppEnabledExtensionNames = surface ? surface->instance_extensions : NULL,
    };
    VkResult r = vkCreateInstance(&info, NULL, &ctx->instance);
    if (r != VK_SUCCESS) {
        ctx->instance = VK_NULL_HANDLE;
        return vk_fail(diag, "creating the instance (is a Vulkan driver installed? VK_ICD_FILENAMES?)", r);
    }
    return 0;
}

/* The first queue family with compute (that can also present to `surface`, when one is given;
 * TPK_VK_NO_PRESENT=1: none can, so that tests reach the viewer's fallback). */
static int compute_family(VkPhysicalDevice dev, VkSurfaceKHR surface, uint32_t *family, uint32_t *timestamp_bits)
{
    const char *no_present = getenv("TPK_VK_NO_PRESENT");
    uint32_t n = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(dev, &n, NULL);
    VkQueueFamilyProperties props[64];
    n = n > 64 ? 64 : n;
    vkGetPhysicalDeviceQueueFamilyProperties(dev, &n, props);
    for (uint32_t i = 0; i < n; i++) {
        VkBool32 present = VK_TRUE;
        if (surface && ((no_present && !strcmp(no_present, "1")) ||
                        vkGetPhysicalDeviceSurfaceSupportKHR(dev, i, surface, &present) != VK_SUCCESS))
            present = VK_FALSE;
        if ((props[i].queueFlags & VK_QUEUE_COMPUTE_BIT) && present) {
            *family = i;
            *timestamp_bits = props[i].timestampValidBits;
            return 0;
        }
    }
    return -1;
}

static int type_rank(VkPhysicalDeviceType t)
{
    return t == VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU     ? 0
           : t == VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU ? 1
           : t == VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU    ? 2
                                                         : 3;
}

/* TPK_VK_DEVICE=N, else the best-ranked Vulkan 1.2 device with a compute queue (that can present to
 * ctx->surface when there is one). */
static int pick_device(tpk_vk_context *ctx, tpk_diag *diag)
{
    uint32_t n = 0;
    VkResult r = vkEnumeratePhysicalDevices(ctx->instance, &n, NULL);
    if (r != VK_SUCCESS)
        return vk_fail(diag, "listing the devices", r);
    if (n == 0)
        return tpk_diag_fail(diag, "vulkan: no Vulkan device (the loader found no driver with a device)");
    VkPhysicalDevice devs[16];
    n = n > 16 ? 16 : n;
    r = vkEnumeratePhysicalDevices(ctx->instance, &n, devs);
    if (r != VK_SUCCESS && r != VK_INCOMPLETE)
        return vk_fail(diag, "listing the devices", r);
    const char *env = getenv("TPK_VK_DEVICE");
    int wanted = env && *env ? atoi(env) : -1;
    if (wanted >= (int)n)
        return tpk_diag_fail(diag, "vulkan: TPK_VK_DEVICE=%d but there are %u devices", wanted, n);
    int best = -1, best_rank = 99;
    for (uint32_t i = 0; i < n; i++) {
        VkPhysicalDeviceProperties p;
        vkGetPhysicalDeviceProperties(devs[i], &p);
        uint32_t family, bits;
        if (p.apiVersion < VK_API_VERSION_1_2 || compute_family(devs[i], ctx->surface, &family, &bits) != 0)
            continue;
        if (wanted == (int)i || (wanted < 0 && type_rank(p.deviceType) < best_rank)) {
            best = (int)i;
            best_rank = type_rank(p.deviceType);
            ctx->queue_family = family;
            ctx->timestamp_bits = bits;
        }
    }
    if (best < 0)
        return tpk_diag_fail(diag, "vulkan: no Vulkan 1.2 device with a compute queue%s%s",
                             ctx->surface ? " that can present to the window" : "",
                             wanted >= 0 ? " at TPK_VK_DEVICE" : "");
    ctx->physical = devs[best];
    vkGetPhysicalDeviceProperties(ctx->physical, &ctx->props);
    vkGetPhysicalDeviceMemoryProperties(ctx->physical, &ctx->memory);
    VkPhysicalDeviceMaintenance3Properties m3 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES};
    VkPhysicalDeviceProperties2 p2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, .pNext = &m3};
    vkGetPhysicalDeviceProperties2(ctx->physical, &p2);
    ctx->max_allocation = m3.maxMemoryAllocationSize ? m3.maxMemoryAllocationSize : (VkDeviceSize)1 << 30;
    ctx->unified = tpk_vk_memory_unified(&ctx->memory, ctx->props.deviceType);
    const char *memory = getenv("TPK_VK_MEMORY"); /* "staged": the discrete path on any device, for tests */
    ctx->staged = !ctx->unified || (memory && !strcmp(memory, "staged"));
    return 0;
}

static int has_extension(VkPhysicalDevice dev, const char *name)
{
    uint32_t n = 0;
    if (vkEnumerateDeviceExtensionProperties(dev, NULL, &n, NULL) != VK_SUCCESS || n == 0)
        return 0;
    VkExtensionProperties *ext = malloc(n * sizeof *ext);
    int found = 0;
    if (ext && vkEnumerateDeviceExtensionProperties(dev, NULL, &n, ext) == VK_SUCCESS)
        for (uint32_t i = 0; i < n && !found; i++)
            found = !strcmp(ext[i].extensionName, name);
    free(ext);
    return found;
}

/* The window's surface on the new instance. */
static int create_surface(tpk_vk_context *ctx, const tpk_vk_surface_source *surface, tpk_diag *diag)
{
    VkResult r = surface->create(ctx->instance, surface->user, &ctx->surface);
    if (r != VK_SUCCESS) {
        ctx->surface = VK_NULL_HANDLE;
        return vk_fail(diag, "creating the window's surface", r);
    }
    return 0;
}

int tpk_vk_has_mesh_shader(VkPhysicalDevice physical)
{
    if (!has_extension(physical, VK_EXT_MESH_SHADER_EXTENSION_NAME))
        return 0;
    VkPhysicalDeviceMeshShaderFeaturesEXT mesh = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MESH_SHADER_FEATURES_EXT};
    VkPhysicalDeviceFeatures2 features = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, .pNext = &mesh};
    vkGetPhysicalDeviceFeatures2(physical, &features);
    return mesh.taskShader == VK_TRUE && mesh.meshShader == VK_TRUE;
}

static int create(tpk_vk_context *ctx, const tpk_vk_surface_source *surface, int want_mesh_shader, tpk_diag *diag);

int tpk_vk_context_create(tpk_vk_context *ctx, tpk_diag *diag)
{
    return create(ctx, NULL, 0, diag);
}

int tpk_vk_context_create_presenting(tpk_vk_context *ctx, const tpk_vk_surface_source *surface, tpk_diag *diag)
{
    return create(ctx, surface, 0, diag);
}

int tpk_vk_context_create_mesh(tpk_vk_context *ctx, tpk_diag *diag)
{
    const char *env = getenv("TETPACK_ISO_MESH_SHADER");
    return create(ctx, NULL, !(env && !strcmp(env, "0")), diag);
}

static int create(tpk_vk_context *ctx, const tpk_vk_surface_source *surface, int want_mesh_shader, tpk_diag *diag)
{
    memset(ctx, 0, sizeof *ctx);
    if (create_instance(ctx, surface, diag) != 0 || (surface && create_surface(ctx, surface, diag) != 0) ||
        pick_device(ctx, diag) != 0) {
        tpk_vk_context_destroy(ctx);
        return -1;
    }
    if (surface && !has_extension(ctx->physical, VK_KHR_SWAPCHAIN_EXTENSION_NAME)) {
        tpk_vk_context_destroy(ctx);
        return tpk_diag_fail(diag, "vulkan: the device has no %s", VK_KHR_SWAPCHAIN_EXTENSION_NAME);
    }
    const float priority = 1.0f;
    VkDeviceQueueCreateInfo queue = {
        .sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO,
        .queueFamilyIndex = ctx->queue_family,
        .queueCount = 1,
        .pQueuePriorities = &priority,
    };
    VkPhysicalDeviceFeatures supported, enabled;
    vkGetPhysicalDeviceFeatures(ctx->physical, &supported);
    memset(&enabled, 0, sizeof enabled);
    /* TPK_VK_NO_FP64=1 takes the variant without doubles on any device, so that tests run it here */
    const char *no_fp64 = getenv("TPK_VK_NO_FP64");
    ctx->fp64 = supported.shaderFloat64 == VK_TRUE && !(no_fp64 && !strcmp(no_fp64, "1"));
    enabled.shaderFloat64 = ctx->fp64 ? VK_TRUE : VK_FALSE;
    /* whether a pipeline came from the pipeline cache (render --json says so) */
    const char *extensions[3];
    uint32_t extension_count = 0;
    ctx->creation_feedback = has_extension(ctx->physical, VK_EXT_PIPELINE_CREATION_FEEDBACK_EXTENSION_NAME);
    if (ctx->creation_feedback)
        extensions[extension_count++] = VK_EXT_PIPELINE_CREATION_FEEDBACK_EXTENSION_NAME;
    if (surface) /* the window's swapchain (vk_present.c) */
        extensions[extension_count++] = VK_KHR_SWAPCHAIN_EXTENSION_NAME;
    /* render --iso-raster's task and mesh shaders (vk_raster.c), nothing else of the extension */
    VkPhysicalDeviceMeshShaderFeaturesEXT mesh = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MESH_SHADER_FEATURES_EXT,
                                                  .taskShader = VK_TRUE, .meshShader = VK_TRUE};
    ctx->mesh_shader = want_mesh_shader && tpk_vk_has_mesh_shader(ctx->physical);
    if (ctx->mesh_shader) {
        extensions[extension_count++] = VK_EXT_MESH_SHADER_EXTENSION_NAME;
        ctx->mesh = (VkPhysicalDeviceMeshShaderPropertiesEXT){
            .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MESH_SHADER_PROPERTIES_EXT};
        VkPhysicalDeviceProperties2 p2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, .pNext = &ctx->mesh};
        vkGetPhysicalDeviceProperties2(ctx->physical, &p2);
        ctx->mesh.pNext = NULL;
    }
    /* render --iso-raster's compute rasterizer (vk_vis.c): 64-bit atomics on storage buffers where the device
     * has them (TPK_VK_NO_INT64_ATOMICS=1: the 32-bit variant on any device, for tests) */
    const char *no_int64 = getenv("TPK_VK_NO_INT64_ATOMICS");
    VkPhysicalDeviceVulkan12Features v12 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    VkPhysicalDeviceFeatures2 f2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, .pNext = &v12};
    vkGetPhysicalDeviceFeatures2(ctx->physical, &f2);
    ctx->int64_atomics = v12.shaderBufferInt64Atomics == VK_TRUE && supported.shaderInt64 == VK_TRUE &&
                         !(no_int64 && !strcmp(no_int64, "1"));
    v12 = (VkPhysicalDeviceVulkan12Features){.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES,
                                             .pNext = ctx->mesh_shader ? &mesh : NULL,
                                             .shaderBufferInt64Atomics = ctx->int64_atomics ? VK_TRUE : VK_FALSE};
    enabled.shaderInt64 = ctx->int64_atomics ? VK_TRUE : VK_FALSE;
    VkDeviceCreateInfo info = {
        .sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO,
        .pNext = &v12,
        .queueCreateInfoCount = 1,
        .pQueueCreateInfos = &queue,
        .enabledExtensionCount = extension_count,
        .ppEnabledExtensionNames = extensions,
        .pEnabledFeatures = &enabled,
    };
    VkResult r = vkCreateDevice(ctx->physical, &info, NULL, &ctx->device);
    if (r != VK_SUCCESS) {
        ctx->device = VK_NULL_HANDLE;
        tpk_vk_context_destroy(ctx);
        return vk_fail(diag, "creating the device", r);
    }
    vkGetDeviceQueue(ctx->device, ctx->queue_family, 0, &ctx->queue);
    return 0;
}

void tpk_vk_context_destroy(tpk_vk_context *ctx)
{
    if (ctx->device)
        vkDestroyDevice(ctx->device, NULL);
    if (ctx->surface)
        vkDestroySurfaceKHR(ctx->instance, ctx->surface, NULL);
    if (ctx->instance)
        vkDestroyInstance(ctx->instance, NULL);
    memset(ctx, 0, sizeof *ctx);
}

VkQueryPool tpk_vk_timestamp_pool(const tpk_vk_context *ctx)
{
    VkQueryPool pool = VK_NULL_HANDLE;
    if (ctx->timestamp_bits == 0 || !(ctx->props.limits.timestampPeriod > 0))
        return VK_NULL_HANDLE;
    VkQueryPoolCreateInfo query = {
        .sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO, .queryType = VK_QUERY_TYPE_TIMESTAMP, .queryCount = 2};
    return vkCreateQueryPool(ctx->device, &query, NULL, &pool) == VK_SUCCESS ? pool : VK_NULL_HANDLE;
}

double tpk_vk_timestamp_seconds(const tpk_vk_context *ctx, VkQueryPool pool)
{
    uint64_t ticks[2];
    if (!pool || vkGetQueryPoolResults(ctx->device, pool, 0, 2, sizeof ticks, ticks, sizeof ticks[0],
                                       VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT) != VK_SUCCESS)
        return -1.0;
    uint64_t mask = ctx->timestamp_bits >= 64 ? ~(uint64_t)0 : ((uint64_t)1 << ctx->timestamp_bits) - 1;
    uint64_t elapsed = ((ticks[1] & mask) - (ticks[0] & mask)) & mask; /* a wrap between the two */
    return 1e-9 * (double)ctx->props.limits.timestampPeriod * (double)elapsed;
}

/* ---- Buffers ------------------------------------------------------------------------------------- */

static VkResult allocate(const tpk_vk_context *ctx, const VkMemoryRequirements *req, tpk_vk_memory_use use,
                         tpk_vk_buffer *out, VkMemoryPropertyFlags *flags)
{
    uint32_t order[VK_MAX_MEMORY_TYPES];
    int n = tpk_vk_memory_rank(&ctx->memory, ctx->unified, req->memoryTypeBits, use, order);
    VkResult r = VK_ERROR_OUT_OF_DEVICE_MEMORY;
    for (int k = 0; k < n && r != VK_SUCCESS; k++) { /* a full heap: the next type */
        VkMemoryAllocateInfo alloc = {
            .sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO,
            .allocationSize = req->size,
            .memoryTypeIndex = order[k],
        };
        r = vkAllocateMemory(ctx->device, &alloc, NULL, &out->memory);
        *flags = ctx->memory.memoryTypes[order[k]].propertyFlags;
    }
    return r;
}

int tpk_vk_buffer_create(const tpk_vk_context *ctx, VkDeviceSize size, VkBufferUsageFlags usage,
                         tpk_vk_memory_use use, const char *what, tpk_vk_buffer *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    VkBufferCreateInfo info = {
        .sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO,
        .size = size,
        .usage = usage,
        .sharingMode = VK_SHARING_MODE_EXCLUSIVE,
    };
    VkResult r = vkCreateBuffer(ctx->device, &info, NULL, &out->buffer);
    if (r != VK_SUCCESS) {
        out->buffer = VK_NULL_HANDLE;
        return tpk_diag_fail(diag, "vulkan: creating the buffer for %s (%llu bytes) failed: %s", what,
                             (unsigned long long)size, tpk_vk_result_name(r));
    }
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(ctx->device, out->buffer, &req);
    VkMemoryPropertyFlags flags = 0;
    if ((r = allocate(ctx, &req, use, out, &flags)) != VK_SUCCESS) {
        out->memory = VK_NULL_HANDLE;
        tpk_vk_buffer_destroy(ctx, out);
        return tpk_diag_fail(diag, "vulkan: allocating %llu bytes for %s failed: %s", (unsigned long long)req.size,
                             what, tpk_vk_result_name(r));
    }
    if ((r = vkBindBufferMemory(ctx->device, out->buffer, out->memory, 0)) != VK_SUCCESS ||
        ((flags & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT) &&
         (r = vkMapMemory(ctx->device, out->memory, 0, VK_WHOLE_SIZE, 0, &out->mapped)) != VK_SUCCESS)) {
        out->mapped = NULL;
        tpk_vk_buffer_destroy(ctx, out);
        return tpk_diag_fail(diag, "vulkan: mapping the memory of %s failed: %s", what, tpk_vk_result_name(r));
    }
    out->coherent = (flags & VK_MEMORY_PROPERTY_HOST_COHERENT_BIT) != 0;
    out->size = size;
    return 0;
}

/* The whole mapping: offset 0 and VK_WHOLE_SIZE meet nonCoherentAtomSize whatever it is. */
int tpk_vk_buffer_flush(const tpk_vk_context *ctx, const tpk_vk_buffer *b, tpk_diag *diag)
{
    if (b->coherent || !b->mapped)
        return 0;
    VkMappedMemoryRange range = {
        .sType = VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE, .memory = b->memory, .offset = 0, .size = VK_WHOLE_SIZE};
    VkResult r = vkFlushMappedMemoryRanges(ctx->device, 1, &range);
    return r == VK_SUCCESS ? 0 : vk_fail(diag, "flushing mapped memory", r);
}

int tpk_vk_buffer_invalidate(const tpk_vk_context *ctx, const tpk_vk_buffer *b, tpk_diag *diag)
{
    if (b->coherent || !b->mapped)
        return 0;
    VkMappedMemoryRange range = {
        .sType = VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE, .memory = b->memory, .offset = 0, .size = VK_WHOLE_SIZE};
    VkResult r = vkInvalidateMappedMemoryRanges(ctx->device, 1, &range);
    return r == VK_SUCCESS ? 0 : vk_fail(diag, "invalidating mapped memory", r);
}

void tpk_vk_buffer_destroy(const tpk_vk_context *ctx, tpk_vk_buffer *b)
{
    if (b->mapped)
        vkUnmapMemory(ctx->device, b->memory);
    if (b->buffer)
        vkDestroyBuffer(ctx->device, b->buffer, NULL);
    if (b->memory)
        vkFreeMemory(ctx->device, b->memory, NULL);
    memset(b, 0, sizeof *b);
}
