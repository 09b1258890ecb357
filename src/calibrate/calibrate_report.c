/* DIR/report.html of karst calibrate (calibrate_internal.h): one self-contained page (inline SVG
 * and CSS, no scripts) with the settings, the posterior of every varied parameter (weighted
 * histograms, a pair plot), acceptance and tolerance per generation, and the metrics of the
 * best-fit ensemble against the survey and the 34 caves of Collon et al. 2017. The plots use the
 * SVG writer of src/report/ (svg_internal.h); the page holds no timing, so a resumed, threaded or
 * MPI run writes the same bytes. */
#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "calibrate/calibrate_internal.h"
#include "karst/compare.h"
#include "karst/metrics.h"
#include "karst/report.h"
#include "karst/version.h"
#include "report/svg_internal.h"

/** Histogram bins of a continuous parameter over its prior range. */
#define PARAM_BINS 20
/** An integer parameter gets one bar per value when it has at most this many values. */
#define INTEGER_BAR_MAX 40
/** Bins of a metric's histograms (prior predictive and best fit share them). */
#define METRIC_BINS 24
/** Side of one cell of the pair plot (pixels). */
#define PAIR_CELL 190
/** Pixels left of each pair-plot cell for its y tick labels. */
#define PAIR_TICK_ROOM 26
/** Extra pixels below each pair-plot cell, so its x tick labels stay clear of the row below. */
#define PAIR_TICK_GAP 14

static const char *const posterior_colour = "#4477AA";
static const char *const prior_colour = "#BBBBBB";
static const char *const survey_colour = "#C00000";

static const char *const css =
    "body{font-family:sans-serif;margin:1.5em;color:#222;max-width:1400px}"
    "h1{font-size:1.5em}h2{font-size:1.2em;margin-top:1.6em;border-bottom:1px solid #ccc}"
    "table{border-collapse:collapse;font-size:0.85em}td,th{border:1px solid #ccc;padding:2px 6px;"
    "text-align:right}th{background:#f0f0f0}td.l,th.l{text-align:left}tr.out td{background:#fde0dc}"
    ".grid{display:flex;flex-wrap:wrap;gap:10px}figure{margin:0}figcaption{font-size:0.8em}"
    "svg text{font-family:sans-serif}svg .tick{font-size:10px;fill:#333}"
    "svg .axis{font-size:11px;fill:#111}svg .note{font-size:10px;fill:#555}"
    "pre{background:#f7f7f7;padding:0.5em;font-size:0.85em}p.small{font-size:0.85em}";

static void fmt(char *out, size_t size, double v) {
  if (isnan(v))
    snprintf(out, size, "–");
  else if (isinf(v))
    snprintf(out, size, v > 0 ? "∞" : "−∞");
  else
    snprintf(out, size, "%.4g", v);
}

static void cell(karst_i_buf_t *b, double v) {
  char s[64];
  fmt(s, sizeof s, v);
  karst_i_buf_printf(b, "<td>%s</td>", s);
}

/* A parameter's plotting coordinate: log10 of the value for a log-uniform prior. */
static double coord(const karst_calibrate_param_t *p, double v) {
  return p->prior == KARST_PRIOR_LOG_UNIFORM ? log10(v) : v;
}

/* The unit of a scenario key, from the last part of its path (docs/scenario.md): a count, metres,
 * degrees, or, for the keys without one (weights, ratios, θ), "1" (dimensionless, as SI writes it);
 * a key this list does not know is labelled with the scenario's own unit. */
static const char *param_unit(const char *key) {
  const char *last = strrchr(key, '.');
  last = last ? last + 1 : key;
  static const char *const count[] = {"steps", "points", "k", "realisations"};
  static const char *const metres[] = {
      "reach",          "elevation",      "radius",           "fill_radius",
      "feature_radius", "epikarst_depth", "water_table_band", "feature_band"};
  static const char *const degrees[] = {"dip", "dip_direction", "vertical_angle"};
  static const char *const none[] = {
      "tortuosity",   "gamma",      "reuse",  "w0",          "horizon",      "fracture",
      "permeability", "prescribed", "weight", "reach_ratio", "points_ratio", "dead_end_fraction"};
  for (size_t i = 0; i < sizeof count / sizeof *count; i++)
    if (!strcmp(last, count[i])) return "count";
  for (size_t i = 0; i < sizeof metres / sizeof *metres; i++)
    if (!strcmp(last, metres[i])) return "m";
  for (size_t i = 0; i < sizeof degrees / sizeof *degrees; i++)
    if (!strcmp(last, degrees[i])) return "degrees";
  for (size_t i = 0; i < sizeof none / sizeof *none; i++)
    if (!strcmp(last, none[i])) return "1";
  return "the scenario's unit";
}

