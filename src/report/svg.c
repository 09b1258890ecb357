/* A small SVG writer (src/report/svg_internal.h). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "karst/io.h"
#include "report/svg_internal.h"

/** Relative half-width given to an empty data range (lo = hi) so an axis can still be drawn;
 *  at least KARST_I_TICKS_EMPTY_MIN_WIDTH in data units. */
#define KARST_I_TICKS_EMPTY_WIDTH 0.1
#define KARST_I_TICKS_EMPTY_MIN_WIDTH 1.0
/** Text boxes are estimated this much wider than the font metrics give (kerning, hinting). */
#define KARST_I_TEXT_WIDTH_MARGIN 1.04

void karst_i_buf_init(karst_i_buf_t *b) {
  memset(b, 0, sizeof *b);
}
void karst_i_buf_destroy(karst_i_buf_t *b) {
  free(b->s);
  memset(b, 0, sizeof *b);
}

static int buf_reserve(karst_i_buf_t *b, size_t extra) {
  if (b->failed) return -1;
  if (b->len + extra + 1 <= b->cap) return 0;
  size_t cap = b->cap ? b->cap : 4096;
  while (cap < b->len + extra + 1)
    cap *= 2;
  char *s = realloc(b->s, cap);
  if (!s) {
    b->failed = 1;
    return -1;
  }
  b->s = s;
  b->cap = cap;
  return 0;
}

void karst_i_buf_printf(karst_i_buf_t *b, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int n = vsnprintf(NULL, 0, fmt, ap);
  va_end(ap);
  if (n < 0 || buf_reserve(b, (size_t)n) != 0) {
    b->failed = 1;
    return;
  }
  va_start(ap, fmt);
  vsnprintf(b->s + b->len, b->cap - b->len, fmt, ap);
  va_end(ap);
  b->len += (size_t)n;
}

void karst_i_buf_puts(karst_i_buf_t *b, const char *s) {
  size_t n = strlen(s);
  if (buf_reserve(b, n) != 0) return;
  memcpy(b->s + b->len, s, n + 1);
  b->len += n;
}

void karst_i_buf_escape(karst_i_buf_t *b, const char *s) {
  for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
    switch (*p) {
    case '&':
      karst_i_buf_puts(b, "&amp;");
      break;
    case '<':
      karst_i_buf_puts(b, "&lt;");
      break;
    case '>':
      karst_i_buf_puts(b, "&gt;");
      break;
    case '"':
      karst_i_buf_puts(b, "&quot;");
      break;
    case '\'':
      karst_i_buf_puts(b, "&#39;");
      break;
    default:
      /* Control characters other than tab/newline are not allowed in XML 1.0. */
      if (*p < 0x20 && *p != '\t' && *p != '\n')
        karst_i_buf_puts(b, "?");
      else
        karst_i_buf_printf(b, "%c", *p);
    }
  }
}

/**
 * Heckbert's nice number (Graphics Gems, 1990, "Nice numbers for graph
 * labels"): with x = f·10^e, 1 <= f < 10, return n·10^e where n is, when
 * rounding, 1 (f < 1.5), 2 (f < 3), 5 (f < 7) or 10; otherwise the ceiling
 * 1 (f <= 1), 2 (f <= 2), 5 (f <= 5) or 10. O(1).
 */
double karst_i_nice_number(double x, int round) {
  if (!(x > 0) || !isfinite(x)) return NAN;
  double e = floor(log10(x));
  double f = x / pow(10.0, e);
  double n;
  if (round)
    n = f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10;
  else
    n = f <= 1 ? 1 : f <= 2 ? 2 : f <= 5 ? 5 : 10;
  return n * pow(10.0, e);
}

static int widen(double *lo, double *hi) {
  if (!isfinite(*lo) || !isfinite(*hi)) return -1;
  if (*lo > *hi) {
    double t = *lo;
    *lo = *hi;
    *hi = t;
  }
  if (*lo == *hi) {
    double w = fmax(fabs(*lo) * KARST_I_TICKS_EMPTY_WIDTH, KARST_I_TICKS_EMPTY_MIN_WIDTH);
    *lo -= w;
    *hi += w;
  }
  return 0;
}

static double tick_step(double lo, double hi, int target) {
  double range = karst_i_nice_number(hi - lo, 0);
  return karst_i_nice_number(range / (target - 1), 1);
}

static int decimals_of(double step) {
  int d = (int)-floor(log10(step) + 1e-9);
  return d > 0 ? d : 0;
}

