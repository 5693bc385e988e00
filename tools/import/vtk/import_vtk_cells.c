/* VTK legacy importer: the POINTS, CELLS (old lists or 5.1 OFFSETS/CONNECTIVITY) and CELL_TYPES
 * sections. Point ids are checked to fit an int32 here, against the point count when the mesh is built. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "import_vtk_internal.h"
#include "base/parallel.h"
#include "base/text_numbers.h"
#include "base/text_scan.h"

/* Cell index holding connectivity entry k (offsets known and monotone up to there). */
static int64_t cell_of_entry(const int64_t *offsets, int64_t cells, int64_t k)
{
    int64_t lo = 0, hi = cells;
    while (hi - lo > 1) {
        int64_t mid = lo + (hi - lo) / 2;
        if (offsets[mid] <= k)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* ---- Passes over binary blocks on all threads ---------------------------------------------------- */

/* What the parallel passes below share: the workers take the block in chunks (tpk_parallel_chunks), each
 * scanned in order up to its first bad item; a worker keeps the smallest it found, so the smallest of the
 * workers' firsts is the item the serial loop stopped at (every chunk before it was scanned whole), and
 * the message stays the same for any thread count. */
typedef struct block_job {
    const unsigned char *p; /* the block's first byte */
    vtk_type type;
    int64_t *offsets;
    int32_t *conn;
    uint8_t *types;
    const int64_t *values;
    int64_t each, limit;
    int64_t base;           /* uniform lists: the conn index of the block's first cell */
    int64_t first_bad[TPK_MAX_THREADS]; /* per worker; INT64_MAX when none */
    /* Per worker, what finish_mesh may take as proved (import_vtk_internal.h, each_size): the largest id
     * or cell type read, the smallest cell type; the OFFSETS pass: most 1 where a cell's size is not
     * `each`. run_block_job merges them into most_all (-1 when nothing was read) and least_all. */
    int64_t most[TPK_MAX_THREADS], least[TPK_MAX_THREADS];
    int64_t most_all, least_all;
} block_job;

/* Items a chunk: a few hundred KiB of the file. */
#define BLOCK_CHUNK ((int64_t)1 << 15)

/* A worker's first bad item, the smallest over its chunks. */
static void found_bad(block_job *job, int worker, int64_t item)
{
    if (item < job->first_bad[worker])
        job->first_bad[worker] = item;
}

static int64_t run_block_job(block_job *job, int64_t count, tpk_range_fn fn)
{
    int threads = vtk_threads_for((uint64_t)count);
    for (int w = 0; w < threads; w++) {
        job->first_bad[w] = INT64_MAX;
        job->most[w] = -1;
        job->least[w] = INT64_MAX;
    }
    tpk_parallel_chunks(count, threads, BLOCK_CHUNK, fn, job);
    int64_t first = INT64_MAX;
    job->most_all = -1;
    job->least_all = INT64_MAX;
    for (int w = 0; w < threads; w++) {
        first = job->first_bad[w] < first ? job->first_bad[w] : first;
        job->most_all = job->most[w] > job->most_all ? job->most[w] : job->most_all;
        job->least_all = job->least[w] < job->least_all ? job->least[w] : job->least_all;
    }
    return first;
}

/* Old CELLS form where every cell has `each` points, in one pass: the counts checked, the offsets filled,
 * the ids copied and checked to be >= 0. A worker stops at its first cell with another count or a
 * negative id (the caller then reads the block the general way, for the message). */
static void uniform_lists_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    block_job *job = ctx;
    int64_t each = job->each;
    int32_t most = -1;
    for (int64_t c = begin; c < end; c++) {
        const unsigned char *cell = job->p + 4 * (size_t)(c * (each + 1));
        if ((int32_t)be32(cell) != each) {
            found_bad(job, worker, c);
            return;
        }
        int32_t *dst = job->conn + c * each;
        for (int64_t j = 0; j < each; j++) {
            int32_t id = (int32_t)be32(cell + 4 + 4 * j);
            if (id < 0) {
                found_bad(job, worker, c);
                return;
            }
            most = id > most ? id : most;
            dst[j] = id;
        }
        job->offsets[c + 1] = job->base + (c + 1) * each;
    }
    job->most[worker] = most > job->most[worker] ? most : job->most[worker];
}

/* Old CELLS form, offsets known: each cell's ids (after its count) copied and checked to be >= 0. */
static void list_ids_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    block_job *job = ctx;
    for (int64_t c = begin; c < end; c++) {
        const unsigned char *ids = job->p + 4 * (size_t)(job->offsets[c] + c + 1);
        int32_t *dst = job->conn + job->offsets[c];
        int64_t count = job->offsets[c + 1] - job->offsets[c];
        for (int64_t j = 0; j < count; j++) {
            int32_t id = (int32_t)be32(ids + 4 * j);
            if (id < 0) {
                found_bad(job, worker, c);
                return;
            }
            dst[j] = id;
        }
    }
}

