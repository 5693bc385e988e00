/* A part set from one converted mesh (spec §15): the tets, already in Hilbert order (tpk_reorder) and
 * connected, are cut into N runs of equal length along the curve, so each part is a compact region of
 * space; each run is written as a complete .tpk (a face on a cut is a shell face there) with the LINK
 * records that tie it to the same face in the other part, and the manifest last, so that a set whose
 * conversion failed is never named. Every part keeps the whole mesh's origin and vertex order. */
#include "parts.h"

#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/output_file.h"
#include "base/strbuf.h"
#include "pipeline.h"
#include "write_tpk.h"

typedef struct part_plan {
    const tpk_tetmesh *mesh;
    const int32_t *neighbors;
    int count;
    int64_t *first;        /* count + 1: part p holds tets [first[p], first[p+1]) */
    int32_t *shell_index;  /* per slot 4t+k: its index in its part's SHEL, or -1 */
} part_plan;

static int part_of(const part_plan *plan, int64_t tet)
{
    int lo = 0, hi = plan->count - 1;
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (plan->first[mid] <= tet)
            lo = mid;
        else
            hi = mid - 1;
    }
    return lo;
}

static int inside(const part_plan *plan, int p, int32_t tet)
{
    return tet >= plan->first[p] && tet < plan->first[p + 1];
}

/* SHEL indices as tpk_build_shell numbers them (tet order, then face order), per part. */
static void number_shell_faces(part_plan *plan)
{
    for (int p = 0; p < plan->count; p++) {
        int32_t next = 0;
        for (int64_t slot = 4 * plan->first[p]; slot < 4 * plan->first[p + 1]; slot++) {
            int32_t u = plan->neighbors[slot];
            plan->shell_index[slot] = u < 0 || !inside(plan, p, u) ? next++ : -1;
        }
    }
}

/* Part p's links, sorted by face (slots are visited in SHEL order). */
static int64_t part_links(const part_plan *plan, int p, tpk_link *links)
{
    int64_t n = 0;
    for (int64_t slot = 4 * plan->first[p]; slot < 4 * plan->first[p + 1]; slot++) {
        int32_t u = plan->neighbors[slot];
        if (u < 0 || inside(plan, p, u))
            continue;
        int q = part_of(plan, u);
        int j = tpk_face_across(plan->mesh->tets, slot / 4, (int)(slot % 4), u);
        links[n++] = (tpk_link){plan->shell_index[slot], q, plan->shell_index[4 * (int64_t)u + j],
                                (int32_t)(u - plan->first[q])};
    }
    return n;
}

/* One part as a tet mesh of its own, in the stored frame of the whole. */
typedef struct part_mesh {
    tpk_tetmesh mesh;
    int32_t *neighbors;
    tpk_link *links;
    int64_t link_count;
} part_mesh;

static void free_part_mesh(part_mesh *pm)
{
    tpk_tetmesh *m = &pm->mesh;
    for (int f = 0; f < m->field_count; f++)
        free(m->fields[f].values);
    free(m->fields);
    free(m->points);
    free(m->vertex_source);
    free(m->tets);
    free(m->tet_source);
    free(pm->neighbors);
    free(pm->links);
    memset(pm, 0, sizeof *pm);
}

/* Fields of the part: point values gathered through the part's vertices, tet values sliced. */
static int copy_fields(const tpk_tetmesh *whole, tpk_tetmesh *m, const int32_t *global_of, int64_t first_tet)
{
    m->fields = calloc((size_t)(whole->field_count ? whole->field_count : 1), sizeof *m->fields);
    if (!m->fields)
        return -1;
    m->field_count = whole->field_count;
    for (int f = 0; f < whole->field_count; f++) {
        const tpk_src_field *src = &whole->fields[f];
        tpk_src_field *dst = &m->fields[f];
        *dst = *src;
        int point = src->association == TPK_ASSOC_POINT;
        int64_t n = point ? m->vertex_count : m->tet_count, whole_n = point ? whole->vertex_count : whole->tet_count;
        dst->values = malloc(sizeof *dst->values * (size_t)(n * src->step_count + 1));
        if (!dst->values)
            return -1;
        for (int s = 0; s < src->step_count; s++)
            for (int64_t i = 0; i < n; i++)
                dst->values[s * n + i] = src->values[s * whole_n + (point ? global_of[i] : first_tet + i)];
    }
    return 0;
}

