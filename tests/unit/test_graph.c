/* The kNN graph (Paris et al. 2021, §4.1): exact neighbour sets against brute
 * force, symmetry, thread independence, edge costs and exclusions, and the
 * CSR builder from edge lists. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "geology_fixture.h"
#include "graph/graph_internal.h"
#include "graph_heads.h"
#include "karst.h"
#include "test_util.h"

/* Box [0, 100]^3 under a terrain at 200 m; cost = w0 = 1 per metre. */
static void open_scenario(karst_scenario_t *sc, int k) {
  karst_scenario_init(sc);
  sc->terrain.elevation = 200;
  sc->sampling.k = k;
  sc->cost.horizon = 0, sc->cost.fracture = 0, sc->cost.permeability = 0;
}

static void random_samples(karst_samples_t *s, int n, uint64_t seed, int line) {
  karst_rng_t r;
  karst_rng_init(&r, seed, 0);
  karst_samples_init(s);
  for (int i = 0; i < n; i++) {
    double p[3];
    for (int a = 0; a < 3; a++)
      p[a] = karst_rng_uniform_range(&r, 0, 100);
    if (line) p[1] = p[2] = p[0]; /* collinear: the diagonal of the box */
    assert_int_equal(karst_samples_add(s, p, KARST_SAMPLE_FILL), KARST_SUCCESS);
  }
}

