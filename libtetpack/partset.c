/* Part sets (format 1.2, spec §15): the manifest's PART table, the part files it names (all, or those
 * meeting a box), each checked against its record, and each part's LINK chunk. */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal_file.h"

typedef struct set_part {
    tpk_part_record record;
    tpk_file *file;     /* NULL: outside the box */
    tpk_link *links;    /* decoded on first use */
    uint64_t link_count;
    int links_read;
} set_part;

struct tpk_partset {
    uint32_t part_count;
    set_part *parts;
    double origin[3];
};

/* §15.2: a plain file name beside the manifest: 1-127 bytes then NULs, no separator, not . or .. */
static int valid_part_name(const tpk_part_record *r)
{
    size_t n = strnlen(r->file, sizeof r->file);
    if (n == 0 || n == sizeof r->file)
        return 0;
    for (size_t k = n; k < sizeof r->file; k++)
        if (r->file[k] != 0)
            return 0;
    if (strchr(r->file, '/') || strchr(r->file, '\\') || !strcmp(r->file, ".") || !strcmp(r->file, ".."))
        return 0;
    for (size_t k = 0; k < sizeof r->reserved; k++)
        if (r->reserved[k])
            return 0;
    return 1;
}

static int meets_box(const tpk_part_record *r, const double *lo, const double *hi)
{
    if (!lo || !hi)
        return 1;
    for (int k = 0; k < 3; k++)
        if (r->bounds_max[k] < lo[k] || r->bounds_min[k] > hi[k])
            return 0;
    return 1;
}

/* The part must be the file its record describes (§15.2). */
static tpk_result check_part(const tpk_partset *set, uint32_t i, const char *path, char *err, size_t cap)
{
    const tpk_part_record *r = &set->parts[i].record;
    const tpk_header *h = &set->parts[i].file->header;
    const char *what = NULL;
    if (h->file_size != r->file_size)
        what = "file_size";
    else if (h->header_checksum != r->header_checksum)
        what = "header_checksum";
    else if (h->vertex_count != r->vertex_count || h->tet_count != r->tet_count ||
             h->shell_face_count != r->shell_face_count)
        what = "counts";
    else if (memcmp(h->bounds_min, r->bounds_min, sizeof h->bounds_min) ||
             memcmp(h->bounds_max, r->bounds_max, sizeof h->bounds_max))
        what = "bounds";
    else if (memcmp(h->origin, set->origin, sizeof h->origin))
        what = "origin (the manifest's)";
    if (what)
        return tpki_text_fail(err, cap, TPK_ERR_CORRUPT, "%s: part %" PRIu32 " ('%s') does not match its record in the "
                        "manifest: %s differ (spec §15.2)", path, i, r->file, what);
    return TPK_OK;
}

static tpk_result read_table(tpk_partset *set, tpk_file *manifest, const char *path, char *err, size_t cap)
{
    uint64_t i;
    if (tpk_find_chunk(manifest, TPK_TAG_PART, 0, 0, &i) != TPK_OK)
        return tpki_text_fail(err, cap, TPK_ERR_NOT_FOUND, "%s: a .tpk file but not a part set (no 'PART' chunk)", path);
    const tpk_dir_entry *e = &manifest->entries[i];
    uint64_t n = e->elem_count / sizeof(tpk_part_record);
    if (n == 0 || n > TPK_MAX_ID)
        return tpki_text_fail(err, cap, TPK_ERR_CORRUPT, "%s: 'PART' lists %" PRIu64 " parts; expected 1 to 2^31-1",
                        path, n);
    if (manifest->header.vertex_count || manifest->header.tet_count || manifest->header.shell_face_count)
        return tpki_text_fail(err, cap, TPK_ERR_CORRUPT, "%s: a manifest holds no mesh of its own; found %" PRIu64
                        " vertices and %" PRIu64 " tets", path, manifest->header.vertex_count,
                        manifest->header.tet_count);
    set->parts = calloc((size_t)n, sizeof *set->parts);
    tpk_part_record *records = malloc((size_t)e->raw_size);
    if (!set->parts || !records) {
        free(records);
        return tpki_text_fail(err, cap, TPK_ERR_OUT_OF_MEMORY, "%s: out of memory for %" PRIu64 " parts", path, n);
    }
    set->part_count = (uint32_t)n;
    tpk_result r = tpk_read_chunk(manifest, i, records, e->raw_size);
    if (r != TPK_OK) {
        free(records);
        return tpki_text_fail(err, cap, r, "%s", tpk_error_text(manifest));
    }
    for (uint32_t p = 0; p < set->part_count; p++) {
        set->parts[p].record = records[p];
        if (!valid_part_name(&records[p])) {
            free(records);
            return tpki_text_fail(err, cap, TPK_ERR_CORRUPT, "%s: part %" PRIu32 ": the file name is not a plain name of "
                            "1 to 127 bytes followed by NULs, or the reserved bytes are not 0 (spec §15.2)", path, p);
        }
    }
    free(records);
    return TPK_OK;
}

