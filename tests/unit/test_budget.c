/* The resource estimate of include/karst/budget.h on tests/data/scenarios/good/minimal.yaml, a
 * 100 x 100 x 50 m box with every default (fill_radius 10, feature_radius 3, feature_band 1,
 * k 40, max_samples 5e6, background permeability 1 >= permeable_threshold 0.3, no horizon),
 * one sink and one spring. Expected values by hand from the bounds the header documents:
 *   fill    = sqrt(2) (100+10)(100+10)(50+10) / 10^3            = 1026.7190462828...
 *   layers  = 0 horizons + 1 spring's water table + 1           = 2
 *   feature = 2 (slopes) x 2 layers x sqrt(2) (103)(103)(2+3) / 3^3 = 11113.623469049...
 *   samples = fill + feature + 2 key points                      = 12142.342515331...
 *   edges   = samples x 40;  searches = 2 key points x 1 spring  = 2
 *   bytes   = 96 MiB + samples (512 + 40 x 18 + 1 thread x 40
 *             + 40 x 16 routed costs x 1 spring, far below the 256 MiB cap) = 123879454.89...
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "karst.h"

#define MINIMAL KARST_SOURCE_DIR "/tests/data/scenarios/good/minimal.yaml"

static void assert_close(double got, double want) {
  if (!(fabs(got - want) <= 1e-9 * fabs(want))) {
    print_error("got %.17g, expected %.17g\n", got, want);
    fail();
  }
}

static void test_counts_of_a_box(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  assert_int_equal(karst_scenario_load(&ctx, MINIMAL, &sc), KARST_SUCCESS);
  karst_budget_t b;
  karst_budget_estimate(&sc, 1, &b);
  assert_close(b.fill_samples, 1026.7190462828670);
  assert_close(b.feature_samples, 11113.623469049011);
  assert_close(b.samples, 12142.342515331879);
  assert_close(b.edges, 12142.342515331879 * 40);
  assert_close(b.searches, 2);
  assert_close(b.amplification_points, 0);
  assert_close(b.bytes, 96.0 * 1024 * 1024 + 12142.342515331879 * (512 + 40 * 18 + 40 + 40 * 16));
  /* the edges drive it (40 x (18 + 16) bytes per sample against 512 + 40): sampling.k, which the
   * file leaves to its default (position 0, reported as 1:1) */
  assert_string_equal(b.driver, "sampling.k");
  /* 4 threads: four A* states, but only as many as there are searches (2) */
  karst_budget_estimate(&sc, 4, &b);
  assert_close(b.bytes,
               96.0 * 1024 * 1024 + 12142.342515331879 * (512 + 40 * 18 + 2 * 40 + 40 * 16));
  /* sampling.refine without the water table: one layer (the extra one) instead of two, so half
   * the feature samples, 5556.8117345245...; with no permeable rock, permeability changes
   * nothing */
  sc.sampling.refine = KARST_REFINE_HORIZONS | KARST_REFINE_PERMEABILITY;
  karst_budget_estimate(&sc, 1, &b);
  assert_close(b.feature_samples, 11113.623469049011 / 2);
  sc.sampling.refine = 0;
  karst_budget_estimate(&sc, 1, &b);
  assert_close(b.feature_samples, 11113.623469049011 / 2);
  /* rock permeable enough everywhere (background 0.1 < 0.3): the whole box at feature_radius,
   * sqrt(2) (103)(103)(53) / 27, counted only when refine names permeability */
  sc.permeability.background = 0.1;
  karst_budget_estimate(&sc, 1, &b);
  assert_close(b.feature_samples, 11113.623469049011 / 2);
  sc.sampling.refine = KARST_REFINE_PERMEABILITY;
  karst_budget_estimate(&sc, 1, &b);
  assert_close(b.feature_samples, 11113.623469049011 / 2 + sqrt(2.0) * 103 * 103 * 53 / 27);
  sc.sampling.refine = KARST_REFINE_ALL, sc.permeability.background = 1;
  /* max_samples caps the samples (sampling refuses more) and then drives the estimate when the
   * file gives it (a key the file gives is named before a defaulted one, here sampling.k) */
  sc.sampling.max_samples = 1000;
  sc.pos_max_samples = (karst_srcpos_t){5, 3};
  karst_budget_estimate(&sc, 1, &b);
  assert_close(b.samples, 1000);
  assert_close(b.edges, 1000.0 * 40);
  assert_string_equal(b.driver, "sampling.max_samples");
  /* k beyond the samples: each sample has at most samples - 1 neighbours */
  sc.sampling.k = 5000;
  karst_budget_estimate(&sc, 1, &b);
  assert_close(b.edges, 1000.0 * 999);
  karst_scenario_destroy(&sc);
}

static void test_check_refuses(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  assert_int_equal(karst_scenario_load(&ctx, MINIMAL, &sc), KARST_SUCCESS);
  assert_int_equal(karst_budget_check(&ctx, &sc, 1, 1e12, NULL), KARST_SUCCESS);
  /* 1 MiB: refused with the file, the estimate and the limit */
  assert_int_equal(karst_budget_check(&ctx, &sc, 1, 1024.0 * 1024, NULL), KARST_ERANGE);
  assert_non_null(strstr(ctx.errmsg, MINIMAL ":1:1: sampling.k: the run needs an "
                                             "estimated 118 MiB of memory"));
  assert_non_null(strstr(ctx.errmsg, "more than the limit of 1 MiB"));
  /* a domain whose volume overflows, and more steps than any hierarchy */
  sc.domain_max[0] = sc.domain_max[1] = 1e300;
  assert_int_equal(karst_budget_check(&ctx, &sc, 1, 1e12, NULL), KARST_ERANGE);
  assert_non_null(strstr(ctx.errmsg, "needs up to inf samples"));
  sc.domain_max[0] = sc.domain_max[1] = 100;
  sc.amplification.steps = KARST_BUDGET_MAX_AMPLIFICATION_STEPS + 1;
  assert_int_equal(karst_budget_check(&ctx, &sc, 1, 1e12, NULL), KARST_ERANGE);
  assert_non_null(strstr(ctx.errmsg, "amplification.steps is 1001, more than 1000"));
  karst_scenario_destroy(&sc);
}

static void test_sizes(void **state) {
  (void)state;
  double v;
  assert_int_equal(karst_budget_parse_size("512M", &v), 0);
  assert_true(v == 512.0 * 1024 * 1024);
  assert_int_equal(karst_budget_parse_size("8G", &v), 0);
  assert_true(v == 8.0 * 1024 * 1024 * 1024);
  assert_int_equal(karst_budget_parse_size("1.5GiB", &v), 0);
  assert_true(v == 1.5 * 1024 * 1024 * 1024);
  assert_int_equal(karst_budget_parse_size("4096", &v), 0);
  assert_true(v == 4096);
  assert_int_equal(karst_budget_parse_size("", &v), -1);
  assert_int_equal(karst_budget_parse_size("0", &v), -1);
  assert_int_equal(karst_budget_parse_size("-1G", &v), -1);
  assert_int_equal(karst_budget_parse_size("8X", &v), -1);
  assert_int_equal(karst_budget_parse_size("lots", &v), -1);
  char buf[48];
  assert_string_equal(karst_budget_format_size(1024.0 * 1024, buf, sizeof buf), "1 MiB");
  assert_string_equal(karst_budget_format_size(1.5 * 1024 * 1024 * 1024, buf, sizeof buf),
                      "1.5 GiB");
  assert_true(karst_budget_machine_memory() > 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_counts_of_a_box),
      cmocka_unit_test(test_check_refuses),
      cmocka_unit_test(test_sizes),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
