# Wrap glslc's `-mfmt=c` output (a brace-enclosed list of 32-bit words) into a C source, so the
# renderer carries its SPIR-V and needs no file at run time. Usage: cmake -DIN=x.inc -DOUT=x.c -P this
file(READ "${IN}" words)
file(WRITE "${OUT}.tmp"
  "/* Generated from tools/render_vk/shaders/render.comp by glslc at build time; do not edit. */\n"
  "#include <stddef.h>\n#include <stdint.h>\n\n"
  "const uint32_t tpk_vk_render_spv[] = ${words};\n"
  "const size_t tpk_vk_render_spv_size = sizeof tpk_vk_render_spv;\n")
file(RENAME "${OUT}.tmp" "${OUT}")
