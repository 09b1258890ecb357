/* Least-cost paths (src/paths): A* against Dijkstra, path validity,
 * unreachable targets, the key-point distance matrix, and three geological
 * cases of Paris et al. 2021 §4.2 (horizon corridor, fracture strike,
 * low-resistance sphere). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "geology_fixture.h"
#include "graph_fixture.h"
#include "graph_heads.h"
#include "test_util.h"

/* Random cost per metre in [1, 3]; one edge in 10 excluded (INFINITY). */
static double random_cost(const double *a, const double *b, void *user) {
  karst_rng_t *rng = user;
  double f = 1.0 + 2.0 * karst_rng_uniform(rng);
  if (karst_rng_uniform(rng) < 0.1) return INFINITY;
  return f * fx_euclid_cost(a, b, NULL);
}

/* Check that p is a walk on g from s to t whose arc costs add up to p->cost (within @p rel). */
static void assert_valid_path_rel(const karst_graph_t *g, const karst_path_t *p, karst_int_t s,
                                  karst_int_t t, double rel) {
  assert_true(p->n >= 1);
  assert_int_equal(p->v[0], s);
  assert_int_equal(p->v[p->n - 1], t);
  double sum = 0;
  for (karst_int_t i = 1; i < p->n; i++) {
    double best = INFINITY;
    karst_arc_reader_t rd = karst_graph_arcs(g, p->v[i - 1]);
    for (karst_int_t a = g->offsets[p->v[i - 1]]; a < g->offsets[p->v[i - 1] + 1]; a++)
      if (karst_arc_next(&rd) == p->v[i] && g->cost[a] < best) best = g->cost[a];
    assert_true(best < INFINITY); /* consecutive vertices are joined by a usable edge */
    sum += best;
  }
  assert_rel(sum, p->cost, rel);
}

static void assert_valid_path(const karst_graph_t *g, const karst_path_t *p, karst_int_t s,
                              karst_int_t t) {
  assert_valid_path_rel(g, p, s, t, 1e-12);
}

/* A cost whose factor spans six decades across the domain (1e-3 to 1e3 per metre) and that is
 * symmetric in its ends (the factor is taken at the midpoint): the double the fixture rounds to
 * the stored float, recomputed here in double for the reference. */
