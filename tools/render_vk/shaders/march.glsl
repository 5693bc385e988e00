// Part of render.comp, included once, in the order it lists.
// The state of a ray's inside-runs (libtetpack/march.c); march_run.glsl is the run itself.

// ---- One inside-run (march.c, march_run) --------------------------------------------------------

uint steps_taken;
uint status;
float run_exit_t; // t of the shell face the last run left through

// What a piece tells the march (MARCH_REPORT), and how a run ends (march_run.glsl).
#define MARCH_GO 0
#define MARCH_STOP 1
#define MARCH_PAUSE 2
#define MARCH_RAY_DONE 0
#define MARCH_RAY_EXIT 1
#define MARCH_RAY_PAUSED 2

struct MarchRun { // one inside-run, resumable: the tet to step next and how it was entered
    Hit h;
    int tet, prev, step;
    float s_in;
};

struct MarchTrace { // the runs of one ray, resumable
    MarchRun run;
    float t_prev, t_low, tmax;
    int face_prev;
    bool in_run;
};

int rank4(int x, int a, int b, int c, int d)
{
    return int(a < x) + int(b < x) + int(c < x) + int(d < x);
}

// A piece [t_in, t_out] with scalars s_in, s_out, cut to [lo, hi] (primary rays: the clip box's range;
// secondary rays: the cast's): false when it ends before lo; else the cut piece in a, b, sa, sb, the
// scalars interpolated along t as the CPU's march does.
bool clip_piece(float t_in, float t_out, float s_in, float s_out, float lo, float hi, out float a, out float b,
                out float sa, out float sb)
{
    a = t_in, b = t_out, sa = s_in, sb = s_out;
    if (t_out < lo)
        return false;
    const float len = t_out - t_in;
    if (t_in < lo) {
        a = lo;
        sa = s_in + (s_out - s_in) * ((lo - t_in) / len);
    }
    if (t_out > hi) {
        b = hi;
        sb = s_in + (s_out - s_in) * ((hi - t_in) / len);
    }
    return true;
}

float hit_scalar(Hit h, vec3 w)
{
    return face_sum(face_first(h), w, h.s);
}
