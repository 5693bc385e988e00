/* CGNS FlowSolution_t to fields. Vertex solutions become point fields, CellCenter ones cell fields (one
 * value per volume cell in element-number order, i fastest for a structured zone). With
 * BaseIterativeData, a zone's ZoneIterativeData says which solution belongs to which step: the
 * IOSS/SEACAS arrays VertexSolutionIndices and CellCenterIndices when they hold solution numbers (IOSS's
 * FlowSolutionPointers name no solution of the file), else the standard FlowSolutionPointers by name,
 * else IOSS's "Step" descriptor in each FlowSolution (older IOSS files have zeros in the index arrays).
 * Solutions no step points at are static: one step, valid at all of them. Fields merge over zones by
 * name and location, NaN where a zone has none. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "import_cgns_internal.h"
#include "tetpack_format.h"

enum { AT_VERTEX = 0, AT_CELL = 1 };

typedef struct field_slot {
    char name[TPK_NAME_MAX];
    int location, steps;
    float *values;           /* steps * (points or cells) */
    int zone, solution;      /* the last static solution written, to tell apart equal names in one zone */
} field_slot;

typedef struct field_table {
    field_slot *slots;
    int count, cap;
    int64_t per_location[2]; /* points, cells of the whole mesh */
} field_table;

/* cg_goto to a node, then the index of the array `name` under it and its size; 0 when absent. */
static int find_array(const char *name, cgsize_t *size, CGNS_ENUMT(DataType_t) *type)
{
    int count = 0;
    if (cg_narrays(&count))
        return 0;
    for (int a = 1; a <= count; a++) {
        char found[33];
        int dims = 0;
        cgsize_t extent[12] = {0};
        if (cg_array_info(a, found, type, &dims, extent) == 0 && !strcmp(found, name)) {
            *size = 1;
            for (int d = 0; d < dims && d < 12; d++)
                *size *= extent[d];
            return a;
        }
    }
    return 0;
}

int cgns_read_times(cgns_reader *r, tpk_mesh *out)
{
    char name[33];
    int steps = 0, rc = cg_biter_read(r->fn, r->base, name, &steps);
    out->step_count = 1;
    if (rc == CG_NODE_NOT_FOUND)
        return 0;
    if (rc)
        return CGNS_FAIL(r, "cannot read BaseIterativeData%s", "");
    if (steps < 1 || steps > r->file_size)
        return tpk_diag_fail(r->diag, "%s: BaseIterativeData '%s' has %d steps, expected 1 to %lld (the file's size)",
                             r->path, name, steps, (long long)r->file_size);
    r->steps = out->step_count = steps;
    cgsize_t size = 0;
    CGNS_ENUMT(DataType_t) type;
    int a = cg_goto(r->fn, r->base, "BaseIterativeData_t", 1, "end") ? 0 : find_array("TimeValues", &size, &type);
    if (!a)
        return 0; /* IterationValues alone: steps without times */
    if (size != steps)
        return tpk_diag_fail(r->diag, "%s: BaseIterativeData '%s': %lld TimeValues, expected %d (NumberOfSteps)",
                             r->path, name, (long long)size, steps);
    out->times = malloc(sizeof *out->times * (size_t)steps);
    if (!out->times || cg_array_read_as(a, CGNS_ENUMV(RealDouble), out->times))
        return CGNS_FAIL(r, "BaseIterativeData '%s': cannot read its %d TimeValues", name, steps);
    return 0;
}

