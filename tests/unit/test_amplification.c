/* Amplification (src/amplification, Paris et al. 2021 §5.2): the θ mapping,
 * midpoint displacement (bounds, bedrock, subdivision count, attributes,
 * determinism) and ramification (dead ends keep a tree, interior points make
 * loops, everything stays connected). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "geology_fixture.h"
#include "graph_fixture.h"
#include "test_util.h"

/* θ → maximum displacement, from the paper's two ends: 0.05 m at θ = 0, 4 m at θ = 1, linear. */
static void test_theta_mapping(void **state) {
  (void)state;
  karst_amplification_options_t opt;
  karst_amplification_options_init(&opt);
  assert_close(karst_amplification_max_displacement(&opt, 0.0), 0.05, 1e-15);
  assert_close(karst_amplification_max_displacement(&opt, 1.0), 4.0, 1e-15);
  assert_close(karst_amplification_max_displacement(&opt, 0.5), 2.025, 1e-15);
  assert_close(karst_amplification_max_displacement(&opt, 7.0), 4.0, 1e-15); /* clamped */
}

/* Distance from p to the line through a and b. */
static double line_dist(const double *p, const double *a, const double *b) {
  double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
         ap[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
  double cr[3] = {ab[1] * ap[2] - ab[2] * ap[1], ab[2] * ap[0] - ab[0] * ap[2],
                  ab[0] * ap[1] - ab[1] * ap[0]};
  return sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]) /
         sqrt(ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2]);
}

/* One 16 m edge just below a flat terrain (z = 10, edge at z = 9.9), min segment 1 m, 3 levels:
 * 16 → 8 → 4 → 2 m pieces, so 7 new nodes and 8 edges (displaced pieces are longer than half
 * their parent, so every split still happens). Displacements sum to at most A(1 + 1/2 + 1/4) <
 * 2A from the original line; no point rises to the terrain. */
static void test_displacement(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  sc.terrain.elevation = 10;
  sc.domain_min[0] = sc.domain_min[1] = sc.domain_min[2] = -100;
  sc.domain_max[0] = sc.domain_max[1] = sc.domain_max[2] = 100;
  karst_amplification_options_t opt;
  karst_amplification_options_init(&opt);
  for (int th = 0; th <= 1; th++) {
    double A = karst_amplification_max_displacement(&opt, th);
    double maxdev_all = 0;
    for (uint64_t seed = 1; seed <= 30; seed++) {
      karst_network_t in, out, out2;
      karst_network_init(&in);
      karst_network_init(&out);
      karst_network_init(&out2);
      karst_network_add_node(&in, 0, 0, 9.9, NULL);
      karst_network_add_node(&in, 16, 0, 9.9, NULL);
      karst_network_add_edge(&in, 0, 1, NULL);
      double *cost, *br;
      karst_network_attr_add(&in, KARST_ATTR_EDGE, "cost", 1, 0, &cost);
      karst_network_attr_add(&in, KARST_ATTR_EDGE, "branch_id", 1, 1, &br);
      cost[0] = 32.0;
      br[0] = 7;
      karst_network_set_label(&in, 0, "sink1");
      karst_rng_t r1, r2;
      karst_rng_init(&r1, seed, 0);
      karst_rng_init(&r2, seed, 0);
      karst_geology_t *geo = geo_make(&sc);
      assert_int_equal(karst_amplification_displace(&ctx, geo, th, &r1, &opt, &in, &out),
                       KARST_SUCCESS);
      assert_int_equal(karst_amplification_displace(&ctx, geo, th, &r2, &opt, &in, &out2),
                       KARST_SUCCESS);
      assert_int_equal(out.n_nodes, 9);
      assert_int_equal(out.n_edges, 8);
      assert_memory_equal(out.xyz, out2.xyz, 9 * 3 * sizeof(double)); /* same stream, same result */
      assert_string_equal(out.node_labels[0], "sink1");
      /* endpoints unchanged; the pieces form one chain 0 → ... → 1 */
      assert_memory_equal(out.xyz, in.xyz, 6 * sizeof(double));
      double csum = 0;
      const double *oc = karst_network_attr_find(&out, KARST_ATTR_EDGE, "cost")->data;
      const double *ob = karst_network_attr_find(&out, KARST_ATTR_EDGE, "branch_id")->data;
      for (karst_int_t e = 0; e < 8; e++) {
        csum += oc[e];
        assert_close(ob[e], 7, 0);
      }
      assert_close(csum, 32.0, 1e-12);
      karst_int_t deg[9] = {0};
      for (karst_int_t e = 0; e < 8; e++)
        deg[out.edges[2 * e]]++, deg[out.edges[2 * e + 1]]++;
      assert_int_equal(deg[0], 1);
      assert_int_equal(deg[1], 1);
      for (int v = 2; v < 9; v++)
        assert_int_equal(deg[v], 2);
      for (karst_int_t v = 0; v < 9; v++) {
        assert_true(out.xyz[3 * v + 2] < 10.0); /* never above the terrain */
        double dev = line_dist(&out.xyz[3 * v], &in.xyz[0], &in.xyz[3]);
        assert_true(dev <= 2 * A);
        maxdev_all = fmax(maxdev_all, dev);
      }
      karst_geology_free(geo);
      karst_network_destroy(&in);
      karst_network_destroy(&out);
      karst_network_destroy(&out2);
    }
    print_message("theta %d: max deviation %.3f m (bound 2A = %.3f m)\n", th, maxdev_all, 2 * A);
    if (th == 1) assert_true(maxdev_all > 1.0); /* θ = 1 does displace by metres */
  }
  karst_rng_t r;
  karst_rng_init(&r, 1, 0);
  karst_network_t a, b;
  karst_network_init(&a);
  karst_network_init(&b);
  karst_geology_t *geo = geo_make(&sc);
  assert_int_equal(karst_amplification_displace(&ctx, geo, 1.5, &r, NULL, &a, &b), KARST_EINVAL);
  /* empty network in, empty network out */
  assert_int_equal(karst_amplification_displace(&ctx, geo, 0.5, &r, NULL, &a, &b), KARST_SUCCESS);
  karst_geology_free(geo);
  assert_int_equal(b.n_nodes, 0);
  karst_network_destroy(&a);
  karst_network_destroy(&b);
  karst_scenario_destroy(&sc);
}

