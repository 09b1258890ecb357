/* Geological surfaces (src/geology/surface*.c) and the GOCAD TSurf reader
 * (src/io/read_tsurf.c). Where each expected value comes from is said at the
 * assertion: a plane written three ways (analytic, grid, TIN) must agree; the
 * fold's interpolation errors are bounded by the classical estimates
 * (bilinear: h^2/8 (max|f_xx| + max|f_yy|); linear on a triangle: (M/2) R^2 with
 * M the largest Hessian norm and R the circumradius) and match closed forms at
 * cell centres and diagonal midpoints; the bucket index is checked against a
 * scan of every triangle; the small files' values were computed by hand. */
#include <ctype.h>
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

#include "geology/surface_internal.h"
#include "karst.h"
#include "test_util.h"

#define DATA KARST_SOURCE_DIR "/tests/data/surfaces/"
#define PLATEAU KARST_SOURCE_DIR "/datasets/scenarios/plateau/"
#define TMP KARST_BINARY_DIR "/tests/surface_tmp"

/* Tolerance on elevations that agree in exact arithmetic (rounding is ~1e-13 m). */
#define Z_TOL 1e-9

static void write_file(const char *path, const char *text, size_t len) {
  FILE *fp = fopen(path, "wb");
  assert_non_null(fp);
  assert_int_equal(fwrite(text, 1, len, fp), len);
  fclose(fp);
}

static int setup(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  return karst_mkdir_p(&ctx, TMP) == KARST_SUCCESS ? 0 : -1;
}

/* ------------------------------------------------------------------------ */
/* Builders                                                                  */
/* ------------------------------------------------------------------------ */

typedef double (*field_fn)(double x, double y, const void *p);

/* Nodes (x0 + i h, y0 + j h) of an nx x ny lattice. */
static double *lattice_z(int nx, int ny, double x0, double y0, double h, field_fn f,
                         const void *p) {
  double *z = malloc((size_t)nx * ny * sizeof *z);
  assert_non_null(z);
  for (int j = 0; j < ny; j++)
    for (int i = 0; i < nx; i++)
      z[j * nx + i] = f(x0 + i * h, y0 + j * h, p);
  return z;
}

/* TIN of the lattice; diag 0: every cell cut from (i, j) to (i+1, j+1); 1: alternating. */
static karst_surface_t *lattice_tin(int nx, int ny, double x0, double y0, double h, field_fn f,
                                    const void *p, int alternate) {
  double *xyz = malloc((size_t)nx * ny * 3 * sizeof *xyz);
  karst_int_t *tri = malloc((size_t)(nx - 1) * (ny - 1) * 6 * sizeof *tri);
  assert_non_null(xyz);
  assert_non_null(tri);
  for (int j = 0; j < ny; j++)
    for (int i = 0; i < nx; i++) {
      double *q = xyz + 3 * (j * nx + i);
      q[0] = x0 + i * h, q[1] = y0 + j * h, q[2] = f(q[0], q[1], p);
    }
  karst_int_t m = 0;
  for (int j = 0; j + 1 < ny; j++)
    for (int i = 0; i + 1 < nx; i++) {
      karst_int_t a = j * nx + i, b = a + 1, c = a + nx, d = c + 1;
      if (!alternate || (i + j) % 2 == 0) {
        karst_int_t t[6] = {a, b, d, a, d, c};
        memcpy(tri + 3 * m, t, sizeof t);
      } else {
        karst_int_t t[6] = {a, b, c, b, d, c};
        memcpy(tri + 3 * m, t, sizeof t);
      }
      m += 2;
    }
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_surface_t *s = NULL;
  karst_error_t err = karst_surface_create_tin(&ctx, (karst_int_t)nx * ny, xyz, m, tri, &s);
  if (err) print_error("%s\n", ctx.errmsg);
  assert_int_equal(err, KARST_SUCCESS);
  free(xyz);
  free(tri);
  return s;
}

typedef struct {
  double e, dip, dipdir, ox, oy;
} plane_t;

static double plane_f(double x, double y, const void *p) {
  const plane_t *P = p;
  karst_horizon_t h = {.elevation = P->e,
                       .dip = P->dip,
                       .dip_direction = P->dipdir,
                       .origin = {P->ox, P->oy},
                       .radius = 1.0};
  return karst_horizon_elevation(&h, x, y);
}

/* ------------------------------------------------------------------------ */
/* Plane, grid and TIN of one plane                                          */
/* ------------------------------------------------------------------------ */

static void test_plane_basics(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  const plane_t P = {300, 8, 120, 1000, 750};
  karst_surface_t *s = NULL;
  assert_int_equal(
      karst_surface_create_plane(&ctx, P.e, P.dip, P.dipdir, (const double[2]){P.ox, P.oy}, &s),
      KARST_SUCCESS);
  assert_int_equal(karst_surface_kind(s), KARST_SURFACE_PLANE);
  assert_null(karst_surface_path(s));
  karst_rng_t rng;
  karst_rng_init(&rng, 11, 0);
  for (int k = 0; k < 1000; k++) {
    double x = karst_rng_uniform_range(&rng, -5000, 5000),
           y = karst_rng_uniform_range(&rng, -5000, 5000);
    /* the same operations as karst_horizon_elevation: equal to the bit */
    assert_true(karst_surface_z(s, x, y) == plane_f(x, y, &P));
  }
  /* gradient: -tan(dip) (sin a, cos a), a = 120 degrees */
  double g[2];
  karst_surface_gradient(s, 3, 4, g);
  assert_close(g[0], -tan(8 * M_PI / 180) * sin(120 * M_PI / 180), 1e-15);
  assert_close(g[1], -tan(8 * M_PI / 180) * cos(120 * M_PI / 180), 1e-15);
  assert_close(karst_surface_lipschitz(s), tan(8 * M_PI / 180), 1e-15);
  double lo[3], hi[3];
  karst_surface_bounds(s, lo, hi);
  assert_true(isinf(lo[0]) && isinf(hi[1]) && isinf(lo[2]));
  /* a plane covers anything */
  assert_int_equal(karst_surface_check_covers(&ctx, s, (const double[2]){-1e6, -1e6},
                                              (const double[2]){1e6, 1e6}, "horizon"),
                   KARST_SUCCESS);
  karst_surface_free(s);

  /* dip outside [0, 90) and non-finite values are refused */
  assert_int_equal(karst_surface_create_plane(&ctx, 0, 90, 0, (const double[2]){0, 0}, &s),
                   KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "dip must be within [0, 90) degrees, got 90"));
  assert_null(s);
  assert_int_equal(karst_surface_create_plane(&ctx, NAN, 0, 0, (const double[2]){0, 0}, &s),
                   KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "must be finite"));
  karst_surface_free(NULL);
}

/* The plane of test_plane_basics as a 20 m grid and as a TIN of the same nodes
 * over [0, 2000] x [0, 1500]: bilinear and linear interpolation reproduce a
 * plane exactly, so z, vertical distances and gradients agree to rounding
 * (Z_TOL) and the segment tests give the analytic answer: z - f is linear
 * along a segment, so its interior is below iff both ends are (ends offset by
 * at least 1 mm here, far above rounding). */
static void test_plane_three_ways(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  const plane_t P = {300, 8, 120, 1000, 750};
  karst_surface_t *sp = NULL, *sg = NULL, *st;
  assert_int_equal(
      karst_surface_create_plane(&ctx, P.e, P.dip, P.dipdir, (const double[2]){P.ox, P.oy}, &sp),
      KARST_SUCCESS);
  double *z = lattice_z(101, 76, 0, 0, 20, plane_f, &P);
  assert_int_equal(karst_surface_create_grid(&ctx, 101, 76, 0, 0, 20, z, &sg), KARST_SUCCESS);
  free(z);
  st = lattice_tin(101, 76, 0, 0, 20, plane_f, &P, 1);
  karst_surface_t *S[3] = {sp, sg, st};
  karst_rng_t rng;
  karst_rng_init(&rng, 12, 0);
  for (int k = 0; k < 20000; k++) {
    double x = karst_rng_uniform_range(&rng, 0, 2000), y = karst_rng_uniform_range(&rng, 0, 1500);
    double pz = karst_rng_uniform_range(&rng, 0, 500);
    double f = plane_f(x, y, &P);
    for (int s = 1; s < 3; s++) {
      assert_close(karst_surface_z(S[s], x, y), f, Z_TOL);
      assert_close(pz - karst_surface_z(S[s], x, y), pz - f, Z_TOL); /* vertical distance */
      double g[2], gp[2];
      karst_surface_gradient(S[s], x, y, g);
      karst_surface_gradient(sp, x, y, gp);
      assert_close(g[0], gp[0], 1e-12);
      assert_close(g[1], gp[1], 1e-12);
    }
  }
  int n_below = 0, n_above = 0;
  for (int k = 0; k < 3000; k++) {
    double a[3], b[3];
    /* a quarter of the segments are long (crossing up to ~170 grid lines) */
    double span = k % 4 == 0 ? 2000 : 100;
    a[0] = karst_rng_uniform_range(&rng, 0, 2000), a[1] = karst_rng_uniform_range(&rng, 0, 1500);
    b[0] = fmin(2000, fmax(0, a[0] + karst_rng_uniform_range(&rng, -span, span)));
    b[1] = fmin(1500, fmax(0, a[1] + karst_rng_uniform_range(&rng, -span, span)));
    double qa = karst_rng_uniform_range(&rng, 1e-3, 30) * (karst_rng_uniform(&rng) < 0.5 ? -1 : 1);
    double qb = karst_rng_uniform_range(&rng, 1e-3, 30) * (karst_rng_uniform(&rng) < 0.5 ? -1 : 1);
    a[2] = plane_f(a[0], a[1], &P) + qa;
    b[2] = plane_f(b[0], b[1], &P) + qb;
    int below = qa < 0 && qb<0, above = qa> 0 && qb > 0;
    n_below += below, n_above += above;
    for (int s = 0; s < 3; s++) {
      assert_int_equal(karst_surface_segment_below(S[s], a, b), below);
      assert_int_equal(karst_surface_segment_above(S[s], a, b), above);
    }
  }
  assert_true(n_below > 500 && n_above > 500); /* both answers were exercised */
  /* the long segments cross more piece boundaries than the segment tests look up
   * at once (128), so they were split: across the domain, 100 + 75 node lines
   * on the grid, and on the TIN those and the 100 x 75 cells' diagonals */
  double tt[1024];
  const double a0[3] = {1, 1, 0}, b0[3] = {1999, 1499, 0};
  assert_true(karst_surface_segment_pieces(sg, a0, b0, tt, 1024) > 128);
  assert_true(karst_surface_segment_pieces(st, a0, b0, tt, 1024) > 128);
  assert_int_equal(karst_surface_segment_pieces(st, a0, b0, tt, 128), -1);
  for (int s = 0; s < 3; s++)
    karst_surface_free(S[s]);
}

