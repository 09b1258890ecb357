/**
 * @file budget.h
 * @brief What a scenario will cost before any work: samples, graph edges, path searches,
 *        amplification points and memory, from its parameters (docs/scenario.md, "Resource
 *        limits"), and the check `karst validate` and `karst generate` apply.
 */
#ifndef KARST_BUDGET_H
#define KARST_BUDGET_H

#include "karst/common.h"
#include "karst/scenario.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Most amplification steps a scenario may ask for (each is a round of path searches; real
 *  hierarchies have a few). */
#define KARST_BUDGET_MAX_AMPLIFICATION_STEPS 1000

/** Bytes the estimate counts (calibrated against peak RSS of the shipped presets; the
 *  estimate is an upper bound, docs/scenario.md gives the measured factor). */
#define KARST_BUDGET_BYTES_BASE (96.0 * 1024 * 1024) /**< the program and its libraries */
#define KARST_BUDGET_BYTES_PER_SAMPLE 512.0          /**< a sample, its grids and geology */
/** A k-NN edge: at most two arcs (itself and its reverse), each a 4-byte cost, a code byte and,
 *  at worst (every head escaped: samples in no spatial order), a 4-byte escaped head, 18 bytes
 *  (about 10.3 in the sampling's Morton order, include/karst/graph.h); while the graph is
 *  built, the k-NN lists (4 bytes per edge), a quarter of the rows 32-bit (2 bytes per edge) and
 *  the coded rows (at most 10) coexist before the costs are allocated, at most 16 bytes. */
#define KARST_BUDGET_BYTES_PER_EDGE 18.0
#define KARST_BUDGET_BYTES_PER_SEARCH_SAMPLE 40.0 /**< A* state per sample per thread */
/** Tabulated routed costs of an edge per spring (both arcs, both ways), up to
 *  KARST_ROUTING_ARC_BUDGET in all (include/karst/routing.h). */
#define KARST_BUDGET_BYTES_PER_ROUTED_EDGE 16.0
#define KARST_BUDGET_BYTES_PER_AMPLIFICATION_POINT 4096.0

/** The estimate of one scenario (karst_budget_estimate). */
typedef struct karst_budget {
  double fill_samples;    /**< upper bound of the fill samples (sphere packing of the domain) */
  double feature_samples; /**< upper bound of the feature samples (layers, permeable volumes) */
  double samples;         /**< min(fill + feature + key points, sampling.max_samples) */
  double samples_needed;  /**< fill + feature + key points, before the max_samples cap */
  double edges;           /**< k-NN edges: samples x min(k, samples - 1) */
  double amplification_points; /**< all steps together (karst_amplification_points_total) */
  double searches;             /**< A* searches: key-point pairs routed + amplification points */
  double bytes;                /**< memory, an upper bound */
  int threads;                 /**< threads the estimate assumed for the searches */
  const char *driver;          /**< the key that drives the memory most, e.g. "sampling.k" */
  karst_srcpos_t driver_pos;   /**< where the scenario gives it (0 when defaulted) */
} karst_budget_t;

/**
 * Estimate what @p sc will need with @p threads worker threads (< 1: 1). Every count is a
 * double (a 1e300 domain gives inf, not an overflow). O(steps + key points).
 */
void karst_budget_estimate(const karst_scenario_t *sc, int threads, karst_budget_t *b);

/**
 * Refuse, before any work, a scenario whose estimate exceeds @p max_memory bytes (<= 0: the
 * machine's memory, karst_budget_machine_memory), whose sample count is beyond any run
 * (more than 1000 x sampling.max_samples or not finite), or with more than
 * KARST_BUDGET_MAX_AMPLIFICATION_STEPS amplification steps: KARST_ERANGE with
 * "FILE:LINE:COLUMN: message" at the key that drives the estimate most, the estimate and the
 * limit in human units. @p out (may be NULL) receives the estimate.
 */
karst_error_t karst_budget_check(karst_ctx_t *ctx, const karst_scenario_t *sc, int threads,
                                 double max_memory, karst_budget_t *out);

/** Physical memory of the machine in bytes (sysconf), or 0 when unknown. */
double karst_budget_machine_memory(void);

/** Parse a size "512M", "8G", "1.5T", "4096" (bytes; K/M/G/T are powers of 1024, an optional
 *  trailing B or iB is allowed); 0 on success, -1 when malformed or not > 0. */
int karst_budget_parse_size(const char *s, double *bytes);

/** "1.5 GiB" into @p buf. */
const char *karst_budget_format_size(double bytes, char *buf, size_t size);

#ifdef __cplusplus
}
#endif
#endif /* KARST_BUDGET_H */
