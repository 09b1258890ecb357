/* Two-stage routing end to end (src/routing, src/skeleton, karst_generate): vadose paths
 * descend, phreatic paths stay at their own spring's water table and never rise back, exclusion
 * zones are gone round, a conduit fault attracts a path and a barrier fault diverts one, and the
 * connectivity matrix is obeyed. Each scenario is small and hand-placed; the expectations are
 * geometric facts stated in each test. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "geology/geology_internal.h"
#include "geology_fixture.h"
#include "karst.h"
#include "test_util.h"

static void add_key(karst_scenario_t *sc, const char *name, karst_keypoint_type_t type, double x,
                    double y, double z) {
  sc->key_points = realloc(sc->key_points, sizeof *sc->key_points * (size_t)(sc->n_key_points + 1));
  karst_keypoint_t *k = &sc->key_points[sc->n_key_points++];
  memset(k, 0, sizeof *k);
  snprintf(k->name, sizeof k->name, "%s", name);
  k->type = type;
  k->p[0] = x, k->p[1] = y, k->p[2] = z;
}

/* 300 x 300 x 150 m under a flat terrain at 150 m: fill radius 8 m, feature radius 4 m (the
 * water table's layer), k = 30, plain costs (w0 = 1), no amplification, no displacement to speak
 * of (θ = 0: a few centimetres). One sink at (30, 30, 148) and one spring at (270, 270, 40):
 * its water table is the horizontal plane z = 40, band ±5 m. */
static void base(karst_scenario_t *sc) {
  karst_scenario_init(sc);
  sc->domain_max[0] = sc->domain_max[1] = 300;
  sc->domain_max[2] = 150;
  sc->terrain.elevation = 150;
  sc->cost.horizon = 0, sc->cost.fracture = 0, sc->cost.permeability = 0;
  sc->sampling.fill_radius = 8, sc->sampling.feature_radius = 4, sc->sampling.k = 30;
  sc->tortuosity = 0;
  sc->reuse = 0.5;
  add_key(sc, "sink", KARST_KEYPOINT_SINK, 30, 30, 148);
  add_key(sc, "spring", KARST_KEYPOINT_SPRING, 270, 270, 40);
}

static void generate(const karst_scenario_t *sc, karst_network_t *net) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_init(net);
  karst_error_t err = karst_generate(&ctx, sc, 3, 0, net, NULL, NULL);
  if (err) print_error("%s\n", ctx.errmsg);
  assert_int_equal(err, KARST_SUCCESS);
}

/* The network path from node a to node b (breadth first; the networks here are trees or
 * nearly so), as node indices into *out; returns its length in nodes, 0 if none. */
static karst_int_t path_between(const karst_network_t *net, karst_int_t a, karst_int_t b,
                                karst_int_t **out) {
  karst_int_t n = net->n_nodes;
  karst_int_t *prev = malloc(sizeof *prev * (size_t)n), *queue = malloc(sizeof *queue * (size_t)n);
  karst_int_t *deg = calloc((size_t)n + 1, sizeof *deg),
              *adj = malloc(sizeof *adj * 2 * (size_t)net->n_edges);
  for (karst_int_t e = 0; e < net->n_edges; e++)
    deg[net->edges[2 * e] + 1]++, deg[net->edges[2 * e + 1] + 1]++;
  for (karst_int_t v = 0; v < n; v++)
    deg[v + 1] += deg[v];
  karst_int_t *fill = calloc((size_t)n, sizeof *fill);
  for (karst_int_t e = 0; e < net->n_edges; e++) {
    karst_int_t u = net->edges[2 * e], w = net->edges[2 * e + 1];
    adj[deg[u] + fill[u]++] = w;
    adj[deg[w] + fill[w]++] = u;
  }
  for (karst_int_t v = 0; v < n; v++)
    prev[v] = -2;
  karst_int_t head = 0, tail = 0;
  queue[tail++] = a, prev[a] = -1;
  while (head < tail && prev[b] == -2) {
    karst_int_t u = queue[head++];
    for (karst_int_t i = deg[u]; i < deg[u + 1]; i++)
      if (prev[adj[i]] == -2) prev[adj[i]] = u, queue[tail++] = adj[i];
  }
  karst_int_t len = 0;
  if (prev[b] != -2) {
    for (karst_int_t v = b; v >= 0; v = prev[v])
      len++;
    *out = malloc(sizeof **out * (size_t)len);
    karst_int_t i = len;
    for (karst_int_t v = b; v >= 0; v = prev[v])
      (*out)[--i] = v;
  }
  free(prev), free(queue), free(deg), free(adj), free(fill);
  return len;
}

