/* The stereonet of the report: conduit orientations on a lower-hemisphere equal-area (Schmidt)
 * net, with the scenario's fracture families as great circles (report_internal.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "karst/palette.h"
#include "report/report_internal.h"

/** Survey conduits drawn as points: at most this many (every k-th edge beyond). */
#define STEREO_MAX_SURVEY_POINTS 3000
/** Points per great circle. */
#define STEREO_CIRCLE_POINTS 91
/** Density classes of the ensemble's shading (opacity steps of the ensemble colour). */
#define STEREO_DENSITY_CLASSES 5
/** Counting cone of the density, as a share of the hemisphere's area (Schmidt's 1 % circle:
 *  a half-angle of acos(0.99) = 8.1 degrees). */
#define STEREO_COUNT_AREA 0.01

static const double deg = M_PI / 180.0;

int karst_i_stereo_init(karst_i_stereo_t *s, int n) {
  memset(s, 0, sizeof *s);
  s->length = calloc((size_t)n * (size_t)n, sizeof *s->length);
  if (!s->length) return -1;
  s->n = n;
  return 0;
}

void karst_i_stereo_destroy(karst_i_stereo_t *s) {
  free(s->length);
  memset(s, 0, sizeof *s);
}

/**
 * Lambert azimuthal equal-area projection of the lower hemisphere onto the unit disc (the
 * Schmidt net; Priest 1985, "Hemispherical projection methods in rock mechanics", §2.4): a
 * line of trend t (clockwise from north) and plunge p (down from horizontal) goes to radius
 * sqrt(2) sin((90° - p) / 2) at azimuth t: horizontal lines on the primitive circle, vertical
 * ones at the centre. O(1).
 */
void karst_i_stereo_project(double trend, double plunge, double *x, double *y) {
  double r = sqrt(2.0) * sin((90.0 - plunge) * deg / 2);
  *x = r * sin(trend * deg);
  *y = r * cos(trend * deg);
}

/* Trend and plunge of the downward direction of the line through @p a and @p b; 0 when they
 * coincide. */
static int line_of(const double *a, const double *b, double *trend, double *plunge, double *len) {
  double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  *len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (!(*len > 0)) return 0;
  if (d[2] > 0)
    for (int k = 0; k < 3; k++)
      d[k] = -d[k];
  *plunge = asin(fmin(1.0, -d[2] / *len)) / deg;
  *trend = fmod(atan2(d[0], d[1]) / deg + 360.0, 360.0);
  return 1;
}

static void stereo_add(karst_i_stereo_t *s, double trend, double plunge, double w) {
  double x, y;
  karst_i_stereo_project(trend, plunge, &x, &y);
  int i = (int)floor((x + 1) / 2 * s->n), j = (int)floor((y + 1) / 2 * s->n);
  i = i < 0 ? 0 : i >= s->n ? s->n - 1 : i;
  j = j < 0 ? 0 : j >= s->n ? s->n - 1 : j;
  s->length[(size_t)j * s->n + i] += w;
  s->total += w;
}

/**
 * Pool the edges of @p net, weighted by 3-D length. A horizontal line has two equal downward
 * directions (t and t + 180°, both on the primitive circle): each gets half its length.
 * Time complexity: O(edges).
 */
void karst_i_stereo_accumulate(karst_i_stereo_t *s, const karst_network_t *net) {
  for (karst_int_t e = 0; e < net->n_edges; e++) {
    double t, p, l;
    if (!line_of(net->xyz + 3 * net->edges[2 * e], net->xyz + 3 * net->edges[2 * e + 1], &t, &p,
                 &l))
      continue;
    if (p == 0) {
      stereo_add(s, t, 0, l / 2);
      stereo_add(s, fmod(t + 180, 360), 0, l / 2);
    } else {
      stereo_add(s, t, p, l);
    }
  }
}

