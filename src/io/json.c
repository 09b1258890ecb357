/* JSON text output shared by run.json, ensemble.json, `karst metrics --format json` and
 * `karst compare --format json`; and the reader of include/karst/json.h. */
#include "karst/json.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "io/input_internal.h"
#include "karst/io.h"

/* Length of the well-formed UTF-8 sequence at @p p (Unicode 15, table 3-7:
 * no overlong forms, no surrogates, nothing above U+10FFFF), or 0. */
static int utf8_sequence(const unsigned char *p) {
  unsigned c = p[0];
  if (c < 0x80) return 1;
  int n = c >= 0xC2 && c <= 0xDF ? 2 : c >= 0xE0 && c <= 0xEF ? 3 : c >= 0xF0 && c <= 0xF4 ? 4 : 0;
  if (n == 0) return 0;
  unsigned lo = 0x80, hi = 0xBF; /* allowed range of the second byte */
  if (c == 0xE0) lo = 0xA0;
  if (c == 0xED) hi = 0x9F;
  if (c == 0xF0) lo = 0x90;
  if (c == 0xF4) hi = 0x8F;
  if (p[1] < lo || p[1] > hi) return 0;
  for (int i = 2; i < n; i++)
    if (p[i] < 0x80 || p[i] > 0xBF) return 0;
  return n;
}

/**
 * Write @p s as a JSON string literal (RFC 8259 §7): quotes, backslashes and
 * control characters escaped, well-formed UTF-8 as it is; a byte that is not
 * part of well-formed UTF-8 (a path in Latin-1, say) is written as the code
 * point of the same value (\u00XX), so the file stays valid JSON and the
 * reader accepts it; NULL is written as null. O(length).
 */
void karst_json_string(FILE *fp, const char *s) {
  if (!s) {
    fputs("null", fp);
    return;
  }
  fputc('"', fp);
  for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
    if (*p == '"' || *p == '\\')
      fprintf(fp, "\\%c", *p);
    else if (*p == '\n')
      fputs("\\n", fp);
    else if (*p < 0x20)
      fprintf(fp, "\\u%04x", *p);
    else {
      int n = utf8_sequence(p);
      if (n == 0) {
        fprintf(fp, "\\u%04x", *p);
      } else {
        fwrite(p, 1, (size_t)n, fp);
        p += n - 1;
      }
    }
  }
  fputc('"', fp);
}

/* ------------------------------------------------------------------------ */
/* The reader (include/karst/json.h)                                        */
/* ------------------------------------------------------------------------ */
/*
 * A recursive-descent parser of RFC 8259 building a tree. Why it exists: karst
 * report reads ensemble.json back, whose "parameters" hold nested objects and
 * arrays over several lines; reading them line by line lost or truncated them.
 * Newlines can only occur in white space (a raw control character in a string
 * is an error), so the line count is kept while skipping white space.
 */

typedef struct parser {
  karst_ctx_t *ctx;
  const char *src;
  const unsigned char *s;
  size_t len, pos;
  int line;
  size_t line_start;
} parser_t;

/* Growable byte buffer for decoded strings. */
typedef struct sbuf {
  char *s;
  size_t len, cap;
} sbuf_t;

static int sbuf_put(sbuf_t *b, const char *p, size_t n) {
  if (b->len + n + 1 > b->cap) {
    size_t cap = b->cap ? 2 * b->cap : 32;
    while (cap < b->len + n + 1)
      cap *= 2;
    char *ns = realloc(b->s, cap);
    if (!ns) return -1;
    b->s = ns;
    b->cap = cap;
  }
  memcpy(b->s + b->len, p, n);
  b->len += n;
  b->s[b->len] = '\0';
  return 0;
}

static int col_at(const parser_t *p, size_t pos) {
  return (int)(pos - p->line_start) + 1;
}

__attribute__((format(printf, 4, 5))) static karst_error_t fail_at(parser_t *p, int line, int col,
                                                                   const char *fmt, ...) {
  char msg[KARST_ERRMSG_MAX / 2];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  return karst_set_error(p->ctx, KARST_EPARSE, "%s:%d:%d: %s", p->src, line, col, msg);
}