static double d2(const double *a, const double *b) {
  return (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
         (a[2] - b[2]) * (a[2] - b[2]);
}

typedef struct {
  double d;
  int i;
} di_t;
static int cmp_di(const void *a, const void *b) {
  const di_t *x = a, *y = b;
  return (x->d > y->d) - (x->d < y->d);
}

/* Brute-force reference: adjacency matrix of the union of the k nearest
 * neighbour relations (O(n² log n), independent of the grid search). */
static unsigned char *brute_knn_union(const karst_samples_t *s, int k) {
  int n = (int)s->n;
  unsigned char *A = calloc((size_t)n * n, 1);
  di_t *buf = malloc(sizeof(di_t) * (size_t)n);
  for (int v = 0; v < n; v++) {
    int m = 0;
    for (int u = 0; u < n; u++)
      if (u != v) buf[m++] = (di_t){d2(s->xyz + 3 * v, s->xyz + 3 * u), u};
    qsort(buf, (size_t)m, sizeof(di_t), cmp_di);
    for (int j = 0; j < k && j < m; j++)
      A[(size_t)v * n + buf[j].i] = A[(size_t)buf[j].i * n + v] = 1;
  }
  free(buf);
  return A;
}

/* The coded rows are the bytes the rule of include/karst/graph.h gives, re-derived here from the
 * decoded heads: a run starts at a row's first arc, and at an arc whose gap to the previous head
 * is outside 1 .. 256 or that would be the 256th of its run; it is its first head (4 bytes,
 * little-endian) and the count of the arcs after it, then each of those arcs' gap less one. */
static void check_coding(const karst_graph_t *g) {
  int32_t *adj = fx_heads(g);
  assert_non_null(adj);
  assert_int_equal(g->code_off[0], 0);
  for (karst_int_t v = 0; v < g->n; v++) {
    const unsigned char *c = g->code + g->code_off[v];
    karst_int_t at = 0, count_at = -1, run = 0;
    for (karst_int_t a = g->offsets[v]; a < g->offsets[v + 1]; a++) {
      int64_t gap = a > g->offsets[v] ? (int64_t)adj[a] - adj[a - 1] : 0;
      if (count_at >= 0 && gap >= 1 && gap <= 256 && run < 255) {
        assert_int_equal(c[at++], gap - 1);
        run++;
        continue;
      }
      if (count_at >= 0) /* the run before ended at the arc before */
        assert_int_equal(c[count_at], at - count_at - 1);
      uint32_t x = (uint32_t)adj[a];
      for (int i = 0; i < 4; i++)
        assert_int_equal(c[at++], (x >> (8 * i)) & 255);
      count_at = at++, run = 0;
    }
    if (count_at >= 0) assert_int_equal(c[count_at], at - count_at - 1);
    assert_int_equal(g->code_off[v + 1] - g->code_off[v], at);
  }
  free(adj);
}

/* The CSR structure is a simple undirected graph: sorted rows, no self-loop,
 * every arc mirrored with the same cost. */
static void check_symmetric(const karst_graph_t *g) {
  assert_int_equal(g->offsets[0], 0);
  assert_int_equal(g->offsets[g->n], g->n_arcs);
  int32_t *adj = fx_heads(g);
  assert_non_null(adj);
  for (karst_int_t v = 0; v < g->n; v++)
    for (karst_int_t a = g->offsets[v]; a < g->offsets[v + 1]; a++) {
      karst_int_t u = adj[a];
      assert_true(u != v && u >= 0 && u < g->n);
      if (a > g->offsets[v]) assert_true(adj[a - 1] < u);
      int found = 0;
      for (karst_int_t b = g->offsets[u]; b < g->offsets[u + 1]; b++)
        if (adj[b] == v) found = 1, assert_true(g->cost[b] == g->cost[a]);
      assert_true(found);
      assert_int_equal(karst_graph_find_arc(g, v, u), a);
    }
  free(adj);
  check_coding(g);
}

static void check_against_brute(const karst_samples_t *s, const karst_graph_t *g, int k) {
  unsigned char *A = brute_knn_union(s, k);
  int n = (int)s->n;
  karst_int_t arcs = 0;
  int32_t *adj = fx_heads(g);
  assert_non_null(adj);
  for (int v = 0; v < n; v++) {
    for (karst_int_t a = g->offsets[v]; a < g->offsets[v + 1]; a++)
      assert_int_equal(A[(size_t)v * n + adj[a]], 1);
    for (int u = 0; u < n; u++)
      arcs += A[(size_t)v * n + u];
  }
  assert_int_equal(arcs, g->n_arcs); /* same size and included: equal sets */
  free(adj);
  free(A);
}

/* 3000 random points, k = 12: neighbour sets equal the brute-force union;
 * the graph is identical with 1 and 2 threads; costs are the edge lengths. */
static void test_knn_exact(void **state) {
  (void)state;
  karst_scenario_t sc;
  open_scenario(&sc, 12);
  karst_samples_t s;
  random_samples(&s, 3000, 99, 0);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_graph_t g1, g2;
  karst_graph_init(&g1), karst_graph_init(&g2);
  ctx.nthreads = 1;
  assert_int_equal(T_graph_build(&ctx, &sc, &s, &g1), KARST_SUCCESS);
  ctx.nthreads = 2;
  assert_int_equal(T_graph_build(&ctx, &sc, &s, &g2), KARST_SUCCESS);
  check_symmetric(&g1);
  check_against_brute(&s, &g1, 12);
  /* The union of the 12-NN relations gives every vertex at least 12 neighbours. */
  for (karst_int_t v = 0; v < g1.n; v++)
    assert_true(g1.offsets[v + 1] - g1.offsets[v] >= 12);
  assert_int_equal(g1.n_arcs, g2.n_arcs);
  assert_memory_equal(g1.offsets, g2.offsets, sizeof(karst_int_t) * (size_t)(g1.n + 1));
  int32_t *adj1 = fx_heads(&g1), *adj2 = fx_heads(&g2);
  assert_non_null(adj1), assert_non_null(adj2);
  assert_memory_equal(adj1, adj2, sizeof *adj1 * (size_t)g1.n_arcs);
  assert_memory_equal(g1.cost, g2.cost, sizeof *g1.cost * (size_t)g1.n_arcs);
  for (karst_int_t v = 0; v < g1.n; v += 97)
    for (karst_int_t a = g1.offsets[v]; a < g1.offsets[v + 1]; a++) {
      /* the stored cost is the nearest float of the length: within 2^-24 relative */
      double len = sqrt(d2(s.xyz + 3 * v, s.xyz + 3 * adj1[a]));
      assert_close(g1.cost[a], len, 0x1p-24 * len + 1e-12);
    }
  free(adj1), free(adj2);
  assert_int_equal(karst_graph_edge_count(&g1), g1.n_arcs / 2);
  karst_graph_destroy(&g1), karst_graph_destroy(&g2);
  karst_samples_destroy(&s);
  karst_scenario_destroy(&sc);
}

/* Collinear points (degenerate geometry for the grid search). */
static void test_knn_collinear(void **state) {
  (void)state;
  karst_scenario_t sc;
  open_scenario(&sc, 4);
  karst_samples_t s;
  random_samples(&s, 500, 3, 1);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_graph_t g;
  karst_graph_init(&g);
  assert_int_equal(T_graph_build(&ctx, &sc, &s, &g), KARST_SUCCESS);
  check_symmetric(&g);
  check_against_brute(&s, &g, 4);
  karst_graph_destroy(&g);
  karst_samples_destroy(&s);
  karst_scenario_destroy(&sc);
}

/* Empty set, a single point, k >= n (complete graph), and two far clusters
 * with small k (disconnected: no edge between them). */
static void test_graph_small_cases(void **state) {
  (void)state;
  karst_scenario_t sc;
  open_scenario(&sc, 40);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_samples_t s;
  karst_samples_init(&s);
  karst_graph_t g;
  karst_graph_init(&g);
  assert_int_equal(T_graph_build(&ctx, &sc, &s, &g), KARST_SUCCESS);
  assert_int_equal(g.n, 0);
  assert_int_equal(g.n_arcs, 0);
  assert_int_equal(g.offsets[0], 0);
  double p[3] = {1, 2, 3};
  karst_samples_add(&s, p, KARST_SAMPLE_KEYPOINT);
  assert_int_equal(T_graph_build(&ctx, &sc, &s, &g), KARST_SUCCESS);
  assert_int_equal(g.n, 1);
  assert_int_equal(g.n_arcs, 0);
  for (int i = 0; i < 5; i++) {
    double q[3] = {10.0 + i, 20.0 + i * i, 30};
    karst_samples_add(&s, q, KARST_SAMPLE_FILL);
  }
  assert_int_equal(T_graph_build(&ctx, &sc, &s, &g), KARST_SUCCESS);
  assert_int_equal(g.n_arcs, 6 * 5); /* complete graph on 6 vertices */
  karst_samples_destroy(&s);

  karst_samples_init(&s);
  karst_rng_t r;
  karst_rng_init(&r, 4, 0);
  for (int i = 0; i < 40; i++) {
    double q[3] = {karst_rng_uniform_range(&r, 0, 5), karst_rng_uniform_range(&r, 0, 5),
                   karst_rng_uniform_range(&r, 0, 5)};
    if (i >= 20) q[0] += 90;
    karst_samples_add(&s, q, KARST_SAMPLE_FILL);
  }
  sc.sampling.k = 5;
  assert_int_equal(T_graph_build(&ctx, &sc, &s, &g), KARST_SUCCESS);
  check_symmetric(&g);
  for (karst_int_t v = 0; v < 40; v++) {
    karst_arc_reader_t rd = karst_graph_arcs(&g, v);
    for (karst_int_t a = g.offsets[v]; a < g.offsets[v + 1]; a++)
      assert_true((v < 20) == (karst_arc_next(&rd) < 20));
  }
  /* Invalid k and non-finite samples are refused. */
  sc.sampling.k = 0;
  assert_int_equal(T_graph_build(&ctx, &sc, &s, &g), KARST_EINVAL);
  sc.sampling.k = 5;
  s.xyz[7] = NAN;
  assert_int_equal(T_graph_build(&ctx, &sc, &s, &g), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "sample 2"));
  assert_int_equal(g.n, 40); /* unchanged on failure */
  karst_graph_destroy(&g);
  karst_samples_destroy(&s);
  karst_scenario_destroy(&sc);
}

