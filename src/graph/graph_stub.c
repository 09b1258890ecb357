/* Placeholder until the sampling and graph stages exist. */
#include "karst/graph.h"
#include <string.h>

karst_error_t karst_graph_from_edges(karst_ctx_t *ctx, karst_graph_t *g, karst_int_t n,
                                     const double *xyz, karst_int_t m, const karst_int_t *u,
                                     const karst_int_t *v, const double *cost) {
  (void)g, (void)n, (void)xyz, (void)m, (void)u, (void)v, (void)cost;
  return karst_set_error(ctx, KARST_ENOTIMPL, "graphs are not available yet");
}
void karst_graph_init(karst_graph_t *g) { memset(g, 0, sizeof *g); }
void karst_graph_destroy(karst_graph_t *g) { memset(g, 0, sizeof *g); }
void karst_samples_init(karst_samples_t *s) { memset(s, 0, sizeof *s); }
void karst_samples_destroy(karst_samples_t *s) { memset(s, 0, sizeof *s); }
