/* ESRI ASCII grid heightfields, the file hash recorded in run outputs, and the
 * "did you mean" helper used by the scenario reader. */
#include <ctype.h>
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "scenario_internal.h"

/* ------------------------------------------------------------------------ */
/* Suggestions                                                              */
/* ------------------------------------------------------------------------ */

/**
 * Levenshtein distance (insertions, deletions, substitutions) with two rows
 * of the dynamic programme; returns cap + 1 as soon as every entry of a row
 * exceeds @p cap. O(|a| |b|) time, O(|b|) memory.
 */
int karst_i_edit_distance(const char *a, const char *b, int cap) {
  size_t la = strlen(a), lb = strlen(b);
  if (la > 64 || lb > 64) return strcmp(a, b) == 0 ? 0 : cap + 1; /* names are short */
  int prev[65], cur[65];
  for (size_t j = 0; j <= lb; j++)
    prev[j] = (int)j;
  for (size_t i = 1; i <= la; i++) {
    cur[0] = (int)i;
    int rowmin = cur[0];
    for (size_t j = 1; j <= lb; j++) {
      int sub = prev[j - 1] + (a[i - 1] != b[j - 1]);
      int del = prev[j] + 1, ins = cur[j - 1] + 1;
      int v = sub < del ? sub : del;
      cur[j] = v < ins ? v : ins;
      if (cur[j] < rowmin) rowmin = cur[j];
    }
    if (rowmin > cap) return cap + 1;
    memcpy(prev, cur, sizeof(int) * (lb + 1));
  }
  return prev[lb];
}

/**
 * Closest candidate to @p word when it is at most
 * min(KARST_I_SUGGEST_MAX_EDITS, max(1, |word| / 2)) edits away, else NULL;
 * ties go to the first candidate. O(n |word| max|candidate|).
 */
const char *karst_i_suggest(const char *word, const char *const *candidates, int n) {
  int len = (int)strlen(word);
  int cap = len / 2 > 1 ? len / 2 : 1;
  if (cap > KARST_I_SUGGEST_MAX_EDITS) cap = KARST_I_SUGGEST_MAX_EDITS;
  const char *best = NULL;
  int bestd = cap + 1;
  for (int i = 0; i < n; i++) {
    if (!candidates[i]) continue;
    int d = karst_i_edit_distance(word, candidates[i], cap);
    if (d < bestd) {
      bestd = d;
      best = candidates[i];
    }
  }
  return best;
}

/* ------------------------------------------------------------------------ */
/* File hash                                                                */
/* ------------------------------------------------------------------------ */

/**
 * FNV-1a 64-bit hash of a file's bytes (Fowler, Noll & Vo; offset basis
 * 0xcbf29ce484222325, prime 0x100000001b3), written as 16 lower-case hex
 * digits. Used to record which scenario produced an output.
 * @param ctx  context for the error message
 * @param path file to hash
 * @param out  receives the 16 digits and a terminating NUL
 * @return KARST_SUCCESS, or KARST_EIO when the file cannot be read or is not a regular
 *         file (karst_i_open_regular), KARST_ERANGE above KARST_INPUT_MAX_BYTES.
 * Time complexity: O(file size).
 */
karst_error_t karst_file_hash(karst_ctx_t *ctx, const char *path, char out[17]) {
  karst_error_t err = KARST_SUCCESS;
  uint64_t h = 0xcbf29ce484222325ULL;
  unsigned char buf[65536];
  FILE *fp;
  if ((err = karst_i_open_regular(ctx, path, "input", KARST_INPUT_MAX_BYTES, &fp))) return err;
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, fp)) > 0) {
    for (size_t i = 0; i < n; i++) {
      h ^= buf[i];
      h *= 0x100000001b3ULL;
    }
  }
  if (ferror(fp)) {
    err = karst_set_error(ctx, KARST_EIO, "%s: cannot read: %s", path, strerror(errno));
    goto cleanup;
  }
  snprintf(out, 17, "%016" PRIx64, h);
