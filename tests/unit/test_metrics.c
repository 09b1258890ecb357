/* Metrics of Collon et al. 2017 (src/metrics/): the shipped caves against Karstnet 1.2.0's
 * values, and the degenerate graphs of METRICS.md built by hand with hand-computed values. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "igraph/paths_igraph.h"
#include "karst.h"
#include "metrics/metrics_internal.h"
#include "test_util.h"

#define DATA KARST_SOURCE_DIR "/datasets/surveys/karstnet/"
/* Agreement required with Karstnet 1.2.0 (issue 4). */
#define REL 1e-9

static karst_network_t build(const double *xyz, int n, const int *e, int m) {
  karst_network_t net;
  karst_network_init(&net);
  for (int i = 0; i < n; i++)
    assert_int_equal(karst_network_add_node(&net, xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2], NULL),
                     KARST_SUCCESS);
  for (int i = 0; i < m; i++)
    assert_int_equal(karst_network_add_edge(&net, e[2 * i], e[2 * i + 1], NULL), KARST_SUCCESS);
  return net;
}

static karst_metrics_t compute(const karst_network_t *net, double rotation, int nthreads) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  ctx.nthreads = nthreads;
  karst_metrics_options_t opt;
  karst_metrics_options_init(&opt);
  opt.azimuth_rotation = rotation;
  karst_metrics_t m;
  karst_error_t err = karst_metrics_compute(&ctx, net, &opt, &m);
  if (err) print_error("%s\n", ctx.errmsg);
  assert_int_equal(err, KARST_SUCCESS);
  return m;
}

/* Monachou (GOCAD PLine): the full-precision Karstnet 1.2.0 values of METRICS.md. */
static void test_monachou(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t net;
  karst_network_init(&net);
  assert_int_equal(karst_read_pline(&ctx, DATA "Monachou.pl", &net), KARST_SUCCESS);
  for (int threads = 1; threads <= 2; threads++) {
    karst_metrics_t m = compute(&net, 0.0, threads);
    assert_int_equal(m.nodes, 251);
    assert_int_equal(m.edges, 258);
    assert_int_equal(m.reduced_nodes, 80);
    assert_int_equal(m.reduced_edges, 87);
    assert_int_equal(m.cycles, 8);
    assert_int_equal(m.components, 1);
    assert_rel(m.mean_length, 8.464115572807527, REL);
    assert_rel(m.cv_length, 0.9032881766753411, REL);
    assert_rel(m.length_entropy, 0.5510231430687663, REL);
    assert_rel(m.tortuosity, 1.2432160789955717, REL);
    assert_rel(m.orientation_entropy, 0.9837612087146957, REL);
    assert_rel(m.aspl, 7.5810126582278485, REL);
    assert_rel(m.cpd, 0.40396221841503066, REL);
    assert_rel(m.mean_degree, 2.175, REL);
    assert_rel(m.cv_degree, 0.500321411333914, REL);
    assert_rel(m.correlation_vertex_degree, -0.2497381415531946, REL);
    /* Howard's parameters from the counts (Howard et al. 1970): 8/155, 87/80, 87/234. */
    assert_rel(m.howard_alpha, 8.0 / 155.0, 1e-15);
    assert_rel(m.howard_beta, 87.0 / 80.0, 1e-15);
    assert_rel(m.howard_gamma, 87.0 / 234.0, 1e-15);
  }
  karst_network_destroy(&net);
}

/* Published value rounded to @p dec decimals, as printed in published_metrics.csv. */
#define assert_printed(v, pub, dec) assert_close(v, pub, 0.5 * pow(10.0, -(dec)) * (1 + 1e-9))

/* Sakany: datasets/published_metrics.csv (Collon et al. 2017 corrected 2021, rounded as printed).
 */