/* CONNECTIVITY (5.1 form): entries converted and checked to lie in [0, INT32_MAX]. */
static void connectivity_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    block_job *job = ctx;
    const unsigned char *p = job->p;
    int64_t most = -1;
    for (int64_t k = begin; k < end; k++) {
        int64_t id = job->type == VT_I64 ? (int64_t)be64(p + 8 * k)
                     : job->type == VT_I32 ? (int32_t)be32(p + 4 * k)
                                           : (int64_t)be_real(p, job->type, (uint64_t)k);
        if (id < 0 || id > INT32_MAX) {
            found_bad(job, worker, k);
            return;
        }
        most = id > most ? id : most;
        job->conn[k] = (int32_t)id;
    }
    job->most[worker] = most > job->most[worker] ? most : job->most[worker];
}

/* OFFSETS: nondecreasing and at most the CELLS size (job->limit); most 1 where a cell has other than
 * job->each ids. */
static void offsets_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    block_job *job = ctx;
    int64_t uneven = 0;
    for (int64_t c = begin; c < end; c++) {
        if (job->offsets[c + 1] < job->offsets[c] || job->offsets[c + 1] > job->limit) {
            found_bad(job, worker, c);
            return;
        }
        uneven |= job->offsets[c + 1] - job->offsets[c] != job->each;
    }
    job->most[worker] = uneven > job->most[worker] ? uneven : job->most[worker];
}

/* CELL_TYPES: each in [0, 255], kept as a byte. */
static void types_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    block_job *job = ctx;
    int64_t lo = 255, hi = 0;
    for (int64_t c = begin; c < end; c++) {
        if (job->values[c] < 0 || job->values[c] > 255) {
            found_bad(job, worker, c);
            return;
        }
        job->types[c] = (uint8_t)job->values[c];
        lo = job->values[c] < lo ? job->values[c] : lo;
        hi = job->values[c] > hi ? job->values[c] : hi;
    }
    job->least[worker] = lo < job->least[worker] ? lo : job->least[worker];
    job->most[worker] = hi > job->most[worker] ? hi : job->most[worker];
}

/* CELL_TYPES in a BINARY file: big-endian int32, each in [0, 255]. */
static void binary_types_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    block_job *job = ctx;
    int32_t lo = 255, hi = 0;
    for (int64_t c = begin; c < end; c++) {
        int32_t type = (int32_t)be32(job->p + 4 * c);
        if (type < 0 || type > 255) {
            found_bad(job, worker, c);
            return;
        }
        job->types[c] = (uint8_t)type;
        lo = type < lo ? type : lo;
        hi = type > hi ? type : hi;
    }
    job->least[worker] = lo < job->least[worker] ? lo : job->least[worker];
    job->most[worker] = hi > job->most[worker] ? hi : job->most[worker];
}

/* ---- POINTS, CELLS, CELL_TYPES ------------------------------------------------------------------ */

int vtk_read_points(vtk_reader *r)
{
    int64_t n;
    vtk_type type;
    if (r->point_count >= 0)
        return vtk_fail_kw(r, "expected one POINTS section, found a second");
    if (vtk_arg_count(r, "POINTS", "a point count", &n) || vtk_arg_type(r, "POINTS", &type) ||
        tpk_scan_end_line(&r->s, "POINTS n type"))
        return -1;
    if ((uint64_t)n > UINT64_MAX / 3)
        return vtk_fail_kw(r, "POINTS %lld: too many points for any file", (long long)n);
    if (vtk_check_room(r, type, 3 * (uint64_t)n, "POINTS"))
        return -1;
    if (n > INT32_MAX)
        return vtk_fail_kw(r, "POINTS %lld: more than 2^31-1 points (the format's limit; split the mesh)",
                           (long long)n);
    r->points = malloc(sizeof(double) * 3 * (size_t)(n ? n : 1));
    if (!r->points)
        return vtk_fail_kw(r, "POINTS %lld: out of memory", (long long)n);
    r->point_count = n;
    return vtk_read_reals(r, type, 3 * (uint64_t)n, r->points, NULL, "POINTS");
}

