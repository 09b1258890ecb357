/* karst calibrate: the APMC engine (src/calibrate/abc.c) on models whose posterior is known in
 * closed form, and the parsing and checking of --vary parameters (src/calibrate/calibrate.c).
 *
 * Independent expectations: for a Gaussian model x ~ N(θ, s²) with a flat prior, ABC with the
 * distance |x − y| and tolerance ε has the posterior N(y, s²) convolved with U(−ε, ε), whose
 * mean is y and variance s² + ε²/3 (hand calculation); weights sum to 1; the tolerance of
 * Lenormand et al. 2013 never increases; no particle leaves the prior box. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "calibrate/calibrate_internal.h"
#include "karst.h"
#include "test_util.h"

#define BRANCHWORK KARST_SOURCE_DIR "/datasets/scenarios/branchwork.yaml"

/* A run of the engine on independent Gaussian components: x_k ~ N(θ_k, s_k²), distance the
 * Euclidean norm of (x − y) / s. Writes the final weighted mean and sd per component, and
 * checks the invariants at every generation. */
typedef struct toy_result {
  double mean[2], sd[2], tolerance, first_tolerance;
  int generations;
  double final_ess;
  uint64_t digest; /* FNV-1a of every proposal and weight, for the determinism check */
} toy_result_t;

static uint64_t fnv(uint64_t h, const void *p, size_t n) {
  const unsigned char *b = p;
  for (size_t i = 0; i < n; i++) {
    h ^= b[i];
    h *= 1099511628211ULL;
  }
  return h;
}

static void run_toy(int d, const double *lo, const double *hi, const double *y, const double *s,
                    karst_int_t n, karst_int_t keep, int gens, uint64_t seed, toy_result_t *res) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_i_abc_t abc;
  assert_int_equal(karst_i_abc_init(&ctx, &abc, d, lo, hi, n, keep), KARST_SUCCESS);
  double *u = malloc((size_t)n * (size_t)d * sizeof *u), *lw = malloc((size_t)n * sizeof *lw);
  double *rho = malloc((size_t)n * sizeof *rho), *w = malloc((size_t)keep * sizeof *w);
  assert_non_null(u);
  assert_non_null(lw);
  assert_non_null(rho);
  assert_non_null(w);
  memset(res, 0, sizeof *res);
  res->digest = 1469598103934665603ULL;
  double prev_tol = INFINITY;
  for (int g = 0; g <= gens; g++) {
    karst_rng_t r;
    karst_rng_init(&r, seed, (uint64_t)g);
    karst_int_t m = karst_i_abc_batch(&abc);
    assert_true(m == (g == 0 ? n : n - keep));
    assert_int_equal(karst_i_abc_propose(&ctx, &abc, &r, u, lw), KARST_SUCCESS);
    for (karst_int_t i = 0; i < m; i++) {
      double dist = 0;
      for (int k = 0; k < d; k++) {
        double th = u[i * d + k];
        /* priors respected: every proposal inside its box */
        assert_true(th >= lo[k] && th < hi[k]);
        double x = th + s[k] * karst_rng_gaussian(&r);
        dist += (x - y[k]) * (x - y[k]) / (s[k] * s[k]);
      }
      rho[i] = sqrt(dist);
      assert_true(isfinite(lw[i]));
    }
    res->digest = fnv(res->digest, u, (size_t)m * (size_t)d * sizeof *u);
    res->digest = fnv(res->digest, lw, (size_t)m * sizeof *lw);
    karst_int_t acc = 0;
    assert_int_equal(karst_i_abc_update(&ctx, &abc, u, lw, rho, &acc), KARST_SUCCESS);
    assert_true(abc.size == keep);
    /* the tolerance never increases (every kept particle is within the previous one) */
    assert_true(abc.tolerance <= prev_tol);
    for (karst_int_t j = 0; j < keep; j++)
      assert_true(abc.rho[j] <= abc.tolerance);
    if (g == 0) res->first_tolerance = abc.tolerance;
    prev_tol = abc.tolerance;
    karst_i_abc_weights(&abc, w);
    double sum = 0;
    for (karst_int_t j = 0; j < keep; j++) {
      assert_true(w[j] >= 0);
      sum += w[j];
    }
    assert_close(sum, 1.0, 1e-12); /* normalised (rounding of `keep` additions) */
  }
  karst_i_abc_weights(&abc, w);
  for (int k = 0; k < d; k++) {
    double m = 0, v = 0;
    for (karst_int_t j = 0; j < keep; j++)
      m += w[j] * abc.u[j * d + k];
    for (karst_int_t j = 0; j < keep; j++)
      v += w[j] * (abc.u[j * d + k] - m) * (abc.u[j * d + k] - m);
    res->mean[k] = m;
    res->sd[k] = sqrt(v);
  }
  res->tolerance = abc.tolerance;
  res->generations = abc.generation;
  res->final_ess = karst_i_abc_ess(&abc);
  print_message("toy %d-D: %d generations, tolerance %.4g -> %.4g, ESS %.0f, mean %.4f sd %.4f\n",
                d, res->generations, res->first_tolerance, res->tolerance, res->final_ess,
                res->mean[0], res->sd[0]);
  free(u);
  free(lw);
  free(rho);
  free(w);
  karst_i_abc_destroy(&abc);
}

