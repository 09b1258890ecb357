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
     CAT, "node_kind_names"},
    {"water_table_distance", "network.vtp point data", "m", "height above the water table (m)",
     "z minus the water-table elevation: positive above the water table (vadose), negative "
     "below it (phreatic)",
     DIV, NULL},
    {"label", "network.vtp point data (string)", KARST_ARRAYS_UNIT_TEXT, "label",
     "name of the key point or survey station at the node (empty for the others)", CAT, NULL},
    /* network.vtp, cell data (one 2-point line per edge) */
    {"tunnel_type", "network.vtp cell data; mesh .vtp cell data", KARST_ARRAYS_UNIT_CATEGORY,
     "tunnel type",
     "cross-section type of the conduit (Paris et al. 2021, section 5.3); -1 on mesh triangles of "
     "the terrain or the box",
     CAT, "tunnel_type_names"},
    {"radius", "network.vtp cell data", "m", "conduit radius (m)",
     "half-width of the conduit's cross-section, drawn in the tunnel type's range", SEQ, NULL},
    {"vadose", "network.vtp cell data", KARST_ARRAYS_UNIT_CATEGORY, "edge above the water table",
     "1 when the edge's midpoint is above the water table, 0 when it is at or below it", CAT,
     "vadose_names"},
    {"cost", "network.vtp cell data", "m", "path cost (cost-weighted m)",
     "line integral along the edge of the dimensionless cost per metre c(p, d) (Paris et al. "
     "2021, section 4.2): the weight the least-cost paths minimised; >= 0",
     SEQ, NULL},
    {"branch_id", "network.vtp cell data", KARST_ARRAYS_UNIT_INDEX, "branch (path index)",
     "0-based index of the least-cost path that laid the edge (skeleton paths first, then "
     "amplification paths)",
     SEQ, NULL},
    {"amplification_step", "network.vtp cell data", KARST_ARRAYS_UNIT_INDEX,
     "amplification step (index)",
     "0 for edges of the gamma-skeleton, s >= 1 for edges added by amplification step s", SEQ,
     NULL},
    {"zone", "network.vtp cell data", KARST_ARRAYS_UNIT_CATEGORY, "hydrological zone",
     "zone of the conduit relative to the water table: vadose (above), epiphreatic (the band of "
     "its fluctuation), phreatic (below)",
     CAT, "zone_names"},
    {"observed", "network.vtp cell data", KARST_ARRAYS_UNIT_CATEGORY, "observed conduit",
     "1 for conduits laid along an observed (surveyed) path, 0 for generated ones", CAT,
     "observed_names"},
    {"generation", "network.vtp cell data", KARST_ARRAYS_UNIT_INDEX,
     "speleogenetic generation (index)",
     "0-based generation of the conduit: 0 formed first, higher values later", SEQ, NULL},
    /* survey networks read by karst (kept when a survey is written back) */
    {"lrud", "survey networks, point data (4 components)", "m", "passage dimensions (m)",
     "distances from the station to the left, right, up and down walls (components 0-3); NaN "
     "where not measured",
     SEQ, NULL},
    {"properties", "Karstnet networks, point data", KARST_ARRAYS_UNIT_AS_READ,
     "Karstnet node properties (as read)",
     "the extra columns of a Karstnet node file, as they were read (their unit is the file's)", SEQ,
     NULL},
    /* samples.vtp */
    {"source", "samples.vtp point data", KARST_ARRAYS_UNIT_CATEGORY, "sample source",
     "which sampler placed the point: a key point, a horizon, the water table, a permeable "
     "zone, the fill, amplification or a prescribed path",
     CAT, "source_names"},
    /* meshes */
    {"feature", "mesh .vtp cell data", KARST_ARRAYS_UNIT_CATEGORY, "surface feature",
     "what the triangle belongs to: the conduit wall or a speleothem", CAT, "feature_names"},
    {"block_type", "block mesh cell data", KARST_ARRAYS_UNIT_CATEGORY, "block type",
     "shape class of the rock block (Paris et al. 2020, section 4)", CAT, "block_type_names"},
    {"sdf", "mesh --sdf .vti point data", "m", "signed distance bound (m, negative inside)",
     "1-Lipschitz signed-distance bound to the meshed surface: negative inside the meshed solid "
     "(the conduits' void, or the rock with --carve), positive outside; the surface is the "
     "0 isosurface",
     DIV, NULL},
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
  if (!name) return NULL;
  for (size_t i = 0; i < sizeof entries / sizeof entries[0]; i++)
    if (strcmp(entries[i].name, name) == 0) return &entries[i];
  return NULL;
}
