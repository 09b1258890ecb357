/**
 * @file graph.h
 * @brief Sampling of the bedrock and the geometric graph on the samples
 *        (Paris et al. 2021, §4.1–4.2): the structures passed between the
 *        sampling, graph, cost and paths stages.
 */
#ifndef KARST_GRAPH_H
#define KARST_GRAPH_H

#include <float.h>
#include <math.h>

#include "karst/common.h"
#include "karst/geology.h"
#include "karst/scenario.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Which feature produced a sample (written as point data in samples.vtp). */
#define KARST_SAMPLE_SOURCE_LIST(X)                                                                \
  X(KARST_SAMPLE_KEYPOINT, "key_point")                                                            \
  X(KARST_SAMPLE_HORIZON, "horizon")                                                               \
  X(KARST_SAMPLE_WATER_TABLE, "water_table")                                                       \
  X(KARST_SAMPLE_PERMEABILITY, "permeability")                                                     \
  X(KARST_SAMPLE_FILL, "fill")                                                                     \
  X(KARST_SAMPLE_AMPLIFICATION, "amplification")                                                   \
  X(KARST_SAMPLE_PRESCRIBED, "prescribed_path")                                                    \
  X(KARST_SAMPLE_SURVEY, "survey")                                                                 \
  X(KARST_SAMPLE_POINTS, "points")

typedef enum {
#define KARST_X_ENUM(code, name) code,
  KARST_SAMPLE_SOURCE_LIST(KARST_X_ENUM)
#undef KARST_X_ENUM
      KARST_SAMPLE_SOURCE_COUNT
} karst_sample_source_t;

const char *karst_sample_source_name(karst_sample_source_t s);

/** A point cloud in the bedrock. Samples 0 .. n_key_points-1 are the scenario's key points, in
 * order. */
typedef struct karst_samples {
  karst_int_t n, cap;
  double *xyz;           /**< 3 * n */
  unsigned char *source; /**< karst_sample_source_t per sample */
  karst_int_t n_key_points;
  /** The coordinate system of xyz (the scenario's crs, written as field data "crs"), or NULL;
   *  borrowed: the scenario that karst_generate filled the samples from owns it. */
  const char *crs;
} karst_samples_t;

void karst_samples_init(karst_samples_t *s);
void karst_samples_destroy(karst_samples_t *s);
karst_error_t karst_samples_add(karst_samples_t *s, const double p[3], karst_sample_source_t src);

/**
 * Undirected weighted graph in compressed sparse row form: the arcs of vertex v
 * are offsets[v] .. offsets[v+1]-1, their heads sorted by index (coded, see
 * karst_graph_t) and the cost of arc a is cost[a]. Every edge appears in both
 * directions with the same cost (the line integral of Paris et al. 2021, §4,
 * is symmetric because c_F depends on (n·d)^2). Excluded edges (cost
 * INFINITY: leaving the bedrock) are removed, so every stored cost is finite.
 *
 * Costs are stored in single precision (karst_arc_cost_t: 4 bytes per arc instead of 8), each
 * the float nearest the double the cost model computed; searches add them up in double. With
 * u = 2^-24 (the unit roundoff of float), a stored cost c' of an exact cost c has
 * |c' - c| <= u c, so every path's stored cost is within a factor (1 ± u) of its exact one (the
 * double sums add at most (len - 1) 2^-53 relative more), and the least-cost path the searches
 * return costs at most (1 + u) / (1 - u) - 1 <= 1.2e-7 relatively more than the exact least
 * cost, for any path length (tests/unit/test_paths.c checks both bounds against a double-cost
 * Dijkstra).
 */
typedef float karst_arc_cost_t;

/** The stored cost of an arc whose cost is @p c: the nearest float (ties to even), INFINITY for
 *  INFINITY, and FLT_MAX for finite costs above it (an arc so dear stays an arc). */
static inline karst_arc_cost_t karst_arc_cost_round(double c) {
  return c > (double)FLT_MAX && c < INFINITY ? FLT_MAX : (karst_arc_cost_t)c;
}

/**
 * The neighbour indices are stored delta-coded, about 1.2 bytes per arc instead of 4 (the
 * samples' Morton order puts most neighbours within a few hundred indices of each other). Row v
 * is the byte string code[code_off[v] .. code_off[v+1]), a sequence of runs: a run is its first
 * arc's head (4 bytes, little-endian), the number r of arcs after it in the run (1 byte, 0 to
 * 255), then one byte per each of those r arcs, the gap to the previous head less one (gaps 1 to
 * 256). A row's first arc always starts a run; a gap outside 1 .. 256 (unsorted rows, repeated
 * heads) or a run of 256 arcs starts a new one. So any row codes, sorted rows smallest (1 byte
 * an arc, 4 more per run). Read a row with karst_graph_arcs and karst_arc_next; the library's
 * loops that must be fast read the runs themselves (KARST_I_ARCS_BEGIN,
 * src/graph/graph_internal.h).
 */
