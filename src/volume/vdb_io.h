// Internal to src/volume: reading scalar grids from VDB files with errors that
// name the file and grid. Includes OpenVDB; never include it outside volume/.
#pragma once

#include <string>

#include <openvdb/openvdb.h>

namespace vdbmarch {

// Reads grid `name` (empty: "density", else the first scalar grid) as a float
// grid; double grids are converted. Throws InputError listing the grids that
// exist when the name is wrong, or naming the type when it is not scalar.
openvdb::FloatGrid::Ptr readFloatGrid(const std::string& path, const std::string& name,
                                      std::string* chosenName = nullptr);

}  // namespace vdbmarch