/* The lines of the plane of dip direction dd and dip d: v(φ) = cos φ · strike + sin φ · dip
 * vector, φ in [0°, 180°], all on or below the horizontal. */
static void great_circle(double dd, double d, double *pts, int n, double cx, double cy, double R) {
  double s[3] = {sin((dd - 90) * deg), cos((dd - 90) * deg), 0};
  double v[3] = {sin(dd * deg) * cos(d * deg), cos(dd * deg) * cos(d * deg), -sin(d * deg)};
  for (int k = 0; k < n; k++) {
    double f = k * 180.0 / (n - 1) * deg, u[3];
    for (int c = 0; c < 3; c++)
      u[c] = cos(f) * s[c] + sin(f) * v[c];
    double plunge = asin(fmin(1.0, fmax(0.0, -u[2]))) / deg;
    double trend = atan2(u[0], u[1]) / deg, x, y;
    karst_i_stereo_project(trend, plunge, &x, &y);
    pts[2 * k] = cx + R * x;
    pts[2 * k + 1] = cy - R * y;
  }
}

static const char *const dashes[4] = {NULL, "6 3", "2 2", "8 3 2 3"};

/**
 * The stereonet (see report_internal.h). The ensemble's conduits are shaded by density in
 * multiples of a uniform distribution (Schmidt's counting circle of STEREO_COUNT_AREA over the
 * cells of the equal-area grid, where cells of equal size weigh equal solid angles), in
 * STEREO_DENSITY_CLASSES classes of the ensemble colour; the survey's conduits are points;
 * each fracture family is a great circle (dark grey, its own dash), named in the legend with
 * its dip direction / dip. Legends and scales sit below the net.
 * Time complexity: O(cells² + survey edges + families × STEREO_CIRCLE_POINTS).
 */
