/* tetpack view's loop: the window and renderer (Vulkan presenting to the window, else OpenGL showing
 * frames read back), input to camera and state, a frame when something changed (at a reduced resolution
 * while dragging when full frames are slow), the window's title with the frame rate and GPU time. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "render/budget.h"
#include "view_internal.h"

/* A drag shows frames at a fraction of the resolution when full frames take longer than this. */
static const double drag_frame_seconds = 1.0 / 15.0;

typedef struct view_loop {
    const tpk_view_options *o;
    view_state state;
    view_renderer renderer;
    view_window *window;
    int vulkan_window;      /* the renderer presents to the window (no OpenGL) */
    uint8_t *rgba;          /* the frame, at most the drawable's size */
    size_t rgba_bytes;
    double full_seconds;    /* the last full-resolution frame's render time */
    int frame;              /* frames shown */
    int screenshots;        /* P presses so far, for the file names */
    int screenshot_due;     /* P was pressed: save the next full frame before it is swapped away */
    double frame_seconds[256]; /* the first full frames' render times, for the summary of --frames */
    double gpu_seconds[256];   /* and their GPU times (-1: none) */
    int timed;
    tpk_cost_model model;      /* --max-ms: fitted on every frame drawn */
    int levels_shown[TPK_MAX_LEVELS + 1]; /* frames drawn at each level, for the summary */
    int last_zoom;             /* the last frame's pixel step (a drag's, or --max-ms's) */
} view_loop;

/* Mouse drags onto the camera: 0.4 degree per pixel, a wheel step zooms by 10%. */
static int apply_drags(view_loop *l, const view_input *in)
{
    tpk_camera *c = &l->state.opt.camera;
    int height = 0, width = 0;
    view_window_size(l->window, &width, &height);
    if (in->orbit[0] != 0 || in->orbit[1] != 0) {
        tpk_view_orbit(c, -0.4 * in->orbit[0]);
        tpk_view_tilt(c, 0.4 * in->orbit[1]);
    }
    if (in->pan[0] != 0 || in->pan[1] != 0)
        tpk_view_pan(c, in->pan[0], in->pan[1], height);
    if (in->zoom != 0)
        tpk_view_zoom(c, pow(1.1, in->zoom));
    return in->orbit[0] != 0 || in->orbit[1] != 0 || in->pan[0] != 0 || in->pan[1] != 0 || in->zoom != 0;
}

/* The window's contents (the last frame drawn) as a PNG. */
static int save_screenshot(view_loop *l, const char *path, int width, int height, tpk_diag *diag)
{
    if (l->renderer.present && view_renderer_read(&l->renderer, l->rgba, width, height, diag) != 0)
        return -1;
    if (!l->renderer.present)
        view_window_read(l->window, l->rgba, width, height);
    if (tpk_write_png(path, width, height, l->rgba, diag) != 0)
        return -1;
    fprintf(stderr, "tetpack view: wrote %s (%dx%d)\n", path, width, height);
    return 0;
}

/* One key's action. Returns 1 to quit, 0 to go on, -1 with a message. */
static int apply_action(view_loop *l, view_action a, tpk_diag *diag)
{
    if (a == VIEW_QUIT)
        return 1;
    if (a == VIEW_SCREENSHOT) {
        l->screenshot_due = 1;
        return 0;
    }
    if (a == VIEW_WRITE_SCENE) {
        const char *path = l->o->save_scene ? l->o->save_scene : "view_scene.json";
        if (view_state_write_scene(&l->state, path, l->renderer.vk != NULL || l->renderer.raster != NULL, diag) != 0)
            return -1;
        fprintf(stderr, "tetpack view: wrote %s\n", path);
        return 0;
    }
    int changed = view_state_apply(&l->state, a, diag);
    if (changed < 0) /* a step or layout that does not load: say so, keep showing what was shown */
        fprintf(stderr, "tetpack view: %s\n", diag->message);
    if (changed > 0 &&
        view_renderer_open(&l->renderer, &l->state, l->o->cpu, l->vulkan_window ? l->window : NULL, diag) != 0)
        return -1;
    return 0;
}

/* --max-ms: the level of the next frame of width x height: the full mesh when the view rests (`resting`),
 * else the finest the cost model predicts to fit (the coarsest before any frame was drawn). The renderer
 * is made again for a new level. 0, or -1 with a message. */
static int pick_level(view_loop *l, int width, int height, int resting, tpk_diag *diag)
{
    view_state *s = &l->state;
    if (!(l->o->max_ms > 0) || s->levels.count < 2)
        return 0;
    int k = resting ? 0 : tpk_level_set_choose(&s->levels, &l->model, (double)width * height, l->o->max_ms / 1e3);
    int changed = view_state_set_level(s, k, diag);
    if (changed < 0)
        return -1;
    if (changed > 0 &&
        view_renderer_open(&l->renderer, s, l->o->cpu, l->vulkan_window ? l->window : NULL, diag) != 0)
        return -1;
    return 0;
}

