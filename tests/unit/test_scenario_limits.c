/* Limits of the scenario reader: inputs that are not regular files, size caps,
 * integers out of their type's range, key points on the ground and close to
 * each other.
 *
 * Every test writes its own files into a fresh directory under /tmp; the
 * expected messages carry positions counted by hand in the text written
 * (line 1 is the first line of the string, columns from 1). */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "geology_fixture.h"
#include "karst.h"
#include "test_util.h"

static char dir[64];

static int setup(void **state) {
  (void)state;
  snprintf(dir, sizeof dir, "/tmp/karst_limits_XXXXXX");
  return mkdtemp(dir) ? 0 : -1;
}

static int teardown(void **state) {
  (void)state;
  return test_util_remove_dir(dir);
}

/* dir/name, written with @p text (or not written when text is NULL). */
static const char *tmp_file(const char *name, const char *text) {
  static char path[8][256];
  static int next;
  char *p = path[next++ % 8];
  snprintf(p, 256, "%s/%s", dir, name);
  if (text) {
    FILE *fp = fopen(p, "w");
    assert_non_null(fp);
    fputs(text, fp);
    fclose(fp);
  }
  return p;
}

/* A sparse file of @p bytes (no disk space used). */
static const char *sparse_file(const char *name, long long bytes) {
  const char *p = tmp_file(name, NULL);
  int fd = open(p, O_CREAT | O_TRUNC | O_WRONLY, 0644);
  assert_true(fd >= 0);
  assert_int_equal(ftruncate(fd, (off_t)bytes), 0);
  close(fd);
  return p;
}

/* Load @p path; expect @p code, the message to start with @p prefix and to contain @p part. */
static void expect_load(const char *path, karst_error_t code, const char *prefix,
                        const char *part) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  karst_error_t err = karst_scenario_load(&ctx, path, &sc);
  if (err != code || strncmp(ctx.errmsg, prefix, strlen(prefix)) || !strstr(ctx.errmsg, part))
    print_error("got %s: \"%s\"\nexpected %s: \"%s...%s...\"\n", karst_error_name(err), ctx.errmsg,
                karst_error_name(code), prefix, part);
  assert_int_equal(err, code);
  assert_true(strncmp(ctx.errmsg, prefix, strlen(prefix)) == 0);
  assert_non_null(strstr(ctx.errmsg, part));
  assert_null(sc.path);
  karst_scenario_destroy(&sc);
}

static void expect_grid(const char *path, karst_error_t code, const char *prefix,
                        const char *part) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_terrain_t t;
  memset(&t, 0, sizeof t);
  karst_error_t err = karst_terrain_load_grid(&ctx, path, &t);
  if (err != code || strncmp(ctx.errmsg, prefix, strlen(prefix)) || !strstr(ctx.errmsg, part))
    print_error("got %s: \"%s\"\nexpected %s: \"%s...%s...\"\n", karst_error_name(err), ctx.errmsg,
                karst_error_name(code), prefix, part);
  assert_int_equal(err, code);
  assert_true(strncmp(ctx.errmsg, prefix, strlen(prefix)) == 0);
  assert_non_null(strstr(ctx.errmsg, part));
  assert_null(t.z);
}

/* A valid scenario around a given terrain block (lines 1-4 before it). */
static const char *scenario_with_terrain(const char *name, const char *terrain_value) {
  char text[1024];
  snprintf(text, sizeof text,
           "domain:\n"
           "  min: [0, 0, 0]\n"
           "  max: [100, 100, 50]\n"
           "terrain:\n"
           "  heightfield: %s\n"
           "key_points:\n"
           "  - {name: in, type: sink, position: [10, 10, 20]}\n"
           "  - {name: out, type: spring, position: [90, 90, 10]}\n",
           terrain_value);
  return tmp_file(name, text);
}

/* ------------------------------------------------------------------------ */
/* 1. Not a regular file; size caps                                         */
/* ------------------------------------------------------------------------ */

