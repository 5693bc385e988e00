/* Fuzz target for `tetpack extract --scene`: the input is the scene file; its layout, field, steps and
 * clip box pick what `extract` keeps of the fixture .tpk (cli_fixture.h), with the command line's own
 * code (tools/cli/cmd_extract.c, tools/extract/). A .tpk that extract writes must open and verify
 * (tpk_verify); any exit code is fine, a crash, a sanitizer report or a leak is a bug. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "cli/cli.h"
#include "cli_fixture.h"
#include "support.h"
#include "tetpack.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *tpk = tpk_fuzz_fixture_tpk();
    const char *scene = tpk_fuzz_scene_file("scene.json", (const char *)data, size);
    if (!scene)
        return 0;
    char out[512];
    snprintf(out, sizeof out, "%s/work/small.tpk", tpk_fuzz_scratch());
    char *argv[] = {"extract", (char *)tpk, out, "--scene", (char *)scene, "--threads", "1", NULL};
    if (tpk_cmd_extract((int)(sizeof argv / sizeof argv[0]) - 1, argv) != 0)
        return 0;
    tpk_file *file = NULL;
    char err[256];
    if (tpk_open_path(&file, out, NULL, err, sizeof err) != TPK_OK || tpk_verify(file) != TPK_OK) {
        fprintf(stderr, "extract wrote %s, which does not verify: %s\n", out, err);
        abort();
    }
    tpk_close(file);
    return 0;
}
