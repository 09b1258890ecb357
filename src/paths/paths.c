/* Least-cost paths on the CSR sample graph (Paris et al. 2021, §4): A*,
 * Dijkstra with several sources and early stop, and the key-point distance
 * matrix of §5.1. */
#include "karst/paths.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "core/memory_internal.h"
#include "core/parallel_internal.h"
#include "graph/graph_internal.h"
#include "paths/paths_internal.h"

/*
 * Per-vertex search state. What every arc relaxation reads (g and whether
 * this search has reached the vertex) is one 16-byte record, so relaxing an
 * arc touches one cache line of the target and the records of a 50 000-vertex
 * graph fit in a core's L2; what only an improving relaxation or a pop needs
 * (heuristic, predecessor, settled stamp) lives in side arrays. Fields other
 * than the stamps are valid only when their stamp == the current generation.
 */
typedef struct {
  double dist;    /* tentative or final distance (g) */
  uint32_t stamp; /* generation in which this record (and h, pred) was written */
  int32_t pos;    /* slot in the heap, -1 when not queued */
} node_t;

/* A heap entry: priority, then vertex index to break ties deterministically. */
typedef struct {
  double key;
  int32_t v;
  int32_t pad;
} heap_entry_t;

/* Heap arity: the 4 children of a slot are 64 contiguous bytes (one cache line, see
 * heap_alloc), and the tree is half as deep as a binary one. */
#define HEAP_D 4

struct karst_search {
  const karst_graph_t *g;
  node_t *node;
  double *h;         /* heuristic of the current search, computed once per vertex and search */
  int32_t *pred;     /* predecessor on the search tree, -1 at a source */
  uint32_t *settled; /* generation in which v was settled (popped with its final key) */
  uint32_t cur;
  void *heap_mem;     /* allocation behind heap */
  heap_entry_t *heap; /* slots 0 .. hn-1; children of i are D i + 1 .. D i + D */
  karst_int_t hn;
  karst_int_t n_settled;
  int32_t *trail; /* vertices touched by the current search (karst_search_record_trail), or NULL */
  karst_int_t n_trail;
};

/* ------------------------------------------------------------------------ */
/* Indexed 4-ary min-heap on (key, vertex) with decrease-key: every vertex  */
/* is queued at most once (node.pos), so the heap never exceeds n entries   */
/* and pops need no stale-entry check. It pops the same (key, vertex)       */
/* sequence as a heap with lazy deletion ordered the same way: that one     */
/* holds, besides the live entry of each queued vertex, only stale entries  */
/* whose key is not below the live one (a vertex is re-pushed only when its */
/* g drops, and adding h is monotone), and those were skipped when popped.  */
/* ------------------------------------------------------------------------ */
static inline int heap_less(const heap_entry_t *a, const heap_entry_t *b) {
  return a->key < b->key || (a->key == b->key && a->v < b->v);
}

static inline void heap_sift_up(karst_search_t *s, karst_int_t i, heap_entry_t e) {
  heap_entry_t *h = s->heap;
  while (i > 0) {
    karst_int_t p = (i - 1) / HEAP_D;
    if (!heap_less(&e, &h[p])) break;
    h[i] = h[p];
    s->node[h[i].v].pos = (int32_t)i;
    i = p;
  }
  h[i] = e;
  s->node[e.v].pos = (int32_t)i;
}

/* Queue v with @p key, or lower its key if it is queued (key never rises: g only drops). */
static inline void heap_update(karst_search_t *s, node_t *nv, double key, karst_int_t v) {
  heap_entry_t e = {key, (int32_t)v, 0};
  karst_int_t i = nv->pos >= 0 ? nv->pos : s->hn++;
  heap_sift_up(s, i, e);
}

static inline heap_entry_t heap_pop(karst_search_t *s) {
  heap_entry_t *h = s->heap;
  heap_entry_t top = h[0];
  s->node[top.v].pos = -1;
  karst_int_t n = --s->hn;
  if (n == 0) return top;
  heap_entry_t last = h[n];
  karst_int_t i = 0;
  for (;;) {
    karst_int_t c = HEAP_D * i + 1;
    if (c >= n) break;
    karst_int_t m = c, end = c + HEAP_D < n ? c + HEAP_D : n;
    for (karst_int_t k = c + 1; k < end; k++)
      if (heap_less(&h[k], &h[m])) m = k;
    if (!heap_less(&h[m], &last)) break;
    h[i] = h[m];
    s->node[h[i].v].pos = (int32_t)i;
    i = m;
  }
  h[i] = last;
  s->node[last.v].pos = (int32_t)i;
  return top;
}

/* Room for n heap entries with slots 1, 5, 9, ... (the first child of each parent) on 64-byte
 * boundaries: entries are 16 bytes, so slot 0 sits 48 bytes into an aligned block. */
static int heap_alloc(karst_search_t *s, size_t n) {
  size_t bytes = ((n + 4) * sizeof(heap_entry_t) + 63) / 64 * 64;
  s->heap_mem = aligned_alloc(64, bytes);
  if (!s->heap_mem) return -1;
  s->heap = (heap_entry_t *)s->heap_mem + 3;
  return 0;
}

/**
 * Create a search workspace for graph @p g (borrowed: it must outlive the
 * workspace). O(n) memory (48 bytes per vertex, 52 with a trail) and time, once; each later
 * search costs what it visits.
 * @return KARST_SUCCESS, KARST_EINVAL, KARST_ENOMEM; KARST_ERANGE for a graph
 *         of 2^31 − 1 vertices or more (vertex indices are stored in 32 bits).
 */
karst_error_t karst_search_create(karst_ctx_t *ctx, const karst_graph_t *g, karst_search_t **out) {
  *out = NULL;
  if (!g || g->n < 0)
    return karst_set_error(ctx, KARST_EINVAL, "search: graph missing or with %lld vertices",
                           g ? (long long)g->n : -1LL);
  if (g->n >= INT32_MAX)
    return karst_set_error(ctx, KARST_ERANGE, "search: %lld vertices exceed 2^31 - 1",
                           (long long)g->n);
  karst_search_t *s = calloc(1, sizeof *s);
  if (!s) return karst_set_error(ctx, KARST_ENOMEM, "search: out of memory");
  size_t n = (size_t)(g->n > 0 ? g->n : 1);
  s->g = g;
  s->node = karst_i_alloc_large(n * sizeof *s->node);
  s->h = karst_i_alloc_large(n * sizeof *s->h);
  s->pred = karst_i_alloc_large(n * sizeof *s->pred);
  s->settled = karst_i_alloc_large(n * sizeof *s->settled);
  if (s->node) memset(s->node, 0, n * sizeof *s->node);
  if (s->settled) memset(s->settled, 0, n * sizeof *s->settled);
  if (!s->node || !s->h || !s->pred || !s->settled || heap_alloc(s, n)) {
    karst_search_free(s);
    return karst_set_error(ctx, KARST_ENOMEM, "search: out of memory for %lld vertices",
                           (long long)g->n);
  }
  *out = s;
  return KARST_SUCCESS;
}

void karst_search_free(karst_search_t *s) {
  if (!s) return;
  free(s->node);
  free(s->h);
  free(s->pred);
  free(s->settled);
  free(s->heap_mem);
  free(s->trail);
  free(s);
}

karst_error_t karst_search_record_trail(karst_ctx_t *ctx, karst_search_t *s) {
  if (s->trail) return KARST_SUCCESS;
  s->trail = karst_i_alloc_large((size_t)(s->g->n > 0 ? s->g->n : 1) * sizeof *s->trail);
  if (!s->trail) return karst_set_error(ctx, KARST_ENOMEM, "search: out of memory for its trail");
  s->n_trail = 0;
  return KARST_SUCCESS;
}