/** Loose nice ticks (see svg_internal.h). O(1). */
int karst_i_ticks_loose(double lo, double hi, int target, karst_i_ticks_t *t) {
  memset(t, 0, sizeof *t);
  if (target < 2 || widen(&lo, &hi) != 0) return -1;
  double step = tick_step(lo, hi, target);
  double k0 = floor(lo / step), k1 = ceil(hi / step);
  t->step = step;
  t->first = k0 * step;
  t->count = (int)(k1 - k0) + 1;
  t->decimals = decimals_of(step);
  return 0;
}

/** Ticks of the loose step that fall inside [lo, hi]. O(1). */
int karst_i_ticks_inside(double lo, double hi, int target, karst_i_ticks_t *t) {
  memset(t, 0, sizeof *t);
  if (target < 2 || widen(&lo, &hi) != 0) return -1;
  double step = tick_step(lo, hi, target);
  double k0 = ceil(lo / step), k1 = floor(hi / step);
  t->step = step;
  t->first = k0 * step;
  t->count = k1 >= k0 ? (int)(k1 - k0) + 1 : 0;
  t->decimals = decimals_of(step);
  return 0;
}

void karst_i_tick_label(char *out, size_t size, double v, int decimals) {
  snprintf(out, size, "%.*f", decimals, v);
  /* "-0", "-0.0": a tick at zero computed as -1e-17 must read 0. */
  int zero = 1;
  for (const char *p = out; *p; p++)
    if (*p >= '1' && *p <= '9') zero = 0;
  if (zero && out[0] == '-') memmove(out, out + 1, strlen(out));
}

double karst_i_plot_px(const karst_i_plot_t *p, double x) {
  return p->x + (x - p->xmin) / (p->xmax - p->xmin) * p->w;
}
double karst_i_plot_py(const karst_i_plot_t *p, double y) {
  return p->y + p->h - (y - p->ymin) / (p->ymax - p->ymin) * p->h;
}

void karst_i_svg_begin(karst_i_buf_t *b, double width, double height, const char *title) {
  karst_i_buf_printf(b,
                     "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%g\" height=\"%g\" "
                     "viewBox=\"0 0 %g %g\" role=\"img\"><title>",
                     width, height, width, height);
  karst_i_buf_escape(b, title ? title : "");
  karst_i_buf_puts(b, "</title>\n");
}

void karst_i_svg_end(karst_i_buf_t *b) {
  karst_i_buf_puts(b, "</svg>\n");
}

void karst_i_svg_text(karst_i_buf_t *b, double x, double y, const char *anchor, const char *cls,
                      const char *text) {
  karst_i_buf_printf(b, "<text x=\"%.2f\" y=\"%.2f\" text-anchor=\"%s\"", x, y,
                     anchor ? anchor : "start");
  if (cls) {
    karst_i_buf_puts(b, " class=\"");
    karst_i_buf_escape(b, cls);
    karst_i_buf_puts(b, "\"");
  }
  karst_i_buf_puts(b, ">");
  karst_i_buf_escape(b, text);
  karst_i_buf_puts(b, "</text>\n");
}

void karst_i_svg_line(karst_i_buf_t *b, double x1, double y1, double x2, double y2,
                      const char *stroke, double width, const char *dash) {
  karst_i_buf_printf(b,
                     "<line x1=\"%.2f\" y1=\"%.2f\" x2=\"%.2f\" y2=\"%.2f\" stroke=\"%s\" "
                     "stroke-width=\"%g\"",
                     x1, y1, x2, y2, stroke, width);
  if (dash) karst_i_buf_printf(b, " stroke-dasharray=\"%s\"", dash);
  karst_i_buf_puts(b, "/>\n");
}

void karst_i_svg_rect(karst_i_buf_t *b, double x, double y, double w, double h, const char *fill,
                      const char *stroke, double opacity) {
  karst_i_buf_printf(b, "<rect x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"%.2f\" fill=\"%s\"", x,
                     y, w < 0 ? 0 : w, h < 0 ? 0 : h, fill ? fill : "none");
  if (stroke) karst_i_buf_printf(b, " stroke=\"%s\"", stroke);
  if (opacity < 1) karst_i_buf_printf(b, " fill-opacity=\"%g\"", opacity);
  karst_i_buf_puts(b, "/>\n");
}

void karst_i_svg_polyline(karst_i_buf_t *b, const double *xy, int n, const char *stroke,
                          double width, const char *fill, int closed) {
  if (n < 1) return;
  karst_i_buf_printf(b, "<%s points=\"", closed ? "polygon" : "polyline");
  for (int i = 0; i < n; i++)
    karst_i_buf_printf(b, "%s%.2f,%.2f", i ? " " : "", xy[2 * i], xy[2 * i + 1]);
  karst_i_buf_printf(b, "\" fill=\"%s\" stroke=\"%s\" stroke-width=\"%g\"/>\n",
                     fill ? fill : "none", stroke ? stroke : "none", width);
}

