/* tetpack convert: source mesh -> .tpk. */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "convert/convert.h"
#include "convert/merge_vertices.h"
#include "base/progress.h"
#include "base/strbuf.h"
#include "import/surface/surface.h"

static const char convert_help[] =
    "usage: tetpack convert INPUT OUTPUT.tpk [options]\n"
    "\n"
    "Reads a volume mesh, or a surface or point cloud (below), in any format listed at the end, splits\n"
    "voxels, hexahedra, wedges and pyramids into tets conformally, orients every tet positively with\n"
    "exact predicates, reorders along a Hilbert curve, builds neighbors, the chosen layouts and the\n"
    "shell, and writes OUTPUT atomically.\n"
    "\n"
    "  --layout tet16|tet20|tet32  layout to store (repeatable; default tet16)\n"
    "  --field NAME                keep this field (repeatable; NAME:mag or NAME:x|y|z for vectors;\n"
    "                              default: every scalar point field)\n"
    "  --cell-to-point             average cell fields to points (each point: the mean over its cells);\n"
    "                              without --field, scalar cell fields are then kept too\n"
    "  --strict-fields             a field the importer cannot read (an OpenFOAM field using #calc) is an\n"
    "                              error; by default it is left out with a warning saying where and why\n"
    "  --higher-order split|corners  second-order cells (quadratic tetra, hexahedra, wedges, pyramids) and\n"
    "                              Lagrange tetra, hexahedra and wedges of order 3 to 10:\n"
    "                              split (default) into linear cells at all their nodes, face and cell\n"
    "                              centres they lack placed and valued by their own shape functions;\n"
    "                              corners: reduced to their corner nodes (fewer tets, values dropped)\n"
    "  --max-error E               refine the tets (conformingly, by edge bisection) until, inside every\n"
    "                              source cell, each point field at every step is within E of the cell's\n"
    "                              own interpolant (trilinear for a hexahedron, the quadratic functions of\n"
    "                              a second-order cell), as a fraction of the field's range, and the tets\n"
    "                              within E of the cell's map, as a fraction of the bounds diagonal. E is\n"
    "                              a fraction (0.01) or a percentage (1%%), 0 < E < 1. The bound is proved\n"
    "                              per tet (Bernstein coefficients), not sampled; META records it and the\n"
    "                              largest error proved. Tetrahedra, voxels, hexahedra, wedges and their\n"
    "                              quadratic kinds, Lagrange tetra of order 3-10, hexahedra of order 3-4\n"
    "                              and wedges of order 3-6; not with pyramids, polyhedra, higher orders,\n"
    "                              14- and 15-node tetra, --higher-order corners,\n"
    "                              --merge-duplicates or --parts\n"
    "  --max-error-field NAME      bound only this point field (repeatable; default: every point field)\n"
    "  --subdivide L               for comparison: instead of --max-error, cut every tet into 8 at its\n"
    "                              edges' midpoints (placed by the cell's own map; every edge halved) L\n"
    "                              times (1-5), a uniform subdivision as ParaView's levels; the bound proved\n"
    "                              over the result is reported and in META (max_error_measured), none\n"
    "                              promised\n"
    "  --zstd LEVEL                compress chunks with zstd (1-22; default: uncompressed, zero-copy)\n"
    "  --no-reorder                keep the source vertex and cell order\n"
    "  --cull                      store culling blocks (spec §17, format 1.4; about 1 byte a tet): an\n"
    "                              iso render then decodes only the blocks of tets that may hold the surface\n"
    "  --levels N                  add up to N levels of detail (spec §16; 1-8): each a complete mesh of\n"
    "                              the domain with about a sixth of the tets of the one before (vertices\n"
    "                              collapsed, tets kept positive), stored in the file; fewer when the\n"
    "                              mesh stops coarsening. render --level K and --max-ms pick one,\n"
    "                              extract --level K writes one\n"
    "  --level-shell-error F       how far a level's shell may lie inside the file's, as a fraction of the\n"
    "                              bounding-box diagonal (0-0.1; default 0.002). 0: shell vertices move\n"
    "                              only within flat pieces of the shell, which then stays exactly\n"
    "  --parts N                   write a part set instead (spec §15): OUTPUT is its manifest (name it\n"
    "                              .tpkset) and N part files <stem>-<p>.tpk beside it, each a complete\n"
    "                              .tpk; the tets are cut into N runs of equal length along the Hilbert\n"
    "                              order, and the faces on each cut are linked across it (LINK). The\n"
    "                              whole mesh is converted in memory first (inputs are not streamed)\n"
    "\n"
    "Orientation: a tet's node order is a labeling. Inverted tets, polyhedra given inside out, and\n"
    "cells whose every tet is negative (a file or block written in the mirrored node order) are turned\n"
    "over and counted; a cell partly inverted (a folded hexahedron) is split from an added point or is a\n"
    "bad cell. An inverted tet that would fold against a neighbour once turned over is a bad cell.\n"
    "  --strict-orientation        refuse inverted tets and mirrored cells instead, naming the first one\n"
    "  --reorient                  accepted for old command lines: turning over is now the default\n"
    "\n"
    "Folds: tets on the same side of a face they share (overlapping cells, e.g. in boundary layers) are\n"
    "an error naming the first face, its cells and points; a written file never links them.\n"
    "  --cut-folds                 cut the adjacency at each folded face instead: both faces become\n"
    "                              shell faces, both cells are kept (counted)\n"
    "\n"
    "Repairs: nothing else is fixed unasked. Without these options a degenerate cell is an error naming\n"
    "the first one and the count, and duplicate points stay apart (tetpack check reports them as\n"
    "duplicate_vertex); with them each is fixed, counted in the summary and recorded in the file's META\n"
    "(\"repairs\", with the orientation and fold counts):\n"
    "  --drop-degenerate           drop zero-volume tets, and cells that --merge-duplicates collapsed\n"
    "  --merge-duplicates[=TOL]    before splitting, merge points with exactly equal coordinates, or\n"
    "                              with TOL (1e-15 <= TOL <= 1) points within TOL times the bounding-box\n"
    "                              diagonal; each point joins the lowest-id kept point in reach (no\n"
    "                              chains), keeps that point's field values; cells are renumbered, and\n"
    "                              one that collapses is an error (or dropped with --drop-degenerate)\n"
    "\n"
    "  --skip-bad-cells            leave out bad cells (counted) instead of failing: cells too warped or\n"
    "                              non-convex to split even with added points, and inverted tets that\n"
    "                              would fold if turned over\n"
    "  --format NAME               force the input format, by a name listed below (default: from the\n"
    "                              extension, else the first bytes)\n"
    "  --threads N                 worker threads (default: all cores)\n"
    "\n"
    "Closed surfaces (STL ASCII/binary, OFF, PLY) are filled with tets by TetGen (refused when open,\n"
    "not manifold or self-intersecting); point clouds (CSV with a header x,y,z,NAME..., PLY vertices)\n"
    "become their Delaunay tetrahedralization, other columns/properties becoming point fields.\n"
    "  --tetgen-quality R[/A]      largest radius-edge ratio R (1 to 1000; default 1.414) and smallest\n"
    "                              dihedral angle A in degrees (0 to 30), or 'off' for no refinement\n"
    "  --tetgen-max-volume V       largest tet volume (default: none)\n"
    "  --tetgen-switches S         expert: TetGen switches instead of the two above, from p q a Y M T O\n"
    "                              o S z Q with their numbers, after p180zQ (always)\n"
    "  --max-tets N                refuse a volume bound (--tetgen-max-volume, or a in the switches)\n"
    "                              estimated to make more than N tets: enclosed volume / bound x 2\n"
    "                              (default 10000000: a few GiB and minutes)\n"
    "  --tetgen-time-limit S       stop TetGen after S seconds (default 3600; 0: no limit)\n"
    "  --json                      print the summary as JSON\n"
    "  --quiet                     print nothing on success (and no progress)\n"
    "  --progress / --no-progress  a progress bar per stage on stderr (import, tetrahedralize, reorder,\n"
    "                              orient, connect, write; import moves with the bytes read by the text\n"
    "                              readers, tetrahedralize with the cells split; default: when stderr is\n"
    "                              a terminal; the file written is the same either way)\n"
    "\n"
    "TetGen runs in a child process: a crash inside it, a time-out, or its memory running out (it may use\n"
    "the machine's memory) is an error naming the input; points that span no volume (all on one plane,\n"
    "decided exactly) or coordinates beyond 1e50 in magnitude (or spanning less than 1e-50) are refused\n"
    "before it starts. With progress (above) a line shows each TetGen stage and its seconds.\n"
    "\n"
    "Input formats (--format NAME; tetpack formats says what each carries):\n";

