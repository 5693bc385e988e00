/* Output paths of the subcommands, checked before any work is done (base/output_file.h): an output
 * that is an input, a directory or a device is refused up front, naming the argument. */
#include <stdlib.h>
#include <string.h>

#include "base/output_file.h"
#include "cli.h"
#include "import/importers.h"

int tpk_cli_check_output(const char *cmd, const char *arg, const char *path, const tpk_output_input *inputs,
                         size_t count)
{
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_output_check(arg, path, inputs, count, &diag) != 0)
        return tpk_cli_fail(cmd, "%s", diag.message);
    return 0;
}

typedef struct input_files {
    tpk_output_input *items;
    size_t count, capacity;
    const char *given;
    int failed;
} input_files;

static void add_input_file(void *user, const char *file)
{
    input_files *list = user;
    if (list->failed)
        return;
    if (list->count == list->capacity) {
        size_t capacity = list->capacity ? 2 * list->capacity : 8;
        tpk_output_input *grown = realloc(list->items, capacity * sizeof *grown);
        if (!grown) {
            list->failed = 1;
            return;
        }
        list->items = grown;
        list->capacity = capacity;
    }
    char *copy = strdup(file);
    if (!copy) {
        list->failed = 1;
        return;
    }
    list->items[list->count++] = (tpk_output_input){.arg = "INPUT", .given = list->given, .file = copy};
}

int tpk_cli_check_convert_output(const char *cmd, const char *arg, const char *input, const char *format,
                                 const char *output)
{
    input_files list = {.given = input};
    tpk_import_input_files(input, format, add_input_file, &list);
    int rc = list.failed ? tpk_cli_fail(cmd, "out of memory listing the files of INPUT '%s'", input)
                         : tpk_cli_check_output(cmd, arg, output, list.items, list.count);
    for (size_t i = 0; i < list.count; i++)
        free((char *)list.items[i].file);
    free(list.items);
    return rc;
}
