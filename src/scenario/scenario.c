/* Scenario lifecycle, defaults, the YAML reader and the cross-field checks.
 *
 * The file is parsed with libyaml's document API (yaml_parser_load), so every
 * node keeps its line and column, and then walked with small tables that say,
 * for each key, its type, where it is stored and its allowed range. The same
 * tables drive the range checks of karst_scenario_check(), so a rule is
 * written once. The format is documented in docs/scenario.md. */
#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <yaml.h>

#include "karst/blocks.h"
#include "karst/conditioning.h"
#include "karst/crs.h"
#include "karst/geology.h"
#include "karst/surface.h"
#include "scenario_internal.h"

/* ------------------------------------------------------------------------ */
/* Lifecycle and defaults                                                   */
/* ------------------------------------------------------------------------ */

/**
 * Fill @p sc with every documented default (docs/scenario.md): a 100 m cube,
 * flat terrain at 100 m, water table at 0 m, no key points, the cost weights,
 * sampling radii, γ = 2 and θ = 0.1 of Paris et al. 2021 (Table 1,
 * "branchwork"), k = 40 (§4.1) and radii 0.5–4 m (epikarst 0.5 m, §5.3).
 * Time complexity: O(1).
 */
void karst_scenario_init(karst_scenario_t *sc) {
  memset(sc, 0, sizeof *sc);
  sc->domain_max[0] = sc->domain_max[1] = sc->domain_max[2] = 100.0;
  sc->terrain.elevation = 100.0;
  sc->permeability.background = 1.0;
  sc->cost.w0 = 1.0;
  sc->cost.horizon = 1.0;
  sc->cost.fracture = 1.0;
  sc->cost.permeability = 1.0;
  sc->cost.prescribed = 0.1;
  sc->sampling.fill_radius = 10.0;
  sc->sampling.feature_radius = 3.0;
  sc->sampling.permeable_threshold = 0.3;
  sc->sampling.feature_band = 1.0;
  sc->sampling.refine = KARST_REFINE_ALL;
  sc->sampling.k = 40;
  sc->sampling.max_samples = 5000000;
  sc->gamma = 2.0;
  sc->reuse = KARST_SCENARIO_DEFAULT_REUSE;
  sc->cost.fracture_combine = KARST_FRACTURE_SUM;
  sc->tortuosity = 0.1;
  sc->amplification.reach_ratio = 0.5;
  sc->amplification.points_ratio = 1.0;
  sc->classification.vertical_angle = 60.0;
  sc->routing.vadose_factor = 2.0;
  sc->routing.rise_cost = 4.0;
  sc->routing.phreatic_depth = 50.0;
  sc->routing.water_table_band = 5.0;
  sc->classification.epikarst_depth = 10.0;
  sc->classification.chamber_resistance = 0.05;
  sc->classification.radius_correlation = 100.0;
  for (int t = 0; t < KARST_TUNNEL_TYPE_COUNT; t++) {
    sc->classification.radius[t].min = 0.5;
    sc->classification.radius[t].max = 4.0;
  }
  sc->classification.radius[KARST_TUNNEL_EPIKARST].max = 0.5;
  sc->seed = 1;
  sc->realisations = 1;
  sc->conditioning.cost_factor = KARST_SCENARIO_DEFAULT_LEG_COST_FACTOR;
  karst_geometry_init(&sc->geometry);
}

/**
 * Defaults of the geometry section (docs/geometry.md): junctions blended over
 * the smallest radius there; wall details after the morphology of each
 * conduit type (fine isotropic roughness in phreatic tubes and the epikarst,
 * flow-aligned scallops and flutes on keyhole and canyon walls, breakdown
 * roughness in chambers); speleothems in chambers, passages and beds.
 * Time complexity: O(1).
 */
void karst_geometry_init(karst_geometry_t *g) {
  memset(g, 0, sizeof *g);
  g->blend = -1;
  g->blend_factor = 1.0;
  g->continuation_angle = 45.0;
  /* amplitude (m), wavelength (m), bandwidth (1/m), orientation (degrees), anisotropy */
  static const double det[KARST_TUNNEL_TYPE_COUNT][5] = {
      {0.02, 0.25, 4.0, 0, 0.0},  /* tube */
      {0.03, 0.40, 2.0, 90, 0.7}, /* keyhole */
      {0.05, 0.50, 1.5, 90, 0.9}, /* canyon: horizontal flutes along the flow */
      {0.02, 0.50, 2.0, 0, 0.3},  /* bed */
      {0.03, 0.40, 2.0, 0, 0.5},  /* passage */
      {0.02, 0.20, 5.0, 0, 0.0},  /* epikarst */
      {0.05, 0.80, 1.25, 0, 0.0}, /* chamber */
  };
  /* density (1/m²), pair height (m), min and max length (m) */
  static const double spe[KARST_TUNNEL_TYPE_COUNT][4] = {
      {0, 4, 0.2, 1.0},    {0, 4, 0.2, 1.0}, {0, 4, 0.2, 1.0},    {0.01, 3, 0.1, 0.5},
      {0.02, 4, 0.2, 1.2}, {0, 4, 0.2, 1.0}, {0.08, 6, 0.3, 2.5},
  };
  for (int t = 0; t < KARST_TUNNEL_TYPE_COUNT; t++) {
    karst_wall_details_t *w = &g->details[t];
    w->amplitude = det[t][0];
    w->wavelength = det[t][1];
    w->bandwidth = det[t][2];
    w->orientation = det[t][3];
    w->anisotropy = det[t][4];
    karst_speleothem_rule_t *r = &g->speleothems[t];
    r->density = spe[t][0];
    r->clearance = 0.5;
    r->pair_height = spe[t][1];
    r->min_length = spe[t][2];
    r->max_length = spe[t][3];
  }
  g->speleothem_relief = 0.01;
  g->fracture_relief = 0;
  g->fracture_spacing = 2.0;
  g->fracture_width = 0.3;
}

static void free_perm(karst_perm_node_t *n) {
  for (int i = 0; i < n->n_children; i++)
    free_perm(&n->children[i]);
  free(n->children);
}

/** Release what a scenario holds and leave it zeroed. O(size). */
void karst_scenario_destroy(karst_scenario_t *sc) {
  free(sc->path);
  free(sc->name);
  free(sc->terrain.path);
  free(sc->terrain.z);
  free(sc->sampling.points);
  free(sc->sampling.points_xyz);
  karst_surface_free(sc->terrain.surface);
  for (int i = 0; i < sc->n_horizons; i++)
    free(sc->horizons[i].path), karst_surface_free(sc->horizons[i].surface);
  free(sc->horizons);
  free(sc->water_table.path), karst_surface_free(sc->water_table.surface);
  for (int i = 0; i < sc->n_key_points; i++)
    free(sc->key_points[i].water_table.path),
        karst_surface_free(sc->key_points[i].water_table.surface), free(sc->key_points[i].station);
  for (int i = 0; i < sc->n_generations; i++)
    free(sc->generations[i].water_table.path),
        karst_surface_free(sc->generations[i].water_table.surface);
  free(sc->generations);
  for (int i = 0; i < sc->conditioning.n_surveys; i++)
    free(sc->conditioning.surveys[i].path), free(sc->conditioning.surveys[i].crs);
  free(sc->conditioning.surveys);
  for (int i = 0; i < sc->conditioning.n_sink_stations; i++)
    free(sc->conditioning.sink_stations[i]);
  free(sc->conditioning.sink_stations);
  karst_survey_set_free(sc->conditioning.data);
  free(sc->crs);
  karst_crs_free(sc->crs_frame);
  for (int i = 0; i < sc->n_strata; i++) {
    free(sc->strata[i].top.path), karst_surface_free(sc->strata[i].top.surface);
    free(sc->strata[i].bottom.path), karst_surface_free(sc->strata[i].bottom.surface);
  }
  free(sc->fractures);
  if (sc->permeability.root) {
    free_perm(sc->permeability.root);
    free(sc->permeability.root);
  }
  free(sc->key_points);
  free(sc->prescribed);
  karst_blocks_section_free(sc->blocks);
  free(sc->strata);
  for (int i = 0; i < sc->n_exclusions; i++)
    free(sc->exclusions[i].polygon);
  free(sc->exclusions);
  free(sc->faults);
  free(sc->connectivity.sinks);
  free(sc->connectivity.springs);
  free(sc->connectivity.matrix);
  memset(sc, 0, sizeof *sc);
}

/* ------------------------------------------------------------------------ */
/* Schema tables                                                            */
/* ------------------------------------------------------------------------ */

typedef struct reader reader_t;
typedef karst_error_t (*field_fn)(reader_t *r, yaml_node_t *val, void *base, const char *path);

typedef enum { T_NUM, T_INT, T_I64, T_U64, T_STR, T_VEC2, T_VEC3, T_ENUM, T_MAP, T_FN } ftype_t;

enum { R_LO = 1, R_LO_OPEN = 2, R_HI = 4, R_HI_OPEN = 8 };
typedef struct range {
  unsigned flags;
  double lo, hi;
  const char *unit; /* " m", " degrees" or "" */
} range_t;

#define RANGE_NONE                                                                                 \
  { 0, 0, 0, "" }
#define RANGE_GT(lo, u)                                                                            \
  { R_LO | R_LO_OPEN, lo, 0, u }
#define RANGE_GE(lo, u)                                                                            \
  { R_LO, lo, 0, u }
#define RANGE_CLOSED(lo, hi, u)                                                                    \
  { R_LO | R_HI, lo, hi, u }
#define RANGE_CLOSED_OPEN(lo, hi, u)                                                               \
  { R_LO | R_HI | R_HI_OPEN, lo, hi, u }
#define RANGE_OPEN_CLOSED(lo, hi, u)                                                               \
  { R_LO | R_LO_OPEN | R_HI, lo, hi, u }

typedef struct schema schema_t;
typedef struct field {
  const char *key;
  ftype_t type;
  size_t off;    /* where the value lives, from the base of the map's object */
  range_t range; /* T_NUM, T_INT, T_I64 */
  int required;
  const schema_t *sub;      /* T_MAP: the nested map, whose offsets start from base + off */
  field_fn fn;              /* T_FN: custom reader */
  const char *const *names; /* T_ENUM: allowed values, stored as their index (an int) */
  int n_names;
  size_t pos; /* offset of a karst_srcpos_t in karst_scenario_t to record, or 0 */
} field_t;

struct schema {
  const field_t *f;
  int n;
};

#define MAX_FIELDS 32
#define PATH_LEN 256

/* Everything the walk needs. */
struct reader {
  karst_ctx_t *ctx;
  const char *file; /* scenario path as given, for messages */
  yaml_document_t *doc;
  karst_scenario_t *sc;
  long perm_nodes;
  yaml_node_t *prescribed;   /* read after the key points, whose names it uses */
  yaml_node_t *connectivity; /* likewise */
  yaml_node_t **drains;      /* per key point: its drains_to list, read after all key points */
  int n_drains;
  karst_i_override_set_t *ovs; /* values put into the document before the walk, or NULL */
  yaml_node_t *generations;    /* read after the top-level keys, whose values are its defaults */
  int generation;              /* the generation whose key points are being read (1-based), or 0 */
};

/* ------------------------------------------------------------------------ */
/* Messages                                                                 */
/* ------------------------------------------------------------------------ */

static int line_of(const yaml_node_t *n) {
  return (int)n->start_mark.line + 1;
}
static int col_of(const yaml_node_t *n) {
  return (int)n->start_mark.column + 1;
}

static karst_error_t fail_at(reader_t *r, const yaml_node_t *n, karst_error_t code, const char *fmt,
                             ...) __attribute__((format(printf, 4, 5)));
/* "FILE:LINE:COLUMN: message" at node @p n; "FILE: ORIGIN: message" at a node an override
 * added (overrides.c). */
static karst_error_t fail_at(reader_t *r, const yaml_node_t *n, karst_error_t code, const char *fmt,
                             ...) {
  char msg[KARST_ERRMSG_MAX];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  int k = karst_i_override_of(r->ovs, r->doc, n);
  if (k >= 0) {
    char lbl[400];
    return karst_set_error(r->ctx, code, "%s: %s: %s", r->file,
                           karst_i_override_label(r->ovs, k, lbl, sizeof lbl), msg);
  }
  return karst_set_error(r->ctx, code, "%s:%d:%d: %s", r->file, line_of(n), col_of(n), msg);
}

/* Record what an override's value was read as; a numeric override of a key that holds no
 * number (@p what: "a string", "one of the names ...") is refused. */
static karst_error_t read_as(reader_t *r, const yaml_node_t *n, const char *path,
                             karst_override_type_t type, const char *what) {
  int k = karst_i_override_of(r->ovs, r->doc, n);
  if (k < 0) return KARST_SUCCESS;
  r->ovs->types[k] = type;
  if (type == KARST_OVERRIDE_TEXT && r->ovs->ov[k].numeric)
    return fail_at(r, n, KARST_EINVAL, "%s is not a numeric key (it holds %s)", path, what);
  return KARST_SUCCESS;
}

static karst_error_t no_memory(reader_t *r) {
  return karst_set_error(r->ctx, KARST_ENOMEM, "%s: out of memory", r->file);
}

/* A scalar's text for a message: at most ~40 characters, control characters shown as '?'. */
static void clip(const char *s, size_t len, char *out, size_t outsz) {
  size_t k = 0, i;
  for (i = 0; i < len && k + 4 < outsz && k < 40; i++) {
    unsigned char c = (unsigned char)s[i];
    out[k++] = (c < 32 || c == 127) ? '?' : (char)c;
  }
  if (i < len) {
    memcpy(out + k, "...", 3);
    k += 3;
  }
  out[k] = '\0';
}

static const char *scalar(const yaml_node_t *n) {
  return (const char *)n->data.scalar.value;
}
static int is_plain(const yaml_node_t *n) {
  return n->data.scalar.style == YAML_PLAIN_SCALAR_STYLE ||
         n->data.scalar.style == YAML_ANY_SCALAR_STYLE;
}
static int is_null(const yaml_node_t *n) {
  if (n->type != YAML_SCALAR_NODE || !is_plain(n)) return 0;
  const char *s = scalar(n);
  return !strcmp(s, "") || !strcmp(s, "~") || !strcmp(s, "null") || !strcmp(s, "Null") ||
         !strcmp(s, "NULL");
}

/* A plain scalar that reads as a number (including .nan, .inf and 1e999). */
static int looks_numeric(const yaml_node_t *n) {
  if (n->type != YAML_SCALAR_NODE || !is_plain(n) || n->data.scalar.length == 0) return 0;
  const char *s = scalar(n);
  const char *u = s + (*s == '+' || *s == '-');
  if (!strcmp(u, ".nan") || !strcmp(u, ".NaN") || !strcmp(u, ".NAN") || !strcmp(u, ".inf") ||
      !strcmp(u, ".Inf") || !strcmp(u, ".INF"))
    return 1;
  char *end;
  (void)strtod(s, &end);
  return end != s && *end == '\0' && (size_t)(end - s) == n->data.scalar.length;
}

/* What a node is, for "got ..." in messages: numbers as written, words quoted. */
static const char *describe(const yaml_node_t *n, char *buf, size_t sz) {
  char t[64];
  switch (n->type) {
  case YAML_MAPPING_NODE:
    return "a map";
  case YAML_SEQUENCE_NODE:
    return "a list";
  case YAML_SCALAR_NODE:
    if (is_null(n)) return n->data.scalar.length == 0 ? "an empty value" : "null";
    clip(scalar(n), n->data.scalar.length, t, sizeof t);
    snprintf(buf, sz, looks_numeric(n) ? "%s" : is_plain(n) ? "'%s'" : "the string \"%s\"", t);
    return buf;
  default:
    return "nothing";
  }
}

static const char *disp(const char *path) {
  return path[0] ? path : "the scenario";
}

/* "in fractures[2]", or "at the top level". */
static const char *where(const char *path, char *buf, size_t sz) {
  if (!path[0]) return "at the top level";
  snprintf(buf, sz, "in %s", path);
  return buf;
}

/* Field paths for messages ("fractures[2].dip"); a path too long to show ends in "...". */
static void join(char *out, const char *path, const char *key) {
  if (snprintf(out, PATH_LEN, "%s%s%s", path, path[0] ? "." : "", key) >= PATH_LEN)
    memcpy(out + PATH_LEN - 4, "...", 4);
}
static void index_path(char *out, const char *path, long i) {
  if (snprintf(out, PATH_LEN, "%s[%ld]", path, i) >= PATH_LEN) memcpy(out + PATH_LEN - 4, "...", 4);
}

/* "within [0, 90) degrees", "> 0 m", ... */
static void range_text(const range_t *g, char *buf, size_t sz) {
  if ((g->flags & R_LO) && (g->flags & R_HI))
    snprintf(buf, sz, "within %c%g, %g%c%s", g->flags & R_LO_OPEN ? '(' : '[', g->lo, g->hi,
             g->flags & R_HI_OPEN ? ')' : ']', g->unit);
  else if (g->flags & R_LO)
    snprintf(buf, sz, "%s %g%s", g->flags & R_LO_OPEN ? ">" : ">=", g->lo, g->unit);
  else if (g->flags & R_HI)
    snprintf(buf, sz, "%s %g%s", g->flags & R_HI_OPEN ? "<" : "<=", g->hi, g->unit);
  else
    snprintf(buf, sz, "any number");
}

static int in_range(const range_t *g, double v) {
  if (g->flags & R_LO) {
    if ((g->flags & R_LO_OPEN) ? !(v > g->lo) : !(v >= g->lo)) return 0;
  }
  if (g->flags & R_HI) {
    if ((g->flags & R_HI_OPEN) ? !(v < g->hi) : !(v <= g->hi)) return 0;
  }
  return 1;
}

/* ------------------------------------------------------------------------ */
/* Scalars                                                                  */
/* ------------------------------------------------------------------------ */

/* A finite number. Quoted scalars are strings, not numbers; .nan, .inf and
 * overflowing literals such as 1e999 are refused as non-finite. */
static karst_error_t get_number(reader_t *r, yaml_node_t *n, const char *path, double *out) {
  char d[80];
  read_as(r, n, path, KARST_OVERRIDE_NUMBER, NULL);
  if (n->type != YAML_SCALAR_NODE || !is_plain(n) || is_null(n))
    return fail_at(r, n, KARST_EINVAL, "%s must be a number, got %s", path,
                   describe(n, d, sizeof d));
  const char *s = scalar(n);
  const char *u = s + (*s == '+' || *s == '-');
  if (!strcmp(u, ".nan") || !strcmp(u, ".NaN") || !strcmp(u, ".NAN") || !strcmp(u, ".inf") ||
      !strcmp(u, ".Inf") || !strcmp(u, ".INF"))
    return fail_at(r, n, KARST_ERANGE, "%s must be a finite number, got %s", path,
                   describe(n, d, sizeof d));
  char *end;
  errno = 0;
  double v = strtod(s, &end);
  if (end == s || *end != '\0' || (size_t)(end - s) != n->data.scalar.length)
    return fail_at(r, n, KARST_EINVAL, "%s must be a number, got %s", path,
                   describe(n, d, sizeof d));
  if (!isfinite(v) || (errno == ERANGE && fabs(v) > 1.0))
    return fail_at(r, n, KARST_ERANGE, "%s must be a finite number, got %s", path,
                   describe(n, d, sizeof d));
  *out = v;
  return KARST_SUCCESS;
}

/* An integer within [lo, hi] (the limits of the C type). Integer literals are
 * read exactly; a floating literal is accepted only when it is a whole
 * number below 2^53 (so "5e6" works and "2.5" does not). A value outside the
 * type is reported with the field's own bounds [mlo, mhi] (e.g. k: 1 to
 * 2147483647), so the message says what is allowed. */
static karst_error_t get_integer(reader_t *r, yaml_node_t *n, const char *path, int64_t lo,
                                 int64_t hi, int64_t mlo, int64_t mhi, int64_t *out) {
  char d[80];
  read_as(r, n, path, KARST_OVERRIDE_INTEGER, NULL);
  if (n->type != YAML_SCALAR_NODE || !is_plain(n) || is_null(n))
    return fail_at(r, n, KARST_EINVAL, "%s must be an integer, got %s", path,
                   describe(n, d, sizeof d));
  const char *s = scalar(n);
  size_t i = (*s == '+' || *s == '-');
  int digits = s[i] != '\0';
  for (; s[i]; i++)
    if (s[i] < '0' || s[i] > '9') digits = 0;
  int64_t v;
  if (digits) {
    errno = 0;
    long long x = strtoll(s, NULL, 10);
    if (errno == ERANGE || x < lo || x > hi)
      return fail_at(r, n, KARST_ERANGE,
                     "%s must be an integer between %" PRId64 " and %" PRId64 ", got %s", path, mlo,
                     mhi, describe(n, d, sizeof d));
    v = (int64_t)x;
  } else {
    char *end;
    double x = strtod(s, &end);
    if (end == s || *end != '\0' || !isfinite(x) || x != floor(x))
      return fail_at(r, n, KARST_EINVAL, "%s must be an integer, got %s", path,
                     describe(n, d, sizeof d));
    if (x < (double)lo || x > (double)hi)
      return fail_at(r, n, KARST_ERANGE,
                     "%s must be an integer between %" PRId64 " and %" PRId64 ", got %s", path, mlo,
                     mhi, describe(n, d, sizeof d));
    if (fabs(x) > 9007199254740992.0)
      return fail_at(r, n, KARST_EINVAL,
                     "%s: %s is beyond 2^53 and not exact in floating notation; write it in digits",
                     path, describe(n, d, sizeof d));
    v = (int64_t)x;
  }
  *out = v;
  return KARST_SUCCESS;
}

