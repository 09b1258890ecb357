/* The γ-skeleton of the key points (Paris et al. 2021, §5.1) and the network
 * that grows path by path on the sample graph. */
#include "karst/skeleton.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/memory_internal.h"
#include "core/parallel_internal.h"
#include "karst/routing.h"

/**
 * Initialise @p sk as an empty network on graph @p g (which must outlive
 * it). O(n) for the vertex → node map.
 */
karst_error_t karst_skeleton_init(karst_ctx_t *ctx, karst_skeleton_t *sk, const karst_graph_t *g) {
  memset(sk, 0, sizeof *sk);
  karst_network_init(&sk->net);
  sk->n_graph = g->n;
  sk->node_of_vertex =
      karst_i_alloc_large((size_t)(g->n > 0 ? g->n : 1) * sizeof *sk->node_of_vertex);
  sk->edge_set_cap = 1024;
  sk->edge_keys = calloc(sk->edge_set_cap, sizeof *sk->edge_keys);
  double *d;
  if (!sk->node_of_vertex || !sk->edge_keys ||
      karst_network_attr_add(&sk->net, KARST_ATTR_NODE, "kind", 1, 1, &d) ||
      karst_network_attr_add(&sk->net, KARST_ATTR_EDGE, "cost", 1, 0, &d) ||
      karst_network_attr_add(&sk->net, KARST_ATTR_EDGE, "branch_id", 1, 1, &d) ||
      karst_network_attr_add(&sk->net, KARST_ATTR_EDGE, "amplification_step", 1, 1, &d) ||
      karst_network_attr_add(&sk->net, KARST_ATTR_NODE, "spring", 1, 1, &d) ||
      karst_network_attr_add(&sk->net, KARST_ATTR_EDGE, "spring", 1, 1, &d)) {
    karst_skeleton_destroy(sk);
    return karst_set_error(ctx, KARST_ENOMEM, "skeleton: out of memory for %lld vertices",
                           (long long)g->n);
  }
  for (karst_int_t v = 0; v < g->n; v++)
    sk->node_of_vertex[v] = -1;
  return KARST_SUCCESS;
}

void karst_skeleton_destroy(karst_skeleton_t *sk) {
  karst_network_destroy(&sk->net);
  free(sk->node_of_vertex);
  free(sk->vertex_of_node);
  free(sk->edge_keys);
  memset(sk, 0, sizeof *sk);
}

/**
 * The γ neighbourhood rule of Paris et al. 2021, §5.1: the pair (a, b) is
 * kept iff d(a, b) is finite and no third key point k has
 * d(a,k)^γ + d(k,b)^γ < d(a,b)^γ. γ = INFINITY is the limit
 * max(d(a,k), d(k,b)) < d(a,b) (relative neighbourhood graph); γ = 2 is the
 * Gabriel graph under the metric d. The test is evaluated on ratios
 * (d(a,k)/d(a,b))^γ + (d(k,b)/d(a,b))^γ < 1 so large γ cannot overflow. For
 * γ ≤ 1 nothing is ever pruned on a path metric: d(a,b) ≤ d(a,k) + d(k,b) and
 * x^γ is subadditive, which is why γ = 0.8 gives the dense mazes of §7.2.
 * Pairs at distance 0 (coincident key points) are kept.
 *
 * @param n     number of key points.
 * @param dist  n × n symmetric distance matrix (INFINITY: unreachable).
 * @param gamma γ > 0, or INFINITY.
 * @param keep  n × n output, keep[a*n+b] = keep[b*n+a] = 1 for kept pairs, 0 elsewhere.
 * @return KARST_SUCCESS or KARST_EINVAL (γ not > 0, or a NaN / negative distance).
 * Time complexity: O(n³).
 */
karst_error_t karst_skeleton_gamma_keep(karst_ctx_t *ctx, karst_int_t n, const double *dist,
                                        double gamma, unsigned char *keep) {
  if (!(gamma > 0)) return karst_set_error(ctx, KARST_EINVAL, "gamma must be > 0, got %g", gamma);
  for (karst_int_t i = 0; i < n * n; i++)
    if (!(dist[i] >= 0))
      return karst_set_error(ctx, KARST_EINVAL,
                             "key-point distance (%lld, %lld) is %g, not a distance",
                             (long long)(i / n), (long long)(i % n), dist[i]);
  memset(keep, 0, (size_t)(n * n));
  for (karst_int_t a = 0; a < n; a++)
    for (karst_int_t b = a + 1; b < n; b++) {
      double dab = dist[a * n + b];
      if (!(dab < INFINITY)) continue;
      int pruned = 0;
      if (dab > 0) {
        for (karst_int_t k = 0; k < n && !pruned; k++) {
          if (k == a || k == b) continue;
          double ra = dist[a * n + k] / dab, rb = dist[k * n + b] / dab;
          if (isinf(gamma))
            pruned = fmax(ra, rb) < 1.0;
          else
            pruned = pow(ra, gamma) + pow(rb, gamma) < 1.0;
        }
      }
      if (!pruned) keep[a * n + b] = keep[b * n + a] = 1;
    }
  return KARST_SUCCESS;
}

/* splitmix-style mixing of an edge key for the open-addressing set. */
static size_t hash_key(uint64_t k, size_t cap) {
  k ^= k >> 33;
  k *= 0xff51afd7ed558ccdULL;
  k ^= k >> 33;
  return (size_t)k & (cap - 1);
}

