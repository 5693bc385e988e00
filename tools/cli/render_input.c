/* render's and view's input (render_input.h): a .tpk as it is, or a mesh converted in memory by the
 * converter's own driver (tpk_convert), writing into a memfd that is then mapped and opened. */
#define _GNU_SOURCE /* memfd_create */
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "convert/convert.h"
#include "tetpack_format.h"
#include "import/importers.h"
#include "render_input.h"

int render_input_is_tpk(const char *path)
{
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISREG(st.st_mode))
        return 0;
    unsigned char head[TPK_MAGIC_SIZE] = {0};
    FILE *f = fopen(path, "rb");
    size_t got = f ? fread(head, 1, sizeof head, f) : 0;
    if (f)
        fclose(f);
    return got == TPK_MAGIC_SIZE && !memcmp(head, TPK_MAGIC, TPK_MAGIC_SIZE);
}

/* Would `tetpack convert` take this path: a format its registry detects, an OpenFOAM case, a TetGen stem? */
static int convertible(const char *path)
{
    char node[4096];
    struct stat st;
    if (tpk_import_format_detect(path) || tpk_openfoam_is_case(path))
        return 1;
    snprintf(node, sizeof node, "%s.node", path);
    return stat(path, &st) != 0 && stat(node, &st) == 0;
}

/* The refusal of a file that is neither: what it starts with, what render takes, and what to do. */
static int refuse(const char *cmd, const char *path)
{
    struct stat st;
    if (stat(path, &st) != 0)
        return tpk_cli_fail(cmd, "%s: cannot open it: %s", path, strerror(errno));
    unsigned char head[8] = {0};
    FILE *f = fopen(path, "rb");
    size_t got = f ? fread(head, 1, sizeof head, f) : 0;
    if (f)
        fclose(f);
    char shown[40] = "";
    for (size_t i = 0, used = 0; i < got && used + 4 < sizeof shown; i++)
        used += (size_t)snprintf(shown + used, sizeof shown - used, "%s%02x", i ? " " : "", head[i]);
    return tpk_cli_fail(cmd, "%s: neither a .tpk nor a mesh in a format tetpack reads (its first bytes: %s); "
                        "%s takes a .tpk or any input of `tetpack formats` (converted in memory first). "
                        "Write the mesh in one of those formats (e.g. .vtu with meshio or ParaView), or give "
                        "its extension if the name lacks it", path, got ? shown : "no bytes", cmd);
}

/* Convert `path` into a memfd (save_tpk NULL) or into save_tpk. */
static int convert_input(const char *cmd, const char *path, const char *save_tpk, int threads, render_input *in)
{
    tpk_convert_options o;
    memset(&o, 0, sizeof o);
    o.input = path;
    o.output = save_tpk ? save_tpk : "(in memory)";
    o.threads = threads;
    o.command_line = save_tpk ? "tetpack render --save-tpk" : "tetpack render (in memory)";
    int fd = -1;
    if (!save_tpk && (fd = memfd_create("tetpack-render", MFD_CLOEXEC)) < 0)
        return tpk_cli_fail(cmd, "%s: cannot make an in-memory file to convert into: %s (give --save-tpk FILE)",
                            path, strerror(errno));
    o.output_fd = fd;
    tpk_convert_report report;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    int rc = 0;
    if (tpk_convert(&o, &report, NULL, NULL, &diag) != 0)
        rc = tpk_cli_fail(cmd, "%s (%s converts with convert's defaults; tetpack convert has options to repair "
                          "such meshes)", diag.message, cmd);
    in->converted = 1;
    in->convert_seconds = report.t_total;
    in->tets = report.tets;
    if (rc == 0 && save_tpk) {
        in->tpk_path = save_tpk;
        rc = tpk_cli_open(cmd, save_tpk, &in->file);
    } else if (rc == 0) {
        struct stat st;
        if (fstat(fd, &st) != 0 || st.st_size <= 0)
            rc = tpk_cli_fail(cmd, "%s: the in-memory conversion is empty", path);
        else if ((in->bytes = mmap(NULL, (size_t)st.st_size, PROT_READ, MAP_PRIVATE, fd, 0)) == MAP_FAILED)
            in->bytes = NULL, rc = tpk_cli_fail(cmd, "%s: cannot map the in-memory conversion: %s", path, strerror(errno));
        else {
            in->size = (size_t)st.st_size;
            char err[1024] = "";
            tpk_result r = tpk_open_memory(&in->file, in->bytes, in->size, NULL, err, sizeof err);
            if (r != TPK_OK)
                rc = tpk_cli_fail_file(cmd, path, err[0] ? err : tpk_result_string(r));
        }
    }
    if (fd >= 0)
        close(fd); /* the mapping keeps the memory */
    return rc;
}

int render_input_open(const char *cmd, const char *path, const char *save_tpk, int threads, render_input *in)
{
    memset(in, 0, sizeof *in);
    if (render_input_is_tpk(path)) {
        if (save_tpk)
            return tpk_cli_fail(cmd, "--save-tpk: %s is a .tpk already (--save-tpk keeps the conversion of another "
                                "format)", path);
        in->tpk_path = path;
        return tpk_cli_open(cmd, path, &in->file);
    }
    char node[4096];
    struct stat st;
    snprintf(node, sizeof node, "%s.node", path);
    if (!convertible(path) || (stat(path, &st) != 0 && stat(node, &st) != 0))
        return refuse(cmd, path);
    int rc = convert_input(cmd, path, save_tpk, threads, in);
    if (rc != 0)
        render_input_close(in);
    return rc;
}

void render_input_close(render_input *in)
{
    if (in->file)
        tpk_close(in->file);
    if (in->bytes)
        munmap(in->bytes, in->size);
    memset(in, 0, sizeof *in);
}
