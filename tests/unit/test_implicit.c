/* Implicit conduit geometry (src/implicit/): cross-sections, primitives,
 * operators, the hierarchy, the network builder. The central property is
 * that every field is 1-Lipschitz, checked numerically on random pairs near
 * and far from the surface: |f(p) - f(q)| <= |p - q| (1 + 1e-9). */
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

/* ---------------------------------------------------------------------- */
/* Sections.                                                               */
/* ---------------------------------------------------------------------- */

/* Dense polyline of a section (for independent checks). */
static int section_polyline(const karst_section_t *s, int per_piece, double (*pts)[2]) {
  int m = 0;
  for (int k = 0; k < s->n; k++) {
    const double *p0 = s->cp[2 * k], *p1 = s->cp[2 * k + 1], *p2 = s->cp[(2 * k + 2) % (2 * s->n)];
    for (int i = 0; i < per_piece; i++) {
      double t = (double)i / per_piece;
      for (int c = 0; c < 2; c++)
        pts[m][c] = (1 - t) * (1 - t) * p0[c] + 2 * t * (1 - t) * p1[c] + t * t * p2[c];
      m++;
    }
  }
  return m;
}

/* Winding number of a closed polyline around q (independent of crossing parity). */
static int winding(double (*pts)[2], int m, const double q[2]) {
  double total = 0;
  for (int i = 0; i < m; i++) {
    const double *a = pts[i], *b = pts[(i + 1) % m];
    double ax = a[0] - q[0], ay = a[1] - q[1], bx = b[0] - q[0], by = b[1] - q[1];
    total += atan2(ax * by - ay * bx, ax * bx + ay * by);
  }
  return (int)lround(total / (2 * M_PI));
}

/* The in-plane distance against brute force on a dense polyline (2000
 * points per piece: chord error below 1e-6 of the radius), and the sign
 * against the winding number of that polyline. */
static void test_section_distance_brute_force(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  enum { PER = 2000 };
  double(*pts)[2] = malloc(sizeof(double[8 * PER][2]));
  assert_non_null(pts);
  karst_rng_t r;
  karst_rng_init(&r, 5, 0);
  for (int type = 0; type < KARST_TUNNEL_TYPE_COUNT; type++) {
    karst_section_t s;
    assert_int_equal(karst_section_for_type(&ctx, type, &s), KARST_SUCCESS);
    assert_int_equal(s.n, 8);
    int m = section_polyline(&s, PER, pts);
    for (int i = 0; i < 300; i++) {
      double q[2] = {karst_rng_uniform_range(&r, -2.5, 2.5),
                     karst_rng_uniform_range(&r, -2.5, 2.5)};
      double best = INFINITY;
      for (int k = 0; k < m; k++) {
        const double *a = pts[k], *b = pts[(k + 1) % m];
        double ux = b[0] - a[0], uy = b[1] - a[1];
        double t = ((q[0] - a[0]) * ux + (q[1] - a[1]) * uy) / (ux * ux + uy * uy + 1e-300);
        t = t < 0 ? 0 : (t > 1 ? 1 : t);
        double dx = a[0] + t * ux - q[0], dy = a[1] + t * uy - q[1];
        best = fmin(best, dx * dx + dy * dy);
      }
      double d = karst_section_distance(&s, q);
      /* the polyline is inside the curve's 1e-6 neighbourhood */
      assert_close(fabs(d), sqrt(best), 1e-6);
      int w = winding(pts, m, q);
      if (fabs(d) > 1e-6) assert_int_equal(d < 0, w != 0);
    }
  }
  free(pts);
}

/* Exact (Green) areas against counting grid cells by the sign (independent):
 * a 1000 x 1000 grid over [-2.5, 2.5]² has cells of 2.5e-5, and the count error
 * is at most the cells the curve crosses (perimeter / cell side, < 4000 cells = 1e-1...
 * in practice far less); we allow 0.5 % of the area. The tube approximates the
 * unit circle by 8 quadratics within 0.4 % in radius: area within 1 % of π. */
