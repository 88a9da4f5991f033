#pragma once
/// @file
/// Purpose: find the sensor glitches in a measured output — single samples far
/// from both neighbours — that a least-squares fit would weigh like any other
/// sample, so an identification can warn instead of bending the model to them.
///
/// Method: sample t is an isolated spike when it departs from both neighbours in
/// the same direction, each step more than `threshold` robust standard deviations
/// of the first difference: a = y(t) - y(t-1), b = y(t) - y(t+1), sign(a) =
/// sign(b), min(|a|, |b|) > threshold sigma and > threshold times the RMS of the
/// other first differences within 8 samples (a burst of ringing near Nyquist has
/// large steps all around; a glitch only at t), with sigma = 1.4826 MAD(diff y) (the
/// median absolute deviation scaled to a Gaussian's sigma; the RMS of the
/// differences when the MAD is zero, as for quantised or mostly constant signals).
/// A step is not a spike (it departs from one neighbour only); the smooth response
/// of a physical plant never is one at the sampling rate. Samples within
/// `input_guard` samples of a sudden input change (an input step or impulse of the
/// same criterion) are not flagged: an output with direct feedthrough (an
/// accelerometer under a hammer tap) follows its input there.
///
/// White Gaussian noise crosses the default threshold (12 sigma of the difference,
/// i.e. about 17 sigma of the noise) with negligible probability.
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "sysid/core/io_data.hpp"

namespace sysid {

struct IsolatedSpikeOptions {
  double threshold = 12.0;       ///< in robust standard deviations of the first difference
  Eigen::Index input_guard = 2;  ///< samples either side of a sudden input change that are not flagged
};

/// Purpose: the indices t (1 <= t <= N-2) of the isolated spikes of x (file comment).
std::vector<Eigen::Index> isolated_spikes(const Eigen::VectorXd& x, double threshold = 12.0);

/// Purpose: one warning per output of `data` with isolated spikes (over all
/// experiments, away from sudden input changes), giving their number and the
/// first few sample indices. `who` prefixes the message ("n4sid: ..."; empty: none).
std::vector<std::string> isolated_spike_warnings(const IoData& data, const std::string& who,
                                                 const IsolatedSpikeOptions& options = {});

}  // namespace sysid