static void test_sakany(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t net;
  karst_network_init(&net);
  assert_int_equal(karst_read_karstnet(&ctx, DATA "Sakany_nodes.dat", &net), KARST_SUCCESS);
  karst_metrics_t m = compute(&net, 0.0, 2);
  assert_int_equal(m.nodes, 1716);
  assert_int_equal(m.edges, 1784);
  assert_int_equal(m.reduced_nodes, 344);
  assert_int_equal(m.reduced_edges, 412);
  assert_int_equal(m.components, 1);
  assert_int_equal(m.cycles, 69);
  assert_printed(m.orientation_entropy, 0.9924004495, 10);
  assert_printed(m.mean_length, 20.70591431, 8);
  assert_printed(m.length_entropy, 0.3770371929, 10);
  assert_printed(m.cv_length, 0.914918698, 9);
  assert_printed(m.tortuosity, 1.400939173, 9);
  assert_printed(m.howard_alpha, 0.101, 3);
  assert_printed(m.howard_beta, 1.2, 1);
  assert_printed(m.howard_gamma, 0.4016, 4);
  assert_printed(m.mean_degree, 2.395348837, 9);
  assert_printed(m.cv_degree, 0.4708073225, 10);
  assert_printed(m.correlation_vertex_degree, -0.1680304631, 10);
  assert_printed(m.aspl, 12.61890637, 8);
  assert_printed(m.cpd, 0.267674075, 9);
  assert_printed(m.total_length / 1000.0, 7.5, 1);
  assert_printed(m.vertical_extent, 141, 0);
  karst_network_destroy(&net);
}

/* Grotte des Huttes, read from the node/link pair and from the Therion SQL export (the same
 * survey; coordinates differ in the last bits). Every value comes from the independent Python
 * reference tests/tools/karstnet_reference.py (METRICS.md's rules, no code shared with
 * src/metrics/; validated on Monachou to 1e-9 and Sakany to the printed digits), printed with
 * %.17g from Huttes_nodes.dat; see tests/tools/README.md to rerun it. Counts also checked with
 * awk on Huttes_links.dat (41 distinct links; degrees: 6 of 1, 29 of 2, 6 of 3; one component,
 * so 41 - 41 + 1 = 1 cycle; no loop or parallel branch, so Gs keeps the 12 nodes of degree != 2
 * and 12 + 1 - 1 edges). */
static void test_huttes(void **state) {
  (void)state;
  const char *files[] = {DATA "Huttes_links.dat", DATA "g_huttes.sql"};
  for (int f = 0; f < 2; f++) {
    karst_ctx_t ctx;
    karst_ctx_init(&ctx);
    karst_network_t net;
    karst_network_init(&net);
    assert_int_equal(karst_read_network(&ctx, files[f], KARST_FORMAT_AUTO, &net), KARST_SUCCESS);
    karst_metrics_t m = compute(&net, 0.0, 1 + f);
    assert_int_equal(m.nodes, 41);
    assert_int_equal(m.edges, 41);
    assert_rel(m.total_length, 190.46232192415874, REL);
    assert_rel(m.vertical_extent, 20.760000000000105, REL);
    assert_int_equal(m.branches, 12);
    assert_rel(m.mean_length, 15.871860160346557, REL);
    assert_rel(m.cv_length, 1.0438102384996826, REL);
    assert_rel(m.length_entropy, 0.6184917646170377, REL);
    assert_rel(m.tortuosity, 1.2066287388401382, REL);
    assert_rel(m.orientation_entropy, 0.9259356844114861, REL);
    assert_int_equal(m.reduced_nodes, 12);
    assert_int_equal(m.reduced_edges, 12);
    assert_int_equal(m.components, 1);
    assert_int_equal(m.cycles, 1);
    assert_int_equal(m.extremities, 6);
    assert_int_equal(m.junctions, 6);
    assert_rel(m.aspl, 3.0151515151515151, REL);
    assert_rel(m.cpd, 0.47438016528925625, REL);
    assert_rel(m.mean_degree, 2.0, REL);
    assert_rel(m.cv_degree, 0.5222329678670935, REL);
    assert_rel(m.correlation_vertex_degree, -0.33333333333333331, REL);
    assert_rel(m.howard_alpha, 0.052631578947368418, REL);
    assert_rel(m.howard_beta, 1.0, REL);
    assert_rel(m.howard_gamma, 0.40000000000000002, REL);
    karst_network_destroy(&net);
  }
}

