/* Cross-sections along an edge (src/implicit/morph.c): mixture areas against
 * Green's theorem and against counting grid cells, a tube that turns into a
 * canyon whose cross-section area, counted in planes across the axis, varies
 * monotonically and follows the interpolated area, the ends equal to plain
 * sweeps, and every morph 1-Lipschitz on random pairs. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "implicit/implicit_internal.h"
#include "karst.h"
#include "sdf_check.h"
#include "test_util.h"

static karst_section_mix_t mix1(int type) {
  karst_section_mix_t m;
  memset(&m, 0, sizeof m);
  m.n = 1;
  karst_section_for_type(NULL, type, &m.section[0]);
  m.weight[0] = 1;
  return m;
}

static karst_section_mix_t mix2(int a, int b, double wa) {
  karst_section_mix_t m = mix1(a);
  m.n = 2;
  karst_section_for_type(NULL, b, &m.section[1]);
  m.weight[0] = wa;
  m.weight[1] = 1 - wa;
  return m;
}

/* Area by counting the cells of an n x n grid over [-2.5, 2.5]² whose centre
 * has a negative field (independent of the integration in morph.c). */
static double counted_area(const karst_section_mix_t *m, int n) {
  double h = 5.0 / n;
  long in = 0;
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) {
      double q[2] = {-2.5 + (i + 0.5) * h, -2.5 + (j + 0.5) * h};
      in += karst_section_mix_distance(m, q) < 0;
    }
  return in * h * h;
}

/* One section: Green's theorem exactly. Mixtures of every pair of built-in
 * sections at weight 1/2: the integrated area agrees with cell counting on a
 * 700² grid (cells of 7.1 mm: the count errs by at most the cells the curve
 * crosses, 0.43 % of these areas) to 0.5 %. The tube alone integrated on the
 * grid (through a two-section mixture of the tube with itself) is within
 * 0.05 % of Green's value: the accuracy of the integration. */
static void test_mix_area(void **state) {
  (void)state;
  karst_section_mix_t t = mix1(KARST_TUNNEL_TUBE);
  assert_close(karst_section_mix_area(&t), karst_section_area(&t.section[0]), 0);
  karst_section_mix_t tt = mix2(KARST_TUNNEL_TUBE, KARST_TUNNEL_TUBE, 0.3);
  double g = karst_section_area(&t.section[0]);
  printf("tube integrated on the grid: %.6f, Green %.6f\n", karst_section_mix_area(&tt), g);
  assert_rel(karst_section_mix_area(&tt), g, 5e-4);
  for (int a = 0; a < KARST_TUNNEL_CHAMBER; a++)
    for (int b = a + 1; b < KARST_TUNNEL_CHAMBER; b++) {
      karst_section_mix_t m = mix2(a, b, 0.5);
      double ia = karst_section_mix_area(&m), ca = counted_area(&m, 700);
      assert_rel(ia, ca, 5e-3);
    }
}

/* Area of the cross-section of node @p node in the plane through a + l u
 * spanned by side and up, by counting an n x n grid of half-width @p ext. */
static double cross_area(const karst_sdf_t *t, karst_int_t node, const double a[3],
                         const double u[3], const double side[3], const double up[3], double l,
                         double ext, int n) {
  double h = 2 * ext / n;
  long in = 0;
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) {
      double x = -ext + (i + 0.5) * h, y = -ext + (j + 0.5) * h, p[3];
      for (int c = 0; c < 3; c++)
        p[c] = a[c] + l * u[c] + x * side[c] + y * up[c];
      in += karst_sdf_eval_node(t, node, p, NULL, NULL) < 0;
    }
  return in * h * h;
}

/* A tube of radius 2 m turning into a canyon of radius 3 m over 12 m: the
 * cross-section area counted in 13 planes across the axis (grid of 1.67 cm)
 * never decreases (tolerance: the counting error, cells along the perimeter
 * of at most 20 m times 1.67 cm: 0.33 m²) and follows the interpolated area
 * (1 - t) A_a + t A_b, t = smoothstep(l/L), to 1 %; at the ends it is the
 * plain sweep's (the in-plane fields are equal to rounding). */