static void axis_label(const karst_calibrate_param_t *p, char *out, size_t size) {
  if (p->prior == KARST_PRIOR_LOG_UNIFORM)
    snprintf(out, size, "log10 %s (%s)", p->key, param_unit(p->key));
  else
    snprintf(out, size, "%s (%s)", p->key, param_unit(p->key));
}

/* The plotted range of a parameter: its prior (integers: value ± 1/2). */
static void param_range(const karst_calibrate_param_t *p, double *lo, double *hi) {
  if (p->is_integer) {
    *lo = coord(p, p->lo) - (p->prior == KARST_PRIOR_LOG_UNIFORM ? 0 : 0.5);
    *hi = coord(p, p->hi) + (p->prior == KARST_PRIOR_LOG_UNIFORM ? 0 : 0.5);
  } else {
    *lo = coord(p, p->lo);
    *hi = coord(p, p->hi);
  }
}

/* Weighted histogram of the final population of parameter @p k, with the flat prior, the
 * median and the 90 % interval. */
static void plot_param(karst_i_buf_t *b, const karst_i_calib_view_t *v, int k, double W, double H,
                       int with_axes_titles) {
  const karst_calibrate_param_t *p = &v->params[k];
  const karst_i_calib_history_t *h = v->hist;
  karst_int_t base = (karst_int_t)(h->n_gen - 1) * h->n_keep;
  karst_i_plot_t pl = {with_axes_titles ? 56 : 34,
                       10,
                       W - (with_axes_titles ? 70 : 44),
                       H - (with_axes_titles ? 56 : 30),
                       0,
                       0,
                       0,
                       0};
  double lo, hi;
  param_range(p, &lo, &hi);
  int nb = PARAM_BINS, per_value = 0;
  if (p->is_integer && p->prior == KARST_PRIOR_UNIFORM && p->hi - p->lo + 1 <= INTEGER_BAR_MAX) {
    nb = (int)(p->hi - p->lo + 1);
    per_value = 1;
  }
  double bins[INTEGER_BAR_MAX > PARAM_BINS ? INTEGER_BAR_MAX : PARAM_BINS] = {0};
  for (karst_int_t j = 0; j < h->n_keep; j++) {
    double x = coord(p, h->values[(base + j) * v->d + k]);
    int i = (int)floor((x - lo) / (hi - lo) * nb);
    if (i >= nb) i = nb - 1;
    if (i < 0) i = 0;
    bins[i] += h->weights[base + j];
  }
  double bw = (hi - lo) / nb, ymax = 1.0 / nb; /* the prior's mass per bin (flat in coord) */
  for (int i = 0; i < nb; i++)
    ymax = fmax(ymax, bins[i]);
  char title[300], xl[300];
  axis_label(p, xl, sizeof xl);
  snprintf(title, sizeof title, "posterior of %s", p->key);
  karst_i_svg_begin(b, W, H, title);
  pl.xmin = lo;
  pl.xmax = hi;
  pl.ymin = 0;
  pl.ymax = ymax * 1.08;
  karst_i_svg_axes(b, &pl, 0, 5, 4, with_axes_titles ? xl : NULL,
                   with_axes_titles ? "posterior mass (fraction)" : NULL);
  double a = karst_i_plot_px(&pl, coord(p, v->low[k])),
         c = karst_i_plot_px(&pl, coord(p, v->high[k]));
  if (per_value) {
    a = karst_i_plot_px(&pl, coord(p, v->low[k]) - 0.5);
    c = karst_i_plot_px(&pl, coord(p, v->high[k]) + 0.5);
  }
  karst_i_svg_rect(b, a, pl.y, c - a, pl.h, posterior_colour, NULL, 0.12);
  for (int i = 0; i < nb; i++) {
    double x0 = karst_i_plot_px(&pl, lo + i * bw), x1 = karst_i_plot_px(&pl, lo + (i + 1) * bw);
    double y0 = karst_i_plot_py(&pl, bins[i]);
    karst_i_svg_rect(b, x0, y0, x1 - x0, pl.y + pl.h - y0, posterior_colour, "#ffffff", 1);
  }
  double yp = karst_i_plot_py(&pl, 1.0 / nb);
  karst_i_svg_line(b, pl.x, yp, pl.x + pl.w, yp, "#777777", 1, "4 3");
  double xm = karst_i_plot_px(&pl, coord(p, v->median[k]));
  karst_i_svg_line(b, xm, pl.y, xm, pl.y + pl.h, "#000000", 1.5, NULL);
  karst_i_svg_end(b);
}