/* Empty network and nodes without edges: nothing to measure, every metric undefined. */
static void test_empty(void **state) {
  (void)state;
  double xyz[] = {0, 0, 0, 1, 2, 3};
  for (int n = 0; n <= 2; n += 2) {
    karst_network_t net = build(xyz, n, NULL, 0);
    karst_metrics_t m = compute(&net, 0.0, 1);
    assert_int_equal(m.nodes, 0); /* a node used by no edge is dropped */
    assert_int_equal(m.edges, 0);
    assert_int_equal(m.reduced_nodes, 0);
    assert_int_equal(m.branches, 0);
    assert_true(isnan(m.mean_length) && isnan(m.cv_length) && isnan(m.length_entropy));
    assert_true(isnan(m.tortuosity) && isnan(m.orientation_entropy) && isnan(m.aspl));
    assert_true(isnan(m.cpd) && isnan(m.mean_degree) && isnan(m.cv_degree));
    assert_true(isnan(m.correlation_vertex_degree) && isnan(m.howard_alpha));
    karst_network_destroy(&net);
  }
}

/* One 3-4-5 edge, by hand: one branch of length 5 and chord 5; Gs = 2 nodes, 1 edge. */
static void test_single_edge(void **state) {
  (void)state;
  double xyz[] = {0, 0, 0, 3, 4, 0};
  int e[] = {0, 1};
  karst_network_t net = build(xyz, 2, e, 1);
  karst_metrics_t m = compute(&net, 0.0, 1);
  assert_int_equal(m.nodes, 2);
  assert_int_equal(m.branches, 1);
  assert_close(m.mean_length, 5.0, 1e-15);
  assert_true(isnan(m.cv_length));          /* sample std of one value */
  assert_close(m.length_entropy, 0.0, 0.0); /* one value */
  assert_close(m.tortuosity, 1.0, 1e-15);
  assert_close(m.orientation_entropy, 0.0, 0.0); /* fewer than 2 edges */
  assert_int_equal(m.reduced_nodes, 2);
  assert_int_equal(m.reduced_edges, 1);
  assert_int_equal(m.cycles, 0);
  assert_close(m.aspl, 1.0, 1e-15);
  assert_close(m.cpd, 0.0, 0.0);
  assert_close(m.mean_degree, 1.0, 0.0);
  assert_close(m.cv_degree, 0.0, 0.0);
  assert_close(m.correlation_vertex_degree, 1.0, 0.0);         /* all degrees equal */
  assert_true(isnan(m.howard_alpha) && isnan(m.howard_gamma)); /* N < 3 */
  assert_close(m.howard_beta, 0.5, 0.0);
  assert_int_equal(m.extremities, 2);
  karst_network_destroy(&net);
}

/* A square ring, by hand: one loop branch of 5 listed nodes (40 m, chord 0) cut at 1 and 2
 * into a triangle; azimuths 90, 0, 90, 0 with equal weights: H = ln 2 / ln 18. */
static void test_ring(void **state) {
  (void)state;
  double xyz[] = {0, 0, 0, 10, 0, 0, 10, 10, 0, 0, 10, 0};
  int e[] = {0, 1, 1, 2, 2, 3, 3, 0};
  karst_network_t net = build(xyz, 4, e, 4);
  karst_metrics_t m = compute(&net, 0.0, 1);
  assert_int_equal(m.branches, 1);
  assert_close(m.mean_length, 40.0, 1e-13);
  assert_true(isnan(m.tortuosity)); /* chord 0 */
  assert_close(m.length_entropy, 0.0, 0.0);
  assert_rel(m.orientation_entropy, log(2.0) / log(18.0), 1e-14);
  assert_int_equal(m.reduced_nodes, 3);
  assert_int_equal(m.reduced_edges, 3);
  assert_int_equal(m.cycles, 1);
  assert_close(m.aspl, 1.0, 1e-15);
  assert_close(m.cpd, 0.0, 0.0);
  assert_close(m.mean_degree, 2.0, 0.0);
  assert_close(m.correlation_vertex_degree, 1.0, 0.0);
  assert_close(m.howard_alpha, 1.0, 1e-15); /* 1 / (2*3 - 5) */
  assert_close(m.howard_beta, 1.0, 1e-15);
  assert_close(m.howard_gamma, 1.0, 1e-15); /* 3 / (3*1) */
  karst_network_destroy(&net);
}