static double flat_f(double x, double y, const void *p) {
  (void)x, (void)y;
  return *(const double *)p;
}

/* A horizontal plane at 250 m, exactly representable three ways: a segment
 * may touch the surface at its ends but not run along it. */
static void test_segment_touching(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  const double e = 250;
  karst_surface_t *S[3] = {NULL, NULL, NULL};
  assert_int_equal(karst_surface_create_plane(&ctx, e, 0, 0, (const double[2]){0, 0}, &S[0]),
                   KARST_SUCCESS);
  double *z = lattice_z(11, 11, 0, 0, 100, flat_f, &e);
  assert_int_equal(karst_surface_create_grid(&ctx, 11, 11, 0, 0, 100, z, &S[1]), KARST_SUCCESS);
  free(z);
  S[2] = lattice_tin(11, 11, 0, 0, 100, flat_f, &e, 0);
  for (int s = 0; s < 3; s++) {
    const double a[3] = {100, 100, 250};
    assert_int_equal(karst_surface_segment_below(S[s], a, (const double[3]){900, 700, 200}), 1);
    assert_int_equal(karst_surface_segment_above(S[s], a, (const double[3]){900, 700, 200}), 0);
    assert_int_equal(karst_surface_segment_below(S[s], a, (const double[3]){900, 700, 250}), 0);
    assert_int_equal(karst_surface_segment_above(S[s], a, (const double[3]){900, 700, 250}), 0);
    assert_int_equal(karst_surface_segment_above(S[s], a, (const double[3]){900, 700, 260}), 1);
    assert_int_equal(karst_surface_segment_below(S[s], a, (const double[3]){900, 700, 260}), 0);
    /* vertical segments: one x-y point */
    assert_int_equal(karst_surface_segment_below(S[s], a, (const double[3]){100, 100, 0}), 1);
    assert_int_equal(karst_surface_segment_below(S[s], (const double[3]){100, 100, 251},
                                                 (const double[3]){100, 100, 0}),
                     0);
    assert_int_equal(karst_surface_segment_below(S[s], a, (const double[3]){NAN, 0, 0}), 0);
  }
  /* a TIN is undefined outside its triangles: no segment is below it there */
  assert_int_equal(karst_surface_segment_below(S[2], (const double[3]){500, 500, 0},
                                               (const double[3]){1500, 500, 0}),
                   0);
  assert_true(isnan(karst_surface_z(S[2], 1000.5, 500)));
  for (int s = 0; s < 3; s++)
    karst_surface_free(S[s]);
}

/* The bilinear saddle z = u v on one cell: along the diagonal from (0, 1) to
 * (1, 0) the surface is t (1 - t), a quadratic with its maximum 1/4 at t = 1/2,
 * so the exact test must look inside the piece (values by hand). */
static void test_grid_quadratic_piece(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  const double z[4] = {0, 0, 0, 1};
  karst_surface_t *s = NULL;
  assert_int_equal(karst_surface_create_grid(&ctx, 2, 2, 0, 0, 1, z, &s), KARST_SUCCESS);
  const double a[3] = {0, 1, 0.2}, b[3] = {1, 0, 0.2};
  assert_int_equal(karst_surface_segment_above(s, a, b), 0); /* 0.2 < 0.25 in the middle */
  assert_int_equal(karst_surface_segment_below(s, a, b), 0); /* 0.2 > 0 at the ends */
  assert_int_equal(
      karst_surface_segment_above(s, (const double[3]){0, 1, 0.25}, (const double[3]){1, 0, 0.25}),
      0); /* touches at t = 1/2 */
  assert_int_equal(
      karst_surface_segment_above(s, (const double[3]){0, 1, 0.26}, (const double[3]){1, 0, 0.26}),
      1);
  /* ends on the surface (z = 0), interior strictly below t (1 - t) > 0 */
  assert_int_equal(
      karst_surface_segment_below(s, (const double[3]){0, 1, 0}, (const double[3]){1, 0, 0}), 1);
  /* max and min over [0.25, 0.75]^2: the corners 0.75^2 and 0.25^2 */
  assert_close(karst_surface_max_rect(s, 0.25, 0.75, 0.25, 0.75), 0.5625, 1e-15);
  assert_close(karst_surface_min_rect(s, 0.25, 0.75, 0.25, 0.75), 0.0625, 1e-15);
  /* Lipschitz: the corner (1, 1) slope sqrt(1 + 1) */
  assert_close(karst_surface_lipschitz(s), sqrt(2.0), 1e-15);
  /* clamped outside: z(2, 0.5) = z(1, 0.5) = 0.5 and the gradient along x is 0 */
  assert_close(karst_surface_z(s, 2, 0.5), 0.5, 1e-15);
  double g[2];
  karst_surface_gradient(s, 2, 0.5, g);
  assert_close(g[0], 0, 0);
  assert_close(g[1], 1, 1e-15);
  karst_surface_gradient(s, 0.5, 0.25, g);
  assert_close(g[0], 0.25, 1e-15);
  assert_close(g[1], 0.5, 1e-15);
  karst_surface_free(s);
}

/* ------------------------------------------------------------------------ */
/* A folded horizon                                                          */
/* ------------------------------------------------------------------------ */

/* Anticline f = 250 + A cos(k (u - u0)), u = x cos(th) + y sin(th): an oblique
 * axis (th = 30 degrees), A = 40 m, wavelength 800 m. */
typedef struct {
  double A, k, th, u0;
} fold_t;

static double fold_f(double x, double y, const void *p) {
  const fold_t *F = p;
  double u = x * cos(F->th) + y * sin(F->th);
  return 250 + F->A * cos(F->k * (u - F->u0));
}

