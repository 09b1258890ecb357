/* The sample container shared by the sampling, graph and output stages. */
#include <stdlib.h>
#include <string.h>

#include "karst/graph.h"

static const char *const source_names[] = {
#define KARST_X_NAME(code, name) name,
    KARST_SAMPLE_SOURCE_LIST(KARST_X_NAME)
#undef KARST_X_NAME
};

/** Name of a sample source as written in samples.vtp ("horizon", ...); "unknown" if invalid. O(1).
 */
const char *karst_sample_source_name(karst_sample_source_t s) {
  if ((int)s < 0 || s >= KARST_SAMPLE_SOURCE_COUNT) return "unknown";
  return source_names[s];
}

/** Make @p s an empty sample set (no allocation). O(1). */
void karst_samples_init(karst_samples_t *s) {
  memset(s, 0, sizeof *s);
}

/** Release the storage of @p s and leave it empty. O(1). */
void karst_samples_destroy(karst_samples_t *s) {
  free(s->xyz);
  free(s->source);
  memset(s, 0, sizeof *s);
}

/**
 * Append the sample @p p with source @p src (amortised O(1): the capacity
 * doubles). On KARST_ENOMEM the set is unchanged.
 */
karst_error_t karst_samples_add(karst_samples_t *s, const double p[3], karst_sample_source_t src) {
  if (s->n == s->cap) {
    karst_int_t cap = s->cap ? 2 * s->cap : 1024;
    double *xyz = realloc(s->xyz, sizeof(double) * 3 * (size_t)cap);
    if (!xyz) return KARST_ENOMEM;
    s->xyz = xyz;
    unsigned char *so = realloc(s->source, (size_t)cap);
    if (!so) return KARST_ENOMEM;
    s->source = so;
    s->cap = cap;
  }
  memcpy(s->xyz + 3 * s->n, p, 3 * sizeof(double));
  s->source[s->n] = (unsigned char)src;
  s->n++;
  return KARST_SUCCESS;
}