/* Two separate edges (1 m east-west, 2 m north-south), by hand: lengths 1, 2: mean 1.5,
 * cv = sqrt(1/2)/1.5; normalised 50, 100 -> bins 5 and 9: H = ln2/ln10; azimuth weights 1 and
 * 2: H = -(1/3 ln 1/3 + 2/3 ln 2/3)/ln 18; aspl: each component 1 -> (2*1 + 2*1)/4 = 1. */
static void test_disconnected(void **state) {
  (void)state;
  double xyz[] = {0, 0, 0, 1, 0, 0, 0, 5, 0, 0, 7, 0};
  int e[] = {0, 1, 2, 3};
  karst_network_t net = build(xyz, 4, e, 2);
  karst_metrics_t m = compute(&net, 0.0, 2);
  assert_close(m.mean_length, 1.5, 1e-15);
  assert_rel(m.cv_length, sqrt(0.5) / 1.5, 1e-14);
  assert_rel(m.length_entropy, log(2.0) / log(10.0), 1e-14);
  assert_close(m.tortuosity, 1.0, 1e-15);
  double p = 1.0 / 3.0, q = 2.0 / 3.0;
  assert_rel(m.orientation_entropy, -(p * log(p) + q * log(q)) / log(18.0), 1e-14);
  assert_int_equal(m.reduced_nodes, 4);
  assert_int_equal(m.reduced_edges, 2);
  assert_int_equal(m.components, 2);
  assert_int_equal(m.cycles, 0);
  assert_close(m.aspl, 1.0, 1e-15);
  assert_close(m.cpd, 0.0, 0.0);
  assert_close(m.howard_alpha, 0.0, 0.0);
  assert_close(m.howard_gamma, 1.0 / 3.0, 1e-15);
  karst_network_destroy(&net);
}

/* A self-loop on the centre of a 2-edge star, by hand: degree(A) = 4; branches A-B, A-C (1 m)
 * and the self-loop (0 m): mean 2/3, cv = sqrt(1/3)/(2/3); entropy of lengths from the two
 * non-zero ones (both 100): 0. Gs = {A-B, A-C, A-A}: aspl = 2(1+1+2)/6 = 4/3; betweenness
 * of A = 1 pair -> 2/(2*1) = 1: cpd = (0+1+1)/2 = 1. Degree pairs (4,1)x2, (1,4)x2, (4,4):
 * Pearson r = -7.2/10.8 = -2/3. */
static void test_self_loop(void **state) {
  (void)state;
  double xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  int e[] = {0, 1, 0, 2, 0, 0};
  karst_network_t net = build(xyz, 3, e, 3);
  karst_metrics_t m = compute(&net, 0.0, 1);
  assert_int_equal(m.edges, 3);
  assert_int_equal(m.branches, 3);
  assert_rel(m.mean_length, 2.0 / 3.0, 1e-15);
  assert_rel(m.cv_length, sqrt(1.0 / 3.0) / (2.0 / 3.0), 1e-14);
  assert_close(m.length_entropy, 0.0, 0.0);
  assert_close(m.tortuosity, 1.0, 1e-15);
  assert_rel(m.orientation_entropy, log(2.0) / log(18.0), 1e-14);
  assert_int_equal(m.reduced_nodes, 3);
  assert_int_equal(m.reduced_edges, 3);
  assert_int_equal(m.cycles, 1);
  assert_rel(m.mean_degree, 2.0, 1e-15);
  assert_rel(m.cv_degree, sqrt(3.0) / 2.0, 1e-14);
  assert_rel(m.aspl, 4.0 / 3.0, 1e-15);
  assert_rel(m.cpd, 1.0, 1e-15);
  assert_rel(m.correlation_vertex_degree, -2.0 / 3.0, 1e-14);
  assert_int_equal(m.extremities, 2);
  assert_int_equal(m.junctions, 1);
  karst_network_destroy(&net);
}

