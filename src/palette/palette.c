/* The one colour scheme of karst (include/karst/palette.h). */
#include "karst/palette.h"

#include <stddef.h>
#include <string.h>

/* Okabe & Ito (2008), "Color universal design (CUD): how to make figures and presentations
 * that are friendly to colorblind people", the eight colours. */
#define OI_BLACK "#000000"
#define OI_ORANGE "#E69F00"
#define OI_SKY_BLUE "#56B4E9"
#define OI_BLUISH_GREEN "#009E73"
#define OI_YELLOW "#F0E442"
#define OI_BLUE "#0072B2"
#define OI_VERMILLION "#D55E00"
#define OI_REDDISH_PURPLE "#CC79A7"
/** "None" and background categories (no tunnel type, terrain, interior nodes, fill samples). */
#define NEUTRAL_GREY "#999999"
/** Surfaces without categories: a pale limestone. */
#define LIMESTONE "#D9D2C5"
/** Survey and observed conduits: the red of the report's survey lines. */
#define SURVEY_RED "#C00000"

/* Tunnel types of Paris et al. 2021, §5.3 (network.h order); -1 labels mesh triangles of the
 * terrain or the box (karst mesh). */
static const karst_palette_category_t tunnel_type[] = {
    {-1, "no type", NEUTRAL_GREY},  {0, "tube", OI_BLUE},          {1, "keyhole", OI_ORANGE},
    {2, "canyon", OI_BLUISH_GREEN}, {3, "bed", OI_REDDISH_PURPLE}, {4, "passage", OI_SKY_BLUE},
    {5, "epikarst", OI_VERMILLION}, {6, "chamber", OI_BLACK}};

/* Node kinds (network.h order): key points strong, interior nodes grey. */
static const karst_palette_category_t node_kind[] = {
    {0, "interior", NEUTRAL_GREY},  {1, "sink", OI_BLUE},
    {2, "spring", OI_BLUISH_GREEN}, {3, "waypoint", OI_REDDISH_PURPLE},
    {4, "junction", OI_ORANGE},     {5, "amplification", OI_SKY_BLUE}};

/* Sample sources (graph.h order). */
static const karst_palette_category_t sample_source[] = {{0, "key_point", OI_BLACK},
                                                         {1, "horizon", OI_ORANGE},
                                                         {2, "water_table", OI_BLUE},
                                                         {3, "permeability", OI_BLUISH_GREEN},
                                                         {4, "fill", NEUTRAL_GREY},
                                                         {5, "amplification", OI_SKY_BLUE},
                                                         {6, "prescribed_path", OI_REDDISH_PURPLE},
                                                         {7, "survey", OI_VERMILLION},
                                                         {8, "points", OI_YELLOW}};

/* Hydrological zones, from dry to flooded: the blues deepen with saturation. */
static const karst_palette_category_t zone[] = {
    {0, "vadose", OI_ORANGE}, {1, "epiphreatic", OI_SKY_BLUE}, {2, "phreatic", OI_BLUE}};

/* The classification's flag: edge midpoint above (1) or below (0) the water table; the
 * colours of the phreatic and vadose zones. */
static const karst_palette_category_t vadose[] = {{0, "below the water table", OI_BLUE},
                                                  {1, "above the water table", OI_ORANGE}};

/* Conduits laid along a surveyed (observed) path, against generated ones. */
static const karst_palette_category_t observed[] = {{0, "generated", NEUTRAL_GREY},
                                                    {1, "observed", SURVEY_RED}};

/* What a polygon of geology.vtp is (include/karst/geology.h order): water tables blue, faults
 * vermillion, fractures green, the terrain neutral. */
static const karst_palette_category_t geology_feature[] = {
    {0, "terrain", NEUTRAL_GREY}, {1, "horizon", OI_ORANGE},
    {2, "water_table", OI_BLUE},  {3, "stratum_boundary", OI_REDDISH_PURPLE},
    {4, "fault", OI_VERMILLION},  {5, "fracture", OI_BLUISH_GREEN},
    {6, "exclusion", OI_BLACK}};

/* The spring a node or edge drains to: one category per spring of the scenario (named by the
 * file's spring_names, coloured by karst_palette_cycle), and -1 for none. */
static const karst_palette_category_t spring[] = {{-1, "none", NEUTRAL_GREY}};

/* Surface details of a conduit mesh (Zanni et al. 2012). */
static const karst_palette_category_t feature[] = {{0, "wall", NEUTRAL_GREY},
                                                   {1, "speleothem", OI_ORANGE}};

