/* Ranges of the metrics over published real caves (datasets/published_metrics.csv). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/input_internal.h"
#include "karst/metrics.h"

/* Columns of the published table and the key each one gives (docs/metrics.md). */
static const struct {
  const char *column, *key;
  double scale;
} column_map[] = {
    {"L_km", "total_length", 1000.0},
    {"dZ_m", "vertical_extent", 1.0},
    {"n_stations", "nodes", 1.0},
    {"s_shots", "edges", 1.0},
    {"H_orient", "orientation_entropy", 1.0},
    {"mean_branch_len_m", "mean_length", 1.0},
    {"H_len", "length_entropy", 1.0},
    {"CV_len", "cv_length", 1.0},
    {"tortuosity", "tortuosity", 1.0},
    {"N_reduced", "reduced_nodes", 1.0},
    {"S_reduced", "reduced_edges", 1.0},
    {"p_components", "components", 1.0},
    {"N_cycles", "cycles", 1.0},
    {"howard_alpha", "howard_alpha", 1.0},
    {"howard_beta", "howard_beta", 1.0},
    {"howard_gamma", "howard_gamma", 1.0},
    {"mean_degree_k", "mean_degree", 1.0},
    {"CV_degree", "cv_degree", 1.0},
    {"r_k_assortativity", "correlation_vertex_degree", 1.0},
    {"ASPL", "aspl", 1.0},
    {"CPD", "cpd", 1.0},
};
enum { N_MAP = sizeof column_map / sizeof column_map[0], MAX_COLS = 128 };

/* Half a unit in the last digit of a printed number: "8.464115573" -> 5e-10,
 * "1.2e3" -> 50, "145" -> 0.5. */
static double printed_half_unit(const char *s) {
  int decimals = 0, in_frac = 0;
  long expo = 0;
  for (const char *p = s; *p; p++) {
    if (*p == '.')
      in_frac = 1;
    else if (*p == 'e' || *p == 'E') {
      expo = strtol(p + 1, NULL, 10);
      break;
    } else if (in_frac && *p >= '0' && *p <= '9')
      decimals++;
  }
  return 0.5 * pow(10.0, (double)(expo - decimals));
}

int karst_metrics_observed_outside(const karst_metrics_observed_t *obs, int k, double value) {
  if (k < 0 || k >= KARST_METRIC_FIELDS_MAX || isnan(value) || isnan(obs->min[k])) return 0;
  return value < obs->min[k] - obs->min_rounding[k] || value > obs->max[k] + obs->max_rounding[k];
}

/* One CSV record starting at *pos: fields split at commas, "quoted" fields
 * with "" for a quote (they may hold commas and newlines). Fields are written
 * in place into @p buf (NUL-terminated). Returns the field count, -1 at end of
 * input, -2 for an unterminated quote; *line advances over newlines. */
static int csv_record(const char *buf, size_t len, size_t *pos, char *out, char **field,
                      int max_fields, long *line) {
  size_t i = *pos, o = 0;
  if (i >= len) return -1;
  int nf = 0, quoted = 0;
  field[nf++] = out;
  for (; i < len; i++) {
    char c = buf[i];
    if (quoted) {
      if (c == '"' && i + 1 < len && buf[i + 1] == '"') {
        out[o++] = '"';
        i++;
      } else if (c == '"') {
        quoted = 0;
      } else {
        if (c == '\n') (*line)++;
        out[o++] = c;
      }
    } else if (c == '"') {
      quoted = 1;
    } else if (c == ',') {
      out[o++] = '\0';
      if (nf < max_fields)
        field[nf++] = out + o;
      else
        nf = max_fields + 1;
    } else if (c == '\n') {
      i++;
      (*line)++;
      break;
    } else if (c != '\r') {
      out[o++] = c;
    }
  }
  if (quoted) return -2;
  out[o] = '\0';
  *pos = i;
  return nf > max_fields ? max_fields : nf;
}