/* Vertices of part p, in the whole's order (so every face keeps the order of its ids, spec §15.4). */
static int make_part(const part_plan *plan, int p, int32_t *local_of, part_mesh *pm)
{
    const tpk_tetmesh *whole = plan->mesh;
    int64_t t0 = plan->first[p], tn = plan->first[p + 1] - t0;
    for (int64_t i = 4 * t0; i < 4 * (t0 + tn); i++)
        local_of[whole->tets[i]] = 0;
    int64_t vn = 0;
    for (int64_t v = 0; v < whole->vertex_count; v++)
        if (local_of[v] == 0)
            local_of[v] = (int32_t)vn++;
    tpk_tetmesh *m = &pm->mesh;
    m->vertex_count = vn;
    m->tet_count = tn;
    memcpy(m->origin, whole->origin, sizeof m->origin);
    m->points = malloc(sizeof *m->points * (size_t)(3 * vn));
    m->vertex_source = malloc(sizeof *m->vertex_source * (size_t)vn);
    m->tets = malloc(sizeof *m->tets * (size_t)(4 * tn));
    m->tet_source = malloc(sizeof *m->tet_source * (size_t)tn);
    pm->neighbors = malloc(sizeof *pm->neighbors * (size_t)(4 * tn));
    pm->links = malloc(sizeof *pm->links * (size_t)(4 * tn));
    int32_t *global_of = malloc(sizeof *global_of * (size_t)(vn ? vn : 1));
    int rc = -1;
    if (m->points && m->vertex_source && m->tets && m->tet_source && pm->neighbors && pm->links && global_of) {
        for (int64_t v = 0; v < whole->vertex_count; v++)
            if (local_of[v] >= 0) {
                int32_t l = local_of[v];
                global_of[l] = (int32_t)v;
                memcpy(m->points + 3 * l, whole->points + 3 * v, 3 * sizeof *m->points);
                m->vertex_source[l] = whole->vertex_source ? whole->vertex_source[v] : (int32_t)v;
            }
        for (int64_t i = 0; i < 4 * tn; i++) {
            m->tets[i] = local_of[whole->tets[4 * t0 + i]];
            int32_t u = plan->neighbors[4 * t0 + i];
            pm->neighbors[i] = u >= 0 && inside(plan, p, u) ? (int32_t)(u - t0) : -1;
        }
        for (int64_t t = 0; t < tn; t++)
            m->tet_source[t] = whole->tet_source ? whole->tet_source[t0 + t] : (int32_t)(t0 + t);
        m->step_count = whole->step_count;
        m->times = whole->times; /* borrowed: free_part_mesh leaves it */
        pm->link_count = part_links(plan, p, pm->links);
        rc = copy_fields(whole, m, global_of, t0);
    }
    for (int64_t i = 4 * t0; i < 4 * (t0 + tn); i++) /* ready for the next part */
        local_of[whole->tets[i]] = -1;
    free(global_of);
    return rc;
}

static void part_bounds(const tpk_tetmesh *m, tpk_header_fields *hdr)
{
    for (int k = 0; k < 3; k++) {
        hdr->bounds_min[k] = m->vertex_count ? 1e308 : 0.0;
        hdr->bounds_max[k] = m->vertex_count ? -1e308 : 0.0;
    }
    for (int64_t i = 0; i < m->vertex_count; i++)
        for (int k = 0; k < 3; k++) {
            double world = hdr->origin[k] + m->points[3 * i + k];
            hdr->bounds_min[k] = world < hdr->bounds_min[k] ? world : hdr->bounds_min[k];
            hdr->bounds_max[k] = world > hdr->bounds_max[k] ? world : hdr->bounds_max[k];
        }
}

/* The header checksum the part was written with: the manifest binds the part by it (spec §15.2). */
int tpk_read_header_checksum(const char *path, uint64_t *out, tpk_diag *diag)
{
    FILE *f = fopen(path, "rb");
    uint8_t header[TPK_HEADER_SIZE];
    int ok = f && fread(header, 1, sizeof header, f) == sizeof header;
    if (f)
        fclose(f);
    if (!ok)
        return tpk_diag_fail(diag, "%s: cannot read back the part just written", path);
    memcpy(out, header + offsetof(tpk_header, header_checksum), sizeof *out);
    return 0;
}

