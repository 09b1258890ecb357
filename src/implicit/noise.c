/* Sparse Gabor noise for wall irregularities (Zanni et al. 2012, after
 * Lagae et al. 2009), with a proven Lipschitz constant so that the displaced
 * field can be rescaled to stay 1-Lipschitz (Paris et al. 2021, §6).
 *
 * Space is cut into cubic cells of side 2 Rk; each cell holds exactly one
 * impulse x_i (uniform in the cell), a weight w_i in [-1, 1], a unit
 * direction d_i and a phase φ_i, all a pure function of (seed, cell). The
 * kernel is a Gabor kernel with a compact C1 window instead of a Gaussian
 * (a truncated Gaussian would be discontinuous):
 *     K_i(p) = W(|p - x_i|) cos(2π d_i.(p - x_i)/λ + φ_i),
 *     W(ρ) = (1 - ρ²/Rk²)² for ρ < Rk, 0 beyond.
 * A ball of radius Rk meets at most 8 cells of side 2 Rk, so at most 8
 * kernels are non-zero at any point, and n(p) = (1/8) Σ w_i K_i(p) has
 * |n| <= 1 and
 *     |∇n| <= max|W'| + 2π/λ = 8 / (3√3 Rk) + 2π/λ,
 * because |∇K_i| <= |W'| + W 2π/λ and max|W'| is reached at ρ = Rk/√3.
 */
#include <math.h>

#include "implicit/implicit_internal.h"

/** Lipschitz constant of the normalised noise (see the file comment). */
double karst_i_noise_lipschitz(double kradius, double wavelength) {
  return 8.0 / (3.0 * sqrt(3.0) * kradius) + 2.0 * M_PI / wavelength;
}

static uint64_t cell_id(int64_t i, int64_t j, int64_t k) {
  uint64_t h = (uint64_t)i * 0x9E3779B97F4A7C15ULL;
  h ^= (uint64_t)j * 0xC2B2AE3D27D4EB4FULL + (h << 6) + (h >> 2);
  h ^= (uint64_t)k * 0x165667B19E3779F9ULL + (h << 6) + (h >> 2);
  return h;
}

/* The normalised noise n(p) in [-1, 1]. O(1): 8 kernels. */
double karst_i_noise_eval(const karst_i_noise_t *nz, const double p[3]) {
  const double cs = 2.0 * nz->kradius;
  const double r2 = nz->kradius * nz->kradius;
  const double f = 2.0 * M_PI / nz->wavelength;
  int64_t c[3], o[3];
  for (int a = 0; a < 3; a++) {
    double x = p[a] / cs;
    double fl = floor(x);
    c[a] = (int64_t)fl;
    o[a] = (x - fl) < 0.5 ? -1 : 1; /* the neighbour cell the ball of radius Rk may reach */
  }
  double sum = 0;
  for (int m = 0; m < 8; m++) {
    int64_t ci = c[0] + ((m & 1) ? o[0] : 0);
    int64_t cj = c[1] + ((m & 2) ? o[1] : 0);
    int64_t ck = c[2] + ((m & 4) ? o[2] : 0);
    karst_rng_t rng;
    karst_rng_init(&rng, nz->seed, cell_id(ci, cj, ck));
    double x[3] = {(ci + karst_rng_uniform(&rng)) * cs, (cj + karst_rng_uniform(&rng)) * cs,
                   (ck + karst_rng_uniform(&rng)) * cs};
    double dx = p[0] - x[0], dy = p[1] - x[1], dz = p[2] - x[2];
    double rho2 = dx * dx + dy * dy + dz * dz;
    if (rho2 >= r2) continue;
    double w = karst_rng_uniform_range(&rng, -1.0, 1.0);
    double d[3];
    karst_rng_unit_vector(&rng, d);
    double phase = karst_rng_uniform_range(&rng, 0.0, 2.0 * M_PI);
    double win = 1.0 - rho2 / r2;
    sum += w * win * win * cos(f * (d[0] * dx + d[1] * dy + d[2] * dz) + phase);
  }
  return sum / 8.0;
}
