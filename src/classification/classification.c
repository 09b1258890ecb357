/* Tunnel types and radii (Paris et al. 2021, §5.3, Fig. 11). */
#include "karst/classification.h"

#include <math.h>
#include <stdlib.h>

/**
 * Zone of elevation @p z: within classification.water_table_band of the
 * water table (|z − W| ≤ band) → water table; above → vadose; below →
 * phreatic (Paris et al. 2021, §3 and Fig. 11). O(1).
 */
karst_zone_t karst_classification_zone(const karst_scenario_t *sc, double z) {
  double dz = z - sc->water_table;
  if (fabs(dz) <= sc->classification.water_table_band) return KARST_ZONE_WATER_TABLE;
  return dz > 0 ? KARST_ZONE_VADOSE : KARST_ZONE_PHREATIC;
}

/**
 * Tunnel type of segment a–b, our reading of Paris et al. 2021, Fig. 11 (the
 * paper fixes the inputs — verticality, distance to the water table, the
 * epikarst and the ghost-rock chambers — but gives no thresholds; ours are
 * the classification.* scenario keys). Evaluated at the segment midpoint m,
 * first rule that applies:
 *
 *   1. resistance π(m) < chamber_resistance               → chamber
 *      (breakout chambers in ghost-rock zones where c_π ≈ 0, §5.3)
 *   2. steep (angle to horizontal ≥ vertical_angle), vadose and depth below
 *      terrain < epikarst_depth                            → epikarst ("narrow vertical
 *      conduits that start from the surface", §5.3: a gentle segment near the
 *      surface is not epikarst but falls through to rule 4)
 *   3. steep:
 *        vadose or at the water table                      → tube (circular shafts, §5.3)
 *        phreatic                                          → passage (phreatic lifts)
 *   4. gentle:
 *        vadose                                            → canyon (vadose entrenchment)
 *        at the water table                                → keyhole (tube entrenched by a
 *                                                             canyon as the table falls)
 *        phreatic                                          → bed (soluble bed conduits, §5.3)
 *
 * A zero-length segment counts as gentle. O(size of the permeability tree).
 */
