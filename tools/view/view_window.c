/* The viewer's window: GLFW for the window and its input; either a Vulkan surface for the renderer's
 * swapchain (no client API), or OpenGL 1.x glDrawPixels to show frames read back (the simplest path
 * that runs anywhere GLFW does, Xvfb with Mesa included). Input is gathered as drags and key actions
 * for view.c to apply. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef TPK_WITH_VULKAN
#include <vulkan/vulkan.h> /* before GLFW: it declares its Vulkan functions when it sees these types */
#endif
#include <GLFW/glfw3.h>

#include "view_internal.h"

struct view_window {
    GLFWwindow *window;
    view_input input;       /* gathered by the callbacks, handed over by view_window_poll */
    double x, y;            /* the cursor at the last event */
    int button;             /* the held button: GLFW_MOUSE_BUTTON_*, -1 none */
    int shift;              /* shift was down when the button went down (shift+left pans) */
    int gl;                 /* an OpenGL context; 0: no client API, for a Vulkan surface */
};

static char glfw_error[512];
static void on_error(int code, const char *text)
{
    snprintf(glfw_error, sizeof glfw_error, "%s (GLFW error 0x%x)", text, code);
}

static void push(view_window *w, view_action a)
{
    if (w->input.action_count < VIEW_MAX_ACTIONS)
        w->input.actions[w->input.action_count++] = a;
}

view_action view_key_action(int key)
{
    switch (key) {
    case 'T': case 't': return VIEW_NEXT_TF;
    case 'F': case 'f': return VIEW_NEXT_FIELD;
    case '[': return VIEW_STEP_BACK;
    case ']': return VIEW_STEP_FORWARD;
    case 'L': case 'l': return VIEW_NEXT_LAYOUT;
    case 'I': case 'i': return VIEW_ISO;
    case 'S': case 's': return VIEW_SHADING;
    case 'C': case 'c': return VIEW_CLIP;
    case 'P': case 'p': return VIEW_SCREENSHOT;
    case 'W': case 'w': return VIEW_WRITE_SCENE;
    case 'Q': case 'q': return VIEW_QUIT;
    case 'O': case 'o': return VIEW_PROBE;
    case 'K': case 'k': return VIEW_PROBE_MODE;
    case '4': return VIEW_PROBE_LEFT;
    case '6': return VIEW_PROBE_RIGHT;
    case '8': return VIEW_PROBE_UP;
    case '2': return VIEW_PROBE_DOWN;
    case '9': return VIEW_PROBE_AWAY;
    case '3': return VIEW_PROBE_NEAR;
    case '+': case '=': return VIEW_PROBE_GROW;
    case '-': return VIEW_PROBE_SHRINK;
    default: return VIEW_NONE;
    }
}

static void on_key(GLFWwindow *window, int key, int scancode, int action, int mods)
{
    (void)scancode, (void)mods;
    view_window *w = glfwGetWindowUserPointer(window);
    if (action != GLFW_PRESS && action != GLFW_REPEAT)
        return;
    /* GLFW's codes of letters and brackets are their (upper case) ASCII codes, whatever the keyboard */
    view_action a = key == GLFW_KEY_ESCAPE ? VIEW_QUIT : key > 0 && key < 128 ? view_key_action(key) : VIEW_NONE;
    switch (key) { /* the arrows and page keys move the probe as 4 6 8 2 9 3 do, as the keypad's keys */
    case GLFW_KEY_LEFT: case GLFW_KEY_KP_4: a = VIEW_PROBE_LEFT; break;
    case GLFW_KEY_RIGHT: case GLFW_KEY_KP_6: a = VIEW_PROBE_RIGHT; break;
    case GLFW_KEY_UP: case GLFW_KEY_KP_8: a = VIEW_PROBE_UP; break;
    case GLFW_KEY_DOWN: case GLFW_KEY_KP_2: a = VIEW_PROBE_DOWN; break;
    case GLFW_KEY_PAGE_UP: case GLFW_KEY_KP_9: a = VIEW_PROBE_AWAY; break;
    case GLFW_KEY_PAGE_DOWN: case GLFW_KEY_KP_3: a = VIEW_PROBE_NEAR; break;
    case GLFW_KEY_KP_ADD: a = VIEW_PROBE_GROW; break;
    case GLFW_KEY_KP_SUBTRACT: a = VIEW_PROBE_SHRINK; break;
    default: break;
    }
    if (a != VIEW_NONE)
        push(w, a);
}

static void on_button(GLFWwindow *window, int button, int action, int mods)
{
    view_window *w = glfwGetWindowUserPointer(window);
    if (action == GLFW_PRESS && w->button < 0) {
        w->button = button;
        w->shift = (mods & GLFW_MOD_SHIFT) != 0;
        glfwGetCursorPos(window, &w->x, &w->y);
    } else if (action == GLFW_RELEASE && button == w->button) {
        w->button = -1;
        w->input.released = 1;
    }
}

static void on_cursor(GLFWwindow *window, double x, double y)
{
    view_window *w = glfwGetWindowUserPointer(window);
    double dx = x - w->x, dy = y - w->y;
    w->x = x, w->y = y;
    if (w->button == GLFW_MOUSE_BUTTON_LEFT && !w->shift)
        w->input.orbit[0] += dx, w->input.orbit[1] += dy;
    else if (w->button == GLFW_MOUSE_BUTTON_MIDDLE || (w->button == GLFW_MOUSE_BUTTON_LEFT && w->shift))
        w->input.pan[0] += dx, w->input.pan[1] += dy;
    else if (w->button == GLFW_MOUSE_BUTTON_RIGHT)
        w->input.zoom += dy / 40.0; /* dragging down moves away, like the wheel turned toward the user */
}

