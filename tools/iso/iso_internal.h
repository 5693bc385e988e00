/* Shared by the iso writers (iso_write.c: PLY, OBJ and the dispatch; iso_glb.c: glTF binary): arrays
 * written little-endian through a small buffer, whatever the host. Static inline, so no writer calls
 * another for them. */
#ifndef TPK_ISO_INTERNAL_H
#define TPK_ISO_INTERNAL_H

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "iso.h"

/* glTF binary (iso_glb.c), to an open stream. 0, or -1 with a message naming `path`. */
int tpk_iso_write_glb(FILE *f, const tpk_iso_surface *s, const tpk_iso_labels *labels, const char *path,
                      tpk_diag *diag);

/* `count` elements of `size` bytes (4 or 8) at `data`, each stored little-endian. */
static inline void iso_put_le(FILE *f, const void *data, size_t count, size_t size)
{
    unsigned char buf[8192];
    const unsigned char *src = data;
    size_t per = sizeof buf / size;
    for (size_t i = 0; i < count; i += per) {
        size_t n = count - i < per ? count - i : per;
        for (size_t j = 0; j < n; j++) {
            uint64_t v = 0;
            if (size == 8) {
                memcpy(&v, src + (i + j) * 8, 8);
            } else {
                uint32_t u;
                memcpy(&u, src + (i + j) * 4, 4);
                v = u;
            }
            for (size_t b = 0; b < size; b++)
                buf[j * size + b] = (unsigned char)(v >> (8 * b));
        }
        fwrite(buf, size, n, f);
    }
}

static inline void iso_put_u32(FILE *f, uint32_t v)
{
    iso_put_le(f, &v, 1, 4);
}

#endif