/* Weighted Pearson correlation of parameters @p i and @p j (plot coordinates). */
static double weighted_corr(const karst_i_calib_view_t *v, int i, int j) {
  const karst_i_calib_history_t *h = v->hist;
  karst_int_t base = (karst_int_t)(h->n_gen - 1) * h->n_keep;
  double mi = 0, mj = 0, sij = 0, sii = 0, sjj = 0;
  for (karst_int_t r = 0; r < h->n_keep; r++) {
    double w = h->weights[base + r];
    mi += w * coord(&v->params[i], h->values[(base + r) * v->d + i]);
    mj += w * coord(&v->params[j], h->values[(base + r) * v->d + j]);
  }
  for (karst_int_t r = 0; r < h->n_keep; r++) {
    double w = h->weights[base + r];
    double a = coord(&v->params[i], h->values[(base + r) * v->d + i]) - mi;
    double c = coord(&v->params[j], h->values[(base + r) * v->d + j]) - mj;
    sij += w * a * c;
    sii += w * a * a;
    sjj += w * c * c;
  }
  return sii > 0 && sjj > 0 ? sij / sqrt(sii * sjj) : NAN;
}

/* The pair plot: weighted histograms on the diagonal, the particles (opacity by weight) below
 * it, the weighted correlation above it. */
static void plot_pairs(karst_i_buf_t *b, const karst_i_calib_view_t *v) {
  int d = v->d;
  const double C = PAIR_CELL, M = 70;
  const karst_i_calib_history_t *h = v->hist;
  karst_int_t base = (karst_int_t)(h->n_gen - 1) * h->n_keep;
  double wmax = 0;
  for (karst_int_t r = 0; r < h->n_keep; r++)
    wmax = fmax(wmax, h->weights[base + r]);
  karst_i_svg_begin(b, M + d * C, M + d * C, "pair plot of the posterior");
  for (int i = 0; i < d; i++) {
    for (int j = 0; j < d; j++) {
      double x0 = M + j * C, y0 = i * C + 4;
      if (i == j) {
        /* the same plot area as the other cells: x0 + PAIR_TICK_ROOM .. x0 + C - 10, y0 ..
         * y0 + C - 20 - PAIR_TICK_GAP (plot_param's margins: 34 left, 10 top, 20 bottom) */
        karst_i_buf_printf(b, "<g transform=\"translate(%.2f %.2f)\">", x0 + PAIR_TICK_ROOM - 34,
                           y0 - 10);
        plot_param(b, v, i, C + 34 - PAIR_TICK_ROOM, C + 10 - PAIR_TICK_GAP, 0);
        karst_i_buf_puts(b, "</g>\n");
        continue;
      }
      /* room on the left of each cell for its y tick labels, so that they do not run into the
       * x tick labels of the cell beside it */
      karst_i_plot_t pl = {
          x0 + PAIR_TICK_ROOM, y0, C - 10 - PAIR_TICK_ROOM, C - 20 - PAIR_TICK_GAP, 0, 0, 0, 0};
      param_range(&v->params[j], &pl.xmin, &pl.xmax);
      param_range(&v->params[i], &pl.ymin, &pl.ymax);
      if (i < j) {
        char t[64], s[32];
        fmt(s, sizeof s, weighted_corr(v, i, j));
        snprintf(t, sizeof t, "r = %s", s);
        karst_i_svg_rect(b, pl.x, pl.y, pl.w, pl.h, "none", "#dddddd", 1);
        karst_i_svg_text(b, pl.x + pl.w / 2, pl.y + pl.h / 2, "middle", "axis", t);
        continue;
      }
      karst_i_svg_axes(b, &pl, 0, 4, 4, NULL, NULL);
      for (karst_int_t r = 0; r < h->n_keep; r++) {
        double w = h->weights[base + r];
        double px = karst_i_plot_px(&pl, coord(&v->params[j], h->values[(base + r) * d + j]));
        double py = karst_i_plot_py(&pl, coord(&v->params[i], h->values[(base + r) * d + i]));
        karst_i_buf_printf(b,
                           "<circle cx=\"%.2f\" cy=\"%.2f\" r=\"2.5\" fill=\"%s\" "
                           "fill-opacity=\"%.3f\"/>\n",
                           px, py, posterior_colour, wmax > 0 ? 0.15 + 0.85 * w / wmax : 1);
      }
    }
    char lab[300];
    axis_label(&v->params[i], lab, sizeof lab);
    karst_i_svg_text(b, M + i * C + PAIR_TICK_ROOM + (C - 10 - PAIR_TICK_ROOM) / 2, d * C + 30,
                     "middle", "axis", lab);
    karst_i_buf_printf(b, "<g transform=\"translate(%.2f %.2f) rotate(-90)\">", 14.0,
                       i * C + 4 + (C - 20 - PAIR_TICK_GAP) / 2);
    karst_i_svg_text(b, 0, 0, "middle", "axis", lab);
    karst_i_buf_puts(b, "</g>\n");
  }
  karst_i_svg_end(b);
}

