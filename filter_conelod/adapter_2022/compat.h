// ConeLOD MeshLab plugin for MeshLab 2022.02 and later — what differs between the versions of
// the FilterPlugin API. CONELOD_MESHLAB_VERSION is the version as a number (2022.02 -> 202202),
// set by CMake from the sources' ML_VERSION.
//
// filter_plugin.h, the document and the mesh are the same in 2022.02, 2023.12 and 2025.07. From
// 2023.12 on the parameters live one class per header and three were renamed: RichAbsPerc ->
// RichPercentage, RichOpenFile -> RichFileOpen, RichSaveFile -> RichFileSave (their .mlx type
// strings did not change: RichAbsPerc, RichOpenFile, RichSaveFile).
#pragma once

#if !defined(CONELOD_MESHLAB_VERSION)
#error "CONELOD_MESHLAB_VERSION must be defined (e.g. 202202)"
#endif

#include <common/parameters/rich_parameter_list.h>

namespace conelod_plugin {

#if CONELOD_MESHLAB_VERSION >= 202312
using RichAbsPercParameter = RichPercentage;
using RichOpenFileParameter = RichFileOpen;
using RichSaveFileParameter = RichFileSave;
#else
using RichAbsPercParameter = RichAbsPerc;
using RichOpenFileParameter = RichOpenFile;
using RichSaveFileParameter = RichSaveFile;
#endif

}  // namespace conelod_plugin
