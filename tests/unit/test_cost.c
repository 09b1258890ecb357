/* Cost functions (Paris et al. 2021, §4.2): line integrals against hand
 * calculations and an independent fine midpoint rule, the fracture term, the
 * bedrock tests and the admissible lower bound. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "geology_fixture.h"
#include "karst.h"
#include "test_util.h"

/* A 100 m box under a flat terrain at 200 m with every weight zero but w0 = 1. */
static void base_scenario(karst_scenario_t *sc) {
  karst_scenario_init(sc);
  for (int a = 0; a < 3; a++)
    sc->domain_min[a] = 0, sc->domain_max[a] = 100;
  sc->terrain.elevation = 200;
  sc->cost.w0 = 1, sc->cost.horizon = 0, sc->cost.fracture = 0, sc->cost.permeability = 0;
}

static void add_horizon(karst_scenario_t *sc, double elev, double radius, double dip,
                        double dipdir) {
  sc->horizons = realloc(sc->horizons, sizeof(karst_horizon_t) * (size_t)(sc->n_horizons + 1));
  karst_horizon_t *h = &sc->horizons[sc->n_horizons++];
  memset(h, 0, sizeof *h);
  h->elevation = elev, h->radius = radius, h->dip = dip, h->dip_direction = dipdir;
  h->origin[0] = 50, h->origin[1] = 50;
}

static void add_fracture(karst_scenario_t *sc, double dipdir, double dip, double w) {
  sc->fractures = realloc(sc->fractures, sizeof(karst_fracture_t) * (size_t)(sc->n_fractures + 1));
  karst_fracture_t *f = &sc->fractures[sc->n_fractures++];
  memset(f, 0, sizeof *f);
  f->dip_direction = dipdir, f->dip = dip, f->weight = w;
}

/* Independent reference: midpoint rule with n points of c(p, d) along [a, b]. */
static double midpoint_integral(const karst_scenario_t *sc, const double a[3], const double b[3],
                                int n) {
  double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), sum = 0;
  karst_geology_t *g = geo_make(sc);
  for (int i = 0; i < n; i++) {
    double s = (i + 0.5) / n, p[3] = {a[0] + s * d[0], a[1] + s * d[1], a[2] + s * d[2]};
    sum += karst_cost_point(g, p, d);
  }
  karst_geology_free(g);
  return sum * len / n;
}

/* Constant c: w0 = 1, wL = 1 with no horizon (cL = 1), wπ = 1 with background
 * 0.5: c = 2.5 per metre; a 3-4-5 edge costs 12.5 (hand calculation). */
static void test_constant_cost(void **state) {
  (void)state;
  karst_scenario_t sc;
  base_scenario(&sc);
  sc.cost.horizon = 1, sc.cost.permeability = 1, sc.permeability.background = 0.5;
  double a[3] = {10, 10, 10}, b[3] = {13, 14, 10};
  assert_close(T_cost_edge(&sc, a, b), 12.5, 1e-12);
  assert_close(T_cost_edge(&sc, a, a), 0.0, 0.0);
  double p[3] = {50, 50, 50}, d[3] = {0, 0, 1};
  assert_close(T_cost_point(&sc, p, d), 2.5, 1e-15);
  karst_scenario_destroy(&sc);
}

/* A horizontal horizon at z = 50 with r = 4. Vertical edge z 40 -> 60:
 * ∫ cL = (20 − 8)·1 + 2 ∫_0^4 g(u/4) du = 12 + 2·4·(1 − 1/2) = 16, so with
 * w0 = wL = 1 the cost is 20 + 16 = 36 (hand calculation, ∫_0^1 g = 1/2). */
