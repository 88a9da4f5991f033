#include <sysid/core/streaming_qr.hpp>

#include <gtest/gtest.h>

#include "random_systems.hpp"

namespace test_unit_core_streaming_qr {

using namespace sysid;

TEST(StreamingQR, MatchesQrOfWholeMatrixForAnyChunking) {
  const Eigen::MatrixXd m = test::white_noise(3001, 17, 7);
  Eigen::HouseholderQR<Eigen::MatrixXd> full(m);
  Eigen::MatrixXd r_full = full.matrixQR().topRows(17).triangularView<Eigen::Upper>();
  for (int i = 0; i < 17; ++i)
    if (r_full(i, i) < 0) r_full.row(i) *= -1;
  for (Eigen::Index chunk : {1, 5, 64, 256, 5000}) {
    StreamingQR qr(17, chunk);
    Eigen::Index done = 0, step = 1;
    while (done < m.rows()) {  // irregular block sizes
      const Eigen::Index take = std::min(step, m.rows() - done);
      qr.add_rows(m.middleRows(done, take));
      done += take;
      step = step * 3 % 97 + 1;
    }
    EXPECT_EQ(qr.rows_added(), m.rows());
    EXPECT_LT((qr.r() - r_full).norm(), 1e-10 * r_full.norm()) << "chunk " << chunk;
  }
}

TEST(StreamingQR, GramIdentityOnIllConditionedColumns) {
  // Columns scaled over 12 decades: R^T R must still equal M^T M column by column.
  Eigen::MatrixXd m = test::white_noise(500, 6, 3);
  for (int c = 0; c < 6; ++c) m.col(c) *= std::pow(10.0, 2.0 * c - 6.0);
  StreamingQR qr(6, 64);
  qr.add_rows(m);
  const Eigen::MatrixXd r = qr.r();
  const Eigen::MatrixXd g = m.transpose() * m, g2 = r.transpose() * r;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) EXPECT_NEAR(g2(i, j), g(i, j), 1e-12 * std::sqrt(g(i, i) * g(j, j)));
}

TEST(StreamingQR, RejectsWrongWidth) {
  StreamingQR qr(3);
  EXPECT_THROW(qr.add_rows(Eigen::MatrixXd::Zero(2, 4)), std::invalid_argument);
  EXPECT_THROW(StreamingQR(0), std::invalid_argument);
}

}  // namespace test_unit_core_streaming_qr
