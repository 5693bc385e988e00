/* A header of export/, which check/sibling.c may not include. */
#define TPK_FAKE_EXPORT 2