static void test_scenario_not_regular(void **state) {
  (void)state;
  char prefix[300];
  snprintf(prefix, sizeof prefix, "%s: ", dir);
  expect_load(dir, KARST_EIO, prefix, "is a directory; the scenario must be a regular file");
  expect_load("/dev/zero", KARST_EIO,
              "/dev/zero: ", "is a character device; the scenario must be a regular file");
  const char *fifo = tmp_file("pipe.yaml", NULL);
  assert_int_equal(mkfifo(fifo, 0600), 0);
  /* Opening a FIFO without a writer would block: the type is checked first. */
  snprintf(prefix, sizeof prefix, "%s: ", fifo);
  expect_load(fifo, KARST_EIO, prefix, "is a FIFO (named pipe)");
}

/* 64 MiB + 1 bytes is one byte over KARST_SCENARIO_MAX_BYTES = 64 * 2^20 = 67108864. */
static void test_scenario_too_large(void **state) {
  (void)state;
  assert_true(KARST_SCENARIO_MAX_BYTES == 67108864LL);
  const char *big = sparse_file("big.yaml", 67108865LL);
  char prefix[300];
  snprintf(prefix, sizeof prefix, "%s: ", big);
  expect_load(big, KARST_ERANGE, prefix,
              "the scenario file is 67108865 bytes, more than the limit of 64 MiB");
}

/* The heightfield value is at line 5, column 16 of scenario_with_terrain's text. */
static void test_heightfield_not_regular(void **state) {
  (void)state;
  char prefix[300];
  const char *s = scenario_with_terrain("hf_dir.yaml", dir);
  snprintf(prefix, sizeof prefix, "%s:5:16: terrain.heightfield: %s: ", s, dir);
  expect_load(s, KARST_EIO, prefix, "is a directory; the heightfield must be a regular file");

  s = scenario_with_terrain("hf_zero.yaml", "/dev/zero");
  snprintf(prefix, sizeof prefix, "%s:5:16: terrain.heightfield: /dev/zero: ", s);
  expect_load(s, KARST_EIO, prefix, "is a character device");

  const char *fifo = tmp_file("pipe.asc", NULL);
  assert_int_equal(mkfifo(fifo, 0600), 0);
  s = scenario_with_terrain("hf_fifo.yaml", "pipe.asc");
  snprintf(prefix, sizeof prefix, "%s:5:16: terrain.heightfield: %s: ", s, fifo);
  expect_load(s, KARST_EIO, prefix, "is a FIFO (named pipe)");
  /* The same through the public grid reader. */
  snprintf(prefix, sizeof prefix, "%s: ", fifo);
  expect_grid(fifo, KARST_EIO, prefix, "is a FIFO (named pipe)");
  expect_grid("/dev/zero", KARST_EIO, "/dev/zero: ", "is a character device");
}

/* 2 GiB + 1 = 2147483649 bytes, one over KARST_HEIGHTFIELD_MAX_BYTES. */
static void test_heightfield_too_large(void **state) {
  (void)state;
  assert_true(KARST_HEIGHTFIELD_MAX_BYTES == 2147483648LL);
  const char *big = sparse_file("big.asc", 2147483649LL);
  char prefix[300];
  snprintf(prefix, sizeof prefix, "%s: ", big);
  expect_grid(big, KARST_ERANGE, prefix,
              "the heightfield file is 2147483649 bytes, more than the limit of 2 GiB");
  const char *s = scenario_with_terrain("hf_big.yaml", "big.asc");
  snprintf(prefix, sizeof prefix, "%s:5:16: terrain.heightfield: %s: ", s, big);
  expect_load(s, KARST_ERANGE, prefix, "more than the limit of 2 GiB");
}

/* Cell cap 1e8: 10001 x 10000 = 100010000 is over it; products that overflow
 * int64 are refused side by side. */
