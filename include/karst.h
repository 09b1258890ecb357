/**
 * @file karst.h
 * @brief Umbrella header of the karst library: include this one.
 *
 * The pipeline, in the order of the folders under src/:
 * scenario -> sampling -> graph -> paths -> skeleton -> amplification ->
 * classification -> export / metrics -> implicit geometry; ensembles of realisations and their
 * calibration against surveys (ensemble, compare, calibrate, report).
 */
#ifndef KARST_H
#define KARST_H

#include "karst/amplification.h"
#include "karst/arrays.h"
#include "karst/budget.h"
#include "karst/calibrate.h"
#include "karst/classification.h"
#include "karst/common.h"
#include "karst/compare.h"
#include "karst/cost.h"
#include "karst/crs.h"
#include "karst/ensemble.h"
#include "karst/export.h"
#include "karst/generate.h"
#include "karst/geology.h"
#include "karst/graph.h"
#include "karst/image.h"
#include "karst/implicit.h"
#include "karst/io.h"
#include "karst/json.h"
#include "karst/mesh.h"
#include "karst/metrics.h"
#include "karst/network.h"
#include "karst/palette.h"
#include "karst/paths.h"
#include "karst/readers.h"
#include "karst/report.h"
#include "karst/routing.h"
#include "karst/sampling.h"
#include "karst/scenario.h"
#include "karst/skeleton.h"
#include "karst/surface.h"
#include "karst/version.h"
#include "karst/view.h"
#include "karst/vtk.h"

#endif
