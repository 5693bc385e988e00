/* Storage against error (bench/report part 2).
 *   bench_storage quant FILE.tpk [size=256] [threads=0]
 *     Quantizes the positions (float16 of the stored relative-to-origin float32; 16-bit fixed point
 *     relative to the bounds) and the field (float16; 16-bit fixed point relative to its range) in memory,
 *     as a quantized chunk would store them, and measures what it costs: tets turned flat or inverted,
 *     rays the marcher refuses (TPK_ERR_MESH), rays lost (entered the volume unquantized, not now), rays
 *     walked through another tet sequence, and the image error (bench_scene.h's scene, BI_EXACT) against
 *     the unquantized image. One JSON line per variant, with the bytes a vertex would save.
 *   bench_storage load FILE.tpk... [runs=9 via TPK_BENCH_RUNS]
 *     Load time of each file: tpk_open_path + tpk_load_arrays(first layout, first field) + one pass over
 *     the arrays (pages touched), median of runs with a warm page cache; with the file size. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bench_clock.h"
#include "bench_scene.h"

/* Round to the nearest float16 value (ties to even via rint), overflow to infinity. */
static float to_half(float v)
{
    if (!isfinite(v) || v == 0)
        return v;
    int e;
    frexp(v, &e); /* |v| in [2^(e-1), 2^e) */
    int exp2 = e - 1 < -14 ? -14 : e - 1;
    double quantum = ldexp(1.0, exp2 - 10);
    double q = rint((double)v / quantum) * quantum;
    return fabs(q) > 65504.0 ? copysignf(INFINITY, v) : (float)q;
}

static float to_fixed16(float v, double lo, double hi)
{
    if (!(hi > lo))
        return v;
    double q = rint((v - lo) / (hi - lo) * 65535.0);
    return (float)(lo + q * (hi - lo) / 65535.0);
}

enum { Q_NONE, Q_HALF, Q_FIXED };
static const char *qname[3] = {"float32", "float16", "fixed16"};

static void quantize(const float *src, float *dst, size_t n, int stride, int kind)
{
    for (int k = 0; k < stride; k++) {
        double lo = INFINITY, hi = -INFINITY;
        for (size_t i = k; i < n; i += (size_t)stride)
            lo = fmin(lo, src[i]), hi = fmax(hi, src[i]);
        for (size_t i = k; i < n; i += (size_t)stride)
            dst[i] = kind == Q_HALF ? to_half(src[i]) : kind == Q_FIXED ? to_fixed16(src[i], lo, hi) : src[i];
    }
}

/* ---- The walk of every ray: a hash of its tet sequence, its count, whether it failed --------------- */

typedef struct walk {
    uint64_t hash;
    uint32_t count;
    int32_t failed;
} walk;

static int on_walk(void *user, const tpk_segment *seg)
{
    walk *w = user;
    w->hash = (w->hash ^ (uint64_t)(uint32_t)seg->tet) * 0x100000001b3ull;
    w->count++;
    return 0;
}

typedef struct walk_job {
    const bi_scene *scene;
    walk *walks;
    atomic_int next_row;
} walk_job;

static void *walk_worker(void *arg)
{
    walk_job *job = arg;
    const bi_scene *sc = job->scene;
    for (int y; (y = atomic_fetch_add(&job->next_row, 1)) < sc->height;)
        for (int x = 0; x < sc->width; x++) {
            double dir[3];
            bi_ray_dir(sc, x, y, dir);
            walk *w = &job->walks[(size_t)y * (size_t)sc->width + (size_t)x];
            w->hash = 0xcbf29ce484222325ull, w->count = 0;
            w->failed = tpk_march_ray(sc->marcher, sc->eye, dir, 0, INFINITY, on_walk, w, NULL) != TPK_OK;
        }
    return NULL;
}

static void walk_all(const bi_scene *sc, walk *walks, int threads)
{
    walk_job job = {sc, walks, 0};
    atomic_init(&job.next_row, 0);
    pthread_t tids[64];
    int started = 0;
    for (int i = 0; i < threads - 1 && i < 64; i++)
        started += pthread_create(&tids[started], NULL, walk_worker, &job) == 0;
    walk_worker(&job);
    for (int i = 0; i < started; i++)
        pthread_join(tids[i], NULL);
}

