/**
 * @file arrays.h
 * @brief The dictionary of the data arrays karst writes: for each array its unit, its meaning
 *        with the sign convention, how it is coloured, and for categorical arrays the
 *        field-data array that names its categories.
 *
 * The VTK writers put each entry into the file itself (the VTK information key UNITS_LABEL on
 * the array, and a row of the field-data string table "array_units"), the ParaView scripts
 * title their colour bars with it, and docs/arrays.md lists it (a unit test checks that the
 * page and this table agree).
 */
#ifndef KARST_ARRAYS_H
#define KARST_ARRAYS_H

#include "karst/palette.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Unit of a categorical array (its values are codes; see the palette and the names array). */
#define KARST_ARRAYS_UNIT_CATEGORY "category"
/** Unit of identifiers and ordinal steps (0-based integers, no physical unit). */
#define KARST_ARRAYS_UNIT_INDEX "index"
/** Unit of text arrays (station names). */
#define KARST_ARRAYS_UNIT_TEXT "text"
/** Unit of values copied from a foreign file whose unit karst does not know. */
#define KARST_ARRAYS_UNIT_AS_READ "as read"

/** One array karst writes. */
typedef struct karst_array_info {
  const char *name;    /**< array name in the files */
  const char *where;   /**< files and association, e.g. "network.vtp point data" */
  const char *unit;    /**< "m", "1" (dimensionless), or one of the KARST_ARRAYS_UNIT_* */
  const char *title;   /**< colour-bar title, quantity and unit, e.g. "radius (m)" */
  const char *meaning; /**< one sentence: what a value means, its sign convention */
  karst_palette_kind_t colouring; /**< categories, or the sequential or diverging ramp */
  const char *names; /**< field-data array naming the categories (value i: code i), or NULL */
} karst_array_info_t;

/** Every entry, in a fixed order; @p n (may be NULL) receives their count. O(1). */
const karst_array_info_t *karst_arrays_list(int *n);
/** The entry of the array named @p name, or NULL. O(number of entries). */
const karst_array_info_t *karst_arrays_find(const char *name);

#ifdef __cplusplus
}
#endif
#endif /* KARST_ARRAYS_H */