static double dist3(const double *a, const double *b) {
  return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
              (a[2] - b[2]) * (a[2] - b[2]));
}

/* The route from the sink to the spring: in the vadose stage (above z = 45) it descends along at
 * least 95 % of its length; once it has met the band it never climbs above it; at least 90 % of
 * its phreatic stage lies within the band (conduits form at the water table). The zone attribute
 * of its edges agrees. */
static void test_vadose_then_phreatic(void **state) {
  (void)state;
  karst_scenario_t sc;
  base(&sc);
  karst_network_t net;
  generate(&sc, &net);
  karst_int_t *p = NULL, m = path_between(&net, 0, 1, &p);
  assert_true(m > 10);
  double vad = 0, down = 0, phr = 0, band = 0;
  int met = 0;
  for (karst_int_t i = 1; i < m; i++) {
    const double *a = &net.xyz[3 * p[i - 1]], *b = &net.xyz[3 * p[i]];
    double L = dist3(a, b);
    if (!met) {
      vad += L;
      if (b[2] <= a[2]) down += L;
      if (b[2] <= 45) met = 1;
    } else {
      assert_true(b[2] <= 45 + 1e-9); /* never back into the vadose zone */
      phr += L;
      if (fabs(b[2] - 40) <= 5 && fabs(a[2] - 40) <= 5) band += L;
    }
  }
  print_message("vadose %.0f m (%.1f %% descending), phreatic %.0f m (%.1f %% in the band)\n", vad,
                100 * down / vad, phr, 100 * band / phr);
  assert_true(met);
  assert_true(vad > 100 && phr > 100);
  assert_true(down >= 0.95 * vad);
  assert_true(band >= 0.90 * phr);
  const double *zone = karst_network_attr_find(&net, KARST_ATTR_EDGE, "zone")->data;
  for (karst_int_t e = 0; e < net.n_edges; e++) {
    double z = 0.5 * (net.xyz[3 * net.edges[2 * e] + 2] + net.xyz[3 * net.edges[2 * e + 1] + 2]);
    int expect =
        z > 45 ? KARST_ZONE_VADOSE : (z < 35 ? KARST_ZONE_PHREATIC : KARST_ZONE_EPIPHREATIC);
    assert_int_equal((int)zone[e], expect);
  }
  free(p);
  karst_network_destroy(&net);
  karst_scenario_destroy(&sc);
}

/* Two springs with their own water tables: A at (270, 270, 40) (table z = 40) and B at
 * (270, 30, 90) with a table dipping from 110 m at x = 0 to 90 m at x = 270 towards the east
 * (dip atan(20/270)). Sink 1 must drain to A, sink 2 to B (drains_to); each route's phreatic
 * stage stays in the band of its own table, and the edges carry their spring. */