typedef struct convert_args {
    tpk_convert_options options;
    tpk_tetgen_options tetgen;
    const char *fields[256];
    const char *error_fields[256];
    int json, quiet, strict_fields;
    int progress; /* -1: when stderr is a terminal */
} convert_args;

static int parse_layout(const char *text, unsigned *layouts)
{
    if (!strcmp(text, "tet16"))
        *layouts |= TPK_LAYOUT_BIT_TET16;
    else if (!strcmp(text, "tet20"))
        *layouts |= TPK_LAYOUT_BIT_TET20;
    else if (!strcmp(text, "tet32"))
        *layouts |= TPK_LAYOUT_BIT_TET32;
    else
        return -1;
    return 0;
}

/* NULL: exactly equal points. A tolerance is a fraction of the bounding-box diagonal. */
static int parse_tolerance(const char *text, tpk_convert_options *o)
{
    o->merge_duplicates = 1;
    o->merge_tolerance = 0.0;
    if (!text)
        return 0;
    char *end = NULL;
    double tolerance = strtod(text, &end);
    if (!*text || *end || !(tolerance >= TPK_MERGE_MIN_TOLERANCE && tolerance <= 1.0))
        return -1;
    o->merge_tolerance = tolerance;
    return 0;
}

/* E as a fraction (0.01) or a percentage (1%), 0 < E < 1. */
static int parse_max_error(const char *text, double *out)
{
    char *end = NULL;
    double e = strtod(text, &end);
    if (end == text)
        return -1;
    if (*end == '%')
        e /= 100, end++;
    if (*end || !(e > 0 && e < 1))
        return -1;
    *out = e;
    return 0;
}

