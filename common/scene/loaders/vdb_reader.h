#pragma once
// Density grids from OpenVDB files (.vdb, through Debian's libopenvdb): one float grid,
// resampled onto a dense grid over the bounding box of its active voxels with one voxel of
// zeros around it, values at the voxels' centres (OpenVDB's index points), placed in the world
// by the grid's own transform. Kept in its own translation unit: OpenVDB's headers are heavy.
#include <filesystem>
#include <string>

#include "common/scene/scene_description.h"

namespace farm {

// Reads grid `gridName` ("" for the file's first float grid) of the .vdb file at `path` into
// *medium's grid fields (type, resolution, densities, worldToGrid, corner-sampled). On failure
// returns false and says why in *problem (not an OpenVDB file, no such grid, not a float grid,
// a transform that is not affine, more than 2^27 values once dense, densities that are not
// finite and non-negative).
bool readVdbDensity(const std::filesystem::path& path, const std::string& gridName,
                    MediumDescription* medium, std::string* problem);

}  // namespace farm