static void test_fold(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  const double h = 20;
  const fold_t F = {40, 2 * M_PI / 800, M_PI / 6, 1000};
  double *z = lattice_z(101, 76, 0, 0, h, fold_f, &F);
  karst_surface_t *sg = NULL, *st = lattice_tin(101, 76, 0, 0, h, fold_f, &F, 0);
  assert_int_equal(karst_surface_create_grid(&ctx, 101, 76, 0, 0, h, z, &sg), KARST_SUCCESS);
  free(z);
  /* |f_uu| <= A k^2; f_xx + f_yy = f_uu (cos^2 + sin^2); |Hessian| = |f_uu| */
  double M = F.A * F.k * F.k;
  double bound_grid = h * h / 8 * M;      /* 0.1234 m */
  double bound_tin = M / 2 * (h * h / 2); /* R^2 = h^2 / 2 for a right triangle of legs h */
  karst_rng_t rng;
  karst_rng_init(&rng, 13, 0);
  double eg = 0, et = 0;
  for (int k = 0; k < 20000; k++) {
    double x = karst_rng_uniform_range(&rng, 0, 2000), y = karst_rng_uniform_range(&rng, 0, 1500);
    eg = fmax(eg, fabs(karst_surface_z(sg, x, y) - fold_f(x, y, &F)));
    et = fmax(et, fabs(karst_surface_z(st, x, y) - fold_f(x, y, &F)));
  }
  print_message("fold: max error grid %.4f m (bound %.4f), TIN %.4f m (bound %.4f)\n", eg,
                bound_grid, et, bound_tin);
  assert_true(eg <= bound_grid);
  assert_true(et <= bound_tin);
  /* Closed forms. The bilinear value at a cell centre is the mean of its four
   * corners, at offsets d with d.n = +-(h/2) cos th +- (h/2) sin th, so its error
   * is A cos(phi) (mean cos(k d.n) - 1). The linear value at the middle of a
   * cell's diagonal is the mean of its two ends: error A cos(phi) (cos(k dd) - 1)
   * with dd = (h/2)(cos th + sin th). */
  for (int i = 10; i < 100; i += 17)
    for (int j = 7; j < 75; j += 13) {
      double cx = (i + 0.5) * h, cy = (j + 0.5) * h;
      double phi = F.k * (cx * cos(F.th) + cy * sin(F.th) - F.u0);
      double c1 = (h / 2) * (cos(F.th) + sin(F.th)), c2 = (h / 2) * (cos(F.th) - sin(F.th));
      double mean = 0.5 * (cos(F.k * c1) + cos(F.k * c2));
      double f = fold_f(cx, cy, &F);
      assert_close(karst_surface_z(sg, cx, cy) - f, F.A * cos(phi) * (mean - 1), 1e-9);
      assert_close(karst_surface_z(st, cx, cy) - f, F.A * cos(phi) * (cos(F.k * c1) - 1), 1e-9);
    }
  /* the errors reach most of their bounds near the crest (cos(phi) = 1):
   * grid (mean - 1) A = -0.1221 m of 0.1234; TIN -0.2302 m of 0.2467 */
  assert_true(eg > 0.9 * bound_grid);
  assert_true(et > 0.8 * bound_tin);

  /* A straight horizontal gallery at 245 m from x = 800 to x = 1200 along the
   * crest-normal passes under the anticline's crest (250 m) but its ends, where the
   * limbs are lower, decide: analytic below iff f > 245 all along. */
  double a[3] = {800, 600, 0}, b[3] = {1300, 600, 0};
  double fmin_ab = INFINITY;
  for (int k = 0; k <= 1000; k++)
    fmin_ab = fmin(fmin_ab, fold_f(800 + k * 0.5, 600, &F));
  a[2] = b[2] = fmin_ab - 0.5; /* 0.5 m below the lowest point: more than both bounds */
  assert_int_equal(karst_surface_segment_below(sg, a, b), 1);
  assert_int_equal(karst_surface_segment_below(st, a, b), 1);
  a[2] = b[2] = fmin_ab + 0.5; /* above the lowest point by more than the bounds */
  assert_int_equal(karst_surface_segment_below(sg, a, b), 0);
  assert_int_equal(karst_surface_segment_below(st, a, b), 0);
  karst_surface_free(sg);
  karst_surface_free(st);
}

/* ------------------------------------------------------------------------ */
/* Bucket index against a scan of every triangle                             */
/* ------------------------------------------------------------------------ */

static void test_bucket_vs_brute(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  /* a 33 x 33 lattice jittered by up to 0.2 h: irregular triangles, 2048 of them */
  const int n = 33;
  const double h = 10;
  karst_rng_t rng;
  karst_rng_init(&rng, 14, 0);
  double *xyz = malloc((size_t)n * n * 3 * sizeof *xyz);
  karst_int_t *tri = malloc((size_t)(n - 1) * (n - 1) * 6 * sizeof *tri);
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) {
      double *q = xyz + 3 * (j * n + i);
      q[0] = i * h + (i > 0 && i < n - 1 ? karst_rng_uniform_range(&rng, -0.2, 0.2) * h : 0);
      q[1] = j * h + (j > 0 && j < n - 1 ? karst_rng_uniform_range(&rng, -0.2, 0.2) * h : 0);
      q[2] = sin(q[0] / 50) * cos(q[1] / 70) * 20;
    }
  karst_int_t m = 0;
  for (int j = 0; j + 1 < n; j++)
    for (int i = 0; i + 1 < n; i++) {
      karst_int_t a = j * n + i, b = a + 1, c = a + n, d = c + 1;
      karst_int_t t[6] = {a, b, d, a, d, c};
      if ((i + j) % 3 == 0) { /* mixed diagonals and windings */
        karst_int_t u[6] = {a, c, b, b, c, d};
        memcpy(t, u, sizeof t);
      }
      memcpy(tri + 3 * m, t, sizeof t);
      m += 2;
    }
  karst_surface_t *s = NULL;
  assert_int_equal(karst_surface_create_tin(&ctx, (karst_int_t)n * n, xyz, m, tri, &s),
                   KARST_SUCCESS);
  int inside = 0;
  for (int k = 0; k < 100000; k++) {
    double x, y;
    if (k % 10 == 0) { /* on a vertex or an edge midpoint, exactly */
      karst_int_t t = (karst_int_t)karst_rng_below(&rng, (uint64_t)m);
      const double *p = xyz + 3 * tri[3 * t], *q = xyz + 3 * tri[3 * t + 1];
      x = k % 20 == 0 ? p[0] : 0.5 * (p[0] + q[0]);
      y = k % 20 == 0 ? p[1] : 0.5 * (p[1] + q[1]);
    } else {
      x = karst_rng_uniform_range(&rng, -10, 330);
      y = karst_rng_uniform_range(&rng, -10, 330);
    }
    karst_int_t tb = karst_i_tin_locate(s, x, y), tf = karst_i_tin_locate_brute(s, x, y);
    if (tb != tf)
      print_error("(%.17g, %.17g): index %lld, scan %lld\n", x, y, (long long)tb, (long long)tf);
    assert_int_equal(tb, tf);
    inside += tb >= 0;
  }
  assert_true(inside > 80000 && inside < 100000); /* both outcomes were exercised */

  /* Piece boundaries against every edge and vertex of the TIN: an edge counts
   * when the trace crosses it properly (exact orientations), at the parameter of
   * the crossing computed from its lower-numbered end; a vertex counts when it
   * lies on the trace strictly between the ends. Segments: random, leaving the
   * TIN, vertex to vertex, and along the west and south borders (x = 0, y = 0
   * exactly), which run through vertices. */
  const double *V;
  const karst_int_t *T;
  karst_int_t nv, nt;
  assert_int_equal(karst_surface_tin(s, &V, &nv, &T, &nt), 1);
  double *expect = malloc(6 * (size_t)nt * sizeof *expect);
  int max_n = 0;
  for (int k = 0; k < 3000; k++) {
    double a[3] = {0, 0, 0}, b[3] = {0, 0, 0};
    if (k % 5 == 0) {
      karst_int_t u = (karst_int_t)karst_rng_below(&rng, (uint64_t)nv);
      karst_int_t w = (karst_int_t)karst_rng_below(&rng, (uint64_t)nv);
      memcpy(a, V + 3 * u, 2 * sizeof(double));
      memcpy(b, V + 3 * w, 2 * sizeof(double));
    } else if (k % 5 == 1) {
      a[k % 2] = 0, a[1 - k % 2] = karst_rng_uniform_range(&rng, -20, 100);
      b[k % 2] = 0, b[1 - k % 2] = karst_rng_uniform_range(&rng, 100, 340);
    } else {
      double span = k % 5 == 2 ? 400 : 30;
      a[0] = karst_rng_uniform_range(&rng, -20, 340),
      a[1] = karst_rng_uniform_range(&rng, -20, 340);
      b[0] = a[0] + karst_rng_uniform_range(&rng, -span, span);
      b[1] = a[1] + karst_rng_uniform_range(&rng, -span, span);
    }
    const double A[2] = {a[0], a[1]}, B[2] = {b[0], b[1]}, D[2] = {b[0] - a[0], b[1] - a[1]};
    int ne = 0;
    if (D[0] != 0 || D[1] != 0) {
      for (karst_int_t t = 0; t < nt; t++)
        for (int e = 0; e < 3; e++) {
          karst_int_t u = T[3 * t + e], w = T[3 * t + (e + 1) % 3];
          if (u > w) {
            karst_int_t x = u;
            u = w, w = x;
          }
          const double *E0 = V + 3 * u, *E1 = V + 3 * w;
          if (karst_i_orient2d(A, B, E0) * karst_i_orient2d(A, B, E1) >= 0) continue;
          if (karst_i_orient2d(E0, E1, A) * karst_i_orient2d(E0, E1, B) >= 0) continue;
          double ex = E1[0] - E0[0], ey = E1[1] - E0[1];
          expect[ne++] = ((E0[0] - A[0]) * ey - (E0[1] - A[1]) * ex) / (D[0] * ey - D[1] * ex);
        }
      for (karst_int_t v = 0; v < nv; v++) {
        const double *P = V + 3 * v;
        if (karst_i_orient2d(A, B, P) != 0) continue;
        double tv = ((P[0] - A[0]) * D[0] + (P[1] - A[1]) * D[1]) / (D[0] * D[0] + D[1] * D[1]);
        if (tv > 0 && tv < 1) expect[ne++] = tv;
      }
    }
    /* sort and drop repeats (an edge is seen from both its triangles) */
    for (int i = 1; i < ne; i++)
      for (int j = i; j > 0 && expect[j - 1] > expect[j]; j--) {
        double x = expect[j];
        expect[j] = expect[j - 1], expect[j - 1] = x;
      }
    int nu = 0;
    for (int i = 0; i < ne; i++)
      if (nu == 0 || expect[i] != expect[nu - 1]) expect[nu++] = expect[i];
    double got[512];
    int n = karst_surface_segment_pieces(s, a, b, got, 512);
    if (n != nu)
      print_error("segment %d (%g, %g)-(%g, %g): %d pieces, expected %d\n", k, a[0], a[1], b[0],
                  b[1], n, nu);
    assert_int_equal(n, nu);
    for (int i = 0; i < n; i++)
      assert_true(got[i] == expect[i]);
    max_n = nu > max_n ? nu : max_n;
  }
  assert_true(max_n > 40); /* long traces were among them */
  free(expect);
  free(xyz);
  free(tri);
  karst_surface_free(s);
}

