/*
 * A small SVG writer for the HTML report: a growable text buffer, XML-escaped
 * text, lines, rectangles, polylines, paths, markers, and plot axes whose
 * ticks are Heckbert's "nice numbers" (Graphics Gems, 1990).
 * Coordinates are SVG pixels (y down); a karst_i_plot_t maps data to pixels.
 */
#ifndef KARST_SVG_INTERNAL_H
#define KARST_SVG_INTERNAL_H

#include <stddef.h>

#include "karst/common.h"

/** Growable text; after an allocation failure @c failed is set and writes are dropped. */
typedef struct karst_i_buf {
  char *s;
  size_t len, cap;
  int failed;
} karst_i_buf_t;

void karst_i_buf_init(karst_i_buf_t *b);
void karst_i_buf_destroy(karst_i_buf_t *b);
void karst_i_buf_printf(karst_i_buf_t *b, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
void karst_i_buf_puts(karst_i_buf_t *b, const char *s);
/** Append @p s with &, <, >, " and ' escaped (valid in XML text and attribute values). */
void karst_i_buf_escape(karst_i_buf_t *b, const char *s);
/** Write the text of @p b to @p path atomically; KARST_ENOMEM (nothing written) when an
 *  append to @p b failed. */
karst_error_t karst_i_buf_write_file(karst_ctx_t *ctx, const karst_i_buf_t *b, const char *path);

/** Heckbert's nice number: 1, 2, 5 or 10 × 10^k near @p x (> 0); rounded or ceiling. */
double karst_i_nice_number(double x, int round);

/** Tick positions: first, step and count (first + i·step, i < count). */
typedef struct karst_i_ticks {
  double first, step;
  int count;
  int decimals; /**< digits after the point that show the step exactly */
} karst_i_ticks_t;

/**
 * "Loose" nice ticks covering [lo, hi] with about @p target ticks (Heckbert
 * 1990): step = nice(nice(hi − lo) / (target − 1)), first = ⌊lo/step⌋·step,
 * last = ⌈hi/step⌉·step. An empty range (lo = hi) is widened to lo ± max(|lo|/10, 1)
 * (KARST_I_TICKS_EMPTY_WIDTH). Returns -1 for non-finite input or target < 2.
 */
int karst_i_ticks_loose(double lo, double hi, int target, karst_i_ticks_t *t);
/** Ticks of the same step that fall inside [lo, hi] ("tight" axes, e.g. equal-aspect maps). */
int karst_i_ticks_inside(double lo, double hi, int target, karst_i_ticks_t *t);
/** Format tick value @p v with @p decimals digits ("-0" printed as "0"). */
void karst_i_tick_label(char *out, size_t size, double v, int decimals);

/** A plot area: pixel rectangle (x, y, w, h) and the data ranges it shows. */
typedef struct karst_i_plot {
  double x, y, w, h;
  double xmin, xmax, ymin, ymax;
} karst_i_plot_t;

double karst_i_plot_px(const karst_i_plot_t *p, double x);
double karst_i_plot_py(const karst_i_plot_t *p, double y);

/** Open <svg> of the given size with a <title> (escaped) for screen readers. */
void karst_i_svg_begin(karst_i_buf_t *b, double width, double height, const char *title);
void karst_i_svg_end(karst_i_buf_t *b);
/** Text at (x, y); anchor "start" | "middle" | "end"; @p cls a CSS class or NULL. */
void karst_i_svg_text(karst_i_buf_t *b, double x, double y, const char *anchor, const char *cls,
                      const char *text);
void karst_i_svg_line(karst_i_buf_t *b, double x1, double y1, double x2, double y2,
                      const char *stroke, double width, const char *dash);
void karst_i_svg_rect(karst_i_buf_t *b, double x, double y, double w, double h, const char *fill,
                      const char *stroke, double opacity);
/** Polyline through @p n points (xy pairs); @p closed draws a polygon. */
void karst_i_svg_polyline(karst_i_buf_t *b, const double *xy, int n, const char *stroke,
                          double width, const char *fill, int closed);
/** A circle marker. */
void karst_i_svg_marker(karst_i_buf_t *b, double x, double y, double r, const char *fill,
                        const char *stroke);

/** Font sizes (px) of the CSS classes tick, note and axis (report.c's style sheet). */
#define KARST_I_TICK_FONT 10.0
#define KARST_I_NOTE_FONT 10.0
#define KARST_I_AXIS_FONT 11.0
/** Least distance in pixels between two text boxes, and between a text box and data. */
#define KARST_I_LABEL_GAP 3.0

/** Estimated width in pixels of @p s in the sans-serif font of @p font_px pixels. */
double karst_i_text_width(const char *s, double font_px);
/** @p text, cut with "…" to at most @p width pixels of the note font. */
void karst_i_fit_text(char *out, size_t size, const char *text, double width);
/** A filled rectangle of CSS class @p cls (data marks: "bar", "band"). */
void karst_i_svg_rect_class(karst_i_buf_t *b, double x, double y, double w, double h,
                            const char *fill, const char *cls);
/** A line of CSS class @p cls (data marks: "survey", "structure"). */
void karst_i_svg_line_class(karst_i_buf_t *b, double x1, double y1, double x2, double y2,
                            const char *stroke, double width, const char *dash, const char *cls);
/** X tick marks and labels of @p t within pixels [px0, px1], labels never closer than
 *  KARST_I_LABEL_GAP (*@p right: right end of the last label, -INFINITY to start). */
void karst_i_svg_xticks(karst_i_buf_t *b, const karst_i_plot_t *p, const karst_i_ticks_t *t,
                        double px0, double px1, double *right);
/** Y tick marks and labels; returns the widest label's width. */
double karst_i_svg_yticks(karst_i_buf_t *b, const karst_i_plot_t *p, const karst_i_ticks_t *t);
/** The rotated y-axis title, left of labels @p widest pixels wide. */
void karst_i_svg_ylabel(karst_i_buf_t *b, const karst_i_plot_t *p, double widest,
                        const char *label);

/**
 * Axes with ticks and labels. When @p expand is set, the plot ranges are
 * widened to loose nice ticks first; otherwise ticks are placed inside the
 * given ranges. Draws the frame, tick marks, tick labels and axis titles.
 * Returns -1 (nothing drawn) on non-finite ranges.
 */
int karst_i_svg_axes(karst_i_buf_t *b, karst_i_plot_t *p, int expand, int xticks, int yticks,
                     const char *xlabel, const char *ylabel);

/* --- density.c: the plan-view density map of simulated conduits ----------------------------- */
struct karst_network;
typedef struct karst_i_density {
  double lo[2], cell; /**< grid origin (x, y) and cell size (m) */
  int nx, ny;
  int *count;      /**< per cell: members with a simulated conduit in it */
  int *stamp;      /**< per cell: the last member that counted it */
  int members;     /**< members added */
  int conditioned; /**< 1 when some member has a surveyed edge (observed = 1) */
  double *legs;    /**< 4 per surveyed leg of the first member: x0 y0 x1 y1 */
  long long n_legs, cap_legs;
} karst_i_density_t;
int karst_i_density_init(karst_i_density_t *d, const double lo[2], const double hi[2]);
void karst_i_density_destroy(karst_i_density_t *d);
int karst_i_density_add(karst_i_density_t *d, const struct karst_network *net);
void karst_i_density_plot(karst_i_buf_t *b, const karst_i_density_t *d, const char *title,
                          const char *leg_colour);

#endif
