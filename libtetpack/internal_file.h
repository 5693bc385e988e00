/* libtetpack private declarations for the container: the open-file handle, error reporting, chunk
 * access, and the pure check_* rules shared by the reader and the writer. Not installed. The rule
 * numbers in comments are those of spec/tetpack-format.md, section "reader".
 * Owners, top to bottom (a file calls only files below it, never back up):
 *   arrays.c   tpk_load_arrays (public), on top of reader.c's tpk_find_chunk and tpk_find_field
 *   reader.c   tpk_open_*, tpk_close, the directory, chunk, field and time queries, tpk_verify (public)
 *   writer.c   tpk_writer_* (public); uses rules.c only
 *   chunks.c   tpki_file_mark_read, tpki_file_decode, tpki_file_needs_sum, tpki_file_check_sum, tpki_file_chunk_bytes,
 *              tpki_file_check_ids, tpki_file_verify_chunk
 *   handle.c   tpki_file_alloc, tpki_file_free, tpki_file_report, tpki_file_refuse, tpki_file_fail,
 *              tpki_file_usable, tpk_error_text (public: the message is the handle's, under its lock)
 *   rules.c    tpki_fail, tpki_text_fail, tpki_tag_name, tpki_entry_name and every pure rule below (tpki_resolve_*,
 *              tpki_elem_type_size, tpki_known_tag, tpki_check_*) */
#ifndef TPK_INTERNAL_FILE_H
#define TPK_INTERNAL_FILE_H

#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdint.h>

#include "tetpack.h"

#if defined(__BYTE_ORDER__) && defined(__ORDER_LITTLE_ENDIAN__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "libtetpack maps little-endian records directly and supports little-endian hosts only"
#endif

#define TPK_ERROR_TEXT_SIZE 512
#define TPK_MAX_FIELDS 4096u
#define TPK_MAX_ID 0x7fffffffu
/* The most a Zstandard frame can expand: a block decodes to at most 128 KiB (RFC 8878
 * Block_Maximum_Size) and an RLE block, the densest, takes 4 bytes. */
#define TPK_ZSTD_MAX_EXPANSION 32768u

/* Defaults of tpk_limits (0 in the options means these). */
#define TPK_DEFAULT_MAX_CHUNKS 65536u
#define TPK_DEFAULT_MAX_CHUNK_BYTES (64ull << 30)
#define TPK_DEFAULT_MAX_TOTAL_BYTES (256ull << 30)

/* Per-chunk state bits, set once with atomic_fetch_or so concurrent readers agree. */
#define TPK_CHUNK_SUM_OK 0x1u /* checksum (and decode) verified */
#define TPK_CHUNK_IDS_OK 0x2u /* rule 17 id ranges verified */
#define TPK_CHUNK_READ 0x4u   /* its bytes were read (decoded, checksummed or handed out): tpk_get_chunk_use */

/* A detailed error text being built by a check, before it reaches a handle or a caller buffer. */
typedef struct tpki_diag {
    char text[TPK_ERROR_TEXT_SIZE];
} tpki_diag;

struct tpk_file {
    tpk_allocator allocator;   /* resolved: never NULL functions */
    uint32_t flags;            /* TPK_OPEN_* */
    tpk_limits limits;         /* resolved: never 0 */
    tpk_message_fn message;
    void *message_user;
    const uint8_t *data;       /* the whole file: a mapping or caller memory */
    uint64_t size;
    void *mapping;             /* non-NULL when we mmap'ed data (length mapping_size) */
    size_t mapping_size;
    tpk_header header;
    tpk_dir_entry *entries;    /* copy of the validated directory, header.chunk_count entries */
    atomic_uint *chunk_state;  /* TPK_CHUNK_* bits per entry */
    void **decoded;            /* per entry: decoded copy of a zstd chunk owned by the handle, or NULL */
    tpk_field_desc *fields;    /* copy of the FDSC chunk */
    uint32_t field_count;
    atomic_int poisoned;
    pthread_mutex_t lock;      /* guards error_text and decoded[] */
    char error_text[TPK_ERROR_TEXT_SIZE];
};

