/* Histograms, the orientation rose and the degree distribution of the report
 * (src/report/report_internal.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "karst/metrics.h"
#include "karst/palette.h"
#include "report/report_internal.h"

/** Histogram bins: ceil(sqrt(n)) clamped to [HIST_MIN_BINS, HIST_MAX_BINS] (square-root rule);
 *  whole-number columns spanning fewer than HIST_MAX_BINS values get one bin per value. */
#define HIST_MIN_BINS 5
#define HIST_MAX_BINS 30
/** A survey value farther than this many ensemble ranges beyond the ensemble gets its own
 *  axis segment (a broken axis): on one linear axis the ensemble would shrink to less than
 *  1 / (1 + 2 × HIST_NEAR_RANGES) of the width. */
#define HIST_NEAR_RANGES 1.5
/** Width of a broken axis' side segment and of the gap before it (px). */
#define HIST_SIDE_PX 58.0
#define HIST_GAP_PX 12.0

static const char *colour(karst_palette_role_t r) {
  return karst_palette_role(r);
}

void karst_i_metric_axis_label(char *out, size_t size, const char *key) {
  int n = 0;
  const karst_metric_field_t *f = karst_metric_fields(&n);
  for (int i = 0; i < n; i++)
    if (strcmp(f[i].key, key) == 0) {
      const char *u = strcmp(f[i].unit, "1") == 0 ? "dimensionless" : f[i].unit;
      snprintf(out, size, "%s (%s)", f[i].label, u);
      return;
    }
  snprintf(out, size, "%s", key);
}

int karst_i_column_constant(const karst_ensemble_table_t *t, int col, double *value,
                            karst_int_t *n) {
  double lo = INFINITY, hi = -INFINITY;
  karst_int_t k = 0;
  for (karst_int_t i = 0; i < t->n_rows; i++) {
    double v = t->values[i * t->n_cols + col];
    if (!isfinite(v)) continue;
    k++;
    lo = fmin(lo, v);
    hi = fmax(hi, v);
  }
  *n = k;
  *value = k > 0 ? lo : NAN;
  return k == 0 || lo == hi;
}