static karst_error_t get_u64(reader_t *r, yaml_node_t *n, const char *path, uint64_t *out) {
  char d[80];
  karst_error_t err = read_as(r, n, path, KARST_OVERRIDE_TEXT, "a seed, not a model parameter");
  if (err) return err;
  int ok = n->type == YAML_SCALAR_NODE && is_plain(n) && !is_null(n);
  const char *s = ok ? scalar(n) : "";
  size_t i = ok && *s == '+';
  if (!s[i]) ok = 0;
  for (; ok && s[i]; i++)
    if (s[i] < '0' || s[i] > '9') ok = 0;
  unsigned long long x = 0;
  if (ok) {
    errno = 0;
    x = strtoull(s, NULL, 10);
    if (errno == ERANGE) ok = 0;
  }
  if (!ok)
    return fail_at(r, n, KARST_EINVAL,
                   "%s must be an unsigned 64-bit integer (0 to 18446744073709551615), got %s",
                   path, describe(n, d, sizeof d));
  *out = (uint64_t)x;
  return KARST_SUCCESS;
}

/* A non-empty string without NUL or control characters (names end up in output files). */
static karst_error_t get_string(reader_t *r, yaml_node_t *n, const char *path, const char **out) {
  char d[80];
  karst_error_t err = read_as(r, n, path, KARST_OVERRIDE_TEXT, "a string");
  if (err) return err;
  if (n->type != YAML_SCALAR_NODE || is_null(n) || n->data.scalar.length == 0)
    return fail_at(r, n, KARST_EINVAL, "%s must be a non-empty string, got %s", path,
                   describe(n, d, sizeof d));
  const char *s = scalar(n);
  for (size_t i = 0; i < n->data.scalar.length; i++)
    if ((unsigned char)s[i] < 32 || s[i] == 127)
      return fail_at(r, n, KARST_EINVAL, "%s must not contain control characters, got %s", path,
                     describe(n, d, sizeof d));
  *out = s;
  return KARST_SUCCESS;
}

/* One of @p names; returns its index. Misspellings get the allowed values and a suggestion. */
static karst_error_t get_enum(reader_t *r, yaml_node_t *n, const char *path,
                              const char *const *names, int count, int *out) {
  char d[80], list[256] = "", what[300];
  for (int i = 0; i < count; i++)
    snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", i ? ", " : "", names[i]);
  snprintf(what, sizeof what, "one of the names %s", list);
  karst_error_t err = read_as(r, n, path, KARST_OVERRIDE_TEXT, what);
  if (err) return err;
  if (n->type != YAML_SCALAR_NODE || is_null(n))
    return fail_at(r, n, KARST_EINVAL, "%s must be one of %s, got %s", path, list,
                   describe(n, d, sizeof d));
  for (int i = 0; i < count; i++) {
    if (strlen(names[i]) == n->data.scalar.length && !strcmp(scalar(n), names[i])) {
      *out = i;
      return KARST_SUCCESS;
    }
  }
  const char *hint = karst_i_suggest(scalar(n), names, count);
  return fail_at(r, n, KARST_EINVAL, "%s must be one of %s, got %s%s%s%s", path, list,
                 describe(n, d, sizeof d), hint ? " (did you mean '" : "", hint ? hint : "",
                 hint ? "'?)" : "");
}

/* A list of exactly @p k finite numbers, e.g. [x, y, z]. */
static karst_error_t get_vec(reader_t *r, yaml_node_t *n, const char *path, int k, double *out) {
  char d[80], sub[PATH_LEN];
  const char *form = k == 3 ? "[x, y, z]" : k == 2 ? "[x, y]" : "[...]";
  if (n->type != YAML_SEQUENCE_NODE)
    return fail_at(r, n, KARST_EINVAL, "%s must be a list of %d numbers %s, got %s", path, k, form,
                   describe(n, d, sizeof d));
  long count = n->data.sequence.items.top - n->data.sequence.items.start;
  if (count != k)
    return fail_at(r, n, KARST_EINVAL, "%s must be a list of %d numbers %s, got %ld item%s", path,
                   k, form, count, count == 1 ? "" : "s");
  for (int i = 0; i < k; i++) {
    yaml_node_t *item = yaml_document_get_node(r->doc, n->data.sequence.items.start[i]);
    index_path(sub, path, i);
    karst_error_t err = get_number(r, item, sub, &out[i]);
    if (err) return err;
  }
  return KARST_SUCCESS;
}

/* ------------------------------------------------------------------------ */
/* Maps                                                                     */
/* ------------------------------------------------------------------------ */

/*
 * Check the key of pair @p k of @p map: a plain name, not given twice, one of
 * @p keys (unknown keys get a "did you mean"). Sets *idx to its index.
 */
static karst_error_t check_key(reader_t *r, yaml_node_t *map, yaml_node_pair_t *pair,
                               const char *const *keys, int nkeys, const char *path,
                               const schema_t *nested_hint, int *idx) {
  char d[80], k1[64], w[PATH_LEN + 8];
  yaml_node_t *key = yaml_document_get_node(r->doc, pair->key);
  if (key->type != YAML_SCALAR_NODE || is_null(key))
    return fail_at(r, key, KARST_EINVAL, "keys %s must be names, got %s", where(path, w, sizeof w),
                   describe(key, d, sizeof d));
  const char *name = scalar(key);
  for (yaml_node_pair_t *p = map->data.mapping.pairs.start; p < pair; p++) {
    yaml_node_t *other = yaml_document_get_node(r->doc, p->key);
    if (other->type == YAML_SCALAR_NODE && other->data.scalar.length == key->data.scalar.length &&
        !memcmp(scalar(other), name, key->data.scalar.length)) {
      clip(name, key->data.scalar.length, k1, sizeof k1);
      return fail_at(r, key, KARST_EINVAL, "duplicate key '%s' %s (first given at line %d)", k1,
                     where(path, w, sizeof w), line_of(other));
    }
  }
  for (int i = 0; i < nkeys; i++) {
    if (strlen(keys[i]) == key->data.scalar.length && !strcmp(keys[i], name)) {
      *idx = i;
      return KARST_SUCCESS;
    }
  }
  clip(name, key->data.scalar.length, k1, sizeof k1);
  const char *hint = karst_i_suggest(name, keys, nkeys);
  if (hint)
    return fail_at(r, key, KARST_EINVAL, "unknown key '%s' %s (did you mean '%s'?)", k1,
                   where(path, w, sizeof w), hint);
  /* A nested key written at the wrong level, e.g. "gamma" instead of skeleton.gamma. */
  for (int i = 0; nested_hint && i < nested_hint->n; i++) {
    const field_t *f = &nested_hint->f[i];
    for (int j = 0; f->type == T_MAP && j < f->sub->n; j++) {
      if (!strcmp(f->sub->f[j].key, name))
        return fail_at(r, key, KARST_EINVAL, "unknown key '%s' %s (did you mean '%s.%s'?)", k1,
                       where(path, w, sizeof w), f->key, name);
    }
  }
  char list[512] = "";
  for (int i = 0; i < nkeys; i++)
    snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", i ? ", " : "", keys[i]);
  return fail_at(r, key, KARST_EINVAL, "unknown key '%s' %s (the keys are %s)", k1,
                 where(path, w, sizeof w), list);
}

static karst_error_t read_field(reader_t *r, const field_t *f, yaml_node_t *val, char *base,
                                const char *path);

/* Read a map against @p s, in file order, then report missing required keys. */
static karst_error_t walk_map(reader_t *r, yaml_node_t *map, const schema_t *s, void *base,
                              const char *path, const schema_t *nested_hint) {
  char d[80], sub[PATH_LEN];
  const char *keys[MAX_FIELDS];
  int seen[MAX_FIELDS] = {0};
  if (map->type != YAML_MAPPING_NODE)
    return fail_at(r, map, KARST_EINVAL, "%s must be a map of keys, got %s", disp(path),
                   describe(map, d, sizeof d));
  for (int i = 0; i < s->n; i++)
    keys[i] = s->f[i].key;
  for (yaml_node_pair_t *p = map->data.mapping.pairs.start; p < map->data.mapping.pairs.top; p++) {
    int idx = 0;
    karst_error_t err = check_key(r, map, p, keys, s->n, path, nested_hint, &idx);
    if (err) return err;
    seen[idx] = 1;
    join(sub, path, keys[idx]);
    err = read_field(r, &s->f[idx], yaml_document_get_node(r->doc, p->value), base, sub);
    if (err) return err;
  }
  for (int i = 0; i < s->n; i++)
    if (s->f[i].required && !seen[i])
      return fail_at(r, map, KARST_EINVAL, "%s is missing the required key '%s'", disp(path),
                     s->f[i].key);
  return KARST_SUCCESS;
}

static karst_error_t check_range(reader_t *r, const field_t *f, yaml_node_t *val, const char *path,
                                 double v) {
  char rt[96], d[80];
  if (in_range(&f->range, v)) return KARST_SUCCESS;
  range_text(&f->range, rt, sizeof rt);
  return fail_at(r, val, KARST_ERANGE, "%s must be %s, got %s", path, rt,
                 describe(val, d, sizeof d));
}

static karst_error_t read_field(reader_t *r, const field_t *f, yaml_node_t *val, char *base,
                                const char *path) {
  karst_error_t err = KARST_SUCCESS;
  void *at = base + f->off;
  switch (f->type) {
  case T_NUM: {
    double v = 0;
    if ((err = get_number(r, val, path, &v))) return err;
    if ((err = check_range(r, f, val, path, v))) return err;
    *(double *)at = v;
    break;
  }
  case T_INT:
  case T_I64: {
    int64_t v = 0;
    int64_t lo = f->type == T_INT ? INT_MIN : INT64_MIN,
            hi = f->type == T_INT ? INT_MAX : INT64_MAX, mlo = lo, mhi = hi;
    if ((f->range.flags & R_LO) && f->range.lo > (double)lo)
      mlo = (int64_t)floor(f->range.lo) + ((f->range.flags & R_LO_OPEN) ? 1 : 0);
    if ((f->range.flags & R_HI) && f->range.hi < (double)hi)
      mhi = (int64_t)ceil(f->range.hi) - ((f->range.flags & R_HI_OPEN) ? 1 : 0);
    if ((err = get_integer(r, val, path, lo, hi, mlo, mhi, &v))) return err;
    if ((err = check_range(r, f, val, path, (double)v))) return err;
    if (f->type == T_INT)
      *(int *)at = (int)v;
    else
      *(karst_int_t *)at = v;
    break;
  }
  case T_U64:
    if ((err = get_u64(r, val, path, (uint64_t *)at))) return err;
    break;
  case T_STR: {
    const char *s;
    if ((err = get_string(r, val, path, &s))) return err;
    char *copy = strdup(s);
    if (!copy) return no_memory(r);
    free(*(char **)at);
    *(char **)at = copy;
    break;
  }
  case T_VEC2:
  case T_VEC3:
    if ((err = get_vec(r, val, path, f->type == T_VEC2 ? 2 : 3, (double *)at))) return err;
    break;
  case T_ENUM: {
    int v = 0;
    if ((err = get_enum(r, val, path, f->names, f->n_names, &v))) return err;
    *(int *)at = v;
    break;
  }
  case T_MAP:
    if ((err = walk_map(r, val, f->sub, at, path, NULL))) return err;
    break;
  case T_FN:
    if ((err = f->fn(r, val, base, path))) return err;
    break;
  }
  if (f->pos) {
    karst_srcpos_t *pos = (karst_srcpos_t *)((char *)r->sc + f->pos);
    pos->line = line_of(val);
    pos->column = col_of(val);
  }
  return KARST_SUCCESS;
}

/* ------------------------------------------------------------------------ */
/* Lists and custom readers                                                 */
/* ------------------------------------------------------------------------ */

/* A list of maps read against @p s into a new array; an empty value is an empty list. */
static karst_error_t read_list(reader_t *r, yaml_node_t *n, const char *path, size_t item_size,
                               const schema_t *s, void (*init)(void *item), size_t line_off,
                               size_t col_off, void **out, int *count) {
  char d[80], sub[PATH_LEN];
  if (is_null(n)) return KARST_SUCCESS;
  if (n->type != YAML_SEQUENCE_NODE)
    return fail_at(r, n, KARST_EINVAL, "%s must be a list of maps, got %s", path,
                   describe(n, d, sizeof d));
  long m = n->data.sequence.items.top - n->data.sequence.items.start;
  if (m > INT_MAX / 2) return fail_at(r, n, KARST_ERANGE, "%s has too many items (%ld)", path, m);
  if (m == 0) return KARST_SUCCESS;
  char *items = calloc((size_t)m, item_size);
  if (!items) return no_memory(r);
  free(*out);
  *out = items;
  *count = (int)m;
  for (long i = 0; i < m; i++) {
    char *item = items + i * item_size;
    yaml_node_t *in = yaml_document_get_node(r->doc, n->data.sequence.items.start[i]);
    init(item);
    *(int *)(item + line_off) = line_of(in);
    *(int *)(item + col_off) = col_of(in);
    index_path(sub, path, i);
    karst_error_t err = walk_map(r, in, s, item, sub, NULL);
    if (err) return err;
  }
  return KARST_SUCCESS;
}

static const char *const keypoint_type_names[] = {"sink", "spring", "waypoint"};
_Static_assert(sizeof(karst_keypoint_type_t) == sizeof(int), "key point type is stored as an int");

static karst_error_t read_kp_name(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_keypoint_t *kp = base;
  const char *s = NULL;
  karst_error_t err = get_string(r, n, path, &s);
  if (err) return err;
  if (strlen(s) >= sizeof kp->name)
    return fail_at(r, n, KARST_ERANGE, "%s must be at most %d characters, got %zu", path,
                   (int)sizeof kp->name - 1, strlen(s));
  memcpy(kp->name, s, strlen(s) + 1);
  return KARST_SUCCESS;
}

static karst_error_t read_horizon_name(reader_t *r, yaml_node_t *n, void *base, const char *path);
static karst_error_t read_horizon_surface(reader_t *r, yaml_node_t *n, void *base,
                                          const char *path);
static karst_error_t read_kp_water_table(reader_t *r, yaml_node_t *n, void *base, const char *path);
static karst_error_t defer_drains(reader_t *r, yaml_node_t *n, void *base, const char *path);
static karst_error_t read_kp_station(reader_t *r, yaml_node_t *n, void *base, const char *path);

static const field_t horizon_fields[] = {
    {.key = "name", .type = T_FN, .fn = read_horizon_name},
    {.key = "surface", .type = T_FN, .fn = read_horizon_surface},
    {.key = "elevation", .type = T_NUM, .off = offsetof(karst_horizon_t, elevation)},
    {.key = "dip",
     .type = T_NUM,
     .off = offsetof(karst_horizon_t, dip),
     .range = RANGE_CLOSED_OPEN(0, 90, " degrees")},
    {.key = "dip_direction",
     .type = T_NUM,
     .off = offsetof(karst_horizon_t, dip_direction),
     .range = RANGE_CLOSED_OPEN(0, 360, " degrees")},
    {.key = "origin", .type = T_VEC2, .off = offsetof(karst_horizon_t, origin)},
    {.key = "radius",
     .type = T_NUM,
     .off = offsetof(karst_horizon_t, radius),
     .range = RANGE_GT(0, " m"),
     .required = 1},
};
static const schema_t horizon_schema = {horizon_fields, 7};

static const field_t dfn_fields[] = {
    {.key = "p32",
     .type = T_NUM,
     .off = offsetof(karst_fracture_t, p32),
     .range = RANGE_GT(0, " m2/m3"),
     .required = 1},
    {.key = "size_exponent",
     .type = T_NUM,
     .off = offsetof(karst_fracture_t, size_exponent),
     .range = RANGE_GT(1, "")},
    {.key = "r_min",
     .type = T_NUM,
     .off = offsetof(karst_fracture_t, r_min),
     .range = RANGE_GT(0, " m")},
    {.key = "r_max",
     .type = T_NUM,
     .off = offsetof(karst_fracture_t, r_max),
     .range = RANGE_GT(0, " m")},
    {.key = "factor",
     .type = T_NUM,
     .off = offsetof(karst_fracture_t, factor),
     .range = RANGE_OPEN_CLOSED(0, 1, "")},
    {.key = "influence",
     .type = T_NUM,
     .off = offsetof(karst_fracture_t, influence),
     .range = RANGE_GT(0, " m")},
};
static const schema_t dfn_schema = {dfn_fields, 6};

/* fractures[i].fisher_kappa: a finite κ > 0 (not given: no dispersion, stored as 0). */
static karst_error_t read_kappa(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  static const range_t gt0 = RANGE_GT(0, "");
  char d[80];
  double v = 0;
  karst_error_t err = get_number(r, n, path, &v);
  if (err) return err;
  if (!in_range(&gt0, v))
    return fail_at(r, n, KARST_ERANGE, "%s must be > 0, got %s", path, describe(n, d, sizeof d));
  ((karst_fracture_t *)base)->kappa = v;
  return KARST_SUCCESS;
}

/* fractures[i].dfn: the family realised as discs (docs/scenario.md, "Fractures"). */
static karst_error_t read_dfn(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_fracture_t *f = base;
  karst_error_t err = walk_map(r, n, &dfn_schema, f, path, NULL);
  if (err) return err;
  if (!(f->r_min <= f->r_max))
    return fail_at(r, n, KARST_ERANGE, "%s: r_min (%g m) must not exceed r_max (%g m)", path,
                   f->r_min, f->r_max);
  f->dfn = 1;
  return KARST_SUCCESS;
}

static const field_t fracture_fields[] = {
    {.key = "dip_direction",
     .type = T_NUM,
     .off = offsetof(karst_fracture_t, dip_direction),
     .range = RANGE_CLOSED_OPEN(0, 360, " degrees"),
     .required = 1},
    {.key = "dip",
     .type = T_NUM,
     .off = offsetof(karst_fracture_t, dip),
     .range = RANGE_CLOSED(0, 90, " degrees"),
     .required = 1},
    {.key = "weight",
     .type = T_NUM,
     .off = offsetof(karst_fracture_t, weight),
     .range = RANGE_GE(0, "")},
    {.key = "fisher_kappa", .type = T_FN, .fn = read_kappa},
    {.key = "dfn", .type = T_FN, .fn = read_dfn},
};
static const schema_t fracture_schema = {fracture_fields, 5};

static const field_t keypoint_fields[] = {
    {.key = "name", .type = T_FN, .fn = read_kp_name},
    {.key = "type",
     .type = T_ENUM,
     .off = offsetof(karst_keypoint_t, type),
     .required = 1,
     .names = keypoint_type_names,
     .n_names = 3},
    {.key = "position", .type = T_VEC3, .off = offsetof(karst_keypoint_t, p)},
    {.key = "water_table", .type = T_FN, .fn = read_kp_water_table},
    {.key = "drains_to", .type = T_FN, .fn = defer_drains},
    {.key = "latitude",
     .type = T_NUM,
     .off = offsetof(karst_keypoint_t, geographic),
     .range = RANGE_CLOSED(-90, 90, " degrees")},
    {.key = "longitude",
     .type = T_NUM,
     .off = offsetof(karst_keypoint_t, geographic) + sizeof(double),
     .range = RANGE_CLOSED(-180, 360, " degrees")},
    {.key = "elevation",
     .type = T_NUM,
     .off = offsetof(karst_keypoint_t, geographic) + 2 * sizeof(double)},
    {.key = "station", .type = T_FN, .fn = read_kp_station},
};
static const schema_t keypoint_schema = {keypoint_fields, 9};

static void init_horizon(void *item) {
  karst_horizon_t *h = item;
  h->origin[0] = h->origin[1] = NAN; /* domain centre, once the domain is known */
  h->elevation = NAN;                /* required unless a surface file is given */
}
static void init_fracture(void *item) {
  karst_fracture_t *f = item;
  f->weight = 1.0;
  f->size_exponent = 2.5; /* the power-law exponent of many joint sets (Bonnet et al. 2001) */
  f->r_min = 5.0;
  f->r_max = 50.0;
  f->factor = 0.5;
  f->influence = NAN; /* sampling.feature_radius, once sampling is read */
}
/* A key point's position comes from position, latitude/longitude/elevation or station: NAN marks
 * what the file did not give (finish checks that exactly one form is given). */
static void init_keypoint(void *item) {
  karst_keypoint_t *kp = item;
  for (int a = 0; a < 3; a++)
    kp->p[a] = NAN, kp->geographic[a] = NAN;
  kp->station_index = -1;
}

