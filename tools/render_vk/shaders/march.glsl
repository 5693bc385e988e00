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

float hit_scalar(Hit h, vec3 w)
{
    return face_sum(face_first(h), w, h.s);
}
