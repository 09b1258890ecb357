/**
 * @file calibrate.h
 * @brief Fit scenario parameters to a surveyed cave: approximate Bayesian computation by
 *        sequential Monte Carlo, the adaptive population Monte Carlo ABC (APMC) of Lenormand,
 *        Jabot & Deffuant (2013, Computational Statistics 28:2777–2796, Algorithm 4), with
 *        the importance weights and Gaussian perturbation kernel of Beaumont, Cornuet, Marin
 *        & Robert (2009, Biometrika 96:983–990). Every simulation is a member of an ensemble
 *        (karst_ensemble_run): threads, Open MPI ranks, resumable. docs/calibration.md.
 *
 * Layout of a calibration directory DIR:
 *   DIR/generations/GGG/particles.csv   the proposals of generation GGG (before it runs)
 *   DIR/generations/GGG/...             its ensemble (realisations/NNNN/metrics.csv, metrics.csv)
 *   DIR/posterior.csv                   the population of every generation: values, weights,
 *                                       distances
 *   DIR/generations.csv                 per generation: simulations, acceptance, tolerance, ESS
 *   DIR/best.yaml                       the scenario at the posterior median
 *   DIR/best/                           an ensemble of best.yaml (karst ensemble layout)
 *   DIR/report.html                     posterior histograms, pair plots, acceptance, fit
 *   DIR/calibration.json                every setting, the distance scales, the summary
 *   DIR/calibration.key                 what the directory holds (guards re-runs)
 */
#ifndef KARST_CALIBRATE_H
#define KARST_CALIBRATE_H

#include "karst/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Most parameters one calibration varies. */
#define KARST_CALIBRATE_MAX_PARAMS 16
/** Most metrics in the distance. */
#define KARST_CALIBRATE_MAX_METRICS 32
/** Most SMC generations after the prior sample. */
#define KARST_CALIBRATE_MAX_GENERATIONS 999
/** Most particles per generation. */
#define KARST_CALIBRATE_MAX_PARTICLES 1000000

/** Default particles per generation (N of Lenormand et al. 2013). */
#define KARST_CALIBRATE_DEFAULT_PARTICLES 200
/** Default fraction α of the particles kept as the population (N_α = ⌊α N⌋); Lenormand et al.
 *  2013 recommend 0.5. */
#define KARST_CALIBRATE_DEFAULT_ALPHA 0.5
/** Default most SMC generations after the prior sample. */
#define KARST_CALIBRATE_DEFAULT_GENERATIONS 10
/** Default stopping rule: stop once the acceptance rate p_acc of a generation is at or below
 *  this (Lenormand et al. 2013 use 0.01 to 0.05; 0.05 is EasyABC's default). */
#define KARST_CALIBRATE_DEFAULT_MIN_ACCEPTANCE 0.05
/** Default members of the ensemble of best.yaml (the fit shown in the report). */
#define KARST_CALIBRATE_DEFAULT_BEST_MEMBERS 20
/** Median absolute deviation to standard deviation under normality, 1 / Φ⁻¹(3/4). */
#define KARST_CALIBRATE_MAD_TO_SD 1.482602218505602
/** Smallest kernel standard deviation, as a fraction of the parameter's (latent) prior width:
 *  keeps the kernel proper when every kept particle has the same value. */
#define KARST_CALIBRATE_MIN_KERNEL_FRACTION 1e-6
/** Most draws of one kernel component before giving up (each lands inside the prior with
 *  probability at least Φ(√2) − 1/2 ≈ 0.42, see src/calibrate/abc.c). */
#define KARST_CALIBRATE_MAX_REDRAWS 10000
/** Credible interval reported: the weighted 5 % and 95 % quantiles (90 %). */
#define KARST_CALIBRATE_CI_LOW 0.05
#define KARST_CALIBRATE_CI_HIGH 0.95

/** Prior of one parameter. */
typedef enum {
  KARST_PRIOR_UNIFORM = 0,    /**< uniform on [lo, hi] */
  KARST_PRIOR_LOG_UNIFORM = 1 /**< log θ uniform on [log lo, log hi] (lo > 0) */
} karst_prior_t;

/** One varied parameter: a numeric scenario key (by its YAML path) and its prior. */
typedef struct karst_calibrate_param {
  char key[256]; /**< e.g. "skeleton.gamma", "fractures[0].weight" */
  double lo, hi; /**< prior bounds, lo < hi (integer keys: whole numbers) */
  karst_prior_t prior;
  int is_integer; /**< set by karst_calibrate_check_params: the parser reads an integer */
  char spec[320]; /**< the text it was parsed from ("skeleton.gamma=0.5:3"), for messages */
} karst_calibrate_param_t;

/**
 * Parse "KEY=LO:HI" (uniform prior), "KEY=LO:HI:log" (log-uniform) or "KEY=LO:HI:uniform".
 * Checks the form only (finite bounds, LO < HI, LO > 0 for log); the key is checked against
 * the scenario by karst_calibrate_check_params.
 */