/* Edges through the air above a V-shaped valley are removed: two groups of
 * points on both slopes, the valley floor at 10 m between them. */
static void test_graph_excludes_air(void **state) {
  (void)state;
  karst_scenario_t sc;
  open_scenario(&sc, 3);
  sc.domain_min[2] = -10;
  sc.terrain.is_grid = 1, sc.terrain.ncols = 3, sc.terrain.nrows = 2, sc.terrain.cellsize = 50;
  sc.terrain.z = malloc(6 * sizeof(double));
  const double v[6] = {90, 10, 90, 90, 10, 90};
  memcpy(sc.terrain.z, v, sizeof v);
  karst_samples_t s;
  karst_samples_init(&s);
  const double P[4][3] = {{0, 20, 50}, {5, 20, 50}, {95, 20, 50}, {100, 20, 50}};
  for (int i = 0; i < 4; i++)
    karst_samples_add(&s, P[i], KARST_SAMPLE_FILL);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_graph_t g;
  karst_graph_init(&g);
  assert_int_equal(T_graph_build(&ctx, &sc, &s, &g), KARST_SUCCESS);
  /* k = 3 joins everything, but only the two 5 m edges stay under ground. */
  assert_int_equal(g.n_arcs, 4);
  check_symmetric(&g);
  assert_close(g.cost[0], 5.0, 1e-12);
  karst_graph_destroy(&g);
  karst_samples_destroy(&s);
  karst_scenario_destroy(&sc);
}

