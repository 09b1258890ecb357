/* The geometric graph on the samples (Paris et al. 2021, §4.1–4.2): exact k
 * nearest neighbours with FLANN, made undirected, stored in CSR form with the
 * line-integral cost of every edge. */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <flann/flann.h>

#include "cost/cost_internal.h"
#include "karst/graph.h"

/* Queries per FLANN call: bounds the result buffers to KNN_BATCH * (k + 1)
 * indices and distances instead of n * (k + 1). */
#define KNN_BATCH 65536
/* Rows handed to a thread at a time (interleaved, so the split is static and
 * the result does not depend on scheduling). */
#define ROW_BLOCK 512
#define MAX_THREADS 256

/** Make @p g an empty graph (no allocation). O(1). */
void karst_graph_init(karst_graph_t *g) {
  memset(g, 0, sizeof *g);
}

/** Release the storage of @p g (not the borrowed positions) and leave it empty. O(1). */
void karst_graph_destroy(karst_graph_t *g) {
  free(g->offsets);
  free(g->adj);
  free(g->cost);
  memset(g, 0, sizeof *g);
}

/** Number of undirected edges. O(1). */
karst_int_t karst_graph_edge_count(const karst_graph_t *g) {
  return g->n_arcs / 2;
}

/* ------------------------------------------------------------------------ */
/* A minimal static-partition thread pool                                    */
/* ------------------------------------------------------------------------ */
typedef void (*task_fn)(void *arg, int tid, int nthreads);
typedef struct task {
  task_fn fn;
  void *arg;
  int tid, nthreads;
} task_t;

static void *task_main(void *p) {
  task_t *t = p;
  t->fn(t->arg, t->tid, t->nthreads);
  return NULL;
}

/* Run fn(arg, tid, nthreads) for tid = 0 .. nthreads-1; a thread that cannot
 * be created runs in the caller, so the work is the same either way. */
static void run_parallel(int nthreads, task_fn fn, void *arg) {
  if (nthreads < 1) nthreads = 1;
  if (nthreads > MAX_THREADS) nthreads = MAX_THREADS;
  pthread_t th[MAX_THREADS];
  task_t tasks[MAX_THREADS];
  int started[MAX_THREADS] = {0};
  for (int t = 0; t < nthreads; t++)
    tasks[t] = (task_t){fn, arg, t, nthreads};
  for (int t = 1; t < nthreads; t++)
    started[t] = pthread_create(&th[t], NULL, task_main, &tasks[t]) == 0;
  fn(arg, 0, nthreads);
  for (int t = 1; t < nthreads; t++) {
    if (started[t])
      pthread_join(th[t], NULL);
    else
      fn(arg, t, nthreads);
  }
}

#define FOR_ROWS(v, n, tid, nth)                                                                   \
  for (karst_int_t blk_ = (tid); blk_ * ROW_BLOCK < (n); blk_ += (nth))                            \
    for (karst_int_t v = blk_ * ROW_BLOCK; v < (n) && v < (blk_ + 1) * ROW_BLOCK; v++)

/* ------------------------------------------------------------------------ */
/* Edge lists                                                                */
/* ------------------------------------------------------------------------ */
typedef struct arc {
  karst_int_t v;
  double c;
} arc_t;

static int cmp_arc(const void *a, const void *b) {
  const arc_t *x = a, *y = b;
  if (x->v != y->v) return (x->v > y->v) - (x->v < y->v);
  return (x->c > y->c) - (x->c < y->c);
}

/**
 * Build a CSR graph from the undirected edges (u[i], v[i]) with costs
 * cost[i]: each edge is stored in both directions, self-loops and edges of
 * cost INFINITY are dropped, of duplicated edges the cheapest is kept, and
 * every neighbour list is sorted by index.
 * @param ctx context for the error message.
 * @param g initialised graph, replaced on success, unchanged on failure.
 * @param n vertices; @param xyz their positions (3 n, borrowed, may be NULL).
 * @param m edges; @param u, v end points in [0, n); @param cost costs, >= 0 (not NaN).
 * @return KARST_SUCCESS, KARST_EINVAL (an index out of range, a negative or
 *         NaN cost, n or m < 0), KARST_ENOMEM.
 * Time complexity: O(n + m log m).
 */