static void test_section_area(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  for (int type = 0; type < KARST_TUNNEL_TYPE_COUNT; type++) {
    karst_section_t s;
    assert_int_equal(karst_section_for_type(&ctx, type, &s), KARST_SUCCESS);
    double area = karst_section_area(&s);
    const int n = 1000;
    double h = 5.0 / n;
    long inside = 0;
    for (int j = 0; j < n; j++)
      for (int i = 0; i < n; i++) {
        double q[2] = {-2.5 + (i + 0.5) * h, -2.5 + (j + 0.5) * h};
        inside += karst_section_distance(&s, q) < 0;
      }
    assert_rel(area, inside * h * h, 5e-3);
    assert_int_equal(karst_section_check(&ctx, &s), KARST_SUCCESS);
    if (type == KARST_TUNNEL_TUBE) assert_rel(area, M_PI, 1e-2);
  }
  /* errors */
  karst_section_t s;
  assert_int_equal(karst_section_for_type(&ctx, 42, &s), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "42"));
  memset(&s, 0, sizeof s);
  s.n = 1;
  assert_int_equal(karst_section_check(&ctx, &s), KARST_EINVAL);
  s.n = 3; /* all control points at the origin: zero area */
  assert_int_equal(karst_section_check(&ctx, &s), KARST_EINVAL);
  karst_section_t a, b, c;
  karst_section_for_type(&ctx, KARST_TUNNEL_TUBE, &a);
  karst_section_for_type(&ctx, KARST_TUNNEL_BED, &b);
  assert_int_equal(karst_section_lerp(&ctx, &a, &b, 0.5, &c), KARST_SUCCESS);
  assert_close(c.cp[3][0], 0.5 * (a.cp[3][0] + b.cp[3][0]), 1e-15);
  assert_int_equal(karst_section_lerp(&ctx, &a, &b, 1.5, &c), KARST_EINVAL);
}

/* ---------------------------------------------------------------------- */
/* Primitives: exact values by hand, and the Lipschitz property.           */
/* ---------------------------------------------------------------------- */

