#pragma once
/// @file
/// Purpose: the real modal form of a real square matrix, shared by modal
/// truncation (reduce/modal_truncation.hpp) and the joint refit of a nominal's
/// linear dynamics (diagnose/linear_core_refit.hpp).
///
/// Method: A V = V diag(lambda) from Eigen's EigenSolver; each real eigenvalue
/// keeps its (real) eigenvector as a column of T, each complex pair lambda,
/// conj(lambda) with Im lambda > 0 the real and imaginary parts of lambda's
/// eigenvector, so that T^-1 A T = blockdiag([lambda] or [[Re, Im], [-Im, Re]]).
/// EigenSolver of a real matrix gives real eigenvalues an exactly zero
/// imaginary part (1x1 blocks of its real Schur form), so the test is exact.
/// Conditioning of T (a defective or nearly defective A) is the caller's to
/// judge: each has its own policy; modal_condition() measures it.
#include <Eigen/Dense>
#include <complex>
#include <optional>
#include <vector>

namespace sysid {

struct RealModalBlock {
  Eigen::Index start = 0;        ///< first column of T
  Eigen::Index size = 1;         ///< 1 (real eigenvalue) or 2 (complex pair)
  std::complex<double> lambda;   ///< the eigenvalue (Im > 0 for a pair)
};

struct RealModalForm {
  Eigen::MatrixXd T;                   ///< n x n
  std::vector<RealModalBlock> blocks;  ///< in EigenSolver's order
};

enum class RealModalStatus { ok, no_convergence, unpaired };

/// Fills `form` for A (n x n, n >= 1); `unpaired` when a complex eigenvalue has
/// no conjugate (the columns would not fill T).
RealModalStatus real_modal_form(const Eigen::MatrixXd& A, RealModalForm& form);

/// cond(T) in the 2-norm (ratio of extreme singular values); infinity for a
/// singular T. Working in the coordinates x = T x_m costs up to this factor in
/// the conditioning of whatever is computed there.
double modal_condition(const Eigen::MatrixXd& T);

/// The real modal form of A when it exists and cond(T) <= condition_limit,
/// else std::nullopt; `condition` receives cond(T) (infinity without a form).
std::optional<RealModalForm> conditioned_real_modal_form(const Eigen::MatrixXd& A, double condition_limit,
                                                         double& condition);

/// A_m = blockdiag of the form's blocks (or its transpose) as flat lists, for
/// recursions x <- A_m x that run once per sample: the 2x2 blocks by their
/// first state, the 1x1 blocks by their state; no branch per block.
class ModalBlockLists {
 public:
  ModalBlockLists() = default;
  /// transposed: the lists hold A_m^T (each pair's Im negated).
  ModalBlockLists(const std::vector<RealModalBlock>& blocks, bool transposed) {
    for (const RealModalBlock& b : blocks) {
      if (b.size == 2) {
        m_pair_start.push_back(b.start);
        m_pair_re.push_back(b.lambda.real());
        m_pair_im.push_back(transposed ? -b.lambda.imag() : b.lambda.imag());
      } else {
        m_single.push_back(b.start);
        m_single_re.push_back(b.lambda.real());
      }
    }
  }

  /// next[i] = addend(i) + (A_m s)[i] for distinct arrays s, next of length n
  /// (addend may read next[i]: next += A_m s); a pair's block is
  /// [[Re, Im], [-Im, Re]] (real_modal_form's convention). The addend is a
  /// callable rather than an array so that callers need no scratch buffer: a
  /// buffer written with scalar stores and read back as a pair is a
  /// store-forwarding stall on x86 (it cost the B/D/x0 recursion ~20 %).
  template <class Addend>
  void product(const double* s, double* next, Addend&& addend) const {
    for (std::size_t j = 0; j < m_pair_start.size(); ++j) {
      const Eigen::Index i = m_pair_start[j];
      const double re = m_pair_re[j], im = m_pair_im[j], first = s[i], second = s[i + 1];
      const double a = addend(i) + (re * first + im * second), b = addend(i + 1) + (re * second - im * first);
      next[i] = a;
      next[i + 1] = b;
    }
    for (std::size_t j = 0; j < m_single.size(); ++j) {
      const Eigen::Index i = m_single[j];
      next[i] = addend(i) + m_single_re[j] * s[i];
    }
  }

 private:
  std::vector<Eigen::Index> m_pair_start, m_single;
  std::vector<double> m_pair_re, m_pair_im, m_single_re;
};

/// The block of an eigenvalue: [Re] (size 1) or [[Re, Im], [-Im, Re]] (size 2).
Eigen::MatrixXd real_modal_block(const RealModalBlock& block);

}  // namespace sysid
