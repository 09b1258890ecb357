/* Private pieces shared by the files of src/metrics/ (and their tests and benchmark). */
#ifndef KARST_METRICS_INTERNAL_H
#define KARST_METRICS_INTERNAL_H

#include "karst/common.h"

/**
 * An undirected graph in compressed-sparse-row form: the neighbours of node v
 * are adj[off[v] .. off[v+1]-1]; each undirected edge u-v appears at u and at v.
 * Self-loops are not stored (they never lie on a shortest path).
 */
typedef struct karst_i_csr {
  karst_int_t n;
  karst_int_t *off; /* n + 1 */
  karst_int_t *adj; /* off[n] */
} karst_i_csr_t;

/**
 * Build a CSR graph of @p n nodes from @p m undirected edges (2*m node
 * indices, 0-based). Self-loops are dropped; repeated edges are kept (callers
 * pass simple graphs). The caller frees with karst_i_csr_destroy().
 */
karst_error_t karst_i_csr_build(karst_ctx_t *ctx, karst_int_t n, karst_int_t m,
                                const karst_int_t *edges, karst_i_csr_t *g);
void karst_i_csr_destroy(karst_i_csr_t *g);

/**
 * One breadth-first search from every node of @p g, in parallel, giving
 * both Brandes' betweenness and the hop-distance sums used by the average
 * shortest path length.
 *
 * @param betweenness n values: Brandes' accumulated dependencies with each
 *        unordered pair counted twice (once from each end), endpoints
 *        excluded; i.e. twice the usual pair-count betweenness. Dividing by
 *        (n-1)(n-2) gives networkx's normalised value.
 * @param dist_sum   n values (may be NULL): for source s, the sum of hop
 *        distances from s to every node it reaches.
 *
 * Sources are cut into blocks whose size depends only on n; the threads
 * (ctx->nthreads) claim blocks of a wave dynamically, and the block results are
 * added in block order, so the result is the same for every thread count.
 * Time O(n·(n+m)), memory O(nthreads·n).
 * Brandes U. (2001) A faster algorithm for betweenness centrality, J. Math.
 * Sociol. 25(2):163-177, Algorithm 1.
 */
karst_error_t karst_i_paths_all_sources(karst_ctx_t *ctx, const karst_i_csr_t *g,
                                        double *betweenness, karst_int_t *dist_sum);

#endif
