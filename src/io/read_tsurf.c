/* GOCAD TSurf (.ts) ASCII objects, the triangulated surfaces geomodelling
 * packages export. Reference: GOCAD ASCII file formats (Earth Decision /
 * Paradigm development kit), "TSurf", read for the grammar:
 *
 *   GOCAD TSurf 1                       one object; a file may hold several
 *   HEADER { name:... }  or  HDR name:...
 *   GOCAD_ORIGINAL_COORDINATE_SYSTEM    NAME, AXIS_NAME, AXIS_UNIT, ZPOSITIVE
 *   ...  END_ORIGINAL_COORDINATE_SYSTEM   (ZPOSITIVE Depth: z is negated)
 *   PROPERTIES p1 p2 / ESIZES / NO_DATA_VALUES / PROPERTY_CLASS_HEADER p { }
 *   TFACE                               a part; several per object
 *   VRTX id x y z [flags] / PVRTX id x y z values... [flags]
 *   ATOM id vertex_id / PATOM id vertex_id ...   the same point under a new id
 *   TRGL id1 id2 id3
 *   BSTONE id / BORDER id id1 id2       border information (checked, not used)
 *   END
 *
 * Liberal in what real exports contain: unknown keywords and the metadata of
 * other packages are skipped (the first unknown keyword is logged), braces may
 * follow a keyword with or without a space, ids need not be sequential, ATOMs
 * may repeat ATOMs, triangles may come before TFACE, lines end in LF or CRLF.
 * Strict in geometry: every number finite, every id defined once per object,
 * every TRGL, ATOM, BSTONE and BORDER naming a defined id, each object closed by
 * END (a missing END is a truncated file). Ids are resolved per object by
 * sorting, so the check costs O(n log n) and no hashing. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "geology/surface_internal.h"
#include "scenario/scenario_internal.h"

/* Characters of a token quoted in a message. */
#define TOKEN_QUOTE_MAX 40

typedef struct {
  karst_int_t id;
  karst_int_t val; /* vertex index, or -1 - atom index */
  long line;
} idrec_t;

typedef struct {
  karst_int_t id, target;
  long line;
  int patom;
} atom_t;

typedef struct {
  karst_int_t id;
  long line;
  int kind; /* 0 BSTONE, 1 BORDER */
} ref_t;

typedef struct reader {
  karst_ctx_t *ctx;
  const char *path;
  karst_i_tsurf_t *ts;
  long lineno;
  char **tok;
  int ntok, tokcap;
  /* growth capacities of ts arrays */
  karst_int_t vcap, tcap;
  karst_int_t *traw; /* 3 per triangle: ids until resolved */
  /* the current object */
  int in_object;
  long object_line;
  karst_int_t obj_v0, obj_t0; /* first vertex and triangle of the object */
  long first_vertex_line;
  double unit[3];
  int zdepth;
  long crs_line, block_line;
  int in_crs, in_block;
  int props_ok; /* the object's property layout matches the file's */
  int nprops;   /* of the current object */
  char **pnames;
  int *pesize;
  double *pnodata;
  int pstride;
  int part_open;
  atom_t *atoms;
  karst_int_t natoms, acap;
  ref_t *refs;
  karst_int_t nrefs, rcap;
  int after_end;
  int warned;
} reader_t;

static void quote(const char *s, char *out) {
  size_t k = 0;
  for (; s[k] && k < TOKEN_QUOTE_MAX; k++) {
    unsigned char c = (unsigned char)s[k];
    out[k] = (c < 32 || c >= 127) ? '?' : (char)c;
  }
  if (s[k]) memcpy(out + k, "...", 3), k += 3;
  out[k] = '\0';
}

#define FAIL(code, ...)                                                                            \
  do {                                                                                             \
    char msg_[KARST_ERRMSG_MAX];                                                                   \
    snprintf(msg_, sizeof msg_, __VA_ARGS__);                                                      \
    return karst_set_error(r->ctx, code, "%s:%ld: %s", r->path, r->lineno, msg_);                  \
  } while (0)

static karst_error_t nomem(reader_t *r) {
  return karst_set_error(r->ctx, KARST_ENOMEM, "%s:%ld: out of memory", r->path, r->lineno);
}

/* Split the line into tokens on blanks (the line is modified). */
static int tokenize(reader_t *r, char *line) {
  r->ntok = 0;
  for (char *p = line; *p;) {
    while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n' || *p == '\f' || *p == '\v')
      *p++ = '\0';
    if (!*p) break;
    if (r->ntok == r->tokcap) {
      int nc = r->tokcap ? 2 * r->tokcap : 32;
      char **nt = realloc(r->tok, (size_t)nc * sizeof *nt);
      if (!nt) return -1;
      r->tok = nt;
      r->tokcap = nc;
    }
    r->tok[r->ntok++] = p;
    while (*p && *p != ' ' && *p != '\t' && *p != '\r' && *p != '\n' && *p != '\f' && *p != '\v')
      p++;
  }
  return 0;
}