/* ------------------------------------------------------------------------ */
/* Pieces, extremes, coverage, triangulation                                 */
/* ------------------------------------------------------------------------ */

static void test_segment_pieces(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  double t[16];
  /* grid of 10 m cells from (0, 0): the trace from (5, 5) to (25, 5) crosses
   * x = 10 and x = 20 at t = 0.25 and 0.75 */
  double z[16] = {0};
  karst_surface_t *g = NULL;
  assert_int_equal(karst_surface_create_grid(&ctx, 4, 4, 0, 0, 10, z, &g), KARST_SUCCESS);
  assert_int_equal(karst_surface_segment_pieces(g, (const double[3]){5, 5, 0},
                                                (const double[3]){25, 5, 0}, t, 16),
                   2);
  assert_close(t[0], 0.25, 1e-15);
  assert_close(t[1], 0.75, 1e-15);
  /* through the node (10, 10) on the diagonal: x and y lines cross at one t */
  assert_int_equal(karst_surface_segment_pieces(g, (const double[3]){5, 5, 0},
                                                (const double[3]){15, 15, 0}, t, 16),
                   1);
  assert_close(t[0], 0.5, 1e-15);
  /* too little room: -1 */
  assert_int_equal(karst_surface_segment_pieces(g, (const double[3]){5, 5, 0},
                                                (const double[3]){25, 5, 0}, t, 1),
                   -1);
  /* beyond the last node line nothing changes (clamped) */
  assert_int_equal(karst_surface_segment_pieces(g, (const double[3]){35, 35, 0},
                                                (const double[3]){80, 35, 0}, t, 16),
                   0);
  karst_surface_free(g);

  /* the unit square cut along its diagonal (0,0)-(1,1) */
  const double xyz[12] = {0, 0, 0, 1, 0, 1, 0, 1, 2, 1, 1, 3};
  const karst_int_t tri[6] = {0, 1, 3, 0, 3, 2};
  karst_surface_t *s = NULL;
  assert_int_equal(karst_surface_create_tin(&ctx, 4, xyz, 2, tri, &s), KARST_SUCCESS);
  /* from (0.5, 0) to (0.5, 1): the diagonal at y = 0.5, t = 0.5 */
  assert_int_equal(karst_surface_segment_pieces(s, (const double[3]){0.5, 0, 0},
                                                (const double[3]){0.5, 1, 0}, t, 16),
                   1);
  assert_close(t[0], 0.5, 1e-15);
  /* from (-1, 0.5) to (2, 0.5): enters at x = 0 (t = 1/3), the diagonal at x = 0.5
   * (t = 1/2), leaves at x = 1 (t = 2/3) */
  assert_int_equal(karst_surface_segment_pieces(s, (const double[3]){-1, 0.5, 0},
                                                (const double[3]){2, 0.5, 0}, t, 16),
                   3);
  assert_close(t[0], 1.0 / 3, 1e-15);
  assert_close(t[1], 0.5, 1e-15);
  assert_close(t[2], 2.0 / 3, 1e-15);
  /* through the vertex (1, 0) from (0.5, -0.5) to (1.5, 0.5): touches the TIN
   * at one point, t = 1/2 */
  assert_int_equal(karst_surface_segment_pieces(s, (const double[3]){0.5, -0.5, 0},
                                                (const double[3]){1.5, 0.5, 0}, t, 16),
                   1);
  assert_close(t[0], 0.5, 1e-15);
  /* along the diagonal itself: no crossing inside, the ends are vertices */
  assert_int_equal(karst_surface_segment_pieces(s, (const double[3]){0, 0, 0},
                                                (const double[3]){1, 1, 0}, t, 16),
                   0);
  /* a plane has none */
  karst_surface_t *p = NULL;
  assert_int_equal(karst_surface_create_plane(&ctx, 0, 10, 0, (const double[2]){0, 0}, &p),
                   KARST_SUCCESS);
  assert_int_equal(karst_surface_segment_pieces(p, (const double[3]){0, 0, 0},
                                                (const double[3]){100, 100, 0}, t, 16),
                   0);
  karst_surface_free(p);
  karst_surface_free(s);
}

static void test_extremes(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  /* one triangle (0,0,0), (10,0,10), (0,10,5): z = x + y / 2 */
  const double xyz[9] = {0, 0, 0, 10, 0, 10, 0, 10, 5};
  const karst_int_t tri[3] = {0, 2, 1}; /* clockwise: turned round */
  karst_surface_t *s = NULL;
  assert_int_equal(karst_surface_create_tin(&ctx, 3, xyz, 1, tri, &s), KARST_SUCCESS);
  assert_close(karst_surface_max_rect(s, 2, 4, 1, 3), 5.5, 1e-15); /* (4, 3) */
  assert_close(karst_surface_min_rect(s, 2, 4, 1, 3), 2.5, 1e-15); /* (2, 1) */
  /* partly outside: over the part x >= 5, max at (10, 0) = 10, min at (5, 0) = 5 */
  assert_close(karst_surface_max_rect(s, 5, 20, -5, 20), 10, 1e-15);
  assert_close(karst_surface_min_rect(s, 5, 20, -5, 20), 5, 1e-15);
  assert_true(isnan(karst_surface_max_rect(s, 20, 30, 20, 30)));
  assert_close(karst_surface_lipschitz(s), hypot(1, 0.5), 1e-15);
  double g[2];
  karst_surface_gradient(s, 2, 2, g);
  assert_close(g[0], 1, 1e-15);
  assert_close(g[1], 0.5, 1e-15);
  karst_surface_gradient(s, 20, 20, g);
  assert_true(isnan(g[0]) && isnan(g[1]));
  double lo[3], hi[3];
  karst_surface_bounds(s, lo, hi);
  assert_close(lo[0], 0, 0);
  assert_close(hi[0], 10, 0);
  assert_close(hi[2], 10, 0);
  karst_surface_free(s);

  /* the fold, three ways: the exact max and min over rectangles bound every
   * sample inside and exceed the samples by at most L * (spacing / sqrt 2) */
  const fold_t F = {40, 2 * M_PI / 800, M_PI / 6, 1000};
  double *z = lattice_z(51, 51, 0, 0, 20, fold_f, &F);
  karst_surface_t *S[2] = {NULL, lattice_tin(51, 51, 0, 0, 20, fold_f, &F, 1)};
  assert_int_equal(karst_surface_create_grid(&ctx, 51, 51, 0, 0, 20, z, &S[0]), KARST_SUCCESS);
  free(z);
  karst_rng_t rng;
  karst_rng_init(&rng, 15, 0);
  for (int r = 0; r < 40; r++) {
    double x0 = karst_rng_uniform_range(&rng, -50, 1000),
           y0 = karst_rng_uniform_range(&rng, -50, 1000);
    double x1 = x0 + karst_rng_uniform_range(&rng, 0, 300),
           y1 = y0 + karst_rng_uniform_range(&rng, 0, 300);
    if (r == 0) x1 = x0; /* degenerate: a segment */
    for (int k = 0; k < 2; k++) {
      double mx = karst_surface_max_rect(S[k], x0, x1, y0, y1);
      double mn = karst_surface_min_rect(S[k], x0, x1, y0, y1);
      double smax = -INFINITY, smin = INFINITY;
      const int ns = 120;
      for (int i = 0; i <= ns; i++)
        for (int j = 0; j <= ns; j++) {
          double v = karst_surface_z(S[k], x0 + (x1 - x0) * i / ns, y0 + (y1 - y0) * j / ns);
          if (isnan(v)) continue;
          smax = fmax(smax, v), smin = fmin(smin, v);
        }
      double slack = karst_surface_lipschitz(S[k]) * hypot(x1 - x0, y1 - y0) / ns;
      assert_true(mx >= smax - 1e-12 && mx <= smax + slack + 1e-12);
      assert_true(mn <= smin + 1e-12 && mn >= smin - slack - 1e-12);
    }
  }
  karst_surface_free(S[0]);
  karst_surface_free(S[1]);
}

static int has(const char *msg, const char *what) {
  if (strstr(msg, what)) return 1;
  print_error("expected '%s' in: %s\n", what, msg);
  return 0;
}