static void test_heightfield_too_many_cells(void **state) {
  (void)state;
  char prefix[300];
  const char *g = tmp_file("wide.asc", "ncols 10001\nnrows 10000\nxllcorner 0\nyllcorner 0\n"
                                       "cellsize 1\n1 2 3\n");
  snprintf(prefix, sizeof prefix, "%s:2:1: ", g);
  expect_grid(g, KARST_ERANGE, prefix,
              "ncols x nrows = 10001 x 10000 = 100010000 cells, more than the limit of 100000000");
  /* A side alone above the cap is refused where it is written, before any
   * product (2^63 - 1 squared would overflow int64). */
  g = tmp_file("huge.asc", "nrows 9223372036854775807\nncols 9223372036854775807\n"
                           "xllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n");
  snprintf(prefix, sizeof prefix, "%s:1:7: ", g);
  expect_grid(g, KARST_ERANGE, prefix,
              "nrows = 9223372036854775807 is more than the limit of 100000000 cells");
  /* Exactly at the cap is accepted by the header check; the short first row
   * is then the error (and only the values read were stored). */
  g = tmp_file("cap.asc", "ncols 10000\nnrows 10000\nxllcorner 0\nyllcorner 0\n"
                          "cellsize 1\n1 2 3\n");
  snprintf(prefix, sizeof prefix, "%s:6:6: ", g);
  expect_grid(g, KARST_EPARSE, prefix, "row 1 has 3 values, expected ncols = 10000");
}

/* ------------------------------------------------------------------------ */
/* 2. Integers out of their type's range                                    */
/* ------------------------------------------------------------------------ */

/* A valid scenario with @p extra as its line 6 (the key under test). */
static const char *scenario_with(const char *name, const char *extra) {
  char text[1024];
  snprintf(text, sizeof text,
           "domain: {min: [0, 0, 0], max: [100, 100, 50]}\n"
           "terrain: {elevation: 40}\n"
           "key_points:\n"
           "  - {name: in, type: sink, position: [10, 10, 20]}\n"
           "  - {name: out, type: spring, position: [90, 90, 10]}\n"
           "%s\n",
           extra);
  return tmp_file(name, text);
}

static void expect_line6(const char *extra, int col, karst_error_t code, const char *part) {
  const char *s = scenario_with("int.yaml", extra);
  char prefix[300];
  snprintf(prefix, sizeof prefix, "%s:6:%d: ", s, col);
  expect_load(s, code, prefix, part);
}

/* INT_MAX = 2^31 - 1 = 2147483647, INT64_MAX = 2^63 - 1 = 9223372036854775807,
 * UINT64_MAX = 2^64 - 1 = 18446744073709551615. Values one past each bound,
 * and far past them, name the field, its bounds and the value as written.
 * Columns: "sampling: {k: " is 14 characters, so the value is at column 15. */
static void test_integer_ranges(void **state) {
  (void)state;
  expect_line6("sampling: {k: 2147483648}", 15, KARST_ERANGE,
               "sampling.k must be an integer between 1 and 2147483647, got 2147483648");
  expect_line6("sampling: {k: 99999999999999999999}", 15, KARST_ERANGE,
               "sampling.k must be an integer between 1 and 2147483647, got 99999999999999999999");
  expect_line6("sampling: {k: 1e17}", 15, KARST_ERANGE,
               "sampling.k must be an integer between 1 and 2147483647, got 1e17");
  expect_line6("sampling: {k: -3}", 15, KARST_ERANGE, "sampling.k must be >= 1, got -3");
  expect_line6("sampling: {k: -2147483649}", 15, KARST_ERANGE,
               "sampling.k must be an integer between 1 and 2147483647, got -2147483649");
  expect_line6("sampling: {max_samples: 9223372036854775808}", 25, KARST_ERANGE,
               "sampling.max_samples must be an integer between 1 and 9223372036854775807, got "
               "9223372036854775808");
  expect_line6("random: {realisations: 2147483648}", 24, KARST_ERANGE,
               "random.realisations must be an integer between 1 and 2147483647, got 2147483648");
  expect_line6("random: {realisations: -1}", 24, KARST_ERANGE,
               "random.realisations must be >= 1, got -1");
  expect_line6("amplification: {steps: -1}", 24, KARST_ERANGE,
               "amplification.steps must be >= 0, got -1");
  expect_line6("amplification: {steps: 2147483648}", 24, KARST_ERANGE,
               "amplification.steps must be an integer between 0 and 2147483647, got 2147483648");
  expect_line6("amplification: {points: 3000000000}", 25, KARST_ERANGE,
               "amplification.points must be an integer between 0 and 2147483647, got 3000000000");
  expect_line6("amplification: {points: -7}", 25, KARST_ERANGE,
               "amplification.points must be >= 0, got -7");
  expect_line6("random: {seed: 18446744073709551616}", 16, KARST_EINVAL,
               "random.seed must be an unsigned 64-bit integer (0 to 18446744073709551615), got "
               "18446744073709551616");
  expect_line6(
      "random: {seed: -1}", 16, KARST_EINVAL,
      "random.seed must be an unsigned 64-bit integer (0 to 18446744073709551615), got -1");
  /* Whole numbers beyond 2^53 in floating notation are not exact: refused as such. */
  expect_line6("sampling: {max_samples: 1e17}", 25, KARST_EINVAL,
               "sampling.max_samples: 1e17 is beyond 2^53");
  /* The bounds themselves are accepted. */
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  const char *ok = scenario_with("ok.yaml", "sampling: {k: 2147483647, max_samples: "
                                            "9223372036854775807}\nrandom: {seed: "
                                            "18446744073709551615, realisations: 2147483647}");
  assert_int_equal(karst_scenario_load(&ctx, ok, &sc), KARST_SUCCESS);
  assert_int_equal(sc.sampling.k, 2147483647);
  assert_true(sc.sampling.max_samples == INT64_MAX);
  assert_true(sc.seed == UINT64_MAX);
  assert_int_equal(sc.realisations, 2147483647);
  karst_scenario_destroy(&sc);
}