static int parse_id(const char *s, karst_int_t *out) {
  if (!*s || *s == '-' || *s == '+') return -1;
  for (const char *p = s; *p; p++)
    if (*p < '0' || *p > '9') return -1;
  errno = 0;
  char *end;
  long long v = strtoll(s, &end, 10);
  if (errno == ERANGE || *end) return -2;
  *out = (karst_int_t)v;
  return 0;
}

/* 0: a finite number; -1: not a number; -2: not finite. */
static int parse_number(const char *s, double *out) {
  char *end;
  errno = 0;
  double v = strtod(s, &end);
  if (end == s || *end) return -1;
  if (!isfinite(v)) return -2;
  *out = v;
  return 0;
}

static karst_error_t get_id(reader_t *r, int k, const char *what, karst_int_t *id) {
  char q[TOKEN_QUOTE_MAX + 4];
  if (k >= r->ntok) FAIL(KARST_EPARSE, "%s: missing %s", r->tok[0], what);
  int rc = parse_id(r->tok[k], id);
  quote(r->tok[k], q);
  if (rc == -2) FAIL(KARST_ERANGE, "%s: %s '%s' is out of range", r->tok[0], what, q);
  if (rc) FAIL(KARST_EPARSE, "%s: %s must be a whole number >= 0, got '%s'", r->tok[0], what, q);
  return KARST_SUCCESS;
}

/* Strip the quotes of "m" and compare unit names. */
static int unit_factor(const char *u, double *f) {
  char buf[32];
  size_t n = strlen(u);
  if (n >= 2 && u[0] == '"' && u[n - 1] == '"') u++, n -= 2;
  if (n == 0 || n >= sizeof buf) return -1;
  memcpy(buf, u, n);
  buf[n] = '\0';
  static const struct {
    const char *name;
    double f;
  } units[] = {{"m", 1.0},       {"meter", 1.0},           {"meters", 1.0}, {"metre", 1.0},
               {"metres", 1.0},  {"km", 1000.0},           {"ft", 0.3048},  {"feet", 0.3048},
               {"foot", 0.3048}, {"usft", 1200.0 / 3937.0}};
  for (size_t k = 0; k < sizeof units / sizeof units[0]; k++)
    if (strcasecmp(buf, units[k].name) == 0) {
      *f = units[k].f;
      return 0;
    }
  return -1;
}

static void object_reset(reader_t *r) {
  for (int k = 0; k < r->nprops; k++)
    free(r->pnames[k]);
  free(r->pnames);
  free(r->pesize);
  free(r->pnodata);
  r->pnames = NULL;
  r->pesize = NULL;
  r->pnodata = NULL;
  r->nprops = 0;
  r->pstride = 0;
  r->natoms = 0;
  r->nrefs = 0;
  r->unit[0] = r->unit[1] = r->unit[2] = 1.0;
  r->zdepth = 0;
  r->first_vertex_line = 0;
  r->part_open = 0;
  r->in_crs = r->in_block = 0;
}

/* @p p grown to hold @p need elements of @p size bytes (doubling), or NULL. */
static void *grow(void *p, karst_int_t *cap, karst_int_t need, size_t size) {
  if (need <= *cap) return p;
  karst_int_t nc = *cap ? 2 * *cap : 1024;
  void *np = realloc(p, (size_t)nc * size);
  if (np) *cap = nc;
  return np;
}

/* Double *cap (from 1024) and every array p[k] of elem[k]-byte elements with it
 * (elem 0: not kept); p[k] holds each array as it stands, so nothing leaks
 * when a later realloc fails. 0, or -1 when out of memory. */
static int grow_together(karst_int_t *cap, int n, void *p[], const size_t elem[]) {
  karst_int_t nc = *cap ? 2 * *cap : 1024;
  for (int k = 0; k < n; k++) {
    if (elem[k] == 0) continue;
    void *q = realloc(p[k], (size_t)nc * elem[k]);
    if (!q) return -1;
    p[k] = q;
  }
  *cap = nc;
  return 0;
}

static karst_error_t ensure_part(reader_t *r) {
  if (!r->part_open) { /* triangles before any TFACE: an implicit first part */
    r->part_open = 1;
    r->ts->nparts++;
  }
  return KARST_SUCCESS;
}

