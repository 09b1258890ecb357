/* Geometric details of Zanni et al. 2012 (src/implicit/details.c): with
 * amplitude 0 the field is the child's exactly; details change the field
 * only in the shell [iso-, iso+] and move the surface by at most the
 * amplitude; the noise's spectral peak lies along ω (2-D FFT of a sampled
 * patch); frames follow the skeleton on tubes and fade at the singularity
 * (Wd ∥ ∇f); parameters blend by the skeleton's field contributions; every
 * configuration is 1-Lipschitz on random pairs. */
#include <complex.h>
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

static const karst_i_details_t *details_of(const karst_sdf_t *t, karst_int_t node) {
  return &t->details[t->nodes[node].u.warp.index];
}

/* The rescaling of the node (the inverse of details.c's squash). */
static double unsquash(const karst_i_details_t *d, double y) {
  if (fabs(y) * d->lip <= d->rc) return y * d->lip;
  double off = d->rc * (1 - 1 / d->lip);
  return y > 0 ? y + off : y - off;
}

static karst_wall_details_t flutes(double amp, double lambda, double omega, double aniso) {
  karst_wall_details_t w = {amp, lambda, 0.5, omega, aniso, 0, 0};
  return w;
}

/* A big box whose top face z = 0 is the wall, a long skeleton segment along
 * x below it: the frame is n = e_z, t = e_x, b = e_y. */
static karst_sdf_t *face(karst_details_params_t *par, karst_int_t *node, uint64_t seed) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  double lo[3] = {-100, -100, -50}, hi[3] = {100, 100, 0};
  karst_int_t box;
  karst_sdf_box(&ctx, t, lo, hi, &box);
  karst_skeleton_segment_t s = {{-90, 0, -1}, {90, 0, -1}, 60, KARST_TUNNEL_CANYON};
  karst_rng_t rng;
  karst_rng_init(&rng, seed, 0);
  assert_int_equal(karst_sdf_details(&ctx, t, box, par, &s, 1, &rng, node), KARST_SUCCESS);
  return t;
}

/* Radix-2 FFT in place (n a power of two), sign -1. */
static void fft(double complex *a, int n, int stride) {
  for (int i = 1, j = 0; i < n; i++) {
    int bit = n >> 1;
    for (; j & bit; bit >>= 1)
      j ^= bit;
    j ^= bit;
    if (i < j) {
      double complex x = a[i * stride];
      a[i * stride] = a[j * stride];
      a[j * stride] = x;
    }
  }
  for (int len = 2; len <= n; len <<= 1) {
    double complex w = cexp(-2 * M_PI * I / len);
    for (int i = 0; i < n; i += len) {
      double complex u = 1;
      for (int k = 0; k < len / 2; k++) {
        double complex x = a[(i + k) * stride], y = a[(i + k + len / 2) * stride] * u;
        a[(i + k) * stride] = x + y;
        a[(i + k + len / 2) * stride] = x - y;
        u *= w;
      }
    }
  }
}

/* The noise sampled on a 256² patch of the face at λ/8 (a 32 λ square), its
 * 2-D FFT: the strongest frequency, averaged over the 5 x 5 bins around the
 * peak, lies along ω (in the frame t = e_x, b = e_y) within 5° (bins are
 * 1/32 of the frequency apart: 1.8° at the ring of radius F) and at 1/λ within
 * 10 %, for ω = 30° and -60°. Isotropic noise (anisotropy 0) has no such
 * direction: the energy in a 20° sector around ω is close to its share. */