/* Repeated links in both directions and an unused node: the simple graph is the path
 * 0-1-2 (3 m east-west then 4 m north-south): one branch of 7 m, chord 5. */
static void test_duplicate_links(void **state) {
  (void)state;
  double xyz[] = {0, 0, 0, 3, 0, 0, 3, 4, 0, 50, 50, 50};
  int e[] = {0, 1, 1, 0, 1, 2, 1, 2, 2, 1};
  karst_network_t net = build(xyz, 4, e, 5);
  karst_metrics_t m = compute(&net, 0.0, 1);
  assert_int_equal(m.nodes, 3);
  assert_int_equal(m.edges, 2);
  assert_int_equal(m.branches, 1);
  assert_close(m.mean_length, 7.0, 1e-15);
  assert_rel(m.tortuosity, 7.0 / 5.0, 1e-15);
  assert_close(m.total_length, 7.0, 1e-15);
  assert_close(m.vertical_extent, 0.0, 0.0);
  double p = 3.0 / 7.0, q = 4.0 / 7.0;
  assert_rel(m.orientation_entropy, -(p * log(p) + q * log(q)) / log(18.0), 1e-14);
  assert_int_equal(m.reduced_nodes, 2);
  assert_int_equal(m.reduced_edges, 1);
  karst_network_destroy(&net);
}

/* Vertical shots only: no azimuth at all, orientation entropy 0 (Karstnet: < 2 values). */
static void test_vertical_only(void **state) {
  (void)state;
  double xyz[] = {0, 0, 0, 0, 0, -5, 0, 0, -8};
  int e[] = {0, 1, 1, 2};
  karst_network_t net = build(xyz, 3, e, 2);
  karst_metrics_t m = compute(&net, 0.0, 1);
  assert_close(m.orientation_entropy, 0.0, 0.0);
  assert_close(m.mean_length, 8.0, 1e-15);
  assert_close(m.tortuosity, 1.0, 1e-15);
  assert_close(m.vertical_extent, 8.0, 0.0);
  karst_network_destroy(&net);
}

/* Two branches between the same pair A-B (the direct 10 m edge and A-C-B through C at
 * (5,5)), with pendant edges A-D and B-E of 5 m. The parallel branch is cut at C, so
 * Gs = {A-B, A-C, C-B, A-D, B-E}, by hand: distance sums A 5, B 5, C 6, D 8, E 8 ->
 * aspl = 32/20; A and B each lie on 3 pairs -> 2*3/(4*3) = 0.5: cpd = 1.5/4; degree pairs
 * give Pearson r = -3.6/6.4. Branch lengths 10, 10*sqrt2, 5, 5. */
static void test_parallel_branches(void **state) {
  (void)state;
  double xyz[] = {0, 0, 0, 10, 0, 0, 5, 5, 0, -5, 0, 0, 15, 0, 0};
  int e[] = {0, 1, 0, 2, 2, 1, 0, 3, 1, 4};
  karst_network_t net = build(xyz, 5, e, 5);
  karst_metrics_t m = compute(&net, 0.0, 1);
  assert_int_equal(m.branches, 4);
  assert_int_equal(m.reduced_nodes, 5);
  assert_int_equal(m.reduced_edges, 5);
  assert_int_equal(m.cycles, 1);
  assert_rel(m.aspl, 1.6, 1e-15);
  assert_rel(m.cpd, 0.375, 1e-15);
  assert_rel(m.mean_degree, 2.0, 1e-15);
  assert_rel(m.cv_degree, 0.5, 1e-15);
  assert_rel(m.correlation_vertex_degree, -0.5625, 1e-14);
  double l[4] = {10.0, 10.0 * sqrt(2.0), 5.0, 5.0}, mean = (l[0] + l[1] + l[2] + l[3]) / 4, ss = 0;
  for (int i = 0; i < 4; i++)
    ss += (l[i] - mean) * (l[i] - mean);
  assert_rel(m.mean_length, mean, 1e-15);
  assert_rel(m.cv_length, sqrt(ss / 3.0) / mean, 1e-14);
  /* normalised lengths 70.7, 100, 35.4, 35.4 -> bins 7, 9, 3, 3 */
  assert_rel(m.length_entropy, 1.5 * log(2.0) / log(10.0), 1e-14);
  assert_rel(m.tortuosity, (3.0 + sqrt(2.0)) / 4.0, 1e-14);
  /* azimuths 90 (10+5+5 m), 45 and 135 (sqrt 50 m each) */
  double w[3] = {20.0, sqrt(50.0), sqrt(50.0)}, t = w[0] + w[1] + w[2], h = 0;
  for (int i = 0; i < 3; i++)
    h -= w[i] / t * log(w[i] / t);
  assert_rel(m.orientation_entropy, h / log(18.0), 1e-14);
  karst_network_destroy(&net);
}

