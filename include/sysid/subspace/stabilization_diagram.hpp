#pragma once
/// @file
/// Purpose: the stabilisation diagram, the modal engineer's tool for choosing the
/// model order and reading the physical modes (PolyMAX, ARTeMIS, MATLAB's
/// `modalsd`): the poles of every model order lo..hi, each marked stable against
/// the order below in frequency, damping and (with several outputs) mode shape;
/// the physical modes read from the columns of stable poles; and an order rule.
///
/// Method (B. Peeters, H. Van der Auweraer, P. Guillaume & J. Leuridan, "The
/// PolyMAX frequency-domain method: a new standard for modal parameter
/// estimation?", Shock and Vibration 11 (2004) 395-409, sec. 3; E. Reynders,
/// "System identification methods for (operational) modal analysis: review and
/// comparison", Arch. Comput. Methods Eng. 19 (2012) 51-124, sec. 6.1):
///  - the poles come from one subspace compression: every order n truncates the
///    same weighted SVD (Gamma_n = U_n S_n^(1/2), A_n from its shift equation;
///    subspace/n4sid.hpp), so n4sid computes them for the cost of one
///    identification (N4sidOptions::stabilization_order_hi);
///  - a pole is a mode candidate when it is an oscillatory pair (Im > 0) with a
///    damping ratio in (0, max_damping]; real and unstable poles are not plotted;
///  - it is stable in frequency when the nearest candidate of order n - 1 lies
///    within frequency_tolerance (relative), in damping when that pole's damping
///    is within damping_tolerance (relative) too, and in shape when the modal
///    assurance criterion MAC = |phi_n^H phi_{n-1}|^2 / (|phi_n|^2 |phi_{n-1}|^2)
///    of the two mode shapes (phi = C v, v the eigenvector) is at least
///    1 - mac_tolerance (core/modal_assurance_criterion.hpp). The
///    defaults, 1 %, 5 % and 2 %, are the usual ones (Peeters et al. sec. 3.2);
///  - physical modes: the fully stable poles (frequency, damping and, with
///    several outputs, shape) sorted by frequency and grouped where neighbours lie
///    within twice the frequency tolerance of the group's mean, at most one pole
///    per order; a group is a physical mode when it holds at least
///    min_column_poles poles and stands at min_column_share or more of the
///    orders from its first stable pole to hi: a physical mode, once found, stays
///    found as the order grows, while a noise pole wanders; and it must start in
///    the lower three quarters of the orders (latest_column_start);
///  - it must not be noise that the high orders fit: a pole's level is the
///    mean of the compression's singular values weighted by its eigenvector's
///    energy in the state coordinates (state j belongs to singular value j), so
///    a pole made of noise-floor states has the floor's level and a mode its
///    own. The poles that wander at an order (new there, and in no column's
///    band) set that order's reference, their median level; a column's level
///    ratio is the median of its poles' level / reference over the upper half of
///    its orders (below the true order the wanderers include modes not yet
///    resolved). A column whose ratio is below min_level_ratio and whose first
///    stable pole comes after every clearer column's first is noise; a weak
///    column among the clear columns' orders stays. Measured: the noise
///    columns of the 28-sensor beam at horizons 30-50 stand at 1.0 x, the 8x8
///    isolator's example log's column at 444 Hz (from order 27 of 2..40; the
///    modes stand from order 17) at 1.8 x; the modes of those at 50-2 700 x; the F-16 ground
///    vibration test's weakest modes at FullMSine level 1 at 11 x (12.3 Hz) and
///    16 x (16.5 Hz, above the excited band), at level 3 12.3 Hz at 2.9 x but
///    from order 18, before the 3.9 Hz mode's 24 (kept); at levels 5 and 7, where
///    the joint's nonlinearity is strong, 12.2 Hz at 0.7-0.9 x from orders
///    34-45 (refused). The threshold, 3, sits between;
///  - and, with many outputs, its mode shapes must be more real than noise: a
///    long horizon lets the extra states of high orders fit the sensor noise
///    with columns that are stable from order to order (28-sensor beam, orders
///    2..60: at horizon 30 columns at 510 and 978 Hz, at 40 one at 524 Hz, beside
///    the twelve modes), but their shapes are random vectors, MPC 0.01-0.09,
///    where the structure's modes have 0.96-1.00. A pole whose
///    quadrature_tolerant_collinearity (core/modal_phase_collinearity.hpp) is
///    below the value a random shape exceeds with probability random_shape_level
///    is random-like; a column with more than half its poles random-like is not
///    a mode and is listed in noise_columns. The test needs a shape
///    spread over enough outputs to tell (that value <= 0.5: about 17 or more
///    effective outputs at 1 %); with fewer it is not made. Strongly
///    non-proportional damping makes physical modes complex too (MPC down to
///    0.1 at 25 % damping from local dashpots): such modes can be refused, and
///    the report names them (random_shape_level = 0 turns the test off);
///  - the order rule: the lowest order whose model has a candidate pole within
///    twice the frequency tolerance of every physical mode. Real poles are not
///    modes; a plant with real poles needs them added by hand (--order N).
///
/// Preconditions (std::invalid_argument): Ts > 0; orders consecutive and
/// increasing; each OrderPoles' shapes have one column per pole (or none).
#include <sysid/core/modal_assurance_criterion.hpp>