static int id_range_error(vtk_reader *r, int64_t cell, int64_t id)
{
    return tpk_scan_fail_at(&r->s, r->cells_pos, r->cells_line,
                            "CELLS: cell %lld uses point id %lld, expected 0 <= id < 2^31-1", (long long)cell,
                            (long long)id);
}

/* The old form's fast path (every cell has job->each points) in slabs of cells, each read on all threads
 * and then its pages of the mapped input let go: the whole input is mapped and read ahead, so without
 * that the CELLS block (most of a big file) and the arrays made from it would be in memory together, the
 * converter's peak on grid 120. 1 when every cell was read (r->s after the block), 0 when a cell is not
 * what the fast path takes (r->s as it was; its pages are read again from the file). */
static int uniform_lists(vtk_reader *r, block_job *job, int64_t n)
{
    size_t start = r->s.pos, cell_bytes = 4 * (size_t)(job->each + 1);
    /* 1/16 of the block, at least 2 MiB (tests/cli/deterministic.sh's grid 30 in 2): few starts of the
     * threads, and pages let go early enough (the most is kept at the start, where the arrays are empty) */
    int64_t slab = n / 16 > (int64_t)((2u << 20) / cell_bytes) ? n / 16 + 1 : (int64_t)((2u << 20) / cell_bytes) + 1;
    int64_t most = -1;
    for (int64_t c = 0; c < n; c += slab) {
        int64_t count = n - c < slab ? n - c : slab;
        block_job part = *job;
        part.p = job->p + cell_bytes * (size_t)c;
        part.offsets = job->offsets + c;
        part.conn = job->conn + c * job->each;
        part.base = c * job->each;
        if (run_block_job(&part, count, uniform_lists_range) != INT64_MAX) {
            r->s.pos = start;
            return 0;
        }
        most = part.most_all > most ? part.most_all : most;
        r->s.pos = start + cell_bytes * (size_t)(c + count);
        tpk_scan_release_consumed(&r->s);
    }
    r->each_size = job->each;
    r->max_id = most;
    return 1;
}

/* Old form in ASCII, fast path: all `size` numbers read on all threads (each in [0, 2^31-1]), then the
 * counts walked and the ids copied. 0 when read (r->offsets and r->conn filled, the position after the
 * block), 1 with nothing read when any number or count is not what the serial reader accepts: it then
 * reads the block again for its message. */
static int ascii_cell_lists(vtk_reader *r, int64_t n, int64_t size)
{
    if (size < 65536)
        return 1;
    int32_t *numbers = malloc(sizeof *numbers * (size_t)size);
    tpk_scan saved = r->s;
    if (!numbers || tpk_scan_numbers(&r->s, (uint64_t)size, TPK_NUMBER_ID32, numbers, 0) != 0) {
        free(numbers);
        return 1;
    }
    int64_t used = 0, k = 0;
    for (int64_t c = 0; c < n; c++) {
        int64_t count = used < size ? numbers[used] : -1;
        if (count < 0 || count > size - used - 1 - (n - c - 1)) {
            free(numbers);
            r->s = saved;
            return 1;
        }
        memcpy(r->conn + k, numbers + used + 1, sizeof *numbers * (size_t)count);
        used += 1 + count;
        k += count;
        r->offsets[c + 1] = k;
    }
    free(numbers);
    if (used != size) {
        r->s = saved;
        return 1;
    }
    return 0;
}

