/* Versions of karst and of the libraries it was built with, for the report. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <CGAL/version.h>
#include <GeographicLib/Config.h>
#include <flann/config.h>
#include <igraph_version.h>
#include <vtkVersionMacros.h>
#include <yaml.h>

#include "karst/report.h"

#if KARST_HAVE_MPI
#include <mpi.h>
#endif

#define KARST_STR2(x) #x
#define KARST_STR(x) KARST_STR2(x)

/**
 * "name version" lines: karst, the compiler, and the versions of VTK,
 * igraph, FLANN, GeographicLib and CGAL headers the library was compiled
 * against, libyaml at run time, and Open MPI when built with it.
 * @return malloc'ed text (NULL when out of memory). O(1).
 */
char *karst_report_versions(void) {
  char mpi[64] = "not built with MPI";
#if KARST_HAVE_MPI && defined(OMPI_MAJOR_VERSION)
  snprintf(mpi, sizeof mpi, "Open MPI %d.%d.%d (MPI %d.%d)", OMPI_MAJOR_VERSION, OMPI_MINOR_VERSION,
           OMPI_RELEASE_VERSION, MPI_VERSION, MPI_SUBVERSION);
#elif KARST_HAVE_MPI
  snprintf(mpi, sizeof mpi, "MPI %d.%d", MPI_VERSION, MPI_SUBVERSION);
#endif
  char *s = malloc(1024);
  if (!s) return NULL;
  snprintf(s, 1024,
           "karst %s\n"
           "compiler %s\n"
           "VTK %s\n"
           "igraph %s\n"
           "FLANN %s\n"
           "GeographicLib %s\n"
           "CGAL %s\n"
           "libyaml %s\n"
           "MPI %s\n",
           karst_version(), __VERSION__, VTK_VERSION, IGRAPH_VERSION, FLANN_VERSION_,
           GEOGRAPHICLIB_VERSION_STRING, KARST_STR(CGAL_VERSION), yaml_get_version_string(), mpi);
  return s;
}