/**
 * Read the published metrics table and keep, for each of our keys, the min
 * and max over the caves of Collon et al. 2017: rows whose `source` column
 * cites "Collon" (all rows when the table has no such column). Empty cells
 * (metrics the paper did not compute, e.g. geometry of 2-D maps) are skipped.
 *
 * @param ctx  context (errors as FILE:LINE: message)
 * @param path the CSV file
 * @param obs  receives the ranges (NAN where no value) and the number of caves
 * @return KARST_SUCCESS, KARST_EIO, KARST_EPARSE (no header, non-numeric cell,
 *         unterminated quote), KARST_ENOMEM.
 * Time complexity: O(file size).
 */
karst_error_t karst_metrics_observed_load(karst_ctx_t *ctx, const char *path,
                                          karst_metrics_observed_t *obs) {
  karst_error_t err = KARST_SUCCESS;
  char *buf = NULL, *rec = NULL;
  size_t len = 0;
  int nfields;
  const karst_metric_field_t *fields = karst_metric_fields(&nfields);
  for (int k = 0; k < KARST_METRIC_FIELDS_MAX; k++) {
    obs->min[k] = obs->max[k] = NAN;
    obs->min_rounding[k] = obs->max_rounding[k] = 0.0;
    obs->n[k] = 0;
  }
  obs->n_caves = 0;
  unsigned char *data;
  if ((err = karst_i_read_regular(ctx, path, "observed table", KARST_TABLE_MAX_BYTES, &data, &len)))
    return err;
  buf = (char *)data;
  rec = malloc(len + 1);
  if (!rec) goto nomem;
  int target[MAX_COLS]; /* field index of each column, -1 when unused */
  double scale[MAX_COLS];
  char *name[MAX_COLS];
  int ncols = -1, source_col = -1;
  size_t pos = 0;
  long line = 1;
  for (;;) {
    long rec_line = line;
    if (pos < len && buf[pos] == '#') { /* comment line */
      while (pos < len && buf[pos] != '\n')
        pos++;
      pos++;
      line++;
      continue;
    }
    char *f[MAX_COLS];
    int nf = csv_record(buf, len, &pos, rec, f, MAX_COLS, &line);
    if (nf == -1) break;
    if (nf == -2) {
      err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld: unterminated quoted field", path, rec_line);
      goto cleanup;
    }
    if (nf == 1 && f[0][0] == '\0') continue; /* blank line */
    if (ncols < 0) {
      ncols = nf;
      for (int c = 0; c < nf; c++) {
        target[c] = -1;
        name[c] = NULL;
        if (strcmp(f[c], "source") == 0) source_col = c;
        for (int k = 0; k < N_MAP; k++)
          if (strcmp(f[c], column_map[k].column) == 0)
            for (int j = 0; j < nfields; j++)
              if (strcmp(fields[j].key, column_map[k].key) == 0) {
                target[c] = j;
                scale[c] = column_map[k].scale;
                name[c] = (char *)column_map[k].column;
              }
      }
      continue;
    }
    if (source_col >= 0 && (source_col >= nf || strncmp(f[source_col], "Collon", 6) != 0)) continue;
    obs->n_caves++;
    for (int c = 0; c < nf && c < ncols; c++) {
      if (target[c] < 0 || f[c][0] == '\0') continue;
      char *end;
      double v = strtod(f[c], &end);
      if (end == f[c] || *end != '\0' || !isfinite(v)) {
        err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld: column %s: '%s' is not a number", path,
                              rec_line, name[c], f[c]);
        goto cleanup;
      }
      v *= scale[c];
      double half = printed_half_unit(f[c]) * scale[c];
      int j = target[c];
      obs->n[j]++;
      if (isnan(obs->min[j]) || v < obs->min[j]) {
        obs->min[j] = v;
        obs->min_rounding[j] = half;
      }
      if (isnan(obs->max[j]) || v > obs->max[j]) {
        obs->max[j] = v;
        obs->max_rounding[j] = half;
      }
    }
  }
  if (ncols < 0) err = karst_set_error(ctx, KARST_EPARSE, "%s: empty file: no header", path);
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
cleanup:
  if (err) obs->n_caves = 0;
  free(buf);
  free(rec);
  return err;
}