/* --tetgen-*: 1 when argv[*i] is one (consumed), 0 when not, or the usage exit code. */
static int parse_tetgen_option(int argc, char **argv, int *i, convert_args *a)
{
    const char *arg = argv[*i], *v;
    double two[2] = {0, 0};
    if (!strncmp(arg, "--tetgen-quality", 16)) {
        if (!(v = tpk_cli_value(argc, argv, i, "--tetgen-quality")))
            return tpk_cli_fail("convert", "--tetgen-quality expects RATIO, RATIO/ANGLE or off");
        char *end;
        two[0] = strtod(v, &end);
        if (*end == '/')
            two[1] = strtod(end + 1, &end);
        if (!strcmp(v, "off"))
            two[0] = -1, end = (char *)"";
        if (*end || end == v || two[0] == 0)
            return tpk_cli_fail("convert", "--tetgen-quality expects RATIO, RATIO/ANGLE or off, found '%s'", v);
        a->tetgen.radius_edge_ratio = two[0];
        a->tetgen.min_dihedral = two[1];
    } else if (!strncmp(arg, "--tetgen-max-volume", 19)) {
        if (!(v = tpk_cli_value(argc, argv, i, "--tetgen-max-volume")) || tpk_cli_parse_doubles(v, two, 1) ||
            !(two[0] > 0))
            return tpk_cli_fail("convert", "--tetgen-max-volume expects a volume > 0, found '%s'", v ? v : "");
        a->tetgen.max_volume = two[0];
    } else if (!strncmp(arg, "--tetgen-time-limit", 19)) {
        if (!(v = tpk_cli_value(argc, argv, i, "--tetgen-time-limit")) || tpk_cli_parse_doubles(v, two, 1) ||
            !(two[0] >= 0))
            return tpk_cli_fail("convert", "--tetgen-time-limit expects seconds >= 0 (0: no limit), found '%s'",
                                v ? v : "");
        a->tetgen.time_limit = two[0] > 0 ? two[0] : -1;
    } else if (!strncmp(arg, "--max-tets", 10)) {
        char *end = NULL;
        long long n = (v = tpk_cli_value(argc, argv, i, "--max-tets")) ? strtoll(v, &end, 10) : 0;
        if (!v || !*v || *end || n < 1)
            return tpk_cli_fail("convert", "--max-tets expects a tet count >= 1, found '%s'", v ? v : "");
        a->tetgen.max_tets = n;
    } else if (!strncmp(arg, "--tetgen-switches", 17)) {
        if (!(v = tpk_cli_value(argc, argv, i, "--tetgen-switches")))
            return tpk_cli_fail("convert", "--tetgen-switches expects TetGen switches");
        a->tetgen.switches = v;
    } else {
        return 0;
    }
    return 1;
}

