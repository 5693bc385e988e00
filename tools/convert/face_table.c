/* Faces by sorted point ids in an open-addressing hash table (tools/convert/face_table.h). */
#include "face_table.h"

#include <stdlib.h>
#include <string.h>

uint64_t tpk_face_hash(const int32_t *sorted, int32_t size)
{
    uint64_t h = 0x9e3779b97f4a7c15ull ^ (uint64_t)size;
    for (int32_t i = 0; i < size; i++) {
        h ^= (uint32_t)sorted[i];
        h *= 0xff51afd7ed558ccdull;
        h ^= h >> 32;
    }
    return h;
}

int64_t tpk_face_table_find(const tpk_face_table *table, const int32_t *sorted, int32_t size, uint64_t hash)
{
    if (!table->slot_count)
        return -1;
    uint64_t mask = (uint64_t)table->slot_count - 1;
    for (uint64_t s = hash & mask;; s = (s + 1) & mask) {
        int64_t at = table->slots[s] - 1;
        if (at < 0)
            return -1;
        const tpk_face_entry *e = &table->entries[at];
        if (e->hash == hash && e->size == size &&
            !memcmp(table->keys + e->key_at, sorted, sizeof *sorted * (size_t)size))
            return at;
    }
}

static void place(tpk_face_table *table, int64_t index)
{
    uint64_t mask = (uint64_t)table->slot_count - 1;
    uint64_t s = table->entries[index].hash & mask;
    while (table->slots[s])
        s = (s + 1) & mask;
    table->slots[s] = index + 1;
}

/* Keep the load at most one half. */
static int grow_slots(tpk_face_table *table)
{
    if (2 * (table->count + 1) <= table->slot_count)
        return 0;
    int64_t slots = table->slot_count ? 2 * table->slot_count : 64;
    int64_t *grown = calloc((size_t)slots, sizeof *grown);
    if (!grown)
        return -1;
    free(table->slots);
    table->slots = grown;
    table->slot_count = slots;
    for (int64_t i = 0; i < table->count; i++)
        place(table, i);
    return 0;
}

int64_t tpk_face_table_add(tpk_face_table *table, const int32_t *sorted, int32_t size, uint64_t hash, int32_t round)
{
    if (grow_slots(table))
        return -1;
    if (table->count == table->cap) {
        int64_t cap = table->cap ? 2 * table->cap : 32;
        tpk_face_entry *grown = realloc(table->entries, sizeof *grown * (size_t)cap);
        if (!grown)
            return -1;
        table->entries = grown;
        table->cap = cap;
    }
    if (table->key_count + size > table->key_cap) {
        int64_t cap = 2 * (table->key_count + size);
        int32_t *grown = realloc(table->keys, sizeof *grown * (size_t)cap);
        if (!grown)
            return -1;
        table->keys = grown;
        table->key_cap = cap;
    }
    memcpy(table->keys + table->key_count, sorted, sizeof *sorted * (size_t)size);
    tpk_face_entry *e = &table->entries[table->count];
    *e = (tpk_face_entry){hash, table->key_count, size, round, -1, {-1, -1}, {0, 0, 0}, {-1, -1}, 0, 0};
    table->key_count += size;
    place(table, table->count);
    return table->count++;
}

void tpk_face_table_free(tpk_face_table *table)
{
    free(table->entries);
    free(table->slots);
    free(table->keys);
    memset(table, 0, sizeof *table);
}