static void test_covers(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  /* 100 x 75 cells of 20 m centred from (10, 10): cell edges exactly 0..2000 x 0..1500 */
  double *z = calloc(100 * 75, sizeof *z);
  karst_surface_t *g = NULL;
  const double lo[2] = {0, 0}, hi[2] = {2000, 1500};
  assert_int_equal(karst_surface_create_grid(&ctx, 100, 75, 10, 10, 20, z, &g), KARST_SUCCESS);
  assert_int_equal(karst_surface_check_covers(&ctx, g, lo, hi, "water table"), KARST_SUCCESS);
  karst_surface_free(g);
  /* moved 20 m east: short by 20 m in the west */
  assert_int_equal(karst_surface_create_grid(&ctx, 100, 75, 30, 10, 20, z, &g), KARST_SUCCESS);
  assert_int_equal(karst_surface_check_covers(&ctx, g, lo, hi, "water table"), KARST_ERANGE);
  assert_true(has(ctx.errmsg, "the water table grid covers x in [20, 2020]"));
  assert_true(has(ctx.errmsg, "falls short by 20 m in the west (x = 0 m)"));
  karst_surface_free(g);
  free(z);

  /* the two-part TIN of [0, 100]^2 */
  karst_surface_t *s = NULL;
  assert_int_equal(karst_surface_load(&ctx, DATA "two_parts.ts", &s), KARST_SUCCESS);
  assert_int_equal(karst_surface_check_covers(&ctx, s, (const double[2]){0, 0},
                                              (const double[2]){100, 100}, "horizon H1"),
                   KARST_SUCCESS);
  assert_int_equal(karst_surface_check_covers(&ctx, s, (const double[2]){0, 0},
                                              (const double[2]){110, 100}, "horizon H1"),
                   KARST_ERANGE);
  assert_true(has(ctx.errmsg, DATA "two_parts.ts: the horizon H1 surface"));
  assert_true(has(ctx.errmsg, "the south-east corner (110, 0) by 10 m"));
  assert_true(has(ctx.errmsg, "the north-east corner (110, 100) by 10 m"));
  karst_surface_free(s);

  /* a 3 x 3 lattice of 10 m cells without its middle cell (a hole), and without
   * the middle cell of its south row (a notch) */
  for (int hole = 0; hole < 2; hole++) {
    double xyz[16 * 3];
    karst_int_t tri[18 * 3], m = 0;
    for (int j = 0; j < 4; j++)
      for (int i = 0; i < 4; i++) {
        double *q = xyz + 3 * (j * 4 + i);
        q[0] = 10 * i, q[1] = 10 * j, q[2] = 0;
      }
    for (int j = 0; j < 3; j++)
      for (int i = 0; i < 3; i++) {
        if (i == 1 && j == (hole ? 1 : 0)) continue;
        karst_int_t a = j * 4 + i, b = a + 1, c = a + 4, d = c + 1;
        karst_int_t t[6] = {a, b, d, a, d, c};
        memcpy(tri + 3 * m, t, sizeof t);
        m += 2;
      }
    assert_int_equal(karst_surface_create_tin(&ctx, 16, xyz, m, tri, &s), KARST_SUCCESS);
    assert_int_equal(karst_surface_check_covers(&ctx, s, (const double[2]){0, 0},
                                                (const double[2]){30, 30}, "stratum top"),
                     KARST_ERANGE);
    assert_true(has(ctx.errmsg, "(surface built in code): the stratum top surface must cover x "
                                "in [0, 30], y in [0, 30] m but has a gap"));
    assert_true(has(ctx.errmsg, "m inside it"));
    /* the part west of the gap is covered */
    assert_int_equal(karst_surface_check_covers(&ctx, s, (const double[2]){0, 0},
                                                (const double[2]){10, 30}, "stratum top"),
                     KARST_SUCCESS);
    karst_surface_free(s);
  }
}

static double tri_area(const double *a, const double *b, const double *c) {
  return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
}

static void test_triangulate(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  double *xyz;
  karst_int_t *tri, nv, nt;
  /* plane over [0, 100] x [0, 50], edges <= 30 m: 4 x 2 cells, 15 vertices, 16 triangles */
  karst_surface_t *p = NULL;
  assert_int_equal(karst_surface_create_plane(&ctx, 100, 10, 45, (const double[2]){0, 0}, &p),
                   KARST_SUCCESS);
  assert_int_equal(karst_surface_triangulate(&ctx, p, (const double[2]){0, 0},
                                             (const double[2]){100, 50}, 30, &xyz, &nv, &tri, &nt),
                   KARST_SUCCESS);
  assert_int_equal(nv, 15);
  assert_int_equal(nt, 16);
  double area = 0;
  for (karst_int_t t = 0; t < nt; t++)
    area += tri_area(xyz + 3 * tri[3 * t], xyz + 3 * tri[3 * t + 1], xyz + 3 * tri[3 * t + 2]);
  assert_close(area, 5000, 1e-9); /* counter-clockwise, tiling the rectangle */
  for (karst_int_t v = 0; v < nv; v++)
    assert_close(xyz[3 * v + 2], karst_surface_z(p, xyz[3 * v], xyz[3 * v + 1]), 0);
  free(xyz);
  free(tri);
  karst_surface_free(p);

  /* grid of 10 m cells from (0, 0) over [5, 45] x [5, 25]: x breaks 5 10 20 30 40 45,
   * y breaks 5 10 20 25: 24 vertices, 5 x 3 x 2 = 30 triangles */
  double z[36];
  for (int k = 0; k < 36; k++)
    z[k] = k * 0.5;
  karst_surface_t *g = NULL;
  assert_int_equal(karst_surface_create_grid(&ctx, 6, 6, 0, 0, 10, z, &g), KARST_SUCCESS);
  assert_int_equal(karst_surface_triangulate(&ctx, g, (const double[2]){5, 5},
                                             (const double[2]){45, 25}, 0, &xyz, &nv, &tri, &nt),
                   KARST_SUCCESS);
  assert_int_equal(nv, 24);
  assert_int_equal(nt, 30);
  for (karst_int_t v = 0; v < nv; v++)
    assert_close(xyz[3 * v + 2], karst_surface_z(g, xyz[3 * v], xyz[3 * v + 1]), 0);
  free(xyz);
  free(tri);
  karst_surface_free(g);

  /* the two-part TIN clipped to [25, 75] x [0, 100]: area 5000, z on the surface */
  karst_surface_t *s = NULL;
  assert_int_equal(karst_surface_load(&ctx, DATA "two_parts.ts", &s), KARST_SUCCESS);
  assert_int_equal(karst_surface_triangulate(&ctx, s, (const double[2]){25, 0},
                                             (const double[2]){75, 100}, 0, &xyz, &nv, &tri, &nt),
                   KARST_SUCCESS);
  area = 0;
  for (karst_int_t t = 0; t < nt; t++) {
    double a = tri_area(xyz + 3 * tri[3 * t], xyz + 3 * tri[3 * t + 1], xyz + 3 * tri[3 * t + 2]);
    assert_true(a > 0);
    area += a;
  }
  assert_close(area, 5000, 1e-9);
  for (karst_int_t v = 0; v < nv; v++)
    assert_close(xyz[3 * v + 2], karst_surface_z(s, xyz[3 * v], xyz[3 * v + 1]), 1e-12);
  /* the clipped points on the shared edge x = 50 are merged: 8 points in all
   * ((25|50|75) x (0|100) and the two crossings of the diagonals with x = 25, 75) */
  assert_int_equal(nv, 8);
  free(xyz);
  free(tri);
  assert_int_equal(karst_surface_triangulate(&ctx, s, (const double[2]){5, 0},
                                             (const double[2]){1, 1}, 0, &xyz, &nv, &tri, &nt),
                   KARST_EINVAL);
  karst_surface_free(s);
}

/* ------------------------------------------------------------------------ */
/* GOCAD TSurf                                                               */
/* ------------------------------------------------------------------------ */

/* two_parts.ts: the plane z = 10 + 0.1 x + 0.2 y over [0, 100]^2 in two TFACEs
 * sharing the edge x = 50 through an ATOM and a PATOM. */
static void test_tsurf_two_parts(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_i_tsurf_t ts;
  assert_int_equal(karst_i_tsurf_read(&ctx, DATA "two_parts.ts", &ts), KARST_SUCCESS);
  assert_int_equal(ts.nv, 6);
  assert_int_equal(ts.nt, 4);
  assert_int_equal(ts.nparts, 2);
  assert_int_equal(ts.natoms, 2);
  assert_int_equal(ts.nbstones, 3);
  assert_int_equal(ts.nborders, 1);
  assert_int_equal(ts.nobjects, 1);
  assert_int_equal(ts.zdepth, 0);
  assert_string_equal(ts.name, "Two parts");
  assert_int_equal(ts.tpart[0], 0);
  assert_int_equal(ts.tpart[3], 1);
  /* TRGL 5 7 8 of part 2: ATOM 5 repeats vertex 2 (index 1) */
  assert_int_equal(ts.tri[6], 1);
  assert_int_equal(ts.tri[11], 3);   /* PATOM 6 repeats vertex 4 */
  assert_int_equal(ts.vline[4], 39); /* PVRTX 7 */
  assert_int_equal(ts.tline[2], 41); /* TRGL 5 7 8 */
  /* PROPERTIES porosity normal, ESIZES 1 3 */
  assert_int_equal(ts.nprops, 2);
  assert_string_equal(ts.prop_names[1], "normal");
  assert_int_equal(ts.prop_stride, 4);
  assert_close(ts.props[0], 0.12, 0);
  assert_true(isnan(ts.props[2 * 4])); /* -99999 is NO_DATA */
  assert_close(ts.props[3 * 4 + 1], 0.1, 0);
  assert_close(ts.props[3 * 4 + 3], 0.97, 0);
  assert_close(ts.xyz[3 * 3 + 2], 35, 0);
  karst_i_tsurf_destroy(&ts);

  karst_surface_t *s = NULL;
  assert_int_equal(karst_surface_load(&ctx, DATA "two_parts.ts", &s), KARST_SUCCESS);
  assert_int_equal(karst_surface_kind(s), KARST_SURFACE_TIN);
  assert_string_equal(karst_surface_path(s), DATA "two_parts.ts");
  assert_string_equal(karst_surface_name(s), "Two parts");
  const double *V;
  const karst_int_t *T;
  karst_int_t nv, nt;
  assert_int_equal(karst_surface_tin(s, &V, &nv, &T, &nt), 1);
  assert_int_equal(nv, 6);
  assert_int_equal(nt, 4);
  karst_rng_t rng;
  karst_rng_init(&rng, 16, 0);
  for (int k = 0; k < 1000; k++) {
    double x = karst_rng_uniform_range(&rng, 0, 100), y = karst_rng_uniform_range(&rng, 0, 100);
    assert_close(karst_surface_z(s, x, y), 10 + 0.1 * x + 0.2 * y, 1e-12);
  }
  assert_close(karst_surface_z(s, 75, 50), 27.5, 1e-12);
  assert_true(isnan(karst_surface_z(s, 100.001, 50)));
  karst_surface_free(s);
}

