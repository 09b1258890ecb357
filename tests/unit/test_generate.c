/* The pipeline (src/generate): everything after the graph on a graph built
 * here (determinism, thread independence, seeds, attributes, unreachable key
 * points), and karst_generate end to end once sampling is available. */
#include <setjmp.h>
#include <spawn.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>

#include "generate/generate_internal.h"
#include "graph_fixture.h"
#include "test_util.h"

typedef struct {
  karst_scenario_t sc;
  karst_geology_t *geo; /* of sc, built once the key points are set */
  double *xyz;
  karst_int_t n;
  karst_graph_t g;
} fixture_t;

/* A 200 × 200 × 60 m block, terrain at 60, water table at 30, one horizon at 30, 5 key points as
 * the first samples (2 sinks near the top, 1 spring at the table, 2 waypoints), a jittered
 * 7 m lattice for the rest. */
static void make_fixture(fixture_t *f, int isolate_key) {
  karst_scenario_init(&f->sc);
  karst_scenario_t *sc = &f->sc;
  sc->domain_max[0] = sc->domain_max[1] = 200;
  sc->domain_max[2] = 60;
  sc->terrain.elevation = 60;
  sc->water_table.given = 1;
  sc->water_table.elevation = 30;
  sc->gamma = 2.0;
  sc->tortuosity = 0.3;
  sc->amplification.steps = 2;
  sc->amplification.points = 4;
  sc->amplification.dead_end_fraction = 0.5;
  sc->name = strdup("fixture");
  const double kp[5][3] = {
      {20, 20, 55}, {180, 40, 55}, {100, 180, 30}, {60, 120, 40}, {150, 150, 20}};
  const karst_keypoint_type_t kt[5] = {KARST_KEYPOINT_SINK, KARST_KEYPOINT_SINK,
                                       KARST_KEYPOINT_SPRING, KARST_KEYPOINT_WAYPOINT,
                                       KARST_KEYPOINT_WAYPOINT};
  const char *names[5] = {"sink_a", "sink_b", "spring", "way_1", "way_2"};
  sc->n_key_points = 5;
  sc->key_points = calloc(5, sizeof *sc->key_points);
  for (int i = 0; i < 5; i++) {
    memcpy(sc->key_points[i].p, kp[i], sizeof kp[i]);
    sc->key_points[i].type = kt[i];
    strcpy(sc->key_points[i].name, names[i]);
  }
  karst_rng_t r;
  karst_rng_init(&r, 99, 0);
  const double o[3] = {3.5, 3.5, 3.5};
  double *lat = fx_jittered_grid(29, 29, 8, 7.0, o, 0.3, &r);
  f->n = 5 + 29 * 29 * 8;
  f->xyz = malloc((size_t)f->n * 3 * sizeof *f->xyz);
  for (int i = 0; i < 5; i++)
    memcpy(&f->xyz[3 * i], kp[i], sizeof kp[i]);
  memcpy(&f->xyz[15], lat, 29 * 29 * 8 * 3 * sizeof *lat);
  free(lat);
  if (isolate_key)       /* move key point 4 far away: its k nearest neighbours are still found, */
    f->xyz[3 * 4] = 1e6; /* so make every edge touching it infinite below instead */
  karst_ctx_t gctx;
  karst_ctx_init(&gctx);
  f->geo = NULL;
  assert_int_equal(karst_geology_create(&gctx, sc, 0, 0, &f->geo), KARST_SUCCESS);
  fx_cost_ctx_t cc = {sc, 4};
  fx_knn_graph(&f->g, f->n, f->xyz, 20, fx_scenario_cost, &cc);
  if (isolate_key)
    for (karst_int_t v = 0; v < f->n; v++) {
      karst_arc_reader_t rd = karst_graph_arcs(&f->g, v);
      for (karst_int_t a = f->g.offsets[v]; a < f->g.offsets[v + 1]; a++)
        if (karst_arc_next(&rd) == 4 || v == 4) f->g.cost[a] = INFINITY;
    }
}

