/* The HTML report of an ensemble (include/karst/report.h). */
#include "karst/report.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "ensemble/ensemble_internal.h"
#include "karst/compare.h"
#include "karst/io.h"
#include "karst/json.h"
#include "karst/metrics.h"
#include "karst/palette.h"
#include "karst/readers.h"
#include "karst/version.h"
#include "report/report_internal.h"

/** Orientation rose: bins of this width over [0, 180) degrees, as the orientation entropy of
 *  Collon et al. 2017 (18 bins of 10 degrees). */
#define ROSE_BIN_DEGREES 10
/** Degrees above this are pooled into the last bar of the degree distribution. */
#define DEGREE_PLOT_MAX 8
/** Stereonet: cells per side of the density grid over the net (a cell is 1/60 of its
 *  diameter, about 2.4 degrees of plunge near the centre, finer than the 8.1-degree counting
 *  circle). */
#define STEREO_GRID 60

void karst_report_survey_init(karst_report_survey_t *s) {
  memset(s, 0, sizeof *s);
  karst_network_init(&s->net);
}

void karst_report_survey_destroy(karst_report_survey_t *s) {
  free(s->label);
  karst_network_destroy(&s->net);
  memset(s, 0, sizeof *s);
}

/**
 * Read the survey at @p path with karst_read_network and compute its metrics
 * (karst_metrics_compute, columns of karst_metric_fields).
 * Time complexity: that of the reader and the metrics.
 */
karst_error_t karst_report_survey_load(karst_ctx_t *ctx, const char *path,
                                       karst_report_survey_t *s) {
  karst_metrics_options_t mo;
  karst_metrics_t m;
  int nf = 0;
  karst_report_survey_t r;
  karst_report_survey_init(&r);
  karst_error_t err = karst_read_network(ctx, path, KARST_FORMAT_AUTO, &r.net);
  if (err) goto cleanup;
  karst_metrics_options_init(&mo);
  err = karst_metrics_compute(ctx, &r.net, &mo, &m);
  if (err) goto cleanup;
  const karst_metric_field_t *f = karst_metric_fields(&nf);
  for (int k = 0; k < nf && k < KARST_REPORT_MAX_METRICS; k++) {
    r.names[k] = f[k].key;
    r.values[k] = karst_metric_value(&m, &f[k]);
    r.n_values++;
  }
  r.label = strdup(path);
  if (!r.label) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  *s = r;
  karst_report_survey_init(&r);
cleanup:
  karst_report_survey_destroy(&r);
  return err;
}

void karst_report_options_init(karst_report_options_t *opt) {
  memset(opt, 0, sizeof *opt);
  opt->members_drawn = 4;
  opt->members_pooled = 50;
}

/* ------------------------------------------------------------------------ */
/* ensemble.json, read with the JSON reader and shown in full               */
/* ------------------------------------------------------------------------ */
/* Text of a scalar as the file has it (a number's literal, a string decoded), or NULL. */
static const char *json_scalar_text(const karst_json_t *v) {
  if (!v) return NULL;
  switch (v->type) {
  case KARST_JSON_NULL:
    return "null";
  case KARST_JSON_FALSE:
    return "false";
  case KARST_JSON_TRUE:
    return "true";
  case KARST_JSON_NUMBER:
  case KARST_JSON_STRING:
    return v->text;
  default:
    return NULL;
  }
}

/* Whether @p v is a non-empty array of objects that all have the same, non-empty set of
 * distinct member names (in any order): such an array is shown as one table, one row per
 * element and one column per name. An object with a repeated name, or elements whose names
 * differ, make it 0 (every element is then shown as its own table).
 * Time complexity: O(n k^2) for n elements of k members. */
static int json_same_keyed_objects(const karst_json_t *v) {
  if (v->type != KARST_JSON_ARRAY || v->n == 0) return 0;
  const karst_json_t *first = &v->items[0];
  if (first->type != KARST_JSON_OBJECT || first->n == 0) return 0;
  for (karst_int_t i = 0; i < v->n; i++) {
    const karst_json_t *e = &v->items[i];
    if (e->type != KARST_JSON_OBJECT || e->n != first->n) return 0;
    /* Same count and every name of the first element exactly once in e (the first element's
     * names distinct, checked at i = 0): then e has exactly the first element's names. */
    for (karst_int_t k = 0; k < first->n; k++) {
      int seen = 0;
      for (karst_int_t m = 0; m < e->n; m++)
        seen += strcmp(first->keys[k], e->keys[m]) == 0;
      if (seen != 1) return 0;
    }
  }
  return 1;
}

