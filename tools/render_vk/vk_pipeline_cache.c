/* The pipeline cache on disk, so that a second run of the same shader on the same device and driver
 * compiles nothing: $XDG_CACHE_HOME/tetpack (else ~/.cache/tetpack), one file per device (pipeline
 * cache UUID), driver version and shader (a hash of the SPIR-V), named after them. The file is our
 * header, then the driver's cache data; a file whose header, size or checksum disagrees is ignored
 * (drivers are not required to survive bad cache data), and it is written atomically (base/output_file:
 * a temporary file linked into place), so concurrent runs each leave a whole file. A cache that cannot
 * be read or written is no error: the pipelines are then compiled as without one. TPK_VK_PIPELINE_CACHE=0
 * turns it off. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "base/output_file.h"
#include "render_vk_internal.h"

#define CACHE_MAGIC "TPKPIPE1"
#define CACHE_MAX_BYTES ((size_t)256 << 20)

/* Our header, little-endian as written by this host (the file is only ever read where it was made). */
typedef struct cache_header {
    char magic[8];
    uint32_t header_size, vendor_id, device_id, driver_version;
    uint8_t uuid[VK_UUID_SIZE];
    uint64_t shader_hash, data_size, data_hash;
} cache_header;

static uint64_t fnv1a(const void *p, size_t n, uint64_t h)
{
    const uint8_t *b = p;
    for (size_t i = 0; i < n; i++)
        h = (h ^ b[i]) * 0x100000001b3ull;
    return h;
}
#define FNV_OFFSET 0xcbf29ce484222325ull

static void header_of(const tpk_vk_context *ctx, uint64_t shader_hash, cache_header *h)
{
    memset(h, 0, sizeof *h);
    memcpy(h->magic, CACHE_MAGIC, 8);
    h->header_size = (uint32_t)sizeof *h;
    h->vendor_id = ctx->props.vendorID;
    h->device_id = ctx->props.deviceID;
    h->driver_version = ctx->props.driverVersion;
    memcpy(h->uuid, ctx->props.pipelineCacheUUID, VK_UUID_SIZE);
    h->shader_hash = shader_hash;
}

/* mkdir -p of the cache directory; 0 when it exists afterwards. */
static int make_dirs(char *path)
{
    for (char *s = path + 1; *s; s++) {
        if (*s != '/')
            continue;
        *s = 0;
        int r = mkdir(path, 0755);
        *s = '/';
        if (r != 0 && errno != EEXIST)
            return -1;
    }
    return mkdir(path, 0755) == 0 || errno == EEXIST ? 0 : -1;
}

/* The cache file's path for this device and shader, its directory created; NULL without one. */
static char *cache_path(const tpk_vk_context *ctx, uint64_t shader_hash)
{
    const char *off = getenv("TPK_VK_PIPELINE_CACHE");
    if (off && !strcmp(off, "0"))
        return NULL;
    const char *xdg = getenv("XDG_CACHE_HOME"), *home = getenv("HOME");
    char dir[4096];
    int n = xdg && xdg[0] == '/' ? snprintf(dir, sizeof dir, "%s/tetpack", xdg)
            : home && *home      ? snprintf(dir, sizeof dir, "%s/.cache/tetpack", home)
                                 : -1;
    if (n < 0 || (size_t)n >= sizeof dir || make_dirs(dir) != 0)
        return NULL;
    char uuid[2 * VK_UUID_SIZE + 1];
    for (unsigned i = 0; i < VK_UUID_SIZE; i++)
        snprintf(uuid + 2 * i, 3, "%02x", ctx->props.pipelineCacheUUID[i]);
    size_t size = strlen(dir) + 128;
    char *path = malloc(size);
    if (path)
        snprintf(path, size, "%s/pipelines-%s-%08x-%016llx.bin", dir, uuid, ctx->props.driverVersion,
                 (unsigned long long)shader_hash);
    return path;
}

