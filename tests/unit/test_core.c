/* Core conventions: error list, context, random streams, atomic output, network storage. */
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "core/math_internal.h"
#include "karst.h"
#include "test_util.h"

static void test_error_list(void **state) {
  (void)state;
  assert_string_equal(karst_strerror(KARST_SUCCESS), "success");
  assert_string_equal(karst_error_name(KARST_EPARSE), "KARST_EPARSE");
  assert_string_equal(karst_strerror((karst_error_t)9999), "unknown error");
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  assert_int_equal(karst_set_error(&ctx, KARST_ERANGE, "f.yaml:%d:%d: dip %g", 3, 5, 135.0),
                   KARST_ERANGE);
  assert_string_equal(ctx.errmsg, "f.yaml:3:5: dip 135");
  assert_int_equal(ctx.errcode, KARST_ERANGE);
  assert_int_equal(karst_set_error(NULL, KARST_EIO, "x"), KARST_EIO);
}

/* Same (seed, stream) gives the same sequence; another stream or seed differs. */
static void test_rng_streams(void **state) {
  (void)state;
  karst_rng_t a, b, c, d;
  karst_rng_init(&a, 42, 7);
  karst_rng_init(&b, 42, 7);
  karst_rng_init(&c, 42, 8);
  karst_rng_init(&d, 43, 7);
  int same_c = 0, same_d = 0;
  for (int i = 0; i < 1000; i++) {
    uint64_t x = karst_rng_u64(&a);
    assert_true(x == karst_rng_u64(&b));
    same_c += x == karst_rng_u64(&c);
    same_d += x == karst_rng_u64(&d);
  }
  assert_int_equal(same_c, 0);
  assert_int_equal(same_d, 0);
}

/* Moments of the uniform and Gaussian variates against their exact values,
 * with 5-sigma tolerances for n = 200000 draws. */
static void test_rng_moments(void **state) {
  (void)state;
  karst_rng_t r;
  karst_rng_init(&r, 1, 0);
  const int n = 200000;
  double su = 0, su2 = 0, sg = 0, sg2 = 0;
  for (int i = 0; i < n; i++) {
    double u = karst_rng_uniform(&r);
    assert_true(u >= 0 && u < 1);
    su += u;
    su2 += u * u;
    double g = karst_rng_gaussian(&r);
    sg += g;
    sg2 += g * g;
  }
  /* uniform: mean 1/2 (sd 1/sqrt(12 n)), E[u^2] = 1/3 */
  assert_true(fabs(su / n - 0.5) < 5 * sqrt(1.0 / 12 / n));
  assert_true(fabs(su2 / n - 1.0 / 3) < 0.003);
  /* standard normal: mean 0 (sd 1/sqrt(n)), variance 1 (sd sqrt(2/n)) */
  assert_true(fabs(sg / n) < 5 / sqrt(n));
  assert_true(fabs(sg2 / n - 1) < 5 * sqrt(2.0 / n));
  /* below(n): every value of [0, 6) appears with frequency 1/6 within 5 sigma */
  int cnt[6] = {0};
  for (int i = 0; i < 60000; i++) {
    uint64_t k = karst_rng_below(&r, 6);
    assert_true(k < 6);
    cnt[k]++;
  }
  for (int k = 0; k < 6; k++)
    assert_true(fabs(cnt[k] - 10000.0) < 5 * sqrt(60000 * (1 / 6.0) * (5 / 6.0)));
  /* unit vectors have norm 1 */
  for (int i = 0; i < 100; i++) {
    double v[3];
    karst_rng_unit_vector(&r, v);
    assert_true(fabs(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] - 1) < 1e-12);
  }
}