static void test_primitives_values(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  assert_int_equal(karst_sdf_create(&ctx, &t), KARST_SUCCESS);
  karst_int_t sp, el, sw, bx;
  double c[3] = {1, 2, 3};
  assert_int_equal(karst_sdf_sphere(&ctx, t, c, 2.0, 0, &sp), KARST_SUCCESS);
  double p[3] = {1, 2, 8}; /* 5 above the centre: 5 - 2 = 3 */
  assert_close(karst_sdf_eval_node(t, sp, p, NULL, NULL), 3.0, 1e-15);
  assert_close(karst_sdf_eval_node(t, sp, c, NULL, NULL), -2.0, 1e-15);

  /* Ellipsoid a = 4 along x, 2, 1: the bound (|D^-1 q| - 1) r_min; at the
   * centre -r_min = -1. */
  double axes[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, radii[3] = {4, 2, 1};
  double o[3] = {0, 0, 0};
  assert_int_equal(karst_sdf_ellipsoid(&ctx, t, o, (const double(*)[3])axes, radii, 6, &el),
                   KARST_SUCCESS);
  double px[3] = {0, 1.5, 0.9}; /* inside the box: sqrt(0.75² + 0.9²) - 1 */
  assert_close(karst_sdf_eval_node(t, el, px, NULL, NULL), sqrt(0.5625 + 0.81) - 1, 1e-15);
  /* beyond the box on the x axis the box clamp gives the exact distance 2 */
  double pfar[3] = {6, 0, 0};
  assert_close(karst_sdf_eval_node(t, el, pfar, NULL, NULL), 2.0, 1e-5);
  assert_close(karst_sdf_eval_node(t, el, o, NULL, NULL), -1.0, 1e-15);
  double surf[3] = {0, 0, 1}; /* on the surface */
  assert_close(karst_sdf_eval_node(t, el, surf, NULL, NULL), 0.0, 1e-15);

  /* Passage sweep along x, radius 2: the floor is the straight piece at
   * y = -0.6 r = -1.2 below the axis, so 0.5 m under it f = 0.5 exactly;
   * 0.3 m beyond the flat end cap on the axis, f = 0.3. */
  karst_section_t pass;
  karst_section_for_type(&ctx, KARST_TUNNEL_PASSAGE, &pass);
  double a[3] = {0, 0, 0}, b[3] = {10, 0, 0};
  assert_int_equal(karst_sdf_sweep(&ctx, t, a, b, &pass, 2.0, NULL, NULL, 4, &sw), KARST_SUCCESS);
  double under[3] = {5, 0.3, -1.7};
  assert_close(karst_sdf_eval_node(t, sw, under, NULL, NULL), 0.5, 1e-12);
  double beyond[3] = {10.3, 0, 0};
  assert_close(karst_sdf_eval_node(t, sw, beyond, NULL, NULL), 0.3, 1e-12);
  /* outside both the floor and the cap: Appendix B's sqrt(s² + d²) = sqrt(0.3² + 0.5²) */
  double corner[3] = {10.3, 0.3, -1.7};
  assert_close(karst_sdf_eval_node(t, sw, corner, NULL, NULL), sqrt(0.34), 1e-12);
  double mid[3] = {5, 0, 0}; /* inside: nearest wall is the floor at 1.2 */
  assert_true(karst_sdf_eval_node(t, sw, mid, NULL, NULL) < -1.0);
  int label = -5;
  karst_sdf_eval_node(t, sw, mid, &label, NULL);
  assert_int_equal(label, 4);

  /* The tube section (a circle bulging to (cos 22.5° + 1/cos 22.5°)/2 = 1.00314
   * between its joints) revolved about its diameter
   * is a ball of radius 2: 3 m from the centre inside the wedge f = 1, at the
   * centre -2 (within the circle's 0.31 % of 2 m); beyond a cutting plane the
   * plane's distance. */
  {
    karst_section_t tube;
    karst_section_for_type(&ctx, KARST_TUNNEL_TUBE, &tube);
    double o[3] = {0, 0, 0}, ax[3] = {0, 0, 1}, side[3] = {1, 0, 0}, up[3] = {0, 0, 1};
    double nn[2][3] = {{0, -1, 0}, {-1, 0, 0}}; /* the quadrant x >= 0, y >= 0 */
    karst_int_t rv;
    assert_int_equal(
        karst_sdf_revolve(&ctx, t, o, ax, side, up, &tube, 2.0, (const double(*)[3])nn, 0, &rv),
        KARST_SUCCESS);
    double p3[3] = {3 * cos(0.7) * 0.6, 3 * sin(0.7) * 0.6, 3 * 0.8};
    assert_close(karst_sdf_eval_node(t, rv, p3, NULL, NULL), 1.0, 2 * 0.00315);
    assert_close(karst_sdf_eval_node(t, rv, o, NULL, NULL), -0.0, 1e-12); /* on both planes */
    double pin[3] = {1, 1, 0}; /* the ball's surface (2 - √2 away) is nearer than the planes (1) */
    assert_close(karst_sdf_eval_node(t, rv, pin, NULL, NULL), sqrt(2.0) - 2, 2 * 0.00315);
    double pc[3] = {-0.5, 0.5, 0}; /* behind the plane x = 0 by 0.5 */
    assert_close(karst_sdf_eval_node(t, rv, pc, NULL, NULL), 0.5, 1e-12);
  }

  double lo[3] = {0, 0, 0}, hi[3] = {1, 2, 3};
  assert_int_equal(karst_sdf_box(&ctx, t, lo, hi, &bx), KARST_SUCCESS);
  double pb[3] = {2, 3, 1.5}; /* outside by (1, 1, 0): sqrt 2 */
  assert_close(karst_sdf_eval_node(t, bx, pb, NULL, NULL), sqrt(2.0), 1e-15);
  double pc[3] = {0.5, 1, 1.5}; /* inside: nearest face at 0.5 */
  assert_close(karst_sdf_eval_node(t, bx, pc, NULL, NULL), -0.5, 1e-15);

  /* errors name the value */
  karst_int_t dummy;
  assert_int_equal(karst_sdf_sphere(&ctx, t, c, -1.0, 0, &dummy), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "-1"));
  assert_int_equal(karst_sdf_sweep(&ctx, t, a, a, &pass, 1.0, NULL, NULL, 0, &dummy), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "zero length"));
  double bad_axes[3][3] = {{1, 0, 0}, {1, 0, 0}, {0, 0, 1}};
  assert_int_equal(karst_sdf_ellipsoid(&ctx, t, o, (const double(*)[3])bad_axes, radii, 0, &dummy),
                   KARST_EINVAL);
  assert_int_equal(karst_sdf_box(&ctx, t, hi, lo, &dummy), KARST_EINVAL);
  assert_int_equal(karst_sdf_union(&ctx, t, 0, NULL, &dummy), KARST_EINVAL);
  karst_int_t nokid = 12345;
  assert_int_equal(karst_sdf_union(&ctx, t, 1, &nokid, &dummy), KARST_EINVAL);
  karst_sdf_free(t);
}

/* The terrain of Appendix A: a tilted plane z = 0.5 x on a grid has λ = 0.5
 * and the field (z - 0.5 x)/sqrt(1.25) is then the exact distance to the
 * plane (hand calculation). A flat terrain is z - elevation. */
