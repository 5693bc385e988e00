/* Output files (tools/base/output_file.h), the files an input consists of (tpk_import_input_files) and
 * the container writer's caller-owned fd (tpk_writer_open_fd). The command-line side, with killed
 * processes, is tests/cli/outputs.sh. */
#include <dirent.h>
#include <fcntl.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "base/output_file.h"
#include "convert/convert.h"
#include "harness.h"
#include "import/importers.h"
#include "tetpack.h"

/* Entries of directory `dir`, "." and ".." left out. */
static int entry_count(const char *dir)
{
    DIR *d = opendir(dir);
    int n = 0;
    for (struct dirent *e; d && (e = readdir(d));)
        n += strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
    if (d)
        closedir(d);
    return n;
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (f) {
        fputs(text, f);
        fclose(f);
    }
}

/* A fresh empty directory under the test's temporary directory. */
static const char *fresh_dir(const char *name)
{
    const char *dir = tpk_temp_path(name);
    mkdir(dir, 0755);
    return dir;
}

TPK_TEST(check_refuses_with_the_argument_named)
{
    tpk_diag diag = {0};
    const char *dir = fresh_dir("check");
    char input[512], fifo[512], hard[512], missing[512];
    snprintf(input, sizeof input, "%s/in.vtk", dir);
    snprintf(fifo, sizeof fifo, "%s/fifo", dir);
    snprintf(hard, sizeof hard, "%s/hard.vtk", dir);
    snprintf(missing, sizeof missing, "%s/none/x.tpk", dir);
    write_text(input, "x");
    CHECK(mkfifo(fifo, 0644) == 0 && link(input, hard) == 0);
    tpk_output_input in = {.arg = "INPUT", .given = input};
    CHECK_EQ_INT(tpk_output_check("OUTPUT", "", &in, 1, &diag), -1);
    CHECK(strstr(diag.message, "OUTPUT is empty"));
    CHECK_EQ_INT(tpk_output_check("OUTPUT", dir, &in, 1, &diag), -1);
    CHECK(strstr(diag.message, "is a directory"));
    CHECK_EQ_INT(tpk_output_check("--vtu", fifo, &in, 1, &diag), -1);
    CHECK(strstr(diag.message, "--vtu '") && strstr(diag.message, "is a FIFO"));
    CHECK_EQ_INT(tpk_output_check("OUTPUT", hard, &in, 1, &diag), -1);
    CHECK(strstr(diag.message, "is the input file (same file as INPUT '"));
    CHECK_EQ_INT(tpk_output_check("OUTPUT", missing, &in, 1, &diag), -1);
    CHECK(strstr(diag.message, "does not exist"));
    char fine[512];
    snprintf(fine, sizeof fine, "%s/out.tpk", dir);
    CHECK_EQ_INT(tpk_output_check("OUTPUT", fine, &in, 1, &diag), 0);
}

typedef struct file_list {
    char names[8][512];
    int count;
} file_list;

static void collect(void *user, const char *file)
{
    file_list *list = user;
    if (list->count < 8)
        snprintf(list->names[list->count++], sizeof list->names[0], "%s", file);
}

TPK_TEST(input_files_name_siblings_and_pieces)
{
    file_list list = {0};
    tpk_import_input_files("d/mesh.ele", NULL, collect, &list);
    CHECK_EQ_INT(list.count, 3);
    CHECK(!strcmp(list.names[0], "d/mesh.ele") && !strcmp(list.names[1], "d/mesh.node") &&
          !strcmp(list.names[2], "d/mesh.ele"));
    memset(&list, 0, sizeof list);
    tpk_import_input_files("d/no_such_stem", NULL, collect, &list); /* a TetGen stem names no file itself */
    CHECK_EQ_INT(list.count, 3);
    CHECK(!strcmp(list.names[1], "d/no_such_stem.node"));
    memset(&list, 0, sizeof list);
    tpk_import_input_files("d/mesh.vtk", NULL, collect, &list);
    CHECK_EQ_INT(list.count, 1);
    const char *dir = fresh_dir("pvd");
    char pvd[512];
    snprintf(pvd, sizeof pvd, "%s/s.pvd", dir);
    write_text(pvd, "<VTKFile type=\"Collection\"><Collection><DataSet timestep=\"1\" file=\"b.vtu\"/>"
                    "<DataSet timestep=\"0\" file=\"/abs/a.vtu\"/></Collection></VTKFile>");
    memset(&list, 0, sizeof list);
    tpk_import_input_files(pvd, NULL, collect, &list);
    CHECK_EQ_INT(list.count, 3);
    char piece[600];
    snprintf(piece, sizeof piece, "%s/b.vtu", dir);
    CHECK(!strcmp(list.names[0], pvd) && !strcmp(list.names[1], piece) && !strcmp(list.names[2], "/abs/a.vtu"));
    memset(&list, 0, sizeof list);
    tpk_import_input_files(pvd, "vtu", collect, &list); /* forced: read as one file */
    CHECK_EQ_INT(list.count, 1);
}

