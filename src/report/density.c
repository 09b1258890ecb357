/*
 * The plan-view density map of the report (docs/ensembles.md, "Report"): where an ensemble
 * conditioned on a survey places the conduits it simulates. A regular grid over the domain's
 * x-y extent counts, per cell, the members that have a simulated conduit (edge attribute
 * observed = 0) crossing the cell; the surveyed legs (observed = 1) are drawn on top.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "karst/network.h"
#include "report/svg_internal.h"

/* Cells along the longer side of the domain. */
#define KARST_I_DENSITY_CELLS 64
/* A segment is walked in steps of this fraction of a cell, so it marks every cell it crosses
 * but a corner of less than this fraction of a cell. */
#define KARST_I_DENSITY_STEP 0.25
/* Colour classes of the fraction of members (upper bounds), light to dark. */
static const double class_top[] = {0.2, 0.4, 0.6, 0.8, 1.0};
static const char *const class_colour[] = {"#DCE9F5", "#A6C8E6", "#5E9CD0", "#2B6CB0", "#0B3D7A"};
#define N_CLASSES 5

/** Set up an empty map over [lo, hi] (x, y); returns -1 when out of memory or the extent is
 *  empty. O(cells). */
int karst_i_density_init(karst_i_density_t *d, const double lo[2], const double hi[2]) {
  memset(d, 0, sizeof *d);
  double dx = hi[0] - lo[0], dy = hi[1] - lo[1];
  if (!(dx > 0) || !(dy > 0) || !isfinite(dx) || !isfinite(dy)) return -1;
  d->cell = fmax(dx, dy) / KARST_I_DENSITY_CELLS;
  d->nx = (int)ceil(dx / d->cell), d->ny = (int)ceil(dy / d->cell);
  if (d->nx < 1) d->nx = 1;
  if (d->ny < 1) d->ny = 1;
  d->lo[0] = lo[0], d->lo[1] = lo[1];
  size_t n = (size_t)d->nx * (size_t)d->ny;
  d->count = calloc(n, sizeof *d->count);
  d->stamp = malloc(n * sizeof *d->stamp);
  if (!d->count || !d->stamp) {
    karst_i_density_destroy(d);
    return -1;
  }
  for (size_t i = 0; i < n; i++)
    d->stamp[i] = -1;
  return 0;
}

void karst_i_density_destroy(karst_i_density_t *d) {
  free(d->count), free(d->stamp), free(d->legs);
  memset(d, 0, sizeof *d);
}

static void mark(karst_i_density_t *d, double x, double y) {
  int i = (int)floor((x - d->lo[0]) / d->cell), j = (int)floor((y - d->lo[1]) / d->cell);
  if (i < 0 || j < 0 || i >= d->nx || j >= d->ny) return;
  size_t c = (size_t)j * (size_t)d->nx + (size_t)i;
  if (d->stamp[c] == d->members) return;
  d->stamp[c] = d->members;
  d->count[c]++;
}

/** Add one member: its simulated edges to the counts; the first member's surveyed legs are kept
 *  for drawing. Returns -1 when out of memory. O(edges × length / cell). */
int karst_i_density_add(karst_i_density_t *d, const karst_network_t *net) {
  karst_attr_t *obs = karst_network_attr_find(net, KARST_ATTR_EDGE, "observed");
  int keep_legs = d->members == 0;
  for (karst_int_t e = 0; e < net->n_edges; e++) {
    const double *a = net->xyz + 3 * net->edges[2 * e], *b = net->xyz + 3 * net->edges[2 * e + 1];
    if (obs && obs->data[e * obs->ncomp] != 0) {
      d->conditioned = 1;
      if (!keep_legs) continue;
      if (d->n_legs == d->cap_legs) {
        long long cap = d->cap_legs ? 2 * d->cap_legs : 256;
        double *l = realloc(d->legs, (size_t)cap * 4 * sizeof *l);
        if (!l) return -1;
        d->legs = l, d->cap_legs = cap;
      }
      double *l = d->legs + 4 * d->n_legs++;
      l[0] = a[0], l[1] = a[1], l[2] = b[0], l[3] = b[1];
      continue;
    }
    double len = hypot(b[0] - a[0], b[1] - a[1]);
    int steps = (int)ceil(len / (KARST_I_DENSITY_STEP * d->cell));
    if (steps > 1000000) steps = 1000000;
    for (int s = 0; s <= steps; s++) {
      double t = steps ? (double)s / steps : 0;
      mark(d, a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]));
    }
  }
  d->members++;
  return 0;
}