static void test_terrain(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  karst_terrain_t flat;
  memset(&flat, 0, sizeof flat);
  flat.elevation = 100;
  karst_int_t f, g, bumpy;
  assert_int_equal(karst_sdf_terrain(&ctx, t, &flat, &f), KARST_SUCCESS);
  double p[3] = {3, 4, 90};
  assert_close(karst_sdf_eval_node(t, f, p, NULL, NULL), -10.0, 1e-15);
  int label = 0;
  karst_sdf_eval_node(t, f, p, &label, NULL);
  assert_int_equal(label, KARST_SDF_NO_LABEL);

  karst_terrain_t tilt;
  memset(&tilt, 0, sizeof tilt);
  tilt.is_grid = 1;
  tilt.ncols = 5, tilt.nrows = 4, tilt.cellsize = 2, tilt.xll = 0, tilt.yll = 0;
  double z[20];
  for (int j = 0; j < 4; j++)
    for (int i = 0; i < 5; i++)
      z[j * 5 + i] = 0.5 * (2.0 * i);
  tilt.z = z;
  assert_int_equal(karst_sdf_terrain(&ctx, t, &tilt, &g), KARST_SUCCESS);
  double q[3] = {3, 3, 4}; /* h = 1.5: (4 - 1.5)/sqrt(1.25) */
  assert_close(karst_sdf_eval_node(t, g, q, NULL, NULL), 2.5 / sqrt(1.25), 1e-12);

  /* A rough grid: the Lipschitz property must hold with the λ computed here
   * even when the caller's value is too small. */
  karst_terrain_t rough = tilt;
  double zr[20];
  karst_rng_t r;
  karst_rng_init(&r, 3, 0);
  for (int i = 0; i < 20; i++)
    zr[i] = karst_rng_uniform_range(&r, -3, 3);
  rough.z = zr;
  rough.lipschitz = 0.01; /* wrong on purpose */
  assert_int_equal(karst_sdf_terrain(&ctx, t, &rough, &bumpy), KARST_SUCCESS);
  assert_lipschitz(t, bumpy, 0, 4000, "rough terrain");
  assert_lipschitz(t, g, 0, 2000, "tilted terrain");

  karst_terrain_t bad = tilt;
  double zb[20];
  memcpy(zb, z, sizeof z);
  zb[7] = NAN;
  bad.z = zb;
  karst_int_t d;
  assert_int_equal(karst_sdf_terrain(&ctx, t, &bad, &d), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "nan"));
  karst_sdf_free(t);
}

/* Every primitive and operator, including mitred sweeps of all sections,
 * is 1-Lipschitz on random pairs near and far from its surface. */