const int32_t *karst_search_trail(const karst_search_t *s, karst_int_t *n) {
  *n = s->trail ? s->n_trail : 0;
  return s->trail;
}

/* Start a new search generation: all distances become "unset" in O(1). */
static void search_begin(karst_search_t *s) {
  s->hn = 0;
  s->n_settled = 0;
  s->n_trail = 0;
  if (++s->cur == 0) { /* wrapped after 2^32 searches: clear the stamps once */
    for (karst_int_t v = 0; v < s->g->n; v++)
      s->node[v].stamp = s->settled[v] = 0;
    s->cur = 1;
  }
}

/* The record of v, reset to "unreached" (g = ∞, not queued) if this search has not written it. */
static inline node_t *touch(karst_search_t *s, karst_int_t v) {
  node_t *nv = &s->node[v];
  if (nv->stamp != s->cur) {
    nv->stamp = s->cur;
    nv->dist = INFINITY;
    nv->pos = -1;
    if (s->trail) s->trail[s->n_trail++] = (int32_t)v;
  }
  return nv;
}

static inline int is_settled(const karst_search_t *s, karst_int_t v) {
  return s->settled[v] == s->cur;
}

double karst_search_dist(const karst_search_t *s, karst_int_t v) {
  if (!s || v < 0 || v >= s->g->n || !is_settled(s, v)) return INFINITY;
  return s->node[v].dist;
}

karst_int_t karst_search_settled(const karst_search_t *s) {
  return s ? s->n_settled : 0;
}

void karst_path_init(karst_path_t *p) {
  memset(p, 0, sizeof *p);
}
void karst_path_destroy(karst_path_t *p) {
  free(p->v);
  memset(p, 0, sizeof *p);
}

/* Make room for @p len vertices in @p path (its storage is reused between calls). */
static karst_error_t path_reserve(karst_ctx_t *ctx, karst_path_t *path, karst_int_t len) {
  if (len <= path->cap) return KARST_SUCCESS;
  karst_int_t *nv = realloc(path->v, (size_t)len * sizeof *nv);
  if (!nv) return karst_set_error(ctx, KARST_ENOMEM, "path: out of memory");
  path->v = nv;
  path->cap = len;
  return KARST_SUCCESS;
}

/**
 * The path from the source of the last search to @p v, following the
 * predecessors. @p v must have been settled by that search.
 * @return KARST_EUNREACHABLE when it was not; KARST_ENOMEM.
 * Time complexity: O(length of the path).
 */
karst_error_t karst_search_path_to(karst_ctx_t *ctx, const karst_search_t *s, karst_int_t v,
                                   karst_path_t *path) {
  if (v < 0 || v >= s->g->n || !is_settled(s, v))
    return karst_set_error(ctx, KARST_EUNREACHABLE, "vertex %lld was not reached by the search",
                           (long long)v);
  karst_int_t len = 0;
  for (karst_int_t u = v; u >= 0; u = s->pred[u])
    len++;
  karst_error_t err = path_reserve(ctx, path, len);
  if (err) return err;
  path->n = len;
  karst_int_t i = len;
  for (karst_int_t u = v; u >= 0; u = s->pred[u])
    path->v[--i] = u;
  path->cost = s->node[v].dist;
  return KARST_SUCCESS;
}

static double euclid(const double *xyz, karst_int_t a, karst_int_t b) {
  double dx = xyz[3 * a] - xyz[3 * b], dy = xyz[3 * a + 1] - xyz[3 * b + 1],
         dz = xyz[3 * a + 2] - xyz[3 * b + 2];
  return sqrt(dx * dx + dy * dy + dz * dz);
}

/* The largest float not above x (x >= 0), so a stored lower bound stays a lower bound. */
static float float_below(double x) {
  float f = (float)x;
  if ((double)f > x) f = nextafterf(f, 0.0f);
  return f;
}

/* The routed cost of arc u → w (karst_route_t) in double precision. */
static inline double route_cost_exact(const karst_route_t *r, double base, karst_int_t u,
                                      karst_int_t w) {
  const float du = r->dz[2 * u], dw = r->dz[2 * w], band = r->band;
  if (dw < -band) {                     /* w in the vadose zone */
    if (!(du < -band)) return INFINITY; /* no rising back into the vadose zone */
  } else if (!(du < -band)) {
    /* Phreatic stage: the mean over the arc of max(0, depth − band), the depth linear in the arc
     * parameter: the mean of the ends when both are below the band, else the triangle of the
     * part below it, hi² / (2 |Δ|). */
    double eu = (double)du - band, ew = (double)dw - band, mean;
    if (eu <= 0 && ew <= 0)
      mean = 0.0;
    else if (eu >= 0 && ew >= 0)
      mean = 0.5 * (eu + ew);
    else {
      double hi = eu > ew ? eu : ew;
      mean = 0.5 * hi * hi / fabs(eu - ew);
    }
    return base * (1.0 + r->inv_phreatic_depth * mean);
  }
  double rise = (double)r->dz[2 * w + 1] - (double)r->dz[2 * u + 1];
  return base * r->vadose_factor + (rise > 0 ? r->rise_cost * rise : 0.0);
}

/* The routed cost of arc u → w rounded to single precision like the stored costs (graph.h), so
 * that the tables (karst_route_tabulate) and the formula evaluated during a search agree. */
static inline double route_cost(const karst_route_t *r, double base, karst_int_t u, karst_int_t w) {
  return (double)karst_arc_cost_round(route_cost_exact(r, base, u, w));
}

double karst_route_arc_cost(const karst_route_t *r, double base, karst_int_t u, karst_int_t w) {
  return r ? route_cost(r, base, u, w) : base;
}

typedef struct {
  const karst_graph_t *g;
  const karst_route_t *r;
  karst_arc_cost_t *fwd, *bwd;
} tabulate_t;

static void tabulate_worker(void *arg, int tid, int nthreads) {
  const tabulate_t *t = arg;
  const karst_graph_t *g = t->g;
  const karst_int_t lo = g->n * tid / nthreads, hi = g->n * (tid + 1) / nthreads;
  for (karst_int_t v = lo; v < hi; v++) {
    KARST_I_ARCS_BEGIN(g, v, a, w)
      t->fwd[a] = (karst_arc_cost_t)route_cost(t->r, g->cost[a], v, w);
      t->bwd[a] = (karst_arc_cost_t)route_cost(t->r, g->cost[a], w, v);
    KARST_I_ARCS_END
  }
}

void karst_route_tabulate(const karst_ctx_t *ctx, const karst_graph_t *g, const karst_route_t *r,
                          karst_arc_cost_t *fwd, karst_arc_cost_t *bwd) {
  tabulate_t t = {g, r, fwd, bwd};
  int T = ctx && ctx->nthreads > 1 ? ctx->nthreads : 1;
  if (g->n_arcs < 100000) T = 1; /* not worth a thread */
  karst_i_parallel_run(T, tabulate_worker, &t);
}

/* What a search run needs besides its sources (run_search). */
typedef struct {
  karst_int_t target;             /* A* target, or -1 */
  double lb;                      /* A* bound per metre, 0: Dijkstra */
  const unsigned char *blocked;   /* may not be entered */
  const unsigned char *noexpand;  /* may be settled but not expanded (unless it is the start) */
  const unsigned char *is_target; /* counted targets */
  karst_int_t stop_after;         /* stop once this many targets are settled (<= 0: never) */
  karst_int_t *last_target;
  int want_pred;
  int backward;               /* relax arcs w → v (least cost TO the sources) */
  const karst_route_t *route; /* routed costs, or NULL */
  int (*check)(void *arg);    /* polled every 256 settled vertices: non-zero stops, or NULL */
  void *check_arg;
} search_opts_t;

