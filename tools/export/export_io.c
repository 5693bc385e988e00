/* Atomic output files and chunk loading for the exporters. */
#include "export_io.h"

#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

int tpk_out_open(tpk_out *o, const char *path, tpk_diag *diag)
{
    memset(o, 0, sizeof *o);
    o->path = path;
    if (tpk_output_open(&o->file, path, diag) != 0)
        return -1;
    o->f = tpk_output_stream(&o->file, diag);
    if (!o->f) {
        tpk_output_abort(&o->file);
        return -1;
    }
    return 0;
}

void tpk_out_write(tpk_out *o, const void *data, size_t size)
{
    if (!o->failed && size && fwrite(data, 1, size, o->f) != size)
        o->failed = errno ? errno : EIO;
}

void tpk_out_printf(tpk_out *o, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    if (!o->failed && vfprintf(o->f, fmt, ap) < 0)
        o->failed = errno ? errno : EIO;
    va_end(ap);
}

static void store_le(unsigned char *dst, uint64_t v, int bytes)
{
    for (int i = 0; i < bytes; i++)
        dst[i] = (unsigned char)(v >> (8 * i));
}

void tpk_out_u64le(tpk_out *o, uint64_t v)
{
    unsigned char b[8];
    store_le(b, v, 8);
    tpk_out_write(o, b, 8);
}

/* Convert through a buffer so the output is little-endian on any host. */
#define WRITE_ARRAY(o, v, count, bytes, to_bits)                         \
    do {                                                                \
        unsigned char buf_[8192];                                       \
        size_t per_ = sizeof buf_ / (bytes);                            \
        for (size_t i_ = 0; i_ < (count); i_ += per_) {                 \
            size_t n_ = (count) - i_ < per_ ? (count) - i_ : per_;      \
            for (size_t j_ = 0; j_ < n_; j_++)                          \
                store_le(buf_ + j_ * (bytes), to_bits((v)[i_ + j_]), (bytes)); \
            tpk_out_write((o), buf_, n_ * (bytes));                     \
        }                                                               \
    } while (0)

static inline uint64_t bits_i32(int32_t v)
{
    return (uint32_t)v;
}
static inline uint64_t bits_i64(int64_t v)
{
    return (uint64_t)v;
}
static inline uint64_t bits_f32(float v)
{
    uint32_t u;
    memcpy(&u, &v, 4);
    return u;
}
static inline uint64_t bits_f64(double v)
{
    uint64_t u;
    memcpy(&u, &v, 8);
    return u;
}

void tpk_out_i32le(tpk_out *o, const int32_t *v, size_t count)
{
    WRITE_ARRAY(o, v, count, 4, bits_i32);
}
void tpk_out_f32le(tpk_out *o, const float *v, size_t count)
{
    WRITE_ARRAY(o, v, count, 4, bits_f32);
}
void tpk_out_f64le(tpk_out *o, const double *v, size_t count)
{
    WRITE_ARRAY(o, v, count, 8, bits_f64);
}
void tpk_out_i64le(tpk_out *o, const int64_t *v, size_t count)
{
    WRITE_ARRAY(o, v, count, 8, bits_i64);
}

int tpk_out_commit(tpk_out *o, tpk_diag *diag)
{
    int err = o->failed;
    o->f = NULL;
    if (err) {
        tpk_output_abort(&o->file);
        return tpk_diag_fail(diag, "%s: write failed: %s (nothing was written)", o->path, strerror(err));
    }
    return tpk_output_commit(&o->file, diag);
}

void tpk_out_abort(tpk_out *o)
{
    o->f = NULL;
    tpk_output_abort(&o->file);
}

static void tag_text(uint32_t tag, char out[5])
{
    for (int i = 0; i < 4; i++) {
        char c = (char)(tag >> (8 * i));
        out[i] = c >= 0x20 && c < 0x7f ? c : '?';
    }
    out[4] = 0;
}

int tpk_export_load_chunk(tpk_file *file, uint32_t tag, uint32_t index, uint32_t step, uint32_t elem_size,
                          uint64_t expected_count, const void **data, void **owned, const char *path,
                          tpk_diag *diag)
{
    *data = NULL;
    *owned = NULL;
    char name[5];
    tag_text(tag, name);
    uint64_t i;
    tpk_result r = tpk_find_chunk(file, tag, index, step, &i);
    if (r == TPK_ERR_NOT_FOUND)
        return 0;
    tpk_dir_entry e;
    if (r == TPK_OK)
        r = tpk_get_chunk(file, i, &e);
    if (r != TPK_OK)
        return tpk_diag_fail(diag, "%s: cannot export: the input's chunk %s (index %u, step %u): %s", path, name,
                             index, step, tpk_error_text(file)[0] ? tpk_error_text(file) : tpk_result_string(r));
    if (e.elem_size != elem_size || e.elem_count != expected_count)
        return tpk_diag_fail(diag, "%s: chunk %s (index %u, step %u) has %llu elements of %u bytes, expected %llu of %u",
                             path, name, index, step, (unsigned long long)e.elem_count, e.elem_size,
                             (unsigned long long)expected_count, elem_size);
    uint64_t size;
    if (e.codec == TPK_CODEC_NONE) {
        r = tpk_view_chunk(file, i, data, &size);
    } else {
        *owned = malloc(e.raw_size ? (size_t)e.raw_size : 1);
        if (!*owned)
            return tpk_diag_fail(diag, "%s: out of memory decoding chunk %s (%llu bytes)", path, name,
                                 (unsigned long long)e.raw_size);
        r = tpk_read_chunk(file, i, *owned, e.raw_size);
        *data = *owned;
    }
    if (r != TPK_OK) {
        free(*owned);
        *owned = NULL;
        *data = NULL;
        return tpk_diag_fail(diag, "%s: cannot export: the input's chunk %s (index %u, step %u): %s", path, name,
                             index, step, tpk_error_text(file)[0] ? tpk_error_text(file) : tpk_result_string(r));
    }
    return 1;
}

int tpk_export_pick_layout(tpk_file *file, const char *path, tpk_layout *out, tpk_diag *diag)
{
    static const struct {
        uint32_t tag;
        tpk_layout layout;
    } order[3] = {{TPK_TAG_TT32, TPK_LAYOUT_TET32}, {TPK_TAG_TT20, TPK_LAYOUT_TET20}, {TPK_TAG_TT16, TPK_LAYOUT_TET16}};
    for (int i = 0; i < 3; i++) {
        uint64_t index;
        if (tpk_find_chunk(file, order[i].tag, 0, 0, &index) == TPK_OK) {
            *out = order[i].layout;
            return 0;
        }
    }
    return tpk_diag_fail(diag, "%s: cannot export: the file has no tet layout (TT32, TT20 or TT16)", path);
}
