/* All-sources breadth-first search: Brandes betweenness and hop-distance sums, in parallel.
 *
 * Written here rather than taken from igraph because one BFS per source gives
 * both the betweenness (cpd) and the distance sums (aspl), where igraph needs
 * two passes (igraph_betweenness + igraph_distances); and because igraph's
 * betweenness is sequential. bench/bench_metrics.c measures both. */
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "metrics/metrics_internal.h"

karst_error_t karst_i_csr_build(karst_ctx_t *ctx, karst_int_t n, karst_int_t m,
                                const karst_int_t *edges, karst_i_csr_t *g) {
  memset(g, 0, sizeof *g);
  karst_error_t err = KARST_SUCCESS;
  g->n = n;
  g->off = calloc((size_t)n + 1, sizeof *g->off);
  karst_int_t *fill = calloc((size_t)n + 1, sizeof *fill);
  if (!g->off || !fill) goto nomem;
  for (karst_int_t e = 0; e < m; e++) {
    karst_int_t u = edges[2 * e], v = edges[2 * e + 1];
    if (u == v) continue;
    g->off[u + 1]++;
    g->off[v + 1]++;
  }
  for (karst_int_t v = 0; v < n; v++)
    g->off[v + 1] += g->off[v];
  g->adj = malloc((size_t)(g->off[n] > 0 ? g->off[n] : 1) * sizeof *g->adj);
  if (!g->adj) goto nomem;
  memcpy(fill, g->off, (size_t)n * sizeof *fill);
  for (karst_int_t e = 0; e < m; e++) {
    karst_int_t u = edges[2 * e], v = edges[2 * e + 1];
    if (u == v) continue;
    g->adj[fill[u]++] = v;
    g->adj[fill[v]++] = u;
  }
  goto cleanup;
nomem:
  karst_i_csr_destroy(g);
  err = karst_set_error(ctx, KARST_ENOMEM, "graph of %lld nodes and %lld edges: out of memory",
                        (long long)n, (long long)m);
cleanup:
  free(fill);
  return err;
}

void karst_i_csr_destroy(karst_i_csr_t *g) {
  free(g->off);
  free(g->adj);
  memset(g, 0, sizeof *g);
}

/* Per-thread work space of one BFS, reset after each source (only the visited part). */
typedef struct {
  const karst_i_csr_t *g;
  karst_int_t *dist, *queue;
  double *sigma, *delta;
  karst_int_t *dsum; /* shared dist_sum (each source written by one thread) */
} worker_t;

/* One wave: blocks first .. first+count-1, claimed by the threads one at a time. */
typedef struct {
  karst_int_t first, count, bs, n;
  double **part; /* count arrays of n: the betweenness of each block */
  atomic_llong next;
} wave_t;

typedef struct {
  worker_t *w;
  wave_t *wave;
} thread_arg_t;

/* Brandes' Algorithm 1 for unweighted graphs on sources s0..s1-1, adding into @p part;
 * predecessors are found again by scanning neighbours at distance d-1 instead of being
 * stored. */
static void bfs_block(worker_t *w, karst_int_t s0, karst_int_t s1, double *part) {
  const karst_int_t *off = w->g->off, *adj = w->g->adj;
  karst_int_t *dist = w->dist, *q = w->queue;
  double *sigma = w->sigma, *delta = w->delta;
  memset(part, 0, (size_t)w->g->n * sizeof *part);
  for (karst_int_t s = s0; s < s1; s++) {
    karst_int_t head = 0, tail = 0, sum = 0;
    dist[s] = 0;
    sigma[s] = 1.0;
    q[tail++] = s;
    while (head < tail) {
      karst_int_t v = q[head++];
      karst_int_t dv = dist[v];
      sum += dv;
      for (karst_int_t k = off[v]; k < off[v + 1]; k++) {
        karst_int_t x = adj[k];
        if (dist[x] < 0) {
          dist[x] = dv + 1;
          q[tail++] = x;
        }
        if (dist[x] == dv + 1) sigma[x] += sigma[v];
      }
    }
    if (w->dsum) w->dsum[s] = sum;
    for (karst_int_t i = tail - 1; i > 0; i--) {
      karst_int_t x = q[i];
      double coeff = (1.0 + delta[x]) / sigma[x];
      karst_int_t dp = dist[x] - 1;
      for (karst_int_t k = off[x]; k < off[x + 1]; k++) {
        karst_int_t v = adj[k];
        if (dist[v] == dp) delta[v] += sigma[v] * coeff;
      }
      part[x] += delta[x];
    }
    for (karst_int_t i = 0; i < tail; i++) {
      karst_int_t x = q[i];
      dist[x] = -1;
      sigma[x] = 0.0;
      delta[x] = 0.0;
    }
  }
}

