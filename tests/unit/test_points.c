/* sampling.points: the point cloud reader (karst_points_load) on well-formed and hostile files,
 * the scenario key, and the sampler's use of the cloud (which points become samples). Expected
 * values are the numbers written into the files, and which points lie in the bedrock or near a
 * key point by hand (the box, terrain and radii below). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "geology_fixture.h"
#include "io/input_internal.h"
#include "karst.h"
#include "test_util.h"

static char dir[64];

static int setup(void **state) {
  (void)state;
  snprintf(dir, sizeof dir, "/tmp/karst_points_XXXXXX");
  return mkdtemp(dir) ? 0 : -1;
}

static int teardown(void **state) {
  (void)state;
  return test_util_remove_dir(dir);
}

/* Write @p len bytes of @p text to DIR/NAME; the path in a static buffer. */
static const char *put(const char *name, const char *text, size_t len) {
  static char path[128];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *fp = fopen(path, "wb");
  assert_non_null(fp);
  assert_int_equal(fwrite(text, 1, len, fp), len);
  fclose(fp);
  return path;
}

static const char *puts_file(const char *name, const char *text) {
  return put(name, text, strlen(text));
}

static void test_points_formats(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  /* A header, comments, blank lines, blanks, tabs, commas with blanks around them, CRLF, a line
   * without its final newline, and numbers in every form strtod reads. */
  const char *p = puts_file("ok.xyz", "# cloud\n"
                                      "X, Y, Z\r\n"
                                      "\n"
                                      "1 2 3\n"
                                      "   # indented comment\n"
                                      "\t4.5\t-6e1\t7.25  \r\n"
                                      "8,9,10\n"
                                      "1e-3 , -0.5 ,+2\n"
                                      "0x1p3 1 1");
  double *xyz = NULL;
  long *lines = NULL;
  karst_int_t n = 0;
  assert_int_equal(karst_points_load(&ctx, p, &xyz, &n, &lines), KARST_SUCCESS);
  assert_int_equal(n, 5);
  const double want[15] = {1, 2, 3, 4.5, -60, 7.25, 8, 9, 10, 1e-3, -0.5, 2, 8, 1, 1};
  const long want_lines[5] = {4, 6, 7, 8, 9};
  for (int i = 0; i < 15; i++)
    assert_true(xyz[i] == want[i]);
  for (int i = 0; i < 5; i++)
    assert_int_equal(lines[i], want_lines[i]);
  free(xyz), free(lines);
  /* Without a header, without the lines. */
  p = puts_file("bare.xyz", "-1 -2 -3\n");
  assert_int_equal(karst_points_load(&ctx, p, &xyz, &n, NULL), KARST_SUCCESS);
  assert_int_equal(n, 1);
  assert_true(xyz[0] == -1 && xyz[1] == -2 && xyz[2] == -3);
  free(xyz);
  /* A field of a full line's length is read, not cut. */
  char line[4200];
  int m = snprintf(line, sizeof line, "1 2 0.5");
  while (m < 4090)
    line[m++] = '0';
  line[m++] = '\n', line[m] = '\0';
  p = puts_file("long_number.xyz", line);
  assert_int_equal(karst_points_load(&ctx, p, &xyz, &n, NULL), KARST_SUCCESS);
  assert_int_equal(n, 1);
  assert_true(xyz[2] == 0.5);
  free(xyz);
}

/* Each hostile file: the error code, and the message naming the file, line, column and field. */
static void expect_error(const char *name, const char *text, size_t len, karst_error_t code,
                         const char *where, const char *what) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  const char *p = put(name, text, len);
  double *xyz = (double *)&ctx; /* must be reset */
  long *lines = (long *)&ctx;
  karst_int_t n = 7;
  karst_error_t err = karst_points_load(&ctx, p, &xyz, &n, &lines);
  if (err != code || !strstr(ctx.errmsg, where) || !strstr(ctx.errmsg, what) ||
      !strstr(ctx.errmsg, name)) {
    print_error("%s: error %d, message '%s'; expected %d with '%s' and '%s'\n", name, (int)err,
                ctx.errmsg, (int)code, where, what);
    fail();
  }
  assert_null(xyz);
  assert_null(lines);
  assert_int_equal(n, 0);
}