/* Block shapes of Paris et al. 2020, §4 and Fig. 2 (the categories of geomorphology). */
static const karst_palette_category_t block_type[] = {{0, "equidimensional", OI_ORANGE},
                                                      {1, "prismatic", OI_SKY_BLUE},
                                                      {2, "polyhedral", OI_BLUISH_GREEN},
                                                      {3, "rhombohedral", OI_YELLOW},
                                                      {4, "tabular", OI_BLUE},
                                                      {5, "columnar", OI_VERMILLION}};

#define N_OF(a) ((int)(sizeof(a) / sizeof(a)[0]))

static const karst_palette_t entries[] = {
    {"tunnel_type", "network.vtp cell data; mesh .vtp cell data (-1: terrain or box)",
     KARST_PALETTE_CATEGORICAL, N_OF(tunnel_type), tunnel_type, NULL},
    {"kind", "network.vtp point data (node kind)", KARST_PALETTE_CATEGORICAL, N_OF(node_kind),
     node_kind, NULL},
    {"source", "samples.vtp point data (sample source)", KARST_PALETTE_CATEGORICAL,
     N_OF(sample_source), sample_source, NULL},
    {"zone", "network.vtp cell data (hydrological zone)", KARST_PALETTE_CATEGORICAL, N_OF(zone),
     zone, NULL},
    {"vadose", "network.vtp cell data", KARST_PALETTE_CATEGORICAL, N_OF(vadose), vadose, NULL},
    {"observed", "network.vtp cell data", KARST_PALETTE_CATEGORICAL, N_OF(observed), observed,
     NULL},
    {"feature", "mesh .vtp cell data (surface detail)", KARST_PALETTE_CATEGORICAL, N_OF(feature),
     feature, "mesh"},
    {"feature", "geology.vtp cell data (what the polygon is)", KARST_PALETTE_CATEGORICAL,
     N_OF(geology_feature), geology_feature, "geology"},
    {"spring", "network.vtp point and cell data (the spring drained to)", KARST_PALETTE_CATEGORICAL,
     N_OF(spring), spring, NULL},
    {"block_type", "block mesh cell data (block shape)", KARST_PALETTE_CATEGORICAL,
     N_OF(block_type), block_type, NULL},
    {"generation", "network.vtp cell data (integer, ordered)", KARST_PALETTE_SEQUENTIAL, 0, NULL,
     NULL},
};

/* viridis (matplotlib 2.0) at t = 0, 1/8, ..., 1: #440154 #472D7B #3B528B #2C728E #21908C
 * #27AD81 #5DC863 #AADC32 #FDE725. */
static const double viridis_points[][4] = {
    {0.000, 68 / 255.0, 1 / 255.0, 84 / 255.0},    {0.125, 71 / 255.0, 45 / 255.0, 123 / 255.0},
    {0.250, 59 / 255.0, 82 / 255.0, 139 / 255.0},  {0.375, 44 / 255.0, 114 / 255.0, 142 / 255.0},
    {0.500, 33 / 255.0, 144 / 255.0, 140 / 255.0}, {0.625, 39 / 255.0, 173 / 255.0, 129 / 255.0},
    {0.750, 93 / 255.0, 200 / 255.0, 99 / 255.0},  {0.875, 170 / 255.0, 220 / 255.0, 50 / 255.0},
    {1.000, 253 / 255.0, 231 / 255.0, 37 / 255.0}};
/* Moreland (2009), "Diverging color maps for scientific visualization", Table 1 (every fourth
 * row): blue (59, 76, 192) through grey (221, 221, 221) to red (180, 4, 38). */
static const double cool_warm_points[][4] = {
    {0.000, 59 / 255.0, 76 / 255.0, 192 / 255.0},   {0.125, 98 / 255.0, 130 / 255.0, 234 / 255.0},
    {0.250, 141 / 255.0, 176 / 255.0, 254 / 255.0}, {0.375, 184 / 255.0, 208 / 255.0, 249 / 255.0},
    {0.500, 221 / 255.0, 221 / 255.0, 221 / 255.0}, {0.625, 245 / 255.0, 196 / 255.0, 173 / 255.0},
    {0.750, 244 / 255.0, 154 / 255.0, 123 / 255.0}, {0.875, 222 / 255.0, 96 / 255.0, 77 / 255.0},
    {1.000, 180 / 255.0, 4 / 255.0, 38 / 255.0}};
static const karst_palette_ramp_t viridis = {"viridis", N_OF(viridis_points), viridis_points};
static const karst_palette_ramp_t cool_warm = {"cool to warm", N_OF(cool_warm_points),
                                               cool_warm_points};

/* Indexed by karst_palette_role_t. The ensemble's blue is Paul Tol's (2021) "bright" blue,
 * apart from every categorical colour so members never read as a category; the structures'
 * dark grey stays visible over the ensemble's blue. */
