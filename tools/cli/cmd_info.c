/* tetpack info: header, chunks, fields, sizes and checksum status of a .tpk. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "base/strbuf.h"
#include "tetpack.h"

static const char info_help[] =
    "usage: tetpack info FILE.tpk [--json]\n"
    "\n"
    "Opens FILE (checking header, directory, offsets, sizes and alignment), checks every chunk's\n"
    "checksum and the counts and ids, and prints the counts, bounds, origin, layouts, fields with\n"
    "their time steps, and every chunk with its codec and sizes. Exit 0 when the file is sound,\n"
    "2 when it cannot be used (the message says which rule failed, where).\n"
    "On a part set's manifest (.tpkset, spec §15) it opens every part, checks it against the manifest\n"
    "and its links, and prints the totals, the outer shell (faces on no cut) apart from the cut faces,\n"
    "and the parts (with --json: part_set, part_count, tets, vertex_records, shell_faces (outer),\n"
    "cut_faces, file_bytes, bounds and parts [{file, vertices, tets, shell_faces, outer_faces,\n"
    "cut_faces, file_bytes, bounds}]).\n"
    "Levels of detail (spec §16) are listed after the chunks, each opened and checked like a file.\n"
    "\n"
    "  --json   one JSON object: format_version, vertices, tets, shell_faces, layouts, fields\n"
    "           [{name, association, steps, units, min, max}], times, bounds {min, max}, origin,\n"
    "           levels [{level, vertices, tets, shell_faces, file_bytes, ok}],\n"
    "           chunks [{tag, codec, required, index, step, elements, offset, stored_bytes, raw_bytes}],\n"
    "           file_bytes, checksums_ok, metadata (the META chunk's JSON object, or null)\n";

static void tag_text(uint32_t tag, char out[5])
{
    for (int i = 0; i < 4; i++) {
        char c = (char)((tag >> (8 * i)) & 0xff);
        out[i] = (c >= 32 && c < 127) ? c : '?';
    }
    out[4] = 0;
}

static const char *layout_name(uint32_t tag)
{
    return tag == TPK_TAG_TT16 ? "tet16" : tag == TPK_TAG_TT20 ? "tet20" : tag == TPK_TAG_TT32 ? "tet32" : NULL;
}

/* The META chunk's bytes, NUL-terminated, or NULL. Caller frees. */
static char *read_meta(tpk_file *file)
{
    uint64_t i;
    tpk_dir_entry e;
    if (tpk_find_chunk(file, TPK_TAG_META, 0, 0, &i) != TPK_OK || tpk_get_chunk(file, i, &e) != TPK_OK ||
        e.raw_size > (1u << 24))
        return NULL;
    char *text = malloc(e.raw_size + 1);
    if (!text || tpk_read_chunk(file, i, text, e.raw_size) != TPK_OK) {
        free(text);
        return NULL;
    }
    text[e.raw_size] = 0;
    return text;
}

static void json_vec3(tpk_strbuf *sb, const double v[3])
{
    tpk_strbuf_printf(sb, "[");
    for (int k = 0; k < 3; k++) {
        if (k)
            tpk_strbuf_printf(sb, ",");
        tpk_strbuf_json_number(sb, v[k]);
    }
    tpk_strbuf_printf(sb, "]");
}

static void json_fields(tpk_strbuf *sb, tpk_file *file)
{
    tpk_strbuf_printf(sb, ",\"fields\":[");
    for (uint32_t i = 0; i < tpk_field_count(file); i++) {
        tpk_field_desc d = {0};
        tpk_get_field(file, i, &d);
        tpk_strbuf_printf(sb, "%s{\"name\":", i ? "," : "");
        tpk_strbuf_json_string(sb, d.name);
        tpk_strbuf_printf(sb, ",\"association\":\"%s\",\"steps\":%u,\"units\":",
                          d.association == TPK_ASSOC_POINT ? "point" : "tet", d.step_count);
        tpk_strbuf_json_string(sb, d.units);
        tpk_strbuf_printf(sb, ",\"min\":");
        tpk_strbuf_json_number(sb, d.min_value);
        tpk_strbuf_printf(sb, ",\"max\":");
        tpk_strbuf_json_number(sb, d.max_value);
        tpk_strbuf_printf(sb, "}");
    }
    tpk_strbuf_printf(sb, "],\"times\":[");
    double t;
    for (uint32_t s = 0; tpk_get_time(file, s, &t) == TPK_OK; s++) {
        if (s)
            tpk_strbuf_printf(sb, ",");
        tpk_strbuf_json_number(sb, t);
    }
    tpk_strbuf_printf(sb, "]");
}

