/* Network amplification (Paris et al. 2021, §5.2): ramification by new
 * dead-end and interior points, then stochastic midpoint displacement. */
#include "karst/amplification.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "amplification/amplification_internal.h"
#include "core/memory_internal.h"
#include "core/parallel_internal.h"
#include "karst/paths.h"
#include "karst/routing.h"
#include "paths/paths_internal.h"

/* Below this many graph vertices the points are connected on one thread. On the presets (about
 * 50 000 vertices) a point's searches settle a few hundred vertices, less than handing points
 * between threads costs: the looping cave's 759 points took 0.016-0.017 s on 1 thread and
 * 0.026-0.028 s on 2; the ramification of the 402 k-sample block of bench_generate alone gained
 * 1.4-1.8x (docs/performance.md, "Both cores"). */
#define RAMIFY_MIN_VERTICES_THREADED 200000

/** Fill @p opt with the documented defaults (see the field comments). O(1). */
void karst_amplification_options_init(karst_amplification_options_t *opt) {
  opt->ratio_at_theta1 = 0.5;
  opt->min_segment = 1.0;
  opt->max_levels = 3;
  opt->max_tries = 32;
  opt->loop_separation = 1.0;
  opt->threaded_from = RAMIFY_MIN_VERTICES_THREADED;
}

/**
 * Tortuosity θ → the largest midpoint displacement as a fraction of the piece being split:
 * ρ(θ) = θ × ratio_at_theta1 (0.5 by default), θ clamped to [0, 1]. The displacement scales with
 * the length it is applied to, as in the fractal midpoint displacement of Fournier, Fussell &
 * Carpenter (1982) with Hurst exponent 1, so the tortuosity it adds depends on θ alone — not on
 * the sampling radius, which sets the length of the graph's edges (Paris et al. 2021, §5.2 give
 * an absolute amplitude, "from a few centimeters to 4 meters", which on 10 m edges leaves
 * branchworks straighter than any of the 34 caves of Collon et al. 2017; docs/generation.md).
 * O(1).
 */
double karst_amplification_displacement_ratio(const karst_amplification_options_t *opt,
                                              double theta) {
  double t = theta < 0 ? 0 : (theta > 1 ? 1 : theta);
  return t * opt->ratio_at_theta1;
}

/**
 * Inside the bedrock (karst_geology_in_bedrock: the domain box, outside every exclusion zone and
 * insoluble stratum) and strictly below the terrain (as the sampling stage draws). O(exclusions).
 */
int karst_amplification_in_bedrock(const karst_geology_t *g, const double p[3]) {
  return karst_geology_in_bedrock(g, p) && p[2] < karst_geology_terrain(g, p[0], p[1]);
}

static double dist3(const double *a, const double *b) {
  double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return sqrt(dx * dx + dy * dy + dz * dz);
}

/* Block (in @p blocked) the graph vertex of every network node of degree >= 3, listing them in
 * *@p list (grown as needed) for unblock. O(nodes + edges). */
static karst_error_t block_junctions(karst_ctx_t *ctx, const karst_skeleton_t *sk,
                                     unsigned char *blocked, karst_int_t **list, karst_int_t *n) {
  const karst_network_t *net = &sk->net;
  karst_int_t *deg = calloc((size_t)(net->n_nodes > 0 ? net->n_nodes : 1), sizeof *deg);
  karst_int_t *l = realloc(*list, (size_t)(net->n_nodes > 0 ? net->n_nodes : 1) * sizeof *l);
  if (!deg || !l) {
    free(deg);
    if (l) *list = l;
    return karst_set_error(ctx, KARST_ENOMEM, "amplification: out of memory");
  }
  *list = l;
  for (karst_int_t e = 0; e < net->n_edges; e++)
    deg[net->edges[2 * e]]++, deg[net->edges[2 * e + 1]]++;
  *n = 0;
  for (karst_int_t u = 0; u < net->n_nodes; u++)
    if (deg[u] >= 3) {
      karst_int_t w = sk->vertex_of_node[u];
      if (!blocked[w]) blocked[w] = 1, l[(*n)++] = w;
    }
  free(deg);
  return KARST_SUCCESS;
}

static void unblock(unsigned char *blocked, const karst_int_t *list, karst_int_t n) {
  for (karst_int_t k = 0; k < n; k++)
    blocked[list[k]] = 0;
}

/* A uniform grid of the graph's vertices off the network, for nearest-vertex queries. */
typedef struct free_grid {
  double lo[3], h;
  long dim[3];
  karst_int_t *start; /* cell c holds item[start[c] .. start[c + 1]) */
  karst_int_t *item;  /* vertex indices (in any order within a cell) */
} free_grid_t;

static long grid_cell(const free_grid_t *G, const double *p, int k) {
  double c = floor((p[k] - G->lo[k]) / G->h);
  return c < 0 ? 0 : (c >= (double)G->dim[k] ? G->dim[k] - 1 : (long)c);
}

/* The cell of @p p (clamped to the grid), as one index. */
static long grid_index(const free_grid_t *G, const double *p) {
  return (grid_cell(G, p, 2) * G->dim[1] + grid_cell(G, p, 1)) * G->dim[0] + grid_cell(G, p, 0);
}

/* The passes of grid_build over the vertices, split by index range over the threads. */
typedef struct {
  karst_int_t n;
  const double *xyz;
  const unsigned char *in_net;
  free_grid_t *G;
  int pass; /* 0: extent and count, 1: vertices per cell, 2: placed in their cells */
  double (*lo)[3], (*hi)[3];
  karst_int_t *m;    /* per thread (pass 0) */
  karst_int_t *fill; /* per cell: next free slot (pass 2) */
} grid_job_t;

static void grid_task(void *arg, int tid, int nth) {
  grid_job_t *J = arg;
  const karst_int_t v0 = J->n * tid / nth, v1 = J->n * (tid + 1) / nth;
  const double *xyz = J->xyz;
  free_grid_t *G = J->G;
  const int shared = nth > 1; /* cells written by several threads: atomic increments */
  if (J->pass == 0) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    karst_int_t m = 0;
    for (karst_int_t v = v0; v < v1; v++) {
      if (J->in_net[v]) continue;
      m++;
      for (int k = 0; k < 3; k++) {
        if (xyz[3 * v + k] < lo[k]) lo[k] = xyz[3 * v + k];
        if (xyz[3 * v + k] > hi[k]) hi[k] = xyz[3 * v + k];
      }
    }
    memcpy(J->lo[tid], lo, sizeof lo), memcpy(J->hi[tid], hi, sizeof hi), J->m[tid] = m;
  } else if (J->pass == 1) {
    for (karst_int_t v = v0; v < v1; v++) {
      if (J->in_net[v]) continue;
      karst_int_t *c = &G->start[grid_index(G, &xyz[3 * v]) + 1];
      if (shared)
        __atomic_fetch_add(c, 1, __ATOMIC_RELAXED);
      else
        ++*c;
    }
  } else {
    for (karst_int_t v = v0; v < v1; v++) {
      if (J->in_net[v]) continue;
      karst_int_t *f = &J->fill[grid_index(G, &xyz[3 * v])];
      G->item[shared ? __atomic_fetch_add(f, 1, __ATOMIC_RELAXED) : (*f)++] = v;
    }
  }
}