karst_error_t karst_graph_from_edges(karst_ctx_t *ctx, karst_graph_t *g, karst_int_t n,
                                     const double *xyz, karst_int_t m, const karst_int_t *u,
                                     const karst_int_t *v, const double *cost) {
  karst_graph_t r;
  karst_graph_init(&r);
  arc_t *arcs = NULL;
  karst_int_t *fillp = NULL;
  karst_error_t err = KARST_SUCCESS;
  if (n < 0 || m < 0)
    return karst_set_error(ctx, KARST_EINVAL,
                           "graph: vertex count %lld and edge count %lld must be >= 0",
                           (long long)n, (long long)m);
  for (karst_int_t i = 0; i < m; i++) {
    if (u[i] < 0 || u[i] >= n || v[i] < 0 || v[i] >= n)
      return karst_set_error(ctx, KARST_EINVAL,
                             "graph: edge %lld (%lld, %lld) has an end outside [0, %lld)",
                             (long long)i, (long long)u[i], (long long)v[i], (long long)n);
    if (!(cost[i] >= 0))
      return karst_set_error(ctx, KARST_EINVAL,
                             "graph: edge %lld (%lld, %lld) has cost %g; costs must be >= 0",
                             (long long)i, (long long)u[i], (long long)v[i], cost[i]);
  }
  r.n = n;
  r.xyz = xyz;
  r.offsets = calloc((size_t)n + 1, sizeof(karst_int_t));
  fillp = malloc(sizeof(karst_int_t) * ((size_t)n + 1));
  if (!r.offsets || !fillp) goto nomem;
  for (karst_int_t i = 0; i < m; i++)
    if (u[i] != v[i] && isfinite(cost[i])) r.offsets[u[i] + 1]++, r.offsets[v[i] + 1]++;
  for (karst_int_t i = 0; i < n; i++)
    r.offsets[i + 1] += r.offsets[i];
  arcs = malloc(sizeof(arc_t) * ((size_t)r.offsets[n] + 1));
  if (!arcs) goto nomem;
  memcpy(fillp, r.offsets, sizeof(karst_int_t) * ((size_t)n + 1));
  for (karst_int_t i = 0; i < m; i++)
    if (u[i] != v[i] && isfinite(cost[i])) {
      arcs[fillp[u[i]]++] = (arc_t){v[i], cost[i]};
      arcs[fillp[v[i]]++] = (arc_t){u[i], cost[i]};
    }
  /* Sort each row by (neighbour, cost) and keep the first of each neighbour. */
  karst_int_t w = 0;
  for (karst_int_t x = 0; x < n; x++) {
    karst_int_t b = r.offsets[x], e = r.offsets[x + 1];
    qsort(arcs + b, (size_t)(e - b), sizeof(arc_t), cmp_arc);
    r.offsets[x] = w;
    for (karst_int_t i = b; i < e; i++)
      if (i == b || arcs[i].v != arcs[i - 1].v) arcs[w++] = arcs[i];
  }
  r.offsets[n] = w;
  r.n_arcs = w;
  r.adj = malloc(sizeof(karst_int_t) * ((size_t)w + 1));
  r.cost = malloc(sizeof(double) * ((size_t)w + 1));
  if (!r.adj || !r.cost) goto nomem;
  for (karst_int_t i = 0; i < w; i++)
    r.adj[i] = arcs[i].v, r.cost[i] = arcs[i].c;
  karst_graph_destroy(g);
  *g = r;
  karst_graph_init(&r);
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "no memory for a graph of %lld vertices and %lld edges",
                        (long long)n, (long long)m);