/* Tets with orient3d <= 0 on the given float positions (double arithmetic on exact float inputs). */
static void count_bad_tets(const int32_t *tets, uint64_t n, const float *pos, long *flat, long *inverted)
{
    *flat = *inverted = 0;
    for (uint64_t t = 0; t < n; t++) {
        const float *p[4];
        for (int k = 0; k < 4; k++)
            p[k] = pos + 3 * (size_t)tets[4 * t + k];
        double u[3], v[3], w[3];
        for (int k = 0; k < 3; k++)
            u[k] = (double)p[1][k] - p[0][k], v[k] = (double)p[2][k] - p[0][k], w[k] = (double)p[3][k] - p[0][k];
        double det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                     u[2] * (v[0] * w[1] - v[1] * w[0]);
        *flat += det == 0;
        *inverted += det < 0;
    }
}

static int quant_main(const char *path, int size, int threads)
{
    bench_scene_mesh m;
    if (bench_scene_open(&m, path) != 0)
        return 1;
    tpk_mesh_arrays base;
    tpk_layout layouts[3] = {TPK_LAYOUT_TET16, TPK_LAYOUT_TET20, TPK_LAYOUT_TET32};
    for (int l = 0; l < 3; l++)
        if (tpk_load_arrays(m.file, layouts[l], NULL, 0, &base) == TPK_OK)
            break;
    base.scalars = m.scalars;
    size_t nv = (size_t)base.vertex_count, pixels = (size_t)size * (size_t)size;
    int32_t *tets = malloc(sizeof(int32_t) * 4 * (size_t)base.tet_count);
    float *pos = malloc(sizeof(float) * 3 * nv), *sca = malloc(sizeof(float) * nv);
    float *img0 = malloc(sizeof(float) * 4 * pixels), *img = malloc(sizeof(float) * 4 * pixels);
    walk *w0 = malloc(sizeof(walk) * pixels), *w = malloc(sizeof(walk) * pixels);
    if (!tets || !pos || !sca || !img0 || !img || !w0 || !w || tpk_recover_tets(&base, tets) != TPK_OK)
        return fprintf(stderr, "bench_storage: out of memory or no tets\n"), 1;
    const bi_method exact = {BI_EXACT, 0, 0.05, 1e-3, 0};
    static const int variants[][2] = {{Q_NONE, Q_NONE},  {Q_HALF, Q_NONE},  {Q_FIXED, Q_NONE}, {Q_NONE, Q_HALF},
                                      {Q_NONE, Q_FIXED}, {Q_FIXED, Q_FIXED}, {Q_HALF, Q_HALF}};
    for (size_t v = 0; v < sizeof variants / sizeof variants[0]; v++) {
        quantize(base.positions, pos, 3 * nv, 3, variants[v][0]);
        quantize(m.scalars, sca, nv, 1, variants[v][1]);
        tpk_mesh_arrays q = base;
        q.positions = pos, q.scalars = sca;
        long flat, inverted;
        count_bad_tets(tets, base.tet_count, pos, &flat, &inverted);
        tpk_marcher *marcher;
        if (tpk_marcher_create(&marcher, &q) != TPK_OK)
            return fprintf(stderr, "bench_storage: marcher\n"), 1;
        bi_scene sc;
        bench_scene_setup(&sc, &m, marcher, size, size);
        int failed = bi_render(&sc, &exact, threads, v ? img : img0, NULL);
        walk_all(&sc, v ? w : w0, threads);
        long refused = 0, lost = 0, differs = 0, entered = 0;
        for (size_t i = 0; i < pixels; i++) {
            entered += w0[i].count > 0;
            if (!v)
                continue;
            refused += w[i].failed;
            lost += w0[i].count > 0 && (w[i].failed || w[i].count == 0);
            differs += w[i].hash != w0[i].hash || w[i].count != w0[i].count || w[i].failed;
        }
        double mx = 0, rmse = v ? bi_rmse(img0, img, pixels, &mx) : 0;
        /* bytes per vertex: positions 12 -> 6, each field step 4 -> 2 */
        int saved = (variants[v][0] ? 6 : 0) + (variants[v][1] ? 2 : 0);
        printf("{\"bench\":\"quantize\",\"file\":\"%s\",\"tets\":%llu,\"vertices\":%zu,\"positions\":\"%s\","
               "\"field\":\"%s\",\"flat_tets\":%ld,\"inverted_tets\":%ld,\"rays\":%zu,\"rays_entering\":%ld,"
               "\"rays_refused\":%ld,\"render_failed\":%d,\"rays_lost\":%ld,\"rays_walk_differs\":%ld,"
               "\"rmse\":%.4e,\"psnr\":%.2f,\"max_abs\":%.3e,\"bytes_saved_per_vertex\":%d,"
               "\"bytes_saved_per_tet\":%.3f,\"file_bytes_per_tet\":%.3f}\n",
               path, (unsigned long long)base.tet_count, nv, qname[variants[v][0]], qname[variants[v][1]], flat,
               inverted, pixels, entered, refused, failed, lost, differs, rmse, fmin(bi_psnr(rmse), 999.0), mx, saved,
               (double)saved * (double)nv / (double)base.tet_count,
               (double)m.info.file_size / (double)base.tet_count);
        fflush(stdout);
        tpk_marcher_destroy(marcher);
    }
    free(tets), free(pos), free(sca), free(img0), free(img), free(w0), free(w);
    bench_scene_close(&m);
    return 0;
}