static void test_horizon_vertical_edge(void **state) {
  (void)state;
  karst_scenario_t sc;
  base_scenario(&sc);
  sc.cost.horizon = 1;
  add_horizon(&sc, 50, 4, 0, 0);
  double a[3] = {20, 20, 40}, b[3] = {20, 20, 60};
  assert_close(T_cost_edge(&sc, a, b), 36.0, 1e-12);
  /* The point term: g(2/4) = 3/4 − 2/8 = 0.5, so c = 1.5. */
  double p[3] = {0, 0, 52}, d[3] = {1, 0, 0};
  assert_close(T_cost_point(&sc, p, d), 1.5, 1e-15);
  /* Edge along the horizon plane costs exactly w0 per metre. */
  double c0[3] = {10, 10, 50}, c1[3] = {90, 10, 50};
  assert_close(T_cost_edge(&sc, c0, c1), 80.0, 1e-12);
  karst_scenario_destroy(&sc);
}

/* Oblique edge from z = 47 to z = 58 with horizontal run 44/3 (3-4-5, so
 * ds = 5/3 dz). ∫ g(|z − 50|/4) dz over [47, 58] = 4 H(3/4) + 4 H(1) + 4
 * with H(t) = t³ − t⁴/2: 4(0.421875 − 0.158203125) + 2 + 4 = 7.0546875.
 * Cost = L + (5/3)·7.0546875 with L = 55/3 (hand calculation). */
static void test_horizon_oblique_edge(void **state) {
  (void)state;
  karst_scenario_t sc;
  base_scenario(&sc);
  sc.cost.horizon = 1;
  add_horizon(&sc, 50, 4, 0, 0);
  double a[3] = {10, 30, 47}, b[3] = {10 + 44.0 / 3.0, 30, 58};
  double expect = 55.0 / 3.0 + 5.0 / 3.0 * 7.0546875;
  assert_close(T_cost_edge(&sc, a, b), expect, 1e-12);
  karst_scenario_destroy(&sc);
}

/* Dipping horizons of different radii overlapping: the exact piecewise
 * integral against an independent 2e6-point midpoint rule (error ~ h² f''
 * < 1e-9 relative here). */
static void test_horizon_dipping_reference(void **state) {
  (void)state;
  karst_scenario_t sc;
  base_scenario(&sc);
  sc.cost.horizon = 2.5;
  add_horizon(&sc, 50, 6, 20, 45);
  add_horizon(&sc, 55, 3, 5, 200);
  add_horizon(&sc, 30, 10, 0, 0);
  const double E[][6] = {{10, 20, 35, 90, 70, 65},
                         {50, 50, 40, 52, 48, 62},
                         {5, 95, 20, 95, 5, 80},
                         {40, 40, 52, 60, 40, 52}};
  for (int e = 0; e < 4; e++) {
    double got = T_cost_edge(&sc, E[e], E[e] + 3);
    double ref = midpoint_integral(&sc, E[e], E[e] + 3, 2000000);
    assert_rel(got, ref, 1e-9);
  }
  karst_scenario_destroy(&sc);
}

/* A vertical fracture plane striking north (dip 90, dip direction 90: normal
 * east). Along strike (north) and along dip (vertical) the edge costs w0 per
 * metre; along the normal (east) it costs w0 + wF·w (hand calculation). */
static void test_fracture_strike(void **state) {
  (void)state;
  karst_scenario_t sc;
  base_scenario(&sc);
  sc.cost.fracture = 2.0;
  add_fracture(&sc, 90, 90, 0.75);
  double a[3] = {50, 10, 50}, north[3] = {50, 30, 50}, up[3] = {50, 10, 70}, east[3] = {70, 10, 50};
  assert_close(T_cost_edge(&sc, a, north), 20.0 * 1.0, 1e-12);
  assert_close(T_cost_edge(&sc, a, up), 20.0 * 1.0, 1e-12);
  assert_close(T_cost_edge(&sc, a, east), 20.0 * (1.0 + 2.0 * 0.75), 1e-12);
  /* 45° between strike and normal: (n·d)² = 1/2. */
  double ne[3] = {60, 20, 50};
  assert_close(T_cost_edge(&sc, a, ne), sqrt(200.0) * (1.0 + 2.0 * 0.75 * 0.5), 1e-12);
  double d[3] = {3, 0, 0};
  assert_close(T_fracture_term(&sc, d), 0.75, 1e-15);
  karst_scenario_destroy(&sc);
}

