/**
 * @file version.h
 * @brief The versions of karst and of the libraries it was built with: one list
 *        behind `karst --version`, the metadata of every output (run.json,
 *        ensemble.json, .vtp field data, GeoPackage metadata) and the report.
 */
#ifndef KARST_VERSION_H
#define KARST_VERSION_H

#include "karst/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** One component: "karst", "compiler" or a library, and its version. */
typedef struct karst_component {
  char name[32];
  char version[96];
} karst_component_t;

/** Most components karst_versions() lists. */
#define KARST_COMPONENTS_MAX 16

/**
 * Fill @p out with karst, the compiler and each library, in a fixed order; returns the count
 * (at most KARST_COMPONENTS_MAX).
 */
int karst_versions(karst_component_t out[KARST_COMPONENTS_MAX]);

/** The same list as "name version" lines (what `karst --version` prints). Caller frees; NULL
 * when out of memory. */
char *karst_versions_text(void);

/** The same list as a one-line JSON object {"karst": "0.1.0", "VTK": "9.1.0", ...}. Caller
 * frees; NULL when out of memory. */
char *karst_versions_json(void);

#ifdef __cplusplus
}
#endif
#endif /* KARST_VERSION_H */