karst_error_t karst_calibrate_param_parse(karst_ctx_t *ctx, const char *spec,
                                          karst_calibrate_param_t *p);

/**
 * Check the parameters against the scenario @p scenario_path: each key must exist in the
 * scenario's schema and hold a number (messages from the scenario parser, with "did you
 * mean"); integer keys need whole bounds; the scenario must load with every combination of
 * the bounds (all corners for up to 10 parameters, else all-low and all-high). Sets
 * is_integer. A repeated key is refused.
 */
karst_error_t karst_calibrate_check_params(karst_ctx_t *ctx, const char *scenario_path, int n,
                                           karst_calibrate_param_t *params);

/** What one generation did (karst_calibrate_options_t.on_generation, generations.csv). */
typedef struct karst_calibrate_generation {
  int generation;          /**< 0: the prior sample */
  karst_int_t simulations; /**< members simulated for this generation */
  karst_int_t computed;    /**< of which computed in this run (the others were on disk) */
  karst_int_t accepted;    /**< new particles closer than the previous tolerance (t ≥ 1) */
  double acceptance;       /**< p_acc = accepted / simulations (NAN for generation 0) */
  karst_int_t undefined;   /**< simulations with an undefined metric (distance +∞) */
  double tolerance;        /**< ε: largest distance in the population after this generation */
  double ess;              /**< effective sample size (Σw)² / Σw² of the population */
  int generations_max;     /**< the run's most generations (for progress displays) */
} karst_calibrate_generation_t;

typedef void (*karst_calibrate_generation_fn)(void *user, const karst_calibrate_generation_t *g);

/** How to calibrate. */
typedef struct karst_calibrate_options {
  const char *scenario_path;             /**< the scenario whose keys are varied */
  const char *survey_path;               /**< the survey (any format karst_read_network reads) */
  int n_params;                          /**< 1 to KARST_CALIBRATE_MAX_PARAMS */
  const karst_calibrate_param_t *params; /**< parsed by karst_calibrate_param_parse */
  int n_metrics;                         /**< 0: the ten metrics of Collon et al. 2017 */
  const char *const *metrics;            /**< metric keys of karst_metric_fields */
  karst_int_t particles;                 /**< N per generation */
  double alpha;                          /**< kept fraction α in (0, 1) */
  int generations;                       /**< most SMC generations after the prior sample */
  double min_acceptance;                 /**< stop once p_acc <= this, in [0, 1] */
  int best_members;                      /**< members of the ensemble of best.yaml (0: none) */
  uint64_t seed;                         /**< base seed */
  int nthreads;                          /**< worker threads for the members */
  int use_mpi;                           /**< split members across MPI ranks when initialised */
  const char *published_path;            /**< the 34-cave table (NULL: karst_published_locate) */
  karst_calibrate_generation_fn on_generation; /**< after each generation (rank 0), or NULL */
  void *on_generation_user;
} karst_calibrate_options_t;

/** Why the run stopped. */
typedef enum {
  KARST_CALIBRATE_STOP_GENERATIONS = 0, /**< the most generations were run */
  KARST_CALIBRATE_STOP_ACCEPTANCE = 1   /**< p_acc fell to min_acceptance (Lenormand et al.) */
} karst_calibrate_stop_t;

/** What a run did. */
typedef struct karst_calibrate_summary {
  int generations; /**< SMC generations after the prior sample */
  karst_calibrate_stop_t stop;
  karst_int_t simulations; /**< members over all generations */
  karst_int_t computed;    /**< of which computed by this process in this run */
  double tolerance;        /**< final ε */
  int n_params;
  double median[KARST_CALIBRATE_MAX_PARAMS]; /**< weighted posterior median (best.yaml) */
  double low[KARST_CALIBRATE_MAX_PARAMS];    /**< weighted 5 % quantile */
  double high[KARST_CALIBRATE_MAX_PARAMS];   /**< weighted 95 % quantile */
  double wall_seconds;
  int ranks, rank;
} karst_calibrate_summary_t;

/** Defaults (KARST_CALIBRATE_DEFAULT_*), seed 1, one thread, MPI when available. */
void karst_calibrate_options_init(karst_calibrate_options_t *opt);

/**
 * The ten metrics of Collon et al. 2017 (mean_length ... correlation_vertex_degree), the
 * default distance; *n receives 10.
 */
const char *const *karst_calibrate_default_metrics(int *n);

/**
 * Check metric names for the distance: each a key of karst_metric_fields (unknown names get a
 * "did you mean"), none twice.
 */
karst_error_t karst_calibrate_check_metrics(karst_ctx_t *ctx, int n, const char *const *names);

/** Run, or complete, the calibration in @p dir (see the file comment and docs/calibration.md). */
karst_error_t karst_calibrate_run(karst_ctx_t *ctx, const char *dir,
                                  const karst_calibrate_options_t *opt,
                                  karst_calibrate_summary_t *summary);

#ifdef __cplusplus
}
#endif
#endif