/* ------------------------------------------------------------------------ */
/* 4. Key points on the ground, coincident, close together                  */
/* ------------------------------------------------------------------------ */

/* Load @p path (must succeed), generate with seed 3, and return the position
 * of the network node labelled @p name through @p xyz; returns the number of
 * nodes with that label. */
static int generate_and_find(const char *path, const char *name, double xyz[3]) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  ctx.nthreads = 1;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  karst_error_t err = karst_scenario_load(&ctx, path, &sc);
  if (err) print_error("load: %s\n", ctx.errmsg);
  assert_int_equal(err, KARST_SUCCESS);
  karst_network_t net;
  karst_network_init(&net);
  err = karst_generate(&ctx, &sc, 3, 0, &net, NULL, NULL);
  if (err) print_error("generate: %s\n", ctx.errmsg);
  assert_int_equal(err, KARST_SUCCESS);
  int found = 0;
  for (karst_int_t i = 0; net.node_labels && i < net.n_nodes; i++) {
    if (net.node_labels[i] && !strcmp(net.node_labels[i], name)) {
      memcpy(xyz, net.xyz + 3 * i, 3 * sizeof(double));
      found++;
    }
  }
  karst_network_destroy(&net);
  karst_scenario_destroy(&sc);
  return found;
}

/* A sink exactly on a flat ground at 40 m: validate and generate agree (the
 * bedrock is z <= h), and the network keeps the sink at (10, 10, 40). */
static void test_keypoint_on_flat_ground(void **state) {
  (void)state;
  const char *s =
      tmp_file("ground_flat.yaml", "domain: {min: [0, 0, 0], max: [100, 100, 50]}\n"
                                   "terrain: {elevation: 40}\n"
                                   "key_points:\n"
                                   "  - {name: in, type: sink, position: [10, 10, 40]}\n"
                                   "  - {name: out, type: spring, position: [90, 90, 10]}\n");
  double p[3];
  assert_int_equal(generate_and_find(s, "in", p), 1);
  assert_close(p[0], 10, 0);
  assert_close(p[1], 10, 0);
  assert_close(p[2], 40, 0);
  /* 1 mm above the ground is still refused, with the terrain height. */
  s = tmp_file("ground_above.yaml", "domain: {min: [0, 0, 0], max: [100, 100, 50]}\n"
                                    "terrain: {elevation: 40}\n"
                                    "key_points:\n"
                                    "  - {name: in, type: sink, position: [10, 10, 40.001]}\n"
                                    "  - {name: out, type: spring, position: [90, 90, 10]}\n");
  char prefix[300];
  snprintf(prefix, sizeof prefix, "%s:4:5: ", s);
  expect_load(s, KARST_ERANGE, prefix, "key_points[0] 'in' at z = 40.001 m is above the terrain");
}