/* Insert key (> 0) unless present; *added says which. Load factor ≤ 1/2. */
static karst_error_t edge_set_insert(karst_skeleton_t *sk, uint64_t key, int *added) {
  if (2 * ((size_t)sk->net.n_edges + 1) > sk->edge_set_cap) {
    size_t cap = sk->edge_set_cap * 2;
    uint64_t *keys = calloc(cap, sizeof *keys);
    if (!keys) return KARST_ENOMEM;
    for (size_t i = 0; i < sk->edge_set_cap; i++) {
      if (!sk->edge_keys[i]) continue;
      size_t h = hash_key(sk->edge_keys[i], cap);
      while (keys[h])
        h = (h + 1) & (cap - 1);
      keys[h] = sk->edge_keys[i];
    }
    free(sk->edge_keys);
    sk->edge_keys = keys;
    sk->edge_set_cap = cap;
  }
  size_t h = hash_key(key, sk->edge_set_cap);
  while (sk->edge_keys[h]) {
    if (sk->edge_keys[h] == key) {
      *added = 0;
      return KARST_SUCCESS;
    }
    h = (h + 1) & (sk->edge_set_cap - 1);
  }
  sk->edge_keys[h] = key;
  *added = 1;
  return KARST_SUCCESS;
}

/* Node of graph vertex v, created (kind interior) when absent. */
static karst_error_t node_for(karst_ctx_t *ctx, karst_skeleton_t *sk, const karst_graph_t *g,
                              karst_int_t v, karst_int_t *node) {
  if (v < 0 || v >= sk->n_graph)
    return karst_set_error(ctx, KARST_EINVAL, "skeleton: vertex %lld outside the graph (n = %lld)",
                           (long long)v, (long long)sk->n_graph);
  if (sk->node_of_vertex[v] >= 0) {
    *node = sk->node_of_vertex[v];
    return KARST_SUCCESS;
  }
  karst_int_t idx;
  if (karst_network_add_node(&sk->net, g->xyz[3 * v], g->xyz[3 * v + 1], g->xyz[3 * v + 2], &idx))
    return karst_set_error(ctx, KARST_ENOMEM, "skeleton: out of memory");
  if (idx >= sk->vertex_cap) {
    karst_int_t cap = sk->vertex_cap ? 2 * sk->vertex_cap : 256;
    karst_int_t *vn = realloc(sk->vertex_of_node, (size_t)cap * sizeof *vn);
    if (!vn) return karst_set_error(ctx, KARST_ENOMEM, "skeleton: out of memory");
    sk->vertex_of_node = vn;
    sk->vertex_cap = cap;
  }
  sk->vertex_of_node[idx] = v;
  sk->node_of_vertex[v] = idx;
  *node = idx;
  return KARST_SUCCESS;
}

/* Cost of arc u -> w (the cheapest, should the graph hold parallel arcs). */
static double arc_cost(const karst_graph_t *g, karst_int_t u, karst_int_t w) {
  double best = INFINITY;
  karst_arc_reader_t rd = karst_graph_arcs(g, u);
  for (karst_int_t a = g->offsets[u]; a < g->offsets[u + 1]; a++)
    if (karst_arc_next(&rd) == w && g->cost[a] < best) best = g->cost[a];
  return best;
}

/**
 * Add a path of graph vertices to the network: its vertices become nodes
 * (once), its consecutive pairs edges (once; an edge already laid keeps its
 * first branch id and step). The path gets branch id sk->n_paths.
 *
 * @param path               vertices of a path on @p g (consecutive ones adjacent).
 * @param amplification_step 0 for the skeleton, s ≥ 1 for amplification step s.
 * @return KARST_SUCCESS, KARST_EINVAL (vertices not adjacent), KARST_ENOMEM.
 * Time complexity: O(path length × degree), amortised.
 */
karst_error_t karst_skeleton_add_path(karst_ctx_t *ctx, karst_skeleton_t *sk,
                                      const karst_graph_t *g, const karst_path_t *path,
                                      int amplification_step) {
  return karst_skeleton_add_route(ctx, sk, g, path, amplification_step, -1);
}

/**
 * karst_skeleton_add_path for a path draining to spring @p spring (its index among the springs,
 * -1 unknown): new edges and nodes get it as their "spring" attribute (a node or edge already
 * laid keeps its first).
 * Time complexity: O(path length × degree), amortised.
 */
karst_error_t karst_skeleton_add_route(karst_ctx_t *ctx, karst_skeleton_t *sk,
                                       const karst_graph_t *g, const karst_path_t *path,
                                       int amplification_step, int spring) {
  karst_int_t prev = -1;
  for (karst_int_t i = 0; i < path->n; i++) {
    karst_int_t node = -1, before = sk->net.n_nodes;
    karst_error_t err = node_for(ctx, sk, g, path->v[i], &node);
    if (err) return err;
    if (node >= before)
      karst_network_attr_find(&sk->net, KARST_ATTR_NODE, "spring")->data[node] = spring;
    if (i > 0 && node != prev) {
      double c = arc_cost(g, path->v[i - 1], path->v[i]);
      if (!(c < INFINITY))
        return karst_set_error(ctx, KARST_EINVAL,
                               "skeleton: path steps from vertex %lld to %lld, which are not "
                               "joined by a finite-cost edge",
                               (long long)path->v[i - 1], (long long)path->v[i]);
      karst_int_t a = prev < node ? prev : node, b = prev < node ? node : prev;
      if (b >= ((karst_int_t)1 << 32))
        return karst_set_error(ctx, KARST_ERANGE, "skeleton: more than 2^32 nodes");
      int added;
      if (edge_set_insert(sk, (((uint64_t)a << 32) | (uint64_t)b) + 1, &added))
        return karst_set_error(ctx, KARST_ENOMEM, "skeleton: out of memory");
      if (added) {
        karst_int_t e;
        if (karst_network_add_edge(&sk->net, a, b, &e))
          return karst_set_error(ctx, KARST_ENOMEM, "skeleton: out of memory");
        karst_network_attr_find(&sk->net, KARST_ATTR_EDGE, "cost")->data[e] = c;
        karst_network_attr_find(&sk->net, KARST_ATTR_EDGE, "branch_id")->data[e] =
            (double)sk->n_paths;
        karst_network_attr_find(&sk->net, KARST_ATTR_EDGE, "amplification_step")->data[e] =
            amplification_step;
        karst_network_attr_find(&sk->net, KARST_ATTR_EDGE, "spring")->data[e] = spring;
      }
    }
    prev = node;
  }
  sk->n_paths++;
  return sk->on_path ? sk->on_path(sk->on_path_arg, path) : KARST_SUCCESS;
}