static void test_lipschitz_all(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  const int N = 3000;
  karst_int_t sp, el, bx, sweeps[KARST_TUNNEL_TYPE_COUNT], mit;
  double c[3] = {0.3, -0.2, 0.1};
  karst_sdf_sphere(&ctx, t, c, 1.5, 0, &sp);
  assert_lipschitz(t, sp, 3, N, "sphere");
  {
    /* the harness is tight: an exact distance reaches ratio ~1 on some pair */
    double box[6];
    karst_sdf_node_box(t, sp, box);
    assert_true(lipschitz_ratio(t, sp, box, 3, N, 1, NULL) > 0.99);
  }
  double axes[3][3], radii[3] = {5, 1.5, 0.4};
  double u[3] = {0.6, 0.8, 0}, v[3] = {-0.8, 0.6, 0}, w[3] = {0, 0, 1};
  memcpy(axes[0], u, sizeof u), memcpy(axes[1], v, sizeof v), memcpy(axes[2], w, sizeof w);
  karst_sdf_ellipsoid(&ctx, t, c, (const double(*)[3])axes, radii, 6, &el);
  assert_lipschitz(t, el, 3, N, "ellipsoid");
  double lo[3] = {-1, -2, -3}, hi[3] = {1, 2, 3};
  karst_sdf_box(&ctx, t, lo, hi, &bx);
  assert_lipschitz(t, bx, 3, N, "box");
  for (int ty = 0; ty < KARST_TUNNEL_TYPE_COUNT; ty++) {
    karst_section_t s;
    karst_section_for_type(&ctx, ty, &s);
    double a[3] = {-4, 1, 0.5}, b[3] = {5, -2, 2.5};
    assert_int_equal(karst_sdf_sweep(&ctx, t, a, b, &s, 1.3, NULL, NULL, ty, &sweeps[ty]),
                     KARST_SUCCESS);
    char what[64];
    snprintf(what, sizeof what, "sweep %s", karst_tunnel_type_name(ty));
    assert_lipschitz(t, sweeps[ty], 3, N, what);
  }
  /* mitred at both ends (planes tilted by 30 and 20 degrees) */
  {
    karst_section_t s;
    karst_section_for_type(&ctx, KARST_TUNNEL_KEYHOLE, &s);
    double a[3] = {0, 0, 0}, b[3] = {8, 0, 0};
    karst_sweep_end_t ends[2] = {{1, {-cos(M_PI / 6), sin(M_PI / 6), 0}},
                                 {1, {cos(M_PI / 9), 0, sin(M_PI / 9)}}};
    assert_int_equal(karst_sdf_sweep(&ctx, t, a, b, &s, 1.5, NULL, ends, 1, &mit), KARST_SUCCESS);
    assert_lipschitz(t, mit, 3, N, "mitred sweep");
    karst_sweep_end_t bad[2] = {{1, {1, 0, 0}}, {0, {0, 0, 0}}}; /* points inwards at a */
    karst_int_t d;
    assert_int_equal(karst_sdf_sweep(&ctx, t, a, b, &s, 1.5, NULL, bad, 1, &d), KARST_EINVAL);
  }
  /* revolved keyhole, axis tilted in its plane, cut to a 100° wedge */
  karst_int_t rev;
  {
    karst_section_t s;
    karst_section_for_type(&ctx, KARST_TUNNEL_KEYHOLE, &s);
    double o[3] = {1, 2, 3}, side[3] = {1, 0, 0}, up[3] = {0, 0.6, 0.8};
    double ax[3] = {cos(0.3), sin(0.3) * 0.6, sin(0.3) * 0.8};
    double nn[2][3] = {{0, -0.8, 0.6}, {0, 0, 0}};
    /* second plane: the first rotated by 100° about the axis */
    double th = 100 * M_PI / 180, k[3] = {ax[0], ax[1], ax[2]}, v[3] = {0, -0.8, 0.6}, kv[3];
    kv[0] = k[1] * v[2] - k[2] * v[1], kv[1] = k[2] * v[0] - k[0] * v[2],
    kv[2] = k[0] * v[1] - k[1] * v[0];
    double kd = (k[0] * v[0] + k[1] * v[1] + k[2] * v[2]) * (1 - cos(th));
    for (int c = 0; c < 3; c++)
      nn[1][c] = -(v[c] * cos(th) + kv[c] * sin(th) + k[c] * kd);
    assert_int_equal(
        karst_sdf_revolve(&ctx, t, o, ax, side, up, &s, 1.4, (const double(*)[3])nn, 1, &rev),
        KARST_SUCCESS);
    assert_lipschitz(t, rev, 3, N, "revolve");
    double bad_ax[3] = {0, 0.8, -0.6}; /* the plane's normal: not in the plane */
    karst_int_t d;
    assert_int_equal(
        karst_sdf_revolve(&ctx, t, o, bad_ax, side, up, &s, 1.4, (const double(*)[3])nn, 1, &d),
        KARST_EINVAL);
  }
  karst_int_t kids[4] = {sp, el, sweeps[KARST_TUNNEL_CANYON], mit};
  karst_int_t un, in, df, bl, nz, nz2;
  assert_int_equal(karst_sdf_union(&ctx, t, 4, kids, &un), KARST_SUCCESS);
  assert_lipschitz(t, un, 3, N, "union");
  assert_int_equal(karst_sdf_intersection(&ctx, t, bx, sweeps[KARST_TUNNEL_BED], &in),
                   KARST_SUCCESS);
  assert_lipschitz(t, in, 3, N, "intersection");
  assert_int_equal(karst_sdf_difference(&ctx, t, bx, sp, &df), KARST_SUCCESS);
  assert_lipschitz(t, df, 3, N, "difference");
  assert_int_equal(karst_sdf_blend(&ctx, t, sp, sweeps[KARST_TUNNEL_TUBE], 1.5, &bl),
                   KARST_SUCCESS);
  assert_lipschitz(t, bl, 3, N, "blend");
  karst_rng_t r;
  karst_rng_init(&r, 11, 0);
  assert_int_equal(karst_sdf_noise(&ctx, t, un, 0.5, 1.0, &r, &nz), KARST_SUCCESS);
  assert_lipschitz(t, nz, 3, 2 * N, "noise");
  /* short wavelength, large amplitude: the rescaling must still hold */
  assert_int_equal(karst_sdf_noise(&ctx, t, sp, 2.0, 0.3, &r, &nz2), KARST_SUCCESS);
  assert_lipschitz(t, nz2, 1, 2 * N, "strong noise");
  karst_int_t d;
  assert_int_equal(karst_sdf_blend(&ctx, t, sp, el, 0, &d), KARST_EINVAL);
  assert_int_equal(karst_sdf_noise(&ctx, t, sp, -1, 1, &r, &d), KARST_EINVAL);
  karst_sdf_stats_t st;
  karst_sdf_stats(t, &st);
  assert_int_equal(st.n_nodes, t->n_nodes);
  assert_int_equal(st.by_kind[KARST_SDF_SWEEP], KARST_TUNNEL_TYPE_COUNT + 1);
  assert_int_equal(st.by_kind[KARST_SDF_REVOLVE], 1);
  assert_true(st.memory_bytes > 0);
  karst_sdf_free(t);
}

/* Negative control: the naive ellipsoid field (|D^-1 q| - 1) r_max is NOT a
 * distance bound, and the test above would catch it (this is what the
 * min-radius scaling avoids). */