/* The same on a heightfield, at the grid node (50, 50) whose elevation the
 * file gives as 37.5 (the bilinear surface passes through its nodes). */
static void test_keypoint_on_heightfield_ground(void **state) {
  (void)state;
  tmp_file("slope.asc", "ncols 3\nnrows 3\nxllcenter 0\nyllcenter 0\ncellsize 50\n"
                        "35 40 45\n32.5 37.5 42.5\n30 35 40\n");
  const char *s =
      tmp_file("ground_grid.yaml", "domain: {min: [0, 0, 0], max: [100, 100, 50]}\n"
                                   "terrain: {heightfield: slope.asc}\n"
                                   "key_points:\n"
                                   "  - {name: in, type: sink, position: [50, 50, 37.5]}\n"
                                   "  - {name: out, type: spring, position: [90, 90, 10]}\n");
  double p[3];
  assert_int_equal(generate_and_find(s, "in", p), 1);
  assert_close(p[2], 37.5, 0);
}

/* Segments from a point on the ground, on the V-shaped grid of test_cost.c
 * (z = 50, 10, 50 at x = 0, 10, 20; one row of cells along y). From the
 * valley floor a = (10, 5, 10), h(x) = 10 + 4|x - 10| near it:
 *   to (0, 5, 40): z - h = (10 + 30 s) - (10 + 40 s) = -10 s < 0 inside -> in;
 *   to (0, 5, 10): z - h = -40 s -> in;  straight down to (10, 5, 0): -10 s -> in;
 *   to (0, 5, 50), on the ground at both ends: z - h = 0 all along -> out;
 *   to (20, 5, 30): crosses the x = 10 grid line at s = 0 only, then
 *   z - h = (10 + 20 s) - (10 + 40 s) < 0 -> in. */
static void test_segments_from_the_ground(void **state) {
  (void)state;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  sc.domain_min[0] = 0, sc.domain_max[0] = 20;
  sc.domain_min[1] = 0, sc.domain_max[1] = 10;
  sc.domain_min[2] = -10, sc.domain_max[2] = 60;
  sc.terrain.is_grid = 1;
  sc.terrain.ncols = 3, sc.terrain.nrows = 2, sc.terrain.cellsize = 10;
  sc.terrain.xll = 0, sc.terrain.yll = 0;
  sc.terrain.z = malloc(6 * sizeof(double));
  assert_non_null(sc.terrain.z);
  const double v[6] = {50, 10, 50, 50, 10, 50};
  memcpy(sc.terrain.z, v, sizeof v);
  const double a[3] = {10, 5, 10};
  const double in1[3] = {0, 5, 40}, in2[3] = {0, 5, 10}, in3[3] = {10, 5, 0}, in4[3] = {20, 5, 30};
  const double along[3] = {0, 5, 50}, above[3] = {10, 5, 10.001};
  assert_true(T_in_bedrock(&sc, a));
  assert_false(T_in_bedrock(&sc, above));
  assert_true(T_segment_in_bedrock(&sc, a, in1));
  assert_true(T_segment_in_bedrock(&sc, in1, a));
  assert_true(T_segment_in_bedrock(&sc, a, in2));
  assert_true(T_segment_in_bedrock(&sc, a, in3));
  assert_true(T_segment_in_bedrock(&sc, a, in4));
  assert_false(T_segment_in_bedrock(&sc, a, along));
  assert_false(T_segment_in_bedrock(&sc, along, a));
  assert_true(isfinite(T_cost_edge(&sc, a, in1)));
  assert_true(isinf(T_cost_edge(&sc, a, along)));
  karst_scenario_destroy(&sc);
}

/* The same rule on a flat ground at 40 m (hand-checked: a segment is linear, so with both ends
 * at or below 40 its inside is strictly below unless both ends are at 40): ground to ground is
 * out, ground to below and below to below are in. */
