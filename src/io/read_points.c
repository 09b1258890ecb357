/* A cloud of sample points (sampling.points, docs/scenario.md): a text file of one point per
 * line, "x y z" in metres, separated by blanks or commas; '#' starts a comment line; blank lines
 * are skipped; a first line "x y z" (any case, same separators) is a header. */
#include <ctype.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "io/input_internal.h"
#include "karst/scenario.h"

/* Exact powers of ten: 10^22 is the largest that a double holds exactly (5^22 < 2^53). */
static const double POW10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                 1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

/* The x87 extended format (a 64-bit significand) is there for the second fast path. */
#if LDBL_MANT_DIG == 64 && (defined(__x86_64__) || defined(__i386__))
#define KARST_X87_DECIMAL 1
#else
#define KARST_X87_DECIMAL 0
#endif

#if KARST_X87_DECIMAL
/* Exact in the x87 extended format: 5^27 < 2^64. */
static const long double POW10L[28] = {1e0L,  1e1L,  1e2L,  1e3L,  1e4L,  1e5L,  1e6L,
                                       1e7L,  1e8L,  1e9L,  1e10L, 1e11L, 1e12L, 1e13L,
                                       1e14L, 1e15L, 1e16L, 1e17L, 1e18L, 1e19L, 1e20L,
                                       1e21L, 1e22L, 1e23L, 1e24L, 1e25L, 1e26L, 1e27L};
#endif

_Static_assert(FLT_EVAL_METHOD == 0, "the fast path needs double arithmetic in double precision");

/* Documented in io/input_internal.h. */
int karst_i_parse_decimal(const char *s, size_t len, double *out) {
  size_t i = 0;
  int neg = 0;
  if (i < len && (s[i] == '+' || s[i] == '-')) neg = s[i++] == '-';
  uint64_t m = 0;
  int sig = 0, digits = 0; /* significant digits kept; all mantissa digits seen */
  long e10 = 0;
  for (; i < len && s[i] >= '0' && s[i] <= '9'; i++, digits++) {
    if (m == 0 && s[i] == '0') continue; /* a leading zero */
    if (++sig > 19) return 0;
    m = 10 * m + (uint64_t)(s[i] - '0');
  }
  if (i < len && s[i] == '.') {
    for (i++; i < len && s[i] >= '0' && s[i] <= '9'; i++, digits++) {
      e10--;
      if (m == 0 && s[i] == '0') continue;
      if (++sig > 19) return 0;
      m = 10 * m + (uint64_t)(s[i] - '0');
    }
  }
  if (digits == 0) return 0;
  if (i < len && (s[i] == 'e' || s[i] == 'E')) {
    i++;
    int eneg = 0;
    if (i < len && (s[i] == '+' || s[i] == '-')) eneg = s[i++] == '-';
    if (i == len || s[i] < '0' || s[i] > '9') return 0;
    long x = 0;
    for (; i < len && s[i] >= '0' && s[i] <= '9'; i++)
      if (x < 100000) x = 10 * x + (s[i] - '0');
    e10 += eneg ? -x : x;
  }
  if (i != len) return 0;
  /* Clinger's fast path: m and 10^|e10| are exact doubles, so one correctly rounded product or
   * quotient is the correctly rounded value (what strtod returns). */
  if (m <= ((uint64_t)1 << 53) && e10 >= -22 && e10 <= 22) {
    double v = (double)m;
    v = e10 >= 0 ? v * POW10[e10] : v / POW10[-e10];
    *out = neg ? -v : v;
    return 1;
  }
#if KARST_X87_DECIMAL
  /* The same in x87 extended precision, for shortest round-trip digits (up to 17 of them) and
   * any 19: m < 2^64 and 10^|e10| (5^27 < 2^64) are exact, so r is v rounded once to 64 bits.
   * Rounding r to 53 bits gives v's correctly rounded double unless r is exactly halfway
   * between two doubles (then v may lie on either side): its 11 low bits are 10000000000.
   * Only normal doubles: below DBL_MIN fewer bits are kept. */
  if (e10 >= -27 && e10 <= 27) {
    long double r = (long double)m;
    r = e10 >= 0 ? r * POW10L[e10] : r / POW10L[-e10];
    uint64_t bits;
    memcpy(&bits, &r, sizeof bits); /* the explicit 64-bit significand */
    if ((bits & 0x7ff) == 0x400 || (m != 0 && !(r >= DBL_MIN && r <= DBL_MAX))) return 0;
    double v = (double)r;
    *out = neg ? -v : v;
    return 1;
  }
#endif
  return 0;
}

/* Longest line (bytes, without its newline): three numbers need far fewer. */
#define POINTS_MAX_LINE 4096

static const char *const AXIS[3] = {"x", "y", "z"};

static int is_sep(char c) {
  return c == ' ' || c == '\t' || c == ',' || c == '\r';
}

static int is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r';
}

