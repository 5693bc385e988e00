/* Levels of detail (levels_internal.h): a level written as a whole .tpk through the converter's own writer
 * into an unnamed file in memory, its bytes mapped from there into the parent's LEVL chunk. */
#define _GNU_SOURCE /* memfd_create */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "levels_internal.h"
#include "write_tpk.h"

/* The level's bytes from the file it was written into: mapped (r->mapped), else read into memory. 0 or -1. */
static int take_level_bytes(int fd, tpk_level *r)
{
    struct stat st;
    if (fstat(fd, &st) != 0 || st.st_size <= 0)
        return -1;
    r->size = (size_t)st.st_size;
    void *map = mmap(NULL, r->size, PROT_READ, MAP_SHARED, fd, 0);
    if (map != MAP_FAILED) {
        r->data = map;
        r->mapped = 1;
        return 0;
    }
    if ((r->data = malloc(r->size)) && pread(fd, r->data, r->size, 0) == (ssize_t)r->size)
        return 0;
    free(r->data);
    r->data = NULL;
    return -1;
}

/* Write the level through the converter's own writer into an unnamed file in memory (a memfd; a
 * temporary file where there is none), and take its bytes. Not a file on disk: the writer flushes what
 * it writes (fsync), and the bytes were then copied into memory (bench/README "Figures behind code
 * comments"). */
int levels_write_file(const tpk_convert_options *o, const tpk_tetmesh *lvl, const int32_t *neighbors, int threads,
                      int k, const char *source_format, const tpk_convert_report *source, tpk_level *r,
                      tpk_diag *diag)
{
    FILE *tmp = NULL;
    int fd = -1, rc = 0;
#ifdef MFD_CLOEXEC
    fd = memfd_create("tetpack-level", MFD_CLOEXEC);
#endif
    if (fd < 0 && (tmp = tmpfile()) != NULL)
        fd = fileno(tmp);
    if (fd < 0)
        rc = tpk_diag_fail(diag, "level %d: cannot make a temporary file", k);
    if (rc == 0) {
        tpk_convert_options lo = *o;
        char name[64];
        snprintf(name, sizeof name, "level %d", k);
        lo.output = name;
        lo.output_fd = fd;
        tpk_header_fields hdr;
        memset(&hdr, 0, sizeof hdr);
        memcpy(hdr.origin, lvl->origin, sizeof hdr.origin);
        levels_bounds_of(lvl->points, lvl->origin, lvl->vertex_count, threads, hdr.bounds_min, hdr.bounds_max);
        /* The file's report: its TMAP and VMAP number the file's source cells and points (spec §16.1),
         * and the pipeline and repairs that made the file made the mesh it was coarsened from; META
         * names them all, as a part's does */
        tpk_convert_report lrep = *source;
        lrep.vertices = lvl->vertex_count;
        lrep.tets = lvl->tet_count;
        rc = tpk_write_tpk(&lo, lvl, neighbors, &hdr, &lrep, source_format, NULL, diag);
        if (rc == 0 && take_level_bytes(fd, r) != 0)
            rc = tpk_diag_fail(diag, "level %d: cannot read back its file", k);
    }
    if (tmp)
        fclose(tmp);
    else if (fd >= 0)
        close(fd);
    return rc;
}

void tpk_levels_free(tpk_levels *levels)
{
    for (int i = 0; i < levels->count; i++)
        if (levels->level[i].mapped)
            munmap(levels->level[i].data, levels->level[i].size);
        else
            free(levels->level[i].data);
    memset(levels, 0, sizeof *levels);
}