#define EXPECT(name, text, code, where, what)                                                      \
  expect_error(name, text, sizeof text - 1, code, where, what)

static void test_points_hostile(void **state) {
  (void)state;
  EXPECT("letters.xyz", "1 2 3\n1 2 abc\n", KARST_EPARSE,
         ":2:5:", "field z: 'abc' is not a number");
  EXPECT("trailing.xyz", "1 2 3x\n", KARST_EPARSE, ":1:5:", "field z: '3x' is not a number");
  EXPECT("missing.xyz", "# c\n1 2\n", KARST_EPARSE, ":2:", "field z missing");
  EXPECT("one.xyz", "7\n", KARST_EPARSE, ":1:", "field y missing");
  EXPECT("fourth.xyz", "1 2 3 4\n", KARST_EPARSE, ":1:7:", "a fourth field '4'");
  EXPECT("comma_end.xyz", "1,2,3,\n", KARST_EPARSE, ":1:7:", "a fourth field ''");
  EXPECT("empty_field.xyz", "1,,3\n", KARST_EPARSE, ":1:3:", "field y: '' is not a number");
  EXPECT("nan.xyz", "1 nan 3\n", KARST_EPARSE, ":1:3:", "field y: 'nan' is not a finite");
  EXPECT("inf.xyz", "-inf 2 3\n", KARST_EPARSE, ":1:1:", "field x: '-inf' is not a finite");
  EXPECT("huge.xyz", "1 2 1e999\n", KARST_EPARSE, ":1:5:", "field z: '1e999' is not a finite");
  EXPECT("late_header.xyz", "1 2 3\nx y z\n", KARST_EPARSE, ":2:1:", "field x: 'x' is not");
  EXPECT("repeat.xyz", "1 2 3\n4 5 6\n\n1 2 3\n", KARST_EPARSE,
         ":4:", "the point (1, 2, 3) repeats line 1");
  EXPECT("signed_zero.xyz", "0 0 5\n-0 0 5\n", KARST_EPARSE, ":2:", "repeats line 1");
  EXPECT("empty.xyz", "", KARST_EPARSE, "empty.xyz:", "no points");
  EXPECT("comments.xyz", "# only\nx y z\n\n", KARST_EPARSE, "comments.xyz:", "no points");
  EXPECT("nul.xyz", "1 2\0 3\n", KARST_EPARSE, ":1:", "NUL byte");
  char big[5000];
  memset(big, '1', sizeof big);
  big[1] = ' ', big[3] = ' ', big[sizeof big - 1] = '\n';
  expect_error("long_line.xyz", big, sizeof big, KARST_EPARSE, ":1:", "longer than 4096 bytes");
  /* Not a regular file, missing. */
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  double *xyz = NULL;
  karst_int_t n = 0;
  char sub[128];
  snprintf(sub, sizeof sub, "%s/a_directory.xyz", dir);
  assert_int_equal(mkdir(sub, 0700), 0);
  assert_int_equal(karst_points_load(&ctx, sub, &xyz, &n, NULL), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "a_directory.xyz"));
  snprintf(sub, sizeof sub, "%s/absent.xyz", dir);
  assert_int_equal(karst_points_load(&ctx, sub, &xyz, &n, NULL), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "absent.xyz"));
  assert_null(xyz);
}

