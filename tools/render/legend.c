/* The colour bar of render --legend (legend.h), drawn with cairo: the bar's pixels are set from the TF
 * directly (so that they are the TF's colours exactly), the panel, ticks and text by cairo. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "legend.h"
#ifdef TPK_WITH_CAIRO
#include <cairo.h>
#endif

int tpk_legend_place(int width, int height, tpk_legend_bar *bar)
{
    if (width < 120 || height < 100)
        return -1;
    int bar_width = height / 24 > 10 ? height / 24 : 10;
    bar->x1 = width - 1 - width / 40 - 4;
    bar->x0 = bar->x1 - bar_width + 1;
    bar->y0 = height / 6 + 14;
    bar->y1 = height - 1 - height / 10;
    return bar->y1 - bar->y0 >= 20 ? 0 : -1;
}

#ifdef TPK_WITH_CAIRO
/* rgba (straight) into cairo's native-endian premultiplied ARGB32, and back. */
static void to_cairo(const uint8_t *rgba, unsigned char *data, int stride, int width, int height)
{
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++) {
            const uint8_t *p = rgba + 4 * ((size_t)y * (size_t)width + (size_t)x);
            uint32_t a = p[3];
            uint32_t v = a << 24 | (p[0] * a / 255) << 16 | (p[1] * a / 255) << 8 | (p[2] * a / 255);
            memcpy(data + (size_t)y * (size_t)stride + 4 * (size_t)x, &v, 4);
        }
}

static void from_cairo(const unsigned char *data, int stride, uint8_t *rgba, int width, int height)
{
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++) {
            uint32_t v;
            memcpy(&v, data + (size_t)y * (size_t)stride + 4 * (size_t)x, 4);
            uint8_t *p = rgba + 4 * ((size_t)y * (size_t)width + (size_t)x);
            uint32_t a = v >> 24;
            for (int c = 0; c < 3; c++) {
                uint32_t premul = (v >> (16 - 8 * c)) & 0xff;
                p[c] = (uint8_t)(a ? (premul * 255 + a / 2) / a : 0);
            }
            p[3] = (uint8_t)a;
        }
}

static void put_text(cairo_t *cr, double x, double y, double right, const char *text)
{
    cairo_text_extents_t e;
    cairo_text_extents(cr, text, &e);
    cairo_move_to(cr, right ? x - e.x_advance : x, y);
    cairo_show_text(cr, text);
}

/* The panel, title, ticks and labels (everything but the bar's pixels). */
static void draw_decor(cairo_t *cr, int height, const tpk_legend_bar *bar, const tpk_legend *legend)
{
    double font = height / 30.0 > 10 ? height / 30.0 : 10;
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, font);
    char labels[5][32];
    double widest = 0;
    for (int k = 0; k < 5; k++) {
        snprintf(labels[k], sizeof labels[k], "%.4g",
                 legend->range_min + (legend->range_max - legend->range_min) * k / 4.0);
        cairo_text_extents_t e;
        cairo_text_extents(cr, labels[k], &e);
        widest = e.x_advance > widest ? e.x_advance : widest;
    }
    char title[128];
    const char *field = legend->field && legend->field[0] ? legend->field : "(no field)";
    snprintf(title, sizeof title, "%s%s%s%s", field, legend->units && legend->units[0] ? " [" : "",
             legend->units && legend->units[0] ? legend->units : "", legend->units && legend->units[0] ? "]" : "");
    cairo_text_extents_t te;
    cairo_text_extents(cr, title, &te);
    double left = bar->x0 - widest - font * 0.9;
    double title_left = bar->x1 + 1 - te.x_advance;
    left = title_left < left ? title_left : left;
    double pad = font * 0.5;
    cairo_set_source_rgba(cr, 0, 0, 0, 0.55);
    cairo_rectangle(cr, left - pad, bar->y0 - font * 1.6 - pad, bar->x1 + 1 - left + 2 * pad,
                    bar->y1 - bar->y0 + font * 2.2 + 2 * pad);
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 0.92, 0.92, 0.92);
    put_text(cr, bar->x1 + 1, bar->y0 - font * 0.8, 1, title);
    cairo_set_line_width(cr, 1);
    for (int k = 0; k < 5; k++) {
        double y = bar->y1 - (bar->y1 - bar->y0) * k / 4.0 + 0.5;
        cairo_move_to(cr, bar->x0 - font * 0.4, y);
        cairo_line_to(cr, bar->x0 - 1, y);
        cairo_stroke(cr);
        put_text(cr, bar->x0 - font * 0.55, y + font * 0.35, 1, labels[k]);
    }
    cairo_rectangle(cr, bar->x0 - 1.5, bar->y0 - 1.5, bar->x1 - bar->x0 + 4, bar->y1 - bar->y0 + 4);
    cairo_stroke(cr);
}

/* The bar's pixels: each row the TF's colour at its s, opaque. */
static void fill_bar(uint8_t *rgba, int width, const tpk_legend_bar *bar, const tpk_transfer_function *tf)
{
    for (int y = bar->y0; y <= bar->y1; y++) {
        double c[4];
        tpk_tf_eval(tf, (double)(bar->y1 - y) / (bar->y1 - bar->y0), c);
        for (int x = bar->x0; x <= bar->x1; x++) {
            uint8_t *p = rgba + 4 * ((size_t)y * (size_t)width + (size_t)x);
            for (int k = 0; k < 3; k++)
                p[k] = (uint8_t)lround(255.0 * (c[k] < 0 ? 0 : c[k] > 1 ? 1 : c[k]));
            p[3] = 255;
        }
    }
}

int tpk_legend_draw(uint8_t *rgba, int width, int height, const tpk_legend *legend, tpk_diag *diag)
{
    tpk_legend_bar bar;
    if (tpk_legend_place(width, height, &bar) != 0)
        return tpk_diag_fail(diag, "--legend: the image (%dx%d) is too small for a legend (at least 120x100)",
                             width, height);
    cairo_surface_t *surface = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, width, height);
    if (cairo_surface_status(surface) != CAIRO_STATUS_SUCCESS) {
        cairo_surface_destroy(surface);
        return tpk_diag_fail(diag, "--legend: cairo cannot make a %dx%d image", width, height);
    }
    int stride = cairo_image_surface_get_stride(surface);
    cairo_surface_flush(surface);
    to_cairo(rgba, cairo_image_surface_get_data(surface), stride, width, height);
    cairo_surface_mark_dirty(surface);
    cairo_t *cr = cairo_create(surface);
    draw_decor(cr, height, &bar, legend);
    cairo_status_t status = cairo_status(cr);
    cairo_destroy(cr);
    cairo_surface_flush(surface);
    if (status == CAIRO_STATUS_SUCCESS)
        from_cairo(cairo_image_surface_get_data(surface), stride, rgba, width, height);
    cairo_surface_destroy(surface);
    if (status != CAIRO_STATUS_SUCCESS)
        return tpk_diag_fail(diag, "--legend: cairo: %s", cairo_status_to_string(status));
    fill_bar(rgba, width, &bar, legend->tf);
    return 0;
}
#else
int tpk_legend_draw(uint8_t *rgba, int width, int height, const tpk_legend *legend, tpk_diag *diag)
{
    (void)rgba, (void)width, (void)height, (void)legend;
    return tpk_diag_fail(diag, "--legend: this tetpack was built without cairo (TETPACK_WITH_CAIRO=OFF; install "
                         "libcairo2-dev and rebuild)");
}
#endif