static void test_tsurf_variants(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_surface_t *s = NULL;
  /* ZPOSITIVE Depth: depths 10 ... 40 give the plane of two_parts.ts' corners, negated:
   * z = -(10 + 0.1 x + 0.2 y) */
  assert_int_equal(karst_surface_load(&ctx, DATA "depth.ts", &s), KARST_SUCCESS);
  assert_string_equal(karst_surface_name(s), "depth_plane");
  assert_close(karst_surface_z(s, 100, 100), 40, 0); /* VRTX 40 100 100 -40 under Depth */
  assert_close(karst_surface_z(s, 50, 50), 25, 1e-12);
  karst_surface_free(s);

  /* two GOCAD TSurf objects in one file: ids restart; the shared points merge */
  karst_i_tsurf_t ts;
  assert_int_equal(karst_i_tsurf_read(&ctx, DATA "two_objects.ts", &ts), KARST_SUCCESS);
  assert_int_equal(ts.nobjects, 2);
  assert_int_equal(ts.nparts, 2);
  assert_string_equal(ts.name, "west");
  karst_i_tsurf_destroy(&ts);
  assert_int_equal(karst_surface_load(&ctx, DATA "two_objects.ts", &s), KARST_SUCCESS);
  const double *V;
  const karst_int_t *T;
  karst_int_t nv, nt;
  assert_int_equal(karst_surface_tin(s, &V, &nv, &T, &nt), 1);
  assert_int_equal(nv, 4);
  assert_int_equal(nt, 2);
  assert_close(karst_surface_z(s, 10, 10), 3, 0);
  karst_surface_free(s);

  /* CRLF, a byte order mark, HEADER{ without a space, AXIS_UNIT in feet,
   * triangles before any TFACE, an ATOM repeating an ATOM, an unknown keyword */
  const char crlf[] = "\xEF\xBB\xBFGOCAD TSurf 1\r\nHEADER{\r\nname:feet\r\n}\r\n"
                      "GOCAD_ORIGINAL_COORDINATE_SYSTEM\r\nAXIS_UNIT ft ft ft\r\n"
                      "END_ORIGINAL_COORDINATE_SYSTEM\r\nSOME_FUTURE_KEYWORD 1 2\r\n"
                      "VRTX 1 0 0 0\r\nVRTX 2 100 0 10\r\nATOM 3 2\r\nATOM 4 3\r\n"
                      "VRTX 5 0 100 20\r\nTRGL 1 4 5\r\nEND\r\n";
  write_file(TMP "/feet.ts", crlf, sizeof crlf - 1);
  assert_int_equal(karst_surface_load(&ctx, TMP "/feet.ts", &s), KARST_SUCCESS);
  assert_string_equal(karst_surface_name(s), "feet");
  assert_close(karst_surface_z(s, 30.48, 0), 3.048, 1e-12); /* 100 ft, 10 ft */
  karst_surface_free(s);

  /* a one-line header, tabs, a non-numeric NO_DATA_VALUES, kilometres */
  const char oneline[] = "GOCAD TSurf 1\nHEADER {name:short}\nPROPERTIES p\n"
                         "NO_DATA_VALUES **none**\nAXIS_UNIT km km m\nTFACE\n"
                         "PVRTX\t1\t0\t0\t5\t7\nPVRTX 2 1 0 5 -99999\nPVRTX 3 0 1 6 1\n"
                         "TRGL 1 2 3\nEND\n";
  write_file(TMP "/oneline.ts", oneline, sizeof oneline - 1);
  assert_int_equal(karst_i_tsurf_read(&ctx, TMP "/oneline.ts", &ts), KARST_SUCCESS);
  assert_string_equal(ts.name, "short");
  assert_close(ts.props[1], -99999, 0); /* no no-data value: kept */
  karst_i_tsurf_destroy(&ts);
  assert_int_equal(karst_surface_load(&ctx, TMP "/oneline.ts", &s), KARST_SUCCESS);
  assert_close(karst_surface_z(s, 0, 1000), 6, 1e-12); /* y 1 km */
  karst_surface_free(s);
}

typedef struct {
  const char *file; /* under tests/data/surfaces/bad/ */
  karst_error_t code;
  const char *where; /* "FILE:LINE:" */
  const char *what;
} bad_case_t;

static void test_tsurf_hostile(void **state) {
  (void)state;
  static const bad_case_t cases[] = {
      {"nonmanifold.ts", KARST_EINVAL, "nonmanifold.ts:8: ",
       "the edge between vertices 1 and 2 belongs to 3 triangles (TRGL 1 2 3, TRGL 2 1 4 (line 9), "
       "TRGL 1 2 5 (line 10)): the surface is not a manifold"},
      {"overlap.ts", KARST_EINVAL, "overlap.ts:9: ",
       "TRGL 1 2 3 and TRGL 4 5 6 (line 10) overlap in plan view around (4, 4): the surface is "
       "multi-valued"},
      {"folded.ts", KARST_EINVAL, "folded.ts:7: ",
       "TRGL 1 2 3 and TRGL 1 2 4 (line 8) lie on the same side of their shared edge (vertices 1 "
       "and 2) in plan view: the surface folds over itself"},
      {"vertical.ts", KARST_EINVAL, "vertical.ts:8: ",
       "TRGL 1 2 4 is vertical: its corners (0, 0, 0), (10, 0, 0) and (5, 0, 10) are collinear"},
      {"duplicate_id.ts", KARST_EPARSE,
       "duplicate_id.ts:5: ", "vertex id 1 is already used at line 3"},
      {"unknown_vertex.ts", KARST_EPARSE, "unknown_vertex.ts:7: ",
       "TRGL 2 3 9: vertex 9 is not defined by a VRTX, PVRTX, ATOM or PATOM"},
      {"nan.ts", KARST_EINVAL, "nan.ts:4: ", "VRTX 2: y must be a finite number, got 'nan'"},
      {"inf.ts", KARST_EINVAL, "inf.ts:4: ", "VRTX 2: x must be a finite number, got '1e999'"},
      {"step.ts", KARST_EINVAL, "step.ts:6: ",
       "vertex 4 at (10, 0) has z = 5 but vertex 2 (line 4) at the same x-y has z = 0: a vertical "
       "step"},
      {"truncated.ts", KARST_EPARSE, "truncated.ts:11: ",
       "TRGL needs three vertex ids, got 2 (the file ends in the middle of this line: "
       "truncated?)"},
      {"truncated_end.ts", KARST_EPARSE, "truncated_end.ts:11: ",
       "the file ends in the object begun at line 1, without END: a truncated file?"},
      {"huge_id.ts", KARST_ERANGE,
       "huge_id.ts:4: ", "VRTX: the vertex id '99999999999999999999' is out of range"},
      {"not_tsurf.ts", KARST_EPARSE,
       "not_tsurf.ts:1: ", "GOCAD PLine object: a surface file must hold GOCAD TSurf objects"},
      {"after_end.ts", KARST_EPARSE, "after_end.ts:8: ", "'VRTX' after END"},
      {"bad_zpositive.ts", KARST_EPARSE,
       "bad_zpositive.ts:3: ", "ZPOSITIVE must be Elevation or Depth, got 'Up'"},
      {"bad_unit.ts", KARST_EPARSE,
       "bad_unit.ts:3: ", "AXIS_UNIT: the unit of z must be m, km or ft"},
      {"short_pvrtx.ts", KARST_EPARSE,
       "short_pvrtx.ts:4: ", "PVRTX 1 has 1 property value, the PROPERTIES line declares 2"},
      {"bad_trgl.ts", KARST_EPARSE,
       "bad_trgl.ts:6: ", "TRGL: a vertex id must be a whole number >= 0, got 'x'"},
      {"atom_unknown.ts", KARST_EPARSE, "atom_unknown.ts:6: ",
       "ATOM 5 repeats vertex 42, which no VRTX, PVRTX, ATOM or PATOM of this object defines"},
      {"same_point.ts", KARST_EINVAL,
       "same_point.ts:6: ", "TRGL 1 2 3: vertices 2 and 3 are the same point (10, 0, 0)"},
      {"repeated_vertex.ts", KARST_EINVAL,
       "repeated_vertex.ts:5: ", "TRGL 1 1 2 names vertex 1 twice"},
      {"no_triangles.ts", KARST_EPARSE, "no_triangles.ts:6: ", "no TRGL triangles"},
      {"unclosed_header.ts", KARST_EPARSE,
       "unclosed_header.ts:5: ", "the file ends inside the block opened at line 2, without END"},
      {"empty.ts", KARST_EPARSE, "empty.ts:1: ", "empty file: expected 'GOCAD TSurf 1'"},
      {"huge.asc", KARST_ERANGE, "huge.asc:1:", "ncols = 1000000000 is more than the limit"},
  };
  for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
    karst_ctx_t ctx;
    karst_ctx_init(&ctx);
    char path[512];
    snprintf(path, sizeof path, DATA "bad/%s", cases[k].file);
    karst_surface_t *s = (karst_surface_t *)&ctx; /* must be reset to NULL */
    karst_error_t err = karst_surface_load(&ctx, path, &s);
    if (err != cases[k].code || !strstr(ctx.errmsg, cases[k].where) ||
        !strstr(ctx.errmsg, cases[k].what))
      print_error("%s: got %s '%s'\n", cases[k].file, karst_error_name(err), ctx.errmsg);
    assert_int_equal(err, cases[k].code);
    assert_non_null(strstr(ctx.errmsg, cases[k].where));
    assert_non_null(strstr(ctx.errmsg, cases[k].what));
    assert_non_null(strstr(ctx.errmsg, DATA "bad/")); /* the full path is named */
    assert_null(s);
  }
}

