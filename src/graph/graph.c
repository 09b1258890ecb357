/* The geometric graph on the samples (Paris et al. 2021, §4.1–4.2): exact k
 * nearest neighbours (knn.c), made undirected, stored in CSR form with the
 * line-integral cost of every edge. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/memory_internal.h"
#include "core/parallel_internal.h"
#include "cost/cost_internal.h"
#include "graph/graph_internal.h"
#include "karst/graph.h"

/** Make @p g an empty graph (no allocation). O(1). */
void karst_graph_init(karst_graph_t *g) {
  memset(g, 0, sizeof *g);
}

/** Release the storage of @p g (not the borrowed positions) and leave it empty. O(1). */
void karst_graph_destroy(karst_graph_t *g) {
  free(g->offsets);
  free(g->code);
  free(g->code_off);
  free(g->cost);
  memset(g, 0, sizeof *g);
}

/** Number of undirected edges. O(1). */
karst_int_t karst_graph_edge_count(const karst_graph_t *g) {
  return g->n_arcs / 2;
}

/* ------------------------------------------------------------------------ */
/* The coded rows (karst_graph_t)                                            */
/* ------------------------------------------------------------------------ */

/* Row coding (karst_graph_t): whether head h, after head prev in a run of @p run arcs after
 * its first, continues the run as a gap (1 to 256). */
static inline int codes_as_gap(int64_t prev, int64_t h, int run) {
  return h - prev >= 1 && h - prev <= 256 && run < 255;
}

/* Bytes of the row h[0 .. d) coded. */
static karst_int_t row_bytes(const int32_t *h, karst_int_t d) {
  karst_int_t bytes = 0;
  int run = 0;
  for (karst_int_t i = 0; i < d; i++) {
    if (i > 0 && codes_as_gap(h[i - 1], h[i], run))
      bytes++, run++;
    else
      bytes += 5, run = 0;
  }
  return bytes;
}

/* Code the row h[0 .. d) into out; returns the bytes written (row_bytes). */
static karst_int_t row_encode(const int32_t *h, karst_int_t d, unsigned char *out) {
  unsigned char *const start = out, *count = NULL;
  for (karst_int_t i = 0; i < d; i++) {
    if (i > 0 && codes_as_gap(h[i - 1], h[i], *count)) {
      *out++ = (unsigned char)(h[i] - h[i - 1] - 1);
      ++*count;
    } else {
      uint32_t x = (uint32_t)h[i];
      out[0] = (unsigned char)x, out[1] = (unsigned char)(x >> 8);
      out[2] = (unsigned char)(x >> 16), out[3] = (unsigned char)(x >> 24);
      out[4] = 0;
      count = out + 4;
      out += 5;
    }
  }
  return out - start;
}

karst_int_t karst_graph_find_arc(const karst_graph_t *g, karst_int_t v, karst_int_t w) {
  if (v < 0 || v >= g->n) return -1;
  karst_arc_reader_t r = karst_graph_arcs(g, v);
  for (karst_int_t a = g->offsets[v]; a < g->offsets[v + 1]; a++)
    if (karst_arc_next(&r) == w) return a;
  return -1;
}

karst_error_t karst_graph_from_rows(karst_ctx_t *ctx, karst_graph_t *g, karst_int_t n,
                                    const double *xyz, const karst_int_t *offsets,
                                    const int32_t *adj, const karst_arc_cost_t *cost) {
  if (n < 0 || n >= INT32_MAX)
    return karst_set_error(ctx, KARST_EINVAL,
                           "graph: %lld vertices; from 0 to 2^31 - 2 are supported", (long long)n);
  if (offsets[0] != 0)
    return karst_set_error(ctx, KARST_EINVAL, "graph: the first row starts at arc %lld, not 0",
                           (long long)offsets[0]);
  for (karst_int_t v = 0; v < n; v++) {
    if (offsets[v + 1] < offsets[v])
      return karst_set_error(ctx, KARST_EINVAL,
                             "graph: row %lld ends (%lld) before it starts (%lld)", (long long)v,
                             (long long)offsets[v + 1], (long long)offsets[v]);
    for (karst_int_t a = offsets[v]; a < offsets[v + 1]; a++)
      if (adj[a] < 0 || adj[a] >= n)
        return karst_set_error(ctx, KARST_EINVAL,
                               "graph: arc %lld of vertex %lld has head %lld, outside [0, %lld)",
                               (long long)a, (long long)v, (long long)adj[a], (long long)n);
  }
  karst_int_t *o = malloc(sizeof(karst_int_t) * ((size_t)n + 1));
  karst_arc_cost_t *c = malloc(sizeof *c * ((size_t)offsets[n] + 1));
  if (!o || !c) {
    free(o), free(c);
    return karst_set_error(ctx, KARST_ENOMEM,
                           "no memory for a graph of %lld vertices and %lld arcs", (long long)n,
                           (long long)offsets[n]);
  }
  memcpy(o, offsets, sizeof(karst_int_t) * ((size_t)n + 1));
  if (offsets[n] > 0) memcpy(c, cost, sizeof *c * (size_t)offsets[n]);
  return karst_i_graph_take_rows(ctx, g, n, xyz, o, adj, c);
}