/* Permeability: a stratum of resistance 0 between z = 10 and 20 in a
 * background of 1: vertical edge 5 -> 25 has ∫π = 5 + 0 + 5 = 10, cost
 * 20 + 10 = 30 (hand calculation; the jumps are break points, so exact). */
static void test_perm_stratum(void **state) {
  (void)state;
  karst_scenario_t sc;
  base_scenario(&sc);
  sc.cost.permeability = 1;
  sc.permeability.background = 1;
  sc.permeability.root = calloc(1, sizeof(karst_perm_node_t));
  sc.permeability.root->kind = KARST_PERM_STRATUM;
  sc.permeability.root->bottom = 10, sc.permeability.root->top = 20;
  sc.permeability.root->resistance = 0;
  double a[3] = {30, 30, 5}, b[3] = {30, 30, 25};
  assert_close(T_cost_edge(&sc, a, b), 30.0, 1e-12);
  karst_scenario_destroy(&sc);
}

/* A low-resistance sphere with a smooth falloff inside a union with a
 * stratum: GL3 with break points against a 2e6-point midpoint rule. */
static void test_perm_sphere_reference(void **state) {
  (void)state;
  karst_scenario_t sc;
  base_scenario(&sc);
  sc.cost.permeability = 3;
  sc.permeability.background = 0.9;
  karst_perm_node_t *root = calloc(1, sizeof *root);
  root->kind = KARST_PERM_UNION;
  root->n_children = 2;
  root->children = calloc(2, sizeof(karst_perm_node_t));
  karst_perm_node_t *sp = &root->children[0], *st = &root->children[1];
  sp->kind = KARST_PERM_SPHERE, sp->center[0] = 50, sp->center[1] = 50, sp->center[2] = 50;
  sp->radius = 8, sp->falloff = 6, sp->resistance = 0.05;
  st->kind = KARST_PERM_STRATUM, st->bottom = 70, st->top = 75, st->resistance = 0.4;
  sc.permeability.root = root;
  const double E[][6] = {{30, 50, 50, 70, 50, 50},
                         {40, 45, 60, 62, 55, 80},
                         {50, 50, 50, 51, 50, 50},
                         {35, 35, 35, 65, 60, 62}};
  for (int e = 0; e < 4; e++) {
    double got = T_cost_edge(&sc, E[e], E[e] + 3);
    double ref = midpoint_integral(&sc, E[e], E[e] + 3, 2000000);
    assert_rel(got, ref, 1e-7);
  }
  karst_scenario_destroy(&sc);
}

/* Bedrock: a V-shaped grid terrain (50, 10, 50 m across x) and the saddle
 * cell of a bilinear surface, whose minimum along a diagonal is inside the
 * cell (h = 10(s² + (1−s)²), min 5 at s = 1/2), found by the exact test. */