int tpk_part_path(const char *manifest, int p, int count, tpk_part_record *record, char **out, tpk_diag *diag)
{
    const char *slash = strrchr(manifest, '/');
    const char *name = slash ? slash + 1 : manifest;
    const char *dot = strrchr(name, '.');
    int stem = dot && dot != name ? (int)(dot - name) : (int)strlen(name);
    int width = snprintf(NULL, 0, "%d", count - 1);
    int n = snprintf(record->file, sizeof record->file, "%.*s-%0*d.tpk", stem, name, width, p);
    if (n <= 0 || n >= (int)sizeof record->file)
        return tpk_diag_fail(diag, "%s: the part file names would be longer than %d bytes; use a shorter name",
                             manifest, TPK_PART_FILE_MAX - 1);
    size_t dir = (size_t)(name - manifest), need = dir + (size_t)n + 1;
    if (!(*out = malloc(need)))
        return tpk_diag_fail(diag, "out of memory");
    snprintf(*out, need, "%.*s%s", (int)dir, manifest, record->file);
    return 0;
}

static int write_part(const part_plan *plan, int p, const tpk_convert_options *o, const tpk_header_fields *whole,
                      const char *source_format, int32_t *local_of, tpk_part_record *record, tpk_convert_report *rep,
                      tpk_diag *diag)
{
    char *path = NULL;
    if (tpk_part_path(o->output, p, plan->count, record, &path, diag) != 0)
        return -1;
    part_mesh pm;
    memset(&pm, 0, sizeof pm);
    int rc = make_part(plan, p, local_of, &pm);
    if (rc != 0)
        rc = tpk_diag_fail(diag, "out of memory for part %d of %d", p, plan->count);
    tpk_convert_options po = *o;
    po.output = path;
    tpk_header_fields hdr = *whole;
    part_bounds(&pm.mesh, &hdr);
    tpk_convert_report prep = *rep;
    tpk_part_extras extras = {pm.links, pm.link_count, p, plan->count};
    if (rc == 0)
        rc = tpk_write_tpk(&po, &pm.mesh, pm.neighbors, &hdr, &prep, source_format, &extras, diag);
    if (rc == 0)
        rc = tpk_read_header_checksum(path, &record->header_checksum, diag);
    if (rc == 0) {
        record->file_size = prep.output_bytes;
        record->vertex_count = hdr.vertex_count;
        record->tet_count = hdr.tet_count;
        record->shell_face_count = hdr.shell_face_count;
        record->link_count = (uint64_t)pm.link_count;
        memcpy(record->bounds_min, hdr.bounds_min, sizeof hdr.bounds_min);
        memcpy(record->bounds_max, hdr.bounds_max, sizeof hdr.bounds_max);
        rep->output_bytes += prep.output_bytes;
        rep->shell_faces += (int64_t)hdr.shell_face_count - pm.link_count; /* the outer shell */
    }
    free_part_mesh(&pm);
    free(path);
    return rc;
}

static void writer_message(void *user, tpk_result code, const char *text)
{
    (void)code;
    tpk_diag_fail(user, "%s", text);
}

static int add_empty(tpk_writer *w, uint32_t tag, tpk_elem_type type, uint32_t size)
{
    tpk_chunk_desc d = {.tag = tag, .flags = TPK_CHUNK_REQUIRED, .elem_type = (uint8_t)type, .elem_size = size};
    return tpk_writer_add_chunk(w, &d, NULL) == TPK_OK ? 0 : -1;
}

/* The manifest: a .tpk of no mesh (empty POS3, TT32, SHEL), the whole's origin, the PART table and a
 * META naming the source (spec §15.1). */
