/* GDAL/OGR's C API as karst uses it (src/export/gpkg.c), loaded on first use.
 *
 * libgdal brings about 110 shared libraries with it; linked into libkarst, loading and
 * relocating them cost every karst process about 30 ms at start-up (measured on the 2-core
 * project machine: an empty program linked with -lgdal starts in 32 ms, without it in 1 ms),
 * though only `karst export --gpkg` needs GDAL. So libkarst is not linked with it: the first
 * GeoPackage export opens the library with dlopen (its soname, KARST_GDAL_SONAME, fixed when
 * karst is configured) and looks up the functions below, typed from GDAL's own headers. */
#ifndef KARST_GDAL_API_INTERNAL_H
#define KARST_GDAL_API_INTERNAL_H

#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal.h>
#include <ogr_api.h>
#include <ogr_srs_api.h>

#include "karst/common.h"

#define KARST_I_GDAL_FUNCTIONS(X)                                                                  \
  X(CPLGetErrorHandlerUserData)                                                                    \
  X(CPLPopErrorHandler)                                                                            \
  X(CPLPushErrorHandlerEx)                                                                         \
  X(CPLSetThreadLocalConfigOption)                                                                 \
  X(GDALAllRegister)                                                                               \
  X(GDALClose)                                                                                     \
  X(GDALCreate)                                                                                    \
  X(GDALDatasetCommitTransaction)                                                                  \
  X(GDALDatasetCreateLayer)                                                                        \
  X(GDALDatasetExecuteSQL)                                                                         \
  X(GDALDatasetGetLayerByName)                                                                     \
  X(GDALDatasetStartTransaction)                                                                   \
  X(GDALGetDriverByName)                                                                           \
  X(GDALSetMetadataItem)                                                                           \
  X(OGR_FD_GetFieldCount)                                                                          \
  X(OGR_FD_GetFieldDefn)                                                                           \
  X(OGR_FD_GetFieldIndex)                                                                          \
  X(OGR_F_Create)                                                                                  \
  X(OGR_F_Destroy)                                                                                 \
  X(OGR_F_SetFieldDateTime)                                                                        \
  X(OGR_F_SetFieldDouble)                                                                          \
  X(OGR_F_SetFieldInteger)                                                                         \
  X(OGR_F_SetFieldInteger64)                                                                       \
  X(OGR_F_SetFieldNull)                                                                            \
  X(OGR_F_SetFieldString)                                                                          \
  X(OGR_F_SetGeometryDirectly)                                                                     \
  X(OGR_Fld_Create)                                                                                \
  X(OGR_Fld_Destroy)                                                                               \
  X(OGR_Fld_GetNameRef)                                                                            \
  X(OGR_Fld_SetSubType)                                                                            \
  X(OGR_G_AddPoint)                                                                                \
  X(OGR_G_CreateGeometry)                                                                          \
  X(OGR_G_SetPoint)                                                                                \
  X(OGR_L_CreateFeature)                                                                           \
  X(OGR_L_CreateField)                                                                             \
  X(OGR_L_GetLayerDefn)                                                                            \
  X(OSRDestroySpatialReference)                                                                    \
  X(OSRNewSpatialReference)                                                                        \
  X(OSRSetAxisMappingStrategy)                                                                     \
  X(OSRSetFromUserInput)

/** The loaded functions: karst_i_gdal.GDALCreate(...) and so on. */
typedef struct {
#define KARST_I_GDAL_POINTER(name) __typeof__(name) *name;
  KARST_I_GDAL_FUNCTIONS(KARST_I_GDAL_POINTER)
#undef KARST_I_GDAL_POINTER
} karst_i_gdal_t;

extern karst_i_gdal_t karst_i_gdal;

/**
 * Load GDAL once per process (thread-safe); later calls return the first call's result.
 * @return KARST_SUCCESS, or KARST_ENOTIMPL with a message naming the library and dlopen's or
 *         dlsym's reason when GDAL cannot be loaded.
 */
karst_error_t karst_i_gdal_load(karst_ctx_t *ctx);

#endif
