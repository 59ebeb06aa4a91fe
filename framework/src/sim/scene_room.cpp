// The standard simulated room (Scene::defaultRoom): an office/lab with furniture along the walls, a
// door, a window, a whiteboard, posters and pictures, a table in the middle, a rug and ceiling lamps.
// Layout decisions are drawn one after another from the (seed, "scene") stream; each face is then
// painted and lit independently (in parallel), so the result does not depend on the thread count.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>

#include "paint.h"
#include "rsvio/sim/rng.h"
#include "rsvio/sim/scene.h"

namespace rsvio::sim {

namespace {

using paint::Decal;
using paint::DecalKind;
using paint::FacePaint;
using paint::Material;

struct PaintJob {
  int texture = -1;
  Vec3 min, max;  // the solid
  int face = 0;
  bool inside_out = false;
  FacePaint paint;
};

struct Lighting {
  std::vector<Vec3> lamps;
  double ambient = 0.35, intensity = 0.7, falloff_m2 = 6.25, scale = 1.0;
  double at(const Vec3& p, const Vec3& n) const {
    double e = ambient;
    for (const Vec3& l : lamps) {
      const Vec3 d = l - p;
      const double r2 = d.squaredNorm();
      e += intensity * std::max(0.0, n.dot(d) / std::sqrt(r2)) / (1.0 + r2 / falloff_m2);
    }
    return scale * e;
  }
};

// Furniture standing against a wall, before it becomes a solid.
struct Item {
  int wall = 0;
  double s0 = 0, s1 = 0, depth = 0, height = 0;
  int type = 0;
};

enum ItemType { kBookshelf, kCabinet, kDrawers, kTallCabinet, kSofa, kCrates, kPlant, kDesk, kNumTypes };

struct Rect {
  double s0, t0, s1, t1;
  bool overlaps(const Rect& o, double m) const {
    return s0 < o.s1 + m && o.s0 < s1 + m && t0 < o.t1 + m && o.t0 < t1 + m;
  }
};

class RoomBuilder {
 public:
  RoomBuilder(Scene& scene, const SceneSpec& spec, uint64_t seed)
      : scene_(scene), spec_(spec), rng_(makeStream(seed, "scene")) {
    rx_ = 0.5 * spec.room_size_m.x();
    ry_ = 0.5 * spec.room_size_m.y();
    h_ = spec.room_size_m.z();
    texel_ = spec.texel_mm * 1e-3;
    light_.scale = spec.brightness;
  }

  void build();                // layout: fills solids_ (room first)
  void createSolids();         // textures and solids in the scene, one paint job per visible face
  void paintAll(int threads);  // paints, lights and filters every texture

 private:
  double wallLength(int w) const { return w < 2 ? 2 * ry_ : 2 * rx_; }
  uint64_t nextSeed() { return rng_(); }
  double u(double lo, double hi) { return uniform(rng_, lo, hi); }
  int pick(int n) { return std::min(n - 1, static_cast<int>(uniform01(rng_) * n)); }

  void placeFurniture();
  void addItemSolids(const Item& it);
  void addSolid(const Vec3& mn, const Vec3& mx, const std::array<FacePaint, 6>& paints, const std::array<bool, 6>& visible);
  void decorateWalls();
  bool tryDecal(int wall, DecalKind kind, double w, double h, double t_lo, double t_hi, int variant, double tone);
  double furnitureTop(int wall, double s0, double s1) const;

