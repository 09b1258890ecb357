/*
 * TEMPORARY weak stand-ins for functions declared in metrics.h and scenario.h
 * whose definitions land with the metrics and scenario branches. A weak symbol
 * is replaced by the real (strong) definition as soon as that exists, so this
 * file changes nothing once they are merged; delete it then.
 */
#include <math.h>
#include <stddef.h>

#include "karst/metrics.h"
#include "karst/scenario.h"

#define FIELD(name, is_int)                                                                        \
  { #name, offsetof(karst_metrics_t, name), is_int }
static const karst_metric_field_t placeholder_fields[] = {FIELD(nodes, 1),
                                                          FIELD(edges, 1),
                                                          FIELD(total_length, 0),
                                                          FIELD(vertical_extent, 0),
                                                          FIELD(mean_length, 0),
                                                          FIELD(cv_length, 0),
                                                          FIELD(length_entropy, 0),
                                                          FIELD(tortuosity, 0),
                                                          FIELD(orientation_entropy, 0),
                                                          FIELD(aspl, 0),
                                                          FIELD(cpd, 0),
                                                          FIELD(mean_degree, 0),
                                                          FIELD(cv_degree, 0),
                                                          FIELD(correlation_vertex_degree, 0),
                                                          FIELD(reduced_nodes, 1),
                                                          FIELD(reduced_edges, 1),
                                                          FIELD(components, 1),
                                                          FIELD(cycles, 1),
                                                          FIELD(howard_alpha, 0),
                                                          FIELD(howard_beta, 0),
                                                          FIELD(howard_gamma, 0)};
#undef FIELD

__attribute__((weak)) const karst_metric_field_t *karst_metric_fields(int *n) {
  *n = (int)(sizeof placeholder_fields / sizeof placeholder_fields[0]);
  return placeholder_fields;
}

__attribute__((weak)) double karst_metric_value(const karst_metrics_t *m,
                                                const karst_metric_field_t *f) {
  const char *p = (const char *)m + f->offset;
  return f->is_int ? (double)*(const karst_int_t *)p : *(const double *)p;
}

__attribute__((weak)) void karst_metrics_options_init(karst_metrics_options_t *opt) {
  opt->azimuth_rotation = 0.0;
}

__attribute__((weak)) karst_error_t karst_file_hash(karst_ctx_t *ctx, const char *path,
                                                    char out[17]) {
  (void)out;
  return karst_set_error(ctx, KARST_ENOTIMPL, "%s: file hashing is not available yet", path);
}