static void on_scroll(GLFWwindow *window, double dx, double dy)
{
    (void)dx;
    view_window *w = glfwGetWindowUserPointer(window);
    w->input.zoom -= dy;
}

static void on_resize(GLFWwindow *window, int width, int height)
{
    (void)width, (void)height;
    view_window *w = glfwGetWindowUserPointer(window);
    w->input.resized = 1;
}

int view_window_open(view_window **out, int width, int height, const char *title, int vulkan, tpk_diag *diag)
{
    *out = NULL;
    glfw_error[0] = 0;
    glfwSetErrorCallback(on_error);
    if (!glfwInit()) {
        tpk_diag_fail(diag, "cannot open a window: %s; no display? (DISPLAY is %s) tetpack render writes "
                      "images without one", glfw_error[0] ? glfw_error : "GLFW cannot start",
                      getenv("DISPLAY") ? getenv("DISPLAY") : "not set");
        return -2;
    }
    if (vulkan && !glfwVulkanSupported()) /* GLFW stays up for the OpenGL window; view_window_close ends it */
        return tpk_diag_fail(diag, "GLFW finds no Vulkan loader with the window system's surface extensions%s%s",
                             glfw_error[0] ? ": " : "", glfw_error);
    view_window *w = calloc(1, sizeof *w);
    if (!w) {
        glfwTerminate();
        return tpk_diag_fail(diag, "out of memory");
    }
    w->button = -1;
    w->gl = !vulkan;
    glfwWindowHint(GLFW_SCALE_TO_MONITOR, GLFW_FALSE); /* the frame is rendered at the drawable's size */
    glfwWindowHint(GLFW_CLIENT_API, vulkan ? GLFW_NO_API : GLFW_OPENGL_API);
    w->window = glfwCreateWindow(width, height, title, NULL, NULL);
    if (!w->window) {
        free(w);
        glfwTerminate();
        tpk_diag_fail(diag, "cannot open a window%s: %s; tetpack render writes images without one",
                      vulkan ? "" : " with an OpenGL context", glfw_error[0] ? glfw_error : "unknown GLFW error");
        return -2;
    }
    glfwSetWindowUserPointer(w->window, w);
    if (w->gl) {
        glfwMakeContextCurrent(w->window);
        glfwSwapInterval(0); /* the renderer is the bottleneck; waiting for vsync adds latency */
    }
    glfwSetKeyCallback(w->window, on_key);
    glfwSetMouseButtonCallback(w->window, on_button);
    glfwSetCursorPosCallback(w->window, on_cursor);
    glfwSetScrollCallback(w->window, on_scroll);
    glfwSetFramebufferSizeCallback(w->window, on_resize);
    *out = w;
    return 0;
}

void view_window_poll(view_window *w, int wait, view_input *in)
{
    if (wait)
        glfwWaitEvents();
    else
        glfwPollEvents();
    *in = w->input;
    in->dragging = w->button >= 0;
    memset(&w->input, 0, sizeof w->input);
}

int view_window_closing(const view_window *w)
{
    return glfwWindowShouldClose(w->window);
}

void view_window_size(const view_window *w, int *width, int *height)
{
    glfwGetFramebufferSize(w->window, width, height);
}

void view_window_draw(view_window *w, const uint8_t *rgba, int width, int height, int zoom)
{
    int fb_width, fb_height;
    glfwGetFramebufferSize(w->window, &fb_width, &fb_height);
    glViewport(0, 0, fb_width, fb_height);
    glClearColor(0.1f, 0.1f, 0.1f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    glMatrixMode(GL_PROJECTION);
    glLoadIdentity();
    glOrtho(0, fb_width, 0, fb_height, -1, 1);
    glMatrixMode(GL_MODELVIEW);
    glLoadIdentity();
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    /* The image's top row first: start at the top edge and draw downwards. */
    glRasterPos2i(0, fb_height);
    glPixelZoom((float)zoom, -(float)zoom);
    glDrawPixels(width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
}

void view_window_read(view_window *w, uint8_t *rgba, int width, int height)
{
    int fb_width, fb_height;
    glfwGetFramebufferSize(w->window, &fb_width, &fb_height);
    (void)fb_width;
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_BACK);
    size_t row = (size_t)width * 4;
    for (int y = 0; y < height; y++) /* GL's rows go up from the bottom */
        glReadPixels(0, fb_height - 1 - y, width, 1, GL_RGBA, GL_UNSIGNED_BYTE, rgba + row * (size_t)y);
    for (size_t i = 3; i < row * (size_t)height; i += 4)
        rgba[i] = 255; /* the window has no alpha to show */
}

void view_window_swap(view_window *w)
{
    if (w->gl) /* a Vulkan window was presented to by the renderer */
        glfwSwapBuffers(w->window);
}

#ifdef TPK_WITH_VULKAN
static VkResult create_surface(VkInstance instance, void *user, VkSurfaceKHR *surface)
{
    const view_window *w = user;
    return glfwCreateWindowSurface(instance, w->window, NULL, surface);
}

void view_window_surface_source(view_window *w, tpk_vk_surface_source *out)
{
    uint32_t count = 0;
    const char **extensions = glfwGetRequiredInstanceExtensions(&count);
    out->instance_extensions = extensions;
    out->instance_extension_count = extensions ? count : 0;
    out->create = create_surface;
    out->user = w;
}
#endif

void view_window_title(view_window *w, const char *title)
{
    glfwSetWindowTitle(w->window, title);
}

void view_window_close(view_window *w, int keep_display)
{
    if (w) {
        glfwDestroyWindow(w->window);
        free(w);
    }
    if (!keep_display)
        glfwTerminate(); /* also after an open that left GLFW up without a window; harmless before glfwInit */
}