karst_error_t karst_i_graph_take_rows(karst_ctx_t *ctx, karst_graph_t *g, karst_int_t n,
                                      const double *xyz, karst_int_t *offsets, const int32_t *adj,
                                      karst_arc_cost_t *cost) {
  karst_int_t *code_off = malloc(sizeof(karst_int_t) * ((size_t)n + 1));
  unsigned char *code = NULL;
  if (code_off) {
    code_off[0] = 0;
    for (karst_int_t v = 0; v < n; v++)
      code_off[v + 1] = code_off[v] + row_bytes(adj + offsets[v], offsets[v + 1] - offsets[v]);
    code = malloc((size_t)code_off[n] + 1);
  }
  if (!code) {
    free(offsets), free(cost), free(code_off);
    return karst_set_error(ctx, KARST_ENOMEM, "no memory for a graph of %lld vertices",
                           (long long)n);
  }
  for (karst_int_t v = 0; v < n; v++)
    row_encode(adj + offsets[v], offsets[v + 1] - offsets[v], code + code_off[v]);
  karst_graph_destroy(g);
  g->n = n;
  g->xyz = xyz;
  g->n_arcs = offsets[n];
  g->offsets = offsets;
  g->code = code;
  g->code_off = code_off;
  g->cost = cost;
  return KARST_SUCCESS;
}

/* Rows handed to a thread at a time (interleaved, so the split is static and
 * the result does not depend on scheduling). */
