/* Fuzz target for `tetpack render --scene`: the input is the scene file, parsed and resolved into render
 * options with the command line's own code (tools/cli/cmd_render.c, tools/scene/scene_options.c), then
 * rendered on the CPU reference at 16x12 (the command line's --size overrides the scene's, so a scene
 * cannot ask for a huge image) from the fixture .tpk (cli_fixture.h). Any exit code is fine; a crash, a
 * sanitizer report, a leak or a hang (libFuzzer's -timeout) is a bug. */
#include <stdint.h>
#include <stdio.h>

#include "cli/cli.h"
#include "cli_fixture.h"
#include "support.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *tpk = tpk_fuzz_fixture_tpk();
    const char *scene = tpk_fuzz_scene_file("scene.json", (const char *)data, size);
    if (!scene)
        return 0;
    char png[512], saved[512];
    snprintf(png, sizeof png, "%s/work/out.png", tpk_fuzz_scratch());
    snprintf(saved, sizeof saved, "%s/work/saved.json", tpk_fuzz_scratch());
    char *argv[] = {"render", (char *)tpk, "-o", png, "--scene", (char *)scene, "--backend", "cpu",
                    "--size", "16x12", "--threads", "1", "--save-scene", saved, NULL};
    tpk_cmd_render((int)(sizeof argv / sizeof argv[0]) - 1, argv);
    return 0;
}