cleanup:
  karst_graph_destroy(&r);
  free(arcs);
  free(fillp);
  return err;
}

/* ------------------------------------------------------------------------ */
/* k nearest neighbours                                                      */
/* ------------------------------------------------------------------------ */
static void sort_i32(int32_t *v, int n) {
  for (int i = 1; i < n; i++) {
    int32_t x = v[i];
    int j = i - 1;
    while (j >= 0 && v[j] > x)
      v[j + 1] = v[j], j--;
    v[j + 1] = x;
  }
}

/* The k nearest other samples of every sample, each list sorted by index.
 * FLANN_INDEX_KDTREE_SINGLE is one exact k-d tree (the 3-D case needs no
 * approximation); its branch-and-bound search with eps = 0 is exact whatever
 * `checks` says. Each query is independent of the others, so the result does
 * not depend on FLANN's thread count. */
static karst_error_t knn_lists(karst_ctx_t *ctx, const double *xyz, karst_int_t n, int k,
                               int nthreads, int32_t *nbr, double *kd2) {
  karst_error_t err = KARST_SUCCESS;
  int *idx = NULL;
  double *dist = NULL;
  flann_log_verbosity(FLANN_LOG_NONE);
  struct FLANNParameters fp = DEFAULT_FLANN_PARAMETERS;
  fp.algorithm = FLANN_INDEX_KDTREE_SINGLE;
  fp.checks = FLANN_CHECKS_UNLIMITED;
  fp.eps = 0.0f;
  fp.sorted = 1;
  fp.cores = nthreads;
  fp.leaf_max_size = 10;
  fp.log_level = FLANN_LOG_NONE;
  float speedup = 0;
  /* FLANN's C API takes a non-const pointer but only reads the data set. */
  flann_index_t index = flann_build_index_double((double *)xyz, (int)n, 3, &speedup, &fp);
  if (!index)
    return karst_set_error(ctx, KARST_EEXTERNAL, "FLANN could not build a k-d tree of %lld points",
                           (long long)n);
  size_t batch = (size_t)(n < KNN_BATCH ? n : KNN_BATCH);
  idx = malloc(sizeof(int) * batch * (size_t)(k + 1));
  dist = malloc(sizeof(double) * batch * (size_t)(k + 1));
  if (!idx || !dist) {
    err = karst_set_error(ctx, KARST_ENOMEM, "no memory for the neighbour search");
    goto cleanup;
  }
  for (karst_int_t b0 = 0; b0 < n; b0 += (karst_int_t)batch) {
    if (karst_interrupted(ctx)) {
      err = karst_set_error(ctx, KARST_EINTERRUPTED, "neighbour search interrupted");
      goto cleanup;
    }
    int rows = (int)(n - b0 < (karst_int_t)batch ? n - b0 : (karst_int_t)batch);
    if (flann_find_nearest_neighbors_index_double(index, (double *)xyz + 3 * b0, rows, idx, dist,
                                                  k + 1, &fp) != 0) {
      err = karst_set_error(ctx, KARST_EEXTERNAL, "FLANN neighbour search failed");
      goto cleanup;
    }
    for (int r = 0; r < rows; r++) {
      karst_int_t v = b0 + r;
      int32_t *out = nbr + (size_t)v * (size_t)k;
      const int *ri = idx + (size_t)r * (size_t)(k + 1);
      int c = 0;
      /* Drop the query itself (with duplicate points it may not come first). */
      for (int j = 0; j <= k && c < k; j++)
        if (ri[j] != v && ri[j] >= 0) out[c++] = ri[j];
      for (int j = 0; c < k && j <= k; j++)
        out[c++] = ri[j];
      kd2[v] = dist[(size_t)r * (size_t)(k + 1) + (size_t)k]; /* farthest of the k + 1 */
      sort_i32(out, k);
    }
    karst_progress(ctx, "neighbours", (double)(b0 + rows), (double)n);
  }
cleanup:
  flann_free_index_double(index, &fp);
  free(idx);
  free(dist);
  return err;
}