static double wide_cost(const double *a, const double *b, void *user) {
  (void)user;
  double m[3] = {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
  double f = pow(10.0, 3.0 * sin(0.07 * m[0]) * cos(0.05 * m[1]) + 0.3 * sin(0.3 * m[2]));
  return f * fx_euclid_cost(a, b, NULL);
}

/* Reference: Dijkstra in double on the exact costs (wide_cost of every arc), by the O(n^2)
 * textbook scan, independent of the library's heap and its float costs. */
static void exact_dijkstra(const karst_graph_t *g, karst_int_t src, double *d, karst_int_t *pred) {
  unsigned char *done = calloc((size_t)g->n, 1);
  for (karst_int_t v = 0; v < g->n; v++)
    d[v] = INFINITY, pred[v] = -1;
  d[src] = 0;
  for (;;) {
    karst_int_t v = -1;
    for (karst_int_t w = 0; w < g->n; w++)
      if (!done[w] && d[w] < INFINITY && (v < 0 || d[w] < d[v])) v = w;
    if (v < 0) break;
    done[v] = 1;
    karst_arc_reader_t rd = karst_graph_arcs(g, v);
    for (karst_int_t a = g->offsets[v]; a < g->offsets[v + 1]; a++) {
      karst_int_t w = karst_arc_next(&rd);
      double nd = d[v] + wide_cost(g->xyz + 3 * v, g->xyz + 3 * w, NULL);
      if (nd < d[w]) d[w] = nd, pred[w] = v;
    }
  }
  free(done);
}

/* The error bound of the single-precision costs (include/karst/graph.h), u = 2^-24: on a
 * 3000-vertex graph whose costs span six decades, from three sources, (1) every least cost the
 * library's Dijkstra finds on the stored floats is within (1 ± u) of the exact (double) least cost,
 * and (2) the path A* returns costs, in exact costs, at most (1 + u) / (1 - u) times the exact
 * least cost. Reference: exact_dijkstra above. The test fails with half-precision costs (u =
 * 2^-11) and catches a heuristic made inadmissible by the rounding (KARST_COST_LB_MARGIN). */
static void test_single_precision_cost_bound(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_rng_t rng;
  karst_rng_init(&rng, 2026, 12);
  const double o[3] = {0, 0, 0};
  double *xyz = fx_jittered_grid(20, 15, 10, 4.0, o, 0.35, &rng);
  const karst_int_t n = 20 * 15 * 10;
  karst_graph_t g;
  fx_knn_graph(&g, n, xyz, 10, wide_cost, NULL);
  const double u = 0x1p-24, slack = 1e-13; /* slack: the double sums, < 1e-13 relative here */
  double *d = malloc((size_t)n * sizeof *d);
  karst_int_t *pred = malloc((size_t)n * sizeof *pred);
  karst_search_t *s = NULL;
  assert_int_equal(karst_search_create(&ctx, &g, &s), KARST_SUCCESS);
  karst_path_t p;
  karst_path_init(&p);
  const karst_int_t sources[3] = {0, n / 2 + 7, n - 1};
  double worst_d = 0, worst_p = 0;
  int n_differ = 0;
  for (int i = 0; i < 3; i++) {
    karst_int_t src = sources[i];
    exact_dijkstra(&g, src, d, pred);
    assert_int_equal(karst_paths_dijkstra(&ctx, s, 1, &src, NULL, NULL, 0, NULL), KARST_SUCCESS);
    for (karst_int_t v = 0; v < n; v++) {
      double df = karst_search_dist(s, v);
      assert_true(d[v] < INFINITY);
      assert_true(df >= (1 - u - slack) * d[v] && df <= (1 + u + slack) * d[v]);
      if (d[v] > 0) worst_d = fmax(worst_d, fabs(df - d[v]) / d[v]);
    }
    for (karst_int_t t = 1; t < n; t += 97) {
      if (t == src) continue;
      /* wide_cost's factor is at least 10^-3.3 per metre; less the library's margin for the
       * rounding of the stored floats, as karst_cost_lower_bound_per_metre does */
      assert_int_equal(
          karst_paths_astar(&ctx, s, src, t, pow(10.0, -3.3) * (1 - KARST_COST_LB_MARGIN), &p),
          KARST_SUCCESS);
      double exact = 0;
      for (karst_int_t j = 1; j < p.n; j++)
        exact += wide_cost(xyz + 3 * p.v[j - 1], xyz + 3 * p.v[j], NULL);
      assert_true(exact >= d[t] * (1 - slack));
      assert_true(exact <= d[t] * ((1 + u) / (1 - u) + slack));
      worst_p = fmax(worst_p, exact / d[t] - 1);
      karst_int_t len = 0;
      for (karst_int_t w = t; w >= 0; w = pred[w])
        len++;
      n_differ += len != p.n;
    }
  }
  print_message("single-precision costs: least costs within %.3g relative (bound 2^-24 = %.3g); "
                "A* paths at most %.3g above the least cost (bound %.3g); %d of the paths differ "
                "in length from the exact ones\n",
                worst_d, u, worst_p, (1 + u) / (1 - u) - 1, n_differ);
  assert_true(worst_d > 0); /* the rounding is seen: the test measures something */
  karst_path_destroy(&p);
  karst_search_free(s);
  fx_graph_free(&g);
  free(d);
  free(pred);
  free(xyz);
}

/* A* (with the admissible bound 1 per metre) equals Dijkstra on 40 random graphs. */
static void test_astar_equals_dijkstra(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  for (uint64_t seed = 1; seed <= 40; seed++) {
    karst_rng_t rng;
    karst_rng_init(&rng, seed, 7);
    const karst_int_t n = 150;
    double *xyz = malloc(3 * n * sizeof *xyz);
    for (karst_int_t i = 0; i < 3 * n; i++)
      xyz[i] = 100 * karst_rng_uniform(&rng);
    karst_graph_t g;
    fx_knn_graph(&g, n, xyz, 5, random_cost, &rng);
    karst_search_t *s1, *s2;
    assert_int_equal(karst_search_create(&ctx, &g, &s1), KARST_SUCCESS);
    assert_int_equal(karst_search_create(&ctx, &g, &s2), KARST_SUCCESS);
    karst_path_t p;
    karst_path_init(&p);
    for (int q = 0; q < 20; q++) {
      karst_int_t a = (karst_int_t)karst_rng_below(&rng, n),
                  b = (karst_int_t)karst_rng_below(&rng, n);
      assert_int_equal(karst_paths_dijkstra(&ctx, s2, 1, &a, NULL, NULL, 0, NULL), KARST_SUCCESS);
      double dref = karst_search_dist(s2, b);
      karst_error_t e = karst_paths_astar(&ctx, s1, a, b, 1.0, &p);
      if (dref < INFINITY) {
        assert_int_equal(e, KARST_SUCCESS);
        assert_rel(p.cost, dref, 1e-12);
        assert_valid_path(&g, &p, a, b);
        /* Dijkstra's own tree path is valid too */
        karst_path_t p2;
        karst_path_init(&p2);
        assert_int_equal(karst_search_path_to(&ctx, s2, b, &p2), KARST_SUCCESS);
        assert_valid_path(&g, &p2, a, b);
        karst_path_destroy(&p2);
      } else {
        assert_int_equal(e, KARST_EUNREACHABLE);
      }
    }
    karst_path_destroy(&p);
    karst_search_free(s1);
    karst_search_free(s2);
    fx_graph_free(&g);
    free(xyz);
  }
}

/* Hand-checked graph: square 0-1-2-3 with unit sides and a diagonal 0-2 of cost 1.5. */
static void test_hand_graph(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  double xyz[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 5, 5, 5};
  karst_int_t u[] = {0, 1, 2, 3, 0}, v[] = {1, 2, 3, 0, 2};
  double c[] = {1, 1, 1, 1, 1.5};
  karst_graph_t g;
  fx_graph_from_edges(&g, 5, xyz, 5, u, v, c); /* vertex 4 is isolated */
  karst_search_t *s;
  assert_int_equal(karst_search_create(&ctx, &g, &s), KARST_SUCCESS);
  karst_path_t p;
  karst_path_init(&p);
  /* 0 -> 2: the diagonal (1.5) beats two sides (2). */
  assert_int_equal(karst_paths_astar(&ctx, s, 0, 2, 1.0, &p), KARST_SUCCESS);
  assert_int_equal(p.n, 2);
  assert_close(p.cost, 1.5, 0);
  /* 1 -> 3: two sides either way (2); ties are broken by vertex index, so the same path every time.
   */
  assert_int_equal(karst_paths_astar(&ctx, s, 1, 3, 1.0, &p), KARST_SUCCESS);
  assert_close(p.cost, 2.0, 0);
  karst_int_t mid = p.v[1];
  for (int r = 0; r < 5; r++) {
    assert_int_equal(karst_paths_astar(&ctx, s, 1, 3, 1.0, &p), KARST_SUCCESS);
    assert_int_equal(p.v[1], mid);
  }
  /* Single point: the path from a vertex to itself is that vertex, cost 0. */
  assert_int_equal(karst_paths_astar(&ctx, s, 3, 3, 1.0, &p), KARST_SUCCESS);
  assert_int_equal(p.n, 1);
  assert_close(p.cost, 0, 0);
  /* Disconnected: vertex 4 cannot be reached; the message names both vertices. */
  assert_int_equal(karst_paths_astar(&ctx, s, 0, 4, 1.0, &p), KARST_EUNREACHABLE);
  assert_non_null(strstr(ctx.errmsg, "vertex 0 to vertex 4"));
  /* Bad input is refused, not crashed on. */
  assert_int_equal(karst_paths_astar(&ctx, s, 0, 9, 1.0, &p), KARST_EINVAL);
  assert_int_equal(karst_paths_astar(&ctx, s, 0, 2, NAN, &p), KARST_EINVAL);
  assert_int_equal(karst_paths_dijkstra(&ctx, s, 0, NULL, NULL, NULL, 0, NULL), KARST_EINVAL);
  /* Multi-source Dijkstra: from {0, 2}, vertex 1 and 3 are at 1, and stop after the first target.
   */
  karst_int_t src[] = {0, 2};
  unsigned char target[5] = {0, 1, 0, 1, 0};
  karst_int_t last;
  assert_int_equal(karst_paths_dijkstra(&ctx, s, 2, src, NULL, target, 1, &last), KARST_SUCCESS);
  assert_int_equal(last, 1); /* equal distances: the lower index first */
  assert_close(karst_search_dist(s, 1), 1.0, 0);
  /* Blocking vertex 1 and 3 leaves only the sources reachable. */
  unsigned char blocked[5] = {0, 1, 0, 1, 0};
  assert_int_equal(karst_paths_dijkstra(&ctx, s, 2, src, blocked, target, 1, &last), KARST_SUCCESS);
  assert_int_equal(last, -1);
  assert_true(isinf(karst_search_dist(s, 1)));
  karst_path_destroy(&p);
  karst_search_free(s);
  fx_graph_free(&g);
}

/* Empty graph and empty key-point set. */
static void test_empty(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_graph_t g;
  fx_graph_from_edges(&g, 0, NULL, 0, NULL, NULL, NULL);
  karst_search_t *s;
  assert_int_equal(karst_search_create(&ctx, &g, &s), KARST_SUCCESS);
  karst_path_t p;
  karst_path_init(&p);
  assert_int_equal(karst_paths_astar(&ctx, s, 0, 0, 1.0, &p), KARST_EINVAL);
  assert_int_equal(karst_paths_keypoint_distances(&ctx, &g, 0, NULL, 1.0, 0, NULL), KARST_SUCCESS);
  karst_search_free(s);
  fx_graph_free(&g);
}

/* The distance matrix: both methods agree, symmetric, independent of the thread count. */
static void test_keypoint_distances(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_rng_t rng;
  karst_rng_init(&rng, 11, 0);
  const karst_int_t n = 600, K = 12;
  double *xyz = malloc(3 * n * sizeof *xyz);
  for (karst_int_t i = 0; i < 3 * n; i++)
    xyz[i] = 100 * karst_rng_uniform(&rng);
  karst_graph_t g;
  fx_knn_graph(&g, n, xyz, 6, random_cost, &rng);
  karst_int_t keys[12];
  for (int i = 0; i < K; i++)
    keys[i] = 50 * i;
  keys[5] = keys[4]; /* a duplicated key point is at distance 0 from its twin */
  double d1[144], d2[144], d3[144];
  ctx.nthreads = 1;
  assert_int_equal(
      karst_paths_keypoint_distances(&ctx, &g, K, keys, 1.0, KARST_PATHS_DIJKSTRA_MULTI, d1),
      KARST_SUCCESS);
  ctx.nthreads = 2;
  assert_int_equal(
      karst_paths_keypoint_distances(&ctx, &g, K, keys, 1.0, KARST_PATHS_DIJKSTRA_MULTI, d2),
      KARST_SUCCESS);
  assert_memory_equal(d1, d2, sizeof d1);
  assert_int_equal(
      karst_paths_keypoint_distances(&ctx, &g, K, keys, 1.0, KARST_PATHS_ASTAR_PAIRS, d3),
      KARST_SUCCESS);
  int finite = 0;
  for (int i = 0; i < K; i++)
    for (int j = 0; j < K; j++) {
      assert_true(d1[i * K + j] == d1[j * K + i]);
      if (isinf(d1[i * K + j])) {
        assert_true(isinf(d3[i * K + j]));
      } else {
        assert_rel(d1[i * K + j], d3[i * K + j], 1e-12);
        finite++;
      }
    }
  assert_true(finite > K); /* the test graph is mostly connected */
  assert_close(d1[4 * K + 5], 0.0, 0);
  assert_close(d1[3 * K + 3], 0.0, 0);
  /* A key point outside the graph is refused. */
  keys[0] = n;
  assert_int_equal(karst_paths_keypoint_distances(&ctx, &g, K, keys, 1.0, 0, d1), KARST_EINVAL);
  fx_graph_free(&g);
  free(xyz);
}

/* Length-weighted mean |cos| between the path's steps and a horizontal unit direction. */
static double alignment(const karst_graph_t *g, const karst_path_t *p, const double dir[3]) {
  double num = 0, den = 0;
  for (karst_int_t i = 1; i < p->n; i++) {
    const double *a = &g->xyz[3 * p->v[i - 1]], *b = &g->xyz[3 * p->v[i]];
    double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    num += fabs(d[0] * dir[0] + d[1] * dir[1] + d[2] * dir[2]);
    den += l;
  }
  return den > 0 ? num / den : 0;
}

static karst_int_t nearest(const double *xyz, karst_int_t n, double x, double y, double z) {
  karst_int_t best = 0;
  double bd = INFINITY;
  for (karst_int_t i = 0; i < n; i++) {
    double d = pow(xyz[3 * i] - x, 2) + pow(xyz[3 * i + 1] - y, 2) + pow(xyz[3 * i + 2] - z, 2);
    if (d < bd) bd = d, best = i;
  }
  return best;
}

/* Fracture family: a vertical plane striking north (normal east, weight 50, w0 = 1). Crossing the
 * strike costs 51 per metre head-on but 2·sqrt(w0·W) ≈ 14 per metre of eastward progress by
 * zig-zagging at asin(sqrt(1/50)) ≈ 8° off strike (minimise (w0 + W sin²φ)/sin φ), so a path to
 * a target due east must run mostly along the strike (north-south steps). Control: without the
 * fracture the path runs east. */
static void test_fracture_strike(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_rng_t rng;
  karst_rng_init(&rng, 3, 0);
  const double o[3] = {0, 0, 0};
  double *xyz = fx_jittered_grid(31, 31, 1, 2.0, o, 0.3, &rng);
  const karst_int_t n = 31 * 31;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  sc.cost.w0 = 1;
  sc.cost.horizon = 0;
  sc.cost.permeability = 0;
  sc.cost.fracture = 1;
  karst_fracture_t fr = {.dip_direction = 90.0,
                         .dip = 90.0,
                         .weight = 50.0}; /* dip direction east, vertical: normal (1, 0, 0) */
  sc.fractures = &fr;
  sc.n_fractures = 1;
  fx_cost_ctx_t cc = {&sc, 4};
  karst_graph_t g;
  fx_knn_graph(&g, n, xyz, 24, fx_scenario_cost, &cc);
  karst_int_t a = nearest(xyz, n, 10, 30, 0), b = nearest(xyz, n, 50, 30, 0);
  karst_search_t *s;
  assert_int_equal(karst_search_create(&ctx, &g, &s), KARST_SUCCESS);
  karst_path_t p;
  karst_path_init(&p);
  assert_int_equal(karst_paths_astar(&ctx, s, a, b, sc.cost.w0, &p), KARST_SUCCESS);
  const double north[3] = {0, 1, 0}, east[3] = {1, 0, 0};
  double al = alignment(&g, &p, north);
  print_message("fracture: alignment with strike %.3f, with normal %.3f\n", al,
                alignment(&g, &p, east));
  assert_true(al >
              0.8); /* the 8° zig-zag gives cos 8° ≈ 0.99; the graph's directions are coarser */
  fx_graph_free(&g);
  sc.n_fractures = 0;
  fx_knn_graph(&g, n, xyz, 24, fx_scenario_cost, &cc);
  karst_search_free(s);
  assert_int_equal(karst_search_create(&ctx, &g, &s), KARST_SUCCESS);
  assert_int_equal(karst_paths_astar(&ctx, s, a, b, sc.cost.w0, &p), KARST_SUCCESS);
  assert_true(alignment(&g, &p, north) < 0.4); /* isotropic: nearly straight east */
  sc.fractures = NULL;
  karst_path_destroy(&p);
  karst_search_free(s);
  fx_graph_free(&g);
  free(xyz);
  karst_scenario_destroy(&sc);
}

/* Length-weighted fraction of the path's horizontal steps within 20° of the x or the y axis. */
static double axis_fraction(const karst_graph_t *g, const karst_path_t *p) {
  double num = 0, den = 0;
  for (karst_int_t i = 1; i < p->n; i++) {
    const double *a = &g->xyz[3 * p->v[i - 1]], *b = &g->xyz[3 * p->v[i]];
    double dx = fabs(b[0] - a[0]), dy = fabs(b[1] - a[1]), l = sqrt(dx * dx + dy * dy);
    if (l == 0) continue;
    num += fmin(dx, dy) / l < sin(20.0 * M_PI / 180.0) ? l : 0.0;
    den += l;
  }
  return den > 0 ? num / den : 0;
}

/* Two vertical fracture families, N–S planes (normal east) and E–W planes (normal north), weight
 * 10 each, w0 = 1. cost.fracture_combine = min: a direction is cheap when it follows either
 * family, so by hand cF(x) = cF(y) = min(10 − 10·1, 10 − 10·0) = 0 and cF(diagonal) =
 * 10 − 10·(1 − 1/2) = 5: 1 per metre along either axis, 6 along the diagonal; a path to a
 * target 40 m east and 40 m north must be a staircase (80 m at 1 beats 56.6 m at 6). With the
 * paper's sum, cF(d) = 10 ((n1·d)² + (n2·d)²) = 10 for every horizontal d (a quadratic form
 * with a double eigenvalue): isotropic, so the path runs along the diagonal. */
static void test_fracture_min_axes(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_rng_t rng;
  karst_rng_init(&rng, 5, 0);
  const double o[3] = {0, 0, 0};
  double *xyz = fx_jittered_grid(31, 31, 1, 2.0, o, 0.2, &rng);
  const karst_int_t n = 31 * 31;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  sc.cost.w0 = 1, sc.cost.horizon = 0, sc.cost.permeability = 0, sc.cost.fracture = 1;
  karst_fracture_t fr[2] = {{.dip_direction = 90.0, .dip = 90.0, .weight = 10.0},
                            {.dip_direction = 0.0, .dip = 90.0, .weight = 10.0}};
  sc.fractures = fr;
  sc.n_fractures = 2;
  const double x[3] = {1, 0, 0}, y[3] = {0, 1, 0}, diag[3] = {1, 1, 0};
  double lb[2], frac[2];
  for (int mode = 0; mode < 2; mode++) {
    sc.cost.fracture_combine = mode ? KARST_FRACTURE_MIN : KARST_FRACTURE_SUM;
    double cx = T_fracture_term(&sc, x), cy = T_fracture_term(&sc, y),
           cd = T_fracture_term(&sc, diag);
    assert_close(cx, mode ? 0.0 : 10.0, 1e-12);
    assert_close(cy, mode ? 0.0 : 10.0, 1e-12);
    assert_close(cd, mode ? 5.0 : 10.0, 1e-12);
    lb[mode] = karst_cost_lower_bound_per_metre(&sc);
    fx_cost_ctx_t cc = {&sc, 1}; /* the cost is constant along an edge: one point is exact */
    karst_graph_t g;
    fx_knn_graph(&g, n, xyz, 24, fx_scenario_cost, &cc);
    karst_int_t a = nearest(xyz, n, 10, 10, 0), b = nearest(xyz, n, 50, 50, 0);
    karst_search_t *s;
    assert_int_equal(karst_search_create(&ctx, &g, &s), KARST_SUCCESS);
    karst_path_t p;
    karst_path_init(&p);
    assert_int_equal(karst_paths_astar(&ctx, s, a, b, lb[mode], &p), KARST_SUCCESS);
    assert_valid_path(&g, &p, a, b);
    frac[mode] = axis_fraction(&g, &p);
    print_message("fracture_combine %s: %.3f of the path within 20 degrees of an axis\n",
                  mode ? "min" : "sum", frac[mode]);
    karst_path_destroy(&p);
    karst_search_free(s);
    fx_graph_free(&g);
  }
  /* Lower bounds by hand: sum: w0 + λmin(10 e_x e_xᵀ + 10 e_y e_yᵀ) = 1 + 0 (vertical d);
   * min: w0 + 0. */
  assert_close(lb[0], 1.0 * (1 - KARST_COST_LB_MARGIN), 1e-8);
  assert_close(lb[1], 1.0 * (1 - KARST_COST_LB_MARGIN), 1e-8);
  assert_true(frac[1] > 0.9); /* staircase */
  assert_true(frac[0] < 0.5); /* diagonal */
  sc.fractures = NULL;
  sc.n_fractures = 0;
  karst_scenario_destroy(&sc);
  free(xyz);
}

/* Copy of g whose arcs flagged in @p flag cost r times as much (the graph karst_paths_astar_reuse
 * searches implicitly). */
static void discounted_copy(const karst_graph_t *g, const unsigned char *flag, double r,
                            karst_graph_t *out, karst_arc_cost_t **cost) {
  *out = *g;
  *cost = malloc((size_t)(g->n_arcs + 1) * sizeof **cost);
  for (karst_int_t a = 0; a < g->n_arcs; a++)
    (*cost)[a] = flag[a] ? karst_arc_cost_round(r * g->cost[a]) : g->cost[a];
  out->cost = *cost;
}

/* Path sharing: A* with the reuse heuristic (key-point distance rows + distance to the network)
 * equals Dijkstra on an explicitly discounted copy of the graph, on 20 random graphs whose
 * network grows path by path; the incrementally lowered distance to the network equals a fresh
 * multi-source Dijkstra from all network vertices; without rows or without the network distance
 * the cost is the same. Reference: Dijkstra on the copy, an independent computation. */
static void test_astar_reuse_equals_dijkstra(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  for (uint64_t seed = 1; seed <= 20; seed++) {
    karst_rng_t rng;
    karst_rng_init(&rng, seed, 11);
    const karst_int_t n = 200, K = 6;
    const double r = 0.1 + 0.8 * karst_rng_uniform(&rng);
    double *xyz = malloc(3 * n * sizeof *xyz);
    for (karst_int_t i = 0; i < 3 * n; i++)
      xyz[i] = 100 * karst_rng_uniform(&rng);
    karst_graph_t g;
    fx_knn_graph(&g, n, xyz, 6, random_cost, &rng);
    karst_int_t keys[6];
    for (int i = 0; i < K; i++)
      keys[i] = (karst_int_t)karst_rng_below(&rng, n);
    double dist[36];
    float *bound = malloc((size_t)(K - 1) * (size_t)n * sizeof *bound);
    assert_int_equal(karst_paths_keypoint_bounds(&ctx, &g, K, keys, dist, bound), KARST_SUCCESS);
    /* The rows are lower bounds of the exact distance to their key point. */
    karst_search_t *s1, *s2;
    assert_int_equal(karst_search_create(&ctx, &g, &s1), KARST_SUCCESS);
    for (int i = 0; i < K - 1; i++) {
      assert_int_equal(karst_paths_dijkstra(&ctx, s1, 1, &keys[i], NULL, NULL, 0, NULL),
                       KARST_SUCCESS);
      for (karst_int_t v = 0; v < n; v++)
        assert_true((double)bound[(size_t)i * n + v] <= karst_search_dist(s1, v));
    }
    unsigned char *flag = calloc((size_t)g.n_arcs + 1, 1), *in_net = calloc((size_t)n, 1);
    int32_t *heads = fx_heads(&g);
    assert_non_null(heads);
    double *to_net = malloc((size_t)n * sizeof *to_net),
           *to_cap = malloc((size_t)n * sizeof *to_cap);
    const double M =
        30.0; /* the skeleton's cap on the network distance, here about a third of the box */
    for (karst_int_t v = 0; v < n; v++)
      to_net[v] = INFINITY, to_cap[v] = M;
    karst_path_t p, q;
    karst_path_init(&p);
    karst_path_init(&q);
    for (int step = 0; step < 12; step++) {
      int ia = (int)karst_rng_below(&rng, K - 1);
      karst_int_t t = keys[ia], src = (karst_int_t)karst_rng_below(&rng, n);
      karst_graph_t gd;
      karst_arc_cost_t *cd;
      discounted_copy(&g, flag, r, &gd, &cd);
      assert_int_equal(karst_search_create(&ctx, &gd, &s2), KARST_SUCCESS);
      assert_int_equal(karst_paths_dijkstra(&ctx, s2, 1, &src, NULL, NULL, 0, NULL), KARST_SUCCESS);
      double dref = karst_search_dist(s2, t);
      const karst_reuse_t full = {r, flag, to_net, NULL, NULL, 0, NULL, NULL},
                          no_net = {r, flag, NULL, NULL, NULL, 0, NULL, NULL},
                          capped = {r, flag, to_cap, NULL, NULL, 0, NULL, NULL};
      karst_error_t e =
          karst_paths_astar_reuse(&ctx, s1, src, t, 1.0, bound + (size_t)ia * n, &full, &p);
      if (!(dref < INFINITY)) {
        assert_int_equal(e, KARST_EUNREACHABLE);
      } else {
        assert_int_equal(e, KARST_SUCCESS);
        /* The search discounts in double, the copy stores r c as a float: they agree within the
         * single-precision bound of include/karst/graph.h, (1 + u) / (1 - u) - 1, u = 2^-24. */
        const double tol = 2 * 0x1p-24 / (1 - 0x1p-24) + 1e-12;
        assert_rel(p.cost, dref, tol);
        assert_valid_path_rel(&gd, &p, src, t, tol); /* gd holds r c rounded, p summed r c */
        assert_int_equal(karst_paths_astar_reuse(&ctx, s1, src, t, 1.0, NULL, &full, &q),
                         KARST_SUCCESS);
        assert_rel(q.cost, dref, tol);
        assert_int_equal(
            karst_paths_astar_reuse(&ctx, s1, src, t, 1.0, bound + (size_t)ia * n, &no_net, &q),
            KARST_SUCCESS);
        assert_rel(q.cost, dref, tol);
        assert_int_equal(
            karst_paths_astar_reuse(&ctx, s1, src, t, 1.0, bound + (size_t)ia * n, &capped, &q),
            KARST_SUCCESS);
        assert_rel(q.cost, dref, tol);
        /* The path joins the network: flag its arcs, lower the distances. */
        for (karst_int_t i = 1; i < p.n; i++)
          for (karst_int_t a = 0; a < g.n_arcs; a++) {
            karst_int_t u = p.v[i - 1], w = p.v[i];
            if (a >= g.offsets[u] && a < g.offsets[u + 1] && heads[a] == w) flag[a] = 1;
            if (a >= g.offsets[w] && a < g.offsets[w + 1] && heads[a] == u) flag[a] = 1;
          }
        for (karst_int_t i = 0; i < p.n; i++)
          in_net[p.v[i]] = 1;
        assert_int_equal(karst_paths_lower_distances(&ctx, s1, p.n, p.v, to_net), KARST_SUCCESS);
        assert_int_equal(karst_paths_lower_distances(&ctx, s1, p.n, p.v, to_cap), KARST_SUCCESS);
        karst_int_t m = 0, *net = malloc((size_t)n * sizeof *net);
        for (karst_int_t v = 0; v < n; v++)
          if (in_net[v]) net[m++] = v;
        assert_int_equal(karst_paths_dijkstra(&ctx, s2, m, net, NULL, NULL, 0, NULL),
                         KARST_SUCCESS);
        for (karst_int_t v = 0; v < n; v++) {
          double ref = karst_search_dist(s2, v);
          if (ref < INFINITY)
            assert_rel(to_net[v], ref, 1e-12);
          else
            assert_true(isinf(to_net[v]));
          /* Capped: min(distance, M), lowered only where the new path comes within M. */
          assert_rel(to_cap[v], ref < M ? ref : M, 1e-12);
        }
        free(net);
      }
      karst_search_free(s2);
      free(cd);
    }
    /* A factor outside (0, 1] is refused. */
    const karst_reuse_t bad = {0.0, flag, to_net, NULL, NULL, 0, NULL, NULL};
    assert_int_equal(karst_paths_astar_reuse(&ctx, s1, keys[0], keys[1], 1.0, NULL, &bad, &p),
                     KARST_EINVAL);
    karst_path_destroy(&p);
    karst_path_destroy(&q);
    karst_search_free(s1);
    free(flag), free(in_net), free(to_net), free(to_cap), free(bound), free(heads);
    fx_graph_free(&g);
    free(xyz);
  }
}

/* A low-resistance sphere (π = 0 inside, radius 15 m, centre 25 m off the straight line) attracts
 * the path: with w0 = 0.1, wπ = 1 and background resistance 1, a metre costs 1.1 outside and 0.1
 * inside, so the detour through the sphere (≈ 2 × 22 m outside + 30 m inside ≈ 51) beats the
 * straight 60 m (66). Control: without the sphere no path vertex enters it. */
static void test_sphere_attracts(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_rng_t rng;
  karst_rng_init(&rng, 5, 0);
  const double o[3] = {0, 0, 0};
  double *xyz = fx_jittered_grid(41, 41, 1, 2.0, o, 0.3, &rng);
  const karst_int_t n = 41 * 41;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  sc.cost.w0 = 0.1;
  sc.cost.horizon = 0;
  sc.cost.fracture = 0;
  sc.cost.permeability = 1;
  karst_perm_node_t sphere;
  memset(&sphere, 0, sizeof sphere);
  sphere.kind = KARST_PERM_SPHERE;
  sphere.resistance = 0;
  sphere.center[0] = 40, sphere.center[1] = 65, sphere.center[2] = 0;
  sphere.radius = 15;
  for (int with = 1; with >= 0; with--) {
    sc.permeability.root = with ? &sphere : NULL;
    fx_cost_ctx_t cc = {&sc, 8};
    karst_graph_t g;
    fx_knn_graph(&g, n, xyz, 12, fx_scenario_cost, &cc);
    karst_search_t *s;
    assert_int_equal(karst_search_create(&ctx, &g, &s), KARST_SUCCESS);
    karst_path_t p;
    karst_path_init(&p);
    karst_int_t a = nearest(xyz, n, 10, 40, 0), b = nearest(xyz, n, 70, 40, 0);
    assert_int_equal(karst_paths_astar(&ctx, s, a, b, sc.cost.w0, &p), KARST_SUCCESS);
    int inside = 0;
    for (karst_int_t i = 0; i < p.n; i++) {
      const double *q = &xyz[3 * p.v[i]];
      inside += hypot(q[0] - 40, q[1] - 65) < 15;
    }
    if (with)
      assert_true(inside >= 5);
    else
      assert_int_equal(inside, 0);
    karst_path_destroy(&p);
    karst_search_free(s);
    fx_graph_free(&g);
  }
  sc.permeability.root = NULL;
  free(xyz);
  karst_scenario_destroy(&sc);
}

/* A straight corridor along a horizon: both ends 8 m above a horizontal horizon at z = 20 (radius
 * 6 m; w0 = 0.2, wL = 1). Off the horizon a metre costs 1.2, on it 0.2, so the path drops onto
 * the horizon and runs along it: its middle third stays within 2 m of z = 20 and along x.
 * Control: without the horizon the path keeps z ≈ 28. */
static void test_horizon_corridor(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_rng_t rng;
  karst_rng_init(&rng, 9, 0);
  const double o[3] = {0, 0, 10};
  double *xyz = fx_jittered_grid(41, 5, 11, 2.0, o, 0.25, &rng);
  const karst_int_t n = 41 * 5 * 11;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  sc.cost.w0 = 0.2;
  sc.cost.horizon = 1;
  sc.cost.fracture = 0;
  sc.cost.permeability = 0;
  karst_horizon_t hz = {.elevation = 20.0, .radius = 6.0};
  for (int with = 1; with >= 0; with--) {
    sc.horizons = with ? &hz : NULL;
    sc.n_horizons = with;
    fx_cost_ctx_t cc = {&sc, 8};
    karst_graph_t g;
    fx_knn_graph(&g, n, xyz, 26, fx_scenario_cost, &cc);
    karst_search_t *s;
    assert_int_equal(karst_search_create(&ctx, &g, &s), KARST_SUCCESS);
    karst_path_t p;
    karst_path_init(&p);
    karst_int_t a = nearest(xyz, n, 2, 4, 28), b = nearest(xyz, n, 78, 4, 28);
    assert_int_equal(karst_paths_astar(&ctx, s, a, b, sc.cost.w0, &p), KARST_SUCCESS);
    double maxdev = 0;
    for (karst_int_t i = 0; i < p.n; i++) {
      const double *q = &xyz[3 * p.v[i]];
      if (q[0] < 27 || q[0] > 53) continue;
      maxdev = fmax(maxdev, fabs(q[2] - (with ? 20.0 : 28.0)));
    }
    print_message("horizon %d: max |z - target| in the middle third %.2f m\n", with, maxdev);
    assert_true(maxdev < 2.0);
    const double east[3] = {1, 0, 0};
    if (with) assert_true(alignment(&g, &p, east) > 0.7);
    karst_path_destroy(&p);
    karst_search_free(s);
    fx_graph_free(&g);
  }
  sc.horizons = NULL;
  sc.n_horizons = 0;
  free(xyz);
  karst_scenario_destroy(&sc);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_astar_equals_dijkstra),
      cmocka_unit_test(test_single_precision_cost_bound),
      cmocka_unit_test(test_hand_graph),
      cmocka_unit_test(test_empty),
      cmocka_unit_test(test_keypoint_distances),
      cmocka_unit_test(test_fracture_strike),
      cmocka_unit_test(test_fracture_min_axes),
      cmocka_unit_test(test_astar_reuse_equals_dijkstra),
      cmocka_unit_test(test_sphere_attracts),
      cmocka_unit_test(test_horizon_corridor),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