static void test_bedrock_segments(void **state) {
  (void)state;
  karst_scenario_t sc;
  base_scenario(&sc);
  sc.domain_min[2] = -10;
  sc.terrain.is_grid = 1;
  sc.terrain.ncols = 3, sc.terrain.nrows = 2, sc.terrain.cellsize = 10;
  sc.terrain.xll = 0, sc.terrain.yll = 0;
  sc.terrain.z = malloc(6 * sizeof(double));
  const double v[6] = {50, 10, 50, 50, 10, 50};
  memcpy(sc.terrain.z, v, sizeof v);
  double a[3] = {0, 5, 30}, b[3] = {20, 5, 30}, a2[3] = {0, 5, 5}, b2[3] = {20, 5, 5};
  assert_true(T_in_bedrock(&sc, a) && T_in_bedrock(&sc, b));
  assert_false(T_segment_in_bedrock(&sc, a, b));
  assert_true(isinf(T_cost_edge(&sc, a, b)));
  assert_true(T_segment_in_bedrock(&sc, a2, b2));
  assert_close(T_cost_edge(&sc, a2, b2), 20.0, 1e-12);
  /* Saddle: one cell, corners z00 = 10, z10 = 0, z01 = 0, z11 = 10. */
  sc.terrain.ncols = 2, sc.terrain.nrows = 2;
  const double s[4] = {10, 0, 0, 10};
  memcpy(sc.terrain.z, s, sizeof s);
  double p[3] = {0, 0, 5.1}, q[3] = {10, 10, 5.1}, p2[3] = {0, 0, 4.9}, q2[3] = {10, 10, 4.9};
  assert_true(T_in_bedrock(&sc, p) && T_in_bedrock(&sc, q));
  assert_false(T_segment_in_bedrock(&sc, p, q));
  assert_true(T_segment_in_bedrock(&sc, p2, q2));
  /* Outside the box, non-finite input. */
  double out[3] = {-1, 5, 0}, nan3[3] = {NAN, 5, 0};
  assert_false(T_in_bedrock(&sc, out));
  assert_true(isinf(T_cost_edge(&sc, out, p2)));
  assert_true(isinf(T_cost_edge(&sc, nan3, p2)));
  karst_scenario_destroy(&sc);
}

/* Prescribed path between two key points: an edge lying on it costs
 * cost.prescribed times its integral; a crossing edge does not. */
static void test_prescribed(void **state) {
  (void)state;
  karst_scenario_t sc;
  base_scenario(&sc);
  sc.cost.prescribed = 0.1;
  sc.sampling.feature_radius = 3;
  sc.n_key_points = 2;
  sc.key_points = calloc(2, sizeof(karst_keypoint_t));
  const double P[3] = {10, 50, 20}, Q[3] = {90, 50, 20};
  memcpy(sc.key_points[0].p, P, sizeof P), memcpy(sc.key_points[1].p, Q, sizeof Q);
  sc.n_prescribed = 1;
  sc.prescribed = calloc(1, sizeof(karst_prescribed_path_t));
  sc.prescribed[0].a = 0, sc.prescribed[0].b = 1;
  double a[3] = {30, 51, 20}, b[3] = {40, 49, 21}, c[3] = {30, 60, 20};
  assert_close(T_cost_edge(&sc, a, b), 0.1 * sqrt(100 + 4 + 1), 1e-12);
  assert_close(T_cost_edge(&sc, a, c), sqrt(81.0), 1e-12);
  karst_scenario_destroy(&sc);
}

/* Lower bound: hand values (one family: λmin = 0, so w0; three orthogonal
 * families of weight w: M = w I, so w0 + wF w), then on random scenarios
 * LB <= c(p, d) for 2e5 random (p, d), LB·|ab| <= cost(a, b) for random
 * edges, and the bound is nearly attained by some direction. */
