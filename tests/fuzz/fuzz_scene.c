/* Fuzz target for scene files (tools/scene/): parse; a failure must say why, and a scene that parses
 * must write back to text that parses to the same values (the round trip render --save-scene relies
 * on). A crash, an overread or a leak is a bug. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* A "tf" "file" key opens a path the input names (/dev/zero would never end): not this target's
     * business, so inputs that could spell it (directly or with \u escapes) are skipped. */
    char *text = malloc(size + 1);
    if (!text)
        return 0;
    memcpy(text, data, size);
    text[size] = 0;
    if (strstr(text, "file") || strstr(text, "\\u")) {
        free(text);
        return 0;
    }
    tpk_scene scene, back;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_scene_parse("fuzz.json", text, NULL, &scene, &diag) != 0) {
        if (!diag.message[0])
            abort(); /* a failure says why */
        free(text);
        return 0;
    }
    char *json = tpk_scene_to_json(&scene);
    if (!json || tpk_scene_parse("back.json", json, NULL, &back, &diag) != 0 || memcmp(&scene, &back, sizeof scene))
        abort();
    free(json);
    free(text);
    return 0;
}