/* One Gaussian parameter, y = 1.5, s = 1, flat prior on [-10, 10): after 14 generations of
 * 2000 particles the ABC posterior is N(1.5, 1 + ε²/3) up to Monte-Carlo error. With an
 * effective sample of several hundred, the standard error of the mean is about 0.05 and of the
 * sd about 0.04; the tolerances (0.15 and 0.12) are three such errors. */
static void test_gaussian_1d(void **state) {
  (void)state;
  double lo[] = {-10}, hi[] = {10}, y[] = {1.5}, s[] = {1};
  toy_result_t r;
  run_toy(1, lo, hi, y, s, 2000, 1000, 14, 42, &r);
  assert_true(r.tolerance < 0.3 && r.tolerance < r.first_tolerance);
  assert_true(r.final_ess > 300);
  assert_close(r.mean[0], 1.5, 0.15);
  assert_close(r.sd[0], sqrt(1 + r.tolerance * r.tolerance / 3), 0.12);
}

/* Two parameters on different scales (s = 0.5 and 2) and a posterior near a prior bound
 * (y2 = 1 with prior [0, 20): the posterior N(1, 4) truncated at 0, whose mean is
 * 1 + 2 λ = 2.0183 and sd 2 √(1 − λ/2 − λ²) = 1.3945 with λ = φ(−0.5)/(1 − Φ(−0.5)), the
 * truncated-normal moments). */
static void test_gaussian_2d_truncated(void **state) {
  (void)state;
  double lo[] = {-5, 0}, hi[] = {5, 20}, y[] = {0.7, 1}, s[] = {0.5, 2};
  toy_result_t r;
  run_toy(2, lo, hi, y, s, 2000, 1000, 14, 7, &r);
  assert_true(r.final_ess > 200);
  assert_close(r.mean[0], 0.7, 0.1);
  assert_close(r.sd[0], 0.5, 0.08);
  /* the uniform-kernel tolerance widens the truncated normal a little: allow 0.3 */
  assert_close(r.mean[1], 2.0183, 0.3);
  assert_close(r.sd[1], 1.3945, 0.3);
}

/* The same seed gives the same proposals and weights, bit for bit; another seed does not. */
static void test_deterministic(void **state) {
  (void)state;
  double lo[] = {-10}, hi[] = {10}, y[] = {1.5}, s[] = {1};
  toy_result_t a, b, c;
  run_toy(1, lo, hi, y, s, 200, 100, 4, 9, &a);
  run_toy(1, lo, hi, y, s, 200, 100, 4, 9, &b);
  run_toy(1, lo, hi, y, s, 200, 100, 4, 10, &c);
  assert_true(a.digest == b.digest);
  assert_true(a.digest != c.digest);
}

/* Ties in distance (a model whose distance is always 0) keep exactly N_α particles, the
 * earliest simulated first, and infinite distances are taken in. */