static void test_own_water_tables(void **state) {
  (void)state;
  karst_scenario_t sc;
  base(&sc);
  add_key(&sc, "springB", KARST_KEYPOINT_SPRING, 270, 30, 90);
  add_key(&sc, "sink2", KARST_KEYPOINT_SINK, 40, 250, 148);
  karst_surface_def_t *w = &sc.key_points[2].water_table;
  w->given = 1, w->elevation = 110, w->dip = atan(20.0 / 270) * 180 / M_PI, w->dip_direction = 90;
  w->origin[0] = 0, w->origin[1] = 0;
  sc.key_points[0].n_drains_to = 1, sc.key_points[0].drains_to[0] = 1;
  sc.key_points[3].n_drains_to = 1, sc.key_points[3].drains_to[0] = 2;
  karst_network_t net;
  generate(&sc, &net);
  karst_geology_t *g = geo_make(&sc);
  const int sinks[2] = {0, 3}, springs[2] = {1, 2};
  for (int r = 0; r < 2; r++) {
    karst_int_t *p = NULL, m = path_between(&net, sinks[r], springs[r], &p);
    assert_true(m > 10);
    int spring = karst_geology_spring_of_key(g, springs[r]), met = 0;
    double phr = 0, band = 0;
    for (karst_int_t i = 1; i < m; i++) {
      const double *a = &net.xyz[3 * p[i - 1]], *b = &net.xyz[3 * p[i]];
      double Wb = karst_geology_water_table(g, spring, b[0], b[1]);
      if (!met && b[2] <= Wb + 5) {
        met = 1;
        continue;
      }
      if (!met) continue;
      assert_true(b[2] <= Wb + 5 + 1e-9);
      double L = dist3(a, b);
      phr += L;
      if (fabs(b[2] - Wb) <= 5) band += L;
    }
    print_message("route %d: phreatic %.0f m, %.1f %% in its own band\n", r, phr, 100 * band / phr);
    assert_true(band >= 0.9 * phr);
    free(p);
  }
  const double *nsp = karst_network_attr_find(&net, KARST_ATTR_NODE, "spring")->data;
  assert_int_equal((int)nsp[0], 0); /* sink 1 drains to spring 0 (A) */
  assert_int_equal((int)nsp[3], 1); /* sink 2 to spring 1 (B) */
  karst_geology_free(g);
  karst_network_destroy(&net);
  karst_scenario_destroy(&sc);
}

/* An exclusion box across the straight line from the sink to the spring (x, y in [90, 210], all
 * z): no node of the network lies in it, no edge crosses it, and the sink still drains to the
 * spring, round it. */
static void test_exclusion_box_avoided(void **state) {
  (void)state;
  karst_scenario_t sc;
  base(&sc);
  sc.n_exclusions = 1;
  sc.exclusions = calloc(1, sizeof *sc.exclusions);
  sc.exclusions[0] =
      (karst_exclusion_t){.kind = KARST_EXCLUSION_BOX, .min = {90, 90, 0}, .max = {210, 210, 150}};
  karst_network_t net;
  generate(&sc, &net);
  for (karst_int_t v = 0; v < net.n_nodes; v++)
    assert_false(karst_i_point_in_exclusion(&sc.exclusions[0], &net.xyz[3 * v]));
  for (karst_int_t e = 0; e < net.n_edges; e++)
    assert_false(karst_i_segment_hits_exclusion(&sc.exclusions[0], &net.xyz[3 * net.edges[2 * e]],
                                                &net.xyz[3 * net.edges[2 * e + 1]]));
  karst_int_t *p = NULL;
  assert_true(path_between(&net, 0, 1, &p) > 10);
  free(p);
  karst_network_destroy(&net);
  karst_scenario_destroy(&sc);
}

/* Length of the network within the slab |x − 60| <= 5 (the fault's damage zone below). */
static double length_near_x60(const karst_network_t *net) {
  double L = 0;
  for (karst_int_t e = 0; e < net->n_edges; e++) {
    const double *a = &net->xyz[3 * net->edges[2 * e]], *b = &net->xyz[3 * net->edges[2 * e + 1]];
    if (fabs(a[0] - 60) <= 5 && fabs(b[0] - 60) <= 5) L += dist3(a, b);
  }
  return L;
}

/* Whether an edge crosses the vertical disc through (150, 150) with normal (1, 1, 0)/√2 and
 * radius 60 (the barrier below). */