static void test_special_files(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_surface_t *s = NULL;
  /* a FIFO is refused without being opened (no blocking), a directory too */
  unlink(TMP "/fifo.ts");
  assert_int_equal(mkfifo(TMP "/fifo.ts", 0600), 0);
  assert_int_equal(karst_surface_load(&ctx, TMP "/fifo.ts", &s), KARST_EIO);
  assert_true(has(ctx.errmsg, "fifo.ts: is a FIFO (named pipe)"));
  assert_int_equal(karst_surface_load(&ctx, TMP, &s), KARST_EIO);
  assert_true(has(ctx.errmsg, "is a directory"));
  assert_int_equal(karst_surface_load(&ctx, TMP "/missing.ts", &s), KARST_EIO);
  assert_true(has(ctx.errmsg, "missing.ts: cannot open"));
  /* 64 KiB of pseudo-random bytes, under each extension and none */
  static char junk[65536];
  karst_rng_t rng;
  karst_rng_init(&rng, 17, 0);
  for (size_t k = 0; k < sizeof junk; k++)
    junk[k] = (char)(karst_rng_u64(&rng) & 0xFF);
  const char *names[3] = {TMP "/junk.ts", TMP "/junk.asc", TMP "/junk.bin"};
  for (int k = 0; k < 3; k++) {
    write_file(names[k], junk, sizeof junk);
    karst_error_t err = karst_surface_load(&ctx, names[k], &s);
    assert_true(err == KARST_EPARSE);
    assert_true(has(ctx.errmsg, names[k]));
    assert_null(s);
  }
  assert_true(has(ctx.errmsg, "not a surface file"));
  /* a NUL byte inside a line */
  const char nul[] = "GOCAD TSurf 1\nTFACE\nVRTX 1 0\0 0 0\nEND\n";
  write_file(TMP "/nul.ts", nul, sizeof nul - 1);
  assert_int_equal(karst_surface_load(&ctx, TMP "/nul.ts", &s), KARST_EPARSE);
  assert_true(has(ctx.errmsg, "nul.ts:3: a NUL byte"));
  /* every prefix of a valid file fails cleanly (or succeeds only once complete) */
  FILE *fp = fopen(DATA "two_parts.ts", "rb");
  assert_non_null(fp);
  static char whole[4096];
  size_t len = fread(whole, 1, sizeof whole, fp);
  fclose(fp);
  for (size_t cut = 0; cut < len; cut += 7) {
    write_file(TMP "/cut.ts", whole, cut);
    karst_error_t err = karst_surface_load(&ctx, TMP "/cut.ts", &s);
    assert_true(err == KARST_EPARSE || err == KARST_EINVAL);
    assert_true(has(ctx.errmsg, "cut.ts:"));
    assert_null(s);
  }
}

/* 3000 random mutations of two_parts.ts and of the plateau horizon's first
 * lines (a byte replaced, a line dropped, repeated or swapped, the file cut):
 * each is read without a crash (the ASan build runs this too) and either
 * accepted or refused with a message that names the file and a line. */
static void test_tsurf_mutations(void **state) {
  (void)state;
  static char src[2][8192], buf[16384];
  size_t len[2];
  const char *from[2] = {DATA "two_parts.ts", PLATEAU "fold_horizon.ts"};
  for (int f = 0; f < 2; f++) {
    FILE *fp = fopen(from[f], "rb");
    assert_non_null(fp);
    len[f] = fread(src[f], 1, sizeof src[f], fp);
    fclose(fp);
    if (f == 1) { /* the header, the first vertices and triangles of the second part, END */
      const char *tail = "TFACE\nATOM 3000 1\nVRTX 3001 -50 -10 120\nVRTX 3002 0 -10 121\n"
                         "TRGL 3000 2 3001\nTRGL 2 3002 3001\nTRGL 1 2 3000\nEND\n";
      char *cut = strstr(src[f], "PVRTX 4 ");
      assert_non_null(cut);
      size_t keep = (size_t)(cut - src[f]);
      memcpy(src[f] + keep, tail, strlen(tail));
      len[f] = keep + strlen(tail);
    }
  }
  static const char chars[] = "0123456789-+.eE \t\n{}:#ATOMVRXGLnaif\0\x01\xff";
  karst_rng_t rng;
  karst_rng_init(&rng, 20, 0);
  int accepted = 0;
  for (int k = 0; k < 3000; k++) {
    int f = k % 2;
    memcpy(buf, src[f], len[f]);
    size_t n = len[f];
    int op = (int)karst_rng_below(&rng, 5);
    size_t at = (size_t)karst_rng_below(&rng, n);
    if (op <= 1) { /* replace a byte (twice as often) */
      buf[at] = chars[karst_rng_below(&rng, sizeof chars - 1)];
    } else if (op == 4) { /* cut */
      n = at;
    } else { /* drop, repeat or swap the line holding at with the next one */
      size_t a = at;
      while (a > 0 && buf[a - 1] != '\n')
        a--;
      size_t b = at;
      while (b < n && buf[b] != '\n')
        b++;
      if (b < n) b++;
      size_t c = b;
      while (c < n && buf[c] != '\n')
        c++;
      if (c < n) c++;
      static char tmp[16384];
      if (op == 2) { /* drop */
        memmove(buf + a, buf + b, n - b);
        n -= b - a;
      } else if (op == 3 && k % 4 == 1) { /* repeat */
        memcpy(tmp, buf + a, b - a);
        memmove(buf + b + (b - a), buf + b, n - b);
        memcpy(buf + b, tmp, b - a);
        n += b - a;
      } else { /* swap with the next line */
        memcpy(tmp, buf + b, c - b);
        memcpy(tmp + (c - b), buf + a, b - a);
        memcpy(buf + a, tmp, c - a);
      }
    }
    write_file(TMP "/mut.ts", buf, n);
    karst_ctx_t ctx;
    karst_ctx_init(&ctx);
    karst_surface_t *s = NULL;
    karst_error_t err = karst_surface_load(&ctx, TMP "/mut.ts", &s);
    if (err == KARST_SUCCESS) {
      assert_non_null(s);
      accepted++;
      karst_surface_free(s);
      continue;
    }
    assert_null(s);
    if (!(err == KARST_EPARSE || err == KARST_EINVAL || err == KARST_ERANGE) ||
        !strstr(ctx.errmsg, TMP "/mut.ts:"))
      print_error("mutation %d: %s '%s'\n", k, karst_error_name(err), ctx.errmsg);
    assert_true(err == KARST_EPARSE || err == KARST_EINVAL || err == KARST_ERANGE);
    const char *named = strstr(ctx.errmsg, TMP "/mut.ts:");
    assert_non_null(named);
    assert_true(isdigit((unsigned char)named[strlen(TMP "/mut.ts:")])); /* a line number */
  }
  print_message("mutations: %d of 3000 still valid surfaces\n", accepted);
  assert_true(accepted > 100 && accepted < 2900); /* both outcomes were exercised */
}

