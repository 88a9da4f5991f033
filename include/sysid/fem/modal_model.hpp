#pragma once
/// @file
/// Purpose: a reduced state-space model of an FE model from its lowest modes — the
/// order a controller can use — continuous or sampled, in the model-file format
/// every other verb reads (so it can be simulated, compared, reduced further and
/// diagnosed).
///
/// Method: with q = Phi eta (Phi mass-normalised, modal_analysis.hpp), the modal
/// equations eta'' + D_m eta' + Omega^2 eta = Phi^T F u, state x = [eta; eta']:
///
///   A = [ 0  I ; -Omega^2  -D_m ],   B = [ 0 ; Phi^T F ],
///   displacement output at DOF d:  C = [ Phi_d  0 ],  D = 0
///   velocity:                      C = [ 0  Phi_d ],  D = 0
///   acceleration:                  C = Phi_d [ -Omega^2  -D_m ],  D = Phi_d Phi^T F
///
/// (Craig & Kurdila, "Fundamentals of Structural Dynamics", 2nd ed., ch. 11 and
/// 14). Static correction (optional) adds the truncated modes' quasi-static
/// contribution to the displacement outputs, D += S_d (K^{-1} F - Phi Omega^{-2}
/// Phi^T F) (residual flexibility, ibid. sec. 14.6), so the reduced model has the
/// full model's static gain; it needs K non-singular (a structure fixed to
/// ground) and is not applied to velocity or acceleration outputs (their
/// residual would need a frequency-dependent term), which a warning says.
/// Sampling is exact zero-order hold (core/discretize.hpp).
#include <string>
#include <vector>

#include "sysid/core/discretize.hpp"
#include "sysid/core/state_space.hpp"
#include "sysid/fem/modal_analysis.hpp"
#include "sysid/fem/second_order_model.hpp"

namespace sysid::fem {

struct ModalModelOptions {
  bool static_correction = false;  ///< add the residual flexibility of the truncated modes (file comment)
  double Ts = 0.0;                 ///< 0: continuous model; > 0: sampled at Ts seconds with `hold`
  /// ZOH for inputs held by a DAC between samples; FOH (core/discretize.hpp) for
  /// smooth signals that were only sampled, where ZOH lags by half a sample.
  Hold hold = Hold::zoh;
};

struct ModalModelResult {
  StateSpace model;                ///< order 2 x modes; inputs and outputs named as in the FE model
  ModalAnalysisResult modes;       ///< the modes it is built from
  std::vector<std::string> warnings;
};

/// Purpose: the state-space model of `modes` (computed from `model`), per the file comment.
/// Preconditions (std::invalid_argument): model.validate(); modes computed on this
/// model (matching DOF count); Ts >= 0; static correction only with no rigid-body
/// modes. Errors: sysid::NumericalError when K cannot be factorised for the static
/// correction.
ModalModelResult modal_model(const SecondOrderModel& model, const ModalAnalysisResult& modes,
                             const ModalModelOptions& options = {});

/// modal_analysis() then modal_model().
ModalModelResult modal_model(const SecondOrderModel& model, const ModalAnalysisOptions& analysis,
                             const ModalModelOptions& options = {});

}  // namespace sysid::fem
