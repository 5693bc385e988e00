/* The fixture .tpk and scene files of the fuzz targets that run a subcommand (cli_fixture.h). */
#include "cli_fixture.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "support.h"

/* VTK legacy text: 3x3x3 points, 8 hexahedra, point fields s (x + 2y) and t (z), cell field c. */
static int write_fixture_vtk(const char *path)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return -1;
    fprintf(f, "# vtk DataFile Version 3.0\nfuzz fixture\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 27 double\n");
    for (int k = 0; k < 3; k++)
        for (int j = 0; j < 3; j++)
            for (int i = 0; i < 3; i++)
                fprintf(f, "%d %d %d\n", i, j, k);
    fprintf(f, "CELLS 8 72\n");
    for (int k = 0; k < 2; k++)
        for (int j = 0; j < 2; j++)
            for (int i = 0; i < 2; i++) {
                int p = i + 3 * j + 9 * k;
                fprintf(f, "8 %d %d %d %d %d %d %d %d\n", p, p + 1, p + 4, p + 3, p + 9, p + 10, p + 13, p + 12);
            }
    fprintf(f, "CELL_TYPES 8\n");
    for (int c = 0; c < 8; c++)
        fprintf(f, "12\n");
    fprintf(f, "POINT_DATA 27\nSCALARS s double 1\nLOOKUP_TABLE default\n");
    for (int p = 0; p < 27; p++)
        fprintf(f, "%d\n", p % 3 + 2 * (p / 3 % 3));
    fprintf(f, "SCALARS t float 1\nLOOKUP_TABLE default\n");
    for (int p = 0; p < 27; p++)
        fprintf(f, "%d\n", p / 9);
    fprintf(f, "CELL_DATA 8\nSCALARS c int 1\nLOOKUP_TABLE default\n");
    for (int c = 0; c < 8; c++)
        fprintf(f, "%d\n", c);
    return fclose(f);
}

const char *tpk_fuzz_fixture_tpk(void)
{
    static char tpk[512];
    if (tpk[0])
        return tpk;
    char vtk[512];
    snprintf(vtk, sizeof vtk, "%s/fixture.vtk", tpk_fuzz_scratch());
    snprintf(tpk, sizeof tpk, "%s/fixture.tpk", tpk_fuzz_scratch());
    char *argv[] = {"convert", vtk, tpk, "--layout", "tet16", "--layout", "tet20", "--layout", "tet32",
                    "--threads", "1", "--quiet", NULL};
    if (write_fixture_vtk(vtk) != 0 || tpk_cmd_convert((int)(sizeof argv / sizeof argv[0]) - 1, argv) != 0) {
        fprintf(stderr, "fuzz: could not make the fixture %s\n", tpk);
        abort();
    }
    return tpk;
}

const char *tpk_fuzz_scene_file(const char *name, const char *data, size_t size)
{
    static char path[512];
    char *text = malloc(size + 1);
    if (!text)
        return NULL;
    memcpy(text, data, size);
    text[size] = 0;
    int names_file = strstr(text, "file") || strstr(text, "\\u");
    free(text);
    if (names_file)
        return NULL;
    snprintf(path, sizeof path, "%s/%s", tpk_fuzz_fresh_dir(NULL), name);
    return tpk_fuzz_write(path, data, size) == 0 ? path : NULL;
}