static tpk_result open_parts(tpk_partset *set, const char *path, const tpk_open_options *options,
                             const double *lo, const double *hi, char *err, size_t cap)
{
    const char *slash = strrchr(path, '/');
    size_t dir_length = slash ? (size_t)(slash - path + 1) : 0;
    for (uint32_t p = 0; p < set->part_count; p++) {
        if (!meets_box(&set->parts[p].record, lo, hi))
            continue;
        size_t need = dir_length + sizeof set->parts[p].record.file + 1;
        char *part_path = malloc(need);
        if (!part_path)
            return tpki_text_fail(err, cap, TPK_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
        snprintf(part_path, need, "%.*s%s", (int)dir_length, path, set->parts[p].record.file);
        char part_err[TPK_ERROR_TEXT_SIZE] = "";
        tpk_result r = tpk_open_path(&set->parts[p].file, part_path, options, part_err, sizeof part_err);
        if (r != TPK_OK)
            tpki_text_fail(err, cap, r, "%s: part %" PRIu32 ": %s", path, p, part_err);
        else
            r = check_part(set, p, path, err, cap);
        free(part_path);
        if (r != TPK_OK)
            return r;
    }
    return TPK_OK;
}

tpk_result tpk_partset_open(tpk_partset **out, const char *path, const tpk_open_options *options,
                            const double *box_min, const double *box_max, char *err, size_t cap)
{
    if (err && cap)
        err[0] = 0;
    if (!out)
        return TPK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (!path)
        return TPK_ERR_INVALID_ARGUMENT;
    tpk_file *manifest = NULL;
    tpk_result r = tpk_open_path(&manifest, path, options, err, cap);
    if (r != TPK_OK)
        return r;
    tpk_partset *set = calloc(1, sizeof *set);
    if (!set) {
        tpk_close(manifest);
        return tpki_text_fail(err, cap, TPK_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    memcpy(set->origin, manifest->header.origin, sizeof set->origin);
    r = read_table(set, manifest, path, err, cap);
    tpk_close(manifest);
    if (r == TPK_OK)
        r = open_parts(set, path, options, box_min, box_max, err, cap);
    if (r != TPK_OK) {
        tpk_partset_close(set);
        return r;
    }
    *out = set;
    return TPK_OK;
}

void tpk_partset_close(tpk_partset *set)
{
    if (!set)
        return;
    for (uint32_t p = 0; p < set->part_count; p++) {
        tpk_close(set->parts[p].file);
        free(set->parts[p].links);
    }
    free(set->parts);
    free(set);
}

uint32_t tpk_partset_part_count(const tpk_partset *set)
{
    return set ? set->part_count : 0;
}

tpk_result tpk_partset_get_part(const tpk_partset *set, uint32_t i, tpk_part_record *out)
{
    if (!set || !out || i >= set->part_count)
        return TPK_ERR_INVALID_ARGUMENT;
    *out = set->parts[i].record;
    return TPK_OK;
}

tpk_file *tpk_partset_file(const tpk_partset *set, uint32_t i)
{
    return set && i < set->part_count ? set->parts[i].file : NULL;
}

void tpk_partset_origin(const tpk_partset *set, double out[3])
{
    memcpy(out, set->origin, sizeof set->origin);
}

/* Links name parts of this set, and faces and tets within the counts the manifest gives them. */
static tpk_result check_links(const tpk_partset *set, uint32_t i, const tpk_link *links, uint64_t n)
{
    for (uint64_t l = 0; l < n; l++) {
        const tpk_link *k = &links[l];
        if ((uint32_t)k->part >= set->part_count || (uint32_t)k->part == i)
            return tpki_file_fail(set->parts[i].file, TPK_ERR_CORRUPT,
                                  "'LINK' record %" PRIu64 ": part %d is not another part of the set (%" PRIu32
                                  " parts)", l, k->part, set->part_count);
        const tpk_part_record *other = &set->parts[k->part].record;
        if ((uint64_t)k->other_face >= other->shell_face_count || (uint64_t)k->other_tet >= other->tet_count)
            return tpki_file_fail(set->parts[i].file, TPK_ERR_CORRUPT,
                                  "'LINK' record %" PRIu64 ": face %d or tet %d is outside part %d (%" PRIu64
                                  " shell faces, %" PRIu64 " tets)", l, k->other_face, k->other_tet, k->part,
                                  other->shell_face_count, other->tet_count);
    }
    return TPK_OK;
}

tpk_result tpk_partset_links(tpk_partset *set, uint32_t i, const tpk_link **out, uint64_t *out_count)
{
    if (!set || !out || !out_count || i >= set->part_count || !set->parts[i].file)
        return TPK_ERR_INVALID_ARGUMENT;
    set_part *part = &set->parts[i];
    if (!part->links_read) {
        uint64_t c;
        if (tpk_find_chunk(part->file, TPK_TAG_LINK, 0, 0, &c) == TPK_OK) {
            const tpk_dir_entry *e = &part->file->entries[c];
            part->links = malloc(e->raw_size ? (size_t)e->raw_size : 1);
            if (!part->links)
                return TPK_ERR_OUT_OF_MEMORY;
            tpk_result r = tpk_read_chunk(part->file, c, part->links, e->raw_size);
            if (r == TPK_OK)
                r = check_links(set, i, part->links, e->elem_count / 4);
            if (r != TPK_OK) {
                free(part->links);
                part->links = NULL;
                return r;
            }
            part->link_count = e->elem_count / 4;
        }
        part->links_read = 1;
    }
    *out = part->links;
    *out_count = part->link_count;
    return TPK_OK;
}