/* Grid of the vertices v with !in_net[v]; *n_free their count. About two per cell. The order of
 * the vertices within a cell depends on the threads (grid_nearest does not depend on it).
 * O(n / threads + cells). */
static karst_error_t grid_build(karst_ctx_t *ctx, karst_int_t n, const double *xyz,
                                const unsigned char *in_net, free_grid_t *G, karst_int_t *n_free) {
  memset(G, 0, sizeof *G);
  int T = ctx && ctx->nthreads > 1 && n >= 65536 ? ctx->nthreads : 1;
  if (T > KARST_I_MAX_THREADS) T = KARST_I_MAX_THREADS;
  grid_job_t J = {n, xyz, in_net, G, 0, NULL, NULL, NULL, NULL};
  J.lo = malloc((size_t)T * sizeof *J.lo), J.hi = malloc((size_t)T * sizeof *J.hi);
  J.m = malloc((size_t)T * sizeof *J.m);
  if (!J.lo || !J.hi || !J.m) {
    free(J.lo), free(J.hi), free(J.m);
    return karst_set_error(ctx, KARST_ENOMEM, "amplification: out of memory");
  }
  karst_i_parallel_run(T, grid_task, &J);
  double hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  G->lo[0] = G->lo[1] = G->lo[2] = INFINITY;
  karst_int_t m = 0;
  for (int t = 0; t < T; t++) {
    m += J.m[t];
    for (int k = 0; k < 3; k++)
      G->lo[k] = fmin(G->lo[k], J.lo[t][k]), hi[k] = fmax(hi[k], J.hi[t][k]);
  }
  free(J.lo), free(J.hi), free(J.m);
  *n_free = m;
  if (m == 0) return KARST_SUCCESS;
  double ext[3], vol = 1;
  for (int k = 0; k < 3; k++) {
    ext[k] = hi[k] - G->lo[k];
    if (!(ext[k] > 0)) ext[k] = 0;
  }
  double big = fmax(ext[0], fmax(ext[1], ext[2]));
  for (int k = 0; k < 3; k++)
    vol *= fmax(ext[k], 1e-6 * big + 1e-12);
  G->h = cbrt(2 * vol / (double)m);
  if (!(G->h > 0) || !isfinite(G->h)) G->h = 1;
  long cells;
  for (;;) { /* a flat or thin set of vertices: coarser cells, at most about 4 per vertex */
    double prod = 1;
    for (int k = 0; k < 3; k++)
      prod *= floor(ext[k] / G->h) + 1;
    if (prod <= 4.0 * (double)m + 64) break;
    G->h *= 1.25;
  }
  cells = 1;
  for (int k = 0; k < 3; k++) {
    G->dim[k] = (long)(floor(ext[k] / G->h) + 1);
    cells *= G->dim[k];
  }
  G->start = calloc((size_t)cells + 1, sizeof *G->start);
  G->item = malloc((size_t)m * sizeof *G->item);
  if (!G->start || !G->item)
    return karst_set_error(ctx, KARST_ENOMEM, "amplification: out of memory");
  J.pass = 1;
  karst_i_parallel_run(T, grid_task, &J);
  for (long c = 0; c < cells; c++)
    G->start[c + 1] += G->start[c];
  J.fill = malloc((size_t)cells * sizeof *J.fill);
  if (!J.fill) return karst_set_error(ctx, KARST_ENOMEM, "amplification: out of memory");
  memcpy(J.fill, G->start, (size_t)cells * sizeof *J.fill);
  J.pass = 2;
  karst_i_parallel_run(T, grid_task, &J);
  free(J.fill);
  return KARST_SUCCESS;
}

/* The nearest vertex of the grid to @p p, ties to the smaller index (as a scan of every vertex
 * in ascending order with a strict '<' finds): shells of cells at Chebyshev distance r around
 * p's cell until the best distance is below (r - 1) h, the least distance of shell r. O(1)
 * expected for points among the vertices. */
static karst_int_t grid_nearest(const free_grid_t *G, const double *xyz, const double *p) {
  long c0[3];
  for (int k = 0; k < 3; k++)
    c0[k] = grid_cell(G, p, k);
  long rmax = G->dim[0] > G->dim[1] ? G->dim[0] : G->dim[1];
  if (G->dim[2] > rmax) rmax = G->dim[2];
  double best = INFINITY;
  karst_int_t bv = -1;
  for (long r = 0; r <= rmax; r++) {
    /* p lies in its cell (or beyond the grid's side): shell r is at least (r - 1) h away */
    if (r > 0 && best < (double)(r - 1) * G->h) break;
    long lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
      lo[k] = c0[k] - r < 0 ? 0 : c0[k] - r;
      hi[k] = c0[k] + r >= G->dim[k] ? G->dim[k] - 1 : c0[k] + r;
    }
    for (long z = lo[2]; z <= hi[2]; z++)
      for (long y = lo[1]; y <= hi[1]; y++) {
        int face = labs(z - c0[2]) == r || labs(y - c0[1]) == r;
        for (long x = lo[0]; x <= hi[0]; x++) {
          if (!face && labs(x - c0[0]) != r) continue; /* inside the shell: done before */
          long c = (z * G->dim[1] + y) * G->dim[0] + x;
          for (karst_int_t j = G->start[c]; j < G->start[c + 1]; j++) {
            karst_int_t v = G->item[j];
            double d = dist3(&xyz[3 * v], p);
            if (d < best || (d == best && v < bv)) best = d, bv = v;
          }
        }
      }
  }
  return bv;
}

/* snap[i]: the vertex off the network nearest to point i, -1 when there is none (see
 * amplification_internal.h). O(n + points) expected. */