static void free_fixture(fixture_t *f) {
  karst_geology_free(f->geo);
  fx_graph_free(&f->g);
  free(f->xyz);
  karst_scenario_destroy(&f->sc);
}

static void assert_same_network(const karst_network_t *a, const karst_network_t *b) {
  assert_int_equal(a->n_nodes, b->n_nodes);
  assert_int_equal(a->n_edges, b->n_edges);
  assert_memory_equal(a->xyz, b->xyz, (size_t)a->n_nodes * 3 * sizeof(double));
  assert_memory_equal(a->edges, b->edges, (size_t)a->n_edges * 2 * sizeof(karst_int_t));
  assert_int_equal(a->n_edge_attrs, b->n_edge_attrs);
  for (int i = 0; i < a->n_edge_attrs; i++)
    assert_memory_equal(a->edge_attrs[i].data, b->edge_attrs[i].data,
                        (size_t)a->n_edges * sizeof(double));
  for (int i = 0; i < a->n_node_attrs; i++)
    assert_memory_equal(a->node_attrs[i].data, b->node_attrs[i].data,
                        (size_t)a->n_nodes * sizeof(double));
}

static void test_pipeline_after_graph(void **state) {
  (void)state;
  fixture_t f;
  make_fixture(&f, 0);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t n1, n2, n3;
  karst_network_init(&n1);
  karst_network_init(&n2);
  karst_network_init(&n3);
  karst_generate_stats_t st;
  memset(&st, 0, sizeof st);
  ctx.nthreads = 1;
  assert_int_equal(karst_i_generate_from_graph(&ctx, f.geo, 42, 0, &f.g, 1.0, &n1, &st),
                   KARST_SUCCESS);
  ctx.nthreads = 2;
  assert_int_equal(karst_i_generate_from_graph(&ctx, f.geo, 42, 0, &f.g, 1.0, &n2, NULL),
                   KARST_SUCCESS);
  assert_same_network(&n1, &n2); /* same seed: identical, whatever the thread count */
  assert_int_equal(karst_i_generate_from_graph(&ctx, f.geo, 43, 0, &f.g, 1.0, &n3, NULL),
                   KARST_SUCCESS);
  assert_true(n3.n_nodes != n1.n_nodes ||
              memcmp(n3.xyz, n1.xyz, (size_t)n1.n_nodes * 3 * sizeof(double)) !=
                  0); /* another seed differs */
  /* Attributes promised by generate.h. */
  const char *node_attrs[] = {"kind", "water_table_distance", "spring"};
  const char *edge_attrs[] = {"tunnel_type", "radius", "cost",      "vadose",
                              "zone",        "spring", "branch_id", "amplification_step"};
  for (int i = 0; i < 3; i++)
    assert_non_null(karst_network_attr_find(&n1, KARST_ATTR_NODE, node_attrs[i]));
  for (int i = 0; i < 8; i++)
    assert_non_null(karst_network_attr_find(&n1, KARST_ATTR_EDGE, edge_attrs[i]));
  /* Key points are nodes 0..4 with their kinds and names (the skeleton adds them first). */
  const double *kind = karst_network_attr_find(&n1, KARST_ATTR_NODE, "kind")->data;
  assert_int_equal((int)kind[0], KARST_NODE_SINK);
  assert_int_equal((int)kind[2], KARST_NODE_SPRING);
  assert_int_equal((int)kind[4], KARST_NODE_WAYPOINT);
  assert_string_equal(n1.node_labels[2], "spring");
  assert_string_equal(n1.title, "fixture");
  int junctions = 0, amp = 0;
  for (karst_int_t v = 0; v < n1.n_nodes; v++) {
    junctions += kind[v] == KARST_NODE_JUNCTION;
    amp += kind[v] == KARST_NODE_AMPLIFICATION;
    /* every node stays in the bedrock */
    assert_true(n1.xyz[3 * v + 2] < 60.0);
  }
  assert_true(junctions >= 1);
  assert_true(amp >= 1 && amp <= 8);
  const double *step = karst_network_attr_find(&n1, KARST_ATTR_EDGE, "amplification_step")->data;
  int has_step2 = 0;
  for (karst_int_t e = 0; e < n1.n_edges; e++)
    has_step2 |= step[e] == 2;
  assert_true(has_step2);
  /* Stats. */
  assert_int_equal(st.n_key_points, 5);
  assert_true(st.n_skeleton_paths >= 4); /* at least a spanning set of 5 key points */
  assert_int_equal(st.n_nodes, n1.n_nodes);
  assert_int_equal(st.n_edges, n1.n_edges);
  double len = 0;
  for (karst_int_t e = 0; e < n1.n_edges; e++)
    len += karst_network_edge_length(&n1, e);
  assert_rel(st.total_length, len, 1e-12);
  assert_true(st.total_length > 200); /* the key points span more than 200 m */
  karst_network_destroy(&n1);
  karst_network_destroy(&n2);
  karst_network_destroy(&n3);
  free_fixture(&f);
}

