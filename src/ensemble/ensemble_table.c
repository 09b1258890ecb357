/* Reading an ensemble's metrics.csv back (karst compare, karst report). */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "io/input_internal.h"
#include "karst/ensemble.h"

void karst_ensemble_table_init(karst_ensemble_table_t *t) {
  memset(t, 0, sizeof *t);
}

void karst_ensemble_table_destroy(karst_ensemble_table_t *t) {
  if (t->names)
    for (int k = 0; k < t->n_cols; k++)
      free(t->names[k]);
  free(t->names);
  free(t->index);
  free(t->seed);
  free(t->values);
  memset(t, 0, sizeof *t);
}

int karst_ensemble_table_column(const karst_ensemble_table_t *t, const char *name) {
  for (int k = 0; k < t->n_cols; k++)
    if (strcmp(t->names[k], name) == 0) return k;
  return -1;
}

/* Split @p line in place at commas; returns the number of cells (at most max). */
static int split_commas(char *line, char **cells, int max) {
  int n = 0;
  char *s = line;
  for (;;) {
    if (n < max) cells[n] = s;
    n++;
    char *c = strchr(s, ',');
    if (!c) break;
    *c = '\0';
    s = c + 1;
  }
  return n;
}

/**
 * Read a metrics table written by karst_ensemble_run ("index,seed,<names>",
 * then one row per member; an empty cell is an undefined value, read as NAN).
 * @param t  initialised by the caller; filled on success, left empty on failure.
 * @return KARST_EIO when unreadable; KARST_EPARSE with "FILE:LINE: message"
 *         naming the column on a malformed row.
 * Time complexity: O(size of the file).
 */
karst_error_t karst_ensemble_table_read(karst_ctx_t *ctx, const char *path,
                                        karst_ensemble_table_t *t) {
  karst_error_t err = KARST_SUCCESS;
  char *line = NULL;
  char **cells = NULL;
  size_t cap = 0;
  karst_int_t row_cap = 0, lineno = 0;
  karst_ensemble_table_t r;
  karst_ensemble_table_init(&r);
  FILE *fp;
  if ((err = karst_i_open_regular(ctx, path, "table", KARST_TABLE_MAX_BYTES, &fp))) return err;

  ssize_t len = getline(&line, &cap, fp);
  lineno = 1;
  if (len <= 0) {
    err = karst_set_error(ctx, KARST_EPARSE, "%s:1: empty file, expected a header line", path);
    goto cleanup;
  }
  line[strcspn(line, "\r\n")] = '\0';
  int ncells = 1;
  for (char *c = line; *c; c++)
    ncells += *c == ',';
  cells = calloc((size_t)ncells, sizeof *cells);
  if (!cells) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  split_commas(line, cells, ncells);
  if (ncells < 2 || strcmp(cells[0], "index") != 0 || strcmp(cells[1], "seed") != 0) {
    err = karst_set_error(ctx, KARST_EPARSE,
                          "%s:1: the header must start with \"index,seed\", got \"%s,%s\"", path,
                          cells[0], ncells > 1 ? cells[1] : "");
    goto cleanup;
  }
  r.n_cols = ncells - 2;
  r.names = calloc((size_t)(r.n_cols > 0 ? r.n_cols : 1), sizeof *r.names);
  if (!r.names) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  for (int k = 0; k < r.n_cols; k++) {
    r.names[k] = strdup(cells[k + 2]);
    if (!r.names[k]) {
      err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
      goto cleanup;
    }
    if (!*r.names[k]) {
      err = karst_set_error(ctx, KARST_EPARSE, "%s:1: column %d has an empty name", path, k + 3);
      goto cleanup;
    }
  }

  while ((len = getline(&line, &cap, fp)) > 0) {
    lineno++;
    line[strcspn(line, "\r\n")] = '\0';
    if (!*line) continue;
    int got = split_commas(line, cells, ncells);
    if (got != ncells) {
      err = karst_set_error(ctx, KARST_EPARSE, "%s:%" PRId64 ": %d cells, expected %d", path,
                            lineno, got, ncells);
      goto cleanup;
    }
    if (r.n_rows == row_cap) {
      row_cap = row_cap ? 2 * row_cap : 64;
      karst_int_t *ni = realloc(r.index, (size_t)row_cap * sizeof *ni);
      if (ni) r.index = ni;
      uint64_t *ns = realloc(r.seed, (size_t)row_cap * sizeof *ns);
      if (ns) r.seed = ns;
      double *nv = realloc(r.values, (size_t)row_cap * (size_t)(r.n_cols + 1) * sizeof *nv);
      if (nv) r.values = nv;
      if (!ni || !ns || !nv) {
        err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
        goto cleanup;
      }
    }
    char *end;
    errno = 0;
    long long idx = strtoll(cells[0], &end, 10);
    if (errno || *end || end == cells[0] || idx < 0) {
      err = karst_set_error(ctx, KARST_EPARSE,
                            "%s:%" PRId64 ": index must be a non-negative integer, got \"%s\"",
                            path, lineno, cells[0]);
      goto cleanup;
    }
    errno = 0;
    unsigned long long sd = strtoull(cells[1], &end, 10);
    if (errno || *end || end == cells[1] || cells[1][0] == '-') {
      err = karst_set_error(ctx, KARST_EPARSE,
                            "%s:%" PRId64 ": seed must be an unsigned integer, got \"%s\"", path,
                            lineno, cells[1]);
      goto cleanup;
    }
    r.index[r.n_rows] = (karst_int_t)idx;
    r.seed[r.n_rows] = (uint64_t)sd;
    for (int k = 0; k < r.n_cols; k++) {
      const char *c = cells[k + 2];
      double v = NAN;
      if (*c) {
        errno = 0;
        v = strtod(c, &end);
        if (*end || end == c || isnan(v)) {
          err = karst_set_error(ctx, KARST_EPARSE,
                                "%s:%" PRId64 ": column '%s' must be a number or empty, got \"%s\"",
                                path, lineno, r.names[k], c);
          goto cleanup;
        }
      }
      r.values[r.n_rows * r.n_cols + k] = v;
    }
    r.n_rows++;
  }
  *t = r;
  karst_ensemble_table_init(&r);
cleanup:
  karst_ensemble_table_destroy(&r);
  free(cells);
  free(line);
  fclose(fp);
  return err;
}