karst_error_t karst_i_amplification_snap(karst_ctx_t *ctx, karst_int_t n, const double *xyz,
                                         const unsigned char *in_net, const double *pts, int n_pts,
                                         karst_int_t *snap) {
  free_grid_t G;
  karst_int_t m = 0;
  karst_error_t err = grid_build(ctx, n, xyz, in_net, &G, &m);
  for (int i = 0; i < n_pts; i++)
    snap[i] = err || m == 0 ? -1 : grid_nearest(&G, xyz, &pts[3 * i]);
  free(G.start);
  free(G.item);
  return err;
}

/* The paper's draw (§5.2): @p n points uniformly in the bounding box of @p net clipped to the
 * domain, each kept only in the bedrock (max_tries draws, else dropped). Returns the count. */
static int draw_in_box(const karst_geology_t *geo, const karst_amplification_options_t *opt,
                       karst_rng_t *rng, const karst_network_t *net, int n, double *pts) {
  const karst_scenario_t *sc = karst_geology_scenario(geo);
  double lo[3], hi[3];
  for (int k = 0; k < 3; k++)
    lo[k] = hi[k] = net->xyz[k];
  for (karst_int_t v = 1; v < net->n_nodes; v++)
    for (int k = 0; k < 3; k++) {
      lo[k] = fmin(lo[k], net->xyz[3 * v + k]);
      hi[k] = fmax(hi[k], net->xyz[3 * v + k]);
    }
  for (int k = 0; k < 3; k++) {
    lo[k] = fmax(lo[k], sc->domain_min[k]);
    hi[k] = fmin(hi[k], sc->domain_max[k]);
  }
  int n_pts = 0;
  for (int i = 0; i < n; i++) {
    for (int t = 0; t < opt->max_tries; t++) {
      double p[3];
      for (int k = 0; k < 3; k++)
        p[k] = karst_rng_uniform_range(rng, lo[k], hi[k] > lo[k] ? hi[k] : lo[k]);
      if (hi[2] <= lo[2]) p[2] = lo[2];
      if (karst_amplification_in_bedrock(geo, p)) {
        memcpy(&pts[3 * n_pts], p, sizeof p);
        n_pts++;
        break;
      }
    }
  }
  return n_pts;
}

/* The hierarchical draw: each of @p n points picks a point uniformly along the paths the
 * previous step added (amplification_step == @p parent, the skeleton for the first step) when
 * @p previous_only, else along the whole network grown so far (amplification_step <= @p parent);
 * every edge when the previous step added none: an edge with probability proportional to its
 * length, then a uniform position on it, and moves from it uniformly within the ball of radius @p
 * reach (rejection from the cube), kept only in the bedrock (max_tries draws of both, else
 * dropped). Returns the count, or -1 when out of memory. O(E log E + n × max_tries × log E). */
static int draw_near(const karst_geology_t *geo, const karst_amplification_options_t *opt,
                     karst_rng_t *rng, const karst_network_t *net, double reach, int parent,
                     int previous_only, int n, double *pts) {
  karst_int_t ne = net->n_edges;
  if (ne == 0) return draw_in_box(geo, opt, rng, net, n, pts);
  const karst_attr_t *st = karst_network_attr_find(net, KARST_ATTR_EDGE, "amplification_step");
  double *cum = malloc((size_t)ne * sizeof *cum);
  if (!cum) return -1;
  double total = 0;
  for (int pass = 0; pass < 2 && !(total > 0); pass++) /* pass 1: every edge */
    for (karst_int_t e = 0; e < ne; e++) {
      if (pass == 0 && st && (previous_only ? st->data[e] != parent : st->data[e] > parent)) {
        cum[e] = total;
        continue;
      }
      total += dist3(&net->xyz[3 * net->edges[2 * e]], &net->xyz[3 * net->edges[2 * e + 1]]);
      cum[e] = total;
    }
  int n_pts = 0;
  for (int i = 0; i < n; i++) {
    for (int t = 0; t < opt->max_tries; t++) {
      double x = karst_rng_uniform(rng) * total;
      karst_int_t lo = 0, hi = ne - 1; /* first edge with cum > x */
      while (lo < hi) {
        karst_int_t mid = lo + (hi - lo) / 2;
        if (cum[mid] > x)
          hi = mid;
        else
          lo = mid + 1;
      }
      const double *a = &net->xyz[3 * net->edges[2 * lo]],
                   *b = &net->xyz[3 * net->edges[2 * lo + 1]];
      double u = karst_rng_uniform(rng), d[3], r2;
      do {
        r2 = 0;
        for (int k = 0; k < 3; k++) {
          d[k] = karst_rng_uniform_range(rng, -1, 1);
          r2 += d[k] * d[k];
        }
      } while (r2 > 1);
      double p[3];
      for (int k = 0; k < 3; k++)
        p[k] = a[k] + u * (b[k] - a[k]) + reach * d[k];
      if (karst_amplification_in_bedrock(geo, p)) {
        memcpy(&pts[3 * n_pts], p, sizeof p);
        n_pts++;
        break;
      }
    }
  }
  free(cum);
  return n_pts;
}

/*
 * The points of a step on ctx->nthreads threads, with the network of the one-thread loop (Paris
 * et al. 2021 connect them in order, each to the network grown so far; issue 17).
 *
 * A thread takes the first point not yet computed within a window ahead of the next point to
 * commit, and computes its paths on its own copy of the network membership (in_net) as it was
 * after the commits so far, and of the blocked junctions; it records every vertex its searches
 * touched (its trail). Points are committed in order, under the lock. A point computed before
 * the commits since then is kept only if
 * - the spring its nearest network node drains to is the same on the current network, and
 * - its trail meets no vertex those commits changed (the vertices of their paths: the only ones
 *   whose membership or degree a path changes).
 * A search reads the membership and the blocking of the vertices it touches only (a blocked
 * vertex stays blocked: degrees only grow), and the second path's cleared nodes differ only by
 * nodes added since, which were off the network in its copy as in the cleared one. So a kept
 * point's searches ran exactly as on the current network; any other is computed again. On one
 * thread every point is computed on the current network: the plain loop.
 */
enum { PROP_TODO, PROP_RUNNING, PROP_READY };

typedef struct {
  int state;
  uint32_t since; /* the commits of this step made when it was computed */
  int taken;      /* no free vertex, or its vertex was on the network: nothing to connect */
  int dead;       /* stopped: an earlier point's paths met what its searches had read */
  int spring;     /* the spring of its nearest network node (-1 without a plan) */
  karst_int_t pv, v1;
  karst_path_t p1, p2;
  int32_t *trail; /* the vertices its searches touched; n_trail < 0: unknown (no memory) */
  karst_int_t n_trail, cap_trail;
  karst_error_t err;
  char msg[KARST_ERRMSG_MAX];
} ramify_prop_t;