static void test_unreachable_key_point(void **state) {
  (void)state;
  fixture_t f;
  make_fixture(&f, 1);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t net;
  karst_network_init(&net);
  assert_int_equal(karst_i_generate_from_graph(&ctx, f.geo, 1, 0, &f.g, 1.0, &net, NULL),
                   KARST_EUNREACHABLE);
  print_message("%s\n", ctx.errmsg);
  assert_non_null(strstr(ctx.errmsg, "'way_2'"));
  assert_int_equal(net.n_nodes, 0); /* nothing half-built survives */
  karst_network_destroy(&net);
  free_fixture(&f);
}

static void test_single_key_point(void **state) {
  (void)state;
  fixture_t f;
  make_fixture(&f, 0);
  f.sc.n_key_points = 1; /* a spring alone: no route, a one-node network */
  f.sc.key_points[0].type = KARST_KEYPOINT_SPRING;
  f.sc.amplification.steps = 0;
  karst_geology_free(f.geo);
  karst_ctx_t gctx;
  karst_ctx_init(&gctx);
  assert_int_equal(karst_geology_create(&gctx, &f.sc, 0, 0, &f.geo), KARST_SUCCESS);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t net;
  karst_network_init(&net);
  assert_int_equal(karst_i_generate_from_graph(&ctx, f.geo, 1, 0, &f.g, 1.0, &net, NULL),
                   KARST_SUCCESS);
  assert_int_equal(net.n_nodes, 1);
  assert_int_equal(net.n_edges, 0);
  f.sc.n_key_points = 0;
  assert_int_equal(karst_i_generate_from_graph(&ctx, f.geo, 1, 0, &f.g, 1.0, &net, NULL),
                   KARST_EINVAL);
  f.sc.n_key_points = 5;
  f.sc.key_points[0].type = KARST_KEYPOINT_SINK;
  karst_network_destroy(&net);
  free_fixture(&f);
}

