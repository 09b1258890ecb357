/*
 * The shared colour scheme (include/karst/palette.h): category names agree with the names
 * karst writes ("*_names" field data come from the same lists), codes are contiguous, colours
 * are valid, distinct (CIE 1976 colour difference in CIELAB, computed here from the sRGB
 * definition) and visible on a white page; ramps interpolate as computed by hand.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "karst.h"
#include "karst/palette.h"
#include "test_util.h"

/** Smallest CIE76 difference between two categories of one array. Okabe & Ito's closest pair
 *  (blue #0072B2 and sky blue #56B4E9) differ by about 30; 20 is clearly distinct side by side. */
#define MIN_DELTA_E 20.0
/** Largest CIELAB lightness of a category colour: lighter ones vanish on a white page. */
#define MAX_LIGHTNESS 92.0

/* sRGB (IEC 61966-2-1) to CIELAB under D65 (CIE 15:2004). */
static void srgb_to_lab(const double rgb[3], double lab[3]) {
  double lin[3], xyz[3], f[3];
  for (int c = 0; c < 3; c++)
    lin[c] = rgb[c] <= 0.04045 ? rgb[c] / 12.92 : pow((rgb[c] + 0.055) / 1.055, 2.4);
  xyz[0] = (0.4124 * lin[0] + 0.3576 * lin[1] + 0.1805 * lin[2]) / 0.95047;
  xyz[1] = 0.2126 * lin[0] + 0.7152 * lin[1] + 0.0722 * lin[2];
  xyz[2] = (0.0193 * lin[0] + 0.1192 * lin[1] + 0.9505 * lin[2]) / 1.08883;
  for (int c = 0; c < 3; c++)
    f[c] = xyz[c] > 216.0 / 24389 ? cbrt(xyz[c]) : (24389.0 / 27 * xyz[c] + 16) / 116;
  lab[0] = 116 * f[1] - 16;
  lab[1] = 500 * (f[0] - f[1]);
  lab[2] = 200 * (f[1] - f[2]);
}

static double delta_e(const char *h1, const char *h2) {
  double a[3], b[3], la[3], lb[3];
  assert_int_equal(karst_palette_hex_rgb(h1, a), 0);
  assert_int_equal(karst_palette_hex_rgb(h2, b), 0);
  srgb_to_lab(a, la);
  srgb_to_lab(b, lb);
  return sqrt(pow(la[0] - lb[0], 2) + pow(la[1] - lb[1], 2) + pow(la[2] - lb[2], 2));
}

/* Hand values: #FFFFFF is L* = 100, black 0; #0072B2 against #56B4E9 about 30 apart. */
static void test_lab_by_hand(void **state) {
  (void)state;
  double rgb[3], lab[3];
  karst_palette_hex_rgb("#FFFFFF", rgb);
  srgb_to_lab(rgb, lab);
  assert_close(lab[0], 100, 0.05);
  assert_close(lab[1], 0, 0.05);
  karst_palette_hex_rgb("#000000", rgb);
  srgb_to_lab(rgb, lab);
  assert_close(lab[0], 0, 1e-9);
  /* #808080: linear 0.2159, L* = 116 * 0.2159^(1/3) - 16 = 53.59 */
  karst_palette_hex_rgb("#808080", rgb);
  srgb_to_lab(rgb, lab);
  assert_close(lab[0], 53.59, 0.01);
  assert_true(delta_e("#0072B2", "#56B4E9") > MIN_DELTA_E);
}

static void test_every_entry(void **state) {
  (void)state;
  int n = 0;
  const karst_palette_t *p = karst_palette_list(&n);
  assert_true(n >= 9);
  for (int i = 0; i < n; i++) {
    assert_ptr_equal(karst_palette_find(p[i].array), &p[i]);
    assert_non_null(p[i].where);
    if (p[i].kind != KARST_PALETTE_CATEGORICAL) {
      assert_int_equal(p[i].n, 0);
      continue;
    }
    assert_true(p[i].n >= 2);
    /* Codes in order: an optional -1 ("none"), then 0, 1, 2, ... */
    int first = p[i].categories[0].code;
    assert_true(first == 0 || first == -1);
    for (int k = 0; k < p[i].n; k++) {
      const karst_palette_category_t *c = &p[i].categories[k];
      double rgb[3], lab[3];
      assert_int_equal(c->code, first + k);
      assert_ptr_equal(karst_palette_category(&p[i], c->code), c);
      assert_true(c->name && c->name[0]);
      assert_int_equal(karst_palette_hex_rgb(c->hex, rgb), 0);
      srgb_to_lab(rgb, lab);
      if (!(lab[0] <= MAX_LIGHTNESS)) fail_msg("%s %s: L* = %.1f", p[i].array, c->name, lab[0]);
      for (int m = 0; m < k; m++) {
        double d = delta_e(c->hex, p[i].categories[m].hex);
        if (!(d >= MIN_DELTA_E))
          fail_msg("%s: %s and %s differ by only %.1f", p[i].array, c->name,
                   p[i].categories[m].name, d);
      }
    }
    assert_null(karst_palette_category(&p[i], first + p[i].n));
  }
  assert_null(karst_palette_find("no_such_array"));
  assert_null(karst_palette_find(NULL));
}