static void test_ties_and_infinity(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_i_abc_t abc;
  double lo[] = {0}, hi[] = {1};
  assert_int_equal(karst_i_abc_init(&ctx, &abc, 1, lo, hi, 10, 5), KARST_SUCCESS);
  double u[10], lw[10], rho[10];
  karst_rng_t r;
  karst_rng_init(&r, 1, 0);
  assert_int_equal(karst_i_abc_propose(&ctx, &abc, &r, u, lw), KARST_SUCCESS);
  for (int i = 0; i < 10; i++)
    rho[i] = i < 3 ? INFINITY : 0;
  karst_int_t acc;
  assert_int_equal(karst_i_abc_update(&ctx, &abc, u, lw, rho, &acc), KARST_SUCCESS);
  assert_true(acc == 10);
  for (int j = 0; j < 5; j++) {
    assert_true(abc.member[j] == 3 + j); /* ties by member index */
    assert_close(abc.rho[j], 0, 0);
  }
  assert_close(abc.tolerance, 0, 0);
  /* next batch: distances of 0 are not below ε = 0, so p_acc = 0 */
  assert_int_equal(karst_i_abc_propose(&ctx, &abc, &r, u, lw), KARST_SUCCESS);
  for (int i = 0; i < 5; i++)
    rho[i] = 0;
  assert_int_equal(karst_i_abc_update(&ctx, &abc, u, lw, rho, &acc), KARST_SUCCESS);
  assert_true(acc == 0);
  for (int j = 0; j < 5; j++)
    assert_int_equal(abc.born[j], 0); /* the older particles win ties */
  /* NaN is refused */
  assert_int_equal(karst_i_abc_propose(&ctx, &abc, &r, u, lw), KARST_SUCCESS);
  rho[2] = NAN;
  assert_int_equal(karst_i_abc_update(&ctx, &abc, u, lw, rho, &acc), KARST_EINVAL);
  karst_i_abc_destroy(&abc);
  /* a population must be at least 2 and smaller than N */
  assert_int_equal(karst_i_abc_init(&ctx, &abc, 1, lo, hi, 10, 10), KARST_ERANGE);
  assert_int_equal(karst_i_abc_init(&ctx, &abc, 1, lo, hi, 10, 1), KARST_ERANGE);
}

/* Weighted type-1 quantiles, by hand: values 1, 2, 3, 4 with weights 0.1, 0.2, 0.3, 0.4. */
static void test_weighted_quantile(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  double x[] = {3, 1, 4, 2}, w[] = {0.3, 0.1, 0.4, 0.2}, q;
  assert_int_equal(karst_i_weighted_quantile(&ctx, x, w, 4, 0.05, &q), KARST_SUCCESS);
  assert_close(q, 1, 0); /* cumulative 0.1 >= 0.05 */
  karst_i_weighted_quantile(&ctx, x, w, 4, 0.3, &q);
  assert_close(q, 2, 0); /* 0.1, 0.3 */
  karst_i_weighted_quantile(&ctx, x, w, 4, 0.5, &q);
  assert_close(q, 3, 0); /* 0.3 < 0.5 <= 0.6 */
  karst_i_weighted_quantile(&ctx, x, w, 4, 0.95, &q);
  assert_close(q, 4, 0);
  karst_i_weighted_quantile(&ctx, x, w, 0, 0.5, &q);
  assert_true(isnan(q));
}