static karst_error_t read_horizons(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_scenario_t *sc = base;
  return read_list(r, n, path, sizeof(karst_horizon_t), &horizon_schema, init_horizon,
                   offsetof(karst_horizon_t, line), offsetof(karst_horizon_t, column),
                   (void **)&sc->horizons, &sc->n_horizons);
}
static karst_error_t read_fractures(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_scenario_t *sc = base;
  return read_list(r, n, path, sizeof(karst_fracture_t), &fracture_schema, init_fracture,
                   offsetof(karst_fracture_t, line), offsetof(karst_fracture_t, column),
                   (void **)&sc->fractures, &sc->n_fractures);
}
static karst_error_t read_key_points(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_scenario_t *sc = base;
  return read_list(r, n, path, sizeof(karst_keypoint_t), &keypoint_schema, init_keypoint,
                   offsetof(karst_keypoint_t, line), offsetof(karst_keypoint_t, column),
                   (void **)&sc->key_points, &sc->n_key_points);
}

static karst_error_t defer_prescribed(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  (void)base;
  (void)path;
  r->prescribed = n;
  return KARST_SUCCESS;
}

/* units: only metres ("m") are supported; every length in the file is in them. */
static karst_error_t read_units(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  char d[80];
  (void)base;
  karst_error_t err = read_as(r, n, path, KARST_OVERRIDE_TEXT, "the name of the unit, m");
  if (err) return err;
  if (n->type == YAML_SCALAR_NODE && !strcmp(scalar(n), "m") && n->data.scalar.length == 1)
    return KARST_SUCCESS;
  return fail_at(r, n, KARST_EUNSUPPORTED, "%s must be m (metres, the only unit supported), got %s",
                 path, describe(n, d, sizeof d));
}

static char *resolve_relative(reader_t *r, const char *name, const char *path);
static karst_error_t read_surface_file(reader_t *r, yaml_node_t *v, const char *path,
                                       const char *file, struct karst_surface **out);

/* terrain: {elevation: z}, {heightfield: file.asc} or {surface: file.ts|.asc}, files relative to
 * the scenario. */
static karst_error_t read_terrain(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  static const char *const keys[] = {"elevation", "heightfield", "surface"};
  karst_scenario_t *sc = base;
  yaml_node_t *vals[3] = {NULL, NULL, NULL};
  char d[80], sub[PATH_LEN];
  karst_error_t err = KARST_SUCCESS;
  char *resolved = NULL;
  FILE *fp = NULL;
  if (n->type != YAML_MAPPING_NODE)
    return fail_at(r, n, KARST_EINVAL,
                   "%s must be a map with elevation (flat, m) or heightfield (an ESRI ASCII grid "
                   "file), got %s",
                   path, describe(n, d, sizeof d));
  for (yaml_node_pair_t *p = n->data.mapping.pairs.start; p < n->data.mapping.pairs.top; p++) {
    int idx = 0;
    if ((err = check_key(r, n, p, keys, 3, path, NULL, &idx))) return err;
    vals[idx] = yaml_document_get_node(r->doc, p->value);
  }
  int given = !!vals[0] + !!vals[1] + !!vals[2];
  if (given > 1)
    return fail_at(r, n, KARST_EINVAL,
                   "%s gives more than one of elevation, heightfield and surface; give one of them",
                   path);
  if (given == 0)
    return fail_at(r, n, KARST_EINVAL,
                   "%s must give elevation (flat, m), heightfield (an ESRI ASCII grid file) or "
                   "surface (a GOCAD TSurf or grid file)",
                   path);
  yaml_node_t *v = vals[0] ? vals[0] : (vals[1] ? vals[1] : vals[2]);
  sc->pos_terrain.line = line_of(v);
  sc->pos_terrain.column = col_of(v);
  if (vals[2]) { /* a triangulated (or grid) terrain through the surface module */
    const char *name;
    join(sub, path, "surface");
    if ((err = get_string(r, v, sub, &name))) return err;
    free(sc->terrain.path);
    if (!(sc->terrain.path = resolve_relative(r, name, sub))) return no_memory(r);
    if ((err = read_surface_file(r, v, sub, sc->terrain.path, &sc->terrain.surface))) return err;
    double lo[3], hi[3];
    karst_surface_bounds(sc->terrain.surface, lo, hi);
    sc->terrain.is_grid = 0;
    sc->terrain.zmin = lo[2], sc->terrain.zmax = hi[2];
    sc->terrain.lipschitz = karst_surface_lipschitz(sc->terrain.surface);
    return KARST_SUCCESS;
  }
  if (vals[0]) {
    join(sub, path, "elevation");
    if ((err = get_number(r, v, sub, &sc->terrain.elevation))) return err;
    sc->terrain.is_grid = 0;
    return KARST_SUCCESS;
  }
  join(sub, path, "heightfield");
  const char *hf;
  if ((err = get_string(r, v, sub, &hf))) return err;
  if (!(resolved = resolve_relative(r, hf, sub))) return no_memory(r);
  if ((err = karst_i_open_regular(r->ctx, resolved, "heightfield", KARST_HEIGHTFIELD_MAX_BYTES,
                                  &fp))) {
    char msg[KARST_ERRMSG_MAX];
    snprintf(msg, sizeof msg, "%s", r->ctx->errmsg);
    err = fail_at(r, v, err, "%s: %s", sub, msg);
    goto cleanup;
  }
  err = karst_i_terrain_read_grid(r->ctx, fp, resolved, &sc->terrain);
  if (err == KARST_EIO) { /* unreadable (e.g. a directory): no grid position to give */
    char msg[KARST_ERRMSG_MAX];
    snprintf(msg, sizeof msg, "%s", r->ctx->errmsg);
    err = fail_at(r, v, KARST_EIO, "%s: %s", sub, msg);
  } else if (err) {
    size_t len = strlen(r->ctx->errmsg);
    snprintf(r->ctx->errmsg + len, KARST_ERRMSG_MAX - len, " (the heightfield of %s at %s:%d:%d)",
             path, r->file, line_of(v), col_of(v));
  }
cleanup:
  if (fp) fclose(fp);
  free(resolved);
  return err;
}

/* --- permeability construction tree ------------------------------------- */

static const field_t sphere_fields[] = {
    {.key = "center", .type = T_VEC3, .off = offsetof(karst_perm_node_t, center), .required = 1},
    {.key = "radius",
     .type = T_NUM,
     .off = offsetof(karst_perm_node_t, radius),
     .range = RANGE_GT(0, " m"),
     .required = 1},
    {.key = "resistance",
     .type = T_NUM,
     .off = offsetof(karst_perm_node_t, resistance),
     .range = RANGE_CLOSED(0, 1, ""),
     .required = 1},
    {.key = "falloff",
     .type = T_NUM,
     .off = offsetof(karst_perm_node_t, falloff),
     .range = RANGE_GE(0, " m")},
};
static const schema_t sphere_schema = {sphere_fields, 4};

static const field_t stratum_fields[] = {
    {.key = "bottom", .type = T_NUM, .off = offsetof(karst_perm_node_t, bottom), .required = 1},
    {.key = "top", .type = T_NUM, .off = offsetof(karst_perm_node_t, top), .required = 1},
    {.key = "resistance",
     .type = T_NUM,
     .off = offsetof(karst_perm_node_t, resistance),
     .range = RANGE_CLOSED(0, 1, ""),
     .required = 1},
};
static const schema_t stratum_schema = {stratum_fields, 3};

static const range_t perm_weight_range = RANGE_GT(0, "");

/* Node keys: the kind (exactly one) and an optional blend weight. */
static const char *const perm_keys[] = {"sphere",       "stratum", "union",
                                        "intersection", "blend",   "weight"};
static const karst_perm_kind_t perm_kinds[] = {KARST_PERM_SPHERE, KARST_PERM_STRATUM,
                                               KARST_PERM_UNION, KARST_PERM_INTERSECTION,
                                               KARST_PERM_BLEND};
#define PERM_KIND_KEYS "sphere, stratum, union, intersection or blend"

static void init_perm_node(karst_perm_node_t *node, const yaml_node_t *n) {
  memset(node, 0, sizeof *node);
  node->weight = 1.0;
  node->line = line_of(n);
  node->column = col_of(n);
}

static karst_error_t read_perm_node(reader_t *r, yaml_node_t *n, karst_perm_node_t *node,
                                    const char *path, int depth);

/* The children of an operator: a non-empty list of nodes. */
static karst_error_t read_perm_children(reader_t *r, yaml_node_t *n, karst_perm_node_t *node,
                                        const char *path, int depth) {
  char d[80], sub[PATH_LEN];
  if (n->type != YAML_SEQUENCE_NODE)
    return fail_at(r, n, KARST_EINVAL, "%s must be a list of nodes, got %s", path,
                   describe(n, d, sizeof d));
  long m = n->data.sequence.items.top - n->data.sequence.items.start;
  if (m == 0)
    return fail_at(r, n, KARST_EINVAL, "%s must list at least one node, got an empty list", path);
  if (m > KARST_SCENARIO_PERM_MAX_NODES)
    return fail_at(r, n, KARST_ERANGE, "%s has %ld nodes, more than the limit of %d", path, m,
                   KARST_SCENARIO_PERM_MAX_NODES);
  node->children = calloc((size_t)m, sizeof *node->children);
  if (!node->children) return no_memory(r);
  node->n_children = (int)m;
  for (long i = 0; i < m; i++) {
    yaml_node_t *c = yaml_document_get_node(r->doc, n->data.sequence.items.start[i]);
    init_perm_node(&node->children[i], c);
    index_path(sub, path, i);
    karst_error_t err = read_perm_node(r, c, &node->children[i], sub, depth + 1);
    if (err) return err;
  }
  return KARST_SUCCESS;
}

static karst_error_t read_perm_node(reader_t *r, yaml_node_t *n, karst_perm_node_t *node,
                                    const char *path, int depth) {
  char d[80], sub[PATH_LEN];
  karst_error_t err;
  if (depth > KARST_SCENARIO_PERM_MAX_DEPTH)
    return fail_at(r, n, KARST_ERANGE,
                   "%s: the permeability tree is nested deeper than %d levels (a YAML alias "
                   "cycle?)",
                   path, KARST_SCENARIO_PERM_MAX_DEPTH);
  if (++r->perm_nodes > KARST_SCENARIO_PERM_MAX_NODES)
    return fail_at(r, n, KARST_ERANGE, "%s: the permeability tree has more than %d nodes", path,
                   KARST_SCENARIO_PERM_MAX_NODES);
  if (n->type != YAML_MAPPING_NODE)
    return fail_at(r, n, KARST_EINVAL, "%s must be a map with one of " PERM_KIND_KEYS ", got %s",
                   path, describe(n, d, sizeof d));
  int kind = -1;
  yaml_node_t *kind_val = NULL, *kind_key = NULL;
  for (yaml_node_pair_t *p = n->data.mapping.pairs.start; p < n->data.mapping.pairs.top; p++) {
    int idx = 0;
    if ((err = check_key(r, n, p, perm_keys, 6, path, NULL, &idx))) return err;
    yaml_node_t *v = yaml_document_get_node(r->doc, p->value);
    if (idx == 5) {
      join(sub, path, "weight");
      if ((err = get_number(r, v, sub, &node->weight))) return err;
      if (!in_range(&perm_weight_range, node->weight))
        return fail_at(r, v, KARST_ERANGE, "%s must be > 0, got %s", sub, describe(v, d, sizeof d));
      continue;
    }
    if (kind >= 0)
      return fail_at(r, yaml_document_get_node(r->doc, p->key), KARST_EINVAL,
                     "%s has both '%s' and '%s': a node is one primitive or one operator", path,
                     perm_keys[kind], perm_keys[idx]);
    kind = idx;
    kind_val = v;
    kind_key = yaml_document_get_node(r->doc, p->key);
  }
  if (kind < 0) return fail_at(r, n, KARST_EINVAL, "%s must contain one of " PERM_KIND_KEYS, path);
  (void)kind_key;
  node->kind = perm_kinds[kind];
  join(sub, path, perm_keys[kind]);
  switch (node->kind) {
  case KARST_PERM_SPHERE:
    return walk_map(r, kind_val, &sphere_schema, node, sub, NULL);
  case KARST_PERM_STRATUM:
    if ((err = walk_map(r, kind_val, &stratum_schema, node, sub, NULL))) return err;
    if (!(node->bottom < node->top))
      return fail_at(r, kind_val, KARST_ERANGE, "%s: bottom (%g m) must be below top (%g m)", sub,
                     node->bottom, node->top);
    return KARST_SUCCESS;
  default:
    return read_perm_children(r, kind_val, node, sub, depth);
  }
}

static karst_error_t new_root(reader_t *r, yaml_node_t *n, karst_permeability_t *p,
                              const char *path) {
  if (p->root)
    return fail_at(r, n, KARST_EINVAL,
                   "%s: give either permeability.tree or permeability.primitives, not both", path);
  p->root = malloc(sizeof *p->root);
  if (!p->root) return no_memory(r);
  init_perm_node(p->root, n);
  return KARST_SUCCESS;
}

static karst_error_t read_perm_tree(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_permeability_t *p = base;
  karst_error_t err = new_root(r, n, p, path);
  if (err) return err;
  return read_perm_node(r, n, p->root, path, 0);
}

/* primitives: [...] is the union of the listed nodes. */
static karst_error_t read_perm_primitives(reader_t *r, yaml_node_t *n, void *base,
                                          const char *path) {
  karst_permeability_t *p = base;
  karst_error_t err = new_root(r, n, p, path);
  if (err) return err;
  p->root->kind = KARST_PERM_UNION;
  ++r->perm_nodes;
  return read_perm_children(r, n, p->root, path, 0);
}

/* classification.radius: {tube: [min, max], ...} for any of the tunnel types. */
static karst_error_t read_radius(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_classification_t *c = base;
  const char *names[KARST_TUNNEL_TYPE_COUNT];
  char d[80], sub[PATH_LEN];
  for (int i = 0; i < KARST_TUNNEL_TYPE_COUNT; i++)
    names[i] = karst_tunnel_type_name((karst_tunnel_type_t)i);
  if (n->type != YAML_MAPPING_NODE)
    return fail_at(r, n, KARST_EINVAL, "%s must be a map from tunnel type to [min, max], got %s",
                   path, describe(n, d, sizeof d));
  for (yaml_node_pair_t *p = n->data.mapping.pairs.start; p < n->data.mapping.pairs.top; p++) {
    int t = 0;
    karst_error_t err = check_key(r, n, p, names, KARST_TUNNEL_TYPE_COUNT, path, NULL, &t);
    if (err) return err;
    yaml_node_t *v = yaml_document_get_node(r->doc, p->value);
    double mm[2];
    join(sub, path, names[t]);
    if (v->type != YAML_SEQUENCE_NODE ||
        v->data.sequence.items.top - v->data.sequence.items.start != 2)
      return fail_at(r, v, KARST_EINVAL, "%s must be a list [min, max] of 2 numbers (m), got %s",
                     sub, describe(v, d, sizeof d));
    if ((err = get_vec(r, v, sub, 2, mm))) return err;
    if (!(mm[0] > 0))
      return fail_at(r, v, KARST_ERANGE, "%s: min must be > 0 m, got %g", sub, mm[0]);
    if (!(mm[0] <= mm[1]))
      return fail_at(r, v, KARST_ERANGE, "%s: min must be <= max, got [%g, %g]", sub, mm[0], mm[1]);
    c->radius[t].min = mm[0];
    c->radius[t].max = mm[1];
  }
  return KARST_SUCCESS;
}

/* --- geometry (karst mesh: docs/geometry.md) -------------------------------- */

/* geometry.blend: "auto" (the smallest radius at each junction times
 * blend_factor, stored as -1) or a width >= 0 m. */
static karst_error_t read_blend(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_geometry_t *g = base;
  char d[80];
  if (n->type == YAML_SCALAR_NODE && is_plain(n) && !strcmp(scalar(n), "auto")) {
    g->blend = -1;
    return KARST_SUCCESS;
  }
  double v = 0;
  karst_error_t err = get_number(r, n, path, &v);
  if (err) return err;
  if (!(v >= 0))
    return fail_at(r, n, KARST_ERANGE, "%s must be auto or a width >= 0 m, got %s", path,
                   describe(n, d, sizeof d));
  g->blend = v;
  return KARST_SUCCESS;
}

static const field_t wall_fields[] = {
    {.key = "amplitude",
     .type = T_NUM,
     .off = offsetof(karst_wall_details_t, amplitude),
     .range = RANGE_GE(0, " m")},
    {.key = "wavelength",
     .type = T_NUM,
     .off = offsetof(karst_wall_details_t, wavelength),
     .range = RANGE_GT(0, " m")},
    {.key = "bandwidth",
     .type = T_NUM,
     .off = offsetof(karst_wall_details_t, bandwidth),
     .range = RANGE_GT(0, " per m")},
    {.key = "orientation",
     .type = T_NUM,
     .off = offsetof(karst_wall_details_t, orientation),
     .range = RANGE_CLOSED(-90, 90, " degrees")},
    {.key = "anisotropy",
     .type = T_NUM,
     .off = offsetof(karst_wall_details_t, anisotropy),
     .range = RANGE_CLOSED(0, 1, "")},
    {.key = "tilt",
     .type = T_NUM,
     .off = offsetof(karst_wall_details_t, tilt),
     .range = RANGE_CLOSED(0, 60, " degrees")},
    {.key = "tilt_direction", .type = T_NUM, .off = offsetof(karst_wall_details_t, tilt_direction)},
};
static const schema_t wall_schema = {wall_fields, 7};

#define WALL_OF(t, name)                                                                           \
  { .key = name, .type = T_MAP, .off = (t) * sizeof(karst_wall_details_t), .sub = &wall_schema }
static const field_t details_fields[] = {
    WALL_OF(KARST_TUNNEL_TUBE, "tube"),       WALL_OF(KARST_TUNNEL_KEYHOLE, "keyhole"),
    WALL_OF(KARST_TUNNEL_CANYON, "canyon"),   WALL_OF(KARST_TUNNEL_BED, "bed"),
    WALL_OF(KARST_TUNNEL_PASSAGE, "passage"), WALL_OF(KARST_TUNNEL_EPIKARST, "epikarst"),
    WALL_OF(KARST_TUNNEL_CHAMBER, "chamber"),
};
#undef WALL_OF
static const schema_t details_schema = {details_fields, KARST_TUNNEL_TYPE_COUNT};

static const field_t speleothem_fields[] = {
    {.key = "density",
     .type = T_NUM,
     .off = offsetof(karst_speleothem_rule_t, density),
     .range = RANGE_GE(0, " per m²")},
    {.key = "clearance",
     .type = T_NUM,
     .off = offsetof(karst_speleothem_rule_t, clearance),
     .range = RANGE_GE(0, " m")},
    {.key = "pair_height",
     .type = T_NUM,
     .off = offsetof(karst_speleothem_rule_t, pair_height),
     .range = RANGE_GE(0, " m")},
    {.key = "min_length",
     .type = T_NUM,
     .off = offsetof(karst_speleothem_rule_t, min_length),
     .range = RANGE_GT(0, " m")},
    {.key = "max_length",
     .type = T_NUM,
     .off = offsetof(karst_speleothem_rule_t, max_length),
     .range = RANGE_GT(0, " m")},
};
static const schema_t speleothem_schema = {speleothem_fields, 5};

/* geometry.speleothems: {chamber: {density: ..}, ...}, min_length <= max_length. */
static karst_error_t read_speleothems(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_geometry_t *g = base;
  const char *names[KARST_TUNNEL_TYPE_COUNT];
  char d[80], sub[PATH_LEN];
  for (int i = 0; i < KARST_TUNNEL_TYPE_COUNT; i++)
    names[i] = karst_tunnel_type_name((karst_tunnel_type_t)i);
  if (n->type != YAML_MAPPING_NODE)
    return fail_at(r, n, KARST_EINVAL, "%s must be a map from tunnel type to a map, got %s", path,
                   describe(n, d, sizeof d));
  for (yaml_node_pair_t *p = n->data.mapping.pairs.start; p < n->data.mapping.pairs.top; p++) {
    int t = 0;
    karst_error_t err = check_key(r, n, p, names, KARST_TUNNEL_TYPE_COUNT, path, NULL, &t);
    if (err) return err;
    yaml_node_t *v = yaml_document_get_node(r->doc, p->value);
    join(sub, path, names[t]);
    karst_speleothem_rule_t *rule = &g->speleothems[t];
    if ((err = walk_map(r, v, &speleothem_schema, rule, sub, NULL))) return err;
    if (!(rule->min_length <= rule->max_length))
      return fail_at(r, v, KARST_ERANGE, "%s: min_length (%g m) must be <= max_length (%g m)", sub,
                     rule->min_length, rule->max_length);
  }
  return KARST_SUCCESS;
}

static const field_t geometry_fields[] = {
    {.key = "blend", .type = T_FN, .fn = read_blend},
    {.key = "blend_factor",
     .type = T_NUM,
     .off = offsetof(karst_geometry_t, blend_factor),
     .range = RANGE_GT(0, "")},
    {.key = "continuation_angle",
     .type = T_NUM,
     .off = offsetof(karst_geometry_t, continuation_angle),
     .range = RANGE_CLOSED(0, 90, " degrees")},
    {.key = "details",
     .type = T_MAP,
     .off = offsetof(karst_geometry_t, details),
     .sub = &details_schema},
    {.key = "speleothems", .type = T_FN, .fn = read_speleothems},
    {.key = "speleothem_relief",
     .type = T_NUM,
     .off = offsetof(karst_geometry_t, speleothem_relief),
     .range = RANGE_GE(0, " m")},
    {.key = "fracture_relief",
     .type = T_NUM,
     .off = offsetof(karst_geometry_t, fracture_relief),
     .range = RANGE_GE(0, " m")},
    {.key = "fracture_spacing",
     .type = T_NUM,
     .off = offsetof(karst_geometry_t, fracture_spacing),
     .range = RANGE_GT(0, " m")},
    {.key = "fracture_width",
     .type = T_NUM,
     .off = offsetof(karst_geometry_t, fracture_width),
     .range = RANGE_GT(0, " m")},
};
static const schema_t geometry_schema = {geometry_fields, 9};