static void test_segments_from_flat_ground(void **state) {
  (void)state;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  sc.domain_min[0] = 0, sc.domain_max[0] = 100;
  sc.domain_min[1] = 0, sc.domain_max[1] = 100;
  sc.domain_min[2] = 0, sc.domain_max[2] = 50;
  sc.terrain.is_grid = 0;
  sc.terrain.elevation = 40;
  const double g1[3] = {10, 5, 40}, g2[3] = {60, 5, 40}, b1[3] = {20, 5, 30}, b2[3] = {30, 9, 39.5};
  assert_false(T_segment_in_bedrock(&sc, g1, g2));
  assert_false(T_segment_in_bedrock(&sc, g2, g1));
  assert_true(T_segment_in_bedrock(&sc, g1, b1));
  assert_true(T_segment_in_bedrock(&sc, b1, g2));
  assert_true(T_segment_in_bedrock(&sc, b1, b2));
  assert_true(isinf(T_cost_edge(&sc, g1, g2)));
  assert_true(isfinite(T_cost_edge(&sc, g1, b1)));
  karst_scenario_destroy(&sc);
}

/* Two key points at one position: refused, naming both and their lines. */
static void test_coincident_key_points(void **state) {
  (void)state;
  const char *s = tmp_file("same.yaml", "domain: {min: [0, 0, 0], max: [100, 100, 50]}\n"
                                        "terrain: {elevation: 40}\n"
                                        "key_points:\n"
                                        "  - {name: a, type: sink, position: [10, 10, 20]}\n"
                                        "  - {name: out, type: spring, position: [90, 90, 10]}\n"
                                        "  - {name: b, type: waypoint, position: [10, 10, 20]}\n");
  char prefix[300];
  snprintf(prefix, sizeof prefix, "%s:6:5: ", s);
  expect_load(s, KARST_EINVAL, prefix,
              "key_points[2] 'b' (line 6) is at the same position (10, 10, 20) as key_points[0] "
              "'a' (line 4); key points must be at distinct positions");
  /* 1e-9 m apart is another position. */
  s = tmp_file("near.yaml", "domain: {min: [0, 0, 0], max: [100, 100, 50]}\n"
                            "terrain: {elevation: 40}\n"
                            "key_points:\n"
                            "  - {name: a, type: sink, position: [10, 10, 20]}\n"
                            "  - {name: out, type: spring, position: [90, 90, 10]}\n"
                            "  - {name: b, type: waypoint, position: [10, 10, 20.000000001]}\n");
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  assert_int_equal(karst_scenario_load(&ctx, s, &sc), KARST_SUCCESS);
  karst_scenario_destroy(&sc);
}

/* Key points closer than sampling.feature_radius (here 0.5 m apart, radius
 * 3 m): the sampler inserts every key point as a sample without a distance
 * test, so both are in the graph and both end up as nodes of the network at
 * their own positions. */
static void test_close_key_points(void **state) {
  (void)state;
  const char *s = tmp_file("close.yaml", "domain: {min: [0, 0, 0], max: [100, 100, 50]}\n"
                                         "terrain: {elevation: 40}\n"
                                         "sampling: {feature_radius: 3}\n"
                                         "key_points:\n"
                                         "  - {name: a, type: sink, position: [10, 10, 20]}\n"
                                         "  - {name: b, type: sink, position: [10.5, 10, 20]}\n"
                                         "  - {name: out, type: spring, position: [90, 90, 10]}\n");
  double pa[3], pb[3];
  assert_int_equal(generate_and_find(s, "a", pa), 1);
  assert_int_equal(generate_and_find(s, "b", pb), 1);
  assert_close(pa[0], 10, 0);
  assert_close(pb[0], 10.5, 0);
}

/* ------------------------------------------------------------------------ */
/* 5. A key point generation cannot connect                                 */
/* ------------------------------------------------------------------------ */

static karst_int_t find_root(karst_int_t *parent, karst_int_t v) {
  while (parent[v] != v)
    v = parent[v] = parent[parent[v]];
  return v;
}

/* tests/data/scenarios/generate/knn_disconnected.yaml (k = 1) validates but
 * cannot be generated. The message gives the key point's FILE:LINE:COLUMN
 * (line 12, column 5: the "{" of its entry), the spring it cannot reach and
 * the number of connected pieces of the graph, which is checked against an
 * independent count: the same samples and graph (same seed and stream as
 * karst_generate) with union-find over the edges instead of the BFS of
 * src/generate. */