/*
 * The one search loop behind A* and Dijkstra. Priority = g(v) + h(v) with
 * h(v) = lb · |v − target| (A*; h = 0 when target < 0 or lb = 0), computed
 * once per vertex and search. Vertices are never closed for good: a shorter g
 * found later re-opens them, so the result stays exact even if rounding made h
 * inconsistent by an ulp (with a consistent h, as ours is in exact
 * arithmetic, nothing is ever re-opened). Stops when @p target is settled, or
 * when @p stop_after vertices marked in @p is_target are settled.
 */
/* Ask for the arc list of u (probably the next vertex popped: the heap's top before v's arcs
 * are relaxed) while v's arcs are relaxed. Always inlined: as a function of its own, GCC 12 finds
 * it "looping pure" (a prefetch has no side effect), and drops every call to it. */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline void
prefetch_arcs(const karst_graph_t *g, const karst_arc_cost_t *cost, karst_int_t u) {
  const karst_int_t *off = g->offsets;
  const char *pa = (const char *)(g->code + g->code_off[u]), *pc = (const char *)(cost + off[u]);
  size_t deg = (size_t)(off[u + 1] - off[u]), bytes = (size_t)(g->code_off[u + 1] - g->code_off[u]);
  for (size_t b = 0; b < bytes; b += 64)
    __builtin_prefetch(pa + b);
  for (size_t b = 0; b < deg * sizeof *cost; b += 64)
    __builtin_prefetch(pc + b);
}

/* The loop of run_search for one combination of its per-arc options (a routed cost formula, a
 * blocked mask), given as constants so that each instance tests neither per arc: about 5
 * instructions of the 23 an arc relaxation costs in the routing rows (callgrind). */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline karst_error_t
run_search_loop(karst_ctx_t *ctx, karst_search_t *s, karst_int_t n_sources,
                const karst_int_t *sources, const search_opts_t *o, const int with_route,
                const int with_blocked, const int with_check) {
  const karst_graph_t *g = s->g;
  const karst_int_t target = o->target;
  const double lb = o->lb;
  const int astar = target >= 0 && lb > 0 && g->xyz;
  const karst_arc_cost_t *restrict cost = g->cost;
  const unsigned char *blocked = o->blocked, *noexpand = o->noexpand, *is_target = o->is_target;
  const karst_route_t *route = o->route;
  const int backward = o->backward, want_pred = o->want_pred;
  /* Tabulated routed costs replace the base costs and the formula (karst_route_tabulate). */
  const karst_arc_cost_t *restrict tab =
      route ? (backward ? route->arc_bwd : route->arc_fwd) : NULL;
  const karst_arc_cost_t *restrict arc_cost = tab ? tab : cost;
  node_t *restrict node = s->node;
  double *restrict hh = s->h;
  int32_t *restrict pred = s->pred;
  uint32_t *restrict settled = s->settled;
  karst_int_t found = 0;
  if (o->last_target) *o->last_target = -1;
  search_begin(s);
  for (karst_int_t i = 0; i < n_sources; i++) {
    karst_int_t v = sources[i];
    if (v < 0 || v >= g->n)
      return karst_set_error(ctx, KARST_EINVAL, "search: source %lld is not a vertex (n = %lld)",
                             (long long)v, (long long)g->n);
    if (node[v].stamp == s->cur) continue;
    node_t *nv = touch(s, v);
    nv->dist = 0.0;
    pred[v] = -1;
    hh[v] = astar ? lb * euclid(g->xyz, v, target) : 0.0;
    heap_update(s, nv, hh[v], v);
  }
  while (s->hn > 0) {
    karst_int_t v = heap_pop(s).v;
    const double gv = node[v].dist;
    if (settled[v] != s->cur) {
      settled[v] = s->cur;
      if ((++s->n_settled & 255) == 0 && with_check && o->check(o->check_arg))
        return karst_set_error(ctx, KARST_EINTERRUPTED, "search stopped by its caller");
    }
    if (v == target) {
      if (o->last_target) *o->last_target = v;
      break;
    }
    if (is_target && is_target[v]) {
      if (o->last_target) *o->last_target = v;
      if (o->stop_after > 0 && ++found >= o->stop_after) break;
    }
    if (noexpand && noexpand[v] && gv > 0.0) continue; /* a start (cost 0) is expanded */
    if (s->hn > 0) prefetch_arcs(g, arc_cost, s->heap[0].v);
    KARST_I_ARCS_BEGIN(g, v, a, w)
      double c = arc_cost[a];
      if (!(c < INFINITY) || (with_blocked && blocked[w])) continue;
      if (with_route) c = backward ? route_cost(route, c, w, v) : route_cost(route, c, v, w);
      double nd = gv + c;
      node_t *nw = &node[w];
      if (nw->stamp != s->cur) { /* first reached: g was ∞ */
        if (!(nd < INFINITY)) continue;
        nw->stamp = s->cur;
        nw->pos = -1;
        if (s->trail) s->trail[s->n_trail++] = (int32_t)w;
        if (astar) hh[w] = lb * euclid(g->xyz, w, target);
      } else if (!(nd < nw->dist)) {
        continue;
      }
      nw->dist = nd;
      if (want_pred) pred[w] = (int32_t)v;
      heap_update(s, nw, astar ? nd + hh[w] : nd, w);
    KARST_I_ARCS_END
  }
  return KARST_SUCCESS;
}

static karst_error_t run_search(karst_ctx_t *ctx, karst_search_t *s, karst_int_t n_sources,
                                const karst_int_t *sources, const search_opts_t *o) {
  /* Tabulated routed costs replace the formula (see run_search_loop). */
  const int with_route = o->route && !(o->backward ? o->route->arc_bwd : o->route->arc_fwd);
  if (o->check) /* the amplification's speculative searches (karst_i_paths_dijkstra_checked) */
    return with_route ? run_search_loop(ctx, s, n_sources, sources, o, 1, o->blocked != NULL, 1)
                      : run_search_loop(ctx, s, n_sources, sources, o, 0, o->blocked != NULL, 1);
  if (o->blocked)
    return with_route ? run_search_loop(ctx, s, n_sources, sources, o, 1, 1, 0)
                      : run_search_loop(ctx, s, n_sources, sources, o, 0, 1, 0);
  return with_route ? run_search_loop(ctx, s, n_sources, sources, o, 1, 0, 0)
                    : run_search_loop(ctx, s, n_sources, sources, o, 0, 0, 0);
}

/**
 * Least-cost path from @p source to @p target with A* (Hart, Nilsson &
 * Raphael 1968) on the sample graph of Paris et al. 2021, §4.
 *
 * Heuristic h(v) = lb_per_metre · |v − target|. It never overestimates: every
 * arc cost is the line integral of c(p, d) along the straight segment u→w, and
 * c ≥ lb everywhere, so cost(u, w) ≥ lb·|u − w|; summing over any path from v
 * to the target and using the triangle inequality, its cost is ≥ lb·|v − t|.
 * The same inequality with |u − t| ≤ |u − w| + |w − t| shows h is consistent
 * (h(u) ≤ cost(u, w) + h(w)), so each vertex is expanded once.
 * Pass lb_per_metre = 0 to get plain Dijkstra.
 *
 * @param ctx          error messages.
 * @param s            workspace created on the graph.
 * @param source       start vertex.
 * @param target       end vertex.
 * @param lb_per_metre a lower bound of the cost per metre (karst_cost_lower_bound_per_metre), >= 0.
 * @param path         receives the vertices source..target and the cost.
 * @return KARST_SUCCESS; KARST_EUNREACHABLE when no finite-cost path exists
 *         (message names both vertices); KARST_EINVAL for bad indices or bound.
 * Time complexity: O((m + n) log n) in the worst case, usually far less.
 */