/* Solution names and locations of a zone: location[S-1] AT_VERTEX, AT_CELL, or -1 (left out). */
static int solution_locations(const cgns_reader *r, const cgns_zone *zone, int count, int *location,
                              char (*names)[33])
{
    int skipped = 0;
    for (int s = 1; s <= count; s++) {
        CGNS_ENUMT(GridLocation_t) at;
        CGNS_ENUMT(PointSetType_t) set = CGNS_ENUMV(PointSetTypeNull);
        cgsize_t points = 0;
        if (cg_sol_info(r->fn, r->base, zone->index, s, names[s - 1], &at))
            return CGNS_FAIL(r, "zone '%s': cannot read FlowSolution %d", zone->name, s);
        cg_sol_ptset_info(r->fn, r->base, zone->index, s, &set, &points);
        location[s - 1] = set != CGNS_ENUMV(PointSetTypeNull) ? -1
                          : at == CGNS_ENUMV(Vertex)           ? AT_VERTEX
                          : at == CGNS_ENUMV(CellCenter)       ? AT_CELL
                                                               : -1;
        skipped += location[s - 1] < 0;
    }
    if (skipped)
        tpk_diag_warn(r->diag, "%s: zone '%s': left out %d FlowSolutions that are not at Vertex or CellCenter, or "
                      "cover only a point set", r->path, zone->name, skipped);
    return 0;
}

/* IOSS's per-location index arrays: map[2 * step + location] = solution (1-based). Returns 1 when found. */
static int read_index_arrays(const cgns_reader *r, const cgns_zone *zone, int count, const int *location, int *map)
{
    static const char *const arrays[2] = {"VertexSolutionIndices", "CellCenterIndices"};
    int found = 0;
    for (int l = 0; l < 2; l++) {
        cgsize_t size = 0;
        CGNS_ENUMT(DataType_t) type;
        int a = find_array(arrays[l], &size, &type), *index = a ? malloc(sizeof *index * (size_t)r->steps) : NULL;
        if (!a)
            continue;
        if (!index || size != r->steps) {
            free(index);
            return tpk_diag_fail(r->diag, "%s: zone '%s': ZoneIterativeData %s has %lld entries, expected %d (one per "
                                 "step)", r->path, zone->name, arrays[l], (long long)size, r->steps);
        }
        if (cg_array_read_as(a, CGNS_ENUMV(Integer), index)) {
            free(index);
            return CGNS_FAIL(r, "zone '%s': cannot read ZoneIterativeData %s", zone->name, arrays[l]);
        }
        for (int s = 0; s < r->steps; s++)
            if (index[s] >= 1 && index[s] <= count && location[index[s] - 1] == l)
                map[2 * s + l] = index[s];
        free(index);
        found = 1;
    }
    return found;
}

/* FlowSolutionPointers by name into map; returns 1 when a pointer names no solution, -1 on error. */
static int read_pointers(const cgns_reader *r, const cgns_zone *zone, int count, const int *location,
                         char (*names)[33], int *map)
{
    cgsize_t size = 0;
    CGNS_ENUMT(DataType_t) type;
    int a = find_array("FlowSolutionPointers", &size, &type);
    if (!a)
        return 0;
    if ((int64_t)size != 32 * (int64_t)r->steps)
        return tpk_diag_fail(r->diag, "%s: zone '%s': FlowSolutionPointers has %lld characters, expected %d (32 per "
                             "step)", r->path, zone->name, (long long)size, 32 * r->steps);
    char *text = malloc((size_t)size);
    if (!text || cg_array_read(a, text)) {
        free(text);
        return CGNS_FAIL(r, "zone '%s': cannot read FlowSolutionPointers", zone->name);
    }
    int rc = 0;
    for (int s = 0; s < r->steps && rc == 0; s++) {
        char name[33];
        memcpy(name, text + 32 * s, 32);
        name[32] = 0;
        for (int k = 31; k >= 0 && (name[k] == ' ' || name[k] == 0); k--)
            name[k] = 0;
        int sol = 0;
        for (int k = 0; k < count && !sol; k++)
            sol = !strcmp(names[k], name) ? k + 1 : 0;
        if (sol && location[sol - 1] >= 0)
            map[2 * s + location[sol - 1]] = sol;
        else if (!sol && name[0] && strcmp(name, "Null"))
            rc = 1;
    }
    free(text);
    return rc;
}

