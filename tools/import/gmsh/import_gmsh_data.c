/* Gmsh importer: $NodeData and $ElementData blocks, and the fields built from them (blocks of the same
 * name at several times become one field with several steps). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "import_gmsh_internal.h"
#include "base/text_scan.h"

/* A string tag: "quoted, may hold spaces" or one token. */
static int read_string(gmsh_reader *r, char *dst, size_t cap)
{
    tpk_scan_skip_space(&r->s);
    const unsigned char *d = r->s.data;
    size_t p = r->s.pos;
    r->s.tok_pos = p;
    r->s.tok_line = r->s.line;
    if (p >= r->s.size)
        return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "expected a string tag, found end of file");
    size_t start, end;
    if (d[p] == '"') {
        start = p + 1;
        end = start;
        while (end < r->s.size && d[end] != '"' && d[end] != '\n')
            end++;
        if (end >= r->s.size || d[end] != '"')
            return tpk_scan_fail(&r->s, "expected a closing '\"' on the line of a string tag, found %s",
                                 end >= r->s.size ? "end of file" : "end of line");
        r->s.pos = end + 1;
    } else {
        const char *tok;
        size_t len = tpk_scan_token(&r->s, &tok);
        start = (size_t)((const unsigned char *)tok - d);
        end = start + len;
    }
    size_t len = end - start;
    if (len >= cap)
        len = cap - 1;
    memcpy(dst, d + start, len);
    dst[len] = 0;
    for (size_t i = 0; i < len; i++)
        if ((unsigned char)dst[i] < ' ')
            dst[i] = '_';
    return 0;
}

int gmsh_read_data(gmsh_reader *r, int association)
{
    const char *section = association == TPK_ASSOC_POINT ? "$NodeData" : "$ElementData";
    int64_t ns, nr, ni, v;
    char name[TPK_NAME_MAX] = "";
    double time = 0, x;
    int64_t step = 0, components = 1, count = 0;
    if (association == TPK_ASSOC_POINT ? r->point_count < 0 : !r->have_elements)
        return tpk_scan_fail(&r->s, "expected %s before %s", association == TPK_ASSOC_POINT ? "$Nodes" : "$Elements",
                             section);
    if (gmsh_read_count(r, "string tags", 1, &ns, 0))
        return -1;
    for (int64_t k = 0; k < ns; k++) {
        char buf[TPK_NAME_MAX];
        if (read_string(r, buf, sizeof buf))
            return -1;
        if (k == 0)
            memcpy(name, buf, sizeof name);
    }
    if (!name[0])
        snprintf(name, sizeof name, "%s", association == TPK_ASSOC_POINT ? "node_data" : "element_data");
    if (gmsh_read_count(r, "real tags", 1, &nr, 0))
        return -1;
    for (int64_t k = 0; k < nr; k++) {
        if (tpk_scan_double(&r->s, &x, "a real tag (the time)"))
            return -1;
        if (k == 0)
            time = x;
    }
    if (gmsh_read_count(r, "integer tags", 1, &ni, 0))
        return -1;
    if (ni < 3)
        return tpk_scan_fail(&r->s, "%s: expected 3 or more integer tags (step, components, count), found %lld",
                             section, (long long)ni);
    for (int64_t k = 0; k < ni; k++) {
        if (tpk_scan_int64(&r->s, &v, "an integer tag"))
            return -1;
        if (k == 0)
            step = v;
        else if (k == 1)
            components = v;
        else if (k == 2)
            count = v;
    }
    if (gmsh_bin_start(r, "the integer tags"))
        return -1;
    (void)step;
    if (components < 1 || components > 9)
        return tpk_scan_fail(&r->s, "%s '%s': expected 1 to 9 components, found %lld", section, name,
                             (long long)components);
    int64_t items = association == TPK_ASSOC_POINT ? r->point_count : r->cell_count;
    if (count < 0 || (uint64_t)count > gmsh_bytes_left(r) / (2 * (uint64_t)(components + 1)) + 1)
        return tpk_scan_fail(&r->s, "%s '%s': %lld values cannot fit in the %zu bytes left (wrong count or "
                                    "truncated file)", section, name, (long long)count, gmsh_bytes_left(r));
    if (association != TPK_ASSOC_POINT && r->elem_listed && !r->elem_sorted) {
        if (gmsh_sort_tags(r, r->elem_tags, r->elem_count, "element"))
            return -1;
        r->elem_sorted = 1;
    }
    /* Each block is stored whole (items * components values): bound their sum by the file size, so that
     * many tiny blocks over a large mesh cannot claim unbounded memory. Dense blocks take at least
     * 2 bytes per value in the file, far below this bound. */
    r->block_values += (uint64_t)items * (uint64_t)components;
    if (r->block_values > 8 * (uint64_t)r->s.size + (1u << 20))
        return tpk_scan_fail(&r->s, "%s '%s': %llu field values in all for a %zu-byte file (too many data "
                                    "blocks for the mesh size)", section, name,
                             (unsigned long long)r->block_values, r->s.size);
    if (r->block_count >= 65536)
        return tpk_scan_fail(&r->s, "%s '%s': more than 65536 data blocks (fields times time steps)", section, name);
    data_block *blocks = realloc(r->blocks, sizeof *blocks * (size_t)(r->block_count + 1));
    if (!blocks)
        return tpk_scan_fail(&r->s, "out of memory");
    r->blocks = blocks;
    data_block *b = &r->blocks[r->block_count];
    memset(b, 0, sizeof *b);
    b->values = malloc(sizeof *b->values * (size_t)(items ? items : 1) * (size_t)components);
    if (!b->values)
        return tpk_scan_fail(&r->s, "out of memory");
    r->block_count++;
    memcpy(b->name, name, sizeof b->name);
    b->association = association;
    b->components = (int)components;
    b->time = time;
    for (int64_t i = 0; i < items * components; i++)
        b->values[i] = NAN;
    for (int64_t i = 0; i < count; i++) {
        int64_t tag;
        int32_t at;
        char user[96];
        if (gmsh_num(r, &tag, association == TPK_ASSOC_POINT ? "a node tag" : "an element tag", 4))
            return -1;
        if (association == TPK_ASSOC_POINT) {
            snprintf(user, sizeof user, "%s '%s'", section, name);
            if ((at = gmsh_node_index(r, tag, user)) < 0)
                return -1;
        } else {
            int found;
            if (r->elem_listed)
                at = gmsh_lookup(r->elem_tags, r->elem_count, tag, &found);
            else if ((found = tag >= r->elem_first_tag && tag - r->elem_first_tag < r->elem_count))
                at = (int32_t)(tag - r->elem_first_tag); /* the run: tag - first is the cell */
            if (!found)
                return tpk_scan_fail(&r->s, "%s '%s' uses element tag %lld, which $Elements does not define",
                                     section, name, (long long)tag);
        }
        for (int64_t k = 0; k < components; k++) {
            if (gmsh_real(r, &x, "a field value"))
                return -1;
            if (at >= 0)
                b->values[at * components + k] = (float)x;
        }
    }
    return gmsh_expect_end(r, association == TPK_ASSOC_POINT ? "$EndNodeData" : "$EndElementData");
}