static void test_network_storage(void **state) {
  (void)state;
  karst_network_t net;
  karst_network_init(&net);
  double *radius;
  assert_int_equal(karst_network_attr_add(&net, KARST_ATTR_EDGE, "radius", 1, 0, &radius), 0);
  for (int i = 0; i < 200; i++)
    assert_int_equal(karst_network_add_node(&net, i, 0, 0, NULL), 0);
  for (int i = 0; i < 199; i++) {
    karst_int_t e;
    assert_int_equal(karst_network_add_edge(&net, i, i + 1, &e), 0);
    karst_network_attr_find(&net, KARST_ATTR_EDGE, "radius")->data[e] = 0.5 * i;
  }
  assert_int_equal(karst_network_add_edge(&net, 0, 200, NULL), KARST_EINVAL);
  assert_int_equal(karst_network_set_label(&net, 3, "st3"), 0);
  assert_int_equal(karst_network_set_crs(&net, "EPSG:7405"), 0);
  karst_network_t copy;
  assert_int_equal(karst_network_copy(&copy, &net), 0);
  karst_network_destroy(&net);
  assert_int_equal(copy.n_nodes, 200);
  assert_int_equal(copy.n_edges, 199);
  assert_close(karst_network_attr_find(&copy, KARST_ATTR_EDGE, "radius")->data[198], 99.0, 0);
  assert_close(karst_network_edge_length(&copy, 10), 1.0, 1e-15);
  assert_string_equal(copy.node_labels[3], "st3");
  assert_null(copy.node_labels[4]);
  assert_string_equal(copy.crs, "EPSG:7405");
  assert_int_equal(karst_tunnel_type_from_name("keyhole"), KARST_TUNNEL_KEYHOLE);
  assert_int_equal(karst_tunnel_type_from_name("cave"), -1);
  karst_network_destroy(&copy);
}

/* An aborted atomic write leaves nothing; a committed one leaves exactly the file. */
static void test_atomic_file(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  char dir[] = "/tmp/karst_atomic_XXXXXX";
  assert_non_null(mkdtemp(dir));
  char path[256];
  snprintf(path, sizeof path, "%s/sub/out.txt", dir);
  char sub[256];
  snprintf(sub, sizeof sub, "%s/sub", dir);
  assert_int_equal(karst_mkdir_p(&ctx, sub), 0);
  karst_atomic_file_t f;
  assert_int_equal(karst_atomic_open(&ctx, &f, path, "w"), 0);
  fputs("half", f.fp);
  karst_atomic_abort(&f);
  assert_int_not_equal(access(path, F_OK), 0);
  assert_int_equal(karst_atomic_open(&ctx, &f, path, "w"), 0);
  fputs("whole\n", f.fp);
  assert_int_equal(karst_atomic_commit(&ctx, &f), 0);
  FILE *in = fopen(path, "r");
  assert_non_null(in);
  char buf[16] = {0};
  assert_non_null(fgets(buf, sizeof buf, in));
  fclose(in);
  assert_string_equal(buf, "whole\n");
  /* nothing else is left in the directory */
  char cmd[600];
  snprintf(cmd, sizeof cmd, "test $(ls -A %s | wc -l) -eq 1", sub);
  assert_int_equal(system(cmd), 0);
  assert_int_equal(karst_atomic_open(&ctx, &f, "/nonexistent-dir/x.txt", "w"), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "/nonexistent-dir/x.txt"));
  snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
  assert_int_equal(system(cmd), 0);
}

/* Write @p text to @p path (a member's temporary). */
static void put(const char *path, const char *text) {
  FILE *fp = fopen(path, "w");
  assert_non_null(fp);
  fputs(text, fp);
  fclose(fp);
}

/* Contents of @p path ("" when it cannot be read). */
static const char *get(const char *dir, const char *name) {
  static char buf[64];
  char path[256];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  buf[0] = '\0';
  FILE *fp = fopen(path, "r");
  if (!fp) return buf;
  size_t n = fread(buf, 1, sizeof buf - 1, fp);
  buf[n] = '\0';
  fclose(fp);
  return buf;
}

