/* The HTML report of an ensemble (include/karst/report.h). */
#include "karst/report.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ensemble/ensemble_internal.h"
#include "karst/compare.h"
#include "karst/io.h"
#include "karst/json.h"
#include "karst/metrics.h"
#include "karst/readers.h"
#include "karst/version.h"
#include "report/svg_internal.h"

/** Orientation rose: bins of this width over [0, 180) degrees, as the orientation entropy of
 *  Collon et al. 2017 (18 bins of 10 degrees). */
#define ROSE_BIN_DEGREES 10
/** Degrees above this are pooled into the last bar of the degree distribution. */
#define DEGREE_PLOT_MAX 8
/** Histogram bins: ceil(sqrt(n)) clamped to [HIST_MIN_BINS, HIST_MAX_BINS] (square-root rule). */
#define HIST_MIN_BINS 5
#define HIST_MAX_BINS 30

/* Okabe & Ito (2008) colour-blind-safe palette, one colour per tunnel type (network.h order). */
static const char *const tunnel_colour[KARST_TUNNEL_TYPE_COUNT] = {
    "#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#D55E00", "#000000"};
static const char *const no_type_colour = "#777777";
static const char *const survey_colour = "#C00000";

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

/* Histogram of one metric column, with the survey value(s) and the 34-cave range. */
static void plot_histogram(karst_i_buf_t *b, const karst_ensemble_table_t *t, int col,
                           const karst_compare_result_t *res, int n_res) {
  const double W = 300, H = 200;
  karst_i_plot_t p = {56, 12, W - 70, H - 58, 0, 0, 0, 0};
  double lo = INFINITY, hi = -INFINITY;
  karst_int_t n = 0;
  for (karst_int_t i = 0; i < t->n_rows; i++) {
    double v = t->values[i * t->n_cols + col];
    if (isnan(v) || !isfinite(v)) continue;
    n++;
    lo = fmin(lo, v);
    hi = fmax(hi, v);
  }
  karst_i_svg_begin(b, W, H, t->names[col]);
  if (n == 0) {
    karst_i_svg_text(b, W / 2, H / 2, "middle", "note", "undefined for every member");
    karst_i_svg_end(b);
    return;
  }
  int nb = (int)ceil(sqrt((double)n));
  if (nb < HIST_MIN_BINS) nb = HIST_MIN_BINS;
  if (nb > HIST_MAX_BINS) nb = HIST_MAX_BINS;
  double blo = lo, bhi = hi;
  if (bhi == blo) { /* one value: one bar centred on it */
    double w = fmax(fabs(blo) * 0.05, 0.5);
    blo -= w;
    bhi += w;
    nb = 1;
  }
  double xlo = blo, xhi = bhi;
  for (int s = 0; s < n_res; s++) {
    double v = res[s].rows[col].survey;
    if (isfinite(v)) {
      xlo = fmin(xlo, v);
      xhi = fmax(xhi, v);
    }
  }
  int *count = calloc((size_t)nb, sizeof *count);
  if (!count) {
    b->failed = 1;
    return;
  }
  int cmax = 0;
  for (karst_int_t i = 0; i < t->n_rows; i++) {
    double v = t->values[i * t->n_cols + col];
    if (isnan(v) || !isfinite(v)) continue;
    int k = (int)floor((v - blo) / (bhi - blo) * nb);
    if (k >= nb) k = nb - 1; /* the last bin is closed */
    if (k < 0) k = 0;
    if (++count[k] > cmax) cmax = count[k];
  }
  p.xmin = xlo;
  p.xmax = xhi;
  p.ymin = 0;
  p.ymax = cmax;
  karst_i_svg_axes(b, &p, 1, 5, 4, t->names[col], "members");
  const karst_compare_row_t *row = n_res > 0 ? &res[0].rows[col] : NULL;
  if (row && row->has_published) {
    double a = fmax(row->published_min, p.xmin), c = fmin(row->published_max, p.xmax);
    if (a < c)
      karst_i_svg_rect(b, karst_i_plot_px(&p, a), p.y,
                       karst_i_plot_px(&p, c) - karst_i_plot_px(&p, a), p.h, "#999999", NULL, 0.18);
    char txt[96], x1[32], x2[32];
    fmt_num(x1, sizeof x1, row->published_min);
    fmt_num(x2, sizeof x2, row->published_max);
    snprintf(txt, sizeof txt, "34 caves: %s – %s%s", x1, x2, a < c ? "" : " (off scale)");
    karst_i_svg_text(b, p.x + p.w - 2, p.y + 11, "end", "note", txt);
  }
  double bw = (bhi - blo) / nb;
  for (int k = 0; k < nb; k++) {
    double x0 = karst_i_plot_px(&p, blo + k * bw), x1 = karst_i_plot_px(&p, blo + (k + 1) * bw);
    double y0 = karst_i_plot_py(&p, count[k]);
    karst_i_svg_rect(b, x0, y0, x1 - x0, p.y + p.h - y0, "#4477AA", "#ffffff", 1);
  }
  for (int s = 0; s < n_res; s++) {
    double v = res[s].rows[col].survey;
    if (!isfinite(v)) continue;
    double x = karst_i_plot_px(&p, v);
    karst_i_svg_line(b, x, p.y, x, p.y + p.h, survey_colour, 2, "5 3");
  }
  free(count);
  karst_i_svg_end(b);
}