/* CSR from edge lists: duplicates keep the cheaper, self-loops and infinite
 * costs are dropped, rows sorted; bad input is refused with the edge named. */
/* Rows given as they are, coded by hand from the rule of include/karst/graph.h. */
static void test_from_rows_coding(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_graph_t g;
  karst_graph_init(&g);
  /* Row 0: 5, 6 (gap 1), 262 (gap 256), 263 (gap 1), 1000 (gap 737: escaped), 1000 (gap 0:
   * escaped), 3 (backwards: escaped): runs [5 6 262 263] [1000] [1000] [3]. Row 1 is empty.
   * Row 2: 0 .. 299, a run of 1 + 255 arcs, then 256 .. 299 (1 + 43). Row 3: the last vertex. */
  enum { N = 1 << 20 };
  karst_int_t off[5] = {0, 7, 7, 307, 308};
  int32_t adj[308];
  karst_arc_cost_t cost[308];
  const int32_t row0[7] = {5, 6, 262, 263, 1000, 1000, 3};
  for (int i = 0; i < 7; i++)
    adj[i] = row0[i];
  for (int i = 0; i < 300; i++)
    adj[7 + i] = i;
  adj[307] = N - 1;
  for (int i = 0; i < 308; i++)
    cost[i] = (karst_arc_cost_t)(i + 0.5);
  karst_int_t *offsets = calloc(N + 1, sizeof *offsets);
  assert_non_null(offsets);
  for (int v = 0; v < N + 1; v++)
    offsets[v] = v < 4 ? off[v] : 308;
  assert_int_equal(karst_graph_from_rows(&ctx, &g, N, NULL, offsets, adj, cost), KARST_SUCCESS);
  assert_int_equal(g.n_arcs, 308);
  const unsigned char row0code[23] = {5, 0,    0, 0, 3, 0, 255, 0, 0xe8, 3, 0, 0,
                                      0, 0xe8, 3, 0, 0, 0, 3,   0, 0,    0, 0};
  assert_int_equal(g.code_off[1], 23);
  assert_memory_equal(g.code, row0code, 23);
  assert_int_equal(g.code_off[2], 23);                    /* row 1: empty */
  assert_int_equal(g.code_off[3], 23 + 5 + 255 + 5 + 43); /* row 2: two runs */
  const unsigned char *r2 = g.code + 23;
  const unsigned char head0[5] = {0, 0, 0, 0, 255}, head256[5] = {0, 1, 0, 0, 43};
  assert_memory_equal(r2, head0, 5); /* 0, then 255 arcs of gap 1 */
  for (int i = 0; i < 255; i++)
    assert_int_equal(r2[5 + i], 0);
  assert_memory_equal(r2 + 260, head256, 5); /* the 256th arc after a run's head starts a run */
  const unsigned char last[5] = {0xff, 0xff, 0x0f, 0, 0};
  assert_memory_equal(g.code + g.code_off[3], last, 5);
  assert_int_equal(g.code_off[N], g.code_off[3] + 5);
  /* Read back as given, costs with their arcs. */
  for (karst_int_t v = 0; v < 4; v++) {
    karst_arc_reader_t r = karst_graph_arcs(&g, v);
    for (karst_int_t a = g.offsets[v]; a < g.offsets[v + 1]; a++) {
      assert_int_equal(karst_arc_next(&r), adj[a]);
      assert_true(g.cost[a] == cost[a]);
    }
  }
  assert_int_equal(karst_graph_find_arc(&g, 0, 1000), 4); /* the first of a repeated head */
  assert_int_equal(karst_graph_find_arc(&g, 0, 4), -1);
  assert_int_equal(karst_graph_find_arc(&g, 2, 299), 306);
  assert_int_equal(karst_graph_find_arc(&g, 1, 0), -1);
  check_coding(&g);
  /* Bad rows: the graph is left as it was, the message says what and where. */
  karst_graph_t before = g;
  offsets[0] = 1;
  assert_int_equal(karst_graph_from_rows(&ctx, &g, N, NULL, offsets, adj, cost), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "first row starts at arc 1"));
  offsets[0] = 0;
  offsets[2] = 3;
  assert_int_equal(karst_graph_from_rows(&ctx, &g, N, NULL, offsets, adj, cost), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "row 1 ends (3) before it starts (7)"));
  offsets[2] = 7;
  adj[5] = N;
  assert_int_equal(karst_graph_from_rows(&ctx, &g, N, NULL, offsets, adj, cost), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "arc 5 of vertex 0 has head 1048576, outside [0, 1048576)"));
  adj[5] = -1;
  assert_int_equal(karst_graph_from_rows(&ctx, &g, N, NULL, offsets, adj, cost), KARST_EINVAL);
  assert_int_equal(karst_graph_from_rows(&ctx, &g, -1, NULL, offsets, adj, cost), KARST_EINVAL);
  assert_memory_equal(&g, &before, sizeof g);
  karst_graph_destroy(&g);
  free(offsets);
}