/* IOSS's descriptor "Step" = N in a FlowSolution: it belongs to step N. */
static void read_step_descriptors(const cgns_reader *r, const cgns_zone *zone, int count, const int *location,
                                  int *map)
{
    for (int s = 1; s <= count; s++) {
        int descriptors = 0;
        if (location[s - 1] < 0 || cg_goto(r->fn, r->base, "Zone_t", zone->index, "FlowSolution_t", s, "end") ||
            cg_ndescriptors(&descriptors))
            continue;
        for (int d = 1; d <= descriptors; d++) {
            char name[33], *text = NULL;
            if (cg_descriptor_read(d, name, &text))
                continue;
            int step = !strcmp(name, "Step") ? atoi(text) : 0;
            if (step >= 1 && step <= r->steps)
                map[2 * (step - 1) + location[s - 1]] = s;
            cg_free(text);
        }
    }
}

static int any_step(const cgns_reader *r, const int *map)
{
    for (int i = 0; i < 2 * r->steps; i++)
        if (map[i])
            return 1;
    return 0;
}

/* Which solution each step takes, per location (0: none). */
static int step_map(const cgns_reader *r, const cgns_zone *zone, int count, const int *location, char (*names)[33],
                    int *map)
{
    char name[33];
    int rc = r->steps ? cg_ziter_read(r->fn, r->base, zone->index, name) : CG_NODE_NOT_FOUND;
    if (rc == CG_NODE_NOT_FOUND)
        return 0;
    if (rc || cg_goto(r->fn, r->base, "Zone_t", zone->index, "ZoneIterativeData_t", 1, "end"))
        return CGNS_FAIL(r, "zone '%s': cannot read its ZoneIterativeData", zone->name);
    if (read_index_arrays(r, zone, count, location, map) < 0)
        return -1;
    if (!any_step(r, map)) {
        if (cg_goto(r->fn, r->base, "Zone_t", zone->index, "ZoneIterativeData_t", 1, "end"))
            return CGNS_FAIL(r, "zone '%s': cannot read its ZoneIterativeData", zone->name);
        rc = read_pointers(r, zone, count, location, names, map);
        if (rc < 0)
            return -1;
        if (rc == 1) /* a pointer names no solution: none of them is trusted */
            memset(map, 0, sizeof *map * 2 * (size_t)r->steps);
    }
    if (!any_step(r, map))
        read_step_descriptors(r, zone, count, location, map);
    if (!any_step(r, map))
        tpk_diag_warn(r->diag, "%s: zone '%s': its ZoneIterativeData points at no FlowSolution of the zone: its "
                      "solutions are read as static fields", r->path, zone->name);
    return 0;
}

/* The slot for (name, location) with at least `steps` steps: created NaN, or widened with its first
 * step repeated (a static field holds at every step). NULL when out of memory. */
static field_slot *slot_for(field_table *t, const char *name, int location, int steps)
{
    field_slot *slot = NULL;
    for (int i = 0; i < t->count && !slot; i++)
        if (t->slots[i].location == location && !strcmp(t->slots[i].name, name))
            slot = &t->slots[i];
    size_t n = (size_t)t->per_location[location];
    if (!slot) {
        if (t->count == t->cap) {
            int cap = t->cap ? 2 * t->cap : 8;
            field_slot *grown = realloc(t->slots, sizeof *grown * (size_t)cap);
            if (!grown)
                return NULL;
            t->slots = grown, t->cap = cap;
        }
        slot = &t->slots[t->count];
        memset(slot, 0, sizeof *slot);
        snprintf(slot->name, sizeof slot->name, "%s", name);
        slot->location = location, slot->steps = 1, slot->zone = -1;
        if (!(slot->values = malloc(sizeof *slot->values * (n ? n : 1))))
            return NULL;
        for (size_t i = 0; i < n; i++)
            slot->values[i] = NAN;
        t->count++;
    }
    if (slot->steps < steps) {
        float *grown = realloc(slot->values, sizeof *grown * n * (size_t)steps);
        if (!grown)
            return NULL;
        for (int s = slot->steps; s < steps; s++)
            memcpy(grown + n * (size_t)s, grown, sizeof *grown * n);
        slot->values = grown, slot->steps = steps;
    }
    return slot;
}

