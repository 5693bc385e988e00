/* Combinatorial shell checks: 401 nonmanifold_edge, 402 nonmanifold_vertex, 403 shell_orientation,
 * 404 open_shell, 405 euler_characteristic. The shell's polygons (triangles, and quads as quads) give
 * half-edges; a counting sort by their smaller vertex id puts every edge's half-edges next to each other
 * (sorted by the other id within a vertex), so edges come out lowest ids first.
 *  - Fans (402): the corners of the faces at a vertex are joined through every shell edge at that
 *    vertex; more than one group is more than one fan. Joining through non-manifold edges too means
 *    the ends of a non-manifold edge count as 401 only, not again as 402.
 *  - Shell components (405): faces joined through edges of exactly two faces; V, E and F are counted
 *    per component (a vertex or non-manifold edge shared by two components counts in each). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check_topo.h"

typedef struct half_edge {
    uint32_t other;  /* the larger vertex id of the edge */
    uint32_t corner; /* 4 * face + i: from v[i] to v[i + 1] of the face */
} half_edge;

typedef struct shell_graph {
    const double *points;    /* the shell's (tpk_topo_match.points) */
    int64_t point_count;
    const tpk_bface *faces;
    int64_t face_count;
    int64_t *start;          /* point_count + 1: half-edges (then corners) of each vertex */
    half_edge *edges;        /* 4 * face_count slots, bucketed by smaller vertex */
    uint32_t *corners;       /* corner ids bucketed by their vertex */
    uint32_t *corner_parent; /* union-find over corners (fans) */
    uint32_t *face_parent;   /* union-find over faces (shell components) */
    uint32_t *comp_v, *comp_e, *comp_f;
} shell_graph;

static int32_t corner_vertex(const shell_graph *g, uint32_t corner)
{
    return g->faces[corner >> 2].v[corner & 3];
}

static uint32_t next_corner(const shell_graph *g, uint32_t corner)
{
    int n = tpk_bface_n(&g->faces[corner >> 2]);
    return (corner & ~3u) | (((corner & 3u) + 1) % (uint32_t)n);
}

static int half_edge_less(const half_edge *a, const half_edge *b)
{
    return a->other != b->other ? a->other < b->other : a->corner < b->corner;
}

static int half_edge_cmp(const void *a, const void *b)
{
    return half_edge_less(a, b) ? -1 : half_edge_less(b, a) ? 1 : 0;
}

static void sort_half_edges(half_edge *h, int64_t n)
{
    if (n > 48) {
        qsort(h, (size_t)n, sizeof *h, half_edge_cmp);
        return;
    }
    for (int64_t i = 1; i < n; i++) {
        half_edge x = h[i];
        int64_t j = i;
        for (; j > 0 && half_edge_less(&x, &h[j - 1]); j--)
            h[j] = h[j - 1];
        h[j] = x;
    }
}

/* Counting sort of the half-edges by smaller vertex; start[] ends as the bucket starts. */
static void bucket_half_edges(shell_graph *g)
{
    int64_t vertices = g->point_count;
    memset(g->start, 0, sizeof *g->start * (size_t)(vertices + 1));
    for (int64_t f = 0; f < g->face_count; f++)
        for (int i = 0, n = tpk_bface_n(&g->faces[f]); i < n; i++) {
            int32_t a = g->faces[f].v[i], b = g->faces[f].v[(i + 1) % n];
            g->start[(a < b ? a : b) + 1]++;
        }
    for (int64_t v = 0; v < vertices; v++)
        g->start[v + 1] += g->start[v];
    for (int64_t f = 0; f < g->face_count; f++)
        for (int i = 0, n = tpk_bface_n(&g->faces[f]); i < n; i++) {
            int32_t a = g->faces[f].v[i], b = g->faces[f].v[(i + 1) % n];
            half_edge h = {(uint32_t)(a < b ? b : a), (uint32_t)(4 * f + i)};
            g->edges[g->start[a < b ? a : b]++] = h;
        }
    for (int64_t v = vertices; v > 0; v--) /* shift back: start[v] was advanced to start[v + 1] */
        g->start[v] = g->start[v - 1];
    g->start[0] = 0;
}