typedef struct karst_graph {
  karst_int_t n;          /**< vertices */
  karst_int_t n_arcs;     /**< directed arcs = 2 * undirected edges */
  const double *xyz;      /**< vertex positions (3 * n), borrowed from the samples */
  karst_int_t *offsets;   /**< n + 1: the arcs of v are offsets[v] .. offsets[v+1]-1 */
  unsigned char *code;    /**< code_off[n] bytes: the coded rows (above) */
  karst_int_t *code_off;  /**< n + 1: row v starts at code[code_off[v]] */
  karst_arc_cost_t *cost; /**< n_arcs, single precision (above) */
} karst_graph_t;

/** Reads the neighbours of one vertex in row order (karst_graph_arcs, karst_arc_next). */
typedef struct karst_arc_reader {
  const unsigned char *p;
  int64_t head;
  unsigned left; /**< arcs left in the run */
} karst_arc_reader_t;

/** A reader of the neighbours of @p v: the i-th call of karst_arc_next returns the head of arc
 *  offsets[v] + i. O(1). */
static inline karst_arc_reader_t karst_graph_arcs(const karst_graph_t *g, karst_int_t v) {
  karst_arc_reader_t r = {g->code + g->code_off[v], -1, 0};
  return r;
}

/** The head of a run (4 bytes, little-endian) at @p p. */
static inline int32_t karst_graph_run_head(const unsigned char *p) {
  return (int32_t)((uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 |
                   (uint32_t)p[3] << 24);
}

/** The head of the next arc of the row (call it at most once per arc, in order). O(1). */
static inline karst_int_t karst_arc_next(karst_arc_reader_t *r) {
  if (r->left == 0) {
    r->head = karst_graph_run_head(r->p);
    r->left = r->p[4];
    r->p += 5;
  } else {
    r->head += (int64_t)*r->p++ + 1;
    r->left--;
  }
  return (karst_int_t)r->head;
}

/** The arc v -> w of @p g (its index into cost), or -1 when there is none. O(degree of v). */
karst_int_t karst_graph_find_arc(const karst_graph_t *g, karst_int_t v, karst_int_t w);

/**
 * Make @p g the graph with the given rows: the arcs of v are heads adj[offsets[v] ..
 * offsets[v+1]-1] with costs cost[...], kept in the order given (sorted rows store smallest).
 * The heads are coded (above) and the costs copied. Every head must be in [0, n).
 * @return KARST_SUCCESS, KARST_EINVAL (n < 0 or >= 2^31 - 1, offsets not nondecreasing from 0,
 *         a head out of range), KARST_ENOMEM; @p g is unchanged on failure.
 * Time complexity: O(n + arcs).
 */
karst_error_t karst_graph_from_rows(karst_ctx_t *ctx, karst_graph_t *g, karst_int_t n,
                                    const double *xyz, const karst_int_t *offsets,
                                    const int32_t *adj, const karst_arc_cost_t *cost);

void karst_graph_init(karst_graph_t *g);
void karst_graph_destroy(karst_graph_t *g);

/**
 * Build a CSR graph from an undirected edge list (u[i], v[i], cost[i]),
 * dropping self-loops and INFINITY costs and keeping the cheaper of
 * duplicated edges. O(n + m log m).
 */
karst_error_t karst_graph_from_edges(karst_ctx_t *ctx, karst_graph_t *g, karst_int_t n,
                                     const double *xyz, karst_int_t m, const karst_int_t *u,
                                     const karst_int_t *v, const double *cost);

/**
 * The geometric graph of Paris et al. 2021, §4.1–4.2, ready for shortest
 * paths: exact k nearest neighbours (k = sampling.k) of every sample, ties
 * broken by the smaller index (grid search, src/graph/knn.c), made
 * undirected (union), edge costs the line integral of c (karst_cost_edge),
 * edges leaving the bedrock removed. @p out must be initialised; it borrows
 * samples->xyz. Uses ctx->nthreads threads; identical for any thread count.
 */
karst_error_t karst_graph_build(karst_ctx_t *ctx, const karst_geology_t *geo,
                                const karst_samples_t *samples, karst_graph_t *out);

/** Number of undirected edges of @p g (n_arcs / 2). */
karst_int_t karst_graph_edge_count(const karst_graph_t *g);

#ifdef __cplusplus
}
#endif
#endif