/** Make graph vertex @p vertex a node (if not yet) and set its kind. O(1) amortised. */
karst_error_t karst_skeleton_mark_node(karst_ctx_t *ctx, karst_skeleton_t *sk,
                                       const karst_graph_t *g, karst_int_t vertex,
                                       karst_node_kind_t kind) {
  karst_int_t node = -1;
  karst_error_t err = node_for(ctx, sk, g, vertex, &node);
  if (err) return err;
  karst_network_attr_find(&sk->net, KARST_ATTR_NODE, "kind")->data[node] = kind;
  return KARST_SUCCESS;
}

/**
 * Graph vertices shared by paths become junctions (§5.1): every node of kind
 * interior whose degree is at least 3 gets kind junction. (Two paths that
 * merely run together over a stretch share degree-2 vertices, which are not
 * branching points.) Key points and amplification points keep their kind.
 * O(nodes + edges).
 */
void karst_skeleton_mark_junctions(karst_skeleton_t *sk) {
  karst_network_t *net = &sk->net;
  karst_int_t *deg = calloc((size_t)(net->n_nodes > 0 ? net->n_nodes : 1), sizeof *deg);
  if (!deg) return;
  for (karst_int_t e = 0; e < net->n_edges; e++)
    deg[net->edges[2 * e]]++, deg[net->edges[2 * e + 1]]++;
  double *kind = karst_network_attr_find(net, KARST_ATTR_NODE, "kind")->data;
  for (karst_int_t v = 0; v < net->n_nodes; v++)
    if (kind[v] == KARST_NODE_INTERIOR && deg[v] >= 3) kind[v] = KARST_NODE_JUNCTION;
  free(deg);
}

static void reverse_path(karst_path_t *p) {
  for (karst_int_t i = 0, j = p->n - 1; i < j; i++, j--) {
    karst_int_t t = p->v[i];
    p->v[i] = p->v[j];
    p->v[j] = t;
  }
}

/* A pair to lay, in increasing d: searched from vertex src to vertex dst with the heuristic row
 * of dst (path sharing), read from a tree (plain union), or searched again; laid as found, or
 * reversed (the symmetric build searches b → a with a's row and lays a → b). */
typedef struct {
  double d;
  karst_int_t a, b;           /* key-point indices, for the order (a, then b) */
  karst_int_t src, dst;       /* graph vertices */
  const float *row;           /* lower bounds of the cost to dst, or NULL */
  const int32_t *pred;        /* symmetric build: the tree of a (read a → b), or NULL */
  const int32_t *succ;        /* routed build: the successor row of dst, or NULL */
  const karst_route_t *route; /* routed costs, or NULL */
  unsigned char tag;          /* path-sharing tag (spring + 1), 0: any */
  int spring;                 /* the spring the route drains to, -1 unknown */
} pair_t;

static int pair_cmp(const void *x, const void *y) {
  const pair_t *p = x, *q = y;
  if (p->d != q->d) return p->d < q->d ? -1 : 1;
  if (p->a != q->a) return p->a < q->a ? -1 : 1;
  return (p->b > q->b) - (p->b < q->b);
}

/* What every pair's search shares. */
typedef struct {
  const karst_graph_t *g;
  double lb, reuse;
  int reverse;                 /* lay the found path reversed */
  const unsigned char *closed; /* vertices a path may only end at */
  unsigned char *flag;         /* path-sharing tags per arc, or NULL (reuse = 1) */
  double *to_net;
} lay_t;

/* Tag both arcs of every edge of @p path (all parallel copies) as network arcs of @p tag (1 when
 * untagged); an arc keeps the tag of the first path that laid it. */
static void flag_path_arcs(const karst_graph_t *g, const karst_path_t *path, unsigned char *flag,
                           unsigned char tag) {
  unsigned char t = tag ? tag : 1;
  for (karst_int_t i = 1; i < path->n; i++) {
    karst_int_t u = path->v[i - 1], w = path->v[i];
    karst_arc_reader_t ru = karst_graph_arcs(g, u), rw = karst_graph_arcs(g, w);
    for (karst_int_t a = g->offsets[u]; a < g->offsets[u + 1]; a++)
      if (karst_arc_next(&ru) == w && !flag[a]) flag[a] = t;
    for (karst_int_t a = g->offsets[w]; a < g->offsets[w + 1]; a++)
      if (karst_arc_next(&rw) == u && !flag[a]) flag[a] = t;
  }
}