/* The driver's data of a valid cache file (malloc'ed, *size bytes), or NULL. */
static void *read_cache(const char *path, const cache_header *expect, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    cache_header h;
    void *data = NULL;
    if (fread(&h, sizeof h, 1, f) != 1 || memcmp(h.magic, expect->magic, 8) || h.header_size != sizeof h ||
        h.vendor_id != expect->vendor_id || h.device_id != expect->device_id ||
        h.driver_version != expect->driver_version || memcmp(h.uuid, expect->uuid, VK_UUID_SIZE) ||
        h.shader_hash != expect->shader_hash || h.data_size < 16 + VK_UUID_SIZE || h.data_size > CACHE_MAX_BYTES)
        goto done;
    data = malloc(h.data_size);
    if (!data || fread(data, 1, h.data_size, f) != h.data_size || fgetc(f) != EOF ||
        fnv1a(data, h.data_size, FNV_OFFSET) != h.data_hash) {
        free(data);
        data = NULL;
        goto done;
    }
    /* the driver's own header: VkPipelineCacheHeaderVersionOne of this device */
    uint32_t words[4];
    memcpy(words, data, sizeof words);
    if (words[0] < 16 + VK_UUID_SIZE || words[1] != VK_PIPELINE_CACHE_HEADER_VERSION_ONE ||
        words[2] != expect->vendor_id || words[3] != expect->device_id ||
        memcmp((const char *)data + 16, expect->uuid, VK_UUID_SIZE)) {
        free(data);
        data = NULL;
        goto done;
    }
    *size = h.data_size;
done:
    fclose(f);
    return data;
}

void tpk_vk_cache_open(const tpk_vk_context *ctx, const void *spirv, size_t spirv_size, tpk_vk_cache *c)
{
    memset(c, 0, sizeof *c);
    c->shader_hash = fnv1a(spirv, spirv_size, FNV_OFFSET);
    c->path = cache_path(ctx, c->shader_hash);
    cache_header expect;
    header_of(ctx, c->shader_hash, &expect);
    size_t size = 0;
    void *data = c->path ? read_cache(c->path, &expect, &size) : NULL;
    VkPipelineCacheCreateInfo info = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_CACHE_CREATE_INFO, .initialDataSize = size, .pInitialData = data};
    if (vkCreatePipelineCache(ctx->device, &info, NULL, &c->cache) != VK_SUCCESS) {
        info.initialDataSize = 0; /* the driver refused the data: start empty */
        info.pInitialData = NULL;
        size = 0;
        if (vkCreatePipelineCache(ctx->device, &info, NULL, &c->cache) != VK_SUCCESS)
            c->cache = VK_NULL_HANDLE;
    }
    c->loaded_bytes = size;
    free(data);
}

/* Write header and data to the cache path atomically; failures are silent (no cache next time). */
static void write_cache(const tpk_vk_context *ctx, const tpk_vk_cache *c, const void *data, size_t size)
{
    cache_header h;
    header_of(ctx, c->shader_hash, &h);
    h.data_size = size;
    h.data_hash = fnv1a(data, size, FNV_OFFSET);
    tpk_diag diag = {0};
    tpk_output out;
    if (access(c->path, F_OK) == 0 && tpk_output_check("cache", c->path, NULL, 0, &diag) != 0)
        return; /* something other than a regular file is there: leave it */
    if (tpk_output_open(&out, c->path, &diag) != 0)
        return;
    FILE *f = tpk_output_stream(&out, &diag);
    if (!f || fwrite(&h, sizeof h, 1, f) != 1 || fwrite(data, 1, size, f) != size) {
        tpk_output_abort(&out);
        return;
    }
    tpk_output_commit(&out, &diag);
}

void tpk_vk_cache_close(const tpk_vk_context *ctx, tpk_vk_cache *c)
{
    if (c->cache && c->path && c->compiled > 0) {
        size_t size = 0;
        void *data = NULL;
        if (vkGetPipelineCacheData(ctx->device, c->cache, &size, NULL) == VK_SUCCESS && size >= 16 + VK_UUID_SIZE &&
            size <= CACHE_MAX_BYTES && (data = malloc(size)) &&
            vkGetPipelineCacheData(ctx->device, c->cache, &size, data) == VK_SUCCESS)
            write_cache(ctx, c, data, size);
        free(data);
    }
    if (c->cache)
        vkDestroyPipelineCache(ctx->device, c->cache, NULL);
    free(c->path);
    memset(c, 0, sizeof *c);
}
