// Ray casting against the room and its boxes (rsvio/sim/scene.h).
#include "rsvio/sim/scene.h"

#include <cmath>
#include <limits>
#include <vector>

#include "rsvio/core/error.h"

namespace rsvio::sim {

int Scene::addTexture(TextureMap tex) {
  textures_.push_back(std::move(tex));
  return static_cast<int>(textures_.size()) - 1;
}

int Scene::addSolid(const Vec3& min, const Vec3& max, const std::array<int, 6>& textures, bool inside_out) {
  if ((max - min).minCoeff() <= 0) throw Error("scene: a box has a non-positive extent");
  if (inside_out != solids_.empty()) throw Error("scene: solid 0 must be the room, and only solid 0");
  for (int t : textures)
    if (t < 0 || t >= static_cast<int>(textures_.size())) throw Error("scene: face texture index out of range");
  solids_.push_back({min, max, textures, inside_out});
  return static_cast<int>(solids_.size()) - 1;
}

namespace {
constexpr double kEps = 1e-9;
}

bool Scene::intersect(const Vec3& o, const Vec3& d, Hit& hit) const {
  thread_local std::vector<int> all;
  all.resize(solids_.empty() ? 0 : solids_.size() - 1);
  for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i + 1);
  return intersect(o, d, hit, all.data(), static_cast<int>(all.size()));
}

bool Scene::intersect(const Vec3& o, const Vec3& d, Hit& hit, const int* solids, int n) const {
  if (solids_.empty()) return false;
  double best = std::numeric_limits<double>::infinity();
  int best_solid = -1, best_face = -1;
  const double inv[3] = {1.0 / d.x(), 1.0 / d.y(), 1.0 / d.z()};
  {
    // The room from inside: the exit plane of each axis; the nearest one is the wall hit.
    const Solid& s = solids_[0];
    for (int a = 0; a < 3; ++a) {
      if (d[a] == 0.0) continue;
      const int side = d[a] > 0 ? 1 : 0;
      const double t = ((side ? s.max[a] : s.min[a]) - o[a]) * inv[a];
      if (t > kEps && t < best) {
        best = t;
        best_solid = 0;
        best_face = 2 * a + side;
      }
    }
  }
  for (int k = 0; k < n; ++k) {
    // Slab test from outside.
    const Solid& s = solids_[solids[k]];
    double t_near = -std::numeric_limits<double>::infinity(), t_far = best;
    int near_axis = -1;
    for (int a = 0; a < 3; ++a) {
      double t0 = (s.min[a] - o[a]) * inv[a], t1 = (s.max[a] - o[a]) * inv[a];
      if (t0 > t1) std::swap(t0, t1);
      if (t0 > t_near) {
        t_near = t0;
        near_axis = a;
      }
      t_far = std::min(t_far, t1);
    }
    if (t_near <= t_far && t_near > kEps && t_near < best && near_axis >= 0) {
      best = t_near;
      best_solid = solids[k];
      best_face = 2 * near_axis + (d[near_axis] < 0 ? 1 : 0);
    }
  }
  if (best_solid < 0) return false;
  hit.t = best;
  hit.solid = best_solid;
  hit.face = best_face;
  hit.p = o + best * d;
  return true;
}

Vec3 Scene::normal(const Hit& hit) const {
  const int axis = hit.face / 2, side = hit.face % 2;
  const bool inward = solids_[hit.solid].inside_out;
  Vec3 n = Vec3::Zero();
  n[axis] = (side == 1) != inward ? 1.0 : -1.0;
  return n;
}

float Scene::radiance(const Hit& hit, double footprint_m) const {
  const Solid& s = solids_[hit.solid];
  const int axis = hit.face / 2;
  const int a0 = axis == 0 ? 1 : 0, a1 = axis == 2 ? 1 : 2;
  return textures_[s.tex[hit.face]].sample(hit.p[a0] - s.min[a0], hit.p[a1] - s.min[a1], footprint_m);
}

size_t Scene::textureBytes() const {
  size_t n = 0;
  for (const auto& t : textures_) n += t.bytes();
  return n;
}

}  // namespace rsvio::sim