static void test_from_edges(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_graph_t g;
  karst_graph_init(&g);
  const karst_int_t u[] = {0, 2, 1, 3, 2, 0, 3};
  const karst_int_t v[] = {1, 0, 0, 3, 3, 4, 0};
  const double c[] = {5, 2, 3, 1, INFINITY, 7, 4};
  assert_int_equal(karst_graph_from_edges(&ctx, &g, 5, NULL, 7, u, v, c), KARST_SUCCESS);
  /* Edges kept: {0,1} cost 3, {0,2} 2, {0,4} 7, {0,3} 4. */
  assert_int_equal(g.n_arcs, 8);
  const karst_int_t row0[] = {1, 2, 3, 4};
  const double cost0[] = {3, 2, 4, 7};
  assert_int_equal(g.offsets[1] - g.offsets[0], 4);
  karst_arc_reader_t rd = karst_graph_arcs(&g, 0);
  for (int i = 0; i < 4; i++) {
    assert_int_equal(karst_arc_next(&rd), row0[i]);
    assert_close(g.cost[i], cost0[i], 0);
  }
  check_symmetric(&g);
  const karst_int_t bad_v[] = {1, 9};
  const karst_int_t bad_u[] = {0, 1};
  const double bc[] = {1, 1};
  assert_int_equal(karst_graph_from_edges(&ctx, &g, 5, NULL, 2, bad_u, bad_v, bc), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "edge 1 (1, 9)"));
  const double neg[] = {1, -2};
  assert_int_equal(karst_graph_from_edges(&ctx, &g, 5, NULL, 2, bad_u, u, neg), KARST_EINVAL);
  assert_int_equal(g.n_arcs, 8); /* unchanged */
  assert_int_equal(karst_graph_from_edges(&ctx, &g, 0, NULL, 0, NULL, NULL, NULL), KARST_SUCCESS);
  assert_int_equal(g.n, 0);
  assert_int_equal(g.offsets[0], 0);
  karst_graph_destroy(&g);
}

/* Sampling followed by the graph: every key point has neighbours and the
 * costs are finite and at least the lower bound times the length. */