static void edge_example(const shell_graph *g, tpk_example *ex, int32_t a, int32_t b, const half_edge *h,
                         int64_t k)
{
    int64_t ids[TPK_CHECK_MAX_IDS] = {a, b};
    int n = 2;
    for (int64_t i = 0; i < k && n < TPK_CHECK_MAX_IDS; i++) { /* each cell once */
        int64_t cell = g->faces[h[i].corner >> 2].cell, seen = 0;
        for (int j = 2; j < n && !seen; j++)
            seen = ids[j] == cell;
        if (!seen)
            ids[n++] = cell;
    }
    tpk_example_ids(ex, n, ids);
    const double *p = g->points + 3 * (int64_t)a, *q = g->points + 3 * (int64_t)b;
    double mid[3] = {(p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2};
    tpk_example_point(ex, mid);
}

/* One edge (a, b), a < b, with its k half-edges: checks, and the unions for fans and components. */
static void visit_edge(shell_graph *g, tpk_check_report *report, int32_t a, int32_t b, const half_edge *h,
                       int64_t k)
{
    for (int64_t i = 0; i < k; i++) {
        uint32_t from = h[i].corner, to = next_corner(g, from);
        uint32_t at_a = corner_vertex(g, from) == a ? from : to;
        uint32_t at_b = at_a == from ? to : from;
        uint32_t first_a = corner_vertex(g, h[0].corner) == a ? h[0].corner : next_corner(g, h[0].corner);
        uint32_t first_b = first_a == h[0].corner ? next_corner(g, h[0].corner) : h[0].corner;
        tpk_uf_union(g->corner_parent, first_a, at_a);
        tpk_uf_union(g->corner_parent, first_b, at_b);
    }
    if (k == 1) {
        tpk_example *ex = tpk_check_hit(report, 404, "edge");
        edge_example(g, ex, a, b, h, k);
        tpk_example_note(ex, "edge of one shell face only (ids: the edge, then the cell)");
    } else if (k == 2) {
        tpk_uf_union(g->face_parent, h[0].corner >> 2, h[1].corner >> 2);
        int forward0 = corner_vertex(g, h[0].corner) == a, forward1 = corner_vertex(g, h[1].corner) == a;
        if (forward0 == forward1) {
            tpk_example *ex = tpk_check_hit(report, 403, "edge");
            edge_example(g, ex, a, b, h, k);
            tpk_example_note(ex, "both shell faces traverse it from %d to %d (ids: the edge, then the cells)",
                             forward0 ? a : b, forward0 ? b : a);
        }
    } else {
        tpk_example *ex = tpk_check_hit(report, 401, "edge");
        edge_example(g, ex, a, b, h, k);
        tpk_example_note(ex, "edge of %lld shell faces (ids: the edge, then the cells)", (long long)k);
    }
}

/* Runs of equal `other` within each vertex's bucket are the edges. */
static void for_each_edge(shell_graph *g, tpk_check_report *report, int count_components)
{
    for (int64_t v = 0; v < g->point_count; v++) {
        half_edge *h = g->edges + g->start[v];
        int64_t n = g->start[v + 1] - g->start[v];
        if (!count_components)
            sort_half_edges(h, n);
        for (int64_t i = 0, j; i < n; i = j) {
            for (j = i + 1; j < n && h[j].other == h[i].other; j++)
                ;
            if (!count_components) {
                visit_edge(g, report, (int32_t)v, (int32_t)h[i].other, h + i, j - i);
                continue;
            }
            /* E per component: each distinct component among the edge's faces */
            for (int64_t x = i; x < j; x++) {
                uint32_t c = tpk_uf_find(g->face_parent, h[x].corner >> 2), seen = 0;
                for (int64_t y = i; y < x && !seen; y++)
                    seen = tpk_uf_find(g->face_parent, h[y].corner >> 2) == c;
                g->comp_e[c] += !seen;
            }
        }
    }
}

static void bucket_corners(shell_graph *g)
{
    int64_t vertices = g->point_count;
    memset(g->start, 0, sizeof *g->start * (size_t)(vertices + 1));
    for (int64_t f = 0; f < g->face_count; f++)
        for (int i = 0, n = tpk_bface_n(&g->faces[f]); i < n; i++)
            g->start[g->faces[f].v[i] + 1]++;
    for (int64_t v = 0; v < vertices; v++)
        g->start[v + 1] += g->start[v];
    for (int64_t f = 0; f < g->face_count; f++)
        for (int i = 0, n = tpk_bface_n(&g->faces[f]); i < n; i++)
            g->corners[g->start[g->faces[f].v[i]]++] = (uint32_t)(4 * f + i);
    for (int64_t v = vertices; v > 0; v--)
        g->start[v] = g->start[v - 1];
    g->start[0] = 0;
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

/* Distinct values of roots[0..n) (sorted in place). */
static int64_t distinct(uint32_t *roots, int64_t n)
{
    qsort(roots, (size_t)n, sizeof *roots, cmp_u32);
    int64_t d = 0;
    for (int64_t i = 0; i < n; i++)
        d += i == 0 || roots[i] != roots[i - 1];
    return d;
}

/* 402 per vertex, and V per shell component. `scratch` holds the largest vertex's corners. */
static void visit_vertices(shell_graph *g, tpk_check_report *report, uint32_t *scratch)
{
    for (int64_t v = 0; v < g->point_count; v++) {
        const uint32_t *c = g->corners + g->start[v];
        int64_t n = g->start[v + 1] - g->start[v];
        if (n == 0)
            continue;
        for (int64_t i = 0; i < n; i++)
            scratch[i] = tpk_uf_find(g->corner_parent, c[i]);
        int64_t fans = distinct(scratch, n);
        if (fans > 1) {
            tpk_example *ex = tpk_check_hit(report, 402, "vertex");
            int64_t id = v;
            tpk_example_ids(ex, 1, &id);
            tpk_example_point(ex, g->points + 3 * v);
            tpk_example_note(ex, "the shell faces around this vertex form %lld fans (volumes touching at a "
                             "vertex)", (long long)fans);
        }
        for (int64_t i = 0; i < n; i++)
            scratch[i] = tpk_uf_find(g->face_parent, c[i] >> 2);
        qsort(scratch, (size_t)n, sizeof *scratch, cmp_u32);
        for (int64_t i = 0; i < n; i++)
            if (i == 0 || scratch[i] != scratch[i - 1])
                g->comp_v[scratch[i]]++;
    }
}

/* 405: V - E + F per shell component, reported (info) where it is not 2, lowest face first. */
static void report_euler(shell_graph *g, tpk_check_report *report)
{
    for (int64_t f = 0; f < g->face_count; f++)
        g->comp_f[tpk_uf_find(g->face_parent, (uint32_t)f)]++;
    tpk_finding *finding = tpk_check_finding(report, 405);
    int64_t components = 0, used = 0;
    char values[200] = "";
    for (int64_t f = 0; f < g->face_count; f++) {
        if (g->face_parent[f] != (uint32_t)f)
            continue;
        components++;
        int64_t chi = (int64_t)g->comp_v[f] - (int64_t)g->comp_e[f] + (int64_t)g->comp_f[f];
        if (chi == 2)
            continue;
        tpk_example *ex = tpk_check_hit(report, 405, "component");
        int64_t id = g->faces[f].cell;
        tpk_example_ids(ex, 1, &id);
        tpk_example_point(ex, g->points + 3 * (int64_t)g->faces[f].v[0]);
        tpk_example_note(ex, "V - E + F = %lld (V %u, E %u, F %u); ids: a cell of this shell component",
                         (long long)chi, g->comp_v[f], g->comp_e[f], g->comp_f[f]);
        if (used >= 0 && used < (int64_t)sizeof values - 48) {
            int wrote = snprintf(values + used, sizeof values - (size_t)used, "%s%lld", used ? ", " : "", (long long)chi);
            used = wrote < 0 ? -1 : used + wrote;
        } else if (used >= 0) {
            used = -1;
            strcat(values, ", ...");
        }
    }
    if (finding->count > 0 &&
        snprintf(finding->summary, sizeof finding->summary, "V-E+F = %s (%lld of %lld shell components; 2 is a "
                 "closed surface of genus 0)", values, (long long)finding->count, (long long)components) >=
            (int)sizeof finding->summary)
        memcpy(finding->summary + sizeof finding->summary - 4, "...", 4); /* cut short: say so */
}

static void free_graph(shell_graph *g)
{
    free(g->start);
    free(g->edges);
    free(g->corners);
    free(g->corner_parent);
    free(g->face_parent);
    free(g->comp_v);
    free(g->comp_e);
    free(g->comp_f);
}

static int alloc_graph(shell_graph *g)
{
    size_t faces = (size_t)(g->face_count ? g->face_count : 1);
    g->start = malloc(sizeof *g->start * (size_t)(g->point_count + 1));
    g->edges = malloc(sizeof *g->edges * 4 * faces);
    g->corners = malloc(sizeof *g->corners * 4 * faces);
    g->corner_parent = malloc(sizeof *g->corner_parent * 4 * faces);
    g->face_parent = malloc(sizeof *g->face_parent * faces);
    g->comp_v = calloc(faces, sizeof *g->comp_v);
    g->comp_e = calloc(faces, sizeof *g->comp_e);
    g->comp_f = calloc(faces, sizeof *g->comp_f);
    if (!g->start || !g->edges || !g->corners || !g->corner_parent || !g->face_parent || !g->comp_v ||
        !g->comp_e || !g->comp_f)
        return -1;
    for (size_t i = 0; i < 4 * faces; i++)
        g->corner_parent[i] = (uint32_t)i;
    for (size_t i = 0; i < faces; i++)
        g->face_parent[i] = (uint32_t)i;
    return 0;
}

int tpk_check_shell_edges(const tpk_topo_match *m, tpk_check_report *report,
                          tpk_diag *diag)
{
    if (m->shell_count >= ((int64_t)1 << 30))
        return tpk_diag_fail(diag, "check: %lld shell faces exceed the shell checks' limit of 2^30",
                             (long long)m->shell_count);
    shell_graph g = {m->points, m->point_count, m->shell, m->shell_count, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    if (alloc_graph(&g)) {
        free_graph(&g);
        return tpk_diag_fail(diag, "check: out of memory (shell of %lld faces)", (long long)m->shell_count);
    }
    bucket_half_edges(&g);
    for_each_edge(&g, report, 0);
    for_each_edge(&g, report, 1);
    bucket_corners(&g);
    int64_t largest = 1;
    for (int64_t v = 0; v < g.point_count; v++)
        if (g.start[v + 1] - g.start[v] > largest)
            largest = g.start[v + 1] - g.start[v];
    uint32_t *scratch = malloc(sizeof *scratch * (size_t)largest);
    if (!scratch) {
        free_graph(&g);
        return tpk_diag_fail(diag, "check: out of memory (shell of %lld faces)", (long long)m->shell_count);
    }
    visit_vertices(&g, report, scratch);
    report_euler(&g, report);
    free(scratch);
    free_graph(&g);
    return 0;
}