/* The scenario key: read relative to the scenario, the file's error followed by the key's place. */
static void test_points_scenario(void **state) {
  (void)state;
  puts_file("cloud.xyz", "x y z\n50 40 30\n20 20 20\n");
  puts_file("bad.xyz", "50 40 30\n20 20\n");
  const char *base = "name: t\nunits: m\ndomain: {min: [0, 0, 0], max: [100, 80, 60]}\n"
                     "terrain: {elevation: 50}\n"
                     "key_points:\n  - {name: s, type: sink, position: [10, 10, 45]}\n"
                     "  - {name: o, type: spring, position: [90, 70, 5]}\n";
  char text[1024];
  snprintf(text, sizeof text,
           "%ssampling: {fill_radius: 8, feature_radius: 3, points: cloud.xyz}\n", base);
  const char *y = puts_file("good.yaml", text);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  assert_int_equal(karst_scenario_load(&ctx, y, &sc), KARST_SUCCESS);
  assert_non_null(sc.sampling.points);
  assert_non_null(strstr(sc.sampling.points, "/cloud.xyz"));
  assert_int_equal(sc.sampling.n_points, 2);
  assert_true(sc.sampling.points_xyz[3] == 20 && sc.sampling.points_xyz[5] == 20);
  /* The file is one of the scenario's files (copied with it by calibrate, listed by files). */
  char **files = NULL;
  int nf = 0, found = 0;
  assert_int_equal(karst_scenario_files(&ctx, y, &files, &nf), KARST_SUCCESS);
  for (int i = 0; i < nf; i++)
    found += strstr(files[i], "cloud.xyz") != NULL, free(files[i]);
  free(files);
  assert_int_equal(found, 1);
  /* The budget counts the file's points in place of the fill. */
  karst_budget_t b;
  karst_budget_estimate(&sc, 1, &b);
  assert_true(b.fill_samples == 2);
  karst_scenario_destroy(&sc);

  snprintf(text, sizeof text, "%ssampling: {points: bad.xyz}\n", base);
  y = puts_file("bad.yaml", text);
  assert_int_equal(karst_scenario_load(&ctx, y, &sc), KARST_EPARSE);
  assert_non_null(strstr(ctx.errmsg, "bad.xyz:2: field z missing"));
  assert_non_null(strstr(ctx.errmsg, "(the points of sampling.points at "));
  assert_non_null(strstr(ctx.errmsg, "bad.yaml:8:20)"));
  snprintf(text, sizeof text, "%ssampling: {points: [1, 2]}\n", base);
  y = puts_file("list.yaml", text);
  assert_int_not_equal(karst_scenario_load(&ctx, y, &sc), KARST_SUCCESS);
  assert_non_null(strstr(ctx.errmsg, "sampling.points"));
}

/* 100 x 80 x 60 m box under a flat terrain at 50 m; a sink at (10, 10, 45) and a spring at
 * (90, 70, 5) whose water table (the plane through it) is sampled within 1 m at r_f = 3 m. */
static void small_scenario(karst_scenario_t *sc) {
  karst_scenario_init(sc);
  sc->domain_max[0] = 100, sc->domain_max[1] = 80, sc->domain_max[2] = 60;
  sc->terrain.elevation = 50;
  sc->sampling.feature_radius = 3;
  sc->sampling.fill_radius = 8;
  sc->sampling.feature_band = 1;
  sc->key_points = calloc(2, sizeof(karst_keypoint_t));
  sc->n_key_points = 2;
  snprintf(sc->key_points[0].name, sizeof sc->key_points[0].name, "sink");
  sc->key_points[0].type = KARST_KEYPOINT_SINK;
  sc->key_points[0].p[0] = 10, sc->key_points[0].p[1] = 10, sc->key_points[0].p[2] = 45;
  snprintf(sc->key_points[1].name, sizeof sc->key_points[1].name, "spring");
  sc->key_points[1].type = KARST_KEYPOINT_SPRING;
  sc->key_points[1].p[0] = 90, sc->key_points[1].p[1] = 70, sc->key_points[1].p[2] = 5;
}