karst_tunnel_type_t karst_classification_type(const karst_scenario_t *sc, const double a[3],
                                              const double b[3]) {
  const karst_classification_t *cl = &sc->classification;
  double m[3] = {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
  if (karst_permeability_eval(&sc->permeability, m) < cl->chamber_resistance)
    return KARST_TUNNEL_CHAMBER;
  karst_zone_t zone = karst_classification_zone(sc, m[2]);
  double dx = b[0] - a[0], dy = b[1] - a[1], dz = b[2] - a[2];
  double angle = atan2(fabs(dz), sqrt(dx * dx + dy * dy)) * (180.0 / M_PI);
  int steep = (dx != 0 || dy != 0 || dz != 0) && angle >= cl->vertical_angle;
  if (steep) {
    double depth = karst_terrain_height(&sc->terrain, m[0], m[1]) - m[2];
    if (zone == KARST_ZONE_VADOSE && depth < cl->epikarst_depth) return KARST_TUNNEL_EPIKARST;
    return zone == KARST_ZONE_PHREATIC ? KARST_TUNNEL_PASSAGE : KARST_TUNNEL_TUBE;
  }
  switch (zone) {
  case KARST_ZONE_VADOSE:
    return KARST_TUNNEL_CANYON;
  case KARST_ZONE_WATER_TABLE:
    return KARST_TUNNEL_KEYHOLE;
  default:
    return KARST_TUNNEL_BED;
  }
}

/* Random Fourier features of the radius field: enough waves for a marginal that is normal to
 * within a few per cent (central limit over cosines of independent phases). */
#define RADIUS_FIELD_WAVES KARST_CLASSIFICATION_RADIUS_WAVES

typedef struct {
  double w[RADIUS_FIELD_WAVES][3];
  double phase[RADIUS_FIELD_WAVES];
} radius_field_t;

/* Draw a stationary Gaussian field with unit variance and covariance exp(-|h|^2 / (2 L^2)):
 * g(p) = sqrt(2 / M) sum_m cos(w_m . p + phi_m), w_m ~ N(0, I / L^2), phi_m ~ U[0, 2 pi)
 * (Rahimi & Recht 2007; the spectral method of geostatistics). */
static void radius_field_draw(radius_field_t *f, double L, karst_rng_t *rng) {
  for (int m = 0; m < RADIUS_FIELD_WAVES; m++) {
    for (int a = 0; a < 3; a++) f->w[m][a] = karst_rng_gaussian(rng) / L;
    f->phase[m] = 2 * M_PI * karst_rng_uniform(rng);
  }
}

/* Φ(g(p)) in (0, 1): uniform marginal (approximately, as g is approximately normal). */
static double radius_field_uniform(const radius_field_t *f, const double p[3]) {
  double g = 0;
  for (int m = 0; m < RADIUS_FIELD_WAVES; m++)
    g += cos(f->w[m][0] * p[0] + f->w[m][1] * p[1] + f->w[m][2] * p[2] + f->phase[m]);
  g *= sqrt(2.0 / RADIUS_FIELD_WAVES);
  return 0.5 * erfc(-g / M_SQRT2);
}

/**
 * Label every edge of @p net (Paris et al. 2021, §5.3): edge attributes
 * "tunnel_type" (karst_tunnel_type_t, karst_classification_type), "radius"
 * (m, uniform in classification.radius[type] — by default 0.5 m for
 * epikarst and [0.5, 4] m otherwise, as in §5.3 — and spatially correlated
 * over classification.radius_correlation metres, as Frantz et al. 2021
 * observe on real networks (semi-variogram ranges 50–200 m): the radius is
 * min + Φ(g(midpoint)) (max − min) for a Gaussian random field g drawn from
 * @p rng; a correlation length of 0 draws each edge independently, in edge
 * order) and "vadose" (1 when the midpoint is above the water table), and node
 * attribute "water_table_distance" (z − W, positive above).
 *
 * @return KARST_SUCCESS; KARST_EINVAL when vertical_angle is outside [0, 90]
 *         or a radius range is not 0 ≤ min ≤ max (the message names the type);
 *         KARST_ENOMEM.
 * Time complexity: O(nodes + edges × (size of the permeability tree + 256)).
 */
karst_error_t karst_classification_run(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                       karst_rng_t *rng, karst_network_t *net) {
  const karst_classification_t *cl = &sc->classification;
  if (!(cl->vertical_angle >= 0 && cl->vertical_angle <= 90))
    return karst_set_error(ctx, KARST_EINVAL,
                           "classification.vertical_angle must be within [0, 90] degrees, got %g",
                           cl->vertical_angle);
  for (int t = 0; t < KARST_TUNNEL_TYPE_COUNT; t++)
    if (!(cl->radius[t].min >= 0 && cl->radius[t].min <= cl->radius[t].max) ||
        isinf(cl->radius[t].max))
      return karst_set_error(
          ctx, KARST_EINVAL, "classification radius of %s: need 0 <= min <= max, got [%g, %g]",
          karst_tunnel_type_name((karst_tunnel_type_t)t), cl->radius[t].min, cl->radius[t].max);
  double *type, *radius, *vadose, *wtd;
  if (karst_network_attr_add(net, KARST_ATTR_EDGE, "tunnel_type", 1, 1, &type) ||
      karst_network_attr_add(net, KARST_ATTR_EDGE, "radius", 1, 0, &radius) ||
      karst_network_attr_add(net, KARST_ATTR_EDGE, "vadose", 1, 1, &vadose) ||
      karst_network_attr_add(net, KARST_ATTR_NODE, "water_table_distance", 1, 0, &wtd))
    return karst_set_error(ctx, KARST_ENOMEM, "classification: out of memory");
  for (karst_int_t v = 0; v < net->n_nodes; v++)
    wtd[v] = net->xyz[3 * v + 2] - sc->water_table;
  radius_field_t *field = NULL;
  if (cl->radius_correlation > 0) {
    if (!(field = malloc(sizeof *field)))
      return karst_set_error(ctx, KARST_ENOMEM, "classification: out of memory");
    radius_field_draw(field, cl->radius_correlation, rng);
  }
  for (karst_int_t e = 0; e < net->n_edges; e++) {
    const double *a = &net->xyz[3 * net->edges[2 * e]], *b = &net->xyz[3 * net->edges[2 * e + 1]];
    karst_tunnel_type_t t = karst_classification_type(sc, a, b);
    type[e] = t;
    double mid[3] = {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
    double u = field ? radius_field_uniform(field, mid) : karst_rng_uniform(rng);
    radius[e] = cl->radius[t].min + u * (cl->radius[t].max - cl->radius[t].min);
    vadose[e] = 0.5 * (a[2] + b[2]) > sc->water_table;
  }
  free(field);
  return KARST_SUCCESS;
}