typedef struct solution_ref {
    const cgns_zone *zone;
    int index, location, step; /* step -1: static */
    const char *name;
} solution_ref;

/* The values stored for `field` of the solution (rind planes included) against what the zone needs: 1
 * when they match, 0 when a lenient caller drops the field, -1 on error. */
static int field_size_ok(const cgns_reader *r, const solution_ref *sol, const char *field, int64_t expected)
{
    int rind[6] = {0};
    cgsize_t size = 0;
    CGNS_ENUMT(DataType_t) type;
    if (cg_goto(r->fn, r->base, "Zone_t", sol->zone->index, "FlowSolution_t", sol->index, "end"))
        return CGNS_FAIL(r, "zone '%s': cannot read FlowSolution '%s'", sol->zone->name, sol->name);
    if (cg_rind_read(rind) != CG_OK)
        memset(rind, 0, sizeof rind);
    int64_t stored = expected + rind[0] + rind[1];
    if (sol->zone->structured) {
        stored = 1;
        for (int a = 0; a < 3; a++)
            stored *= sol->zone->dims[a] - (sol->location == AT_CELL) + rind[2 * a] + rind[2 * a + 1];
    }
    if (!find_array(field, &size, &type))
        return CGNS_FAIL(r, "zone '%s' FlowSolution '%s': cannot find field '%s'", sol->zone->name, sol->name, field);
    if (size == stored)
        return 1;
    char place[96];
    snprintf(place, sizeof place, "zone '%s' FlowSolution '%s'", sol->zone->name, sol->name);
    if (tpk_diag_field_problem(r->diag, field, stored, size, place) == 0)
        return 0;
    return tpk_diag_fail(r->diag, "%s: %s field '%s' has %lld values, expected %lld (one per %s)", r->path, place,
                         field, (long long)size, (long long)stored, sol->location == AT_CELL ? "cell" : "vertex");
}

/* Field F of a solution into its slot: one step, or every step for a static solution. */
static int read_field(const cgns_reader *r, const solution_ref *sol, int f, field_table *t, float *buf)
{
    char field[33];
    CGNS_ENUMT(DataType_t) type;
    if (cg_field_info(r->fn, r->base, sol->zone->index, sol->index, f, &type, field))
        return CGNS_FAIL(r, "zone '%s' FlowSolution '%s': cannot read field %d", sol->zone->name, sol->name, f);
    if (type == CGNS_ENUMV(Character))
        return 0;
    int64_t n = sol->location == AT_CELL ? sol->zone->cells : sol->zone->vertices;
    int ok = field_size_ok(r, sol, field, n);
    if (ok <= 0)
        return ok;
    cgsize_t lo[3] = {1, 1, 1}, hi[3];
    for (int a = 0; a < 3; a++)
        hi[a] = sol->zone->structured ? (cgsize_t)(sol->zone->dims[a] - (sol->location == AT_CELL)) : (cgsize_t)n;
    if (cg_field_read(r->fn, r->base, sol->zone->index, sol->index, field, CGNS_ENUMV(RealSingle), lo, hi, buf))
        return CGNS_FAIL(r, "zone '%s' FlowSolution '%s': cannot read field '%s'", sol->zone->name, sol->name, field);
    char name[TPK_NAME_MAX];
    snprintf(name, sizeof name, "%s", field);
    field_slot *slot = slot_for(t, name, sol->location, sol->step < 0 ? 1 : r->steps);
    if (slot && sol->step < 0 && slot->zone == sol->zone->index && slot->solution != sol->index) {
        snprintf(name, sizeof name, "%s/%s", sol->name, field); /* a second static solution of the zone */
        slot = slot_for(t, name, sol->location, 1);
    }
    if (!slot)
        return tpk_diag_fail(r->diag, "%s: out of memory for field '%s'", r->path, field);
    if (sol->step < 0)
        slot->zone = sol->zone->index, slot->solution = sol->index;
    size_t per = (size_t)t->per_location[sol->location];
    int64_t first = sol->location == AT_CELL ? sol->zone->first_cell : sol->zone->first_point;
    for (int s = sol->step < 0 ? 0 : sol->step; s < (sol->step < 0 ? slot->steps : sol->step + 1); s++)
        memcpy(slot->values + per * (size_t)s + first, buf, sizeof *buf * (size_t)n);
    return 0;
}

