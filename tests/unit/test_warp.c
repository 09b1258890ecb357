/* The gradient-based warping node (src/implicit/warp.c, Paris et al. 2020,
 * §4.3): the paper's formula checked by hand on planes (where the child's
 * gradient is exact), every relief kind and both modes 1-Lipschitz on random
 * pairs, zero amplitude exact, image reliefs read from a file, fracture
 * grooves along their planes, bad parameters refused. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "implicit/implicit_internal.h"
#include "karst.h"
#include "sdf_check.h"
#include "test_util.h"

/* A caller's relief, sin(u/0.7) cos(v/0.9): |∇| <= hypot(1/0.7, 1/0.9). */
static double wave(const void *user, double u, double v) {
  (void)user;
  return sin(u / 0.7) * cos(v / 0.9);
}
static const double WAVE_LIP = 1.8104; /* hypot(1/0.7, 1/0.9) = 1.81035..., rounded up */

/* The top face z = 0 of a large box: near its middle the box distance is z,
 * linear, so the finite-difference gradient is exactly e_z and the paper's
 * weights are α = (0, 0, 1): the warped field times 1 + L_δ is exactly
 * z + A d(x, y), and the warped surface is z = -A d(x, y). On the tilted
 * terrain plane z = 0.5 x (exact distance (z - 0.5 x)/√1.25, gradient
 * g = (-0.5, 0, 1)/√1.25), α = (0.4472, 0, 0.8944) and the field times 1 + L_δ
 * is c(p) + A (|g_x| d(y, z) + |g_z| d(x, y)) (c linear, |g| = 1). */
static void test_warp_planes_by_hand(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  double lo[3] = {-50, -50, -50}, hi[3] = {50, 50, 0};
  karst_int_t box, w;
  assert_int_equal(karst_sdf_box(&ctx, t, lo, hi, &box), KARST_SUCCESS);
  karst_relief_t r;
  karst_relief_init(&r, KARST_RELIEF_FUNCTION);
  r.fn = wave;
  r.fn_lipschitz = WAVE_LIP;
  r.amplitude = 0.3;
  assert_int_equal(karst_sdf_warp(&ctx, t, box, &r, NULL, NULL, &w), KARST_SUCCESS);
  double L = karst_sdf_warp_lipschitz(t, w);
  /* hand: ε = 0.2, m = 0.5: L_g = 10; L_δ = 2√3 0.3 10 + √2 0.3 WAVE_LIP */
  assert_close(L, 1 + 2 * sqrt(3.0) * 0.3 * 10 + sqrt(2.0) * 0.3 * WAVE_LIP, 1e-12);
  karst_rng_t rng;
  karst_rng_init(&rng, 4, 0);
  for (int i = 0; i < 500; i++) {
    double p[3] = {karst_rng_uniform_range(&rng, -10, 10), karst_rng_uniform_range(&rng, -10, 10),
                   karst_rng_uniform_range(&rng, -2, -0.5)};
    double f = karst_sdf_eval_node(t, w, p, NULL, NULL);
    assert_close(f * L, p[2] + 0.3 * wave(NULL, p[0], p[1]), 1e-12);
    double s[3] = {p[0], p[1], -0.3 * wave(NULL, p[0], p[1])};
    assert_close(karst_sdf_eval_node(t, w, s, NULL, NULL), 0, 1e-12);
  }

  /* the tilted plane */
  karst_terrain_t tilt;
  memset(&tilt, 0, sizeof tilt);
  tilt.is_grid = 1;
  tilt.ncols = 41, tilt.nrows = 41, tilt.cellsize = 1, tilt.xll = -20, tilt.yll = -20;
  double *z = malloc(41 * 41 * sizeof *z);
  assert_non_null(z);
  for (int j = 0; j < 41; j++)
    for (int i = 0; i < 41; i++)
      z[j * 41 + i] = 0.5 * (-20 + i);
  tilt.z = z;
  karst_int_t plane, w2;
  assert_int_equal(karst_sdf_terrain(&ctx, t, &tilt, &plane), KARST_SUCCESS);
  assert_int_equal(karst_sdf_warp(&ctx, t, plane, &r, NULL, NULL, &w2), KARST_SUCCESS);
  double gx = -0.5 / sqrt(1.25), gz = 1 / sqrt(1.25);
  for (int i = 0; i < 500; i++) {
    double p[3] = {karst_rng_uniform_range(&rng, -8, 8), karst_rng_uniform_range(&rng, -8, 8), 0};
    p[2] = 0.5 * p[0] + karst_rng_uniform_range(&rng, -1, 1);
    double c = (p[2] - 0.5 * p[0]) / sqrt(1.25);
    double want = c + 0.3 * (fabs(gx) * wave(NULL, p[1], p[2]) + fabs(gz) * wave(NULL, p[0], p[1]));
    assert_close(karst_sdf_eval_node(t, w2, p, NULL, NULL) * L, want, 1e-9);
  }
  free(z);
  karst_sdf_free(t);
}