static void test_lower_bound(void **state) {
  (void)state;
  karst_scenario_t sc;
  base_scenario(&sc);
  sc.cost.fracture = 2;
  add_fracture(&sc, 30, 60, 1.0);
  assert_close(karst_cost_lower_bound_per_metre(&sc), 1.0 * (1 - KARST_COST_LB_MARGIN), 1e-8);
  karst_scenario_destroy(&sc);
  base_scenario(&sc);
  sc.cost.fracture = 2;
  add_fracture(&sc, 0, 0, 0.5);
  add_fracture(&sc, 0, 90, 0.5);
  add_fracture(&sc, 90, 90, 0.5);
  assert_close(karst_cost_lower_bound_per_metre(&sc), 2.0 * (1 - KARST_COST_LB_MARGIN), 1e-8);
  /* cost.fracture_combine = min: cF = 0 in any of the three planes (hand: W − w_k = 0 for equal
   * weights), so the bound is w0 = 1. */
  sc.cost.fracture_combine = KARST_FRACTURE_MIN;
  assert_close(karst_cost_lower_bound_per_metre(&sc), 1.0 * (1 - KARST_COST_LB_MARGIN), 1e-8);
  karst_scenario_destroy(&sc);

  karst_rng_t r;
  karst_rng_init(&r, 7, 0);
  for (int trial = 0; trial < 20; trial++) {
    base_scenario(&sc);
    sc.cost.w0 = karst_rng_uniform_range(&r, 0.1, 2);
    sc.cost.horizon = karst_rng_uniform(&r);
    sc.cost.fracture = karst_rng_uniform_range(&r, 0, 3);
    sc.cost.permeability = karst_rng_uniform(&r);
    sc.cost.fracture_combine = trial % 3 == 2 ? KARST_FRACTURE_MIN : KARST_FRACTURE_SUM;
    int nf = (int)karst_rng_below(&r, 5);
    for (int k = 0; k < nf; k++)
      add_fracture(&sc, karst_rng_uniform_range(&r, 0, 360), karst_rng_uniform_range(&r, 0, 90),
                   karst_rng_uniform(&r));
    if (trial % 2) add_horizon(&sc, karst_rng_uniform_range(&r, 20, 80), 5, 10, 30);
    sc.permeability.background = karst_rng_uniform(&r);
    sc.permeability.root = calloc(1, sizeof(karst_perm_node_t));
    sc.permeability.root->kind = KARST_PERM_SPHERE;
    for (int a = 0; a < 3; a++)
      sc.permeability.root->center[a] = 50;
    sc.permeability.root->radius = 20, sc.permeability.root->falloff = 10;
    sc.permeability.root->resistance = karst_rng_uniform(&r);
    double lb = karst_cost_lower_bound_per_metre(&sc), cmin = INFINITY, fmin_seen = INFINITY;
    karst_geology_t *g = geo_make(&sc);
    for (int i = 0; i < 10000; i++) {
      double p[3], d[3];
      for (int a = 0; a < 3; a++)
        p[a] = karst_rng_uniform_range(&r, 0, 100);
      karst_rng_unit_vector(&r, d);
      double c = karst_cost_point(g, p, d);
      assert_true(lb <= c);
      cmin = fmin(cmin, c);
      fmin_seen = fmin(fmin_seen, karst_cost_fracture_term(g, d));
    }
    for (int i = 0; i < 300; i++) {
      double a[3], b[3], d[3];
      for (int k = 0; k < 3; k++)
        a[k] = karst_rng_uniform_range(&r, 10, 90);
      karst_rng_unit_vector(&r, d);
      double len = karst_rng_uniform_range(&r, 0.1, 10);
      for (int k = 0; k < 3; k++)
        b[k] = a[k] + len * d[k];
      assert_true(lb * len <= karst_cost_edge(g, a, b));
    }
    karst_geology_free(g);
    (void)cmin;
    /* The fracture part of the bound is tight: some random direction comes
     * within 2 % of Σ w_k of the minimum λmin (1e4 directions). */
    double lbF =
        (lb / (1 - KARST_COST_LB_MARGIN) - sc.cost.w0 - sc.cost.horizon * (sc.n_horizons == 0) -
         sc.cost.permeability *
             fmin(sc.permeability.background, sc.permeability.root->resistance)) /
        (sc.cost.fracture > 0 ? sc.cost.fracture : 1);
    double sw = 0;
    for (int k = 0; k < nf; k++)
      sw += sc.fractures[k].weight;
    if (nf > 0 && sc.cost.fracture > 0) assert_true(fmin_seen <= lbF + 0.02 * sw + 1e-12);
    karst_scenario_destroy(&sc);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_constant_cost),
      cmocka_unit_test(test_horizon_vertical_edge),
      cmocka_unit_test(test_horizon_oblique_edge),
      cmocka_unit_test(test_horizon_dipping_reference),
      cmocka_unit_test(test_fracture_strike),
      cmocka_unit_test(test_perm_stratum),
      cmocka_unit_test(test_perm_sphere_reference),
      cmocka_unit_test(test_bedrock_segments),
      cmocka_unit_test(test_prescribed),
      cmocka_unit_test(test_lower_bound),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
