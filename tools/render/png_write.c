/* PNG output (libpng), written atomically: a temporary file next to the target, renamed into place. */
#include "render.h"

#include <errno.h>
#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

typedef struct png_error_state {
    char message[256];
} png_error_state;

static void on_png_error(png_structp png, png_const_charp text)
{
    png_error_state *state = png_get_error_ptr(png);
    snprintf(state->message, sizeof state->message, "%s", text);
    png_longjmp(png, 1);
}

static void on_png_warning(png_structp png, png_const_charp text)
{
    (void)png;
    (void)text;
}

/* Encode into an open stream; returns 0 or -1 with state->message set. */
static int encode(FILE *file, int width, int height, const uint8_t *rgba, png_error_state *state)
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, state, on_png_error, on_png_warning);
    if (!png) {
        snprintf(state->message, sizeof state->message, "out of memory");
        return -1;
    }
    png_infop info = png_create_info_struct(png);
    /* volatile: read after longjmp */
    volatile int rc = -1;
    if (info && !setjmp(png_jmpbuf(png))) {
        png_init_io(png, file);
        png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, 8, PNG_COLOR_TYPE_RGB_ALPHA,
                     PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
        png_write_info(png, info);
        for (int y = 0; y < height; y++)
            png_write_row(png, (png_const_bytep)(rgba + (size_t)y * (size_t)width * 4));
        png_write_end(png, NULL);
        rc = 0;
    } else if (!info) {
        snprintf(state->message, sizeof state->message, "out of memory");
    }
    png_destroy_write_struct(&png, info ? &info : NULL);
    return rc;
}

int tpk_write_png(const char *path, int width, int height, const uint8_t *rgba, tpk_diag *diag)
{
    if (!path || !rgba || width < 1 || height < 1 || width > 1000000 || height > 1000000)
        return tpk_diag_fail(diag, "%s: cannot write a %dx%d PNG", path ? path : "(null)", width, height);
    size_t len = strlen(path);
    char *temp = malloc(len + 16);
    if (!temp)
        return tpk_diag_fail(diag, "%s: out of memory", path);
    snprintf(temp, len + 16, "%s.tmp.XXXXXX", path);
    int fd = mkstemp(temp);
    if (fd < 0) {
        int e = errno;
        free(temp);
        return tpk_diag_fail(diag, "%s: cannot create a temporary file next to it: %s", path, strerror(e));
    }
    (void)fchmod(fd, 0644); /* mkstemp makes 0600; an image is for sharing (cosmetic if it fails) */
    FILE *file = fdopen(fd, "wb");
    if (!file) {
        int e = errno;
        close(fd);
        unlink(temp);
        free(temp);
        return tpk_diag_fail(diag, "%s: %s", path, strerror(e));
    }
    png_error_state state = {""};
    int rc = encode(file, width, height, rgba, &state);
    if (rc != 0) {
        fclose(file);
        unlink(temp);
        free(temp);
        return tpk_diag_fail(diag, "%s: PNG encoding failed: %s", path, state.message);
    }
    int write_error = fflush(file) != 0 || ferror(file) || fsync(fileno(file)) != 0;
    int e = errno;
    if (fclose(file) != 0 && !write_error) {
        write_error = 1;
        e = errno;
    }
    if (write_error || rename(temp, path) != 0) {
        if (!write_error)
            e = errno;
        unlink(temp);
        free(temp);
        return tpk_diag_fail(diag, "%s: write failed: %s", path, strerror(e));
    }
    free(temp);
    return 0;
}