/* A relief image written as PGM and read back: on the flat face the warped
 * surface passes through z = -A (2 v_ij - 1) above each pixel centre (x, y) =
 * (i, -j) / (pixels per metre), values by hand; the image repeats every
 * tile metres. */
static void test_warp_image(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  const int W = 4, H = 3;
  const int px[3][4] = {{0, 255, 128, 64}, {32, 200, 10, 250}, {90, 90, 180, 0}};
  char path[] = "/tmp/karst_relief_XXXXXX";
  int fd = mkstemp(path);
  assert_true(fd >= 0);
  FILE *f = fdopen(fd, "wb");
  fprintf(f, "P5\n# relief\n%d %d\n255\n", W, H);
  for (int j = 0; j < H; j++)
    for (int i = 0; i < W; i++)
      fputc(px[j][i], f);
  fclose(f);
  karst_image_t img;
  karst_image_init(&img);
  assert_int_equal(karst_image_read(&ctx, path, &img), KARST_SUCCESS);
  remove(path);
  assert_int_equal(img.width, W);
  assert_int_equal(img.height, H);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  double lo[3] = {-50, -50, -50}, hi[3] = {50, 50, 0};
  karst_int_t box, w;
  karst_sdf_box(&ctx, t, lo, hi, &box);
  karst_relief_t r;
  karst_relief_init(&r, KARST_RELIEF_IMAGE);
  r.image = &img;
  r.tile = 2.0; /* 4 pixels over 2 m: 2 pixels per metre */
  r.amplitude = 0.1;
  assert_int_equal(karst_sdf_warp(&ctx, t, box, &r, NULL, NULL, &w), KARST_SUCCESS);
  karst_image_destroy(&img); /* the tree keeps its own copy */
  for (int rep = -1; rep <= 1; rep++)
    for (int j = 0; j < H; j++)
      for (int i = 0; i < W; i++) {
        double x = i / 2.0 + rep * 2.0, y = -j / 2.0 - rep * 1.5; /* tiles of 2 x 1.5 m */
        double hgt = -0.1 * (2 * px[j][i] / 255.0 - 1);
        double s[3] = {x, y, hgt};
        assert_close(karst_sdf_eval_node(t, w, s, NULL, NULL), 0, 1e-7);
        double pr[3] = {x, y, 0};
        assert_close(karst_sdf_warp_relief(t, w, pr), -hgt, 1e-7);
      }
  /* L_d by hand: the largest bilinear gradient of the tiled image, grey levels per pixel, is at
   * the cell of (255, 128 / 200, 10) ... every cell checked by the code; here only that the bound
   * covers the steepest single step, 250 - 10 = 240 grey levels over one pixel */
  double L = karst_sdf_warp_lipschitz(t, w);
  assert_true(L - 1 >= sqrt(2.0) * 0.1 * 2 * (240 / 255.0) * 2);
  assert_lipschitz(t, w, 1, 3000, "image warp of a box");
  karst_sdf_free(t);
}

/* Fracture grooves: a single vertical family (normal x) on the flat face
 * makes the relief a function of x only, in [-A, 0], reaching -A at the
 * groove centres (one per spacing on average). */
