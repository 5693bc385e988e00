/* A function of mesh/, which base/low.c may not use. */
int tpk_fake_high(void);