cleanup:
  fclose(fp);
  return err;
}

/* ------------------------------------------------------------------------ */
/* ESRI ASCII grid                                                          */
/* ------------------------------------------------------------------------ */

/* Header fields, in their usual order. */
enum {
  H_NCOLS,
  H_NROWS,
  H_XLLCORNER,
  H_XLLCENTER,
  H_YLLCORNER,
  H_YLLCENTER,
  H_CELLSIZE,
  H_NODATA,
  H_COUNT
};
static const char *const header_names[H_COUNT] = {"ncols",     "nrows",       "xllcorner",
                                                  "xllcenter", "yllcorner",   "yllcenter",
                                                  "cellsize",  "nodata_value"};

typedef struct grid_reader {
  karst_ctx_t *ctx;
  const char *name;
  FILE *fp;
  char *line;
  size_t cap;
  int lineno;
  long long bytes; /* read so far, against KARST_HEIGHTFIELD_MAX_BYTES */
} grid_reader_t;

/* Next line (without its end-of-line characters); 0 at end of file. */
static int next_line(grid_reader_t *g) {
  ssize_t n = getline(&g->line, &g->cap, g->fp);
  if (n < 0) return 0;
  g->bytes += n;
  g->lineno++;
  while (n > 0 && (g->line[n - 1] == '\n' || g->line[n - 1] == '\r'))
    g->line[--n] = '\0';
  return 1;
}

static const char *skip_space(const char *s) {
  while (*s == ' ' || *s == '\t')
    s++;
  return s;
}

static const char *token_end(const char *s) {
  while (*s && *s != ' ' && *s != '\t')
    s++;
  return s;
}

/* Copy a token for a message (shortened, control characters replaced). */
static void token_text(const char *s, const char *e, char *out, size_t outsz) {
  size_t n = (size_t)(e - s), k = 0;
  for (size_t i = 0; i < n && k + 4 < outsz; i++) {
    unsigned char c = (unsigned char)s[i];
    out[k++] = (c < 32 || c == 127) ? '?' : (char)c;
  }
  if (k < n && k + 4 <= outsz) {
    memcpy(out + k, "...", 3);
    k += 3;
  }
  out[k] = '\0';
}

/* Parse the token [s, e) as a finite double; 0 on success. */
static int parse_double(const char *s, const char *e, double *v) {
  char buf[128];
  size_t n = (size_t)(e - s);
  if (n == 0 || n >= sizeof buf) return -1;
  memcpy(buf, s, n);
  buf[n] = '\0';
  char *end;
  errno = 0;
  *v = strtod(buf, &end);
  if (end != buf + n) return -1;
  if (!isfinite(*v)) return -2;
  return 0;
}

/* Parse the token [s, e) as a decimal integer; 0 on success. */
static int parse_int64(const char *s, const char *e, int64_t *v) {
  char buf[32];
  size_t n = (size_t)(e - s);
  if (n == 0 || n >= sizeof buf) return -1;
  memcpy(buf, s, n);
  buf[n] = '\0';
  for (size_t i = (buf[0] == '+' || buf[0] == '-'); i < n; i++)
    if (!isdigit((unsigned char)buf[i])) return -1;
  char *end;
  errno = 0;
  long long x = strtoll(buf, &end, 10);
  if (end != buf + n || errno == ERANGE) return -1;
  *v = (int64_t)x;
  return 0;
}

/**
 * Lipschitz constant of the bilinear surface: inside a cell, dh/dx is linear
 * in v only and dh/dy linear in u only, so |grad h| is largest at a corner,
 * where it is sqrt(max(|dz_south|, |dz_north|)^2 + max(|dz_west|, |dz_east|)^2)
 * / cellsize. The surface is continuous, so its Lipschitz constant is the
 * largest over the cells (clamping outside the grid only flattens it). O(cells).
 */