/* One thread's copy of what a point's computation reads of the network. */
typedef struct {
  karst_search_t *s;
  unsigned char *in_net, *blocked;
  size_t applied;     /* entries of the change log applied to in_net */
  karst_int_t *junc;  /* junctions to block, then unblock */
  karst_int_t n_junc; /* (grown by block_junctions) */
  double *nxyz;       /* network nodes: position, spring, graph vertex */
  double *nspring;
  karst_int_t *nvert, n_nodes, cap_nodes;
  karst_int_t *cleared;
  karst_ctx_t wctx;
  karst_error_t setup_err;
} ramify_thread_t;

typedef struct {
  karst_ctx_t *ctx;
  const karst_graph_t *g;
  const karst_routing_plan_t *plan;
  const karst_amplification_options_t *opt;
  karst_skeleton_t *sk;
  const karst_int_t *snap;
  int n_pts, n_dead, step, window;
  ramify_thread_t *th;
  ramify_prop_t *prop;
  pthread_mutex_t mu;
  pthread_cond_t cv;
  /* under mu: */
  int commit, stop;
  karst_error_t err;
  unsigned char *in_net; /* the network's vertices, as committed */
  uint32_t *mark;        /* per vertex: the commit of this step that last changed it (0: none) */
  /* commits of this step that changed the network: written under mu, also read without it by
   * the searches (ramify_check) */
  atomic_uint n_commits;
  int32_t *log; /* vertices put on the network, in order (at most n) */
  size_t n_log;
  karst_int_t added_points, added_paths, recomputed;
} ramify_par_t;

/* The spring of the network node nearest @p p, the first on ties (-1: no "spring" attribute). */
static int nearest_spring(karst_int_t n, const double *xyz, const double *spring, const double *p) {
  double best = INFINITY;
  int s = -1;
  for (karst_int_t u = 0; u < n; u++) {
    double d = dist3(&xyz[3 * u], p);
    if (d < best) best = d, s = (int)spring[u];
  }
  return s;
}

/* Copy into the thread what point computations read of the network now. Under mu. */
static karst_error_t ramify_sync(ramify_par_t *R, ramify_thread_t *T) {
  for (; T->applied < R->n_log; T->applied++)
    T->in_net[R->log[T->applied]] = 1;
  const karst_network_t *net = &R->sk->net;
  if (net->n_nodes > T->cap_nodes) {
    karst_int_t cap = 2 * net->n_nodes;
    double *x = realloc(T->nxyz, (size_t)cap * 3 * sizeof *x);
    if (x) T->nxyz = x;
    double *s = realloc(T->nspring, (size_t)cap * sizeof *s);
    if (s) T->nspring = s;
    karst_int_t *v = realloc(T->nvert, (size_t)cap * sizeof *v);
    if (v) T->nvert = v;
    karst_int_t *c = realloc(T->cleared, (size_t)cap * sizeof *c);
    if (c) T->cleared = c;
    if (!x || !s || !v || !c)
      return karst_set_error(&T->wctx, KARST_ENOMEM, "amplification: out of memory");
    T->cap_nodes = cap;
  }
  /* Nodes are only appended, and a node's position, vertex and spring never change: copy the
   * new ones. */
  const karst_int_t from = T->n_nodes, add = net->n_nodes - from;
  memcpy(T->nxyz + 3 * from, net->xyz + 3 * from, (size_t)add * 3 * sizeof *T->nxyz);
  memcpy(T->nvert + from, R->sk->vertex_of_node + from, (size_t)add * sizeof *T->nvert);
  const karst_attr_t *sp = karst_network_attr_find(net, KARST_ATTR_NODE, "spring");
  if (sp) memcpy(T->nspring + from, sp->data + from, (size_t)add * sizeof *T->nspring);
  T->n_nodes = net->n_nodes;
  return block_junctions(&T->wctx, R->sk, T->blocked, &T->junc, &T->n_junc);
}

/* Keep the trail of the search just run in @p P (appended). */
static void keep_trail(ramify_prop_t *P, const karst_search_t *s) {
  karst_int_t n = 0;
  const int32_t *t = karst_search_trail(s, &n);
  if (P->n_trail < 0) return;
  if (P->n_trail + n > P->cap_trail) {
    karst_int_t cap = 2 * (P->n_trail + n);
    int32_t *nt = realloc(P->trail, (size_t)cap * sizeof *nt);
    if (!nt) {
      P->n_trail = -1;
      return;
    }
    P->trail = nt, P->cap_trail = cap;
  }
  memcpy(P->trail + P->n_trail, t, (size_t)n * sizeof *t);
  P->n_trail += n;
}

/* A point's search under way, as ramify_check sees it. */
typedef struct {
  ramify_par_t *R;
  ramify_prop_t *P;
  const karst_search_t *s;
  uint32_t seen;    /* the commits its trail has been checked against */
  karst_int_t upto; /* entries of the search's trail checked against them */
} ramify_run_t;

/* Polled by a point's searches every 256 settled vertices. Once paths have been committed since
 * the point's copy of the network, whether they meet what its searches have touched so far
 * (then it would be computed again anyway: stop now): after each new commit the whole trail,
 * else the entries added since the last poll. Non-zero to stop. */
static int ramify_check(void *arg) {
  ramify_run_t *run = arg;
  ramify_par_t *R = run->R;
  ramify_prop_t *P = run->P;
  const uint32_t c = atomic_load_explicit(&R->n_commits, memory_order_acquire);
  if (c == P->since) return 0; /* nothing committed since its copy */
  karst_int_t n = 0, from = run->upto;
  const int32_t *t = karst_search_trail(run->s, &n);
  pthread_mutex_lock(&R->mu);
  int dead = R->stop;
  if (c != run->seen) {                                   /* a new commit: everything read so far */
    for (karst_int_t k = 0; !dead && k < P->n_trail; k++) /* the first search's (in the second) */
      dead = R->mark[P->trail[k]] > P->since;
    from = 0;
  }
  for (karst_int_t k = from; !dead && k < n; k++)
    dead = R->mark[t[k]] > P->since;
  pthread_mutex_unlock(&R->mu);
  run->seen = c, run->upto = n;
  return P->dead = dead;
}

/* Point @p i's paths on the thread's copy of the network (blocked junctions already set); if
 * ramify_check stops a search, P->dead. */