static void *bfs_thread(void *arg) {
  thread_arg_t *a = arg;
  wave_t *wv = a->wave;
  for (;;) {
    long long i = atomic_fetch_add(&wv->next, 1);
    if (i >= wv->count) break;
    karst_int_t s0 = (wv->first + i) * wv->bs;
    karst_int_t s1 = s0 + wv->bs < wv->n ? s0 + wv->bs : wv->n;
    bfs_block(a->w, s0, s1, wv->part[i]);
  }
  return NULL;
}

/* Sources per block: a function of n only, so that the order in which block
 * results are added (and hence every bit of the result) does not depend on the
 * thread count. At most 512 blocks keep the reduction cost at 512·n. */
static karst_int_t block_size(karst_int_t n) {
  karst_int_t b = (n + 511) / 512;
  return b < 32 ? 32 : b;
}

/* Blocks per thread and wave: threads claim blocks dynamically inside a wave, so a
 * thread slowed down by another process does not hold the others back. */
enum { BLOCKS_PER_THREAD = 4 };

karst_error_t karst_i_paths_all_sources(karst_ctx_t *ctx, const karst_i_csr_t *g,
                                        double *betweenness, karst_int_t *dist_sum) {
  karst_error_t err = KARST_SUCCESS;
  const karst_int_t n = g->n;
  int nt = ctx && ctx->nthreads > 1 ? ctx->nthreads : 1;
  const karst_int_t bs = block_size(n);
  const karst_int_t nblocks = (n + bs - 1) / bs;
  if (nt > nblocks) nt = nblocks > 0 ? (int)nblocks : 1;
  const karst_int_t wmax = (karst_int_t)nt * BLOCKS_PER_THREAD;
  size_t nn = (size_t)(n > 0 ? n : 1);
  worker_t *w = calloc((size_t)nt, sizeof *w);
  thread_arg_t *args = calloc((size_t)nt, sizeof *args);
  pthread_t *tid = calloc((size_t)nt, sizeof *tid);
  double **part = calloc((size_t)wmax, sizeof *part);
  wave_t wave;
  if (!w || !args || !tid || !part) goto nomem;
  for (karst_int_t i = 0; i < wmax; i++)
    if (!(part[i] = malloc(nn * sizeof **part))) goto nomem;
  for (int t = 0; t < nt; t++) {
    w[t].g = g;
    w[t].dist = malloc(nn * sizeof *w[t].dist);
    w[t].queue = malloc(nn * sizeof *w[t].queue);
    w[t].sigma = calloc(nn, sizeof *w[t].sigma);
    w[t].delta = calloc(nn, sizeof *w[t].delta);
    w[t].dsum = dist_sum;
    if (!w[t].dist || !w[t].queue || !w[t].sigma || !w[t].delta) goto nomem;
    for (karst_int_t v = 0; v < n; v++)
      w[t].dist[v] = -1;
    args[t].w = &w[t];
    args[t].wave = &wave;
  }
  memset(betweenness, 0, (size_t)n * sizeof *betweenness);
  wave.bs = bs;
  wave.n = n;
  wave.part = part;
  for (karst_int_t b0 = 0; b0 < nblocks; b0 += wmax) {
    if (karst_interrupted(ctx)) {
      err = karst_set_error(ctx, KARST_EINTERRUPTED, "shortest paths: interrupted");
      goto cleanup;
    }
    wave.first = b0;
    wave.count = nblocks - b0 < wmax ? nblocks - b0 : wmax;
    atomic_store(&wave.next, 0);
    /* The calling thread works too; the others are started per wave. If a thread
     * cannot be started the remaining ones simply claim more blocks. */
    int started = 0;
    for (int t = 1; t < nt; t++, started++)
      if (pthread_create(&tid[t], NULL, bfs_thread, &args[t]) != 0) break;
    bfs_thread(&args[0]);
    for (int t = 1; t <= started; t++)
      pthread_join(tid[t], NULL);
    for (karst_int_t i = 0; i < wave.count; i++) /* fixed block order: deterministic sums */
      for (karst_int_t v = 0; v < n; v++)
        betweenness[v] += part[i][v];
    karst_progress(ctx, "shortest paths", (double)(b0 + wave.count), (double)nblocks);
  }
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM,
                        "shortest paths on %lld nodes with %d threads: out of memory", (long long)n,
                        nt);
cleanup:
  if (w)
    for (int t = 0; t < nt; t++) {
      free(w[t].dist);
      free(w[t].queue);
      free(w[t].sigma);
      free(w[t].delta);
    }
  if (part)
    for (karst_int_t i = 0; i < wmax; i++)
      free(part[i]);
  free(part);
  free(w);
  free(args);
  free(tid);
  return err;
}
