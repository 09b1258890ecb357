/* Comparison of field surveys with an ensemble (include/karst/compare.h). */
#include "karst/io.h"
#include "karst/compare.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "karst/metrics.h"
#include "karst/readers.h"

/* ------------------------------------------------------------------------ */
/* Statistics                                                               */
/* ------------------------------------------------------------------------ */

/**
 * Quantile of sorted data, Hyndman & Fan (1996) definition 7 (linear
 * interpolation between order statistics; R's and NumPy's default):
 * h = (n − 1) p, q = x[⌊h⌋] + (h − ⌊h⌋) (x[⌊h⌋ + 1] − x[⌊h⌋]).
 * @param sorted ascending values, @p n >= 1; @param p in [0, 1] (clamped).
 * @return the quantile, NAN when n < 1. Time complexity: O(1).
 */
double karst_compare_quantile(const double *sorted, karst_int_t n, double p) {
  if (n < 1 || isnan(p)) return NAN;
  if (p <= 0) return sorted[0];
  if (p >= 1) return sorted[n - 1];
  double h = (double)(n - 1) * p;
  karst_int_t lo = (karst_int_t)floor(h);
  if (lo >= n - 1) return sorted[n - 1];
  return sorted[lo] + (h - (double)lo) * (sorted[lo + 1] - sorted[lo]);
}

/**
 * Percentile of @p v within @p sorted: 100 × #{x ≤ v} / n, the empirical
 * distribution function at v (ties count as at or below).
 * @return a value in [0, 100]; NAN when n = 0 or v is NAN.
 * Time complexity: O(log n) (binary search for the last x ≤ v).
 */
