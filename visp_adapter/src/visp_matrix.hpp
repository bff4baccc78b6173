#pragma once
// Copies between ViSP's matrices and Eigen's, for the adapter's sources only (never installed
// with the public headers: they must show no ViSP type).

#include <stdexcept>

#include <Eigen/Core>
#include <visp3/core/vpColVector.h>
#include <visp3/core/vpMatrix.h>

namespace pepper::visp_adapter {

template <int Rows, int Cols>
Eigen::Matrix<double, Rows, Cols> to_eigen(const vpMatrix& m) {
  if (m.getRows() != static_cast<unsigned>(Rows) || m.getCols() != static_cast<unsigned>(Cols)) {
    throw std::logic_error("visp_adapter: ViSP returned a matrix of unexpected size");
  }
  Eigen::Matrix<double, Rows, Cols> out;
  for (int r = 0; r < Rows; ++r)
    for (int c = 0; c < Cols; ++c) out(r, c) = m[static_cast<unsigned>(r)][static_cast<unsigned>(c)];
  return out;
}

inline vpMatrix to_visp(const Eigen::MatrixXd& m) {
  vpMatrix out(static_cast<unsigned>(m.rows()), static_cast<unsigned>(m.cols()));
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c)
      out[static_cast<unsigned>(r)][static_cast<unsigned>(c)] = m(r, c);
  return out;
}

inline vpColVector to_visp(const Eigen::VectorXd& v) {
  vpColVector out(static_cast<unsigned>(v.size()));
  for (Eigen::Index i = 0; i < v.size(); ++i) out[static_cast<unsigned>(i)] = v(i);
  return out;
}

inline Eigen::VectorXd to_eigen(const vpColVector& v) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(v.size()));
  for (unsigned i = 0; i < v.size(); ++i) out(static_cast<Eigen::Index>(i)) = v[i];
  return out;
}

}  // namespace pepper::visp_adapter