static void test_unreachable_message(void **state) {
  (void)state;
  const char *path = KARST_SOURCE_DIR "/tests/data/scenarios/generate/knn_disconnected.yaml";
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  ctx.nthreads = 1;
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  assert_int_equal(karst_scenario_load(&ctx, path, &sc), KARST_SUCCESS);
  karst_network_t net;
  karst_network_init(&net);
  assert_int_equal(karst_generate(&ctx, &sc, sc.seed, 0, &net, NULL, NULL), KARST_EUNREACHABLE);
  assert_int_equal(net.n_nodes, 0);
  char msg[KARST_ERRMSG_MAX];
  snprintf(msg, sizeof msg, "%s", ctx.errmsg);
  print_message("%s\n", msg);

  karst_samples_t smp;
  karst_samples_init(&smp);
  karst_graph_t g;
  karst_graph_init(&g);
  karst_rng_t r;
  karst_rng_derive(&r, sc.seed, 0, KARST_STAGE_SAMPLING);
  assert_int_equal(T_sampling_run(&ctx, &sc, &r, &smp), KARST_SUCCESS);
  assert_int_equal(T_graph_build(&ctx, &sc, &smp, &g), KARST_SUCCESS);
  karst_int_t *parent = malloc(sizeof *parent * (size_t)g.n);
  assert_non_null(parent);
  for (karst_int_t v = 0; v < g.n; v++)
    parent[v] = v;
  for (karst_int_t u = 0; u < g.n; u++) {
    karst_arc_reader_t rd = karst_graph_arcs(&g, u);
    for (karst_int_t a = g.offsets[u]; a < g.offsets[u + 1]; a++)
      parent[find_root(parent, u)] = find_root(parent, karst_arc_next(&rd));
  }
  long long pieces = 0;
  for (karst_int_t v = 0; v < g.n; v++)
    pieces += find_root(parent, v) == v;
  int apart = find_root(parent, 0) != find_root(parent, 1);
  assert_true(apart);
  assert_true(pieces > 1);

  char expect[KARST_ERRMSG_MAX], pieces_text[256];
  snprintf(expect, sizeof expect,
           "%s:12:5: key point 'far_sink' at (10.00, 10.00, 20.00) cannot drain to 'outlet' "
           "(line 13): no path through the bedrock reaches it",
           path);
  snprintf(pieces_text, sizeof pieces_text,
           "the k-nearest-neighbour graph of %lld samples falls into %lld connected pieces, and "
           "the 2 key points lie in 2 of them",
           (long long)g.n, pieces);
  if (strncmp(msg, expect, strlen(expect)) != 0 || !strstr(msg, pieces_text) ||
      !strstr(msg, "raise sampling.k (now 1) or lower sampling.fill_radius (now 10 m)"))
    print_error("got      \"%s\"\nexpected \"%s...\" with \"%s\"\n", msg, expect, pieces_text);
  assert_true(strncmp(msg, expect, strlen(expect)) == 0);
  assert_non_null(strstr(msg, pieces_text));
  assert_non_null(strstr(msg, "raise sampling.k (now 1) or lower sampling.fill_radius (now 10 m)"));
  free(parent);
  karst_graph_destroy(&g);
  karst_samples_destroy(&smp);
  karst_scenario_destroy(&sc);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_scenario_not_regular),
      cmocka_unit_test(test_scenario_too_large),
      cmocka_unit_test(test_heightfield_not_regular),
      cmocka_unit_test(test_heightfield_too_large),
      cmocka_unit_test(test_heightfield_too_many_cells),
      cmocka_unit_test(test_integer_ranges),
      cmocka_unit_test(test_keypoint_on_flat_ground),
      cmocka_unit_test(test_keypoint_on_heightfield_ground),
      cmocka_unit_test(test_segments_from_the_ground),
      cmocka_unit_test(test_segments_from_flat_ground),
      cmocka_unit_test(test_coincident_key_points),
      cmocka_unit_test(test_close_key_points),
      cmocka_unit_test(test_unreachable_message),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
