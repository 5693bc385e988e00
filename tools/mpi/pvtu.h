/* The piece list of a parallel VTU file (.pvtu: a PUnstructuredGrid whose <Piece Source="..."/> name the
 * .vtu files, relative to the .pvtu's folder), for tetpack-mpi. */
#ifndef TPK_PVTU_H
#define TPK_PVTU_H

#include "base/diag.h"

typedef struct tpk_piece_list {
    int count;
    char **paths; /* each resolved against the .pvtu's folder (or the case's processor<k> folders) */
    int openfoam; /* the pieces are OpenFOAM processor folders (decomposePar) */
    const char *format; /* "pvtu", "openfoam" or "exodus" (static), for the manifest and the parts */
} tpk_piece_list;

/* The pieces of INPUT: a .pvtu's; an OpenFOAM case folder's processor0, processor1, ... (as many as
 * exist in a row, at least one); or, for any other name, Exodus files per processor (exodus_pieces.c).
 * Returns 0, or -1 with a message. */
int tpk_input_pieces(const char *path, tpk_piece_list *out, tpk_diag *diag);

/* Exodus files per processor as SEACAS's decomposers write them: `path` is one of them, BASE.N.K, or
 * BASE with BASE.N.K beside it (one N). Lists BASE.N.0 .. BASE.N.(N-1); every one must exist. Returns 0,
 * or -1 with a message naming the missing piece (or saying none were found). */
int tpk_exodus_pieces(const char *path, tpk_piece_list *out, tpk_diag *diag);

/* Read `path`'s piece list. A Source with a '/' at its start or a ".." component is refused (pieces live
 * beside or below the .pvtu). Returns 0, or -1 with a message naming the file and the place. */
int tpk_pvtu_pieces(const char *path, tpk_piece_list *out, tpk_diag *diag);
void tpk_piece_list_free(tpk_piece_list *list);

#endif