static void test_pipeline(void **state) {
  (void)state;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  sc.domain_max[2] = 60, sc.terrain.elevation = 50, T_set_water_table(&sc, 30);
  sc.sampling.fill_radius = 6, sc.sampling.feature_radius = 3, sc.sampling.k = 20;
  sc.n_fractures = 1;
  sc.fractures = calloc(1, sizeof(karst_fracture_t));
  sc.fractures[0].dip = 80, sc.fractures[0].dip_direction = 30, sc.fractures[0].weight = 1;
  sc.n_key_points = 2;
  sc.key_points = calloc(2, sizeof(karst_keypoint_t));
  const double a[3] = {10, 10, 40}, b[3] = {90, 90, 5};
  memcpy(sc.key_points[0].p, a, sizeof a), memcpy(sc.key_points[1].p, b, sizeof b);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  ctx.nthreads = 2;
  karst_rng_t rng;
  karst_rng_init(&rng, 1, 0);
  karst_samples_t s;
  karst_samples_init(&s);
  assert_int_equal(T_sampling_run(&ctx, &sc, &rng, &s), KARST_SUCCESS);
  karst_graph_t g;
  karst_graph_init(&g);
  assert_int_equal(T_graph_build(&ctx, &sc, &s, &g), KARST_SUCCESS);
  check_symmetric(&g);
  double lb = karst_cost_lower_bound_per_metre(&sc);
  for (karst_int_t v = 0; v < g.n; v++) {
    if (v < 2) assert_true(g.offsets[v + 1] - g.offsets[v] >= 20);
    karst_arc_reader_t rd = karst_graph_arcs(&g, v);
    for (karst_int_t e = g.offsets[v]; e < g.offsets[v + 1]; e++) {
      karst_int_t w = karst_arc_next(&rd);
      assert_true(isfinite(g.cost[e]));
      assert_true(g.cost[e] >= lb * sqrt(d2(s.xyz + 3 * v, s.xyz + 3 * w)));
    }
  }
  /* Built in batches (karst_graph_build: each quarter of the arcs built 32-bit, then coded; large
   * graphs only, here forced), on 1 and 3 threads: the same graph byte for byte, edges leaving
   * the bedrock (above the terrain) dropped alike. */
  const karst_int_t saved = karst_i_graph_min_batch_arcs;
  karst_i_graph_min_batch_arcs = 0;
  for (int t = 1; t <= 3; t += 2) {
    karst_graph_t h;
    karst_graph_init(&h);
    ctx.nthreads = t;
    assert_int_equal(T_graph_build(&ctx, &sc, &s, &h), KARST_SUCCESS);
    assert_int_equal(h.n_arcs, g.n_arcs);
    assert_memory_equal(h.offsets, g.offsets, sizeof *g.offsets * (size_t)(g.n + 1));
    assert_memory_equal(h.code_off, g.code_off, sizeof *g.code_off * (size_t)(g.n + 1));
    assert_memory_equal(h.code, g.code, (size_t)g.code_off[g.n]);
    assert_memory_equal(h.cost, g.cost, sizeof *g.cost * (size_t)g.n_arcs);
    karst_graph_destroy(&h);
  }
  karst_i_graph_min_batch_arcs = saved;
  karst_graph_destroy(&g);
  karst_samples_destroy(&s);
  karst_scenario_destroy(&sc);
}

/* A scenario with every cost term: a dipping horizon, three fracture
 * families, a blend of a permeable sphere and a stratum (exercising the
 * shortcut for edges far from every primitive), under a flat terrain.
 * Expected values: each arc's cost is karst_cost_edge of its ends (the
 * public single-edge function, from the smaller index), both arcs carry it, and it agrees with an
 * independent 4000-point midpoint rule of karst_cost_point along the edge
 * (tolerance: the rule's error bound for the stratum's jumps, see below).
 * 1, 2 and 5 threads give identical graphs. */
