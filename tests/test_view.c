/* The viewer's camera navigation (tools/view/view_nav.c): orbit, tilt, zoom and pan against closed
 * forms (the window itself is tested by tests/cli/view.sh under Xvfb). */
#include <math.h>
#include <string.h>

#include "harness.h"
#include "view/view.h"

static tpk_camera start(void)
{
    tpk_camera c = {{3, 0, 1}, {1, 0, 1}, {0, 0, 1}, 40}; /* 2 units from the look-at point, level */
    return c;
}

static double dist(const double a[3], const double b[3])
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

TPK_TEST(orbit_turns_around_up)
{
    tpk_camera c = start(), s = start();
    tpk_view_orbit(&c, 90); /* counter-clockwise seen from +z: +x turns into +y */
    double want[3] = {1, 2, 1};
    CHECK(dist(c.eye, want) < 1e-12);
    for (int i = 0; i < 4; i++)
        tpk_view_orbit(&c, 67.5); /* 270 degrees more: where it started */
    CHECK(dist(c.eye, s.eye) < 1e-12);
    tpk_view_orbit(&c, -45);
    CHECK(fabs(dist(c.eye, c.at) - 2) < 1e-12 && fabs(c.eye[2] - 1) < 1e-12 && c.eye[1] < -1.4);
    CHECK(!memcmp(c.at, s.at, sizeof c.at) && !memcmp(c.up, s.up, sizeof c.up));
}

TPK_TEST(tilt_stops_short_of_up)
{
    tpk_camera c = start();
    tpk_view_tilt(&c, 30); /* 30 degrees up: height 2 sin 30 = 1 above the look-at point */
    CHECK(fabs(c.eye[2] - 2) < 1e-12 && fabs(dist(c.eye, c.at) - 2) < 1e-12 && fabs(c.eye[1]) < 1e-12);
    tpk_view_tilt(&c, 100); /* clamped 1 degree from the up axis */
    CHECK(fabs(c.eye[2] - 1 - 2 * cos(M_PI / 180)) < 1e-12 && c.eye[0] > 1);
    tpk_view_tilt(&c, -300);
    CHECK(fabs(c.eye[2] - 1 + 2 * cos(M_PI / 180)) < 1e-12 && c.eye[0] > 1);
}

TPK_TEST(zoom_scales_the_distance)
{
    tpk_camera c = start();
    tpk_view_zoom(&c, 0.5);
    double want[3] = {2, 0, 1};
    CHECK(dist(c.eye, want) < 1e-15);
    tpk_view_zoom(&c, 0); /* refused: the eye would sit on the look-at point */
    tpk_view_zoom(&c, NAN);
    CHECK(dist(c.eye, want) < 1e-15);
}

TPK_TEST(pan_follows_the_cursor)
{
    /* 100 pixels high at fovy 90 and distance 2: the view is 4 units high there, 0.04 per pixel. The
     * camera looks along -x with up +z, so screen right is forward x up = +y; the content follows the
     * cursor, so the camera moves the other way. */
    tpk_camera c = start();
    c.fovy_deg = 90;
    tpk_view_pan(&c, 10, 0, 100); /* content 10 pixels right: camera 0.4 left */
    CHECK(fabs(c.eye[1] + 0.4) < 1e-12 && fabs(c.at[1] + 0.4) < 1e-12 && fabs(c.eye[0] - 3) < 1e-12);
    tpk_view_pan(&c, 0, 5, 100); /* content 5 pixels down: camera 0.2 up */
    CHECK(fabs(c.eye[2] - 1.2) < 1e-12 && fabs(c.at[2] - 1.2) < 1e-12);
}
