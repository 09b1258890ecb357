/* Tunnel types and radii (Paris et al. 2021, §5.3, Fig. 11). */
#include "karst/classification.h"

#include "karst/geology.h"

#include <math.h>
#include <stdlib.h>

/**
 * Tunnel type of segment a–b draining to spring @p spring: our reading of Paris et al. 2021,
 * §5.3 and Fig. 11, which fix the inputs — verticality, position relative to the water table, the
 * epikarst and the ghost-rock chambers — but give no thresholds (ours are the classification.*
 * and routing.water_table_band keys), with the speleogenetic forms of Palmer (2007, "Cave
 * Geology", ch. 6–7) and Ford & Williams (2007, §7) for each zone. Evaluated at the segment
 * midpoint m against the spring's own water table W, first rule that applies:
 *
 *   1. resistance π(m) < chamber_resistance               → chamber
 *      (breakout chambers in ghost-rock zones where c_π ≈ 0, §5.3)
 *   2. vadose (above the epiphreatic band):
 *        steep (angle to horizontal ≥ vertical_angle) and depth below terrain < epikarst_depth
 *                                                          → epikarst (§5.3: "narrow vertical
 *                                                             conduits that start from the
 * surface") steep                                             → tube (circular shafts, §5.3) gentle
 * → canyon (vadose entrenchment)
 *   3. epiphreatic (|z − W| ≤ band):
 *        steep                                             → tube
 *        gentle, above W                                   → keyhole (a tube entrenched by a
 *                                                             vadose canyon as the table falls)
 *        gentle, at or below W                             → passage (epiphreatic passages at the
 *                                                             water table)
 *   4. phreatic (below the band):
 *        within an inception horizon's radius (cL(m) < 1)  → bed (soluble bed conduits, §5.3)
 *        otherwise                                         → tube (phreatic tubes and lifts)
 *
 * A zero-length segment counts as gentle. O(horizons + size of the permeability tree).
 */
karst_tunnel_type_t karst_classification_type(const karst_geology_t *geo, int spring,
                                              const double a[3], const double b[3]) {
  const karst_classification_t *cl = &karst_geology_scenario(geo)->classification;
  double m[3] = {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
  if (karst_geology_permeability(geo, m) < cl->chamber_resistance) return KARST_TUNNEL_CHAMBER;
  karst_zone_t zone = karst_geology_zone(geo, spring, m);
  double dx = b[0] - a[0], dy = b[1] - a[1], dz = b[2] - a[2];
  double angle = atan2(fabs(dz), sqrt(dx * dx + dy * dy)) * (180.0 / M_PI);
  int steep = (dx != 0 || dy != 0 || dz != 0) && angle >= cl->vertical_angle;
  switch (zone) {
  case KARST_ZONE_VADOSE:
    if (steep) {
      double depth = karst_geology_terrain(geo, m[0], m[1]) - m[2];
      return depth < cl->epikarst_depth ? KARST_TUNNEL_EPIKARST : KARST_TUNNEL_TUBE;
    }
    return KARST_TUNNEL_CANYON;
  case KARST_ZONE_EPIPHREATIC:
    if (steep) return KARST_TUNNEL_TUBE;
    return m[2] > karst_geology_water_table(geo, spring, m[0], m[1]) ? KARST_TUNNEL_KEYHOLE
                                                                     : KARST_TUNNEL_PASSAGE;
  default:
    return karst_geology_horizon_term(geo, m) < 1.0 ? KARST_TUNNEL_BED : KARST_TUNNEL_TUBE;
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
    for (int a = 0; a < 3; a++)
      f->w[m][a] = karst_rng_gaussian(rng) / L;
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
 * "tunnel_type" (karst_tunnel_type_t, karst_classification_type against the water table of the
 * edge's "spring" — an edge without one is judged against the first spring), "zone"
 * (karst_zone_t of its midpoint), "vadose" (1 when the zone is vadose), "radius"
 * (m, uniform in classification.radius[type] — by default 0.5 m for
 * epikarst and [0.5, 4] m otherwise, as in §5.3 — and spatially correlated
 * over classification.radius_correlation metres, as Frantz et al. 2021
 * observe on real networks (semi-variogram ranges 50–200 m): the radius is
 * min + Φ(g(midpoint)) (max − min) for a Gaussian random field g drawn from
 * @p rng; a correlation length of 0 draws each edge independently, in edge
 * order), and node attribute "water_table_distance" (z − W of the node's spring, m, positive
 * above).
 *
 * @return KARST_SUCCESS; KARST_EINVAL when vertical_angle is outside [0, 90]
 *         or a radius range is not 0 ≤ min ≤ max (the message names the type);
 *         KARST_ENOMEM.
 * Time complexity: O(nodes + edges × (size of the permeability tree + 256)).
 */
karst_error_t karst_classification_run(karst_ctx_t *ctx, const karst_geology_t *geo,
                                       karst_rng_t *rng, karst_network_t *net) {
  const karst_classification_t *cl = &karst_geology_scenario(geo)->classification;
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
  double *type, *radius, *vadose, *zone, *wtd;
  if (karst_network_attr_add(net, KARST_ATTR_EDGE, "tunnel_type", 1, 1, &type) ||
      karst_network_attr_add(net, KARST_ATTR_EDGE, "radius", 1, 0, &radius) ||
      karst_network_attr_add(net, KARST_ATTR_EDGE, "zone", 1, 1, &zone) ||
      karst_network_attr_add(net, KARST_ATTR_EDGE, "vadose", 1, 1, &vadose) ||
      karst_network_attr_add(net, KARST_ATTR_NODE, "water_table_distance", 1, 0, &wtd))
    return karst_set_error(ctx, KARST_ENOMEM, "classification: out of memory");
  const karst_attr_t *nsp = karst_network_attr_find(net, KARST_ATTR_NODE, "spring");
  const karst_attr_t *esp = karst_network_attr_find(net, KARST_ATTR_EDGE, "spring");
  const int n_springs = karst_geology_n_springs(geo);
#define SPRING_OF(attr, i)                                                                         \
  ((attr) && (attr)->data[i] >= 0 && (attr)->data[i] < n_springs ? (int)(attr)->data[i] : 0)
  for (karst_int_t v = 0; v < net->n_nodes; v++) {
    const double *p = &net->xyz[3 * v];
    wtd[v] = p[2] - karst_geology_water_table(geo, SPRING_OF(nsp, v), p[0], p[1]);
  }
  radius_field_t *field = NULL;
  if (cl->radius_correlation > 0) {
    if (!(field = malloc(sizeof *field)))
      return karst_set_error(ctx, KARST_ENOMEM, "classification: out of memory");
    radius_field_draw(field, cl->radius_correlation, rng);
  }
  for (karst_int_t e = 0; e < net->n_edges; e++) {
    const double *a = &net->xyz[3 * net->edges[2 * e]], *b = &net->xyz[3 * net->edges[2 * e + 1]];
    int spring = SPRING_OF(esp, e);
    karst_tunnel_type_t t = karst_classification_type(geo, spring, a, b);
    type[e] = t;
    double mid[3] = {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
    double u = field ? radius_field_uniform(field, mid) : karst_rng_uniform(rng);
    radius[e] = cl->radius[t].min + u * (cl->radius[t].max - cl->radius[t].min);
    zone[e] = karst_geology_zone(geo, spring, mid);
    vadose[e] = zone[e] == KARST_ZONE_VADOSE;
  }
#undef SPRING_OF
  free(field);
  return KARST_SUCCESS;
}