static void test_naive_ellipsoid_fails(void **state) {
  (void)state;
  double r[3] = {5, 1.5, 0.4};
  /* two points on the short axis: |Δf| = (0.8/0.4 - 0.6/0.4) * 5 = 2.5 over 0.2 m */
  double f1 = (0.8 / r[2] - 1) * r[0], f2 = (0.6 / r[2] - 1) * r[0];
  assert_true(fabs(f1 - f2) / 0.2 > 1 + LIP_TOL);
  double g1 = (0.8 / r[2] - 1) * r[2], g2 = (0.6 / r[2] - 1) * r[2];
  assert_true(fabs(g1 - g2) / 0.2 <= 1 + LIP_TOL);
}

/* The hierarchy returns exactly the brute-force minimum (spheres are not
 * changed by the box clamp: the box distance never exceeds the sphere's) and
 * touches few nodes: 1000 spheres on a line, at most 2 log2(1000/4) + 8 = 24
 * hierarchy nodes near one of them. */
static void test_bvh(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  enum { N = 1000 };
  karst_int_t ids[N], un;
  double cen[N][3];
  karst_rng_t r;
  karst_rng_init(&r, 8, 0);
  for (int i = 0; i < N; i++) {
    cen[i][0] = 3.0 * i;
    cen[i][1] = karst_rng_uniform_range(&r, -1, 1);
    cen[i][2] = karst_rng_uniform_range(&r, -1, 1);
    assert_int_equal(karst_sdf_sphere(&ctx, t, cen[i], 1.0, i % 7, &ids[i]), KARST_SUCCESS);
  }
  assert_int_equal(karst_sdf_union(&ctx, t, N, ids, &un), KARST_SUCCESS);
  karst_int_t max_touched = 0;
  for (int k = 0; k < 2000; k++) {
    double p[3] = {karst_rng_uniform_range(&r, -10, 3.0 * N + 10),
                   karst_rng_uniform_range(&r, -5, 5), karst_rng_uniform_range(&r, -5, 5)};
    double brute = INFINITY;
    int blab = -1;
    for (int i = 0; i < N; i++) {
      double d =
          sqrt((p[0] - cen[i][0]) * (p[0] - cen[i][0]) + (p[1] - cen[i][1]) * (p[1] - cen[i][1]) +
               (p[2] - cen[i][2]) * (p[2] - cen[i][2])) -
          1.0;
      if (d < brute) brute = d, blab = i % 7;
    }
    karst_int_t touched = 0;
    int lab;
    double v = karst_sdf_eval_node(t, un, p, &lab, &touched);
    assert_close(v, brute, 1e-12);
    assert_int_equal(lab, blab);
    if (touched > max_touched) max_touched = touched;
  }
  karst_sdf_stats_t st;
  karst_sdf_stats(t, &st);
  printf("bvh: %lld hierarchy nodes over %d spheres, at most %lld touched per evaluation\n",
         (long long)st.n_bvh_nodes, N, (long long)max_touched);
  assert_true(max_touched <= 24);
  assert_true(st.n_bvh_nodes >= N / 4);
  karst_sdf_free(t);
}

/* ---------------------------------------------------------------------- */
/* The network builder.                                                    */
/* ---------------------------------------------------------------------- */

static void add_edge(karst_network_t *net, const double a[3], const double b[3]) {
  karst_int_t u, v;
  karst_network_add_node(net, a[0], a[1], a[2], &u);
  karst_network_add_node(net, b[0], b[1], b[2], &v);
  karst_network_add_edge(net, u, v, NULL);
}