/* A value per generation (acceptance or tolerance) as a line with markers. */
static void plot_generations(karst_i_buf_t *b, const karst_i_calib_view_t *v, int tolerance) {
  const double W = 340, H = 220;
  const karst_i_calib_history_t *h = v->hist;
  karst_i_plot_t pl = {56, 12, W - 72, H - 58, 0, h->n_gen > 1 ? h->n_gen - 1 : 1, 0, 0};
  double ymax = 0;
  int first = tolerance ? 0 : 1, n = 0;
  double *xy = malloc(2 * (size_t)(h->n_gen > 0 ? h->n_gen : 1) * sizeof *xy);
  if (!xy) {
    b->failed = 1;
    return;
  }
  for (int g = first; g < h->n_gen; g++) {
    double y = tolerance ? h->gen[g].tolerance : h->gen[g].acceptance;
    if (isfinite(y)) ymax = fmax(ymax, y);
  }
  karst_i_svg_begin(b, W, H, tolerance ? "tolerance per generation" : "acceptance per generation");
  pl.ymax = tolerance ? (ymax > 0 ? ymax * 1.05 : 1) : 1;
  karst_i_svg_axes(b, &pl, 0, h->n_gen < 8 ? (h->n_gen > 1 ? h->n_gen : 2) : 8, 5,
                   "generation (index)",
                   tolerance ? "tolerance ε (1)" : "acceptance rate p_acc (fraction)");
  for (int g = first; g < h->n_gen; g++) {
    double y = tolerance ? h->gen[g].tolerance : h->gen[g].acceptance;
    if (!isfinite(y)) continue;
    xy[2 * n] = karst_i_plot_px(&pl, g);
    xy[2 * n + 1] = karst_i_plot_py(&pl, y);
    n++;
  }
  karst_i_svg_polyline(b, xy, n, posterior_colour, 1.5, NULL, 0);
  for (int i = 0; i < n; i++)
    karst_i_svg_marker(b, xy[2 * i], xy[2 * i + 1], 3, posterior_colour, "#ffffff");
  if (!tolerance && v->opt->min_acceptance > 0) {
    double y = karst_i_plot_py(&pl, v->opt->min_acceptance);
    karst_i_svg_line(b, pl.x, y, pl.x + pl.w, y, "#777777", 1, "4 3");
    karst_i_svg_text(b, pl.x + pl.w - 2, y - 3, "end", "note", "stopping rule");
  }
  if (n == 0) karst_i_svg_text(b, W / 2, H / 2, "middle", "note", "no generation after the prior");
  free(xy);
  karst_i_svg_end(b);
}

/* One metric: the prior predictive (generation 0, grey), the best-fit ensemble (blue), the
 * survey (red dashed line) and the 34-cave range (grey band). */