/* The names in @p dir, sorted, hidden ones included, joined by spaces. */
static const char *listing(const char *dir) {
  static char buf[512];
  char cmd[300];
  snprintf(cmd, sizeof cmd, "ls -A %s | sort | tr '\\n' ' '", dir);
  FILE *p = popen(cmd, "r");
  assert_non_null(p);
  size_t n = fread(buf, 1, sizeof buf - 1, p);
  buf[n] = '\0';
  pclose(p);
  return buf;
}

/* Add a, b (and stale s when @p stale), then c, writing "<tag> a" ... to the temporaries. */
static void fill_set(karst_ctx_t *ctx, karst_fileset_t *fs, const char *dir, const char *tag,
                     int stale) {
  const char *names[] = {"a", "b", "c"};
  char path[256], text[32];
  for (int i = 0; i < 3; i++) {
    if (i == 2 && stale) {
      snprintf(path, sizeof path, "%s/s", dir);
      assert_int_equal(karst_fileset_add_stale(ctx, fs, path), 0);
    }
    const char *tmp = NULL;
    snprintf(path, sizeof path, "%s/%s", dir, names[i]);
    assert_int_equal(karst_fileset_add(ctx, fs, path, NULL, &tmp), 0);
    snprintf(text, sizeof text, "%s %s", tag, names[i]);
    put(tmp, text);
  }
}

/* A file set is committed whole or not at all: a failure on its last member (c is a non-empty
 * directory, which rename cannot replace) leaves none of a new set in an empty directory and puts
 * back the previous versions of a set it was replacing; a commit replaces a, b and c and removes
 * the stale s; an abort leaves nothing. */
static void test_fileset(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  char dir[] = "/tmp/karst_fileset_XXXXXX";
  assert_non_null(mkdtemp(dir));
  char path[256], cmd[600];
  karst_fileset_t fs;

  /* Empty set: commit and abort do nothing. */
  karst_fileset_init(&fs);
  assert_int_equal(karst_fileset_commit(&ctx, &fs), 0);
  karst_fileset_abort(&fs);
  assert_string_equal(listing(dir), "");

  /* Abort: the temporaries go, nothing else appears. */
  karst_fileset_init(&fs);
  fill_set(&ctx, &fs, dir, "new", 0);
  assert_int_equal(fs.n, 3);
  karst_fileset_abort(&fs);
  assert_string_equal(listing(dir), "");

  /* Failure on the last member in an empty directory: none of a, b. */
  snprintf(path, sizeof path, "%s/c/x", dir);
  assert_int_equal(karst_mkdir_p(&ctx, path), 0);
  karst_fileset_init(&fs);
  fill_set(&ctx, &fs, dir, "new", 0);
  assert_int_equal(karst_fileset_commit(&ctx, &fs), KARST_EIO);
  snprintf(path, sizeof path, "%s/c: cannot rename into place", dir);
  assert_non_null(strstr(ctx.errmsg, path));
  assert_string_equal(listing(dir), "c ");
  assert_int_equal(fs.n, 0);

  /* Failure over a previous set: a and b get their old contents back, s stays. */
  snprintf(path, sizeof path, "%s/a", dir), put(path, "old a");
  snprintf(path, sizeof path, "%s/b", dir), put(path, "old b");
  snprintf(path, sizeof path, "%s/s", dir), put(path, "old s");
  karst_fileset_init(&fs);
  fill_set(&ctx, &fs, dir, "new", 1);
  assert_int_equal(karst_fileset_commit(&ctx, &fs), KARST_EIO);
  assert_string_equal(listing(dir), "a b c s ");
  assert_string_equal(get(dir, "a"), "old a");
  assert_string_equal(get(dir, "b"), "old b");
  assert_string_equal(get(dir, "s"), "old s");

  /* Success over a previous set: the new a, b, c; s removed; no temporary or backup left. */
  snprintf(cmd, sizeof cmd, "rm -r %s/c && printf 'old c' > %s/c", dir, dir);
  assert_int_equal(system(cmd), 0);
  karst_fileset_init(&fs);
  fill_set(&ctx, &fs, dir, "new", 1);
  assert_int_equal(karst_fileset_commit(&ctx, &fs), 0);
  assert_string_equal(listing(dir), "a b c ");
  assert_string_equal(get(dir, "a"), "new a");
  assert_string_equal(get(dir, "b"), "new b");
  assert_string_equal(get(dir, "c"), "new c");

  /* A member whose temporary was never written: an error naming it, nothing replaced. */
  karst_fileset_init(&fs);
  fill_set(&ctx, &fs, dir, "third", 0);
  snprintf(path, sizeof path, "%s/d", dir);
  assert_int_equal(karst_fileset_add(&ctx, &fs, path, NULL, NULL), 0);
  assert_int_equal(karst_fileset_commit(&ctx, &fs), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "/d: its temporary"));
  assert_string_equal(listing(dir), "a b c ");
  assert_string_equal(get(dir, "a"), "new a");

  snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
  assert_int_equal(system(cmd), 0);
}

