/* The dictionary of the arrays karst writes (include/karst/arrays.h). */
#include "karst/arrays.h"

#include <stddef.h>
#include <string.h>

#define CAT KARST_PALETTE_CATEGORICAL
#define SEQ KARST_PALETTE_SEQUENTIAL
#define DIV KARST_PALETTE_DIVERGING

/* Coordinates everywhere: x east, y north, z up, metres (network.h). Keep docs/arrays.md in
 * step: test_arrays compares the two. */
static const karst_array_info_t entries[] = {
    /* network.vtp, point data */
    {"kind", "network.vtp point data", KARST_ARRAYS_UNIT_CATEGORY, "node kind",
     "what the node is: an interior node, a key point (sink, spring, waypoint), a junction of "
     "the gamma-skeleton or a node added by amplification",
     CAT, "node_kind_names", NULL},
    {"water_table_distance", "network.vtp point data", "m", "height above the water table (m)",
     "z minus the elevation of the water table of the node's spring: positive above it, negative "
     "below it",
     DIV, NULL, NULL},
    {"spring", "network.vtp point and cell data", KARST_ARRAYS_UNIT_CATEGORY, "spring drained to",
     "index of the spring the node or edge drains to (names in spring_names), -1 for none", CAT,
     "spring_names", NULL},
    {"label", "network.vtp point data (string)", KARST_ARRAYS_UNIT_TEXT, "label",
     "name of the key point or survey station at the node (empty for the others)", CAT, NULL, NULL},
    /* network.vtp, cell data (one 2-point line per edge) */
    {"tunnel_type", "network.vtp cell data; mesh .vtp cell data", KARST_ARRAYS_UNIT_CATEGORY,
     "tunnel type",
     "cross-section type of the conduit (Paris et al. 2021, section 5.3); -1 on mesh triangles of "
     "the terrain or the box",
     CAT, "tunnel_type_names", NULL},
    {"radius", "network.vtp cell data", "m", "conduit radius (m)",
     "half-width of the conduit's cross-section, drawn in the tunnel type's range", SEQ, NULL,
     NULL},
    {"vadose", "network.vtp cell data", KARST_ARRAYS_UNIT_CATEGORY, "edge above the water table",
     "1 when the edge's zone is vadose (above its spring's water table and its band), 0 "
     "otherwise",
     CAT, "vadose_names", NULL},
    {"cost", "network.vtp cell data", "m", "path cost (cost-weighted m)",
     "line integral along the edge of the dimensionless cost per metre c(p, d) (Paris et al. "
     "2021, section 4.2): the weight the least-cost paths minimised; >= 0",
     SEQ, NULL, NULL},
    {"branch_id", "network.vtp cell data", KARST_ARRAYS_UNIT_INDEX, "branch (path index)",
     "0-based index of the least-cost path that laid the edge (skeleton paths first, then "
     "amplification paths)",
     SEQ, NULL, NULL},
    {"amplification_step", "network.vtp cell data", KARST_ARRAYS_UNIT_INDEX,
     "amplification step (index)",
     "0 for edges of the gamma-skeleton, s >= 1 for edges added by amplification step s", SEQ, NULL,
     NULL},
    {"zone", "network.vtp cell data", KARST_ARRAYS_UNIT_CATEGORY, "hydrological zone",
     "zone of the conduit against the water table W of its own spring: vadose above W + b, "
     "epiphreatic within b of W, phreatic below W - b (b = routing.water_table_band)",
     CAT, "zone_names", NULL},
    {"observed", "network.vtp cell data", KARST_ARRAYS_UNIT_CATEGORY, "observed conduit",
     "1 for conduits laid along an observed (surveyed) path, 0 for generated ones", CAT,
     "observed_names", NULL},
    {"generation", "network.vtp cell data", KARST_ARRAYS_UNIT_INDEX,
     "speleogenetic phase (index)",
     "1-based phase (generations, oldest first) that dissolved the conduit; 0 for surveyed legs "
     "(docs/conditioning.md)",
     SEQ, NULL, NULL},
    {"reactivated", "network.vtp cell data", KARST_ARRAYS_UNIT_INDEX,
     "reactivating phase (index)",
     "the last younger phase whose routes followed this conduit, 0 if none (docs/conditioning.md)",
     SEQ, NULL, NULL},
    /* survey networks read by karst (kept when a survey is written back) */
    {"lrud", "survey networks, point data (4 components)", "m", "passage dimensions (m)",
     "distances from the station to the left, right, up and down walls (components 0-3); NaN "
     "where not measured",
     SEQ, NULL, NULL},
    {"properties", "Karstnet networks, point data", KARST_ARRAYS_UNIT_AS_READ,
     "Karstnet node properties (as read)",
     "the extra columns of a Karstnet node file, as they were read (their unit is the file's)", SEQ,
     NULL, NULL},
    /* samples.vtp */
    {"source", "samples.vtp point data", KARST_ARRAYS_UNIT_CATEGORY, "sample source",
     "which sampler placed the point: a key point, a horizon, the water table, a permeable "
     "zone, the fill, amplification, a prescribed path, a survey station or the point cloud of "
     "sampling.points",
     CAT, "source_names", NULL},
    /* meshes */
    {"feature", "mesh .vtp cell data", KARST_ARRAYS_UNIT_CATEGORY, "surface feature",
     "what the triangle belongs to: the conduit wall or a speleothem", CAT, "feature_names",
     "mesh"},
    /* geology.vtp */
    {"feature", "geology.vtp cell data", KARST_ARRAYS_UNIT_CATEGORY, "geological feature",
     "what the polygon is: the terrain, a horizon, a water table, a stratum boundary, a fault, a "
     "fracture disc or an exclusion zone",
     CAT, "feature_names", "geology"},
    {"feature_id", "geology.vtp cell data", KARST_ARRAYS_UNIT_INDEX, "feature index (index)",
     "0-based index of the polygon's horizon, spring (water table), stratum, fault, fracture "
     "family or exclusion zone in the scenario",
     SEQ, NULL, "geology"},
    {"block_id", "block mesh cell data", KARST_ARRAYS_UNIT_INDEX, "block (index)",
     "0-based index of the rock block the triangle bounds, -1 for the terrain (docs/blocks.md)",
     SEQ, NULL, NULL},
    {"block_type", "block mesh cell data", KARST_ARRAYS_UNIT_CATEGORY, "block type",
     "shape class of the rock block (Paris et al. 2020, section 4)", CAT, "block_type_names", NULL},
    {"sdf", "mesh --sdf .vti point data", "m", "signed distance bound (m, negative inside)",
     "1-Lipschitz signed-distance bound to the meshed surface: negative inside the meshed solid "
     "(the conduits' void, or the rock with --carve), positive outside; the surface is the "
     "0 isosurface",
     DIV, NULL, NULL},
};

