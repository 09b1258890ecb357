/* Shared-private entry of the generation pipeline: everything after the
 * graph, so tests and benchmarks can run the path stages on a graph they
 * built themselves. */
#ifndef KARST_GENERATE_INTERNAL_H
#define KARST_GENERATE_INTERNAL_H

#include "karst/generate.h"
#include "karst/geology.h"
#include "karst/paths.h"

/* Key-point distance matrix method used by the pipeline (see paths.c for the measurement). */
#define KARST_I_KEYPOINT_METHOD KARST_PATHS_DIJKSTRA_MULTI
/* Memory (bytes) the pipeline may spend on the key points' shortest-path trees (4 bytes per
 * vertex per key point); above it, distances are computed without trees and each kept pair's
 * path is found again with A*. 1 GiB. */
#define KARST_I_TREE_BUDGET ((size_t)1 << 30)

karst_error_t karst_i_generate_from_graph(karst_ctx_t *ctx, const karst_geology_t *geo,
                                          uint64_t seed, uint64_t realisation, karst_graph_t *g,
                                          double lb_per_metre, karst_network_t *net,
                                          karst_generate_stats_t *stats);

/* The same with surveyed stations (karst_conditioning_add_samples; NULL: none) whose legs @p g
 * carries. The graph's costs are changed while a generation runs and put back bit for bit. */
karst_error_t karst_i_generate_network(karst_ctx_t *ctx, const karst_geology_t *geo, uint64_t seed,
                                       uint64_t realisation, karst_graph_t *g,
                                       const karst_int_t *station_vertex, double lb_per_metre,
                                       karst_network_t *net, karst_generate_stats_t *stats);

/* Random stream of each drawing stage (karst_rng_derive's substream). Fixed numbers, not the
 * stage indices: they are the indices the stages had while a "cost" stage was listed, kept so
 * that a seed gives the same network as before it was dropped from the timings. */
#define KARST_I_STREAM_SAMPLING 0
#define KARST_I_STREAM_AMPLIFICATION 5
#define KARST_I_STREAM_CLASSIFICATION 6
/* The geology's draws (discrete fracture networks): src/geology/geology.c's GEOLOGY_STREAM. */
#define KARST_I_STREAM_GEOLOGY 7

/* Seconds on a monotonic clock. */
double karst_i_now(void);
/* Peak resident memory of the process in bytes (VmHWM of /proc/self/status; getrusage without
 * /proc). */
size_t karst_i_peak_bytes(void);

#endif
