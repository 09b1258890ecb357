/* Shared by the files of the graph module: the exact k-nearest-neighbour
 * search on a uniform grid (knn.c) and the squared distance both it and the
 * symmetrisation in graph.c must compute identically. */
#ifndef KARST_GRAPH_INTERNAL_H
#define KARST_GRAPH_INTERNAL_H

#include <stdint.h>

#include "karst/common.h"
#include "karst/graph.h"

/**
 * Squared Euclidean distance |a − b|², always evaluated as ((dx² + dy²) + dz²) with
 * d = a − b. The neighbour search orders points by this exact double and the
 * symmetrisation decides "is u among v's neighbours" by comparing it with v's
 * k-th value, so both must use this one function (rounding is symmetric:
 * (a − b)² = (b − a)² exactly in IEEE arithmetic).
 */
static inline double karst_i_dist2_xyz(double ax, double ay, double az, const double *b) {
  double dx = ax - b[0], dy = ay - b[1], dz = az - b[2];
  return (dx * dx + dy * dy) + dz * dz;
}

/** karst_i_dist2_xyz with a's coordinates as an array. */
static inline double karst_i_dist2(const double *a, const double *b) {
  return karst_i_dist2_xyz(a[0], a[1], a[2], b);
}

/** Least arcs per batch in which karst_graph_build builds its rows 32-bit before coding them
 *  (4 Mi: smaller graphs take one batch); a test lowers it to build small graphs in batches. */
extern karst_int_t karst_i_graph_min_batch_arcs;

/**
 * Make @p g the graph with rows (offsets, adj, cost), as karst_graph_from_rows, coding the heads
 * @p adj (the caller keeps them) and taking @p offsets and @p cost (malloc'd, cost of offsets[n]
 * entries): they belong to @p g or are freed, on failure too. The rows are not checked. @p g is
 * unchanged on failure.
 * @return KARST_SUCCESS, KARST_ENOMEM.
 */
karst_error_t karst_i_graph_take_rows(karst_ctx_t *ctx, karst_graph_t *g, karst_int_t n,
                                      const double *xyz, karst_int_t *offsets, const int32_t *adj,
                                      karst_arc_cost_t *cost);

/* The arcs a of row v with their heads w, read run by run (karst_graph_t) in two nested loops
 * opened by KARST_I_ARCS_BEGIN and closed by KARST_I_ARCS_END: per arc one byte and two additions,
 * where karst_arc_next also tests for the run's end (the searches' relaxations wait on memory, and
 * the fewer instructions an arc takes, the more arcs the processor has in flight; measured in
 * docs/performance.md, "Memory at scale"). A run's first arc takes its count byte as its code
 * (head_ starts that much below the run's head), so every arc adds its byte plus one. The body
 * may `continue` to the next arc; it must not `break`. */
#define KARST_I_ARCS_BEGIN(g, v, a, w)                                                             \
  {                                                                                                \
    const unsigned char *q_ = (g)->code + (g)->code_off[v];                                        \
    for (karst_int_t a = (g)->offsets[v], end_ = (g)->offsets[(v) + 1]; a < end_;) {               \
      const int32_t first_ = karst_graph_run_head(q_);                                             \
      q_ += 4;                                                                                     \
      const karst_int_t run_end_ = a + 1 + *q_;                                                    \
      int64_t head_ = (int64_t)first_ - *q_ - 1;                                                   \
      for (; a < run_end_; a++) {                                                                  \
        head_ += *q_++ + 1;                                                                        \
        const karst_int_t w = (karst_int_t)head_;
#define KARST_I_ARCS_END                                                                           \
  }                                                                                                \
  }                                                                                                \
  }

/** (d, i) < (e, j) in the lexicographic order that breaks distance ties by index. */
static inline int karst_i_knn_less(double d, int32_t i, double e, int32_t j) {
  return d < e || (d == e && i < j);
}

/**
 * The k nearest other points of every point, ties broken by the smaller
 * index, so that the result is one well-defined set (no "up to ties").
 * @param ctx context (errors, interrupt, progress "neighbours").
 * @param xyz 3 n coordinates, all finite; @param n points, 2 <= n < INT32_MAX.
 * @param k neighbours per point, 1 <= k <= n − 1.
 * @param nthreads worker threads (the result does not depend on them).
 * @param nbr out, n k indices: the neighbours of v are nbr[v k .. v k + k − 1], in
 *        an unspecified (but deterministic) order.
 * @param kd2 out, n: the k-th smallest squared distance (karst_i_dist2) of v.
 * @param kidx out, n: the index of that k-th neighbour.
 * @return KARST_SUCCESS, KARST_ENOMEM, KARST_EINTERRUPTED.
 */
karst_error_t karst_i_knn(karst_ctx_t *ctx, const double *xyz, karst_int_t n, int k, int nthreads,
                          int32_t *nbr, double *kd2, int32_t *kidx);

/** The same through FLANN's exact single k-d tree (knn_flann.c, sampling.knn = flann). */
karst_error_t karst_i_knn_flann(karst_ctx_t *ctx, const double *xyz, karst_int_t n, int k,
                                int nthreads, int32_t *nbr, double *kd2, int32_t *kidx);

#endif