static int contains_i32(const int32_t *v, int n, int32_t x) {
  int lo = 0, hi = n;
  while (lo < hi) {
    int mid = (lo + hi) / 2;
    if (v[mid] < x)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < n && v[lo] == x;
}

static karst_int_t find_arc(const karst_int_t *adj, karst_int_t b, karst_int_t e, karst_int_t x) {
  while (b < e) {
    karst_int_t mid = b + (e - b) / 2;
    if (adj[mid] < x)
      b = mid + 1;
    else
      e = mid;
  }
  return b;
}

typedef struct build {
  karst_ctx_t *ctx;
  karst_int_t n;
  int k;
  const int32_t *nbr;
  const double *kd2;
  unsigned char *mutual, *inside;
  karst_graph_t *g;
  const karst_i_cost_model_t *model;
  karst_int_t max_deg;
  int failed[MAX_THREADS];
} build_t;

/* mutual[u k + j] = whether u is also among the neighbours of v = nbr[u k + j].
 * A point strictly closer to v than v's k-th neighbour is in v's list, one
 * strictly farther is not; only distances within MUTUAL_BAND (relative) of
 * the k-th distance, where FLANN's rounding or a tie could decide, are
 * looked up in the list. The band only chooses the exact path: no effect
 * on the result. */
#define MUTUAL_BAND 1e-9
static void task_mutual(void *p, int tid, int nth) {
  build_t *B = p;
  int k = B->k;
  const double *x = B->g->xyz;
  FOR_ROWS(u, B->n, tid, nth) {
    for (int j = 0; j < k; j++) {
      int32_t v = B->nbr[(size_t)u * k + j];
      const double *a = x + 3 * u, *b = x + 3 * (karst_int_t)v;
      double d2 = (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                  (a[2] - b[2]) * (a[2] - b[2]);
      double kd = B->kd2[v];
      unsigned char m;
      if (d2 < kd * (1 - MUTUAL_BAND))
        m = 1;
      else if (d2 > kd * (1 + MUTUAL_BAND))
        m = 0;
      else
        m = (unsigned char)contains_i32(B->nbr + (size_t)v * k, k, (int32_t)u);
      B->mutual[(size_t)u * k + j] = m;
    }
  }
}

/* ok[v] = whether vertex v is in the bedrock (edges at v are then excluded). */
static void task_inside(void *p, int tid, int nth) {
  build_t *B = p;
  FOR_ROWS(v, B->n, tid, nth)
  B->inside[v] = (unsigned char)karst_cost_in_bedrock(B->model->sc, B->g->xyz + 3 * v);
}

/* Each row holds its own k neighbours then, in increasing order, the
 * vertices that chose it without being chosen: merge the two sorted runs. */
static void task_merge(void *p, int tid, int nth) {
  build_t *B = p;
  karst_graph_t *g = B->g;
  karst_int_t *tmp = malloc(sizeof(karst_int_t) * ((size_t)B->max_deg + 1));
  if (!tmp) {
    B->failed[tid] = 1;
    return;
  }
  FOR_ROWS(v, B->n, tid, nth) {
    karst_int_t b = g->offsets[v], mid = b + B->k, e = g->offsets[v + 1];
    if (mid >= e) continue;
    karst_int_t i = b, j = mid, w = 0;
    while (i < mid && j < e)
      tmp[w++] = g->adj[i] < g->adj[j] ? g->adj[i++] : g->adj[j++];
    while (i < mid)
      tmp[w++] = g->adj[i++];
    while (j < e)
      tmp[w++] = g->adj[j++];
    memcpy(g->adj + b, tmp, sizeof(karst_int_t) * (size_t)w);
  }
  free(tmp);
}

/* Cost of each undirected edge {u, v}, u < v, computed once by the thread
 * owning row u and written to both arcs: no two threads write the same
 * slot, and the value is a pure function of the two positions. */
static void task_cost(void *p, int tid, int nth) {
  build_t *B = p;
  karst_graph_t *g = B->g;
  FOR_ROWS(u, B->n, tid, nth) {
    if ((u & 4095) == 0 && karst_interrupted(B->ctx)) {
      B->failed[tid] = 2;
      return;
    }
    for (karst_int_t a = g->offsets[u]; a < g->offsets[u + 1]; a++) {
      karst_int_t v = g->adj[a];
      if (v < u) continue;
      double c = B->inside[u] && B->inside[v]
                     ? karst_i_cost_edge_inside(B->model, g->xyz + 3 * u, g->xyz + 3 * v)
                     : INFINITY;
      g->cost[a] = c;
      g->cost[find_arc(g->adj, g->offsets[v], g->offsets[v + 1], u)] = c;
    }
  }
}

/**
 * The graph G of Paris et al. 2021, §4.1–4.2 on the samples: every sample is
 * joined to its k = sampling.k nearest other samples (exact search with
 * FLANN's single k-d tree; k is reduced to n − 1 when there are fewer
 * samples), the relation is made symmetric (union of u→v and v→u), each
 * edge gets the line integral of the cost c along its segment
 * (karst_cost_edge, including the prescribed-path factor) and edges leaving
 * the bedrock are removed. Neighbour lists are sorted by index.
 * The neighbour search (FLANN, OpenMP) and the costs (pthreads) use
 * ctx->nthreads threads; the result is identical for any thread count.
 * @param ctx context (threads, errors, progress, interrupt).
 * @param sc the scenario (k and the cost weights).
 * @param samples the vertices; the graph borrows samples->xyz.
 * @param out initialised graph, replaced on success, unchanged on failure.
 * @return KARST_SUCCESS, KARST_EINVAL (k < 1, non-finite sample, more than
 *         INT32_MAX samples), KARST_ENOMEM, KARST_EEXTERNAL (FLANN failed),
 *         KARST_EINTERRUPTED.
 * Time complexity: O(n k log n) for the search (k-d tree), O(n k log k) to
 * symmetrise, O(n k q) for the costs with q quadrature points per edge.
 */
karst_error_t karst_graph_build(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                const karst_samples_t *samples, karst_graph_t *out) {
  karst_graph_t g;
  karst_graph_init(&g);
  int32_t *nbr = NULL;
  double *kd2 = NULL;
  unsigned char *mutual = NULL, *inside = NULL;
  karst_int_t *cursor = NULL;
  karst_i_cost_model_t model;
  memset(&model, 0, sizeof model);
  karst_error_t err = KARST_SUCCESS;
  karst_int_t n = samples->n;
  int nth = ctx && ctx->nthreads > 0 ? ctx->nthreads : 1;
  if (sc->sampling.k < 1)
    return karst_set_error(ctx, KARST_EINVAL, "sampling.k must be >= 1, got %d", sc->sampling.k);
  if (n < 0 || n >= INT32_MAX)
    return karst_set_error(ctx, KARST_EINVAL, "graph: %lld samples; at most %d are supported",
                           (long long)n, INT32_MAX - 1);
  for (karst_int_t i = 0; i < 3 * n; i++)
    if (!isfinite(samples->xyz[i]))
      return karst_set_error(ctx, KARST_EINVAL, "graph: sample %lld has a non-finite coordinate %g",
                             (long long)(i / 3), samples->xyz[i]);
  if ((err = karst_i_cost_model_init(ctx, &model, sc)) != KARST_SUCCESS) return err;
  g.n = n;
  g.xyz = samples->xyz;
  g.offsets = calloc((size_t)n + 1, sizeof(karst_int_t));
  if (!g.offsets) goto nomem;
  int k = sc->sampling.k < n - 1 ? sc->sampling.k : (int)(n > 0 ? n - 1 : 0);
  if (k > 0) {
    nbr = malloc(sizeof(int32_t) * (size_t)n * (size_t)k);
    kd2 = malloc(sizeof(double) * (size_t)n);
    mutual = malloc((size_t)n * (size_t)k);
    inside = malloc((size_t)n);
    cursor = malloc(sizeof(karst_int_t) * (size_t)n);
    if (!nbr || !kd2 || !mutual || !inside || !cursor) goto nomem;
    if ((err = knn_lists(ctx, samples->xyz, n, k, nth, nbr, kd2)) != KARST_SUCCESS) goto cleanup;
    build_t B = {ctx, n, k, nbr, kd2, mutual, inside, &g, &model, 0, {0}};
    run_parallel(nth, task_mutual, &B);
    run_parallel(nth, task_inside, &B);
    /* Degrees: k own neighbours plus the vertices that chose v alone. */
    for (karst_int_t v = 0; v < n; v++)
      g.offsets[v + 1] = k;
    for (size_t a = 0; a < (size_t)n * (size_t)k; a++)
      if (!mutual[a]) g.offsets[nbr[a] + 1]++;
    for (karst_int_t v = 0; v < n; v++) {
      B.max_deg = g.offsets[v + 1] > B.max_deg ? g.offsets[v + 1] : B.max_deg;
      g.offsets[v + 1] += g.offsets[v];
    }
    g.n_arcs = g.offsets[n];
    g.adj = malloc(sizeof(karst_int_t) * (size_t)g.n_arcs);
    g.cost = malloc(sizeof(double) * (size_t)g.n_arcs);
    if (!g.adj || !g.cost) goto nomem;
    for (karst_int_t v = 0; v < n; v++) {
      for (int j = 0; j < k; j++)
        g.adj[g.offsets[v] + j] = nbr[(size_t)v * k + j];
      cursor[v] = g.offsets[v] + k;
    }
    for (karst_int_t u = 0; u < n; u++)
      for (int j = 0; j < k; j++)
        if (!mutual[(size_t)u * k + j]) {
          int32_t v = nbr[(size_t)u * k + j];
          g.adj[cursor[v]++] = u;
        }
    free(nbr), free(mutual), free(cursor), free(kd2);
    nbr = NULL, mutual = NULL, cursor = NULL, kd2 = NULL;
    run_parallel(nth, task_merge, &B);
    for (int t = 0; t < MAX_THREADS; t++)
      if (B.failed[t]) goto nomem;
    karst_progress(ctx, "edge costs", 0, 1);
    run_parallel(nth, task_cost, &B);
    for (int t = 0; t < MAX_THREADS; t++)
      if (B.failed[t]) {
        err = karst_set_error(ctx, KARST_EINTERRUPTED, "edge cost evaluation interrupted");
        goto cleanup;
      }
    /* Remove the excluded (infinite) edges; costs are symmetric, so both
     * arcs of an edge go together. */
    karst_int_t w = 0;
    for (karst_int_t v = 0; v < n; v++) {
      karst_int_t b = g.offsets[v], e = g.offsets[v + 1];
      g.offsets[v] = w;
      for (karst_int_t a = b; a < e; a++)
        if (isfinite(g.cost[a])) g.adj[w] = g.adj[a], g.cost[w++] = g.cost[a];
    }
    g.offsets[n] = w;
    g.n_arcs = w;
    karst_progress(ctx, "edge costs", 1, 1);
  }
  karst_log(ctx, KARST_LOG_INFO, "graph: %lld vertices, %lld edges (k = %d)", (long long)n,
            (long long)(g.n_arcs / 2), k);
  karst_graph_destroy(out);
  *out = g;
  karst_graph_init(&g);
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "no memory for the graph of %lld samples", (long long)n);
cleanup:
  karst_graph_destroy(&g);
  karst_i_cost_model_destroy(&model);
  free(nbr);
  free(kd2);
  free(mutual);
  free(inside);
  free(cursor);
  return err;
}
