/*
 * Comparison statistics against hand-computed values, the published ranges
 * against Python's csv module, and the three output formats.
 */
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

#include "karst.h"
#include "test_util.h"

/* Quantiles of 1..10, type 7 (by hand: h = 9p; R's quantile(1:10, c(.05, .95)) prints the
 * same 1.45 and 9.55). */
static void test_quantile_type7(void **state) {
  (void)state;
  double x[10] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  assert_close(karst_compare_quantile(x, 10, 0.05), 1.45, 1e-12);
  assert_close(karst_compare_quantile(x, 10, 0.95), 9.55, 1e-12);
  assert_close(karst_compare_quantile(x, 10, 0.5), 5.5, 1e-12);
  assert_close(karst_compare_quantile(x, 10, 0), 1, 0);
  assert_close(karst_compare_quantile(x, 10, 1), 10, 0);
  /* One value: every quantile is that value. */
  assert_close(karst_compare_quantile(x + 3, 1, 0.05), 4, 0);
  assert_true(isnan(karst_compare_quantile(x, 0, 0.5)));
  /* Two values 3, 7: h = p, q = 3 + 4p. */
  double y[2] = {3, 7};
  assert_close(karst_compare_quantile(y, 2, 0.05), 3.2, 1e-12);
  assert_close(karst_compare_quantile(y, 2, 0.95), 6.8, 1e-12);
}

/* Percentile = 100 × #{x ≤ v} / n, by counting. */
static void test_percentile(void **state) {
  (void)state;
  double x[10] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  assert_close(karst_compare_percentile(x, 10, 5), 50, 0);
  assert_close(karst_compare_percentile(x, 10, 5.5), 50, 0);
  assert_close(karst_compare_percentile(x, 10, 0.5), 0, 0);
  assert_close(karst_compare_percentile(x, 10, 10), 100, 0);
  assert_close(karst_compare_percentile(x, 10, 1e9), 100, 0);
  double t[4] = {1, 2, 2, 3}; /* ties count as at or below: 3 of 4 */
  assert_close(karst_compare_percentile(t, 4, 2), 75, 0);
  assert_true(isnan(karst_compare_percentile(x, 0, 1)));
  assert_true(isnan(karst_compare_percentile(x, 10, NAN)));
}

static void test_stats(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_compare_stats_t s;
  /* 1..10 shuffled, with a NAN that must be skipped: mean 5.5, sd = sqrt(82.5 / 9). */
  double x[11] = {7, 3, NAN, 10, 1, 9, 2, 8, 4, 6, 5};
  assert_int_equal(karst_compare_stats(&ctx, x, 11, 1, &s), KARST_SUCCESS);
  assert_int_equal(s.n, 10);
  assert_close(s.mean, 5.5, 1e-12);
  assert_close(s.sd, sqrt(82.5 / 9.0), 1e-12);
  assert_close(s.p05, 1.45, 1e-12);
  assert_close(s.p95, 9.55, 1e-12);
  assert_close(s.min, 1, 0);
  assert_close(s.max, 10, 0);
  /* A column of a row-major table (stride 2): {3, 1, 2}: mean 2, sd 1, p05 = 1.1, p95 = 2.9. */
  double t[6] = {3, -100, 1, -100, 2, -100};
  assert_int_equal(karst_compare_stats(&ctx, t, 3, 2, &s), KARST_SUCCESS);
  assert_int_equal(s.n, 3);
  assert_close(s.mean, 2, 1e-12);
  assert_close(s.sd, 1, 1e-12);
  assert_close(s.p05, 1.1, 1e-12);
  assert_close(s.p95, 2.9, 1e-12);
  /* One value: sd undefined. */
  assert_int_equal(karst_compare_stats(&ctx, t, 1, 1, &s), KARST_SUCCESS);
  assert_int_equal(s.n, 1);
  assert_close(s.mean, 3, 0);
  assert_true(isnan(s.sd));
  assert_close(s.p05, 3, 0);
  /* Nothing defined. */
  double u[2] = {NAN, NAN};
  assert_int_equal(karst_compare_stats(&ctx, u, 2, 1, &s), KARST_SUCCESS);
  assert_int_equal(s.n, 0);
  assert_true(isnan(s.mean) && isnan(s.p05) && isnan(s.max));
  assert_int_equal(karst_compare_stats(&ctx, u, 0, 1, &s), KARST_SUCCESS);
  assert_int_equal(s.n, 0);
  /* Large offset: the two-pass variance keeps the digits (one-pass would lose them). */
  double big[3] = {1e9 + 1, 1e9 + 2, 1e9 + 3};
  assert_int_equal(karst_compare_stats(&ctx, big, 3, 1, &s), KARST_SUCCESS);
  assert_close(s.sd, 1, 1e-9);
}

/* The shipped table: 34 Collon et al. rows; ranges computed independently with Python's csv
 * module over the rows whose source starts with "Collon" (empty cells skipped). */