/**
 * Every array karst writes. @p n (may be NULL) receives the count.
 * Time complexity: O(1).
 */
const karst_array_info_t *karst_arrays_list(int *n) {
  if (n) *n = (int)(sizeof entries / sizeof entries[0]);
  return entries;
}

/**
 * The entry of array @p name (exact match), or NULL for NULL or an unknown name.
 * Time complexity: O(number of entries).
 */
const karst_array_info_t *karst_arrays_find(const char *name) {
  return karst_arrays_find_role(name, NULL);
}

/**
 * The entry of @p name for files of kind @p role: the one of that role, else the one without a
 * role, else (for @p role NULL) the first of that name; NULL when there is none.
 * Time complexity: O(number of entries).
 */
const karst_array_info_t *karst_arrays_find_role(const char *name, const char *role) {
  const karst_array_info_t *any = NULL, *plain = NULL;
  if (!name) return NULL;
  for (size_t i = 0; i < sizeof entries / sizeof entries[0]; i++) {
    if (strcmp(entries[i].name, name) != 0) continue;
    if (!any) any = &entries[i];
    if (!entries[i].role && !plain) plain = &entries[i];
    if (role && entries[i].role && strcmp(entries[i].role, role) == 0) return &entries[i];
  }
  return plain ? plain : role ? NULL : any;
}