static uint64_t double_bits(double x) {
  uint64_t u;
  memcpy(&u, &x, sizeof u);
  return u;
}

/* karst_i_fmin / karst_i_fmax against libm's fmin / fmax, bit for bit (src/core/math_internal.h):
 * every pair of special values (signed zeros, infinities, quiet NaNs of both signs, the smallest
 * subnormals, the largest finite value), then 2 million random bit patterns, a third of them a
 * value against itself or its negation (ties of equal magnitude). Signalling NaNs are left out
 * (libm quiets them); for two NaNs both must give a NaN. */
static void test_fminmax(void **state) {
  (void)state;
  const double special[] = {0.0,  -0.0,   1.0,     -1.0,    INFINITY, -INFINITY, NAN,
                            -NAN, 5e-324, -5e-324, DBL_MAX, -DBL_MAX, 3.5};
  const int ns = (int)(sizeof special / sizeof special[0]);
  for (int i = 0; i < ns; i++)
    for (int j = 0; j < ns; j++) {
      volatile double a = special[i], b = special[j];
      if (isnan(a) && isnan(b)) {
        assert_true(isnan(karst_i_fmin(a, b)) && isnan(karst_i_fmax(a, b)));
        continue;
      }
      assert_true(double_bits(karst_i_fmin(a, b)) == double_bits(fmin(a, b)));
      assert_true(double_bits(karst_i_fmax(a, b)) == double_bits(fmax(a, b)));
    }
  karst_rng_t rng;
  karst_rng_init(&rng, 2026, 12);
  int compared = 0;
  for (int i = 0; i < 2000000; i++) {
    uint64_t x = karst_rng_u64(&rng), y = karst_rng_u64(&rng);
    if (i % 3 == 0) y = x ^ (y & 1 ? 0x8000000000000000ull : 0);
    double a, b;
    memcpy(&a, &x, sizeof a), memcpy(&b, &y, sizeof b);
    if ((isnan(a) && !(x >> 51 & 1)) || (isnan(b) && !(y >> 51 & 1))) continue; /* signalling */
    volatile double va = a, vb = b;
    if (isnan(a) && isnan(b)) {
      assert_true(isnan(karst_i_fmin(va, vb)) && isnan(karst_i_fmax(va, vb)));
      continue;
    }
    assert_true(double_bits(karst_i_fmin(va, vb)) == double_bits(fmin(va, vb)));
    assert_true(double_bits(karst_i_fmax(va, vb)) == double_bits(fmax(va, vb)));
    compared++;
  }
  assert_true(compared > 1990000);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_error_list),  cmocka_unit_test(test_rng_streams),
      cmocka_unit_test(test_rng_moments), cmocka_unit_test(test_network_storage),
      cmocka_unit_test(test_atomic_file), cmocka_unit_test(test_fileset),
      cmocka_unit_test(test_fminmax),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