/* The member @p key of object @p obj (which has it exactly once). */
static const karst_json_t *json_member(const karst_json_t *obj, const char *key) {
  for (karst_int_t m = 0; m < obj->n; m++)
    if (strcmp(obj->keys[m], key) == 0) return &obj->items[m];
  return NULL;
}

static void html_json(karst_i_buf_t *b, const karst_json_t *v);

/* An array of same-keyed objects (json_same_keyed_objects) as one table: a header row with the
 * first element's member names in its order, then one row per element; each cell is rendered
 * by html_json (scalars and arrays of scalars inline, e.g. a position "[1, 2, 3]"). */
static void html_json_rows(karst_i_buf_t *b, const karst_json_t *v) {
  const karst_json_t *first = &v->items[0];
  karst_i_buf_puts(b, "<table class=\"json rows\"><tr>");
  for (karst_int_t k = 0; k < first->n; k++) {
    karst_i_buf_puts(b, "<th class=\"l\">");
    karst_i_buf_escape(b, first->keys[k]);
    karst_i_buf_puts(b, "</th>");
  }
  karst_i_buf_puts(b, "</tr>");
  for (karst_int_t i = 0; i < v->n; i++) {
    karst_i_buf_puts(b, "<tr>");
    for (karst_int_t k = 0; k < first->n; k++) {
      karst_i_buf_puts(b, "<td class=\"l\">");
      html_json(b, json_member(&v->items[i], first->keys[k]));
      karst_i_buf_puts(b, "</td>");
    }
    karst_i_buf_puts(b, "</tr>");
  }
  karst_i_buf_puts(b, "</table>");
}

/* Every value in full: scalars as text, arrays of scalars inline ("[a, b, c]", strings in
 * quotes), arrays of same-keyed objects as one table (html_json_rows), other arrays and
 * objects as nested tables (one row per element or member). */
static void html_json(karst_i_buf_t *b, const karst_json_t *v) {
  if (karst_json_is_scalar(v)) {
    karst_i_buf_escape(b, json_scalar_text(v));
    return;
  }
  int is_obj = v->type == KARST_JSON_OBJECT;
  if (v->n == 0) {
    karst_i_buf_puts(b, is_obj ? "{ }" : "[ ]");
    return;
  }
  int flat = !is_obj;
  for (karst_int_t i = 0; flat && i < v->n; i++)
    flat = karst_json_is_scalar(&v->items[i]);
  if (flat) {
    karst_i_buf_puts(b, "[");
    for (karst_int_t i = 0; i < v->n; i++) {
      const karst_json_t *e = &v->items[i];
      if (i) karst_i_buf_puts(b, ", ");
      if (e->type == KARST_JSON_STRING) karst_i_buf_puts(b, "&quot;");
      karst_i_buf_escape(b, json_scalar_text(e));
      if (e->type == KARST_JSON_STRING) karst_i_buf_puts(b, "&quot;");
    }
    karst_i_buf_puts(b, "]");
    return;
  }
  if (json_same_keyed_objects(v)) {
    html_json_rows(b, v);
    return;
  }
  karst_i_buf_puts(b, "<table class=\"json\">");
  for (karst_int_t i = 0; i < v->n; i++) {
    karst_i_buf_puts(b, "<tr><th class=\"l\">");
    if (is_obj)
      karst_i_buf_escape(b, v->keys[i]);
    else
      karst_i_buf_printf(b, "[%" PRId64 "]", i);
    karst_i_buf_puts(b, "</th><td class=\"l\">");
    html_json(b, &v->items[i]);
    karst_i_buf_puts(b, "</td></tr>");
  }
  karst_i_buf_puts(b, "</table>");
}

/* ------------------------------------------------------------------------ */
/* Plots                                                                    */
/* ------------------------------------------------------------------------ */
static void fmt_num(char *out, size_t size, double v) {
  if (isnan(v))
    snprintf(out, size, "–");
  else
    snprintf(out, size, "%.4g", v);
}