static void test_warp_fractures(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  double lo[3] = {-500, -50, -50}, hi[3] = {500, 50, 0};
  karst_int_t box, w;
  karst_sdf_box(&ctx, t, lo, hi, &box);
  karst_relief_t r;
  karst_relief_init(&r, KARST_RELIEF_FRACTURES);
  r.n_planes = 1;
  r.normals[0][0] = 3; /* normalised by the node */
  r.weights[0] = 2;
  r.spacing = 2;
  r.width = 0.25;
  r.amplitude = 0.2;
  karst_rng_t rng;
  karst_rng_init(&rng, 9, 0);
  assert_int_equal(karst_sdf_warp(&ctx, t, box, &r, NULL, &rng, &w), KARST_SUCCESS);
  double lowest = 0;
  int grooves = 0, in = 0;
  for (int i = 0; i < 400000; i++) {
    double x = -400 + i * 0.002;
    double p[3] = {x, 3.7, -1}, q[3] = {x, -11.2, -2};
    double d = karst_sdf_warp_relief(t, w, p);
    assert_true(d >= -0.2 && d <= 0);
    assert_close(d, karst_sdf_warp_relief(t, w, q), 0);
    lowest = fmin(lowest, d);
    int now = d < -0.1;
    grooves += now && !in;
    in = now;
  }
  printf("fracture grooves: %d over 800 m at spacing 2 m, deepest %.6f m\n", grooves, lowest);
  assert_close(lowest, -0.2, 1e-4);
  /* 400 fractures expected; adjacent ones may merge into one groove */
  assert_true(grooves > 300 && grooves <= 400);
  assert_lipschitz(t, w, 1, 3000, "fracture warp of a box");
  karst_sdf_free(t);
}

/* Every relief kind, in both modes, over a union of a sphere, a keyhole sweep
 * and an ellipsoid (creases where the gradient jumps) and over a blend: the
 * warped field is 1-Lipschitz on random pairs near and far from the surface.
 * With amplitude 0 the node is its child, value for value. Far from the
 * surface in band mode it is the child shifted by rc (1 - 1/L). */
static void test_warp_lipschitz(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  karst_int_t sp, sw, el, un, bl;
  double c[3] = {0, 0, 0}, a[3] = {-3, 0.5, 0}, b[3] = {4, -1, 1};
  karst_sdf_sphere(&ctx, t, c, 1.6, 0, &sp);
  karst_section_t s;
  karst_section_for_type(&ctx, KARST_TUNNEL_KEYHOLE, &s);
  karst_sdf_sweep(&ctx, t, a, b, &s, 1.2, NULL, NULL, 1, &sw);
  double axes[3][3] = {{0.6, 0.8, 0}, {-0.8, 0.6, 0}, {0, 0, 1}}, radii[3] = {3, 1.2, 0.7};
  double ce[3] = {1, 2, -0.5};
  karst_sdf_ellipsoid(&ctx, t, ce, (const double(*)[3])axes, radii, 6, &el);
  karst_int_t kids[3] = {sp, sw, el};
  karst_sdf_union(&ctx, t, 3, kids, &un);
  karst_sdf_blend(&ctx, t, sp, sw, 1.0, &bl);
  karst_image_t img;
  img.width = 5, img.height = 4;
  float pix[20];
  karst_rng_t rng;
  karst_rng_init(&rng, 21, 0);
  for (int i = 0; i < 20; i++)
    pix[i] = (float)karst_rng_uniform(&rng);
  img.v = pix;
  for (int kind = 0; kind < KARST_RELIEF_KIND_COUNT; kind++)
    for (int mode = 0; mode < 2; mode++)
      for (int child = 0; child < 2; child++) {
        karst_relief_t r;
        karst_relief_init(&r, (karst_relief_kind_t)kind);
        r.amplitude = kind == KARST_RELIEF_FRACTURES ? -0.25 : 0.15;
        r.wavelength = 0.8;
        r.image = &img;
        r.tile = 1.3;
        r.fn = wave;
        r.fn_lipschitz = WAVE_LIP;
        r.n_planes = 2;
        r.normals[0][2] = 1;
        r.normals[1][0] = 1, r.normals[1][1] = 1;
        r.weights[0] = 1, r.weights[1] = 0.5;
        r.spacing = 1.1;
        r.width = 0.3;
        karst_warp_params_t par;
        karst_warp_params_init(&par);
        if (mode) par.band = 0.5;
        karst_int_t w;
        assert_int_equal(karst_sdf_warp(&ctx, t, child ? bl : un, &r, &par, &rng, &w),
                         KARST_SUCCESS);
        char what[96];
        snprintf(what, sizeof what, "warp: relief %d, %s, over a %s", kind,
                 mode ? "band 0.5 m" : "everywhere", child ? "blend" : "union");
        assert_lipschitz(t, w, 2, 3000, what);
      }
  /* zero amplitude: the child exactly */
  karst_relief_t r0;
  karst_relief_init(&r0, KARST_RELIEF_NOISE);
  r0.amplitude = 0;
  karst_int_t w0, wb;
  assert_int_equal(karst_sdf_warp(&ctx, t, un, &r0, NULL, &rng, &w0), KARST_SUCCESS);
  assert_true(karst_sdf_warp_lipschitz(t, w0) == 1);
  /* band mode far from the surface */
  karst_relief_t rn;
  karst_relief_init(&rn, KARST_RELIEF_NOISE);
  rn.amplitude = 0.1;
  karst_warp_params_t pb;
  karst_warp_params_init(&pb);
  pb.band = 0.4;
  assert_int_equal(karst_sdf_warp(&ctx, t, un, &rn, &pb, &rng, &wb), KARST_SUCCESS);
  double L = karst_sdf_warp_lipschitz(t, wb), rc = 0.4 + sqrt(3.0) * 0.1, wbox[6];
  karst_sdf_node_box(t, wb, wbox);
  for (int i = 0; i < 2000; i++) {
    double p[3] = {karst_rng_uniform_range(&rng, -8, 8), karst_rng_uniform_range(&rng, -8, 8),
                   karst_rng_uniform_range(&rng, -5, 5)};
    double f = karst_sdf_eval_node(t, un, p, NULL, NULL);
    assert_true(karst_sdf_eval_node(t, w0, p, NULL, NULL) == f);
    double g = karst_sdf_eval_node(t, wb, p, NULL, NULL);
    /* (every node is clamped from below by its box distance) */
    if (fabs(f) > rc)
      assert_close(g, fmax(f - (f > 0 ? 1 : -1) * rc * (1 - 1 / L), karst_i_sdbox(wbox, p)), 1e-12);
    if (fabs(f) < 0.4 - 1e-9) assert_true(fabs(g) <= rc / L);
  }
  karst_sdf_free(t);
}