static void json_chunks(tpk_strbuf *sb, tpk_file *file, const tpk_file_info *info)
{
    tpk_strbuf_printf(sb, ",\"layouts\":[");
    int first = 1;
    for (uint64_t i = 0; i < info->chunk_count; i++) {
        tpk_dir_entry e = {0};
        tpk_get_chunk(file, i, &e);
        if (layout_name(e.tag)) {
            tpk_strbuf_printf(sb, "%s\"%s\"", first ? "" : ",", layout_name(e.tag));
            first = 0;
        }
    }
    tpk_strbuf_printf(sb, "],\"chunks\":[");
    for (uint64_t i = 0; i < info->chunk_count; i++) {
        tpk_dir_entry e = {0};
        char tag[5];
        tpk_get_chunk(file, i, &e);
        tag_text(e.tag, tag);
        tpk_strbuf_printf(sb, "%s{\"tag\":", i ? "," : "");
        tpk_strbuf_json_string(sb, tag);
        tpk_strbuf_printf(sb,
                          ",\"codec\":\"%s\",\"required\":%s,\"index\":%u,\"step\":%u,\"elements\":%llu,"
                          "\"offset\":%llu,\"stored_bytes\":%llu,\"raw_bytes\":%llu}",
                          e.codec == TPK_CODEC_ZSTD ? "zstd" : "none",
                          (e.flags & TPK_CHUNK_REQUIRED) ? "true" : "false", e.index, e.step,
                          (unsigned long long)e.elem_count, (unsigned long long)e.offset,
                          (unsigned long long)e.stored_size, (unsigned long long)e.raw_size);
    }
    tpk_strbuf_printf(sb, "]");
}

/* Level k's counts (0 when it does not open) and whether its chunks verify. */
static tpk_result level_info(tpk_file *file, uint32_t k, tpk_file_info *out, char *err, size_t cap)
{
    tpk_file *lf = NULL;
    memset(out, 0, sizeof *out);
    tpk_result r = tpk_open_level(file, k, NULL, &lf, err, cap);
    if (r == TPK_OK) {
        tpk_get_info(lf, out);
        r = tpk_verify(lf);
        if (r != TPK_OK)
            snprintf(err, cap, "level %u: %s", k, tpk_error_text(lf));
        tpk_close(lf);
    }
    return r;
}

static void json_levels(tpk_strbuf *sb, tpk_file *file)
{
    tpk_strbuf_printf(sb, ",\"levels\":[");
    for (uint32_t k = 1; k <= tpk_level_count(file); k++) {
        tpk_file_info li;
        char err[512] = "";
        tpk_result r = level_info(file, k, &li, err, sizeof err);
        tpk_strbuf_printf(sb, "%s{\"level\":%u,\"vertices\":%llu,\"tets\":%llu,\"shell_faces\":%llu,"
                          "\"file_bytes\":%llu,\"ok\":%s", k > 1 ? "," : "", k, (unsigned long long)li.vertex_count,
                          (unsigned long long)li.tet_count, (unsigned long long)li.shell_face_count,
                          (unsigned long long)li.file_size, r == TPK_OK ? "true" : "false");
        if (r != TPK_OK) {
            tpk_strbuf_printf(sb, ",\"error\":");
            tpk_strbuf_json_string(sb, err);
        }
        tpk_strbuf_printf(sb, "}");
    }
    tpk_strbuf_printf(sb, "]");
}

