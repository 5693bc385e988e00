/* Private to tools/scene/. Owners: scene_locate.c (positions of keys in the scene text: cJSON keeps
 * none, so messages find them here), scene_parse.c (tpk_scene_load, tpk_scene_parse), scene_write.c
 * (tpk_scene_to_json, tpk_scene_write), scene_options.c (tpk_scene_apply, tpk_scene_from_options). */
#ifndef TPK_SCENE_INTERNAL_H
#define TPK_SCENE_INTERNAL_H

#include <stddef.h>

/* 1-based line and column of byte `offset` of `text` (a tab counts as one column). */
void tpk_scene_line_col(const char *text, size_t offset, int *line, int *col);

/* Byte offset of the key `path` ("effects.ao_rays": a key of an object nested in key "effects") in
 * the JSON `text`, at its opening quote; `nth` 0 for its first occurrence, 1 for a repeat. -1 when
 * absent. */
long tpk_scene_key_offset(const char *text, const char *path, int nth);

/* The path of keys ("camera.eye") whose value encloses byte `offset` of `text`, as far as the text up
 * to there shows (for a syntax error: the key being read when the text went wrong); "" at the top. */
void tpk_scene_key_at(const char *text, size_t offset, char *path, size_t cap);

#endif
