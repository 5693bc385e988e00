/* SHEL records (spec §6.6): each is a boundary face of its tet, listed once (TPK-M09, 609), and faces
 * outward (TPK-M10, 610, exact). Marks the faces it covers so the tet pass can report boundary faces
 * missing from SHEL. Serial: records may name the same tet, and S is small next to T. */
#include <inttypes.h>

#include "check_tpk_internal.h"

/* Position in q of the vertex not in face f, or -1 when f is not three distinct ids of q. */
static int face_position(const int32_t q[4], const int32_t f[3])
{
    if (f[0] == f[1] || f[0] == f[2] || f[1] == f[2])
        return -1;
    int missing = -1, found = 0;
    for (int k = 0; k < 4; k++) {
        if (q[k] == f[0] || q[k] == f[1] || q[k] == f[2])
            found++;
        else
            missing = k;
    }
    return found == 3 ? missing : -1;
}

static void check_record(tpkc *c, tpkc_sink *sink, int64_t s)
{
    const tpk_shell_face *sf = &c->shell[s];
    int32_t q[4], n[4], f[3] = {sf->a, sf->b, sf->c};
    const int32_t ids[5] = {(int32_t)s, sf->t, sf->a, sf->b, sf->c};
    if (!tpkc_usable(c, sf->t, q))
        return; /* 601 or the walk reported the tet */
    int j = face_position(q, f);
    if (j < 0) {
        tpk_example *ex = tpkc_hit(sink, 609, "shell_face");
        tpkc_example_ids32(ex, 5, ids);
        tpk_example_note(ex, "not a face of tet %d (%d %d %d %d)", sf->t, q[0], q[1], q[2], q[3]);
        return;
    }
    tpkc_neighbors(c, sf->t, q, n);
    if (n[j] != -1) {
        tpk_example *ex = tpkc_hit(sink, 609, "shell_face");
        tpkc_example_ids32(ex, 5, ids);
        tpk_example_note(ex, "tet %d has neighbor %d across this face, so it is not a boundary face", sf->t, n[j]);
    } else if (c->covered[sf->t] & (1u << j)) {
        tpk_example *ex = tpkc_hit(sink, 609, "shell_face");
        tpkc_example_ids32(ex, 5, ids);
        tpk_example_note(ex, "face listed twice in SHEL (this is a later record)");
    } else {
        c->covered[sf->t] |= (uint8_t)(1u << j);
    }
    /* Outward: the fourth vertex q[j] lies on the positive side of (a, c, b). */
    int sign = tpkc_orient(c, sf->a, sf->c, sf->b, q[j]);
    if (sign <= 0) {
        tpk_example *ex = tpkc_hit(sink, 610, "shell_face");
        tpkc_example_ids32(ex, 5, ids);
        tpk_example_note(ex, "%s: its fourth vertex %d is %s the plane of (a, b, c) (exact)",
                         sign < 0 ? "faces inward" : "flat", q[j], sign < 0 ? "in front of" : "on");
    }
}

int tpkc_check_shell(tpkc *c, tpk_diag *diag)
{
    (void)diag;
    tpkc_sink sink = {.max_examples = c->report->options.max_examples};
    for (int64_t s = 0; s < c->S; s++)
        check_record(c, &sink, s);
    tpkc_merge(c->report, &sink, 1);
    return 0;
}