static karst_error_t add_vertex(reader_t *r, int with_props) {
  karst_i_tsurf_t *ts = r->ts;
  karst_error_t err;
  char q[TOKEN_QUOTE_MAX + 4];
  karst_int_t id;
  if (r->ntok < 5)
    FAIL(KARST_EPARSE, "%s needs an id and x y z, got %d value%s", r->tok[0], r->ntok - 1,
         r->ntok == 2 ? "" : "s");
  if ((err = get_id(r, 1, "the vertex id", &id))) return err;
  if (ts->nv >= KARST_SURFACE_MAX_VERTICES)
    FAIL(KARST_ERANGE, "more than %lld vertices", (long long)KARST_SURFACE_MAX_VERTICES);
  double x[3];
  for (int c = 0; c < 3; c++) {
    int rc = parse_number(r->tok[2 + c], &x[c]);
    quote(r->tok[2 + c], q);
    if (rc)
      FAIL(KARST_EINVAL, "%s %lld: %c must be a %snumber, got '%s'", r->tok[0], (long long)id,
           "xyz"[c], rc == -2 ? "finite " : "", q);
    x[c] *= r->unit[c];
  }
  if (r->zdepth) x[2] = -x[2];
  int nvals = with_props ? r->pstride : 0;
  if (with_props && r->ntok - 5 < nvals)
    FAIL(KARST_EPARSE, "PVRTX %lld has %d property value%s, the PROPERTIES line declares %d",
         (long long)id, r->ntok - 5, r->ntok - 5 == 1 ? "" : "s", nvals);
  if (ts->nv == r->vcap) {
    void *p[4] = {ts->xyz, ts->vid, ts->vline, ts->props};
    const size_t elem[4] = {3 * sizeof(double), sizeof(karst_int_t), sizeof(long),
                            (size_t)ts->prop_stride * sizeof(double)};
    int bad = grow_together(&r->vcap, 4, p, elem);
    ts->xyz = p[0], ts->vid = p[1], ts->vline = p[2], ts->props = p[3];
    if (bad) return nomem(r);
  }
  if (ts->prop_stride > 0) {
    double *pv = ts->props + ts->nv * ts->prop_stride;
    for (int k = 0; k < ts->prop_stride; k++)
      pv[k] = NAN;
    if (with_props && r->props_ok) {
      int c = 0;
      for (int p = 0; p < r->nprops; p++)
        for (int e = 0; e < r->pesize[p]; e++, c++) {
          double v = NAN; /* a property (not geometry) may be nan or inf: no value */
          int rc = parse_number(r->tok[5 + c], &v);
          quote(r->tok[5 + c], q);
          if (rc == -1)
            FAIL(KARST_EPARSE, "PVRTX %lld: property %s must be a number, got '%s'", (long long)id,
                 r->pnames[p], q);
          pv[c] = rc || v == r->pnodata[p] ? NAN : v;
        }
    }
  }
  memcpy(ts->xyz + 3 * ts->nv, x, sizeof x);
  ts->vid[ts->nv] = id;
  ts->vline[ts->nv] = r->lineno;
  if (!r->first_vertex_line) r->first_vertex_line = r->lineno;
  ts->nv++;
  return KARST_SUCCESS;
}

static karst_error_t add_atom(reader_t *r, int patom) {
  karst_error_t err;
  karst_int_t id, target;
  if (r->ntok < 3)
    FAIL(KARST_EPARSE, "%s needs an id and the id of the vertex it repeats", r->tok[0]);
  if ((err = get_id(r, 1, "the atom id", &id)) || (err = get_id(r, 2, "the vertex id", &target)))
    return err;
  atom_t *na = grow(r->atoms, &r->acap, r->natoms + 1, sizeof *na);
  if (!na) return nomem(r);
  r->atoms = na;
  r->atoms[r->natoms++] = (atom_t){id, target, r->lineno, patom};
  if (!r->first_vertex_line) r->first_vertex_line = r->lineno;
  r->ts->natoms++;
  return KARST_SUCCESS;
}

static karst_error_t add_triangle(reader_t *r) {
  karst_i_tsurf_t *ts = r->ts;
  karst_error_t err;
  karst_int_t id[3];
  if (r->ntok < 4) FAIL(KARST_EPARSE, "TRGL needs three vertex ids, got %d", r->ntok - 1);
  for (int k = 0; k < 3; k++)
    if ((err = get_id(r, 1 + k, "a vertex id", &id[k]))) return err;
  if (ts->nt >= KARST_SURFACE_MAX_TRIANGLES)
    FAIL(KARST_ERANGE, "more than %lld triangles", (long long)KARST_SURFACE_MAX_TRIANGLES);
  ensure_part(r);
  if (ts->nt == r->tcap) {
    void *p[3] = {r->traw, ts->tline, ts->tpart};
    const size_t elem[3] = {3 * sizeof(karst_int_t), sizeof(long), sizeof(int)};
    int bad = grow_together(&r->tcap, 3, p, elem);
    r->traw = p[0], ts->tline = p[1], ts->tpart = p[2];
    if (bad) return nomem(r);
  }
  memcpy(r->traw + 3 * ts->nt, id, sizeof id);
  ts->tline[ts->nt] = r->lineno;
  ts->tpart[ts->nt] = ts->nparts - 1;
  ts->nt++;
  return KARST_SUCCESS;
}