/* --- geological surfaces ------------------------------------------------- */

/* The file @p name, given at key @p path, resolved relative to the scenario file (caller frees),
 * or NULL (no memory). A load with overrides notes the key, so that a scenario written elsewhere
 * can rebase it (karst_scenario_write_with_overrides). */
static char *resolve_relative(reader_t *r, const char *name, const char *path) {
  const char *slash = strrchr(r->file, '/');
  size_t dirlen = (name[0] == '/' || !slash) ? 0 : (size_t)(slash - r->file) + 1;
  char *out = malloc(dirlen + strlen(name) + 1);
  if (!out) return NULL;
  memcpy(out, r->file, dirlen);
  strcpy(out + dirlen, name);
  if (r->ovs && karst_i_overrides_note_file(r->ovs, path, name) != 0) {
    free(out);
    return NULL;
  }
  return out;
}

/* Read the surface file @p file (a grid .asc or a GOCAD TSurf .ts) into *out; a failure names
 * the key and its position in the scenario after the file's own FILE:LINE message. */
static karst_error_t read_surface_file(reader_t *r, yaml_node_t *v, const char *path,
                                       const char *file, struct karst_surface **out) {
  karst_surface_free(*out);
  *out = NULL;
  karst_error_t err = karst_surface_load(r->ctx, file, out);
  if (err) {
    size_t len = strlen(r->ctx->errmsg);
    snprintf(r->ctx->errmsg + len, KARST_ERRMSG_MAX - len, " (the surface of %s at %s:%d:%d)", path,
             r->file, line_of(v), col_of(v));
  }
  return err;
}

/* Read the surface file of a definition. */
static karst_error_t load_surface_file(reader_t *r, yaml_node_t *v, const char *path,
                                       karst_surface_def_t *d) {
  return read_surface_file(r, v, path, d->path, &d->surface);
}

static karst_error_t read_surface_path(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_surface_def_t *d = base;
  const char *name;
  karst_error_t err = get_string(r, n, path, &name);
  if (err) return err;
  free(d->path);
  if (!(d->path = resolve_relative(r, name, path))) return no_memory(r);
  return load_surface_file(r, n, path, d);
}

static const field_t surface_fields[] = {
    {.key = "elevation", .type = T_NUM, .off = offsetof(karst_surface_def_t, elevation)},
    {.key = "dip",
     .type = T_NUM,
     .off = offsetof(karst_surface_def_t, dip),
     .range = RANGE_CLOSED_OPEN(0, 90, " degrees")},
    {.key = "dip_direction",
     .type = T_NUM,
     .off = offsetof(karst_surface_def_t, dip_direction),
     .range = RANGE_CLOSED_OPEN(0, 360, " degrees")},
    {.key = "origin", .type = T_VEC2, .off = offsetof(karst_surface_def_t, origin)},
    {.key = "surface", .type = T_FN, .fn = read_surface_path},
};
static const schema_t surface_schema = {surface_fields, 5};

/* A surface: a number (a horizontal plane at that elevation), a plane {elevation, dip,
 * dip_direction, origin}, or {surface: FILE}. */
static karst_error_t read_surface_def(reader_t *r, yaml_node_t *n, karst_surface_def_t *d,
                                      const char *path) {
  char d2[80];
  karst_error_t err;
  d->origin[0] = d->origin[1] = NAN; /* the domain centre, once the domain is known */
  d->line = line_of(n);
  d->column = col_of(n);
  if (n->type == YAML_SCALAR_NODE) {
    if ((err = get_number(r, n, path, &d->elevation))) return err;
    d->given = 1;
    return KARST_SUCCESS;
  }
  if (n->type != YAML_MAPPING_NODE)
    return fail_at(r, n, KARST_EINVAL,
                   "%s must be an elevation (m), a plane {elevation, dip, dip_direction, origin} "
                   "or {surface: FILE}, got %s",
                   path, describe(n, d2, sizeof d2));
  d->elevation = NAN;
  int has_file = 0, has_plane = 0;
  for (yaml_node_pair_t *p = n->data.mapping.pairs.start; p < n->data.mapping.pairs.top; p++) {
    yaml_node_t *k = yaml_document_get_node(r->doc, p->key);
    if (k->type != YAML_SCALAR_NODE) continue;
    if (!strcmp(scalar(k), "surface"))
      has_file = 1;
    else
      has_plane = 1;
  }
  if (has_file && has_plane) /* before any file is read */
    return fail_at(r, n, KARST_EINVAL,
                   "%s gives both a surface file and plane keys (elevation, dip, dip_direction, "
                   "origin); give one of them",
                   path);
  if ((err = walk_map(r, n, &surface_schema, d, path, NULL))) return err;
  int plane_keys = 0;
  for (yaml_node_pair_t *p = n->data.mapping.pairs.start; p < n->data.mapping.pairs.top; p++) {
    const char *k = scalar(yaml_document_get_node(r->doc, p->key));
    plane_keys += strcmp(k, "surface") != 0;
    if (!strcmp(k, "elevation")) { /* messages about the plane point at its elevation */
      yaml_node_t *v = yaml_document_get_node(r->doc, p->value);
      d->line = line_of(v), d->column = col_of(v);
    }
  }
  if (d->path && plane_keys > 0)
    return fail_at(r, n, KARST_EINVAL,
                   "%s gives both a surface file and plane keys (elevation, dip, dip_direction, "
                   "origin); give one of them",
                   path);
  if (!d->path && isnan(d->elevation))
    return fail_at(r, n, KARST_EINVAL, "%s needs elevation (a plane) or surface (a file)", path);
  d->given = 1;
  return KARST_SUCCESS;
}

static karst_error_t read_water_table(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_scenario_t *sc = base;
  karst_error_t err = read_surface_def(r, n, &sc->water_table, path);
  sc->pos_water_table.line = line_of(n);
  sc->pos_water_table.column = col_of(n);
  return err;
}

static karst_error_t read_kp_water_table(reader_t *r, yaml_node_t *n, void *base,
                                         const char *path) {
  return read_surface_def(r, n, &((karst_keypoint_t *)base)->water_table, path);
}

/* drains_to: a list of spring names, resolved once every key point is known (finish). */
static karst_error_t defer_drains(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  (void)path;
  karst_keypoint_t *kp = base;
  long idx = kp - r->sc->key_points;
  if (idx < 0 || idx >= r->sc->n_key_points) return KARST_SUCCESS;
  if (!r->drains || idx >= r->n_drains) { /* generations append key points after the first read */
    yaml_node_t **d = realloc(r->drains, (size_t)r->sc->n_key_points * sizeof *d);
    if (!d) return no_memory(r);
    for (int i = r->drains ? r->n_drains : 0; i < r->sc->n_key_points; i++)
      d[i] = NULL;
    r->drains = d;
    r->n_drains = r->sc->n_key_points;
  }
  r->drains[idx] = n;
  kp->drains_line = line_of(n);
  kp->drains_column = col_of(n);
  return KARST_SUCCESS;
}

static karst_error_t read_stratum_top(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  return read_surface_def(r, n, &((karst_stratum_t *)base)->top, path);
}
static karst_error_t read_stratum_bottom(reader_t *r, yaml_node_t *n, void *base,
                                         const char *path) {
  return read_surface_def(r, n, &((karst_stratum_t *)base)->bottom, path);
}

/* A name of at most KARST_SCENARIO_NAME_MAX - 1 bytes into a char[KARST_SCENARIO_NAME_MAX] at base.
 */
static karst_error_t read_name_into(reader_t *r, yaml_node_t *n, char *out, const char *path) {
  const char *s = NULL;
  karst_error_t err = get_string(r, n, path, &s);
  if (err) return err;
  if (strlen(s) >= KARST_SCENARIO_NAME_MAX)
    return fail_at(r, n, KARST_ERANGE, "%s must be at most %d characters, got %zu", path,
                   KARST_SCENARIO_NAME_MAX - 1, strlen(s));
  memcpy(out, s, strlen(s) + 1);
  return KARST_SUCCESS;
}
static karst_error_t read_stratum_name(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  return read_name_into(r, n, ((karst_stratum_t *)base)->name, path);
}
static karst_error_t read_fault_name(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  return read_name_into(r, n, ((karst_fault_t *)base)->name, path);
}
static karst_error_t read_horizon_name(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  return read_name_into(r, n, ((karst_horizon_t *)base)->name, path);
}

static karst_error_t read_horizon_surface(reader_t *r, yaml_node_t *n, void *base,
                                          const char *path) {
  karst_horizon_t *h = base;
  const char *name;
  karst_error_t err = get_string(r, n, path, &name);
  if (err) return err;
  free(h->path);
  if (!(h->path = resolve_relative(r, name, path))) return no_memory(r);
  return read_surface_file(r, n, path, h->path, &h->surface);
}

static const char *const soluble_names[] = {"false", "true"};

static const field_t strat_fields[] = {
    {.key = "name", .type = T_FN, .fn = read_stratum_name},
    {.key = "top", .type = T_FN, .fn = read_stratum_top},
    {.key = "bottom", .type = T_FN, .fn = read_stratum_bottom},
    {.key = "soluble",
     .type = T_ENUM,
     .off = offsetof(karst_stratum_t, soluble),
     .names = soluble_names,
     .n_names = 2},
};
static const schema_t strata_schema = {strat_fields, 4};

static void init_stratum(void *item) {
  ((karst_stratum_t *)item)->soluble = 1;
}
static karst_error_t read_strata(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_scenario_t *sc = base;
  return read_list(r, n, path, sizeof(karst_stratum_t), &strata_schema, init_stratum,
                   offsetof(karst_stratum_t, line), offsetof(karst_stratum_t, column),
                   (void **)&sc->strata, &sc->n_strata);
}

/* --- exclusion zones ------------------------------------------------------ */

static const field_t exbox_fields[] = {
    {.key = "min", .type = T_VEC3, .off = offsetof(karst_exclusion_t, min), .required = 1},
    {.key = "max", .type = T_VEC3, .off = offsetof(karst_exclusion_t, max), .required = 1},
};
static const schema_t exbox_schema = {exbox_fields, 2};
static const field_t exsphere_fields[] = {
    {.key = "center", .type = T_VEC3, .off = offsetof(karst_exclusion_t, center), .required = 1},
    {.key = "radius",
     .type = T_NUM,
     .off = offsetof(karst_exclusion_t, radius),
     .range = RANGE_GT(0, " m"),
     .required = 1},
};
static const schema_t exsphere_schema = {exsphere_fields, 2};

/* prism.polygon: [[x, y], ...], at least 3 vertices. */
static karst_error_t read_polygon(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_exclusion_t *e = base;
  char d[80], sub[PATH_LEN];
  if (n->type != YAML_SEQUENCE_NODE)
    return fail_at(r, n, KARST_EINVAL, "%s must be a list of [x, y] vertices, got %s", path,
                   describe(n, d, sizeof d));
  long m = n->data.sequence.items.top - n->data.sequence.items.start;
  if (m < 3 || m > KARST_SCENARIO_PRISM_MAX_VERTICES)
    return fail_at(r, n, KARST_ERANGE, "%s must have 3 to %d vertices, got %ld", path,
                   KARST_SCENARIO_PRISM_MAX_VERTICES, m);
  double *poly = malloc(sizeof(double) * 2 * (size_t)m);
  if (!poly) return no_memory(r);
  free(e->polygon);
  e->polygon = poly;
  e->n_vertices = (int)m;
  for (long i = 0; i < m; i++) {
    yaml_node_t *v = yaml_document_get_node(r->doc, n->data.sequence.items.start[i]);
    index_path(sub, path, i);
    karst_error_t err = get_vec(r, v, sub, 2, poly + 2 * i);
    if (err) return err;
  }
  /* A polygon of zero area would exclude nothing but its outline. */
  double area = 0;
  for (long i = 0, j = m - 1; i < m; j = i++)
    area += poly[2 * j] * poly[2 * i + 1] - poly[2 * i] * poly[2 * j + 1];
  if (!(fabs(area) > 0))
    return fail_at(r, n, KARST_EINVAL, "%s has zero area (its vertices are collinear)", path);
  return KARST_SUCCESS;
}
static const field_t exprism_fields[] = {
    {.key = "polygon", .type = T_FN, .fn = read_polygon, .required = 1},
    {.key = "bottom", .type = T_NUM, .off = offsetof(karst_exclusion_t, bottom), .required = 1},
    {.key = "top", .type = T_NUM, .off = offsetof(karst_exclusion_t, top), .required = 1},
};
static const schema_t exprism_schema = {exprism_fields, 3};

static karst_error_t read_ex_name(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  return read_name_into(r, n, ((karst_exclusion_t *)base)->name, path);
}
/* One exclusion: a name and exactly one of box, sphere, prism. */
static karst_error_t read_ex_shape(reader_t *r, yaml_node_t *n, void *base, const char *path,
                                   int kind) {
  karst_exclusion_t *e = base;
  static const schema_t *const schemas[3] = {&exbox_schema, &exsphere_schema, &exprism_schema};
  static const char *const names[3] = {"box", "sphere", "prism"};
  if (e->kind >= 0)
    return fail_at(r, n, KARST_EINVAL, "%s: an exclusion is one shape; this one is already a %s",
                   path, names[e->kind]);
  e->kind = kind;
  karst_error_t err = walk_map(r, n, schemas[kind], e, path, NULL);
  if (err) return err;
  if (kind == KARST_EXCLUSION_BOX)
    for (int a = 0; a < 3; a++)
      if (!(e->min[a] < e->max[a]))
        return fail_at(r, n, KARST_ERANGE, "%s: min[%d] (%g m) must be below max[%d] (%g m)", path,
                       a, e->min[a], a, e->max[a]);
  if (kind == KARST_EXCLUSION_PRISM && !(e->bottom < e->top))
    return fail_at(r, n, KARST_ERANGE, "%s: bottom (%g m) must be below top (%g m)", path,
                   e->bottom, e->top);
  return KARST_SUCCESS;
}
static karst_error_t read_ex_box(reader_t *r, yaml_node_t *n, void *b, const char *p) {
  return read_ex_shape(r, n, b, p, KARST_EXCLUSION_BOX);
}
static karst_error_t read_ex_sphere(reader_t *r, yaml_node_t *n, void *b, const char *p) {
  return read_ex_shape(r, n, b, p, KARST_EXCLUSION_SPHERE);
}
static karst_error_t read_ex_prism(reader_t *r, yaml_node_t *n, void *b, const char *p) {
  return read_ex_shape(r, n, b, p, KARST_EXCLUSION_PRISM);
}
static const field_t exclusion_fields[] = {
    {.key = "name", .type = T_FN, .fn = read_ex_name},
    {.key = "box", .type = T_FN, .fn = read_ex_box},
    {.key = "sphere", .type = T_FN, .fn = read_ex_sphere},
    {.key = "prism", .type = T_FN, .fn = read_ex_prism},
};
static const schema_t exclusion_schema = {exclusion_fields, 4};
static void init_exclusion(void *item) {
  ((karst_exclusion_t *)item)->kind = -1;
}
static karst_error_t read_exclusions(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_scenario_t *sc = base;
  karst_error_t err =
      read_list(r, n, path, sizeof(karst_exclusion_t), &exclusion_schema, init_exclusion,
                offsetof(karst_exclusion_t, line), offsetof(karst_exclusion_t, column),
                (void **)&sc->exclusions, &sc->n_exclusions);
  if (err) return err;
  for (int i = 0; i < sc->n_exclusions; i++)
    if (sc->exclusions[i].kind < 0) {
      char sub[PATH_LEN];
      index_path(sub, path, i);
      return karst_set_error(r->ctx, KARST_EINVAL, "%s:%d:%d: %s needs one of box, sphere, prism",
                             r->file, sc->exclusions[i].line, sc->exclusions[i].column, sub);
    }
  return KARST_SUCCESS;
}

/* --- faults ----------------------------------------------------------------- */

/* faults[i].radius: a finite radius > 0 (not given: an unbounded plane, stored as INFINITY). */
static karst_error_t read_fault_radius(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  static const range_t gt0 = RANGE_GT(0, " m");
  char d[80];
  double v = 0;
  karst_error_t err = get_number(r, n, path, &v);
  if (err) return err;
  if (!in_range(&gt0, v))
    return fail_at(r, n, KARST_ERANGE, "%s must be > 0 m, got %s", path, describe(n, d, sizeof d));
  ((karst_fault_t *)base)->radius = v;
  return KARST_SUCCESS;
}

static const char *const fault_kind_names[] = {"conduit", "barrier"};
static const field_t fault_fields[] = {
    {.key = "name", .type = T_FN, .fn = read_fault_name},
    {.key = "center", .type = T_VEC3, .off = offsetof(karst_fault_t, center), .required = 1},
    {.key = "dip_direction",
     .type = T_NUM,
     .off = offsetof(karst_fault_t, dip_direction),
     .range = RANGE_CLOSED_OPEN(0, 360, " degrees"),
     .required = 1},
    {.key = "dip",
     .type = T_NUM,
     .off = offsetof(karst_fault_t, dip),
     .range = RANGE_CLOSED(0, 90, " degrees"),
     .required = 1},
    {.key = "radius", .type = T_FN, .fn = read_fault_radius},
    {.key = "damage_zone",
     .type = T_NUM,
     .off = offsetof(karst_fault_t, damage_zone),
     .range = RANGE_GT(0, " m")},
    {.key = "kind",
     .type = T_ENUM,
     .off = offsetof(karst_fault_t, barrier),
     .names = fault_kind_names,
     .n_names = 2},
    {.key = "factor",
     .type = T_NUM,
     .off = offsetof(karst_fault_t, factor),
     .range = RANGE_OPEN_CLOSED(0, 1, "")},
    {.key = "crossing_cost",
     .type = T_NUM,
     .off = offsetof(karst_fault_t, crossing_cost),
     .range = RANGE_GE(0, "")},
};
static const schema_t fault_schema = {fault_fields, 9};
static void init_fault(void *item) {
  karst_fault_t *f = item;
  f->radius = INFINITY;
  f->damage_zone = 10.0;
  f->factor = 0.3;
  f->crossing_cost = 100.0;
}
static karst_error_t read_faults(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_scenario_t *sc = base;
  return read_list(r, n, path, sizeof(karst_fault_t), &fault_schema, init_fault,
                   offsetof(karst_fault_t, line), offsetof(karst_fault_t, column),
                   (void **)&sc->faults, &sc->n_faults);
}

/* --- connectivity --------------------------------------------------------- */

static karst_error_t defer_connectivity(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  (void)base;
  (void)path;
  r->connectivity = n;
  return KARST_SUCCESS;
}

static const field_t routing_fields[] = {
    {.key = "vadose_factor",
     .type = T_NUM,
     .off = offsetof(karst_routing_t, vadose_factor),
     .range = RANGE_GE(1, "")},
    {.key = "rise_cost",
     .type = T_NUM,
     .off = offsetof(karst_routing_t, rise_cost),
     .range = RANGE_GE(0, "")},
    {.key = "phreatic_depth",
     .type = T_NUM,
     .off = offsetof(karst_routing_t, phreatic_depth),
     .range = RANGE_GT(0, " m")},
    {.key = "water_table_band",
     .type = T_NUM,
     .off = offsetof(karst_routing_t, water_table_band),
     .range = RANGE_GE(0, " m")},
};
static const schema_t routing_schema = {routing_fields, 4};

/* classification.water_table_band moved to routing.water_table_band (the band is the routing's
 * epiphreatic zone, which the classification also uses): say so rather than "unknown key". */
static karst_error_t moved_water_table_band(reader_t *r, yaml_node_t *n, void *base,
                                            const char *path) {
  (void)base;
  return fail_at(r, n, KARST_EINVAL,
                 "%s is now routing.water_table_band (the epiphreatic band of the two-stage "
                 "routing, which the classification uses too); move it there",
                 path);
}

/* --- coordinates, conditioning and generations (docs/scenario.md) --------- */

/* key_points[i].station: the name of a surveyed station (conditioning), resolved in finish. */
static karst_error_t read_kp_station(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_keypoint_t *kp = base;
  const char *name = NULL;
  karst_error_t err = get_string(r, n, path, &name);
  if (err) return err;
  free(kp->station);
  if (!(kp->station = strdup(name))) return no_memory(r);
  return KARST_SUCCESS;
}

/* crs: the scenario's coordinate reference system, parsed at once so a mistake names its line. */
static karst_error_t read_crs(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_scenario_t *sc = base;
  const char *text = NULL;
  karst_error_t err = get_string(r, n, path, &text);
  if (err) return err;
  karst_crs_free(sc->crs_frame);
  sc->crs_frame = NULL;
  free(sc->crs);
  if (!(sc->crs = strdup(text))) return no_memory(r);
  karst_ctx_t c;
  karst_ctx_init(&c);
  if ((err = karst_crs_create(&c, text, &sc->crs_frame)))
    return fail_at(r, n, err, "%s: %s", path, c.errmsg);
  sc->pos_crs.line = line_of(n);
  sc->pos_crs.column = col_of(n);
  return KARST_SUCCESS;
}

