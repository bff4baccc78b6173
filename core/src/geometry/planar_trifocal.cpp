// Planar-motion three-view line RANSAC (see planar_trifocal.hpp for the model and the solver).
#include "core/geometry/planar_trifocal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>

// The core runs single-threaded (ARCHITECTURE.md): no OpenMP inside Eigen products.
#ifndef EIGEN_DONT_PARALLELIZE
#define EIGEN_DONT_PARALLELIZE
#endif
#include <Eigen/Dense>

#include "core/geometry/essential_ransac.hpp"

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
    const double ab = std::sqrt(lk.x() * lk.x() + lk.y() * lk.y());
    if (ab < 1e-300) return std::numeric_limits<double>::infinity();
    return std::max(std::abs(lk.dot(p.e0[k])), std::abs(lk.dot(p.e1[k]))) / ab;
  }
  // Signed distances of every view's endpoints to the line transferred from the two other views,
  // each weighted by the sine of those views' planes (first-order conditioning: a transfer's
  // error grows like 1 / sine), for LM: r = (view 0: e0, e1, view 1: e0, e1, view 2: e0, e1).
  // A degenerate transfer gives zeros.
  void weighted_transfers(const Prepared& p, double* r) const {
    std::array<Vec3, 3> n;
    std::array<double, 3> delta;
    for (int v = 0; v < 3; ++v) {
      n[v] = R[v].transpose() * p.l[v];
      delta[v] = -p.l[v].dot(t[v]);
    }
    for (int k = 0; k < 3; ++k) {
      r[2 * k] = r[2 * k + 1] = 0.0;
      const int i = k == 0 ? 1 : 0, j = k == 2 ? 1 : 2;
      const Vec3 D = n[i].cross(n[j]);
      const double dd = D.squaredNorm();
      if (dd < 1e-30) continue;
      const Vec3 X0 = (delta[i] * n[j].cross(D) + delta[j] * D.cross(n[i])) / dd;
      Vec3 lk = (R[k] * X0 + t[k]).cross(R[k] * D);
      const double ab = std::sqrt(lk.x() * lk.x() + lk.y() * lk.y());
      if (ab < 1e-300) continue;
      // Sign fixed by the observed line so that the residual is continuous in the parameters.
      if (lk.x() * p.l[k].x() + lk.y() * p.l[k].y() < 0) lk = -lk;
      const double w = std::sqrt(dd) / ab;
      r[2 * k] = w * lk.dot(p.e0[k]);
      r[2 * k + 1] = w * lk.dot(p.e1[k]);
    }
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

// Segment check on the 3D line. The line is triangulated from the best-conditioned pair of
// back-projected planes; each segment endpoint is mapped to its point on that line (the line cut
// by the plane through the endpoint's ray and the image line's normal). The three segments must
// overlap along the line pairwise (margin: 10 % of the longer one + `margin_px` converted with
// each view's scale), and the depths of the six points in their own cameras tell which side of
// the cameras the line is on: +1 all in front, -1 all behind (in front for the model with t
// negated, which the line constraints cannot tell apart), 0 mixed. Unlike the epipolar-line
// overlap, this stays defined when two views' planes coincide (a 3D line in an epipolar plane of
// that pair): then the third view's segment is consistent with *some* 3D line in that plane
// whatever it is, and only its extent and depth can expose a wrong match.
struct LineSupport {
  bool judged = false;  // false: no stable 3D line (all plane pairs within `min_plane_sine`)
  bool overlap = true;
  int side = 0;
};

LineSupport line_support(const Prepared& p, const Scorer& sc, double margin_px, double focal_px,
                         double min_plane_sine) {
  LineSupport out;
  std::array<Vec3, 3> n;
  std::array<double, 3> delta;
  for (int v = 0; v < 3; ++v) {
    n[v] = sc.R[v].transpose() * p.l[v];
    delta[v] = -p.l[v].dot(sc.t[v]);
  }
  int bi = 0, bj = 1;
  double best = -1.0;
  for (const auto& [i, j] : std::array<std::pair<int, int>, 3>{{{0, 1}, {0, 2}, {1, 2}}}) {
    const double c = n[i].cross(n[j]).squaredNorm();
    if (c > best) best = c, bi = i, bj = j;
  }
  // All three planes nearly coincide: the 3D line (and its depth) is undetermined. A wrong
  // segment in one view would make its plane differ from the two others, so this is no outlier.
  if (best < min_plane_sine * min_plane_sine) return out;
  const Vec3 D = n[bi].cross(n[bj]);
  const Vec3 X0 = (delta[bi] * n[bj].cross(D) + delta[bj] * D.cross(n[bi])) / D.squaredNorm();
  // X(s) = X0 + s D in view 0; the same s in every view.
  std::array<std::array<double, 2>, 3> s{};
  std::array<double, 3> s_per_px{};
  int front = 0;
  for (int v = 0; v < 3; ++v) {
    const Vec3 P = sc.R[v] * X0 + sc.t[v], Dv = sc.R[v] * D;
    const Vec3 normal_dir(p.l[v].x(), p.l[v].y(), 0.0);
    const std::array<const Vec3*, 2> ends{&p.e0[v], &p.e1[v]};
    for (int k = 0; k < 2; ++k) {
      const Vec3 m = ends[k]->cross(normal_dir);
      const double den = m.dot(Dv);
      if (std::abs(den) < 1e-6 * m.norm() * Dv.norm()) return out;  // line along the ray
      s[v][k] = -m.dot(P) / den;
      if ((P + s[v][k] * Dv).z() > 0.0) ++front;
    }
    const double len_px =
        focal_px * std::hypot(p.e1[v].x() - p.e0[v].x(), p.e1[v].y() - p.e0[v].y());
    if (!(len_px > 0.0)) return out;
    s_per_px[v] = std::abs(s[v][1] - s[v][0]) / len_px;
  }
  out.judged = true;
  out.side = front == 6 ? 1 : (front == 0 ? -1 : 0);
  for (int a = 0; a < 3; ++a) {
    for (int b = a + 1; b < 3; ++b) {
      const double lo_a = std::min(s[a][0], s[a][1]), hi_a = std::max(s[a][0], s[a][1]);
      const double lo_b = std::min(s[b][0], s[b][1]), hi_b = std::max(s[b][0], s[b][1]);
      const double mg = 0.1 * std::max(hi_a - lo_a, hi_b - lo_b) +
                        margin_px * std::max(s_per_px[a], s_per_px[b]);
      if (hi_a < lo_b - mg || hi_b < lo_a - mg) out.overlap = false;
    }
  }
  return out;
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
    const double ab = std::sqrt(lk.x() * lk.x() + lk.y() * lk.y());
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

// Levenberg-Marquardt on the weighted transfer residuals of the given triplets, over (yaw1, yaw2,
// tx1, tz1, tx2, tz2); the scale of t is a gauge freedom absorbed by the damping and removed by
// renormalising.
void lm_refine(const std::vector<Prepared>& prep, const std::vector<int>& idx, Model& m,
               int iterations, double scale) {
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
    for (size_t q = 0; q < idx.size(); ++q)
      sc.weighted_transfers(prep[static_cast<size_t>(idx[q])], r.data() + 6 * q);
  };
  // Cauchy loss of scale `scale` (IRLS weights in the normal equations): the triplets selected
  // around a rough model can still hold a few outliers, which a squared loss lets pull the model.
  const double s2 = scale * scale;
  auto robust_cost = [&](const Eigen::VectorXd& r) {
    return (r.array().square() / s2).log1p().sum();
  };
  Eigen::VectorXd r0, r1;
  residuals(x, r0);
  double cost = robust_cost(r0);
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
    const Eigen::VectorXd w = (1.0 + r0.array().square() / s2).inverse();
    const Eigen::Matrix<double, 6, 6> H = J.transpose() * w.asDiagonal() * J;
    const Vec6 g = J.transpose() * (w.array() * r0.array()).matrix();
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
      const double c1 = robust_cost(r1);
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

// The triplets of one call and the scoring shared by the prior and the unseeded searches.
struct Problem {
  std::vector<Prepared> prep;
  std::vector<int> rot_idx;  // triplets with rotation leverage
  int n = 0;
  double thr = 0.0;          // scoring threshold, normalised units
  double focal_px = 0.0;
  const PlanarTrifocalOptions* options = nullptr;

  bool has_leverage(int i) const {
    return prep[static_cast<size_t>(i)].leverage >= options->min_rotation_leverage;
  }

  // MSAC cost; optionally the inlier count and the inliers with rotation leverage.
  double cost_of(const Model& m, int* inliers, int* rot_inliers) const {
    const Scorer sc(m);
    const double thr2 = thr * thr;
    double cost = 0.0;
    int cnt = 0, rcnt = 0;
    for (int i = 0; i < n; ++i) {
      const double r = sc.residual(prep[static_cast<size_t>(i)], thr);
      if (r <= thr) {
        cost += r * r;
        ++cnt;
        if (has_leverage(i)) ++rcnt;
      } else {
        cost += thr2;
      }
    }
    if (inliers) *inliers = cnt;
    if (rot_inliers) *rot_inliers = rcnt;
    return cost;
  }

  std::vector<int> inliers_of(const Model& m, double threshold) const {
    const Scorer sc(m);
    std::vector<int> idx;
    for (int i = 0; i < n; ++i)
      if (sc.residual(prep[static_cast<size_t>(i)], threshold) <= threshold) idx.push_back(i);
    return idx;
  }

  // Triplets for the LM: all six weighted transfer residuals within `threshold`, and segments
  // that overlap on one side of the cameras when the 3D line is defined (either side: the sign of
  // t is chosen at the end). The best-transfer inliers also hold outliers whose other transfers
  // are far off, and wrong segments in a view whose two partners' planes nearly coincide (all
  // transfers small); either kind holds the LM at a wrong fixed point, even on noiseless data.
  std::vector<int> consistent_of(const Model& m, double threshold) const {
    const Scorer sc(m);
    std::vector<int> idx;
    std::array<double, 6> r{};
    for (int i = 0; i < n; ++i) {
      const Prepared& p = prep[static_cast<size_t>(i)];
      sc.weighted_transfers(p, r.data());
      if (std::any_of(r.begin(), r.end(), [&](double v) { return std::abs(v) > threshold; }))
        continue;
      const LineSupport s = line_support(p, sc, options->overlap_margin_px, focal_px,
                                         options->overlap_min_plane_sine);
      if (s.judged && !(s.overlap && s.side != 0)) continue;
      idx.push_back(i);
    }
    return idx;
  }

  // Local optimisation (LO-RANSAC): LM on the geometric residuals of the model's consistent
  // triplets, twice (the set grows after the first).
  Model local_optimisation(const Model& m) const {
    Model lo = m;
    for (int rep = 0; rep < 2; ++rep)
      lm_refine(prep, consistent_of(lo, 2.0 * thr), lo, options->lo_iterations, thr);
    return lo;
  }
};

// A scored model.
struct Incumbent {
  Model model;
  double cost = std::numeric_limits<double>::infinity();
  int inliers = 0;
  int rot_inliers = 0;
  bool from_prior = false;
  /// Takes (m, cost, ...) when it costs less than the incumbent; returns whether it did.
  bool offer(const Model& m, double m_cost, int m_inliers, int m_rot_inliers) {
    if (!(m_cost < cost)) return false;
    model = m;
    cost = m_cost;
    inliers = m_inliers;
    rot_inliers = m_rot_inliers;
    return true;
  }
};

// Samples needed for `confidence` when a clean sample has probability p.
int samples_needed(double p, double confidence) {
  const double q = std::clamp(p, 1e-12, 1.0 - 1e-12);
  const double needed = std::log(1.0 - confidence) / std::log(1.0 - q);
  return needed > 1e9 ? 1000000000 : static_cast<int>(std::ceil(needed));
}

// Search with a prior: the yaws and the directions d_1, d_2 of t_1, t_2 are given; one triplet's
// translation equation fixes the split phi of the scale (t_1 = cos(phi) d_1, t_2 = sin(phi) d_2).
// The best single-triplet model is then refined over all 5 DOF (local optimisation).
std::optional<Incumbent> prior_search(const Problem& pb, const PlanarMotionPrior& prior,
                                       std::mt19937_64& rng, PlanarTrifocalResult& result) {
  const PlanarTrifocalOptions& o = *pb.options;
  const Mat3 R1 = rot_y(prior.view1.yaw_rad), R2 = rot_y(prior.view2.yaw_rad);
  const Eigen::Vector2d d1 =
      Eigen::Vector2d(prior.view1.t_dir_xz[0], prior.view1.t_dir_xz[1]).normalized();
  const Eigen::Vector2d d2 =
      Eigen::Vector2d(prior.view2.t_dir_xz[0], prior.view2.t_dir_xz[1]).normalized();
  if (!d1.allFinite() || !d2.allFinite()) return std::nullopt;
  // phi of every triplet: its translation row restricted to the prior reads
  // cos(phi) a + sin(phi) b = 0. A phi outside [0, pi/2] contradicts the prior's signs.
  std::vector<double> phis;
  phis.reserve(static_cast<size_t>(pb.n));
  for (int i = 0; i < pb.n; ++i) {
    Eigen::RowVector4d row;
    if (!translation_row(pb.prep[static_cast<size_t>(i)], R1, R2, row)) continue;
    const Eigen::Vector2d v(row(0) * d1(0) + row(1) * d1(1), row(2) * d2(0) + row(3) * d2(1));
    if (v.norm() < 1e-9) continue;  // no scale information in this triplet
    double c = v(1), s = -v(0);     // (cos, sin) of phi with cos >= 0
    if (c < 0.0) c = -c, s = -s;
    const double phi = std::atan2(s, c);
    if (phi >= 0.0) phis.push_back(phi);
  }
  if (phis.empty()) return std::nullopt;
  auto model_of = [&](double phi) {
    Model m;
    m.yaw1 = prior.view1.yaw_rad;
    m.yaw2 = prior.view2.yaw_rad;
    m.t << std::cos(phi) * d1, std::sin(phi) * d2;
    return m;
  };
  const int np = static_cast<int>(phis.size());
  std::uniform_int_distribution<int> pick(0, np - 1);
  Incumbent inc;
  inc.from_prior = true;
  int max_iter = std::min(o.max_iterations, std::max(o.prior_min_samples, np));
  for (int it = 0; it < max_iter; ++it) {
    ++result.iterations;
    ++result.hypotheses;
    const double phi = phis[static_cast<size_t>(pick(rng))];
    const Model m = model_of(phi);
    int inl = 0, rinl = 0;
    const double cost = pb.cost_of(m, &inl, &rinl);
    if (inc.offer(m, cost, inl, rinl)) {
      const int wanted = std::max(o.prior_min_samples,
                                  samples_needed(static_cast<double>(inl) / pb.n, o.confidence));
      max_iter = std::min(max_iter, wanted);
    }
  }
  const Model lo = pb.local_optimisation(inc.model);
  int inl = 0, rinl = 0;
  const double lo_cost = pb.cost_of(lo, &inl, &rinl);
  inc.offer(lo, lo_cost, inl, rinl);
  return inc;
}

// Unseeded search: 3-triplet samples (two with rotation leverage give the yaws, the third the
// translation). After a prior these are challengers of the prior's model: adaptive stopping from
// its support, at most `prior_max_challengers` samples and no minimum.
void sampled_search(const Problem& pb, std::mt19937_64& rng, PlanarTrifocalResult& result,
                    Incumbent& inc) {
  const PlanarTrifocalOptions& o = *pb.options;
  const int nr = static_cast<int>(pb.rot_idx.size());
  if (nr < 2) return;
  auto wanted_for = [&](const Incumbent& m, int at_least) {
    const double w = static_cast<double>(m.inliers) / pb.n;
    const double wr = static_cast<double>(m.rot_inliers) / nr;
    return std::max(at_least, samples_needed(wr * wr * w, o.confidence));
  };
  const int at_least = inc.from_prior ? 0 : o.min_iterations;
  int max_iter = o.max_iterations;
  if (inc.from_prior) max_iter = std::min(o.prior_max_challengers, wanted_for(inc, at_least));
  int lo_runs = 0;
  std::uniform_int_distribution<int> pick_r(0, nr - 1), pick_all(0, pb.n - 1);
  for (int it = 0; it < max_iter; ++it) {
    ++result.iterations;
    const int a = pb.rot_idx[static_cast<size_t>(pick_r(rng))];
    int b = a;
    for (int guard = 0; b == a && guard < 16; ++guard)
      b = pb.rot_idx[static_cast<size_t>(pick_r(rng))];
    int c = a;
    for (int guard = 0; (c == a || c == b) && guard < 16; ++guard) c = pick_all(rng);
    if (a == b || c == a || c == b) continue;
    const Prepared& pa = pb.prep[static_cast<size_t>(a)];
    const Prepared& pbb = pb.prep[static_cast<size_t>(b)];
    const Prepared& pc = pb.prep[static_cast<size_t>(c)];
    for (const auto& [y1, y2] : solve_yaws(pa.B, pbb.B, o.max_yaw_rad, o.yaw_scan_steps)) {
      Incumbent h;
      h.model.yaw1 = y1;
      h.model.yaw2 = y2;
      const Mat3 R1 = rot_y(y1), R2 = rot_y(y2);
      std::vector<Eigen::RowVector4d> rows(3);
      if (!translation_row(pa, R1, R2, rows[0]) || !translation_row(pbb, R1, R2, rows[1]) ||
          !translation_row(pc, R1, R2, rows[2]) || !translation_from_rows(rows, h.model.t)) {
        continue;
      }
      ++result.hypotheses;
      h.cost = pb.cost_of(h.model, &h.inliers, &h.rot_inliers);
      if (!(h.cost < inc.cost)) continue;
      if (lo_runs < o.max_lo_runs) {
        ++lo_runs;
        Incumbent lo;
        lo.model = pb.local_optimisation(h.model);
        lo.cost = pb.cost_of(lo.model, &lo.inliers, &lo.rot_inliers);
        if (lo.cost < h.cost) h = lo;
      }
      inc = h;
      max_iter = std::min(max_iter, wanted_for(inc, at_least));
    }
  }
}

// The final model and its verified triplets.
struct Verified {
  Model model;
  std::vector<int> inliers;
};

// Final LM on the consistent triplets (kept if it lowers the MSAC cost), then the classification:
// best-transfer residual within 2x the threshold, the per-triplet optimal triangulation check and
// (with check_overlap) the segment check on the 3D line, with the sign of t that puts most lines
// in front of the cameras.
Verified finish(const Problem& pb, const Incumbent& inc) {
  const PlanarTrifocalOptions& o = *pb.options;
  Verified v;
  v.model = inc.model;
  {
    Model m = inc.model;
    lm_refine(pb.prep, pb.consistent_of(inc.model, 2.0 * pb.thr), m, o.lo_iterations, pb.thr);
    if (pb.cost_of(m, nullptr, nullptr) < inc.cost) v.model = m;
  }
  const Scorer sc(v.model);
  std::vector<int> cand;
  std::vector<LineSupport> support;
  for (int i : pb.inliers_of(v.model, 2.0 * pb.thr)) {
    const Prepared& p = pb.prep[static_cast<size_t>(i)];
    if (optimal_residual(p, sc) > o.optimal_threshold_px / pb.focal_px) continue;
    cand.push_back(i);
    if (o.check_overlap)
      support.push_back(
          line_support(p, sc, o.overlap_margin_px, pb.focal_px, o.overlap_min_plane_sine));
  }
  if (!o.check_overlap) {
    v.inliers = std::move(cand);
    return v;
  }
  int front = 0, behind = 0;
  for (const LineSupport& s : support) {
    if (s.judged && s.side > 0) ++front;
    if (s.judged && s.side < 0) ++behind;
  }
  const int side = front >= behind ? 1 : -1;
  if (side < 0) v.model.t = -v.model.t;
  for (size_t q = 0; q < cand.size(); ++q) {
    const LineSupport& s = support[q];
    if (s.judged && !(s.overlap && s.side == side)) continue;
    v.inliers.push_back(cand[q]);
  }
  return v;
}

PlanarTrifocalResult verify(const std::vector<LineTriplet>& triplets, double focal_px,
                            const PlanarTrifocalOptions& options, const PlanarMotionPrior* prior) {
  if (!(focal_px > 0.0)) throw std::invalid_argument("verify_line_triplets: focal_px must be > 0");
  const auto errors = options.validate();
  if (!errors.empty()) throw std::invalid_argument("verify_line_triplets: " + errors.front());

  PlanarTrifocalResult result;
  Problem pb;
  pb.n = static_cast<int>(triplets.size());
  pb.options = &options;
  pb.thr = options.threshold_px / focal_px;
  pb.focal_px = focal_px;
  if (pb.n < 3) return result;
  pb.prep.reserve(triplets.size());
  for (int i = 0; i < pb.n; ++i) {
    pb.prep.push_back(prepare(triplets[static_cast<size_t>(i)]));
    if (pb.has_leverage(i)) pb.rot_idx.push_back(i);
  }

  std::mt19937_64 rng(options.seed);
  std::optional<Incumbent> prior_model;
  if (prior) prior_model = prior_search(pb, *prior, rng, result);
  Incumbent inc = prior_model.value_or(Incumbent{});
  sampled_search(pb, rng, result, inc);
  if (inc.inliers < 3) return result;

  Verified v = finish(pb, inc);
  result.from_prior = inc.from_prior;
  if (prior_model && !inc.from_prior && prior_model->inliers >= 3) {
    // A challenger beat the prior's model on the MSAC cost. With many ill-conditioned triplets
    // (short baselines) a wrong model can do that and even verify about as many triplets, while
    // the prior also has the verified points behind it: the challenger must verify clearly more.
    Verified vs = finish(pb, *prior_model);
    const double needed = options.prior_replace_ratio * static_cast<double>(vs.inliers.size());
    if (static_cast<double>(v.inliers.size()) < needed) {
      v = std::move(vs);
      result.from_prior = true;
    }
  }
  result.inliers = std::move(v.inliers);
  result.motion.yaw_rad = {0.0, v.model.yaw1, v.model.yaw2};
  result.motion.t_xz = {cv::Vec2d(0, 0), cv::Vec2d(v.model.t(0), v.model.t(1)),
                        cv::Vec2d(v.model.t(2), v.model.t(3))};
  result.found = static_cast<int>(result.inliers.size()) >= options.min_inliers;
  if (!result.found) result.inliers.clear();
  return result;
}

// Planar refinement of a prior on its point pairs: E's five DOF absorb noise that the planar
// motion (yaw and direction of t: two DOF) cannot, so the yaw and the direction are re-estimated
// by Gauss-Newton on the Sampson distances (px) of x_i^T [t_i]x R_y(yaw) x_0 = 0 (the pairs are
// verified inliers; left-over outliers are down-weighted by a Cauchy kernel of scale 1 px).
void refine_planar_pair(const std::vector<cv::Point2d>& xi, const std::vector<cv::Point2d>& x0,
                        double focal_px, PlanarViewPrior& s) {
  const auto n = static_cast<Eigen::Index>(xi.size());
  auto residuals = [&](const Eigen::Vector2d& q, Eigen::VectorXd& r) {
    const Vec3 t(std::sin(q(1)), 0.0, std::cos(q(1)));
    Mat3 tx;
    tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
    const Mat3 E = tx * rot_y(q(0));
    r.resize(n);
    for (Eigen::Index k = 0; k < n; ++k) {
      const Vec3 a(x0[static_cast<size_t>(k)].x, x0[static_cast<size_t>(k)].y, 1.0);
      const Vec3 b(xi[static_cast<size_t>(k)].x, xi[static_cast<size_t>(k)].y, 1.0);
      const Vec3 Ea = E * a, Etb = E.transpose() * b;
      const double den = Ea.x() * Ea.x() + Ea.y() * Ea.y() + Etb.x() * Etb.x() + Etb.y() * Etb.y();
      r(k) = den > 0 ? b.dot(Ea) / std::sqrt(den) * focal_px : 0.0;
    }
  };
  Eigen::Vector2d q(s.yaw_rad, std::atan2(s.t_dir_xz[0], s.t_dir_xz[1]));
  Eigen::VectorXd r0, r1;
  residuals(q, r0);
  Eigen::MatrixXd J(n, 2);
  for (int it = 0; it < 10; ++it) {
    for (int c = 0; c < 2; ++c) {
      Eigen::Vector2d qp = q;
      qp(c) += 1e-7;
      residuals(qp, r1);
      J.col(c) = (r1 - r0) / 1e-7;
    }
    const Eigen::VectorXd w = (1.0 + r0.array().square()).inverse();
    const Eigen::Matrix2d H = J.transpose() * w.asDiagonal() * J;
    const Eigen::Vector2d g = J.transpose() * (w.array() * r0.array()).matrix();
    const Eigen::Vector2d step = H.ldlt().solve(-g);
    if (!step.allFinite()) break;
    q += step;
    residuals(q, r0);
    if (step.norm() < 1e-9) break;
  }
  if (!q.allFinite()) return;
  s.yaw_rad = q(0);
  s.t_dir_xz = cv::Vec2d(std::sin(q(1)), std::cos(q(1)));
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
  if (!(overlap_min_plane_sine >= 0.0 && overlap_min_plane_sine < 1.0))
    bad("overlap_min_plane_sine", overlap_min_plane_sine, "[0, 1)");
  if (!(min_iterations >= 1 && min_iterations <= max_iterations))
    bad("min_iterations", min_iterations, "[1, max_iterations]");
  if (!(optimal_threshold_px > 0.0)) bad("optimal_threshold_px", optimal_threshold_px, "(0, inf)");
  if (!(max_lo_runs >= 0 && max_lo_runs <= 1000)) bad("max_lo_runs", max_lo_runs, "[0, 1000]");
  if (!(lo_iterations >= 0 && lo_iterations <= 100)) bad("lo_iterations", lo_iterations, "[0, 100]");
  if (!(yaw_scan_steps >= 4 && yaw_scan_steps <= 10000)) bad("yaw_scan_steps", yaw_scan_steps, "[4, 10000]");
  if (!(prior_min_points >= 5)) bad("prior_min_points", prior_min_points, "[5, inf)");
  if (!(prior_max_tilt_rad >= 0.0 && prior_max_tilt_rad < M_PI_2))
    bad("prior_max_tilt_rad", prior_max_tilt_rad, "[0, pi/2)");
  if (!(prior_max_t_y >= 0.0 && prior_max_t_y <= 1.0))
    bad("prior_max_t_y", prior_max_t_y, "[0, 1]");
  if (!(prior_min_parallax_px >= 0.0))
    bad("prior_min_parallax_px", prior_min_parallax_px, "[0, inf)");
  if (!(prior_min_cheirality > 0.5 && prior_min_cheirality <= 1.0))
    bad("prior_min_cheirality", prior_min_cheirality, "(0.5, 1]");
  if (!(prior_min_samples >= 1 && prior_min_samples <= max_iterations))
    bad("prior_min_samples", prior_min_samples, "[1, max_iterations]");
  if (!(prior_replace_ratio >= 1.0)) bad("prior_replace_ratio", prior_replace_ratio, "[1, inf)");
  if (!(prior_max_challengers >= 0 && prior_max_challengers <= max_iterations))
    bad("prior_max_challengers", prior_max_challengers, "[0, max_iterations]");
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
  return verify(triplets, focal_px, options, nullptr);
}

PlanarTrifocalResult verify_line_triplets(const std::vector<LineTriplet>& triplets, double focal_px,
                                          const PlanarTrifocalOptions& options,
                                          const PlanarMotionPrior& prior) {
  return verify(triplets, focal_px, options, &prior);
}

std::optional<PlanarViewPrior> planar_view_prior(const cv::Matx33d& E_0_i,
                                                 const std::vector<cv::Point2d>& view_i_norm,
                                                 const std::vector<cv::Point2d>& view_0_norm,
                                                 double focal_px,
                                                 const PlanarTrifocalOptions& options) {
  if (view_i_norm.size() != view_0_norm.size())
    throw std::invalid_argument("planar_view_prior: " + std::to_string(view_i_norm.size()) +
                                " points in view i, " + std::to_string(view_0_norm.size()) +
                                " in view 0");
  if (!(focal_px > 0.0)) throw std::invalid_argument("planar_view_prior: focal_px must be > 0");
  const auto errors = options.validate();
  if (!errors.empty()) throw std::invalid_argument("planar_view_prior: " + errors.front());
  const int n = static_cast<int>(view_i_norm.size());
  if (n < options.prior_min_points) return std::nullopt;
  // E's convention X_0 = R X_i + t  <=>  the trifocal model's X_i = R^T X_0 - R^T t.
  const RelativePose pose = recover_relative_pose(E_0_i, view_i_norm, view_0_norm);
  if (pose.in_front < options.prior_min_cheirality * n) return std::nullopt;
  Mat3 R;
  Vec3 t;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R(r, c) = pose.R_b_a(r, c);
    t(r) = pose.t_b_a[r];
  }
  const Mat3 Ri = R.transpose();
  const Vec3 ti = -Ri * t;
  const double yaw = std::atan2(Ri(0, 2), Ri(0, 0));
  // Rotation off the vertical axis: the angle of Ri R_y(yaw)^T.
  const double cos_tilt =
      std::clamp(0.5 * ((Ri * rot_y(yaw).transpose()).trace() - 1.0), -1.0, 1.0);
  if (std::acos(cos_tilt) > options.prior_max_tilt_rad) return std::nullopt;
  if (std::abs(ti.y()) > options.prior_max_t_y * ti.norm()) return std::nullopt;
  // Parallax after derotation: with too little of it the direction of t is noise.
  std::vector<double> parallax;
  parallax.reserve(static_cast<size_t>(n));
  for (int k = 0; k < n; ++k) {
    const cv::Point2d& pi = view_i_norm[static_cast<size_t>(k)];
    const cv::Point2d& p0 = view_0_norm[static_cast<size_t>(k)];
    const Vec3 xi(pi.x, pi.y, 1.0), x0(p0.x, p0.y, 1.0);
    const Vec3 r = R * xi;
    parallax.push_back(std::atan2(r.cross(x0).norm(), r.dot(x0)) * focal_px);
  }
  std::nth_element(parallax.begin(), parallax.begin() + n / 2, parallax.end());
  if (parallax[static_cast<size_t>(n / 2)] < options.prior_min_parallax_px) return std::nullopt;
  const double txz = std::hypot(ti.x(), ti.z());
  if (!(txz > 0.0)) return std::nullopt;
  PlanarViewPrior s;
  s.yaw_rad = yaw;
  s.t_dir_xz = cv::Vec2d(ti.x() / txz, ti.z() / txz);
  refine_planar_pair(view_i_norm, view_0_norm, focal_px, s);
  return s;
}

}  // namespace pepper::core::geometry
