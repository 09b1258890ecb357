/* The members' views of the report: plan, two vertical sections and an oblique 3-D view on
 * one common scale, with north arrows and scale bars (report_internal.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "karst/palette.h"
#include "report/report_internal.h"

/** Plot area of every view (px) and the margins around it. */
#define VIEW_PW 300.0
#define VIEW_PLAN_PH 220.0
#define VIEW_SECTION_PH 120.0
#define VIEW_TOP 24.0
#define VIEW_RIGHT 44.0
/** Sections are exaggerated vertically when the depth would take less than this share of
 *  their height, by the smallest of 2, 5, 10, 20, 50, 100 that makes it take at least that. */
#define VIEW_MIN_SECTION_SHARE 0.25
/** The oblique view looks along azimuth VIEW_AZIMUTH (from the south-south-west towards the
 *  north-north-east) from VIEW_ELEVATION above the horizontal; orthographic. */
#define VIEW_AZIMUTH 30.0
#define VIEW_ELEVATION 30.0
/** Scale bars and the oblique view's axes: a nice length near this share of the width. */
#define VIEW_SCALE_SHARE 0.25

static const double deg = M_PI / 180.0;

void karst_i_bounds_add(const karst_network_t *net, double lo[3], double hi[3]) {
  for (karst_int_t v = 0; v < net->n_nodes; v++)
    for (int k = 0; k < 3; k++) {
      lo[k] = fmin(lo[k], net->xyz[3 * v + k]);
      hi[k] = fmax(hi[k], net->xyz[3 * v + k]);
    }
}

static double extent(const double *lo, const double *hi, int k) {
  return fmax(hi[k] - lo[k], 1e-6);
}

/* Screen coordinates (x right, y up) of point @p p in the oblique view. */
static void oblique(const double *p, double *sx, double *sy) {
  double a = VIEW_AZIMUTH * deg, e = VIEW_ELEVATION * deg;
  *sx = p[0] * cos(a) - p[1] * sin(a);
  *sy = p[0] * sin(a) * sin(e) + p[1] * cos(a) * sin(e) + p[2] * cos(e);
}

/* Projected extent of a box in the oblique view. */
static void oblique_extent(const double *lo, const double *hi, double *w, double *h) {
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  for (int c = 0; c < 8; c++) {
    double p[3] = {c & 1 ? hi[0] : lo[0], c & 2 ? hi[1] : lo[1], c & 4 ? hi[2] : lo[2]}, x, y;
    oblique(p, &x, &y);
    x0 = fmin(x0, x), x1 = fmax(x1, x), y0 = fmin(y0, y), y1 = fmax(y1, y);
  }
  *w = fmax(x1 - x0, 1e-6);
  *h = fmax(y1 - y0, 1e-6);
}

/**
 * The frame the members' views share (report_internal.h): the box of the members, grown by
 * the survey's when the two overlap in plan (then the survey is drawn in the members' frame);
 * one scale in pixels per metre that fits the box (and the survey's own box otherwise) in the
 * plan and both sections; the sections' vertical exaggeration.
 * Time complexity: O(survey nodes).
 */