static karst_error_t ramify_compute(ramify_par_t *R, ramify_thread_t *T, int i, ramify_prop_t *P) {
  const karst_graph_t *g = R->g;
  karst_ctx_t *ctx = &T->wctx;
  karst_error_t err = KARST_SUCCESS;
  const karst_int_t pv = R->snap[i];
  P->pv = pv, P->v1 = -1, P->p1.n = 0, P->p2.n = 0, P->n_trail = 0, P->spring = -1, P->dead = 0;
  ramify_run_t run = {R, P, T->s, P->since, 0};
  P->taken = pv < 0 || T->in_net[pv];
  if (P->taken) return KARST_SUCCESS;
  const karst_route_t *route = NULL;
  if (R->plan) {
    P->spring = nearest_spring(T->n_nodes, T->nxyz, T->nspring, &g->xyz[3 * pv]);
    route = karst_routing_route(R->plan, P->spring);
  }
  unsigned char *in_net = T->in_net, *blocked = T->blocked;
  err = karst_i_paths_dijkstra_checked(ctx, T->s, route, 1, &pv, blocked, in_net, 1, &P->v1,
                                       ramify_check, &run);
  if (P->dead) return KARST_SUCCESS;
  if (err) return err;
  keep_trail(P, T->s);
  if (P->v1 < 0) return KARST_SUCCESS;
  if ((err = karst_search_path_to(ctx, T->s, P->v1, &P->p1))) return err;
  if (i < R->n_dead) return KARST_SUCCESS;
  /* Interior point: a second path, disjoint from the first, to a distinct part. */
  const double sep = R->opt->loop_separation * dist3(&g->xyz[3 * pv], &g->xyz[3 * P->v1]);
  karst_int_t n_cleared = 0, v2 = -1;
  for (karst_int_t u = 0; u < T->n_nodes; u++)
    if (dist3(&T->nxyz[3 * u], &g->xyz[3 * P->v1]) <= sep) {
      karst_int_t w = T->nvert[u];
      in_net[w] = 0;
      T->cleared[n_cleared++] = w;
    }
  for (karst_int_t k = 1; k < P->p1.n; k++)
    blocked[P->p1.v[k]] = 1;
  run.upto = 0, run.seen = P->since; /* the second search's trail, and the first's again */
  err = karst_i_paths_dijkstra_checked(ctx, T->s, route, 1, &pv, blocked, in_net, 1, &v2,
                                       ramify_check, &run);
  for (karst_int_t k = 1; k < P->p1.n; k++)
    blocked[P->p1.v[k]] = 0;
  for (karst_int_t k = 0; k < n_cleared; k++)
    in_net[T->cleared[k]] = 1;
  if (P->dead) return KARST_SUCCESS;
  if (err) return err;
  keep_trail(P, T->s);
  if (v2 >= 0) err = karst_search_path_to(ctx, T->s, v2, &P->p2);
  return err;
}

static void ramify_fail(ramify_par_t *R, karst_error_t err) {
  if (!R->err) R->err = err;
  R->stop = 1;
  pthread_cond_broadcast(&R->cv);
}

/* Commit point R->commit, ready, if it still holds (see above); else it is to be computed again.
 * Under mu. */
static void ramify_commit_one(ramify_par_t *R) {
  ramify_prop_t *P = &R->prop[R->commit];
  karst_ctx_t *ctx = R->ctx;
  karst_skeleton_t *sk = R->sk;
  const karst_graph_t *g = R->g;
  karst_error_t err;
  if (karst_interrupted(ctx)) {
    ramify_fail(R, karst_set_error(ctx, KARST_EINTERRUPTED, "amplification interrupted"));
    return;
  }
  if (P->err) {
    ramify_fail(R, karst_set_error(ctx, P->err, "%s", P->msg));
    return;
  }
  const karst_int_t pv = P->pv;
  int skip = P->taken || R->in_net[pv]; /* its vertex taken by an earlier point */
  if (!skip && P->since != atomic_load_explicit(&R->n_commits, memory_order_relaxed)) {
    int valid = P->n_trail >= 0;
    if (valid && R->plan) {
      const karst_attr_t *sp = karst_network_attr_find(&sk->net, KARST_ATTR_NODE, "spring");
      valid = nearest_spring(sk->net.n_nodes, sk->net.xyz, sp->data, &g->xyz[3 * pv]) == P->spring;
    }
    for (karst_int_t k = 0; valid && k < P->n_trail; k++)
      valid = R->mark[P->trail[k]] <= P->since;
    if (!valid) {
      P->state = PROP_TODO;
      R->recomputed++;
      return;
    }
  }
  P->state = PROP_TODO; /* consumed */
  R->commit++;
  if (skip) return;
  if (P->v1 < 0) {
    karst_log(ctx, KARST_LOG_DEBUG, "amplification: point at vertex %lld cannot reach the network",
              (long long)pv);
    return;
  }
  if ((err = karst_skeleton_add_route(ctx, sk, g, &P->p1, R->step, P->spring))) goto fail;
  R->added_paths++;
  if (P->p2.n > 0) {
    if ((err = karst_skeleton_add_route(ctx, sk, g, &P->p2, R->step, P->spring))) goto fail;
    R->added_paths++;
  }
  if ((err = karst_skeleton_mark_node(ctx, sk, g, pv, KARST_NODE_AMPLIFICATION))) goto fail;
  R->added_points++;
  const uint32_t id = atomic_load_explicit(&R->n_commits, memory_order_relaxed) + 1;
  for (int pass = 0; pass < 2; pass++) {
    const karst_path_t *p = pass ? &P->p2 : &P->p1;
    for (karst_int_t k = 0; k < p->n; k++) {
      karst_int_t v = p->v[k];
      R->mark[v] = id;
      if (!R->in_net[v]) R->in_net[v] = 1, R->log[R->n_log++] = (int32_t)v;
    }
  }
  atomic_store_explicit(&R->n_commits, id, memory_order_release);
  return;
fail:
  ramify_fail(R, err);
}

/* Each thread makes its own workspace and copies (their pages first touched on that thread). */
static void ramify_setup(void *arg, int tid, int nthreads) {
  (void)nthreads;
  ramify_par_t *R = arg;
  ramify_thread_t *T = &R->th[tid];
  const size_t n = (size_t)(R->g->n > 0 ? R->g->n : 1);
  karst_ctx_init(&T->wctx);
  karst_error_t err = karst_search_create(&T->wctx, R->g, &T->s);
  if (!err) err = karst_search_record_trail(&T->wctx, T->s);
  if (!err) {
    T->in_net = karst_i_alloc_large(n);
    T->blocked = karst_i_calloc_large(n, 1);
    if (!T->in_net || !T->blocked)
      err = karst_set_error(&T->wctx, KARST_ENOMEM, "amplification: out of memory");
  }
  T->setup_err = err;
}