/* The path of one pair (see pair_t), oriented as it is laid. */
static karst_error_t search_pair(karst_ctx_t *ctx, karst_search_t *s, const lay_t *L,
                                 const pair_t *P, int (*cancelled)(void *), void *cancel_arg,
                                 karst_path_t *path) {
  karst_error_t err;
  if (L->flag) {
    const karst_reuse_t ru = {L->reuse,   L->flag, L->to_net, cancelled,
                              cancel_arg, P->tag,  P->route,  L->closed};
    err = karst_paths_astar_reuse(ctx, s, P->src, P->dst, L->lb, P->row, &ru, path);
  } else if (P->succ) {
    err = karst_paths_row_path(ctx, L->g, P->succ, P->route, P->src, path);
  } else if (P->pred) {
    return karst_paths_tree_path(ctx, L->g, P->pred, P->src, P->dst, path);
  } else if (P->route || L->closed) {
    const karst_reuse_t ru = {1.0, NULL, NULL, cancelled, cancel_arg, 0, P->route, L->closed};
    err = karst_paths_astar_reuse(ctx, s, P->src, P->dst, L->lb, P->row, &ru, path);
  } else {
    err = karst_paths_astar(ctx, s, P->src, P->dst, L->lb, path);
  }
  if (!err && L->reverse) reverse_path(path);
  return err;
}

/* ------------------------------------------------------------------------ */
/* Laying the pairs on several threads without changing a single result.   */
/*                                                                          */
/* Each pair's search depends on the network laid by the pairs before it,   */
/* so the pairs are committed strictly in order. But most pairs add         */
/* nothing: on the looping-cave preset (1081 pairs) 857 least-cost paths    */
/* run entirely along conduits already laid, and the network — the only     */
/* state a search reads besides the graph — is then unchanged. So the       */
/* threads search the next pairs ahead of the commit point on the current   */
/* network (speculation); results are committed in pair order. When a      */
/* committed path adds an edge, the searches under way pause at their next  */
/* check (every 256 settled vertices), the network is updated with no       */
/* search running, and each search, finished or paused, is kept only if it  */
/* has read nothing the update changed: it then runs (or ran) exactly as it */
/* would have on the new network. Every committed path was thus computed on */
/* exactly the network the one-thread loop would have had, and the searches */
/* are exact with deterministic ties: the skeleton is the same for any      */
/* thread count (tests/unit/test_skeleton.c checks it).                     */
/* ------------------------------------------------------------------------ */

/*
 * Cap of the network distance kept for the path-sharing heuristic, as a
 * fraction of the longest kept pair's least cost. Beyond a few per cent of
 * that, knowing how far the network is barely narrows the searches, while
 * keeping it exact costs a Dijkstra over each new conduit's whole catchment.
 * Measured (skeleton stage, 2 threads, same networks each time): looping cave
 * 0.49 s uncapped, 0.43 s at 0.1, 0.39 s at 0.03, 0.43 s at 0.01, 0.47 s at
 * 0 (no network term); rectilinear maze 0.19 s, 0.13, 0.12, 0.08 s;
 * superimposed 0.17 s, 0.06, 0.05, 0.04 s.
 */
#define KARST_SKELETON_NET_DISTANCE_CAP 0.02

/* Pairs searched ahead of the commit point, per thread. */
#define SPEC_WINDOW_PER_THREAD 4

/*
 * The threads always search ahead. Until 6 December 2026 they did so only while at most half of
 * the recent commits changed the network, because a change threw away every search under way
 * and every finished one; once finished searches that read nothing of a change were kept (5
 * December), and then paused searches too (6 December), searching ahead paid on the 1.5 M sample
 * block of bench_generate as well (50 pairs, 43 of which add edges; docs/performance.md).
 */

typedef struct {
  karst_path_t path;
  karst_error_t err;
  char msg[KARST_ERRMSG_MAX];
  int ready;
  karst_int_t pair; /* the pair whose result this is (when ready) */
  int32_t *trail;   /* the vertices its search touched (karst_search_trail) */
  karst_int_t n_trail, cap_trail;
} spec_slot_t;

typedef struct {
  karst_ctx_t *ctx;
  const lay_t *L;
  const pair_t *pairs;
  karst_int_t n_pairs;
  karst_skeleton_t *sk;
  karst_search_t **ws; /* one workspace per thread */
  spec_slot_t *slot;   /* pair k lives in slot k % window until committed */
  karst_int_t window;
  pthread_mutex_t mu;
  pthread_cond_t cv;
  /* under mu: */
  karst_int_t next;   /* next pair to hand out */
  karst_int_t commit; /* next pair to commit */
  int in_flight, mutating, stop;
  karst_error_t err;
  karst_int_t kept;
  uint32_t *mark; /* per vertex: the change (mark_id) that last altered what it reads */
  uint32_t mark_id;
  karst_int_t n_kept_results;      /* finished searches kept across a network change (statistics) */
  karst_int_t n_paused, n_resumed; /* searches paused by a change, and of those resumed */
  int paused;                      /* searches waiting in spec_check for a change to end */
  karst_int_t *running;            /* per thread: the pair it is searching, or -1 */
  int n_threads;
  atomic_int attention; /* read by the searches without the lock: pause */
} spec_t;

/* One thread's search under way, as spec_check sees it. A search is never running while the
 * network changes (the change waits until every search under way has paused or left), so unless
 * a change stopped it (dead) its result holds on the network as it is, a change still pending
 * being checked on the finished slots when it is applied. */
typedef struct {
  spec_t *sp;
  karst_search_t *ws;
  int dead; /* stopped: it had touched what a change altered, or the loop stops */
} spec_run_t;

/* Whether vertex list @p v (n entries) meets a vertex marked after change @p since. */
static int spec_touched_since(const spec_t *sp, const int32_t *v, karst_int_t n, uint32_t since) {
  for (karst_int_t i = 0; i < n; i++)
    if (sp->mark[v[i]] > since) return 1;
  return 0;
}

/* The searches' check, every 256 settled vertices (no lock unless a change is pending). When a
 * commit is changing the network, the search pauses here, at a point where it reads nothing,
 * until the change is applied; it then goes on if it has touched no vertex the change altered
 * (everything it read is as on the new network, so it runs on as a search started on the new
 * network would), else it stops. Returns nonzero to stop. */