/* ------------------------------------------------------------------------ */
/* HTML                                                                     */
/* ------------------------------------------------------------------------ */
static const char *const css =
    "body{font-family:sans-serif;margin:1.5em;color:#222;max-width:1400px}"
    "h1{font-size:1.5em}h2{font-size:1.2em;margin-top:1.6em;border-bottom:1px solid #ccc}"
    "table{border-collapse:collapse;font-size:0.85em}td,th{border:1px solid #ccc;padding:2px 6px;"
    "text-align:right}th{background:#f0f0f0}td.l,th.l{text-align:left}tr.out td{background:#fde0dc}"
    ".grid{display:flex;flex-wrap:wrap;gap:10px}figure{margin:0}figcaption{font-size:0.8em}"
    "svg text{font-family:'DejaVu Sans',Verdana,sans-serif}svg .tick{font-size:10px;fill:#333}"
    "svg .axis{font-size:11px;fill:#111}svg .note{font-size:10px;fill:#555}"
    ".legend span{display:inline-block;margin-right:1em;font-size:0.85em}"
    ".sw{display:inline-block;width:1.6em;height:0.35em;margin-right:0.3em;vertical-align:middle}"
    "pre{background:#f7f7f7;padding:0.5em;font-size:0.85em}"
    "table.json table.json{font-size:1em;margin:0}table.rows td{vertical-align:top}";

static void html_cell_num(karst_i_buf_t *b, double v) {
  char s[64];
  fmt_num(s, sizeof s, v);
  karst_i_buf_printf(b, "<td>%s</td>", s);
}

static void html_compare_table(karst_i_buf_t *b, const karst_compare_result_t *r) {
  karst_i_buf_puts(b, "<table><tr><th class=\"l\">metric</th><th>survey</th><th>percentile</th>"
                      "<th>n</th><th>mean</th><th>sd</th><th>p5</th><th>p95</th>"
                      "<th>34 caves min</th><th>34 caves max</th><th class=\"l\">flag</th></tr>\n");
  for (int k = 0; k < r->n_rows; k++) {
    const karst_compare_row_t *row = &r->rows[k];
    karst_i_buf_printf(b, "<tr%s><td class=\"l\">", row->outside ? " class=\"out\"" : "");
    karst_i_buf_escape(b, row->metric);
    karst_i_buf_puts(b, "</td>");
    html_cell_num(b, row->survey);
    if (isnan(row->percentile))
      karst_i_buf_puts(b, "<td>–</td>");
    else
      karst_i_buf_printf(b, "<td>%.1f %%</td>", row->percentile);
    karst_i_buf_printf(b, "<td>%" PRId64 "</td>", row->ens.n);
    html_cell_num(b, row->ens.mean);
    html_cell_num(b, row->ens.sd);
    html_cell_num(b, row->ens.p05);
    html_cell_num(b, row->ens.p95);
    html_cell_num(b, row->published_min);
    html_cell_num(b, row->published_max);
    karst_i_buf_printf(b, "<td class=\"l\">%s</td></tr>\n",
                       row->outside ? "outside the 5–95 % band" : "");
  }
  karst_i_buf_puts(b, "</table>\n");
}

/* Fracture families of the scenario, from ensemble.json's "parameters": "fractures", each
 * with numeric "dip_direction" and "dip" (others are skipped). At most @p max. */
static int read_planes(const karst_json_t *params, karst_i_plane_t *planes, int max) {
  const karst_json_t *fr = karst_json_get(params, "fractures");
  int n = 0;
  if (!fr || fr->type != KARST_JSON_ARRAY) return 0;
  for (karst_int_t i = 0; i < fr->n && n < max; i++) {
    const karst_json_t *dd = karst_json_get(&fr->items[i], "dip_direction");
    const karst_json_t *d = karst_json_get(&fr->items[i], "dip");
    if (!dd || !d || dd->type != KARST_JSON_NUMBER || d->type != KARST_JSON_NUMBER) continue;
    planes[n].dip_direction = dd->number;
    planes[n].dip = d->number;
    n++;
  }
  return n;
}

/* The directory of @p path ("." when it has none); caller frees. */
static char *dir_of(const char *path) {
  const char *slash = strrchr(path, '/');
  if (!slash) return strdup(".");
  if (slash == path) return strdup("/");
  char *d = malloc((size_t)(slash - path) + 1);
  if (d) memcpy(d, path, (size_t)(slash - path)), d[slash - path] = '\0';
  return d;
}

/* @p file as the page shows it: relative to the page's directory @p page_dir when it can be
 * resolved, else as given (lexically normalised). Caller frees. */
static char *shown_path(const char *page_dir, const char *file) {
  karst_ctx_t quiet;
  karst_ctx_init(&quiet);
  char *rel = NULL;
  if (karst_path_relative(&quiet, page_dir, file, &rel) == KARST_SUCCESS) return rel;
  return karst_path_normalize(file);
}

/* The scenario file as ensemble.json records it, shown relative to the page when it can be
 * found (absolute, or relative to the working directory, where karst ensemble most likely
 * ran), else as recorded, normalised. Caller frees. */