static void fmt(char *out, size_t size, double v) {
  snprintf(out, size, "%.4g", v);
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* Dash patterns of the survey lines, one per survey (in the order of --survey). */
static const char *const survey_dashes[4] = {"5 3", "1.5 2.5", "9 3 2 3", "3 1.5"};

const char *karst_i_survey_dash(int survey) {
  return survey_dashes[(survey < 0 ? 0 : survey) % 4];
}

/* One segment of a (possibly broken) x axis: values [v0, v1] on pixels [x0, x0 + w]. */
typedef struct {
  karst_i_plot_t p;
  int main; /* the segment of the ensemble's bars */
} segment_t;

static int in_segment(const segment_t *s, double v) {
  return v >= s->p.xmin && v <= s->p.xmax;
}

/* A side segment around the far survey values @p v (n of them). */
static void side_range(const double *v, int n, double span, double *lo, double *hi) {
  *lo = INFINITY, *hi = -INFINITY;
  for (int i = 0; i < n; i++)
    *lo = fmin(*lo, v[i]), *hi = fmax(*hi, v[i]);
  double pad = *hi > *lo ? 0.15 * (*hi - *lo) : fmax(0.1 * span, 1e-9 * fabs(*lo));
  *lo -= pad;
  *hi += pad;
}

/* Tick labels at the survey values of a side segment (nice ticks would be meaningless on a
 * stretch that holds only them). */
static void side_ticks(karst_i_buf_t *b, const segment_t *s, const double *v, int n,
                       double *right) {
  char lab[32];
  for (int i = 0; i < n; i++) {
    double px = karst_i_plot_px(&s->p, v[i]);
    karst_i_svg_line(b, px, s->p.y + s->p.h, px, s->p.y + s->p.h + 4, "#444", 1, NULL);
    fmt(lab, sizeof lab, v[i]);
    double w = karst_i_text_width(lab, KARST_I_TICK_FONT);
    if (px - w / 2 < *right + KARST_I_LABEL_GAP) continue;
    karst_i_svg_text(b, px, s->p.y + s->p.h + 15, "middle", "tick", lab);
    *right = px + w / 2;
  }
}

/* The two slanted strokes of an axis break at pixel @p x of the axis line at @p y. */
static void break_mark(karst_i_buf_t *b, double x, double y) {
  for (int k = -1; k <= 1; k += 2)
    karst_i_svg_line(b, x + 2.5 * k - 3, y + 5, x + 2.5 * k + 3, y - 5, "#444", 1, NULL);
}

/**
 * Histogram of column @p col (see report_internal.h). Layout, top to bottom, each on its own
 * row: the metric's key; the survey value(s); the range of the 34 published caves; the plot;
 * tick labels; the quantity and unit. Bars are filled, without outline, at least
 * KARST_I_MIN_BAR_PX wide. A survey value farther than HIST_NEAR_RANGES ensemble ranges from
 * the ensemble gets a side segment of the x axis (a broken axis, marked //), so the ensemble
 * keeps most of the width whatever the survey.
 * Time complexity: O(members + bins).
 */
void karst_i_plot_histogram(karst_i_buf_t *b, const karst_ensemble_table_t *t, int col,
                            const karst_compare_result_t *res, int n_res) {
  const double W = 330, H = 236, x0 = 52, x1 = W - 14;
  const double ytop = 50, yplot = 130;
  double lo = INFINITY, hi = -INFINITY;
  karst_int_t n = 0;
  int integral = 1;
  for (karst_int_t i = 0; i < t->n_rows; i++) {
    double v = t->values[i * t->n_cols + col];
    if (!isfinite(v)) continue;
    n++;
    lo = fmin(lo, v);
    hi = fmax(hi, v);
    integral &= v == floor(v);
  }
  char label[160];
  karst_i_metric_axis_label(label, sizeof label, t->names[col]);
  karst_i_svg_begin(b, W, H, t->names[col]);
  karst_i_svg_text(b, 4, 13, "start", "axis", t->names[col]);
  if (!(n > 0 && hi > lo)) { /* the page lists such columns as values; never called so */
    karst_i_svg_text(b, W / 2, H / 2, "middle", "note", "constant over the ensemble");
    karst_i_svg_end(b);
    return;
  }
  /* Bins. */
  int nb;
  double blo, bhi;
  if (integral && hi - lo < HIST_MAX_BINS) {
    nb = (int)(hi - lo) + 1;
    blo = lo - 0.5;
    bhi = hi + 0.5;
  } else {
    nb = (int)ceil(sqrt((double)n));
    nb = nb < HIST_MIN_BINS ? HIST_MIN_BINS : nb > HIST_MAX_BINS ? HIST_MAX_BINS : nb;
    blo = lo;
    bhi = hi;
  }
  int *count = calloc((size_t)nb, sizeof *count);
  if (!count) {
    b->failed = 1;
    return;
  }
  int cmax = 0;
  for (karst_int_t i = 0; i < t->n_rows; i++) {
    double v = t->values[i * t->n_cols + col];
    if (!isfinite(v)) continue;
    int k = (int)floor((v - blo) / (bhi - blo) * nb);
    k = k >= nb ? nb - 1 : k < 0 ? 0 : k; /* the last bin is closed */
    if (++count[k] > cmax) cmax = count[k];
  }
  /* Survey values: near ones widen the main segment, far ones get a side segment. */
  double span = hi - lo, near_lo = lo - HIST_NEAR_RANGES * span,
         near_hi = hi + HIST_NEAR_RANGES * span;
  double vlo = blo, vhi = bhi, left[16], right[16], all[16];
  int nl = 0, nr = 0, na = 0, which[16];
  for (int s = 0; s < n_res && na < 16; s++) {
    double v = res[s].rows[col].survey;
    if (!isfinite(v)) continue;
    which[na] = s;
    all[na++] = v;
    if (v < near_lo)
      left[nl++] = v;
    else if (v > near_hi)
      right[nr++] = v;
    else
      vlo = fmin(vlo, v), vhi = fmax(vhi, v);
  }
  if (vlo == blo || vhi == bhi) { /* a little room so that an edge value's line shows */
    double pad = 0.02 * (vhi - vlo);
    if (vlo == blo) vlo -= pad;
    if (vhi == bhi) vhi += pad;
  }
  segment_t seg[3];
  int ns = 0;
  double x = x0, main_w = (x1 - x0) - (nl > 0) * (HIST_SIDE_PX + HIST_GAP_PX) -
                          (nr > 0) * (HIST_SIDE_PX + HIST_GAP_PX);
  karst_i_plot_t base = {0, ytop, 0, yplot, 0, 0, 0, cmax};
  karst_i_ticks_t ty;
  karst_i_ticks_loose(0, cmax, 4, &ty);
  if (ty.step < 1) { /* counts are whole numbers */
    ty.step = 1, ty.first = 0, ty.count = cmax + 1, ty.decimals = 0;
  }
  base.ymax = ty.first + (ty.count - 1) * ty.step;
  if (nl > 0) {
    seg[ns] = (segment_t){base, 0};
    seg[ns].p.x = x, seg[ns].p.w = HIST_SIDE_PX;
    side_range(left, nl, span, &seg[ns].p.xmin, &seg[ns].p.xmax);
    ns++;
    x += HIST_SIDE_PX + HIST_GAP_PX;
  }
  int im = ns;
  seg[ns] = (segment_t){base, 1};
  seg[ns].p.x = x, seg[ns].p.w = main_w, seg[ns].p.xmin = vlo, seg[ns].p.xmax = vhi;
  ns++;
  x += main_w + HIST_GAP_PX;
  if (nr > 0) {
    seg[ns] = (segment_t){base, 0};
    seg[ns].p.x = x, seg[ns].p.w = HIST_SIDE_PX;
    side_range(right, nr, span, &seg[ns].p.xmin, &seg[ns].p.xmax);
    ns++;
  }
  /* Notes, each on its own row above the plot. */
  char note[256], fitted[256], v1[32], v2[32];
  qsort(left, (size_t)nl, sizeof *left, cmp_double); /* tick labels left to right */
  qsort(right, (size_t)nr, sizeof *right, cmp_double);
  if (na > 0) {
    int m = snprintf(note, sizeof note, "survey: ");
    for (int s = 0; s < na && m < (int)sizeof note - 40; s++) {
      fmt(v1, sizeof v1, all[s]);
      if (n_res > 1)
        m += snprintf(note + m, sizeof note - (size_t)m, "%s%d: %s", s ? ", " : "", which[s] + 1,
                      v1);
      else
        m += snprintf(note + m, sizeof note - (size_t)m, "%s", v1);
    }
    if (nl + nr > 0)
      snprintf(note + m, sizeof note - (size_t)m, " (far from the members: axis broken)");
    karst_i_fit_text(fitted, sizeof fitted, note, W - 8);
    karst_i_buf_printf(b, "<text x=\"4\" y=\"27\" class=\"note\" fill=\"%s\">",
                       colour(KARST_PALETTE_ROLE_SURVEY));
    karst_i_buf_escape(b, fitted);
    karst_i_buf_puts(b, "</text>\n");
  }
  const karst_compare_row_t *row = n_res > 0 ? &res[0].rows[col] : NULL;
  if (row && row->has_published) {
    fmt(v1, sizeof v1, row->published_min);
    fmt(v2, sizeof v2, row->published_max);
    snprintf(note, sizeof note, "34 caves: %s – %s (grey band)", v1, v2);
    karst_i_fit_text(fitted, sizeof fitted, note, W - 8);
    karst_i_svg_text(b, 4, 41, "start", "note", fitted);
  }
  /* Data: the published band, the bars, the survey lines; then frames and ticks. */
  for (int k = 0; k < ns && row && row->has_published; k++) {
    double a = fmax(row->published_min, seg[k].p.xmin), c = fmin(row->published_max, seg[k].p.xmax);
    if (a < c)
      karst_i_buf_printf(
          b,
          "<rect class=\"band\" x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"%.2f\" "
          "fill=\"%s\" fill-opacity=\"0.22\"/>\n",
          karst_i_plot_px(&seg[k].p, a), seg[k].p.y,
          karst_i_plot_px(&seg[k].p, c) - karst_i_plot_px(&seg[k].p, a), seg[k].p.h,
          colour(KARST_PALETTE_ROLE_PUBLISHED));
  }
  const karst_i_plot_t *pm = &seg[im].p;
  double bw = (bhi - blo) / nb;
  for (int k = 0; k < nb; k++) {
    if (count[k] == 0) continue;
    double a = karst_i_plot_px(pm, blo + k * bw), c = karst_i_plot_px(pm, blo + (k + 1) * bw);
    double w = c - a;
    if (w >= 4) a += 0.5, w -= 1; /* a pixel between neighbours */
    if (w < KARST_I_MIN_BAR_PX) a -= (KARST_I_MIN_BAR_PX - w) / 2, w = KARST_I_MIN_BAR_PX;
    double y0 = fmin(karst_i_plot_py(pm, count[k]), pm->y + pm->h - KARST_I_MIN_BAR_PX);
    karst_i_svg_rect_class(b, a, y0, w, pm->y + pm->h - y0, colour(KARST_PALETTE_ROLE_ENSEMBLE),
                           "bar");
  }
  for (int s = 0; s < na; s++)
    for (int k = 0; k < ns; k++)
      if (in_segment(&seg[k], all[s])) {
        double px = karst_i_plot_px(&seg[k].p, all[s]);
        karst_i_svg_line_class(b, px, seg[k].p.y, px, seg[k].p.y + seg[k].p.h,
                               colour(KARST_PALETTE_ROLE_SURVEY), 2, karst_i_survey_dash(which[s]),
                               "survey");
      }
  double rightmost = -INFINITY;
  for (int k = 0; k < ns; k++) {
    karst_i_svg_rect(b, seg[k].p.x, seg[k].p.y, seg[k].p.w, seg[k].p.h, "none", "#444", 1);
    if (seg[k].main) {
      karst_i_ticks_t tx;
      if (karst_i_ticks_inside(seg[k].p.xmin, seg[k].p.xmax, 5, &tx) == 0)
        karst_i_svg_xticks(b, &seg[k].p, &tx, seg[k].p.x, seg[k].p.x + seg[k].p.w, &rightmost);
    } else {
      side_ticks(b, &seg[k], k < im ? left : right, k < im ? nl : nr, &rightmost);
    }
    if (k > 0) break_mark(b, seg[k].p.x - HIST_GAP_PX / 2, seg[k].p.y + seg[k].p.h);
  }
  double widest = karst_i_svg_yticks(b, &seg[0].p, &ty);
  karst_i_svg_ylabel(b, &seg[0].p, widest, "members (count)");
  karst_i_fit_text(fitted, sizeof fitted, label, W - 8);
  karst_i_svg_text(b, W / 2, ytop + yplot + 30, "middle", "axis", fitted);
  free(count);
  karst_i_svg_end(b);
}

/* ------------------------------------------------------------------------ */
/* Rose                                                                     */
/* ------------------------------------------------------------------------ */
void karst_i_rose_accumulate(const karst_network_t *net, double *bins, int nb) {
  for (karst_int_t e = 0; e < net->n_edges; e++) {
    const double *a = net->xyz + 3 * net->edges[2 * e], *c = net->xyz + 3 * net->edges[2 * e + 1];
    double dx = c[0] - a[0], dy = c[1] - a[1], l2 = hypot(dx, dy);
    if (!(l2 > 0)) continue;
    double az = atan2(dx, dy) * 180.0 / M_PI; /* clockwise from +y */
    az = fmod(az + 360.0, 180.0);
    int k = (int)floor(az / (180.0 / nb));
    k = k >= nb ? nb - 1 : k < 0 ? 0 : k;
    bins[k] += l2;
  }
}

/* The petal outline of bin fractions @p f (both halves, az and az + 180) at radius
 * R sqrt(f / fmax): equal area, petal area proportional to the share of length. */
static int rose_outline(const double *f, int nb, double fmax, double cx, double cy, double R,
                        double *pts) {
  int m = 0;
  for (int half = 0; half < 2; half++)
    for (int k = 0; k < nb; k++) {
      double r = R * sqrt(f[k] / fmax);
      for (int j = 0; j <= 4; j++) {
        double a = (half * 180.0 + (k + j / 4.0) * 180.0 / nb) * M_PI / 180.0;
        pts[2 * m] = cx + r * sin(a);
        pts[2 * m + 1] = cy - r * cos(a);
        m++;
      }
    }
  return m;
}

/**
 * Equal-area orientation rose (Nemec 1988: radius proportional to the square root of the
 * share, so petal areas compare): the pooled members filled, the survey outlined, both
 * normalised to their own total horizontal length and drawn on ONE radial scale, whose rings
 * are labelled on a ruler below the rose; a legend below that. Azimuths clockwise from grid
 * north (+y).
 * Time complexity: O(bins).
 */
void karst_i_plot_rose(karst_i_buf_t *b, const double *ens, const double *survey, int nb,
                       karst_int_t pooled, const char *survey_label) {
  const double W = 360, R = 118, cx = W / 2, cy = 150;
  double se = 0, ss = 0, fe[36] = {0}, fs[36] = {0}, fbig = 0;
  if (nb > 36) nb = 36;
  for (int k = 0; k < nb; k++) {
    se += ens[k];
    if (survey) ss += survey[k];
  }
  for (int k = 0; k < nb; k++) {
    fe[k] = se > 0 ? ens[k] / se : 0;
    fs[k] = ss > 0 ? survey[k] / ss : 0;
    fbig = fmax(fbig, fmax(fe[k], fs[k]));
  }
  const int have_survey = survey && ss > 0;
  const double H = have_survey ? 396 : 378;
  karst_i_svg_begin(b, W, H, "length-weighted orientation rose");
  karst_i_svg_text(b, cx, cy - R - 8, "middle", "tick", "N");
  karst_i_svg_text(b, cx + R + 12, cy + 4, "middle", "tick", "E");
  karst_i_svg_text(b, cx, cy + R + 16, "middle", "tick", "S");
  karst_i_svg_text(b, cx - R - 12, cy + 4, "middle", "tick", "W");
  if (!(se > 0)) {
    karst_i_svg_marker(b, cx, cy, R, "none", "#dddddd");
    karst_i_svg_text(b, cx, cy, "middle", "note", "no horizontal conduits");
    karst_i_svg_end(b);
    return;
  }
  /* Rings at nice shares up to the largest petal. */
  karst_i_ticks_t t;
  karst_i_ticks_loose(0, 100 * fbig, 4, &t);
  double top = t.first + (t.count - 1) * t.step; /* percent at the outer ring */
  for (int i = 1; i < t.count; i++)
    karst_i_svg_marker(b, cx, cy, R * sqrt((t.first + i * t.step) / top), "none", "#dddddd");
  karst_i_svg_line(b, cx - R, cy, cx + R, cy, "#eeeeee", 1, NULL);
  karst_i_svg_line(b, cx, cy - R, cx, cy + R, "#eeeeee", 1, NULL);
  double pts[2 * 2 * 36 * 5];
  int m = rose_outline(fe, nb, top / 100, cx, cy, R, pts);
  karst_i_buf_puts(b, "<g class=\"bar\">");
  karst_i_svg_polyline(b, pts, m, colour(KARST_PALETTE_ROLE_ENSEMBLE), 0.5,
                       colour(KARST_PALETTE_ROLE_ENSEMBLE), 1);
  karst_i_buf_puts(b, "</g>\n");
  if (have_survey) {
    m = rose_outline(fs, nb, top / 100, cx, cy, R, pts);
    karst_i_buf_puts(b, "<g class=\"survey\">");
    karst_i_svg_polyline(b, pts, m, colour(KARST_PALETTE_ROLE_SURVEY), 2, NULL, 1);
    karst_i_buf_puts(b, "</g>\n");
  }
  /* Radial scale: a ruler from the centre's radius 0 to R, ticks at the rings. */
  const double yr = cy + R + 40;
  karst_i_svg_line(b, cx, yr, cx + R, yr, "#444", 1, NULL);
  char lab[32];
  double right = -INFINITY;
  for (int i = 0; i < t.count; i++) {
    double v = t.first + i * t.step, px = cx + R * sqrt(v / top);
    karst_i_svg_line(b, px, yr, px, yr + 4, "#444", 1, NULL);
    snprintf(lab, sizeof lab, "%.*f", t.decimals, v);
    double w = karst_i_text_width(lab, KARST_I_TICK_FONT);
    if (px - w / 2 < right + KARST_I_LABEL_GAP) continue;
    karst_i_svg_text(b, px, yr + 15, "middle", "tick", lab);
    right = px + w / 2;
  }
  karst_i_svg_text(b, cx - 8, yr + 4, "end", "tick", "radius:");
  karst_i_svg_text(b, cx, yr + 30, "middle", "axis", "share of horizontal length per 10° (%)");
  karst_i_svg_text(b, cx, yr + 44, "middle", "note",
                   "equal-area petals; each normalised to its own total");
  /* Legend. */
  char txt[256], fitted[256];
  double yl = yr + 62;
  karst_i_svg_rect(b, 8, yl - 8, 14, 9, colour(KARST_PALETTE_ROLE_ENSEMBLE), NULL, 1);
  snprintf(txt, sizeof txt, "members (%lld pooled)", (long long)pooled);
  karst_i_svg_text(b, 28, yl, "start", "note", txt);
  if (have_survey) {
    karst_i_svg_line(b, 8, yl + 14, 22, yl + 14, colour(KARST_PALETTE_ROLE_SURVEY), 2, NULL);
    snprintf(txt, sizeof txt, "survey: %s", survey_label);
    karst_i_fit_text(fitted, sizeof fitted, txt, W - 36);
    karst_i_svg_text(b, 28, yl + 18, "start", "note", fitted);
  }
  karst_i_svg_end(b);
}

/* ------------------------------------------------------------------------ */
/* Degree distribution                                                      */
/* ------------------------------------------------------------------------ */
void karst_i_degree_accumulate(const karst_network_t *net, double *count, int max_degree) {
  karst_int_t *deg = calloc((size_t)(net->n_nodes > 0 ? net->n_nodes : 1), sizeof *deg);
  if (!deg) return;
  for (karst_int_t e = 0; e < net->n_edges; e++) {
    deg[net->edges[2 * e]]++;
    deg[net->edges[2 * e + 1]]++;
  }
  for (karst_int_t v = 0; v < net->n_nodes; v++) {
    karst_int_t d = deg[v];
    if (d < 1) continue;
    if (d > max_degree) d = max_degree;
    count[d] += 1;
  }
  free(deg);
}

/**
 * Degree distribution of the full graph: the share of nodes of each degree, pooled members as
 * bars, the survey as dots; the legend on its own row above the plot.
 * Time complexity: O(max_degree).
 */
void karst_i_plot_degrees(karst_i_buf_t *b, const double *ens, const double *survey, int max_degree,
                          const char *survey_label) {
  const double W = 340, H = 262;
  karst_i_plot_t p = {56, 40, W - 72, H - 92, 0.5, max_degree + 0.5, 0, 0};
  double se = 0, ss = 0, ymax = 0;
  for (int d = 1; d <= max_degree; d++) {
    se += ens[d];
    if (survey) ss += survey[d];
  }
  karst_i_svg_begin(b, W, H, "degree distribution");
  if (se <= 0) {
    karst_i_svg_text(b, W / 2, H / 2, "middle", "note", "no edges");
    karst_i_svg_end(b);
    return;
  }
  const int have_survey = survey && ss > 0;
  for (int d = 1; d <= max_degree; d++) {
    ymax = fmax(ymax, ens[d] / se);
    if (have_survey) ymax = fmax(ymax, survey[d] / ss);
  }
  karst_i_svg_rect(b, 8, 8, 14, 9, colour(KARST_PALETTE_ROLE_ENSEMBLE), NULL, 1);
  karst_i_svg_text(b, 28, 16, "start", "note", "members (pooled)");
  if (have_survey) {
    char txt[256], fitted[256];
    karst_i_svg_marker(b, 15, 28, 4, colour(KARST_PALETTE_ROLE_SURVEY), "#ffffff");
    snprintf(txt, sizeof txt, "survey: %s", survey_label);
    karst_i_fit_text(fitted, sizeof fitted, txt, W - 36);
    karst_i_svg_text(b, 28, 32, "start", "note", fitted);
  }
  p.ymax = ymax * 1.08; /* headroom so the tallest bar does not touch the frame */
  char xl[64];
  snprintf(xl, sizeof xl, "node degree (edges per node; last: %d or more)", max_degree);
  karst_i_svg_axes(b, &p, 0, max_degree, 5, xl, "share of nodes (fraction)");
  for (int d = 1; d <= max_degree; d++) {
    double x0 = karst_i_plot_px(&p, d - 0.35), x1 = karst_i_plot_px(&p, d + 0.35);
    double y0 = fmin(karst_i_plot_py(&p, ens[d] / se), p.y + p.h - KARST_I_MIN_BAR_PX);
    if (ens[d] > 0)
      karst_i_svg_rect_class(b, x0, y0, x1 - x0, p.y + p.h - y0,
                             colour(KARST_PALETTE_ROLE_ENSEMBLE), "bar");
  }
  if (have_survey) {
    karst_i_buf_puts(b, "<g class=\"survey\">");
    for (int d = 1; d <= max_degree; d++)
      karst_i_svg_marker(b, karst_i_plot_px(&p, d), karst_i_plot_py(&p, survey[d] / ss), 4,
                         colour(KARST_PALETTE_ROLE_SURVEY), "#ffffff");
    karst_i_buf_puts(b, "</g>\n");
  }
  karst_i_svg_end(b);
}