karst_error_t karst_paths_astar(karst_ctx_t *ctx, karst_search_t *s, karst_int_t source,
                                karst_int_t target, double lb_per_metre, karst_path_t *path) {
  const karst_graph_t *g = s->g;
  if (source < 0 || source >= g->n || target < 0 || target >= g->n)
    return karst_set_error(ctx, KARST_EINVAL, "A*: vertices %lld -> %lld outside [0, %lld)",
                           (long long)source, (long long)target, (long long)g->n);
  if (!(lb_per_metre >= 0) || isinf(lb_per_metre))
    return karst_set_error(ctx, KARST_EINVAL,
                           "A*: the cost lower bound per metre must be finite and >= 0, got %g",
                           lb_per_metre);
  const search_opts_t o = {target, lb_per_metre, NULL, NULL, NULL, 0, NULL, 1, 0, NULL, NULL, NULL};
  karst_error_t err = run_search(ctx, s, 1, &source, &o);
  if (err) return err;
  if (!is_settled(s, target))
    return karst_set_error(ctx, KARST_EUNREACHABLE,
                           "no finite-cost path from vertex %lld to vertex %lld", (long long)source,
                           (long long)target);
  return karst_search_path_to(ctx, s, target, path);
}

/**
 * Dijkstra (1959) from several sources at distance 0 (a "super-source"), so
 * that each settled vertex gets its least cost to the nearest source.
 *
 * @param n_sources, sources  start vertices (at least one).
 * @param blocked     vertices the search may not enter (NULL: none); sources are never blocked.
 * @param is_target   vertices counted as targets (NULL: none).
 * @param stop_after  stop once this many targets are settled (<= 0: run to exhaustion).
 * @param last_target receives the last target settled, -1 if none (may be NULL).
 * Distances and paths are then read with karst_search_dist / karst_search_path_to.
 * @return KARST_SUCCESS (even when targets were not reached: check last_target), KARST_EINVAL,
 *         KARST_ENOMEM.
 * Time complexity: O((m + n) log n) for what is visited.
 */
karst_error_t karst_paths_dijkstra(karst_ctx_t *ctx, karst_search_t *s, karst_int_t n_sources,
                                   const karst_int_t *sources, const unsigned char *blocked,
                                   const unsigned char *is_target, karst_int_t stop_after,
                                   karst_int_t *last_target) {
  return karst_paths_dijkstra_routed(ctx, s, NULL, n_sources, sources, blocked, is_target,
                                     stop_after, last_target);
}

/** karst_paths_dijkstra on the routed costs of @p route (karst_route_t). Same complexity. */
karst_error_t karst_paths_dijkstra_routed(karst_ctx_t *ctx, karst_search_t *s,
                                          const karst_route_t *route, karst_int_t n_sources,
                                          const karst_int_t *sources, const unsigned char *blocked,
                                          const unsigned char *is_target, karst_int_t stop_after,
                                          karst_int_t *last_target) {
  if (n_sources < 1 || !sources)
    return karst_set_error(ctx, KARST_EINVAL, "Dijkstra: no source given");
  const search_opts_t o = {-1,          0.0, blocked, NULL,  is_target, stop_after,
                           last_target, 1,   0,       route, NULL,      NULL};
  return run_search(ctx, s, n_sources, sources, &o);
}

/* karst_paths_dijkstra_routed that polls @p check(@p arg) every 256 settled vertices and stops
 * with KARST_EINTERRUPTED when it returns non-zero (paths_internal.h). */
karst_error_t karst_i_paths_dijkstra_checked(
    karst_ctx_t *ctx, karst_search_t *s, const karst_route_t *route, karst_int_t n_sources,
    const karst_int_t *sources, const unsigned char *blocked, const unsigned char *is_target,
    karst_int_t stop_after, karst_int_t *last_target, int (*check)(void *), void *arg) {
  if (n_sources < 1 || !sources)
    return karst_set_error(ctx, KARST_EINVAL, "Dijkstra: no source given");
  const search_opts_t o = {-1,          0.0, blocked, NULL,  is_target, stop_after,
                           last_target, 1,   0,       route, check,     arg};
  return run_search(ctx, s, n_sources, sources, &o);
}

/* ------------------------------------------------------------------------ */
/* Path sharing: least-cost paths on the graph whose network arcs are        */
/* discounted (Galin et al. 2011, used by Paris et al. 2021, §5.1).          */
/* ------------------------------------------------------------------------ */

/*
 * The heuristic of karst_paths_astar_reuse at v (see there for the proof):
 * max(r·lb·|v − t|, r·D(v) + (1 − r)·min(N(v), D(v))), shrunk by
 * KARST_PATHS_HEURISTIC_MARGIN against rounding.
 */
static double reuse_h(const karst_graph_t *g, karst_int_t v, karst_int_t target, double rlb,
                      const float *bound, const karst_reuse_t *ru) {
  double h = rlb > 0 ? rlb * euclid(g->xyz, v, target) : 0.0;
  if (bound) {
    double D = bound[v], N = ru->dist_to_net ? ru->dist_to_net[v] : 0.0;
    double hb = ru->factor * D + (1.0 - ru->factor) * (N < D ? N : D);
    if (hb > h) h = hb;
  }
  return h * (1.0 - KARST_PATHS_HEURISTIC_MARGIN);
}

/**
 * Least-cost path from @p source to @p target on the graph in which the arcs
 * flagged in reuse->reused (the network laid so far) cost reuse->factor = r
 * times their cost: the path-sharing search of Galin et al. 2011 ("Authoring
 * hierarchical road networks", on which Paris et al. 2021 §5.1 build), where
 * a new path prefers to run along conduits already there.
 *
 * A* with h(v) = max(h_E(v), h_N(v)), where, with c the original arc costs and
 * c' the discounted ones (c' = r c on network arcs, c elsewhere):
 * - h_E(v) = r·lb·|v − t|: c' >= r c >= r·lb·length on every arc, so any path
 *   from v costs >= r·lb·|v − t| (triangle inequality); the same argument on
 *   one arc gives consistency. This is the plain A* bound times r.
 * - h_N(v) = r·D(v) + (1 − r)·min(N(v), D(v)), where D (@p target_bound) is a
 *   lower bound of the original least cost from v to t that changes by at most
 *   c(u, w) along an arc (karst_paths_keypoint_bounds gives one; the exact
 *   distance is one), and N (reuse->dist_to_net) the original least cost from
 *   v to the nearest network vertex (karst_paths_lower_distances), or that
 *   cost capped at a constant M, min(N, M), which is below it and, like it,
 *   changes by at most c along an arc (the skeleton keeps N capped so that a
 *   new path lowers it only nearby).
 *   Admissible: a path P from v to t of original cost C >= d(v, t) >= D(v), of
 *   which Y is spent on non-network arcs, costs C' = r C + (1 − r) Y. If P uses
 *   no network arc, Y = C >= D(v); otherwise the part of P before its first
 *   network arc ends at a network vertex, so Y >= N(v). Hence
 *   C' >= r D(v) + (1 − r) min(N(v), D(v)).
 *   Consistent: on a network arc both ends are network vertices (N = 0), so
 *   h_N changes by r |ΔD| <= r c = c'; on any other arc D and N (a least-cost
 *   distance to a set, capped or not) change by at most c, so h_N changes by
 *   at most r c + (1 − r) c = c = c'.
 *   Why it pays: far from the network it is the exact remaining cost times
 *   r plus (1 − r) times the cost of reaching the network, so the search stays
 *   within a thin shell around the network and the straight corridor, where
 *   h_E alone (a few tenths of the typical cost per metre once multiplied by
 *   r) lets it flood a ball of radius d(source, target).
 * The maximum of two consistent heuristics is consistent. Both are shrunk by
 * the relative KARST_PATHS_HEURISTIC_MARGIN so that rounding cannot make them
 * overestimate; the search also re-opens vertices, so it stays exact anyway.
 *
 * @param s             workspace created on the graph.
 * @param source, target vertices.
 * @param lb_per_metre  lower bound of the original cost per metre (>= 0).
 * @param target_bound  n lower bounds of the original cost to @p target as
 *                      above, or NULL (then only h_E is used).
 * @param reuse         the discount: factor in (0, 1], reused = n_arcs flags
 *                      set on both arcs of every network edge (NULL: no arc is
 *                      discounted), dist_to_net = n distances (NULL: 0 everywhere,
 *                      which is always safe: h_N = r·D).
 * @param path          receives source .. target; path->cost is the discounted cost.
 * @return KARST_SUCCESS; KARST_EUNREACHABLE; KARST_EINVAL for bad indices,
 *         bound or factor; KARST_ENOMEM; KARST_EINTERRUPTED when reuse->cancelled said so.
 * Time complexity: O((m + n) log n) in the worst case; in practice the shell
 * described above.
 */