/* Render and draw one frame; `reduced`: at a fraction of the resolution (a drag on a slow device);
 * `resting`: no input since the last frame (--max-ms then draws the full mesh). */
static int show_frame(view_loop *l, int reduced, int resting, tpk_diag *diag)
{
    int width, height;
    view_window_size(l->window, &width, &height);
    if (width < 1 || height < 1) /* minimized */
        return 0;
    if (pick_level(l, width, height, resting && !reduced, diag) != 0)
        return -1;
    int zoom = 1;
    if (reduced && l->full_seconds > drag_frame_seconds)
        zoom = (int)fmin(8.0, ceil(sqrt(l->full_seconds / drag_frame_seconds)));
    /* --max-ms past the coarsest level, while the view moves: rays at every d-th pixel (budget.h) */
    if (l->o->max_ms > 0 && !(resting && !reduced)) {
        int d = tpk_cost_model_pixel_step(&l->model, (double)width * height,
                                          (double)l->state.levels.tets[l->state.level], l->o->max_ms / 1e3,
                                          l->o->max_pixel_step);
        zoom = d > zoom ? d : zoom;
    }
    l->last_zoom = zoom;
    int w = (width + zoom - 1) / zoom, h = (height + zoom - 1) / zoom;
    size_t bytes = (size_t)width * (size_t)height * 4;
    if (bytes > l->rgba_bytes) {
        uint8_t *grown = realloc(l->rgba, bytes);
        if (!grown)
            return tpk_diag_fail(diag, "out of memory for a %dx%d frame", width, height);
        l->rgba = grown, l->rgba_bytes = bytes;
    }
    tpk_render_stats stats;
    double t0 = tpk_now_seconds();
    if (view_renderer_frame(&l->renderer, &l->state, w, h, l->rgba, &stats, diag) != 0)
        return -1;
    double seconds = tpk_now_seconds() - t0;
    tpk_cost_model_add(&l->model, (double)w * h, (double)l->state.levels.tets[l->state.level], seconds);
    l->levels_shown[l->state.level]++;
    if (zoom == 1) /* the size a scene written now says */
        l->full_seconds = seconds, l->state.opt.width = width, l->state.opt.height = height;
    if (zoom == 1 && l->timed < 256)
        l->gpu_seconds[l->timed] = stats.gpu_seconds, l->frame_seconds[l->timed++] = seconds;
    if (!l->renderer.present)
        view_window_draw(l->window, l->rgba, w, h, zoom);
    char what[1024], gpu[64] = "", title[1500];
    view_state_describe(&l->state, what, sizeof what);
    if (l->renderer.vk && stats.gpu_seconds >= 0)
        snprintf(gpu, sizeof gpu, ", GPU %.2f ms", 1e3 * stats.gpu_seconds);
    snprintf(title, sizeof title, "%s | %s | %.1f fps, %.1f ms%s, %dx%d", what, l->renderer.device, 1.0 / seconds,
             1e3 * seconds, gpu, w, h);
    view_window_title(l->window, title);
    l->frame++;
    return 0;
}

/* P: the frame just drawn (before the swap), to --screenshot or view_NNN.png. */
static int screenshot_now(view_loop *l, tpk_diag *diag)
{
    char path[4096];
    if (l->o->screenshot)
        snprintf(path, sizeof path, "%s", l->o->screenshot);
    else
        snprintf(path, sizeof path, "view_%03d.png", l->screenshots);
    l->screenshots++;
    l->screenshot_due = 0;
    int width, height;
    view_window_size(l->window, &width, &height);
    return save_screenshot(l, path, width, height, diag);
}

