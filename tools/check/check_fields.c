/* Field checks (5xx): NaN/Inf values, lengths that do not match the mesh (recorded by importers read
 * leniently, see tpk_diag_field_problem), and the range of every field and step. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "tetpack.h"

static void report_problems(const tpk_check_input *in, tpk_check_report *report)
{
    if (!in->import_diag)
        return;
    const tpk_diag *d = in->import_diag;
    for (long long k = 0; k < d->field_problem_count; k++) {
        if (k >= TPK_DIAG_MAX_FIELD_PROBLEMS) {
            tpk_check_count(report, 502, d->field_problem_count - k);
            break;
        }
        const tpk_field_problem *p = &d->field_problems[k];
        tpk_example *ex = tpk_check_hit(report, 502, "field");
        tpk_example_note(ex, "'%s' at %s: %lld values, expected %lld", p->name, p->place, p->found, p->expected);
    }
}

static void check_field(const tpk_mesh *m, int index, const tpk_src_field *f, tpk_check_report *report)
{
    int64_t items = f->association == TPK_ASSOC_POINT ? m->point_count : m->cell_count;
    int64_t per_step = items * f->components;
    for (int s = 0; s < f->step_count; s++) {
        /* no points or cells: no values (values may be NULL, and NULL + 0 is undefined) */
        const float *v = per_step > 0 ? f->values + (int64_t)s * per_step : NULL;
        double lo = INFINITY, hi = -INFINITY;
        int64_t bad = 0, first_bad = -1;
        for (int64_t i = 0; i < per_step; i++) {
            if (!isfinite(v[i])) {
                if (first_bad < 0)
                    first_bad = i;
                bad++;
                continue;
            }
            lo = fmin(lo, v[i]);
            hi = fmax(hi, v[i]);
        }
        if (bad) {
            tpk_example *ex = tpk_check_hit(report, 501, "field");
            if (bad > 1)
                tpk_check_count(report, 501, bad - 1);
            int64_t ids[3] = {index, s, first_bad / f->components};
            tpk_example_ids(ex, 3, ids);
            tpk_example_note(ex, "'%s' step %d: %lld non-finite values, the first at %s %lld", f->name, s,
                             (long long)bad, f->association == TPK_ASSOC_POINT ? "vertex" : "cell",
                             (long long)(first_bad / f->components));
        }
        if (report->field_stat_count < TPK_CHECK_MAX_FIELD_STATS) {
            tpk_field_stat *st = &report->field_stats[report->field_stat_count++];
            snprintf(st->name, sizeof st->name, "%s", f->name);
            st->association = f->association;
            st->components = f->components;
            st->step = s;
            st->min = bad == per_step ? NAN : lo;
            st->max = bad == per_step ? NAN : hi;
            st->nonfinite = bad;
        }
    }
}

int tpk_check_fields(const tpk_check_input *in, tpk_check_report *report, tpk_diag *diag)
{
    (void)diag;
    report_problems(in, report);
    for (int i = 0; i < in->mesh->field_count; i++)
        check_field(in->mesh, i, &in->mesh->fields[i], report);
    return 0;
}