static int spec_check(void *arg) {
  spec_run_t *run = arg;
  spec_t *sp = run->sp;
  if (!atomic_load_explicit(&sp->attention, memory_order_acquire)) return 0;
  pthread_mutex_lock(&sp->mu);
  if (sp->mutating && !sp->stop) {
    const uint32_t since = sp->mark_id;
    sp->paused++;
    sp->n_paused++;
    pthread_cond_broadcast(&sp->cv);
    while (sp->mutating && !sp->stop)
      pthread_cond_wait(&sp->cv, &sp->mu);
    sp->paused--;
    karst_int_t n = 0;
    const int32_t *trail = karst_search_trail(run->ws, &n);
    /* mark_id below since: the marks wrapped and were cleared, so they cannot tell */
    if (sp->stop || sp->mark_id < since || spec_touched_since(sp, trail, n, since)) {
      run->dead = 1;
    } else {
      sp->n_resumed++;
    }
  }
  const int stop = run->dead || sp->stop;
  pthread_mutex_unlock(&sp->mu);
  return stop;
}

/* Commit pair sp->commit from its slot. Called with sp->mu held by thread @p tid. */
static void spec_commit_one(spec_t *sp, int tid) {
  spec_slot_t *sl = &sp->slot[sp->commit % sp->window];
  karst_error_t err = KARST_SUCCESS;
  sl->ready = 0;
  if (karst_interrupted(sp->ctx))
    err = karst_set_error(sp->ctx, KARST_EINTERRUPTED, "skeleton interrupted");
  else if (sl->err)
    err = karst_set_error(sp->ctx, sl->err, "%s", sl->msg);
  karst_int_t e0 = sp->sk->net.n_edges;
  const pair_t *P = &sp->pairs[sp->commit];
  if (!err) err = karst_skeleton_add_route(sp->ctx, sp->sk, sp->L->g, &sl->path, 0, P->spring);
  if (err) {
    sp->err = err;
    sp->stop = 1;
    atomic_store_explicit(&sp->attention, 1, memory_order_release);
    pthread_cond_broadcast(&sp->cv);
    return;
  }
  sp->kept++;
  sp->commit++;
  karst_progress(sp->ctx, "skeleton", (double)sp->commit, (double)sp->n_pairs);
  if (sp->sk->net.n_edges == e0) return; /* nothing new: every speculative search stays valid */
  /* The network changes: wait until every search under way has paused (spec_check) or left. */
  sp->mutating = 1;
  atomic_store_explicit(&sp->attention, 1, memory_order_release);
  while (sp->in_flight > sp->paused)
    pthread_cond_wait(&sp->cv, &sp->mu);
  flag_path_arcs(sp->L->g, &sl->path, sp->L->flag, P->tag);
  err = karst_paths_lower_distances(sp->ctx, sp->ws[tid], sl->path.n, sl->path.v, sp->L->to_net);
  /* A finished search stays valid if it read nothing this change altered: the new flags are on
   * arcs between the path's vertices (read only when one of them is expanded, so touched), the
   * lowered network distances are at the vertices lower_distances touched (read only at a
   * touched vertex). Then the search would have run identically on the new network. */
  if (++sp->mark_id == 0) { /* wrapped: clear the marks once (a paused search then stops) */
    memset(sp->mark, 0, (size_t)sp->L->g->n * sizeof *sp->mark);
    sp->mark_id = 1;
  }
  karst_int_t n_changed = 0;
  const int32_t *changed = karst_search_trail(sp->ws[tid], &n_changed);
  for (karst_int_t i = 0; i < n_changed; i++)
    sp->mark[changed[i]] = sp->mark_id;
  for (karst_int_t i = 0; i < sl->path.n; i++)
    sp->mark[sl->path.v[i]] = sp->mark_id;
  for (karst_int_t i = 0; i < sp->window; i++) {
    spec_slot_t *o = &sp->slot[i];
    if (!o->ready) continue;
    int valid = o->pair >= sp->commit && !o->err && o->n_trail >= 0 &&
                !spec_touched_since(sp, o->trail, o->n_trail, sp->mark_id - 1);
    o->ready = valid;
    sp->n_kept_results += valid;
  }
  sp->next = sp->commit;
  sp->mutating = 0;
  if (err) {
    sp->err = err;
    sp->stop = 1;
  }
  atomic_store_explicit(&sp->attention, sp->stop, memory_order_release);
  pthread_cond_broadcast(&sp->cv);
}