/* --vary specifications: the form, then the key against the scenario parser. */
static void test_param_parse(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_calibrate_param_t p;
  assert_int_equal(karst_calibrate_param_parse(&ctx, "skeleton.gamma=0.5:3", &p), KARST_SUCCESS);
  assert_string_equal(p.key, "skeleton.gamma");
  assert_close(p.lo, 0.5, 0);
  assert_close(p.hi, 3, 0);
  assert_int_equal(p.prior, KARST_PRIOR_UNIFORM);
  assert_int_equal(karst_calibrate_param_parse(&ctx, "cost.weights=0.1:20:log", &p), KARST_SUCCESS);
  assert_int_equal(p.prior, KARST_PRIOR_LOG_UNIFORM);
  assert_int_equal(karst_calibrate_param_parse(&ctx, "fractures[0].weight=1e-2:1e2:uniform", &p),
                   KARST_SUCCESS);
  assert_close(p.lo, 0.01, 0);
  static const char *const bad[][2] = {
      {"skeleton.gamma", "needs KEY=LO:HI"},
      {"=0:1", "no key before '='"},
      {"skeleton.gamma=3:0.5", "LO must be below HI"},
      {"skeleton.gamma=1:1", "LO must be below HI"},
      {"skeleton.gamma=0:3:log", "a log-uniform prior needs LO > 0"},
      {"skeleton.gamma=a:3", "LO must be a finite number"},
      {"skeleton.gamma=0:inf", "HI must be a finite number"},
      {"skeleton.gamma=0:nan", "HI must be a finite number"},
      {"skeleton.gamma=0:3:cubic", "the prior must be 'uniform' or 'log'"},
      {"skeleton.gamma=0", "needs KEY=LO:HI"},
      {"skeleton.gamma=0:1:log:x", "the prior must be 'uniform' or 'log'"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    assert_int_not_equal(karst_calibrate_param_parse(&ctx, bad[i][0], &p), KARST_SUCCESS);
    if (!strstr(ctx.errmsg, bad[i][1]) || !strstr(ctx.errmsg, bad[i][0])) {
      print_error("'%s': message lacks \"%s\" or the spec: %s\n", bad[i][0], bad[i][1], ctx.errmsg);
      fail();
    }
  }
}

static void test_check_params(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_calibrate_param_t p[3];
  assert_int_equal(karst_calibrate_param_parse(&ctx, "skeleton.gamma=0.5:3", &p[0]), 0);
  assert_int_equal(karst_calibrate_param_parse(&ctx, "amplification.steps=0:5", &p[1]), 0);
  assert_int_equal(karst_calibrate_param_parse(&ctx, "cost.fracture=0.1:20:log", &p[2]), 0);
  assert_int_equal(karst_calibrate_check_params(&ctx, BRANCHWORK, 3, p), KARST_SUCCESS);
  assert_int_equal(p[0].is_integer, 0);
  assert_int_equal(p[1].is_integer, 1);
  assert_int_equal(p[2].is_integer, 0);
  static const char *const bad[][2] = {
      {"skeleton.gama=0.5:3", "did you mean 'gamma'?"},
      {"name=0:1", "name is not a numeric key"},
      {"cost.fracture_combine=0:1", "is not a numeric key"},
      {"amplification.steps=0.5:3", "amplification.steps is an integer key: LO and HI must be "
                                    "whole numbers"},
      {"tortuosity=0:2", "tortuosity must be within [0, 1], got 2"},
      {"skeleton.gamma=0:3", "skeleton.gamma must be > 0, got 0"},
      {"random.seed=1:5", "random.seed is not a numeric key"},
      {"random.realisations=1:5", "random.realisations is not a model parameter"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    karst_calibrate_param_t q;
    assert_int_equal(karst_calibrate_param_parse(&ctx, bad[i][0], &q), KARST_SUCCESS);
    karst_error_t err = karst_calibrate_check_params(&ctx, BRANCHWORK, 1, &q);
    if (err == KARST_SUCCESS || !strstr(ctx.errmsg, bad[i][1]) || !strstr(ctx.errmsg, bad[i][0])) {
      print_error("'%s': %d, message lacks \"%s\" or the spec: %s\n", bad[i][0], err, bad[i][1],
                  ctx.errmsg);
      fail();
    }
  }
  /* the same key twice */
  karst_calibrate_param_t two[2];
  karst_calibrate_param_parse(&ctx, "tortuosity=0:1", &two[0]);
  karst_calibrate_param_parse(&ctx, "tortuosity=0.2:0.5", &two[1]);
  assert_int_equal(karst_calibrate_check_params(&ctx, BRANCHWORK, 2, two), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "tortuosity is varied twice"));
  /* a combination of bounds that breaks a cross-field rule (feature_radius <= fill_radius):
   * each bound alone is fine, the corner (fill 5, feature 8) is not */
  karst_calibrate_param_parse(&ctx, "sampling.fill_radius=5:12", &two[0]);
  karst_calibrate_param_parse(&ctx, "sampling.feature_radius=4:8", &two[1]);
  assert_int_equal(karst_calibrate_check_params(&ctx, BRANCHWORK, 2, two), KARST_ERANGE);
  assert_non_null(strstr(ctx.errmsg, "must not exceed sampling.fill_radius"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_gaussian_1d),       cmocka_unit_test(test_gaussian_2d_truncated),
      cmocka_unit_test(test_deterministic),     cmocka_unit_test(test_ties_and_infinity),
      cmocka_unit_test(test_weighted_quantile), cmocka_unit_test(test_param_parse),
      cmocka_unit_test(test_check_params),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