/* "'x'", "byte 0xNN" or "the end of the input", for messages about the byte at p->pos. */
static const char *describe(const parser_t *p, char out[32]) {
  if (p->pos >= p->len) return "the end of the input";
  unsigned char c = p->s[p->pos];
  if (c >= 0x21 && c < 0x7f)
    snprintf(out, 32, "'%c'", c);
  else
    snprintf(out, 32, "byte 0x%02x", c);
  return out;
}

static void skip_ws(parser_t *p) {
  while (p->pos < p->len) {
    unsigned char c = p->s[p->pos];
    if (c == '\n') {
      p->line++;
      p->line_start = p->pos + 1;
    } else if (c != ' ' && c != '\t' && c != '\r') {
      break;
    }
    p->pos++;
  }
}

static karst_error_t oom(parser_t *p) {
  return karst_set_error(p->ctx, KARST_ENOMEM, "%s: out of memory", p->src);
}

static void free_contents(karst_json_t *v) {
  if (!v) return;
  free(v->text);
  for (karst_int_t i = 0; i < v->n; i++) {
    free_contents(&v->items[i]);
    if (v->keys) free(v->keys[i]);
  }
  free(v->items);
  free(v->keys);
  memset(v, 0, sizeof *v);
}

/** Free a tree from karst_json_parse. O(size of the tree). */
void karst_json_free(karst_json_t *v) {
  free_contents(v);
  free(v);
}

