/* The bytes of one chunk of an open file: decoding, checksums (rule 16) and id ranges (rule 17),
 * each remembered per chunk, and the decoded copies of zstd chunks the handle keeps. Shared by the
 * reader, tpk_load_arrays and tpk_verify; calls only handle.c and rules.c. */
#include <inttypes.h>
#include <string.h>
#include <xxhash.h>
#include <zstd.h>

#include "internal_file.h"

/* ---- decoding and checksums --------------------------------------------------------------------- */

/* Rule 16's frame part (spec §4.2), before anything is allocated for the chunk: the stored bytes are
 * exactly one Zstandard frame (not a skippable frame, nothing after it), needing no dictionary, whose
 * declared content size, when present, is raw_size. A frame that would decode to a size the file does
 * not claim is refused here instead of costing a raw_size allocation first. */
static tpk_result check_zstd_frame(tpk_file *file, uint64_t i)
{
    const tpk_dir_entry *e = &file->entries[i];
    const uint8_t *src = file->data + e->offset;
    char name[80];
    tpki_entry_name(i, e, name);
    uint32_t magic = 0;
    if (e->stored_size >= 4)
        memcpy(&magic, src, 4);
    if ((magic & ZSTD_MAGIC_SKIPPABLE_MASK) == ZSTD_MAGIC_SKIPPABLE_START)
        return tpki_file_fail(file, TPK_ERR_DECOMPRESS, "%s: starts with a skippable frame (magic 0x%08" PRIx32
                             "), codec zstd needs one Zstandard frame (magic 0xFD2FB528)", name, magic);
    if (magic != ZSTD_MAGICNUMBER)
        return tpki_file_fail(file, TPK_ERR_DECOMPRESS, "%s: the %" PRIu64 " stored bytes do not start with a "
                             "Zstandard frame (magic 0x%08" PRIx32 ", expected 0xFD2FB528)", name, e->stored_size, magic);
    size_t frame = ZSTD_findFrameCompressedSize(src, e->stored_size);
    if (ZSTD_isError(frame))
        return tpki_file_fail(file, TPK_ERR_DECOMPRESS, "%s: the %" PRIu64 " stored bytes are not a complete "
                             "zstd frame: %s", name, e->stored_size, ZSTD_getErrorName(frame));
    if (frame != e->stored_size)
        return tpki_file_fail(file, TPK_ERR_DECOMPRESS, "%s: a zstd frame of %zu bytes is followed by %" PRIu64
                             " more stored bytes at file offset %" PRIu64 " (a second or skippable frame, or "
                             "trailing data); codec zstd allows exactly one frame", name, frame,
                             e->stored_size - frame, e->offset + frame);
    unsigned dictionary = ZSTD_getDictID_fromFrame(src, e->stored_size);
    if (dictionary != 0)
        return tpki_file_fail(file, TPK_ERR_DECOMPRESS, "%s: the zstd frame needs dictionary %u; codec zstd "
                             "allows no dictionary", name, dictionary);
    unsigned long long declared = ZSTD_getFrameContentSize(src, e->stored_size);
    if (declared != ZSTD_CONTENTSIZE_UNKNOWN && declared != e->raw_size)
        return tpki_file_fail(file, TPK_ERR_DECOMPRESS, "%s: zstd frame declares %llu bytes but raw_size is %" PRIu64
                             ": the directory's size claim is damaged",
                             name, declared, e->raw_size);
    return TPK_OK;
}

static tpk_result decode_zstd(tpk_file *file, uint64_t i, void *dst)
{
    const tpk_dir_entry *e = &file->entries[i];
    tpk_result r = check_zstd_frame(file, i);
    if (r != TPK_OK)
        return r;
    char name[80];
    tpki_entry_name(i, e, name);
    size_t got = ZSTD_decompress(dst, e->raw_size, file->data + e->offset, e->stored_size);
    if (ZSTD_isError(got))
        return tpki_file_fail(file, TPK_ERR_DECOMPRESS, "%s: zstd: %s (raw_size %" PRIu64 ")", name,
                             ZSTD_getErrorName(got), e->raw_size);
    if (got != e->raw_size)
        return tpki_file_fail(file, TPK_ERR_DECOMPRESS, "%s: decoded %zu bytes but raw_size is %" PRIu64, name, got,
                             e->raw_size);
    return TPK_OK;
}

/* Memory for the decoded bytes of zstd chunk i, after its frame passed check_zstd_frame: a claim the
 * frame contradicts never reaches the allocator, and a failure names the chunk and what the file
 * claims, since a huge raw_size in a small file is far more often damage than a real need. */
static tpk_result alloc_decoded(tpk_file *file, uint64_t i, void **out)
{
    const tpk_dir_entry *e = &file->entries[i];
    tpk_result r = check_zstd_frame(file, i);
    if (r != TPK_OK)
        return r;
    *out = tpki_file_alloc(file, e->raw_size);
    if (*out)
        return TPK_OK;
    char name[80];
    tpki_entry_name(i, e, name);
    return tpki_file_fail(file, TPK_ERR_OUT_OF_MEMORY, "%s: out of memory for the %" PRIu64 " bytes the file "
                         "claims the chunk decodes to (%" PRIu64 " bytes stored, header: %" PRIu64 " vertices, %"
                         PRIu64 " tets)", name, e->raw_size, e->stored_size, file->header.vertex_count,
                         file->header.tet_count);
}

void tpki_file_mark_read(tpk_file *file, uint64_t i)
{
    atomic_fetch_or(&file->chunk_state[i], TPK_CHUNK_READ);
}

tpk_result tpki_file_decode(tpk_file *file, uint64_t i, void *dst)
{
    const tpk_dir_entry *e = &file->entries[i];
    tpki_file_mark_read(file, i);
    if (e->codec == TPK_CODEC_ZSTD)
        return decode_zstd(file, i, dst);
    if (e->raw_size > 0)
        memcpy(dst, file->data + e->offset, e->raw_size);
    return TPK_OK;
}

tpk_result tpki_file_check_sum(tpk_file *file, uint64_t i, const void *raw)
{
    const tpk_dir_entry *e = &file->entries[i];
    tpki_file_mark_read(file, i);
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
    void *mine;
    tpk_result r = alloc_decoded(file, i, &mine);
    if (r != TPK_OK)
        return r;
    r = tpki_file_decode(file, i, mine);
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
    tpki_file_mark_read(file, i);
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
        r = alloc_decoded(file, i, &owned);
        if (r != TPK_OK)
            return r;
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