static karst_error_t add_ref(reader_t *r, int kind) {
  karst_error_t err;
  karst_int_t id;
  int first = kind == 0 ? 1 : 2, last = kind == 0 ? 1 : 3;
  if (r->ntok <= last)
    FAIL(KARST_EPARSE, "%s needs %s", r->tok[0],
         kind == 0 ? "a vertex id" : "a border id and two vertex ids");
  if (kind == 1 && (err = get_id(r, 1, "the border id", &id))) return err;
  for (int k = first; k <= last; k++) {
    if ((err = get_id(r, k, "a vertex id", &id))) return err;
    ref_t *nr = grow(r->refs, &r->rcap, r->nrefs + 1, sizeof *nr);
    if (!nr) return nomem(r);
    r->refs = nr;
    r->refs[r->nrefs++] = (ref_t){id, r->lineno, kind};
  }
  if (kind == 0)
    r->ts->nbstones++;
  else
    r->ts->nborders++;
  return KARST_SUCCESS;
}

static int cmp_idrec(const void *pa, const void *pb) {
  const idrec_t *a = pa, *b = pb;
  if (a->id != b->id) return a->id < b->id ? -1 : 1;
  return a->line < b->line ? -1 : (a->line > b->line);
}

static const idrec_t *find_id(const idrec_t *recs, karst_int_t n, karst_int_t id) {
  karst_int_t lo = 0, hi = n;
  while (lo < hi) {
    karst_int_t mid = lo + (hi - lo) / 2;
    if (recs[mid].id < id)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < n && recs[lo].id == id ? recs + lo : NULL;
}

/* At the END of an object: ids defined once, ATOMs, TRGLs, BSTONEs and
 * BORDERs resolved to vertex indices. */
static karst_error_t resolve_object(reader_t *r) {
  karst_i_tsurf_t *ts = r->ts;
  karst_error_t err = KARST_SUCCESS;
  karst_int_t nvo = ts->nv - r->obj_v0, n = nvo + r->natoms;
  idrec_t *recs = malloc((size_t)(n > 0 ? n : 1) * sizeof *recs);
  if (!recs) return nomem(r);
  for (karst_int_t v = 0; v < nvo; v++)
    recs[v] = (idrec_t){ts->vid[r->obj_v0 + v], r->obj_v0 + v, ts->vline[r->obj_v0 + v]};
  for (karst_int_t a = 0; a < r->natoms; a++)
    recs[nvo + a] = (idrec_t){r->atoms[a].id, -1 - a, r->atoms[a].line};
  qsort(recs, (size_t)n, sizeof *recs, cmp_idrec);
  long dup_line = 0, dup_first = 0;
  karst_int_t dup_id = 0;
  for (karst_int_t k = 1; k < n; k++)
    if (recs[k].id == recs[k - 1].id && (!dup_line || recs[k].line < dup_line)) {
      dup_line = recs[k].line, dup_first = recs[k - 1].line, dup_id = recs[k].id;
    }
  if (dup_line) {
    err = karst_set_error(r->ctx, KARST_EPARSE,
                          "%s:%ld: vertex id %lld is already used at line %ld: ids must be "
                          "unique within an object",
                          r->path, dup_line, (long long)dup_id, dup_first);
    goto cleanup;
  }
  /* ATOMs: follow to the vertex they repeat (an ATOM may repeat an ATOM). */
  for (karst_int_t k = 0; k < n; k++) {
    karst_int_t val = recs[k].val, steps = 0;
    while (val < 0) {
      const atom_t *a = r->atoms + (-1 - val);
      const idrec_t *t = find_id(recs, n, a->target);
      if (!t || ++steps > r->natoms) {
        err = karst_set_error(r->ctx, KARST_EPARSE, "%s:%ld: %s %lld repeats vertex %lld, which %s",
                              r->path, a->line, a->patom ? "PATOM" : "ATOM", (long long)a->id,
                              (long long)a->target,
                              t ? "leads round a cycle of ATOMs"
                                : "no VRTX, PVRTX, ATOM or PATOM of this object defines");
        goto cleanup;
      }
      val = t->val;
    }
    recs[k].val = val;
  }
  for (karst_int_t t = r->obj_t0; t < ts->nt; t++) {
    karst_int_t *tv = r->traw + 3 * t, idx[3];
    for (int c = 0; c < 3; c++) {
      const idrec_t *d = find_id(recs, n, tv[c]);
      if (!d) {
        err = karst_set_error(r->ctx, KARST_EPARSE,
                              "%s:%ld: TRGL %lld %lld %lld: vertex %lld is not defined by a "
                              "VRTX, PVRTX, ATOM or PATOM of this object",
                              r->path, ts->tline[t], (long long)tv[0], (long long)tv[1],
                              (long long)tv[2], (long long)tv[c]);
        goto cleanup;
      }
      idx[c] = d->val;
    }
    memcpy(tv, idx, sizeof idx); /* ids become vertex indices */
  }
  for (karst_int_t k = 0; k < r->nrefs; k++)
    if (!find_id(recs, n, r->refs[k].id)) {
      err = karst_set_error(r->ctx, KARST_EPARSE,
                            "%s:%ld: %s names vertex %lld, which no VRTX, PVRTX, ATOM or PATOM "
                            "of this object defines",
                            r->path, r->refs[k].line, r->refs[k].kind ? "BORDER" : "BSTONE",
                            (long long)r->refs[k].id);
      goto cleanup;
    }
cleanup:
  free(recs);
  return err;
}

/* PROPERTIES / ESIZES / NO_DATA_VALUES of the current object. */
static karst_error_t read_properties(reader_t *r) {
  const char *kw = r->tok[0];
  char q[TOKEN_QUOTE_MAX + 4];
  if (r->first_vertex_line)
    FAIL(KARST_EPARSE, "%s must come before the vertices (the first is at line %ld)", kw,
         r->first_vertex_line);
  if (strcmp(kw, "PROPERTIES") == 0) {
    int np = r->ntok - 1;
    for (int k = 0; k < r->nprops; k++)
      free(r->pnames[k]);
    free(r->pnames);
    free(r->pesize);
    free(r->pnodata);
    r->nprops = 0;
    r->pnames = calloc((size_t)(np > 0 ? np : 1), sizeof *r->pnames);
    r->pesize = malloc((size_t)(np > 0 ? np : 1) * sizeof *r->pesize);
    r->pnodata = malloc((size_t)(np > 0 ? np : 1) * sizeof *r->pnodata);
    if (!r->pnames || !r->pesize || !r->pnodata) return nomem(r);
    for (int k = 0; k < np; k++) {
      if (!(r->pnames[k] = strdup(r->tok[1 + k]))) return nomem(r);
      r->nprops = k + 1;
      r->pesize[k] = 1;
      r->pnodata[k] = NAN;
    }
  } else if (strcmp(kw, "ESIZES") == 0) {
    if (r->ntok - 1 != r->nprops)
      FAIL(KARST_EPARSE, "ESIZES gives %d size%s for %d PROPERTIES", r->ntok - 1,
           r->ntok == 2 ? "" : "s", r->nprops);
    for (int k = 0; k < r->nprops; k++) {
      karst_int_t e;
      quote(r->tok[1 + k], q);
      if (parse_id(r->tok[1 + k], &e) || e < 1 || e > 1024)
        FAIL(KARST_EPARSE, "ESIZES: the size of %s must be a whole number in [1, 1024], got '%s'",
             r->pnames[k], q);
      r->pesize[k] = (int)e;
    }
  } else { /* NO_DATA_VALUES */
    if (r->ntok - 1 != r->nprops)
      FAIL(KARST_EPARSE, "NO_DATA_VALUES gives %d value%s for %d PROPERTIES", r->ntok - 1,
           r->ntok == 2 ? "" : "s", r->nprops);
    for (int k = 0; k < r->nprops; k++) /* not a number (**none**): no no-data value */
      if (parse_number(r->tok[1 + k], &r->pnodata[k])) r->pnodata[k] = NAN;
  }
  r->pstride = 0;
  for (int k = 0; k < r->nprops; k++)
    r->pstride += r->pesize[k];
  return KARST_SUCCESS;
}

/* The file's property layout is the first object's (fixed before its first
 * vertex); a later object with another layout keeps its geometry but its
 * values are not stored. */
static karst_error_t settle_properties(reader_t *r) {
  karst_i_tsurf_t *ts = r->ts;
  if (ts->nobjects == 1) {
    for (int k = 0; k < ts->nprops; k++)
      free(ts->prop_names[k]);
    free(ts->prop_names);
    free(ts->prop_esize);
    ts->prop_names = NULL;
    ts->prop_esize = NULL;
    ts->nprops = 0;
    ts->prop_stride = 0;
    if (r->nprops > 0) {
      ts->prop_names = calloc((size_t)r->nprops, sizeof *ts->prop_names);
      ts->prop_esize = malloc((size_t)r->nprops * sizeof *ts->prop_esize);
      if (!ts->prop_names || !ts->prop_esize) return nomem(r);
      for (int k = 0; k < r->nprops; k++) {
        if (!(ts->prop_names[k] = strdup(r->pnames[k]))) return nomem(r);
        ts->prop_esize[k] = r->pesize[k];
        ts->nprops = k + 1;
      }
      ts->prop_stride = r->pstride;
    }
  }
  r->props_ok = ts->nprops == r->nprops;
  for (int k = 0; r->props_ok && k < r->nprops; k++)
    r->props_ok = strcmp(ts->prop_names[k], r->pnames[k]) == 0 && ts->prop_esize[k] == r->pesize[k];
  return KARST_SUCCESS;
}

/* Lines of the GOCAD_ORIGINAL_COORDINATE_SYSTEM block (and ZPOSITIVE anywhere
 * before the vertices). */
static karst_error_t read_crs_line(reader_t *r) {
  const char *kw = r->tok[0];
  char q[TOKEN_QUOTE_MAX + 4];
  if (strcmp(kw, "ZPOSITIVE") == 0 || strcmp(kw, "AXIS_UNIT") == 0) {
    if (r->first_vertex_line)
      FAIL(KARST_EPARSE, "%s must come before the vertices (the first is at line %ld)", kw,
           r->first_vertex_line);
  }
  if (strcmp(kw, "ZPOSITIVE") == 0) {
    if (r->ntok < 2) FAIL(KARST_EPARSE, "ZPOSITIVE needs Elevation or Depth");
    quote(r->tok[1], q);
    if (strcasecmp(r->tok[1], "Elevation") == 0)
      r->zdepth = 0;
    else if (strcasecmp(r->tok[1], "Depth") == 0)
      r->zdepth = 1;
    else
      FAIL(KARST_EPARSE, "ZPOSITIVE must be Elevation or Depth, got '%s'", q);
    if (r->ts->nobjects == 1) r->ts->zdepth = r->zdepth;
  } else if (strcmp(kw, "AXIS_UNIT") == 0) {
    if (r->ntok < 4)
      FAIL(KARST_EPARSE, "AXIS_UNIT needs the units of x, y and z, got %d", r->ntok - 1);
    for (int c = 0; c < 3; c++) {
      quote(r->tok[1 + c], q);
      if (unit_factor(r->tok[1 + c], &r->unit[c]))
        FAIL(KARST_EPARSE,
             "AXIS_UNIT: the unit of %c must be m, km or ft (or metres, meters, feet, usft), got "
             "'%s'",
             "xyz"[c], q);
    }
  }
  return KARST_SUCCESS; /* NAME, AXIS_NAME, PROJECTION, DATUM ...: kept as they are */
}

static int is_keyword(const char *kw, const char *const *list, size_t n) {
  for (size_t k = 0; k < n; k++)
    if (strcmp(kw, list[k]) == 0) return 1;
  return 0;
}

/* Metadata of the TSurf grammar and of common exports, skipped silently. */
static const char *const skipped[] = {"GEOLOGICAL_FEATURE",
                                      "GEOLOGICAL_TYPE",
                                      "STRATIGRAPHIC_POSITION",
                                      "PROPERTY_CLASSES",
                                      "PROP_LEGAL_RANGES",
                                      "PROPERTY_KINDS",
                                      "PROPERTY_SUBCLASSES",
                                      "UNITS",
                                      "PROP_UNIT",
                                      "PROP_ORIGINAL_UNIT",
                                      "TRGL_PROPERTIES",
                                      "TRGL_PROP_LEGAL_RANGES",
                                      "TRGL_NO_DATA_VALUES",
                                      "TRGL_PROPERTY_CLASSES",
                                      "TRGL_PROPERTY_KINDS",
                                      "TRGL_PROPERTY_SUBCLASSES",
                                      "TRGL_ESIZES",
                                      "TRGL_UNITS",
                                      "NAME",
                                      "PROJECTION",
                                      "DATUM",
                                      "AXIS_NAME",
                                      "CONSTRAINT",
                                      "SUBVSET",
                                      "INTERPOLATION_METHOD",
                                      "REGION",
                                      "LAYER"};

static karst_error_t object_line(reader_t *r) {
  const char *kw = r->tok[0];
  karst_error_t err;
  if (r->in_block) {
    if (kw[0] == '}')
      r->in_block = 0;
    else if (strncmp(kw, "name:", 5) == 0 && !r->ts->name && r->ts->nobjects == 1) {
      /* "name:Top Jurassic": the rest of the line, words joined by one space */
      size_t len = 0;
      for (int k = 0; k < r->ntok; k++)
        len += strlen(r->tok[k]) + 1;
      char *nm = malloc(len + 1);
      if (!nm) return nomem(r);
      nm[0] = '\0';
      strcat(nm, kw + 5);
      for (int k = 1; k < r->ntok; k++) {
        if (nm[0]) strcat(nm, " ");
        strcat(nm, r->tok[k]);
      }
      r->ts->name = nm;
    }
    return KARST_SUCCESS;
  }
  if (r->in_crs) {
    if (strcmp(kw, "END_ORIGINAL_COORDINATE_SYSTEM") == 0) {
      r->in_crs = 0;
      return KARST_SUCCESS;
    }
    return read_crs_line(r);
  }
  const char *last = r->tok[r->ntok - 1];
  if (strncmp(kw, "HEADER", 6) == 0 && strchr(kw, '{') == NULL && r->ntok > 1 &&
      r->tok[1][0] == '{' && last[strlen(last) - 1] == '}') { /* HEADER {name:x} on one line */
    for (int k = 1; k < r->ntok; k++) {
      const char *t = r->tok[k] + (r->tok[k][0] == '{');
      if (strncmp(t, "name:", 5) == 0 && !r->ts->name && r->ts->nobjects == 1) {
        size_t nlen = strlen(t + 5) - (t[strlen(t) - 1] == '}');
        if (!(r->ts->name = strndup(t + 5, nlen))) return nomem(r);
      }
    }
    return KARST_SUCCESS;
  }
  if (last[strlen(last) - 1] == '{') { /* HEADER {, HEADER{, PROPERTY_CLASS_HEADER Z { */
    r->in_block = 1;
    r->block_line = r->lineno;
    return KARST_SUCCESS;
  }
  if (strcmp(kw, "VRTX") == 0) return add_vertex(r, 0);
  if (strcmp(kw, "PVRTX") == 0) return add_vertex(r, 1);
  if (strcmp(kw, "TRGL") == 0) return add_triangle(r);
  if (strcmp(kw, "ATOM") == 0) return add_atom(r, 0);
  if (strcmp(kw, "PATOM") == 0) return add_atom(r, 1);
  if (strcmp(kw, "TFACE") == 0 || strcmp(kw, "TRIANGLES") == 0) {
    r->part_open = 1;
    r->ts->nparts++;
    return KARST_SUCCESS;
  }
  if (strcmp(kw, "BSTONE") == 0) return add_ref(r, 0);
  if (strcmp(kw, "BORDER") == 0) return add_ref(r, 1);
  if (strcmp(kw, "GOCAD_ORIGINAL_COORDINATE_SYSTEM") == 0) {
    r->in_crs = 1;
    r->crs_line = r->lineno;
    return KARST_SUCCESS;
  }
  if (strcmp(kw, "ZPOSITIVE") == 0 || strcmp(kw, "AXIS_UNIT") == 0) return read_crs_line(r);
  if (strcmp(kw, "PROPERTIES") == 0 || strcmp(kw, "ESIZES") == 0 ||
      strcmp(kw, "NO_DATA_VALUES") == 0) {
    if ((err = read_properties(r))) return err;
    return settle_properties(r);
  }
  if (strcmp(kw, "HDR") == 0) {
    if (r->ntok >= 2 && strncmp(r->tok[1], "name:", 5) == 0 && !r->ts->name &&
        r->ts->nobjects == 1 && !(r->ts->name = strdup(r->tok[1] + 5)))
      return nomem(r);
    return KARST_SUCCESS;
  }
  if (strcmp(kw, "END") == 0) {
    if ((err = resolve_object(r))) return err;
    r->in_object = 0;
    r->after_end = 1;
    return KARST_SUCCESS;
  }
  if (strcmp(kw, "GOCAD") == 0) {
    char q[TOKEN_QUOTE_MAX + 4];
    quote(r->ntok > 1 ? r->tok[1] : "", q);
    FAIL(KARST_EPARSE, "a new GOCAD %s object begins before the END of the one at line %ld", q,
         r->object_line);
  }
  if (is_keyword(kw, skipped, sizeof skipped / sizeof skipped[0])) return KARST_SUCCESS;
  if (kw[0] == '#' || kw[0] == '*') return KARST_SUCCESS;
  if (!r->warned) {
    char q[TOKEN_QUOTE_MAX + 4];
    quote(kw, q);
    karst_log(r->ctx, KARST_LOG_WARNING, "%s:%ld: unknown TSurf keyword '%s' skipped", r->path,
              r->lineno, q);
    r->warned = 1;
  }
  return KARST_SUCCESS;
}

static karst_error_t header_line(reader_t *r) {
  char q[TOKEN_QUOTE_MAX + 4];
  quote(r->tok[0], q);
  if (strcmp(r->tok[0], "GOCAD") != 0) {
    if (r->after_end)
      FAIL(KARST_EPARSE,
           "'%s' after END: expected the end of the file or a new 'GOCAD TSurf' "
           "object",
           q);
    FAIL(KARST_EPARSE, "not a GOCAD TSurf file: expected 'GOCAD TSurf 1', got '%s'", q);
  }
  quote(r->ntok > 1 ? r->tok[1] : "", q);
  if (r->ntok < 2 || strcasecmp(r->tok[1], "TSurf") != 0)
    FAIL(KARST_EPARSE, "GOCAD %s object: a surface file must hold GOCAD TSurf objects", q);
  object_reset(r);
  r->in_object = 1;
  r->object_line = r->lineno;
  r->obj_v0 = r->ts->nv;
  r->obj_t0 = r->ts->nt;
  r->ts->nobjects++;
  return settle_properties(r);
}

/**
 * Read a GOCAD TSurf file into @p ts (zeroed by the caller): see the grammar
 * at the top of this file. Vertices keep their file ids and lines; z is
 * negated under ZPOSITIVE Depth and every axis scaled to metres by AXIS_UNIT;
 * ATOM and PATOM ids resolve to the vertex they repeat; TRGL ids become vertex
 * indices. The geometry is not checked here (karst_i_surface_tin does it, with
 * these lines in its messages).
 * @param ctx context; errors read "FILE:LINE: message" quoting the value.
 * @param path the file (a regular file of at most KARST_SURFACE_MAX_BYTES).
 * @return KARST_SUCCESS, KARST_EIO, KARST_EPARSE (malformed, truncated, an
 *         unknown id, another GOCAD object), KARST_EINVAL (a number not
 *         finite), KARST_ERANGE (an id or count too large) or KARST_ENOMEM;
 *         @p ts is emptied on failure.
 * Time complexity: O(file size + n log n) for n vertices and atoms.
 */
karst_error_t karst_i_tsurf_read(karst_ctx_t *ctx, const char *path, karst_i_tsurf_t *ts) {
  reader_t rd;
  reader_t *r = &rd;
  memset(r, 0, sizeof *r);
  r->ctx = ctx;
  r->path = path;
  r->ts = ts;
  r->unit[0] = r->unit[1] = r->unit[2] = 1.0;
  memset(ts, 0, sizeof *ts);
  FILE *fp = NULL;
  char *line = NULL;
  size_t cap = 0;
  karst_error_t err = karst_i_open_regular(ctx, path, "surface", KARST_SURFACE_MAX_BYTES, &fp);
  if (err) return err;
  ssize_t len;
  int seen = 0;
  while ((len = getline(&line, &cap, fp)) >= 0) {
    r->lineno++;
    char *p = line;
    if (r->lineno == 1 && len >= 3 && (unsigned char)p[0] == 0xEF && (unsigned char)p[1] == 0xBB &&
        (unsigned char)p[2] == 0xBF)
      p += 3;
    if ((size_t)len != strlen(line)) {
      err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld: a NUL byte: not a text file", path,
                            r->lineno);
      goto cleanup;
    }
    if (tokenize(r, p)) {
      err = nomem(r);
      goto cleanup;
    }
    if (r->ntok == 0 || (r->tok[0][0] == '#' && !r->in_block)) continue;
    seen = 1;
    err = r->in_object ? object_line(r) : header_line(r);
    if (err) {
      if (line[len - 1] != '\n' && ctx) { /* the last line, cut short */
        size_t used = strlen(ctx->errmsg);
        snprintf(ctx->errmsg + used, sizeof ctx->errmsg - used,
                 " (the file ends in the middle of this line: truncated?)");
      }
      goto cleanup;
    }
  }
  if (ferror(fp)) {
    err = karst_set_error(ctx, KARST_EIO, "%s:%ld: cannot read: %s", path, r->lineno,
                          strerror(errno));
    goto cleanup;
  }
  if (!seen) {
    err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld: empty file: expected 'GOCAD TSurf 1'", path,
                          r->lineno > 0 ? r->lineno : 1);
    goto cleanup;
  }
  if (r->in_object) {
    const char *what = r->in_block ? "inside the block opened"
                       : r->in_crs ? "inside the "
                                     "coordinate system "
                                     "opened"
                                   : "in the object begun";
    long at = r->in_block ? r->block_line : r->in_crs ? r->crs_line : r->object_line;
    err = karst_set_error(ctx, KARST_EPARSE,
                          "%s:%ld: the file ends %s at line %ld, without END: a truncated file?",
                          path, r->lineno, what, at);
    goto cleanup;
  }
  if (ts->nt == 0) {
    err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld: no TRGL triangles in the file", path,
                          r->lineno);
    goto cleanup;
  }
  ts->tri = r->traw;
  r->traw = NULL;
cleanup:
  object_reset(r);
  free(r->tok);
  free(r->traw);
  free(r->atoms);
  free(r->refs);
  free(line);
  fclose(fp);
  if (err) karst_i_tsurf_destroy(ts);
  return err;
}

/** Release what karst_i_tsurf_read allocated and zero @p ts. O(properties). */
void karst_i_tsurf_destroy(karst_i_tsurf_t *ts) {
  free(ts->xyz);
  free(ts->vid);
  free(ts->vline);
  free(ts->tri);
  free(ts->tline);
  free(ts->tpart);
  free(ts->name);
  for (int k = 0; k < ts->nprops; k++)
    free(ts->prop_names[k]);
  free(ts->prop_names);
  free(ts->prop_esize);
  free(ts->props);
  memset(ts, 0, sizeof *ts);
}
