// Random SPD systems with the shape of a windowed photometric bundle adjustment, for the sparse solver's
// tests (and the same generator as bench/solver_bench.cpp).
//
// k keyframes x 8 parameters (pose 6 + affine brightness 2), then n points x 1 (inverse depth). Each
// point lives in a host keyframe and is observed in 1-4 other keyframes (2-5 keyframes in all); each
// observation gives `rows_per_obs` residuals depending on host, target and the point, as in DSO. So H
// has: camera blocks coupling co-observing keyframes, 8x1 camera-point blocks for host and targets,
// and a diagonal point block. H = J'J + a weak camera prior (fixes the gauge) + damping.
#pragma once
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace rsvio::test {

struct BaSystem {
  int k = 0;  // keyframes
  int n = 0;  // points
  Eigen::SparseMatrix<double> H;  // (8k + n) square, full symmetric storage
  Eigen::VectorXd b;
  int cams() const { return 8 * k; }
};

inline BaSystem makeBaSystem(int k, int n, unsigned seed, int rows_per_obs = 2, double damping = 1e-3) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  std::uniform_int_distribution<int> n_obs(2, 5);
  std::uniform_int_distribution<int> pick(0, k - 1);
  BaSystem s;
  s.k = k;
  s.n = n;
  const int nc = 8 * k;
  const int dim = nc + n;
  std::vector<Eigen::Triplet<double>> jt;
  int row = 0;
  for (int p = 0; p < n; ++p) {
    // Points mostly observed by keyframes near their host, as in a sliding window.
    const int host = pick(rng);
    std::vector<int> kfs = {host};
    const int m = std::min(n_obs(rng), k);
    for (int tries = 0; static_cast<int>(kfs.size()) < m && tries < 100; ++tries) {
      const int t = std::clamp(host + static_cast<int>(std::lround(3.0 * g(rng))), 0, k - 1);
      if (std::find(kfs.begin(), kfs.end(), t) == kfs.end()) kfs.push_back(t);
    }
    const double d_scale = 5.0 + 20.0 * std::abs(g(rng));  // d r / d idepth is large and varies
    for (size_t o = 1; o < kfs.size(); ++o) {
      for (int r = 0; r < rows_per_obs; ++r, ++row) {
        for (int c = 0; c < 8; ++c) {
          jt.emplace_back(row, 8 * host + c, g(rng));
          jt.emplace_back(row, 8 * kfs[o] + c, g(rng));
        }
        jt.emplace_back(row, nc + p, d_scale * g(rng));
      }
    }
  }
  Eigen::SparseMatrix<double> J(row, dim);
  J.setFromTriplets(jt.begin(), jt.end());
  s.H = Eigen::SparseMatrix<double>(J.transpose() * J);
  // Gauge prior on the first keyframe, damping on the diagonal (as Levenberg-Marquardt adds it).
  for (int c = 0; c < 8; ++c) s.H.coeffRef(c, c) += 1.0;
  for (int i = 0; i < dim; ++i) s.H.coeffRef(i, i) += damping * (1.0 + s.H.coeff(i, i));
  s.H.makeCompressed();
  s.b.resize(dim);
  for (int i = 0; i < dim; ++i) s.b[i] = g(rng);
  return s;
}

// Reference: the Schur complement S = Hcc - Hcp Hpp^-1 Hpc built explicitly (Hpp is diagonal).
struct SchurSystem {
  Eigen::MatrixXd S;
  Eigen::VectorXd bc;
  Eigen::MatrixXd Hcp;  // dense nc x n
  Eigen::VectorXd hpp, bp;
};

inline SchurSystem schurReduce(const BaSystem& s) {
  const int nc = s.cams();
  SchurSystem r;
  const Eigen::MatrixXd Hd(s.H);
  r.Hcp = Hd.block(0, nc, nc, s.n);
  r.hpp = Hd.diagonal().tail(s.n);
  r.bp = s.b.tail(s.n);
  const Eigen::MatrixXd W = r.Hcp * r.hpp.cwiseInverse().asDiagonal();
  r.S = Hd.topLeftCorner(nc, nc) - W * r.Hcp.transpose();
  r.bc = s.b.head(nc) - W * r.bp;
  return r;
}

// Point part by back-substitution: xp = Hpp^-1 (bp - Hpc xc).
inline Eigen::VectorXd backSubstitute(const SchurSystem& r, const Eigen::VectorXd& xc) {
  return (r.bp - r.Hcp.transpose() * xc).cwiseQuotient(r.hpp);
}

}  // namespace rsvio::test
