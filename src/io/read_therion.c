/* Therion SQL export reader (the `export database -fmt sql` output of
 * Therion's thexpdb.cxx): STATION, SHOT and SHOT_FLAG tables. */
#include "karst/readers.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "survey_internal.h"

/* Coordinates beyond this magnitude (metres) cannot be survey positions and
 * would overflow the centimetre keys: reported as out of range. */
#define MAX_COORD_M 1.0e9
/* Anonymous stations, the far ends of splay shots in Therion ("." and "-"). */
#define IS_SPLAY_NAME(s) (strcmp((s), ".") == 0 || strcmp((s), "-") == 0)

/* ------------------------------------------------------------------------ */
/* A small SQL tokenizer: words, numbers, 'strings' ('' escapes), punctuation. */
/* ------------------------------------------------------------------------ */
typedef enum { TOK_END, TOK_WORD, TOK_STRING, TOK_PUNCT } tok_kind_t;

typedef struct lexer {
  karst_ctx_t *ctx;
  const char *path;
  const char *p, *end;
  long line;
  tok_kind_t kind;
  char *text; /* current token text (strings unquoted) */
  size_t len, cap;
  long tok_line;
} lexer_t;

static karst_error_t lfail(lexer_t *lx, long line, karst_error_t code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
static karst_error_t lfail(lexer_t *lx, long line, karst_error_t code, const char *fmt, ...) {
  char msg[KARST_ERRMSG_MAX / 2];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  return karst_set_error(lx->ctx, code, "%s:%ld: %s", lx->path, line, msg);
}

static karst_error_t push(lexer_t *lx, char c) {
  if (lx->len + 2 > lx->cap) {
    size_t cap = lx->cap ? 2 * lx->cap : 64;
    char *t = realloc(lx->text, cap);
    if (!t) return lfail(lx, lx->line, KARST_ENOMEM, "out of memory");
    lx->text = t;
    lx->cap = cap;
  }
  lx->text[lx->len++] = c;
  lx->text[lx->len] = '\0';
  return KARST_SUCCESS;
}

static int is_word_char(char c) {
  return isalnum((unsigned char)c) || c == '_' || c == '.' || c == '-' || c == '+';
}

static karst_error_t next(lexer_t *lx) {
  karst_error_t err;
  lx->len = 0;
  if (!lx->text && (err = push(lx, '\0'))) return err; /* so that text is never NULL */
  lx->len = 0;
  lx->text[0] = '\0';
  for (;;) { /* blanks and "--" comments */
    while (lx->p < lx->end && isspace((unsigned char)*lx->p))
      if (*lx->p++ == '\n') lx->line++;
    if (lx->end - lx->p >= 2 && lx->p[0] == '-' && lx->p[1] == '-') {
      while (lx->p < lx->end && *lx->p != '\n')
        lx->p++;
      continue;
    }
    break;
  }
  lx->tok_line = lx->line;
  if (lx->p >= lx->end) {
    lx->kind = TOK_END;
    return KARST_SUCCESS;
  }
  char c = *lx->p;
  if (c == '\'') {
    lx->kind = TOK_STRING;
    for (lx->p++;; lx->p++) {
      if (lx->p >= lx->end)
        return lfail(lx, lx->tok_line, KARST_EPARSE, "string opened here is never closed");
      if (*lx->p == '\'') {
        if (lx->p + 1 < lx->end && lx->p[1] == '\'') {
          lx->p++; /* '' is a quote inside the string */
        } else {
          lx->p++;
          return KARST_SUCCESS;
        }
      }
      if (*lx->p == '\n') lx->line++;
      if ((err = push(lx, *lx->p))) return err;
    }
  }
  if (is_word_char(c)) {
    lx->kind = TOK_WORD;
    while (lx->p < lx->end && is_word_char(*lx->p))
      if ((err = push(lx, *lx->p++))) return err;
    return KARST_SUCCESS;
  }
  lx->kind = TOK_PUNCT;
  lx->p++;
  return push(lx, c);
}

static int is_punct(const lexer_t *lx, char c) {
  return lx->kind == TOK_PUNCT && lx->text[0] == c;
}
static int is_word(const lexer_t *lx, const char *w) {
  return lx->kind == TOK_WORD && strcasecmp(lx->text, w) == 0;
}

static const char *tok_desc(const lexer_t *lx) {
  return lx->kind == TOK_END ? "the end of the file" : lx->text;
}

static karst_error_t expect_punct(lexer_t *lx, char c) {
  if (!is_punct(lx, c))
    return lfail(lx, lx->tok_line, KARST_EPARSE, "expected '%c', got '%s'", c, tok_desc(lx));
  return next(lx);
}

/* Skip a statement we do not read, up to and including its ';'. */
static karst_error_t skip_statement(lexer_t *lx) {
  karst_error_t err;
  while (lx->kind != TOK_END && !is_punct(lx, ';'))
    if ((err = next(lx))) return err;
  return lx->kind == TOK_END ? KARST_SUCCESS : next(lx);
}

/* ------------------------------------------------------------------------ */
/* Tables                                                                    */
/* ------------------------------------------------------------------------ */
enum { T_STATION, T_SHOT, T_SHOT_FLAG, T_COUNT };
static const char *const TABLE_NAMES[T_COUNT] = {"STATION", "SHOT", "SHOT_FLAG"};
/* The columns read from each table, and their positions in Therion's own
 * layout, used when the file has no "create table" statement for it. */
#define MAX_COLS 5
static const char *const COLS[T_COUNT][MAX_COLS] = {{"ID", "NAME", "X", "Y", "Z"},
                                                    {"ID", "FROM_ID", "TO_ID", NULL, NULL},
                                                    {"SHOT_ID", "FLAG", NULL, NULL, NULL}};
static const int DEFAULT_POS[T_COUNT][MAX_COLS] = {
    {0, 1, 3, 4, 5}, {0, 1, 2, -1, -1}, {0, 1, -1, -1, -1}};
/* Therion's own column lists (as in the shipped g_huttes.sql), quoted when a row is too short
 * for the layout assumed without a "create table". */
static const char *const THERION_LAYOUT[T_COUNT] = {
    "ID, NAME, SURVEY_ID, X, Y, Z",
    "ID, FROM_ID, TO_ID, CENTRELINE_ID, LENGTH, BEARING, GRADIENT, ... (13 values)",
    "SHOT_ID, FLAG"};

typedef struct station {
  int64_t id;
  char *name;
  double xyz[3];
  long line;
} station_t;

typedef struct shot {
  int64_t id, from, to;
  long line;
} shot_t;

typedef struct tables {
  int pos[T_COUNT][MAX_COLS]; /* column index of each needed column, -1 when absent */
  long create_line[T_COUNT];  /* line of the table's "create table", 0 when none */
  station_t *st;
  size_t n_st, cap_st;
  shot_t *sh;
  size_t n_sh, cap_sh;
  int64_t *flagged; /* SHOT_IDs flagged srf / dpl / spl */
  size_t n_fl, cap_fl;
} tables_t;

static int table_index(const char *name) {
  for (int t = 0; t < T_COUNT; t++)
    if (strcasecmp(name, TABLE_NAMES[t]) == 0) return t;
  return -1;
}

/* create table NAME (col type..., col type...); */
static karst_error_t parse_create(lexer_t *lx, tables_t *tb) {
  karst_error_t err;
  if ((err = next(lx))) return err; /* "create" */
  if (!is_word(lx, "table")) return skip_statement(lx);
  if ((err = next(lx))) return err;
  int t = lx->kind == TOK_WORD ? table_index(lx->text) : -1;
  if (t < 0) return skip_statement(lx);
  long line = lx->tok_line;
  if ((err = next(lx)) || (err = expect_punct(lx, '('))) return err;
  int pos[MAX_COLS];
  for (int c = 0; c < MAX_COLS; c++)
    pos[c] = -1;
  for (int col = 0;; col++) {
    if (lx->kind != TOK_WORD)
      return lfail(lx, lx->tok_line, KARST_EPARSE, "table %s: expected a column name, got '%s'",
                   TABLE_NAMES[t], tok_desc(lx));
    for (int c = 0; c < MAX_COLS; c++)
      if (COLS[t][c] && strcasecmp(lx->text, COLS[t][c]) == 0) pos[c] = col;
    int depth = 0; /* skip the type, e.g. varchar(20) */
    while (lx->kind != TOK_END && !(depth == 0 && (is_punct(lx, ',') || is_punct(lx, ')')))) {
      depth += is_punct(lx, '(') - is_punct(lx, ')');
      if ((err = next(lx))) return err;
    }
    if (lx->kind == TOK_END)
      return lfail(lx, line, KARST_EPARSE, "table %s: the column list is never closed",
                   TABLE_NAMES[t]);
    int last = is_punct(lx, ')');
    if ((err = next(lx))) return err;
    if (last) break;
  }
  for (int c = 0; c < MAX_COLS; c++)
    if (COLS[t][c] && pos[c] < 0)
      return lfail(lx, line, KARST_EPARSE, "table %s has no column %s", TABLE_NAMES[t], COLS[t][c]);
  memcpy(tb->pos[t], pos, sizeof pos);
  tb->create_line[t] = line;
  return skip_statement(lx);
}

typedef struct value {
  int is_null, is_string;
  char *text;
} value_t;

static void free_values(value_t *v, size_t n) {
  for (size_t i = 0; i < n; i++)
    free(v[i].text);
  free(v);
}

static karst_error_t get_int(lexer_t *lx, long line, int t, const value_t *v, const char *col,
                             int64_t *out) {
  char *end;
  if (v->is_null || v->is_string)
    return lfail(lx, line, KARST_EPARSE, "%s %s: expected an integer, got %s%s%s", TABLE_NAMES[t],
                 col, v->is_null ? "NULL" : "'", v->is_null ? "" : v->text, v->is_null ? "" : "'");
  errno = 0;
  long long x = strtoll(v->text, &end, 10);
  if (*end || end == v->text || errno)
    return lfail(lx, line, KARST_EPARSE, "%s %s: expected an integer, got '%s'", TABLE_NAMES[t],
                 col, v->text);
  *out = x;
  return KARST_SUCCESS;
}

static karst_error_t get_coord(lexer_t *lx, long line, const value_t *v, const char *col,
                               double *out) {
  char *end;
  if (v->is_null || v->is_string)
    return lfail(lx, line, KARST_EPARSE, "STATION %s: expected a number, got %s%s%s", col,
                 v->is_null ? "NULL" : "'", v->is_null ? "" : v->text, v->is_null ? "" : "'");
  double x = strtod(v->text, &end);
  if (*end || end == v->text)
    return lfail(lx, line, KARST_EPARSE, "STATION %s: expected a number, got '%s'", col, v->text);
  if (!(fabs(x) <= MAX_COORD_M))
    return lfail(lx, line, KARST_ERANGE, "STATION %s: %s is not a position (|%s| > %g m)", col,
                 v->text, col, MAX_COORD_M);
  *out = x;
  return KARST_SUCCESS;
}

#define GROW(arr, n, cap)                                                                          \
  do {                                                                                             \
    if ((n) == (cap)) {                                                                            \
      size_t c_ = (cap) ? 2 * (cap) : 256;                                                         \
      void *p_ = realloc((arr), c_ * sizeof *(arr));                                               \
      if (!p_) {                                                                                   \
        err = lfail(lx, line, KARST_ENOMEM, "out of memory");                                      \
        goto cleanup;                                                                              \
      }                                                                                            \
      (arr) = p_;                                                                                  \
      (cap) = c_;                                                                                  \
    }                                                                                              \
  } while (0)

/* insert into NAME [(cols)] values (v, v, ...); */
static karst_error_t parse_insert(lexer_t *lx, tables_t *tb) {
  karst_error_t err;
  value_t *vals = NULL;
  size_t nv = 0, capv = 0;
  long line = lx->tok_line;
  if ((err = next(lx))) return err; /* "insert" */
  if (!is_word(lx, "into")) return skip_statement(lx);
  if ((err = next(lx))) return err;
  int t = lx->kind == TOK_WORD ? table_index(lx->text) : -1;
  if (t < 0) return skip_statement(lx);
  if ((err = next(lx))) return err;
  if (!is_word(lx, "values")) {
    err = lfail(lx, lx->tok_line, KARST_EPARSE, "insert into %s: expected 'values', got '%s'",
                TABLE_NAMES[t], tok_desc(lx));
    goto cleanup;
  }
  if ((err = next(lx)) || (err = expect_punct(lx, '('))) goto cleanup;
  for (;;) {
    GROW(vals, nv, capv);
    value_t *v = &vals[nv];
    memset(v, 0, sizeof *v);
    if (lx->kind == TOK_STRING)
      v->is_string = 1;
    else if (lx->kind == TOK_WORD)
      v->is_null = strcasecmp(lx->text, "NULL") == 0;
    else {
      err = lfail(lx, lx->tok_line, KARST_EPARSE, "insert into %s: expected a value, got '%s'",
                  TABLE_NAMES[t], tok_desc(lx));
      goto cleanup;
    }
    if (!(v->text = strdup(lx->text))) {
      err = lfail(lx, line, KARST_ENOMEM, "out of memory");
      goto cleanup;
    }
    nv++;
    if ((err = next(lx))) goto cleanup;
    if (is_punct(lx, ')')) break;
    if ((err = expect_punct(lx, ','))) goto cleanup;
  }
  if ((err = next(lx))) goto cleanup;
  if (!is_punct(lx, ';')) {
    err = lfail(lx, lx->tok_line, KARST_EPARSE, "insert into %s: expected ';', got '%s'",
                TABLE_NAMES[t], tok_desc(lx));
    goto cleanup;
  }
  if ((err = next(lx))) goto cleanup;
  const int *pos = tb->pos[t];
  int last = 0; /* the needed column placed furthest right */
  for (int c = 1; c < MAX_COLS; c++)
    if (pos[c] > pos[last]) last = c;
  if (pos[last] >= (int)nv) {
    if (tb->create_line[t])
      err = lfail(lx, line, KARST_EPARSE,
                  "insert into %s: %zu value%s, expected at least %d: 'create table %s' on line "
                  "%ld puts %s at value %d",
                  TABLE_NAMES[t], nv, nv == 1 ? "" : "s", pos[last] + 1, TABLE_NAMES[t],
                  tb->create_line[t], COLS[t][last], pos[last] + 1);
    else
      err = lfail(lx, line, KARST_EPARSE,
                  "insert into %s: %zu value%s, expected at least %d: with no 'create table %s' "
                  "in the file, Therion's layout is assumed: %s",
                  TABLE_NAMES[t], nv, nv == 1 ? "" : "s", pos[last] + 1, TABLE_NAMES[t],
                  THERION_LAYOUT[t]);
    goto cleanup;
  }
  if (t == T_STATION) {
    GROW(tb->st, tb->n_st, tb->cap_st);
    station_t *s = &tb->st[tb->n_st];
    memset(s, 0, sizeof *s);
    s->line = line;
    if ((err = get_int(lx, line, t, &vals[pos[0]], "ID", &s->id))) goto cleanup;
    for (int i = 0; i < 3; i++)
      if ((err = get_coord(lx, line, &vals[pos[2 + i]], COLS[t][2 + i], &s->xyz[i]))) goto cleanup;
    if (!vals[pos[1]].is_null && !(s->name = strdup(vals[pos[1]].text))) {
      err = lfail(lx, line, KARST_ENOMEM, "out of memory");
      goto cleanup;
    }
    tb->n_st++;
  } else if (t == T_SHOT) {
    GROW(tb->sh, tb->n_sh, tb->cap_sh);
    shot_t *s = &tb->sh[tb->n_sh];
    s->line = line;
    if ((err = get_int(lx, line, t, &vals[pos[0]], "ID", &s->id)) ||
        (err = get_int(lx, line, t, &vals[pos[1]], "FROM_ID", &s->from)) ||
        (err = get_int(lx, line, t, &vals[pos[2]], "TO_ID", &s->to)))
      goto cleanup;
    tb->n_sh++;
  } else {
    /* Leg flags written by Therion: srf surface, dpl duplicate, spl splay
     * (dropped); apx approximate (kept). */
    const char *f = vals[pos[1]].text;
    if (strcmp(f, "srf") == 0 || strcmp(f, "dpl") == 0 || strcmp(f, "spl") == 0) {
      GROW(tb->flagged, tb->n_fl, tb->cap_fl);
      if ((err = get_int(lx, line, t, &vals[pos[0]], "SHOT_ID", &tb->flagged[tb->n_fl])))
        goto cleanup;
      tb->n_fl++;
    }
  }
cleanup:
  free_values(vals, nv);
  return err;
}

static int cmp_i64(const void *a, const void *b) {
  int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
  return (x > y) - (x < y);
}
static int cmp_station(const void *a, const void *b) {
  return cmp_i64(&((const station_t *)a)->id, &((const station_t *)b)->id);
}

static const station_t *find_station(const tables_t *tb, int64_t id) {
  station_t key = {.id = id};
  return bsearch(&key, tb->st, tb->n_st, sizeof *tb->st, cmp_station);
}

static karst_i_cmkey_t cm_key(const double xyz[3]) {
  karst_i_cmkey_t k = {llround(xyz[0] * KARST_I_SURVEY_CM_PER_M),
                       llround(xyz[1] * KARST_I_SURVEY_CM_PER_M),
                       llround(xyz[2] * KARST_I_SURVEY_CM_PER_M)};
  return k;
}

/**
 * karst_read_therion_sql: read a Therion SQL export into a network.
 *
 * Reads the STATION (ID, NAME, X, Y, Z) and SHOT (ID, FROM_ID, TO_ID) rows
 * and SHOT_FLAG; column positions come from the file's "create table"
 * statements (Therion's own layout when absent). Shots flagged 'srf', 'dpl'
 * or 'spl' (surface, duplicate, splay) and shots to anonymous splay stations
 * (named "." or "-") are dropped (METRICS.md: "removed before anything
 * else"); stations are keyed by their centimetre coordinates like the Survex
 * reader (Therion writes them with two decimals), so equated stations are one
 * node; stations no kept shot uses are dropped. Labels are the station names.
 *
 * @param ctx  context for the error message ("FILE:LINE: message")
 * @param path the .sql file
 * @param net  initialised network, replaced on success, left empty on failure
 * @return KARST_SUCCESS; KARST_EIO, KARST_EPARSE (syntax, non-numeric
 *         values, duplicate station ID, a shot naming no station, no STATION
 *         rows), KARST_ERANGE (a coordinate beyond 1e9 m), KARST_ENOMEM.
 *
 * Time complexity: O(file size + S log S) for S stations.
 */
karst_error_t karst_read_therion_sql(karst_ctx_t *ctx, const char *path, karst_network_t *net) {
  karst_error_t err;
  unsigned char *data = NULL;
  size_t len = 0;
  tables_t tb;
  lexer_t lx = {.ctx = ctx, .path = path, .line = 1};
  karst_i_survey_t sv;
  karst_network_t out;
  karst_int_t n_flag = 0, n_splay = 0, n_zero = 0;
  memset(&tb, 0, sizeof tb);
  memcpy(tb.pos, DEFAULT_POS, sizeof tb.pos);
  karst_i_survey_init(&sv);
  karst_network_init(&out);
  if ((err = karst_i_read_file(ctx, path, &data, &len))) goto cleanup;
  if (memchr(data, '\0', len)) {
    err = karst_set_error(ctx, KARST_EPARSE, "%s: binary data (a NUL byte): not an SQL text file",
                          path);
    goto cleanup;
  }
  lx.p = (const char *)data;
  lx.end = lx.p + len;
  if ((err = next(&lx))) goto cleanup;
  while (lx.kind != TOK_END) {
    if (is_word(&lx, "create"))
      err = parse_create(&lx, &tb);
    else if (is_word(&lx, "insert"))
      err = parse_insert(&lx, &tb);
    else
      err = skip_statement(&lx);
    if (err) goto cleanup;
  }
  if (tb.n_st == 0) {
    err = karst_set_error(ctx, KARST_EPARSE,
                          "%s: no STATION rows: not a Therion SQL export (export database -fmt "
                          "sql)",
                          path);
    goto cleanup;
  }
  qsort(tb.st, tb.n_st, sizeof *tb.st, cmp_station);
  for (size_t i = 1; i < tb.n_st; i++)
    if (tb.st[i].id == tb.st[i - 1].id) {
      long a = tb.st[i - 1].line, b = tb.st[i].line;
      err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld: STATION ID %lld already used on line %ld",
                            path, a > b ? a : b, (long long)tb.st[i].id, a > b ? b : a);
      goto cleanup;
    }
  if (tb.n_fl) qsort(tb.flagged, tb.n_fl, sizeof *tb.flagged, cmp_i64);
  for (size_t i = 0; i < tb.n_sh; i++) {
    const shot_t *s = &tb.sh[i];
    const station_t *a = find_station(&tb, s->from), *b = find_station(&tb, s->to);
    if (!a || !b) {
      err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld: SHOT %lld: %s %lld names no STATION", path,
                            s->line, (long long)s->id, a ? "TO_ID" : "FROM_ID",
                            (long long)(a ? s->to : s->from));
      goto cleanup;
    }
    if (tb.n_fl && bsearch(&s->id, tb.flagged, tb.n_fl, sizeof *tb.flagged, cmp_i64)) {
      n_flag++;
      continue;
    }
    if ((a->name && IS_SPLAY_NAME(a->name)) || (b->name && IS_SPLAY_NAME(b->name))) {
      n_splay++;
      continue;
    }
    karst_int_t pa, pb;
    if ((err = karst_i_survey_point(&sv, cm_key(a->xyz), &pa)) ||
        (a->name && (err = karst_i_survey_name(&sv, pa, a->name))) ||
        (err = karst_i_survey_point(&sv, cm_key(b->xyz), &pb)) ||
        (b->name && (err = karst_i_survey_name(&sv, pb, b->name))) ||
        (err = karst_i_survey_leg(&sv, pa, pb))) {
      err = karst_set_error(ctx, err, "%s:%ld: %s", path, s->line, karst_strerror(err));
      goto cleanup;
    }
  }
  if ((err = karst_i_survey_build(ctx, &sv, 0, &out, &n_zero))) goto cleanup;
  karst_log(ctx, KARST_LOG_INFO,
            "%s: %zu stations, %zu shots; dropped %lld flagged srf/dpl/spl, %lld to splay "
            "stations, %lld of zero length; %lld nodes, %lld edges",
            path, tb.n_st, tb.n_sh, (long long)n_flag, (long long)n_splay, (long long)n_zero,
            (long long)out.n_nodes, (long long)out.n_edges);
  karst_network_destroy(net);
  *net = out;
  karst_network_init(&out);
cleanup:
  karst_network_destroy(&out);
  karst_i_survey_destroy(&sv);
  for (size_t i = 0; i < tb.n_st; i++)
    free(tb.st[i].name);
  free(tb.st);
  free(tb.sh);
  free(tb.flagged);
  free(lx.text);
  free(data);
  return err;
}
