/* Benchmark of the reference CPU marcher: tet steps per second per layout (Tet32/20/16) and thread
 * count, on a Kuhn-split grid of N^3 cubes (6 N^3 tets) in Hilbert order, as the converter writes it.
 * usage: bench_march [N=55] [runs=3] [image=512] [threads list, default "1 2"]
 * One JSON line per layout and thread count (median of runs), primary rays of a pinhole camera from the
 * default 3/4 view; every piece is consumed (no early termination), shell search included. */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_clock.h"
#include "../tests/march_fixtures.h"
#include "mesh/mesh.h"
#include "convert/pipeline.h"
#include "render/render.h"

typedef struct bench_job {
    const tpk_marcher *marcher;
    double eye[3], forward[3], right[3], up[3];
    int size;
    atomic_int next_row;
    atomic_uint_least64_t steps;
    atomic_int errors;
    double checksum[64];
} bench_job;

static int consume(void *user, const tpk_segment *s)
{
    double *acc = user;
    *acc += (s->t_out - s->t_in) * (s->scalar_in + s->scalar_out);
    return 0;
}

static void *bench_worker(void *arg)
{
    bench_job *job = arg;
    uint64_t steps = 0;
    double acc = 0;
    for (;;) {
        int y = atomic_fetch_add(&job->next_row, 1);
        if (y >= job->size)
            break;
        for (int x = 0; x < job->size; x++) {
            double px = (2.0 * (x + 0.5) / job->size - 1.0) * 0.3, py = (1.0 - 2.0 * (y + 0.5) / job->size) * 0.3;
            double dir[3];
            for (int k = 0; k < 3; k++)
                dir[k] = job->forward[k] + px * job->right[k] + py * job->up[k];
            tpk_march_stats st;
            if (tpk_march_ray(job->marcher, job->eye, dir, 0, INFINITY, consume, &acc, &st) != TPK_OK)
                atomic_fetch_add(&job->errors, 1);
            steps += st.tet_steps;
        }
    }
    atomic_fetch_add(&job->steps, steps);
    return NULL;
}

static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static void normalize3(double v[3])
{
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int k = 0; k < 3; k++)
        v[k] /= l;
}

/* One timed pass; returns wall seconds, *cpu the process CPU seconds, *steps the tet steps. */
static double run_once(const tpk_marcher *marcher, const tpk_camera *cam, int size, int threads, uint64_t *steps,
                       double *cpu)
{
    bench_job job;
    memset(&job, 0, sizeof job);
    job.marcher = marcher;
    job.size = size;
    for (int k = 0; k < 3; k++) {
        job.eye[k] = cam->eye[k];
        job.forward[k] = cam->at[k] - cam->eye[k];
    }
    normalize3(job.forward);
    cross3(job.forward, cam->up, job.right);
    normalize3(job.right);
    cross3(job.right, job.forward, job.up);
    atomic_init(&job.next_row, 0);
    atomic_init(&job.steps, 0);
    atomic_init(&job.errors, 0);
    pthread_t tids[64];
    double t0 = now(), c0 = cpu_now();
    for (int i = 0; i < threads - 1; i++)
        pthread_create(&tids[i], NULL, bench_worker, &job);
    bench_worker(&job);
    for (int i = 0; i < threads - 1; i++)
        pthread_join(tids[i], NULL);
    double t = now() - t0;
    *cpu = cpu_now() - c0;
    if (atomic_load(&job.errors))
        fprintf(stderr, "bench_march: %d rays failed\n", atomic_load(&job.errors));
    *steps = atomic_load(&job.steps);
    return t;
}

