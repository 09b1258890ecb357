/* Adaptive population Monte Carlo ABC (calibrate_internal.h).
 *
 * The method is Algorithm 4 of Lenormand, Jabot & Deffuant (2013), "Adaptive approximate
 * Bayesian computation for complex models", Computational Statistics 28:2777–2796:
 *   t = 0: simulate N particles from the prior, weight 1; keep the N_α = ⌊αN⌋ closest;
 *          ε_1 = their largest distance; kernel variance σ² = 2 var_w (Beaumont et al. 2009).
 *   t ≥ 1: simulate N − N_α new particles, each a draw from the kept population (probability
 *          ∝ weight) moved by the Gaussian kernel, with the importance weight of Beaumont,
 *          Cornuet, Marin & Robert (2009, Biometrika 96:983) w = π(θ) / Σ_j w̄_j K_σ(θ | θ_j);
 *          p_acc = the fraction of them closer than ε_t; merge with the kept N_α, keep the
 *          N_α closest, ε_{t+1} = their largest distance; stop when p_acc <= p_acc_min.
 * So ε never increases: the kept particles are all within ε_t, and the new quantile is taken
 * over them and the newcomers.
 *
 * Two choices the paper leaves open, made so that the weights stay exact:
 *  - The kernel is Beaumont et al.'s component-wise Gaussian (σ_k² = 2 × the weighted variance
 *    of parameter k), truncated to the prior box: a component is redrawn until it falls inside
 *    [lo_k, hi_k), and K includes the normalising constant Z_jk = Φ((hi−θ_jk)/σ_k) −
 *    Φ((lo−θ_jk)/σ_k), so no simulation is spent outside the prior and w is the true ratio of
 *    prior to proposal density.
 *  - Ties in distance are broken by (generation, member index), so exactly N_α particles are
 *    kept and the result does not depend on sorting details.
 * Weights are kept as logarithms (log-sum-exp over the mixture) so that a narrow kernel cannot
 * underflow them. Everything here is sequential and depends only on the inputs and the
 * generator: the same seed gives the same bits on any thread or process count. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "calibrate/calibrate_internal.h"

/** log √(2π). */
#define LOG_SQRT_2PI 0.91893853320467274178

karst_error_t karst_i_abc_init(karst_ctx_t *ctx, karst_i_abc_t *abc, int d, const double *lo,
                               const double *hi, karst_int_t n, karst_int_t n_keep) {
  memset(abc, 0, sizeof *abc);
  if (d < 1 || d > KARST_CALIBRATE_MAX_PARAMS)
    return karst_set_error(ctx, KARST_ERANGE, "between 1 and %d parameters are supported, got %d",
                           KARST_CALIBRATE_MAX_PARAMS, d);
  if (n_keep < 2 || n_keep >= n)
    return karst_set_error(ctx, KARST_ERANGE,
                           "the population (%lld particles) must hold at least 2 and fewer than "
                           "the %lld particles per generation",
                           (long long)n_keep, (long long)n);
  for (int k = 0; k < d; k++) {
    if (!(isfinite(lo[k]) && isfinite(hi[k]) && lo[k] < hi[k]))
      return karst_set_error(ctx, KARST_EINVAL, "parameter %d: invalid prior box [%g, %g)", k,
                             lo[k], hi[k]);
    abc->lo[k] = lo[k];
    abc->hi[k] = hi[k];
  }
  abc->d = d;
  abc->n = n;
  abc->n_keep = n_keep;
  abc->generation = -1;
  abc->tolerance = INFINITY;
  abc->u = malloc((size_t)n_keep * (size_t)d * sizeof *abc->u);
  abc->logw = malloc((size_t)n_keep * sizeof *abc->logw);
  abc->rho = malloc((size_t)n_keep * sizeof *abc->rho);
  abc->born = malloc((size_t)n_keep * sizeof *abc->born);
  abc->member = malloc((size_t)n_keep * sizeof *abc->member);
  if (!abc->u || !abc->logw || !abc->rho || !abc->born || !abc->member) {
    karst_i_abc_destroy(abc);
    return karst_set_error(ctx, KARST_ENOMEM, "out of memory for %lld particles",
                           (long long)n_keep);
  }
  return KARST_SUCCESS;
}