void karst_i_svg_marker(karst_i_buf_t *b, double x, double y, double r, const char *fill,
                        const char *stroke) {
  karst_i_buf_printf(b, "<circle cx=\"%.2f\" cy=\"%.2f\" r=\"%g\" fill=\"%s\" stroke=\"%s\"/>\n", x,
                     y, r, fill ? fill : "none", stroke ? stroke : "none");
}

/**
 * Width in pixels of @p s set in the report's font (DejaVu Sans, the widest of the common
 * sans-serif faces, and the one the report's style sheet asks for first) of @p font_px pixels:
 * per-character advance widths in em from DejaVu Sans 2.37 (digits 0.636, narrow letters and
 * punctuation 0.28-0.32, f j r t and brackets 0.35-0.41, m w M W % 0.82-0.99, capitals
 * 0.68-0.78, non-ASCII such as "…" up to 1), each class at its widest, times
 * KARST_I_TEXT_WIDTH_MARGIN, so a layout that avoids these boxes avoids the rendered ones.
 * O(length).
 */
double karst_i_text_width(const char *s, double font_px) {
  double em = 0;
  for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
    unsigned char c = *p;
    if ((c & 0xC0) == 0x80) continue; /* continuation byte */
    if (c >= 0x80) /* "…" and "–" are as wide as an em in DejaVu Sans, "°" half */
      em += 1.0;
    else if (strchr("il.,:;'|!", c))
      em += 0.32;
    else if (strchr("fjrt()[] -/", c))
      em += 0.41;
    else if (strchr("mwMW%", c))
      em += 0.99;
    else if (c >= 'A' && c <= 'Z')
      em += 0.78;
    else
      em += 0.64;
  }
  return em * font_px * KARST_I_TEXT_WIDTH_MARGIN;
}

/** @p text cut (with "…") to at most @p width pixels of the note font. O(length²). */
void karst_i_fit_text(char *out, size_t size, const char *text, double width) {
  snprintf(out, size, "%s", text);
  if (karst_i_text_width(out, KARST_I_NOTE_FONT) <= width) return;
  size_t n = strlen(out);
  for (; n > 0; n--) {
    if (((unsigned char)text[n] & 0xC0) == 0x80) continue; /* cut between UTF-8 characters */
    if (n + 4 > size) continue;
    memcpy(out, text, n);
    memcpy(out + n, "…", 4); /* three bytes and the terminator */
    if (karst_i_text_width(out, KARST_I_NOTE_FONT) <= width) return;
  }
  snprintf(out, size, "…");
}

void karst_i_svg_rect_class(karst_i_buf_t *b, double x, double y, double w, double h,
                            const char *fill, const char *cls) {
  karst_i_buf_printf(b,
                     "<rect class=\"%s\" x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"%.2f\" "
                     "fill=\"%s\"/>\n",
                     cls, x, y, w < 0 ? 0 : w, h < 0 ? 0 : h, fill);
}

void karst_i_svg_line_class(karst_i_buf_t *b, double x1, double y1, double x2, double y2,
                            const char *stroke, double width, const char *dash, const char *cls) {
  karst_i_buf_printf(b,
                     "<line class=\"%s\" x1=\"%.2f\" y1=\"%.2f\" x2=\"%.2f\" y2=\"%.2f\" "
                     "stroke=\"%s\" stroke-width=\"%g\"",
                     cls, x1, y1, x2, y2, stroke, width);
  if (dash) karst_i_buf_printf(b, " stroke-dasharray=\"%s\"", dash);
  karst_i_buf_puts(b, "/>\n");
}

/**
 * Tick marks and labels along the bottom of @p p between pixels @p px0 and @p px1 for the
 * values of @p t; a label is left out when its box would come closer than
 * KARST_I_LABEL_GAP pixels to the previous one kept (*@p right, the right end of the last
 * label, updated; start it at -INFINITY). O(ticks).
 */
