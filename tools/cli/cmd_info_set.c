/* tetpack info on a part set's manifest: totals, the outer shell apart from the faces on cuts, and the
 * parts with their counts, links and bounds (text or JSON). */
#include <stdio.h>
#include <string.h>

#include "base/strbuf.h"
#include "cli.h"
#include "tetpack.h"

typedef struct set_totals {
    uint64_t vertices, tets, shell_faces, link_records, bytes;
    double lo[3], hi[3];
} set_totals;

static void add_part(set_totals *s, const tpk_part_record *r, uint32_t p)
{
    s->vertices += r->vertex_count;
    s->tets += r->tet_count;
    s->shell_faces += r->shell_face_count;
    s->link_records += r->link_count;
    s->bytes += r->file_size;
    for (int k = 0; k < 3; k++) {
        s->lo[k] = p == 0 || r->bounds_min[k] < s->lo[k] ? r->bounds_min[k] : s->lo[k];
        s->hi[k] = p == 0 || r->bounds_max[k] > s->hi[k] ? r->bounds_max[k] : s->hi[k];
    }
}

static void json_vec3(tpk_strbuf *sb, const double v[3])
{
    tpk_strbuf_printf(sb, "[");
    for (int k = 0; k < 3; k++) {
        tpk_strbuf_printf(sb, k ? "," : "");
        tpk_strbuf_json_number(sb, v[k]);
    }
    tpk_strbuf_printf(sb, "]");
}

static void print_json(const tpk_partset *set, const set_totals *s)
{
    tpk_strbuf sb = {0};
    tpk_strbuf_printf(&sb, "{\"format_version\":\"%d.%d\",\"part_set\":true,\"part_count\":%u,\"tets\":%llu,"
                      "\"vertex_records\":%llu,\"shell_faces\":%llu,\"cut_faces\":%llu,\"file_bytes\":%llu,"
                      "\"bounds\":{\"min\":", TPK_VERSION_MAJOR, TPK_VERSION_MINOR_PARTS, tpk_partset_part_count(set),
                      (unsigned long long)s->tets, (unsigned long long)s->vertices,
                      (unsigned long long)(s->shell_faces - s->link_records), (unsigned long long)(s->link_records / 2),
                      (unsigned long long)s->bytes);
    json_vec3(&sb, s->lo);
    tpk_strbuf_printf(&sb, ",\"max\":");
    json_vec3(&sb, s->hi);
    tpk_strbuf_printf(&sb, "},\"parts\":[");
    for (uint32_t p = 0; p < tpk_partset_part_count(set); p++) {
        tpk_part_record r;
        tpk_partset_get_part(set, p, &r);
        tpk_strbuf_printf(&sb, "%s{\"file\":", p ? "," : "");
        tpk_strbuf_json_string(&sb, r.file);
        tpk_strbuf_printf(&sb, ",\"vertices\":%llu,\"tets\":%llu,\"shell_faces\":%llu,\"outer_faces\":%llu,"
                          "\"cut_faces\":%llu,\"file_bytes\":%llu,\"bounds\":{\"min\":",
                          (unsigned long long)r.vertex_count, (unsigned long long)r.tet_count,
                          (unsigned long long)r.shell_face_count,
                          (unsigned long long)(r.shell_face_count - r.link_count), (unsigned long long)r.link_count,
                          (unsigned long long)r.file_size);
        json_vec3(&sb, r.bounds_min);
        tpk_strbuf_printf(&sb, ",\"max\":");
        json_vec3(&sb, r.bounds_max);
        tpk_strbuf_printf(&sb, "}}");
    }
    tpk_strbuf_printf(&sb, "]}\n");
    if (!sb.failed)
        fwrite(sb.data, 1, sb.length, stdout);
    tpk_strbuf_free(&sb);
}

static void print_text(const char *path, const tpk_partset *set, const set_totals *s)
{
    uint32_t n = tpk_partset_part_count(set);
    printf("%s: tetpack part set (format %d.%d), %u parts, %llu bytes in all\n", path, TPK_VERSION_MAJOR,
           TPK_VERSION_MINOR_PARTS, n, (unsigned long long)s->bytes);
    printf("  tets %llu, vertex records %llu (a vertex on a cut is in each part that uses it)\n",
           (unsigned long long)s->tets, (unsigned long long)s->vertices);
    printf("  outer shell faces %llu (on no cut), cut faces %llu (each linked from both sides)\n",
           (unsigned long long)(s->shell_faces - s->link_records), (unsigned long long)(s->link_records / 2));
    printf("  bounds (%.9g, %.9g, %.9g) .. (%.9g, %.9g, %.9g)\n", s->lo[0], s->lo[1], s->lo[2], s->hi[0], s->hi[1],
           s->hi[2]);
    printf("  parts:\n    #   file                         vertices        tets   outer faces   cut faces\n");
    for (uint32_t p = 0; p < n; p++) {
        tpk_part_record r;
        tpk_partset_get_part(set, p, &r);
        printf("    %-3u %-24s %12llu %11llu %13llu %11llu\n", p, r.file, (unsigned long long)r.vertex_count,
               (unsigned long long)r.tet_count, (unsigned long long)(r.shell_face_count - r.link_count),
               (unsigned long long)r.link_count);
    }
    printf("  checksums, ids and links: ok\n");
}

int tpk_cli_info_set(const char *path, int json)
{
    tpk_partset *set = NULL;
    char err[1024] = "";
    tpk_result r = tpk_partset_open(&set, path, NULL, NULL, NULL, err, sizeof err);
    if (r != TPK_OK)
        return tpk_cli_fail("info", "%s", err[0] ? err : tpk_result_string(r));
    set_totals totals;
    memset(&totals, 0, sizeof totals);
    for (uint32_t p = 0; p < tpk_partset_part_count(set) && r == TPK_OK; p++) {
        tpk_part_record rec;
        tpk_partset_get_part(set, p, &rec);
        add_part(&totals, &rec, p);
        const tpk_link *links;
        uint64_t count;
        r = tpk_verify(tpk_partset_file(set, p));
        if (r == TPK_OK)
            r = tpk_partset_links(set, p, &links, &count);
        if (r != TPK_OK)
            tpk_cli_fail("info", "%s: part %u (%s): %s", path, p, rec.file, tpk_error_text(tpk_partset_file(set, p)));
    }
    if (r == TPK_OK && json)
        print_json(set, &totals);
    else if (r == TPK_OK)
        print_text(path, set, &totals);
    tpk_partset_close(set);
    return r == TPK_OK ? TPK_EXIT_OK : TPK_EXIT_USAGE;
}
