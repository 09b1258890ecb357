/*
 * The SVG module of the report: Heckbert's nice numbers and ticks checked by
 * hand, escaping, and well-formed XML checked by Python's XML parser.
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

#include "report/svg_internal.h"
#include "test_util.h"

/* Nice numbers by hand: x = f·10^e; round: f < 1.5 → 1, < 3 → 2, < 7 → 5, else 10;
 * ceiling: f ≤ 1 → 1, ≤ 2 → 2, ≤ 5 → 5, else 10. */
static void test_nice_number(void **state) {
  (void)state;
  assert_close(karst_i_nice_number(97, 0), 100, 1e-9);
  assert_close(karst_i_nice_number(97, 1), 100, 1e-9);
  assert_close(karst_i_nice_number(25, 1), 20, 1e-9);
  assert_close(karst_i_nice_number(0.25, 1), 0.2, 1e-12);
  assert_close(karst_i_nice_number(1.5, 0), 2, 1e-12);
  assert_close(karst_i_nice_number(1.4, 1), 1, 1e-12);
  assert_close(karst_i_nice_number(7, 1), 10, 1e-12);
  assert_close(karst_i_nice_number(6.9, 1), 5, 1e-12);
  assert_close(karst_i_nice_number(4.2e-7, 0), 5e-7, 1e-19);
  assert_true(isnan(karst_i_nice_number(0, 1)));
  assert_true(isnan(karst_i_nice_number(-3, 1)));
  assert_true(isnan(karst_i_nice_number(INFINITY, 1)));
}

static void expect_ticks(const karst_i_ticks_t *t, double first, double step, int count,
                         int decimals) {
  assert_close(t->first, first, 1e-12 * fmax(1, fabs(first)));
  assert_close(t->step, step, 1e-12 * step);
  assert_int_equal(t->count, count);
  assert_int_equal(t->decimals, decimals);
}

/* Loose ticks by hand: step = nice(nice(hi − lo, ceiling) / (target − 1), round),
 * first = floor(lo / step)·step, last = ceil(hi / step)·step. */
static void test_ticks(void **state) {
  (void)state;
  karst_i_ticks_t t;
  /* [0, 1]: range 1, step nice(0.25) = 0.2 → 0, 0.2, ..., 1.0 */
  assert_int_equal(karst_i_ticks_loose(0, 1, 5, &t), 0);
  expect_ticks(&t, 0, 0.2, 6, 1);
  /* [0, 97]: range 100, step nice(25) = 20 → 0, 20, ..., 100 */
  assert_int_equal(karst_i_ticks_loose(0, 97, 5, &t), 0);
  expect_ticks(&t, 0, 20, 6, 0);
  /* [-3.7, 12.2]: range nice(15.9) = 20, step 5 → -5, 0, 5, 10, 15 */
  assert_int_equal(karst_i_ticks_loose(-3.7, 12.2, 5, &t), 0);
  expect_ticks(&t, -5, 5, 5, 0);
  /* [0.00123, 0.00567]: range 0.005, step nice(0.00125) = 0.001 → 0.001 ... 0.006 */
  assert_int_equal(karst_i_ticks_loose(0.00123, 0.00567, 5, &t), 0);
  expect_ticks(&t, 0.001, 0.001, 6, 3);
  /* Reversed bounds are swapped. */
  assert_int_equal(karst_i_ticks_loose(97, 0, 5, &t), 0);
  expect_ticks(&t, 0, 20, 6, 0);
  /* Empty range 5..5 widened to [4, 6]: range 2, step 0.5 → 4, 4.5, ..., 6 */
  assert_int_equal(karst_i_ticks_loose(5, 5, 5, &t), 0);
  expect_ticks(&t, 4, 0.5, 5, 1);
  /* Empty range at 1000: widened by 10 % → [900, 1100]: range 200, step 50 */
  assert_int_equal(karst_i_ticks_loose(1000, 1000, 5, &t), 0);
  expect_ticks(&t, 900, 50, 5, 0);
  /* Inside [0.3, 9.7]: step nice(nice(9.4) / 4) = 2 → 2, 4, 6, 8 */
  assert_int_equal(karst_i_ticks_inside(0.3, 9.7, 5, &t), 0);
  expect_ticks(&t, 2, 2, 4, 0);
  /* Non-finite input and too few ticks are refused. */
  assert_int_equal(karst_i_ticks_loose(NAN, 1, 5, &t), -1);
  assert_int_equal(karst_i_ticks_loose(0, INFINITY, 5, &t), -1);
  assert_int_equal(karst_i_ticks_loose(0, 1, 1, &t), -1);
}