static int print_json(tpk_file *file, const tpk_file_info *info, tpk_result verified)
{
    tpk_strbuf sb = {0};
    tpk_strbuf_printf(&sb, "{\"format_version\":\"%u.%u\",\"file_bytes\":%llu,\"vertices\":%llu,\"tets\":%llu,"
                           "\"shell_faces\":%llu",
                      info->version_major, info->version_minor, (unsigned long long)info->file_size,
                      (unsigned long long)info->vertex_count, (unsigned long long)info->tet_count,
                      (unsigned long long)info->shell_face_count);
    tpk_strbuf_printf(&sb, ",\"origin\":");
    json_vec3(&sb, info->origin);
    tpk_strbuf_printf(&sb, ",\"bounds\":{\"min\":");
    json_vec3(&sb, info->bounds_min);
    tpk_strbuf_printf(&sb, ",\"max\":");
    json_vec3(&sb, info->bounds_max);
    tpk_strbuf_printf(&sb, "}");
    json_chunks(&sb, file, info);
    json_fields(&sb, file);
    json_levels(&sb, file);
    tpk_strbuf_printf(&sb, ",\"checksums_ok\":%s", verified == TPK_OK ? "true" : "false");
    if (verified != TPK_OK) {
        tpk_strbuf_printf(&sb, ",\"error\":");
        tpk_strbuf_json_string(&sb, tpk_error_text(file));
    }
    char *meta = read_meta(file);
    /* META is JSON written by a converter; embed it only if it looks like an object. */
    tpk_strbuf_printf(&sb, ",\"metadata\":%s}\n", meta && meta[0] == '{' ? meta : "null");
    free(meta);
    if (!sb.failed)
        fputs(sb.data, stdout);
    tpk_strbuf_free(&sb);
    return 0;
}

/* META's "higher_order" (written only for sources with higher-order cells): how they were converted. */
static void print_higher_order(const char *meta)
{
    const char *how = strstr(meta, "\"higher_order\":\""), *cells = strstr(meta, "\"higher_order_cells\":"),
               *points = strstr(meta, "\"higher_order_points\":");
    long long n = 0, added = 0;
    if (!how || !cells || !points || sscanf(cells + 21, "%lld", &n) != 1 || sscanf(points + 22, "%lld", &added) != 1)
        return;
    how += 16;
    if (!strncmp(how, "split\"", 6))
        printf("  higher-order cells: split whole (%lld cells, at all their nodes; %lld face and cell centres "
               "added)\n", n, added);
    else if (!strncmp(how, "corners\"", 8))
        printf("  higher-order cells: reduced to their corners (%lld cells; their other nodes unused)\n", n);
}

/* META's "max_error" (convert --max-error): the bound promised and the largest error the converter proved. */
static void print_max_error(const char *meta)
{
    const char *bound = strstr(meta, "\"max_error\":"), *measured = strstr(meta, "\"max_error_measured\":"),
               *geometry = strstr(meta, "\"max_error_geometry\":");
    double e = 0, m = 0, g = 0;
    if (!bound || !measured || !geometry || sscanf(bound + 12, "%lf", &e) != 1 || sscanf(measured + 21, "%lf", &m) != 1 ||
        sscanf(geometry + 21, "%lf", &g) != 1)
        return;
    printf("  max error: %g requested (convert --max-error), %.3g proved (fields, of their range), %.3g "
           "(geometry, of the bounds diagonal)%s\n", e, m, g,
           strstr(meta, "\"max_error_fields\":") ? "; bounded fields in metadata" : "");
}