/* A polygonized warped sphere is closed and manifold, same for 1 and 2
 * threads, and its volume moves with the relief's mean (0 for this noise,
 * within the voxel error): the warp node in a real mesh. */
static void test_warp_mesh(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  double c[3] = {0.1, 0.2, 0.3};
  karst_int_t sp, w;
  karst_sdf_sphere(&ctx, t, c, 2.5, 0, &sp);
  karst_relief_t r;
  karst_relief_init(&r, KARST_RELIEF_NOISE);
  r.amplitude = 0.15;
  r.wavelength = 1.5;
  karst_rng_t rng;
  karst_rng_init(&rng, 5, 0);
  karst_warp_params_t par;
  karst_warp_params_init(&par);
  par.band = 0.5;
  assert_int_equal(karst_sdf_warp(&ctx, t, sp, &r, &par, &rng, &w), KARST_SUCCESS);
  karst_sdf_set_root(&ctx, t, w);
  double box[6] = {-3.5, -3.5, -3.5, 3.5, 3.5, 3.5};
  karst_mesh_t m1, m2;
  karst_mesh_init(&m1);
  karst_mesh_init(&m2);
  ctx.nthreads = 1;
  assert_int_equal(karst_mesh_polygonize(&ctx, t, box, 0.1, &m1, NULL), KARST_SUCCESS);
  ctx.nthreads = 2;
  assert_int_equal(karst_mesh_polygonize(&ctx, t, box, 0.1, &m2, NULL), KARST_SUCCESS);
  assert_int_equal(m1.n_triangles, m2.n_triangles);
  assert_memory_equal(m1.xyz, m2.xyz, (size_t)m1.n_vertices * 3 * sizeof(double));
  karst_mesh_check_t chk;
  assert_int_equal(karst_mesh_check(&ctx, &m1, &chk), KARST_SUCCESS);
  assert_int_equal(chk.boundary_edges + chk.nonmanifold_edges + chk.degenerate, 0);
  double v = karst_mesh_volume(&m1), v0 = 4.0 / 3.0 * M_PI * 2.5 * 2.5 * 2.5;
  printf("warped sphere: %lld triangles, volume %.3f m3 (sphere %.3f)\n", (long long)m1.n_triangles,
         v, v0);
  /* the surface moves by at most √3 A = 0.26 m: the volume within that shell */
  assert_true(fabs(v - v0) < 4 * M_PI * 2.5 * 2.5 * sqrt(3.0) * 0.15);
  assert_true(fabs(v - v0) > 1e-3); /* and it did move */
  karst_mesh_destroy(&m1);
  karst_mesh_destroy(&m2);
  karst_sdf_free(t);
}