/* The fields of a line: their starts and lengths, at most 4 (a fourth is an error). Fields are
 * separated by blanks, or by one comma with blanks around it; "1,,2" has an empty second field
 * and "1,2," an empty third. */
static int split(const char *line, size_t len, const char *f[4], size_t fl[4]) {
  int n = 0;
  size_t i = 0;
  while (i < len && is_blank(line[i]))
    i++;
  if (i >= len) return 0;
  for (;;) {
    size_t s = i;
    while (i < len && !is_sep(line[i]))
      i++;
    f[n] = line + s, fl[n] = i - s, n++;
    while (i < len && is_blank(line[i]))
      i++;
    if (i >= len || n == 4) return n;
    if (line[i] == ',') {
      i++;
      while (i < len && is_blank(line[i]))
        i++;
    }
  }
}

static int is_header(const char *f[4], const size_t fl[4], int n) {
  if (n != 3) return 0;
  for (int a = 0; a < 3; a++)
    if (fl[a] != 1 || tolower((unsigned char)f[a][0]) != AXIS[a][0]) return 0;
  return 1;
}

/* A point's hash: its three coordinates' bits (+0 for -0, which compares equal). */
static uint64_t point_hash(const double p[3]) {
  uint64_t h = 0x9E3779B97F4A7C15ull;
  for (int k = 0; k < 3; k++) {
    double x = p[k] == 0.0 ? 0.0 : p[k];
    uint64_t b;
    memcpy(&b, &x, sizeof b);
    h = (h ^ b) * 0xff51afd7ed558ccdull;
    h ^= h >> 33;
  }
  return h;
}

/* The first point in file order that repeats an earlier one (*rep, or -1), and its first copy
 * (*earlier): an open-addressing table of point indices, O(n). */
static karst_error_t find_repeat(karst_ctx_t *ctx, const char *path, const double *xyz,
                                 karst_int_t n, karst_int_t *rep, karst_int_t *earlier) {
  *rep = -1, *earlier = -1;
  size_t cap = 1024;
  while (cap < 2 * (size_t)n)
    cap *= 2;
  int32_t *slot = malloc(sizeof(int32_t) * cap);
  if (!slot) return karst_set_error(ctx, KARST_ENOMEM, "%s: no memory to check the points", path);
  memset(slot, 0xff, sizeof(int32_t) * cap);
  for (karst_int_t i = 0; i < n && *rep < 0; i++) {
    const double *p = xyz + 3 * i;
    size_t s = (size_t)point_hash(p) & (cap - 1);
    for (; slot[s] >= 0; s = (s + 1) & (cap - 1)) {
      const double *q = xyz + 3 * (karst_int_t)slot[s];
      if (p[0] == q[0] && p[1] == q[1] && p[2] == q[2]) {
        *rep = i, *earlier = slot[s];
        break;
      }
    }
    slot[s] = (int32_t)i;
  }
  free(slot);
  return KARST_SUCCESS;
}