static int read_solution(const cgns_reader *r, const solution_ref *sol, field_table *t, float *buf)
{
    int fields = 0;
    if (cg_nfields(r->fn, r->base, sol->zone->index, sol->index, &fields))
        return CGNS_FAIL(r, "zone '%s': cannot read FlowSolution '%s'", sol->zone->name, sol->name);
    for (int f = 1; f <= fields; f++)
        if (read_field(r, sol, f, t, buf))
            return -1;
    return 0;
}

/* Every solution of one zone: those a step points at into that step, the rest static. */
static int read_zone(const cgns_reader *r, const cgns_zone *zone, field_table *t)
{
    int count = 0;
    if (cg_nsols(r->fn, r->base, zone->index, &count))
        return CGNS_FAIL(r, "zone '%s': cannot read its FlowSolutions", zone->name);
    if (count < 1)
        return 0;
    int *location = calloc((size_t)count, sizeof *location);
    int *map = calloc((size_t)(2 * r->steps + 2), sizeof *map);
    char(*names)[33] = calloc((size_t)count, sizeof *names);
    float *buf = malloc(sizeof *buf * (size_t)(zone->vertices > zone->cells ? zone->vertices : zone->cells));
    int rc = location && map && names && buf ? 0 : tpk_diag_fail(r->diag, "%s: out of memory", r->path);
    if (rc == 0)
        rc = solution_locations(r, zone, count, location, names);
    if (rc == 0)
        rc = step_map(r, zone, count, location, names, map);
    for (int s = 1; rc == 0 && s <= count; s++) {
        solution_ref sol = {zone, s, location[s - 1], -1, names[s - 1]};
        for (int step = 0; step < r->steps && sol.location >= 0; step++)
            if (map[2 * step + sol.location] == s) {
                sol.step = step;
                if ((rc = read_solution(r, &sol, t, buf)) != 0)
                    break;
            }
        if (rc == 0 && sol.step < 0 && sol.location >= 0)
            rc = read_solution(r, &sol, t, buf);
    }
    free(location);
    free(map);
    free(names);
    free(buf);
    return rc;
}

int cgns_read_solutions(const cgns_reader *r, const cgns_zone *zones, int zone_count, tpk_mesh *out)
{
    field_table t = {.per_location = {out->point_count, out->cell_count}};
    int rc = 0;
    for (int z = 0; z < zone_count && rc == 0; z++)
        rc = read_zone(r, &zones[z], &t);
    for (int i = 0; i < t.count; i++) {
        field_slot *slot = &t.slots[i];
        if (rc == 0 && tpk_mesh_add_field(out, slot->name, slot->location == AT_CELL ? TPK_ASSOC_TET : TPK_ASSOC_POINT,
                                          1, slot->steps, slot->values))
            rc = tpk_diag_fail(r->diag, "%s: out of memory for field '%s'", r->path, slot->name);
        else if (rc == 0)
            slot->values = NULL;
        free(slot->values);
    }
    free(t.slots);
    return rc;
}