/* Length-weighted azimuth histogram of a network (horizontal length, azimuth clockwise from
 * north folded into [0, 180)), accumulated into bins. */
static void rose_accumulate(const karst_network_t *net, double *bins, int nb) {
  for (karst_int_t e = 0; e < net->n_edges; e++) {
    const double *a = net->xyz + 3 * net->edges[2 * e], *c = net->xyz + 3 * net->edges[2 * e + 1];
    double dx = c[0] - a[0], dy = c[1] - a[1], l2 = hypot(dx, dy);
    if (!(l2 > 0)) continue;
    double az = atan2(dx, dy) * 180.0 / M_PI; /* clockwise from +y */
    az = fmod(az + 360.0, 180.0);
    int k = (int)floor(az / ROSE_BIN_DEGREES);
    if (k >= nb) k = nb - 1;
    if (k < 0) k = 0;
    bins[k] += l2;
  }
}

static void plot_rose(karst_i_buf_t *b, const double *ens, const double *survey, int nb,
                      const char *survey_label) {
  const double W = 340, H = 340, cx = W / 2, cy = H / 2 + 6, R = 130;
  double emax = 0, smax = 0;
  for (int k = 0; k < nb; k++) {
    emax = fmax(emax, ens[k]);
    if (survey) smax = fmax(smax, survey[k]);
  }
  karst_i_svg_begin(b, W, H, "length-weighted orientation rose");
  for (int r = 1; r <= 4; r++)
    karst_i_svg_marker(b, cx, cy, R * r / 4.0, "none", "#dddddd");
  karst_i_svg_text(b, cx, cy - R - 6, "middle", "tick", "N");
  karst_i_svg_text(b, cx + R + 10, cy + 4, "middle", "tick", "E");
  karst_i_svg_text(b, cx, cy + R + 14, "middle", "tick", "S");
  karst_i_svg_text(b, cx - R - 10, cy + 4, "middle", "tick", "W");
  if (emax <= 0) {
    karst_i_svg_text(b, cx, cy, "middle", "note", "no horizontal conduits");
    karst_i_svg_end(b);
    return;
  }
  /* Each bin is drawn twice (az and az + 180), radius proportional to its weight. */
  for (int half = 0; half < 2; half++)
    for (int k = 0; k < nb; k++) {
      double r = R * ens[k] / emax, pts[2 * 7];
      double a0 = (half * 180.0 + k * ROSE_BIN_DEGREES) * M_PI / 180.0;
      double a1 = a0 + ROSE_BIN_DEGREES * M_PI / 180.0;
      pts[0] = cx;
      pts[1] = cy;
      for (int j = 0; j <= 5; j++) {
        double a = a0 + (a1 - a0) * j / 5.0;
        pts[2 + 2 * j] = cx + r * sin(a);
        pts[3 + 2 * j] = cy - r * cos(a);
      }
      karst_i_svg_polyline(b, pts, 7, "#ffffff", 0.5, "#4477AA", 1);
    }
  if (survey && smax > 0) {
    double pts[2 * 72];
    int m = 0;
    for (int half = 0; half < 2; half++)
      for (int k = 0; k < nb; k++) {
        double r = R * survey[k] / smax;
        for (int j = 0; j < 2; j++) {
          double a = (half * 180.0 + (k + j) * ROSE_BIN_DEGREES) * M_PI / 180.0;
          pts[2 * m] = cx + r * sin(a);
          pts[2 * m + 1] = cy - r * cos(a);
          m++;
        }
      }
    karst_i_svg_polyline(b, pts, m, survey_colour, 2, NULL, 1);
    char txt[300];
    snprintf(txt, sizeof txt, "outline: %s", survey_label);
    karst_i_svg_text(b, 4, H - 4, "start", "note", txt);
  }
  karst_i_svg_end(b);
}

