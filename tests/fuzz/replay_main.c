/* Replays a fuzz target over every file of a corpus directory (or over single files), so ctest runs the
 * crashers and seeds without libFuzzer. A crash or sanitizer report fails the test. */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
/* A target's custom mutator (fuzz_tpk_struct), when it has one: the replay runs it too. */
size_t LLVMFuzzerCustomMutator(uint8_t *data, size_t size, size_t max_size, unsigned int seed) __attribute__((weak));

/* libFuzzer's byte mutator, for a custom mutator that falls back on it: here one byte changes. */
size_t LLVMFuzzerMutate(uint8_t *data, size_t size, size_t max_size);
size_t LLVMFuzzerMutate(uint8_t *data, size_t size, size_t max_size)
{
    static unsigned calls;
    calls++;
    if (size > 0)
        data[calls * 2654435761u % size] ^= (uint8_t)(1u << calls % 8);
    else if (max_size > 0)
        data[size++] = (uint8_t)calls;
    return size;
}

/* The custom mutator on a copy of the input, a few seeds, each result replayed (exact size). */
static void replay_mutations(const uint8_t *data, size_t size)
{
    size_t max_size = size * 2 + 4096;
    for (unsigned seed = 1; seed <= 16; seed++) {
        uint8_t *copy = malloc(max_size);
        if (!copy)
            return;
        memcpy(copy, data, size);
        size_t mutated = LLVMFuzzerCustomMutator(copy, size, max_size, seed);
        uint8_t *exact = malloc(mutated ? mutated : 1);
        if (exact) {
            memcpy(exact, copy, mutated);
            LLVMFuzzerTestOneInput(exact, mutated);
        }
        free(exact);
        free(copy);
    }
}

static int replay_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        perror(path);
        return -1;
    }
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    /* Exact-size allocation so an overread hits the sanitizer's redzone. */
    uint8_t *data = malloc(size > 0 ? (size_t)size : 1);
    if (!data || fread(data, 1, (size_t)size, f) != (size_t)size) {
        fclose(f);
        free(data);
        fprintf(stderr, "%s: read failed\n", path);
        return -1;
    }
    fclose(f);
    LLVMFuzzerTestOneInput(data, (size_t)size);
    if (LLVMFuzzerCustomMutator)
        replay_mutations(data, (size_t)size);
    free(data);
    return 0;
}

int main(int argc, char **argv)
{
    int files = 0;
    for (int i = 1; i < argc; i++) {
        struct stat st;
        if (stat(argv[i], &st) != 0) {
            perror(argv[i]);
            return 1;
        }
        if (!S_ISDIR(st.st_mode)) {
            if (replay_file(argv[i]) != 0)
                return 1;
            files++;
            continue;
        }
        DIR *dir = opendir(argv[i]);
        struct dirent *e;
        while (dir && (e = readdir(dir)) != NULL) {
            if (e->d_name[0] == '.')
                continue;
            char path[4096];
            snprintf(path, sizeof path, "%s/%s", argv[i], e->d_name);
            if (replay_file(path) != 0)
                return 1;
            files++;
        }
        if (dir)
            closedir(dir);
    }
    if (files == 0) {
        fprintf(stderr, "no corpus files\n");
        return 1;
    }
    printf("%d passed, 0 failed\n", files);
    return 0;
}