static const field_t survey_fields[] = {
    {.key = "file", .type = T_STR, .off = offsetof(karst_survey_def_t, path), .required = 1},
    {.key = "crs", .type = T_STR, .off = offsetof(karst_survey_def_t, crs)},
};
static const schema_t survey_schema = {survey_fields, 2};

/* conditioning.surveys: a list of file names, or of {file, crs} maps. */
static karst_error_t read_surveys(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_conditioning_t *c = base;
  char d[80], sub[PATH_LEN];
  if (n->type != YAML_SEQUENCE_NODE)
    return fail_at(r, n, KARST_EINVAL, "%s must be a list of survey files, got %s", path,
                   describe(n, d, sizeof d));
  long m = n->data.sequence.items.top - n->data.sequence.items.start;
  if (m < 1 || m > 1000)
    return fail_at(r, n, KARST_ERANGE, "%s must name 1 to 1000 surveys, got %ld", path, m);
  for (int i = 0; i < c->n_surveys; i++)
    free(c->surveys[i].path), free(c->surveys[i].crs);
  free(c->surveys);
  c->n_surveys = 0;
  if (!(c->surveys = calloc((size_t)m, sizeof *c->surveys))) return no_memory(r);
  for (long i = 0; i < m; i++) {
    yaml_node_t *in = yaml_document_get_node(r->doc, n->data.sequence.items.start[i]);
    karst_survey_def_t *sd = &c->surveys[c->n_surveys++];
    index_path(sub, path, i);
    sd->line = line_of(in), sd->column = col_of(in);
    const char *name = NULL;
    karst_error_t err;
    if (in->type == YAML_MAPPING_NODE) {
      if ((err = walk_map(r, in, &survey_schema, sd, sub, NULL))) return err;
      name = sd->path;
    } else if ((err = get_string(r, in, sub, &name))) {
      return err;
    }
    char *resolved = resolve_relative(r, name, sub);
    if (!resolved) return no_memory(r);
    free(sd->path);
    sd->path = resolved;
  }
  c->line = line_of(n), c->column = col_of(n);
  return KARST_SUCCESS;
}

/* conditioning.sinks: entrances, none, or a list of station names. */
static karst_error_t read_cond_sinks(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_conditioning_t *c = base;
  char d[80], sub[PATH_LEN];
  for (int i = 0; i < c->n_sink_stations; i++)
    free(c->sink_stations[i]);
  free(c->sink_stations);
  c->sink_stations = NULL;
  c->n_sink_stations = 0;
  if (n->type == YAML_SCALAR_NODE) {
    static const char *const modes[] = {"none", "entrances"};
    int v = 0;
    karst_error_t err = get_enum(r, n, path, modes, 2, &v);
    if (err) return err;
    c->sinks = v ? KARST_CONDITIONING_SINKS_ENTRANCES : KARST_CONDITIONING_SINKS_NONE;
    return KARST_SUCCESS;
  }
  if (n->type != YAML_SEQUENCE_NODE)
    return fail_at(r, n, KARST_EINVAL,
                   "%s must be 'entrances', 'none' or a list of station names, got %s", path,
                   describe(n, d, sizeof d));
  long m = n->data.sequence.items.top - n->data.sequence.items.start;
  if (m > 10000)
    return fail_at(r, n, KARST_ERANGE, "%s names %ld stations, at most 10000", path, m);
  if (m > 0 && !(c->sink_stations = calloc((size_t)m, sizeof *c->sink_stations)))
    return no_memory(r);
  for (long i = 0; i < m; i++) {
    yaml_node_t *in = yaml_document_get_node(r->doc, n->data.sequence.items.start[i]);
    const char *name;
    index_path(sub, path, i);
    karst_error_t err = get_string(r, in, sub, &name);
    if (err) return err;
    if (!(c->sink_stations[c->n_sink_stations++] = strdup(name))) return no_memory(r);
  }
  c->sinks = KARST_CONDITIONING_SINKS_LIST;
  return KARST_SUCCESS;
}

static const field_t conditioning_fields[] = {
    {.key = "surveys", .type = T_FN, .fn = read_surveys, .required = 1},
    {.key = "cost_factor",
     .type = T_NUM,
     .off = offsetof(karst_conditioning_t, cost_factor),
     .range = RANGE_OPEN_CLOSED(0, 1, "")},
    {.key = "sinks", .type = T_FN, .fn = read_cond_sinks},
    {.key = "generation",
     .type = T_INT,
     .off = offsetof(karst_conditioning_t, generation),
     .range = RANGE_GE(0, " (0: the last generation)")},
};
static const schema_t conditioning_schema = {conditioning_fields, 4};

static karst_error_t defer_generations(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  (void)base;
  (void)path;
  r->generations = n;
  return KARST_SUCCESS;
}

static karst_error_t read_gen_name(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  return read_name_into(r, n, ((karst_generation_t *)base)->name, path);
}
static karst_error_t read_gen_water_table(reader_t *r, yaml_node_t *n, void *base,
                                          const char *path) {
  return read_surface_def(r, n, &((karst_generation_t *)base)->water_table, path);
}

/* generations[i].key_points: appended to the scenario's key points, tagged with the generation. */
static karst_error_t read_gen_key_points(reader_t *r, yaml_node_t *n, void *base,
                                         const char *path) {
  (void)base;
  karst_scenario_t *sc = r->sc;
  char d[80], sub[PATH_LEN];
  if (is_null(n)) return KARST_SUCCESS;
  if (n->type != YAML_SEQUENCE_NODE)
    return fail_at(r, n, KARST_EINVAL, "%s must be a list of maps, got %s", path,
                   describe(n, d, sizeof d));
  long m = n->data.sequence.items.top - n->data.sequence.items.start;
  if (m > INT_MAX / 4 - sc->n_key_points)
    return fail_at(r, n, KARST_ERANGE, "%s has too many items (%ld)", path, m);
  for (long i = 0; i < m; i++) {
    yaml_node_t *in = yaml_document_get_node(r->doc, n->data.sequence.items.start[i]);
    karst_keypoint_t *kps = realloc(sc->key_points, (size_t)(sc->n_key_points + 1) * sizeof *kps);
    if (!kps) return no_memory(r);
    sc->key_points = kps;
    karst_keypoint_t *kp = &kps[sc->n_key_points++];
    memset(kp, 0, sizeof *kp);
    init_keypoint(kp);
    kp->line = line_of(in), kp->column = col_of(in);
    kp->generation = r->generation;
    index_path(sub, path, i);
    karst_error_t err = walk_map(r, in, &keypoint_schema, kp, sub, NULL);
    if (err) return err;
  }
  return KARST_SUCCESS;
}

static const field_t gen_skeleton_fields[] = {
    {.key = "gamma",
     .type = T_NUM,
     .off = offsetof(karst_generation_t, gamma),
     .range = RANGE_GT(0, "")},
    {.key = "reuse",
     .type = T_NUM,
     .off = offsetof(karst_generation_t, reuse),
     .range = RANGE_OPEN_CLOSED(0, 1, "")},
};
static const schema_t gen_skeleton_schema = {gen_skeleton_fields, 2};
static const schema_t amplification_schema; /* defined with the top-level tables below */
static const field_t generation_fields[] = {
    {.key = "name", .type = T_FN, .fn = read_gen_name},
    {.key = "water_table", .type = T_FN, .fn = read_gen_water_table},
    {.key = "key_points", .type = T_FN, .fn = read_gen_key_points},
    {.key = "routing",
     .type = T_MAP,
     .off = offsetof(karst_generation_t, routing),
     .sub = &routing_schema},
    {.key = "skeleton", .type = T_MAP, .sub = &gen_skeleton_schema},
    {.key = "amplification",
     .type = T_MAP,
     .off = offsetof(karst_generation_t, amplification),
     .sub = &amplification_schema},
    {.key = "cohesion",
     .type = T_NUM,
     .off = offsetof(karst_generation_t, cohesion),
     .range = RANGE_OPEN_CLOSED(0, 1, "")},
};
static const schema_t generation_schema = {generation_fields, 7};

/* generations: oldest first; each starts from the top-level routing, skeleton and amplification
 * values, which must therefore be read first (finish). */
static karst_error_t read_generations(reader_t *r, yaml_node_t *n) {
  karst_scenario_t *sc = r->sc;
  char d[80], sub[PATH_LEN];
  const char *path = "generations";
  if (is_null(n)) return KARST_SUCCESS;
  if (n->type != YAML_SEQUENCE_NODE)
    return fail_at(r, n, KARST_EINVAL, "%s must be a list of maps (oldest first), got %s", path,
                   describe(n, d, sizeof d));
  long m = n->data.sequence.items.top - n->data.sequence.items.start;
  if (m < 1 || m > KARST_SCENARIO_MAX_GENERATIONS)
    return fail_at(r, n, KARST_ERANGE, "%s must list 1 to %d generations, got %ld", path,
                   KARST_SCENARIO_MAX_GENERATIONS, m);
  if (!(sc->generations = calloc((size_t)m, sizeof *sc->generations))) return no_memory(r);
  for (long i = 0; i < m; i++) {
    yaml_node_t *in = yaml_document_get_node(r->doc, n->data.sequence.items.start[i]);
    karst_generation_t *G = &sc->generations[sc->n_generations++];
    G->routing = sc->routing;
    G->gamma = sc->gamma;
    G->reuse = sc->reuse;
    G->amplification = sc->amplification;
    G->cohesion = KARST_SCENARIO_DEFAULT_COHESION;
    G->line = line_of(in), G->column = col_of(in);
    snprintf(G->name, sizeof G->name, "generation%ld", i + 1);
    index_path(sub, path, i);
    r->generation = (int)i + 1;
    karst_error_t err = walk_map(r, in, &generation_schema, G, sub, NULL);
    r->generation = 0;
    if (err) return err;
  }
  return KARST_SUCCESS;
}

/* A key point placed by the conditioning (an entrance sink, a survey piece's waypoint). */
static karst_error_t add_station_key_point(reader_t *r, karst_int_t st, karst_keypoint_type_t type,
                                           const char *name, int gen) {
  karst_scenario_t *sc = r->sc;
  const karst_survey_set_t *s = sc->conditioning.data;
  karst_keypoint_t *kps = realloc(sc->key_points, (size_t)(sc->n_key_points + 1) * sizeof *kps);
  if (!kps) return no_memory(r);
  sc->key_points = kps;
  karst_keypoint_t *kp = &kps[sc->n_key_points++];
  memset(kp, 0, sizeof *kp);
  init_keypoint(kp);
  kp->type = type;
  kp->generation = gen;
  kp->line = sc->conditioning.line, kp->column = sc->conditioning.column;
  memcpy(kp->p, &s->xyz[3 * st], sizeof kp->p);
  kp->station_index = st;
  /* Named after its station when the name fits, so the network's node label stays the
   * station's name; otherwise the description (entrance 1, survey piece 2 ...). */
  const char *label = s->labels[st];
  snprintf(kp->name, sizeof kp->name, "%s",
           label && label[0] && strlen(label) < sizeof kp->name ? label : name);
  if (!(kp->station = strdup(label ? label : name))) return no_memory(r);
  return KARST_SUCCESS;
}

/* A key point is on the survey when it names a station or sits exactly on one. */
static karst_int_t station_of_key_point(const karst_survey_set_t *s, const karst_keypoint_t *kp) {
  if (kp->station) return kp->station_index;
  for (karst_int_t i = 0; i < s->n_stations; i++)
    if (s->xyz[3 * i] == kp->p[0] && s->xyz[3 * i + 1] == kp->p[1] && s->xyz[3 * i + 2] == kp->p[2])
      return i;
  return -1;
}

/* After the walk: positions from latitude/longitude and from stations, the surveys read into the
 * scenario's frame, the key points the conditioning adds. */
static karst_error_t finish_frame(reader_t *r) {
  karst_scenario_t *sc = r->sc;
  karst_conditioning_t *c = &sc->conditioning;
  karst_error_t err;
  if (c->generation > 0 && c->generation > (sc->n_generations > 0 ? sc->n_generations : 1))
    return karst_set_error(r->ctx, KARST_ERANGE,
                           "%s:%d:%d: conditioning.generation is %d but the scenario has %d "
                           "generation%s",
                           r->file, c->line, c->column, c->generation,
                           sc->n_generations > 0 ? sc->n_generations : 1,
                           sc->n_generations > 1 ? "s" : "");
  if (c->n_surveys > 0 && (err = karst_conditioning_load(r->ctx, sc))) return err;
  const karst_survey_set_t *s = c->data;
  const int cgen =
      sc->n_generations > 0 ? (c->generation > 0 ? c->generation : sc->n_generations) : 0;
  for (int i = 0; i < sc->n_key_points; i++) {
    karst_keypoint_t *kp = &sc->key_points[i];
    int has_pos = !isnan(kp->p[0]) || !isnan(kp->p[1]) || !isnan(kp->p[2]);
    int has_geo =
        !isnan(kp->geographic[0]) || !isnan(kp->geographic[1]) || !isnan(kp->geographic[2]);
    int forms = has_pos + has_geo + (kp->station != NULL);
    char kpath[PATH_LEN];
    index_path(kpath, "key_points", i);
    if (forms != 1)
      return karst_set_error(r->ctx, KARST_EINVAL,
                             "%s:%d:%d: %s%s%s needs exactly one of position: [x, y, z], "
                             "latitude/longitude/elevation, or station: NAME; it gives %d",
                             r->file, kp->line, kp->column, kpath, kp->name[0] ? " " : "", kp->name,
                             forms);
    if (has_geo) {
      if (isnan(kp->geographic[0]) || isnan(kp->geographic[1]) || isnan(kp->geographic[2]))
        return karst_set_error(r->ctx, KARST_EINVAL,
                               "%s:%d:%d: %s needs all of latitude, longitude and elevation",
                               r->file, kp->line, kp->column, kpath);
      if (!sc->crs_frame)
        return karst_set_error(r->ctx, KARST_EINVAL,
                               "%s:%d:%d: %s is given in latitude/longitude but the scenario "
                               "states no crs to convert it into (crs: 'UTM 30N', 'EPSG:27700' "
                               "...)",
                               r->file, kp->line, kp->column, kpath);
      double ll[2] = {kp->geographic[1], kp->geographic[0]};
      if ((err = karst_crs_from_lonlat(r->ctx, sc->crs_frame, 1, ll, kp->p))) {
        size_t len = strlen(r->ctx->errmsg);
        snprintf(r->ctx->errmsg + len, KARST_ERRMSG_MAX - len, " (%s:%d:%d: %s)", r->file, kp->line,
                 kp->column, kpath);
        return err;
      }
      kp->p[2] = kp->geographic[2];
    }
    if (kp->station) {
      karst_int_t st = s ? karst_survey_find_station(s, kp->station) : -1;
      if (st < 0)
        return karst_set_error(r->ctx, KARST_ENOTFOUND, "%s:%d:%d: %s names station '%s', which %s",
                               r->file, kp->line, kp->column, kpath, kp->station,
                               s ? "no survey of conditioning.surveys has"
                                 : "needs a conditioning section with the survey");
      kp->station_index = st;
      memcpy(kp->p, &s->xyz[3 * st], sizeof kp->p);
    }
  }
  if (!s) return KARST_SUCCESS;
  /* Entrance sinks. */
  if (c->sinks == KARST_CONDITIONING_SINKS_ENTRANCES) {
    int found = 0;
    for (karst_int_t i = 0; i < s->n_stations; i++) {
      if (!s->entrance[i]) continue;
      found++;
      int taken = 0;
      for (int k = 0; k < sc->n_key_points && !taken; k++)
        taken = station_of_key_point(s, &sc->key_points[k]) == i;
      if (taken) continue;
      char name[KARST_SCENARIO_NAME_MAX];
      snprintf(name, sizeof name, "entrance %d", found);
      if ((err = add_station_key_point(r, i, KARST_KEYPOINT_SINK, name, cgen))) return err;
    }
    if (!found)
      return karst_set_error(r->ctx, KARST_EINVAL,
                             "%s:%d:%d: conditioning.sinks is 'entrances' but no survey flags an "
                             "entrance (Survex *entrance); name the stations instead",
                             r->file, c->line, c->column);
  } else if (c->sinks == KARST_CONDITIONING_SINKS_LIST) {
    for (int j = 0; j < c->n_sink_stations; j++) {
      karst_int_t st = karst_survey_find_station(s, c->sink_stations[j]);
      if (st < 0)
        return karst_set_error(r->ctx, KARST_ENOTFOUND,
                               "%s:%d:%d: conditioning.sinks[%d] names station '%s', which no "
                               "survey has",
                               r->file, c->line, c->column, j, c->sink_stations[j]);
      char name[KARST_SCENARIO_NAME_MAX];
      snprintf(name, sizeof name, "sink at %.50s", c->sink_stations[j]);
      if ((err = add_station_key_point(r, st, KARST_KEYPOINT_SINK, name, cgen))) return err;
    }
  }
  /* Every piece of the survey that no key point sits on gets a waypoint at its lowest station,
   * so the routing joins it to the simulated network. */
  unsigned char *covered = calloc((size_t)(s->n_components > 0 ? s->n_components : 1), 1);
  if (!covered) return no_memory(r);
  for (int k = 0; k < sc->n_key_points; k++) {
    karst_int_t st = station_of_key_point(s, &sc->key_points[k]);
    if (st >= 0) {
      sc->key_points[k].station_index = st;
      covered[s->component[st]] = 1;
    }
  }
  for (karst_int_t cc = 0; cc < s->n_components && !err; cc++) {
    if (covered[cc]) continue;
    char name[KARST_SCENARIO_NAME_MAX];
    snprintf(name, sizeof name, "survey piece %lld", (long long)cc + 1);
    err = add_station_key_point(r, s->component_station[cc], KARST_KEYPOINT_WAYPOINT, name, cgen);
  }
  free(covered);
  return err;
}

/* --- the top level --------------------------------------------------------- */

static const field_t domain_fields[] = {
    {.key = "min", .type = T_VEC3, .off = offsetof(karst_scenario_t, domain_min), .required = 1},
    {.key = "max", .type = T_VEC3, .off = offsetof(karst_scenario_t, domain_max), .required = 1},
};
static const schema_t domain_schema = {domain_fields, 2};

static const field_t permeability_fields[] = {
    {.key = "background",
     .type = T_NUM,
     .off = offsetof(karst_permeability_t, background),
     .range = RANGE_CLOSED(0, 1, "")},
    {.key = "tree", .type = T_FN, .fn = read_perm_tree},
    {.key = "primitives", .type = T_FN, .fn = read_perm_primitives},
};
static const schema_t permeability_schema = {permeability_fields, 3};

/* Indexed by karst_fracture_combine_t. */
static const char *const fracture_combine_names[] = {"sum", "min"};

static const field_t cost_fields[] = {
    {.key = "w0",
     .type = T_NUM,
     .off = offsetof(karst_cost_weights_t, w0),
     .range = RANGE_GT(0, "")},
    {.key = "horizon",
     .type = T_NUM,
     .off = offsetof(karst_cost_weights_t, horizon),
     .range = RANGE_GE(0, "")},
    {.key = "fracture",
     .type = T_NUM,
     .off = offsetof(karst_cost_weights_t, fracture),
     .range = RANGE_GE(0, "")},
    {.key = "permeability",
     .type = T_NUM,
     .off = offsetof(karst_cost_weights_t, permeability),
     .range = RANGE_GE(0, "")},
    {.key = "prescribed",
     .type = T_NUM,
     .off = offsetof(karst_cost_weights_t, prescribed),
     .range = RANGE_OPEN_CLOSED(0, 1, "")},
    {.key = "fracture_combine",
     .type = T_ENUM,
     .off = offsetof(karst_cost_weights_t, fracture_combine),
     .names = fracture_combine_names,
     .n_names = 2},
};
static const schema_t cost_schema = {cost_fields, 6};

/* Indexed by karst_knn_method_t. */
static const char *const knn_method_names[] = {"grid", "flann"};

/* sampling.points: a point cloud file (relative to the scenario) read now, so that every
 * realisation of an ensemble shares it; a failure gives the file's FILE:LINE:COLUMN message
 * followed by the key and its position in the scenario. */
static karst_error_t read_points_file(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_sampling_t *sp = base;
  const char *name;
  karst_error_t err = get_string(r, n, path, &name);
  if (err) return err;
  free(sp->points), free(sp->points_xyz);
  sp->points = NULL, sp->points_xyz = NULL, sp->n_points = 0;
  if (!(sp->points = resolve_relative(r, name, path))) return no_memory(r);
  err = karst_points_load(r->ctx, sp->points, &sp->points_xyz, &sp->n_points, NULL);
  if (err) {
    size_t len = strlen(r->ctx->errmsg);
    snprintf(r->ctx->errmsg + len, KARST_ERRMSG_MAX - len, " (the points of %s at %s:%d:%d)", path,
             r->file, line_of(n), col_of(n));
  }
  return err;
}

/* sampling.refine: the names of the features sampled at feature_radius, each bit i of
 * karst_refine_t named refine_names[i]; [] for none. */
static const char *const refine_names[] = {"horizons", "water_table", "permeability"};