/* Old form: per cell a count then that many ids; `size` numbers in all. */
static int read_cell_lists(vtk_reader *r, int64_t n, int64_t size)
{
    if (size < n)
        return vtk_fail_kw(r, "CELLS %lld %lld: the size must count every cell's point count too (at least %lld)",
                           (long long)n, (long long)size, (long long)n);
    if (vtk_check_room(r, VT_I32, (uint64_t)size, "CELLS"))
        return -1;
    r->offsets = malloc(sizeof(int64_t) * (size_t)(n + 1));
    r->conn = malloc(sizeof(int32_t) * (size_t)(size - n > 0 ? size - n : 1));
    if (!r->offsets || !r->conn)
        return vtk_fail_kw(r, "CELLS %lld %lld: out of memory", (long long)n, (long long)size);
    r->cell_count = n;
    int64_t used = 0, k = 0;
    r->offsets[0] = 0;
    if (r->binary) {
        /* The cell starts follow from the counts, one after the other, unless every cell has the first
         * cell's count (a mesh of one cell type), which all threads check at once as they copy the ids.
         * Otherwise (or where that pass finds a bad count or id) the counts are walked on one thread and
         * the ids copied and checked on all; a bad count is reported after any bad id of an earlier
         * cell, as the serial reader found them. */
        const unsigned char *p = r->s.data + r->s.pos;
        block_job job = {.p = p, .offsets = r->offsets, .conn = r->conn};
        int64_t known = n; /* cells whose counts are good */
        job.each = n > 0 ? (int32_t)be32(p) : -1;
        if (n > 0 && job.each >= 0 && size % n == 0 && size / n - 1 == job.each && uniform_lists(r, &job, n)) {
            return 0;
        } else {
            for (int64_t c = 0; c < n; c++) {
                int64_t count = used < size ? (int32_t)be32(p + 4 * used) : -1;
                if (count < 0 || count > size - used - 1 - (n - c - 1)) {
                    known = c;
                    break;
                }
                used += 1 + count;
                k += count;
                r->offsets[c + 1] = k;
            }
        }
        int64_t bad = known > 0 ? run_block_job(&job, known, list_ids_range) : INT64_MAX;
        if (bad != INT64_MAX) {
            const unsigned char *ids = p + 4 * (size_t)(r->offsets[bad] + bad + 1);
            for (int64_t j = 0; j < r->offsets[bad + 1] - r->offsets[bad]; j++)
                if ((int32_t)be32(ids + 4 * j) < 0)
                    return id_range_error(r, bad, (int32_t)be32(ids + 4 * j));
        }
        if (known < n) {
            int64_t c = known;
            if (used >= size)
                return vtk_fail_kw(r, "CELLS %lld %lld: the size is used up after %lld of %lld cells", (long long)n,
                                   (long long)size, (long long)c, (long long)n);
            int64_t count = (int32_t)be32(p + 4 * used);
            return tpk_scan_fail_at(&r->s, r->s.pos + 4 * (size_t)used, 0,
                                    "CELLS: cell %lld has point count %lld, but the CELLS size %lld "
                                    "leaves room for at most %lld", (long long)c, (long long)count,
                                    (long long)size, (long long)(size - used - 1 - (n - c - 1)));
        }
        r->s.pos += 4 * (size_t)size;
    } else if (ascii_cell_lists(r, n, size) == 0) {
        return 0;
    } else {
        for (int64_t c = 0; c < n; c++) {
            int64_t count;
            if (used >= size)
                return vtk_fail_kw(r, "CELLS %lld %lld: the size is used up after %lld of %lld cells", (long long)n,
                                   (long long)size, (long long)c, (long long)n);
            if (tpk_scan_int64(&r->s, &count, "a cell's point count"))
                return -1;
            if (count < 0 || count > size - used - 1 - (n - c - 1))
                return tpk_scan_fail(&r->s, "CELLS: cell %lld has point count %lld, but the CELLS size %lld "
                                     "leaves room for at most %lld", (long long)c, (long long)count,
                                     (long long)size, (long long)(size - used - 1 - (n - c - 1)));
            used++;
            for (int64_t j = 0; j < count; j++, used++) {
                int64_t id;
                if (tpk_scan_int64(&r->s, &id, "a point id"))
                    return -1;
                if (id < 0 || id > INT32_MAX)
                    return tpk_scan_fail(&r->s, "CELLS: cell %lld uses point id %lld, expected 0 <= id < 2^31-1",
                                         (long long)c, (long long)id);
                r->conn[k++] = (int32_t)id;
            }
            r->offsets[c + 1] = k;
        }
    }
    if (used != size)
        return vtk_fail_kw(r, "CELLS %lld %lld: the %lld cells hold %lld numbers, expected %lld", (long long)n,
                           (long long)size, (long long)n, (long long)used, (long long)size);
    return 0;
}