static int crosses_barrier(const karst_network_t *net) {
  const double c[3] = {150, 150, 75}, n[3] = {M_SQRT1_2, M_SQRT1_2, 0};
  for (karst_int_t e = 0; e < net->n_edges; e++) {
    const double *a = &net->xyz[3 * net->edges[2 * e]], *b = &net->xyz[3 * net->edges[2 * e + 1]];
    double ea = 0, eb = 0;
    for (int k = 0; k < 3; k++)
      ea += n[k] * (a[k] - c[k]), eb += n[k] * (b[k] - c[k]);
    if ((ea > 0 && eb > 0) || (ea < 0 && eb < 0) || ea == eb) continue;
    double t = ea / (ea - eb), x[3];
    for (int k = 0; k < 3; k++)
      x[k] = a[k] + t * (b[k] - a[k]) - c[k];
    if (x[0] * x[0] + x[1] * x[1] + x[2] * x[2] <= 60 * 60) return 1;
  }
  return 0;
}

/* A conduit fault (the vertical plane x = 60, damage zone 10 m, factor 0.2) draws the route
 * along it: at least 100 m of the network runs in its damage zone, against less than a third of
 * that without the fault. A barrier disc (radius 60 m, straddling the straight line, crossing cost
 * 10^5) is crossed by the route without it and gone round with it. */
static void test_faults(void **state) {
  (void)state;
  karst_scenario_t sc;
  base(&sc);
  karst_network_t plainnet, net;
  generate(&sc, &plainnet);
  double L0 = length_near_x60(&plainnet);
  int crossed0 = crosses_barrier(&plainnet);
  sc.n_faults = 1;
  sc.faults = calloc(1, sizeof *sc.faults);
  karst_fault_t *F = &sc.faults[0];
  F->center[0] = 60, F->center[1] = 150, F->center[2] = 75;
  F->dip_direction = 90, F->dip = 90, F->radius = INFINITY, F->damage_zone = 10, F->factor = 0.2;
  generate(&sc, &net);
  double L1 = length_near_x60(&net);
  print_message("in the damage zone: %.0f m without the fault, %.0f m with it\n", L0, L1);
  assert_true(L1 >= 100 && L1 >= 3 * L0);
  karst_network_destroy(&net);
  *F = (karst_fault_t){.center = {150, 150, 75},
                       .dip_direction = 45,
                       .dip = 90,
                       .radius = 60,
                       .damage_zone = 10,
                       .barrier = 1,
                       .factor = 1,
                       .crossing_cost = 1e5};
  generate(&sc, &net);
  print_message("barrier crossed: %d without it, %d with it\n", crossed0, crosses_barrier(&net));
  assert_true(crossed0);
  assert_false(crosses_barrier(&net));
  karst_network_destroy(&net);
  karst_network_destroy(&plainnet);
  karst_scenario_destroy(&sc);
}

/* Length of the network within 5 m (vertically) of the horizon z = 100 − 0.25 |x − 150|. */
static double length_on_fold(const karst_network_t *net) {
  double L = 0;
  for (karst_int_t e = 0; e < net->n_edges; e++) {
    const double *a = &net->xyz[3 * net->edges[2 * e]], *b = &net->xyz[3 * net->edges[2 * e + 1]];
    double fa = 100 - 0.25 * fabs(a[0] - 150), fb = 100 - 0.25 * fabs(b[0] - 150);
    if (fabs(a[2] - fa) <= 5 && fabs(b[2] - fb) <= 5) L += dist3(a, b);
  }
  return L;
}

/* A folded horizon given as a triangulated surface (a ridge z = 100 − 0.25 |x − 150|, crest along
 * x = 150, limbs dipping 14°), strongly attractive (cost.horizon = 3, radius 5): the route from a
 * sink above the crest to a spring at the foot of the east limb runs down the limb along the
 * horizon — at least 100 m of the network within 5 m of it, against less than a third of that
 * when the horizon has no weight. */