void karst_i_frame_make(karst_i_frame_t *f, const double lo[3], const double hi[3],
                        const karst_network_t *survey) {
  memset(f, 0, sizeof *f);
  memcpy(f->lo, lo, sizeof f->lo);
  memcpy(f->hi, hi, sizeof f->hi);
  double slo[3] = {INFINITY, INFINITY, INFINITY}, shi[3] = {-INFINITY, -INFINITY, -INFINITY};
  if (survey) karst_i_bounds_add(survey, slo, shi);
  int have_survey = survey && isfinite(slo[0]);
  if (!isfinite(f->lo[0])) { /* no member drawn: the survey alone */
    if (have_survey)
      memcpy(f->lo, slo, sizeof slo), memcpy(f->hi, shi, sizeof shi);
    else
      for (int k = 0; k < 3; k++)
        f->lo[k] = 0, f->hi[k] = 1;
  }
  if (have_survey && slo[0] <= f->hi[0] && shi[0] >= f->lo[0] && slo[1] <= f->hi[1] &&
      shi[1] >= f->lo[1]) {
    f->survey_inside = 1;
    for (int k = 0; k < 3; k++)
      f->lo[k] = fmin(f->lo[k], slo[k]), f->hi[k] = fmax(f->hi[k], shi[k]);
  }
  double dx = extent(f->lo, f->hi, 0), dy = extent(f->lo, f->hi, 1), dz = extent(f->lo, f->hi, 2);
  double s = fmin(fmin(VIEW_PW / dx, VIEW_PLAN_PH / dy), VIEW_PW / dy);
  if (have_survey && !f->survey_inside) {
    s = fmin(s, fmin(fmin(VIEW_PW / extent(slo, shi, 0), VIEW_PLAN_PH / extent(slo, shi, 1)),
                     VIEW_PW / extent(slo, shi, 1)));
    dz = fmax(dz, extent(slo, shi, 2));
  }
  s = fmin(s, VIEW_SECTION_PH / dz); /* sections without exaggeration fit */
  f->scale = s * 0.94;               /* a margin inside the frames */
  double w, h;
  oblique_extent(f->lo, f->hi, &w, &h);
  f->oblique_scale = fmin(VIEW_PW / w, VIEW_PLAN_PH / h);
  if (have_survey && !f->survey_inside) {
    oblique_extent(slo, shi, &w, &h);
    f->oblique_scale = fmin(f->oblique_scale, fmin(VIEW_PW / w, VIEW_PLAN_PH / h));
  }
  f->oblique_scale *= 0.94;
  static const double steps[] = {1, 2, 5, 10, 20, 50, 100};
  f->exaggeration = 1;
  for (size_t i = 0; i < sizeof steps / sizeof steps[0]; i++) {
    f->exaggeration = steps[i];
    if (dz * f->scale * steps[i] >= VIEW_MIN_SECTION_SHARE * VIEW_SECTION_PH) break;
    if (i + 1 < sizeof steps / sizeof steps[0] &&
        dz * f->scale * steps[i + 1] > 0.94 * VIEW_SECTION_PH)
      break;
  }
}

/* Width of the widest tick label of ticks inside [lo, hi]. */
static double widest_label(double lo, double hi, int target) {
  karst_i_ticks_t t;
  char lab[64];
  double w = 0;
  if (karst_i_ticks_inside(lo, hi, target, &t) != 0) return 0;
  for (int i = 0; i < t.count; i++) {
    karst_i_tick_label(lab, sizeof lab, t.first + i * t.step, t.decimals);
    w = fmax(w, karst_i_text_width(lab, KARST_I_TICK_FONT));
  }
  return w;
}

/* One <path> per tunnel type (and the survey's) of the edges of @p net, through @p map. */
typedef void (*map_fn)(const void *ctx, const double *p, double *x, double *y);

static void draw_network(karst_i_buf_t *b, const karst_network_t *net, map_fn map, const void *mctx,
                         int as_survey) {
  karst_attr_t *type =
      as_survey ? NULL : karst_network_attr_find(net, KARST_ATTR_EDGE, "tunnel_type");
  const karst_palette_t *pal = karst_palette_find("tunnel_type");
  for (int t = as_survey ? -2 : -1; t < (as_survey ? -1 : KARST_TUNNEL_TYPE_COUNT); t++) {
    int any = 0;
    for (karst_int_t e = 0; e < net->n_edges; e++) {
      int et = type ? (int)type->data[e * type->ncomp] : -1;
      if (et < 0 || et >= KARST_TUNNEL_TYPE_COUNT) et = -1;
      if (!as_survey && et != t) continue;
      if (!any) {
        const karst_palette_category_t *c = karst_palette_category(pal, t);
        if (as_survey)
          karst_i_buf_printf(
              b,
              "<path class=\"survey\" fill=\"none\" stroke=\"%s\" stroke-width=\"1\" "
              "stroke-opacity=\"0.8\" d=\"",
              karst_palette_role(KARST_PALETTE_ROLE_SURVEY));
        else
          karst_i_buf_printf(b,
                             "<path class=\"network\" fill=\"none\" stroke=\"%s\" "
                             "stroke-width=\"1.5\" d=\"",
                             c ? c->hex : karst_palette_role(KARST_PALETTE_ROLE_NONE));
        any = 1;
      }
      double x0, y0, x1, y1;
      map(mctx, net->xyz + 3 * net->edges[2 * e], &x0, &y0);
      map(mctx, net->xyz + 3 * net->edges[2 * e + 1], &x1, &y1);
      karst_i_buf_printf(b, "M%.1f %.1fL%.1f %.1f", x0, y0, x1, y1);
    }
    if (any) karst_i_buf_puts(b, "\"/>\n");
  }
}

/* An orthogonal view: horizontal axis h, vertical axis v of the point. */
typedef struct {
  karst_i_plot_t p;
  int h, v;
} ortho_t;

static void map_ortho(const void *ctx, const double *q, double *x, double *y) {
  const ortho_t *o = ctx;
  *x = karst_i_plot_px(&o->p, q[o->h]);
  *y = karst_i_plot_py(&o->p, q[o->v]);
}

