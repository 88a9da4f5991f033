#pragma once
/// @file
/// Purpose: recorded input/output data: one or several experiments on the same
/// machine with the same channels and sample time, kept apart so that no
/// algorithm treats the end of one record and the start of the next as contiguous.
#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

/// One contiguous record: samples in rows.
struct Experiment {
  Eigen::MatrixXd u;   ///< N x m inputs
  Eigen::MatrixXd y;   ///< N x l outputs
  std::string source;  ///< where it came from (file name), for messages
  Eigen::Index samples() const { return y.rows(); }
};

struct IoData {
  std::vector<Experiment> experiments;
  double Ts = 0.0;  ///< sample time in seconds (> 0)
  std::vector<std::string> input_names;
  std::vector<std::string> output_names;

  IoData() = default;
  /// Single experiment.
  IoData(Eigen::MatrixXd u, Eigen::MatrixXd y, double ts, std::vector<std::string> in_names = {},
         std::vector<std::string> out_names = {}, std::string source = {})
      : Ts(ts), input_names(std::move(in_names)), output_names(std::move(out_names)) {
    experiments.push_back({std::move(u), std::move(y), std::move(source)});
    validate();
  }

  Eigen::Index inputs() const { return experiments.empty() ? 0 : experiments.front().u.cols(); }
  Eigen::Index outputs() const { return experiments.empty() ? 0 : experiments.front().y.cols(); }
  Eigen::Index total_samples() const {
    Eigen::Index n = 0;
    for (const auto& e : experiments) n += e.samples();
    return n;
  }
  std::string input_name(Eigen::Index j) const {
    return j < static_cast<Eigen::Index>(input_names.size()) ? input_names[j] : "u" + std::to_string(j + 1);
  }
  std::string output_name(Eigen::Index i) const {
    return i < static_cast<Eigen::Index>(output_names.size()) ? output_names[i] : "y" + std::to_string(i + 1);
  }

  /// Appends another experiment; channels and Ts must match.
  void add_experiment(Experiment e) {
    experiments.push_back(std::move(e));
    validate();
  }

  /// Throws std::invalid_argument on inconsistent dimensions, Ts <= 0 or non-finite samples.
  void validate() const {
    if (experiments.empty()) throw std::invalid_argument("io-data: no experiments");
    if (!(Ts > 0.0) || !std::isfinite(Ts)) throw std::invalid_argument("io-data: sample time must be > 0");
    const auto m = inputs(), l = outputs();
    for (const auto& e : experiments) {
      if (e.u.rows() != e.y.rows())
        throw std::invalid_argument("io-data: " + e.source + ": " + std::to_string(e.u.rows()) + " input samples but " +
                                    std::to_string(e.y.rows()) + " output samples");
      if (e.u.cols() != m || e.y.cols() != l)
        throw std::invalid_argument("io-data: experiments have different numbers of channels");
      if (!e.u.allFinite() || !e.y.allFinite()) throw std::invalid_argument("io-data: " + e.source + ": NaN or Inf in the data");
    }
    if (!input_names.empty() && static_cast<Eigen::Index>(input_names.size()) != m)
      throw std::invalid_argument("io-data: input name count differs from input count");
    if (!output_names.empty() && static_cast<Eigen::Index>(output_names.size()) != l)
      throw std::invalid_argument("io-data: output name count differs from output count");
  }
};

/// Channel means over all experiments (weighted by their lengths).
struct ChannelOffsets {
  Eigen::VectorXd input;   ///< m
  Eigen::VectorXd output;  ///< l
};

/// Subtracts the mean of every channel (over all experiments) and returns the
/// offsets removed, so a model can record them (model JSON input_offset/output_offset).
inline ChannelOffsets remove_means(IoData& data) {
  data.validate();
  ChannelOffsets off{Eigen::VectorXd::Zero(data.inputs()), Eigen::VectorXd::Zero(data.outputs())};
  const double n = static_cast<double>(data.total_samples());
  for (const auto& e : data.experiments) {
    off.input += e.u.colwise().sum().transpose() / n;
    off.output += e.y.colwise().sum().transpose() / n;
  }
  for (auto& e : data.experiments) {
    e.u.rowwise() -= off.input.transpose();
    e.y.rowwise() -= off.output.transpose();
  }
  return off;
}

/// Removes a least-squares straight line from every channel of every experiment
/// (each experiment its own line: records taken apart drift apart).
inline void remove_trends(IoData& data) {
  data.validate();
  auto detrend = [](Eigen::MatrixXd& x) {
    const Eigen::Index n = x.rows();
    if (n < 2) return;
    // Orthogonal basis {1, t - mean(t)} makes the fit two independent projections.
    const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)).array() - 0.5 * static_cast<double>(n - 1);
    const double tt = t.squaredNorm();
    for (Eigen::Index c = 0; c < x.cols(); ++c) {
      const double mean = x.col(c).mean();
      const double slope = t.dot(x.col(c)) / tt;
      x.col(c) = (x.col(c).array() - mean - slope * t.array()).matrix();
    }
  };
  for (auto& e : data.experiments) {
    detrend(e.u);
    detrend(e.y);
  }
}

/// Estimation/validation split: the first `fraction` of every experiment for
/// estimation, the rest for validation (time order kept, so validation is a true
/// look into data the fit never saw).
struct DataSplit {
  IoData estimation;
  IoData validation;
};

inline DataSplit split(const IoData& data, double fraction) {
  if (!(fraction > 0.0 && fraction < 1.0)) throw std::invalid_argument("split: fraction must be in (0, 1)");
  data.validate();
  DataSplit s;
  for (IoData* part : {&s.estimation, &s.validation}) {
    part->Ts = data.Ts;
    part->input_names = data.input_names;
    part->output_names = data.output_names;
  }
  for (const auto& e : data.experiments) {
    const Eigen::Index n = e.samples();
    const auto ne = static_cast<Eigen::Index>(fraction * static_cast<double>(n));
    if (ne < 1 || ne >= n) throw std::invalid_argument("split: experiment " + e.source + " too short to split");
    s.estimation.experiments.push_back({e.u.topRows(ne), e.y.topRows(ne), e.source});
    s.validation.experiments.push_back({e.u.bottomRows(n - ne), e.y.bottomRows(n - ne), e.source});
  }
  return s;
}

}  // namespace sysid