/* ---- Load time ---------------------------------------------------------------------------------- */

static double load_once(const char *path, double *checksum)
{
    double t0 = now();
    tpk_file *f;
    char err[256];
    if (tpk_open_path(&f, path, NULL, err, sizeof err) != TPK_OK)
        return fprintf(stderr, "%s: %s\n", path, err), -1;
    tpk_mesh_arrays a;
    tpk_layout layouts[3] = {TPK_LAYOUT_TET16, TPK_LAYOUT_TET20, TPK_LAYOUT_TET32};
    int ok = 0;
    for (int l = 0; l < 3 && !ok; l++)
        ok = tpk_load_arrays(f, layouts[l], NULL, 0, &a) == TPK_OK;
    if (!ok)
        return fprintf(stderr, "%s: %s\n", path, tpk_error_text(f)), tpk_close(f), -1;
    const unsigned char *recs = a.tet16 ? (const void *)a.tet16 : a.tet20 ? (const void *)a.tet20 : (const void *)a.tet32;
    size_t rec_bytes = (size_t)a.tet_count * (size_t)a.layout;
    double sum = 0;
    for (size_t i = 0; i < rec_bytes; i += 64) /* touch every cache line once: zero-copy maps read too */
        sum += recs[i];
    for (uint64_t v = 0; v < a.vertex_count; v++)
        sum += a.positions[3 * v] + (a.scalars ? a.scalars[v] : 0);
    *checksum += sum;
    tpk_close(f);
    return now() - t0;
}

static int load_main(int argc, char **argv)
{
    const char *env = getenv("TPK_BENCH_RUNS");
    int runs = env && atoi(env) > 0 ? atoi(env) : 9;
    runs = runs > 99 ? 99 : runs;
    for (int i = 0; i < argc; i++) {
        double times[99], checksum = 0;
        FILE *fp = fopen(argv[i], "rb");
        if (!fp)
            return fprintf(stderr, "bench_storage: cannot open %s\n", argv[i]), 1;
        fseek(fp, 0, SEEK_END);
        long bytes = ftell(fp);
        fclose(fp);
        load_once(argv[i], &checksum); /* warm the page cache */
        for (int r = 0; r < runs; r++)
            if ((times[r] = load_once(argv[i], &checksum)) < 0)
                return 1;
        qsort(times, (size_t)runs, sizeof times[0], bench_compare_double);
        printf("{\"bench\":\"load\",\"file\":\"%s\",\"bytes\":%ld,\"runs\":%d,\"median_ms\":%.3f,\"min_ms\":%.3f,"
               "\"checksum\":%.6g}\n",
               argv[i], bytes, runs, times[runs / 2] * 1e3, times[0] * 1e3, checksum);
        fflush(stdout);
    }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc >= 3 && strcmp(argv[1], "quant") == 0) {
        int threads = argc > 4 ? atoi(argv[4]) : 0;
        return quant_main(argv[2], argc > 3 ? atoi(argv[3]) : 256,
                          threads > 0 ? threads : (int)sysconf(_SC_NPROCESSORS_ONLN));
    }
    if (argc >= 3 && strcmp(argv[1], "load") == 0)
        return load_main(argc - 2, argv + 2);
    fprintf(stderr, "usage: bench_storage quant FILE.tpk [size] [threads] | bench_storage load FILE.tpk...\n");
    return 2;
}