static double grid_lipschitz(const karst_terrain_t *t) {
  double best = 0;
  karst_int_t nc = t->ncols, nr = t->nrows;
  karst_int_t ci = nc > 1 ? nc - 1 : 1, cj = nr > 1 ? nr - 1 : 1;
  for (karst_int_t j = 0; j < cj; j++) {
    for (karst_int_t i = 0; i < ci; i++) {
      karst_int_t i1 = nc > 1 ? i + 1 : i, j1 = nr > 1 ? j + 1 : j;
      double z00 = t->z[j * nc + i], z10 = t->z[j * nc + i1];
      double z01 = t->z[j1 * nc + i], z11 = t->z[j1 * nc + i1];
      double gx = fmax(fabs(z10 - z00), fabs(z11 - z01));
      double gy = fmax(fabs(z01 - z00), fabs(z11 - z10));
      double g = sqrt(gx * gx + gy * gy) / t->cellsize;
      if (g > best) best = g;
    }
  }
  return best;
}

static karst_error_t read_header(grid_reader_t *g, double hv[H_COUNT], int hline[H_COUNT],
                                 int *have_data) {
  karst_ctx_t *ctx = g->ctx;
  char tok[64];
  *have_data = 0;
  while (next_line(g)) {
    const char *s = skip_space(g->line);
    if (*s == '\0') continue; /* blank line */
    if (!isalpha((unsigned char)*s)) {
      *have_data = 1; /* first row of values */
      return KARST_SUCCESS;
    }
    const char *e = token_end(s);
    token_text(s, e, tok, sizeof tok);
    int h = -1;
    for (int k = 0; k < H_COUNT; k++)
      if ((size_t)(e - s) == strlen(header_names[k]) && strncasecmp(s, header_names[k], e - s) == 0)
        h = k;
    int col = (int)(s - g->line) + 1;
    if (h < 0) {
      char lower[64];
      size_t n = strlen(tok);
      for (size_t k = 0; k <= n; k++)
        lower[k] = (char)tolower((unsigned char)tok[k]);
      const char *hint = karst_i_suggest(lower, header_names, H_COUNT);
      return karst_set_error(
          ctx, KARST_EPARSE,
          "%s:%d:%d: unknown ESRI grid header field '%s' (expected ncols, nrows, "
          "xllcorner or xllcenter, yllcorner or yllcenter, cellsize, "
          "NODATA_value)%s%s%s",
          g->name, g->lineno, col, tok, hint ? "; did you mean '" : "", hint ? hint : "",
          hint ? "'?" : "");
    }
    if (hline[h])
      return karst_set_error(ctx, KARST_EPARSE, "%s:%d:%d: %s given twice (first at line %d)",
                             g->name, g->lineno, col, header_names[h], hline[h]);
    int other = h == H_XLLCORNER   ? H_XLLCENTER
                : h == H_XLLCENTER ? H_XLLCORNER
                : h == H_YLLCORNER ? H_YLLCENTER
                : h == H_YLLCENTER ? H_YLLCORNER
                                   : -1;
    if (other >= 0 && hline[other])
      return karst_set_error(ctx, KARST_EPARSE, "%s:%d:%d: %s and %s (line %d) are exclusive",
                             g->name, g->lineno, col, header_names[h], header_names[other],
                             hline[other]);
    const char *vs = skip_space(e), *ve = token_end(vs);
    int vcol = (int)(vs - g->line) + 1;
    if (vs == ve)
      return karst_set_error(ctx, KARST_EPARSE, "%s:%d:%d: %s has no value", g->name, g->lineno,
                             vcol, header_names[h]);
    if (*skip_space(ve) != '\0') {
      const char *xs = skip_space(ve);
      token_text(xs, token_end(xs), tok, sizeof tok);
      return karst_set_error(ctx, KARST_EPARSE, "%s:%d:%d: %s takes one value, got extra '%s'",
                             g->name, g->lineno, (int)(xs - g->line) + 1, header_names[h], tok);
    }
    token_text(vs, ve, tok, sizeof tok);
    if (h == H_NCOLS || h == H_NROWS) {
      int64_t v;
      if (parse_int64(vs, ve, &v) != 0 || v < 1)
        return karst_set_error(ctx, KARST_EPARSE,
                               "%s:%d:%d: %s must be a whole number >= 1, got %s", g->name,
                               g->lineno, vcol, header_names[h], tok);
      if (v > KARST_HEIGHTFIELD_MAX_CELLS) /* also keeps it exact in a double */
        return karst_set_error(
            ctx, KARST_ERANGE, "%s:%d:%d: %s = %s is more than the limit of %lld cells", g->name,
            g->lineno, vcol, header_names[h], tok, (long long)KARST_HEIGHTFIELD_MAX_CELLS);
      hv[h] = (double)v;
    } else {
      double v;
      int rc = parse_double(vs, ve, &v);
      if (rc != 0)
        return karst_set_error(ctx, KARST_EPARSE, "%s:%d:%d: %s must be a %snumber, got %s",
                               g->name, g->lineno, vcol, header_names[h], rc == -2 ? "finite " : "",
                               tok);
      if (h == H_CELLSIZE && !(v > 0))
        return karst_set_error(ctx, KARST_ERANGE, "%s:%d:%d: cellsize must be > 0, got %s", g->name,
                               g->lineno, vcol, tok);
      hv[h] = v;
    }
    hline[h] = g->lineno;
  }
  return KARST_SUCCESS;
}

