/* consumer: opens a .tpk through the installed libtetpack (tetpack.h only) and prints its counts.
 * The example for "use libtetpack from your project" (README); ctest builds it against an installed
 * prefix with CMake and with pkg-config (tests/install/install.sh). Exit 0, or 2 with the reason. */
#include <stdio.h>

#include <tetpack.h>

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: consumer FILE.tpk\n");
        return 2;
    }
    char err[256] = "";
    tpk_file *file = NULL;
    tpk_result rc = tpk_open_path(&file, argv[1], NULL, err, sizeof err);
    if (rc != TPK_OK) {
        fprintf(stderr, "consumer: %s: %s (%s)\n", argv[1], tpk_result_string(rc), err);
        return 2;
    }
    tpk_file_info info;
    rc = tpk_get_info(file, &info);
    if (rc == TPK_OK)
        rc = tpk_verify(file);
    if (rc != TPK_OK) {
        fprintf(stderr, "consumer: %s: %s (%s)\n", argv[1], tpk_result_string(rc), tpk_error_text(file));
        tpk_close(file);
        return 2;
    }
    printf("library %s, format %u.%u\n", TPK_LIBRARY_VERSION, info.version_major, info.version_minor);
    printf("vertices %llu\n", (unsigned long long)info.vertex_count);
    printf("tets %llu\n", (unsigned long long)info.tet_count);
    printf("shell_faces %llu\n", (unsigned long long)info.shell_face_count);
    printf("chunks %llu\n", (unsigned long long)info.chunk_count);
    uint32_t fields = tpk_field_count(file);
    printf("fields %u\n", fields);
    for (uint32_t i = 0; i < fields; i++) {
        tpk_field_desc field;
        if (tpk_get_field(file, i, &field) == TPK_OK)
            printf("field %s steps %u range %g %g\n", field.name, field.step_count, field.min_value,
                   field.max_value);
    }
    tpk_close(file);
    return 0;
}