static void spec_worker(void *arg, int tid, int nthreads) {
  (void)nthreads;
  spec_t *sp = arg;
  karst_ctx_t wctx;
  karst_ctx_init(&wctx);
  karst_path_t local;
  karst_path_init(&local);
  int32_t *local_trail = NULL;
  karst_int_t local_cap = 0;
  pthread_mutex_lock(&sp->mu);
  while (!sp->stop && sp->commit < sp->n_pairs) {
    if (sp->next < sp->commit) sp->next = sp->commit; /* committed from a kept slot meanwhile */
    if (sp->mutating || sp->next >= sp->n_pairs || sp->next >= sp->commit + sp->window) {
      pthread_cond_wait(&sp->cv, &sp->mu);
      continue;
    }
    const karst_int_t k = sp->next++;
    spec_slot_t *mine = &sp->slot[k % sp->window];
    if (mine->ready && mine->pair == k) continue; /* kept across a network change */
    int taken = 0;                                /* by a search that went on across a change */
    for (int t = 0; t < sp->n_threads; t++)
      taken |= sp->running[t] == k;
    if (taken) continue;
    spec_run_t run = {sp, sp->ws[tid], 0};
    sp->running[tid] = k;
    sp->in_flight++;
    pthread_mutex_unlock(&sp->mu);
    karst_error_t err =
        search_pair(&wctx, sp->ws[tid], sp->L, &sp->pairs[k], spec_check, &run, &local);
    karst_int_t n_trail = 0;
    const int32_t *trail = err ? NULL : karst_search_trail(sp->ws[tid], &n_trail);
    if (trail && n_trail > local_cap) { /* grown outside the lock */
      int32_t *nt = realloc(local_trail, (size_t)n_trail * sizeof *nt);
      if (nt) local_trail = nt, local_cap = n_trail;
    }
    int have_trail = trail && n_trail <= local_cap;
    if (have_trail) memcpy(local_trail, trail, (size_t)n_trail * sizeof *trail);
    pthread_mutex_lock(&sp->mu);
    sp->in_flight--;
    sp->running[tid] = -1;
    if (run.dead && !sp->stop && k >= sp->commit && sp->next > k)
      sp->next = k; /* stopped by a change it had read: to be searched again */
    if (!run.dead && !sp->stop && k >= sp->commit) {
      spec_slot_t *sl = &sp->slot[k % sp->window];
      karst_path_t t = sl->path;
      sl->path = local;
      local = t;
      sl->err = err;
      if (err) snprintf(sl->msg, sizeof sl->msg, "%s", wctx.errmsg);
      sl->ready = 1;
      sl->pair = k;
      /* Its trail goes with it (swapped, not copied, under the lock); without one (no memory)
       * it cannot be kept across a change: an empty trail there would wrongly mean "read
       * nothing", so it is marked by n_trail < 0. */
      int32_t *tt = sl->trail;
      karst_int_t tc = sl->cap_trail;
      sl->trail = local_trail, sl->cap_trail = local_cap;
      sl->n_trail = have_trail ? n_trail : -1;
      local_trail = tt, local_cap = tc;
      /* Not while another thread's commit waits for the searches to pause: that thread commits
       * this slot once its change is applied. */
      while (!sp->stop && !sp->mutating && sp->commit < sp->n_pairs &&
             sp->slot[sp->commit % sp->window].ready &&
             sp->slot[sp->commit % sp->window].pair == sp->commit)
        spec_commit_one(sp, tid);
    }
    pthread_cond_broadcast(&sp->cv);
  }
  pthread_cond_broadcast(&sp->cv);
  pthread_mutex_unlock(&sp->mu);
  karst_path_destroy(&local);
  free(local_trail);
}

/* Lay the sorted pairs with path sharing on @p T >= 2 threads (see above). */
static karst_error_t lay_pairs_parallel(karst_ctx_t *ctx, const lay_t *L, int T,
                                        const pair_t *pairs, karst_int_t n_pairs,
                                        karst_skeleton_t *sk, karst_int_t *kept) {
  spec_t sp;
  memset(&sp, 0, sizeof sp);
  karst_error_t err = KARST_SUCCESS;
  sp.ctx = ctx;
  sp.L = L;
  sp.pairs = pairs;
  sp.n_pairs = n_pairs;
  sp.sk = sk;
  sp.window = (karst_int_t)T * SPEC_WINDOW_PER_THREAD;
  atomic_init(&sp.attention, 0);
  sp.ws = calloc((size_t)T, sizeof *sp.ws);
  sp.slot = calloc((size_t)sp.window, sizeof *sp.slot);
  sp.running = malloc((size_t)T * sizeof *sp.running);
  if (!sp.ws || !sp.slot || !sp.running) {
    err = karst_set_error(ctx, KARST_ENOMEM, "skeleton: out of memory");
    goto cleanup;
  }
  for (int t = 0; t < T; t++)
    sp.running[t] = -1;
  sp.n_threads = T;
  for (int t = 0; t < T; t++)
    if ((err = karst_search_create(ctx, L->g, &sp.ws[t])) ||
        (err = karst_search_record_trail(ctx, sp.ws[t])))
      goto cleanup;
  sp.mark = karst_i_calloc_large((size_t)(L->g->n > 0 ? L->g->n : 1), sizeof *sp.mark);
  if (!sp.mark) {
    err = karst_set_error(ctx, KARST_ENOMEM, "skeleton: out of memory");
    goto cleanup;
  }
  if (pthread_mutex_init(&sp.mu, NULL)) {
    err = karst_set_error(ctx, KARST_ENOMEM, "skeleton: cannot create a mutex");
    goto cleanup;
  }
  if (pthread_cond_init(&sp.cv, NULL)) {
    pthread_mutex_destroy(&sp.mu);
    err = karst_set_error(ctx, KARST_ENOMEM, "skeleton: cannot create a condition variable");
    goto cleanup;
  }
  karst_i_parallel_run(T, spec_worker, &sp);
  pthread_cond_destroy(&sp.cv);
  pthread_mutex_destroy(&sp.mu);
  err = sp.err;
  karst_log(ctx, KARST_LOG_DEBUG,
            "skeleton: %lld pairs on %d threads; across a change %lld finished searches kept, "
            "%lld of %lld paused searches resumed",
            (long long)n_pairs, T, (long long)sp.n_kept_results, (long long)sp.n_resumed,
            (long long)sp.n_paused);
cleanup:
  *kept = sp.kept;
  if (sp.ws)
    for (int t = 0; t < T; t++)
      karst_search_free(sp.ws[t]);
  if (sp.slot)
    for (karst_int_t i = 0; i < sp.window; i++) {
      karst_path_destroy(&sp.slot[i].path);
      free(sp.slot[i].trail);
    }
  free(sp.mark);
  free(sp.running);
  free(sp.ws);
  free(sp.slot);
  return err;
}