static void test_tube_to_canyon(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  karst_section_mix_t ma = mix1(KARST_TUNNEL_TUBE), mb = mix1(KARST_TUNNEL_CANYON);
  double Aa = 4 * karst_section_area(&ma.section[0]), Ab = 9 * karst_section_area(&mb.section[0]);
  double a[3] = {1, 2, 3}, b[3] = {13, 2, 3};
  karst_int_t m, pa, pb;
  assert_int_equal(karst_sdf_sweep_morph(&ctx, t, a, b, &ma, Aa, &mb, Ab, NULL, NULL, 2, &m),
                   KARST_SUCCESS);
  assert_int_equal(karst_sdf_sweep(&ctx, t, a, b, &ma.section[0], 2, NULL, NULL, 0, &pa),
                   KARST_SUCCESS);
  assert_int_equal(karst_sdf_sweep(&ctx, t, a, b, &mb.section[0], 3, NULL, NULL, 2, &pb),
                   KARST_SUCCESS);
  const karst_i_sweep_t *sw = &t->nodes[m].u.sweep;
  const karst_i_morph_t *mo = &t->morphs[sw->morph - 1];
  printf("tube -> canyon: Lipschitz factor K = %.4f\n", mo->k);
  assert_true(mo->k > 1);
  double prev = 0;
  for (int i = 0; i <= 12; i++) {
    double l = 0.05 + 11.9 * i / 12.0, s = l / 12;
    double tt = s * s * (3 - 2 * s), want = (1 - tt) * Aa + tt * Ab;
    double area = cross_area(t, m, a, sw->u, sw->side, sw->up, l, 5.0, 600);
    printf("l = %5.2f m: area %.4f m2, interpolated %.4f\n", l, area, want);
    assert_rel(area, want, 0.01);
    if (i > 0) assert_true(area >= prev - 0.33);
    prev = area;
  }
  /* ends: the in-plane field of the plain sweeps */
  karst_rng_t r;
  karst_rng_init(&r, 3, 0);
  for (int i = 0; i < 200; i++) {
    double x = karst_rng_uniform_range(&r, -5, 5), y = karst_rng_uniform_range(&r, -5, 5);
    double q2[2] = {x / 2, y / 2}, q3[2] = {x / 3, y / 3};
    assert_close(karst_i_morph_sweep_w(t, mo, 0, x, y),
                 2 * karst_section_distance(&ma.section[0], q2), 1e-12);
    assert_close(karst_i_morph_sweep_w(t, mo, 12, x, y),
                 3 * karst_section_distance(&mb.section[0], q3), 1e-12);
  }
  assert_lipschitz(t, m, 3, 4000, "tube -> canyon");
  karst_sdf_free(t);
}

/* Short, strongly changing morphs between every pair of sections, mixtures
 * of three and four, mitred ends and a revolved mixture: all 1-Lipschitz.
 * Equal ends make K = 1. */
static void test_morph_lipschitz(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  double a[3] = {0, 0, 0}, b[3] = {2.5, 1, -0.5};
  for (int x = 0; x < KARST_TUNNEL_CHAMBER; x++)
    for (int y = 0; y < KARST_TUNNEL_CHAMBER; y++) {
      if (x == y) continue;
      karst_section_mix_t ma = mix1(x), mb = mix2(x, y, 0.4);
      karst_int_t m;
      assert_int_equal(karst_sdf_sweep_morph(&ctx, t, a, b, &ma, 2.0, &mb, 6.0, NULL, NULL, x, &m),
                       KARST_SUCCESS);
      char what[64];
      snprintf(what, sizeof what, "morph %s -> %s", karst_tunnel_type_name(x),
               karst_tunnel_type_name(y));
      assert_lipschitz(t, m, 2, 1000, what);
    }
  karst_section_mix_t m3 = mix2(KARST_TUNNEL_BED, KARST_TUNNEL_KEYHOLE, 0.5), m4, m5;
  m4 = mix2(KARST_TUNNEL_CANYON, KARST_TUNNEL_PASSAGE, 0.3);
  m5 = mix2(KARST_TUNNEL_EPIKARST, KARST_TUNNEL_PASSAGE, 0.3);
  m3.n = 3;
  karst_section_for_type(NULL, KARST_TUNNEL_CANYON, &m3.section[2]);
  m3.weight[2] = 0.7;
  karst_sweep_end_t ends[2] = {{1, {-cos(0.4), sin(0.4), 0}}, {1, {0.9, 0.3, 0.2}}};
  karst_int_t m, same, rv;
  assert_int_equal(karst_sdf_sweep_morph(&ctx, t, a, b, &m3, 3.0, &m4, 1.0, NULL, ends, 3, &m),
                   KARST_SUCCESS);
  assert_lipschitz(t, m, 2, 3000, "morph of a 3-mixture to a 2-mixture (4 sections), mitred");
  assert_int_equal(karst_sdf_sweep_morph(&ctx, t, a, b, &m3, 3.0, &m3, 3.0, NULL, NULL, 3, &same),
                   KARST_SUCCESS);
  assert_close(t->morphs[t->nodes[same].u.sweep.morph - 1].k, 1, 0);
  double o[3] = {1, 1, 1}, side[3] = {1, 0, 0}, up[3] = {0, 0, 1}, ax[3] = {0, 0, 1};
  double nn[2][3] = {{0, -1, 0}, {-1, 0, 0}};
  assert_int_equal(
      karst_sdf_revolve_mix(&ctx, t, o, ax, side, up, &m5, 2.0, (const double(*)[3])nn, 1, &rv),
      KARST_SUCCESS);
  assert_lipschitz(t, rv, 2, 3000, "revolved mixture");
  /* errors */
  karst_section_mix_t bad = mix1(0);
  bad.weight[0] = 0;
  karst_int_t d;
  assert_int_equal(karst_sdf_sweep_morph(&ctx, t, a, b, &bad, 1, &m4, 1, NULL, NULL, 0, &d),
                   KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "weight 0"));
  assert_int_equal(karst_sdf_sweep_morph(&ctx, t, a, b, &m4, -1, &m4, 1, NULL, NULL, 0, &d),
                   KARST_EINVAL);
  assert_int_equal(karst_sdf_sweep_morph(&ctx, t, a, b, &m3, 1, &m5, 1, NULL, NULL, 0, &d),
                   KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "more than 4 sections"));
  assert_int_equal(karst_sdf_sweep_morph(&ctx, t, a, a, &m4, 1, &m4, 1, NULL, NULL, 0, &d),
                   KARST_EINVAL);
  karst_sdf_free(t);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_mix_area),
      cmocka_unit_test(test_tube_to_canyon),
      cmocka_unit_test(test_morph_lipschitz),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