static void test_build_errors_and_empty(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t net;
  karst_network_init(&net);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  /* empty network, no terrain: nothing to build */
  assert_int_equal(karst_implicit_build(&ctx, &net, NULL, NULL, t, NULL), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "nothing to build"));
  assert_int_equal(karst_sdf_root(t), -1);
  /* a single point: same */
  karst_network_add_node(&net, 1, 2, 3, NULL);
  assert_int_equal(karst_implicit_build(&ctx, &net, NULL, NULL, t, NULL), KARST_EINVAL);
  /* with a terrain: the terrain alone */
  karst_terrain_t flat;
  memset(&flat, 0, sizeof flat);
  flat.elevation = 10;
  assert_int_equal(karst_implicit_build(&ctx, &net, NULL, &flat, t, NULL), KARST_SUCCESS);
  double p[3] = {0, 0, 4};
  assert_close(karst_sdf_eval(t, p, NULL), -6.0, 1e-15);
  karst_sdf_free(t);

  /* a zero-length edge is skipped; a bad radius or tunnel type is an error
   * naming the edge and value, and leaves the tree empty */
  karst_sdf_create(&ctx, &t);
  karst_network_add_edge(&net, 0, 0, NULL);
  double a[3] = {0, 0, 0}, b[3] = {10, 0, 0};
  add_edge(&net, a, b);
  karst_implicit_stats_t st;
  assert_int_equal(karst_implicit_build(&ctx, &net, NULL, NULL, t, &st), KARST_SUCCESS);
  assert_int_equal(st.n_skipped_edges, 1);
  assert_int_equal(st.n_sweeps, 1);
  karst_sdf_free(t);
  double *rad, *typ;
  karst_network_attr_add(&net, KARST_ATTR_EDGE, "radius", 1, 0, &rad);
  karst_network_attr_add(&net, KARST_ATTR_EDGE, "tunnel_type", 1, 1, &typ);
  rad[0] = 1, rad[1] = -2;
  karst_sdf_create(&ctx, &t);
  assert_int_equal(karst_implicit_build(&ctx, &net, NULL, NULL, t, NULL), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "edge 1 has radius -2"));
  assert_int_equal(t->n_nodes, 0);
  rad[1] = 1;
  typ[1] = 9;
  assert_int_equal(karst_implicit_build(&ctx, &net, NULL, NULL, t, NULL), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "tunnel_type 9"));
  typ[1] = 0;
  karst_implicit_params_t par;
  karst_implicit_params_init(&par);
  par.sphere_radius = 0;
  assert_int_equal(karst_implicit_build(&ctx, &net, &par, NULL, t, NULL), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "sphere_radius"));
  karst_sdf_free(t);
  karst_network_destroy(&net);
}

/* A network with every kind of joint, two components, a chamber and noise,
 * carved from a terrain: checks what was built, where the caves are, and
 * the Lipschitz property of the whole tree. */