static void test_costs_all_terms(void **state) {
  (void)state;
  karst_scenario_t sc;
  open_scenario(&sc, 10);
  sc.cost.horizon = 1, sc.cost.fracture = 0.7, sc.cost.permeability = 2;
  sc.n_horizons = 1;
  sc.horizons = calloc(1, sizeof(karst_horizon_t));
  sc.horizons[0].elevation = 40, sc.horizons[0].radius = 6, sc.horizons[0].dip = 10;
  sc.horizons[0].dip_direction = 30, sc.horizons[0].origin[0] = 50, sc.horizons[0].origin[1] = 50;
  sc.n_fractures = 3;
  sc.fractures = calloc(3, sizeof(karst_fracture_t));
  const double F[3][3] = {{0, 90, 0.5}, {90, 90, 0.5}, {30, 70, 0.3}};
  for (int i = 0; i < 3; i++)
    sc.fractures[i].dip_direction = F[i][0], sc.fractures[i].dip = F[i][1],
    sc.fractures[i].weight = F[i][2];
  sc.permeability.background = 0.9;
  karst_perm_node_t *root = calloc(1, sizeof(karst_perm_node_t));
  sc.permeability.root = root;
  root->kind = KARST_PERM_BLEND, root->n_children = 2;
  root->children = calloc(2, sizeof(karst_perm_node_t));
  karst_perm_node_t *sp = &root->children[0], *st = &root->children[1];
  sp->kind = KARST_PERM_SPHERE, sp->center[0] = 30, sp->center[1] = 60, sp->center[2] = 50;
  sp->radius = 8, sp->falloff = 6, sp->resistance = 0.1, sp->weight = 2;
  st->kind = KARST_PERM_STRATUM, st->bottom = 70, st->top = 74, st->resistance = 0.3;
  st->weight = 1;
  karst_samples_t s;
  random_samples(&s, 1500, 17, 0);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_graph_t g[3];
  const int threads[3] = {1, 2, 5};
  for (int t = 0; t < 3; t++) {
    karst_graph_init(&g[t]);
    ctx.nthreads = threads[t];
    assert_int_equal(T_graph_build(&ctx, &sc, &s, &g[t]), KARST_SUCCESS);
  }
  check_symmetric(&g[0]);
  check_against_brute(&s, &g[0], 10);
  int32_t *adj0 = fx_heads(&g[0]);
  assert_non_null(adj0);
  for (int t = 1; t < 3; t++) {
    assert_int_equal(g[0].n_arcs, g[t].n_arcs);
    int32_t *adjt = fx_heads(&g[t]);
    assert_non_null(adjt);
    assert_memory_equal(adj0, adjt, sizeof *adj0 * (size_t)g[0].n_arcs);
    free(adjt);
    assert_memory_equal(g[0].cost, g[t].cost, sizeof *g[0].cost * (size_t)g[0].n_arcs);
  }
  for (karst_int_t v = 0; v < g[0].n; v++)
    for (karst_int_t a = g[0].offsets[v]; a < g[0].offsets[v + 1]; a++) {
      karst_int_t w = adj0[a];
      const double *p = s.xyz + 3 * v, *q = s.xyz + 3 * w;
      /* computed once, from the smaller index to the larger, and stored as its nearest float */
      assert_true(g[0].cost[a] ==
                  karst_arc_cost_round(v < w ? T_cost_edge(&sc, p, q) : T_cost_edge(&sc, q, p)));
      if (v % 37 != 0) continue;
      double d[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, sum = 0;
      const int m = 4000;
      for (int i = 0; i < m; i++) {
        double x[3], t = (i + 0.5) / m;
        for (int c = 0; c < 3; c++)
          x[c] = p[c] + t * d[c];
        sum += T_cost_point(&sc, x, d);
      }
      /* The stratum makes π jump (by at most 1) where the edge crosses its
       * two faces; a midpoint rule errs by at most |jump| h / 2 per jump,
       * h = len / m, on top of the O(h²) smooth part. */
      double len = sqrt(d2(p, q)), ref = sum / m * len;
      assert_close(g[0].cost[a], ref, sc.cost.permeability * len / m + 1e-6 * ref);
    }
  free(adj0);
  for (int t = 0; t < 3; t++)
    karst_graph_destroy(&g[t]);
  karst_samples_destroy(&s);
  karst_scenario_destroy(&sc);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_knn_exact),         cmocka_unit_test(test_knn_collinear),
      cmocka_unit_test(test_graph_small_cases), cmocka_unit_test(test_graph_excludes_air),
      cmocka_unit_test(test_from_edges),        cmocka_unit_test(test_pipeline),
      cmocka_unit_test(test_from_rows_coding),  cmocka_unit_test(test_costs_all_terms),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