karst_error_t karst_paths_astar_reuse(karst_ctx_t *ctx, karst_search_t *s, karst_int_t source,
                                      karst_int_t target, double lb_per_metre,
                                      const float *target_bound, const karst_reuse_t *reuse,
                                      karst_path_t *path) {
  const karst_graph_t *g = s->g;
  if (source < 0 || source >= g->n || target < 0 || target >= g->n)
    return karst_set_error(ctx, KARST_EINVAL, "A*: vertices %lld -> %lld outside [0, %lld)",
                           (long long)source, (long long)target, (long long)g->n);
  if (!(lb_per_metre >= 0) || isinf(lb_per_metre))
    return karst_set_error(ctx, KARST_EINVAL,
                           "A*: the cost lower bound per metre must be finite and >= 0, got %g",
                           lb_per_metre);
  if (!reuse || !(reuse->factor > 0 && reuse->factor <= 1))
    return karst_set_error(ctx, KARST_EINVAL, "A*: the reuse factor must be within (0, 1], got %g",
                           reuse ? reuse->factor : NAN);
  const double r = reuse->factor, rlb = g->xyz ? r * lb_per_metre : 0.0;
  const unsigned char *flag = reuse->reused, *closed = reuse->closed, tag = reuse->tag;
  /* A tagged arc joins two network vertices, whose network distance is 0 (a lower bound of 0):
   * the tags of a vertex's arcs are read only when that distance is not positive, so a search
   * reads the tags (one byte per arc, not backed by large pages) only along the network. */
  const double *dn = reuse->dist_to_net;
  const karst_route_t *route = reuse->route;
  /* Tabulated routed costs replace the base costs and the formula (karst_route_tabulate). */
  const karst_arc_cost_t *restrict cost = route && route->arc_fwd ? route->arc_fwd : g->cost;
  if (route && route->arc_fwd) route = NULL;
  node_t *restrict node = s->node;
  double *restrict hh = s->h;
  int32_t *restrict pred = s->pred;
  uint32_t *restrict settled = s->settled;
  int32_t *trail = s->trail;
  search_begin(s);
  node_t *ns = touch(s, source);
  ns->dist = 0.0;
  pred[source] = -1;
  hh[source] = reuse_h(g, source, target, rlb, target_bound, reuse);
  heap_update(s, ns, hh[source], source);
  while (s->hn > 0) {
    karst_int_t v = heap_pop(s).v;
    const double gv = node[v].dist;
    if (settled[v] != s->cur) {
      settled[v] = s->cur;
      if ((++s->n_settled & 255) == 0 && reuse->cancelled && reuse->cancelled(reuse->cancel_arg))
        return karst_set_error(ctx, KARST_EINTERRUPTED, "A*: search from vertex %lld cancelled",
                               (long long)source);
    }
    if (v == target) break;
    if (s->hn > 0) prefetch_arcs(g, cost, s->heap[0].v);
    const unsigned char *vflag = flag && !(dn && dn[v] > 0.0) ? flag : NULL;
    KARST_I_ARCS_BEGIN(g, v, a, w)
      double c = cost[a];
      if (!(c < INFINITY) || (closed && closed[w] && w != target)) continue;
      if (route) c = route_cost(route, c, v, w);
      if (vflag && vflag[a] && (!tag || vflag[a] == tag)) c *= r;
      double nd = gv + c;
      node_t *nw = &node[w];
      if (nw->stamp != s->cur) { /* first reached: g was ∞ */
        if (!(nd < INFINITY)) continue;
        nw->stamp = s->cur;
        nw->pos = -1;
        if (trail) trail[s->n_trail++] = (int32_t)w;
        hh[w] = reuse_h(g, w, target, rlb, target_bound, reuse);
      } else if (!(nd < nw->dist)) {
        continue;
      }
      nw->dist = nd;
      pred[w] = (int32_t)v;
      heap_update(s, nw, nd + hh[w], w);
    KARST_I_ARCS_END
  }
  if (!is_settled(s, target))
    return karst_set_error(ctx, KARST_EUNREACHABLE,
                           "no finite-cost path from vertex %lld to vertex %lld", (long long)source,
                           (long long)target);
  return karst_search_path_to(ctx, s, target, path);
}

/**
 * Lower @p dist (n values, the least cost from every vertex to a growing set
 * of vertices, INFINITY for the empty set) after @p sources joined the set:
 * a Dijkstra from the new sources at 0 that only goes where it improves the
 * stored value, so adding a path to the network costs the region whose
 * nearest network vertex changes, not a search of the whole graph. The
 * result equals a multi-source Dijkstra from the whole set.
 *
 * @param s         workspace on the graph (its heap is used; the last search is forgotten).
 * @param n_sources, sources  the new members (indices are checked).
 * @param dist      n values, updated in place.
 * @return KARST_SUCCESS, KARST_EINVAL, KARST_ENOMEM.
 * Time complexity: O((m' + n') log n') for the n' vertices whose value drops.
 */
karst_error_t karst_paths_lower_distances(karst_ctx_t *ctx, karst_search_t *s,
                                          karst_int_t n_sources, const karst_int_t *sources,
                                          double *dist) {
  const karst_graph_t *g = s->g;
  search_begin(s);
  for (karst_int_t i = 0; i < n_sources; i++) {
    karst_int_t v = sources[i];
    if (v < 0 || v >= g->n)
      return karst_set_error(ctx, KARST_EINVAL, "search: source %lld is not a vertex (n = %lld)",
                             (long long)v, (long long)g->n);
    if (dist[v] > 0.0) {
      dist[v] = 0.0;
      heap_update(s, touch(s, v), 0.0, v);
    }
  }
  while (s->hn > 0) {
    heap_entry_t e = heap_pop(s);
    if (s->hn > 0) prefetch_arcs(g, g->cost, s->heap[0].v);
    KARST_I_ARCS_BEGIN(g, e.v, a, w)
      double nd = e.key + g->cost[a];
      if (nd < dist[w]) {
        dist[w] = nd;
        heap_update(s, touch(s, w), nd, w);
      }
    KARST_I_ARCS_END
  }
  return KARST_SUCCESS;
}