/* Lay the sorted pairs one after another (one thread), or speculatively on several. */
static karst_error_t lay_pairs(karst_ctx_t *ctx, lay_t *L, const pair_t *pairs, karst_int_t n_pairs,
                               karst_skeleton_t *sk, karst_int_t *n_kept) {
  karst_error_t err = KARST_SUCCESS;
  karst_search_t *s = NULL;
  karst_path_t path;
  karst_path_init(&path);
  karst_int_t kept = 0;
  const int sharing = L->reuse < 1.0;
  if (sharing) {
    const karst_graph_t *g = L->g;
    L->flag = calloc((size_t)(g->n_arcs > 0 ? g->n_arcs : 1), 1);
    L->to_net = karst_i_alloc_large((size_t)(g->n > 0 ? g->n : 1) * sizeof *L->to_net);
    if (!L->flag || !L->to_net) {
      err = karst_set_error(ctx, KARST_ENOMEM, "skeleton: out of memory for path sharing");
      goto cleanup;
    }
    /* The network distance N is kept only up to a cap M: min(N, M) is still a lower bound of N
     * that changes by at most the arc cost along an arc, which is all the A* heuristic needs
     * (karst_paths_astar_reuse), and each new path then lowers N only within M of it instead
     * of over its whole catchment (for the first path, the whole graph). */
    double dmax = 0.0;
    for (karst_int_t k = 0; k < n_pairs; k++)
      dmax = fmax(dmax, pairs[k].d);
    const double cap = n_pairs > 0 ? KARST_SKELETON_NET_DISTANCE_CAP * dmax : 0.0;
    for (karst_int_t v = 0; v < g->n; v++)
      L->to_net[v] = cap;
  }
  const int T = ctx && ctx->nthreads > 1 ? ctx->nthreads : 1;
  if (sharing && T > 1 && n_pairs > 1) {
    err = lay_pairs_parallel(ctx, L, T, pairs, n_pairs, sk, &kept);
    goto cleanup;
  }
  if ((err = karst_search_create(ctx, L->g, &s))) goto cleanup;
  for (karst_int_t k = 0; k < n_pairs; k++) {
    if (karst_interrupted(ctx)) {
      err = karst_set_error(ctx, KARST_EINTERRUPTED, "skeleton interrupted");
      goto cleanup;
    }
    const pair_t *P = &pairs[k];
    if ((err = search_pair(ctx, s, L, P, NULL, NULL, &path))) goto cleanup;
    if ((err = karst_skeleton_add_route(ctx, sk, L->g, &path, 0, P->spring))) goto cleanup;
    if (sharing) {
      flag_path_arcs(L->g, &path, L->flag, P->tag);
      if ((err = karst_paths_lower_distances(ctx, s, path.n, path.v, L->to_net))) goto cleanup;
    }
    kept++;
    karst_progress(ctx, "skeleton", (double)(k + 1), (double)n_pairs);
  }
cleanup:
  if (n_kept) *n_kept = kept;
  karst_path_destroy(&path);
  karst_search_free(s);
  free(L->flag);
  free(L->to_net);
  L->flag = NULL;
  L->to_net = NULL;
  return err;
}

/**
 * The large-scale skeleton S (Paris et al. 2021, §5.1): apply the γ rule to
 * the key-point distance matrix (on the original least-cost distances d),
 * then lay a least-cost path for every kept pair; the skeleton is the union
 * of these paths. Pairs are laid in increasing d(a, b) (ties by a, then b),
 * each on the graph where the edges already in the network cost @p reuse ×
 * their cost — the path sharing of Galin et al. 2011 ("Authoring hierarchical
 * road networks", the method §5.1 builds on): short connections are laid
 * first, and longer ones follow them where that is cheaper than a parallel
 * tunnel, so conduits merge into shared corridors instead of braiding. With
 * reuse = 1 each path is the pair's least-cost path and the skeleton is their
 * plain union. Key-point nodes get kind interior here; the caller marks them.
 * This is the symmetric build on a metric d (every key point connected to every
 * other); the generation pipeline lays the routes of karst_skeleton_build_routes.
 *
 * Searches (reuse < 1): one A* per kept pair with the heuristic of
 * karst_paths_astar_reuse (the key point's exact-distance row when @p bound is
 * given, plus the cost of reaching the network), searched from b towards a so
 * that row a — which every pair a < b has — is the target's row. The network
 * distance it needs is kept up to date with karst_paths_lower_distances after
 * each path. Measured on the looping-cave preset (47 key points, γ = 0.8 so all
 * 1081 pairs are kept, 51 k vertices, 1.1 M edges, one thread, shared 2-core
 * machine, first binary-heap version), for the 1081 searches: at reuse = 0.8 (the preset) 1.26
 * s; 1.55 s without the network term (N = 0, h = r·D); 13.5 s with the Euclidean bound r·lb·|v − t|
 * alone. With ctx->nthreads > 1 the searches run ahead on several threads and are
 * committed in pair order (lay_pairs_parallel), same network.
 *
 * @param g             the sample graph.
 * @param n_keys, keys  key points as vertices.
 * @param dist          their distance matrix (karst_paths_keypoint_distances).
 * @param pred          (reuse = 1) the shortest-path trees of karst_paths_keypoint_trees,
 *                      read for pair (a < b) from row a; NULL: one A* per pair.
 * @param bound         (reuse < 1) the rows of karst_paths_keypoint_bounds, or NULL
 *                      (then the A* heuristic is r × lb_per_metre × distance only).
 * @param gamma         γ > 0 or INFINITY.
 * @param reuse         cost factor of network edges for later paths, in (0, 1].
 * @param lb_per_metre  cost lower bound for the A* heuristic.
 * @param sk            initialised on @p g; receives the paths.
 * @param n_kept        receives the number of kept pairs (may be NULL).
 * @return KARST_SUCCESS, KARST_EINVAL (γ, reuse), KARST_ENOMEM, KARST_EINTERRUPTED.
 * Time complexity: O(k³) for the rule, O(p log p) to order the p kept pairs,
 * plus per pair the path length (trees) or one A* search.
 */
