/* make_exodus_pieces IN.e OUT_BASE N: cut an Exodus mesh into N Exodus files per processor, as SEACAS's
 * nem_slice + nem_spread do (Debian packages neither): OUT_BASE.N.K, K = 0 .. N-1 zero-padded to the
 * digits of N, each a whole Exodus file with its own node and element numbering, a node number map and an
 * element number map giving the input's ids, every element block (empty where the processor has none of
 * its elements), the nodal and element variables at every time step, and the time values. The cut is
 * spatial and balanced: elements sorted by centroid x, the k-th N-th to processor k. A test tool for
 * tetpack-mpi (tests/mpi/mpi_convert.sh); exits 2 with a message on any failure. */
#include <exodusII.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct block {
    int64_t id, count, per, first; /* first: the block's first element in the input's element order */
    char type[MAX_STR_LENGTH + 1];
    int64_t *conn;                 /* count * per input node ids, 1-based */
} block;

typedef struct input {
    int exoid;
    int64_t nodes, elems, nblocks, steps;
    int nvars[2];            /* nodal, element */
    char **names[2];
    int *truth;              /* nblocks * element vars */
    double *xyz[3];
    int64_t *node_map, *elem_map;
    block *blocks;
    int *part;               /* per element: its processor */
} input;

static void die(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("make_exodus_pieces: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    exit(2);
}

static void *alloc(size_t n)
{
    void *p = calloc(n ? n : 1, 1);
    if (!p)
        die("out of memory");
    return p;
}

static void read_blocks(input *in)
{
    int64_t *ids = alloc(sizeof *ids * (size_t)in->nblocks), first = 0;
    in->blocks = alloc(sizeof *in->blocks * (size_t)in->nblocks);
    if (ex_get_ids(in->exoid, EX_ELEM_BLOCK, ids) < 0)
        die("cannot read the block ids");
    for (int64_t b = 0; b < in->nblocks; b++) {
        block *blk = &in->blocks[b];
        int64_t edges, faces, attrs;
        blk->id = ids[b], blk->first = first;
        if (ex_get_block(in->exoid, EX_ELEM_BLOCK, blk->id, blk->type, &blk->count, &blk->per, &edges, &faces,
                         &attrs) < 0)
            die("cannot read block %lld", (long long)blk->id);
        blk->conn = alloc(sizeof *blk->conn * (size_t)(blk->count * blk->per));
        if (blk->count && ex_get_conn(in->exoid, EX_ELEM_BLOCK, blk->id, blk->conn, NULL, NULL) < 0)
            die("cannot read the connectivity of block %lld", (long long)blk->id);
        first += blk->count;
    }
    free(ids);
}

static void read_names(input *in, int which, ex_entity_type type)
{
    if (ex_get_variable_param(in->exoid, type, &in->nvars[which]) < 0)
        die("cannot read the variable counts");
    in->names[which] = alloc(sizeof(char *) * (size_t)in->nvars[which]);
    for (int v = 0; v < in->nvars[which]; v++)
        in->names[which][v] = alloc(MAX_STR_LENGTH + 1);
    if (in->nvars[which] && ex_get_variable_names(in->exoid, type, in->nvars[which], in->names[which]) < 0)
        die("cannot read the variable names");
}

static void read_input(const char *path, input *in)
{
    int cpu_ws = 8, io_ws = 0;
    float version;
    if ((in->exoid = ex_open(path, EX_READ, &cpu_ws, &io_ws, &version)) < 0)
        die("%s: cannot open", path);
    ex_set_int64_status(in->exoid, EX_ALL_INT64_API);
    ex_init_params p;
    if (ex_get_init_ext(in->exoid, &p) < 0 || p.num_dim != 3)
        die("%s: expected a 3-D Exodus mesh", path);
    in->nodes = p.num_nodes, in->elems = p.num_elem, in->nblocks = p.num_elem_blk;
    in->steps = ex_inquire_int(in->exoid, EX_INQ_TIME);
    for (int k = 0; k < 3; k++)
        in->xyz[k] = alloc(sizeof(double) * (size_t)in->nodes);
    in->node_map = alloc(sizeof *in->node_map * (size_t)in->nodes);
    in->elem_map = alloc(sizeof *in->elem_map * (size_t)in->elems);
    if (ex_get_coord(in->exoid, in->xyz[0], in->xyz[1], in->xyz[2]) < 0 ||
        ex_get_id_map(in->exoid, EX_NODE_MAP, in->node_map) < 0 ||
        ex_get_id_map(in->exoid, EX_ELEM_MAP, in->elem_map) < 0)
        die("%s: cannot read the coordinates or number maps", path);
    read_blocks(in);
    read_names(in, 0, EX_NODAL);
    read_names(in, 1, EX_ELEM_BLOCK);
    in->truth = alloc(sizeof *in->truth * (size_t)(in->nblocks * in->nvars[1]));
    if (in->nvars[1] && ex_get_truth_table(in->exoid, EX_ELEM_BLOCK, (int)in->nblocks, in->nvars[1], in->truth) < 0)
        die("%s: cannot read the element variable truth table", path);
}

static const double *centroid_x;

static int by_centroid(const void *a, const void *b)
{
    int64_t i = *(const int64_t *)a, j = *(const int64_t *)b;
    if (centroid_x[i] != centroid_x[j])
        return centroid_x[i] < centroid_x[j] ? -1 : 1;
    return (i > j) - (i < j);
}

/* Elements sorted by centroid x; the k-th N-th goes to processor k. */
static void cut(input *in, int n)
{
    double *cx = alloc(sizeof *cx * (size_t)in->elems);
    int64_t *order = alloc(sizeof *order * (size_t)in->elems);
    for (int64_t b = 0; b < in->nblocks; b++)
        for (int64_t e = 0; e < in->blocks[b].count; e++) {
            const block *blk = &in->blocks[b];
            for (int64_t k = 0; k < blk->per; k++)
                cx[blk->first + e] += in->xyz[0][blk->conn[e * blk->per + k] - 1] / (double)blk->per;
        }
    for (int64_t i = 0; i < in->elems; i++)
        order[i] = i;
    centroid_x = cx;
    qsort(order, (size_t)in->elems, sizeof *order, by_centroid);
    in->part = alloc(sizeof *in->part * (size_t)in->elems);
    for (int64_t i = 0; i < in->elems; i++)
        in->part[order[i]] = (int)(i * n / in->elems);
    free(cx), free(order);
}

/* One processor's nodes in order of first use by its elements (input 1-based id -> local 1-based in
 * local[], local -> input in *nodes_of); returns their count. */
static int64_t local_nodes(const input *in, int k, int64_t *local, int64_t *nodes_of)
{
    int64_t count = 0;
    memset(local, 0, sizeof *local * (size_t)in->nodes);
    for (int64_t b = 0; b < in->nblocks; b++)
        for (int64_t e = 0; e < in->blocks[b].count; e++) {
            const block *blk = &in->blocks[b];
            if (in->part[blk->first + e] != k)
                continue;
            for (int64_t j = 0; j < blk->per; j++) {
                int64_t v = blk->conn[e * blk->per + j] - 1;
                if (!local[v]) {
                    local[v] = ++count;
                    nodes_of[count - 1] = v;
                }
            }
        }
    return count;
}

/* Every step's nodal and element variables, restricted to the processor's nodes and elements. */
static void write_variables(const input *in, int out, int k, const int64_t *nodes_of, int64_t count)
{
    double *buf = alloc(sizeof *buf * (size_t)(in->nodes > in->elems ? in->nodes : in->elems));
    double *sub = alloc(sizeof *sub * (size_t)(in->nodes > in->elems ? in->nodes : in->elems));
    for (int64_t s = 1; s <= in->steps; s++) {
        double t;
        if (ex_get_time(in->exoid, (int)s, &t) < 0 || ex_put_time(out, (int)s, &t) < 0)
            die("cannot copy time step %lld", (long long)s);
        for (int v = 1; v <= in->nvars[0]; v++) {
            if (ex_get_var(in->exoid, (int)s, EX_NODAL, v, 1, in->nodes, buf) < 0)
                die("cannot read nodal variable %d", v);
            for (int64_t i = 0; i < count; i++)
                sub[i] = buf[nodes_of[i]];
            if (ex_put_var(out, (int)s, EX_NODAL, v, 1, count, sub) < 0)
                die("cannot write nodal variable %d", v);
        }
        for (int64_t b = 0; b < in->nblocks; b++)
            for (int v = 1; v <= in->nvars[1]; v++) {
                const block *blk = &in->blocks[b];
                int64_t n = 0;
                if (!in->truth[b * in->nvars[1] + v - 1] || !blk->count)
                    continue;
                if (ex_get_var(in->exoid, (int)s, EX_ELEM_BLOCK, v, blk->id, blk->count, buf) < 0)
                    die("cannot read element variable %d on block %lld", v, (long long)blk->id);
                for (int64_t e = 0; e < blk->count; e++)
                    if (in->part[blk->first + e] == k)
                        sub[n++] = buf[e];
                if (n && ex_put_var(out, (int)s, EX_ELEM_BLOCK, v, blk->id, n, sub) < 0)
                    die("cannot write element variable %d on block %lld", v, (long long)blk->id);
            }
    }
    free(buf), free(sub);
}

/* Processor k's blocks (all of them, empty where it has none of the block's elements), connectivity in
 * its local node ids, and its element number map. */
static void write_blocks(const input *in, int out, int k, const int64_t *local)
{
    int64_t *conn = NULL, *emap = alloc(sizeof *emap * (size_t)in->elems), ne = 0;
    for (int64_t b = 0; b < in->nblocks; b++) {
        const block *blk = &in->blocks[b];
        int64_t n = 0;
        free(conn);
        conn = alloc(sizeof *conn * (size_t)(blk->count * blk->per));
        for (int64_t e = 0; e < blk->count; e++) {
            if (in->part[blk->first + e] != k)
                continue;
            for (int64_t j = 0; j < blk->per; j++)
                conn[n * blk->per + j] = local[blk->conn[e * blk->per + j] - 1];
            emap[ne++] = in->elem_map[blk->first + e];
            n++;
        }
        if (ex_put_block(out, EX_ELEM_BLOCK, blk->id, blk->type, n, blk->per, 0, 0, 0) < 0 ||
            (n && ex_put_conn(out, EX_ELEM_BLOCK, blk->id, conn, NULL, NULL) < 0))
            die("cannot write block %lld", (long long)blk->id);
    }
    if (ex_put_id_map(out, EX_ELEM_MAP, emap) < 0)
        die("cannot write the element number map");
    free(conn), free(emap);
}

static void write_piece(const input *in, const char *path, int k, int64_t *local, int64_t *nodes_of)
{
    int64_t count = local_nodes(in, k, local, nodes_of), elems = 0;
    for (int64_t e = 0; e < in->elems; e++)
        elems += in->part[e] == k;
    int cpu_ws = 8, io_ws = 8;
    int out = ex_create(path, EX_CLOBBER | EX_ALL_INT64_API, &cpu_ws, &io_ws);
    if (out < 0)
        die("%s: cannot create", path);
    ex_init_params p = {.num_dim = 3, .num_nodes = count, .num_elem = elems, .num_elem_blk = in->nblocks};
    snprintf(p.title, sizeof p.title, "processor %d of a decomposed mesh", k);
    double *xyz[3];
    int64_t *nmap = alloc(sizeof *nmap * (size_t)count);
    for (int c = 0; c < 3; c++) {
        xyz[c] = alloc(sizeof(double) * (size_t)count);
        for (int64_t i = 0; i < count; i++)
            xyz[c][i] = in->xyz[c][nodes_of[i]];
    }
    for (int64_t i = 0; i < count; i++)
        nmap[i] = in->node_map[nodes_of[i]];
    if (ex_put_init_ext(out, &p) < 0 || ex_put_coord(out, xyz[0], xyz[1], xyz[2]) < 0 ||
        ex_put_id_map(out, EX_NODE_MAP, nmap) < 0)
        die("%s: cannot write the nodes", path);
    write_blocks(in, out, k, local);
    if ((in->nvars[0] && (ex_put_variable_param(out, EX_NODAL, in->nvars[0]) < 0 ||
                          ex_put_variable_names(out, EX_NODAL, in->nvars[0], in->names[0]) < 0)) ||
        (in->nvars[1] && (ex_put_variable_param(out, EX_ELEM_BLOCK, in->nvars[1]) < 0 ||
                          ex_put_variable_names(out, EX_ELEM_BLOCK, in->nvars[1], in->names[1]) < 0 ||
                          ex_put_truth_table(out, EX_ELEM_BLOCK, (int)in->nblocks, in->nvars[1], in->truth) < 0)))
        die("%s: cannot write the variable names", path);
    write_variables(in, out, k, nodes_of, count);
    if (ex_close(out) < 0)
        die("%s: cannot close", path);
    for (int c = 0; c < 3; c++)
        free(xyz[c]);
    free(nmap);
}

int main(int argc, char **argv)
{
    int n = argc == 4 ? atoi(argv[3]) : 0;
    if (n < 1)
        die("usage: make_exodus_pieces IN.e OUT_BASE N (N >= 1 processors)");
    input in;
    memset(&in, 0, sizeof in);
    ex_opts(EX_VERBOSE);
    read_input(argv[1], &in);
    if (in.elems < n)
        die("%s: %lld elements for %d processors", argv[1], (long long)in.elems, n);
    cut(&in, n);
    int64_t *local = alloc(sizeof *local * (size_t)in.nodes), *nodes_of = alloc(sizeof *nodes_of * (size_t)in.nodes);
    int width = snprintf(NULL, 0, "%d", n);
    for (int k = 0; k < n; k++) {
        size_t need = strlen(argv[2]) + 32;
        char *path = alloc(need);
        snprintf(path, need, "%s.%d.%0*d", argv[2], n, width, k);
        write_piece(&in, path, k, local, nodes_of);
        free(path);
    }
    ex_close(in.exoid);
    for (int w = 0; w < 2; w++) {
        for (int v = 0; v < in.nvars[w]; v++)
            free(in.names[w][v]);
        free(in.names[w]);
    }
    for (int64_t b = 0; b < in.nblocks; b++)
        free(in.blocks[b].conn);
    for (int c = 0; c < 3; c++)
        free(in.xyz[c]);
    free(in.blocks), free(in.truth), free(in.node_map), free(in.elem_map), free(in.part), free(local), free(nodes_of);
    return 0;
}