static void test_folded_horizon_followed(void **state) {
  (void)state;
  karst_scenario_t sc;
  base(&sc);
  sc.key_points[0].p[0] = 150, sc.key_points[0].p[1] = 150;
  sc.key_points[1].p[0] = 290, sc.key_points[1].p[1] = 150, sc.key_points[1].p[2] = 40;
  /* The ridge as a TIN: columns every 10 m (one at the crest), rows every 50 m. */
  enum { NX = 31, NY = 7 };
  double xyz[3 * NX * NY];
  karst_int_t tri[6 * (NX - 1) * (NY - 1)], nt = 0;
  for (int j = 0; j < NY; j++)
    for (int i = 0; i < NX; i++) {
      double x = 10.0 * i, y = 50.0 * j;
      xyz[3 * (j * NX + i)] = x, xyz[3 * (j * NX + i) + 1] = y;
      xyz[3 * (j * NX + i) + 2] = 100 - 0.25 * fabs(x - 150);
    }
  for (int j = 0; j + 1 < NY; j++)
    for (int i = 0; i + 1 < NX; i++) {
      karst_int_t a = j * NX + i, b = a + 1, c = a + NX, d = c + 1;
      tri[3 * nt] = a, tri[3 * nt + 1] = b, tri[3 * nt + 2] = d, nt++;
      tri[3 * nt] = a, tri[3 * nt + 1] = d, tri[3 * nt + 2] = c, nt++;
    }
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  sc.n_horizons = 1;
  sc.horizons = calloc(1, sizeof *sc.horizons);
  sc.horizons[0].radius = 5;
  sc.horizons[0].path = strdup("ridge (built in code)");
  assert_int_equal(karst_surface_create_tin(&ctx, NX * NY, xyz, nt, tri, &sc.horizons[0].surface),
                   KARST_SUCCESS);
  karst_geology_t *g = geo_make(&sc);
  const double crest[3] = {150, 20, 100}, limb[3] = {250, 20, 75};
  assert_close(karst_geology_horizon_term(g, crest), 0.0, 1e-12);
  assert_close(karst_geology_horizon_term(g, limb), 0.0, 1e-12);
  karst_geology_free(g);
  sc.cost.horizon = 3;
  karst_network_t with, without;
  generate(&sc, &with);
  sc.cost.horizon = 0;
  generate(&sc, &without);
  double L1 = length_on_fold(&with), L0 = length_on_fold(&without);
  print_message("along the folded horizon: %.0f m with its weight, %.0f m without\n", L1, L0);
  assert_true(L1 >= 100 && L1 >= 3 * L0);
  karst_network_destroy(&with);
  karst_network_destroy(&without);
  karst_scenario_destroy(&sc);
}

/* The routing plan of @p sc on the graph of the pipeline's own sampling (stream (seed, 0, 0)):
 * its geology (returned), samples, graph and plan, all to be freed by the caller. */
static karst_geology_t *plan_on_own_graph(karst_scenario_t *sc, uint64_t seed, karst_ctx_t *ctx,
                                          karst_samples_t *s, karst_graph_t *gr,
                                          karst_routing_plan_t *plan) {
  karst_ctx_init(ctx);
  karst_geology_t *g = geo_make(sc);
  karst_samples_init(s);
  karst_rng_t r;
  karst_rng_derive(&r, seed, 0, 0);
  assert_int_equal(karst_sampling_run(ctx, g, &r, s), KARST_SUCCESS);
  karst_graph_init(gr);
  assert_int_equal(karst_graph_build(ctx, g, s, gr), KARST_SUCCESS);
  karst_routing_plan_init(plan);
  assert_int_equal(karst_routing_plan(ctx, g, gr, 0, plan), KARST_SUCCESS);
  return g;
}

/* The connectivity matrix: sinks s1, s2, s3 and springs A (270, 270, 40), B (270, 30, 40);
 * s1: [2, 0] (A required, B never), s2: [0, 1] (only B allowed), s3: [2, 2] (both required).
 * The plan lays no route from s1 to B nor from s2 to A, routes from s1 to A and from s3 to both;
 * in the network s3 is joined to both springs and the sinks' spring attribute is allowed. */