karst_error_t karst_skeleton_build(karst_ctx_t *ctx, const karst_graph_t *g, karst_int_t n_keys,
                                   const karst_int_t *keys, const double *dist, const int32_t *pred,
                                   const float *bound, double gamma, double reuse,
                                   double lb_per_metre, karst_skeleton_t *sk, karst_int_t *n_kept) {
  karst_error_t err = KARST_SUCCESS;
  unsigned char *keep = malloc((size_t)(n_keys * n_keys > 0 ? n_keys * n_keys : 1));
  pair_t *pairs = NULL;
  karst_int_t n_pairs = 0;
  if (n_kept) *n_kept = 0;
  if (!(reuse > 0 && reuse <= 1)) {
    err = karst_set_error(ctx, KARST_EINVAL, "skeleton.reuse must be within (0, 1], got %g", reuse);
    goto cleanup;
  }
  if (!keep) {
    err = karst_set_error(ctx, KARST_ENOMEM, "skeleton: out of memory");
    goto cleanup;
  }
  if ((err = karst_skeleton_gamma_keep(ctx, n_keys, dist, gamma, keep))) goto cleanup;
  for (karst_int_t i = 0; i < n_keys; i++)
    if ((err = karst_skeleton_mark_node(ctx, sk, g, keys[i], KARST_NODE_INTERIOR))) goto cleanup;
  pairs = malloc((size_t)(n_keys * n_keys / 2 + 1) * sizeof *pairs);
  if (!pairs) {
    err = karst_set_error(ctx, KARST_ENOMEM, "skeleton: out of memory");
    goto cleanup;
  }
  const int sharing = reuse < 1.0;
  for (karst_int_t a = 0; a < n_keys; a++)
    for (karst_int_t b = a + 1; b < n_keys; b++)
      if (keep[a * n_keys + b] && keys[a] != keys[b]) {
        pair_t P = {dist[a * n_keys + b], a, b, keys[a], keys[b], NULL, NULL, NULL, NULL, 0, -1};
        if (sharing) { /* b towards a, with a's row; laid reversed */
          P.src = keys[b], P.dst = keys[a];
          P.row = bound ? bound + (size_t)a * (size_t)g->n : NULL;
        } else {
          P.pred = pred ? pred + (size_t)a * (size_t)g->n : NULL;
        }
        pairs[n_pairs++] = P;
      }
  qsort(pairs, (size_t)n_pairs, sizeof *pairs, pair_cmp);
  lay_t L = {g, lb_per_metre, reuse, sharing, NULL, NULL, NULL};
  err = lay_pairs(ctx, &L, pairs, n_pairs, sk, n_kept);
cleanup:
  free(keep);
  free(pairs);
  return err;
}

/**
 * The skeleton of a routing plan (karst_routing_plan): its routes laid in the plan's order
 * (increasing routed cost), each from its upstream key point to its target on the routed costs of
 * the route's spring, with path sharing (@p reuse < 1: a route follows conduits already laid
 * towards the same spring at reuse × their cost; the heuristic rows are the plan's backward rows)
 * or as the plain union of least-cost paths read from the plan's successor rows (reuse = 1). A
 * route never passes through a sink or a spring (plan->closed). New edges and nodes get the
 * route's spring. The plan's key points (plan->active) get nodes of kind interior here; the caller
 * marks them.
 * Same-network guarantee as karst_skeleton_build on any thread count.
 * @return KARST_SUCCESS, KARST_EINVAL (reuse), KARST_EUNREACHABLE, KARST_ENOMEM,
 *         KARST_EINTERRUPTED.
 * Time complexity: per route the path length (rows) or one A* search.
 */
karst_error_t karst_skeleton_build_routes(karst_ctx_t *ctx, const karst_graph_t *g,
                                          const karst_routing_plan_t *plan, double reuse,
                                          double lb_per_metre, karst_skeleton_t *sk,
                                          karst_int_t *n_kept) {
  karst_error_t err = KARST_SUCCESS;
  if (n_kept) *n_kept = 0;
  if (!(reuse > 0 && reuse <= 1))
    return karst_set_error(ctx, KARST_EINVAL, "skeleton.reuse must be within (0, 1], got %g",
                           reuse);
  for (int k = 0; k < plan->n_keys; k++)
    if ((!plan->active || plan->active[k]) &&
        (err = karst_skeleton_mark_node(ctx, sk, g, k, KARST_NODE_INTERIOR)))
      return err;
  pair_t *pairs = malloc((size_t)(plan->n_pairs > 0 ? plan->n_pairs : 1) * sizeof *pairs);
  if (!pairs) return karst_set_error(ctx, KARST_ENOMEM, "skeleton: out of memory");
  for (int i = 0; i < plan->n_pairs; i++) {
    const karst_route_pair_t *R = &plan->pairs[i];
    size_t row = (size_t)R->target * (size_t)g->n;
    pairs[i] = (pair_t){R->d,
                        R->src,
                        R->dst,
                        R->src,
                        R->dst,
                        plan->bound ? plan->bound + row : NULL,
                        NULL,
                        plan->succ && reuse >= 1.0 ? plan->succ + row : NULL,
                        karst_routing_route(plan, R->spring),
                        (unsigned char)(R->spring + 1),
                        R->spring};
  }
  lay_t L = {g, lb_per_metre, reuse, 0, plan->closed, NULL, NULL};
  err = lay_pairs(ctx, &L, pairs, plan->n_pairs, sk, n_kept);
  free(pairs);
  return err;
}