/* The [0,180) fold: an exact north-south edge is in bin 0 whichever way it points, so two of
 * them give H = 0 and one with an edge at 175 degrees gives ln2/ln18 (it would be 0 if
 * north-south landed at 180). A rotation moves azimuths across bins. */
static void test_azimuth_fold_and_rotation(void **state) {
  (void)state;
  double s175 = sin(175.0 * M_PI / 180.0), c175 = cos(175.0 * M_PI / 180.0);
  double xyz[] = {0, 0, 0, 0, 10, 0, 5, 0, 0, 5, -10, 0, 20, 0, 0, 20 + 10 * s175, 10 * c175, 0};
  int e[] = {0, 1, 2, 3, 4, 5};
  karst_network_t ns = build(xyz, 4, e, 2);
  assert_close(compute(&ns, 0.0, 1).orientation_entropy, 0.0, 0.0);
  /* rotated by 7 degrees both stay together (bin 0) ... */
  assert_close(compute(&ns, 7.0, 1).orientation_entropy, 0.0, 0.0);
  /* ... and by -5 they fold to 175 (bin 17), still together */
  assert_close(compute(&ns, -5.0, 1).orientation_entropy, 0.0, 0.0);
  karst_network_destroy(&ns);
  int e2[] = {0, 1, 4, 5};
  karst_network_t mix = build(xyz, 6, e2, 2);
  assert_rel(compute(&mix, 0.0, 1).orientation_entropy, log(2.0) / log(18.0), 1e-14);
  /* +6 degrees: 6 and 181 -> 1: both in bin 0 */
  assert_close(compute(&mix, 6.0, 1).orientation_entropy, 0.0, 0.0);
  karst_network_destroy(&mix);
}

/* Bad input is reported, not crashed on. */
static void test_invalid(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  double xyz[] = {0, 0, 0, NAN, 1, 0};
  int e[] = {0, 1};
  karst_network_t net = build(xyz, 2, e, 1);
  karst_metrics_t m;
  assert_int_equal(karst_metrics_compute(&ctx, &net, NULL, &m), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "non-finite"));
  net.edges[1] = 7;
  assert_int_equal(karst_metrics_compute(&ctx, &net, NULL, &m), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "7"));
  karst_metrics_options_t opt;
  karst_metrics_options_init(&opt);
  opt.azimuth_rotation = INFINITY;
  net.edges[1] = 1;
  net.xyz[3] = 1;
  assert_int_equal(karst_metrics_compute(&ctx, &net, &opt, &m), KARST_EINVAL);
  karst_network_destroy(&net);
}

/* The parallel BFS against igraph 0.10 (an independent implementation) on a random sparse
 * multi-component graph, and bit-identical results for 1, 2 and 3 threads. */