static char *scenario_path(const char *page_dir, const char *recorded) {
  if (access(recorded, F_OK) == 0) return shown_path(page_dir, recorded);
  return karst_path_normalize(recorded);
}

/* The legend of tunnel-type colours (and the survey's) above the members' views. */
static void html_type_legend(karst_i_buf_t *b, int with_survey) {
  const karst_palette_t *pal = karst_palette_find("tunnel_type");
  karst_i_buf_puts(b, "<p class=\"legend\">");
  for (int k = 0; k < pal->n; k++)
    karst_i_buf_printf(b, "<span><i class=\"sw\" style=\"background:%s\"></i>%s</span>",
                       pal->categories[k].hex, pal->categories[k].name);
  if (with_survey)
    karst_i_buf_printf(b, "<span><i class=\"sw\" style=\"background:%s\"></i>survey</span>",
                       karst_palette_role(KARST_PALETTE_ROLE_SURVEY));
  karst_i_buf_puts(b, "</p>\n");
}

/* The metrics that are not plotted: constant over the ensemble, or undefined for every
 * member; shown as values in one table. Returns how many. */
static int html_constant_metrics(karst_i_buf_t *b, const karst_ensemble_table_t *t,
                                 const karst_compare_result_t *res, int n_surveys) {
  int n = 0;
  for (int c = 0; c < t->n_cols; c++) {
    double v;
    karst_int_t k;
    if (!karst_i_column_constant(t, c, &v, &k)) continue;
    if (n++ == 0) {
      karst_i_buf_puts(b, "<p>Metrics with one value for every member are shown as that value, "
                          "not as a histogram:</p>\n<table><tr><th class=\"l\">metric</th>"
                          "<th class=\"l\">quantity (unit)</th><th>members' value</th>"
                          "<th>members</th>");
      if (n_surveys > 0) karst_i_buf_puts(b, "<th>survey</th>");
      karst_i_buf_puts(b, "<th>34 caves min</th><th>34 caves max</th></tr>\n");
    }
    char label[160], num[64];
    karst_i_metric_axis_label(label, sizeof label, t->names[c]);
    karst_i_buf_puts(b, "<tr><td class=\"l\">");
    karst_i_buf_escape(b, t->names[c]);
    karst_i_buf_puts(b, "</td><td class=\"l\">");
    karst_i_buf_escape(b, label);
    if (k == 0)
      karst_i_buf_puts(b, "</td><td>undefined for every member</td>");
    else {
      fmt_num(num, sizeof num, v);
      karst_i_buf_printf(b, "</td><td>%s</td>", num);
    }
    karst_i_buf_printf(b, "<td>%" PRId64 "</td>", k);
    const karst_compare_row_t *row = &res[0].rows[c];
    if (n_surveys > 0) html_cell_num(b, row->survey);
    html_cell_num(b, row->has_published ? row->published_min : NAN);
    html_cell_num(b, row->has_published ? row->published_max : NAN);
    karst_i_buf_puts(b, "</tr>\n");
  }
  if (n) karst_i_buf_puts(b, "</table>\n");
  return n;
}

/**
 * Write the report (see report.h) of the ensemble in @p ensemble_dir.
 * Reads DIR/ensemble.json, DIR/metrics.csv and the network.vtp of the first members; writes
 * @p path atomically. A member that cannot be read is named in the page instead of its plot
 * (the page is still written). Files are named relative to the page's directory.
 * Time complexity: O(members × metrics log members + edges of the members read).
 */