static void test_spectral_peak(void **state) {
  (void)state;
  enum { N = 256 };
  const double lambda = 0.4, h = lambda / 8;
  double complex *a = malloc(sizeof(double complex) * N * N);
  assert_non_null(a);
  const double omegas[3] = {30, -60, 30}, aniso[3] = {1, 1, 0};
  for (int c = 0; c < 3; c++) {
    karst_details_params_t par;
    karst_details_params_init(&par);
    par.type[KARST_TUNNEL_CANYON] = flutes(0.05, lambda, omegas[c], aniso[c]);
    karst_int_t node;
    karst_sdf_t *t = face(&par, &node, 17);
    double fr[3][3];
    double p0[3] = {0.3, 0.2, 0};
    karst_sdf_details_noise(t, node, p0, fr);
    assert_close(fr[0][2], 1, 1e-9); /* n */
    assert_close(fr[1][0], 1, 1e-9); /* t */
    assert_close(fr[2][1], 1, 1e-9); /* b */
    double mean = 0;
    for (int j = 0; j < N; j++)
      for (int i = 0; i < N; i++) {
        double p[3] = {i * h - 6, j * h - 6, 0};
        a[j * N + i] = karst_sdf_details_noise(t, node, p, NULL);
        mean += creal(a[j * N + i]);
      }
    mean /= N * N;
    for (int k = 0; k < N * N; k++)
      a[k] -= mean;
    for (int j = 0; j < N; j++)
      fft(a + j * N, N, 1);
    for (int i = 0; i < N; i++)
      fft(a + i, N, N);
    double best = 0, kx = 0, ky = 0, sector = 0, total = 0;
    int bi = 0, bj = 0;
    for (int j = 0; j < N; j++)
      for (int i = 0; i < N; i++) {
        int fi = i < N / 2 ? i : i - N, fj = j < N / 2 ? j : j - N;
        double e = cabs(a[j * N + i]) * cabs(a[j * N + i]);
        if (fi == 0 && fj == 0) continue;
        total += e;
        double ang = atan2((double)fj, (double)fi) * 180 / M_PI;
        double dd = fmod(fabs(ang - omegas[c]) + 360, 180);
        if (fmin(dd, 180 - dd) < 10) sector += e;
        if (e > best) best = e, bi = fi, bj = fj;
      }
    double wsum = 0;
    for (int dj = -2; dj <= 2; dj++)
      for (int di = -2; di <= 2; di++) {
        int i = (bi + di + N) % N, j = (bj + dj + N) % N;
        double e = cabs(a[j * N + i]) * cabs(a[j * N + i]);
        kx += e * (bi + di), ky += e * (bj + dj), wsum += e;
      }
    kx /= wsum * N * h, ky /= wsum * N * h; /* cycles per metre */
    double ang = atan2(ky, kx) * 180 / M_PI, freq = hypot(kx, ky);
    double dd = fmod(fabs(ang - omegas[c]) + 360, 180);
    dd = fmin(dd, 180 - dd);
    printf("ω = %g°, anisotropy %g: peak at %.1f° (off by %.1f°), %.3f cycles/m (1/λ = %.3f); "
           "%.0f %% of the energy within 10° of ω\n",
           omegas[c], aniso[c], ang, dd, freq, 1 / lambda, 100 * sector / total);
    if (aniso[c] == 1) {
      assert_true(dd < 5);
      assert_rel(freq, 1 / lambda, 0.10);
      assert_true(sector / total > 0.5);
    } else {
      assert_true(sector / total < 0.25); /* a 20° sector of 180°: 11 % when isotropic */
    }
    karst_sdf_free(t);
  }
  free(a);
}

/* With every amplitude 0 the node returns its child's value, bit for bit.
 * With details, outside the shell the field is the child's rescaled (the
 * linear band) and beyond it the child's shifted; the sign changes only
 * where |f_S| <= the amplitude (the surface moves by at most that); and
 * details really move it somewhere. */
static void test_shell(void **state) {
  (void)state;
  karst_details_params_t par;
  karst_details_params_init(&par);
  karst_int_t z, d;
  karst_sdf_t *t0 = face(&par, &z, 1);
  par.type[KARST_TUNNEL_CANYON] = flutes(0.04, 0.3, 20, 0.8);
  karst_sdf_t *t = face(&par, &d, 1);
  const karst_i_details_t *dd = details_of(t, d);
  assert_close(dd->shell, KARST_DETAILS_SHELL_FACTOR * 0.04, 1e-15);
  assert_true(karst_sdf_details_lipschitz(t0, z) == 1);
  printf("details of 4 cm at 30 cm: L = %.1f, shell %.2f m, band %.3f m\n", dd->lip, dd->shell,
         dd->rc);
  double nbox[6];
  karst_sdf_node_box(t, d, nbox);
  karst_rng_t r;
  karst_rng_init(&r, 2, 0);
  int moved = 0;
  double sum2 = 0;
  long nsum = 0;
  for (int i = 0; i < 20000; i++) {
    double p[3] = {karst_rng_uniform_range(&r, -20, 20), karst_rng_uniform_range(&r, -20, 20),
                   karst_rng_uniform_range(&r, -0.6, 0.6)};
    if (i % 2) p[2] *= 0.1;
    double fs = karst_sdf_eval_node(t, 0, p, NULL, NULL);
    assert_true(karst_sdf_eval_node(t0, z, p, NULL, NULL) == fs);
    double f = karst_sdf_eval_node(t, d, p, NULL, NULL), u = unsquash(dd, f);
    if (fabs(fs) > 0.04 * (1 + 1e-9)) assert_true((f < 0) == (fs < 0));
    if ((f < 0) != (fs < 0)) moved++;
    /* (every node is clamped from below by the distance to its box) */
    if (karst_i_sdbox(nbox, p) >= f) continue;
    if (fabs(fs) >= dd->shell) assert_close(u, fs, 1e-12);
    assert_true(fabs(u - fs) <= dd->hmax * (1 + 1e-12));
    if (fabs(fs) < 1e-3) sum2 += (u - fs) * (u - fs), nsum++;
  }
  printf("%d of 20000 points changed side; RMS change of the field at the wall %.4f m "
         "(amplitude 0.04 m)\n",
         moved, sqrt(sum2 / nsum));
  assert_true(moved > 100);
  karst_sdf_free(t0);
  karst_sdf_free(t);
}