static void test_published_ranges(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_published_t p;
  karst_published_init(&p);
  assert_int_equal(
      karst_published_read(&ctx, KARST_SOURCE_DIR "/datasets/published_metrics.csv", &p),
      KARST_SUCCESS);
  assert_int_equal(p.n_caves, 34);
  const karst_published_range_t *r = karst_published_find(&p, "orientation_entropy");
  assert_non_null(r);
  assert_int_equal(r->n, 31);
  assert_close(r->min, 0.7457353974, 0);
  assert_close(r->max, 0.9969936972, 0);
  r = karst_published_find(&p, "total_length"); /* L_km × 1000 */
  assert_int_equal(r->n, 34);
  assert_close(r->min, 600, 1e-9);
  assert_close(r->max, 329000, 1e-9);
  r = karst_published_find(&p, "cycles");
  assert_close(r->min, 0, 0);
  assert_close(r->max, 779, 0);
  r = karst_published_find(&p, "cpd");
  assert_close(r->max, 0.5717169483, 0);
  r = karst_published_find(&p, "tortuosity");
  assert_int_equal(r->n, 31);
  assert_close(r->min, 1.121286816, 0);
  assert_null(karst_published_find(&p, "no_such_metric"));
  karst_published_destroy(&p);
}

static void write_text(const char *path, const char *text) {
  FILE *fp = fopen(path, "w");
  assert_non_null(fp);
  fputs(text, fp);
  fclose(fp);
}

static void test_published_errors(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_published_t p;
  karst_published_init(&p);
  char path[] = "/tmp/karst_test_published_XXXXXX";
  int fd = mkstemp(path);
  assert_true(fd >= 0);
  close(fd);
  const char *hdr = "cave,L_km,dZ_m,n_stations,s_shots,H_orient,mean_branch_len_m,H_len,CV_len,"
                    "tortuosity,N_reduced,S_reduced,p_components,N_cycles,howard_alpha,"
                    "howard_beta,howard_gamma,mean_degree_k,CV_degree,r_k_assortativity,ASPL,"
                    "CPD,source\n";
  char text[2048];
  snprintf(text, sizeof text,
           "# comment\n%s\"Open,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,"
           "19,20,21,Collon\n",
           hdr);
  write_text(path, text);
  assert_int_equal(karst_published_read(&ctx, path, &p), KARST_EPARSE);
  assert_non_null(strstr(ctx.errmsg, ":3: unterminated quoted field"));
  snprintf(text, sizeof text,
           "%s\"A, cave\",x,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20,"
           "21,Collon et al.\n",
           hdr);
  write_text(path, text);
  assert_int_equal(karst_published_read(&ctx, path, &p), KARST_EPARSE);
  assert_non_null(strstr(ctx.errmsg, ":2: column L_km: 'x' is not a number"));
  /* A table with fewer columns (a user's own caves) gives ranges for the columns it has. */
  write_text(path, "cave,L_km,source\nA,1,Collon\n");
  assert_int_equal(karst_published_read(&ctx, path, &p), KARST_SUCCESS);
  assert_int_equal(p.n_caves, 1);
  assert_close(karst_published_find(&p, "total_length")->max, 1000, 0);
  assert_null(karst_published_find(&p, "vertical_extent"));
  /* A quoted comma and a row of another source (not counted). */
  snprintf(text, sizeof text,
           "%s\"A, cave\",1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20,21,\"Collon, P.\"\n"
           "B,9,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20,21,karstnet data\n",
           hdr);
  write_text(path, text);
  assert_int_equal(karst_published_read(&ctx, path, &p), KARST_SUCCESS);
  assert_int_equal(p.n_caves, 1);
  assert_close(karst_published_find(&p, "total_length")->max, 1000, 0);
  karst_published_destroy(&p);
  unlink(path);
}