static void ramify_worker(void *arg, int tid, int nthreads) {
  (void)nthreads;
  ramify_par_t *R = arg;
  ramify_thread_t *T = &R->th[tid];
  pthread_mutex_lock(&R->mu);
  /* The network's vertices as they stand (another thread may have committed already). */
  memcpy(T->in_net, R->in_net, (size_t)(R->g->n > 0 ? R->g->n : 1));
  T->applied = R->n_log;
  while (!R->stop && R->commit < R->n_pts) {
    if (R->prop[R->commit].state == PROP_READY) {
      ramify_commit_one(R);
      pthread_cond_broadcast(&R->cv);
      continue;
    }
    int i = R->commit, end = R->commit + R->window < R->n_pts ? R->commit + R->window : R->n_pts;
    while (i < end && R->prop[i].state != PROP_TODO)
      i++;
    if (i == end) {
      pthread_cond_wait(&R->cv, &R->mu);
      continue;
    }
    ramify_prop_t *P = &R->prop[i];
    P->state = PROP_RUNNING;
    P->since = atomic_load_explicit(&R->n_commits, memory_order_relaxed);
    karst_error_t err = ramify_sync(R, T);
    pthread_mutex_unlock(&R->mu);
    if (!err) err = ramify_compute(R, T, i, P);
    unblock(T->blocked, T->junc, T->n_junc);
    pthread_mutex_lock(&R->mu);
    P->err = err;
    if (err)
      snprintf(P->msg, sizeof P->msg, "%s",
               T->wctx.errmsg[0] ? T->wctx.errmsg : "amplification: out of memory");
    P->state = P->dead ? PROP_TODO : PROP_READY; /* stopped: to be computed again */
    R->recomputed += P->dead;
    pthread_cond_broadcast(&R->cv);
  }
  pthread_cond_broadcast(&R->cv);
  pthread_mutex_unlock(&R->mu);
}

/**
 * Ramification (Paris et al. 2021, §5.2): sc->amplification.steps steps; step
 * s has karst_amplification_step_points(am, s) points (points × points_ratio^(s−1)).
 * With reach = 0 (the paper's draw) they are drawn uniformly in the bounding
 * box of the current network (clipped to the domain); with reach > 0 each is
 * drawn within reach_ratio^(s−1) × reach of a point taken uniformly along the
 * previous step's paths (anchor previous) or the whole network (anchor
 * network): a hierarchy of ever shorter tributaries (docs/generation.md).
 * Either way a point is kept only inside the bedrock (rejection, at most
 * opt->max_tries draws per point; a point that finds no bedrock is dropped). Each point is snapped
 * to the nearest graph vertex that is not yet on the network (the sample cloud is a Poisson set, so
 * the snap moves it by at most about the fill radius). The first round(dead_end_fraction × points)
 * points of a step are dead ends: one least-cost path to the nearest network vertex (a Dijkstra
 * from the point that stops at the first network vertex it settles — the same as a multi-source
 * Dijkstra from the network, since costs are symmetric). The others are interior points: a second
 * least-cost path, vertex-disjoint from the first, to a network vertex farther than
 * opt->loop_separation × |p − first end| from the first end, so the two paths close a loop through
 * distinct parts of the network (when no such path exists the point stays a
 * dead end). Points connect in order, each to the network grown so far; with
 * ctx->nthreads > 1 later points are computed ahead on the other threads and kept only when
 * what they read is unchanged (ramify_worker), so the network is the same on any number of
 * threads. New paths may not end at a network junction (a vertex of degree >= 3): a
 * tributary joins a passage, so no amplification raises a node above degree 3
 * and the degree distribution keeps the spread of real caves.
 * New edges get amplification_step = s (1-based) and a new branch id.
 *
 * @param geo      the geology (bedrock, and its scenario's amplification parameters).
 * @param g        the sample graph the network lives on.
 * @param plan     the routing plan whose routed costs the new paths follow (each point's
 *                 paths on the route of the spring its nearest network node drains to), or
 *                 NULL for the base costs.
 * @param rng      the amplification stream.
 * @param opt      constants (NULL: defaults).
 * @param sk       the network to grow.
 * @param n_points receives the number of points connected (may be NULL).
 * @param n_paths  receives the number of paths added (may be NULL).
 * @return KARST_SUCCESS, KARST_EINVAL (bad parameters), KARST_ENOMEM, KARST_EINTERRUPTED.
 * Time complexity: O(Σ_s (T n + points_s × (nodes + edges + local Dijkstra))), points_s the
 * points of step s, T the threads (each keeps its own copy of the network's vertices); memory
 * O(T n).
 */
