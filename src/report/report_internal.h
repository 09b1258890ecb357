/*
 * The plots of the HTML report (src/report/): metric histograms, the orientation rose, the
 * degree distribution, the stereonet and the members' views. Each writes one inline <svg>.
 *
 * Layout rules every plot keeps (the Chromium test measures them): no two text boxes
 * overlap (text widths come from karst_i_text_width, lines of text have their own rows);
 * annotations sit outside the plotted data (legends and notes in margins above or below);
 * every bar is filled and at least KARST_I_MIN_BAR_PX wide; every axis names its quantity and
 * unit. Data marks carry a CSS class ("bar", "band", "survey", "structure", "density") so the
 * test can find them.
 */
#ifndef KARST_REPORT_INTERNAL_H
#define KARST_REPORT_INTERNAL_H

#include "karst/compare.h"
#include "karst/ensemble.h"
#include "karst/network.h"
#include "report/svg_internal.h"

/** Narrowest bar drawn, in pixels. */
#define KARST_I_MIN_BAR_PX 2.0

/** "quantity (unit)" of a metric column: its label and unit from karst_metric_fields
 *  ("dimensionless" for unit 1), or the bare key when the table does not know it. */
void karst_i_metric_axis_label(char *out, size_t size, const char *key);

/** Whether column @p col of @p t is constant over its defined values (or undefined for all):
 *  then it is listed as a value, not plotted. *@p value receives the value (NAN if none) and
 *  *@p n the number of members with a value. */
int karst_i_column_constant(const karst_ensemble_table_t *t, int col, double *value,
                            karst_int_t *n);

/** Dash pattern of survey @p survey's lines (0-based, in the order given). */
const char *karst_i_survey_dash(int survey);

/** Histogram of a non-constant column with the survey values of @p res (n_res results; 0:
 *  no survey) and the range of the 34 published caves; a broken axis when a survey value is
 *  far from the ensemble. */
void karst_i_plot_histogram(karst_i_buf_t *b, const karst_ensemble_table_t *t, int col,
                            const karst_compare_result_t *res, int n_res);

/** Length-weighted azimuth histogram (horizontal length, [0, 180) folded) into @p nb bins. */
void karst_i_rose_accumulate(const karst_network_t *net, double *bins, int nb);
/** Equal-area rose of the pooled members and the survey, one common scale. */
void karst_i_plot_rose(karst_i_buf_t *b, const double *ens, const double *survey, int nb,
                       karst_int_t pooled, const char *survey_label);

/** Nodes of degree 1 .. max_degree (the last pools higher degrees) into count[1..]. */
void karst_i_degree_accumulate(const karst_network_t *net, double *count, int max_degree);
void karst_i_plot_degrees(karst_i_buf_t *b, const double *ens, const double *survey, int max_degree,
                          const char *survey_label);

/** Orientations pooled for the stereonet: a grid of conduit length on the equal-area net. */
typedef struct karst_i_stereo {
  int n;          /**< cells per side of the square grid over the net */
  double *length; /**< n * n: conduit length whose line falls in each cell */
  double total;   /**< length pooled */
} karst_i_stereo_t;

/** A fracture family: a plane given by dip direction and dip (degrees). */
typedef struct karst_i_plane {
  double dip_direction, dip;
} karst_i_plane_t;

int karst_i_stereo_init(karst_i_stereo_t *s, int n);
void karst_i_stereo_destroy(karst_i_stereo_t *s);
/** Add the edges of @p net (each a line: trend and plunge of its downward direction). */
void karst_i_stereo_accumulate(karst_i_stereo_t *s, const karst_network_t *net);
/** Equal-area position (unit circle, x east, y north) of the line of trend / plunge degrees
 *  on the lower hemisphere (Schmidt net): r = sqrt(2) sin((90 - plunge) / 2). */
void karst_i_stereo_project(double trend, double plunge, double *x, double *y);
/** Lower-hemisphere equal-area stereonet: the ensemble's density, the survey's conduits as
 *  points, the fracture families as great circles. */
void karst_i_plot_stereonet(karst_i_buf_t *b, const karst_i_stereo_t *ens,
                            const karst_network_t *survey, const char *survey_label,
                            const karst_i_plane_t *planes, int n_planes, karst_int_t pooled);

/** The frame every member view shares: one scale for all members (and the survey). */
typedef struct karst_i_frame {
  double lo[3], hi[3];  /**< the box drawn (members, and the survey when it overlaps) */
  double scale;         /**< pixels per metre, the same in every view and member */
  double oblique_scale; /**< pixels per metre of the oblique views (same for all of them) */
  double exaggeration;  /**< vertical exaggeration of the sections (1: none) */
  int survey_inside;    /**< the survey overlaps the members in plan: drawn in their frame */
} karst_i_frame_t;

/** Grow @p lo, @p hi (start at +/-INFINITY) by the nodes of @p net. */
void karst_i_bounds_add(const karst_network_t *net, double lo[3], double hi[3]);
/** The common frame of members within @p lo, @p hi and a survey (NULL: none). */
void karst_i_frame_make(karst_i_frame_t *f, const double lo[3], const double hi[3],
                        const karst_network_t *survey);
/** The four views of one network (plan, section x-z looking north, section y-z looking west,
 *  oblique 3-D), coloured by tunnel type, with @p survey drawn in the same frame when
 *  @p f->survey_inside; north arrows and scale bars. @p title names the network. */
void karst_i_plot_views(karst_i_buf_t *b, const karst_i_frame_t *f, const karst_network_t *net,
                        const karst_network_t *survey, const char *title);
/** Number of <svg> karst_i_plot_views writes. */
#define KARST_I_VIEWS_PER_NETWORK 4

#endif