static void test_points_sampling(void **state) {
  (void)state;
  karst_scenario_t sc;
  small_scenario(&sc);
  /* Kept: (50, 40, 30), (20, 20, 20), (99, 1, 49) (inside, far from the key points and 25 m and
   * more above the water-table layer [4, 6]). Dropped: above the terrain (50, 40, 55) and
   * (30, 30, 60), outside the box (150, 40, 30) and (50, -1, 30), within r_m = min(3, 8) m of
   * the sink (12, 10, 45: 2 m). */
  static const double pts[] = {50, 40, 30, 50, 40, 55, 150, 40, 30, 20, 20, 20,
                               12, 10, 45, 30, 30, 60, 50,  -1, 30, 99, 1,  49};
  const int n = (int)(sizeof pts / sizeof pts[0] / 3);
  sc.sampling.points = strdup("in-memory");
  sc.sampling.points_xyz = malloc(sizeof pts);
  memcpy(sc.sampling.points_xyz, pts, sizeof pts);
  sc.sampling.n_points = n;
  const double kept[3][3] = {{50, 40, 30}, {20, 20, 20}, {99, 1, 49}};
  karst_samples_t first;
  karst_samples_init(&first);
  for (int threads = 1; threads <= 3; threads += 2) {
    karst_ctx_t ctx;
    karst_ctx_init(&ctx);
    ctx.nthreads = threads;
    karst_rng_t rng;
    karst_rng_init(&rng, 5, 0);
    karst_samples_t s;
    karst_samples_init(&s);
    assert_int_equal(T_sampling_run(&ctx, &sc, &rng, &s), KARST_SUCCESS);
    int n_points = 0, n_fill = 0, n_table = 0, seen[3] = {0, 0, 0};
    for (karst_int_t i = 0; i < s.n; i++) {
      n_fill += s.source[i] == KARST_SAMPLE_FILL;
      n_table += s.source[i] == KARST_SAMPLE_WATER_TABLE;
      if (s.source[i] != KARST_SAMPLE_POINTS) continue;
      n_points++;
      for (int k = 0; k < 3; k++)
        if (!memcmp(s.xyz + 3 * i, kept[k], sizeof kept[k])) seen[k]++;
    }
    assert_int_equal(n_points, 3);
    assert_int_equal(seen[0] + seen[1] + seen[2], 3);
    assert_true(seen[0] == 1 && seen[1] == 1 && seen[2] == 1);
    assert_int_equal(n_fill, 0); /* the cloud replaces the fill */
    assert_true(n_table > 0);    /* the features are still sampled */
    assert_int_equal(s.n, 2 + n_table + 3);
    if (threads == 1) {
      first = s;
    } else { /* the same samples on 3 threads */
      assert_int_equal(s.n, first.n);
      assert_memory_equal(s.xyz, first.xyz, sizeof(double) * 3 * (size_t)s.n);
      assert_memory_equal(s.source, first.source, (size_t)s.n);
      karst_samples_destroy(&s);
    }
  }
  karst_samples_destroy(&first);
  /* More points kept than max_samples: refused, naming the stage. */
  sc.sampling.max_samples = 4;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_rng_t rng;
  karst_rng_init(&rng, 5, 0);
  karst_samples_t s;
  karst_samples_init(&s);
  /* 2 key points and the water table's samples leave no room for the points. */
  assert_int_not_equal(T_sampling_run(&ctx, &sc, &rng, &s), KARST_SUCCESS);
  assert_non_null(strstr(ctx.errmsg, "max_samples"));
  karst_samples_destroy(&s);
  karst_scenario_destroy(&sc);
}

/* The reader's fast decimal path (karst_i_parse_decimal) against glibc's correctly rounded
 * strtod, the independent method: equal to the bit wherever it answers, on hand-picked edge
 * cases and on 300 000 random decimals; and it declines what it must leave to strtod. */
static void same_as_strtod(const char *t) {
  double fast = 0, slow = strtod(t, NULL);
  if (karst_i_parse_decimal(t, strlen(t), &fast) && memcmp(&fast, &slow, sizeof fast) != 0) {
    print_error("'%s': fast path %.17g, strtod %.17g\n", t, fast, slow);
    fail();
  }
}