/* End to end through sampling and the graph . */
static void test_generate_end_to_end(void **state) {
  (void)state;
  fixture_t f;
  make_fixture(&f, 0);
  f.sc.sampling.fill_radius = 8;
  f.sc.sampling.feature_radius = 4;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t a, b;
  karst_network_init(&a);
  karst_network_init(&b);
  karst_samples_t s;
  karst_samples_init(&s);
  karst_generate_stats_t st;
  karst_error_t err = karst_generate(&ctx, &f.sc, 7, 0, &a, &s, &st);
  assert_int_equal(err, KARST_SUCCESS);
  assert_int_equal(s.n_key_points, 5);
  assert_int_equal(st.n_samples, s.n);
  assert_true(st.n_graph_edges > s.n);
  ctx.nthreads = 2;
  assert_int_equal(karst_generate(&ctx, &f.sc, 7, 0, &b, NULL, NULL), KARST_SUCCESS);
  assert_same_network(&a, &b);
  /* S is counted before amplification: the same with no amplification step (the ramified
   * branches come after the skeleton and do not change it), and shorter than the network
   * that the two steps of the fixture grow from it. */
  assert_true(st.skeleton_length > 0 && st.n_skeleton_nodes > 1);
  assert_true(st.skeleton_length < st.total_length);
  assert_true(st.n_skeleton_nodes < st.n_nodes);
  karst_generate_stats_t st0;
  f.sc.amplification.steps = 0;
  karst_network_destroy(&b);
  karst_network_init(&b);
  assert_int_equal(karst_generate(&ctx, &f.sc, 7, 0, &b, NULL, &st0), KARST_SUCCESS);
  assert_int_equal(st0.n_skeleton_nodes, st.n_skeleton_nodes);
  assert_true(st0.skeleton_length == st.skeleton_length);
  assert_true(st0.n_nodes < st.n_nodes);
  karst_network_destroy(&a);
  karst_network_destroy(&b);
  karst_samples_destroy(&s);
  free_fixture(&f);
}

extern char **environ;

/* The peak memory a run reports (run.json's "peak_bytes") is its own, however it was started.
 * getrusage's ru_maxrss, which karst read before, carries over execve the resident set of the
 * address space a posix_spawn (vfork) child replaces: the parent's. Here the parent holds
 * 512 MiB, touched, and starts this program again, which only reports its peak: that is a few
 * MiB (the program and its libraries; tens under ASan), far below 256 MiB; the old reading gave
 * at least 512 MiB. */
static void test_peak_bytes_own_process(void **state) {
  (void)state;
  const size_t held = (size_t)512 << 20;
  unsigned char *big = malloc(held);
  assert_non_null(big);
  memset(big, 0x5a, held);
  assert_true(karst_i_peak_bytes() >= held); /* the parent's own peak counts what it holds */
  int fd[2];
  assert_int_equal(pipe(fd), 0);
  posix_spawn_file_actions_t fa;
  assert_int_equal(posix_spawn_file_actions_init(&fa), 0);
  posix_spawn_file_actions_adddup2(&fa, fd[1], 1);
  posix_spawn_file_actions_addclose(&fa, fd[0]);
  char *argv[] = {"/proc/self/exe", "--print-peak-bytes", NULL};
  pid_t pid;
  assert_int_equal(posix_spawn(&pid, "/proc/self/exe", &fa, NULL, argv, environ), 0);
  posix_spawn_file_actions_destroy(&fa);
  close(fd[1]);
  char buf[64] = {0};
  size_t got = 0;
  ssize_t r;
  while (got < sizeof buf - 1 && (r = read(fd[0], buf + got, sizeof buf - 1 - got)) > 0)
    got += (size_t)r;
  close(fd[0]);
  int status;
  assert_int_equal(waitpid(pid, &status, 0), pid);
  assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  unsigned long long child = strtoull(buf, NULL, 10);
  printf("peak: parent %.0f MiB, child %.1f MiB\n", karst_i_peak_bytes() / 1048576.0,
         child / 1048576.0);
  assert_true(child > 0);
  assert_true(child < ((unsigned long long)256 << 20));
  assert_int_equal(big[held / 2], 0x5a);
  free(big);
}

int main(int argc, char **argv) {
  if (argc == 2 && strcmp(argv[1], "--print-peak-bytes") == 0) { /* test_peak_bytes_own_process */
    printf("%zu\n", karst_i_peak_bytes());
    return 0;
  }
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_peak_bytes_own_process), cmocka_unit_test(test_pipeline_after_graph),
      cmocka_unit_test(test_unreachable_key_point),  cmocka_unit_test(test_single_key_point),
      cmocka_unit_test(test_generate_end_to_end),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
