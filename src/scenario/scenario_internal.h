/* Helpers shared by the files of the scenario module (not part of the public API). */
#ifndef KARST_SCENARIO_INTERNAL_H
#define KARST_SCENARIO_INTERNAL_H

#include <stdio.h>

#include "karst/scenario.h"

/**
 * Read an ESRI ASCII grid from an open stream; @p name is the file name used
 * in messages ("NAME:LINE:COLUMN: ..."). On success @p t holds the grid (its
 * previous grid and path are released); on failure @p t is unchanged.
 */
karst_error_t karst_i_terrain_read_grid(karst_ctx_t *ctx, FILE *fp, const char *name,
                                        karst_terrain_t *t);

/**
 * Open @p path for reading only when it is a regular file of at most
 * @p max_bytes bytes. The type is checked with stat() before opening, so a
 * FIFO is refused without blocking and /dev/zero without reading forever.
 * @p what names the file in messages ("scenario", "heightfield").
 * @return KARST_SUCCESS with *fp open, KARST_EIO (missing, unreadable, not a
 *         regular file) or KARST_ERANGE (too large); ctx->errmsg starts with
 *         "PATH: ".
 */
karst_error_t karst_i_open_regular(karst_ctx_t *ctx, const char *path, const char *what,
                                   long long max_bytes, FILE **fp);

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

#endif