typedef struct {
  double cx, cy, ox, oy, s; /* screen centre (px), projected centre of the box, scale */
} oblique_t;

static void map_oblique(const void *ctx, const double *q, double *x, double *y) {
  const oblique_t *o = ctx;
  double sx, sy;
  oblique(q, &sx, &sy);
  *x = o->cx + (sx - o->ox) * o->s;
  *y = o->cy - (sy - o->oy) * o->s;
}

/* A scale bar of a nice length near VIEW_SCALE_SHARE of the plot width, at (x, y). */
static double scale_bar(karst_i_buf_t *b, double x, double y, double scale, double note_right) {
  double len = karst_i_nice_number(VIEW_SCALE_SHARE * VIEW_PW / scale, 1), px = len * scale;
  karst_i_svg_rect(b, x, y - 3, px / 2, 4, "#222222", "#222222", 1);
  karst_i_svg_rect(b, x + px / 2, y - 3, px / 2, 4, "#ffffff", "#222222", 1);
  char lab[48];
  snprintf(lab, sizeof lab, "%g m", len);
  double lx = x + px + 6;
  if (lx + karst_i_text_width(lab, KARST_I_NOTE_FONT) < note_right)
    karst_i_svg_text(b, lx, y + 2, "start", "note", lab);
  return lx + karst_i_text_width(lab, KARST_I_NOTE_FONT);
}

/* A north arrow at (x, y) pointing to screen direction (dx, dy) (y down), length @p len. */
static void north_arrow(karst_i_buf_t *b, double x, double y, double dx, double dy, double len) {
  double n = hypot(dx, dy);
  dx /= n, dy /= n;
  double tx = x + dx * len, ty = y + dy * len;
  karst_i_svg_line(b, x, y, tx, ty, "#222222", 1.5, NULL);
  double pts[6] = {tx,
                   ty,
                   tx - 5 * dx - 3.5 * dy,
                   ty - 5 * dy + 3.5 * dx,
                   tx - 5 * dx + 3.5 * dy,
                   ty - 5 * dy - 3.5 * dx};
  karst_i_svg_polyline(b, pts, 3, "#222222", 1, "#222222", 1);
  karst_i_svg_text(b, tx + dx * 9, ty + dy * 9 + 4, "middle", "tick", "N");
}

/* Plan (h = 0, v = 1) or section (h = 0 or 1, v = 2). */
static void view_ortho(karst_i_buf_t *b, const karst_i_frame_t *f, const karst_network_t *net,
                       const karst_network_t *survey, int h, int v, const char *title,
                       const char *svg_title) {
  const double vs = v == 2 ? f->scale * f->exaggeration : f->scale;
  const double ph = v == 2 ? VIEW_SECTION_PH : VIEW_PLAN_PH;
  double hc = (f->lo[h] + f->hi[h]) / 2, vc = (f->lo[v] + f->hi[v]) / 2;
  if (net && net->n_nodes > 0 && !f->survey_inside && net == survey) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    karst_i_bounds_add(net, lo, hi); /* the survey in its own frame: centred on itself */
    hc = (lo[h] + hi[h]) / 2, vc = (lo[v] + hi[v]) / 2;
  }
  ortho_t o = {{0, VIEW_TOP, VIEW_PW, ph, hc - VIEW_PW / 2 / f->scale, hc + VIEW_PW / 2 / f->scale,
                vc - ph / 2 / vs, vc + ph / 2 / vs},
               h,
               v};
  double widest = widest_label(o.p.ymin, o.p.ymax, v == 2 ? 4 : 5);
  o.p.x = KARST_I_AXIS_FONT + 6 + widest + 8;
  const double W = o.p.x + VIEW_PW + VIEW_RIGHT, H = VIEW_TOP + ph + 64;
  karst_i_svg_begin(b, W, H, svg_title);
  karst_i_svg_text(b, 4, 14, "start", "axis", title);
  static const char *const names[3] = {"x (m, east)", "y (m, north)", "z (m, up)"};
  karst_i_svg_axes(b, &o.p, 0, 6, v == 2 ? 4 : 5, names[h], names[v]);
  if (survey && f->survey_inside && survey != net) draw_network(b, survey, map_ortho, &o, 1);
  if (net) draw_network(b, net, map_ortho, &o, net == survey);
  double yb = VIEW_TOP + ph + 52;
  if (v == 2) {
    char ve[64];
    if (f->exaggeration > 1)
      snprintf(ve, sizeof ve, "vertical exaggeration ×%g", f->exaggeration);
    else
      snprintf(ve, sizeof ve, "no vertical exaggeration");
    double w = karst_i_text_width(ve, KARST_I_NOTE_FONT);
    karst_i_svg_text(b, W - 4, yb + 2, "end", "note", ve);
    scale_bar(b, o.p.x, yb, f->scale, W - 4 - w - KARST_I_LABEL_GAP);
  } else {
    scale_bar(b, o.p.x, yb, f->scale, W);
    north_arrow(b, o.p.x + VIEW_PW + VIEW_RIGHT / 2, VIEW_TOP + 62, 0, -1, 38);
  }
  karst_i_svg_end(b);
}

