/**
 * @file report.h
 * @brief One self-contained HTML page about an ensemble (inline SVG and CSS,
 *        no scripts, no external requests): scenario summary and seed,
 *        per-metric histograms with the survey value and the 34-cave range,
 *        a length-weighted orientation rose, the degree distribution, plan
 *        (x–y) and cross-section (x–z) views of a few members coloured by
 *        tunnel type, the comparison table and the software versions.
 */
#ifndef KARST_REPORT_H
#define KARST_REPORT_H

#include "karst/common.h"
#include "karst/network.h"

#ifdef __cplusplus
extern "C" {
#endif

#define KARST_REPORT_MAX_METRICS 64

/** A survey shown in the report: its metrics and its network (rose and degree overlays). */
typedef struct karst_report_survey {
  char *label;
  int n_values;
  const char *names[KARST_REPORT_MAX_METRICS]; /**< borrowed (static strings) */
  double values[KARST_REPORT_MAX_METRICS];
  karst_network_t net;
} karst_report_survey_t;

void karst_report_survey_init(karst_report_survey_t *s);
void karst_report_survey_destroy(karst_report_survey_t *s);
/** Read a survey (karst_read_network) and compute its metrics (karst_metrics_compute). */
karst_error_t karst_report_survey_load(karst_ctx_t *ctx, const char *path,
                                       karst_report_survey_t *s);

/** Reads a member's network.vtp; NULL means karst_read_network. */
typedef karst_error_t (*karst_report_reader_fn)(karst_ctx_t *ctx, void *user, const char *path,
                                                karst_network_t *net);

typedef struct karst_report_options {
  const karst_report_survey_t *surveys;
  int n_surveys;
  const char *published_path; /**< NULL: karst_published_locate; missing file: ranges omitted */
  int members_drawn;          /**< plan/section views of the first members (default 4) */
  int members_pooled;         /**< members pooled for the rose and degree plots (default 50) */
  karst_report_reader_fn read_network;
  void *read_user;
} karst_report_options_t;

void karst_report_options_init(karst_report_options_t *opt);

/** Write the report of the ensemble in @p ensemble_dir to @p path (atomically). */
karst_error_t karst_report_write(karst_ctx_t *ctx, const char *ensemble_dir, const char *path,
                                 const karst_report_options_t *opt);

#ifdef __cplusplus
}
#endif
#endif