static int parse_args(int argc, char **argv, convert_args *a)
{
    const char *positional[2];
    int npos = 0, rc;
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i], *v;
        if (!strcmp(arg, "--help") || !strcmp(arg, "-h")) {
            fputs(convert_help, stdout);
            tpk_cli_print_formats(stdout);
            exit(TPK_EXIT_OK);
        } else if (!strncmp(arg, "--layout", 8)) {
            if (!(v = tpk_cli_value(argc, argv, &i, "--layout")) || parse_layout(v, &a->options.layouts))
                return tpk_cli_fail("convert", "--layout expects tet16, tet20 or tet32, found '%s'", v ? v : "");
        } else if (!strncmp(arg, "--field", 7)) {
            if (!(v = tpk_cli_value(argc, argv, &i, "--field")) || !*v)
                return tpk_cli_fail("convert", "--field expects a field name");
            if (a->options.field_count >= 256)
                return tpk_cli_fail("convert", "too many --field options (at most 256)");
            a->fields[a->options.field_count++] = v;
        } else if (!strncmp(arg, "--zstd", 6)) {
            if (!(v = tpk_cli_value(argc, argv, &i, "--zstd")) ||
                tpk_cli_parse_int(v, 1, 22, &a->options.zstd_level))
                return tpk_cli_fail("convert", "--zstd expects a level from 1 to 22, found '%s'", v ? v : "");
        } else if (!strncmp(arg, "--threads", 9)) {
            if (!(v = tpk_cli_value(argc, argv, &i, "--threads")) ||
                tpk_cli_parse_int(v, 1, 1024, &a->options.threads))
                return tpk_cli_fail("convert", "--threads expects a number from 1 to 1024, found '%s'", v ? v : "");
        } else if (!strncmp(arg, "--format", 8)) {
            if (!(v = tpk_cli_value(argc, argv, &i, "--format")))
                return tpk_cli_fail("convert", "--format expects a format name (tetpack formats lists them)");
            a->options.format = v;
        } else if (!strcmp(arg, "--no-reorder")) {
            a->options.no_reorder = 1;
        } else if (!strcmp(arg, "--cull")) {
            a->options.cull = 1;
        } else if (!strncmp(arg, "--level-shell-error", 19) && (!arg[19] || arg[19] == '=')) {
            char *end = NULL;
            double e = (v = tpk_cli_value(argc, argv, &i, "--level-shell-error")) ? strtod(v, &end) : -1;
            if (!v || !*v || *end || !(e >= 0 && e <= 0.1))
                return tpk_cli_fail("convert", "--level-shell-error expects a fraction of the bounding-box diagonal "
                                    "from 0 to 0.1, found '%s'", v ? v : "");
            a->options.level_shell_error = e;
        } else if (!strncmp(arg, "--levels", 8)) {
            if (!(v = tpk_cli_value(argc, argv, &i, "--levels")) || tpk_cli_parse_int(v, 1, 8, &a->options.levels))
                return tpk_cli_fail("convert", "--levels expects a number of levels from 1 to 8, found '%s'",
                                    v ? v : "");
        } else if (!strncmp(arg, "--parts", 7)) {
            if (!(v = tpk_cli_value(argc, argv, &i, "--parts")) || tpk_cli_parse_int(v, 1, 65536, &a->options.parts))
                return tpk_cli_fail("convert", "--parts expects a number of parts from 1 to 65536, found '%s'",
                                    v ? v : "");
        } else if (!strcmp(arg, "--drop-degenerate")) {
            a->options.drop_degenerate = 1;
        } else if (!strcmp(arg, "--reorient")) {
            /* the default now; old command lines keep working */
        } else if (!strcmp(arg, "--strict-orientation")) {
            a->options.strict_orientation = 1;
        } else if (!strcmp(arg, "--strict-fields")) {
            a->strict_fields = 1;
        } else if (!strcmp(arg, "--cut-folds")) {
            a->options.cut_folds = 1;
        } else if (!strncmp(arg, "--merge-duplicates", 18) && (!arg[18] || arg[18] == '=')) {
            if (parse_tolerance(arg[18] ? arg + 19 : NULL, &a->options))
                return tpk_cli_fail("convert", "--merge-duplicates=TOL expects %g <= TOL <= 1 (a fraction of the "
                                    "bounding-box diagonal), found '%s'", TPK_MERGE_MIN_TOLERANCE, arg + 19);
        } else if (!strcmp(arg, "--skip-bad-cells")) {
            a->options.skip_bad_cells = 1;
        } else if (!strcmp(arg, "--higher-order")) {
            if (!(v = tpk_cli_value(argc, argv, &i, "--higher-order")) || (strcmp(v, "split") && strcmp(v, "corners")))
                return tpk_cli_fail("convert", "--higher-order expects split or corners, found '%s'", v ? v : "");
            a->options.higher_order_corners = !strcmp(v, "corners");
        } else if (!strncmp(arg, "--max-error-field", 17) && (!arg[17] || arg[17] == '=')) {
            if (!(v = tpk_cli_value(argc, argv, &i, "--max-error-field")) || !*v)
                return tpk_cli_fail("convert", "--max-error-field expects a point field's name");
            if (a->options.max_error_field_count >= 256)
                return tpk_cli_fail("convert", "too many --max-error-field options (at most 256)");
            a->error_fields[a->options.max_error_field_count++] = v;
        } else if (!strncmp(arg, "--max-error", 11) && (!arg[11] || arg[11] == '=')) {
            if (!(v = tpk_cli_value(argc, argv, &i, "--max-error")) || parse_max_error(v, &a->options.max_error))
                return tpk_cli_fail("convert", "--max-error expects a fraction (0.01) or a percentage (1%%) above 0 "
                                    "and below 1, found '%s'", v ? v : "");
        } else if (!strncmp(arg, "--subdivide", 11) && (!arg[11] || arg[11] == '=')) {
            if (!(v = tpk_cli_value(argc, argv, &i, "--subdivide")) || tpk_cli_parse_int(v, 1, 5, &a->options.subdivide))
                return tpk_cli_fail("convert", "--subdivide expects a number of levels from 1 to 5, found '%s'",
                                    v ? v : "");
        } else if (!strcmp(arg, "--cell-to-point")) {
            a->options.cell_to_point = 1;
        } else if (!strcmp(arg, "--json")) {
            a->json = 1;
        } else if (!strcmp(arg, "--quiet")) {
            a->quiet = 1;
        } else if (!strcmp(arg, "--progress")) {
            a->progress = 1;
        } else if (!strcmp(arg, "--no-progress")) {
            a->progress = 0;
        } else if ((rc = parse_tetgen_option(argc, argv, &i, a)) != 0) {
            if (rc != 1)
                return rc;
        } else if (arg[0] == '-' && arg[1]) {
            return tpk_cli_fail("convert", "unknown option '%s' (see tetpack convert --help)", arg);
        } else if (npos < 2) {
            positional[npos++] = arg;
        } else {
            return tpk_cli_fail("convert", "unexpected argument '%s': expected INPUT OUTPUT.tpk", arg);
        }
    }
    if (npos != 2)
        return tpk_cli_fail("convert", "expected INPUT and OUTPUT.tpk (see tetpack convert --help)");
    if (a->options.subdivide > 0 && a->options.max_error > 0)
        return tpk_cli_fail("convert", "--subdivide and --max-error: one or the other");
    if (a->options.subdivide > 0 && (a->options.higher_order_corners || a->options.merge_duplicates || a->options.parts))
        return tpk_cli_fail("convert", "--subdivide: not with --higher-order corners, --merge-duplicates or --parts");
    if (a->options.max_error_field_count > 0 && !(a->options.max_error > 0) && !(a->options.subdivide > 0))
        return tpk_cli_fail("convert", "--max-error-field needs --max-error E");
    if (a->options.max_error > 0 && a->options.higher_order_corners)
        return tpk_cli_fail("convert", "--max-error and --higher-order corners: the bound is against each cell's own "
                            "functions, which reducing to corners drops");
    if (a->options.max_error > 0 && a->options.merge_duplicates)
        return tpk_cli_fail("convert", "--max-error and --merge-duplicates: the bound holds each cell to its own "
                            "nodes, which merging renumbers; merge the source first");
    if (a->options.max_error > 0 && a->options.parts > 0)
        return tpk_cli_fail("convert", "--max-error and --parts: a part set does not record the bound");
    a->options.max_error_fields = a->options.max_error_field_count ? a->error_fields : NULL;
    if (a->options.levels > 0 && a->options.parts > 0)
        return tpk_cli_fail("convert", "--levels and --parts: levels of detail are for one file, not a part set");
    a->options.input = positional[0];
    a->options.output = positional[1];
    a->options.fields = a->options.field_count ? a->fields : NULL;
    return 0;
}

