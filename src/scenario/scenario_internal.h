/* Helpers shared by the files of the scenario module (not part of the public API). */
#ifndef KARST_SCENARIO_INTERNAL_H
#define KARST_SCENARIO_INTERNAL_H

#include <stdio.h>

#include "io/input_internal.h"
#include "karst/scenario.h"

/**
 * Read an ESRI ASCII grid from an open stream; @p name is the file name used
 * in messages ("NAME:LINE:COLUMN: ..."). On success @p t holds the grid (its
 * previous grid and path are released); on failure @p t is unchanged.
 */
karst_error_t karst_i_terrain_read_grid(karst_ctx_t *ctx, FILE *fp, const char *name,
                                        karst_terrain_t *t);

/* karst_i_open_regular(), the guarded opening of every input file, is in
 * io/input_internal.h (shared by all readers of the library). */

/**
 * Levenshtein distance between @p a and @p b, stopping early at @p cap + 1
 * (enough to decide whether a suggestion is close). O(|a| |b|).
 */
int karst_i_edit_distance(const char *a, const char *b, int cap);

/**
 * The candidate closest to @p word for a "did you mean" hint, or NULL when
 * none is close enough (see KARST_I_SUGGEST_MAX_EDITS).
 */
const char *karst_i_suggest(const char *word, const char *const *candidates, int n);

/** A suggestion is offered when at most this many edits away (and at most half the word). */
#define KARST_I_SUGGEST_MAX_EDITS 3

/* ------------------------------------------------------------------------ */
/* Overrides (src/scenario/overrides.c): values put into the YAML document   */
/* before the schema walk of scenario.c.                                     */
/* ------------------------------------------------------------------------ */
#include <yaml.h>

/** What the document holds where an override was put. */
typedef struct karst_i_override_target {
  int replaced;      /**< 1: a scalar of the file was replaced; 0: the key was added */
  size_t start, end; /**< replaced: byte range of the file's scalar */
  int shared;        /**< replaced: the file's scalar is also reached through an alias */
} karst_i_override_target_t;

/** The overrides of one load and the document nodes they added. */
typedef struct karst_i_override_set {
  int n;
  const karst_scenario_override_t *ov;
  karst_override_type_t *types;       /**< n entries: what the walk read each value as */
  karst_i_override_target_t *targets; /**< n entries */
  int first_node;                     /**< document nodes with this id or above were added */
  int n_added, cap_added;
  int *owner;             /**< owner[id - first_node]: the override of an added node */
  int n_files, cap_files; /**< file paths the walk resolved (heightfield, surfaces) */
  char **file_keys;       /**< their key paths, e.g. "terrain.heightfield" */
  char **file_values;     /**< the text the scenario gives (relative to the file) */
} karst_i_override_set_t;

/** An empty set for @p n overrides (caller frees with karst_i_overrides_destroy). */
karst_error_t karst_i_overrides_init(karst_ctx_t *ctx, karst_i_override_set_t *set,
                                     const karst_scenario_override_t *ov, int n);
void karst_i_overrides_destroy(karst_i_override_set_t *set);

/**
 * Put every override of @p set into @p doc (whose root is a map): a value the file gives is
 * replaced by a new plain scalar, a missing key is added (with the maps leading to it).
 * Errors ("FILE: ORIGIN: ...") name a malformed path, a key that leads through a value
 * that is not a map, or a list index beyond the list. O(document size) per override.
 */
karst_error_t karst_i_overrides_apply(karst_ctx_t *ctx, const char *file, yaml_document_t *doc,
                                      karst_i_override_set_t *set);

/** Note that the walk read the file @p value at key path @p key (copies both); 0, or -1 when out
 *  of memory. O(1) amortised. */
int karst_i_overrides_note_file(karst_i_override_set_t *set, const char *key, const char *value);

/** The override that added node @p n of @p doc, or -1 for a node of the file. O(1). */
int karst_i_override_of(const karst_i_override_set_t *set, const yaml_document_t *doc,
                        const yaml_node_t *n);

/** "ORIGIN" of override @p k: its origin, or "override KEY=VALUE" written into @p buf. */
const char *karst_i_override_label(const karst_i_override_set_t *set, int k, char *buf,
                                   size_t size);

/**
 * karst_scenario_load with the overrides of @p set (NULL: none) applied to the document
 * before the walk; when @p keep_doc is not NULL the document (with the overrides in it) and
 * the file's bytes are handed to the caller instead of being freed (*keep_doc loaded, *text
 * and *text_len the bytes; free with yaml_document_delete and free).
 */
karst_error_t karst_i_scenario_load(karst_ctx_t *ctx, const char *path, karst_i_override_set_t *set,
                                    karst_scenario_t *sc, yaml_document_t *keep_doc,
                                    unsigned char **text, size_t *text_len);

#endif