static void test_connectivity(void **state) {
  (void)state;
  karst_scenario_t sc;
  base(&sc);
  sc.key_points[0].p[1] = 150; /* s1 mid-west */
  add_key(&sc, "B", KARST_KEYPOINT_SPRING, 270, 30, 40);
  add_key(&sc, "s2", KARST_KEYPOINT_SINK, 200, 250, 148); /* nearer A than B */
  add_key(&sc, "s3", KARST_KEYPOINT_SINK, 150, 150, 148);
  karst_connectivity_t *c = &sc.connectivity;
  c->given = 1, c->n_sinks = 3, c->n_springs = 2;
  c->sinks = malloc(3 * sizeof(int)), c->springs = malloc(2 * sizeof(int));
  c->matrix = malloc(6);
  c->sinks[0] = 0, c->sinks[1] = 3, c->sinks[2] = 4, c->springs[0] = 1, c->springs[1] = 2;
  const unsigned char M[6] = {2, 0, 0, 1, 2, 2};
  memcpy(c->matrix, M, 6);
  /* The plan, on the graph of the pipeline's own sampling. */
  karst_ctx_t ctx;
  karst_samples_t s;
  karst_graph_t gr;
  karst_routing_plan_t plan;
  karst_geology_t *g = plan_on_own_graph(&sc, 3, &ctx, &s, &gr, &plan);
  int s1A = 0, s3A = 0, s3B = 0;
  for (int i = 0; i < plan.n_pairs; i++) {
    const karst_route_pair_t *P = &plan.pairs[i];
    assert_false(P->src == 0 && P->dst == 2);
    assert_false(P->src == 3 && P->dst == 1);
    s1A |= P->src == 0 && P->dst == 1;
    s3A |= P->src == 4 && P->dst == 1;
    s3B |= P->src == 4 && P->dst == 2;
    assert_int_equal(P->spring, karst_geology_spring_of_key(g, P->dst));
  }
  assert_true(s1A && s3A && s3B);
  assert_int_equal(plan.key_spring[0], 0);
  assert_int_equal(plan.key_spring[3], 1);
  /* The rows go once the skeleton is laid (generate.c); the routes and the springs stay. */
  assert_true(plan.bound != NULL || plan.succ != NULL);
  karst_routing_plan_drop_rows(&plan);
  assert_null(plan.bound);
  assert_null(plan.succ);
  assert_ptr_equal(karst_routing_route(&plan, 1), &plan.routes[1]);
  assert_int_equal(plan.key_spring[3], 1);
  karst_routing_plan_drop_rows(&plan); /* twice: nothing left to free */
  karst_routing_plan_destroy(&plan);
  karst_graph_destroy(&gr);
  karst_samples_destroy(&s);
  /* The network. */
  karst_network_t net;
  generate(&sc, &net);
  karst_int_t *p = NULL;
  assert_true(path_between(&net, 4, 1, &p) > 0), free(p), p = NULL;
  assert_true(path_between(&net, 4, 2, &p) > 0), free(p), p = NULL;
  const double *nsp = karst_network_attr_find(&net, KARST_ATTR_NODE, "spring")->data;
  assert_int_equal((int)nsp[0], 0);
  assert_int_equal((int)nsp[3], 1);
  karst_network_destroy(&net);
  /* A required connection the geology makes impossible: spring B sealed in a corridor
   * (265 < x <= 300, 25 < y < 35) by exclusion walls south, north and west of it is an error
   * naming the sink and the spring. */
  const karst_exclusion_t wall[3] = {
      {.kind = KARST_EXCLUSION_BOX, .min = {230, 0, 0}, .max = {300, 25, 150}},
      {.kind = KARST_EXCLUSION_BOX, .min = {230, 35, 0}, .max = {300, 60, 150}},
      {.kind = KARST_EXCLUSION_BOX, .min = {230, 25, 0}, .max = {265, 35, 150}}};
  sc.exclusions = calloc(3, sizeof *sc.exclusions);
  memcpy(sc.exclusions, wall, sizeof wall);
  sc.n_exclusions = 3;
  karst_network_init(&net);
  karst_error_t err = karst_generate(&ctx, &sc, 3, 0, &net, NULL, NULL);
  print_message("%s\n", ctx.errmsg);
  assert_int_equal(err, KARST_EUNREACHABLE);
  /* s2 (only B allowed) is reported first: the sinks are checked in file order. */
  assert_non_null(strstr(ctx.errmsg, "key point 's2' at (200.00, 250.00, 148.00) cannot drain to "
                                     "'B': no path"));
  /* With s2 free to drain to A, the required connection of s3 is the one named. */
  c->matrix[2] = 1;
  err = karst_generate(&ctx, &sc, 3, 0, &net, NULL, NULL);
  print_message("%s\n", ctx.errmsg);
  assert_int_equal(err, KARST_EUNREACHABLE);
  assert_non_null(strstr(ctx.errmsg, "key point 's3' at (150.00, 150.00, 148.00) cannot drain to "
                                     "'B', which the connectivity requires"));
  karst_network_destroy(&net);
  karst_geology_free(g);
  karst_scenario_destroy(&sc);
}