/* Cyclomatic number E − N + C of a network. */
static karst_int_t cyclomatic(const karst_network_t *net, karst_int_t *components) {
  karst_int_t *parent = malloc((size_t)(net->n_nodes + 1) * sizeof *parent);
  for (karst_int_t i = 0; i < net->n_nodes; i++)
    parent[i] = i;
  for (karst_int_t e = 0; e < net->n_edges; e++) {
    karst_int_t a = net->edges[2 * e], b = net->edges[2 * e + 1];
    while (parent[a] != a)
      a = parent[a];
    while (parent[b] != b)
      b = parent[b];
    if (a != b) parent[a] = b;
  }
  karst_int_t c = 0;
  for (karst_int_t i = 0; i < net->n_nodes; i++)
    c += parent[i] == i;
  free(parent);
  *components = c;
  return net->n_edges - net->n_nodes + c;
}

/* Ramification on a jittered 3-D lattice (Euclidean cost) from a straight skeleton path. */
static void run_ramify(double dead_fraction, karst_int_t *cyc, karst_int_t *comp, karst_int_t *npts,
                       karst_int_t *namp, int *max_amp_step) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_rng_t r;
  karst_rng_init(&r, 4, 0);
  const double o[3] = {0, 0, 0};
  double *xyz = fx_jittered_grid(20, 20, 4, 5.0, o, 0.3, &r);
  const karst_int_t n = 20 * 20 * 4;
  karst_graph_t g;
  fx_knn_graph(&g, n, xyz, 14, fx_euclid_cost, NULL);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  sc.terrain.elevation = 1000;
  sc.domain_min[0] = sc.domain_min[1] = sc.domain_min[2] = -10;
  sc.domain_max[0] = sc.domain_max[1] = sc.domain_max[2] = 110;
  sc.amplification.steps = 2;
  sc.amplification.points = 6;
  sc.amplification.dead_end_fraction = dead_fraction;
  karst_search_t *s;
  karst_search_create(&ctx, &g, &s);
  karst_path_t p;
  karst_path_init(&p);
  /* skeleton: corner to corner on two levels, so the bounding box has volume */
  assert_int_equal(karst_paths_astar(&ctx, s, 0, n - 1, 1.0, &p), KARST_SUCCESS);
  karst_skeleton_t sk;
  assert_int_equal(karst_skeleton_init(&ctx, &sk, &g), KARST_SUCCESS);
  assert_int_equal(karst_skeleton_add_path(&ctx, &sk, &g, &p, 0), KARST_SUCCESS);
  karst_int_t before = sk.net.n_edges;
  karst_rng_t ra;
  karst_rng_init(&ra, 77, 0);
  karst_int_t paths;
  karst_geology_t *geo = geo_make(&sc);
  assert_int_equal(karst_amplification_ramify(&ctx, geo, &g, NULL, &ra, NULL, &sk, npts, &paths),
                   KARST_SUCCESS);
  karst_geology_free(geo);
  assert_true(sk.net.n_edges > before);
  *cyc = cyclomatic(&sk.net, comp);
  const double *kind = karst_network_attr_find(&sk.net, KARST_ATTR_NODE, "kind")->data;
  *namp = 0;
  for (karst_int_t v = 0; v < sk.net.n_nodes; v++)
    *namp += kind[v] == KARST_NODE_AMPLIFICATION;
  const double *step =
      karst_network_attr_find(&sk.net, KARST_ATTR_EDGE, "amplification_step")->data;
  *max_amp_step = 0;
  for (karst_int_t e = 0; e < sk.net.n_edges; e++)
    if ((int)step[e] > *max_amp_step) *max_amp_step = (int)step[e];
  karst_skeleton_destroy(&sk);
  karst_path_destroy(&p);
  karst_search_free(s);
  fx_graph_free(&g);
  free(xyz);
  karst_scenario_destroy(&sc);
}

/* Dead ends only: each point adds a path whose vertices are all new except its last (the search
 * stops at the first network vertex), so the network stays a tree (cyclomatic number 0).
 * Interior points only: each adds a second path to another part, closing at least one loop. */
static void test_ramify(void **state) {
  (void)state;
  karst_int_t cyc, comp, npts, namp;
  int maxstep;
  run_ramify(1.0, &cyc, &comp, &npts, &namp, &maxstep);
  assert_int_equal(comp, 1);
  assert_int_equal(cyc, 0);
  assert_true(npts >= 10 && npts <= 12); /* 2 steps × 6 points, a few may collide on a vertex */
  assert_int_equal(namp, npts);
  assert_int_equal(maxstep, 2);
  run_ramify(0.0, &cyc, &comp, &npts, &namp, &maxstep);
  assert_int_equal(comp, 1);
  assert_true(cyc >= npts / 2); /* most interior points close a loop */
  assert_true(npts >= 10);
  print_message("interior points: %lld points, cyclomatic number %lld\n", (long long)npts,
                (long long)cyc);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_theta_mapping),
      cmocka_unit_test(test_displacement),
      cmocka_unit_test(test_ramify),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