/* One survey against a two-column table: percentile, band flag, published range. */
static void test_compare_rows_and_formats(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_ensemble_table_t t;
  char *names[2] = {strdup("aspl"), strdup("custom")};
  karst_int_t idx[10];
  uint64_t seeds[10];
  double v[20];
  for (int i = 0; i < 10; i++) {
    idx[i] = i;
    seeds[i] = 100 + (uint64_t)i;
    v[2 * i] = i + 1;            /* aspl: 1..10 */
    v[2 * i + 1] = 10 * (i + 1); /* custom: 10..100 */
  }
  t.n_rows = 10;
  t.n_cols = 2;
  t.names = names;
  t.index = idx;
  t.seed = seeds;
  t.values = v;
  karst_published_t pub;
  karst_published_init(&pub);
  assert_int_equal(
      karst_published_read(&ctx, KARST_SOURCE_DIR "/datasets/published_metrics.csv", &pub),
      KARST_SUCCESS);
  const char *sn[2] = {"custom", "aspl"};
  double sv[2] = {5, 9.6}; /* aspl 9.6 > p95 = 9.55: outside; custom 5 < p05 = 14.5: outside */
  karst_compare_result_t r[2];
  assert_int_equal(karst_compare_compute(&ctx, &t, "cave.3d", sn, sv, 2, &pub, &r[0]),
                   KARST_SUCCESS);
  assert_int_equal(r[0].n_rows, 2);
  assert_string_equal(r[0].rows[0].metric, "aspl");
  assert_close(r[0].rows[0].survey, 9.6, 0);
  assert_close(r[0].rows[0].percentile, 90, 0); /* 9 of 10 members ≤ 9.6 */
  assert_close(r[0].rows[0].ens.p95, 9.55, 1e-12);
  assert_int_equal(r[0].rows[0].outside, 1);
  assert_int_equal(r[0].rows[0].has_published, 1);
  assert_close(r[0].rows[0].published_max, 55.72220194, 0); /* ASPL column, Python csv */
  assert_close(r[0].rows[1].percentile, 0, 0);
  assert_close(r[0].rows[1].ens.p05, 14.5, 1e-12);
  assert_int_equal(r[0].rows[1].outside, 1);
  assert_int_equal(r[0].rows[1].has_published, 0);
  /* Inside the band: 5.5 within [1.45, 9.55]. */
  double sv2[2] = {50, 5.5};
  assert_int_equal(karst_compare_compute(&ctx, &t, "b,\"q\".pl", sn, sv2, 2, NULL, &r[1]),
                   KARST_SUCCESS);
  assert_int_equal(r[1].rows[0].outside, 0);
  assert_close(r[1].rows[0].percentile, 50, 0);
  assert_int_equal(r[1].rows[0].has_published, 0);

  char path[] = "/tmp/karst_test_compare_XXXXXX";
  int fd = mkstemp(path);
  assert_true(fd >= 0);
  close(fd);
  char cmd[1024];
  FILE *fp = fopen(path, "w");
  assert_int_equal(karst_compare_write(&ctx, fp, KARST_COMPARE_JSON, r, 2), KARST_SUCCESS);
  fclose(fp);
  /* Independent parse of the JSON output. */
  snprintf(
      cmd, sizeof cmd,
      "/usr/bin/python3 -c \"import json; d=json.load(open('%s')); "
      "a=d[0]['metrics']['aspl']; assert d[0]['survey']=='cave.3d' and a['outside_5_95'] "
      "and a['percentile']==90 and abs(a['p95']-9.55)<1e-12 and "
      "d[1]['metrics']['custom']['published_min'] is None and d[1]['survey']=='b,\\\"q\\\".pl'\"",
      path);
  assert_int_equal(system(cmd), 0);
  fp = fopen(path, "w");
  assert_int_equal(karst_compare_write(&ctx, fp, KARST_COMPARE_CSV, r, 2), KARST_SUCCESS);
  fclose(fp);
  snprintf(cmd, sizeof cmd,
           "/usr/bin/python3 -c \"import csv; r=list(csv.DictReader(open('%s'))); "
           "assert len(r)==4 and r[0]['metric']=='aspl' and r[0]['outside_5_95']=='1' and "
           "r[2]['survey']=='b,\\\"q\\\".pl' and r[1]['published_min']=='' and "
           "abs(float(r[0]['sd'])**2*9-82.5)<1e-9\"",
           path);
  assert_int_equal(system(cmd), 0);
  fp = fopen(path, "w");
  assert_int_equal(karst_compare_write(&ctx, fp, KARST_COMPARE_TABLE, r, 1), KARST_SUCCESS);
  fclose(fp);
  char buf[8192] = "";
  fp = fopen(path, "r");
  size_t got = fread(buf, 1, sizeof buf - 1, fp);
  buf[got] = '\0';
  fclose(fp);
  assert_non_null(strstr(buf, "survey: cave.3d"));
  assert_non_null(strstr(buf, "OUTSIDE 5-95%"));
  assert_non_null(strstr(buf, " 90.0%"));
  unlink(path);
  assert_int_equal(karst_compare_format_from_name("json"), KARST_COMPARE_JSON);
  assert_int_equal(karst_compare_format_from_name("xml"), -1);
  karst_compare_result_destroy(&r[0]);
  karst_compare_result_destroy(&r[1]);
  karst_published_destroy(&pub);
  free(names[0]);
  free(names[1]);
}

/* No survey: statistics only, nothing flagged. */
static void test_compare_without_survey(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  char *names[1] = {strdup("m")};
  karst_int_t idx[3] = {0, 1, 2};
  uint64_t seeds[3] = {1, 2, 3};
  double v[3] = {2, NAN, 4};
  karst_ensemble_table_t t = {3, 1, names, idx, seeds, v};
  karst_compare_result_t r;
  assert_int_equal(karst_compare_compute(&ctx, &t, NULL, NULL, NULL, 0, NULL, &r), KARST_SUCCESS);
  assert_null(r.label);
  assert_int_equal(r.rows[0].ens.n, 2);
  assert_close(r.rows[0].ens.mean, 3, 0);
  assert_true(isnan(r.rows[0].survey) && isnan(r.rows[0].percentile));
  assert_int_equal(r.rows[0].outside, 0);
  karst_compare_result_destroy(&r);
  free(names[0]);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_quantile_type7),
      cmocka_unit_test(test_percentile),
      cmocka_unit_test(test_stats),
      cmocka_unit_test(test_published_ranges),
      cmocka_unit_test(test_published_errors),
      cmocka_unit_test(test_compare_rows_and_formats),
      cmocka_unit_test(test_compare_without_survey),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