char *karst_refine_names(unsigned refine, const char *sep, char *buf, size_t size) {
  size_t len = 0;
  if (size == 0) return buf;
  buf[0] = '\0';
  for (int i = 0; i < 3; i++)
    if (refine & (1u << i)) {
      int w = snprintf(buf + len, size - len, "%s%s", len ? sep : "", refine_names[i]);
      if (w < 0 || (size_t)w >= size - len) break;
      len += (size_t)w;
    }
  return buf;
}

static karst_error_t read_refine(reader_t *r, yaml_node_t *n, void *base, const char *path) {
  karst_sampling_t *sp = base;
  char d[80], sub[PATH_LEN];
  if (n->type != YAML_SEQUENCE_NODE)
    return fail_at(r, n, KARST_EINVAL,
                   "%s must be a list of the names horizons, water_table, permeability "
                   "([] for none), got %s",
                   path, describe(n, d, sizeof d));
  unsigned mask = 0;
  long m = n->data.sequence.items.top - n->data.sequence.items.start;
  for (long i = 0; i < m; i++) {
    yaml_node_t *it = yaml_document_get_node(r->doc, n->data.sequence.items.start[i]);
    int v = 0;
    index_path(sub, path, i);
    karst_error_t err = get_enum(r, it, sub, refine_names, 3, &v);
    if (err) return err;
    if (mask & (1u << v))
      return fail_at(r, it, KARST_EINVAL, "%s: '%s' is listed twice", sub, refine_names[v]);
    mask |= 1u << v;
  }
  sp->refine = mask;
  return KARST_SUCCESS;
}

static const field_t sampling_fields[] = {
    {.key = "fill_radius",
     .type = T_NUM,
     .off = offsetof(karst_sampling_t, fill_radius),
     .range = RANGE_GT(0, " m"),
     .pos = offsetof(karst_scenario_t, pos_fill_radius)},
    {.key = "feature_radius",
     .type = T_NUM,
     .off = offsetof(karst_sampling_t, feature_radius),
     .range = RANGE_GT(0, " m"),
     .pos = offsetof(karst_scenario_t, pos_feature_radius)},
    {.key = "permeable_threshold",
     .type = T_NUM,
     .off = offsetof(karst_sampling_t, permeable_threshold),
     .range = RANGE_CLOSED(0, 1, "")},
    {.key = "feature_band",
     .type = T_NUM,
     .off = offsetof(karst_sampling_t, feature_band),
     .range = RANGE_GE(0, " m")},
    {.key = "k",
     .type = T_INT,
     .off = offsetof(karst_sampling_t, k),
     .range = RANGE_GE(1, ""),
     .pos = offsetof(karst_scenario_t, pos_k)},
    {.key = "max_samples",
     .type = T_I64,
     .off = offsetof(karst_sampling_t, max_samples),
     .range = RANGE_GE(1, ""),
     .pos = offsetof(karst_scenario_t, pos_max_samples)},
    {.key = "knn",
     .type = T_ENUM,
     .off = offsetof(karst_sampling_t, knn),
     .names = knn_method_names,
     .n_names = 2},
    {.key = "points",
     .type = T_FN,
     .fn = read_points_file,
     .pos = offsetof(karst_scenario_t, pos_points)},
    {.key = "refine", .type = T_FN, .fn = read_refine},
};
static const schema_t sampling_schema = {sampling_fields, 9};

static const field_t skeleton_fields[] = {
    {.key = "gamma",
     .type = T_NUM,
     .off = offsetof(karst_scenario_t, gamma),
     .range = RANGE_GT(0, "")},
    {.key = "reuse",
     .type = T_NUM,
     .off = offsetof(karst_scenario_t, reuse),
     .range = RANGE_OPEN_CLOSED(0, 1, "")},
};
static const schema_t skeleton_schema = {skeleton_fields, 2};

/* Indexed by karst_amplification_anchor_t. */
static const char *const amplification_anchor_names[] = {"previous", "network"};

static const field_t amplification_fields[] = {
    {.key = "steps",
     .type = T_INT,
     .off = offsetof(karst_amplification_t, steps),
     .range = RANGE_GE(0, ""),
     .pos = offsetof(karst_scenario_t, pos_amplification_steps)},
    {.key = "points",
     .type = T_INT,
     .off = offsetof(karst_amplification_t, points),
     .range = RANGE_GE(0, ""),
     .pos = offsetof(karst_scenario_t, pos_amplification_points)},
    {.key = "dead_end_fraction",
     .type = T_NUM,
     .off = offsetof(karst_amplification_t, dead_end_fraction),
     .range = RANGE_CLOSED(0, 1, "")},
    {.key = "reach",
     .type = T_NUM,
     .off = offsetof(karst_amplification_t, reach),
     .range = RANGE_GE(0, " m")},
    {.key = "reach_ratio",
     .type = T_NUM,
     .off = offsetof(karst_amplification_t, reach_ratio),
     .range = RANGE_OPEN_CLOSED(0, 1, "")},
    {.key = "points_ratio",
     .type = T_NUM,
     .off = offsetof(karst_amplification_t, points_ratio),
     .range = RANGE_GT(0, "")},
    {.key = "anchor",
     .type = T_ENUM,
     .off = offsetof(karst_amplification_t, anchor),
     .names = amplification_anchor_names,
     .n_names = 2},
};
static const schema_t amplification_schema = {amplification_fields, 7};

static const field_t classification_fields[] = {
    {.key = "vertical_angle",
     .type = T_NUM,
     .off = offsetof(karst_classification_t, vertical_angle),
     .range = RANGE_CLOSED(0, 90, " degrees")},
    {.key = "epikarst_depth",
     .type = T_NUM,
     .off = offsetof(karst_classification_t, epikarst_depth),
     .range = RANGE_GE(0, " m")},
    {.key = "chamber_resistance",
     .type = T_NUM,
     .off = offsetof(karst_classification_t, chamber_resistance),
     .range = RANGE_CLOSED(0, 1, "")},
    {.key = "radius_correlation",
     .type = T_NUM,
     .off = offsetof(karst_classification_t, radius_correlation),
     .range = RANGE_GE(0, " m")},
    {.key = "radius", .type = T_FN, .fn = read_radius},
    {.key = "water_table_band", .type = T_FN, .fn = moved_water_table_band},
};
static const schema_t classification_schema = {classification_fields, 6};

static const field_t random_fields[] = {
    {.key = "seed", .type = T_U64, .off = offsetof(karst_scenario_t, seed)},
    {.key = "realisations",
     .type = T_INT,
     .off = offsetof(karst_scenario_t, realisations),
     .range = RANGE_GE(1, "")},
};
static const schema_t random_schema = {random_fields, 2};

#include "scenario/scenario_blocks.inc"

static const field_t top_fields[] = {
    {.key = "name", .type = T_STR, .off = offsetof(karst_scenario_t, name)},
    {.key = "units", .type = T_FN, .fn = read_units},
    {.key = "domain",
     .type = T_MAP,
     .sub = &domain_schema,
     .pos = offsetof(karst_scenario_t, pos_domain)},
    {.key = "terrain", .type = T_FN, .fn = read_terrain},
    {.key = "water_table", .type = T_FN, .fn = read_water_table},
    {.key = "strata", .type = T_FN, .fn = read_strata},
    {.key = "exclusions", .type = T_FN, .fn = read_exclusions},
    {.key = "faults", .type = T_FN, .fn = read_faults},
    {.key = "connectivity", .type = T_FN, .fn = defer_connectivity},
    {.key = "routing",
     .type = T_MAP,
     .off = offsetof(karst_scenario_t, routing),
     .sub = &routing_schema},
    {.key = "horizons", .type = T_FN, .fn = read_horizons},
    {.key = "fractures", .type = T_FN, .fn = read_fractures},
    {.key = "permeability",
     .type = T_MAP,
     .off = offsetof(karst_scenario_t, permeability),
     .sub = &permeability_schema},
    {.key = "key_points",
     .type = T_FN,
     .fn = read_key_points,
     .pos = offsetof(karst_scenario_t, pos_key_points)},
    {.key = "prescribed_paths", .type = T_FN, .fn = defer_prescribed},
    {.key = "cost", .type = T_MAP, .off = offsetof(karst_scenario_t, cost), .sub = &cost_schema},
    {.key = "sampling",
     .type = T_MAP,
     .off = offsetof(karst_scenario_t, sampling),
     .sub = &sampling_schema,
     .pos = offsetof(karst_scenario_t, pos_sampling)},
    {.key = "skeleton", .type = T_MAP, .sub = &skeleton_schema},
    {.key = "amplification",
     .type = T_MAP,
     .off = offsetof(karst_scenario_t, amplification),
     .sub = &amplification_schema,
     .pos = offsetof(karst_scenario_t, pos_amplification)},
    {.key = "tortuosity",
     .type = T_NUM,
     .off = offsetof(karst_scenario_t, tortuosity),
     .range = RANGE_CLOSED(0, 1, "")},
    {.key = "classification",
     .type = T_MAP,
     .off = offsetof(karst_scenario_t, classification),
     .sub = &classification_schema},
    {.key = "random", .type = T_MAP, .sub = &random_schema},
    {.key = "geometry",
     .type = T_MAP,
     .off = offsetof(karst_scenario_t, geometry),
     .sub = &geometry_schema},
    {.key = "blocks", .type = T_FN, .fn = read_blocks},
    {.key = "crs", .type = T_FN, .fn = read_crs},
    {.key = "conditioning",
     .type = T_MAP,
     .off = offsetof(karst_scenario_t, conditioning),
     .sub = &conditioning_schema},
    {.key = "generations", .type = T_FN, .fn = defer_generations},
};
static const schema_t top_schema = {top_fields, 27};
_Static_assert(sizeof top_fields / sizeof top_fields[0] <= MAX_FIELDS, "raise MAX_FIELDS");

/* ------------------------------------------------------------------------ */
/* After the walk: defaults that depend on other keys, names, paths          */
/* ------------------------------------------------------------------------ */

static int find_key_point(const karst_scenario_t *sc, const char *name) {
  for (int i = 0; i < sc->n_key_points; i++)
    if (!strcmp(sc->key_points[i].name, name)) return i;
  return -1;
}

/* prescribed_paths: [[from, to], ...] naming key points. */
static karst_error_t read_prescribed(reader_t *r, yaml_node_t *n) {
  karst_scenario_t *sc = r->sc;
  char d[80], sub[PATH_LEN], nm[64];
  const char *path = "prescribed_paths";
  if (is_null(n)) return KARST_SUCCESS;
  if (n->type != YAML_SEQUENCE_NODE)
    return fail_at(r, n, KARST_EINVAL,
                   "%s must be a list of pairs [from, to] of key-point names, got %s", path,
                   describe(n, d, sizeof d));
  long m = n->data.sequence.items.top - n->data.sequence.items.start;
  if (m == 0) return KARST_SUCCESS;
  if (m > INT_MAX / 2) return fail_at(r, n, KARST_ERANGE, "%s has too many items", path);
  sc->prescribed = calloc((size_t)m, sizeof *sc->prescribed);
  if (!sc->prescribed) return no_memory(r);
  sc->n_prescribed = (int)m;
  const char **names = malloc(sizeof(char *) * (sc->n_key_points > 0 ? sc->n_key_points : 1));
  if (!names) return no_memory(r);
  for (int i = 0; i < sc->n_key_points; i++)
    names[i] = sc->key_points[i].name;
  karst_error_t err = KARST_SUCCESS;
  for (long i = 0; i < m && !err; i++) {
    yaml_node_t *it = yaml_document_get_node(r->doc, n->data.sequence.items.start[i]);
    karst_prescribed_path_t *pp = &sc->prescribed[i];
    index_path(sub, path, i);
    pp->line = line_of(it);
    pp->column = col_of(it);
    if (it->type != YAML_SEQUENCE_NODE ||
        it->data.sequence.items.top - it->data.sequence.items.start != 2) {
      err = fail_at(r, it, KARST_EINVAL, "%s must be a pair [from, to] of key-point names, got %s",
                    sub, describe(it, d, sizeof d));
      break;
    }
    int ends[2];
    for (int e = 0; e < 2 && !err; e++) {
      yaml_node_t *v = yaml_document_get_node(r->doc, it->data.sequence.items.start[e]);
      char esub[PATH_LEN];
      const char *name = NULL;
      index_path(esub, sub, e);
      if ((err = get_string(r, v, esub, &name))) break;
      ends[e] = find_key_point(sc, name);
      if (ends[e] < 0) {
        const char *hint = karst_i_suggest(name, names, sc->n_key_points);
        clip(name, strlen(name), nm, sizeof nm);
        err = fail_at(r, v, KARST_ENOTFOUND, "%s names an unknown key point '%s'%s%s%s", esub, nm,
                      hint ? " (did you mean '" : "", hint ? hint : "", hint ? "'?)" : "");
      }
    }
    if (err) break;
    if (ends[0] == ends[1]) {
      err = fail_at(r, it, KARST_EINVAL, "%s joins key point '%s' to itself", sub,
                    sc->key_points[ends[0]].name);
      break;
    }
    pp->a = ends[0];
    pp->b = ends[1];
  }
  free(names);
  return err;
}

/* Key points by name, ties by position in the list (qsort is not stable). */
static int cmp_kp_name(const void *a, const void *b) {
  const karst_keypoint_t *x = *(const karst_keypoint_t *const *)a;
  const karst_keypoint_t *y = *(const karst_keypoint_t *const *)b;
  int c = strcmp(x->name, y->name);
  return c ? c : (x < y ? -1 : x > y);
}
static int cmp_name_kp(const void *key, const void *elem) {
  return strcmp((const char *)key, (*(const karst_keypoint_t *const *)elem)->name);
}

/* The named key points sorted by name (caller frees); NULL when out of memory. */
static const karst_keypoint_t **sorted_named(const karst_scenario_t *sc, int *m) {
  size_t n = sc->n_key_points > 0 ? (size_t)sc->n_key_points : 1;
  const karst_keypoint_t **v = malloc(sizeof *v * n);
  if (!v) return NULL;
  *m = 0;
  for (int i = 0; i < sc->n_key_points; i++)
    if (sc->key_points[i].name[0]) v[(*m)++] = &sc->key_points[i];
  qsort(v, (size_t)*m, sizeof *v, cmp_kp_name);
  return v;
}

/* The first key point, in list order, whose name an earlier one already has:
 * sets *dup and *first (the earlier holder), or *dup = -1. O(n log n). */
static void first_duplicate(const karst_scenario_t *sc, const karst_keypoint_t **v, int m, int *dup,
                            int *first) {
  *dup = -1;
  *first = -1;
  int group = 0;
  for (int k = 1; k < m; k++) {
    if (strcmp(v[k]->name, v[k - 1]->name) != 0) {
      group = k;
      continue;
    }
    int idx = (int)(v[k] - sc->key_points);
    if (*dup < 0 || idx < *dup) {
      *dup = idx;
      *first = (int)(v[group] - sc->key_points);
    }
  }
}

/* Names given in the file must be unique; the others become sink1, spring1,
 * waypoint3 ... (the ordinal among key points of that type), the number
 * increased past names given in the file. Generated numbers only grow within
 * a type, so generated names cannot collide with each other. O(n log n). */
static karst_error_t name_key_points(reader_t *r) {
  karst_scenario_t *sc = r->sc;
  int m = 0, dup, first;
  const karst_keypoint_t **v = sorted_named(sc, &m);
  if (!v) return no_memory(r);
  first_duplicate(sc, v, m, &dup, &first);
  if (dup >= 0) {
    const karst_keypoint_t *kp = &sc->key_points[dup];
    free(v);
    return karst_set_error(r->ctx, KARST_EINVAL,
                           "%s:%d:%d: key_points[%d].name '%s' is already used by key_points[%d] "
                           "(line %d); names must be unique",
                           r->file, kp->line, kp->column, dup, kp->name, first,
                           sc->key_points[first].line);
  }
  int ordinal[3] = {0, 0, 0}, last[3] = {0, 0, 0};
  char name[sizeof sc->key_points[0].name];
  for (int i = 0; i < sc->n_key_points; i++) {
    karst_keypoint_t *kp = &sc->key_points[i];
    int t = (int)kp->type;
    int k = ++ordinal[t];
    if (kp->name[0]) continue;
    if (k <= last[t]) k = last[t] + 1;
    for (;; k++) {
      snprintf(name, sizeof name, "%s%d", keypoint_type_names[t], k);
      if (!bsearch(name, v, (size_t)m, sizeof *v, cmp_name_kp)) break;
    }
    last[t] = k;
    memcpy(kp->name, name, sizeof name);
  }
  free(v);
  return KARST_SUCCESS;
}

/* Index of the key point named @p name among those of @p type, or fail with a did-you-mean. */
static karst_error_t key_of_type(reader_t *r, yaml_node_t *v, const char *path,
                                 karst_keypoint_type_t type, int *out) {
  karst_scenario_t *sc = r->sc;
  const char *name;
  char nm[64];
  karst_error_t err = get_string(r, v, path, &name);
  if (err) return err;
  int k = find_key_point(sc, name);
  if (k >= 0 && sc->key_points[k].type == type) {
    *out = k;
    return KARST_SUCCESS;
  }
  clip(name, strlen(name), nm, sizeof nm);
  if (k >= 0)
    return fail_at(r, v, KARST_EINVAL, "%s names key point '%s', which is a %s, not a %s", path, nm,
                   keypoint_type_names[sc->key_points[k].type], keypoint_type_names[type]);
  const char **names = malloc(sizeof(char *) * (sc->n_key_points > 0 ? sc->n_key_points : 1));
  if (!names) return no_memory(r);
  int m = 0;
  for (int i = 0; i < sc->n_key_points; i++)
    if (sc->key_points[i].type == type) names[m++] = sc->key_points[i].name;
  const char *hint = karst_i_suggest(name, names, m);
  err = fail_at(r, v, KARST_ENOTFOUND, "%s names an unknown %s '%s'%s%s%s", path,
                keypoint_type_names[type], nm, hint ? " (did you mean '" : "", hint ? hint : "",
                hint ? "'?)" : "");
  free(names);
  return err;
}

/* key_points[i].drains_to: [spring, ...]. */
static karst_error_t read_drains(reader_t *r, int i, yaml_node_t *n) {
  karst_keypoint_t *kp = &r->sc->key_points[i];
  char d[80], kpath[PATH_LEN], path[PATH_LEN], sub[PATH_LEN];
  index_path(kpath, "key_points", i);
  join(path, kpath, "drains_to");
  if (kp->type != KARST_KEYPOINT_SINK)
    return fail_at(r, n, KARST_EINVAL, "%s: only a sink drains to springs; '%s' is a %s", path,
                   kp->name, keypoint_type_names[kp->type]);
  if (n->type != YAML_SEQUENCE_NODE)
    return fail_at(r, n, KARST_EINVAL, "%s must be a list of spring names, got %s", path,
                   describe(n, d, sizeof d));
  long m = n->data.sequence.items.top - n->data.sequence.items.start;
  if (m < 1 || m > KARST_SCENARIO_MAX_SPRINGS)
    return fail_at(r, n, KARST_ERANGE, "%s must name 1 to %d springs, got %ld", path,
                   KARST_SCENARIO_MAX_SPRINGS, m);
  kp->n_drains_to = 0;
  for (long j = 0; j < m; j++) {
    yaml_node_t *v = yaml_document_get_node(r->doc, n->data.sequence.items.start[j]);
    int k;
    index_path(sub, path, j);
    karst_error_t err = key_of_type(r, v, sub, KARST_KEYPOINT_SPRING, &k);
    if (err) return err;
    for (int q = 0; q < kp->n_drains_to; q++)
      if (kp->drains_to[q] == k)
        return fail_at(r, v, KARST_EINVAL, "%s names spring '%s' twice", path,
                       r->sc->key_points[k].name);
    kp->drains_to[kp->n_drains_to++] = k;
  }
  return KARST_SUCCESS;
}

/* A list of key-point names of one type into a new array of indices. */
static karst_error_t read_name_list(reader_t *r, yaml_node_t *n, const char *path,
                                    karst_keypoint_type_t type, int **out, int *count) {
  char d[80], sub[PATH_LEN];
  if (n->type != YAML_SEQUENCE_NODE)
    return fail_at(r, n, KARST_EINVAL, "%s must be a list of %s names, got %s", path,
                   keypoint_type_names[type], describe(n, d, sizeof d));
  long m = n->data.sequence.items.top - n->data.sequence.items.start;
  if (m < 1 || m > r->sc->n_key_points)
    return fail_at(r, n, KARST_ERANGE, "%s must name 1 to %d key points, got %ld", path,
                   r->sc->n_key_points, m);
  int *v = malloc(sizeof(int) * (size_t)m);
  if (!v) return no_memory(r);
  free(*out);
  *out = v;
  *count = (int)m;
  for (long j = 0; j < m; j++) {
    yaml_node_t *it = yaml_document_get_node(r->doc, n->data.sequence.items.start[j]);
    index_path(sub, path, j);
    karst_error_t err = key_of_type(r, it, sub, type, &v[j]);
    if (err) return err;
    for (long q = 0; q < j; q++)
      if (v[q] == v[j])
        return fail_at(r, it, KARST_EINVAL, "%s names '%s' twice", path,
                       r->sc->key_points[v[j]].name);
  }
  return KARST_SUCCESS;
}

