/**
 * @file palette.h
 * @brief One colour scheme for everything karst draws or writes: the categories of every
 *        categorical array (their codes, names and colours), the colour ramps of ordered and
 *        continuous arrays, and the colours of the roles in comparison plots (ensemble,
 *        survey, published range).
 *
 * The HTML report, the ParaView scripts written beside every output, the pictures of docs/
 * and the QGIS styles all take their colours from here, so a tunnel type, a zone or a block
 * type has the same colour wherever a geologist meets it. Categorical colours are those of
 * Okabe & Ito (2008, "Color universal design", distinguishable under the common colour
 * vision deficiencies), with a neutral grey for "none" and background categories; ramps are
 * viridis (van der Walt & Smith 2015, perceptually uniform) and Moreland's (2009) cool-to-warm
 * diverging map for signed quantities.
 *
 * Category codes are the integer values stored in the array (e.g. tunnel_type 0 = tube); the
 * category names equal the strings of the array's "<array>_names" field data.
 */
#ifndef KARST_PALETTE_H
#define KARST_PALETTE_H

#ifdef __cplusplus
extern "C" {
#endif

/** One category of a categorical array: the stored code, its name and its colour. */
typedef struct karst_palette_category {
  int code;         /**< value stored in the array */
  const char *name; /**< as in the "<array>_names" field data (index = code for codes >= 0) */
  const char *hex;  /**< colour "#RRGGBB" */
} karst_palette_category_t;

typedef enum {
  KARST_PALETTE_CATEGORICAL = 0, /**< a fixed list of named categories */
  KARST_PALETTE_SEQUENTIAL = 1,  /**< ordered integers or reals: the viridis ramp */
  KARST_PALETTE_DIVERGING = 2    /**< signed values around 0: the cool-to-warm ramp */
} karst_palette_kind_t;

/** The presentation of one array karst writes. */
typedef struct karst_palette {
  const char *array; /**< array name, e.g. "tunnel_type" */
  const char *where; /**< where karst writes it, e.g. "network.vtp cell data" */
  karst_palette_kind_t kind;
  int n;                                      /**< categories (0 for ramps) */
  const karst_palette_category_t *categories; /**< n categories in code order, or NULL */
} karst_palette_t;

/** A colour ramp: @c n control points (t in [0, 1], increasing), linear in sRGB between them. */
typedef struct karst_palette_ramp {
  const char *name; /**< "viridis" or "cool to warm" */
  int n;
  const double (*points)[4]; /**< n rows t, r, g, b (r, g, b in [0, 1]) */
} karst_palette_ramp_t;

/** Roles in comparison plots. */
typedef enum {
  KARST_PALETTE_ROLE_ENSEMBLE = 0,  /**< generated members: bars, roses, stereonet points */
  KARST_PALETTE_ROLE_SURVEY = 1,    /**< the surveyed cave: lines, outlines, markers */
  KARST_PALETTE_ROLE_PUBLISHED = 2, /**< the range of the 34 published caves */
  KARST_PALETTE_ROLE_NONE = 3,      /**< no category (e.g. an edge without a tunnel type) */
  KARST_PALETTE_ROLE_STRUCTURE = 4, /**< geological structures drawn over data (fractures) */
  KARST_PALETTE_ROLE_SURFACE = 5,   /**< a surface without categories (a conduit wall, rock) */
  KARST_PALETTE_ROLE_COUNT
} karst_palette_role_t;

/** Every array with a palette entry, in a fixed order; @p n receives their count. O(1). */
const karst_palette_t *karst_palette_list(int *n);
/** The entry of array @p array, or NULL when karst gives it none. O(number of entries). */
const karst_palette_t *karst_palette_find(const char *array);
/** The category of @p code in @p p, or NULL (not a category of it, or @p p is a ramp). O(n). */
const karst_palette_category_t *karst_palette_category(const karst_palette_t *p, int code);
/** The ramp a sequential or diverging entry uses (the viridis ramp for categorical ones). */
const karst_palette_ramp_t *karst_palette_ramp(karst_palette_kind_t kind);
/** Colour "#RRGGBB" of a role (never NULL; the role's colour of KARST_PALETTE_ROLE_NONE for
 *  an unknown role). */
const char *karst_palette_role(karst_palette_role_t role);
/** The ramp's colour at @p t (clamped to [0, 1]) as r, g, b in [0, 1]. O(ramp points). */
void karst_palette_ramp_eval(const karst_palette_ramp_t *r, double t, double rgb[3]);
/** Parse "#RRGGBB" into r, g, b in [0, 1]; returns 0, or -1 for anything else. O(1). */
int karst_palette_hex_rgb(const char *hex, double rgb[3]);

#ifdef __cplusplus
}
#endif
#endif /* KARST_PALETTE_H */