/* From code: messages name the triangle by index. */
static void test_create_tin_errors(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_surface_t *s = NULL;
  const double line[9] = {0, 0, 0, 1, 1, 1, 2, 2, 5}; /* collinear in plan view */
  const karst_int_t t0[3] = {0, 1, 2};
  assert_int_equal(karst_surface_create_tin(&ctx, 3, line, 1, t0, &s), KARST_EINVAL);
  assert_true(has(ctx.errmsg, "triangle 0 (vertices 0, 1, 2) is vertical"));
  assert_int_equal(karst_surface_create_tin(&ctx, 3, line, 0, t0, &s), KARST_EINVAL);
  assert_true(has(ctx.errmsg, "needs at least one triangle"));
  /* not collinear, but so thin that its slope is 1e8 / 1e-300 = 1e308, beyond
   * KARST_SURFACE_MAX_SLOPE */
  const double thin[9] = {0, 0, 0, 1, 0, 0, 0.5, 1e-300, 1e8};
  assert_int_equal(karst_surface_create_tin(&ctx, 3, thin, 1, t0, &s), KARST_EINVAL);
  assert_true(has(ctx.errmsg, "triangle 0 (vertices 0, 1, 2) is vertical: its slope 1e+308 is "
                              "steeper than 1e+06"));
  /* a sliver 1 km long and 1 m wide, 1e5 m high at one corner: slope 1e5, accepted, and
   * its one-row index stays small */
  const double sliver[9] = {0, 0, 0, 1000, 0, 0, 0, 1, 1e5};
  assert_int_equal(karst_surface_create_tin(&ctx, 3, sliver, 1, t0, &s), KARST_SUCCESS);
  assert_close(karst_surface_lipschitz(s), 1e5, 1e-6);
  assert_close(karst_surface_z(s, 0, 0.5), 5e4, 1e-6);
  karst_surface_free(s);
  s = NULL;
  const karst_int_t t1[3] = {0, 1, 7};
  assert_int_equal(karst_surface_create_tin(&ctx, 3, line, 1, t1, &s), KARST_EINVAL);
  assert_true(has(ctx.errmsg, "triangle 0: vertex index 7 is outside [0, 3)"));
  const double far[9] = {0, 0, 0, 1, 0, 0, 0, 2e9, 0};
  assert_int_equal(karst_surface_create_tin(&ctx, 3, far, 1, t0, &s), KARST_EINVAL);
  assert_true(has(ctx.errmsg, "vertex 2: y must be a finite number within +-1e+09 m, got 2e+09"));
  /* identical triangles given twice: each edge is in more than two */
  const double sq[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const karst_int_t t2[6] = {0, 1, 2, 0, 2, 1};
  assert_int_equal(karst_surface_create_tin(&ctx, 3, sq, 2, t2, &s), KARST_EINVAL);
  assert_true(has(ctx.errmsg, "lie on the same side of their shared edge"));
  assert_null(s);
  /* a grid: a NaN cell is named */
  double z[4] = {0, 1, NAN, 2};
  assert_int_equal(karst_surface_create_grid(&ctx, 2, 2, 0, 0, 1, z, &s), KARST_EINVAL);
  assert_true(has(ctx.errmsg, "column 1, row 2 (from the south) must be finite, got nan"));
  assert_int_equal(karst_surface_create_grid(&ctx, 2, 2, 0, 0, 0, z, &s), KARST_EINVAL);
  assert_true(has(ctx.errmsg, "cellsize must be finite and > 0"));
}

/* ------------------------------------------------------------------------ */
/* Grids from files                                                          */
/* ------------------------------------------------------------------------ */

static void test_grid_file_is_terrain(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  const char *path = KARST_SOURCE_DIR "/datasets/scenarios/terrain/hillside.asc";
  karst_surface_t *s = NULL;
  assert_int_equal(karst_surface_load(&ctx, path, &s), KARST_SUCCESS);
  assert_int_equal(karst_surface_kind(s), KARST_SURFACE_GRID);
  karst_terrain_t t;
  memset(&t, 0, sizeof t);
  assert_int_equal(karst_terrain_load_grid(&ctx, path, &t), KARST_SUCCESS);
  karst_rng_t rng;
  karst_rng_init(&rng, 18, 0);
  for (int k = 0; k < 10000; k++) {
    double x = karst_rng_uniform_range(&rng, -100, 500),
           y = karst_rng_uniform_range(&rng, -100, 400);
    assert_true(karst_surface_z(s, x, y) == karst_terrain_height(&t, x, y)); /* to the bit */
  }
  assert_rel(karst_surface_lipschitz(s), t.lipschitz, 1e-14);
  double lo[3], hi[3];
  karst_surface_bounds(s, lo, hi);
  assert_close(lo[2], t.zmin, 0);
  assert_close(hi[2], t.zmax, 0);
  assert_close(lo[0], -12.5, 0); /* xllcenter 0, cellsize 25: cell edges from -12.5 */
  assert_close(hi[0], 16 * 25 + 12.5, 0);
  free(t.z);
  free(t.path);
  karst_surface_free(s);
}

/* ------------------------------------------------------------------------ */
/* The plateau scenario's surfaces                                           */
/* ------------------------------------------------------------------------ */

/* The generator's formulas (datasets/scenarios/plateau/make_surfaces.py). */
static double plateau_fold(double x, double y) {
  double d = x - (1000 + 40 * sin(2 * M_PI * y / 3000));
  return 250 - tan(8 * M_PI / 180) * (sqrt(d * d + 150 * 150) - 150);
}

static void test_plateau_surfaces(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  const double lo[2] = {0, 0}, hi[2] = {2000, 1500};
  karst_i_tsurf_t ts;
  assert_int_equal(karst_i_tsurf_read(&ctx, PLATEAU "fold_horizon.ts", &ts), KARST_SUCCESS);
  assert_int_equal(ts.nparts, 2);
  assert_int_equal(ts.natoms, 41); /* the shared column, one ATOM a row */
  assert_int_equal(ts.nt, 2 * 54 * 40);
  assert_int_equal(ts.nprops, 1);
  assert_string_equal(ts.prop_names[0], "dip");
  karst_i_tsurf_destroy(&ts);
  karst_surface_t *f = NULL;
  assert_int_equal(karst_surface_load(&ctx, PLATEAU "fold_horizon.ts", &f), KARST_SUCCESS);
  assert_string_equal(karst_surface_name(f), "H1_inception_anticline");
  assert_int_equal(karst_surface_check_covers(&ctx, f, lo, hi, "inception horizon"), KARST_SUCCESS);
  /* Interpolation bound (M/2) R^2: |Hessian| <= |g''| (1 + a'^2) + |g'| |a''| with
   * g'' <= tan 8 / 150 = 9.37e-4, a' <= 0.0838, a'' <= 1.75e-4, g' <= tan 8:
   * M <= 9.68e-4 /m; the largest cells are 50 x 40 m, R^2 = (50^2 + 40^2) / 4:
   * 0.496 m; the file rounds z to 0.1 mm. */
  double bound = 9.68e-4 / 2 * (50.0 * 50 + 40 * 40) / 4 + 1e-4;
  karst_rng_t rng;
  karst_rng_init(&rng, 19, 0);
  double err = 0;
  for (int k = 0; k < 20000; k++) {
    double x = karst_rng_uniform_range(&rng, 0, 2000), y = karst_rng_uniform_range(&rng, 0, 1500);
    err = fmax(err, fabs(karst_surface_z(f, x, y) - plateau_fold(x, y)));
  }
  print_message("plateau fold: max error %.4f m (bound %.4f)\n", err, bound);
  assert_true(err <= bound);
  /* crest 250 m on the axis; limbs dipping towards 8 degrees: at d = 900 m the dip
   * is atan(tan 8 * 900 / sqrt(900^2 + 150^2)) = 7.89 degrees, down to the east */
  assert_close(karst_surface_z(f, 1000, 0), 250, 1e-3);
  double g[2];
  karst_surface_gradient(f, 1900 + 40 * sin(2 * M_PI * 700 / 3000.0), 700, g);
  assert_close(atan(hypot(g[0], g[1])) * 180 / M_PI, 7.89, 0.1);
  assert_true(g[0] < 0);
  karst_surface_gradient(f, 100, 700, g);
  assert_true(g[0] > 0);
  karst_surface_free(f);

  karst_surface_t *w = NULL;
  assert_int_equal(karst_surface_load(&ctx, PLATEAU "water_table.asc", &w), KARST_SUCCESS);
  assert_int_equal(karst_surface_kind(w), KARST_SURFACE_GRID);
  assert_int_equal(karst_surface_check_covers(&ctx, w, lo, hi, "water table"), KARST_SUCCESS);
  /* z = 150 + 70 (1 - s)^1.2 + 2 sin(2 pi x / 1000) sin(2 pi y / 900): 220 m at the
   * north-west corner (s = 0), 150 m at the south-east (s = 1) */
  assert_close(karst_surface_z(w, 0, 1500), 220, 0.005);
  assert_close(karst_surface_z(w, 2000, 0), 150, 0.005);
  double bl[3], bh[3];
  karst_surface_bounds(w, bl, bh);
  assert_close(bh[2], 220, 0.5);
  assert_close(bl[2], 150, 0.5);
  karst_surface_gradient(w, 1000, 750, g); /* down towards the south-east */
  assert_true(g[0] < 0 && g[1] > 0);
  karst_surface_free(w);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_plane_basics),
      cmocka_unit_test(test_plane_three_ways),
      cmocka_unit_test(test_segment_touching),
      cmocka_unit_test(test_grid_quadratic_piece),
      cmocka_unit_test(test_fold),
      cmocka_unit_test(test_bucket_vs_brute),
      cmocka_unit_test(test_segment_pieces),
      cmocka_unit_test(test_extremes),
      cmocka_unit_test(test_covers),
      cmocka_unit_test(test_triangulate),
      cmocka_unit_test(test_tsurf_two_parts),
      cmocka_unit_test(test_tsurf_variants),
      cmocka_unit_test(test_tsurf_hostile),
      cmocka_unit_test(test_special_files),
      cmocka_unit_test(test_tsurf_mutations),
      cmocka_unit_test(test_create_tin_errors),
      cmocka_unit_test(test_grid_file_is_terrain),
      cmocka_unit_test(test_plateau_surfaces),
  };
  return cmocka_run_group_tests(tests, setup, NULL);
}