/* connectivity: {sinks: [...], springs: [...], matrix: [[0|1|2, ...], ...]} (KarstNSim's
 * matrix: rows sinks, columns springs); sinks and springs default to all, in file order. */
static karst_error_t read_connectivity(reader_t *r, yaml_node_t *n) {
  static const char *const keys[] = {"sinks", "springs", "matrix"};
  karst_scenario_t *sc = r->sc;
  karst_connectivity_t *c = &sc->connectivity;
  const char *path = "connectivity";
  char d[80], sub[PATH_LEN], sub2[PATH_LEN];
  yaml_node_t *vals[3] = {NULL, NULL, NULL};
  karst_error_t err;
  if (is_null(n)) return KARST_SUCCESS;
  if (n->type != YAML_MAPPING_NODE)
    return fail_at(r, n, KARST_EINVAL, "%s must be a map with sinks, springs and matrix, got %s",
                   path, describe(n, d, sizeof d));
  for (yaml_node_pair_t *p = n->data.mapping.pairs.start; p < n->data.mapping.pairs.top; p++) {
    int idx = 0;
    if ((err = check_key(r, n, p, keys, 3, path, NULL, &idx))) return err;
    vals[idx] = yaml_document_get_node(r->doc, p->value);
  }
  if (!vals[2]) return fail_at(r, n, KARST_EINVAL, "%s is missing the required key 'matrix'", path);
  c->line = line_of(n);
  c->column = col_of(n);
  for (int t = 0; t < 2; t++) {
    karst_keypoint_type_t type = t ? KARST_KEYPOINT_SPRING : KARST_KEYPOINT_SINK;
    int **list = t ? &c->springs : &c->sinks, *cnt = t ? &c->n_springs : &c->n_sinks;
    join(sub, path, keys[t]);
    if (vals[t]) {
      if ((err = read_name_list(r, vals[t], sub, type, list, cnt))) return err;
    } else {
      int m = 0;
      for (int i = 0; i < sc->n_key_points; i++)
        m += sc->key_points[i].type == type;
      if (m == 0)
        return fail_at(r, n, KARST_EINVAL, "%s: the scenario has no %s", path,
                       keypoint_type_names[type]);
      if (!(*list = malloc(sizeof(int) * (size_t)m))) return no_memory(r);
      *cnt = 0;
      for (int i = 0; i < sc->n_key_points; i++)
        if (sc->key_points[i].type == type) (*list)[(*cnt)++] = i;
    }
  }
  yaml_node_t *mx = vals[2];
  join(sub, path, "matrix");
  long rows = mx->type == YAML_SEQUENCE_NODE
                  ? mx->data.sequence.items.top - mx->data.sequence.items.start
                  : -1;
  if (rows != c->n_sinks)
    return fail_at(
        r, mx, KARST_EINVAL, "%s must be a list of %d rows (one per sink), got %s", sub, c->n_sinks,
        rows < 0 ? describe(mx, d, sizeof d) : (snprintf(d, sizeof d, "%ld rows", rows), d));
  if (!(c->matrix = malloc((size_t)c->n_sinks * (size_t)c->n_springs))) return no_memory(r);
  for (long i = 0; i < rows; i++) {
    yaml_node_t *row = yaml_document_get_node(r->doc, mx->data.sequence.items.start[i]);
    index_path(sub2, sub, i);
    long cols = row->type == YAML_SEQUENCE_NODE
                    ? row->data.sequence.items.top - row->data.sequence.items.start
                    : -1;
    if (cols != c->n_springs)
      return fail_at(r, row, KARST_EINVAL,
                     "%s (sink '%s') must list %d values 0, 1 or 2 (one per spring), got %s", sub2,
                     sc->key_points[c->sinks[i]].name, c->n_springs,
                     cols < 0 ? describe(row, d, sizeof d)
                              : (snprintf(d, sizeof d, "%ld values", cols), d));
    int any = 0;
    for (long j = 0; j < cols; j++) {
      yaml_node_t *v = yaml_document_get_node(r->doc, row->data.sequence.items.start[j]);
      char sub3[PATH_LEN];
      int64_t x;
      index_path(sub3, sub2, j);
      if ((err = get_integer(r, v, sub3, 0, 2, 0, 2, &x))) return err;
      c->matrix[i * c->n_springs + j] = (unsigned char)x;
      any |= x > 0;
    }
    if (!any)
      return fail_at(r, row, KARST_EINVAL,
                     "%s: sink '%s' may drain to no spring (every value is 0); allow at least one",
                     sub2, sc->key_points[c->sinks[i]].name);
  }
  c->given = 1;
  return KARST_SUCCESS;
}

/* Plane origins left out default to the domain centre. */
static void centre_origin(const karst_scenario_t *sc, karst_surface_def_t *d) {
  for (int a = 0; a < 2; a++)
    if (isnan(d->origin[a])) d->origin[a] = 0.5 * (sc->domain_min[a] + sc->domain_max[a]);
}

static karst_error_t finish(reader_t *r) {
  karst_scenario_t *sc = r->sc;
  karst_error_t err;
  if (!sc->name) {
    const char *base = strrchr(r->file, '/');
    base = base ? base + 1 : r->file;
    const char *dot = strrchr(base, '.');
    size_t len = dot && dot > base ? (size_t)(dot - base) : strlen(base);
    sc->name = strndup(base, len);
    if (!sc->name) return no_memory(r);
  }
  for (int i = 0; i < sc->n_horizons; i++) {
    karst_horizon_t *h = &sc->horizons[i];
    for (int a = 0; a < 2; a++)
      if (isnan(h->origin[a])) h->origin[a] = 0.5 * (sc->domain_min[a] + sc->domain_max[a]);
    if (!h->path && isnan(h->elevation))
      return karst_set_error(r->ctx, KARST_EINVAL,
                             "%s:%d:%d: horizons[%d] needs elevation (a plane) or surface (a "
                             "grid or TSurf file)",
                             r->file, h->line, h->column, i);
    if (h->path && !isnan(h->elevation))
      return karst_set_error(r->ctx, KARST_EINVAL,
                             "%s:%d:%d: horizons[%d] gives both elevation and surface; give one "
                             "of them",
                             r->file, h->line, h->column, i);
    if (h->path) h->elevation = 0; /* unused: the surface file gives the elevations */
  }
  centre_origin(sc, &sc->water_table);
  for (int i = 0; i < sc->n_key_points; i++)
    centre_origin(sc, &sc->key_points[i].water_table);
  for (int i = 0; i < sc->n_strata; i++) {
    centre_origin(sc, &sc->strata[i].top);
    centre_origin(sc, &sc->strata[i].bottom);
  }
  for (int i = 0; i < sc->n_fractures; i++)
    if (isnan(sc->fractures[i].influence)) sc->fractures[i].influence = sc->sampling.feature_radius;
  if (r->generations && (err = read_generations(r, r->generations))) return err;
  if ((err = finish_frame(r))) return err;
  if ((err = name_key_points(r))) return err;
  if (r->prescribed && (err = read_prescribed(r, r->prescribed))) return err;
  for (int i = 0; i < r->n_drains; i++)
    if (r->drains[i] && (err = read_drains(r, i, r->drains[i]))) return err;
  if (r->connectivity && (err = read_connectivity(r, r->connectivity))) return err;
  return KARST_SUCCESS;
}

/* ------------------------------------------------------------------------ */
/* Cross-field checks                                                       */
/* ------------------------------------------------------------------------ */

/* Prefix "FILE:LINE:COLUMN: " when the scenario came from a file (1:1 for a
 * rule about something the file left out). */
karst_error_t karst_scenario_fail_at(karst_ctx_t *ctx, const karst_scenario_t *sc, int line,
                                     int col, karst_error_t code, const char *fmt, ...) {
  char msg[KARST_ERRMSG_MAX];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  if (!sc->path) return karst_set_error(ctx, code, "%s", msg);
  return karst_set_error(ctx, code, "%s:%d:%d: %s", sc->path, line > 0 ? line : 1,
                         line > 0 && col > 0 ? col : 1, msg);
}

/* Key points by position (x, then y, then z), ties by list order. */
static int cmp_kp_pos(const void *a, const void *b) {
  const karst_keypoint_t *x = *(const karst_keypoint_t *const *)a;
  const karst_keypoint_t *y = *(const karst_keypoint_t *const *)b;
  for (int k = 0; k < 3; k++)
    if (x->p[k] != y->p[k]) return x->p[k] < y->p[k] ? -1 : 1;
  return x < y ? -1 : x > y;
}

/* The first pair (in list order of the later one) of key points at exactly
 * the same position: *dup is the later, *first the earlier; *dup = -1 when
 * there is none. Such a pair would be two samples at one point, joined by a
 * zero-length edge. NaN positions compare unequal (refused elsewhere).
 * Returns 0, or -1 when out of memory. O(n log n). */
static int first_coincident(const karst_scenario_t *sc, int *dup, int *first) {
  *dup = -1;
  *first = -1;
  int n = sc->n_key_points;
  if (n < 2) return 0;
  const karst_keypoint_t **v = malloc(sizeof *v * (size_t)n);
  if (!v) return -1;
  for (int i = 0; i < n; i++)
    v[i] = &sc->key_points[i];
  qsort(v, (size_t)n, sizeof *v, cmp_kp_pos);
  for (int i = 0; i + 1 < n;) {
    int j = i + 1;
    while (j < n && v[j]->p[0] == v[i]->p[0] && v[j]->p[1] == v[i]->p[1] &&
           v[j]->p[2] == v[i]->p[2])
      j++;
    if (j > i + 1) { /* v[i] is the earliest of the group, v[i + 1] the next */
      int later = (int)(v[i + 1] - sc->key_points);
      if (*dup < 0 || later < *dup) {
        *dup = later;
        *first = (int)(v[i] - sc->key_points);
      }
    }
    i = j;
  }
  free(v);
  return 0;
}

/* The per-field rules of a schema, applied to values already in memory
 * (they matter for scenarios built in code; the reader checked them on the way in). */
static karst_error_t check_values(karst_ctx_t *ctx, const karst_scenario_t *sc, const schema_t *s,
                                  const char *base, const char *path, int line, int col) {
  char rt[96], sub[PATH_LEN];
  for (int i = 0; i < s->n; i++) {
    const field_t *f = &s->f[i];
    const char *at = base + f->off;
    join(sub, path, f->key);
    double v;
    switch (f->type) {
    case T_NUM:
      v = *(const double *)at;
      if (!isfinite(v))
        return karst_scenario_fail_at(ctx, sc, line, col, KARST_ERANGE,
                                      "%s must be a finite number, got %g", sub, v);
      break;
    case T_INT:
      v = *(const int *)at;
      break;
    case T_I64:
      v = (double)*(const karst_int_t *)at;
      break;
    case T_VEC2:
    case T_VEC3:
      for (int k = 0; k < (f->type == T_VEC2 ? 2 : 3); k++)
        if (!isfinite(((const double *)at)[k]))
          return karst_scenario_fail_at(ctx, sc, line, col, KARST_ERANGE,
                                        "%s[%d] must be a finite number, got %g", sub, k,
                                        ((const double *)at)[k]);
      continue;
    case T_MAP: {
      karst_error_t err = check_values(ctx, sc, f->sub, at, sub, line, col);
      if (err) return err;
      continue;
    }
    case T_ENUM: {
      int e = *(const int *)at;
      if (e < 0 || e >= f->n_names)
        return karst_scenario_fail_at(ctx, sc, line, col, KARST_ERANGE,
                                      "%s must be one of %d names (such as '%s'), got the index %d",
                                      sub, f->n_names, f->names[0], e);
      continue;
    }
    default:
      continue;
    }
    if (!in_range(&f->range, v)) {
      range_text(&f->range, rt, sizeof rt);
      return karst_scenario_fail_at(ctx, sc, line, col, KARST_ERANGE, "%s must be %s, got %.15g",
                                    sub, rt, v);
    }
  }
  return KARST_SUCCESS;
}

static karst_error_t check_perm(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                const karst_perm_node_t *n, const char *path, int depth) {
  char sub[PATH_LEN];
  karst_error_t err;
  if (depth > KARST_SCENARIO_PERM_MAX_DEPTH)
    return karst_scenario_fail_at(ctx, sc, n->line, n->column, KARST_ERANGE,
                                  "%s: the permeability tree is nested deeper than %d levels", path,
                                  KARST_SCENARIO_PERM_MAX_DEPTH);
  if (!(n->weight > 0) || !isfinite(n->weight))
    return karst_scenario_fail_at(ctx, sc, n->line, n->column, KARST_ERANGE,
                                  "%s.weight must be > 0, got %g", path, n->weight);
  switch (n->kind) {
  case KARST_PERM_SPHERE:
    join(sub, path, "sphere");
    return check_values(ctx, sc, &sphere_schema, (const char *)n, sub, n->line, n->column);
  case KARST_PERM_STRATUM:
    join(sub, path, "stratum");
    if ((err = check_values(ctx, sc, &stratum_schema, (const char *)n, sub, n->line, n->column)))
      return err;
    if (!(n->bottom < n->top))
      return karst_scenario_fail_at(ctx, sc, n->line, n->column, KARST_ERANGE,
                                    "%s: bottom (%g m) must be below top (%g m)", sub, n->bottom,
                                    n->top);
    return KARST_SUCCESS;
  case KARST_PERM_UNION:
  case KARST_PERM_INTERSECTION:
  case KARST_PERM_BLEND:
    if (n->n_children < 1 || !n->children)
      return karst_scenario_fail_at(ctx, sc, n->line, n->column, KARST_EINVAL,
                                    "%s: an operator node needs at least one child", path);
    for (int i = 0; i < n->n_children; i++) {
      index_path(sub, path, i);
      if ((err = check_perm(ctx, sc, &n->children[i], sub, depth + 1))) return err;
    }
    return KARST_SUCCESS;
  }
  return karst_scenario_fail_at(ctx, sc, n->line, n->column, KARST_EINVAL,
                                "%s: unknown node kind %d", path, (int)n->kind);
}

/* A plane surface must have finite values; a file surface must have been read. */
static karst_error_t check_surface(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                   const karst_surface_def_t *d, const char *path) {
  if (!d->given) return KARST_SUCCESS;
  if (d->path) {
    if (!d->surface)
      return karst_scenario_fail_at(ctx, sc, d->line, d->column, KARST_EINVAL,
                                    "%s: the surface file '%s' was not read", path, d->path);
    const double lo[2] = {sc->domain_min[0], sc->domain_min[1]},
                 hi[2] = {sc->domain_max[0], sc->domain_max[1]};
    karst_ctx_t cover;
    karst_ctx_init(&cover);
    if (karst_surface_check_covers(&cover, d->surface, lo, hi, path))
      return karst_scenario_fail_at(ctx, sc, d->line, d->column, KARST_ERANGE, "%s", cover.errmsg);
    return KARST_SUCCESS;
  }
  if (!isfinite(d->elevation) || !isfinite(d->origin[0]) || !isfinite(d->origin[1]))
    return karst_scenario_fail_at(ctx, sc, d->line, d->column, KARST_ERANGE,
                                  "%s: elevation and origin must be finite, got %g at (%g, %g)",
                                  path, d->elevation, d->origin[0], d->origin[1]);
  if (!(d->dip >= 0 && d->dip < 90) || !(d->dip_direction >= 0 && d->dip_direction < 360))
    return karst_scenario_fail_at(
        ctx, sc, d->line, d->column, KARST_ERANGE,
        "%s: dip must be within [0, 90) and dip_direction within [0, 360) degrees, "
        "got %g and %g",
        path, d->dip, d->dip_direction);
  return KARST_SUCCESS;
}

/* A water table given as a plane must reach the domain: its elevation at the origin within the
 * domain's z range. */
static karst_error_t check_water_table(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                       const karst_surface_def_t *d, const char *path) {
  if (!d->given || d->path) return KARST_SUCCESS;
  if (!(d->elevation >= sc->domain_min[2] && d->elevation <= sc->domain_max[2]))
    return karst_scenario_fail_at(
        ctx, sc, d->line, d->column, KARST_ERANGE,
        "%s.elevation must be within the domain's z range [%g, %g] m, got %g", path,
        sc->domain_min[2], sc->domain_max[2], d->elevation);
  return KARST_SUCCESS;
}

/**
 * Check the rules of a scenario: every field within its documented range,
 * and the cross-field rules — domain min < max, the terrain above the domain
 * bottom and (for a heightfield) covering the domain's x-y extent, the water
 * table inside the domain's z range, key points with unique names inside the
 * domain and not above the terrain (the heightfield evaluated at the point),
 * at least one spring, prescribed paths joining two different existing key
 * points, feature_radius <= fill_radius.
 * @param ctx context; the message is "FILE:LINE:COLUMN: ..." when the
 *            scenario was read from a file (the position of the entry at fault)
 * @param sc  scenario to check
 * @return KARST_SUCCESS, or KARST_EINVAL / KARST_ERANGE with the first rule broken.
 * Time complexity: O(n_key_points^2 + size of the permeability tree + other lists).
 */
