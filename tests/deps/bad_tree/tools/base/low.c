/* Breaks the folder order twice: base/ includes a header of mesh/ and calls a function of mesh/. */
#include "mesh/high.h"

int tpk_fake_low(void)
{
    return tpk_fake_high() + 1;
}