static int hexval(unsigned char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

/* Four hex digits at p->pos (after "\u"); -1 when malformed. */
static long hex4(const parser_t *p) {
  if (p->pos + 4 > p->len) return -1;
  long v = 0;
  for (int k = 0; k < 4; k++) {
    int h = hexval(p->s[p->pos + (size_t)k]);
    if (h < 0) return -1;
    v = v * 16 + h;
  }
  return v;
}

static int put_utf8(sbuf_t *b, unsigned long cp) {
  char u[4];
  size_t n;
  if (cp < 0x80) {
    u[0] = (char)cp;
    n = 1;
  } else if (cp < 0x800) {
    u[0] = (char)(0xC0 | (cp >> 6));
    u[1] = (char)(0x80 | (cp & 0x3F));
    n = 2;
  } else if (cp < 0x10000) {
    u[0] = (char)(0xE0 | (cp >> 12));
    u[1] = (char)(0x80 | ((cp >> 6) & 0x3F));
    u[2] = (char)(0x80 | (cp & 0x3F));
    n = 3;
  } else {
    u[0] = (char)(0xF0 | (cp >> 18));
    u[1] = (char)(0x80 | ((cp >> 12) & 0x3F));
    u[2] = (char)(0x80 | ((cp >> 6) & 0x3F));
    u[3] = (char)(0x80 | (cp & 0x3F));
    n = 4;
  }
  return sbuf_put(b, u, n);
}

/* Length of the well-formed UTF-8 sequence at s[0..avail) (RFC 3629: no overlong forms, no
 * surrogates, at most U+10FFFF), or 0. */
static size_t utf8_len(const unsigned char *s, size_t avail) {
  unsigned char c = s[0];
  size_t n;
  unsigned char lo = 0x80, hi = 0xBF;
  if (c >= 0xC2 && c <= 0xDF)
    n = 2;
  else if (c >= 0xE0 && c <= 0xEF) {
    n = 3;
    if (c == 0xE0) lo = 0xA0;
    if (c == 0xED) hi = 0x9F;
  } else if (c >= 0xF0 && c <= 0xF4) {
    n = 4;
    if (c == 0xF0) lo = 0x90;
    if (c == 0xF4) hi = 0x8F;
  } else
    return 0;
  if (avail < n) return 0;
  if (s[1] < lo || s[1] > hi) return 0;
  for (size_t k = 2; k < n; k++)
    if (s[k] < 0x80 || s[k] > 0xBF) return 0;
  return n;
}

/* A string at p->pos (which is '"'); the decoded text goes to *out (malloc'ed). */
static karst_error_t parse_string(parser_t *p, char **out) {
  int line = p->line, col = col_at(p, p->pos);
  sbuf_t b = {NULL, 0, 0};
  karst_error_t err = KARST_SUCCESS;
  *out = NULL;
  p->pos++;
  if (sbuf_put(&b, "", 0)) return oom(p);
  for (;;) {
    if (p->pos >= p->len) {
      err = fail_at(p, line, col,
                    "unterminated string (no closing '\"' before the end of the input)");
      goto cleanup;
    }
    unsigned char c = p->s[p->pos];
    if (c == '"') {
      p->pos++;
      break;
    }
    if (c < 0x20) {
      err = fail_at(p, p->line, col_at(p, p->pos),
                    "control character 0x%02x in a string (write it as \\u%04x%s)", c, c,
                    c == '\n' ? ", or the string is missing its closing '\"'" : "");
      goto cleanup;
    }
    if (c == '\\') {
      size_t at = p->pos;
      if (p->pos + 1 >= p->len) {
        err = fail_at(p, line, col,
                      "unterminated string (no closing '\"' before the end of the input)");
        goto cleanup;
      }
      unsigned char e = p->s[p->pos + 1];
      const char *simple = NULL;
      switch (e) {
      case '"':
        simple = "\"";
        break;
      case '\\':
        simple = "\\";
        break;
      case '/':
        simple = "/";
        break;
      case 'b':
        simple = "\b";
        break;
      case 'f':
        simple = "\f";
        break;
      case 'n':
        simple = "\n";
        break;
      case 'r':
        simple = "\r";
        break;
      case 't':
        simple = "\t";
        break;
      default:
        break;
      }
      if (simple) {
        if (sbuf_put(&b, simple, 1)) goto nomem;
        p->pos += 2;
        continue;
      }
      if (e != 'u') {
        char d[32];
        p->pos++;
        err = fail_at(p, p->line, col_at(p, at),
                      "invalid escape in a string: '\\' followed by %s (valid: \\\" \\\\ \\/ \\b "
                      "\\f \\n \\r \\t \\uXXXX)",
                      describe(p, d));
        goto cleanup;
      }
      p->pos += 2;
      long cp = hex4(p);
      if (cp < 0) {
        err = fail_at(p, p->line, col_at(p, at), "\\u must be followed by four hexadecimal digits");
        goto cleanup;
      }
      p->pos += 4;
      if (cp >= 0xDC00 && cp <= 0xDFFF) {
        err = fail_at(p, p->line, col_at(p, at),
                      "\\u%04lX is a low surrogate without a high surrogate before it", cp);
        goto cleanup;
      }
      if (cp >= 0xD800 && cp <= 0xDBFF) {
        long lo = -1;
        if (p->pos + 1 < p->len && p->s[p->pos] == '\\' && p->s[p->pos + 1] == 'u') {
          p->pos += 2;
          lo = hex4(p);
          p->pos += 4;
        }
        if (lo < 0xDC00 || lo > 0xDFFF) {
          err = fail_at(
              p, p->line, col_at(p, at),
              "\\u%04lX is a high surrogate not followed by a low surrogate \\uDC00-\\uDFFF", cp);
          goto cleanup;
        }
        cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
      }
      if (cp == 0) {
        err = fail_at(p, p->line, col_at(p, at),
                      "\\u0000 (a NUL character) is not supported in strings");
        goto cleanup;
      }
      if (put_utf8(&b, (unsigned long)cp)) goto nomem;
      continue;
    }
    if (c < 0x80) {
      if (sbuf_put(&b, (const char *)&p->s[p->pos], 1)) goto nomem;
      p->pos++;
      continue;
    }
    size_t n = utf8_len(&p->s[p->pos], p->len - p->pos);
    if (n == 0) {
      err = fail_at(p, p->line, col_at(p, p->pos), "invalid UTF-8 (byte 0x%02x) in a string", c);
      goto cleanup;
    }
    if (sbuf_put(&b, (const char *)&p->s[p->pos], n)) goto nomem;
    p->pos += n;
  }
  *out = b.s;
  return KARST_SUCCESS;
nomem:
  err = oom(p);
cleanup:
  free(b.s);
  return err;
}

static int is_digit(unsigned char c) {
  return c >= '0' && c <= '9';
}

/* A number at p->pos: RFC 8259 §6 grammar, -?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)? */
static karst_error_t parse_number(parser_t *p, karst_json_t *v) {
  size_t start = p->pos, i = p->pos;
  int line = p->line, col = col_at(p, start);
  if (i < p->len && p->s[i] == '-') i++;
  if (i >= p->len || !is_digit(p->s[i]))
    return fail_at(p, line, col_at(p, i), "expected a digit after '-'");
  if (p->s[i] == '0') {
    i++;
    if (i < p->len && is_digit(p->s[i]))
      return fail_at(p, line, col, "a number must not have leading zeros");
  } else {
    while (i < p->len && is_digit(p->s[i]))
      i++;
  }
  if (i < p->len && p->s[i] == '.') {
    i++;
    if (i >= p->len || !is_digit(p->s[i]))
      return fail_at(p, line, col_at(p, i), "expected a digit after the decimal point");
    while (i < p->len && is_digit(p->s[i]))
      i++;
  }
  if (i < p->len && (p->s[i] == 'e' || p->s[i] == 'E')) {
    i++;
    if (i < p->len && (p->s[i] == '+' || p->s[i] == '-')) i++;
    if (i >= p->len || !is_digit(p->s[i]))
      return fail_at(p, line, col_at(p, i), "expected a digit in the exponent");
    while (i < p->len && is_digit(p->s[i]))
      i++;
  }
  v->text = malloc(i - start + 1);
  if (!v->text) return oom(p);
  memcpy(v->text, p->s + start, i - start);
  v->text[i - start] = '\0';
  errno = 0;
  v->number = strtod(v->text, NULL);
  if (isinf(v->number))
    return fail_at(p, line, col, "the number %s is beyond the range of a double", v->text);
  v->type = KARST_JSON_NUMBER;
  p->pos = i;
  return KARST_SUCCESS;
}

static karst_error_t parse_value(parser_t *p, karst_json_t *v, int depth);

/* An array or an object at p->pos ('[' or '{'). */
static karst_error_t parse_container(parser_t *p, karst_json_t *v, int depth) {
  int is_obj = p->s[p->pos] == '{';
  int line = p->line, col = col_at(p, p->pos);
  const char *what = is_obj ? "object" : "array";
  char close = is_obj ? '}' : ']';
  karst_int_t cap = 0;
  char d[32];
  if (depth >= KARST_JSON_MAX_DEPTH)
    return fail_at(p, line, col, "arrays and objects nested deeper than %d", KARST_JSON_MAX_DEPTH);
  v->type = is_obj ? KARST_JSON_OBJECT : KARST_JSON_ARRAY;
  p->pos++;
  skip_ws(p);
  if (p->pos < p->len && p->s[p->pos] == close) {
    p->pos++;
    return KARST_SUCCESS;
  }
  for (;;) {
    char *key = NULL;
    skip_ws(p);
    if (is_obj) {
      int kline = p->line, kcol = col_at(p, p->pos);
      if (p->pos >= p->len || p->s[p->pos] != '"')
        return fail_at(p, p->line, col_at(p, p->pos),
                       "expected a member name in double quotes in the object opened at %d:%d, "
                       "got %s",
                       line, col, describe(p, d));
      karst_error_t err = parse_string(p, &key);
      if (err) return err;
      for (karst_int_t k = 0; k < v->n; k++)
        if (strcmp(v->keys[k], key) == 0) {
          err =
              fail_at(p, kline, kcol, "duplicate member name \"%s\" (its first value is at %d:%d)",
                      key, v->items[k].line, v->items[k].col);
          free(key);
          return err;
        }
      skip_ws(p);
      if (p->pos >= p->len || p->s[p->pos] != ':') {
        err = fail_at(p, p->line, col_at(p, p->pos),
                      "expected ':' after the member name \"%s\", got %s", key, describe(p, d));
        free(key);
        return err;
      }
      p->pos++;
    }
    if (v->n == cap) {
      karst_int_t nc = cap ? 2 * cap : 4;
      karst_json_t *ni = realloc(v->items, (size_t)nc * sizeof *ni);
      if (ni) v->items = ni;
      char **nk = is_obj ? realloc(v->keys, (size_t)nc * sizeof *nk) : NULL;
      if (nk) v->keys = nk;
      if (!ni || (is_obj && !nk)) {
        free(key);
        return oom(p);
      }
      cap = nc;
    }
    karst_json_t *child = &v->items[v->n];
    memset(child, 0, sizeof *child);
    karst_error_t err = parse_value(p, child, depth + 1);
    if (err) {
      free_contents(child);
      free(key);
      return err;
    }
    if (is_obj) v->keys[v->n] = key;
    v->n++;
    skip_ws(p);
    if (p->pos < p->len && p->s[p->pos] == ',') {
      p->pos++;
      continue;
    }
    if (p->pos < p->len && p->s[p->pos] == close) {
      p->pos++;
      return KARST_SUCCESS;
    }
    return fail_at(p, p->line, col_at(p, p->pos),
                   "expected ',' or '%c' after %s %" PRId64 " of the %s opened at %d:%d, got %s",
                   close, is_obj ? "member" : "element", v->n, what, line, col, describe(p, d));
  }
}

static karst_error_t parse_value(parser_t *p, karst_json_t *v, int depth) {
  char d[32];
  skip_ws(p);
  v->line = p->line;
  v->col = col_at(p, p->pos);
  if (p->pos >= p->len)
    return fail_at(p, v->line, v->col, "expected a value, got the end of the input");
  unsigned char c = p->s[p->pos];
  if (c == '{' || c == '[') return parse_container(p, v, depth);
  if (c == '"') {
    v->type = KARST_JSON_STRING;
    return parse_string(p, &v->text);
  }
  if (c == '-' || is_digit(c)) return parse_number(p, v);
  static const struct {
    const char *word;
    karst_json_type_t type;
  } lit[] = {{"true", KARST_JSON_TRUE}, {"false", KARST_JSON_FALSE}, {"null", KARST_JSON_NULL}};
  for (int k = 0; k < 3; k++) {
    size_t n = strlen(lit[k].word);
    if (p->len - p->pos >= n && memcmp(p->s + p->pos, lit[k].word, n) == 0) {
      v->type = lit[k].type;
      p->pos += n;
      return KARST_SUCCESS;
    }
  }
  return fail_at(p, v->line, v->col,
                 "expected a value (object, array, string, number, true, false or null), got %s",
                 describe(p, d));
}

/**
 * Parse one JSON value (see json.h).
 * @param ctx    context (error message)
 * @param source name of the input in messages (a file name)
 * @param text   the bytes, not necessarily NUL-terminated
 * @param len    their number
 * @param out    receives the tree, or NULL on failure
 * @return KARST_SUCCESS, KARST_EPARSE ("SOURCE:LINE:COL: ..."), KARST_ENOMEM.
 * Time complexity: O(len), plus O(m²) string comparisons for an object of m members
 * (duplicate check).
 */
karst_error_t karst_json_parse(karst_ctx_t *ctx, const char *source, const char *text, size_t len,
                               karst_json_t **out) {
  parser_t p = {ctx, source ? source : "(json)", (const unsigned char *)text, len, 0, 1, 0};
  char d[32];
  *out = NULL;
  if (len >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0) p.pos = p.line_start = 3;
  karst_json_t *v = calloc(1, sizeof *v);
  if (!v) return oom(&p);
  karst_error_t err = parse_value(&p, v, 0);
  if (!err) {
    skip_ws(&p);
    if (p.pos < p.len)
      err = fail_at(&p, p.line, col_at(&p, p.pos), "unexpected %s after the end of the JSON value",
                    describe(&p, d));
  }
  if (err) {
    karst_json_free(v);
    return err;
  }
  *out = v;
  return KARST_SUCCESS;
}

/** Read the whole of @p path and parse it (karst_json_parse). O(file size). */
karst_error_t karst_json_read_file(karst_ctx_t *ctx, const char *path, karst_json_t **out) {
  *out = NULL;
  unsigned char *data;
  size_t len;
  karst_error_t err = karst_i_read_regular(ctx, path, "JSON", KARST_JSON_MAX_BYTES, &data, &len);
  if (err) return err;
  err = karst_json_parse(ctx, path, (const char *)data, len, out);
  free(data);
  return err;
}

/** Member @p key of @p obj, or NULL. O(members). */
const karst_json_t *karst_json_get(const karst_json_t *obj, const char *key) {
  if (!obj || obj->type != KARST_JSON_OBJECT) return NULL;
  for (karst_int_t i = 0; i < obj->n; i++)
    if (strcmp(obj->keys[i], key) == 0) return &obj->items[i];
  return NULL;
}

/** Non-zero for a value without children. O(1). */
int karst_json_is_scalar(const karst_json_t *v) {
  return v && v->type != KARST_JSON_ARRAY && v->type != KARST_JSON_OBJECT;
}