/* The names are those of the enums (the "*_names" field data are written from them). */
static void test_names_match_the_enums(void **state) {
  (void)state;
  const karst_palette_t *t = karst_palette_find("tunnel_type");
  assert_non_null(t);
  for (int c = 0; c < KARST_TUNNEL_TYPE_COUNT; c++)
    assert_string_equal(karst_palette_category(t, c)->name,
                        karst_tunnel_type_name((karst_tunnel_type_t)c));
  assert_int_equal(t->n, KARST_TUNNEL_TYPE_COUNT + 1); /* and -1, "no type" */
  const karst_palette_t *k = karst_palette_find("kind");
  assert_int_equal(k->n, KARST_NODE_KIND_COUNT);
  for (int c = 0; c < KARST_NODE_KIND_COUNT; c++)
    assert_string_equal(karst_palette_category(k, c)->name,
                        karst_node_kind_name((karst_node_kind_t)c));
  const karst_palette_t *s = karst_palette_find("source");
  assert_int_equal(s->n, KARST_SAMPLE_SOURCE_COUNT);
  for (int c = 0; c < KARST_SAMPLE_SOURCE_COUNT; c++)
    assert_string_equal(karst_palette_category(s, c)->name,
                        karst_sample_source_name((karst_sample_source_t)c));
  /* The report's Okabe & Ito colours of the tunnel types, unchanged. */
  assert_string_equal(karst_palette_category(t, KARST_TUNNEL_TUBE)->hex, "#0072B2");
  assert_string_equal(karst_palette_category(t, KARST_TUNNEL_CHAMBER)->hex, "#000000");
  const karst_palette_t *z = karst_palette_find("zone");
  assert_string_equal(karst_palette_category(z, 0)->name, "vadose");
  assert_string_equal(karst_palette_category(z, 1)->name, "epiphreatic");
  assert_string_equal(karst_palette_category(z, 2)->name, "phreatic");
  const karst_palette_t *b = karst_palette_find("block_type");
  assert_int_equal(b->n, 6);
  assert_string_equal(karst_palette_category(b, 5)->name, "columnar");
  assert_int_equal(karst_palette_find("generation")->kind, KARST_PALETTE_SEQUENTIAL);
}

/* Ramps: endpoints exact, midpoints linear between control points (by hand). */
static void test_ramps(void **state) {
  (void)state;
  const karst_palette_ramp_t *v = karst_palette_ramp(KARST_PALETTE_SEQUENTIAL);
  const karst_palette_ramp_t *d = karst_palette_ramp(KARST_PALETTE_DIVERGING);
  assert_string_equal(v->name, "viridis");
  assert_string_equal(d->name, "cool to warm");
  for (int r = 0; r < 2; r++) {
    const karst_palette_ramp_t *x = r ? d : v;
    assert_close(x->points[0][0], 0, 0);
    assert_close(x->points[x->n - 1][0], 1, 0);
    for (int k = 1; k < x->n; k++)
      assert_true(x->points[k][0] > x->points[k - 1][0]);
  }
  double rgb[3];
  karst_palette_ramp_eval(v, 0, rgb); /* #440154 */
  assert_close(rgb[0], 68 / 255.0, 1e-12);
  karst_palette_ramp_eval(v, 7, rgb); /* clamped to 1: #FDE725 */
  assert_close(rgb[1], 231 / 255.0, 1e-12);
  karst_palette_ramp_eval(v, 0.0625, rgb); /* halfway between #440154 and #472D7B */
  assert_close(rgb[1], (1 + 45) / 2.0 / 255.0, 1e-12);
  karst_palette_ramp_eval(d, 0.5, rgb); /* Moreland's grey (221, 221, 221) */
  assert_close(rgb[2], 221 / 255.0, 1e-12);
  karst_palette_ramp_eval(d, NAN, rgb);
  assert_close(rgb[0], 59 / 255.0, 1e-12);
}

static void test_hex_and_roles(void **state) {
  (void)state;
  double rgb[3] = {-1, -1, -1};
  assert_int_equal(karst_palette_hex_rgb("#ff8000", rgb), 0);
  assert_close(rgb[0], 1, 1e-12);
  assert_close(rgb[1], 128 / 255.0, 1e-12);
  const char *bad[] = {NULL, "", "#", "ff8000", "#ff800", "#ff80000", "#gg8000", "#ff 000"};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
    assert_int_equal(karst_palette_hex_rgb(bad[i], rgb), -1);
  assert_close(rgb[0], 1, 1e-12); /* untouched */
  for (int r = 0; r < KARST_PALETTE_ROLE_COUNT; r++)
    assert_int_equal(karst_palette_hex_rgb(karst_palette_role((karst_palette_role_t)r), rgb), 0);
  assert_true(delta_e(karst_palette_role(KARST_PALETTE_ROLE_ENSEMBLE),
                      karst_palette_role(KARST_PALETTE_ROLE_SURVEY)) > MIN_DELTA_E);
  assert_string_equal(karst_palette_role((karst_palette_role_t)99),
                      karst_palette_role(KARST_PALETTE_ROLE_NONE));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_lab_by_hand),           cmocka_unit_test(test_every_entry),
      cmocka_unit_test(test_names_match_the_enums), cmocka_unit_test(test_ramps),
      cmocka_unit_test(test_hex_and_roles),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
