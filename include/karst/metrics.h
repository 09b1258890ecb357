/**
 * @file metrics.h
 * @brief Metrics of Collon et al. 2017 exactly as Karstnet 1.2.0 computes
 *        them (docs/metrics.md), plus reduced- and full-graph counts.
 */
#ifndef KARST_METRICS_H
#define KARST_METRICS_H

#include "karst/common.h"
#include "karst/network.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Every value; undefined ones are NAN (printed as null / empty). */
typedef struct karst_metrics {
  /* full graph */
  karst_int_t nodes, edges;
  double total_length;    /**< sum of 3-D edge lengths (m) */
  double vertical_extent; /**< max z - min z (m) */
  /* the ten metrics, names as Karstnet prints them */
  double mean_length;
  double cv_length;
  double length_entropy;
  double tortuosity;
  double orientation_entropy;
  double aspl;
  double cpd;
  double mean_degree;
  double cv_degree;
  double correlation_vertex_degree;
  /* reduced graph Gs */
  karst_int_t reduced_nodes, reduced_edges, components, cycles, extremities, junctions;
  karst_int_t branches;
  double howard_alpha, howard_beta, howard_gamma;
} karst_metrics_t;

typedef struct karst_metrics_options {
  /** Degrees added (clockwise) to every azimuth before the orientation entropy,
   *  e.g. the meridian convergence gamma of karst_crs_convergence() for
   *  --true-north (true azimuth = grid azimuth + gamma); default 0. */
  double azimuth_rotation;
} karst_metrics_options_t;

/** Defaults: no azimuth rotation. */
void karst_metrics_options_init(karst_metrics_options_t *opt);

/**
 * Compute every metric of @p net (see docs/metrics.md). @p opt may be NULL
 * (defaults). Betweenness uses ctx->nthreads threads; the result does not
 * depend on the thread count.
 */
karst_error_t karst_metrics_compute(karst_ctx_t *ctx, const karst_network_t *net,
                                    const karst_metrics_options_t *opt, karst_metrics_t *out);

/** Metric table: name (JSON/CSV key), offset in karst_metrics_t, integer or double, unit
 *  ("m", "count", "edges" for hop counts, "1" for dimensionless) and what it measures. */
typedef struct karst_metric_field {
  const char *key;
  size_t offset;
  int is_int;
  const char *unit;
  const char *label; /**< the quantity in words, e.g. "mean branch length" */
} karst_metric_field_t;
/** The fields in output order; *n receives the count. */
const karst_metric_field_t *karst_metric_fields(int *n);
/** Value of a field as a double (integers converted). */
double karst_metric_value(const karst_metrics_t *m, const karst_metric_field_t *f);

/** Upper bound on the number of fields of karst_metric_fields(). */
#define KARST_METRIC_FIELDS_MAX 32

/**
 * Range of each metric over the caves of a published table
 * (datasets/published_metrics.csv, Collon et al. 2017 corrected 2021).
 * Indexed like karst_metric_fields(); NAN when the table has no such column.
 */
typedef struct karst_metrics_observed {
  int n_caves;
  int n[KARST_METRIC_FIELDS_MAX]; /**< caves with a value of each field (2-D caves lack some) */
  double min[KARST_METRIC_FIELDS_MAX];
  double max[KARST_METRIC_FIELDS_MAX];
  /** Half a unit in the last printed digit of min / max: the table is rounded. */
  double min_rounding[KARST_METRIC_FIELDS_MAX];
  double max_rounding[KARST_METRIC_FIELDS_MAX];
} karst_metrics_observed_t;

/**
 * Non-zero when @p value of field @p k lies outside the observed range by more
 * than the rounding of the printed bound (so a published cave is never outside
 * its own range). 0 for NAN values or fields without a range.
 */
int karst_metrics_observed_outside(const karst_metrics_observed_t *obs, int k, double value);

/**
 * Read the published table (CSV with '#' comment lines, a header, quoted
 * fields) and keep the min / max of each column that maps to one of our keys
 * (docs/metrics.md lists the mapping). Errors name FILE:LINE.
 */
karst_error_t karst_metrics_observed_load(karst_ctx_t *ctx, const char *path,
                                          karst_metrics_observed_t *obs);

#ifdef __cplusplus
}
#endif
#endif