double karst_compare_percentile(const double *sorted, karst_int_t n, double v) {
  if (n < 1 || isnan(v)) return NAN;
  karst_int_t lo = 0, hi = n; /* first index with sorted[i] > v */
  while (lo < hi) {
    karst_int_t mid = lo + (hi - lo) / 2;
    if (sorted[mid] <= v)
      lo = mid + 1;
    else
      hi = mid;
  }
  return 100.0 * (double)lo / (double)n;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* Sorted copy of the defined values (NAN skipped). */
static karst_error_t sorted_defined(karst_ctx_t *ctx, const double *values, karst_int_t n,
                                    karst_int_t stride, double **out, karst_int_t *m) {
  double *s = malloc((size_t)(n > 0 ? n : 1) * sizeof *s);
  if (!s) return karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  karst_int_t k = 0;
  for (karst_int_t i = 0; i < n; i++) {
    double v = values[i * stride];
    if (!isnan(v)) s[k++] = v;
  }
  qsort(s, (size_t)k, sizeof *s, cmp_double);
  *out = s;
  *m = k;
  return KARST_SUCCESS;
}

/**
 * Ensemble statistics of one metric: n, mean, sample standard deviation
 * (divisor n − 1), type-7 5th and 95th percentiles, min and max.
 * @param values @p n entries, @p stride apart (a column of a row-major table);
 *        NAN entries are left out. Undefined statistics are NAN (all of them
 *        for n = 0, sd for n = 1).
 * The mean is the plain sum divided by n; the variance uses the two-pass
 * formula Σ(x − mean)² / (n − 1), which avoids the cancellation of the
 * one-pass Σx² − n·mean² (Chan, Golub & LeVeque 1983).
 * Time complexity: O(n log n).
 */
karst_error_t karst_compare_stats(karst_ctx_t *ctx, const double *values, karst_int_t n,
                                  karst_int_t stride, karst_compare_stats_t *out) {
  double *s = NULL;
  karst_int_t m = 0;
  karst_error_t err = sorted_defined(ctx, values, n, stride, &s, &m);
  if (err) return err;
  karst_compare_stats_t st = {m, NAN, NAN, NAN, NAN, NAN, NAN};
  if (m > 0) {
    double sum = 0;
    for (karst_int_t i = 0; i < m; i++)
      sum += s[i];
    st.mean = sum / (double)m;
    if (m > 1) {
      double ss = 0;
      for (karst_int_t i = 0; i < m; i++)
        ss += (s[i] - st.mean) * (s[i] - st.mean);
      st.sd = sqrt(ss / (double)(m - 1));
    }
    st.p05 = karst_compare_quantile(s, m, 0.05);
    st.p95 = karst_compare_quantile(s, m, 0.95);
    st.min = s[0];
    st.max = s[m - 1];
  }
  *out = st;
  free(s);
  return KARST_SUCCESS;
}

/* ------------------------------------------------------------------------ */
/* The published table                                                      */
/* ------------------------------------------------------------------------ */
void karst_published_init(karst_published_t *p) {
  memset(p, 0, sizeof *p);
}
void karst_published_destroy(karst_published_t *p) {
  free(p->ranges);
  memset(p, 0, sizeof *p);
}

/**
 * Read the published ranges (see compare.h) through the metrics module's
 * reader of the same table (karst_metrics_observed_load: one CSV parser and
 * one column mapping for `karst metrics --observed`, compare and report).
 * Only the rows of Collon et al. 2017 (corrected 2021) count, the 34 caves;
 * empty cells (2-D caves have no geometric metrics) are skipped, so n may be
 * below 34. Time complexity: O(size of the file).
 */
karst_error_t karst_published_read(karst_ctx_t *ctx, const char *path, karst_published_t *p) {
  karst_metrics_observed_t obs;
  karst_error_t err = karst_metrics_observed_load(ctx, path, &obs);
  if (err) return err;
  int nf;
  const karst_metric_field_t *fields = karst_metric_fields(&nf);
  karst_published_t r;
  karst_published_init(&r);
  r.ranges = calloc((size_t)nf, sizeof *r.ranges);
  if (!r.ranges) return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
  for (int k = 0; k < nf; k++) {
    if (obs.n[k] == 0) continue;
    karst_published_range_t *g = &r.ranges[r.n_ranges++];
    snprintf(g->key, sizeof g->key, "%s", fields[k].key);
    g->n = obs.n[k];
    g->min = obs.min[k];
    g->max = obs.max[k];
  }
  r.n_caves = obs.n_caves;
  karst_published_destroy(p);
  *p = r;
  return KARST_SUCCESS;
}

const karst_published_range_t *karst_published_find(const karst_published_t *p, const char *key) {
  if (!p) return NULL;
  for (int k = 0; k < p->n_ranges; k++)
    if (strcmp(p->ranges[k].key, key) == 0) return &p->ranges[k];
  return NULL;
}

static int is_file(const char *path) {
  struct stat st;
  return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

karst_error_t karst_published_locate(karst_ctx_t *ctx, char *out, size_t size) {
  const char *name = "published_metrics.csv";
  char tried[1024] = "";
  const char *env = getenv("KARST_DATA_DIR");
  if (env && *env) {
    snprintf(out, size, "%s/%s", env, name);
    if (is_file(out)) return KARST_SUCCESS;
    snprintf(tried + strlen(tried), sizeof tried - strlen(tried), " %s", out);
  }
  char exe[512];
  ssize_t len = readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (len > 0) {
    exe[len] = '\0';
    char *slash = strrchr(exe, '/');
    if (slash) *slash = '\0';
    static const char *const rel[] = {"../datasets", "../../datasets", "../share/karst"};
    for (size_t i = 0; i < sizeof rel / sizeof rel[0]; i++) {
      snprintf(out, size, "%s/%s/%s", exe, rel[i], name);
      if (is_file(out)) return KARST_SUCCESS;
      snprintf(tried + strlen(tried), sizeof tried - strlen(tried), " %s", out);
    }
  }
#ifdef KARST_DATADIR
  snprintf(out, size, "%s/%s", KARST_DATADIR, name); /* the installed copy */
  if (is_file(out)) return KARST_SUCCESS;
  snprintf(tried + strlen(tried), sizeof tried - strlen(tried), " %s", out);
#endif
  snprintf(out, size, "datasets/%s", name);
  if (is_file(out)) return KARST_SUCCESS;
  snprintf(tried + strlen(tried), sizeof tried - strlen(tried), " %s", out);
  out[0] = '\0';
  return karst_set_error(ctx, KARST_ENOTFOUND,
                         "cannot find %s (tried:%s); set KARST_DATA_DIR to karst's datasets/ "
                         "folder or pass --published FILE",
                         name, tried);
}

/* ------------------------------------------------------------------------ */
/* Comparison                                                               */
/* ------------------------------------------------------------------------ */
void karst_compare_result_init(karst_compare_result_t *r) {
  memset(r, 0, sizeof *r);
}
void karst_compare_result_destroy(karst_compare_result_t *r) {
  free(r->label);
  free(r->rows);
  memset(r, 0, sizeof *r);
}

/**
 * One row per metric column of @p table (see compare.h for every definition).
 * Time complexity: O(columns × members log members).
 */
karst_error_t karst_compare_compute(karst_ctx_t *ctx, const karst_ensemble_table_t *table,
                                    const char *label, const char *const *names,
                                    const double *values, int n_values,
                                    const karst_published_t *pub, karst_compare_result_t *out) {
  karst_error_t err = KARST_SUCCESS;
  karst_compare_result_t r;
  double *sorted = NULL;
  karst_compare_result_init(&r);
  r.label = label ? strdup(label) : NULL;
  r.rows = calloc((size_t)(table->n_cols > 0 ? table->n_cols : 1), sizeof *r.rows);
  if ((label && !r.label) || !r.rows) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  r.n_rows = table->n_cols;
  for (int c = 0; c < table->n_cols; c++) {
    karst_compare_row_t *row = &r.rows[c];
    snprintf(row->metric, sizeof row->metric, "%s", table->names[c]);
    err = karst_compare_stats(ctx, table->values + c, table->n_rows, table->n_cols, &row->ens);
    if (err) goto cleanup;
    row->survey = NAN;
    for (int k = 0; k < n_values; k++)
      if (names[k] && strcmp(names[k], table->names[c]) == 0) row->survey = values[k];
    karst_int_t m = 0;
    free(sorted);
    sorted = NULL;
    err = sorted_defined(ctx, table->values + c, table->n_rows, table->n_cols, &sorted, &m);
    if (err) goto cleanup;
    row->percentile = karst_compare_percentile(sorted, m, row->survey);
    row->outside =
        !isnan(row->survey) && m > 0 && (row->survey < row->ens.p05 || row->survey > row->ens.p95);
    const karst_published_range_t *g = karst_published_find(pub, table->names[c]);
    row->published_min = row->published_max = NAN;
    if (g && g->n > 0) {
      row->has_published = 1;
      row->published_min = g->min;
      row->published_max = g->max;
      row->published_n = g->n;
    }
  }
  *out = r;
  karst_compare_result_init(&r);
cleanup:
  free(sorted);
  karst_compare_result_destroy(&r);
  return err;
}

/**
 * Read a survey with karst_read_network and compute its metrics with
 * karst_metrics_compute, in the order of karst_metric_fields.
 * Time complexity: that of the reader and of the metrics.
 */
karst_error_t karst_compare_survey_metrics(karst_ctx_t *ctx, const char *path, int max,
                                           const char **names, double *values, int *n) {
  karst_network_t net;
  karst_metrics_options_t mo;
  karst_metrics_t m;
  int nf = 0;
  karst_network_init(&net);
  *n = 0;
  karst_error_t err = karst_read_network(ctx, path, KARST_FORMAT_AUTO, &net);
  if (err) goto cleanup;
  karst_metrics_options_init(&mo);
  err = karst_metrics_compute(ctx, &net, &mo, &m);
  if (err) goto cleanup;
  const karst_metric_field_t *f = karst_metric_fields(&nf);
  for (int k = 0; k < nf && k < max; k++) {
    names[k] = f[k].key;
    values[k] = karst_metric_value(&m, &f[k]);
    (*n)++;
  }
cleanup:
  karst_network_destroy(&net);
  return err;
}

/* ------------------------------------------------------------------------ */
/* Output                                                                   */
/* ------------------------------------------------------------------------ */
int karst_compare_format_from_name(const char *name) {
  if (strcmp(name, "table") == 0) return KARST_COMPARE_TABLE;
  if (strcmp(name, "csv") == 0) return KARST_COMPARE_CSV;
  if (strcmp(name, "json") == 0) return KARST_COMPARE_JSON;
  return -1;
}

static void csv_num(FILE *fp, double v) {
  fputc(',', fp);
  if (!isnan(v)) fprintf(fp, "%.17g", v);
}
static void json_num(FILE *fp, const char *key, double v, int comma) {
  fprintf(fp, "\"%s\": ", key);
  if (isfinite(v))
    fprintf(fp, "%.17g", v);
  else
    fputs("null", fp);
  if (comma) fputs(", ", fp);
}
static void csv_str(FILE *fp, const char *s) {
  if (!strpbrk(s, ",\"\n\r")) {
    fputs(s, fp);
    return;
  }
  fputc('"', fp);
  for (const char *p = s; *p; p++) {
    if (*p == '"') fputc('"', fp);
    fputc(*p, fp);
  }
  fputc('"', fp);
}
static void table_num(FILE *fp, double v, int width) {
  if (isnan(v))
    fprintf(fp, " %*s", width, "-");
  else
    fprintf(fp, " %*.4g", width, v);
}

/**
 * Print comparisons. table: one block per survey for people; csv: header
 * "survey,metric,survey_value,percentile,n,mean,sd,p05,p95,min,max,
 * published_min,published_max,published_n,outside_5_95" and one row per
 * survey and metric (%.17g, empty when undefined); json: an array of
 * {"survey": ..., "metrics": {key: {...}}} (null when undefined).
 * Time complexity: O(surveys × metrics).
 */
karst_error_t karst_compare_write(karst_ctx_t *ctx, FILE *fp, karst_compare_format_t format,
                                  const karst_compare_result_t *results, int n) {
  if (format == KARST_COMPARE_CSV) {
    fputs("survey,metric,survey_value,percentile,n,mean,sd,p05,p95,min,max,published_min,"
          "published_max,published_n,outside_5_95\n",
          fp);
    for (int s = 0; s < n; s++)
      for (int k = 0; k < results[s].n_rows; k++) {
        const karst_compare_row_t *r = &results[s].rows[k];
        csv_str(fp, results[s].label ? results[s].label : "");
        fputc(',', fp);
        csv_str(fp, r->metric);
        csv_num(fp, r->survey);
        csv_num(fp, r->percentile);
        fprintf(fp, ",%" PRId64, r->ens.n);
        csv_num(fp, r->ens.mean);
        csv_num(fp, r->ens.sd);
        csv_num(fp, r->ens.p05);
        csv_num(fp, r->ens.p95);
        csv_num(fp, r->ens.min);
        csv_num(fp, r->ens.max);
        csv_num(fp, r->published_min);
        csv_num(fp, r->published_max);
        fprintf(fp, ",%d,%d\n", r->published_n, r->outside);
      }
  } else if (format == KARST_COMPARE_JSON) {
    fputs("[", fp);
    for (int s = 0; s < n; s++) {
      fputs(s ? ",\n {\"survey\": " : "\n {\"survey\": ", fp);
      if (results[s].label)
        karst_json_string(fp, results[s].label);
      else
        fputs("null", fp);
      fputs(", \"metrics\": {", fp);
      for (int k = 0; k < results[s].n_rows; k++) {
        const karst_compare_row_t *r = &results[s].rows[k];
        fputs(k ? ",\n   " : "\n   ", fp);
        karst_json_string(fp, r->metric);
        fputs(": {", fp);
        json_num(fp, "survey", r->survey, 1);
        json_num(fp, "percentile", r->percentile, 1);
        fprintf(fp, "\"n\": %" PRId64 ", ", r->ens.n);
        json_num(fp, "mean", r->ens.mean, 1);
        json_num(fp, "sd", r->ens.sd, 1);
        json_num(fp, "p05", r->ens.p05, 1);
        json_num(fp, "p95", r->ens.p95, 1);
        json_num(fp, "min", r->ens.min, 1);
        json_num(fp, "max", r->ens.max, 1);
        json_num(fp, "published_min", r->published_min, 1);
        json_num(fp, "published_max", r->published_max, 1);
        fprintf(fp, "\"published_n\": %d, \"outside_5_95\": %s}", r->published_n,
                r->outside ? "true" : "false");
      }
      fputs("\n }}", fp);
    }
    fputs("\n]\n", fp);
  } else if (format == KARST_COMPARE_TABLE) {
    for (int s = 0; s < n; s++) {
      const karst_compare_result_t *res = &results[s];
      if (s) fputc('\n', fp);
      fprintf(fp, "survey: %s\n", res->label ? res->label : "(none: ensemble statistics only)");
      fprintf(fp, "%-26s %10s %6s %10s %10s %10s %10s %23s  %s\n", "metric", "survey", "pctl",
              "mean", "sd", "p5", "p95", "34 caves: min - max (n)", "flag");
      for (int k = 0; k < res->n_rows; k++) {
        const karst_compare_row_t *r = &res->rows[k];
        fprintf(fp, "%-26s", r->metric);
        table_num(fp, r->survey, 10);
        if (isnan(r->percentile))
          fprintf(fp, " %6s", "-");
        else
          fprintf(fp, " %5.1f%%", r->percentile);
        table_num(fp, r->ens.mean, 10);
        table_num(fp, r->ens.sd, 10);
        table_num(fp, r->ens.p05, 10);
        table_num(fp, r->ens.p95, 10);
        if (r->has_published) {
          char buf[64];
          snprintf(buf, sizeof buf, "%.4g - %.4g (%d)", r->published_min, r->published_max,
                   r->published_n);
          fprintf(fp, " %23s", buf);
        } else {
          fprintf(fp, " %23s", "-");
        }
        fprintf(fp, "  %s\n", r->outside ? "OUTSIDE 5-95%" : "");
      }
    }
  } else {
    return karst_set_error(ctx, KARST_EINVAL, "unknown output format %d", (int)format);
  }
  if (ferror(fp)) return karst_set_error(ctx, KARST_EIO, "cannot write the comparison");
  return KARST_SUCCESS;
}
