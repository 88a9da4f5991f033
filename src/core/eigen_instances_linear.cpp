// The one compiled copy of the Eigen linear decompositions declared in
// src/core/detail/eigen_instances.hpp (explicit instantiation definitions,
// C++ [temp.explicit]/2); why, in that header. Kept out of the unity batches
// (CMakeLists.txt) so the two lists compile side by side.
#include "core/detail/eigen_instances.hpp"

SYSID_EIGEN_LINEAR_INSTANCES()