/* A straight tube along x: on its wall the frame's t is the skeleton
 * direction (Zanni §3: "t tends to be in the same direction as the weighted
 * direction"); on the end cap's axis n ∥ Wd, the singularity: anisotropic
 * details fade out there and the field is the child's. */
static void test_frames_and_fade(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  double a[3] = {0, 0, 0}, b[3] = {20, 0, 0};
  karst_section_t s;
  karst_section_for_type(&ctx, KARST_TUNNEL_TUBE, &s);
  karst_int_t tube, d;
  karst_sdf_sweep(&ctx, t, a, b, &s, 2, NULL, NULL, 0, &tube);
  karst_details_params_t par;
  karst_details_params_init(&par);
  par.type[0] = flutes(0.05, 0.4, 0, 1);
  karst_skeleton_segment_t seg = {{0, 0, 0}, {20, 0, 0}, 6, 0};
  karst_rng_t rng;
  karst_rng_init(&rng, 3, 0);
  assert_int_equal(karst_sdf_details(&ctx, t, tube, &par, &seg, 1, &rng, &d), KARST_SUCCESS);
  for (int i = 0; i < 100; i++) {
    double th = 2 * M_PI * i / 100, p[3] = {3 + 0.14 * i, 2.01 * cos(th), 2.01 * sin(th)}, fr[3][3];
    karst_sdf_details_noise(t, d, p, fr);
    assert_true(fabs(fr[1][0]) > 0.99);
  }
  const karst_i_details_t *dd = details_of(t, d);
  for (int i = 0; i < 50; i++) {
    double p[3] = {20 + 0.002 * i - 0.05, 0.01 * (i % 3), 0};
    double fs = karst_sdf_eval_node(t, tube, p, NULL, NULL);
    assert_close(unsquash(dd, karst_sdf_eval_node(t, d, p, NULL, NULL)), fs, 1e-12);
  }
  assert_lipschitz(t, d, 1, 3000, "details on a tube");
  karst_sdf_free(t);
}

/* A T-junction of a detailed canyon (ω = 90°) and an undetailed tube
 * blended together: details on the canyon's wall far from the junction,
 * none on the tube's wall far from it, a blend of the parameters between;
 * 1-Lipschitz, with tilt too. The unrescaled field is steeper than 1: the
 * rescaling is needed (and the test would see a missing one). */
