/* The ABC-SMC engine of src/calibrate/ (abc.c), free of scenarios and files so that it can be
 * tested on models whose posterior is known, and helpers shared by the files of the module. */
#ifndef KARST_CALIBRATE_INTERNAL_H
#define KARST_CALIBRATE_INTERNAL_H

#include "karst/calibrate.h"

/**
 * Adaptive population Monte Carlo ABC (Lenormand, Jabot & Deffuant 2013, Algorithm 4) on a box
 * of "latent" coordinates u in [lo_k, hi_k) with a uniform prior (calibrate.c maps
 * log-uniform and integer parameters onto such a box). The population holds the n_keep =
 * ⌊α N⌋ particles of smallest distance so far, each with its log importance weight
 * log π(u) − log q(u) (0 for the prior sample), its distance, and where it was simulated.
 */
typedef struct karst_i_abc {
  int d;                                 /**< parameters */
  double lo[KARST_CALIBRATE_MAX_PARAMS]; /**< latent prior box */
  double hi[KARST_CALIBRATE_MAX_PARAMS];
  karst_int_t n, n_keep;                    /**< particles per generation, population size */
  int generation;                           /**< last generation taken in (-1: none yet) */
  karst_int_t size;                         /**< particles in the population (n_keep after t = 0) */
  double *u;                                /**< size × d latent values */
  double *logw;                             /**< log importance weights (unnormalised) */
  double *rho;                              /**< distances */
  int *born;                                /**< generation in which each was simulated */
  karst_int_t *member;                      /**< its member index in that generation */
  double tolerance;                         /**< ε: the largest distance kept */
  double sigma[KARST_CALIBRATE_MAX_PARAMS]; /**< kernel standard deviations for the next batch */
} karst_i_abc_t;

/** An empty engine for @p d parameters on the box [lo, hi), N = @p n, N_α = @p n_keep. */
karst_error_t karst_i_abc_init(karst_ctx_t *ctx, karst_i_abc_t *abc, int d, const double *lo,
                               const double *hi, karst_int_t n, karst_int_t n_keep);
void karst_i_abc_destroy(karst_i_abc_t *abc);

/** Particles the next generation simulates: N for the prior sample, N − N_α after it. */
karst_int_t karst_i_abc_batch(const karst_i_abc_t *abc);

/**
 * The proposals of the next generation into @p u (batch × d) and their log importance weights
 * into @p logw: the prior sample, else draws from the weighted population moved by the
 * truncated Gaussian kernel (Beaumont et al. 2009), weighted π(u) / Σ_j w̄_j K(u | u_j).
 */
karst_error_t karst_i_abc_propose(karst_ctx_t *ctx, const karst_i_abc_t *abc, karst_rng_t *rng,
                                  double *u, double *logw);

/**
 * Take in the distances @p rho of the proposals (+∞ allowed, NaN not): merge them with the
 * population, keep the N_α of smallest distance (ties by generation, then member index), set
 * the tolerance and the kernel for the next batch. @p accepted receives the proposals with a
 * distance below the previous tolerance (Lenormand's p_acc numerator; the batch size for the
 * prior sample).
 */
karst_error_t karst_i_abc_update(karst_ctx_t *ctx, karst_i_abc_t *abc, const double *u,
                                 const double *logw, const double *rho, karst_int_t *accepted);

/** Normalised weights of the population into @p w (size entries, summing to 1). */
void karst_i_abc_weights(const karst_i_abc_t *abc, double *w);

/** Effective sample size (Σw)² / Σw² of the population. */
double karst_i_abc_ess(const karst_i_abc_t *abc);

/**
 * Weighted quantile of type 1 (inverse of the weighted empirical distribution function): the
 * smallest x_i of positive weight whose cumulative weight, in ascending order of x (ties by
 * index), reaches p × Σw; *out is NAN for n = 0.
 */
karst_error_t karst_i_weighted_quantile(karst_ctx_t *ctx, const double *x, const double *w,
                                        karst_int_t n, double p, double *out);

/* ------------------------------------------------------------------------ */
/* What a calibration knows at the end (calibrate.c), for its files and report */
/* ------------------------------------------------------------------------ */
#include "karst/ensemble.h"

/** The population after each generation, in parameter values (not latent coordinates). */
typedef struct karst_i_calib_history {
  int n_gen, cap;                    /**< generations 0 .. n_gen − 1 */
  karst_calibrate_generation_t *gen; /**< n_gen entries */
  int d;
  karst_int_t n_keep;
  double *values;      /**< n_gen × n_keep × d, population order (distance, then age) */
  double *weights;     /**< n_gen × n_keep, normalised per generation */
  double *dist;        /**< n_gen × n_keep */
  int *born;           /**< generation in which each particle was simulated */
  karst_int_t *member; /**< its member index in that generation's ensemble */
  uint64_t *seed;      /**< its member seed */
} karst_i_calib_history_t;

/** Everything the report shows (calibrate_report.c). */
typedef struct karst_i_calib_view {
  const karst_calibrate_options_t *opt;
  const char *dir;
  int d;
  const karst_calibrate_param_t *params;
  const char (
      *file_value)[64]; /**< d entries: the scenario file's text of each key ("": default) */
  int n_sel;
  const char *metric[KARST_CALIBRATE_MAX_METRICS]; /**< selected metrics */
  double survey[KARST_CALIBRATE_MAX_METRICS];      /**< the survey's values */
  double scale[KARST_CALIBRATE_MAX_METRICS];       /**< spread under the prior (NAN: not used) */
  int scale_is_mad[KARST_CALIBRATE_MAX_METRICS];   /**< 1: MAD × 1.4826, 0: standard deviation */
  const karst_i_calib_history_t *hist;
  const double *median, *low, *high;   /**< d entries: posterior median and 90 % interval */
  const karst_ensemble_table_t *prior; /**< the members of generation 0 */
  const karst_ensemble_table_t *best;  /**< the ensemble of best.yaml, or NULL */
  karst_calibrate_stop_t stop;
} karst_i_calib_view_t;

/** Write DIR/report.html (atomically) from @p v. */
karst_error_t karst_i_calibrate_report(karst_ctx_t *ctx, const char *path,
                                       const karst_i_calib_view_t *v);

#endif