static void view_oblique(karst_i_buf_t *b, const karst_i_frame_t *f, const karst_network_t *net,
                         const karst_network_t *survey, const char *svg_title) {
  const double W = 56 + VIEW_PW + VIEW_RIGHT, H = VIEW_TOP + VIEW_PLAN_PH + 64;
  double lo[3], hi[3];
  memcpy(lo, f->lo, sizeof lo);
  memcpy(hi, f->hi, sizeof hi);
  if (net == survey && !f->survey_inside) {
    for (int k = 0; k < 3; k++)
      lo[k] = INFINITY, hi[k] = -INFINITY;
    karst_i_bounds_add(net, lo, hi);
  }
  const double s = f->oblique_scale;
  double c[3] = {(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2};
  oblique_t o = {56 + VIEW_PW / 2, VIEW_TOP + VIEW_PLAN_PH / 2, 0, 0, s};
  oblique(c, &o.ox, &o.oy);
  karst_i_svg_begin(b, W, H, svg_title);
  karst_i_svg_text(b, 4, 14, "start", "axis",
                   "oblique 3-D view from the south-south-west, 30° above the horizon");
  if (survey && f->survey_inside && survey != net) draw_network(b, survey, map_oblique, &o, 1);
  if (net) draw_network(b, net, map_oblique, &o, net == survey);
  /* Axes of a nice length in the lower left margin: the view's scale in every direction. */
  double len = karst_i_nice_number(VIEW_SCALE_SHARE * VIEW_PW / s / 2, 1);
  const double ox = 40, oy = H - 16;
  static const char *const axis[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; k++) {
    double p[3] = {0, 0, 0}, sx, sy;
    p[k] = len;
    oblique(p, &sx, &sy);
    double tx = ox + sx * s, ty = oy - sy * s;
    karst_i_svg_line(b, ox, oy, tx, ty, "#222222", 1.5, NULL);
    double n = hypot(tx - ox, ty - oy);
    karst_i_svg_text(b, tx + (tx - ox) / n * 7, ty + (ty - oy) / n * 7 + 4, "middle", "tick",
                     axis[k]);
  }
  char lab[64];
  snprintf(lab, sizeof lab, "axes x, y, z: %g m each (orthographic)", len);
  karst_i_svg_text(b, ox + 44, oy + 2, "start", "note", lab);
  double nx, ny, north[3] = {0, 1, 0}, zero[3] = {0, 0, 0}, zx, zy;
  oblique(north, &nx, &ny);
  oblique(zero, &zx, &zy);
  north_arrow(b, 56 + VIEW_PW + VIEW_RIGHT / 2, VIEW_TOP + 62, nx - zx, -(ny - zy), 38);
  karst_i_svg_end(b);
}

/**
 * The four views of @p net (see report_internal.h); @p net may be @p survey itself (the
 * survey's own row of views when it lies outside the members' frame).
 * Time complexity: O(edges × tunnel types).
 */
void karst_i_plot_views(karst_i_buf_t *b, const karst_i_frame_t *f, const karst_network_t *net,
                        const karst_network_t *survey, const char *title) {
  char t[160];
  karst_i_buf_puts(b, "<figure>");
  snprintf(t, sizeof t, "%s: plan", title);
  view_ortho(b, f, net, survey, 0, 1, "plan (x–y), north up", t);
  karst_i_buf_puts(b, "</figure><figure>");
  snprintf(t, sizeof t, "%s: section x-z", title);
  view_ortho(b, f, net, survey, 0, 2, "section x–z, looking north", t);
  karst_i_buf_puts(b, "</figure><figure>");
  snprintf(t, sizeof t, "%s: section y-z", title);
  view_ortho(b, f, net, survey, 1, 2, "section y–z, looking west", t);
  karst_i_buf_puts(b, "</figure><figure>");
  snprintf(t, sizeof t, "%s: oblique view", title);
  view_oblique(b, f, net, survey, t);
  karst_i_buf_puts(b, "</figure>\n");
}