/** Draw the map: cells coloured by the fraction of members, the surveyed legs in @p leg_colour.
 *  O(cells + legs). */
void karst_i_density_plot(karst_i_buf_t *b, const karst_i_density_t *d, const char *title,
                          const char *leg_colour) {
  /* Room on the left for 7-digit projected coordinates, on the right for the legend. */
  const double W = 720, H = 520;
  karst_i_plot_t p = {96, 12, W - 96 - 190, H - 56, 0, 0, 0, 0};
  double ex = d->nx * d->cell, ey = d->ny * d->cell;
  double s = fmin(p.w / ex, p.h / ey);
  double mx = d->lo[0] + ex / 2, my = d->lo[1] + ey / 2;
  p.xmin = mx - p.w / s / 2, p.xmax = mx + p.w / s / 2;
  p.ymin = my - p.h / s / 2, p.ymax = my + p.h / s / 2;
  karst_i_svg_begin(b, W, H, title);
  /* The y title further left than karst_i_svg_axes puts it: projected northings are wide. */
  karst_i_svg_axes(b, &p, 0, 6, 6, "x (m)", NULL);
  karst_i_buf_printf(b, "<g transform=\"translate(%.2f %.2f) rotate(-90)\">", p.x - 78,
                     p.y + p.h / 2);
  karst_i_svg_text(b, 0, 0, "middle", "axis", "y (m)");
  karst_i_buf_puts(b, "</g>\n");
  for (int k = 0; k < N_CLASSES; k++) {
    int any = 0;
    for (int j = 0; j < d->ny; j++)
      for (int i = 0; i < d->nx; i++) {
        int c = d->count[(size_t)j * (size_t)d->nx + (size_t)i];
        if (c == 0 || d->members == 0) continue;
        double f = (double)c / d->members;
        int cls = 0;
        while (cls < N_CLASSES - 1 && f > class_top[cls])
          cls++;
        if (cls != k) continue;
        if (!any) karst_i_buf_printf(b, "<path fill=\"%s\" d=\"", class_colour[k]), any = 1;
        double x0 = karst_i_plot_px(&p, d->lo[0] + i * d->cell);
        double y1 = karst_i_plot_py(&p, d->lo[1] + (j + 1) * d->cell);
        double w = d->cell * s;
        karst_i_buf_printf(b, "M%.1f %.1fh%.2fv%.2fh%.2fz", x0, y1, w, w, -w);
      }
    if (any) karst_i_buf_puts(b, "\"/>\n");
  }
  if (d->n_legs > 0) {
    karst_i_buf_printf(b, "<path fill=\"none\" stroke=\"%s\" stroke-width=\"1.2\" d=\"",
                       leg_colour);
    for (long long l = 0; l < d->n_legs; l++) {
      const double *v = d->legs + 4 * l;
      karst_i_buf_printf(b, "M%.1f %.1fL%.1f %.1f", karst_i_plot_px(&p, v[0]),
                         karst_i_plot_py(&p, v[1]), karst_i_plot_px(&p, v[2]),
                         karst_i_plot_py(&p, v[3]));
    }
    karst_i_buf_puts(b, "\"/>\n");
  }
  /* Legend: the classes, then the survey. */
  double lx = p.x + p.w + 16, ly = p.y + 10;
  karst_i_svg_text(b, lx, ly, "start", "note", "members with a");
  karst_i_svg_text(b, lx, ly + 13, "start", "note", "simulated conduit:");
  for (int k = 0; k < N_CLASSES; k++) {
    char txt[48];
    double y = ly + 26 + 18 * k;
    karst_i_svg_rect(b, lx, y, 14, 14, class_colour[k], "#999999", 1);
    snprintf(txt, sizeof txt, "%s%.0f – %.0f %%", k ? "> " : "", k ? 100 * class_top[k - 1] : 0,
             100 * class_top[k]);
    karst_i_svg_text(b, lx + 20, y + 11, "start", "note", txt);
  }
  double y = ly + 26 + 18 * N_CLASSES + 6;
  karst_i_svg_line(b, lx, y + 7, lx + 14, y + 7, leg_colour, 2, NULL);
  karst_i_svg_text(b, lx + 20, y + 11, "start", "note", "surveyed legs");
  karst_i_svg_end(b);
}