karst_error_t karst_amplification_ramify(karst_ctx_t *ctx, const karst_geology_t *geo,
                                         const karst_graph_t *g, const karst_routing_plan_t *plan,
                                         karst_rng_t *rng, const karst_amplification_options_t *opt,
                                         karst_skeleton_t *sk, karst_int_t *n_points,
                                         karst_int_t *n_paths) {
  const karst_scenario_t *sc = karst_geology_scenario(geo);
  karst_amplification_options_t defaults;
  if (!opt) karst_amplification_options_init(&defaults), opt = &defaults;
  const karst_amplification_t *am = &sc->amplification;
  karst_error_t err = KARST_SUCCESS;
  unsigned char *in_net = NULL;
  double *pts = NULL;
  karst_int_t *snap = NULL;
  /* On a small graph a point's searches cost less than handing the points between threads. */
  const int T = ctx && ctx->nthreads > 1 && g->n >= opt->threaded_from
                    ? (ctx->nthreads < KARST_I_MAX_THREADS ? ctx->nthreads : KARST_I_MAX_THREADS)
                    : 1;
  int sync_ready = 0;
  ramify_par_t R;
  memset(&R, 0, sizeof R);
  size_t max_pts = 1;
  if (am->steps < 0 || am->points < 0 ||
      !(am->dead_end_fraction >= 0 && am->dead_end_fraction <= 1))
    return karst_set_error(ctx, KARST_EINVAL,
                           "amplification: steps (%d) and points (%d) must be >= 0 and "
                           "dead_end_fraction (%g) within [0, 1]",
                           am->steps, am->points, am->dead_end_fraction);
  if (am->steps == 0 || am->points == 0 || sk->net.n_nodes == 0) goto cleanup;
  size_t n = (size_t)(g->n > 0 ? g->n : 1);
  double largest = 0;
  karst_amplification_points_total(am, INFINITY, &largest);
  max_pts = largest > 1 ? (size_t)largest : 1;
  in_net = karst_i_calloc_large(n, 1);
  pts = malloc(max_pts * 3 * sizeof *pts);
  snap = malloc(max_pts * sizeof *snap);
  R.th = calloc((size_t)T, sizeof *R.th);
  R.prop = calloc(max_pts, sizeof *R.prop);
  R.mark = karst_i_alloc_large(n * sizeof *R.mark);
  R.log = karst_i_alloc_large(n * sizeof *R.log);
  if (!in_net || !pts || !snap || !R.th || !R.prop || !R.mark || !R.log) goto nomem;
  for (size_t i = 0; i < max_pts; i++)
    karst_path_init(&R.prop[i].p1), karst_path_init(&R.prop[i].p2);
  R.g = g;
  karst_i_parallel_run(T, ramify_setup, &R);
  for (int t = 0; t < T; t++)
    if (R.th[t].setup_err) {
      err = karst_set_error(ctx, R.th[t].setup_err, "%s", R.th[t].wctx.errmsg);
      goto cleanup;
    }
  if (pthread_mutex_init(&R.mu, NULL)) {
    err = karst_set_error(ctx, KARST_ENOMEM, "amplification: cannot create a mutex");
    goto cleanup;
  }
  if (pthread_cond_init(&R.cv, NULL)) {
    pthread_mutex_destroy(&R.mu);
    err = karst_set_error(ctx, KARST_ENOMEM, "amplification: cannot create a condition variable");
    goto cleanup;
  }
  sync_ready = 1;
  R.ctx = ctx, R.plan = plan, R.opt = opt, R.sk = sk, R.snap = snap, R.in_net = in_net;
  R.window = 3 * T;
  for (karst_int_t v = 0; v < g->n; v++)
    in_net[v] = sk->node_of_vertex[v] >= 0;
  double reach = am->reach, n_next = am->points; /* karst_amplification_step_points, running */
  for (int step = 1; step <= am->steps; step++) {
    const int n_step = n_next >= 0.5 ? (int)floor(n_next + 0.5) : 0;
    if (n_next >= 0.5) n_next *= am->points_ratio;
    const int n_dead = (int)llround(am->dead_end_fraction * n_step);
    if (n_step == 0) break; /* later steps have no more points (points_ratio <= 1) */
    int n_pts = am->reach > 0 ? draw_near(geo, opt, rng, &sk->net, reach, step - 1,
                                          am->anchor == KARST_ANCHOR_PREVIOUS, n_step, pts)
                              : draw_in_box(geo, opt, rng, &sk->net, n_step, pts);
    if (n_pts < 0) goto nomem;
    reach *= am->reach_ratio;
    /* Snap every point to its nearest vertex off the network (ties: the smaller index). */
    if ((err = karst_i_amplification_snap(ctx, g->n, g->xyz, in_net, pts, n_pts, snap)))
      goto cleanup;
    /* Connect the points in order, each to the network grown so far (see ramify_worker). */
    R.n_pts = n_pts, R.n_dead = n_dead, R.step = step;
    R.commit = 0, R.n_log = 0;
    atomic_store(&R.n_commits, 0);
    memset(R.mark, 0, n * sizeof *R.mark);
    for (int i = 0; i < n_pts; i++)
      R.prop[i].state = PROP_TODO;
    karst_i_parallel_run(T, ramify_worker, &R);
    if ((err = R.err)) goto cleanup;
  }
  karst_log(ctx, KARST_LOG_DEBUG, "amplification: %lld points on %d threads, %lld computed again",
            (long long)R.added_points, T, (long long)R.recomputed);
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "amplification: out of memory");
cleanup:
  if (n_points) *n_points = R.added_points;
  if (n_paths) *n_paths = R.added_paths;
  if (sync_ready) pthread_cond_destroy(&R.cv), pthread_mutex_destroy(&R.mu);
  if (R.th)
    for (int t = 0; t < T; t++) {
      ramify_thread_t *th = &R.th[t];
      karst_search_free(th->s);
      free(th->in_net);
      free(th->blocked);
      free(th->junc);
      free(th->nxyz);
      free(th->nspring);
      free(th->nvert);
      free(th->cleared);
    }
  if (R.prop)
    for (size_t i = 0; i < max_pts; i++) {
      karst_path_destroy(&R.prop[i].p1);
      karst_path_destroy(&R.prop[i].p2);
      free(R.prop[i].trail);
    }
  free(R.th);
  free(R.prop);
  free(R.mark);
  free(R.log);
  free(in_net);
  free(pts);
  free(snap);
  return err;
}

/* A uniformly random unit vector orthogonal to unit vector t (rejection on degenerate draws). */
static void random_orthogonal(karst_rng_t *rng, const double t[3], double u[3]) {
  for (;;) {
    karst_rng_unit_vector(rng, u);
    double d = u[0] * t[0] + u[1] * t[1] + u[2] * t[2];
    for (int k = 0; k < 3; k++)
      u[k] -= d * t[k];
    double l = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (l > 1e-3) { /* the unit draw was not (nearly) parallel to t */
      for (int k = 0; k < 3; k++)
        u[k] /= l;
      return;
    }
  }
}

typedef struct {
  const karst_geology_t *geo;
  const karst_amplification_options_t *opt;
  karst_rng_t *rng;
  double *pts; /* growing list of intermediate points of the current edge */
  karst_int_t n, cap;
} subdiv_t;

static int push_point(subdiv_t *sd, const double p[3]) {
  if (sd->n == sd->cap) {
    karst_int_t cap = sd->cap ? 2 * sd->cap : 16;
    double *np = realloc(sd->pts, (size_t)cap * 3 * sizeof *np);
    if (!np) return -1;
    sd->pts = np;
    sd->cap = cap;
  }
  memcpy(&sd->pts[3 * sd->n++], p, 3 * sizeof *p);
  return 0;
}