/* Documented in include/karst/scenario.h. */
karst_error_t karst_points_load(karst_ctx_t *ctx, const char *path, double **xyz, karst_int_t *n,
                                long **lines) {
  *xyz = NULL, *n = 0;
  if (lines) *lines = NULL;
  FILE *fp = NULL;
  karst_error_t err = karst_i_open_regular(ctx, path, "point cloud", KARST_POINTS_MAX_BYTES, &fp);
  if (err) return err;
  /* The file is read in chunks (a line is at most POINTS_MAX_LINE bytes), and the points go to
   * arrays reserved for as many points as the file's size allows (a point takes 6 bytes or more,
   * "0 0 0\n"): untouched pages cost nothing, and no array is grown and copied. */
  struct stat st;
  karst_int_t cap = 1;
  if (fstat(fileno(fp), &st) == 0 && st.st_size > 0) cap = (karst_int_t)(st.st_size / 6) + 1;
  if (cap > KARST_POINTS_MAX_POINTS) cap = KARST_POINTS_MAX_POINTS;
  enum { CHUNK = 1 << 16 };
  const size_t bufcap = CHUNK + POINTS_MAX_LINE + 1;
  char *text = malloc(bufcap);
  double *v = malloc(sizeof(double) * 3 * (size_t)cap);
  long *ln = malloc(sizeof(long) * (size_t)cap);
  karst_int_t m = 0;
  long lineno = 0;
  long long total = 0;
  int seen_data = 0, eof = 0;
  if (!text || !v || !ln) goto nomem;
  for (size_t at = 0, have = 0;;) {
    char *buf = text + at;
    size_t avail = have - at;
    const char *eol = memchr(buf, '\n', avail);
    if (!eol && !eof && avail <= POINTS_MAX_LINE) { /* no whole line yet: read more */
      memmove(text, buf, avail);
      at = 0, have = avail;
      size_t got = fread(text + have, 1, bufcap - have, fp);
      if (got == 0) {
        if (ferror(fp)) {
          err = karst_set_error(ctx, KARST_EIO, "%s: read error after line %ld", path, lineno);
          goto fail;
        }
        eof = 1;
      }
      have += got, total += (long long)got;
      if (total > KARST_POINTS_MAX_BYTES) {
        err =
            karst_set_error(ctx, KARST_ERANGE, "%s: the point cloud file grew beyond 1 GiB", path);
        goto fail;
      }
      continue;
    }
    if (avail == 0) break;
    size_t len = eol ? (size_t)(eol - buf) : avail;
    at += len + (eol != NULL);
    lineno++;
    if (len > POINTS_MAX_LINE) {
      err = karst_set_error(ctx, KARST_EPARSE,
                            "%s:%ld: line longer than %d bytes; a line holds x y z only", path,
                            lineno, POINTS_MAX_LINE);
      goto fail;
    }
    if (memchr(buf, '\0', len)) {
      err = karst_set_error(ctx, KARST_EPARSE,
                            "%s:%ld: a NUL byte; the points file must be text (x y z per line)",
                            path, lineno);
      goto fail;
    }
    size_t s = 0;
    while (s < len && (buf[s] == ' ' || buf[s] == '\t' || buf[s] == '\r'))
      s++;
    if (s == len || buf[s] == '#') continue;
    const char *f[4];
    size_t fl[4];
    int nf = split(buf, len, f, fl);
    if (!seen_data && is_header(f, fl, nf)) {
      seen_data = 1;
      continue;
    }
    seen_data = 1;
    if (nf > 3) {
      err = karst_set_error(ctx, KARST_EPARSE,
                            "%s:%ld:%ld: a fourth field '%.*s'; a line holds x y z only", path,
                            lineno, (long)(f[3] - buf) + 1, (int)(fl[3] > 40 ? 40 : fl[3]), f[3]);
      goto fail;
    }
    if (nf < 3) {
      err = karst_set_error(ctx, KARST_EPARSE,
                            "%s:%ld: field %s missing; a line holds x y z (%d field%s found)", path,
                            lineno, AXIS[nf], nf, nf == 1 ? "" : "s");
      goto fail;
    }
    if (m == cap) { /* only at KARST_POINTS_MAX_POINTS (or a file grown since its size was read) */
      err = karst_set_error(ctx, KARST_ERANGE,
                            "%s:%ld: more than %lld points; sampling.points takes at most %d", path,
                            lineno, (long long)cap, KARST_POINTS_MAX_POINTS);
      goto fail;
    }
    for (int a = 0; a < 3; a++) {
      char tok[POINTS_MAX_LINE + 1]; /* a field is no longer than its line */
      long col = (long)(f[a] - buf) + 1;
      if (fl[a] == 0 || fl[a] >= sizeof tok) {
        err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld:%ld: field %s: '%.*s' is not a number",
                              path, lineno, col, AXIS[a], (int)(fl[a] > 40 ? 40 : fl[a]), f[a]);
        goto fail;
      }
      double x;
      if (karst_i_parse_decimal(f[a], fl[a], &x)) {
        v[3 * m + a] = x; /* finite: at most 19 digits times 10^27 */
        continue;
      }
      memcpy(tok, f[a], fl[a]);
      tok[fl[a]] = '\0';
      char *end;
      x = strtod(tok, &end);
      if (end == tok || *end != '\0') {
        err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld:%ld: field %s: '%s' is not a number", path,
                              lineno, col, AXIS[a], tok);
        goto fail;
      }
      if (!isfinite(x)) {
        err = karst_set_error(ctx, KARST_EPARSE,
                              "%s:%ld:%ld: field %s: '%s' is not a finite number of metres", path,
                              lineno, col, AXIS[a], tok);
        goto fail;
      }
      v[3 * m + a] = x;
    }
    ln[m++] = lineno;
  }
  if (m == 0) {
    err = karst_set_error(ctx, KARST_EPARSE, "%s: no points (a line per point: x y z)", path);
    goto fail;
  }
  karst_int_t rep, earlier;
  if ((err = find_repeat(ctx, path, v, m, &rep, &earlier))) goto fail;
  if (rep >= 0) {
    err = karst_set_error(ctx, KARST_EPARSE,
                          "%s:%ld: the point (%.17g, %.17g, %.17g) repeats line %ld; each sample "
                          "must be a distinct point",
                          path, ln[rep], v[3 * rep], v[3 * rep + 1], v[3 * rep + 2], ln[earlier]);
    goto fail;
  }
  free(text);
  fclose(fp);
  double *vs = realloc(v, sizeof(double) * 3 * (size_t)m); /* give back the reserve */
  if (vs) v = vs;
  long *ls = realloc(ln, sizeof(long) * (size_t)m);
  if (ls) ln = ls;
  *xyz = v, *n = m;
  if (lines)
    *lines = ln;
  else
    free(ln);
  return KARST_SUCCESS;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "%s: no memory for %lld points", path, (long long)m);
fail:
  free(text);
  fclose(fp);
  free(v);
  free(ln);
  return err;
}
