/* Whole reads and writes on a file descriptor (pipes between tetpack and its child processes: the
 * TetGen child, mesher/tetgen_child.c, and isolated importers, import/isolate.c). */
#ifndef TPK_FD_IO_H
#define TPK_FD_IO_H

#include <stddef.h>

/* Write all `size` bytes, retrying after signals and short writes. 0, or -1 (the descriptor failed or
 * was closed). */
int tpk_fd_write_all(int fd, const void *data, size_t size);
/* Read exactly `size` bytes, retrying after signals and short reads. 0, or -1 (an error, or the end of
 * the stream before `size` bytes). */
int tpk_fd_read_all(int fd, void *data, size_t size);

#endif
