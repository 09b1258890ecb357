/* The Lipschitz check of construction-tree nodes shared by the unit tests of
 * src/implicit/ (include after cmocka.h): random pairs near and far from a
 * node's surface must satisfy |f(p) - f(q)| <= |p - q| (1 + LIP_TOL). */
#ifndef KARST_SDF_CHECK_H
#define KARST_SDF_CHECK_H

#include <math.h>
#include <string.h>

#include "karst.h"

/* Relative slack of the Lipschitz test (rounding only). */
#define LIP_TOL 1e-9

/* Random pairs around the box {lo, hi} grown by `far`: p uniform in the grown
 * box, q = p + a random direction times a log-uniform length in [1e-3, 10] m.
 * Every other p is first moved onto the surface, by bisection between it and
 * a sample of the other sign. Returns the largest |f(p) - f(q)| / |p - q|. */
static inline double lipschitz_ratio(const karst_sdf_t *t, karst_int_t node, const double box[6],
                                     double far, int npairs, uint64_t seed, int *near_surface) {
  karst_rng_t r;
  karst_rng_init(&r, seed, 99);
  enum { KEEP = 64 };
  double ins[KEEP][3], outs[KEEP][3];
  int ni = 0, no = 0;
  for (int k = 0; k < 200000 && (ni < KEEP || no < KEEP); k++) {
    double s[3];
    for (int a = 0; a < 3; a++)
      s[a] = karst_rng_uniform_range(&r, box[a] - far, box[a + 3] + far);
    double fs = karst_sdf_eval_node(t, node, s, NULL, NULL);
    if (fs < 0 && ni < KEEP) memcpy(ins[ni++], s, sizeof s);
    if (fs >= 0 && no < KEEP) memcpy(outs[no++], s, sizeof s);
  }
  double worst = 0;
  int near = 0;
  for (int i = 0; i < npairs; i++) {
    double p[3], q[3], d[3];
    for (int a = 0; a < 3; a++)
      p[a] = karst_rng_uniform_range(&r, box[a] - far, box[a + 3] + far);
    double fp = karst_sdf_eval_node(t, node, p, NULL, NULL);
    if (i % 2 && ((fp < 0 && no > 0) || (fp >= 0 && ni > 0))) {
      double s[3];
      memcpy(s,
             fp < 0 ? outs[karst_rng_below(&r, (uint64_t)no)]
                    : ins[karst_rng_below(&r, (uint64_t)ni)],
             sizeof s);
      for (int it = 0; it < 50; it++) {
        double m[3] = {0.5 * (p[0] + s[0]), 0.5 * (p[1] + s[1]), 0.5 * (p[2] + s[2])};
        double fm = karst_sdf_eval_node(t, node, m, NULL, NULL);
        if ((fm < 0) == (fp < 0))
          memcpy(p, m, sizeof m), fp = fm;
        else
          memcpy(s, m, sizeof m);
      }
      near++;
    }
    karst_rng_unit_vector(&r, d);
    double len = exp(karst_rng_uniform_range(&r, log(1e-3), log(10.0)));
    for (int a = 0; a < 3; a++)
      q[a] = p[a] + len * d[a];
    fp = karst_sdf_eval_node(t, node, p, NULL, NULL);
    double fq = karst_sdf_eval_node(t, node, q, NULL, NULL);
    double dist = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                       (p[2] - q[2]) * (p[2] - q[2]));
    assert_true(isfinite(fp) && isfinite(fq));
    double ratio = fabs(fp - fq) / dist;
    if (ratio > worst) worst = ratio;
  }
  if (near_surface) *near_surface = near;
  return worst;
}

static inline void assert_lipschitz(const karst_sdf_t *t, karst_int_t node, double far, int npairs,
                                    const char *what) {
  double box[6];
  karst_sdf_node_box(t, node, box);
  for (int a = 0; a < 3; a++)
    if (!isfinite(box[a]) || !isfinite(box[a + 3])) box[a] = -20, box[a + 3] = 20;
  int near = 0;
  double w = lipschitz_ratio(t, node, box, far, npairs, (uint64_t)node + 1, &near);
  if (!(w <= 1 + LIP_TOL)) {
    print_error("%s: Lipschitz ratio %.12g > 1\n", what, w);
    fail();
  }
  /* the test must really have probed the surface */
  if (near < npairs / 2 - 1) {
    print_error("%s: only %d of %d pairs near the surface\n", what, near, npairs);
    fail();
  }
}

#endif