void karst_i_plot_stereonet(karst_i_buf_t *b, const karst_i_stereo_t *ens,
                            const karst_network_t *survey, const char *survey_label,
                            const karst_i_plane_t *planes, int n_planes, karst_int_t pooled) {
  const double W = 360, R = 128, cx = W / 2, cy = 150;
  /* Rows below the net: the density scale (88 px), then 16 px per legend line. */
  const int rows = 2 + (survey && survey->n_edges > 0) + n_planes;
  const double H = cy + R + 80 + 16.0 * rows;
  karst_i_svg_begin(b, W, H, "stereonet of conduit orientations");
  karst_i_svg_text(b, cx, cy - R - 8, "middle", "tick", "N");
  karst_i_svg_text(b, cx + R + 12, cy + 4, "middle", "tick", "E");
  karst_i_svg_text(b, cx, cy + R + 16, "middle", "tick", "S");
  karst_i_svg_text(b, cx - R - 12, cy + 4, "middle", "tick", "W");
  const char *ens_col = karst_palette_role(KARST_PALETTE_ROLE_ENSEMBLE);
  const char *sv_col = karst_palette_role(KARST_PALETTE_ROLE_SURVEY);
  const char *st_col = karst_palette_role(KARST_PALETTE_ROLE_STRUCTURE);
  /* Density: the Schmidt counting-circle method (Priest 1985, §4.2): at each cell centre the
   * share of the pooled length whose lines lie within the cone of STEREO_COUNT_AREA of the
   * hemisphere around it, over STEREO_COUNT_AREA: multiples of a uniform distribution (MUD).
   * Lines are axes, so a cone also counts the lines opposite (|cos| above the cone's). */
  const int g = ens->n;
  const double cell = 2.0 / g, cos_cone = 1 - STEREO_COUNT_AREA;
  double *dir = calloc((size_t)g * g * 3, sizeof *dir), *mud = calloc((size_t)g * g, sizeof *mud);
  double mud_max = 0;
  if (!dir || !mud) {
    b->failed = 1;
  } else if (ens->total > 0) {
    for (int j = 0; j < g; j++)
      for (int i = 0; i < g; i++) {
        double x = -1 + (i + 0.5) * cell, y = -1 + (j + 0.5) * cell, r = hypot(x, y);
        double *u = dir + 3 * ((size_t)j * g + i);
        if (r > 1) continue;
        double plunge = 90 - 2 * asin(r / sqrt(2.0)) / deg, trend = atan2(x, y);
        u[0] = sin(trend) * cos(plunge * deg);
        u[1] = cos(trend) * cos(plunge * deg);
        u[2] = -sin(plunge * deg);
      }
    for (int c = 0; c < g * g; c++) {
      const double *u = dir + 3 * c;
      if (u[0] == 0 && u[1] == 0 && u[2] == 0) continue; /* outside the net */
      double w = 0;
      for (int k = 0; k < g * g; k++) {
        const double *v = dir + 3 * k;
        if (ens->length[k] > 0 && fabs(u[0] * v[0] + u[1] * v[1] + u[2] * v[2]) >= cos_cone)
          w += ens->length[k];
      }
      mud[c] = w / ens->total / STEREO_COUNT_AREA;
      mud_max = fmax(mud_max, mud[c]);
    }
  }
  double top = mud_max > 0 ? karst_i_nice_number(mud_max, 0) : 1;
  if (ens->total > 0 && mud) {
    /* Cells on the rim reach past the primitive circle: clip them to it. */
    karst_i_buf_printf(b,
                       "<defs><clipPath id=\"karst-stereonet-net\"><circle cx=\"%.2f\" "
                       "cy=\"%.2f\" r=\"%.2f\"/></clipPath></defs>\n",
                       cx, cy, R);
    karst_i_buf_puts(b, "<g class=\"density\" clip-path=\"url(#karst-stereonet-net)\">");
    for (int j = 0; j < g; j++)
      for (int i = 0; i < g; i++) {
        double v = mud[(size_t)j * g + i];
        int c = (int)ceil(v / top * STEREO_DENSITY_CLASSES - 1e-9);
        if (c < 1) continue;
        c = c > STEREO_DENSITY_CLASSES ? STEREO_DENSITY_CLASSES : c;
        double x = cx + R * (-1 + i * cell), y = cy - R * (-1 + (j + 1) * cell);
        karst_i_buf_printf(b,
                           "<rect x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"%.2f\" "
                           "fill=\"%s\" fill-opacity=\"%.2f\"/>",
                           x, y, R * cell + 0.3, R * cell + 0.3, ens_col,
                           (double)c / STEREO_DENSITY_CLASSES);
      }
    karst_i_buf_puts(b, "</g>\n");
  }
  free(dir);
  free(mud);
  /* Net: the primitive circle (over the density cells, which it clips visually), centre. */
  karst_i_svg_marker(b, cx, cy, R, "none", "#444");
  karst_i_svg_line(b, cx - 5, cy, cx + 5, cy, "#444", 1, NULL);
  karst_i_svg_line(b, cx, cy - 5, cx, cy + 5, "#444", 1, NULL);
  /* Survey points. */
  karst_int_t shown = 0, every = 1;
  if (survey && survey->n_edges > STEREO_MAX_SURVEY_POINTS)
    every = (survey->n_edges + STEREO_MAX_SURVEY_POINTS - 1) / STEREO_MAX_SURVEY_POINTS;
  if (survey && survey->n_edges > 0) {
    karst_i_buf_printf(b, "<g class=\"survey\" fill=\"%s\" fill-opacity=\"0.7\">", sv_col);
    for (karst_int_t e = 0; e < survey->n_edges; e += every) {
      double t, p, l, x, y;
      if (!line_of(survey->xyz + 3 * survey->edges[2 * e],
                   survey->xyz + 3 * survey->edges[2 * e + 1], &t, &p, &l))
        continue;
      karst_i_stereo_project(t, p, &x, &y);
      karst_i_buf_printf(b, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"1.6\"/>", cx + R * x, cy - R * y);
      shown++;
    }
    karst_i_buf_puts(b, "</g>\n");
  }
  /* Fracture families. */
  double pts[2 * STEREO_CIRCLE_POINTS];
  for (int f = 0; f < n_planes; f++) {
    great_circle(planes[f].dip_direction, planes[f].dip, pts, STEREO_CIRCLE_POINTS, cx, cy, R);
    karst_i_buf_printf(b,
                       "<polyline class=\"structure\" fill=\"none\" stroke=\"%s\" "
                       "stroke-width=\"1.5\"%s%s%s points=\"",
                       st_col, dashes[f % 4] ? " stroke-dasharray=\"" : "",
                       dashes[f % 4] ? dashes[f % 4] : "", dashes[f % 4] ? "\"" : "");
    for (int k = 0; k < STEREO_CIRCLE_POINTS; k++)
      karst_i_buf_printf(b, "%s%.2f,%.2f", k ? " " : "", pts[2 * k], pts[2 * k + 1]);
    karst_i_buf_puts(b, "\"/>\n");
  }
  /* Below the net: the density scale, then one legend row per item. */
  double y = cy + R + 36;
  const double bar_x = 40, bar_w = W - 80;
  for (int c = 1; c <= STEREO_DENSITY_CLASSES; c++)
    karst_i_buf_printf(b,
                       "<rect x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"8\" fill=\"%s\" "
                       "fill-opacity=\"%.2f\" stroke=\"#444\" stroke-width=\"0.5\"/>\n",
                       bar_x + (c - 1) * bar_w / STEREO_DENSITY_CLASSES, y,
                       bar_w / STEREO_DENSITY_CLASSES, ens_col, (double)c / STEREO_DENSITY_CLASSES);
  char lab[64];
  for (int c = 0; c <= STEREO_DENSITY_CLASSES; c++) {
    snprintf(lab, sizeof lab, "%.3g", top * c / STEREO_DENSITY_CLASSES);
    karst_i_svg_text(b, bar_x + c * bar_w / STEREO_DENSITY_CLASSES, y + 20, "middle", "tick", lab);
  }
  karst_i_svg_text(b, cx, y + 34, "middle", "axis", "members: length density (× uniform)");
  char txt[256];
  y += 52;
  karst_i_svg_text(b, 8, y, "start", "note", "lower hemisphere, equal area (Schmidt net)");
  y += 16;
  snprintf(txt, sizeof txt, "density: 1 %% counting circle, %lld members pooled",
           (long long)pooled);
  karst_i_svg_text(b, 8, y, "start", "note", txt);
  y += 16;
  if (survey && survey->n_edges > 0) {
    karst_i_svg_marker(b, 15, y - 4, 2.5, sv_col, NULL);
    char fitted[256];
    if (every > 1)
      snprintf(txt, sizeof txt, "survey: %s (every %lldth of %lld conduits)",
               survey_label ? survey_label : "", (long long)every, (long long)survey->n_edges);
    else
      snprintf(txt, sizeof txt, "survey: %s (%lld conduits)", survey_label ? survey_label : "",
               (long long)shown);
    karst_i_fit_text(fitted, sizeof fitted, txt, W - 36);
    karst_i_svg_text(b, 28, y, "start", "note", fitted);
    y += 16;
  }
  for (int f = 0; f < n_planes; f++) {
    karst_i_svg_line(b, 6, y - 4, 24, y - 4, st_col, 1.5, dashes[f % 4]);
    char fitted[256];
    snprintf(txt, sizeof txt, "fracture family %d: %03.0f° / %02.0f° (dip direction / dip)", f + 1,
             planes[f].dip_direction, planes[f].dip);
    karst_i_fit_text(fitted, sizeof fitted, txt, W - 36);
    karst_i_svg_text(b, 28, y, "start", "note", fitted);
    y += 16;
  }
  karst_i_svg_end(b);
}
