// Planar-motion three-view line RANSAC (see planar_trifocal.hpp for the model and the solver).
#include "core/geometry/planar_trifocal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>

// The core runs single-threaded (ARCHITECTURE.md): no OpenMP inside Eigen products.
#ifndef EIGEN_DONT_PARALLELIZE
#define EIGEN_DONT_PARALLELIZE
#endif
#include <Eigen/Dense>

namespace pepper::core::geometry {
namespace {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

Mat3 rot_y(double a) {
  const double c = std::cos(a), s = std::sin(a);
  Mat3 r;
  r << c, 0, s, 0, 1, 0, -s, 0, c;
  return r;
}

// Per-triplet data precomputed once.
struct Prepared {
  std::array<Vec3, 3> l;    // unit-norm homogeneous image lines (normalised coordinates)
  std::array<Vec3, 3> e0;   // homogeneous endpoints
  std::array<Vec3, 3> e1;
  double leverage = 0.0;    // min over views of |normal_y| (a^2 + b^2 = 1 scaling)
  Mat3 B;                   // bilinear rotation form: det = e(yaw1)^T B e(yaw2)
};

Vec3 hom(const cv::Point2d& p) { return {p.x, p.y, 1.0}; }

// Rotated column R(yaw)^T l = cos*u0 + sin*u1 + u2 (see header): returns u0, u1, u2.
void column_basis(const Vec3& l, Vec3& u0, Vec3& u1, Vec3& u2) {
  u0 = Vec3(l.x(), 0.0, l.z());
  u1 = Vec3(-l.z(), 0.0, l.x());
  u2 = Vec3(0.0, l.y(), 0.0);
}

Prepared prepare(const LineTriplet& t) {
  Prepared p;
  p.leverage = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    p.e0[i] = hom(t.view[i].p0);
    p.e1[i] = hom(t.view[i].p1);
    Vec3 l = p.e0[i].cross(p.e1[i]);
    const double ab = std::hypot(l.x(), l.y());
    if (ab > 0) p.leverage = std::min(p.leverage, std::abs(l.y()) / ab);
    else p.leverage = 0.0;
    const double n = l.norm();
    p.l[i] = n > 0 ? Vec3(l / n) : Vec3::Zero();
  }
  std::array<Vec3, 3> u1, u2;
  column_basis(p.l[1], u1[0], u1[1], u1[2]);
  column_basis(p.l[2], u2[0], u2[1], u2[2]);
  for (int m = 0; m < 3; ++m)
    for (int n = 0; n < 3; ++n) p.B(m, n) = p.l[0].dot(u1[m].cross(u2[n]));
  return p;
}

Vec3 e_of(double a) { return {std::cos(a), std::sin(a), 1.0}; }

// f(yaw1) for two rotation equations: v = (B_A^T e1) x (B_B^T e1); f = vx^2 + vy^2 - vz^2.
double resultant(const Mat3& BA, const Mat3& BB, double yaw1, Vec3* v_out) {
  const Vec3 e1 = e_of(yaw1);
  const Vec3 v = (BA.transpose() * e1).cross(BB.transpose() * e1);
  if (v_out) *v_out = v;
  return v.x() * v.x() + v.y() * v.y() - v.z() * v.z();
}

// Yaw pairs solving both rotation equations with |yaw| <= max_yaw.
std::vector<std::pair<double, double>> solve_yaws(const Mat3& BA, const Mat3& BB, double max_yaw,
                                                  int steps) {
  std::vector<std::pair<double, double>> out;
  const double lo = -max_yaw, hi = max_yaw;
  double a_prev = lo;
  double f_prev = resultant(BA, BB, a_prev, nullptr);
  for (int s = 1; s <= steps; ++s) {
    const double a = lo + (hi - lo) * s / steps;
    const double f = resultant(BA, BB, a, nullptr);
    if ((f_prev <= 0.0) != (f <= 0.0)) {
      double x0 = a_prev, x1 = a, f0 = f_prev;
      for (int it = 0; it < 20; ++it) {
        const double xm = 0.5 * (x0 + x1);
        const double fm = resultant(BA, BB, xm, nullptr);
        if ((f0 <= 0.0) == (fm <= 0.0)) {
          x0 = xm;
          f0 = fm;
        } else {
          x1 = xm;
        }
        if (x1 - x0 < 1e-9) break;
      }
      const double yaw1 = 0.5 * (x0 + x1);
      Vec3 v;
      resultant(BA, BB, yaw1, &v);
      if (std::abs(v.z()) > 1e-9 * v.norm() && v.norm() > 1e-15) {
        const double yaw2 = std::atan2(v.y() / v.z(), v.x() / v.z());
        if (std::abs(yaw2) <= max_yaw * 1.05) out.emplace_back(yaw1, yaw2);
      }
    }
    a_prev = a;
    f_prev = f;
  }
  return out;
}

// Translation equation row of one triplet given rotations (coefficients of tx1, tz1, tx2, tz2).
bool translation_row(const Prepared& p, const Mat3& R1, const Mat3& R2, Eigen::RowVector4d& row) {
  Mat3 U;
  U.col(0) = p.l[0];
  U.col(1) = R1.transpose() * p.l[1];
  U.col(2) = R2.transpose() * p.l[2];
  // Null vector of U from the pair of rows with the largest cross product.
  Vec3 best = Vec3::Zero();
  for (int a = 0; a < 3; ++a) {
    for (int b = a + 1; b < 3; ++b) {
      const Vec3 c = Vec3(U.row(a)).cross(Vec3(U.row(b)));
      if (c.squaredNorm() > best.squaredNorm()) best = c;
    }
  }
  if (best.squaredNorm() < 1e-24) return false;
  const Vec3& l1 = p.l[1];
  const Vec3& l2 = p.l[2];
  row << best(1) * l1.x(), best(1) * l1.z(), best(2) * l2.x(), best(2) * l2.z();
  const double n = row.norm();
  if (n < 1e-12) return false;
  row /= n;
  return true;
}

struct Model {
  double yaw1 = 0, yaw2 = 0;
  Eigen::Vector4d t = Eigen::Vector4d::Zero();  // tx1, tz1, tx2, tz2
};

// Scoring: residual in normalised units (max endpoint distance to the transferred line).
struct Scorer {
  std::array<Mat3, 3> R;
  std::array<Vec3, 3> t;
  explicit Scorer(const Model& m) {
    R[0] = Mat3::Identity();
    R[1] = rot_y(m.yaw1);
    R[2] = rot_y(m.yaw2);
    t[0] = Vec3::Zero();
    t[1] = Vec3(m.t(0), 0.0, m.t(1));
    t[2] = Vec3(m.t(2), 0.0, m.t(3));
  }
  // Distance (normalised units) of view k's segment endpoints to the line transferred from
  // views i and j (3D line = intersection of their back-projected planes).
  double transfer(const Prepared& p, const std::array<Vec3, 3>& n, const std::array<double, 3>& delta,
                  int i, int j, int k) const {
    const Vec3 D = n[i].cross(n[j]);
    const double d2 = D.squaredNorm();
    if (d2 < 1e-30) return std::numeric_limits<double>::infinity();
    const Vec3 X0 = (delta[i] * n[j].cross(D) + delta[j] * D.cross(n[i])) / d2;
    const Vec3 lk = (R[k] * X0 + t[k]).cross(R[k] * D);
    const double ab = std::hypot(lk.x(), lk.y());
    if (ab < 1e-300) return std::numeric_limits<double>::infinity();
    return std::max(std::abs(lk.dot(p.e0[k])), std::abs(lk.dot(p.e1[k]))) / ab;
  }
  // Signed distances of view k's endpoints to the line transferred from views i, j (for LM).
  bool transfer_signed(const Prepared& p, int k, double& d0, double& d1, bool weighted = false) const {
    std::array<Vec3, 3> n;
    std::array<double, 3> delta;
    for (int v = 0; v < 3; ++v) {
      n[v] = R[v].transpose() * p.l[v];
      delta[v] = -p.l[v].dot(t[v]);
    }
    const int i = k == 0 ? 1 : 0, j = k == 2 ? 1 : 2;
    const Vec3 D = n[i].cross(n[j]);
    const double dd = D.squaredNorm();
    if (dd < 1e-30) return false;
    const Vec3 X0 = (delta[i] * n[j].cross(D) + delta[j] * D.cross(n[i])) / dd;
    Vec3 lk = (R[k] * X0 + t[k]).cross(R[k] * D);
    const double ab = std::hypot(lk.x(), lk.y());
    if (ab < 1e-300) return false;
    lk /= ab;
    // Fix the sign with the observed line so that the residual is continuous in the parameters.
    if (lk.x() * p.l[k].x() + lk.y() * p.l[k].y() < 0) lk = -lk;
    d0 = lk.dot(p.e0[k]);
    d1 = lk.dot(p.e1[k]);
    if (weighted) {
      // First-order conditioning of the transfer: its error grows like 1 / sin(angle between the
      // two back-projected planes), so weight by that sine.
      const double w = std::sqrt(dd);
      d0 *= w;
      d1 *= w;
    }
    return true;
  }
  // Index of the view whose transfer residual is the smallest.
  int best_view(const Prepared& p) const {
    std::array<Vec3, 3> n;
    std::array<double, 3> delta;
    for (int i = 0; i < 3; ++i) {
      n[i] = R[i].transpose() * p.l[i];
      delta[i] = -p.l[i].dot(t[i]);
    }
    const double r2 = transfer(p, n, delta, 0, 1, 2);
    const double r1 = transfer(p, n, delta, 0, 2, 1);
    const double r0 = transfer(p, n, delta, 1, 2, 0);
    return (r0 <= r1 && r0 <= r2) ? 0 : (r1 <= r2 ? 1 : 2);
  }
  // Best (smallest) of the three transfer residuals. With `accept` > 0 the search stops at the
  // first transfer within `accept` (best-conditioned pair first): enough to classify an inlier.
  double residual(const Prepared& p, double accept = 0.0) const {
    std::array<Vec3, 3> n;
    std::array<double, 3> delta;  // plane n . X = delta
    for (int i = 0; i < 3; ++i) {
      n[i] = R[i].transpose() * p.l[i];
      delta[i] = -p.l[i].dot(t[i]);
    }
    // Transfer into k from the other two views; order by the conditioning |n_i x n_j|.
    const double c2 = n[0].cross(n[1]).squaredNorm();  // into view 2
    const double c1 = n[0].cross(n[2]).squaredNorm();  // into view 1
    const double c0 = n[1].cross(n[2]).squaredNorm();  // into view 0
    std::array<int, 3> order{2, 1, 0};
    const std::array<double, 3> cond{c0, c1, c2};
    std::sort(order.begin(), order.end(), [&](int a, int b) { return cond[a] > cond[b]; });
    double best = std::numeric_limits<double>::infinity();
    for (int k : order) {
      const int i = k == 0 ? 1 : 0, j = k == 2 ? 1 : 2;
      best = std::min(best, transfer(p, n, delta, i, j, k));
      if (best <= accept) break;
    }
    // The best of the three transfers: a transfer through two nearly coplanar back-projected
    // planes amplifies noise, the best-conditioned one does not (docs/perception.md).
    return best;
  }
};

// Segment check between view 0 and view b (1 or 2) under a model: the epipolar lines of view 0's
// endpoints cut view b's line at points that must overlap view b's segment (margin: 10 % of its
// length + `margin` normalised units). Independent of the sign of t. Segments within 10 degrees
// of their epipolar lines carry no such constraint and pass (the intersection is unstable; a
// cheirality test on these intersections was tried and rejected for the same reason).
bool segments_consistent(const Prepared& p, const Model& m, int b, double margin) {
  const Mat3 R = rot_y(b == 1 ? m.yaw1 : m.yaw2);
  const Vec3 t = b == 1 ? Vec3(m.t(0), 0.0, m.t(1)) : Vec3(m.t(2), 0.0, m.t(3));
  Mat3 tx;
  tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
  const Mat3 E = tx * R;
  const Vec3& lb = p.l[static_cast<size_t>(b)];
  const Vec3 eb0 = p.e0[static_cast<size_t>(b)], eb1 = p.e1[static_cast<size_t>(b)];
  const Eigen::Vector2d u2(eb1.x() - eb0.x(), eb1.y() - eb0.y());
  const double len = u2.norm();
  if (len <= 0) return true;
  const Eigen::Vector2d u = u2 / len;
  double s[2];
  const Vec3 ends[2] = {p.e0[0], p.e1[0]};
  for (int k = 0; k < 2; ++k) {
    const Vec3 ep = E * ends[k];
    const double n_ep = std::hypot(ep.x(), ep.y());
    if (n_ep <= 0) return true;
    if (std::abs(ep.x() * u.y() - ep.y() * u.x()) / n_ep < 0.1736) return true;  // < 10 deg
    const Vec3 q = lb.cross(ep);
    if (std::abs(q.z()) < 1e-12) return true;
    const Vec3 qn = q / q.z();
    s[k] = (qn.x() - eb0.x()) * u.x() + (qn.y() - eb0.y()) * u.y();
  }
  const double lo = std::min(s[0], s[1]), hi = std::max(s[0], s[1]);
  const double mg = 0.1 * len + margin;
  return hi >= -mg && lo <= len + mg;
}

// Per-triplet optimal check under a fixed motion: the 3D line is parametrised by its (corrected)
// images in the two views whose back-projected planes are the least parallel, the third image is
// their transfer; Levenberg-Marquardt moves the two corrected lines to minimise the squared
// distances of all six segment endpoints to the three image lines. Returns the RMS endpoint
// distance (normalised units). Unlike the best-transfer residual, an outlier in any view must be
// explained by the same 3D line as the two others.
double optimal_residual(const Prepared& p, const Scorer& sc) {
  std::array<Vec3, 3> n;
  for (int v = 0; v < 3; ++v) n[v] = sc.R[v].transpose() * p.l[v];
  const double s01 = n[0].cross(n[1]).squaredNorm(), s02 = n[0].cross(n[2]).squaredNorm(),
               s12 = n[1].cross(n[2]).squaredNorm();
  int i, j, k;
  if (s01 >= s02 && s01 >= s12) {
    i = 0, j = 1, k = 2;
  } else if (s02 >= s12) {
    i = 0, j = 2, k = 1;
  } else {
    i = 1, j = 2, k = 0;
  }
  // Parameters: (theta, rho) of the corrected lines in views i and j.
  auto to_tr = [](const Vec3& l) {
    const double ab = std::hypot(l.x(), l.y());
    return Eigen::Vector2d(std::atan2(l.y(), l.x()), -l.z() / ab);
  };
  auto from_tr = [](double th, double rho) { return Vec3(std::cos(th), std::sin(th), -rho); };
  Eigen::Vector4d x;
  x << to_tr(p.l[i]), to_tr(p.l[j]);
  auto residuals = [&](const Eigen::Vector4d& xx, Eigen::Matrix<double, 6, 1>& r) -> bool {
    const Vec3 li = from_tr(xx(0), xx(1)), lj = from_tr(xx(2), xx(3));
    r(0) = li.dot(p.e0[i]);
    r(1) = li.dot(p.e1[i]);
    r(2) = lj.dot(p.e0[j]);
    r(3) = lj.dot(p.e1[j]);
    const Vec3 ni = sc.R[i].transpose() * li, nj = sc.R[j].transpose() * lj;
    const double di = -li.dot(sc.t[i]), dj = -lj.dot(sc.t[j]);
    const Vec3 D = ni.cross(nj);
    const double dd = D.squaredNorm();
    if (dd < 1e-30) return false;
    const Vec3 X0 = (di * nj.cross(D) + dj * D.cross(ni)) / dd;
    const Vec3 lk = (sc.R[k] * X0 + sc.t[k]).cross(sc.R[k] * D);
    const double ab = std::hypot(lk.x(), lk.y());
    if (ab < 1e-300) return false;
    r(4) = lk.dot(p.e0[k]) / ab;
    r(5) = lk.dot(p.e1[k]) / ab;
    return true;
  };
  Eigen::Matrix<double, 6, 1> r0, r1;
  if (!residuals(x, r0)) return std::numeric_limits<double>::infinity();
  double cost = r0.squaredNorm();
  double lambda = 1e-3;
  Eigen::Matrix<double, 6, 4> J;
  for (int it = 0; it < 8; ++it) {
    for (int c = 0; c < 4; ++c) {
      Eigen::Vector4d xp = x;
      xp(c) += 1e-7;
      if (!residuals(xp, r1)) return std::sqrt(cost / 6.0);
      J.col(c) = (r1 - r0) / 1e-7;
    }
    const Eigen::Matrix4d H = J.transpose() * J;
    const Eigen::Vector4d g = J.transpose() * r0;
    bool improved = false;
    for (int tries = 0; tries < 4 && !improved; ++tries) {
      Eigen::Matrix4d A = H;
      for (int d = 0; d < 4; ++d) A(d, d) += lambda * (H(d, d) + 1e-12);
      const Eigen::Vector4d xn = x + A.ldlt().solve(-g);
      if (xn.allFinite() && residuals(xn, r1) && r1.squaredNorm() < cost) {
        const double gain = cost - r1.squaredNorm();
        x = xn;
        r0 = r1;
        cost = r1.squaredNorm();
        lambda = std::max(lambda * 0.3, 1e-9);
        improved = true;
        if (gain < 1e-6 * cost) it = 8;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) break;
  }
  return std::sqrt(cost / 6.0);
}

bool translation_from_rows(const std::vector<Eigen::RowVector4d>& rows, Eigen::Vector4d& t) {
  if (rows.size() < 3) return false;
  if (rows.size() == 3) {
    Eigen::Matrix<double, 3, 4> A;
    for (int r = 0; r < 3; ++r) A.row(r) = rows[static_cast<size_t>(r)];
    // Generalised cross product: signed 3x3 minors.
    for (int k = 0; k < 4; ++k) {
      Eigen::Matrix3d M;
      int c = 0;
      for (int j = 0; j < 4; ++j) {
        if (j == k) continue;
        M.col(c++) = A.col(j);
      }
      t(k) = ((k % 2) ? -1.0 : 1.0) * M.determinant();
    }
  } else {
    Eigen::Matrix4d AtA = Eigen::Matrix4d::Zero();
    for (const auto& r : rows) AtA.noalias() += r.transpose() * r;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(AtA);
    t = es.eigenvectors().col(0);
  }
  const double n = t.norm();
  if (n < 1e-12) return false;
  t /= n;
  return true;
}

// Levenberg-Marquardt on the geometric transfer residuals of the given triplets (each measured
// in the view chosen by best_view at the start), over (yaw1, yaw2, tx1, tz1, tx2, tz2); the scale
// of t is a gauge freedom absorbed by the damping and removed by renormalising.
void lm_refine(const std::vector<Prepared>& prep, const std::vector<int>& idx, Model& m, int iterations) {
  if (idx.size() < 4) return;
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  auto to_model = [](const Vec6& x) {
    Model r;
    r.yaw1 = x(0);
    r.yaw2 = x(1);
    r.t = x.tail<4>();
    const double n = r.t.norm();
    if (n > 0) r.t /= n;
    return r;
  };
  Vec6 x;
  x << m.yaw1, m.yaw2, m.t;
  // Residuals: all three transfers of every triplet, each weighted by its conditioning (the
  // scoring residual, the best transfer, is too permissive to pull a model out of the
  // yaw / lateral-translation valley).
  const int nres = static_cast<int>(idx.size()) * 6;
  auto residuals = [&](const Vec6& xx, Eigen::VectorXd& r) {
    const Scorer sc(to_model(xx));
    r.resize(nres);
    for (size_t q = 0; q < idx.size(); ++q) {
      for (int k = 0; k < 3; ++k) {
        double d0 = 0, d1 = 0;
        if (!sc.transfer_signed(prep[static_cast<size_t>(idx[q])], k, d0, d1, true)) d0 = d1 = 0.0;
        r(static_cast<int>(6 * q + 2 * k)) = d0;
        r(static_cast<int>(6 * q + 2 * k + 1)) = d1;
      }
    }
  };
  Eigen::VectorXd r0, r1;
  residuals(x, r0);
  double cost = r0.squaredNorm();
  double lambda = 1e-3;
  Eigen::MatrixXd J(nres, 6);
  for (int it = 0; it < iterations; ++it) {
    for (int c = 0; c < 6; ++c) {
      Vec6 xp = x;
      const double h = 1e-7;
      xp(c) += h;
      residuals(xp, r1);
      J.col(c) = (r1 - r0) / h;
    }
    const Eigen::Matrix<double, 6, 6> H = J.transpose() * J;
    const Vec6 g = J.transpose() * r0;
    bool improved = false;
    for (int tries = 0; tries < 5 && !improved; ++tries) {
      Eigen::Matrix<double, 6, 6> A = H;
      for (int d = 0; d < 6; ++d) A(d, d) += lambda * (H(d, d) + 1e-12);
      const Vec6 step = A.ldlt().solve(-g);
      if (!step.allFinite()) break;
      Vec6 xn = x + step;
      const double n = xn.tail<4>().norm();
      if (n <= 0) break;
      xn.tail<4>() /= n;
      residuals(xn, r1);
      const double c1 = r1.squaredNorm();
      if (c1 < cost) {
        x = xn;
        r0 = r1;
        const double rel = (cost - c1) / std::max(cost, 1e-300);
        cost = c1;
        lambda = std::max(lambda * 0.3, 1e-9);
        improved = true;
        if (rel < 1e-8) it = iterations;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) break;
  }
  m = to_model(x);
}

}  // namespace

std::vector<std::string> PlanarTrifocalOptions::validate() const {
  std::vector<std::string> e;
  auto bad = [&](const char* name, double v, const char* range) {
    std::ostringstream os;
    os << "trifocal." << name << " = " << v << " must be in " << range;
    e.push_back(os.str());
  };
  if (!(threshold_px > 0.0 && threshold_px <= 100.0)) bad("threshold_px", threshold_px, "(0, 100]");
  if (!(confidence > 0.0 && confidence < 1.0)) bad("confidence", confidence, "(0, 1)");
  if (!(max_iterations >= 1 && max_iterations <= 1000000)) bad("max_iterations", max_iterations, "[1, 1e6]");
  if (!(min_inliers >= 3)) bad("min_inliers", min_inliers, "[3, inf)");
  if (!(max_yaw_rad > 0.0 && max_yaw_rad < M_PI_2)) bad("max_yaw_rad", max_yaw_rad, "(0, pi/2)");
  if (!(min_rotation_leverage >= 0.0 && min_rotation_leverage < 1.0))
    bad("min_rotation_leverage", min_rotation_leverage, "[0, 1)");
  if (!(overlap_margin_px >= 0.0)) bad("overlap_margin_px", overlap_margin_px, "[0, inf)");
  if (!(min_iterations >= 1 && min_iterations <= max_iterations))
    bad("min_iterations", min_iterations, "[1, max_iterations]");
  if (!(optimal_threshold_px > 0.0)) bad("optimal_threshold_px", optimal_threshold_px, "(0, inf)");
  if (!(max_lo_runs >= 0 && max_lo_runs <= 1000)) bad("max_lo_runs", max_lo_runs, "[0, 1000]");
  if (!(lo_iterations >= 0 && lo_iterations <= 100)) bad("lo_iterations", lo_iterations, "[0, 100]");
  if (!(yaw_scan_steps >= 4 && yaw_scan_steps <= 10000)) bad("yaw_scan_steps", yaw_scan_steps, "[4, 10000]");
  return e;
}

double line_triplet_residual_px(const LineTriplet& triplet, const PlanarMotion3& motion,
                                double focal_px) {
  Model m;
  m.yaw1 = motion.yaw_rad[1];
  m.yaw2 = motion.yaw_rad[2];
  m.t << motion.t_xz[1][0], motion.t_xz[1][1], motion.t_xz[2][0], motion.t_xz[2][1];
  return Scorer(m).residual(prepare(triplet)) * focal_px;
}

PlanarTrifocalResult verify_line_triplets(const std::vector<LineTriplet>& triplets, double focal_px,
                                          const PlanarTrifocalOptions& options) {
  if (!(focal_px > 0.0)) throw std::invalid_argument("verify_line_triplets: focal_px must be > 0");
  const auto errors = options.validate();
  if (!errors.empty()) throw std::invalid_argument("verify_line_triplets: " + errors.front());

  PlanarTrifocalResult result;
  const int n = static_cast<int>(triplets.size());
  if (n < 3) return result;
  std::vector<Prepared> prep;
  prep.reserve(triplets.size());
  std::vector<int> rot_idx;
  for (int i = 0; i < n; ++i) {
    prep.push_back(prepare(triplets[static_cast<size_t>(i)]));
    if (prep.back().leverage >= options.min_rotation_leverage) rot_idx.push_back(i);
  }
  if (rot_idx.size() < 2) return result;

  const double thr = options.threshold_px / focal_px;
  const double thr2 = thr * thr;
  auto cost_of = [&](const Model& m, int* inliers, int* rot_inliers) {
    const Scorer sc(m);
    double cost = 0.0;
    int cnt = 0, rcnt = 0;
    for (int i = 0; i < n; ++i) {
      const double r = sc.residual(prep[static_cast<size_t>(i)], thr);
      if (r <= thr) {
        cost += r * r;
        ++cnt;
        if (prep[static_cast<size_t>(i)].leverage >= options.min_rotation_leverage) ++rcnt;
      } else {
        cost += thr2;
      }
    }
    if (inliers) *inliers = cnt;
    if (rot_inliers) *rot_inliers = rcnt;
    return cost;
  };

  auto inliers_of = [&](const Model& m, double threshold) {
    const Scorer sc(m);
    std::vector<int> idx;
    for (int i = 0; i < n; ++i)
      if (sc.residual(prep[static_cast<size_t>(i)], threshold) <= threshold) idx.push_back(i);
    return idx;
  };

  std::mt19937_64 rng(options.seed);
  Model best;
  double best_cost = std::numeric_limits<double>::infinity();
  int best_inliers = 0;
  int max_iter = options.max_iterations;
  int lo_runs = 0;
  const int nr = static_cast<int>(rot_idx.size());
  for (int it = 0; it < max_iter && it < options.max_iterations; ++it) {
    ++result.iterations;
    std::uniform_int_distribution<int> pick_r(0, nr - 1), pick_all(0, n - 1);
    const int a = rot_idx[static_cast<size_t>(pick_r(rng))];
    int b = a;
    for (int guard = 0; b == a && guard < 16; ++guard) b = rot_idx[static_cast<size_t>(pick_r(rng))];
    int c = a;
    for (int guard = 0; (c == a || c == b) && guard < 16; ++guard) c = pick_all(rng);
    if (a == b || c == a || c == b) continue;
    const auto yaws = solve_yaws(prep[static_cast<size_t>(a)].B, prep[static_cast<size_t>(b)].B,
                                 options.max_yaw_rad, options.yaw_scan_steps);
    for (const auto& [y1, y2] : yaws) {
      Model m;
      m.yaw1 = y1;
      m.yaw2 = y2;
      const Mat3 R1 = rot_y(y1), R2 = rot_y(y2);
      std::vector<Eigen::RowVector4d> rows(3);
      if (!translation_row(prep[static_cast<size_t>(a)], R1, R2, rows[0]) ||
          !translation_row(prep[static_cast<size_t>(b)], R1, R2, rows[1]) ||
          !translation_row(prep[static_cast<size_t>(c)], R1, R2, rows[2]) ||
          !translation_from_rows(rows, m.t)) {
        continue;
      }
      ++result.hypotheses;
      int inl = 0, rinl = 0;
      const double cost = cost_of(m, &inl, &rinl);
      if (cost < best_cost) {
        // Local optimisation (LO-RANSAC): LM on the geometric residuals of this model's inliers.
        Model lo = m;
        double lo_cost = std::numeric_limits<double>::infinity();
        int lo_inl = 0, lo_rinl = 0;
        if (lo_runs < options.max_lo_runs) {
          ++lo_runs;
          for (int rep = 0; rep < 2; ++rep) lm_refine(prep, inliers_of(lo, 2.0 * thr), lo, options.lo_iterations);
          lo_cost = cost_of(lo, &lo_inl, &lo_rinl);
        }
        if (lo_cost < cost) {
          m = lo;
          inl = lo_inl;
          rinl = lo_rinl;
          best_cost = lo_cost;
        } else {
          best_cost = cost;
        }
        best = m;
        best_inliers = inl;
        // Adaptive stopping: P(sample clean) = w_r^2 * w.
        const double w = static_cast<double>(inl) / n;
        const double wr = static_cast<double>(rinl) / nr;
        const double p = std::clamp(wr * wr * w, 1e-12, 1.0 - 1e-12);
        const double needed = std::log(1.0 - options.confidence) / std::log(1.0 - p);
        const int wanted = std::max(options.min_iterations, static_cast<int>(std::ceil(needed)));
        if (wanted < max_iter) max_iter = wanted;
      }
    }
  }
  if (best_inliers < 3) return result;

  // Final refinement: LM on all inliers, twice (the inlier set may grow after the first).
  for (int round = 0; round < 1; ++round) {
    Model m = best;
    lm_refine(prep, inliers_of(best, thr), m, options.lo_iterations);
    int inl = 0;
    const double cost = cost_of(m, &inl, nullptr);
    if (!(cost < best_cost)) break;
    best_cost = cost;
    best = m;
    best_inliers = inl;
  }

  // Final inliers: best-transfer residual within 2x the threshold, then the per-triplet optimal
  // triangulation check, then the segment overlap check (views 0-1 and 0-2).
  const double margin = options.overlap_margin_px / focal_px;
  {
    const Scorer sc(best);
    for (int i : inliers_of(best, 2.0 * thr)) {
      const Prepared& p = prep[static_cast<size_t>(i)];
      if (optimal_residual(p, sc) > options.optimal_threshold_px / focal_px) continue;
      if (options.check_overlap &&
          !(segments_consistent(p, best, 1, margin) && segments_consistent(p, best, 2, margin)))
        continue;
      result.inliers.push_back(i);
    }
  }
  result.motion.yaw_rad = {0.0, best.yaw1, best.yaw2};
  result.motion.t_xz = {cv::Vec2d(0, 0), cv::Vec2d(best.t(0), best.t(1)), cv::Vec2d(best.t(2), best.t(3))};
  result.found = static_cast<int>(result.inliers.size()) >= options.min_inliers;
  if (!result.found) result.inliers.clear();
  return result;
}

}  // namespace pepper::core::geometry