/* Open, write "data", then commit or abort; `named` forces the fallback of filesystems without
 * O_TMPFILE. Checks what the directory shows along the way. */
static void round_trip(const char *dir, int named, int commit)
{
    char path[512];
    snprintf(path, sizeof path, "%s/out.bin", dir);
    setenv("TPK_TEST_OUTPUT_NAMED", named ? "1" : "0", 1);
    tpk_output out;
    tpk_diag diag = {0};
    int before = entry_count(dir);
    CHECK_MSG(tpk_output_open(&out, path, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(entry_count(dir), before + named); /* unnamed: nothing to leave behind */
    CHECK(!named == !out.temp);
    CHECK_EQ_INT(write(out.fd, "data", 4), 4);
    if (!commit) {
        tpk_output_abort(&out);
        CHECK_EQ_INT(entry_count(dir), before);
        return;
    }
    CHECK_MSG(tpk_output_commit(&out, &diag) == 0, "%s", diag.message);
    struct stat st;
    CHECK(stat(path, &st) == 0 && st.st_size == 4 && (st.st_mode & 0777) == 0644);
    CHECK_EQ_INT(entry_count(dir), 1); /* the file, no temporary name */
}

TPK_TEST(unnamed_and_named_outputs)
{
    for (int named = 0; named < 2; named++)
        for (int commit = 0; commit < 2; commit++) {
            char name[32];
            snprintf(name, sizeof name, "rt%d%d", named, commit);
            const char *dir = fresh_dir(name);
            round_trip(dir, named, commit);
            if (commit)
                round_trip(dir, named, commit); /* again, over the file now there */
        }
    unsetenv("TPK_TEST_OUTPUT_NAMED");
}

/* A FIFO that appears at the path while the output is written is not replaced at commit. */
TPK_TEST(commit_never_replaces_what_appeared)
{
    const char *dir = fresh_dir("appeared");
    char path[512];
    snprintf(path, sizeof path, "%s/out.bin", dir);
    tpk_output out;
    tpk_diag diag = {0};
    CHECK(tpk_output_open(&out, path, &diag) == 0);
    CHECK(mkfifo(path, 0644) == 0);
    CHECK_EQ_INT(tpk_output_commit(&out, &diag), -1);
    CHECK(strstr(diag.message, "is now a FIFO"));
    struct stat st;
    CHECK(lstat(path, &st) == 0 && S_ISFIFO(st.st_mode));
    CHECK_EQ_INT(entry_count(dir), 1);
}

/* The writer never closes the caller's fd: not on abort, not when finish refuses an invalid file. */
TPK_TEST(writer_leaves_the_callers_fd_open)
{
    int fd = open(tpk_temp_path("fd.tpk"), O_RDWR | O_CREAT | O_TRUNC, 0644);
    CHECK(fd >= 0);
    tpk_writer *w = NULL;
    char err[256] = "";
    CHECK_EQ_INT(tpk_writer_open_fd(&w, fd, "fd.tpk", NULL, err, sizeof err), TPK_OK);
    tpk_writer_abort(w);
    CHECK(fcntl(fd, F_GETFD) != -1);
    CHECK(ftruncate(fd, 0) == 0 && lseek(fd, 0, SEEK_SET) == 0);
    CHECK_EQ_INT(tpk_writer_open_fd(&w, fd, "fd.tpk", NULL, err, sizeof err), TPK_OK);
    tpk_header_fields h = {0};
    CHECK(tpk_writer_finish(w, &h) != TPK_OK); /* no chunks: refused by the layout rules */
    CHECK(fcntl(fd, F_GETFD) != -1);
    close(fd);
}

/* tpk_convert writes through an output file: the result opens, and nothing else is in the directory. */
TPK_TEST(convert_writes_through_an_output_file)
{
    const char *dir = fresh_dir("convert");
    char path[512];
    snprintf(path, sizeof path, "%s/c.tpk", dir);
    tpk_convert_options o = {.input = TPK_SOURCE_DIR "/samples/cylinder.vtk", .output = path, .threads = 1};
    tpk_convert_report report;
    tpk_diag diag = {0};
    CHECK_MSG(tpk_convert(&o, &report, NULL, NULL, &diag) == 0, "%s", diag.message);
    tpk_file *file = NULL;
    char err[256] = "";
    CHECK_MSG(tpk_open_path(&file, path, NULL, err, sizeof err) == TPK_OK, "%s", err);
    tpk_close(file);
    CHECK_EQ_INT(entry_count(dir), 1);
}