static void test_build_network(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t net;
  karst_network_init(&net);
  /* path 0-1-2-3: a gentle 30° joint at 1, a sharp 90° joint at 2 */
  double P[][3] = {
      {0, 0, 0}, {20, 0, 0}, {20 + 20 * cos(M_PI / 6), 20 * sin(M_PI / 6), 0}, {0, 0, 0}};
  P[3][0] = P[2][0] - 20 * sin(M_PI / 6), P[3][1] = P[2][1] + 20 * cos(M_PI / 6), P[3][2] = 0;
  for (int i = 0; i < 4; i++)
    karst_network_add_node(&net, P[i][0], P[i][1], P[i][2], NULL);
  karst_network_add_edge(&net, 0, 1, NULL);
  karst_network_add_edge(&net, 2, 1, NULL); /* stored backwards on purpose */
  karst_network_add_edge(&net, 2, 3, NULL);
  /* a junction of three edges at node 4, disconnected from the path */
  karst_int_t j, e1, e2, e3;
  karst_network_add_node(&net, 0, 60, 0, &j);
  karst_network_add_node(&net, 15, 60, 0, &e1);
  karst_network_add_node(&net, -10, 70, 0, &e2);
  karst_network_add_node(&net, 0, 60, -12, &e3);
  karst_network_add_edge(&net, j, e1, NULL);
  karst_network_add_edge(&net, j, e2, NULL);
  karst_network_add_edge(&net, j, e3, NULL);
  /* a chamber */
  karst_int_t c0, c1;
  karst_network_add_node(&net, 40, 60, 0, &c0);
  karst_network_add_node(&net, 60, 60, 0, &c1);
  karst_network_add_edge(&net, c0, c1, NULL);
  double *rad, *typ;
  karst_network_attr_add(&net, KARST_ATTR_EDGE, "radius", 1, 0, &rad);
  karst_network_attr_add(&net, KARST_ATTR_EDGE, "tunnel_type", 1, 1, &typ);
  const int types[7] = {KARST_TUNNEL_TUBE,   KARST_TUNNEL_KEYHOLE, KARST_TUNNEL_PASSAGE,
                        KARST_TUNNEL_CANYON, KARST_TUNNEL_BED,     KARST_TUNNEL_EPIKARST,
                        KARST_TUNNEL_CHAMBER};
  for (int e = 0; e < 7; e++)
    rad[e] = 1.5, typ[e] = types[e];
  rad[6] = 5;
  karst_implicit_params_t par;
  karst_implicit_params_init(&par);
  for (int mode = 0; mode < 2; mode++) {
    par.bend_spheres = mode;
    karst_sdf_t *t;
    karst_sdf_create(&ctx, &t);
    karst_implicit_stats_t st;
    assert_int_equal(karst_implicit_build(&ctx, &net, &par, NULL, t, &st), KARST_SUCCESS);
    printf("built: %lld sweeps, %lld mitred ends, %lld ellipsoids, %lld balls, %lld spheres at "
           "%lld bends\n",
           (long long)st.n_sweeps, (long long)st.n_mitred_ends, (long long)st.n_ellipsoids,
           (long long)st.n_joint_balls, (long long)st.n_spheres, (long long)st.n_bends);
    assert_int_equal(st.n_sweeps, 6);
    assert_int_equal(st.n_ellipsoids, 1);
    assert_int_equal(st.n_mitred_ends, 2); /* the 30° joint */
    assert_int_equal(st.n_bends, 1);       /* the 90° joint */
    if (mode == 0) {
      /* the two sections revolved about the bend axis */
      assert_int_equal(st.n_revolves, 2);
      assert_int_equal(st.n_spheres, 0);
      assert_int_equal(st.n_joint_balls, 1); /* the junction */
    } else {
      assert_true(st.n_spheres > 50);
      assert_int_equal(st.n_joint_balls, 2); /* the junction and the sharp bend */
    }
    /* Inside / outside by construction. The outer corner of the sharp bend at
     * node 2, 1 m out along the outer bisector, lies in the rotated section
     * (radius 1.5) but outside both flat-capped sweeps: the spheres fill it. */
    double t1[3] = {cos(M_PI / 6), sin(M_PI / 6), 0}, t2[3] = {-sin(M_PI / 6), cos(M_PI / 6), 0};
    double outer[3] = {t1[0] - t2[0], t1[1] - t2[1], 0};
    double on = hypot(outer[0], outer[1]);
    double q[3] = {P[2][0] + 0.9 * outer[0] / on, P[2][1] + 0.9 * outer[1] / on, 0};
    int label = -9;
    assert_true(karst_sdf_eval(t, q, &label) < 0);
    assert_true(label == KARST_TUNNEL_KEYHOLE || label == KARST_TUNNEL_PASSAGE);
    /* ... and does not bulge: at the axis height the sections reach 1.08 m
     * (keyhole) and 1.5 m (passage) out, the spheres at most R/2 = 0.19 m more,
     * the sweeps' caps nothing: 1.8 m out is outside. The revolved passage
     * reaches exactly 1.5 m: 1.6 m out is at 0.1 m. */
    if (mode == 0) {
      double q3[3] = {P[2][0] + 1.6 * outer[0] / on, P[2][1] + 1.6 * outer[1] / on, 0};
      assert_close(karst_sdf_eval(t, q3, NULL), 0.1, 1e-9);
    }
    double q2[3] = {P[2][0] + 1.8 * outer[0] / on, P[2][1] + 1.8 * outer[1] / on, 0};
    assert_true(karst_sdf_eval(t, q2, NULL) > 0);
    double mid[3] = {10, 0, 0};
    assert_true(karst_sdf_eval(t, mid, &label) < -1.0);
    assert_int_equal(label, KARST_TUNNEL_TUBE);
    double ch[3] = {50, 60, 0};
    assert_true(karst_sdf_eval(t, ch, &label) < -2.0);
    assert_int_equal(label, KARST_TUNNEL_CHAMBER);
    double far[3] = {10, 30, 0};
    assert_true(karst_sdf_eval(t, far, NULL) > 5.0);
    assert_lipschitz(t, karst_sdf_root(t), 3, 4000, "network conduits");
    karst_sdf_free(t);
  }
  karst_sdf_t *t;
  double mid[3] = {10, 0, 0};

  /* with noise and carved from a terrain at z = 3 (default bends) */
  karst_terrain_t flat;
  memset(&flat, 0, sizeof flat);
  flat.elevation = 3;
  par.noise_amplitude = 0.3;
  par.bend_spheres = 0;
  karst_sdf_create(&ctx, &t);
  assert_int_equal(karst_implicit_build(&ctx, &net, &par, &flat, t, NULL), KARST_SUCCESS);
  assert_true(karst_sdf_eval(t, mid, NULL) > 0); /* in the cave: outside the rock */
  double rock[3] = {10, 30, -5};
  assert_true(karst_sdf_eval(t, rock, NULL) < 0); /* in the rock */
  double air[3] = {10, 30, 8};
  assert_true(karst_sdf_eval(t, air, NULL) > 0);
  assert_lipschitz(t, karst_sdf_root(t), 3, 4000, "carved noisy network");
  karst_sdf_free(t);
  karst_network_destroy(&net);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_section_distance_brute_force),
      cmocka_unit_test(test_section_area),
      cmocka_unit_test(test_primitives_values),
      cmocka_unit_test(test_terrain),
      cmocka_unit_test(test_lipschitz_all),
      cmocka_unit_test(test_naive_ellipsoid_fails),
      cmocka_unit_test(test_bvh),
      cmocka_unit_test(test_build_errors_and_empty),
      cmocka_unit_test(test_build_network),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
