/**
 * @file survey_internal.h
 * @brief Shared by the survey readers (Survex .3d, Therion SQL): whole-file
 *        loading, and a builder that keys stations by their integer
 *        centimetre coordinates, collects legs, and turns the result into a
 *        karst_network_t.
 *
 * Keying by centimetres is what Survex itself does in a .3d file (every
 * coordinate is stored as a whole number of centimetres), so two stations
 * equated in the survey, which cavern places at one point, become one node.
 */
#ifndef KARST_IO_SURVEY_INTERNAL_H
#define KARST_IO_SURVEY_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "karst/common.h"
#include "karst/network.h"

/** Centimetres per metre: survey coordinates are keyed by whole centimetres. */
#define KARST_I_SURVEY_CM_PER_M 100.0

/** A station position: integer centimetres (x east, y north, z up). */
typedef struct karst_i_cmkey {
  int64_t x, y, z;
} karst_i_cmkey_t;

typedef struct karst_i_survey_point {
  karst_i_cmkey_t key;
  const char *label; /**< first name seen at this point (owned by the label table) or NULL */
  double lrud[4];    /**< left, right, up, down in metres; NAN when absent */
  unsigned char entrance; /**< 1 when a station at this point is flagged an entrance */
} karst_i_survey_point_t;

typedef struct karst_i_survey {
  karst_i_survey_point_t *points;
  karst_int_t n_points, cap_points;
  karst_int_t *slots; /**< open-addressing table of point index + 1 (0 = empty) */
  karst_int_t n_slots;
  karst_int_t *legs; /**< 2 * n_legs point indices */
  karst_int_t n_legs, cap_legs;
  char **lab_names;       /**< open-addressing label table: name (owned) ... */
  karst_int_t *lab_point; /**< ... and the point it names */
  karst_int_t n_lab_slots, n_labels;
} karst_i_survey_t;

void karst_i_survey_init(karst_i_survey_t *s);
void karst_i_survey_destroy(karst_i_survey_t *s);

/** The point at @p key, created (with no label and no LRUD) when new. Amortised O(1). */
karst_error_t karst_i_survey_point(karst_i_survey_t *s, karst_i_cmkey_t key, karst_int_t *index);
/** Name point @p p @p label (the first name of a point is the one kept as its label). O(|label|).
 */
karst_error_t karst_i_survey_name(karst_i_survey_t *s, karst_int_t p, const char *label);
/** The point named @p label, or -1. O(|label|) expected. */
karst_int_t karst_i_survey_lookup(const karst_i_survey_t *s, const char *label);
/** Record a kept leg between points @p a and @p b. Amortised O(1). */
karst_error_t karst_i_survey_leg(karst_i_survey_t *s, karst_int_t a, karst_int_t b);

/**
 * Build @p net (initialised and empty) from the kept legs: one node per
 * point used by a leg, in order of first appearance; one edge per leg. A leg
 * whose two ends are the same point (zero length after keying, e.g. a leg
 * between two stations Survex equated) carries no passage and is dropped;
 * their number goes to @p n_zero (may be NULL). Labels become
 * net->node_labels; with @p with_lrud the node attribute "lrud" (4
 * components) is added; when a point is flagged an entrance, the integer node attribute
 * "entrance" (1 at entrances, 0 elsewhere). On failure @p net is left empty.
 * Time complexity: O(points + legs).
 */
karst_error_t karst_i_survey_build(karst_ctx_t *ctx, const karst_i_survey_t *s, int with_lrud,
                                   karst_network_t *net, karst_int_t *n_zero);

/** Whole-file read into a malloc'd buffer (NUL-terminated for text parsers), through
 * karst_i_read_regular (regular file of at most KARST_SURVEY_MAX_BYTES). */
karst_error_t karst_i_read_file(karst_ctx_t *ctx, const char *path, unsigned char **data,
                                size_t *len);

#endif