static int by_value(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The headless end: the frame times, the last frame's window contents and scene, as asked. */
static int finish(view_loop *l, tpk_diag *diag)
{
    qsort(l->frame_seconds, (size_t)l->timed, sizeof l->frame_seconds[0], by_value);
    qsort(l->gpu_seconds, (size_t)l->timed, sizeof l->gpu_seconds[0], by_value);
    int width, height;
    view_window_size(l->window, &width, &height);
    char gpu[64] = "";
    if (l->renderer.vk && l->timed > 0 && l->gpu_seconds[0] >= 0)
        snprintf(gpu, sizeof gpu, ", GPU median %.2f ms", 1e3 * l->gpu_seconds[l->timed / 2]);
    fprintf(stderr, "tetpack view: %d frames of %dx%d on %s, render time median %.1f ms%s (of the first %d)\n",
            l->frame, width, height, l->renderer.device, 1e3 * l->frame_seconds[l->timed / 2], gpu, l->timed);
    if (l->o->max_ms > 0) {
        fprintf(stderr, "tetpack view: --max-ms %g: frames per level", l->o->max_ms);
        for (int k = 0; k < l->state.levels.count; k++)
            fprintf(stderr, " %d:%d", k, l->levels_shown[k]);
        fprintf(stderr, " (0: the full mesh); the last at level %d, pixel step %d\n", l->state.level, l->last_zoom);
    }
    if (l->o->screenshot && save_screenshot(l, l->o->screenshot, width, height, diag) != 0)
        return -1;
    if (l->o->save_scene && apply_action(l, VIEW_WRITE_SCENE, diag) != 0)
        return -1;
    return 0;
}

static int run(view_loop *l, tpk_diag *diag)
{
    const tpk_view_options *o = l->o;
    int dirty = 1, reduced = 0, moved = 1, refine = 0;
    for (const char *k = o->keys; k && *k; k++) { /* --keys: as if typed before the window showed */
        int rc = apply_action(l, view_key_action((unsigned char)*k), diag);
        if (rc)
            return rc < 0 ? -1 : 0;
    }
    while (!view_window_closing(l->window)) {
        view_input in;
        view_window_poll(l->window, !dirty && !refine && o->frames <= 0, &in);
        moved = apply_drags(l, &in) | in.resized | (in.action_count > 0) | in.dragging;
        dirty |= moved;
        if (refine && !moved) /* --max-ms: the view rests after a coarser frame: the full mesh once */
            dirty = 1;
        reduced = in.dragging;
        if (in.released) /* a drag's reduced frames end with a full one */
            dirty = 1;
        for (int i = 0; i < in.action_count; i++) {
            int rc = apply_action(l, in.actions[i], diag);
            if (rc)
                return rc < 0 ? -1 : 0;
            dirty |= in.actions[i] != VIEW_WRITE_SCENE;
        }
        if (o->frames > 0 && l->frame > 0 && o->orbit_deg != 0) {
            tpk_view_orbit(&l->state.opt.camera, o->orbit_deg);
            moved = 1;
        }
        int resting = refine && !moved;
        if ((dirty || o->frames > 0) && show_frame(l, reduced && !l->screenshot_due, resting, diag) != 0)
            return -1;
        refine = o->max_ms > 0 && l->state.level > 0 && !resting;
        dirty = 0; /* wait for the next event (a drag's motion, a key) */
        if (o->frames > 0 && l->frame >= o->frames)
            return finish(l, diag);
        if (l->screenshot_due && screenshot_now(l, diag) != 0)
            return -1;
        view_window_swap(l->window);
    }
    return 0;
}

/* A window without OpenGL and a renderer presenting to it. 0; -2 without a display; -1 with a message
 * when Vulkan cannot present (the CPU reference included: l->renderer.present stays NULL). */
static int open_vulkan(view_loop *l, const char *title, tpk_diag *diag)
{
    const tpk_view_options *o = l->o;
    int rc = view_window_open(&l->window, o->render.width, o->render.height, title, 1, diag);
    if (rc == 0)
        rc = view_renderer_open(&l->renderer, &l->state, o->cpu, l->window, diag);
    if (rc == 0 && !l->renderer.present)
        rc = tpk_diag_fail(diag, "the renderer is the CPU reference");
    l->vulkan_window = rc == 0;
    return rc;
}

/* The window and renderer as --present asks: Vulkan's swapchain (auto: where it can be had, else a note
 * and OpenGL), or OpenGL. 0; -2 without a display; -1 with a message. */
static int open_output(view_loop *l, tpk_diag *diag)
{
    const tpk_view_options *o = l->o;
    char title[1024];
    view_state_describe(&l->state, title, sizeof title);
#ifdef TPK_WITH_VULKAN
    if (o->present != TPK_VIEW_PRESENT_GL && !o->cpu) {
        int rc = open_vulkan(l, title, diag);
        if (rc == 0 || rc == -2)
            return rc;
        char why[sizeof diag->message];
        snprintf(why, sizeof why, "%s", diag->message);
        if (o->present == TPK_VIEW_PRESENT_VULKAN)
            return tpk_diag_fail(diag, "--present vulkan: %s", why);
        fprintf(stderr, "tetpack view: note: no Vulkan presentation (%s); showing frames through OpenGL\n", why);
        view_renderer_close(&l->renderer);
        view_window_close(l->window, 1); /* the OpenGL window opens on the same connection */
        l->window = NULL;
    }
#endif
    if (o->present == TPK_VIEW_PRESENT_VULKAN)
        return tpk_diag_fail(diag, "--present vulkan: %s", o->cpu ? "the CPU reference shows frames through OpenGL"
                                                                  : "this tetpack was built without Vulkan");
    int rc = view_window_open(&l->window, o->render.width, o->render.height, title, 0, diag);
    if (rc == 0)
        rc = view_renderer_open(&l->renderer, &l->state, o->cpu, NULL, diag);
    return rc;
}

int tpk_view_run(const tpk_view_options *o, tpk_diag *diag)
{
    view_loop *l = calloc(1, sizeof *l);
    if (!l)
        return tpk_diag_fail(diag, "out of memory");
    l->o = o;
    int rc = view_state_init(&l->state, o, diag);
    if (rc == 0)
        rc = open_output(l, diag);
    if (rc == 0)
        rc = run(l, diag);
    view_renderer_close(&l->renderer);
    view_state_close(&l->state);
    view_window_close(l->window, 0);
    free(l->rgba);
    free(l);
    return rc;
}
