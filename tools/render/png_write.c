/* PNG output (libpng), written atomically: an output file (base/output_file.h), put in place whole. */
#include "render.h"

#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/output_file.h"

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
    tpk_output out;
    if (tpk_output_open(&out, path, diag) != 0)
        return -1;
    FILE *file = tpk_output_stream(&out, diag);
    png_error_state state = {""};
    if (!file || encode(file, width, height, rgba, &state) != 0) {
        tpk_output_abort(&out);
        return file ? tpk_diag_fail(diag, "%s: PNG encoding failed: %s", path, state.message) : -1;
    }
    return tpk_output_commit(&out, diag);
}
