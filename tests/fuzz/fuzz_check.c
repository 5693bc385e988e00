/* Fuzz target for `tetpack check` end to end: the first input byte picks the file's extension (a volume
 * format or .tpk; surfaces are left out, TetGen runs in a child process), the rest is written to a file
 * on tmpfs, which is imported strictly (as convert does), then checked: lenient import, every group of
 * checks (or the 6xx .tpk groups and the mesh ones after them), the text and JSON reports. Findings are
 * fine; a crash, a sanitizer report, a leak, or a failure that does not say why is a bug. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check/check.h"
#include "import/importers.h"
#include "support.h"

static const char *const extensions[] = {".tpk", ".vtk", ".vtu", ".msh", ".mesh", ".meshb", ".ugrid",
                                         ".b8.ugrid", ".lb8.ugrid", ".inp", ".xdmf", ".xml", ".tpk", ".vtk"};

static void import_strict(const char *path)
{
    tpk_mesh mesh;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    diag.warn = tpk_fuzz_ignore;
    if (tpk_import_any(path, NULL, &mesh, &diag) == 0)
        tpk_mesh_free(&mesh);
    else if (!diag.message[0])
        abort();
}

static void check(const char *path)
{
    tpk_check_options options;
    tpk_check_options_default(&options);
    options.threads = 1;
    tpk_check_report report;
    if (tpk_check_report_init(&report, &options) != 0)
        return;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    diag.warn = tpk_fuzz_ignore;
    if (tpk_check_path(path, NULL, &report, &diag) != 0 && !diag.message[0])
        abort(); /* an input check cannot read must say why */
    FILE *sink = fopen("/dev/null", "w");
    if (sink) {
        tpk_check_print_text(&report, sink);
        fclose(sink);
    }
    tpk_strbuf json;
    memset(&json, 0, sizeof json);
    tpk_check_write_json(&report, &json);
    tpk_strbuf_free(&json);
    tpk_check_has_problems(&report, 1);
    tpk_check_report_free(&report);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0)
        return 0;
    char path[512];
    const char *extension = extensions[data[0] % (sizeof extensions / sizeof extensions[0])];
    snprintf(path, sizeof path, "%s/fuzz%s", tpk_fuzz_fresh_dir(NULL), extension);
    if (tpk_fuzz_write(path, data + 1, size - 1) != 0)
        return 0;
    if (strcmp(extension, ".tpk"))
        import_strict(path);
    check(path);
    return 0;
}
