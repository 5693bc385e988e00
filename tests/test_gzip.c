/* Gzip inputs (tools/import/gzip_input.h and the registry's .gz path): inflation of one and several
 * members against zlib's own deflate, the size limit (the trailer's size field lies mod 2^32), every
 * truncation, and tpk_import_any on a real mesh gzipped: the same mesh as the file itself; formats
 * without a memory reader refused by name. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "harness.h"
#include "import/gzip_input.h"
#include "import/importers.h"

/* `text` as one gzip member (zlib's deflate with a gzip wrapper) appended to buf at *used. */
static void gzip_member(const char *text, size_t n, unsigned char *buf, size_t cap, size_t *used)
{
    z_stream z;
    memset(&z, 0, sizeof z);
    if (deflateInit2(&z, 6, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) != Z_OK)
        return;
    z.next_in = (unsigned char *)text;
    z.avail_in = (uInt)n;
    z.next_out = buf + *used;
    z.avail_out = (uInt)(cap - *used);
    deflate(&z, Z_FINISH);
    *used = cap - z.avail_out;
    deflateEnd(&z);
}

static void quiet(tpk_diag *d)
{
    memset(d, 0, sizeof *d);
}

static void silent(void *user, const char *text)
{
    (void)user;
    (void)text;
}

TPK_TEST(members_and_limit)
{
    static unsigned char gz[1 << 16];
    size_t used = 0;
    char big[20000];
    for (size_t i = 0; i < sizeof big; i++)
        big[i] = (char)('a' + (i * 7) % 26);
    gzip_member(big, sizeof big, gz, sizeof gz, &used);
    size_t one = used;
    gzip_member("tail", 4, gz, sizeof gz, &used);
    char *out;
    size_t n;
    tpk_diag d;
    quiet(&d);
    CHECK_MSG(tpk_gzip_inflate("x.gz", (char *)gz, used, 0, &out, &n, &d) == 0, "%s", d.message);
    CHECK(n == sizeof big + 4 && memcmp(out, big, sizeof big) == 0 && memcmp(out + sizeof big, "tail", 4) == 0);
    free(out);
    /* the limit: exactly the size passes, one byte less is refused */
    CHECK(tpk_gzip_inflate("x.gz", (char *)gz, one, sizeof big, &out, &n, &d) == 0 && n == sizeof big);
    free(out);
    CHECK(tpk_gzip_inflate("x.gz", (char *)gz, one, sizeof big - 1, &out, &n, &d) != 0 && out == NULL);
    CHECK_MSG(strstr(d.message, "x.gz: inflates to more than 19999 bytes"), "%s", d.message);
    /* a trailer claiming 4 GiB + 5 bytes is only a hint: the real size comes out */
    gz[one - 1] = 1;
    CHECK_MSG(tpk_gzip_inflate("x.gz", (char *)gz, one, 0, &out, &n, &d) != 0 && strstr(d.message, "byte"),
              "a wrong size field must fail zlib's length check: %s", d.message);
    gz[one - 1] = 0;
    /* bytes after the last member that start no other: ignored with a warning */
    memcpy(gz + one, "junk", 4);
    d.warn = silent;
    CHECK(tpk_gzip_inflate("x.gz", (char *)gz, one + 4, 0, &out, &n, &d) == 0 && n == sizeof big &&
          d.warning_count == 1);
    free(out);
    CHECK(tpk_gzip_inflate("x.gz", "# vtk", 5, 0, &out, &n, &d) != 0 &&
          strstr(d.message, "x.gz: byte 0: expected the gzip signature 1f 8b"));
}

/* Every prefix of a gzip stream fails with a placed message (or is whole); the copy has the exact
 * size, so ASan catches an overread. */
TPK_TEST(every_truncation)
{
    unsigned char gz[512];
    size_t used = 0;
    gzip_member("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n", 35, gz, sizeof gz, &used);
    for (size_t cut = 0; cut < used; cut++) {
        char *copy = malloc(cut ? cut : 1), *out;
        memcpy(copy, gz, cut);
        size_t n;
        tpk_diag d;
        quiet(&d);
        int rc = tpk_gzip_inflate("cut.gz", copy, cut, 0, &out, &n, &d);
        free(copy);
        CHECK_MSG(rc != 0 && out == NULL && strstr(d.message, "cut.gz: byte "), "prefix %zu: '%s'", cut, d.message);
    }
}

/* A real Gmsh file gzipped reads as the same mesh; errors name the .gz file. */
TPK_TEST(registry_reads_gz)
{
    const char *src = tpk_data_path("gmsh/t5_small_tet_ascii22.msh");
    char gzpath[] = "/tmp/tpk_gz_XXXXXX.msh.gz";
    int fd = mkstemps(gzpath, 7);
    CHECK(fd >= 0);
    gzFile g = gzdopen(fd, "wb");
    FILE *f = fopen(src, "rb");
    char chunk[4096];
    size_t got;
    while (f && g && (got = fread(chunk, 1, sizeof chunk, f)) > 0)
        gzwrite(g, chunk, (unsigned)got);
    if (f)
        fclose(f);
    gzclose(g);
    tpk_mesh a, b;
    tpk_diag d;
    quiet(&d);
    CHECK_MSG(tpk_import_any(src, NULL, &a, &d) == 0, "%s", d.message);
    CHECK_MSG(tpk_import_any(gzpath, NULL, &b, &d) == 0, "%s", d.message);
    CHECK(a.point_count == b.point_count && a.cell_count == b.cell_count && a.cell_count > 0 &&
          !memcmp(a.points, b.points, sizeof *a.points * 3 * (size_t)a.point_count) &&
          !memcmp(a.cell_conn, b.cell_conn, sizeof *a.cell_conn * (size_t)a.cell_offsets[a.cell_count]));
    CHECK(tpk_import_format_detect(gzpath) == tpk_import_format_named("gmsh", NULL));
    tpk_mesh_free(&a);
    tpk_mesh_free(&b);
    /* forced to a format with no memory reader: refused by name */
    CHECK(tpk_import_any(gzpath, "exodus", &b, &d) != 0 && strstr(d.message, "exodus input is not read compressed"));
    /* forced to another reader: its message, placed in the inflated text, names the .gz file */
    size_t n = strlen(gzpath);
    CHECK_MSG(tpk_import_any(gzpath, "medit", &b, &d) != 0 && !strncmp(d.message, gzpath, n) &&
                  !strncmp(d.message + n, ":1: expected 'MeshVersionFormatted'", 35),
              "%s", d.message);
    remove(gzpath);
}
