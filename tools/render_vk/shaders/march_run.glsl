// One inside-run of the marcher (march.c, march_run), included twice by render.comp: for primary rays
// and for the secondary rays of shadows and ambient occlusion, which GLSL cannot reach by recursion.
// The includer defines MARCH_RUN (the function's name), MARCH_TRACE (the runs' loop), MARCH_TMAX (the
// ray's tmax), MARCH_REPORT(t_in, t_out, s_in, s_out, v) (what a piece does: MARCH_GO on, MARCH_STOP
// the ray, or MARCH_PAUSE: stop before this piece and redo it on the next call) and MARCH_OUT_OF_WORK
// (true pauses the run before its next step: a sliced ray's work in this dispatch is done).
//
// Why pause: the primary ray's shade points cast secondary rays, each a whole march of its own. Cast
// from inside the primary march, a ray's state would be spread over two nested marches; paused, the
// primary march stops before a piece that needs casts, main() casts them at the top level, and the
// march resumes from the state it kept (a MarchRun and a MarchTrace), redoing that piece. So the whole
// state of a ray lies in a few variables between two steps of main()'s loop, where a sliced ray
// (vk_layout.h, "Slices") can stop and be saved for the next dispatch.

// Starts a run at entry face `h` of tet `tet`.
MarchRun MARCH_RUN_START(Hit h, int tet)
{
    MarchRun m;
    m.h = h;
    m.tet = tet;
    m.prev = -1;
    m.step = 0;
    m.s_in = hit_scalar(h, face_weights(h));
    return m;
}

// March from m's entry face until the ray leaves the volume. Returns MARCH_RAY_DONE (opaque, past the
// clip box, or an error), MARCH_RAY_EXIT (left the volume through the shell; run_exit_t says where) or
// MARCH_RAY_PAUSED (m is the tet to redo).
int MARCH_RUN(inout MarchRun m)
{
    const int tet_count = P.mode.x;
    int result = MARCH_RAY_DONE;
    for (;;) {
        if (MARCH_OUT_OF_WORK) {
            result = MARCH_RAY_PAUSED;
            break;
        }
        if (m.step >= tet_count) {
            status = TPK_VK_STATUS_MESH; // a cycle: watertight marching never revisits a tet
            break;
        }
        m.step++;
        steps_taken++;
        work++;
        if (m.h.t > MARCH_TMAX)
            break;
        const Hit h = m.h;
        const int tet = m.tet, prev = m.prev;
        const int a = h.v[0], b = h.v[1], c = h.v[2];
        ivec4 rec0, rec1 = ivec4(0);
        int vx;
        if (LAYOUT == TPK_VK_LAYOUT_TET16) {
            rec0 = fetch_tets(uint(tet));
            vx = rec0[TPK_VK_TET16_VX];
        } else if (LAYOUT == TPK_VK_LAYOUT_TET20) {
            rec0 = ivec4(0);
            vx = fetch_tets(uint(tet) * uint(TPK_VK_TET20_WORDS) + uint(TPK_VK_TET20_VX)).x;
        } else {
            rec0 = fetch_tets(2u * uint(tet));
            vx = rec0[TPK_VK_TET32_VX];
        }
        const int d = vx ^ a ^ b ^ c;
        if (d < 0 || d >= P.mode.y || d == a || d == b || d == c) {
            status = TPK_VK_STATUS_MESH;
            break;
        }
        int n3 = 0;
        if (LAYOUT == TPK_VK_LAYOUT_TET16) {
            int rp = int(a < d) + int(b < d) + int(c < d);
            n3 = rp == 3 ? prev : (rec0[1 + rp] ^ prev);
        }
        float sd;
        vec4 pd = project(d, sd);
        float va, vb, vc;
        const int sa = edge_sign(a, h.p0, d, pd, va);
        const int sb = edge_sign(b, h.p1, d, pd, vb);
        const int sc = edge_sign(c, h.p2, d, pd, vc);
        Hit o;
        int opposite;
        if (sb == -1 && sa == 1) {
            o = Hit(ivec3(a, b, d), h.p0, h.p1, pd, vec3(h.e[0], vb, -va), vec3(h.s[0], h.s[1], sd), 0.0);
            opposite = c;
        } else if (sc == -1 && sb == 1) {
            o = Hit(ivec3(b, c, d), h.p1, h.p2, pd, vec3(h.e[1], vc, -vb), vec3(h.s[1], h.s[2], sd), 0.0);
            opposite = a;
        } else if (sa == -1 && sc == 1) {
            o = Hit(ivec3(c, a, d), h.p2, h.p0, pd, vec3(h.e[2], va, -vc), vec3(h.s[2], h.s[0], sd), 0.0);
            opposite = b;
        } else {
            status = TPK_VK_STATUS_MESH;
            break;
        }
        vec3 w = face_weights(o);
        float t_out = hit_t(o, w);
        if (!(t_out >= h.t))
            t_out = h.t; // rounding: keep the chain monotone
        o.t = t_out;
        float s_out = hit_scalar(o, w);

        int next;
        if (LAYOUT == TPK_VK_LAYOUT_TET32) {
            int v3 = rec0[3] ^ rec0[0] ^ rec0[1] ^ rec0[2];
            int k = opposite == rec0[0] ? 0 : opposite == rec0[1] ? 1 : opposite == rec0[2] ? 2
                  : opposite == v3      ? 3 : -1;
            if (k < 0) {
                status = TPK_VK_STATUS_MESH;
                break;
            }
            next = fetch_tets(2u * uint(tet) + 1u)[k];
        } else {
            int r = rank4(opposite, a, b, c, d);
            if (LAYOUT == TPK_VK_LAYOUT_TET20)
                next = fetch_tets(uint(tet) * uint(TPK_VK_TET20_WORDS) + 1u + uint(r)).x;
            else
                next = r == 3 ? n3 : (rec0[1 + r] ^ n3);
        }
        if (next < -1 || next >= tet_count) {
            status = TPK_VK_STATUS_MESH;
            break;
        }
        float piece_in = m.s_in, piece_out = s_out;
        if (P.mode.w == 2) // a tet field: constant in the tet
            piece_in = piece_out = fetch_tet_scalars(uint(tet)).x;
        const int said = MARCH_REPORT(h.t, t_out, piece_in, piece_out, face_from_first(h, d));
        if (said == MARCH_PAUSE) {
            m.step--; // this tet is stepped again on the next call
            steps_taken--;
            result = MARCH_RAY_PAUSED;
            break;
        }
        if (said == MARCH_STOP)
            break;
        if (next < 0) {
            run_exit_t = t_out;
            result = MARCH_RAY_EXIT;
            break;
        }
        m.prev = tet;
        m.tet = next;
        m.h = o;
        m.s_in = s_out;
    }
    return result; // one exit: no `return` inside the loop (Mesa 22.3 mishandled those inlined into loops)
}