static void test_paths_against_igraph(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_rng_t rng;
  karst_rng_init(&rng, 4, 0);
  const int n = 700, m = 900;
  karst_int_t *ed = malloc(2 * m * sizeof *ed);
  int k = 0;
  while (k < m) { /* simple graph: no loops, no repeats (checked by brute force) */
    karst_int_t u = (karst_int_t)karst_rng_below(&rng, n),
                v = (karst_int_t)karst_rng_below(&rng, n);
    int dup = u == v;
    for (int j = 0; j < k && !dup; j++)
      dup = (ed[2 * j] == u && ed[2 * j + 1] == v) || (ed[2 * j] == v && ed[2 * j + 1] == u);
    if (dup) continue;
    ed[2 * k] = u;
    ed[2 * k + 1] = v;
    k++;
  }
  karst_i_csr_t g;
  assert_int_equal(karst_i_csr_build(&ctx, n, m, ed, &g), KARST_SUCCESS);
  double *b1 = malloc(n * sizeof *b1), *b2 = malloc(n * sizeof *b2), *bi = malloc(n * sizeof *bi);
  karst_int_t *d1 = malloc(n * sizeof *d1), *d2 = malloc(n * sizeof *d2),
              *di = malloc(n * sizeof *di);
  ctx.nthreads = 1;
  assert_int_equal(karst_i_paths_all_sources(&ctx, &g, b1, d1), KARST_SUCCESS);
  assert_int_equal(karst_i_paths_igraph(&ctx, &g, bi, di), KARST_SUCCESS);
  for (int t = 2; t <= 3; t++) {
    ctx.nthreads = t;
    assert_int_equal(karst_i_paths_all_sources(&ctx, &g, b2, d2), KARST_SUCCESS);
    assert_memory_equal(b1, b2, n * sizeof *b1);
    assert_memory_equal(d1, d2, n * sizeof *d1);
  }
  for (int v = 0; v < n; v++) {
    assert_int_equal(d1[v], di[v]);
    assert_close(b1[v], bi[v], 1e-9 * (1.0 + fabs(bi[v])));
  }
  karst_i_csr_destroy(&g);
  free(ed);
  free(b1);
  free(b2);
  free(bi);
  free(d1);
  free(d2);
  free(di);
}

/* The field table drives every output format: keys of the issue, each once. */
static void test_fields(void **state) {
  (void)state;
  int n;
  const karst_metric_field_t *f = karst_metric_fields(&n);
  assert_true(n <= KARST_METRIC_FIELDS_MAX);
  const char *keys[] = {"nodes",
                        "edges",
                        "mean_length",
                        "cv_length",
                        "length_entropy",
                        "tortuosity",
                        "orientation_entropy",
                        "aspl",
                        "cpd",
                        "mean_degree",
                        "cv_degree",
                        "correlation_vertex_degree",
                        "reduced_nodes",
                        "reduced_edges",
                        "components",
                        "cycles",
                        "howard_alpha",
                        "howard_beta",
                        "howard_gamma"};
  for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++) {
    int found = 0;
    for (int j = 0; j < n; j++)
      found += strcmp(f[j].key, keys[i]) == 0;
    assert_int_equal(found, 1);
  }
  karst_metrics_t m;
  memset(&m, 0, sizeof m);
  m.cycles = 12;
  m.cpd = 0.25;
  for (int j = 0; j < n; j++) {
    if (strcmp(f[j].key, "cycles") == 0) assert_close(karst_metric_value(&m, &f[j]), 12.0, 0.0);
    if (strcmp(f[j].key, "cpd") == 0) assert_close(karst_metric_value(&m, &f[j]), 0.25, 0.0);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_monachou),
      cmocka_unit_test(test_sakany),
      cmocka_unit_test(test_huttes),
      cmocka_unit_test(test_empty),
      cmocka_unit_test(test_single_edge),
      cmocka_unit_test(test_ring),
      cmocka_unit_test(test_disconnected),
      cmocka_unit_test(test_self_loop),
      cmocka_unit_test(test_duplicate_links),
      cmocka_unit_test(test_vertical_only),
      cmocka_unit_test(test_parallel_branches),
      cmocka_unit_test(test_azimuth_fold_and_rotation),
      cmocka_unit_test(test_invalid),
      cmocka_unit_test(test_paths_against_igraph),
      cmocka_unit_test(test_fields),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