static void print_text(const char *path, tpk_file *file, const tpk_file_info *info, tpk_result verified)
{
    printf("%s: tetpack format %u.%u, %llu bytes\n", path, info->version_major, info->version_minor,
           (unsigned long long)info->file_size);
    printf("  vertices %llu, tets %llu, shell faces %llu\n", (unsigned long long)info->vertex_count,
           (unsigned long long)info->tet_count, (unsigned long long)info->shell_face_count);
    printf("  origin (%.17g, %.17g, %.17g)\n", info->origin[0], info->origin[1], info->origin[2]);
    printf("  bounds (%.9g, %.9g, %.9g) .. (%.9g, %.9g, %.9g)\n", info->bounds_min[0], info->bounds_min[1],
           info->bounds_min[2], info->bounds_max[0], info->bounds_max[1], info->bounds_max[2]);
    printf("  fields:%s\n", tpk_field_count(file) ? "" : " none");
    for (uint32_t i = 0; i < tpk_field_count(file); i++) {
        tpk_field_desc d = {0};
        tpk_get_field(file, i, &d);
        printf("    %-24s %-5s %u step(s)  range [%g, %g]%s%s\n", d.name,
               d.association == TPK_ASSOC_POINT ? "point" : "tet", d.step_count, d.min_value, d.max_value,
               d.units[0] ? "  units " : "", d.units);
    }
    printf("  chunks:\n    %-3s %-4s %-5s %-3s %5s %5s %12s %14s %14s\n", "#", "tag", "codec", "req", "index",
           "step", "offset", "stored", "raw");
    for (uint64_t i = 0; i < info->chunk_count; i++) {
        tpk_dir_entry e = {0};
        char tag[5];
        tpk_get_chunk(file, i, &e);
        tag_text(e.tag, tag);
        printf("    %-3llu %-4s %-5s %-3s %5u %5u %12llu %14llu %14llu\n", (unsigned long long)i, tag,
               e.codec == TPK_CODEC_ZSTD ? "zstd" : "none", (e.flags & TPK_CHUNK_REQUIRED) ? "yes" : "no",
               e.index, e.step, (unsigned long long)e.offset, (unsigned long long)e.stored_size,
               (unsigned long long)e.raw_size);
    }
    for (uint32_t k = 1; k <= tpk_level_count(file); k++) {
        tpk_file_info li;
        char err[512] = "";
        if (level_info(file, k, &li, err, sizeof err) == TPK_OK)
            printf("  level %u: vertices %llu, tets %llu, shell faces %llu, %llu bytes (a complete file: "
                   "render --level %u, extract --level %u)\n", k, (unsigned long long)li.vertex_count,
                   (unsigned long long)li.tet_count, (unsigned long long)li.shell_face_count,
                   (unsigned long long)li.file_size, k, k);
        else
            printf("  level %u: FAILED: %s\n", k, err);
    }
    if (verified == TPK_OK)
        printf("  checksums and ids: ok\n");
    else
        printf("  checksums and ids: FAILED: %s\n", tpk_error_text(file));
    char *meta = read_meta(file);
    if (meta)
        print_higher_order(meta);
    if (meta)
        print_max_error(meta);
    if (meta)
        printf("  metadata: %s\n", meta);
    free(meta);
}

int tpk_cmd_info(int argc, char **argv)
{
    const char *path = NULL;
    int json = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            fputs(info_help, stdout);
            return TPK_EXIT_OK;
        } else if (!strcmp(argv[i], "--json")) {
            json = 1;
        } else if (argv[i][0] == '-' && argv[i][1]) {
            return tpk_cli_fail("info", "unknown option '%s' (see tetpack info --help)", argv[i]);
        } else if (!path) {
            path = argv[i];
        } else {
            return tpk_cli_fail("info", "expected one FILE.tpk, found a second argument '%s'", argv[i]);
        }
    }
    if (!path)
        return tpk_cli_fail("info", "expected FILE.tpk (see tetpack info --help)");
    tpk_file *file = NULL;
    if (tpk_cli_open("info", path, &file))
        return TPK_EXIT_USAGE;
    uint64_t part_chunk;
    if (tpk_find_chunk(file, TPK_TAG_PART, 0, 0, &part_chunk) == TPK_OK) { /* a part set's manifest */
        tpk_close(file);
        return tpk_cli_info_set(path, json);
    }
    tpk_file_info info;
    tpk_get_info(file, &info);
    tpk_result verified = tpk_verify(file);
    for (uint32_t k = 1; verified == TPK_OK && k <= tpk_level_count(file); k++) { /* every level's chunks too */
        tpk_file_info li;
        char err[512] = "";
        if (level_info(file, k, &li, err, sizeof err) != TPK_OK) {
            verified = TPK_ERR_CORRUPT;
            fprintf(stderr, "tetpack info: error: %s: %s\n", path, err);
        }
    }
    if (json)
        print_json(file, &info, verified);
    else
        print_text(path, file, &info, verified);
    if (verified != TPK_OK)
        fprintf(stderr, "tetpack info: error: %s: %s\n", path, tpk_error_text(file));
    tpk_close(file);
    return verified == TPK_OK ? TPK_EXIT_OK : TPK_EXIT_USAGE;
}