karst_error_t karst_scenario_check(karst_ctx_t *ctx, const karst_scenario_t *sc) {
  char sub[PATH_LEN];
  karst_error_t err;
  const karst_srcpos_t *pd = &sc->pos_domain, *pt = &sc->pos_terrain;
  static const char axis[3] = {'x', 'y', 'z'};

  /* Per-field ranges of the top-level scalar and map keys. */
  if ((err = check_values(ctx, sc, &top_schema, (const char *)sc, "", 0, 0))) return err;
  if (!isfinite(sc->permeability.background))
    return karst_scenario_fail_at(ctx, sc, 0, 0, KARST_ERANGE,
                                  "permeability.background must be finite");
  for (int t = 0; t < KARST_TUNNEL_TYPE_COUNT; t++) {
    const karst_radius_range_t *rr = &sc->classification.radius[t];
    if (!(rr->min > 0) || !(rr->min <= rr->max) || !isfinite(rr->max))
      return karst_scenario_fail_at(
          ctx, sc, 0, 0, KARST_ERANGE,
          "classification.radius.%s must have 0 < min <= max, got [%g, %g]",
          karst_tunnel_type_name((karst_tunnel_type_t)t), rr->min, rr->max);
  }

  double am_total = karst_amplification_points_total(&sc->amplification,
                                                     KARST_SCENARIO_MAX_AMPLIFICATION_POINTS, NULL);
  if (am_total > KARST_SCENARIO_MAX_AMPLIFICATION_POINTS)
    return karst_scenario_fail_at(
        ctx, sc, sc->pos_amplification.line, sc->pos_amplification.column, KARST_ERANGE,
        "amplification: %d steps of %d points growing by points_ratio %g make %.4g "
        "points, more than %d",
        sc->amplification.steps, sc->amplification.points, sc->amplification.points_ratio, am_total,
        KARST_SCENARIO_MAX_AMPLIFICATION_POINTS);

  for (int a = 0; a < 3; a++) {
    if (!(sc->domain_min[a] < sc->domain_max[a]))
      return karst_scenario_fail_at(
          ctx, sc, pd->line, pd->column, KARST_ERANGE,
          "domain.max %c (%g m) must be greater than domain.min %c (%g m)", axis[a],
          sc->domain_max[a], axis[a], sc->domain_min[a]);
  }

  const karst_terrain_t *tr = &sc->terrain;
  if (tr->surface) {
    const double lo[2] = {sc->domain_min[0], sc->domain_min[1]},
                 hi[2] = {sc->domain_max[0], sc->domain_max[1]};
    karst_ctx_t cover;
    karst_ctx_init(&cover);
    if (karst_surface_check_covers(&cover, tr->surface, lo, hi, "terrain.surface"))
      return karst_scenario_fail_at(ctx, sc, pt->line, pt->column, KARST_ERANGE, "%s",
                                    cover.errmsg);
    if (!(tr->zmax > sc->domain_min[2]))
      return karst_scenario_fail_at(
          ctx, sc, pt->line, pt->column, KARST_ERANGE,
          "terrain.surface '%s' peaks at %g m, not above domain.min z (%g m): "
          "there is no bedrock",
          tr->path ? tr->path : "", tr->zmax, sc->domain_min[2]);
  } else if (tr->is_grid) {
    if (!tr->z || tr->ncols < 1 || tr->nrows < 1 || !(tr->cellsize > 0))
      return karst_scenario_fail_at(ctx, sc, pt->line, pt->column, KARST_EINVAL,
                                    "terrain.heightfield holds no grid");
    double cs = tr->cellsize, slack = KARST_SCENARIO_GRID_COVER_SLACK * cs;
    double x0 = tr->xll - 0.5 * cs, x1 = tr->xll + ((double)tr->ncols - 0.5) * cs;
    double y0 = tr->yll - 0.5 * cs, y1 = tr->yll + ((double)tr->nrows - 0.5) * cs;
    if (sc->domain_min[0] < x0 - slack || sc->domain_max[0] > x1 + slack ||
        sc->domain_min[1] < y0 - slack || sc->domain_max[1] > y1 + slack)
      return karst_scenario_fail_at(
          ctx, sc, pt->line, pt->column, KARST_ERANGE,
          "terrain.heightfield '%s' covers x in [%g, %g], y in [%g, %g] m but the "
          "domain spans x in [%g, %g], y in [%g, %g] m",
          tr->path ? tr->path : "", x0, x1, y0, y1, sc->domain_min[0], sc->domain_max[0],
          sc->domain_min[1], sc->domain_max[1]);
    if (!(tr->zmax > sc->domain_min[2]))
      return karst_scenario_fail_at(
          ctx, sc, pt->line, pt->column, KARST_ERANGE,
          "terrain.heightfield '%s' peaks at %g m, not above domain.min z (%g m): "
          "there is no bedrock",
          tr->path ? tr->path : "", tr->zmax, sc->domain_min[2]);
  } else {
    if (!isfinite(tr->elevation) || !(tr->elevation > sc->domain_min[2]))
      return karst_scenario_fail_at(
          ctx, sc, pt->line, pt->column, KARST_ERANGE,
          "terrain.elevation (%g m) must be above domain.min z (%g m): there would "
          "be no bedrock",
          tr->elevation, sc->domain_min[2]);
  }

  /* Surveyed stations in the domain and in the bedrock (the message says by how much), before
   * the key points: the entrance sinks and survey waypoints sit on stations. */
  if ((err = karst_conditioning_check(ctx, sc))) return err;
  if ((err = check_surface(ctx, sc, &sc->water_table, "water_table"))) return err;
  if ((err = check_water_table(ctx, sc, &sc->water_table, "water_table"))) return err;
  for (int i = 0; i < sc->n_key_points; i++) {
    const karst_keypoint_t *kp = &sc->key_points[i];
    char kpath[PATH_LEN];
    index_path(kpath, "key_points", i);
    join(sub, kpath, "water_table");
    if (kp->water_table.given && kp->type != KARST_KEYPOINT_SPRING)
      return karst_scenario_fail_at(ctx, sc, kp->water_table.line, kp->water_table.column,
                                    KARST_EINVAL,
                                    "%s: only a spring has a water table; '%s' is a %s", sub,
                                    kp->name, keypoint_type_names[kp->type]);
    if ((err = check_surface(ctx, sc, &kp->water_table, sub))) return err;
    if ((err = check_water_table(ctx, sc, &kp->water_table, sub))) return err;
  }
  for (int i = 0; i < sc->n_strata; i++) {
    const karst_stratum_t *st = &sc->strata[i];
    index_path(sub, "strata", i);
    char sub2[PATH_LEN];
    join(sub2, sub, "top");
    if ((err = check_surface(ctx, sc, &st->top, sub2))) return err;
    join(sub2, sub, "bottom");
    if ((err = check_surface(ctx, sc, &st->bottom, sub2))) return err;
    for (int j = 0; j < i; j++)
      if (st->name[0] && !strcmp(st->name, sc->strata[j].name))
        return karst_scenario_fail_at(ctx, sc, st->line, st->column, KARST_EINVAL,
                                      "%s.name '%s' is already used by strata[%d] (line %d)", sub,
                                      st->name, j, sc->strata[j].line);
  }
  for (int i = 0; i < sc->n_exclusions; i++) {
    const karst_exclusion_t *e = &sc->exclusions[i];
    int ok = 1;
    for (int a = 0; a < 3; a++)
      ok &= isfinite(e->min[a]) && isfinite(e->max[a]) && isfinite(e->center[a]);
    if (e->kind == KARST_EXCLUSION_SPHERE) ok &= e->radius > 0 && isfinite(e->radius);
    if (e->kind == KARST_EXCLUSION_PRISM) {
      ok &= e->n_vertices >= 3 && e->polygon && e->bottom < e->top;
      for (int v = 0; ok && v < 2 * e->n_vertices; v++)
        ok &= isfinite(e->polygon[v]);
    }
    if (e->kind < 0 || e->kind > 2 || !ok)
      return karst_scenario_fail_at(ctx, sc, e->line, e->column, KARST_EINVAL,
                                    "exclusions[%d] is not a valid box, sphere or prism", i);
  }
  for (int i = 0; i < sc->n_faults; i++) {
    const karst_fault_t *f = &sc->faults[i];
    index_path(sub, "faults", i);
    if ((err = check_values(ctx, sc, &fault_schema, (const char *)f, sub, f->line, f->column)))
      return err;
  }
  if (sc->connectivity.given) {
    const karst_connectivity_t *c = &sc->connectivity;
    for (int i = 0; i < c->n_sinks; i++) {
      const karst_keypoint_t *kp = &sc->key_points[c->sinks[i]];
      if (kp->n_drains_to > 0)
        return karst_scenario_fail_at(
            ctx, sc, kp->drains_line, kp->drains_column, KARST_EINVAL,
            "key point '%s' has drains_to and a row of the connectivity matrix "
            "(line %d); give one of them",
            kp->name, c->line);
    }
  }

  for (int i = 0; i < sc->n_horizons; i++) {
    const karst_horizon_t *h = &sc->horizons[i];
    index_path(sub, "horizons", i);
    if ((err = check_values(ctx, sc, &horizon_schema, (const char *)h, sub, h->line, h->column)))
      return err;
  }
  for (int i = 0; i < sc->n_fractures; i++) {
    const karst_fracture_t *f = &sc->fractures[i];
    index_path(sub, "fractures", i);
    if ((err = check_values(ctx, sc, &fracture_schema, (const char *)f, sub, f->line, f->column)))
      return err;
  }
  if (sc->permeability.root &&
      (err = check_perm(ctx, sc, sc->permeability.root, "permeability.tree", 0)))
    return err;

  for (int i = 0; i < sc->n_key_points; i++) {
    const karst_keypoint_t *kp = &sc->key_points[i];
    if (!kp->name[0] || !memchr(kp->name, '\0', sizeof kp->name))
      return karst_scenario_fail_at(ctx, sc, kp->line, kp->column, KARST_EINVAL,
                                    "key_points[%d] has no name", i);
  }
  {
    int m = 0, dup, first;
    const karst_keypoint_t **v = sorted_named(sc, &m);
    if (!v) return karst_set_error(ctx, KARST_ENOMEM, "out of memory checking key-point names");
    first_duplicate(sc, v, m, &dup, &first);
    free(v);
    if (dup >= 0)
      return karst_scenario_fail_at(
          ctx, sc, sc->key_points[dup].line, sc->key_points[dup].column, KARST_EINVAL,
          "key_points[%d].name '%s' is already used by key_points[%d]; names "
          "must be unique",
          dup, sc->key_points[dup].name, first);
  }
  int springs = 0;
  for (int i = 0; i < sc->n_key_points; i++) {
    const karst_keypoint_t *kp = &sc->key_points[i];
    const double *p = kp->p;
    if ((int)kp->type < 0 || (int)kp->type > 2)
      return karst_scenario_fail_at(ctx, sc, kp->line, kp->column, KARST_EINVAL,
                                    "key_points[%d].type must be sink, spring or waypoint, got %d",
                                    i, (int)kp->type);
    springs += kp->type == KARST_KEYPOINT_SPRING;
    for (int a = 0; a < 3; a++) {
      if (!isfinite(p[a]))
        return karst_scenario_fail_at(ctx, sc, kp->line, kp->column, KARST_ERANGE,
                                      "key_points[%d] '%s': position[%d] must be finite, got %g", i,
                                      kp->name, a, p[a]);
    }
    for (int a = 0; a < 3; a++) {
      if (p[a] < sc->domain_min[a] || p[a] > sc->domain_max[a])
        return karst_scenario_fail_at(
            ctx, sc, kp->line, kp->column, KARST_ERANGE,
            "key_points[%d] '%s' at (%g, %g, %g) is outside the domain: %c must be "
            "within [%g, %g] m, got %g",
            i, kp->name, p[0], p[1], p[2], axis[a], sc->domain_min[a], sc->domain_max[a], p[a]);
    }
    double h = karst_terrain_height(&sc->terrain, p[0], p[1]);
    if (p[2] > h)
      return karst_scenario_fail_at(
          ctx, sc, kp->line, kp->column, KARST_ERANGE,
          "key_points[%d] '%s' at z = %g m is above the terrain (%g m at x = %g, "
          "y = %g); key points must lie in the bedrock",
          i, kp->name, p[2], h, p[0], p[1]);
  }
  {
    int dup, first;
    if (first_coincident(sc, &dup, &first))
      return karst_set_error(ctx, KARST_ENOMEM, "out of memory checking key-point positions");
    if (dup >= 0) {
      const karst_keypoint_t *a = &sc->key_points[first], *b = &sc->key_points[dup];
      return karst_scenario_fail_at(
          ctx, sc, b->line, b->column, KARST_EINVAL,
          "key_points[%d] '%s' (line %d) is at the same position (%g, %g, %g) as "
          "key_points[%d] '%s' (line %d); key points must be at distinct positions",
          dup, b->name, b->line, b->p[0], b->p[1], b->p[2], first, a->name, a->line);
    }
  }
  if (springs == 0)
    return karst_scenario_fail_at(
        ctx, sc, sc->pos_key_points.line, sc->pos_key_points.column, KARST_EINVAL,
        "no spring among the %d key points: the network needs at least one "
        "(key_points: - {type: spring, position: [x, y, z]})",
        sc->n_key_points);

  for (int i = 0; i < sc->n_prescribed; i++) {
    const karst_prescribed_path_t *pp = &sc->prescribed[i];
    if (pp->a < 0 || pp->a >= sc->n_key_points || pp->b < 0 || pp->b >= sc->n_key_points)
      return karst_scenario_fail_at(
          ctx, sc, pp->line, pp->column, KARST_EINVAL,
          "prescribed_paths[%d] refers to key points %d and %d; there are %d", i, pp->a, pp->b,
          sc->n_key_points);
    if (pp->a == pp->b)
      return karst_scenario_fail_at(ctx, sc, pp->line, pp->column, KARST_EINVAL,
                                    "prescribed_paths[%d] joins key point '%s' to itself", i,
                                    sc->key_points[pp->a].name);
  }

  if (sc->sampling.feature_radius > sc->sampling.fill_radius)
    return karst_scenario_fail_at(
        ctx, sc, sc->pos_sampling.line, sc->pos_sampling.column, KARST_ERANGE,
        "sampling.feature_radius (%g m) must not exceed sampling.fill_radius (%g m): "
        "features are sampled more finely than the fill",
        sc->sampling.feature_radius, sc->sampling.fill_radius);
  return KARST_SUCCESS;
}

/* ------------------------------------------------------------------------ */
/* Loading                                                                  */
/* ------------------------------------------------------------------------ */

/* libyaml's own problem and position (1-based), or the byte offset for encoding errors. */
static karst_error_t syntax_error(reader_t *r, const yaml_parser_t *p, const unsigned char *buf,
                                  size_t len) {
  if (p->error == YAML_MEMORY_ERROR) return no_memory(r);
  if (p->error == YAML_READER_ERROR) {
    int line = 1, col = 1;
    for (size_t i = 0; i < p->problem_offset && i < len; i++) {
      if (buf[i] == '\n') {
        line++;
        col = 1;
      } else {
        col++;
      }
    }
    return karst_set_error(r->ctx, KARST_EPARSE, "%s:%d:%d: invalid text: %s (byte 0x%02x)",
                           r->file, line, col, p->problem ? p->problem : "unreadable",
                           (unsigned)(p->problem_value & 0xff));
  }
  char ctxt[160] = "";
  if (p->context)
    snprintf(ctxt, sizeof ctxt, " (%s at line %d, column %d)", p->context,
             (int)p->context_mark.line + 1, (int)p->context_mark.column + 1);
  return karst_set_error(r->ctx, KARST_EPARSE, "%s:%d:%d: YAML syntax error: %s%s", r->file,
                         (int)p->problem_mark.line + 1, (int)p->problem_mark.column + 1,
                         p->problem ? p->problem : "malformed document", ctxt);
}

/* libyaml's parse time grows with the square of the flow-collection nesting
 * depth (minutes at 200 000 levels), so absurd nesting is refused before
 * parsing. Brackets count where YAML reads them as flow indicators: anywhere
 * inside a flow collection, and where a value starts outside one; quoted
 * scalars and comments are skipped. O(file size). */
static karst_error_t check_nesting(reader_t *r, const unsigned char *buf, size_t len) {
  int depth = 0, line = 1, col = 1, start = 1;
  for (size_t i = 0; i < len; i++, col++) {
    unsigned char c = buf[i];
    if (c == '\n') {
      line++;
      col = 0;
      start = 1;
    } else if (c == ' ' || c == '\t' || c == '\r') {
      /* a value may still start here */
    } else if (c == '#' &&
               (i == 0 || buf[i - 1] == ' ' || buf[i - 1] == '\t' || buf[i - 1] == '\n')) {
      while (i + 1 < len && buf[i + 1] != '\n')
        i++;
    } else if ((c == '"' || c == '\'') && start) {
      for (i++; i < len && buf[i] != c; i++) {
        if (buf[i] == '\n') {
          line++;
          col = 0;
        } else {
          col++;
        }
        if (c == '"' && buf[i] == '\\' && i + 1 < len && buf[i + 1] != '\n') {
          i++;
          col++;
        }
      }
      col++;
      start = 0;
    } else if ((c == '[' || c == '{') && (start || depth > 0)) {
      if (++depth > KARST_SCENARIO_MAX_NESTING)
        return karst_set_error(r->ctx, KARST_EPARSE,
                               "%s:%d:%d: lists and maps are nested more than %d levels deep",
                               r->file, line, col, KARST_SCENARIO_MAX_NESTING);
      start = 1;
    } else if ((c == ']' || c == '}') && depth > 0) {
      depth--;
      start = 0;
    } else {
      start = c == ':' || c == ',' || c == '-' || c == '?';
    }
  }
  return KARST_SUCCESS;
}

static karst_error_t read_file(karst_ctx_t *ctx, const char *path, unsigned char **out,
                               size_t *len) {
  karst_error_t err = KARST_SUCCESS;
  unsigned char *buf = NULL;
  size_t n = 0, cap = 0;
  FILE *fp = NULL;
  if ((err = karst_i_open_regular(ctx, path, "scenario", KARST_SCENARIO_MAX_BYTES, &fp)))
    return err;
  for (;;) {
    if (n > (size_t)KARST_SCENARIO_MAX_BYTES) { /* grew after it was opened */
      err = karst_set_error(ctx, KARST_ERANGE, "%s: the scenario file is more than %lld bytes",
                            path, (long long)KARST_SCENARIO_MAX_BYTES);
      goto cleanup;
    }
    if (n == cap) {
      size_t ncap = cap ? 2 * cap : 65536;
      unsigned char *nb = realloc(buf, ncap);
      if (!nb) {
        err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
        goto cleanup;
      }
      buf = nb;
      cap = ncap;
    }
    size_t got = fread(buf + n, 1, cap - n, fp);
    n += got;
    if (got == 0) break;
  }
  if (ferror(fp)) {
    err = karst_set_error(ctx, KARST_EIO, "%s: cannot read: %s", path, strerror(errno));
    goto cleanup;
  }
  *out = buf;
  *len = n;
  buf = NULL;
cleanup:
  free(buf);
  fclose(fp);
  return err;
}

/**
 * Read and validate a YAML scenario (format: docs/scenario.md).
 * Keys absent from the file keep the values @p sc had from
 * karst_scenario_init(); water_table defaults to the domain bottom and a
 * horizon's origin to the domain centre; unnamed key points are named sink1,
 * spring1, waypoint1 ... Then karst_scenario_check() is applied.
 * @param ctx  context; on failure ctx->errmsg is "FILE:LINE:COLUMN: message"
 *             naming the field path (e.g. fractures[2].dip) and the value
 * @param path scenario file; a heightfield is resolved relative to it
 * @param sc   initialised scenario; replaced on success, untouched on failure
 * @return KARST_SUCCESS, KARST_EIO (unreadable file), KARST_EPARSE (YAML
 *         syntax, empty file), KARST_EINVAL (unknown key, wrong type, bad
 *         enum, broken rule), KARST_ERANGE (value out of range, non-finite),
 *         KARST_ENOTFOUND (prescribed path naming an unknown key point) or
 *         KARST_ENOMEM.
 * Time complexity: O(file size + heightfield size + n_key_points^2).
 */
karst_error_t karst_scenario_load(karst_ctx_t *ctx, const char *path, karst_scenario_t *sc) {
  return karst_i_scenario_load(ctx, path, NULL, sc, NULL, NULL, NULL);
}

/* " (with KEY=VALUE, ...)" after a cross-field rule broken by a scenario with overrides. */
static void note_overrides(karst_ctx_t *ctx, const karst_i_override_set_t *set) {
  size_t len = strlen(ctx->errmsg);
  for (int k = 0; k < set->n && len + 8 < KARST_ERRMSG_MAX; k++) {
    snprintf(ctx->errmsg + len, KARST_ERRMSG_MAX - len, "%s%s=%s%s", k ? ", " : " (with ",
             set->ov[k].key, set->ov[k].value, k == set->n - 1 ? ")" : "");
    len = strlen(ctx->errmsg);
  }
}

/**
 * karst_scenario_load with the overrides of @p set (NULL: none) put into the document before
 * the walk (scenario_internal.h, overrides.c); with @p keep_doc the document and the file's
 * bytes are handed to the caller on success.
 * Time complexity: that of karst_scenario_load plus O(file size) per override.
 */
karst_error_t karst_i_scenario_load(karst_ctx_t *ctx, const char *path, karst_i_override_set_t *set,
                                    karst_scenario_t *sc, yaml_document_t *keep_doc,
                                    unsigned char **text, size_t *text_len) {
  karst_error_t err = KARST_SUCCESS;
  karst_scenario_t tmp;
  yaml_parser_t parser;
  yaml_document_t doc, doc2;
  int parser_ok = 0, doc_ok = 0;
  unsigned char *buf = NULL;
  size_t len = 0;
  reader_t r = {ctx, path, &doc, &tmp, 0, NULL, NULL, NULL, 0, set, NULL, 0};

  karst_scenario_init(&tmp);
  if (!path || !sc) {
    err = karst_set_error(ctx, KARST_EINVAL, "karst_scenario_load: NULL argument");
    goto cleanup;
  }
  if ((err = read_file(ctx, path, &buf, &len))) goto cleanup;
  if (!(tmp.path = strdup(path))) {
    err = no_memory(&r);
    goto cleanup;
  }
  if (!yaml_parser_initialize(&parser)) {
    err = no_memory(&r);
    goto cleanup;
  }
  parser_ok = 1;
  if ((err = check_nesting(&r, buf, len))) goto cleanup;
  yaml_parser_set_input_string(&parser, buf, len);
  if (!yaml_parser_load(&parser, &doc)) {
    err = syntax_error(&r, &parser, buf, len);
    goto cleanup;
  }
  doc_ok = 1;
  yaml_node_t *root = yaml_document_get_root_node(&doc);
  if (!root) {
    err = karst_set_error(ctx, KARST_EPARSE,
                          "%s:1:1: the scenario file is empty (expected a map with keys such as "
                          "domain, terrain and key_points; see docs/scenario.md)",
                          path);
    goto cleanup;
  }
  /* A second document would be silently ignored: refuse it. */
  if (!yaml_parser_load(&parser, &doc2)) {
    err = syntax_error(&r, &parser, buf, len);
    goto cleanup;
  }
  yaml_node_t *root2 = yaml_document_get_root_node(&doc2);
  if (root2) {
    err = karst_set_error(ctx, KARST_EPARSE,
                          "%s:%d:%d: a scenario file holds one YAML document; a second one "
                          "starts here",
                          path, (int)doc2.start_mark.line + 1, (int)doc2.start_mark.column + 1);
  }
  yaml_document_delete(&doc2);
  if (err) goto cleanup;
  if (root->type != YAML_MAPPING_NODE) {
    char d[80];
    err = fail_at(&r, root, KARST_EINVAL,
                  "the scenario must be a map with keys such as domain, terrain and key_points, "
                  "got %s",
                  describe(root, d, sizeof d));
    goto cleanup;
  }
  if (set && set->n > 0) {
    if ((err = karst_i_overrides_apply(ctx, path, &doc, set))) goto cleanup;
    root = yaml_document_get_root_node(&doc); /* the node array may have moved */
  }
  if ((err = walk_map(&r, root, &top_schema, &tmp, "", &top_schema))) goto cleanup;
  if ((err = finish(&r))) goto cleanup;
  if ((err = karst_scenario_check(ctx, &tmp))) {
    if (set && set->n > 0) note_overrides(ctx, set);
    goto cleanup;
  }
  for (int k = 0; set && k < set->n; k++) {
    if (set->ov[k].numeric && set->types[k] != KARST_OVERRIDE_NUMBER &&
        set->types[k] != KARST_OVERRIDE_INTEGER) {
      char lbl[400];
      err = karst_set_error(ctx, KARST_EINVAL, "%s: %s: %s is not a numeric key", path,
                            karst_i_override_label(set, k, lbl, sizeof lbl), set->ov[k].key);
      goto cleanup;
    }
  }
  karst_scenario_destroy(sc);
  *sc = tmp;
  karst_scenario_init(&tmp); /* ownership moved to sc */
  if (keep_doc) {
    *keep_doc = doc;
    doc_ok = 0;
    *text = buf;
    *text_len = len;
    buf = NULL;
  }

cleanup:
  if (doc_ok) yaml_document_delete(&doc);
  if (parser_ok) yaml_parser_delete(&parser);
  free(r.drains);
  free(buf);
  karst_scenario_destroy(&tmp);
  return err;
}