/* ------------------------------------------------------------------------ */
/* Key-point distance matrix, one row per task, rows spread over threads.   */
/* ------------------------------------------------------------------------ */
typedef struct {
  karst_ctx_t ctx; /* private context: errors are copied back by the caller */
  const karst_graph_t *g;
  karst_int_t n_keys;
  const karst_int_t *keys;
  double lb;
  karst_paths_method_t method;
  double *dist;
  int32_t *pred; /* (n_keys − 1) × n trees, or NULL */
  float *bound;  /* (n_keys − 1) × n lower bounds of the distance to key i, or NULL */
  int thread, nthreads;
  volatile int *interrupt;
  karst_error_t err;
} rows_task_t;

static void *rows_worker(void *arg) {
  rows_task_t *t = arg;
  karst_search_t *s = NULL;
  unsigned char *mask = NULL;
  karst_path_t path;
  karst_path_init(&path);
  t->err = karst_search_create(&t->ctx, t->g, &s);
  if (t->err) goto cleanup;
  if (t->method == KARST_PATHS_DIJKSTRA_MULTI) {
    mask = karst_i_calloc_large((size_t)(t->g->n > 0 ? t->g->n : 1), 1);
    if (!mask) {
      t->err = karst_set_error(&t->ctx, KARST_ENOMEM, "key-point distances: out of memory");
      goto cleanup;
    }
  }
  /* Row i holds the distances to keys j > i; the last row has nothing to do. */
  for (karst_int_t i = t->thread; i < t->n_keys - 1; i += t->nthreads) {
    if (t->interrupt && *t->interrupt) {
      t->err = karst_set_error(&t->ctx, KARST_EINTERRUPTED, "key-point distances interrupted");
      goto cleanup;
    }
    karst_int_t ki = t->keys[i];
    if (t->method == KARST_PATHS_DIJKSTRA_MULTI) {
      karst_int_t want = 0;
      for (karst_int_t j = i + 1; j < t->n_keys; j++)
        if (!mask[t->keys[j]]) mask[t->keys[j]] = 1, want++;
      /* The bound rows need no predecessors. */
      const search_opts_t o = {-1, 0.0,  NULL, NULL, mask, want, NULL, t->pred != NULL,
                               0,  NULL, NULL, NULL};
      t->err = run_search(&t->ctx, s, 1, &ki, &o);
      for (karst_int_t j = i + 1; j < t->n_keys; j++)
        mask[t->keys[j]] = 0;
      if (t->err) goto cleanup;
      for (karst_int_t j = i + 1; j < t->n_keys; j++)
        t->dist[i * t->n_keys + j] = karst_search_dist(s, t->keys[j]);
      if (t->pred) {
        int32_t *row = t->pred + (size_t)i * (size_t)t->g->n;
        for (karst_int_t v = 0; v < t->g->n; v++)
          row[v] = is_settled(s, v) ? s->pred[v] : -2;
      }
      if (t->bound) {
        /* Dijkstra settles in nondecreasing distance, so a vertex it did not settle is at
         * least as far as the farthest settled one (R): min(d, R) bounds d from below and,
         * like d, changes by at most the arc cost along an arc. */
        float *row = t->bound + (size_t)i * (size_t)t->g->n;
        double R = 0.0;
        for (karst_int_t v = 0; v < t->g->n; v++)
          if (is_settled(s, v) && s->node[v].dist > R) R = s->node[v].dist;
        for (karst_int_t v = 0; v < t->g->n; v++)
          row[v] = float_below(is_settled(s, v) ? s->node[v].dist : R);
      }
    } else {
      for (karst_int_t j = i + 1; j < t->n_keys; j++) {
        karst_error_t e = karst_paths_astar(&t->ctx, s, ki, t->keys[j], t->lb, &path);
        if (e == KARST_EUNREACHABLE) {
          t->dist[i * t->n_keys + j] = INFINITY;
          continue;
        }
        if (e) {
          t->err = e;
          goto cleanup;
        }
        t->dist[i * t->n_keys + j] = path.cost;
      }
    }
  }
cleanup:
  karst_path_destroy(&path);
  free(mask);
  karst_search_free(s);
  return NULL;
}

static karst_error_t keypoint_rows(karst_ctx_t *ctx, const karst_graph_t *g, karst_int_t n_keys,
                                   const karst_int_t *keys, double lb_per_metre,
                                   karst_paths_method_t method, double *dist, int32_t *pred,
                                   float *bound);

/**
 * Least-cost distances between all pairs of key points (the complete graph
 * of Paris et al. 2021, §5.1, before γ pruning).
 *
 * Which method is faster: one multi-target Dijkstra per key point. Measured by
 * bench/bench_generate (47 key points on a 72 000-vertex, 1.77 M-arc graph,
 * costs 1–2 × length, 1 thread, shared 2-core machine): Dijkstra rows 2.7 s,
 * A* pairs 7.8 s (2.8 × slower); on 300 000 vertices 9.6 s against 52 s. Why:
 * with k key points, A* runs k(k−1)/2 searches, and each one to a distant key
 * point still settles an ellipsoid-shaped region that the cost heuristic
 * (which only knows the minimum cost per metre, often far below the typical
 * cost per metre) barely narrows; a Dijkstra from key point i settles one
 * ball reaching the farthest key point j > i once and serves all k−1−i
 * targets. Rows are independent, so they are spread over ctx->nthreads
 * threads (row i to thread i mod T); the matrix does not depend on T.
 *
 * @param g            the sample graph.
 * @param n_keys, keys key points as vertex indices (need not be distinct).
 * @param lb_per_metre lower bound of the cost per metre (A* heuristic; ignored by Dijkstra).
 * @param method       KARST_PATHS_DIJKSTRA_MULTI (default) or KARST_PATHS_ASTAR_PAIRS.
 * @param dist         n_keys × n_keys row-major output, symmetric, 0 on the
 *                     diagonal, INFINITY where no finite-cost path exists.
 * @return KARST_SUCCESS, KARST_EINVAL, KARST_ENOMEM, KARST_EINTERRUPTED.
 * Time complexity: O(k (m + n) log n) with Dijkstra rows.
 */
karst_error_t karst_paths_keypoint_distances(karst_ctx_t *ctx, const karst_graph_t *g,
                                             karst_int_t n_keys, const karst_int_t *keys,
                                             double lb_per_metre, karst_paths_method_t method,
                                             double *dist) {
  return keypoint_rows(ctx, g, n_keys, keys, lb_per_metre, method, dist, NULL, NULL);
}

/**
 * The key-point distance matrix (as karst_paths_keypoint_distances with
 * Dijkstra rows) together with the shortest-path tree of each row, so the
 * skeleton can read the path of every kept pair without searching again
 * (one search per key point in all, instead of one more A* per kept pair —
 * with γ ≤ 1 every pair is kept: 1081 searches for 47 key points).
 *
 * @param dist  n_keys × n_keys output as in karst_paths_keypoint_distances.
 * @param pred  (n_keys − 1) × n output: row i holds, for each vertex settled by
 *              the search from key i, its predecessor (−1 at key i), and −2 for
 *              vertices that search did not settle. Read paths with
 *              karst_paths_tree_path. The graph must have fewer than 2^31 vertices.
 * @return as karst_paths_keypoint_distances; KARST_ERANGE for too large a graph.
 * Time complexity: O(k (m + n) log n); memory 4 (k − 1) n bytes.
 */
