/* Whole reads and writes on a file descriptor (fd_io.h). */
#define _POSIX_C_SOURCE 200809L
#include "fd_io.h"

#include <errno.h>
#include <unistd.h>

int tpk_fd_write_all(int fd, const void *data, size_t size)
{
    const char *at = data;
    while (size > 0) {
        ssize_t n = write(fd, at, size);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return -1;
        at += n, size -= (size_t)n;
    }
    return 0;
}

int tpk_fd_read_all(int fd, void *data, size_t size)
{
    char *at = data;
    while (size > 0) {
        ssize_t n = read(fd, at, size);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return -1;
        at += n, size -= (size_t)n;
    }
    return 0;
}
