/* The all-sources quantities of src/metrics/paths.c computed with igraph 0.10, as an independent
 * check (tests/unit/test_metrics.c) and a speed comparison (bench/bench_metrics.c). Not part of
 * libkarst: linked into those two programs only, so that no karst process loads igraph and the
 * dozen libraries it brings (BLAS, LAPACK, ARPACK, GLPK, libxml2 and ICU, libgfortran...), about
 * 10 ms at every start on the 2-core project machine. */
#ifndef KARST_TESTS_PATHS_IGRAPH_H
#define KARST_TESTS_PATHS_IGRAPH_H

#include "metrics/metrics_internal.h"

/**
 * Betweenness (counted from both ends of each pair, as paths.c and networkx do) with
 * igraph_betweenness, and, when @p dist_sum is not NULL, each node's sum of hop distances with
 * igraph_distances per source.
 * @return KARST_SUCCESS, or KARST_EEXTERNAL when igraph fails.
 */
karst_error_t karst_i_paths_igraph(karst_ctx_t *ctx, const karst_i_csr_t *g, double *betweenness,
                                   karst_int_t *dist_sum);

#endif