/* The stage now drawn, so that the next one (or the end) can complete its bar first. */
typedef struct stage_bar {
    const char *stage;
} stage_bar;

/* A new stage name means the previous stage is done (its bar at 100%, erased); NULL: the last is done.
 * A stage's own 100% (import after its last section) waits for that, so each bar is erased once. */
static void show_stage(void *user, const char *stage, double fraction)
{
    stage_bar *bar = user;
    if (bar->stage && (!stage || strcmp(stage, bar->stage)))
        tpk_progress_draw("convert", bar->stage, 1.0);
    bar->stage = stage;
    if (stage && fraction < 1.0)
        tpk_progress_draw("convert", stage, fraction);
}

/* One line per repair asked for, with what it did (also when it found nothing to do); orientation and
 * folds only when there was something to turn over or cut. */
static void print_repairs(const tpk_convert_options *o, const tpk_convert_report *r)
{
    if (r->inverted_fixed || r->mirrored_cells)
        printf("  orientation: %lld inverted tets and %lld mirrored cells turned over (node order; "
               "--strict-orientation refuses them)\n", (long long)r->inverted_fixed, (long long)r->mirrored_cells);
    if (o->cut_folds)
        printf("  repair --cut-folds: %lld folded faces cut (both sides now shell faces)\n", (long long)r->folds_cut);
    if (!o->merge_duplicates && !o->drop_degenerate) {
        if (!o->cut_folds)
            printf("  repairs: none asked for\n");
        return;
    }
    if (o->merge_duplicates && o->merge_tolerance > 0)
        printf("  repair --merge-duplicates=%g: %lld points merged into a twin within %g times the "
               "bounding-box diagonal\n", o->merge_tolerance, (long long)r->merged_vertices, o->merge_tolerance);
    else if (o->merge_duplicates)
        printf("  repair --merge-duplicates: %lld points merged into a twin with equal coordinates\n",
               (long long)r->merged_vertices);
    if (o->drop_degenerate)
        printf("  repair --drop-degenerate: %lld zero-volume tets and %lld cells collapsed by merging dropped\n",
               (long long)r->degenerate_dropped, (long long)r->collapsed_cells_dropped);
}