/**
 * Read an ESRI ASCII grid from an open stream (see karst_terrain_load_grid).
 * Time complexity: O(file size).
 */
karst_error_t karst_i_terrain_read_grid(karst_ctx_t *ctx, FILE *fp, const char *name,
                                        karst_terrain_t *t) {
  karst_error_t err = KARST_SUCCESS;
  grid_reader_t g = {ctx, name, fp, NULL, 0, 0, 0};
  double hv[H_COUNT] = {0};
  int hline[H_COUNT] = {0};
  double *z = NULL;
  char *path_copy = NULL;
  char tok[64];
  int have_data = 0;

  err = read_header(&g, hv, hline, &have_data);
  if (err) goto cleanup;
  if (ferror(fp)) {
    err = karst_set_error(ctx, KARST_EIO, "%s: cannot read: %s", name, strerror(errno));
    goto cleanup;
  }
  if (g.lineno == 0 || (!have_data && !hline[H_NCOLS] && !hline[H_NROWS])) {
    err = karst_set_error(ctx, KARST_EPARSE,
                          "%s:%d:1: empty heightfield: expected an ESRI ASCII grid (ncols, nrows, "
                          "xllcorner, yllcorner, cellsize, then the rows of elevations)",
                          name, g.lineno > 0 ? g.lineno : 1);
    goto cleanup;
  }
  static const struct {
    int a, b;
    const char *what;
  } required[] = {{H_NCOLS, -1, "ncols"},
                  {H_NROWS, -1, "nrows"},
                  {H_XLLCORNER, H_XLLCENTER, "xllcorner or xllcenter"},
                  {H_YLLCORNER, H_YLLCENTER, "yllcorner or yllcenter"},
                  {H_CELLSIZE, -1, "cellsize"}};
  for (size_t k = 0; k < sizeof required / sizeof required[0]; k++) {
    if (!hline[required[k].a] && (required[k].b < 0 || !hline[required[k].b])) {
      err = karst_set_error(ctx, KARST_EPARSE, "%s:%d:1: the ESRI grid header is missing %s%s",
                            name, g.lineno, required[k].what,
                            have_data ? " before the first row of values" : "");
      goto cleanup;
    }
  }
  if (!have_data) {
    err = karst_set_error(ctx, KARST_EPARSE, "%s:%d:1: no rows of elevations after the header",
                          name, g.lineno);
    goto cleanup;
  }
  int64_t ncols = (int64_t)hv[H_NCOLS], nrows = (int64_t)hv[H_NROWS];
  double cs = hv[H_CELLSIZE];
  int has_nodata = hline[H_NODATA] != 0;
  double nodata = hv[H_NODATA];
  /* Each is <= 1e8 (read_header), so the product fits in int64; still,
   * ncols > MAX / nrows (integer division) is ncols * nrows > MAX without forming it. */
  if (ncols > KARST_HEIGHTFIELD_MAX_CELLS / nrows) {
    err = karst_set_error(ctx, KARST_ERANGE,
                          "%s:%d:1: ncols x nrows = %" PRId64 " x %" PRId64 " = %" PRId64
                          " cells, more than the limit of %lld",
                          name, hline[H_NROWS] > hline[H_NCOLS] ? hline[H_NROWS] : hline[H_NCOLS],
                          ncols, nrows, ncols * nrows, (long long)KARST_HEIGHTFIELD_MAX_CELLS);
    goto cleanup;
  }
  /* Rows arrive north to south; they are stored in file order and flipped at
   * the end. The array grows with the values actually read, so a header that
   * promises more than the file holds cannot make us allocate it. */
  int64_t zcap = 0, row = 0;
  do {
    if (g.bytes > KARST_HEIGHTFIELD_MAX_BYTES) {
      err = karst_set_error(ctx, KARST_ERANGE, "%s:%d:1: the heightfield is larger than %lld bytes",
                            name, g.lineno, (long long)KARST_HEIGHTFIELD_MAX_BYTES);
      goto cleanup;
    }
    const char *s = skip_space(g.line);
    if (*s == '\0') continue;
    if (row >= nrows) {
      err = karst_set_error(ctx, KARST_EPARSE, "%s:%d:%d: more rows than nrows = %" PRId64, name,
                            g.lineno, (int)(s - g.line) + 1, nrows);
      goto cleanup;
    }
    int64_t col = 0;
    while (*s) {
      const char *e = token_end(s);
      int c = (int)(s - g.line) + 1;
      token_text(s, e, tok, sizeof tok);
      if (col >= ncols) {
        err = karst_set_error(ctx, KARST_EPARSE,
                              "%s:%d:%d: row %" PRId64 " has more than ncols = %" PRId64
                              " values (extra value %s)",
                              name, g.lineno, c, row + 1, ncols, tok);
        goto cleanup;
      }
      if (row * ncols + col >= zcap) { /* below the cell limit, so no overflow */
        int64_t ncap = zcap ? 2 * zcap : 4096;
        if (ncap > nrows * ncols) ncap = nrows * ncols;
        double *nz = realloc(z, (size_t)ncap * sizeof(double));
        if (!nz) {
          err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory for %" PRId64 " cells", name,
                                ncap);
          goto cleanup;
        }
        z = nz;
        zcap = ncap;
      }
      double v;
      int rc = parse_double(s, e, &v);
      if (rc != 0) {
        err = karst_set_error(ctx, KARST_EPARSE,
                              "%s:%d:%d: row %" PRId64 ", column %" PRId64
                              ": elevation must be a %snumber, got %s",
                              name, g.lineno, c, row + 1, col + 1, rc == -2 ? "finite " : "", tok);
        goto cleanup;
      }
      if (has_nodata && v == nodata) {
        err = karst_set_error(ctx, KARST_EINVAL,
                              "%s:%d:%d: row %" PRId64 ", column %" PRId64
                              " is NODATA (%s): a heightfield must give every cell",
                              name, g.lineno, c, row + 1, col + 1, tok);
        goto cleanup;
      }
      z[row * ncols + col] = v;
      col++;
      s = skip_space(e);
    }
    if (col < ncols) {
      err = karst_set_error(ctx, KARST_EPARSE,
                            "%s:%d:%d: row %" PRId64 " has %" PRId64
                            " values, expected ncols = %" PRId64,
                            name, g.lineno, (int)strlen(g.line) + 1, row + 1, col, ncols);
      goto cleanup;
    }
    row++;
  } while (next_line(&g));
  if (ferror(fp)) {
    err = karst_set_error(ctx, KARST_EIO, "%s: cannot read: %s", name, strerror(errno));
    goto cleanup;
  }
  if (row < nrows) {
    err =
        karst_set_error(ctx, KARST_EPARSE,
                        "%s:%d:1: the file ends after %" PRId64 " rows, expected nrows = %" PRId64,
                        name, g.lineno, row, nrows);
    goto cleanup;
  }
  /* Flip to row 0 = southernmost. */
  for (int64_t a = 0, b = nrows - 1; a < b; a++, b--) {
    for (int64_t i = 0; i < ncols; i++) {
      double tmp = z[a * ncols + i];
      z[a * ncols + i] = z[b * ncols + i];
      z[b * ncols + i] = tmp;
    }
  }
  path_copy = strdup(name);
  if (!path_copy) {
    err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", name);
    goto cleanup;
  }
  free(t->z);
  free(t->path);
  t->is_grid = 1;
  t->path = path_copy;
  path_copy = NULL;
  t->ncols = ncols;
  t->nrows = nrows;
  t->cellsize = cs;
  /* ESRI "corner" is the outer corner of the lower-left cell; store its centre. */
  t->xll = hline[H_XLLCENTER] ? hv[H_XLLCENTER] : hv[H_XLLCORNER] + 0.5 * cs;
  t->yll = hline[H_YLLCENTER] ? hv[H_YLLCENTER] : hv[H_YLLCORNER] + 0.5 * cs;
  t->z = z;
  z = NULL;
  t->zmin = INFINITY;
  t->zmax = -INFINITY;
  for (int64_t k = 0; k < ncols * nrows; k++) {
    if (t->z[k] < t->zmin) t->zmin = t->z[k];
    if (t->z[k] > t->zmax) t->zmax = t->z[k];
  }
  t->lipschitz = grid_lipschitz(t);

