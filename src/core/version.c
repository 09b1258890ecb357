/* The versions of karst and of the libraries it was built with (include/karst/version.h). */
#include "karst/version.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <CGAL/version.h>
#include <GeographicLib/Config.h>
#include <flann/config.h>
#include <gdal_version.h>
#include <proj.h>
#include <vtkVersionMacros.h>
#include <yaml.h>

#if KARST_HAVE_MPI
#include <mpi.h>
#endif

#include "karst/io.h"

#ifndef KARST_VERSION_STRING
#define KARST_VERSION_STRING "0.0.0"
#endif

#define KARST_STR2(x) #x
#define KARST_STR(x) KARST_STR2(x)

const char *karst_version(void) {
  return KARST_VERSION_STRING;
}

static void put(karst_component_t *c, int *n, const char *name, const char *version) {
  snprintf(c[*n].name, sizeof c[*n].name, "%s", name);
  snprintf(c[*n].version, sizeof c[*n].version, "%s", version);
  (*n)++;
}

/**
 * The components in a fixed order: karst, the compiler, then VTK, FLANN,
 * GeographicLib, CGAL, libyaml, GDAL, PROJ and MPI. Where the library reports
 * its version at run time (libyaml) that one
 * is given, else the version of the headers karst was compiled against (VTK,
 * FLANN, GeographicLib, CGAL, Open MPI).
 * @param out  receives the components.
 * @return their number. Time complexity: O(1).
 */
int karst_versions(karst_component_t out[KARST_COMPONENTS_MAX]) {
  int n = 0;
  char buf[96];
  put(out, &n, "karst", karst_version());
#if defined(__clang__)
  put(out, &n, "compiler", "clang " __clang_version__);
#elif defined(__GNUC__)
  put(out, &n, "compiler", "GCC " __VERSION__);
#else
  put(out, &n, "compiler", "unknown");
#endif
  put(out, &n, "VTK", VTK_VERSION);
  put(out, &n, "FLANN", FLANN_VERSION_);
  put(out, &n, "GeographicLib", GEOGRAPHICLIB_VERSION_STRING);
  put(out, &n, "CGAL", KARST_STR(CGAL_VERSION));
  put(out, &n, "libyaml", yaml_get_version_string());
  /* GDAL is loaded only by the GeoPackage export (src/export/gdal_api_internal.h): the version
   * karst was built against, which the soname it loads pins. */
  put(out, &n, "GDAL", GDAL_RELEASE_NAME);
  /* PROJ too is loaded on first use (src/crs/proj_api_internal.h): the version karst was built
   * against, which the soname it loads pins. */
  snprintf(buf, sizeof buf, "%d.%d.%d", PROJ_VERSION_MAJOR, PROJ_VERSION_MINOR, PROJ_VERSION_PATCH);
  put(out, &n, "PROJ", buf);
#if KARST_HAVE_MPI && defined(OMPI_MAJOR_VERSION)
  snprintf(buf, sizeof buf, "Open MPI %d.%d.%d (MPI %d.%d)", OMPI_MAJOR_VERSION, OMPI_MINOR_VERSION,
           OMPI_RELEASE_VERSION, MPI_VERSION, MPI_SUBVERSION);
  put(out, &n, "MPI", buf);
#elif KARST_HAVE_MPI
  snprintf(buf, sizeof buf, "MPI %d.%d", MPI_VERSION, MPI_SUBVERSION);
  put(out, &n, "MPI", buf);
#else
  put(out, &n, "MPI", "not built with MPI");
#endif
  return n;
}

/**
 * karst_versions() as "name version" lines.
 * @return malloc'ed text, NULL when out of memory. Time complexity: O(1).
 */
char *karst_versions_text(void) {
  karst_component_t c[KARST_COMPONENTS_MAX];
  int n = karst_versions(c);
  size_t cap = sizeof c + 2 * KARST_COMPONENTS_MAX + 1, len = 0;
  char *s = malloc(cap);
  if (!s) return NULL;
  s[0] = '\0';
  for (int i = 0; i < n; i++)
    len += (size_t)snprintf(s + len, cap - len, "%s %s\n", c[i].name, c[i].version);
  return s;
}

/**
 * karst_versions() as a one-line JSON object, names as keys, in list order.
 * @return malloc'ed text, NULL when out of memory. Time complexity: O(1).
 */
char *karst_versions_json(void) {
  karst_component_t c[KARST_COMPONENTS_MAX];
  int n = karst_versions(c);
  char *text = NULL;
  size_t len = 0;
  FILE *fp = open_memstream(&text, &len);
  if (!fp) return NULL;
  fputc('{', fp);
  for (int i = 0; i < n; i++) {
    if (i) fputs(", ", fp);
    karst_json_string(fp, c[i].name);
    fputs(": ", fp);
    karst_json_string(fp, c[i].version);
  }
  fputc('}', fp);
  int bad = ferror(fp);
  if (fclose(fp) != 0 || bad) {
    free(text);
    return NULL;
  }
  return text;
}