  Scene& scene_;
  SceneSpec spec_;
  std::mt19937_64 rng_;
  double rx_, ry_, h_, texel_;
  Lighting light_;
  int hidden_tex_ = -1;
  std::array<FacePaint, 6> room_paint_;
  std::vector<Item> items_;
  std::vector<Rect> used_[4];  // decal rectangles per wall
  struct SolidSpec {
    Vec3 min, max;
    std::array<FacePaint, 6> paints;
    std::array<bool, 6> visible;
    bool room = false;
  };
  std::vector<SolidSpec> solids_;
  std::vector<PaintJob> jobs_;
};

double RoomBuilder::furnitureTop(int wall, double s0, double s1) const {
  double top = 0.0;
  for (const Item& it : items_)
    if (it.wall == wall && it.s0 < s1 && s0 < it.s1) top = std::max(top, it.height);
  return top;
}

bool RoomBuilder::tryDecal(int wall, DecalKind kind, double w, double h, double t_lo, double t_hi, int variant,
                           double tone) {
  const double len = wallLength(wall);
  for (int attempt = 0; attempt < 30; ++attempt) {
    const double s0 = u(0.15, std::max(0.16, len - w - 0.15));
    const double t0 = u(t_lo, std::max(t_lo + 1e-3, t_hi - h));
    const Rect r{s0, t0, s0 + w, t0 + h};
    if (r.s1 > len - 0.1 || r.t1 > h_ - 0.1) continue;
    if (furnitureTop(wall, r.s0 - 0.05, r.s1 + 0.05) > r.t0 - 0.08) continue;
    bool free = true;
    for (const Rect& o : used_[wall]) free = free && !r.overlaps(o, 0.12);
    if (!free) continue;
    used_[wall].push_back(r);
    room_paint_[wall].decals.push_back({kind, r.s0, r.t0, r.s1, r.t1, nextSeed(), variant, tone});
    return true;
  }
  return false;
}

void RoomBuilder::build() {
  hidden_tex_ = scene_.addTexture(TextureMap::constant(0.1f));
  // Lamps on a 2 x 2 grid under the ceiling.
  for (int i = 0; i < 4; ++i)
    light_.lamps.emplace_back((i % 2 ? 0.5 : -0.5) * rx_, (i / 2 ? 0.5 : -0.5) * ry_, h_ - 0.05);

  const double wall_tone = u(0.55, 0.72);
  for (int w = 0; w < 4; ++w) room_paint_[w] = {Material::Plaster, nextSeed(), wall_tone * u(0.93, 1.07), false, {}};
  room_paint_[pick(4)].material = Material::Wallpaper;
  room_paint_[4] = {Material::FloorPlanks, nextSeed(), u(0.45, 0.6), uniform01(rng_) < 0.5, {}};
  room_paint_[5] = {Material::CeilingTiles, nextSeed(), 0.8, false, {}};

  placeFurniture();
  decorateWalls();

  // Floor rug and ceiling lamps (room face coordinates: floor/ceiling s = x + rx, t = y + ry).
  const double rug_w = u(2.0, 3.0), rug_h = u(1.4, 2.0);
  const double rug_s = rx_ + u(-1.0, 1.0) - 0.5 * rug_w, rug_t = ry_ + u(-0.8, 0.8) - 0.5 * rug_h;
  room_paint_[4].decals.push_back({DecalKind::Rug, rug_s, rug_t, rug_s + rug_w, rug_t + rug_h, nextSeed(), 0, u(0.3, 0.6)});
  for (const Vec3& l : light_.lamps) {
    const double s = l.x() + rx_, t = l.y() + ry_;
    room_paint_[5].decals.push_back({DecalKind::Lamp, s - 0.6, t - 0.15, s + 0.6, t + 0.15, nextSeed(), 0, 0.7});
  }

  // The room is solid 0.
  SolidSpec room{Vec3(-rx_, -ry_, 0.0), Vec3(rx_, ry_, h_), room_paint_, {true, true, true, true, true, true}, true};
  solids_.insert(solids_.begin(), room);
}

void RoomBuilder::placeFurniture() {
  // Door first (furniture keeps clear of it), on a random wall.
  const int door_wall = pick(4);
  const double door_w = 0.95;
  const double door_s = u(0.9, wallLength(door_wall) - door_w - 0.9);
  room_paint_[door_wall].decals.push_back({DecalKind::Door, door_s, 0.0, door_s + door_w, 2.05, nextSeed(), 0, u(0.4, 0.6)});
  used_[door_wall].push_back({door_s, 0.0, door_s + door_w, 2.05});
  room_paint_[door_wall].decals.push_back({DecalKind::Switch, door_s + door_w + 0.12, 1.05, door_s + door_w + 0.2, 1.17, nextSeed(), 0, 0.9});

  // Items per wall in proportion to its length.
  const double total = 2 * wallLength(0) + 2 * wallLength(2);
  for (int w = 0; w < 4; ++w) {
    const int n = static_cast<int>(std::lround(spec_.furniture * wallLength(w) / total));
    const double margin = w < 2 ? 0.05 : 0.7;  // y-walls keep clear of the x-walls' furniture
    double s = margin + u(0.0, 0.4);
    for (int k = 0; k < n; ++k) {
      Item it;
      it.wall = w;
      it.type = pick(kNumTypes);
      double width = 1.0;
      switch (it.type) {
        case kBookshelf: width = u(0.8, 1.2), it.depth = 0.35, it.height = u(1.7, 2.1); break;
        case kCabinet: width = u(0.8, 1.6), it.depth = 0.45, it.height = u(0.8, 1.1); break;
        case kDrawers: width = u(0.5, 0.9), it.depth = 0.5, it.height = u(0.6, 1.0); break;
        case kTallCabinet: width = u(0.6, 1.0), it.depth = 0.55, it.height = u(1.8, 2.0); break;
        case kSofa: width = u(1.6, 2.2), it.depth = 0.6, it.height = u(0.75, 0.85); break;
        case kCrates: width = u(0.4, 0.6), it.depth = u(0.4, 0.55), it.height = u(0.4, 0.7); break;
        case kPlant: width = 0.45, it.depth = 0.45, it.height = u(1.0, 1.5); break;
        default: width = u(1.2, 1.6), it.depth = 0.6, it.height = 0.74; break;
      }
      if (w == door_wall && s < door_s + door_w + 0.35 && s + width > door_s - 0.1) s = door_s + door_w + 0.35;
      if (s + width > wallLength(w) - margin) break;
      it.s0 = s;
      it.s1 = s + width;
      items_.push_back(it);
      addItemSolids(it);
      s += width + u(0.05, 0.8);
    }
  }
  if (spec_.table) {
    const double tw = u(1.4, 1.8), td = u(0.8, 1.0);
    // Separate statements: the order of draws inside one call's arguments is unspecified in C++.
    const double cx = u(-std::max(0.0, rx_ - 2.5), std::max(0.0, rx_ - 2.5));
    const double cy = u(-std::max(0.0, ry_ - 2.2), std::max(0.0, ry_ - 2.2));
    const Vec3 c(cx, cy, 0.0);
    const Vec3 mn(c.x() - 0.5 * tw, c.y() - 0.5 * td, 0.0), mx(c.x() + 0.5 * tw, c.y() + 0.5 * td, 0.74);
    FacePaint side{Material::DarkWood, nextSeed(), 0.8, true, {}};
    FacePaint top{Material::Wood, nextSeed(), u(0.5, 0.7), uniform01(rng_) < 0.5, {}};
    addSolid(mn, mx, {side, side, side, side, side, top}, {true, true, true, true, false, true});
    // A few flat things on it (kept low: the camera flies at least 1 m above the floor).
    for (int k = 0; k < 3; ++k) {
      const double ow = u(0.15, 0.4), od = u(0.15, 0.3), oh = u(0.02, 0.1);
      const double ox = u(mn.x() + 0.05, mx.x() - ow - 0.05);
      const double oy = u(mn.y() + 0.05, mx.y() - od - 0.05);
      const Vec3 omn(ox, oy, 0.74);
      FacePaint p{k == 0 ? Material::Cardboard : Material::Plain, nextSeed(), u(0.15, 0.85), false, {}};
      addSolid(omn, omn + Vec3(ow, od, oh), {p, p, p, p, p, p}, {true, true, true, true, false, true});
    }
  }
}

void RoomBuilder::addItemSolids(const Item& it) {
  Vec3 mn, mx;
  const int w = it.wall;
  if (w < 2) {  // x-walls: s runs along y
    mn = Vec3(w == 0 ? -rx_ : rx_ - it.depth, -ry_ + it.s0, 0.0);
    mx = Vec3(w == 0 ? -rx_ + it.depth : rx_, -ry_ + it.s1, it.height);
  } else {
    mn = Vec3(-rx_ + it.s0, w == 2 ? -ry_ : ry_ - it.depth, 0.0);
    mx = Vec3(-rx_ + it.s1, w == 2 ? -ry_ + it.depth : ry_, it.height);
  }
  const int front = w == 0 ? 1 : w == 1 ? 0 : w == 2 ? 3 : 2;
  const double width = it.s1 - it.s0;
  FacePaint side{Material::Wood, nextSeed(), u(0.45, 0.7), true, {}};
  FacePaint top{Material::Wood, nextSeed(), side.tone, false, {}};
  FacePaint fr = side;
  fr.seed = nextSeed();
  switch (it.type) {
    case kBookshelf: fr = {Material::Books, nextSeed(), side.tone, false, {}}; break;
    case kCabinet:
      fr.decals.push_back({DecalKind::CabinetDoors, 0, 0, width, it.height, nextSeed(), pick(3), 0.5});
      break;
    case kDrawers:
      fr.material = Material::Plain;
      fr.decals.push_back({DecalKind::Drawers, 0, 0, width, it.height, nextSeed(), pick(3), 0.5});
      break;
    case kTallCabinet:
      side.material = top.material = fr.material = Material::Plain;
      side.tone = top.tone = fr.tone = u(0.5, 0.8);
      fr.decals.push_back({DecalKind::CabinetDoors, 0, 0, width, it.height, nextSeed(), 1, 0.5});
      break;
    case kSofa: side = top = fr = {Material::Fabric, nextSeed(), u(0.25, 0.6), false, {}}; break;
    case kCrates:
      side = top = fr = {Material::Cardboard, nextSeed(), u(0.4, 0.55), false, {}};
      fr.decals.push_back({DecalKind::Tape, 0, 0.45 * it.height, width, 0.45 * it.height + 0.05, nextSeed(), 0, 0.8});
      break;
    case kPlant: side = top = fr = {Material::Leaves, nextSeed(), u(0.25, 0.4), false, {}}; break;
    default:  // desk: drawers on one side of the front
      fr.decals.push_back({DecalKind::Drawers, width - 0.45, 0.0, width - 0.02, it.height - 0.03, nextSeed(), 1, 0.5});
      break;
  }
  std::array<FacePaint, 6> paints = {side, side, side, side, side, top};
  paints[front] = fr;
  std::array<bool, 6> visible = {true, true, true, true, false, true};
  visible[front ^ 1] = false;  // the back, against the wall
  addSolid(mn, mx, paints, visible);
  // Something on top of low furniture.
  if (it.height < 1.2 && it.type != kSofa && it.type != kPlant && uniform01(rng_) < 0.6) {
    const double ow = std::min(width - 0.1, u(0.2, 0.5)), oh = u(0.1, 0.35);
    const double off = u(0.05, std::max(0.06, width - ow - 0.05));
    Vec3 omn = mn, omx = mx;
    const int along = w < 2 ? 1 : 0;
    omn[along] = mn[along] + off;
    omx[along] = omn[along] + ow;
    const int across = 1 - along;
    omn[across] = mn[across] + 0.05;
    omx[across] = mx[across] - 0.05;
    omn.z() = it.height;
    omx.z() = it.height + oh;
    FacePaint p{uniform01(rng_) < 0.5 ? Material::Cardboard : Material::Books, nextSeed(), u(0.3, 0.7), false, {}};
    addSolid(omn, omx, {p, p, p, p, p, p}, {true, true, true, true, false, true});
  }
}

void RoomBuilder::decorateWalls() {
  const int window_wall = pick(4), board_wall = (window_wall + 1 + pick(3)) % 4;
  for (int w = 0; w < 4; ++w)
    room_paint_[w].decals.insert(room_paint_[w].decals.begin(),
                                 Decal{DecalKind::Baseboard, 0.0, 0.0, wallLength(w), 0.09, nextSeed(), 0, u(0.7, 0.9)});
  tryDecal(window_wall, DecalKind::Window, u(1.2, 1.8), 1.3, 1.0, 2.6, 0, 0.8);
  tryDecal(board_wall, DecalKind::Whiteboard, u(1.5, 2.0), 1.1, 0.9, 2.2, 0, 0.9);
  tryDecal(pick(4), DecalKind::Clock, 0.32, 0.32, 1.9, 2.7, 0, 0.9);
  for (int w = 0; w < 4; ++w) {
    const int n = static_cast<int>(2 + wallLength(w) / 1.6);
    for (int k = 0; k < n; ++k) {
      const bool frame = uniform01(rng_) < 0.35;
      const double pw = u(0.4, 1.1), ph = u(0.5, 1.0);
      tryDecal(w, frame ? DecalKind::Frame : DecalKind::Poster, pw, ph, 0.5, h_ - 0.2, pick(6), 0.5);
    }
  }
}

void RoomBuilder::addSolid(const Vec3& mn, const Vec3& mx, const std::array<FacePaint, 6>& paints,
                           const std::array<bool, 6>& visible) {
  solids_.push_back({mn, mx, paints, visible, false});
}

void RoomBuilder::createSolids() {
  for (const SolidSpec& sp : solids_) {
    std::array<int, 6> tex;
    for (int f = 0; f < 6; ++f) {
      if (!sp.visible[f]) {
        tex[f] = hidden_tex_;
        continue;
      }
      const int axis = f / 2, a0 = axis == 0 ? 1 : 0, a1 = axis == 2 ? 1 : 2;
      const double texel = (sp.room && f == 5) ? 2.0 * texel_ : texel_;  // the ceiling matters less
      const int tw = std::max(1, static_cast<int>(std::ceil((sp.max[a0] - sp.min[a0]) / texel)));
      const int th = std::max(1, static_cast<int>(std::ceil((sp.max[a1] - sp.min[a1]) / texel)));
      tex[f] = scene_.addTexture(TextureMap(tw, th, texel));
      jobs_.push_back({tex[f], sp.min, sp.max, f, sp.room, sp.paints[f]});
    }
    scene_.addSolid(sp.min, sp.max, tex, sp.room);
  }
}

void RoomBuilder::paintAll(int threads) {
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (size_t j = next++; j < jobs_.size(); j = next++) {
      const PaintJob& job = jobs_[j];
      TextureMap& tex = scene_.mutableTexture(job.texture);
      const int axis = job.face / 2, side = job.face % 2, a0 = axis == 0 ? 1 : 0, a1 = axis == 2 ? 1 : 2;
      Vec3 n = Vec3::Zero();
      n[axis] = (side == 1) != job.inside_out ? 1.0 : -1.0;
      Vec3 p;
      p[axis] = side ? job.max[axis] : job.min[axis];
      const double texel = tex.texelSize();
      for (int y = 0; y < tex.height(); ++y) {
        const double t = (y + 0.5) * texel;
        p[a1] = job.min[a1] + t;
        for (int x = 0; x < tex.width(); ++x) {
          const double s = (x + 0.5) * texel;
          p[a0] = job.min[a0] + s;
          const paint::Shade sh = paint::shade(job.paint, s, t);
          tex.at(x, y) = static_cast<float>(sh.albedo * light_.at(p, n) + sh.emission * spec_.brightness);
        }
      }
      tex.buildMips();
    }
  };
  std::vector<std::thread> pool;
  for (int i = 1; i < threads; ++i) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
}

}  // namespace

Scene Scene::defaultRoom(const SceneSpec& spec, uint64_t seed, int threads) {
  Scene scene;
  RoomBuilder b(scene, spec, seed);
  b.build();
  b.createSolids();
  b.paintAll(std::max(1, threads));
  return scene;
}

}  // namespace rsvio::sim