cleanup:
  free(z);
  free(path_copy);
  free(g.line);
  return err;
}

/**
 * Read an ESRI ASCII grid heightfield: header lines ncols, nrows,
 * xllcorner|xllcenter, yllcorner|yllcenter, cellsize, optional NODATA_value
 * (names case-insensitive), then nrows rows of ncols elevations, north to
 * south. A NODATA cell is an error (the terrain must be complete). Computes
 * zmin, zmax and the Lipschitz constant of the bilinear surface (used by the
 * implicit terrain, Paris et al. 2021 Appendix A).
 * @param ctx  context; errors read "FILE:LINE:COLUMN: field ..., got VALUE"
 * @param path the .asc file
 * @param t    terrain to fill (is_grid = 1, path, grid, range, lipschitz);
 *             unchanged on failure
 * Limits: a regular file (not a directory, FIFO or device) of at most
 * KARST_HEIGHTFIELD_MAX_BYTES with at most KARST_HEIGHTFIELD_MAX_CELLS cells;
 * the elevation array grows with the values read, never from the header alone.
 * @return KARST_SUCCESS, KARST_EIO (cannot read, not a regular file),
 *         KARST_EPARSE (malformed), KARST_ERANGE (cellsize <= 0, too large),
 *         KARST_EINVAL (NODATA cell) or KARST_ENOMEM.
 * Time complexity: O(file size).
 */
karst_error_t karst_terrain_load_grid(karst_ctx_t *ctx, const char *path, karst_terrain_t *t) {
  FILE *fp = NULL;
  karst_error_t oerr =
      karst_i_open_regular(ctx, path, "heightfield", KARST_HEIGHTFIELD_MAX_BYTES, &fp);
  if (oerr) return oerr;
  karst_error_t err = karst_i_terrain_read_grid(ctx, fp, path, t);
  fclose(fp);
  return err;
}
