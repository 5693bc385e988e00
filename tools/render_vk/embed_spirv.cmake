# Wrap glslc's `-mfmt=c` outputs (brace-enclosed lists of 32-bit words) of the four shader variants into
# one C source, so the renderer carries its SPIR-V and needs no file at run time.
# Usage: cmake -DDIR=<dir with render_fp64.inc, render_fp32.inc and their _one variants> -DOUT=x.c -P this
#        cmake -DDIR=<dir> -DNAME=iso -DOUT=x.c -P this     (one shader, <dir>/iso.inc: tpk_vk_iso_spv)
if(DEFINED NAME)
  set(text "/* Generated from tools/render_vk/shaders/ (${NAME}) by glslc at build time; do not edit. */\n")
  string(APPEND text "#include <stddef.h>\n#include <stdint.h>\n")
  file(READ "${DIR}/${NAME}.inc" words)
  string(APPEND text "\nconst uint32_t tpk_vk_${NAME}_spv[] = ${words};\n"
         "const size_t tpk_vk_${NAME}_spv_size = sizeof tpk_vk_${NAME}_spv;\n")
  file(WRITE "${OUT}.tmp" "${text}")
  file(RENAME "${OUT}.tmp" "${OUT}")
  return()
endif()
set(text "/* Generated from tools/render_vk/shaders/render.comp by glslc at build time; do not edit. */\n")
string(APPEND text "#include <stddef.h>\n#include <stdint.h>\n")
foreach(variant fp64 fp32 fp64_one fp32_one)
  file(READ "${DIR}/render_${variant}.inc" words)
  string(APPEND text "\nconst uint32_t tpk_vk_render_spv_${variant}[] = ${words};\n"
         "const size_t tpk_vk_render_spv_${variant}_size = sizeof tpk_vk_render_spv_${variant};\n")
endforeach()
file(WRITE "${OUT}.tmp" "${text}")
file(RENAME "${OUT}.tmp" "${OUT}")
