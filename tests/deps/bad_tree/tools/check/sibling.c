/* Breaks the folder order: check/ and export/ are siblings (one level), so neither includes the other. */
#include "export/exporter.h"

int tpk_fake_check(void)
{
    return TPK_FAKE_EXPORT;
}