void karst_i_svg_xticks(karst_i_buf_t *b, const karst_i_plot_t *p, const karst_i_ticks_t *t,
                        double px0, double px1, double *right) {
  char lab[64];
  for (int i = 0; i < t->count; i++) {
    double v = t->first + i * t->step;
    double px = karst_i_plot_px(p, v);
    if (px < px0 - 0.5 || px > px1 + 0.5) continue;
    karst_i_svg_line(b, px, p->y + p->h, px, p->y + p->h + 4, "#444", 1, NULL);
    karst_i_tick_label(lab, sizeof lab, v, t->decimals);
    double w = karst_i_text_width(lab, KARST_I_TICK_FONT);
    if (px - w / 2 < *right + KARST_I_LABEL_GAP) continue;
    karst_i_svg_text(b, px, p->y + p->h + 15, "middle", "tick", lab);
    *right = px + w / 2;
  }
}

int karst_i_svg_axes(karst_i_buf_t *b, karst_i_plot_t *p, int expand, int xticks, int yticks,
                     const char *xlabel, const char *ylabel) {
  karst_i_ticks_t tx, ty;
  int (*ticks)(double, double, int, karst_i_ticks_t *) =
      expand ? karst_i_ticks_loose : karst_i_ticks_inside;
  if (ticks(p->xmin, p->xmax, xticks, &tx) != 0 || ticks(p->ymin, p->ymax, yticks, &ty) != 0)
    return -1;
  if (expand) {
    p->xmin = tx.first;
    p->xmax = tx.first + (tx.count - 1) * tx.step;
    p->ymin = ty.first;
    p->ymax = ty.first + (ty.count - 1) * ty.step;
  } else {
    widen(&p->xmin, &p->xmax);
    widen(&p->ymin, &p->ymax);
  }
  karst_i_svg_rect(b, p->x, p->y, p->w, p->h, "none", "#444", 1);
  double right = -INFINITY;
  karst_i_svg_xticks(b, p, &tx, p->x, p->x + p->w, &right);
  double widest = karst_i_svg_yticks(b, p, &ty);
  if (xlabel) karst_i_svg_text(b, p->x + p->w / 2, p->y + p->h + 30, "middle", "axis", xlabel);
  if (ylabel) karst_i_svg_ylabel(b, p, widest, ylabel);
  return 0;
}

/**
 * Tick marks and labels of @p t along the left side of @p p; a label is left out when it
 * would come closer than KARST_I_LABEL_GAP to the previous one kept (above or below).
 * @return the width of the widest label drawn (for karst_i_svg_ylabel). O(ticks).
 */
double karst_i_svg_yticks(karst_i_buf_t *b, const karst_i_plot_t *p, const karst_i_ticks_t *t) {
  char lab[64];
  double widest = 0, last = INFINITY;
  for (int i = 0; i < t->count; i++) {
    double v = t->first + i * t->step;
    double py = karst_i_plot_py(p, v);
    if (py < p->y - 0.5 || py > p->y + p->h + 0.5) continue;
    karst_i_svg_line(b, p->x - 4, py, p->x, py, "#444", 1, NULL);
    if (py > last - KARST_I_TICK_FONT - KARST_I_LABEL_GAP) continue;
    karst_i_tick_label(lab, sizeof lab, v, t->decimals);
    karst_i_svg_text(b, p->x - 6, py + 4, "end", "tick", lab);
    widest = fmax(widest, karst_i_text_width(lab, KARST_I_TICK_FONT));
    last = py;
  }
  return widest;
}

/** The title of the y axis, rotated, left of tick labels at most @p widest pixels wide. */
void karst_i_svg_ylabel(karst_i_buf_t *b, const karst_i_plot_t *p, double widest,
                        const char *label) {
  /* The rotated text's glyphs reach about one font height left of its baseline. */
  double x = fmax(p->x - 6 - widest - KARST_I_LABEL_GAP - 3, KARST_I_AXIS_FONT);
  karst_i_buf_printf(b, "<g transform=\"translate(%.2f %.2f) rotate(-90)\">", x, p->y + p->h / 2);
  karst_i_svg_text(b, 0, 0, "middle", "axis", label);
  karst_i_buf_puts(b, "</g>\n");
}

/**
 * Write the text of @p b to @p path atomically (karst_atomic_open / commit).
 * @return KARST_ENOMEM when an append to @p b failed (nothing is written), else the writer's code.
 * Time complexity: O(length).
 */
karst_error_t karst_i_buf_write_file(karst_ctx_t *ctx, const karst_i_buf_t *b, const char *path) {
  if (b->failed) return karst_set_error(ctx, KARST_ENOMEM, "out of memory while building %s", path);
  karst_atomic_file_t f;
  karst_error_t err = karst_atomic_open(ctx, &f, path, "wb");
  if (err) return err;
  if (b->len) fwrite(b->s, 1, b->len, f.fp);
  return karst_atomic_commit(ctx, &f);
}
