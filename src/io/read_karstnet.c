/* Karstnet node/link pairs: X_nodes.dat ("x y [z] [properties...]" per line) and
 * X_links.dat ("i j" per line, 1-based node indices), as read by Karstnet's
 * from_nodlink_dat (numpy.loadtxt: whitespace separated, '#' comments, blank lines skipped). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "io/input_internal.h"
#include "karst/readers.h"

enum { MAX_COLUMNS = 64 };

static int ends_with(const char *s, const char *suffix) {
  size_t n = strlen(s), k = strlen(suffix);
  return n >= k && strcmp(s + n - k, suffix) == 0;
}

/* Split @p line at blanks (after stripping a '#' comment) into at most MAX_COLUMNS tokens. */
static int split_line(char *line, char **tok) {
  char *hash = strchr(line, '#');
  if (hash) *hash = '\0';
  int n = 0;
  char *save = NULL;
  for (char *s = strtok_r(line, " \t\r\n\v\f", &save); s;
       s = strtok_r(NULL, " \t\r\n\v\f", &save)) {
    if (n == MAX_COLUMNS) return MAX_COLUMNS + 1;
    tok[n++] = s;
  }
  return n;
}

static int parse_number(const char *s, double *out) {
  char *end;
  errno = 0;
  double v = strtod(s, &end);
  if (end == s || *end != '\0' || !isfinite(v)) return -1;
  *out = v;
  return 0;
}

static karst_error_t read_nodes(karst_ctx_t *ctx, const char *path, karst_network_t *net) {
  karst_error_t err = KARST_SUCCESS;
  char *line = NULL;
  size_t cap = 0;
  long lineno = 0, first_line = 0;
  int ncols = 0;
  FILE *fp;
  if ((err = karst_i_open_regular(ctx, path, "Karstnet", KARST_SURVEY_MAX_BYTES, &fp))) return err;
  while (getline(&line, &cap, fp) >= 0) {
    lineno++;
    char *tok[MAX_COLUMNS];
    int n = split_line(line, tok);
    if (n == 0) continue;
    if (n > MAX_COLUMNS) {
      err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld: more than %d columns", path, lineno,
                            MAX_COLUMNS);
      goto cleanup;
    }
    if (ncols == 0) {
      if (n < 2) {
        err = karst_set_error(ctx, KARST_EPARSE,
                              "%s:%ld: expected node coordinates 'x y [z]', got %d column", path,
                              lineno, n);
        goto cleanup;
      }
      ncols = n;
      first_line = lineno;
    } else if (n != ncols) {
      err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld: expected %d columns as on line %ld, got %d",
                            path, lineno, ncols, first_line, n);
      goto cleanup;
    }
    double v[MAX_COLUMNS];
    for (int c = 0; c < n; c++)
      if (parse_number(tok[c], &v[c])) {
        err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld: column %d: '%s' is not a finite number",
                              path, lineno, c + 1, tok[c]);
        goto cleanup;
      }
    karst_int_t idx;
    /* Karstnet: two columns are x, y with z = 0; columns after z are node properties. */
    if (karst_network_add_node(net, v[0], v[1], n > 2 ? v[2] : 0.0, &idx)) goto nomem;
    if (n > 3) {
      double *d;
      if (karst_network_attr_add(net, KARST_ATTR_NODE, "properties", n - 3, 0, &d)) goto nomem;
      memcpy(d + (size_t)idx * (n - 3), v + 3, (size_t)(n - 3) * sizeof *d);
    }
  }
  if (ferror(fp)) {
    err = karst_set_error(ctx, KARST_EIO, "%s:%ld: read error", path, lineno);
    goto cleanup;
  }
  if (net->n_nodes == 0)
    err = karst_set_error(ctx, KARST_EPARSE, "%s: empty file: no node coordinates", path);
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "%s:%ld: out of memory", path, lineno);
cleanup:
  free(line);
  fclose(fp);
  return err;
}

