/**
 * @file conditioning.h
 * @brief Realisations that contain surveyed passages (docs/generation.md, "Conditioning"): the
 *        surveys a scenario names are read with the network readers (karst_read_network),
 *        converted into the scenario's coordinate system, checked against the domain and the
 *        terrain; their stations become samples, their legs graph edges of near-zero cost and
 *        edges of every network (edge attribute "observed" = 1), and each connected piece of
 *        the survey is joined to the simulated network by the routing.
 */
#ifndef KARST_CONDITIONING_H
#define KARST_CONDITIONING_H

#include "karst/common.h"
#include "karst/graph.h"
#include "karst/scenario.h"
#include "karst/skeleton.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The surveys of a scenario, merged, in the scenario's frame. */
typedef struct karst_survey_set {
  karst_int_t n_stations;
  double *xyz;             /**< 3 per station (m, the scenario's CRS) */
  char **labels;           /**< station names (entries may be NULL) */
  unsigned char *entrance; /**< 1 where a survey flags the station an entrance */
  double *lrud;            /**< 4 per station: left, right, up, down (m), NAN when not surveyed */
  int *survey;             /**< index (in conditioning.surveys) of the file a station comes from */
  karst_int_t n_legs;
  karst_int_t *legs;       /**< 2 per leg: station indices */
  karst_int_t n_components;
  karst_int_t *component;  /**< per station: its connected piece of the survey, 0 .. n_components-1 */
  karst_int_t *component_station; /**< per piece: its lowest station (ties: the first) */
  double length;           /**< total length of the legs (m) */
  int n_surveys;
  char **source_crs;       /**< per survey: the CRS its file was in (NULL: none, taken as the
                                scenario's) */
  char **conversion;       /**< per survey: how it was converted (karst_crs_describe), or NULL */
  double *accuracy;        /**< per survey: the accuracy of that conversion (m; 0 exact, -1 unknown) */
} karst_survey_set_t;

/** Release a survey set (NULL is fine). */
void karst_survey_set_free(karst_survey_set_t *s);

/**
 * Read the surveys of sc->conditioning into sc->conditioning.data: each file with
 * karst_read_network (any format `karst metrics` reads; splay, surface and duplicate legs are
 * dropped by the readers as Survex does), converted from its CRS (the scenario's entry, else the
 * file's own) into the scenario's CRS, stations merged where two surveys put them at the same
 * point. Called by karst_scenario_load. O(stations + legs) after the readers.
 */
karst_error_t karst_conditioning_load(karst_ctx_t *ctx, karst_scenario_t *sc);

/** Index of the station named @p name, or -1. O(stations). */
karst_int_t karst_survey_find_station(const karst_survey_set_t *s, const char *name);

/**
 * Whether every station lies in the domain and at or below the terrain; otherwise
 * KARST_ERANGE with the survey, the station farthest out, by how much, and how many are out.
 * O(stations).
 */
karst_error_t karst_conditioning_check(karst_ctx_t *ctx, const karst_scenario_t *sc);

/**
 * Append the stations that are not key points to @p samples (source "survey") and write the
 * sample (graph vertex) of every station to @p station_vertex (n_stations entries): a station a
 * key point sits on is that key point's sample. O(stations).
 */
karst_error_t karst_conditioning_add_samples(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                             karst_samples_t *samples, karst_int_t *station_vertex);

/**
 * Make every leg an edge of @p g of cost cost_factor × @p lb_per_metre × its length: an edge the
 * k-nearest-neighbour graph already has gets that cost, the others are added (src/conditioning/
 * conditioning_graph.c). O(n + arcs + legs log legs).
 */
karst_error_t karst_conditioning_add_legs(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                          const karst_int_t *station_vertex, double lb_per_metre,
                                          karst_graph_t *g);

/** The smallest cost per metre an edge of a graph carrying the legs can have. O(1). */
double karst_conditioning_lower_bound_per_metre(const karst_scenario_t *sc, double lb_per_metre);

/**
 * Lay every leg as an edge of @p sk (edge attribute "observed" = 1; nodes get the station name
 * as label and "observed" = 1). O(legs × degree).
 */
karst_error_t karst_conditioning_lay(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                     const karst_graph_t *g, const karst_int_t *station_vertex,
                                     karst_skeleton_t *sk);

/**
 * Give the surveyed nodes and edges of @p sk that drain nowhere yet the spring that the routing
 * of the generation @p view routes sends their piece of the survey to (the key_spring, from a
 * routing plan, of a key point on a station of the piece). O(stations + edges).
 */
karst_error_t karst_conditioning_assign_springs(karst_ctx_t *ctx, const karst_scenario_t *view,
                                                const karst_int_t *station_vertex,
                                                const int *key_spring, karst_skeleton_t *sk);

/**
 * The radius of every surveyed edge of @p out (the network karst_amplification_displace made from
 * @p sk) from the LRUD of its stations where they were surveyed: per station the mean of the
 * half-width (L + R) / 2 and the half-height (U + D) / 2 it has, per edge the mean of its
 * stations' values; edges without LRUD keep the classification's radius. O(nodes + edges).
 */
karst_error_t karst_conditioning_passage_radius(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                                const karst_int_t *station_vertex,
                                                const karst_skeleton_t *sk, karst_network_t *out);

#ifdef __cplusplus
}
#endif
#endif /* KARST_CONDITIONING_H */