/* VTK 5.1 form: CELLS n+1 m, then OFFSETS type (n+1 values) and CONNECTIVITY type (m values). */
static int read_offsets_connectivity(vtk_reader *r, int64_t n_offsets, int64_t m)
{
    vtk_type type;
    if (n_offsets < 1)
        return vtk_fail_kw(r, "CELLS %lld %lld: expected at least one offset", (long long)n_offsets, (long long)m);
    if (vtk_arg_type(r, "OFFSETS", &type) || tpk_scan_end_line(&r->s, "OFFSETS type") ||
        vtk_check_room(r, type, (uint64_t)n_offsets, "OFFSETS"))
        return -1;
    int64_t n = n_offsets - 1;
    if (n > INT32_MAX)
        return vtk_fail_kw(r, "CELLS: %lld cells, more than 2^31-1", (long long)n);
    r->offsets = malloc(sizeof(int64_t) * (size_t)n_offsets);
    if (!r->offsets)
        return vtk_fail_kw(r, "OFFSETS: out of memory");
    r->cell_count = n;
    size_t offsets_pos = r->s.pos;
    int64_t offsets_line = r->s.line;
    if (vtk_read_ints(r, type, (uint64_t)n_offsets, r->offsets, "OFFSETS"))
        return -1;
    if (r->offsets[0] != 0)
        return tpk_scan_fail_at(&r->s, offsets_pos, offsets_line, "OFFSETS: expected the first offset 0, found %lld",
                                (long long)r->offsets[0]);
    block_job job = {.offsets = r->offsets, .limit = m, .each = n > 0 ? r->offsets[1] - r->offsets[0] : 0};
    int64_t bad = run_block_job(&job, n, offsets_range);
    int even = n > 0 && job.most_all <= 0; /* every cell has job.each ids */
    for (int64_t c = bad; c < n; c++)
        if (r->offsets[c + 1] < r->offsets[c] || r->offsets[c + 1] > m)
            return tpk_scan_fail_at(&r->s, offsets_pos, offsets_line,
                                    "OFFSETS: cell %lld ends at %lld, expected a value between %lld and %lld",
                                    (long long)c, (long long)r->offsets[c + 1], (long long)r->offsets[c], (long long)m);
    if (r->offsets[n] != m)
        return tpk_scan_fail_at(&r->s, offsets_pos, offsets_line,
                                "OFFSETS: expected the last offset to equal the CELLS size %lld, found %lld",
                                (long long)m, (long long)r->offsets[n]);
    const char *tok;
    size_t len = tpk_scan_token(&r->s, &tok);
    r->kw_pos = r->s.tok_pos;
    r->kw_line = r->s.tok_line;
    if (!tpk_token_is(tok, len, "CONNECTIVITY")) {
        char q[64];
        return tpk_scan_fail(&r->s, "expected 'CONNECTIVITY type' after the OFFSETS block, found '%s'",
                             len ? vtk_quote(tok, len, q, sizeof q) : "end of file");
    }
    if (vtk_arg_type(r, "CONNECTIVITY", &type) || tpk_scan_end_line(&r->s, "CONNECTIVITY type"))
        return -1;
    if (!vtk_is_integer_type(type))
        return vtk_fail_kw(r, "CONNECTIVITY: expected an integer data type, found a floating-point one");
    if (vtk_check_room(r, type, (uint64_t)m, "CONNECTIVITY"))
        return -1;
    r->conn = malloc(sizeof(int32_t) * (size_t)(m ? m : 1));
    if (!r->conn)
        return vtk_fail_kw(r, "CONNECTIVITY: out of memory");
    if (r->binary) {
        const unsigned char *p = r->s.data + r->s.pos;
        block_job cj = {.p = p, .type = type, .conn = r->conn};
        int64_t k = run_block_job(&cj, m, connectivity_range);
        if (k != INT64_MAX)
            return id_range_error(r, cell_of_entry(r->offsets, n, k),
                                  type == VT_I64 ? (int64_t)be64(p + 8 * k)
                                  : type == VT_I32 ? (int32_t)be32(p + 4 * k)
                                                   : (int64_t)be_real(p, type, (uint64_t)k));
        if (even) {
            r->each_size = job.each;
            r->max_id = cj.most_all;
        }
        r->s.pos += vtk_bytes_for(type, (uint64_t)m);
        return 0;
    }
    if (tpk_scan_numbers(&r->s, (uint64_t)m, TPK_NUMBER_ID32, r->conn, 0) == 0)
        return 0;
    for (int64_t k = 0; k < m; k++) {
        int64_t id;
        const char *t;
        size_t tl = tpk_scan_token(&r->s, &t);
        if (!tl || tpk_parse_int64(t, tl, &id) != 0) {
            char q[64];
            if (!tl)
                return vtk_ascii_value_error(r, t, tl, "CONNECTIVITY", (uint64_t)k, (uint64_t)m);
            return tpk_scan_fail(&r->s, "CONNECTIVITY: expected a point id (value %lld of %lld), found '%s'",
                                 (long long)k + 1, (long long)m, vtk_quote(t, tl, q, sizeof q));
        }
        if (id < 0 || id > INT32_MAX)
            return tpk_scan_fail(&r->s, "CONNECTIVITY: cell %lld uses point id %lld, expected 0 <= id < 2^31-1",
                                 (long long)cell_of_entry(r->offsets, n, k), (long long)id);
        r->conn[k] = (int32_t)id;
    }
    return 0;
}