static void test_warp_errors(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  double c[3] = {0, 0, 0};
  karst_int_t sp, w;
  karst_sdf_sphere(&ctx, t, c, 1, 0, &sp);
  karst_rng_t rng;
  karst_rng_init(&rng, 1, 0);
  karst_relief_t r;
  karst_relief_init(&r, KARST_RELIEF_NOISE);
  assert_int_equal(karst_sdf_warp(&ctx, t, 99, &r, NULL, &rng, &w), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "node 99"));
  assert_int_equal(karst_sdf_warp(&ctx, t, sp, &r, NULL, NULL, &w), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "generator"));
  r.octaves = 9;
  assert_int_equal(karst_sdf_warp(&ctx, t, sp, &r, NULL, &rng, &w), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "octaves 9"));
  r.octaves = 2;
  r.wavelength = -1;
  assert_int_equal(karst_sdf_warp(&ctx, t, sp, &r, NULL, &rng, &w), KARST_EINVAL);
  r.wavelength = 1;
  r.amplitude = NAN;
  assert_int_equal(karst_sdf_warp(&ctx, t, sp, &r, NULL, &rng, &w), KARST_EINVAL);
  r.amplitude = 0.1;
  karst_warp_params_t par;
  karst_warp_params_init(&par);
  par.grad_floor = 1.5;
  assert_int_equal(karst_sdf_warp(&ctx, t, sp, &r, &par, &rng, &w), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "grad_floor 1.5"));
  karst_warp_params_init(&par);
  par.epsilon = 0;
  assert_int_equal(karst_sdf_warp(&ctx, t, sp, &r, &par, &rng, &w), KARST_EINVAL);
  karst_warp_params_init(&par);
  par.band = -2;
  assert_int_equal(karst_sdf_warp(&ctx, t, sp, &r, &par, &rng, &w), KARST_EINVAL);
  karst_relief_init(&r, KARST_RELIEF_IMAGE);
  assert_int_equal(karst_sdf_warp(&ctx, t, sp, &r, NULL, &rng, &w), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "image"));
  karst_image_t img = {2, 1, NULL};
  float v[2] = {0.5f, 1.5f};
  img.v = v;
  r.image = &img;
  assert_int_equal(karst_sdf_warp(&ctx, t, sp, &r, NULL, &rng, &w), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "pixel 1"));
  karst_relief_init(&r, KARST_RELIEF_FUNCTION);
  assert_int_equal(karst_sdf_warp(&ctx, t, sp, &r, NULL, &rng, &w), KARST_EINVAL);
  karst_relief_init(&r, KARST_RELIEF_FRACTURES);
  r.n_planes = 1;
  assert_int_equal(karst_sdf_warp(&ctx, t, sp, &r, NULL, &rng, &w), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "normal"));
  r.normals[0][1] = 1;
  assert_int_equal(karst_sdf_warp(&ctx, t, sp, &r, NULL, &rng, &w), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "weights"));
  r.weights[0] = 1;
  r.width = 100;
  assert_int_equal(karst_sdf_warp(&ctx, t, sp, &r, NULL, &rng, &w), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "width 100"));
  r.width = 0.3;
  assert_int_equal(karst_sdf_warp(&ctx, t, sp, &r, NULL, &rng, &w), KARST_SUCCESS);
  karst_sdf_free(t);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_warp_planes_by_hand), cmocka_unit_test(test_warp_image),
      cmocka_unit_test(test_warp_fractures),      cmocka_unit_test(test_warp_lipschitz),
      cmocka_unit_test(test_warp_mesh),           cmocka_unit_test(test_warp_errors),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