/* With one spring every waypoint drains to it, so the plan tabulates the spring's routed costs
 * before any row, the spring's own row included. That row must be the one the formula gives: it
 * is computed here again by karst_paths_target_rows on the same route without its tables (the
 * routed cost of each arc evaluated as the search relaxes it), and every vertex's bound must be
 * equal, bit for bit, to the plan's. */
static void test_one_spring_rows_on_tables(void **state) {
  (void)state;
  karst_scenario_t sc;
  base(&sc);
  add_key(&sc, "w1", KARST_KEYPOINT_WAYPOINT, 150, 100, 60);
  add_key(&sc, "w2", KARST_KEYPOINT_WAYPOINT, 100, 200, 80);
  add_key(&sc, "s2", KARST_KEYPOINT_SINK, 250, 60, 148);
  karst_ctx_t ctx;
  karst_samples_t s;
  karst_graph_t gr;
  karst_routing_plan_t plan;
  karst_geology_t *g = plan_on_own_graph(&sc, 5, &ctx, &s, &gr, &plan);
  assert_int_equal(plan.n_targets, 3); /* the spring, then the two waypoints */
  assert_int_equal(plan.targets[0], 1);
  assert_non_null(plan.routes[0].arc_bwd); /* tabulated */
  assert_non_null(plan.bound);
  karst_route_t formula = plan.routes[0];
  formula.arc_fwd = formula.arc_bwd = NULL;
  const karst_route_t *routes[1] = {&formula};
  const karst_int_t target = plan.targets[0], sources[4] = {0, 2, 3, 4};
  double dist[4];
  float *row = malloc(sizeof *row * (size_t)gr.n);
  assert_non_null(row);
  assert_int_equal(karst_paths_target_rows(&ctx, &gr, 1, &target, routes, plan.closed, 4, sources,
                                           dist, row, NULL),
                   KARST_SUCCESS);
  karst_int_t differ = 0;
  for (karst_int_t v = 0; v < gr.n; v++)
    differ += memcmp(&row[v], &plan.bound[v], sizeof *row) != 0;
  assert_int_equal(differ, 0);
  for (int j = 0; j < 4; j++)
    assert_true(isfinite(dist[j]) && dist[j] > 0);
  free(row);
  karst_routing_plan_destroy(&plan);
  karst_graph_destroy(&gr);
  karst_samples_destroy(&s);
  karst_geology_free(g);
  karst_scenario_destroy(&sc);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_one_spring_rows_on_tables),
      cmocka_unit_test(test_vadose_then_phreatic),
      cmocka_unit_test(test_own_water_tables),
      cmocka_unit_test(test_exclusion_box_avoided),
      cmocka_unit_test(test_faults),
      cmocka_unit_test(test_folded_horizon_followed),
      cmocka_unit_test(test_connectivity),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
