/* render --legend (render/legend.h): the bar's pixels are the TF's colours at their s, row by row, for
 * the presets and a TF file's points; the panel and text change only the legend's corner; too small an
 * image is refused. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "render/legend.h"

#define W 400
#define H 300

static int draw(const char *tf_name, uint8_t *rgba, tpk_transfer_function *tf)
{
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_tf_load(tf_name, tf, &diag) != 0)
        return -1;
    for (size_t i = 0; i < (size_t)W * H; i++)
        memcpy(rgba + 4 * i, (uint8_t[4]){26, 26, 26, 255}, 4);
    tpk_legend legend = {tf, 290, 380.5, "temperature", "K"};
    return tpk_legend_draw(rgba, W, H, &legend, &diag);
}

TPK_TEST(bar_is_the_tf)
{
#ifndef TPK_WITH_CAIRO
    TPK_SKIP("built without cairo");
#endif
    const char *names[] = {"viridis", "inferno", "cool-warm", "grayscale"};
    uint8_t *rgba = malloc((size_t)W * H * 4);
    CHECK(rgba != NULL);
    for (int n = 0; n < 4; n++) {
        tpk_transfer_function tf;
        CHECK(draw(names[n], rgba, &tf) == 0);
        tpk_legend_bar bar;
        CHECK(tpk_legend_place(W, H, &bar) == 0);
        CHECK(bar.x0 > W / 2 && bar.x1 < W && bar.y0 > 0 && bar.y1 < H && bar.y1 - bar.y0 > 100);
        for (int y = bar.y0; y <= bar.y1; y++) {
            double c[4];
            tpk_tf_eval(&tf, (double)(bar.y1 - y) / (bar.y1 - bar.y0), c);
            for (int x = bar.x0; x <= bar.x1; x += bar.x1 - bar.x0) {
                const uint8_t *p = rgba + 4 * ((size_t)y * W + (size_t)x);
                for (int k = 0; k < 3; k++)
                    CHECK_MSG(abs(p[k] - (int)lround(255 * c[k])) <= 1, "%s: bar pixel (%d,%d) channel %d: %d, TF %g",
                              names[n], x, y, k, p[k], 255 * c[k]);
                CHECK(p[3] == 255);
            }
        }
        /* the bottom is s = 0 and the top s = 1 */
        double lo[4], hi[4];
        tpk_tf_eval(&tf, 0, lo);
        tpk_tf_eval(&tf, 1, hi);
        CHECK(rgba[4 * ((size_t)bar.y1 * W + (size_t)bar.x0)] == (uint8_t)lround(255 * lo[0]));
        CHECK(rgba[4 * ((size_t)bar.y0 * W + (size_t)bar.x0)] == (uint8_t)lround(255 * hi[0]));
    }
    free(rgba);
}

TPK_TEST(text_and_panel_stay_in_the_corner)
{
#ifndef TPK_WITH_CAIRO
    TPK_SKIP("built without cairo");
#endif
    uint8_t *rgba = malloc((size_t)W * H * 4);
    CHECK(rgba != NULL);
    tpk_transfer_function tf;
    CHECK(draw("viridis", rgba, &tf) == 0);
    tpk_legend_bar bar;
    CHECK(tpk_legend_place(W, H, &bar) == 0);
    int bright = 0, changed_left = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const uint8_t *p = rgba + 4 * ((size_t)y * W + (size_t)x);
            int changed = p[0] != 26 || p[1] != 26 || p[2] != 26 || p[3] != 255;
            if (x < W / 2)
                changed_left += changed;
            if (x < bar.x0 - 2 && p[0] > 150 && p[1] > 150 && p[2] > 150)
                bright++; /* the labels and title: light text on the dark panel */
        }
    CHECK_MSG(changed_left == 0, "%d pixels changed in the left half", changed_left);
    CHECK_MSG(bright > 50, "only %d text pixels", bright);
    free(rgba);
}

TPK_TEST(too_small_refused)
{
    uint8_t rgba[64 * 64 * 4] = {0};
    tpk_transfer_function tf;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    CHECK(tpk_tf_load("viridis", &tf, &diag) == 0);
    tpk_legend legend = {&tf, 0, 1, "f", ""};
    CHECK(tpk_legend_draw(rgba, 64, 64, &legend, &diag) != 0);
    CHECK(strstr(diag.message, "too small") != NULL || strstr(diag.message, "without cairo") != NULL);
}