int vtk_read_cells(vtk_reader *r)
{
    int64_t n, size;
    if (r->cell_count >= 0)
        return vtk_fail_kw(r, "expected one CELLS section, found a second");
    r->cells_pos = r->kw_pos;
    r->cells_line = r->kw_line;
    if (vtk_arg_count(r, "CELLS", "a cell count", &n) || vtk_arg_count(r, "CELLS", "the CELLS size", &size) ||
        tpk_scan_end_line(&r->s, "CELLS n size"))
        return -1;
    if (vtk_next_is(r, "OFFSETS")) {
        r->kw_pos = r->s.tok_pos;
        r->kw_line = r->s.tok_line;
        r->offsets_form = 1;
        return read_offsets_connectivity(r, n, size);
    }
    if (n > INT32_MAX)
        return vtk_fail_kw(r, "CELLS %lld: more than 2^31-1 cells", (long long)n);
    return read_cell_lists(r, n, size);
}

int vtk_read_cell_types(vtk_reader *r)
{
    int64_t n;
    if (r->type_count >= 0)
        return vtk_fail_kw(r, "expected one CELL_TYPES section, found a second");
    r->types_pos = r->kw_pos;
    r->types_line = r->kw_line;
    if (vtk_arg_count(r, "CELL_TYPES", "a cell count", &n) || tpk_scan_end_line(&r->s, "CELL_TYPES n"))
        return -1;
    if (r->cell_count < 0)
        return vtk_fail_kw(r, "expected CELLS before CELL_TYPES");
    if (n != r->cell_count)
        return vtk_fail_kw(r, "CELL_TYPES %lld: expected one type per cell (CELLS has %lld cells)", (long long)n,
                           (long long)r->cell_count);
    if (vtk_check_room(r, VT_I32, (uint64_t)n, "CELL_TYPES"))
        return -1;
    r->types = malloc((size_t)(n ? n : 1));
    if (!r->types)
        return vtk_fail_kw(r, "CELL_TYPES: out of memory");
    r->type_count = n;
    if (r->binary) { /* straight from the file's big-endian int32, no int64 copy */
        block_job job = {.p = r->s.data + r->s.pos, .types = r->types};
        int64_t bad = run_block_job(&job, n, binary_types_range);
        if (bad != INT64_MAX)
            return vtk_fail_kw(r, "CELL_TYPES: cell %lld has unsupported cell type %lld", (long long)bad,
                               (long long)(int32_t)be32(job.p + 4 * bad));
        if (n > 0) {
            r->type_lo = (int)job.least_all;
            r->type_hi = (int)job.most_all;
        }
        r->s.pos += 4 * (size_t)n;
        return 0;
    }
    int64_t *values = malloc(sizeof(int64_t) * (size_t)(n ? n : 1));
    if (!values)
        return vtk_fail_kw(r, "CELL_TYPES: out of memory");
    int rc = vtk_read_ints(r, VT_I32, (uint64_t)n, values, "CELL_TYPES");
    block_job job = {.types = r->types, .values = values};
    int64_t bad = rc == 0 ? run_block_job(&job, n, types_range) : n;
    if (rc == 0 && bad == INT64_MAX && n > 0) {
        r->type_lo = (int)job.least_all;
        r->type_hi = (int)job.most_all;
    }
    for (int64_t c = bad; rc == 0 && c < n; c++) {
        if (values[c] < 0 || values[c] > 255)
            rc = vtk_fail_kw(r, "CELL_TYPES: cell %lld has unsupported cell type %lld", (long long)c,
                             (long long)values[c]);
        else
            r->types[c] = (uint8_t)values[c];
    }
    free(values);
    return rc;
}