karst_error_t karst_paths_keypoint_trees(karst_ctx_t *ctx, const karst_graph_t *g,
                                         karst_int_t n_keys, const karst_int_t *keys, double *dist,
                                         int32_t *pred) {
  if (g->n >= INT32_MAX)
    return karst_set_error(ctx, KARST_ERANGE, "key-point trees: %lld vertices exceed 2^31 - 1",
                           (long long)g->n);
  return keypoint_rows(ctx, g, n_keys, keys, 0.0, KARST_PATHS_DIJKSTRA_MULTI, dist, pred, NULL);
}

/**
 * The key-point distance matrix (Dijkstra rows, as karst_paths_keypoint_trees)
 * together with, for each row i < n_keys − 1, a lower bound of the least cost
 * from every vertex to key i: the exact distance where the row's search
 * settled the vertex, else the farthest settled distance R_i (Dijkstra settles
 * in nondecreasing order, so every other vertex is at least R_i away, and
 * R_i >= d(i, j) for every key j > i). Values are rounded down to float.
 * These rows are the A* heuristic of karst_paths_astar_reuse for a pair (a, b),
 * a < b, searched from b towards a: a bound that knows the geology between the
 * two key points, not only the minimum cost per metre.
 *
 * @param dist   n_keys × n_keys output as in karst_paths_keypoint_distances.
 * @param bound  (n_keys − 1) × n output, row i for key i.
 * @return as karst_paths_keypoint_distances.
 * Time complexity: O(k (m + n) log n); memory 4 (k − 1) n bytes.
 */
karst_error_t karst_paths_keypoint_bounds(karst_ctx_t *ctx, const karst_graph_t *g,
                                          karst_int_t n_keys, const karst_int_t *keys, double *dist,
                                          float *bound) {
  return keypoint_rows(ctx, g, n_keys, keys, 0.0, KARST_PATHS_DIJKSTRA_MULTI, dist, NULL, bound);
}

/**
 * The path from @p source to @p target in a shortest-path tree written by
 * karst_paths_keypoint_trees (the row of @p source).
 * @return KARST_EUNREACHABLE when @p target was not settled in that tree.
 * Time complexity: O(path length).
 */
karst_error_t karst_paths_tree_path(karst_ctx_t *ctx, const karst_graph_t *g,
                                    const int32_t *pred_row, karst_int_t source, karst_int_t target,
                                    karst_path_t *path) {
  if (target < 0 || target >= g->n || pred_row[target] == -2)
    return karst_set_error(ctx, KARST_EUNREACHABLE,
                           "no finite-cost path from vertex %lld to vertex %lld", (long long)source,
                           (long long)target);
  karst_int_t len = 0;
  for (karst_int_t u = target; u >= 0; u = pred_row[u]) {
    if (++len > g->n)
      return karst_set_error(ctx, KARST_EINVAL, "key-point tree of vertex %lld has a cycle",
                             (long long)source);
  }
  karst_error_t err = path_reserve(ctx, path, len);
  if (err) return err;
  path->n = len;
  karst_int_t i = len;
  double cost = 0;
  for (karst_int_t u = target; u >= 0; u = pred_row[u]) {
    path->v[--i] = u;
    karst_int_t p = pred_row[u];
    if (p >= 0) {
      double best = INFINITY;
      karst_arc_reader_t rd = karst_graph_arcs(g, p);
      for (karst_int_t a = g->offsets[p]; a < g->offsets[p + 1]; a++)
        if (karst_arc_next(&rd) == u && g->cost[a] < best) best = g->cost[a];
      cost += best;
    }
  }
  if (path->v[0] != source)
    return karst_set_error(ctx, KARST_EINVAL, "tree row does not start at vertex %lld",
                           (long long)source);
  path->cost = cost;
  return KARST_SUCCESS;
}

static karst_error_t keypoint_rows(karst_ctx_t *ctx, const karst_graph_t *g, karst_int_t n_keys,
                                   const karst_int_t *keys, double lb_per_metre,
                                   karst_paths_method_t method, double *dist, int32_t *pred,
                                   float *bound) {
  karst_error_t err = KARST_SUCCESS;
  rows_task_t *tasks = NULL;
  pthread_t *threads = NULL;
  int started = 0;
  if (n_keys < 0 || (n_keys > 0 && (!keys || !dist)))
    return karst_set_error(ctx, KARST_EINVAL, "key-point distances: %lld key points",
                           (long long)n_keys);
  for (karst_int_t i = 0; i < n_keys; i++)
    if (keys[i] < 0 || keys[i] >= g->n)
      return karst_set_error(
          ctx, KARST_EINVAL,
          "key-point distances: key point %lld is vertex %lld, outside [0, %lld)", (long long)i,
          (long long)keys[i], (long long)g->n);
  for (karst_int_t i = 0; i < n_keys * n_keys; i++)
    dist[i] = INFINITY;
  for (karst_int_t i = 0; i < n_keys; i++)
    dist[i * n_keys + i] = 0.0;
  if (n_keys < 2) return KARST_SUCCESS;
  int T = ctx && ctx->nthreads > 1 ? ctx->nthreads : 1;
  if (T > n_keys - 1) T = (int)(n_keys - 1);
  tasks = calloc((size_t)T, sizeof *tasks);
  threads = calloc((size_t)T, sizeof *threads);
  if (!tasks || !threads) {
    err = karst_set_error(ctx, KARST_ENOMEM, "key-point distances: out of memory");
    goto cleanup;
  }
  for (int t = 0; t < T; t++) {
    karst_ctx_init(&tasks[t].ctx);
    tasks[t].g = g;
    tasks[t].n_keys = n_keys;
    tasks[t].keys = keys;
    tasks[t].lb = lb_per_metre;
    tasks[t].method = method;
    tasks[t].dist = dist;
    tasks[t].pred = pred;
    tasks[t].bound = bound;
    tasks[t].thread = t;
    tasks[t].nthreads = T;
    tasks[t].interrupt = ctx ? ctx->interrupt : NULL;
  }
  if (T == 1) {
    rows_worker(&tasks[0]);
    started = 0;
  } else {
    for (; started < T; started++)
      if (pthread_create(&threads[started], NULL, rows_worker, &tasks[started])) break;
    if (started == 0) rows_worker(&tasks[0]), started = -1;
    /* Threads that could not start: their rows are done here, in order. */
    for (int t = started < 0 ? 1 : started; t < T; t++)
      rows_worker(&tasks[t]);
    for (int t = 0; t < (started < 0 ? 0 : started); t++)
      pthread_join(threads[t], NULL);
  }
  for (int t = 0; t < T; t++)
    if (tasks[t].err) {
      err = karst_set_error(ctx, tasks[t].err, "%s", tasks[t].ctx.errmsg);
      goto cleanup;
    }
  for (karst_int_t i = 0; i < n_keys; i++)
    for (karst_int_t j = i + 1; j < n_keys; j++) {
      if (keys[i] == keys[j]) dist[i * n_keys + j] = 0.0;
      dist[j * n_keys + i] = dist[i * n_keys + j];
    }
cleanup:
  free(tasks);
  free(threads);
  return err;
}

/* ------------------------------------------------------------------------ */
/* Routed rows towards targets (backward searches), one target per task.    */
/* ------------------------------------------------------------------------ */
typedef struct {
  karst_ctx_t ctx; /* private context: errors are copied back by the caller */
  const karst_graph_t *g;
  karst_int_t n_targets, n_sources;
  const karst_int_t *targets, *sources;
  const karst_route_t *const *routes;
  const unsigned char *closed;
  double *dist;
  float *bound;
  int32_t *succ;
  int thread, nthreads;
  volatile int *interrupt;
  karst_error_t err;
} trows_task_t;