void karst_i_abc_destroy(karst_i_abc_t *abc) {
  free(abc->u);
  free(abc->logw);
  free(abc->rho);
  free(abc->born);
  free(abc->member);
  memset(abc, 0, sizeof *abc);
}

karst_int_t karst_i_abc_batch(const karst_i_abc_t *abc) {
  return abc->generation < 0 ? abc->n : abc->n - abc->n_keep;
}

/* Normalised weights w̄ and their logarithms, by max-subtraction. */
static void normalise(const karst_i_abc_t *abc, double *w, double *logwbar) {
  double m = -INFINITY, s = 0;
  for (karst_int_t j = 0; j < abc->size; j++)
    if (abc->logw[j] > m) m = abc->logw[j];
  for (karst_int_t j = 0; j < abc->size; j++)
    s += exp(abc->logw[j] - m);
  double ls = log(s);
  for (karst_int_t j = 0; j < abc->size; j++) {
    double lw = abc->logw[j] - m - ls;
    if (logwbar) logwbar[j] = lw;
    if (w) w[j] = exp(lw);
  }
}

/**
 * Normalised weights of the population (sum 1 up to rounding).
 * Time complexity: O(size).
 */
void karst_i_abc_weights(const karst_i_abc_t *abc, double *w) {
  normalise(abc, w, NULL);
}

/**
 * Kish's effective sample size (Σw)² / Σw² of the population's weights.
 * Time complexity: O(size).
 */
double karst_i_abc_ess(const karst_i_abc_t *abc) {
  double m = -INFINITY, s1 = 0, s2 = 0;
  for (karst_int_t j = 0; j < abc->size; j++)
    if (abc->logw[j] > m) m = abc->logw[j];
  for (karst_int_t j = 0; j < abc->size; j++) {
    double w = exp(abc->logw[j] - m);
    s1 += w;
    s2 += w * w;
  }
  return s2 > 0 ? s1 * s1 / s2 : 0;
}

static double std_normal_cdf(double x) {
  return 0.5 * erfc(-x / M_SQRT2);
}

/**
 * Proposals of the next generation (calibrate_internal.h): the prior sample (uniform on the box,
 * log weight 0) for the first generation; else particle j is chosen with probability w̄_j and
 * each component moved by N(0, σ_k²) truncated to the box (redrawn until inside), with log
 * weight log π(u) − log Σ_j w̄_j Π_k φ((u_k − u_jk)/σ_k) / (σ_k Z_jk) (Beaumont et al. 2009).
 * Time complexity: O(batch × size × d).
 */