/* Blocks of the same name and association become one field, their times the steps. */
int gmsh_build_fields(gmsh_reader *r, tpk_mesh *out)
{
    int max_steps = 1, first_multi = -1;
    int *group = calloc((size_t)(r->block_count ? r->block_count : 1), sizeof *group);
    if (!group)
        return tpk_scan_fail(&r->s, "out of memory");
    int *heads = malloc(sizeof *heads * 1024);
    int head_count = 0;
    if (!heads) {
        free(group);
        return tpk_scan_fail(&r->s, "out of memory");
    }
    for (int i = 0; i < r->block_count; i++) {
        group[i] = i;
        for (int h = 0; h < head_count; h++) {
            int j = heads[h];
            if (r->blocks[j].association == r->blocks[i].association && !strcmp(r->blocks[j].name, r->blocks[i].name)) {
                group[i] = j;
                break;
            }
        }
        if (group[i] != i)
            continue;
        if (head_count == 1024) {
            free(heads);
            free(group);
            return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "more than 1024 fields in $NodeData and "
                                                                 "$ElementData");
        }
        heads[head_count++] = i;
    }
    free(heads);
    for (int i = 0; i < r->block_count; i++) {
        if (group[i] != i)
            continue;
        int steps = 0;
        for (int j = i; j < r->block_count; j++)
            steps += group[j] == i;
        if (steps > max_steps) {
            max_steps = steps;
            first_multi = i;
        }
    }
    int rc = 0;
    for (int i = 0; i < r->block_count && !rc; i++) {
        if (group[i] != i)
            continue;
        data_block *b = &r->blocks[i];
        int steps = 0;
        for (int j = i; j < r->block_count; j++)
            if (group[j] == i && r->blocks[j].components != b->components) {
                rc = tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "field '%s': %d components in one step, %d in "
                                      "another", b->name, b->components, r->blocks[j].components);
                break;
            } else
                steps += group[j] == i;
        if (rc)
            break;
        if (steps != 1 && steps != max_steps) {
            tpk_diag_warn(r->s.diag, "%s: field '%s' has %d time steps, others %d: only its first is kept",
                          r->s.name, b->name, steps, max_steps);
            steps = 1;
        }
        int64_t items = b->association == TPK_ASSOC_POINT ? r->point_count : r->cell_count;
        size_t per = (size_t)items * (size_t)b->components;
        float *values = malloc(sizeof *values * (per ? per : 1) * (size_t)steps);
        if (!values) {
            rc = tpk_scan_fail(&r->s, "out of memory");
            break;
        }
        int s = 0;
        for (int j = i; j < r->block_count && s < steps; j++)
            if (group[j] == i)
                memcpy(values + per * (size_t)s++, r->blocks[j].values, sizeof *values * per);
        if (tpk_mesh_add_field(out, b->name, b->association, b->components, steps, values)) {
            free(values);
            rc = tpk_scan_fail(&r->s, "out of memory");
        }
    }
    if (!rc && max_steps > 1) {
        out->times = malloc(sizeof *out->times * (size_t)max_steps);
        if (!out->times)
            rc = tpk_scan_fail(&r->s, "out of memory");
        int s = 0;
        for (int j = first_multi; !rc && j < r->block_count; j++)
            if (group[j] == first_multi)
                out->times[s++] = r->blocks[j].time;
    }
    out->step_count = max_steps;
    free(group);
    return rc;
}