static void plot_fit(karst_i_buf_t *b, const karst_i_calib_view_t *v, const char *name,
                     double survey, const karst_published_range_t *pub) {
  const double W = 300, H = 200;
  karst_i_plot_t pl = {56, 12, W - 70, H - 58, 0, 0, 0, 0};
  const karst_ensemble_table_t *tabs[2] = {v->prior, v->best};
  int cols[2] = {tabs[0] ? karst_ensemble_table_column(tabs[0], name) : -1,
                 tabs[1] ? karst_ensemble_table_column(tabs[1], name) : -1};
  double lo = INFINITY, hi = -INFINITY;
  for (int t = 0; t < 2; t++)
    for (karst_int_t r = 0; cols[t] >= 0 && r < tabs[t]->n_rows; r++) {
      double x = tabs[t]->values[r * tabs[t]->n_cols + cols[t]];
      if (isfinite(x)) lo = fmin(lo, x), hi = fmax(hi, x);
    }
  if (isfinite(survey)) lo = fmin(lo, survey), hi = fmax(hi, survey);
  karst_i_svg_begin(b, W, H, name);
  if (!(lo <= hi)) {
    karst_i_svg_text(b, W / 2, H / 2, "middle", "note", "undefined for every member");
    karst_i_svg_end(b);
    return;
  }
  if (hi == lo) {
    double w = fmax(fabs(lo) * 0.05, 0.5);
    lo -= w;
    hi += w;
  }
  double frac[2][METRIC_BINS] = {{0}}, ymax = 0;
  for (int t = 0; t < 2; t++) {
    karst_int_t n = 0;
    for (karst_int_t r = 0; cols[t] >= 0 && r < tabs[t]->n_rows; r++) {
      double x = tabs[t]->values[r * tabs[t]->n_cols + cols[t]];
      if (!isfinite(x)) continue;
      int i = (int)floor((x - lo) / (hi - lo) * METRIC_BINS);
      if (i >= METRIC_BINS) i = METRIC_BINS - 1;
      if (i < 0) i = 0;
      frac[t][i] += 1;
      n++;
    }
    for (int i = 0; i < METRIC_BINS; i++) {
      if (n) frac[t][i] /= (double)n;
      ymax = fmax(ymax, frac[t][i]);
    }
  }
  pl.xmin = lo;
  pl.xmax = hi;
  pl.ymin = 0;
  pl.ymax = ymax > 0 ? ymax * 1.08 : 1;
  char xtitle[160];
  snprintf(xtitle, sizeof xtitle, "%s (1)", name);
  int nf = 0;
  const karst_metric_field_t *mf = karst_metric_fields(&nf);
  for (int f = 0; f < nf; f++)
    if (!strcmp(mf[f].key, name) && mf[f].unit && *mf[f].unit && strcmp(mf[f].unit, "1"))
      snprintf(xtitle, sizeof xtitle, "%s (%s)", name, mf[f].unit);
  karst_i_svg_axes(b, &pl, 1, 5, 4, xtitle, "members (fraction)");
  if (pub) {
    double a = fmax(pub->min, pl.xmin), c = fmin(pub->max, pl.xmax);
    if (a < c)
      karst_i_svg_rect(b, karst_i_plot_px(&pl, a), pl.y,
                       karst_i_plot_px(&pl, c) - karst_i_plot_px(&pl, a), pl.h, "#999999", NULL,
                       0.18);
    char txt[96], x1[32], x2[32];
    fmt(x1, sizeof x1, pub->min);
    fmt(x2, sizeof x2, pub->max);
    snprintf(txt, sizeof txt, "34 caves: %s – %s%s", x1, x2, a < c ? "" : " (off scale)");
    karst_i_svg_text(b, pl.x + pl.w - 2, pl.y + 11, "end", "note", txt);
  }
  double bw = (hi - lo) / METRIC_BINS;
  for (int t = 0; t < 2; t++)
    for (int i = 0; i < METRIC_BINS; i++) {
      if (frac[t][i] <= 0) continue;
      double x0 = karst_i_plot_px(&pl, lo + i * bw), x1 = karst_i_plot_px(&pl, lo + (i + 1) * bw);
      double y0 = karst_i_plot_py(&pl, frac[t][i]);
      karst_i_svg_rect(b, x0, y0, x1 - x0, pl.y + pl.h - y0, t ? posterior_colour : prior_colour,
                       "#ffffff", t ? 0.75 : 1);
    }
  if (isfinite(survey)) {
    double x = karst_i_plot_px(&pl, survey);
    karst_i_svg_line(b, x, pl.y, x, pl.y + pl.h, survey_colour, 2, "5 3");
  }
  karst_i_svg_end(b);
}