karst_error_t karst_i_abc_propose(karst_ctx_t *ctx, const karst_i_abc_t *abc, karst_rng_t *rng,
                                  double *u, double *logw) {
  karst_int_t m = karst_i_abc_batch(abc);
  int d = abc->d;
  if (abc->generation < 0) {
    for (karst_int_t i = 0; i < m; i++) {
      for (int k = 0; k < d; k++)
        u[i * d + k] = karst_rng_uniform_range(rng, abc->lo[k], abc->hi[k]);
      logw[i] = 0;
    }
    return KARST_SUCCESS;
  }
  karst_int_t size = abc->size;
  karst_error_t err = KARST_SUCCESS;
  double *cum = malloc((size_t)size * sizeof *cum);
  double *lwbar = malloc((size_t)size * sizeof *lwbar);
  double *logz = malloc((size_t)size * (size_t)d * sizeof *logz);
  double *terms = malloc((size_t)size * sizeof *terms);
  if (!cum || !lwbar || !logz || !terms) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory for %lld particles", (long long)size);
    goto cleanup;
  }
  normalise(abc, cum, lwbar);
  for (karst_int_t j = 1; j < size; j++)
    cum[j] += cum[j - 1];
  double log_prior = 0;
  for (int k = 0; k < d; k++)
    log_prior -= log(abc->hi[k] - abc->lo[k]);
  for (karst_int_t j = 0; j < size; j++)
    for (int k = 0; k < d; k++) {
      double mu = abc->u[j * d + k], s = abc->sigma[k];
      double z = std_normal_cdf((abc->hi[k] - mu) / s) - std_normal_cdf((abc->lo[k] - mu) / s);
      logz[j * d + k] = log(z);
    }
  for (karst_int_t i = 0; i < m; i++) {
    /* choose a particle: the first j with cum[j] > r (cum[size-1] is 1 up to rounding) */
    double r = karst_rng_uniform(rng) * cum[size - 1];
    karst_int_t a = 0, b = size - 1;
    while (a < b) {
      karst_int_t c = a + (b - a) / 2;
      if (cum[c] > r)
        b = c;
      else
        a = c + 1;
    }
    for (int k = 0; k < d; k++) {
      double mu = abc->u[a * d + k], v = NAN;
      for (int tries = 0; tries < KARST_CALIBRATE_MAX_REDRAWS; tries++) {
        double z = mu + abc->sigma[k] * karst_rng_gaussian(rng);
        if (z >= abc->lo[k] && z < abc->hi[k]) {
          v = z;
          break;
        }
      }
      if (isnan(v)) {
        err = karst_set_error(ctx, KARST_ERANGE,
                              "parameter %d: %d kernel draws around %g (sd %g) all fell outside "
                              "the prior [%g, %g)",
                              k, KARST_CALIBRATE_MAX_REDRAWS, mu, abc->sigma[k], abc->lo[k],
                              abc->hi[k]);
        goto cleanup;
      }
      u[i * d + k] = v;
    }
    /* log q(u_i) by log-sum-exp over the mixture */
    double mx = -INFINITY;
    for (karst_int_t j = 0; j < size; j++) {
      double t = lwbar[j];
      for (int k = 0; k < d; k++) {
        double z = (u[i * d + k] - abc->u[j * d + k]) / abc->sigma[k];
        t += -0.5 * z * z - log(abc->sigma[k]) - LOG_SQRT_2PI - logz[j * d + k];
      }
      terms[j] = t;
      if (t > mx) mx = t;
    }
    double s = 0;
    for (karst_int_t j = 0; j < size; j++)
      s += exp(terms[j] - mx);
    logw[i] = log_prior - (mx + log(s));
  }
cleanup:
  free(cum);
  free(lwbar);
  free(logz);
  free(terms);
  return err;
}

/* A candidate of the merged population, ordered by distance, then generation, then member. */
typedef struct cand {
  double rho;
  int born;
  karst_int_t member;
  karst_int_t from; /* < size: population index; else size + proposal index */
} cand_t;

static int cmp_cand(const void *a, const void *b) {
  const cand_t *x = a, *y = b;
  if (x->rho != y->rho) return x->rho < y->rho ? -1 : 1;
  if (x->born != y->born) return x->born < y->born ? -1 : 1;
  return x->member < y->member ? -1 : x->member > y->member;
}

/**
 * Merge the proposals of the generation just simulated (calibrate_internal.h) and keep the N_α
 * closest; σ_k² = 2 Σ_j w̄_j (u_jk − ū_k)² for the next batch, at least
 * (KARST_CALIBRATE_MIN_KERNEL_FRACTION × (hi_k − lo_k))².
 * Time complexity: O((size + batch) log(size + batch) + size × d).
 */