/* ---- diagnostics (rules.c) ---- */
tpk_result tpki_fail(tpki_diag *diag, tpk_result code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* The same into a caller's buffer err of cap bytes (none when err is NULL or cap 0): the part-set calls'
 * error text. Returns code. */
tpk_result tpki_text_fail(char *err, size_t cap, tpk_result code, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
/* "'TT16'" when the four bytes are printable ASCII, else "0x........". */
void tpki_tag_name(uint32_t tag, char out[16]);
/* "chunk 3 'TT16' at offset 4096", the prefix of every per-chunk message. */
void tpki_entry_name(uint64_t i, const tpk_dir_entry *e, char out[80]);

/* ---- pure rules (rules.c), shared by reader and writer ---- */
void tpki_resolve_limits(const tpk_limits *in, tpk_limits *out);
/* Fill NULL alloc/free with malloc/free wrappers. */
void tpki_resolve_allocator(const tpk_allocator *in, tpk_allocator *out);
/* Size of one element of a type, 0 for an unknown type. */
uint32_t tpki_elem_type_size(uint32_t elem_type);
/* Whether the tag is one of TPK_TAG_*, the element type it must have, and whether a writer must mark
 * it REQUIRED (out pointers may be NULL). */
int tpki_known_tag(uint32_t tag, uint32_t *out_elem_type, int *out_required);
/* Rule 5: header_size, dir_entry_size, flags, reserved bytes. */
tpk_result tpki_check_header_fields(const tpk_header *h, tpki_diag *diag);
/* Rules 7 and 8: counts, chunk_count limit, directory placement against h->file_size. */
tpk_result tpki_check_header_counts(const tpk_header *h, const tpk_limits *limits, tpki_diag *diag);
/* Rules 10, 11 and the bounds half of 12 for entry i; *total_raw accumulates raw sizes. */
tpk_result tpki_check_entry(const tpk_header *h, const tpk_limits *limits, uint64_t i,
                           const tpk_dir_entry *e, uint64_t *total_raw, tpki_diag *diag);
/* The overlap half of rule 12 over all entries (scratch memory from the allocator). */
tpk_result tpki_check_overlaps(const tpk_header *h, const tpk_dir_entry *entries,
                              const tpk_allocator *allocator, tpki_diag *diag);
/* Rules 13 and 14 over all entries. A writer allows unknown (vendor) chunks marked REQUIRED. */
tpk_result tpki_check_tags(const tpk_header *h, const tpk_dir_entry *entries, int allow_unknown_required,
                          const tpk_allocator *allocator, tpki_diag *diag);
/* Rule 15: field descriptors, FDAT and TIME chunks agree. fields may be NULL when count is 0. */
tpk_result tpki_check_fields(const tpk_header *h, const tpk_dir_entry *entries,
                            const tpk_field_desc *fields, uint32_t field_count,
                            const tpk_allocator *allocator, tpki_diag *diag);
/* Rule 17: id ranges in the raw bytes of entry i (TT32, TT20, TT16, SHEL, TMAP; others pass). */
tpk_result tpki_check_records(const tpk_header *h, uint64_t i, const tpk_dir_entry *e, const void *raw,
                             tpki_diag *diag);
/* Rules 5, 7, 8 and 10 to 15 on a header and directory built in memory (the writer's self-check). */
tpk_result tpki_check_layout(const tpk_header *h, const tpk_dir_entry *entries,
                            const tpk_field_desc *fields, uint32_t field_count,
                            const tpk_allocator *allocator, tpki_diag *diag);

/* ---- handle state (handle.c) ---- */
/* Allocation through the handle's allocator; a size of 0 gets 1 byte, one over SIZE_MAX gets NULL. */
void *tpki_file_alloc(const tpk_file *file, uint64_t size);
void tpki_file_free(const tpk_file *file, void *ptr);
/* Store the text, call the message callback, poison the handle unless the code is a caller-side or
 * resource error (INVALID_ARGUMENT, NOT_FOUND, OUT_OF_MEMORY, LIMIT). Returns code. */
tpk_result tpki_file_report(tpk_file *file, tpk_result code, const char *text);
/* Store the text and call the message callback, never poisoning: a caller mistake whose code would
 * otherwise poison (tpk_view_chunk asked for a zstd chunk). Returns code. */
tpk_result tpki_file_refuse(tpk_file *file, tpk_result code, const char *text);
tpk_result tpki_file_fail(tpk_file *file, tpk_result code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* TPK_ERR_BAD_STATE (reported) when the handle is poisoned, else TPK_OK. */
tpk_result tpki_file_usable(tpk_file *file);

/* ---- chunk bytes (chunks.c) ---- */
/* Remember that chunk i's bytes were read (tpk_get_chunk_use). */
void tpki_file_mark_read(tpk_file *file, uint64_t i);
/* Decode chunk i into dst (raw_size bytes) without checking its checksum. */
tpk_result tpki_file_decode(tpk_file *file, uint64_t i, void *dst);
/* Whether chunk i's checksum is still to be checked before its content is used (not TRUSTED, not done). */
int tpki_file_needs_sum(const tpk_file *file, uint64_t i);
/* Compare raw bytes with chunk i's checksum, remember success. */
tpk_result tpki_file_check_sum(tpk_file *file, uint64_t i, const void *raw);
/* Verified raw bytes of chunk i: a view for codec none, a handle-owned decoded copy for zstd
 * (kept until tpk_close). The checksum is checked on first use unless the file is TRUSTED. */
tpk_result tpki_file_chunk_bytes(tpk_file *file, uint64_t i, const void **out);
/* Rule 17 on chunk i's raw bytes, remembered per chunk. */
tpk_result tpki_file_check_ids(tpk_file *file, uint64_t i, const void *raw);
/* Checksum (decoding a zstd chunk into a temporary buffer) and, if check_ids, rule 17. */
tpk_result tpki_file_verify_chunk(tpk_file *file, uint64_t i, int check_ids);

#endif
