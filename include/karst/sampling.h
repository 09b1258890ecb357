/**
 * @file sampling.h
 * @brief Adaptive Poisson-sphere sampling of the bedrock (Paris et al. 2021,
 *        §4.1): key points, feature-radius samples on the inception horizons,
 *        the water table, prescribed paths and permeable volumes, then fill.
 *        The sample container itself (karst_samples_t) is in graph.h.
 */
#ifndef KARST_SAMPLING_H
#define KARST_SAMPLING_H

#include "karst/common.h"
#include "karst/geology.h"
#include "karst/graph.h"
#include "karst/scenario.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * Dart-throwing passes over the background grid: each grid cell receives at
 * most this many darts (one per pass, cells visited in a random order), so
 * the number of failures per cell is bounded and the sampling is O(cells).
 * Default 8: measured fill densities of 0.63–0.68 samples per r³ (a
 * saturated random sequential addition reaches about 0.73 per r³, Torquato
 * 2002); the first pass alone gives about 84 % of the final count.
 */
#define KARST_SAMPLING_DART_PASSES 8
/**
 * A region needing more than this many background-grid cells per allowed
 * sample (sampling.max_samples) is refused before any work: a maximal
 * Poisson sampling with cells of size r/√3 holds at least one sample per
 * 4π√27/3 ≈ 21.8 cells, so such a region would exceed max_samples anyway.
 */
#define KARST_SAMPLING_MAX_CELLS_PER_SAMPLE 32

/**
 * Sample the bedrock of the geology @p geo (see karst_sampling_run in sampling.c for the
 * order and the rules). @p out must be initialised (karst_samples_init); its
 * previous content is replaced on success and left untouched on failure.
 */
karst_error_t karst_sampling_run(karst_ctx_t *ctx, const karst_geology_t *geo, karst_rng_t *rng,
                                 karst_samples_t *out);

#ifdef __cplusplus
}
#endif
#endif /* KARST_SAMPLING_H */