static karst_error_t read_links(karst_ctx_t *ctx, const char *path, const char *nodes_path,
                                karst_network_t *net) {
  karst_error_t err = KARST_SUCCESS;
  char *line = NULL;
  size_t cap = 0;
  long lineno = 0;
  FILE *fp;
  if ((err = karst_i_open_regular(ctx, path, "Karstnet", KARST_SURVEY_MAX_BYTES, &fp))) return err;
  while (getline(&line, &cap, fp) >= 0) {
    lineno++;
    char *tok[MAX_COLUMNS];
    int n = split_line(line, tok);
    if (n == 0) continue;
    if (n != 2) {
      err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld: expected a link 'i j', got %d column%s",
                            path, lineno, n > MAX_COLUMNS ? MAX_COLUMNS : n, n == 1 ? "" : "s");
      goto cleanup;
    }
    karst_int_t ij[2];
    for (int c = 0; c < 2; c++) {
      double v;
      if (parse_number(tok[c], &v) || v != floor(v) || fabs(v) > 9e15) {
        err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld: column %d: '%s' is not a node number",
                              path, lineno, c + 1, tok[c]);
        goto cleanup;
      }
      if (v < 1 || v > (double)net->n_nodes) {
        err = karst_set_error(ctx, KARST_ERANGE,
                              "%s:%ld: link to node %.0f points %s the node list: links are "
                              "1-based and %s has %lld nodes",
                              path, lineno, v, v < 1 ? "before" : "past", nodes_path,
                              (long long)net->n_nodes);
        goto cleanup;
      }
      ij[c] = (karst_int_t)v - 1;
    }
    if (karst_network_add_edge(net, ij[0], ij[1], NULL)) {
      err = karst_set_error(ctx, KARST_ENOMEM, "%s:%ld: out of memory", path, lineno);
      goto cleanup;
    }
  }
  if (ferror(fp)) {
    err = karst_set_error(ctx, KARST_EIO, "%s:%ld: read error", path, lineno);
    goto cleanup;
  }
  if (net->n_edges == 0) err = karst_set_error(ctx, KARST_EPARSE, "%s: empty file: no links", path);
cleanup:
  free(line);
  fclose(fp);
  return err;
}

/**
 * Read a Karstnet node/link pair into @p net.
 *
 * @param ctx  context (error message "FILE:LINE: ...")
 * @param path X_nodes.dat or X_links.dat (the other file is taken beside it),
 *             or the common prefix X
 * @param net  initialised, empty network; filled only on success
 * @return KARST_SUCCESS; KARST_ENOTFOUND when a file of the pair is missing;
 *         KARST_EPARSE for empty files, wrong column counts, non-numeric values;
 *         KARST_ERANGE for a link pointing outside the node list.
 * Time complexity: O(file size). Format: Karstnet from_nodlink_dat (Collon et al. 2017 data).
 */
karst_error_t karst_read_karstnet(karst_ctx_t *ctx, const char *path, karst_network_t *net) {
  karst_error_t err = KARST_SUCCESS;
  karst_network_t tmp;
  karst_network_init(&tmp);
  size_t n = strlen(path);
  char *base = malloc(n + 16), *nodes = malloc(n + 16), *links = malloc(n + 16);
  if (!base || !nodes || !links) {
    err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
    goto cleanup;
  }
  memcpy(base, path, n + 1);
  if (ends_with(path, "_nodes.dat") || ends_with(path, "_links.dat"))
    base[n - strlen("_nodes.dat")] = '\0';
  snprintf(nodes, n + 16, "%s_nodes.dat", base);
  snprintf(links, n + 16, "%s_links.dat", base);
  for (int i = 0; i < 2; i++) {
    const char *f = i == 0 ? nodes : links;
    struct stat st;
    if (stat(f, &st) != 0) {
      int e = errno;
      err = karst_set_error(ctx, e == ENOENT ? KARST_ENOTFOUND : KARST_EIO,
                            "%s: cannot open %s of the Karstnet pair %s_nodes.dat + "
                            "%s_links.dat: %s",
                            path, f, base, base, strerror(e));
      goto cleanup;
    }
    if ((err = karst_i_check_regular(ctx, f, "Karstnet", KARST_SURVEY_MAX_BYTES))) goto cleanup;
  }
  if ((err = read_nodes(ctx, nodes, &tmp))) goto cleanup;
  if ((err = read_links(ctx, links, nodes, &tmp))) goto cleanup;
  const char *slash = strrchr(base, '/');
  tmp.title = strdup(slash ? slash + 1 : base);
  if (!tmp.title) {
    err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
    goto cleanup;
  }
  karst_network_destroy(net);
  *net = tmp;
  karst_network_init(&tmp);
cleanup:
  karst_network_destroy(&tmp);
  free(base);
  free(nodes);
  free(links);
  return err;
}