static const char *const roles[KARST_PALETTE_ROLE_COUNT] = {"#4477AA",    SURVEY_RED, NEUTRAL_GREY,
                                                            NEUTRAL_GREY, "#333333",  LIMESTONE};

/**
 * Every palette entry. @p n receives their count (may be NULL).
 * Time complexity: O(1).
 */
const karst_palette_t *karst_palette_list(int *n) {
  if (n) *n = N_OF(entries);
  return entries;
}

/**
 * The palette entry of the array named @p array (exact, case-sensitive), or NULL.
 * Time complexity: O(number of entries).
 */
const karst_palette_t *karst_palette_find(const char *array) {
  return karst_palette_find_role(array, NULL);
}

/**
 * The entry of @p array for files of kind @p role: the one of that role, else the one without a
 * role, else (for @p role NULL) the first one of that name; NULL when there is none.
 * Time complexity: O(number of entries).
 */
const karst_palette_t *karst_palette_find_role(const char *array, const char *role) {
  const karst_palette_t *any = NULL, *plain = NULL;
  if (!array) return NULL;
  for (int i = 0; i < N_OF(entries); i++) {
    if (strcmp(entries[i].array, array) != 0) continue;
    if (!any) any = &entries[i];
    if (!entries[i].role && !plain) plain = &entries[i];
    if (role && entries[i].role && strcmp(entries[i].role, role) == 0) return &entries[i];
  }
  return plain ? plain : role ? NULL : any;
}

/* The colours of categories an entry does not list, in turn. */
static const char *const cycle[] = {OI_BLUE,           OI_ORANGE,   OI_BLUISH_GREEN, OI_VERMILLION,
                                    OI_REDDISH_PURPLE, OI_SKY_BLUE, OI_YELLOW};

/**
 * Colour of an unlisted category code: the cycle of Okabe & Ito colours but black (the colour
 * of text), the neutral grey for a negative code.
 * Time complexity: O(1).
 */
const char *karst_palette_cycle(int code) {
  return code < 0 ? NEUTRAL_GREY : cycle[code % N_OF(cycle)];
}

/**
 * The category whose stored value is @p code, or NULL.
 * Time complexity: O(categories).
 */
const karst_palette_category_t *karst_palette_category(const karst_palette_t *p, int code) {
  if (!p) return NULL;
  for (int i = 0; i < p->n; i++)
    if (p->categories[i].code == code) return &p->categories[i];
  return NULL;
}

/**
 * The ramp of a kind: cool to warm for diverging, viridis otherwise.
 * Time complexity: O(1).
 */
const karst_palette_ramp_t *karst_palette_ramp(karst_palette_kind_t kind) {
  return kind == KARST_PALETTE_DIVERGING ? &cool_warm : &viridis;
}

/**
 * The colour of a comparison role (see karst_palette_role_t).
 * Time complexity: O(1).
 */
const char *karst_palette_role(karst_palette_role_t role) {
  if ((int)role < 0 || role >= KARST_PALETTE_ROLE_COUNT) return roles[KARST_PALETTE_ROLE_NONE];
  return roles[role];
}

/**
 * Colour of ramp @p r at @p t: linear interpolation in sRGB between the two control points
 * around t (t clamped to [0, 1]; NaN gives the colour at 0).
 * Time complexity: O(control points).
 */
void karst_palette_ramp_eval(const karst_palette_ramp_t *r, double t, double rgb[3]) {
  if (!(t > 0)) t = 0;
  if (t > 1) t = 1;
  int k = 0;
  while (k + 2 < r->n && t > r->points[k + 1][0])
    k++;
  const double *a = r->points[k], *b = r->points[k + 1];
  double u = b[0] > a[0] ? (t - a[0]) / (b[0] - a[0]) : 0;
  for (int c = 0; c < 3; c++)
    rgb[c] = a[c + 1] + u * (b[c + 1] - a[c + 1]);
}

static int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

/**
 * Parse "#RRGGBB" (exactly seven characters) into r, g, b in [0, 1].
 * @return 0, or -1 (rgb untouched) for any other text.
 * Time complexity: O(1).
 */
int karst_palette_hex_rgb(const char *hex, double rgb[3]) {
  if (!hex || hex[0] != '#' || strlen(hex) != 7) return -1;
  int v[6];
  for (int i = 0; i < 6; i++)
    if ((v[i] = hex_digit(hex[1 + i])) < 0) return -1;
  for (int c = 0; c < 3; c++)
    rgb[c] = (16 * v[2 * c] + v[2 * c + 1]) / 255.0;
  return 0;
}