static const char *prior_name(const karst_calibrate_param_t *p) {
  return p->prior == KARST_PRIOR_LOG_UNIFORM ? "log-uniform" : "uniform";
}

/**
 * Write the calibration report to @p path (atomically), see the file comment.
 * Time complexity: O(G N_α d + N_α d² + members × metrics).
 */
karst_error_t karst_i_calibrate_report(karst_ctx_t *ctx, const char *path,
                                       const karst_i_calib_view_t *v) {
  karst_error_t err = KARST_SUCCESS;
  karst_i_buf_t b;
  karst_i_buf_init(&b);
  karst_published_t pub;
  karst_published_init(&pub);
  int have_pub = 0;
  char pubpath[4096] = "", *versions = karst_versions_text();
  karst_compare_result_t cmp;
  karst_compare_result_init(&cmp);
  const karst_calibrate_options_t *o = v->opt;
  const karst_i_calib_history_t *h = v->hist;
  const karst_calibrate_generation_t *last = &h->gen[h->n_gen - 1];
  if (!versions) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  {
    karst_ctx_t quiet = *ctx;
    if (o->published_path) snprintf(pubpath, sizeof pubpath, "%s", o->published_path);
    if ((o->published_path ||
         karst_published_locate(&quiet, pubpath, sizeof pubpath) == KARST_SUCCESS) &&
        karst_published_read(&quiet, pubpath, &pub) == KARST_SUCCESS)
      have_pub = 1;
    else
      karst_log(ctx, KARST_LOG_WARNING, "calibration report without the 34-cave ranges: %s",
                quiet.errmsg);
  }

  karst_i_buf_puts(&b, "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                       "<title>karst calibration report</title><style>");
  karst_i_buf_puts(&b, css);
  karst_i_buf_puts(&b, "</style></head><body>\n<h1>karst calibration report</h1>\n");

  /* --- settings --- */
  karst_i_buf_puts(&b, "<h2>Calibration</h2>\n<table>");
  const char *labels[] = {"scenario", "survey"};
  const char *values[] = {o->scenario_path, o->survey_path};
  for (int i = 0; i < 2; i++) {
    karst_i_buf_printf(&b, "<tr><th class=\"l\">%s</th><td class=\"l\">", labels[i]);
    karst_i_buf_escape(&b, values[i]);
    karst_i_buf_puts(&b, "</td></tr>");
  }
  karst_i_buf_printf(&b,
                     "<tr><th class=\"l\">base seed</th><td class=\"l\">%" PRIu64 "</td></tr>"
                     "<tr><th class=\"l\">particles per generation N</th><td class=\"l\">%" PRId64
                     "</td></tr><tr><th class=\"l\">population N<sub>α</sub> (α = %g)</th>"
                     "<td class=\"l\">%" PRId64 "</td></tr>"
                     "<tr><th class=\"l\">generations after the prior sample</th><td "
                     "class=\"l\">%d (%s)</td></tr>"
                     "<tr><th class=\"l\">final tolerance ε</th><td class=\"l\">%.4g</td></tr>"
                     "</table>\n",
                     o->seed, o->particles, o->alpha, h->n_keep, h->n_gen - 1,
                     v->stop == KARST_CALIBRATE_STOP_ACCEPTANCE
                         ? "stopped: acceptance at or below the minimum"
                         : "the most generations asked for",
                     last->tolerance);
  karst_i_buf_printf(
      &b,
      "<p>Approximate Bayesian computation by sequential Monte Carlo: the adaptive population "
      "Monte Carlo ABC of Lenormand, Jabot &amp; Deffuant (2013, Algorithm 4), with the "
      "importance weights and the Gaussian perturbation kernel (variance twice the weighted "
      "variance of the population, truncated to the prior) of Beaumont et al. (2009). "
      "Generation 0 simulates N particles from the prior and keeps the N<sub>α</sub> closest; "
      "each later generation simulates N − N<sub>α</sub> particles moved from the population "
      "and keeps the N<sub>α</sub> closest of old and new, so the tolerance ε (the largest "
      "distance kept) never increases. Acceptance p<sub>acc</sub>: the fraction of a "
      "generation's particles closer than the previous ε; the run stops when it falls to %g "
      "or after the most generations.</p>\n",
      o->min_acceptance);
  karst_i_buf_puts(&b, "<p>Distance: the Euclidean norm of (member − survey) / scale over the "
                       "metrics below, the scale being the spread of the metric over the "
                       "prior sample (median absolute deviation × 1.4826, or the standard "
                       "deviation when that is 0).</p>\n<table><tr><th class=\"l\">metric</th>"
                       "<th>survey</th><th>scale</th><th class=\"l\">scale from</th></tr>");
  for (int k = 0; k < v->n_sel; k++) {
    karst_i_buf_puts(&b, "<tr><td class=\"l\">");
    karst_i_buf_escape(&b, v->metric[k]);
    karst_i_buf_puts(&b, "</td>");
    cell(&b, v->survey[k]);
    cell(&b, v->scale[k]);
    karst_i_buf_printf(&b, "<td class=\"l\">%s</td></tr>",
                       isnan(v->scale[k])   ? "constant over the prior: not used"
                       : v->scale_is_mad[k] ? "MAD × 1.4826"
                                            : "standard deviation");
  }
  karst_i_buf_puts(&b, "</table>\n");

  /* --- posterior --- */
  karst_i_buf_puts(&b, "<h2>Posterior</h2>\n<p>The weighted population of the last generation. "
                       "Median and 90 % credible interval: weighted 5, 50 and 95 % quantiles "
                       "(inverse of the weighted distribution function). best.yaml holds the "
                       "medians.</p>\n<table><tr><th class=\"l\">parameter</th><th "
                       "class=\"l\">prior</th><th>low</th><th>high</th><th>scenario file</th>"
                       "<th>median (best.yaml)</th><th>5 %</th><th>95 %</th></tr>");
  for (int k = 0; k < v->d; k++) {
    const karst_calibrate_param_t *p = &v->params[k];
    karst_i_buf_puts(&b, "<tr><td class=\"l\">");
    karst_i_buf_escape(&b, p->key);
    karst_i_buf_printf(&b, "</td><td class=\"l\">%s%s</td>", prior_name(p),
                       p->is_integer ? ", integer" : "");
    cell(&b, p->lo);
    cell(&b, p->hi);
    karst_i_buf_puts(&b, "<td>");
    karst_i_buf_escape(&b, v->file_value[k][0] ? v->file_value[k] : "default");
    karst_i_buf_puts(&b, "</td>");
    cell(&b, v->median[k]);
    cell(&b, v->low[k]);
    cell(&b, v->high[k]);
    karst_i_buf_puts(&b, "</tr>");
  }
  karst_i_buf_puts(&b, "</table>\n<p class=\"small\">Bars: posterior mass per bin. Dashed line: "
                       "the prior. Black line: median. Shaded: 90 % interval. Log-uniform "
                       "parameters are plotted against log10 of the value.</p>\n<div "
                       "class=\"grid\">");
  for (int k = 0; k < v->d; k++) {
    karst_i_buf_puts(&b, "<figure>");
    plot_param(&b, v, k, 300, 210, 1);
    karst_i_buf_puts(&b, "</figure>");
  }
  karst_i_buf_puts(&b, "</div>\n");
  if (v->d >= 2) {
    karst_i_buf_puts(&b, "<h2>Pairs</h2>\n<p class=\"small\">Below the diagonal: the particles "
                         "of the last generation (darker: heavier). Above: the weighted "
                         "correlation.</p>\n<figure>");
    plot_pairs(&b, v);
    karst_i_buf_puts(&b, "</figure>\n");
  }

  /* --- generations --- */
  karst_i_buf_puts(&b, "<h2>Generations</h2>\n<div class=\"grid\"><figure>");
  plot_generations(&b, v, 0);
  karst_i_buf_puts(&b, "</figure><figure>");
  plot_generations(&b, v, 1);
  karst_i_buf_puts(&b, "</figure></div>\n<table><tr><th>generation</th><th>simulations</th>"
                       "<th>accepted</th><th>acceptance</th><th>undefined metric</th>"
                       "<th>tolerance ε</th><th>effective sample size</th></tr>");
  for (int g = 0; g < h->n_gen; g++) {
    const karst_calibrate_generation_t *x = &h->gen[g];
    karst_i_buf_printf(&b, "<tr><td>%d</td><td>%" PRId64 "</td>", x->generation, x->simulations);
    if (g > 0)
      karst_i_buf_printf(&b, "<td>%" PRId64 "</td>", x->accepted);
    else
      karst_i_buf_puts(&b, "<td>–</td>");
    cell(&b, x->acceptance);
    karst_i_buf_printf(&b, "<td>%" PRId64 "</td>", x->undefined);
    cell(&b, x->tolerance);
    cell(&b, x->ess);
    karst_i_buf_puts(&b, "</tr>");
  }
  karst_i_buf_puts(&b, "</table>\n");

  /* --- fit --- */
  karst_i_buf_puts(&b, "<h2>Fit</h2>\n");
  if (v->best) {
    const char *names[KARST_CALIBRATE_MAX_METRICS];
    for (int k = 0; k < v->n_sel; k++)
      names[k] = v->metric[k];
    err = karst_compare_compute(ctx, v->best, o->survey_path, names, v->survey, v->n_sel,
                                have_pub ? &pub : NULL, &cmp);
    if (err) goto cleanup;
    karst_i_buf_printf(&b,
                       "<p>The ensemble of best.yaml (%" PRId64 " members, base seed %" PRIu64
                       ", in best/) against the survey and the "
                       "34 caves of Collon et al. 2017 (corrected 2021). Percentile of the "
                       "survey: 100 × (members ≤ survey) / n.</p>\n",
                       v->best->n_rows, o->seed);
    karst_i_buf_puts(&b, "<table><tr><th class=\"l\">metric</th><th>survey</th><th>best-fit "
                         "mean</th><th>p5</th><th>p95</th><th>survey percentile</th><th>34 "
                         "caves min</th><th>34 caves max</th></tr>");
    for (int k = 0; k < v->n_sel; k++) {
      const karst_compare_row_t *row = NULL;
      for (int i = 0; i < cmp.n_rows; i++)
        if (!strcmp(cmp.rows[i].metric, v->metric[k])) row = &cmp.rows[i];
      if (!row) continue;
      karst_i_buf_printf(&b, "<tr%s><td class=\"l\">", row->outside ? " class=\"out\"" : "");
      karst_i_buf_escape(&b, row->metric);
      karst_i_buf_puts(&b, "</td>");
      cell(&b, v->survey[k]);
      cell(&b, row->ens.mean);
      cell(&b, row->ens.p05);
      cell(&b, row->ens.p95);
      cell(&b, row->percentile);
      cell(&b, row->has_published ? row->published_min : NAN);
      cell(&b, row->has_published ? row->published_max : NAN);
      karst_i_buf_puts(&b, "</tr>");
    }
    karst_i_buf_puts(&b, "</table>\n<p class=\"small\">Highlighted: the survey lies outside the "
                         "5–95 % band of the best-fit ensemble.</p>\n");
  } else {
    karst_i_buf_puts(&b, "<p>No best-fit ensemble was run (--best-members 0).</p>\n");
  }
  karst_i_buf_puts(&b, "<p class=\"small\">Grey bars: the prior sample (generation 0). Blue "
                       "bars: the best-fit ensemble. Dashed red line: the survey. Grey band: "
                       "the range of the 34 caves.</p>\n<div class=\"grid\">");
  for (int k = 0; k < v->n_sel; k++) {
    karst_i_buf_puts(&b, "<figure>");
    plot_fit(&b, v, v->metric[k], v->survey[k],
             have_pub ? karst_published_find(&pub, v->metric[k]) : NULL);
    karst_i_buf_puts(&b, "</figure>");
  }
  karst_i_buf_puts(&b, "</div>\n<h2>Software</h2>\n<pre>");
  karst_i_buf_escape(&b, versions);
  karst_i_buf_puts(&b, "</pre>\n");
  if (have_pub) {
    karst_i_buf_printf(&b, "<p class=\"small\">Published ranges: %d caves read from ", pub.n_caves);
    karst_i_buf_escape(&b, pubpath);
    karst_i_buf_puts(&b, ".</p>\n");
  }
  karst_i_buf_puts(&b, "</body></html>\n");
  err = karst_i_buf_write_file(ctx, &b, path);
cleanup:
  karst_compare_result_destroy(&cmp);
  karst_published_destroy(&pub);
  karst_i_buf_destroy(&b);
  free(versions);
  return err;
}