static void print_summary(const convert_args *a, const tpk_convert_report *r)
{
    if (a->json) {
        tpk_strbuf sb = {0};
        tpk_strbuf_printf(&sb, "{\"input\":");
        tpk_strbuf_json_string(&sb, a->options.input);
        tpk_strbuf_printf(&sb, ",\"output\":");
        tpk_strbuf_json_string(&sb, a->options.output);
        tpk_strbuf_printf(&sb,
                          ",\"source_points\":%lld,\"source_cells\":%lld,\"vertices\":%lld,\"tets\":%lld,"
                          "\"shell_faces\":%lld,\"inverted_fixed\":%lld,\"degenerate_dropped\":%lld,"
                          "\"fields\":%d,\"steps\":%d,\"output_bytes\":%llu,",
                          (long long)r->source_points, (long long)r->source_cells, (long long)r->vertices,
                          (long long)r->tets, (long long)r->shell_faces, (long long)r->inverted_fixed,
                          (long long)r->degenerate_dropped, r->field_count, r->step_count,
                          (unsigned long long)r->output_bytes);
        if (r->higher_order_cells > 0) /* only then: other outputs are as they were */
            tpk_strbuf_printf(&sb, "\"higher_order\":{\"mode\":\"%s\",\"cells\":%lld,\"added_points\":%lld},",
                              r->higher_order_split ? "split" : "corners", (long long)r->higher_order_cells,
                              (long long)r->higher_order_points);
        if (a->options.max_error > 0 || a->options.subdivide > 0) {
            tpk_strbuf_printf(&sb, "\"max_error\":{\"subdivide\":%d,\"requested\":%.9g,", r->max_error.subdivide,
                              r->max_error.requested);
            tpk_strbuf_printf(&sb, "\"measured\":%.9g,\"geometry\":%.9g,\"worst_field\":", r->max_error.field_error,
                              r->max_error.geometry_error);
            tpk_strbuf_json_string(&sb, r->max_error.worst_field);
            tpk_strbuf_printf(&sb, ",\"fields\":%d,\"tets_before\":%lld,\"vertices_added\":%lld,\"passes\":%d,"
                              "\"seconds\":%.6f},", r->max_error.fields, (long long)r->max_error.tets_before,
                              (long long)r->max_error.vertices_added, r->max_error.passes, r->max_error.seconds);
        }
        tpk_strbuf_printf(&sb,
                          "\"cells_split\":{\"tetra\":%lld,\"pyramid_into_2\":%lld,\"wedge_into_3\":%lld,"
                          "\"hexahedron_into_5\":%lld,\"hexahedron_into_6\":%lld},\"mirrored_cells\":%lld,"
                          "\"steiner_cells\":%lld,\"face_steiner_points\":%lld,\"polyhedra\":%lld,"
                          "\"fixed_boundary_cells\":%lld,\"bad_cells_skipped\":%lld,\"merged_vertices\":%lld,"
                          "\"collapsed_cells_dropped\":%lld,\"folds_cut\":%lld,\"thin_faces_recut\":%lld,"
                          "\"flat_tets\":%lld,\"repairs\":",
                          (long long)r->cells_into[1], (long long)r->cells_into[2], (long long)r->cells_into[3],
                          (long long)r->cells_into[5], (long long)r->cells_into[6], (long long)r->mirrored_cells,
                          (long long)r->steiner_cells, (long long)r->face_steiner_points,
                          (long long)r->polyhedra, (long long)r->fixed_boundary_cells, (long long)r->bad_cells_skipped,
                          (long long)r->merged_vertices, (long long)r->collapsed_cells_dropped, (long long)r->folds_cut,
                          (long long)r->thin_faces_recut, (long long)r->flat_tets);
        tpk_convert_repairs_json(&sb, &a->options, r);
        tpk_strbuf_printf(&sb, ",\"levels\":[");
        for (int k = 0; k < r->level_count; k++) {
            tpk_strbuf_printf(&sb, "%s{\"level\":%d,\"vertices\":%lld,\"tets\":%lld,\"bytes\":%llu,"
                              "\"error_samples\":%lld,\"error_max\":", k ? "," : "", k + 1,
                              (long long)r->level[k].vertices, (long long)r->level[k].tets,
                              (unsigned long long)r->level[k].bytes, (long long)r->level[k].error_samples);
            tpk_strbuf_json_number(&sb, r->level[k].error_max);
            tpk_strbuf_printf(&sb, ",\"error_rms\":");
            tpk_strbuf_json_number(&sb, r->level[k].error_rms);
            tpk_strbuf_printf(&sb, ",\"shell_distance\":");
            tpk_strbuf_json_number(&sb, r->level[k].shell_distance);
            tpk_strbuf_printf(&sb, ",\"shell_tolerance\":");
            tpk_strbuf_json_number(&sb, r->level[k].shell_tolerance);
            tpk_strbuf_printf(&sb, ",\"seconds\":%.6f}", r->level[k].seconds);
        }
        tpk_strbuf_printf(&sb,
                          "],\"seconds\":{\"import\":%.6f,\"tetrahedralize\":%.6f,\"orient\":%.6f,\"reorder\":%.6f,"
                          "\"connect\":%.6f,\"levels\":%.6f,\"write\":%.6f,\"total\":%.6f}}\n",
                          r->t_import, r->t_tetrahedralize, r->t_orient, r->t_reorder, r->t_connect, r->t_levels,
                          r->t_write, r->t_total);
        if (!sb.failed)
            fputs(sb.data, stdout);
        tpk_strbuf_free(&sb);
        return;
    }
    printf("%s: %lld tets, %lld vertices, %lld shell faces, %d field(s) x %d step(s), %.2f MiB\n",
           a->options.output, (long long)r->tets, (long long)r->vertices, (long long)r->shell_faces,
           r->field_count, r->step_count, (double)r->output_bytes / 1048576.0);
    printf("  source: %lld cells, %lld points\n", (long long)r->source_cells, (long long)r->source_points);
    if (a->options.subdivide > 0)
        printf("  subdivided %d times: proved %.3g of the range (%s), geometry %.3g of the diagonal; %lld tets into "
               "%lld (%lld points added)\n", r->max_error.subdivide, r->max_error.field_error,
               r->max_error.worst_field[0] ? r->max_error.worst_field : "no field", r->max_error.geometry_error,
               (long long)r->max_error.tets_before, (long long)r->tets, (long long)r->max_error.vertices_added);
    else if (a->options.max_error > 0)
        printf("  max error: %g requested; proved %.3g of the range (%s), geometry %.3g of the diagonal; %lld tets "
               "refined into %lld (%lld points added, %d passes)\n", r->max_error.requested, r->max_error.field_error,
               r->max_error.worst_field[0] ? r->max_error.worst_field : "no field", r->max_error.geometry_error,
               (long long)r->max_error.tets_before, (long long)r->tets, (long long)r->max_error.vertices_added,
               r->max_error.passes);
    if (r->higher_order_cells > 0 && r->higher_order_split)
        printf("  higher-order cells: %lld split whole at all their nodes (%lld face and cell centres added); the "
               "cell counts below are of their linear pieces\n", (long long)r->higher_order_cells,
               (long long)r->higher_order_points);
    else if (r->higher_order_cells > 0)
        printf("  higher-order cells: %lld reduced to their corners (--higher-order corners)\n",
               (long long)r->higher_order_cells);
    print_repairs(&a->options, r);
    if (r->cells_into[2] || r->cells_into[3] || r->cells_into[5] || r->cells_into[6] || r->steiner_cells ||
        r->bad_cells_skipped || r->polyhedra)
        printf("  cells: %lld tetra, %lld pyramids (2 tets), %lld wedges (3), %lld hexahedra into 5 and %lld "
               "into 6, %lld polyhedra; %lld split from a point at their centre, %lld points added at face "
               "centres, %lld tetrahedralized inside their boundary (TetGen); %lld bad cells skipped\n",
               (long long)r->cells_into[1], (long long)r->cells_into[2], (long long)r->cells_into[3],
               (long long)r->cells_into[5], (long long)r->cells_into[6], (long long)r->polyhedra,
               (long long)r->steiner_cells, (long long)r->face_steiner_points, (long long)r->fixed_boundary_cells,
               (long long)r->bad_cells_skipped);
    for (int k = 0; k < r->level_count; k++) {
        printf("  level %d: %lld tets, %lld vertices, %.2f MiB; ", k + 1, (long long)r->level[k].tets,
               (long long)r->level[k].vertices, (double)r->level[k].bytes / 1048576.0);
        if (r->level[k].error_samples > 0)
            printf("field error at %lld removed vertices: max %.4g, RMS %.4g; ", (long long)r->level[k].error_samples,
                   r->level[k].error_max, r->level[k].error_rms);
        else
            printf("no point field to measure an error on; ");
        if (r->level[k].shell_distance > 0)
            printf("shell distance %g (allowed %g)\n", r->level[k].shell_distance, r->level[k].shell_tolerance);
        else
            printf("shell distance 0 (the same surface)\n");
    }
    if (a->options.levels > r->level_count)
        printf("  levels: %d of the %d asked (the next would keep more than 85%% of the tets before it)\n",
               r->level_count, a->options.levels);
    printf("  time: %.3f s (import %.3f, tetrahedralize %.3f, orient %.3f, reorder %.3f, connect %.3f, ", r->t_total,
           r->t_import, r->t_tetrahedralize, r->t_orient, r->t_reorder, r->t_connect);
    if (r->level_count)
        printf("levels %.3f, ", r->t_levels);
    printf("write %.3f)\n", r->t_write);
}

