/**
 * @file compare.h
 * @brief Where a surveyed cave falls within an ensemble: per-metric ensemble
 *        statistics (mean, standard deviation, 5th and 95th percentiles), the
 *        survey's percentile, the range of the 34 caves of Collon et al. 2017
 *        (datasets/published_metrics.csv) and a flag outside the 5–95 % band.
 *
 * Definitions (docs/ensembles.md):
 *  - undefined member values (empty cells) are left out; n counts the rest;
 *  - mean = Σx/n; sd = sample standard deviation, divisor n − 1 (NAN for n < 2);
 *  - quantile q_p: Hyndman & Fan (1996) type 7, linear interpolation between
 *    order statistics: h = (n − 1) p, q = x_(⌊h⌋) + (h − ⌊h⌋)(x_(⌊h⌋+1) − x_(⌊h⌋))
 *    on the sorted values x_(0) ≤ … ≤ x_(n−1) (R's and NumPy's default);
 *  - percentile of a survey value v: 100 × #{members ≤ v} / n (the empirical
 *    distribution function, so ties count as below; 0 below every member,
 *    100 at or above the largest);
 *  - outside the band: v < q_0.05 or v > q_0.95.
 */
#ifndef KARST_COMPARE_H
#define KARST_COMPARE_H

#include <stdio.h>

#include "karst/common.h"
#include "karst/ensemble.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Ensemble statistics of one metric. */
typedef struct karst_compare_stats {
  karst_int_t n;   /**< defined values */
  double mean, sd; /**< sd: divisor n − 1 */
  double p05, p95; /**< type-7 quantiles */
  double min, max;
} karst_compare_stats_t;

/** Type-7 quantile of @p sorted (ascending, n >= 1), p in [0, 1]. O(1). */
double karst_compare_quantile(const double *sorted, karst_int_t n, double p);
/** 100 × #{sorted ≤ v} / n (NAN when n = 0 or v is NAN). O(log n). */
double karst_compare_percentile(const double *sorted, karst_int_t n, double v);
/** Statistics of @p values (NAN entries skipped; @p stride between entries). O(n log n). */
karst_error_t karst_compare_stats(karst_ctx_t *ctx, const double *values, karst_int_t n,
                                  karst_int_t stride, karst_compare_stats_t *out);

/** Range of one metric over the published caves. */
typedef struct karst_published_range {
  char key[48]; /**< our metric key, e.g. "orientation_entropy" */
  int n;        /**< caves with a value */
  double min, max;
} karst_published_range_t;

typedef struct karst_published {
  int n_caves; /**< caves read (rows of Collon et al. 2017) */
  int n_ranges;
  karst_published_range_t *ranges;
} karst_published_t;

void karst_published_init(karst_published_t *p);
void karst_published_destroy(karst_published_t *p);
/**
 * Read published_metrics.csv: only the rows of Collon et al. 2017 (source
 * column starting with "Collon"), the 34 caves; columns mapped to our keys
 * (L_km → total_length in metres ...). Errors name FILE:LINE.
 */
karst_error_t karst_published_read(karst_ctx_t *ctx, const char *path, karst_published_t *p);
/** Range for @p key, or NULL. */
const karst_published_range_t *karst_published_find(const karst_published_t *p, const char *key);
/**
 * Find datasets/published_metrics.csv: $KARST_DATA_DIR, then beside the
 * running program (../datasets, ../../datasets: a build tree; ../share/karst: an
 * installed prefix), then the installed data directory, then ./datasets. Writes the path into @p out. KARST_ENOTFOUND names the places tried.
 */
karst_error_t karst_published_locate(karst_ctx_t *ctx, char *out, size_t size);

/** One metric of one comparison. */
typedef struct karst_compare_row {
  char metric[48];
  double survey;     /**< NAN without survey or when undefined */
  double percentile; /**< of the survey value; NAN when undefined */
  karst_compare_stats_t ens;
  int has_published;
  double published_min, published_max;
  int published_n;
  int outside; /**< survey outside [p05, p95] */
} karst_compare_row_t;

/** A comparison of one survey (or none) with an ensemble. */
typedef struct karst_compare_result {
  char *label; /**< survey file, or NULL for ensemble statistics only */
  int n_rows;
  karst_compare_row_t *rows;
} karst_compare_result_t;

void karst_compare_result_init(karst_compare_result_t *r);
void karst_compare_result_destroy(karst_compare_result_t *r);

/**
 * Compare: one row per metric column of @p table; the survey value of a
 * column is taken from (@p names, @p values, @p n_values) by name (NAN when
 * absent, or when @p n_values = 0). @p pub may be NULL. @p label is copied.
 */
karst_error_t karst_compare_compute(karst_ctx_t *ctx, const karst_ensemble_table_t *table,
                                    const char *label, const char *const *names,
                                    const double *values, int n_values,
                                    const karst_published_t *pub, karst_compare_result_t *out);

/**
 * Metrics of a survey file (any format karst_read_network reads) in the
 * order of karst_metric_fields: @p names (borrowed) and @p values receive up
 * to @p max entries; *n the count.
 */
karst_error_t karst_compare_survey_metrics(karst_ctx_t *ctx, const char *path, int max,
                                           const char **names, double *values, int *n);

typedef enum {
  KARST_COMPARE_TABLE = 0,
  KARST_COMPARE_CSV = 1,
  KARST_COMPARE_JSON = 2
} karst_compare_format_t;

/** Parse "table", "csv" or "json"; -1 when unknown. */
int karst_compare_format_from_name(const char *name);
/** Print @p n results in @p format (csv: one header, one row per survey and metric). */
karst_error_t karst_compare_write(karst_ctx_t *ctx, FILE *fp, karst_compare_format_t format,
                                  const karst_compare_result_t *results, int n);

#ifdef __cplusplus
}
#endif
#endif