static void test_points_decimal(void **state) {
  (void)state;
  double x;
  static const char *const taken[] = {"0", "-0", "+7", "1.", ".5", "-751.7014069032869", "1e22",
                                      "2E-22", "1e+5", "000012.5000", "9007199254740992",
                                      "0.000123", "4.9e-3",
                                      /* x87 extended precision: 17 and 19 digits, |e| to 27 */
                                      "-751.70140690328693", "18014398509481985",
                                      "1234567890123456789", "1e24", "1e-23", "4.5e-26", "0e25"};
  for (size_t i = 0; i < sizeof taken / sizeof *taken; i++) {
    assert_true(karst_i_parse_decimal(taken[i], strlen(taken[i]), &x));
    same_as_strtod(taken[i]);
  }
  assert_true(karst_i_parse_decimal("-0", 2, &x) && signbit(x) && x == 0);
  /* Left to strtod: exactly halfway between two doubles (by hand: 2^53 + 1 lies halfway
   * between 2^53 and 2^53 + 2, where the extended result is exact and its 11 low bits are
   * 10000000000; 10^23 = 2^23 5^23 with 5^23 odd and 54 bits long, the classic hard case),
   * beyond 10^27, more than 19 digits, other spellings, and whatever is not a
   * number at all. */
  static const char *const declined[] = {"9007199254740993",
                                         "1e23",
                                         "1e28",
                                         "1e-28",
                                         "12345678901234567890",
                                         "0x10",
                                         "inf",
                                         "nan",
                                         "",
                                         ".",
                                         "e5",
                                         "1e",
                                         "1e+",
                                         "1.2.3",
                                         "--1",
                                         "1 ",
                                         "1,5",
                                         "0e999"};
  for (size_t i = 0; i < sizeof declined / sizeof *declined; i++)
    assert_false(karst_i_parse_decimal(declined[i], strlen(declined[i]), &x));
  karst_rng_t rng;
  karst_rng_init(&rng, 2026, 12);
  int taken_n = 0;
  const int N = 300000;
  for (int t = 0; t < N; t++) {
    char buf[80];
    int n = 0;
    int r = (int)karst_rng_below(&rng, 3);
    if (r == 1) buf[n++] = '-';
    if (r == 2) buf[n++] = '+';
    int ni = (int)karst_rng_below(&rng, 11), nf = (int)karst_rng_below(&rng, 13);
    for (int i = 0; i < ni; i++)
      buf[n++] = (char)('0' + karst_rng_below(&rng, 10));
    if (nf > 0 || karst_rng_below(&rng, 2)) {
      buf[n++] = '.';
      for (int i = 0; i < nf; i++)
        buf[n++] = (char)('0' + karst_rng_below(&rng, 10));
    }
    if (ni + nf == 0) buf[n++] = '3';
    if (karst_rng_below(&rng, 3) == 0)
      n += snprintf(buf + n, sizeof buf - (size_t)n, "e%d", (int)karst_rng_below(&rng, 61) - 30);
    buf[n] = '\0';
    taken_n += karst_i_parse_decimal(buf, (size_t)n, &x);
    same_as_strtod(buf);
  }
  assert_true(taken_n > N / 2); /* the fast path is what runs */
  /* Shortest round-trip digits of random doubles (what bench_peers and most exporters write) and
   * the exact halfway points between neighbouring doubles, written with 17 to 19 digits (so
   * within a unit of the 19th digit of a tie: the hardest inputs for the double rounding). */
  int halfway = 0;
  for (int t = 0; t < N; t++) {
    char buf[80];
    double d = ldexp(karst_rng_uniform_range(&rng, 1, 2), (int)karst_rng_below(&rng, 80) - 40);
    snprintf(buf, sizeof buf, "%.17g", d);
    for (int p = 1; p <= 17; p++) { /* the shortest of them that reads back as d */
      char sh[80];
      snprintf(sh, sizeof sh, "%.*g", p, d);
      if (strtod(sh, NULL) == d) {
        memcpy(buf, sh, sizeof sh);
        break;
      }
    }
    same_as_strtod(buf);
    long double mid = ((long double)d + (long double)nextafter(d, INFINITY)) / 2;
    snprintf(buf, sizeof buf, "%.*Le", 16 + (int)karst_rng_below(&rng, 3), mid);
    halfway += !karst_i_parse_decimal(buf, strlen(buf), &x);
    same_as_strtod(buf);
  }
  assert_true(halfway > 0); /* some ties reach the check that declines them */
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_points_formats),  cmocka_unit_test(test_points_hostile),
      cmocka_unit_test(test_points_scenario), cmocka_unit_test(test_points_sampling),
      cmocka_unit_test(test_points_decimal),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