static int compare_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The grid through the converter's reorder stage, then layouts and shell. */
static int make_mesh(int n, fx_mesh *m)
{
    if (fx_grid(m, n, n, n, NULL, 1.0, NULL) != 0)
        return -1;
    tpk_tetmesh tm;
    memset(&tm, 0, sizeof tm);
    tm.vertex_count = m->vertex_count;
    tm.tet_count = m->tet_count;
    tm.points = m->points;
    tm.tets = m->tets;
    tm.step_count = 1;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_reorder(&tm, 0, &diag) != 0) {
        fprintf(stderr, "bench_march: reorder: %s\n", diag.message);
        return -1;
    }
    m->points = tm.points;
    m->tets = tm.tets;
    free(tm.vertex_source);
    free(tm.tet_source);
    for (int64_t i = 0; i < 3 * m->vertex_count; i++)
        m->positions[i] = (float)m->points[i];
    m->scalars = malloc((size_t)m->vertex_count * sizeof(float));
    if (!m->scalars)
        return -1;
    for (int64_t v = 0; v < m->vertex_count; v++)
        m->scalars[v] = m->positions[3 * v] + 2 * m->positions[3 * v + 1];
    return fx_build(m);
}

int main(int argc, char **argv)
{
    int n = argc > 1 ? atoi(argv[1]) : 55;
    int runs = argc > 2 ? atoi(argv[2]) : 3;
    int size = argc > 3 ? atoi(argv[3]) : 512;
    int thread_list[8] = {1, 2}, thread_count = 2;
    if (argc > 4) {
        thread_count = 0;
        for (int i = 4; i < argc && thread_count < 8; i++)
            thread_list[thread_count++] = atoi(argv[i]);
    }
    if (n < 1 || runs < 1 || runs > 99 || size < 1)
        return fprintf(stderr, "usage: bench_march [N] [runs] [image] [threads...]\n"), 2;
    fx_mesh m;
    double t0 = now();
    if (make_mesh(n, &m) != 0)
        return fprintf(stderr, "bench_march: cannot build the mesh\n"), 1;
    fprintf(stderr, "mesh: %lld tets, %lld shell faces, built in %.2f s\n", (long long)m.tet_count,
            (long long)m.shell_count, now() - t0);
    const double lo[3] = {0, 0, 0}, hi[3] = {n, n, n};
    tpk_camera cam;
    tpk_camera_default(lo, hi, &cam);
    const tpk_layout layouts[3] = {TPK_LAYOUT_TET32, TPK_LAYOUT_TET20, TPK_LAYOUT_TET16};
    for (int l = 0; l < 3; l++) {
        tpk_mesh_arrays arrays = fx_arrays(&m, layouts[l]);
        tpk_marcher *marcher;
        if (tpk_marcher_create(&marcher, &arrays) != TPK_OK)
            return fprintf(stderr, "bench_march: marcher\n"), 1;
        for (int ti = 0; ti < thread_count; ti++) {
            double rates[99], cpu_rates[99];
            uint64_t steps = 0;
            for (int r = 0; r < runs; r++) {
                double cpu;
                double t = run_once(marcher, &cam, size, thread_list[ti], &steps, &cpu);
                rates[r] = (double)steps / t;
                cpu_rates[r] = (double)steps / cpu;
            }
            qsort(rates, (size_t)runs, sizeof rates[0], compare_double);
            qsort(cpu_rates, (size_t)runs, sizeof cpu_rates[0], compare_double);
            /* msteps_per_s: wall clock (all threads); msteps_per_cpu_s: per busy core, less sensitive
             * to other load on a shared machine */
            printf("{\"bench\":\"march\",\"tets\":%lld,\"layout\":\"tet%d\",\"threads\":%d,\"rays\":%d,"
                   "\"tet_steps\":%llu,\"msteps_per_s\":%.2f,\"msteps_per_cpu_s\":%.2f}\n",
                   (long long)m.tet_count, (int)layouts[l], thread_list[ti], size * size,
                   (unsigned long long)steps, rates[runs / 2] * 1e-6, cpu_rates[runs / 2] * 1e-6);
            fflush(stdout);
        }
        tpk_marcher_destroy(marcher);
    }
    fx_free(&m);
    return 0;
}