static void test_junction_blend(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  for (int tilt = 0; tilt < 2; tilt++) {
    karst_sdf_t *t;
    karst_sdf_create(&ctx, &t);
    karst_section_t sc, st;
    karst_section_for_type(&ctx, KARST_TUNNEL_CANYON, &sc);
    karst_section_for_type(&ctx, KARST_TUNNEL_TUBE, &st);
    double a[3] = {-15, 0, 0}, b[3] = {15, 0, 0}, c[3] = {0, 0, 0}, e[3] = {0, 15, 0};
    karst_int_t can, tub, bl, d;
    karst_sdf_sweep(&ctx, t, a, b, &sc, 1.5, NULL, NULL, KARST_TUNNEL_CANYON, &can);
    karst_sdf_sweep(&ctx, t, c, e, &st, 1.2, NULL, NULL, KARST_TUNNEL_TUBE, &tub);
    karst_sdf_blend(&ctx, t, can, tub, 1.0, &bl);
    karst_details_params_t par;
    karst_details_params_init(&par);
    par.type[KARST_TUNNEL_CANYON] = flutes(0.05, 0.35, 90, 0.9);
    if (tilt)
      par.type[KARST_TUNNEL_CANYON].tilt = 30, par.type[KARST_TUNNEL_CANYON].tilt_direction = 45;
    karst_skeleton_segment_t seg[2] = {{{-15, 0, 0}, {15, 0, 0}, 5, KARST_TUNNEL_CANYON},
                                       {{0, 0, 0}, {0, 15, 0}, 4, KARST_TUNNEL_TUBE}};
    karst_rng_t rng;
    karst_rng_init(&rng, 4, 0);
    assert_int_equal(karst_sdf_details(&ctx, t, bl, &par, seg, 2, &rng, &d), KARST_SUCCESS);
    const karst_i_details_t *dd = details_of(t, d);
    /* far along the canyon (x = -12) its wall is detailed; far along the tube (y = 12) not */
    double on_canyon = 0, on_tube = 0;
    for (int i = 0; i < 400; i++) {
      double z = -1.5 + 3.0 * i / 400;
      double pc[3] = {-12 + 0.01 * i, 0.45, z},
             pt[3] = {1.2 * cos(i * 0.0157), 12, 1.2 * sin(i * 0.0157)};
      on_canyon = fmax(on_canyon, fabs(unsquash(dd, karst_sdf_eval_node(t, d, pc, NULL, NULL)) -
                                       karst_sdf_eval_node(t, bl, pc, NULL, NULL)));
      on_tube = fmax(on_tube, fabs(unsquash(dd, karst_sdf_eval_node(t, d, pt, NULL, NULL)) -
                                   karst_sdf_eval_node(t, bl, pt, NULL, NULL)));
    }
    printf("tilt %d: largest change of the field on the canyon wall %.4f m, on the tube wall "
           "%.2g m; L = %.0f\n",
           tilt, on_canyon, on_tube, dd->lip);
    assert_true(on_canyon > 0.01);
    assert_close(on_tube, 0, 1e-12);
    assert_lipschitz(t, d, 1, 4000,
                     tilt ? "tilted details at a junction" : "details at a junction");
    /* negative control: the unrescaled field f_S - h */
    double box[6] = {-14, -3, -3, 14, 14, 3}, worst = 0;
    karst_rng_t r;
    karst_rng_init(&r, 8, 0);
    for (int i = 0; i < 20000; i++) {
      double p[3], q[3];
      for (int k = 0; k < 3; k++)
        p[k] = karst_rng_uniform_range(&r, box[k], box[k + 3]);
      if (fabs(karst_sdf_eval_node(t, bl, p, NULL, NULL)) > 0.2) continue;
      double dir[3];
      karst_rng_unit_vector(&r, dir);
      for (int k = 0; k < 3; k++)
        q[k] = p[k] + 0.002 * dir[k];
      double fp = unsquash(dd, karst_sdf_eval_node(t, d, p, NULL, NULL));
      double fq = unsquash(dd, karst_sdf_eval_node(t, d, q, NULL, NULL));
      worst = fmax(worst, fabs(fp - fq) / 0.002);
    }
    printf("  unrescaled field: steepest slope %.2f (bound L = %.0f)\n", worst, dd->lip);
    assert_true(worst > 1.05);
    assert_true(worst <= dd->lip);
    karst_sdf_free(t);
  }
}

static void test_errors_and_determinism(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_details_params_t par;
  karst_details_params_init(&par);
  par.type[2] = flutes(0.03, 0.3, 0, 1);
  karst_int_t d1, d2, d3;
  karst_sdf_t *t1 = face(&par, &d1, 5), *t2 = face(&par, &d2, 5), *t3 = face(&par, &d3, 6);
  int differ = 0;
  for (int i = 0; i < 200; i++) {
    double p[3] = {0.1 * i, 0.07 * i, 0.001 * (i % 7)};
    double v1 = karst_sdf_eval_node(t1, d1, p, NULL, NULL);
    assert_true(v1 == karst_sdf_eval_node(t2, d2, p, NULL, NULL));
    differ += v1 != karst_sdf_eval_node(t3, d3, p, NULL, NULL);
  }
  assert_true(differ > 100);
  karst_rng_t rng;
  karst_rng_init(&rng, 1, 0);
  karst_skeleton_segment_t s = {{0, 0, 0}, {1, 0, 0}, 1, 2};
  karst_int_t n;
  par.type[2].orientation = 120;
  assert_int_equal(karst_sdf_details(&ctx, t1, 0, &par, &s, 1, &rng, &n), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "canyon: orientation 120"));
  par.type[2].orientation = 0;
  par.type[2].wavelength = 0;
  assert_int_equal(karst_sdf_details(&ctx, t1, 0, &par, &s, 1, &rng, &n), KARST_EINVAL);
  par.type[2].wavelength = 0.3;
  s.support = -1;
  assert_int_equal(karst_sdf_details(&ctx, t1, 0, &par, &s, 1, &rng, &n), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "segment 0"));
  s.support = 1;
  assert_int_equal(karst_sdf_details(&ctx, t1, 0, &par, &s, 0, &rng, &n), KARST_EINVAL);
  assert_int_equal(karst_sdf_details(&ctx, t1, 0, &par, &s, 1, NULL, &n), KARST_EINVAL);
  assert_int_equal(karst_sdf_details(&ctx, t1, 77, &par, &s, 1, &rng, &n), KARST_EINVAL);
  karst_sdf_free(t1);
  karst_sdf_free(t2);
  karst_sdf_free(t3);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_spectral_peak),          cmocka_unit_test(test_shell),
      cmocka_unit_test(test_frames_and_fade),        cmocka_unit_test(test_junction_blend),
      cmocka_unit_test(test_errors_and_determinism),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
