/* tetpack: git-style command line (convert, info, render, export). */
#include <stdio.h>
#include <string.h>

int main(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    fprintf(stderr, "tetpack: under construction\n");
    return 2;
}