int tpk_write_manifest(const char *path, const double origin[3], const tpk_part_record *records, int count,
                       const char *meta_json, tpk_diag *diag)
{
    tpk_output out;
    if (tpk_output_open(&out, path, diag) != 0)
        return -1;
    tpk_write_options wopt = {.size = sizeof wopt, .message = writer_message, .message_user = diag};
    tpk_writer *w = NULL;
    char err[512] = "";
    if (tpk_writer_open_fd(&w, out.fd, path, &wopt, err, sizeof err) != TPK_OK) {
        tpk_output_abort(&out);
        return tpk_diag_fail(diag, "%s", err);
    }
    tpk_chunk_desc part = {.tag = TPK_TAG_PART, .elem_type = TPK_ELEM_BYTE, .elem_size = 1,
                           .elem_count = (uint64_t)count * sizeof *records};
    tpk_chunk_desc meta = {.tag = TPK_TAG_META, .elem_type = TPK_ELEM_BYTE, .elem_size = 1,
                           .elem_count = strlen(meta_json)};
    int rc = add_empty(w, TPK_TAG_POS3, TPK_ELEM_VEC3_F32, 12);
    if (rc == 0)
        rc = add_empty(w, TPK_TAG_TT32, TPK_ELEM_TET32, 32);
    if (rc == 0)
        rc = add_empty(w, TPK_TAG_SHEL, TPK_ELEM_SHELL_FACE, 16);
    if (rc == 0)
        rc = tpk_writer_add_chunk(w, &part, records) == TPK_OK ? 0 : -1;
    if (rc == 0)
        rc = tpk_writer_add_chunk(w, &meta, meta_json) == TPK_OK ? 0 : -1;
    if (rc != 0) {
        tpk_diag_fail(diag, "%s", tpk_writer_error_text(w));
        tpk_writer_abort(w);
        tpk_output_abort(&out);
        return -1;
    }
    tpk_header_fields hdr = {0};
    memcpy(hdr.origin, origin, sizeof hdr.origin);
    if (tpk_writer_finish(w, &hdr) != TPK_OK) {
        tpk_output_abort(&out);
        return diag->message[0] ? -1 : tpk_diag_fail(diag, "%s: could not finish the manifest", path);
    }
    return tpk_output_commit(&out, diag);
}

int tpk_write_part_set(const tpk_convert_options *o, const tpk_tetmesh *mesh, const int32_t *neighbors,
                       const tpk_header_fields *whole, tpk_convert_report *rep, const char *source_format,
                       tpk_diag *diag)
{
    int count = o->parts;
    if (count < 1 || count > mesh->tet_count)
        return tpk_diag_fail(diag, "%s: --parts %d, but the mesh has %lld tets: each part needs at least one",
                             o->input, count, (long long)mesh->tet_count);
    part_plan plan = {mesh, neighbors, count, NULL, NULL};
    plan.first = malloc(sizeof *plan.first * (size_t)(count + 1));
    plan.shell_index = malloc(sizeof *plan.shell_index * (size_t)(4 * mesh->tet_count));
    int32_t *local_of = malloc(sizeof *local_of * (size_t)(mesh->vertex_count ? mesh->vertex_count : 1));
    tpk_part_record *records = calloc((size_t)count, sizeof *records);
    int rc = plan.first && plan.shell_index && local_of && records ? 0 : tpk_diag_fail(diag, "out of memory");
    if (rc == 0) {
        for (int p = 0; p <= count; p++) /* balanced by tets; the tets follow the Hilbert curve */
            plan.first[p] = mesh->tet_count * p / count;
        number_shell_faces(&plan);
        for (int64_t v = 0; v < mesh->vertex_count; v++)
            local_of[v] = -1;
        rep->shell_faces = 0;
        rep->output_bytes = 0;
    }
    for (int p = 0; rc == 0 && p < count; p++)
        rc = write_part(&plan, p, o, whole, source_format, local_of, &records[p], rep, diag);
    if (rc == 0) {
        tpk_strbuf sb = {0};
        tpk_strbuf_printf(&sb, "{\"converter\":{\"name\":\"tetpack\",\"version\":\"%s\"},\"source\":{\"path\":",
                          TPK_LIBRARY_VERSION);
        tpk_strbuf_json_string(&sb, o->input);
        tpk_strbuf_printf(&sb, ",\"format\":");
        tpk_strbuf_json_string(&sb, source_format);
        tpk_strbuf_printf(&sb, "},\"part_set\":{\"parts\":%d,\"vertices\":%lld,\"tets\":%lld,\"cut\":\"hilbert\"}}",
                          count, (long long)mesh->vertex_count, (long long)mesh->tet_count);
        rc = sb.failed ? tpk_diag_fail(diag, "out of memory")
                       : tpk_write_manifest(o->output, whole->origin, records, count, sb.data, diag);
        tpk_strbuf_free(&sb);
    }
    free(plan.first);
    free(plan.shell_index);
    free(local_of);
    free(records);
    return rc;
}