static void test_tick_labels(void **state) {
  (void)state;
  char s[32];
  karst_i_tick_label(s, sizeof s, -1e-17, 1); /* 0 computed as -1e-17 */
  assert_string_equal(s, "0.0");
  karst_i_tick_label(s, sizeof s, 0.6000000000000001, 1);
  assert_string_equal(s, "0.6");
  karst_i_tick_label(s, sizeof s, -5, 0);
  assert_string_equal(s, "-5");
  karst_i_tick_label(s, sizeof s, 0.003, 3);
  assert_string_equal(s, "0.003");
}

static void test_escape(void **state) {
  (void)state;
  karst_i_buf_t b;
  karst_i_buf_init(&b);
  karst_i_buf_escape(&b, "a<b & \"c\" 'd'>\x01");
  assert_string_equal(b.s, "a&lt;b &amp; &quot;c&quot; &#39;d&#39;&gt;?");
  karst_i_buf_destroy(&b);
}

/* A plot with every element, parsed by Python's XML parser; the text survives escaping. */
static void test_well_formed(void **state) {
  (void)state;
  karst_i_buf_t b;
  karst_i_buf_init(&b);
  karst_i_svg_begin(&b, 300, 200, "title with <tags> & \"quotes\"");
  karst_i_plot_t p = {50, 10, 230, 150, -3.7, 12.2, 0, 97};
  assert_int_equal(karst_i_svg_axes(&b, &p, 1, 5, 5, "x <m>", "count & more"), 0);
  /* expand widened the ranges to the ticks */
  assert_close(p.xmin, -5, 1e-12);
  assert_close(p.xmax, 15, 1e-12);
  assert_close(p.ymax, 100, 1e-12);
  assert_close(karst_i_plot_px(&p, -5), 50, 1e-12);
  assert_close(karst_i_plot_px(&p, 15), 280, 1e-12);
  assert_close(karst_i_plot_py(&p, 0), 160, 1e-12);
  assert_close(karst_i_plot_py(&p, 100), 10, 1e-12);
  karst_i_svg_rect(&b, 60, 20, 10, 30, "#4477AA", "#fff", 0.5);
  double xy[6] = {1, 2, 3, 4, 5, 6};
  karst_i_svg_polyline(&b, xy, 3, "red", 1, NULL, 0);
  karst_i_svg_polyline(&b, xy, 3, "red", 1, "blue", 1);
  karst_i_svg_marker(&b, 10, 10, 3, "red", NULL);
  karst_i_svg_line(&b, 0, 0, 5, 5, "#000", 2, "4 2");
  karst_i_svg_text(&b, 5, 5, "start", "note", "Grotte <d'Huttes> & co");
  assert_int_equal(karst_i_svg_axes(&b, &p, 1, 5, 5, NULL, NULL), 0);
  karst_i_plot_t bad = {0, 0, 10, 10, NAN, 1, 0, 1};
  assert_int_equal(karst_i_svg_axes(&b, &bad, 1, 5, 5, NULL, NULL), -1);
  karst_i_svg_end(&b);
  assert_int_equal(b.failed, 0);

  char path[] = "/tmp/karst_test_svg_XXXXXX";
  int fd = mkstemp(path);
  assert_true(fd >= 0);
  assert_int_equal(write(fd, b.s, b.len), (ssize_t)b.len);
  close(fd);
  char cmd[2048];
  snprintf(cmd, sizeof cmd,
           "/usr/bin/python3 -c \"import xml.etree.ElementTree as E; r=E.parse('%s').getroot(); "
           "ns='{http://www.w3.org/2000/svg}'; t=[e.text for e in r.iter(ns+'text')]; "
           "assert r.tag==ns+'svg'; assert 'Grotte <d\\'Huttes> & co' in t, t; "
           "assert ['-5','0','5','10','15'] == t[:5], t; "
           "assert r.find(ns+'title').text=='title with <tags> & \\\"quotes\\\"'\"",
           path);
  int rc = system(cmd);
  unlink(path);
  assert_int_equal(rc, 0);
  karst_i_buf_destroy(&b);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_nice_number), cmocka_unit_test(test_ticks),
      cmocka_unit_test(test_tick_labels), cmocka_unit_test(test_escape),
      cmocka_unit_test(test_well_formed),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
