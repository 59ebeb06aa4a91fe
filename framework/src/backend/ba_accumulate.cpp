// Bundle adjustment, accumulation: from the observations evaluated by ba_linearize.cpp
// (Linearization::obs), each point's Schur data (H_pp, b_p, its couplings to the host and target
// blocks) and the camera blocks, in 16 fixed chunks of points whose sums are added in order (the same
// bits for 1 and 2 threads). Global shutter: accumulateChunkGlobal; rolling shutter:
// accumulateChunkRolling (default) or accumulateChunk (the explicit reference, and the points-only pass).
#include <algorithm>
#include <cmath>

#include "ba_internal.h"

namespace rsvio {
namespace ba {

namespace {

// The chunk's points [begin, end), with its line-delay sums, energies and counters reset.
std::pair<int, int> startChunk(const BundleAdjuster::Impl& m, ChunkSums& cs, int chunk) {
  cs.Hll = cs.bl = 0.0;
  cs.energy = cs.energy_in = 0.0;
  cs.num_in = cs.num_oob = cs.num_outlier = 0;
  const int np = static_cast<int>(m.points.size());
  return {static_cast<int>(static_cast<long>(np) * chunk / kPointChunks),
          static_cast<int>(static_cast<long>(np) * (chunk + 1) / kPointChunks)};
}

// Counts one observation into the chunk's energies and counters; true for an inlier (it has blocks).
bool countObservation(ChunkSums& cs, const ObsLin& ol) {
  cs.energy += ol.energy;
  if (ol.state == ObsState::kOob) ++cs.num_oob;
  if (ol.state == ObsState::kOutlier) ++cs.num_outlier;
  if (ol.state != ObsState::kIn) return false;
  ++cs.num_in;
  cs.energy_in += ol.energy;
  return true;
}

// One point's entries in the Schur arena (Linearization::blk_ids, hpc): its host block first, cleared
// here, then one block per inlier observation's target, in observation order; done() stores the count.
template <int KD>
struct PointArena {
  Linearization& L;
  const int point, ab;
  int nb = 1;
  Eigen::Map<Eigen::Matrix<double, KD, 1>> host;
  PointArena(Linearization& lin, int i, int host_index)
      : L(lin), point(i), ab(lin.blk_begin[static_cast<size_t>(i)]),
        host(lin.hpc.data() + static_cast<size_t>(ab) * KD) {
    L.blk_ids[static_cast<size_t>(ab)] = host_index;
    host.setZero();
  }
  // The next target's block (to be written whole).
  Eigen::Map<Eigen::Matrix<double, KD, 1>> target(int target_index) {
    L.blk_ids[static_cast<size_t>(ab + nb)] = target_index;
    return Eigen::Map<Eigen::Matrix<double, KD, 1>>(L.hpc.data() + static_cast<size_t>(ab + nb++) * KD);
  }
  void done() { L.blk_count[static_cast<size_t>(point)] = nb; }
};

// A point's own Schur sums: H_pp, b_p and its line-delay coupling h_pl (zero unless estimated).
struct PointSums {
  double Hpp = 0.0, bp = 0.0, hpl = 0.0;
};

// The chunk's points [begin, end), each with its arena and sums: visit(ol, hb, tb, arena, sums) for each
// observation that counts as an inlier (host block hb, target block tb), then the sums are stored and
// the arena closed. All three accumulations below walk the points this way.
template <int KD, class Visit>
void forEachInlier(const BundleAdjuster::Impl& m, Linearization& L, ChunkSums& cs, int begin, int end,
                   Visit&& visit) {
  for (int i = begin; i < end; ++i) {
    const ActivePoint& p = *m.points[static_cast<size_t>(i)];
    const int hb = p.host->index;
    PointSums sums;
    PointArena<KD> arena(L, i, hb);
    for (int r = m.point_obs_begin[static_cast<size_t>(i)]; r < m.point_obs_begin[static_cast<size_t>(i) + 1]; ++r) {
      const ObsLin& ol = L.obs[static_cast<size_t>(r)];
      if (!countObservation(cs, ol)) continue;
      const int tb = p.obs[static_cast<size_t>(m.obs_refs[static_cast<size_t>(r)].obs)].target->index;
      visit(ol, hb, tb, arena, sums);
    }
    L.Hpp[static_cast<size_t>(i)] = sums.Hpp;
    L.bp[static_cast<size_t>(i)] = sums.bp;
    L.hpl[static_cast<size_t>(i)] = sums.hpl;
    arena.done();
  }
}

// One observation's compact products over its NG geometric columns G (2 x NG, gathered by the caller;
// the four affine columns are selectors and need no products): MG = M_uu G (form), then the upper
// triangle (a <= c) of H_gg = G^T M_uu G, H_ga = G^T M_ua and b_g = -G^T g_uv (formUpper).
template <int NG>
struct CompactProducts {
  Eigen::Matrix<double, 2, NG> G, MG;
  Eigen::Matrix<double, NG, NG> Hgg;
  Eigen::Matrix<double, NG, 4> Hga;
  Eigen::Matrix<double, NG, 1> bg;
  void form(const ObsLin& ol) { MG.noalias() = ol.M.template topLeftCorner<2, 2>().lazyProduct(G); }
  void formGradient(const ObsLin& ol) { bg.noalias() = -G.transpose() * ol.g.template head<2>(); }
  void formUpper(const ObsLin& ol) {
    for (int a = 0; a < NG; ++a) {
      const double g0 = G(0, a), g1 = G(1, a);
      for (int c = a; c < NG; ++c) Hgg(a, c) = g0 * MG(0, c) + g1 * MG(1, c);
    }
    Hga.noalias() = G.transpose().lazyProduct(ol.M.template topRightCorner<2, 4>());
    formGradient(ol);
  }
};

// Rolling shutter (global shutter: accumulateChunkGlobal below). Accumulates the points of one chunk:
// their Schur data and the camera blocks. LD: the line delay is
// estimated, one more geometric column (after the inverse depth) whose row goes to ChunkSums::Hl, Hll,
// bl and, for the inverse depth, to Linearization::hpl.
// PO (points only, BundleAdjuster::optimizeDepths): only each point's H_pp and b_p and the counts and
// energies, no camera blocks; the same numbers as the full accumulation (bit-identical).
template <bool LD, bool PO = false>
void accumulateChunk(BundleAdjuster::Impl& m, Linearization& L, int chunk) {
  // Per observation, Hl = Jl^T M Jl over the N = 2 KD + 1 coordinates (host block, target block,
  // inverse depth) is formed compactly: only NG geometric columns (poses, twists when rolling, inverse
  // depth) carry d uv, and the four affine columns are selectors, so
  //   H_gg = G^T M_uu G, H_ga = G^T M_ua, H_aa = M_aa   (G: 2 x NG)
  // and then scattered into the chunk's blocks (about 5x fewer products than the dense 6 x N form).
  constexpr int KD = 14;
  constexpr int N = 2 * KD + 1;
  constexpr int NG0 = 25;  // poses, twists, inverse depth (index NG0 - 1)
  constexpr int NG = NG0 + (LD ? 1 : 0);  // and the line delay (index NG0)
  ChunkSums& cs = m.chunks[static_cast<size_t>(chunk)];
  if constexpr (!PO) {
    cs.H.setZero();
    cs.b.setZero();
    cs.Hl.setZero();
  }
  const auto [begin, end] = startChunk(m, cs, chunk);
  // Where the compact columns go in Hl, and where they come from in ObsLin::Jg.
  int gidx[NG], gsrc[NG];
  {
    int k = 0;
    for (int i = 0; i < 6; ++i, ++k) gidx[k] = StateLayout::kPose + i, gsrc[k] = kColHostPose + i;
    for (int i = 0; i < 6; ++i, ++k) gidx[k] = StateLayout::kTwist + i, gsrc[k] = kColHostTwist + i;
    for (int i = 0; i < 6; ++i, ++k) gidx[k] = KD + StateLayout::kPose + i, gsrc[k] = kColTargetPose + i;
    for (int i = 0; i < 6; ++i, ++k) gidx[k] = KD + StateLayout::kTwist + i, gsrc[k] = kColTargetTwist + i;
    gidx[k] = 2 * KD, gsrc[k] = kColIdepth;
  }
  constexpr int ID = NG0 - 1;  // the inverse depth's compact column
  const int aidx[4] = {StateLayout::kAffine, StateLayout::kAffine + 1, KD + StateLayout::kAffine,
                       KD + StateLayout::kAffine + 1};
  CompactProducts<NG> P;
  const auto& G = P.G;
  const auto& MG = P.MG;
  const auto& Hgg = P.Hgg;
  const auto& Hga = P.Hga;
  const auto& bg = P.bg;
  forEachInlier<KD>(m, L, cs, begin, end,
                    [&](const ObsLin& ol, int hb, int tb, PointArena<KD>& arena, PointSums& ps) {
    for (int k = 0; k < NG0; ++k) P.G.col(k) = ol.Jg.col(gsrc[k]);
    if constexpr (LD) P.G.col(NG0) = ol.Jl;
    P.form(ol);
    if constexpr (PO) {
      // The inverse depth's entries alone, as the triangle below forms them.
      ps.Hpp += G(0, ID) * MG(0, ID) + G(1, ID) * MG(1, ID);
      P.formGradient(ol);
      ps.bp += bg[ID];
      return;
    }
    P.formUpper(ol);  // upper triangle only (a <= c): all the scatter below reads
    // Straight into the chunk's blocks: each entry of the host/target blocks receives the same one
    // addition per observation as through an N x N staging matrix (bit-identical), without writing
    // and re-reading that matrix. Local index x < KD is the host block, KD <= x < 2 KD the target's,
    // 2 KD the inverse depth (kept per point for the Schur complement).
    int row[N];
    for (int x = 0; x < KD; ++x) row[x] = hb * KD + x, row[KD + x] = tb * KD + x;
    double* Hd = cs.H.data();
    const Eigen::Index ld = cs.H.rows();
    double hcol[N];  // column 2 KD of the local Hessian: d^2 E / d rho d x
    // Only the upper triangles of Hgg and of cs.H are formed, and linearizePhotometric mirrors cs.H's
    // to the lower triangle once: half the products and scattered additions of the full form (the
    // largest cost of a rolling-shutter linearisation, profiled in docs/rolling_shutter.md, "Cost").
    for (int a = 0; a < ID; ++a) {
      const int ga = gidx[a];
      const int ra = row[ga];
      for (int c = a; c < ID; ++c) {
        const int rc = row[gidx[c]];
        Hd[static_cast<Eigen::Index>(std::max(ra, rc)) * ld + std::min(ra, rc)] += Hgg(a, c);
      }
      for (int c = 0; c < 4; ++c) {
        const int rc = row[aidx[c]];
        Hd[static_cast<Eigen::Index>(std::max(ra, rc)) * ld + std::min(ra, rc)] += Hga(a, c);
      }
      hcol[ga] = Hgg(a, ID);
      cs.b[ra] += bg[a];
      if constexpr (LD) cs.Hl[ra] += Hgg(a, NG0);
    }
    for (int a = 0; a < 4; ++a) {
      const int ra = row[aidx[a]];
      for (int c = 0; c < 4; ++c) {
        const int rc = row[aidx[c]];
        if (ra <= rc) Hd[static_cast<Eigen::Index>(rc) * ld + ra] += ol.M(2 + a, 2 + c);
      }
      hcol[aidx[a]] = Hga(ID, a);
      cs.b[ra] += -ol.g[2 + a];
      if constexpr (LD) cs.Hl[ra] += Hga(NG0, a);
    }
    ps.Hpp += Hgg(ID, ID);
    ps.bp += bg[ID];
    if constexpr (LD) {
      cs.Hll += Hgg(NG0, NG0);
      cs.bl += bg[NG0];
      ps.hpl += Hgg(ID, NG0);
    }
    arena.host += Eigen::Map<const Eigen::Matrix<double, KD, 1>>(hcol);
    arena.target(tb) = Eigen::Map<const Eigen::Matrix<double, KD, 1>>(hcol + KD);
  });
}

// Rolling shutter, the host pose's blocks from the target pose's. The global-shutter identity below
// holds with twists too: host and target move as T_c_w(t) = exp(xi t) T_c_w^0 (rs_projection.h), so
// the target pixel depends on the two central poses only through T_t^0 (T_h^0)^-1 (the host row's
// exponential multiplies it on the right, the target row's on the left, and the target row's implicit
// solve sees the same product); left perturbations then give, at any row times and line delay,
//   d uv / d host pose = -(d uv / d target pose) A,   A = Adj(T_t^0 (T_h^0)^-1)
// (checked against the projection's own host Jacobian in tests/framework/geometry and, as whole
// systems, against accumulateChunk in BundleAdjustmentGradient). Per observation: the compact
// columns (target pose 0-5, host twist 6-11, target twist 12-17, inverse depth 18, line delay 19 when
// it is estimated): 19 or 20 instead of accumulateChunk's 25 or 26, into the pair's sums over
// y = (target pose, host twist, target twist, line delay, host affine, target affine); once per pair,
// after the chunks (addRollingPairs), the host pose follows with B: y -> z = (host pose, y), J_z = J_y B:
//   H_hh = A^T S_tt A,  H_h,y = -A^T S_t,y,  H_yy = S,  b_h = -A^T b_t.
// Only upper triangles are formed (S and L.Hcc), as in accumulateChunk. The numbers differ from
// accumulateChunk's by rounding only.
template <bool LD>
void accumulateChunkRolling(BundleAdjuster::Impl& m, Linearization& L, int chunk) {
  constexpr int KD = 14;
  constexpr int NY = 23, YL = 18, YA = 19;  // pair sums; the line delay's and the first affine index
  constexpr int ID = 18;                    // the inverse depth's compact column
  constexpr int NG = ID + 1 + (LD ? 1 : 0);
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  ChunkSums& cs = m.chunks[static_cast<size_t>(chunk)];
  const int nk = static_cast<int>(m.window->size());
  cs.pair_Hr.resize(static_cast<size_t>(nk) * nk);
  cs.pair_br.resize(static_cast<size_t>(nk) * nk);
  cs.pair_used.assign(static_cast<size_t>(nk) * nk, 0);
  const auto [begin, end] = startChunk(m, cs, chunk);
  int gsrc[ID];
  for (int i = 0; i < 6; ++i)
    gsrc[i] = kColTargetPose + i, gsrc[6 + i] = kColHostTwist + i, gsrc[12 + i] = kColTargetTwist + i;
  auto yOf = [](int a) { return a < ID ? a : YL; };  // compact column (not the inverse depth) -> y
  CompactProducts<NG> P;
  const auto& Hgg = P.Hgg;
  const auto& Hga = P.Hga;
  const auto& bg = P.bg;
  forEachInlier<KD>(m, L, cs, begin, end,
                    [&](const ObsLin& ol, int hb, int tb, PointArena<KD>& arena, PointSums& ps) {
    for (int k = 0; k < ID; ++k) P.G.col(k) = ol.Jg.col(gsrc[k]);
    P.G.col(ID) = ol.Jg.col(kColIdepth);
    if constexpr (LD) P.G.col(ID + 1) = ol.Jl;
    P.form(ol);
    P.formUpper(ol);  // upper triangle (a <= c)
    const size_t pi = static_cast<size_t>(hb) * nk + tb;
    Eigen::Matrix<double, NY, NY>& S = cs.pair_Hr[pi];
    Eigen::Matrix<double, NY, 1>& sb = cs.pair_br[pi];
    if (!cs.pair_used[pi]) {
      S.setZero();
      sb.setZero();
      cs.pair_used[pi] = 1;
    }
    for (int a = 0; a < NG; ++a) {
      if (a == ID) continue;
      const int ya = yOf(a);  // yOf keeps the order, so S gets its upper triangle
      for (int c = a; c < NG; ++c)
        if (c != ID) S(ya, yOf(c)) += Hgg(a, c);
      for (int c = 0; c < 4; ++c) S(ya, YA + c) += Hga(a, c);
      sb[ya] += bg[a];
    }
    for (int a = 0; a < 4; ++a) {
      for (int c = a; c < 4; ++c) S(YA + a, YA + c) += ol.M(2 + a, 2 + c);
      sb[YA + a] -= ol.g[2 + a];
    }
    ps.Hpp += Hgg(ID, ID);
    ps.bp += bg[ID];
    if constexpr (LD) ps.hpl += Hgg(ID, ID + 1);
    // The point's coupling to its host block (pose through the adjoint, twist, affine (a_h, b_h))
    // and to the target block (pose, twist, affine (a_t, b_t)).
    Eigen::Matrix<double, ID, 1> hc;  // d^2 E / d rho d (target pose, host twist, target twist)
    for (int k = 0; k < ID; ++k) hc[k] = Hgg(k, ID);
    const Eigen::Vector4d ha = Hga.row(ID).transpose();
    const Mat6& A = L.pair_adj[pi];
    arena.host.segment<6>(StateLayout::kPose).noalias() -= A.transpose() * hc.head<6>();
    arena.host.segment<6>(StateLayout::kTwist) += hc.segment<6>(6);
    arena.host.segment<2>(StateLayout::kAffine) += ha.head<2>();
    Eigen::Map<Eigen::Matrix<double, KD, 1>> h_t = arena.target(tb);
    h_t.segment<6>(StateLayout::kPose) = hc.head<6>();
    h_t.segment<6>(StateLayout::kTwist) = hc.segment<6>(12);
    h_t.segment<2>(StateLayout::kAffine) = ha.tail<2>();
  });
}

// accumulateChunkRolling's pair sums, added over the chunks in chunk order, into L.Hcc and L.bc (upper
// triangle; L.Hcc and L.bc zero on entry): once per pair and linearisation, not per chunk, and the
// chunks carry no window-sized blocks to clear and add.
void addRollingPairs(const BundleAdjuster::Impl& m, Linearization& L) {
  constexpr int KD = 14, NY = 23, YL = 18;
  constexpr int NZ = 6 + NY, ZL = 6 + YL;  // z = (host pose, y); the line delay's index in z
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  const int nk = static_cast<int>(m.window->size());
  double* Hd = L.Hcc.data();
  const Eigen::Index ld = L.Hcc.rows();
  Eigen::Matrix<double, NY, NY> S;
  Eigen::Matrix<double, NY, 1> sb;
  Eigen::Matrix<double, NZ, NZ> Z;
  Eigen::Matrix<double, NZ, 1> zb;
  for (int h = 0; h < nk; ++h)
    for (int t = 0; t < nk; ++t) {
      const size_t pi = static_cast<size_t>(h) * nk + t;
      bool used = false;
      for (const ChunkSums& c : m.chunks) {
        if (!c.pair_used[pi]) continue;
        if (used) {
          S += c.pair_Hr[pi];
          sb += c.pair_br[pi];
        } else {
          S = c.pair_Hr[pi];
          sb = c.pair_br[pi];
          used = true;
        }
      }
      if (!used) continue;
      const Eigen::Matrix<double, NY, NY> F = S.selfadjointView<Eigen::Upper>();
      const Mat6& A = L.pair_adj[pi];
      const Eigen::Matrix<double, 6, NY> H_hy = -(A.transpose() * F.topRows<6>());
      Z.topLeftCorner<6, 6>().noalias() = -(H_hy.leftCols<6>() * A);
      Z.topRightCorner<6, NY>() = H_hy;
      Z.bottomRightCorner<NY, NY>() = F;
      zb.head<6>().noalias() = -(A.transpose() * sb.head<6>());
      zb.tail<NY>() = sb;
      const int oh = h * KD, ot = t * KD;
      int zr[NZ];
      for (int k = 0; k < 6; ++k) {
        zr[k] = oh + StateLayout::kPose + k;
        zr[6 + k] = ot + StateLayout::kPose + k;
        zr[12 + k] = oh + StateLayout::kTwist + k;
        zr[18 + k] = ot + StateLayout::kTwist + k;
      }
      zr[ZL] = m.gl;  // the line delay's camera dimension (after every keyframe's), or -1
      for (int k = 0; k < 2; ++k) zr[ZL + 1 + k] = oh + StateLayout::kAffine + k, zr[ZL + 3 + k] = ot + StateLayout::kAffine + k;
      for (int a = 0; a < NZ; ++a) {
        const int ra = zr[a];
        if (ra < 0) continue;
        for (int c = a; c < NZ; ++c) {
          const int rc = zr[c];
          if (rc < 0) continue;
          Hd[static_cast<Eigen::Index>(std::max(ra, rc)) * ld + std::min(ra, rc)] += Z(a, c);
        }
        L.bc[ra] += zb[a];
      }
    }
}

// Global shutter: DSO's factorisation of the pose Jacobians. With left perturbations of T_c_w, a point
// of host h seen in target t has d uv / d host pose = -(d uv / d target pose) Adj(T_t T_h^-1) exactly
// (projectPairGlobal's two Jacobians; checked in the BA gradient tests), so each observation adds only
// the 7 x 7 block of (target pose, inverse depth) and its affine couplings to its pair's sums, and the
// host's blocks follow once per pair and chunk:
//   H_hh = A^T H_tt A,  H_ht = -A^T H_tt,  H_h,x = -A^T H_t,x (x: the affine columns),  b_h = -A^T b_t.
// About a third of the products of the 13-column form it replaced (host pose, target pose, inverse
// depth per observation, docs/performance.md "Host blocks from the target's"); the numbers differ from
// it by rounding only. PO: the points' H_pp and b_p only, the same numbers as the full accumulation.
template <bool PO>
void accumulateChunkGlobal(BundleAdjuster::Impl& m, Linearization& L, int chunk) {
  constexpr int KD = 8;
  using G7 = Eigen::Matrix<double, 2, 7>;
  ChunkSums& cs = m.chunks[static_cast<size_t>(chunk)];
  const int nk = static_cast<int>(m.window->size());
  if constexpr (!PO) {
    cs.H.setZero();
    cs.b.setZero();
    cs.Hl.setZero();
    cs.pair_H.resize(static_cast<size_t>(nk) * nk);
    cs.pair_b.resize(static_cast<size_t>(nk) * nk);
    cs.pair_used.assign(static_cast<size_t>(nk) * nk, 0);
  }
  const auto [begin, end] = startChunk(m, cs, chunk);
  G7 G, MG;
  Eigen::Matrix<double, 7, 7> Hgg;
  Eigen::Matrix<double, 7, 4> Hga;
  Eigen::Matrix<double, 7, 1> bg;
  forEachInlier<KD>(m, L, cs, begin, end,
                    [&](const ObsLin& ol, int hb, int tb, PointArena<KD>& arena, PointSums& ps) {
    G.leftCols<6>() = ol.Jg.block<2, 6>(0, kColTargetPose);
    G.col(6) = ol.Jg.col(kColIdepth);
    MG.noalias() = ol.M.topLeftCorner<2, 2>().lazyProduct(G);
    if constexpr (PO) {
      ps.Hpp += G(0, 6) * MG(0, 6) + G(1, 6) * MG(1, 6);
      ps.bp += -(G(0, 6) * ol.g[0] + G(1, 6) * ol.g[1]);
      return;
    }
    Hgg.noalias() = G.transpose().lazyProduct(MG);
    Hga.noalias() = G.transpose().lazyProduct(ol.M.topRightCorner<2, 4>());
    bg.noalias() = -G.transpose() * ol.g.head<2>();
    const size_t pi = static_cast<size_t>(hb) * nk + tb;
    Eigen::Matrix<double, 10, 10>& S = cs.pair_H[pi];
    Eigen::Matrix<double, 10, 1>& sb = cs.pair_b[pi];
    if (!cs.pair_used[pi]) {
      S.setZero();
      sb.setZero();
      cs.pair_used[pi] = 1;
    }
    S.topLeftCorner<6, 6>() += Hgg.topLeftCorner<6, 6>();
    S.block<6, 4>(0, 6) += Hga.topRows<6>();
    S.bottomRightCorner<4, 4>() += ol.M.bottomRightCorner<4, 4>();
    sb.head<6>() += bg.head<6>();
    sb.tail<4>() -= ol.g.tail<4>();
    ps.Hpp += Hgg(6, 6);
    ps.bp += bg[6];
    // The point's coupling to its host block (pose through the adjoint, affine (a_h, b_h)) and to the
    // target block (pose, affine (a_t, b_t)).
    const Eigen::Matrix<double, 6, 6>& A = L.pair_adj[pi];
    arena.host.head<6>().noalias() -= A.transpose() * Hgg.col(6).head<6>();
    arena.host.tail<2>() += Hga.row(6).head<2>().transpose();
    Eigen::Map<Eigen::Matrix<double, KD, 1>> h_t = arena.target(tb);
    h_t.head<6>() = Hgg.col(6).head<6>();
    h_t.tail<2>() = Hga.row(6).tail<2>().transpose();
  });
  if constexpr (PO) return;
  // The pairs' sums into the chunk's camera blocks (state order per block: pose 0-5, affine 6-7).
  for (int h = 0; h < nk; ++h)
    for (int t = 0; t < nk; ++t) {
      const size_t pi = static_cast<size_t>(h) * nk + t;
      if (!cs.pair_used[pi]) continue;
      const Eigen::Matrix<double, 10, 10>& S = cs.pair_H[pi];
      const Eigen::Matrix<double, 10, 1>& sb = cs.pair_b[pi];
      const Eigen::Matrix<double, 6, 6>& A = L.pair_adj[pi];
      const Eigen::Matrix<double, 6, 6> S_tt = S.topLeftCorner<6, 6>();
      const Eigen::Matrix<double, 6, 6> AtS = A.transpose() * S_tt;  // A^T H_tt
      const int oh = h * KD, ot = t * KD;
      const Eigen::Matrix<double, 6, 6> H_hh = AtS * A;
      cs.H.block<6, 6>(oh, oh) += 0.5 * (H_hh + H_hh.transpose());  // symmetric to the last bit
      cs.H.block<6, 6>(oh, ot) -= AtS;
      cs.H.block<6, 6>(ot, oh) -= AtS.transpose();
      cs.H.block<6, 6>(ot, ot) += S_tt;
      // Pose-affine couplings: columns 6-7 of S are the host's affine, 8-9 the target's.
      const Eigen::Matrix<double, 6, 4> S_ta = S.block<6, 4>(0, 6);
      const Eigen::Matrix<double, 6, 4> H_ha = -(A.transpose() * S_ta);
      for (int side = 0; side < 2; ++side) {
        const int oa = (side == 0 ? oh : ot) + StateLayout::kAffine;
        cs.H.block<6, 2>(oh, oa) += H_ha.middleCols<2>(2 * side);
        cs.H.block<2, 6>(oa, oh) += H_ha.middleCols<2>(2 * side).transpose();
        cs.H.block<6, 2>(ot, oa) += S_ta.middleCols<2>(2 * side);
        cs.H.block<2, 6>(oa, ot) += S_ta.middleCols<2>(2 * side).transpose();
      }
      for (int sa = 0; sa < 2; ++sa)
        for (int sc = 0; sc < 2; ++sc)
          cs.H.block<2, 2>((sa == 0 ? oh : ot) + StateLayout::kAffine, (sc == 0 ? oh : ot) + StateLayout::kAffine) +=
              S.block<2, 2>(6 + 2 * sa, 6 + 2 * sc);
      cs.b.segment<6>(ot) += sb.head<6>();
      cs.b.segment<6>(oh).noalias() -= A.transpose() * sb.head<6>();
      cs.b.segment<2>(oh + StateLayout::kAffine) += sb.segment<2>(6);
      cs.b.segment<2>(ot + StateLayout::kAffine) += sb.segment<2>(8);
    }
}

}  // namespace

double photometricEnergy(const BundleAdjuster::Impl& m, const Linearization& L) {
  // The sums of accumulateChunk (per chunk, points in order, their observations in order) and of the
  // chunks in order after it: the same bits as L.energy_photo of the full accumulation.
  const int np = static_cast<int>(m.points.size());
  double total = 0.0;
  for (int chunk = 0; chunk < kPointChunks; ++chunk) {
    const int begin = static_cast<int>(static_cast<long>(np) * chunk / kPointChunks);
    const int end = static_cast<int>(static_cast<long>(np) * (chunk + 1) / kPointChunks);
    double e = 0.0;
    for (int r = m.point_obs_begin[static_cast<size_t>(begin)]; r < m.point_obs_begin[static_cast<size_t>(end)]; ++r)
      e += L.obs[static_cast<size_t>(r)].energy;
    total += e;
  }
  return total;
}

void accumulatePhotometric(BundleAdjuster::Impl& m, Linearization& L, const BundleAdjustmentConfig& cfg,
                           bool points_only) {
  if (points_only) {
    if (cfg.layout.rolling)
      m.runner->run(kPointChunks, [&](int c) { accumulateChunk<false, true>(m, L, c); });
    else
      m.runner->run(kPointChunks, [&](int c) { accumulateChunkGlobal<true>(m, L, c); });
    L.energy_photo = L.energy_photo_in = 0.0;
    L.num_in = L.num_oob = L.num_outlier = 0;
    for (const ChunkSums& c : m.chunks) {
      L.energy_photo += c.energy;
      L.energy_photo_in += c.energy_in;
      L.num_in += c.num_in;
      L.num_oob += c.num_oob;
      L.num_outlier += c.num_outlier;
    }
    return;
  }
  const bool pairs = cfg.layout.rolling && cfg.host_blocks_from_adjoint;  // accumulateChunkRolling
  if (pairs) {
    if (m.gl >= 0)
      m.runner->run(kPointChunks, [&](int c) { accumulateChunkRolling<true>(m, L, c); });
    else
      m.runner->run(kPointChunks, [&](int c) { accumulateChunkRolling<false>(m, L, c); });
  } else if (m.gl >= 0) {
    m.runner->run(kPointChunks, [&](int c) { accumulateChunk<true>(m, L, c); });
  } else if (cfg.layout.rolling) {
    m.runner->run(kPointChunks, [&](int c) { accumulateChunk<false>(m, L, c); });
  } else {
    m.runner->run(kPointChunks, [&](int c) { accumulateChunkGlobal<false>(m, L, c); });
  }
  L.Hcc.setZero(m.nc, m.nc);
  L.bc.setZero(m.nc);
  L.energy_photo = L.energy_photo_in = 0.0;
  L.num_in = L.num_oob = L.num_outlier = 0;
  for (const ChunkSums& c : m.chunks) {  // fixed order: deterministic
    if (!pairs) {
      L.Hcc.topLeftCorner(m.nkd, m.nkd) += c.H;
      L.bc.head(m.nkd) += c.b;
      if (m.gl >= 0) {
        L.Hcc.col(m.gl).head(m.nkd) += c.Hl;
        L.Hcc.row(m.gl).head(m.nkd) += c.Hl.transpose();
        L.Hcc(m.gl, m.gl) += c.Hll;
        L.bc[m.gl] += c.bl;
      }
    }
    L.energy_photo += c.energy;
    L.energy_photo_in += c.energy_in;
    L.num_in += c.num_in;
    L.num_oob += c.num_oob;
    L.num_outlier += c.num_outlier;
  }
  if (pairs) addRollingPairs(m, L);
  // Rolling shutter: the upper triangle only was formed (accumulateChunk, addRollingPairs; the latter's
  // line-delay row too).
  if (cfg.layout.rolling) {
    for (Eigen::Index j = 0; j < m.nkd; ++j)
      for (Eigen::Index i = j + 1; i < m.nkd; ++i) L.Hcc(i, j) = L.Hcc(j, i);
    if (pairs && m.gl >= 0) L.Hcc.row(m.gl).head(m.nkd) = L.Hcc.col(m.gl).head(m.nkd).transpose();
  }
}

}  // namespace ba
}  // namespace rsvio