karst_error_t karst_report_write(karst_ctx_t *ctx, const char *ensemble_dir, const char *path,
                                 const karst_report_options_t *opt) {
  karst_error_t err = KARST_SUCCESS;
  karst_report_options_t defaults;
  karst_ensemble_table_t table;
  karst_published_t pub;
  karst_compare_result_t *res = NULL;
  karst_i_buf_t b, maps, problems;
  karst_json_t *summary = NULL;
  int n_res = 0, have_pub = 0;
  char *jpath = NULL, *mpath = NULL, *versions = NULL, *page_dir = NULL;
  char **labels = NULL;
  karst_network_t net, *drawn = NULL;
  karst_int_t n_drawn = 0;
  karst_i_stereo_t stereo = {0, NULL, 0};
  double rose[180 / ROSE_BIN_DEGREES] = {0}, srose[180 / ROSE_BIN_DEGREES] = {0};
  double deg[DEGREE_PLOT_MAX + 1] = {0}, sdeg[DEGREE_PLOT_MAX + 1] = {0};
  const int nrose = 180 / ROSE_BIN_DEGREES;
  char pubpath[1024];
  char(*mnames)[32] = NULL;
  uint64_t *mseeds = NULL;

  karst_ensemble_table_init(&table);
  karst_published_init(&pub);
  karst_i_buf_init(&b);
  karst_i_buf_init(&maps);
  karst_i_buf_init(&problems);
  karst_network_init(&net);
  if (!opt) {
    karst_report_options_init(&defaults);
    opt = &defaults;
  }
  jpath = karst_i_path_join(ensemble_dir, "ensemble.json");
  mpath = karst_i_path_join(ensemble_dir, "metrics.csv");
  versions = karst_versions_text();
  page_dir = dir_of(path);
  if (!jpath || !mpath || !versions || !page_dir ||
      karst_i_stereo_init(&stereo, STEREO_GRID) != 0) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  err = karst_json_read_file(ctx, jpath, &summary);
  if (err) goto cleanup;
  if (summary->type != KARST_JSON_OBJECT) {
    err = karst_set_error(ctx, KARST_EPARSE,
                          "%s:%d:%d: expected an object (ensemble.json of "
                          "karst ensemble), got another JSON value",
                          jpath, summary->line, summary->col);
    goto cleanup;
  }
  err = karst_ensemble_table_read(ctx, mpath, &table);
  if (err) goto cleanup;

  if (opt->published_path) {
    snprintf(pubpath, sizeof pubpath, "%s", opt->published_path);
    err = karst_published_read(ctx, pubpath, &pub);
    if (err) goto cleanup;
    have_pub = 1;
  } else {
    karst_ctx_t quiet = *ctx;
    if (karst_published_locate(&quiet, pubpath, sizeof pubpath) == KARST_SUCCESS &&
        karst_published_read(&quiet, pubpath, &pub) == KARST_SUCCESS)
      have_pub = 1;
    else
      karst_log(ctx, KARST_LOG_WARNING, "report without the 34-cave ranges: %s", quiet.errmsg);
  }

  n_res = opt->n_surveys > 0 ? opt->n_surveys : 1;
  res = calloc((size_t)n_res, sizeof *res);
  labels = calloc((size_t)n_res, sizeof *labels);
  if (!res || !labels) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  for (int s = 0; s < n_res; s++) {
    const karst_report_survey_t *sv = opt->n_surveys > 0 ? &opt->surveys[s] : NULL;
    if (sv && sv->label && !(labels[s] = shown_path(page_dir, sv->label))) {
      err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
      goto cleanup;
    }
    err =
        karst_compare_compute(ctx, &table, labels[s], sv ? sv->names : NULL, sv ? sv->values : NULL,
                              sv ? sv->n_values : 0, have_pub ? &pub : NULL, &res[s]);
    if (err) goto cleanup;
  }

  /* --- page head and summary --- */
  karst_i_buf_puts(&b, "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                       "<title>karst ensemble report</title><style>");
  karst_i_buf_puts(&b, css);
  karst_i_buf_puts(&b, "</style></head><body>\n<h1>karst ensemble report</h1>\n");
  const karst_json_t *params = karst_json_get(summary, "parameters");
  const char *name = json_scalar_text(karst_json_get(params, "name"));
  karst_i_buf_puts(&b, "<h2>Scenario</h2>\n<table>");
  const char *keys[] = {"scenario", "scenario_hash", "seed", "realisations", "karst_version"};
  const char *key_labels[] = {"scenario file", "scenario hash (FNV-1a 64)", "base seed",
                              "realisations", "karst version"};
  karst_i_buf_puts(&b, "<tr><th class=\"l\">name</th><td class=\"l\">");
  karst_i_buf_escape(&b, name ? name : "–");
  karst_i_buf_puts(&b, "</td></tr>");
  for (int i = 0; i < 5; i++) {
    const char *v = json_scalar_text(karst_json_get(summary, keys[i]));
    char *norm = i == 0 && v ? scenario_path(page_dir, v) : NULL;
    karst_i_buf_printf(&b, "<tr><th class=\"l\">%s</th><td class=\"l\">", key_labels[i]);
    karst_i_buf_escape(&b, norm ? norm : v ? v : "–");
    karst_i_buf_puts(&b, "</td></tr>");
    free(norm);
  }
  /* The coordinate system of every coordinate below (docs/scenario.md, "Coordinates"). */
  const char *crs = json_scalar_text(karst_json_get(params, "crs"));
  karst_i_buf_puts(&b, "<tr><th class=\"l\">coordinate system</th><td class=\"l\">");
  karst_i_buf_escape(&b, crs ? crs : "local (no crs given)");
  karst_i_buf_puts(&b, "</td></tr>");
  karst_i_buf_printf(&b,
                     "<tr><th class=\"l\">members in metrics.csv</th><td class=\"l\">%" PRId64
                     "</td></tr></table>\n",
                     table.n_rows);
  karst_i_buf_puts(&b, "<p>Member <i>i</i> is generated from its own seed (column "
                       "<code>seed</code> of metrics.csv), derived from the base seed and "
                       "<i>i</i>; <code>karst generate --seed</code> with that seed reproduces "
                       "it.</p>\n<details><summary>effective parameters (all of them, as "
                       "ensemble.json records them)</summary>");
  if (params)
    html_json(&b, params);
  else
    karst_i_buf_puts(&b, "<p>ensemble.json records no parameters.</p>");
  karst_i_buf_puts(&b, "</details>\n");

  /* --- comparison --- */
  karst_i_buf_puts(&b,
                   "<h2>Comparison with the ensemble</h2>\n<p>Percentile of a survey value "
                   "v: 100 × (members ≤ v) / n. Mean, sample standard deviation (divisor "
                   "n − 1), 5th and 95th percentiles by linear interpolation (Hyndman &amp; "
                   "Fan type 7). 34 caves: range of Collon et al. 2017 (corrected 2021).</p>\n");
  for (int s = 0; s < n_res; s++) {
    karst_i_buf_puts(&b, "<h3>");
    karst_i_buf_escape(&b, res[s].label ? res[s].label : "ensemble statistics (no survey given)");
    karst_i_buf_puts(&b, "</h3>\n");
    html_compare_table(&b, &res[s]);
  }

  /* --- histograms, after the metrics shown as values --- */
  const int n_sv = opt->n_surveys > 0 ? n_res : 0;
  karst_i_buf_puts(&b, "<h2>Metrics of the members</h2>\n");
  html_constant_metrics(&b, &table, res, n_sv);
  karst_i_buf_puts(&b, "<p>Bars: members per bin. Dashed red lines: survey values (an axis "
                       "broken by // gives a survey far from the members its own stretch). Grey "
                       "band: range of the 34 published caves.");
  for (int s = 0; n_sv > 1 && s < n_sv; s++) {
    karst_i_buf_printf(&b,
                       " <svg width=\"30\" height=\"8\" role=\"img\"><title>survey %d</title>"
                       "<line x1=\"1\" y1=\"4\" x2=\"29\" y2=\"4\" stroke=\"%s\" "
                       "stroke-width=\"2\" stroke-dasharray=\"%s\"/></svg> survey %d: ",
                       s + 1, karst_palette_role(KARST_PALETTE_ROLE_SURVEY), karst_i_survey_dash(s),
                       s + 1);
    karst_i_buf_escape(&b, labels[s] ? labels[s] : "");
    karst_i_buf_puts(&b, s + 1 < n_sv ? ";" : ".");
  }
  karst_i_buf_puts(&b, "</p>\n<div class=\"grid\">\n");
  for (int c = 0; c < table.n_cols; c++) {
    double v;
    karst_int_t k;
    if (karst_i_column_constant(&table, c, &v, &k)) continue;
    karst_i_buf_puts(&b, "<figure>");
    karst_i_plot_histogram(&b, &table, c, res, n_sv);
    karst_i_buf_puts(&b, "</figure>\n");
  }
  karst_i_buf_puts(&b, "</div>\n");

  /* --- member networks: pooled for the rose, degrees and stereonet; the first drawn --- */
  karst_int_t pooled = 0;
  /* The plan-view density of simulated conduits over the domain (drawn when the members are
   * conditioned on a survey). */
  karst_i_density_t dens;
  int have_dens = 0;
  {
    const karst_json_t *dmin = karst_json_get(params, "domain_min"),
                       *dmax = karst_json_get(params, "domain_max");
    if (dmin && dmax && dmin->type == KARST_JSON_ARRAY && dmax->type == KARST_JSON_ARRAY &&
        dmin->n >= 2 && dmax->n >= 2) {
      double lo[2] = {dmin->items[0].number, dmin->items[1].number},
             hi[2] = {dmax->items[0].number, dmax->items[1].number};
      have_dens = karst_i_density_init(&dens, lo, hi) == 0;
    }
  }
  karst_int_t upto = table.n_rows;
  if (upto > opt->members_pooled) upto = opt->members_pooled;
  int want = opt->members_drawn > 0 ? opt->members_drawn : 0;
  drawn = calloc((size_t)(want > 0 ? want : 1), sizeof *drawn);
  mnames = calloc((size_t)(want > 0 ? want : 1), sizeof *mnames);
  mseeds = calloc((size_t)(want > 0 ? want : 1), sizeof *mseeds);
  if (!drawn || !mnames || !mseeds) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (karst_int_t r = 0; r < upto; r++) {
    char mname[32], rel[96];
    karst_i_member_name(mname, table.index[r]);
    snprintf(rel, sizeof rel, "realisations/%s/network.vtp", mname);
    char *vtp = karst_i_path_join(ensemble_dir, rel);
    if (!vtp) {
      b.failed = 1;
      break;
    }
    karst_ctx_t mctx = *ctx;
    mctx.errmsg[0] = '\0';
    karst_network_destroy(&net);
    karst_network_init(&net);
    karst_error_t rerr = opt->read_network
                             ? opt->read_network(&mctx, opt->read_user, vtp, &net)
                             : karst_read_network(&mctx, vtp, KARST_FORMAT_AUTO, &net);
    free(vtp);
    if (rerr) {
      karst_i_buf_puts(&problems, "<li>");
      karst_i_buf_escape(&problems, mctx.errmsg[0] ? mctx.errmsg : karst_strerror(rerr));
      karst_i_buf_puts(&problems, "</li>\n");
      continue;
    }
    pooled++;
    if (have_dens && karst_i_density_add(&dens, &net)) b.failed = 1;
    karst_i_rose_accumulate(&net, rose, nrose);
    karst_i_degree_accumulate(&net, deg, DEGREE_PLOT_MAX);
    karst_i_stereo_accumulate(&stereo, &net);
    if (n_drawn < want) {
      karst_i_bounds_add(&net, lo, hi);
      snprintf(mnames[n_drawn], 32, "%s", mname);
      mseeds[n_drawn] = table.seed[r];
      drawn[n_drawn++] = net; /* kept: the next member starts from a fresh network */
      karst_network_init(&net);
    }
  }
  const karst_report_survey_t *s0 = opt->n_surveys > 0 ? &opt->surveys[0] : NULL;
  const char *s0_label = s0 ? labels[0] : "";
  if (s0) {
    karst_i_rose_accumulate(&s0->net, srose, nrose);
    karst_i_degree_accumulate(&s0->net, sdeg, DEGREE_PLOT_MAX);
  }
  karst_i_plane_t planes[16];
  int n_planes = read_planes(params, planes, 16);
  karst_i_buf_printf(&b,
                     "<h2>Orientation and degree</h2>\n<p>Pooled over the first %" PRId64
                     " members. Rose: conduit azimuths (clockwise from grid north, 10° bins, "
                     "drawn symmetrically), weighted by horizontal length. Stereonet: each "
                     "conduit as a line (trend and plunge of its downward direction), weighted "
                     "by length; the scenario's fracture families as great circles.</p>\n"
                     "<div class=\"grid\"><figure>",
                     pooled);
  karst_i_plot_rose(&b, rose, s0 ? srose : NULL, nrose, pooled, s0_label);
  karst_i_buf_puts(&b, "<figcaption>length-weighted orientation rose</figcaption></figure>"
                       "<figure>");
  karst_i_plot_stereonet(&b, &stereo, s0 ? &s0->net : NULL, s0_label, planes, n_planes, pooled);
  karst_i_buf_puts(&b, "<figcaption>stereonet of conduit orientations</figcaption></figure>"
                       "<figure>");
  karst_i_plot_degrees(&b, deg, s0 ? sdeg : NULL, DEGREE_PLOT_MAX, s0_label);
  karst_i_buf_puts(&b, "<figcaption>degree distribution (full graph)</figcaption></figure>"
                       "</div>\n");

  /* --- the members' views, one frame for all --- */
  karst_i_frame_t frame;
  karst_i_frame_make(&frame, lo, hi, s0 && s0->net.n_edges > 0 ? &s0->net : NULL);
  karst_i_buf_puts(&b, "<h2>Members: plan, sections and oblique view</h2>\n");
  karst_i_buf_printf(&b,
                     "<p>Every view of every member has the same scale (%.3g px per metre; "
                     "the sections' vertical exaggeration is written on them). ",
                     frame.scale);
  if (s0 && s0->net.n_edges > 0)
    karst_i_buf_puts(&b, frame.survey_inside
                             ? "The survey is drawn in red in each member's frame (their "
                               "coordinates overlap).</p>\n"
                             : "The survey's coordinates do not overlap the members': it has "
                               "its own row of views at the same scale.</p>\n");
  else
    karst_i_buf_puts(&b, "</p>\n");
  html_type_legend(&b, s0 && s0->net.n_edges > 0 && frame.survey_inside);
  const karst_network_t *sv_net = s0 && s0->net.n_edges > 0 ? &s0->net : NULL;
  for (karst_int_t i = 0; i < n_drawn; i++) {
    char title[96];
    snprintf(title, sizeof title, "member %s", mnames[i]);
    karst_i_buf_printf(&maps, "<h3>member %s (seed %" PRIu64 ")</h3><div class=\"grid\">",
                       mnames[i], mseeds[i]);
    karst_i_plot_views(&maps, &frame, &drawn[i], frame.survey_inside ? sv_net : NULL, title);
    karst_i_buf_puts(&maps, "</div>\n");
  }
  if (sv_net && !frame.survey_inside) {
    karst_i_buf_puts(&maps, "<h3>survey ");
    karst_i_buf_escape(&maps, s0_label);
    karst_i_buf_puts(&maps, " (its own frame, same scale)</h3><div class=\"grid\">");
    karst_i_plot_views(&maps, &frame, sv_net, sv_net, "survey");
    karst_i_buf_puts(&maps, "</div>\n");
  }
  if (have_dens && dens.conditioned) {
    karst_i_buf_printf(&b,
                       "<h2>Where the ensemble places the unexplored conduits</h2>\n<p>Plan view "
                       "of the %d members read: each %.0f m cell is coloured by the fraction of "
                       "members that have a simulated conduit (edge attribute "
                       "<code>observed</code> = 0) crossing it; the surveyed legs (observed = 1, "
                       "the same in every member) are drawn in red.</p>\n<figure id=\"density\">",
                       dens.members, dens.cell);
    karst_i_density_plot(&b, &dens, "plan-view density of simulated conduits",
                         karst_palette_role(KARST_PALETTE_ROLE_SURVEY));
    karst_i_buf_puts(&b, "<figcaption>density of simulated (not surveyed) conduits, plan view"
                         "</figcaption></figure>\n");
  }
  if (have_dens) karst_i_density_destroy(&dens);
  if (maps.s) karst_i_buf_puts(&b, maps.s);
  if (problems.s) {
    karst_i_buf_puts(&b, "<p>Members that could not be read:</p><ul>\n");
    karst_i_buf_puts(&b, problems.s);
    karst_i_buf_puts(&b, "</ul>\n");
  }
  if (maps.failed || problems.failed) b.failed = 1;

  /* --- versions --- */
  karst_i_buf_puts(&b, "<h2>Software</h2>\n<pre>");
  karst_i_buf_escape(&b, versions);
  karst_i_buf_puts(&b, "</pre>\n");
  if (have_pub) {
    char *shown = shown_path(page_dir, pubpath);
    karst_i_buf_printf(&b, "<p>Published ranges: %d caves read from ", pub.n_caves);
    karst_i_buf_escape(&b, shown ? shown : pubpath);
    karst_i_buf_puts(&b, " (relative to this page).</p>\n");
    free(shown);
  }
  karst_i_buf_puts(&b, "</body></html>\n");
  if (b.failed) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory while building the report");
    goto cleanup;
  }
  {
    karst_atomic_file_t f;
    err = karst_atomic_open(ctx, &f, path, "wb");
    if (err) goto cleanup;
    fwrite(b.s, 1, b.len, f.fp);
    err = karst_atomic_commit(ctx, &f);
  }
cleanup:
  if (res)
    for (int s = 0; s < n_res; s++)
      karst_compare_result_destroy(&res[s]);
  free(res);
  if (labels)
    for (int s = 0; s < n_res; s++)
      free(labels[s]);
  free(labels);
  if (drawn)
    for (karst_int_t i = 0; i < n_drawn; i++)
      karst_network_destroy(&drawn[i]);
  free(drawn);
  free(mnames);
  free(mseeds);
  karst_i_stereo_destroy(&stereo);
  karst_network_destroy(&net);
  karst_i_buf_destroy(&b);
  karst_i_buf_destroy(&maps);
  karst_i_buf_destroy(&problems);
  karst_published_destroy(&pub);
  karst_ensemble_table_destroy(&table);
  karst_json_free(summary);
  free(versions);
  free(mpath);
  free(jpath);
  free(page_dir);
  return err;
}