/* Fraction of nodes of each degree 1..DEGREE_PLOT_MAX (the last pools the higher degrees). */
static void degree_accumulate(const karst_network_t *net, double *count) {
  karst_int_t *deg = calloc((size_t)(net->n_nodes > 0 ? net->n_nodes : 1), sizeof *deg);
  if (!deg) return;
  for (karst_int_t e = 0; e < net->n_edges; e++) {
    deg[net->edges[2 * e]]++;
    deg[net->edges[2 * e + 1]]++;
  }
  for (karst_int_t v = 0; v < net->n_nodes; v++) {
    karst_int_t d = deg[v];
    if (d < 1) continue;
    if (d > DEGREE_PLOT_MAX) d = DEGREE_PLOT_MAX;
    count[d] += 1;
  }
  free(deg);
}

static void plot_degrees(karst_i_buf_t *b, const double *ens, const double *survey,
                         const char *survey_label) {
  const double W = 340, H = 240;
  karst_i_plot_t p = {56, 14, W - 72, H - 62, 0.5, DEGREE_PLOT_MAX + 0.5, 0, 0};
  double se = 0, ss = 0, ymax = 0;
  for (int d = 1; d <= DEGREE_PLOT_MAX; d++) {
    se += ens[d];
    if (survey) ss += survey[d];
  }
  karst_i_svg_begin(b, W, H, "degree distribution");
  if (se <= 0) {
    karst_i_svg_text(b, W / 2, H / 2, "middle", "note", "no edges");
    karst_i_svg_end(b);
    return;
  }
  for (int d = 1; d <= DEGREE_PLOT_MAX; d++) {
    ymax = fmax(ymax, ens[d] / se);
    if (survey && ss > 0) ymax = fmax(ymax, survey[d] / ss);
  }
  p.ymax = ymax * 1.08; /* headroom so the tallest bar does not touch the frame */
  karst_i_svg_axes(b, &p, 0, 8, 5, "node degree (last bar: 8 or more)", "fraction of nodes");
  for (int d = 1; d <= DEGREE_PLOT_MAX; d++) {
    double x0 = karst_i_plot_px(&p, d - 0.35), x1 = karst_i_plot_px(&p, d + 0.35);
    double y0 = karst_i_plot_py(&p, ens[d] / se);
    karst_i_svg_rect(b, x0, y0, x1 - x0, p.y + p.h - y0, "#4477AA", NULL, 1);
    if (survey && ss > 0)
      karst_i_svg_marker(b, karst_i_plot_px(&p, d), karst_i_plot_py(&p, survey[d] / ss), 4,
                         survey_colour, "#ffffff");
  }
  if (survey && ss > 0) {
    char txt[300];
    snprintf(txt, sizeof txt, "dots: %s", survey_label);
    karst_i_svg_text(b, p.x + p.w - 2, p.y + 12, "end", "note", txt);
  }
  karst_i_svg_end(b);
}