/* Midpoint displacement of segment a–b: emits the interior points in order. */
static int subdivide(subdiv_t *sd, const double a[3], const double b[3], double ratio, int level) {
  double len = dist3(a, b);
  if (level >= sd->opt->max_levels || len < 2 * sd->opt->min_segment || !(ratio > 0)) return 0;
  double t[3] = {(b[0] - a[0]) / len, (b[1] - a[1]) / len, (b[2] - a[2]) / len};
  double m[3] = {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
  double A = ratio * len;
  double q[3];
  memcpy(q, m, sizeof q);
  for (int tries = 0; tries < sd->opt->max_tries; tries++) {
    double u[3];
    random_orthogonal(sd->rng, t, u);
    double r = A * karst_rng_uniform(sd->rng);
    double c[3] = {m[0] + r * u[0], m[1] + r * u[1], m[2] + r * u[2]};
    if (karst_amplification_in_bedrock(sd->geo, c)) {
      memcpy(q, c, sizeof q);
      break;
    }
  }
  if (subdivide(sd, a, q, ratio, level + 1)) return -1;
  if (push_point(sd, q)) return -1;
  return subdivide(sd, q, b, ratio, level + 1);
}

/**
 * Stochastic midpoint displacement (Paris et al. 2021, §5.2; Fournier,
 * Fussell & Carpenter 1982): every edge a–b longer than 2 × min_segment is
 * split at its midpoint, displaced perpendicular to a–b in a uniformly random
 * direction by a uniform distance in [0, ρ L], L the length of the piece split and
 * ρ = karst_amplification_displacement_ratio(θ); both halves are refined again up to
 * max_levels, each with the same ratio of its own length (so the added tortuosity does
 * not depend on the length of the graph's edges). A displacement that would put the
 * point outside the bedrock is rejected and redrawn (max_tries times; then the
 * midpoint stays on the segment), so no node leaves the bedrock. θ = 0 displaces
 * nothing. Original nodes keep their position and attributes; new nodes get zero
 * attributes (kind interior) but their edge's "spring"; each piece copies its edge's
 * attributes, except "cost", which is shared among the pieces in proportion to
 * their length.
 * Edges flagged "observed" (surveyed legs) are copied unchanged, with no draw.
 * Edges are processed in index order with @p rng, so the output is
 * deterministic.
 *
 * @param in   the network to refine (unchanged).
 * @param out  initialised by the caller; receives the refined network.
 * @return KARST_SUCCESS, KARST_EINVAL (θ outside [0, 1]), KARST_ENOMEM.
 * Time complexity: O(edges × 2^max_levels).
 */
karst_error_t karst_amplification_displace(karst_ctx_t *ctx, const karst_geology_t *geo,
                                           double theta, karst_rng_t *rng,
                                           const karst_amplification_options_t *opt,
                                           const karst_network_t *in, karst_network_t *out) {
  karst_amplification_options_t defaults;
  if (!opt) karst_amplification_options_init(&defaults), opt = &defaults;
  if (!(theta >= 0 && theta <= 1))
    return karst_set_error(ctx, KARST_EINVAL, "tortuosity must be within [0, 1], got %g", theta);
  karst_error_t err = KARST_SUCCESS;
  subdiv_t sd = {geo, opt, rng, NULL, 0, 0};
  const double ratio = karst_amplification_displacement_ratio(opt, theta);
  karst_network_t tmp;
  karst_network_init(&tmp);
  for (karst_int_t v = 0; v < in->n_nodes; v++)
    if (karst_network_add_node(&tmp, in->xyz[3 * v], in->xyz[3 * v + 1], in->xyz[3 * v + 2], NULL))
      goto nomem;
  for (int i = 0; i < in->n_node_attrs; i++) {
    const karst_attr_t *a = &in->node_attrs[i];
    double *d;
    if (karst_network_attr_add(&tmp, KARST_ATTR_NODE, a->name, a->ncomp, a->integer, &d))
      goto nomem;
    memcpy(d, a->data, (size_t)in->n_nodes * a->ncomp * sizeof *d);
  }
  if (in->node_labels)
    for (karst_int_t v = 0; v < in->n_nodes; v++)
      if (in->node_labels[v] && karst_network_set_label(&tmp, v, in->node_labels[v])) goto nomem;
  for (int i = 0; i < in->n_edge_attrs; i++) {
    const karst_attr_t *a = &in->edge_attrs[i];
    double *d;
    if (karst_network_attr_add(&tmp, KARST_ATTR_EDGE, a->name, a->ncomp, a->integer, &d))
      goto nomem;
  }
  /* A surveyed leg (edge attribute "observed", src/conditioning/) stays where it was surveyed. */
  const karst_attr_t *observed = karst_network_attr_find(in, KARST_ATTR_EDGE, "observed");
  for (karst_int_t e = 0; e < in->n_edges; e++) {
    karst_int_t u = in->edges[2 * e], w = in->edges[2 * e + 1];
    const double *a = &in->xyz[3 * u], *b = &in->xyz[3 * w];
    sd.n = 0;
    if (!(observed && observed->data[e] != 0) && subdivide(&sd, a, b, ratio, 0)) goto nomem;
    /* Lengths of the pieces, for sharing the cost. */
    double total = 0;
    const double *prev = a;
    for (karst_int_t k = 0; k <= sd.n; k++) {
      const double *next = k < sd.n ? &sd.pts[3 * k] : b;
      total += dist3(prev, next);
      prev = next;
    }
    karst_int_t pn = u;
    prev = a;
    for (karst_int_t k = 0; k <= sd.n; k++) {
      karst_int_t nn = w;
      const double *next = k < sd.n ? &sd.pts[3 * k] : b;
      if (k < sd.n) {
        if (karst_network_add_node(&tmp, next[0], next[1], next[2], &nn)) goto nomem;
        karst_attr_t *ns = karst_network_attr_find(&tmp, KARST_ATTR_NODE, "spring");
        const karst_attr_t *es = karst_network_attr_find(in, KARST_ATTR_EDGE, "spring");
        if (ns && es) ns->data[nn] = es->data[e];
      }
      karst_int_t ne;
      if (karst_network_add_edge(&tmp, pn, nn, &ne)) goto nomem;
      double share = total > 0 ? dist3(prev, next) / total : 1.0 / (double)(sd.n + 1);
      for (int i = 0; i < in->n_edge_attrs; i++) {
        const karst_attr_t *src = &in->edge_attrs[i];
        karst_attr_t *dst = &tmp.edge_attrs[i];
        for (int c = 0; c < src->ncomp; c++) {
          double val = src->data[e * src->ncomp + c];
          dst->data[ne * dst->ncomp + c] = strcmp(src->name, "cost") == 0 ? val * share : val;
        }
      }
      pn = nn;
      prev = next;
    }
  }
  if (in->crs && karst_network_set_crs(&tmp, in->crs)) goto nomem;
  karst_network_destroy(out);
  *out = tmp;
  karst_network_init(&tmp);
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "midpoint displacement: out of memory");
cleanup:
  karst_network_destroy(&tmp);
  free(sd.pts);
  return err;
}