#define ROW_BLOCK 512

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
  if (n < 0 || m < 0 || n >= INT32_MAX)
    return karst_set_error(ctx, KARST_EINVAL,
                           "graph: vertex count %lld and edge count %lld must be >= 0, with "
                           "fewer than 2^31 - 1 vertices",
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
  int32_t *adj = malloc(sizeof(int32_t) * ((size_t)w + 1));
  karst_arc_cost_t *c = malloc(sizeof *c * ((size_t)w + 1));
  if (!adj || !c) {
    free(adj), free(c);
    goto nomem;
  }
  for (karst_int_t i = 0; i < w; i++)
    adj[i] = (int32_t)arcs[i].v, c[i] = karst_arc_cost_round(arcs[i].c);
  err = karst_i_graph_take_rows(ctx, g, n, xyz, r.offsets, adj, c);
  r.offsets = NULL;
  free(adj);
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
/* The kNN graph                                                             */
/* ------------------------------------------------------------------------ */
/* Sources are split into at most this many contiguous chunks for the
 * scatter of the arcs into rows (one count array of n entries each). */
#define SCATTER_MAX_CHUNKS 8

/* First arc of row v whose head is x or more (rows are sorted), or offsets[v + 1]. Usually
 * few heads precede x (neighbours have nearby indices in the samples' Morton order). */
static karst_int_t first_at_least(const karst_graph_t *g, karst_int_t v, karst_int_t x) {
  karst_arc_reader_t r = karst_graph_arcs(g, v);
  karst_int_t a = g->offsets[v];
  for (; a < g->offsets[v + 1]; a++)
    if (karst_arc_next(&r) >= x) break;
  return a;
}

typedef struct build {
  karst_ctx_t *ctx;
  karst_int_t n;
  int k, nchunks;
  int32_t *nbr; /* n k; an arc u -> w whose reverse is not a kNN arc is stored as ~w */
  const int32_t *kidx;
  const double *kd2;
  int32_t *cnt;     /* nchunks n: arcs of chunk c into w, then their next slot in row w */
  int32_t *own;     /* per vertex: own arcs whose reverse is not a kNN arc */
  int32_t *lo, *hi; /* per vertex: its least and greatest k nearest */
  /* The batch of rows being built: rows v0 .. v1-1, their heads in buf (arc a at a - a0). */
  karst_int_t v0, v1, a0;
  int32_t *buf;
  unsigned char *inside;
  karst_graph_t *g;
  const karst_i_cost_model_t *model;
  karst_int_t n_infinite[KARST_I_MAX_THREADS];
  int failed[KARST_I_MAX_THREADS];
} build_t;

/* Contiguous source chunks per thread for the edge costs (see task_cost). */
#define COST_CHUNKS_PER_THREAD 8
/* Threads for the edge costs: each holds a cursor per vertex (4 n bytes). */
#define COST_MAX_THREADS 16

#define CHUNK_BEGIN(B, c) ((B)->n * (karst_int_t)(c) / (B)->nchunks)

/* Whether u is among the k nearest of v: the neighbours of v are exactly
 * the points (d², index) <= v's k-th in the search's total order, with d²
 * computed by the same karst_i_dist2. */
static int chosen_by(const build_t *B, karst_int_t u, int32_t v) {
  double d = karst_i_dist2(B->g->xyz + 3 * u, B->g->xyz + 3 * (karst_int_t)v);
  return !karst_i_knn_less(B->kd2[v], B->kidx[v], d, (int32_t)u);
}

/* The row of v is in(v) = {u : v among the k nearest of u} plus the own
 * neighbours w of v that did not choose v. Count both, chunk by chunk. */
static void task_count(void *p, int tid, int nth) {
  build_t *B = p;
  int k = B->k;
  for (int c = tid; c < B->nchunks; c += nth) {
    int32_t *cnt = B->cnt + (size_t)c * (size_t)B->n;
    for (karst_int_t u = CHUNK_BEGIN(B, c); u < CHUNK_BEGIN(B, c + 1); u++) {
      B->inside[u] = (unsigned char)karst_geology_in_bedrock(B->model->geo, B->g->xyz + 3 * u);
      int32_t *row = B->nbr + (size_t)u * k, own = 0, lo = INT32_MAX, hi = -1;
      for (int j = 0; j < k; j++) {
        int32_t w = row[j];
        cnt[w]++;
        lo = w < lo ? w : lo, hi = w > hi ? w : hi;
        if (!chosen_by(B, u, w)) row[j] = ~w, own++;
      }
      B->own[u] = own, B->lo[u] = lo, B->hi[u] = hi;
    }
  }
}

/* Sources in increasing order within a chunk, chunks in increasing order
 * within a row: every in(v) run comes out sorted, whatever the threads. Only the
 * rows of the batch are written (sources whose neighbours all lie outside it are
 * skipped). */
static void task_scatter(void *p, int tid, int nth) {
  build_t *B = p;
  int k = B->k;
  const karst_graph_t *g = B->g;
  const karst_int_t v0 = B->v0, v1 = B->v1, a0 = B->a0;
  for (int c = tid; c < B->nchunks; c += nth) {
    int32_t *cnt = B->cnt + (size_t)c * (size_t)B->n;
    for (karst_int_t u = CHUNK_BEGIN(B, c); u < CHUNK_BEGIN(B, c + 1); u++) {
      if (B->hi[u] < v0 || B->lo[u] >= v1) continue;
      const int32_t *row = B->nbr + (size_t)u * k;
      for (int j = 0; j < k; j++) {
        int32_t w = row[j] < 0 ? ~row[j] : row[j];
        if (w >= v0 && w < v1) B->buf[g->offsets[w] - a0 + cnt[w]++] = (int32_t)u;
      }
    }
  }
}

static void sort_small_i32(int32_t *v, int n) {
  for (int i = 1; i < n; i++) {
    int32_t x = v[i];
    int j = i - 1;
    while (j >= 0 && v[j] > x)
      v[j + 1] = v[j], j--;
    v[j + 1] = x;
  }
}

/* The rows of the batch, ROW_BLOCK at a time, interleaved between the threads. */
#define FOR_BATCH_ROWS(v, B, tid, nth)                                                             \
  for (karst_int_t blk_ = (B)->v0 + (karst_int_t)(tid)*ROW_BLOCK; blk_ < (B)->v1;                  \
       blk_ += (karst_int_t)(nth)*ROW_BLOCK)                                                       \
    for (karst_int_t v = blk_; v < (B)->v1 && v < blk_ + ROW_BLOCK; v++)

/* Coded bytes of each row of the batch, into code_off[v + 1] (made a prefix sum after). */
static void task_count_bytes(void *p, int tid, int nth) {
  build_t *B = p;
  karst_graph_t *g = B->g;
  FOR_BATCH_ROWS(v, B, tid, nth) {
    g->code_off[v + 1] =
        row_bytes(B->buf + (g->offsets[v] - B->a0), g->offsets[v + 1] - g->offsets[v]);
  }
}

/* Code the rows of the batch (code_off ready, code large enough). */
static void task_encode(void *p, int tid, int nth) {
  build_t *B = p;
  karst_graph_t *g = B->g;
  FOR_BATCH_ROWS(v, B, tid, nth) {
    row_encode(B->buf + (g->offsets[v] - B->a0), g->offsets[v + 1] - g->offsets[v],
               g->code + g->code_off[v]);
  }
}

/* Merge the sorted in(v) run at the start of each row with the few own
 * neighbours that did not choose v (sorted here), which fill the row. */
static void task_merge(void *p, int tid, int nth) {
  build_t *B = p;
  karst_graph_t *g = B->g;
  int k = B->k;
  int32_t *tmp = malloc(sizeof(int32_t) * (size_t)(k + 1));
  if (!tmp) {
    B->failed[tid] = 1;
    return;
  }
  FOR_BATCH_ROWS(v, B, tid, nth) {
    int own = B->own[v];
    if (own == 0) continue;
    const int32_t *row = B->nbr + (size_t)v * k;
    int m = 0;
    for (int j = 0; j < k; j++)
      if (row[j] < 0) tmp[m++] = ~row[j];
    sort_small_i32(tmp, m);
    /* Merge from the back: the free slots are at the end of the row. */
    int32_t *adj = B->buf + (g->offsets[v] - B->a0);
    karst_int_t i = g->offsets[v + 1] - g->offsets[v] - own - 1, w = i + own;
    int j = own - 1;
    while (j >= 0) {
      if (i >= 0 && adj[i] > tmp[j])
        adj[w--] = adj[i--];
      else
        adj[w--] = tmp[j--];
    }
  }
  free(tmp);
}

/* Cost of each undirected edge {u, v}, u < v, computed once and written to
 * both arcs. Sources are taken in contiguous chunks, in increasing order:
 * the sources u < v of one chunk that are neighbours of v then form one run
 * of v's sorted row, met in the same order, so the reverse arc's slot is a
 * per-row cursor (started at the chunk's first source by one scan of v's row)
 * instead of a search per edge. No two chunks write the same slot, and each
 * value is a pure function of the two positions. */
static void task_cost(void *p, int tid, int nth) {
  build_t *B = p;
  karst_graph_t *g = B->g;
  karst_int_t n_inf = 0;
  int32_t *cursor = malloc(sizeof(int32_t) * ((size_t)B->n + 1));
  if (!cursor) {
    B->failed[tid] = 1;
    return;
  }
  memset(cursor, 0xff, sizeof(int32_t) * ((size_t)B->n + 1)); /* -1: not started */
  for (int c = tid; c < B->nchunks; c += nth) {
    karst_int_t u0 = CHUNK_BEGIN(B, c), u1 = CHUNK_BEGIN(B, c + 1);
    for (karst_int_t u = u0; u < u1; u++) {
      if ((u & 4095) == 0 && karst_interrupted(B->ctx)) {
        B->failed[tid] = 2;
        goto cleanup;
      }
      KARST_I_ARCS_BEGIN(g, u, a, v)
        if (v <= u) continue;
        const karst_int_t b = g->offsets[v];
        double cst = B->inside[u] && B->inside[v]
                         ? karst_i_cost_edge_inside(B->model, g->xyz + 3 * u, g->xyz + 3 * v)
                         : INFINITY;
        n_inf += !isfinite(cst);
        const karst_arc_cost_t cf = karst_arc_cost_round(cst);
        g->cost[a] = cf;
        if (cursor[v] < 0) cursor[v] = (int32_t)(first_at_least(g, v, u0) - b);
        g->cost[b + cursor[v]++] = cf;
      KARST_I_ARCS_END
    }
    for (karst_int_t u = u0; u < u1; u++) { /* reset what this chunk started */
      KARST_I_ARCS_BEGIN(g, u, a, w)
        (void)a;
        cursor[w] = -1;
      KARST_I_ARCS_END
    }
  }
cleanup:
  B->n_infinite[tid] = n_inf;
  free(cursor);
}

/* Batches the rows of a large graph are built in (see karst_graph_build). */
#define BUILD_BATCHES 4

karst_int_t karst_i_graph_min_batch_arcs = (karst_int_t)1 << 22;

/* Remove the @p n_drop arcs of infinite cost (edges leaving the bedrock; costs are symmetric, so
 * both arcs of an edge go together): each row is read and coded again over its kept arcs into a
 * new byte array (a removed arc can turn the gap after it into a new run: 4 bytes more at most),
 * the costs moving down in place. O(arcs). */
static karst_error_t drop_infinite_arcs(karst_ctx_t *ctx, karst_graph_t *g, karst_int_t n_drop) {
  karst_int_t maxdeg = 0;
  for (karst_int_t v = 0; v < g->n; v++)
    if (g->offsets[v + 1] - g->offsets[v] > maxdeg) maxdeg = g->offsets[v + 1] - g->offsets[v];
  unsigned char *code = karst_i_alloc_large((size_t)(g->code_off[g->n] + 4 * n_drop) + 1);
  int32_t *row = malloc(sizeof(int32_t) * ((size_t)maxdeg + 1));
  if (!code || !row) {
    free(code), free(row);
    return karst_set_error(ctx, KARST_ENOMEM, "no memory for the graph of %lld samples",
                           (long long)g->n);
  }
  karst_int_t w = 0, x = 0;
  for (karst_int_t v = 0; v < g->n; v++) {
    karst_arc_reader_t r = karst_graph_arcs(g, v);
    karst_int_t b = g->offsets[v], e = g->offsets[v + 1], m = 0;
    g->offsets[v] = w, g->code_off[v] = x;
    for (karst_int_t a = b; a < e; a++) {
      int32_t h = (int32_t)karst_arc_next(&r);
      if (isfinite(g->cost[a])) row[m] = h, g->cost[w + m++] = g->cost[a];
    }
    w += m, x += row_encode(row, m, code + x);
  }
  g->offsets[g->n] = w, g->code_off[g->n] = x;
  g->n_arcs = w;
  free(row);
  free(g->code);
  g->code = code;
  return KARST_SUCCESS;
}

/**
 * The graph G of Paris et al. 2021, §4.1–4.2 on the samples: every sample is
 * joined to its k = sampling.k nearest other samples (exact search on a
 * uniform grid, ties broken by the smaller index, see knn.c; k is reduced to
 * n − 1 when there are fewer samples), the relation is made symmetric (union
 * of u→v and v→u), each edge gets the line integral of the cost c along its
 * segment (karst_cost_edge, including the prescribed-path factor) and edges
 * leaving the bedrock are removed. Neighbour lists are sorted by index.
 * Every stage uses ctx->nthreads threads; the result is identical for any
 * thread count.
 * @param ctx context (threads, errors, progress, interrupt).
 * @param geo the geology (with its scenario: k and the cost weights).
 * @param samples the vertices; the graph borrows samples->xyz.
 * @param out initialised graph, replaced on success, unchanged on failure.
 * @return KARST_SUCCESS, KARST_EINVAL (k < 1, non-finite sample, more than
 *         INT32_MAX samples), KARST_ENOMEM, KARST_EINTERRUPTED.
 * Time complexity: O(n k log k) for nearly uniform samples (the search,
 * knn.c), O(n k) to symmetrise, O(n k q) for the costs with q quadrature
 * points per edge.
 */
karst_error_t karst_graph_build(karst_ctx_t *ctx, const karst_geology_t *geo,
                                const karst_samples_t *samples, karst_graph_t *out) {
  karst_graph_t g;
  karst_graph_init(&g);
  int32_t *nbr = NULL, *kidx = NULL, *cnt = NULL, *own = NULL, *lo = NULL, *hi = NULL, *buf = NULL;
  double *kd2 = NULL;
  unsigned char *inside = NULL;
  karst_i_cost_model_t model;
  memset(&model, 0, sizeof model);
  karst_error_t err = KARST_SUCCESS;
  karst_int_t n = samples->n;
  int nth = ctx && ctx->nthreads > 0 ? ctx->nthreads : 1;
  const karst_scenario_t *sc = karst_geology_scenario(geo);
  if (sc->sampling.k < 1)
    return karst_set_error(ctx, KARST_EINVAL, "sampling.k must be >= 1, got %d", sc->sampling.k);
  if (n < 0 || n >= INT32_MAX)
    return karst_set_error(ctx, KARST_EINVAL, "graph: %lld samples; at most %d are supported",
                           (long long)n, INT32_MAX - 1);
  for (karst_int_t i = 0; i < 3 * n; i++)
    if (!isfinite(samples->xyz[i]))
      return karst_set_error(ctx, KARST_EINVAL, "graph: sample %lld has a non-finite coordinate %g",
                             (long long)(i / 3), samples->xyz[i]);
  if ((err = karst_i_cost_model_init(ctx, &model, geo)) != KARST_SUCCESS) return err;
  g.n = n;
  g.xyz = samples->xyz;
  g.offsets = karst_i_calloc_large((size_t)n + 1, sizeof(karst_int_t));
  if (!g.offsets) goto nomem;
  int k = sc->sampling.k < n - 1 ? sc->sampling.k : (int)(n > 0 ? n - 1 : 0);
  g.code_off = karst_i_calloc_large((size_t)n + 1, sizeof(karst_int_t));
  if (!g.code_off) goto nomem;
  if (k > 0) {
    int nchunks = nth < SCATTER_MAX_CHUNKS ? nth : SCATTER_MAX_CHUNKS;
    nbr = karst_i_alloc_large(sizeof(int32_t) * (size_t)n * (size_t)k);
    kidx = malloc(sizeof(int32_t) * (size_t)n);
    kd2 = malloc(sizeof(double) * (size_t)n);
    inside = malloc((size_t)n);
    own = malloc(sizeof(int32_t) * (size_t)n);
    lo = malloc(sizeof(int32_t) * (size_t)n);
    hi = malloc(sizeof(int32_t) * (size_t)n);
    cnt = calloc((size_t)nchunks * (size_t)n, sizeof(int32_t));
    if (!nbr || !kidx || !kd2 || !inside || !own || !lo || !hi || !cnt) goto nomem;
    err = sc->sampling.knn == KARST_KNN_FLANN
              ? karst_i_knn_flann(ctx, samples->xyz, n, k, nth, nbr, kd2, kidx)
              : karst_i_knn(ctx, samples->xyz, n, k, nth, nbr, kd2, kidx);
    if (err != KARST_SUCCESS) goto cleanup;
    build_t B = {ctx, n, k, nchunks, nbr,  kidx,   kd2, cnt,    own, lo,
                 hi,  0, 0, 0,       NULL, inside, &g,  &model, {0}, {0}};
    karst_i_parallel_run(nth, task_count, &B);
    /* Row of v: in(v), then the own arcs not chosen back. Turn the chunk
     * counts into each chunk's first slot within the row. */
    for (karst_int_t v = 0; v < n; v++) {
      int32_t at = 0;
      for (int c = 0; c < nchunks; c++) {
        int32_t x = cnt[(size_t)c * (size_t)n + v];
        cnt[(size_t)c * (size_t)n + v] = at;
        at += x;
      }
      g.offsets[v + 1] = g.offsets[v] + at + own[v];
    }
    g.n_arcs = g.offsets[n];
    /* Room for 1.25 bytes an arc (1.16 on the 1.5 M block); grown when a batch needs more. */
    karst_int_t code_cap = g.n_arcs + g.n_arcs / 4 + 64;
    g.code = karst_i_alloc_large((size_t)code_cap);
    if (!g.code) goto nomem;
    /* The rows are built 32-bit in BUILD_BATCHES batches of about equal arcs (at least
     * karst_i_graph_min_batch_arcs), each coded before the next: the 32-bit rows of a large graph
     * never sit beside the k nearest (docs/performance.md, "Memory at scale"). A batch scans
     * every source, so small graphs take one. */
    karst_int_t batch = g.n_arcs / BUILD_BATCHES;
    if (batch < karst_i_graph_min_batch_arcs) batch = karst_i_graph_min_batch_arcs;
    karst_int_t largest = 0;
    for (karst_int_t v0 = 0, v1; v0 < n; v0 = v1) {
      for (v1 = v0 + 1; v1 < n && g.offsets[v1 + 1] - g.offsets[v0] <= batch; v1++) {
      }
      karst_int_t arcs = g.offsets[v1] - g.offsets[v0];
      if (arcs > largest) {
        free(buf);
        buf = malloc(sizeof(int32_t) * ((size_t)arcs + 1));
        if (!buf) goto nomem;
        largest = arcs;
      }
      B.v0 = v0, B.v1 = v1, B.a0 = g.offsets[v0], B.buf = buf;
      karst_i_parallel_run(nth, task_scatter, &B);
      karst_i_parallel_run(nth, task_merge, &B);
      karst_i_parallel_run(nth, task_count_bytes, &B);
      for (karst_int_t v = v0; v < v1; v++)
        g.code_off[v + 1] += g.code_off[v];
      if (g.code_off[v1] > code_cap) {
        karst_int_t cap = g.code_off[v1] + (g.n_arcs - g.offsets[v1]) * 5 / 4 + 64;
        unsigned char *c = karst_i_realloc_large(g.code, (size_t)g.code_off[v0], (size_t)cap);
        if (!c) goto nomem;
        g.code = c, code_cap = cap;
      }
      karst_i_parallel_run(nth, task_encode, &B);
      for (int t = 0; t < KARST_I_MAX_THREADS; t++)
        if (B.failed[t]) goto nomem;
    }
    free(buf), free(cnt), free(kidx), free(kd2), free(nbr), free(own), free(lo), free(hi);
    buf = NULL, cnt = NULL, kidx = NULL, kd2 = NULL, nbr = NULL, own = NULL, lo = NULL, hi = NULL;
    g.cost = karst_i_alloc_large(sizeof *g.cost * (size_t)g.n_arcs);
    if (!g.cost) goto nomem;
    karst_progress(ctx, "edge costs", 0, 1);
    /* Several chunks per thread balance the costlier regions (near
     * horizons and permeable bodies) between threads. */
    int cth = nth < COST_MAX_THREADS ? nth : COST_MAX_THREADS;
    B.nchunks = cth * COST_CHUNKS_PER_THREAD;
    karst_i_parallel_run(cth, task_cost, &B);
    karst_int_t n_inf = 0;
    for (int t = 0; t < KARST_I_MAX_THREADS; t++) {
      if (B.failed[t] == 1) goto nomem;
      if (B.failed[t] == 2) {
        err = karst_set_error(ctx, KARST_EINTERRUPTED, "edge cost evaluation interrupted");
        goto cleanup;
      }
      n_inf += B.n_infinite[t];
    }
    if (n_inf > 0 && (err = drop_infinite_arcs(ctx, &g, 2 * n_inf)) != KARST_SUCCESS) goto cleanup;
    karst_progress(ctx, "edge costs", 1, 1);
  }
  if (!g.code) { /* no arcs: the rows are still readable */
    g.code = malloc(1);
    if (!g.code) goto nomem;
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
  free(kidx);
  free(kd2);
  free(inside);
  free(cnt);
  free(own);
  free(lo);
  free(hi);
  free(buf);
  return err;
}
