/* Writes render_options.glsl to stdout at build time: for each option of render/render_options.def that
 * the Vulkan renderer's uniform block holds (TPK_VK), the name its shaders read it by, "#define
 * TPK_VK_<ID> P.<member>.<component>", so that vk_params.c's side and the shaders' come from one row. */
#include <stdio.h>

#include "render/render_options.h"

int main(void)
{
    printf("// Generated from tools/render/render_options.def by tools/render_vk/options_glsl.c; do not edit.\n");
#define TPK_VK(member, index, value) printf("#define TPK_VK_%s P.%s.%c\n", id, #member, "xyzw"[index]);
#define TPK_VK_NONE
#define TPK_OPTION(ID, name, kind, R, A, S, rule, cli, key, use, vk)                                          \
    {                                                                                                          \
        const char *id = #ID;                                                                                  \
        TPK_IF(R, vk)                                                                                          \
        (void)id;                                                                                              \
    }
#include "render/render_options.def"
#undef TPK_OPTION
    return 0;
}
