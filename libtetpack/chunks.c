/* The bytes of one chunk of an open file: decoding, checksums (rule 16) and id ranges (rule 17),
 * each remembered per chunk, and the decoded copies of zstd chunks the handle keeps. Shared by the
 * reader, tpk_load_arrays and tpk_verify; calls only handle.c and rules.c. */
#include <inttypes.h>
#include <string.h>
#include <xxhash.h>
#include <zstd.h>

#include "internal_file.h"

/* ---- decoding and checksums --------------------------------------------------------------------- */

static tpk_result decode_zstd(tpk_file *file, uint64_t i, void *dst)
{
    const tpk_dir_entry *e = &file->entries[i];
    const uint8_t *src = file->data + e->offset;
    char name[80];
    tpki_entry_name(i, &file->entries[i], name);
    unsigned long long declared = ZSTD_getFrameContentSize(src, e->stored_size);
    if (declared == ZSTD_CONTENTSIZE_ERROR)
        return tpki_file_fail(file, TPK_ERR_DECOMPRESS, "%s: the %" PRIu64 " stored bytes are not a zstd frame",
                             name, e->stored_size);
    if (declared != ZSTD_CONTENTSIZE_UNKNOWN && declared != e->raw_size)
        return tpki_file_fail(file, TPK_ERR_DECOMPRESS, "%s: zstd frame declares %llu bytes but raw_size is %" PRIu64,
                             name, declared, e->raw_size);
    size_t got = ZSTD_decompress(dst, e->raw_size, src, e->stored_size);
    if (ZSTD_isError(got))
        return tpki_file_fail(file, TPK_ERR_DECOMPRESS, "%s: zstd: %s (raw_size %" PRIu64 ")", name,
                             ZSTD_getErrorName(got), e->raw_size);
    if (got != e->raw_size)
        return tpki_file_fail(file, TPK_ERR_DECOMPRESS, "%s: decoded %zu bytes but raw_size is %" PRIu64, name, got,
                             e->raw_size);
    return TPK_OK;
}

tpk_result tpki_file_decode(tpk_file *file, uint64_t i, void *dst)
{
    const tpk_dir_entry *e = &file->entries[i];
    if (e->codec == TPK_CODEC_ZSTD)
        return decode_zstd(file, i, dst);
    if (e->raw_size > 0)
        memcpy(dst, file->data + e->offset, e->raw_size);
    return TPK_OK;
}

tpk_result tpki_file_check_sum(tpk_file *file, uint64_t i, const void *raw)
{
    const tpk_dir_entry *e = &file->entries[i];
    uint64_t sum = XXH64(raw, e->raw_size, 0);
    if (sum != e->checksum) {
        char name[80];
        tpki_entry_name(i, &file->entries[i], name);
        return tpki_file_fail(file, TPK_ERR_CHUNK_CHECKSUM,
                             "%s: checksum of the %" PRIu64 " raw bytes is 0x%016" PRIx64 ", directory says 0x%016" PRIx64,
                             name, e->raw_size, sum, e->checksum);
    }
    atomic_fetch_or(&file->chunk_state[i], TPK_CHUNK_SUM_OK);
    return TPK_OK;
}

int tpki_file_needs_sum(const tpk_file *file, uint64_t i)
{
    return !(file->flags & TPK_OPEN_TRUSTED) && !(atomic_load(&file->chunk_state[i]) & TPK_CHUNK_SUM_OK);
}

/* ---- verified bytes --------------------------------------------------------------------------------- */

/* Install a freshly decoded copy unless another thread got there first; returns the copy to use. */
static void *install_decoded(tpk_file *file, uint64_t i, void *mine)
{
    pthread_mutex_lock(&file->lock);
    void *kept = file->decoded[i];
    if (!kept)
        file->decoded[i] = kept = mine;
    pthread_mutex_unlock(&file->lock);
    if (kept != mine)
        tpki_file_free(file, mine);
    return kept;
}

static tpk_result decoded_copy(tpk_file *file, uint64_t i, const void **out)
{
    pthread_mutex_lock(&file->lock);
    void *existing = file->decoded[i];
    pthread_mutex_unlock(&file->lock);
    if (existing) {
        *out = existing;
        return TPK_OK;
    }
    const tpk_dir_entry *e = &file->entries[i];
    void *mine = tpki_file_alloc(file, e->raw_size);
    if (!mine)
        return tpki_file_fail(file, TPK_ERR_OUT_OF_MEMORY, "out of memory decoding chunk %" PRIu64 " (%" PRIu64 " bytes)",
                             i, e->raw_size);
    tpk_result r = tpki_file_decode(file, i, mine);
    if (r == TPK_OK && tpki_file_needs_sum(file, i))
        r = tpki_file_check_sum(file, i, mine);
    if (r != TPK_OK) {
        tpki_file_free(file, mine);
        return r;
    }
    *out = install_decoded(file, i, mine);
    return TPK_OK;
}

tpk_result tpki_file_chunk_bytes(tpk_file *file, uint64_t i, const void **out)
{
    const tpk_dir_entry *e = &file->entries[i];
    if (e->codec != TPK_CODEC_NONE)
        return decoded_copy(file, i, out);
    const void *raw = file->data + e->offset;
    if (tpki_file_needs_sum(file, i)) {
        tpk_result r = tpki_file_check_sum(file, i, raw);
        if (r != TPK_OK)
            return r;
    }
    *out = raw;
    return TPK_OK;
}

tpk_result tpki_file_check_ids(tpk_file *file, uint64_t i, const void *raw)
{
    if (atomic_load(&file->chunk_state[i]) & TPK_CHUNK_IDS_OK)
        return TPK_OK;
    tpki_diag diag;
    tpk_result r = tpki_check_records(&file->header, i, &file->entries[i], raw, &diag);
    if (r != TPK_OK)
        return tpki_file_report(file, r, diag.text);
    atomic_fetch_or(&file->chunk_state[i], TPK_CHUNK_IDS_OK);
    return TPK_OK;
}

/* Checksum, decode and ids of one chunk; zstd chunks are decoded into a temporary buffer. */
tpk_result tpki_file_verify_chunk(tpk_file *file, uint64_t i, int check_ids)
{
    const tpk_dir_entry *e = &file->entries[i];
    void *owned = NULL;
    const void *raw = file->data + e->offset;
    tpk_result r = TPK_OK;
    if (e->codec != TPK_CODEC_NONE) {
        owned = tpki_file_alloc(file, e->raw_size);
        if (!owned)
            return tpki_file_fail(file, TPK_ERR_OUT_OF_MEMORY, "out of memory decoding chunk %" PRIu64
                                 " (%" PRIu64 " bytes)", i, e->raw_size);
        raw = owned;
        r = tpki_file_decode(file, i, owned);
        if (r != TPK_OK)
            goto fail;
    }
    if (!(atomic_load(&file->chunk_state[i]) & TPK_CHUNK_SUM_OK))
        r = tpki_file_check_sum(file, i, raw);
    if (r == TPK_OK && check_ids)
        r = tpki_file_check_ids(file, i, raw);
fail:
    tpki_file_free(file, owned);
    return r;
}
