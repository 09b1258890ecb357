/**
 * @file classification.h
 * @brief Tunnel types and radii of Paris et al. 2021, §5.3 and Fig. 11:
 *        each segment labelled from its verticality, its position relative to
 *        the water table, its depth below the terrain and the resistance of
 *        the bedrock (decision table in docs/generation.md).
 */
#ifndef KARST_CLASSIFICATION_H
#define KARST_CLASSIFICATION_H

#include "karst/common.h"
#include "karst/geology.h"
#include "karst/network.h"
#include "karst/scenario.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Number of random Fourier waves of the conduit-radius field (karst_classification_run). */
#define KARST_CLASSIFICATION_RADIUS_WAVES 256

karst_tunnel_type_t karst_classification_type(const karst_geology_t *geo, int spring,
                                              const double a[3], const double b[3]);

karst_error_t karst_classification_run(karst_ctx_t *ctx, const karst_geology_t *geo,
                                       karst_rng_t *rng, karst_network_t *net);

#ifdef __cplusplus
}
#endif
#endif