// The ray's runs over [tmin, tmax] (march.c, tpk_march_ray): the last shell entry before tmin (the ray
// may start inside), then each next entry in (t, face) order, nearer BVH child first, from where the
// last run left (in a valid mesh runs do not overlap; the margin covers the rounding of t).
MarchTrace MARCH_TRACE_START(float tmin, float tmax)
{
    MarchTrace s;
    Hit h;
    s.t_prev = P.shell_info.x != 0 && bvh_query(0, -INF, tmin, 0.0, -1, h) >= 0 ? h.t : -INF;
    s.face_prev = -1;
    s.t_low = s.t_prev;
    s.tmax = tmax;
    s.in_run = false;
    return s;
}

// Runs the ray on from where s stands. Returns false when a run paused (call again to resume), true
// when the ray is done.
bool MARCH_TRACE(inout MarchTrace s)
{
    bool paused = false;
    while (P.shell_info.x != 0) {
        if (!s.in_run) {
            Hit h;
            int face = bvh_query(1, s.t_low, INF, s.t_prev, s.face_prev, h);
            if (face < 0 || h.t > s.tmax)
                break;
            s.run = MARCH_RUN_START(h, fetch_shell(uint(face)).w);
            s.in_run = true;
            s.t_prev = h.t;
            s.face_prev = face;
        }
        int r = MARCH_RUN(s.run);
        if (r == MARCH_RAY_PAUSED) {
            paused = true;
            break;
        }
        s.in_run = false;
        if (r == MARCH_RAY_DONE)
            break;
        s.t_low = max(s.t_prev, run_exit_t - 1e-5 * abs(run_exit_t) - P.up.w);
    }
    return !paused;
}