#include <Eigen/Dense>
#include <limits>
#include <string>
#include <vector>

namespace sysid {

/// The poles of one model order and their mode shapes, from one subspace compression.
struct OrderPoles {
  int order = 0;
  Eigen::VectorXcd poles;   ///< discrete-time eigenvalues of A_n (sample time Ts)
  Eigen::MatrixXcd shapes;  ///< outputs x n: C_n v_k for each eigenvector v_k (may be empty)
  /// Per pole: the singular values weighted by |v_k|^2 (file comment); may be
  /// empty (the level test is then not made).
  Eigen::VectorXd levels;
};

struct StabilizationOptions {
  double frequency_tolerance = 0.01;  ///< relative frequency change to the order below: 1 %
  double damping_tolerance = 0.05;    ///< relative damping change to the order below: 5 %
  double mac_tolerance = 0.02;        ///< 1 - MAC to the order below: 2 % (several outputs only)
  double max_damping = 0.3;           ///< candidates more damped than this are not modes
  int min_column_poles = 3;           ///< a physical mode holds at least this many stable poles
  /// ... and is stable at this share of the orders from its first stable pole to hi,
  double min_column_share = 0.5;
  /// ... and its first stable pole lies in this lower share of the orders lo..hi:
  /// a column that only appears among the highest orders is noise that the extra
  /// states fit (on the 28-sensor beam at horizon 16, columns at 1.30 and 1.75 kHz
  /// from orders 53 and 55; the structure's twelve modes appear by order 25).
  double latest_column_start = 0.75;
  /// A column whose level is below this many times that of the poles that
  /// wander at its orders, first stable after every clearer column, is noise
  /// (file comment); 0 turns the test off.
  double min_level_ratio = 3.0;
  /// A pole's shape is random-like when a random shape of as many effective
  /// outputs is at least as collinear with this probability or less (file
  /// comment); 0 turns the shape test off.
  double random_shape_level = 0.01;
};

/// One mode candidate of one order.
struct StabilizationPole {
  int order = 0;
  double freq_hz = 0, damping = 0;
  Eigen::VectorXcd shape;  ///< C v (empty when the orders came without shapes)
  double level = std::numeric_limits<double>::quiet_NaN();  ///< OrderPoles::levels (NaN without)
  bool stable_frequency = false, stable_damping = false, stable_shape = false;
  int mode = -1;  ///< index into StabilizationDiagram::modes of the column it belongs to, -1: none
  /// The diagram's symbol: 'o' new, 'f' stable frequency, 'd' frequency and
  /// damping, 'v' frequency and shape, 's' stable in all (in frequency and damping
  /// when there is one output).
  char mark(bool with_shapes) const {
    if (!stable_frequency) return 'o';
    const bool shape_ok = !with_shapes || stable_shape;
    if (stable_damping && shape_ok) return 's';
    if (stable_damping) return 'd';
    return with_shapes && stable_shape ? 'v' : 'f';
  }
};

/// A physical mode: a column of stable poles.
struct PhysicalMode {
  double freq_hz = 0, damping = 0;     ///< medians over the column's stable poles
  double freq_spread = 0;              ///< (max - min) / median frequency over those poles
  double damping_spread = 0;           ///< (max - min) / median damping
  int first_order = 0;                 ///< lowest order with a stable pole in the column
  int stable_poles = 0;                ///< stable poles in the column
  Eigen::VectorXcd shape;              ///< the highest order's shape in the column (unit norm; empty for one output)
  /// Median quadrature_tolerant_collinearity of the column's shapes (1: real); NaN for one output.
  double shape_collinearity = std::numeric_limits<double>::quiet_NaN();
  int random_like_poles = 0;  ///< poles whose shape is no more collinear than a random one's (file comment)
  /// Median over the upper half of the column's orders of level / the median
  /// level of the poles that wander there (file comment); NaN without levels or wanderers.
  double level_ratio = std::numeric_limits<double>::quiet_NaN();
  std::string noise_reason;  ///< for noise_columns: why the column is not a mode
};

struct StabilizationDiagram {
  StabilizationOptions options;
  int order_lo = 0, order_hi = 0;
  bool with_shapes = false;  ///< several outputs: shapes compared by MAC
  std::vector<StabilizationPole> poles;  ///< every candidate of every order, by order then frequency
  std::vector<PhysicalMode> modes;       ///< by frequency
  /// Columns that persist like modes but stand at the noise's level or have
  /// random-like shapes: noise that the high orders fit (file comment); by frequency.
  std::vector<PhysicalMode> noise_columns;
  /// The rule's order (file comment); 0 when no physical mode was found.
  int chosen_order = 0;
  std::string rule;  ///< how chosen_order came about, in words

  /// The physical modes as a table (frequency, damping, their spreads, first
  /// order, stable poles, level ratio and, with several outputs, the shapes'
  /// collinearity).
  std::string modes_table() const;
  /// noise_columns as the same table with each one's reason ("" when there are none).
  std::string noise_columns_table() const;
  /// The tolerances in words, for reports and plots.
  std::string criteria() const;
};

/// Purpose: the diagram of `orders` (file comment), poles at sample time Ts.
StabilizationDiagram stabilization_diagram(const std::vector<OrderPoles>& orders, double Ts,
                                           const StabilizationOptions& options = {});

}  // namespace sysid