int tpk_cmd_convert(int argc, char **argv)
{
    static convert_args a;
    memset(&a, 0, sizeof a);
    a.options.level_shell_error = TPK_LEVEL_SHELL_ERROR;
    a.progress = -1;
    int rc = parse_args(argc, argv, &a);
    if (rc == 0)
        rc = tpk_cli_check_convert_output("convert", "OUTPUT", a.options.input, a.options.format, a.options.output);
    if (rc)
        return rc;
    a.options.command_line = tpk_cli_joined(argc, argv, a.options.output);
    tpk_convert_report report;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    diag.strict_fields = a.strict_fields;
    /* Scripts and tests read a quiet stderr: progress only on a terminal, or when asked. */
    int progress = !a.quiet && (a.progress >= 0 ? a.progress : isatty(2));
    a.tetgen.progress = progress;
    a.options.tetgen = &a.tetgen;
    stage_bar bar = {NULL};
    rc = tpk_convert(&a.options, &report, progress ? show_stage : NULL, &bar, &diag);
    if (progress && rc == 0)
        show_stage(&bar, NULL, 1.0);
    else if (progress)
        fprintf(stderr, "\r\033[K"); /* a failed stage's bar is left unfinished: erase it for the message */
    if (rc != 0) {
        const char *why = diag.message[0] ? diag.message : "conversion failed";
        /* Pipeline stages speak of tets and vertices; say which file they came from. */
        if (strstr(why, a.options.input) || strstr(why, a.options.output))
            return tpk_cli_fail("convert", "%s", why);
        return tpk_cli_fail("convert", "%s: %s", a.options.input, why);
    }
    if (!a.quiet)
        print_summary(&a, &report);
    return TPK_EXIT_OK;
}
