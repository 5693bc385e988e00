/* tetpack: git-style command line. Each subcommand lives in cmd_<name>.c. */
#include <malloc.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "tetpack.h"

static const struct {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *summary;
} commands[] = {
    {"convert", tpk_cmd_convert, "turn a simulation mesh (tetpack formats lists them) into a render-ready .tpk, with\n"
                                  "           levels of detail (--levels) or as a part set (--parts)"},
    {"info", tpk_cmd_info, "print a .tpk file's header, chunks, fields, levels and checksum status (--json)"},
    {"render", tpk_cmd_render, "render a .tpk (or any mesh convert reads) to PNG: Vulkan compute on a GPU, else\n"
                                "           the CPU reference marcher (--backend); --max-ms picks a level of detail"},
    {"view", tpk_cmd_view, "a window that renders a .tpk as you orbit, zoom and change what it shows (Vulkan,\n"
                            "           else the CPU reference)"},
    {"extract", tpk_cmd_extract, "keep only what a scene needs (layout, field, steps, clip box) in a smaller .tpk"},
    {"export", tpk_cmd_export, "write a .tpk's tets and fields as VTU or VTKHDF, or its shell as PLY, OBJ, OFF or STL"},
    {"iso", tpk_cmd_iso, "extract isosurfaces of a point field as triangles: PLY, OBJ or glTF binary (.glb)"},
    {"check", tpk_cmd_check, "validate a mesh or a .tpk file: connectivity, degeneracies, spec MUSTs"},
    {"formats", tpk_cmd_formats, "list the input formats convert and check read (--json for tools)"},
};

static void usage(FILE *out)
{
    fprintf(out, "usage: tetpack <command> [options]   (tetpack <command> --help for details)\n\n");
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        fprintf(out, "  %-8s %s\n", commands[i].name, commands[i].summary);
    fprintf(out, "\nExit codes: 0 ok, 1 problems found, 2 unusable input or usage.\n");
}

int main(int argc, char **argv)
{
    /* glibc raises its mmap threshold to the size of each large block freed (up to 32 MiB), after which
     * such arrays come from the heap and stay resident once freed: on a 1M-tet conversion that was a
     * third of the peak memory. A fixed threshold keeps every array of 1 MiB or more in its own
     * mapping, returned to the kernel when freed. */
    mallopt(M_MMAP_THRESHOLD, 1 << 20);
    if (argc < 2) {
        usage(stderr);
        return TPK_EXIT_USAGE;
    }
    if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
        usage(stdout);
        return TPK_EXIT_OK;
    }
    if (!strcmp(argv[1], "--version")) {
        printf("tetpack %s (format %d.%d)\n", TPK_LIBRARY_VERSION, TPK_VERSION_MAJOR, TPK_VERSION_MINOR);
        return TPK_EXIT_OK;
    }
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (!strcmp(argv[1], commands[i].name))
            return commands[i].run(argc - 1, argv + 1);
    fprintf(stderr, "tetpack: unknown command '%s'\n", argv[1]);
    usage(stderr);
    return TPK_EXIT_USAGE;
}
