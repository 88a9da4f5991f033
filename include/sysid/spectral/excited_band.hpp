#pragma once
/// @file
/// Purpose: the band in which a record's inputs carry power, for the tools that
/// must judge a model only where the data say something (n4sid's band-limited
/// checks, a model family's uncertainty bound).
///
/// Method: Welch PSD of the inputs (Hann, nfft = N/8 clamped to 64..4096), summed
/// over the inputs; the band runs from the lowest to the highest frequency whose
/// summed PSD lies within `dynamic_range_db` of its peak (30 dB by default: a chirp
/// or multisine's band edges, not its leakage).
///
/// Preconditions (std::invalid_argument, from welch_psd): fs > 0, at least 8
/// samples, finite values, at least one input column.
#include <Eigen/Dense>
#include <utility>

namespace sysid {

/// {low, high} in Hz of the band the columns of `u` (N x m) excite.
std::pair<double, double> excited_band(const Eigen::Ref<const Eigen::MatrixXd>& u, double fs_hz,
                                       double dynamic_range_db = 30.0);

}  // namespace sysid
