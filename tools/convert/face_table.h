/* A set of faces named by their sorted point ids: the faces that carry a point added at their centre,
 * so that the cells on both sides of a face find and share the same point. */
#ifndef TPK_FACE_TABLE_H
#define TPK_FACE_TABLE_H

#include <stdint.h>

typedef struct tpk_face_entry {
    uint64_t hash;
    int64_t key_at;   /* the face's point ids, ascending, at keys[key_at .. key_at + size) */
    int32_t size;
    int32_t round;    /* when it was added (tpk_steiner_stage's rounds) */
    int32_t point;    /* its vertex id once numbered, else -1 */
    int32_t cells[2]; /* the cells that used the point, -1 for none yet */
    double at[3];     /* where the point goes, and */
    int32_t pair[2];  /* the two corners it is the midpoint of, or -1: the mean of all (set by the caller) */
    int32_t diagonal; /* 1: no point; the quad is cut along pair instead (set by the caller) */
    int32_t changed;  /* the caller changed how it is cut once (it may not again) */
} tpk_face_entry;

/* Zero-initialise; free with tpk_face_table_free. */
typedef struct tpk_face_table {
    tpk_face_entry *entries;
    int64_t count, cap;
    int64_t *slots;       /* open addressing, slot_count a power of two: entry index + 1, 0 when empty */
    int64_t slot_count;
    int32_t *keys;
    int64_t key_count, key_cap;
} tpk_face_table;

uint64_t tpk_face_hash(const int32_t *sorted, int32_t size);
/* Index of the entry with these sorted ids, or -1. */
int64_t tpk_face_table_find(const tpk_face_table *table, const int32_t *sorted, int32_t size, uint64_t hash);
/* Add a face not yet in the table; returns its index, or -1 when out of memory. */
int64_t tpk_face_table_add(tpk_face_table *table, const int32_t *sorted, int32_t size, uint64_t hash,
                           int32_t round);
void tpk_face_table_free(tpk_face_table *table);

#endif