karst_error_t karst_i_abc_update(karst_ctx_t *ctx, karst_i_abc_t *abc, const double *u,
                                 const double *logw, const double *rho, karst_int_t *accepted) {
  karst_int_t m = karst_i_abc_batch(abc), size = abc->size, total = size + m;
  int d = abc->d, gen = abc->generation + 1;
  karst_error_t err = KARST_SUCCESS;
  cand_t *c = malloc((size_t)total * sizeof *c);
  double *nu = malloc((size_t)abc->n_keep * (size_t)d * sizeof *nu);
  double *nlw = malloc((size_t)abc->n_keep * sizeof *nlw);
  double *w = malloc((size_t)abc->n_keep * sizeof *w);
  if (!c || !nu || !nlw || !w) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory for %lld particles", (long long)total);
    goto cleanup;
  }
  karst_int_t acc = 0;
  for (karst_int_t i = 0; i < m; i++) {
    if (isnan(rho[i]) || isnan(logw[i])) {
      err = karst_set_error(ctx, KARST_EINVAL, "particle %lld of generation %d: NaN distance",
                            (long long)i, gen);
      goto cleanup;
    }
    acc += gen == 0 || rho[i] < abc->tolerance;
  }
  for (karst_int_t j = 0; j < size; j++)
    c[j] = (cand_t){abc->rho[j], abc->born[j], abc->member[j], j};
  for (karst_int_t i = 0; i < m; i++)
    c[size + i] = (cand_t){rho[i], gen, i, size + i};
  qsort(c, (size_t)total, sizeof *c, cmp_cand);
  karst_int_t keep = abc->n_keep;
  int *nborn = abc->born;
  karst_int_t *nmember = abc->member;
  double *nrho = abc->rho;
  /* c is sorted; population entries may be overwritten only after they are copied, so gather
   * into the new arrays first (born/member/rho are copied from c itself). */
  for (karst_int_t r = 0; r < keep; r++) {
    karst_int_t f = c[r].from;
    const double *src = f < size ? &abc->u[f * d] : &u[(f - size) * d];
    memcpy(&nu[r * d], src, (size_t)d * sizeof *nu);
    nlw[r] = f < size ? abc->logw[f] : logw[f - size];
  }
  for (karst_int_t r = 0; r < keep; r++) {
    nborn[r] = c[r].born;
    nmember[r] = c[r].member;
    nrho[r] = c[r].rho;
  }
  memcpy(abc->u, nu, (size_t)keep * (size_t)d * sizeof *nu);
  memcpy(abc->logw, nlw, (size_t)keep * sizeof *nlw);
  abc->size = keep;
  abc->generation = gen;
  abc->tolerance = nrho[keep - 1];
  karst_i_abc_weights(abc, w);
  for (int k = 0; k < d; k++) {
    double mean = 0, var = 0;
    for (karst_int_t j = 0; j < keep; j++)
      mean += w[j] * abc->u[j * d + k];
    for (karst_int_t j = 0; j < keep; j++) {
      double e = abc->u[j * d + k] - mean;
      var += w[j] * e * e;
    }
    double floor_sd = KARST_CALIBRATE_MIN_KERNEL_FRACTION * (abc->hi[k] - abc->lo[k]);
    abc->sigma[k] = fmax(sqrt(2 * var), floor_sd);
  }
  if (accepted) *accepted = acc;
cleanup:
  free(c);
  free(nu);
  free(nlw);
  free(w);
  return err;
}

typedef struct keyed {
  double x;
  karst_int_t i;
} keyed_t;

/* Ascending x, ties by index: a total order. */
static int cmp_keyed(const void *a, const void *b) {
  const keyed_t *p = a, *q = b;
  if (p->x != q->x) return p->x < q->x ? -1 : 1;
  return p->i < q->i ? -1 : p->i > q->i;
}

/**
 * Weighted type-1 quantile (calibrate_internal.h).
 * Time complexity: O(n log n).
 */
karst_error_t karst_i_weighted_quantile(karst_ctx_t *ctx, const double *x, const double *w,
                                        karst_int_t n, double p, double *out) {
  *out = NAN;
  if (n <= 0) return KARST_SUCCESS;
  keyed_t *k = malloc((size_t)n * sizeof *k);
  if (!k) return karst_set_error(ctx, KARST_ENOMEM, "out of memory for %lld values", (long long)n);
  for (karst_int_t i = 0; i < n; i++)
    k[i] = (keyed_t){x[i], i};
  qsort(k, (size_t)n, sizeof *k, cmp_keyed);
  double total = 0;
  for (karst_int_t i = 0; i < n; i++)
    total += w[k[i].i];
  double target = p * total, cum = 0;
  *out = k[n - 1].x;
  for (karst_int_t i = 0; i < n; i++) {
    cum += w[k[i].i];
    if (cum >= target && w[k[i].i] > 0) {
      *out = k[i].x;
      break;
    }
  }
  free(k);
  return KARST_SUCCESS;
}
