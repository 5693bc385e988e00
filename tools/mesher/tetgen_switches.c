/* TetGen's command-line switches as tetpack builds and accepts them: the quality options become
 * q/a switches; expert switches are limited to those that keep TetGen in memory, quiet and on a
 * piecewise linear complex (no refinement of an input mesh, no files, no extra output). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "mesher.h"

/* Switches that take a number (digits, '.', 'e', '+', '-', '/' as TetGen reads them); p's is the
 * facet-merging angle. */
static const char with_number[] = "pqaTOoS";
/* Every surface run: a PLC (p) whose facets are never merged, even when they meet at nearly 180
 * degrees (TetGen's default merges facets within 0.1 degree of flat and re-triangulates them, which
 * moves the boundary: 1e-9 of the volume on float STL parts); 0-based (z) and quiet (Q). Expert
 * switches come after, so "p179.9" there restores TetGen's merging (fewer tets). */
#define SURFACE_BASE "p180zQ"

/* Switches without one. */
static const char plain[] = "YMzQ";

static int number_char(char c)
{
    return (c >= '0' && c <= '9') || c == '.' || c == 'e' || c == 'E' || c == '+' || c == '-' || c == '/';
}

int tpk_tetgen_check_switches(const char *switches, tpk_diag *diag)
{
    if (!switches)
        return 0;
    size_t n = strlen(switches);
    if (n > 64)
        return tpk_diag_fail(diag, "--tetgen-switches: at most 64 characters, found %zu", n);
    for (size_t i = 0; i < n;) {
        char c = switches[i];
        if (c == '-' && i == 0) {
            i++;
            continue;
        }
        if (c && strchr(with_number, c)) {
            for (i++; i < n && number_char(switches[i]); i++)
                ;
            continue;
        }
        if (c && strchr(plain, c)) {
            i++;
            continue;
        }
        return tpk_diag_fail(diag, "--tetgen-switches '%s': '%c' at position %zu is not allowed; allowed are "
                             "p, q, a, Y, M, T, O, o, S, z, Q and their numbers (other switches read or write "
                             "files, refine an input mesh, print, or change what TetGen outputs)",
                             switches, c, i + 1);
    }
    return 0;
}

int tpk_tetgen_surface_switches(const tpk_tetgen_options *o, char *buf, size_t cap, tpk_diag *diag)
{
    static const tpk_tetgen_options defaults;
    if (!o)
        o = &defaults;
    if (o->switches) {
        if (o->radius_edge_ratio || o->min_dihedral || o->max_volume)
            return tpk_diag_fail(diag, "--tetgen-switches replaces --tetgen-quality and --tetgen-max-volume; "
                                 "give one or the other");
        if (tpk_tetgen_check_switches(o->switches, diag))
            return -1;
        snprintf(buf, cap, "%s%s", SURFACE_BASE, o->switches + (o->switches[0] == '-'));
        return 0;
    }
    double ratio = o->radius_edge_ratio == 0 ? 1.414 : o->radius_edge_ratio;
    if (ratio > 0 && !(ratio >= 1.0 && ratio <= 1000.0))
        return tpk_diag_fail(diag, "--tetgen-quality: the radius-edge ratio must be from 1.0 to 1000 (TetGen may "
                             "not finish below 1), found %g", ratio);
    if (!(o->min_dihedral >= 0 && o->min_dihedral <= 30))
        return tpk_diag_fail(diag, "--tetgen-quality: the smallest dihedral angle must be from 0 to 30 degrees "
                             "(TetGen may not finish above), found %g", o->min_dihedral);
    if (!(o->max_volume >= 0 && isfinite(o->max_volume)))
        return tpk_diag_fail(diag, "--tetgen-max-volume: expected a volume > 0, found %g", o->max_volume);
    int at = snprintf(buf, cap, "%s", SURFACE_BASE);
    if (ratio > 0)
        at += snprintf(buf + at, cap - (size_t)at, "q%.6g", ratio);
    if (ratio > 0 && o->min_dihedral > 0)
        at += snprintf(buf + at, cap - (size_t)at, "/%.6g", o->min_dihedral);
    if (o->max_volume > 0)
        snprintf(buf + at, cap - (size_t)at, "a%.17g", o->max_volume);
    return 0;
}