static void *trows_worker(void *arg) {
  trows_task_t *t = arg;
  karst_search_t *s = NULL;
  unsigned char *mask = NULL;
  const karst_graph_t *g = t->g;
  t->err = karst_search_create(&t->ctx, g, &s);
  if (t->err) goto cleanup;
  mask = karst_i_calloc_large((size_t)(g->n > 0 ? g->n : 1), 1);
  if (!mask) {
    t->err = karst_set_error(&t->ctx, KARST_ENOMEM, "target rows: out of memory");
    goto cleanup;
  }
  for (karst_int_t i = t->thread; i < t->n_targets; i += t->nthreads) {
    if (t->interrupt && *t->interrupt) {
      t->err = karst_set_error(&t->ctx, KARST_EINTERRUPTED, "routing searches interrupted");
      goto cleanup;
    }
    karst_int_t ti = t->targets[i], want = 0;
    for (karst_int_t j = 0; j < t->n_sources; j++)
      if (!mask[t->sources[j]]) mask[t->sources[j]] = 1, want++;
    const search_opts_t o = {-1,   0.0,
                             NULL, t->closed,
                             mask, want,
                             NULL, t->succ != NULL,
                             1,    t->routes ? t->routes[i] : NULL,
                             NULL, NULL};
    t->err = run_search(&t->ctx, s, 1, &ti, &o);
    for (karst_int_t j = 0; j < t->n_sources; j++)
      mask[t->sources[j]] = 0;
    if (t->err) goto cleanup;
    for (karst_int_t j = 0; j < t->n_sources; j++)
      t->dist[i * t->n_sources + j] = karst_search_dist(s, t->sources[j]);
    if (t->succ) {
      int32_t *row = t->succ + (size_t)i * (size_t)g->n;
      for (karst_int_t v = 0; v < g->n; v++)
        row[v] = is_settled(s, v) ? s->pred[v] : -2;
    }
    if (t->bound) {
      /* Dijkstra settles in nondecreasing cost, so a vertex it did not settle costs at least the
       * largest settled cost R: min(d, R) bounds d from below and, like d, changes by at most the
       * arc cost along an arc. */
      float *row = t->bound + (size_t)i * (size_t)g->n;
      double R = 0.0;
      for (karst_int_t v = 0; v < g->n; v++)
        if (is_settled(s, v) && s->node[v].dist > R) R = s->node[v].dist;
      for (karst_int_t v = 0; v < g->n; v++)
        row[v] = float_below(is_settled(s, v) ? s->node[v].dist : R);
    }
  }
cleanup:
  free(mask);
  karst_search_free(s);
  return NULL;
}

/**
 * Least routed costs from sources to targets (see paths.h). Each target's row is one backward
 * Dijkstra (Dijkstra 1959 on the reversed arcs: the routed costs are directed), rows spread over
 * threads, target i to thread i mod T: the output does not depend on T.
 * Time complexity: O(targets (m + n) log n) in the worst case.
 */
karst_error_t karst_paths_target_rows(karst_ctx_t *ctx, const karst_graph_t *g,
                                      karst_int_t n_targets, const karst_int_t *targets,
                                      const karst_route_t *const *routes,
                                      const unsigned char *closed, karst_int_t n_sources,
                                      const karst_int_t *sources, double *dist, float *bound,
                                      int32_t *succ) {
  karst_error_t err = KARST_SUCCESS;
  trows_task_t *tasks = NULL;
  pthread_t *threads = NULL;
  if (n_targets < 0 || n_sources < 0 || (n_targets > 0 && (!targets || !dist)) ||
      (n_sources > 0 && !sources))
    return karst_set_error(ctx, KARST_EINVAL, "target rows: %lld targets, %lld sources",
                           (long long)n_targets, (long long)n_sources);
  if (g->n >= INT32_MAX)
    return karst_set_error(ctx, KARST_ERANGE, "target rows: %lld vertices exceed 2^31 - 1",
                           (long long)g->n);
  for (karst_int_t i = 0; i < n_targets + n_sources; i++) {
    karst_int_t v = i < n_targets ? targets[i] : sources[i - n_targets];
    if (v < 0 || v >= g->n)
      return karst_set_error(ctx, KARST_EINVAL, "target rows: vertex %lld outside [0, %lld)",
                             (long long)v, (long long)g->n);
  }
  if (n_targets == 0) return KARST_SUCCESS;
  int T = ctx && ctx->nthreads > 1 ? ctx->nthreads : 1;
  if (T > n_targets) T = (int)n_targets;
  tasks = calloc((size_t)T, sizeof *tasks);
  threads = calloc((size_t)T, sizeof *threads);
  if (!tasks || !threads) {
    err = karst_set_error(ctx, KARST_ENOMEM, "target rows: out of memory");
    goto cleanup;
  }
  for (int t = 0; t < T; t++) {
    karst_ctx_init(&tasks[t].ctx);
    tasks[t] = (trows_task_t){
        tasks[t].ctx, g,    n_targets, n_sources, targets, sources, routes,
        closed,       dist, bound,     succ,      t,       T,       ctx ? ctx->interrupt : NULL,
        KARST_SUCCESS};
  }
  int started = 0;
  if (T > 1)
    for (; started < T; started++)
      if (pthread_create(&threads[started], NULL, trows_worker, &tasks[started])) break;
  for (int t = started; t < T; t++) /* threads that could not start: their rows are done here */
    trows_worker(&tasks[t]);
  for (int t = 0; t < started; t++)
    pthread_join(threads[t], NULL);
  for (int t = 0; t < T; t++)
    if (tasks[t].err) {
      err = karst_set_error(ctx, tasks[t].err, "%s", tasks[t].ctx.errmsg);
      goto cleanup;
    }
cleanup:
  free(tasks);
  free(threads);
  return err;
}

/**
 * The path from @p source to a succ row's target (karst_paths_target_rows), following the
 * successors, and its routed cost under @p route (NULL: base costs).
 * @return KARST_EUNREACHABLE when the row did not settle @p source; KARST_EINVAL for a cycle.
 * Time complexity: O(path length × degree).
 */
karst_error_t karst_paths_row_path(karst_ctx_t *ctx, const karst_graph_t *g,
                                   const int32_t *succ_row, const karst_route_t *route,
                                   karst_int_t source, karst_path_t *path) {
  if (source < 0 || source >= g->n || succ_row[source] == -2)
    return karst_set_error(ctx, KARST_EUNREACHABLE, "no finite-cost path from vertex %lld",
                           (long long)source);
  karst_int_t len = 0;
  for (karst_int_t u = source; u >= 0; u = succ_row[u])
    if (++len > g->n)
      return karst_set_error(ctx, KARST_EINVAL, "routing row from vertex %lld has a cycle",
                             (long long)source);
  karst_error_t err = path_reserve(ctx, path, len);
  if (err) return err;
  path->n = len;
  double cost = 0;
  karst_int_t i = 0;
  for (karst_int_t u = source; u >= 0; u = succ_row[u]) {
    path->v[i++] = u;
    karst_int_t w = succ_row[u];
    if (w >= 0) {
      double best = INFINITY;
      karst_arc_reader_t rd = karst_graph_arcs(g, u);
      for (karst_int_t a = g->offsets[u]; a < g->offsets[u + 1]; a++)
        if (karst_arc_next(&rd) == w) {
          double c = route ? route_cost(route, g->cost[a], u, w) : g->cost[a];
          if (c < best) best = c;
        }
      cost += best;
    }
  }
  path->cost = cost;
  return KARST_SUCCESS;
}