/* Plan (axis 1 = y) or section (axis 1 = z) of a network, equal scale, coloured by tunnel type. */
static void plot_map(karst_i_buf_t *b, const karst_network_t *net, int axis, const char *title) {
  const double W = 420, H = 300;
  karst_i_plot_t p = {60, 12, W - 76, H - 56, 0, 0, 0, 0};
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (karst_int_t v = 0; v < net->n_nodes; v++) {
    double c[2] = {net->xyz[3 * v], net->xyz[3 * v + axis]};
    for (int j = 0; j < 2; j++) {
      lo[j] = fmin(lo[j], c[j]);
      hi[j] = fmax(hi[j], c[j]);
    }
  }
  karst_i_svg_begin(b, W, H, title);
  if (net->n_edges == 0 || !isfinite(lo[0])) {
    karst_i_svg_text(b, W / 2, H / 2, "middle", "note", "empty network");
    karst_i_svg_end(b);
    return;
  }
  /* Equal scale: widen the shorter data range to the aspect of the plot area. */
  double dx = fmax(hi[0] - lo[0], 1e-9), dy = fmax(hi[1] - lo[1], 1e-9);
  double s = fmin(p.w / dx, p.h / dy);
  double mx = (lo[0] + hi[0]) / 2, my = (lo[1] + hi[1]) / 2;
  p.xmin = mx - p.w / s / 2;
  p.xmax = mx + p.w / s / 2;
  p.ymin = my - p.h / s / 2;
  p.ymax = my + p.h / s / 2;
  karst_i_svg_axes(b, &p, 0, 6, 5, "x (m)", axis == 1 ? "y (m)" : "z (m)");
  karst_attr_t *type = karst_network_attr_find(net, KARST_ATTR_EDGE, "tunnel_type");
  /* One <path> per tunnel type keeps the page small. */
  for (int t = -1; t < KARST_TUNNEL_TYPE_COUNT; t++) {
    int any = 0;
    for (karst_int_t e = 0; e < net->n_edges; e++) {
      int et = type ? (int)type->data[e * type->ncomp] : -1;
      if (et < 0 || et >= KARST_TUNNEL_TYPE_COUNT) et = -1;
      if (et != t) continue;
      if (!any) {
        karst_i_buf_printf(b, "<path fill=\"none\" stroke=\"%s\" stroke-width=\"1.5\" d=\"",
                           t < 0 ? no_type_colour : tunnel_colour[t]);
        any = 1;
      }
      const double *a = net->xyz + 3 * net->edges[2 * e], *c = net->xyz + 3 * net->edges[2 * e + 1];
      karst_i_buf_printf(b, "M%.1f %.1fL%.1f %.1f", karst_i_plot_px(&p, a[0]),
                         karst_i_plot_py(&p, a[axis]), karst_i_plot_px(&p, c[0]),
                         karst_i_plot_py(&p, c[axis]));
    }
    if (any) karst_i_buf_puts(b, "\"/>\n");
  }
  karst_i_svg_end(b);
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
    "svg text{font-family:sans-serif}svg .tick{font-size:10px;fill:#333}"
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

/**
 * Write the report (see report.h) of the ensemble in @p ensemble_dir.
 * Reads DIR/ensemble.json, DIR/metrics.csv and the network.vtp of the first
 * members; writes @p path atomically. A member that cannot be read is named
 * in the page instead of its plot (the page is still written).
 * Time complexity: O(members × metrics log members + edges of the members read).
 */
karst_error_t karst_report_write(karst_ctx_t *ctx, const char *ensemble_dir, const char *path,
                                 const karst_report_options_t *opt) {
  karst_error_t err = KARST_SUCCESS;
  karst_report_options_t defaults;
  karst_ensemble_table_t table;
  karst_published_t pub;
  karst_compare_result_t *res = NULL;
  karst_i_buf_t b;
  karst_json_t *summary = NULL;
  int n_res = 0, have_pub = 0;
  char *jpath = NULL, *mpath = NULL, *versions = NULL;
  karst_network_t net;
  double rose[180 / ROSE_BIN_DEGREES] = {0}, srose[180 / ROSE_BIN_DEGREES] = {0};
  double deg[DEGREE_PLOT_MAX + 1] = {0}, sdeg[DEGREE_PLOT_MAX + 1] = {0};
  const int nrose = 180 / ROSE_BIN_DEGREES;
  char pubpath[1024];

  karst_ensemble_table_init(&table);
  karst_published_init(&pub);
  karst_i_buf_init(&b);
  karst_network_init(&net);
  if (!opt) {
    karst_report_options_init(&defaults);
    opt = &defaults;
  }
  jpath = karst_i_path_join(ensemble_dir, "ensemble.json");
  mpath = karst_i_path_join(ensemble_dir, "metrics.csv");
  versions = karst_versions_text();
  if (!jpath || !mpath || !versions) {
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
  if (!res) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  for (int s = 0; s < n_res; s++) {
    const karst_report_survey_t *sv = opt->n_surveys > 0 ? &opt->surveys[s] : NULL;
    err = karst_compare_compute(ctx, &table, sv ? sv->label : NULL, sv ? sv->names : NULL,
                                sv ? sv->values : NULL, sv ? sv->n_values : 0,
                                have_pub ? &pub : NULL, &res[s]);
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
  const char *labels[] = {"scenario file", "scenario hash (FNV-1a 64)", "base seed", "realisations",
                          "karst version"};
  karst_i_buf_puts(&b, "<tr><th class=\"l\">name</th><td class=\"l\">");
  karst_i_buf_escape(&b, name ? name : "–");
  karst_i_buf_puts(&b, "</td></tr>");
  for (int i = 0; i < 5; i++) {
    const char *v = json_scalar_text(karst_json_get(summary, keys[i]));
    karst_i_buf_printf(&b, "<tr><th class=\"l\">%s</th><td class=\"l\">", labels[i]);
    karst_i_buf_escape(&b, v ? v : "–");
    karst_i_buf_puts(&b, "</td></tr>");
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

  /* --- histograms --- */
  karst_i_buf_puts(&b, "<h2>Metrics of the members</h2>\n<p>Bars: members per bin. Dashed red "
                       "line: survey value. Grey band: range of the 34 published caves.</p>\n"
                       "<div class=\"grid\">\n");
  for (int c = 0; c < table.n_cols; c++) {
    karst_i_buf_puts(&b, "<figure>");
    plot_histogram(&b, &table, c, res, opt->n_surveys > 0 ? n_res : 0);
    karst_i_buf_puts(&b, "</figure>\n");
  }
  karst_i_buf_puts(&b, "</div>\n");

  /* --- member networks: rose, degree distribution, plan and section views --- */
  karst_int_t pooled = 0, nread = 0;
  karst_i_buf_t maps, problems;
  karst_i_buf_init(&maps);
  karst_i_buf_init(&problems);
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
    if (rerr) {
      karst_i_buf_puts(&problems, "<li>");
      karst_i_buf_escape(&problems, mctx.errmsg[0] ? mctx.errmsg : karst_strerror(rerr));
      karst_i_buf_puts(&problems, "</li>\n");
      free(vtp);
      continue;
    }
    free(vtp);
    pooled++;
    if (have_dens && karst_i_density_add(&dens, &net)) b.failed = 1;
    rose_accumulate(&net, rose, nrose);
    degree_accumulate(&net, deg);
    if (nread < opt->members_drawn) {
      char title[96];
      karst_i_buf_printf(&maps, "<h3>member %s (seed %" PRIu64 ")</h3><div class=\"grid\">", mname,
                         table.seed[r]);
      snprintf(title, sizeof title, "member %s, plan view (x-y)", mname);
      karst_i_buf_puts(&maps, "<figure>");
      plot_map(&maps, &net, 1, title);
      karst_i_buf_puts(&maps, "<figcaption>plan (x–y)</figcaption></figure><figure>");
      snprintf(title, sizeof title, "member %s, cross-section (x-z)", mname);
      plot_map(&maps, &net, 2, title);
      karst_i_buf_puts(&maps, "<figcaption>cross-section (x–z)</figcaption></figure></div>\n");
      nread++;
    }
  }
  const karst_report_survey_t *s0 = opt->n_surveys > 0 ? &opt->surveys[0] : NULL;
  if (s0) {
    rose_accumulate(&s0->net, srose, nrose);
    degree_accumulate(&s0->net, sdeg);
  }
  karst_i_buf_printf(&b,
                     "<h2>Orientation and degree</h2>\n<p>Pooled over the first %" PRId64
                     " members. Rose: conduit azimuths (clockwise from grid north, 10° bins, "
                     "drawn symmetrically), weighted by horizontal length.</p>\n"
                     "<div class=\"grid\"><figure>",
                     pooled);
  plot_rose(&b, rose, s0 ? srose : NULL, nrose, s0 ? s0->label : "");
  karst_i_buf_puts(&b, "<figcaption>length-weighted orientation rose</figcaption></figure>"
                       "<figure>");
  plot_degrees(&b, deg, s0 ? sdeg : NULL, s0 ? s0->label : "");
  karst_i_buf_puts(&b, "<figcaption>degree distribution (full graph)</figcaption></figure>"
                       "</div>\n<h2>Members: plan and cross-section</h2>\n<p class=\"legend\">");
  for (int t = 0; t < KARST_TUNNEL_TYPE_COUNT; t++)
    karst_i_buf_printf(&b, "<span><i class=\"sw\" style=\"background:%s\"></i>%s</span>",
                       tunnel_colour[t], karst_tunnel_type_name(t));
  karst_i_buf_printf(&b, "<span><i class=\"sw\" style=\"background:%s\"></i>no type</span></p>\n",
                     no_type_colour);
  if (have_dens && dens.conditioned) {
    karst_i_buf_printf(&b,
                       "<h2>Where the ensemble places the unexplored conduits</h2>\n<p>Plan view "
                       "of the %d members read: each %.0f m cell is coloured by the fraction of "
                       "members that have a simulated conduit (edge attribute "
                       "<code>observed</code> = 0) crossing it; the surveyed legs (observed = 1, "
                       "the same in every member) are drawn in red.</p>\n<figure id=\"density\">",
                       dens.members, dens.cell);
    karst_i_density_plot(&b, &dens, "plan-view density of simulated conduits", survey_colour);
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
  karst_i_buf_destroy(&maps);
  karst_i_buf_destroy(&problems);

  /* --- versions --- */
  karst_i_buf_puts(&b, "<h2>Software</h2>\n<pre>");
  karst_i_buf_escape(&b, versions);
  karst_i_buf_puts(&b, "</pre>\n");
  if (have_pub) {
    karst_i_buf_printf(&b, "<p>Published ranges: %d caves read from ", pub.n_caves);
    karst_i_buf_escape(&b, pubpath);
    karst_i_buf_puts(&b, ".</p>\n");
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
  karst_network_destroy(&net);
  karst_i_buf_destroy(&b);
  karst_published_destroy(&pub);
  karst_ensemble_table_destroy(&table);
  karst_json_free(summary);
  free(versions);
  free(mpath);
  free(jpath);
  return err;
}
